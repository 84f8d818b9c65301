//! The reader's limits and magic numbers, and the checks on them that
//! several parts share.

use super::packet::Order;

/// The channel of every packet of a pcap file (it has one interface, and
/// no name for it): what a pcapng interface without a name is called too.
pub const CHANNEL: &str = "0";
/// Largest pcapng block read; longer ones are taken as corruption.
pub const MAX_BLOCK: usize = 16 * 1024 * 1024;
/// Largest pcap record read (libpcap's and Wireshark's largest snapshot
/// length); longer ones are taken as corruption.
pub const MAX_PACKET: usize = 262_144;
/// The buffer's size until a block needs more.
pub(super) const BUFFER: usize = 256 * 1024;
/// Interfaces one pcapng section may describe.
pub(super) const MAX_INTERFACES: usize = 65_536;
/// Devices of an interface that captures several whose counted frames'
/// channel is kept (see `decode::device_counted`).
pub(super) const MAX_COUNTED_DEVICES: usize = 64;
/// Link type 227 packets that decide the byte order of its id word.
pub const SAMPLE: u32 = 32;
/// Packets held (and their bytes) while the byte order is not known.
pub(super) const MAX_HELD: usize = 4096;
pub(super) const MAX_HELD_BYTES: usize = 1 << 20;
/// A 227 packet's bytes kept while it waits: the header and 64 data bytes.
pub(super) const KEEP: usize = 72;
/// Plain frames counted in one [`PcapReader::advance`] at most.
pub(super) const PLAIN_RUN: u64 = 1 << 16;

pub(super) const SHB: [u8; 4] = [0x0A, 0x0D, 0x0D, 0x0A];
pub(super) const BOM: u32 = 0x1A2B_3C4D;
pub(super) const PCAP_MAGICS: [([u8; 4], Order, bool); 4] = [
    ([0xD4, 0xC3, 0xB2, 0xA1], Order::Little, false),
    ([0xA1, 0xB2, 0xC3, 0xD4], Order::Big, false),
    ([0x4D, 0x3C, 0xB2, 0xA1], Order::Little, true),
    ([0xA1, 0xB2, 0x3C, 0x4D], Order::Big, true),
];
/// The obsolete packet block (pcapng before 1.0).
pub(super) const PACKET_BLOCK: u32 = 2;
/// The enhanced packet block.
pub(super) const EPB: u32 = 6;
/// Block types a resync accepts: SHB, IDB, PB, SPB, NRB, ISB, EPB, SJE,
/// DSB, CB, DCB, PIB.
pub(super) const KNOWN_BLOCKS: [u32; 12] = [
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

/// The byte order a section header's byte-order magic (bytes 8..12) says.
pub(super) fn bom(shb: &[u8]) -> Option<Order> {
    [Order::Little, Order::Big]
        .into_iter()
        .find(|o| o.u32(shb, 8) == Some(BOM))
}

/// The byte order and time unit (nanoseconds or not) of a pcap file header
/// at `head`: one of the magics, then version 2.4 or older 2.x, as every
/// writer since libpcap 0.4 puts there. A record whose time happened to
/// match a magic has a fraction of a second where the version is.
pub(super) fn file_header(head: &[u8]) -> Option<(Order, bool)> {
    let magic = head.get(..4)?;
    let &(_, order, nanos) = PCAP_MAGICS.iter().find(|(m, _, _)| m == magic)?;
    (order.u16(head, 4)? == 2 && order.u16(head, 6)? <= 4).then_some((order, nanos))
}

pub(super) fn sane_block(len: usize) -> bool {
    (12..=MAX_BLOCK).contains(&len) && len.is_multiple_of(4)
}
