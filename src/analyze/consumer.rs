//! The consumer: turns classified lines into timelines, events and counts,
//! in line order, and hands events to the sink.

mod axis;
mod deadlines;
pub(super) mod health;

use std::borrow::Borrow;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::io::Write;
use std::sync::Arc;

use super::classify::{FoldedRun, Foreign, LineSink};
use super::diagnostics::{DiagnosticLog, InputDiagnostics};
use super::event::{
    BootEvent, CodeTexts, Counts, EVENT_ACTIVE_MAX, EmcyEvent, InputReport, NodeReport,
};
use super::interest::{add_emcy_id, interest};
use super::parallel::SharedInterest;
use super::sink::Sink;
use super::{Analysis, Options, OutputError};
use crate::cache::{Cache, profile_code_key};
use crate::canopen::NodeId;
use crate::canopen::codes::CodeInfo;
use crate::canopen::emcy::{self, Emcy, Warning};
use crate::canopen::profile::Profile;
use crate::canopen::profile_choice::{NodeProfiles, ProfileSource, default_profile};
use crate::canopen::sdo;
use crate::timeline::history::{ErrorHistory, History};
use crate::timeline::{At, NodeTimeline, Step};
use crate::trace::deltas::{self, TimeMode};
use crate::trace::ethercat::{CoeMessage, CoeService, Retries};
use crate::trace::{FoldBuffers, Format, Frame, FrameKind, Interest, Reason, Timestamp};
use axis::Drives;
use health::HealthState;

/// Per-channel node timelines. Channels are usually few, but every distinct
/// interface name in the trace is one, so a hostile trace can name a million:
/// lookup is hashed and a channel holds only the nodes it has seen, keeping
/// time and memory linear in the input. A channel's name is allocated once
/// and shared by the channel, its key and the history.
struct Nodes {
    channels: Vec<ChannelNodes>,
    /// Channels by the bytes the trace names them with. Different bytes can
    /// read as one name (invalid UTF-8 becomes U+FFFD); reports and the
    /// history know a channel by its name, so those bytes are one channel:
    /// every channel is also found under its name's bytes.
    index: HashMap<ChannelKey, usize>,
    /// The channel of the previous lookup: nearly every trace has one or two.
    last: Option<usize>,
    /// Closed intervals of every node (timelines keep only active ones).
    history: History,
}

struct ChannelNodes {
    /// The one copy of the name (the history holds it too).
    name: Arc<str>,
    /// The channel's index in the history.
    id: u32,
    /// Sorted by node id.
    nodes: Vec<(NodeId, NodeTimeline)>,
    /// Bit n: node n (0..=127) is in `nodes`. Those come first in `nodes`,
    /// so a CAN node's place is the count of bits below its own, without
    /// the binary search (a tenth of a heartbeat's cost, measured).
    can_nodes: u128,
}

impl ChannelNodes {
    /// Where `node` is in `nodes` (`Err`: where it would go).
    #[inline]
    fn position(&self, node: NodeId) -> Result<usize, usize> {
        // In 64-bit halves: a u128 shift and count cost twice as much.
        let (low, high) = (self.can_nodes as u64, (self.can_nodes >> 64) as u64);
        let (word, before, bit) = match u32::from(node) {
            n @ 0..=63 => (low, 0, n),
            n @ 64..=127 => (high, low.count_ones(), n - 64),
            _ => return self.nodes.binary_search_by_key(&node, |(n, _)| *n),
        };
        let below = (before + (word & ((1u64 << bit) - 1)).count_ones()) as usize;
        if word >> bit & 1 == 1 {
            Ok(below)
        } else {
            Err(below)
        }
    }
}

/// How [`Nodes::index`] knows a channel: its name, shared, or for bytes
/// that are not UTF-8, those bytes. Hashed and compared as bytes, so a
/// lookup takes the trace's bytes as they are.
enum ChannelKey {
    Name(Arc<str>),
    Bytes(Box<[u8]>),
}

impl ChannelKey {
    fn bytes(&self) -> &[u8] {
        match self {
            ChannelKey::Name(name) => name.as_bytes(),
            ChannelKey::Bytes(bytes) => bytes,
        }
    }
}

impl PartialEq for ChannelKey {
    fn eq(&self, other: &Self) -> bool {
        self.bytes() == other.bytes()
    }
}

