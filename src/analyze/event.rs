//! What the analysis reports: one event per decoded EMCY or boot-up, and
//! per input its counts, node states and error history. Renderers receive
//! these through [`Sink`](super::Sink); the JSON key names derived from
//! them are a public contract (docs/guide/output.md).

use std::borrow::Cow;
use std::sync::Arc;

use crate::canopen::NodeId;
use crate::canopen::codes::CodeInfo;
use crate::canopen::emcy::{Emcy, Warning};
use crate::canopen::lss::Lss;
use crate::canopen::nmt::{Command, NmtState};
use crate::canopen::pdo::Mapping;
use crate::canopen::profile::{Decoded, Profile};
use crate::canopen::profile_choice::{Chosen, ProfileSource};
use crate::canopen::sdo::Object;
use crate::canopen::sdo::transfer::{Data, Direction, Outcome, Protocol};
use crate::timeline::drive::{self, DriveState, Fault};
use crate::timeline::heartbeat::{Outage, Supervision, TimeoutSource};
use crate::timeline::history::ErrorHistory;
use crate::timeline::nmt::{GuardCounts, Via};
use crate::timeline::{At, NodeStats, State};
use crate::trace::can_error::ErrorKind;
use crate::trace::deltas::TimeMode;
use crate::trace::{Format, Span, Timestamp};

/// Active codes an event lists at most: a node can have thousands active,
/// and listing them all in every event made output and work quadratic in
/// them. The node object at the end lists them all.
pub const EVENT_ACTIVE_MAX: usize = 64;

/// One decoded EMCY frame, borrowed from the pipeline (no allocation per event).
pub struct EmcyEvent<'a> {
    pub file: &'a str,
    pub line: u64,
    pub time: Option<Timestamp>,
    pub channel: &'a str,
    pub node: NodeId,
    /// The CAN id it came on; `None` for a CoE emergency (EtherCAT).
    pub cob_id: Option<u32>,
    pub data: &'a [u8],
    pub emcy: &'a Emcy,
    pub info: &'a CodeInfo,
    /// The code's description by the node's profile (its vendor row, else
    /// the CiA tables).
    pub description: &'a str,
    pub transition: Option<u8>,
    pub state: State,
    /// The first [`EVENT_ACTIVE_MAX`] codes active after it, in the order
    /// they were raised.
    pub active: &'a [u16],
    /// How many codes are active after it (more than `active` holds when
    /// the list was cut).
    pub active_total: usize,
    pub cleared: &'a [u16],
    pub warnings: &'a [Warning],
    /// The node's profile (it gave `info`) and why.
    pub profile: Chosen,
    /// The manufacturer bytes as the profile reads them.
    pub decoded: Option<&'a Decoded>,
    /// For a communication error (0x81xx), the start of the burst of
    /// error frames on its channel it came in or right after.
    pub bus_error: Option<Timestamp>,
}

/// An NMT boot-up: the node restarted, its errors are gone.
pub struct BootEvent<'a> {
    pub file: &'a str,
    pub line: u64,
    pub time: Option<Timestamp>,
    pub channel: &'a str,
    pub node: NodeId,
    pub cleared: &'a [u16],
}

/// An event of the bus rather than of one node's services: a burst of
/// error frames, a bus-off, an LSS service. `time` and `line` are where it
/// began (a burst is told when it closes, so after later events).
pub struct BusEvent<'a> {
    pub file: &'a str,
    pub line: u64,
    pub time: Option<Timestamp>,
    pub channel: &'a str,
    pub bus: &'a Bus,
}

/// What a [`BusEvent`] says; the JSON `type` is [`Bus::slug`].
#[derive(Clone, Debug, PartialEq)]
pub enum Bus {
    /// Error frames with no more than [`BURST_GAP_MS`] between two.
    Errors(ErrorBurst),
    /// A controller (the logging one, or a node) left the bus.
    BusOff(BusOff),
    /// A layer setting service (CiA 305).
    Lss(LssReport),
    /// Fault-like events of several nodes and the bus told as one story
    /// (see [`super::incident`]).
    Incident(Box<super::incident::Incident>),
    /// SYNC skipped cycles (one event per gap).
    SyncMissed(super::traffic::SyncMissed),
    /// An SDO transfer between the master and a node ended (told by the
    /// frame that ended it; an unanswered one by the client's last frame,
    /// once the timeout passed). A node that never answered is made no
    /// node by it.
    Sdo(Box<SdoTransfer>),
}

