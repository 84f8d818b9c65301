//! One node's error state machine (the rules are in the folder's notes).

use super::interval::{At, ClearedBy, Interval};
use super::{drive, health};
use crate::canopen::codes;
use crate::canopen::emcy::{Emcy, Warning};
use crate::canopen::register::Register;
use crate::trace::{Span, Timestamp};

/// A node's error state (CiA 301).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum State {
    /// No error active.
    #[default]
    ErrorFree,
    /// At least one error raised and not cleared.
    ErrorOccurred,
}

impl State {
    /// The stable name in JSON (`error_free`).
    pub fn slug(self) -> &'static str {
        match self {
            State::ErrorFree => "error_free",
            State::ErrorOccurred => "error_occurred",
        }
    }
}

/// What one EMCY did to its node.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Step {
    /// 1-4, or `None` for a reset that changed nothing.
    pub transition: Option<u8>,
    /// The node's state after it.
    pub state: State,
    /// Codes closed by this frame.
    pub cleared: Vec<u16>,
    /// The intervals it closed; the caller keeps the history (the timeline
    /// holds only what is active, so its memory is bounded by active errors).
    pub closed: Vec<Interval>,
}

/// The error state of one node.
#[derive(Clone, Debug, Default)]
pub struct NodeTimeline {
    state: State,
    /// Open intervals, in the order they were raised.
    active: Vec<Interval>,
    /// Only while [`INDEXED_FROM`] or more errors are active (a trace can
    /// leave thousands of codes active on a node; a scan per EMCY made that
    /// quadratic): where each active code is, and what a partial reset can
    /// close. Nodes with few active errors, nearly all of them, pay 8 bytes.
    index: Option<Box<ActiveIndex>>,
    next_seq: u64,
    emcy_count: u64,
    /// Allocated when there is something to count: a node that only ever
    /// booted has none. Boxed, so the report takes it without a copy.
    stats: Option<Box<NodeStats>>,
    /// NMT, heartbeats, error history: allocated for nodes that have any.
    health: Option<Box<health::NodeHealth>>,
}

/// From this many active errors on, a node keeps an [`ActiveIndex`]; below
/// it a scan of the active list is as fast and needs no memory.
const INDEXED_FROM: usize = 16;

/// The active errors of a node with many of them, by code.
#[derive(Clone, Debug, Default)]
struct ActiveIndex {
    /// Each active code's raise order (`Interval::seq`, ascending in
    /// `active`, so its position is a binary search away).
    seq_of: std::collections::BTreeMap<u16, u64>,
    /// Per error register bit, the active errors a partial reset without
    /// that bit would close (class bit set when raised): a reset that can
    /// close none is answered without a scan.
    closable: [u32; 8],
}

impl ActiveIndex {
    fn of(active: &[Interval]) -> Box<ActiveIndex> {
        let mut index = Box::<ActiveIndex>::default();
        for iv in active {
            index.add(iv);
        }
        index
    }

    fn add(&mut self, iv: &Interval) {
        self.seq_of.insert(iv.code, iv.seq);
        if let Some(n) = attributable_bit(iv).and_then(|b| self.closable.get_mut(usize::from(b))) {
            *n += 1;
        }
    }

    fn remove(&mut self, iv: &Interval) {
        self.seq_of.remove(&iv.code);
        if let Some(n) = attributable_bit(iv).and_then(|b| self.closable.get_mut(usize::from(b))) {
            *n = n.saturating_sub(1);
        }
    }

    /// Whether a partial reset with register `now` can close an error.
    fn partial_reset_closes_any(&self, now: Register) -> bool {
        (0u8..8).any(|bit| !now.has(bit) && self.closable.get(usize::from(bit)) != Some(&0))
    }
}

/// The register bit whose drop closes `iv` in a partial reset: its class's
/// bit, if it was set in the register it was raised with.
fn attributable_bit(iv: &Interval) -> Option<u8> {
    codes::lookup(iv.code)
        .class
        .register_bit()
        .filter(|&bit| iv.raised_register.has(bit))
}

/// Running totals for the summary view, kept as the trace goes (bounded
/// memory whatever its length).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct NodeStats {
    /// Errors raised, per code (a repeat of an active code is not a raise).
    pub raised: std::collections::BTreeMap<u16, u64>,
    pub first_emcy: Option<At>,
    pub last_emcy: Option<At>,
    /// Time spent in error-occurred, over periods that ended.
    pub time_in_error: Span,
    /// When the current error period began (the node is in error now).
    pub in_error_since: Option<Timestamp>,
    /// The longest error that ended: its code and duration.
    pub longest: Option<(u16, Span)>,
}

