//! PEAK TRC (PCAN-View, PCAN-Explorer, PEAK-Converter), versions 1.0 to 2.1:
//!
//! ```text
//! ;$FILEVERSION=2.1
//! ;$STARTTIME=41766.4648963872
//! ;$COLUMNS=N,O,T,B,I,d,R,L,D
//!       1      1059.900 DT 1      0300 Rx -  7    00 00 00 00 04 00 00
//!      13      1336.543 RR 1      0100 Rx -  3
//! ```
//!
//! Older versions have fixed columns: `N)` number, offset, then
//! 1.0 `ID DLC data`, 1.1 `Type ID DLC data`, 1.2 `Bus Type ID DLC data`,
//! 1.3 `Bus Type ID Reserved DLC data`. A file without `;$FILEVERSION` is 1.0.
//!
//! Times: the offset column is milliseconds since `;$STARTTIME`, which is
//! days since 1899-12-30 (taken as UTC: the file does not say). The sum is
//! kept exactly (a day fraction times 86400 is a finite decimal). Without a
//! start time, or with one before 1970 (PEAK writes 0 when unknown), times
//! are seconds since the start of the measurement, like relative ASC.
//!
//! Ids: up to 4 hex digits are standard ids, 5 to 8 extended (PEAK writes 4
//! and 8; the digit count decides, like candump). Files without a bus column
//! put every frame on channel `1`, PEAK's first bus.
//!
//! Skipped: `;` comments and headers, blank lines, status rows (v1 `Warng`
//! and id `FFFFFFFF`; v2 `ST`, `EC`, `EV`). `Error`/`ERROR`/`ER` rows are
//! error frames; `RTR` rows and `RR` are remote frames; `FD`, `FB`, `FE`,
//! `BI` are CAN FD frames (never an EMCY).

use crate::error_frame::{ErrorFrame, protocol};
use crate::{
    Format, Frame, FrameKind, Interest, LineParser, Parsed, Payload, Reason, Scan, Timestamp,
    show_token as show,
};
use crate::{hex, is_blank, trim_start};

/// A PEAK error frame (a TRC error row, as PCAN-Basic hands it over) in the
/// SocketCAN representation: the one place that says what its fields mean.
///
/// | field | values | error.h |
/// |---|---|---|
/// | type | 1 bit, 2 form, 4 stuff, 8 other (bits) | the protocol type byte; other: unspecified |
/// | direction | 0 transmitting, 1 receiving | `CAN_ERR_PROT_TX` |
/// | position | the SJA1000 segment code | the location byte (its codes) |
/// | RX, TX counters | 0-255 | data\[7\], data\[6\], `CAN_ERR_CNT` |
fn peak_error(kind: u8, direction: u8, position: u8, counters: Option<(u8, u8)>) -> ErrorFrame {
    let mut e = ErrorFrame::default();
    for (bit, violation) in [
        (1, protocol::BIT),
        (2, protocol::FORM),
        (4, protocol::STUFF),
        (8, protocol::UNSPECIFIED),
    ] {
        if kind & bit != 0 {
            e.violation(violation);
        }
    }
    if e.class != 0 {
        e.at(position & 0x1F);
        if direction == 0 {
            e.transmitting();
        }
        e.with_ack_inferred();
    }
    if let Some((rx, tx)) = counters {
        e.counters(tx, rx);
    }
    e
}

/// The trailing run of two-digit hex tokens of an error row, at most 8.
fn error_bytes(tokens: &[&[u8]]) -> Vec<u8> {
    let run = tokens
        .iter()
        .rev()
        .take_while(|t| t.len() == 2 && t.iter().all(u8::is_ascii_hexdigit))
        .count()
        .min(8);
    tokens
        .get(tokens.len() - run..)
        .unwrap_or_default()
        .iter()
        .filter_map(|t| hex::parse_u32(t).and_then(|v| u8::try_from(v).ok()))
        .collect()
}

/// The TRC file versions (`;$FILEVERSION=`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Version {
    /// Version 1.0: `N) offset ID DLC data`.
    V1_0,
    /// Version 1.1: `N) offset Type ID DLC data`.
    V1_1,
    /// Version 1.2: `N) offset Bus Type ID DLC data`.
    V1_2,
    /// Version 1.3: `N) offset Bus Type ID Reserved DLC data`.
    V1_3,
    /// Version 2.0: fixed columns, the same in every file.
    V2_0,
    /// Version 2.1: the columns as `;$COLUMNS` names them.
    V2_1,
}

impl Version {
    fn parse(text: &[u8]) -> Option<Version> {
        Some(match text {
            b"1.0" => Version::V1_0,
            b"1.1" => Version::V1_1,
            b"1.2" => Version::V1_2,
            b"1.3" => Version::V1_3,
            b"2.0" => Version::V2_0,
            b"2.1" => Version::V2_1,
            _ => return None,
        })
    }

    fn is_v2(self) -> bool {
        matches!(self, Version::V2_0 | Version::V2_1)
    }
}

/// Where the columns of a version 2 row are (`;$COLUMNS=`), as token indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Columns {
    offset: u8,
    kind: u8,
    bus: Option<u8>,
    id: u8,
    dir: Option<u8>,
    /// `L` (a DLC) or `l` (a byte count) and its index.
    len: (u8, bool),
    /// The data column, always the last one.
    data: u8,
    count: u8,
}