impl Bus {
    /// The event's JSON `type` (docs/guide/output.md, the JSON contract).
    pub fn slug(&self) -> &'static str {
        match self {
            Bus::Errors(_) => "bus_error",
            Bus::BusOff(_) => "bus_off",
            Bus::Lss(_) => "lss",
            Bus::Incident(_) => "incident",
            Bus::SyncMissed(_) => "sync_missed",
            Bus::Sdo(_) => "sdo",
        }
    }

    /// The node the event is of: a node's bus-off, the node-id an LSS
    /// frame configures or inquires, an SDO transfer's node; `None` for
    /// the bus's own events (a burst, the logging controller's bus-off).
    pub fn node(&self) -> Option<NodeId> {
        match self {
            Bus::BusOff(off) => off.node,
            Bus::Lss(l) => l.node,
            Bus::Sdo(t) => Some(t.node),
            Bus::Errors(_) | Bus::Incident(_) | Bus::SyncMissed(_) => None,
        }
    }
}

/// An SDO transfer that ended: what the master asked of which object of
/// the node, the data that moved, and how it ended
/// ([`crate::canopen::sdo::transfer`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SdoTransfer {
    pub node: NodeId,
    pub direction: Direction,
    pub object: Object,
    /// The object's name: from the node's DCF, else the CiA tables.
    pub name: Option<Cow<'static, str>>,
    /// `None` for an upload the node never answered.
    pub protocol: Option<Protocol>,
    /// The size the initiate gave.
    pub indicated: Option<u32>,
    /// The data that moved; `None` when none did.
    pub data: Option<Data>,
    /// The data as text, for a VISIBLE_STRING object shown whole.
    pub text: Option<String>,
    pub outcome: Outcome,
    /// An abort code's meaning.
    pub abort_text: Option<&'static str>,
    /// Its first frame and the one that ended it.
    pub start: At,
    pub end: At,
}

/// An LSS frame, with what the frames before it said: the node-id a
/// configure node-id answer confirms, and the identity of the node the
/// master had selected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LssReport {
    pub lss: Lss,
    /// Sent by the master (0x7E5), else by a node (0x7E4).
    pub from_master: bool,
    /// The node-id configured (a configure node-id request, and its
    /// answer) or inquired.
    pub node: Option<NodeId>,
    /// The identity of the node in configuration, as far as the master
    /// selected or inquired it.
    pub identity: Option<LssIdentity>,
}

/// A node's identity (object 0x1018) as LSS frames showed it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LssIdentity {
    pub vendor_id: Option<u32>,
    pub product_code: Option<u32>,
    pub revision: Option<u32>,
    pub serial: Option<u32>,
}

/// The bus's TIME producer over an input: how many stamps, the first, and
/// how far its clock was from the trace's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimeProducer {
    pub frames: u64,
    /// The first stamp, as the producer's clock read (Unix time).
    pub first: Timestamp,
    /// The producer's clock minus the trace's at the first and the last
    /// stamp; `None` when the trace has no times.
    pub first_offset: Option<Span>,
    pub last_offset: Option<Span>,
}

/// A burst of error frames ends after this long without one.
pub const BURST_GAP_MS: u64 = 1000;

/// A burst of error frames on one channel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ErrorBurst {
    pub start: Option<Timestamp>,
    /// The last error frame's time.
    pub end: Option<Timestamp>,
    pub frames: u64,
    /// Error frames by kind, indexed by [`ErrorKind::index`] (a frame may
    /// count under several kinds).
    pub kinds: [u64; ErrorKind::ALL.len()],
    /// The highest error counters the frames reported; `None` when none
    /// reported them.
    pub tx_errors_max: Option<u8>,
    pub rx_errors_max: Option<u8>,
}

