//! The chart's time scale (its horizontal axis; "axis" alone means a CiA
//! 402 drive elsewhere): what it measures ([`Measure`]), how positions
//! become scale values and readable times ([`Clock`]), the calendar of
//! wall-clock times, tick spacing and labels, and drawing the scale's line,
//! grid and ticks. Kept together because tick labels and tooltip times must
//! agree on the clock.

use std::fmt::{self, Write as _};

use super::style::{LANES_TOP, PLOT_W, X0, X1};
use super::text::N;
use crate::report::timefmt::utc_date;
use crate::timeline::At;
use crate::trace::Timestamp;

/// Maps axis values to x pixels.
#[derive(Clone, Copy)]
pub(super) struct Scale {
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// The last frame of the input.
    pub(super) end: f64,
}

impl Scale {
    pub(super) fn x(&self, v: f64) -> f64 {
        let v = v.clamp(self.lo, self.hi);
        X0 + (v - self.lo) / (self.hi - self.lo) * PLOT_W
    }
    pub(super) fn per_px(&self) -> f64 {
        (self.hi - self.lo) / PLOT_W
    }
}

/// What the time scale measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Measure {
    /// candump times: Unix seconds, shown as UTC clock times.
    Wall,
    /// ASC times and relative candump times: seconds.
    Seconds,
    /// No timestamps at all (candump screen output without -t): trace lines.
    Lines,
}

/// Converts trace positions to scale values and formats them.
#[derive(Clone, Copy, Debug)]
pub(in crate::report) struct Clock {
    pub(super) measure: Measure,
    /// Time of scale value 0 (timed scales).
    pub(super) origin: Option<Timestamp>,
    /// All times of the input fall on one UTC day (wall clock only).
    pub(super) one_day: bool,
}

impl Measure {
    /// How the HTML page's script names it (`data-axis`).
    pub(super) fn slug(self) -> &'static str {
        match self {
            Measure::Wall => "wall",
            Measure::Seconds => "seconds",
            Measure::Lines => "lines",
        }
    }
}

impl Clock {
    /// The absolute value of axis value 0: ticks fall on round absolute
    /// values (whole seconds of the clock).
    pub(super) fn base(&self) -> f64 {
        match self.measure {
            Measure::Lines => 0.0,
            _ => self.origin.map_or(0.0, Timestamp::as_f64),
        }
    }

    /// Measure value of a position: seconds after the origin, or the line.
    pub(in crate::report) fn value(&self, at: &At) -> Option<f64> {
        match self.measure {
            Measure::Lines => Some(at.line as f64),
            Measure::Wall | Measure::Seconds => Some(at.time?.since(self.origin?).as_f64()),
        }
    }

    /// A time as a reader wants it: `22:13:21.250000 UTC` (the date too when
    /// the trace spans days), `1.250000 s`, or `line 12` without times.
    pub(super) fn at(&self, at: &At) -> String {
        match (self.measure, at.time) {
            (Measure::Lines, _) | (_, None) => format!("line {}", at.line),
            (Measure::Wall, Some(t)) => format!("{} UTC", self.wall(t)),
            (Measure::Seconds, Some(t)) => format!("{t} s"),
        }
    }

