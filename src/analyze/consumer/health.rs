//! The consumer's NMT, heartbeat, SDO abort and error history side: what
//! frames on 0x000, 0x700 + node and the SDO ids do to a node's health, and
//! the events that says. Kept apart from the EMCY path (the hot one).

use std::io::Write;

use super::deadlines::Deadlines;
use super::{Consumer, NodeSlot, Nodes};
use crate::analyze::Options;
use crate::analyze::OutputError;
use crate::analyze::classify::{FoldedRun, LineSink};
use crate::analyze::event::{
    Health, HealthEvent, HeartbeatReport, HistoryItem, HistoryReport, NodeReport,
};
use crate::analyze::sink::Sink;
use crate::canopen::NodeId;
use crate::canopen::nmt::{self, ErrorControl, NmtState, Target};
use crate::canopen::sdo::{self, Sdo};
use crate::canopen::sdo_abort;
use crate::timeline::At;
use crate::timeline::error_history::ReadOut;
use crate::timeline::health::NodeHealth;
use crate::timeline::heartbeat::{Back, Lost, TimeoutSource};
use crate::timeline::nmt::{NmtChange, NmtWarning};
use crate::trace::{FoldBuffers, Frame, FrameKind, Inner, Payload, Span, Timestamp};

/// What the consumer keeps for every node's health.
#[derive(Default)]
pub(in crate::analyze) struct HealthState {
    /// When monitored nodes may have passed their heartbeat deadline.
    deadlines: Deadlines,
    /// Buffers reused from frame to frame.
    pub(super) events: Vec<(At, Health)>,
    warnings: Vec<NmtWarning>,
    read_outs: Vec<ReadOut>,
    groups: Vec<u32>,
    due: Vec<(Timestamp, u32, NodeId)>,
    rebounds: Vec<(u32, Option<Timestamp>)>,
    taken_as: Vec<TakenFold>,
    /// The last block's fold vectors, for the next.
    pub(super) spare_folds: FoldBuffers,
}

/// What taking a fold does ([`Consumer::takes_folds`]), worked out once:
/// the time of its last frame, and for a heartbeat fold the node (and
/// where it is in its channel) and its new deadline.
#[derive(Clone, Copy)]
pub(super) struct TakenFold {
    last: Timestamp,
    node: Option<(NodeId, usize)>,
    deadline: Option<Timestamp>,
}

impl HealthState {
    /// Tells the schedule a node's deadline after anything but a steady
    /// heartbeat (those only move it later, which the schedule allows).
    fn schedule(&mut self, channel_id: u32, node: NodeId, h: &mut NodeHealth) {
        if let Some(deadline) = h.heartbeat.deadline() {
            self.deadlines
                .schedule(&mut h.schedule_slot, (channel_id, node), deadline);
        }
    }

    /// Whether the trace's clock at `now` may have passed a deadline.
    #[inline]
    pub(super) fn passed(&self, now: Timestamp) -> bool {
        self.deadlines.passed(now)
    }
}

/// Hands `events` (emptied) to the sink as the node's events, if the
/// options select the node (`--channel`, `--node`).
pub(super) fn emit(
    sink: &mut dyn Sink,
    file: &str,
    opts: &Options,
    channel: &str,
    node: NodeId,
    events: &mut Vec<(At, Health)>,
) -> Result<(), OutputError> {
    let selected = events.is_empty() || opts.selects(channel, node);
    for (at, health) in events.drain(..) {
        if selected {
            sink.health(&HealthEvent {
                file,
                line: at.line,
                time: at.time,
                channel,
                node,
                health: &health,
            })
            .map_err(OutputError)?;
        }
    }
    Ok(())
}

fn lost_event(lost: Lost, line: u64, timeout: Option<(Span, TimeoutSource)>) -> (At, Health) {
    let (timeout, timeout_source) = timeout.unwrap_or((Span::ZERO, TimeoutSource::Learnt));
    (
        At {
            time: Some(lost.deadline),
            line,
        },
        Health::HeartbeatLost {
            last_seen: lost.last_seen.time,
            last_seen_line: lost.last_seen.line,
            timeout,
            timeout_source,
        },
    )
}

