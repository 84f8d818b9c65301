//! pcap and pcapng through the binary: the fixtures of
//! `scripts/make_pcap_fixtures.py` (the S300 sequence as a pcap in both
//! byte orders and units, with link type 227's id word swapped, as a
//! pcapng with several interfaces; `mixed.pcapng` with CAN FD, frames that
//! are not EMCYs and damage) decode like the candump log, name their
//! channels, keep nanoseconds exactly, read from gzip and stdin, and say
//! what they skip and why.

use std::io::Write;
use std::path::Path;

use emcy_decode::{Format, Record, TraceReader};
use serde_json::Value;

use crate::support::{self, emcy_decode, input, run, semantic_6};

fn ndjson(args: &[&str]) -> Vec<Value> {
    support::ndjson(args)
}

fn events(v: &[Value]) -> Vec<&Value> {
    v.iter()
        .filter(|o| o["type"] == "emcy" || o["type"] == "boot")
        .collect()
}

fn lines_of(stdout: &str) -> Vec<Value> {
    stdout
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect()
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes).unwrap();
    enc.finish().unwrap()
}

#[test]
fn every_s300_capture_decodes_like_the_candump_log() {
    let log = semantic_6(&ndjson(&["fixtures/s300.log"]));
    assert!(log.iter().any(|o| o["type"] == "emcy"));
    for (capture, format) in [
        ("fixtures/s300.pcap", "pcap"),
        ("fixtures/s300.ns-be.pcap", "pcap"),
        ("fixtures/s300.swapped.pcap", "pcap"),
        ("fixtures/s300.pcapng", "pcapng"),
    ] {
        // s300.pcapng has more on other interfaces: its can0 is the log
        // (but for the time in error, counted to the input's last frame).
        let v = ndjson(&["--channel", "can0", "--channel", "0", capture]);
        let strip = |v: Vec<Value>| -> Vec<Value> {
            v.iter()
                .map(|o| support::without(o, &["time_in_error"]))
                .collect()
        };
        assert_eq!(strip(semantic_6(&v)), strip(log.clone()), "{capture}");
        let i = input(&v);
        assert_eq!(i["format"], format, "{capture}");
        assert_eq!(i["malformed"], 0, "{capture}");
    }
}

#[test]
fn node_guarding_from_a_capture_is_as_from_the_candump_log() {
    // The guard requests are remote frames on 0x700 + node: a capture
    // hands them to node guarding as the text readers do.
    let log = semantic_6(&ndjson(&["fixtures/network-guarding.log"]));
    let capture = semantic_6(&ndjson(&["fixtures/network-guarding.pcap"]));
    assert!(
        log.iter()
            .any(|o| o["type"] == "node" && o["heartbeat"]["via"] == "guarding"),
        "the log is guarded"
    );
    assert_eq!(capture, log);
}

#[test]
fn pcapng_interfaces_are_channels_by_if_name_and_non_can_packets_are_skipped() {
    let v = ndjson(&["fixtures/s300.pcapng"]);
    let i = input(&v);
    // 19 frames of the S300 sequence on can0, 2 on can1, 1 on interface 3;
    // 2 LIN packets and 1 ARP packet skipped; the other blocks not lines.
    assert_eq!(
        (
            &i["lines"],
            &i["frames"],
            &i["skipped"],
            &i["malformed"],
            &i["emcy"]
        ),
        (
            &Value::from(25),
            &Value::from(22),
            &Value::from(3),
            &Value::from(0),
            &Value::from(10)
        ),
        "{i}"
    );
    let mut channels: Vec<&str> = events(&v)
        .iter()
        .map(|e| e["channel"].as_str().unwrap())
        .collect();
    channels.dedup();
    assert_eq!(channels, ["can0", "can1", "3"]);
    // The line is the packet's number, as Wireshark numbers frames.
    let last = events(&v).last().copied().unwrap().clone();
    assert_eq!(
        (&last["line"], &last["node"]),
        (&Value::from(25), &Value::from(6))
    );
}

