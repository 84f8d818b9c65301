//! Incidents: fault-like events of every node and of the bus that follow
//! each other within a gap on one channel, told as one story with the
//! event that started it (its root), the links that tie the others to
//! their causes, and a sentence. The builder hears every event before the
//! `--node`/`--channel` filters (an incident does not change with which
//! nodes are shown) and hands an incident on when it closes: at the first
//! followed frame or event after the trace's clock has passed its last
//! event by the gap (and by [`LATE_MS`], for events told after later
//! lines), or at the end of the input. The consumer asks [`Builder::passed`]
//! for every timed frame, and its fast paths (folded runs, steady
//! heartbeats) leave a frame past that time to the frame path, so the
//! output does not depend on how the input was split. The rules and their reasons are in docs/guide/incidents.md.

use std::collections::HashMap;
use std::fmt::Write as _;

use crate::canopen::NodeId;
use crate::timeline::At;
use crate::trace::{Span, Timestamp};

/// The default `--incident-gap`: events further apart start a new incident.
pub const DEFAULT_GAP_MS: u64 = 2_000;

/// How much longer an incident is held open than its gap: error bursts are
/// told when they close (a second after their last error frame) with the
/// time they began, and a heartbeat loss when the clock passed its
/// deadline, so both reach the builder after frames later than them.
pub const LATE_MS: u64 = 1_500;

/// Events an incident keeps (and the rules look at); the rest are counted.
pub const MAX_EVENTS: usize = 100;

/// Distinct incident roots an input report keeps (for `check`); the
/// incidents past them are told but not recorded.
pub const MAX_ROOTS: usize = 1024;

/// What started an incident, as a baseline records it: the same root in
/// two runs is the same trouble.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct RootKey {
    pub channel: String,
    pub node: Option<NodeId>,
    pub kind: &'static str,
    pub code: Option<u16>,
}

impl RootKey {
    /// `node 3 heartbeat_lost`, `node 5 emcy 0x8130`, `bus bus_error`.
    pub fn words(&self) -> String {
        let mut s = match self.node {
            Some(n) => format!("node {n} {}", self.kind),
            None => format!("bus {}", self.kind),
        };
        if let Some(c) = self.code {
            let _ = write!(s, " 0x{c:04X}");
        }
        s
    }
}

/// Channels with an open incident at once; an event of a channel past them
/// is counted in [`Builder::ignored`], not grouped.
pub const MAX_OPEN: usize = 256;

/// Events of several nodes this close are "at once" (a common cause, or
/// a tie the evidence cannot order).
const AT_ONCE_MS: u64 = 100;

/// A drive's fault and an EMCY of the same node this close are one fault.
const SAME_FAULT_MS: u64 = 500;

/// A boot-up this long after a reset command was the command's.
const COMMANDED_BOOT_MS: u64 = 10_000;

/// What an incident's event is; the JSON `kind`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// An error EMCY (not a reset).
    Emcy,
    /// The node's heartbeat or guarding deadline passed.
    HeartbeatLost,
    /// A node heard before booted again: nobody commanded it (an
    /// uncommanded boot); or, as context, the boot-up a reset caused.
    Boot,
    /// A node left operational on its own; or, as context, a master's
    /// NMT command.
    Nmt,
    /// A CiA 402 drive entered fault reaction active or fault.
    AxisFault,
    /// A burst of error frames.
    BusError,
    /// A controller left the bus.
    BusOff,
    /// Context only: the master reset a drive's fault.
    FaultReset,
    /// The SYNC producer skipped cycles.
    SyncMissed,
}

impl Kind {
    pub fn slug(self) -> &'static str {
        match self {
            Kind::Emcy => "emcy",
            Kind::HeartbeatLost => "heartbeat_lost",
            Kind::Boot => "boot",
            Kind::Nmt => "nmt",
            Kind::AxisFault => "axis_fault",
            Kind::BusError => "bus_error",
            Kind::BusOff => "bus_off",
            Kind::FaultReset => "fault_reset",
            Kind::SyncMissed => "sync_missed",
        }
    }
}

/// One event of an incident.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Occurrence {
    /// `None`: the bus's own (a burst, the logging controller's bus-off).
    pub node: Option<NodeId>,
    pub kind: Kind,
    /// The EMCY code, for an EMCY.
    pub code: Option<u16>,
    pub time: Timestamp,
    pub line: u64,
    /// A master's action (a command, the boot-up it caused, a fault
    /// reset): inside an incident, never its start nor its root.
    pub context: bool,
    /// For an EMCY 0x81xx, the start of the burst it belongs to; for a
    /// burst, its start.
    pub burst: Option<Timestamp>,
}

