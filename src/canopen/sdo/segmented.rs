//! Assembling SDO downloads, expedited and segmented, to the writes a node
//! confirmed, and segmented uploads to the values a node reported. PDO
//! mappings are configured by such writes (a mapping entry may come in
//! segments) and read back by such uploads, so PDO learning reads what
//! this assembles.

use super::access::{
    CCS_DOWNLOAD_INITIATE, CCS_DOWNLOAD_SEGMENT, CS_ABORT, Object, PerNode, SCS_DOWNLOAD_SEGMENT,
    SCS_UPLOAD_INITIATE, SCS_UPLOAD_SEGMENT, Sdo,
};
use super::frame::parse;
use crate::canopen::NodeId;

/// A download the node confirmed: `value` holds its first `len` bytes
/// (little endian); longer values are not kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Confirmed {
    pub node: NodeId,
    pub object: Object,
    pub value: u32,
    /// Bytes written: as the expedited frame said (4 when it did not), or
    /// as many as the segments carried.
    pub len: u32,
}

/// Bytes of a segmented download kept: every object the decoder learns
/// from is at most 4 bytes; a longer download is followed to its end (so
/// the next transfer is read right) but its value not kept.
const KEPT_BYTES: usize = 4;

/// One node's SDO download in progress.
#[derive(Clone, Copy, Debug, Default)]
enum Transfer {
    #[default]
    Idle,
    /// An expedited initiate awaiting its confirmation.
    Expedited {
        object: Object,
        value: u32,
        len: u32,
    },
    /// A segmented initiate awaiting its confirmation.
    Initiating { object: Object, size: Option<u32> },
    /// Segments going: `toggle` is the bit the next segment must carry;
    /// `pending` a segment sent and not yet confirmed.
    Segments {
        object: Object,
        size: Option<u32>,
        kept: [u8; KEPT_BYTES],
        len: u32,
        toggle: bool,
        pending: Option<Segment>,
    },
}

/// A download segment awaiting confirmation.
#[derive(Clone, Copy, Debug)]
struct Segment {
    data: [u8; 7],
    used: u8,
    toggle: bool,
    last: bool,
}

/// Follows SDO downloads (expedited and segmented) to their confirmation,
/// per node: the writes a node accepted, of any object. Memory is one small
/// fixed record per node (ids 1-127), whatever the trace.
#[derive(Clone, Debug, Default)]
pub struct Downloads {
    transfers: PerNode<Transfer>,
}

impl Downloads {
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether the node of SDO id `id` has a download in progress: its
    /// segment frames name no object, so only this says they matter.
    pub fn in_progress(&self, id: u32) -> bool {
        self.transfers
            .going_on(id, |t| !matches!(t, Transfer::Idle))
    }

    /// Whether the node of SDO id `id` has a segmented download going on
    /// (initiated or in segments; not an expedited one awaiting its
    /// confirmation, which names its object).
    pub fn in_segments(&self, id: u32) -> bool {
        self.transfers.going_on(id, |t| {
            matches!(t, Transfer::Initiating { .. } | Transfer::Segments { .. })
        })
    }

