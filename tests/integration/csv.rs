//! `--format csv` through the binary: every fixture's rows say what its
//! NDJSON says, column by column, with the header the README documents;
//! `--view summary` gives one row per node.

use serde_json::Value;

use crate::support::golden::fixtures;
use crate::support::{self, emcy_decode};

const EVENT_HEADER: &str = "type,file,line,time,time_text,channel,node,cob_id,code,class,\
description,register,register_bits,data,manufacturer,profile,profile_fields,transition,state,\
cleared,warnings,details";
const NODE_HEADER: &str = "file,channel,node,state,active,emcy_count,errors_seen,time_in_error,\
longest_error_code,longest_error_duration,first_emcy,first_emcy_text,last_emcy,last_emcy_text,\
profile,profile_source,device_type,device_profile";

/// The rows of a CSV run (header first), parsed by the csv crate.
fn rows(args: &[&std::ffi::OsStr]) -> Vec<csv::StringRecord> {
    let out = emcy_decode()
        .args(["--format", "csv"])
        .args(args)
        .output()
        .unwrap();
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(out.stdout.as_slice());
    reader.records().map(|r| r.expect("valid CSV")).collect()
}

fn codes(v: &Value) -> String {
    v.as_array()
        .unwrap()
        .iter()
        .map(|c| cia(c.as_str().unwrap()))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The JSON's `0x4310` as the CSV writes it, `4310h`.
fn cia(hex: &str) -> String {
    format!("{}h", hex.strip_prefix("0x").expect("0x hex"))
}

/// The JSON's `10430801` as the CSV writes it, `10 43 08 01`.
fn spaced(hex: &str) -> String {
    let pairs: Vec<&str> = (0..hex.len()).step_by(2).map(|i| &hex[i..i + 2]).collect();
    pairs.join(" ")
}

/// A JSON number's text as the binary wrote it (`serde_json` keeps it with
/// `arbitrary_precision` off only as f64: compare the raw line instead).
fn raw_time(line: &str) -> String {
    let at = line.find("\"time\":").unwrap() + 7;
    line[at..].split(',').next().unwrap().to_string()
}

#[test]
fn every_fixtures_event_rows_say_what_its_ndjson_says() {
    for fixture in fixtures() {
        let f = fixture.as_os_str();
        let rows = rows(&[f]);
        assert_eq!(rows[0].iter().collect::<Vec<_>>().join(","), EVENT_HEADER);
        let out = emcy_decode()
            .args(["--format", "ndjson"])
            .arg(f)
            .output()
            .unwrap();
        let text = String::from_utf8(out.stdout).unwrap();
        let events: Vec<(&str, Value)> = text
            .lines()
            .map(|l| (l, serde_json::from_str::<Value>(l).unwrap()))
            .filter(|(_, v)| !matches!(v["type"].as_str(), Some("node" | "input" | "channel")))
            .collect();
        assert_eq!(rows.len() - 1, events.len(), "{fixture:?}");
        for (row, (line, ev)) in rows[1..].iter().zip(&events) {
            assert_eq!(row.len(), 22, "{fixture:?}: {row:?}");
            let cell = |name: &str| {
                let i = EVENT_HEADER.split(',').position(|c| c == name).unwrap();
                row.get(i).unwrap().to_string()
            };
            assert_eq!(cell("type"), ev["type"].as_str().unwrap());
            assert_eq!(cell("line"), ev["line"].to_string());
            let time = raw_time(line);
            assert_eq!(cell("time"), if time == "null" { "" } else { &time });
            // An event of no node (a burst of error frames) has an empty cell.
            let node = match &ev["node"] {
                Value::Null => String::new(),
                n => n.to_string(),
            };
            assert_eq!(cell("node"), node);
            if ev["type"] != "emcy" && ev["type"] != "boot" {
                // Health events: their JSON object in `details`.
                let details: Value = serde_json::from_str(&cell("details")).unwrap();
                assert_eq!(&details, ev);
                assert!(!cell("description").is_empty());
                continue;
            }
            assert_eq!(cell("cleared"), codes(&ev["cleared"]));
            if ev["type"] == "emcy" {
                assert_eq!(cell("code"), cia(ev["code"].as_str().unwrap()));
                assert_eq!(cell("data"), spaced(ev["data"].as_str().unwrap()));
                assert_eq!(
                    cell("manufacturer"),
                    spaced(ev["manufacturer"].as_str().unwrap())
                );
                assert_eq!(cell("description"), ev["description"].as_str().unwrap());
                assert_eq!(cell("state"), ev["state"].as_str().unwrap());
                let decoded = cell("profile_fields");
                if ev["manufacturer_decoded"].is_null() {
                    assert_eq!(decoded, "");
                } else {
                    let parsed: Value = serde_json::from_str(&decoded).unwrap();
                    assert_eq!(parsed, ev["manufacturer_decoded"]);
                }
                match ev["cob_id"].as_u64() {
                    Some(id) => assert_eq!(cell("cob_id"), id.to_string()),
                    None => assert_eq!(cell("cob_id"), ""),
                }
            }
        }
    }
}

#[test]
fn time_text_is_iso_utc_for_unix_times_and_the_seconds_otherwise() {
    let log = rows(&["fixtures/s300.log".as_ref()]);
    let emcy = log.iter().find(|r| &r[0] == "emcy").unwrap();
    assert_eq!(&emcy[3], "1700000001.250000");
    assert_eq!(&emcy[4], "2023-11-14T22:13:21.250000Z");
    // ASC times are seconds since the measurement started.
    let asc = rows(&["fixtures/festo.asc".as_ref()]);
    assert_eq!(&asc[1][3], "0.000000");
    assert_eq!(&asc[1][3], &asc[1][4]);
}

#[test]
fn summary_is_one_row_per_node_object() {
    let rows = rows(&[
        "--view".as_ref(),
        "summary".as_ref(),
        "fixtures/s300.log".as_ref(),
        "fixtures/stoeber-ecat.pcapng".as_ref(),
        "fixtures/cia402-commissioning.log".as_ref(),
    ]);
    assert_eq!(rows[0].iter().collect::<Vec<_>>().join(","), NODE_HEADER);
    let nodes: Vec<Value> = support::ndjson([
        "fixtures/s300.log",
        "fixtures/stoeber-ecat.pcapng",
        "fixtures/cia402-commissioning.log",
    ])
    .into_iter()
    .filter(|o| o["type"] == "node")
    .collect();
    assert_eq!(rows.len() - 1, nodes.len());
    for (row, n) in rows[1..].iter().zip(&nodes) {
        assert_eq!(row.len(), 18);
        assert_eq!(&row[1], n["channel"].as_str().unwrap());
        assert_eq!(row[2], n["node"].to_string());
        assert_eq!(&row[3], n["state"].as_str().unwrap());
        assert_eq!(row[5], n["emcy_count"].to_string());
        let seen: Vec<String> = n["errors_seen"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(c, k)| format!("{}:{k}", cia(c)))
            .collect();
        assert_eq!(&row[6], seen.join(" "));
        assert_eq!(&row[14], n["profile"].as_str().unwrap());
        assert_eq!(
            row[16],
            n["device_type"].as_str().map(cia).unwrap_or_default()
        );
        assert_eq!(&row[17], n["device_profile"].as_str().unwrap_or_default());
    }
    assert!(
        rows.iter()
            .any(|r| &r[16] == "00020192h" && &r[17] == "CiA 402 drive")
    );
}

#[test]
fn a_trace_without_events_still_has_the_header() {
    let rows = rows(&["fixtures/no-frame.asc".as_ref()]);
    assert_eq!(rows.len(), 1);
}

/// Names from a trace or the file system cannot attack whoever opens the
/// CSV: control characters are escaped as in every other output (no
/// terminal sequence reaches `cat events.csv`), and a cell a spreadsheet
/// would run as a formula (`=`, `@`, `+`, `-` first) starts with `'` and
/// is quoted, as OWASP recommends; numbers, negative ones included, stay
/// numbers.
#[test]
fn names_can_neither_run_formulas_nor_reach_the_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let channels = [
        "=cmd|'/Ccalc'!A0",
        "@SUM(1+1)",
        "+1+1",
        "-2+3",
        "\u{1b}]2;owned\u{7}",
        "\u{1b}[2J",
        "can0",
    ];
    let mut trace = String::new();
    for (i, channel) in channels.iter().enumerate() {
        trace.push_str(&format!(
            "(1700000010.{i}00000) {channel} 085#1043090000000000\n"
        ));
    }
    // A clock going backwards: the can0 node's durations are negative.
    trace.push_str("(1700000009.000000) can0 085#0000000000000000\n");
    // A boot-up: an NMT event, whose details cell is JSON with the
    // channel (DEL and a C1 CSI in it).
    trace.push_str("(1700000009.500000) can\u{7f}\u{9b}1 705#00\n");
    std::fs::write(dir.path().join("=1+1.log"), trace).unwrap();
    for summary in [false, true] {
        let mut args = vec!["--format", "csv", "=1+1.log"];
        if summary {
            args.extend(["--view", "summary"]);
        }
        let out = emcy_decode()
            .current_dir(dir.path())
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(
            !text.chars().any(|c| c.is_control() && c != '\n'),
            "a control character in {text}"
        );
        assert!(text.contains(r#""'=cmd|'/Ccalc'!A0""#), "{text}");
        assert!(text.contains(r#""'@SUM(1+1)""#), "{text}");
        let mut reader = csv::ReaderBuilder::new().from_reader(text.as_bytes());
        let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.unwrap()).collect();
        let (file, channel) = (1 - usize::from(summary), 5 - 4 * usize::from(summary));
        let mut shown: Vec<&str> = rows.iter().map(|r| &r[channel]).collect();
        shown.sort_unstable();
        shown.dedup();
        assert_eq!(
            shown,
            [
                "'+1+1",
                "'-2+3",
                "'=cmd|'/Ccalc'!A0",
                "'@SUM(1+1)",
                r"\u{1b}[2J",
                r"\u{1b}]2;owned\u{7}",
                "can0",
                r"can\u{7f}\u{9b}1",
            ]
        );
        assert!(rows.iter().all(|r| &r[file] == "'=1+1.log"));
        if summary {
            let can0 = rows.iter().find(|r| &r[1] == "can0").unwrap();
            assert_eq!(&can0[7], "-1.600000", "time_in_error, a number");
            assert_eq!(&can0[9], "-1.600000", "longest_error_duration");
        }
    }
}

/// Reads the CSV files given with DuckDB and pandas, no options, and prints
/// each code, id and byte column that either guessed as anything but text.
const GUESS_TYPES: &str = r#"
import sys
import duckdb
import pandas as pd

TEXT = ["code", "data", "manufacturer", "cleared", "active", "errors_seen",
        "longest_error_code", "device_type"]
for path in sys.argv[1:]:
    duck = {r[0]: r[1] for r in duckdb.sql(f"DESCRIBE SELECT * FROM read_csv('{path}')").fetchall()}
    frame = pd.read_csv(path)
    for col in TEXT:
        if col not in duck:
            continue
        values = frame[col].dropna()
        if duck[col] != "VARCHAR" and not (duck[col] == "NULL" or values.empty):
            print(f"duckdb {path} {col} {duck[col]}")
        if not values.empty and not all(isinstance(v, str) for v in values):
            print(f"pandas {path} {col} {frame[col].dtype}")
"#;

#[test]
fn duckdb_and_pandas_read_codes_ids_and_bytes_as_text_without_options() {
    let ready = std::process::Command::new("python3")
        .args(["-c", "import duckdb, pandas"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ready {
        eprintln!("skipped: python3 with duckdb and pandas not found (.ci/run installs them)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for (name, view) in [("events.csv", "full"), ("nodes.csv", "summary")] {
        let out = emcy_decode()
            .args(["--format", "csv", "--view", view])
            .args([
                "fixtures/edge.log",
                "fixtures/s300.log",
                "fixtures/cia402-commissioning.log",
                "fixtures/stoeber-ecat.pcapng",
            ])
            .output()
            .unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, out.stdout).unwrap();
        files.push(path);
    }
    let out = std::process::Command::new("python3")
        .args(["-c", GUESS_TYPES])
        .args(&files)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(String::from_utf8_lossy(&out.stdout), "");
}
