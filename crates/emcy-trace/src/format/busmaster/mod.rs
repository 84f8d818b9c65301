//! BUSMASTER log files (`.log`, versions 1.6 to 2.4 seen), which CANopen
//! users paste into bug reports:
//!
//! ```text
//! ***BUSMASTER Ver 2.0.0***
//! ***PROTOCOL CAN***
//! ***NOTE: PLEASE DO NOT EDIT THIS DOCUMENT***
//! ***[START LOGGING SESSION]***
//! ***START DATE AND TIME 20:11:2013 14:19:9:538***
//! ***HEX***
//! ***SYSTEM MODE***
//! ***<Time><Tx/Rx><Channel><CAN ID><Type><DLC><DataBytes>***
//! 14:19:11:4184 Tx 1 0x099 s 8 00 00 00 00 00 00 00 00
//! 17:42:08:8830 Tx 1 0x103 xr 8 00 00 00 00 00 00 00 00
//! ***END DATE AND TIME 20:11:2013 14:19:24:711***
//! ***[STOP LOGGING SESSION]***
//! ```
//!
//! Every `***...***` line is a header (skipped). A file is a run of
//! sessions, each from `***BUSMASTER Ver` (or `***[START LOGGING SESSION]***`,
//! which keeps the start date of a file without version lines) on; a session
//! starts with nothing known and its headers set:
//!
//! - the number base of ids and data bytes: `***HEX***` or `***DEC***`. The
//!   data length is always decimal. Older writers (1.6.3, the 2.2 format
//!   converter) write no base line: then the numbers decide (see
//!   `Base::from_byte_width`), once per session.
//! - the time mode: `***SYSTEM MODE***` (time of day), `***ABSOLUTE MODE***`
//!   (time since logging started) or `***RELATIVE MODE***` (each stamp the
//!   delta to the previous frame). Without a mode line times are read as
//!   the time of day (what the writers without one wrote).
//! - the start date (`***START DATE AND TIME d:m:yyyy h:m:s:ms***`): system
//!   times are that day's time of day, as UTC seconds since the Unix epoch
//!   (the file does not say its zone, as TRC). A time more than 12 hours
//!   before the session's start time is on the next day (a session across
//!   midnight); 12 hours, not any earlier time, because Tx and Rx copies of
//!   one frame are written a few 100 us out of order and one writer (2.2)
//!   wrote start times on a 12-hour clock. Without a date, system times are
//!   seconds since midnight.
//! - the protocol: `***PROTOCOL CAN***`, `J1939` (its own line layout) or
//!   another bus (`LIN`: its lines are not CAN frames, skipped).
//!
//! Times are `H:M:S:F`, fields not always zero-padded: up to version 2.2, F
//! is 4 digits of 1/10000 s; version 2.4 writes milliseconds without padding
//! (`22:20:15:2` is 15.002 s, by the 10 ms steps around it), so a field of
//! 1 to 3 digits is milliseconds.
//!
//! Frame types: `s` and `x` (11- and 29-bit data), `sr` and `xr` (remote:
//! the DLC is the requested length, data bytes may follow and are ignored),
//! `s-fd` and `x-fd` (CAN FD, the length a byte count), and `ERR...` (error
//! frames). Rx and Tx are both frames; the channel is kept as written.

use crate::error_frame::{ErrorFrame, class};
use crate::time::{SECS_PER_DAY, unix_midnight};
use crate::{
    Format, Frame, FrameKey, FrameKind, Interest, LineParser, Parsed, Payload, Reason, Scan,
    Timestamp, show_token as show,
};
use crate::{hex, is_blank, trim_start};

const STANDARD_MAX: u32 = 0x7FF;
const EXTENDED_MAX: u32 = 0x1FFF_FFFF;

/// CAN FD payload lengths.
const FD_LEN: [u8; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// Number base of ids and data bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Base {
    Hex,
    Dec,
    /// No `***HEX***`/`***DEC***` line in this session and no data byte
    /// read yet that tells.
    Undecided,
}

impl Base {
    /// The base a data byte's width proves. BUSMASTER writes a byte as two
    /// hex digits (`%02X`) in HEX mode and as three decimal digits (`%03d`,
    /// `000`-`255`) in DEC mode: three digits cannot be a hex byte (`153`
    /// would be 0x153, over 255), and a decimal byte is never two digits
    /// wide. So the first data byte of a session without a base line
    /// decides the session.
    fn from_byte_width(token: &[u8]) -> Option<Base> {
        match token.len() {
            2 => Some(Base::Hex),
            3 => Some(Base::Dec),
            _ => None,
        }
    }

    /// For a line with no data byte in an undecided session (nothing is
    /// decided from it): `0x` or a hex letter means hex; four or ten
    /// digits is how DEC mode writes 11- and 29-bit ids (`%04d`, `0940`);
    /// anything else is read as hex, HEX mode's `%03X`/`%08X` widths.
    fn guess_from_id(id: &[u8]) -> Base {
        let digits = id.iter().all(u8::is_ascii_digit);
        if digits && (id.len() == 4 || id.len() == 10) {
            Base::Dec
        } else {
            Base::Hex
        }
    }
}

/// How a session writes times.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TimeMode {
    /// Time of day (also sessions without a mode line).
    System,
    /// Time since logging started.
    Absolute,
    /// Each time the delta to the previous frame's.
    Relative,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Protocol {
    Can,
    J1939,
    /// LIN or another bus: its lines are not CAN frames.
    Other,
}

/// A session's start: the Unix second of its date's midnight and its time
/// of day in seconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Start {
    midnight: u64,
    time_of_day: u64,
}

/// Reads BUSMASTER log lines; the session headers set base, time mode,
/// protocol and start date; relative times are summed here.
#[derive(Clone, Debug)]
pub struct BusmasterParser {
    base: Base,
    mode: TimeMode,
    protocol: Protocol,
    start: Option<Start>,
    /// Lines that set the start date, read: `***BUSMASTER` (none yet)
    /// and `***START DATE AND TIME` (the parallel reader's context: a block
    /// read from a fork is valid only if the fork saw every one; saturates).
    dates: u8,
    /// The running time of a relative session.
    now: Timestamp,
    /// A `***BUSMASTER` header was read: only BUSMASTER writes it.
    identified: bool,
}

impl BusmasterParser {
    /// A parser before the first line.
    pub fn new() -> Self {
        BusmasterParser {
            base: Base::Undecided,
            mode: TimeMode::System,
            protocol: Protocol::Can,
            start: None,
            dates: 0,
            now: Timestamp::ZERO,
            identified: false,
        }
    }

    /// A new session: nothing known until its headers say. The start date
    /// is reset by `***BUSMASTER` only (see [`BusmasterParser::header`]).
    fn new_session(&mut self) {
        self.base = Base::Undecided;
        self.mode = TimeMode::System;
        self.now = Timestamp::ZERO;
    }
}

impl Default for BusmasterParser {
    fn default() -> Self {
        BusmasterParser::new()
    }
}

