//! What every reader yields: a [`Frame`], its [`FrameKind`] and its
//! [`Payload`].

use std::fmt;

use crate::{FrameKey, Timestamp};

/// What kind of frame a line carries. Only `Data` frames can be EMCY.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FrameKind {
    /// Classic CAN data frame, 0..=8 bytes.
    Data,
    /// Remote transmission request; carries no data.
    Remote,
    /// Error frame; `id` holds the error class bits and `data` the bytes of
    /// linux/can/error.h, whatever the format ([`crate::error_frame`]).
    Error,
    /// CAN FD frame, 0..=64 bytes.
    Fd,
}

/// Up to 64 payload bytes. Classic frames (all that EMCY and NMT use) stay
/// inline; CAN FD data past 8 bytes goes to the heap. Frames are moved on
/// the hot path, so this keeps them small; FD data is decoded only for the
/// ids a caller asked for.
#[derive(Clone, PartialEq, Eq)]
pub struct Payload {
    inline: [u8; 8],
    len: u8,
    long: Option<Box<[u8; 64]>>,
}

impl Payload {
    /// The most bytes a payload holds (a CAN FD frame's).
    pub const MAX: usize = 64;

    /// No bytes.
    pub const fn new() -> Payload {
        Payload {
            inline: [0; 8],
            len: 0,
            long: None,
        }
    }

    /// The bytes of a payload of at most 8 as one word (first byte lowest,
    /// zeros after the last), and how many.
    #[inline]
    pub fn word(&self) -> Option<(u64, u8)> {
        if self.long.is_some() || self.len > 8 {
            return None;
        }
        let keep = u64::MAX
            .checked_shr(8 * (8 - u32::from(self.len)))
            .unwrap_or(0);
        Some((u64::from_le_bytes(self.inline) & keep, self.len))
    }

    /// The first `len` (at most 8) of `bytes`.
    #[inline]
    pub fn inline(bytes: [u8; 8], len: u8) -> Payload {
        Payload {
            inline: bytes,
            len: len.min(8),
            long: None,
        }
    }

    /// Appends a byte; `false` (and nothing stored) when already full.
    #[inline]
    pub fn push(&mut self, b: u8) -> bool {
        let i = usize::from(self.len);
        if i < self.inline.len() && self.long.is_none() {
            self.inline[i] = b;
        } else if i < Self::MAX {
            let long = self.long.get_or_insert_with(|| {
                let mut all = Box::new([0u8; 64]);
                all[..8].copy_from_slice(&self.inline);
                all
            });
            long[i] = b;
        } else {
            return false;
        }
        self.len += 1;
        true
    }

    /// The bytes of `data`; `None` when more than [`Payload::MAX`].
    pub fn from_slice(data: &[u8]) -> Option<Payload> {
        let mut p = Payload::new();
        for &b in data {
            if !p.push(b) {
                return None;
            }
        }
        Some(p)
    }

    /// The bytes.
    pub fn as_slice(&self) -> &[u8] {
        let n = usize::from(self.len);
        match &self.long {
            Some(all) => &all[..n],
            None => &self.inline[..n.min(8)],
        }
    }

    /// How many bytes.
    #[cfg(any(test, feature = "fuzzing"))]
    pub fn len(&self) -> usize {
        usize::from(self.len)
    }

    /// Whether there are none.
    #[cfg(any(test, feature = "fuzzing"))]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl Default for Payload {
    fn default() -> Self {
        Payload::new()
    }
}

impl fmt::Debug for Payload {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Payload({})", HexBytes(self.as_slice()))
    }
}

/// Formats bytes as contiguous uppercase hex (`1043080100000000`).
pub struct HexBytes<'a>(pub &'a [u8]);

impl fmt::Display for HexBytes<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for b in self.0 {
            write!(f, "{b:02X}")?;
        }
        Ok(())
    }
}

/// One CAN frame read from a trace line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame<'a> {
    /// Seconds as the trace wrote them; `None` when the trace has no times
    /// (candump screen output without `-t`) or the frame was not of interest.
    pub time: Option<Timestamp>,
    /// Interface (candump) or channel number (ASC) exactly as written.
    pub channel: &'a [u8],
    /// 11- or 29-bit identifier (for error frames, the error class bits).
    /// An error frame's data is always filled, whatever the interest.
    pub id: u32,
    /// 29-bit identifier. For candump this follows the digit count, not the value.
    pub extended: bool,
    /// Data, remote, error or CAN FD.
    pub kind: FrameKind,
    /// Number of data bytes the frame carries (0 for remote frames).
    pub len: u8,
    /// The data bytes; filled only for frames the caller's [`Interest`](crate::Interest)
    /// covers (id-first filtering: other frames are validated, not decoded).
    pub data: Payload,
}

impl<'a> Frame<'a> {
    /// What the frame is counted under ([`IdCounts`](crate::IdCounts)).
    #[inline]
    pub fn key(&self) -> FrameKey<'a> {
        FrameKey {
            channel: self.channel,
            id: self.id,
            extended: self.extended,
        }
    }

    /// An error frame as the text formats write one: no class bits, no data.
    pub fn error(time: Option<Timestamp>, channel: &'a [u8]) -> Frame<'a> {
        Frame {
            time,
            channel,
            id: 0,
            extended: false,
            kind: FrameKind::Error,
            len: 0,
            data: Payload::new(),
        }
    }
}

/// A channel a binary format gives as a number (BLF, MF4), kept as the
/// decimal text a [`Frame`] borrows: no allocation per frame.
#[derive(Clone, Copy, Default)]
pub struct NumberedChannel {
    text: [u8; 20],
    len: usize,
}

impl NumberedChannel {
    /// Sets the number and gives its text.
    pub fn name(&mut self, n: u64) -> &[u8] {
        let mut b = itoa::Buffer::new();
        let text = b.format(n).as_bytes();
        let n = text.len().min(self.text.len());
        if let (Some(dst), Some(src)) = (self.text.get_mut(..n), text.get(..n)) {
            dst.copy_from_slice(src);
        }
        self.len = n;
        self.text.get(..n).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payload_holds_64_bytes_and_refuses_more() {
        let mut p = Payload::new();
        for i in 0..64 {
            assert!(p.push(i as u8));
            assert_eq!(p.as_slice(), (0..=i).map(|b| b as u8).collect::<Vec<_>>());
        }
        assert!(!p.push(0));
        assert_eq!(p.len(), 64);
        assert!(Payload::from_slice(&[0; 65]).is_none());
        assert_eq!(
            Payload::from_slice(&[1, 2, 3]).unwrap().as_slice(),
            [1, 2, 3]
        );
    }

    #[test]
    fn frames_stay_small_enough_to_move_in_registers() {
        assert!(
            std::mem::size_of::<Frame<'_>>() <= 96,
            "{}",
            std::mem::size_of::<Frame<'_>>()
        );
    }
}
