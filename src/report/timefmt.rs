//! How the table shows times (`--time`): candump's Unix times as UTC
//! ISO-8601 by default, ASC's seconds since measurement start as written.

use std::cell::{Cell, RefCell};
use std::io::Write;

use crate::trace::{Span, Timestamp};

/// `--time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TimeStyle {
    /// ISO-8601 UTC for Unix times (after 2001-09-09), else seconds as written
    #[default]
    Auto,
    /// Seconds exactly as the trace wrote them
    Absolute,
    /// Seconds since the input's first reported event
    Relative,
    /// ISO-8601 UTC, every time taken as Unix time
    Iso,
    /// As `Auto`, in this time zone with its offset (`+01:00`), daylight
    /// saving time followed (`--time local`, `--tz ZONE`). The zone is made
    /// once per run, hence `'static`: the style stays `Copy`.
    Local(&'static jiff::tz::TimeZone),
}

/// Times from 10^9 s (2001-09-09) on are taken for Unix time: no relative
/// trace clock (ASC, candump -td/-tz) runs for 31 years.
pub(crate) const UNIX_FROM: u64 = 1_000_000_000;

/// A style and, for `relative`, the origin of the current input.
#[derive(Clone, Debug, Default)]
pub struct TimeFormat {
    pub style: TimeStyle,
    pub origin: Option<Timestamp>,
    /// `YYYY-MM-DDTHH:MM:SS` of the last second shown: consecutive events
    /// share it, and the calendar arithmetic is the costly part.
    iso_second: Cell<Option<(u64, [u8; 19])>>,
    /// The text being built by [`TimeFormat::push`], kept for its capacity.
    scratch: RefCell<Vec<u8>>,
    /// Dated times without their date (`22:13:21.250000Z`): a table whose
    /// times all fall on one day says the day once, in its title
    /// ([`SameDay`]), and gives the columns to what differs.
    pub without_date: bool,
}

/// 9999-12-31T23:59:59Z: the last second the calendar writes.
const LAST_ISO_SECOND: u64 = 253_402_300_799;

/// `YYYY-MM-DDT`: what a dated time loses without its date.
pub const DATE_WIDTH: usize = 11;

impl TimeFormat {
    pub fn new(style: TimeStyle) -> Self {
        TimeFormat {
            style,
            origin: None,
            iso_second: Cell::new(None),
            scratch: RefCell::new(Vec::new()),
            without_date: false,
        }
    }

    /// The day `t` is shown on, numbered from 1970-01-01 in the style's
    /// zone; `None` when the style shows it with no date (seconds).
    pub fn day(&self, t: Timestamp) -> Option<u64> {
        let secs = t.secs();
        if secs > LAST_ISO_SECOND {
            return None;
        }
        match self.style {
            TimeStyle::Absolute | TimeStyle::Relative => None,
            TimeStyle::Auto | TimeStyle::Local(_) if secs < UNIX_FROM => None,
            TimeStyle::Auto | TimeStyle::Iso => Some(secs / SECS_PER_DAY),
            TimeStyle::Local(zone) => {
                let unix = i64::try_from(secs).ok()?;
                let offset = zone
                    .to_offset(jiff::Timestamp::from_second(unix).ok()?)
                    .seconds();
                let local = u64::try_from(unix.checked_add(i64::from(offset))?).ok()?;
                Some(local / SECS_PER_DAY)
            }
        }
    }

    /// The first time of an input (relative times count from it).
    pub fn set_origin(&mut self, t: Option<Timestamp>) {
        if self.origin.is_none() {
            self.origin = t;
        }
    }

    pub fn show(&self, t: Timestamp) -> String {
        let mut s = String::new();
        self.push(&mut s, t);
        s
    }

    pub fn show_opt(&self, t: Option<Timestamp>) -> String {
        let mut s = String::new();
        self.push_opt(&mut s, t);
        s
    }

    /// Appends what [`TimeFormat::show`] gives, without allocating (the
    /// table's hot path: a time per event and two per error).
    pub fn push(&self, out: &mut String, t: Timestamp) {
        let mut own = Vec::new();
        let mut scratch = self.scratch.try_borrow_mut();
        let text = match &mut scratch {
            Ok(s) => &mut **s,
            Err(_) => &mut own,
        };
        text.clear();
        match self.style {
            TimeStyle::Absolute => t.push_decimal(text),
            TimeStyle::Auto | TimeStyle::Local(_) if t.secs() < UNIX_FROM => t.push_decimal(text),
            TimeStyle::Local(zone) => {
                if !push_zoned(text, t, zone) {
                    t.push_decimal(text);
                }
            }
            TimeStyle::Auto | TimeStyle::Iso => {
                if !self.push_iso(text, t) {
                    t.push_decimal(text);
                }
            }
            TimeStyle::Relative => match self.origin {
                Some(o) => t.push_since(o, text),
                None => t.push_decimal(text),
            },
        }
        // Only a dated time has a `T` at DATE_WIDTH - 1: seconds never do.
        let text = match text.get(DATE_WIDTH - 1) {
            Some(b'T') if self.without_date => &text[DATE_WIDTH..],
            _ => &text[..],
        };
        // Digits, `-`, `.`, `:`, `T` and `Z` only.
        out.push_str(std::str::from_utf8(text).unwrap_or_default());
    }

