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

use crate::Format;
use crate::time::MAX_FRACTION_DIGITS;
use crate::{
    DataHead, Folds, Frame, FrameKey, FrameKind, HexText, IdCounts, Interest, LineParser, Parsed,
    Payload, Reason, Run, Scan, Ticks, TimedLine, Timestamp, is_blank, split_token, trim_end,
    trim_start,
};
use crate::{hex, scan};

/// The bytes [`LineParser::run`] looks at with every frame timed: fewer
/// lines than a `u32` counts (a line has at least its newline), whatever
/// block a caller hands it. Without every frame timed, the slices callers
/// hand over are that short ([`LineParser::run`]).
const MAX_RUN_BYTES: usize = u32::MAX as usize;

/// Where the dot of a time in Unix seconds with microseconds is, what
/// candump writes: `(1700000000.001000)`.
const UNIX_DOT: usize = 11;

/// candump sets this bit in an 8-digit id to mark an error frame.
pub const ERROR_FLAG: u32 = 0x2000_0000;
const EFF_MASK: u32 = 0x1FFF_FFFF;

/// Reads `candump -l` / `-L` log lines.
#[derive(Default, Clone, Copy)]
pub struct CandumpLogParser {
    /// The layout of the last canonical line (a cache: results never
    /// depend on it, only speed).
    layout: Option<Layout>,
    /// The last line read was a frame with a note after it (see
    /// [`LineParser::take_annotated`]); no line depends on it.
    annotated: bool,
}

impl CandumpLogParser {
    /// A parser before the first line.
    pub fn new() -> Self {
        CandumpLogParser::default()
    }

    /// The shape of a canonical line: the last line's layout first, then
    /// the general scan (which then becomes the layout).
    #[inline]
    fn shape(&mut self, line: &[u8]) -> Option<Shape> {
        if let Some(shape) = self.layout.as_ref().and_then(|l| l.shape(line)) {
            return Some(shape);
        }
        let shape = shape(line)?;
        self.layout = Layout::of(line, &shape);
        Some(shape)
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
        match self.shape(line) {
            Some(shape) => shape.scan(line, interest),
            None => Scan::Parse,
        }
    }

    #[inline]
    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        self.annotated = false;
        if let Some(frame) = canonical(line, interest) {
            return Parsed::Frame(frame);
        }
        match parse_line_full(line, interest) {
            Ok(Some((frame, annotated))) => {
                self.annotated = annotated;
                Parsed::Frame(frame)
            }
            Ok(None) => Parsed::Skipped,
            Err(_) if is_candump_command(line) => Parsed::Skipped,
            Err(reason) => Parsed::Malformed(reason),
        }
    }

    fn take_annotated(&mut self) -> bool {
        std::mem::take(&mut self.annotated)
    }

    /// Lines of the last line's layout, found without a separate newline
    /// search: the data field's end is where the line must end.
    #[inline]
    fn run<'a>(
        &mut self,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        folds: &mut Folds,
        ids: &mut IdCounts,
    ) -> Run<'a> {
        if interest.times_every_frame() {
            self.every_frame_lines(bytes, max_line, interest, folds, ids)
        } else {
            self.lines::<false>(bytes, max_line, interest, folds, ids)
        }
    }
}

impl CandumpLogParser {
    /// [`CandumpLogParser::lines`] with every frame timed, not inlined:
    /// the default loop alone in its caller keeps the time it had (with
    /// both inlined, the same instructions ran 2-3% slower: the bench's
    /// noisy bus, 512 MiB, `-j1`).
    #[inline(never)]
    fn every_frame_lines<'a>(
        &mut self,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        folds: &mut Folds,
        ids: &mut IdCounts,
    ) -> Run<'a> {
        // Every line is a timed line here, and a run numbers them in a
        // `u32` ([`TimedLine::idx`]): the line cut here ends the run, and the
        // caller reads it whole. The default loop has no such cut (it cost
        // that loop 4% of its time, the bench's segmented firmware trace):
        // only SYNC lines are timed there, in slices callers keep shorter.
        let bytes = bytes.get(..MAX_RUN_BYTES).unwrap_or(bytes);
        self.lines::<true>(bytes, max_line, interest, folds, ids)
    }

    /// [`LineParser::run`], one loop with every frame timed
    /// (`EVERY_FRAME`, each line only counted handed over with its time)
    /// and one without: the loop without lost 2-10 instructions a line to
    /// the other's code in its body (callgrind, the bench's traces).
    #[inline]
    fn lines<'a, const EVERY_FRAME: bool>(
        &mut self,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        folds: &mut Folds,
        ids: &mut IdCounts,
    ) -> Run<'a> {
        let mut run = Run::default();
        let Some(layout) = self.layout.as_ref() else {
            return run;
        };
        let mut last_timed = None;
        // Every line of the layout has its `) DEV ` bytes, so its channel:
        // found in the counts once per run, if the run has a line. (Found
        // on the first line counted instead, or by parsing the first line
        // twice, it cost every line 10-20 instructions more: callgrind, the
        // bench's traces.)
        if !layout.sep.matches(bytes, layout.close) {
            return run;
        }
        run.channel = layout.channel(bytes);
        let (channel, timed_lines) = ids.run_parts(run.channel);
        while let Some(rest) = bytes.get(run.bytes..)
            && let Some((shape, len)) = layout.line(rest)
            && len <= max_line
        {
            let line = rest.get(..len).unwrap_or_default();
            // Counted where the line is only counted or timed: a frame
            // handed on is the caller's to count.
            match shape.kind(line, interest) {
                Kind::Plain => {
                    channel.count(shape.id, shape.extended);
                    if EVERY_FRAME {
                        // Timed, as every frame is: handed over.
                        timed_lines.push(shape.timed_line(line, run.plain + run.timed));
                    }
                    run.plain += 1;
                }
                Kind::Handed => {
                    channel.count(shape.id, shape.extended);
                    let idx = run.plain + run.timed;
                    if EVERY_FRAME {
                        // Most lines here: in the loop's body.
                        timed_lines.push(shape.timed_line(line, idx));
                    } else {
                        hand_over(timed_lines, shape, line, idx);
                    }
                    run.plain += 1;
                }
                Kind::Timed => {
                    channel.count(shape.id, shape.extended);
                    // Of a run of these (folded frames among them) only the
                    // first and last time count.
                    if run.first_time.is_none() {
                        run.first_time = shape.time(line);
                    }
                    run.timed += 1;
                    last_timed = Some(line);
                }
                Kind::Frame(frame) => {
                    run.before_frame = run.bytes;
                    run.bytes += len + 1;
                    run.frame = Some(frame);
                    break;
                }
                // The Timed and Frame arms again, not one match on the
                // result nor helpers for them: each way cost every plain
                // line 7-15 instructions (callgrind: the 20 MB heartbeat
                // trace went 160.6M -> 164-170M).
                Kind::Fold => {
                    let (id, extended) = (shape.id, shape.extended);
                    // For the line's timed line (the shape moves on).
                    let data_len = shape.data.len();
                    match fold_line(folds, shape, line, run.plain + run.timed, interest) {
                        Kind::Timed => {
                            channel.count(id, extended);
                            if EVERY_FRAME {
                                // Folded, and timed as every frame is: its
                                // ticks are the fold's latest, read already.
                                let idx = run.plain + run.timed;
                                let time = folds.latest_ticks();
                                timed_lines.push(data_line(id, data_len, time, idx));
                            }
                            if run.first_time.is_none() {
                                run.first_time = time_at(line, layout.dot, layout.close);
                            }
                            run.timed += 1;
                            last_timed = Some(line);
                        }
                        Kind::Frame(frame) => {
                            run.before_frame = run.bytes;
                            run.bytes += len + 1;
                            run.frame = Some(frame);
                            break;
                        }
                        Kind::Handed if EVERY_FRAME => {
                            channel.count(id, extended);
                            let idx = run.plain + run.timed;
                            let time = ticks_at(line, layout.dot, layout.close);
                            timed_lines.push(data_line(id, data_len, time, idx));
                            run.plain += 1;
                        }
                        _ => break,
                    }
                }
                Kind::Parse => break,
            }
            run.bytes += len + 1;
        }
        if folds.any()
            && let Some(line) = last_timed
        {
            // Every line of the run has the layout, and so the channel.
            run.fold_channel = layout.channel(line);
        }
        if let Some(line) = last_timed {
            // A run's last time only moves the input's last time, and a data
            // frame with a time after it moves it again: its conversion
            // (about 150 instructions, once per heartbeat in a busy trace)
            // is spared then.
            let superseded = run.frame.as_ref().is_some_and(|f| {
                f.kind == FrameKind::Data && f.time.is_some() && interest.times(f.id, f.extended)
            });
            run.last_time = if superseded {
                run.first_time
            } else {
                time_at(line, layout.dot, layout.close)
            };
        }
        if run.frame.is_none() {
            run.before_frame = run.bytes;
        }
        run
    }
}

