//! Just enough SDO (CiA 301 §7.2.4) to learn object values a trace shows:
//! expedited uploads (a node answering a read) and confirmed expedited
//! downloads (a write the node acknowledged). Segmented and block transfers
//! carry nothing the decoder needs (device type, vendor id and COB-ID EMCY
//! all fit in four bytes) and are ignored.

use super::NodeId;

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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Object {
    pub index: u16,
    pub sub: u8,
}

/// Command specifiers (the top three bits of byte 0).
const CCS_DOWNLOAD_INITIATE: u8 = 1;
const SCS_UPLOAD_INITIATE: u8 = 2;
const SCS_DOWNLOAD_INITIATE: u8 = 3;
const CS_ABORT: u8 = 4;

/// Whether `index` is an object whose value the decoder follows: device type and vendor id
/// choose a node's profile, COB-ID EMCY moves its EMCY id, the error
/// history is read out, heartbeat times set the timeouts. Frames naming
/// any other object change nothing (the [`Tracker`] ignores them) except
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
            | IDENTITY
    )
}

/// Whether `id` is a node's SDO request or response id.
pub fn is_sdo_id(id: u32) -> bool {
    (RESPONSE_BASE + 1..=RESPONSE_BASE + 127).contains(&id)
        || (REQUEST_BASE + 1..=REQUEST_BASE + 127).contains(&id)
}

/// The object index an SDO frame's bytes 1-2 name (any command).
fn named_index(data: &[u8]) -> Option<u16> {
    match data {
        [_, lo, hi, ..] => Some(u16::from_le_bytes([*lo, *hi])),
        _ => None,
    }
}

/// Whether an SDO frame (request or response, any command) names `index`:
/// a cheap test for frames that may change a value the decoder follows.
pub fn names_object(id: u32, data: &[u8], index: u16) -> bool {
    is_sdo_id(id) && named_index(data) == Some(index)
}

/// Whether an SDO frame names one of the followed objects ([`is_followed`]): only those
/// can change what the decoder knows. The content filter asks it in one
/// pass with its other questions (`analyze::interest::content_matters`,
/// tested equal to this).
#[cfg(test)]
pub fn names_followed_object(id: u32, data: &[u8]) -> bool {
    is_sdo_id(id) && named_index(data).is_some_and(is_followed)
}

/// Whether an SDO frame's command byte says abort (any object).
pub fn is_abort(data: &[u8]) -> bool {
    data.first().is_some_and(|cmd| cmd >> 5 == CS_ABORT)
}

/// Reads an SDO frame on a standard id; `None` for anything that is not an
/// SDO id or not a frame this module tracks.
pub fn parse(id: u32, data: &[u8]) -> Option<Sdo> {
    let (request, node) = if (RESPONSE_BASE + 1..=RESPONSE_BASE + 127).contains(&id) {
        (false, id - RESPONSE_BASE)
    } else if (REQUEST_BASE + 1..=REQUEST_BASE + 127).contains(&id) {
        (true, id - REQUEST_BASE)
    } else {
        return None;
    };
    parse_payload(node as NodeId, request, data)
}