    /// The columns [`TimeFormat::show`] takes for `t`, counted without
    /// writing it where the style allows (ISO-8601 UTC: a fixed shape).
    pub fn width(&self, t: Timestamp) -> usize {
        let iso = match self.style {
            TimeStyle::Iso => true,
            TimeStyle::Auto => t.secs() >= UNIX_FROM,
            _ => false,
        };
        if iso && t.secs() <= LAST_ISO_SECOND {
            let (_, _, digits) = t.to_raw();
            let digits = usize::from(digits).min(crate::trace::time::MAX_FRACTION_DIGITS);
            // `YYYY-MM-DDTHH:MM:SS`, `.` and the digits, `Z`.
            let date = if self.without_date { 0 } else { DATE_WIDTH };
            return date + 8 + if digits == 0 { 0 } else { digits + 1 } + 1;
        }
        let mut s = String::new();
        self.push(&mut s, t);
        s.len()
    }

    /// [`TimeFormat::push`], `-` for no time.
    pub fn push_opt(&self, out: &mut String, t: Option<Timestamp>) {
        match t {
            Some(t) => self.push(out, t),
            None => out.push('-'),
        }
    }
}

impl TimeFormat {
    /// `2023-11-14T22:13:21.250000Z`, with the trace's fraction digits;
    /// `false` (nothing written) beyond the calendar.
    fn push_iso(&self, out: &mut Vec<u8>, t: Timestamp) -> bool {
        let (secs, atto, digits) = t.to_raw();
        let second = match self.iso_second.get() {
            Some((s, text)) if s == secs => text,
            _ => {
                let Some(text) = calendar_second(secs) else {
                    return false;
                };
                self.iso_second.set(Some((secs, text)));
                text
            }
        };
        out.extend_from_slice(&second);
        // The fraction exactly as the trace wrote it: `secs.frac`.
        crate::trace::time::push_fraction(out, atto, digits);
        out.push(b'Z');
        true
    }
}

/// `2023-11-14T23:13:21.250000+01:00`: the wall clock in `zone` at `t`,
/// with the trace's fraction digits and the zone's offset then (jiff reads
/// the zone's rules, so a trace across a DST change shows both offsets);
/// `false` (nothing written) beyond the calendar.
fn push_zoned(out: &mut Vec<u8>, t: Timestamp, zone: &jiff::tz::TimeZone) -> bool {
    let (secs, atto, digits) = t.to_raw();
    let Some(unix) = i64::try_from(secs).ok() else {
        return false;
    };
    let Ok(instant) = jiff::Timestamp::from_second(unix) else {
        return false;
    };
    let offset = zone.to_offset(instant).seconds();
    let Some(local) = unix
        .checked_add(i64::from(offset))
        .and_then(|s| u64::try_from(s).ok())
        .and_then(calendar_second)
    else {
        return false;
    };
    out.extend_from_slice(&local);
    crate::trace::time::push_fraction(out, atto, digits);
    let sign = if offset < 0 { '-' } else { '+' };
    let abs = offset.unsigned_abs();
    let _ = write!(out, "{sign}{:02}:{:02}", abs / 3600, abs / 60 % 60);
    true
}

/// Whether every time a table shows falls on one day, and which: the
/// table then says the day once in its title and shows times of day.
#[derive(Clone, Copy, Debug, Default)]
pub struct SameDay {
    /// The day and a time on it, while every time seen was on it.
    day: Option<(u64, Timestamp)>,
    /// A time on another day, or one shown without a date, was seen.
    mixed: bool,
}

impl SameDay {
    pub fn see(&mut self, times: &TimeFormat, t: Timestamp) {
        match (times.day(t), self.day) {
            (None, _) => self.mixed = true,
            (Some(d), None) => self.day = Some((d, t)),
            (Some(d), Some((seen, _))) => self.mixed |= d != seen,
        }
    }

    /// `2023-11-14` when every time seen (at least one) was on that day.
    pub fn day(&self, times: &TimeFormat) -> Option<String> {
        let (_, t) = self.day.filter(|_| !self.mixed)?;
        let mut full = TimeFormat::new(times.style);
        full.origin = times.origin;
        let text = full.show(t);
        text.get(..DATE_WIDTH - 1).map(str::to_string)
    }
}

