//! Read-outs of object 0x1003, the pre-defined error field: a node's last
//! few error codes, newest in sub 1, read by SDO.
//!
//! A read-out is the uploads of sub 0 (the count) and subs 1..=count: it is
//! complete once every sub up to the count was read. A read of sub 0, or of
//! a sub read already, begins a new read-out and ends the one before as
//! partial; so does the end of the input. A read of 0 entries is a
//! complete, empty read-out. A confirmed write of 0 to sub 0 clears the
//! history.

use super::interval::At;

/// The subs a read-out may hold (sub 0 is UNSIGNED8, 255 is reserved).
pub const MAX_ENTRIES: u8 = 254;

/// One entry: sub n holds a 32-bit value, the error code in the low 16
/// bits, manufacturer information in the high 16.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HistoryEntry {
    pub sub: u8,
    pub code: u16,
    pub info: u16,
    /// The trace never saw the node raise the code (set by the caller, who
    /// knows the node's errors).
    pub before_trace: bool,
}

impl HistoryEntry {
    pub fn of(sub: u8, value: u32) -> HistoryEntry {
        HistoryEntry {
            sub,
            code: (value & 0xFFFF) as u16,
            info: (value >> 16) as u16,
            before_trace: false,
        }
    }
}

/// One read-out of the history.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadOut {
    /// Newest first (ascending sub).
    pub entries: Vec<HistoryEntry>,
    /// The count sub 0 gave, if it was read.
    pub count: Option<u8>,
    /// Every sub from 1 to the count was read.
    pub complete: bool,
    /// The last frame of the read-out.
    pub at: At,
}

#[derive(Clone, Debug)]
struct Partial {
    count: Option<u8>,
    entries: Vec<HistoryEntry>,
    at: At,
}

impl Partial {
    fn into_read_out(self, complete: bool) -> ReadOut {
        ReadOut {
            entries: self.entries,
            count: self.count,
            complete,
            at: self.at,
        }
    }
}

/// Assembles a node's read-outs.
#[derive(Clone, Debug, Default)]
pub struct HistoryReader {
    pending: Option<Partial>,
}

impl HistoryReader {
    /// Sub 0 was read: `value` entries. The read-out before ends (partial).
    pub fn count(&mut self, value: u32, at: At, done: &mut Vec<ReadOut>) {
        self.flush(done);
        let count = u8::try_from(value).unwrap_or(u8::MAX).min(MAX_ENTRIES);
        let partial = Partial {
            count: Some(count),
            entries: Vec::new(),
            at,
        };
        if count == 0 {
            done.push(partial.into_read_out(true));
        } else {
            self.pending = Some(partial);
        }
    }

    /// Sub `sub` (1 or more) was read as `value`.
    pub fn entry(&mut self, sub: u8, value: u32, at: At, done: &mut Vec<ReadOut>) {
        if sub == 0 || sub > MAX_ENTRIES {
            return;
        }
        if self
            .pending
            .as_ref()
            .is_some_and(|p| p.entries.iter().any(|e| e.sub == sub))
        {
            self.flush(done);
        }
        let p = self.pending.get_or_insert(Partial {
            count: None,
            entries: Vec::new(),
            at,
        });
        if p.count.is_some_and(|c| sub > c) {
            // Past the count: not part of the history.
            return;
        }
        p.at = at;
        let i = p.entries.partition_point(|e| e.sub < sub);
        p.entries.insert(i, HistoryEntry::of(sub, value));
        if let Some(count) = p.count
            && p.entries.len() == usize::from(count)
            && let Some(p) = self.pending.take()
        {
            done.push(p.into_read_out(true));
        }
    }

    /// The history was cleared; a read-out going on ends (partial).
    pub fn cleared(&mut self, done: &mut Vec<ReadOut>) {
        self.flush(done);
    }

    /// Whether a read-out is going on.
    pub fn is_reading(&self) -> bool {
        self.pending.is_some()
    }

