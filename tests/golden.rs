//! Golden outputs: every fixture in every output format, byte for byte.
//! Refresh after an intended change with `UPDATE_GOLDEN=1 cargo test --test golden`
//! and review the diff like code.

mod common;

use std::fs;
use std::path::{Path, PathBuf};

use common::emcy_decode;
use serde_json::Value;

/// Golden file suffix and the flags that produce it.
const OUTPUTS: [(&str, &[&str]); 4] = [
    ("table", &["--format", "table"]),
    ("ndjson", &["--format", "ndjson"]),
    ("json", &["--format", "json"]),
    ("summary", &["--view", "summary"]),
];

fn fixtures() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = fs::read_dir("fixtures")
        .expect("fixtures/ exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            !name.ends_with(".py")
                && !name.ends_with(".md")
                && !name.ends_with(".toml")
                && p.is_file()
        })
        .collect();
    files.sort();
    assert!(
        files.len() >= 15,
        "expected the fixture set, found {files:?}"
    );
    files
}

/// Flags a scenario needs: the profile its trace cannot choose itself
/// (CANopenNode devices have no vendor id of their own; an AX2000 reports
/// Kollmorgen's).
fn scenario_flags(fixture: &Path) -> &'static [&'static str] {
    let name = fixture
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    match name.split('.').next().unwrap_or_default() {
        "canopennode" => &["--profile", "20=canopennode"],
        "ax2000" => &["--profile", "beckhoff-ax2000"],
        "acme-servo" => &["--profile-file", "fixtures/profiles/acme-servo.toml"],
        _ => &[],
    }
}

fn golden_path(fixture: &Path, suffix: &str) -> PathBuf {
    let name = fixture
        .file_name()
        .and_then(|n| n.to_str())
        .expect("utf-8 name");
    Path::new("tests/golden").join(format!("{name}.{suffix}"))
}

/// Compares `actual` with the golden file, or rewrites it under UPDATE_GOLDEN.
fn check(path: &Path, actual: &str, failures: &mut Vec<String>) {
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        fs::create_dir_all(path.parent().expect("has parent")).expect("mkdir");
        fs::write(path, actual).expect("write golden");
        return;
    }
    match fs::read_to_string(path) {
        Ok(expected) if expected == actual => {}
        Ok(expected) => failures.push(format!(
            "{} differs:\n{}",
            path.display(),
            common::first_difference(&expected, actual)
        )),
        Err(_) => failures.push(format!(
            "{} is missing (run UPDATE_GOLDEN=1 cargo test --test golden)",
            path.display()
        )),
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
            check(&golden_path(&fixture, format), &stdout, &mut failures);
            if format == "table" {
                let stderr = String::from_utf8(out.stderr).expect("utf-8 stderr");
                let status = format!("exit {}\n{stderr}", out.status.code().unwrap_or(-1));
                check(&golden_path(&fixture, "stderr"), &status, &mut failures);
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// The fields of an event that must not depend on the trace format.
fn semantic(v: &Value) -> Value {
    let mut v = v.clone();
    if let Some(o) = v.as_object_mut() {
        for key in [
            "file",
            "line",
            "time",
            "channel",
            "start",
            "end",
            "duration",
            "start_line",
            "end_line",
            "time_in_error",
            "longest_error",
            "first_emcy",
            "last_emcy",
        ] {
            o.remove(key);
        }
        if let Some(Value::Array(errors)) = o.get_mut("errors") {
            for e in errors.iter_mut() {
                *e = semantic(e);
            }
        }
    }
    v
}

fn ndjson(path: &Path) -> Vec<Value> {
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .args(scenario_flags(path))
        .arg(path)
        .output()
        .expect("runs");
    String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("valid JSON line"))
        .collect()
}

#[test]
fn every_scenario_decodes_the_same_in_every_trace_format() {
    for scenario in ["s300", "stoeber", "festo", "canopennode", "edge", "ax2000"] {
        let per_format: Vec<(String, Vec<Value>)> = ["log", "txt", "asc"]
            .iter()
            .map(|ext| {
                let path = PathBuf::from(format!("fixtures/{scenario}.{ext}"));
                let objects: Vec<Value> = ndjson(&path)
                    .iter()
                    .filter(|o| o["type"] != "input")
                    .map(semantic)
                    .collect();
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
