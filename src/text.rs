//! Text that comes from a trace, made safe to print.

use std::borrow::Cow;

/// A channel name as the trace wrote it, with control characters escaped: a
/// hostile trace must not put terminal control sequences on the screen
/// (`(1.0) \x1b]0;title\x07 081#...` is a valid candump log line).
pub fn printable(s: &str) -> Cow<'_, str> {
    if !s.chars().any(char::is_control) {
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
    }
}
