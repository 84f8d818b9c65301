//! Every SDO transfer of a trace, from the client's first frame to its end:
//! which object of which node, upload or download, expedited, segmented or
//! block, the bytes it carried, and how it ended (confirmed, aborted, never
//! answered, or cut short). The other followers of this folder learn the
//! values the decoder needs; this one tells the user what the master did.
//!
//! One small fixed record per node (ids 1-127), whatever the trace: a
//! transfer keeps its first [`SHOWN_BYTES`] bytes, and every byte it carried
//! goes into a running hash and a count, so a long value is compared
//! without being stored.
//!
//! Block transfers are followed by [`Blocks`](super::Blocks), which knows
//! which frames are segments; it tells this follower where one began and
//! ended ([`Transfers::block_begun`], [`Transfers::block_done`]).
//!
//! Segments of a segmented transfer are read one by one only while the
//! transfer is short ([`READ_LIMIT`]) or of unknown size
//! ([`Transfers::reads_segments`] says so, and the analysis lets the node's
//! frames through its filter then): a firmware download's thousands of
//! segments are counted from the size its initiate gave, and only its last
//! segment and the answer to it are read.

use super::access::{
    CCS_DOWNLOAD_INITIATE, CCS_DOWNLOAD_SEGMENT, CS_ABORT, Object, PerNode, SCS_DOWNLOAD_INITIATE,
    SCS_DOWNLOAD_SEGMENT, SCS_UPLOAD_INITIATE, SCS_UPLOAD_SEGMENT,
};
use crate::canopen::NodeId;
use crate::trace::{Span, Timestamp};

/// The client's upload initiate and upload segment request.
const CCS_UPLOAD_INITIATE: u8 = 2;
const CCS_UPLOAD_SEGMENT: u8 = 3;

/// Bytes of a transfer's data kept to show: a value longer than this is
/// shown by its first bytes, its size and its hash.
pub const SHOWN_BYTES: usize = 64;

/// The longest segmented transfer (by the size its initiate gave) whose
/// segments are read one by one: up to 586 segments. Longer ones (firmware,
/// recorded data) are counted from their size, not read.
pub const READ_LIMIT: u32 = 4096;

/// Where in the trace a frame was: the analysis's time and line. The
/// follower needs only the time (for timeouts) and hands the rest back.
pub trait Moment: Copy + std::fmt::Debug {
    fn time(&self) -> Option<Timestamp>;
}

/// Which way the data went.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Direction {
    /// The client wrote to the node.
    Download,
    /// The client read from the node.
    Upload,
}

impl Direction {
    pub fn name(self) -> &'static str {
        match self {
            Direction::Download => "download",
            Direction::Upload => "upload",
        }
    }
}

/// Which SDO protocol carried the data.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Protocol {
    /// Up to four bytes in the initiate itself.
    Expedited,
    /// Seven bytes a segment, each confirmed.
    Segmented,
    /// Sub-blocks of up to 127 segments, each sub-block acknowledged.
    Block,
}

impl Protocol {
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Expedited => "expedited",
            Protocol::Segmented => "segmented",
            Protocol::Block => "block",
        }
    }
}

/// How a transfer ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Outcome {
    /// The node confirmed the download, or sent the whole upload.
    Ok,
    /// Aborted with `code`, by the node (`by_server`) or by the client.
    Abort { code: u32, by_server: bool },
    /// The node owed an answer and gave none within the timeout (or before
    /// the client asked something else, or before the trace ended).
    Unanswered,
    /// The client owed the next frame and asked something else instead, or
    /// the trace ended first.
    Incomplete,
}

impl Outcome {
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Ok => "ok",
            Outcome::Abort { .. } => "abort",
            Outcome::Unanswered => "unanswered",
            Outcome::Incomplete => "incomplete",
        }
    }
}

/// The bytes a transfer carried: the first [`SHOWN_BYTES`], how many in
/// all, and a hash of all of them (FNV-1a, 64 bits: cheap per byte, and
/// only ever compared with another trace's hash of the same object).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Data {
    head: [u8; SHOWN_BYTES],
    /// Bytes carried (counted from the initiate's size when the segments
    /// were not read).
    pub size: u32,
    pub hash: u64,
    /// Every byte was read: false when the segments were left unread (a
    /// long transfer) or some were not seen.
    pub whole: bool,
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