/// Reads the eight bytes of an SDO frame for `node`, sent by the client
/// (`request`) or the node, however they were carried (a CAN frame, a CoE
/// mailbox message of CANopen over EtherCAT).
pub fn parse_payload(node: NodeId, request: bool, data: &[u8]) -> Option<Sdo> {
    // Every SDO frame is 8 bytes; a shorter one is not trusted.
    let &[cmd, lo, hi, sub, b4, b5, b6, b7] = data else {
        return None;
    };
    let object = Object {
        index: u16::from_le_bytes([lo, hi]),
        sub,
    };
    let cs = cmd >> 5;
    if cs == CS_ABORT {
        return Some(Sdo::Aborted {
            node,
            object,
            code: u32::from_le_bytes([b4, b5, b6, b7]),
            by_server: !request,
        });
    }
    let expedited_value = || {
        // e = 1 (bit 1); with s = 1 (bit 0), n (bits 2-3) bytes are unused.
        if cmd & 0b10 == 0 {
            return None;
        }
        let used = if cmd & 0b01 != 0 {
            4 - usize::from((cmd >> 2) & 0b11)
        } else {
            4
        };
        let mut bytes = [b4, b5, b6, b7];
        for b in bytes.iter_mut().skip(used) {
            *b = 0;
        }
        Some(u32::from_le_bytes(bytes))
    };
    match (request, cs) {
        (false, SCS_UPLOAD_INITIATE) => Some(Sdo::Uploaded {
            node,
            object,
            value: expedited_value()?,
        }),
        (true, CCS_DOWNLOAD_INITIATE) => Some(Sdo::Writing {
            node,
            object,
            value: expedited_value()?,
        }),
        (false, SCS_DOWNLOAD_INITIATE) => Some(Sdo::Written { node, object }),
        _ => None,
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

/// Follows writes to their confirmation, per node: a value counts only once
/// the node accepted it (or reported it in an upload). Only the
/// followed objects ([`is_followed`]) are tracked: a write to any other object neither
/// counts nor drops a pending one (its confirmation names its object), so
/// frames for other objects can be skipped without reading them.
#[derive(Debug, Default)]
pub struct Tracker {
    pending: Vec<(NodeId, Object, u32)>,
}

impl Tracker {
    /// Feeds one SDO frame; returns an object value the node now holds.
    pub fn feed(&mut self, sdo: Sdo) -> Option<(NodeId, Object, u32)> {
        let (Sdo::Uploaded { object, .. }
        | Sdo::Writing { object, .. }
        | Sdo::Written { object, .. }
        | Sdo::Aborted { object, .. }) = sdo;
        if !is_followed(object.index) {
            return None;
        }
        match sdo {
            Sdo::Uploaded {
                node,
                object,
                value,
            } => Some((node, object, value)),
            Sdo::Writing {
                node,
                object,
                value,
            } => {
                self.pending.retain(|&(n, _, _)| n != node);
                self.pending.push((node, object, value));
                None
            }
            Sdo::Written { node, object } => {
                let at = self
                    .pending
                    .iter()
                    .position(|&(n, o, _)| n == node && o == object)?;
                let (n, o, v) = self.pending.swap_remove(at);
                Some((n, o, v))
            }
            Sdo::Aborted { node, .. } => {
                self.pending.retain(|&(n, _, _)| n != node);
                None
            }
        }
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

    const EMCY_OBJ: Object = Object {
        index: 0x1014,
        sub: 0,
    };

    #[test]
    fn expedited_upload_of_four_bytes() {
        let sdo = parse(0x585, &[0x43, 0x14, 0x10, 0x00, 0x85, 0x00, 0x00, 0x00]);
        assert_eq!(
            sdo,
            Some(Sdo::Uploaded {
                node: 5,
                object: EMCY_OBJ,
                value: 0x85
            })
        );
    }

    #[test]
    fn expedited_size_indicator_masks_unused_bytes() {
        // 0x4B: 2 bytes used, bytes 6-7 are junk.
        let sdo = parse(0x581, &[0x4B, 0x00, 0x10, 0x00, 0x92, 0x01, 0xAA, 0xBB]);
        assert_eq!(
            sdo,
            Some(Sdo::Uploaded {
                node: 1,
                object: Object {
                    index: 0x1000,
                    sub: 0
                },
                value: 0x0192
            })
        );
        // 0x4F: 1 byte used.
        let Some(Sdo::Uploaded { value, .. }) =
            parse(0x581, &[0x4F, 0x00, 0x10, 0x00, 0x92, 0x01, 0xAA, 0xBB])
        else {
            panic!("not an upload")
        };
        assert_eq!(value, 0x92);
        // 0x42: expedited, size not indicated: all four bytes.
        let Some(Sdo::Uploaded { value, .. }) =
            parse(0x581, &[0x42, 0x00, 0x10, 0x00, 0x01, 0x02, 0x03, 0x04])
        else {
            panic!("not an upload")
        };
        assert_eq!(value, 0x0403_0201);
    }

    #[test]
    fn segmented_upload_is_not_tracked() {
        // 0x41: segmented initiate (e = 0): the value is not in this frame.
        assert_eq!(parse(0x581, &[0x41, 0x08, 0x10, 0x00, 0x10, 0, 0, 0]), None);
    }

    #[test]
    fn short_frames_and_other_ids_are_ignored() {
        assert_eq!(parse(0x585, &[0x43, 0x14, 0x10, 0x00]), None);
        assert_eq!(parse(0x580, &[0x43, 0x14, 0x10, 0, 0x85, 0, 0, 0]), None);
        assert_eq!(parse(0x600, &[0x23, 0x14, 0x10, 0, 0x85, 0, 0, 0]), None);
        assert_eq!(parse(0x085, &[0x43, 0x14, 0x10, 0, 0x85, 0, 0, 0]), None);
        assert_eq!(parse(0x680, &[0x43, 0x14, 0x10, 0, 0x85, 0, 0, 0]), None);
    }

    #[test]
    fn download_counts_only_once_confirmed() {
        let mut t = Tracker::default();
        let write = parse(0x605, &[0x23, 0x14, 0x10, 0x00, 0xA5, 0, 0, 0]).unwrap();
        assert_eq!(t.feed(write), None);
        let ok = parse(0x585, &[0x60, 0x14, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        assert_eq!(t.feed(ok), Some((5, EMCY_OBJ, 0xA5)));
        // A second confirmation has nothing pending.
        assert_eq!(t.feed(ok), None);
    }

    #[test]
    fn aborted_download_is_dropped() {
        let mut t = Tracker::default();
        t.feed(parse(0x605, &[0x23, 0x14, 0x10, 0x00, 0xA5, 0, 0, 0]).unwrap());
        let abort = parse(0x585, &[0x80, 0x14, 0x10, 0x00, 0x00, 0x00, 0x09, 0x06]).unwrap();
        assert_eq!(t.feed(abort), None);
        let ok = parse(0x585, &[0x60, 0x14, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        assert_eq!(t.feed(ok), None);
    }

    #[test]
    fn confirmation_must_name_the_written_object() {
        let mut t = Tracker::default();
        t.feed(parse(0x605, &[0x23, 0x14, 0x10, 0x00, 0xA5, 0, 0, 0]).unwrap());
        let other = parse(0x585, &[0x60, 0x08, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        assert_eq!(t.feed(other), None);
        let other_node = parse(0x586, &[0x60, 0x14, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        assert_eq!(t.feed(other_node), None);
    }

    #[test]
    fn objects_not_followed_are_ignored() {
        let mut t = Tracker::default();
        let upload = parse(0x585, &[0x43, 0x00, 0x20, 0x00, 1, 0, 0, 0]).unwrap();
        assert_eq!(t.feed(upload), None, "upload of 0x2000");
        t.feed(parse(0x605, &[0x23, 0x14, 0x10, 0x00, 0xA5, 0, 0, 0]).unwrap());
        // A write and an abort for another object leave the 0x1014 write pending.
        t.feed(parse(0x605, &[0x23, 0x40, 0x60, 0x00, 0x0F, 0, 0, 0]).unwrap());
        t.feed(parse(0x585, &[0x80, 0x40, 0x60, 0x00, 0, 0, 0x09, 0x06]).unwrap());
        let ok = parse(0x585, &[0x60, 0x14, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        assert_eq!(t.feed(ok), Some((5, EMCY_OBJ, 0xA5)));
        // Uploads of the followed objects count.
        let vendor = parse(0x585, &[0x43, 0x18, 0x10, 0x01, 0x6A, 0, 0, 0]).unwrap();
        assert_eq!(
            t.feed(vendor),
            Some((
                5,
                Object {
                    index: IDENTITY,
                    sub: 1
                },
                0x6A
            ))
        );
    }

    #[test]
    fn followed_objects_are_recognised_by_their_index() {
        assert!(names_followed_object(0x605, &[0x23, 0x14, 0x10, 0]));
        assert!(names_followed_object(
            0x581,
            &[0x43, 0x00, 0x10, 0, 0, 0, 0, 0]
        ));
        assert!(names_followed_object(0x581, &[0x41, 0x18, 0x10, 2]));
        assert!(!names_followed_object(0x581, &[0x43, 0x08, 0x10, 0]));
        assert!(!names_followed_object(0x581, &[0x43, 0x00]));
        assert!(!names_followed_object(0x081, &[0x43, 0x00, 0x10, 0]));
        assert!(!names_followed_object(0x680, &[0x43, 0x00, 0x10, 0]));
    }

    #[test]
    fn names_object_looks_at_the_index_of_sdo_ids_only() {
        assert!(names_object(0x605, &[0x23, 0x14, 0x10, 0], COB_ID_EMCY));
        assert!(names_object(0x585, &[0x80, 0x14, 0x10], COB_ID_EMCY));
        assert!(!names_object(0x585, &[0x43, 0x18, 0x10, 1], COB_ID_EMCY));
        assert!(!names_object(0x085, &[0x23, 0x14, 0x10, 0], COB_ID_EMCY));
        assert!(!names_object(0x605, &[0x23, 0x14], COB_ID_EMCY));
    }

    #[test]
    fn aborts_carry_the_code_and_side() {
        assert_eq!(
            parse(0x585, &[0x80, 0x03, 0x10, 0x09, 0x11, 0x00, 0x09, 0x06]),
            Some(Sdo::Aborted {
                node: 5,
                object: Object {
                    index: ERROR_HISTORY,
                    sub: 9
                },
                code: 0x0609_0011,
                by_server: true,
            })
        );
        assert_eq!(
            parse(0x605, &[0x80, 0x00, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05]),
            Some(Sdo::Aborted {
                node: 5,
                object: Object {
                    index: 0x2000,
                    sub: 0
                },
                code: 0x0504_0000,
                by_server: false,
            })
        );
        assert!(is_abort(&[0x80, 0, 0]));
        assert!(!is_abort(&[0x43, 0, 0]));
        assert!(!is_abort(&[]));
    }

    #[test]
    fn history_and_heartbeat_objects_are_followed() {
        let mut t = Tracker::default();
        let count = parse(0x585, &[0x4F, 0x03, 0x10, 0x00, 2, 0, 0, 0]).unwrap();
        assert_eq!(
            t.feed(count),
            Some((
                5,
                Object {
                    index: ERROR_HISTORY,
                    sub: 0
                },
                2
            ))
        );
        t.feed(parse(0x605, &[0x2F, 0x03, 0x10, 0x00, 0, 0, 0, 0]).unwrap());
        let ok = parse(0x585, &[0x60, 0x03, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        assert_eq!(
            t.feed(ok),
            Some((
                5,
                Object {
                    index: ERROR_HISTORY,
                    sub: 0
                },
                0
            ))
        );
        let producer = parse(0x585, &[0x4B, 0x17, 0x10, 0x00, 0x64, 0, 0, 0]).unwrap();
        assert_eq!(
            t.feed(producer),
            Some((
                5,
                Object {
                    index: PRODUCER_HEARTBEAT,
                    sub: 0
                },
                100
            ))
        );
        assert!(names_followed_object(0x581, &[0x43, 0x16, 0x10, 1]));
    }

    #[test]
    fn cob_id_emcy_values() {
        assert_eq!(cob_id_emcy(0x0000_0085), Some((0x85, false)));
        assert_eq!(cob_id_emcy(0x8000_0085), None, "bit 31: no EMCY");
        assert_eq!(cob_id_emcy(0x2000_1234), Some((0x1234, true)));
        assert_eq!(cob_id_emcy(0x0000_F8A5), Some((0x0A5, false)), "11-bit id");
    }
}
