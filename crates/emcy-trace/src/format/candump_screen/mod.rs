//! candump's screen output (the default, what people paste and `tee`):
//!
//! ```text
//!   vcan0  1F4   [4]  01 02 03 04
//!  (015.052211)  vcan0  00000123   [0]  remote request
//! (1613749650.388103)  can1       0AD  [08]  A6 55 3B CF 3F 1A F5 2A
//!   vcan0  20000004   [8]  00 00 00 00 00 00 00 00   ERRORFRAME
//!  (2018-12-06 09:31:30.572475)  can0  RX B -  57E   [5]  C7 35 06 18 00
//! ```
//!
//! The layout comes from can-utils (`candump.c` and `lib.c`'s long frame
//! printer). The reader is whitespace-insensitive because candump pads
//! interface names to the longest one seen (right-aligned) and indents
//! standard ids once an extended frame was printed; people also strip or
//! re-indent pasted lines.
//!
//! What candump's options add, all accepted:
//! - `-t a|z|d|A`: a leading `(...)` time. This parser takes numeric times
//!   as printed; `-td` deltas are summed above it, by the detector, when
//!   the first lines prove them or the user says so ([`crate::deltas`]).
//!   `-tA` local dates carry no zone; they are read as UTC.
//! - `-x`: `RX`/`TX` and a BRS/ESI pair (`- -`, `B -`, `- E`, `B E`) before the id.
//! - `-8`: the classic length as a raw DLC in braces, `{0}`..`{F}`; candump
//!   prints a DLC above 8 only for 8-byte frames, so `{X}` carries min(X, 8) bytes.
//! - `-a`: an ASCII column in quotes after the data (checked against the bytes).
//! - `-i` (binary bytes, `10100101`) and `-S` (bytes in reverse order joined
//!   by `` ` ``, ASCII column in backticks).
//! - `-c`: ANSI colour sequences (`ESC [ ... m`) between fields; they are
//!   treated as blanks.
//! - `-e`: error frame explanations on continuation lines that start with a tab.
//!
//! CAN XL frames (`[nnnn]` lengths) are reported as malformed: a [`Frame`]
//! cannot hold them and dropping them silently would hide data.

use crate::format::candump_log::{
    ERROR_FLAG, is_candump_command, is_candump_non_frame, starts_note,
};
use crate::hex;
use crate::time::{MAX_FRACTION_DIGITS, unix_midnight};
use crate::{
    Format, Frame, FrameKind, Interest, LineParser, Parsed, Payload, Reason, Timestamp, trim_start,
};

const EFF_MASK: u32 = 0x1FFF_FFFF;
const ESC: u8 = 0x1B;

/// Reader for candump's default screen output. Stateless: every line
/// carries all it needs (ids are told apart by digit count, not indentation).
#[derive(Default, Clone, Copy)]
pub struct CandumpScreenParser {
    /// The last line read was a frame with a note after it (see
    /// [`LineParser::take_annotated`]); no line depends on it.
    annotated: bool,
}

impl CandumpScreenParser {
    /// A parser before the first line.
    pub fn new() -> Self {
        CandumpScreenParser::default()
    }
}

impl LineParser for CandumpScreenParser {
    fn format(&self) -> Format {
        Format::CandumpScreen
    }

    /// Stateless: times are taken as printed, so no line depends on another.
    fn context(&self) -> Option<u8> {
        Some(0)
    }

    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        self.annotated = false;
        if is_candump_non_frame(line) {
            return Parsed::Skipped;
        }
        let mut cursor = Cursor::new(line);
        cursor.skip_blanks();
        if cursor.peek().is_none() {
            // Only colour codes: `-c -c` resets the colour after `-e` text.
            return Parsed::Skipped;
        }
        match parse_line::<false>(line, interest) {
            Ok((frame, _)) => Parsed::Frame(frame),
            // Only a line the strict reading refused is read again for
            // notes after its frame: ordinary lines pay nothing for them.
            Err(_) => match parse_line::<true>(line, interest) {
                Ok((frame, annotated)) => {
                    self.annotated = annotated;
                    Parsed::Frame(frame)
                }
                Err(_) if is_error_explanation(line) || is_candump_command(line) => Parsed::Skipped,
                Err(reason) => Parsed::Malformed(reason),
            },
        }
    }

    fn take_annotated(&mut self) -> bool {
        std::mem::take(&mut self.annotated)
    }
}

/// `-e` prints the decoded error classes of an error frame on lines of
/// their own, each starting with a tab and a lowercase class name
/// (`\tcontroller-problem{rx-error-warning}`, `\tbus-off`). candump itself
/// never starts a frame line with a tab, but a re-indented paste might, so
/// such lines are tried as frames first.
fn is_error_explanation(line: &[u8]) -> bool {
    match line.strip_prefix(b"\t") {
        Some(rest) => trim_start(rest)
            .first()
            .is_some_and(|b| b.is_ascii_lowercase()),
        None => false,
    }
}

/// Walks a line token by token. Blanks and ANSI CSI sequences both separate
/// tokens, so colour codes never end up inside an interface name or id.
struct Cursor<'a> {
    line: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn new(line: &'a [u8]) -> Self {
        Cursor { line, pos: 0 }
    }

    fn peek(&self) -> Option<u8> {
        self.line.get(self.pos).copied()
    }

    fn rest(&self) -> &'a [u8] {
        self.line.get(self.pos..).unwrap_or_default()
    }

    fn skip_blanks(&mut self) {
        loop {
            match self.peek() {
                Some(b' ' | b'\t') => self.pos += 1,
                Some(ESC) => match csi_end(self.line, self.pos) {
                    Some(end) => self.pos = end,
                    None => return,
                },
                _ => return,
            }
        }
    }

    /// The next token, `None` at the end of the line.
    fn token(&mut self) -> Option<&'a [u8]> {
        self.skip_blanks();
        let start = self.pos;
        while let Some(b) = self.peek() {
            if b == b' ' || b == b'\t' || (b == ESC && csi_end(self.line, self.pos).is_some()) {
                break;
            }
            self.pos += 1;
        }
        self.line.get(start..self.pos).filter(|t| !t.is_empty())
    }
}

/// End (exclusive) of an ANSI CSI sequence `ESC [ params intermediates final`
/// starting at `i`; `None` if there is none (a stray ESC is an ordinary byte).
fn csi_end(line: &[u8], i: usize) -> Option<usize> {
    if line.get(i) != Some(&ESC) || line.get(i.checked_add(1)?) != Some(&b'[') {
        return None;
    }
    let mut j = i + 2;
    while matches!(line.get(j), Some(0x30..=0x3F)) {
        j += 1;
    }
    while matches!(line.get(j), Some(0x20..=0x2F)) {
        j += 1;
    }
    match line.get(j) {
        Some(0x40..=0x7E) => Some(j + 1),
        _ => None,
    }
}