impl Default for Data {
    fn default() -> Self {
        Data {
            head: [0; SHOWN_BYTES],
            size: 0,
            hash: FNV_OFFSET,
            whole: true,
        }
    }
}

impl Data {
    /// The data of `bytes`, all read.
    pub fn of(bytes: &[u8]) -> Data {
        let mut d = Data::default();
        d.extend(bytes);
        d
    }

    fn extend(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if let Some(k) = self.head.get_mut(self.size as usize) {
                *k = b;
            }
            self.size = self.size.saturating_add(1);
            self.hash = (self.hash ^ u64::from(b)).wrapping_mul(FNV_PRIME);
        }
    }

    /// The bytes kept: all of them up to [`SHOWN_BYTES`], else the first.
    pub fn shown(&self) -> &[u8] {
        let n = (self.size as usize).min(SHOWN_BYTES);
        self.head.get(..n).unwrap_or_default()
    }

    /// Whether all the bytes are shown.
    pub fn complete(&self) -> bool {
        self.whole && self.size as usize <= SHOWN_BYTES
    }

    /// The value as a little-endian number, for data of at most four bytes
    /// read whole.
    pub fn number(&self) -> Option<u32> {
        match *self.shown() {
            _ if !self.whole => None,
            [a] => Some(u32::from(a)),
            [a, b] => Some(u32::from(u16::from_le_bytes([a, b]))),
            [a, b, c] => Some(u32::from_le_bytes([a, b, c, 0])),
            [a, b, c, d] => Some(u32::from_le_bytes([a, b, c, d])),
            _ => None,
        }
    }
}

/// A transfer that ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ended<M> {
    pub node: NodeId,
    pub direction: Direction,
    pub object: Object,
    /// `None` for an upload the node never answered: the node chooses
    /// between expedited and segmented.
    pub protocol: Option<Protocol>,
    /// The size the initiate (or the node's answer to an upload) gave.
    pub indicated: Option<u32>,
    /// What it carried; `None` when no data moved (an upload aborted before
    /// the node answered, one never answered).
    pub data: Option<Data>,
    pub outcome: Outcome,
    /// Its first frame, and the frame that ended it (for an unanswered
    /// transfer, the last frame the client sent).
    pub start: M,
    pub end: M,
}

/// Where a transfer stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// The client sent the initiate; the node's answer is due.
    Initiating,
    /// Segments going: `toggle` is the bit the next one carries.
    Segments { toggle: bool },
    /// A block transfer, followed by [`Blocks`](super::Blocks).
    Block,
}

/// A download segment the node has not confirmed yet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Pending {
    bytes: [u8; 7],
    used: u8,
    toggle: bool,
    last: bool,
}

/// One node's transfer going on.
#[derive(Clone, Copy, Debug)]
struct Going<M> {
    direction: Direction,
    object: Object,
    protocol: Protocol,
    indicated: Option<u32>,
    phase: Phase,
    data: Data,
    /// Whether data has begun to move (an upload's answer came).
    moved: bool,
    /// A download segment sent and not yet confirmed.
    pending: Option<Pending>,
    /// The segments are not read (a long transfer): only the last one and
    /// its answer.
    unread: bool,
    start: M,
    /// The transfer's last frame so far.
    last: M,
    /// The node owes the next frame since this one of the client's.
    waiting: Option<M>,
}

impl<M: Moment> Going<M> {
    fn new(direction: Direction, object: Object, protocol: Protocol, at: M) -> Self {
        Going {
            direction,
            object,
            protocol,
            indicated: None,
            phase: Phase::Initiating,
            data: Data::default(),
            moved: false,
            pending: None,
            unread: false,
            start: at,
            last: at,
            waiting: Some(at),
        }
    }

