//! Trace readers: one line parser per text format, one reader per binary
//! format (BLF, pcap/pcapng, MF4), all yielding [`Frame`].
//!
//! Every line is classified as exactly one of: a frame, a known non-frame line
//! (header, comment, status, blank: "skipped"), or a malformed line with a
//! reason. Parsers never panic and never stop: the caller counts and reports.
//! (A binary format's "line" is its record: a BLF object, a pcap packet,
//! an MF4 record.)

pub mod asc;
pub mod blf;
pub mod busmaster;
pub mod cancel;
pub mod candump_log;
pub mod candump_screen;
pub mod deltas;
pub mod detect;
pub mod ethercat;
pub mod fold;
pub mod follow;
pub mod hex;
pub mod input;
pub mod lines;
pub mod mf4;
pub mod pcap;
pub mod reader;
pub mod scan;
pub mod time;
pub mod trc;

use std::borrow::Cow;
use std::fmt;

pub use fold::{Fold, FoldBuffers, FoldRule, Folded, Folds, HexText, Inner};
pub use time::{Span, Step, Ticks, Timestamp};

/// The text formats we read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// `candump -l` / `-L` log lines: `(1469439874.299654) can0 081#1043080100000000`.
    CandumpLog,
    /// candump's default screen output: `  can0  081   [8]  10 43 08 01 00 00 00 00`.
    CandumpScreen,
    /// Vector ASC (CANalyzer/CANoe, log2asc).
    Asc,
    /// PEAK TRC (PCAN-View, PCAN-Explorer), versions 1.0 to 2.1.
    Trc,
    /// BUSMASTER log (`***BUSMASTER Ver 2.0.0***`, `14:19:11:4184 Tx 1 0x099 s 8 ...`).
    Busmaster,
    /// Vector BLF, binary: read object by object, not line by line, and
    /// detected by its `LOGG` magic, so it is not in [`Format::ALL`].
    Blf,
    /// libpcap capture file (tcpdump, scapy, Wireshark's "pcap"), binary:
    /// read packet by packet, detected by its magic number.
    Pcap,
    /// pcapng capture file (Wireshark, dumpcap), binary: read packet by
    /// packet, detected by its section header block.
    Pcapng,
    /// ASAM MDF 4 bus logging (CANedge, Vector, python-can), binary: read
    /// record by record, detected by its identification block.
    Mf4,
}

impl Format {
    /// The text formats, read line by line and detected from their lines.
    pub const ALL: [Format; 5] = [
        Format::CandumpLog,
        Format::CandumpScreen,
        Format::Asc,
        Format::Trc,
        Format::Busmaster,
    ];

