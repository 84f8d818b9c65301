//! A CiA 402 drive's own state, through the command line, on the
//! fixtures of scripts/make_cia402_fixtures.py: states and faults from
//! PDOs, where each mapping came from (sdo, dcf, option, assumed), the
//! fault's EMCY and reset, `--fail-on fault`, `check`'s `drive_fault_new`,
//! and the note for a drive whose mapping is unknown.

use std::fs;

use serde_json::Value;

use crate::support::{Rig, emcy_decode, ndjson};

const COMMISSIONING: &str = "fixtures/cia402-commissioning.log";
const DCF_TRACE: &str = "fixtures/cia402-dcf.log";
const DCF: &str = "5=fixtures/cia402-drive.dcf";
const UNKNOWN: &str = "fixtures/cia402-unknown.log";

fn of_type<'a>(objects: &'a [Value], t: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == t).collect()
}

fn drive(objects: &[Value], n: u64) -> Value {
    objects
        .iter()
        .find(|o| o["type"] == "node" && o["node"] == n)
        .map(|o| o["axis"].clone())
        .unwrap_or(Value::Null)
}

fn states(objects: &[Value]) -> Vec<String> {
    of_type(objects, "axis_state")
        .iter()
        .map(|e| e["state"].as_str().unwrap_or_default().to_string())
        .collect()
}

/// The drive's life as the fixture writes it: enable, fault, reset,
/// enable again.
const LIFE: [&str; 10] = [
    "switch_on_disabled",
    "ready_to_switch_on",
    "switched_on",
    "operation_enabled",
    "fault_reaction_active",
    "fault",
    "switch_on_disabled",
    "ready_to_switch_on",
    "switched_on",
    "operation_enabled",
];

#[test]
fn the_commissioning_trace_gives_the_drive_states_from_its_learnt_tpdo() {
    let objects = ndjson([COMMISSIONING]);
    assert_eq!(states(&objects), LIFE);
    let events = of_type(&objects, "axis_state");
    let first = events[0];
    assert_eq!(first["statusword"], "0x0250");
    assert_eq!(first["via"], "pdo");
    assert_eq!(first["cob_id"], 0x185);
    assert_eq!(first["from"], Value::Null);
    assert_eq!(events[3]["statusword"], "0x0237");
    assert_eq!(events[4]["from"], "operation_enabled");
    // A state change only: 150 TPDOs, 10 changes.
    let resets = of_type(&objects, "fault_reset");
    assert_eq!(resets.len(), 1);
    assert_eq!(resets[0]["controlword"], "0x0080");
    assert_eq!(resets[0]["time_text"], "2023-11-14T22:13:20.887000Z");
}

#[test]
fn the_fault_interval_has_its_emcy_its_reset_and_its_duration() {
    let objects = ndjson([COMMISSIONING]);
    let a = drive(&objects, 5);
    assert_eq!(a["state"], "operation_enabled");
    assert_eq!(a["fault_count"], 1);
    let faults = a["faults"].as_array().expect("faults");
    assert_eq!(faults.len(), 1);
    let f = &faults[0];
    assert_eq!(f["start_text"], "2023-11-14T22:13:20.677000Z");
    assert_eq!(f["end_text"], "2023-11-14T22:13:20.888000Z");
    assert_eq!(f["duration"].as_f64(), Some(0.211));
    // The EMCY came 1 ms after the statusword entered fault reaction.
    assert_eq!(f["emcy_code"], "0x7305");
    assert_eq!(f["error_code"], "0x7305");
    assert_eq!(f["cleared_by_text"], "2023-11-14T22:13:20.887000Z");
    let t = &a["time_in_state"];
    assert_eq!(t["fault"].as_f64(), Some(0.2));
    assert_eq!(t["fault_reaction_active"].as_f64(), Some(0.011));
    let total: f64 = t
        .as_object()
        .expect("object")
        .values()
        .filter_map(Value::as_f64)
        .sum();
    // From the first statusword (.067) to the last (1.369).
    assert!((total - 1.302).abs() < 1e-9, "{total}");
}

