//! `emcy-decode config TRACE`: the configuration a trace wrote into its
//! nodes, on fixtures/sdo-startup.log (scripts/make_sdo_fixtures.py) and
//! its node 3's DCF (fixtures/sdo-startup-node3.dcf, our own).

use std::fs;
use std::path::Path;

use serde_json::Value;

use crate::support::golden::check;
use crate::support::run;

const TRACE: &str = "fixtures/sdo-startup.log";
const DCF: &str = "fixtures/sdo-startup-node3.dcf";

/// The sections of an INI text, each with its keys and comments.
fn section<'a>(text: &'a str, name: &str) -> Vec<&'a str> {
    let head = format!("[{name}]");
    text.lines()
        .skip_while(|l| *l != head)
        .skip(1)
        .take_while(|l| !l.is_empty())
        .collect()
}

#[test]
fn the_last_confirmed_value_wins_and_a_refused_write_is_never_a_value() {
    let (out, err, code) = run(&["config", TRACE], b"");
    assert_eq!(code, 0, "{err}");
    // Written twice (disabled, then enabled): the last write is the value.
    assert_eq!(
        section(&out, "1800sub1"),
        [
            "ParameterName=TPDO communication parameter",
            "ParameterValue=0x00000183",
            "; line 36 (the last of 2 writes)",
        ]
    );
    assert_eq!(section(&out, "1A00sub1")[1], "ParameterValue=0x60410010");
    assert_eq!(section(&out, "1A00sub0")[1], "ParameterValue=0x01");
    // Node 4 aborted its write: a comment, no section, no value.
    assert!(out.contains("; [6200sub1] never applied\n"), "{out}");
    assert!(
        out.contains("; line 60: a write of FF aborted by the node, 0x06020000"),
        "{out}"
    );
    assert!(section(&out, "6200sub1").is_empty());
    // Reads are no configuration; nor is a request nobody answered.
    assert!(!out.contains("[1000]") && !out.contains("[1008]"), "{out}");
    // A value over four bytes is no number: its bytes and hash as comments;
    // one whose segments were not read, its size.
    assert!(out.contains("; 70 bytes, no number: 000102"), "{out}");
    assert!(out.contains("; 4100 bytes, no number: its segments not read"));
    // One file per node, each with its header.
    assert_eq!(out.matches("; emcy-decode config: node ").count(), 2);
}

#[test]
fn the_files_read_back_as_dcfs() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (_, err, code) = run(
        &["config", "-o", dir.path().to_str().expect("utf-8"), TRACE],
        b"",
    );
    assert_eq!(code, 0, "{err}");
    let node3 = dir.path().join("node3.dcf");
    assert!(err.contains(&format!("wrote {}", node3.display())), "{err}");
    assert!(dir.path().join("node4.dcf").exists());
    // Our own DCF reader takes it: TPDO1 of node 3 on 0x183 with the
    // statusword, as the trace configured it.
    let dcf = emcy_decode::canopen::dcf::parse(&fs::read(&node3).expect("written"), 3);
    assert_eq!(dcf.problems, []);
    let tpdo: Vec<(u32, Vec<u32>)> = dcf
        .mappings
        .iter()
        .map(|m| {
            (
                m.cob_id.id,
                m.objects
                    .iter()
                    .map(|o| {
                        (u32::from(o.object.index) << 16)
                            | (u32::from(o.object.sub) << 8)
                            | u32::from(o.bits)
                    })
                    .collect(),
            )
        })
        .collect();
    assert_eq!(tpdo, [(0x183, vec![0x6041_0010])]);
}

#[test]
fn files_it_did_not_write_are_left_as_they_are() {
    let dir = tempfile::tempdir().expect("temp dir");
    let foreign = dir.path().join("node3.dcf");
    fs::write(&foreign, "[DeviceInfo]\nVendorNumber=1\n").expect("write");
    let out_dir = dir.path().to_str().expect("utf-8");
    let (_, err, code) = run(&["config", "-o", out_dir, TRACE], b"");
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("node3.dcf exists and was not written by emcy-decode config"),
        "{err}"
    );
    assert_eq!(
        fs::read_to_string(&foreign).expect("kept"),
        "[DeviceInfo]\nVendorNumber=1\n"
    );
    assert!(
        dir.path().join("node4.dcf").exists(),
        "the other is written"
    );
    // Its own files it writes over.
    fs::remove_file(&foreign).expect("remove");
    assert_eq!(run(&["config", "-o", out_dir, TRACE], b"").2, 0);
    assert_eq!(run(&["config", "-o", out_dir, TRACE], b"").2, 0);
    assert_eq!(
        run(&["config", "-f", "json", "-o", out_dir, TRACE], b"").2,
        0
    );
    fs::write(dir.path().join("config.json"), "{}").expect("write");
    assert_eq!(
        run(&["config", "-f", "json", "-o", out_dir, TRACE], b"").2,
        2
    );
}

#[test]
fn a_dcf_gives_the_differences_from_the_trace() {
    let spec = format!("3={DCF}");
    let (out, err, code) = run(&["config", "--node", "3", "--dcf", &spec, TRACE], b"");
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains(
            ";   [1800sub1] trace 0x00000183, file $NODEID+0x80000180 = 0x80000183 (line 14)"
        ),
        "{out}"
    );
    assert!(
        out.contains(";   [1A00sub0] trace 0x01, file no value"),
        "{out}"
    );
    assert!(
        !out.contains(";   [1A00sub1]"),
        "the same value is no difference"
    );
    assert!(!out.contains("node 4"), "--node 3 only");
    let (json, _, _) = run(&["config", "-f", "json", "--dcf", &spec, TRACE], b"");
    let v: Value = serde_json::from_str(&json).expect("JSON");
    let nodes = v["nodes"].as_array().expect("nodes");
    assert_eq!(nodes.len(), 2);
    let diffs = nodes[0]["dcf"]["differences"]
        .as_array()
        .expect("differences");
    assert_eq!(diffs.len(), 2);
    assert_eq!(diffs[0]["index"], "0x1800");
    assert_eq!(diffs[0]["file_line"], 14);
    assert!(nodes[1]["dcf"].is_null(), "node 4 has no DCF");
    let refused = &nodes[1]["objects"][1]["refused"];
    assert_eq!(refused["result"], "abort");
    assert_eq!(refused["abort_code"], "0x06020000");
}

#[test]
fn config_outputs_match_their_golden_files() {
    let spec = format!("3={DCF}");
    let mut failures = Vec::new();
    for (name, args) in [
        (
            "sdo-startup.dcf",
            vec!["config", "--dcf", spec.as_str(), TRACE],
        ),
        (
            "sdo-startup.json",
            vec!["config", "-f", "json", "--dcf", spec.as_str(), TRACE],
        ),
    ] {
        let (out, err, code) = run(&args, b"");
        assert_eq!(code, 0, "{err}");
        check(
            &Path::new("tests/golden/config").join(name),
            &out,
            &mut failures,
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_trace_that_cannot_be_read_writes_nothing() {
    let (out, err, code) = run(&["config", "fixtures/no-such-trace.log"], b"");
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert_eq!(
        err.lines().filter(|l| l.starts_with("error:")).count(),
        1,
        "{err}"
    );
    // A trace without downloads: nothing to write, said once.
    let (out, err, code) = run(&["config", "fixtures/s300.log"], b"");
    assert_eq!((code, out.as_str()), (0, ""));
    assert!(err.contains("no SDO download"), "{err}");
}
