use super::*;
use proptest::prelude::*;

const HEADER: [&str; 7] = [
    "ASCII Trace IXXAT MiniMon V3  Version: 1.0.0.1271",
    "Date: 03.02.2026",
    "Start time: 09:12:00",
    "Stop time: 09:15:30",
    "Overruns: 0         ",
    "Baudrate: 250 kbit/s",
    "\"Time\";\"Identifier (hex)\";\"Format\";\"Flags\";\"Data (hex)\"",
];

fn parse(line: &str) -> Parsed<'_> {
    IxxatParser::new().parse(line.as_bytes(), &Interest::all())
}

fn frame(line: &str) -> Frame<'_> {
    match parse(line) {
        Parsed::Frame(f) => f,
        other => panic!("{line:?} -> {other:?}"),
    }
}

fn malformed(line: &str) -> String {
    match parse(line) {
        Parsed::Malformed(r) => r.into_owned(),
        other => panic!("{line:?} should be malformed, got {other:?}"),
    }
}

#[test]
fn header_lines_are_skipped_and_the_title_identifies_the_format() {
    let mut p = IxxatParser::new();
    assert!(!p.identified());
    for line in HEADER {
        assert_eq!(
            p.parse(line.as_bytes(), &Interest::all()),
            Parsed::Skipped,
            "{line}"
        );
        assert!(p.identified(), "{line}");
    }
    assert_eq!(p.context(), Some(1));
    assert_eq!(p.bit_rate(), Some(250_000));
    // Before the title, a `Key: value` line is nobody's header.
    assert!(malformed("Date: 03.02.2026").contains("quoted fields"));
    assert_eq!(parse(""), Parsed::Skipped);
    assert_eq!(parse("   "), Parsed::Skipped);
}

#[test]
fn data_rows() {
    let f = frame("\"00:02:20.66\";\"83\";\"Std\";\"\";\"00 00 00 01 20 00 00 00 \"");
    assert_eq!(
        (f.id, f.extended, f.kind, f.len),
        (0x83, false, FrameKind::Data, 8)
    );
    assert_eq!(f.data.as_slice(), [0, 0, 0, 1, 0x20, 0, 0, 0]);
    assert_eq!(f.time.map(|t| t.to_string()).as_deref(), Some("140.66"));
    assert_eq!(f.channel, b"1");
    let f = frame("\"00:00:01.5\";\"703\";\"Std\";\"\";\"7F \"");
    assert_eq!((f.id, f.len), (0x703, 1));
    assert_eq!(f.time.map(|t| t.to_string()).as_deref(), Some("1.5"));
    // No data: `""`.
    let f = frame("\"00:02:20.71\";\"83\";\"Std\";\"\";\"\"");
    assert_eq!((f.kind, f.len), (FrameKind::Data, 0));
    // Hours past a day and without a leading zero.
    let f = frame("\"27:00:00.00\";\"0\";\"Std\";\"\";\"01 00 \"");
    assert_eq!(f.time.map(|t| t.secs()), Some(27 * 3600));
}

#[test]
fn the_format_column_decides_extended_ids() {
    let f = frame("\"00:00:02.00\";\"18FF0103\";\"Ext\";\"\";\"11 22 \"");
    assert_eq!((f.id, f.extended), (0x18FF_0103, true));
    // A small id in an extended frame stays extended: never an EMCY.
    let f = frame("\"00:00:02.00\";\"81\";\"Ext\";\"\";\"11 22 \"");
    assert_eq!((f.id, f.extended), (0x81, true));
    assert!(malformed("\"00:00:02.00\";\"800\";\"Std\";\"\";\"\"").contains("over 7FF"));
    assert!(malformed("\"00:00:02.00\";\"20000000\";\"Ext\";\"\";\"\"").contains("over 1FFFFFFF"));
    assert!(malformed("\"00:00:02.00\";\"81\";\"Xtd\";\"\";\"\"").contains("neither Std nor Ext"));
}

#[test]
fn remote_requests() {
    let f = frame("\"00:02:30.72\";\"702\";\"Std\";\"Rtr \";\"Remote request  DLC = 1 \"");
    assert_eq!((f.id, f.kind, f.len), (0x702, FrameKind::Remote, 1));
    assert!(f.data.is_empty());
    assert!(
        malformed("\"00:02:30.72\";\"702\";\"Std\";\"Rtr \";\"01 \"").contains("Remote request")
    );
    assert!(
        malformed("\"00:02:30.72\";\"702\";\"Std\";\"Rtr \";\"Remote request  DLC = 9 \"")
            .contains("0-8")
    );
}

