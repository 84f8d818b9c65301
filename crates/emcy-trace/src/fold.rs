//! Frames a reader's hot loop folds instead of handing them over one by
//! one: on the ids the [`Interest`](super::Interest) marks foldable (NMT
//! error control, 0x700 + node; a drive's PDOs), a frame whose data
//! repeats the one before it on its id in the same run, in the bits the
//! interest says matter (a PDO's position changes every frame, its
//! statusword's state bits seldom). A node heartbeating every 100 ms on a busy
//! bus sends one such frame every few hundred lines, and each used to end
//! the hot loop, be built, recorded and replayed on its own (about 830
//! instructions a heartbeat, measured in docs/performance.md). A fold keeps
//! what the consumer needs to take them all at once (how many, the first
//! and last time, the last line, the largest gap between two of them), and
//! each frame, for when it cannot: then it takes them one by one, so the
//! result never depends on folding.

use super::{ContentFilter, Frame, FrameKind, Payload, Ticks, Timestamp, hex};

/// A frame's data as the hex digits its line wrote, up to 16 of them read
/// as one little-endian number (first digit lowest, in two words): a
/// repeat is found by comparing these, before anything is parsed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HexText {
    words: [u64; 2],
    /// How many digits (twice the data bytes).
    len: u8,
}

/// Which digits of a [`HexText`] must repeat.
type DigitMask = [u64; 2];

impl HexText {
    /// The digits in `start..end` of `line`, which the caller checked are
    /// an even number (at most 16) of hex digits; `None` when fewer than 16
    /// bytes of the line end there (read as one number).
    #[inline]
    pub fn of(line: &[u8], start: usize, end: usize) -> Option<HexText> {
        let len = end.checked_sub(start).filter(|&n| n <= 16 && n % 2 == 0)?;
        let bytes: [u8; 16] = line.get(end.checked_sub(16)?..end)?.try_into().ok()?;
        let digits = u128::from_le_bytes(bytes)
            .checked_shr(8 * (16 - len as u32))
            .unwrap_or(0);
        Some(HexText {
            words: [digits as u64, (digits >> 64) as u64],
            len: len as u8,
        })
    }

    /// The data bytes as [`Payload::word`](super::Payload::word) gives them.
    pub fn word(self) -> u64 {
        let [lo, hi] = self.words;
        let mut digits = [0u8; 16];
        digits[..8].copy_from_slice(&lo.to_le_bytes());
        digits[8..].copy_from_slice(&hi.to_le_bytes());
        let mut word = 0u64;
        for (i, pair) in digits
            .chunks_exact(2)
            .take(usize::from(self.bytes()))
            .enumerate()
        {
            let byte = hex::parse_byte(pair[0], pair[1]).unwrap_or(0);
            word |= u64::from(byte) << (8 * i);
        }
        word
    }

    /// Data bytes.
    pub fn bytes(self) -> u8 {
        self.len / 2
    }

    /// The digits that hold any of the data bits `mask`.
    fn mask(self, mask: u64) -> DigitMask {
        let mut words = [0u64; 2];
        for i in 0..usize::from(self.bytes()).min(8) {
            let byte = (mask >> (8 * i)) as u8;
            // Byte i is digits 2i (its high nibble) and 2i + 1.
            let word = words.get_mut(i / 4);
            if let Some(w) = word {
                let at = 16 * (i % 4);
                if byte & 0xF0 != 0 {
                    *w |= 0xFF << at;
                }
                if byte & 0x0F != 0 {
                    *w |= 0xFF << (at + 8);
                }
            }
        }
        words
    }

    /// Whether `self` and `other` differ in a digit of `mask`.
    #[inline]
    fn differs(self, other: [u64; 2], mask: DigitMask) -> bool {
        let [a, b] = self.words;
        ((a ^ other[0]) & mask[0]) | ((b ^ other[1]) & mask[1]) != 0
    }
}

/// The frames of one id folded in a run. Times are kept as the layout's
/// [`Ticks`] (all of a run's have the same digits) and converted on
/// request: a fold of a steady heartbeat holds two frames on a typical bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fold {
    /// The standard id whose frames these are.
    pub id: u32,
    count: u32,
    /// The last frame's line, as an index into the run's lines.
    last_idx: u32,
    digits: u8,
    /// Data digits (twice the bytes).
    len: u8,
    first_text: [u64; 2],
    last_text: [u64; 2],
    first: u64,
    last: u64,
    /// In ticks.
    max_gap: u64,
}