    /// The name used on the command line and in the `format` JSON key.
    pub fn name(self) -> &'static str {
        match self {
            Format::CandumpLog => "candump",
            Format::CandumpScreen => "candump-screen",
            Format::Asc => "asc",
            Format::Trc => "trc",
            Format::Busmaster => "busmaster",
            Format::Blf => "blf",
            Format::Pcap => "pcap",
            Format::Pcapng => "pcapng",
            Format::Mf4 => "mf4",
        }
    }

    /// A binary format: read record by record by its own reader (its
    /// "lines" are BLF objects or pcap packets), never by the line parsers.
    pub fn is_binary(self) -> bool {
        matches!(
            self,
            Format::Blf | Format::Pcap | Format::Pcapng | Format::Mf4
        )
    }

    pub(crate) fn parser(self) -> AnyParser {
        match self {
            Format::CandumpLog => AnyParser::CandumpLog(candump_log::CandumpLogParser::new()),
            Format::CandumpScreen => {
                AnyParser::CandumpScreen(candump_screen::CandumpScreenParser::new())
            }
            Format::Asc => AnyParser::Asc(asc::AscParser::new()),
            Format::Trc => AnyParser::Trc(trc::TrcParser::new()),
            Format::Busmaster => AnyParser::Busmaster(busmaster::BusmasterParser::new()),
            Format::Blf | Format::Pcap | Format::Pcapng | Format::Mf4 => {
                AnyParser::Binary(BinaryParser(self))
            }
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What kind of frame a line carries. Only `Data` frames can be EMCY.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FrameKind {
    /// Classic CAN data frame, 0..=8 bytes.
    Data,
    /// Remote transmission request; carries no data.
    Remote,
    /// Error frame; `id` holds the error class bits as the trace wrote them.
    Error,
    /// CAN FD frame, 0..=64 bytes.
    Fd,
}

/// Up to 64 payload bytes. Classic frames (all that EMCY and NMT use) stay
/// inline; CAN FD data past 8 bytes goes to the heap. Frames are moved on
/// the hot path, so this keeps them small; FD data is decoded only for the
/// ids a caller asked for.
#[derive(Clone, PartialEq, Eq)]
pub struct Payload {
    inline: [u8; 8],
    len: u8,
    long: Option<Box<[u8; 64]>>,
}

impl Payload {
    pub const MAX: usize = 64;

    pub const fn new() -> Payload {
        Payload {
            inline: [0; 8],
            len: 0,
            long: None,
        }
    }

    /// The bytes of a payload of at most 8 as one word (first byte lowest,
    /// zeros after the last), and how many.
    #[inline]
    pub fn word(&self) -> Option<(u64, u8)> {
        if self.long.is_some() || self.len > 8 {
            return None;
        }
        let keep = u64::MAX
            .checked_shr(8 * (8 - u32::from(self.len)))
            .unwrap_or(0);
        Some((u64::from_le_bytes(self.inline) & keep, self.len))
    }

    /// The first `len` (at most 8) of `bytes`.
    #[inline]
    pub fn inline(bytes: [u8; 8], len: u8) -> Payload {
        Payload {
            inline: bytes,
            len: len.min(8),
            long: None,
        }
    }

    /// Appends a byte; `false` (and nothing stored) when already full.
    #[inline]
    pub fn push(&mut self, b: u8) -> bool {
        let i = usize::from(self.len);
        if i < self.inline.len() && self.long.is_none() {
            self.inline[i] = b;
        } else if i < Self::MAX {
            let long = self.long.get_or_insert_with(|| {
                let mut all = Box::new([0u8; 64]);
                all[..8].copy_from_slice(&self.inline);
                all
            });
            long[i] = b;
        } else {
            return false;
        }
        self.len += 1;
        true
    }

    pub fn from_slice(data: &[u8]) -> Option<Payload> {
        let mut p = Payload::new();
        for &b in data {
            if !p.push(b) {
                return None;
            }
        }
        Some(p)
    }

    pub fn as_slice(&self) -> &[u8] {
        let n = usize::from(self.len);
        match &self.long {
            Some(all) => &all[..n],
            None => &self.inline[..n.min(8)],
        }
    }

    #[cfg(any(test, feature = "fuzzing"))]
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    #[cfg(any(test, feature = "fuzzing"))]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl Default for Payload {
    fn default() -> Self {
        Payload::new()
    }
}

impl fmt::Debug for Payload {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Payload({})", HexBytes(self.as_slice()))
    }
}

/// Formats bytes as contiguous uppercase hex (`1043080100000000`).
pub struct HexBytes<'a>(pub &'a [u8]);

impl fmt::Display for HexBytes<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for b in self.0 {
            write!(f, "{b:02X}")?;
        }
        Ok(())
    }
}

/// One CAN frame read from a trace line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame<'a> {
    /// Seconds as the trace wrote them; `None` when the trace has no times
    /// (candump screen output without `-t`) or the frame was not of interest.
    pub time: Option<Timestamp>,
    /// Interface (candump) or channel number (ASC) exactly as written.
    pub channel: &'a [u8],
    /// 11- or 29-bit identifier (for error frames, the error class bits).
    pub id: u32,
    /// 29-bit identifier. For candump this follows the digit count, not the value.
    pub extended: bool,
    pub kind: FrameKind,
    /// Number of data bytes the frame carries (0 for remote frames).
    pub len: u8,
    /// The data bytes; filled only for frames the caller's [`Interest`]
    /// covers (id-first filtering: other frames are validated, not decoded).
    pub data: Payload,
}

