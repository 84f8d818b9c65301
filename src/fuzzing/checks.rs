//! What every output of a fuzz run must hold, shared by the targets that
//! render: events and nodes well-formed in NDJSON, no control characters
//! on a terminal.

use serde_json::Value;

pub(super) fn ndjson_values(out: &[u8]) -> Vec<Value> {
    out.split(|b| *b == b'\n')
        .filter(|l| !l.is_empty())
        .map(|l| {
            serde_json::from_slice(l).unwrap_or_else(|e| {
                panic!(
                    "ndjson line does not parse ({e}): {}",
                    String::from_utf8_lossy(l)
                )
            })
        })
        .collect()
}

pub(super) fn codes(v: &Value) -> Vec<String> {
    v.as_array()
        .expect("an array of codes")
        .iter()
        .map(|c| c.as_str().expect("a code string").to_string())
        .collect()
}

/// An EMCY event agrees with the state machine's rules. `plain`: decoded
/// without error status bits (a status-bit reset may be an information
/// report that changes nothing, whatever its register).
pub(super) fn check_emcy_event(v: &Value, plain: bool) {
    let code = v["code"].as_str().expect("code");
    let transition = v["transition"].as_u64();
    let state = v["state"].as_str().expect("state");
    let active = codes(&v["active"]);
    let cleared = codes(&v["cleared"]);
    let data = v["data"].as_str().expect("data");
    assert!(
        (6..=16).contains(&data.len()) && data.len().is_multiple_of(2),
        "EMCY data has 3 to 8 bytes: {v}"
    );
    assert!(
        has_unique(&active),
        "an active code is listed once: {active:?}"
    );
    if code != "0x0000" {
        assert!(matches!(transition, Some(1 | 3)), "raise: {v}");
        assert_eq!(state, "error_occurred");
        assert!(active.iter().any(|a| a == code), "raised code active: {v}");
        assert!(cleared.is_empty(), "a raise clears nothing: {v}");
    } else {
        assert!(matches!(transition, None | Some(2 | 4)), "reset: {v}");
        if plain && v["register"] == 0 {
            assert_eq!(state, "error_free", "{v}");
            assert!(active.is_empty(), "full reset leaves nothing active: {v}");
        } else if plain {
            assert_eq!(state, "error_occurred", "{v}");
        }
    }
    for c in &cleared {
        assert!(
            !active.iter().any(|a| a == c),
            "cleared and still active: {v}"
        );
    }
    if state == "error_free" {
        assert!(active.is_empty(), "error-free with active errors: {v}");
    }
}

/// A node's error list: each error ends after it starts (in line order),
/// the still-active ones are exactly the node's active codes.
pub(super) fn check_node(v: &Value) {
    let active = codes(&v["active"]);
    let errors = v["errors"].as_array().expect("errors");
    let mut open = Vec::new();
    for e in errors {
        let start = e["start_line"].as_u64().expect("start_line");
        match e["end_line"].as_u64() {
            Some(end) => {
                assert!(
                    end >= start,
                    "error ends at line {end} before it starts at {start}"
                );
                assert!(!e["cleared_by"].is_null(), "a closed error says why");
            }
            None => {
                assert!(e["end_line"].is_null());
                assert!(e["cleared_by"].is_null(), "an open error is not cleared");
                open.push(e["code"].as_str().expect("code").to_string());
            }
        }
    }
    assert_eq!(
        open, active,
        "open errors = active codes, in raise order: {v}"
    );
    if v["state"] == "error_free" {
        assert!(active.is_empty(), "error-free node with active errors: {v}");
    }
}

pub(super) fn has_unique(items: &[String]) -> bool {
    items
        .iter()
        .enumerate()
        .all(|(i, a)| !items.iter().skip(i + 1).any(|b| a == b))
}

/// What goes to a terminal must be UTF-8 with no control character but the
/// newline: a trace must not be able to send escape sequences.
pub(super) fn no_control_characters(what: &str, bytes: &[u8]) {
    let text = std::str::from_utf8(bytes).unwrap_or_else(|e| panic!("{what} is not UTF-8: {e}"));
    if let Some(c) = text.chars().find(|&c| c.is_control() && c != '\n') {
        panic!("{what} holds control character {c:?}");
    }
}