fn back_event(back: Back, at: At) -> (At, Health) {
    (
        at,
        Health::HeartbeatBack {
            silent: back.silent,
            restarted: back.restarted,
        },
    )
}

/// A sign of life (heartbeat or boot-up) for a node's monitor: the outage
/// it ends, found now or before, as events. `Some(start)` when it ends an
/// outage that began after it (the trace's clock went back, or a frame
/// stamped ahead of the bus declared the node lost): the outage's duration
/// is negative, which [`Consumer::outage_after_its_end`] says.
fn sign_of_life(
    h: &mut NodeHealth,
    at: At,
    boot: bool,
    events: &mut Vec<(At, Health)>,
) -> Option<Timestamp> {
    let timeout = h.heartbeat.timeout();
    let (newly, back) = if boot {
        h.heartbeat.boot(at)
    } else {
        h.heartbeat.seen(at)
    };
    if let Some(lost) = newly {
        events.push(lost_event(lost, at.line, timeout));
    }
    let back = back?;
    events.push(back_event(back, at));
    at.time.filter(|&now| now < back.lost.deadline)?;
    Some(back.lost.deadline)
}

fn nmt_event(change: Option<NmtChange>, at: At, events: &mut Vec<(At, Health)>) {
    if let Some(c) = change {
        events.push((
            at,
            Health::Nmt {
                state: c.state,
                via: c.via,
            },
        ));
    }
}

impl Nodes {
    /// The nodes a channel has seen (an NMT command to node 0 is for them).
    fn nodes_of(&self, raw: &[u8]) -> Vec<NodeId> {
        self.index
            .get(raw)
            .and_then(|&i| self.channels.get(i))
            .map(|c| c.nodes.iter().map(|(n, _)| *n).collect())
            .unwrap_or_default()
    }

    /// A node by its channel's history id (deadlines name channels so).
    fn slot_by_id(&mut self, id: u32, node: NodeId) -> Option<NodeSlot<'_>> {
        let Nodes {
            channels, history, ..
        } = self;
        let ch = channels.get_mut(id as usize).filter(|c| c.id == id)?;
        let i = ch.position(node).ok()?;
        let timeline = &mut ch.nodes.get_mut(i)?.1;
        Some(NodeSlot {
            channel: &ch.name,
            channel_id: ch.id,
            timeline,
            history,
        })
    }
}

impl<E: Write> Consumer<'_, '_, E> {
    /// The trace's clock reached `now` (a frame at `line`): every node whose
    /// deadline passed is lost, in the order of the deadlines.
    pub(super) fn deadlines_passed(
        &mut self,
        now: Timestamp,
        line: u64,
    ) -> Result<(), OutputError> {
        let mut groups = std::mem::take(&mut self.health.groups);
        let mut due = std::mem::take(&mut self.health.due);
        self.health.deadlines.due_groups(now, &mut groups);
        for g in groups.drain(..) {
            let mut earliest: Option<Timestamp> = None;
            for &(id, node) in self.health.deadlines.members(g) {
                let deadline = self
                    .nodes
                    .slot_by_id(id, node)
                    .and_then(|slot| slot.timeline.health())
                    .and_then(|h| h.heartbeat.deadline());
                match deadline {
                    Some(d) if now > d => due.push((d, id, node)),
                    Some(d) => earliest = Some(earliest.map_or(d, |e| e.min(d))),
                    None => {}
                }
            }
            self.health.deadlines.rebound(g, earliest);
        }
        due.sort_unstable();
        let result = self.lose(now, line, &mut due);
        due.clear();
        self.health.groups = groups;
        self.health.due = due;
        result
    }

    /// The nodes in `due` passed their deadline at `now`: lost.
    fn lose(
        &mut self,
        now: Timestamp,
        line: u64,
        due: &mut Vec<(Timestamp, u32, NodeId)>,
    ) -> Result<(), OutputError> {
        for (_, id, node) in due.drain(..) {
            let Some(slot) = self.nodes.slot_by_id(id, node) else {
                continue;
            };
            let h = slot.timeline.health_mut(self.opts.heartbeat_timeout);
            let timeout = h.heartbeat.timeout();
            if let Some(lost) = h.heartbeat.check(now) {
                self.health.events.push(lost_event(lost, line, timeout));
            }
            if self.health.events.is_empty() {
                continue;
            }
            emit(
                self.sink,
                self.file,
                self.opts,
                slot.channel,
                node,
                &mut self.health.events,
            )?;
        }
        Ok(())
    }