/// Start-setting lines counted in the context: 3 bits, two a session, so
/// files of up to 3 sessions are read in parallel (more: sequentially).
const MAX_DATES: u8 = 7;

impl LineParser for BusmasterParser {
    fn format(&self) -> Format {
        Format::Busmaster
    }

    /// Base, time mode and protocol exactly, plus how many lines that set
    /// the start date were read (a fork that missed one has a lower count;
    /// one that saw them all has the same start). Relative times chain every frame to the
    /// one before: `None`, parse sequentially.
    fn clock(&self) -> Option<Timestamp> {
        (self.mode == TimeMode::Relative).then_some(self.now)
    }

    fn context(&self) -> Option<u8> {
        if self.mode == TimeMode::Relative || self.dates > MAX_DATES {
            return None;
        }
        let base = match self.base {
            Base::Hex => 0,
            Base::Dec => 1,
            Base::Undecided => 2,
        };
        let mode = u8::from(self.mode == TimeMode::Absolute);
        let protocol = match self.protocol {
            Protocol::Can => 0,
            Protocol::J1939 => 1,
            Protocol::Other => 2,
        };
        // 3 * 2 * 3 = 18 states below 32: 5 bits, then the count.
        Some((base * 6 + mode * 3 + protocol) | self.dates << 5)
    }

    fn identified(&self) -> bool {
        self.identified
    }

    #[inline]
    fn scan<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Scan<'a> {
        // Headers, sessions still deciding their base and other protocols'
        // layouts go to `parse`.
        if self.base == Base::Undecided || self.protocol != Protocol::Can {
            return Scan::Parse;
        }
        let Some(c) = self.common(line) else {
            return Scan::Parse;
        };
        let key = FrameKey {
            channel: c.channel,
            id: c.id,
            extended: c.extended,
        };
        let wanted = interest.wants(c.id, c.extended);
        if !wanted && self.mode != TimeMode::Relative {
            // `common` checked the time; only a relative one moves the state.
            return Scan::Plain(key);
        }
        let Ok(t) = self.commit(c.time) else {
            return Scan::Parse;
        };
        if !wanted {
            return Scan::Plain(key);
        }
        let mut data = Payload::new();
        let mut at = c.data;
        for _ in 0..c.len {
            let (byte, next) = self.byte_at(line, at).unwrap_or_default();
            data.push(byte);
            at = next;
        }
        if interest.timed_only(c.id, c.extended, data.as_slice()) {
            return Scan::Timed(t, key);
        }
        Scan::Frame(Frame {
            time: Some(t),
            channel: c.channel,
            id: c.id,
            extended: c.extended,
            kind: FrameKind::Data,
            len: c.len,
            data,
        })
    }

    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        let t = trim_start(line);
        if let Some(header) = t.strip_prefix(b"***") {
            return match self.header(header) {
                Ok(()) => Parsed::Skipped,
                Err(reason) => Parsed::Malformed(reason),
            };
        }
        if is_blank(t) || t == b"\r" {
            return Parsed::Skipped;
        }
        let mut fields = Fields::EMPTY;
        if !fields.split(line) {
            return Parsed::Malformed("too many fields for a BUSMASTER line".into());
        }
        let parsed = match self.protocol {
            Protocol::Can => self.can_line(&fields, interest),
            Protocol::J1939 if j1939_message(&fields) => return Parsed::Skipped,
            Protocol::J1939 => self.j1939_line(&fields, interest),
            Protocol::Other => {
                // Lines of another bus: known, not CAN frames.
                return if fields.get(0).is_some_and(is_time_shape) {
                    Parsed::Skipped
                } else {
                    Parsed::Malformed(not_a_line())
                };
            }
        };
        match parsed {
            Ok(Line {
                frame,
                time,
                decided,
            }) => {
                if let Some(base) = decided {
                    self.base = base;
                }
                match self.commit(time) {
                    // The time is kept for wanted ids and error frames.
                    Ok(t)
                        if frame.kind == FrameKind::Error
                            || interest.wants(frame.id, frame.extended) =>
                    {
                        Parsed::Frame(Frame {
                            time: Some(t),
                            ..frame
                        })
                    }
                    Ok(_) => Parsed::Frame(frame),
                    Err(reason) => Parsed::Malformed(reason),
                }
            }
            Err((time, reason)) => {
                // A relative stamp still adds to the running time, even on a
                // line that is not a frame: the next delta is from it.
                if let Some(time) = time
                    && self.mode == TimeMode::Relative
                {
                    let _ = self.commit(time);
                }
                Parsed::Malformed(reason)
            }
        }
    }
}

/// At most this many fields: 11 J1939 columns and 64 data bytes, with room.
const MAX_FIELDS: usize = 80;

/// The blank-separated fields of a line.
struct Fields<'a> {
    at: [&'a [u8]; MAX_FIELDS],
    n: usize,
}

impl<'a> Fields<'a> {
    const EMPTY: Fields<'static> = Fields {
        at: [&[]; MAX_FIELDS],
        n: 0,
    };

    /// `false` when the line has too many fields.
    #[inline]
    fn split(&mut self, line: &'a [u8]) -> bool {
        for f in line
            .split(|b| matches!(b, b' ' | b'\t' | b'\r'))
            .filter(|f| !f.is_empty())
        {
            let Some(slot) = self.at.get_mut(self.n) else {
                return false;
            };
            *slot = f;
            self.n += 1;
        }
        true
    }

    #[inline]
    fn get(&self, i: usize) -> Option<&'a [u8]> {
        self.all().get(i).copied()
    }

    #[inline]
    fn all(&self) -> &[&'a [u8]] {
        self.at.get(..self.n).unwrap_or_default()
    }
}

/// A time as written: `H:M:S:F`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Written {
    /// Hours, minutes and seconds in seconds.
    secs: u64,
    frac: u64,
    digits: u8,
}

/// What a frame line gave: the frame (time not yet set), its time as
/// written, and the base its numbers decided for the session.
struct Line<'a> {
    frame: Frame<'a>,
    time: Written,
    decided: Option<Base>,
}

/// The digits at `*at` (1 to `max` of them) and the byte `stop` after
/// them: their value and count; `*at` moves past `stop`.
#[inline]
fn number(line: &[u8], at: &mut usize, max: usize, stop: u8) -> Option<(u64, usize)> {
    let start = *at;
    let mut v = 0u64;
    while let Some(&b) = line.get(*at)
        && b.is_ascii_digit()
        && *at - start < max
    {
        v = v * 10 + u64::from(b - b'0');
        *at += 1;
    }
    let n = *at - start;
    if n == 0 || line.get(*at) != Some(&stop) {
        return None;
    }
    *at += 1;
    Some((v, n))
}

/// A data frame line of the common shape ([`BusmasterParser::common`]).
struct Common<'a> {
    time: Written,
    channel: &'a [u8],
    id: u32,
    extended: bool,
    len: u8,
    /// Where the first data byte starts.
    data: usize,
}

