//! Vector ASC reader (CANalyzer/CANoe ASCII logging; also written by
//! can-utils `log2asc` and python-can's `ASCWriter`):
//!
//! ```text
//! date Sam Sep 30 15:06:13.191 2017
//! base hex  timestamps absolute
//!    3.098426 1  18EBFF00x       Rx d 8 01 A0 0F A6 60 3B D1 40    Length = 273910 BitCount = 141 ID = 418119424x
//!    2.584921 4 300 Tx r 8
//!    2.501020 2 ErrorFrame Flags = 0xe CodeExt = 0x20a2 Code = 0x82
//!   30.005071 CANFD   3 Rx   30a  Generic_Name_12   1 1 8  8 01 02 03 04 05 06 07 08   102203  133   303000 e0006659 ...
//! ```
//!
//! The parser is stateful: the `base` header decides whether ids and data
//! bytes are hex or decimal, and `timestamps relative` turns every line's time
//! into a delta from the previous timestamped line, so the running time is
//! kept here. Lines that are known Vector events but not CAN frames (status,
//! statistics, other buses, variables, markers) are skipped; anything else
//! that does not parse is malformed with a reason.

mod body;
mod error;
mod shape;
mod syntax;

use crate::time::MAX_FRACTION_DIGITS;
use crate::{
    Format, Frame, FrameKind, Interest, LineParser, Parsed, Payload, Reason, Scan, Timestamp,
};
use crate::{hex, scan};

use body::{check_tail, classic_data, fd_body};
use shape::{AscLayout, AscShape, Places, blanks_after, canonical_tail, id_field};
use syntax::{
    Base, FD_TAIL_FULL, Tokens, is, is_digits, is_other_event, is_tx_request, parse_dlc, parse_id,
    show, start_of_measurement, starts_with_ic, words,
};

/// Reads ASC lines; keeps the header settings and the running time.
#[derive(Clone)]
pub struct AscParser {
    base: Base,
    relative: bool,
    /// Time of the last timestamped line (the running sum when relative).
    now: Timestamp,
    /// The layout of the last canonical line (a cache: results never
    /// depend on it, only speed).
    layout: Option<AscLayout>,
    /// What the last line's frame needed made good (see
    /// [`LineParser::take_warning`]).
    warning: Option<Reason>,
    /// A `base` or `Begin Triggerblock` line was read: only ASC writes them.
    identified: bool,
}

impl AscParser {
    /// Without a header: hex numbers, absolute times (what log2asc and
    /// CANoe write by default).
    pub fn new() -> Self {
        AscParser {
            base: Base::Hex,
            relative: false,
            now: Timestamp::ZERO,
            layout: None,
            warning: None,
            identified: false,
        }
    }
}

impl Default for AscParser {
    fn default() -> Self {
        AscParser::new()
    }
}

impl LineParser for AscParser {
    fn format(&self) -> Format {
        Format::Asc
    }

    #[inline]
    fn scan<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Scan<'a> {
        let Some(shape) = self.shape(line) else {
            return Scan::Parse;
        };
        if !interest.wants(shape.id, shape.extended) {
            self.now = shape.time;
            return Scan::Plain(shape.key(line));
        }
        match shape.frame(line, true) {
            Some(frame) => {
                self.now = shape.time;
                if interest.timed_only(frame.id, frame.extended, frame.data.as_slice()) {
                    Scan::Timed(shape.time, frame.key())
                } else {
                    Scan::Frame(frame)
                }
            }
            None => Scan::Parse,
        }
    }

    /// The number base; relative timestamps chain every line to the last.
    fn clock(&self) -> Option<Timestamp> {
        self.relative.then_some(self.now)
    }

    fn context(&self) -> Option<u8> {
        match (self.relative, self.base) {
            (true, _) => None,
            (false, Base::Hex) => Some(0),
            (false, Base::Dec) => Some(1),
        }
    }

    fn take_warning(&mut self) -> Option<Reason> {
        self.warning.take()
    }

    fn identified(&self) -> bool {
        self.identified
    }

    #[inline]
    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        self.warning = None;
        if let Some((frame, now)) = self.canonical(line, interest) {
            self.now = now;
            return Parsed::Frame(frame);
        }
        match self.parse_line(line, interest) {
            Ok(Some(frame)) => Parsed::Frame(frame),
            Ok(None) => Parsed::Skipped,
            Err(reason) => Parsed::Malformed(reason),
        }
    }
}