    /// The common heartbeat (a node still in the state it was, before its
    /// deadline, nothing awaited of it): its deadline moves on and nothing
    /// else happens. Checked ahead of the general frame path, which costs
    /// several times as much (measured in docs/performance.md). `false`:
    /// not that case, nothing was changed.
    #[inline]
    pub(super) fn steady_heartbeat(&mut self, idx: u64, frame: &Frame<'_>) -> bool {
        let (Some(time), &[byte]) = (frame.time, frame.data.as_slice()) else {
            return false;
        };
        // A boot-up (0x00) is never steady: it restarts the node.
        let (Some(node), Some(state), FrameKind::Data, false) = (
            nmt::error_control_node(frame.id),
            NmtState::from_byte(byte).filter(|&s| s != NmtState::Initialising),
            frame.kind,
            frame.extended,
        ) else {
            return false;
        };
        if !self.decided
            || self.health.passed(time)
            || !self.interest.wants(frame.id, false)
            || (!self.emcy_ids.is_empty() && self.emcy_node(frame.id, false).is_some())
        {
            return false;
        }
        let at = At {
            time: Some(time),
            line: self.line_no(idx),
        };
        let Some(h) = self
            .nodes
            .known(frame.channel, node)
            .and_then(|timeline| timeline.health_if_any())
        else {
            return false;
        };
        if !(h.nmt.steady(state) && h.heartbeat.steady(at)) {
            return false;
        }
        self.counts.frames += 1;
        self.time(time);
        true
    }

