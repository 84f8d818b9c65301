//! The packet decoder: blocks and records into items, by the section's
//! byte order and interfaces.

use std::collections::VecDeque;

use pcap_parser::Block;
use pcap_parser::traits::PcapNGPacketBlock;

use crate::ethercat::{self, CoeMessage, EthercatPacket};
use crate::id_counts::CountedChannel;
use crate::{IdCounts, Interest, Reason, Timestamp};

use super::clock::{self, Clock};
use super::consts::{
    KEEP, KNOWN_BLOCKS, MAX_BLOCK, MAX_COUNTED_DEVICES, MAX_INTERFACES, MAX_PACKET, PACKET_BLOCK,
    bom, is_pcapng_block_type, sane_block,
};
use super::counted::{Hot, RawTime};
use super::items::{Interface, Item, Ts};
use super::packet::{self, Order, Packet};

/// What a block is to the caller.
pub(super) enum Outcome {
    /// A line.
    Item(Item),
    /// A block that describes the capture: not a line.
    Nothing,
}

/// Whether a resync found the start of a block (or record).
pub(super) enum Candidate {
    Yes,
    No,
    /// Needs this many bytes from the candidate's start to tell.
    More(usize),
}

/// What turns blocks into items: the section's byte order, its
/// interfaces, the byte order of link type 227.
pub(super) struct Decoder {
    /// The file's byte order (pcap) or the current section's (pcapng).
    pub(super) order: Order,
    /// pcap: nanosecond times.
    pub(super) nanos: bool,
    pub(super) interfaces: Vec<Interface>,
    /// The byte order of link type 227's id word, once known.
    pub(super) socketcan: Option<Order>,
    pub(super) notes: VecDeque<String>,
    /// A note about units finer than attoseconds was given.
    pub(super) fine_noted: bool,
}

impl Decoder {
    /// The channel of interface `iface`: its name (empty when no
    /// interface description declares it).
    pub(super) fn interface_name(&self, iface: usize) -> Box<[u8]> {
        self.interfaces
            .get(iface)
            .map_or_else(Box::default, |i| i.name.clone())
    }

    /// `NAME:INDEX`: a device seen through an interface that captures
    /// several (`any`).
    pub(super) fn device_channel(&self, iface: usize, device: u32) -> Box<[u8]> {
        device_name(self.interfaces.get(iface).map_or(&[], |i| &i.name), device)
    }

    /// The device a packet on interface `iface` came from, when it is part
    /// of its channel's name (see [`Interface::several`]).
    #[inline]
    pub(super) fn device(&self, iface: usize, data: &[u8]) -> Option<u32> {
        self.interfaces.get(iface).and_then(|i| device(i, data))
    }

    /// [`Decoder::counted_channel`] of a frame on interface `iface` whose
    /// packet is `data`.
    #[inline(never)]
    pub(super) fn counted_channel_of(
        &mut self,
        ids: &mut IdCounts,
        iface: usize,
        data: &[u8],
    ) -> CountedChannel {
        let device = self.device(iface, data);
        self.counted_channel(ids, iface, device)
    }

    /// Where a frame only counted on interface `iface` (from `device`) is
    /// counted: under the channel its frame would name, looked up by name
    /// on the interface's first such frame (and each device's).
    #[inline]
    pub(super) fn counted_channel(
        &mut self,
        ids: &mut IdCounts,
        iface: usize,
        device: Option<u32>,
    ) -> CountedChannel {
        let Some(i) = self.interfaces.get_mut(iface) else {
            // No packet is read on an interface not described.
            return CountedChannel::Unknown;
        };
        if let Some(device) = device {
            return device_counted(i, ids, device);
        }
        if i.counted == CountedChannel::Unknown {
            i.counted = ids.counted_channel(&i.name);
        }
        i.counted
    }

    pub(super) fn time(&self, interface: &Interface, ts: Ts) -> Result<Option<Timestamp>, Reason> {
        match ts {
            Ts::None => Ok(None),
            Ts::Legacy { secs, frac } => Ok(Some(clock::legacy(secs, frac, self.nanos))),
            Ts::Units(units) => interface.clock.time(units).map(Some).ok_or_else(|| {
                format!(
                    "a time of {units} units of {} is before 1970 or too late once the \
                     interface's if_tsoffset is added",
                    interface.clock.describe()
                )
                .into()
            }),
        }
    }