impl Eq for ChannelKey {}

impl Hash for ChannelKey {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.bytes().hash(state);
    }
}

impl Borrow<[u8]> for ChannelKey {
    fn borrow(&self) -> &[u8] {
        self.bytes()
    }
}

/// A node's timeline, borrowed with what an event needs around it.
struct NodeSlot<'n> {
    channel: &'n str,
    channel_id: u32,
    timeline: &'n mut NodeTimeline,
    history: &'n mut History,
}

impl Nodes {
    fn new(spill_at: usize) -> Self {
        Nodes {
            channels: Vec::new(),
            index: HashMap::new(),
            last: None,
            history: History::new(spill_at),
        }
    }

    fn get(&mut self, raw: &[u8], node: NodeId) -> NodeSlot<'_> {
        let cached = self.last.filter(|&i| {
            self.channels
                .get(i)
                .is_some_and(|c| c.name.as_bytes() == raw)
        });
        let idx = match cached.or_else(|| self.index.get(raw).copied()) {
            Some(i) => i,
            None => self.add_channel(raw),
        };
        self.last = Some(idx);
        let Nodes {
            channels, history, ..
        } = self;
        let ch = &mut channels[idx];
        let slot = match ch.position(node) {
            Ok(i) => i,
            Err(i) => {
                if let Some(bit) = 1u128.checked_shl(u32::from(node)) {
                    ch.can_nodes |= bit;
                }
                if ch.nodes.capacity() == 0 {
                    // Most channels have one node or a few: not the four
                    // slots (over a KiB) a first insert reserves.
                    ch.nodes.reserve_exact(1);
                }
                ch.nodes.insert(i, (node, NodeTimeline::new()));
                i
            }
        };
        NodeSlot {
            channel: &ch.name,
            channel_id: ch.id,
            timeline: &mut ch.nodes[slot].1,
            history,
        }
    }

    /// A node's timeline if the channel and node are known: the heartbeat
    /// path's lookup, inlined (the general one costs about 150
    /// instructions; heartbeats are a tenth of a busy trace's frames).
    #[inline(always)]
    fn known(&mut self, raw: &[u8], node: NodeId) -> Option<&mut NodeTimeline> {
        let c = self.channel_index(raw)?;
        self.timeline_at(c, node)
    }

    /// The index of the channel named by `raw`, if known.
    #[inline(always)]
    fn channel_index(&mut self, raw: &[u8]) -> Option<usize> {
        let same = |ch: &ChannelNodes| ch.name.len() == raw.len() && ch.name.as_bytes() == raw;
        match self.last {
            Some(c) if self.channels.get(c).is_some_and(same) => Some(c),
            _ => {
                let c = *self.index.get(raw)?;
                self.last = Some(c);
                Some(c)
            }
        }
    }

    /// The timeline of `node` on the channel at `c`, if known.
    #[inline(always)]
    fn timeline_at(&mut self, c: usize, node: NodeId) -> Option<&mut NodeTimeline> {
        let ch = self.channels.get_mut(c)?;
        let i = ch.position(node).ok()?;
        ch.nodes.get_mut(i).map(|(_, timeline)| timeline)
    }

    /// Where `node` is among the nodes of the channel at `c`, if known:
    /// for [`Nodes::timeline_of`], which then spares the search.
    #[inline]
    fn node_index(&self, c: usize, node: NodeId) -> Option<usize> {
        self.channels.get(c)?.position(node).ok()
    }

    /// The timeline of `node`, the `i`th node of the channel at `c`
    /// ([`Nodes::node_index`]); `None` if it is not.
    #[inline]
    fn timeline_of(&mut self, c: usize, i: usize, node: NodeId) -> Option<&mut NodeTimeline> {
        let (n, timeline) = self.channels.get_mut(c)?.nodes.get_mut(i)?;
        (*n == node).then_some(timeline)
    }

    /// The history id of the channel at `c`.
    fn channel_id_at(&self, c: usize) -> Option<u32> {
        self.channels.get(c).map(|ch| ch.id)
    }

    /// The channel of bytes the index does not know: the channel of their
    /// name, new if no bytes read as that name before.
    fn add_channel(&mut self, raw: &[u8]) -> usize {
        let name = String::from_utf8_lossy(raw);
        let i = match self.index.get(name.as_bytes()) {
            Some(&i) => i,
            None => {
                let name: Arc<str> = Arc::from(&*name);
                let id = self.history.add_channel(Arc::clone(&name));
                self.channels.push(ChannelNodes {
                    name: Arc::clone(&name),
                    id,
                    nodes: Vec::new(),
                    can_nodes: 0,
                });
                let i = self.channels.len() - 1;
                self.index.insert(ChannelKey::Name(name), i);
                i
            }
        };
        if name.as_bytes() != raw {
            self.index.insert(ChannelKey::Bytes(raw.into()), i);
        }
        i
    }

    /// Node reports sorted by channel name, then node, and the history with
    /// the still-active intervals added.
    fn into_reports(self, opts: &Options) -> (Vec<NodeReport>, ErrorHistory, Option<String>) {
        let Nodes {
            mut channels,
            index,
            mut history,
            ..
        } = self;
        // Lookups are over: the keys' memory is free for the reports.
        drop(index);
        channels.sort_by(|a, b| a.name.cmp(&b.name));
        let selected = channels
            .iter()
            .flat_map(|ch| ch.nodes.iter().map(|(node, _)| (&ch.name, *node)))
            .filter(|(name, node)| opts.selects(name, *node))
            .count();
        let unmatched = (selected == 0)
            .then(|| unmatched_filter(&channels, opts))
            .flatten();
        let mut out = Vec::with_capacity(selected);
        for ch in channels {
            for (node, tl) in ch.nodes {
                let end = tl.into_end();
                let reported = opts.selects(&ch.name, node);
                let active = match reported {
                    true => end.active.iter().map(|iv| iv.code).collect(),
                    false => Vec::new(),
                };
                // Still-active intervals join the closed ones, spilling to
                // disk like them when there are many.
                for iv in end.active {
                    history.push(ch.id, node, iv);
                }
                if !reported {
                    continue;
                }
                let mut report = NodeReport {
                    channel: ch.name.to_string(),
                    node,
                    state: end.state,
                    active,
                    emcy_count: end.emcy_count,
                    stats: end.stats,
                    profile: default_profile(),
                    profile_source: ProfileSource::Default,
                    profile_reason: None,
                    descriptions: CodeTexts::default(),
                    nmt_state: None,
                    heartbeat: None,
                    error_history: None,
                    axis: None,
                };
                health::report_health(&mut report, end.health);
                out.push(report);
            }
        }
        (out, history.finish([]), unmatched)
    }
}

