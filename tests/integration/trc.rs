//! PEAK TRC: every version decodes to the same events as the candump log of
//! the same scenario; gzip copies read transparently; random frames rendered
//! as TRC rows come back as the same frames.

use std::io::Write;
use std::path::Path;

use emcy_decode::fuzzing::{self, Detector, Ids, Scanned};
use emcy_decode::{CanFrame, Format, FrameKind, Timestamp};
use proptest::prelude::*;
use serde_json::Value;

use crate::support::frames::*;
use crate::support::{self, PLACE, TIMES, emcy_decode, read_last};

const VERSIONS: [&str; 6] = ["v1_0", "v1_1", "v1_2", "v1_3", "v2_0", "v2_1"];

fn ndjson(path: &Path) -> Vec<Value> {
    support::ndjson([path])
}

/// Events and nodes without what depends on the trace format (like
/// `golden` does).
fn semantic(objects: &[Value], keep_time: bool) -> Vec<Value> {
    let mut drop = PLACE.to_vec();
    if !keep_time {
        drop.extend(TIMES);
    }
    support::semantic(objects, &drop)
}

/// The same instant, however many fraction digits each was written with.
fn same_instant(a: Timestamp, b: Timestamp) -> bool {
    !a.since(b).is_negative() && !b.since(a).is_negative()
}

#[test]
fn every_trc_version_decodes_like_the_candump_log() {
    let log = ndjson(Path::new("fixtures/s300.log"));
    assert!(log.iter().any(|o| o["type"] == "emcy"));
    for v in VERSIONS {
        let path = format!("fixtures/s300.{v}.trc");
        let trc = ndjson(Path::new(&path));
        let input = trc.iter().find(|o| o["type"] == "input").expect("input");
        assert_eq!(input["format"], "trc", "{path}");
        assert_eq!(input["malformed"], 0, "{path}");
        assert_eq!(semantic(&trc, false), semantic(&log, false), "{path}");
        if v != "v1_0" {
            // With ;$STARTTIME the times are absolute and equal the log's
            // (compared as JSON numbers: 1.1 offsets have 4 digits, the log 6).
            let times = |o: &[Value]| -> Vec<String> {
                o.iter()
                    .filter(|e| e["type"] == "emcy")
                    .map(|e| e["time"].to_string())
                    .collect()
            };
            assert_eq!(times(&trc), times(&log), "{path}");
        }
    }
    let edge = ndjson(Path::new("fixtures/edge.trc"));
    assert_eq!(
        semantic(&edge, true),
        semantic(&ndjson(Path::new("fixtures/edge.log")), true),
        "edge.trc"
    );
}

#[test]
fn gzip_trc_is_detected_from_content() {
    let plain = std::fs::read("fixtures/s300.v2_1.trc").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.bin");
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(&plain).unwrap();
    std::fs::write(&path, enc.finish().unwrap()).unwrap();
    let gz = ndjson(&path);
    let input = gz.iter().find(|o| o["type"] == "input").unwrap();
    assert_eq!(input["gzip"], true);
    assert_eq!(input["format"], "trc");
    assert_eq!(
        semantic(&gz, true),
        semantic(&ndjson(Path::new("fixtures/s300.v2_1.trc")), true)
    );
}

#[test]
fn forced_trc_and_counts_add_up() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "--input-format", "trc"])
        .arg("fixtures/edge.trc")
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let input: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    let n = |k: &str| input[k].as_u64().unwrap();
    assert_eq!(n("lines"), n("frames") + n("skipped") + n("malformed"));
    assert_eq!(n("malformed"), 1);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("fixtures/edge.trc:28: standard id 812 is over 7FF"),
        "{stderr}"
    );
}