#[test]
fn times_are_exact_nanoseconds_and_binary_fractions() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "fixtures/s300.ns-be.pcap"])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains(r#""time":1700000001.250000007"#), "{text}");
    assert!(
        text.contains(r#""first_time":1700000000.000000007"#),
        "{text}"
    );
    let out = emcy_decode()
        .args(["--format", "ndjson", "fixtures/s300.pcapng"])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    // can0: if_tsresol 9; can1: 2^-10 s; interface 3: if_tsoffset.
    assert!(
        text.contains(r#""time":1700000001.250000000,"time_text":"2023-11-14T22:13:21.250000000Z","channel":"can0""#),
        "{text}"
    );
    assert!(
        text.contains(r#""time":1700000008.0009765625,"time_text":"2023-11-14T22:13:28.0009765625Z","channel":"can1""#),
        "{text}"
    );
    assert!(
        text.contains(
            r#""time":1700000009.500000,"time_text":"2023-11-14T22:13:29.500000Z","channel":"3""#
        ),
        "{text}"
    );
}

#[test]
fn gzip_and_stdin_read_as_the_file() {
    let plain = std::fs::read("fixtures/s300.pcapng").unwrap();
    let reference = semantic_6(&ndjson(&["fixtures/s300.pcapng"]));
    let dir = tempfile::tempdir().unwrap();
    let gz = dir.path().join("capture.pcapng.gz");
    std::fs::write(&gz, gzip(&plain)).unwrap();
    let v = ndjson(&[gz.to_str().unwrap()]);
    assert_eq!(semantic_6(&v), reference);
    assert_eq!(
        (&input(&v)["gzip"], &input(&v)["format"]),
        (&Value::from(true), &Value::from("pcapng"))
    );
    for bytes in [plain.clone(), gzip(&plain)] {
        let (out, err, code) = run(&["--format", "ndjson", "-"], &bytes);
        assert_eq!(code, 0, "{err}");
        let v = lines_of(&out);
        assert_eq!(semantic_6(&v), reference);
        assert_eq!(input(&v)["file"], "<stdin>");
    }
}

#[test]
fn input_format_pcap_forces_both_flavours_and_refuses_text() {
    for (file, format) in [
        ("fixtures/s300.pcap", "pcap"),
        ("fixtures/s300.pcapng", "pcapng"),
    ] {
        for value in ["pcap", "pcapng"] {
            let v = ndjson(&["--input-format", value, file]);
            assert_eq!(input(&v)["format"], format, "{value} {file}");
            assert_eq!(input(&v)["emcy"].as_u64().map(|n| n >= 7), Some(true));
        }
    }
    let out = emcy_decode()
        .args(["--input-format", "pcap", "fixtures/s300.log"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains(
            "error: fixtures/s300.log: not a pcap or pcapng file: it starts with 28 31 37"
        ),
        "{stderr}"
    );
    // A text format forced on a capture reads its bytes as lines.
    let out = emcy_decode()
        .args(["--input-format", "candump", "fixtures/s300.pcap"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    // --help lists the value.
    let help = emcy_decode().arg("--help").output().unwrap();
    assert!(String::from_utf8(help.stdout).unwrap().contains("- pcap:"));
}

#[test]
fn swapped_socketcan_ids_are_noted_once_and_read_right() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "fixtures/s300.swapped.pcap"])
        .output()
        .unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert_eq!(
        stderr.matches("stored little-endian").count(),
        1,
        "{stderr}"
    );
    assert!(
        stderr.starts_with(
            "fixtures/s300.swapped.pcap: the CAN ids of the CAN_SOCKETCAN packets are stored \
             little-endian, not big-endian as the link type defines"
        ),
        "{stderr}"
    );
    let v = lines_of(&String::from_utf8(out.stdout).unwrap());
    assert_eq!(input(&v)["emcy"], 7);
    // The same ids big-endian, as the link type defines: no note.
    let out = emcy_decode()
        .args(["--format", "ndjson", "fixtures/s300.pcap"])
        .output()
        .unwrap();
    assert_eq!(String::from_utf8(out.stderr).unwrap(), "");
    // The library says it as a note record, not a line.
    let mut notes = 0;
    let mut lines = 0;
    for record in TraceReader::new(std::fs::File::open("fixtures/s300.swapped.pcap").unwrap()) {
        match record.unwrap() {
            Record::Note(n) => {
                assert!(n.contains("little-endian"));
                notes += 1;
            }
            _ => lines += 1,
        }
    }
    assert_eq!((notes, lines), (1, 19));
}

#[test]
fn damage_is_reported_with_packet_and_byte_and_reading_goes_on() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "fixtures/mixed.pcapng"])
        .output()
        .unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    for expected in [
        "fixtures/mixed.pcapng:8: node 2: EMCY frame has 2 data bytes",
        "fixtures/mixed.pcapng:10: block of type 0x00000006 at byte 696 declares 4294967295 bytes",
        "fixtures/mixed.pcapng:11: a packet on interface 7, which no interface description declares",
        "fixtures/mixed.pcapng:12: LINUX_SLL packet: classic CAN frame of 9 bytes (at most 8)",
    ] {
        assert!(stderr.contains(expected), "{expected}\n{stderr}");
    }
    let v = lines_of(&String::from_utf8(out.stdout).unwrap());
    let i = input(&v);
    // FD, remote, error and extended frames on EMCY ids are not EMCYs; the
    // reset after the damage is.
    let codes: Vec<&str> = v
        .iter()
        .filter(|o| o["type"] == "emcy")
        .map(|o| o["code"].as_str().unwrap())
        .collect();
    assert_eq!(codes, ["0x4310", "0x8130", "0x0000"]);
    assert_eq!(
        (
            &i["frames"],
            &i["malformed"],
            &i["emcy_invalid"],
            &i["lines"]
        ),
        (
            &Value::from(10),
            &Value::from(3),
            &Value::from(1),
            &Value::from(13)
        ),
        "{i}"
    );
    // --strict turns it into exit 2.
    let strict = emcy_decode()
        .args(["--strict", "fixtures/mixed.pcapng"])
        .output()
        .unwrap();
    assert_eq!(strict.status.code(), Some(2));
}

