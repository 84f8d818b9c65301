//! Reading one SDO frame: the commands that carry or confirm a value, and
//! aborts. Cheap tests of what a frame names let the content filter skip
//! frames without reading them.

#[cfg(test)]
use super::access::is_followed;
use super::access::{
    CCS_DOWNLOAD_INITIATE, CS_ABORT, Object, SCS_DOWNLOAD_INITIATE, SCS_UPLOAD_INITIATE, Sdo,
    is_sdo_id, sender,
};
use crate::canopen::NodeId;

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

/// Whether an SDO frame begins a segmented transfer: the client's download
/// initiate or the node's answer to an upload initiate with e = 0 (ccs 1,
/// scs 2): its segments follow, naming no object. (The client's upload
/// request cannot say; the node's answer does.)
pub fn begins_segmented_transfer(id: u32, data: &[u8]) -> bool {
    let (Some((request, _)), Some(&cmd)) = (sender(id), data.first()) else {
        return false;
    };
    let cs = if request {
        CCS_DOWNLOAD_INITIATE
    } else {
        SCS_UPLOAD_INITIATE
    };
    cmd >> 5 == cs && cmd & 0b10 == 0
}

/// Whether an SDO frame's command byte says abort (any object).
pub fn is_abort(data: &[u8]) -> bool {
    data.first().is_some_and(|cmd| cmd >> 5 == CS_ABORT)
}

/// Reads an SDO frame on a standard id; `None` for anything that is not an
/// SDO id or not a frame this module tracks.
pub fn parse(id: u32, data: &[u8]) -> Option<Sdo> {
    let (request, node) = sender(id)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canopen::sdo::{COB_ID_EMCY, ERROR_HISTORY};

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
    fn segmented_transfers_begin() {
        assert!(begins_segmented_transfer(0x581, &[0x41, 0x08, 0x10, 0]));
        assert!(begins_segmented_transfer(0x581, &[0x40, 0x08, 0x10, 0]));
        assert!(
            !begins_segmented_transfer(0x581, &[0x43, 0x08, 0x10, 0]),
            "expedited"
        );
        assert!(
            !begins_segmented_transfer(0x601, &[0x41, 0x08, 0x10, 0]),
            "an upload request: the answer says"
        );
        assert!(begins_segmented_transfer(0x601, &[0x21, 0x00, 0x1A, 1]));
        assert!(
            !begins_segmented_transfer(0x601, &[0x23, 0x00, 0x1A, 1]),
            "an expedited download"
        );
        assert!(
            !begins_segmented_transfer(0x581, &[0x21, 0x00, 0x1A, 1]),
            "a download segment's answer"
        );
        assert!(!begins_segmented_transfer(0x581, &[]));
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
}