impl Columns {
    /// `N,O,T,I,d,l,D`, version 2.0's columns.
    const V2_0: Columns = Columns {
        offset: 1,
        kind: 2,
        bus: None,
        id: 3,
        dir: Some(4),
        len: (5, false),
        data: 6,
        count: 7,
    };
    /// `N,O,T,B,I,d,R,L,D`, version 2.1's columns.
    const V2_1: Columns = Columns {
        offset: 1,
        kind: 2,
        bus: Some(3),
        id: 4,
        dir: Some(5),
        len: (7, true),
        data: 8,
        count: 9,
    };

    fn parse(text: &[u8]) -> Result<Columns, Reason> {
        let mut offset = None;
        let mut kind = None;
        let mut bus = None;
        let mut id = None;
        let mut dir = None;
        let mut len = None;
        let mut data = None;
        let mut count = 0u8;
        for (i, name) in text.split(|b| *b == b',').enumerate() {
            let i = u8::try_from(i).map_err(|_| "too many columns in ;$COLUMNS")?;
            let name = crate::trim_end(trim_start(name));
            let slot = match name {
                b"N" | b"R" => None,
                b"O" => Some(&mut offset),
                b"T" => Some(&mut kind),
                b"B" => Some(&mut bus),
                b"I" => Some(&mut id),
                b"d" => Some(&mut dir),
                b"L" | b"l" => {
                    if len.replace((i, name.contains(&b'L'))).is_some() {
                        return Err(";$COLUMNS names the length twice (L and l)".into());
                    }
                    None
                }
                b"D" => Some(&mut data),
                other => {
                    return Err(format!("unknown column '{}' in ;$COLUMNS", show(other)).into());
                }
            };
            if let Some(slot) = slot
                && slot.replace(i).is_some()
            {
                return Err("a column appears twice in ;$COLUMNS".into());
            }
            count = i + 1;
        }
        let need = |c: Option<u8>, what: &str| -> Result<u8, Reason> {
            c.ok_or_else(|| format!(";$COLUMNS has no {what} column").into())
        };
        let cols = Columns {
            offset: need(offset, "time offset (O)")?,
            kind: need(kind, "type (T)")?,
            bus,
            id: need(id, "id (I)")?,
            dir,
            len: len.ok_or(";$COLUMNS has no length column (L or l)")?,
            data: need(data, "data (D)")?,
            count,
        };
        if cols.data + 1 != count {
            return Err(";$COLUMNS: the data column (D) must be the last one".into());
        }
        Ok(cols)
    }
}

/// Reads PEAK TRC lines; headers set the version, start time and columns.
#[derive(Clone, Debug)]
pub struct TrcParser {
    version: Version,
    columns: Columns,
    /// The start time in attoseconds since the Unix epoch, and the fraction
    /// digits it needs; `None` for times relative to the measurement start.
    start: Option<(u128, u8)>,
    /// Header lines that changed the state (the parallel reader's context).
    changes: u16,
    /// A `;$FILEVERSION`, `;$STARTTIME` or `;$COLUMNS` line was read: only
    /// PEAK writes them, so the file is a TRC before its first frame, and a
    /// header it cannot read is reported rather than taken for a comment.
    identified: bool,
}

impl TrcParser {
    /// A parser before the first line (the header sets the version).
    pub fn new() -> Self {
        TrcParser {
            version: Version::V1_0,
            columns: Columns::V2_1,
            start: None,
            changes: 0,
            identified: false,
        }
    }

    #[cfg(test)]
    fn version(&self) -> Version {
        self.version
    }
}

impl Default for TrcParser {
    fn default() -> Self {
        TrcParser::new()
    }
}

impl LineParser for TrcParser {
    fn format(&self) -> Format {
        Format::Trc
    }

    /// Headers change the state; they come first in every real file, so a
    /// count of changes tells forks apart exactly (until it saturates).
    fn context(&self) -> Option<u8> {
        u8::try_from(self.changes).ok().filter(|c| *c < u8::MAX)
    }

    fn identified(&self) -> bool {
        self.identified
    }

    #[inline]
    fn scan<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Scan<'a> {
        // Header lines change the state: leave them to `parse`.
        if trim_start(line).first() == Some(&b';') {
            return Scan::Parse;
        }
        match self.row(line, interest) {
            // An error frame's id is its class bits, no identifier: it is
            // wanted as error frames are.
            // (Unwanted, it is parsed and counted as an error frame, which
            // no key can say.)
            Ok(Some(f)) if f.kind == FrameKind::Error => {
                if interest.wants_error_frames() {
                    Scan::Frame(f)
                } else {
                    Scan::Parse
                }
            }
            Ok(Some(f)) if !interest.wants(f.id, f.extended) => Scan::Plain(f.key()),
            Ok(Some(f))
                if f.kind == FrameKind::Data
                    && interest.timed_only(f.id, f.extended, f.data.as_slice()) =>
            {
                f.time.map_or(Scan::Parse, |t| Scan::Timed(t, f.key()))
            }
            Ok(Some(f)) => Scan::Frame(f),
            _ => Scan::Parse,
        }
    }

    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        let t = trim_start(line);
        if let Some(comment) = t.strip_prefix(b";") {
            return match self.header(comment) {
                Ok(()) => Parsed::Skipped,
                Err(reason) => Parsed::Malformed(reason),
            };
        }
        if is_blank(t) {
            return Parsed::Skipped;
        }
        match self.row(line, interest) {
            Ok(Some(frame)) => Parsed::Frame(frame),
            Ok(None) => Parsed::Skipped,
            Err(reason) => Parsed::Malformed(reason),
        }
    }
}

