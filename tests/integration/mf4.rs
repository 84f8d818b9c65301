//! MF4 (ASAM MDF 4) bus logging through the binary and the library: the
//! fixtures of `scripts/make_mf4_fixtures.py`, each of which python-can
//! (through asammdf) reads as the frames it was written with (the script
//! checks that): python-can's own MF4Writer output, plain and transposed-
//! deflate DZ; CANedge's unfinalized layouts (DT length 24, records to the
//! end, VLSD data after its frame; the 73-group one with virtual constant
//! channels, a DLC table and 48-bit times); a finalized sorted file with an
//! HL/DL list of a DT and a DZ block and its SD block after the records;
//! and a damaged file.

use std::io::Write;
use std::path::Path;

use emcy_decode::{Format, FrameKind, Record, TraceReader};
use serde_json::Value;

use crate::support::{self, emcy_decode, input, run, semantic_6};

fn ndjson(args: &[&str]) -> Vec<Value> {
    support::ndjson(args)
}

fn frames(path: &str) -> Vec<emcy_decode::CanFrame> {
    let mut r = TraceReader::new(std::fs::File::open(path).unwrap());
    let frames: Vec<_> = r
        .by_ref()
        .filter_map(|x| match x.unwrap() {
            Record::Frame(f) => Some(f),
            _ => None,
        })
        .collect();
    assert_eq!(r.format(), Some(Format::Mf4), "{path}");
    frames
}

#[test]
fn every_s300_mf4_decodes_like_the_candump_log() {
    let log = semantic_6(&ndjson(&["fixtures/s300.log"]));
    assert!(log.iter().any(|o| o["type"] == "emcy"));
    for (file, channel) in [
        ("fixtures/s300.mf4", "1"),
        ("fixtures/s300.dz.mf4", "1"),
        ("fixtures/canedge.mf4", "1"),
        ("fixtures/canedge73.mf4", "1"),
        ("fixtures/sorted-sd.mf4", "3"),
    ] {
        let v = ndjson(&["--channel", channel, file]);
        // The CANedge recordings log an error frame the candump scenario
        // has not: the EMCYs, nodes and boot-ups are compared.
        let strip = |v: Vec<Value>| -> Vec<Value> {
            v.iter()
                .filter(|o| o["type"] != "bus_error" && o["type"] != "bus_off")
                .filter(|o| o["type"] != "incident")
                .map(|o| support::without(o, &["time_in_error"]))
                .collect()
        };
        assert_eq!(strip(semantic_6(&v)), strip(log.clone()), "{file}");
        let i = input(&v);
        assert_eq!(i["format"], "mf4", "{file}");
        assert_eq!(i["malformed"], 0, "{file}");
    }
}

#[test]
fn counts_of_every_fixture_are_pinned() {
    // (file, lines, frames, skipped, malformed, emcy): a line per record.
    for (file, lines, frames, skipped, malformed, emcy) in [
        ("fixtures/s300.mf4", 19, 19, 0, 0, 7),
        ("fixtures/s300.dz.mf4", 19, 19, 0, 0, 7),
        // 22 frames, their 20 VLSD records and 3 LIN frames (skipped).
        ("fixtures/canedge.mf4", 45, 22, 23, 0, 7),
        // 22 frames, the VLSD records of the 2 FD frames.
        ("fixtures/canedge73.mf4", 24, 22, 2, 0, 7),
        ("fixtures/sorted-sd.mf4", 20, 20, 0, 0, 7),
        ("fixtures/damaged.mf4", 13, 9, 0, 4, 2),
    ] {
        let v = ndjson(&[file]);
        let i = input(&v);
        let got = [
            &i["lines"],
            &i["frames"],
            &i["skipped"],
            &i["malformed"],
            &i["emcy"],
        ]
        .map(|x| x.as_u64().unwrap());
        assert_eq!(
            got,
            [lines, frames, skipped, malformed, emcy],
            "{file}: {i}"
        );
    }
}