impl Occurrence {
    fn words(&self) -> String {
        let who = match self.node {
            Some(n) => format!("node {n}"),
            None => "the bus".to_string(),
        };
        match (self.kind, self.code) {
            (Kind::Emcy, Some(code)) => format!("{who} EMCY 0x{code:04X}"),
            (Kind::HeartbeatLost, _) => format!("{who} fell silent"),
            (Kind::Boot, _) if self.context => format!("{who} booted after a reset"),
            (Kind::Boot, _) => format!("{who} rebooted on its own"),
            (Kind::Nmt, _) if self.context => format!("NMT command to {who}"),
            (Kind::Nmt, _) => format!("{who} left operational"),
            (Kind::AxisFault, _) => format!("{who} drive fault"),
            (Kind::BusError, _) => "error frames".to_string(),
            (Kind::BusOff, _) if self.node.is_none() => {
                "the logging controller went bus-off".to_string()
            }
            (Kind::BusOff, _) => format!("{who} went bus-off"),
            (Kind::FaultReset, _) => format!("fault reset of {who}"),
            (Kind::SyncMissed, _) => "SYNC skipped cycles".to_string(),
            (Kind::Emcy, None) => format!("{who} EMCY"),
        }
    }
}

/// A cause: `from` follows from `to` (indices into the incident's events).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Link {
    pub from: usize,
    pub to: usize,
    pub reason: String,
}

/// The event that started an incident.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Root {
    /// Index into the events: the root, or the earliest candidate when
    /// undecided.
    pub event: usize,
    pub reason: String,
    /// More than one: the evidence does not decide between them.
    pub candidates: Vec<usize>,
}

impl Root {
    pub fn decided(&self) -> bool {
        self.candidates.len() <= 1
    }
}

/// A closed incident.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Incident {
    pub channel: String,
    pub start: Timestamp,
    pub end: Timestamp,
    /// Every node with an event in it, ascending.
    pub nodes: Vec<NodeId>,
    /// The first [`MAX_EVENTS`] events, in time order.
    pub events: Vec<Occurrence>,
    pub events_total: u64,
    pub links: Vec<Link>,
    pub root: Root,
    /// The earliest event that is not context.
    pub first: usize,
    pub summary: String,
}

/// What one node said last, for the rules that need its past.
#[derive(Clone, Copy, Debug, Default)]
struct NodePast {
    operational: bool,
    reset_commanded: Option<Timestamp>,
}

#[derive(Debug)]
struct Open {
    end: Timestamp,
    events: Vec<Occurrence>,
    total: u64,
    faults: u64,
}

/// Groups events into incidents. Fed by the monitors' [`Emit`]; closed
/// incidents wait in [`Builder::closed`] for the consumer to tell them.
///
/// [`Emit`]: super::monitor::context::Emit
#[derive(Debug)]
pub struct Builder {
    gap: Span,
    /// Open incidents by channel: a list searched by name, not a hash map,
    /// since every error EMCY looks its channel up here and traces have a
    /// few channels (hashing the name cost 8% of the instructions on an
    /// EMCY-heavy trace; docs/performance.md).
    open: Vec<(String, Open)>,
    /// By channel, then node: looked up by `&str`, with no allocation per
    /// event (EMCY storms feed every frame here).
    past: HashMap<String, HashMap<NodeId, NodePast>>,
    /// The producers a node consumes: heartbeats (0x1016) and RPDOs
    /// (0x1400 sub 1, by the predefined COB-IDs), per channel and node.
    consumes: HashMap<(String, NodeId), Consumed>,
    /// When the first open incident is due to close, or earlier: an
    /// event that moves an incident's end leaves it (recomputing it for
    /// every EMCY of a storm cost more than the rest of the builder), and
    /// [`Builder::tick`] finds the incidents really due when it has passed.
    due: Option<Timestamp>,
    pub closed: Vec<Incident>,
    /// Events not grouped: their channel came past [`MAX_OPEN`].
    pub ignored: u64,
    /// Incidents closed, over the input.
    pub count: u64,
    /// Incidents told (their nodes and channel selected).
    pub told: u64,
    /// The roots of the incidents told, with how many each started.
    pub roots: std::collections::BTreeMap<RootKey, u64>,
}

#[derive(Clone, Debug, Default)]
struct Consumed {
    heartbeat: Vec<NodeId>,
    rpdo: Vec<NodeId>,
}

impl Builder {
    pub fn new(gap: Span) -> Builder {
        Builder {
            gap,
            open: Vec::new(),
            past: HashMap::new(),
            consumes: HashMap::new(),
            due: None,
            closed: Vec::new(),
            ignored: 0,
            count: 0,
            told: 0,
            roots: std::collections::BTreeMap::new(),
        }
    }

