//! The interfaces every format implements: [`LineParser`] for a text
//! format's lines, [`FrameSource`] for anything that yields records one by
//! one (a binary format's reader, or the text formats through their line
//! parser), and what they return.

use std::borrow::Cow;
use std::io;

use crate::ethercat::{EthercatCounts, EthercatPacket};
use crate::{Folds, Format, Frame, FrameKey, IdCounts, Interest, Timestamp};

/// Why a line is not a frame of the format being read.
pub type Reason = Cow<'static, str>;

/// The classification of one line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Parsed<'a> {
    /// A frame.
    Frame(Frame<'a>),
    /// A line that is known not to be a frame (header, comment, status, blank).
    Skipped,
    /// A line that is not what the format allows, with the reason.
    Malformed(Reason),
}

/// What [`LineParser::scan`] made of a line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Scan<'a> {
    /// A valid frame whose id is not wanted: count it, under its key.
    Plain(FrameKey<'a>),
    /// A valid frame on a wanted id, as `parse` returns it.
    Frame(Frame<'a>),
    /// A valid frame on a wanted id whose data the content filter rejects:
    /// only its time is needed (and its key, to count it).
    Timed(Timestamp, FrameKey<'a>),
    /// Not the common shape: call `parse`.
    Parse,
}

/// What [`LineParser::run`] read from the start of a block's bytes: `bytes`
/// of whole lines, `plain` frames only to count and `timed` frames only to
/// time (the first and last of their times), then, when `frame` is set, one
/// wanted frame (the last line read).
#[derive(Debug, Default)]
pub struct Run<'a> {
    /// Bytes of whole lines read.
    pub bytes: usize,
    /// Valid frames on ids the interest does not want: only counted.
    pub plain: u64,
    /// Wanted frames whose data the content filter rejects: only timed.
    pub timed: u64,
    /// The first of the timed frames' times.
    pub first_time: Option<Timestamp>,
    /// The last of the timed frames' times.
    pub last_time: Option<Timestamp>,
    /// The wanted frame that ended the run, if one did.
    pub frame: Option<Frame<'a>>,
    /// The bytes of the lines before `frame` (all of `bytes` without one).
    pub before_frame: usize,
    /// The channel of the frames folded into the run's [`Folds`] (counted
    /// in `timed`; a run has one layout, so one channel).
    pub fold_channel: &'a [u8],
    /// The channel of the lines the run added to
    /// [`IdCounts::timed_lines`] (counted in `plain`).
    pub channel: &'a [u8],
}

impl Run<'_> {
    /// Counts a frame that is only timed.
    #[inline]
    pub fn timed(&mut self, t: Timestamp) {
        self.timed += 1;
        self.first_time.get_or_insert(t);
        self.last_time = Some(t);
    }
}

/// A parser for one text format. Parsers may keep state across lines (ASC
/// headers set the number base and relative timestamps).
pub trait LineParser: Send {
    /// The format this parser reads.
    fn format(&self) -> Format;

    /// Classifies one line (terminator already removed). Must not panic on
    /// any input.
    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a>;

    /// The id-first shortcut for the common shape of a format's frame line,
    /// validated once: [`Scan::Plain`] for a valid frame on an id `interest`
    /// does not want (only counted), [`Scan::Frame`] for one it wants,
    /// exactly as `parse` would return it, [`Scan::Parse`] for anything
    /// else. State a parser keeps is updated as by `parse`.
    #[inline]
    fn scan<'a>(&mut self, _line: &'a [u8], _interest: &Interest) -> Scan<'a> {
        Scan::Parse
    }

    /// The hot loop: reads lines from the start of `bytes` (whole lines of
    /// a block) while [`LineParser::scan`] counts them as plain, and stops
    /// after a wanted frame or before any other line (too long, `\r\n`,
    /// no newline, or not the common shape), which the caller then reads
    /// one at a time. Saves the per-line dispatch of the general loop.
    /// Every frame only counted or timed is counted in `ids`; the frame
    /// that ends the run is the caller's to count. `bytes` is shorter than
    /// 4 GiB, as a [`BlockReader`](crate::lines::BlockReader)'s blocks are:
    /// a run numbers its lines in a `u32` ([`TimedLine::idx`](crate::TimedLine::idx)).
    #[inline]
    fn run<'a>(
        &mut self,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        _folds: &mut Folds,
        ids: &mut IdCounts,
    ) -> Run<'a> {
        let mut run = Run::default();
        while let Some(rest) = bytes.get(run.bytes..)
            && let Some(len) = memchr::memchr(b'\n', rest)
            && len <= max_line
            && let Some(line) = rest.get(..len)
            && line.last() != Some(&b'\r')
        {
            match self.scan(line, interest) {
                Scan::Plain(key) => {
                    ids.count(key);
                    run.plain += 1;
                    run.bytes += len + 1;
                }
                Scan::Timed(t, key) => {
                    ids.count(key);
                    run.timed(t);
                    run.bytes += len + 1;
                }
                Scan::Frame(frame) => {
                    run.before_frame = run.bytes;
                    run.bytes += len + 1;
                    run.frame = Some(frame);
                    return run;
                }
                Scan::Parse => break,
            }
        }
        run.before_frame = run.bytes;
        run
    }

    /// After `parse` returned a frame: a contradiction in the line that the
    /// parser resolved to read it (a diagnostic for that line, which stays
    /// a frame). Cleared by the call and by the next `parse`.
    fn take_warning(&mut self) -> Option<Reason> {
        None
    }

    /// After `parse` returned a frame: whether text followed the complete
    /// frame on its line (a note someone pasted, `< response`, `// boot`),
    /// which the frame's reading ignored. Cleared by the call and by the
    /// next `parse`. Counted, never an error.
    fn take_annotated(&mut self) -> bool {
        false
    }

    /// Whether a line read so far was a header only this format writes
    /// (an ASC `base` line): the format is known without a frame, and lines
    /// it cannot read are its malformed lines, not an unknown format.
    fn identified(&self) -> bool {
        false
    }

    /// The time of the last frame read, for a format whose times chain
    /// (relative times: each line's time is the sum of those before, so
    /// every line's is read); `None` where a line's time stands alone and
    /// the lines nobody decodes keep theirs unread.
    fn clock(&self) -> Option<Timestamp> {
        None
    }

    /// The bit rate the trace's header records (IXXAT's `Baudrate:`), in
    /// bit/s, once a header line said it.
    fn bit_rate(&self) -> Option<u32> {
        None
    }

    /// The state later lines depend on, as a small exact value (below 256):
    /// a block parsed from a fork is valid only if the state it started from
    /// equals the state the previous block ended in. `None` when every line
    /// depends on the one before (ASC relative times): parse sequentially.
    fn context(&self) -> Option<u8>;
}

