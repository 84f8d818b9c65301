//! Text from outside (a trace, a file name, a user's profile), made safe to
//! print on a terminal. Below every layer: it imports nothing of ours.

use std::borrow::Cow;

/// A channel name as the trace wrote it, with control characters escaped: a
/// hostile trace must not put terminal control sequences on the screen
/// (`(1.0) \x1b]0;title\x07 081#...` is a valid candump log line).
pub fn printable(s: &str) -> Cow<'_, str> {
    // Most text is clean: byte scans decide. C0 controls and DEL are single
    // bytes (a vectorised scan); C1 controls U+0080-U+009F are 0xC2
    // 0x80-0x9F (memchr to each 0xC2, its next byte checked). Taking every
    // 0xC2 as suspect sent each description with a `·` (0xC2 0xB7) to a
    // char-by-char check: 8% of a table run of a trace with 30% EMCY.
    let b = s.as_bytes();
    // A fold, not `any`: without the early exit the scan is vectorised.
    let control = b
        .iter()
        .fold(false, |found, &c| found | (c < 0x20) | (c == 0x7F))
        || memchr::memchr_iter(0xC2, b)
            .any(|i| b.get(i + 1).is_some_and(|n| (0x80..0xA0).contains(n)));
    if !control {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

/// Whether XML 1.0 can hold `c` at all, even as a character reference
/// (its `Char` production): not the C0 controls but tab, line feed and
/// carriage return, and not U+FFFE and U+FFFF (surrogates are no `char`).
/// An SVG or JUnit file with one of them is no XML: no viewer or CI opens
/// it. The XML outputs replace them with U+FFFD.
pub fn is_xml_char(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}' | '\u{10000}'..)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_holds_every_char_but_c0_controls_and_two_nonchars() {
        for c in [
            '\t',
            '\n',
            '\r',
            ' ',
            'a',
            '\u{7f}',
            '\u{85}',
            '\u{D7FF}',
            '\u{E000}',
            '\u{FFFD}',
            '\u{10000}',
            '\u{10FFFF}',
        ] {
            assert!(is_xml_char(c), "{c:?}");
        }
        for c in ['\0', '\u{1b}', '\u{1f}', '\u{FFFE}', '\u{FFFF}'] {
            assert!(!is_xml_char(c), "{c:?}");
        }
    }

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable("can\u{1b}]0"), "can\\u{1b}]0");
        assert_eq!(printable("can0"), "can0");
        assert_eq!(printable("a\u{85}b\u{7f}"), "a\\u{85}b\\u{7f}");
        assert_eq!(printable("Stöber · ±15 V"), "Stöber · ±15 V");
        assert!(matches!(printable("Temperature · drive"), Cow::Borrowed(_)));
        // U+009F, the last C1 control; U+00A0 is none.
        assert_eq!(printable("a\u{9f}\u{a0}"), "a\\u{9f}\u{a0}");
        assert_eq!(printable("\u{c2}"), "\u{c2}");
    }
}