/// A node's timeline at the end of its input ([`NodeTimeline::into_end`]).
pub struct NodeEnd {
    pub state: State,
    pub emcy_count: u64,
    /// Still open, in the order they were raised.
    pub active: Vec<Interval>,
    pub stats: Box<NodeStats>,
    pub health: Option<Box<health::NodeHealth>>,
}

impl NodeTimeline {
    /// A node that has sent nothing yet: error-free.
    pub fn new() -> Self {
        Self::default()
    }

    /// The state now.
    pub fn state(&self) -> State {
        self.state
    }

    /// EMCY frames applied, resets included.
    pub fn emcy_count(&self) -> u64 {
        self.emcy_count
    }

    /// Running totals for the summary view (the program takes them with
    /// [`NodeTimeline::into_end`]).
    #[cfg(any(test, feature = "fuzzing"))]
    pub(crate) fn stats(&self) -> &NodeStats {
        static NONE_YET: std::sync::LazyLock<NodeStats> =
            std::sync::LazyLock::new(NodeStats::default);
        self.stats.as_deref().unwrap_or(&NONE_YET)
    }

    /// The last EMCY frame the node sent (a sign of life, as a heartbeat is).
    pub fn last_emcy(&self) -> Option<At> {
        self.stats.as_ref().and_then(|s| s.last_emcy)
    }

    fn stats_mut(&mut self) -> &mut NodeStats {
        self.stats.get_or_insert_with(Box::default)
    }

    /// Bookkeeping after every frame: counts, first/last EMCY, time in error,
    /// longest error.
    fn account(&mut self, was: State, at: At, emcy: bool, closed: &[Interval]) {
        if !emcy && closed.is_empty() && was == self.state {
            return;
        }
        let state = self.state;
        let st = self.stats_mut();
        if emcy {
            st.first_emcy.get_or_insert(at);
            st.last_emcy = Some(at);
        }
        for iv in closed {
            if let (Some(start), Some(end)) = (iv.start.time, iv.end.and_then(|e| e.time)) {
                let d = end.since(start);
                if st.longest.is_none_or(|(_, l)| d > l) {
                    st.longest = Some((iv.code, d));
                }
            }
        }
        match (was, state) {
            (State::ErrorFree, State::ErrorOccurred) => st.in_error_since = at.time,
            (State::ErrorOccurred, State::ErrorFree) => {
                if let (Some(since), Some(now)) = (st.in_error_since.take(), at.time) {
                    st.time_in_error = st
                        .time_in_error
                        .checked_add(now.since(since))
                        .unwrap_or(st.time_in_error);
                }
            }
            _ => {}
        }
    }

    /// What is left of the node at the end of its input, taken apart
    /// (nothing copied: a trace can end with a million nodes).
    pub(crate) fn into_end(self) -> NodeEnd {
        NodeEnd {
            state: self.state,
            emcy_count: self.emcy_count,
            active: self.active,
            stats: self.stats.unwrap_or_default(),
            health: self.health,
        }
    }

    /// The node's NMT, heartbeat and error history side, if it has one.
    pub(crate) fn health(&self) -> Option<&health::NodeHealth> {
        self.health.as_deref()
    }

    /// The node's NMT, heartbeat and error history side to change, if it
    /// has one.
    #[inline]
    pub(crate) fn health_if_any(&mut self) -> Option<&mut health::NodeHealth> {
        self.health.as_deref_mut()
    }

    /// The node's NMT, heartbeat and error history side, made on first use
    /// with `timeout` (`--heartbeat-timeout`).
    pub(crate) fn health_mut(&mut self, timeout: Option<Span>) -> &mut health::NodeHealth {
        self.health
            .get_or_insert_with(|| Box::new(health::NodeHealth::new(timeout)))
    }

    /// The node's CiA 402 drive, if a word of it was decoded.
    #[inline]
    pub(crate) fn drive_mut(&mut self) -> Option<&mut drive::DriveRecord> {
        self.health.as_deref_mut()?.drive.as_deref_mut()
    }

    /// Whether the node raised `code` in the trace.
    pub fn has_raised(&self, code: u16) -> bool {
        self.stats
            .as_ref()
            .is_some_and(|s| s.raised.contains_key(&code))
    }

    /// The open intervals, in the order they were raised (`end: None`).
    pub fn active(&self) -> &[Interval] {
        &self.active
    }

