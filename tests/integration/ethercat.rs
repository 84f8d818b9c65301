//! EtherCAT captures through the binary: the fixtures of
//! `scripts/make_ethercat_fixtures.py` (two STÖBER slaves, CoE emergencies
//! read from their mailboxes among process data and empty polls, an SDO
//! identity read, a retry, VLAN and UDP framing, damage) give the slaves'
//! error timelines by station address; Wireshark's own EtherCAT dissector
//! agrees on which packets carry which emergency.

use std::collections::BTreeMap;
use std::process::Command;

use serde_json::Value;

use crate::support::{self, emcy_decode};

const PCAPNG: &str = "fixtures/stoeber-ecat.pcapng";
const PCAP: &str = "fixtures/stoeber-ecat.pcap";

fn of_type<'v>(objects: &'v [Value], kind: &str) -> Vec<&'v Value> {
    objects.iter().filter(|o| o["type"] == kind).collect()
}

#[test]
fn coe_emergencies_are_events_of_their_station_with_no_cob_id() {
    let out = support::ndjson([PCAPNG]);
    let emcys = of_type(&out, "emcy");
    let seen: Vec<(u64, u64, &str, &str)> = emcys
        .iter()
        .map(|e| {
            (
                e["line"].as_u64().unwrap(),
                e["node"].as_u64().unwrap(),
                e["code"].as_str().unwrap(),
                e["data"].as_str().unwrap(),
            )
        })
        .collect();
    // Line 59 repeats line 58 with the same mailbox counter: a retry.
    assert_eq!(
        seen,
        [
            (58, 1001, "0x4310", "1043012900000000"),
            (60, 1002, "0x3210", "1032050700000000"),
            (63, 1001, "0x0000", "0000001E00000000"),
            (63, 1002, "0x0000", "0000001E00000000"),
        ]
    );
    for e in &emcys {
        assert_eq!(e["cob_id"], Value::Null);
        assert_eq!(e["channel"], "eth0");
    }
    // The fault and its acknowledgment, as the STÖBER manual describes.
    assert_eq!(
        emcys[0]["manufacturer_decoded"]["event_text"],
        "Temperature motor TMS"
    );
    assert_eq!(emcys[2]["transition"], 4);
    assert_eq!(emcys[2]["cleared"], serde_json::json!(["0x4310"]));
}

#[test]
fn the_identity_read_over_coe_chooses_the_profile() {
    let out = support::ndjson([PCAPNG]);
    let nodes = of_type(&out, "node");
    let by_node: BTreeMap<u64, &Value> = nodes
        .iter()
        .map(|n| (n["node"].as_u64().unwrap(), *n))
        .collect();
    assert_eq!(by_node[&1001]["profile"], "stoeber");
    assert_eq!(by_node[&1001]["profile_source"], "trace");
    assert_eq!(
        by_node[&1001]["profile_reason"],
        "vendor id 0x000000B9 (STÖBER)"
    );
    // 1002 never said who it is.
    assert_eq!(by_node[&1002]["profile_source"], "default");
    let named = support::ndjson(["--profile", "1002=stoeber", PCAPNG]);
    let n = of_type(&named, "node")
        .into_iter()
        .find(|n| n["node"] == 1002)
        .cloned()
        .unwrap();
    assert_eq!(n["profile"], "stoeber");
    assert_eq!(n["profile_source"], "flag");
}

#[test]
fn the_input_counts_ethercat_frames_mailbox_messages_retries_and_polls() {
    for (file, format) in [(PCAPNG, "pcapng"), (PCAP, "pcap")] {
        let out = support::ndjson([file]);
        let input = of_type(&out, "input")[0].clone();
        assert_eq!(input["format"], format, "{file}");
        // 70 packets: an ARP request, 69 EtherCAT frames (one damaged).
        assert_eq!(input["lines"], 70, "{file}");
        assert_eq!(input["frames"], 0, "{file}");
        assert_eq!(input["skipped"], 69, "{file}");
        assert_eq!(input["malformed"], 1, "{file}");
        assert_eq!(input["ethercat_frames"], 69, "{file}");
        assert_eq!(input["mailbox_messages"], 17, "{file}");
        assert_eq!(input["mailbox_retries"], 1, "{file}");
        assert_eq!(input["mailbox_empty_polls"], 105, "{file}");
        assert_eq!(input["emcy"], 4, "{file}");
    }
    // CAN inputs keep their objects as they were.
    let can = support::ndjson(["fixtures/s300.pcap"]);
    assert!(of_type(&can, "input")[0].get("ethercat_frames").is_none());
}

#[test]
fn the_damaged_frame_is_reported_with_its_line_and_reading_goes_on() {
    let out = emcy_decode().arg(PCAPNG).output().unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains(&format!(
            "{PCAPNG}:62: EtherCAT datagram 2 (FPRD) of 200 data bytes runs past the end"
        )),
        "{stderr}"
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(
        stdout.contains("bus: 69 EtherCAT frames (17 mailbox messages, 1 retry, 105 empty polls)"),
        "{stdout}"
    );
}

#[test]
fn node_and_fail_on_work_on_station_addresses() {
    let only = support::ndjson(["--node", "1002", PCAPNG]);
    let emcys = of_type(&only, "emcy");
    assert_eq!(emcys.len(), 2);
    assert!(emcys.iter().all(|e| e["node"] == 1002));
    emcy_decode()
        .args(["--fail-on", "any", "--node", "1001", PCAPNG])
        .assert()
        .code(1);
    emcy_decode()
        .args(["--node", "65536", PCAPNG])
        .assert()
        .code(2);
}

