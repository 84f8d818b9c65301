//! IXXAT MiniMon V3 ASCII traces (the text export of IXXAT's MiniMon bus
//! monitor):
//!
//! ```text
//! ASCII Trace IXXAT MiniMon V3  Version: 1.0.0.1271
//! Date: 28.01.2025
//! Start time: 10:47:15
//! Stop time: 10:49:43
//! Overruns: 0
//! Baudrate: 500 kbit/s
//! "Time";"Identifier (hex)";"Format";"Flags";"Data (hex)"
//! "00:02:20.66";"83";"Std";"";"00 00 00 01 20 00 00 00 "
//! "00:02:30.72";"702";"Std";"Rtr ";"Remote request  DLC = 1 "
//! "00:02:31.01";"18FF0103";"Ext";"";""
//! ```
//!
//! Rows are five quoted fields separated by `;`: the time, the id in hex
//! without `0x` (`Std` standard, `Ext` extended: the format column
//! decides, not the digit count), flags (`Rtr`: a remote request, whose
//! data column says `Remote request  DLC = n`), and the data bytes in hex,
//! each followed by a blank (`""`: no data).
//!
//! Times are `H:MM:SS.ff`, read as seconds since the start of the
//! measurement, like relative ASC times, and never turned into dates: the
//! header's `Date` and `Start time` do not say what the column counts from
//! (real traces have times past `Stop time - Start time`, so the column is
//! not the time since `Start time`), and a made-up date would be wrong.
//!
//! Skipped: the title line and, after it, the header lines (`Date:`,
//! `Start time:`, `Stop time:`, `Overruns:`, `Baudrate:`, and any other
//! `Key: value` line before the rows), the column header row, blank lines.
//! The title line alone identifies the format. Every frame is on
//! channel `1`: the trace names no bus.

use crate::{
    Format, Frame, FrameKind, Interest, LineParser, Parsed, Payload, Reason, Timestamp, hex,
    is_blank, show_token as show, trim_end, trim_start,
};

/// The title line's start, which only this format writes.
const TITLE: &[u8] = b"ASCII Trace IXXAT MiniMon";
const STANDARD_MAX: u32 = 0x7FF;
const EXTENDED_MAX: u32 = 0x1FFF_FFFF;
/// The channel of every frame (the trace names none).
const CHANNEL: &[u8] = b"1";

/// Reads IXXAT MiniMon V3 ASCII trace lines.
#[derive(Clone, Copy, Debug, Default)]
pub struct IxxatParser {
    /// The title line was read: header lines are known from now on.
    titled: bool,
    /// The header's `Baudrate: 500 kbit/s`, in bit/s.
    bit_rate: Option<u32>,
}

impl IxxatParser {
    /// A parser before the first line.
    pub fn new() -> Self {
        IxxatParser::default()
    }
}

impl LineParser for IxxatParser {
    fn format(&self) -> Format {
        Format::Ixxat
    }

    /// Only the title changes what later lines are (header lines become
    /// known), and it comes first.
    fn context(&self) -> Option<u8> {
        Some(u8::from(self.titled))
    }

    fn identified(&self) -> bool {
        self.titled
    }

    fn bit_rate(&self) -> Option<u32> {
        self.bit_rate
    }

    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        let t = trim_end(trim_start(line));
        if t.is_empty() || is_blank(t) {
            return Parsed::Skipped;
        }
        if t.starts_with(TITLE) {
            self.titled = true;
            return Parsed::Skipped;
        }
        if t.first() != Some(&b'"') {
            // `Date: 28.01.2025`, `Overruns: 0`: header lines, once the
            // title said whose they are.
            return if self.titled && is_header(t) {
                if let Some(rate) = t.strip_prefix(b"Baudrate:") {
                    self.bit_rate = crate::parse_bit_rate(rate);
                }
                Parsed::Skipped
            } else {
                Parsed::Malformed(
                    "expected a row of quoted fields (\"Time\";\"Identifier (hex)\";...)".into(),
                )
            };
        }
        match row(t, interest) {
            Ok(Some(frame)) => Parsed::Frame(frame),
            Ok(None) => Parsed::Skipped,
            Err(reason) => Parsed::Malformed(reason),
        }
    }
}

/// A `Key: value` header line (`Start time: 10:47:15`): a key of letters
/// and blanks, then a colon.
fn is_header(t: &[u8]) -> bool {
    match memchr::memchr(b':', t) {
        Some(colon) => {
            let key = t.get(..colon).unwrap_or_default();
            !key.is_empty() && key.iter().all(|b| b.is_ascii_alphabetic() || *b == b' ')
        }
        None => false,
    }
}

/// The five fields of a row, without their quotes.
fn fields(t: &[u8]) -> Result<[&[u8]; 5], Reason> {
    let mut out: [&[u8]; 5] = [&[]; 5];
    let mut rest = t;
    for (i, slot) in out.iter_mut().enumerate() {
        let inner = rest
            .strip_prefix(b"\"")
            .ok_or_else(|| format!("field {} is not in quotes", i + 1))?;
        let close = memchr::memchr(b'"', inner)
            .ok_or_else(|| format!("field {} has no closing quote", i + 1))?;
        *slot = inner.get(..close).unwrap_or_default();
        rest = inner.get(close + 1..).unwrap_or_default();
        if i < 4 {
            rest = rest
                .strip_prefix(b";")
                .ok_or("expected 5 fields separated by ';' (time, id, format, flags, data)")?;
        }
    }
    if !rest.is_empty() {
        return Err(format!("unexpected '{}' after the data field", show(rest)).into());
    }
    Ok(out)
}

