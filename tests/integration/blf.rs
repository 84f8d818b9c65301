//! Vector BLF: a writer of our own builds files object by object (plain and
//! zlib containers, objects spanning containers, header v1/v2, 10 us / 1 ns,
//! every CAN object type, corrupt and truncated files); they must decode to
//! the events of the equivalent candump fixture, and random frames must come
//! back as the same frames.

use std::io::Write;
use std::path::Path;

use emcy_decode::{Format, FrameKind, Record, TraceReader};
use proptest::prelude::*;
use serde_json::Value;

use crate::support::frames::*;
use crate::support::{self, PLACE, emcy_decode};

// ---- a BLF writer ------------------------------------------------------------------

#[derive(Clone, Copy, Debug)]
struct Header {
    version: u16,
    /// 1 = 10 us, 2 = 1 ns.
    unit: u32,
}

const V1_NS: Header = Header {
    version: 1,
    unit: 2,
};

fn object(kind: u32, payload: &[u8], ticks: u64, h: Header) -> Vec<u8> {
    let mut head = Vec::new();
    head.extend(h.unit.to_le_bytes());
    if h.version == 1 {
        head.extend([0u8; 4]); // client index, object version
        head.extend(ticks.to_le_bytes());
    } else {
        head.extend([0u8; 4]); // timestamp status, reserved, object version
        head.extend(ticks.to_le_bytes());
        head.extend(0u64.to_le_bytes()); // original timestamp
    }
    let header_size = 16 + head.len();
    let size = header_size + payload.len();
    let mut o = b"LOBJ".to_vec();
    o.extend((header_size as u16).to_le_bytes());
    o.extend(h.version.to_le_bytes());
    o.extend((size as u32).to_le_bytes());
    o.extend(kind.to_le_bytes());
    o.extend(head);
    o.extend(payload);
    o.extend(vec![0u8; size % 4]);
    o
}

fn raw_id(id: u32, extended: bool) -> u32 {
    id | if extended { 0x8000_0000 } else { 0 }
}

/// CAN message (1) or CAN message 2 (86).
fn can_message(kind: u32, ch: u16, id: u32, ext: bool, rtr: bool, data: &[u8]) -> (u32, Vec<u8>) {
    let mut p = ch.to_le_bytes().to_vec();
    p.push(if rtr { 0x80 } else { 0 });
    p.push(data.len() as u8);
    p.extend(raw_id(id, ext).to_le_bytes());
    let mut d = data.to_vec();
    d.resize(8, 0);
    p.extend(d);
    if kind == 86 {
        p.extend([0u8; 8]);
    }
    (kind, p)
}

/// CAN FD message (100).
fn fd_message(ch: u16, id: u32, ext: bool, edl: bool, data: &[u8]) -> (u32, Vec<u8>) {
    let mut p = ch.to_le_bytes().to_vec();
    p.push(0);
    p.push(if edl {
        fd_dlc(data.len()) as u8
    } else {
        data.len() as u8
    });
    p.extend(raw_id(id, ext).to_le_bytes());
    p.extend([0u8; 4]); // frame length
    p.push(0); // bit count
    p.push(u8::from(edl));
    p.push(data.len() as u8);
    p.push(0);
    p.extend([0u8; 4]);
    let mut d = data.to_vec();
    d.resize(64, 0);
    p.extend(d);
    p.extend([0u8; 4]);
    (100, p)
}

/// CAN FD message 64 (101).
fn fd64(ch: u8, id: u32, ext: bool, edl: bool, rtr: bool, data: &[u8]) -> (u32, Vec<u8>) {
    let dlc = if edl { fd_dlc(data.len()) } else { data.len() } as u8;
    let mut p = vec![ch, dlc, data.len() as u8, 0];
    p.extend(raw_id(id, ext).to_le_bytes());
    p.extend([0u8; 4]);
    let flags: u32 = if edl { 0x1000 } else { 0 } | if rtr { 0x10 } else { 0 };
    p.extend(flags.to_le_bytes());
    p.extend([0u8; 24]); // btr x2, time offsets x2, bit count, dir, ext offset, crc
    p.extend(data);
    (101, p)
}

