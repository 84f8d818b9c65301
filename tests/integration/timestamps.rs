//! candump `-td` delta times: detected from the first lines or
//! said with `--timestamps`, summed exactly, across blocks and threads, in
//! the program and in the library's reader.

use std::fmt::Write as _;
use std::fs::File;

use emcy_decode::{Record, TimeMode, TraceReader};
use serde_json::Value;

use crate::support::{PLACE, TIMES, binary, emcy_decode, ndjson, semantic};

/// The `"time"` texts of the EMCY events in ndjson output, exactly as
/// printed (a JSON number read as f64 would round them).
fn event_times(stdout: &str) -> Vec<String> {
    stdout
        .lines()
        .filter(|l| l.starts_with("{\"type\":\"emcy\""))
        .map(|l| {
            let at = l.find("\"time\":").expect("a time") + 7;
            let rest = &l[at..];
            rest[..rest.find(',').expect("more keys")].to_string()
        })
        .collect()
}

fn run(args: &[&str]) -> (String, String) {
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .args(args)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(0), "{args:?}");
    (
        String::from_utf8(out.stdout).expect("utf-8"),
        String::from_utf8(out.stderr).expect("utf-8"),
    )
}

fn input(stdout: &str) -> Value {
    let last = stdout.lines().last().expect("an input object");
    serde_json::from_str(last).expect("JSON")
}

/// `1700000000` plus a summed time, as text: the -ta trace's time.
fn plus_base(t: &str) -> String {
    let (int, frac) = t.split_once('.').expect("a fraction");
    format!(
        "{}.{frac}",
        1_700_000_000 + int.parse::<u64>().expect("seconds")
    )
}

#[test]
fn td_traces_are_summed_to_the_times_of_the_same_trace_with_ta() {
    let (absolute, _) = run(&["fixtures/s300.txt"]);
    let expected = event_times(&absolute);
    assert_eq!(expected.len(), 7);
    for td in ["fixtures/s300.td.txt", "fixtures/s300.td.log"] {
        let (out, err) = run(&[td]);
        let summed: Vec<String> = event_times(&out).iter().map(|t| plus_base(t)).collect();
        assert_eq!(summed, expected, "{td}");
        assert!(
            err.contains("times read as candump -td deltas and summed: 3 of the first 15"),
            "{td}: {err}"
        );
        assert!(!err.contains("went backwards"), "{td}: {err}");
        assert_eq!(input(&out)["timestamps"], "delta", "{td}");
        // Everything but the times and places is what the -ta trace gives.
        let objects = |args: &str| semantic(&ndjson([args]), &[&PLACE[..], &TIMES[..]].concat());
        let drop_format = |mut v: Vec<Value>| {
            for o in &mut v {
                if let Some(o) = o.as_object_mut() {
                    o.remove("format");
                    o.remove("timestamps");
                }
            }
            v
        };
        assert_eq!(
            drop_format(objects(td)),
            drop_format(objects("fixtures/s300.txt")),
            "{td}"
        );
    }
}

#[test]
fn traces_read_as_written_have_no_note_and_no_timestamps_key() {
    for trace in [
        "fixtures/s300.txt",
        "fixtures/festo.txt",
        "fixtures/s300.log",
    ] {
        let (out, err) = run(&[trace]);
        assert!(!err.contains("deltas"), "{trace}: {err}");
        assert!(input(&out).get("timestamps").is_none(), "{trace}");
    }
}

#[test]
fn zero_based_times_are_read_as_written_with_or_without_the_flag() {
    let (detected, _) = run(&["fixtures/festo.txt"]);
    let (said, err) = run(&["--timestamps", "zero", "fixtures/festo.txt"]);
    assert_eq!(said, detected);
    assert!(err.is_empty(), "{err}");
}

