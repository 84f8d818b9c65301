//! Small helpers the text formats share to split a line into tokens.

/// A token quoted in a reason (TRC, BUSMASTER): at most 40 characters,
/// invalid UTF-8 replaced and control characters shown as `?`, so a hostile
/// trace cannot put control sequences on the terminal.
pub fn show_token(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(token);
    let mut out: String = text.chars().take(40).collect();
    if text.chars().count() > 40 {
        out.push('…');
    }
    out.chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect()
}

/// Splits off leading spaces and tabs.
#[inline]
pub fn trim_start(s: &[u8]) -> &[u8] {
    let n = s.iter().take_while(|b| **b == b' ' || **b == b'\t').count();
    &s[n..]
}

/// Splits off trailing spaces and tabs.
#[inline]
pub fn trim_end(s: &[u8]) -> &[u8] {
    let n = s
        .iter()
        .rev()
        .take_while(|b| **b == b' ' || **b == b'\t')
        .count();
    &s[..s.len() - n]
}

/// Splits `s` at the first space or tab: (token, rest starting at the blank).
#[inline]
pub fn split_token(s: &[u8]) -> (&[u8], &[u8]) {
    let end = s
        .iter()
        .position(|b| *b == b' ' || *b == b'\t')
        .unwrap_or(s.len());
    s.split_at(end)
}

/// True for lines that carry nothing (only blanks).
#[inline]
pub fn is_blank(s: &[u8]) -> bool {
    s.iter().all(|b| *b == b' ' || *b == b'\t')
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::HexBytes;
    #[test]
    fn tokenizing() {
        assert_eq!(trim_start(b" \t x "), b"x ");
        assert_eq!(trim_end(b" x \t"), b" x");
        assert_eq!(split_token(b"ab cd"), (&b"ab"[..], &b" cd"[..]));
        assert!(is_blank(b" \t"));
        assert!(!is_blank(b" x"));
        assert_eq!(HexBytes(&[0x10, 0xab]).to_string(), "10AB");
    }
}
