//! candump text pasted into an issue thread or a document: indented lines,
//! the command line above the output, `...` where lines were cut, blank
//! lines and `#`/`//` notes are skipped; notes after a complete frame are
//! counted as `annotated` and their frames read. The screen paste (`-td
//! -a`) and the log paste of one scenario decode to the same events.

use std::path::Path;

use serde_json::Value;

use crate::support::{self, PLACE, TIMES, emcy_decode};

fn ndjson(path: &str) -> Vec<Value> {
    support::ndjson([Path::new(path)])
}

fn input(objects: &[Value]) -> &Value {
    objects
        .iter()
        .find(|o| o["type"] == "input")
        .expect("an input object")
}

#[test]
fn pasted_screen_and_log_output_read_every_frame_and_count_the_notes() {
    let screen = ndjson("fixtures/pasted.txt");
    let log = ndjson("fixtures/pasted.log");
    let n = |o: &Value, k: &str| o[k].as_u64();
    for (objects, format, skipped, annotated) in
        [(&screen, "candump-screen", 7, 6), (&log, "candump", 2, 4)]
    {
        let i = input(objects);
        assert_eq!(i["format"], format);
        assert_eq!(n(i, "frames"), Some(16), "{format}");
        assert_eq!(n(i, "malformed"), Some(0), "{format}");
        assert_eq!(n(i, "skipped"), Some(skipped), "{format}");
        assert_eq!(n(i, "annotated"), Some(annotated), "{format}");
        assert_eq!(n(i, "boot"), Some(1), "{format}");
        assert_eq!(n(i, "emcy"), Some(2), "{format}");
        // The SDO abort sits on an annotated line.
        let aborts: Vec<&Value> = objects
            .iter()
            .filter(|o| o["type"] == "sdo_abort")
            .collect();
        assert_eq!(aborts.len(), 1, "{format}");
        assert_eq!(aborts[0]["abort_code"], "0x06020000", "{format}");
    }
    let drop = [&PLACE[..], &TIMES[..]].concat();
    assert_eq!(
        support::semantic(&screen, &drop),
        support::semantic(&log, &drop)
    );
}

#[test]
fn inputs_without_notes_keep_their_json_object_and_table_as_they_were() {
    let objects = ndjson("fixtures/s300.txt");
    assert!(input(&objects).get("annotated").is_none());
    let out = emcy_decode().arg("fixtures/s300.txt").output().unwrap();
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(!table.contains("ANNOTATED") && !table.contains("annotated"));
    let out = emcy_decode().arg("fixtures/pasted.txt").output().unwrap();
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(table.contains("ANNOTATED"), "{table}");
    assert!(table.contains("16 frames (6 annotated)"), "{table}");
}

#[test]
fn a_cut_in_a_td_paste_is_told_where_its_deltas_go_missing() {
    let out = emcy_decode().arg("fixtures/pasted.txt").output().unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains(
            "fixtures/pasted.txt:13: lines were left out here: their -td deltas are missing"
        ),
        "{stderr}"
    );
    // Absolute times lose nothing at a cut.
    let out = emcy_decode().arg("fixtures/pasted.log").output().unwrap();
    assert!(!String::from_utf8(out.stderr).unwrap().contains("left out"));
}