    fn end(self, node: NodeId, outcome: Outcome, at: M) -> Ended<M> {
        let moved = self.moved || self.direction == Direction::Download;
        let chosen = moved || self.protocol == Protocol::Block;
        // What a transfer that did not complete carried is known only as
        // far as it was read: not of a block transfer (its segments are
        // not read) nor of a long one.
        let known = outcome == Outcome::Ok
            || !(self.unread || self.protocol == Protocol::Block && !self.moved);
        Ended {
            node,
            direction: self.direction,
            object: self.object,
            protocol: chosen.then_some(self.protocol),
            indicated: self.indicated,
            data: (moved && known).then_some(self.data),
            outcome,
            start: self.start,
            end: at,
        }
    }

    /// It ends without an end of its own: unanswered when the node owed
    /// the next frame, incomplete when the client did.
    fn cut(self, node: NodeId) -> Ended<M> {
        match self.waiting {
            Some(w) => self.end(node, Outcome::Unanswered, w),
            None => self.end(node, Outcome::Incomplete, self.last),
        }
    }
}

/// Follows every node's SDO transfers (see the module's text).
#[derive(Clone, Debug)]
pub struct Transfers<M: Moment> {
    going: PerNode<Option<Going<M>>>,
    /// No later than the earliest time a transfer waiting for its node
    /// runs out (`None`: none waits).
    due: Option<Timestamp>,
    timeout: Span,
}

impl<M: Moment> Transfers<M> {
    /// Transfers the node does not answer within `timeout` are unanswered.
    pub fn new(timeout: Span) -> Self {
        Transfers {
            going: PerNode::default(),
            due: None,
            timeout,
        }
    }

    /// Whether the node of SDO id `id` has a segmented transfer whose
    /// every frame must be read: a short one or one of unknown size, or a
    /// long download whose last segment awaits its confirmation.
    pub fn reads_segments(&self, id: u32) -> bool {
        self.going.going_on(id, |g| {
            g.as_ref().is_some_and(|g| {
                matches!(g.phase, Phase::Segments { .. })
                    && (!g.unread || g.pending.is_some_and(|p| p.last))
            })
        })
    }

    /// Whether the node of SDO id `id` has a long segmented transfer going
    /// on (its initiate gave a size over [`READ_LIMIT`]): its last segment
    /// must pass the content filter, which other transfers' segments need
    /// not.
    pub fn is_long(&self, id: u32) -> bool {
        self.going
            .going_on(id, |g| g.as_ref().is_some_and(|g| g.unread))
    }

    /// Whether any node has a long segmented transfer going on.
    pub fn any_long(&self) -> bool {
        (1..=127).any(|node| self.is_long(super::REQUEST_BASE + node))
    }

    /// Feeds one frame on an SDO id that no block transfer took.
    pub fn feed(&mut self, id: u32, data: &[u8], at: M) -> Option<Ended<M>> {
        let (request, node, slot) = self.going.by_id(id)?;
        let node = node as NodeId;
        let &[cmd, ..] = data else {
            return None;
        };
        let cs = cmd >> 5;
        let ended = if request {
            client(slot, node, cmd, cs, data, at)
        } else {
            server(slot, node, cmd, cs, data, at)
        };
        if let Some(g) = slot
            && let Some(w) = g.waiting
        {
            self.note_due(w);
        }
        ended
    }

    /// A block transfer began (the client's initiate, which [`Blocks`]
    /// took): the one going on for the node, if any, is cut short.
    ///
    /// [`Blocks`]: super::Blocks
    pub fn block_begun(
        &mut self,
        node: NodeId,
        direction: Direction,
        object: Object,
        indicated: Option<u32>,
        at: M,
    ) -> Option<Ended<M>> {
        let slot = self.slot(node)?;
        let cut = slot.take().map(|g| g.cut(node));
        let mut g = Going::new(direction, object, Protocol::Block, at);
        g.indicated = indicated;
        g.phase = Phase::Block;
        // The block follower keeps the time of no frame after the
        // initiate: a block transfer is not timed out, only cut short.
        g.waiting = None;
        *slot = Some(g);
        cut
    }

