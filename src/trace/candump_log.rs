//! candump log format (`candump -l`, `candump -L`, what canplayer replays):
//!
//! ```text
//! (1469439874.299654) can0 081#1043080100000000
//! (000.000100)  vcan-0 12345678#R
//! (1735270588.936508) can0 120##500112233445566778899AABB T
//! ```
//!
//! The number of id digits decides the frame type (3 = standard, 8 =
//! extended), not the value: `00000081#...` is an extended frame.

use super::time::MAX_FRACTION_DIGITS;
use super::{
    Frame, FrameKind, Interest, LineParser, Parsed, Payload, Reason, Scan, Timestamp, is_blank,
    split_token, trim_end, trim_start,
};
use super::{hex, scan};
use crate::trace::Format;

/// candump sets this bit in an 8-digit id to mark an error frame.
pub const ERROR_FLAG: u32 = 0x2000_0000;
const EFF_MASK: u32 = 0x1FFF_FFFF;

#[derive(Default, Clone, Copy)]
pub struct CandumpLogParser;

impl CandumpLogParser {
    pub fn new() -> Self {
        CandumpLogParser
    }
}

impl LineParser for CandumpLogParser {
    fn format(&self) -> Format {
        Format::CandumpLog
    }

    /// Stateless: every line stands alone.
    fn context(&self) -> Option<u8> {
        Some(0)
    }

    #[inline]
    fn scan<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Scan<'a> {
        let Some(shape) = shape(line) else {
            return Scan::Parse;
        };
        if !interest.wants(shape.id, shape.extended) {
            return Scan::Plain;
        }
        match shape.frame(line, true) {
            Some(frame) => Scan::Frame(frame),
            None => Scan::Parse,
        }
    }

    #[inline]
    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        match parse_line(line, interest) {
            Ok(Some(frame)) => Parsed::Frame(frame),
            Ok(None) => Parsed::Skipped,
            Err(reason) => Parsed::Malformed(reason),
        }
    }
}

/// Lines every candump output may contain besides frames: blank lines,
/// comments people add, and candump's own `DROPCOUNT:` notices.
pub(crate) fn is_candump_non_frame(line: &[u8]) -> bool {
    let t = trim_start(line);
    is_blank(t)
        || t.starts_with(b"#")
        || t.starts_with(b"//")
        || t.starts_with(b";")
        || t.starts_with(b"DROPCOUNT")
}

#[inline]
fn parse_line<'a>(line: &'a [u8], interest: &Interest) -> Result<Option<Frame<'a>>, Reason> {
    match canonical(line, interest) {
        Some(frame) => Ok(Some(frame)),
        None => parse_line_full(line, interest),
    }
}

/// Every form the format allows, with a reason for what it does not.
fn parse_line_full<'a>(line: &'a [u8], interest: &Interest) -> Result<Option<Frame<'a>>, Reason> {
    if is_candump_non_frame(line) {
        return Ok(None);
    }
    let t = trim_end(trim_start(line));
    let Some(after_paren) = t.strip_prefix(b"(") else {
        return Err("expected '(' and a timestamp at the start of the line".into());
    };
    let close = memchr::memchr(b')', after_paren).ok_or("timestamp has no closing ')'")?;
    let time_text = &after_paren[..close];
    let rest = &after_paren[close + 1..];
    if !rest.starts_with(b" ") && !rest.starts_with(b"\t") {
        return Err("expected a space after the timestamp".into());
    }
    let (channel, rest) = split_token(trim_start(rest));
    if channel.is_empty() {
        return Err("missing interface name".into());
    }
    let (frame_text, rest) = split_token(trim_start(rest));
    if frame_text.is_empty() {
        return Err("missing frame after the interface name".into());
    }
    match trim_start(rest) {
        b"" | b"T" | b"R" => {}
        _ => return Err("unexpected text after the frame (only T or R may follow)".into()),
    }

    let mut frame = parse_frame(frame_text, interest)?;
    // The timestamp is validated for every frame but only converted for wanted ones.
    let time = Timestamp::parse(time_text).map_err(Reason::from)?;
    if interest.wants(frame.id, frame.extended) {
        frame.time = Some(time);
    }
    frame.channel = channel;
    Ok(Some(frame))
}

/// The fast path for what `candump -l` writes, nearly every line of a real
/// log: `(SECS.FRAC) DEV ID#HEX` with a single space between fields, 3 or 8
/// id digits and 0-8 plain data bytes, optionally ` T`/` R`. Anything else
/// (padding, dots, remote, FD, raw DLC, errors of any kind) returns `None`
/// and goes to the full parser, which is the one source of error messages;
/// the fast path only accepts lines the full parser accepts identically.
#[inline]
fn canonical<'a>(line: &'a [u8], interest: &Interest) -> Option<Frame<'a>> {
    let shape = shape(line)?;
    shape.frame(line, interest.wants(shape.id, shape.extended))
}

