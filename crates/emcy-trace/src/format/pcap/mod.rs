//! pcap and pcapng capture files (tcpdump, dumpcap and Wireshark, scapy,
//! converters), read as a stream with the `pcap-parser` crate's block
//! readers.
//!
//! What is read: packets of the link types that carry Linux SocketCAN
//! frames, LINKTYPE_CAN_SOCKETCAN (227), LINUX_SLL (113) and LINUX_SLL2
//! (276), CAN classic and CAN FD (see `packet`). Every other packet (LIN
//! and other link types, other protocols behind a cooked header, CAN XL)
//! is skipped and counted. pcap: microsecond and nanosecond files in
//! either byte order, one channel, named [`CHANNEL`]. pcapng: every
//! section and interface; a packet's channel is its interface's `if_name`
//! (the interface's index in its section when it has none; `NAME:INDEX`
//! with the device's interface index for LINUX_SLL2 on an interface that
//! captures several devices, `any`), its time the
//! interface's `if_tsresol` units (powers of ten and of two) plus
//! `if_tsoffset` seconds, exactly (`clock`). Simple packet blocks have
//! no time; obsolete packet blocks are read like enhanced ones.
//!
//! Counting: each packet is one "line", numbered from 1 in file order as
//! Wireshark numbers its frames; the blocks that describe the capture
//! (section header, interface description, statistics, name resolution,
//! ...) are not lines. Bytes that cannot be read (a block whose length
//! is not sane, a truncated block) are one malformed line each, with the
//! byte offset in the message; reading goes on at the next block that is
//! one (pcapng: a known block type whose trailing length repeats its
//! length; pcap: two record headers in a row that fit).
//!
//! Link type 227 defines its id word as big-endian, but some writers
//! (scapy) store it little-endian. The first packets of that link type
//! decide which it is (see `packet::evidence`): they are held, at most
//! [`SAMPLE`] of them with what came between (bounded), until the order is
//! known: at once when one order makes no packet impossible and the other
//! two (a live capture is not held for 32 packets), else after the sample.
//! A note says when it is little-endian.
//!
//! Speed: frames on ids the caller does not want are only validated and
//! counted, in a hot loop ([`PcapReader::advance`] with an interest) that
//! reads the fixed fields of an enhanced packet block without options
//! itself; every other block, and every packet the caller wants, goes
//! through the crate's parsers.
//!
//! Memory is bounded by the buffer, which grows only as far as one block
//! (at most [`MAX_BLOCK`] bytes, a pcap record at most [`MAX_PACKET`]),
//! plus the held packets, whatever the file's size.

mod clock;
mod packet;

use std::collections::VecDeque;
use std::io::{self, Read};
use std::sync::{Arc, Mutex, PoisonError};

use pcap_parser::traits::{PcapNGPacketBlock, PcapReaderIterator};
use pcap_parser::{Block, LegacyPcapReader, PcapBlockOwned, PcapError, PcapNGReader};

use crate::ethercat::{self, CoeMessage, EthercatCounts, EthercatPacket};
use crate::read::read_full;
use crate::{Format, Frame, FrameSource, Interest, Next, Parsed, Reason, Timestamp};
use clock::Clock;
use packet::{CAN_SOCKETCAN, Can, Order, Packet, Shape};

/// The channel of every packet of a pcap file (it has one interface, and
/// no name for it): what a pcapng interface without a name is called too.
pub const CHANNEL: &str = "0";
/// Largest pcapng block read; longer ones are taken as corruption.
pub const MAX_BLOCK: usize = 16 * 1024 * 1024;
/// Largest pcap record read (libpcap's and Wireshark's largest snapshot
/// length); longer ones are taken as corruption.
pub const MAX_PACKET: usize = 262_144;
/// The buffer's size until a block needs more.
const BUFFER: usize = 256 * 1024;
/// Interfaces one pcapng section may describe.
const MAX_INTERFACES: usize = 65_536;
/// Link type 227 packets that decide the byte order of its id word.
pub const SAMPLE: u32 = 32;
/// Packets held (and their bytes) while the byte order is not known.
const MAX_HELD: usize = 4096;
const MAX_HELD_BYTES: usize = 1 << 20;
/// A 227 packet's bytes kept while it waits: the header and 64 data bytes.
const KEEP: usize = 72;
/// Plain frames counted in one [`PcapReader::advance`] at most.
const PLAIN_RUN: u64 = 1 << 16;

const SHB: [u8; 4] = [0x0A, 0x0D, 0x0D, 0x0A];
const BOM: u32 = 0x1A2B_3C4D;
const PCAP_MAGICS: [([u8; 4], Order, bool); 4] = [
    ([0xD4, 0xC3, 0xB2, 0xA1], Order::Little, false),
    ([0xA1, 0xB2, 0xC3, 0xD4], Order::Big, false),
    ([0x4D, 0x3C, 0xB2, 0xA1], Order::Little, true),
    ([0xA1, 0xB2, 0x3C, 0x4D], Order::Big, true),
];
/// The obsolete packet block (pcapng before 1.0).
const PACKET_BLOCK: u32 = 2;
/// The enhanced packet block.
const EPB: u32 = 6;
/// Block types a resync accepts: SHB, IDB, PB, SPB, NRB, ISB, EPB, SJE,
/// DSB, CB, DCB, PIB.
const KNOWN_BLOCKS: [u32; 12] = [
    0x0A0D_0D0A,
    1,
    2,
    3,
    4,
    5,
    6,
    9,
    0x0A,
    0x0BAD,
    0x4000_0BAD,
    0x8000_0001,
];

/// Whether `head` starts with the block type of a pcapng section header.
pub fn is_pcapng_block_type(head: &[u8]) -> bool {
    head.get(..4) == Some(SHB.as_slice())
}

/// The format whose magic `head` (at least 4 bytes; 12 for pcapng: its
/// block type, length and byte-order magic) starts with.
pub fn sniff(head: &[u8]) -> Option<Format> {
    let magic = head.get(..4)?;
    if PCAP_MAGICS.iter().any(|(m, _, _)| m == magic) {
        return Some(Format::Pcap);
    }
    (is_pcapng_block_type(head) && bom(head).is_some()).then_some(Format::Pcapng)
}