impl Fold {
    fn new(id: u32, text: HexText, time: Ticks, idx: u32) -> Fold {
        Fold {
            id,
            count: 1,
            last_idx: idx,
            digits: time.digits,
            len: text.len,
            first_text: text.words,
            last_text: text.words,
            first: time.value,
            last: time.value,
            max_gap: 0,
        }
    }

    /// One more frame, `text` at `t` ticks (not before the last).
    #[inline]
    fn push(&mut self, text: HexText, t: u64, idx: u32) {
        self.max_gap = self.max_gap.max(t.saturating_sub(self.last));
        self.count = self.count.saturating_add(1);
        self.last_text = text.words;
        self.last = t;
        self.last_idx = idx;
    }

    /// How many frames.
    pub fn count(&self) -> u64 {
        u64::from(self.count)
    }

    /// The last frame's line, as an index into the run's lines.
    pub fn last_idx(&self) -> u64 {
        u64::from(self.last_idx)
    }

    /// The time of the fold's first frame.
    pub fn first(&self) -> Timestamp {
        self.ticks(self.first).timestamp()
    }

    /// The time of its last frame.
    pub fn last(&self) -> Timestamp {
        self.ticks(self.last).timestamp()
    }

    /// The largest time between two of its frames, in attoseconds (0 for
    /// one frame).
    pub fn max_gap(&self) -> i128 {
        self.ticks(0).attos(self.max_gap)
    }

    /// The data of its first frame, as [`Payload::word`](super::Payload::word)
    /// gives it; every frame of the fold had the same bits as it under the
    /// id's mask.
    pub fn data(&self) -> u64 {
        self.text(self.first_text).word()
    }

    /// The data of its last frame.
    pub fn last_data(&self) -> u64 {
        self.text(self.last_text).word()
    }

    /// Data bytes.
    // The frame's data length, not the size of a collection: there is no
    // emptiness to ask about apart from it.
    #[allow(clippy::len_without_is_empty)]
    pub fn len(&self) -> u8 {
        self.len / 2
    }

    fn text(&self, words: [u64; 2]) -> HexText {
        HexText {
            words,
            len: self.len,
        }
    }

    fn ticks(&self, value: u64) -> Ticks {
        Ticks {
            value,
            digits: self.digits,
        }
    }
}

/// One frame of a fold, kept so that a consumer refusing the folds can
/// take the frames one by one without reading the lines again (reading
/// them again cost 43M instructions more on the 20 MB plain candump bench
/// trace, whose heartbeats at random intervals are refused run after run).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Folded {
    /// The frame's line, as an index into the run's lines.
    idx: u32,
    id: u16,
    len: u8,
    digits: u8,
    ticks: u64,
    text: [u64; 2],
}

impl Folded {
    fn new(id: u32, text: HexText, time: Ticks, idx: u32) -> Folded {
        Folded {
            idx,
            ticks: time.value,
            text: text.words,
            // Standard ids: at most 0x7FF.
            id: id as u16,
            len: text.len,
            digits: time.digits,
        }
    }

    /// The frame's standard id.
    pub fn id(&self) -> u32 {
        u32::from(self.id)
    }

    /// The frame's line, as an index into the run's lines.
    pub fn idx(&self) -> u64 {
        u64::from(self.idx)
    }

    /// The frame's time.
    pub fn time(&self) -> Timestamp {
        Ticks {
            value: self.ticks,
            digits: self.digits,
        }
        .timestamp()
    }

    /// As [`Payload::word`](super::Payload::word) gives it.
    pub fn data(&self) -> u64 {
        self.text().word()
    }

    /// Data bytes.
    // The frame's data length, not the size of a collection.
    #[allow(clippy::len_without_is_empty)]
    pub fn len(&self) -> u8 {
        self.text().bytes()
    }

    fn text(&self) -> HexText {
        HexText {
            words: self.text,
            len: self.len,
        }
    }
}

/// A frame that did not end its run of folds ([`Folds::keep_inside`]): a
/// caller that takes the folds whole takes it after them, one that cannot
/// takes it in line order among their frames. On a busy bus EMCYs come
/// every few hundred lines; ending a run at each made a heartbeat's fold
/// hold two frames, and the consumer's work per fold was a fifth of the
/// critical path on two threads (docs/performance.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inner {
    /// The frame's line, as an index into the run's lines.
    idx: u32,
    len: u8,
    id: u32,
    data: [u8; 8],
    time: Timestamp,
}