#[test]
fn frames_are_what_python_can_reads() {
    // canedge.mf4: S300 on channel 1, a remote frame on 0x081, an error
    // frame, a 29-bit frame on channel 2 (as the generator checked).
    let f = frames("fixtures/canedge.mf4");
    assert_eq!(f.len(), 22);
    let remote = f.iter().find(|f| f.kind == FrameKind::Remote).unwrap();
    assert_eq!(
        (remote.id, remote.extended, remote.data.len()),
        (0x81, false, 0)
    );
    let error = f.iter().find(|f| f.kind == FrameKind::Error).unwrap();
    assert_eq!(error.channel, "1");
    let ext = f.iter().find(|f| f.extended).unwrap();
    assert_eq!(
        (ext.id, ext.channel.as_str(), ext.data.as_slice()),
        (0x100_0085, "2", &[0x10, 0x43, 8, 1, 0, 0, 0, 0][..])
    );
    // Lines are records in file order: LIN and VLSD records count too.
    assert_eq!(f[0].line, 1);
    assert_eq!(f[1].line, 3);
    // canedge73.mf4: FD frames of 12 and 64 bytes through the DLC table
    // and the VLSD group, 29 bits from a virtual IDE channel.
    let f = frames("fixtures/canedge73.mf4");
    let fd: Vec<_> = f.iter().filter(|f| f.kind == FrameKind::Fd).collect();
    assert_eq!(fd.len(), 2);
    assert_eq!((fd[0].id, fd[0].channel.as_str()), (0x085, "2"));
    assert_eq!(fd[0].data, (0..12).collect::<Vec<u8>>());
    assert_eq!(fd[1].data, (0..64).collect::<Vec<u8>>());
    let ide: Vec<_> = f.iter().filter(|f| f.extended).collect();
    assert_eq!(ide.len(), 1);
    assert_eq!(ide[0].id, 0x100_0085);
    // sorted-sd.mf4: the remote frame of the second data group comes after
    // the data frames (file order), the record split across DT and DZ whole.
    let f = frames("fixtures/sorted-sd.mf4");
    assert_eq!(f.last().map(|f| f.kind), Some(FrameKind::Remote));
    let s300 = frames("fixtures/s300.mf4");
    let data: Vec<_> = f.iter().take(19).map(|f| (f.id, f.data.clone())).collect();
    let want: Vec<_> = s300.iter().map(|f| (f.id, f.data.clone())).collect();
    assert_eq!(data, want);
}

/// A sorted file stores its groups one after another, so its last record
/// need not be its latest: its span runs from its earliest frame to its
/// latest, whichever group holds them, the same whether the frames were
/// decoded or only counted (`--timing` decodes every one).
#[test]
fn a_sorted_file_spans_its_earliest_to_its_latest_frame() {
    let file = "fixtures/sorted-sd.mf4";
    let f = frames(file);
    let times: Vec<_> = f.iter().filter_map(|f| f.time).collect();
    let latest = times.iter().max().expect("times").to_string();
    let last = times.last().expect("times").to_string();
    assert!(
        last < latest,
        "the file's last record is not its latest frame"
    );
    let span = |extra: &[&str]| {
        let mut args = extra.to_vec();
        args.push(file);
        let v = ndjson(&args);
        let input = v.iter().find(|o| o["type"] == "input").expect("input");
        (
            input["first_time_text"].as_str().map(String::from),
            input["last_time_text"].as_str().map(String::from),
        )
    };
    let default = span(&[]);
    assert_eq!(default.1.as_deref(), Some("2023-11-14T22:13:27.100000000Z"));
    assert_eq!(default.0.as_deref(), Some("2023-11-14T22:13:20.000000000Z"));
    assert_eq!(span(&["--timing"]), default);
}