/// The byte order a section header's byte-order magic (bytes 8..12) says.
fn bom(shb: &[u8]) -> Option<Order> {
    [Order::Little, Order::Big]
        .into_iter()
        .find(|o| o.u32(shb, 8) == Some(BOM))
}

/// Bytes read from the input at once, into a page-aligned buffer.
const STAGE: usize = 128 * 1024;
const PAGE: usize = 4096;

/// The input, first the header bytes already read, then the rest; a read
/// error is kept for the caller (the crate only says "read error").
///
/// The rest is read into a page-aligned buffer of its own and copied from
/// there: the crate's buffer puts the unfinished block in front of each
/// read, so reads into it land anywhere in a page, and the kernel copies
/// out of the page cache into a misaligned buffer at a third of the speed
/// (measured: 0.15 s against 0.05 s of system time for 200 MB).
struct Tap<R> {
    head: io::Cursor<Vec<u8>>,
    input: R,
    error: Arc<Mutex<Option<io::Error>>>,
    stage: Vec<u8>,
    /// The stage's page-aligned part starts here.
    base: usize,
    /// Unread bytes of the stage: `base + at .. base + end`.
    at: usize,
    end: usize,
}

impl<R> Tap<R> {
    fn new(head: Vec<u8>, input: R, error: Arc<Mutex<Option<io::Error>>>) -> Tap<R> {
        let stage = vec![0u8; STAGE + PAGE];
        let base = stage.as_ptr().align_offset(PAGE).min(PAGE);
        Tap {
            head: io::Cursor::new(head),
            input,
            error,
            stage,
            base,
            at: 0,
            end: 0,
        }
    }
}

impl<R: Read> Read for Tap<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if (self.head.position() as usize) < self.head.get_ref().len() {
            return self.head.read(buf);
        }
        if self.at == self.end {
            let stage = self
                .stage
                .get_mut(self.base..self.base + STAGE)
                .unwrap_or_default();
            let n = loop {
                match self.input.read(stage) {
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        let message = e.to_string();
                        *self.error.lock().unwrap_or_else(PoisonError::into_inner) = Some(e);
                        return Err(io::Error::other(message));
                    }
                    Ok(n) => break n,
                }
            };
            self.at = 0;
            self.end = n;
        }
        let n = (self.end - self.at).min(buf.len());
        let from = self.base + self.at;
        if let (Some(dst), Some(src)) = (buf.get_mut(..n), self.stage.get(from..from + n)) {
            dst.copy_from_slice(src);
        }
        self.at += n;
        Ok(n)
    }
}

enum Stream<R: Read> {
    Legacy(LegacyPcapReader<Tap<R>>),
    Ng(PcapNGReader<Tap<R>>),
}

impl<R: Read> Stream<R> {
    fn it(&mut self) -> &mut dyn PcapReaderIterator {
        match self {
            Stream::Legacy(r) => r,
            Stream::Ng(r) => r,
        }
    }
}

/// A pcapng interface (or the one of a pcap file).
#[derive(Debug)]
struct Interface {
    linktype: u16,
    name: Box<[u8]>,
    /// It captures several devices: named `any`, or with no name of its
    /// own (pcap). Its LINUX_SLL2 frames are told apart by the device's
    /// interface index: channel `NAME:INDEX`.
    several: bool,
    clock: Clock,
    /// 0: no limit.
    snaplen: u32,
}

/// A packet's time as the file stores it.
#[derive(Clone, Copy)]
enum Ts {
    /// A simple packet block: none.
    None,
    Legacy {
        secs: u32,
        frac: u32,
    },
    Units(u64),
}

/// What one "line" is, owned.
#[derive(Debug)]
enum Item {
    Frame {
        iface: usize,
        /// The device's interface index (LINUX_SLL2 on an interface that
        /// captures several), part of the channel's name.
        device: Option<u32>,
        time: Option<Timestamp>,
        can: Can,
    },
    /// A valid frame the caller's interest does not want: counted only.
    Plain,
    /// An EtherCAT frame: not a CAN frame (a skipped line, or a malformed
    /// one when its walk failed), but maybe CoE messages.
    Ethercat {
        iface: usize,
        packet: Box<EthercatPacket>,
    },
    /// A link type 227 packet read before the byte order is known.
    Undecided {
        iface: usize,
        time: Option<Timestamp>,
        bytes: Box<[u8]>,
        reported: u32,
    },
    Skipped,
    Malformed(Reason),
}

impl<R: Read> FrameSource for PcapReader<R> {
    /// [`Format::Pcap`] or [`Format::Pcapng`].
    fn format(&self) -> Option<Format> {
        Some(self.format)
    }

    /// What [`PcapReader::advance`] read, in the order the caller must
    /// learn it: the notes it led to, then the frames it only counted
    /// (they came before the packet), then the packet, or the error or
    /// end it met.
    fn next_item(&mut self, interest: Option<&Interest>) -> io::Result<Option<Next<'_>>> {
        loop {
            if self.advanced.is_none() {
                self.advanced = Some(self.advance(interest));
            }
            if let Some(note) = self.take_note() {
                return Ok(Some(Next::Note(note)));
            }
            let skipped = self.take_quiet();
            let (counted, timed) = self.take_counted();
            if counted + skipped > 0 {
                let timed_n = timed.map_or(0, |(n, _, _)| n);
                return Ok(Some(Next::Counted(crate::Counted {
                    plain: counted.saturating_sub(timed_n),
                    timed,
                    skipped,
                })));
            }
            match self.advanced.take() {
                Some(Ok(true)) => {
                    if self.ready.is_some() {
                        return Ok(self.take().map(Next::Record));
                    }
                }
                Some(Err(e)) => return Err(e),
                Some(Ok(false)) | None => return Ok(None),
            }
        }
    }

    fn take_ethercat(&mut self) -> Option<(Box<EthercatPacket>, &[u8])> {
        PcapReader::take_ethercat(self)
    }

    fn ethercat_counts(&self) -> Option<EthercatCounts> {
        Some(PcapReader::ethercat_counts(self))
    }
}

