//! Incidents told as stories: each fixture of `scripts/make_incident_fixtures.py`
//! has a known answer (which incidents, which root), and the answer does
//! not depend on node numbers, threads or filters of other nodes.

use serde_json::Value;

use crate::support::{ndjson, run};

fn incidents(args: &[&str]) -> Vec<Value> {
    ndjson(args)
        .into_iter()
        .filter(|v| v["type"] == "incident")
        .collect()
}

fn root(i: &Value) -> (Value, &str, Value, bool) {
    let r = &i["root"];
    (
        r["node"].clone(),
        r["kind"].as_str().unwrap(),
        r["code"].clone(),
        r["decided"].as_bool().unwrap(),
    )
}

#[test]
fn a_silent_producer_is_the_root_before_its_consumers_errors() {
    for (fixture, producer, consumers) in [
        ("fixtures/incident-silent-producer.log", 3, [5, 7]),
        ("fixtures/incident-silent-producer-permuted.log", 7, [3, 5]),
    ] {
        let found = incidents(&[fixture]);
        assert_eq!(found.len(), 1, "{fixture}: {found:#?}");
        let i = &found[0];
        assert_eq!(
            root(i),
            (producer.into(), "heartbeat_lost", Value::Null, true),
            "{fixture}"
        );
        let mut nodes = vec![producer, consumers[0], consumers[1]];
        nodes.sort_unstable();
        assert_eq!(i["nodes"], serde_json::json!(nodes));
        // Each consumer's 0x8130 links to the producer's silence, with the
        // configuration that says so.
        let links = i["links"].as_array().unwrap();
        for c in consumers {
            let l = links
                .iter()
                .find(|l| l["from"]["node"] == c && l["from"]["kind"] == "emcy")
                .unwrap_or_else(|| panic!("{fixture}: no link from node {c}: {links:#?}"));
            assert_eq!(l["to"]["node"], producer);
            assert_eq!(l["to"]["kind"], "heartbeat_lost");
            assert!(
                l["reason"].as_str().unwrap().contains("configured by SDO"),
                "{l}"
            );
        }
        let summary = i["summary"].as_str().unwrap();
        assert!(
            summary.starts_with(&format!("root: node {producer} fell silent")),
            "{summary}"
        );
        assert_eq!(i["events_total"], 5);
    }
}

#[test]
fn the_same_fault_thirty_seconds_apart_is_two_incidents() {
    let found = incidents(&["fixtures/incident-repeated.log"]);
    assert_eq!(found.len(), 2, "{found:#?}");
    for i in &found {
        assert_eq!(root(i).0, 3);
        assert_eq!(root(i).1, "heartbeat_lost");
    }
    // A gap longer than the pause makes them one.
    let one = incidents(&["--incident-gap", "40", "fixtures/incident-repeated.log"]);
    assert_eq!(one.len(), 1, "{one:#?}");
}

#[test]
fn a_master_resetting_every_node_is_no_incident() {
    assert_eq!(
        incidents(&["fixtures/incident-reset-all.log"]),
        Vec::<Value>::new()
    );
}

#[test]
fn an_rpdo_timeout_points_to_the_producer_that_stopped_even_when_it_came_first() {
    let found = incidents(&["fixtures/incident-rpdo-timeout.log"]);
    assert_eq!(found.len(), 1, "{found:#?}");
    let i = &found[0];
    assert_eq!(root(i), (3.into(), "heartbeat_lost", Value::Null, true));
    // The consumer's EMCY is the earliest event, not the root.
    assert_eq!(i["first"]["node"], 4);
    assert_eq!(i["first"]["code"], "0x8250");
    assert!(
        i["root"]["reason"]
            .as_str()
            .unwrap()
            .contains("an event it explains came first"),
        "{}",
        i["root"]
    );
}

#[test]
fn several_drives_under_voltage_at_once_is_a_common_cause() {
    let found = incidents(&["fixtures/incident-undervoltage.log"]);
    assert_eq!(found.len(), 1, "{found:#?}");
    let i = &found[0];
    assert_eq!(root(i), (4.into(), "emcy", "0x3220".into(), true));
    assert!(
        i["root"]["reason"]
            .as_str()
            .unwrap()
            .contains("a common cause outside the bus"),
        "{}",
        i["root"]
    );
    assert_eq!(i["links"].as_array().unwrap().len(), 4);
}

#[test]
fn a_bus_off_among_error_frames_starts_with_the_error_frames() {
    let found = incidents(&["fixtures/bus-off.log"]);
    let first = &found[0];
    assert_eq!(root(first).1, "bus_error", "{first:#}");
    assert!(
        first["links"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l["from"]["kind"] == "bus_off" && l["to"]["kind"] == "bus_error"),
        "{first:#}"
    );
}

#[test]
fn incidents_do_not_depend_on_threads_or_on_filters_of_other_nodes() {
    for fixture in [
        "fixtures/incident-silent-producer.log",
        "fixtures/incident-repeated.log",
        "fixtures/bus-off.log",
        "fixtures/commissioning.log",
    ] {
        let all = incidents(&[fixture]);
        assert_eq!(incidents(&["-j", "2", fixture]), all, "{fixture}: -j 2");
        assert_eq!(incidents(&["-j", "1", fixture]), all, "{fixture}: -j 1");
        // Filtered to one of an incident's nodes, the incident is the same.
        for i in &all {
            let node = i["nodes"][0].to_string();
            let filtered = incidents(&["--node", &node, fixture]);
            assert!(filtered.contains(i), "{fixture} --node {node}");
        }
    }
    // A node outside every incident selects none of them.
    assert_eq!(
        incidents(&["--node", "9", "fixtures/incident-silent-producer.log"]),
        Vec::<Value>::new()
    );
}