/// CAN error frame ext (73).
fn error_ext(ch: u16) -> (u32, Vec<u8>) {
    let mut p = ch.to_le_bytes().to_vec();
    p.extend([0u8; 30]);
    (73, p)
}

fn container(part: &[u8], zlib: bool) -> Vec<u8> {
    let data = if zlib {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
        z.write_all(part).unwrap();
        z.finish().unwrap()
    } else {
        part.to_vec()
    };
    let size = 32 + data.len();
    let mut c = b"LOBJ".to_vec();
    c.extend(16u16.to_le_bytes());
    c.extend(1u16.to_le_bytes());
    c.extend((size as u32).to_le_bytes());
    c.extend(10u32.to_le_bytes());
    c.extend((if zlib { 2u16 } else { 0 }).to_le_bytes());
    c.extend([0u8; 6]);
    c.extend((part.len() as u32).to_le_bytes());
    c.extend([0u8; 4]);
    c.extend(data);
    c.extend(vec![0u8; size % 4]);
    c
}

/// 2023-11-14 22:13:20.000 UTC = 1700000000.
const START: [u16; 8] = [2023, 11, 2, 14, 22, 13, 20, 0];

fn file_header(start: [u16; 8]) -> Vec<u8> {
    let mut h = b"LOGG".to_vec();
    h.extend(144u32.to_le_bytes());
    h.extend([0u8; 8]);
    h.extend([0u8; 24]); // sizes and object count: not needed to read
    for v in start {
        h.extend(v.to_le_bytes());
    }
    h.resize(144, 0);
    h
}

/// A file of `stream` (concatenated objects) in containers of `chunk` bytes.
fn blf(stream: &[u8], chunk: usize, zlib: bool) -> Vec<u8> {
    let mut f = file_header(START);
    for part in stream.chunks(chunk.max(1)) {
        f.extend(container(part, zlib));
    }
    f
}

// ---- reading helpers ----------------------------------------------------------------

#[derive(Debug, PartialEq)]
enum Got {
    Frame {
        time: String,
        channel: String,
        id: u32,
        extended: bool,
        kind: FrameKind,
        data: Vec<u8>,
    },
    Skipped,
    Malformed(String),
    /// What the reader made good in the frame that follows.
    Warning(String),
}

/// The objects of a BLF file, read as BLF ([`TraceReader::with_format`]);
/// notes about the file as a whole are left out.
fn read(bytes: &[u8]) -> Vec<Got> {
    let mut out = Vec::new();
    for record in TraceReader::with_format(bytes, Format::Blf) {
        out.push(match record.expect("a BLF header and no I/O error") {
            Record::Frame(f) => Got::Frame {
                time: f.time.map(|t| t.to_string()).unwrap_or_default(),
                channel: f.channel,
                id: f.id,
                extended: f.extended,
                kind: f.kind,
                data: f.data,
            },
            Record::Skipped { .. } => Got::Skipped,
            Record::Malformed { reason, .. } => Got::Malformed(reason),
            Record::Warning { reason, .. } => Got::Warning(reason),
            Record::Note(_) => continue,
            other => panic!("a record this test does not know: {other:?}"),
        });
    }
    out
}

fn frames(got: &[Got]) -> Vec<&Got> {
    got.iter()
        .filter(|g| matches!(g, Got::Frame { .. }))
        .collect()
}

fn run(bytes: &[u8]) -> (Vec<Value>, String, i32) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.blf");
    std::fs::write(&path, bytes).unwrap();
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .arg(&path)
        .output()
        .unwrap();
    let v = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    (
        v,
        String::from_utf8(out.stderr).unwrap(),
        out.status.code().unwrap_or(-1),
    )
}

fn input(v: &[Value]) -> &Value {
    v.iter()
        .find(|o| o["type"] == "input")
        .expect("input object")
}