/// What the hot loop made of a packet it counts.
#[derive(Clone, Copy)]
enum Hot {
    /// A CAN frame only counted, and timed if it has a [`RawTime`].
    Plain(Option<RawTime>),
    /// An EtherCAT frame without mailbox messages: a skipped line.
    Ethercat(ethercat::Walked),
}

/// What a block is to the caller.
enum Outcome {
    /// A line.
    Item(Item),
    /// A block that describes the capture: not a line.
    Nothing,
}

/// Whether a resync found the start of a block (or record).
enum Candidate {
    Yes,
    No,
    /// Needs this many bytes from the candidate's start to tell.
    More(usize),
}

/// What turns blocks into items: the section's byte order, its
/// interfaces, the byte order of link type 227.
struct Decoder {
    /// The file's byte order (pcap) or the current section's (pcapng).
    order: Order,
    /// pcap: nanosecond times.
    nanos: bool,
    interfaces: Vec<Interface>,
    /// The byte order of link type 227's id word, once known.
    socketcan: Option<Order>,
    notes: VecDeque<String>,
    /// A note about units finer than attoseconds was given.
    fine_noted: bool,
}

impl Decoder {
    /// The channel of interface `iface`: its name (empty when no
    /// interface description declares it).
    fn interface_name(&self, iface: usize) -> Box<[u8]> {
        self.interfaces
            .get(iface)
            .map_or_else(Box::default, |i| i.name.clone())
    }

    /// `NAME:INDEX`: a device seen through an interface that captures
    /// several (`any`).
    fn device_channel(&self, iface: usize, device: u32) -> Box<[u8]> {
        let mut name = self
            .interfaces
            .get(iface)
            .map_or_else(Vec::new, |i| i.name.to_vec());
        name.push(b':');
        name.extend_from_slice(itoa::Buffer::new().format(device).as_bytes());
        name.into()
    }

