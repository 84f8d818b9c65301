//! The node table is bounded: past [`Options::max_nodes`] nodes (pairs of
//! channel and node id), reading stops with an error that says the bound,
//! and what was read is reported. A trace naming a million channels took
//! 1.03 GB and aborted under a 768 MB address-space limit.

use serde_json::Value;

use crate::analyze::{DiagnosticLog, Options, Sink, analyze};
use crate::report::ndjson::Ndjson;

/// One EMCY on each of `channels` channels.
fn many_channels(channels: usize) -> Vec<u8> {
    let mut t = Vec::new();
    for i in 0..channels {
        t.extend(format!("({i}.0) c{i} 081#1043080100000000\n").bytes());
    }
    t
}

/// The input object and the node objects, read with `max_nodes` and
/// blocks of `block_size` bytes.
fn read(trace: &[u8], max_nodes: usize, block_size: usize) -> (Value, usize) {
    let opts = Options {
        max_nodes,
        block_size,
        ..Options::default()
    };
    let mut out = Vec::new();
    {
        let mut renderer = Ndjson::new(&mut out, false);
        let mut log = DiagnosticLog::new(Vec::new());
        let a = analyze("t", trace, false, &opts, &mut renderer, &mut log).unwrap();
        renderer.finish(&[a.report], &[]).unwrap();
    }
    let objects: Vec<Value> = String::from_utf8(out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let nodes = objects.iter().filter(|o| o["type"] == "node").count();
    let input = objects.into_iter().find(|o| o["type"] == "input").unwrap();
    (input, nodes)
}

#[test]
fn past_the_node_cap_reading_stops_with_an_error_and_the_report() {
    let trace = many_channels(1000);
    // Under the cap: everything, no error.
    let (input, nodes) = read(&trace, 1000, 4096);
    assert_eq!((input["error"].clone(), nodes), (Value::Null, 1000));
    // Over it: reading stops within the block that filled the table (at
    // most one block later), and says why.
    let (input, nodes) = read(&trace, 100, 4096);
    assert_eq!(
        input["error"],
        "more than 100 nodes (pairs of channel and node id): reading stopped there (the node \
         table is bounded; a trace names that many only when it is damaged or hostile)"
    );
    let lines = input["lines"].as_u64().unwrap() as usize;
    assert!((101..=101 + 4096 / 20).contains(&lines), "{lines} lines");
    assert_eq!(nodes, lines, "one node a line, each reported");
}

/// NMT commands to ids that never spoke make no node, but each id is kept
/// (what was sent to it shapes how its first frames read): the same bound.
#[test]
fn ids_addressed_before_they_spoke_count_against_the_cap() {
    let mut trace = Vec::new();
    for i in 0..1000 {
        trace.extend(format!("({i}.0) c{i} 000#0105\n").bytes());
    }
    let (input, nodes) = read(&trace, 1000, 4096);
    assert_eq!((input["error"].clone(), nodes), (Value::Null, 0));
    let (input, _) = read(&trace, 100, 4096);
    assert!(
        input["error"]
            .as_str()
            .is_some_and(|e| e.starts_with("more than 100 nodes")),
        "{input}"
    );
}