fn emcy_codes(v: &[Value]) -> Vec<String> {
    v.iter()
        .filter(|o| o["type"] == "emcy")
        .map(|o| o["code"].to_string())
        .collect()
}

fn ndjson(path: &Path) -> Vec<Value> {
    support::ndjson([path])
}

/// Events and nodes without where they were (file, line, channel).
fn semantic(objects: &[Value]) -> Vec<Value> {
    support::semantic(objects, &PLACE)
}

/// Times as numbers (BLF prints 9 digits for 1 ns objects, the log 6).
fn normalise_times(v: &mut Value) {
    match v {
        Value::Number(n) => {
            if let Some(f) = n.as_f64()
                && n.to_string().contains('.')
            {
                *v = Value::String(format!("{f:.6}"));
            }
        }
        Value::Array(a) => a.iter_mut().for_each(normalise_times),
        Value::Object(o) => o.values_mut().for_each(normalise_times),
        _ => {}
    }
}

// ---- tests -------------------------------------------------------------------------

#[test]
fn fixtures_decode_like_the_candump_log() {
    for (blf, log) in [
        ("fixtures/s300.blf", "fixtures/s300.log"),
        ("fixtures/s300.plain.blf", "fixtures/s300.log"),
        ("fixtures/edge.blf", "fixtures/edge.log"),
    ] {
        let mut a = semantic(&ndjson(Path::new(blf)));
        let mut b = semantic(&ndjson(Path::new(log)));
        a.iter_mut().for_each(normalise_times);
        b.iter_mut().for_each(normalise_times);
        assert!(b.iter().any(|o| o["type"] == "emcy"));
        assert_eq!(a, b, "{blf} vs {log}");
    }
    // The fixture with the unknown object: 19 frames (s300.log's, with the
    // SDO identity reads), 1 unknown object and the containers skipped.
    let v = ndjson(Path::new("fixtures/s300.blf"));
    let i = input(&v);
    assert_eq!(i["format"], "blf");
    assert_eq!(i["frames"], 19);
    assert_eq!(
        i["lines"].as_u64(),
        Some(i["frames"].as_u64().unwrap() + i["skipped"].as_u64().unwrap())
    );
}

#[test]
fn gzip_blf_is_detected_from_content() {
    let plain = std::fs::read("fixtures/s300.blf").unwrap();
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(&plain).unwrap();
    let (v, stderr, code) = run(&enc.finish().unwrap());
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(input(&v)["gzip"], true);
    assert_eq!(input(&v)["format"], "blf");
    assert_eq!(
        semantic(&v),
        semantic(&ndjson(Path::new("fixtures/s300.blf")))
    );
}

fn emcy(ch: u16, code: u16, t: u64) -> Vec<u8> {
    let [lo, hi] = code.to_le_bytes();
    let (k, p) = can_message(1, ch, 0x81, false, false, &[lo, hi, 1, 0, 0, 0, 0, 0]);
    object(k, &p, t, V1_NS)
}

#[test]
fn an_object_spanning_two_containers_is_read_whole() {
    let mut stream = emcy(1, 0x4310, 1_000_000_000);
    stream.extend(emcy(1, 0x0000, 2_000_000_000));
    for zlib in [false, true] {
        // Cut inside the first object's data, and inside the second's header.
        for cut in [5, 20, 40, 50, 60] {
            let got = read(&blf(&stream, cut, zlib));
            assert_eq!(frames(&got).len(), 2, "cut {cut}: {got:?}");
            assert!(
                !got.iter().any(|g| matches!(g, Got::Malformed(_))),
                "{got:?}"
            );
        }
    }
}

