//! What one packet (a "line") is once read, and what it is read with.

use crate::ethercat::EthercatPacket;
use crate::id_counts::CountedChannel;
use crate::{Reason, Timestamp};

use super::clock::Clock;
use super::packet::{Can, Ident, LINUX_SLL2};

/// A pcapng interface (or the one of a pcap file).
#[derive(Debug)]
pub(super) struct Interface {
    pub(super) linktype: u16,
    pub(super) name: Box<[u8]>,
    /// It captures several devices: named `any`, or with no name of its
    /// own (pcap). Its LINUX_SLL2 frames are told apart by the device's
    /// interface index: channel `NAME:INDEX`.
    pub(super) several: bool,
    pub(super) clock: Clock,
    /// 0: no limit.
    pub(super) snaplen: u32,
    /// Where the frames only counted on it are counted, once one was: its
    /// own channel, and its first devices' (see `several`).
    pub(super) counted: CountedChannel,
    pub(super) devices: Vec<(u32, CountedChannel)>,
}

impl Interface {
    pub(super) fn new(
        linktype: u16,
        name: Box<[u8]>,
        several: bool,
        clock: Clock,
        snaplen: u32,
    ) -> Interface {
        Interface {
            linktype,
            name,
            several,
            clock,
            snaplen,
            counted: CountedChannel::Unknown,
            devices: Vec::new(),
        }
    }

    /// Its frames' channel names the device (see `several`).
    #[inline]
    pub(super) fn by_device(&self) -> bool {
        self.several && self.linktype == LINUX_SLL2
    }

    /// Where its frames only counted are counted, when the interface
    /// alone says it: [`CountedChannel::Unknown`] before its first, and
    /// for the devices of one that captures several.
    #[inline]
    pub(super) fn counted(&self) -> CountedChannel {
        if self.by_device() {
            CountedChannel::Unknown
        } else {
            self.counted
        }
    }
}

/// A packet's time as the file stores it.
#[derive(Clone, Copy, Debug)]
pub(super) enum Ts {
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
pub(super) enum Item {
    Frame {
        iface: usize,
        /// The device's interface index (LINUX_SLL2 on an interface that
        /// captures several), part of the channel's name.
        device: Option<u32>,
        time: Option<Timestamp>,
        can: Can,
    },
    /// A valid frame the caller's interest does not want: counted only,
    /// under the channel and identifier its frame would have.
    Plain {
        iface: usize,
        /// Its time as stored (read only if it is the input's first or
        /// last frame).
        ts: Ts,
        device: Option<u32>,
        ident: Ident,
    },
    /// A long run of plain frames, counted: no packet this time.
    Run,
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