/// A line that is not a frame: its time when that much was read (a
/// relative session still counts it), and why.
type Failed = (Option<Written>, Reason);

impl BusmasterParser {
    /// A `***` line (the `***` removed): session boundaries and settings;
    /// why a start date cannot be read (the line is then malformed: the
    /// session's times are read without a date, which must not pass unsaid).
    fn header(&mut self, header: &[u8]) -> Result<(), Reason> {
        let text = header.strip_suffix(b"\r").unwrap_or(header);
        let text = crate::trim_end(text);
        let text = text.strip_suffix(b"***").unwrap_or(text);
        if text.starts_with(b"BUSMASTER") {
            self.identified = true;
            self.protocol = Protocol::Can;
            self.new_session();
            // Every line that sets the start is counted, whatever it was
            // before: the count is then the same for a fork only if the fork
            // read every such line, and so holds the same start.
            self.start = None;
            self.dates = self.dates.saturating_add(1);
            return Ok(());
        }
        match text {
            b"[START LOGGING SESSION]" => self.new_session(),
            b"HEX" => self.base = Base::Hex,
            b"DEC" => self.base = Base::Dec,
            b"SYSTEM MODE" => self.mode = TimeMode::System,
            b"ABSOLUTE MODE" => self.mode = TimeMode::Absolute,
            b"RELATIVE MODE" => {
                if self.mode != TimeMode::Relative {
                    self.now = Timestamp::ZERO;
                }
                self.mode = TimeMode::Relative;
            }
            b"PROTOCOL CAN" => self.protocol = Protocol::Can,
            b"PROTOCOL J1939" => self.protocol = Protocol::J1939,
            _ => {
                if text.starts_with(b"PROTOCOL ") {
                    self.protocol = Protocol::Other;
                } else if let Some(when) = text.strip_prefix(b"START DATE AND TIME") {
                    // An unreadable date leaves the session without one.
                    let when = trim_start(when);
                    self.start = start_date(when);
                    self.dates = self.dates.saturating_add(1);
                    if self.start.is_none() {
                        return Err(format!(
                            "'{}' is not a start date and time (d:m:yyyy h:m:s:ms, from 1970 \
                             to 9999): the session's system times are seconds since midnight",
                            show(when)
                        )
                        .into());
                    }
                }
            }
        }
        Ok(())
    }

    /// The shape BUSMASTER writes for a data frame, read in one pass
    /// without splitting the line (the hot path, ~4x faster than the
    /// general reading): `H:M:S:F Rx|Tx CH ID s|x D BYTE*` with single
    /// spaces, trailing spaces allowed. Validated exactly as
    /// [`BusmasterParser::can_line`] and [`BusmasterParser::commit`] do;
    /// `None` for anything else (which the general reading then takes).
    #[inline]
    fn common<'a>(&self, line: &'a [u8]) -> Option<Common<'a>> {
        let mut at = 0;
        let (h, _) = number(line, &mut at, 9, b':')?;
        let (m, _) = number(line, &mut at, 2, b':')?;
        let (s, _) = number(line, &mut at, 2, b':')?;
        let (frac, f_digits) = number(line, &mut at, 4, b' ')?;
        if m > 59 || s > 59 {
            return None;
        }
        let secs = h * 3600 + m * 60 + s;
        if self.mode == TimeMode::System && secs >= SECS_PER_DAY {
            return None;
        }
        let time = Written {
            secs,
            frac,
            digits: if f_digits == 4 { 4 } else { 3 },
        };
        match line.get(at..at + 3)? {
            b"Rx " | b"Tx " => at += 3,
            _ => return None,
        }
        let ch_start = at;
        number(line, &mut at, 3, b' ')?;
        let channel = line.get(ch_start..at - 1)?;
        let id_start = at;
        // At most `0x` and 10 digits: a short loop, not a search.
        let id_end = id_start
            + line
                .get(id_start..)?
                .iter()
                .take(13)
                .position(|b| *b == b' ')?;
        let id = parse_id(line.get(id_start..id_end)?, self.base).ok()?;
        at = id_end + 1;
        let extended = match line.get(at..at + 2)? {
            b"s " => false,
            b"x " => true,
            _ => return None,
        };
        at += 2;
        if id > if extended { EXTENDED_MAX } else { STANDARD_MAX } {
            return None;
        }
        let len = match (line.get(at), line.get(at + 1)) {
            (Some(d @ b'0'..=b'8'), None | Some(b' ')) => d - b'0',
            _ => return None,
        };
        at = (at + 2).min(line.len());
        let data = at;
        for _ in 0..len {
            at = self.byte_at(line, at)?.1;
        }
        if !line
            .get(at..)
            .unwrap_or_default()
            .iter()
            .all(|b| *b == b' ')
        {
            return None;
        }
        Some(Common {
            time,
            channel,
            id,
            extended,
            len,
            data,
        })
    }

    /// The data byte at `at` and where the next one starts (after one
    /// space, or at the end of the line). Bytes are 2 or 3 characters: a
    /// loop of ours, a search for the blank cost more than the byte.
    #[inline]
    fn byte_at(&self, line: &[u8], at: usize) -> Option<(u8, usize)> {
        let (byte, end) = if self.base == Base::Dec {
            let mut v = 0u32;
            let mut end = at;
            while let Some(&b) = line.get(end)
                && b.is_ascii_digit()
                && end - at < 3
            {
                v = v * 10 + u32::from(b - b'0');
                end += 1;
            }
            if end == at {
                return None;
            }
            (u8::try_from(v).ok()?, end)
        } else {
            (hex::parse_byte(*line.get(at)?, *line.get(at + 1)?)?, at + 2)
        };
        match line.get(end) {
            None => Some((byte, end)),
            Some(b' ') => Some((byte, end + 1)),
            Some(_) => None,
        }
    }

    /// `Time Rx|Tx Channel Id Type DLC Data...` (or `... Id ERR...`).
    fn can_line<'a>(&self, f: &Fields<'a>, interest: &Interest) -> Result<Line<'a>, Failed> {
        let time_text = f.get(0).ok_or((None, not_a_line()))?;
        let time = written_time(time_text).map_err(|r| (None, r))?;
        let fail = |reason: Reason| (Some(time), reason);
        let [_, dir, channel, id_text, kind, rest @ ..] = f.all() else {
            return Err(fail("line ends before the frame type".into()));
        };
        direction(dir).map_err(fail)?;
        let channel = channel_of(channel).map_err(fail)?;
        if kind.starts_with(b"ERR") {
            return Ok(Line {
                frame: error_frame(rest).frame(None, channel),
                time,
                decided: None,
            });
        }
        let (kind, extended) = frame_type(kind).map_err(fail)?;
        let [len_text, data @ ..] = rest else {
            return Err(fail("line ends before the data length".into()));
        };
        self.frame((channel, id_text, kind, extended), len_text, data, interest)
            .map(|(frame, decided)| Line {
                frame,
                time,
                decided,
            })
            .map_err(fail)
    }

    /// J1939 sessions: `Time Channel Id PGN Type Src Dest Prio Rx|Tx DLC
    /// Data...`, a CAN frame with a 29-bit id (see [`j1939_message`]).
    fn j1939_line<'a>(&self, f: &Fields<'a>, interest: &Interest) -> Result<Line<'a>, Failed> {
        let time_text = f.get(0).ok_or((None, not_a_line()))?;
        let time = written_time(time_text).map_err(|r| (None, r))?;
        let fail = |reason: Reason| (Some(time), reason);
        let [
            _,
            channel,
            id_text,
            _pgn,
            _kind,
            _src,
            _dst,
            _prio,
            dir,
            len_text,
            data @ ..,
        ] = f.all()
        else {
            return Err(fail("J1939 line ends before the data length".into()));
        };
        direction(dir).map_err(fail)?;
        let channel = channel_of(channel).map_err(fail)?;
        self.frame(
            (channel, id_text, FrameKind::Data, true),
            len_text,
            data,
            interest,
        )
        .map(|(frame, decided)| Line {
            frame,
            time,
            decided,
        })
        .map_err(fail)
    }

    /// The id, length and data of a frame; the data decoded only when the
    /// id is wanted. Returns the base the data bytes decided, if undecided.
    fn frame<'a>(
        &self,
        (channel, id_text, kind, extended): (&'a [u8], &[u8], FrameKind, bool),
        len_text: &[u8],
        data: &[&[u8]],
        interest: &Interest,
    ) -> Result<(Frame<'a>, Option<Base>), Reason> {
        let (base, decided) = match self.base {
            Base::Undecided => match data.first().and_then(|b| Base::from_byte_width(b)) {
                Some(b) => (b, Some(b)),
                None if data.is_empty() => (Base::guess_from_id(id_text), None),
                None => {
                    return Err(format!(
                        "'{}' is not a data byte (2 hex or 3 decimal digits)",
                        show(data.first().copied().unwrap_or_default())
                    )
                    .into());
                }
            },
            b => (b, None),
        };
        let id = parse_id(id_text, base)?;
        let max = if extended { EXTENDED_MAX } else { STANDARD_MAX };
        if id > max {
            return Err(format!(
                "id {id:#X} is out of range for a {}-bit id",
                if extended { 29 } else { 11 }
            )
            .into());
        }
        // The length is decimal in both bases.
        let value = hex::parse_dec_u32(len_text)
            .ok_or_else(|| format!("'{}' is not a data length", show(len_text)))?;
        let len = match kind {
            FrameKind::Fd => u8::try_from(value)
                .ok()
                .filter(|l| FD_LEN.contains(l))
                .ok_or_else(|| format!("{value} is not a CAN FD data length"))?,
            _ if value <= 8 => value as u8,
            _ => return Err(format!("data length {value} is over 8").into()),
        };
        let remote = kind == FrameKind::Remote;
        // A remote request may be written with its DLC's worth of bytes.
        if data.len() != usize::from(len) && !(remote && data.is_empty()) {
            return Err(format!(
                "the length says {len} data bytes but the line has {}",
                data.len()
            )
            .into());
        }
        let wanted = interest.wants(id, extended) && !remote;
        let mut payload = Payload::new();
        for b in data {
            let byte = parse_byte(b, base)?;
            if wanted {
                payload.push(byte);
            }
        }
        Ok((
            Frame {
                time: None,
                channel,
                id,
                extended,
                kind,
                len: if remote { 0 } else { len },
                data: payload,
            },
            decided,
        ))
    }

    /// The frame's time in this session; the running time moves on in a
    /// relative session.
    fn commit(&mut self, written: Written) -> Result<Timestamp, Reason> {
        let here = Timestamp::from_parts(written.secs, written.frac, written.digits);
        let t = match self.mode {
            TimeMode::Relative => {
                let t = self
                    .now
                    .checked_add(here)
                    .ok_or("relative times add up past 2^64 seconds")?;
                self.now = t;
                t
            }
            TimeMode::Absolute => here,
            TimeMode::System => {
                if written.secs >= SECS_PER_DAY {
                    return Err("the time of day is past 23:59:59".into());
                }
                match self.start {
                    Some(start) => {
                        let next_day = written.secs + SECS_PER_DAY / 2 < start.time_of_day;
                        let secs =
                            start.midnight + written.secs + u64::from(next_day) * SECS_PER_DAY;
                        Timestamp::from_parts(secs, written.frac, written.digits)
                    }
                    None => here,
                }
            }
        };
        Ok(t)
    }
}

