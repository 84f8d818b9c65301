//! The NMT monitor: what frames on 0x000 and 0x700 + node do to a node's
//! NMT state and heartbeat (boot-ups, heartbeats, node guarding, NMT
//! commands), the heartbeat deadlines and the events that says. Kept apart
//! from the EMCY path (the hot one); its own fast paths are the steady
//! heartbeat and the folded runs of them.

use std::io::Write;

use super::context::{Emit, Fact, Facts, Monitor, Seen, Step};
use super::deadlines::Deadlines;
use crate::analyze::analysis::OutputError;
use crate::analyze::event::{Health, HeartbeatReport, NodeReport};
use crate::analyze::nodes::Nodes;
use crate::analyze::options::Options;
use crate::canopen::NodeId;
use crate::canopen::emcy;
use crate::canopen::nmt::{self, ErrorControl, NmtState, Target};
use crate::canopen::sdo;
use crate::timeline::At;
use crate::timeline::health::NodeHealth;
use crate::timeline::heartbeat::{Back, Lost, TimeoutSource};
use crate::timeline::nmt::{NmtChange, NmtWarning};
use crate::trace::{Fold, Frame, FrameKind, Interest, Span, Timestamp};

/// What the NMT monitor keeps besides each node's health (which the node
/// table holds).
#[derive(Default)]
pub(in crate::analyze) struct NmtMonitor {
    /// When monitored nodes may have passed their heartbeat deadline.
    deadlines: Deadlines,
    /// Buffers reused from frame to frame.
    events: Vec<(At, Health)>,
    warnings: Vec<NmtWarning>,
    groups: Vec<u32>,
    due: Vec<(Timestamp, u32, NodeId)>,
}

/// What taking a fold does, worked out once: the time of its last frame,
/// and for a heartbeat fold the node (and where it is in its channel) and
/// its new deadline.
#[derive(Clone, Copy)]
pub(in crate::analyze) struct TakenFold {
    pub(in crate::analyze) last: Timestamp,
    pub(in crate::analyze) node: Option<(NodeId, usize)>,
    pub(in crate::analyze) deadline: Option<Timestamp>,
}

impl Monitor for NmtMonitor {
    fn new(_opts: &Options) -> Self {
        NmtMonitor::default()
    }

