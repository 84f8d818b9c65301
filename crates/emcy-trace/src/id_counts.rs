//! [`IdCounts`]: every frame of an input counted by channel and identifier,
//! whether anybody decodes it or not. A reader's hot loop reads a line's
//! id before it decides the line is of no interest, so counting it there
//! is one array increment; the traffic report (frames per channel and per
//! identifier) comes from these counts on every run, not only when every
//! frame is decoded.

use crate::Ticks;

/// Channels counted; frames on more are counted in [`IdCounts::others`], so
/// a hostile input cannot grow the counts without bound (each channel holds
/// 16 KiB for its standard ids).
pub const MAX_CHANNELS: usize = 256;

/// Extended identifiers counted per channel; frames on more are counted in
/// the channel's [`ChannelCounts::other`].
pub const MAX_EXTENDED: usize = 4096;

/// What a frame is counted under: its channel and identifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameKey<'a> {
    /// The channel as the line or record names it.
    pub channel: &'a [u8],
    /// The identifier, without flags.
    pub id: u32,
    /// Whether the identifier is a 29-bit one.
    pub extended: bool,
}

/// Frames by channel and identifier. Error frames are counted per channel
/// only: their "identifier" is the error's class.
#[derive(Clone, Debug, Default)]
pub struct IdCounts {
    channels: Vec<ChannelCounts>,
    /// The channel of the last count (most inputs have one).
    last: usize,
    /// Frames on channels past [`MAX_CHANNELS`] ([`IdCounts::others`]).
    other: u64,
    /// Where [`IdCounts::run_parts`] counts frames on channels past
    /// [`MAX_CHANNELS`] (part of [`IdCounts::others`]).
    overflow: Option<Box<ChannelCounts>>,
    /// With every frame timed ([`Interest::every_frame`](crate::Interest::every_frame)):
    /// the lines a reader's hot loop counted without decoding them, with
    /// their times, for the caller to time; the caller empties it after
    /// each run ([`Run::channel`](crate::Run::channel) names their channel).
    pub timed_lines: Vec<TimedLine>,
}

/// A frame a reader only counted while every frame is timed: what timing
/// it needs, without its data. Only the candump reader's hot loop makes
/// them, and its lines there are classic data frames on standard ids, so
/// that is what a timed line is: 16 bytes rather than the 32 a general
/// frame's fields took. With every frame timed there is one a line, written
/// by a worker and read by the consumer on another core: the 32 bytes cost
/// 7% of `--timing`'s time (interleaved runs, the bench's 512 MiB segmented
/// firmware trace).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimedLine {
    /// Its time's ticks ([`Ticks::value`]).
    ticks: u64,
    /// Its line, as an index into the run's lines.
    pub idx: u32,
    /// Its 11-bit identifier.
    id: u16,
    /// Its data length, 0 to 8.
    pub len: u8,
    /// Its time's fraction digits ([`Ticks::digits`]); [`NO_TIME`]: the
    /// line's time has too many digits to read as ticks.
    digits: u8,
}

/// [`TimedLine::digits`] of a line without [`Ticks`].
const NO_TIME: u8 = u8::MAX;

impl TimedLine {
    /// Line `idx` of its run, a classic data frame on standard `id` with
    /// `len` data bytes at `time`.
    #[inline]
    pub fn new(idx: u32, time: Option<Ticks>, id: u16, len: u8) -> Self {
        let (ticks, digits) = time.map_or((0, NO_TIME), |t| (t.value, t.digits));
        TimedLine {
            ticks,
            idx,
            id,
            len,
            digits,
        }
    }

    /// Its time, as the line wrote it (`None`: too many digits to read so).
    #[inline]
    pub fn time(&self) -> Option<Ticks> {
        (self.digits != NO_TIME).then_some(Ticks {
            value: self.ticks,
            digits: self.digits,
        })
    }

    /// Its identifier (a standard one).
    #[inline]
    pub fn id(&self) -> u32 {
        u32::from(self.id)
    }
}