#[test]
fn a_truncated_or_corrupt_gzip_capture_keeps_what_was_read() {
    let plain = std::fs::read("fixtures/s300.pcap").unwrap();
    let gz = gzip(&plain);
    let (out, err, code) = run(&["--format", "ndjson", "-"], &gz[..gz.len() - 12]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("error: <stdin>: "), "{err}");
    let v = lines_of(&out);
    assert!(input(&v)["error"].is_string());
    assert_eq!(input(&v)["format"], "pcap");
}

#[test]
fn the_library_reads_captures_packet_by_packet() {
    let mut r = TraceReader::new(std::fs::File::open("fixtures/s300.pcapng").unwrap());
    let frames: Vec<_> = r
        .by_ref()
        .filter_map(|x| match x.unwrap() {
            Record::Frame(f) => Some(f),
            _ => None,
        })
        .collect();
    assert_eq!(r.format(), Some(Format::Pcapng));
    assert_eq!(frames.len(), 22);
    assert_eq!((frames[21].line, frames[21].channel.as_str()), (25, "3"));
    assert_eq!(
        frames[20].time.map(|t| t.to_string()),
        Some("1700000008.5000000000".to_string())
    );
    assert!(Path::new("scripts/make_pcap_fixtures.py").exists());
}

/// `--follow` on a capture that grows (dumpcap writing it): each event is
/// printed as its packet is written, not held for the byte-order sample or
/// until Ctrl-C, and Ctrl-C says nothing about lines (a capture has none).
#[cfg(unix)]
#[test]
fn a_followed_capture_prints_events_as_it_grows() {
    use crate::live::{WAIT, exit_within_wait, interrupt, lines_of, spawn};

    let whole = std::fs::read("fixtures/s300.pcap").expect("fixture");
    // The pcap header and the first 8 packets (16-byte record header and
    // 16-byte frame each): up to the boot-up and before the first EMCY.
    let cut = 24 + 8 * 32;
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("live.pcap");
    std::fs::write(&path, &whole[..cut]).expect("write");
    let mut child = spawn(&[
        "--follow",
        "--format",
        "ndjson",
        path.to_str().expect("utf-8"),
    ]);
    let out = lines_of(child.stdout.take().expect("stdout"));
    let err = lines_of(child.stderr.take().expect("stderr"));
    let next = || -> Value {
        let line = out
            .recv_timeout(WAIT)
            .expect("an event while the capture grows");
        serde_json::from_str(&line).expect("JSON")
    };
    assert_eq!(
        next()["type"],
        "boot",
        "the boot-up, before more is written"
    );
    let mut file = std::fs::OpenOptions::new()
        .append(true)
        .open(&path)
        .expect("open");
    file.write_all(&whole[cut..]).expect("append");
    drop(file);
    let mut emcy = 0;
    while emcy < 7 {
        if next()["type"] == "emcy" {
            emcy += 1;
        }
    }
    interrupt(&child);
    assert_eq!(exit_within_wait(&mut child, "--follow"), Some(130));
    let notes: Vec<String> = err.try_iter().collect();
    assert!(!notes.iter().any(|n| n.contains("line")), "{notes:?}");
}

