//! A node's whole error state, through the command line, on the
//! commissioning fixture (fixtures/make_fixtures.py, `commissioning()`):
//! NMT states, lost heartbeats, the 1003h error history, SDO aborts, and
//! `--heartbeat-timeout`, `--fail-on lost`, `check`'s `heartbeat_lost_new`.

use std::fs;

use serde_json::{Value, json};

use crate::support::{Rig, emcy_decode, ndjson};

const TRACE: &str = "fixtures/commissioning.log";

fn of_type<'a>(objects: &'a [Value], t: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == t).collect()
}

fn node(objects: &[Value], n: u64) -> Value {
    objects
        .iter()
        .find(|o| o["type"] == "node" && o["node"] == n)
        .cloned()
        .unwrap_or(Value::Null)
}

#[test]
fn every_health_event_has_the_common_keys_and_line_order() {
    let objects = ndjson([TRACE]);
    let mut last = 0;
    let mut types = std::collections::BTreeSet::new();
    for o in objects
        .iter()
        // The summaries at the end: nodes, channels, inputs.
        .filter(|o| !matches!(o["type"].as_str(), Some("node" | "channel" | "input")))
        // An incident is told when it closes, after later lines.
        .filter(|o| o["type"] != "incident")
    {
        for key in ["file", "line", "time", "channel", "node"] {
            assert!(o.get(key).is_some(), "{key} missing in {o}");
        }
        assert_eq!(o["file"], TRACE);
        let line = o["line"].as_u64().expect("line");
        assert!(line >= last, "line order: {o}");
        last = line;
        types.insert(o["type"].as_str().unwrap_or_default().to_string());
    }
    let expected = [
        "boot",
        "emcy",
        "error_history",
        "error_history_cleared",
        "heartbeat_back",
        "heartbeat_lost",
        "nmt",
        "sdo",
        "sdo_abort",
    ];
    assert_eq!(types.into_iter().collect::<Vec<_>>(), expected);
}

#[test]
fn nmt_events_are_state_changes_with_their_source() {
    let objects = ndjson([TRACE]);
    let changes = |n: u64| -> Vec<(String, String)> {
        of_type(&objects, "nmt")
            .into_iter()
            .filter(|o| o["node"] == n)
            .map(|o| {
                (
                    o["state"].as_str().unwrap_or_default().to_string(),
                    o["via"].as_str().unwrap_or_default().to_string(),
                )
            })
            .collect()
    };
    let pair = |s: &str, v: &str| (s.to_string(), v.to_string());
    // Node 1: the boot-up enters pre-operational (CiA 301), the start
    // command asks for operational, its own heartbeat confirms it.
    assert_eq!(
        changes(1),
        [
            pair("pre_operational", "boot_up"),
            pair("operational", "command"),
            pair("operational", "heartbeat"),
        ]
    );
    // Node 3 ignores the stop: the command asks for stopped, its heartbeat
    // 3 ms later was queued before it, the one after the grace still says
    // operational, which it never stopped being: no event.
    assert_eq!(changes(3)[3..], [pair("stopped", "command")]);
    // Node 2 restarts after the outage and is started again.
    assert_eq!(
        changes(2)[3..],
        [
            pair("pre_operational", "boot_up"),
            pair("operational", "command"),
            pair("operational", "heartbeat"),
        ]
    );
    // Node 4 is guarded, not heartbeating.
    assert_eq!(
        changes(4),
        [
            pair("pre_operational", "guarding"),
            pair("operational", "command"),
            pair("operational", "guarding"),
        ]
    );
    let n4 = node(&objects, 4);
    assert_eq!(n4["nmt_state"], "operational");
    assert_eq!(n4["nmt_commanded"], Value::Null);
    // Supervised by its guarding replies, the toggle error counted.
    assert_eq!(n4["heartbeat"]["via"], "guarding");
    assert_eq!(n4["heartbeat"]["guarding"]["toggle_errors"], 1);
    assert_eq!(
        n4["heartbeat"]["guarding"]["requests"],
        n4["heartbeat"]["guarding"]["replies"]
    );
}