    /// What is known of `node`'s past on `channel`, made on first use. (Only
    /// NMT states come here, a few per node: the channel's name is copied
    /// for the lookup.)
    fn past(&mut self, channel: &str, node: NodeId) -> &mut NodePast {
        self.past
            .entry(channel.to_owned())
            .or_default()
            .entry(node)
            .or_default()
    }

    /// An error EMCY (codes other than 0x0000).
    pub fn emcy(
        &mut self,
        channel: &str,
        node: NodeId,
        code: u16,
        at: At,
        burst: Option<Timestamp>,
    ) {
        if code == 0 {
            self.tick(at.time);
            return;
        }
        self.occur(
            channel,
            Some(node),
            Kind::Emcy,
            Some(code),
            at,
            false,
            burst,
        );
    }

    /// A boot-up: a fault when the node was heard before (`heard`, as the
    /// node table knows) and no reset was commanded shortly before; the
    /// reset's context when one was.
    pub fn boot(&mut self, channel: &str, node: NodeId, heard: bool, at: At) {
        self.tick(at.time);
        // Only nodes whose NMT state was told have a past here: a trace of
        // a hundred thousand channels of EMCYs keeps none.
        let past = match self.past.get_mut(channel).and_then(|m| m.get_mut(&node)) {
            Some(p) => {
                let was = *p;
                p.operational = false;
                p.reset_commanded = None;
                was
            }
            None => NodePast::default(),
        };
        let commanded = match (past.reset_commanded, at.time) {
            (Some(c), Some(t)) => t.since(c) <= Span::from_millis(COMMANDED_BOOT_MS),
            (Some(_), None) => true,
            _ => false,
        };
        if commanded {
            self.occur(channel, Some(node), Kind::Boot, None, at, true, None);
        } else if heard {
            self.occur(channel, Some(node), Kind::Boot, None, at, false, None);
        }
    }

    /// An NMT state the node said (`commanded` false) or a master's
    /// command set (`true`); `reset` for a reset command.
    pub fn nmt(
        &mut self,
        channel: &str,
        node: NodeId,
        operational: bool,
        commanded: bool,
        reset: bool,
        at: At,
    ) {
        let p = self.past(channel, node);
        let was = p.operational;
        p.operational = operational;
        if commanded {
            if reset {
                p.reset_commanded = at.time;
            }
            self.occur(channel, Some(node), Kind::Nmt, None, at, true, None);
        } else {
            if was && !operational {
                self.occur(channel, Some(node), Kind::Nmt, None, at, false, None);
            }
        }
    }

    pub fn heartbeat_lost(&mut self, channel: &str, node: NodeId, at: At) {
        self.occur(
            channel,
            Some(node),
            Kind::HeartbeatLost,
            None,
            at,
            false,
            None,
        );
    }

    pub fn axis_fault(&mut self, channel: &str, node: NodeId, at: At) {
        self.occur(channel, Some(node), Kind::AxisFault, None, at, false, None);
    }

    pub fn fault_reset(&mut self, channel: &str, node: NodeId, at: At) {
        self.occur(channel, Some(node), Kind::FaultReset, None, at, true, None);
    }

    pub fn bus_error(&mut self, channel: &str, at: At) {
        self.occur(channel, None, Kind::BusError, None, at, false, at.time);
    }

    /// A gap in SYNC: `at` is the SYNC that ended it.
    pub fn sync_missed(&mut self, channel: &str, at: At) {
        self.occur(channel, None, Kind::SyncMissed, None, at, false, None);
    }

    pub fn bus_off(&mut self, channel: &str, node: Option<NodeId>, at: At) {
        self.occur(channel, node, Kind::BusOff, None, at, false, None);
    }

    /// `consumer` consumes `producer`'s heartbeat (0x1016 written).
    pub fn consumes_heartbeat(&mut self, channel: &str, consumer: NodeId, producer: NodeId) {
        let c = self
            .consumes
            .entry((channel.to_string(), consumer))
            .or_default();
        if !c.heartbeat.contains(&producer) && c.heartbeat.len() < 127 {
            c.heartbeat.push(producer);
        }
    }

    /// `consumer` receives a PDO on `cob_id` (0x1400.. sub 1 written); a
    /// predefined TPDO COB-ID (0x180-0x57F) names its producer.
    pub fn consumes_pdo(&mut self, channel: &str, consumer: NodeId, cob_id: u32) {
        if !(0x181..=0x57F).contains(&cob_id) || cob_id & 0x7F == 0 {
            return;
        }
        let producer = (cob_id & 0x7F) as NodeId;
        let c = self
            .consumes
            .entry((channel.to_string(), consumer))
            .or_default();
        if !c.rpdo.contains(&producer) && c.rpdo.len() < 127 {
            c.rpdo.push(producer);
        }
    }