    /// One packet on interface `iface` (of this section), `data` as
    /// captured, `reported` bytes long on the wire; with `interest`, a
    /// frame it does not want is only validated ([`Item::Plain`]).
    pub(super) fn packet(
        &self,
        iface: usize,
        ts: Ts,
        data: &[u8],
        reported: u32,
        interest: Option<&Interest>,
    ) -> Item {
        let Some(interface) = self.interfaces.get(iface) else {
            return Item::Malformed(
                format!("a packet on interface {iface}, which no interface description declares")
                    .into(),
            );
        };
        match packet::decode(
            interface.linktype,
            data,
            reported,
            self.order,
            self.socketcan,
            interest,
        ) {
            Packet::Plain(ident) => Item::Plain {
                iface,
                ts,
                device: device(interface, data),
                ident,
            },
            Packet::Can(can) => match self.time(interface, ts) {
                Ok(time) => Item::Frame {
                    iface,
                    device: device(interface, data),
                    time,
                    can,
                },
                Err(why) => Item::Malformed(why),
            },
            Packet::Undecided(bytes) => match self.time(interface, ts) {
                Ok(time) => Item::Undecided {
                    iface,
                    time,
                    bytes: bytes.get(..KEEP).unwrap_or(bytes).into(),
                    reported,
                },
                Err(why) => Item::Malformed(why),
            },
            Packet::NotCan => match ethercat::locate(interface.linktype, data) {
                Some(frame) => match self.time(interface, ts) {
                    Ok(time) => Item::Ethercat {
                        iface,
                        packet: Box::new(walk_ethercat(frame, time)),
                    },
                    Err(why) => Item::Malformed(why),
                },
                None => Item::Skipped,
            },
            Packet::Malformed(why) => Item::Malformed(why),
        }
    }

    /// A packet's time as stored, with what reads it.
    pub(super) fn raw_time(&self, iface: usize, ts: Ts) -> Option<RawTime> {
        let i = self.interfaces.get(iface)?;
        Some(RawTime {
            clock: i.clock,
            ts,
            nanos: self.nanos,
        })
    }

    /// What the hot loop makes of a packet (see [`packet::quick`]): a
    /// plain frame, a frame only timed (with its time, to be read when
    /// needed: it cannot fail), an EtherCAT frame with no mailbox message,
    /// or `None` for the general path.
    #[inline]
    pub(super) fn quick(
        &self,
        iface: usize,
        ts: Ts,
        data: &[u8],
        reported: u32,
        interest: &Interest,
    ) -> Option<Hot> {
        let i = self.interfaces.get(iface)?;
        match packet::quick(
            i.linktype,
            data,
            reported,
            self.order,
            self.socketcan,
            interest,
        ) {
            packet::Quick::Plain(ident) => Some(Hot::Plain(ident, i.counted(), None)),
            packet::Quick::Timed(ident) => {
                let sure = match ts {
                    Ts::Legacy { .. } => true,
                    Ts::Units(_) => i.clock.infallible(),
                    Ts::None => false,
                };
                sure.then_some(Hot::Plain(
                    ident,
                    i.counted(),
                    Some(RawTime {
                        clock: i.clock,
                        ts,
                        nanos: self.nanos,
                    }),
                ))
            }
            packet::Quick::Full => {
                // Process data and empty polls, nearly every packet of an
                // EtherCAT capture, are counted here; a mailbox message
                // (or damage) takes the general path.
                let frame = ethercat::locate(i.linktype, data)?;
                match ethercat::walk(frame, |_| {}) {
                    Ok(w) if w.mailboxes == 0 => Some(Hot::Ethercat(w)),
                    _ => None,
                }
            }
        }
    }

