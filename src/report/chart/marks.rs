//! What streams in: markers (resets, partial resets, boot-ups) placed on
//! the time scale while the input is read, and coalesced as they come so memory
//! stays bounded by the chart's pixels, not by the trace.

use std::collections::BTreeMap;

use crate::canopen::NodeId;
use crate::timeline::At;
use crate::trace::Timestamp;

/// Coalesced markers kept per lane and kind while streaming.
const MARKER_CAP: usize = 2048;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mark {
    Reset,
    Partial,
    Boot,
}

pub(super) const MARKS: [Mark; 3] = [Mark::Reset, Mark::Partial, Mark::Boot];

impl Mark {
    pub(super) fn css(self) -> &'static str {
        match self {
            Mark::Reset => "reset",
            Mark::Partial => "partial",
            Mark::Boot => "boot",
        }
    }
    pub(super) fn noun(self, n: u64) -> &'static str {
        match (self, n) {
            (Mark::Reset, 1) => "reset (0x0000, register 0x00)",
            (Mark::Reset, _) => "resets (0x0000, register 0x00)",
            (Mark::Partial, 1) => "partial reset (0x0000, register bits still set)",
            (Mark::Partial, _) => "partial resets (0x0000, register bits still set)",
            (Mark::Boot, 1) => "NMT boot-up",
            (Mark::Boot, _) => "NMT boot-ups",
        }
    }
}

/// Markers of one kind that lie close together: their value range, count
/// and first and last positions.
#[derive(Clone, Debug)]
pub(super) struct Cluster {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) count: u64,
    pub(super) first: At,
    pub(super) last: At,
}

/// Coalesced markers. While streaming the final scale is unknown, so when
/// the list passes [`MARKER_CAP`] markers closer than a fraction of the span
/// seen so far merge: finer than a pixel of the final chart, whose span can
/// only be larger.
#[derive(Clone, Debug, Default)]
pub(super) struct Clusters {
    pub(super) items: Vec<Cluster>,
}

impl Clusters {
    fn push(&mut self, v: f64, at: At) {
        if let Some(last) = self.items.last_mut()
            && v >= last.lo
            && v <= last.hi
        {
            last.count += 1;
            last.last = at;
            return;
        }
        self.items.push(Cluster {
            lo: v,
            hi: v,
            count: 1,
            first: at,
            last: at,
        });
        if self.items.len() > MARKER_CAP {
            let (lo, hi) = self.bounds();
            self.coarsen((hi - lo) / (MARKER_CAP / 4) as f64);
        }
    }

    fn bounds(&self) -> (f64, f64) {
        self.items
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                (lo.min(c.lo), hi.max(c.hi))
            })
    }

    /// Merges clusters whose gap is at most `gap`.
    pub(super) fn coarsen(&mut self, gap: f64) {
        self.items.sort_by(|a, b| a.lo.total_cmp(&b.lo));
        let mut out: Vec<Cluster> = Vec::with_capacity(self.items.len());
        for c in self.items.drain(..) {
            match out.last_mut() {
                Some(last) if c.lo - last.hi <= gap => {
                    last.hi = last.hi.max(c.hi);
                    last.count += c.count;
                    last.last = c.last;
                }
                _ => out.push(c),
            }
        }
        self.items = out;
    }
}

#[derive(Debug, Default)]
pub(super) struct LaneMarks {
    pub(super) marks: [Clusters; 3],
}

/// What one input's events leave for the chart.
#[derive(Debug, Default)]
pub(super) struct Streamed {
    /// Whether the events carry times (decided by the first event).
    pub(super) timed: Option<bool>,
    /// Marker values are seconds after this time (timed inputs).
    pub(super) origin: Option<Timestamp>,
    pub(super) lanes: BTreeMap<String, BTreeMap<NodeId, LaneMarks>>,
    pub(super) lo: Option<f64>,
    pub(super) hi: Option<f64>,
    /// Events that could not be placed (no time in a timed trace).
    pub(super) unplaced: u64,
    pub(super) counts: [u64; 3],
    /// Incidents as numbered bands over every lane: start, end and
    /// summary, the first [`MAX_INCIDENT_BANDS`].
    pub(super) incidents: Vec<(At, At, String)>,
    /// The bus's own events for the bus strip above the lanes, the first
    /// [`MAX_BUS_MARKS`]; how many more were not drawn.
    pub(super) bus: Vec<BusMark>,
    pub(super) bus_not_drawn: u64,
}

/// Incidents a panel draws at most (one band each).
pub(super) const MAX_INCIDENT_BANDS: usize = 100;

/// Bus events a panel draws at most in its bus strip.
pub(super) const MAX_BUS_MARKS: usize = 1000;

/// One of the bus's own events as the bus strip shows it: a band from
/// `start` to `end` (`None`: to the end of the trace).
#[derive(Debug)]
pub(super) struct BusMark {
    /// The CSS class: `be` a burst of error frames, `bo` a bus-off, `sg` a
    /// gap in SYNC.
    pub(super) class: &'static str,
    pub(super) start: At,
    pub(super) end: Option<At>,
    pub(super) title: String,
}

impl Streamed {
    pub(super) fn mark(
        &mut self,
        channel: &str,
        node: NodeId,
        time: Option<Timestamp>,
        line: u64,
        mark: Mark,
    ) {
        let timed = *self.timed.get_or_insert(time.is_some());
        let value = if timed {
            time.map(|t| t.since(*self.origin.get_or_insert(t)).as_f64())
        } else {
            Some(line as f64)
        };
        let Some(v) = value else {
            self.unplaced += 1;
            return;
        };
        self.lo = Some(self.lo.map_or(v, |lo| lo.min(v)));
        self.hi = Some(self.hi.map_or(v, |hi| hi.max(v)));
        let lane = match self.lanes.get_mut(channel) {
            Some(nodes) => nodes.entry(node).or_default(),
            None => self
                .lanes
                .entry(channel.to_string())
                .or_default()
                .entry(node)
                .or_default(),
        };
        let k = mark as usize;
        if let Some(c) = lane.marks.get_mut(k) {
            c.push(v, At { time, line });
        }
        if let Some(n) = self.counts.get_mut(k) {
            *n += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(line: u64) -> At {
        At { time: None, line }
    }

    #[test]
    fn marker_clusters_stay_bounded() {
        let mut c = Clusters::default();
        for i in 0..100_000u64 {
            c.push(i as f64, at(i));
        }
        assert!(c.items.len() <= MARKER_CAP, "{}", c.items.len());
        assert_eq!(c.items.iter().map(|c| c.count).sum::<u64>(), 100_000);
        assert_eq!(c.items.first().map(|c| c.first.line), Some(0));
        assert_eq!(c.items.last().map(|c| c.last.line), Some(99_999));
    }
}
