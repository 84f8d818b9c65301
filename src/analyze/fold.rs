//! The fold fast path: runs of steady heartbeats and repeated drive PDOs
//! the reader folded ([`FoldedRun`]) are taken whole when reading their
//! lines one by one would have changed nothing but deadlines and times.
//! A run mixes the NMT monitor's frames and the drive monitor's, so the
//! dispatcher takes it, asking each monitor about its folds.

use std::io::Write;
use std::iter::Peekable;

use super::analysis::OutputError;
use super::classify::{FoldedRun, LineSink};
use super::consumer::Consumer;
use super::monitor::{NmtMonitor, TakenFold};
use crate::canopen::nmt;
use crate::timeline::At;
use crate::trace::{Frame, FrameKind, Inner, Payload, TimedLine, Timestamp};

impl<E: Write> Consumer<'_, '_, E> {
    /// Heartbeats and PDOs the reader folded ([`FoldedRun`]), with the
    /// rest of their run: taken whole when reading the lines one by one
    /// would have sent each heartbeat down the steady heartbeat path
    /// ([`NmtMonitor::steady_heartbeat`]), made each PDO a repeat and found
    /// no node lost at any of them, and then the frames kept inside the
    /// run after them (EMCYs, which depend on no heartbeat: see
    /// [`Consumer::inner_after_folds`]); else the folded frames and those
    /// kept inside are taken one by one in line order, as if their lines
    /// had been read (the others of the run only count and move the
    /// input's first and last time), so the result never depends on
    /// folding.
    ///
    /// The lines handed over for their times alone (SYNC) change nothing
    /// but their id's timing until one ends a gap, which is an event: those
    /// before it are timed first, and a run with such a gap is taken one by
    /// one, the event in its place among the others.
    pub(super) fn take_folded_run(
        &mut self,
        idx: u64,
        run: &FoldedRun<'_>,
    ) -> Result<(), OutputError> {
        let timed = self.time_handed_until_gap(idx, run);
        let handed = run.handed.get(timed..).unwrap_or_default();
        #[cfg(test)]
        fold_tally::gap(!handed.is_empty());
        if handed.is_empty()
            && (run.inner.is_empty() || self.inner_after_folds(run))
            && self.take_folds(idx, run)
        {
            for inner in run.inner {
                self.inner_frame(idx, run, inner)?;
            }
            if !run.inner.is_empty() {
                // The run's last time, after theirs.
                self.time(run.last);
            }
            #[cfg(test)]
            fold_tally::inner(run.inner.len());
            return Ok(());
        }
        self.unfold(idx, run, handed)
    }

    /// The lines `run` handed over, timed in order up to the first that
    /// would end a gap (an event to tell in line order): how many.
    fn time_handed_until_gap(&mut self, idx: u64, run: &FoldedRun<'_>) -> usize {
        if run.handed.is_empty() {
            return 0;
        }
        match self.traffic.channel_index(run.channel) {
            Some(c) => self
                .traffic
                .lines_until_gap(c, self.line_no(idx), run.handed),
            // Past the channel bound: counted, not timed.
            None => run.handed.len(),
        }
    }

    /// Whether the frames kept inside `run` may be taken after its folds:
    /// they are EMCYs, which change no heartbeat or NMT state and read
    /// none, and the folds are heartbeats (a drive's PDOs and its EMCYs
    /// both change the drive's state). The run's times only go forward,
    /// the frames' too, so when the folds are taken whole no node was lost
    /// at any frame of the run either.
    fn inner_after_folds(&self, run: &FoldedRun<'_>) -> bool {
        let drive = &self.monitors.drive;
        run.folds
            .iter()
            .all(|f| nmt::error_control_node(f.id).is_some())
            && run.inner.iter().all(|i| {
                self.wanted.interest.wants(i.id(), false)
                    && self.facts.emcy_node(i.id(), false).is_some()
                    && drive.slot(i.id(), false).is_none()
                    && !drive.watches(i.id())
            })
    }