/// A J1939 line of more than 8 data bytes: a message the transport protocol
/// reassembled from frames, not a frame on the bus (skipped).
fn j1939_message(f: &Fields<'_>) -> bool {
    f.get(9)
        .and_then(hex::parse_dec_u32)
        .is_some_and(|len| len > 8)
}

fn not_a_line() -> Reason {
    "not a BUSMASTER line (expected H:M:S:F Rx|Tx channel id type DLC data)".into()
}

/// `H:M:S:F` with 1 to 4 digits in F (a 4-digit F is 1/10000 s, fewer
/// digits are milliseconds: see the module documentation).
fn written_time(text: &[u8]) -> Result<Written, Reason> {
    let bad = || -> Reason { format!("'{}' is not a time (H:M:S:F)", show(text)).into() };
    let mut parts = text.split(|b| *b == b':');
    let mut field = |max_len: usize| -> Result<u64, Reason> {
        let p = parts.next().ok_or_else(bad)?;
        if p.is_empty() || p.len() > max_len || !p.iter().all(u8::is_ascii_digit) {
            return Err(bad());
        }
        Ok(crate::scan::decimal_u64(p))
    };
    // Hours may pass 24 in absolute and relative sessions.
    let (h, m, s) = (field(9)?, field(2)?, field(2)?);
    let f_text = parts.next().ok_or_else(bad)?;
    if parts.next().is_some() || m > 59 || s > 59 {
        return Err(bad());
    }
    if f_text.is_empty() || f_text.len() > 4 || !f_text.iter().all(u8::is_ascii_digit) {
        return Err(bad());
    }
    let frac = crate::scan::decimal_u64(f_text);
    let digits = if f_text.len() == 4 { 4 } else { 3 };
    Ok(Written {
        secs: h * 3600 + m * 60 + s,
        frac,
        digits,
    })
}

/// Whether a field looks like a BUSMASTER time (for other buses' lines).
fn is_time_shape(text: &[u8]) -> bool {
    written_time(text).is_ok()
}