impl ErrorBurst {
    /// The kinds seen, with their counts, in [`ErrorKind::ALL`]'s order.
    pub fn kinds(&self) -> impl Iterator<Item = (ErrorKind, u64)> + '_ {
        kind_counts(&self.kinds)
    }
}

/// The non-zero counts of `kinds`, with their kind.
pub fn kind_counts(
    kinds: &[u64; ErrorKind::ALL.len()],
) -> impl Iterator<Item = (ErrorKind, u64)> + '_ {
    ErrorKind::ALL
        .into_iter()
        .zip(kinds.iter().copied())
        .filter(|(_, n)| *n > 0)
}

/// A controller off the bus: the logging controller's (its error frames
/// say so) or a node's (inferred: it cannot say so while off).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BusOff {
    /// `None`: the controller that logged the trace.
    pub node: Option<NodeId>,
    pub start: Option<Timestamp>,
    /// `None`: still off at the end of the input.
    pub end: Option<Timestamp>,
    /// What showed it, in time order.
    pub evidence: Vec<Evidence>,
}

/// One thing that showed a bus-off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Evidence {
    pub kind: EvidenceKind,
    pub time: Option<Timestamp>,
    pub line: u64,
}

/// What a piece of [`Evidence`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EvidenceKind {
    /// The burst of error frames (at its start).
    BusError,
    /// An error frame of class bus-off.
    BusOffFrame,
    /// An error frame saying the controller restarted or is error active
    /// again.
    RecoveryFrame,
    /// The node's last sign of life before its silence.
    LastSeen,
    /// The node's EMCY with this code (0x8140: recovered from bus-off).
    Emcy(u16),
    /// The node's boot-up.
    BootUp,
}

impl EvidenceKind {
    /// The stable name in JSON.
    pub fn slug(self) -> &'static str {
        match self {
            EvidenceKind::BusError => "bus_error",
            EvidenceKind::BusOffFrame => "bus_off_frame",
            EvidenceKind::RecoveryFrame => "recovery_frame",
            EvidenceKind::LastSeen => "last_seen",
            EvidenceKind::Emcy(_) => "emcy",
            EvidenceKind::BootUp => "boot_up",
        }
    }

    /// In words, for the table: "EMCY 0x8140", "boot-up".
    pub fn words(self) -> String {
        match self {
            EvidenceKind::BusError => "error frames".to_string(),
            EvidenceKind::BusOffFrame => "bus-off error frame".to_string(),
            EvidenceKind::RecoveryFrame => "controller restarted".to_string(),
            EvidenceKind::LastSeen => "last heard".to_string(),
            EvidenceKind::Emcy(code) => format!("EMCY 0x{code:04X}"),
            EvidenceKind::BootUp => "boot-up".to_string(),
        }
    }
}

/// The error frames of one channel over an input.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ChannelErrors {
    pub channel: String,
    pub frames: u64,
    /// By kind, indexed by [`ErrorKind::index`].
    pub kinds: [u64; ErrorKind::ALL.len()],
    pub bursts: u64,
    pub tx_errors_max: Option<u8>,
    pub rx_errors_max: Option<u8>,
    /// Bus-offs in all, the controller's and the nodes'.
    pub bus_off_count: u64,
    /// The first [`MAX_BUS_OFFS_KEPT`] bus-offs.
    pub bus_offs: Vec<BusOffRecord>,
}

/// Bus-offs an input's report keeps per channel (the count goes on).
pub const MAX_BUS_OFFS_KEPT: usize = 64;

/// A bus-off as the input's report keeps it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusOffRecord {
    /// `None`: the logging controller.
    pub node: Option<NodeId>,
    pub start: Option<Timestamp>,
    pub end: Option<Timestamp>,
}

/// A node's NMT, heartbeat, SDO abort or error history event (rare next to
/// EMCYs: each is owned, so recording one is a clone).
pub struct HealthEvent<'a> {
    pub file: &'a str,
    pub line: u64,
    /// For `heartbeat_lost`, when the deadline passed (the line is where
    /// the trace showed it had).
    pub time: Option<Timestamp>,
    pub channel: &'a str,
    pub node: NodeId,
    pub health: &'a Health,
}

