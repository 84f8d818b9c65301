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

use super::Timestamp;

/// The frames of one id folded in a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fold {
    pub id: u32,
    /// The data of the fold's first frame, as [`Payload::word`](super::Payload::word) gives it;
    /// every frame of the fold had the same bits under `mask`.
    pub data: u64,
    /// The data of its last frame.
    pub last_data: u64,
    pub mask: u64,
    pub len: u8,
    pub count: u64,
    pub first: Timestamp,
    pub last: Timestamp,
    /// The last frame's line, as an index into the run's lines.
    pub last_idx: u64,
    /// The largest time between two frames of the fold, in attoseconds
    /// (0 for one frame).
    pub max_gap: i128,
}

/// One frame of a fold, kept so that a consumer refusing the folds can
/// take the frames one by one without reading the lines again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Folded {
    /// The frame's line, as an index into the run's lines.
    pub idx: u64,
    pub time: Timestamp,
    pub id: u32,
    /// As [`Payload::word`](super::Payload::word) gives it.
    pub data: u64,
    pub len: u8,
}

/// The folds of one run, at most one per (standard) id.
#[derive(Clone, Debug)]
pub struct Folds {
    list: Vec<Fold>,
    /// Every frame folded, in line order.
    frames: Vec<Folded>,
    /// Index + 1 into `list` by id; 0: none.
    slot: Box<[u16; 2048]>,
    /// The time of the last frame folded: times only go forward in a fold
    /// (the consumer's checks of the folds rely on it).
    latest: Option<Timestamp>,
}

impl Default for Folds {
    fn default() -> Self {
        Folds {
            list: Vec::new(),
            frames: Vec::new(),
            slot: Box::new([0; 2048]),
            latest: None,
        }
    }
}

impl Folds {
    /// Empties them for the next run.
    #[inline]
    pub fn clear(&mut self) {
        if self.latest.is_none() {
            return;
        }
        for f in &self.list {
            if let Some(s) = self.slot.get_mut(f.id as usize) {
                *s = 0;
            }
        }
        self.list.clear();
        self.frames.clear();
        self.latest = None;
    }

    pub fn as_slice(&self) -> &[Fold] {
        &self.list
    }

    /// Every frame folded, in line order.
    pub fn frames(&self) -> &[Folded] {
        &self.frames
    }

    /// The time of the last frame folded (the latest: times only go
    /// forward).
    pub fn latest(&self) -> Option<Timestamp> {
        self.latest
    }