fn tpdo(a: &Value) -> (u64, Vec<String>, String) {
    let m = &a["mapping"]["tpdo"][0];
    (
        m["cob_id"].as_u64().unwrap_or_default(),
        m["objects"]
            .as_array()
            .map(|o| {
                o.iter()
                    .filter_map(|s| s.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default(),
        m["source"].as_str().unwrap_or_default().to_string(),
    )
}

#[test]
fn each_mapping_source_is_recorded_and_the_first_one_wins() {
    let both = || vec!["0x6041:16".to_string(), "0x603F:16".to_string()];
    // The trace's SDO writes (the COB-ID by a segmented download).
    let objects = ndjson([COMMISSIONING]);
    assert_eq!(tpdo(&drive(&objects, 5)), (0x185, both(), "sdo".into()));
    assert_eq!(drive(&objects, 5)["mapping"]["rpdo"][0]["source"], "sdo");
    // The trace's own writes win over a DCF and --pdo.
    let objects = ndjson(["--dcf", DCF, "--pdo", "0x185=0x6041", COMMISSIONING]);
    assert_eq!(tpdo(&drive(&objects, 5)), (0x185, both(), "sdo".into()));
    // Only the DCF.
    let objects = ndjson(["--dcf", DCF, DCF_TRACE]);
    assert_eq!(tpdo(&drive(&objects, 5)), (0x185, both(), "dcf".into()));
    assert_eq!(states(&objects), LIFE);
    // The DCF's vendor id chose the profile, as a 0x1018 upload would.
    let node = objects.iter().find(|o| o["type"] == "node").expect("node");
    assert_eq!(node["profile"], "kollmorgen");
    // --pdo, and the DCF wins over it.
    let objects = ndjson(["--pdo", "0x185=0x6041", DCF_TRACE]);
    assert_eq!(
        tpdo(&drive(&objects, 5)),
        (0x185, vec!["0x6041:16".to_string()], "option".into())
    );
    assert_eq!(states(&objects), LIFE);
    // No controlword mapped: no reset seen, the fault still cleared.
    assert!(of_type(&objects, "fault_reset").is_empty());
    let objects = ndjson(["--pdo", "0x185=0x6041", "--dcf", DCF, DCF_TRACE]);
    assert_eq!(tpdo(&drive(&objects, 5)).2, "dcf");
    // The assumption: the statusword first in TPDO1, as it is here.
    let objects = ndjson(["--assume-cia402-pdo", DCF_TRACE]);
    assert_eq!(
        tpdo(&drive(&objects, 5)),
        (0x185, vec!["0x6041:16".to_string()], "assumed".into())
    );
    assert_eq!(
        drive(&objects, 5)["mapping"]["rpdo"][0]["source"],
        "assumed"
    );
    assert_eq!(states(&objects), LIFE);
    assert_eq!(of_type(&objects, "fault_reset").len(), 1);
}

#[test]
fn without_a_mapping_nothing_is_decoded_and_one_note_says_how_to_give_it() {
    let out = emcy_decode()
        .args(["--format", "ndjson", UNKNOWN])
        .env_remove("NO_COLOR")
        .env_remove("COLUMNS")
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(0));
    let stdout = String::from_utf8(out.stdout).expect("utf-8");
    assert!(!stdout.contains("axis"), "{stdout}");
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    for hint in ["--dcf 3=FILE", "--pdo 0x183=0x6041", "--assume-cia402-pdo"] {
        assert!(stderr.contains(hint), "{hint}: {stderr}");
    }
    // The same trace with the mapping given decodes and says nothing.
    let out = emcy_decode()
        .args(["--format", "ndjson", "--pdo", "0x183=0x6041", UNKNOWN])
        .output()
        .expect("runs");
    assert!(out.stderr.is_empty());
    let objects: Vec<Value> = String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    assert_eq!(states(&objects), LIFE[..4]);
}

#[test]
fn one_thread_and_two_give_the_same_output() {
    // Big enough for blocks on several threads (4 MiB): the trace 400
    // times, each copy 2 s later.
    const COPIES: u64 = 400;
    let dir = tempfile::tempdir().expect("temp dir");
    let text = fs::read_to_string(COMMISSIONING).expect("fixture");
    let mut big = String::new();
    for copy in 0..COPIES {
        for line in text.lines() {
            let (time, rest) = line.split_once(')').expect("candump line");
            let secs: f64 = time.trim_start_matches('(').parse().expect("time");
            big.push_str(&format!("({:.6}){rest}\n", secs + 2.0 * copy as f64));
        }
    }
    let path = dir.path().join("big.log");
    fs::write(&path, big).expect("write");
    let run = |j: &str| {
        emcy_decode()
            .args(["--format", "ndjson", "-j", j])
            .arg(&path)
            .output()
            .expect("runs")
    };
    let one = run("1");
    let two = run("2");
    assert_eq!(one.stdout, two.stdout);
    assert_eq!(one.stderr, two.stderr);
    let text = String::from_utf8(one.stdout).expect("utf-8");
    assert_eq!(
        text.matches("\"type\":\"axis_state\"").count(),
        10 * COPIES as usize
    );
}

#[test]
fn fail_on_fault_exits_1_only_when_a_drive_faulted() {
    let out = emcy_decode()
        .args(["--fail-on", "fault", COMMISSIONING])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    assert!(stderr.contains("fault: 1 drive faulted 1 time"), "{stderr}");
    emcy_decode()
        .args(["--fail-on", "fault", UNKNOWN])
        .assert()
        .code(0);
}

#[test]
fn a_missing_or_bad_dcf_is_one_error_line_and_exit_2() {
    for (spec, says) in [
        ("5=fixtures/no-such.dcf", "no-such.dcf"),
        ("5=fixtures/cia402-commissioning.log", "not a DCF"),
        ("200=fixtures/cia402-drive.dcf", "node id"),
    ] {
        let out = emcy_decode()
            .args(["--dcf", spec, DCF_TRACE])
            .output()
            .expect("runs");
        assert_eq!(out.status.code(), Some(2), "{spec}");
        let stderr = String::from_utf8(out.stderr).expect("utf-8");
        assert!(stderr.starts_with("error:"), "{spec}: {stderr}");
        assert!(stderr.contains(says), "{spec}: {stderr}");
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn check_reports_a_new_drive_fault_as_a_regression() {
    // The baseline: the drive enabled, never faulted (the trace up to the fault).
    let healthy: String = fs::read_to_string(COMMISSIONING)
        .expect("fixture")
        .lines()
        .take_while(|l| !l.contains("185#3F02"))
        .map(|l| format!("{l}\n"))
        .collect();
    let rig = Rig::new(&healthy);
    let text = rig.baseline(&[]);
    assert!(!text.contains("axis_faults"), "{text}");
    rig.trace_from(COMMISSIONING);
    let (code, found) = rig.check("axis_fault_new");
    assert_eq!(code, Some(1));
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0]["node"], 5);
    assert_eq!(found[0]["severity"], "regression");
    // Recorded, then nothing regresses; the options are recorded too.
    let text = rig.baseline(&[]);
    assert!(text.contains("\"axis_faults\": 1"), "{text}");
    assert_eq!(rig.check("axis_fault_new"), (Some(0), vec![]));
    let text = rig.baseline(&["--assume-cia402-pdo"]);
    assert!(text.contains("\"assume_cia402_pdo\": true"), "{text}");
}

#[test]
fn the_summary_says_how_often_the_drive_faulted_and_how_it_ended() {
    let out = emcy_decode()
        .args(["--view", "summary", "--color", "never", COMMISSIONING])
        .env_remove("NO_COLOR")
        .env_remove("COLUMNS")
        .output()
        .expect("runs");
    let stdout = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        stdout.contains("faulted 1 time, recovered to operation enabled"),
        "{stdout}"
    );
}

#[test]
fn the_chart_draws_the_fault_as_a_band_on_the_drive_lane() {
    let out = emcy_decode()
        .args(["--format", "svg", COMMISSIONING])
        .output()
        .expect("runs");
    let svg = String::from_utf8(out.stdout).expect("utf-8");
    assert_eq!(svg.matches("<title>axis fault from").count(), 1, "{svg}");
    assert!(
        svg.contains("EMCY 0x7305, cleared by a fault reset at"),
        "{svg}"
    );
    // The drive states as a strip along the lane's foot, in trace order,
    // and their fills in the style sheet.
    let strips: Vec<&str> = svg
        .match_indices("<title>axis state ")
        .filter_map(|(i, _)| svg[i + 18..].split(' ').next())
        .collect();
    assert_eq!(strips, LIFE, "{svg}");
    assert!(svg.contains(".ec .a-operation_enabled{fill:"));
    // A trace without a drive has no such band.
    let out = emcy_decode()
        .args(["--format", "svg", UNKNOWN])
        .output()
        .expect("runs");
    let svg = String::from_utf8(out.stdout).expect("utf-8");
    assert!(!svg.contains("axis fault"), "{svg}");
    assert!(!svg.contains("axis state"), "{svg}");
    assert!(!svg.contains(".a-operation_enabled"), "no axis: no fills");
}

const NOT_DRIVE: &str = "fixtures/cia402-not-drive.log";
const CONTROLWORD_READ: &str = "fixtures/cia402-controlword-read.log";
const PDO_READ: &str = "fixtures/cia402-pdo-read.log";

fn node(objects: &[Value], n: u64) -> Value {
    objects
        .iter()
        .find(|o| o["type"] == "node" && o["node"] == n)
        .cloned()
        .unwrap_or(Value::Null)
}

#[test]
fn the_device_type_decides_which_nodes_the_assumption_reads_as_drives() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "--assume-cia402-pdo", NOT_DRIVE])
        .output()
        .expect("runs");
    let objects: Vec<Value> = String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    // Node 5 is a drive; node 3 (I/O) and 7 (encoder) are not: node 3's
    // PDO read before its device type came stays an event, but its report
    // has no drive, and its later PDOs (and node 7's) are not read.
    let drives: Vec<(u64, String)> = of_type(&objects, "axis_state")
        .iter()
        .map(|e| (e["node"].as_u64().unwrap_or(0), e["time_text"].to_string()))
        .collect();
    assert_eq!(
        drives.iter().filter(|(n, _)| *n == 3).count(),
        1,
        "{drives:?}"
    );
    assert_eq!(drives.iter().filter(|(n, _)| *n == 5).count(), 3);
    assert!(drives.iter().all(|(n, _)| *n != 7));
    assert_eq!(drive(&objects, 3), Value::Null);
    assert_eq!(drive(&objects, 7), Value::Null);
    assert_eq!(drive(&objects, 5)["state"], "operation_enabled");
    for (n, t, p) in [
        (3, "0x000F0191", "CiA 401 I/O"),
        (5, "0x00020192", "CiA 402 drive"),
        (7, "0x00010196", "CiA 406 encoder"),
    ] {
        let o = node(&objects, n);
        assert_eq!(o["device_type"], t, "node {n}");
        assert_eq!(o["device_profile"], p, "node {n}");
    }
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains(
            "--assume-cia402-pdo: nodes 3 (0x000F0191, CiA 401 I/O), 7 (0x00010196, CiA 406 \
             encoder) are not drives by their device type; their PDOs are not read as CiA 402"
        ),
        "{stderr}"
    );
    // Without the assumption nothing is read as a drive, and no note.
    let out = emcy_decode()
        .args(["--format", "ndjson", NOT_DRIVE])
        .output()
        .expect("runs");
    assert!(out.stderr.is_empty());
    // A DCF's device type decides before the first PDO: node 3 is never
    // read as a drive.
    let dir = tempfile::tempdir().expect("temp dir");
    let dcf = dir.path().join("io.dcf");
    fs::write(&dcf, "[1000]\nDefaultValue=0x000F0191\n").expect("write");
    let out = emcy_decode()
        .args(["--format", "ndjson", "--assume-cia402-pdo", "--dcf"])
        .arg(format!("3={}", dcf.display()))
        .arg(NOT_DRIVE)
        .output()
        .expect("runs");
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(!text.contains("\"node\":3,\"state\":\"operation_enabled\""));
    let objects: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    assert!(
        of_type(&objects, "axis_state")
            .iter()
            .all(|e| e["node"] != 3)
    );
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    assert!(stderr.contains("nodes 3 (0x000F0191"), "{stderr}");
    assert!(!stderr.contains("left out"), "{stderr}");
}

