//! BUSMASTER logs: each fixture decodes to the same events as the candump log
//! of its scenario; appended sessions read the same on many threads as on
//! one; random frames written as BUSMASTER lines come back as the same
//! frames through format detection.

use std::fmt::Write as _;
use std::path::Path;

use emcy_decode::{Format, FrameKind};
use proptest::prelude::*;
use serde_json::Value;

use crate::support::frames::*;
use crate::support::{self, PLACE, TIMES, emcy_decode, read_last};

fn ndjson(args: &[&str]) -> Vec<Value> {
    support::ndjson(args.iter().map(Path::new))
}

fn input(objects: &[Value]) -> &Value {
    objects
        .iter()
        .find(|o| o["type"] == "input")
        .expect("an input object")
}

fn emcy_times(objects: &[Value]) -> Vec<String> {
    objects
        .iter()
        .filter(|e| e["type"] == "emcy")
        .map(|e| e["time"].to_string())
        .collect()
}

#[test]
fn every_busmaster_fixture_decodes_like_the_candump_log() {
    // (scenario, flags, whether the times are the log's Unix times)
    let cases: [(&str, &[&str], bool); 4] = [
        ("s300", &[], true),
        ("stoeber", &[], false),
        ("festo", &[], false),
        ("canopennode", &["--profile", "20=canopennode"], true),
    ];
    for (scenario, flags, wall_clock) in cases {
        let bm_path = format!("fixtures/{scenario}.busmaster.log");
        let log_path = format!("fixtures/{scenario}.log");
        let bm = ndjson(&[flags, &[bm_path.as_str()]].concat());
        let log = ndjson(&[flags, &[log_path.as_str()]].concat());
        assert!(log.iter().any(|o| o["type"] == "emcy"), "{log_path}");
        assert_eq!(input(&bm)["format"], "busmaster", "{bm_path}");
        assert_eq!(input(&bm)["malformed"], 0, "{bm_path}");
        let drop = [&PLACE[..], &TIMES[..]].concat();
        assert_eq!(
            support::semantic(&bm, &drop),
            support::semantic(&log, &drop),
            "{bm_path}"
        );
        if scenario == "canopennode" {
            // Its first line is SYNC in decimal (`0128`), which the
            // candump twin lacks: timed as SYNC, not read as an EMCY.
            let timed = ndjson(&[flags, &["--timing", bm_path.as_str()]].concat());
            let sync: Vec<_> = timed
                .iter()
                .filter(|o| o["type"] == "channel")
                .flat_map(|o| o["ids"].as_array().cloned().unwrap_or_default())
                .filter(|id| id["service"] == "sync")
                .collect();
            assert_eq!(sync.len(), 1, "{bm_path}");
            assert_eq!(sync[0]["cob_id"], 0x80);
            assert_eq!(sync[0]["count"], 1);
        }
        if wall_clock {
            // System times on the start date are the log's Unix times
            // (compared as numbers: 4 fraction digits against 6).
            let num = |v: Vec<String>| -> Vec<f64> {
                v.iter().map(|t| t.parse::<f64>().unwrap()).collect()
            };
            assert_eq!(num(emcy_times(&bm)), num(emcy_times(&log)), "{bm_path}");
        }
    }
    // Absolute and relative times: seconds since logging started.
    let festo = ndjson(&["fixtures/festo.busmaster.log"]);
    // (JSON numbers: serde_json drops the trailing zeros of "0.2000".)
    assert_eq!(emcy_times(&festo), ["0.2", "0.8", "1.5", "2.5", "3.5"]);
}

#[test]
fn appended_sessions_read_like_the_edge_log() {
    // Three CAN sessions (DEC, HEX, 2.4) and a LIN one between them hold
    // the edge scenario; the last line is malformed (a 3-digit byte in HEX).
    let bm = ndjson(&["fixtures/edge.busmaster.log"]);
    let log = ndjson(&["fixtures/edge.log"]);
    let drop = [&PLACE[..], &TIMES[..]].concat();
    assert_eq!(
        support::semantic(&bm, &drop),
        support::semantic(&log, &drop)
    );
    let counts = input(&bm);
    assert_eq!(
        (counts["frames"].as_u64(), counts["malformed"].as_u64()),
        (Some(20), Some(1))
    );
}