#[test]
fn times_are_the_start_plus_the_master_channel_exactly() {
    let time = |file: &str, i: usize| {
        frames(file)[i]
            .time
            .map(|t| t.to_string())
            .unwrap_or_default()
    };
    // python-can: float seconds, to the microsecond here.
    assert_eq!(time("fixtures/s300.mf4", 8), "1700000001.250000");
    // CANedge: float nanoseconds x 1e-9 (9 digits); the HD's time zone
    // (+60 min) does not move UTC times.
    assert_eq!(time("fixtures/canedge.mf4", 8), "1700000001.250000000");
    // The 48-bit microsecond master x 1e-6.
    assert_eq!(time("fixtures/canedge73.mf4", 8), "1700000001.250000");
    // uint64 nanoseconds x 1e-9.
    assert_eq!(time("fixtures/sorted-sd.mf4", 8), "1700000001.250000000");
}

#[test]
fn gzip_and_stdin_read_as_the_file() {
    for file in ["fixtures/canedge.mf4", "fixtures/sorted-sd.mf4"] {
        let plain = std::fs::read(file).unwrap();
        let reference = semantic_6(&ndjson(&[file]));
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(&plain).unwrap();
        let gz = enc.finish().unwrap();
        for bytes in [plain, gz] {
            let (out, err, code) = run(&["--format", "ndjson", "-"], &bytes);
            assert_eq!(code, 0, "{err}");
            let v: Vec<Value> = out
                .lines()
                .map(|l| serde_json::from_str(l).unwrap())
                .collect();
            assert_eq!(semantic_6(&v), reference, "{file}");
            assert_eq!(input(&v)["format"], "mf4");
        }
    }
}

#[test]
fn input_format_mf4_is_forced_and_other_files_and_mdf3_are_refused() {
    let v = ndjson(&["--input-format", "mf4", "fixtures/s300.mf4"]);
    assert_eq!(input(&v)["emcy"], 7);
    let out = emcy_decode()
        .args(["--input-format", "mf4", "fixtures/s300.log"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("not an MDF file"), "{stderr}");
    // MDF 3: a clear one-line error, not garbage.
    let mut mdf3 = b"MDF     3.30    TOOL    ".to_vec();
    mdf3.resize(512, 0);
    let (_, err, code) = run(&["-"], &mdf3);
    assert_eq!(code, 2);
    assert!(
        err.contains("MDF version 3.30 is not read, only MDF 4"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    let help = emcy_decode().arg("--help").output().unwrap();
    assert!(String::from_utf8(help.stdout).unwrap().contains("- mf4:"));
}

#[test]
fn damage_is_reported_with_its_byte_offset_and_reading_goes_on() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "fixtures/damaged.mf4"])
        .output()
        .unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    for needle in [
        "damaged.mf4:1: 16 bytes at byte offset",
        "are no MDF block; skipped",
        "damaged.mf4:5: record id 9 is not declared by its data group",
        "damaged.mf4:6: DataLength 12 is more than the 8 data bytes stored",
        "damaged.mf4:13: record cut off by the end of its data (10 bytes)",
    ] {
        assert!(stderr.contains(needle), "{needle}: {stderr}");
    }
    // The EMCY after the damage (node 5, in the second DT block) is read.
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains(r#""node":5"#), "{text}");
    // Reading a truncated file at every length never fails or panics.
    let bytes = std::fs::read("fixtures/canedge73.mf4").unwrap();
    for cut in (0..bytes.len()).step_by(97) {
        let r = TraceReader::new(&bytes[..cut]);
        for record in r {
            if record.is_err() {
                break;
            }
        }
    }
}

/// A file of many DZ blocks listed after them (python-can's writer through
/// asammdf): the blocks are spooled and inflated ahead on a second thread
/// while the one before is decoded. Every record arrives once, in file
/// order, on any thread count.
#[test]
fn many_spooled_dz_blocks_read_in_order_and_whole() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("dz.mf4");
    let mut file = std::fs::File::create(&path).expect("create");
    // About 5 blocks of 4 MiB of records.
    let (records, emcy, _) =
        support::tracegen::write_mf4_dz(&mut file, 18 << 20, 20, 7).expect("write");
    drop(file);
    let path = path.to_str().expect("utf-8");
    let (out, err, code) = run(&["--format", "ndjson", "-j", "2", path], b"");
    assert_eq!(code, 0, "{err}");
    assert!(
        err.is_empty(),
        "no diagnostic (a block out of order would turn the clock back): {err}"
    );
    let objects: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect();
    let input = input(&objects);
    assert_eq!(input["frames"], Value::from(records));
    assert_eq!(input["emcy"], Value::from(emcy));
    assert!(emcy > 1000, "{emcy}");
    let lines: Vec<u64> = objects
        .iter()
        .filter(|o| o["type"] == "emcy")
        .map(|o| o["line"].as_u64().expect("a line"))
        .collect();
    assert!(lines.windows(2).all(|w| w[0] < w[1]), "in record order");
    let (one, _, _) = run(&["--format", "ndjson", "-j", "1", path], b"");
    assert_eq!(one, out);
}