/// Where the fields of a canonical line are.
struct Shape {
    dot: usize,
    close: usize,
    channel: std::ops::Range<usize>,
    id: u32,
    extended: bool,
    kind: FrameKind,
    data: std::ops::Range<usize>,
}

impl Shape {
    /// The frame of the line the shape was taken from; time and data are
    /// converted only when `wanted`.
    #[inline]
    fn frame<'a>(&self, line: &'a [u8], wanted: bool) -> Option<Frame<'a>> {
        let mut frame = Frame {
            time: None,
            channel: line.get(self.channel.clone())?,
            id: self.id,
            extended: self.extended,
            kind: self.kind,
            len: (self.data.len() / 2) as u8,
            data: Payload::new(),
        };
        if wanted {
            // At most 19 digits: always fits in u64.
            let secs = scan::decimal_u64(line.get(1..self.dot)?);
            let frac = line.get(self.dot + 1..self.close)?;
            frame.time = Some(Timestamp::from_parts(
                secs,
                scan::decimal_u64(frac),
                frac.len() as u8,
            ));
            for pair in line.get(self.data.clone())?.chunks_exact(2) {
                frame.data.push(hex::parse_byte(pair[0], pair[1])?);
            }
        }
        Some(frame)
    }
}

/// Validates a canonical line (see [`canonical`]) without building a frame.
#[inline]
fn shape(line: &[u8]) -> Option<Shape> {
    if line.first() != Some(&b'(') {
        return None;
    }
    let int_len = scan::digit_run(line, 1);
    let dot = 1 + int_len;
    if int_len == 0 || int_len > 19 || line.get(dot) != Some(&b'.') {
        return None;
    }
    let frac_len = scan::digit_run(line, dot + 1);
    let close = dot + 1 + frac_len;
    if frac_len == 0 || frac_len > MAX_FRACTION_DIGITS || line.get(close) != Some(&b')') {
        return None;
    }
    let dev_start = close + 2;
    if line.get(close + 1) != Some(&b' ') {
        return None;
    }
    let dev_len = scan::token_run(line, dev_start);
    let id_start = dev_start + dev_len + 1;
    if dev_len == 0 || line.get(dev_start + dev_len) != Some(&b' ') {
        return None;
    }
    let id_len = scan::hex_run(line, id_start);
    let hash = id_start + id_len;
    if line.get(hash) != Some(&b'#') {
        return None;
    }
    let id = hex::parse_u32(line.get(id_start..hash)?)?;
    let (extended, kind) = match id_len {
        3 if id <= 0x7FF => (false, FrameKind::Data),
        8 if id & !(EFF_MASK | ERROR_FLAG) != 0 => return None,
        8 if id & ERROR_FLAG != 0 => (true, FrameKind::Error),
        8 => (true, FrameKind::Data),
        _ => return None,
    };
    let data_start = hash + 1;
    let data_end = match line {
        [.., b' ', b'T' | b'R'] => line.len() - 2,
        _ => line.len(),
    };
    let data_len = data_end.checked_sub(data_start)?;
    if data_len % 2 != 0 || data_len > 16 || !scan::all_hex(line.get(data_start..data_end)?) {
        return None;
    }
    Some(Shape {
        dot,
        close,
        channel: dev_start..dev_start + dev_len,
        id,
        extended,
        kind,
        data: data_start..data_end,
    })
}