/// What a [`HealthEvent`] says; the JSON `type` is [`Health::slug`].
#[derive(Clone, Debug, PartialEq)]
pub enum Health {
    /// The NMT state changed.
    Nmt { state: NmtState, via: Via },
    /// The node's heartbeat (or life guarding) deadline passed.
    HeartbeatLost {
        last_seen: Option<Timestamp>,
        last_seen_line: u64,
        timeout: Span,
        timeout_source: TimeoutSource,
        /// Heartbeats or guarding replies stopped.
        via: Supervision,
    },
    /// A lost node was heard again.
    HeartbeatBack {
        /// From its last sign of life before the outage to this one.
        silent: Span,
        /// It came back with a boot-up.
        restarted: bool,
        /// What it was supervised by when lost.
        via: Supervision,
    },
    /// An SDO transfer was aborted.
    SdoAbort {
        index: u16,
        subindex: u8,
        abort_code: u32,
        text: &'static str,
        /// The node aborted (else the client).
        by_server: bool,
    },
    /// A read-out of object 0x1003.
    ErrorHistory(HistoryReport),
    /// A confirmed write of 0 to 0x1003 sub 0.
    ErrorHistoryCleared,
    /// A CiA 402 drive's statusword showed another state.
    DriveState {
        state: DriveState,
        /// The state before; `None` for the drive's first statusword.
        from: Option<DriveState>,
        statusword: u16,
        /// A PDO (with its COB-ID) or an SDO upload.
        via: drive::Via,
    },
    /// A controlword's bit 7 rose: the master reset the drive's fault.
    FaultReset { controlword: u16 },
}

impl Health {
    /// The event's JSON `type` (docs/guide/output.md, the JSON contract).
    pub fn slug(&self) -> &'static str {
        match self {
            Health::Nmt { .. } => "nmt",
            Health::HeartbeatLost { .. } => "heartbeat_lost",
            Health::HeartbeatBack { .. } => "heartbeat_back",
            Health::SdoAbort { .. } => "sdo_abort",
            Health::ErrorHistory(_) => "error_history",
            Health::ErrorHistoryCleared => "error_history_cleared",
            Health::DriveState { .. } => "axis_state",
            Health::FaultReset { .. } => "fault_reset",
        }
    }
}

/// A read-out of a node's error history (0x1003), newest first.
#[derive(Clone, Debug, PartialEq)]
pub struct HistoryReport {
    pub entries: Vec<HistoryItem>,
    /// The count sub 0 gave, if read.
    pub count: Option<u8>,
    /// Every entry up to the count was read.
    pub complete: bool,
    /// The last frame of the read-out.
    pub time: Option<Timestamp>,
    pub line: u64,
}

/// One entry of a read-out.
#[derive(Clone, Debug, PartialEq)]
pub struct HistoryItem {
    pub code: u16,
    /// The manufacturer-specific high 16 bits.
    pub info: u16,
    /// By the node's profile.
    pub description: String,
    /// The trace never saw the node raise it: it predates the trace.
    pub before_trace: bool,
}

/// A node's heartbeats (or guarding replies) over the input.
#[derive(Clone, Debug, PartialEq)]
pub struct HeartbeatReport {
    /// Heartbeats, or node guarding once the node answered a guard request.
    pub via: Supervision,
    /// The typical interval, once learnt.
    pub period: Option<Span>,
    /// The period the trace configured by SDO: the producer heartbeat time
    /// (0x1017), or for guarding the guard time (0x100C).
    pub configured_period: Option<Span>,
    /// `period` is further from `configured_period` than the tolerance
    /// ([`DRIFT_PER_MILLE`](crate::timeline::heartbeat::DRIFT_PER_MILLE)).
    pub drifts: bool,
    /// Node guarding: the life time factor (0x100D) configured, and the
    /// requests, replies and errors counted; `None` for a node never
    /// guarded.
    pub guarding: Option<GuardingReport>,
    /// The timeout in force at the end, and where it came from.
    pub timeout: Option<(Span, TimeoutSource)>,
    /// Outages in all.
    pub lost: u64,
    /// The first outages (`end: None`: silent to the end).
    pub outages: Vec<Outage>,
    pub silent_at_end: bool,
}