/// Quotes a piece of the line for a reason: escaped (no raw control bytes
/// reach the user's terminal) and cut short.
fn show(bytes: &[u8]) -> String {
    const MAX: usize = 24;
    let cut = bytes.get(..MAX).unwrap_or(bytes);
    let mut s = cut.escape_ascii().to_string();
    if bytes.len() > MAX {
        s.push_str("...");
    }
    s
}

/// The length field after the id.
#[derive(Clone, Copy)]
enum LenField {
    /// `[n]`: classic CAN, 0..=8 bytes.
    Classic(u8),
    /// `[nn]`: CAN FD, 0..=64 bytes (always two digits: `[08]`).
    Fd(u8),
    /// `{X}` (`-8`): a classic frame's raw DLC 0..=15.
    RawDlc(u8),
}

impl LenField {
    /// How many data bytes candump prints after this field.
    fn bytes(self) -> usize {
        match self {
            LenField::Classic(n) | LenField::Fd(n) => usize::from(n),
            LenField::RawDlc(dlc) => usize::from(dlc.min(8)),
        }
    }
}

fn parse_len(tok: &[u8]) -> Result<LenField, Reason> {
    let digit = |b: u8| b.is_ascii_digit().then(|| b - b'0');
    match tok {
        [b'[', d, b']'] => match digit(*d) {
            Some(n @ 0..=8) => Ok(LenField::Classic(n)),
            Some(n) => Err(format!("length [{n}] is too large for a classic frame (max 8)").into()),
            None => Err(format!("length field '{}' is not a number", show(tok)).into()),
        },
        [b'[', hi, lo, b']'] => match (digit(*hi), digit(*lo)) {
            (Some(h), Some(l)) if h * 10 + l <= 64 => Ok(LenField::Fd(h * 10 + l)),
            (Some(h), Some(l)) => Err(format!(
                "length [{}] is too large for a CAN FD frame (max 64)",
                h * 10 + l
            )
            .into()),
            _ => Err(format!("length field '{}' is not a number", show(tok)).into()),
        },
        [b'[', inner @ .., b']'] if inner.len() == 4 && inner.iter().all(u8::is_ascii_digit) => {
            Err(format!("CAN XL frame (length {}) is not supported", show(tok)).into())
        }
        [b'{', x, b'}'] => match hex::nibble(*x) {
            Some(dlc) => Ok(LenField::RawDlc(dlc)),
            None => Err(format!("raw DLC '{}' is not one hex digit", show(tok)).into()),
        },
        [b'[' | b'{', ..] => {
            Err(format!("length field '{}' is not [n], [nn] or {{X}}", show(tok)).into())
        }
        _ => Err(format!(
            "missing length field ([n], [nn] or {{X}}) after the id, found '{}'",
            show(tok)
        )
        .into()),
    }
}

/// `(id, extended)` from a 3- or 8-digit id token (digit count decides, as
/// in the log format; an 8-digit id may carry the error flag).
fn parse_id(tok: &[u8]) -> Result<(u32, bool), Reason> {
    if memchr::memchr(b'#', tok).is_some() {
        return Err(format!(
            "'{}' is candump log format (ID#DATA), not screen output",
            show(tok)
        )
        .into());
    }
    if matches!(tok.first(), Some(b'[' | b'{')) {
        return Err("missing interface name or CAN id before the length field".into());
    }
    match (tok.len(), hex::parse_u32(tok)) {
        (3, Some(id)) if id <= 0x7FF => Ok((id, false)),
        (3, Some(id)) => Err(format!("standard id {id:03X} exceeds 7FF").into()),
        (8, Some(id)) if id & !(EFF_MASK | ERROR_FLAG) != 0 => {
            Err(format!("extended id {id:08X} has bits above 29 set").into())
        }
        (8, Some(id)) => Ok((id, true)),
        (3 | 8, None) => Err(format!("id '{}' is not hexadecimal", show(tok)).into()),
        (n, _) => Err(format!(
            "id '{}' has {n} digits; candump writes 3 (standard) or 8 (extended)",
            show(tok)
        )
        .into()),
    }
}

/// One printed data byte: two hex digits, or eight binary digits (`-i`).
/// `width` remembers which one the line uses.
fn parse_byte(piece: &[u8], width: &mut Option<usize>) -> Result<u8, Reason> {
    let byte = match piece {
        [hi, lo] => hex::parse_byte(*hi, *lo)
            .ok_or_else(|| format!("data byte '{}' is not hexadecimal", show(piece)))?,
        bits if bits.len() == 8 && bits.iter().all(|b| matches!(b, b'0' | b'1')) => bits
            .iter()
            .fold(0u8, |acc, b| (acc << 1) | u8::from(*b == b'1')),
        _ => {
            return Err(format!(
                "data byte '{}' is not two hex digits (or eight binary digits)",
                show(piece)
            )
            .into());
        }
    };
    match width {
        Some(w) if *w != piece.len() => Err("data mixes hex and binary bytes".into()),
        _ => {
            *width = Some(piece.len());
            Ok(byte)
        }
    }
}

/// What follows the length field, as printed left to right.
struct Body<'a> {
    /// The bytes in printed order (reversed under `-S`); only the first 64 kept.
    shown: [u8; Payload::MAX],
    /// How many bytes were printed (may exceed 64 on a bad line).
    count: usize,
    /// `-S`: bytes were printed last-to-first, joined by backticks.
    swapped: bool,
    errorframe: bool,
    /// The `-a` column between its quotes.
    ascii: Option<&'a [u8]>,
    /// Text followed the complete frame (lenient reading only).
    annotated: bool,
}