/// A line of [`CandumpLogParser::run`] on an id the interest hands over
/// ([`Interest::hand_over`]): with its time, line `idx` of the run. Not
/// inlined: in the loop's body it made every plain line 30 instructions
/// slower (callgrind, the bench's trace of 32 drives, which has no SYNC),
/// and so did taking the shape by reference (10 instructions a line).
#[inline(never)]
fn hand_over(timed_lines: &mut Vec<TimedLine>, shape: Shape, line: &[u8], idx: u64) {
    timed_lines.push(shape.timed_line(line, idx));
}

/// A line of [`CandumpLogParser::run`] on a foldable id: folded into
/// `folds` ([`Folds::add`]) and then timed like a frame nobody wants, or
/// what [`Shape::kind`] makes of it (with every frame timed, one the
/// content filter only times is handed over, as [`Shape::wanted`] says).
/// Not inlined: in the loop's body it made every line slower (callgrind
/// on plain lines).
#[inline(never)]
fn fold_line<'a>(
    folds: &mut Folds,
    shape: Shape,
    line: &'a [u8],
    idx: u64,
    interest: &Interest,
) -> Kind<'a> {
    let text = HexText::of(line, shape.data.start, shape.data.end);
    let time = shape.ticks(line);
    let rule = || interest.fold_rule(shape.id);
    if let (Some(text), Some(time)) = (text, time)
        && folds.repeat(shape.id, text, time, idx, rule)
    {
        return Kind::Timed;
    }
    let Some(data) = shape.data(line) else {
        return Kind::Parse;
    };
    if interest.timed_only_head(shape.id, DataHead::of(data.as_slice())) {
        return if interest.times_every_frame() {
            Kind::Handed
        } else {
            Kind::Timed
        };
    }
    if let (Some((word, _)), Some(text), Some(time)) = (data.word(), text, time)
        && folds.add(shape.id, word, text, time, idx, rule)
    {
        return Kind::Timed;
    }
    match (shape.frame(line, false), shape.time(line)) {
        (Some(frame), Some(time)) => Kind::Frame(Frame {
            time: Some(time),
            data,
            ..frame
        }),
        _ => Kind::Parse,
    }
}

/// Lines every candump output may contain besides frames: blank lines,
/// comments people add, candump's own `DROPCOUNT:` notices, and the `...`
/// (or `…`) with which a pasted excerpt says lines were left out.
pub fn is_candump_non_frame(line: &[u8]) -> bool {
    let t = trim_start(line);
    is_blank(t)
        || t.starts_with(b"#")
        || t.starts_with(b"//")
        || t.starts_with(b";")
        || t.starts_with(b"DROPCOUNT")
        || is_elision(t)
}

/// Whether a line is `...` or `…` alone: where a paste left lines out.
/// Under `-td` the left-out lines' deltas are missing from every later time.
pub fn is_elision_line(line: &[u8]) -> bool {
    is_elision(trim_start(line))
}

/// Whether text after a complete frame (blanks already skipped) starts a
/// note: `// boot`, `# config`, `< response`, any sign or non-ASCII
/// character. A letter or digit there is more likely damage (two lines run
/// together, a split data field) than a note, so it stays an error.
pub fn starts_note(rest: &[u8]) -> bool {
    rest.first()
        .is_some_and(|b| !b.is_ascii_alphanumeric() && !b.is_ascii_control() && *b != b' ')
}