/// `secs.frac` seconds as a millisecond offset text.
fn ms_text(f: &TestFrame) -> String {
    let digits = usize::from(f.digits);
    let frac = format!("{:0w$}", f.frac, w = digits);
    let (ms_part, rest) = if digits >= 3 {
        frac.split_at(3)
    } else {
        (frac.as_str(), "")
    };
    let ms_part = format!("{ms_part:0<3}");
    let whole = (u128::from(f.secs) * 1000 + ms_part.parse::<u128>().unwrap()).to_string();
    if rest.is_empty() {
        whole
    } else {
        format!("{whole}.{rest}")
    }
}

fn id_text(f: &TestFrame) -> String {
    if f.extended {
        format!("{:08X}", f.id)
    } else {
        format!("{:04X}", f.id)
    }
}

/// The header and the row of a frame in one version.
fn render(f: &TestFrame, version: &str, bus: u8) -> (Vec<String>, String) {
    let bytes = hex(&f.data, " ", false);
    let header = |v: &str, cols: Option<&str>| {
        let mut h = vec![format!(";$FILEVERSION={v}"), ";$STARTTIME=0".into()];
        h.extend(cols.map(|c| format!(";$COLUMNS={c}")));
        h
    };
    let ms = ms_text(f);
    let id = id_text(f);
    match version {
        "1.3" => {
            let (typ, id, body) = match f.kind {
                FrameKind::Remote => ("Rx", id, "RTR".to_string()),
                FrameKind::Error => ("Error", "0000".into(), bytes.clone()),
                _ => ("Tx", id, bytes.clone()),
            };
            (
                header("1.3", None),
                format!("  1) {ms} {bus} {typ} {id} - {} {body}", f.data.len()),
            )
        }
        "2.0" => {
            let typ = match f.kind {
                FrameKind::Data => "DT",
                FrameKind::Fd => "FB",
                FrameKind::Remote => "RR",
                FrameKind::Error => "ER",
            };
            let (id, body) = match f.kind {
                FrameKind::Error => (String::new(), bytes.clone()),
                FrameKind::Remote => (id, String::new()),
                _ => (id, bytes.clone()),
            };
            (
                header("2.0", Some("N,O,T,I,d,l,D")),
                format!("  7 {ms} {typ} {id} Rx {} {body}", f.data.len()),
            )
        }
        _ => {
            let typ = match f.kind {
                FrameKind::Data => "DT",
                FrameKind::Fd => "BI",
                FrameKind::Remote => "RR",
                FrameKind::Error => "ER",
            };
            // A DLC column: FD data is padded to the next FD length.
            let mut data = f.data.clone();
            let dlc = if f.kind == FrameKind::Fd {
                let dlc = fd_dlc(data.len());
                data.resize(FD_LENS[dlc], 0);
                dlc
            } else {
                data.len()
            };
            let body = match f.kind {
                FrameKind::Remote => String::new(),
                _ => hex(&data, " ", false),
            };
            let id = if f.kind == FrameKind::Error {
                "-".into()
            } else {
                id
            };
            (
                header("2.1", Some("N,O,T,B,I,d,R,L,D")),
                format!("  7 {ms} {typ} {bus} {id} Tx - {dlc} {body}"),
            )
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Random frames as TRC rows of 1.3, 2.0 and 2.1, read through format
    /// detection, come back as the same frames (error rows carry no id).
    #[test]
    fn random_frames_round_trip(
        f in frame(),
        version in prop_oneof![Just("1.3"), Just("2.0"), Just("2.1")],
        bus in 1u8..=16,
    ) {
        // Version 1 has no CAN FD; error ids are candump's, not TRC's.
        prop_assume!(!(version == "1.3" && f.kind == FrameKind::Fd));
        let (header, row) = render(&f, version, bus);
        let mut lines = header.clone();
        lines.push(row.clone());
        let (got, format) = read_last(&lines)?;
        prop_assert_eq!(format, Some(Format::Trc));
        prop_assert_eq!(got.kind, f.kind, "{}", row);
        // Version 2.0 has no bus column: everything is on channel 1.
        let bus_text = if version == "2.0" { "1".to_string() } else { bus.to_string() };
        prop_assert_eq!(&got.channel, &bus_text, "{}", row);
        let time = got.time.expect("wanted frames carry their time");
        prop_assert!(same_instant(time, f.time()), "{} read as {}", row, time);
        if f.kind == FrameKind::Error {
            return Ok(());
        }
        prop_assert_eq!(got.id, f.id, "{}", row);
        prop_assert_eq!(got.extended, f.extended, "{}", row);
        if f.kind != FrameKind::Remote {
            let n = f.data.len();
            prop_assert_eq!(&got.data[..n], f.data.as_slice(), "{}", row);
        }
        // The id-first path (the analysis's, not the reader's: through the
        // `fuzzing` hook) agrees: an unwanted valid row is only counted.
        let mut q = Detector::auto(Ids::All);
        for h in &header {
            q.parse(h.as_bytes());
        }
        q.parse(row.as_bytes());
        prop_assert!(
            q.fork(Ids::None).scan(row.as_bytes()) == Scanned::Plain
                || f.kind == FrameKind::Error
        );
        // And a wanted one comes back as the full parser reads it.
        prop_assert_eq!(
            q.fork(Ids::All).scan(row.as_bytes()),
            Scanned::Frame(CanFrame { line: 0, ..got })
        );
    }

    /// Whatever the bytes, the reader classifies every line without a panic.
    #[test]
    fn any_bytes_are_classified(lines in prop::collection::vec(
        prop::collection::vec(any::<u8>(), 0..120), 0..20)
    ) {
        let mut text = b";$FILEVERSION=2.1\n".to_vec();
        for l in &lines {
            text.extend_from_slice(l);
            text.push(b'\n');
        }
        // The TRC fuzz target: the reader's own checks, then the pipeline's.
        fuzzing::trc(&text);
    }
}

/// A start time that cannot be a time: before, the header line was taken
/// for a comment while the format was still being detected, and every time
/// became seconds since the start without a word. Now the line is
/// malformed, with its line number, and `--strict` fails.
#[test]
fn a_start_time_that_is_no_time_is_a_malformed_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    for bad in ["99999999999999", "999999999", "x"] {
        let path = dir.path().join("start.trc");
        let text = std::fs::read_to_string("fixtures/edge.trc")
            .expect("fixture")
            .replace(";$STARTTIME=45244.925", &format!(";$STARTTIME={bad}"));
        std::fs::write(&path, text).expect("write");
        let out = crate::support::emcy_decode()
            .args(["--format", "ndjson"])
            .arg(&path)
            .output()
            .expect("runs");
        let stderr = String::from_utf8(out.stderr).expect("utf-8");
        assert!(
            stderr.contains(&format!(
                "start.trc:2: '{bad}' is not a start time in days (since 1899-12-30, up to the \
                 year 9999): times are seconds since the start of the measurement"
            )),
            "{bad}: {stderr}"
        );
        let text = String::from_utf8(out.stdout).expect("utf-8");
        let input: serde_json::Value =
            serde_json::from_str(text.lines().last().expect("input")).expect("JSON");
        // The fixture's own malformed line, and this one.
        assert_eq!(input["malformed"], 2, "{bad}: {input}");
        assert_eq!(
            input["first_time_text"], "80.000000",
            "{bad}: since the start"
        );
    }
    // The start time on the first line, before anything says TRC (a 1.0
    // file has no `$FILEVERSION`): the line tells the format, and is still
    // reported.
    let path = dir.path().join("first.trc");
    let text = std::fs::read_to_string("fixtures/s300.v1_0.trc").expect("fixture");
    std::fs::write(&path, format!(";$STARTTIME=99999999999999\n{text}")).expect("write");
    let out = crate::support::emcy_decode()
        .args(["--strict"])
        .arg(&path)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    assert!(
        stderr.contains("first.trc:1: '99999999999999' is not a start time in days"),
        "{stderr}"
    );
}