/// The body after the length field. `LENIENT` reads a pasted line that
/// the strict reading refused: the ASCII column is exactly one character
/// per byte between its quotes (so it may hold quotes and be followed by
/// text), and text after the complete frame (after the data bytes, the
/// ASCII column or `ERRORFRAME`) is a note, `annotated`.
fn parse_body<'a, const LENIENT: bool>(
    cur: &mut Cursor<'a>,
    expected: usize,
) -> Result<Body<'a>, Reason> {
    let mut body = Body {
        shown: [0; Payload::MAX],
        count: 0,
        swapped: false,
        errorframe: false,
        ascii: None,
        annotated: false,
    };
    let mut width = None;
    let mut groups = 0usize;
    loop {
        cur.skip_blanks();
        let start = cur.pos;
        if let Some(quote @ (b'\'' | b'`')) = cur.peek() {
            if LENIENT {
                body.ascii = Some(ascii_column(cur, quote, body.count)?);
                if let Some(extra) = cur.token() {
                    if !starts_note(extra) {
                        return Err(format!(
                            "unexpected '{}' after the ASCII column (a note after a frame \
                             starts with a sign such as //, # or <)",
                            show(extra)
                        )
                        .into());
                    }
                    body.annotated = true;
                }
                break;
            }
            // The ASCII column may hold blanks and quotes: it runs to the
            // last token of the line and must end with its opening quote.
            let mut end = start;
            while cur.token().is_some() {
                end = cur.pos;
            }
            let column = cur.line.get(start..end).unwrap_or_default();
            let inner = column
                .strip_prefix(&[quote])
                .and_then(|c| c.strip_suffix(&[quote]))
                .ok_or("ASCII column is not closed by its quote")?;
            body.ascii = Some(inner);
            break;
        }
        let Some(tok) = cur.token() else { break };
        if tok == b"ERRORFRAME" {
            if let Some(extra) = cur.token() {
                if !LENIENT || !starts_note(extra) {
                    return Err(format!("unexpected '{}' after ERRORFRAME", show(extra)).into());
                }
                body.annotated = true;
            }
            body.errorframe = true;
            break;
        }
        if LENIENT && !is_data_byte(tok) {
            if body.count == expected && starts_note(tok) {
                // The frame is complete: the rest of the line is a note.
                body.annotated = true;
                break;
            }
            if !tok.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'`') {
                // Not meant as a byte (`<`, `//`, `#`): a note after too
                // few or too many bytes.
                return Err(format!(
                    "{} data bytes where the length field says {expected}, then '{}'",
                    body.count,
                    show(tok)
                )
                .into());
            }
        }
        groups += 1;
        if memchr::memchr(b'`', tok).is_some() {
            body.swapped = true;
        }
        for piece in tok.split(|b| *b == b'`') {
            let byte = parse_byte(piece, &mut width)?;
            if let Some(slot) = body.shown.get_mut(body.count) {
                *slot = byte;
            }
            body.count += 1;
        }
    }
    if body.swapped && groups > 1 {
        return Err("byte-swapped data (-S) must be one group joined by '`'".into());
    }
    Ok(body)
}

/// Whether a token reads as one printed data byte (or a `-S` group of
/// them): a note after the data never starts with one, or it would be a
/// byte too many.
fn is_data_byte(tok: &[u8]) -> bool {
    let mut width = None;
    tok.split(|b| *b == b'`')
        .all(|piece| parse_byte(piece, &mut width).is_ok())
}

/// The `-a` column of a frame of `count` bytes, the cursor on its opening
/// quote: candump prints exactly one character per byte, so the column
/// ends `count` characters later with the same quote (a quote inside it is
/// a byte), and a blank or the end of the line follows. The cursor ends
/// after the column.
fn ascii_column<'a>(cur: &mut Cursor<'a>, quote: u8, count: usize) -> Result<&'a [u8], Reason> {
    let open = cur.pos;
    let inner = cur
        .line
        .get(open + 1..open + 1 + count)
        .filter(|inner| inner.len() == count);
    let close = open + 1 + count;
    let closed = cur.line.get(close) == Some(&quote)
        && matches!(
            cur.line.get(close + 1).copied(),
            None | Some(b' ' | b'\t' | ESC)
        );
    match inner {
        Some(inner) if closed => {
            cur.pos = close + 1;
            Ok(inner)
        }
        _ => Err(format!(
            "ASCII column must be {count} characters (one per data byte) between {q} and {q}, found {}",
            crate::show_token(crate::trim_end(cur.rest())),
            q = char::from(quote)
        )
        .into()),
    }
}

/// `-a` prints each byte as itself when printable ASCII, else as `.`.
fn ascii_matches(column: &[u8], bytes: &[u8]) -> bool {
    column.len() == bytes.len()
        && column.iter().zip(bytes).all(|(&c, &b)| {
            if (0x20..0x7F).contains(&b) {
                c == b
            } else {
                c == b'.'
            }
        })
}

/// A frame line, and whether a note followed the frame (only `LENIENT`
/// reads notes, see [`parse_body`]).
fn parse_line<'a, const LENIENT: bool>(
    line: &'a [u8],
    interest: &Interest,
) -> Result<(Frame<'a>, bool), Reason> {
    let mut cur = Cursor::new(line);
    cur.skip_blanks();

    let time_text = if cur.peek() == Some(b'(') {
        let close = memchr::memchr(b')', cur.rest()).ok_or("timestamp has no closing ')'")?;
        let text = cur
            .line
            .get(cur.pos + 1..cur.pos + close)
            .unwrap_or_default();
        cur.pos += close + 1;
        if !matches!(cur.peek(), None | Some(b' ' | b'\t' | ESC)) {
            return Err("expected a space after the timestamp".into());
        }
        Some(text)
    } else {
        None
    };

    let channel = cur.token().ok_or("missing interface name")?;
    let mut id_tok = cur
        .token()
        .ok_or("missing CAN id after the interface name")?;
    if id_tok == b"RX" || id_tok == b"TX" {
        // `-x`: direction, then bit rate switch and error state indicator.
        match (cur.token(), cur.token()) {
            (Some(b"-" | b"B"), Some(b"-" | b"E")) => {}
            _ => {
                return Err(
                    "after RX/TX expected the flags pair '- -', 'B -', '- E' or 'B E'".into(),
                );
            }
        }
        id_tok = cur.token().ok_or("missing CAN id after the RX/TX flags")?;
    }
    let (id, extended) = parse_id(id_tok)?;
    let is_error = extended && id & ERROR_FLAG != 0;

    let len_tok = cur
        .token()
        .ok_or("missing length field ([n], [nn] or {X}) after the id")?;
    let len_field = parse_len(len_tok)?;
    let is_fd = matches!(len_field, LenField::Fd(_));
    if is_error && is_fd {
        return Err("error frame with a CAN FD length".into());
    }

    // Error frames are rare: always decoded whole, whatever the interest.
    let wanted = is_error || interest.wants(id, extended);
    let mut data = Payload::new();
    let before_body = cur.pos;
    let mut annotated = false;
    let (kind, len) = if matches!(cur.token(), Some(b"remote")) {
        if !matches!(cur.token(), Some(b"request")) {
            return Err("expected 'remote request' and nothing after it".into());
        }
        if let Some(note) = cur.token() {
            if !LENIENT || !starts_note(note) {
                return Err("expected 'remote request' and nothing after it".into());
            }
            annotated = true;
        }
        if is_error {
            return Err("error frame printed as a remote request".into());
        }
        if is_fd {
            return Err("CAN FD frames have no remote requests".into());
        }
        (FrameKind::Remote, 0)
    } else {
        cur.pos = before_body;
        let expected = len_field.bytes();
        let body = parse_body::<LENIENT>(&mut cur, expected)?;
        annotated = body.annotated;
        if body.count != expected {
            let note = match len_field {
                LenField::RawDlc(dlc) if dlc > 8 => " (a raw DLC above 8 means 8 bytes)",
                _ => "",
            };
            return Err(format!("{}{note} but {} data bytes", show(len_tok), body.count).into());
        }
        // `expected` <= 64, so every printed byte was kept.
        let shown = body.shown.get(..body.count).unwrap_or_default();
        if is_error && !body.errorframe {
            return Err("error frame (id with 0x20000000) lacks the ERRORFRAME marker".into());
        }
        if body.errorframe && !is_error {
            return Err("ERRORFRAME on a frame without the error flag 0x20000000".into());
        }
        if let Some(column) = body.ascii
            && !ascii_matches(column, shown)
        {
            return Err(format!(
                "ASCII column '{}' does not match the data bytes",
                show(column)
            )
            .into());
        }
        if wanted {
            // `-S` printed the last byte first.
            if body.swapped {
                for b in shown.iter().rev() {
                    data.push(*b);
                }
            } else {
                for b in shown {
                    data.push(*b);
                }
            }
        }
        let kind = if is_error {
            FrameKind::Error
        } else if is_fd {
            FrameKind::Fd
        } else {
            FrameKind::Data
        };
        (kind, body.count as u8)
    };

    // Validated for every frame, kept only for wanted ones.
    let time = match time_text {
        Some(text) => Some(parse_time(text)?),
        None => None,
    };
    let (id, extended) = if is_error {
        // The class bits, without the flag (`crate::error_frame`).
        (id & !ERROR_FLAG, false)
    } else {
        (id, extended)
    };
    let frame = Frame {
        time: if wanted { time } else { None },
        channel,
        id,
        extended,
        kind,
        len,
        data,
    };
    Ok((frame, annotated))
}

