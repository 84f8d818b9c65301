//! Golden outputs: every fixture in every output format, byte for byte.
//! Refresh after an intended change with
//! `UPDATE_GOLDEN=1 cargo test --test integration -- golden::` and review
//! the diff like code.

use std::path::{Path, PathBuf};

use crate::support::golden::{self, check, fixtures};
use crate::support::{self, PLACE, TIMES, emcy_decode, semantic};
use serde_json::Value;

/// Golden file suffix and the flags that produce it.
const OUTPUTS: [(&str, &[&str]); 5] = [
    ("table", &["--format", "table"]),
    ("ndjson", &["--format", "ndjson"]),
    ("json", &["--format", "json"]),
    ("summary", &["--view", "summary"]),
    ("csv", &["--format", "csv"]),
];

/// Flags a scenario needs: the profile its trace cannot choose itself
/// (CANopenNode devices have no vendor id of their own; an AX2000 reports
/// Kollmorgen's).
pub(crate) fn scenario_flags(fixture: &Path) -> &'static [&'static str] {
    let name = fixture
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    match name.split('.').next().unwrap_or_default() {
        "canopennode" => &["--profile", "20=canopennode"],
        "ax2000" => &["--profile", "beckhoff-ax2000"],
        "acme-servo" => &["--profile-file", "fixtures/profiles/acme-servo.toml"],
        // 1001 reads its vendor id over CoE; 1002 is named by station address.
        "stoeber-ecat" => &["--profile", "1002=stoeber"],
        // Only the DCF gives this drive's PDO mapping.
        "cia402-dcf" => &["--dcf", "5=fixtures/cia402-drive.dcf"],
        // Nodes 3 and 7 are no drives by their device type.
        "cia402-not-drive" => &["--assume-cia402-pdo"],
        // SYNC's gaps, every id's timing and the load need --timing.
        "sync-gaps" => &["--bitrate", "500k"],
        // Every SDO transfer in the table too.
        "sdo-startup" => &["--show", "sdo"],
        _ => &[],
    }
}

#[test]
fn every_fixture_in_every_output_format_matches_its_golden_file() {
    let mut failures = Vec::new();
    for fixture in fixtures() {
        for (format, flags) in OUTPUTS {
            let out = emcy_decode()
                .args(flags)
                .args(scenario_flags(&fixture))
                .arg(&fixture)
                .output()
                .expect("runs");
            let stdout = String::from_utf8(out.stdout).expect("utf-8 output");
            check(&golden::path(&fixture, format), &stdout, &mut failures);
            if format == "table" {
                let stderr = String::from_utf8(out.stderr).expect("utf-8 stderr");
                let status = format!("exit {}\n{stderr}", out.status.code().unwrap_or(-1));
                check(&golden::path(&fixture, "stderr"), &status, &mut failures);
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// The objects of a fixture's ndjson run, with the flags it needs.
fn ndjson(path: &Path) -> Vec<Value> {
    let flags = scenario_flags(path).iter().map(Path::new);
    support::ndjson(flags.chain([path]))
}

#[test]
fn every_scenario_decodes_the_same_in_every_trace_format() {
    for scenario in ["s300", "stoeber", "festo", "canopennode", "edge", "ax2000"] {
        let per_format: Vec<(String, Vec<Value>)> = ["log", "txt", "asc"]
            .iter()
            .map(|ext| {
                let path = PathBuf::from(format!("fixtures/{scenario}.{ext}"));
                // What must not depend on the trace format: where and when
                // (and what an error frame says beyond being one: `semantic`
                // leaves that out).
                let objects = semantic(&ndjson(&path), &[&PLACE[..], &TIMES[..]].concat());
                (path.display().to_string(), objects)
            })
            .collect();
        let (first_name, first) = &per_format[0];
        assert!(
            first.iter().any(|o| o["type"] == "emcy"),
            "{first_name} has no EMCY events"
        );
        for (name, objects) in &per_format[1..] {
            assert_eq!(
                objects, first,
                "{name} decodes differently from {first_name}"
            );
        }
    }
}

#[test]
fn gzip_copy_decodes_like_the_original() {
    let plain = ndjson(Path::new("fixtures/s300.log"));
    let gz = ndjson(Path::new("fixtures/s300.log.gz"));
    let strip = |v: &[Value]| -> Vec<Value> {
        v.iter()
            .map(|o| {
                let mut o = o.clone();
                if let Some(m) = o.as_object_mut() {
                    m.remove("file");
                    m.remove("gzip");
                }
                o
            })
            .collect()
    };
    assert_eq!(strip(&plain), strip(&gz));
    assert!(gz.iter().any(|o| o["type"] == "input" && o["gzip"] == true));
}