/// Parses `ID#DATA`, `ID#R[len]`, `ID##<flags>DATA` (the token after the
/// interface). Used by the candump log reader and by tests of other readers.
pub fn parse_frame<'a>(token: &[u8], interest: &Interest) -> Result<Frame<'a>, Reason> {
    let hash = memchr::memchr(b'#', token).ok_or("frame has no '#' between id and data")?;
    let id_text = &token[..hash];
    let body = &token[hash + 1..];
    let value = hex::parse_u32(id_text);
    let (id, extended, is_error) = match (id_text.len(), value) {
        (3, Some(id)) if id <= 0x7FF => (id, false, false),
        (3, Some(id)) => return Err(format!("standard id {id:03X} exceeds 7FF").into()),
        (8, Some(id)) if id & !(EFF_MASK | ERROR_FLAG) != 0 => {
            return Err(format!("extended id {id:08X} has bits above 29 set").into());
        }
        (8, Some(id)) => (id, true, id & ERROR_FLAG != 0),
        (3 | 8, None) => return Err("id is not hexadecimal".into()),
        (n, _) => {
            return Err(
                format!("id has {n} digits; candump writes 3 (standard) or 8 (extended)").into(),
            );
        }
    };
    let wanted = interest.wants(id, extended);
    let mut data = Payload::new();
    let (kind, len) = if let Some(fd) = body.strip_prefix(b"#") {
        if is_error {
            return Err("error frame written as a CAN FD frame".into());
        }
        let (&flags, hexdata) = fd
            .split_first()
            .ok_or("CAN FD frame needs a flags digit after '##'")?;
        hex::nibble(flags).ok_or("CAN FD flags digit is not hexadecimal")?;
        let len = parse_data(hexdata, 64, wanted.then_some(&mut data))?;
        (FrameKind::Fd, len)
    } else if let Some(rtr) = body.strip_prefix(b"R").or_else(|| body.strip_prefix(b"r")) {
        if is_error {
            return Err("error frame written as a remote frame".into());
        }
        let (len_text, dlc) = split_raw_dlc(rtr);
        let len = match len_text {
            [] => 0,
            [d @ b'0'..=b'8'] => d - b'0',
            _ => return Err("remote frame length must be one digit 0-8".into()),
        };
        check_raw_dlc(dlc, len)?;
        (FrameKind::Remote, 0)
    } else {
        let (hexdata, dlc) = split_raw_dlc(body);
        let len = parse_data(hexdata, 8, wanted.then_some(&mut data))?;
        check_raw_dlc(dlc, len)?;
        let kind = if is_error {
            FrameKind::Error
        } else {
            FrameKind::Data
        };
        (kind, len)
    };
    Ok(Frame {
        time: None,
        channel: &[],
        id,
        extended,
        kind,
        len,
        data,
    })
}

/// Splits `1122334455667788_E` into data and the raw DLC digit.
fn split_raw_dlc(body: &[u8]) -> (&[u8], Option<&[u8]>) {
    match memchr::memchr(b'_', body) {
        Some(i) => (&body[..i], Some(&body[i + 1..])),
        None => (body, None),
    }
}

/// A raw DLC (`_9`..`_F`) is only meaningful on an 8-byte classic frame.
fn check_raw_dlc(dlc: Option<&[u8]>, len: u8) -> Result<(), Reason> {
    match dlc {
        None => Ok(()),
        Some([d]) if len == 8 && matches!(hex::nibble(*d), Some(9..=15)) => Ok(()),
        Some(_) => Err("raw DLC suffix must be _9.._F after 8 data bytes".into()),
    }
}