impl Inner {
    /// The frame's line, as an index into the run's lines.
    pub fn idx(&self) -> u64 {
        u64::from(self.idx)
    }

    /// The frame's id.
    pub fn id(&self) -> u32 {
        self.id
    }

    /// The frame again, on `channel` (the run's: a run has one).
    pub fn frame<'a>(&self, channel: &'a [u8]) -> Frame<'a> {
        Frame {
            time: Some(self.time),
            channel,
            id: self.id,
            extended: false,
            kind: FrameKind::Data,
            len: self.len,
            data: Payload::inline(self.data, self.len),
        }
    }
}

/// What folds an id's frames: the bits that must repeat, and the content
/// filter when the id is under it (then a frame folds only with data the
/// filter lets through).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FoldRule {
    /// The bits of the data (the first 8 bytes as a little-endian word) that
    /// must repeat.
    pub mask: u64,
    /// The content filter a frame's data must pass to fold, when the id is
    /// under it.
    pub filter: Option<ContentFilter>,
}

/// An id's folding, across the runs of the folds.
#[derive(Clone, Copy, Debug)]
struct IdState {
    /// Its fold in `list`, if `run` is the current run.
    fold: u32,
    run: u32,
    /// The rule its last fold was started with.
    rule: FoldRule,
    /// The digits of that fold's first frame, how many, and those that
    /// must repeat for a frame to fold without being parsed (under a
    /// content filter, every one: the same data has the same verdict).
    text: [u64; 2],
    len: u8,
    text_mask: DigitMask,
    /// The last digits the rule's filter let through.
    passed: Option<HexText>,
}

/// The folds of a block's runs, at most one per (standard) id and run, and
/// what was learnt of each id in the runs before (a block's runs are short:
/// a heartbeat's fold holds two frames on a busy bus, so starting a fold
/// must be as cheap as extending one). Every run's are kept until the
/// block is done, so a worker hands them on without copying them.
#[derive(Clone, Debug)]
pub struct Folds {
    list: Vec<Fold>,
    /// Every frame folded, in line order.
    frames: Vec<Folded>,
    /// Frames kept inside the runs ([`Folds::keep_inside`]), in line order.
    inner: Vec<Inner>,
    /// Where the current run's begin in `list`, `frames` and `inner`.
    run_list: usize,
    run_frames: usize,
    run_inner: usize,
    /// The lines of the current run before the reader's present stretch
    /// of it (a run goes on past a frame kept inside): added to the lines
    /// the reader counts.
    base: u64,
    /// Whether the runs before are kept (for a sink that takes the
    /// block's whole, [`Folds::into_buffers`]); if not, each run's are
    /// dropped at the next, and their memory stays in the cache.
    keep: bool,
    /// Every id folded since the folds were made.
    ids: Vec<IdState>,
    /// Index + 1 into `ids` by id; 0: none.
    slot: Box<[u16; 2048]>,
    /// The run the folds are of (counted by [`Folds::next_run`]).
    run: u32,
    /// The time of the last frame folded or kept inside: times only go
    /// forward in a run (the consumer's checks of the folds rely on it),
    /// and all have the same digits.
    latest: Option<Ticks>,
}

/// The vectors of a block's folds and their frames ([`Folds::into_buffers`]).
#[derive(Clone, Debug, Default)]
pub struct FoldBuffers {
    /// The folds, run after run.
    pub folds: Vec<Fold>,
    /// The frames folded, one by one, for a caller that cannot take folds
    /// whole.
    pub frames: Vec<Folded>,
    /// The frames kept inside runs ([`Folds::keep_inside`]).
    pub inner: Vec<Inner>,
}

impl Default for Folds {
    fn default() -> Self {
        Folds::with_buffers(FoldBuffers::default(), false)
    }
}

impl Folds {
    /// Folds that fill `buffers` (emptied first; a sink's, from the block
    /// before), and `keep` every run's.
    pub fn with_buffers(buffers: FoldBuffers, keep: bool) -> Folds {
        let FoldBuffers {
            folds: mut list,
            mut frames,
            mut inner,
        } = buffers;
        list.clear();
        frames.clear();
        inner.clear();
        Folds {
            list,
            frames,
            inner,
            run_list: 0,
            run_frames: 0,
            run_inner: 0,
            base: 0,
            keep,
            ids: Vec::new(),
            slot: Box::new([0; 2048]),
            run: 0,
            latest: None,
        }
    }