#[test]
fn header_versions_and_time_units() {
    let (k, p) = can_message(86, 2, 0x1234_5678, true, false, &[1, 2, 3]);
    let mut stream = object(
        k,
        &p,
        125_000,
        Header {
            version: 1,
            unit: 1,
        },
    );
    stream.extend(object(
        k,
        &p,
        1_250_000_001,
        Header {
            version: 2,
            unit: 2,
        },
    ));
    stream.extend(object(
        k,
        &p,
        7,
        Header {
            version: 2,
            unit: 1,
        },
    ));
    let got = read(&blf(&stream, 1 << 17, true));
    let times: Vec<_> = got
        .iter()
        .filter_map(|g| match g {
            Got::Frame { time, .. } => Some(time.as_str()),
            _ => None,
        })
        .collect();
    assert_eq!(
        times,
        [
            "1700000001.250000",
            "1700000001.250000001",
            "1700000000.000070"
        ]
    );
    match &got[1] {
        Got::Frame {
            channel,
            id,
            extended,
            kind,
            data,
            ..
        } => {
            assert_eq!(
                (channel.as_str(), *id, *extended, *kind, data.as_slice()),
                ("2", 0x1234_5678, true, FrameKind::Data, &[1u8, 2, 3][..])
            );
        }
        other => panic!("{other:?}"),
    }
    // Start time all zero (unknown): times since the measurement start.
    let mut f = file_header([0; 8]);
    f.extend(container(&stream, false));
    match &read(&f)[1] {
        Got::Frame { time, .. } => assert_eq!(time, "1.250000"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn every_can_object_type_and_only_classic_data_is_an_emcy() {
    let payload = [0x10, 0x43, 0x09, 0x01, 0, 0, 0, 0];
    let objs = [
        can_message(1, 1, 0x81, false, false, &payload), // EMCY
        can_message(86, 1, 0x81, false, false, &payload), // EMCY
        fd_message(1, 0x81, false, false, &payload),     // classic in an FD object: EMCY
        fd64(1, 0x81, false, false, false, &payload),    // likewise
        fd_message(1, 0x81, false, true, &payload),      // CAN FD: not an EMCY
        fd64(1, 0x81, false, true, false, &payload),     // CAN FD: not an EMCY
        fd64(1, 0x81, false, false, true, &[]),          // remote: not an EMCY
        can_message(1, 1, 0x81, false, true, &[]),       // remote
        can_message(1, 1, 0x81, true, false, &payload),  // extended 0x81: not an EMCY
        error_ext(1),                                    // error frame
        (2, vec![1, 0, 0, 0, 0, 0, 0, 0]),               // CAN error frame (old)
        (65, b"some application text".to_vec()),         // unknown: skipped
    ];
    let mut stream = Vec::new();
    for (i, (k, p)) in objs.iter().enumerate() {
        stream.extend(object(*k, p, i as u64 * 1_000_000, V1_NS));
    }
    let got = read(&blf(&stream, 64, true));
    let kinds: Vec<_> = got
        .iter()
        .filter_map(|g| match g {
            Got::Frame { kind, .. } => Some(*kind),
            _ => None,
        })
        .collect();
    use FrameKind::*;
    assert_eq!(
        kinds,
        [
            Data, Data, Data, Data, Fd, Fd, Remote, Remote, Data, Error, Error
        ]
    );
    let (v, stderr, code) = run(&blf(&stream, 64, true));
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(emcy_codes(&v).len(), 4, "{v:?}");
    let i = input(&v);
    assert_eq!(i["frames"], 11);
    assert_eq!(i["malformed"], 0);
    // The unknown object and the containers are skipped and counted.
    let containers = got.iter().filter(|g| **g == Got::Skipped).count() as u64;
    assert_eq!(i["skipped"].as_u64(), Some(containers));
    assert_eq!(i["lines"].as_u64(), Some(11 + containers));
}

#[test]
fn a_corrupt_object_is_reported_and_skipped_by_its_size() {
    let mut stream = emcy(1, 0x4310, 1_000_000_000);
    // A CAN message with DLC 20: sane size, wrong content.
    let (k, mut p) = can_message(1, 1, 0x81, false, false, &[0; 8]);
    p[3] = 20;
    stream.extend(object(k, &p, 1_500_000_000, V1_NS));
    // An unknown object header version.
    stream.extend(object(
        1,
        &p,
        1,
        Header {
            version: 9,
            unit: 2,
        },
    ));
    stream.extend(emcy(1, 0x0000, 2_000_000_000));
    let (v, stderr, code) = run(&blf(&stream, 1 << 17, true));
    assert_eq!(code, 0);
    assert_eq!(emcy_codes(&v), ["\"0x4310\"", "\"0x0000\""], "{v:?}");
    assert_eq!(input(&v)["malformed"], 2);
    // Object 1 is the container; the corrupt ones are objects 3 and 4.
    assert!(
        stderr.contains("t.blf:3: CAN message object (type 1) of 48 bytes: DLC 20 is over 15"),
        "{stderr}"
    );
    assert!(
        stderr.contains(
            "t.blf:4: CAN message object (type 1) of 56 bytes: unknown object header version 9"
        ),
        "{stderr}"
    );
}

#[test]
fn garbage_between_objects_is_skipped_to_the_next_signature() {
    let mut stream = emcy(1, 0x4310, 1_000_000_000);
    stream.extend(b"garbage!");
    // An insane declared size: the reader looks for the next LOBJ.
    let mut bad = emcy(1, 0x2310, 1_200_000_000);
    bad[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    stream.extend(bad);
    stream.extend(emcy(1, 0x0000, 2_000_000_000));
    for (chunk, zlib) in [(1 << 17, true), (7, false), (33, true)] {
        let got = read(&blf(&stream, chunk, zlib));
        assert_eq!(frames(&got).len(), 2, "chunk {chunk}: {got:?}");
        let malformed = got
            .iter()
            .filter(|g| matches!(g, Got::Malformed(_)))
            .count();
        assert_eq!(malformed, 2, "{got:?}");
    }
    // Garbage at the top level, between containers.
    let mut f = file_header(START);
    f.extend(container(&emcy(1, 0x4310, 1), true));
    f.extend(b"\x00\x01\x02 not an object");
    f.extend(container(&emcy(1, 0x0000, 2), false));
    let (v, stderr, _) = run(&f);
    assert_eq!(emcy_codes(&v).len(), 2, "{stderr}");
    assert!(stderr.contains("no LOBJ signature at byte"), "{stderr}");
}

#[test]
fn a_broken_container_costs_only_what_it_held() {
    let mut f = file_header(START);
    f.extend(container(&emcy(1, 0x4310, 1), true));
    let mut broken = container(&emcy(1, 0x2310, 2), true);
    let n = broken.len();
    broken[n - 8] ^= 0xFF; // inside the zlib data
    broken[n - 12] ^= 0xFF;
    f.extend(broken);
    f.extend(container(&emcy(1, 0x0000, 3), false));
    let (v, stderr, code) = run(&f);
    assert_eq!(code, 0);
    let codes = emcy_codes(&v);
    assert!(codes.contains(&"\"0x4310\"".to_string()), "{codes:?}");
    assert!(codes.contains(&"\"0x0000\"".to_string()), "{codes:?}");
    assert!(stderr.contains("log container at byte"), "{stderr}");
}

#[test]
fn a_truncated_file_is_reported_and_what_was_read_still_counts() {
    let mut stream = Vec::new();
    for i in 0..50u64 {
        stream.extend(emcy(1, if i % 2 == 0 { 0x4310 } else { 0 }, i * 1000));
    }
    for zlib in [false, true] {
        let whole = blf(&stream, 600, zlib);
        for cut in [whole.len() - 5, whole.len() - 200, 144 + 40] {
            let (v, stderr, code) = run(&whole[..cut]);
            assert_eq!(code, 0, "{stderr}");
            let i = input(&v);
            assert!(i["malformed"].as_u64().unwrap() >= 1, "cut {cut}: {i}");
            assert!(stderr.contains("the file ends inside"), "{stderr}");
            let n = |k: &str| i[k].as_u64().unwrap();
            assert_eq!(n("lines"), n("frames") + n("skipped") + n("malformed"));
            if cut > 1000 {
                assert!(n("emcy") > 0, "{i}");
            }
        }
    }
    // A cut header is an input error (exit 2).
    let (_, stderr, code) = run(&file_header(START)[..100]);
    assert_eq!(code, 2);
    assert!(stderr.contains("header cut off"), "{stderr}");
}

#[test]
fn forced_blf_on_text_is_an_error_and_text_formats_ignore_blf() {
    let (_, stderr, code) = {
        let out = emcy_decode()
            .args(["--input-format", "blf", "fixtures/s300.log"])
            .output()
            .unwrap();
        (
            (),
            String::from_utf8(out.stderr).unwrap(),
            out.status.code(),
        )
    };
    assert_eq!(code, Some(2));
    assert!(stderr.contains("not a BLF file"), "{stderr}");
    let out = emcy_decode()
        .args(["--input-format", "candump", "fixtures/s300.blf"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
}

/// `object` as a writer that does not pad it leaves it.
fn unpadded(mut o: Vec<u8>) -> Vec<u8> {
    let size = u32::from_le_bytes(o[8..12].try_into().unwrap()) as usize;
    o.truncate(size);
    o
}

#[test]
fn an_object_written_without_padding_does_not_hide_the_next() {
    // CANoe writes some object types (118 here, 270 bytes) without the
    // padding `size % 4` asks for: the next LOBJ comes 2 bytes early.
    let odd = unpadded(object(118, &[0x55; 254], 0, V1_NS));
    assert_eq!(odd.len() % 4, 2);
    let mut stream = emcy(1, 0x4310, 1_000_000_000);
    stream.extend(&odd);
    stream.extend(emcy(1, 0x2310, 1_100_000_000));
    stream.extend(unpadded(object(118, &[0x55; 253], 0, V1_NS)));
    stream.extend(emcy(1, 0x0000, 2_000_000_000));
    for zlib in [false, true] {
        for chunk in (1..=70).chain([317, 318, 319, 320, 321, 1 << 17]) {
            let (v, stderr, code) = run(&blf(&stream, chunk, zlib));
            assert_eq!(code, 0, "{stderr}");
            assert_eq!(
                emcy_codes(&v),
                ["\"0x4310\"", "\"0x2310\"", "\"0x0000\""],
                "chunk {chunk}: {stderr}"
            );
            assert_eq!(input(&v)["malformed"], 0, "chunk {chunk}: {stderr}");
            assert_eq!(stderr, "", "chunk {chunk}");
        }
    }
    // Outside containers too.
    let mut f = file_header(START);
    f.extend(&stream);
    let (v, stderr, _) = run(&f);
    assert_eq!(emcy_codes(&v).len(), 3, "{stderr}");
    assert_eq!(input(&v)["malformed"], 0, "{stderr}");
}

#[test]
fn fd64_data_bytes_not_stored_are_zeros_with_a_warning() {
    // TSMaster writes CAN FD message 64 objects whose valid byte count (64)
    // exceeds the data stored (48): CANoe and python-can pad with zeros.
    let data: Vec<u8> = (1..=64).collect();
    let (k, mut p) = fd64(2, 0x6A9, false, true, false, &data);
    p.truncate(40 + 48);
    let mut stream = emcy(1, 0x4310, 1_000_000_000);
    stream.extend(object(k, &p, 1_500_000_000, V1_NS));
    stream.extend(emcy(1, 0x0000, 2_000_000_000));
    let bytes = blf(&stream, 1 << 17, true);
    let got = read(&bytes);
    let mut want = data[..48].to_vec();
    want.resize(64, 0);
    assert_eq!(
        &got[2..4],
        [
            Got::Warning(
                "CAN FD message 64 object (type 101) of 120 bytes: 64 valid data bytes but 48 \
                 stored; read with the other 16 as zeros, as CANoe does"
                    .into()
            ),
            Got::Frame {
                time: "1700000001.500000000".into(),
                channel: "2".into(),
                id: 0x6A9,
                extended: false,
                kind: FrameKind::Fd,
                data: want,
            }
        ],
        "{got:?}"
    );
    // The program: a frame, a diagnostic naming the object, nothing malformed,
    // so not a failure under --strict either.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.blf");
    std::fs::write(&path, &bytes).unwrap();
    let out = emcy_decode()
        .args(["--strict", "--format", "ndjson"])
        .arg(&path)
        .output()
        .unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("t.blf:3: CAN FD message 64 object (type 101)"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    let v = support::ndjson([&path]);
    assert_eq!(
        (
            input(&v)["frames"].as_u64(),
            input(&v)["malformed"].as_u64()
        ),
        (Some(3), Some(0))
    );
}

// ---- properties ------------------------------------------------------------------------

/// A test frame as one BLF object of a type that can carry it.
fn as_object(f: &TestFrame, style: u8, ch: u8, h: Header, ticks: u64) -> Vec<u8> {
    let (k, p) = match f.kind {
        FrameKind::Error => error_ext(u16::from(ch)),
        FrameKind::Fd if style.is_multiple_of(2) => {
            fd_message(u16::from(ch), f.id, f.extended, true, &f.data)
        }
        FrameKind::Fd => fd64(ch, f.id, f.extended, true, false, &f.data),
        FrameKind::Remote if style == 3 => fd64(ch, f.id, f.extended, false, true, &[]),
        FrameKind::Remote => can_message(1, u16::from(ch), f.id, f.extended, true, &[]),
        FrameKind::Data => match style {
            0 => can_message(1, u16::from(ch), f.id, f.extended, false, &f.data),
            1 => can_message(86, u16::from(ch), f.id, f.extended, false, &f.data),
            2 => fd_message(u16::from(ch), f.id, f.extended, false, &f.data),
            _ => fd64(ch, f.id, f.extended, false, false, &f.data),
        },
    };
    object(k, &p, ticks, h)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Random frames written as BLF (any container size, plain or zlib,
    /// header v1 or v2, either unit) read back as the same frames.
    #[test]
    fn random_frames_round_trip(
        items in prop::collection::vec((frame(), 0u8..4, 1u8..=32, any::<u32>()), 0..30),
        chunk in 1usize..400,
        zlib in any::<bool>(),
        version in 1u16..=2,
        unit in 1u32..=2,
    ) {
        let h = Header { version, unit };
        let mut stream = Vec::new();
        for (f, style, ch, ticks) in &items {
            stream.extend(as_object(f, *style, *ch, h, u64::from(*ticks)));
        }
        let got = read(&blf(&stream, chunk, zlib));
        let got: Vec<_> = got.iter().filter(|g| **g != Got::Skipped).collect();
        prop_assert_eq!(got.len(), items.len(), "{:?}", got);
        for (g, (f, _, ch, ticks)) in got.iter().zip(&items) {
            let Got::Frame { channel, id, extended, kind, data, time } = g else {
                return Err(TestCaseError::fail(format!("{g:?}")));
            };
            prop_assert_eq!(*kind, f.kind);
            prop_assert_eq!(channel, &ch.to_string());
            let (scale, digits) = if unit == 1 { (10_000u64, 6) } else { (1, 9) };
            let ns = u64::from(*ticks) * scale;
            let want = format!("{}.{:0d$}", 1_700_000_000 + ns / 1_000_000_000,
                (ns % 1_000_000_000) / 10u64.pow(9 - digits as u32), d = digits);
            prop_assert_eq!(time, &want);
            if f.kind == FrameKind::Error {
                continue;
            }
            prop_assert_eq!((*id, *extended), (f.id, f.extended));
            if f.kind != FrameKind::Remote {
                prop_assert_eq!(data, &f.data);
            }
        }
    }

    /// Any bytes after a valid header: no panic, no endless loop.
    #[test]
    fn any_bytes_are_read_to_the_end(body in prop::collection::vec(any::<u8>(), 0..600)) {
        // The BLF fuzz target: the reader's own checks, then the pipeline's.
        let mut f = file_header(START);
        f.extend(&body);
        emcy_decode::fuzzing::blf(&f);
        // And the same bytes inside a container.
        let mut g = file_header(START);
        g.extend(container(&body, true));
        emcy_decode::fuzzing::blf(&g);
    }
}