/// At most this many fields on a row: 9 columns and 64 data bytes, with room.
const MAX_FIELDS: usize = 80;

/// Days from 1899-12-30 (the TRC epoch) to 1970-01-01.
const UNIX_EPOCH_DAY: u64 = 25569;
/// Days from 1899-12-30 to 9999-12-31, the last day a start may be (as in
/// spreadsheets, whose day count TRC uses).
const LAST_DAY: u64 = 2_958_465;
const ATTO: u128 = 1_000_000_000_000_000_000;

impl TrcParser {
    /// A `;` line: `$FILEVERSION`, `$STARTTIME`, `$COLUMNS` or a comment.
    fn header(&mut self, comment: &[u8]) -> Result<(), Reason> {
        let Some(rest) = comment.strip_prefix(b"$") else {
            return Ok(());
        };
        let Some(eq) = memchr::memchr(b'=', rest) else {
            return Ok(());
        };
        let (key, value) = (&rest[..eq], &rest[eq + 1..]);
        // `;$STARTTIME=39878.6772258947;` occurs (PEAK's own example).
        let value = crate::trim_end(trim_start(value));
        let value = value.strip_suffix(b";").unwrap_or(value);
        if matches!(key, b"FILEVERSION" | b"STARTTIME" | b"COLUMNS") {
            self.identified = true;
        }
        match key {
            b"FILEVERSION" => {
                let v = Version::parse(value).ok_or_else(|| {
                    format!(
                        "unsupported TRC file version '{}' (1.0-1.3, 2.0, 2.1 are read)",
                        show(value)
                    )
                })?;
                self.version = v;
                self.columns = if v == Version::V2_0 {
                    Columns::V2_0
                } else {
                    Columns::V2_1
                };
            }
            b"STARTTIME" => self.start = start_time(value)?,
            b"COLUMNS" => self.columns = Columns::parse(value)?,
            _ => return Ok(()),
        }
        self.changes = self.changes.saturating_add(1);
        Ok(())
    }