    /// The folds and frames of every run kept, the block being done.
    pub fn into_buffers(self) -> FoldBuffers {
        FoldBuffers {
            folds: self.list,
            frames: self.frames,
            inner: self.inner,
        }
    }

    /// Starts the next run (the folds of the last stay in the buffers).
    #[inline]
    pub fn next_run(&mut self) {
        self.base = 0;
        if self.latest.is_none() {
            return;
        }
        self.run = self.run.wrapping_add(1);
        if self.run == 0 {
            // After 2^32 runs a stale `run` could match again.
            self.ids.iter_mut().for_each(|s| s.run = u32::MAX);
        }
        if self.keep {
            self.run_list = self.list.len();
            self.run_frames = self.frames.len();
            self.run_inner = self.inner.len();
        } else {
            self.list.clear();
            self.frames.clear();
            self.inner.clear();
        }
        self.latest = None;
    }

    /// The current run's folds.
    pub fn as_slice(&self) -> &[Fold] {
        self.list.get(self.run_list..).unwrap_or_default()
    }

    /// Every frame folded in the current run, in line order.
    pub fn frames(&self) -> &[Folded] {
        self.frames.get(self.run_frames..).unwrap_or_default()
    }

    /// The frames kept inside the current run, in line order.
    pub fn inner(&self) -> &[Inner] {
        self.inner.get(self.run_inner..).unwrap_or_default()
    }

    /// Where the current run's folds, frames and frames kept inside begin
    /// in the buffers ([`Folds::into_buffers`]).
    pub fn run_start(&self) -> (usize, usize, usize) {
        (self.run_list, self.run_frames, self.run_inner)
    }

    /// Keeps `frame`, on line `idx` of the reader's present stretch of the
    /// run, inside the run instead of ending it, if it can be: a classic
    /// standard data frame, timed in order with the frames folded so far
    /// (so that the run's times only go forward, and its latest time is
    /// its last: a caller checking the folds at that time checks them at
    /// the frame too). The reader's next stretch goes on after it; the
    /// caller says which frames may stay ([`Interest::keeps_inside`]).
    ///
    /// [`Interest::keeps_inside`]: super::Interest::keeps_inside
    pub fn keep_inside(&mut self, frame: &Frame<'_>, idx: u64) -> bool {
        if self.latest.is_none() || frame.kind != FrameKind::Data || frame.extended {
            return false;
        }
        let (Some(time), Some(ticks)) = (frame.time, frame.time.and_then(Timestamp::ticks)) else {
            return false;
        };
        let Some(at) = self.admits(ticks, idx) else {
            return false;
        };
        let mut data = [0u8; 8];
        let bytes = frame.data.as_slice();
        match (data.get_mut(..bytes.len()), u8::try_from(bytes.len())) {
            (Some(d), Ok(len)) if len == frame.len => {
                d.copy_from_slice(bytes);
                self.inner.push(Inner {
                    idx: at,
                    len,
                    id: frame.id,
                    data,
                    time,
                });
            }
            _ => return false,
        }
        self.latest = Some(ticks);
        self.base += idx + 1;
        true
    }

    /// The time of the last frame folded or kept inside the run (the
    /// latest: times only go forward).
    pub fn latest(&self) -> Option<Timestamp> {
        self.latest.map(Ticks::timestamp)
    }

    /// [`Folds::latest`] as the line's ticks: the time of the line folded
    /// last, for a caller that times it without reading it again.
    #[inline]
    pub fn latest_ticks(&self) -> Option<Ticks> {
        self.latest
    }

    /// Line `idx` as kept, if a frame at `time` may follow the frames
    /// folded so far (times only go forward, with the same digits; a
    /// block's lines are far fewer than 2^32).
    #[inline]
    fn admits(&self, time: Ticks, idx: u64) -> Option<u32> {
        let in_order = self
            .latest
            .is_none_or(|l| time.value >= l.value && time.digits == l.digits);
        u32::try_from(self.base + idx).ok().filter(|_| in_order)
    }