/// How many channel or node names a note lists.
const NAMES_LISTED: usize = 12;

/// `--channel` / `--node` selected no node of the input: what it has
/// instead (channels, or the nodes on the channels selected), so a typo is
/// told from a trace without errors. `None` when there is nothing to name.
fn unmatched_filter(channels: &[ChannelNodes], opts: &Options) -> Option<String> {
    let list = |names: Vec<String>| {
        let more = names.len().saturating_sub(NAMES_LISTED);
        let mut text = names
            .into_iter()
            .take(NAMES_LISTED)
            .collect::<Vec<_>>()
            .join(", ");
        if more > 0 {
            text.push_str(&format!(" and {more} more"));
        }
        text
    };
    let on_channel =
        |name: &str| opts.channels.is_empty() || opts.channels.iter().any(|c| c == name);
    if channels.is_empty() {
        return None;
    }
    if !channels.iter().any(|ch| on_channel(&ch.name)) {
        let names = channels.iter().map(|ch| ch.name.to_string()).collect();
        return Some(format!(
            "--channel {} matches no channel; the channels with EMCY or boot-up frames: {}",
            opts.channels.join(","),
            list(names)
        ));
    }
    let mut nodes: Vec<NodeId> = channels
        .iter()
        .filter(|ch| on_channel(&ch.name))
        .flat_map(|ch| ch.nodes.iter().map(|(n, _)| *n))
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let wanted: Vec<String> = opts.nodes.iter().map(ToString::to_string).collect();
    let place = if opts.channels.is_empty() {
        String::new()
    } else {
        format!(" on channel {}", opts.channels.join(","))
    };
    Some(format!(
        "--node {} matches no node{place}; the nodes that sent EMCY or boot-up frames: {}",
        wanted.join(","),
        list(nodes.iter().map(ToString::to_string).collect())
    ))
}