impl<'a> Frame<'a> {
    /// An error frame as the text formats write one: no class bits, no data.
    pub(crate) fn error(time: Option<Timestamp>, channel: &'a [u8]) -> Frame<'a> {
        Frame {
            time,
            channel,
            id: 0,
            extended: false,
            kind: FrameKind::Error,
            len: 0,
            data: Payload::new(),
        }
    }
}

/// A channel a binary format gives as a number (BLF, MF4), kept as the
/// decimal text a [`Frame`] borrows: no allocation per frame.
#[derive(Clone, Copy, Default)]
pub(crate) struct NumberedChannel {
    text: [u8; 20],
    len: usize,
}

impl NumberedChannel {
    /// Sets the number and gives its text.
    pub(crate) fn name(&mut self, n: u64) -> &[u8] {
        let mut b = itoa::Buffer::new();
        let text = b.format(n).as_bytes();
        let n = text.len().min(self.text.len());
        if let (Some(dst), Some(src)) = (self.text.get_mut(..n), text.get(..n)) {
            dst.copy_from_slice(src);
        }
        self.len = n;
        self.text.get(..n).unwrap_or_default()
    }
}

/// Which identifiers the caller wants decoded. Parsers read the id first and
/// skip decoding time and data for everything else.
///
/// Some wanted standard ids can be given a content filter: a frame on them
/// whose data the filter rejects is only timed ([`Scan::Timed`]): the caller
/// needs its time but nothing else (a heartbeat, when only boot-ups matter).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Interest {
    standard: [u64; 32],
    /// Every extended id (tests, conversions).
    all_extended: bool,
    /// Single extended ids (a node whose 0x1014 moved its EMCY to 29 bits).
    extended: Vec<u32>,
    /// Standard ids under `content`.
    filtered: [u64; 32],
    content: ContentFilter,
    /// Standard ids whose repeated frames a reader's hot loop may fold
    /// ([`fold`]).
    foldable: [u64; 32],
    /// The bits that must repeat for a fold, by id (sorted; ids not here:
    /// every bit).
    fold_masks: Vec<(u32, u64)>,
    /// Wanted standard ids whose frames do not move the input's time (a
    /// drive's PDOs before their mapping is known, [`Interest::untime`]).
    untimed: [u64; 32],
    /// Standard ids whose frames need not end a run of folds
    /// ([`Interest::keep_inside`]).
    inside: [u64; 32],
}

/// Whether a frame's data matters (see [`Interest`]), from its head.
#[derive(Clone, Copy)]
pub struct ContentFilter(pub fn(u32, DataHead) -> bool);

impl ContentFilter {
    fn any(_: u32, _: DataHead) -> bool {
        true
    }
}

/// What a [`ContentFilter`] decides by: a frame's data length and its
/// first three bytes. That is all the analysis asks (an SDO frame's
/// command and object index, a heartbeat's length), and all a reader need
/// parse to ask it: a busy trace's SDO traffic is mostly timed only, and
/// parsing its 8 bytes cost about 50 instructions more a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DataHead {
    len: u8,
    bytes: [u8; 3],
}

impl DataHead {
    /// The head of `data`.
    pub fn of(data: &[u8]) -> DataHead {
        let mut bytes = [0u8; 3];
        for (b, d) in bytes.iter_mut().zip(data) {
            *b = *d;
        }
        DataHead {
            len: data.len().min(usize::from(u8::MAX)) as u8,
            bytes,
        }
    }

    /// Of data `len` bytes long whose first bytes are `bytes` (those past
    /// `len` are ignored).
    pub fn new(len: u8, bytes: [u8; 3]) -> DataHead {
        let mut head = DataHead { len, bytes };
        for (i, b) in head.bytes.iter_mut().enumerate() {
            if i >= usize::from(len) {
                *b = 0;
            }
        }
        head
    }

    /// The data's length.
    // A frame's data length (its DLC in bytes), not a container's size:
    // nothing asks whether it is empty.
    #[allow(clippy::len_without_is_empty)]
    pub fn len(self) -> usize {
        usize::from(self.len)
    }

    /// Its first bytes, at most three.
    pub fn head(&self) -> &[u8] {
        self.bytes.get(..self.len()).unwrap_or(&self.bytes)
    }
}

impl PartialEq for ContentFilter {
    fn eq(&self, other: &Self) -> bool {
        // Same function, same filter (only ever compared in tests).
        self.0 as usize == other.0 as usize
    }
}

impl Eq for ContentFilter {}

