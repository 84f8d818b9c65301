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