/// Node guarding of one node over the input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GuardingReport {
    pub life_time_factor: Option<u8>,
    pub counts: GuardCounts,
}

/// What the master sent, over an input, to ids that never answered (sent
/// no frame at all): one NMT command, or node guarding's remote request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unanswered {
    /// `None`: guard requests.
    pub command: Option<Command>,
    /// Frames sent.
    pub sent: u64,
    /// Ids (per channel) they were sent to.
    pub ids: u64,
}

impl Unanswered {
    /// The stable name in JSON: the command's (`reset_node`), or
    /// `guard_request`.
    pub fn slug(&self) -> &'static str {
        self.command.map_or("guard_request", Command::slug)
    }

    /// "NMT reset node sent 1,576 times to 116 ids that never answered".
    pub fn sentence(&self) -> String {
        let what = match self.command {
            Some(c) => format!("NMT {}", c.name()),
            None => "node guarding request".to_string(),
        };
        let times = match self.sent {
            1 => "once".to_string(),
            n => format!("{} times", grouped(n)),
        };
        let ids = match self.ids {
            1 => "1 id that never answered".to_string(),
            n => format!("{} ids that never answered", grouped(n)),
        };
        format!("{what} sent {times} to {ids}")
    }
}

/// `1576` as `1,576`.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A node's state at the end of an input; its errors are in the input's
/// [`ErrorHistory`] (read with `history.merge().node_errors(..)`).
#[derive(Clone, Debug)]
pub struct NodeReport {
    pub channel: String,
    pub node: NodeId,
    pub state: State,
    pub active: Vec<u16>,
    pub emcy_count: u64,
    /// Boxed: taken from the timeline as it is (a trace can end with a
    /// million nodes, and a report is several times the size without it).
    pub stats: Box<NodeStats>,
    pub profile: &'static Profile,
    pub profile_source: ProfileSource,
    /// Why the trace chose the profile (vendor id, device type).
    pub profile_reason: Option<String>,
    /// The profile's description of every code the node raised.
    pub descriptions: CodeTexts,
    /// Its device type (object 0x1000) as the trace or its DCF showed it.
    pub device_type: Option<u32>,
    /// The NMT state the node said last; `None` if it never told.
    pub nmt_state: Option<NmtState>,
    /// The state a command asked for that the node had not confirmed by
    /// the end; `None` when no command waits.
    pub nmt_commanded: Option<NmtState>,
    /// `None` for a node that sent no heartbeat.
    pub heartbeat: Option<HeartbeatReport>,
    /// The last read-out of 0x1003.
    pub error_history: Option<HistoryReport>,
    /// Its CiA 402 drive; `None` for a node no statusword, controlword or
    /// PDO mapping was seen of.
    pub drive: Option<Box<DriveReport>>,
    /// What the node answered when its identity was read; `None` when no
    /// read of 0x1000 or 0x1018 was answered. Boxed: most nodes of a big
    /// trace have none, and a report per node is held to the end.
    pub identity: Option<Box<NodeIdentity>>,
}

/// What a node said it is: its device type (0x1000), identity object
/// (0x1018 subs 1-4), device name (0x1008), hardware and software versions
/// (0x1009, 0x100A), each as it answered a read.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct NodeIdentity {
    pub device_type: Option<Identified>,
    pub vendor_id: Option<Identified>,
    pub product_code: Option<Identified>,
    pub revision: Option<Identified>,
    pub serial: Option<Identified>,
    pub name: Option<IdentifiedText>,
    pub hardware_version: Option<IdentifiedText>,
    pub software_version: Option<IdentifiedText>,
}

/// A text of a node's identity (at most 64 bytes as the node sent them,
/// read as UTF-8, else Latin-1) and the line of the answer that completed
/// it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IdentifiedText {
    pub text: String,
    pub line: u64,
}