impl fmt::Debug for ContentFilter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ContentFilter")
    }
}

#[inline]
fn bit(set: &[u64; 32], id: u32) -> bool {
    set.get((id >> 6) as usize)
        .is_some_and(|word| word & (1 << (id & 63)) != 0)
}

impl Interest {
    /// Decode every frame (tests, conversions).
    pub fn all() -> Interest {
        Interest {
            standard: [u64::MAX; 32],
            all_extended: true,
            extended: Vec::new(),
            filtered: [0; 32],
            content: ContentFilter(ContentFilter::any),
            foldable: [0; 32],
            fold_masks: Vec::new(),
            untimed: [0; 32],
            inside: [0; 32],
        }
    }

    pub fn none() -> Interest {
        Interest {
            standard: [0; 32],
            all_extended: false,
            extended: Vec::new(),
            filtered: [0; 32],
            content: ContentFilter(ContentFilter::any),
            foldable: [0; 32],
            fold_masks: Vec::new(),
            untimed: [0; 32],
            inside: [0; 32],
        }
    }

    /// Puts wanted standard ids under a content filter (one for all).
    pub fn filter_content(&mut self, ids: std::ops::RangeInclusive<u32>, content: ContentFilter) {
        self.content = content;
        for id in ids {
            if let Some(word) = self.filtered.get_mut((id >> 6) as usize) {
                *word |= 1 << (id & 63);
            }
        }
    }

    /// Takes a standard id out of the content filter: all its frames
    /// matter, one by one.
    pub fn unfilter(&mut self, id: u32) {
        for set in [&mut self.filtered, &mut self.foldable] {
            if let Some(word) = set.get_mut((id >> 6) as usize) {
                *word &= !(1 << (id & 63));
            }
        }
    }

    /// Lets readers fold frames on the standard ids in `ids` that repeat
    /// the one before on their id.
    pub fn fold(&mut self, ids: std::ops::RangeInclusive<u32>) {
        for id in ids {
            if let Some(word) = self.foldable.get_mut((id >> 6) as usize) {
                *word |= 1 << (id & 63);
            }
        }
    }

    /// Lets frames on the standard ids in `ids` stay inside a run of folds
    /// ([`Folds::keep_inside`]) rather than end it: the caller takes them
    /// after the run's folds when it takes those whole, so what they do
    /// must not depend on what the folds change, nor change the interest.
    pub fn keep_inside(&mut self, ids: std::ops::RangeInclusive<u32>) {
        for id in ids {
            if let Some(word) = self.inside.get_mut((id >> 6) as usize) {
                *word |= 1 << (id & 63);
            }
        }
    }

    /// Every frame ends a run of folds again (what the frames kept inside
    /// do came to depend on the folds).
    pub fn end_runs_at_frames(&mut self) {
        self.inside = [0; 32];
    }

    /// Whether a frame on a standard id may stay inside a run of folds.
    #[inline]
    pub fn keeps_inside(&self, id: u32) -> bool {
        bit(&self.inside, id)
    }

    /// Lets readers fold frames on standard `id` whose data (the first 8
    /// bytes as a little-endian word) repeats the one before under `mask`.
    pub fn fold_masked(&mut self, id: u32, mask: u64) {
        self.fold(id..=id);
        match self.fold_masks.binary_search_by_key(&id, |&(i, _)| i) {
            Ok(i) => {
                if let Some(m) = self.fold_masks.get_mut(i) {
                    m.1 = mask;
                }
            }
            Err(i) => self.fold_masks.insert(i, (id, mask)),
        }
    }

    /// The bits that must repeat for a fold on `id`.
    pub fn fold_mask(&self, id: u32) -> u64 {
        match self.fold_masks.binary_search_by_key(&id, |&(i, _)| i) {
            Ok(i) => self.fold_masks.get(i).map_or(u64::MAX, |m| m.1),
            Err(_) => u64::MAX,
        }
    }

    /// How frames on a foldable id fold: the bits that must repeat, and
    /// whether the content filter applies to the id.
    pub fn fold_rule(&self, id: u32) -> FoldRule {
        FoldRule {
            mask: self.fold_mask(id),
            filter: self.filters(id).then_some(self.content),
        }
    }