#[test]
fn warnings_name_the_ignored_command_and_the_toggle_error() {
    let out = emcy_decode()
        .args(["--format", "ndjson", TRACE])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(
            "commissioning.log:106: node 3: ignored the NMT command stop (it reports operational, not stopped)"
        ),
        "{stderr}"
    );
    assert!(
        stderr.contains(
            "commissioning.log:84: node 4: node guarding: toggle bit error (the reply has 1, expected 0)"
        ),
        "{stderr}"
    );
}

#[test]
fn pulled_cable_is_an_outage_until_the_boot_up() {
    let objects = ndjson([TRACE]);
    let lost: Vec<&Value> = of_type(&objects, "heartbeat_lost")
        .into_iter()
        .filter(|o| o["node"] == 2)
        .collect();
    assert_eq!(lost.len(), 1);
    // Producer time 100 ms read by SDO, with the margin: 150 ms after the
    // last heartbeat.
    assert_eq!(lost[0]["time"].as_f64(), "1700000001.652000".parse().ok());
    assert_eq!(
        lost[0]["last_seen"].as_f64(),
        "1700000001.502000".parse().ok()
    );
    assert_eq!(lost[0]["timeout_source"], "producer");
    let back: Vec<&Value> = of_type(&objects, "heartbeat_back")
        .into_iter()
        .filter(|o| o["node"] == 2)
        .collect();
    assert_eq!(back.len(), 1);
    assert_eq!(back[0]["silent"].as_f64(), Some(0.998000));
    assert_eq!(back[0]["restarted"], true);
    let hb = &node(&objects, 2)["heartbeat"];
    assert_eq!(hb["lost"], 1);
    assert_eq!(hb["silent_at_end"], false);
    assert_eq!(hb["period"].as_f64(), Some(0.100000));
    assert_eq!(
        hb["outages"],
        serde_json::from_str::<Value>(
            r#"[{"start":1700000001.652000,"start_text":"2023-11-14T22:13:21.652000Z","end":1700000002.500000,"end_text":"2023-11-14T22:13:22.500000Z","duration":0.848000}]"#
        )
        .unwrap_or_default()
    );
}

#[test]
fn a_node_silent_to_the_end_is_lost_at_its_deadline() {
    let objects = ndjson([TRACE]);
    let lost: Vec<&Value> = of_type(&objects, "heartbeat_lost")
        .into_iter()
        .filter(|o| o["node"] == 3)
        .collect();
    assert_eq!(lost.len(), 1);
    // The consumer time node 1 was given for node 3 (0x1016 sub 1, 250 ms).
    assert_eq!(lost[0]["timeout_source"], "consumer");
    assert_eq!(lost[0]["time"].as_f64(), "1700000003.053000".parse().ok());
    let hb = &node(&objects, 3)["heartbeat"];
    assert_eq!(hb["silent_at_end"], true);
    assert_eq!(hb["outages"][0]["end"], Value::Null);
    // Node 1 never lost its heartbeat: its timeout is learnt.
    let hb1 = &node(&objects, 1)["heartbeat"];
    assert_eq!(hb1["lost"], 0);
    assert_eq!(hb1["timeout_source"], "learnt");
    assert_eq!(hb1["timeout"].as_f64(), Some(0.300000));
}

#[test]
fn heartbeat_timeout_flag_wins_over_the_trace() {
    let objects = ndjson(["--heartbeat-timeout", "2", TRACE]);
    // Two seconds: node 2's one-second outage is none; node 3 is silent
    // for less than two seconds before the trace ends.
    assert!(of_type(&objects, "heartbeat_lost").is_empty());
    let hb = &node(&objects, 2)["heartbeat"];
    assert_eq!(hb["timeout_source"], "option");
    assert_eq!(hb["timeout"].as_f64(), Some(2.0));
    emcy_decode()
        .args(["--heartbeat-timeout", "0", TRACE])
        .assert()
        .code(2);
    emcy_decode()
        .args(["--heartbeat-timeout", "soon", TRACE])
        .assert()
        .code(2);
}

