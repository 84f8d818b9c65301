//! What a packet of a CAN link type holds: Linux SocketCAN's `can_frame`
//! or `canfd_frame` (4-byte id and flags word, length, FD flags, two
//! reserved bytes, data), bare (LINKTYPE_CAN_SOCKETCAN, 227) or behind a
//! Linux "cooked" header (LINUX_SLL, 113; LINUX_SLL2, 276).
//!
//! The id word is big-endian in link type 227 (as the link type defines),
//! and in the capturing host's byte order, which is the file's, behind
//! LINUX_SLL and LINUX_SLL2 (libpcap writes it as the kernel handed it).

use crate::{FrameKind, Interest, Payload, Reason};

pub const CAN_SOCKETCAN: u16 = 227;
pub const LINUX_SLL: u16 = 113;
pub const LINUX_SLL2: u16 = 276;

const EFF_FLAG: u32 = 0x8000_0000;
const RTR_FLAG: u32 = 0x4000_0000;
const ERR_FLAG: u32 = 0x2000_0000;
const EFF_MASK: u32 = 0x1FFF_FFFF;
const SFF_MASK: u32 = 0x0000_07FF;
/// Error classes the kernel defines (`CAN_ERR_TX_TIMEOUT` .. `CAN_ERR_CNT`).
const ERR_CLASSES: u32 = 0x0000_03FF;
/// The length of every error frame the kernel sends (`CAN_ERR_DLC`).
const ERR_DLC: u8 = 8;

const CANFD_BRS: u8 = 0x01;
const CANFD_ESI: u8 = 0x02;
const CANFD_FDF: u8 = 0x04;
/// In the length byte's place, the flag of a CAN XL frame.
const CANXL_XLF: u8 = 0x80;
/// `sizeof(struct canfd_frame)`: a packet this long is CAN FD.
const CANFD_MTU: u32 = 72;

/// `sll_protocol` / `sll2_protocol` values of CAN classic and FD (Linux
/// `ETH_P_CAN`, `ETH_P_CANFD`; `ETH_P_CANXL`, 0x000E, is not read).
const ETH_P_CAN: u16 = 0x000C;
const ETH_P_CANFD: u16 = 0x000D;
/// ARPHRD types whose protocol field means something else.
const ARPHRD_IPGRE: u16 = 778;
const ARPHRD_NETLINK: u16 = 824;

/// A byte order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    Big,
    Little,
}

impl Order {
    pub fn u16(self, b: &[u8], at: usize) -> Option<u16> {
        let bytes: [u8; 2] = b.get(at..at + 2)?.try_into().ok()?;
        Some(match self {
            Order::Big => u16::from_be_bytes(bytes),
            Order::Little => u16::from_le_bytes(bytes),
        })
    }

    pub fn u32(self, b: &[u8], at: usize) -> Option<u32> {
        let bytes: [u8; 4] = b.get(at..at + 4)?.try_into().ok()?;
        Some(match self {
            Order::Big => u32::from_be_bytes(bytes),
            Order::Little => u32::from_le_bytes(bytes),
        })
    }

    pub fn u64(self, b: &[u8], at: usize) -> Option<u64> {
        let bytes: [u8; 8] = b.get(at..at + 8)?.try_into().ok()?;
        Some(match self {
            Order::Big => u64::from_be_bytes(bytes),
            Order::Little => u64::from_le_bytes(bytes),
        })
    }
}

/// A CAN frame as a packet carried it (everything of a `Frame` but its
/// time and channel).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Can {
    pub id: u32,
    pub extended: bool,
    pub kind: FrameKind,
    pub len: u8,
    pub data: Payload,
}

/// The identifier of a frame only counted: what it is counted under.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ident {
    pub id: u32,
    pub extended: bool,
}

/// What one packet is.
#[derive(Debug, PartialEq, Eq)]
pub enum Packet<'p> {
    Can(Can),
    /// A valid CAN frame the caller's [`Interest`] does not want (not a
    /// data frame, or on an id it does not decode): only counted.
    Plain(Ident),
    /// A LINKTYPE_CAN_SOCKETCAN packet read before the byte order of its id
    /// word is known (see [`evidence`]): decode it later with `socketcan`.
    Undecided(&'p [u8]),
    /// Not a CAN classic or FD frame: another link type, another
    /// protocol behind a cooked header, a CAN XL frame. Skipped.
    NotCan,
    Malformed(Reason),
}

