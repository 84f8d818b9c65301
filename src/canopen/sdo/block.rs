//! Following SDO block transfers (CiA 301 §7.2.4.3.9-16), download and
//! upload, per node: which frames belong to one, and the value one carried.
//!
//! A block transfer's segments carry a sequence number (1-127, bit 7 set on
//! the transfer's last segment) where other frames carry a command
//! specifier, so only the transfer they belong to says what they are: the
//! last segment of a block download, `0x85` say, would otherwise read as a
//! client's abort, and a segment's data as an object index. Where a
//! segment may stand is decided by the phase alone: right after the
//! receiver's initiate response, start or acknowledgement a sub-block
//! begins with segment 1 (or the sender ends the transfer); inside a
//! sub-block every frame of the sender but an abort (`0x80`) is a segment.
//!
//! Data is kept only for the objects the decoder learns from, and only
//! their first [`KEPT_BYTES`]: a firmware download (0x1F50) is followed to
//! its end and nothing of it kept.
//!
//! The content filter lets through only the SDO frames that may matter, so
//! not every segment of a long transfer reaches this: it need not. A value
//! kept fits in a transfer's one segment (1, `0x01` or `0x81`), the block
//! commands and every sub-block's segment 1 always pass the filter, and
//! inside a sub-block a missed segment changes nothing but the data, which
//! is not kept then (the receiver's acknowledgement tells what it took).

use super::access::{
    CCS_BLOCK_DOWNLOAD, CCS_BLOCK_UPLOAD, CS_ABORT, Object, PerNode, SCS_BLOCK_DOWNLOAD,
    SCS_BLOCK_UPLOAD,
};
use super::segmented::Confirmed;
use crate::canopen::NodeId;

/// Bytes of a transfer's data kept: every object the decoder learns from
/// is at most 4 bytes.
const KEPT_BYTES: usize = 4;

/// Data bytes in a sub-block segment.
const SEGMENT_BYTES: u32 = 7;

/// The abort command byte: during a sub-block the sender's frames are
/// segments unless they are exactly this (a segment's sequence number is
/// never 0).
const ABORT: u8 = CS_ABORT << 5;

/// What a frame on an SDO id is to the block transfers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockStep {
    /// No block transfer's frame: read it as any other SDO frame (aborts
    /// included: an abort ends the node's block transfer and is then read
    /// as one).
    Other,
    /// A frame of a block transfer: its initiate, or one of a transfer
    /// going on.
    Part,
    /// The frame that completed a block transfer: an upload the client
    /// confirmed (`upload`), or a download the node confirmed. `None` when
    /// the value was not kept (longer than [`KEPT_BYTES`], segments not
    /// all seen, a size or CRC that did not match).
    Done {
        node: NodeId,
        object: Object,
        upload: bool,
        value: Option<Confirmed>,
        /// Bytes the receiver acknowledged, less those unused in the last
        /// segment.
        size: u32,
    },
}

/// One node's block transfer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Phase {
    #[default]
    Idle,
    /// The client asked; the server's initiate response is due.
    Initiating,
    /// Upload only: the server answered with the size; the client's start
    /// is due.
    Answered,
    /// A sub-block is due or going on: `seen` segments of it so far.
    SubBlock { seen: u8 },
    /// The sender ended the transfer; the receiver's end response is due.
    Ending,
}

/// One node's block transfer and what it has carried.
#[derive(Clone, Copy, Debug, Default)]
struct Transfer {
    phase: Phase,
    upload: bool,
    object: Object,
    /// Whether the data is kept ([`keeps`] said so at the initiate).
    keep: bool,
    /// Both sides said they support a CRC (the initiate and its response).
    crc: bool,
    /// The size the initiate (download) or its response (upload) gave.
    size: Option<u32>,
    /// Sequence number of the last segment of this sub-block received in
    /// order (the receiver acknowledges this one).
    in_order: u8,
    /// Whether the segment `in_order` was the transfer's last.
    last_in_order: bool,
    /// Whether the last acknowledgement covered the transfer's last segment.
    last_acked: bool,
    /// Bytes acknowledged in earlier sub-blocks, of segments received in
    /// order (the data kept is placed by it).
    acked: u32,
    /// Bytes the receiver said it took, whether the trace showed their
    /// segments or not (the content filter keeps most of them back): the
    /// transfer's size.
    carried: u32,
    /// The transfer's first bytes, as far as received.
    kept: [u8; KEPT_BYTES],
    /// Whether the data kept can be trusted: a frame of the transfer was
    /// missed or out of step when this is false.
    whole: bool,
}