    /// Whether an incident is due to close at `now`: one comparison, the
    /// cost every timed frame pays.
    #[inline]
    pub fn passed(&self, now: Timestamp) -> bool {
        self.due.is_some_and(|d| now > d)
    }

    fn hold(&self) -> Span {
        self.gap
            .checked_add(Span::from_millis(LATE_MS))
            .unwrap_or(self.gap)
    }

    fn update_due(&mut self) {
        let hold = self.hold();
        self.due = self
            .open
            .iter()
            .filter_map(|(_, o)| o.end.checked_add_span(hold))
            .min();
    }

    /// The trace's clock reached `now`: incidents whose gap has passed close.
    pub fn tick(&mut self, now: Option<Timestamp>) {
        let Some(now) = now else { return };
        if !self.passed(now) {
            return;
        }
        let hold = self.hold();
        let mut due: Vec<String> = self
            .open
            .iter()
            .filter(|(_, o)| now.since(o.end) > hold)
            .map(|(c, _)| c.clone())
            .collect();
        due.sort();
        for channel in due {
            self.close(&channel);
        }
        self.update_due();
    }

    /// The end of the input: every open incident closes, in channel order.
    pub fn finish(&mut self) {
        let mut channels: Vec<String> = self.open.iter().map(|(c, _)| c.clone()).collect();
        channels.sort();
        for channel in channels {
            self.close(&channel);
        }
        self.due = None;
    }

    #[allow(clippy::too_many_arguments)]
    fn occur(
        &mut self,
        channel: &str,
        node: Option<NodeId>,
        kind: Kind,
        code: Option<u16>,
        at: At,
        context: bool,
        burst: Option<Timestamp>,
    ) {
        // Without a time an event cannot be placed within a gap.
        let Some(time) = at.time else { return };
        self.tick(Some(time));
        let o = Occurrence {
            node,
            kind,
            code,
            time,
            line: at.line,
            context,
            burst,
        };
        let gap = self.gap;
        let mut at = self.open.iter().position(|(c, _)| c == channel);
        let joins = at.is_some_and(|i| time.since(self.open[i].1.end) <= gap);
        if !joins {
            if at.is_some() {
                self.close(channel);
            }
            // A master's action starts nothing.
            if context {
                return;
            }
            if self.open.len() >= MAX_OPEN {
                self.ignored += 1;
                return;
            }
            self.open.push((
                channel.to_string(),
                Open {
                    end: time,
                    events: Vec::new(),
                    total: 0,
                    faults: 0,
                },
            ));
            at = Some(self.open.len() - 1);
        }
        let Some(i) = at else { return };
        let open = &mut self.open[i].1;
        if time > open.end {
            open.end = time;
        }
        open.total += 1;
        open.faults += u64::from(!context);
        if open.events.len() < MAX_EVENTS {
            open.events.push(o);
        }
        if !joins {
            let new = time.checked_add_span(self.hold());
            self.due = match (self.due, new) {
                (Some(d), Some(n)) => Some(d.min(n)),
                (d, n) => d.or(n),
            };
        }
    }

    fn close(&mut self, channel: &str) {
        let Some(i) = self.open.iter().position(|(c, _)| c == channel) else {
            return;
        };
        let (_, mut open) = self.open.swap_remove(i);
        // Context alone (a reset that came within the gap of nothing) is
        // no incident.
        if open.faults == 0 {
            return;
        }
        // Stable: events of one time keep the order they were told in.
        open.events.sort_by_key(|o| o.time);
        let consumes = |node: NodeId| self.consumes.get(&(channel.to_string(), node));
        let links = link(&open.events, consumes);
        let root = root(&open.events, &links);
        let first = open
            .events
            .iter()
            .position(|o| !o.context)
            .unwrap_or_default();
        let mut nodes: Vec<NodeId> = open.events.iter().filter_map(|o| o.node).collect();
        nodes.sort_unstable();
        nodes.dedup();
        let start = open.events[first].time;
        let summary = summary(
            &open.events,
            &root,
            open.faults,
            open.total - open.faults,
            open.end.since(start),
        );
        self.count += 1;
        self.closed.push(Incident {
            channel: channel.to_string(),
            start,
            end: open.end,
            nodes,
            events: open.events,
            events_total: open.total,
            links,
            root,
            first,
            summary,
        });
    }
}