/// Hex bytes, optionally separated by single dots between bytes
/// (`11223344` or `11.22.33.44`). Fills `out` when given.
pub(crate) fn parse_data(
    text: &[u8],
    max: usize,
    mut out: Option<&mut Payload>,
) -> Result<u8, Reason> {
    let mut len = 0usize;
    let mut i = 0;
    while i < text.len() {
        if text[i] == b'.' {
            if i == 0 || i + 1 == text.len() || text[i + 1] == b'.' {
                return Err("misplaced '.' separator in data".into());
            }
            i += 1;
            continue;
        }
        let (Some(&hi), Some(&lo)) = (text.get(i), text.get(i + 1)) else {
            return Err("odd number of hex digits in data".into());
        };
        let byte = match hex::parse_byte(hi, lo) {
            Some(b) => b,
            None if lo == b'.' => return Err("odd number of hex digits in data".into()),
            None => return Err("data is not hexadecimal".into()),
        };
        len += 1;
        if len > max {
            return Err(format!("more than {max} data bytes").into());
        }
        if let Some(p) = out.as_deref_mut() {
            p.push(byte);
        }
        i += 2;
    }
    Ok(len as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(line: &str) -> Parsed<'_> {
        CandumpLogParser::new().parse(line.as_bytes(), &Interest::all())
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
    fn classic_standard_frame() {
        let f = frame("(1469439874.299654) can0 081#1043080100000000");
        assert_eq!(f.time.unwrap().to_string(), "1469439874.299654");
        assert_eq!(f.channel, b"can0");
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x81, false, FrameKind::Data, 8)
        );
        assert_eq!(f.data.as_slice(), [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
    }

    #[test]
    fn digit_count_not_value_decides_extended() {
        let f = frame("(000.000000) vcan0 00000081#1043080100000000");
        assert!(f.extended);
        assert_eq!(f.id, 0x81);
        assert!(!frame("(0.0) can0 081#00").extended);
    }

    #[test]
    fn error_frames() {
        let f = frame("(1.000000) can0 20000004#0000000000000000");
        assert_eq!(f.kind, FrameKind::Error);
        assert_eq!(f.id, 0x2000_0004);
    }

    #[test]
    fn remote_frames() {
        let f = frame("(1735279048.349278) can1 110#R4");
        assert_eq!((f.kind, f.len), (FrameKind::Remote, 0));
        assert_eq!(frame("(1.0) can1 110#R").kind, FrameKind::Remote);
        assert_eq!(frame("(1.0) can1 110#r").kind, FrameKind::Remote);
        assert_eq!(frame("(1.0) can1 110#R8_E").kind, FrameKind::Remote);
        assert!(malformed("(1.0) can1 110#R9").contains("0-8"));
        assert!(malformed("(1.0) can0 20000004#R").contains("error frame"));
    }

    #[test]
    fn fd_frames() {
        let f = frame("(1735270588.936508) can0 120##500112233445566778899AABB");
        assert_eq!((f.kind, f.len), (FrameKind::Fd, 12));
        assert_eq!(f.data.as_slice()[0], 0x00);
        let f = frame("(1614188636.000000) can1 4A8##28001E9A318ACC0 R");
        assert_eq!((f.kind, f.len), (FrameKind::Fd, 7));
        assert_eq!(frame("(1.0) can0 123##1").len, 0);
        assert!(malformed("(1.0) can0 123##").contains("flags"));
        assert!(malformed("(1.0) can0 123##G00").contains("flags"));
        let long = format!("(1.0) can0 123##0{}", "00".repeat(65));
        assert!(malformed(&long).contains("64"));
    }

    #[test]
    fn separators_and_case() {
        let f = frame("(1.0) can0 123#11.22.33");
        assert_eq!(f.data.as_slice(), [0x11, 0x22, 0x33]);
        assert_eq!(frame("(1.0) can0 0ab#deadbeef").id, 0xAB);
        assert!(malformed("(1.0) can0 123#11..22").contains("separator"));
        assert!(malformed("(1.0) can0 123#.11").contains("separator"));
        assert!(malformed("(1.0) can0 123#11.").contains("separator"));
        assert!(malformed("(1.0) can0 123#1.122").contains("odd"));
    }

    #[test]
    fn raw_dlc() {
        let f = frame("(1.0) can0 123#1122334455667788_E");
        assert_eq!(f.len, 8);
        assert!(malformed("(1.0) can0 123#11_E").contains("raw DLC"));
        assert!(malformed("(1.0) can0 123#1122334455667788_5").contains("raw DLC"));
        assert!(malformed("(1.0) can0 123#1122334455667788_").contains("raw DLC"));
    }

    #[test]
    fn fraction_digits_any_count() {
        assert_eq!(frame("(1.5) can0 081#00").time.unwrap().to_string(), "1.5");
        assert_eq!(
            frame("(1700000000.123456789) can0 081#00")
                .time
                .unwrap()
                .to_string(),
            "1700000000.123456789"
        );
    }

    #[test]
    fn padded_names_and_odd_characters() {
        let f = frame("(1.0)   vcan-0 081#00");
        assert_eq!(f.channel, b"vcan-0");
        assert_eq!(frame("(1.0) can0.1 081#00").channel, b"can0.1");
        assert_eq!(frame("(1.0) my_can 081#00").channel, b"my_can");
        assert_eq!(frame("(1.0)\tcan0\t081#00 T").channel, b"can0");
    }

    #[test]
    fn non_frame_lines_are_skipped() {
        for line in [
            "",
            "   ",
            "# a comment",
            "// another",
            "DROPCOUNT: dropped 3 CAN frames on 'can0' socket (total drops 7)",
        ] {
            assert_eq!(parse(line), Parsed::Skipped, "{line:?}");
        }
    }

    #[test]
    fn malformed_lines_say_why() {
        assert!(malformed("can0 081#00").contains("'('"));
        assert!(malformed("(1.0 can0 081#00").contains("')'"));
        assert!(malformed("(1.0)can0 081#00").contains("space"));
        assert!(malformed("(1.0) can0").contains("missing frame"));
        assert!(malformed("(1.0) can0 08100").contains("'#'"));
        assert!(malformed("(1.0) can0 0081#00").contains("4 digits"));
        assert!(malformed("(1.0) can0 #00").contains("0 digits"));
        assert!(malformed("(1.0) can0 08G#00").contains("hexadecimal"));
        assert!(malformed("(1.0) can0 800#00").contains("exceeds"));
        assert!(malformed("(1.0) can0 40000000#00").contains("29"));
        assert!(malformed("(1.0) can0 081#0").contains("odd"));
        assert!(malformed("(1.0) can0 081#ZZ").contains("hexadecimal"));
        assert!(malformed("(1.0) can0 081#001122334455667788").contains("8"));
        assert!(malformed("(1.0) can0 081#00 X").contains("unexpected"));
        assert!(malformed("(x.0) can0 081#00").contains("decimal"));
        assert!(malformed("(99999999999999999999.0) can0 081#00").contains("overflow"));
        let long_id = format!("(1.0) can0 {}#00", "1".repeat(10_000));
        assert!(malformed(&long_id).contains("10000 digits"));
    }

    proptest::proptest! {
        /// The fast path may decline a line, but what it accepts the full
        /// parser accepts identically.
        #[test]
        fn fast_path_agrees_with_the_full_parser(
            line in "\\(([0-9]{0,21}\\.[0-9]{0,20}|x)\\)[ ]{1,2}[a-z0-9._-]{0,5}[ ]{1,2}[0-9a-fA-F]{0,9}[#_.R]{0,2}[0-9a-fA-FRr._#]{0,20}( T| R| X|  )?",
            narrow in proptest::bool::ANY,
        ) {
            let mut interest = if narrow { Interest::none() } else { Interest::all() };
            interest.add_standard(0x81);
            if let Some(fast) = canonical(line.as_bytes(), &interest) {
                proptest::prop_assert_eq!(Ok(Some(fast)), parse_line_full(line.as_bytes(), &interest));
            }
        }

        /// Lines of the canonical shape are taken by the fast path (unless the
        /// id is out of range) and read the same as by the full parser.
        #[test]
        fn canonical_lines_take_the_fast_path(
            line in "\\([0-9]{1,19}\\.[0-9]{1,18}\\) [a-z0-9]{1,5} ([0-7][0-9a-fA-F]{2}|[01][0-9a-fA-F]{7})#([0-9a-fA-F]{2}){0,8}( T| R)?",
            narrow in proptest::bool::ANY,
        ) {
            let mut interest = if narrow { Interest::none() } else { Interest::all() };
            interest.add_standard(0x81);
            let fast = canonical(line.as_bytes(), &interest);
            proptest::prop_assert!(fast.is_some(), "declined {}", line);
            proptest::prop_assert_eq!(Ok(fast), parse_line_full(line.as_bytes(), &interest));
        }
    }

    #[test]
    fn scan_counts_valid_unwanted_lines_and_decodes_wanted_ones() {
        let mut p = CandumpLogParser::new();
        let mut interest = Interest::none();
        interest.add_standard(0x81);
        assert_eq!(p.scan(b"(1.000000) can0 181#1122", &interest), Scan::Plain);
        let line = b"(1.000000) can0 081#1122";
        assert_eq!(
            p.scan(line, &interest),
            Scan::Frame(canonical(line, &interest).unwrap()),
            "wanted"
        );
        let Scan::Frame(f) = p.scan(line, &interest) else {
            unreachable!()
        };
        assert_eq!(f.data.as_slice(), [0x11, 0x22]);
        assert_eq!(f.time.map(|t| t.to_string()).as_deref(), Some("1.000000"));
        assert_eq!(
            p.scan(b"(1.000000) can0 181#112", &interest),
            Scan::Parse,
            "invalid"
        );
        assert_eq!(
            p.scan(b"(1.000000)  can0 181#1122", &interest),
            Scan::Parse,
            "not canonical"
        );
    }

    #[test]
    fn fast_path_takes_the_common_line() {
        assert!(
            canonical(
                b"(1469439874.299654) can0 081#1043080100000000",
                &Interest::all()
            )
            .is_some()
        );
        assert!(canonical(b"(1469439874.299654) can0 00000081#10 T", &Interest::all()).is_some());
        assert!(canonical(b"(1469439874.299654)  can0 081#10", &Interest::all()).is_none());
        assert!(canonical(b"(1469439874.299654) can0 081#R", &Interest::all()).is_none());
    }

    #[test]
    fn uninteresting_frames_are_validated_but_not_decoded() {
        let mut interest = Interest::none();
        interest.add_standard(0x81);
        let mut p = CandumpLogParser::new();
        match p.parse(b"(1.0) can0 123#1122", &interest) {
            Parsed::Frame(f) => {
                assert_eq!(f.len, 2);
                assert!(f.data.is_empty());
                assert!(f.time.is_none());
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            p.parse(b"(1.0) can0 123#11ZZ", &interest),
            Parsed::Malformed(_)
        ));
    }
}