    /// Frames on standard `id` are wanted but move no time: a reader that
    /// spares converting a run's last time because the frame ending the
    /// run moves it again must not count on one of these.
    pub fn untime(&mut self, id: u32) {
        if let Some(word) = self.untimed.get_mut((id >> 6) as usize) {
            *word |= 1 << (id & 63);
        }
    }

    /// Whether a frame on `id` moves the input's first and last time when
    /// the caller gets it.
    #[inline]
    pub fn times(&self, id: u32, extended: bool) -> bool {
        extended || !bit(&self.untimed, id)
    }

    /// Whether a reader may fold repeated frames on a standard id.
    #[inline]
    pub fn folds(&self, id: u32) -> bool {
        bit(&self.foldable, id)
    }

    /// Whether a frame on a wanted id is only to be timed: a standard id
    /// under the content filter, and data it rejects.
    #[inline]
    pub fn timed_only(&self, id: u32, extended: bool, data: &[u8]) -> bool {
        !extended && self.timed_only_head(id, DataHead::of(data))
    }

    /// [`Interest::timed_only`] for a standard id, from the data's head.
    #[inline]
    pub fn timed_only_head(&self, id: u32, head: DataHead) -> bool {
        bit(&self.filtered, id) && !(self.content.0)(id, head)
    }

    /// Whether frames on a standard id are under the content filter.
    #[inline]
    pub fn filters(&self, id: u32) -> bool {
        bit(&self.filtered, id)
    }

    pub fn add_extended(&mut self, id: u32) {
        if let Err(i) = self.extended.binary_search(&id) {
            self.extended.insert(i, id);
        }
    }

    pub fn add_standard(&mut self, id: u32) {
        if let Some(word) = self.standard.get_mut((id >> 6) as usize) {
            *word |= 1 << (id & 63);
        }
    }

    pub fn add_standard_range(&mut self, ids: std::ops::RangeInclusive<u32>) {
        for id in ids {
            self.add_standard(id);
        }
    }

    #[inline]
    pub fn wants(&self, id: u32, extended: bool) -> bool {
        if extended {
            return self.all_extended || self.extended.binary_search(&id).is_ok();
        }
        match self.standard.get((id >> 6) as usize) {
            Some(word) => word & (1 << (id & 63)) != 0,
            None => false,
        }
    }
}

/// Why a line is not a frame of the format being read.
pub type Reason = Cow<'static, str>;

/// The classification of one line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Parsed<'a> {
    Frame(Frame<'a>),
    /// A line that is known not to be a frame (header, comment, status, blank).
    Skipped,
    Malformed(Reason),
}

/// What [`LineParser::scan`] made of a line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Scan<'a> {
    /// A valid frame whose id is not wanted: count it.
    Plain,
    /// A valid frame on a wanted id, as `parse` returns it.
    Frame(Frame<'a>),
    /// A valid frame on a wanted id whose data the content filter rejects:
    /// only its time is needed.
    Timed(Timestamp),
    /// Not the common shape: call `parse`.
    Parse,
}