/// Follows the block transfers of every node (ids 1-127): one small fixed
/// record per node, whatever the trace.
#[derive(Clone, Debug, Default)]
pub struct Blocks {
    transfers: PerNode<Transfer>,
    /// How many nodes have a block transfer going on: the per-frame test
    /// is this one number while none has.
    going: u8,
}

/// Whether a block transfer of `object` keeps its data: the objects some
/// monitor learns from (followed, PDO parameters, the drive's words).
pub type Keeps = fn(u16) -> bool;

impl Blocks {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds one frame on an SDO id; `keeps` says of a transfer's object
    /// whether its data is worth keeping.
    pub fn feed(&mut self, id: u32, data: &[u8], keeps: Keeps) -> BlockStep {
        let Some((request, node, t)) = self.transfers.by_id(id) else {
            return BlockStep::Other;
        };
        let &[cmd, ..] = data else {
            return BlockStep::Other;
        };
        let cs = cmd >> 5;
        // Only initiates start a transfer: nothing else to read while no
        // node has one going.
        if self.going == 0 && !(request && (cs == CCS_BLOCK_DOWNLOAD || cs == CCS_BLOCK_UPLOAD)) {
            return BlockStep::Other;
        }
        let node = node as NodeId;
        let was_going = t.phase != Phase::Idle;
        let step = step(t, node, request, cmd, data, keeps);
        let going = t.phase != Phase::Idle;
        match (was_going, going) {
            (false, true) => self.going = self.going.saturating_add(1),
            (true, false) => self.going = self.going.saturating_sub(1),
            _ => {}
        }
        step
    }

    /// The block transfer `node` just began (its client's initiate, no
    /// answer yet): whether it is an upload, its object and the size the
    /// initiate gave.
    pub fn begun(&self, node: NodeId) -> Option<(bool, Object, Option<u32>)> {
        self.transfers
            .get(u32::from(node))
            .filter(|t| t.phase == Phase::Initiating)
            .map(|t| (t.upload, t.object, t.size))
    }

    /// Whether `node` has a block transfer going on.
    pub fn going(&self, node: NodeId) -> bool {
        self.transfers
            .get(u32::from(node))
            .is_some_and(|t| t.phase != Phase::Idle)
    }
}

/// The object an initiate names.
fn object_of(data: &[u8]) -> Option<Object> {
    match *data {
        [_, lo, hi, sub, ..] => Some(Object {
            index: u16::from_le_bytes([lo, hi]),
            sub,
        }),
        _ => None,
    }
}

/// Bytes 4-7 as a number (a size), if the frame has them.
fn size_of(data: &[u8]) -> Option<u32> {
    match *data {
        [_, _, _, _, a, b, c, d, ..] => Some(u32::from_le_bytes([a, b, c, d])),
        _ => None,
    }
}