    /// Folds a frame on standard `id` when its digits alone say it may:
    /// they repeat its fold's where they must, or they start a fold as
    /// digits the id's filter let through before did, under the rule it
    /// had then (`rule`, asked then, is the interest's now). The common
    /// case, a few dozen instructions; `false`, and nothing changed,
    /// otherwise: then [`Folds::add`] decides.
    #[inline]
    pub fn repeat(
        &mut self,
        id: u32,
        text: HexText,
        time: Ticks,
        idx: u64,
        rule: impl FnOnce() -> FoldRule,
    ) -> bool {
        let Some(idx) = self.admits(time, idx) else {
            return false;
        };
        let run = self.run;
        let Some(state) = self
            .slot
            .get(id as usize)
            .and_then(|&s| usize::from(s).checked_sub(1))
            .and_then(|i| self.ids.get_mut(i))
        else {
            return false;
        };
        if state.len != text.len {
            return false;
        }
        if state.run == run {
            if text.differs(state.text, state.text_mask) {
                return false;
            }
            let Some(f) = self.list.get_mut(state.fold as usize) else {
                return false;
            };
            f.push(text, time.value, idx);
        } else {
            if (state.rule.filter.is_some() && state.passed != Some(text)) || rule() != state.rule {
                return false;
            }
            state.start(run, &mut self.list, id, text, time, idx);
        }
        self.kept(id, text, time, idx)
    }

    /// Folds a frame on standard `id` with `data` (its [`Payload::word`](super::Payload::word))
    /// and `text` at `time`, line `idx` of the run, which passed `rule`'s
    /// filter if it has one; `rule` is asked when the id's fold starts.
    /// `false` when it cannot be (other data than its id's fold under the
    /// rule's mask, a time before the last one folded or of other digits):
    /// the caller hands it over. Not inlined: in a reader's hot loop that
    /// cost every line there ~50 instructions (callgrind, a trace of plain
    /// lines; the loop's code got worse).
    #[inline(never)]
    pub fn add(
        &mut self,
        id: u32,
        data: u64,
        text: HexText,
        time: Ticks,
        idx: u64,
        rule: impl FnOnce() -> FoldRule,
    ) -> bool {
        let Some(idx) = self.admits(time, idx) else {
            return false;
        };
        let Some(slot) = self.slot.get_mut(id as usize) else {
            return false;
        };
        if *slot == 0 {
            // At most 2048: one per slot.
            self.ids.push(IdState {
                fold: 0,
                run: self.run.wrapping_sub(1),
                rule: FoldRule {
                    mask: 0,
                    filter: None,
                },
                text: [0; 2],
                len: u8::MAX,
                text_mask: [0; 2],
                passed: None,
            });
            *slot = self.ids.len() as u16;
        }
        let Some(state) = self.ids.get_mut(usize::from(*slot) - 1) else {
            return false;
        };
        if state.run == self.run {
            let Some(f) = self.list.get_mut(state.fold as usize) else {
                return false;
            };
            if state.len != text.len || (data ^ f.data()) & state.rule.mask != 0 {
                return false;
            }
            f.push(text, time.value, idx);
        } else {
            let rule = rule();
            if rule != state.rule || text.len != state.len {
                let mask = if rule.filter.is_some() {
                    u64::MAX
                } else {
                    rule.mask
                };
                state.text_mask = text.mask(mask);
                state.rule = rule;
                state.len = text.len;
            }
            state.start(self.run, &mut self.list, id, text, time, idx);
        }
        if state.rule.filter.is_some() {
            state.passed = Some(text);
        }
        self.kept(id, text, time, idx)
    }

    /// A frame folded: it is the latest, and kept.
    #[inline]
    fn kept(&mut self, id: u32, text: HexText, time: Ticks, idx: u32) -> bool {
        self.latest = Some(time);
        self.frames.push(Folded::new(id, text, time, idx));
        true
    }

    /// Whether a frame was folded in the current run.
    #[inline]
    pub fn any(&self) -> bool {
        self.latest.is_some()
    }
}

