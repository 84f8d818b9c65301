//! Property tests for the readers: random frames, rendered in each format with
//! random valid variations (padding, case, separators, fraction digits, -x
//! columns, ASC base dec...), read back through format detection
//! (`emcy_decode::TraceReader`), must come back as the same frames.

use emcy_decode::FrameKind;
use proptest::prelude::*;

use crate::support::frames::*;
use crate::support::read_last;

fn check(line: &str, f: &TestFrame, with_time: bool) -> Result<(), TestCaseError> {
    check_lines(&[line.to_string()], f, with_time, false)
}

fn check_lines(
    lines: &[String],
    f: &TestFrame,
    with_time: bool,
    asc: bool,
) -> Result<(), TestCaseError> {
    let (got, _) = read_last(lines)?;
    let line = lines.last().expect("at least one line").as_str();
    prop_assert_eq!(got.kind, f.kind, "{}", line);
    if asc && f.kind == FrameKind::Error {
        // ASC error frames carry no id.
        return Ok(());
    }
    prop_assert_eq!(got.id, f.id, "{}", line);
    prop_assert_eq!(got.extended, f.extended, "{}", line);
    if !asc {
        prop_assert_eq!(&got.channel, &f.channel, "{}", line);
    }
    if f.kind != FrameKind::Remote {
        // An FD frame is padded up to the next valid FD length.
        let n = if f.kind == FrameKind::Fd && asc {
            got.data.len()
        } else {
            f.data.len()
        };
        prop_assert_eq!(
            &got.data[..f.data.len().min(n)],
            f.data.as_slice(),
            "{}",
            line
        );
        prop_assert_eq!(got.data.len(), n, "{}", line);
    }
    if with_time {
        prop_assert_eq!(got.time, Some(f.time()), "{}", line);
    } else {
        prop_assert_eq!(got.time, None, "{}", line);
    }
    Ok(())
}

/// A note someone pasted after a frame: any printable text that does not
/// start like more of the frame (a data byte, an ASCII column, candump's
/// `T`/`R` direction flag).
const NOTE: &str = "[<>/#=!*~(\\[-][ -~]{0,30}";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn candump_log_roundtrip(f in frame(), style in log_style()) {
        check(&render_log(&f, &style), &f, true)?;
    }

    #[test]
    fn candump_screen_roundtrip(f in frame(), style in screen_style()) {
        check(&render_screen(&f, &style), &f, style.time)?;
    }

    /// A pasted line: indented, with a note after the complete frame
    /// (`< response`, `// boot`), reads as the same frame.
    #[test]
    fn candump_log_with_a_note_roundtrip(
        f in frame(),
        style in log_style(),
        indent in "[ \t]{0,4}",
        gap in "[ \t]{1,3}",
        note in NOTE,
    ) {
        check(&format!("{indent}{}{gap}{note}", render_log(&f, &style)), &f, true)?;
    }

    #[test]
    fn candump_screen_with_a_note_roundtrip(
        f in frame(),
        style in screen_style(),
        indent in "[ \t]{0,4}",
        gap in "[ \t]{1,3}",
        note in NOTE,
    ) {
        check(&format!("{indent}{}{gap}{note}", render_screen(&f, &style)), &f, style.time)?;
    }

    #[test]
    fn asc_roundtrip(f in frame(), style in asc_style()) {
        check_lines(&render_asc(&f, &style), &f, true, true)?;
    }
}
