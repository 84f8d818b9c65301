//! Hex and decimal helpers shared by the line readers. Table-driven so the
//! hot path does one load per character and no branches on character ranges.

const INVALID: u8 = 0xFF;

static HEX_VALUE: [u8; 256] = {
    let mut t = [INVALID; 256];
    let mut i = 0;
    while i < 10 {
        t[b'0' as usize + i] = i as u8;
        i += 1;
    }
    let mut i = 0;
    while i < 6 {
        t[b'a' as usize + i] = 10 + i as u8;
        t[b'A' as usize + i] = 10 + i as u8;
        i += 1;
    }
    t
};

/// The value of one hex digit, either case.
#[inline]
pub fn nibble(b: u8) -> Option<u8> {
    let v = HEX_VALUE[usize::from(b)];
    (v != INVALID).then_some(v)
}

/// A hex number of 1..=8 digits (no prefix). `None` if empty, too long or not hex.
#[inline]
pub fn parse_u32(text: &[u8]) -> Option<u32> {
    if text.is_empty() || text.len() > 8 {
        return None;
    }
    let mut v: u32 = 0;
    for &b in text {
        v = (v << 4) | u32::from(nibble(b)?);
    }
    Some(v)
}

/// A decimal number that fits in u32.
#[inline]
pub fn parse_dec_u32(text: &[u8]) -> Option<u32> {
    if text.is_empty() || text.len() > 10 {
        return None;
    }
    let mut v: u32 = 0;
    for &b in text {
        if !b.is_ascii_digit() {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(u32::from(b - b'0'))?;
    }
    Some(v)
}

/// One byte from exactly two hex digits.
#[inline]
pub fn parse_byte(hi: u8, lo: u8) -> Option<u8> {
    Some((nibble(hi)? << 4) | nibble(lo)?)
}

/// Parses `0x4310`, `4310`, `0X4310` into a 16-bit value (at most 4 digits).
pub fn parse_code(text: &str) -> Option<u16> {
    let t = text.trim();
    let digits = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .unwrap_or(t);
    if digits.is_empty() || digits.len() > 4 {
        return None;
    }
    parse_u32(digits.as_bytes()).and_then(|v| u16::try_from(v).ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nibbles_both_cases() {
        assert_eq!(nibble(b'0'), Some(0));
        assert_eq!(nibble(b'9'), Some(9));
        assert_eq!(nibble(b'a'), Some(10));
        assert_eq!(nibble(b'F'), Some(15));
        for b in [b'g', b'G', b' ', b'.', b'#', 0, 0xFF] {
            assert_eq!(nibble(b), None);
        }
    }

    #[test]
    fn u32_limits() {
        assert_eq!(parse_u32(b"081"), Some(0x81));
        assert_eq!(parse_u32(b"1FFFFFFF"), Some(0x1FFF_FFFF));
        assert_eq!(parse_u32(b"FFFFFFFF"), Some(u32::MAX));
        assert_eq!(parse_u32(b"100000000"), None);
        assert_eq!(parse_u32(b""), None);
        assert_eq!(parse_u32(b"12G"), None);
    }

    #[test]
    fn decimal() {
        assert_eq!(parse_dec_u32(b"0"), Some(0));
        assert_eq!(parse_dec_u32(b"4294967295"), Some(u32::MAX));
        assert_eq!(parse_dec_u32(b"4294967296"), None);
        assert_eq!(parse_dec_u32(b"1a"), None);
    }

    #[test]
    fn codes() {
        assert_eq!(parse_code("4310"), Some(0x4310));
        assert_eq!(parse_code("0x4310"), Some(0x4310));
        assert_eq!(parse_code(" 0Xff00 "), Some(0xFF00));
        assert_eq!(parse_code("10000"), None);
        assert_eq!(parse_code("0x"), None);
        assert_eq!(parse_code("xyz"), None);
    }

    #[test]
    fn bytes() {
        assert_eq!(parse_byte(b'A', b'5'), Some(0xA5));
        assert_eq!(parse_byte(b'A', b'x'), None);
    }
}