    /// A pcapng block the crate parsed, at byte `at`.
    pub(super) fn block(
        &mut self,
        block: Block<'_>,
        at: u64,
        interest: Option<&Interest>,
    ) -> Outcome {
        match block {
            Block::SectionHeader(shb) => {
                self.order = if shb.big_endian() {
                    Order::Big
                } else {
                    Order::Little
                };
                self.interfaces.clear();
                Outcome::Nothing
            }
            Block::InterfaceDescription(idb) => {
                if self.interfaces.len() >= MAX_INTERFACES {
                    return Outcome::Item(Item::Malformed(
                        format!(
                            "interface description at byte {at}: more than {MAX_INTERFACES} \
                             interfaces in one section; its packets are not read"
                        )
                        .into(),
                    ));
                }
                let option = |code: u16| {
                    idb.options
                        .iter()
                        .find(|o| o.code.0 == code)
                        .and_then(|o| o.as_bytes().ok())
                };
                let index = self.interfaces.len();
                let (name, several): (Box<[u8]>, bool) = match option(2) {
                    Some(name) if !name.is_empty() => (name.into(), name == b"any"),
                    _ => (index.to_string().into_bytes().into(), true),
                };
                let resolution = option(9).and_then(|v| v.first().copied()).unwrap_or(6);
                let offset = option(14)
                    .and_then(|v| self.order.u64(v, 0))
                    .map_or(0, |v| v as i64);
                let clock = Clock::new(resolution, offset);
                if clock.finer_than_atto() && !self.fine_noted {
                    self.fine_noted = true;
                    self.notes.push_back(format!(
                        "interface {} counts time in units of {}: times are cut to \
                         attoseconds (18 digits)",
                        String::from_utf8_lossy(&name),
                        clock.describe()
                    ));
                }
                self.interfaces.push(Interface::new(
                    (idb.linktype.0 & 0xFFFF) as u16,
                    name,
                    several,
                    clock,
                    idb.snaplen,
                ));
                Outcome::Nothing
            }
            Block::EnhancedPacket(epb) => {
                let units = u64::from(epb.ts_high) << 32 | u64::from(epb.ts_low);
                Outcome::Item(self.packet(
                    epb.if_id as usize,
                    Ts::Units(units),
                    epb.packet_data(),
                    epb.origlen,
                    interest,
                ))
            }
            Block::SimplePacket(spb) => {
                // Captured: the original length, cut by the snapshot length.
                let snaplen = self.interfaces.first().map_or(0, |i| i.snaplen);
                let mut captured = spb.origlen as usize;
                if snaplen > 0 {
                    captured = captured.min(snaplen as usize);
                }
                let data = spb.data.get(..captured).unwrap_or(spb.data);
                Outcome::Item(self.packet(0, Ts::None, data, spb.origlen, interest))
            }
            Block::Unknown(b)
                if self.order.u32(&b.block_type.to_le_bytes(), 0) == Some(PACKET_BLOCK) =>
            {
                let d = b.data;
                let o = self.order;
                let (Some(iface), Some(high), Some(low), Some(caplen), Some(len)) = (
                    o.u16(d, 0),
                    o.u32(d, 4),
                    o.u32(d, 8),
                    o.u32(d, 12),
                    o.u32(d, 16),
                ) else {
                    return Outcome::Item(Item::Malformed(
                        format!("packet block at byte {at}: its header is cut off").into(),
                    ));
                };
                let Some(data) = d.get(20..20 + caplen as usize) else {
                    return Outcome::Item(Item::Malformed(
                        format!(
                            "packet block at byte {at}: {caplen} captured bytes do not fit in it"
                        )
                        .into(),
                    ));
                };
                let units = u64::from(high) << 32 | u64::from(low);
                Outcome::Item(self.packet(
                    usize::from(iface),
                    Ts::Units(units),
                    data,
                    len,
                    interest,
                ))
            }
            _ => Outcome::Nothing,
        }
    }

