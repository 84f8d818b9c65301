//! Bit rates as people and trace headers write them: `500k`, `1M`,
//! `125000`, `500 kbit/s`, `1 Mbit/s`, `250 kBaud`.

/// The bit rate `text` says, in bit/s; `None` for anything else, zero and
/// rates over 100 Mbit/s included (no CAN bus runs faster than a few).
pub fn parse_bit_rate(text: &[u8]) -> Option<u32> {
    let t = crate::trim_end(crate::trim_start(text));
    let digits = t.iter().take_while(|b| b.is_ascii_digit()).count();
    let (number, unit) = t.split_at(digits);
    let value: u64 = std::str::from_utf8(number).ok()?.parse().ok()?;
    let unit = crate::trim_start(unit).to_ascii_lowercase();
    let scale: u64 = match unit.first() {
        None => 1,
        Some(b'k') => 1_000,
        Some(b'm') => 1_000_000,
        Some(b'b') => 1,
        _ => return None,
    };
    let rest = if scale == 1 { &unit[..] } else { &unit[1..] };
    let known: [&[u8]; 8] = [
        b"", b"bit/s", b"bits/s", b"bps", b"baud", b"bd", b"b/s", b"bit",
    ];
    if !known.contains(&rest) {
        return None;
    }
    let rate = value.checked_mul(scale)?;
    u32::try_from(rate)
        .ok()
        .filter(|r| (1..=100_000_000).contains(r))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_way_of_writing_a_bit_rate() {
        for (text, want) in [
            ("500k", Some(500_000)),
            ("1M", Some(1_000_000)),
            ("125000", Some(125_000)),
            ("500 kbit/s", Some(500_000)),
            (" 1 Mbit/s ", Some(1_000_000)),
            ("250 kBaud", Some(250_000)),
            ("20kbps", Some(20_000)),
            ("0", None),
            ("", None),
            ("fast", None),
            ("500 kbytes", None),
            ("99999999999999999999", None),
            ("200M", None),
        ] {
            assert_eq!(parse_bit_rate(text.as_bytes()), want, "{text}");
        }
    }
}