/// `d:m:yyyy h:m:s:ms` (the `***` already removed); `None` when unreadable
/// or before 1970.
fn start_date(text: &[u8]) -> Option<Start> {
    let mut words = text
        .split(|b| *b == b' ')
        .filter(|w| !w.is_empty() && *w != b"***");
    let date = words.next()?;
    let time = words.next()?;
    let num = |p: &[u8]| -> Option<u64> {
        (!p.is_empty() && p.len() <= 4 && p.iter().all(u8::is_ascii_digit))
            .then(|| crate::scan::decimal_u64(p))
    };
    let mut d = date.split(|b| *b == b':');
    let (day, month, year) = (num(d.next()?)?, num(d.next()?)?, num(d.next()?)?);
    let mut t = time.split(|b| *b == b':');
    let (h, m, s) = (num(t.next()?)?, num(t.next()?)?, num(t.next()?)?);
    if d.next().is_some() || h > 23 || m > 59 || s > 59 || year < 1970 {
        return None;
    }
    Some(Start {
        midnight: unix_midnight(year, month, day)?,
        time_of_day: h * 3600 + m * 60 + s,
    })
}

fn direction(dir: &[u8]) -> Result<(), Reason> {
    match dir {
        b"Rx" | b"Tx" => Ok(()),
        other => Err(format!("expected Rx or Tx, not '{}'", show(other)).into()),
    }
}

fn channel_of(channel: &[u8]) -> Result<&[u8], Reason> {
    if !channel.is_empty() && channel.len() <= 3 && channel.iter().all(u8::is_ascii_digit) {
        Ok(channel)
    } else {
        Err(format!("'{}' is not a channel number", show(channel)).into())
    }
}

/// `s`, `x`, `sr`, `xr`, `s-fd`, `x-fd`: the kind and whether 29-bit.
fn frame_type(kind: &[u8]) -> Result<(FrameKind, bool), Reason> {
    Ok(match kind {
        b"s" => (FrameKind::Data, false),
        b"x" => (FrameKind::Data, true),
        b"sr" => (FrameKind::Remote, false),
        b"xr" => (FrameKind::Remote, true),
        b"s-fd" => (FrameKind::Fd, false),
        b"x-fd" => (FrameKind::Fd, true),
        other => {
            return Err(format!(
                "unknown frame type '{}' (s, x, sr, xr, s-fd, x-fd)",
                show(other)
            )
            .into());
        }
    })
}

/// An id in the session's base: hex with or without `0x`, or decimal.
fn parse_id(text: &[u8], base: Base) -> Result<u32, Reason> {
    let id = match base {
        Base::Dec => hex::parse_dec_u32(text),
        _ => hex::parse_u32(
            text.strip_prefix(b"0x")
                .or_else(|| text.strip_prefix(b"0X"))
                .unwrap_or(text),
        ),
    };
    id.ok_or_else(|| {
        let what = if base == Base::Dec { "decimal" } else { "hex" };
        format!("'{}' is not a {what} id", show(text)).into()
    })
}

/// A data byte: two hex digits, or up to three decimal digits (`000`-`255`).
#[inline]
fn parse_byte(text: &[u8], base: Base) -> Result<u8, Reason> {
    let byte = match (base, text) {
        (Base::Dec, _) if !text.is_empty() && text.len() <= 3 => {
            hex::parse_dec_u32(text).and_then(|v| u8::try_from(v).ok())
        }
        (Base::Dec, _) => None,
        (_, [hi, lo]) => hex::parse_byte(*hi, *lo),
        _ => None,
    };
    byte.ok_or_else(|| {
        let what = if base == Base::Dec {
            "a decimal data byte (0-255)"
        } else {
            "a hex data byte (two digits)"
        };
        format!("'{}' is not {what}", show(text)).into()
    })
}

/// Fuzz target body: any bytes, line by line, must classify without a
/// panic, frames must be well-formed, and the scan shortcut must agree
/// with `parse` (same frame, same state after it).
#[cfg(feature = "fuzzing")]
pub fn fuzz_busmaster(data: &[u8]) {
    let mut p = BusmasterParser::new();
    let all = Interest::all();
    let none = Interest::none();
    for line in data.split(|b| *b == b'\n') {
        let mut scanned = p.clone();
        let scan = scanned.scan(line, &none);
        let parsed = p.parse(line, &all);
        if let Parsed::Frame(f) = &parsed {
            assert!(usize::from(f.len) <= Payload::MAX);
            if f.kind == FrameKind::Data || f.kind == FrameKind::Fd {
                assert_eq!(f.data.len(), usize::from(f.len));
            }
            assert!(f.extended || f.id <= STANDARD_MAX);
            assert!(f.id <= EXTENDED_MAX);
            assert!(f.time.is_some());
        }
        if let Scan::Plain(key) = scan {
            let Parsed::Frame(f) = &parsed else {
                panic!("scan took a non-frame");
            };
            assert_eq!(key, f.key(), "counted under another key than the frame's");
            assert_eq!(scanned.context(), p.context());
            assert_eq!(scanned.now, p.now);
        }
    }
}