/// `YYYY-MM-DDTHH:MM:SS` of a Unix second; `None` beyond the calendar.
pub(crate) fn calendar_second(secs: u64) -> Option<[u8; 19]> {
    let (date, second) = utc_date(secs)?;
    let mut text = *b"0000-00-00T00:00:00";
    // `utc_date` gives years 1970 to 9999: always four digits.
    let year = u32::try_from(date.year()).ok()?;
    for (at, value, width) in [
        (0, year, 4),
        (5, u32::from(date.month().unsigned_abs()), 2),
        (8, u32::from(date.day().unsigned_abs()), 2),
        (11, second / 3600, 2),
        (14, second / 60 % 60, 2),
        (17, second % 60, 2),
    ] {
        let mut rest = value;
        for d in text[at..at + width].iter_mut().rev() {
            *d = b'0' + (rest % 10) as u8;
            rest /= 10;
        }
    }
    Some(text)
}

/// Seconds in a UTC day: Unix time has no leap seconds.
const SECS_PER_DAY: u64 = 86_400;

/// The UTC date of a Unix second and the second of that day; `None` after
/// 9999-12-31, where the calendar ends.
pub(crate) fn utc_date(secs: u64) -> Option<(jiff::civil::Date, u32)> {
    const UNIX_EPOCH: jiff::civil::Date = jiff::civil::date(1970, 1, 1);
    let days = i64::try_from(secs / SECS_PER_DAY).ok()?;
    let date = UNIX_EPOCH
        .checked_add(jiff::Span::new().try_days(days).ok()?)
        .ok()?;
    Some((date, (secs % SECS_PER_DAY) as u32))
}

/// A duration as a person reads it, with the digits that matter: `1 s`,
/// `1.44 s`, `1.002 s`, `100 ms`, `12.5 ms`: seconds to the millisecond
/// from one second up, milliseconds to the microsecond below, trailing
/// zeros dropped. For the table's periods and timeouts, whose trace
/// precision (`1.000000`) says nothing; JSON keeps the numbers.
pub(crate) fn human_span(span: Span) -> String {
    let attos = span.attos();
    let sign = if attos < 0 { "-" } else { "" };
    let attos = attos.unsigned_abs();
    const ATTO_PER_MS: u128 = 1_000_000_000_000_000;
    let (unit, scale, digits) = if attos >= 1000 * ATTO_PER_MS {
        ("s", 1000 * ATTO_PER_MS, 3u32)
    } else {
        ("ms", ATTO_PER_MS, 3u32)
    };
    let step = scale / 10u128.pow(digits);
    // Rounded to the last digit shown, half away from zero.
    let rounded = (attos + step / 2) / step;
    let whole = rounded / 10u128.pow(digits);
    let frac = rounded % 10u128.pow(digits);
    let mut text = format!("{sign}{whole}");
    if frac > 0 {
        let f = format!("{frac:0width$}", width = digits as usize);
        text.push('.');
        text.push_str(f.trim_end_matches('0'));
    }
    format!("{text} {unit}")
}

#[cfg(test)]
mod tests {

    #[test]
    fn human_spans_show_the_digits_that_matter() {
        use super::human_span;
        use crate::trace::{Span, Timestamp};
        let ms = |n| human_span(Span::from_millis(n));
        assert_eq!(ms(1000), "1 s");
        assert_eq!(ms(1440), "1.44 s");
        assert_eq!(ms(100), "100 ms");
        assert_eq!(ms(4200), "4.2 s");
        assert_eq!(ms(0), "0 ms");
        let t = |text: &str| Timestamp::parse(text.as_bytes()).expect("a time");
        // Trace precision is not shown: 1.000000 s is 1 s.
        assert_eq!(human_span(t("2.000000").since(t("1.000000"))), "1 s");
        assert_eq!(human_span(t("1.0016").since(t("0"))), "1.002 s");
        assert_eq!(human_span(t("0.0125").since(t("0"))), "12.5 ms");
        assert_eq!(human_span(t("0").since(t("0.25"))), "-250 ms");
    }