#[test]
fn a_controlword_read_is_no_fault_reset_and_one_written_is() {
    let objects = ndjson([CONTROLWORD_READ]);
    let resets = of_type(&objects, "fault_reset");
    assert_eq!(resets.len(), 1, "{resets:?}");
    assert_eq!(resets[0]["controlword"], "0x0080");
    assert_eq!(drive(&objects, 5)["fault_resets"], 1);
    // Written by SDO download (confirmed), the word commands; read by an
    // upload, it does not.
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("sdo.log");
    fs::write(
        &path,
        "(1.000000) can0 605#4040600000000000\n\
         (1.001000) can0 585#4B40600080000000\n\
         (1.002000) can0 605#2B40600080000000\n\
         (1.003000) can0 585#6040600000000000\n",
    )
    .expect("write");
    let objects = ndjson([&path]);
    let resets = of_type(&objects, "fault_reset");
    assert_eq!(resets.len(), 1, "{objects:?}");
    assert_eq!(resets[0]["time"], 1.003);
}

#[test]
fn a_mapping_read_back_decodes_the_tpdo() {
    let objects = ndjson([PDO_READ]);
    assert_eq!(states(&objects), LIFE);
    let (cob_id, objects_mapped, source) = tpdo(&drive(&objects, 6));
    assert_eq!(cob_id, 0x186);
    assert_eq!(objects_mapped, ["0x6041:16", "0x603F:16"]);
    assert_eq!(source, "sdo");
}

