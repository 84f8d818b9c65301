//! `emcy-decode diff GOOD BAD`: two traces compared by CANopen meaning,
//! with diff(1)'s exit codes.

use std::path::Path;

use serde_json::Value;

use crate::support::golden::{check, fixtures};
use crate::support::run;

const GOOD: &str = "fixtures/diff-good.log";
const ABORTED: &str = "fixtures/diff-aborted.log";
const RETIMED: &str = "fixtures/diff-retimed.log";

fn json(good: &str, bad: &str) -> (Value, i32) {
    let (out, err, code) = run(&["diff", "-f", "json", good, bad], b"");
    let v: Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}{err}"));
    (v, code)
}

#[test]
fn an_aborted_write_is_the_one_difference_and_exit_1() {
    let (v, code) = json(GOOD, ABORTED);
    assert_eq!(code, 1);
    assert_eq!(v["same"], false);
    assert_eq!(v["differences"], 1, "{v:#}");
    // The write went through in one and was aborted in the other.
    let first = &v["first"];
    assert_eq!(first["node"], 2);
    assert_eq!(first["kind"], "changed");
    assert_eq!(first["good"]["kind"], "sdo");
    assert_eq!(first["good"]["line"], 10);
    assert_eq!(first["bad"]["kind"], "sdo_abort");
    assert_eq!(first["bad"]["index"], "0x1017");
    assert_eq!(first["bad"]["subindex"], 0);
    assert_eq!(first["bad"]["abort_code"], "0x06090030");
    assert_eq!(first["bad"]["line"], 10);
    let nodes = v["nodes"].as_array().unwrap();
    assert_eq!(nodes.len(), 1, "only node 2 differs");
    assert_eq!(
        nodes[0]["equal_before"], 2,
        "its boot-up and the read of its device type are told alike"
    );
}

#[test]
fn the_other_way_round_the_abort_is_removed() {
    let (v, code) = json(ABORTED, GOOD);
    assert_eq!(code, 1);
    assert_eq!(v["first"]["kind"], "changed");
    assert_eq!(v["first"]["good"]["abort_code"], "0x06090030");
    assert_eq!(v["first"]["bad"]["kind"], "sdo");
}

#[test]
fn timing_and_process_data_are_no_difference() {
    let (out, err, code) = run(&["diff", GOOD, RETIMED], b"");
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(
        out,
        "fixtures/diff-good.log and fixtures/diff-retimed.log tell the same CANopen story\n"
    );
    let (v, _) = json(GOOD, RETIMED);
    assert_eq!(v["same"], true);
    assert_eq!(v["first"], Value::Null);
    assert_eq!(v["nodes"], Value::Array(Vec::new()));
}

#[test]
fn one_scenario_in_two_formats_is_the_same_story() {
    for other in [
        "fixtures/s300.asc",
        "fixtures/s300.trc",
        "fixtures/s300.blf",
    ] {
        if !Path::new(other).exists() {
            continue;
        }
        let (out, err, code) = run(&["diff", "fixtures/s300.log", other], b"");
        assert_eq!(code, 0, "{other}: {out}{err}");
    }
}

#[test]
fn every_fixture_is_the_same_as_itself() {
    for f in fixtures() {
        let f = f.to_str().unwrap();
        let (out, err, code) = run(&["diff", f, f], b"");
        // A fixture that cannot be read whole (a damaged file) is trouble,
        // never a difference.
        assert!(code == 0 || code == 2, "{f}: {code} {out}{err}");
        if code == 0 {
            assert!(out.ends_with("tell the same CANopen story\n"), "{f}: {out}");
        }
    }
}