/// One value of a node's identity and the line of the answer that gave it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Identified {
    pub value: u32,
    pub line: u64,
}

/// A node's CiA 402 drive at the end of an input (the `drive` object).
#[derive(Clone, Debug, PartialEq)]
pub struct DriveReport {
    /// The state the last statusword showed; `None` before any.
    pub state: Option<DriveState>,
    pub statusword: Option<u16>,
    /// Faults, oldest first, the open one last (at most
    /// [`drive::MAX_FAULTS_KEPT`] closed ones).
    pub faults: Vec<Fault>,
    /// Every fault entered, kept or not.
    pub fault_count: u64,
    /// Fault resets the master sent.
    pub fault_resets: u64,
    /// The states it was in, with the time in each (standard's order).
    pub time_in_state: Vec<(DriveState, Span)>,
    /// The node's PDO mappings in force at the end, transmit then receive.
    pub mappings: Vec<Mapping>,
}

impl DriveReport {
    /// "faulted 2 times, recovered to operation enabled": the summary's
    /// sentence; `None` for a drive that never faulted.
    pub fn fault_summary(&self) -> Option<String> {
        let n = self.fault_count;
        if n == 0 {
            return None;
        }
        let times = if n == 1 {
            "1 time".to_string()
        } else {
            format!("{n} times")
        };
        let end = match self.state {
            Some(s) if s.is_fault() => "still in fault at the end".to_string(),
            Some(DriveState::State(s)) => format!("recovered to {}", s.words()),
            _ => "state unknown at the end".to_string(),
        };
        Some(format!("faulted {times}, {end}"))
    }
}

/// Descriptions of a node's codes, made once per input: its error list
/// (millions of errors in a long trace) needs one per error, and the node
/// raised only a few codes. Shared, so renderer threads can hold them.
#[derive(Clone, Debug, Default)]
pub struct CodeTexts(Arc<[(u16, Box<str>)]>);

impl CodeTexts {
    /// `profile`'s descriptions of `codes` (ascending).
    pub fn new(profile: &Profile, codes: impl Iterator<Item = u16>) -> Self {
        CodeTexts(
            codes
                .map(|code| (code, profile.describe(code).into_boxed_str()))
                .collect(),
        )
    }

    /// The description of `code`, if the node raised it.
    pub fn get(&self, code: u16) -> Option<&str> {
        let i = self.0.binary_search_by_key(&code, |(c, _)| *c).ok()?;
        self.0.get(i).map(|(_, text)| &**text)
    }

    /// Every code with its description, ascending.
    pub fn iter(&self) -> impl Iterator<Item = (u16, &str)> {
        self.0.iter().map(|(code, text)| (*code, &**text))
    }
}

impl NodeReport {
    /// The description of a code the node raised, by its profile.
    pub fn describe(&self, code: u16) -> Cow<'_, str> {
        match self.descriptions.get(code) {
            Some(text) => Cow::Borrowed(text),
            // Every error of the node was raised by it; kept for safety.
            None => Cow::Owned(self.profile.describe(code)),
        }
    }

    /// Time spent in error: periods that ended, plus the current one up to
    /// `trace_end` when the node is still in error. `None` without times.
    pub fn time_in_error(&self, trace_end: Option<Timestamp>) -> Option<Span> {
        let first = self.stats.first_emcy?.time?;
        // Zero at the trace's precision: "0.000000", not "0".
        let zero = first.since(first);
        let open = match (self.stats.in_error_since, trace_end) {
            (Some(since), Some(end)) => end.since(since),
            _ => zero,
        };
        zero.checked_add(self.stats.time_in_error)?
            .checked_add(open)
    }

    /// Whether the node raised any error (a reset alone does not count).
    pub fn had_errors(&self) -> bool {
        !self.stats.raised.is_empty()
    }
}