/// The name of a link type in messages.
pub fn link_name(linktype: u16) -> &'static str {
    match linktype {
        CAN_SOCKETCAN => "CAN_SOCKETCAN",
        LINUX_SLL => "LINUX_SLL",
        LINUX_SLL2 => "LINUX_SLL2",
        _ => "packet",
    }
}

/// How CAN FD frames are told from classic ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Link type 227: by length and flags, as Wireshark does (a 72-byte
    /// packet, or the FDF flag with no unknown flag and zero reserved bytes).
    Guess,
    /// The cooked header's protocol says classic (`ETH_P_CAN`).
    Classic,
    /// ... or CAN FD (`ETH_P_CANFD`).
    Fd,
}

/// Where a packet's SocketCAN frame is: the frame's bytes, its reported
/// length, the byte order of its id word and how FD is told.
enum Located<'p> {
    Frame(&'p [u8], u32, Order, Shape),
    /// Link type 227 before its byte order is known.
    Undecided,
    NotCan,
    Malformed(Reason),
}

#[inline]
fn locate(
    linktype: u16,
    data: &[u8],
    reported: u32,
    file: Order,
    socketcan: Option<Order>,
) -> Located<'_> {
    let (header, protocol_at, hatype_at) = match linktype {
        CAN_SOCKETCAN => {
            return match socketcan {
                None => Located::Undecided,
                Some(order) => Located::Frame(data, reported, order, Shape::Guess),
            };
        }
        LINUX_SLL => (16, 14, 2),
        LINUX_SLL2 => (20, 0, 8),
        _ => return Located::NotCan,
    };
    let Some(payload) = data.get(header..) else {
        return Located::Malformed(
            format!(
                "{} packet of {} bytes: shorter than its {header}-byte header",
                link_name(linktype),
                data.len()
            )
            .into(),
        );
    };
    let protocol = Order::Big.u16(data, protocol_at).unwrap_or(0);
    let hatype = Order::Big.u16(data, hatype_at).unwrap_or(0);
    if matches!(hatype, ARPHRD_IPGRE | ARPHRD_NETLINK) {
        return Located::NotCan;
    }
    let shape = match protocol {
        ETH_P_CAN => Shape::Classic,
        ETH_P_CANFD => Shape::Fd,
        // CAN XL and everything else.
        _ => return Located::NotCan,
    };
    let reported = reported.saturating_sub(header as u32);
    Located::Frame(payload, reported, file, shape)
}

/// Decodes one packet of `linktype`. `reported` is the packet's length on
/// the wire (the original length), `file` the file's byte order (the id
/// word behind a cooked header), `socketcan` the byte order of link type
/// 227's id word, `None` while it is not known. With `interest`, a valid
/// frame it does not want is [`Packet::Plain`], its data not copied.
pub fn decode<'p>(
    linktype: u16,
    data: &'p [u8],
    reported: u32,
    file: Order,
    socketcan: Option<Order>,
    interest: Option<&Interest>,
) -> Packet<'p> {
    match locate(linktype, data, reported, file, socketcan) {
        Located::Frame(d, reported, order, shape) => {
            frame(linktype, d, reported, order, shape, interest)
        }
        Located::Undecided => Packet::Undecided(data),
        Located::NotCan => Packet::NotCan,
        Located::Malformed(why) => Packet::Malformed(why),
    }
}

/// What the hot loop makes of a packet, without building anything.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quick {
    /// What [`decode`] with the interest says is [`Packet::Plain`].
    Plain(Ident),
    /// A valid data frame on a wanted id whose data the interest's content
    /// filter rejects: only its time is needed.
    Timed(Ident),
    /// Anything else: [`decode`] it.
    Full,
}

#[inline]
pub fn quick(
    linktype: u16,
    data: &[u8],
    reported: u32,
    file: Order,
    socketcan: Option<Order>,
    interest: &Interest,
) -> Quick {
    let Located::Frame(d, reported, order, shape) =
        locate(linktype, data, reported, file, socketcan)
    else {
        return Quick::Full;
    };
    match head(d, reported, order, shape) {
        Ok(Some(h)) if h.plain(interest) => Quick::Plain(h.ident()),
        Ok(Some(h))
            if interest.timed_only(
                h.id,
                h.extended,
                d.get(8..8 + usize::from(h.len)).unwrap_or_default(),
            ) =>
        {
            Quick::Timed(h.ident())
        }
        _ => Quick::Full,
    }
}