    /// Boot-ups (whose EMCY side the EMCY monitor took first), heartbeats,
    /// guarding replies and NMT commands.
    fn frame<E: Write>(
        &mut self,
        frame: &Seen<'_>,
        nodes: &mut Nodes,
        _facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<Step, OutputError> {
        if frame.extended {
            return Ok(Step::Pass);
        }
        if let Some(node) = emcy::boot_node(frame.id, frame.data) {
            self.boot(frame.channel, node, frame.at, nodes, emit)?;
            return Ok(Step::Done);
        }
        self.nmt_frame(frame, nodes, emit)
    }

    /// Heartbeat times set by SDO: the consumer times (0x1016) and the
    /// producer time (0x1017).
    fn learn<E: Write>(
        &mut self,
        channel: &[u8],
        _at: At,
        fact: Fact,
        nodes: &mut Nodes,
        _facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        let Fact::Holds {
            node,
            object,
            value,
            ..
        } = fact
        else {
            return Ok(());
        };
        let timeout = emit.opts.heartbeat_timeout;
        match object.index {
            sdo::CONSUMER_HEARTBEAT if object.sub > 0 => {
                let producer = ((value >> 16) & 0xFF) as NodeId;
                if (1..=127).contains(&producer) {
                    self.set_timeout(channel, producer, nodes, timeout, |h| {
                        h.heartbeat.set_consumer_ms((value & 0xFFFF) as u16)
                    });
                }
            }
            sdo::PRODUCER_HEARTBEAT if object.sub == 0 => {
                self.set_timeout(channel, node, nodes, timeout, |h| {
                    h.heartbeat.set_producer_ms((value & 0xFFFF) as u16)
                });
            }
            _ => {}
        }
        Ok(())
    }

    /// Nodes silent past their deadline at the end are lost.
    fn finish<E: Write>(
        &mut self,
        end: At,
        nodes: &mut Nodes,
        _facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        match end.time {
            Some(time) => self.deadlines_passed(time, end.line, nodes, emit),
            None => Ok(()),
        }
    }

    fn report(&self, report: &mut NodeReport, health: Option<&NodeHealth>) {
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
    }
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
/// is negative, which [`outage_after_its_end`] says.
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

impl NmtMonitor {
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
    pub(in crate::analyze) fn passed(&self, now: Timestamp) -> bool {
        self.deadlines.passed(now)
    }

    /// The trace's clock reached `now` (a frame at `line`): every node whose
    /// deadline passed is lost, in the order of the deadlines.
    pub(in crate::analyze) fn deadlines_passed<E: Write>(
        &mut self,
        now: Timestamp,
        line: u64,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        let mut groups = std::mem::take(&mut self.groups);
        let mut due = std::mem::take(&mut self.due);
        self.deadlines.due_groups(now, &mut groups);
        for g in groups.drain(..) {
            let mut earliest: Option<Timestamp> = None;
            for &(id, node) in self.deadlines.members(g) {
                let deadline = nodes
                    .slot_by_id(id, node)
                    .and_then(|slot| slot.timeline.health())
                    .and_then(|h| h.heartbeat.deadline());
                match deadline {
                    Some(d) if now > d => due.push((d, id, node)),
                    Some(d) => earliest = Some(earliest.map_or(d, |e| e.min(d))),
                    None => {}
                }
            }
            self.deadlines.rebound(g, earliest);
        }
        due.sort_unstable();
        let result = self.lose(now, line, &mut due, nodes, emit);
        due.clear();
        self.groups = groups;
        self.due = due;
        result
    }

    /// The nodes in `due` passed their deadline at `now`: lost.
    fn lose<E: Write>(
        &mut self,
        now: Timestamp,
        line: u64,
        due: &mut Vec<(Timestamp, u32, NodeId)>,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        for (_, id, node) in due.drain(..) {
            let Some(slot) = nodes.slot_by_id(id, node) else {
                continue;
            };
            let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
            let timeout = h.heartbeat.timeout();
            if let Some(lost) = h.heartbeat.check(now) {
                self.events.push(lost_event(lost, line, timeout));
            }
            if self.events.is_empty() {
                continue;
            }
            emit.health(slot.channel, node, &mut self.events)?;
        }
        Ok(())
    }

    /// The common heartbeat (a node still in the state it was, before its
    /// deadline, nothing awaited of it): its deadline moves on and nothing
    /// else happens; its time, `Some`, is all the dispatcher has to count.
    /// Checked ahead of the general frame path, which costs several times
    /// as much (measured in docs/performance.md). `None`: not that case,
    /// nothing was changed.
    #[inline]
    pub(in crate::analyze) fn steady_heartbeat(
        &self,
        frame: &Frame<'_>,
        line: impl FnOnce() -> u64,
        decided: bool,
        interest: &Interest,
        facts: &Facts<'_>,
        nodes: &mut Nodes,
    ) -> Option<Timestamp> {
        let (Some(time), &[byte]) = (frame.time, frame.data.as_slice()) else {
            return None;
        };
        // A boot-up (0x00) is never steady: it restarts the node.
        let (Some(node), Some(state), FrameKind::Data, false) = (
            nmt::error_control_node(frame.id),
            NmtState::from_byte(byte).filter(|&s| s != NmtState::Initialising),
            frame.kind,
            frame.extended,
        ) else {
            return None;
        };
        if !decided
            || self.passed(time)
            || !interest.wants(frame.id, false)
            || facts.moved_emcy(frame.id)
        {
            return None;
        }
        let at = At {
            time: Some(time),
            line: line(),
        };
        let h = nodes
            .known(frame.channel, node)
            .and_then(|timeline| timeline.health_if_any())?;
        (h.nmt.steady(state) && h.heartbeat.steady(at)).then_some(time)
    }

    /// How a fold of heartbeats of `node` (on the channel at `c`, the run's
    /// latest time `latest`) is taken whole: the node is known, in the
    /// steady state its data says, each heartbeat steady
    /// ([`HeartbeatMonitor::takes_fold`]). `None`: it cannot be.
    ///
    /// [`HeartbeatMonitor::takes_fold`]: crate::timeline::heartbeat::HeartbeatMonitor::takes_fold
    pub(in crate::analyze) fn takes_heartbeat_fold(
        f: &Fold,
        node: NodeId,
        c: usize,
        latest: Timestamp,
        nodes: &mut Nodes,
    ) -> Option<TakenFold> {
        if f.len() != 1 {
            return None;
        }
        let byte = f.data() as u8;
        let state = NmtState::from_byte(byte).filter(|&s| s != NmtState::Initialising)?;
        let at = nodes.node_index(c, node)?;
        let h = nodes
            .timeline_of(c, at, node)
            .and_then(|timeline| timeline.health_if_any())?;
        if !h.nmt.steady(state) {
            return None;
        }
        let last = f.last();
        let deadline = h
            .heartbeat
            .takes_fold(f.first(), f.max_gap(), last, latest)?;
        Some(TakenFold {
            last,
            node: Some((node, at)),
            deadline: Some(deadline),
        })
    }

    /// Whether, with the folds of a run on the channel `channel` taken as
    /// `taken_as` says, every node is still within its deadline at the
    /// run's `latest` time. `folded[node]` is the index + 1 of the node's
    /// fold in `taken_as` (0: not folded). When the schedule's bound
    /// passed, the groups looked at and their earliest deadline after the
    /// folds go to `rebounds`.
    pub(in crate::analyze) fn deadlines_hold(
        &self,
        latest: Timestamp,
        channel: Option<u32>,
        folded: &[u8; 128],
        taken_as: &[TakenFold],
        rebounds: &mut Vec<(u32, Option<Timestamp>)>,
        nodes: &mut Nodes,
    ) -> bool {
        if !self.passed(latest) {
            // Every deadline is after the bound, the bound not before `latest`.
            return true;
        }
        for g in self.deadlines.passed_groups(latest) {
            let mut earliest: Option<Timestamp> = None;
            for &(id, node) in self.deadlines.members(g) {
                // A folded node's deadline is the one after its fold
                // (checked not to pass).
                let after_fold = (Some(id) == channel)
                    .then(|| folded.get(usize::from(node)))
                    .flatten()
                    .and_then(|&i| taken_as.get(usize::from(i).checked_sub(1)?))
                    .map(|t| t.deadline);
                let deadline = match after_fold {
                    Some(d) => d,
                    None => nodes
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

    /// The groups looked at while taking a run whose latest time is
    /// `latest` get the bounds found ([`NmtMonitor::deadlines_hold`]):
    /// nobody is due.
    pub(in crate::analyze) fn rebound(
        &mut self,
        latest: Timestamp,
        rebounds: &[(u32, Option<Timestamp>)],
    ) {
        if rebounds.is_empty() {
            return;
        }
        let mut groups = std::mem::take(&mut self.groups);
        self.deadlines.due_groups(latest, &mut groups);
        for &(g, earliest) in rebounds {
            self.deadlines.rebound(g, earliest);
        }
        groups.clear();
        self.groups = groups;
    }

    /// A boot-up: the node's NMT state and heartbeat monitor (its EMCY
    /// timeline has been told).
    fn boot<E: Write>(
        &mut self,
        raw: &[u8],
        node: NodeId,
        at: At,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        let slot = nodes.get(raw, node);
        let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
        let early = sign_of_life(h, at, true, &mut self.events);
        let change = h.nmt.heartbeat(NmtState::Initialising, &mut self.warnings);
        nmt_event(change, at, &mut self.events);
        self.schedule(slot.channel_id, node, h);
        emit.health(slot.channel, node, &mut self.events)?;
        outage_after_its_end(node, "boot-up", at, early, emit);
        self.nmt_warnings(node, at.line, emit);
        Ok(())
    }

    /// NMT warnings as diagnostics at `line`.
    fn nmt_warnings<E: Write>(&mut self, node: NodeId, line: u64, emit: &mut Emit<'_, E>) {
        for w in self.warnings.drain(..) {
            emit.diagnostic(line, format!("node {node}: {w}"));
        }
    }

    /// A remote request on a standard id: on 0x700 + node, node guarding.
    pub(in crate::analyze) fn remote_frame(
        raw: &[u8],
        id: u32,
        nodes: &mut Nodes,
        timeout: Option<Span>,
    ) {
        if let Some(node) = nmt::error_control_node(id) {
            nodes
                .get(raw, node)
                .timeline
                .health_mut(timeout)
                .nmt
                .guard_request();
        }
    }

    /// A data frame that is neither EMCY, SDO nor boot-up: a heartbeat or
    /// guarding reply on 0x700 + node, or an NMT command on 0x000.
    fn nmt_frame<E: Write>(
        &mut self,
        frame: &Seen<'_>,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) -> Result<Step, OutputError> {
        let (raw, data, at) = (frame.channel, frame.data, frame.at);
        if let Some((command, target)) = nmt::parse_command(frame.id, data) {
            self.nmt_command(raw, command, target, at, nodes, emit)?;
            return Ok(Step::Done);
        }
        let Some(ec) = nmt::parse_error_control(frame.id, data) else {
            return Ok(Step::Pass);
        };
        let (ErrorControl::Heartbeat { node, .. } | ErrorControl::Unknown { node, .. }) = ec;
        let slot = nodes.get(raw, node);
        let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
        // Nearly every heartbeat: same state, in time. Its deadline moves
        // on; the schedule catches up lazily.
        if let ErrorControl::Heartbeat { state, .. } = ec
            && h.nmt.steady(state)
            && h.heartbeat.steady(at)
        {
            return Ok(Step::Done);
        }
        let events = &mut self.events;
        let warnings = &mut self.warnings;
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
        self.schedule(slot.channel_id, node, h);
        emit.health(slot.channel, node, &mut self.events)?;
        outage_after_its_end(node, "heartbeat", at, early, emit);
        if let Some(byte) = undefined {
            self.warnings.clear();
            emit.diagnostic(
                at.line,
                format!("node {node}: NMT error control byte 0x{byte:02X} names no NMT state"),
            );
        }
        self.nmt_warnings(node, at.line, emit);
        Ok(Step::Done)
    }

    /// An NMT command: what the master asked of one node or of every node
    /// the channel has seen.
    fn nmt_command<E: Write>(
        &mut self,
        raw: &[u8],
        command: nmt::Command,
        target: Target,
        at: At,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        let targets: Vec<NodeId> = match target {
            Target::Node(n) => vec![n],
            Target::All => nodes.nodes_of(raw),
        };
        for node in targets {
            if node == 0 {
                continue;
            }
            let slot = nodes.get(raw, node);
            let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
            nmt_event(h.nmt.command(command), at, &mut self.events);
            emit.health(slot.channel, node, &mut self.events)?;
        }
        Ok(())
    }

    fn set_timeout(
        &mut self,
        raw: &[u8],
        node: NodeId,
        nodes: &mut Nodes,
        timeout: Option<Span>,
        set: impl FnOnce(&mut NodeHealth),
    ) {
        let slot = nodes.get(raw, node);
        let h = slot.timeline.health_mut(timeout);
        set(h);
        self.schedule(slot.channel_id, node, h);
    }
}

/// The diagnostic for a sign of life (`what`, at `at`) that ended an
/// outage starting later, at `start` ([`sign_of_life`]).
fn outage_after_its_end<E: Write>(
    node: NodeId,
    what: &str,
    at: At,
    start: Option<Timestamp>,
    emit: &mut Emit<'_, E>,
) {
    let Some(start) = start else { return };
    let now = at.time.map_or_else(String::new, |t| format!(" at {t}"));
    let msg = format!(
        "node {node}: {what}{now} ends a heartbeat outage that began later, at {start}: the \
         trace's clock went backwards (the outage's duration is negative)"
    );
    emit.diagnostic(at.line, msg);
}