    /// The read-out going on ends as partial (a new one begins, the input ends).
    pub fn flush(&mut self, done: &mut Vec<ReadOut>) {
        if let Some(p) = self.pending.take() {
            done.push(p.into_read_out(false));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(line: u64) -> At {
        At { time: None, line }
    }

    #[test]
    fn entry_splits_code_and_info() {
        assert_eq!(
            HistoryEntry::of(1, 0x0012_4310),
            HistoryEntry {
                sub: 1,
                code: 0x4310,
                info: 0x0012,
                before_trace: false,
            }
        );
    }

    #[test]
    fn complete_read_out() {
        let mut r = HistoryReader::default();
        let mut done = Vec::new();
        r.count(2, at(1), &mut done);
        assert!(done.is_empty());
        r.entry(1, 0x4310, at(2), &mut done);
        assert!(done.is_empty());
        r.entry(2, 0x0001_3120, at(3), &mut done);
        assert_eq!(
            done,
            [ReadOut {
                entries: vec![
                    HistoryEntry::of(1, 0x4310),
                    HistoryEntry::of(2, 0x0001_3120)
                ],
                count: Some(2),
                complete: true,
                at: at(3)
            }]
        );
        // Nothing left to flush.
        r.flush(&mut done);
        assert_eq!(done.len(), 1);
    }

    #[test]
    fn entries_in_any_order_newest_first() {
        let mut r = HistoryReader::default();
        let mut done = Vec::new();
        r.count(3, at(1), &mut done);
        r.entry(3, 3, at(2), &mut done);
        r.entry(1, 1, at(3), &mut done);
        r.entry(2, 2, at(4), &mut done);
        let subs: Vec<u8> = done[0].entries.iter().map(|e| e.sub).collect();
        assert_eq!(subs, [1, 2, 3]);
        assert!(done[0].complete);
    }

    #[test]
    fn empty_history_is_complete_at_once() {
        let mut r = HistoryReader::default();
        let mut done = Vec::new();
        r.count(0, at(7), &mut done);
        assert_eq!(done.len(), 1);
        assert!(done[0].complete);
        assert!(done[0].entries.is_empty());
    }

    #[test]
    fn interrupted_read_out_is_partial() {
        let mut r = HistoryReader::default();
        let mut done = Vec::new();
        r.count(3, at(1), &mut done);
        r.entry(1, 0x4310, at(2), &mut done);
        r.count(1, at(3), &mut done);
        assert_eq!(done.len(), 1);
        assert!(!done[0].complete);
        assert_eq!(done[0].count, Some(3));
        assert_eq!(done[0].at, at(2));
        r.entry(1, 0x5000, at(4), &mut done);
        assert_eq!(done.len(), 2);
        assert!(done[1].complete);
    }

    #[test]
    fn entries_without_the_count_are_partial() {
        let mut r = HistoryReader::default();
        let mut done = Vec::new();
        r.entry(1, 0x4310, at(1), &mut done);
        r.entry(2, 0x3120, at(2), &mut done);
        assert!(done.is_empty());
        // A re-read of sub 1 starts again.
        r.entry(1, 0x4310, at(3), &mut done);
        assert_eq!(done.len(), 1);
        assert!(!done[0].complete);
        assert_eq!(done[0].count, None);
        assert_eq!(done[0].entries.len(), 2);
        r.flush(&mut done);
        assert_eq!(done.len(), 2);
        assert_eq!(done[1].entries.len(), 1);
    }

    #[test]
    fn subs_past_the_count_are_not_history() {
        let mut r = HistoryReader::default();
        let mut done = Vec::new();
        r.count(1, at(1), &mut done);
        r.entry(5, 0x1000, at(2), &mut done);
        r.entry(0, 0x1000, at(2), &mut done);
        r.entry(255, 0x1000, at(2), &mut done);
        assert!(done.is_empty());
        r.entry(1, 0x2000, at(3), &mut done);
        assert_eq!(done[0].entries, [HistoryEntry::of(1, 0x2000)]);
    }

    #[test]
    fn huge_count_is_capped() {
        let mut r = HistoryReader::default();
        let mut done = Vec::new();
        r.count(100_000, at(1), &mut done);
        r.flush(&mut done);
        assert_eq!(done[0].count, Some(MAX_ENTRIES));
    }

    #[test]
    fn clear_ends_a_read_out() {
        let mut r = HistoryReader::default();
        let mut done = Vec::new();
        r.count(2, at(1), &mut done);
        r.entry(1, 1, at(2), &mut done);
        r.cleared(&mut done);
        assert_eq!(done.len(), 1);
        assert!(!done[0].complete);
        r.cleared(&mut done);
        assert_eq!(done.len(), 1);
    }

    proptest::proptest! {
        /// Any reads of sub 0 and subs: every read-out lists distinct subs
        /// in ascending order, within its count; a complete one has exactly
        /// the count's entries.
        #[test]
        fn read_outs_are_consistent(
            reads in proptest::collection::vec((0u8..8, 0u32..6), 0..40),
        ) {
            let mut r = HistoryReader::default();
            let mut done = Vec::new();
            for (i, (sub, value)) in reads.iter().enumerate() {
                if *sub == 0 {
                    r.count(*value, at(i as u64), &mut done);
                } else {
                    r.entry(*sub, *value, at(i as u64), &mut done);
                }
            }
            r.flush(&mut done);
            for ro in &done {
                let subs: Vec<u8> = ro.entries.iter().map(|e| e.sub).collect();
                proptest::prop_assert!(subs.windows(2).all(|w| w[0] < w[1]), "{:?}", subs);
                if let Some(c) = ro.count {
                    proptest::prop_assert!(subs.iter().all(|s| *s >= 1 && *s <= c));
                }
                if ro.complete {
                    proptest::prop_assert_eq!(Some(ro.entries.len() as u8), ro.count);
                }
            }
        }
    }
}