impl AscParser {
    /// The fast path for the classic frame line CANoe and log2asc write, by
    /// far the most common line of an ASC trace:
    /// `T CH ID[x] Rx|Tx d DLC HH... [Length = n BitCount = n ID = n[x]]`
    /// with hex numbers, DLC 0-8 and two-digit bytes. Anything else returns
    /// `None` and goes to the full parser (the one source of error messages);
    /// what this accepts, the full parser reads identically. Returns the frame
    /// and the new running time; the caller commits it.
    #[inline]
    fn canonical<'a>(&self, line: &'a [u8], interest: &Interest) -> Option<(Frame<'a>, Timestamp)> {
        let shape = self.shape_general(line)?;
        let frame = shape.frame(line, interest.wants(shape.id, shape.extended))?;
        Some((frame, shape.time))
    }

    /// Validates a canonical line (see [`AscParser::canonical`]) without
    /// building a frame; computes the running time.
    /// The shape of a canonical line: the last line's layout first, then
    /// the general scan (which then becomes the layout).
    #[inline]
    fn shape(&mut self, line: &[u8]) -> Option<AscShape> {
        if self.base != Base::Hex {
            return None;
        }
        if let Some(layout) = self.layout.as_ref()
            && let Some(shape) = self.shape_as(layout, line)
        {
            return Some(shape);
        }
        let shape = self.shape_general(line)?;
        self.layout = AscLayout::of(line, &shape);
        Some(shape)
    }

    /// The shape of a line with `layout`'s fixed part.
    #[inline]
    fn shape_as(&self, layout: &AscLayout, line: &[u8]) -> Option<AscShape> {
        let at = layout.at;
        if layout.lead.is_some_and(|lead| !lead.matches(line, 0))
            || line.get(at.dot) != Some(&b'.')
            || !layout.digits.matches(line)
            || !layout.gap.matches(line, at.time_end)
        {
            return None;
        }
        let (id, extended, id_end) = id_field(line, at.id)?;
        if id_end >= at.dir || !scan::all_spaces_at(line, id_end, at.dir) {
            return None;
        }
        if !layout.mid.matches(line, at.dir) {
            return None;
        }
        let (start, len) = layout.channel;
        self.finish(line, at, start..start + len, id, extended)
    }

    /// Validates a canonical line (see [`AscParser::canonical`]) without
    /// building a frame; computes the running time.
    #[inline]
    fn shape_general(&self, line: &[u8]) -> Option<AscShape> {
        // The fast path reads hex numbers only.
        if self.base != Base::Hex {
            return None;
        }
        let time_at = scan::blank_run(line, 0);
        if time_at == 0 && line.first().is_some_and(|b| !b.is_ascii_digit()) {
            return None;
        }
        // Time: digits '.' digits.
        let int_len = scan::digit_run(line, time_at);
        let dot = time_at + int_len;
        if int_len == 0 || int_len > 19 || line.get(dot) != Some(&b'.') {
            return None;
        }
        let frac_len = scan::digit_run(line, dot + 1);
        let time_end = dot + 1 + frac_len;
        if frac_len == 0 || frac_len > MAX_FRACTION_DIGITS {
            return None;
        }
        // Channel: a small decimal number.
        let channel_start = blanks_after(line, time_end)?;
        let ch_len = scan::digit_run(line, channel_start);
        if ch_len == 0 || ch_len > 3 {
            return None;
        }
        // Id, hex, `x` for extended.
        let id_at = blanks_after(line, channel_start + ch_len)?;
        let (id, extended, id_end) = id_field(line, id_at)?;
        // Direction, `d`, DLC.
        let dir = blanks_after(line, id_end)?;
        match line.get(dir..dir + 2)? {
            b"Rx" | b"Tx" => {}
            _ => return None,
        }
        let d = blanks_after(line, dir + 2)?;
        if line.get(d) != Some(&b'd') {
            return None;
        }
        let dlc = blanks_after(line, d + 1)?;
        let at = Places {
            time: time_at,
            dot,
            time_end,
            id: id_at,
            dir,
            dlc,
        };
        self.finish(
            line,
            at,
            channel_start..channel_start + ch_len,
            id,
            extended,
        )
    }

    /// The time, the DLC and data bytes and the tail, once the fields
    /// before them are known.
    #[inline]
    fn finish(
        &self,
        line: &[u8],
        at: Places,
        channel: std::ops::Range<usize>,
        id: u32,
        extended: bool,
    ) -> Option<AscShape> {
        let dlc = match line.get(at.dlc) {
            Some(d @ b'0'..=b'8') => d - b'0',
            _ => return None,
        };
        // Bytes: a single blank, then two hex digits, DLC times.
        let data_start = at.dlc + 1;
        let mut i = data_start;
        for _ in 0..dlc {
            if line.get(i) != Some(&b' ') {
                return None;
            }
            let (&hi, &lo) = (line.get(i + 1)?, line.get(i + 2)?);
            hex::parse_byte(hi, lo)?;
            i += 3;
        }
        if !canonical_tail(line.get(i..)?) {
            return None;
        }
        let frac = line.get(at.dot + 1..at.time_end)?;
        let written = Timestamp::from_parts(
            scan::decimal_u64(line.get(at.time..at.dot)?),
            scan::decimal_u64(frac),
            frac.len() as u8,
        );
        let time = if self.relative {
            self.now.checked_add(written)?
        } else {
            written
        };
        Some(AscShape {
            time,
            channel,
            id,
            extended,
            dlc,
            data_start,
            places: at,
        })
    }

    fn parse_line<'a>(
        &mut self,
        line: &'a [u8],
        interest: &Interest,
    ) -> Result<Option<Frame<'a>>, Reason> {
        // A file saved by a Windows editor may start with a UTF-8 byte order mark.
        let line = line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(line);
        let all = Tokens::new(line);
        let mut toks = all.clone();
        let Some(first) = toks.next() else {
            return Ok(None);
        };
        if first.starts_with(b"//") {
            return Ok(None);
        }
        if !first.first().is_some_and(u8::is_ascii_digit) {
            return self.header(first, toks, all).map(|()| None);
        }
        let written =
            Timestamp::parse(first).map_err(|e| Reason::from(format!("{e}: '{}'", show(first))))?;
        // Every timestamped line advances relative time, even one that turns
        // out malformed: its delta is still part of the sum.
        let time = self.advance(written)?;
        self.event(time, toks, interest)
    }

    fn advance(&mut self, written: Timestamp) -> Result<Timestamp, Reason> {
        let time = if self.relative {
            self.now
                .checked_add(written)
                .ok_or("relative timestamps add up past 2^64 seconds")?
        } else {
            written
        };
        self.now = time;
        Ok(time)
    }

    /// Lines without a timestamp: the header and trigger block markers.
    fn header(&mut self, first: &[u8], rest: Tokens<'_>, all: Tokens<'_>) -> Result<(), Reason> {
        let begin =
            is(first, b"begin") && rest.clone().next().is_some_and(|t| is(t, b"triggerblock"));
        let known = is(first, b"date")
            || words(rest.clone(), &[b"events", b"logged"]) && is(first, b"internal")
            || words(rest.clone(), &[b"internal", b"events", b"logged"]) && is(first, b"no")
            || begin
            || is(first, b"end") && words(rest.clone(), &[b"triggerblock"])
            || start_of_measurement(all);
        if known {
            // `date` alone does not identify the format: a pasted shell
            // `date` looks the same.
            self.identified |= begin;
            return Ok(());
        }
        if is(first, b"base") {
            let read = self.base_line(rest);
            self.identified |= read.is_ok();
            return read;
        }
        Err(format!(
            "unknown line: '{}' is neither a timestamp nor an ASC header keyword",
            show(first)
        )
        .into())
    }

    /// `base hex|dec  timestamps absolute|relative`; a bad line changes nothing.
    fn base_line(&mut self, mut rest: Tokens<'_>) -> Result<(), Reason> {
        let base = match rest.next() {
            Some(t) if is(t, b"hex") => Base::Hex,
            Some(t) if is(t, b"dec") => Base::Dec,
            Some(t) => {
                return Err(format!("number base '{}' is neither hex nor dec", show(t)).into());
            }
            None => return Err("'base' line names no number base (hex or dec)".into()),
        };
        let relative = match rest.next() {
            None => None,
            Some(t) if is(t, b"timestamps") => match rest.next() {
                Some(m) if is(m, b"absolute") => Some(false),
                Some(m) if is(m, b"relative") => Some(true),
                Some(m) => {
                    return Err(format!(
                        "timestamp mode '{}' is neither absolute nor relative",
                        show(m)
                    )
                    .into());
                }
                None => return Err("'base' line ends after 'timestamps'".into()),
            },
            Some(t) => {
                return Err(format!(
                    "unexpected '{}' in the 'base' line (expected 'timestamps')",
                    show(t)
                )
                .into());
            }
        };
        if let Some(t) = rest.next() {
            return Err(format!("unexpected '{}' at the end of the 'base' line", show(t)).into());
        }
        self.base = base;
        if let Some(relative) = relative {
            // Turning relative times on starts the running time at 0 (the
            // measurement start of what follows, as at the top of a file),
            // not at the last absolute time: otherwise the state after this
            // line would depend on lines before it that `context` does not
            // show, and a block read in parallel would get other times.
            if relative && !self.relative {
                self.now = Timestamp::ZERO;
            }
            self.relative = relative;
        }
        Ok(())
    }

    /// Everything after a timestamp.
    fn event<'a>(
        &mut self,
        time: Timestamp,
        mut toks: Tokens<'a>,
        interest: &Interest,
    ) -> Result<Option<Frame<'a>>, Reason> {
        if start_of_measurement(toks.clone()) {
            return Ok(None);
        }
        let after = toks.clone();
        let Some(what) = toks.next() else {
            return Err("timestamp is not followed by an event".into());
        };
        if is_digits(what) {
            return self.channel_event(time, what, toks, interest);
        }
        if is(what, b"CANFD") {
            return self.canfd(time, toks, interest);
        }
        if is(what, b"CANXL") {
            // These can carry classic and FD frames (log2asc -x); saying so
            // beats dropping them silently.
            return Err("CANXL lines are not read (CAN XL logging format)".into());
        }
        if is(what, b"CAN") {
            return match (toks.next(), toks.next()) {
                (Some(ch), Some(status)) if is_digits(ch) && starts_with_ic(status, b"Status:") => {
                    Ok(None)
                }
                _ => Err("'CAN' event is not 'CAN <channel> Status:...'".into()),
            };
        }
        if is_other_event(what, toks.clone()) {
            return Ok(None);
        }
        // Environment variable: `T name := value`.
        if memchr::memmem::find(after.rest(), b":=").is_some() {
            return Ok(None);
        }
        Err(format!("unknown event '{}' after the timestamp", show(what)).into())
    }

    /// `T CH ...`: a classic frame, an error frame or a channel statistic.
    fn channel_event<'a>(
        &self,
        time: Timestamp,
        channel: &'a [u8],
        mut toks: Tokens<'a>,
        interest: &Interest,
    ) -> Result<Option<Frame<'a>>, Reason> {
        let after = toks.clone();
        let Some(what) = toks.next() else {
            return Err("line ends after the channel number".into());
        };
        if is(what, b"ErrorFrame") {
            return Ok(Some(error::classic(toks).frame(Some(time), channel)));
        }
        let known = is(what, b"Statistic:")
            || is(what, b"OverloadFrame")
            || is(what, b"J1939TP")
            // Macro signal: `T CH Node::Msg::Signal = value`.
            || memchr::memmem::find(what, b"::").is_some()
            // Global marker: `T n n n 0|1 GMGroup: ...`.
            || after.take(5).any(|t| is(t, b"GMGroup:"));
        if known {
            return Ok(None);
        }
        self.classic(time, channel, what, toks, interest)
    }

    /// `ID[x] DIR d DLC BYTE* [tail]` or `ID[x] DIR r [DLC] [tail]`.
    fn classic<'a>(
        &self,
        time: Timestamp,
        channel: &'a [u8],
        id_tok: &[u8],
        mut toks: Tokens<'a>,
        interest: &Interest,
    ) -> Result<Option<Frame<'a>>, Reason> {
        let (id, extended) = parse_id(id_tok, self.base)?;
        let dir = toks
            .next()
            .ok_or("line ends after the id (expected Rx, Tx or TxRq)")?;
        if is_tx_request(dir)? {
            return Ok(None);
        }
        let kind = toks
            .next()
            .ok_or("line ends after the direction (expected d or r)")?;
        let mut frame = Frame {
            time: Some(time),
            channel,
            id,
            extended,
            kind: FrameKind::Data,
            len: 0,
            data: Payload::new(),
        };
        if is(kind, b"d") {
            let dlc_tok = toks.next().ok_or("data frame has no DLC")?;
            let dlc = parse_dlc(dlc_tok, self.base)
                .ok_or_else(|| format!("DLC '{}' is not a hex digit 0-F", show(dlc_tok)))?;
            // DLC 9..F on a classic frame still means 8 bytes.
            let expected = dlc.min(8);
            let wanted = interest.wants(id, extended);
            classic_data(
                &mut toks,
                expected,
                self.base,
                wanted.then_some(&mut frame.data),
            )?;
            frame.len = expected;
        } else if is(kind, b"r") {
            let mut peek = toks.clone();
            if peek
                .next()
                .is_some_and(|t| parse_dlc(t, self.base).is_some())
            {
                toks = peek;
            }
            frame.kind = FrameKind::Remote;
        } else {
            return Err(format!(
                "frame type '{}' is neither d (data) nor r (remote)",
                show(kind)
            )
            .into());
        }
        check_tail(toks.rest())?;
        Ok(Some(frame))
    }

    /// `CANFD CH DIR ID[x] [NAME] BRS ESI DLC DATALEN BYTE* DUR LEN FLAGS ...`
    fn canfd<'a>(
        &mut self,
        time: Timestamp,
        mut toks: Tokens<'a>,
        interest: &Interest,
    ) -> Result<Option<Frame<'a>>, Reason> {
        if start_of_measurement(toks.clone()) {
            return Ok(None);
        }
        let channel = toks.next().ok_or("CANFD line ends after 'CANFD'")?;
        if !is_digits(channel) {
            return Err(format!("CANFD channel '{}' is not a number", show(channel)).into());
        }
        let dir = toks.next().ok_or("CANFD line ends after the channel")?;
        let tx_request = is_tx_request(dir)?;
        let what = toks.next().ok_or("CANFD line ends after the direction")?;
        if is(what, b"ErrorFrame") {
            let e = error::fd(is(dir, b"Tx"), toks.rest());
            return Ok(Some(e.frame(Some(time), channel)));
        }
        let (id, extended) = parse_id(what, self.base)?;
        if tx_request {
            return Ok(None);
        }
        let wanted = interest.wants(id, extended);

        // The symbolic name is optional and may itself be a number, so try
        // both layouts and keep the one whose fields are consistent.
        let plain = fd_body(toks.clone(), self.base, wanted);
        let mut after_name = toks;
        let name = after_name.next();
        let named = fd_body(after_name, self.base, wanted);
        let body = match (plain, named) {
            (Ok(p), Err(_)) => p,
            (Err(_), Ok(n)) => n,
            // A layout that needs no contradiction resolved beats one that does.
            (Ok(p), Ok(n)) if p.warning.is_some() != n.warning.is_some() => {
                if p.warning.is_none() {
                    p
                } else {
                    n
                }
            }
            (Ok(p), Ok(n)) => {
                if p.same_frame(&n)
                    || (p.after_data == FD_TAIL_FULL && n.after_data != FD_TAIL_FULL)
                {
                    p
                } else if n.after_data == FD_TAIL_FULL && p.after_data != FD_TAIL_FULL {
                    n
                } else {
                    return Err(format!(
                        "ambiguous CANFD line: '{}' reads both as a symbolic name and as the BRS flag",
                        show(name.unwrap_or_default())
                    )
                    .into());
                }
            }
            // Report the layout the writer most likely meant: a token that
            // cannot be a BRS flag is a name.
            (Err(p), Err(n)) => {
                return Err(if name.is_some_and(|t| t != b"0" && t != b"1") {
                    n
                } else {
                    p
                });
            }
        };
        self.warning = body.warning;
        Ok(Some(Frame {
            time: Some(time),
            channel,
            id,
            extended,
            kind: body.kind,
            len: body.len,
            data: body.data,
        }))
    }
}