impl IdState {
    /// The id's fold in `run` starts with a frame of `text` at `time`, on
    /// line `idx`, as the next of `list`.
    #[inline]
    fn start(
        &mut self,
        run: u32,
        list: &mut Vec<Fold>,
        id: u32,
        text: HexText,
        time: Ticks,
        idx: u32,
    ) {
        self.run = run;
        self.fold = list.len() as u32;
        self.text = text.words;
        list.push(Fold::new(id, text, time, idx));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DataHead;
    use proptest::prelude::*;

    fn t(ms: u64) -> Ticks {
        Ticks {
            value: ms,
            digits: 3,
        }
    }

    fn ts(ms: u64) -> Timestamp {
        Timestamp::from_parts(ms / 1000, ms % 1000, 3)
    }

    /// The digits of `hex` as a line ending in them has them.
    fn text(hex: &str) -> HexText {
        let line = format!("(1.000) can0 701#{hex}");
        HexText::of(line.as_bytes(), line.len() - hex.len(), line.len()).unwrap()
    }

    fn all() -> FoldRule {
        FoldRule {
            mask: u64::MAX,
            filter: None,
        }
    }

    fn masked(mask: u64) -> impl Fn() -> FoldRule {
        move || FoldRule { mask, filter: None }
    }

    fn up_to_one_byte(_: u32, data: DataHead) -> bool {
        data.len() <= 1
    }

    fn filtered() -> FoldRule {
        FoldRule {
            mask: u64::MAX,
            filter: Some(ContentFilter(up_to_one_byte)),
        }
    }

    /// What a reader does with a frame: the digits first, then the data.
    fn fold(
        f: &mut Folds,
        id: u32,
        hex: &str,
        ms: u64,
        idx: u64,
        rule: impl Fn() -> FoldRule,
    ) -> bool {
        let x = text(hex);
        f.repeat(id, x, t(ms), idx, &rule) || f.add(id, x.word(), x, t(ms), idx, &rule)
    }

    #[test]
    fn digits_read_as_their_bytes() {
        assert_eq!(text("05").word(), 5);
        assert_eq!(text("05").bytes(), 1);
        assert_eq!(text("").word(), 0);
        assert_eq!(text("3706FFFF0000a0b1").word(), 0xB1A0_0000_FFFF_0637);
        assert_eq!(text("3706FFFF0000a0b1").bytes(), 8);
        let short = b"#05";
        assert_eq!(HexText::of(short, 1, 3), None, "fewer than 16 bytes");
        assert_eq!(HexText::of(b"0123456789ABCDEF0", 0, 17), None, "17 digits");
    }

    #[test]
    fn digit_masks_cover_the_nibbles_of_the_bits() {
        let x = text("3706FFFF");
        assert_eq!(x.mask(0x00EF), [0xFFFF, 0]);
        assert_eq!(x.mask(0x0010), [0xFF, 0]);
        assert_eq!(x.mask(0x0100), [0xFF << 24, 0]);
        assert_eq!(x.mask(u64::MAX), [u64::MAX, 0], "only the frame's digits");
        assert_eq!(text("0011223344556677").mask(u64::MAX), [u64::MAX; 2]);
        assert_eq!(text("0011223344556677").mask(0xFF << 40), [0, 0xFFFF << 16]);
    }

    #[test]
    fn repeats_of_an_id_fold_with_their_largest_gap() {
        let mut f = Folds::default();
        assert!(fold(&mut f, 0x705, "05", 100, 0, all));
        assert!(fold(&mut f, 0x706, "05", 150, 3, all));
        assert!(fold(&mut f, 0x705, "05", 200, 7, all));
        assert!(fold(&mut f, 0x705, "05", 450, 9, all));
        let folds = f.as_slice();
        assert_eq!(folds.len(), 2);
        let a = folds[0];
        assert_eq!(
            (a.id, a.count(), a.first(), a.last(), a.last_idx()),
            (0x705, 3, ts(100), ts(450), 9)
        );
        assert_eq!((a.data(), a.last_data(), a.len()), (5, 5, 1));
        assert_eq!(a.max_gap(), 250 * 1_000_000_000_000_000);
        assert_eq!((folds[1].count(), folds[1].max_gap()), (1, 0));
        assert_eq!(f.latest(), Some(ts(450)));
        let frames: Vec<_> = f
            .frames()
            .iter()
            .map(|x| (x.idx(), x.id(), x.time(), x.data(), x.len()))
            .collect();
        assert_eq!(
            frames,
            [
                (0, 0x705, ts(100), 5, 1),
                (3, 0x706, ts(150), 5, 1),
                (7, 0x705, ts(200), 5, 1),
                (9, 0x705, ts(450), 5, 1)
            ]
        );
    }

    /// An EMCY-like frame at `ms` on `id` with `data`.
    fn frame(id: u32, ms: u64, data: &[u8]) -> Frame<'static> {
        let mut bytes = [0u8; 8];
        bytes[..data.len()].copy_from_slice(data);
        Frame {
            time: Some(ts(ms)),
            channel: b"can0",
            id,
            extended: false,
            kind: FrameKind::Data,
            len: data.len() as u8,
            data: Payload::inline(bytes, data.len() as u8),
        }
    }