/// Wireshark's EtherCAT mailbox dissector (tshark) on the same capture:
/// every CoE emergency it shows (CoE service 1), by frame and bytes, is
/// one of our events or the one retry the input counts.
#[test]
fn tshark_sees_the_same_emergencies_in_the_same_packets() {
    let Ok(out) = Command::new("tshark")
        .args([
            "-r",
            PCAPNG,
            "-Y",
            "ecat_mailbox.coe.type == 1",
            "-T",
            "fields",
        ])
        .args(["-e", "frame.number", "-e", "ecat_mailbox.coe.type"])
        .args(["-e", "ecat_mailbox.coe", "-E", "occurrence=a"])
        .args(["-E", "aggregator=;"])
        .output()
    else {
        // .ci/run installs tshark; without it here, say so loudly.
        assert!(
            std::env::var_os("CI").is_none(),
            "tshark is not installed (apt-get install tshark)"
        );
        eprintln!("tshark not installed: EtherCAT cross-check skipped");
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut theirs: Vec<(u64, String)> = Vec::new();
    for line in String::from_utf8(out.stdout).unwrap().lines() {
        let mut fields = line.split('\t');
        let frame: u64 = fields.next().unwrap().parse().unwrap();
        let types = fields.next().unwrap().split(';');
        let bodies = fields.next().unwrap().split(';');
        for (kind, body) in types.zip(bodies) {
            if kind == "1" {
                // The CoE header's two bytes, then the EMCY's eight.
                let hex: String = body.chars().filter(|c| *c != ':').skip(4).collect();
                theirs.push((frame, hex.to_uppercase()));
            }
        }
    }
    let objects = support::ndjson([PCAPNG]);
    let mut ours: Vec<(u64, String)> = of_type(&objects, "emcy")
        .iter()
        .map(|e| {
            (
                e["line"].as_u64().unwrap(),
                e["data"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    let retries = of_type(&objects, "input")[0]["mailbox_retries"]
        .as_u64()
        .unwrap();
    assert_eq!(theirs.len() as u64, ours.len() as u64 + retries);
    // The retry is frame 59, a copy of frame 58's emergency.
    ours.push((59, "1043012900000000".to_string()));
    ours.sort();
    theirs.sort();
    assert_eq!(ours, theirs);
}

/// The capture's first `packets` packets: its blocks up to there (section
/// and interface headers, then one enhanced packet block per packet).
fn first_packets(packets: usize) -> Vec<u8> {
    let bytes = std::fs::read(PCAPNG).unwrap();
    let mut at = 0;
    let mut seen = 0;
    while at < bytes.len() {
        let kind = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
        let len = u32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap()) as usize;
        if kind == 6 {
            if seen == packets {
                break;
            }
            seen += 1;
        }
        at += len;
    }
    bytes[..at].to_vec()
}

#[test]
fn check_reports_a_slave_whose_fault_is_no_longer_acknowledged() {
    // Baseline keys are paths relative to where check runs: one directory.
    let dir = tempfile::tempdir().unwrap();
    let trace = dir.path().join("stoeber-ecat.pcapng");
    std::fs::copy(PCAPNG, &trace).unwrap();
    let run = |args: &[&str]| {
        let out = emcy_decode()
            .current_dir(dir.path())
            .args(args)
            .output()
            .unwrap();
        let text = String::from_utf8(out.stdout).unwrap() + &String::from_utf8(out.stderr).unwrap();
        (out.status.code(), text)
    };
    let trace_arg = "stoeber-ecat.pcapng";
    assert_eq!(run(&["baseline", trace_arg, "-o", "b.json"]).0, Some(0));
    assert_eq!(
        run(&["check", "--baseline", "b.json", trace_arg]).0,
        Some(0)
    );
    // The same trace without the acknowledgments (packet 63 on).
    std::fs::write(&trace, first_packets(62)).unwrap();
    let (code, text) = run(&["check", "--baseline", "b.json", trace_arg]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("1001") && text.contains("0x4310"), "{text}");
}

#[test]
fn coe_sdo_aborts_and_the_error_history_are_the_same_events_as_on_can() {
    let out = support::ndjson([PCAPNG]);
    let aborts = of_type(&out, "sdo_abort");
    assert_eq!(aborts.len(), 1);
    let a = aborts[0];
    assert_eq!(
        (a["line"].as_u64(), a["node"].as_u64()),
        (Some(7), Some(1002))
    );
    assert_eq!(a["index"], "0x1003");
    assert_eq!(a["subindex"], 5);
    assert_eq!(a["abort_code"], "0x06090011");
    let history = of_type(&out, "error_history");
    assert_eq!(history.len(), 1);
    let h = history[0];
    assert_eq!(
        (h["line"].as_u64(), h["node"].as_u64()),
        (Some(70), Some(1001))
    );
    assert_eq!(h["complete"], true);
    let entries: Vec<(&str, bool)> = h["entries"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["code"].as_str().unwrap(),
                e["before_trace"].as_bool().unwrap(),
            )
        })
        .collect();
    // 0x4310 was raised in the trace; 0x7305 before it began.
    assert_eq!(entries, [("0x4310", false), ("0x7305", true)]);
    let node = of_type(&out, "node")
        .into_iter()
        .find(|n| n["node"] == 1001)
        .unwrap();
    assert_eq!(node["error_history"]["entries"][1]["code"], "0x7305");
}