/// Line counts of one input. Every line is exactly one of frame, skipped, malformed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub lines: u64,
    pub frames: u64,
    pub emcy: u64,
    pub skipped: u64,
    pub malformed: u64,
    /// NMT boot-up frames.
    pub boot: u64,
    /// Frames on an EMCY id too short to decode (fewer than 3 bytes).
    pub emcy_invalid: u64,
    /// Frames read in another format than the one detected (mixed files).
    pub other_format: u64,
    /// EtherCAT in a capture: frames (skipped lines: they are not CAN
    /// frames), the mailbox messages in them, the CoE messages that were
    /// retries of the one before, reads of an empty mailbox.
    pub ethercat_frames: u64,
    pub mailbox_messages: u64,
    pub mailbox_retries: u64,
    pub mailbox_empty_polls: u64,
    /// Frames lost before they were logged, as the trace says (candump
    /// `DROPCOUNT` lines): not lines, so outside the line sum.
    pub dropped: u64,
    /// Frame lines with a note after the complete frame (a pasted trace's
    /// `< response`, `// boot`): frames, so counted in `frames` too.
    pub annotated: u64,
}

/// Everything known about one input after reading it.
#[derive(Clone, Debug)]
pub struct InputReport {
    pub file: String,
    pub format: Option<Format>,
    pub gzip: bool,
    pub counts: Counts,
    pub nodes: Vec<NodeReport>,
    /// Every error interval of every node, in report order.
    pub history: ErrorHistory,
    /// Times of the input's first and last frame, decoded or not: the span
    /// the summary measures rates and open errors against.
    pub first_time: Option<Timestamp>,
    pub last_time: Option<Timestamp>,
    /// Candump times summed as `-td` deltas (detected or `--timestamps
    /// delta`); `None` when times were read as written.
    pub timestamps: Option<TimeMode>,
    /// Why reading stopped early (I/O error, corrupt gzip, unknown format).
    pub error: Option<String>,
    /// NMT commands and guard requests sent to ids that never answered,
    /// one entry per command (in the order of their bytes), guard requests
    /// last; empty when every id addressed spoke.
    pub nmt_unanswered: Vec<Unanswered>,
    /// `--node`/`--channel` selected no node of this input: what it has
    /// instead (`--node 9 matches no node; the nodes that sent ...: 7`).
    pub unmatched: Option<String>,
    /// Error frames and bus-offs per channel that had any, in the order
    /// the channels first had one.
    pub bus_errors: Vec<ChannelErrors>,
    /// The TIME producer, if the input has TIME frames.
    pub time_producer: Option<TimeProducer>,
    /// The roots of the incidents told, each (channel, node, kind, code)
    /// once with how many incidents it started, in that order; at most
    /// [`super::incident::MAX_ROOTS`] of them.
    pub incident_roots: Vec<(super::incident::RootKey, u64)>,
    /// Each channel's traffic, in the order the channels first had a frame
    /// that came to it (SYNC; every frame with `--timing`).
    pub channels: Vec<super::traffic::ChannelReport>,
}

impl InputReport {
    /// EMCY frames per second over the input's span; `None` without times
    /// or over an empty span.
    pub fn emcy_rate(&self) -> Option<f64> {
        let span = self.last_time?.since(self.first_time?).as_f64();
        (span > 0.0).then(|| self.counts.emcy as f64 / span)
    }

    /// How many reported nodes raised an error.
    pub fn nodes_with_errors(&self) -> usize {
        self.nodes.iter().filter(|n| n.had_errors()).count()
    }
}

/// A line that could not be read, or an EMCY that could not be decoded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    pub file: String,
    pub line: u64,
    pub message: String,
}

impl std::fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.file, self.line, self.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unanswered_reads_well() {
        let u = Unanswered {
            command: Some(Command::ResetNode),
            sent: 1576,
            ids: 116,
        };
        assert_eq!(
            u.sentence(),
            "NMT reset node sent 1,576 times to 116 ids that never answered"
        );
        assert_eq!(u.slug(), "reset_node");
        let g = Unanswered {
            command: None,
            sent: 1,
            ids: 1,
        };
        assert_eq!(
            g.sentence(),
            "node guarding request sent once to 1 id that never answered"
        );
        assert_eq!(grouped(1_234_567), "1,234,567");
        assert_eq!(grouped(999), "999");
    }
}