/// `--follow` on a libpcap capture whose writer starts again (a restarted
/// tcpdump truncates the file and writes a new 24-byte header; `-C`/`-G`
/// rotation renames it and starts a new one). Before, the new header was
/// read as a record and the next record's time as a captured length
/// ("declares 1700000000 captured bytes"): every packet of the new file
/// was skipped. Now the header starts the new file over, with a note.
#[cfg(unix)]
fn follow_a_capture_started_again(start_again: fn(&std::path::Path, &[u8])) {
    use crate::live::{WAIT, exit_within_wait, interrupt, lines_of, spawn};

    let whole = std::fs::read("fixtures/s300.pcap").expect("fixture");
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("live.pcap");
    std::fs::write(&path, &whole).expect("write");
    let mut child = spawn(&[
        "--follow",
        "--format",
        "ndjson",
        path.to_str().expect("utf-8"),
    ]);
    let out = lines_of(child.stdout.take().expect("stdout"));
    let err = lines_of(child.stderr.take().expect("stderr"));
    let mut objects: Vec<Value> = Vec::new();
    let wait_emcys = |n: usize, objects: &mut Vec<Value>| {
        while objects.iter().filter(|o| o["type"] == "emcy").count() < n {
            let line = out.recv_timeout(WAIT).unwrap_or_else(|_| {
                panic!(
                    "{n} EMCYs never came: {objects:?}, stderr {:?}",
                    err.try_iter().collect::<Vec<_>>()
                )
            });
            objects.push(serde_json::from_str(&line).expect("JSON"));
        }
    };
    wait_emcys(7, &mut objects);
    // The new capture's packets are those of the first 100 s later (the
    // same bytes at the same place would be no truncation to see).
    let mut later = whole.clone();
    let mut at = 24;
    while at + 16 <= later.len() {
        let secs = u32::from_le_bytes(later[at..at + 4].try_into().expect("4 bytes")) + 100;
        later[at..at + 4].copy_from_slice(&secs.to_le_bytes());
        at += 16 + u32::from_le_bytes(later[at + 8..at + 12].try_into().expect("4 bytes")) as usize;
    }
    start_again(&path, &later);
    wait_emcys(14, &mut objects);
    interrupt(&child);
    assert_eq!(exit_within_wait(&mut child, "--follow"), Some(130));
    objects.extend(out.iter().map(|l| serde_json::from_str(&l).expect("JSON")));
    let input = objects.last().expect("the input object");
    assert_eq!(input["type"], "input");
    assert_eq!(
        (input["frames"].as_u64(), input["malformed"].as_u64()),
        (Some(38), Some(0)),
        "{input}"
    );
    let notes: Vec<String> = err.iter().collect();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("a new pcap file header at byte 598")),
        "{notes:?}"
    );
}

#[cfg(unix)]
#[test]
fn a_followed_capture_truncated_by_a_restarted_writer_is_read_on_from_its_new_header() {
    follow_a_capture_started_again(|path, whole| std::fs::write(path, whole).expect("rewrite"));
}

#[cfg(unix)]
#[test]
fn a_followed_capture_rotated_to_a_new_file_is_read_on_from_its_new_header() {
    follow_a_capture_started_again(|path, whole| {
        std::fs::rename(path, path.with_extension("pcap.1")).expect("rename");
        std::fs::write(path, whole).expect("new file");
    });
}