    /// A data row: `Ok(None)` for status rows.
    fn row<'a>(&self, line: &'a [u8], interest: &Interest) -> Result<Option<Frame<'a>>, Reason> {
        let mut fields: [&[u8]; MAX_FIELDS] = [&[]; MAX_FIELDS];
        let mut n = 0;
        for f in line
            .split(|b| *b == b' ' || *b == b'\t')
            .filter(|f| !f.is_empty())
        {
            let slot = fields
                .get_mut(n)
                .ok_or("too many fields for a TRC row (at most 64 data bytes)")?;
            *slot = f;
            n += 1;
        }
        let fields = fields.get(..n).unwrap_or_default();
        if self.version.is_v2() {
            self.row_v2(fields, interest)
        } else {
            self.row_v1(fields, interest)
        }
    }

    fn row_v1<'a>(&self, f: &[&'a [u8]], interest: &Interest) -> Result<Option<Frame<'a>>, Reason> {
        let (number, offset) = match f {
            [number, offset, ..] => (*number, *offset),
            _ => return Err("expected 'N)' and a time offset".into()),
        };
        match number.strip_suffix(b")") {
            Some(digits) if is_digits(digits) => {}
            _ => return Err("expected a message number followed by ')'".into()),
        }
        let (bus, kind, rest) = match (self.version, f.get(2..).unwrap_or_default()) {
            (Version::V1_0, rest) => (None, None, rest),
            (Version::V1_1, [kind, rest @ ..]) => (None, Some(*kind), rest),
            (Version::V1_2 | Version::V1_3, [bus, kind, rest @ ..]) => {
                (Some(*bus), Some(*kind), rest)
            }
            _ => return Err("row ends before the id".into()),
        };
        let (id_text, rest) = match (self.version, rest) {
            (Version::V1_3, [id, _reserved, rest @ ..]) => (*id, rest),
            (Version::V1_3, _) => return Err("row ends before the data length".into()),
            (_, [id, rest @ ..]) => (*id, rest),
            (_, []) => return Err("row ends before the id".into()),
        };
        let channel = channel(bus)?;
        // Bus status rows: `Warng` or the id FFFFFFFF (version 1.0).
        if kind == Some(b"Warng") || id_text == b"FFFFFFFF" {
            return Ok(None);
        }
        let error = match kind {
            None | Some(b"Rx" | b"Tx") => false,
            Some(b"Error") => true,
            Some(other) => {
                return Err(format!("unknown message type '{}'", show(other)).into());
            }
        };
        let (id, extended) = parse_id(id_text)?;
        let [dlc_text, data @ ..] = rest else {
            return Err("row ends before the data length".into());
        };
        let dlc = hex::parse_dec_u32(dlc_text)
            .filter(|d| *d <= 15)
            .ok_or_else(|| format!("'{}' is not a data length code (0-15)", show(dlc_text)))?;
        let len = dlc.min(8) as u8;
        let time = || self.time(offset);
        if error || data.first() == Some(&&b"ERROR"[..]) {
            // Version 1 rows: the id is the error type, the data the
            // direction, the position and the counters (after `ERROR` in 1.0).
            let bytes = data.strip_prefix(&[&b"ERROR"[..]]).unwrap_or(data);
            let fields = error_bytes(bytes);
            let e = match (u8::try_from(id).ok(), fields.as_slice()) {
                (Some(kind), [dir, position, rx, tx]) => {
                    peak_error(kind, *dir, *position, Some((*rx, *tx)))
                }
                _ => ErrorFrame::default(),
            };
            return Ok(Some(e.frame(Some(time()?), channel)));
        }
        if data == [&b"RTR"[..]] {
            return Ok(Some(remote_frame(time()?, channel, id, extended, interest)));
        }
        frame(
            time,
            channel,
            (id, extended),
            FrameKind::Data,
            len,
            data,
            interest,
        )
        .map(Some)
    }

    fn row_v2<'a>(&self, f: &[&'a [u8]], interest: &Interest) -> Result<Option<Frame<'a>>, Reason> {
        let c = &self.columns;
        let at = |i: u8| f.get(usize::from(i)).copied();
        let kind = at(c.kind).ok_or("row ends before the message type")?;
        let offset = at(c.offset).ok_or("row ends before the time offset")?;
        let time = || self.time(offset);
        let (frame_kind, fd_len) = match kind {
            b"DT" => (FrameKind::Data, false),
            b"FD" | b"FB" | b"FE" | b"BI" => (FrameKind::Fd, true),
            b"RR" => (FrameKind::Remote, false),
            // Hardware status, error counter change, user event.
            b"ST" | b"EC" | b"EV" => return Ok(None),
            b"ER" => {
                let channel = channel(c.bus.and_then(at))?;
                // The error type, direction, position, RX and TX counters
                // are the row's last five bytes (version 2.0 leaves the id
                // column empty, so the columns do not place them).
                let fields = error_bytes(f);
                let e = match fields.as_slice() {
                    [.., kind, dir, position, rx, tx] => {
                        peak_error(*kind, *dir, *position, Some((*rx, *tx)))
                    }
                    _ => ErrorFrame::default(),
                };
                return Ok(Some(e.frame(Some(time()?), channel)));
            }
            other => return Err(format!("unknown message type '{}'", show(other)).into()),
        };
        if f.len() < usize::from(c.data) {
            return Err("row ends before the data length".into());
        }
        let channel = channel(c.bus.and_then(at))?;
        let (id, extended) = parse_id(at(c.id).ok_or("row has no id")?)?;
        if let Some(dir) = c.dir.and_then(at)
            && dir != b"Rx"
            && dir != b"Tx"
        {
            return Err(format!("expected Rx or Tx, not '{}'", show(dir)).into());
        }
        let (len_at, is_dlc) = c.len;
        let len_text = at(len_at).ok_or("row ends before the data length")?;
        let value = hex::parse_dec_u32(len_text)
            .ok_or_else(|| format!("'{}' is not a data length", show(len_text)))?;
        let len = match (is_dlc, fd_len) {
            (true, true) => dlc_to_len(value),
            (true, false) if value <= 15 => Some(value.min(8) as u8),
            (false, true) if value <= 64 => Some(value as u8),
            (false, false) if value <= 8 => Some(value as u8),
            _ => None,
        }
        .ok_or_else(|| format!("data length {value} is out of range"))?;
        let data = f.get(usize::from(c.data)..).unwrap_or_default();
        if frame_kind == FrameKind::Remote {
            if !data.is_empty() {
                return Err("a remote request carries no data".into());
            }
            return Ok(Some(remote_frame(time()?, channel, id, extended, interest)));
        }
        frame(
            time,
            channel,
            (id, extended),
            frame_kind,
            len,
            data,
            interest,
        )
        .map(Some)
    }

    /// Start time plus an offset in milliseconds, exactly.
    fn time(&self, offset: &[u8]) -> Result<Timestamp, Reason> {
        let (int, frac) = match memchr::memchr(b'.', offset) {
            Some(dot) => (&offset[..dot], &offset[dot + 1..]),
            None => (offset, &b""[..]),
        };
        if int.is_empty()
            || int.len() > 19
            || frac.len() > 15
            || !is_digits(int)
            || !frac.iter().all(u8::is_ascii_digit)
            || (frac.is_empty() && offset.ends_with(b"."))
        {
            return Err(format!("'{}' is not a time offset in ms", show(offset)).into());
        }
        let ms = u128::from(crate::scan::decimal_u64(int));
        let frac_digits = frac.len() as u32;
        let atto = ms * 1_000_000_000_000_000
            + u128::from(crate::scan::decimal_u64(frac)) * 10u128.pow(15 - frac_digits);
        let (start, start_digits) = self.start.unwrap_or((0, 0));
        let total = start + atto;
        let digits = (frac_digits as u8 + 3).max(start_digits);
        u64::try_from(total / ATTO)
            .ok()
            .and_then(|secs| Timestamp::from_raw(secs, (total % ATTO) as u64, digits))
            .ok_or_else(|| "time offset is out of range".into())
    }
}