/// One channel's counts.
#[derive(Clone, Debug)]
pub struct ChannelCounts {
    name: Box<[u8]>,
    standard: Box<[u64; 2048]>,
    /// Sorted by id.
    extended: Vec<(u32, u64)>,
    error_frames: u64,
    /// Frames on extended ids past [`MAX_EXTENDED`].
    pub other: u64,
}

impl<'a> FrameKey<'a> {
    /// The key of a frame on `channel` with `id`.
    pub const fn new(channel: &'a [u8], id: u32, extended: bool) -> Self {
        FrameKey {
            channel,
            id,
            extended,
        }
    }
}

impl IdCounts {
    /// No counts.
    pub fn new() -> Self {
        IdCounts::default()
    }

    /// The index of channel `name`, made on its first frame; `None` past
    /// [`MAX_CHANNELS`] (the caller counts the frame in `other`).
    #[inline]
    pub fn channel(&mut self, name: &[u8]) -> Option<usize> {
        if let Some(c) = self.channels.get(self.last)
            && *c.name == *name
        {
            return Some(self.last);
        }
        self.find(name)
    }

    #[inline(never)]
    fn find(&mut self, name: &[u8]) -> Option<usize> {
        let i = match self.channels.iter().position(|c| *c.name == *name) {
            Some(i) => i,
            None if self.channels.len() < MAX_CHANNELS => {
                self.channels.push(ChannelCounts::new(name));
                self.channels.len() - 1
            }
            None => return None,
        };
        self.last = i;
        Some(i)
    }

    /// The counts of channel `name` and the timed lines, for a reader
    /// whose run of lines is on one channel: it finds the counts once and
    /// counts each line with [`ChannelCounts::count`]. Past
    /// [`MAX_CHANNELS`], counts that only add to [`IdCounts::others`].
    #[inline]
    pub fn run_parts(&mut self, name: &[u8]) -> (&mut ChannelCounts, &mut Vec<TimedLine>) {
        let i = self.channel(name);
        let IdCounts {
            channels,
            overflow,
            timed_lines,
            ..
        } = self;
        let counts = match i.and_then(|i| channels.get_mut(i)) {
            Some(c) => c,
            None => overflow.get_or_insert_with(|| Box::new(ChannelCounts::new(b""))),
        };
        (counts, timed_lines)
    }

    /// One frame.
    #[inline]
    pub fn count(&mut self, key: FrameKey<'_>) {
        match self.channel(key.channel) {
            Some(c) => self.count_at(c, key.id, key.extended),
            None => self.other += 1,
        }
    }

    /// One frame on the channel [`IdCounts::channel`] gave `c` (a reader
    /// whose run of lines has one channel finds it once).
    #[inline]
    pub fn count_at(&mut self, c: usize, id: u32, extended: bool) {
        match self.channels.get_mut(c) {
            Some(channel) => channel.count(id, extended),
            None => self.other += 1,
        }
    }

    /// One error frame on `channel`.
    pub fn error_frame(&mut self, channel: &[u8]) {
        match self.channel(channel).and_then(|c| self.channels.get_mut(c)) {
            Some(c) => c.error_frames += 1,
            None => self.other += 1,
        }
    }

    /// Adds `other`'s counts (the next block's) to these: channels new to
    /// these come after theirs, in `other`'s order.
    pub fn add(&mut self, other: &IdCounts) {
        for theirs in &other.channels {
            let frames = theirs.frames();
            if frames == 0 {
                // A slot kept from an earlier block for its memory.
                continue;
            }
            let Some(c) = self.channel(&theirs.name) else {
                self.other += frames;
                continue;
            };
            if let Some(ours) = self.channels.get_mut(c) {
                ours.add(theirs);
            }
        }
        self.other += other.others();
    }

