//! How codes and bytes are written, in one place for every output: a code
//! as `0x4310`, bytes as upper-case hex pairs (`10AB`), lists of codes and
//! of codes with their counts. Each output keeps its own punctuation (a
//! [`ListStyle`]); the digits and the order come from here, so the table,
//! the CSV and the JSON cannot drift apart.
//!
//! Everything is pushed into the caller's buffer, a `String` (the table)
//! or bytes (CSV, JSON), without allocating: these run once or more per
//! event.

/// A buffer ASCII text is appended to.
pub(crate) trait Ascii {
    fn push_ascii(&mut self, ascii: &[u8]);
}

impl Ascii for Vec<u8> {
    fn push_ascii(&mut self, ascii: &[u8]) {
        self.extend_from_slice(ascii);
    }
}

impl Ascii for String {
    fn push_ascii(&mut self, ascii: &[u8]) {
        self.extend(ascii.iter().map(|&b| char::from(b)));
    }
}

const HEX: &[u8; 16] = b"0123456789ABCDEF";

/// `0x4310`: an error code (or any 16-bit object index) as the CiA
/// documents write it.
pub(crate) fn code(code: u16) -> [u8; 6] {
    let mut text = *b"0x0000";
    for (d, shift) in text[2..].iter_mut().zip([12, 8, 4, 0]) {
        *d = HEX[usize::from((code >> shift) & 0xF)];
    }
    text
}

/// `4310h`: a code as CiA 301 itself writes hex, for the CSV. DuckDB reads
/// `0x4310` as the number 17168 (quoted or not) and pandas reads digit
/// strings as numbers; a trailing `h` keeps the cell text in both without
/// options, where a code must stay (it is looked up, never added).
pub(crate) fn cia_code(code: u16) -> [u8; 5] {
    let mut text = *b"0000h";
    for (d, shift) in text[..4].iter_mut().zip([12, 8, 4, 0]) {
        *d = HEX[usize::from((code >> shift) & 0xF)];
    }
    text
}

/// How a list writes each code.
#[derive(Clone, Copy)]
pub(crate) enum Notation {
    /// `0x4310`.
    Prefixed,
    /// `4310h` ([`cia_code`]).
    Cia,
}

/// Appends `0x4310`.
pub(crate) fn push_code(out: &mut impl Ascii, c: u16) {
    out.push_ascii(&code(c));
}

/// `0x4310` as a string of its own.
pub(crate) fn code_text(c: u16) -> String {
    let mut s = String::with_capacity(6);
    push_code(&mut s, c);
    s
}

/// Appends `bytes` as upper-case hex pairs with nothing between
/// (`1043080100000000`).
/// A device type (object 0x1000) as every output writes it: `0x00020192`.
pub(crate) fn device_type(value: u32) -> String {
    format!("0x{value:08X}")
}

pub(crate) fn push_hex(out: &mut impl Ascii, bytes: &[u8]) {
    if let Ok(classic) = <&[u8; 8]>::try_from(bytes) {
        // The usual EMCY payload: one word, one copy.
        out.push_ascii(&hex16(u64::from_be_bytes(*classic)));
        return;
    }
    for chunk in bytes.chunks(8) {
        let mut word = [0u8; 8];
        word[..chunk.len()].copy_from_slice(chunk);
        let text = hex16(u64::from_be_bytes(word));
        out.push_ascii(text.get(..2 * chunk.len()).unwrap_or_default());
    }
}

/// Appends `bytes` as upper-case hex pairs with a space between
/// (`10 43 08 01`): the CSV's bytes, which two or more pairs keep text in
/// DuckDB and pandas (`1043080100000000` is a number to pandas).
pub(crate) fn push_hex_spaced(out: &mut impl Ascii, bytes: &[u8]) {
    for (i, &b) in bytes.iter().enumerate() {
        if i > 0 {
            out.push_ascii(b" ");
        }
        push_hex_byte(out, b);
    }
}