/// Builds a data or FD frame from `len` hex data bytes, decoding the time and
/// the data only when the id is wanted.
fn frame<'a>(
    time: impl FnOnce() -> Result<Timestamp, Reason>,
    channel: &'a [u8],
    (id, extended): (u32, bool),
    kind: FrameKind,
    len: u8,
    data: &[&[u8]],
    interest: &Interest,
) -> Result<Frame<'a>, Reason> {
    if data.len() != usize::from(len) {
        return Err(format!(
            "the length says {len} data bytes but the row has {}",
            data.len()
        )
        .into());
    }
    let wanted = interest.wants(id, extended);
    let mut payload = Payload::new();
    for b in data {
        let byte = match b {
            [hi, lo] => hex::parse_byte(*hi, *lo),
            _ => None,
        }
        .ok_or_else(|| format!("'{}' is not a data byte (two hex digits)", show(b)))?;
        if wanted {
            payload.push(byte);
        }
    }
    // The time is validated for every frame, kept for wanted ones.
    let t = time()?;
    Ok(Frame {
        time: wanted.then_some(t),
        channel,
        id,
        extended,
        kind,
        len,
        data: payload,
    })
}

/// The bus column as the channel; `1` when the file has none.
fn channel(bus: Option<&[u8]>) -> Result<&[u8], Reason> {
    match bus {
        None => Ok(b"1"),
        Some(b) if is_digits(b) => Ok(b),
        Some(b) => Err(format!("'{}' is not a bus number", show(b)).into()),
    }
}

/// 1-4 hex digits: a standard id; 5-8: an extended id.
fn parse_id(text: &[u8]) -> Result<(u32, bool), Reason> {
    let value = hex::parse_u32(text)
        .ok_or_else(|| format!("'{}' is not an id (1-8 hex digits)", show(text)))?;
    match text.len() {
        1..=4 if value <= 0x7FF => Ok((value, false)),
        1..=4 => Err(format!("standard id {value:X} is over 7FF").into()),
        _ if value <= 0x1FFF_FFFF => Ok((value, true)),
        _ => Err(format!("extended id {value:X} is over 1FFFFFFF").into()),
    }
}

/// CAN FD DLC to byte count.
fn dlc_to_len(dlc: u32) -> Option<u8> {
    Some(match dlc {
        0..=8 => dlc as u8,
        9 => 12,
        10 => 16,
        11 => 20,
        12 => 24,
        13 => 32,
        14 => 48,
        15 => 64,
        _ => return None,
    })
}

/// `;$STARTTIME=` days since 1899-12-30 (decimal) to attoseconds since the
/// Unix epoch and the digits they need; `None` before 1970.
fn start_time(value: &[u8]) -> Result<Option<(u128, u8)>, Reason> {
    let bad = || -> Reason {
        format!(
            "'{}' is not a start time in days (since 1899-12-30, up to the year 9999): times are \
             seconds since the start of the measurement",
            show(value)
        )
        .into()
    };
    let (int, frac) = match memchr::memchr(b'.', value) {
        Some(dot) => (&value[..dot], &value[dot + 1..]),
        None => (value, &b""[..]),
    };
    if int.is_empty() || int.len() > 9 || frac.len() > 18 || !is_digits(int) {
        return Err(bad());
    }
    if !frac.iter().all(u8::is_ascii_digit) {
        return Err(bad());
    }
    let days = crate::scan::decimal_u64(int);
    if days < UNIX_EPOCH_DAY {
        return Ok(None);
    }
    // A start after the year 9999 is no date any trace was written on, and
    // no time could show it as one.
    if days > LAST_DAY {
        return Err(bad());
    }
    // frac < 10^18, so frac * 86400 * 10^(18 - n) < 86400 * 10^18: fits.
    let frac_atto =
        u128::from(crate::scan::decimal_u64(frac)) * 86_400 * 10u128.pow(18 - frac.len() as u32);
    let total = u128::from(days - UNIX_EPOCH_DAY) * 86_400 * ATTO + frac_atto;
    // The digits the exact value needs (trailing zeros dropped).
    let mut digits = 18u8;
    let mut rest = total % ATTO;
    while digits > 0 && rest.is_multiple_of(10) {
        rest /= 10;
        digits -= 1;
    }
    Ok(Some((total, digits)))
}

fn is_digits(s: &[u8]) -> bool {
    !s.is_empty() && s.iter().all(u8::is_ascii_digit)
}

/// Fuzz target body: any bytes, line by line, must classify without a
/// panic, and frames must be well-formed.
#[cfg(feature = "fuzzing")]
pub fn fuzz_trc(data: &[u8]) {
    let mut p = TrcParser::new();
    let all = Interest::all();
    let none = Interest::none();
    for line in data.split(|b| *b == b'\n') {
        let plain = match p.clone().scan(line, &none) {
            Scan::Plain(key) => Some(key),
            _ => None,
        };
        let parsed = p.parse(line, &all);
        if let Parsed::Frame(f) = &parsed {
            assert!(usize::from(f.len) <= Payload::MAX);
            if f.kind == FrameKind::Data || f.kind == FrameKind::Fd {
                assert_eq!(f.data.len(), usize::from(f.len));
            }
            assert!(f.extended || f.id <= 0x7FF);
            assert!(f.id <= 0x1FFF_FFFF);
            assert!(f.time.is_some());
        }
        if let Some(key) = plain {
            let Parsed::Frame(f) = &parsed else {
                panic!("scan took a non-frame");
            };
            assert_eq!(key, f.key(), "counted under another key than the frame's");
        }
    }
}