/// `...` or `…` alone on a line (blanks aside): lines left out of a paste.
fn is_elision(t: &[u8]) -> bool {
    matches!(trim_end(t), b"..." | b"\xE2\x80\xA6")
}

/// The shell command line people paste above candump's output
/// (`candump can0`, `$ candump -l can0`, `pi@box:~ $ candump -td -a vcan0`,
/// `/usr/bin/candump any`): a prompt, then candump or a path ending in it.
/// Only asked of lines that are no frame, so it costs frame lines nothing.
pub fn is_candump_command(line: &[u8]) -> bool {
    let t = trim_start(line);
    // Everything up to a prompt's `$ ` or `> ` is the prompt.
    let command = match memchr::memmem::find(t, b"$ ").or_else(|| memchr::memmem::find(t, b"> ")) {
        Some(at) => trim_start(t.get(at + 2..).unwrap_or_default()),
        None => t,
    };
    let (program, _) = split_token(command);
    program == b"candump" || program.ends_with(b"/candump")
}

/// The frames a candump `DROPCOUNT:` line says the kernel dropped
/// (`DROPCOUNT: dropped 3 CAN frames on 'can0' socket (total drops 7)`:
/// 3, the total being the sum of these); `None` for any other line. Frames
/// are lost there, and EMCYs may be among them.
pub fn dropped_frames(line: &[u8]) -> Option<u64> {
    let rest = trim_start(line).strip_prefix(b"DROPCOUNT")?;
    let text = std::str::from_utf8(rest).ok()?;
    let mut words = text.split_whitespace();
    words.find(|w| *w == "dropped")?;
    words.next()?.parse().ok()
}

/// Every form the format allows, with a reason for what it does not: a
/// frame, and whether a note followed it (`(...) can0 701#00  // boot`).
fn parse_line_full<'a>(
    line: &'a [u8],
    interest: &Interest,
) -> Result<Option<(Frame<'a>, bool)>, Reason> {
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
    // `-L` may write T or R (the direction) after the frame; anything after
    // that is a note someone added, unless it reads as more data: hex
    // digits after a blank mean the data was split, not annotated.
    let (flag, after_flag) = split_token(trim_start(rest));
    let note = match flag {
        b"T" | b"R" => trim_start(after_flag),
        _ => trim_start(rest),
    };
    let annotated = !note.is_empty();
    let (first_word, _) = split_token(note);
    if !first_word.is_empty()
        && first_word
            .iter()
            .all(|b| matches!(b, b'0'..=b'9' | b'A'..=b'F'))
    {
        return Err(format!(
            "'{}' after the frame looks like more data: ID#DATA is one word, without blanks",
            crate::show_token(first_word)
        )
        .into());
    }
    if annotated && !starts_note(note) {
        return Err(format!(
            "unexpected '{}' after the frame (only T or R may follow it, or a note \
             starting with a sign such as //, # or <)",
            crate::show_token(first_word)
        )
        .into());
    }

    let mut frame = parse_frame(frame_text, interest)?;
    // The timestamp is validated for every frame but only converted for wanted ones.
    let time = Timestamp::parse(time_text).map_err(Reason::from)?;
    if frame.kind == FrameKind::Error || interest.wants(frame.id, frame.extended) {
        frame.time = Some(time);
    }
    frame.channel = channel;
    Ok(Some((frame, annotated)))
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
#[derive(Debug, PartialEq, Eq)]
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
            frame.time = Some(self.time(line)?);
            frame.data = self.data(line)?;
        }
        Some(frame)
    }

    #[inline]
    fn time(&self, line: &[u8]) -> Option<Timestamp> {
        time_at(line, self.dot, self.close)
    }

    /// What the line's frame is counted under.
    #[inline]
    fn key<'a>(&self, line: &'a [u8]) -> FrameKey<'a> {
        FrameKey {
            channel: line.get(self.channel.clone()).unwrap_or_default(),
            id: self.id,
            extended: self.extended,
        }
    }

    /// The time as [`Ticks`] (what folding compares); `None` past 19 digits.
    #[inline]
    fn ticks(&self, line: &[u8]) -> Option<Ticks> {
        ticks_at(line, self.dot, self.close)
    }

    /// The line as a [`TimedLine`], line `idx` of its run (a line of a
    /// [`Layout`], so a classic data frame on a standard id).
    #[inline]
    fn timed_line(&self, line: &[u8], idx: u64) -> TimedLine {
        data_line(self.id, self.data.len(), self.ticks(line), idx)
    }

    /// The data's head ([`DataHead`]), its first three bytes parsed.
    #[inline]
    fn head(&self, line: &[u8]) -> Option<DataHead> {
        // At most 8 bytes (the shape checked it).
        let text = line.get(self.data.clone())?;
        let mut bytes = [0u8; 3];
        for (b, pair) in bytes.iter_mut().zip(text.chunks_exact(2)) {
            *b = hex::parse_byte(pair[0], pair[1])?;
        }
        Some(DataHead::new((text.len() / 2) as u8, bytes))
    }

    #[inline]
    fn data(&self, line: &[u8]) -> Option<Payload> {
        // At most 8 bytes (the shape checked it).
        let text = line.get(self.data.clone())?;
        let mut bytes = [0u8; 8];
        for (b, pair) in bytes.iter_mut().zip(text.chunks_exact(2)) {
            *b = hex::parse_byte(pair[0], pair[1])?;
        }
        Some(Payload::inline(bytes, (text.len() / 2) as u8))
    }

    /// What a line of this shape is to a caller with `interest`.
    #[inline]
    fn scan<'a>(&self, line: &'a [u8], interest: &Interest) -> Scan<'a> {
        let kind = match self.kind(line, interest) {
            Kind::Fold => self.wanted(line, interest),
            kind => kind,
        };
        match kind {
            // A line to be timed, outside the hot loop, is decoded (as
            // every frame once was: it is rare there).
            Kind::Plain if interest.times_every_frame() => {
                self.frame(line, true).map_or(Scan::Parse, Scan::Frame)
            }
            Kind::Handed => self.frame(line, true).map_or(Scan::Parse, Scan::Frame),
            Kind::Plain => Scan::Plain(self.key(line)),
            Kind::Timed => self
                .time(line)
                .map_or(Scan::Parse, |t| Scan::Timed(t, self.key(line))),
            Kind::Frame(frame) => Scan::Frame(frame),
            Kind::Fold | Kind::Parse => Scan::Parse,
        }
    }

    /// [`Shape::scan`] without converting the time of a frame only to be
    /// timed (a run needs only the first and last of those).
    #[inline(always)]
    fn kind<'a>(&self, line: &'a [u8], interest: &Interest) -> Kind<'a> {
        if !interest.decodes(self.id, self.extended) {
            return Kind::Plain;
        }
        if self.kind == FrameKind::Data && !self.extended && interest.folds(self.id) {
            return Kind::Fold;
        }
        if interest.hands_over(self.id, self.extended) {
            return Kind::Handed;
        }
        self.wanted(line, interest)
    }

    /// [`Shape::kind`] of a frame on a wanted id, folding aside.
    #[inline(always)]
    fn wanted<'a>(&self, line: &'a [u8], interest: &Interest) -> Kind<'a> {
        if self.kind == FrameKind::Data && !self.extended && interest.filters(self.id) {
            // Only the data's head decides; the rest is parsed, and the
            // frame built, only if it matters.
            let Some(head) = self.head(line) else {
                return Kind::Parse;
            };
            if interest.timed_only_head(self.id, head) {
                // With every frame timed, handed over (not decoded: an
                // SDO-heavy bus's segments are most of its lines).
                return if interest.times_every_frame() {
                    Kind::Handed
                } else {
                    Kind::Timed
                };
            }
            let Some(data) = self.data(line) else {
                return Kind::Parse;
            };
            // Heartbeats get here (about 150 instructions saved on each by
            // not parsing the data twice).
            return match (self.frame(line, false), self.time(line)) {
                (Some(frame), Some(time)) => Kind::Frame(Frame {
                    time: Some(time),
                    data,
                    ..frame
                }),
                _ => Kind::Parse,
            };
        }
        match self.frame(line, true) {
            Some(frame) => Kind::Frame(frame),
            None => Kind::Parse,
        }
    }
}