    /// Feeds one frame on an SDO id (others change nothing); the download
    /// it completes, if it completes one.
    pub fn feed(&mut self, id: u32, data: &[u8]) -> Option<Confirmed> {
        let (request, node, slot) = self.transfers.by_id(id)?;
        let node = node as NodeId;
        let &[cmd, ..] = data else {
            return None;
        };
        let cs = cmd >> 5;
        // Segment frames carry no object; `parse` reads the others.
        match (request, cs, *slot) {
            (true, CCS_DOWNLOAD_SEGMENT, Transfer::Segments { .. }) => {
                let [_, rest @ ..] = data else { return None };
                let used = 7 - ((cmd >> 1) & 0b111);
                let mut seg = Segment {
                    data: [0; 7],
                    used,
                    toggle: cmd & 0x10 != 0,
                    last: cmd & 0x01 != 0,
                };
                let mut n = 0;
                for (to, &from) in seg.data.iter_mut().zip(rest).take(usize::from(used)) {
                    *to = from;
                    n += 1;
                }
                seg.used = n;
                if let Transfer::Segments { pending, .. } = slot {
                    // A repeat replaces the segment it repeats.
                    *pending = Some(seg);
                }
                return None;
            }
            (false, SCS_DOWNLOAD_SEGMENT, Transfer::Segments { .. }) => {
                return Self::segment_confirmed(slot, node, cmd & 0x10 != 0);
            }
            (true, CCS_DOWNLOAD_INITIATE, _) if cmd & 0b10 == 0 => {
                // Segmented initiate (e = 0): size in bytes 4-7 when s = 1.
                let &[_, lo, hi, sub, b4, b5, b6, b7] = data else {
                    *slot = Transfer::Idle;
                    return None;
                };
                *slot = Transfer::Initiating {
                    object: Object {
                        index: u16::from_le_bytes([lo, hi]),
                        sub,
                    },
                    size: (cmd & 0x01 != 0).then(|| u32::from_le_bytes([b4, b5, b6, b7])),
                };
                return None;
            }
            _ => {}
        }
        match parse(id, data) {
            Some(Sdo::Writing { object, value, .. }) => {
                // s = 1: n (bits 2-3) bytes of the four unused.
                let len = if cmd & 0x01 != 0 {
                    4 - u32::from((cmd >> 2) & 0b11)
                } else {
                    4
                };
                *slot = Transfer::Expedited { object, value, len };
                None
            }
            Some(Sdo::Written { object, .. }) => match *slot {
                Transfer::Expedited {
                    object: o,
                    value,
                    len,
                } if o == object => {
                    *slot = Transfer::Idle;
                    Some(Confirmed {
                        node,
                        object,
                        value,
                        len,
                    })
                }
                Transfer::Initiating { object: o, size } if o == object => {
                    *slot = Transfer::Segments {
                        object,
                        size,
                        kept: [0; KEPT_BYTES],
                        len: 0,
                        toggle: false,
                        pending: None,
                    };
                    None
                }
                _ => None,
            },
            Some(Sdo::Aborted { .. }) => {
                *slot = Transfer::Idle;
                None
            }
            // An upload, or a frame of no transfer: a new command from the
            // client ends whatever was in progress.
            _ => {
                if request {
                    *slot = Transfer::Idle;
                }
                None
            }
        }
    }

    /// The server confirmed a segment carrying `toggle`.
    fn segment_confirmed(slot: &mut Transfer, node: NodeId, toggle: bool) -> Option<Confirmed> {
        let Transfer::Segments {
            object,
            size,
            mut kept,
            mut len,
            toggle: expected,
            pending,
        } = *slot
        else {
            return None;
        };
        let Some(seg) = pending.filter(|s| s.toggle == expected && toggle == expected) else {
            // A confirmation out of step: the transfer cannot be trusted.
            *slot = Transfer::Idle;
            return None;
        };
        for &b in seg.data.iter().take(usize::from(seg.used)) {
            if let Some(k) = kept.get_mut(len as usize) {
                *k = b;
            }
            len = len.saturating_add(1);
        }
        if !seg.last {
            *slot = Transfer::Segments {
                object,
                size,
                kept,
                len,
                toggle: !expected,
                pending: None,
            };
            return None;
        }
        *slot = Transfer::Idle;
        if size.is_some_and(|s| s != len) || len as usize > KEPT_BYTES {
            return None;
        }
        Some(Confirmed {
            node,
            object,
            value: u32::from_le_bytes(kept),
            len,
        })
    }
}

/// One node's segmented upload in progress: the server answered the
/// initiate without the value (e = 0), its segments are coming.
#[derive(Clone, Copy, Debug, Default)]
enum Upload {
    #[default]
    Idle,
    /// `toggle` is the bit the next segment must carry.
    Segments {
        object: Object,
        size: Option<u32>,
        kept: [u8; TEXT_BYTES],
        len: u32,
        toggle: bool,
    },
}

