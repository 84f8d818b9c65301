//! The timeline chart shared by `--format svg` and `--format html`: one lane
//! per (channel, node), error intervals as bars coloured by class, resets and
//! boot-ups as markers, a time axis, a legend.
//!
//! Plain SVG text, not a plotting crate. What the chart needs is a `<title>`
//! tooltip on every bar, CSS classes instead of repeated style attributes
//! (that is what keeps a file with thousands of bars small), exact control of
//! number formatting (golden tests compare bytes) and escaping of
//! trace-controlled text. plotters' SVG backend gives none of the first three
//! (every element carries inline styles, no child elements for tooltips) and
//! brings a font stack for text measurement we do not need; the chart is a
//! few rectangles and lines, so writing them directly is less code than
//! adapting a backend.
//!
//! Memory stays bounded by pixels, not by the trace: markers (resets, partial
//! resets, boot-ups) are coalesced while they stream in ([`Clusters`]), and
//! the error intervals are read once from the input's history at the end and
//! folded into at most a few thousand bars per lane ([`Bars`]); intervals
//! narrower than [`SMALL_PX`] that follow each other within a pixel become one
//! bar whose tooltip says how many errors it merges.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt::{self, Write as _};
use std::io;

use crate::analyze::{BootEvent, EmcyEvent, InputReport, NodeReport};
use crate::canopen::codes::{self, Class};
use crate::timeline::{At, ClearedBy, Interval};
use crate::trace::{Format, Timestamp};

/// Width of the whole chart in px.
pub const WIDTH: f64 = 960.0;
/// Left edge of the plot area (the lane labels are left of it).
const X0: f64 = 170.0;
/// Right edge of the plot area.
const X1: f64 = WIDTH - 28.0;
const PLOT_W: f64 = X1 - X0;
/// Height of one bar row inside a lane, and of a bar.
const ROW_H: f64 = 12.0;
const BAR_H: f64 = 9.0;
const LANE_MIN_H: f64 = 28.0;
/// Concurrent errors of one node get their own row, up to this many; more
/// overlap in the last rows.
const MAX_ROWS: usize = 4;
/// Where the lanes start below the panel's top (title and subtitle above).
const LANES_TOP: f64 = 52.0;
/// A bar narrower than this may merge with its neighbours.
pub const SMALL_PX: f64 = 2.0;
/// Small bars closer than this merge.
const MERGE_GAP_PX: f64 = 1.0;
/// Markers of one kind closer than this are drawn as one.
const MARKER_GAP_PX: f64 = 3.0;
/// Past this many bars in one lane everything merges (a bound, not a look).
const MAX_BARS_PER_LANE: usize = 4 * PLOT_W as usize;
/// Coalesced markers kept per lane and kind while streaming.
const MARKER_CAP: usize = 2048;
/// Distinct codes listed in a merged bar's tooltip.
const TOOLTIP_CODES: usize = 6;
/// Room right of the last frame, as a fraction of the span.
const END_ROOM: f64 = 0.03;
/// Times from this Unix second on (1973) are wall-clock times.
const UNIX_FROM: u64 = 100_000_000;