/// [`Scan`] with a timed frame's time not yet converted.
enum Kind<'a> {
    Plain,
    /// Wanted for its time alone ([`Interest::hand_over`]).
    Handed,
    Timed,
    Frame(Frame<'a>),
    /// A data frame on an id the interest folds (a reader that folds
    /// decides the rest, one that does not asks [`Shape::wanted`]).
    Fold,
    Parse,
}

/// The time of a canonical line with its dot and `)` at `dot` and `close`.
#[inline]
fn time_at(line: &[u8], dot: usize, close: usize) -> Option<Timestamp> {
    // At most 19 digits: always fits in u64.
    let secs = scan::decimal_u64(line.get(1..dot)?);
    let frac = line.get(dot + 1..close)?;
    Some(Timestamp::from_parts(
        secs,
        scan::decimal_u64(frac),
        frac.len() as u8,
    ))
}

/// The fixed part of a canonical line: nearly every line of a log has the
/// same timestamp width and interface, so a line is first checked against
/// the last one's layout, a few word compares, before the general scan.
/// Accepts exactly what [`shape`] accepts with these positions and a 3-digit id.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    dot: usize,
    close: usize,
    time: scan::Decimal,
    /// `) DEV `.
    sep: scan::Fixed,
}

/// A classic data frame on standard `id` with `data_len` hex digits at
/// `time`, line `idx` of its run, as a [`TimedLine`] (a folded line's,
/// whose shape is gone). `idx` fits a `u32` ([`MAX_RUN_BYTES`]; a
/// conversion that checked it cost every timed line 16 instructions).
#[inline]
fn data_line(id: u32, data_len: usize, time: Option<Ticks>, idx: u64) -> TimedLine {
    // A layout's id has three hex digits and its data at most 16.
    TimedLine::new(idx as u32, time, id as u16, (data_len / 2) as u8)
}

/// The time of a canonical line with its dot and `)` at `dot` and
/// `close`, as [`Ticks`]; `None` past 19 digits. Inlined, with the
/// general reading a call: a call for every line cost 15 instructions of
/// saved registers more (callgrind, `--timing`).
#[inline(always)]
fn ticks_at(line: &[u8], dot: usize, close: usize) -> Option<Ticks> {
    let value = if (dot, close) == (UNIX_DOT, UNIX_DOT + 7) {
        scan::unix_micros(line)?
    } else {
        scan::decimal_ticks(line, 1, dot, close)?
    };
    Ticks::new(value, (close - dot - 1) as u8)
}

impl Layout {
    fn of(line: &[u8], s: &Shape) -> Option<Layout> {
        if s.kind != FrameKind::Data || s.extended {
            return None;
        }
        Some(Layout {
            dot: s.dot,
            close: s.close,
            time: scan::Decimal::new(1, s.dot, s.close)?,
            sep: scan::Fixed::of(line, s.close, s.channel.end + 1 - s.close)?,
        })
    }

    /// The shape and length of the line at the start of `bytes` when it
    /// has this layout and ends with a newline right after its frame.
    #[inline(always)]
    fn line(&self, bytes: &[u8]) -> Option<(Shape, usize)> {
        let id_start = self.head(bytes)?;
        let data_start = id_start + 4;
        let data_len = scan::hex_run(bytes, data_start);
        let data_end = data_start + data_len;
        let len = match bytes.get(data_end) {
            Some(b'\n') => data_end,
            Some(b' ')
                if matches!(
                    bytes.get(data_end + 1..data_end + 3),
                    Some([b'T' | b'R', b'\n'])
                ) =>
            {
                data_end + 2
            }
            _ => return None,
        };
        if !data_len.is_multiple_of(2) || data_len > 16 {
            return None;
        }
        Some((self.shape_at(id_start, bytes, data_end)?, len))
    }

