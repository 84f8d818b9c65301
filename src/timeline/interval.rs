//! Where in a trace something happened, and the error intervals a node's
//! timeline closes: the vocabulary every per-node state machine shares.

use crate::canopen::register::Register;
use crate::trace::{Span, Timestamp};

/// How an error interval ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ClearedBy {
    /// Code 0x0000 with register 0x00 (transition 4).
    Reset,
    /// Code 0x0000 whose register no longer shows the error's class bit (transition 2).
    PartialReset,
    /// The node sent an NMT boot-up: it restarted.
    Boot,
    /// A reset frame named the error status bit the error was raised with
    /// (CANopenNode: exact, where register inference cannot be).
    StatusBit,
}

impl ClearedBy {
    /// The stable name in JSON (`partial_reset`).
    pub fn slug(self) -> &'static str {
        match self {
            ClearedBy::Reset => "reset",
            ClearedBy::PartialReset => "partial_reset",
            ClearedBy::Boot => "boot",
            ClearedBy::StatusBit => "status_bit",
        }
    }
}

/// Where in the trace something happened.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct At {
    /// The frame's time, as the trace wrote it.
    pub time: Option<Timestamp>,
    /// Its 1-based line.
    pub line: u64,
}

#[cfg(test)]
impl At {
    /// `ms` milliseconds after the epoch (three fraction digits), at `line`:
    /// the place of a test's frame.
    pub(crate) fn ms(ms: u64, line: u64) -> At {
        At {
            time: Some(Timestamp::from_parts(ms / 1000, ms % 1000, 3)),
            line,
        }
    }
}

/// One error from the EMCY that raised it to the frame that cleared it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Interval {
    /// Raise order within the node (0, 1, 2, ...): the order reports list errors in.
    pub seq: u64,
    /// The error code.
    pub code: u16,
    /// The EMCY that raised it.
    pub start: At,
    /// The frame that cleared it; `None` while active.
    pub end: Option<At>,
    /// What cleared it; `None` while active.
    pub cleared_by: Option<ClearedBy>,
    /// The error register sent with the raising EMCY: the class bit that must
    /// later drop for a partial reset to be attributed to this error.
    pub raised_register: Register,
    /// The error status bit it was raised with, under a profile that tracks them.
    pub status_bit: Option<u8>,
}

impl Interval {
    /// How long the error lasted: from the raising EMCY to the frame that
    /// cleared it, at the finer precision of the two; negative when the
    /// trace's clock went backwards. `None` while active or without times.
    pub fn duration(&self) -> Option<Span> {
        Some(self.end?.time?.since(self.start.time?))
    }
}

/// SDO transfers are followed in frames' [`At`]s: the time for their
/// timeout, the line to tell.
impl crate::canopen::sdo::transfer::Moment for At {
    fn time(&self) -> Option<Timestamp> {
        self.time
    }
}