/// Value errors in an otherwise usable DCF: before, exit 0 and nothing on
/// stderr, the COB-ID that overflows silently the predefined one. Now one
/// `warning:` line each, with the file and line, before the report.
#[test]
fn value_errors_in_a_usable_dcf_are_warnings_with_their_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("bad.dcf");
    let text = fs::read_to_string("fixtures/cia402-drive.dcf")
        .expect("fixture")
        .replace(
            "ParameterValue=$NODEID+0x180\n",
            "ParameterValue=$NODEID+0xFFFFFFFFFFFFFFFF\n",
        )
        .replace("ParameterValue=0x60410010\n", "ParameterValue=0x6041001O\n");
    let line_of = |needle: &str| {
        text.lines()
            .position(|l| l.ends_with(needle))
            .expect("edited")
            + 1
    };
    let (cob, entry) = (line_of("0xFFFFFFFFFFFFFFFF"), line_of("0x6041001O"));
    fs::write(&path, &text).expect("write");
    let out = emcy_decode()
        .arg("--dcf")
        .arg(format!("5={}", path.display()))
        .args(["--format", "ndjson", DCF_TRACE])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(0));
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    let name = path.display();
    assert!(
        stderr.contains(&format!(
            "warning: --dcf {name}:{cob}: `0xFFFFFFFFFFFFFFFF` is above 32 bits: 0x1800 sub 1 \
             is not read from this file: the PDO keeps its predefined COB-ID\n"
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!(
            "warning: --dcf {name}:{entry}: `0x6041001O` is not a hex number: 0x1A00 sub 1 is \
             not read from this file\n"
        )),
        "{stderr}"
    );
    assert_eq!(stderr.matches("warning: --dcf").count(), 2, "{stderr}");
    // The fixture itself has none.
    let out = emcy_decode()
        .args(["--dcf", "5=fixtures/cia402-drive.dcf", DCF_TRACE])
        .output()
        .expect("runs");
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
}