    /// Every count back to zero, the channels' memory kept for the next
    /// block.
    pub fn clear(&mut self) {
        for c in &mut self.channels {
            c.standard.fill(0);
            c.extended.clear();
            c.error_frames = 0;
            c.other = 0;
        }
        self.timed_lines.clear();
        // A cleared channel without frames is no channel: dropped when it
        // is not reused, by name, in [`IdCounts::channel`] (kept here only
        // for its memory).
        self.other = 0;
        self.overflow = None;
    }

    /// The channels that had a frame, in the order of their first.
    pub fn channels(&self) -> impl Iterator<Item = &ChannelCounts> {
        self.channels.iter().filter(|c| c.frames() > 0)
    }

    /// Every frame counted.
    pub fn frames(&self) -> u64 {
        self.channels.iter().map(ChannelCounts::frames).sum::<u64>() + self.others()
    }

    /// Frames on channels past [`MAX_CHANNELS`].
    pub fn others(&self) -> u64 {
        self.other + self.overflow.as_ref().map_or(0, |o| o.frames())
    }
}

/// Where a reader counts the frames of a channel it knows by a number (a
/// pcapng interface, an MF4 bus channel): looked up by name in an
/// [`IdCounts`] once, so that counting a frame is one increment, not a
/// comparison of names.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum CountedChannel {
    /// Not looked up yet.
    #[default]
    Unknown,
    /// The index [`IdCounts::channel`] gave (below [`MAX_CHANNELS`]: kept
    /// small, as a reader's hot loop passes it around with every frame).
    At(u32),
    /// Past [`MAX_CHANNELS`]: its frames are counted in [`IdCounts::others`].
    Other,
}

impl IdCounts {
    /// Where frames on channel `name` are counted (see [`CountedChannel`]).
    pub(crate) fn counted_channel(&mut self, name: &[u8]) -> CountedChannel {
        match self.channel(name).and_then(|c| u32::try_from(c).ok()) {
            Some(c) => CountedChannel::At(c),
            None => CountedChannel::Other,
        }
    }

    /// One frame on `channel`, which [`IdCounts::counted_channel`] gave
    /// (an unknown one is counted in `other`, as one past the limit).
    #[inline]
    pub(crate) fn count_in(&mut self, channel: CountedChannel, id: u32, extended: bool) {
        match channel {
            CountedChannel::At(c) => self.count_at(c as usize, id, extended),
            CountedChannel::Unknown | CountedChannel::Other => self.other += 1,
        }
    }
}

impl ChannelCounts {
    fn new(name: &[u8]) -> Self {
        ChannelCounts {
            name: name.into(),
            standard: Box::new([0; 2048]),
            extended: Vec::new(),
            error_frames: 0,
            other: 0,
        }
    }

    /// One frame on `id`.
    #[inline]
    pub fn count(&mut self, id: u32, extended: bool) {
        match self.standard.get_mut(id as usize) {
            Some(n) if !extended => *n += 1,
            _ => self.count_extended(id),
        }
    }

    /// Not inlined: rare on the buses we read, and it kept the hot loop's
    /// standard-id count one branch long.
    #[inline(never)]
    fn count_extended(&mut self, id: u32) {
        self.add_extended(id, 1);
    }

    fn add_extended(&mut self, id: u32, n: u64) {
        match self.extended.binary_search_by_key(&id, |e| e.0) {
            Ok(i) => {
                if let Some(e) = self.extended.get_mut(i) {
                    e.1 += n;
                }
            }
            Err(i) if self.extended.len() < MAX_EXTENDED => self.extended.insert(i, (id, n)),
            Err(_) => self.other += n,
        }
    }

    fn add(&mut self, other: &ChannelCounts) {
        for (n, m) in self.standard.iter_mut().zip(other.standard.iter()) {
            *n += m;
        }
        for &(id, n) in &other.extended {
            self.add_extended(id, n);
        }
        self.error_frames += other.error_frames;
        self.other += other.other;
    }

    /// The channel's name as its lines or records wrote it.
    pub fn name(&self) -> &[u8] {
        &self.name
    }

