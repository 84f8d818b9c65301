//! An event lists at most [`EVENT_ACTIVE_MAX`] of its node's active codes,
//! and says how many there are when it lists fewer: a node with thousands of
//! errors that never clear made every event list them all (output and work
//! quadratic in them). The node object at the end lists them all.

use serde_json::Value;

use crate::analyze::event::EVENT_ACTIVE_MAX;
use crate::analyze::{DiagnosticLog, Options, Sink, analyze};
use crate::report::ndjson::Ndjson;

/// Node 1 raises `codes` distinct codes (0x1001, 0x1002, ...) and never
/// clears them; then node 2 raises one.
fn never_cleared(codes: u16) -> Vec<u8> {
    let mut t = Vec::new();
    for i in 0..codes {
        let [lo, hi] = (0x1001 + i).to_le_bytes();
        t.extend(format!("({i}.0) can0 081#{lo:02X}{hi:02X}0100000000\n").bytes());
    }
    t.extend(b"(99999.0) can0 082#1043090100000000\n");
    t
}

fn objects(trace: &[u8]) -> Vec<Value> {
    let mut out = Vec::new();
    {
        let mut renderer = Ndjson::new(&mut out, false);
        let mut log = DiagnosticLog::new(Vec::new());
        let a = analyze(
            "t",
            trace,
            false,
            &Options::default(),
            &mut renderer,
            &mut log,
        )
        .unwrap();
        renderer.finish(&[a.report], &[]).unwrap();
    }
    String::from_utf8(out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn codes(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap().to_string())
        .collect()
}

#[test]
fn events_list_the_first_active_codes_and_count_the_rest() {
    let n = EVENT_ACTIVE_MAX as u16 * 3;
    let objects = objects(&never_cleared(n));
    let events: Vec<&Value> = objects.iter().filter(|o| o["type"] == "emcy").collect();
    assert_eq!(events.len(), usize::from(n) + 1);
    let raised: Vec<String> = (0..n).map(|i| format!("0x{:04X}", 0x1001 + i)).collect();
    for (i, event) in events.iter().take(usize::from(n)).enumerate() {
        let active = codes(&event["active"]);
        let total = i + 1;
        assert_eq!(active, raised[..total.min(EVENT_ACTIVE_MAX)], "event {i}");
        match total > EVENT_ACTIVE_MAX {
            true => assert_eq!(event["active_truncated"], total, "event {i}"),
            false => assert!(event.get("active_truncated").is_none(), "event {i}"),
        }
    }
    // Another node's event is its own.
    let last = events.last().unwrap();
    assert_eq!(codes(&last["active"]), ["0x4310"]);
    assert!(last.get("active_truncated").is_none());
    // The node object lists every active code.
    let node = objects
        .iter()
        .find(|o| o["type"] == "node" && o["node"] == 1)
        .unwrap();
    assert_eq!(codes(&node["active"]), raised);
}