/// The rules: each event that one explains gets its links (several when
/// the evidence names several possible causes).
fn link<'c>(events: &[Occurrence], consumes: impl Fn(NodeId) -> Option<&'c Consumed>) -> Vec<Link> {
    let mut links = Vec::new();
    let within = |a: &Occurrence, b: &Occurrence, s: Span| {
        let d = if a.time >= b.time {
            a.time.since(b.time)
        } else {
            b.time.since(a.time)
        };
        d <= s
    };
    let silent = |o: &Occurrence| {
        matches!(o.kind, Kind::HeartbeatLost) || (o.kind == Kind::Boot && !o.context)
    };
    for (i, e) in events.iter().enumerate() {
        if e.context {
            continue;
        }
        let mut add = |to: usize, reason: String| {
            links.push(Link {
                from: i,
                to,
                reason,
            })
        };
        // The node's own events of `kind` at or before this one (within
        // `ms` of it when given): the first of them, or the last.
        let own = |kind: Kind, ms: Option<u64>, last: bool| {
            let mut found = events
                .iter()
                .enumerate()
                .filter(|(_, o)| {
                    o.kind == kind
                        && o.node == e.node
                        && o.time <= e.time
                        && ms.is_none_or(|ms| within(o, e, Span::from_millis(ms)))
                })
                .map(|(j, _)| j);
            if last {
                found.next_back()
            } else {
                found.next()
            }
        };
        match (e.kind, e.code) {
            // A consumer's heartbeat error, RPDO timeout or SYNC error: the
            // producer it consumes fell silent (or restarted).
            // A SYNC error after SYNC skipped cycles: the gap.
            (Kind::Emcy, Some(0x8240))
                if events
                    .iter()
                    .any(|o| o.kind == Kind::SyncMissed && o.time <= e.time) =>
            {
                let gap = events
                    .iter()
                    .rposition(|o| o.kind == Kind::SyncMissed && o.time <= e.time);
                if let Some(j) = gap {
                    add(
                        j,
                        format!(
                            "{} reports a SYNC error (0x8240) after SYNC skipped cycles",
                            e.words()
                        ),
                    );
                }
            }
            (Kind::Emcy, Some(code @ (0x8130 | 0x8250 | 0x8240))) => {
                let Some(me) = e.node else { continue };
                let configured: Vec<NodeId> = consumes(me)
                    .map(|c| {
                        if code == 0x8130 {
                            c.heartbeat.clone()
                        } else if code == 0x8250 {
                            c.rpdo.clone()
                        } else {
                            Vec::new()
                        }
                    })
                    .unwrap_or_default();
                let silent_others: Vec<usize> = events
                    .iter()
                    .enumerate()
                    .filter(|(_, o)| silent(o) && o.node.is_some_and(|n| n != me))
                    .map(|(j, _)| j)
                    .collect();
                let of_configured: Vec<usize> = silent_others
                    .iter()
                    .copied()
                    .filter(|&j| events[j].node.is_some_and(|n| configured.contains(&n)))
                    .collect();
                let (chosen, why) = if !of_configured.is_empty() {
                    (
                        of_configured,
                        "it consumes, as configured by SDO in the trace,",
                    )
                } else {
                    (silent_others, "on its bus")
                };
                let what = match code {
                    0x8130 => "heartbeat or life guarding error",
                    0x8250 => "RPDO timeout",
                    _ => "SYNC error",
                };
                let n = chosen.len();
                for j in chosen {
                    let of = if n > 1 {
                        format!(" (one of {n} candidates)")
                    } else {
                        String::new()
                    };
                    add(
                        j,
                        format!(
                            "{} reports a {what} (0x{code:04X}): {} {why} fell silent{of}",
                            e.words(),
                            events[j]
                                .words()
                                .replace(" fell silent", "")
                                .replace(" rebooted on its own", "")
                        ),
                    );
                }
            }
            // SYNC skipped cycles while error frames were on the bus: the
            // producer could not send, or its frames were destroyed.
            (Kind::SyncMissed, _) => {
                let burst = events.iter().rposition(|o| {
                    matches!(o.kind, Kind::BusError | Kind::BusOff) && o.time <= e.time
                });
                if let Some(j) = burst {
                    add(
                        j,
                        format!(
                            "SYNC skipped cycles after {} at line {}",
                            events[j].words(),
                            events[j].line
                        ),
                    );
                }
            }
            // A communication EMCY (overrun, error passive, recovered from
            // bus-off): the burst it came in.
            (Kind::Emcy, Some(code)) if code & 0xFF00 == 0x8100 => {
                let burst = events.iter().position(|o| {
                    o.kind == Kind::BusError && e.burst.is_some() && o.burst == e.burst
                });
                let off = own(Kind::BusOff, None, false);
                if let Some(j) = off.filter(|_| code == 0x8140) {
                    add(
                        j,
                        format!("{} says the node recovered from bus-off", e.words()),
                    );
                } else if let Some(j) = burst {
                    add(
                        j,
                        format!(
                            "{} came in the burst of error frames at line {}",
                            e.words(),
                            events[j].line
                        ),
                    );
                }
            }
            (Kind::Emcy, Some(code)) => {
                // The same code from several nodes at once: a cause they
                // share outside the bus.
                let earliest = events.iter().position(|o| {
                    o.kind == Kind::Emcy
                        && o.code == Some(code)
                        && o.node != e.node
                        && !o.context
                        && o.time <= e.time
                        && within(o, e, Span::from_millis(AT_ONCE_MS))
                });
                if let Some(j) = earliest.filter(|&j| j < i) {
                    add(
                        j,
                        format!(
                            "the same code 0x{code:04X} from several nodes within {AT_ONCE_MS} ms: a common cause outside the bus (their supply, say)"
                        ),
                    );
                    continue;
                }
                // An EMCY sent with a drive's fault just before it.
                if let Some(j) = own(Kind::AxisFault, Some(SAME_FAULT_MS), false) {
                    add(
                        j,
                        format!("{} came with the drive's fault: one fault", e.words()),
                    );
                }
            }
            (Kind::AxisFault, _) => {
                if let Some(j) = own(Kind::Emcy, Some(SAME_FAULT_MS), false) {
                    add(
                        j,
                        format!(
                            "{} came with its EMCY 0x{:04X}: one fault",
                            e.words(),
                            events[j].code.unwrap_or_default()
                        ),
                    );
                }
            }
            (Kind::Nmt, _) => {
                // Out of operational after its own error: its error
                // behaviour (0x1029).
                if let Some(j) = own(Kind::Emcy, None, true) {
                    add(
                        j,
                        format!(
                            "{} after its own EMCY 0x{:04X} (its error behaviour, object 1029h)",
                            e.words(),
                            events[j].code.unwrap_or_default()
                        ),
                    );
                }
            }
            (Kind::HeartbeatLost, _) => {
                if let Some(j) = own(Kind::BusOff, None, false) {
                    add(j, format!("{}: it was bus-off", e.words()));
                    continue;
                }
                // Several nodes silent at once: one cause (a cable, power).
                if let Some(j) = events
                    .iter()
                    .position(|o| {
                        o.kind == Kind::HeartbeatLost
                            && o.node != e.node
                            && within(o, e, Span::from_millis(AT_ONCE_MS))
                    })
                    .filter(|&j| j < i)
                {
                    add(
                        j,
                        format!(
                            "several nodes fell silent within {AT_ONCE_MS} ms: a common cause (a cable, their supply)"
                        ),
                    );
                }
            }
            (Kind::Boot, _) => {
                if let Some(j) = own(Kind::HeartbeatLost, None, true) {
                    add(
                        j,
                        format!("{} after falling silent: it restarted", e.words()),
                    );
                }
            }
            (Kind::BusOff, _) => {
                if let Some(j) = events
                    .iter()
                    .position(|o| o.kind == Kind::BusError && o.time <= e.time)
                {
                    add(
                        j,
                        format!(
                            "{} among the error frames at line {}",
                            e.words(),
                            events[j].line
                        ),
                    );
                }
            }
            _ => {}
        }
    }
    links
}

