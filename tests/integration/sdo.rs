//! SDO transfers through the command line, on fixtures/sdo-block.log
//! (scripts/make_cia402_fixtures.py): block downloads and uploads of two
//! nodes interleaved, their segments never read as aborts, the value a
//! block upload carried learnt, and a real abort reported once.

use std::fs;

use serde_json::Value;

use crate::support::{emcy_decode, ndjson};

const BLOCK: &str = "fixtures/sdo-block.log";

fn of_type<'a>(objects: &'a [Value], t: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == t).collect()
}

#[test]
fn block_segments_are_no_aborts_and_the_real_abort_is_reported() {
    let objects = ndjson([BLOCK]);
    let aborts = of_type(&objects, "sdo_abort");
    // The last segment 0x85 of node 4's download is no client abort; the
    // node's abort of the second download is the only one.
    assert_eq!(aborts.len(), 1, "{aborts:?}");
    let a = aborts[0];
    assert_eq!(a["node"], 4);
    assert_eq!(a["index"], "0x1F50");
    assert_eq!(a["subindex"], 2);
    assert_eq!(a["abort_code"], "0x05040004");
    assert_eq!(a["by"], "server");
}

#[test]
fn a_block_upload_of_the_device_type_is_learnt() {
    let objects = ndjson([BLOCK]);
    let node = |n: u64| {
        objects
            .iter()
            .find(|o| o["type"] == "node" && o["node"] == n)
            .cloned()
            .unwrap_or(Value::Null)
    };
    assert_eq!(node(3)["device_type"], "0x000F0191");
    assert_eq!(node(3)["device_profile"], "CiA 401 I/O");
    assert_eq!(node(3)["profile_reason"], "device type 401 (not a drive)");
    // Node 4 only took a firmware download: nothing of it is a fact.
    assert_eq!(node(4)["device_type"], Value::Null);
    assert_eq!(node(4)["device_profile"], Value::Null);
}

#[test]
fn block_transfers_read_the_same_on_one_thread_and_two() {
    // Big enough for blocks on several threads: the trace 3000 times, each
    // copy 1 s later (a block transfer's frames then fall on both sides of
    // a block boundary somewhere).
    const COPIES: u64 = 3000;
    let dir = tempfile::tempdir().expect("temp dir");
    let text = fs::read_to_string(BLOCK).expect("fixture");
    let mut big = String::new();
    for copy in 0..COPIES {
        for line in text.lines() {
            let (time, rest) = line.split_once(')').expect("candump line");
            let secs: f64 = time.trim_start_matches('(').parse().expect("time");
            big.push_str(&format!("({:.6}){rest}\n", secs + copy as f64));
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
        text.matches("\"type\":\"sdo_abort\"").count(),
        COPIES as usize
    );
}

/// A client's abort is the master speaking: to an id that never answered
/// it makes no node and is said once at its line; to a node that spoke it
/// is that node's `sdo_abort`.
#[test]
fn a_client_abort_to_a_silent_id_makes_no_node() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace = dir.path().join("aborts.log");
    fs::write(
        &trace,
        "(1.000) can0 705#00\n\
         (1.100) can0 605#4000100000000000\n\
         (1.200) can0 605#8000100000000405\n\
         (1.300) can0 606#4000100000000000\n\
         (1.400) can0 606#8000100000000405\n",
    )
    .expect("write");
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .arg(&trace)
        .output()
        .expect("runs");
    let objects: Vec<Value> = String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect();
    let nodes: Vec<&Value> = of_type(&objects, "node");
    assert_eq!(nodes.len(), 1, "{nodes:?}");
    assert_eq!(nodes[0]["node"], 5);
    let aborts = of_type(&objects, "sdo_abort");
    assert_eq!(aborts.len(), 1, "{aborts:?}");
    assert_eq!(
        (&aborts[0]["node"], &aborts[0]["by"]),
        (&5.into(), &"client".into())
    );
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    assert!(
        stderr.contains("aborts.log:5: the SDO client aborted its transfer of 0x1000 sub 0 to node 6, which never answered"),
        "{stderr}"
    );
}