/// One frame of `node`'s SDO channel against its block transfer `t`.
fn step(
    t: &mut Transfer,
    node: NodeId,
    request: bool,
    cmd: u8,
    data: &[u8],
    keeps: Keeps,
) -> BlockStep {
    let cs = cmd >> 5;
    // The side that sends the segments: the client downloads, the server
    // uploads.
    let sender = request != t.upload;
    match t.phase {
        Phase::Idle => return initiate(t, request, cmd, data, keeps),
        Phase::SubBlock { seen } if sender => {
            if cmd == ABORT {
                *t = Transfer::default();
                return BlockStep::Other;
            }
            let seqno = cmd & 0x7F;
            if seen == 0 && seqno != 1 {
                // No sub-block going: the sender ends the transfer, or
                // this is no frame of it.
                let ends = cs == end_cs(t.upload) && cmd & 0x01 != 0;
                if ends {
                    return end(t, cmd, data);
                }
                return give_up(t, request, cmd, data, keeps);
            }
            segment(t, seqno, cmd & 0x80 != 0, data);
            t.phase = Phase::SubBlock {
                seen: seen.saturating_add(1),
            };
            return BlockStep::Part;
        }
        _ => {}
    }
    if cs == CS_ABORT {
        *t = Transfer::default();
        return BlockStep::Other;
    }
    match (t.phase, t.upload, request) {
        // Download: the server's initiate response, with its block size.
        (Phase::Initiating, false, false) if cs == SCS_BLOCK_DOWNLOAD && cmd & 0x03 == 0 => {
            t.crc &= cmd & 0x04 != 0;
            t.phase = Phase::SubBlock { seen: 0 };
            BlockStep::Part
        }
        // Upload: the server's initiate response, with the size; or a
        // switch to the segmented or expedited protocol (the client's
        // threshold allowed it), read as any other frame.
        (Phase::Initiating, true, false) if cs == SCS_BLOCK_UPLOAD && cmd & 0x01 == 0 => {
            t.crc &= cmd & 0x04 != 0;
            t.size = (cmd & 0x02 != 0).then(|| size_of(data)).flatten();
            t.phase = Phase::Answered;
            BlockStep::Part
        }
        // Upload: the client starts the first sub-block.
        (Phase::Answered, true, true) if cs == CCS_BLOCK_UPLOAD && cmd & 0x03 == 0x03 => {
            t.phase = Phase::SubBlock { seen: 0 };
            BlockStep::Part
        }
        // The receiver acknowledges a sub-block: `ackseq` segments taken,
        // the next sub-block's size.
        (Phase::SubBlock { .. }, upload, request)
            if request == upload && cs == ack_cs(upload) && cmd & 0x03 == 0x02 =>
        {
            acknowledged(t, data.get(1).copied().unwrap_or(0));
            BlockStep::Part
        }
        // The receiver's end response.
        (Phase::Ending, upload, request)
            if request == upload && cs == ack_cs(upload) && cmd & 0x03 == 0x01 =>
        {
            let done = BlockStep::Done {
                node,
                object: t.object,
                upload,
                value: value(t, node),
                size: t.carried,
            };
            *t = Transfer::default();
            done
        }
        // Anything else: the transfer is out of step (or the client began
        // another), and the frame is read as any other.
        _ => give_up(t, request, cmd, data, keeps),
    }
}

/// The command specifier of the sender's end: the block command of its
/// side.
fn end_cs(upload: bool) -> u8 {
    if upload {
        SCS_BLOCK_UPLOAD
    } else {
        CCS_BLOCK_DOWNLOAD
    }
}

/// The command specifier of the receiver's acknowledgements and end
/// response.
fn ack_cs(upload: bool) -> u8 {
    if upload {
        CCS_BLOCK_UPLOAD
    } else {
        SCS_BLOCK_DOWNLOAD
    }
}

/// A frame of no transfer: the client's block initiate starts one.
fn initiate(t: &mut Transfer, request: bool, cmd: u8, data: &[u8], keeps: Keeps) -> BlockStep {
    let cs = cmd >> 5;
    if !request {
        return BlockStep::Other;
    }
    // Download initiate: cc (bit 2), s (bit 1), cs = 0 (bit 0). Upload
    // initiate: cc (bit 2), cs = 0 (bits 0-1).
    let (upload, size) = match cs {
        CCS_BLOCK_DOWNLOAD if cmd & 0x01 == 0 => {
            (false, (cmd & 0x02 != 0).then(|| size_of(data)).flatten())
        }
        CCS_BLOCK_UPLOAD if cmd & 0x03 == 0 => (true, None),
        _ => return BlockStep::Other,
    };
    let Some(object) = object_of(data) else {
        return BlockStep::Other;
    };
    *t = Transfer {
        phase: Phase::Initiating,
        upload,
        object,
        keep: keeps(object.index),
        crc: cmd & 0x04 != 0,
        size,
        whole: true,
        ..Transfer::default()
    };
    BlockStep::Part
}