/// The root: the earliest event no link explains. Undecided when the
/// candidates of one link are all unexplained, or when unexplained events
/// of other nodes came at once with it.
fn root(events: &[Occurrence], links: &[Link]) -> Root {
    let explained = |i: usize| links.iter().any(|l| l.from == i);
    let unexplained: Vec<usize> = (0..events.len())
        .filter(|&i| !events[i].context && !explained(i))
        .collect();
    let Some(&earliest) = unexplained.first() else {
        // Every event explained by another (a cycle of at-once events):
        // the earliest is where it began.
        let first = events.iter().position(|o| !o.context).unwrap_or_default();
        return Root {
            event: first,
            reason: "the earliest event; the others follow from one another".to_string(),
            candidates: vec![first],
        };
    };
    let mut candidates = vec![earliest];
    // Candidates named together by one link's source.
    for l in links.iter().filter(|l| l.to == earliest) {
        for other in links
            .iter()
            .filter(|o| o.from == l.from && o.to != earliest)
        {
            if unexplained.contains(&other.to) && !candidates.contains(&other.to) {
                candidates.push(other.to);
            }
        }
    }
    for &i in &unexplained[1..] {
        let e = &events[i];
        if e.node != events[earliest].node
            && e.time.since(events[earliest].time) <= Span::from_millis(AT_ONCE_MS)
            && !candidates.contains(&i)
        {
            candidates.push(i);
        }
    }
    candidates.sort_unstable();
    let event = candidates[0];
    let following = links.iter().filter(|l| candidates.contains(&l.to)).count();
    let reason = if candidates.len() > 1 {
        let names: Vec<String> = candidates.iter().map(|&i| events[i].words()).collect();
        format!(
            "undecided: the evidence does not tell which started it: {}",
            names.join(", ")
        )
    } else {
        let common = links
            .iter()
            .find(|l| l.to == event && l.reason.starts_with("the same code"));
        let mut r = match common {
            Some(l) => format!(
                "the first of {}",
                l.reason.trim_start_matches("the same code ")
            ),
            None => "the earliest event no rule explains".to_string(),
        };
        if following > 0 {
            let _ = write!(
                r,
                "; {following} event{} from it",
                if following == 1 {
                    " follows"
                } else {
                    "s follow"
                }
            );
        }
        if events[event].time
            > events
                .iter()
                .find(|o| !o.context)
                .map_or(events[event].time, |o| o.time)
        {
            r.push_str(", though an event it explains came first in the trace");
        }
        r
    };
    Root {
        event,
        reason,
        candidates: if candidates.len() > 1 {
            candidates
        } else {
            vec![event]
        },
    }
}