    /// Folds a frame on standard `id` with `data` (a [`Payload::word`](super::Payload::word), `len`
    /// bytes) at `time`, line `idx` of the run; `mask` gives the bits that
    /// matter on the id (asked for its first frame in the run). `false`
    /// when it cannot be (other data than its id's fold under the mask, a
    /// time before the last one folded): the caller hands it over. Not
    /// inlined: in a reader's hot loop that cost every line there ~50
    /// instructions (callgrind, a trace of plain lines; the loop's code got
    /// worse).
    #[inline(never)]
    pub fn add(
        &mut self,
        id: u32,
        data: u64,
        len: u8,
        time: Timestamp,
        idx: u64,
        mask: impl FnOnce() -> u64,
    ) -> bool {
        if self.latest.is_some_and(|l| time < l) {
            return false;
        }
        let Some(slot) = self.slot.get_mut(id as usize) else {
            return false;
        };
        if *slot == 0 {
            // At most 2048 folds: one per slot.
            self.list.push(Fold {
                id,
                data,
                last_data: data,
                mask: mask(),
                len,
                count: 1,
                first: time,
                last: time,
                last_idx: idx,
                max_gap: 0,
            });
            *slot = self.list.len() as u16;
        } else {
            let Some(f) = self.list.get_mut(usize::from(*slot) - 1) else {
                return false;
            };
            if f.len != len || (f.data ^ data) & f.mask != 0 {
                return false;
            }
            let (s, a, _) = time.to_raw();
            let (ls, la, _) = f.last.to_raw();
            // Whole seconds first: a heartbeat gap under a second needs no
            // 128-bit product.
            let gap = if s == ls {
                i128::from(a) - i128::from(la)
            } else {
                (i128::from(s) - i128::from(ls)) * 1_000_000_000_000_000_000
                    + (i128::from(a) - i128::from(la))
            };
            f.max_gap = f.max_gap.max(gap);
            f.count += 1;
            f.last_data = data;
            f.last = time;
            f.last_idx = idx;
        }
        self.latest = Some(time);
        self.frames.push(Folded {
            idx,
            time,
            id,
            data,
            len,
        });
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(ms: u64) -> Timestamp {
        Timestamp::from_parts(ms / 1000, ms % 1000, 3)
    }

    fn all() -> u64 {
        u64::MAX
    }

    #[test]
    fn repeats_of_an_id_fold_with_their_largest_gap() {
        let mut f = Folds::default();
        assert!(f.add(0x705, 5, 1, t(100), 0, all));
        assert!(f.add(0x706, 5, 1, t(150), 3, all));
        assert!(f.add(0x705, 5, 1, t(200), 7, all));
        assert!(f.add(0x705, 5, 1, t(450), 9, all));
        let folds = f.as_slice();
        assert_eq!(folds.len(), 2);
        let a = folds[0];
        assert_eq!(
            (a.id, a.count, a.first, a.last, a.last_idx),
            (0x705, 3, t(100), t(450), 9)
        );
        assert_eq!(a.max_gap, 250 * 1_000_000_000_000_000);
        assert_eq!((folds[1].count, folds[1].max_gap), (1, 0));
        assert_eq!(f.latest(), Some(t(450)));
        let lines: Vec<(u64, u32)> = f.frames().iter().map(|x| (x.idx, x.id)).collect();
        assert_eq!(lines, [(0, 0x705), (3, 0x706), (7, 0x705), (9, 0x705)]);
    }

    #[test]
    fn gaps_across_seconds_are_exact() {
        let mut f = Folds::default();
        assert!(f.add(0x705, 5, 1, t(900), 0, all));
        assert!(f.add(0x705, 5, 1, t(1_050), 1, all));
        assert!(f.add(0x705, 5, 1, t(3_000), 2, all));
        assert_eq!(f.as_slice()[0].max_gap, 1_950 * 1_000_000_000_000_000);
    }

    #[test]
    fn other_data_and_earlier_times_are_refused() {
        let mut f = Folds::default();
        assert!(f.add(0x705, 5, 1, t(100), 0, all));
        assert!(!f.add(0x705, 0x7F, 1, t(200), 1, all), "other state");
        assert!(!f.add(0x705, 5, 2, t(200), 1, all), "other length");
        assert!(!f.add(0x706, 5, 1, t(50), 1, all), "backwards");
        assert_eq!(f.as_slice().len(), 1);
        assert_eq!(f.as_slice()[0].count, 1);
        assert_eq!(f.frames().len(), 1, "refused frames are not kept");
    }

    #[test]
    fn only_the_bits_that_matter_must_repeat() {
        let mut f = Folds::default();
        let low_byte = || 0xFF;
        assert!(f.add(0x185, 0x1234_0637, 4, t(1), 0, low_byte));
        assert!(
            f.add(0x185, 0x9999_1237, 4, t(2), 1, low_byte),
            "position, bit 12"
        );
        assert!(
            !f.add(0x185, 0x1234_0638, 4, t(3), 2, low_byte),
            "state bits"
        );
        assert!(
            f.add(0x205, 0x0F, 2, t(3), 2, low_byte),
            "another id, its own fold"
        );
        assert_eq!(f.as_slice()[0].count, 2);
        assert_eq!(f.as_slice()[0].data, 0x1234_0637, "the first frame's data");
        assert_eq!(f.as_slice()[0].last_data, 0x9999_1237, "and the last's");
    }

    #[test]
    fn clear_empties_every_slot() {
        let mut f = Folds::default();
        for id in 0..2048 {
            assert!(f.add(id, 5, 1, t(u64::from(id)), 0, all));
        }
        f.clear();
        assert!(f.as_slice().is_empty() && f.frames().is_empty());
        assert_eq!(f.latest(), None);
        assert!(f.add(0x701, 4, 1, t(1), 0, all), "a fresh fold, other data");
        assert_eq!(f.as_slice()[0].count, 1);
    }
}
