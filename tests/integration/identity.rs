//! Who is on the bus, through the command line, on the identity fixture
//! (scripts/make_identity_fixtures.py): each node's identity as it
//! answered reads, with the lines, and the Inventory table.

use serde_json::Value;

use crate::support::{emcy_decode, ndjson, run};

const TRACE: &str = "fixtures/identity.log";

fn node(objects: &[Value], n: u64) -> &Value {
    objects
        .iter()
        .find(|o| o["type"] == "node" && o["node"] == n)
        .unwrap_or_else(|| panic!("node {n}"))
}

#[test]
fn every_node_says_what_it_is_with_the_line_of_its_answer() {
    let objects = ndjson([TRACE]);
    let drive = &node(&objects, 5)["identity"];
    assert_eq!(drive["device_type"]["value"], "0x00020192");
    assert_eq!(drive["device_type"]["profile"], "CiA 402 drive");
    assert_eq!(drive["device_type"]["line"], 14);
    assert_eq!(drive["vendor_id"]["value"], "0x0000006A");
    assert_eq!(drive["vendor_id"]["name"], "Kollmorgen");
    assert_eq!(drive["product_code"]["value"], "0x00001234");
    assert_eq!(drive["revision"]["value"], "0x00010002");
    assert_eq!(drive["serial"]["value"], "0x00ABCDEF");
    assert_eq!(drive["serial"]["line"], 22);
    // Segmented, 15 bytes: the last segment's line.
    assert_eq!(drive["name"]["value"], "AKD Servo Drive");
    assert_eq!(drive["name"]["line"], 30);
    // Asked, never answered.
    assert!(drive["hardware_version"].is_null());
    let io = &node(&objects, 2)["identity"];
    assert_eq!(io["device_type"]["profile"], "CiA 401 I/O");
    assert!(io["vendor_id"]["name"].is_null(), "a vendor we do not know");
    // Four bytes, expedited.
    assert_eq!(io["software_version"]["value"], "1.02");
    assert!(io["name"].is_null());
}

#[test]
fn a_node_nobody_asked_has_no_identity() {
    let objects = ndjson(["fixtures/canopennode.log"]);
    assert!(node(&objects, 20)["identity"].is_null());
}

#[test]
fn a_write_says_nothing_of_who_the_node_is() {
    // The master writes 0x1018 sub 4 and the node confirms: no read.
    let trace = b"(1.000000) can0 605#23181004EFBEADDE\n\
                  (1.001000) can0 585#6018100400000000\n\
                  (1.002000) can0 085#1043080000000000\n";
    let (out, _, _) = run(&["-f", "ndjson", "-"], trace);
    let objects: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(node(&objects, 5)["identity"].is_null(), "{out}");
}

#[test]
fn the_inventory_table_lists_the_nodes_that_answered() {
    for view in [&["--view", "summary"][..], &[][..]] {
        let out = emcy_decode()
            .env_remove("NO_COLOR")
            .env_remove("COLUMNS")
            .args(view)
            .arg(TRACE)
            .output()
            .unwrap();
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.contains("\nInventory\n"), "{view:?}: {text}");
        assert!(
            text.contains("Kollmorgen (0x0000006A)") && text.contains("AKD Servo Drive"),
            "{text}"
        );
    }
    let out = emcy_decode()
        .arg("fixtures/canopennode.log")
        .output()
        .unwrap();
    assert!(!String::from_utf8(out.stdout).unwrap().contains("Inventory"));
}
