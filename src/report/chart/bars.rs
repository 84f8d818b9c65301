//! Binning of error intervals into bars: a lane's intervals are laid into
//! rows, and intervals narrower than [`SMALL_PX`] that follow each other
//! within a pixel become one bar that counts what it merges. A lane never
//! holds more than a few thousand bars, however long the trace.

use super::style::PLOT_W;
use crate::canopen::codes::{self, Class};
use crate::timeline::{At, ClearedBy, Interval};

/// A bar narrower than this may merge with its neighbours.
pub(super) const SMALL_PX: f64 = 2.0;
/// Small bars closer than this merge.
const MERGE_GAP_PX: f64 = 1.0;
/// Concurrent errors of one node get their own row, up to this many; more
/// overlap in the last rows.
const MAX_ROWS: usize = 4;
/// Past this many bars in one lane everything merges (a bound, not a look).
const MAX_BARS_PER_LANE: usize = 4 * PLOT_W as usize;
/// Distinct codes listed in a merged bar's tooltip.
const TOOLTIP_CODES: usize = 6;

#[derive(Debug)]
pub(super) struct Bar {
    pub(super) row: usize,
    pub(super) x0: f64,
    pub(super) x1: f64,
    pub(super) count: u64,
    /// The first interval (all a single bar's tooltip needs).
    pub(super) first: Interval,
    /// The latest end among the merged intervals.
    pub(super) last_end: Option<At>,
    pub(super) open: u64,
    /// Only small intervals went in: later small ones may join.
    mergeable: bool,
    pub(super) codes: Vec<(u16, u64)>,
    pub(super) other_codes: u64,
    /// reset, partial_reset, boot, status_bit.
    pub(super) cleared: [u64; 4],
}

impl Bar {
    fn add(&mut self, iv: &Interval, x0: f64, x1: f64) {
        self.count += 1;
        self.x0 = self.x0.min(x0);
        self.x1 = self.x1.max(x1);
        if iv.end.is_none() {
            self.open += 1;
        }
        if let Some(end) = iv.end {
            let later = match (self.last_end.and_then(|e| e.time), end.time) {
                (Some(a), Some(b)) => b >= a,
                _ => self.last_end.is_none_or(|e| end.line >= e.line),
            };
            if later {
                self.last_end = Some(end);
            }
        }
        if let Some(i) = cleared_index(iv.cleared_by)
            && let Some(n) = self.cleared.get_mut(i)
        {
            *n += 1;
        }
        if let Some((_, n)) = self.codes.iter_mut().find(|(c, _)| *c == iv.code) {
            *n += 1;
        } else if self.codes.len() < TOOLTIP_CODES {
            self.codes.push((iv.code, 1));
        } else {
            self.other_codes += 1;
        }
    }

    /// The most frequent code (the first on a tie): the one the bar is
    /// coloured and labelled by.
    pub(super) fn code(&self) -> u16 {
        let mut best: Option<(u16, u64)> = None;
        for &(c, n) in &self.codes {
            if best.is_none_or(|(_, m)| n > m) {
                best = Some((c, n));
            }
        }
        best.map_or(self.first.code, |(c, _)| c)
    }

    /// The class of [`Bar::code`].
    pub(super) fn class(&self) -> Class {
        codes::lookup(self.code()).class
    }
}

fn cleared_index(c: Option<ClearedBy>) -> Option<usize> {
    Some(match c? {
        ClearedBy::Reset => 0,
        ClearedBy::PartialReset => 1,
        ClearedBy::Boot => 2,
        ClearedBy::StatusBit => 3,
    })
}

pub(super) const CLEARED_SLUGS: [&str; 4] = ["reset", "partial_reset", "boot", "status_bit"];

/// Lays a lane's intervals (in raise order) into rows of bars.
#[derive(Debug, Default)]
pub(super) struct Bars {
    /// Per row: where its last bar ends, and that bar's index.
    pub(super) rows: Vec<(f64, usize)>,
    pub(super) bars: Vec<Bar>,
    /// Intervals without a time in a timed trace.
    pub(super) unplaced: u64,
    merged: bool,
}

impl Bars {
    pub(super) fn push(&mut self, iv: Interval, x0: f64, x1: f64) {
        let small = x1 - x0 < SMALL_PX;
        let full = self.bars.len() >= MAX_BARS_PER_LANE;
        // Join a row's last bar: small after small within a pixel, or
        // anything once the lane has its fill of bars.
        for &(_, idx) in &self.rows {
            let Some(bar) = self.bars.get_mut(idx) else {
                continue;
            };
            let near = x0 <= bar.x1 + MERGE_GAP_PX && x0 >= bar.x0 - MERGE_GAP_PX;
            // (A full lane takes the first row, whatever the order of times.)
            if (small && bar.mergeable && near) || full {
                bar.add(&iv, x0, x1);
                bar.mergeable &= small;
                self.merged |= bar.count > 1;
                let end = bar.x1;
                if let Some(row) = self.rows.iter_mut().find(|r| r.1 == idx) {
                    row.0 = row.0.max(end);
                }
                return;
            }
        }
        // The first row free at x0; else a new row; else the one that frees first.
        let row = match self.rows.iter().position(|&(end, _)| end <= x0 + 1e-9) {
            Some(r) => r,
            None if self.rows.len() < MAX_ROWS => {
                self.rows.push((x1, 0));
                self.rows.len() - 1
            }
            None => self
                .rows
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.0.total_cmp(&b.1.0))
                .map_or(0, |(i, _)| i),
        };
        let mut bar = Bar {
            row,
            x0,
            x1,
            count: 0,
            first: iv.clone(),
            last_end: None,
            open: 0,
            mergeable: small,
            codes: Vec::new(),
            other_codes: 0,
            cleared: [0; 4],
        };
        bar.add(&iv, x0, x1);
        self.bars.push(bar);
        let idx = self.bars.len() - 1;
        if let Some(r) = self.rows.get_mut(row) {
            *r = (r.0.max(x1), idx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::chart::style::X0;

    fn at(line: u64) -> At {
        At { time: None, line }
    }

    fn interval(seq: u64) -> Interval {
        Interval {
            seq,
            code: 0x4310,
            start: at(seq),
            end: Some(at(seq + 1)),
            cleared_by: Some(ClearedBy::Reset),
            raised_register: crate::canopen::register::Register(0x09),
            status_bit: None,
        }
    }

    #[test]
    fn bars_merge_small_neighbours_and_stay_bounded() {
        let mut b = Bars::default();
        // Small and adjacent: one bar.
        for i in 0..1000u64 {
            let x = X0 + i as f64 * 0.5;
            b.push(interval(i), x, x + 0.1);
        }
        assert_eq!(b.bars.len(), 1);
        assert_eq!(b.bars.first().map(|b| b.count), Some(1000));
        // Wide and far apart, in any order: never more than the bound.
        let mut b = Bars::default();
        for i in 0..100_000u64 {
            let x = X0 + ((i * 7919) % 700) as f64;
            b.push(interval(i), x, x + 5.0);
        }
        assert!(b.bars.len() <= MAX_BARS_PER_LANE + MAX_ROWS);
        assert_eq!(b.bars.iter().map(|b| b.count).sum::<u64>(), 100_000);
        assert!(b.rows.len() <= MAX_ROWS);
    }
}
