//! Differential test against the `candump-parse` crate: on every well-formed
//! candump log line that crate accepts, we read the same frame. (Where it is
//! wrong — `(1.5)` as 5 us, odd nibbles, `081#` vs `00000081#` — the unit tests
//! in src/trace/candump_log.rs pin our behaviour instead.) Our side is the
//! library's reader with the format forced to the candump log.

use std::panic;

use chumsky::Parser as _;
use emcy_decode::{CanFrame, Format, Record, TraceReader};
use proptest::prelude::*;

/// One line read as a candump log line: the frame, or `None` when the line
/// is not one.
fn parse(line: &str) -> Option<CanFrame> {
    let records: Vec<Record> = TraceReader::with_format(line.as_bytes(), Format::CandumpLog)
        .collect::<Result<_, _>>()
        .expect("reading a string cannot fail");
    assert_eq!(records.len(), 1, "one line, one record: {records:?}");
    match records.into_iter().next() {
        Some(Record::Frame(f)) => Some(f),
        _ => None,
    }
}

/// The subset of the log grammar candump-parse was written for: 6 fraction
/// digits, an identifier-like interface, 3 or 8 hex id digits, 0-8 data bytes.
fn well_formed_line() -> impl Strategy<Value = String> {
    let secs = 0u64..=9_999_999_999;
    let micros = 0u32..1_000_000;
    let iface = "[a-zA-Z_][a-zA-Z0-9_]{0,10}";
    let id = prop_oneof![
        (0u32..=0x7FF).prop_map(|i| format!("{i:03X}")),
        (0u32..=0x1FFF_FFFF).prop_map(|i| format!("{i:08X}")),
        (0u32..=0x1FFF_FFFF).prop_map(|i| format!("{i:08x}")),
    ];
    let data = prop::collection::vec(any::<u8>(), 0..=8);
    let lower = any::<bool>();
    (secs, micros, iface, id, data, lower).prop_map(|(s, us, iface, id, data, lower)| {
        let hex: String = data.iter().map(|b| format!("{b:02X}")).collect();
        let hex = if lower { hex.to_lowercase() } else { hex };
        format!("({s:010}.{us:06}) {iface} {id}#{hex}")
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn we_agree_with_candump_parse_where_it_accepts(line in well_formed_line()) {
        let theirs = panic::catch_unwind(|| candump_parse::parser().parse(line.as_str()));
        let Ok(Ok(theirs)) = theirs else {
            // It panicked or refused: nothing to compare on this line.
            return Ok(());
        };
        let Some(frame) = parse(&line) else {
            panic!("we rejected a well-formed line candump-parse accepts: {line}");
        };
        prop_assert_eq!(frame.id, theirs.id);
        prop_assert_eq!(frame.data.as_slice(), theirs.data.as_slice());
        prop_assert_eq!(frame.channel.as_bytes(), theirs.interface.as_bytes());
        let time = frame.time.expect("time decoded");
        prop_assert_eq!(time.secs(), theirs.timestamp.as_secs());
        let text = time.to_string();
        let micros: u32 = text.rsplit('.').next().unwrap().parse().unwrap();
        prop_assert_eq!(micros, theirs.timestamp.subsec_micros());
    }
}

#[test]
fn the_comparison_is_not_vacuous() {
    // candump-parse does accept the canonical line, so the property above compares.
    let line = "(1469439874.299654) can0 081#1043080100000000";
    let theirs = candump_parse::parser().parse(line).expect("accepted");
    assert_eq!(theirs.id, 0x81);
    let Some(ours) = parse(line) else {
        panic!("rejected");
    };
    assert_eq!(ours.data.as_slice(), theirs.data.as_slice());
}

#[test]
fn where_candump_parse_is_wrong_we_are_right() {
    // (1.5) is one and a half seconds, not 1 s + 5 us.
    let theirs = candump_parse::parser()
        .parse("(1.5) can0 081#00")
        .expect("accepted");
    assert_eq!(theirs.timestamp.subsec_micros(), 5);
    assert_eq!(
        parse("(1.5) can0 081#00")
            .unwrap()
            .time
            .unwrap()
            .to_string(),
        "1.5"
    );
    // An odd nibble is not a byte.
    assert!(
        candump_parse::parser()
            .parse("(1.000000) can0 081#123")
            .is_ok()
    );
    assert!(parse("(1.000000) can0 081#123").is_none());
    // 081# and 00000081# are different frames.
    assert!(!parse("(1.000000) can0 081#00").unwrap().extended);
    assert!(parse("(1.000000) can0 00000081#00").unwrap().extended);
    // Dotted data is read whole, not cut after the first byte.
    assert_eq!(parse("(1.000000) can0 123#11.22.33").unwrap().data.len(), 3);
    // An over-long id is a malformed line, not a panic.
    assert!(parse("(1.000000) can0 123456789ABCDEF#00").is_none());
}