/// Appends one byte as its upper-case hex pair: the table's register and
/// manufacturer bytes, a byte at a time, where [`push_hex`]'s word at a
/// time would convert seven bytes for nothing.
pub(crate) fn push_hex_byte(out: &mut impl Ascii, byte: u8) {
    out.push_ascii(&[HEX[usize::from(byte >> 4)], HEX[usize::from(byte & 0xF)]]);
}

/// The 16 upper-case hex digits of `v`, all at once: each nibble moved into
/// a byte of its own, then `0`..`9` and `A`..`F` chosen per byte. An EMCY
/// payload is one `u64`, so its hex is one call instead of a lookup per
/// nibble.
fn hex16(v: u64) -> [u8; 16] {
    const LANES: u128 = 0x0101_0101_0101_0101_0101_0101_0101_0101;
    let mut x = u128::from(v);
    // Byte i of v into 16-bit lane i, then its nibbles into the lane's two bytes.
    x = (x | x << 32) & 0x0000_0000_FFFF_FFFF_0000_0000_FFFF_FFFF;
    x = (x | x << 16) & 0x0000_FFFF_0000_FFFF_0000_FFFF_0000_FFFF;
    x = (x | x << 8) & 0x00FF_00FF_00FF_00FF_00FF_00FF_00FF_00FF;
    const HI: u128 = 0x0F00_0F00_0F00_0F00_0F00_0F00_0F00_0F00;
    x = ((x << 4) & HI) | (x & (HI >> 8));
    // A nibble of 10 or more has bit 4 set after adding 6: 7 more for A..F.
    let letters = ((x + LANES * 6) >> 4) & LANES;
    (x + LANES * u128::from(b'0') + letters * 7).to_be_bytes()
}

/// The punctuation of a list of codes in one output.
pub(crate) struct ListStyle {
    /// Before the first item (`[` in JSON).
    pub open: &'static str,
    /// Around each code (`"` in JSON).
    pub quote: &'static str,
    /// Between items.
    pub separator: &'static str,
    /// Between a code and its count, in lists with counts.
    pub count: &'static str,
    /// After the last item.
    pub close: &'static str,
    pub notation: Notation,
}

/// The table's lists: `0x4310, 0x2310` and `0x3120 x1, 0x4210 x2`.
pub(crate) const TABLE_LIST: ListStyle = ListStyle {
    open: "",
    quote: "",
    separator: ", ",
    count: " x",
    close: "",
    notation: Notation::Prefixed,
};

/// A CSV cell's lists: `4310h 2310h` and `3120h:1 4210h:2` (no commas,
/// so a cell needs no quoting).
pub(crate) const CSV_LIST: ListStyle = ListStyle {
    open: "",
    quote: "",
    separator: " ",
    count: ":",
    close: "",
    notation: Notation::Cia,
};

/// A JSON array of codes: `["0x4310","0x2310"]`.
pub(crate) const JSON_ARRAY: ListStyle = ListStyle {
    open: "[",
    quote: "\"",
    separator: ",",
    count: "",
    close: "]",
    notation: Notation::Prefixed,
};

/// A JSON object from codes to counts: `{"0x3120":1,"0x4210":2}`.
pub(crate) const JSON_COUNTS: ListStyle = ListStyle {
    open: "{",
    quote: "\"",
    separator: ",",
    count: ":",
    close: "}",
    notation: Notation::Prefixed,
};

/// Appends `codes` as a list in `style`.
pub(crate) fn push_codes(
    out: &mut impl Ascii,
    codes: impl IntoIterator<Item = u16>,
    style: &ListStyle,
) {
    out.push_ascii(style.open.as_bytes());
    for (i, c) in codes.into_iter().enumerate() {
        if i > 0 {
            out.push_ascii(style.separator.as_bytes());
        }
        push_quoted_code(out, c, style);
    }
    out.push_ascii(style.close.as_bytes());
}

/// Appends codes with how often each came as a list in `style`.
pub(crate) fn push_code_counts(
    out: &mut impl Ascii,
    counts: impl IntoIterator<Item = (u16, u64)>,
    style: &ListStyle,
) {
    out.push_ascii(style.open.as_bytes());
    for (i, (c, count)) in counts.into_iter().enumerate() {
        if i > 0 {
            out.push_ascii(style.separator.as_bytes());
        }
        push_quoted_code(out, c, style);
        out.push_ascii(style.count.as_bytes());
        out.push_ascii(itoa::Buffer::new().format(count).as_bytes());
    }
    out.push_ascii(style.close.as_bytes());
}