    /// Every frame on the channel, error frames included.
    pub fn frames(&self) -> u64 {
        self.standard.iter().sum::<u64>()
            + self.extended.iter().map(|e| e.1).sum::<u64>()
            + self.error_frames
            + self.other
    }

    /// Error frames.
    pub fn error_frames(&self) -> u64 {
        self.error_frames
    }

    /// Frames per identifier that had any: `(id, extended, frames)`, the
    /// standard ids first, each kind by id.
    pub fn ids(&self) -> impl Iterator<Item = (u32, bool, u64)> + '_ {
        let standard = (0u32..)
            .zip(self.standard.iter())
            .filter(|(_, n)| **n > 0)
            .map(|(id, n)| (id, false, *n));
        standard.chain(self.extended.iter().map(|&(id, n)| (id, true, n)))
    }
}

/// What the readers' tests (and fuzz target bodies) check
/// [`FrameSource::counted_ids`] with: the frames a reader hands on, counted
/// as its caller counts them, plus the frames it only counted, must be
/// every frame of the input.
///
/// [`FrameSource::counted_ids`]: crate::FrameSource::counted_ids
#[cfg(any(test, feature = "fuzzing"))]
pub(crate) mod testing {
    use std::collections::BTreeMap;

    use super::IdCounts;
    #[cfg(test)]
    use crate::{ContentFilter, FrameSource, Interest, Next, Parsed};
    use crate::{Frame, FrameKind};

    /// What a count is of: an identifier, a channel's error frames, or the
    /// frames past a bound.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
    pub(crate) enum Counted {
        Id(u32, bool),
        ErrorFrames,
        Other,
    }

    /// Every count of `ids` by channel (`None`: frames on channels past the
    /// bound), in an order that does not depend on which came first.
    pub(crate) fn table(ids: &IdCounts) -> BTreeMap<(Option<Vec<u8>>, Counted), u64> {
        let mut t = BTreeMap::new();
        for c in ids.channels() {
            let name = Some(c.name().to_vec());
            for (id, extended, n) in c.ids() {
                t.insert((name.clone(), Counted::Id(id, extended)), n);
            }
            for (what, n) in [
                (Counted::ErrorFrames, c.error_frames()),
                (Counted::Other, c.other),
            ] {
                if n > 0 {
                    t.insert((name.clone(), what), n);
                }
            }
        }
        if ids.others() > 0 {
            t.insert((None, Counted::Other), ids.others());
        }
        t
    }

    /// Counts a frame handed on as its caller counts it: an error frame
    /// per channel, any other by identifier.
    pub(crate) fn count_frame(ids: &mut IdCounts, f: &Frame<'_>) {
        if f.kind == FrameKind::Error {
            ids.error_frame(f.channel);
        } else {
            ids.count(f.key());
        }
    }

    /// The interests the readers' tests read with: none, the EMCY ids,
    /// and the EMCY ids with the heartbeats wanted only when they are a
    /// boot-up (the others only timed).
    #[cfg(test)]
    pub(crate) fn interests() -> Vec<(&'static str, Interest)> {
        let mut emcy = Interest::none();
        emcy.add_standard_range(0x81..=0xFF);
        let mut boot_ups = emcy.clone();
        boot_ups.add_standard_range(0x701..=0x77F);
        boot_ups.filter_content(0x701..=0x77F, ContentFilter(|_, d| d.head() == [0]));
        vec![
            ("no id wanted", Interest::none()),
            ("the EMCY ids wanted", emcy),
            ("boot-ups wanted, other heartbeats timed", boot_ups),
        ]
    }

    /// The repository's fixtures whose names end in one of `extensions`,
    /// with their bytes.
    #[cfg(test)]
    pub(crate) fn fixtures(extensions: &[&str]) -> Vec<(String, Vec<u8>)> {
        // The workspace's fixtures, two folders up from this crate.
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
        let mut found: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
            .expect("the fixtures folder")
            .filter_map(|e| {
                let path = e.ok()?.path();
                let ext = path.extension()?.to_str()?;
                if !extensions.contains(&ext) {
                    return None;
                }
                let name = path.file_name()?.to_str()?.to_string();
                Some((name, std::fs::read(&path).ok()?))
            })
            .collect();
        found.sort();
        assert!(!found.is_empty(), "no fixture ends in {extensions:?}");
        found
    }