#[test]
fn forced_busmaster_reports_bad_lines_and_counts_add_up() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "--input-format", "busmaster"])
        .arg("fixtures/edge.busmaster.log")
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let input: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    let n = |k: &str| input[k].as_u64().unwrap();
    assert_eq!(n("lines"), n("frames") + n("skipped") + n("malformed"));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("fixtures/edge.busmaster.log:86: '123' is not a hex data byte"),
        "{stderr}"
    );
    // Another format's trace forced as BUSMASTER: every frame line malformed.
    let out = emcy_decode()
        .args(["--format", "ndjson", "--input-format", "busmaster"])
        .arg("fixtures/s300.log")
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let input: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(input["frames"], 0);
    assert_eq!(input["malformed"], input["lines"]);
}

/// A BUSMASTER log of `sessions` appended sessions cycling through every
/// header variant (HEX/DEC/none, system/absolute/relative, dates a day
/// apart), each with `frames` frames, some EMCYs.
fn many_sessions(sessions: usize, frames: usize) -> String {
    let mut out = String::new();
    let mut seed = 7u64;
    for s in 0..sessions {
        let base = ["***HEX***", "***DEC***", ""][s % 3];
        let mode = [
            "***SYSTEM MODE***",
            "***ABSOLUTE MODE***",
            "***RELATIVE MODE***",
            "",
        ][s % 4];
        let _ = write!(
            out,
            "***BUSMASTER Ver 2.0.0***\n***PROTOCOL CAN***\n***[START LOGGING SESSION]***\n\
             ***START DATE AND TIME {}:11:2023 1:0:0:000***\n",
            1 + s % 28
        );
        for h in [base, mode] {
            if !h.is_empty() {
                out.push_str(h);
                out.push('\n');
            }
        }
        let dec = base == "***DEC***" || base.is_empty();
        for i in 0..frames {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let id = if seed >> 60 < 3 {
                0x81 + (seed >> 40) as u32 % 4
            } else {
                0x181 + (seed >> 50) as u32 % 3
            };
            let data = [
                0x10,
                0x43,
                (seed >> 8) as u8 & 9,
                1,
                0,
                0,
                0,
                (seed >> 16) as u8,
            ];
            let (secs, frac) = (i / 10 % 86_000, i % 10 * 1000);
            let time = format!(
                "{}:{}:{}:{frac:04}",
                1 + secs / 3600,
                secs / 60 % 60,
                secs % 60
            );
            let bytes: String = data
                .iter()
                .map(|b| {
                    if dec {
                        format!(" {b:03}")
                    } else {
                        format!(" {b:02X}")
                    }
                })
                .collect();
            let id_text = if dec {
                format!("{id:04}")
            } else {
                format!("0x{id:03X}")
            };
            let time = if mode == "***RELATIVE MODE***" {
                "00:00:00:1000".to_string()
            } else {
                time
            };
            let _ = writeln!(out, "{time} Rx {} {id_text} s 8{bytes} ", 1 + s % 2);
        }
        out.push_str("***END DATE AND TIME ***\n***[STOP LOGGING SESSION]***\n");
    }
    out
}

#[test]
fn appended_sessions_read_the_same_on_many_threads() {
    // Big enough for the parallel reader (over 16 MiB), with sessions
    // across many blocks: a block read from a fork that missed a session's
    // headers must be read again.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sessions.log");
    std::fs::write(&path, many_sessions(40, 8_000)).unwrap();
    let run = |threads: &str| {
        let out = emcy_decode()
            .args(["--format", "ndjson", "-j", threads])
            .arg(&path)
            .output()
            .unwrap();
        assert!(out.status.success());
        String::from_utf8(out.stdout).unwrap()
    };
    let one = run("1");
    assert!(one.contains("\"format\":\"busmaster\""));
    assert!(
        one.contains("\"malformed\":0"),
        "{}",
        one.lines().last().unwrap()
    );
    assert_eq!(run("2"), one);
    // And through the fuzz target's check: tiny blocks, 2-4 threads, the
    // same ndjson and diagnostics as read in one go.
    emcy_decode::fuzzing::detect(many_sessions(12, 40).as_bytes());
}