    /// Whether a pcapng block starts at `d` (see the module's doc).
    pub(super) fn block_at(&self, d: &[u8], end: bool) -> Candidate {
        if d.len() < 12 {
            return if end {
                Candidate::No
            } else {
                Candidate::More(12)
            };
        }
        let order = if is_pcapng_block_type(d) {
            match bom(d) {
                Some(o) => o,
                None => return Candidate::No,
            }
        } else {
            self.order
        };
        let (Some(kind), Some(len)) = (order.u32(d, 0), order.u32(d, 4)) else {
            return Candidate::No;
        };
        let len = len as usize;
        if !KNOWN_BLOCKS.contains(&kind) || !sane_block(len) {
            return Candidate::No;
        }
        match order.u32(d, len - 4) {
            Some(trailer) if trailer as usize == len => Candidate::Yes,
            Some(_) => Candidate::No,
            None if end => Candidate::No,
            None => Candidate::More(len),
        }
    }

    /// The captured length of a pcap record header at `d` that could be
    /// one: a fraction under a second, a captured length the reader takes,
    /// not over the original length and not under the link type's header.
    fn record_header(&self, d: &[u8]) -> Option<usize> {
        let frac = self.order.u32(d, 4)?;
        let caplen = self.order.u32(d, 8)?;
        let origlen = self.order.u32(d, 12)?;
        let per_sec = if self.nanos { 1_000_000_000 } else { 1_000_000 };
        let least = match self.interfaces.first().map(|i| i.linktype) {
            Some(packet::CAN_SOCKETCAN) => 8,
            Some(packet::LINUX_SLL) => 16,
            Some(packet::LINUX_SLL2) => 20,
            _ => 0,
        };
        (frac < per_sec
            && caplen as usize <= MAX_PACKET
            && caplen <= origlen
            && origlen as usize <= MAX_BLOCK
            && caplen >= least)
            .then_some(caplen as usize)
    }

    /// Whether a pcap record starts at `d`: it and the two after it have
    /// headers that fit (or the file ends right after one of them).
    pub(super) fn record_at(&self, d: &[u8], end: bool) -> Candidate {
        let mut at = 0;
        for _ in 0..3 {
            if end && at > 0 && at >= d.len() {
                // The file ends right after a record, or inside one.
                return if at == d.len() {
                    Candidate::Yes
                } else {
                    Candidate::No
                };
            }
            let rest = d.get(at..).unwrap_or_default();
            if rest.len() < 16 {
                return if end {
                    Candidate::No
                } else {
                    Candidate::More(at + 16)
                };
            }
            let Some(caplen) = self.record_header(rest) else {
                return Candidate::No;
            };
            at += 16 + caplen;
        }
        Candidate::Yes
    }
}

/// The device of a packet on `interface`: part of its channel's name when
/// the interface captures several and the packet's LINUX_SLL2 header says
/// which (its interface index).
#[inline]
fn device(interface: &Interface, data: &[u8]) -> Option<u32> {
    interface
        .by_device()
        .then(|| Order::Big.u32(data, 4))
        .flatten()
}

/// `NAME:INDEX`, the channel of a device seen through interface `NAME`.
fn device_name(interface: &[u8], device: u32) -> Box<[u8]> {
    let mut name = interface.to_vec();
    name.push(b':');
    name.extend_from_slice(itoa::Buffer::new().format(device).as_bytes());
    name.into()
}

/// Where a frame only counted from `device` on interface `i` is counted:
/// looked up by its channel's name once per device, for the first
/// [`MAX_COUNTED_DEVICES`] devices (a capture of `any` sees a few; a
/// damaged one may name any number, each then looked up by name).
#[inline(never)]
fn device_counted(i: &mut Interface, ids: &mut IdCounts, device: u32) -> CountedChannel {
    if let Some(&(_, c)) = i.devices.iter().find(|(d, _)| *d == device) {
        return c;
    }
    let c = ids.counted_channel(&device_name(&i.name, device));
    if i.devices.len() < MAX_COUNTED_DEVICES {
        i.devices.push((device, c));
    }
    c
}

/// An EtherCAT frame's walk: its CoE messages kept, the others counted.
pub(super) fn walk_ethercat(frame: &[u8], time: Option<Timestamp>) -> EthercatPacket {
    let mut messages = Vec::new();
    let mut walked = ethercat::Walked::default();
    // What was walked before any damage still counts.
    let error = ethercat::walk_into(frame, &mut walked, |m| {
        messages.extend(CoeMessage::of(&m));
    })
    .err();
    EthercatPacket {
        time,
        walked,
        messages,
        error,
    }
}