    /// What reading a source to its end gave: the frames it handed on,
    /// counted as a caller counts them (error frames per channel), the
    /// frames its [`Next::Counted`] items said it only counted (`plain`
    /// and `timed`), and its [`FrameSource::counted_ids`].
    #[cfg(test)]
    pub(crate) struct Read {
        pub(crate) handed_on: IdCounts,
        pub(crate) only_counted: u64,
        pub(crate) counted_ids: Option<IdCounts>,
    }

    /// Reads `source` to its end (or its first error) with `interest`.
    #[cfg(test)]
    pub(crate) fn read(source: &mut impl FrameSource, interest: &Interest) -> Read {
        let mut handed_on = IdCounts::new();
        let mut only_counted = 0;
        while let Ok(Some(next)) = source.next_item(Some(interest)) {
            match next {
                Next::Record(Parsed::Frame(f)) => count_frame(&mut handed_on, &f),
                Next::Counted(c) => only_counted += c.plain + c.timed.map_or(0, |t| t.0),
                Next::Record(_) | Next::Note(_) => {}
            }
        }
        Read {
            handed_on,
            only_counted,
            counted_ids: source.counted_ids().cloned(),
        }
    }

    /// Reads `all` with [`Interest::all`] and `some` (the same input) with
    /// `interest`: the frames `some` hands on plus its
    /// [`FrameSource::counted_ids`] must be the frames of `all` by channel
    /// and identifier, and those counts exactly the frames its
    /// [`Next::Counted`] items say it only counted, none an error frame.
    /// Returns how many frames `some` only counted.
    #[cfg(test)]
    pub(crate) fn assert_counts_add_up(
        all: &mut impl FrameSource,
        some: &mut impl FrameSource,
        interest: &Interest,
        what: &str,
    ) -> u64 {
        let all = read(all, &Interest::all());
        assert_eq!(all.only_counted, 0, "{what}: every frame wanted");
        if let Some(ids) = &all.counted_ids {
            assert_eq!(ids.frames(), 0, "{what}: nothing only counted");
        }
        let some = read(some, interest);
        let counted = some.counted_ids.unwrap_or_default();
        assert_eq!(
            counted.frames(),
            some.only_counted,
            "{what}: the counts are the frames only counted"
        );
        assert!(
            counted.channels().all(|c| c.error_frames() == 0),
            "{what}: error frames are handed on, never only counted"
        );
        let mut sum = some.handed_on;
        sum.add(&counted);
        assert_eq!(table(&sum), table(&all.handed_on), "{what}");
        some.only_counted
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::MAX_FRACTION_DIGITS;

    #[test]
    fn a_timed_line_keeps_its_time_or_none_in_16_bytes() {
        let t = Ticks::new(1_700_000_000_123_456, 6);
        let l = TimedLine::new(7, t, 0x7FF, 8);
        assert_eq!((l.idx, l.time(), l.id(), l.len), (7, t, 0x7FF, 8));
        // No digits a time can have read as none.
        for digits in 0..=MAX_FRACTION_DIGITS as u8 {
            let t = Ticks::new(u64::MAX, digits);
            assert!(t.is_some());
            assert_eq!(TimedLine::new(0, t, 0x80, 0).time(), t);
        }
        assert_eq!(TimedLine::new(0, None, 0x80, 0).time(), None);
        // What the consumer streams through once a line (see the type).
        assert_eq!(std::mem::size_of::<TimedLine>(), 16);
    }

    fn key(channel: &[u8], id: u32, extended: bool) -> FrameKey<'_> {
        FrameKey {
            channel,
            id,
            extended,
        }
    }

