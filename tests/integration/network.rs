//! Real CANopen networks' NMT traffic, on the fixtures of
//! `scripts/make_network_fixtures.py`: a node exists when it speaks (a
//! reset scan of absent ids makes none), a boot-up enters pre-operational,
//! a command is answered after its grace, node guarding is supervised like
//! heartbeats, a heartbeat period off its configuration is said.

use serde_json::Value;

use crate::support::{emcy_decode, ndjson, run};

const RESET_SCAN: &str = "fixtures/network-reset-scan.log";
const GUARDING: &str = "fixtures/network-guarding.log";
const GRACE: &str = "fixtures/network-nmt-grace.log";
const DRIFT: &str = "fixtures/network-drift.log";

fn of_type<'a>(objects: &'a [Value], t: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == t).collect()
}

fn node(objects: &[Value], n: u64) -> &Value {
    objects
        .iter()
        .find(|o| o["type"] == "node" && o["node"] == n)
        .unwrap_or_else(|| panic!("no node {n}"))
}

/// Node `n`'s NMT events as (state, via).
fn nmt_story(objects: &[Value], n: u64) -> Vec<(String, String)> {
    of_type(objects, "nmt")
        .into_iter()
        .filter(|o| o["node"] == n)
        .map(|o| {
            (
                o["state"].as_str().unwrap_or_default().to_string(),
                o["via"].as_str().unwrap_or_default().to_string(),
            )
        })
        .collect()
}

fn pair(s: &str, v: &str) -> (String, String) {
    (s.to_string(), v.to_string())
}

fn stderr_of(args: &[&str]) -> String {
    let out = emcy_decode().args(args).output().expect("runs");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn stdout_of(args: &[&str]) -> String {
    let out = emcy_decode().args(args).output().expect("runs");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn a_reset_scan_of_absent_ids_makes_no_nodes() {
    let objects = ndjson([RESET_SCAN]);
    let nodes: Vec<u64> = of_type(&objects, "node")
        .iter()
        .filter_map(|o| o["node"].as_u64())
        .collect();
    assert_eq!(nodes, [3, 17, 42], "only the ids that spoke");
    // No event for an id that never spoke.
    for o in objects.iter().filter(|o| o["node"].is_u64()) {
        assert!(
            [3, 17, 42].contains(&o["node"].as_u64().unwrap_or(0)),
            "{o}"
        );
    }
    let input = of_type(&objects, "input")[0];
    assert_eq!(
        input["nmt_unanswered"],
        serde_json::json!([{"request": "reset_node", "sent": 248, "ids": 124}])
    );
    // Each node was reset before it first spoke: its story starts with its
    // boot-up, in pre-operational, then the start to all and its answer.
    for n in [3, 17, 42] {
        assert_eq!(
            nmt_story(&objects, n),
            [
                pair("pre_operational", "boot_up"),
                pair("operational", "command"),
                pair("operational", "heartbeat"),
            ],
            "node {n}"
        );
        assert_eq!(node(&objects, n)["nmt_commanded"], Value::Null);
    }
    let stderr = stderr_of(&[RESET_SCAN]);
    assert_eq!(
        stderr,
        "fixtures/network-reset-scan.log:315: NMT reset node sent 248 times to 124 ids that \
         never answered (the first at line 1)\n"
    );
    let summary = stdout_of(&["--view", "summary", RESET_SCAN]);
    assert!(
        summary
            .contains("unanswered: NMT reset node sent 248 times to 124 ids that never answered"),
        "{summary}"
    );
    assert!(!summary.contains("initialising"), "{summary}");
}

#[test]
fn an_id_that_speaks_after_being_addressed_becomes_a_node_then() {
    // Id 9 is reset and asked for guarding before it speaks; a consumer
    // heartbeat time (0x1016 of node 1 naming it, 250 ms) is set too. Its
    // first frame is then a guarding reply (the request waits for it) and
    // its timeout the consumer time. Id 8 is only reset, never speaks.
    let trace = "\
(1.000000) can0 000#8109
(1.001000) can0 000#8108
(1.010000) can0 601#23161001FA000900
(1.011000) can0 581#6016100100000000
(1.020000) can0 709#00
(1.100000) can0 709#R
(1.101000) can0 709#7F
(1.200000) can0 709#R
(1.201000) can0 709#FF
";
    let (out, err, code) = run(&["--format", "ndjson", "-"], trace.as_bytes());
    assert_eq!(code, 0, "{err}");
    let objects: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    let nodes: Vec<u64> = of_type(&objects, "node")
        .iter()
        .filter_map(|o| o["node"].as_u64())
        .collect();
    assert_eq!(nodes, [1, 9]);
    let n9 = node(&objects, 9);
    assert_eq!(n9["heartbeat"]["via"], "guarding");
    // A consumer heartbeat time does not apply to a guarded node, and two
    // replies teach no period: no timeout.
    assert_eq!(n9["heartbeat"]["timeout_source"], Value::Null);
    assert_eq!(n9["heartbeat"]["guarding"]["toggle_errors"], 0);
    assert_eq!(
        nmt_story(&objects, 9),
        [pair("pre_operational", "boot_up")],
        "the replies say pre-operational, its state since the boot-up"
    );
    assert!(
        err.contains("NMT reset node sent once to 1 id that never answered"),
        "{err}"
    );
    assert!(!err.contains("node 9"), "{err}");
}

#[test]
fn a_consumer_time_for_a_producer_not_heard_yet_waits_for_it() {
    let trace = "\
(1.010000) can0 601#23161001FA000900
(1.011000) can0 581#6016100100000000
(1.020000) can0 709#7F
(1.120000) can0 709#7F
(1.500000) can0 701#7F
";
    let (out, err, code) = run(&["--format", "ndjson", "-"], trace.as_bytes());
    assert_eq!(code, 0, "{err}");
    let objects: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    let n9 = node(&objects, 9);
    assert_eq!(n9["heartbeat"]["timeout_source"], "consumer");
    assert_eq!(n9["heartbeat"]["timeout"], 0.25);
    assert_eq!(of_type(&objects, "heartbeat_lost")[0]["via"], "heartbeat");
}

#[test]
fn node_guarding_is_supervised_by_its_life_time() {
    let objects = ndjson([GUARDING]);
    let n10 = node(&objects, 10);
    let hb = &n10["heartbeat"];
    assert_eq!(hb["via"], "guarding");
    assert_eq!(hb["configured_period"], 0.1);
    assert_eq!(hb["timeout"], 0.3);
    assert_eq!(hb["timeout_source"], "life_time");
    assert_eq!(hb["lost"], 1);
    let g = &hb["guarding"];
    assert_eq!(g["life_time_factor"], 3);
    assert_eq!(g["requests"], 40);
    assert_eq!(g["replies"], 33);
    assert_eq!(g["unanswered"], 7, "one alone, six in the silence");
    assert_eq!(g["toggle_errors"], 1);
    let lost = of_type(&objects, "heartbeat_lost");
    assert_eq!(lost.len(), 1);
    assert_eq!(lost[0]["via"], "guarding");
    assert_eq!(lost[0]["timeout_source"], "life_time");
    // Found at the master's request after the deadline, not at the reply.
    assert_eq!(lost[0]["line"], 52);
    let back = of_type(&objects, "heartbeat_back");
    assert_eq!(back[0]["via"], "guarding");
    assert_eq!(
        nmt_story(&objects, 10),
        [
            pair("pre_operational", "boot_up"),
            pair("operational", "command"),
            pair("operational", "guarding"),
        ]
    );
    let input = of_type(&objects, "input")[0];
    assert_eq!(
        input["nmt_unanswered"],
        serde_json::json!([{"request": "guard_request", "sent": 3, "ids": 1}])
    );
    let stderr = stderr_of(&[GUARDING]);
    for said in [
        "network-guarding.log:30: node 10: node guarding: no reply to the guard request at line 28",
        "network-guarding.log:38: node 10: node guarding: toggle bit error (the reply has 0, expected 1)",
        "network-guarding.log:50: node 10: node guarding: no reply to the guard request at line 49",
        "network-guarding.log:82: node guarding request sent 3 times to 1 id that never answered \
         (the first at line 27)",
    ] {
        assert!(stderr.contains(said), "{said}\n{stderr}");
    }
    let summary = stdout_of(&["--view", "summary", GUARDING]);
    assert!(
        summary.contains(
            "lost 1x, 7 unanswered, 1 toggle error, guarding 100 ms x 3, period 100 ms, \
             timeout 300 ms (life_time)"
        ),
        "{summary}"
    );
    let out = emcy_decode()
        .args(["--fail-on", "lost", GUARDING])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1), "a guarding outage is lost");
}