/// The text between the parentheses: a decimal number of seconds
/// (`-ta`, `-tz`, `-td`) or a `-tA` date.
fn parse_time(text: &[u8]) -> Result<Timestamp, Reason> {
    if text.iter().any(|b| matches!(b, b'-' | b':' | b' ')) {
        parse_date(text)
    } else {
        Timestamp::parse(text).map_err(Reason::from)
    }
}

/// All-digit text of exactly `n` digits as a number.
fn fixed_digits(text: &[u8], n: usize) -> Option<u64> {
    if text.len() != n || !text.iter().all(u8::is_ascii_digit) {
        return None;
    }
    Some(
        text.iter()
            .fold(0u64, |acc, b| acc * 10 + u64::from(b - b'0')),
    )
}

/// `-tA`: `YYYY-MM-DD HH:MM:SS.uuuuuu`, local time without a zone, read as
/// UTC seconds since the Unix epoch. The fraction keeps its digits exactly.
fn parse_date(text: &[u8]) -> Result<Timestamp, Reason> {
    const SHAPE: &str = "date timestamp is not (YYYY-MM-DD HH:MM:SS.uuuuuu)";
    let blank = text.iter().position(|b| *b == b' ').ok_or(SHAPE)?;
    let (date, clock) = text.split_at(blank);
    let clock = trim_start(clock);
    let (hms, frac) = match memchr::memchr(b'.', clock) {
        Some(dot) => (
            clock.get(..dot).unwrap_or_default(),
            Some(clock.get(dot + 1..).unwrap_or_default()),
        ),
        None => (clock, None),
    };
    let field = |part: Option<&[u8]>, n| part.and_then(|p| fixed_digits(p, n)).ok_or(SHAPE);
    let mut d = date.split(|b| *b == b'-');
    let (year, month, day) = (
        field(d.next(), 4)?,
        field(d.next(), 2)?,
        field(d.next(), 2)?,
    );
    let mut t = hms.split(|b| *b == b':');
    let (hour, minute, second) = (
        field(t.next(), 2)?,
        field(t.next(), 2)?,
        field(t.next(), 2)?,
    );
    if d.next().is_some() || t.next().is_some() {
        return Err(SHAPE.into());
    }
    let midnight = unix_midnight(year, month, day)
        .ok_or_else(|| format!("invalid date {year:04}-{month:02}-{day:02} (or before 1970)"))?;
    if hour > 23 || minute > 59 || second > 59 {
        return Err(format!("invalid time of day {hour:02}:{minute:02}:{second:02}").into());
    }
    let secs = midnight + hour * 3600 + minute * 60 + second;
    let (frac_value, digits) = match frac {
        None => (0, 0),
        Some([]) => return Err("timestamp ends with a dot".into()),
        Some(f) if f.len() > MAX_FRACTION_DIGITS => {
            return Err("timestamp has more than 18 fraction digits".into());
        }
        Some(f) => (
            fixed_digits(f, f.len()).ok_or("timestamp fraction is not decimal")?,
            f.len() as u8,
        ),
    };
    Ok(Timestamp::from_parts(secs, frac_value, digits))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::borrow::Cow;

    fn parse(line: &str) -> Parsed<'_> {
        CandumpScreenParser::new().parse(line.as_bytes(), &Interest::all())
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

    fn time(line: &str) -> String {
        frame(line).time.expect("a time").to_string()
    }

    #[test]
    fn format_is_candump_screen() {
        assert_eq!(CandumpScreenParser::new().format(), Format::CandumpScreen);
    }

    #[test]
    fn plain_classic_frame() {
        let f = frame("  vcan0  1F4   [4]  01 02 03 04");
        assert_eq!(f.time, None);
        assert_eq!(f.channel, b"vcan0");
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x1F4, false, FrameKind::Data, 4)
        );
        assert_eq!(f.data.as_slice(), [1, 2, 3, 4]);
    }

    #[test]
    fn remote_request() {
        let f = frame(" (015.052211)  vcan0  00000123   [0]  remote request");
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x123, true, FrameKind::Remote, 0)
        );
        assert_eq!(f.time.unwrap().to_string(), "15.052211");
        assert!(f.data.is_empty());
        // The bracket holds the requested DLC, not carried data.
        let f = frame("  can0  081   [8]  remote request");
        assert_eq!((f.kind, f.len), (FrameKind::Remote, 0));
        assert_eq!(
            frame("  can0  081   {F}  remote request").kind,
            FrameKind::Remote
        );
        assert!(malformed("  can0  081   [8]  remote").contains("remote request"));
        assert!(malformed("  can0  081   [8]  remote request 11").contains("remote request"));
        assert!(malformed("  can0  20000004   [8]  remote request").contains("error frame"));
        assert!(malformed("  can0  081  [08]  remote request").contains("CAN FD"));
    }

    #[test]
    fn fd_frame_with_two_digit_length() {
        let f = frame("(1613749650.388103)  can1       0AD  [08]  A6 55 3B CF 3F 1A F5 2A");
        assert_eq!((f.id, f.kind, f.len), (0xAD, FrameKind::Fd, 8));
        assert_eq!(
            f.data.as_slice(),
            [0xA6, 0x55, 0x3B, 0xCF, 0x3F, 0x1A, 0xF5, 0x2A]
        );
        assert_eq!(f.time.unwrap().to_string(), "1613749650.388103");
        // One digit is classic, two digits are FD, whatever the value.
        assert_eq!(
            frame("  can1  0AD   [8]  00 00 00 00 00 00 00 00").kind,
            FrameKind::Data
        );
        assert_eq!(frame("  can1  0AD  [00]").kind, FrameKind::Fd);
    }

    #[test]
    fn fd_frame_with_64_bytes() {
        let bytes: Vec<String> = (0..64).map(|i| format!("{i:02X}")).collect();
        let line = format!("  can0  12345678  [64]  {}", bytes.join(" "));
        let f = frame(&line);
        assert_eq!((f.kind, f.len, f.extended), (FrameKind::Fd, 64, true));
        assert_eq!(f.data.as_slice(), (0..64).collect::<Vec<u8>>());
        let short = format!("  can0  123  [64]  {}", bytes[..63].join(" "));
        assert!(malformed(&short).contains("[64] but 63 data bytes"));
        let long = format!("  can0  123  [64]  {} 00", bytes.join(" "));
        assert!(malformed(&long).contains("[64] but 65 data bytes"));
        assert!(malformed("  can0  123  [65]").contains("max 64"));
        assert!(malformed("  can0  123  [99]").contains("max 64"));
    }

    #[test]
    fn error_frame_marker_is_not_a_byte() {
        let f = frame("  vcan0  20000004   [8]  00 00 00 00 00 00 00 00   ERRORFRAME");
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x004, false, FrameKind::Error, 8)
        );
        assert_eq!(f.data.as_slice(), [0; 8]);
        let f = frame("  can0  20001111   [7]  C6 23 7B 32 69 98 3C      ERRORFRAME");
        assert_eq!((f.kind, f.len), (FrameKind::Error, 7));
        assert!(
            malformed("  vcan0  20000004   [8]  00 00 00 00 00 00 00 00").contains("ERRORFRAME")
        );
        assert!(
            malformed("  vcan0  00000004   [2]  00 00   ERRORFRAME")
                .contains("without the error flag")
        );
        assert!(
            malformed("  vcan0  20000004   [2]  00 00   ERRORFRAME x").contains("after ERRORFRAME")
        );
        assert_eq!(
            frame("  vcan0  20000004   [2]  00 00   ERRORFRAME  // bus off?").kind,
            FrameKind::Error,
            "a note after ERRORFRAME"
        );
        assert!(malformed("  vcan0  20000004  [08]  00 00 00 00 00 00 00 00").contains("CAN FD"));
    }

    #[test]
    fn date_timestamp() {
        let f = frame(" (2018-12-06 09:31:30.572475)  can0  57E   [5]  C7 35 06 18 00");
        assert_eq!(f.time.unwrap().to_string(), "1544088690.572475");
        assert_eq!((f.id, f.len), (0x57E, 5));
        assert_eq!(f.data.as_slice(), [0xC7, 0x35, 0x06, 0x18, 0x00]);
    }

    #[test]
    fn date_timestamps_are_utc_and_exact() {
        let at = |date: &str| time(&format!(" ({date})  can0  081   [0]"));
        assert_eq!(at("1970-01-01 00:00:00.000000"), "0.000000");
        // Leap days, including the 400-year rule.
        assert_eq!(at("2020-02-29 23:59:59.999999"), "1583020799.999999");
        assert_eq!(at("2000-02-29 00:00:00.000001"), "951782400.000001");
        assert_eq!(at("2000-03-01 00:00:00.000000"), "951868800.000000");
        assert_eq!(at("2100-03-01 00:00:00.000000"), "4107542400.000000");
        assert_eq!(at("2024-12-31 23:59:59.123456789"), "1735689599.123456789");
        assert_eq!(at("2024-12-31 23:59:59"), "1735689599");
    }

    #[test]
    fn invalid_dates_are_malformed() {
        let bad = |date: &str| malformed(&format!(" ({date})  can0  081   [0]"));
        assert!(bad("2018-13-40 09:31:30.572475").contains("invalid date 2018-13-40"));
        assert!(bad("2018-00-10 09:31:30.572475").contains("invalid date"));
        assert!(bad("2018-12-00 09:31:30.572475").contains("invalid date"));
        assert!(bad("2018-04-31 09:31:30.572475").contains("invalid date"));
        assert!(bad("2019-02-29 09:31:30.572475").contains("invalid date"));
        assert!(bad("2100-02-29 09:31:30.572475").contains("invalid date"));
        assert!(bad("1969-12-31 23:59:59.000000").contains("before 1970"));
        assert!(bad("2018-12-06 24:00:00.000000").contains("time of day"));
        assert!(bad("2018-12-06 23:60:00.000000").contains("time of day"));
        assert!(bad("2018-12-06 23:00:60.000000").contains("time of day"));
        assert!(bad("2018-12-6 09:31:30.572475").contains("YYYY-MM-DD"));
        assert!(bad("2018-12-06 09:31.572475").contains("YYYY-MM-DD"));
        assert!(bad("2018-12-06-01 09:31:30.5").contains("YYYY-MM-DD"));
        assert!(bad("2018-12-06 09:31:30.").contains("dot"));
        assert!(bad("2018-12-06 09:31:30.5x").contains("decimal"));
        assert!(bad("2018-12-06").contains("YYYY-MM-DD"));
    }

    /// `parse_date` at the calendar's edges: exact seconds and fractions,
    /// exact messages.
    #[test]
    fn date_edges_are_exact() {
        let date = |text: &str| {
            parse_date(text.as_bytes())
                .map(|t| t.to_string())
                .map_err(Cow::into_owned)
        };
        let ok = |s: &str| Ok(s.to_string());
        let invalid_date = |d: &str| Err(format!("invalid date {d} (or before 1970)"));
        let invalid_time = |t: &str| Err(format!("invalid time of day {t}"));
        // The epoch and the last second before it.
        assert_eq!(date("1970-01-01 00:00:00"), ok("0"));
        assert_eq!(date("1970-01-01 00:00:00.000000"), ok("0.000000"));
        assert_eq!(date("1969-12-31 23:59:59"), invalid_date("1969-12-31"));
        assert_eq!(date("0000-01-01 00:00:00"), invalid_date("0000-01-01"));
        // The millennium, and 2000-02-29 (divisible by 400: a leap year).
        assert_eq!(date("1999-12-31 23:59:59.999999"), ok("946684799.999999"));
        assert_eq!(date("2000-01-01 00:00:00"), ok("946684800"));
        assert_eq!(date("2000-02-29 00:00:00"), ok("951782400"));
        assert_eq!(date("2000-02-29 23:59:59.5"), ok("951868799.5"));
        // 2100 is divisible by 100, not by 400: a common year.
        assert_eq!(date("2100-02-28 23:59:59"), ok("4107542399"));
        assert_eq!(date("2100-02-29 00:00:00"), invalid_date("2100-02-29"));
        assert_eq!(date("2024-02-29 23:59:59.123456"), ok("1709251199.123456"));
        assert_eq!(date("2023-02-29 00:00:00"), invalid_date("2023-02-29"));
        assert_eq!(date("2024-02-30 00:00:00"), invalid_date("2024-02-30"));
        // The 31st of the 30-day months; the 30th is fine.
        for month in ["04", "06", "09", "11"] {
            let d = format!("2023-{month}-31");
            assert_eq!(date(&format!("{d} 00:00:00")), invalid_date(&d));
        }
        assert_eq!(date("2023-04-30 23:59:59"), ok("1682899199"));
        assert_eq!(date("2023-01-31 00:00:00"), ok("1675123200"));
        assert_eq!(date("2023-01-32 00:00:00"), invalid_date("2023-01-32"));
        // Month 0 and 13, day 0.
        assert_eq!(date("2023-00-10 00:00:00"), invalid_date("2023-00-10"));
        assert_eq!(date("2023-13-10 00:00:00"), invalid_date("2023-13-10"));
        assert_eq!(date("2023-12-00 00:00:00"), invalid_date("2023-12-00"));
        assert_eq!(date("2023-99-99 00:00:00"), invalid_date("2023-99-99"));
        // The last date of four-digit years, with all 18 fraction digits.
        assert_eq!(
            date("9999-12-31 23:59:59.999999999999999999"),
            ok("253402300799.999999999999999999")
        );
        // The last second of a day; one past it in each field.
        assert_eq!(date("2018-12-06 23:59:59"), ok("1544140799"));
        assert_eq!(date("2018-12-06 24:00:00"), invalid_time("24:00:00"));
        assert_eq!(date("2018-12-06 23:60:00"), invalid_time("23:60:00"));
        assert_eq!(date("2018-12-06 23:59:60"), invalid_time("23:59:60"));
        assert_eq!(date("2018-12-06 99:99:99"), invalid_time("99:99:99"));
        // The date is checked first.
        assert_eq!(date("2100-02-29 24:00:00"), invalid_date("2100-02-29"));
    }

    #[test]
    fn numeric_timestamps_are_literal() {
        // -ta absolute, -tz zero-based, -td delta (not accumulated), -N nanoseconds.
        assert_eq!(
            time(" (1613749650.388103)  can0  081   [0]"),
            "1613749650.388103"
        );
        assert_eq!(time(" (000.000100)  can0  081   [0]"), "0.000100");
        assert_eq!(time(" (015.052211)  can0  081   [0]"), "15.052211");
        assert_eq!(time(" (001.000001)  can0  081   [0]"), "1.000001");
        assert_eq!(
            time(" (1613749650.388103123)  can0  081   [0]"),
            "1613749650.388103123"
        );
        assert_eq!(time(" (123456789012.5)  can0  081   [0]"), "123456789012.5");
        assert!(malformed(" (1.0  can0  081   [0]").contains("')'"));
        assert!(malformed(" (1.0)can0  081   [0]").contains("space"));
        assert!(malformed(" (x.0)  can0  081   [0]").contains("decimal"));
        assert!(malformed(" ()  can0  081   [0]").contains("integer part"));
    }

    #[test]
    fn extra_info_flags() {
        for flags in ["- -", "B -", "- E", "B E"] {
            for dir in ["RX", "TX"] {
                let line = format!(" (1.000000)  can0  {dir} {flags}  123  [02]  11 22");
                let f = frame(&line);
                assert_eq!((f.id, f.kind, f.len), (0x123, FrameKind::Fd, 2), "{line}");
                assert_eq!(f.data.as_slice(), [0x11, 0x22]);
                assert_eq!(f.channel, b"can0");
            }
        }
        assert!(malformed("  can0  RX E B  123   [0]").contains("flags pair"));
        assert!(malformed("  can0  RX -  123   [0]").contains("flags pair"));
        assert!(malformed("  can0  RX - -").contains("missing CAN id"));
    }

    #[test]
    fn ascii_column_with_spaces_and_quotes() {
        let f = frame("  can0  123   [4]  31 20 27 34   '1 '4'");
        assert_eq!(f.data.as_slice(), [0x31, 0x20, 0x27, 0x34]);
        let f = frame("  can0  14B0DC51   [8]  4A 94 E8 2A EC 58 55 62   'J..*.XUb'");
        assert_eq!(f.len, 8);
        assert_eq!(
            frame("  can0  123   [2]  27 27                     ''''").len,
            2
        );
        assert_eq!(
            frame("  can0  123   [2]  20 20                     '  '").len,
            2
        );
        assert_eq!(
            frame("  can0  123   [0]                            ''").len,
            0
        );
        assert!(malformed("  can0  123   [4]  31 20 27 34   '1 '5'").contains("does not match"));
        assert!(
            malformed("  can0  123   [4]  31 20 27 34   '1 '4")
                .contains("ASCII column must be 4 characters (one per data byte) between ' and '")
        );
        assert!(malformed("  can0  123   [4]  31 20 27 34   '").contains("found '"));
        assert!(malformed("  can0  123   [2]  31 32   '1' 2'").contains("found '1' 2'"));
        // A closed column holding a quote, then a note.
        let f = frame("    (000.000010)  vcan0  604   [2]  62 27   'b'' < response");
        assert_eq!(f.data.as_slice(), [0x62, 0x27]);
    }

    #[test]
    fn notes_after_the_frame_are_counted_not_errors() {
        let mut p = CandumpScreenParser::new();
        let all = Interest::all();
        let mut read = |line: &str| match p.parse(line.as_bytes(), &all) {
            Parsed::Frame(f) => (f.id, f.data.as_slice().to_vec(), p.take_annotated()),
            other => panic!("{line:?} -> {other:?}"),
        };
        let ok = |id, data: &[u8]| (id, data.to_vec(), true);
        assert_eq!(
            read("    (000.000010)  vcan0  603   [2]  A2 7F   '..' < response"),
            ok(0x603, &[0xA2, 0x7F])
        );
        assert_eq!(
            read("  can0  701   [1]  00   // boot of node 1"),
            ok(0x701, &[0])
        );
        assert_eq!(read("  can0  701   [1]  00   # boot"), ok(0x701, &[0]));
        assert_eq!(
            read("  can0  123   [2]  31 32   '12' <- 33"),
            ok(0x123, &[0x31, 0x32])
        );
        assert_eq!(
            read("  can0  701   [1]  remote request  < guard"),
            ok(0x701, &[])
        );
        // The common line stays unannotated, and a read clears the flag.
        assert_eq!(read("  can0  701   [1]  00"), (0x701, vec![0], false));
        assert!(!p.take_annotated());
        // Too few or too many bytes before a note say so.
        assert_eq!(
            malformed("  can0  123   [8]  31 32  < response"),
            "2 data bytes where the length field says 8, then '<'"
        );
        assert_eq!(
            malformed("  can0  123   [2]  31 32 33 // x"),
            "3 data bytes where the length field says 2, then '//'"
        );
        // A letter or digit after the frame is damage, not a note.
        assert!(malformed("  can0  081   [8]  remote request 11").contains("remote request"));
        assert_eq!(
            malformed("  can0  123   [2]  31 32   '12' 33"),
            "unexpected '33' after the ASCII column (a note after a frame starts with a sign such as //, # or <)"
        );
        assert!(malformed("  can0  123   [2]  31 32  boot").contains("'boot' is not"));
    }

    #[test]
    fn pasted_excerpts_skip_elisions_and_the_command_line() {
        for line in [
            "    ...",
            "\u{2026}",
            "candump can0",
            "$ candump -td -a vcan0",
            "",
            "    // SDO upload",
        ] {
            assert_eq!(parse(line), Parsed::Skipped, "{line:?}");
        }
    }

    #[test]
    fn raw_dlc_braces() {
        // -8 prints DLCs 9..F only on 8-byte frames; below that {X} is the length.
        let f = frame("  can0  321   {B}  11 22 33 44 55 66 77 88");
        assert_eq!((f.id, f.kind, f.len), (0x321, FrameKind::Data, 8));
        assert_eq!(f.data.as_slice()[7], 0x88);
        assert_eq!(frame("  can0  321   {3}  11 22 33").len, 3);
        assert_eq!(frame("  can0  321   {0}").len, 0);
        assert_eq!(frame("  can0  321   {8}  11 22 33 44 55 66 77 88").len, 8);
        assert_eq!(
            frame("  can0  20000004   {8}  00 00 00 00 00 00 00 00   ERRORFRAME").kind,
            FrameKind::Error
        );
        assert!(
            malformed("  can0  321   {B}  11 22 33")
                .contains("{B} (a raw DLC above 8 means 8 bytes) but 3")
        );
        assert!(malformed("  can0  321   {3}  11 22").contains("{3} but 2 data bytes"));
        assert!(malformed("  can0  321   {G}  11").contains("hex digit"));
        assert!(malformed("  can0  321   {10}  11").contains("{X}"));
    }

    #[test]
    fn indented_standard_ids_and_padded_names() {
        let f = frame("  can0       123   [3]  11 22 33");
        assert_eq!((f.id, f.extended), (0x123, false));
        let f = frame(" (0.5)   can0       081   [1]  11");
        assert_eq!((f.channel, f.id), (&b"can0"[..], 0x81));
        // Names are right-aligned to the longest one; odd characters are kept.
        assert_eq!(frame("   vcan-0  081   [0]").channel, b"vcan-0");
        assert_eq!(frame("  can0.1  081   [0]").channel, b"can0.1");
        // Pasted without the leading blanks, or indented with tabs.
        assert_eq!(frame("can0 081 [1] 11").id, 0x81);
        assert_eq!(frame("\tcan0\t081\t[1]\t11").id, 0x81);
        // log2long: time at column 0, always indented standard ids.
        assert_eq!(
            frame("(1.000000)  can0       123   [1]  11   '.'").id,
            0x123
        );
    }

    #[test]
    fn digit_count_not_value_decides_extended() {
        let f = frame("  can0  00000081   [1]  11");
        assert_eq!((f.id, f.extended), (0x81, true));
        assert!(!frame("  can0  081   [1]  11").extended);
    }

    #[test]
    fn colour_codes_are_ignored() {
        // -c: colour on before the name, off after it (or after -x info).
        let f = frame(" (1.000000)  \x1b[1m\x1b[34mcan0\x1b[0m  123   [2]  11 22");
        assert_eq!((f.channel, f.id, f.len), (&b"can0"[..], 0x123, 2));
        // -c -c: off after the frame, here right after the ASCII column.
        let f = frame("  \x1b[1m\x1b[31mcan1  123   [2]  31 32   '12'\x1b[0m");
        assert_eq!(
            (f.channel, f.data.as_slice()),
            (&b"can1"[..], &[0x31, 0x32][..])
        );
        let f = frame("  \x1b[1m\x1b[31mcan1  RX B E\x1b[0m  123  [01]  11\x1b[0m");
        assert_eq!((f.kind, f.len), (FrameKind::Fd, 1));
        // -c -c -c: colour on before the time.
        let f = frame(
            " \x1b[1;32m(1.5)  can0  20000004   [8]  00 00 00 00 00 00 00 00   ERRORFRAME\x1b[0m",
        );
        assert_eq!(
            (f.kind, f.time.unwrap().to_string()),
            (FrameKind::Error, "1.5".to_string())
        );
        // A stray ESC that starts no sequence is an ordinary (bad) byte.
        assert!(matches!(
            parse("  can0  123   [1]  1\x1b"),
            Parsed::Malformed(_)
        ));
        assert_eq!(parse("\x1b[0m"), Parsed::Skipped);
    }

    #[test]
    fn error_explanations_are_skipped() {
        for line in [
            "\tcontroller-problem{rx-error-warning}",
            "\tprotocol-violation{{bit-stuffing-error}{data-field}}",
            "\tlost-arbitration{at bit 3}",
            "\tbus-off\x1b[0m",
            "\terror-counter-tx-rx{{0}{5}}",
        ] {
            assert_eq!(parse(line), Parsed::Skipped, "{line:?}");
        }
        // A tab-indented line that is a frame stays a frame; tab + garbage is malformed.
        assert_eq!(frame("\t  can0  081   [1]  11").id, 0x81);
        assert!(matches!(parse("\t(garbage"), Parsed::Malformed(_)));
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
    fn binary_and_swapped_views() {
        // -i: eight binary digits per byte.
        let f = frame("  can0  123   [2]  00010001 11111111");
        assert_eq!(f.data.as_slice(), [0x11, 0xFF]);
        // -S: last byte first, joined by backticks; ASCII column in backticks.
        let f = frame("  can0  123   [3]  33`32`31                 `321`");
        assert_eq!(f.data.as_slice(), [0x31, 0x32, 0x33]);
        let f = frame("  can0  123   [2]  11111111`00010001");
        assert_eq!(f.data.as_slice(), [0x11, 0xFF]);
        assert!(malformed("  can0  123   [2]  11 00010001").contains("mixes"));
        assert!(malformed("  can0  123   [3]  33`32 31").contains("one group"));
        assert!(malformed("  can0  123   [2]  33``32").contains("not two hex digits"));
    }

    #[test]
    fn count_mismatch_says_both_numbers() {
        assert!(malformed("  can0  123   [8]  01 02 03 04 05").contains("[8] but 5 data bytes"));
        assert!(malformed("  can0  123   [0]  01").contains("[0] but 1 data bytes"));
        assert!(malformed("  can0  123   [1]").contains("[1] but 0 data bytes"));
    }

    #[test]
    fn uninteresting_frames_are_validated_but_not_decoded() {
        let mut interest = Interest::none();
        interest.add_standard(0x81);
        let mut p = CandumpScreenParser::new();
        match p.parse(b" (1.000000)  can0  123   [2]  11 22", &interest) {
            Parsed::Frame(f) => {
                assert_eq!((f.id, f.len), (0x123, 2));
                assert!(f.data.is_empty());
                assert!(f.time.is_none());
            }
            other => panic!("{other:?}"),
        }
        match p.parse(b" (1.000000)  can0  081   [2]  11 22", &interest) {
            Parsed::Frame(f) => {
                assert_eq!(f.data.as_slice(), [0x11, 0x22]);
                assert_eq!(f.time.unwrap().to_string(), "1.000000");
            }
            other => panic!("{other:?}"),
        }
        for bad in [
            &b" (1.000000)  can0  123   [2]  11 ZZ"[..],
            b" (1.000000)  can0  123   [2]  11",
            b" (2018-13-40 00:00:00.0)  can0  123   [2]  11 22",
            b" (1.000000)  can0  12345678   [2]  11 22   'xx'",
        ] {
            assert!(
                matches!(p.parse(bad, &interest), Parsed::Malformed(_)),
                "{}",
                bad.escape_ascii()
            );
        }
    }

    #[test]
    fn malformed_lines_say_why() {
        assert!(malformed("  can0  0081   [1]  11").contains("4 digits"));
        assert!(malformed("  can0  81   [1]  11").contains("2 digits"));
        assert!(malformed("  can0  123456789   [1]  11").contains("9 digits"));
        assert!(malformed("  can0  08G   [1]  11").contains("not hexadecimal"));
        assert!(malformed("  can0  800   [1]  11").contains("exceeds 7FF"));
        assert!(malformed("  can0  40000000   [1]  11").contains("29"));
        assert!(malformed("  can0  123   [2]  11 ZZ").contains("'ZZ' is not hexadecimal"));
        assert!(malformed("  can0  123   [2]  11 2").contains("not two hex digits"));
        assert!(malformed("  can0  123").contains("missing length field"));
        assert!(malformed("  can0  123  11 22").contains("missing length field"));
        assert!(malformed("  can0  123   [9]  11").contains("too large"));
        assert!(malformed("  can0  123   [x]  11").contains("not a number"));
        assert!(malformed("  can0  123   [123]").contains("[n], [nn]"));
        assert!(malformed("  can0").contains("missing CAN id"));
        assert!(malformed("  can0  [1]  11").contains("missing interface name or CAN id"));
        assert!(malformed(" (1.0)").contains("missing interface name"));
        assert!(
            malformed("  can0       123 [0003] (45|81:00:12345678) 11 22 33").contains("CAN XL")
        );
        let long_id = format!("  can0  {}   [0]", "1".repeat(10_000));
        let reason = malformed(&long_id);
        assert!(
            reason.contains("10000 digits") && reason.len() < 200,
            "{reason}"
        );
        // Control bytes are escaped in reasons.
        assert!(malformed("  can0  1\x07   [0]").contains("\\x07"));
    }

    #[test]
    fn other_formats_are_not_read_as_screen_frames() {
        // Detection relies on these not being frames.
        assert!(malformed("(1469439874.299654) can1 701#7F").contains("log format"));
        for line in [
            "   3.098426 1  18EBFF00x       Rx d 8 01 A0 0F A6 60 3B D1 40",
            "   0.003287 1  123             Rx   d 8 11 22 33 44 55 66 77 88",
            "date Sam Sep 30 15:06:13.191 2017",
            "base hex  timestamps absolute",
            "   0.000000 Start of measurement",
        ] {
            assert!(matches!(parse(line), Parsed::Malformed(_)), "{line}");
        }
    }

    /// xorshift64: deterministic pseudo-random numbers without a dependency.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            let mut x = self.0;
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            self.0 = x;
            x
        }

        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
    }

    const VALID: [&str; 12] = [
        "  vcan0  1F4   [4]  01 02 03 04",
        " (015.052211)  vcan0  00000123   [0]  remote request",
        "(1613749650.388103)  can1       0AD  [08]  A6 55 3B CF 3F 1A F5 2A",
        "  vcan0  20000004   [8]  00 00 00 00 00 00 00 00   ERRORFRAME",
        " (2018-12-06 09:31:30.572475)  can0  57E   [5]  C7 35 06 18 00",
        "  can0  123   [4]  31 20 27 34   '1 '4'",
        " (1.000000)  can0  TX B E  123  [02]  11 22",
        "  can0  321   {B}  11 22 33 44 55 66 77 88",
        " \x1b[1;32m(1.5)  \x1b[1m\x1b[34mcan0\x1b[0m  081   [2]  11 22\x1b[0m",
        "  can0  123   [3]  33`32`31                 `321`",
        "  can0  123   [2]  00010001 11111111",
        "\tcontroller-problem{rx-error-warning}",
    ];

    #[test]
    fn valid_corpus_parses() {
        for line in VALID {
            assert!(!matches!(parse(line), Parsed::Malformed(_)), "{line:?}");
        }
    }

    #[test]
    fn never_panics_on_random_or_damaged_lines() {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let mut p = CandumpScreenParser::new();
        let all = Interest::all();
        let mut some = Interest::none();
        some.add_standard(0x81);
        let mut check = |line: &[u8]| {
            let _ = p.parse(line, &all);
            let _ = p.parse(line, &some);
        };
        // Random bytes, and random strings over the format's own alphabet.
        let alphabet =
            b" \t()[]{}-:.'`#0123456789ABCDEFabcdefRXTBE\x1b\x7fm;remote request ERRORFRAME";
        for _ in 0..400 {
            let len = rng.below(120);
            let random: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
            check(&random);
            let letters: Vec<u8> = (0..len)
                .map(|_| alphabet[rng.below(alphabet.len())])
                .collect();
            check(&letters);
        }
        // Every truncation of every valid line, and random byte mutations.
        for line in VALID {
            let bytes = line.as_bytes();
            for cut in 0..=bytes.len() {
                check(&bytes[..cut]);
                check(&bytes[cut..]);
            }
            for _ in 0..100 {
                let mut m = bytes.to_vec();
                for _ in 0..1 + rng.below(3) {
                    let i = rng.below(m.len());
                    match rng.below(3) {
                        0 => m[i] = rng.next() as u8,
                        1 => {
                            m.remove(i);
                        }
                        _ => m.insert(i, alphabet[rng.below(alphabet.len())]),
                    }
                    if m.is_empty() {
                        break;
                    }
                }
                check(&m);
            }
        }
        // Extremes: huge numbers, long lines, many colour codes.
        check(b" (99999999999999999999.0)  can0  081   [0]");
        check(b" (9999-12-31 23:59:59.999999999999999999)  can0  081   [0]");
        check(b" (9999-12-31 23:59:59.9999999999999999999)  can0  081   [0]");
        check(format!("  can0  123  [64]  {}", "FF ".repeat(5000)).as_bytes());
        check("\x1b[".repeat(5000).as_bytes());
        check(format!("  can0  123   [1]  11   '{}", "'".repeat(5000)).as_bytes());
    }
}