/// Turns classified lines into timelines, events and counts, in line order.
pub(super) struct Consumer<'r, 'l, E: Write> {
    pub(super) file: &'r str,
    pub(super) opts: &'r Options,
    sink: &'r mut dyn Sink,
    pub(super) log: &'l mut DiagnosticLog<E>,
    pub(super) counts: Counts,
    nodes: Nodes,
    pub(super) diags: InputDiagnostics,
    errors_raised: u64,
    frames_with_warnings: u64,
    worst_category: Option<u8>,
    pub(super) decided: bool,
    /// Set when candump times are summed as deltas: said in the report.
    pub(super) timestamps: Option<TimeMode>,
    /// Lines before the current block.
    line_base: u64,
    /// Time and line of the last EMCY or boot-up: the trace's clock as far
    /// as the timelines see it.
    clock: Option<(Timestamp, u64)>,
    /// EMCY ids other than 0x80 + node, to their node.
    emcy_ids: HashMap<(u32, bool), NodeId>,
    /// First and last time of a decoded frame.
    first_time: Option<Timestamp>,
    last_time: Option<Timestamp>,
    pub(super) interest: Interest,
    pub(super) interest_gen: u64,
    /// Set while workers run: where they read the interest from.
    pub(super) shared_interest: Option<SharedInterest>,
    warnings: Vec<Warning>,
    active: Vec<u16>,
    sdo: sdo::Tracker,
    /// CoE messages seen last, per station: a repeat is a retry.
    coe_retries: Retries,
    profiles: NodeProfiles<'r>,
    /// The last timeline step, handed back for its vectors.
    step_buffers: Step,
    /// What each (profile, code) means: the one code lookup of the run. A
    /// lookup is a few binary searches and a profile's description
    /// allocates, and an EMCY-heavy trace repeats a few codes millions of
    /// times on this thread, so the event carries both from here and no
    /// renderer looks a code up again.
    codes: Cache<(usize, u16), CodeEntry, 64>,
    /// NMT states, heartbeat deadlines, error history read-outs.
    health: HealthState,
    /// CiA 402: PDO mappings and the ids they decode.
    drives: Drives,
}

/// A code as a profile reads it.
pub(super) struct CodeEntry {
    info: CodeInfo,
    description: String,
}

impl CodeEntry {
    fn of(profile: &Profile, code: u16) -> CodeEntry {
        CodeEntry {
            info: profile.info(code),
            description: profile.describe(code),
        }
    }
}

impl<'r, 'l, E: Write> Consumer<'r, 'l, E> {
    pub(super) fn new(
        file: &'r str,
        opts: &'r Options,
        sink: &'r mut dyn Sink,
        log: &'l mut DiagnosticLog<E>,
        decided: bool,
    ) -> Self {
        let drives = Drives::new(opts);
        let mut c = Consumer {
            file,
            opts,
            sink,
            decided,
            timestamps: None,
            log,
            counts: Counts::default(),
            nodes: Nodes::new(opts.spill_at),
            diags: InputDiagnostics {
                file: file.to_string(),
                limit: opts.max_diagnostics,
                shown: 0,
                suppressed: 0,
                pending: Vec::new(),
            },
            errors_raised: 0,
            frames_with_warnings: 0,
            worst_category: None,
            line_base: 0,
            clock: None,
            first_time: None,
            last_time: None,
            emcy_ids: opts
                .emcy_ids
                .iter()
                .map(|e| ((e.id, e.extended), e.node))
                .collect(),
            interest: {
                let mut i = interest(opts);
                drives.add_to(&mut i);
                i
            },
            interest_gen: 0,
            shared_interest: None,
            warnings: Vec::new(),
            active: Vec::new(),
            sdo: sdo::Tracker::default(),
            coe_retries: Retries::default(),
            profiles: NodeProfiles::new(&opts.profiles),
            step_buffers: Step::default(),
            codes: Cache::default(),
            health: HealthState::default(),
            drives,
        };
        c.dcf_identities();
        c
    }