#[test]
fn a_heartbeat_queued_before_a_command_is_not_its_answer() {
    let objects = ndjson([GRACE]);
    // Node 5: its heartbeat 3 ms after the start still says
    // pre-operational; no warning, no flicker, one change when it
    // confirms. The stop likewise; the reset is answered by the boot-up.
    assert_eq!(
        nmt_story(&objects, 5),
        [
            pair("pre_operational", "boot_up"),
            pair("operational", "command"),
            pair("operational", "heartbeat"),
            pair("stopped", "command"),
            pair("stopped", "heartbeat"),
            pair("initialising", "command"),
            pair("pre_operational", "boot_up"),
        ]
    );
    // Node 6 still says pre-operational 103 ms after the start: ignored.
    assert_eq!(
        nmt_story(&objects, 6),
        [
            pair("pre_operational", "boot_up"),
            pair("operational", "command"),
        ]
    );
    assert_eq!(node(&objects, 6)["nmt_state"], "pre_operational");
    assert_eq!(node(&objects, 6)["nmt_commanded"], Value::Null, "answered");
    let stderr = stderr_of(&[GRACE]);
    assert_eq!(
        stderr,
        "fixtures/network-nmt-grace.log:16: node 6: ignored the NMT command start (it reports \
         pre_operational, not operational)\n"
    );
}

#[test]
fn a_heartbeat_period_off_its_configuration_is_said() {
    let objects = ndjson([DRIFT]);
    let n7 = &node(&objects, 7)["heartbeat"];
    assert_eq!(n7["period"], 1.44);
    assert_eq!(n7["configured_period"], 1.4);
    assert_eq!(n7["drifts"], true);
    let n8 = &node(&objects, 8)["heartbeat"];
    assert_eq!(n8["period"], 1.405);
    assert_eq!(n8["drifts"], false);
    let summary = stdout_of(&["--view", "summary", DRIFT]);
    assert!(
        summary.contains("period 1.44 s (configured 1.4 s: drifts), timeout 2.1 s (producer)"),
        "{summary}"
    );
    assert!(
        summary.contains("period 1.405 s, timeout 2.1 s (producer)"),
        "{summary}"
    );
}
