//! What an SDO frame can say, shared by every part of the folder: the
//! request and response ids, the command specifiers, the objects the
//! decoder follows and the access (`Sdo`) a frame is read into.

use crate::canopen::NodeId;

/// Server-to-client (response) ids are 0x580 + node.
pub const RESPONSE_BASE: u32 = 0x580;
/// Client-to-server (request) ids are 0x600 + node.
pub const REQUEST_BASE: u32 = 0x600;

/// Object 0x1000: device type (profile number in the low 16 bits).
pub const DEVICE_TYPE: u16 = 0x1000;
/// Object 0x1014: COB-ID EMCY.
pub const COB_ID_EMCY: u16 = 0x1014;
/// Object 0x1018: identity (sub 1 = vendor id, sub 2 = product code).
pub const IDENTITY: u16 = 0x1018;
/// Object 0x1003: pre-defined error field (sub 0 = count, sub 1 = newest).
pub const ERROR_HISTORY: u16 = 0x1003;
/// Object 0x1016: consumer heartbeat times (sub n = producer node in bits
/// 16-23, time in ms in bits 0-15).
pub const CONSUMER_HEARTBEAT: u16 = 0x1016;
/// Object 0x1017: producer heartbeat time (ms).
pub const PRODUCER_HEARTBEAT: u16 = 0x1017;
/// Object 0x100C: node guarding's guard time (ms).
pub const GUARD_TIME: u16 = 0x100C;
/// Object 0x100D: node guarding's life time factor (the node's life time
/// is the guard time times this).
pub const LIFE_TIME_FACTOR: u16 = 0x100D;

/// One SDO frame that matters to value tracking.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sdo {
    /// Expedited upload response: the node reports `value`.
    Uploaded {
        node: NodeId,
        object: Object,
        value: u32,
    },
    /// Expedited download request: a client writes `value` (not yet confirmed).
    Writing {
        node: NodeId,
        object: Object,
        value: u32,
    },
    /// Download response: the node accepted the last write to `object`.
    Written { node: NodeId, object: Object },
    /// Abort (either direction): the transfer of `object` failed with
    /// `code` (a pending write to it with it). `by_server`: the node
    /// aborted (on 0x580 + node), else the client did.
    Aborted {
        node: NodeId,
        object: Object,
        code: u32,
        by_server: bool,
    },
}

/// An object dictionary entry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Object {
    pub index: u16,
    pub sub: u8,
}

/// Command specifiers (the top three bits of byte 0). Segment frames reuse
/// the numbers of other commands, so which one a number means depends on
/// the direction and on the transfer in progress.
pub(super) const CCS_DOWNLOAD_SEGMENT: u8 = 0;
pub(super) const CCS_DOWNLOAD_INITIATE: u8 = 1;
pub(super) const SCS_DOWNLOAD_SEGMENT: u8 = 1;
pub(super) const SCS_UPLOAD_INITIATE: u8 = 2;
pub(super) const SCS_DOWNLOAD_INITIATE: u8 = 3;
pub(super) const CS_ABORT: u8 = 4;
pub(super) const SCS_UPLOAD_SEGMENT: u8 = 0;
/// Block transfers: the client's block upload commands share 5 with the
/// server's block download responses, and 6 the other way round.
pub(super) const CCS_BLOCK_UPLOAD: u8 = 5;
pub(super) const CCS_BLOCK_DOWNLOAD: u8 = 6;
pub(super) const SCS_BLOCK_DOWNLOAD: u8 = 5;
pub(super) const SCS_BLOCK_UPLOAD: u8 = 6;

