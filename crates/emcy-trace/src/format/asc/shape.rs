//! The fast path's shape of a canonical classic line, and the layout of
//! the last one, which the next line is compared with.

use crate::{Frame, FrameKey, FrameKind, Payload, Timestamp, trim_end, trim_start};
use crate::{hex, scan};

/// Where the fields of a canonical classic line are.
#[derive(Debug, PartialEq, Eq)]
pub(super) struct AscShape {
    pub(super) time: Timestamp,
    pub(super) channel: std::ops::Range<usize>,
    pub(super) id: u32,
    pub(super) extended: bool,
    pub(super) dlc: u8,
    pub(super) data_start: usize,
    /// Where the time's first digit, its dot and its end, the id, the
    /// direction and the DLC are: what the next line's layout is made of.
    pub(super) places: Places,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Places {
    pub(super) time: usize,
    pub(super) dot: usize,
    pub(super) time_end: usize,
    pub(super) id: usize,
    pub(super) dir: usize,
    pub(super) dlc: usize,
}

/// The fixed part of the last canonical line: the right-aligned time's
/// width, the channel, the id column's width, `Rx   d `. Nearly every line
/// of a file has them, so a line is compared with the last one's, a few
/// words, before the general scan. Accepts exactly what the general scan
/// accepts at these places.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct AscLayout {
    pub(super) at: Places,
    /// The blanks before the time, exactly (none when it starts the line).
    pub(super) lead: Option<scan::Fixed>,
    pub(super) digits: scan::Decimal,
    /// Blanks, channel, blanks: from the time's end to the id.
    pub(super) gap: scan::Fixed,
    /// The channel's start and length (inside `gap`).
    pub(super) channel: (usize, usize),
    /// From the direction to the DLC: `Rx   d `.
    pub(super) mid: scan::Fixed,
}

impl AscLayout {
    pub(super) fn of(line: &[u8], s: &AscShape) -> Option<AscLayout> {
        let at = s.places;
        Some(AscLayout {
            at,
            lead: match at.time {
                0 => None,
                n => Some(scan::Fixed::of(line, 0, n)?),
            },
            digits: scan::Decimal::new(at.time, at.dot, at.time_end)?,
            gap: scan::Fixed::of(line, at.time_end, at.id - at.time_end)?,
            channel: (s.channel.start, s.channel.len()),
            mid: scan::Fixed::of(line, at.dir, at.dlc - at.dir)?,
        })
    }
}

impl AscShape {
    /// What the line's frame is counted under.
    #[inline]
    pub(super) fn key<'a>(&self, line: &'a [u8]) -> FrameKey<'a> {
        FrameKey {
            channel: line.get(self.channel.clone()).unwrap_or_default(),
            id: self.id,
            extended: self.extended,
        }
    }

    /// The frame of the line the shape was taken from; data bytes are
    /// converted only when `wanted`.
    #[inline]
    pub(super) fn frame<'a>(&self, line: &'a [u8], wanted: bool) -> Option<Frame<'a>> {
        let mut frame = Frame {
            time: Some(self.time),
            channel: line.get(self.channel.clone())?,
            id: self.id,
            extended: self.extended,
            kind: FrameKind::Data,
            len: self.dlc,
            data: Payload::new(),
        };
        if wanted {
            for k in 0..usize::from(self.dlc) {
                let at = self.data_start + 3 * k;
                frame
                    .data
                    .push(hex::parse_byte(*line.get(at + 1)?, *line.get(at + 2)?)?);
            }
        }
        Some(frame)
    }
}

/// A hex id of 1-8 digits at `at`, `x` after it for extended: the id, its
/// kind and where it ends; `None` when out of range.
#[inline]
pub(super) fn id_field(line: &[u8], at: usize) -> Option<(u32, bool, usize)> {
    let len = scan::hex_run(line, at);
    if len == 0 || len > 8 {
        return None;
    }
    let id = hex::parse_u32(line.get(at..at + len)?)?;
    let mut end = at + len;
    let extended = line.get(end) == Some(&b'x');
    if extended {
        end += 1;
    }
    if id > if extended { 0x1FFF_FFFF } else { 0x7FF } {
        return None;
    }
    Some((id, extended, end))
}

/// Index after at least one blank following `at`; `None` when there is none.
#[inline]
pub(super) fn blanks_after(line: &[u8], at: usize) -> Option<usize> {
    let n = scan::blank_run(line, at);
    (n > 0).then_some(at + n)
}

/// Nothing, or the bit-timing tail `Length = n BitCount = n ID = n[x]`.
#[inline]
pub(super) fn canonical_tail(rest: &[u8]) -> bool {
    let t = trim_end(rest);
    if t.is_empty() {
        return true;
    }
    let Some(t) = trim_start(t).strip_prefix(b"Length = ") else {
        return false;
    };
    let n = scan::digit_run(t, 0);
    let Some(t) = t.get(n..).and_then(|t| t.strip_prefix(b" BitCount = ")) else {
        return false;
    };
    let m = scan::digit_run(t, 0);
    let Some(t) = t.get(m..).and_then(|t| t.strip_prefix(b" ID = ")) else {
        return false;
    };
    let k = scan::digit_run(t, 0);
    n > 0 && m > 0 && k > 0 && matches!(t.get(k..), Some(b"" | b"x"))
}