/// A remote request; its time is kept only for wanted ids, like data frames.
fn remote_frame<'a>(
    t: Timestamp,
    channel: &'a [u8],
    id: u32,
    extended: bool,
    interest: &Interest,
) -> Frame<'a> {
    Frame {
        time: interest.wants(id, extended).then_some(t),
        channel,
        id,
        extended,
        kind: FrameKind::Remote,
        len: 0,
        data: Payload::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_all<'a>(p: &mut TrcParser, lines: &[&'a str]) -> Vec<Parsed<'a>> {
        lines
            .iter()
            .map(|l| p.parse(l.as_bytes(), &Interest::all()))
            .collect()
    }

    fn frame_of(p: &Parsed<'_>) -> (String, String, u32, bool, FrameKind, Vec<u8>) {
        match p {
            Parsed::Frame(f) => (
                f.time.map(|t| t.to_string()).unwrap_or_default(),
                String::from_utf8_lossy(f.channel).into_owned(),
                f.id,
                f.extended,
                f.kind,
                f.data.as_slice().to_vec(),
            ),
            other => panic!("not a frame: {other:?}"),
        }
    }

    #[test]
    fn version_1_0_without_header_is_read_by_shape() {
        let mut p = TrcParser::new();
        let got = parse_all(
            &mut p,
            &[
                ";##########",
                "     1)      1841      0081  8  10 43 08 01 00 00 00 00  ",
                "     2)      1842      0008  4  ERROR 00 19 08 08 ",
                "     3)      1843  FFFFFFFF  4  00 00 00 04 -- -- -- --  BUSLIGHT ",
                "     4)      1844      0100  3  RTR ",
                "     5)      1845  00000081  1  05",
            ],
        );
        assert_eq!(got[0], Parsed::Skipped);
        assert_eq!(
            frame_of(&got[1]),
            (
                "1.841".into(),
                "1".into(),
                0x81,
                false,
                FrameKind::Data,
                vec![0x10, 0x43, 8, 1, 0, 0, 0, 0]
            )
        );
        assert_eq!(frame_of(&got[2]).4, FrameKind::Error);
        assert_eq!(got[3], Parsed::Skipped);
        assert_eq!(frame_of(&got[4]).4, FrameKind::Remote);
        assert!(frame_of(&got[5]).3);
    }

    #[test]
    fn version_1_1_to_1_3_columns() {
        let mut p = TrcParser::new();
        let got = parse_all(
            &mut p,
            &[
                ";$FILEVERSION=1.1",
                "     1)      1059.9  Rx         0300  7  00 00 00 00 04 00 00  ",
                "     5)      1346.8  Warng  FFFFFFFF  4  00 00 00 04  BUSLIGHT ",
                "     6)      1349.2  Error      0008  4  00 19 08 08 ",
                "     7)      1352.7  Rx         0100  3  RTR ",
                ";$FILEVERSION=1.2",
                "     1)      1059.900  2  Rx         0300  7  00 00 00 00 04 00 00  ",
                ";$FILEVERSION=1.3",
                "     1)      1059.900 3  Rx        0300 -  7    00 00 00 00 04 00 00  ",
                "     5)      1346.834 1  Warng FFFFFFFF -  4    00 00 00 04  BUSLIGHT ",
            ],
        );
        assert_eq!(frame_of(&got[1]).0, "1.0599");
        assert_eq!(frame_of(&got[1]).2, 0x300);
        assert_eq!(got[2], Parsed::Skipped);
        assert_eq!(frame_of(&got[3]).4, FrameKind::Error);
        assert_eq!(frame_of(&got[4]).4, FrameKind::Remote);
        assert_eq!(frame_of(&got[6]).1, "2");
        assert_eq!(frame_of(&got[6]).0, "1.059900");
        assert_eq!(frame_of(&got[8]).1, "3");
        assert_eq!(got[9], Parsed::Skipped);
    }

    #[test]
    fn version_2_rows_follow_the_columns() {
        let mut p = TrcParser::new();
        let got = parse_all(
            &mut p,
            &[
                ";$FILEVERSION=2.0",
                ";$COLUMNS=N,O,T,I,d,l,D",
                "      5      1334.416 FD     0500 Tx 12 01 02 03 04 05 06 07 08 09 0A 0B 0C ",
                "      6      1334.522 ER          Rx    04 00 02 00 00 ",
                "      7      1334.531 ST          Rx    00 00 00 08 ",
                "      8      1334.643 EC          Rx    02 02 ",
                "      9      1335.156 DT 18EFC034 Tx 8  01 02 03 04 05 06 07 08 ",
                "     10      1336.543 RR     0100 Rx 3 ",
                ";$FILEVERSION=2.1",
                ";$COLUMNS=N,O,T,B,I,d,R,L,D",
                "      5      1334.416 FD 1      0500 Tx -  9    01 02 03 04 05 06 07 08 09 0A 0B 0C ",
                "      7      1334.224 EV 1  User-defined event for bus 1 ",
                "      8      1334.225 EV -  User-defined event for all busses ",
                "      9      1334.231 ST 1         - Rx -  4    00 00 00 08 ",
                "     10      1334.268 ER 1         - Rx -  5    04 00 02 08 00 ",
                "     12      1335.156 DT 2       081 Tx -  8    10 43 08 01 00 00 00 00 ",
                "     13      1336.543 RR 1      0100 Rx -  3 ",
                "     14      1336.600 FB 1      0081 Rx -  2    10 43",
            ],
        );
        assert_eq!(frame_of(&got[2]).4, FrameKind::Fd);
        assert_eq!(frame_of(&got[2]).5.len(), 12);
        assert_eq!(frame_of(&got[3]).4, FrameKind::Error);
        assert_eq!(got[4], Parsed::Skipped);
        assert_eq!(got[5], Parsed::Skipped);
        assert_eq!(frame_of(&got[6]).2, 0x18EF_C034);
        assert_eq!(frame_of(&got[7]).4, FrameKind::Remote);
        assert_eq!(frame_of(&got[10]).5.len(), 12);
        assert_eq!(got[11], Parsed::Skipped);
        assert_eq!(got[12], Parsed::Skipped);
        assert_eq!(got[13], Parsed::Skipped);
        assert_eq!(frame_of(&got[14]).4, FrameKind::Error);
        assert_eq!(
            frame_of(&got[15]),
            (
                "1.335156".into(),
                "2".into(),
                0x81,
                false,
                FrameKind::Data,
                vec![0x10, 0x43, 8, 1, 0, 0, 0, 0]
            )
        );
        assert_eq!(frame_of(&got[16]).4, FrameKind::Remote);
        assert_eq!(frame_of(&got[17]).4, FrameKind::Fd);
    }

    #[test]
    fn start_time_plus_offset_is_exact() {
        let mut p = TrcParser::new();
        // 45244.925 days = 2023-11-14 22:12:00 UTC = 1699999920.
        let got = parse_all(
            &mut p,
            &[
                ";$FILEVERSION=2.1",
                ";$STARTTIME=45244.925",
                "      1     80000.000 DT 1      0081 Rx -  1    00",
                "      2     81250.1 DT 1      0081 Rx -  1    00",
            ],
        );
        assert_eq!(frame_of(&got[2]).0, "1700000000.000000");
        assert_eq!(frame_of(&got[3]).0, "1700000001.2501");
        // PEAK's example: 10 fraction digits of a day are 8 digits of a second.
        p.parse(b";$STARTTIME=41766.4648963872;", &Interest::all());
        let f = frame_of(&p.parse(b"1 0.5 DT 1 0081 Rx - 0", &Interest::all()));
        assert_eq!(f.0, "1399460967.04835408");
        // Zero (unknown) start: times relative to the measurement.
        p.parse(b";$STARTTIME=0", &Interest::all());
        let f = frame_of(&p.parse(b"1 1500 DT 1 0081 Rx - 0", &Interest::all()));
        assert_eq!(f.0, "1.500");
    }

    #[test]
    fn malformed_rows_say_why() {
        let mut p = TrcParser::new();
        let bad = |p: &mut TrcParser, l: &str| match p.parse(l.as_bytes(), &Interest::all()) {
            Parsed::Malformed(r) => r.into_owned(),
            other => panic!("{l:?} -> {other:?}"),
        };
        assert!(bad(&mut p, "1) 10 0081 8 00").contains("says 8 data bytes"));
        assert!(bad(&mut p, "1 10 0081 1 00").contains("')'"));
        assert!(bad(&mut p, "1) 1x 0081 1 00").contains("time offset"));
        assert!(bad(&mut p, "1) 10 0800 1 00").contains("over 7FF"));
        assert!(bad(&mut p, "1) 10 0081 1 0G").contains("data byte"));
        assert!(bad(&mut p, ";$FILEVERSION=3.0").contains("unsupported"));
        assert!(bad(&mut p, ";$STARTTIME=x").contains("start time"));
        p.parse(b";$FILEVERSION=2.1", &Interest::all());
        assert!(bad(&mut p, "1 10 XX 1 0081 Rx - 1 00").contains("unknown message type"));
        assert!(bad(&mut p, "1 10 DT 1 0081 Up - 1 00").contains("Rx or Tx"));
        assert!(bad(&mut p, "1 10 RR 1 0081 Rx - 1 00").contains("no data"));
        assert!(bad(&mut p, ";$COLUMNS=N,O,T,I,D,L").contains("last"));
        assert!(bad(&mut p, ";$COLUMNS=N,O,T,X").contains("unknown column"));
    }

    #[test]
    fn frames_the_content_filter_rejects_are_only_timed() {
        let mut interest = Interest::none();
        interest.add_standard(0x705);
        interest.filter_content(0x705..=0x705, crate::ContentFilter(|_, d| d.head() == [0]));
        let mut p = TrcParser::new();
        let Scan::Timed(t, _) = p.scan(b"     1)      1841      0705  1  05", &interest) else {
            panic!("a heartbeat is only timed");
        };
        assert_eq!(t.to_string(), "1.841");
        assert!(matches!(
            p.scan(b"     2)      1842      0705  1  00", &interest),
            Scan::Frame(f) if f.data.as_slice() == [0]
        ));
    }

    #[test]
    fn an_error_row_is_wanted_as_error_frames_are_not_by_its_class_bits() {
        let mut p = TrcParser::new();
        p.parse(b";$FILEVERSION=1.1", &Interest::none());
        // Class bits 0x0008 are no id anyone asked for.
        let line = b"     6)      1349.2  Error      0008  4  00 19 08 08 ";
        let mut errors = Interest::none();
        errors.add_error_frames();
        assert!(matches!(
            p.scan(line, &errors),
            Scan::Frame(f) if f.kind == FrameKind::Error
        ));
        // Unwanted, it is parsed, so that it is counted as an error frame.
        assert_eq!(p.scan(line, &Interest::none()), Scan::Parse);
    }

    #[test]
    fn unwanted_frames_are_validated_not_decoded() {
        let mut p = TrcParser::new();
        let line = b"     1)      1841      0181  2  10 43";
        match p.parse(line, &Interest::none()) {
            Parsed::Frame(f) => {
                assert!(f.time.is_none());
                assert!(f.data.is_empty());
                assert_eq!(f.len, 2);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(
            p.scan(line, &Interest::none()),
            Scan::Plain(crate::FrameKey::new(b"1", 0x181, false))
        );
        let Parsed::Frame(wanted) = p.clone().parse(line, &Interest::all()) else {
            panic!("a frame line");
        };
        assert_eq!(p.scan(line, &Interest::all()), Scan::Frame(wanted));
        assert_eq!(
            p.scan(b"     1)      1841      0181  2  10", &Interest::none()),
            Scan::Parse
        );
        assert_eq!(p.scan(b";$FILEVERSION=2.1", &Interest::none()), Scan::Parse);
        assert_eq!(p.version(), Version::V1_0);
    }

    #[test]
    fn context_counts_header_changes() {
        let mut p = TrcParser::new();
        assert_eq!(p.context(), Some(0));
        p.parse(b";$FILEVERSION=2.1", &Interest::all());
        p.parse(b"; a comment", &Interest::all());
        assert_eq!(p.context(), Some(1));
        for _ in 0..300 {
            p.parse(b";$FILEVERSION=2.1", &Interest::all());
        }
        assert_eq!(p.context(), None);
    }

    #[test]
    fn fuzz_body_survives_odd_input() {
        fuzz_trc(b";$FILEVERSION=2.1\n;$COLUMNS=O,T,I,L,D\n1 DT 81 15 00\n\xff\x00)\n");
        fuzz_trc(b";$STARTTIME=999999999.999999999999999999\n1) 9999999999999999999.999999999999999 0081 0\n");
    }

    #[test]
    fn every_peak_error_field() {
        use crate::error_frame::{LOCATION_BYTE, PROTOCOL_BYTE, location};
        let of = |e: ErrorFrame| {
            (
                e.class,
                e.data[PROTOCOL_BYTE],
                e.data[LOCATION_BYTE],
                e.data[6],
                e.data[7],
            )
        };
        // (type, direction, position) -> (class, type byte, location)
        let rows = [
            (1, 1, 0x02, 0x288, protocol::BIT, location::ID28_21),
            (2, 1, 0x1A, 0x288, protocol::FORM, location::EOF),
            (
                4,
                0,
                0x0A,
                0x288,
                protocol::STUFF | protocol::TX,
                location::DATA,
            ),
            (
                8,
                1,
                0x08,
                0x288,
                protocol::UNSPECIFIED,
                location::CRC_SEQUENCE,
            ),
            (8, 0, 0x19, 0x2A8, protocol::TX, location::ACK_SLOT),
            (0, 0, 0x19, 0x200, 0, 0),
        ];
        for (kind, dir, position, class, byte, at) in rows {
            assert_eq!(
                of(peak_error(kind, dir, position, Some((9, 130)))),
                (class, byte, at, 130, 9),
                "type {kind} direction {dir}"
            );
        }
        assert_eq!(peak_error(0, 0, 0, None), ErrorFrame::default());
    }

    #[test]
    fn error_rows_carry_their_fields() {
        let mut p = TrcParser::new();
        let got = parse_all(
            &mut p,
            &[
                ";$FILEVERSION=1.1",
                "     6)      1349.2  Error      0008  4  00 19 08 08 ",
                ";$FILEVERSION=2.0",
                ";$COLUMNS=N,O,T,I,d,l,D",
                "      6      1334.522 ER          Rx    04 00 02 00 00 ",
                ";$FILEVERSION=2.1",
                ";$COLUMNS=N,O,T,B,I,d,R,L,D",
                "     10      1334.268 ER 1         - Rx -  5    04 01 02 08 00 ",
                "     11      1334.269 ER 1         - Rx -  2    04 01 ",
            ],
        );
        let f = |i: usize| match &got[i] {
            Parsed::Frame(f) => (f.id, f.data.as_slice().to_vec()),
            other => panic!("{other:?}"),
        };
        assert_eq!(f(1), (0x2A8, vec![0, 0, 0x80, 0x19, 0, 0, 8, 8]));
        assert_eq!(f(4), (0x288, vec![0, 0, 0x84, 0x02, 0, 0, 0, 0]));
        assert_eq!(f(7), (0x288, vec![0, 0, 0x04, 0x02, 0, 0, 0, 8]));
        assert_eq!(f(8), (0, vec![]));
    }
}