    #[test]
    fn frames_kept_inside_a_run_keep_its_times_and_lines_in_order() {
        let mut f = Folds::default();
        let emcy = frame(0x85, 120, &[0x10, 0x43, 0x09]);
        assert!(!f.keep_inside(&emcy, 0), "no folds: the frame ends the run");
        assert!(fold(&mut f, 0x705, "05", 100, 2, all));
        assert!(f.keep_inside(&emcy, 4), "line 4 of the run, at 120 ms");
        // The reader's next stretch counts its lines from 0 again.
        assert!(!fold(&mut f, 0x705, "05", 110, 1, all), "before the frame");
        assert!(fold(&mut f, 0x705, "05", 200, 1, all));
        assert_eq!(f.latest(), Some(ts(200)));
        assert!(
            !f.keep_inside(&frame(0x85, 150, &[0; 8]), 3),
            "before the fold"
        );
        let mut remote = frame(0x85, 250, &[]);
        remote.kind = FrameKind::Remote;
        assert!(!f.keep_inside(&remote, 3), "not a data frame");
        let mut extended = frame(0x85, 250, &[]);
        extended.extended = true;
        assert!(!f.keep_inside(&extended, 3), "an extended id");
        assert!(f.keep_inside(&frame(0x86, 250, &[]), 3), "no data: kept");
        assert_eq!(f.latest(), Some(ts(250)));
        let inner: Vec<_> = f
            .inner()
            .iter()
            .map(|i| (i.idx(), i.id(), i.frame(b"can0")))
            .collect();
        assert_eq!(
            inner,
            [(4, 0x85, emcy), (8, 0x86, frame(0x86, 250, &[]))],
            "lines 4 and 5 + 3 of the run"
        );
        assert_eq!(f.as_slice()[0].last_idx(), 6, "5 + 1");
        // The next run starts counting anew, its kept frames alone.
        f.next_run();
        assert!(f.inner().is_empty());
        assert!(fold(&mut f, 0x705, "05", 300, 2, all));
        assert_eq!(f.as_slice()[0].last_idx(), 2);
    }

    #[test]
    fn gaps_across_seconds_are_exact() {
        let mut f = Folds::default();
        assert!(fold(&mut f, 0x705, "05", 900, 0, all));
        assert!(fold(&mut f, 0x705, "05", 1_050, 1, all));
        assert!(fold(&mut f, 0x705, "05", 3_000, 2, all));
        assert_eq!(f.as_slice()[0].max_gap(), 1_950 * 1_000_000_000_000_000);
    }

    #[test]
    fn other_data_and_earlier_times_are_refused() {
        let mut f = Folds::default();
        assert!(fold(&mut f, 0x705, "05", 100, 0, all));
        assert!(!fold(&mut f, 0x705, "7F", 200, 1, all), "other state");
        assert!(!fold(&mut f, 0x705, "0500", 200, 1, all), "other length");
        assert!(!fold(&mut f, 0x706, "05", 50, 1, all), "backwards");
        let micro = Ticks {
            value: 300_000,
            digits: 6,
        };
        let x = text("05");
        assert!(!f.repeat(0x705, x, micro, 1, all), "other digits");
        assert!(!f.add(0x705, 5, x, micro, 1, all), "other digits");
        assert_eq!(f.as_slice().len(), 1);
        assert_eq!(f.as_slice()[0].count(), 1);
        assert_eq!(f.frames().len(), 1, "refused frames are not kept");
    }

    #[test]
    fn only_the_bits_that_matter_must_repeat() {
        let mut f = Folds::default();
        let low_byte = masked(0xFF);
        assert!(fold(&mut f, 0x185, "37063412", 1, 0, &low_byte));
        let x = text("37129999");
        assert!(
            f.repeat(0x185, x, t(2), 1, &low_byte),
            "position, bit 12: the digits tell"
        );
        let y = text("37069999");
        assert!(
            !f.repeat(0x185, text("38069999"), t(3), 2, &low_byte),
            "state bits differ"
        );
        assert!(
            fold(&mut f, 0x205, "0F", 3, 2, &low_byte),
            "another id, its own fold"
        );
        assert!(f.repeat(0x185, y, t(4), 3, &low_byte));
        assert!(
            !fold(&mut f, 0x185, "38069999", 5, 4, &low_byte),
            "state bits"
        );
        let fold185 = f.as_slice()[0];
        assert_eq!(fold185.count(), 3);
        assert_eq!(fold185.data(), 0x1234_0637, "the first frame's data");
        assert_eq!(fold185.last_data(), 0x9999_0637, "and the last's");
    }