    /// The interface of a line of this layout.
    fn channel<'a>(&self, line: &'a [u8]) -> &'a [u8] {
        // `) DEV `.
        let end = (self.close + self.sep.width()).saturating_sub(1);
        line.get(self.close + 2..end).unwrap_or_default()
    }

    /// Through the id: the index where the 3-digit id starts, when `line`
    /// has this layout up to a `#` after it.
    #[inline(always)]
    fn head(&self, line: &[u8]) -> Option<usize> {
        // `)`, a space, the interface, a space: the bytes of the last line.
        if line.first() != Some(&b'(')
            || line.get(self.dot) != Some(&b'.')
            || !self.time.matches(line)
            || !self.sep.matches(line, self.close)
        {
            return None;
        }
        let id_start = self.close + self.sep.width();
        match line.get(id_start + 3) {
            Some(b'#') => Some(id_start),
            _ => None,
        }
    }

    /// The shape of a whole line.
    #[inline]
    fn shape(&self, line: &[u8]) -> Option<Shape> {
        let id_start = self.head(line)?;
        let data_start = id_start + 4;
        let data_end = match line {
            [.., b' ', b'T' | b'R'] => line.len() - 2,
            _ => line.len(),
        };
        let data_len = data_end.checked_sub(data_start)?;
        if data_len % 2 != 0 || data_len > 16 || !scan::all_hex_at(line, data_start, data_end) {
            return None;
        }
        self.shape_at(id_start, line, data_end)
    }

    /// The shape once the layout matched and the data was checked.
    #[inline(always)]
    fn shape_at(&self, id_start: usize, line: &[u8], data_end: usize) -> Option<Shape> {
        let id = hex::parse_u32(line.get(id_start..id_start + 3)?)?;
        if id > 0x7FF {
            return None;
        }
        let data_start = id_start + 4;
        Some(Shape {
            dot: self.dot,
            close: self.close,
            channel: self.close + 2..id_start - 1,
            id,
            extended: false,
            kind: FrameKind::Data,
            data: data_start..data_end,
        })
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
        // Error frames are rare and always decoded whole: the general path.
        8 if id & ERROR_FLAG != 0 => return None,
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
        // An error frame's id is its class bits, without the flag (the
        // representation every reader gives, `crate::error_frame`).
        (8, Some(id)) if id & ERROR_FLAG != 0 => (id & EFF_MASK, false, true),
        (8, Some(id)) => (id, true, false),
        (3 | 8, None) => return Err("id is not hexadecimal".into()),
        (n, _) => {
            return Err(
                format!("id has {n} digits; candump writes 3 (standard) or 8 (extended)").into(),
            );
        }
    };
    // Error frames are rare: their data is always read.
    let wanted = is_error || interest.wants(id, extended);
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
pub fn parse_data(text: &[u8], max: usize, mut out: Option<&mut Payload>) -> Result<u8, Reason> {
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
    use crate::ContentFilter;
    use crate::id_counts::testing::{Counted, table};

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
        // Whatever the interest: error frames are always decoded whole.
        let mut p = CandumpLogParser::new();
        let line = b"(1.000000) can0 20000204#0004000000000A85";
        let Parsed::Frame(f) = p.parse(line, &Interest::none()) else {
            panic!("an error frame");
        };
        assert_eq!((f.kind, f.id, f.extended), (FrameKind::Error, 0x204, false));
        assert_eq!(f.data.as_slice(), [0, 4, 0, 0, 0, 0, 0x0A, 0x85]);
        assert_eq!(f.time.map(|t| t.to_string()).as_deref(), Some("1.000000"));
        assert!(matches!(p.scan(line, &Interest::none()), Scan::Parse));
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
            "...",
            "    ...  ",
            "\u{2026}",
            "candump -l can0",
            "$ candump -L any",
            "pi@box:~ $ candump -td vcan0",
            "  /usr/bin/candump can0,701:7FF",
        ] {
            assert_eq!(parse(line), Parsed::Skipped, "{line:?}");
        }
        // Only a line that says nothing more is an elision or a command.
        for line in ["... (1.0) can0 081#00", "candumps", "cat log | candumpx"] {
            assert!(matches!(parse(line), Parsed::Malformed(_)), "{line:?}");
        }
    }

    #[test]
    fn notes_after_the_frame_are_counted_not_errors() {
        let mut p = CandumpLogParser::new();
        let all = Interest::all();
        let mut read = |line: &str| match p.parse(line.as_bytes(), &all) {
            Parsed::Frame(f) => (f.id, f.data.as_slice().to_vec(), p.take_annotated()),
            other => panic!("{line:?} -> {other:?}"),
        };
        assert_eq!(
            read("(1.0) can0 701#00  // boot of node 1"),
            (0x701, vec![0], true)
        );
        assert_eq!(
            read("    (1.0) can0 701#00 T < response"),
            (0x701, vec![0], true)
        );
        assert_eq!(read("(1.0) can0 701#00 # add"), (0x701, vec![0], true));
        // The direction flag alone is no note; the flag is cleared by a read.
        assert_eq!(read("(1.0) can0 701#00 R"), (0x701, vec![0], false));
        assert_eq!(read("(1.0) can0 701#00"), (0x701, vec![0], false));
        assert!(!p.take_annotated());
    }

    #[test]
    fn dropcount_lines_say_how_many_frames_were_dropped() {
        let n = |l: &str| dropped_frames(l.as_bytes());
        assert_eq!(
            n("DROPCOUNT: dropped 3 CAN frames on 'can0' socket (total drops 7)"),
            Some(3)
        );
        assert_eq!(
            n("  DROPCOUNT: dropped 1 CAN frame on 'vcan0' socket (total drops 1)\r"),
            Some(1)
        );
        assert_eq!(n("DROPCOUNT: garbled"), None);
        assert_eq!(n("(1.0) can0 081#00"), None);
        assert_eq!(n("# DROPCOUNT: dropped 3"), None);
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
        assert!(
            malformed("(1.0) can0 081#00 11").contains("'11' after the frame looks like more data")
        );
        assert!(malformed("(1.0) can0 081#00 T 2F").contains("looks like more data"));
        assert_eq!(
            malformed("(1.0) can0 081#00 boot"),
            "unexpected 'boot' after the frame (only T or R may follow it, or a note starting with a sign such as //, # or <)"
        );
        assert!(malformed("(x.0) can0 081#00").contains("decimal"));
        assert!(malformed("(99999999999999999999.0) can0 081#00").contains("overflow"));
        let long_id = format!("(1.0) can0 {}#00", "1".repeat(10_000));
        assert!(malformed(&long_id).contains("10000 digits"));
    }

    proptest::proptest! {
        /// A note after any valid line (after a blank, not starting like
        /// more data) leaves its frame as it was, and is counted.
        #[test]
        fn a_note_after_a_frame_changes_nothing_of_it(
            line in "\\([0-9]{1,10}\\.[0-9]{1,9}\\) [a-z0-9]{1,5} ([0-7][0-9A-F]{2}|[01][0-9A-F]{7})#(R[0-8]?|([0-9A-F]{2}){0,8}|#[0-9A-F]([0-9A-F]{2}){0,12})( T| R)?",
            gap in "[ \t]{1,3}",
            // A note starts with a sign (a letter or digit is damage).
            note in "[<>/#=!*~(\\[-][^\r\n]{0,30}",
        ) {
            let all = Interest::all();
            let mut p = CandumpLogParser::new();
            let Parsed::Frame(plain) = p.parse(line.as_bytes(), &all) else {
                return Err(proptest::test_runner::TestCaseError::fail(format!("{line:?} is no frame")));
            };
            proptest::prop_assert!(!p.take_annotated());
            let annotated = format!("{line}{gap}{note}");
            let mut q = CandumpLogParser::new();
            proptest::prop_assert_eq!(q.parse(annotated.as_bytes(), &all), Parsed::Frame(plain));
            proptest::prop_assert!(q.take_annotated(), "{:?} not counted", annotated);
        }

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
                proptest::prop_assert_eq!(Ok(Some((fast, false))), parse_line_full(line.as_bytes(), &interest));
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
            proptest::prop_assert_eq!(
                Ok(fast.map(|f| (f, false))),
                parse_line_full(line.as_bytes(), &interest)
            );
        }

        /// The last line's layout accepts exactly what the general scan
        /// accepts at the same positions, and takes the usual next line.
        #[test]
        fn layout_agrees_with_the_general_scan(
            first in r"\([0-9]{1,12}\.[0-9]{1,9}\) [a-z0-9-]{1,14} [0-7][0-9a-fA-F]{2}#([0-9a-fA-F]{2}){0,8}",
            next in r"\(([0-9]{0,12}\.[0-9]{0,9}|x)\)[ ]{1,2}[a-z0-9-]{0,14}[ ]{1,2}[0-9a-fA-FxR]{0,9}[#_.R]{0,2}[0-9a-fA-FRr._#]{0,18}( T| R| X|  )?",
            same_layout in "[0-7][0-9a-fA-F]{2}#([0-9a-fA-F]{2}){0,8}( T| R)?",
            at in 0usize..48,
            byte in proptest::sample::select(b"09aG.) #xTR-\t".to_vec()),
        ) {
            let first = first.as_bytes();
            let general = shape(first).expect("a canonical line");
            let Some(layout) = Layout::of(first, &general) else {
                // Only short or long timestamps and long interface names keep none.
                let sep_len = general.channel.end + 1 - general.close;
                proptest::prop_assert!(general.close < 9 || general.close > 25 || sep_len > 16);
                return Ok(());
            };
            if let Some(fast) = layout.shape(next.as_bytes()) {
                proptest::prop_assert_eq!(Some(fast), shape(next.as_bytes()), "{}", next);
            }
            // The same timestamp width and interface with another frame.
            let sep_end = layout.close + layout.sep.width();
            let mut usual = first[..sep_end].to_vec();
            usual.extend_from_slice(same_layout.as_bytes());
            let fast = layout.shape(&usual);
            proptest::prop_assert!(fast.is_some(), "declined {:?}", String::from_utf8_lossy(&usual));
            proptest::prop_assert_eq!(fast, shape(&usual));
            // One byte changed anywhere: still never a different answer.
            if let Some(b) = usual.get_mut(at) {
                *b = byte;
            }
            if let Some(fast) = layout.shape(&usual) {
                proptest::prop_assert_eq!(Some(fast), shape(&usual), "{:?}", String::from_utf8_lossy(&usual));
            }
        }
    }

    /// What `run` must return: line by line with `scan`, as the general
    /// loop would read them.
    /// Frames on foldable ids are folded as [`Folds::add`] allows.
    fn run_by_lines<'a>(
        p: &mut CandumpLogParser,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        folds: &mut Folds,
        ids: &mut IdCounts,
    ) -> Run<'a> {
        let mut run = Run::default();
        while let Some(rest) = bytes.get(run.bytes..)
            && let Some(len) = rest.iter().position(|b| *b == b'\n')
            && len <= max_line
            && !rest[..len].ends_with(b"\r")
        {
            let line = &rest[..len];
            match p.scan(line, interest) {
                Scan::Plain(key) => {
                    ids.count(key);
                    run.plain += 1;
                }
                Scan::Timed(t, key) => {
                    ids.count(key);
                    run.timed(t);
                }
                Scan::Frame(f) => {
                    let idx = run.plain + run.timed;
                    // The data's digits, as the line wrote them.
                    let start = line.iter().position(|b| *b == b'#').map_or(0, |i| i + 1);
                    let text = HexText::of(line, start, start + 2 * usize::from(f.len));
                    let folded = match (f.time.and_then(Timestamp::ticks), f.data.word(), text) {
                        (Some(t), Some((word, _)), Some(text))
                            if interest.folds(f.id) && !f.extended =>
                        {
                            let rule = || interest.fold_rule(f.id);
                            (f.kind == FrameKind::Data && folds.add(f.id, word, text, t, idx, rule))
                                .then(|| t.timestamp())
                        }
                        _ => None,
                    };
                    if let Some(t) = folded {
                        ids.count(f.key());
                        run.timed(t);
                        if run.fold_channel.is_empty() {
                            run.fold_channel = f.channel;
                        }
                    } else {
                        run.before_frame = run.bytes;
                        run.bytes += len + 1;
                        run.frame = Some(f);
                        return run;
                    }
                }
                Scan::Parse => break,
            }
            run.bytes += len + 1;
        }
        run.before_frame = run.bytes;
        run
    }

    type Fields<'a> = (
        (usize, usize),
        u64,
        u64,
        Option<Timestamp>,
        Option<Timestamp>,
        Option<Frame<'a>>,
        &'a [u8],
    );

    fn fields<'a>(r: &Run<'a>, interest: &Interest) -> Fields<'a> {
        // A run that ends in a data frame with a time may leave its last
        // time unconverted (the frame's time supersedes it).
        let superseded = r.frame.as_ref().is_some_and(|f| {
            f.kind == FrameKind::Data && f.time.is_some() && interest.times(f.id, f.extended)
        });
        (
            (r.bytes, r.before_frame),
            r.plain,
            r.timed,
            r.first_time,
            if superseded { None } else { r.last_time },
            r.frame.clone(),
            r.fold_channel,
        )
    }

    proptest::proptest! {
        /// The hot loop reads what reading line by line would.
        #[test]
        fn run_equals_line_by_line(
            lines in proptest::collection::vec(proptest::prop_oneof![
                4 => r"\(1700000000\.[0-9]{6}\) can0 [0-7][0-9A-F]{2}#([0-9A-F]{2}){0,8}( T)?",
                // The layout with any id and data: odd lengths and near misses.
                3 => r"\(1700000000\.[0-9]{6}\) can0 [0-9A-Fa-fg]{3}#[0-9A-Fa-f]{0,18}[g ]?( T| R|\r| X)?",
                1 => r"\(1700000000\.[0-9]{6}\) can[01] [0-9A-Fa-f]{3,8}#[0-9A-Fa-fR._]{0,18}( T| R|\r)?",
                1 => r"\(17000000[0-9]{2}\.[0-9]{5,6}\)  ?[a-z0-9]{3,5} [0-9a-f]{3}#[0-9a-f]{0,17}",
                // Heartbeat-like repeats on foldable ids, times mostly rising.
                3 => r"\(170000000[0-2]\.[0-9]{6}\) can0 70[1-3]#0[05]",
            ], 1..12),
            last_newline in proptest::bool::ANY,
            max_line in 30usize..60,
            narrow in proptest::bool::ANY,
            filtered in proptest::bool::ANY,
            untimed in proptest::bool::ANY,
        ) {
            let mut interest = if narrow { Interest::none() } else { Interest::all() };
            interest.add_standard(0x181);
            if untimed {
                // A run ending in a frame that moves no time keeps its last.
                interest.untime(0x181);
            }
            if filtered {
                // Frames on 0x100-0x3FF and 0x700-0x77F matter only when
                // their data starts with 00; repeats on 0x701-0x77F fold.
                interest.add_standard_range(0x100..=0x3FF);
                interest.add_standard_range(0x700..=0x77F);
                let filter = ContentFilter(|_, d| d.head().first() == Some(&0));
                interest.filter_content(0x100..=0x3FF, filter);
                interest.filter_content(0x700..=0x77F, filter);
                interest.fold(0x701..=0x77F);
            }
            let mut text = lines.join("\n");
            if last_newline {
                text.push('\n');
            }
            let bytes = text.as_bytes();
            let mut fast = CandumpLogParser::new();
            fast.scan(b"(1700000000.000000) can0 080#", &interest);
            let mut slow = fast;
            let mut at = 0;
            // Run after run, as the classifier calls it.
            for _ in 0..lines.len() + 1 {
                // It may stop early (a line of another layout), but the lines
                // it read, read one by one, give the same.
                let (mut fast_folds, mut slow_folds) = (Folds::default(), Folds::default());
                let (mut fast_ids, mut slow_ids) = (IdCounts::new(), IdCounts::new());
                let got = fast.run(&bytes[at..], max_line, &interest, &mut fast_folds, &mut fast_ids);
                let consumed = &bytes[at..at + got.bytes];
                let want = run_by_lines(&mut slow, consumed, max_line, &interest, &mut slow_folds, &mut slow_ids);
                proptest::prop_assert_eq!(fields(&got, &interest), fields(&want, &interest));
                proptest::prop_assert_eq!(table(&fast_ids), table(&slow_ids));
                // Every line read is counted but the frame that ended the run.
                proptest::prop_assert_eq!(fast_ids.frames(), got.plain + got.timed);
                proptest::prop_assert_eq!(fast_folds.as_slice(), slow_folds.as_slice());
                proptest::prop_assert_eq!(fast_folds.frames(), slow_folds.frames());
                at += got.bytes;
                if got.frame.is_none() {
                    // The general loop reads the next line; skip it here.
                    match bytes[at..].iter().position(|b| *b == b'\n') {
                        Some(i) => {
                            let line = &bytes[at..at + i];
                            fast.scan(line, &interest);
                            slow.scan(line, &interest);
                            at += i + 1;
                        }
                        None => break,
                    }
                }
            }
        }
    }

    #[test]
    fn the_layout_is_kept_between_lines_and_replaced_when_it_changes() {
        let mut p = CandumpLogParser::new();
        let all = Interest::all();
        let a = b"(1700000000.000100) can0 383#724F5046";
        let b = b"(1700000000.000517) can0 604#3684F0716DEF09E6 T";
        let c = b"(1700000000.000753) vcan12 085#";
        assert!(p.scan(a, &all) != Scan::Parse);
        let kept = p.layout;
        assert!(kept.is_some());
        assert_eq!(p.scan(b, &all), Scan::Frame(canonical(b, &all).unwrap()));
        assert_eq!(p.layout, kept, "same layout: not recomputed");
        assert_eq!(p.scan(c, &all), Scan::Frame(canonical(c, &all).unwrap()));
        assert_ne!(p.layout, kept, "another interface: a new layout");
        // A line that fits no layout is left to the full parser.
        assert_eq!(p.scan(b"(1700000000.000753) can0 085#1", &all), Scan::Parse);
        // The hot loop takes every line of the layout, and stops at a wanted one.
        let block = b"(1.000001) can0 181#00\n(1.000002) can0 281#0102 T\n\
                      (1.000003) can0 381#\n(1.000004) can0 081#10\n(1.000005) can0 181#\n";
        let mut interest = Interest::none();
        interest.add_standard(0x81);
        let mut p = CandumpLogParser::new();
        let folds = &mut Folds::default();
        let ids = &mut IdCounts::new();
        assert_eq!(
            p.run(block, 100, &interest, folds, ids).bytes,
            0,
            "no layout yet"
        );
        p.scan(b"(9.000000) can0 080#", &interest);
        let run = p.run(block, 100, &interest, folds, ids);
        assert_eq!((run.bytes, run.plain), (94, 3));
        assert_eq!(run.frame.map(|f| f.id), Some(0x81));
        let run = p.run(&block[94..], 100, &interest, folds, ids);
        assert_eq!((run.bytes, run.plain, run.frame), (21, 1, None));
        // Every plain line counted by its id, the wanted 0x081 not (the
        // caller counts the frame it is handed).
        let can0 = |id| (Some(b"can0".to_vec()), Counted::Id(id, false));
        assert_eq!(
            table(ids),
            [(can0(0x181), 2), (can0(0x281), 1), (can0(0x381), 1)].into()
        );
        assert_eq!(
            p.run(&block[..22], 100, &interest, folds, ids).bytes,
            0,
            "no newline"
        );
        assert_eq!(
            p.run(block, 20, &interest, folds, ids).bytes,
            0,
            "longer than max_line"
        );
    }

    #[test]
    fn lines_only_timed_and_handed_ids_are_handed_over_at_their_index_in_the_run() {
        // 0x705 under a filter that keeps only boot-ups (data 00), 0x080
        // handed over: a heartbeat is only timed, SYNC handed over.
        let block = b"(1.000001) can0 705#05\n(1.000002) can0 080#\n\
                      (1.000003) can0 181#01\n(1.000004) can0 705#05\n\
                      (1.000005) can0 080#\n(1.000006) can0 705#00\n";
        let mut interest = Interest::none();
        interest.add_standard(0x705);
        interest.filter_content(0x705..=0x705, ContentFilter(|_, d| d.head() == [0]));
        interest.hand_over(0x080);
        let mut p = CandumpLogParser::new();
        p.scan(b"(9.000000) can0 080#", &interest);
        let mut handed = |interest: &Interest| {
            let (folds, ids) = (&mut Folds::default(), &mut IdCounts::new());
            let run = p.run(block, 100, interest, folds, ids);
            assert_eq!((run.plain + run.timed, run.channel), (5, &b"can0"[..]));
            assert_eq!(run.frame.map(|f| f.data.as_slice().to_vec()), Some(vec![0]));
            let lines: Vec<_> = ids.timed_lines.iter().map(|l| (l.idx, l.id())).collect();
            lines
        };
        // SYNC alone on the default path, as lines 1 and 4 of the run.
        assert_eq!(handed(&interest), vec![(1, 0x080), (4, 0x080)]);
        // Every line with every frame timed, the heartbeats only timed too.
        assert_eq!(
            handed(&interest.every_frame()),
            vec![(0, 0x705), (1, 0x080), (2, 0x181), (3, 0x705), (4, 0x080)]
        );
        // Outside the hot loop, both are decoded.
        let sync = b"(1.000002) can0 080#";
        assert!(matches!(p.scan(sync, &interest), Scan::Frame(f) if f.id == 0x80));
        let beat = b"(1.000001) can0 705#05";
        assert!(matches!(p.scan(beat, &interest), Scan::Timed(..)));
        assert!(matches!(
            p.scan(beat, &interest.every_frame()),
            Scan::Frame(_)
        ));
    }

    #[test]
    fn with_every_frame_timed_the_hot_loop_hands_counted_lines_over_with_their_times() {
        let block = b"(1.000001) can0 181#00\n(1.000002) can0 281#0102 T\n\
                      (1.000003) can0 381#\n(1.000004) can0 081#10\n";
        let mut interest = Interest::none();
        interest.add_standard(0x81);
        let every = interest.every_frame();
        let mut p = CandumpLogParser::new();
        p.scan(b"(9.000000) can0 080#", &interest);
        let (folds, ids) = (&mut Folds::default(), &mut IdCounts::new());
        let run = p.run(block, 100, &every, folds, ids);
        assert_eq!((run.plain, run.channel), (3, &b"can0"[..]));
        assert_eq!(run.frame.map(|f| f.id), Some(0x81), "its own still decoded");
        let got: Vec<_> = ids
            .timed_lines
            .iter()
            .map(|l| {
                (
                    l.idx,
                    l.time().map(|t| t.timestamp().to_string()),
                    l.id(),
                    l.len,
                )
            })
            .collect();
        let at = |us: u8| Some(format!("1.00000{us}"));
        assert_eq!(
            got,
            vec![
                (0, at(1), 0x181, 1),
                (1, at(2), 0x281, 2),
                (2, at(3), 0x381, 0),
            ]
        );
        // Unix seconds with microseconds, what candump writes, are read
        // their own way: the same times.
        let unix = b"(1700000000.000001) can0 181#00\n(1700000000.999999) can0 281#0102 T\n\
                     (1700000001.000003) can0 381#\n(1700000001.000004) can0 081#10\n";
        p.scan(b"(1700000000.000000) can0 080#", &interest);
        let ids = &mut IdCounts::new();
        p.run(unix, 100, &every, folds, ids);
        let got: Vec<_> = ids.timed_lines.iter().map(|l| l.time()).collect();
        let ticks = |value| Ticks::new(value, 6);
        assert_eq!(
            got,
            vec![
                ticks(1_700_000_000_000_001),
                ticks(1_700_000_000_999_999),
                ticks(1_700_000_001_000_003)
            ]
        );
        // Without every frame timed, none is handed over.
        let ids = &mut IdCounts::new();
        p.run(block, 100, &interest, folds, ids);
        assert!(ids.timed_lines.is_empty());
        // Outside the hot loop, a line only counted is decoded instead.
        let line = b"(1.000001) can0 181#00";
        assert!(matches!(p.scan(line, &every), Scan::Frame(f) if f.time.is_some()));
        assert!(matches!(p.scan(line, &interest), Scan::Plain(_)));
    }

    #[test]
    fn scan_counts_valid_unwanted_lines_and_decodes_wanted_ones() {
        let mut p = CandumpLogParser::new();
        let mut interest = Interest::none();
        interest.add_standard(0x81);
        assert_eq!(
            p.scan(b"(1.000000) can0 181#1122", &interest),
            Scan::Plain(FrameKey::new(b"can0", 0x181, false))
        );
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