    /// The block transfer of `node` ended with its receiver's end response:
    /// `size` bytes, `value` the first of them if the block follower kept
    /// them.
    pub fn block_done(
        &mut self,
        node: NodeId,
        size: u32,
        value: Option<(u32, u32)>,
        at: M,
    ) -> Option<Ended<M>> {
        let slot = self.slot(node)?;
        let mut g = slot.take().filter(|g| g.phase == Phase::Block)?;
        g.data = match value {
            Some((v, len)) => Data::of(v.to_le_bytes().get(..len as usize).unwrap_or_default()),
            None => Data {
                size,
                whole: false,
                ..Data::default()
            },
        };
        g.moved = true;
        Some(g.end(node, Outcome::Ok, at))
    }

    /// Whether a transfer waiting for its node may have run out by `now`.
    #[inline]
    pub fn passed(&self, now: Timestamp) -> bool {
        self.due.is_some_and(|d| now > d)
    }

    /// Transfers whose node gave no answer within the timeout by `now` end
    /// as unanswered, into `out` (by node).
    pub fn expire(&mut self, now: Timestamp, out: &mut Vec<Ended<M>>) {
        self.due = None;
        let timeout = self.timeout;
        let mut due: Option<Timestamp> = None;
        for node in 1..=127 as NodeId {
            let Some(slot) = self.slot(node) else {
                continue;
            };
            let Some(g) = *slot else { continue };
            let Some(limit) = g
                .waiting
                .and_then(|w| w.time())
                .and_then(|t| t.checked_add_span(timeout))
            else {
                continue;
            };
            if now > limit {
                *slot = None;
                out.push(g.cut(node));
            } else {
                due = Some(due.map_or(limit, |d| d.min(limit)));
            }
        }
        self.due = due;
    }

    /// The end of the input: every transfer still going is cut short, into
    /// `out` (by node).
    pub fn finish(&mut self, out: &mut Vec<Ended<M>>) {
        for node in 1..=127 as NodeId {
            if let Some(slot) = self.slot(node)
                && let Some(g) = slot.take()
            {
                out.push(g.cut(node));
            }
        }
        self.due = None;
    }

    fn slot(&mut self, node: NodeId) -> Option<&mut Option<Going<M>>> {
        let id = super::REQUEST_BASE + u32::from(node);
        self.going.by_id(id).map(|(_, _, slot)| slot)
    }

    fn note_due(&mut self, waiting: M) {
        if let Some(limit) = waiting
            .time()
            .and_then(|t| t.checked_add_span(self.timeout))
        {
            self.due = Some(self.due.map_or(limit, |d| d.min(limit)));
        }
    }
}

/// The object bytes 1-3 name.
fn object_of(data: &[u8]) -> Object {
    match *data {
        [_, lo, hi, sub, ..] => Object {
            index: u16::from_le_bytes([lo, hi]),
            sub,
        },
        [_, lo, hi] => Object {
            index: u16::from_le_bytes([lo, hi]),
            sub: 0,
        },
        _ => Object::default(),
    }
}

/// Bytes 4-7 as a size.
fn size_of(data: &[u8]) -> Option<u32> {
    match *data {
        [_, _, _, _, a, b, c, d, ..] => Some(u32::from_le_bytes([a, b, c, d])),
        _ => None,
    }
}

/// An expedited frame's data: 4 - n bytes when s is set, else four.
fn expedited(cmd: u8, data: &[u8]) -> Data {
    let used = if cmd & 0x01 != 0 {
        4 - usize::from((cmd >> 2) & 0b11)
    } else {
        4
    };
    Data::of(data.get(4..4 + used).unwrap_or_default())
}

/// An abort (its code in bytes 4-7) ends the transfer going on, if any.
fn aborted<M: Moment>(
    slot: &mut Option<Going<M>>,
    node: NodeId,
    data: &[u8],
    by_server: bool,
    at: M,
) -> Option<Ended<M>> {
    let code = size_of(data).unwrap_or(0);
    let g = slot.take()?;
    Some(g.end(node, Outcome::Abort { code, by_server }, at))
}