    /// The folded frames of `run`, those kept inside it and the lines it
    /// handed over not yet timed (`handed`) one by one, in line order; its
    /// other lines counted.
    fn unfold(
        &mut self,
        idx: u64,
        run: &FoldedRun<'_>,
        handed: &[TimedLine],
    ) -> Result<(), OutputError> {
        self.plain_frames(run.plain);
        let others = run.timed.saturating_sub(run.frames.len() as u64);
        self.counts.frames += others;
        // The run's first time before its frames', its last after.
        self.time(run.first);
        let mut between = Between {
            inner: run.inner.iter().peekable(),
            handed: handed.iter().peekable(),
        };
        for f in run.frames {
            self.lines_before(idx, run, &mut between, f.idx())?;
            // With every frame timed, the folded lines were handed over
            // too: timed there, in line order with the others.
            self.timed_as_lines = self.traffic.wants();
            let frame = Frame {
                time: Some(f.time()),
                channel: run.channel,
                id: f.id(),
                extended: false,
                kind: FrameKind::Data,
                len: f.len(),
                data: Payload::inline(f.data().to_le_bytes(), f.len()),
            };
            let taken = self.frame(idx + f.idx(), &frame, None);
            self.timed_as_lines = false;
            taken?;
        }
        self.lines_before(idx, run, &mut between, u64::MAX)?;
        self.time(run.last);
        Ok(())
    }

    /// The frames kept inside `run` and its lines handed over that come
    /// before its line `end`, in line order.
    fn lines_before(
        &mut self,
        idx: u64,
        run: &FoldedRun<'_>,
        between: &mut Between<'_>,
        end: u64,
    ) -> Result<(), OutputError> {
        loop {
            let inner = between.inner.peek().map(|i| i.idx()).filter(|&n| n < end);
            let handed = between
                .handed
                .peek()
                .map(|l| u64::from(l.idx))
                .filter(|&n| n < end);
            match (inner, handed) {
                (Some(i), Some(h)) if h < i => self.handed_line(idx, run, between)?,
                (Some(_), _) => {
                    if let Some(i) = between.inner.next() {
                        self.inner_frame(idx, run, i)?;
                    }
                }
                (None, Some(_)) => self.handed_line(idx, run, between)?,
                (None, None) => return Ok(()),
            }
        }
    }

    /// The next line `run` handed over, timed.
    fn handed_line(
        &mut self,
        idx: u64,
        run: &FoldedRun<'_>,
        between: &mut Between<'_>,
    ) -> Result<(), OutputError> {
        match (
            between.handed.next(),
            self.traffic.channel_index(run.channel),
        ) {
            (Some(l), Some(c)) => self.timed_line(idx, c, run.channel, l),
            _ => Ok(()),
        }
    }

    /// A frame kept inside `run` (of the block's lines from `idx`), as
    /// its line would have given it.
    fn inner_frame(&mut self, idx: u64, run: &FoldedRun<'_>, i: &Inner) -> Result<(), OutputError> {
        self.frame(idx + i.idx(), &i.frame(run.channel), None)
    }

    /// [`Consumer::take_folded_run`] when the folds can be taken whole:
    /// `false`, nothing changed, when they cannot.
    fn take_folds(&mut self, idx: u64, run: &FoldedRun<'_>) -> bool {
        let mut rebounds = std::mem::take(&mut self.rebounds);
        let mut taken_as = std::mem::take(&mut self.taken_as);
        rebounds.clear();
        taken_as.clear();
        let channel = self.nodes.channel_index(run.channel);
        let taken = self.decided
            && channel.is_some_and(|c| self.takes_folds(run, c, &mut taken_as, &mut rebounds));
        if let Some(c) = channel.filter(|_| taken) {
            self.plain_frames(run.plain);
            self.timed_frames(run.timed, run.first, run.last);
            for (f, taken) in run.folds.iter().zip(&taken_as) {
                let at = At {
                    time: Some(taken.last),
                    line: self.line_no(idx + f.last_idx()),
                };
                match (taken.node, taken.deadline) {
                    (Some((node, i)), Some(deadline)) => {
                        if let Some(h) = self
                            .nodes
                            .timeline_of(c, i, node)
                            .and_then(|timeline| timeline.health_if_any())
                        {
                            h.heartbeat.fold(f.count(), at, deadline);
                        }
                    }
                    _ => self.monitors.drive.fold_pdos(f, at),
                }
            }
            self.monitors.nmt.rebound(run.latest, &rebounds);
        }
        self.rebounds = rebounds;
        self.taken_as = taken_as;
        #[cfg(test)]
        fold_tally::count(taken);
        taken
    }