    /// Heartbeats and PDOs the reader folded ([`FoldedRun`]), with the
    /// rest of their run: taken whole when reading the lines one by one
    /// would have sent each heartbeat down [`Consumer::steady_heartbeat`],
    /// made each PDO a repeat and found no node lost at any of them, and
    /// then the frames kept inside the run after them (EMCYs, which depend
    /// on no heartbeat: see [`Consumer::inner_after_folds`]); else the
    /// folded frames and those kept inside are taken one by one in line
    /// order, as if their lines had been read (the others of the run only
    /// count and move the input's first and last time), so the result
    /// never depends on folding.
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
    /// both change its axis state). The run's times only go forward, the
    /// frames' too, so when the folds are taken whole no node was lost at
    /// any frame of the run either.
    fn inner_after_folds(&self, run: &FoldedRun<'_>) -> bool {
        run.folds
            .iter()
            .all(|f| nmt::error_control_node(f.id).is_some())
            && run.inner.iter().all(|i| {
                self.interest.wants(i.id(), false)
                    && self.emcy_node(i.id(), false).is_some()
                    && self.drives.slot(i.id(), false).is_none()
                    && !self.drives.watches(i.id())
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
        let mut rebounds = std::mem::take(&mut self.health.rebounds);
        let mut taken_as = std::mem::take(&mut self.health.taken_as);
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
                    _ => self.fold_pdos(f, at),
                }
            }
            // The groups looked at get the bounds found: nobody is due.
            if !rebounds.is_empty() {
                let mut groups = std::mem::take(&mut self.health.groups);
                self.health.deadlines.due_groups(run.latest, &mut groups);
                for &(g, earliest) in &rebounds {
                    self.health.deadlines.rebound(g, earliest);
                }
                groups.clear();
                self.health.groups = groups;
            }
        }
        self.health.rebounds = rebounds;
        self.health.taken_as = taken_as;
        #[cfg(test)]
        fold_tally::count(taken);
        taken
    }

    /// Whether [`Consumer::take_folded_run`] can take `run`'s folds (on
    /// the channel at `c`): each one heartbeats of a known node in the
    /// steady state its data says, each of them steady
    /// ([`HeartbeatMonitor::takes_fold`]), or a drive's PDOs that repeat,
    /// and every other node within its deadline at the last of them. Each
    /// fold's last time and node, and a heartbeat's new deadline, go to
    /// `taken_as` (one per fold, in order); when the schedule's bound
    /// passed, the groups looked at and their earliest deadline after the
    /// folds go to `rebounds`.
    ///
    /// [`HeartbeatMonitor::takes_fold`]: crate::timeline::heartbeat::HeartbeatMonitor::takes_fold
    fn takes_folds(
        &mut self,
        run: &FoldedRun<'_>,
        c: usize,
        taken_as: &mut Vec<TakenFold>,
        rebounds: &mut Vec<(u32, Option<Timestamp>)>,
    ) -> bool {
        // Index + 1 into the folds by node (0: not folded).
        let mut folded = [0u8; 128];
        for (i, f) in run.folds.iter().enumerate() {
            let last = f.last();
            let Some(node) = nmt::error_control_node(f.id) else {
                // A drive's PDOs (the frame path tries heartbeats first).
                if !(self.interest.wants(f.id, false) && self.takes_pdo_fold(run.channel, f)) {
                    return false;
                }
                taken_as.push(TakenFold {
                    last,
                    node: None,
                    deadline: None,
                });
                continue;
            };
            if f.len() != 1 {
                return false;
            }
            let byte = f.data() as u8;
            let Some(state) = NmtState::from_byte(byte).filter(|&s| s != NmtState::Initialising)
            else {
                return false;
            };
            if !self.interest.wants(f.id, false)
                || (!self.emcy_ids.is_empty() && self.emcy_node(f.id, false).is_some())
            {
                return false;
            }
            let Some(at) = self.nodes.node_index(c, node) else {
                return false;
            };
            let Some(h) = self
                .nodes
                .timeline_of(c, at, node)
                .and_then(|timeline| timeline.health_if_any())
            else {
                return false;
            };
            if !h.nmt.steady(state) {
                return false;
            }
            let Some(deadline) = h
                .heartbeat
                .takes_fold(f.first(), f.max_gap(), last, run.latest)
            else {
                return false;
            };
            taken_as.push(TakenFold {
                last,
                node: Some((node, at)),
                deadline: Some(deadline),
            });
            if let Some(slot) = folded.get_mut(usize::from(node)) {
                *slot = u8::try_from(i + 1).unwrap_or(0);
            }
        }
        let latest = run.latest;
        if !self.health.passed(latest) {
            // Every deadline is after the bound, the bound not before `latest`.
            return true;
        }
        let channel = self.nodes.channel_id_at(c);
        let HealthState { deadlines, .. } = &self.health;
        for g in deadlines.passed_groups(latest) {
            let mut earliest: Option<Timestamp> = None;
            for &(id, node) in deadlines.members(g) {
                // A folded node's deadline is the one after its fold
                // (checked above not to pass).
                let after_fold = (Some(id) == channel)
                    .then(|| folded.get(usize::from(node)))
                    .flatten()
                    .and_then(|&i| taken_as.get(usize::from(i).checked_sub(1)?))
                    .map(|t| t.deadline);
                let deadline = match after_fold {
                    Some(d) => d,
                    None => self
                        .nodes
                        .slot_by_id(id, node)
                        .and_then(|slot| slot.timeline.health())
                        .and_then(|h| h.heartbeat.deadline()),
                };
                match deadline {
                    Some(d) if after_fold.is_none() && latest > d => return false,
                    Some(d) => earliest = Some(earliest.map_or(d, |e| e.min(d))),
                    None => {}
                }
            }
            rebounds.push((g, earliest));
        }
        true
    }

    /// A boot-up: the node's NMT state and heartbeat monitor (its EMCY
    /// timeline has been told).
    pub(super) fn boot_health(
        &mut self,
        raw: &[u8],
        node: NodeId,
        at: At,
    ) -> Result<(), OutputError> {
        let slot = self.nodes.get(raw, node);
        let h = slot.timeline.health_mut(self.opts.heartbeat_timeout);
        let early = sign_of_life(h, at, true, &mut self.health.events);
        let change = h
            .nmt
            .heartbeat(NmtState::Initialising, &mut self.health.warnings);
        nmt_event(change, at, &mut self.health.events);
        self.health.schedule(slot.channel_id, node, h);
        emit(
            self.sink,
            self.file,
            self.opts,
            slot.channel,
            node,
            &mut self.health.events,
        )?;
        self.outage_after_its_end(node, "boot-up", at, early);
        self.nmt_warnings(node, at.line);
        Ok(())
    }

    /// The diagnostic for a sign of life (`what`, at `at`) that ended an
    /// outage starting later, at `start` ([`sign_of_life`]).
    fn outage_after_its_end(&mut self, node: NodeId, what: &str, at: At, start: Option<Timestamp>) {
        let Some(start) = start else { return };
        let now = at.time.map_or_else(String::new, |t| format!(" at {t}"));
        let msg = format!(
            "node {node}: {what}{now} ends a heartbeat outage that began later, at {start}: the \
             trace's clock went backwards (the outage's duration is negative)"
        );
        self.diags.report(self.log, true, at.line, msg);
    }

    /// NMT warnings as diagnostics at `line`.
    fn nmt_warnings(&mut self, node: NodeId, line: u64) {
        for w in std::mem::take(&mut self.health.warnings) {
            self.diags
                .report(self.log, true, line, format!("node {node}: {w}"));
        }
    }

    /// A remote request on a standard id: on 0x700 + node, node guarding.
    pub(super) fn remote_frame(&mut self, raw: &[u8], id: u32) {
        if let Some(node) = nmt::error_control_node(id) {
            self.nodes
                .get(raw, node)
                .timeline
                .health_mut(self.opts.heartbeat_timeout)
                .nmt
                .guard_request();
        }
    }

    /// A data frame that is neither EMCY, SDO nor boot-up: a heartbeat or
    /// guarding reply on 0x700 + node, or an NMT command on 0x000.
    pub(super) fn nmt_frame(
        &mut self,
        raw: &[u8],
        id: u32,
        data: &[u8],
        at: At,
    ) -> Result<(), OutputError> {
        if let Some((command, target)) = nmt::parse_command(id, data) {
            return self.nmt_command(raw, command, target, at);
        }
        let Some(ec) = nmt::parse_error_control(id, data) else {
            return Ok(());
        };
        let (ErrorControl::Heartbeat { node, .. } | ErrorControl::Unknown { node, .. }) = ec;
        let slot = self.nodes.get(raw, node);
        let h = slot.timeline.health_mut(self.opts.heartbeat_timeout);
        // Nearly every heartbeat: same state, in time. Its deadline moves
        // on; the schedule catches up lazily.
        if let ErrorControl::Heartbeat { state, .. } = ec
            && h.nmt.steady(state)
            && h.heartbeat.steady(at)
        {
            return Ok(());
        }
        let events = &mut self.health.events;
        let warnings = &mut self.health.warnings;
        let mut undefined = None;
        let mut early = None;
        if h.nmt.guard_asked() {
            let byte = data.first().copied().unwrap_or_default();
            let reply = nmt::guard_reply(byte);
            if reply.state.is_none() {
                undefined = Some(byte);
            }
            nmt_event(h.nmt.guard_reply(reply, warnings), at, events);
        } else {
            match ec {
                ErrorControl::Heartbeat { state, .. } => {
                    early = sign_of_life(h, at, false, events);
                    nmt_event(h.nmt.heartbeat(state, warnings), at, events);
                }
                ErrorControl::Unknown { byte, .. } => undefined = Some(byte),
            }
        }
        self.health.schedule(slot.channel_id, node, h);
        emit(
            self.sink,
            self.file,
            self.opts,
            slot.channel,
            node,
            &mut self.health.events,
        )?;
        self.outage_after_its_end(node, "heartbeat", at, early);
        if let Some(byte) = undefined {
            self.health.warnings.clear();
            self.diags.report(
                self.log,
                true,
                at.line,
                format!("node {node}: NMT error control byte 0x{byte:02X} names no NMT state"),
            );
        }
        self.nmt_warnings(node, at.line);
        Ok(())
    }

    /// An NMT command: what the master asked of one node or of every node
    /// the channel has seen.
    fn nmt_command(
        &mut self,
        raw: &[u8],
        command: nmt::Command,
        target: Target,
        at: At,
    ) -> Result<(), OutputError> {
        let nodes: Vec<NodeId> = match target {
            Target::Node(n) => vec![n],
            Target::All => self.nodes.nodes_of(raw),
        };
        for node in nodes {
            if node == 0 {
                continue;
            }
            let slot = self.nodes.get(raw, node);
            let h = slot.timeline.health_mut(self.opts.heartbeat_timeout);
            nmt_event(h.nmt.command(command), at, &mut self.health.events);
            emit(
                self.sink,
                self.file,
                self.opts,
                slot.channel,
                node,
                &mut self.health.events,
            )?;
        }
        Ok(())
    }

    /// An SDO frame (on a CAN SDO id, or parsed from another transport by
    /// [`sdo::parse_payload`]) on channel `raw` at `at`: aborts, values of
    /// the followed objects, the error history, heartbeat times.
    pub(in crate::analyze) fn sdo_access(
        &mut self,
        raw: &[u8],
        at: At,
        access: Sdo,
    ) -> Result<(), OutputError> {
        self.axis_sdo(raw, at, &access)?;
        let written = matches!(access, Sdo::Written { .. });
        if let Sdo::Aborted {
            node,
            object,
            code,
            by_server,
        } = access
        {
            self.sdo_abort(raw, node, object, code, by_server, at)?;
        }
        if let Some((node, object, value)) = self.sdo.feed(access) {
            self.object_value(node, object, value);
            self.health_object_value(raw, node, object, value, written, at)?;
        }
        Ok(())
    }

    fn sdo_abort(
        &mut self,
        raw: &[u8],
        node: NodeId,
        object: sdo::Object,
        code: u32,
        by_server: bool,
        at: At,
    ) -> Result<(), OutputError> {
        let slot = self.nodes.get(raw, node);
        self.health.events.push((
            at,
            Health::SdoAbort {
                index: object.index,
                subindex: object.sub,
                abort_code: code,
                text: sdo_abort::describe(code),
                by_server,
            },
        ));
        if object.index == sdo::ERROR_HISTORY {
            // The read-out going on will not finish.
            let h = slot.timeline.health_mut(self.opts.heartbeat_timeout);
            h.history.flush(&mut self.health.read_outs);
        }
        let id = slot.channel_id;
        self.read_outs_out(id, node, at);
        let slot = self.nodes.get(raw, node);
        emit(
            self.sink,
            self.file,
            self.opts,
            slot.channel,
            node,
            &mut self.health.events,
        )
    }

    /// A value of 0x1003, 0x1016 or 0x1017 a node holds (uploaded, or a
    /// confirmed write when `written`).
    fn health_object_value(
        &mut self,
        raw: &[u8],
        node: NodeId,
        object: sdo::Object,
        value: u32,
        written: bool,
        at: At,
    ) -> Result<(), OutputError> {
        match object.index {
            sdo::ERROR_HISTORY => {
                let slot = self.nodes.get(raw, node);
                let h = slot.timeline.health_mut(self.opts.heartbeat_timeout);
                let done = &mut self.health.read_outs;
                match (object.sub, written) {
                    (0, true) if value == 0 => {
                        h.history.cleared(done);
                        self.health.events.push((at, Health::ErrorHistoryCleared));
                    }
                    (0, true) => {}
                    (0, false) => h.history.count(value, at, done),
                    (sub, false) => h.history.entry(sub, value, at, done),
                    (_, true) => {}
                }
                let cleared = written && object.sub == 0 && value == 0;
                let id = slot.channel_id;
                self.read_outs_out(id, node, at);
                if cleared {
                    // Known empty from here.
                    let slot = self.nodes.get(raw, node);
                    slot.timeline
                        .health_mut(self.opts.heartbeat_timeout)
                        .last_read_out = Some(ReadOut {
                        entries: Vec::new(),
                        count: Some(0),
                        complete: true,
                        at,
                    });
                }
                let slot = self.nodes.get(raw, node);
                emit(
                    self.sink,
                    self.file,
                    self.opts,
                    slot.channel,
                    node,
                    &mut self.health.events,
                )
            }
            sdo::CONSUMER_HEARTBEAT if object.sub > 0 => {
                let producer = ((value >> 16) & 0xFF) as NodeId;
                if (1..=127).contains(&producer) {
                    self.set_timeout(raw, producer, |h| {
                        h.heartbeat.set_consumer_ms((value & 0xFFFF) as u16)
                    });
                }
                Ok(())
            }
            sdo::PRODUCER_HEARTBEAT if object.sub == 0 => {
                self.set_timeout(raw, node, |h| {
                    h.heartbeat.set_producer_ms((value & 0xFFFF) as u16)
                });
                Ok(())
            }
            _ => Ok(()),
        }
    }

    fn set_timeout(&mut self, raw: &[u8], node: NodeId, set: impl FnOnce(&mut NodeHealth)) {
        let slot = self.nodes.get(raw, node);
        let h = slot.timeline.health_mut(self.opts.heartbeat_timeout);
        set(h);
        self.health.schedule(slot.channel_id, node, h);
    }

    /// Read-outs finished by the frame at `now` become events at it (one
    /// it interrupted ended there, after the events before: events stay in
    /// line order) and the node's last read-out (which keeps its own
    /// line): codes the node never raised in the trace are marked as older
    /// than it.
    fn read_outs_out(&mut self, channel_id: u32, node: NodeId, now: At) {
        if self.health.read_outs.is_empty() {
            return;
        }
        let profile = self.profiles.get(node).profile;
        let Some(slot) = self.nodes.slot_by_id(channel_id, node) else {
            return;
        };
        for mut r in self.health.read_outs.drain(..) {
            for e in &mut r.entries {
                e.before_trace = !slot.timeline.has_raised(e.code);
            }
            let report = history_report(&r, |code| profile.describe(code));
            self.health.events.push((now, Health::ErrorHistory(report)));
            slot.timeline
                .health_mut(self.opts.heartbeat_timeout)
                .last_read_out = Some(r);
        }
    }

    /// The end of the input: nodes silent past their deadline are lost,
    /// read-outs going on end as partial (their events at the last line,
    /// after every event before; the node keeps the read-out's own line).
    pub(super) fn finish_health(&mut self) -> Result<(), OutputError> {
        let line = self.line_base;
        if let Some(end) = self.last_time {
            self.deadlines_passed(end, line)?;
        }
        let end = At {
            time: self.last_time,
            line,
        };
        let reading: Vec<(u32, NodeId)> = self
            .nodes
            .channels
            .iter()
            .flat_map(|ch| {
                ch.nodes
                    .iter()
                    .filter(|(_, tl)| tl.health().is_some_and(|h| h.history.is_reading()))
                    .map(|(node, _)| (ch.id, *node))
            })
            .collect();
        for (id, node) in reading {
            let Some(slot) = self.nodes.slot_by_id(id, node) else {
                continue;
            };
            slot.timeline
                .health_mut(self.opts.heartbeat_timeout)
                .history
                .flush(&mut self.health.read_outs);
            self.read_outs_out(id, node, end);
            let Some(slot) = self.nodes.slot_by_id(id, node) else {
                continue;
            };
            emit(
                self.sink,
                self.file,
                self.opts,
                slot.channel,
                node,
                &mut self.health.events,
            )?;
        }
        Ok(())
    }
}