fn push_quoted_code(out: &mut impl Ascii, c: u16, style: &ListStyle) {
    out.push_ascii(style.quote.as_bytes());
    match style.notation {
        Notation::Prefixed => push_code(out, c),
        Notation::Cia => out.push_ascii(&cia_code(c)),
    }
    out.push_ascii(style.quote.as_bytes());
}

/// `0x4310, 0x2310` as a string of its own (a boot event's cleared codes).
pub(crate) fn codes_list(codes: &[u16]) -> String {
    let mut s = String::with_capacity(codes.len() * 8);
    push_codes(&mut s, codes.iter().copied(), &TABLE_LIST);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_four_upper_case_digits() {
        assert_eq!(code_text(0x4310), "0x4310");
        assert_eq!(code_text(0x00AB), "0x00AB");
        assert_eq!(code_text(0xFF01), "0xFF01");
        let mut bytes = Vec::new();
        push_code(&mut bytes, 0x0001);
        assert_eq!(bytes, b"0x0001");
    }

    #[test]
    fn hex_pairs_of_any_length() {
        let mut s = String::new();
        push_hex(&mut s, &[0x10, 0xAB]);
        assert_eq!(s, "10AB");
        let mut v = Vec::new();
        push_hex(&mut v, &[0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0, 0xFE]);
        assert_eq!(v, b"1043080100000000FE");
        let mut none = String::new();
        push_hex(&mut none, &[]);
        assert_eq!(none, "");
    }

    #[test]
    fn a_byte_alone_is_the_pair_the_word_writer_gives() {
        for b in 0..=u8::MAX {
            let (mut alone, mut word) = (String::new(), String::new());
            push_hex_byte(&mut alone, b);
            push_hex(&mut word, &[b]);
            assert_eq!(alone, word, "{b:#04x}");
            assert_eq!(alone, format!("{b:02X}"));
        }
    }

    #[test]
    fn lists_in_each_style() {
        let codes = [0x3120, 0x4210];
        let counts = [(0x3120, 1), (0x4210, 12)];
        let list = |style| {
            let mut s = String::new();
            push_codes(&mut s, codes, style);
            s
        };
        let with_counts = |style| {
            let mut s = String::new();
            push_code_counts(&mut s, counts, style);
            s
        };
        assert_eq!(list(&TABLE_LIST), "0x3120, 0x4210");
        assert_eq!(with_counts(&TABLE_LIST), "0x3120 x1, 0x4210 x12");
        assert_eq!(list(&CSV_LIST), "3120h 4210h");
        assert_eq!(with_counts(&CSV_LIST), "3120h:1 4210h:12");
        assert_eq!(list(&JSON_ARRAY), r#"["0x3120","0x4210"]"#);
        assert_eq!(with_counts(&JSON_COUNTS), r#"{"0x3120":1,"0x4210":12}"#);
        assert_eq!(codes_list(&[]), "");
    }

    #[test]
    fn the_csv_writes_codes_as_cia_and_bytes_spaced() {
        assert_eq!(&cia_code(0x4310), b"4310h");
        assert_eq!(&cia_code(0x00AF), b"00AFh");
        let mut out = String::new();
        push_hex_spaced(&mut out, &[0x10, 0x43, 0x0C, 0x01]);
        assert_eq!(out, "10 43 0C 01");
        out.clear();
        push_hex_spaced(&mut out, &[]);
        assert_eq!(out, "");
    }

    proptest::proptest! {
        #[test]
        fn hex_is_written_as_std_writes_it(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..20)) {
            let mut out = String::new();
            push_hex(&mut out, &bytes);
            let want: String = bytes.iter().map(|b| format!("{b:02X}")).collect();
            proptest::prop_assert_eq!(out, want);
        }
    }
}