/// What [`LineParser::run`] read from the start of a block's bytes: `bytes`
/// of whole lines, `plain` frames only to count and `timed` frames only to
/// time (the first and last of their times), then, when `frame` is set, one
/// wanted frame (the last line read).
#[derive(Debug, Default)]
pub struct Run<'a> {
    pub bytes: usize,
    pub plain: u64,
    pub timed: u64,
    pub first_time: Option<Timestamp>,
    pub last_time: Option<Timestamp>,
    pub frame: Option<Frame<'a>>,
    /// The bytes of the lines before `frame` (all of `bytes` without one).
    pub before_frame: usize,
    /// The channel of the frames folded into the run's [`Folds`] (counted
    /// in `timed`; a run has one layout, so one channel).
    pub fold_channel: &'a [u8],
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
    #[inline]
    fn run<'a>(
        &mut self,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        _folds: &mut Folds,
    ) -> Run<'a> {
        let mut run = Run::default();
        while let Some(rest) = bytes.get(run.bytes..)
            && let Some(len) = memchr::memchr(b'\n', rest)
            && len <= max_line
            && let Some(line) = rest.get(..len)
            && line.last() != Some(&b'\r')
        {
            match self.scan(line, interest) {
                Scan::Plain => {
                    run.plain += 1;
                    run.bytes += len + 1;
                }
                Scan::Timed(t) => {
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

    /// Whether a line read so far was a header only this format writes
    /// (an ASC `base` line): the format is known without a frame, and lines
    /// it cannot read are its malformed lines, not an unknown format.
    fn identified(&self) -> bool {
        false
    }

    /// The state later lines depend on, as a small exact value (below 256):
    /// a block parsed from a fork is valid only if the state it started from
    /// equals the state the previous block ended in. `None` when every line
    /// depends on the one before (ASC relative times): parse sequentially.
    fn context(&self) -> Option<u8>;
}

/// One parser of each text format, dispatched by `match`: the set is closed,
/// and a match lets the hot path inline where a trait object would not.
/// `Clone` is how a parser is forked for another thread.
#[derive(Clone)]
pub enum AnyParser {
    CandumpLog(candump_log::CandumpLogParser),
    CandumpScreen(candump_screen::CandumpScreenParser),
    Asc(asc::AscParser),
    Trc(trc::TrcParser),
    Busmaster(busmaster::BusmasterParser),
    Binary(BinaryParser),
}

impl LineParser for AnyParser {
    fn format(&self) -> Format {
        match self {
            AnyParser::CandumpLog(p) => p.format(),
            AnyParser::CandumpScreen(p) => p.format(),
            AnyParser::Asc(p) => p.format(),
            AnyParser::Trc(p) => p.format(),
            AnyParser::Busmaster(p) => p.format(),
            AnyParser::Binary(p) => p.format(),
        }
    }

    #[inline]
    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        match self {
            AnyParser::CandumpLog(p) => p.parse(line, interest),
            AnyParser::CandumpScreen(p) => p.parse(line, interest),
            AnyParser::Asc(p) => p.parse(line, interest),
            AnyParser::Trc(p) => p.parse(line, interest),
            AnyParser::Busmaster(p) => p.parse(line, interest),
            AnyParser::Binary(p) => p.parse(line, interest),
        }
    }

    fn take_warning(&mut self) -> Option<Reason> {
        match self {
            AnyParser::CandumpLog(p) => p.take_warning(),
            AnyParser::CandumpScreen(p) => p.take_warning(),
            AnyParser::Asc(p) => p.take_warning(),
            AnyParser::Trc(p) => p.take_warning(),
            AnyParser::Busmaster(p) => p.take_warning(),
            AnyParser::Binary(p) => p.take_warning(),
        }
    }

    fn identified(&self) -> bool {
        match self {
            AnyParser::CandumpLog(p) => p.identified(),
            AnyParser::CandumpScreen(p) => p.identified(),
            AnyParser::Asc(p) => p.identified(),
            AnyParser::Trc(p) => p.identified(),
            AnyParser::Busmaster(p) => p.identified(),
            AnyParser::Binary(p) => p.identified(),
        }
    }

    fn context(&self) -> Option<u8> {
        match self {
            AnyParser::CandumpLog(p) => p.context(),
            AnyParser::CandumpScreen(p) => p.context(),
            AnyParser::Asc(p) => p.context(),
            AnyParser::Trc(p) => p.context(),
            AnyParser::Busmaster(p) => p.context(),
            AnyParser::Binary(p) => p.context(),
        }
    }

    #[inline]
    fn run<'a>(
        &mut self,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        folds: &mut Folds,
    ) -> Run<'a> {
        match self {
            AnyParser::CandumpLog(p) => p.run(bytes, max_line, interest, folds),
            AnyParser::CandumpScreen(p) => p.run(bytes, max_line, interest, folds),
            AnyParser::Asc(p) => p.run(bytes, max_line, interest, folds),
            AnyParser::Trc(p) => p.run(bytes, max_line, interest, folds),
            AnyParser::Busmaster(p) => p.run(bytes, max_line, interest, folds),
            AnyParser::Binary(p) => p.run(bytes, max_line, interest, folds),
        }
    }

    fn scan<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Scan<'a> {
        match self {
            AnyParser::CandumpLog(p) => p.scan(line, interest),
            AnyParser::CandumpScreen(p) => p.scan(line, interest),
            AnyParser::Asc(p) => p.scan(line, interest),
            AnyParser::Trc(p) => p.scan(line, interest),
            AnyParser::Busmaster(p) => p.scan(line, interest),
            AnyParser::Binary(p) => p.scan(line, interest),
        }
    }
}