    /// The heading of a time column.
    pub(in crate::report) fn heading(&self) -> &'static str {
        match self.measure {
            Measure::Wall => "time (UTC)",
            Measure::Seconds => "time (s)",
            Measure::Lines => "time",
        }
    }

    /// An event's time for the HTML table.
    pub(in crate::report) fn cell(&self, time: Option<Timestamp>) -> String {
        match (self.measure, time) {
            (_, None) => "-".to_string(),
            (Measure::Wall, Some(t)) => self.wall(t),
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
pub(super) fn wall_clock(t: Timestamp) -> (String, String) {
    let (secs, atto, digits) = t.to_raw();
    let c = Utc::of(secs);
    let mut clock = format!("{:02}:{:02}:{:02}", c.hour, c.minute, c.second);
    if digits > 0 {
        let digits = u32::from(digits.min(18));
        let frac = atto / 10u64.pow(18 - digits);
        let _ = write!(clock, ".{frac:0w$}", w = digits as usize);
    }
    (format!("{:04}-{:02}-{:02}", c.year, c.month, c.day), clock)
}

/// Seconds in 400 Gregorian years (146 097 days), after which the calendar
/// repeats itself exactly.
const CYCLE_SECS: u64 = 146_097 * 86_400;

/// A Unix second as a UTC calendar date and clock time.
#[derive(Clone, Copy, Debug)]
struct Utc {
    year: u64,
    month: u8,
    day: u8,
    hour: u8,
    minute: u8,
    second: u8,
}

impl Utc {
    /// The calendar counts years up to 9999; a trace's times can be any
    /// `u64` (nothing stops a candump log from saying
    /// `(99999999999999.5)`), so whole 400-year cycles come off before and
    /// go back onto the year after.
    fn of(secs: u64) -> Utc {
        let cycles = secs / CYCLE_SECS;
        // Below 400 years after 1970: always in the calendar's range.
        let (date, second) =
            utc_date(secs % CYCLE_SECS).unwrap_or((jiff::civil::date(1970, 1, 1), 0));
        Utc {
            year: u64::from(date.year().unsigned_abs()) + 400 * cycles,
            month: date.month().unsigned_abs(),
            day: date.day().unsigned_abs(),
            hour: (second / 3600) as u8,
            minute: (second / 60 % 60) as u8,
            second: (second % 60) as u8,
        }
    }
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

fn tick_step(measure: Measure, span: f64) -> f64 {
    // A tick every 90 px or more: room for a label like 22:13:21.25.
    let raw = span / (PLOT_W / 90.0);
    match measure {
        Measure::Lines => nice_step(raw).max(1.0),
        Measure::Seconds => nice_step(raw),
        Measure::Wall => WALL_STEPS
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

fn tick_label(measure: Measure, value: f64, step: f64, one_day: bool) -> String {
    let d = decimals(step);
    match measure {
        Measure::Lines => format!("{value:.0}"),
        Measure::Seconds => format!("{value:.d$}"),
        Measure::Wall => {
            let scale = 10f64.powi(d as i32);
            let units = (value * scale).round();
            if !(units.is_finite() && units >= 0.0) {
                return String::new();
            }
            let units = units as u64;
            let per = 10u64.pow(d as u32);
            let secs = units / per;
            let frac = units % per;
            let Utc {
                month: m,
                day,
                hour: h,
                minute: min,
                second: s,
                ..
            } = Utc::of(secs);
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

pub(super) fn write_time_scale(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    line_y: f64,
) -> fmt::Result {
    let span = scale.hi - scale.lo;
    let step = tick_step(clock.measure, span);
    let base = clock.base();
    let first = ((base + scale.lo) / step).ceil() * step;
    // Classed so the HTML page's script can redraw the ticks it zooms.
    out.push_str("<g class=\"ax\">\n");
    writeln!(
        out,
        "<line class=\"axis\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
        N(X0),
        N(line_y),
        N(X1),
        N(line_y)
    )?;
    out.push_str("<g class=\"ticks\">\n");
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
            N(line_y + 4.0),
            N(line_y + 16.0),
            tick_label(clock.measure, abs, step, clock.one_day),
            x = N(x),
        )?;
    }
    out.push_str("</g>\n");
    let x = N(scale.x(scale.end));
    writeln!(
        out,
        "<line class=\"end\" x1=\"{x}\" y1=\"{}\" x2=\"{x}\" y2=\"{}\"><title>last frame of the trace</title></line>",
        N(LANES_TOP),
        N(line_y)
    )?;
    let caption = match clock.measure {
        Measure::Wall => "time (UTC)",
        Measure::Seconds => "time (s)",
        Measure::Lines => "trace line",
    };
    writeln!(
        out,
        "<text class=\"cap\" x=\"{}\" y=\"{}\">{caption}</text>",
        N(X1),
        N(line_y + 30.0)
    )?;
    out.push_str("</g>\n");
    Ok(())
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
    }

    /// Dates and clock times at the calendar's edges, each second before
    /// and after where it matters.
    #[test]
    fn wall_clock_at_calendar_edges() {
        let wall = |t: &str| {
            let (date, clock) = wall_clock(ts(t));
            format!("{date} {clock}")
        };
        assert_eq!(wall("0"), "1970-01-01 00:00:00");
        assert_eq!(wall("0.000000"), "1970-01-01 00:00:00.000000");
        assert_eq!(wall("86399.999999"), "1970-01-01 23:59:59.999999");
        assert_eq!(wall("946684799.999999"), "1999-12-31 23:59:59.999999");
        assert_eq!(wall("946684800"), "2000-01-01 00:00:00");
        // 2000 is a leap year (divisible by 400), 2100 is not (by 100).
        assert_eq!(wall("951782399"), "2000-02-28 23:59:59");
        assert_eq!(wall("951782400"), "2000-02-29 00:00:00");
        assert_eq!(wall("951868799"), "2000-02-29 23:59:59");
        assert_eq!(wall("1709251199.5"), "2024-02-29 23:59:59.5");
        assert_eq!(wall("1709251200"), "2024-03-01 00:00:00");
        assert_eq!(wall("4107542399"), "2100-02-28 23:59:59");
        assert_eq!(wall("4107542400"), "2100-03-01 00:00:00");
        // A 30-day month has no 31st.
        assert_eq!(wall("1682899199"), "2023-04-30 23:59:59");
        assert_eq!(wall("1682899200"), "2023-05-01 00:00:00");
        // All 18 fraction digits kept.
        assert_eq!(
            wall("253402300799.999999999999999999"),
            "9999-12-31 23:59:59.999999999999999999"
        );
        // Past `time`'s calendar: whole 400-year cycles.
        assert_eq!(wall("253402300800"), "10000-01-01 00:00:00");
        assert_eq!(wall("12622780799"), "2369-12-31 23:59:59");
        assert_eq!(wall("12622780800"), "2370-01-01 00:00:00");
        assert_eq!(
            wall("18446744073709551615.5"),
            "584554051223-11-09 07:00:15.5"
        );
    }

    #[test]
    fn tick_labels_at_calendar_edges() {
        let day = 86_400.0;
        assert_eq!(tick_label(Measure::Wall, 0.0, day, false), "01-01");
        assert_eq!(
            tick_label(Measure::Wall, 951_782_400.0, day, false),
            "02-29"
        );
        assert_eq!(
            tick_label(Measure::Wall, 4_107_542_400.0, day, false),
            "03-01"
        );
        assert_eq!(
            tick_label(Measure::Wall, 946_684_799.0, 1.0, true),
            "23:59:59"
        );
        assert_eq!(
            tick_label(Measure::Wall, 1_682_899_140.0, 600.0, false),
            "04-30 23:59"
        );
        assert_eq!(
            tick_label(Measure::Wall, 253_402_300_799.5, 0.5, true),
            "23:59:59.5"
        );
        assert_eq!(
            tick_label(Measure::Wall, 253_402_300_800.0, 3600.0, false),
            "01-01 00:00"
        );
    }

    #[test]
    fn ticks_are_round() {
        assert_eq!(nice_step(0.26), 0.5);
        assert_eq!(nice_step(3.0), 5.0);
        assert_eq!(nice_step(0.0), 1.0);
        assert_eq!(tick_step(Measure::Wall, 7.0), 1.0);
        assert_eq!(tick_step(Measure::Wall, 3000.0), 600.0);
        assert_eq!(tick_step(Measure::Lines, 3.0), 1.0);
        assert_eq!(
            tick_label(Measure::Wall, 1_700_000_001.5, 0.5, true),
            "22:13:21.5"
        );
        assert_eq!(
            tick_label(Measure::Wall, 1_700_000_040.0, 60.0, true),
            "22:14"
        );
        assert_eq!(
            tick_label(Measure::Wall, 1_700_000_040.0, 600.0, false),
            "11-14 22:14"
        );
        assert_eq!(tick_label(Measure::Seconds, 2.0, 0.5, true), "2.0");
        assert_eq!(tick_label(Measure::Seconds, 12.0, 2.0, true), "12");
    }
}
