//! The NMT monitor: what frames on 0x000 and 0x700 + node do to a node's
//! NMT state and heartbeat (boot-ups, heartbeats, node guarding, NMT
//! commands), the heartbeat deadlines and the events that says. Kept apart
//! from the EMCY path (the hot one); its own fast paths are the steady
//! heartbeat and the folded runs of them.

use std::collections::HashMap;
use std::io::Write;

use super::context::{Emit, Fact, Facts, Monitor, Seen, Step};
use super::deadlines::Deadlines;
use crate::analyze::analysis::OutputError;
use crate::analyze::event::{GuardingReport, Health, HeartbeatReport, NodeReport, Unanswered};
use crate::analyze::nodes::Nodes;
use crate::analyze::options::Options;
use crate::canopen::NodeId;
use crate::canopen::emcy;
use crate::canopen::nmt::{self, Command, ErrorControl, NmtState, Target};
use crate::canopen::sdo;
use crate::timeline::At;
use crate::timeline::health::NodeHealth;
use crate::timeline::heartbeat::{Back, Lost, Supervision, TimeoutSource};
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
    /// What the master sent to ids that have not spoken, by channel (the
    /// trace's bytes) and id: at most 127 entries a channel.
    addressed: HashMap<Box<[u8]>, HashMap<NodeId, Addressed>>,
    /// At the end: what went to ids that never spoke.
    unanswered: Vec<Unanswered>,
}

/// What the master sent to an id that has not spoken (yet). A node exists
/// once it speaks; until then an NMT command or a guard request to its id
/// is not its story (the trace cannot tell whether anything was on the bus
/// to receive it), only counted here, a few facts per id. When the id
/// speaks these are dropped, except what shapes how its frames read: a
/// guard request waiting makes its first frame a guarding reply, and a
/// consumer heartbeat time set for it is its timeout. When it never
/// speaks, the counts become the input's [`Unanswered`].
#[derive(Clone, Copy, Debug, Default)]
struct Addressed {
    /// Commands by [`Command::index`], guard requests last.
    sent: [u64; 6],
    /// The line of the first of each (0: none sent).
    first_line: [u64; 6],
    /// The line of a guard request waiting for its reply.
    guard_asked: Option<u64>,
    /// A consumer heartbeat time (0x1016, ms) naming it.
    consumer_ms: Option<u16>,
}

/// Where guard requests are counted in [`Addressed::sent`].
const GUARD_REQUESTS: usize = 5;

impl Addressed {
    /// One more of kind `i` sent, at `line`.
    fn sent_at(&mut self, i: usize, line: u64) {
        if let (Some(n), Some(first)) = (self.sent.get_mut(i), self.first_line.get_mut(i)) {
            if *n == 0 {
                *first = line;
            }
            *n += 1;
        }
    }
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

    /// The node that answered by SDO exists; heartbeat times set by SDO:
    /// the consumer times (0x1016) and the producer time (0x1017); node
    /// guarding's guard time (0x100C) and life time factor (0x100D).
    fn learn<E: Write>(
        &mut self,
        channel: &[u8],
        at: At,
        fact: Fact,
        nodes: &mut Nodes,
        _facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        // Every fact comes from the node's own SDO response (an upload, or
        // the confirmation of a write): it spoke, so it is a node. (SDO
        // traffic about objects the decoder does not follow is only timed,
        // never decoded, so those responses make no node.)
        if let Fact::Produced { node } = fact {
            let slot = nodes.get(channel, node);
            let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
            nmt_event(h.nmt.produced(), at, &mut self.events);
            return emit.health(slot.channel, node, &mut self.events);
        }
        let node = match fact {
            Fact::Read { node, .. } | Fact::Holds { node, .. } | Fact::Written { node, .. } => node,
            Fact::Produced { node } => node,
        };
        nodes.get(channel, node);
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
                let ms = (value & 0xFFFF) as u16;
                if !(1..=127).contains(&producer) {
                    return Ok(());
                }
                let name = nodes.get(channel, node).channel;
                emit.incidents.consumes_heartbeat(name, node, producer);
                if nodes.known(channel, producer).is_some() {
                    self.set_timeout(channel, producer, nodes, timeout, |h| {
                        h.heartbeat.set_consumer_ms(ms)
                    });
                } else {
                    // A producer that has not spoken is no node yet: the
                    // time waits for it.
                    self.addressed(channel, producer, nodes).consumer_ms = Some(ms);
                }
            }
            sdo::GUARD_TIME if object.sub == 0 => {
                self.set_timeout(channel, node, nodes, timeout, |h| {
                    h.heartbeat.set_guard_time_ms((value & 0xFFFF) as u16)
                });
            }
            sdo::LIFE_TIME_FACTOR if object.sub == 0 => {
                self.set_timeout(channel, node, nodes, timeout, |h| {
                    h.heartbeat.set_life_time_factor((value & 0xFF) as u8)
                });
            }
            sdo::PRODUCER_HEARTBEAT if object.sub == 0 => {
                self.set_timeout(channel, node, nodes, timeout, |h| {
                    h.heartbeat.set_producer_ms((value & 0xFFFF) as u16)
                });
            }
            // An RPDO's COB-ID: whose PDOs the node waits for (0x8250).
            0x1400..=0x15FF if object.sub == 1 && value & 0x8000_0000 == 0 => {
                let name = nodes.get(channel, node).channel;
                emit.incidents.consumes_pdo(name, node, value & 0x7FF);
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
        if let Some(time) = end.time {
            self.deadlines_passed(time, end.line, nodes, emit)?;
        }
        self.unanswered_at_end(end.line, nodes, emit);
        Ok(())
    }

