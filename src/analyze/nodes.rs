//! The node table: every node's timeline, per channel, found by the
//! bytes the trace names its channel with. Every monitor keeps its facts
//! about a node in the node's timeline, so the table is shared by all of
//! them and owned by none.

use std::borrow::Borrow;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::io::{self, Read};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use super::event::{CodeTexts, NodeReport};
use super::options::Options;
use crate::canopen::NodeId;
use crate::canopen::profile_choice::{ProfileSource, default_profile};
use crate::timeline::NodeTimeline;
use crate::timeline::health::NodeHealth;
use crate::timeline::history::{ErrorHistory, History};

/// Per-channel node timelines. Channels are usually few, but every distinct
/// interface name in the trace is one, so a hostile trace can name a million:
/// lookup is hashed and a channel holds only the nodes it has seen, keeping
/// time and memory linear in the input. A channel's name is allocated once
/// and shared by the channel, its key and the history.
pub(super) struct Nodes {
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
    /// Nodes in the table (pairs of channel and node id), and the most it
    /// may hold (`Options::max_nodes`).
    count: usize,
    limit: usize,
    /// Set once the table holds more than `limit`: the input's reader
    /// ([`Capped`]) then ends reading.
    full: Arc<AtomicBool>,
}

/// The input's bytes, until the node table is full: then reading ends with
/// an error that says the bound, as a read error does (one `error:` line,
/// the report of what was read). Checked once per read of the input (a
/// block of lines or a chunk of a binary file), never per frame; the lines
/// already read when the table fills are still analysed, a bounded
/// overshoot of at most the blocks in flight.
pub(super) struct Capped<R> {
    inner: R,
    full: Arc<AtomicBool>,
    limit: usize,
}

impl<R> Capped<R> {
    pub(super) fn new(inner: R, nodes: &Nodes) -> Self {
        Capped {
            inner,
            full: Arc::clone(&nodes.full),
            limit: nodes.limit,
        }
    }
}

impl<R: Read> Read for Capped<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.full.load(Ordering::Relaxed) {
            return Err(io::Error::other(format!(
                "more than {} nodes (pairs of channel and node id): reading stopped there \
                 (the node table is bounded; a trace names that many only when it is damaged \
                 or hostile)",
                self.limit
            )));
        }
        self.inner.read(buf)
    }
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
pub(super) struct NodeSlot<'n> {
    pub(super) channel: &'n str,
    pub(super) channel_id: u32,
    pub(super) timeline: &'n mut NodeTimeline,
    pub(super) history: &'n mut History,
}

impl Nodes {
    pub(super) fn new(spill_at: usize, limit: usize) -> Self {
        Nodes {
            channels: Vec::new(),
            index: HashMap::new(),
            last: None,
            history: History::new(spill_at),
            count: 0,
            limit,
            full: Arc::new(AtomicBool::new(false)),
        }
    }

    pub(super) fn get(&mut self, raw: &[u8], node: NodeId) -> NodeSlot<'_> {
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
            channels,
            history,
            count,
            limit,
            full,
            ..
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
                *count += 1;
                if *count > *limit {
                    full.store(true, Ordering::Relaxed);
                }
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

    /// One more pair of channel and node id kept outside the table (the NMT
    /// monitor's ids addressed before they spoke): counted against the
    /// same bound, which is about memory per pair wherever it is kept.
    pub(super) fn count_kept_elsewhere(&mut self) {
        self.count += 1;
        if self.count > self.limit {
            self.full.store(true, Ordering::Relaxed);
        }
    }

    /// A node's timeline if the channel and node are known: the heartbeat
    /// path's lookup, inlined (the general one costs about 150
    /// instructions; heartbeats are a tenth of a busy trace's frames).
    #[inline(always)]
    pub(super) fn known(&mut self, raw: &[u8], node: NodeId) -> Option<&mut NodeTimeline> {
        let c = self.channel_index(raw)?;
        self.timeline_at(c, node)
    }

    /// The index of the channel named by `raw`, if known.
    #[inline(always)]
    pub(super) fn channel_index(&mut self, raw: &[u8]) -> Option<usize> {
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
    pub(super) fn node_index(&self, c: usize, node: NodeId) -> Option<usize> {
        self.channels.get(c)?.position(node).ok()
    }

    /// The timeline of `node`, the `i`th node of the channel at `c`
    /// ([`Nodes::node_index`]); `None` if it is not.
    #[inline]
    pub(super) fn timeline_of(
        &mut self,
        c: usize,
        i: usize,
        node: NodeId,
    ) -> Option<&mut NodeTimeline> {
        let (n, timeline) = self.channels.get_mut(c)?.nodes.get_mut(i)?;
        (*n == node).then_some(timeline)
    }

    /// The history id of the channel at `c`.
    pub(super) fn channel_id_at(&self, c: usize) -> Option<u32> {
        self.channels.get(c).map(|ch| ch.id)
    }

    /// The nodes a channel has seen (an NMT command to node 0 is for them).
    pub(super) fn nodes_of(&self, raw: &[u8]) -> Vec<NodeId> {
        self.index
            .get(raw)
            .and_then(|&i| self.channels.get(i))
            .map(|c| c.nodes.iter().map(|(n, _)| *n).collect())
            .unwrap_or_default()
    }

    /// A node by its channel's history id (deadlines name channels so).
    pub(super) fn slot_by_id(&mut self, id: u32, node: NodeId) -> Option<NodeSlot<'_>> {
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

    /// Every node whose timeline `pick` picks, by its channel's history id.
    pub(super) fn picked(&self, pick: impl Fn(&NodeTimeline) -> bool) -> Vec<(u32, NodeId)> {
        self.channels
            .iter()
            .flat_map(|ch| {
                ch.nodes
                    .iter()
                    .filter(|(_, tl)| pick(tl))
                    .map(|(node, _)| (ch.id, *node))
            })
            .collect()
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
    /// the still-active intervals added. `fill` adds what the monitors kept
    /// of a node's health to its report.
    pub(super) fn into_reports(
        self,
        opts: &Options,
        fill: impl Fn(&mut NodeReport, Option<&NodeHealth>),
    ) -> (Vec<NodeReport>, ErrorHistory, Option<String>) {
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
                    device_type: None,
                    identity: None,
                    descriptions: CodeTexts::default(),
                    nmt_state: None,
                    nmt_commanded: None,
                    heartbeat: None,
                    error_history: None,
                    drive: None,
                };
                fill(&mut report, end.health.as_deref());
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Nodes put in any order are found where the sorted list has them,
    /// below 64, from 64 to 127 (the set's two halves) and above (EtherCAT
    /// station addresses, searched).
    #[test]
    fn node_places_match_the_sorted_list() {
        let mut nodes = Nodes::new(1 << 20, 1 << 20);
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
