//! The bus under the CANopen story, through the command line, on the
//! bus-off fixture (scripts/make_bus_fixtures.py): error bursts, the
//! logging controller's bus-off, a node's bus-off inferred from its
//! silence, a heartbeat loss that stays one, `--fail-on bus-off` and
//! `bus-errors`, `check`'s `bus_off_new`, and the CSV rows.

use std::fs;

use serde_json::Value;

use crate::support::{Rig, emcy_decode, ndjson};

const TRACE: &str = "fixtures/bus-off.log";

fn of_type<'a>(objects: &'a [Value], t: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == t).collect()
}

#[test]
fn error_frames_make_three_bursts_with_their_kinds_and_counters() {
    let objects = ndjson([TRACE]);
    let bursts = of_type(&objects, "bus_error");
    assert_eq!(bursts.len(), 3);
    let first = bursts[0];
    assert_eq!(first["channel"], "can0");
    assert!(first["node"].is_null());
    assert_eq!(first["start_text"], "2023-11-14T22:13:28.000000Z");
    assert_eq!(first["end_text"], "2023-11-14T22:13:28.600000Z");
    assert_eq!(first["frames"], 13);
    assert_eq!(first["kinds"]["protocol_violation"], 12);
    assert_eq!(first["kinds"]["bus_error"], 12);
    assert_eq!(first["kinds"]["tx_passive"], 1);
    assert_eq!(first["tx_errors_max"], 128);
    // The lone no-ACK frame reports no counters: unknown, not zero.
    let lone = bursts[2];
    assert_eq!(lone["frames"], 1);
    assert!(lone["tx_errors_max"].is_null() && lone["rx_errors_max"].is_null());
    let input = of_type(&objects, "input")[0];
    let can0 = &input["bus_errors"][0];
    assert_eq!(can0["error_frames"], 20);
    assert_eq!(can0["bursts"], 3);
    assert_eq!(can0["bus_off_count"], 3);
}

#[test]
fn bus_offs_of_the_controller_and_of_nodes_name_their_evidence() {
    let objects = ndjson([TRACE]);
    let offs = of_type(&objects, "bus_off");
    let who: Vec<&Value> = offs.iter().map(|o| &o["node"]).collect();
    assert_eq!(who, [&Value::from(5), &Value::Null, &Value::from(6)]);
    let kinds = |o: &Value| -> Vec<String> {
        o["evidence"]
            .as_array()
            .map(|e| e.iter().map(|e| e["kind"].to_string()).collect())
            .unwrap_or_default()
    };
    // Node 5: last heard, the burst, its EMCY 0x8140.
    assert_eq!(
        kinds(offs[0]),
        ["\"last_seen\"", "\"bus_error\"", "\"emcy\""]
    );
    assert_eq!(offs[0]["evidence"][2]["code"], "0x8140");
    assert_eq!(offs[0]["end_text"], "2023-11-14T22:13:30.500000Z");
    // The controller: its bus-off frame to its restart.
    assert_eq!(
        kinds(offs[1]),
        ["\"bus_error\"", "\"bus_off_frame\"", "\"recovery_frame\""]
    );
    assert_eq!(offs[1]["start_text"], "2023-11-14T22:13:38.100000Z");
    assert_eq!(offs[1]["end_text"], "2023-11-14T22:13:38.400000Z");
    // Node 6: silent across the lone error frame, back with a boot-up.
    assert_eq!(
        kinds(offs[2]),
        ["\"last_seen\"", "\"bus_error\"", "\"boot_up\""]
    );
}

#[test]
fn a_silence_without_a_burst_stays_a_heartbeat_loss() {
    let objects = ndjson([TRACE]);
    let lost: Vec<&Value> = of_type(&objects, "heartbeat_lost")
        .into_iter()
        .filter(|o| o["node"] == 6)
        .collect();
    assert_eq!(lost.len(), 2, "node 6 lost twice");
    // Its first silence (14.0-16.0 s) had no error frame: no bus-off then.
    let offs = of_type(&objects, "bus_off");
    assert!(
        offs.iter()
            .all(|o| o["node"] != 6 || o["start_text"] != "2023-11-14T22:13:33.801000Z")
    );
}

#[test]
fn a_communication_emcy_names_the_burst_it_came_in() {
    let objects = ndjson([TRACE]);
    let emcys = of_type(&objects, "emcy");
    let by_code = |code: &str| emcys.iter().find(|o| o["code"] == code).copied();
    let recovered = by_code("0x8140").expect("0x8140");
    assert_eq!(recovered["bus_error_text"], "2023-11-14T22:13:28.000000Z");
    let overrun = by_code("0x8110").expect("0x8110");
    assert_eq!(overrun["bus_error_text"], "2023-11-14T22:13:38.000000Z");
    // Resets are no communication errors: no key.
    assert!(
        emcys
            .iter()
            .filter(|o| o["code"] == "0x0000")
            .all(|o| o.get("bus_error").is_none())
    );
}