/// The CSS of the chart: one copy per document (the SVG's root, the HTML head).
pub const STYLE: &str = "\
.ec text{font:11px system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;fill:#222}
.ec .t1{font-size:15px;font-weight:600}
.ec .t2{fill:#555}
.ec .lbl{font-weight:600}
.ec .lbl2{fill:#666;font-size:10px}
.ec .tick{fill:#444;text-anchor:middle}
.ec .cap{fill:#666;text-anchor:end}
.ec .bg{fill:#f3f4f6}
.ec .grid{stroke:#dcdfe4;stroke-width:1}
.ec .axis{stroke:#555;stroke-width:1}
.ec .end{stroke:#777;stroke-dasharray:4 3}
.ec .none{fill:#777}
.ec rect.b{stroke:#0006;stroke-width:.5}
.ec rect.b:hover{stroke:#000;stroke-width:1.5}
.ec rect.m{fill-opacity:.55;stroke-dasharray:2 1}
.ec rect.o{stroke:#000;stroke-width:1;stroke-dasharray:3 2}
.ec .oe{fill:#000}
.ec .mk line{stroke-width:1.5}
.ec .reset line{stroke:#1b7837}
.ec .reset circle{fill:#1b7837}
.ec .partial line{stroke:#5aae61;stroke-dasharray:2 2}
.ec .partial circle{fill:#fff;stroke:#1b7837;stroke-width:1.2}
.ec .boot line{stroke:#2c4f9e}
.ec .boot path{fill:#2c4f9e}
.ec .mk rect{fill-opacity:.5}
.ec .reset rect{fill:#1b7837}
.ec .partial rect{fill:#5aae61}
.ec .boot rect{fill:#2c4f9e}
.ec .c-current{fill:#e69f00}
.ec .c-voltage{fill:#0072b2}
.ec .c-temperature{fill:#d55e00}
.ec .c-communication{fill:#56b4e9}
.ec .c-hardware{fill:#cc79a7}
.ec .c-software{fill:#009e73}
.ec .c-monitoring{fill:#e8d21d}
.ec .c-manufacturer{fill:#8c564b}
.ec .c-generic{fill:#a0a0a0}
.ec .c-modules{fill:#9467bd}
.ec .c-external{fill:#7f7f00}
.ec .c-additional_functions{fill:#bcbd22}
.ec .c-reset{fill:#c7c7c7}
.ec .c-undefined{fill:#4d4d4d}
";

/// Classes in legend order: the CiA 301 classes users look for first.
const LEGEND_ORDER: [Class; 14] = [
    Class::Current,
    Class::Voltage,
    Class::Temperature,
    Class::Communication,
    Class::Hardware,
    Class::Software,
    Class::Monitoring,
    Class::Manufacturer,
    Class::Generic,
    Class::Modules,
    Class::External,
    Class::AdditionalFunctions,
    Class::Reset,
    Class::Undefined,
];

fn class_index(class: Class) -> usize {
    LEGEND_ORDER.iter().position(|&c| c == class).unwrap_or(0)
}

/// Text from a trace (channel and file names) made safe for XML and HTML:
/// markup characters become entities, control characters (not allowed in
/// XML 1.0 at all, even as references) become visible escapes. Line breaks
/// and tabs stay (tooltips are multi-line).
pub fn esc(s: &str) -> Cow<'_, str> {
    let special = |c: char| matches!(c, '&' | '<' | '>' | '"' | '\'') || is_bad_control(c);
    if !s.chars().any(special) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 16);
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c if is_bad_control(c) => out.extend(c.escape_default()),
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

fn is_bad_control(c: char) -> bool {
    c.is_control() && c != '\n' && c != '\t'
}

/// A coordinate with at most one decimal, without a trailing `.0`: small
/// files and the same bytes on every platform.
pub struct N(pub f64);

impl fmt::Display for N {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let tenths = if self.0.is_finite() {
            (self.0 * 10.0).round() as i64
        } else {
            0
        };
        let sign = if tenths < 0 { "-" } else { "" };
        let a = tenths.unsigned_abs();
        match a % 10 {
            0 => write!(f, "{sign}{}", a / 10),
            d => write!(f, "{sign}{}.{d}", a / 10),
        }
    }
}

// ---- time --------------------------------------------------------------------

/// What the horizontal axis measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// candump times: Unix seconds, shown as UTC clock times.
    Wall,
    /// ASC times and relative candump times: seconds.
    Seconds,
    /// No timestamps at all (candump screen output without -t): trace lines.
    Lines,
}

/// Converts trace positions to axis values and formats them.
#[derive(Clone, Copy, Debug)]
pub struct Clock {
    pub axis: Axis,
    /// Time of axis value 0 (timed axes).
    origin: Option<Timestamp>,
    /// All times of the input fall on one UTC day (wall clock only).
    one_day: bool,
}

impl Clock {
    /// Axis value of a position: seconds after the origin, or the line.
    fn value(&self, at: &At) -> Option<f64> {
        match self.axis {
            Axis::Lines => Some(at.line as f64),
            Axis::Wall | Axis::Seconds => Some(at.time?.since(self.origin?).as_f64()),
        }
    }

    /// A time as a reader wants it: `22:13:21.250000 UTC` (the date too when
    /// the trace spans days), `1.250000 s`, or `line 12` without times.
    pub fn at(&self, at: &At) -> String {
        match (self.axis, at.time) {
            (Axis::Lines, _) | (_, None) => format!("line {}", at.line),
            (Axis::Wall, Some(t)) => format!("{} UTC", self.wall(t)),
            (Axis::Seconds, Some(t)) => format!("{t} s"),
        }
    }

    /// The heading of a time column.
    pub fn heading(&self) -> &'static str {
        match self.axis {
            Axis::Wall => "time (UTC)",
            Axis::Seconds => "time (s)",
            Axis::Lines => "time",
        }
    }

    /// An event's time for the HTML table.
    pub fn cell(&self, time: Option<Timestamp>) -> String {
        match (self.axis, time) {
            (_, None) => "-".to_string(),
            (Axis::Wall, Some(t)) => self.wall(t),
            (_, Some(t)) => t.to_string(),
        }
    }

    fn wall(&self, t: Timestamp) -> String {
        let (date, clock) = wall_clock(t);
        if self.one_day {
            clock
        } else {
            format!("{date} {clock}")
        }
    }
}

/// `("2023-11-14", "22:13:21.250000")`, exact to the trace's digits.
pub fn wall_clock(t: Timestamp) -> (String, String) {
    let (secs, atto, digits) = t.to_raw();
    let days = secs / 86_400;
    let rest = secs % 86_400;
    let (y, m, d) = civil_from_days(days);
    let mut clock = format!(
        "{:02}:{:02}:{:02}",
        rest / 3600,
        rest % 3600 / 60,
        rest % 60
    );
    if digits > 0 {
        let digits = u32::from(digits.min(18));
        let frac = atto / 10u64.pow(18 - digits);
        let _ = write!(clock, ".{frac:0w$}", w = digits as usize);
    }
    (format!("{y:04}-{m:02}-{d:02}"), clock)
}

/// Days since 1970-01-01 to (year, month, day), proleptic Gregorian
/// (H. Hinnant's `civil_from_days`).
fn civil_from_days(days: u64) -> (u64, u64, u64) {
    let z = days + 719_468;
    let era = z / 146_097;
    let doe = z % 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + u64::from(m <= 2);
    (y, m, d)
}

/// Tick spacing of a wall-clock axis, in seconds.
const WALL_STEPS: [f64; 28] = [
    1e-6, 2e-6, 5e-6, 1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 0.01, 0.02, 0.05, 0.1,
    0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 30.0, 60.0, 120.0, 300.0, 600.0,
];
const WALL_STEPS_LONG: [f64; 8] = [
    900.0, 1800.0, 3600.0, 7200.0, 10_800.0, 21_600.0, 43_200.0, 86_400.0,
];

/// The smallest 1-2-5 step of at least `raw`.
fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(raw.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * mag >= raw * (1.0 - 1e-9) {
            return m * mag;
        }
    }
    10.0 * mag
}

fn tick_step(axis: Axis, span: f64) -> f64 {
    // A tick every 90 px or more: room for a label like 22:13:21.25.
    let raw = span / (PLOT_W / 90.0);
    match axis {
        Axis::Lines => nice_step(raw).max(1.0),
        Axis::Seconds => nice_step(raw),
        Axis::Wall => WALL_STEPS
            .iter()
            .chain(&WALL_STEPS_LONG)
            .copied()
            .find(|&s| s >= raw)
            .unwrap_or_else(|| 86_400.0 * nice_step(raw / 86_400.0)),
    }
}

/// Decimals a label needs at this step.
fn decimals(step: f64) -> usize {
    let mut d = 0;
    while d < 9 && (step * 10f64.powi(d as i32)).fract().abs() > 1e-6 {
        d += 1;
    }
    d
}

fn tick_label(axis: Axis, value: f64, step: f64, one_day: bool) -> String {
    let d = decimals(step);
    match axis {
        Axis::Lines => format!("{value:.0}"),
        Axis::Seconds => format!("{value:.d$}"),
        Axis::Wall => {
            let scale = 10f64.powi(d as i32);
            let units = (value * scale).round();
            if !(units.is_finite() && units >= 0.0) {
                return String::new();
            }
            let units = units as u64;
            let per = 10u64.pow(d as u32);
            let secs = units / per;
            let frac = units % per;
            let (_, m, day) = civil_from_days(secs / 86_400);
            let rest = secs % 86_400;
            let (h, min, s) = (rest / 3600, rest % 3600 / 60, rest % 60);
            if step >= 86_400.0 {
                format!("{m:02}-{day:02}")
            } else if !one_day {
                format!("{m:02}-{day:02} {h:02}:{min:02}")
            } else if step >= 60.0 {
                format!("{h:02}:{min:02}")
            } else if d == 0 {
                format!("{h:02}:{min:02}:{s:02}")
            } else {
                format!("{h:02}:{min:02}:{s:02}.{frac:0d$}")
            }
        }
    }
}

// ---- what streams in ------------------------------------------------------------

/// Markers: a reset, a partial reset, an NMT boot-up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mark {
    Reset,
    Partial,
    Boot,
}

const MARKS: [Mark; 3] = [Mark::Reset, Mark::Partial, Mark::Boot];

impl Mark {
    fn css(self) -> &'static str {
        match self {
            Mark::Reset => "reset",
            Mark::Partial => "partial",
            Mark::Boot => "boot",
        }
    }
    fn noun(self, n: u64) -> &'static str {
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
struct Cluster {
    lo: f64,
    hi: f64,
    count: u64,
    first: At,
    last: At,
}

/// Coalesced markers. While streaming the final scale is unknown, so when
/// the list passes [`MARKER_CAP`] markers closer than a fraction of the span
/// seen so far merge: finer than a pixel of the final chart, whose span can
/// only be larger.
#[derive(Clone, Debug, Default)]
struct Clusters {
    items: Vec<Cluster>,
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
    fn coarsen(&mut self, gap: f64) {
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
struct LaneMarks {
    marks: [Clusters; 3],
}

/// What one input's events leave for the chart.
#[derive(Debug, Default)]
struct Streamed {
    /// Whether the events carry times (decided by the first event).
    timed: Option<bool>,
    /// Marker values are seconds after this time (timed inputs).
    origin: Option<Timestamp>,
    lanes: BTreeMap<String, BTreeMap<u8, LaneMarks>>,
    lo: Option<f64>,
    hi: Option<f64>,
    /// Events that could not be placed (no time in a timed trace).
    unplaced: u64,
    counts: [u64; 3],
}

impl Streamed {
    fn mark(&mut self, channel: &str, node: u8, time: Option<Timestamp>, line: u64, mark: Mark) {
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

/// Collects one input at a time and lays it out as a [`Panel`].
#[derive(Debug, Default)]
pub struct Collector {
    current: Streamed,
}

impl Collector {
    pub fn begin_input(&mut self) {
        self.current = Streamed::default();
    }

    pub fn emcy(&mut self, ev: &EmcyEvent<'_>) {
        if !ev.emcy.is_reset() {
            // Errors are drawn from the history, which has their ends; the
            // event only fixes whether the trace is timed.
            self.current.timed.get_or_insert(ev.time.is_some());
            if let (Some(t), None) = (ev.time, self.current.origin) {
                self.current.origin = Some(t);
            }
            return;
        }
        let mark = if ev.emcy.register.0 == 0 {
            Mark::Reset
        } else {
            Mark::Partial
        };
        self.current
            .mark(ev.channel, ev.node, ev.time, ev.line, mark);
    }

    pub fn boot(&mut self, ev: &BootEvent<'_>) {
        self.current
            .mark(ev.channel, ev.node, ev.time, ev.line, Mark::Boot);
    }

    /// Lays out the input that just ended.
    pub fn end_input(&mut self, input: &InputReport) -> io::Result<Panel> {
        let streamed = std::mem::take(&mut self.current);
        Panel::build(input, streamed)
    }
}

// ---- bars ------------------------------------------------------------------------

/// One drawn bar: a single interval, or merged small ones.
#[derive(Debug)]
struct Bar {
    row: usize,
    x0: f64,
    x1: f64,
    count: u64,
    /// The first interval (all a single bar's tooltip needs).
    first: Interval,
    /// The latest end among the merged intervals.
    last_end: Option<At>,
    open: u64,
    /// Only small intervals went in: later small ones may join.
    mergeable: bool,
    codes: Vec<(u16, u64)>,
    other_codes: u64,
    /// reset, partial_reset, boot, status_bit.
    cleared: [u64; 4],
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

    /// The class of the most frequent code (the first on a tie).
    fn class(&self) -> Class {
        let mut best: Option<(u16, u64)> = None;
        for &(c, n) in &self.codes {
            if best.is_none_or(|(_, m)| n > m) {
                best = Some((c, n));
            }
        }
        codes::lookup(best.map_or(self.first.code, |(c, _)| c)).class
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

const CLEARED_SLUGS: [&str; 4] = ["reset", "partial_reset", "boot", "status_bit"];

/// Lays a lane's intervals (in raise order) into rows of bars.
#[derive(Debug, Default)]
struct Bars {
    /// Per row: where its last bar ends, and that bar's index.
    rows: Vec<(f64, usize)>,
    bars: Vec<Bar>,
    /// Intervals without a time in a timed trace.
    unplaced: u64,
    merged: bool,
}

impl Bars {
    fn push(&mut self, iv: Interval, x0: f64, x1: f64) {
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

// ---- the panel -------------------------------------------------------------------

/// The label of a lane: `can0 · node 5`, and a second line.
pub struct LaneLabel {
    pub main: String,
    pub detail: Option<String>,
}

/// The one place a lane's label is made: channel and node, then the node's
/// profile and why it has it.
pub fn lane_label(node: &NodeReport) -> LaneLabel {
    LaneLabel {
        main: format!("{} · node {}", node.channel, node.node),
        detail: Some(format!(
            "{} ({})",
            node.profile.name(),
            node.profile_source.slug()
        )),
    }
}

/// Key of a lane in the HTML filter: `channel/node`.
pub fn lane_key(channel: &str, node: u8) -> String {
    format!("{channel}/{node}")
}

/// One input laid out: the SVG fragment (without `<svg>` and style), its
/// height, and the clock its times are shown with.
pub struct Panel {
    pub svg: String,
    pub height: f64,
    pub clock: Clock,
    /// `(key, label)` per lane, for the HTML filter.
    pub lanes: Vec<(String, String)>,
}

struct Lane<'a> {
    node: &'a NodeReport,
    bars: Bars,
    marks: Option<LaneMarks>,
    height: f64,
}

/// Maps axis values to x pixels.
#[derive(Clone, Copy)]
struct Scale {
    lo: f64,
    hi: f64,
    /// The last frame of the input.
    end: f64,
}

impl Scale {
    fn x(&self, v: f64) -> f64 {
        let v = v.clamp(self.lo, self.hi);
        X0 + (v - self.lo) / (self.hi - self.lo) * PLOT_W
    }
    fn per_px(&self) -> f64 {
        (self.hi - self.lo) / PLOT_W
    }
}

impl Panel {
    fn build(input: &InputReport, mut streamed: Streamed) -> io::Result<Panel> {
        let timed = streamed.timed.unwrap_or(input.first_time.is_some());
        let origin = input.first_time.or(streamed.origin);
        let wall = matches!(
            input.format,
            Some(Format::CandumpLog | Format::CandumpScreen)
        ) && origin.is_some_and(|t| t.secs() >= UNIX_FROM);
        let axis = match (timed, wall) {
            (false, _) => Axis::Lines,
            (true, true) => Axis::Wall,
            (true, false) => Axis::Seconds,
        };
        let one_day = match (input.first_time, input.last_time) {
            (Some(a), Some(b)) => a.secs() / 86_400 == b.secs() / 86_400,
            _ => true,
        };
        let clock = Clock {
            axis,
            origin,
            one_day,
        };
        // Streamed marker values are relative to the first event's time;
        // the axis is relative to the input's first frame.
        let shift = match (streamed.origin, origin) {
            (Some(s), Some(o)) if timed => s.since(o).as_f64(),
            _ => 0.0,
        };
        for nodes in streamed.lanes.values_mut() {
            for lane in nodes.values_mut() {
                for c in lane.marks.iter_mut().flat_map(|m| m.items.iter_mut()) {
                    c.lo += shift;
                    c.hi += shift;
                }
            }
        }
        let (mut lo, mut hi): (f64, f64) = match axis {
            Axis::Lines => (1.0, input.counts.lines.max(1) as f64),
            _ => (
                0.0,
                match (input.last_time, origin) {
                    (Some(l), Some(o)) => l.since(o).as_f64(),
                    _ => 0.0,
                },
            ),
        };
        if let (Some(a), Some(b)) = (streamed.lo, streamed.hi) {
            lo = lo.min(a + shift);
            hi = hi.max(b + shift);
        }
        // An empty span (one frame, or no times): one unit wide.
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            hi = lo + 1.0;
        }
        // Room right of the last frame, so an error still active there
        // visibly runs on to the edge.
        let scale = Scale {
            lo,
            hi: hi + (hi - lo) * END_ROOM,
            end: hi,
        };

        let mut lanes = Vec::with_capacity(input.nodes.len());
        let mut merge = input.history.merge();
        for node in &input.nodes {
            let mut bars = Bars::default();
            for iv in merge.node_errors(&node.channel, node.node) {
                let start = clock.value(&iv.start);
                let end = match iv.end {
                    Some(e) => clock.value(&e),
                    None => Some(scale.hi),
                };
                let (Some(s), Some(e)) = (start, end) else {
                    bars.unplaced += 1;
                    continue;
                };
                let (x0, x1) = (scale.x(s), scale.x(e.max(s)));
                bars.push(iv, x0, x1);
            }
            let marks = streamed
                .lanes
                .get_mut(node.channel.as_str())
                .and_then(|n| n.remove(&node.node));
            let rows = bars.rows.len().max(1) as f64;
            lanes.push(Lane {
                node,
                bars,
                marks,
                height: (rows * ROW_H + 10.0).max(LANE_MIN_H),
            });
        }
        if let Some(e) = merge.take_error() {
            return Err(e);
        }
        let mut svg = String::new();
        let height = write_panel(&mut svg, input, &clock, scale, &lanes, &streamed)
            .map_err(|_| io::Error::other("formatting the chart failed"))?;
        let lanes = lanes
            .iter()
            .map(|l| {
                (
                    lane_key(&l.node.channel, l.node.node),
                    lane_label(l.node).main,
                )
            })
            .collect();
        Ok(Panel {
            svg,
            height,
            clock,
            lanes,
        })
    }
}

/// Title line two: the time span, what the chart shows.
fn subtitle(input: &InputReport, clock: &Clock, lanes: &[Lane<'_>], streamed: &Streamed) -> String {
    let mut s = match (clock.axis, input.first_time, input.last_time) {
        (Axis::Wall, Some(a), Some(b)) => {
            let (da, ca) = wall_clock(a);
            let (db, cb) = wall_clock(b);
            let to = if da == db { cb } else { format!("{db} {cb}") };
            format!("{da} {ca} – {to} UTC ({} s)", b.since(a))
        }
        (Axis::Seconds, Some(a), Some(b)) => format!("{a} s – {b} s ({} s)", b.since(a)),
        _ => format!(
            "lines 1–{} (the trace has no timestamps)",
            input.counts.lines
        ),
    };
    let errors: u64 = lanes
        .iter()
        .flat_map(|l| &l.bars.bars)
        .map(|b| b.count)
        .sum();
    let open: u64 = lanes
        .iter()
        .flat_map(|l| &l.bars.bars)
        .map(|b| b.open)
        .sum();
    let _ = write!(
        s,
        " · {} node{} · {errors} error{}",
        lanes.len(),
        plural(lanes.len() as u64),
        plural(errors)
    );
    if open > 0 {
        let _ = write!(s, " ({open} still active)");
    }
    for (mark, n) in MARKS.iter().zip(streamed.counts) {
        if n > 0 {
            let _ = write!(
                s,
                " · {n} {}",
                match mark {
                    Mark::Reset => "reset",
                    Mark::Partial => "partial reset",
                    Mark::Boot => "boot-up",
                }
            );
            s.push_str(plural(n));
        }
    }
    let unplaced = streamed.unplaced + lanes.iter().map(|l| l.bars.unplaced).sum::<u64>();
    if unplaced > 0 {
        let _ = write!(s, " · {unplaced} without a time not drawn");
    }
    s
}

fn plural(n: u64) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Writes one input's chart; returns its height.
fn write_panel(
    out: &mut String,
    input: &InputReport,
    clock: &Clock,
    scale: Scale,
    lanes: &[Lane<'_>],
    streamed: &Streamed,
) -> Result<f64, fmt::Error> {
    writeln!(
        out,
        "<text class=\"t1\" x=\"10\" y=\"20\">{}</text>",
        esc(&input.file)
    )?;
    writeln!(
        out,
        "<text class=\"t2\" x=\"10\" y=\"38\">{}</text>",
        esc(&subtitle(input, clock, lanes, streamed))
    )?;
    if lanes.is_empty() {
        let why = match &input.error {
            Some(e) => format!("nothing to draw: {e}"),
            None => "no EMCY or boot-up frames".to_string(),
        };
        writeln!(
            out,
            "<text class=\"none\" x=\"{}\" y=\"{}\">{}</text>",
            N(X0),
            N(LANES_TOP + 16.0),
            esc(&why)
        )?;
        return Ok(LANES_TOP + 32.0);
    }
    let lanes_h: f64 = lanes.iter().map(|l| l.height).sum();
    let axis_y = LANES_TOP + lanes_h;

    // Alternate lane backgrounds, then the grid over them, then the lanes.
    let mut y = LANES_TOP;
    for (i, lane) in lanes.iter().enumerate() {
        if i % 2 == 0 {
            writeln!(
                out,
                "<rect class=\"bg\" x=\"0\" y=\"{}\" width=\"{}\" height=\"{}\"/>",
                N(y),
                N(WIDTH),
                N(lane.height)
            )?;
        }
        y += lane.height;
    }
    write_axis(out, clock, scale, axis_y)?;
    let mut y = LANES_TOP;
    for lane in lanes {
        write_lane(out, clock, scale, lane, y)?;
        y += lane.height;
    }
    let legend_h = write_legend(out, lanes, axis_y + 44.0)?;
    Ok(axis_y + 44.0 + legend_h)
}

fn write_axis(out: &mut String, clock: &Clock, scale: Scale, axis_y: f64) -> fmt::Result {
    let span = scale.hi - scale.lo;
    let step = tick_step(clock.axis, span);
    // Ticks fall on round absolute values (whole seconds of the clock).
    let base = match clock.axis {
        Axis::Lines => 0.0,
        _ => clock.origin.map_or(0.0, Timestamp::as_f64),
    };
    let first = ((base + scale.lo) / step).ceil() * step;
    out.push_str("<g>\n");
    writeln!(
        out,
        "<line class=\"axis\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
        N(X0),
        N(axis_y),
        N(X1),
        N(axis_y)
    )?;
    for i in 0..200 {
        let abs = first + f64::from(i) * step;
        let v = abs - base;
        if v > scale.hi + step * 1e-6 {
            break;
        }
        let x = scale.x(v);
        writeln!(
            out,
            "<line class=\"grid\" x1=\"{x}\" y1=\"{}\" x2=\"{x}\" y2=\"{}\"/>\
             <text class=\"tick\" x=\"{x}\" y=\"{}\">{}</text>",
            N(LANES_TOP),
            N(axis_y + 4.0),
            N(axis_y + 16.0),
            tick_label(clock.axis, abs, step, clock.one_day),
            x = N(x),
        )?;
    }
    let x = N(scale.x(scale.end));
    writeln!(
        out,
        "<line class=\"end\" x1=\"{x}\" y1=\"{}\" x2=\"{x}\" y2=\"{}\"><title>last frame of the trace</title></line>",
        N(LANES_TOP),
        N(axis_y)
    )?;
    let caption = match clock.axis {
        Axis::Wall => "time (UTC)",
        Axis::Seconds => "time (s)",
        Axis::Lines => "trace line",
    };
    writeln!(
        out,
        "<text class=\"cap\" x=\"{}\" y=\"{}\">{caption}</text>",
        N(X1),
        N(axis_y + 30.0)
    )?;
    out.push_str("</g>\n");
    Ok(())
}

fn write_lane(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    lane: &Lane<'_>,
    y: f64,
) -> fmt::Result {
    let node = lane.node;
    let label = lane_label(node);
    writeln!(
        out,
        "<g class=\"lane\" data-lane=\"{}\" transform=\"translate(0,{})\">",
        esc(&lane_key(&node.channel, node.node)),
        N(y)
    )?;
    let mid = lane.height / 2.0;
    match &label.detail {
        None => writeln!(
            out,
            "<text class=\"lbl\" x=\"10\" y=\"{}\">{}</text>",
            N(mid + 4.0),
            esc(&clip(&label.main, 24))
        )?,
        Some(detail) => writeln!(
            out,
            "<text class=\"lbl\" x=\"10\" y=\"{}\">{}</text>\
             <text class=\"lbl2\" x=\"10\" y=\"{}\">{}</text>",
            N(mid - 1.0),
            esc(&clip(&label.main, 24)),
            N(mid + 10.0),
            esc(&clip(detail, 28))
        )?,
    }
    let rows = lane.bars.rows.len().max(1) as f64;
    let top = (lane.height - rows * ROW_H) / 2.0 + (ROW_H - BAR_H) / 2.0;
    for bar in &lane.bars.bars {
        write_bar(out, clock, scale, lane, bar, top)?;
    }
    if let Some(marks) = &lane.marks {
        for (mark, clusters) in MARKS.iter().zip(&marks.marks) {
            write_marks(out, clock, scale, *mark, clusters, lane.height)?;
        }
    }
    out.push_str("</g>\n");
    Ok(())
}

/// At most `n` characters, with an ellipsis when cut.
fn clip(s: &str, n: usize) -> Cow<'_, str> {
    if s.chars().count() <= n {
        return Cow::Borrowed(s);
    }
    let mut t: String = s.chars().take(n.saturating_sub(1)).collect();
    t.push('…');
    Cow::Owned(t)
}

fn write_bar(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    lane: &Lane<'_>,
    bar: &Bar,
    top: f64,
) -> fmt::Result {
    let y = top + bar.row as f64 * ROW_H;
    let w = (bar.x1 - bar.x0).max(1.0);
    let mut class = format!("b c-{}", bar.class().slug());
    if bar.count > 1 {
        class.push_str(" m");
    } else if bar.open > 0 {
        class.push_str(" o");
    }
    writeln!(
        out,
        "<rect class=\"{class}\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"><title>{}</title></rect>",
        N(bar.x0),
        N(y),
        N(w),
        N(BAR_H),
        esc(&bar_title(clock, scale, lane.node, bar))
    )?;
    if bar.open > 0 {
        // The open end: a triangle past the end of the plot area.
        let x = N(bar.x1 + 1.0);
        writeln!(
            out,
            "<path class=\"oe\" d=\"M{x} {}l7 {}l-7 {}z\"><title>still active at the end of the trace</title></path>",
            N(y - 1.0),
            N(BAR_H / 2.0 + 1.0),
            N(BAR_H / 2.0 + 1.0),
        )?;
    }
    Ok(())
}

fn bar_title(clock: &Clock, scale: Scale, node: &NodeReport, bar: &Bar) -> String {
    let label = lane_label(node).main;
    let iv = &bar.first;
    if bar.count == 1 {
        let (end, duration, cleared) = match iv.end {
            Some(e) => (
                clock.at(&e),
                match (e.time, iv.start.time) {
                    (Some(b), Some(a)) if clock.axis != Axis::Lines => format!("{} s", b.since(a)),
                    _ => "-".to_string(),
                },
                iv.cleared_by.map_or("-", ClearedBy::slug),
            ),
            None => (
                "still active at the end of the trace".to_string(),
                "open".to_string(),
                "-",
            ),
        };
        let lines = match iv.end {
            Some(e) => format!("lines {}–{}", iv.start.line, e.line),
            None => format!("line {}", iv.start.line),
        };
        return format!(
            "0x{:04X} {}\n{label}\nstart: {}\nend: {end}\nduration: {duration}\ncleared by: {cleared}\n{lines}",
            iv.code,
            node.describe(iv.code),
            clock.at(&iv.start),
        );
    }
    let mut s = format!(
        "{} errors merged into one bar (each shorter than {} px, about {} {} at this scale)\n{label}\n",
        bar.count,
        N(SMALL_PX),
        short_number(scale.per_px() * SMALL_PX),
        match clock.axis {
            Axis::Lines => "lines",
            _ => "s",
        }
    );
    let mut codes_sorted = bar.codes.clone();
    codes_sorted.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    for (code, n) in codes_sorted {
        let _ = writeln!(s, "0x{code:04X} ×{n} {}", node.describe(code));
    }
    if bar.other_codes > 0 {
        let _ = writeln!(s, "{} more of other codes", bar.other_codes);
    }
    let _ = write!(s, "from: {}\nto: ", clock.at(&iv.start));
    match (bar.open, bar.last_end) {
        (0, Some(e)) => s.push_str(&clock.at(&e)),
        _ => s.push_str("still active at the end of the trace"),
    }
    let cleared: Vec<String> = CLEARED_SLUGS
        .iter()
        .zip(bar.cleared)
        .filter(|(_, n)| *n > 0)
        .map(|(slug, n)| format!("{slug} ×{n}"))
        .collect();
    if !cleared.is_empty() {
        let _ = write!(s, "\ncleared by: {}", cleared.join(", "));
    }
    if bar.open > 0 {
        let _ = write!(s, "\n{} still active", bar.open);
    }
    s
}

/// A positive number with three significant digits: `0.00271`, `12.3`, `4560`.
fn short_number(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return "0".to_string();
    }
    let mag = v.log10().floor() as i32;
    let d = (2 - mag).max(0) as usize;
    format!("{v:.d$}")
}

fn write_marks(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    mark: Mark,
    clusters: &Clusters,
    height: f64,
) -> fmt::Result {
    // Markers closer than a few pixels are one marker at this scale.
    let mut merged = clusters.clone();
    merged.coarsen(scale.per_px() * MARKER_GAP_PX);
    for c in &merged.items {
        let (x_lo, x_hi) = (scale.x(c.lo), scale.x(c.hi));
        let title = if c.count == 1 {
            format!("{} at {}", mark.noun(1), clock.at(&c.first))
        } else {
            format!(
                "{} {} from {} to {} (merged: closer than {} px)",
                c.count,
                mark.noun(c.count),
                clock.at(&c.first),
                clock.at(&c.last),
                N(MARKER_GAP_PX)
            )
        };
        write!(
            out,
            "<g class=\"mk {}\"><title>{}</title>",
            mark.css(),
            esc(&title)
        )?;
        let bottom = N(height - 2.0);
        if x_hi - x_lo < MARKER_GAP_PX {
            let x = N((x_lo + x_hi) / 2.0);
            write!(
                out,
                "<line x1=\"{x}\" y1=\"2\" x2=\"{x}\" y2=\"{bottom}\"/>"
            )?;
            match mark {
                Mark::Reset | Mark::Partial => {
                    write!(out, "<circle cx=\"{x}\" cy=\"4\" r=\"3\"/>")?
                }
                Mark::Boot => write!(out, "<path d=\"M{x} 0l4 4l-4 4l-4-4z\"/>")?,
            }
        } else {
            // Many markers over a stretch: a band from the first to the last.
            let (a, b) = (N(x_lo), N(x_hi));
            write!(
                out,
                "<line x1=\"{a}\" y1=\"2\" x2=\"{a}\" y2=\"{bottom}\"/>\
                 <line x1=\"{b}\" y1=\"2\" x2=\"{b}\" y2=\"{bottom}\"/>\
                 <rect x=\"{a}\" y=\"1\" width=\"{}\" height=\"4\"/>",
                N(x_hi - x_lo)
            )?;
        }
        out.push_str("</g>\n");
    }
    Ok(())
}

/// The legend: classes drawn in this panel, then the marker kinds.
fn write_legend(out: &mut String, lanes: &[Lane<'_>], y: f64) -> Result<f64, fmt::Error> {
    let mut classes = [false; LEGEND_ORDER.len()];
    let (mut merged, mut open) = (false, false);
    let mut marks = [false; 3];
    for lane in lanes {
        for bar in &lane.bars.bars {
            if let Some(c) = classes.get_mut(class_index(bar.class())) {
                *c = true;
            }
            merged |= bar.count > 1;
            open |= bar.open > 0;
        }
        if let Some(m) = &lane.marks {
            for (seen, c) in marks.iter_mut().zip(&m.marks) {
                *seen |= !c.items.is_empty();
            }
        }
    }
    let y0 = y;
    let mut x = 10.0;
    let mut y = y;
    let mut item = |out: &mut String, glyph: String, text: &str| -> fmt::Result {
        let w = 16.0 + text.chars().count() as f64 * 5.8 + 14.0;
        if x + w > WIDTH - 10.0 {
            x = 10.0;
            y += 18.0;
        }
        writeln!(
            out,
            "<g transform=\"translate({},{})\">{glyph}<text x=\"16\" y=\"9\">{text}</text></g>",
            N(x),
            N(y)
        )?;
        x += w;
        Ok(())
    };
    out.push_str("<g class=\"legend\">\n");
    for (class, _) in LEGEND_ORDER.iter().zip(classes).filter(|(_, seen)| *seen) {
        item(
            out,
            format!(
                "<rect class=\"b c-{}\" width=\"11\" height=\"{}\"/>",
                class.slug(),
                N(BAR_H)
            ),
            &match class {
                // 0x00xx other than 0x0000: an error, not a reset marker.
                Class::Reset => "00xx (not a reset)".to_string(),
                c => c.slug().replace('_', " "),
            },
        )?;
    }
    if open {
        item(
            out,
            format!(
                "<rect class=\"b o c-generic\" width=\"5\" height=\"{}\"/><path class=\"oe\" d=\"M6 -1l6 5.5l-6 5.5z\"/>",
                N(BAR_H)
            ),
            "still active at end",
        )?;
    }
    if merged {
        item(
            out,
            format!(
                "<rect class=\"b m c-generic\" width=\"11\" height=\"{}\"/>",
                N(BAR_H)
            ),
            "merged short errors",
        )?;
    }
    for (mark, _) in MARKS.iter().zip(marks).filter(|(_, seen)| *seen) {
        let glyph = match mark {
            Mark::Reset | Mark::Partial => {
                "<line x1=\"5\" y1=\"-1\" x2=\"5\" y2=\"11\"/><circle cx=\"5\" cy=\"1\" r=\"3\"/>"
            }
            Mark::Boot => {
                "<line x1=\"5\" y1=\"-1\" x2=\"5\" y2=\"11\"/><path d=\"M5 -3l4 4l-4 4l-4-4z\"/>"
            }
        };
        let text = match mark {
            Mark::Reset => "reset",
            Mark::Partial => "partial reset",
            Mark::Boot => "boot-up",
        };
        item(
            out,
            format!("<g class=\"mk {}\">{glyph}</g>", mark.css()),
            text,
        )?;
    }
    out.push_str("</g>\n");
    Ok(y - y0 + 18.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ts(s: &str) -> Timestamp {
        Timestamp::parse(s.as_bytes()).expect("timestamp")
    }

    #[test]
    fn wall_clock_is_utc_and_exact() {
        assert_eq!(
            wall_clock(ts("1700000001.250000")),
            ("2023-11-14".to_string(), "22:13:21.250000".to_string())
        );
        assert_eq!(
            wall_clock(ts("0")),
            ("1970-01-01".to_string(), "00:00:00".to_string())
        );
        // A leap day, and nanosecond digits kept.
        assert_eq!(
            wall_clock(ts("951782400.000000001")),
            ("2000-02-29".to_string(), "00:00:00.000000001".to_string())
        );
        assert_eq!(civil_from_days(19_675), (2023, 11, 14));
    }

    #[test]
    fn ticks_are_round() {
        assert_eq!(nice_step(0.26), 0.5);
        assert_eq!(nice_step(3.0), 5.0);
        assert_eq!(nice_step(0.0), 1.0);
        assert_eq!(tick_step(Axis::Wall, 7.0), 1.0);
        assert_eq!(tick_step(Axis::Wall, 3000.0), 600.0);
        assert_eq!(tick_step(Axis::Lines, 3.0), 1.0);
        assert_eq!(
            tick_label(Axis::Wall, 1_700_000_001.5, 0.5, true),
            "22:13:21.5"
        );
        assert_eq!(tick_label(Axis::Wall, 1_700_000_040.0, 60.0, true), "22:14");
        assert_eq!(
            tick_label(Axis::Wall, 1_700_000_040.0, 600.0, false),
            "11-14 22:14"
        );
        assert_eq!(tick_label(Axis::Seconds, 2.0, 0.5, true), "2.0");
        assert_eq!(tick_label(Axis::Seconds, 12.0, 2.0, true), "12");
    }

    #[test]
    fn numbers_and_escapes() {
        assert_eq!(N(170.0).to_string(), "170");
        assert_eq!(N(387.74).to_string(), "387.7");
        assert_eq!(N(-0.04).to_string(), "0");
        assert_eq!(N(-2.55).to_string(), "-2.6");
        assert_eq!(N(f64::NAN).to_string(), "0");
        assert_eq!(esc("can0"), "can0");
        assert_eq!(esc("a<b>&\"'"), "a&lt;b&gt;&amp;&quot;&#39;");
        assert_eq!(esc("x\u{1b}y\nz"), "x\\u{1b}y\nz");
        assert_eq!(clip("abcdef", 4), "abc…");
    }

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