#[cfg(test)]
mod tests {
    mod fast_path {
        use super::super::*;
        use proptest::prelude::*;

        #[test]
        fn scan_counts_valid_unwanted_lines_decodes_wanted_ones_and_keeps_the_clock() {
            let mut interest = Interest::none();
            interest.add_standard(0x81);
            let mut p = parser(true, 5);
            assert_eq!(
                p.scan(b"   0.5 1  181  Rx   d 1 00", &interest),
                Scan::Plain(crate::FrameKey::new(b"1", 0x181, false))
            );
            assert_eq!(p.now.to_string(), "5.750");
            let Scan::Frame(f) = p.scan(b"   0.25 1  81  Rx   d 2 10 8A", &interest) else {
                panic!("a wanted frame is decoded");
            };
            assert_eq!((f.id, f.data.as_slice()), (0x81, &[0x10, 0x8A][..]));
            assert_eq!(f.time.map(|t| t.to_string()).as_deref(), Some("6.000"));
            assert_eq!(p.now.to_string(), "6.000");
            assert_eq!(
                p.scan(b"   0.5 1  181  Rx   d 2 00", &interest),
                Scan::Parse,
                "invalid"
            );
            assert_eq!(
                p.now.to_string(),
                "6.000",
                "a declined line leaves the clock"
            );
        }

        #[test]
        fn frames_the_content_filter_rejects_are_only_timed() {
            let mut interest = Interest::none();
            interest.add_standard(0x705);
            interest.filter_content(0x705..=0x705, crate::ContentFilter(|_, d| d.head() == [0]));
            let mut p = parser(false, 0);
            assert_eq!(
                p.scan(b"   2.500000 1  705             Rx   d 1 05", &interest),
                Scan::Timed(
                    Timestamp::from_parts(2, 500_000, 6),
                    crate::FrameKey::new(b"1", 0x705, false)
                )
            );
            assert!(matches!(
                p.scan(b"   3.000000 1  705             Rx   d 1 00", &interest),
                Scan::Frame(f) if f.data.as_slice() == [0]
            ));
        }

        fn parser(relative: bool, now: u64) -> AscParser {
            let mut p = AscParser::new();
            p.relative = relative;
            p.now = Timestamp::from_parts(now, 250, 3);
            p
        }

