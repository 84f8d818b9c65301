//! The frames the hot loop only counts, and when they were.

use crate::ethercat::{self, EthercatCounts};
use crate::id_counts::CountedChannel;
use crate::{IdCounts, Timestamp};

use super::clock::{self, Clock};
use super::consts::PLAIN_RUN;
use super::items::Ts;
use super::packet::Ident;

/// What the hot loop made of a packet it counts.
#[derive(Clone, Copy)]
pub(super) enum Hot {
    /// A CAN frame only counted, with where it is counted when its
    /// interface alone says it (else [`CountedChannel::Unknown`]), and
    /// timed if it has a [`RawTime`].
    Plain(Ident, CountedChannel, Option<RawTime>),
    /// An EtherCAT frame without mailbox messages: a skipped line.
    Ethercat(ethercat::Walked),
}

/// A packet's time as stored, with what reads it.
#[derive(Clone, Copy)]
pub(super) struct RawTime {
    pub(super) clock: Clock,
    pub(super) ts: Ts,
    pub(super) nanos: bool,
}

impl RawTime {
    pub(super) fn get(self) -> Option<Timestamp> {
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
pub(super) struct Timed {
    pub(super) n: u64,
    pub(super) first: Option<Timestamp>,
    pub(super) last: Option<RawTime>,
}

impl Timed {
    #[inline]
    pub(super) fn count(&mut self, t: RawTime) {
        self.n += 1;
        if self.first.is_none() {
            self.first = t.get();
        }
        self.last = Some(t);
    }
}

/// Packets only counted since the caller last asked: plain frames (and,
/// of those, the ones only timed) and quiet EtherCAT frames (skipped
/// lines); and all EtherCAT seen, and every plain frame by channel and
/// identifier.
#[derive(Default)]
pub(super) struct Counted {
    pub(super) plain: u64,
    /// Every plain frame so far ([`crate::FrameSource::counted_ids`]).
    pub(super) ids: IdCounts,
    pub(super) timed: Timed,
    /// The input's first and last plain frames' interfaces and times as
    /// stored (read only when asked for): the input's span.
    pub(super) span: Option<((usize, Ts), (usize, Ts))>,
    pub(super) quiet: u64,
    pub(super) ethercat: EthercatCounts,
}

impl Counted {
    /// One packet of the hot loop counted: a plain frame (timed, if it is
    /// one whose time the report wants) or a quiet EtherCAT frame; false
    /// once the run is long enough to hand back to the caller.
    #[inline]
    pub(super) fn add(&mut self, hot: Hot) -> bool {
        match hot {
            Hot::Plain(_, _, time) => {
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

    /// A plain frame's interface and time as stored: two stores a packet
    /// (timing every one as [`Timed`] does cost pcapng 16% more
    /// instructions).
    #[inline]
    pub(super) fn saw(&mut self, iface: usize, ts: Ts) {
        match &mut self.span {
            Some((_, last)) => *last = (iface, ts),
            None => self.span = Some(((iface, ts), (iface, ts))),
        }
    }

    /// A plain frame's channel and identifier.
    #[inline]
    pub(super) fn count(&mut self, channel: CountedChannel, ident: Ident) {
        self.ids.count_in(channel, ident.id, ident.extended);
    }

    /// Packets counted and not yet asked for.
    pub(super) fn run(&self) -> u64 {
        self.plain + self.quiet
    }
}