#[test]
fn fail_on_bus_off_and_bus_errors() {
    for (when, trace, code, says) in [
        ("bus-off", TRACE, 1, "bus-off: 3 bus-offs"),
        (
            "bus-errors",
            TRACE,
            1,
            "bus-errors: 20 error frames in 3 bursts",
        ),
        ("bus-off,bus-errors", "fixtures/s300.log", 0, ""),
    ] {
        let out = emcy_decode()
            .args(["--fail-on", when, "--format", "ndjson", trace])
            .output()
            .expect("runs");
        assert_eq!(out.status.code(), Some(code), "{when} {trace}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(says), "{when}: {stderr}");
    }
}

#[test]
fn check_reports_a_new_bus_off_as_a_regression() {
    // The baseline: the trace before the first error frame.
    let healthy: String = fs::read_to_string(TRACE)
        .expect("fixture")
        .lines()
        .take_while(|l| !l.contains(" 2000"))
        .map(|l| format!("{l}\n"))
        .collect();
    let rig = Rig::new(&healthy);
    let text = rig.baseline(&[]);
    assert!(!text.contains("bus_off"), "{text}");
    rig.trace_from(TRACE);
    let (code, found) = rig.check("bus_off_new");
    assert_eq!(code, Some(1));
    let nodes: Vec<&Value> = found.iter().map(|f| &f["node"]).collect();
    assert_eq!(nodes, [&Value::Null, &Value::from(5), &Value::from(6)]);
    assert!(found.iter().all(|f| f["severity"] == "regression"));
    // Recorded, then nothing regresses.
    let text = rig.baseline(&[]);
    assert!(text.contains("\"bus_off\": 1"), "{text}");
    assert_eq!(rig.check("bus_off_new"), (Some(0), vec![]));
}

#[test]
fn csv_has_a_row_per_burst_and_bus_off() {
    let out = emcy_decode()
        .args(["--format", "csv", TRACE])
        .output()
        .expect("runs");
    let mut reader = ::csv::Reader::from_reader(out.stdout.as_slice());
    let rows: Vec<::csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
    let of = |t: &str| rows.iter().filter(|r| &r[0] == t).count();
    assert_eq!((of("bus_error"), of("bus_off")), (3, 3));
    let burst = rows.iter().find(|r| &r[0] == "bus_error").expect("burst");
    // No node for a burst; the details are its JSON object.
    assert_eq!(&burst[6], "");
    let details: Value = serde_json::from_str(&burst[21]).expect("json details");
    assert_eq!(details["frames"], 13);
}

#[test]
fn the_table_lists_bursts_and_bus_offs_and_ends_with_a_bus_errors_table() {
    let out = emcy_decode().arg(TRACE).output().expect("runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("  errors  "), "{text}");
    assert!(text.contains("node 5 bus-off for 2.5 s"), "{text}");
    assert!(text.contains("EMCY 0x8140 at"), "{text}");
    let table = text
        .split("Bus errors\n")
        .nth(1)
        .expect("a Bus errors table");
    let row = table.lines().nth(1).expect("a row");
    assert!(row.starts_with("can0               20       3"), "{row}");
    assert!(row.ends_with("node 5, controller, node 6"), "{row}");
    assert!(
        text.contains("20 error frames in 3 bursts, 3 bus-offs"),
        "{text}"
    );
    // The summary view keeps the table and the line, not the events.
    let out = emcy_decode()
        .args(["--view", "summary", TRACE])
        .output()
        .expect("runs");
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("Bus errors\n") && !summary.contains("  errors  "));
}

#[test]
fn lss_says_who_became_node_5_and_when() {
    let objects = ndjson(["fixtures/lss-time.log"]);
    let lss = of_type(&objects, "lss");
    assert_eq!(lss.len(), 28);
    let configured: Vec<&&Value> = lss
        .iter()
        .filter(|o| o["service"] == "configure_node_id" && o["from"] == "node")
        .collect();
    assert_eq!(configured.len(), 3);
    let five = configured[0];
    assert_eq!(five["node"], 5);
    assert_eq!(five["result"], "ok");
    assert_eq!(five["time_text"], "2023-11-14T22:13:21.110000Z");
    assert_eq!(five["identity"]["serial"], 0xBEEF);
    assert_eq!(five["identity"]["vendor_id"], 0xA5);
    assert_eq!(configured[1]["node"], 200);
    assert_eq!(configured[1]["result"], "failed: node-id out of range");
    assert_eq!(configured[2]["identity"]["serial"], 0xBEF0);
    let services: std::collections::BTreeSet<&str> =
        lss.iter().filter_map(|o| o["service"].as_str()).collect();
    for s in [
        "switch_state_global",
        "switch_state_selective",
        "configure_bit_timing",
        "store_configuration",
        "activate_bit_timing",
        "inquire",
        "identify_non_configured_slave",
    ] {
        assert!(services.contains(s), "{s}: {services:?}");
    }
}

#[test]
fn time_stamps_give_the_producer_clock_against_the_trace() {
    let objects = ndjson(["fixtures/lss-time.log"]);
    let input = of_type(&objects, "input")[0];
    let t = &input["time_producer"];
    assert_eq!(t["frames"], 6);
    assert_eq!(t["first_text"], "2023-11-14T22:13:21.500Z");
    assert_eq!(t["first_offset"].as_f64(), Some(1.5));
    assert_eq!(t["last_offset"].as_f64(), Some(1.51));
    // No event per stamp.
    assert!(objects.iter().all(|o| o["type"] != "time"));
}