/// Decodes a SocketCAN `can_frame` / `canfd_frame` whose id word is in
/// `order`. An error frame's id is its class bits without the error flag,
/// as every reader gives it (`crate::error_frame`).
pub fn frame<'p>(
    linktype: u16,
    d: &'p [u8],
    reported: u32,
    order: Order,
    shape: Shape,
    interest: Option<&Interest>,
) -> Packet<'p> {
    let head = match head(d, reported, order, shape) {
        Ok(Some(head)) => head,
        Ok(None) => return Packet::NotCan,
        Err(why) => {
            return Packet::Malformed(format!("{} packet: {why}", link_name(linktype)).into());
        }
    };
    if interest.is_some_and(|i| head.plain(i)) {
        return Packet::Plain(head.ident());
    }
    let data = if head.kind == FrameKind::Remote {
        Payload::new()
    } else {
        match payload(d, head.len) {
            Some(data) => data,
            None => return Packet::Malformed("more than 64 data bytes".into()),
        }
    };
    Packet::Can(Can {
        id: head.id,
        extended: head.extended,
        kind: head.kind,
        len: head.len,
        data,
    })
}

/// The frame's data bytes, `len` of them after the 8-byte header (which
/// [`head`] made sure are there).
#[inline]
fn payload(d: &[u8], len: u8) -> Option<Payload> {
    let n = usize::from(len);
    if let Some(bytes) = d.get(8..16)
        && n <= 8
    {
        // Eight bytes at once, those past the length cleared.
        let word = u64::from_le_bytes(bytes.try_into().unwrap_or_default());
        let mask = u64::MAX.checked_shr(64 - 8 * n as u32).unwrap_or(0);
        return Some(Payload::inline((word & mask).to_le_bytes(), len));
    }
    Payload::from_slice(d.get(8..8 + n)?)
}

/// What a frame is, checked, before its data is copied.
#[derive(Clone, Copy, Debug)]
struct Head {
    id: u32,
    extended: bool,
    kind: FrameKind,
    len: u8,
}

impl Head {
    #[inline]
    fn ident(self) -> Ident {
        Ident {
            id: self.id,
            extended: self.extended,
        }
    }

    /// Only counted: on an id `interest` does not want (CAN FD frames
    /// also unless it wants those), as the text readers count.
    #[inline]
    fn plain(self, interest: &Interest) -> bool {
        match self.kind {
            // Rare, and always decoded whole, whatever the interest.
            FrameKind::Error => false,
            FrameKind::Data | FrameKind::Remote => !interest.wants(self.id, self.extended),
            FrameKind::Fd => !interest.wants_fd_on(self.id, self.extended),
        }
    }
}

/// Reads and checks a frame's header: `Ok(None)` for a CAN XL frame (not
/// read), `Err` with the reason when it is no valid frame, the data bytes
/// it declares included.
#[inline]
fn head(d: &[u8], reported: u32, order: Order, shape: Shape) -> Result<Option<Head>, String> {
    let Some(&[b0, b1, b2, b3, len, flags, r0, r1]) = d.first_chunk::<8>() else {
        return Err(short(d));
    };
    let word = match order {
        Order::Big => u32::from_be_bytes([b0, b1, b2, b3]),
        Order::Little => u32::from_le_bytes([b0, b1, b2, b3]),
    };
    let reserved = r0 == 0 && r1 == 0;
    let fd = match shape {
        Shape::Guess if len & CANXL_XLF != 0 && reported > 12 => return Ok(None),
        Shape::Guess => {
            reported == CANFD_MTU
                || (flags & CANFD_FDF != 0
                    && flags & !(CANFD_BRS | CANFD_ESI | CANFD_FDF) == 0
                    && reserved)
        }
        Shape::Classic => false,
        Shape::Fd => true,
    };
    let head = if word & ERR_FLAG != 0 {
        if len > 8 {
            return Err(format!("error frame with {len} data bytes (at most 8)"));
        }
        Head {
            // The class bits, without the flag (`crate::error_frame`).
            id: word & EFF_MASK,
            extended: false,
            kind: FrameKind::Error,
            len,
        }
    } else {
        let extended = word & EFF_FLAG != 0;
        if !extended && word & EFF_MASK & !SFF_MASK != 0 {
            return Err(format!(
                "id word 0x{word:08X}: a standard (11-bit) id with bits above bit 10 set"
            ));
        }
        let id = word & if extended { EFF_MASK } else { SFF_MASK };
        let remote = word & RTR_FLAG != 0;
        let (kind, len) = if fd {
            if remote {
                return Err(format!(
                    "CAN FD frame 0x{id:X} with the remote flag (CAN FD has no remote frames)"
                ));
            }
            if len > 64 {
                return Err(format!("CAN FD frame of {len} bytes (at most 64)"));
            }
            (FrameKind::Fd, len)
        } else if remote {
            (FrameKind::Remote, 0)
        } else {
            if len > 8 {
                return Err(format!("classic CAN frame of {len} bytes (at most 8)"));
            }
            (FrameKind::Data, len)
        };
        Head {
            id,
            extended,
            kind,
            len,
        }
    };
    if d.len() < 8 + usize::from(head.len) {
        return Err(format!(
            "{} of the frame's {} data bytes captured",
            d.len() - 8,
            head.len
        ));
    }
    Ok(Some(head))
}

