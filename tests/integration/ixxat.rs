//! IXXAT MiniMon V3 ASCII traces: the S300 fixture decodes to the same
//! events as the candump log of its scenario, at the same times since the
//! start; the guarding fixture's remote requests, extended frames and empty
//! SYNC are frames, none of them an EMCY; header lines are skipped lines;
//! a damaged row is reported with its file and line.

use std::path::Path;

use serde_json::Value;

use crate::support::{self, PLACE, TIMES, emcy_decode};

fn ndjson(path: &str) -> Vec<Value> {
    support::ndjson([Path::new(path)])
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
fn the_s300_trace_decodes_like_the_candump_log() {
    let ixxat = ndjson("fixtures/s300.ixxat.trc");
    let log = ndjson("fixtures/s300.log");
    let i = input(&ixxat);
    assert_eq!(i["format"], "ixxat");
    assert_eq!(i["malformed"], 0);
    // The title, five header lines and the column header row.
    assert_eq!(i["skipped"], 7);
    assert_eq!(i["frames"], input(&log)["frames"]);
    let drop = [&PLACE[..], &TIMES[..]].concat();
    assert_eq!(
        support::semantic(&ixxat, &drop),
        support::semantic(&log, &drop)
    );
    // Seconds since the start of the measurement, never a date.
    assert_eq!(
        emcy_times(&ixxat),
        ["1.25", "2.0", "2.5", "3.0", "4.0", "5.0", "7.0"]
    );
}

#[test]
fn remote_requests_extended_frames_and_empty_frames_are_no_emcy() {
    let objects = ndjson("fixtures/guarding.ixxat.trc");
    let i = input(&objects);
    assert_eq!(
        (i["frames"].as_u64(), i["malformed"].as_u64()),
        (Some(13), Some(0))
    );
    // 0x84 as an extended id carries an EMCY's bytes but is not one.
    assert_eq!(i["emcy"], 3);
    let codes: Vec<&str> = objects
        .iter()
        .filter(|o| o["type"] == "emcy")
        .filter_map(|o| o["code"].as_str())
        .collect();
    assert_eq!(codes, ["0x4210", "0x0000", "0x8130"]);
}

#[test]
fn detected_from_its_rows_without_the_header_and_damaged_rows_say_where() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rows.txt");
    std::fs::write(
        &path,
        "\"00:00:01.00\";\"83\";\"Std\";\"\";\"10 43 09 00 00 00 00 00 \"\r\n\
         \"00:00:02.00\";\"83\";\"Std\";\"Err\";\"00 \"\r\n",
    )
    .unwrap();
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .arg(&path)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let input: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(input["format"], "ixxat");
    assert_eq!(
        (input["emcy"].as_u64(), input["malformed"].as_u64()),
        (Some(1), Some(1))
    );
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("rows.txt:2: unknown flag 'Err' (Rtr is read)"),
        "{stderr}"
    );
}

#[test]
fn the_header_bit_rate_is_read() {
    let file = std::fs::File::open("fixtures/s300.ixxat.trc").expect("fixture");
    let mut reader = emcy_decode::TraceReader::new(std::io::BufReader::new(file));
    assert_eq!(reader.bit_rate(), None);
    let first_frame = reader
        .by_ref()
        .find(|r| matches!(r, Ok(emcy_decode::Record::Frame(_))));
    assert!(first_frame.is_some());
    assert_eq!(reader.bit_rate(), Some(250_000));
}