        proptest! {
            /// What the fast path accepts, the full parser reads identically,
            /// including the running time it leaves behind.
            #[test]
            fn agrees_with_the_full_parser(
                line in "[ \t]{0,3}[0-9]{0,20}\\.?[0-9]{0,19}[ ]{0,2}[0-9]{0,4}[ ]{1,3}[0-9a-fA-FxX]{0,10}[ ]{1,14}(Rx|Tx|rx|TxRq)[ ]{1,3}[dDr][ ]{1,2}[0-9a-fA-F]{1,2}( [0-9a-fA-F]{1,3}){0,9}( {1,4}Length = [0-9]{0,6} BitCount = [0-9]{1,3} ID = [0-9]{1,9}x?| x)?[ ]{0,2}",
                relative in any::<bool>(),
                now in 0u64..1000,
                narrow in any::<bool>(),
            ) {
                let mut interest = if narrow { Interest::none() } else { Interest::all() };
                interest.add_standard(0x81);
                let fast = parser(relative, now);
                if let Some((frame, time)) = fast.canonical(line.as_bytes(), &interest) {
                    let mut full = parser(relative, now);
                    prop_assert_eq!(full.parse_line(line.as_bytes(), &interest), Ok(Some(frame)));
                    prop_assert_eq!(full.now, time);
                }
            }

            /// The last line's layout accepts exactly what the general scan
            /// accepts at the same places, and takes the usual next line.
            #[test]
            fn layout_agrees_with_the_general_scan(
                first in r"[ ]{0,4}[0-9]{1,6}\.[0-9]{6} [1-9]  ([0-7][0-9A-F]{2}|1[0-9A-F]{7}x)[ ]{1,13} (Rx|Tx)   d (0|2 [0-9A-F]{2} [0-9A-F]{2}|8( [0-9A-F]{2}){8})(  Length = [0-9]{1,6} BitCount = [0-9]{2,3} ID = [0-9]{1,9}x?)?",
                next in r"[ \t]{0,4}[0-9]{0,7}\.?[0-9]{0,7}[ ]{0,2}[0-9]{0,3}[ ]{1,3}[0-9a-fA-FxX]{0,10}[ ]{1,14}(Rx|Tx|rx)[ ]{1,3}[dDr][ ]{1,2}[0-9a-fA-F]{1,2}( [0-9a-fA-F]{1,3}){0,9}( {1,4}Length = [0-9]{0,6} BitCount = [0-9]{1,3} ID = [0-9]{1,9}x?| x)?[ ]{0,2}",
                at in 0usize..80,
                byte in proptest::sample::select(b"09aG.x dR\t".to_vec()),
                relative in any::<bool>(),
            ) {
                let mut p = parser(relative, 3);
                // The DLC and bytes of `first` may disagree: cut to the DLC.
                let Some(general) = p.shape_general(first.as_bytes()) else {
                    return Ok(());
                };
                let Some(layout) = AscLayout::of(first.as_bytes(), &general) else {
                    return Ok(());
                };
                for line in [next.as_bytes().to_vec(), {
                    let mut l = first.as_bytes().to_vec();
                    if let Some(b) = l.get_mut(at) {
                        *b = byte;
                    }
                    l
                }] {
                    if let Some(fast) = p.shape_as(&layout, &line) {
                        prop_assert_eq!(Some(fast), p.shape_general(&line), "{:?}", String::from_utf8_lossy(&line));
                    }
                }
                prop_assert_eq!(p.shape_as(&layout, first.as_bytes()), Some(general));
                p.layout = Some(layout);
                prop_assert!(p.shape(first.as_bytes()).is_some());
            }

            /// The shape CANoe and log2asc write takes the fast path.
            #[test]
            fn takes_the_common_line(
                line in "[ ]{1,3}[0-9]{1,6}\\.[0-9]{4,9} [1-9]  ([0-7][0-9A-F]{2}|1[0-9A-F]{7}x)[ ]{1,13} (Rx|Tx)   d (0|1 [0-9A-F]{2}|8( [0-9A-F]{2}){8})(  Length = [0-9]{1,6} BitCount = [0-9]{2,3} ID = [0-9]{1,9}x?)?",
            ) {
                for relative in [false, true] {
                    let p = parser(relative, 7);
                    let fast = p.canonical(line.as_bytes(), &Interest::all());
                    prop_assert!(fast.is_some(), "declined {}", line);
                    let mut full = parser(relative, 7);
                    prop_assert_eq!(full.parse_line(line.as_bytes(), &Interest::all()), Ok(fast.clone().map(|f| f.0)));
                    prop_assert_eq!(Some(full.now), fast.map(|f| f.1));
                }
            }
        }
    }

    use super::syntax::{EXTENDED_MAX, STANDARD_MAX};
    use super::*;