    /// The end of the input: held diagnostics, node reports, the history;
    /// the sink gets the input's report.
    pub(super) fn finish(
        mut self,
        format: Option<Format>,
        gzip: bool,
        mut error: Option<String>,
    ) -> Result<Analysis, OutputError> {
        let file = self.file;
        self.finish_health()?;
        self.finish_axes();
        if format.is_none() && self.counts.malformed > 0 && error.is_none() {
            error = Some(
                "cannot detect the trace format: no line is a candump log, candump screen, \
             Vector ASC, PEAK TRC or BUSMASTER frame and the input is not BLF, pcap, pcapng \
             or MF4 (force one with --input-format \
             candump|candump-screen|asc|trc|busmaster|blf|pcap|mf4)"
                    .to_string(),
            );
        } else {
            self.diags.release(self.log);
            if self.diags.suppressed > 0 {
                self.log.note(&format!(
                    "{file}: {} more diagnostics not shown (--max-diagnostics {})",
                    self.diags.suppressed, self.opts.max_diagnostics
                ));
            }
        }
        let nodes_taken = std::mem::replace(&mut self.nodes, Nodes::new(1));
        let (mut nodes, history, unmatched) = nodes_taken.into_reports(self.opts);
        if let Some(note) = unmatched {
            self.log.note(&format!("{file}: {note}"));
        }
        // Nodes that raised the same codes under the same profile share
        // one set of descriptions (a trace with a million channels has a
        // million nodes, nearly all alike).
        let mut shared: HashMap<*const Profile, HashMap<Box<[u16]>, CodeTexts>> = HashMap::new();
        let mut codes = Vec::new();
        for n in &mut nodes {
            let chosen = self.profiles.get(n.node);
            n.profile = chosen.profile;
            n.profile_source = chosen.source;
            n.profile_reason = self.profiles.reason(n.node).map(str::to_string);
            self.axis_report(n.node, &mut n.axis);
            if let Some(h) = &mut n.error_history {
                for e in &mut h.entries {
                    e.description = n.profile.describe(e.code);
                }
            }
            codes.clear();
            codes.extend(n.stats.raised.keys().copied());
            let same = shared.entry(std::ptr::from_ref(n.profile)).or_default();
            n.descriptions = match same.get(codes.as_slice()) {
                Some(texts) => texts.clone(),
                None => {
                    let texts = CodeTexts::new(n.profile, codes.iter().copied());
                    same.insert(codes.as_slice().into(), texts.clone());
                    texts
                }
            };
        }
        drop(shared);
        if self.counts.dropped > 0 {
            self.log.note(&format!(
                "{file}: warning: candump reported {} dropped by the kernel (DROPCOUNT \
                 lines): EMCYs may be missing",
                match self.counts.dropped {
                    1 => "1 frame".to_string(),
                    n => format!("{n} frames"),
                }
            ));
        }
        if let Some(e) = history.spill_error() {
            self.log.note(&format!(
                "{file}: could not move the error history to a temporary file ({e}); kept in memory"
            ));
        }
        let report = InputReport {
            first_time: self.first_time,
            last_time: self.last_time,
            timestamps: self.timestamps,
            file: file.to_string(),
            format,
            gzip,
            counts: self.counts,
            nodes,
            history,
            error,
        };
        self.sink.end_input(&report).map_err(OutputError)?;
        Ok(Analysis {
            report,
            errors_raised: self.errors_raised,
            frames_with_warnings: self.frames_with_warnings,
            worst_category: self.worst_category,
        })
    }

    pub(super) fn line_no(&self, idx: u64) -> u64 {
        self.line_base + idx + 1
    }

    /// The node a data frame's EMCY id belongs to: a moved id first, then
    /// the pre-defined set (standard ids 0x081-0x0FF).
    pub(super) fn emcy_node(&self, id: u32, extended: bool) -> Option<NodeId> {
        // Nearly always empty: no hashing per frame then.
        let moved = if self.emcy_ids.is_empty() {
            None
        } else {
            self.emcy_ids.get(&(id, extended)).copied()
        };
        moved.or_else(|| if extended { None } else { emcy::emcy_node(id) })
    }

    /// A node holds `value` in `object` (SDO upload or confirmed download).
    fn object_value(&mut self, node: NodeId, object: sdo::Object, value: u32) {
        self.profiles.object_value(node, object, value);
        if object.index == sdo::DEVICE_TYPE && object.sub == 0 {
            self.device_type(node, value);
        }
        if object.index == sdo::COB_ID_EMCY
            && object.sub == 0
            && let Some((id, extended)) = sdo::cob_id_emcy(value)
        {
            self.map_emcy_id(id, extended, node);
        }
    }