/// The transfer ends out of step; the frame may begin another.
fn give_up(t: &mut Transfer, request: bool, cmd: u8, data: &[u8], keeps: Keeps) -> BlockStep {
    *t = Transfer::default();
    initiate(t, request, cmd, data, keeps)
}

/// Segment `seqno` of the sub-block (the transfer's last when `last`).
fn segment(t: &mut Transfer, seqno: u8, last: bool, data: &[u8]) {
    if seqno != t.in_order.wrapping_add(1) || t.last_in_order {
        // Out of order: the receiver ignores it (and its acknowledgement
        // asks again from the last one in order).
        return;
    }
    t.in_order = seqno;
    t.last_in_order = last;
    if !t.keep {
        return;
    }
    let at = t.acked.saturating_add(u32::from(seqno - 1) * SEGMENT_BYTES);
    for (i, &b) in data.iter().skip(1).take(SEGMENT_BYTES as usize).enumerate() {
        let pos = at.saturating_add(i as u32) as usize;
        if let Some(k) = t.kept.get_mut(pos) {
            *k = b;
        }
    }
}

/// The receiver took `ackseq` segments of the sub-block.
fn acknowledged(t: &mut Transfer, ackseq: u8) {
    if ackseq > t.in_order {
        // It took segments the trace did not show in order.
        t.whole = false;
    }
    let taken = ackseq.min(t.in_order);
    t.acked = t.acked.saturating_add(u32::from(taken) * SEGMENT_BYTES);
    t.carried = t
        .carried
        .saturating_add(u32::from(ackseq & 0x7F) * SEGMENT_BYTES);
    t.last_acked = t.last_in_order && ackseq >= t.in_order;
    t.in_order = 0;
    t.last_in_order = false;
    t.phase = Phase::SubBlock { seen: 0 };
}

/// The sender's end: `n` (bits 2-4) bytes of the last segment unused, and
/// the CRC in bytes 1-2.
fn end(t: &mut Transfer, cmd: u8, data: &[u8]) -> BlockStep {
    if !t.last_acked {
        t.whole = false;
    }
    let unused = u32::from((cmd >> 2) & 0x07);
    t.carried = t.carried.saturating_sub(unused);
    let len = t.acked.saturating_sub(unused);
    if t.size.is_some_and(|s| s != len) {
        t.whole = false;
    }
    t.acked = len;
    if t.crc
        && let [_, lo, hi, ..] = *data
        && len as usize <= KEPT_BYTES
    {
        let kept = t.kept.get(..len as usize).unwrap_or(&[]);
        if crc16(kept) != u16::from_le_bytes([lo, hi]) {
            t.whole = false;
        }
    }
    t.phase = Phase::Ending;
    BlockStep::Part
}

/// The value a completed transfer carried, if it was kept whole.
fn value(t: &Transfer, node: NodeId) -> Option<Confirmed> {
    if !(t.keep && t.whole) || t.acked as usize > KEPT_BYTES {
        return None;
    }
    let mut bytes = t.kept;
    for b in bytes.iter_mut().skip(t.acked as usize) {
        *b = 0;
    }
    Some(Confirmed {
        node,
        object: t.object,
        value: u32::from_le_bytes(bytes),
        len: t.acked,
    })
}