#[test]
fn error_history_read_out_clear_and_partial() {
    let objects = ndjson([TRACE]);
    let histories = of_type(&objects, "error_history");
    assert_eq!(histories.len(), 3);
    let first = histories[0];
    assert_eq!(first["node"], 1);
    assert_eq!(first["complete"], true);
    assert_eq!(first["count"], 3);
    assert_eq!(
        first["entries"],
        json!([
            {"code": "0x4310", "info": "0x0012",
             "description": "Temperature · drive · excess temperature drive", "before_trace": true},
            {"code": "0x3120", "info": "0x0000",
             "description": "Voltage · mains · mains under-voltage", "before_trace": false},
            {"code": "0xFF01", "info": "0x0007",
             "description": first["entries"][2]["description"], "before_trace": true},
        ])
    );
    let cleared = of_type(&objects, "error_history_cleared");
    assert_eq!(cleared.len(), 1);
    assert_eq!(cleared[0]["node"], 1);
    // Read again after the clear: empty and complete.
    assert_eq!(histories[1]["entries"], json!([]));
    assert_eq!(histories[1]["complete"], true);
    // Node 3's read-out stops after sub 1 of 2.
    assert_eq!(histories[2]["node"], 3);
    assert_eq!(histories[2]["complete"], false);
    assert_eq!(histories[2]["count"], 2);
    // The node objects keep the last read-out, with its own line.
    let h1 = &node(&objects, 1)["error_history"];
    assert_eq!(h1["entries"], json!([]));
    assert_eq!(h1["line"], 64);
    let h3 = &node(&objects, 3)["error_history"];
    assert_eq!(h3["complete"], false);
    assert_eq!(h3["line"], 74);
    assert_eq!(node(&objects, 2)["error_history"], Value::Null);
}

#[test]
fn sdo_abort_on_a_missing_sub_index() {
    let objects = ndjson([TRACE]);
    let aborts = of_type(&objects, "sdo_abort");
    assert_eq!(aborts.len(), 1);
    let a = aborts[0];
    assert_eq!(a["node"], 1);
    assert_eq!(a["index"], "0x1003");
    assert_eq!(a["subindex"], 4);
    assert_eq!(a["abort_code"], "0x06090011");
    assert_eq!(a["text"], "sub-index does not exist");
    assert_eq!(a["by"], "server");
}

#[test]
fn fail_on_lost_fails_only_when_a_heartbeat_was_lost() {
    emcy_decode()
        .args(["--fail-on", "lost", TRACE])
        .assert()
        .code(1)
        .stderr(predicates::str::contains(
            "fail-on: lost: 2 nodes lost their heartbeat",
        ));
    emcy_decode()
        .args(["--fail-on", "lost", "--heartbeat-timeout", "5", TRACE])
        .assert()
        .code(0);
    emcy_decode()
        .args(["--fail-on", "lost", "fixtures/s300.log"])
        .assert()
        .code(0);
}

#[test]
fn table_and_summary_show_state_outages_and_history() {
    for view in ["full", "summary"] {
        let out = emcy_decode()
            .args(["--view", view, TRACE])
            .output()
            .expect("runs");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("Node health"), "{view}: {text}");
        assert!(text.contains("lost 1x, silent at end"), "{view}: {text}");
        assert!(
            text.contains("0x8110* (partial; * before the trace)"),
            "{view}"
        );
        assert!(text.contains("2 nodes lost their heartbeat"), "{view}");
    }
}

#[test]
fn chart_shades_nmt_states_and_outages() {
    let out = emcy_decode()
        .args(["--format", "svg", TRACE])
        .output()
        .expect("runs");
    let svg = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        svg.matches("<rect class=\"out\" x=").count(),
        2,
        "two outages"
    );
    assert!(svg.contains("heartbeat lost from"));
    assert!(svg.contains("<rect class=\"n-operational\""));
    assert!(svg.contains("<rect class=\"n-stopped\""));
}