/// Bytes of a segmented upload kept: a value of at most 4 bytes, or the
/// text of an object the node names itself by ([`is_text`]); a longer
/// upload is followed to its end but not kept.
pub const TEXT_BYTES: usize = 64;

/// The objects a node names itself by, as VISIBLE_STRING (CiA 301): its
/// device name (0x1008), hardware version (0x1009), software version
/// (0x100A).
pub fn is_text(index: u16) -> bool {
    matches!(index, 0x1008..=0x100A)
}

/// The text of an upload of a text object ([`is_text`]) longer than four
/// bytes: whose, which object, and its bytes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Text {
    pub node: NodeId,
    pub object: Object,
    pub bytes: Vec<u8>,
}

/// Follows segmented uploads, per node, to the value the node reported
/// (expedited uploads carry theirs in one frame: [`parse`] reads them).
/// Memory is one small fixed record per node (ids 1-127).
#[derive(Clone, Debug, Default)]
pub struct Uploads {
    transfers: PerNode<Upload>,
    /// The text the last frame completed, until taken.
    text: Option<Text>,
}

impl Uploads {
    pub fn new() -> Self {
        Self::default()
    }

    /// The text of a text object the last frame fed completed, if it did.
    pub fn take_text(&mut self) -> Option<Text> {
        self.text.take()
    }

    /// Whether the node of SDO id `id` has a segmented upload going on:
    /// its segments name no object, so only this says they matter.
    pub fn in_progress(&self, id: u32) -> bool {
        self.transfers.going_on(id, |t| !matches!(t, Upload::Idle))
    }