#[test]
fn fail_on_incident_fails_when_one_is_told() {
    let (_, err, code) = run(
        &[
            "--fail-on",
            "incident",
            "fixtures/incident-undervoltage.log",
        ],
        b"",
    );
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("incident: 1 incident"), "{err}");
    let (_, err, code) = run(
        &["--fail-on", "incident", "fixtures/incident-reset-all.log"],
        b"",
    );
    assert_eq!(code, 0, "{err}");
}

#[test]
fn the_table_tells_the_incident_in_one_row() {
    let (out, _, _) = run(&["fixtures/incident-silent-producer.log"], b"");
    let row = out
        .lines()
        .find(|l| l.contains("  incident  "))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(row.contains("root: node 3 fell silent"), "{row}");
}

#[test]
fn check_reports_an_incident_whose_root_the_baseline_has_not_seen() {
    use crate::support::Rig;
    let rig = Rig::new("");
    rig.trace_from("fixtures/incident-reset-all.log");
    let base = rig.baseline(&[]);
    assert!(!base.contains("\"incidents\""), "{base}");
    // Error frames start two incidents: a root no other finding names.
    rig.trace_from("fixtures/bus-off.log");
    let (code, found) = rig.check("incident_new");
    assert_eq!(code, Some(1), "{found:?}");
    let messages: Vec<&str> = found
        .iter()
        .map(|f| f["message"].as_str().unwrap())
        .collect();
    assert_eq!(
        messages,
        ["can0: 2 incidents rooted in bus bus_error, baseline none"],
        "{found:#?}"
    );
    assert_eq!(found[0]["severity"], "regression");
    // A root that has its own finding (node 6's first bus-off and heartbeat
    // loss) is not said twice.
    let (_, offs) = rig.check("bus_off_new");
    assert!(!offs.is_empty());
    // Recorded, the same roots are no longer new; gone, an improvement.
    let base = rig.baseline(&[]);
    assert!(base.contains("\"bus bus_error\": 2"), "{base}");
    assert_eq!(rig.check("incident_new"), (Some(0), vec![]));
    rig.trace_from("fixtures/incident-reset-all.log");
    let (_, gone) = rig.check("incident_gone");
    let messages: Vec<&str> = gone
        .iter()
        .map(|f| f["message"].as_str().unwrap())
        .collect();
    assert_eq!(
        messages,
        ["can0: no incident rooted in bus bus_error now (baseline 2)"]
    );
}

#[test]
fn the_chart_marks_each_incident_as_a_numbered_band() {
    let told = incidents(&["fixtures/bus-off.log"]);
    let (svg, _, code) = run(&["--format", "svg", "fixtures/bus-off.log"], b"");
    assert_eq!(code, 0);
    let doc = roxmltree::Document::parse(&svg).expect("well-formed SVG");
    let bands: Vec<roxmltree::Node<'_, '_>> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("inc"))
        .collect();
    assert_eq!(bands.len(), told.len());
    // The legend says what the bands are, where there are any.
    assert!(
        svg.contains(">incident (numbered as in the table)<"),
        "{svg}"
    );
    let (quiet, _, _) = run(&["--format", "svg", "fixtures/incident-reset-all.log"], b"");
    assert!(!quiet.contains("incident (numbered"), "{quiet}");
    for (k, (band, incident)) in bands.iter().zip(&told).enumerate() {
        let title = band
            .descendants()
            .find(|n| n.has_tag_name("title"))
            .and_then(|t| t.text())
            .unwrap();
        assert_eq!(
            title,
            format!(
                "incident {}: {}",
                k + 1,
                incident["summary"].as_str().unwrap()
            )
        );
        let number = band
            .descendants()
            .find(|n| n.has_tag_name("text"))
            .and_then(|t| t.text())
            .unwrap();
        assert_eq!(number, (k + 1).to_string());
    }
}

/// Live input: an incident is told once the trace's clock has passed its
/// gap, while the input is still open, not only at its end.
#[test]
fn a_live_incident_is_told_while_the_input_stays_open() {
    use std::io::Write;
    let mut child = crate::live::spawn(&["--format", "ndjson", "--incident-gap", "0.5", "-"]);
    let mut stdin = child.stdin.take().unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        use std::io::BufRead;
        for line in std::io::BufReader::new(stdout)
            .lines()
            .map_while(Result::ok)
        {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let trace = std::fs::read("fixtures/incident-silent-producer.log").unwrap();
    stdin.write_all(&trace).unwrap();
    stdin.flush().unwrap();
    // stdin stays open: the incident must come out on the clock alone.
    let incident = loop {
        let line = rx
            .recv_timeout(crate::live::WAIT)
            .expect("the incident is told while the input is open");
        if line.starts_with(r#"{"type":"incident""#) {
            break line;
        }
    };
    assert!(incident.contains("root: node 3 fell silent"), "{incident}");
    drop(stdin);
    assert!(child.wait().unwrap().success());
}