    fn report(&self, report: &mut NodeReport, health: Option<&NodeHealth>) {
        let Some(h) = health else { return };
        report.nmt_state = h.nmt.state();
        report.nmt_commanded = h.nmt.commanded();
        if h.heartbeat.monitored() {
            let via = h.heartbeat.supervision();
            let counts = h.nmt.guard_counts();
            report.heartbeat = Some(HeartbeatReport {
                via,
                period: h.heartbeat.period(),
                configured_period: h.heartbeat.configured_period(),
                drifts: h.heartbeat.drifts(),
                guarding: (via == Supervision::Guarding || counts.requests > 0).then_some(
                    GuardingReport {
                        life_time_factor: h.heartbeat.life_time_factor(),
                        counts,
                    },
                ),
                timeout: h.heartbeat.timeout(),
                lost: h.heartbeat.lost_count(),
                outages: h.heartbeat.outages().to_vec(),
                silent_at_end: h.heartbeat.is_lost(),
            });
        }
    }
}

fn lost_event(
    lost: Lost,
    line: u64,
    timeout: Option<(Span, TimeoutSource)>,
    via: Supervision,
) -> (At, Health) {
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
            via,
        },
    )
}

fn back_event(back: Back, at: At, via: Supervision) -> (At, Health) {
    (
        at,
        Health::HeartbeatBack {
            silent: back.silent,
            restarted: back.restarted,
            via,
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
    let via = h.heartbeat.supervision();
    let (newly, back) = if boot {
        h.heartbeat.boot(at)
    } else {
        h.heartbeat.seen(at)
    };
    if let Some(lost) = newly {
        events.push(lost_event(lost, at.line, timeout, via));
    }
    let back = back?;
    events.push(back_event(back, at, via));
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
            let via = h.heartbeat.supervision();
            if let Some(lost) = h.heartbeat.check(now) {
                self.events.push(lost_event(lost, line, timeout, via));
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
    /// as much (measured in docs/performance.md), once the dispatcher found
    /// nothing else due (`Consumer::frame_path_due`). `None`: not that
    /// case, nothing was changed.
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
        let first = slot.timeline.health().is_none();
        let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
        if first {
            self.spoke(raw, node, h);
        }
        let early = sign_of_life(h, at, true, &mut self.events);
        nmt_event(Some(h.nmt.boot_up()), at, &mut self.events);
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

    /// A remote request on a standard id at `line`: on 0x700 + node, node
    /// guarding's guard request. It asks; it does not make a node.
    pub(in crate::analyze) fn remote_frame<E: Write>(
        &mut self,
        raw: &[u8],
        id: u32,
        line: u64,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) {
        let Some(node) = nmt::error_control_node(id) else {
            return;
        };
        let timeout = emit.opts.heartbeat_timeout;
        match nodes.known(raw, node) {
            Some(timeline) => {
                let h = timeline.health_mut(timeout);
                h.nmt.guard_request(line, &mut self.warnings);
            }
            None => {
                let a = self.addressed(raw, node, nodes);
                a.sent_at(GUARD_REQUESTS, line);
                a.guard_asked = Some(line);
            }
        }
        self.nmt_warnings(node, line, emit);
    }

    /// The facts kept of what was sent to `node` on `raw` before it spoke.
    /// Each id kept counts against the node table's bound: a trace that
    /// addresses a million silent ids on a million channels grows this
    /// table as one that names them grows the node table.
    fn addressed(&mut self, raw: &[u8], node: NodeId, nodes: &mut Nodes) -> &mut Addressed {
        // The channel's name is copied for the key on every call: only
        // commands to ids that never spoke come here, never a hot path.
        let ids = self.addressed.entry(raw.into()).or_default();
        if !ids.contains_key(&node) {
            nodes.count_kept_elsewhere();
        }
        ids.entry(node).or_default()
    }

    /// `node` on `raw` spoke for the first time to this monitor (its health
    /// is new): what was sent to it before that shapes how its frames read
    /// (see [`Addressed`]).
    fn spoke(&mut self, raw: &[u8], node: NodeId, h: &mut NodeHealth) {
        if self.addressed.is_empty() {
            return;
        }
        let Some(a) = self
            .addressed
            .get_mut(raw)
            .and_then(|ids| ids.remove(&node))
        else {
            return;
        };
        if let Some(line) = a.guard_asked {
            h.nmt.guard_request(line, &mut self.warnings);
        }
        if let Some(ms) = a.consumer_ms {
            h.heartbeat.set_consumer_ms(ms);
        }
    }

    /// The end of the input (its last line `line`): what was sent to ids
    /// that never spoke (no frame of theirs made a node), one diagnostic
    /// per command, at the last line (diagnostics come in line order) and
    /// naming the line of the first one sent, where a reader finds it.
    fn unanswered_at_end<E: Write>(
        &mut self,
        line: u64,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) {
        let mut sent = [0u64; 6];
        let mut ids = [0u64; 6];
        let mut first = [u64::MAX; 6];
        for (raw, addressed) in &self.addressed {
            for (&node, a) in addressed {
                // Spoken to another monitor (EMCY, SDO, PDO): a node.
                if nodes.known(raw, node).is_some() {
                    continue;
                }
                for i in 0..sent.len() {
                    if a.sent[i] > 0 {
                        sent[i] += a.sent[i];
                        ids[i] += 1;
                        first[i] = first[i].min(a.first_line[i]);
                    }
                }
            }
        }
        self.addressed = HashMap::new();
        let commands = Command::ALL.iter().map(|&c| Some(c));
        for (i, command) in commands.chain([None]).enumerate() {
            if sent[i] == 0 {
                continue;
            }
            let u = Unanswered {
                command,
                sent: sent[i],
                ids: ids[i],
            };
            let said = format!("{} (the first at line {})", u.sentence(), first[i]);
            emit.diagnostic(line, said);
            self.unanswered.push(u);
        }
    }

    /// What went to ids that never spoke ([`NmtMonitor::finish`] found it).
    pub(in crate::analyze) fn take_unanswered(&mut self) -> Vec<Unanswered> {
        std::mem::take(&mut self.unanswered)
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
        let first = slot.timeline.health().is_none();
        let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
        if first {
            self.spoke(raw, node, h);
        }
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
            // A reply is the guarded node's sign of life (life guarding).
            h.heartbeat.guarded();
            early = sign_of_life(h, at, false, events);
            nmt_event(h.nmt.guard_reply(reply, at.time, warnings), at, events);
        } else {
            match ec {
                ErrorControl::Heartbeat { state, .. } => {
                    early = sign_of_life(h, at, false, events);
                    nmt_event(h.nmt.heartbeat(state, at.time, warnings), at, events);
                }
                ErrorControl::Unknown { byte, .. } => undefined = Some(byte),
            }
        }
        let what = match h.heartbeat.supervision() {
            Supervision::Guarding => "guarding reply",
            Supervision::Heartbeat => "heartbeat",
        };
        self.schedule(slot.channel_id, node, h);
        emit.health(slot.channel, node, &mut self.events)?;
        outage_after_its_end(node, what, at, early, emit);
        if let Some(byte) = undefined {
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
            if nodes.known(raw, node).is_none() {
                // Addressed, not heard: no node (see `Addressed`).
                self.addressed(raw, node, nodes)
                    .sent_at(command.index(), at.line);
                continue;
            }
            let slot = nodes.get(raw, node);
            let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
            nmt_event(h.nmt.command(command, at.time), at, &mut self.events);
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