    #[test]
    fn one_day_shows_times_without_the_date_and_the_day_once() {
        let mut f = TimeFormat::new(TimeStyle::Auto);
        let mut day = SameDay::default();
        day.see(&f, ts("1700000001.250000"));
        day.see(&f, ts("1700003600"));
        assert_eq!(day.day(&f).as_deref(), Some("2023-11-14"));
        f.without_date = true;
        assert_eq!(f.show(ts("1700000001.250000")), "22:13:21.250000Z");
        assert_eq!(f.width(ts("1700000001.250000")), 16);
        // Seconds, which have no date, are shown whole.
        assert_eq!(f.show(ts("12.5")), "12.5");
        // The next day, or a time without a date: no one day.
        let mut two = day;
        two.see(&f, ts("1700100000"));
        assert_eq!(two.day(&f), None);
        let mut seconds = day;
        seconds.see(&f, ts("12.5"));
        assert_eq!(seconds.day(&f), None);
        assert_eq!(SameDay::default().day(&f), None);
        let relative = TimeFormat::new(TimeStyle::Relative);
        let mut none = SameDay::default();
        none.see(&relative, ts("1700000001"));
        assert_eq!(none.day(&relative), None);
        // A zone's day: 23:30 UTC is the next day in Berlin.
        let berlin: &'static jiff::tz::TimeZone =
            Box::leak(Box::new(jiff::tz::TimeZone::get("Europe/Berlin").unwrap()));
        let mut local = TimeFormat::new(TimeStyle::Local(berlin));
        let mut day = SameDay::default();
        day.see(&local, ts("1700004600"));
        assert_eq!(day.day(&local).as_deref(), Some("2023-11-15"));
        local.without_date = true;
        assert_eq!(local.show(ts("1700004600")), "00:30:00+01:00");
    }

    #[test]
    fn widths_are_the_shown_lengths() {
        let times = [
            "1700000001.250000",
            "1700000001",
            "1700000001.123456789",
            "1700000001.5",
            "12.5",
            "999999999.000",
            "253402300799.1",
            "253402300800.1",
            "99999999999999.123",
        ];
        for style in [
            TimeStyle::Auto,
            TimeStyle::Absolute,
            TimeStyle::Relative,
            TimeStyle::Iso,
        ] {
            for without_date in [false, true] {
                let mut f = TimeFormat::new(style);
                f.set_origin(Some(ts("1.0")));
                f.without_date = without_date;
                for t in times {
                    assert_eq!(
                        f.width(ts(t)),
                        f.show(ts(t)).len(),
                        "{style:?} {t} without_date {without_date}"
                    );
                }
            }
        }
    }

    #[test]
    fn local_times_carry_the_zone_offset_of_their_instant() {
        let berlin: &'static jiff::tz::TimeZone =
            Box::leak(Box::new(jiff::tz::TimeZone::get("Europe/Berlin").unwrap()));
        let f = TimeFormat::new(TimeStyle::Local(berlin));
        // 2023-11-14 is winter time (+01:00); 2023-07-01 summer (+02:00).
        assert_eq!(
            f.show(ts("1700000001.250000")),
            "2023-11-14T23:13:21.250000+01:00"
        );
        assert_eq!(f.show(ts("1688169600.5")), "2023-07-01T02:00:00.5+02:00");
        // Not Unix times (an ASC clock): as written, as for auto.
        assert_eq!(f.show(ts("12.5")), "12.5");
        let west: &'static jiff::tz::TimeZone = Box::leak(Box::new(
            jiff::tz::TimeZone::get("America/St_Johns").unwrap(),
        ));
        let f = TimeFormat::new(TimeStyle::Local(west));
        assert_eq!(f.show(ts("1700000000")), "2023-11-14T18:43:20-03:30");
    }

    use super::*;

    fn ts(s: &str) -> Timestamp {
        Timestamp::parse(s.as_bytes()).unwrap()
    }

    #[test]
    fn auto_shows_unix_times_as_iso_and_others_as_written() {
        let f = TimeFormat::new(TimeStyle::Auto);
        assert_eq!(
            f.show(ts("1700000001.250000")),
            "2023-11-14T22:13:21.250000Z"
        );
        assert_eq!(f.show(ts("1700000001")), "2023-11-14T22:13:21Z");
        assert_eq!(f.show(ts("12.500")), "12.500");
        assert_eq!(f.show(ts("999999999.9")), "999999999.9");
    }

    #[test]
    fn iso_and_absolute_are_forced() {
        assert_eq!(
            TimeFormat::new(TimeStyle::Iso).show(ts("0.5")),
            "1970-01-01T00:00:00.5Z"
        );
        assert_eq!(
            TimeFormat::new(TimeStyle::Absolute).show(ts("1700000001.250000")),
            "1700000001.250000"
        );
        // Beyond the calendar's range: the seconds as written.
        let huge = Timestamp::from_parts(10u64.pow(15), 1, 1);
        assert_eq!(TimeFormat::new(TimeStyle::Iso).show(huge), huge.to_string());
    }

    #[test]
    fn relative_counts_from_the_first_origin() {
        let mut f = TimeFormat::new(TimeStyle::Relative);
        assert_eq!(f.show(ts("5.0")), "5.0", "no origin yet");
        f.set_origin(Some(ts("1700000001.250000")));
        f.set_origin(Some(ts("1700000009.000000")));
        assert_eq!(f.show(ts("1700000003.000000")), "1.750000");
        assert_eq!(f.show_opt(None), "-");
    }
}