/// A frame of the client's (request id).
fn client<M: Moment>(
    slot: &mut Option<Going<M>>,
    node: NodeId,
    cmd: u8,
    cs: u8,
    data: &[u8],
    at: M,
) -> Option<Ended<M>> {
    match (cs, slot.as_mut()) {
        (CS_ABORT, Some(_)) => return aborted(slot, node, data, false, at),
        (CS_ABORT, None) => return None,
        (CCS_DOWNLOAD_SEGMENT, Some(g))
            if g.direction == Direction::Download && matches!(g.phase, Phase::Segments { .. }) =>
        {
            let used = 7 - ((cmd >> 1) & 0b111);
            let mut p = Pending {
                bytes: [0; 7],
                used: 0,
                toggle: cmd & 0x10 != 0,
                last: cmd & 0x01 != 0,
            };
            for (to, &from) in p
                .bytes
                .iter_mut()
                .zip(data.iter().skip(1))
                .take(used.into())
            {
                *to = from;
                p.used += 1;
            }
            // A repeat replaces the segment it repeats.
            g.pending = Some(p);
            g.last = at;
            g.waiting = Some(at);
            return None;
        }
        (CCS_UPLOAD_SEGMENT, Some(g))
            if g.direction == Direction::Upload && matches!(g.phase, Phase::Segments { .. }) =>
        {
            g.last = at;
            g.waiting = Some(at);
            return None;
        }
        _ => {}
    }
    // Anything else from the client begins a transfer (or is no command
    // this follower reads): what was going on is cut short.
    let cut = slot.take().map(|g| g.cut(node));
    let object = object_of(data);
    match cs {
        CCS_DOWNLOAD_INITIATE => {
            let mut g = Going::new(Direction::Download, object, Protocol::Expedited, at);
            if cmd & 0b10 != 0 {
                g.data = expedited(cmd, data);
                g.indicated = (cmd & 0x01 != 0).then_some(g.data.size);
            } else {
                g.protocol = Protocol::Segmented;
                g.indicated = (cmd & 0x01 != 0).then(|| size_of(data)).flatten();
                g.unread = g.indicated.is_some_and(|s| s > READ_LIMIT);
            }
            *slot = Some(g);
        }
        CCS_UPLOAD_INITIATE => {
            *slot = Some(Going::new(
                Direction::Upload,
                object,
                Protocol::Expedited,
                at,
            ));
        }
        _ => {}
    }
    cut
}