    #[test]
    fn counts_by_channel_and_id_in_the_order_channels_came() {
        let mut c = IdCounts::new();
        c.count(key(b"can1", 0x181, false));
        c.count(key(b"can0", 0x181, false));
        c.count(key(b"can1", 0x181, false));
        c.count(key(b"can1", 0x181, true));
        c.error_frame(b"can0");
        let got: Vec<_> = c
            .channels()
            .map(|ch| {
                (
                    ch.name().to_vec(),
                    ch.ids().collect::<Vec<_>>(),
                    ch.frames(),
                )
            })
            .collect();
        assert_eq!(
            got,
            vec![
                (
                    b"can1".to_vec(),
                    vec![(0x181, false, 2), (0x181, true, 1)],
                    3
                ),
                (b"can0".to_vec(), vec![(0x181, false, 1)], 2),
            ]
        );
        assert_eq!(c.frames(), 5);
    }

    #[test]
    fn adding_blocks_equals_counting_them_whole() {
        let lines = [
            (b"a".as_slice(), 1u32, false),
            (b"b", 0x1FFF_FFFF, true),
            (b"a", 0x7FF, false),
            (b"c", 2, false),
            (b"a", 1, false),
        ];
        let mut whole = IdCounts::new();
        for &(ch, id, ext) in &lines {
            whole.count(key(ch, id, ext));
        }
        for split in 0..=lines.len() {
            let (first, second) = lines.split_at(split);
            let mut sum = IdCounts::new();
            let mut block = IdCounts::new();
            for part in [first, second] {
                block.clear();
                for &(ch, id, ext) in part {
                    block.count(key(ch, id, ext));
                }
                sum.add(&block);
            }
            let names = |c: &IdCounts| {
                c.channels()
                    .map(|ch| ch.name().to_vec())
                    .collect::<Vec<_>>()
            };
            let ids = |c: &IdCounts| {
                c.channels()
                    .map(|ch| ch.ids().collect::<Vec<_>>())
                    .collect::<Vec<_>>()
            };
            assert_eq!(names(&sum), names(&whole), "split at {split}");
            assert_eq!(ids(&sum), ids(&whole), "split at {split}");
        }
    }

    #[test]
    fn channels_and_extended_ids_past_the_bounds_are_counted_as_other() {
        let mut c = IdCounts::new();
        for i in 0..MAX_CHANNELS + 3 {
            c.count(key(format!("ch{i}").as_bytes(), 1, false));
        }
        assert_eq!(c.channels().count(), MAX_CHANNELS);
        assert_eq!(c.others(), 3);
        let mut e = IdCounts::new();
        for id in 0..MAX_EXTENDED as u32 + 5 {
            e.count(key(b"can0", id, true));
        }
        let ch = e.channels().next().expect("one channel");
        assert_eq!((ch.ids().count(), ch.other), (MAX_EXTENDED, 5));
        assert_eq!(e.frames(), MAX_EXTENDED as u64 + 5);
    }

    #[test]
    fn a_run_on_a_channel_past_the_bound_counts_in_others_and_adds_up() {
        let mut block = IdCounts::new();
        for i in 0..MAX_CHANNELS {
            block.count(key(format!("ch{i}").as_bytes(), 1, false));
        }
        let (past, _) = block.run_parts(b"one too many");
        past.count(0x181, false);
        past.count(0x181, false);
        assert_eq!(
            (block.others(), block.frames()),
            (2, MAX_CHANNELS as u64 + 2)
        );
        let mut input = IdCounts::new();
        input.add(&block);
        input.add(&block);
        assert_eq!(input.others(), 4);
        assert_eq!(input.frames(), 2 * (MAX_CHANNELS as u64 + 2));
    }

    #[test]
    fn an_id_past_the_standard_range_without_the_flag_is_counted_as_extended() {
        let mut c = IdCounts::new();
        c.count(key(b"x", 0x800, false));
        let ch = c.channels().next().expect("one channel");
        assert_eq!(ch.ids().collect::<Vec<_>>(), vec![(0x800, true, 1)]);
    }
}