/// "node 3 fell silent started it; then node 5 EMCY 0x8130 (+0.200 s),
/// ...; 4 events on 3 nodes over 0.800 s".
/// `faults` and `actions` count every event, kept or not: the faults,
/// and the master's actions among them.
fn summary(events: &[Occurrence], root: &Root, faults: u64, actions: u64, span: Span) -> String {
    let r = &events[root.event];
    let mut s = if root.decided() {
        format!("root: {}", r.words())
    } else {
        let names: Vec<String> = root.candidates.iter().map(|&i| events[i].words()).collect();
        format!("root undecided between {}", names.join(" and "))
    };
    let then: Vec<String> = events
        .iter()
        .enumerate()
        .filter(|(i, o)| !o.context && !root.candidates.contains(i))
        .take(4)
        .map(|(_, o)| {
            let d = o.time.since(r.time).as_f64();
            format!("{} ({d:+.3} s)", o.words())
        })
        .collect();
    if !then.is_empty() {
        let _ = write!(s, "; then {}", then.join(", "));
    }
    let mut nodes: Vec<NodeId> = events
        .iter()
        .filter(|o| !o.context)
        .filter_map(|o| o.node)
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let _ = write!(
        s,
        "; {faults} event{} on {} node{} over {:.3} s",
        if faults == 1 { "" } else { "s" },
        nodes.len(),
        if nodes.len() == 1 { "" } else { "s" },
        span.as_f64()
    );
    if actions > 0 {
        let _ = write!(
            s,
            ", amid {actions} master action{} (NMT commands, the boot-ups they caused, fault resets)",
            if actions == 1 { "" } else { "s" }
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(ms: u64, line: u64) -> At {
        At {
            time: Timestamp::ZERO.checked_add_span(Span::from_millis(ms)),
            line,
        }
    }

    fn builder() -> Builder {
        Builder::new(Span::from_millis(DEFAULT_GAP_MS))
    }

    #[test]
    fn events_within_the_gap_are_one_incident_and_further_apart_two() {
        let mut b = builder();
        b.emcy("can0", 1, 0x4310, at(0, 1), None);
        b.emcy("can0", 2, 0x4310, at(1_900, 2), None);
        b.emcy("can0", 1, 0x5000, at(10_000, 3), None);
        b.finish();
        assert_eq!(b.closed.len(), 2);
        assert_eq!(b.closed[0].nodes, [1, 2]);
        assert_eq!(b.closed[1].events_total, 1);
    }

    #[test]
    fn a_sync_error_follows_from_the_gap_and_the_gap_from_the_errors() {
        let mut b = builder();
        b.bus_error("can0", at(0, 1));
        b.sync_missed("can0", at(300, 5));
        b.emcy("can0", 4, 0x8240, at(320, 6), None);
        b.finish();
        let i = &b.closed[0];
        let kinds: Vec<Kind> = i.events.iter().map(|o| o.kind).collect();
        assert_eq!(kinds, [Kind::BusError, Kind::SyncMissed, Kind::Emcy]);
        let links: Vec<(usize, usize)> = i.links.iter().map(|l| (l.from, l.to)).collect();
        assert_eq!(links, [(1, 0), (2, 1)], "{:?}", i.links);
        assert_eq!(i.root.event, 0);
        assert!(i.root.decided());
        assert!(i.links[1].reason.contains("after SYNC skipped cycles"));
        // Without error frames, the gap is the root.
        let mut b = builder();
        b.sync_missed("can0", at(300, 5));
        b.emcy("can0", 4, 0x8240, at(320, 6), None);
        b.finish();
        assert_eq!(b.closed[0].root.event, 0);
        assert_eq!(b.closed[0].events[0].kind.slug(), "sync_missed");
    }

    #[test]
    fn channels_are_apart_and_an_error_reset_is_no_event() {
        let mut b = builder();
        b.emcy("can0", 1, 0x4310, at(0, 1), None);
        b.emcy("can1", 1, 0x4310, at(10, 2), None);
        b.emcy("can0", 1, 0x0000, at(20, 3), None);
        b.finish();
        let channels: Vec<&str> = b.closed.iter().map(|i| i.channel.as_str()).collect();
        assert_eq!(channels, ["can0", "can1"]);
        assert!(b.closed.iter().all(|i| i.events_total == 1));
    }

    #[test]
    fn a_master_action_starts_nothing() {
        let mut b = builder();
        b.nmt("can0", 1, false, true, true, at(0, 1));
        b.boot("can0", 1, true, at(100, 2));
        b.fault_reset("can0", 1, at(200, 3));
        b.finish();
        assert!(b.closed.is_empty(), "{:?}", b.closed);
    }

    #[test]
    fn a_commanded_reboot_is_context_and_an_uncommanded_one_a_fault() {
        let mut b = builder();
        b.emcy("can0", 2, 0x4310, at(0, 1), None);
        b.nmt("can0", 1, false, true, true, at(100, 2));
        b.boot("can0", 1, true, at(200, 3));
        b.boot("can0", 3, true, at(300, 4));
        b.boot("can0", 4, false, at(400, 5));
        b.finish();
        let i = &b.closed[0];
        let boots: Vec<(Option<NodeId>, bool)> = i
            .events
            .iter()
            .filter(|o| o.kind == Kind::Boot)
            .map(|o| (o.node, o.context))
            .collect();
        // Node 4 was never heard before: its first boot-up is no event.
        assert_eq!(boots, [(Some(1), true), (Some(3), false)]);
    }

    #[test]
    fn a_node_leaving_operational_after_its_emcy_follows_from_it() {
        let mut b = builder();
        b.nmt("can0", 5, true, false, false, at(0, 1));
        b.emcy("can0", 5, 0x8130, at(1_000, 2), None);
        b.nmt("can0", 5, false, false, false, at(1_050, 3));
        b.finish();
        let i = &b.closed[0];
        assert_eq!(i.events[i.root.event].kind, Kind::Emcy);
        assert_eq!(i.links.len(), 1);
        assert!(i.links[0].reason.contains("1029h"), "{}", i.links[0].reason);
    }

    #[test]
    fn two_silent_producers_leave_the_root_undecided() {
        let mut b = builder();
        b.heartbeat_lost("can0", 3, at(1_000, 10));
        b.heartbeat_lost("can0", 4, at(1_500, 11));
        b.emcy("can0", 5, 0x8130, at(1_600, 12), None);
        b.finish();
        let i = &b.closed[0];
        assert!(!i.root.decided());
        let candidates: Vec<Option<NodeId>> = i
            .root
            .candidates
            .iter()
            .map(|&c| i.events[c].node)
            .collect();
        assert_eq!(candidates, [Some(3), Some(4)]);
        assert!(
            i.summary.starts_with("root undecided between"),
            "{}",
            i.summary
        );
    }

    #[test]
    fn the_configured_producer_wins_over_other_silent_nodes() {
        let mut b = builder();
        b.consumes_heartbeat("can0", 5, 4);
        b.heartbeat_lost("can0", 3, at(1_000, 10));
        b.heartbeat_lost("can0", 4, at(1_500, 11));
        b.emcy("can0", 5, 0x8130, at(1_600, 12), None);
        b.finish();
        let i = &b.closed[0];
        let link = i
            .links
            .iter()
            .find(|l| i.events[l.from].node == Some(5))
            .unwrap();
        assert_eq!(i.events[link.to].node, Some(4));
    }

    #[test]
    fn an_incident_keeps_a_hundred_events_and_counts_the_rest() {
        let mut b = builder();
        for k in 0..250 {
            b.emcy(
                "can0",
                1 + (k % 100) as NodeId,
                0x4310,
                at(k * 10, k + 1),
                None,
            );
        }
        b.finish();
        let i = &b.closed[0];
        assert_eq!(i.events.len(), MAX_EVENTS);
        assert_eq!(i.events_total, 250);
    }

    #[test]
    fn an_incident_closes_when_the_clock_passes_its_gap() {
        let mut b = builder();
        b.emcy("can0", 1, 0x4310, at(0, 1), None);
        let due = Timestamp::ZERO
            .checked_add_span(Span::from_millis(DEFAULT_GAP_MS + LATE_MS + 1))
            .unwrap();
        assert!(b.passed(due));
        b.tick(Some(due));
        assert_eq!(b.closed.len(), 1);
        assert!(!b.passed(due));
    }
}