    /// A node's EMCY id moved (object 0x1014 seen in the trace): decode
    /// frames on it from here on.
    fn map_emcy_id(&mut self, id: u32, extended: bool, node: NodeId) {
        if self.emcy_ids.insert((id, extended), node) == Some(node) {
            return;
        }
        add_emcy_id(&mut self.interest, id, extended);
        self.interest_gen += 1;
        if let Some(shared) = &self.shared_interest
            && let Ok(mut w) = shared.write()
        {
            *w = (self.interest_gen, self.interest.clone());
        }
    }

    /// An EMCY of `node` (on CAN id `cob_id`; `None` for a CoE emergency):
    /// its timeline step, counts and event.
    fn emcy(
        &mut self,
        at: At,
        channel_bytes: &[u8],
        node: NodeId,
        cob_id: Option<u32>,
        data: &[u8],
    ) -> Result<(), OutputError> {
        let emcy = match Emcy::decode(data) {
            Ok(e) => e,
            Err(short) => {
                self.counts.emcy_invalid += 1;
                self.diags
                    .report(self.log, true, at.line, format!("node {node}: {short}"));
                return Ok(());
            }
        };
        self.counts.emcy += 1;
        self.check_clock(at);
        let chosen = self.profiles.get(node);
        let profile = chosen.profile;
        let (key, slot) = profile_code_key(profile, emcy.code);
        let looked_up;
        let entry = match self
            .codes
            .get(key, slot, || CodeEntry::of(profile, emcy.code))
        {
            Some(entry) => entry,
            None => {
                looked_up = CodeEntry::of(profile, emcy.code);
                &looked_up
            }
        };
        let info = &entry.info;
        self.warnings.clear();
        emcy.frame_warnings(info, &mut self.warnings);
        profile.frame_warnings(&emcy, &mut self.warnings);
        let NodeSlot {
            channel,
            channel_id,
            timeline,
            history,
        } = self.nodes.get(channel_bytes, node);
        let step = timeline.apply(
            &emcy,
            at,
            profile.status_bit(&emcy),
            &mut self.warnings,
            std::mem::take(&mut self.step_buffers),
        );
        for iv in &step.closed {
            history.push(channel_id, node, iv.clone());
        }
        if !emcy.is_reset() {
            Self::axis_emcy(timeline.axis_mut(), at, emcy.code);
        }
        if !self.opts.selects(channel, node) {
            self.step_buffers = step;
            return Ok(());
        }
        if !emcy.is_reset() {
            self.errors_raised += 1;
            if let Some(c) = profile.category(&emcy) {
                self.worst_category = Some(self.worst_category.map_or(c, |w| w.min(c)));
            }
        }
        if !self.warnings.is_empty() {
            self.frames_with_warnings += 1;
        }
        // The first few: an event's size must not grow with the node's
        // active errors (a trace can leave thousands active).
        self.active.clear();
        self.active
            .extend(timeline.active_codes().take(EVENT_ACTIVE_MAX));
        let decoded = profile.decode_manufacturer(&emcy);
        let event = EmcyEvent {
            file: self.file,
            line: at.line,
            time: at.time,
            channel,
            node,
            cob_id,
            data,
            emcy: &emcy,
            info,
            description: &entry.description,
            transition: step.transition,
            state: step.state,
            active: &self.active,
            active_total: timeline.active().len(),
            cleared: &step.cleared,
            warnings: &self.warnings,
            profile: chosen,
            decoded: decoded.as_ref(),
        };
        self.sink.emcy(&event).map_err(OutputError)?;
        self.step_buffers = step;
        Ok(())
    }