    /// Codes active now, in the order they were raised.
    pub fn active_codes(&self) -> impl Iterator<Item = u16> + '_ {
        self.active.iter().map(|iv| iv.code)
    }

    /// Where `code`'s open interval is in `active`, if it is active: a scan
    /// of a few, a lookup in the index of many.
    fn position(&self, code: u16) -> Option<usize> {
        match &self.index {
            Some(index) => {
                let seq = *index.seq_of.get(&code)?;
                self.active.binary_search_by_key(&seq, |iv| iv.seq).ok()
            }
            None => {
                work::scanned(self.active.len());
                self.active.iter().position(|iv| iv.code == code)
            }
        }
    }

    /// Opens an interval (its code is not active).
    fn open(&mut self, iv: Interval) {
        if self.active.capacity() == 0 {
            // Most nodes never have two errors at once: room for one, not
            // the four a first push reserves (a trace can have a million nodes).
            self.active.reserve_exact(1);
        }
        match &mut self.index {
            Some(index) => index.add(&iv),
            None if self.active.len() + 1 >= work::indexed_from() => {
                let mut index = ActiveIndex::of(&self.active);
                index.add(&iv);
                self.index = Some(index);
            }
            None => {}
        }
        self.active.push(iv);
    }

    /// Applies one EMCY. Warnings that depend on the node's history are
    /// appended to `warnings`.
    pub fn emcy(&mut self, emcy: &Emcy, at: At, warnings: &mut Vec<Warning>) -> Step {
        self.emcy_reusing(emcy, at, warnings, Step::default())
    }

    /// [`NodeTimeline::emcy`] or, with the profile's status bit,
    /// [`NodeTimeline::emcy_with_status_bit`], filling `reuse`'s vectors
    /// (emptied first) instead of new ones: a caller that hands each step
    /// back allocates nothing per clearing frame. (The buffers stay with the
    /// caller, not in every timeline: a trace can have thousands of nodes.)
    pub(crate) fn apply(
        &mut self,
        emcy: &Emcy,
        at: At,
        status_bit: Option<u8>,
        warnings: &mut Vec<Warning>,
        reuse: Step,
    ) -> Step {
        match status_bit {
            Some(bit) => self.status_bit_reusing(emcy, at, bit, warnings, reuse),
            None => self.emcy_reusing(emcy, at, warnings, reuse),
        }
    }

    fn emcy_reusing(
        &mut self,
        emcy: &Emcy,
        at: At,
        warnings: &mut Vec<Warning>,
        mut reuse: Step,
    ) -> Step {
        self.emcy_count += 1;
        let was = self.state;
        reuse.closed.clear();
        reuse.cleared.clear();
        let mut closed = reuse.closed;
        let transition = if !emcy.is_reset() {
            if self.position(emcy.code).is_none() {
                self.open(Interval {
                    seq: self.next_seq,
                    code: emcy.code,
                    start: at,
                    end: None,
                    cleared_by: None,
                    raised_register: emcy.register,
                    status_bit: None,
                });
                self.next_seq += 1;
                *self.stats_mut().raised.entry(emcy.code).or_insert(0) += 1;
            }
            self.state = State::ErrorOccurred;
            Some(if was == State::ErrorFree { 1 } else { 3 })
        } else if emcy.register.0 != 0 {
            let now = emcy.register;
            if self
                .index
                .as_ref()
                .is_none_or(|index| index.partial_reset_closes_any(now))
            {
                self.close_where(at, ClearedBy::PartialReset, &mut closed, |iv| {
                    attributable_bit(iv).is_some_and(|bit| !now.has(bit))
                });
            }
            self.state = State::ErrorOccurred;
            if was == State::ErrorFree {
                warnings.push(Warning::PartialResetWhileErrorFree);
                None
            } else {
                if closed.is_empty() {
                    warnings.push(Warning::PartialResetUnattributed { register: now.0 });
                }
                Some(2)
            }
        } else {
            self.close_where(at, ClearedBy::Reset, &mut closed, |_| true);
            self.state = State::ErrorFree;
            if was == State::ErrorFree {
                warnings.push(Warning::ResetWhileErrorFree);
                None
            } else {
                Some(4)
            }
        };
        self.account(was, at, true, &closed);
        self.step(transition, closed, reuse.cleared)
    }

    /// Applies one EMCY from a node whose profile names an error status bit in
    /// every frame (CANopenNode sends a frame when a bit is set and when it is
    /// cleared, and says which): an error is raised as usual and remembers its
    /// bit; a code-0x0000 frame closes exactly the error raised with its bit
    /// (transition 2, or 4 when nothing is left). A code-0x0000 frame whose
    /// bit is not active is an information report (the CAN bus warning):
    /// not a reset, no transition, state unchanged.
    pub fn emcy_with_status_bit(
        &mut self,
        emcy: &Emcy,
        at: At,
        bit: u8,
        warnings: &mut Vec<Warning>,
    ) -> Step {
        self.status_bit_reusing(emcy, at, bit, warnings, Step::default())
    }

    fn status_bit_reusing(
        &mut self,
        emcy: &Emcy,
        at: At,
        bit: u8,
        warnings: &mut Vec<Warning>,
        mut reuse: Step,
    ) -> Step {
        if !emcy.is_reset() {
            let step = self.emcy_reusing(emcy, at, warnings, reuse);
            if let Some(iv) = self
                .position(emcy.code)
                .and_then(|i| self.active.get_mut(i))
            {
                iv.status_bit.get_or_insert(bit);
            }
            return step;
        }
        self.emcy_count += 1;
        let was = self.state;
        reuse.closed.clear();
        reuse.cleared.clear();
        let mut closed = reuse.closed;
        self.close_where(at, ClearedBy::StatusBit, &mut closed, |iv| {
            iv.status_bit == Some(bit)
        });
        let transition = if closed.is_empty() {
            None
        } else if self.active.is_empty() {
            self.state = State::ErrorFree;
            Some(4)
        } else {
            Some(2)
        };
        self.account(was, at, true, &closed);
        self.step(transition, closed, reuse.cleared)
    }

    fn step(
        &mut self,
        transition: Option<u8>,
        closed: Vec<Interval>,
        mut cleared: Vec<u16>,
    ) -> Step {
        cleared.extend(closed.iter().map(|iv| iv.code));
        Step {
            transition,
            state: self.state,
            cleared,
            closed,
        }
    }

    /// Applies an NMT boot-up; returns the intervals it closed.
    pub fn boot(&mut self, at: At) -> Vec<Interval> {
        let was = self.state;
        let mut closed = Vec::new();
        self.close_where(at, ClearedBy::Boot, &mut closed, |_| true);
        self.state = State::ErrorFree;
        self.account(was, at, false, &closed);
        closed
    }

    /// Closes the active errors `closes` picks, in one pass (removing them
    /// one by one moved the rest each time: quadratic in active errors).
    fn close_where(
        &mut self,
        at: At,
        by: ClearedBy,
        closed: &mut Vec<Interval>,
        mut closes: impl FnMut(&Interval) -> bool,
    ) {
        let from = closed.len();
        work::scanned(self.active.len());
        closed.extend(self.active.extract_if(.., |iv| closes(iv)).map(|mut iv| {
            iv.end = Some(at);
            iv.cleared_by = Some(by);
            iv
        }));
        if self.active.len() < work::indexed_from() {
            self.index = None;
        } else if let Some(index) = &mut self.index {
            for iv in closed.get(from..).unwrap_or_default() {
                index.remove(iv);
            }
        }
    }
}