/// A data row as a frame; `None` for the column header row.
fn row<'a>(t: &'a [u8], interest: &Interest) -> Result<Option<Frame<'a>>, Reason> {
    let [time, id, format, flags, data] = fields(t)?;
    if time == b"Time" {
        return Ok(None);
    }
    let time = parse_time(time)?;
    let extended = match format {
        b"Std" => false,
        b"Ext" => true,
        other => {
            return Err(format!("format '{}' is neither Std nor Ext", show(other)).into());
        }
    };
    let id_text = trim_end(trim_start(id));
    let id = match hex::parse_u32(id_text) {
        Some(id) if id_text.len() <= 8 => id,
        _ => return Err(format!("identifier '{}' is not hexadecimal", show(id)).into()),
    };
    if !extended && id > STANDARD_MAX {
        return Err(format!("standard identifier {id:X} is over 7FF").into());
    }
    if id > EXTENDED_MAX {
        return Err(format!("extended identifier {id:X} is over 1FFFFFFF").into());
    }
    let mut remote = false;
    for flag in flags
        .split(|b| *b == b' ' || *b == b'\t')
        .filter(|f| !f.is_empty())
    {
        match flag {
            b"Rtr" => remote = true,
            other => {
                return Err(format!("unknown flag '{}' (Rtr is read)", show(other)).into());
            }
        }
    }
    let wanted = interest.wants(id, extended);
    let (kind, len, payload) = if remote {
        (FrameKind::Remote, remote_dlc(data)?, Payload::new())
    } else {
        let (len, payload) = parse_data(data, wanted)?;
        (FrameKind::Data, len, payload)
    };
    Ok(Some(Frame {
        time: wanted.then_some(time),
        channel: CHANNEL,
        id,
        extended,
        kind,
        len,
        data: payload,
    }))
}

/// `H:MM:SS.ff` (any number of hour and fraction digits) as seconds.
fn parse_time(text: &[u8]) -> Result<Timestamp, Reason> {
    const SHAPE: &str = "time is not H:MM:SS.ff";
    let mut parts = text.split(|b| *b == b':');
    let (Some(h), Some(m), Some(s), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(format!("{SHAPE}: '{}'", show(text)).into());
    };
    let (whole, frac) = match memchr::memchr(b'.', s) {
        Some(dot) => (
            s.get(..dot).unwrap_or_default(),
            s.get(dot + 1..).unwrap_or_default(),
        ),
        None => (s, &b""[..]),
    };
    let number = |digits: &[u8], max_len: usize| -> Option<u64> {
        if digits.is_empty() || digits.len() > max_len || !digits.iter().all(u8::is_ascii_digit) {
            return None;
        }
        Some(
            digits
                .iter()
                .fold(0u64, |n, b| n * 10 + u64::from(b - b'0')),
        )
    };
    let (Some(hours), Some(minutes), Some(seconds)) =
        (number(h, 12), number(m, 2), number(whole, 2))
    else {
        return Err(format!("{SHAPE}: '{}'", show(text)).into());
    };
    if minutes > 59 || seconds > 59 {
        return Err(format!("{SHAPE}: '{}' (minutes and seconds below 60)", show(text)).into());
    }
    let secs = hours * 3600 + minutes * 60 + seconds;
    let int = secs.to_string();
    Timestamp::from_decimal(int.as_bytes(), frac).map_err(|why| format!("{SHAPE}: {why}").into())
}

/// `Remote request  DLC = n`: the requested length.
fn remote_dlc(data: &[u8]) -> Result<u8, Reason> {
    let t = trim_end(trim_start(data));
    let dlc = t
        .strip_prefix(b"Remote request")
        .map(trim_start)
        .and_then(|r| r.strip_prefix(b"DLC"))
        .map(trim_start)
        .and_then(|r| r.strip_prefix(b"="))
        .map(trim_start);
    match dlc {
        Some([d]) if (b'0'..=b'8').contains(d) => Ok(d - b'0'),
        _ => Err(format!(
            "a remote request's data field is not 'Remote request  DLC = n' (n 0-8): '{}'",
            show(data)
        )
        .into()),
    }
}

/// Hex bytes, each followed by a blank: the count, and the bytes when
/// `wanted`.
fn parse_data(data: &[u8], wanted: bool) -> Result<(u8, Payload), Reason> {
    let mut payload = Payload::new();
    let mut len = 0u8;
    for byte in data
        .split(|b| *b == b' ' || *b == b'\t')
        .filter(|f| !f.is_empty())
    {
        let value = match byte {
            [hi, lo] => hex::parse_byte(*hi, *lo),
            _ => None,
        }
        .ok_or_else(|| format!("data byte '{}' is not two hex digits", show(byte)))?;
        if len == 8 {
            return Err("more than 8 data bytes (MiniMon V3 traces classic CAN)".into());
        }
        if wanted {
            payload.push(value);
        }
        len += 1;
    }
    Ok((len, payload))
}

/// The fuzz target's checks of this reader: well-formed frames from any
/// input, and a title line identifies the format whatever follows.
#[cfg(any(test, feature = "fuzzing"))]
pub fn fuzz_ixxat(data: &[u8]) {
    let mut p = IxxatParser::new();
    let all = Interest::all();
    for line in data.split(|b| *b == b'\n') {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if let Parsed::Frame(f) = p.parse(line, &all) {
            assert!(f.len <= 8);
            if f.kind == FrameKind::Data {
                assert_eq!(f.data.len(), usize::from(f.len));
            } else {
                assert!(f.data.is_empty());
            }
            assert!(f.extended || f.id <= STANDARD_MAX);
            assert!(f.id <= EXTENDED_MAX);
            assert!(f.time.is_some());
        }
        if trim_start(line).starts_with(TITLE) {
            assert!(p.identified());
        }
    }
}

#[cfg(test)]
mod tests;