/// Whether `index` is an object whose value the decoder follows: device type and vendor id
/// choose a node's profile, COB-ID EMCY moves its EMCY id, the error
/// history is read out, heartbeat and guarding times set the timeouts. Frames naming
/// any other object change nothing (the `Tracker` ignores them) except
/// aborts, which are reported whatever they name.
///
/// A `match`, not a search of a list: asked of every SDO frame, the search
/// cost some 100 instructions a frame.
#[inline]
pub fn is_followed(index: u16) -> bool {
    matches!(
        index,
        DEVICE_TYPE
            | ERROR_HISTORY
            | COB_ID_EMCY
            | CONSUMER_HEARTBEAT
            | PRODUCER_HEARTBEAT
            | GUARD_TIME
            | LIFE_TIME_FACTOR
            | IDENTITY
    )
}

/// Whether `id` is a node's SDO request or response id.
pub fn is_sdo_id(id: u32) -> bool {
    (RESPONSE_BASE + 1..=RESPONSE_BASE + 127).contains(&id)
        || (REQUEST_BASE + 1..=REQUEST_BASE + 127).contains(&id)
}

/// Which side sent a frame on an SDO id, and for which node: `(request,
/// node)`; `None` for an id that is not a node's SDO id.
#[inline]
pub(super) fn sender(id: u32) -> Option<(bool, u32)> {
    if (RESPONSE_BASE + 1..=RESPONSE_BASE + 127).contains(&id) {
        Some((false, id - RESPONSE_BASE))
    } else if (REQUEST_BASE + 1..=REQUEST_BASE + 127).contains(&id) {
        Some((true, id - REQUEST_BASE))
    } else {
        None
    }
}

/// One record per node id (1-127; the slot for 0 is never used): what an
/// SDO follower keeps of each node's transfer, one small fixed record per
/// node whatever the trace. A record's default is "no transfer".
#[derive(Clone, Debug)]
pub(super) struct PerNode<T>(Box<[T; 128]>);

impl<T: Copy + Default> Default for PerNode<T> {
    fn default() -> Self {
        PerNode(Box::new([T::default(); 128]))
    }
}

impl<T> PerNode<T> {
    /// The record of `node`.
    pub(super) fn get(&self, node: u32) -> Option<&T> {
        self.0.get(node as usize)
    }

    /// The record of the node that sends or receives on SDO id `id`, with
    /// whether the frame is the client's request, and the node.
    pub(super) fn by_id(&mut self, id: u32) -> Option<(bool, u32, &mut T)> {
        let (request, node) = sender(id)?;
        Some((request, node, self.0.get_mut(node as usize)?))
    }

    /// Whether the node of SDO id `id` has a transfer going on (`going`
    /// says of a record).
    pub(super) fn going_on(&self, id: u32, going: impl Fn(&T) -> bool) -> bool {
        sender(id).is_some_and(|(_, node)| self.get(node).is_some_and(going))
    }
}

/// The EMCY id a COB-ID EMCY value (object 0x1014) selects: `(id, extended)`,
/// or `None` when bit 31 says the node sends no EMCY.
pub fn cob_id_emcy(value: u32) -> Option<(u32, bool)> {
    if value & 0x8000_0000 != 0 {
        return None;
    }
    if value & 0x2000_0000 != 0 {
        Some((value & 0x1FFF_FFFF, true))
    } else {
        Some((value & 0x7FF, false))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_followed_objects_are_exactly_these() {
        let followed = [
            DEVICE_TYPE,
            ERROR_HISTORY,
            COB_ID_EMCY,
            CONSUMER_HEARTBEAT,
            PRODUCER_HEARTBEAT,
            GUARD_TIME,
            LIFE_TIME_FACTOR,
            IDENTITY,
        ];
        for index in 0..=u16::MAX {
            assert_eq!(
                is_followed(index),
                followed.contains(&index),
                "{index:#06X}"
            );
        }
    }

    #[test]
    fn cob_id_emcy_values() {
        assert_eq!(cob_id_emcy(0x0000_0085), Some((0x85, false)));
        assert_eq!(cob_id_emcy(0x8000_0085), None, "bit 31: no EMCY");
        assert_eq!(cob_id_emcy(0x2000_1234), Some((0x1234, true)));
        assert_eq!(cob_id_emcy(0x0000_F8A5), Some((0x0A5, false)), "11-bit id");
    }
}