/// A frame of the node's (response id).
fn server<M: Moment>(
    slot: &mut Option<Going<M>>,
    node: NodeId,
    cmd: u8,
    cs: u8,
    data: &[u8],
    at: M,
) -> Option<Ended<M>> {
    if cs == CS_ABORT {
        return aborted(slot, node, data, true, at);
    }
    match cs {
        SCS_UPLOAD_INITIATE => {
            // The answer to an upload initiate; one the trace did not show
            // the request of (it began before) begins here.
            let mut g = match slot.take() {
                // A block upload the node switched to another protocol
                // answers so too.
                Some(g)
                    if g.direction == Direction::Upload
                        && matches!(g.phase, Phase::Initiating | Phase::Block) =>
                {
                    g
                }
                // An answer to something else: that transfer goes on.
                Some(other) => {
                    *slot = Some(other);
                    return None;
                }
                None => Going::new(Direction::Upload, object_of(data), Protocol::Expedited, at),
            };
            g.object = object_of(data);
            g.moved = true;
            g.last = at;
            g.waiting = None;
            if cmd & 0b10 != 0 {
                g.protocol = Protocol::Expedited;
                g.data = expedited(cmd, data);
                g.indicated = (cmd & 0x01 != 0).then_some(g.data.size);
                return Some(g.end(node, Outcome::Ok, at));
            }
            g.protocol = Protocol::Segmented;
            g.indicated = (cmd & 0x01 != 0).then(|| size_of(data)).flatten();
            g.unread = g.indicated.is_some_and(|s| s > READ_LIMIT);
            g.phase = Phase::Segments { toggle: false };
            *slot = Some(g);
            None
        }
        SCS_DOWNLOAD_INITIATE => {
            let g = slot.as_mut()?;
            if g.direction != Direction::Download || g.phase != Phase::Initiating {
                return None;
            }
            g.last = at;
            g.waiting = None;
            if g.protocol == Protocol::Expedited {
                let g = slot.take()?;
                return Some(g.end(node, Outcome::Ok, at));
            }
            g.phase = Phase::Segments { toggle: false };
            None
        }
        SCS_DOWNLOAD_SEGMENT => {
            let g = slot.as_mut()?;
            let Phase::Segments { toggle } = g.phase else {
                return None;
            };
            if g.direction != Direction::Download {
                return None;
            }
            let p = g.pending.take()?;
            let confirmed = cmd & 0x10 != 0;
            if !g.unread {
                if p.toggle != toggle || confirmed != toggle {
                    // Out of step: the data cannot be trusted.
                    g.data.whole = false;
                }
                g.data
                    .extend(p.bytes.get(..p.used.into()).unwrap_or_default());
            }
            g.last = at;
            g.waiting = None;
            g.phase = Phase::Segments { toggle: !toggle };
            if !p.last {
                return None;
            }
            let mut g = slot.take()?;
            count_unread(&mut g);
            Some(g.end(node, Outcome::Ok, at))
        }
        SCS_UPLOAD_SEGMENT => {
            let g = slot.as_mut()?;
            let Phase::Segments { toggle } = g.phase else {
                return None;
            };
            if g.direction != Direction::Upload {
                return None;
            }
            if !g.unread {
                if (cmd & 0x10 != 0) != toggle {
                    g.data.whole = false;
                }
                let used = usize::from(7 - ((cmd >> 1) & 0b111));
                g.data.extend(
                    data.get(1..)
                        .unwrap_or_default()
                        .get(..used)
                        .unwrap_or_default(),
                );
            }
            g.last = at;
            g.waiting = None;
            g.phase = Phase::Segments { toggle: !toggle };
            if cmd & 0x01 == 0 {
                return None;
            }
            let mut g = slot.take()?;
            count_unread(&mut g);
            if g.indicated.is_some_and(|s| s != g.data.size) {
                g.data.whole = false;
            }
            Some(g.end(node, Outcome::Ok, at))
        }
        _ => None,
    }
}