    /// A CoE message of an EtherCAT frame (a skipped line, counted by the
    /// caller) at line `idx` of the block: an emergency is an EMCY of the
    /// station, an SDO transfer may say which profile it has.
    pub(super) fn coe(
        &mut self,
        idx: u64,
        time: Option<Timestamp>,
        channel: &[u8],
        m: &CoeMessage,
    ) -> Result<(), OutputError> {
        self.decide();
        if self.coe_retries.is_retry(channel, m) {
            self.counts.mailbox_retries += 1;
            return Ok(());
        }
        if let Some(t) = time {
            self.time(t);
        }
        let at = At {
            time,
            line: self.line_no(idx),
        };
        match m.service {
            CoeService::Emergency => self.emcy(at, channel, m.station, None, m.data()),
            CoeService::SdoRequest | CoeService::SdoResponse => {
                // The same SDO path as CAN's: identity, aborts, the 1003h
                // history, heartbeat times.
                let request = m.service == CoeService::SdoRequest;
                match sdo::parse_payload(m.station, request, m.data()) {
                    Some(access) => self.sdo_access(channel, at, access),
                    None => Ok(()),
                }
            }
        }
    }

    /// EtherCAT seen in the input: frames, mailbox messages, empty polls.
    pub(super) fn ethercat(&mut self, frames: u64, mailbox_messages: u64, empty_polls: u64) {
        self.counts.ethercat_frames = frames;
        self.counts.mailbox_messages = mailbox_messages;
        self.counts.mailbox_empty_polls = empty_polls;
    }

    /// Skipped lines the reader only counted.
    pub(super) fn skipped_lines(&mut self, n: u64) {
        self.counts.skipped += n;
    }

    /// A frame was read: the format is known, held diagnostics go out.
    pub(super) fn decide(&mut self) {
        if !self.decided {
            self.decided = true;
            self.diags.release(self.log);
        }
    }

    /// A wanted frame's time: the input's first and last time.
    pub(super) fn time(&mut self, t: Timestamp) {
        self.first_time.get_or_insert(t);
        self.last_time = Some(t);
    }

    /// A time earlier than the previous EMCY's or boot-up's (two logs
    /// concatenated, a clock reset) gets a diagnostic: durations across this
    /// line come out negative, and the user should know why.
    fn check_clock(&mut self, at: At) {
        let Some(time) = at.time else { return };
        if let Some((previous, line)) = self.clock
            && time.since(previous).is_negative()
        {
            self.diags.report(
                self.log,
                self.decided,
                at.line,
                format!(
                    "time {time} is earlier than {previous} at line {line}: the trace's clock \
                     went backwards (durations across this line are negative){}",
                    if self.opts.timestamps.is_none()
                        && self.timestamps.is_none()
                        && time.secs() < deltas::DELTA_BELOW_SECS
                    {
                        "; if these are candump -td deltas, --timestamps delta sums them"
                    } else {
                        ""
                    }
                ),
            );
        }
        self.clock = Some((time, at.line));
    }
}

impl<E: Write> LineSink for Consumer<'_, '_, E> {
    fn interest(&self) -> &Interest {
        &self.interest
    }

    fn plain_frames(&mut self, n: u64) {
        self.counts.frames += n;
        self.decide();
    }

    fn timed_frames(&mut self, n: u64, first: Timestamp, last: Timestamp) {
        self.counts.frames += n;
        self.decide();
        self.time(first);
        self.time(last);
    }

    fn folded(&mut self, idx: u64, run: &FoldedRun<'_>) -> Result<(), OutputError> {
        self.take_folded_run(idx, run)
    }

    fn fold_buffers(&mut self) -> FoldBuffers {
        std::mem::take(&mut self.health.spare_folds)
    }

    fn block_folds(&mut self, folds: FoldBuffers) {
        self.health.spare_folds = folds;
    }

    fn lines(&mut self, n: u64) {
        self.counts.lines += n;
        self.line_base += n;
    }

    fn skipped(&mut self) {
        self.counts.skipped += 1;
    }

    fn dropped(&mut self, n: u64) {
        self.counts.dropped = self.counts.dropped.saturating_add(n);
    }

    fn malformed(&mut self, idx: u64, reason: Reason) {
        self.counts.malformed += 1;
        let line = self.line_no(idx);
        self.diags
            .report(self.log, self.decided, line, reason.into_owned());
    }

    fn warning(&mut self, idx: u64, reason: Reason) {
        let line = self.line_no(idx);
        self.diags
            .report(self.log, self.decided, line, reason.into_owned());
    }

    fn format_known(&mut self) {
        self.decide();
    }