#[test]
fn check_reports_a_new_heartbeat_loss_as_a_regression() {
    // The baseline: the trace without the pulled cable and the silence.
    let healthy: String = fs::read_to_string(TRACE)
        .expect("fixture")
        .lines()
        .filter(|l| !l.contains(" 702#") && !l.contains(" 703#"))
        .map(|l| format!("{l}\n"))
        .collect();
    let rig = Rig::new(&healthy);
    let text = rig.baseline(&[]);
    assert!(!text.contains("heartbeat_lost"), "{text}");
    rig.trace_from(TRACE);
    let (code, lost) = rig.check("heartbeat_lost_new");
    assert_eq!(code, Some(1));
    let nodes: Vec<u64> = lost.iter().filter_map(|f| f["node"].as_u64()).collect();
    assert_eq!(nodes, [2, 3]);
    assert!(lost.iter().all(|f| f["severity"] == "regression"));
    // The baseline of this trace records it, and then nothing regresses.
    assert!(rig.baseline(&[]).contains("\"heartbeat_lost\": 1"));
    assert_eq!(rig.check("heartbeat_lost_new"), (Some(0), vec![]));
}

/// `trace` from stdin with a heartbeat timeout of 0.5 s: its ndjson
/// objects and stderr (the run must succeed).
fn with_half_second_timeout(trace: &str) -> (Vec<Value>, String) {
    let (out, err, code) = crate::support::run(
        &["--format", "ndjson", "--heartbeat-timeout", "0.5", "-"],
        trace.as_bytes(),
    );
    assert_eq!(code, 0, "{err}");
    let objects = out
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect();
    (objects, err)
}

#[test]
fn nodes_found_lost_at_one_frame_come_in_deadline_order() {
    // Timeout 0.5 s. Node 3 beats at 0.0 and 0.3 (deadline 0.8), node 4 at
    // 0.1 (deadline 0.6); the next frame, at 2.0, passes both: node 4 was
    // lost first. (An earlier schedule kept node 3 at its first deadline,
    // 0.5, and said node 3 first.)
    let trace = "(1700000000.000000) can0 703#05\n\
                 (1700000000.100000) can0 704#05\n\
                 (1700000000.300000) can0 703#05\n\
                 (1700000002.000000) can0 705#05\n";
    let (objects, _) = with_half_second_timeout(trace);
    let lost: Vec<(u64, String)> = objects
        .iter()
        .filter(|o| o["type"] == "heartbeat_lost")
        .map(|o| (o["node"].as_u64().unwrap_or(0), o["time_text"].to_string()))
        .collect();
    assert_eq!(
        lost,
        [
            (4, "\"2023-11-14T22:13:20.600000Z\"".to_string()),
            (3, "\"2023-11-14T22:13:20.800000Z\"".to_string()),
        ]
    );
}

#[test]
fn an_outage_ended_before_it_began_is_said_on_stderr() {
    // Timeout 0.5 s. An EMCY stamped a second ahead of the bus (a gateway
    // with its own clock) passes node 3's deadline, 0.6: lost there. Its
    // next heartbeat, at 0.2 by the bus's clock, ends the outage 0.4 s
    // before it began, which stderr says with the line.
    let trace = "(1700000000.000000) can0 703#05\n\
                 (1700000000.100000) can0 703#05\n\
                 (1700000001.150000) can0 085#1043090100000000\n\
                 (1700000000.200000) can0 703#05\n";
    let (objects, err) = with_half_second_timeout(trace);
    let outages = &node(&objects, 3)["heartbeat"]["outages"];
    assert_eq!(outages[0]["duration"], json!(-0.4), "{outages}");
    assert_eq!(
        err.lines()
            .filter(|l| l.contains("ends a heartbeat outage that began later"))
            .collect::<Vec<_>>(),
        [
            "<stdin>:4: node 3: heartbeat at 1700000000.200000 ends a heartbeat outage \
          that began later, at 1700000000.600000: the trace's clock went backwards (the \
          outage's duration is negative)"
        ],
        "{err}"
    );
}