    /// Feeds one frame on an SDO id (others change nothing); the upload it
    /// completes, if it completes one with a value of at most four bytes.
    /// Only the server's frames matter: its initiate response names the
    /// object, and its segments carry the toggle the client asked for.
    pub fn feed(&mut self, id: u32, data: &[u8]) -> Option<Confirmed> {
        let (request, node, slot) = self.transfers.by_id(id)?;
        let &[cmd, ..] = data else {
            return None;
        };
        let cs = cmd >> 5;
        if cs == CS_ABORT {
            *slot = Upload::Idle;
            return None;
        }
        if request {
            return None;
        }
        match (cs, *slot) {
            (SCS_UPLOAD_INITIATE, _) => {
                *slot = match *data {
                    // e = 0: the segments follow; s = 1: size in bytes 4-7.
                    [_, lo, hi, sub, b4, b5, b6, b7] if cmd & 0b10 == 0 => Upload::Segments {
                        object: Object {
                            index: u16::from_le_bytes([lo, hi]),
                            sub,
                        },
                        size: (cmd & 0x01 != 0).then(|| u32::from_le_bytes([b4, b5, b6, b7])),
                        kept: [0; TEXT_BYTES],
                        len: 0,
                        toggle: false,
                    },
                    _ => Upload::Idle,
                };
                None
            }
            (
                SCS_UPLOAD_SEGMENT,
                Upload::Segments {
                    object,
                    size,
                    mut kept,
                    mut len,
                    toggle,
                },
            ) => {
                if (cmd & 0x10 != 0) != toggle {
                    // Out of step: the value cannot be trusted.
                    *slot = Upload::Idle;
                    return None;
                }
                // n (bits 1-3) bytes of the seven unused.
                let used = usize::from(7 - ((cmd >> 1) & 0b111));
                for &b in data.iter().skip(1).take(used) {
                    if let Some(k) = kept.get_mut(len as usize) {
                        *k = b;
                    }
                    len = len.saturating_add(1);
                }
                if cmd & 0x01 == 0 {
                    *slot = Upload::Segments {
                        object,
                        size,
                        kept,
                        len,
                        toggle: !toggle,
                    };
                    return None;
                }
                *slot = Upload::Idle;
                if size.is_some_and(|s| s != len) {
                    return None;
                }
                if len as usize > KEPT_BYTES {
                    if is_text(object.index) && len as usize <= TEXT_BYTES {
                        self.text = Some(Text {
                            node: node as NodeId,
                            object,
                            bytes: kept.get(..len as usize).unwrap_or_default().to_vec(),
                        });
                    }
                    return None;
                }
                let [a, b, c, d, ..] = kept;
                Some(Confirmed {
                    node: node as NodeId,
                    object,
                    value: u32::from_le_bytes([a, b, c, d]),
                    len,
                })
            }
            // Any other answer of the server ends the upload.
            _ => {
                *slot = Upload::Idle;
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segmented_upload_of_a_small_value() {
        let mut u = Uploads::new();
        // The client asks (nothing to the follower), the server answers
        // with size 4 (0x41), then one last segment, toggle 0, n = 3: 0x07.
        assert_eq!(u.feed(0x603, &[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]), None);
        assert_eq!(u.feed(0x583, &[0x41, 0x00, 0x10, 0x00, 4, 0, 0, 0]), None);
        assert_eq!(u.feed(0x603, &[0x60, 0, 0, 0, 0, 0, 0, 0]), None);
        let c = u
            .feed(0x583, &[0x07, 0x91, 0x01, 0x0F, 0x00, 0xEE, 0xEE, 0xEE])
            .expect("done");
        assert_eq!(
            c.object,
            Object {
                index: 0x1000,
                sub: 0
            }
        );
        assert_eq!((c.node, c.value, c.len), (3, 0x000F_0191, 4));
        assert_eq!(u.feed(0x583, &[0x07, 1, 2, 3, 4, 0, 0, 0]), None, "idle");
    }

    #[test]
    fn a_text_object_longer_than_four_bytes_is_kept_as_text() {
        let mut u = Uploads::new();
        // 0x1008 in two segments, 7 bytes and 1 (no size given).
        u.feed(0x585, &[0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0]);
        assert_eq!(
            u.feed(0x585, &[0x00, b'A', b'K', b'D', b' ', b'S', b'e', b'r']),
            None
        );
        assert_eq!(u.take_text(), None, "not done yet");
        assert_eq!(u.feed(0x585, &[0x1D, b'v', 0, 0, 0, 0, 0, 0]), None);
        let text = u.take_text().expect("a text");
        assert_eq!(
            (text.node, text.object.index, text.object.sub),
            (5, 0x1008, 0)
        );
        assert_eq!(text.bytes, b"AKD Serv");
        assert_eq!(u.take_text(), None, "taken once");
        // A size that the segments do not keep to: nothing.
        u.feed(0x585, &[0x41, 0x0A, 0x10, 0x00, 9, 0, 0, 0]);
        u.feed(0x585, &[0x00, 1, 2, 3, 4, 5, 6, 7]);
        u.feed(0x585, &[0x1D, 8, 0, 0, 0, 0, 0, 0]);
        assert_eq!(u.take_text(), None, "8 bytes of 9");
        // Another object's long value, and a text past 64 bytes: nothing.
        u.feed(0x585, &[0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0]);
        u.feed(0x585, &[0x00, 1, 2, 3, 4, 5, 6, 7]);
        u.feed(0x585, &[0x1D, 8, 0, 0, 0, 0, 0, 0]);
        assert_eq!(u.take_text(), None, "0x2000 is no text");
        u.feed(0x585, &[0x40, 0x09, 0x10, 0x00, 0, 0, 0, 0]);
        for i in 0..10u8 {
            u.feed(0x585, &[(i % 2) << 4, 1, 2, 3, 4, 5, 6, 7]);
        }
        u.feed(0x585, &[0x01, 1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(u.take_text(), None, "77 bytes");
        assert!(is_text(0x1008) && is_text(0x100A) && !is_text(0x1007) && !is_text(0x100B));
    }

    #[test]
    fn segmented_upload_in_two_segments_and_out_of_step() {
        let mut u = Uploads::new();
        // No size: 7 bytes then 1 (toggle 1, n = 6, last: 0x1D): too long.
        u.feed(0x583, &[0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0]);
        assert_eq!(u.feed(0x583, &[0x00, 1, 2, 3, 4, 5, 6, 7]), None);
        assert_eq!(u.feed(0x583, &[0x1D, 8, 0, 0, 0, 0, 0, 0]), None);
        // Two bytes in two segments: 0x0D (n = 6, one byte), then 0x1D.
        u.feed(0x583, &[0x40, 0x00, 0x1A, 0x00, 0, 0, 0, 0]);
        u.feed(0x583, &[0x0C, 0x02, 0, 0, 0, 0, 0, 0]);
        let c = u
            .feed(0x583, &[0x1D, 0x01, 0, 0, 0, 0, 0, 0])
            .expect("done");
        assert_eq!((c.value, c.len), (0x0102, 2));
        // A toggle out of step drops the upload.
        u.feed(0x583, &[0x40, 0x00, 0x1A, 0x00, 0, 0, 0, 0]);
        assert_eq!(u.feed(0x583, &[0x1D, 0x01, 0, 0, 0, 0, 0, 0]), None);
        assert_eq!(u.feed(0x583, &[0x0D, 0x01, 0, 0, 0, 0, 0, 0]), None);
        // An abort drops it; an expedited answer starts none.
        u.feed(0x583, &[0x40, 0x00, 0x1A, 0x00, 0, 0, 0, 0]);
        u.feed(0x603, &[0x80, 0x00, 0x1A, 0x00, 0, 0, 0x04, 0x05]);
        assert_eq!(u.feed(0x583, &[0x0D, 0x01, 0, 0, 0, 0, 0, 0]), None);
        u.feed(0x583, &[0x43, 0x00, 0x1A, 0x00, 1, 0, 0, 0]);
        assert_eq!(u.feed(0x583, &[0x0D, 0x01, 0, 0, 0, 0, 0, 0]), None);
    }

    #[test]
    fn expedited_downloads_count_once_confirmed() {
        let mut d = Downloads::new();
        assert_eq!(
            d.feed(0x605, &[0x23, 0x00, 0x1A, 0x01, 0x10, 0x00, 0x41, 0x60]),
            None
        );
        let ok = [0x60, 0x00, 0x1A, 0x01, 0, 0, 0, 0];
        assert_eq!(
            d.feed(0x585, &ok),
            Some(Confirmed {
                node: 5,
                object: Object {
                    index: 0x1A00,
                    sub: 1
                },
                value: 0x6041_0010,
                len: 4,
            })
        );
        assert_eq!(d.feed(0x585, &ok), None, "nothing pending");
        // One byte (0x2F: n = 3), the unused bytes not part of the value.
        d.feed(0x605, &[0x2F, 0x00, 0x1A, 0x00, 0x03, 0xAA, 0xBB, 0xCC]);
        let c = d
            .feed(0x585, &[0x60, 0x00, 0x1A, 0x00, 0, 0, 0, 0])
            .expect("confirmed");
        assert_eq!((c.value, c.len), (3, 1));
        // Aborted: nothing.
        d.feed(0x605, &[0x23, 0x00, 0x18, 0x01, 0x85, 0x01, 0, 0]);
        d.feed(0x585, &[0x80, 0x00, 0x18, 0x01, 0x00, 0x00, 0x09, 0x06]);
        assert_eq!(d.feed(0x585, &[0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0]), None);
        // A confirmation for another object or node does not count.
        d.feed(0x605, &[0x23, 0x00, 0x18, 0x01, 0x85, 0x01, 0, 0]);
        assert_eq!(d.feed(0x585, &[0x60, 0x01, 0x18, 0x01, 0, 0, 0, 0]), None);
        assert_eq!(d.feed(0x586, &[0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0]), None);
        assert!(
            d.feed(0x585, &[0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0])
                .is_some()
        );
    }

    #[test]
    fn segmented_download_of_a_small_value() {
        let mut d = Downloads::new();
        // Initiate, size 4 indicated (0x21).
        assert_eq!(d.feed(0x605, &[0x21, 0x00, 0x18, 0x01, 4, 0, 0, 0]), None);
        assert_eq!(d.feed(0x585, &[0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0]), None);
        // Last segment (c = 1), toggle 0, n = 3 unused: 0x07.
        assert_eq!(
            d.feed(0x605, &[0x07, 0x85, 0x02, 0x00, 0x00, 0xEE, 0xEE, 0xEE]),
            None
        );
        let c = d.feed(0x585, &[0x20, 0, 0, 0, 0, 0, 0, 0]).expect("done");
        assert_eq!(
            c.object,
            Object {
                index: 0x1800,
                sub: 1
            }
        );
        assert_eq!((c.value, c.len), (0x285, 4));
    }

    #[test]
    fn segmented_download_follows_toggles_to_the_end() {
        let mut d = Downloads::new();
        // 10 bytes: too long to keep, followed to its end all the same.
        d.feed(0x605, &[0x21, 0x08, 0x10, 0x00, 10, 0, 0, 0]);
        d.feed(0x585, &[0x60, 0x08, 0x10, 0x00, 0, 0, 0, 0]);
        d.feed(0x605, &[0x00, b'a', b'b', b'c', b'd', b'e', b'f', b'g']);
        // A repeated segment (no answer yet) replaces the first.
        d.feed(0x605, &[0x00, b'a', b'b', b'c', b'd', b'e', b'f', b'g']);
        assert_eq!(d.feed(0x585, &[0x20, 0, 0, 0, 0, 0, 0, 0]), None);
        // Second segment: toggle 1, last, n = 4 (3 bytes): 0x19.
        d.feed(0x605, &[0x19, b'h', b'i', b'j', 0, 0, 0, 0]);
        assert_eq!(d.feed(0x585, &[0x30, 0, 0, 0, 0, 0, 0, 0]), None);
        // The channel is free again: an expedited write is read right.
        d.feed(0x605, &[0x23, 0x00, 0x18, 0x01, 0x85, 0x01, 0, 0]);
        assert!(
            d.feed(0x585, &[0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0])
                .is_some()
        );
    }

    #[test]
    fn segmented_download_out_of_step_is_dropped() {
        let mut d = Downloads::new();
        d.feed(0x605, &[0x20, 0x00, 0x18, 0x01, 0, 0, 0, 0]);
        d.feed(0x585, &[0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0]);
        // Toggle 1 where 0 was due.
        d.feed(0x605, &[0x17, 0x85, 0x01, 0x00, 0x00, 0, 0, 0]);
        assert_eq!(d.feed(0x585, &[0x30, 0, 0, 0, 0, 0, 0, 0]), None);
        // Size indicated and not met.
        d.feed(0x605, &[0x21, 0x00, 0x18, 0x01, 4, 0, 0, 0]);
        d.feed(0x585, &[0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0]);
        d.feed(0x605, &[0x0B, 0x85, 0x01, 0, 0, 0, 0, 0]);
        assert_eq!(d.feed(0x585, &[0x20, 0, 0, 0, 0, 0, 0, 0]), None);
        // Size not indicated: what came is the value.
        d.feed(0x605, &[0x20, 0x00, 0x18, 0x01, 0, 0, 0, 0]);
        d.feed(0x585, &[0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0]);
        d.feed(0x605, &[0x0B, 0x85, 0x01, 0, 0, 0, 0, 0]);
        let c = d.feed(0x585, &[0x20, 0, 0, 0, 0, 0, 0, 0]).expect("done");
        assert_eq!((c.value, c.len), (0x185, 2));
    }
}