#[test]
fn timestamps_absolute_reads_deltas_as_written() {
    let (out, err) = run(&["--timestamps", "absolute", "fixtures/s300.td.txt"]);
    assert!(!err.contains("deltas and summed"), "{err}");
    assert!(err.contains("went backwards"), "{err}");
    assert!(
        !err.contains("--timestamps delta sums"),
        "said, so no hint: {err}"
    );
    assert!(input(&out).get("timestamps").is_none());
    assert_eq!(
        event_times(&out).last().map(String::as_str),
        Some("0.900000")
    );
}

/// `trace` piped to the binary (a live stream) with `flags`: (stdout, stderr).
fn piped(trace: &str, flags: &[&str]) -> (String, String) {
    let out = emcy_decode()
        .args(["--format", "ndjson", "-"])
        .args(flags)
        .write_stdin(trace.to_string())
        .output()
        .expect("runs");
    (
        String::from_utf8(out.stdout).expect("utf-8"),
        String::from_utf8(out.stderr).expect("utf-8"),
    )
}

/// Equal deltas never go backwards: nothing proves them, so a file of
/// them is read as written unless the user says what they are.
#[test]
fn equal_deltas_are_not_detected_and_timestamps_delta_sums_them() {
    let mut trace = String::new();
    for i in 0..20 {
        let frame = if i == 10 {
            "081#1043080100000000"
        } else {
            "701#05"
        };
        writeln!(trace, "(000.100000) can0 {frame}").unwrap();
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("equal.td.log");
    std::fs::write(&path, &trace).expect("write");
    let (out, err) = run(&[path.to_str().expect("utf-8")]);
    assert_eq!(event_times(&out), ["0.100000"]);
    assert!(err.is_empty(), "{err}");
    let (summed, _) = piped(&trace, &["--timestamps", "delta"]);
    assert_eq!(event_times(&summed), ["1.100000"]);
    assert_eq!(input(&summed)["timestamps"], "delta");
}

/// A live stream is not read ahead (its first event would wait for 16
/// lines): deltas there are said with the flag, and a time going backwards
/// says so.
#[test]
fn a_live_td_stream_is_summed_when_said_and_hinted_when_not() {
    let trace = std::fs::read_to_string("fixtures/s300.td.txt").expect("fixture");
    let read = |flags: &[&str]| piped(&trace, flags);
    let (out, err) = read(&[]);
    assert_eq!(
        event_times(&out).last().map(String::as_str),
        Some("0.900000")
    );
    assert!(
        err.contains("went backwards (durations across this line are negative); if these are candump -td deltas, --timestamps delta sums them"),
        "{err}"
    );
    let (out, err) = read(&["--timestamps", "delta"]);
    assert_eq!(
        event_times(&out).last().map(String::as_str),
        Some("7.000000")
    );
    assert!(err.is_empty(), "{err}");
    assert_eq!(input(&out)["timestamps"], "delta");
}

/// A -td trace on stdin redirected from a file (`< trace.txt`: not a
/// stream) is detected as from a file.
#[test]
fn a_td_trace_redirected_to_stdin_is_detected() {
    let out = binary()
        .args(["--format", "ndjson", "-"])
        .stdin(File::open("fixtures/s300.td.txt").expect("fixture"))
        .output()
        .expect("runs");
    let stdout = String::from_utf8(out.stdout).expect("utf-8");
    let (file, _) = run(&["fixtures/s300.td.txt"]);
    assert_eq!(event_times(&stdout), event_times(&file));
    assert_eq!(input(&stdout)["timestamps"], "delta");
}

/// Summing chains every line to the one before: a trace of many blocks
/// read with several threads gives exactly the sum, and the output of one.
#[test]
fn deltas_are_summed_exactly_across_blocks_whatever_the_thread_count() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("big.td.log");
    let mut trace = String::new();
    let n = 200_000u64;
    let mut sum_us = 0u64;
    for i in 0..n {
        // 100 and 300 us alternating, an EMCY every 10 000 frames.
        let us = if i % 2 == 0 { 100 } else { 300 };
        let us = if i == 0 { 0 } else { us };
        sum_us += us;
        let frame = if i % 10_000 == 9_999 {
            "081#1043080100000000"
        } else {
            "181#0000000000000000"
        };
        writeln!(trace, "(000.{us:06}) can0 {frame}").unwrap();
    }
    std::fs::write(&path, &trace).expect("write");
    assert!(trace.len() > 4 << 20, "several 1 MiB blocks");
    let path = path.to_str().expect("utf-8 path");
    let (one, _) = run(&["-j", "1", path]);
    let (four, err) = run(&["-j", "4", path]);
    assert_eq!(one, four);
    assert!(err.contains("deltas and summed"), "{err}");
    let times = event_times(&one);
    assert_eq!(times.len(), 20);
    assert_eq!(
        input(&one)["frames"],
        Value::from(n),
        "every frame counted once"
    );
    let last = format!("{}.{:06}", sum_us / 1_000_000, sum_us % 1_000_000);
    assert_eq!(times.last(), Some(&last));
    // The EMCY at frame 9 999: 5 000 steps of 300 us, 4 999 of 100 us.
    assert_eq!(times[0], "1.999900");
}