fn short(d: &[u8]) -> String {
    format!(
        "{} bytes of CAN frame, shorter than its 8-byte header",
        d.len()
    )
}

/// Whether an id word read in some byte order is one no CAN frame has:
/// an error frame with the extended or remote flag, an error class the
/// kernel does not define or a length other than 8; a standard id with
/// bits above bit 10; or an extended id whose low 16 bits are all zero
/// where the other byte order reads a plain standard id (the mark of a
/// little-endian 11-bit id read big-endian: `81 00 00 00`).
fn impossible(word: u32, other: u32, len: u8) -> bool {
    let extended = word & EFF_FLAG != 0;
    if word & ERR_FLAG != 0 {
        return extended
            || word & RTR_FLAG != 0
            || word & EFF_MASK & !ERR_CLASSES != 0
            || len != ERR_DLC;
    }
    if !extended {
        return word & EFF_MASK & !SFF_MASK != 0;
    }
    word & 0xFFFF == 0 && other & !SFF_MASK == 0
}

/// What a LINKTYPE_CAN_SOCKETCAN packet says about the byte order of the
/// id words: `[impossible read big-endian, impossible read little-endian]`;
/// `None` when it is no CAN frame either way (too short, or a length the
/// captured bytes do not hold).
pub fn evidence(d: &[u8]) -> Option<[bool; 2]> {
    let big = Order::Big.u32(d, 0)?;
    let little = Order::Little.u32(d, 0)?;
    let len = *d.get(4)?;
    if len > 64 || d.len() < 8 + usize::from(len) {
        return None;
    }
    Some([impossible(big, little, len), impossible(little, big, len)])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn can(id_word: [u8; 4], len: u8, flags: u8, data: &[u8]) -> Vec<u8> {
        let mut p = id_word.to_vec();
        p.extend([len, flags, 0, 0]);
        p.extend(data);
        p
    }

    fn decoded(p: Packet<'_>) -> Can {
        match p {
            Packet::Can(c) => c,
            other => panic!("{other:?}"),
        }
    }

    fn malformed(p: Packet<'_>) -> String {
        match p {
            Packet::Malformed(r) => r.into_owned(),
            other => panic!("{other:?}"),
        }
    }

    const BE: Option<Order> = Some(Order::Big);

    #[test]
    fn socketcan_flags_make_extended_remote_and_error_frames() {
        let emcy = can([0, 0, 0, 0x81], 8, 0, &[0x10, 0x43, 8, 1, 0, 0, 0, 0]);
        let c = decoded(decode(227, &emcy, 16, Order::Little, BE, None));
        assert_eq!(
            (c.id, c.extended, c.kind, c.len),
            (0x81, false, FrameKind::Data, 8)
        );
        assert_eq!(c.data.as_slice(), &emcy[8..]);

        let ext = can([0x81, 0x23, 0x45, 0x67], 2, 0, &[1, 2]);
        let c = decoded(decode(227, &ext, 10, Order::Little, BE, None));
        assert_eq!(
            (c.id, c.extended, c.kind),
            (0x0123_4567, true, FrameKind::Data)
        );

        let rtr = can([0x40, 0, 0x01, 0x23], 4, 0, &[]);
        let c = decoded(decode(227, &rtr, 8, Order::Little, BE, None));
        assert_eq!(
            (c.id, c.extended, c.kind, c.len),
            (0x123, false, FrameKind::Remote, 0)
        );

        let err = can([0x20, 0, 0, 0x04], 8, 0, &[0, 4, 0, 0, 0, 0, 0, 0]);
        let c = decoded(decode(227, &err, 16, Order::Little, BE, None));
        assert_eq!((c.id, c.extended, c.kind), (0x004, false, FrameKind::Error));
    }

    #[test]
    fn can_fd_is_told_by_length_or_clean_flags() {
        let mut fd = can([0, 0, 0, 0x81], 12, CANFD_BRS, &[0; 12]);
        fd.resize(72, 0);
        assert_eq!(
            decoded(decode(227, &fd, 72, Order::Big, BE, None)).kind,
            FrameKind::Fd
        );
        // The FDF flag, no unknown flags, zero reserved bytes: FD even when short.
        let short_fd = can([0, 0, 0, 0x81], 3, CANFD_FDF | CANFD_BRS, &[1, 2, 3]);
        assert_eq!(
            decoded(decode(227, &short_fd, 11, Order::Big, BE, None)).kind,
            FrameKind::Fd
        );
        // Junk in the flags byte of a classic frame: classic.
        let junk = can([0, 0, 0, 0x81], 3, 0xF4, &[0x10, 0x43, 8]);
        let c = decoded(decode(227, &junk, 11, Order::Big, BE, None));
        assert_eq!((c.kind, c.len), (FrameKind::Data, 3));
        // A CAN XL frame is not read.
        let xl = can([0, 0, 0, 0x81], CANXL_XLF, 0, &[0; 8]);
        assert_eq!(decode(227, &xl, 16, Order::Big, BE, None), Packet::NotCan);
    }

    #[test]
    fn bad_lengths_and_ids_are_malformed() {
        let long = can([0, 0, 0, 0x81], 9, 0, &[0; 9]);
        assert!(malformed(decode(227, &long, 17, Order::Big, BE, None)).contains("at most 8"));
        let cut = can([0, 0, 0, 0x81], 8, 0, &[0; 5]);
        assert!(
            malformed(decode(227, &cut, 13, Order::Big, BE, None)).contains("5 of the frame's 8")
        );
        let wide = can([0, 0, 0x08, 0x01], 0, 0, &[]);
        assert!(
            malformed(decode(227, &wide, 8, Order::Big, BE, None)).contains("bits above bit 10")
        );
        assert!(
            malformed(decode(227, &[0, 0, 0], 3, Order::Big, BE, None)).contains("8-byte header")
        );
        let mut fd_rtr = can([0x40, 0, 0, 0x81], 8, 0, &[0; 8]);
        fd_rtr.resize(72, 0);
        assert!(malformed(decode(227, &fd_rtr, 72, Order::Big, BE, None)).contains("remote"));
    }

    fn sll(protocol: u16, hatype: u16, frame: &[u8]) -> Vec<u8> {
        let mut p = vec![0, 1];
        p.extend(hatype.to_be_bytes());
        p.extend([0u8; 10]);
        p.extend(protocol.to_be_bytes());
        p.extend(frame);
        p
    }

    fn sll2(protocol: u16, frame: &[u8]) -> Vec<u8> {
        let mut p = protocol.to_be_bytes().to_vec();
        p.extend([0, 0, 0, 0, 0, 3]); // reserved, interface index 3
        p.extend(280u16.to_be_bytes());
        p.extend([0, 0]);
        p.extend([0u8; 8]);
        p.extend(frame);
        p
    }

    #[test]
    fn cooked_headers_carry_the_id_in_the_file_byte_order() {
        let le = can([0x81, 0, 0, 0], 3, 0, &[0x10, 0x43, 8]);
        let p = sll(ETH_P_CAN, 280, &le);
        let c = decoded(decode(
            LINUX_SLL,
            &p,
            p.len() as u32,
            Order::Little,
            None,
            None,
        ));
        assert_eq!((c.id, c.kind, c.len), (0x81, FrameKind::Data, 3));
        let be = can([0, 0, 0, 0x81], 3, 0, &[0x10, 0x43, 8]);
        let p = sll2(ETH_P_CAN, &be);
        let c = decoded(decode(
            LINUX_SLL2,
            &p,
            p.len() as u32,
            Order::Big,
            None,
            None,
        ));
        assert_eq!((c.id, c.kind), (0x81, FrameKind::Data));
        // The protocol decides FD, whatever the length.
        let p = sll(ETH_P_CANFD, 0, &le);
        let c = decoded(decode(
            LINUX_SLL,
            &p,
            p.len() as u32,
            Order::Little,
            None,
            None,
        ));
        assert_eq!(
            (c.kind, c.data.as_slice()),
            (FrameKind::Fd, &[0x10, 0x43, 8][..])
        );
        // Other protocols, CAN XL and netlink captures are not CAN frames.
        for (linktype, p) in [
            (LINUX_SLL, sll(0x0800, 1, &le)),
            (LINUX_SLL, sll(0x000E, 280, &le)), // CAN XL
            (LINUX_SLL, sll(ETH_P_CAN, ARPHRD_NETLINK, &le)),
            (LINUX_SLL2, sll2(0x86DD, &le)),
        ] {
            assert_eq!(
                decode(linktype, &p, 0, Order::Little, None, None),
                Packet::NotCan
            );
        }
        assert!(
            malformed(decode(LINUX_SLL2, &[0; 19], 19, Order::Big, None, None)).contains("20-byte")
        );
        // Other link types: not CAN, never malformed.
        assert_eq!(decode(1, &[], 0, Order::Big, None, None), Packet::NotCan);
        assert_eq!(
            decode(212, &[1, 2, 3], 3, Order::Big, None, None),
            Packet::NotCan
        );
    }

    #[test]
    fn unwanted_frames_are_plain_and_still_validated() {
        let mut interest = Interest::none();
        interest.add_standard_range(0x81..=0xFF);
        let i = Some(&interest);
        let emcy = can([0, 0, 0, 0x81], 3, 0, &[0x10, 0x43, 8, 0xAA, 0xBB]);
        let c = decoded(decode(227, &emcy, 13, Order::Big, BE, i));
        // Only the frame's bytes, whatever follows them.
        assert_eq!(c.data, Payload::from_slice(&[0x10, 0x43, 8]).unwrap());
        let pdo = can([0, 0, 0x01, 0x81], 8, 0, &[0; 8]);
        let plain = Packet::Plain(Ident {
            id: 0x181,
            extended: false,
        });
        assert_eq!(decode(227, &pdo, 16, Order::Big, BE, i), plain);
        // A remote frame is counted or decoded by its id, as a data frame.
        let rtr = can([0x40, 0, 0x01, 0x81], 0, 0, &[]);
        assert_eq!(decode(227, &rtr, 8, Order::Big, BE, i), plain);
        let rtr = can([0x40, 0, 0, 0x81], 0, 0, &[]);
        assert_eq!(
            decoded(decode(227, &rtr, 8, Order::Big, BE, i)).kind,
            FrameKind::Remote
        );
        let cut = can([0, 0, 0x01, 0x81], 8, 0, &[0; 3]);
        assert!(malformed(decode(227, &cut, 11, Order::Big, BE, i)).contains("3 of the frame's 8"));
    }

    #[test]
    fn little_endian_ids_read_big_endian_are_impossible() {
        // As scapy writes link type 227: 0x12A, 0x081, 0x701, 0x000.
        let le = |id: u32, len: u8| can(id.to_le_bytes(), len, 0, &vec![0; usize::from(len)]);
        assert_eq!(evidence(&le(0x12A, 8)), Some([true, false]));
        assert_eq!(evidence(&le(0x081, 8)), Some([true, false]));
        assert_eq!(evidence(&le(0x701, 1)), Some([true, false]));
        assert_eq!(evidence(&le(0x000, 2)), Some([false, false]));
        // The same ids written big-endian, as the link type defines.
        let be = |id: u32, len: u8| can(id.to_be_bytes(), len, 0, &vec![0; usize::from(len)]);
        assert_eq!(evidence(&be(0x12A, 8)), Some([false, true]));
        assert_eq!(evidence(&be(0x081, 8)), Some([false, true]));
        // Extended ids and error frames written big-endian.
        assert_eq!(evidence(&be(0x8123_4567, 8)), Some([false, true]));
        assert_eq!(evidence(&be(0x2000_0004, 8)), Some([false, true]));
        // An error frame must have 8 bytes.
        assert_eq!(evidence(&be(0x2000_0004, 2)), Some([true, true]));
        // Not a CAN frame either way: no evidence.
        assert_eq!(evidence(&can([0; 4], 8, 0, &[0; 3])), None);
        assert_eq!(evidence(&[0; 5]), None);
    }
}