/// Active intervals looked at, counted in tests: the work per frame must
/// not grow with the node's active errors.
#[cfg(test)]
mod work {
    use std::cell::Cell;

    thread_local! {
        static SCANNED: Cell<usize> = const { Cell::new(0) };
    }

    pub(super) fn scanned(n: usize) {
        SCANNED.with(|s| s.set(s.get().saturating_add(n)));
    }

    /// Intervals looked at by this thread so far.
    pub(super) fn total() -> usize {
        SCANNED.with(Cell::get)
    }

    thread_local! {
        static INDEXED_FROM: Cell<usize> = const { Cell::new(super::INDEXED_FROM) };
    }

    /// [`INDEXED_FROM`](super::INDEXED_FROM), or what a test set for this thread (to
    /// check the index against the scan it replaces).
    pub(super) fn indexed_from() -> usize {
        INDEXED_FROM.with(Cell::get)
    }

    pub(super) fn index_from(n: usize) {
        INDEXED_FROM.with(|i| i.set(n));
    }
}

#[cfg(not(test))]
mod work {
    #[inline(always)]
    pub(super) fn scanned(_: usize) {}

    #[inline(always)]
    pub(super) fn indexed_from() -> usize {
        crate::timeline::node::INDEXED_FROM
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn emcy(code: u16, register: u8) -> Emcy {
        let [lo, hi] = code.to_le_bytes();
        Emcy::decode(&[lo, hi, register, 0, 0, 0, 0, 0]).unwrap()
    }

    fn at(line: u64) -> At {
        At {
            time: Some(Timestamp::from_parts(line, 0, 1)),
            line,
        }
    }

    /// Per frame: the transition and the warning tags.
    type Steps = Vec<(Option<u8>, Vec<&'static str>)>;

    /// A timeline and every interval it handed out, as a caller keeps them.
    struct Kept {
        t: NodeTimeline,
        closed: Vec<Interval>,
    }

    impl Kept {
        /// Closed and open intervals in raise order.
        fn intervals(&self) -> Vec<Interval> {
            let mut all: Vec<Interval> =
                self.closed.iter().chain(self.t.active()).cloned().collect();
            all.sort_by_key(|iv| iv.seq);
            all
        }
        fn state(&self) -> State {
            self.t.state()
        }
        fn active_codes(&self) -> Vec<u16> {
            self.t.active_codes().collect()
        }
        fn boot(&mut self, at: At) -> Vec<u16> {
            let closed = self.t.boot(at);
            let codes = closed.iter().map(|iv| iv.code).collect();
            self.closed.extend(closed);
            codes
        }
        fn emcy(&mut self, e: &Emcy, at: At, w: &mut Vec<Warning>) -> Step {
            let step = self.t.emcy(e, at, w);
            self.closed.extend(step.closed.iter().cloned());
            step
        }
    }

    /// Applies frames (code, register) in order.
    fn run(frames: &[(u16, u8)]) -> (Kept, Steps) {
        let mut t = Kept {
            t: NodeTimeline::new(),
            closed: Vec::new(),
        };
        let mut steps = Vec::new();
        for (i, &(code, reg)) in frames.iter().enumerate() {
            let mut w = Vec::new();
            let step = t.emcy(&emcy(code, reg), at(i as u64 + 1), &mut w);
            steps.push((step.transition, w.iter().map(Warning::tag).collect()));
        }
        (t, steps)
    }

    fn summary(t: &Kept) -> Vec<(u16, Option<u64>, Option<&'static str>)> {
        t.intervals()
            .iter()
            .map(|iv| {
                (
                    iv.code,
                    iv.end.map(|e| e.line),
                    iv.cleared_by.map(ClearedBy::slug),
                )
            })
            .collect()
    }

    #[test]
    fn starts_error_free() {
        let t = NodeTimeline::new();
        assert_eq!(t.state(), State::ErrorFree);
        assert_eq!(t.active_codes().count(), 0);
    }

    #[test]
    fn status_bit_reset_closes_exactly_its_error() {
        let mut t = NodeTimeline::new();
        let mut w = Vec::new();
        // Heartbeat timeout (bit 0x1B) and a PDO length error (bit 0x04), both communication.
        t.emcy_with_status_bit(&emcy(0x8130, 0x11), at(1), 0x1B, &mut w);
        let s2 = t.emcy_with_status_bit(&emcy(0x8210, 0x11), at(2), 0x04, &mut w);
        assert_eq!(s2.transition, Some(3));
        // The register cannot say which ended; the bit can.
        let s3 = t.emcy_with_status_bit(&emcy(0x0000, 0x11), at(3), 0x04, &mut w);
        assert_eq!((s3.transition, s3.state), (Some(2), State::ErrorOccurred));
        assert_eq!(s3.cleared, [0x8210]);
        assert_eq!(s3.closed[0].cleared_by, Some(ClearedBy::StatusBit));
        let s4 = t.emcy_with_status_bit(&emcy(0x0000, 0x00), at(4), 0x1B, &mut w);
        assert_eq!((s4.transition, s4.state), (Some(4), State::ErrorFree));
        assert_eq!(s4.cleared, [0x8130]);
        assert!(w.is_empty(), "{w:?}");
    }

    #[test]
    fn status_bit_report_of_an_inactive_bit_is_information() {
        let mut t = NodeTimeline::new();
        let mut w = Vec::new();
        // CANopenNode's CAN bus warning: code 0x0000, bit 0x01, never raised as an error.
        let s = t.emcy_with_status_bit(&emcy(0x0000, 0x11), at(1), 0x01, &mut w);
        assert_eq!((s.transition, s.state), (None, State::ErrorFree));
        assert!(s.cleared.is_empty() && w.is_empty());
        // With an error active, an unrelated bit still closes nothing.
        t.emcy_with_status_bit(&emcy(0x8130, 0x11), at(2), 0x1B, &mut w);
        let s = t.emcy_with_status_bit(&emcy(0x0000, 0x11), at(3), 0x01, &mut w);
        assert_eq!((s.transition, s.state), (None, State::ErrorOccurred));
        assert_eq!(t.active_codes().collect::<Vec<_>>(), [0x8130]);
        assert_eq!(t.emcy_count(), 3);
    }

    #[test]
    fn stats_follow_the_trace() {
        let (t, _) = run(&[
            (0x4310, 0x09), // line 1: error period starts
            (0x4310, 0x09), // repeat: not a raise
            (0x2310, 0x0B),
            (0x0000, 0x09), // line 4: 0x2310 closes after 1 s
            (0x0000, 0x00), // line 5: 0x4310 closes after 4 s; period ends (4 s)
            (0x4310, 0x09), // line 6: a new period, still open at the end
        ]);
        let st = t.t.stats();
        assert_eq!(
            st.raised.iter().map(|(c, n)| (*c, *n)).collect::<Vec<_>>(),
            [(0x2310, 1), (0x4310, 2)]
        );
        assert_eq!(st.first_emcy.map(|a| a.line), Some(1));
        assert_eq!(st.last_emcy.map(|a| a.line), Some(6));
        assert_eq!(st.time_in_error.to_string(), "4.0");
        assert_eq!(
            st.longest.map(|(c, d)| (c, d.to_string())),
            Some((0x4310, "4.0".to_string()))
        );
        assert_eq!(
            st.in_error_since.map(|t| t.to_string()),
            Some("6.0".to_string())
        );
    }

    #[test]
    fn a_boot_ends_an_error_period() {
        let (mut t, _) = run(&[(0x4310, 0x09)]);
        t.boot(at(3));
        let st = t.t.stats();
        assert_eq!(st.time_in_error.to_string(), "2.0");
        assert_eq!(st.in_error_since, None);
        assert_eq!(st.longest.map(|(c, _)| c), Some(0x4310));
    }

    #[test]
    fn memory_holds_only_active_errors() {
        let mut t = NodeTimeline::new();
        let mut w = Vec::new();
        for i in 0..1000 {
            t.emcy(&emcy(0x4310, 0x09), at(2 * i + 1), &mut w);
            t.emcy(&emcy(0, 0), at(2 * i + 2), &mut w);
        }
        assert!(t.active().is_empty());
        t.emcy(&emcy(0x4310, 0x09), at(5000), &mut w);
        assert_eq!(t.active().len(), 1);
        assert_eq!(t.active()[0].seq, 1000);
    }

    #[test]
    fn transition_1_error_free_to_error_occurred() {
        let (t, steps) = run(&[(0x4310, 0x09)]);
        assert_eq!(steps[0].0, Some(1));
        assert_eq!(t.state(), State::ErrorOccurred);
        assert_eq!(t.active_codes(), [0x4310]);
    }

    #[test]
    fn transition_3_new_error_while_in_error() {
        let (t, steps) = run(&[(0x4310, 0x09), (0x2310, 0x0B)]);
        assert_eq!(steps[1].0, Some(3));
        assert_eq!(t.active_codes(), [0x4310, 0x2310]);
    }

    #[test]
    fn repeated_code_keeps_one_interval() {
        let (t, steps) = run(&[(0x4310, 0x09), (0x4310, 0x09)]);
        assert_eq!(steps[1].0, Some(3));
        assert_eq!(t.intervals().len(), 1);
        assert_eq!(t.t.emcy_count(), 2);
    }

    #[test]
    fn transition_4_reset_closes_everything() {
        let (t, steps) = run(&[(0x4310, 0x09), (0x2310, 0x0B), (0x0000, 0x00)]);
        assert_eq!(steps[2].0, Some(4));
        assert_eq!(t.state(), State::ErrorFree);
        assert_eq!(
            summary(&t),
            [
                (0x4310, Some(3), Some("reset")),
                (0x2310, Some(3), Some("reset"))
            ]
        );
    }

    #[test]
    fn transition_2_closes_the_error_whose_class_bit_dropped() {
        // Temperature (bit 3) and current (bit 1) raised; the register drops bit 1.
        let (t, steps) = run(&[(0x4310, 0x09), (0x2310, 0x0B), (0x0000, 0x09)]);
        assert_eq!(steps[2], (Some(2), vec![]));
        assert_eq!(t.state(), State::ErrorOccurred);
        assert_eq!(
            summary(&t),
            [
                (0x4310, None, None),
                (0x2310, Some(3), Some("partial_reset"))
            ]
        );
        assert_eq!(t.active_codes(), [0x4310]);
    }

    #[test]
    fn partial_reset_that_names_no_error_keeps_all_active() {
        // The S300 manual's example: the register still shows the temperature bit.
        let (t, steps) = run(&[(0x4310, 0x08), (0x0000, 0x08)]);
        assert_eq!(steps[1], (Some(2), vec!["partial_reset_unattributed"]));
        assert_eq!(t.active_codes(), [0x4310]);
    }

    #[test]
    fn errors_without_a_class_bit_are_never_inferred_closed() {
        // 0x5530 (hardware) has no register bit; 0x8611 (monitoring) neither.
        let (t, _) = run(&[(0x5530, 0x01), (0x8611, 0x21), (0x0000, 0x01)]);
        assert_eq!(t.active_codes(), [0x5530, 0x8611]);
    }

    #[test]
    fn inference_needs_the_bit_set_when_raised() {
        // 0x2310 raised without the current bit: a later register without it proves nothing.
        let (t, _) = run(&[(0x2310, 0x01), (0x4310, 0x09), (0x0000, 0x01)]);
        assert_eq!(
            summary(&t),
            [
                (0x2310, None, None),
                (0x4310, Some(3), Some("partial_reset"))
            ]
        );
    }

    #[test]
    fn each_class_bit_attributes_its_class() {
        for (code, bit) in [
            (0x2310u16, 1u8),
            (0x3210, 2),
            (0x4210, 3),
            (0x8110, 4),
            (0x8210, 4),
            (0xFF01, 7),
        ] {
            let raised = 0x01 | (1 << bit);
            let (t, _) = run(&[(code, raised), (0x1000, 0x01 | 0x20), (0x0000, 0x21)]);
            assert_eq!(
                summary(&t)[0],
                (code, Some(3), Some("partial_reset")),
                "code {code:04X}"
            );
        }
    }

    #[test]
    fn partial_reset_while_error_free_warns_and_enters_error_occurred() {
        let (t, steps) = run(&[(0x0000, 0x08)]);
        assert_eq!(steps[0], (None, vec!["partial_reset_while_error_free"]));
        assert_eq!(t.state(), State::ErrorOccurred);
    }

    #[test]
    fn reset_while_error_free_warns() {
        let (t, steps) = run(&[(0x0000, 0x00)]);
        assert_eq!(steps[0], (None, vec!["reset_while_error_free"]));
        assert_eq!(t.state(), State::ErrorFree);
    }

    #[test]
    fn boot_closes_everything_and_returns_error_free() {
        let (mut t, _) = run(&[(0x4310, 0x09), (0x3210, 0x05)]);
        assert_eq!(t.boot(at(9)), [0x4310, 0x3210]);
        assert_eq!(t.state(), State::ErrorFree);
        assert_eq!(
            summary(&t),
            [
                (0x4310, Some(9), Some("boot")),
                (0x3210, Some(9), Some("boot"))
            ]
        );
        assert!(t.boot(at(10)).is_empty());
        // After boot a new error is transition 1 again.
        let mut w = Vec::new();
        assert_eq!(
            t.emcy(&emcy(0x4310, 0x09), at(11), &mut w).transition,
            Some(1)
        );
        assert_eq!(t.intervals().len(), 3);
    }

    #[test]
    fn odd_reset_codes_are_errors() {
        let (t, steps) = run(&[(0x0012, 0x01)]);
        assert_eq!(steps[0].0, Some(1));
        assert_eq!(t.active_codes(), [0x0012]);
    }

    #[test]
    fn step_reports_what_it_cleared() {
        let mut t = NodeTimeline::new();
        let mut w = Vec::new();
        t.emcy(&emcy(0x4310, 0x09), at(1), &mut w);
        let step = t.emcy(&emcy(0, 0), at(2), &mut w);
        assert_eq!(step.cleared, [0x4310]);
        assert_eq!(step.closed.len(), 1);
        assert_eq!(step.closed[0].cleared_by, Some(ClearedBy::Reset));
        assert_eq!(step.state, State::ErrorFree);
        assert!(t.active().is_empty());
    }

    #[test]
    fn a_reused_step_keeps_nothing_of_the_last_one() {
        let mut t = NodeTimeline::new();
        let mut w = Vec::new();
        t.emcy(&emcy(0x4310, 0x09), at(1), &mut w);
        let first = t.apply(&emcy(0, 0), at(2), None, &mut w, Step::default());
        assert_eq!(first.cleared, [0x4310]);
        let raise = t.apply(&emcy(0x2310, 0x03), at(3), Some(0x1B), &mut w, first);
        assert!(raise.cleared.is_empty() && raise.closed.is_empty());
        let second = t.apply(&emcy(0, 0), at(4), None, &mut w, raise);
        assert_eq!(second.cleared, [0x2310]);
        assert_eq!(second.closed.len(), 1);
        assert_eq!(second.closed[0].start.line, 3);
    }

    /// Frames of one node with many active errors: raises, repeats,
    /// partial resets that close nothing; the intervals looked at per frame
    /// stay bounded (a scan per frame made it quadratic in active errors).
    #[test]
    fn work_per_frame_does_not_grow_with_active_errors() {
        const N: u16 = 5000;
        let mut t = NodeTimeline::new();
        let mut w = Vec::new();
        let before = work::total();
        let mut line = 0;
        let mut frame = |t: &mut NodeTimeline, code: u16, register: u8| {
            line += 1;
            t.emcy(&emcy(code, register), at(line), &mut w)
        };
        for i in 0..N {
            frame(&mut t, 0x1001 + i, 0x01);
        }
        for i in 0..N {
            let repeat = (u32::from(i) * 7919 % u32::from(N)) as u16;
            let step = frame(&mut t, 0x1001 + repeat, 0x01);
            assert_eq!(step.transition, Some(3));
        }
        for _ in 0..N {
            // The generic bit alone: no error can be attributed.
            let step = frame(&mut t, 0x0000, 0x01);
            assert!(step.cleared.is_empty());
        }
        assert_eq!(t.active().len(), usize::from(N));
        let frames = 3 * usize::from(N);
        let scanned = work::total() - before;
        assert!(
            scanned <= INDEXED_FROM * frames,
            "{scanned} intervals looked at for {frames} frames"
        );
        // A reset closes all of them in one pass.
        let step = frame(&mut t, 0x0000, 0x00);
        assert_eq!(step.cleared.len(), usize::from(N));
        assert!(work::total() - before <= INDEXED_FROM * frames + usize::from(N));
        assert!(t.active().is_empty());
    }

    /// One frame of a random script.
    #[derive(Clone, Debug)]
    enum Frame {
        Emcy {
            code: u16,
            register: u8,
            bit: Option<u8>,
        },
        Boot,
    }

    fn frame_strategy() -> impl proptest::strategy::Strategy<Value = Frame> {
        use proptest::prelude::*;
        // Few codes of every class, registers with any class bits: many
        // errors active at once, partial resets that close some.
        let code = prop_oneof![
            3 => (0u16..40).prop_map(|i| [0x1000, 0x2310, 0x3210, 0x4210, 0x5530, 0x8110, 0xFF00][usize::from(i % 7)] + i),
            1 => Just(0x0000u16),
        ];
        prop_oneof![
            30 => (code, any::<u8>(), proptest::option::of(0u8..4))
                .prop_map(|(code, register, bit)| Frame::Emcy { code, register, bit }),
            1 => Just(Frame::Boot),
        ]
    }

    /// Everything a timeline says after each frame of `frames`, with the
    /// index from `indexed_from` active errors on.
    fn replay(frames: &[Frame], indexed_from: usize) -> Vec<String> {
        work::index_from(indexed_from);
        let mut t = NodeTimeline::new();
        let mut said = Vec::new();
        for (i, f) in frames.iter().enumerate() {
            let at = at(i as u64 + 1);
            let mut w = Vec::new();
            let step = match f {
                Frame::Emcy {
                    code,
                    register,
                    bit,
                } => t.apply(&emcy(*code, *register), at, *bit, &mut w, Step::default()),
                Frame::Boot => Step {
                    closed: t.boot(at),
                    ..Step::default()
                },
            };
            said.push(format!("{step:?} {w:?} {:?} {:?}", t.active(), t.stats()));
        }
        work::index_from(INDEXED_FROM);
        said
    }

    proptest::proptest! {
        /// The index answers exactly what a scan of the active list does.
        #[test]
        fn the_index_changes_nothing(frames in proptest::collection::vec(frame_strategy(), 0..400)) {
            let scanned = replay(&frames, usize::MAX);
            proptest::prop_assert_eq!(&replay(&frames, 1), &scanned);
            proptest::prop_assert_eq!(&replay(&frames, 4), &scanned);
            proptest::prop_assert_eq!(&replay(&frames, INDEXED_FROM), &scanned);
        }
    }

    /// A node that never had two errors at once holds room for one, and a
    /// boot-up alone allocates nothing: a trace can name a million nodes.
    #[test]
    fn a_node_holds_only_what_it_needs() {
        let mut t = NodeTimeline::new();
        t.boot(at(1));
        assert_eq!(t.active.capacity(), 0);
        assert!(t.stats.is_none());
        let mut w = Vec::new();
        t.emcy(&emcy(0x4310, 0x09), at(2), &mut w);
        assert_eq!(t.active.capacity(), 1);
        assert!(t.index.is_none());
    }
}