/// What BUSMASTER writes after `ERR`, in the SocketCAN representation:
/// `Bus Off` is the class bus-off; any other text an error frame whose
/// class is unknown.
fn error_frame(words: &[&[u8]]) -> ErrorFrame {
    let mut e = ErrorFrame::default();
    if let [a, b, ..] = words
        && a.eq_ignore_ascii_case(b"Bus")
        && b.eq_ignore_ascii_case(b"Off")
    {
        e.class |= class::BUS_OFF;
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(p: &mut BusmasterParser, lines: &str) -> Vec<Parsed<'static>> {
        let text: &'static str = Box::leak(lines.to_string().into_boxed_str());
        text.lines()
            .map(|l| p.parse(l.as_bytes(), &Interest::all()))
            .collect()
    }

    /// (time, channel, id, extended, kind, len, data) of a frame.
    type Seen = (String, String, u32, bool, FrameKind, u8, Vec<u8>);

    fn frames(parsed: &[Parsed<'_>]) -> Vec<Seen> {
        parsed
            .iter()
            .filter_map(|p| match p {
                Parsed::Frame(f) => Some((
                    f.time.map(|t| t.to_string()).unwrap_or_default(),
                    String::from_utf8_lossy(f.channel).into_owned(),
                    f.id,
                    f.extended,
                    f.kind,
                    f.len,
                    f.data.as_slice().to_vec(),
                )),
                _ => None,
            })
            .collect()
    }

    fn malformed(parsed: &[Parsed<'_>]) -> Vec<String> {
        parsed
            .iter()
            .filter_map(|p| match p {
                Parsed::Malformed(r) => Some(r.to_string()),
                _ => None,
            })
            .collect()
    }

    const HEADER_HEX_SYSTEM: &str = "***BUSMASTER Ver 2.0.0***
***PROTOCOL CAN***
***NOTE: PLEASE DO NOT EDIT THIS DOCUMENT***
***[START LOGGING SESSION]***
***START DATE AND TIME 14:11:2023 22:13:19:538***
***HEX***
***SYSTEM MODE***
***START CHANNEL BAUD RATE***
***CHANNEL 1 - Kvaser - Virtual #0 (Channel 0) - 500000 bps***
***END CHANNEL BAUD RATE***
***<Time><Tx/Rx><Channel><CAN ID><Type><DLC><DataBytes>***
";

    #[test]
    fn headers_are_skipped_and_identify_the_format() {
        let mut p = BusmasterParser::new();
        assert!(!p.identified());
        let parsed = read(&mut p, HEADER_HEX_SYSTEM);
        assert!(parsed.iter().all(|r| *r == Parsed::Skipped));
        assert!(p.identified());
        assert_eq!(p.base, Base::Hex);
        assert_eq!(p.mode, TimeMode::System);
    }

    #[test]
    fn system_times_are_the_time_of_day_on_the_start_date() {
        let mut p = BusmasterParser::new();
        let text = format!(
            "{HEADER_HEX_SYSTEM}22:13:20:0000 Rx 1 0x081 s 8 10 43 08 01 00 00 00 00 \n\
             22:13:21:2500 Tx 2 701 s 1 05\n"
        );
        let got = frames(&read(&mut p, &text));
        assert_eq!(
            got,
            [
                (
                    "1700000000.0000".into(),
                    "1".into(),
                    0x81,
                    false,
                    FrameKind::Data,
                    8,
                    vec![0x10, 0x43, 8, 1, 0, 0, 0, 0]
                ),
                (
                    "1700000001.2500".into(),
                    "2".into(),
                    0x701,
                    false,
                    FrameKind::Data,
                    1,
                    vec![5]
                ),
            ]
        );
    }

    #[test]
    fn a_session_across_midnight_goes_on_to_the_next_day() {
        let mut p = BusmasterParser::new();
        let got = frames(&read(
            &mut p,
            "***BUSMASTER Ver 2.0.0***\n***START DATE AND TIME 14:11:2023 23:59:59:000***\n\
             ***HEX***\n23:59:59:9000 Rx 1 081 s 0\n0:0:1:0000 Rx 1 081 s 0\n\
             23:59:59:8990 Tx 1 081 s 0\n",
        ));
        let times: Vec<_> = got.iter().map(|f| f.0.as_str()).collect();
        // 2023-11-15 00:00:01 UTC is 1700006401; Tx just before the Rx
        // stays on the same day.
        assert_eq!(
            times,
            ["1700006399.9000", "1700006401.0000", "1700006399.8990"]
        );
    }

    #[test]
    fn absolute_times_are_seconds_since_logging_started() {
        let mut p = BusmasterParser::new();
        let got = frames(&read(
            &mut p,
            "***BUSMASTER Ver 1.6.4***\n***START DATE AND TIME 29:6:2012 11:39:2:250***\n\
             ***DEC***\n***ABSOLUTE MODE***\n00:00:01:2549 Tx 1 0129 s 2 016 067\n\
             25:00:00:0001 Tx 1 0129 s 0\n",
        ));
        assert_eq!(got[0].0, "1.2549");
        assert_eq!(got[0].2, 129);
        assert_eq!(got[0].6, [16, 67]);
        assert_eq!(got[1].0, "90000.0001");
    }

    #[test]
    fn relative_times_add_up_and_make_parsing_sequential() {
        let mut p = BusmasterParser::new();
        let parsed = read(
            &mut p,
            "***BUSMASTER Ver 1.6.4***\n***HEX***\n***RELATIVE MODE***\n\
             00:00:00:0000 Tx 1 0x013 s 0\n00:00:01:0005 Tx 1 0x013 s 0\n\
             00:00:00:0005 Tx 1 0x013 q 0\n00:00:00:0010 Tx 1 0x013 s 0\n",
        );
        assert_eq!(p.context(), None);
        let times: Vec<_> = frames(&parsed).into_iter().map(|f| f.0).collect();
        // The malformed line's delta still counts.
        assert_eq!(times, ["0.0000", "1.0005", "1.0020"]);
        // A new session starts over, in its own mode.
        read(
            &mut p,
            "***BUSMASTER Ver 1.6.4***\n***HEX***\n***ABSOLUTE MODE***\n",
        );
        assert!(p.context().is_some());
    }

    #[test]
    fn a_session_without_a_base_line_is_decided_by_its_byte_widths() {
        // 1.6.3 writes no base line: three-digit bytes are decimal.
        let mut p = BusmasterParser::new();
        let got = frames(&read(
            &mut p,
            "***BUSMASTER Ver 1.6.3***\n***[START LOGGING SESSION]***\n\
             ***START DATE AND TIME 30:5:2012 13:29:58:000***\n\
             13:56:5:4749 Tx 1 0940 s 0\n\
             13:57:9:9759 Tx 1 0151 s 8 153 000 000 102 000 000 153 000 \n\
             13:57:9:9760 Tx 1 0166 s 1 039\n",
        ));
        // The empty frame comes before any byte: the 4-digit id reads decimal.
        assert_eq!(got[0].2, 940);
        assert_eq!(
            (got[1].2, got[1].6.clone()),
            (151, vec![153, 0, 0, 102, 0, 0, 153, 0])
        );
        assert_eq!(got[2].2, 166);
        assert_eq!(p.base, Base::Dec);
        // The 2.2 converter: no base line either, two-digit bytes are hex;
        // the next session decides again.
        let got = frames(&read(
            &mut p,
            "***BUSMASTER Ver 2.2.0***\n***[START LOGGING SESSION]***\n\
             12:26:55:3602 Tx 1 124 s 2 0A 10\n12:26:55:3603 Tx 1 0FF s 0\n",
        ));
        assert_eq!((got[0].2, got[0].6.clone()), (0x124, vec![0x0A, 0x10]));
        assert_eq!(got[1].2, 0xFF);
        assert_eq!(p.base, Base::Hex);
    }

    #[test]
    fn error_texts() {
        assert_eq!(error_frame(&[b"Bus", b"Off"]).class, class::BUS_OFF);
        assert_eq!(error_frame(&[b"bus", b"off", b"x"]).class, class::BUS_OFF);
        assert_eq!(error_frame(&[b"Bus"]), ErrorFrame::default());
        assert_eq!(error_frame(&[]), ErrorFrame::default());
    }

    #[test]
    fn appended_sessions_switch_base_and_channels_stay_as_written() {
        let mut p = BusmasterParser::new();
        let parsed = read(
            &mut p,
            "***BUSMASTER Ver 2.0.0***\n***DEC***\n***SYSTEM MODE***\n\
             17:9:36:0000 Rx 2 0000000259 x 1 255\n***[STOP LOGGING SESSION]***\n\n\
             ***BUSMASTER Ver 2.0.0***\n***HEX***\n***SYSTEM MODE***\n\
             17:42:08:8830 Tx 1 0x103 xr 8 00 00 00 00 00 00 00 00 \n\
             17:42:08:8840 Rx 2 0x103 sr 2\n\
             17:42:08:8850 Rx 0 00000103 s-fd 12 00 01 02 03 04 05 06 07 08 09 0A 0B\n\
             17:42:08:8860 Rx 1 0 ERR Bus Off\n",
        );
        let got = frames(&parsed);
        assert_eq!(got[0].1, "2");
        assert_eq!(
            (got[0].2, got[0].3, got[0].6.clone()),
            (259, true, vec![255])
        );
        assert_eq!(
            (got[1].2, got[1].3, got[1].4, got[1].5),
            (0x103, true, FrameKind::Remote, 0)
        );
        assert_eq!((got[2].3, got[2].4), (false, FrameKind::Remote));
        assert_eq!(
            (got[3].1.as_str(), got[3].4, got[3].5),
            ("0", FrameKind::Fd, 12)
        );
        assert_eq!(got[3].6, (0..12).collect::<Vec<u8>>());
        assert_eq!(
            (got[4].2, got[4].4, got[4].6.clone()),
            (0x40, FrameKind::Error, vec![0; 8])
        );
        assert!(malformed(&parsed).is_empty());
    }

    #[test]
    fn version_2_4_writes_unpadded_milliseconds() {
        let mut p = BusmasterParser::new();
        let got = frames(&read(
            &mut p,
            "***BUSMASTER Ver 2.4.0***\n***START DATE AND TIME 14:11:2023 22:13:19:000***\n\
             ***HEX***\n***SYSTEM MODE***\n22:13:20:992 Rx 0 0000021A s 1 FE\n\
             22:13:21:2 Rx 0 0000021A s 1 FE\n",
        ));
        let times: Vec<_> = got.iter().map(|f| f.0.as_str()).collect();
        assert_eq!(times, ["1700000000.992", "1700000001.002"]);
        assert_eq!(got[0].2, 0x21A);
    }

    #[test]
    fn bad_lines_are_malformed_with_a_reason() {
        let mut p = BusmasterParser::new();
        let cases = [
            ("22:13:20:0000 Rx 1 081 s 1 123", "not a hex data byte"),
            ("22:13:20:0000 Rx 1 081 s 2 12", "length says 2"),
            ("22:13:20:0000 Rx 1 800 s 0", "out of range for a 11-bit id"),
            ("22:13:20:0000 Rx 1 081 s 9", "over 8"),
            ("22:13:20:0000 Rx 1 081 q 0", "unknown frame type"),
            ("22:13:20:0000 Xx 1 081 s 0", "expected Rx or Tx"),
            ("22:13:20:0000 Rx one 081 s 0", "not a channel number"),
            ("22:61:20:0000 Rx 1 081 s 0", "not a time"),
            ("24:00:00:0000 Rx 1 081 s 0", "past 23:59:59"),
            ("22:13:20:00000 Rx 1 081 s 0", "not a time"),
            ("22:13:20:0000 Rx 1 081", "ends before the frame type"),
            ("22:13:20:0000 Rx 1 08G s 0", "not a hex id"),
            (
                "22:13:20:0000 Rx 1 081 s-fd 9 00 00 00 00 00 00 00 00 00",
                "not a CAN FD",
            ),
            ("(1700000000.000000) can0 081#00", "not a time"),
        ];
        read(&mut p, "***HEX***\n");
        for (line, why) in cases {
            let parsed = p.parse(line.as_bytes(), &Interest::all());
            match parsed {
                Parsed::Malformed(r) => assert!(r.contains(why), "{line}: {r}"),
                other => panic!("{line}: {other:?}"),
            }
        }
        read(&mut p, "***DEC***\n");
        let parsed = p.parse(b"22:13:20:0000 Rx 1 0129 s 1 256", &Interest::all());
        assert!(matches!(parsed, Parsed::Malformed(r) if r.contains("decimal data byte")));
    }

    #[test]
    fn other_buses_are_skipped_and_j1939_lines_are_29_bit_frames() {
        let mut p = BusmasterParser::new();
        let parsed = read(
            &mut p,
            "***BUSMASTER Ver 2.0.0***\n***PROTOCOL LIN***\n***HEX***\n\
             10:00:00:0000 Rx 1 0x01 s 2 12 34\n\
             ***BUSMASTER Ver 2.0.0***\n***PROTOCOL J1939***\n***HEX***\n\
             10:00:00:0000 1 0x18FEF100 0x00FEF1 BROADCAST 0x00 0xFF 6 Rx 8 01 02 03 04 05 06 07 08\n\
             10:00:00:0001 1 0x18EBFF00 0x00EB00 DATA 0x00 0xFF 7 Rx 20 01 02 03 04 05 06 07 08 09 0A 0B 0C 0D 0E 0F 10 11 12 13 14\n",
        );
        assert_eq!(parsed[3], Parsed::Skipped);
        let got = frames(&parsed);
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].2, got[0].3, got[0].5), (0x18FE_F100, true, 8));
        assert_eq!(parsed.last(), Some(&Parsed::Skipped));
    }

    #[test]
    fn context_holds_base_mode_protocol_and_the_dates_read() {
        let mut p = BusmasterParser::new();
        let start = p.context();
        read(&mut p, "***HEX***\n");
        let hex = p.context();
        read(&mut p, "***DEC***\n");
        let dec = p.context();
        read(&mut p, "***ABSOLUTE MODE***\n");
        let abs = p.context();
        read(&mut p, "***START DATE AND TIME 1:1:2020 0:0:0:0***\n");
        let dated = p.context();
        let all = [start, hex, dec, abs, dated];
        for (i, a) in all.iter().enumerate() {
            assert!(a.is_some());
            for b in &all[i + 1..] {
                assert_ne!(a, b);
            }
        }
        // A new session with the same settings but no date: the start
        // differs, so must the context (a fork that missed this line would
        // keep the old date).
        read(&mut p, "***HEX***\n***SYSTEM MODE***\n");
        let mut q = p.clone();
        read(
            &mut q,
            "***BUSMASTER Ver 2.0.0***\n***HEX***\n***SYSTEM MODE***\n",
        );
        assert_eq!((q.base, q.mode, q.start), (p.base, p.mode, None));
        assert!(p.start.is_some());
        assert_ne!(q.context(), p.context());
        for _ in 0..MAX_DATES {
            read(&mut p, "***START DATE AND TIME 1:1:2020 0:0:0:0***\n");
        }
        assert_eq!(p.context(), None, "past the count: sequential");
    }

    #[test]
    fn scan_counts_unwanted_frames_and_decodes_wanted_ones() {
        let mut p = BusmasterParser::new();
        read(&mut p, HEADER_HEX_SYSTEM);
        let mut interest = Interest::none();
        interest.add_standard(0x81);
        assert_eq!(
            p.scan(b"22:13:20:0000 Rx 1 0x181 s 1 00", &interest),
            Scan::Plain(FrameKey::new(b"1", 0x181, false))
        );
        assert!(matches!(
            p.scan(b"22:13:20:0000 Rx 1 0x081 s 1 10", &interest),
            Scan::Frame(f) if f.data.as_slice() == [0x10] && f.time.is_some()
        ));
        // Headers and bad lines go to `parse`.
        assert_eq!(p.scan(b"***DEC***", &interest), Scan::Parse);
        assert_eq!(
            p.scan(b"22:13:20:0000 Rx 1 0x081 s 1 1", &interest),
            Scan::Parse
        );
        // An undecided base is decided by `parse`.
        let mut q = BusmasterParser::new();
        assert_eq!(
            q.scan(b"22:13:20:0000 Rx 1 181 s 1 00", &interest),
            Scan::Parse
        );
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        /// A frame as BUSMASTER writes it, in either base, and what it is.
        fn written_frame() -> impl Strategy<Value = (bool, String, u32, bool, Vec<u8>, u64)> {
            (
                any::<bool>(),
                any::<bool>(),
                0u32..=EXTENDED_MAX,
                prop::collection::vec(any::<u8>(), 0..=8),
                0u64..86_400 * 10_000,
                any::<bool>(),
            )
                .prop_map(|(dec, extended, id, data, tenths, prefix)| {
                    let id = if extended { id } else { id & STANDARD_MAX };
                    let (secs, frac) = (tenths / 10_000, tenths % 10_000);
                    let time =
                        format!("{}:{}:{}:{frac:04}", secs / 3600, secs / 60 % 60, secs % 60);
                    let id_text = match (dec, extended, prefix) {
                        (true, true, _) => format!("{id:010}"),
                        (true, false, _) => format!("{id:04}"),
                        (false, true, true) => format!("0x{id:08X}"),
                        (false, true, false) => format!("{id:08X}"),
                        (false, false, true) => format!("0x{id:03X}"),
                        (false, false, false) => format!("{id:03X}"),
                    };
                    let bytes: String = data
                        .iter()
                        .map(|b| {
                            if dec {
                                format!(" {b:03}")
                            } else {
                                format!(" {b:02X}")
                            }
                        })
                        .collect();
                    let line = format!(
                        "{time} Rx 1 {id_text} {} {}{bytes} ",
                        if extended { "x" } else { "s" },
                        data.len()
                    );
                    (dec, line, id, extended, data, tenths)
                })
        }

        proptest! {
            /// Generated lines read back as the frame they were made from, with
            /// or without a base line (the bytes decide, or the id width), and
            /// `scan` agrees with `parse`.
            #[test]
            fn generated_lines_round_trip((dec, line, id, extended, data, tenths) in written_frame(), headerless in any::<bool>()) {
                let mut p = BusmasterParser::new();
                let header = match (headerless, dec) {
                    (true, _) => "***BUSMASTER Ver 1.6.3***\n***ABSOLUTE MODE***\n",
                    (false, true) => "***BUSMASTER Ver 2.0.0***\n***DEC***\n***ABSOLUTE MODE***\n",
                    (false, false) => "***BUSMASTER Ver 2.0.0***\n***HEX***\n***ABSOLUTE MODE***\n",
                };
                read(&mut p, header);
                let mut scanned = p.clone();
                let parsed = p.parse(line.as_bytes(), &Interest::all());
                let Parsed::Frame(f) = parsed.clone() else {
                    // Headerless without data: only the id width can tell, and
                    // a 3-digit hex id of digits only reads as hex.
                    prop_assert!(headerless && data.is_empty(), "{line}: {parsed:?}");
                    return Ok(());
                };
                if !(headerless && data.is_empty()) {
                    prop_assert_eq!((f.id, f.extended), (id, extended), "{}", line);
                }
                prop_assert_eq!(f.data.as_slice(), &data[..]);
                prop_assert_eq!(f.time, Some(Timestamp::from_parts(tenths / 10_000, tenths % 10_000, 4)));
                match scanned.scan(line.as_bytes(), &Interest::all()) {
                    Scan::Parse => prop_assert!(headerless),
                    Scan::Frame(g) => prop_assert_eq!(Parsed::Frame(g), parsed),
                    other => prop_assert!(false, "{:?}", other),
                }
            }

            /// The one-pass reading of the common shape accepts only lines the
            /// general reading reads, and reads them alike.
            #[test]
            fn common_shape_agrees_with_the_general_reading(
                line in "[0-9]{1,3}:[0-9]{1,3}:[0-9]{1,2}:[0-9]{1,5}[ ]{1,2}(Rx|Tx|Qx) [0-9]{1,4} (0x)?[0-9A-Fa-f]{1,11} (s|x|sr)[ ]{1,2}[0-9]{1,2}( [0-9A-F]{1,3}){0,9}[ ]{0,2}",
                dec in any::<bool>(),
                absolute in any::<bool>(),
            ) {
                let mut p = BusmasterParser::new();
                read(&mut p, if dec { "***DEC***\n" } else { "***HEX***\n" });
                if absolute {
                    read(&mut p, "***ABSOLUTE MODE***\n");
                }
                let Some(c) = p.common(line.as_bytes()) else {
                    return Ok(());
                };
                let mut fields = Fields::EMPTY;
                prop_assert!(fields.split(line.as_bytes()));
                let general = p.can_line(&fields, &Interest::all());
                let Ok(g) = general else {
                    prop_assert!(false, "only the fast path reads {}", line);
                    return Ok(());
                };
                prop_assert_eq!((c.id, c.extended, c.len, c.channel), (g.frame.id, g.frame.extended, g.frame.len, g.frame.channel));
                prop_assert_eq!(c.time, g.time);
                prop_assert_eq!(p.clone().commit(c.time).is_ok(), p.clone().commit(g.time).is_ok());
                let mut q = p.clone();
                match q.scan(line.as_bytes(), &Interest::all()) {
                    Scan::Frame(f) => prop_assert_eq!(f.data, g.frame.data),
                    other => prop_assert!(false, "{:?}", other),
                }
            }

            /// Any line: scan only counts frames, and leaves the same state.
            #[test]
            fn scan_agrees_with_parse(
                line in "[0-9]{1,3}:[0-9]{1,2}:[0-9]{1,2}:[0-9]{1,5} (Rx|Tx|Qx) [0-9a]{1,2} (0x)?[0-9A-Fa-f]{1,9} (s|x|sr|xr|s-fd|ERR|q) [0-9]{1,2}( [0-9A-F]{1,3}){0,10} ?",
                relative in any::<bool>(),
                dec in any::<bool>(),
            ) {
                let mut p = BusmasterParser::new();
                read(&mut p, if dec { "***DEC***\n" } else { "***HEX***\n" });
                if relative {
                    read(&mut p, "***RELATIVE MODE***\n00:00:01:0000 Rx 1 1 s 0\n");
                }
                let mut scanned = p.clone();
                let scan = scanned.scan(line.as_bytes(), &Interest::none());
                let parsed = p.parse(line.as_bytes(), &Interest::none());
                match scan {
                    Scan::Plain(key) => {
                        prop_assert!(matches!(&parsed, Parsed::Frame(f) if f.key() == key), "{}", line);
                        prop_assert_eq!(scanned.now, p.now);
                        prop_assert_eq!(scanned.context(), p.context());
                    }
                    Scan::Parse => {}
                    other => prop_assert!(false, "nothing is wanted: {:?}", other),
                }
            }
        }
    }
}