    fn time(&self, interface: &Interface, ts: Ts) -> Result<Option<Timestamp>, Reason> {
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
    fn packet(
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
            Packet::Plain => Item::Plain,
            Packet::Can(can) => match self.time(interface, ts) {
                Ok(time) => Item::Frame {
                    iface,
                    device: (interface.several && interface.linktype == packet::LINUX_SLL2)
                        .then(|| Order::Big.u32(data, 4))
                        .flatten(),
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

    /// What the hot loop makes of a packet (see [`packet::quick`]): a
    /// plain frame, a frame only timed (with its time, to be read when
    /// needed: it cannot fail), an EtherCAT frame with no mailbox message,
    /// or `None` for the general path.
    #[inline]
    fn quick(
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
            packet::Quick::Plain => Some(Hot::Plain(None)),
            packet::Quick::Timed => {
                let sure = match ts {
                    Ts::Legacy { .. } => true,
                    Ts::Units(_) => i.clock.infallible(),
                    Ts::None => false,
                };
                sure.then_some(Hot::Plain(Some(RawTime {
                    clock: i.clock,
                    ts,
                    nanos: self.nanos,
                })))
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
    fn block(&mut self, block: Block<'_>, at: u64, interest: Option<&Interest>) -> Outcome {
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
                self.interfaces.push(Interface {
                    linktype: (idb.linktype.0 & 0xFFFF) as u16,
                    name,
                    several,
                    clock,
                    snaplen: idb.snaplen,
                });
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
    fn block_at(&self, d: &[u8], end: bool) -> Candidate {
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
    fn record_at(&self, d: &[u8], end: bool) -> Candidate {
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

fn sane_block(len: usize) -> bool {
    (12..=MAX_BLOCK).contains(&len) && len.is_multiple_of(4)
}

/// What the crate's error means for a block whose bytes are all there.
fn describe(e: &PcapError<&[u8]>) -> String {
    match e {
        PcapError::NomError(_, kind) => format!("its content is not valid ({kind:?})"),
        PcapError::OwnedNomError(_, kind) => format!("its content is not valid ({kind:?})"),
        PcapError::Incomplete(_) | PcapError::BufferTooSmall | PcapError::UnexpectedEof => {
            "a field of it runs past its end".to_string()
        }
        other => other.to_string(),
    }
}

/// Reads a pcap or pcapng stream packet by packet.
pub struct PcapReader<R: Read> {
    stream: Stream<R>,
    /// The input's read error, kept by the [`Tap`].
    error: Arc<Mutex<Option<io::Error>>>,
    format: Format,
    /// The buffer's size (it grows for a long block).
    capacity: usize,
    decoder: Decoder,
    /// Link type 227 evidence so far: impossible read big-endian, read
    /// little-endian, packets that told.
    evidence: [u32; 2],
    sampled: u32,
    /// Items held while the byte order of link type 227 is not known, with
    /// the channel of each frame.
    held: VecDeque<(Item, Box<[u8]>)>,
    held_bytes: usize,
    /// The item [`PcapReader::take`] returns, and whether it was held (its
    /// channel is then in `channel`).
    ready: Option<(Item, bool)>,
    channel: Box<[u8]>,
    /// Packets only counted since the caller last asked, and all EtherCAT.
    counted: Counted,
    /// The EtherCAT frame [`PcapReader::take`] returned, for
    /// [`PcapReader::take_ethercat`].
    taken_ethercat: Option<Box<EthercatPacket>>,
    /// What the last [`PcapReader::advance`] returned, while the notes and
    /// counts it led to go out first ([`FrameSource::next_item`]).
    advanced: Option<io::Result<bool>>,
    /// The input ended (or failed: the error, returned after the held items).
    ended: bool,
    failed: Option<io::Error>,
}

impl<R: Read> PcapReader<R> {
    /// Reads the file header (pcap) or the first section header (pcapng).
    /// An error means this is not a readable pcap or pcapng file.
    pub fn new(mut input: R) -> io::Result<PcapReader<R>> {
        let invalid = |m: String| io::Error::new(io::ErrorKind::InvalidData, m);
        let mut head = vec![0u8; 12];
        let got = read_full(&mut input, head.get_mut(..4).unwrap_or_default())?;
        let magic = head.get(..4).unwrap_or_default();
        let error = Arc::new(Mutex::new(None));
        if let Some(&(_, order, nanos)) = PCAP_MAGICS.iter().find(|(m, _, _)| m == magic) {
            head.resize(24, 0);
            let got = 4 + read_full(&mut input, head.get_mut(4..).unwrap_or_default())?;
            if got < 24 {
                return Err(invalid(format!(
                    "pcap file header cut off after {got} of 24 bytes"
                )));
            }
            let linktype = order.u32(&head, 20).unwrap_or(0) & 0xFFFF;
            let tap = Tap::new(head, input, error.clone());
            let mut reader = LegacyPcapReader::new(BUFFER, tap)
                .map_err(|e| invalid(format!("pcap file header: {}", describe(&e))))?;
            // The first block is the file header.
            reader.consume(24);
            return Ok(PcapReader::with(
                Stream::Legacy(reader),
                error,
                Format::Pcap,
                BUFFER,
                Decoder {
                    order,
                    nanos,
                    interfaces: vec![Interface {
                        linktype: linktype as u16,
                        name: CHANNEL.as_bytes().into(),
                        several: true,
                        clock: Clock::default(),
                        snaplen: 0,
                    }],
                    socketcan: None,
                    notes: VecDeque::new(),
                    fine_noted: false,
                },
            ));
        }
        if got == 4 && is_pcapng_block_type(&head) {
            let got = 4 + read_full(&mut input, head.get_mut(4..12).unwrap_or_default())?;
            let Some(order) = bom(&head) else {
                return Err(invalid(if got < 12 {
                    format!("pcapng section header cut off after {got} bytes")
                } else {
                    "not a pcapng file: its section header has no byte-order magic".to_string()
                }));
            };
            let len = order.u32(&head, 4).unwrap_or(0) as usize;
            if !sane_block(len) || len < 28 {
                return Err(invalid(format!(
                    "pcapng section header of {len} bytes: not sane (28 to {MAX_BLOCK}, \
                     a multiple of 4)"
                )));
            }
            head.resize(len, 0);
            let got = 12 + read_full(&mut input, head.get_mut(12..).unwrap_or_default())?;
            if got < len {
                return Err(invalid(format!(
                    "pcapng section header cut off after {got} of {len} bytes"
                )));
            }
            let capacity = BUFFER.max(len);
            let tap = Tap::new(head, input, error.clone());
            let reader = PcapNGReader::new(capacity, tap)
                .map_err(|e| invalid(format!("pcapng section header: {}", describe(&e))))?;
            return Ok(PcapReader::with(
                Stream::Ng(reader),
                error,
                Format::Pcapng,
                capacity,
                Decoder {
                    order,
                    nanos: false,
                    interfaces: Vec::new(),
                    socketcan: None,
                    notes: VecDeque::new(),
                    fine_noted: false,
                },
            ));
        }
        let shown: Vec<String> = head
            .get(..got)
            .unwrap_or_default()
            .iter()
            .map(|b| format!("{b:02X}"))
            .collect();
        Err(invalid(format!(
            "not a pcap or pcapng file: it starts with {}",
            if shown.is_empty() {
                "nothing".to_string()
            } else {
                shown.join(" ")
            }
        )))
    }

    fn with(
        stream: Stream<R>,
        error: Arc<Mutex<Option<io::Error>>>,
        format: Format,
        capacity: usize,
        decoder: Decoder,
    ) -> Self {
        PcapReader {
            stream,
            error,
            format,
            capacity,
            decoder,
            evidence: [0; 2],
            sampled: 0,
            held: VecDeque::new(),
            held_bytes: 0,
            ready: None,
            channel: Box::default(),
            counted: Counted::default(),
            taken_ethercat: None,
            advanced: None,
            ended: false,
            failed: None,
        }
    }

    /// Something about the input worth telling the user, once each (a
    /// byte order other than the link type's, time units finer than a
    /// [`Timestamp`] holds). Ask after each [`PcapReader::advance`].
    pub fn take_note(&mut self) -> Option<String> {
        self.decoder.notes.pop_front()
    }

    /// The next packet (or unreadable run of bytes), classified;
    /// `Ok(None)` at the end. An error is an I/O error of the input (a
    /// corrupt gzip stream): reading stops.
    #[cfg(any(test, feature = "fuzzing"))]
    pub fn next_packet(&mut self) -> io::Result<Option<Parsed<'_>>> {
        if !self.advance(None)? {
            return Ok(None);
        }
        Ok(self.take())
    }

    /// Reads up to the next packet, which [`PcapReader::take`] then
    /// returns; `Ok(false)` at the end. Notes it leads to are ready for
    /// [`PcapReader::take_note`] before the packet is taken. With
    /// `interest`, valid frames it does not want are only counted, for
    /// [`PcapReader::take_counted`], up to the next other packet (or a
    /// long run of them: then there is no packet to take).
    pub fn advance(&mut self, interest: Option<&Interest>) -> io::Result<bool> {
        loop {
            if (self.decoder.socketcan.is_some() || self.ended)
                && let Some((item, channel)) = self.held.pop_front()
            {
                self.held_bytes = self.held_bytes.saturating_sub(held_size(&item, &channel));
                self.channel = channel;
                self.ready = Some((item, true));
                return Ok(true);
            }
            if self.ended {
                return match self.failed.take() {
                    Some(e) => Err(e),
                    None => Ok(false),
                };
            }
            // Held packets wait for their order: what follows them too.
            let interest = if self.held.is_empty() { interest } else { None };
            match self.read_item(interest) {
                // A long run of plain frames (counted by the reader).
                Ok(Some(Item::Plain)) => return Ok(true),
                Ok(Some(item)) => {
                    if self.held.is_empty() && !matches!(item, Item::Undecided { .. }) {
                        self.ready = Some((item, false));
                        return Ok(true);
                    }
                    self.hold(item);
                }
                Ok(None) => self.end(None),
                Err(e) => self.end(Some(e)),
            }
        }
    }

    /// How many frames [`PcapReader::advance`] only counted (they come
    /// before the packet it read), and how many of them, with which first
    /// and last time, it only timed (wanted ids whose data the interest's
    /// content filter rejects): `(counted, Some((timed, first, last)))`.
    /// The counts start again from 0.
    pub fn take_counted(&mut self) -> (u64, Option<(u64, Timestamp, Timestamp)>) {
        let timed = std::mem::take(&mut self.counted.timed);
        let last = timed.last.and_then(RawTime::get);
        let times = timed.first.zip(last).map(|(f, l)| (timed.n, f, l));
        (std::mem::take(&mut self.counted.plain), times)
    }

    /// EtherCAT frames [`PcapReader::advance`] only counted (they carried
    /// no mailbox message): skipped lines before the packet it read. The
    /// count starts again from 0.
    pub fn take_quiet(&mut self) -> u64 {
        std::mem::take(&mut self.counted.quiet)
    }

    /// The EtherCAT frame [`PcapReader::take`] just returned as skipped
    /// (or malformed), with its CoE messages and the channel they came on.
    pub fn take_ethercat(&mut self) -> Option<(Box<EthercatPacket>, &[u8])> {
        let packet = self.taken_ethercat.take()?;
        Some((packet, &self.channel))
    }

    /// EtherCAT seen so far: frames, mailbox messages, empty polls.
    pub fn ethercat_counts(&self) -> EthercatCounts {
        self.counted.ethercat
    }

    /// The packet [`PcapReader::advance`] read.
    pub fn take(&mut self) -> Option<Parsed<'_>> {
        self.taken_ethercat = None;
        let (item, held) = self.ready.take()?;
        if let Item::Ethercat { iface, packet } = item {
            self.counted.ethercat.add(packet.walked);
            if !held {
                self.channel = self.decoder.interface_name(iface);
            }
            let parsed = match &packet.error {
                Some(why) => Parsed::Malformed(why.clone()),
                None => Parsed::Skipped,
            };
            self.taken_ethercat = Some(packet);
            return Some(parsed);
        }
        if let Item::Frame {
            iface,
            device: Some(device),
            ..
        } = &item
            && !held
        {
            self.channel = self.decoder.device_channel(*iface, *device);
        }
        let channel: &[u8] = match &item {
            Item::Frame { device: None, .. } | Item::Undecided { .. } if !held => {
                let iface = match &item {
                    Item::Frame { iface, .. } | Item::Undecided { iface, .. } => *iface,
                    _ => 0,
                };
                self.decoder
                    .interfaces
                    .get(iface)
                    .map_or(&[][..], |i| &i.name)
            }
            _ => &self.channel,
        };
        let frame = |time: Option<Timestamp>, can: Can| Frame {
            time,
            channel,
            id: can.id,
            extended: can.extended,
            kind: can.kind,
            len: can.len,
            data: can.data,
        };
        Some(match item {
            Item::Frame { time, can, .. } => Parsed::Frame(frame(time, can)),
            Item::Undecided {
                time,
                bytes,
                reported,
                ..
            } => {
                let order = self.decoder.socketcan.unwrap_or(Order::Big);
                match packet::frame(CAN_SOCKETCAN, &bytes, reported, order, Shape::Guess, None) {
                    Packet::Can(can) => Parsed::Frame(frame(time, can)),
                    Packet::Malformed(why) => Parsed::Malformed(why),
                    Packet::NotCan | Packet::Plain | Packet::Undecided(_) => Parsed::Skipped,
                }
            }
            Item::Skipped | Item::Plain | Item::Ethercat { .. } => Parsed::Skipped,
            Item::Malformed(why) => Parsed::Malformed(why),
        })
    }

    fn end(&mut self, error: Option<io::Error>) {
        self.ended = true;
        self.failed = error;
        if self.decoder.socketcan.is_none() && !self.held.is_empty() {
            self.decide();
        }
    }

    /// Holds an item until the byte order of link type 227 is known.
    fn hold(&mut self, item: Item) {
        let channel: Box<[u8]> = match &item {
            Item::Frame {
                iface,
                device: Some(device),
                ..
            } => self.decoder.device_channel(*iface, *device),
            Item::Frame { iface, .. }
            | Item::Undecided { iface, .. }
            | Item::Ethercat { iface, .. } => self.decoder.interface_name(*iface),
            _ => Box::default(),
        };
        if let Item::Undecided { bytes, .. } = &item
            && let Some([big, little]) = packet::evidence(bytes)
        {
            self.evidence[0] += u32::from(big);
            self.evidence[1] += u32::from(little);
            self.sampled += 1;
        }
        self.held_bytes += held_size(&item, &channel);
        self.held.push_back((item, channel));
        let [big, little] = self.evidence;
        // Clear evidence decides at once, so that a live capture or a
        // followed file is not held for 32 packets: no impossible packet in
        // one order and at least two in the other.
        let clear = (big == 0 && little >= 2) || (little == 0 && big >= 2);
        if clear
            || self.sampled >= SAMPLE
            || self.held.len() >= MAX_HELD
            || self.held_bytes >= MAX_HELD_BYTES
        {
            self.decide();
        }
    }

    /// Fixes the byte order of link type 227 from the evidence: little-endian
    /// when fewer packets are impossible read little-endian than read
    /// big-endian and at least two are impossible read big-endian (one odd
    /// extended id proves nothing); big-endian, as the link type defines,
    /// otherwise.
    fn decide(&mut self) {
        let [big, little] = self.evidence;
        let order = if little < big && big >= 2 {
            Order::Little
        } else {
            Order::Big
        };
        self.decoder.socketcan = Some(order);
        if order == Order::Little {
            self.decoder.notes.push_back(format!(
                "the CAN ids of the CAN_SOCKETCAN packets are stored little-endian, not \
                 big-endian as the link type defines ({big} of the first {} packets read \
                 big-endian have flags or an id no CAN frame has, {little} read little-endian); \
                 read as little-endian",
                self.sampled
            ));
        }
    }

    /// The next item that is not a plain frame (those are counted in
    /// `plain`; [`Item::Plain`] when a long run of them ends the call).
    fn read_item(&mut self, interest: Option<&Interest>) -> io::Result<Option<Item>> {
        loop {
            self.hot(interest);
            if self.counted.run() >= PLAIN_RUN {
                return Ok(Some(Item::Plain));
            }
            let item = match self.stream {
                Stream::Legacy(_) => self.read_record(interest)?,
                Stream::Ng(_) => self.read_block(interest)?,
            };
            match item {
                Some(Item::Plain) => self.counted.plain += 1,
                // As the hot loop counts them.
                Some(Item::Ethercat { packet, .. }) if interest.is_some() && packet.quiet() => {
                    self.counted.add(Hot::Ethercat(packet.walked));
                }
                other => return Ok(other),
            }
        }
    }

    /// The hot loop: packets whole in the buffer, read by the crate's
    /// packet parsers directly, while they are plain frames (counted).
    /// Anything else (a packet the caller wants, another block, a block
    /// that is not whole or not sane) is left for the general path.
    fn hot(&mut self, interest: Option<&Interest>) {
        let Some(interest) = interest else {
            return;
        };
        let order = self.decoder.order;
        match &mut self.stream {
            Stream::Ng(reader) => loop {
                // An enhanced packet block without options, whole in the
                // buffer: its fixed fields are read here (the crate's
                // parser costs some 250 instructions a packet, most of the
                // time of a capture of small CAN packets). Any other block,
                // or anything unusual, goes to the general path and the
                // crate; the fuzz target checks both read alike.
                let data = reader.data();
                let Some(fixed) = data.first_chunk::<28>() else {
                    return;
                };
                let field = |at: usize| order.u32(fixed, at).unwrap_or(0);
                let (len, caplen) = (field(4) as usize, field(20) as usize);
                if field(0) != EPB
                    || caplen > MAX_PACKET
                    || len != 32 + caplen.next_multiple_of(4)
                    || order.u32(data, len - 4) != Some(len as u32)
                {
                    return;
                }
                let Some(packet) = data.get(28..28 + caplen) else {
                    return;
                };
                let units = u64::from(field(12)) << 32 | u64::from(field(16));
                let Some(hot) = self.decoder.quick(
                    field(8) as usize,
                    Ts::Units(units),
                    packet,
                    field(24),
                    interest,
                ) else {
                    return;
                };
                reader.consume_noshift(len);
                if !self.counted.add(hot) {
                    return;
                }
            },
            Stream::Legacy(reader) => loop {
                let data = reader.data();
                let Some(caplen) = order.u32(data, 8) else {
                    return;
                };
                let len = 16 + caplen as usize;
                if caplen as usize > MAX_PACKET || data.len() < len {
                    return;
                }
                let parsed = match order {
                    Order::Little => pcap_parser::parse_pcap_frame(data),
                    Order::Big => pcap_parser::parse_pcap_frame_be(data),
                };
                let Ok((_, b)) = parsed else {
                    return;
                };
                let ts = Ts::Legacy {
                    secs: b.ts_sec,
                    frac: b.ts_usec,
                };
                let Some(hot) = self.decoder.quick(0, ts, b.data, b.origlen, interest) else {
                    return;
                };
                reader.consume_noshift(len);
                if !self.counted.add(hot) {
                    return;
                }
            },
        }
    }

    /// The input's error, kept by the tap.
    fn take_error(&self) -> io::Error {
        self.error
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
            .unwrap_or_else(|| io::Error::other("read error"))
    }

    /// Makes `need` bytes available (growing the buffer to hold them);
    /// `Ok(false)` when the input ends first.
    fn fill(&mut self, need: usize) -> io::Result<bool> {
        loop {
            let it = self.stream.it();
            if it.data().len() >= need {
                return Ok(true);
            }
            if it.reader_exhausted() {
                return Ok(false);
            }
            if need > self.capacity {
                it.grow(need);
                self.capacity = need;
            }
            if it.refill().is_err() {
                return Err(self.take_error());
            }
        }
    }

    /// The rest of the input (fewer than `need` bytes) as one malformed line.
    fn cut_off(&mut self, what: &str, at: u64, need: usize) -> Option<Item> {
        let it = self.stream.it();
        let rest = it.data().len();
        if rest == 0 {
            return None;
        }
        it.consume_noshift(rest);
        Some(Item::Malformed(
            format!("the file ends inside {what} at byte {at} ({rest} of {need} bytes)").into(),
        ))
    }

    /// The next pcap record.
    fn read_record(&mut self, interest: Option<&Interest>) -> io::Result<Option<Item>> {
        let at = self.stream.it().consumed() as u64;
        if !self.fill(16)? {
            return Ok(self.cut_off("a packet record header", at, 16));
        }
        let header = self.stream.it().data();
        let caplen = self.decoder.order.u32(header, 8).unwrap_or(0) as usize;
        if caplen > MAX_PACKET {
            let skipped = self.resync()?;
            return Ok(Some(Item::Malformed(
                format!(
                    "packet record at byte {at} declares {caplen} captured bytes (at most \
                     {MAX_PACKET} are read): {skipped} bytes skipped to the next record"
                )
                .into(),
            )));
        }
        let need = 16 + caplen;
        if !self.fill(need)? {
            return Ok(self.cut_off("the packet", at, need));
        }
        let it = self.stream.it();
        let item = match it.next() {
            Ok((_, PcapBlockOwned::Legacy(b))) => self.decoder.packet(
                0,
                Ts::Legacy {
                    secs: b.ts_sec,
                    frac: b.ts_usec,
                },
                b.data,
                b.origlen,
                interest,
            ),
            Ok(_) => Item::Skipped,
            Err(e) => {
                Item::Malformed(format!("packet record at byte {at}: {}", describe(&e)).into())
            }
        };
        it.consume_noshift(need);
        Ok(Some(item))
    }

    /// The next pcapng block that is a line.
    fn read_block(&mut self, interest: Option<&Interest>) -> io::Result<Option<Item>> {
        loop {
            let at = self.stream.it().consumed() as u64;
            if !self.fill(12)? {
                return Ok(self.cut_off("a block header", at, 12));
            }
            let head = self.stream.it().data();
            let order = if is_pcapng_block_type(head) {
                match bom(head) {
                    Some(o) => o,
                    None => {
                        let skipped = self.resync()?;
                        return Ok(Some(Item::Malformed(
                            format!(
                                "section header at byte {at} without a byte-order magic: \
                                 {skipped} bytes skipped to the next block"
                            )
                            .into(),
                        )));
                    }
                }
            } else {
                self.decoder.order
            };
            let kind = order.u32(head, 0).unwrap_or(0);
            let len = order.u32(head, 4).unwrap_or(0) as usize;
            if !sane_block(len) {
                let skipped = self.resync()?;
                return Ok(Some(Item::Malformed(
                    format!(
                        "block of type 0x{kind:08X} at byte {at} declares {len} bytes (a multiple \
                         of 4 from 12 to {MAX_BLOCK} is read): {skipped} bytes skipped to the next \
                         block"
                    )
                    .into(),
                )));
            }
            if !self.fill(len)? {
                return Ok(self.cut_off(&format!("the block of type 0x{kind:08X}"), at, len));
            }
            let trailer = order.u32(self.stream.it().data(), len - 4).unwrap_or(0) as usize;
            if trailer != len {
                let skipped = self.resync()?;
                return Ok(Some(Item::Malformed(
                    format!(
                        "block of type 0x{kind:08X} at byte {at} declares {len} bytes but ends \
                         with {trailer}: {skipped} bytes skipped to the next block"
                    )
                    .into(),
                )));
            }
            let it = self.stream.it();
            let outcome = match it.next() {
                Ok((_, PcapBlockOwned::NG(block))) => self.decoder.block(block, at, interest),
                Ok(_) => Outcome::Nothing,
                Err(e) => Outcome::Item(Item::Malformed(
                    format!(
                        "block of type 0x{kind:08X} at byte {at} ({len} bytes): {}",
                        describe(&e)
                    )
                    .into(),
                )),
            };
            it.consume_noshift(len);
            if let Outcome::Item(item) = outcome {
                return Ok(Some(item));
            }
        }
    }

    /// Skips from the current position (at least one byte) to the next
    /// block or record that is one; returns the bytes skipped.
    fn resync(&mut self) -> io::Result<u64> {
        let mut skipped = 0u64;
        let mut from = 1;
        loop {
            let it = self.stream.it();
            let end = it.reader_exhausted();
            let data = it.data();
            let mut verdict = None;
            for p in from..data.len() {
                let rest = data.get(p..).unwrap_or_default();
                let candidate = match self.format {
                    Format::Pcap => self.decoder.record_at(rest, end),
                    _ => self.decoder.block_at(rest, end),
                };
                match candidate {
                    Candidate::No => {}
                    Candidate::Yes => {
                        verdict = Some((p, None));
                        break;
                    }
                    Candidate::More(need) => {
                        verdict = Some((p, Some(need)));
                        break;
                    }
                }
            }
            match verdict {
                Some((p, None)) => {
                    it.consume_noshift(p);
                    return Ok(skipped + p as u64);
                }
                Some((p, Some(need))) => {
                    it.consume_noshift(p);
                    skipped += p as u64;
                    from = 0;
                    self.fill(need)?;
                }
                None => {
                    let n = data.len();
                    it.consume_noshift(n);
                    skipped += n as u64;
                    from = 0;
                    if !self.fill(1)? {
                        return Ok(skipped);
                    }
                }
            }
        }
    }
}

/// A packet's time as stored, with what reads it.
#[derive(Clone, Copy)]
struct RawTime {
    clock: Clock,
    ts: Ts,
    nanos: bool,
}

impl RawTime {
    fn get(self) -> Option<Timestamp> {
        match self.ts {
            Ts::None => None,
            Ts::Legacy { secs, frac } => Some(clock::legacy(secs, frac, self.nanos)),
            Ts::Units(units) => self.clock.time(units),
        }
    }
}

/// Frames only timed: how many, the first time and the last (read only
/// when asked for).
#[derive(Clone, Copy, Default)]
struct Timed {
    n: u64,
    first: Option<Timestamp>,
    last: Option<RawTime>,
}

impl Timed {
    #[inline]
    fn count(&mut self, t: RawTime) {
        self.n += 1;
        if self.first.is_none() {
            self.first = t.get();
        }
        self.last = Some(t);
    }
}

/// Packets only counted since the caller last asked: plain frames (and,
/// of those, the ones only timed) and quiet EtherCAT frames (skipped
/// lines); and all EtherCAT seen.
#[derive(Default)]
struct Counted {
    plain: u64,
    timed: Timed,
    quiet: u64,
    ethercat: EthercatCounts,
}

impl Counted {
    /// One packet of the hot loop counted: a plain frame (timed, if it is
    /// one whose time the report wants) or a quiet EtherCAT frame; false
    /// once the run is long enough to hand back to the caller.
    #[inline]
    fn add(&mut self, hot: Hot) -> bool {
        match hot {
            Hot::Plain(time) => {
                self.plain += 1;
                if let Some(t) = time {
                    self.timed.count(t);
                }
            }
            Hot::Ethercat(walked) => {
                self.quiet += 1;
                self.ethercat.add(walked);
            }
        }
        self.run() < PLAIN_RUN
    }

    /// Packets counted and not yet asked for.
    fn run(&self) -> u64 {
        self.plain + self.quiet
    }
}

/// An EtherCAT frame's walk: its CoE messages kept, the others counted.
fn walk_ethercat(frame: &[u8], time: Option<Timestamp>) -> EthercatPacket {
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

fn held_size(item: &Item, channel: &[u8]) -> usize {
    let bytes = match item {
        Item::Undecided { bytes, .. } => bytes.len(),
        Item::Malformed(why) => why.len(),
        Item::Ethercat { packet, .. } => {
            std::mem::size_of::<CoeMessage>() * packet.messages.len()
                + packet.error.as_ref().map_or(0, |w| w.len())
        }
        _ => 0,
    };
    64 + channel.len() + bytes
}

/// A pcapng capture of `packet`, `copies` times, on one interface of
/// `linktype` (nanosecond times): what the `ethercat` fuzz target reads.
#[cfg(feature = "fuzzing")]
pub fn capture_of(linktype: u16, packet: &[u8], copies: u32) -> Vec<u8> {
    fn block(out: &mut Vec<u8>, kind: u32, body: &[u8]) {
        let padded = body.len().next_multiple_of(4);
        let len = (12 + padded) as u32;
        out.extend_from_slice(&kind.to_le_bytes());
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(body);
        out.resize(out.len() + padded - body.len(), 0);
        out.extend_from_slice(&len.to_le_bytes());
    }
    let mut out = Vec::new();
    let mut shb = BOM.to_le_bytes().to_vec();
    shb.extend_from_slice(&[1, 0, 0, 0]);
    shb.extend_from_slice(&(-1i64).to_le_bytes());
    block(&mut out, 0x0A0D_0D0A, &shb);
    let mut idb = u32::from(linktype).to_le_bytes().to_vec();
    idb.extend_from_slice(&0u32.to_le_bytes());
    // if_tsresol 9: nanoseconds.
    idb.extend_from_slice(&[9, 0, 1, 0, 9, 0, 0, 0, 0, 0, 0, 0]);
    block(&mut out, 1, &idb);
    for i in 0..copies {
        let units = 1_700_000_000_000_000_000u64 + u64::from(i) * 1_000_000;
        let mut epb = 0u32.to_le_bytes().to_vec();
        epb.extend_from_slice(&((units >> 32) as u32).to_le_bytes());
        epb.extend_from_slice(&(units as u32).to_le_bytes());
        epb.extend_from_slice(&(packet.len() as u32).to_le_bytes());
        epb.extend_from_slice(&(packet.len() as u32).to_le_bytes());
        epb.extend_from_slice(packet);
        block(&mut out, EPB, &epb);
    }
    out
}

/// Fuzz target body: any bytes must read to the end without a panic or an
/// endless loop, every frame well-formed, the buffers bounded.
#[cfg(feature = "fuzzing")]
pub fn fuzz_pcap(data: &[u8]) {
    use crate::{FrameKind, Payload};
    let Ok(mut r) = PcapReader::new(data) else {
        return;
    };
    let mut packets = 0usize;
    let timed = r.format == Format::Pcap;
    while let Ok(Some(parsed)) = r.next_packet() {
        packets += 1;
        // Every line consumes at least one byte of input.
        assert!(packets <= data.len(), "no progress");
        if let Parsed::Frame(f) = parsed {
            assert!(usize::from(f.len) <= Payload::MAX);
            match f.kind {
                FrameKind::Data => {
                    assert!(f.len <= 8);
                    assert_eq!(f.data.len(), usize::from(f.len));
                }
                FrameKind::Fd => assert_eq!(f.data.len(), usize::from(f.len)),
                FrameKind::Remote => assert!(f.data.is_empty()),
                FrameKind::Error => assert!(f.extended && f.id & 0x2000_0000 != 0),
            }
            if f.kind != FrameKind::Error {
                assert!(f.id <= if f.extended { 0x1FFF_FFFF } else { 0x7FF });
            }
            assert!(!f.channel.is_empty());
            if timed {
                assert!(f.time.is_some());
            }
        }
        assert!(r.held.len() <= MAX_HELD);
    }
    assert!(r.capacity <= MAX_BLOCK.max(BUFFER) + 32);
    while r.take_note().is_some() {}

    // Read again with the EMCY ids as the interest: the frames it does not
    // want are only counted, everything else comes out as without it.
    let mut interest = Interest::none();
    interest.add_standard_range(0x81..=0xFF);
    let wanted = |p: &Parsed<'_>| match p {
        Parsed::Frame(f) => f.kind == FrameKind::Data && interest.wants(f.id, f.extended),
        _ => true,
    };
    // What a packet shows (an EtherCAT frame's messages are part of it),
    // pushed with the count of plain ones before it; plain ones (and quiet
    // EtherCAT frames, only counted under an interest) only counted.
    let classify = |r: &mut PcapReader<&[u8]>,
                    want: bool,
                    text: String,
                    seen: &mut Vec<(u64, String)>,
                    plain: &mut u64| {
        let ethercat = r
            .take_ethercat()
            .map(|(e, channel)| (e.quiet(), format!("{e:?} on {channel:?}")));
        let shown = match ethercat {
            Some((true, _)) => None,
            Some((false, e)) => Some(format!("{text} {e}")),
            None => want.then_some(text),
        };
        match shown {
            Some(shown) => seen.push((std::mem::take(plain), shown)),
            None => *plain += 1,
        }
    };
    let shown = |p: &Parsed<'_>| format!("{p:?}");
    let mut full = PcapReader::new(data).expect("read once");
    let mut expected = Vec::new();
    let mut plain = 0u64;
    while let Ok(Some(p)) = full.next_packet() {
        let (want, text) = (wanted(&p), shown(&p));
        classify(&mut full, want, text, &mut expected, &mut plain);
    }
    let mut fast = PcapReader::new(data).expect("read once");
    let mut got = Vec::new();
    let mut counted = 0u64;
    while let Ok(more) = fast.advance(Some(&interest)) {
        counted += fast.take_counted().0 + fast.take_quiet();
        if !more {
            break;
        }
        // Held packets (link type 227 before its byte order is known)
        // come out whole: the caller's own check makes them plain (and
        // the quiet EtherCAT frames among them).
        if let Some(p) = fast.take() {
            let (want, text) = (wanted(&p), shown(&p));
            classify(&mut fast, want, text, &mut got, &mut counted);
        }
    }
    counted += fast.take_counted().0 + fast.take_quiet();
    assert_eq!(
        fast.ethercat_counts(),
        full.ethercat_counts(),
        "the same EtherCAT counts with and without the interest"
    );
    assert_eq!(
        got, expected,
        "the same packets with and without the interest"
    );
    assert_eq!(
        counted, plain,
        "the same plain frames after the last packet"
    );
}

#[cfg(test)]
mod tests;
