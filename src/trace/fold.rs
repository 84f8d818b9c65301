//! Frames a reader's hot loop folds instead of handing them over one by
//! one: on the ids the [`Interest`](super::Interest) marks foldable (NMT
//! error control, 0x700 + node), a frame whose data repeats the one before
//! it on its id in the same run. A node heartbeating every 100 ms on a busy
//! bus sends one such frame every few hundred lines, and each used to end
//! the hot loop, be built, recorded and replayed on its own (about 830
//! instructions a heartbeat, measured in docs/performance.md). A fold keeps
//! what the consumer needs to take them all at once, or to tell it cannot
//! (then the lines are read again one at a time, so the result never
//! depends on folding): how many, the first and last time, the last line,
//! and the largest gap between two of them.

use super::Timestamp;

/// The frames of one id folded in a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fold {
    pub id: u32,
    /// The data every frame of the fold carried, as [`Payload::word`](super::Payload::word) gives it.
    pub data: u64,
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

/// The folds of one run, at most one per id; ids are looked up by their
/// low 7 bits (every foldable id is 0x700 + node).
#[derive(Clone, Debug)]
pub struct Folds {
    list: Vec<Fold>,
    /// Index + 1 into `list` by the id's low 7 bits; 0: none.
    slot: [u8; 128],
    /// The time of the last frame folded: times only go forward in a fold
    /// (the consumer's checks of the folds rely on it).
    latest: Option<Timestamp>,
}

impl Default for Folds {
    fn default() -> Self {
        Folds {
            list: Vec::new(),
            slot: [0; 128],
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
            if let Some(s) = self.slot.get_mut((f.id & 0x7F) as usize) {
                *s = 0;
            }
        }
        self.list.clear();
        self.latest = None;
    }

    pub fn as_slice(&self) -> &[Fold] {
        &self.list
    }

    /// The time of the last frame folded (the latest: times only go
    /// forward).
    pub fn latest(&self) -> Option<Timestamp> {
        self.latest
    }

    /// Folds a frame on `id` with `data` (a [`Payload::word`](super::Payload::word), `len` bytes) at
    /// `time`, line `idx` of the run; `false` when it cannot be (other data
    /// than its id's fold, another id with the same low bits, a time
    /// before the last one folded): the caller hands it over. Not inlined:
    /// in a reader's hot loop that cost every line there ~50 instructions
    /// (callgrind, a trace of plain lines; the loop's code got worse).
    #[inline(never)]
    pub fn add(&mut self, id: u32, data: u64, len: u8, time: Timestamp, idx: u64) -> bool {
        if self.latest.is_some_and(|l| time < l) {
            return false;
        }
        let Some(slot) = self.slot.get_mut((id & 0x7F) as usize) else {
            return false;
        };
        if *slot == 0 {
            // At most 128 folds: one per slot.
            self.list.push(Fold {
                id,
                data,
                len,
                count: 1,
                first: time,
                last: time,
                last_idx: idx,
                max_gap: 0,
            });
            *slot = self.list.len() as u8;
        } else {
            let Some(f) = self.list.get_mut(usize::from(*slot) - 1) else {
                return false;
            };
            if f.id != id || f.len != len || f.data != data {
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
            f.last = time;
            f.last_idx = idx;
        }
        self.latest = Some(time);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(ms: u64) -> Timestamp {
        Timestamp::from_parts(ms / 1000, ms % 1000, 3)
    }

    #[test]
    fn repeats_of_an_id_fold_with_their_largest_gap() {
        let mut f = Folds::default();
        assert!(f.add(0x705, 5, 1, t(100), 0));
        assert!(f.add(0x706, 5, 1, t(150), 3));
        assert!(f.add(0x705, 5, 1, t(200), 7));
        assert!(f.add(0x705, 5, 1, t(450), 9));
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
    }

    #[test]
    fn gaps_across_seconds_are_exact() {
        let mut f = Folds::default();
        assert!(f.add(0x705, 5, 1, t(900), 0));
        assert!(f.add(0x705, 5, 1, t(1_050), 1));
        assert!(f.add(0x705, 5, 1, t(3_000), 2));
        assert_eq!(f.as_slice()[0].max_gap, 1_950 * 1_000_000_000_000_000);
    }

    #[test]
    fn other_data_other_ids_on_the_slot_and_earlier_times_are_refused() {
        let mut f = Folds::default();
        assert!(f.add(0x705, 5, 1, t(100), 0));
        assert!(!f.add(0x705, 0x7F, 1, t(200), 1), "other state");
        assert!(!f.add(0x705, 5, 2, t(200), 1), "other length");
        assert!(!f.add(0x785, 5, 1, t(200), 1), "same low bits");
        assert!(!f.add(0x706, 5, 1, t(50), 1), "backwards");
        assert_eq!(f.as_slice().len(), 1);
        assert_eq!(f.as_slice()[0].count, 1);
    }

    #[test]
    fn clear_empties_every_slot() {
        let mut f = Folds::default();
        for node in 1..=127 {
            assert!(f.add(0x700 + node, 5, 1, t(u64::from(node)), 0));
        }
        f.clear();
        assert!(f.as_slice().is_empty());
        assert_eq!(f.latest(), None);
        assert!(f.add(0x701, 4, 1, t(1), 0), "a fresh fold, other data");
        assert_eq!(f.as_slice()[0].count, 1);
    }
}
