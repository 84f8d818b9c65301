//! Following the values of the objects the decoder follows (device type,
//! identity, COB-ID EMCY, error history, heartbeat times) to their
//! confirmation.

use super::access::{Object, Sdo, is_followed};
use crate::canopen::NodeId;

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
    use crate::canopen::sdo::{
        ERROR_HISTORY, IDENTITY, PRODUCER_HEARTBEAT, names_followed_object, parse,
    };

    const EMCY_OBJ: Object = Object {
        index: 0x1014,
        sub: 0,
    };

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
}