    /// Whether [`Consumer::take_folded_run`] can take `run`'s folds (on
    /// the channel at `c`): each one heartbeats of a known node in the
    /// steady state its data says, each of them steady
    /// ([`NmtMonitor::takes_heartbeat_fold`]), or a drive's PDOs that
    /// repeat, and every other node within its deadline at the last of
    /// them ([`NmtMonitor::deadlines_hold`]). Each fold's last time and
    /// node, and a heartbeat's new deadline, go to `taken_as` (one per
    /// fold, in order); when the schedule's bound passed, the groups
    /// looked at and their earliest deadline after the folds go to
    /// `rebounds`.
    fn takes_folds(
        &mut self,
        run: &FoldedRun<'_>,
        c: usize,
        taken_as: &mut Vec<TakenFold>,
        rebounds: &mut Vec<(u32, Option<Timestamp>)>,
    ) -> bool {
        // Something the frame path tells falls due within the run: frame
        // by frame, so it is told where the frame path tells it.
        if self.frame_path_due(run.latest) {
            return false;
        }
        // Index + 1 into the folds by node (0: not folded).
        let mut folded = [0u8; 128];
        for (i, f) in run.folds.iter().enumerate() {
            let wanted = self.wanted.interest.wants(f.id, false);
            let Some(node) = nmt::error_control_node(f.id) else {
                // A drive's PDOs (the frame path tries heartbeats first).
                if !(wanted && self.monitors.drive.takes_pdo_fold(run.channel, f)) {
                    return false;
                }
                taken_as.push(TakenFold {
                    last: f.last(),
                    node: None,
                    deadline: None,
                });
                continue;
            };
            if !wanted || self.facts.moved_emcy(f.id) {
                return false;
            }
            let Some(taken) =
                NmtMonitor::takes_heartbeat_fold(f, node, c, run.latest, &mut self.nodes)
            else {
                return false;
            };
            taken_as.push(taken);
            if let Some(slot) = folded.get_mut(usize::from(node)) {
                *slot = u8::try_from(i + 1).unwrap_or(0);
            }
        }
        let channel = self.nodes.channel_id_at(c);
        self.monitors.nmt.deadlines_hold(
            run.latest,
            channel,
            &folded,
            taken_as,
            rebounds,
            &mut self.nodes,
        )
    }
}

/// What of a folded run comes between its folded frames, in line order.
struct Between<'a> {
    inner: Peekable<std::slice::Iter<'a, Inner>>,
    handed: Peekable<std::slice::Iter<'a, TimedLine>>,
}

/// How many folded runs the consumer took and refused on this thread, for
/// tests that must see both paths taken.
#[cfg(test)]
pub(crate) mod fold_tally {
    use std::cell::Cell;

    thread_local! {
        static TALLY: Cell<(u64, u64)> = const { Cell::new((0, 0)) };
        static INNER: Cell<u64> = const { Cell::new(0) };
        static GAPS: Cell<u64> = const { Cell::new(0) };
    }

    /// A folded run whose handed lines end a gap (`true`): taken one by one.
    pub(super) fn gap(gap: bool) {
        GAPS.with(|t| t.set(t.get() + u64::from(gap)));
    }

    /// Folded runs with a gap in their handed lines since the last call.
    pub(crate) fn take_gaps() -> u64 {
        GAPS.with(|t| t.replace(0))
    }

    /// Frames kept inside a run taken after its folds.
    pub(super) fn inner(n: usize) {
        INNER.with(|t| t.set(t.get() + n as u64));
    }

    /// Frames taken after their run's folds since the last call.
    pub(crate) fn take_inner() -> u64 {
        INNER.with(|t| t.replace(0))
    }

    pub(super) fn count(taken: bool) {
        TALLY.with(|t| {
            let (a, r) = t.get();
            t.set(if taken { (a + 1, r) } else { (a, r + 1) });
        });
    }

    /// (taken, refused) since the last call.
    pub(crate) fn take() -> (u64, u64) {
        TALLY.with(|t| t.replace((0, 0)))
    }
}