/// The block transfer's CRC (CiA 301: CRC-16-CCITT, x^16 + x^12 + x^5 + 1,
/// starting from 0), of data the decoder kept whole.
pub fn crc16(data: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    for &b in data {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keeps(index: u16) -> bool {
        index < 0x1F00
    }

    const DEVICE_TYPE: Object = Object {
        index: 0x1000,
        sub: 0,
    };

    fn feed(b: &mut Blocks, id: u32, data: &[u8]) -> BlockStep {
        b.feed(id, data, keeps)
    }

    /// A block download of `value` (4 bytes) to node 4, CRC on both sides.
    fn download_frames(value: [u8; 4]) -> Vec<(u32, [u8; 8])> {
        let crc = crc16(&value).to_le_bytes();
        vec![
            (0x604, [0xC6, 0x00, 0x10, 0x00, 4, 0, 0, 0]),
            (0x584, [0xA4, 0x00, 0x10, 0x00, 127, 0, 0, 0]),
            // The only segment, the last: 0x81, 3 bytes unused.
            (
                0x604,
                [0x81, value[0], value[1], value[2], value[3], 0, 0, 0],
            ),
            (0x584, [0xA2, 1, 127, 0, 0, 0, 0, 0]),
            // End: n = 3 (0x0C), CRC.
            (0x604, [0xCD, crc[0], crc[1], 0, 0, 0, 0, 0]),
            (0x584, [0xA1, 0, 0, 0, 0, 0, 0, 0]),
        ]
    }

    #[test]
    fn download_every_phase() {
        let mut b = Blocks::new();
        let frames = download_frames([0x92, 0x01, 0x02, 0x00]);
        let steps: Vec<BlockStep> = frames.iter().map(|(id, d)| feed(&mut b, *id, d)).collect();
        assert!(steps[..5].iter().all(|s| *s == BlockStep::Part));
        assert_eq!(
            steps[5],
            BlockStep::Done {
                node: 4,
                object: DEVICE_TYPE,
                upload: false,
                value: Some(Confirmed {
                    node: 4,
                    object: DEVICE_TYPE,
                    value: 0x0002_0192,
                    len: 4
                }),
                size: 4,
            }
        );
        assert!(!b.going(4));
        assert_eq!(b.going, 0);
    }

    #[test]
    fn the_size_is_what_the_receiver_acknowledged_seen_or_not() {
        let mut b = Blocks::new();
        // 20 bytes to 0x2010 sub 1; segment 2 never reaches the follower
        // (the content filter keeps it back).
        feed(&mut b, 0x603, &[0xC2, 0x10, 0x20, 1, 20, 0, 0, 0]);
        assert_eq!(
            b.begun(3),
            Some((
                false,
                Object {
                    index: 0x2010,
                    sub: 1
                },
                Some(20)
            ))
        );
        feed(&mut b, 0x583, &[0xA0, 0x10, 0x20, 1, 127, 0, 0, 0]);
        assert_eq!(b.begun(3), None, "answered");
        feed(&mut b, 0x603, &[0x01, 1, 2, 3, 4, 5, 6, 7]);
        feed(&mut b, 0x603, &[0x83, 15, 16, 17, 18, 19, 20, 0]);
        feed(&mut b, 0x583, &[0xA2, 3, 127, 0, 0, 0, 0, 0]);
        feed(&mut b, 0x603, &[0xC5, 0, 0, 0, 0, 0, 0, 0]);
        let done = feed(&mut b, 0x583, &[0xA1, 0, 0, 0, 0, 0, 0, 0]);
        assert!(
            matches!(
                done,
                BlockStep::Done {
                    size: 20,
                    value: None,
                    ..
                }
            ),
            "{done:?}"
        );
    }

    #[test]
    fn a_wrong_crc_or_size_keeps_no_value() {
        let mut b = Blocks::new();
        let mut frames = download_frames([0x92, 0x01, 0x02, 0x00]);
        frames[4].1[1] ^= 0xFF;
        let last = frames.iter().map(|(id, d)| feed(&mut b, *id, d)).last();
        assert!(matches!(last, Some(BlockStep::Done { value: None, .. })));
        // The server without CRC (0xA0): the CRC bytes are not read.
        let mut frames = download_frames([0x92, 0x01, 0x02, 0x00]);
        frames[1].1[0] = 0xA0;
        frames[4].1[1] ^= 0xFF;
        let last = frames.iter().map(|(id, d)| feed(&mut b, *id, d)).last();
        assert!(matches!(last, Some(BlockStep::Done { value: Some(_), .. })));
        // A size of 5 indicated, 4 sent.
        let mut frames = download_frames([0x92, 0x01, 0x02, 0x00]);
        frames[0].1[4] = 5;
        let last = frames.iter().map(|(id, d)| feed(&mut b, *id, d)).last();
        assert!(matches!(last, Some(BlockStep::Done { value: None, .. })));
    }

    #[test]
    fn a_last_segment_is_no_abort_and_data_is_no_command() {
        let mut b = Blocks::new();
        // A long download of 0x1F50 (not kept): sub-block of 5 segments,
        // the last 0x85; segments whose bytes look like commands.
        feed(&mut b, 0x604, &[0xC2, 0x50, 0x1F, 0x01, 33, 0, 0, 0]);
        feed(&mut b, 0x584, &[0xA0, 0x50, 0x1F, 0x01, 5, 0, 0, 0]);
        for seg in [
            [0x01, 0x00, 0x10, 0, 0, 0, 0, 0],
            [0x02, 0x14, 0x10, 0, 0, 0, 0, 0],
            [0x03, 0x00, 0x1A, 1, 0, 0, 0, 0],
            [0x04, 0x40, 0x60, 0, 0, 0, 0, 0],
        ] {
            assert_eq!(feed(&mut b, 0x604, &seg), BlockStep::Part);
        }
        assert_eq!(
            feed(&mut b, 0x584, &[0xA2, 4, 5, 0, 0, 0, 0, 0]),
            BlockStep::Part
        );
        // Next sub-block: one segment, the transfer's last (0x81).
        assert_eq!(
            feed(&mut b, 0x604, &[0x81, 1, 2, 3, 4, 5, 0, 0]),
            BlockStep::Part
        );
        assert_eq!(
            feed(&mut b, 0x584, &[0xA2, 1, 5, 0, 0, 0, 0, 0]),
            BlockStep::Part
        );
        // End, n = 2: 28 + 5 = 33 bytes.
        assert_eq!(
            feed(&mut b, 0x604, &[0xC9, 0, 0, 0, 0, 0, 0, 0]),
            BlockStep::Part
        );
        assert_eq!(
            feed(&mut b, 0x584, &[0xA1, 0, 0, 0, 0, 0, 0, 0]),
            BlockStep::Done {
                node: 4,
                object: Object {
                    index: 0x1F50,
                    sub: 1
                },
                upload: false,
                value: None,
                size: 33,
            }
        );
        // The same with 0x85 as the fifth segment of a sub-block.
        feed(&mut b, 0x604, &[0xC0, 0x50, 0x1F, 0x01, 0, 0, 0, 0]);
        feed(&mut b, 0x584, &[0xA0, 0x50, 0x1F, 0x01, 127, 0, 0, 0]);
        for seq in 1..=4u8 {
            feed(&mut b, 0x604, &[seq, 0xFF, 0, 0, 0, 0, 0, 0]);
        }
        assert_eq!(
            feed(&mut b, 0x604, &[0x85, 0x00, 0x10, 0, 0, 0, 0, 0]),
            BlockStep::Part
        );
        assert!(b.going(4));
    }

    #[test]
    fn segments_the_filter_kept_back_change_nothing_but_the_data() {
        // Only segment 1 and the last (0x85) of a sub-block reach the
        // follower, as the content filter lets them by: the transfer is
        // still read to its end, the 0x85 no abort.
        let mut b = Blocks::new();
        feed(&mut b, 0x604, &[0xC2, 0x00, 0x10, 0x01, 33, 0, 0, 0]);
        feed(&mut b, 0x584, &[0xA0, 0x00, 0x10, 0x01, 127, 0, 0, 0]);
        assert_eq!(
            feed(&mut b, 0x604, &[0x01, 1, 2, 3, 4, 5, 6, 7]),
            BlockStep::Part
        );
        assert_eq!(
            feed(&mut b, 0x604, &[0x85, 0, 0, 0, 0, 0, 0, 0]),
            BlockStep::Part
        );
        assert_eq!(
            feed(&mut b, 0x584, &[0xA2, 5, 127, 0, 0, 0, 0, 0]),
            BlockStep::Part
        );
        assert_eq!(
            feed(&mut b, 0x604, &[0xC9, 0, 0, 0, 0, 0, 0, 0]),
            BlockStep::Part
        );
        let done = feed(&mut b, 0x584, &[0xA1, 0, 0, 0, 0, 0, 0, 0]);
        assert!(
            matches!(done, BlockStep::Done { value: None, .. }),
            "{done:?}"
        );
        assert!(!b.going(4));
    }

    #[test]
    fn wrong_sequence_is_asked_again() {
        let mut b = Blocks::new();
        // 10 bytes of 0x1000 sub 1 (kept, but too long to keep whole): the
        // server takes segment 1 only, segment 2 comes again.
        feed(&mut b, 0x604, &[0xC2, 0x00, 0x10, 0x01, 10, 0, 0, 0]);
        feed(&mut b, 0x584, &[0xA0, 0x00, 0x10, 0x01, 127, 0, 0, 0]);
        feed(&mut b, 0x604, &[0x01, 1, 2, 3, 4, 5, 6, 7]);
        // Segment 3 where 2 was due: ignored.
        assert_eq!(
            feed(&mut b, 0x604, &[0x83, 9, 9, 9, 0, 0, 0, 0]),
            BlockStep::Part
        );
        feed(&mut b, 0x584, &[0xA2, 1, 127, 0, 0, 0, 0, 0]);
        feed(&mut b, 0x604, &[0x81, 8, 9, 10, 0, 0, 0, 0]);
        feed(&mut b, 0x584, &[0xA2, 1, 127, 0, 0, 0, 0, 0]);
        feed(&mut b, 0x604, &[0xD1, 0, 0, 0, 0, 0, 0, 0]);
        let done = feed(&mut b, 0x584, &[0xA1, 0, 0, 0, 0, 0, 0, 0]);
        assert!(matches!(done, BlockStep::Done { value: None, .. }));
        // The receiver took more than the trace showed: not whole.
        let mut t = Transfer {
            keep: true,
            whole: true,
            ..Transfer::default()
        };
        segment(&mut t, 1, false, &[0x01, 0xAA, 0, 0, 0, 0, 0, 0]);
        acknowledged(&mut t, 2);
        assert!(!t.whole);
        assert_eq!(t.acked, 7);
        // A sub-block that begins with any segment but 1 is out of step:
        // the frame is read as any other.
        feed(&mut b, 0x604, &[0xC0, 0x00, 0x10, 0x00, 0, 0, 0, 0]);
        feed(&mut b, 0x584, &[0xA0, 0x00, 0x10, 0x00, 127, 0, 0, 0]);
        assert_eq!(
            feed(&mut b, 0x604, &[0x23, 0x17, 0x10, 0, 0, 0, 0, 0]),
            BlockStep::Other
        );
        assert!(!b.going(4));
    }

    /// Node 3's block upload of 0x1000 carrying `value`, every phase: the
    /// client asks (CRC, blksize 127, pst 0), the server answers (CRC, size
    /// 4), one sub-block of one last segment, its acknowledgement, the
    /// server's end with the CRC and the client's end response.
    fn upload_frames(value: [u8; 4]) -> [(u32, [u8; 8]); 7] {
        let crc = crc16(&value).to_le_bytes();
        [
            (0x603, [0xA4, 0x00, 0x10, 0x00, 127, 0, 0, 0]),
            (0x583, [0xC6, 0x00, 0x10, 0x00, 4, 0, 0, 0]),
            (0x603, [0xA3, 0, 0, 0, 0, 0, 0, 0]),
            (
                0x583,
                [0x81, value[0], value[1], value[2], value[3], 0, 0, 0],
            ),
            (0x603, [0xA2, 1, 127, 0, 0, 0, 0, 0]),
            (0x583, [0xCD, crc[0], crc[1], 0, 0, 0, 0, 0]),
            (0x603, [0xA1, 0, 0, 0, 0, 0, 0, 0]),
        ]
    }

    #[test]
    fn upload_every_phase() {
        let mut b = Blocks::new();
        let frames = upload_frames([0x91, 0x01, 0x0F, 0x00]);
        let steps: Vec<BlockStep> = frames.iter().map(|(id, d)| feed(&mut b, *id, d)).collect();
        assert!(steps[..6].iter().all(|s| *s == BlockStep::Part));
        let BlockStep::Done {
            upload: true,
            value: Some(c),
            ..
        } = steps[6]
        else {
            panic!("{:?}", steps[6])
        };
        assert_eq!((c.node, c.value, c.len), (3, 0x000F_0191, 4));
    }

    #[test]
    fn upload_switched_to_the_plain_protocol() {
        let mut b = Blocks::new();
        feed(&mut b, 0x603, &[0xA0, 0x00, 0x10, 0x00, 127, 21, 0, 0]);
        // The server answers expedited (scs 2): read as any frame.
        assert_eq!(
            feed(&mut b, 0x583, &[0x43, 0x00, 0x10, 0x00, 0x91, 1, 0x0F, 0]),
            BlockStep::Other
        );
        assert!(!b.going(3));
    }

    #[test]
    fn aborts_end_a_transfer_in_every_phase() {
        let abort_client = [0x80, 0x00, 0x10, 0x00, 0x00, 0x00, 0x04, 0x05];
        let abort_server = [0x80, 0x00, 0x10, 0x00, 0x04, 0x00, 0x04, 0x05];
        let frames = download_frames([1, 2, 3, 4]);
        for phase in 1..frames.len() {
            for (id, abort) in [(0x604, abort_client), (0x584, abort_server)] {
                let mut b = Blocks::new();
                for (i, d) in &frames[..phase] {
                    feed(&mut b, *i, d);
                }
                assert_eq!(feed(&mut b, id, &abort), BlockStep::Other, "{phase}");
                assert!(!b.going(4), "{phase}");
                assert_eq!(b.going, 0);
            }
        }
    }

    #[test]
    fn interleaved_nodes_are_followed_apart() {
        let mut b = Blocks::new();
        let value = [0x92, 0x01, 0x02, 0x00];
        let download = download_frames(value);
        let upload = upload_frames(value);
        let mut done = Vec::new();
        for i in 0..7 {
            for f in [upload.get(i), download.get(i)].into_iter().flatten() {
                if let BlockStep::Done { node, value, .. } = feed(&mut b, f.0, &f.1) {
                    done.push((node, value.map(|c| c.value)));
                }
            }
            if i == 2 {
                assert_eq!(b.going, 2);
            }
        }
        assert_eq!(done, [(4, Some(0x0002_0192)), (3, Some(0x0002_0192))]);
    }

    #[test]
    fn frames_of_no_transfer_are_other() {
        let mut b = Blocks::new();
        for (id, d) in [
            (0x604, [0x85, 0, 0, 0, 0, 0, 0, 0]),
            (0x584, [0xA2, 1, 127, 0, 0, 0, 0, 0]),
            (0x604, [0xC1, 0, 0, 0, 0, 0, 0, 0]),
            (0x104, [0xC0, 0, 0x10, 0, 0, 0, 0, 0]),
        ] {
            assert_eq!(feed(&mut b, id, &d), BlockStep::Other);
        }
        assert_eq!(feed(&mut b, 0x604, &[]), BlockStep::Other);
    }

    #[test]
    fn crc_of_known_data() {
        // CRC-16/XMODEM check value.
        assert_eq!(crc16(b"123456789"), 0x31C3);
        assert_eq!(crc16(&[]), 0);
    }
}
