//! Text from outside (a trace, a file name, a user's profile), made safe to
//! print on a terminal. Below every layer: it imports nothing of ours.

use std::borrow::Cow;

/// A channel name as the trace wrote it, with control characters escaped: a
/// hostile trace must not put terminal control sequences on the screen
/// (`(1.0) \x1b]0;title\x07 081#...` is a valid candump log line).
pub fn printable(s: &str) -> Cow<'_, str> {
    // Most text is clean: a byte scan first (C0 controls and DEL are single
    // bytes, C1 controls U+0080-U+009F start with 0xC2), the char check
    // only where one of those bytes occurs.
    let suspect = s.bytes().any(|b| b < 0x20 || b == 0x7F || b == 0xC2);
    if !suspect || !s.chars().any(char::is_control) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable("can\u{1b}]0"), "can\\u{1b}]0");
        assert_eq!(printable("can0"), "can0");
        assert_eq!(printable("a\u{85}b\u{7f}"), "a\\u{85}b\\u{7f}");
        assert_eq!(printable("Stöber · ±15 V"), "Stöber · ±15 V");
    }
}