/// What a [`FrameSource`] read next.
#[derive(Debug)]
pub enum Next<'a> {
    /// One record (a text line, a BLF object, a pcap packet, an MF4
    /// record), classified.
    Record(Parsed<'a>),
    /// Records the source only counted, because the caller's interest
    /// needs no more of them (they come before the next item).
    Counted(Counted),
    /// Something about the input as a whole worth telling the user, once
    /// (a BLF start time that is no date, a pcap's byte order).
    Note(String),
}

/// Records a [`FrameSource`] only counted, each one line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counted {
    /// Valid frames on ids the interest does not want.
    pub plain: u64,
    /// Wanted frames whose data the interest's content filter rejects:
    /// how many, and the first and last of their times.
    pub timed: Option<(u64, Timestamp, Timestamp)>,
    /// Records known not to be frames (an EtherCAT frame without a
    /// mailbox message).
    pub skipped: u64,
}

impl Counted {
    /// How many lines these are.
    pub fn lines(&self) -> u64 {
        self.plain + self.timed.map_or(0, |(n, _, _)| n) + self.skipped
    }
}

/// Any source of records, one call per record: a binary format's reader
/// directly, the text formats through their line parser
/// ([`TextReader`](crate::text::TextReader)). An
/// [`AnyReader`](crate::AnyReader) holds any of them; a caller writes its
/// read loop once, over this trait, and runs it with
/// [`AnyReader::visit`](crate::AnyReader::visit).
pub trait FrameSource {
    /// The format read: `None` for text whose format is not known yet.
    fn format(&self) -> Option<Format>;

    /// The next item; `Ok(None)` at the end. With `interest`, a source may
    /// count frames the interest does not want (or wants only timed)
    /// rather than decode them ([`Next::Counted`]); without, every record
    /// comes one by one. An error is an I/O error of the input: reading
    /// stops.
    fn next_item(&mut self, interest: Option<&Interest>) -> io::Result<Option<Next<'_>>>;

    /// After a frame record: what the reader made good to read it (data
    /// bytes a BLF object lacks, read as zeros), a diagnostic for that
    /// record, which stays a frame. Cleared by the call and the next item.
    fn take_warning(&mut self) -> Option<Reason> {
        None
    }

    /// After a frame record: whether a note followed the frame on its line
    /// (see [`LineParser::take_annotated`]). Cleared by the call and the
    /// next item.
    fn take_annotated(&mut self) -> bool {
        false
    }

    /// After a skipped or malformed record that was an EtherCAT frame: its
    /// CoE messages, and the channel they came on.
    fn take_ethercat(&mut self) -> Option<(Box<EthercatPacket>, &[u8])> {
        None
    }

    /// The bit rate the input records, in bit/s, once read (see
    /// [`LineParser::bit_rate`]).
    fn bit_rate(&self) -> Option<u32> {
        None
    }

    /// The EtherCAT seen so far, for a format that can carry it.
    fn ethercat_counts(&self) -> Option<EthercatCounts> {
        None
    }

    /// The times of the first and last frames the reader only counted
    /// ([`Next::Counted`]), read once when asked: with the times of the
    /// records it handed on, the input's span. Kept as stored until then
    /// (converting every plain frame's time cost a pcapng 16% and an MF4
    /// 23% more instructions). A source whose records are not in time
    /// order (MF4's groups, one after another) gives the earliest and
    /// latest of every frame, handed on or counted.
    fn plain_span(&self) -> Option<(Timestamp, Timestamp)> {
        None
    }

    /// Every frame the reader only counted ([`Next::Counted`]: `plain`
    /// and `timed`), by channel and identifier, over the input so far.
    /// `None` from a source that hands every frame on.
    fn counted_ids(&self) -> Option<&IdCounts> {
        None
    }
}