/// Lines never reach this parser: binary input (BLF, pcap) goes to its own
/// reader. It exists so that every [`Format`] has a parser.
#[derive(Clone, Copy, Debug)]
pub struct BinaryParser(Format);

impl LineParser for BinaryParser {
    fn format(&self) -> Format {
        self.0
    }

    fn parse<'a>(&mut self, _line: &'a [u8], _interest: &Interest) -> Parsed<'a> {
        Parsed::Malformed(format!("{} is a binary format, not read line by line", self.0).into())
    }

    fn context(&self) -> Option<u8> {
        Some(0)
    }
}

/// A token quoted in a reason (TRC, BUSMASTER): at most 40 characters,
/// invalid UTF-8 replaced and control characters shown as `?`, so a hostile
/// trace cannot put control sequences on the terminal.
pub(crate) fn show_token(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(token);
    let mut out: String = text.chars().take(40).collect();
    if text.chars().count() > 40 {
        out.push('…');
    }
    out.chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect()
}

/// Splits off leading spaces and tabs.
#[inline]
pub(crate) fn trim_start(s: &[u8]) -> &[u8] {
    let n = s.iter().take_while(|b| **b == b' ' || **b == b'\t').count();
    &s[n..]
}

#[inline]
pub(crate) fn trim_end(s: &[u8]) -> &[u8] {
    let n = s
        .iter()
        .rev()
        .take_while(|b| **b == b' ' || **b == b'\t')
        .count();
    &s[..s.len() - n]
}

/// Splits `s` at the first space or tab: (token, rest starting at the blank).
#[inline]
pub(crate) fn split_token(s: &[u8]) -> (&[u8], &[u8]) {
    let end = s
        .iter()
        .position(|b| *b == b' ' || *b == b'\t')
        .unwrap_or(s.len());
    s.split_at(end)
}

/// True for lines that carry nothing (only blanks).
#[inline]
pub(crate) fn is_blank(s: &[u8]) -> bool {
    s.iter().all(|b| *b == b' ' || *b == b'\t')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payload_holds_64_bytes_and_refuses_more() {
        let mut p = Payload::new();
        for i in 0..64 {
            assert!(p.push(i as u8));
            assert_eq!(p.as_slice(), (0..=i).map(|b| b as u8).collect::<Vec<_>>());
        }
        assert!(!p.push(0));
        assert_eq!(p.len(), 64);
        assert!(Payload::from_slice(&[0; 65]).is_none());
        assert_eq!(
            Payload::from_slice(&[1, 2, 3]).unwrap().as_slice(),
            [1, 2, 3]
        );
    }

    #[test]
    fn frames_stay_small_enough_to_move_in_registers() {
        assert!(
            std::mem::size_of::<Frame<'_>>() <= 96,
            "{}",
            std::mem::size_of::<Frame<'_>>()
        );
    }

    #[test]
    fn interest_bitset() {
        let mut i = Interest::none();
        i.add_standard_range(0x81..=0xFF);
        assert!(i.wants(0x81, false));
        assert!(i.wants(0xFF, false));
        assert!(!i.wants(0x80, false));
        assert!(!i.wants(0x81, true));
        assert!(!i.wants(0x7FF, false));
        assert!(!i.wants(u32::MAX, false));
        i.add_standard(5000); // out of range: ignored, no panic
        assert!(Interest::all().wants(0x1234_5678, true));
        i.add_extended(0x1234_5678);
        assert!(i.wants(0x1234_5678, true));
        assert!(!i.wants(0x1234_5679, true));
        assert!(!i.wants(0x78, false));
    }

    #[test]
    fn tokenizing() {
        assert_eq!(trim_start(b" \t x "), b"x ");
        assert_eq!(trim_end(b" x \t"), b" x");
        assert_eq!(split_token(b"ab cd"), (&b"ab"[..], &b" cd"[..]));
        assert!(is_blank(b" \t"));
        assert!(!is_blank(b" x"));
        assert_eq!(HexBytes(&[0x10, 0xab]).to_string(), "10AB");
    }
}