/// `fixtures/s300.mf4` with the length of its first `##<id>` block set to
/// `len`, in a temporary file; and that block's offset.
fn with_block_length(id: &[u8; 2], len: u64) -> (tempfile::TempDir, std::path::PathBuf, usize) {
    let mut bytes = std::fs::read("fixtures/s300.mf4").unwrap();
    let sig = [b'#', b'#', id[0], id[1]];
    let at = bytes.windows(4).position(|w| w == sig).unwrap();
    bytes[at + 8..at + 16].copy_from_slice(&len.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("long.mf4");
    std::fs::write(&path, bytes).unwrap();
    (dir, path, at)
}

/// A block whose length runs past the end of the file: before, it was
/// skipped to the end in silence, with everything after it (`lines 0,
/// malformed 0`, exit 0 even with `--strict`). Now it is malformed, with
/// where, and reading goes on at the first block in it.
#[test]
fn a_block_longer_than_the_file_is_malformed_and_reading_goes_on() {
    // The comment before the data block, claiming 1 MiB: every record is
    // still read.
    let (_dir, path, at) = with_block_length(b"MD", 1 << 20);
    let out = emcy_decode()
        .args(["--format", "ndjson", path.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains(&format!(
            "long.mf4:1: ##MD block at byte offset {at} declares 1048576 bytes, but the file ends"
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains(": read on from the block at byte offset"),
        "{stderr}"
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let input: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(
        (
            input["frames"].as_u64(),
            input["emcy"].as_u64(),
            input["malformed"].as_u64()
        ),
        (Some(19), Some(7), Some(1)),
        "{input}"
    );
    emcy_decode()
        .args(["--strict", path.to_str().unwrap()])
        .assert()
        .code(2);
    // A channel group claiming 2^62 bytes: its group is lost, and said so.
    let (_dir, path, at) = with_block_length(b"CG", 1 << 62);
    let out = emcy_decode()
        .args(["--strict", path.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains(&format!(
            "##CG block at byte offset {at} declares 4611686018427387904 bytes, but the file ends"
        )),
        "{stderr}"
    );
}

/// A file whose data comes before its metadata keeps that data in a
/// temporary file: when none can be made, the message blames the
/// temporary directory, not the trace (before: `error: s300.mf4: No such
/// file or directory`, as if the trace were missing), gzip or not.
#[test]
fn without_a_temporary_directory_the_message_blames_it() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("gone");
    let gz = dir.path().join("s300.mf4.gz");
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(&std::fs::read("fixtures/s300.mf4").unwrap())
        .unwrap();
    std::fs::write(&gz, enc.finish().unwrap()).unwrap();
    for trace in [Path::new("fixtures/s300.mf4"), gz.as_path()] {
        let out = emcy_decode()
            .env("TMPDIR", &missing)
            .arg(trace)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{}", trace.display());
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert!(
            stderr.contains(&format!(
                "{}: cannot create a temporary file in {} (TMPDIR) for the MF4 data written \
                 before its metadata: No such file or directory",
                trace.display(),
                missing.display()
            )),
            "{stderr}"
        );
    }
}