    fn frame(&mut self, idx: u64, frame: &Frame<'_>, foreign: Foreign) -> Result<(), OutputError> {
        // Heartbeats are the most frequent frames decoded.
        if foreign.is_none() && self.steady_heartbeat(idx, frame) {
            return Ok(());
        }
        self.counts.frames += 1;
        let line_no = self.line_no(idx);
        self.decide();
        if let Some((other, primary)) = foreign {
            self.counts.other_format += 1;
            let msg = format!(
                "line is in {} format, not {} like the rest; read anyway",
                other.name(),
                primary.name()
            );
            self.diags.report(self.log, true, line_no, msg);
        }
        if frame.kind != FrameKind::Data {
            if frame.kind == FrameKind::Remote
                && !frame.extended
                && self.interest.wants(frame.id, false)
            {
                self.remote_frame(frame.channel, frame.id);
            }
            return Ok(());
        }
        // Only wanted ids count: workers may hand over frames the sequential
        // reader only counts, and the result must not depend on the path.
        if !self.interest.wants(frame.id, frame.extended) {
            return Ok(());
        }
        // A drive's PDO of unknown mapping is only noted: it moves no time,
        // as when it was not wanted.
        if self.watched(frame.id, frame.extended) {
            return Ok(());
        }
        if let Some(t) = frame.time {
            self.time(t);
            if self.health.passed(t) {
                self.deadlines_passed(t, line_no)?;
            }
        }
        if self
            .interest
            .timed_only(frame.id, frame.extended, frame.data.as_slice())
        {
            return Ok(());
        }
        let at = At {
            time: frame.time,
            line: line_no,
        };
        let data = frame.data.as_slice();
        if let Some(slot) = self.drives.slot(frame.id, frame.extended) {
            return self.pdo(frame.channel, at, frame.id, slot, data);
        }
        if let Some(node) = self.emcy_node(frame.id, frame.extended) {
            self.emcy(at, frame.channel, node, Some(frame.id), data)?;
        } else if frame.extended {
            return Ok(());
        } else if sdo::is_sdo_id(frame.id) {
            self.pdo_configuration(frame.id, data);
            if let Some(access) = sdo::parse(frame.id, data) {
                self.sdo_access(frame.channel, at, access)?;
            }
        } else if let Some(node) = emcy::boot_node(frame.id, data) {
            self.counts.boot += 1;
            self.check_clock(at);
            let NodeSlot {
                channel,
                channel_id,
                timeline,
                history,
            } = self.nodes.get(frame.channel, node);
            let closed = timeline.boot(at);
            let cleared: Vec<u16> = closed.iter().map(|iv| iv.code).collect();
            for iv in closed {
                history.push(channel_id, node, iv);
            }
            if self.opts.selects(channel, node) {
                let event = BootEvent {
                    file: self.file,
                    line: line_no,
                    time: frame.time,
                    channel,
                    node,
                    cleared: &cleared,
                };
                self.sink.boot(&event).map_err(OutputError)?;
            }
            self.boot_health(frame.channel, node, at)?;
        } else {
            self.nmt_frame(frame.channel, frame.id, data, at)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nodes put in any order are found where the sorted list has them,
    /// below 64, from 64 to 127 (the set's two halves) and above (EtherCAT
    /// station addresses, searched).
    #[test]
    fn node_places_match_the_sorted_list() {
        let mut nodes = Nodes::new(1 << 20);
        let ids: [NodeId; 9] = [127, 5, 64, 300, 1, 63, 65_535, 100, 128];
        for &n in &ids {
            nodes.get(b"can0", n);
        }
        let ch = &nodes.channels[0];
        let sorted: Vec<NodeId> = ch.nodes.iter().map(|(n, _)| *n).collect();
        let mut expected = ids.to_vec();
        expected.sort_unstable();
        assert_eq!(sorted, expected);
        for (i, &n) in expected.iter().enumerate() {
            assert_eq!(ch.position(n), Ok(i), "node {n}");
        }
        for (n, place) in [(0, 0), (2, 1), (66, 4), (126, 5), (129, 7), (65_534, 8)] {
            assert_eq!(ch.position(n), Err(place), "absent node {n}");
        }
        assert!(nodes.known(b"can0", 64).is_some());
        assert!(nodes.known(b"can0", 2).is_none());
        assert!(nodes.known(b"can1", 64).is_none());
    }
}