/// A read-out as reported, each code described by `describe`.
pub(super) fn history_report(r: &ReadOut, describe: impl Fn(u16) -> String) -> HistoryReport {
    HistoryReport {
        entries: r
            .entries
            .iter()
            .map(|e| HistoryItem {
                code: e.code,
                info: e.info,
                description: describe(e.code),
                before_trace: e.before_trace,
            })
            .collect(),
        count: r.count,
        complete: r.complete,
        time: r.at.time,
        line: r.at.line,
    }
}

/// The health half of a node's report (descriptions of its history come
/// with its profile, later).
pub(super) fn report_health(report: &mut NodeReport, health: Option<Box<NodeHealth>>) {
    let Some(h) = health else { return };
    report.nmt_state = h.nmt.state();
    if h.heartbeat.monitored() {
        report.heartbeat = Some(HeartbeatReport {
            period: h.heartbeat.period(),
            timeout: h.heartbeat.timeout(),
            lost: h.heartbeat.lost_count(),
            outages: h.heartbeat.outages().to_vec(),
            silent_at_end: h.heartbeat.is_lost(),
        });
    }
    report.error_history = h
        .last_read_out
        .as_ref()
        .map(|r| history_report(r, |_| String::new()));
    report.axis = h
        .axis
        .as_deref()
        .map(|a| Box::new(super::axis::report_axis(a)));
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