    #[test]
    fn digits_that_differ_in_case_are_told_by_their_bits() {
        let mut f = Folds::default();
        assert!(fold(&mut f, 0x185, "0A", 1, 0, all));
        assert!(!f.repeat(0x185, text("0a"), t(2), 1, all), "other digits");
        assert!(f.add(0x185, 0x0A, text("0a"), t(2), 1, all), "same bits");
        assert_eq!(f.as_slice()[0].count(), 2);
    }

    #[test]
    fn a_later_run_starts_folds_from_what_the_id_had() {
        let mut f = Folds::default();
        assert!(fold(&mut f, 0x705, "05", 100, 0, filtered));
        assert!(fold(&mut f, 0x706, "05", 110, 1, all));
        f.next_run();
        assert!(f.as_slice().is_empty() && f.frames().is_empty());
        assert_eq!(f.latest(), None);
        assert!(
            f.repeat(0x705, text("05"), t(200), 0, filtered),
            "digits the filter let through"
        );
        assert!(
            !f.repeat(0x705, text("7F"), t(210), 1, filtered),
            "other digits of a filtered id ask the filter"
        );
        assert!(
            f.repeat(0x706, text("7F"), t(220), 2, all),
            "no filter: any digits start a fold"
        );
        assert!(
            !f.repeat(0x707, text("05"), t(230), 3, all),
            "an id never folded before"
        );
        f.next_run();
        assert!(
            !f.repeat(0x706, text("7F"), t(300), 0, masked(0xFF)),
            "the interest's rule changed"
        );
        assert!(fold(&mut f, 0x706, "7F", 300, 0, masked(0xFF)));
        assert_eq!(f.as_slice()[0].first(), ts(300));
    }

    #[test]
    fn every_id_can_fold() {
        let mut f = Folds::default();
        for id in 0..2048 {
            assert!(fold(&mut f, id, "05", u64::from(id), 0, all));
        }
        assert_eq!(f.as_slice().len(), 2048);
        f.next_run();
        assert!(
            fold(&mut f, 0x701, "04", 3000, 0, all),
            "a fresh fold, other data"
        );
        assert_eq!(f.as_slice()[0].count(), 1);
    }

    proptest! {
        /// Trying the digits first never changes what folds: the same
        /// frames through `add` alone give the same folds.
        #[test]
        fn digits_first_fold_as_data_alone(
            frames in prop::collection::vec(
                (0x700u32..0x704, prop::sample::select(vec!["05", "7F", "7f", "0500", "", "0A", "0a"]), 0u64..30, any::<bool>()),
                0..60,
            ),
            mask in prop::sample::select(vec![u64::MAX, 0xFF, 0x0F, 0xF0]),
            with_filter in any::<bool>(),
        ) {
            let rule = move || FoldRule {
                mask,
                filter: with_filter.then_some(ContentFilter(up_to_one_byte)),
            };
            let (mut fast, mut slow) = (Folds::default(), Folds::default());
            let mut ms = 0;
            for (idx, (id, hex, step, end_run)) in frames.into_iter().enumerate() {
                ms += step;
                let x = text(hex);
                let passes = !with_filter || x.bytes() <= 1;
                let idx = idx as u64;
                let a = fast.repeat(id, x, t(ms), idx, rule)
                    || (passes && fast.add(id, x.word(), x, t(ms), idx, rule));
                let b = passes && slow.add(id, x.word(), x, t(ms), idx, rule);
                prop_assert_eq!(a, b);
                let view = |f: &Folds| {
                    f.as_slice()
                        .iter()
                        .map(|x| (x.id, x.count(), x.first(), x.last(), x.max_gap(), x.data(), x.last_data(), x.len(), x.last_idx()))
                        .collect::<Vec<_>>()
                };
                prop_assert_eq!(view(&fast), view(&slow));
                let frames = |f: &Folds| {
                    f.frames()
                        .iter()
                        .map(|x| (x.idx(), x.id(), x.time(), x.data(), x.len()))
                        .collect::<Vec<_>>()
                };
                prop_assert_eq!(frames(&fast), frames(&slow));
                if end_run {
                    fast.next_run();
                    slow.next_run();
                }
            }
        }
    }
}
