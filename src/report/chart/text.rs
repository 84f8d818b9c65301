//! Text and numbers as the chart writes them: escaping of trace-controlled
//! text for XML and HTML, coordinates with at most one decimal, and the
//! small formatting helpers of labels and tooltips. Golden tests compare
//! bytes, so every number the chart prints goes through here.

use std::borrow::Cow;
use std::fmt;

use crate::text::is_xml_char;

/// Text from a trace or a user's profile (channel and file names, error
/// descriptions) made safe for XML and HTML: markup characters become
/// entities, control characters (not allowed in XML 1.0 at all, even as
/// references) become visible escapes, and the other characters XML cannot
/// hold (U+FFFE, U+FFFF) U+FFFD, as in the JUnit report. Line breaks and
/// tabs stay (tooltips are multi-line).
pub(in crate::report) fn esc(s: &str) -> Cow<'_, str> {
    let special =
        |c: char| matches!(c, '&' | '<' | '>' | '"' | '\'') || is_bad_control(c) || !is_xml_char(c);
    if !s.chars().any(special) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 16);
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c if is_bad_control(c) => out.extend(c.escape_default()),
            c if !is_xml_char(c) => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

fn is_bad_control(c: char) -> bool {
    c.is_control() && c != '\n' && c != '\t'
}

/// A coordinate with at most one decimal, without a trailing `.0`: small
/// files and the same bytes on every platform.
pub(in crate::report) struct N(pub(in crate::report) f64);

impl fmt::Display for N {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let tenths = if self.0.is_finite() {
            (self.0 * 10.0).round() as i64
        } else {
            0
        };
        let sign = if tenths < 0 { "-" } else { "" };
        let a = tenths.unsigned_abs();
        match a % 10 {
            0 => write!(f, "{sign}{}", a / 10),
            d => write!(f, "{sign}{}.{d}", a / 10),
        }
    }
}

/// At most `n` characters, with an ellipsis when cut.
pub(super) fn clip(s: &str, n: usize) -> Cow<'_, str> {
    if s.chars().count() <= n {
        return Cow::Borrowed(s);
    }
    let mut t: String = s.chars().take(n.saturating_sub(1)).collect();
    t.push('…');
    Cow::Owned(t)
}

/// A positive number with three significant digits: `0.00271`, `12.3`, `4560`.
pub(super) fn short_number(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return "0".to_string();
    }
    let mag = v.log10().floor() as i32;
    let d = (2 - mag).max(0) as usize;
    format!("{v:.d$}")
}

pub(super) fn plural(n: u64) -> &'static str {
    if n == 1 { "" } else { "s" }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_escapes() {
        assert_eq!(N(170.0).to_string(), "170");
        assert_eq!(N(387.74).to_string(), "387.7");
        assert_eq!(N(-0.04).to_string(), "0");
        assert_eq!(N(-2.55).to_string(), "-2.6");
        assert_eq!(N(f64::NAN).to_string(), "0");
        assert_eq!(esc("can0"), "can0");
        assert_eq!(esc("a<b>&\"'"), "a&lt;b&gt;&amp;&quot;&#39;");
        assert_eq!(esc("x\u{1b}y\nz"), "x\\u{1b}y\nz");
        assert_eq!(esc("a\u{FFFE}b\u{FFFF}\r"), "a\u{FFFD}b\u{FFFD}\\r");
        assert_eq!(clip("abcdef", 4), "abc…");
    }
}