#[test]
fn the_library_reader_sums_deltas_too_unless_told_otherwise() {
    let frames = |reader: TraceReader<'_>| -> (Vec<String>, Vec<String>) {
        let (mut notes, mut times) = (Vec::new(), Vec::new());
        for record in reader {
            match record.expect("reads") {
                Record::Note(n) => notes.push(n),
                Record::Frame(f) if f.id == 0x81 => {
                    times.push(f.time.expect("a time").to_string());
                }
                _ => {}
            }
        }
        (notes, times)
    };
    let open = || File::open("fixtures/s300.td.txt").expect("fixture");
    let (notes, times) = frames(TraceReader::new(open()));
    assert_eq!(notes.len(), 1);
    assert!(notes[0].contains("deltas and summed"), "{notes:?}");
    assert_eq!(times.first().map(String::as_str), Some("1.250000"));
    assert_eq!(times.last().map(String::as_str), Some("7.000000"));
    let (notes, times) = frames(TraceReader::new(open()).with_timestamps(TimeMode::Absolute));
    assert!(notes.is_empty(), "{notes:?}");
    assert_eq!(times.first().map(String::as_str), Some("1.050000"));
    // And said for a trace nothing proves: the -ta trace's times summed.
    let log = File::open("fixtures/s300.log").expect("fixture");
    let (notes, times) = frames(TraceReader::new(log).with_timestamps(TimeMode::Delta));
    assert!(notes.is_empty());
    assert_eq!(times.len(), 7);
    let first: f64 = times[0].parse().expect("a number");
    assert!(
        (9.0 * 1.7e9..9.0 * 1.7e9 + 10.0).contains(&first),
        "{times:?}"
    );
}

/// The input's span is its first and last frame, decoded or not: s300 ends
/// with a TPDO nobody decodes, 7.1 s after its first frame, in every format
/// that has times (from a text block's edges, a pcap packet's header, a
/// BLF object, an MF4 record), on one thread and on two.
#[test]
fn the_input_spans_every_frame_decoded_or_not_in_every_format() {
    let formats = [
        "s300.log",
        "s300.log.gz",
        "s300.td.log",
        "s300.td.txt",
        "s300.asc",
        "s300.busmaster.log",
        "s300.v1_1.trc",
        "s300.v2_1.trc",
        "s300.pcap",
        "s300.swapped.pcap",
        "s300.blf",
        "s300.plain.blf",
        "s300.mf4",
        "s300.dz.mf4",
    ];
    for name in formats {
        for threads in ["-j1", "-j2"] {
            let path = format!("fixtures/{name}");
            let (stdout, _) = run(&["-q", threads, &path]);
            let input = input(&stdout);
            let (first, last) = (&input["first_time"], &input["last_time"]);
            let span = last.as_f64().expect("a last time") - first.as_f64().expect("a first time");
            assert!(
                (span - 7.1).abs() < 1e-6,
                "{name} {threads}: span {span} ({first} to {last})"
            );
        }
    }
}