#[test]
fn malformed_rows_say_why() {
    let row = |time: &str, id: &str, flags: &str, data: &str| {
        malformed(&format!(
            "\"{time}\";\"{id}\";\"Std\";\"{flags}\";\"{data}\""
        ))
    };
    // Whole seconds are a time too.
    assert_eq!(
        frame("\"00:02:20\";\"83\";\"Std\";\"\";\"\"")
            .time
            .map(|t| t.secs()),
        Some(140)
    );
    assert!(row("2:20.66", "83", "", "").contains("H:MM:SS.ff"));
    assert!(row("00:62:20.66", "83", "", "").contains("below 60"));
    assert!(row("00:02:2x.66", "83", "", "").contains("H:MM:SS.ff"));
    assert!(row("00:02:20.66", "8G", "", "").contains("not hexadecimal"));
    assert!(row("00:02:20.66", "", "", "").contains("not hexadecimal"));
    assert!(row("00:02:20.66", "83", "Ovr", "").contains("unknown flag 'Ovr'"));
    assert!(row("00:02:20.66", "83", "", "0 1 ").contains("'0' is not two hex digits"));
    assert!(row("00:02:20.66", "83", "", &"00 ".repeat(9)).contains("more than 8"));
    assert!(malformed("\"00:02:20.66\";\"83\";\"Std\";\"\"").contains("5 fields"));
    assert!(malformed("\"00:02:20.66\";\"83\";\"Std\";\"\";\"00 \";").contains("after the data"));
    assert!(malformed("\"00:02:20.66\";83;\"Std\";\"\";\"00 \"").contains("field 2"));
    assert!(malformed("\"00:02:20.66").contains("closing quote"));
    // Other formats' lines are no IXXAT rows (detection relies on it).
    for line in [
        "(1469439874.299654) can0 081#1043080100000000",
        "  can0  081   [8]  10 43 08 01 00 00 00 00",
        "   1.000000 1  81  Rx   d 8 10 43 08 01 00 00 00 00",
        "      1      1059.900 DT 1      0300 Rx -  7    00 00 00 00 04 00 00",
    ] {
        assert!(matches!(parse(line), Parsed::Malformed(_)), "{line}");
    }
}

#[test]
fn unwanted_frames_are_validated_but_not_decoded() {
    let mut p = IxxatParser::new();
    let none = Interest::none();
    let Parsed::Frame(f) = p.parse(b"\"00:00:01.00\";\"181\";\"Std\";\"\";\"01 02 \"", &none)
    else {
        panic!("a frame");
    };
    assert_eq!((f.id, f.len, f.time), (0x181, 2, None));
    assert!(f.data.is_empty());
    assert!(matches!(
        p.parse(b"\"00:00:01.00\";\"181\";\"Std\";\"\";\"01 0Z \"", &none),
        Parsed::Malformed(_)
    ));
}

#[test]
fn fuzz_checks_hold_on_a_header_and_damaged_rows() {
    let mut text = HEADER.join("\r\n");
    text.push_str("\r\n\"00:00:01.00\";\"81\";\"Std\";\"\";\"10 43 \"\r\n\"0:0:0\";\";\"\r\n");
    fuzz_ixxat(text.as_bytes());
}

fn row_text(secs: u64, centis: u64, id: u32, extended: bool, kind: u8, data: &[u8]) -> String {
    let time = format!(
        "{:02}:{:02}:{:02}.{centis:02}",
        secs / 3600,
        secs / 60 % 60,
        secs % 60
    );
    let format = if extended { "Ext" } else { "Std" };
    let (flags, data) = match kind {
        0 => (
            String::new(),
            data.iter().map(|b| format!("{b:02X} ")).collect::<String>(),
        ),
        _ => (
            "Rtr ".to_string(),
            format!("Remote request  DLC = {} ", data.len()),
        ),
    };
    format!("\"{time}\";\"{id:X}\";\"{format}\";\"{flags}\";\"{data}\"")
}

proptest! {
    /// Any frame MiniMon can write reads back as itself: id, kind, length,
    /// data and time (seconds since the start, exactly).
    #[test]
    fn rows_read_back_as_the_frames_written(
        secs in 0u64..400_000,
        centis in 0u64..100,
        extended in any::<bool>(),
        sid in 0u32..=STANDARD_MAX,
        eid in 0u32..=EXTENDED_MAX,
        remote in any::<bool>(),
        data in prop::collection::vec(any::<u8>(), 0..=8),
    ) {
        let id = if extended { eid } else { sid };
        let line = row_text(secs, centis, id, extended, u8::from(remote), &data);
        let f = frame(&line);
        prop_assert_eq!((f.id, f.extended, usize::from(f.len)), (id, extended, data.len()));
        if remote {
            prop_assert_eq!(f.kind, FrameKind::Remote);
            prop_assert!(f.data.is_empty());
        } else {
            prop_assert_eq!(f.kind, FrameKind::Data);
            prop_assert_eq!(f.data.as_slice(), data.as_slice());
        }
        prop_assert_eq!(f.time, Some(Timestamp::from_parts(secs, centis, 2)));
    }

    /// Any line at all: no panic, and every frame is well formed.
    #[test]
    fn any_line_is_a_well_formed_frame_or_a_reason(line in "[\"0-9A-Fa-z:;. \\t]{0,80}") {
        fuzz_ixxat(line.as_bytes());
    }
}