#[test]
fn nodes_of_one_trace_only_say_which_trace() {
    let (v, code) = json(
        "fixtures/commissioning.log",
        "fixtures/cia402-commissioning.log",
    );
    assert_eq!(code, 1);
    let only: Vec<(u64, &str)> = v["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| Some((n["node"].as_u64()?, n["only_in"].as_str()?)))
        .collect();
    assert!(only.contains(&(1, "good")), "{only:?}");
    assert!(only.contains(&(5, "bad")), "{only:?}");
}

#[test]
fn an_unreadable_input_is_exit_2_and_both_are_named() {
    let (out, err, code) = run(&["diff", "no-such-good.log", "no-such-bad.log"], b"");
    assert_eq!(code, 2);
    assert_eq!(out, "");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 2, "{err}");
    assert!(lines[0].starts_with("error: no-such-good.log"), "{err}");
    assert!(lines[1].starts_with("error: no-such-bad.log"), "{err}");
    let (_, err, code) = run(&["diff", GOOD, "no-such-bad.log"], b"");
    assert_eq!(code, 2, "{err}");
}

#[test]
fn both_from_stdin_is_a_usage_error() {
    let (out, err, code) = run(&["diff", "-", "-"], b"");
    assert_eq!(code, 2);
    assert_eq!(out, "");
    assert_eq!(err, "error: GOOD and BAD cannot both be stdin (`-`)\n");
}

#[test]
fn one_side_from_stdin_reads_it() {
    let text = std::fs::read(ABORTED).unwrap();
    let (_, err, code) = run(&["diff", GOOD, "-"], &text);
    assert_eq!(code, 1, "{err}");
}

/// The text and JSON of the fixture pairs, byte for byte.
#[test]
fn diff_outputs_match_their_golden_files() {
    let pairs = [
        ("aborted", GOOD, ABORTED),
        ("retimed", GOOD, RETIMED),
        (
            "commissioning",
            "fixtures/commissioning.log",
            "fixtures/cia402-commissioning.log",
        ),
    ];
    let mut failures = Vec::new();
    for (name, good, bad) in pairs {
        for (format, suffix) in [("text", "txt"), ("json", "json")] {
            let (out, _, _) = run(&["diff", "-f", format, good, bad], b"");
            let path = Path::new("tests/golden/diff").join(format!("{name}.{suffix}"));
            check(&path, &out, &mut failures);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn new_firmware_on_a_node_is_the_difference() {
    // The same start-up, but node 2 answers its software version "1.03".
    let dir = tempfile::tempdir().unwrap();
    let updated = dir.path().join("updated.log");
    let text = std::fs::read_to_string("fixtures/identity.log").unwrap();
    assert!(text.contains("582#430A1000312E3032"));
    std::fs::write(
        &updated,
        text.replace("582#430A1000312E3032", "582#430A1000312E3033"),
    )
    .unwrap();
    let (out, err, code) = run(
        &["diff", "fixtures/identity.log", updated.to_str().unwrap()],
        b"",
    );
    assert_eq!(code, 1, "{out}{err}");
    assert!(out.contains("software_version"), "{out}");
    assert!(out.contains("1.02") && out.contains("1.03"), "{out}");
    let (v, _) = json("fixtures/identity.log", updated.to_str().unwrap());
    let nodes = v["nodes"].as_array().unwrap();
    assert_eq!(nodes.len(), 1, "only node 2 differs: {v:#}");
    assert_eq!(nodes[0]["node"], 2);
}

/// The SDO start-up (scripts/make_sdo_fixtures.py) with one write aborted
/// is that one difference; retimed (an hour later, every gap a quarter
/// longer), none.
#[test]
fn an_sdo_start_up_differs_by_its_aborted_write_only() {
    const STARTUP: &str = "fixtures/sdo-startup.log";
    let (v, code) = json(STARTUP, "fixtures/sdo-startup-aborted.log");
    assert_eq!(code, 1);
    assert_eq!(v["differences"], 1, "{v:#}");
    let first = &v["first"];
    assert_eq!(
        (&first["node"], &first["kind"]),
        (&3.into(), &"changed".into())
    );
    assert_eq!(first["good"]["kind"], "sdo");
    assert!(
        first["good"]["text"]
            .as_str()
            .is_some_and(|t| t.starts_with("SDO download 0x2000.00 = 000102")),
        "{first}"
    );
    assert_eq!(first["bad"]["kind"], "sdo_abort");
    assert_eq!(first["bad"]["abort_code"], "0x08000020");
    let (out, err, code) = run(&["diff", STARTUP, "fixtures/sdo-startup-retimed.log"], b"");
    assert_eq!(code, 0, "{out}{err}");
}