/// A long transfer whose segments were not read carried what its initiate
/// said.
fn count_unread<M>(g: &mut Going<M>) {
    if g.unread {
        g.data = Data {
            size: g.indicated.unwrap_or(0),
            whole: false,
            ..Data::default()
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line number and a time in milliseconds.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    struct L(u64);

    impl Moment for L {
        fn time(&self) -> Option<Timestamp> {
            Some(Timestamp::from_parts(self.0 / 1000, self.0 % 1000, 3))
        }
    }

    fn follower() -> Transfers<L> {
        Transfers::new(Span::from_millis(1000))
    }

    fn object(index: u16, sub: u8) -> Object {
        Object { index, sub }
    }

    #[test]
    fn expedited_download_and_upload() {
        let mut t = follower();
        assert_eq!(
            t.feed(0x605, &[0x2B, 0x17, 0x10, 0, 0xE8, 0x03, 0, 0], L(1)),
            None
        );
        let e = t
            .feed(0x585, &[0x60, 0x17, 0x10, 0, 0, 0, 0, 0], L(2))
            .unwrap();
        assert_eq!(
            (e.node, e.direction, e.object, e.protocol, e.outcome),
            (
                5,
                Direction::Download,
                object(0x1017, 0),
                Some(Protocol::Expedited),
                Outcome::Ok
            )
        );
        assert_eq!((e.start, e.end, e.indicated), (L(1), L(2), Some(2)));
        assert_eq!(e.data.unwrap().shown(), &[0xE8, 0x03]);
        assert_eq!(e.data.unwrap().number(), Some(1000));
        t.feed(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0], L(3));
        let e = t
            .feed(0x585, &[0x43, 0x00, 0x10, 0, 0x92, 0x01, 0x02, 0x00], L(4))
            .unwrap();
        assert_eq!((e.direction, e.outcome), (Direction::Upload, Outcome::Ok));
        assert_eq!(e.data.unwrap().number(), Some(0x0002_0192));
        assert_eq!(
            t.feed(0x585, &[0x60, 0x17, 0x10, 0, 0, 0, 0, 0], L(5)),
            None
        );
    }

    #[test]
    fn segmented_upload_of_a_text() {
        let mut t = follower();
        t.feed(0x603, &[0x40, 0x08, 0x10, 0, 0, 0, 0, 0], L(1));
        t.feed(0x583, &[0x41, 0x08, 0x10, 0, 9, 0, 0, 0], L(2));
        assert!(t.reads_segments(0x583) && t.reads_segments(0x603));
        t.feed(0x603, &[0x60, 0, 0, 0, 0, 0, 0, 0], L(3));
        t.feed(
            0x583,
            &[0x00, b'S', b'e', b'r', b'v', b'o', b' ', b'X'],
            L(4),
        );
        t.feed(0x603, &[0x70, 0, 0, 0, 0, 0, 0, 0], L(5));
        let e = t
            .feed(0x583, &[0x1B, b'1', b'2', 0, 0, 0, 0, 0], L(6))
            .unwrap();
        let d = e.data.unwrap();
        assert_eq!(d.shown(), b"Servo X12");
        assert!(d.complete());
        assert_eq!(
            (e.protocol, e.indicated, e.start, e.end),
            (Some(Protocol::Segmented), Some(9), L(1), L(6))
        );
        assert!(!t.reads_segments(0x583));
        assert_eq!(d.hash, Data::of(b"Servo X12").hash);
    }

    #[test]
    fn segmented_download_with_a_repeat_and_toggles() {
        let mut t = follower();
        t.feed(0x605, &[0x21, 0x00, 0x20, 1, 10, 0, 0, 0], L(1));
        t.feed(0x585, &[0x60, 0x00, 0x20, 1, 0, 0, 0, 0], L(2));
        t.feed(0x605, &[0x00, 1, 2, 3, 4, 5, 6, 7], L(3));
        t.feed(0x605, &[0x00, 1, 2, 3, 4, 5, 6, 7], L(4));
        assert_eq!(t.feed(0x585, &[0x20, 0, 0, 0, 0, 0, 0, 0], L(5)), None);
        t.feed(0x605, &[0x19, 8, 9, 10, 0, 0, 0, 0], L(6));
        let e = t.feed(0x585, &[0x30, 0, 0, 0, 0, 0, 0, 0], L(7)).unwrap();
        let d = e.data.unwrap();
        assert_eq!(d.shown(), &[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]);
        assert!(d.whole);
        assert_eq!(e.outcome, Outcome::Ok);
    }

    #[test]
    fn long_transfers_are_counted_not_read() {
        let mut t = follower();
        // A 100 kB firmware download: only its initiate, last segment and
        // the answer to it are seen.
        t.feed(0x602, &[0x21, 0x50, 0x1F, 1, 0xA0, 0x86, 0x01, 0], L(1));
        t.feed(0x582, &[0x60, 0x50, 0x1F, 1, 0, 0, 0, 0], L(2));
        assert!(!t.reads_segments(0x602), "segments left to the filter");
        assert!(t.is_long(0x602) && t.is_long(0x582) && t.any_long());
        assert!(!t.is_long(0x603));
        t.feed(0x602, &[0x0B, 1, 2, 3, 4, 0, 0, 0], L(900));
        assert!(t.reads_segments(0x602), "the answer to the last segment");
        let e = t.feed(0x582, &[0x30, 0, 0, 0, 0, 0, 0, 0], L(901)).unwrap();
        let d = e.data.unwrap();
        assert_eq!((d.size, d.whole, e.outcome), (100_000, false, Outcome::Ok));
        assert!(!t.any_long(), "over");
        assert!(!d.complete());
    }

    #[test]
    fn aborts_unanswered_and_cut_short() {
        let mut t = follower();
        // The node aborts a write.
        t.feed(0x605, &[0x23, 0x00, 0x18, 1, 0x85, 0x01, 0, 0], L(1));
        let e = t
            .feed(0x585, &[0x80, 0x00, 0x18, 1, 0x00, 0x00, 0x09, 0x06], L(2))
            .unwrap();
        assert_eq!(
            e.outcome,
            Outcome::Abort {
                code: 0x0609_0000,
                by_server: true
            }
        );
        // An upload nobody answers: unanswered once the timeout passed.
        t.feed(0x607, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0], L(1000));
        let mut out = Vec::new();
        t.expire(Timestamp::from_parts(2, 0, 3), &mut out);
        assert!(out.is_empty(), "at the timeout is still in time");
        assert!(
            !t.passed(Timestamp::from_parts(2, 0, 3)),
            "due again at 2.000"
        );
        assert!(t.passed(Timestamp::from_parts(2, 1, 3)));
        t.expire(Timestamp::from_parts(2, 1, 3), &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(
            (out[0].node, out[0].outcome, out[0].data),
            (7, Outcome::Unanswered, None)
        );
        assert_eq!(out[0].end, L(1000));
        assert!(!t.passed(Timestamp::from_parts(99, 0, 3)));
        // A new request before the answer: the first was unanswered.
        t.feed(0x607, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0], L(3000));
        let e = t
            .feed(0x607, &[0x40, 0x18, 0x10, 1, 0, 0, 0, 0], L(3001))
            .unwrap();
        assert_eq!(
            (e.outcome, e.object),
            (Outcome::Unanswered, object(0x1000, 0))
        );
        // The client stops asking for segments: incomplete at the end.
        t.feed(0x583, &[0x41, 0x08, 0x10, 0, 9, 0, 0, 0], L(3002));
        out.clear();
        t.finish(&mut out);
        let outcomes: Vec<_> = out.iter().map(|e| (e.node, e.outcome)).collect();
        assert_eq!(
            outcomes,
            [(3, Outcome::Incomplete), (7, Outcome::Unanswered)]
        );
    }

    #[test]
    fn block_transfers_are_told_by_the_block_follower() {
        let mut t = follower();
        t.block_begun(4, Direction::Download, object(0x1F50, 1), Some(300), L(1));
        assert_eq!(
            t.feed(0x584, &[0xA4, 0x50, 0x1F, 1, 127, 0, 0, 0], L(2)),
            None
        );
        let e = t.block_done(4, 300, None, L(9)).unwrap();
        assert_eq!(
            (e.protocol, e.outcome, e.data.unwrap().size),
            (Some(Protocol::Block), Outcome::Ok, 300)
        );
        // An abort ends one.
        t.block_begun(4, Direction::Upload, object(0x2000, 0), None, L(10));
        let e = t
            .feed(0x604, &[0x80, 0x00, 0x20, 0, 0x01, 0x00, 0x04, 0x05], L(11))
            .unwrap();
        assert_eq!(e.outcome.name(), "abort");
        assert_eq!(e.data, None, "its segments were not read");
        // A long download aborted: nothing read, nothing told of its data.
        t.feed(0x602, &[0x21, 0x50, 0x1F, 1, 0xA0, 0x86, 0x01, 0], L(20));
        t.feed(0x582, &[0x60, 0x50, 0x1F, 1, 0, 0, 0, 0], L(21));
        let e = t
            .feed(0x582, &[0x80, 0x50, 0x1F, 1, 0, 0, 0x04, 0x05], L(22))
            .unwrap();
        assert_eq!((e.data, e.indicated), (None, Some(100_000)));
    }

    #[test]
    fn data_numbers_and_hashes() {
        assert_eq!(Data::of(&[0x34, 0x12]).number(), Some(0x1234));
        assert_eq!(Data::of(&[1, 2, 3, 4, 5]).number(), None);
        let long: Vec<u8> = (0..200u8).collect();
        let d = Data::of(&long);
        assert_eq!((d.size, d.shown().len(), d.complete()), (200, 64, false));
        assert_ne!(d.hash, Data::of(&long[..199]).hash);
    }
}