    fn parse_with<'a>(p: &mut AscParser, line: &'a str) -> Parsed<'a> {
        p.parse(line.as_bytes(), &Interest::all())
    }

    fn parse(line: &str) -> Parsed<'_> {
        parse_with(&mut AscParser::new(), line)
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

    fn time(f: &Frame<'_>) -> String {
        f.time.expect("ASC frames carry a time").to_string()
    }

    const FD_EXAMPLE: &str = "  30.005071 CANFD   3 Rx        30a  Generic_Name_12                  1 1 8  8 01 02 03 04 05 06 07 08   102203  133   303000 e0006659 46500250 4b140250 20011736 2001040d";

    #[test]
    fn classic_extended_frame_with_tail() {
        let f = frame(
            "   3.098426 1  18EBFF00x       Rx d 8 01 A0 0F A6 60 3B D1 40    Length = 273910 BitCount = 141 ID = 418119424x",
        );
        assert_eq!(time(&f), "3.098426");
        assert_eq!(f.channel, b"1");
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x18EB_FF00, true, FrameKind::Data, 8)
        );
        assert_eq!(
            f.data.as_slice(),
            [0x01, 0xA0, 0x0F, 0xA6, 0x60, 0x3B, 0xD1, 0x40]
        );
    }

    #[test]
    fn log2asc_classic_frame() {
        let f = frame("   0.003287 1  123             Rx   d 8 11 22 33 44 55 66 77 88");
        assert_eq!(time(&f), "0.003287");
        assert_eq!((f.id, f.extended, f.len), (0x123, false, 8));
        assert_eq!(f.data.as_slice()[7], 0x88);
        // Standard id with the optional tail (python-can test data).
        let f = frame(
            "  17.876708 1  6F9             Rx   d 8 05 0C 00 00 00 00 00 00  Length = 240015 BitCount = 124 ID = 1785",
        );
        assert_eq!((f.id, f.extended), (0x6F9, false));
        // Tabs, lower-case hex, one-digit bytes, zero bytes.
        let f = frame("1.5\t2\t1a0\tTx\td\t2\tab\tc");
        assert_eq!((f.id, f.channel), (0x1A0, &b"2"[..]));
        assert_eq!(f.data.as_slice(), [0xAB, 0x0C]);
        assert_eq!(frame("1.0 1 081 Rx d 0").len, 0);
    }

    #[test]
    fn extended_marker_and_id_limits() {
        let f = frame("1.0 1 123x Rx d 1 00");
        assert_eq!((f.id, f.extended), (0x123, true));
        assert_eq!(frame("1.0 1 1FFFFFFFX Rx d 0").id, 0x1FFF_FFFF);
        assert_eq!(frame("1.0 1 7FF Rx d 0").id, 0x7FF);
        assert_eq!(frame("1.0 1 00000000081 Rx d 0").id, 0x81);
        assert!(malformed("1.0 1 800 Rx d 0").contains("standard id '800' is above 7FF"));
        assert!(malformed("1.0 1 20000000x Rx d 0").contains("extended id '20000000x' is above"));
        assert!(malformed("1.0 1 123456789x Rx d 0").contains("above 1FFFFFFF"));
    }

    #[test]
    fn remote_frames() {
        let f = frame("   2.584921 4 300 Tx r 8 Length = 1704000 BitCount = 145 ID = 88888888x");
        assert_eq!(f.channel, b"4");
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x300, false, FrameKind::Remote, 0)
        );
        assert!(f.data.is_empty());
        assert_eq!(frame("1.0 1 300 Rx r").kind, FrameKind::Remote);
        assert_eq!(frame("1.0 1 300x Rx r F").kind, FrameKind::Remote);
        assert!(
            malformed("1.0 1 300 Rx r 8 junk").contains("unexpected text after the frame: 'junk'")
        );
    }

    #[test]
    fn error_frames() {
        let f = frame(
            "   2.501020 2 ErrorFrame Flags = 0xe CodeExt = 0x20a2 Code = 0x82 ID = 0 DLC = 0 Position = 5 Length = 11300",
        );
        assert_eq!(time(&f), "2.501020");
        assert_eq!(f.channel, b"2");
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x88, false, FrameKind::Error, 8)
        );
        assert_eq!(f.data.as_slice(), [0, 0, 0x04, 0, 0, 0, 0, 0]);
        let unknown = frame("   0.5 1  ErrorFrame");
        assert_eq!(
            (unknown.kind, unknown.id, unknown.len),
            (FrameKind::Error, 0, 0)
        );
        let ecc = frame("3.501000 1 ErrorFrame ECC: 10100010");
        assert_eq!((ecc.kind, ecc.id), (FrameKind::Error, 0x88));
        assert_eq!(ecc.data.as_slice(), [0, 0, 0x04, 0x02, 0, 0, 0, 0]);
        let f = frame(
            "  30.806898 CANFD   5 Tx ErrorFrame Not Acknowledge error, dominant error flag fffe c7 31ca Arb. 556 44 0 0 f 64 00 00",
        );
        assert_eq!(
            (f.kind, f.channel, f.id),
            (FrameKind::Error, &b"5"[..], 0xA8)
        );
        assert_eq!(f.data.as_slice(), [0, 0, 0x80, 0x19, 0, 0, 0, 0]);
    }

    #[test]
    fn headers_and_markers_are_skipped() {
        for line in [
            "",
            "   ",
            "\t",
            "date Sam Sep 30 15:06:13.191 2017",
            "date Thu Apr 28 10:44:52.480 am 2022",
            "date",
            "base hex  timestamps absolute",
            "internal events logged",
            " internal events logged",
            "no internal events logged",
            "// version 9.0.0",
            "//comment without a space",
            "   // Measurement UUID: cc9c7b54-68ae-46d2-a43a-6aa87df7dd74",
            "Begin Triggerblock Sam Sep 30 15:06:13.191 2017",
            "Begin TriggerBlock Thu Apr 28 10:44:52.480 am 2022",
            "begin triggerblock",
            "End TriggerBlock",
            "End Triggerblock",
            "   0.000000 Start of measurement",
            "0.000000 Start der Messung",
            "Start der Messung",
            "0.000000 CANFD   Start of measurement",
            "\u{feff}date Mon Jan 1 00:00:00 2024",
        ] {
            assert_eq!(parse(line), Parsed::Skipped, "{line:?}");
        }
        assert!(malformed("End TriggerBlock now").contains("unknown line"));
        assert!(malformed("hello world").contains("unknown line: 'hello'"));
    }

    #[test]
    fn known_non_frame_events_are_skipped() {
        for line in [
            "   0.015991 CAN 1 Status:chip status error passive - TxErr: 132 RxErr: 0",
            "  12.3 CAN 2 Status: chip status error active",
            "   1.015991 1  Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%",
            "   3.297743 1  J1939TP FEE3p        6    0  0   -   Rx   d 23 A0 0F A6 60 3B D1 40 1F DE 80 25 DF C0 2B E1 00 4B FF FF 3C 0F 00 4B FF FF FF FF FF FF FF FF FF FF FF FF",
            "   3.297743 J1939TP FEE3p 6 0 0 - Rx d 23 A0",
            "   1.2 1 OverloadFrame",
            "   4.2 Li 1 Rx 3 00 11 22",
            "   4.2 L1 12 Rx 2 01 02 checksum = 5A header time = 40, full time = 90",
            "   5.0 SV: 2 0 0 ::Namespace::Var = 3",
            "   5.0 EnvSpeed := 12",
            "   5.1 log trigger event",
            "   5.2 log direct start (100ms)",
            "   5.3 log direct stop (200ms)",
            "   6.0 GPS-Device: 1 La: 48.1 Lo: 11.5 Alt: 500.0 Sp: 0.0 Co: 0.0",
            "   6.1 Comment: 1 a note",
            "   6.2 ETH 1 Rx 40:0011223344",
            "   6.3 AFDX 1 Rx 1 0 1 4:00112233",
            "   6.4 Fr RMSG 0 0 1 1 1 0 Rx 0 0 0 0 0 x 0 0 0 0 0",
            "   6.5 M1 LL: 1",
            "   6.6 KL1 Tx 10400 3 01 02 03",
            "   6.7 COM3 Rx 10400 1 55",
            "   6.8 DiagRequest [ECU] 10 01",
            "   7.0 1 Engine::EngineData::Speed = 100",
            "   7.1 1 0 1 0 GMGroup: g GMMarker: m GMDescription: d",
        ] {
            assert_eq!(parse(line), Parsed::Skipped, "{line:?}");
        }
        assert!(malformed("1.0 CAN 1 Bogus").contains("CAN <channel> Status"));
        assert!(malformed("1.0 Foo bar").contains("unknown event 'Foo'"));
        assert!(malformed("1.0").contains("not followed by an event"));
        assert!(malformed("1.0 1").contains("after the channel"));
        assert!(malformed("  59.1 CANXL 2 Rx CBFF 243215 176 432 f 8 e1").contains("CANXL"));
    }

    #[test]
    fn base_dec_makes_ids_and_data_decimal() {
        let mut p = AscParser::new();
        assert_eq!(
            parse_with(&mut p, "base dec  timestamps absolute"),
            Parsed::Skipped
        );
        match parse_with(&mut p, "1.0 1 129 Rx d 8 16 67 8 1 0 0 0 0") {
            Parsed::Frame(f) => {
                assert_eq!((f.id, f.extended), (0x81, false));
                assert_eq!(f.data.as_slice(), [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
            }
            other => panic!("{other:?}"),
        }
        match parse_with(&mut p, "1.0 1 418119424x Rx d 1 255") {
            Parsed::Frame(f) => {
                assert_eq!((f.id, f.extended), (0x18EB_FF00, true));
                assert_eq!(f.data.as_slice(), [0xFF]);
            }
            other => panic!("{other:?}"),
        }
        // DLC stays a hex digit (or 10..15 written in decimal).
        match parse_with(&mut p, "1.0 1 129 Rx d 12 1 2 3 4 5 6 7 8") {
            Parsed::Frame(f) => assert_eq!(f.len, 8),
            other => panic!("{other:?}"),
        }
        let Parsed::Malformed(r) = parse_with(&mut p, "1.0 1 1A0 Rx d 0") else {
            panic!("hex id in a dec file")
        };
        assert!(r.contains("not a decimal number"), "{r}");
        let Parsed::Malformed(r) = parse_with(&mut p, "1.0 1 129 Rx d 1 256") else {
            panic!("256 is not a byte")
        };
        assert!(r.contains("'256' is not a decimal byte"), "{r}");
        let Parsed::Malformed(r) = parse_with(&mut p, "1.0 1 2048 Rx d 0") else {
            panic!("2048 > 7FF")
        };
        assert!(r.contains("above 7FF"), "{r}");
        // CAN FD data follows the base too; DLC is hex, data length decimal.
        match parse_with(
            &mut p,
            "2.0 CANFD 1 Rx 129 1 0 9 12 1 2 3 4 5 6 7 8 9 10 11 255 0 0 3000 0 0 0 0 0",
        ) {
            Parsed::Frame(f) => {
                assert_eq!((f.id, f.kind, f.len), (0x81, FrameKind::Fd, 12));
                assert_eq!(f.data.as_slice()[11], 0xFF);
                assert_eq!(f.data.as_slice()[9], 10);
            }
            other => panic!("{other:?}"),
        }
        // Back to hex.
        assert_eq!(parse_with(&mut p, "base hex"), Parsed::Skipped);
        assert!(matches!(
            parse_with(&mut p, "1.0 1 1A0 Rx d 0"),
            Parsed::Frame(_)
        ));
    }

    #[test]
    fn bad_base_lines_are_malformed_and_change_nothing() {
        let mut p = AscParser::new();
        for (line, why) in [
            ("base oct  timestamps absolute", "neither hex nor dec"),
            (
                "base dec  timestamps sideways",
                "neither absolute nor relative",
            ),
            ("base dec  timestamps", "ends after 'timestamps'"),
            ("base dec  clocks absolute", "expected 'timestamps'"),
            ("base dec  timestamps relative extra", "at the end"),
            ("base", "names no number base"),
        ] {
            match parse_with(&mut p, line) {
                Parsed::Malformed(r) => assert!(r.contains(why), "{line:?}: {r}"),
                other => panic!("{line:?} -> {other:?}"),
            }
        }
        // Still hex and absolute.
        match parse_with(&mut p, "0.5 1 1A0 Rx d 0") {
            Parsed::Frame(f) => assert_eq!((f.id, time(&f).as_str()), (0x1A0, "0.5")),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn relative_timestamps_accumulate_over_every_timestamped_line() {
        let mut p = AscParser::new();
        assert_eq!(
            parse_with(&mut p, "base hex  timestamps relative"),
            Parsed::Skipped
        );
        let times: Vec<String> = [
            "0.1 1 081 Rx d 0",
            "0.25 1 081 Rx d 0",
            "0.05 CAN 1 Status:chip status error active",
            "0.05 1  Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%",
            "0.000100 1 081 Rx TxRq d 0",
            "0.000100 1 081 TxRq d 0",
            "1 2 ErrorFrame",
        ]
        .iter()
        .filter_map(|l| match parse_with(&mut p, l) {
            Parsed::Frame(f) => Some(time(&f)),
            _ => None,
        })
        .collect();
        // 0.1; 0.35; +0.05 +0.05 (skipped) +0.0001 (malformed: bad direction)
        // +0.0001 (TxRq, skipped) +1 -> 1.450200.
        assert_eq!(times, ["0.1", "0.35", "1.450200"]);

        // Absolute again: times as written.
        assert_eq!(
            parse_with(&mut p, "base hex  timestamps absolute"),
            Parsed::Skipped
        );
        match parse_with(&mut p, "0.5 1 081 Rx d 0") {
            Parsed::Frame(f) => assert_eq!(time(&f), "0.5"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn turning_relative_times_on_starts_from_zero() {
        // Found by fuzzing (fuzz/regressions/detect/asc-relative-after-absolute):
        // relative times went on from the last absolute time, which the
        // parser's context does not carry, so a block read on another thread
        // got other times than the same block read in order.
        let mut p = AscParser::new();
        let t = |p: &mut AscParser, l: &str| match parse_with(p, l) {
            Parsed::Frame(f) => time(&f),
            other => panic!("{other:?}"),
        };
        assert_eq!(t(&mut p, "0.45 1 081 Rx d 0"), "0.45");
        parse_with(&mut p, "base hex  timestamps relative");
        assert_eq!(t(&mut p, "0.1 1 081 Rx d 0"), "0.1");
        assert_eq!(t(&mut p, "0.1 1 081 Rx d 0"), "0.2");
        // Saying relative again changes nothing: the sum goes on.
        parse_with(&mut p, "base dec  timestamps relative");
        assert_eq!(t(&mut p, "0.1 1 129 Rx d 0"), "0.3");
    }

    #[test]
    fn relative_timestamp_overflow_is_malformed() {
        let mut p = AscParser::new();
        parse_with(&mut p, "base hex timestamps relative");
        assert!(matches!(
            parse_with(&mut p, "18446744073709551615.5 1 081 Rx d 0"),
            Parsed::Frame(_)
        ));
        match parse_with(&mut p, "0.5 1 081 Rx d 0") {
            Parsed::Malformed(r) => assert!(r.contains("add up past"), "{r}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn tx_requests_are_skipped() {
        assert_eq!(
            parse("1.0 1 123 TxRq d 8 01 02 03 04 05 06 07 08"),
            Parsed::Skipped
        );
        assert_eq!(parse("1.0 1 123 TxRq r"), Parsed::Skipped);
        assert_eq!(
            parse("1.0 CANFD 1 TxRq 123 1 0 8 8 01 02 03 04 05 06 07 08 0 0 3000 0 0 0 0 0"),
            Parsed::Skipped
        );
    }

    #[test]
    fn classic_dlc_above_8_means_8_bytes() {
        for dlc in ["9", "A", "c", "D", "F"] {
            let line = format!("1.0 1 3FF Tx d {dlc} 55 AA 01 02 03 04 05 06");
            let f = frame(&line);
            assert_eq!(f.len, 8, "{line}");
            assert_eq!(f.data.as_slice(), [0x55, 0xAA, 1, 2, 3, 4, 5, 6]);
        }
        // Not 13 (python-can once read `d D` as 32 bytes).
        let line = format!("1.0 1 3FF Tx d D {}", ["00"; 13].join(" "));
        assert_eq!(malformed(&line), "data has 13 bytes, DLC says 8");
        assert!(malformed("1.0 1 3FF Tx d G 00").contains("DLC 'G' is not a hex digit"));
        assert!(malformed("1.0 1 3FF Tx d 10 00").contains("DLC '10'"));
        assert!(malformed("1.0 1 3FF Tx d").contains("no DLC"));
    }

    #[test]
    fn byte_count_must_match_the_dlc() {
        assert_eq!(
            malformed("1.0 1 081 Rx d 8 01 02 03 04 05"),
            "data has 5 bytes, DLC says 8"
        );
        assert_eq!(
            malformed("1.0 1 081 Rx d 8 01 02 03 Length = 5 BitCount = 3"),
            "data has 3 bytes, DLC says 8"
        );
        assert_eq!(
            malformed("1.0 1 081 Rx d 2 01 02 03"),
            "data has 3 bytes, DLC says 2"
        );
        assert_eq!(
            malformed("1.0 1 081 Rx d 2 01 02 03 04 Length = 1"),
            "data has 4 bytes, DLC says 2"
        );
    }

    #[test]
    fn malformed_lines_say_why() {
        assert!(malformed("1.2.3 1 123 Rx d 0").contains("not a decimal number: '1.2.3'"));
        assert!(malformed("1. 1 123 Rx d 0").contains("ends with a dot"));
        assert!(malformed("1.0 1 123 Rz d 0").contains("unknown direction 'Rz'"));
        assert!(malformed("1.0 1 123").contains("expected Rx, Tx or TxRq"));
        assert!(malformed("1.0 1 123 Rx").contains("expected d or r"));
        assert!(malformed("1.0 1 123 Rx q 0").contains("frame type 'q'"));
        assert!(malformed("1.0 1 12G Rx d 0").contains("id '12G' is not a hexadecimal number"));
        assert!(malformed("1.0 1 x Rx d 0").contains("id 'x' is not"));
        assert!(
            malformed("1.0 1 123 Rx d 2 01 ZZ")
                .contains("data byte 2 'ZZ' is not a hexadecimal byte")
        );
        assert!(malformed("1.0 1 123 Rx d 1 123").contains("data byte 1 '123'"));
        assert!(
            malformed("1.0 1 123 Rx d 1 01 junk")
                .contains("unexpected text after the frame: 'junk'")
        );
        assert!(
            malformed("1.0 1 123 Rx d 1 01 Length = 5 junk")
                .contains("unexpected text after the frame: 'junk'")
        );
        assert!(malformed("1.0 1 123 Rx d 1 01 Length 5").contains("expected '=' after 'Length'"));
        assert!(malformed("1.0 1 123 Rx d 1 01 ID = 12y").contains("ID value '12y'"));
        assert!(malformed("1.0 1 123 Rx d 1 01 Lengthy = 5").contains("'Lengthy'"));
        // Non-ASCII bytes are escaped in reasons.
        let r = match AscParser::new().parse(b"1.0 1 123 Rx d 1 \xff\x1b", &Interest::all()) {
            Parsed::Malformed(r) => r,
            other => panic!("{other:?}"),
        };
        assert!(r.contains("\\xff\\x1b"), "{r}");
        let long = format!("1.0 1 {} Rx d 0", "9".repeat(10_000));
        assert!(malformed(&long).contains("..."));
    }

    #[test]
    fn tail_variants() {
        for line in [
            "1.0 1 123 Rx d 1 01 Length=5 BitCount=3 ID=291",
            "1.0 1 123 Rx d 1 01 Length =5 BitCount= 3 TE ID = 291",
            "1.0 1 123 Rx d 1 01 ID = 291 Length = 5",
            "1.0 1 123 Rx d 1 01 WU",
        ] {
            assert_eq!(frame(line).len, 1, "{line}");
        }
    }

    #[test]
    fn canfd_with_symbolic_name() {
        let f = frame(FD_EXAMPLE);
        assert_eq!(time(&f), "30.005071");
        assert_eq!(f.channel, b"3");
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x30A, false, FrameKind::Fd, 8)
        );
        assert_eq!(f.data.as_slice(), [1, 2, 3, 4, 5, 6, 7, 8]);
        // Without a name, extended, python-can test data.
        let f = frame(
            "   0.045746 CANFD   62 Rx        167x  VehicleOperatingModes            1 0 8  8 73 80 00 10 00 09 e3 00   102187  133   323000 e000fb6c 46500250 4b140250 20011736 2001040d",
        );
        assert_eq!((f.id, f.extended, f.channel), (0x167, true, &b"62"[..]));
        let f = frame(
            "   0.045636 CANFD   62 Rx         88                                   0 1 8  8 00 00 f6 90 00 00 00 00   105812  137   323000 d001b0b3 46500250 4b140250 20011736 2001040d",
        );
        assert_eq!((f.id, f.kind, f.len), (0x88, FrameKind::Fd, 8));
        assert_eq!(f.data.as_slice()[2], 0xF6);
    }

    #[test]
    fn canfd_digit_only_symbolic_names() {
        for name in ["1234", "1", "0", "42"] {
            let line = format!(
                "30.005071 CANFD 3 Rx 30a {name} 1 1 8 8 01 02 03 04 05 06 07 08 102203 133 303000 e0006659 46500250 4b140250 20011736 2001040d"
            );
            let f = frame(&line);
            assert_eq!((f.kind, f.len), (FrameKind::Fd, 8), "{line}");
            assert_eq!(f.data.as_slice(), [1, 2, 3, 4, 5, 6, 7, 8], "{line}");
        }
        // Both layouts consistent, only the unnamed one has the full eight
        // fields after the data: it wins.
        let f = frame("1.0 CANFD 1 Rx 123 0 0 0 0 0 0 1000 0 0 0 0 0");
        assert_eq!((f.kind, f.len), (FrameKind::Fd, 0));
        // Both consistent, different frames, neither has eight fields.
        assert!(malformed("1.0 CANFD 1 Rx 123 0 0 0 0 0 0 0 1000 0").contains("ambiguous"));
        // Both consistent and the same frame: no need to choose.
        assert_eq!(
            frame("1.0 CANFD 1 Rx 123 1 1 1 1 1 01 0 1000 1000")
                .data
                .as_slice(),
            [0x01]
        );
    }

    #[test]
    fn canfd_line_without_fdf_carries_a_classic_frame() {
        // log2asc -f
        let f = frame(
            "   0.003287 CANFD   1 Rx         81                                  0 0 8  8 10 43 08 01 00 00 00 00   130000  130        0 0 0 0 0 0",
        );
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x81, false, FrameKind::Data, 8)
        );
        assert_eq!(f.data.as_slice(), [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
        // Classic DLC 9..F with 8 bytes.
        let f = frame("1.0 CANFD 1 Rx 81 0 0 f 8 10 43 08 01 00 00 00 00 130000 130 0 0 0 0 0 0");
        assert_eq!((f.kind, f.len), (FrameKind::Data, 8));
        // 12 bytes are not a classic frame whatever the flags say: see
        // `canfd_line_over_8_bytes_without_fdf_is_fd_with_a_warning`.
        let mut p = AscParser::new();
        let line = "1.0 CANFD 1 Rx 81 0 0 9 12 00 00 00 00 00 00 00 00 00 00 00 00 1 1 0 0 0 0 0 0";
        assert!(matches!(parse_with(&mut p, line), Parsed::Frame(f) if f.kind == FrameKind::Fd));
        assert!(p.take_warning().is_some_and(|w| w.contains("lack FDF")));
        // A classic frame cannot switch bit rate.
        assert!(
            malformed("1.0 CANFD 1 Rx 81 1 0 8 8 10 43 08 01 00 00 00 00 130000 130 0 0 0 0 0 0")
                .contains("BRS is 1 but flags 0 lack FDF")
        );
    }

    #[test]
    fn canfd_line_over_8_bytes_without_fdf_is_fd_with_a_warning() {
        // python-can's ASCWriter and hand-edited files: DLC F, 64 bytes,
        // flags 0 (no FDF); python-can reads the byte count, so do we.
        let zeros = " 00".repeat(60);
        let plain = format!(
            "  30.506898 CANFD   4 Rx        4EE                                   0 1 f 64 A1 02 03 04{zeros} 1331984 11 0 46500250 460a0250 20011736 20010205"
        );
        let named = format!(
            "  31.506898 CANFD   4 Rx        1C4D80A7x    SomeName_2                 1 0 f 64 b1 02 03 04{zeros} 1331984 11 0 46500250 460a0250 20011736 20010205"
        );
        let mut p = AscParser::new();
        for (line, id, first) in [(&plain, 0x4EE, 0xA1), (&named, 0x1C4D_80A7, 0xB1)] {
            let f = match parse_with(&mut p, line) {
                Parsed::Frame(f) => f,
                other => panic!("{line:?} -> {other:?}"),
            };
            assert_eq!((f.id, f.kind, f.len), (id, FrameKind::Fd, 64));
            assert_eq!(f.data.as_slice()[..4], [first, 2, 3, 4]);
            assert_eq!(f.data.as_slice()[63], 0);
            assert_eq!(
                p.take_warning().as_deref(),
                Some(
                    "CANFD line: flags 0 lack FDF 1000 but 64 data bytes (DLC F) only fit \
                     a CAN FD frame; read as one"
                )
            );
            assert_eq!(p.take_warning(), None, "taken once");
        }
        // The next line clears it; a line with FDF has none.
        p.parse(b"not a line", &Interest::all());
        assert_eq!(p.take_warning(), None);
        assert!(matches!(parse_with(&mut p, FD_EXAMPLE), Parsed::Frame(_)));
        assert_eq!(p.take_warning(), None);
        // Up to 8 bytes the flags still decide: classic, or BRS an error.
        assert_eq!(
            frame("1.0 CANFD 1 Rx 81 0 0 8 8 10 43 08 01 00 00 00 00 1 1 0 0 0 0 0 0").kind,
            FrameKind::Data
        );
        assert!(
            malformed("1.0 CANFD 1 Rx 81 1 0 8 8 10 43 08 01 00 00 00 00 1 1 0 0 0 0 0 0")
                .contains("BRS is 1")
        );
        // The count must still be the DLC's.
        assert!(
            malformed(&format!(
                "1.0 CANFD 1 Rx 81 0 0 e 64{} 1 1 0",
                " 00".repeat(64)
            ))
            .contains("does not match DLC E")
        );
    }

    #[test]
    fn base_and_triggerblock_headers_identify_the_format() {
        let mut p = AscParser::new();
        assert!(matches!(
            parse_with(&mut p, "date Sam Sep 30 15:06:13.191 2017"),
            Parsed::Skipped
        ));
        assert!(!p.identified(), "a shell's `date` looks the same");
        assert!(matches!(
            parse_with(&mut p, "base hex  octal"),
            Parsed::Malformed(_)
        ));
        assert!(!p.identified(), "a base line that is not one");
        assert!(matches!(
            parse_with(&mut p, "base hex  timestamps absolute"),
            Parsed::Skipped
        ));
        assert!(p.identified());
        let mut p = AscParser::new();
        parse_with(&mut p, "Begin Triggerblock Sam Sep 30 15:06:13.191 2017");
        assert!(p.identified());
    }

    #[test]
    fn canfd_remote_frames() {
        let f = frame(
            "  30.300981 CANFD   3 Tx     50005x                                0 1 5 0 140000 73 200050 7a60 46500250 460a0250 20011736 20010205",
        );
        assert_eq!(
            (f.id, f.extended, f.kind, f.len),
            (0x50005, true, FrameKind::Remote, 0)
        );
        assert!(f.data.is_empty());
        assert!(
            malformed("1.0 CANFD 1 Rx 81 Name 0 0 1 1 00 0 0 10 0 0 0 0 0")
                .contains("remote frame")
        );
    }

    #[test]
    fn canfd_64_bytes() {
        let f = frame(
            "  24.986902 CANFD   7 Tx        716                                   1 0 f 64 12 3b 36 01 7b 0a 20 20 20 20 22 66 69 6c 65 43 6f 75 6e 74 22 3a 20 31 2c 20 0a 20 20 20 20 22 65 63 75 49 64 22 3a 20 22 30 78 30 37 31 36 22 2c 20 0a 20 20 20 20 22 64 69 64 22 3a 20 22 46        0    0     3000        0        0        0        0        0",
        );
        assert_eq!((f.id, f.kind, f.len), (0x716, FrameKind::Fd, 64));
        assert_eq!(f.data.len(), 64);
        assert_eq!(f.data.as_slice()[63], 0x46);
        assert!(
            malformed("1.0 CANFD 1 Rx 81 0 0 a 12 00 00 00 00 00 00 00 00 00 00 00 00 1 1 3000")
                .contains("does not match DLC A (16 bytes)")
        );
    }

    #[test]
    fn canfd_malformed_lines_say_why() {
        // Truncated before the flags: never a frame, always a reason. (A cut
        // inside the optional CRC/bit-timing words leaves a complete frame.)
        let n = FD_EXAMPLE.trim_end().len();
        let cut_points = [40, 70, 90, 100, 110, 120];
        for cut in cut_points {
            assert!(cut < n);
            let line = &FD_EXAMPLE[..cut];
            assert!(
                matches!(parse(line), Parsed::Malformed(_)),
                "{line:?} -> {:?}",
                parse(line)
            );
        }
        let r = malformed(&FD_EXAMPLE[..100]);
        assert!(r.contains("ends after 7 of 8 data bytes"), "{r}");
        let r = malformed(&FD_EXAMPLE[..115]);
        assert!(r.contains("ends early"), "{r}");
        let r = malformed(&FD_EXAMPLE[..120]);
        assert!(r.contains("BRS is 1 but flags 3 lack FDF"), "{r}");
        assert!(malformed("1.0 CANFD").contains("ends after 'CANFD'"));
        assert!(malformed("1.0 CANFD x Rx 1").contains("channel 'x'"));
        assert!(malformed("1.0 CANFD 1 Rq 1").contains("unknown direction 'Rq'"));
        assert!(malformed("1.0 CANFD 1 Rx").contains("ends after the direction"));
        assert!(malformed("1.0 CANFD 1 Rx 80000").contains("above 7FF"));
        assert!(malformed("1.0 CANFD 1 Rx 123").contains("before the BRS flag"));
        assert!(malformed("1.0 CANFD 1 Rx 123 Name 2 0 8 8").contains("BRS flag '2'"));
        assert!(malformed("1.0 CANFD 1 Rx 123 1 0 8 8").contains("ends after 0 of 8 data bytes"));
        assert!(
            malformed("1.0 CANFD 1 Rx 123 Name 1 0 8 8 01 02 03 04 05 06 07 ZZ 0 0 3000")
                .contains("data byte 8 'ZZ'")
        );
        assert!(
            malformed("1.0 CANFD 1 Rx 123 1 0 8 8 01 02 03 04 05 06 07 08 0 0 3000 0 0 0 0 0 0")
                .contains("at most 8")
        );
        assert!(
            malformed("1.0 CANFD 1 Rx 123 1 0 8 8 01 02 03 04 05 06 07 08 0 0 3000 zz")
                .contains("unexpected 'zz'")
        );
        assert!(
            malformed("1.0 CANFD 1 Rx 123 1 0 8 8 01 02 03 04 05 06 07 08 x 0 3000")
                .contains("message duration 'x'")
        );
        assert!(
            malformed("1.0 CANFD 1 Rx 123 1 0 8 8 01 02 03 04 05 06 07 08 0 0 3g00")
                .contains("flags '3g00'")
        );
        assert!(malformed("1.0 CANFD 1 Rx 123 1 0 8 65").contains("0-64"));
        assert!(malformed("1.0 CANFD 1 Rx 123 1 0 8 7").contains("does not match DLC 8"));
    }

    #[test]
    fn several_channels_keep_their_tokens() {
        let mut p = AscParser::new();
        let mut channels = Vec::new();
        for line in [
            "1.0 1 081 Rx d 0",
            "1.1 2 081 Rx d 0",
            "1.2 12 ErrorFrame",
            "1.3 CANFD 62 Rx 81 0 0 0 0 0 0 3000",
        ] {
            match parse_with(&mut p, line) {
                Parsed::Frame(f) => channels.push(f.channel.to_vec()),
                other => panic!("{line:?} -> {other:?}"),
            }
        }
        assert_eq!(channels, [&b"1"[..], b"2", b"12", b"62"]);
    }

    #[test]
    fn uninteresting_frames_are_validated_but_not_decoded() {
        let mut interest = Interest::none();
        interest.add_standard(0x81);
        let mut p = AscParser::new();
        let lines: [&[u8]; 3] = [
            b"1.0 1 123 Rx d 2 11 22",
            b"1.0 1 081x Rx d 2 11 22",
            b"1.0 CANFD 1 Rx 123 1 0 2 2 11 22 0 0 3000",
        ];
        for line in lines {
            match p.parse(line, &interest) {
                Parsed::Frame(f) => {
                    assert_eq!(f.len, 2);
                    assert!(f.data.is_empty());
                    assert!(f.time.is_some());
                }
                other => panic!("{other:?}"),
            }
        }
        match p.parse(b"1.0 1 081 Rx d 2 11 22", &interest) {
            Parsed::Frame(f) => assert_eq!(f.data.as_slice(), [0x11, 0x22]),
            other => panic!("{other:?}"),
        }
        match p.parse(b"1.0 CANFD 1 Rx 81 0 0 2 2 11 22 0 0 0", &interest) {
            Parsed::Frame(f) => {
                assert_eq!(f.kind, FrameKind::Data);
                assert_eq!(f.data.as_slice(), [0x11, 0x22]);
            }
            other => panic!("{other:?}"),
        }
        for bad in [
            &b"1.0 1 123 Rx d 2 11 ZZ"[..],
            b"1.0 1 123 Rx d 2 11",
            b"1.0 CANFD 1 Rx 123 1 0 2 2 11 ZZ 0 0 3000",
        ] {
            assert!(matches!(p.parse(bad, &interest), Parsed::Malformed(_)));
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
            (self.next() % n.max(1) as u64) as usize
        }
    }

    fn check_invariants(parsed: &Parsed<'_>) {
        if let Parsed::Frame(f) = parsed {
            assert!(f.len <= 64);
            assert!(f.data.is_empty() || f.data.len() == usize::from(f.len));
            assert!(f.id <= EXTENDED_MAX);
            assert!(f.extended || f.id <= STANDARD_MAX);
            assert!(f.time.is_some());
        }
    }

    #[test]
    fn never_panics_on_random_or_damaged_lines() {
        const ALPHABET: &[u8] =
            b" \t\t  0123456789.xXabcdefABCDEF:=-/dDrRTxRqCANFDErrorFrameLengthIDBitCount\xff\x00\xc3";
        let valid = [
            "   3.098426 1  18EBFF00x       Rx d 8 01 A0 0F A6 60 3B D1 40    Length = 273910 BitCount = 141 ID = 418119424x",
            "   2.584921 4 300 Tx r 8 Length = 1704000 BitCount = 145 ID = 88888888x",
            "   2.501020 2 ErrorFrame Flags = 0xe CodeExt = 0x20a2 Code = 0x82",
            FD_EXAMPLE,
            "  30.300981 CANFD   3 Tx     50005x                                0 1 5 0 140000 73 200050 7a60 46500250 460a0250 20011736 20010205",
            "   0.015991 CAN 1 Status:chip status error passive - TxErr: 132 RxErr: 0",
            "base dec  timestamps relative",
            "base hex  timestamps absolute",
            "Begin Triggerblock Sam Sep 30 15:06:13.191 2017",
        ];
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let interests = [Interest::all(), Interest::none()];
        let mut p = AscParser::new();
        let feed = |p: &mut AscParser, line: &[u8], rng: &mut Rng| {
            let interest = &interests[rng.below(2)];
            check_invariants(&p.parse(line, interest));
        };

        for _ in 0..400 {
            let len = rng.below(160);
            let line: Vec<u8> = (0..len)
                .map(|_| ALPHABET[rng.below(ALPHABET.len())])
                .collect();
            feed(&mut p, &line, &mut rng);
            // Random bytes of any value too.
            let raw: Vec<u8> = (0..rng.below(64)).map(|_| rng.next() as u8).collect();
            feed(&mut p, &raw, &mut rng);
        }
        for line in valid {
            let bytes = line.as_bytes();
            for cut in 0..=bytes.len() {
                feed(&mut p, &bytes[..cut], &mut rng);
            }
            for _ in 0..200 {
                let mut m = bytes.to_vec();
                for _ in 0..1 + rng.below(3) {
                    let i = rng.below(m.len());
                    match rng.below(3) {
                        0 => m[i] = ALPHABET[rng.below(ALPHABET.len())],
                        1 => {
                            m.remove(i);
                        }
                        _ => m.insert(i, ALPHABET[rng.below(ALPHABET.len())]),
                    }
                    if m.is_empty() {
                        break;
                    }
                }
                feed(&mut p, &m, &mut rng);
            }
            // Token shuffles keep the vocabulary but break the grammar.
            let mut toks: Vec<&str> = line.split_whitespace().collect();
            for _ in 0..50 {
                let (a, b) = (rng.below(toks.len()), rng.below(toks.len()));
                toks.swap(a, b);
                feed(&mut p, toks.join(" ").as_bytes(), &mut rng);
            }
        }
        // Huge numbers everywhere.
        for line in [
            format!("{} 1 081 Rx d 0", "9".repeat(5000)),
            format!("1.{} 1 081 Rx d 0", "9".repeat(5000)),
            format!("1.0 {} 081 Rx d 0", "9".repeat(5000)),
            format!("1.0 1 081 Rx d 1 00 Length = {}", "9".repeat(5000)),
            format!("1.0 CANFD 1 Rx 81 1 0 8 {}", "9".repeat(5000)),
            format!("1.0 1 081 Rx d 8 {}", "00 ".repeat(5000)),
        ] {
            feed(&mut p, line.as_bytes(), &mut rng);
        }
    }
}
