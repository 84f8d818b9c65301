//! The fold fast path: runs of steady heartbeats and repeated drive PDOs
//! the reader folded ([`FoldedRun`]) are taken whole when reading their
//! lines one by one would have changed nothing but deadlines and times.
//! A run mixes the NMT monitor's frames and the drive monitor's, so the
//! dispatcher takes it, asking each monitor about its folds.

use std::io::Write;

use super::analysis::OutputError;
use super::classify::{FoldedRun, LineSink};
use super::consumer::Consumer;
use super::monitor::{NmtMonitor, TakenFold};
use crate::canopen::nmt;
use crate::timeline::At;
use crate::trace::{Frame, FrameKind, Inner, Payload, Timestamp};

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
    pub(super) fn take_folded_run(
        &mut self,
        idx: u64,
        run: &FoldedRun<'_>,
    ) -> Result<(), OutputError> {
        if (run.inner.is_empty() || self.inner_after_folds(run)) && self.take_folds(idx, run) {
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
        self.unfold(idx, run)
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

    /// The folded frames of `run` and those kept inside it one by one, in
    /// line order; its other lines counted.
    fn unfold(&mut self, idx: u64, run: &FoldedRun<'_>) -> Result<(), OutputError> {
        self.plain_frames(run.plain);
        let others = run.timed.saturating_sub(run.frames.len() as u64);
        self.counts.frames += others;
        // The run's first time before its frames', its last after.
        self.time(run.first);
        let mut inner = run.inner.iter().peekable();
        for f in run.frames {
            while let Some(i) = inner.next_if(|i| i.idx() < f.idx()) {
                self.inner_frame(idx, run, i)?;
            }
            let frame = Frame {
                time: Some(f.time()),
                channel: run.channel,
                id: f.id(),
                extended: false,
                kind: FrameKind::Data,
                len: f.len(),
                data: Payload::inline(f.data().to_le_bytes(), f.len()),
            };
            self.frame(idx + f.idx(), &frame, None)?;
        }
        for i in inner {
            self.inner_frame(idx, run, i)?;
        }
        self.time(run.last);
        Ok(())
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
        // A burst of error frames closes within the run: frame by frame,
        // so it closes where the frame path closes it.
        if self.facts.bus.passed(run.latest) || self.incidents.passed(run.latest) {
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

/// How many folded runs the consumer took and refused on this thread, for
/// tests that must see both paths taken.
#[cfg(test)]
pub(crate) mod fold_tally {
    use std::cell::Cell;

    thread_local! {
        static TALLY: Cell<(u64, u64)> = const { Cell::new((0, 0)) };
        static INNER: Cell<u64> = const { Cell::new(0) };
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
