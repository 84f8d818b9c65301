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
mod consts;
mod counted;
mod decode;
#[cfg(feature = "fuzzing")]
mod fuzzing;
mod items;
mod packet;
mod reader;
mod stream;

use crate::Format;
use consts::{PCAP_MAGICS, bom};

pub use consts::{CHANNEL, MAX_BLOCK, MAX_PACKET, SAMPLE, is_pcapng_block_type};
#[cfg(feature = "fuzzing")]
pub use fuzzing::{capture_of, fuzz_pcap};
pub use reader::PcapReader;

/// The format whose magic `head` (at least 4 bytes; 12 for pcapng: its
/// block type, length and byte-order magic) starts with.
pub fn sniff(head: &[u8]) -> Option<Format> {
    let magic = head.get(..4)?;
    if PCAP_MAGICS.iter().any(|(m, _, _)| m == magic) {
        return Some(Format::Pcap);
    }
    (is_pcapng_block_type(head) && bom(head).is_some()).then_some(Format::Pcapng)
}

#[cfg(test)]
mod tests;