/// A frame as a BUSMASTER line, in hex or decimal, and the header before it.
fn render(f: &TestFrame, dec: bool, prefix: bool) -> (Vec<String>, String) {
    let header = vec![
        "***BUSMASTER Ver 2.0.0***".to_string(),
        "***PROTOCOL CAN***".to_string(),
        format!("***{}***", if dec { "DEC" } else { "HEX" }),
        "***ABSOLUTE MODE***".to_string(),
    ];
    // 4 fraction digits of the frame's time; hours may pass 24 here.
    let tenths = f.frac * 10_000 / 10u64.pow(u32::from(f.digits));
    let time = format!(
        "{}:{}:{}:{tenths:04}",
        f.secs / 3600,
        f.secs / 60 % 60,
        f.secs % 60
    );
    let id = match (dec, f.extended, prefix) {
        (true, true, _) => format!("{:010}", f.id),
        (true, false, _) => format!("{:04}", f.id),
        (false, true, true) => format!("0x{:08X}", f.id),
        (false, true, false) => format!("{:08X}", f.id),
        (false, false, true) => format!("0x{:03X}", f.id),
        (false, false, false) => format!("{:03X}", f.id),
    };
    let bytes: String = f
        .data
        .iter()
        .map(|b| {
            if dec {
                format!("{b:03} ")
            } else {
                format!("{b:02X} ")
            }
        })
        .collect();
    let x = if f.extended { "x" } else { "s" };
    let line = match f.kind {
        FrameKind::Error => format!("{time} Rx 1 0 ERR Bus Off"),
        FrameKind::Remote => format!("{time} Tx 1 {id} {x}r 8 "),
        FrameKind::Fd => {
            let mut data = f.data.clone();
            data.resize(FD_LENS[fd_dlc(data.len())], 0);
            let bytes: String = data
                .iter()
                .map(|b| {
                    if dec {
                        format!("{b:03} ")
                    } else {
                        format!("{b:02X} ")
                    }
                })
                .collect();
            format!("{time} Rx 1 {id} {x}-fd {} {bytes}", data.len())
        }
        FrameKind::Data => format!("{time} Rx 1 {id} {x} {} {bytes}", f.data.len()),
    };
    (header, line)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Random frames as BUSMASTER lines, read through format detection,
    /// come back as the same frames (error lines carry no id).
    #[test]
    fn random_frames_round_trip(f in frame(), dec in any::<bool>(), prefix in any::<bool>()) {
        let (mut lines, line) = render(&f, dec, prefix);
        lines.push(line.clone());
        let (got, format) = read_last(&lines)?;
        prop_assert_eq!(format, Some(Format::Busmaster));
        prop_assert_eq!(got.kind, f.kind, "{}", line);
        prop_assert_eq!(got.channel.as_str(), "1");
        let time = got.time.expect("a time");
        let tenths = f.frac * 10_000 / 10u64.pow(u32::from(f.digits));
        prop_assert_eq!(time.to_string(), format!("{}.{tenths:04}", f.secs), "{}", line);
        if f.kind == FrameKind::Error {
            return Ok(());
        }
        prop_assert_eq!((got.id, got.extended), (f.id, f.extended), "{}", line);
        if f.kind != FrameKind::Remote {
            prop_assert_eq!(&got.data[..f.data.len()], f.data.as_slice(), "{}", line);
        }
    }
}

/// A start date that is no date (30 February): before, dropped in silence
/// and every system time read as seconds since midnight. Now the header
/// line is malformed, with its line number, and `--strict` fails.
#[test]
fn a_start_date_that_is_no_date_is_a_malformed_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("feb30.busmaster.log");
    let text = std::fs::read_to_string("fixtures/s300.busmaster.log").expect("fixture");
    let line = text
        .lines()
        .position(|l| l.starts_with("***START DATE AND TIME"))
        .expect("a start date")
        + 1;
    let text = text.replace(
        "***START DATE AND TIME 14:11:2023 22:13:19:500***",
        "***START DATE AND TIME 30:02:2023 22:13:19:500***",
    );
    std::fs::write(&path, text).expect("write");
    let out = crate::support::emcy_decode()
        .arg("--strict")
        .arg(&path)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    assert!(
        stderr.contains(&format!(
            "feb30.busmaster.log:{line}: '30:02:2023 22:13:19:500' is not a start date and time \
             (d:m:yyyy h:m:s:ms, from 1970 to 9999): the session's system times are seconds \
             since midnight"
        )),
        "{stderr}"
    );
}
