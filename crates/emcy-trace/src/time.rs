//! Exact trace timestamps.
//!
//! Traces write times as decimal text (`1469439874.299654`, `3.098426`,
//! nanosecond `-N` logs). Users diff our JSON against the trace, so a time is
//! kept exactly as written: an integer count of attoseconds plus the number of
//! fraction digits the trace used, which is how it is printed back. `f64` would
//! round a nanosecond Unix time.

use std::fmt;

/// Seconds in a day.
pub const SECS_PER_DAY: u64 = 86_400;

/// Seconds from the Unix epoch to the UTC midnight that starts a civil
/// (proleptic Gregorian) date; `None` for impossible dates (month 0 or 13,
/// February 29th of a common year, ...), dates before 1970 and years past
/// 9999, which no trace that writes dates (candump `-tA`, BUSMASTER
/// session starts) can mean.
pub fn unix_midnight(year: u64, month: u64, day: u64) -> Option<u64> {
    if !(1970..=9999).contains(&year) {
        return None;
    }
    u64::try_from(days_from_civil(year, month, day)?)
        .ok()?
        .checked_mul(SECS_PER_DAY)
}

/// Days from 1970-01-01 to a civil (proleptic Gregorian) date, negative
/// before it; `None` for a month or a day of the month that does not
/// exist, or a year past 1 000 000 (no trace writes one, and the sums
/// below stay far from overflow).
///
/// The calendar is plain arithmetic (Howard Hinnant's `days_from_civil`):
/// a year counted from March puts the leap day last, so the days before a
/// month follow one formula, and 400 years are always 146 097 days.
pub fn days_from_civil(year: u64, month: u64, day: u64) -> Option<i64> {
    if year > 1_000_000 {
        return None;
    }
    let leap = year.is_multiple_of(4) && (!year.is_multiple_of(100) || year.is_multiple_of(400));
    let month_days = match month {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if leap => 29,
        2 => 28,
        _ => return None,
    };
    if day == 0 || day > month_days {
        return None;
    }
    // Both checked above: small enough for any sum below.
    let (year, month, day) = (year as i64, month as i64, day as i64);
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let year_of_era = y - era * 400;
    let day_of_year = (153 * ((month + 9) % 12) + 2) / 5 + day - 1;
    let day_of_era = year_of_era * 365 + year_of_era / 4 - year_of_era / 100 + day_of_year;
    // 719 468 days from 0000-03-01 to 1970-01-01.
    Some(era * 146_097 + day_of_era - 719_468)
}

/// Most fraction digits a timestamp may carry (attosecond resolution).
pub const MAX_FRACTION_DIGITS: usize = 18;

const ATTO_PER_SEC: u128 = 1_000_000_000_000_000_000;

/// A point in time: seconds since the trace's epoch (Unix time for candump,
/// measurement start for ASC), exact to the digits the trace wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Timestamp {
    // Two u64 rather than one u128: half the size (frames carrying a time
    // are moved on the hot path), same exactness.
    secs: u64,
    /// Attoseconds within the second, < 10^18.
    atto: u64,
    digits: u8,
}

/// A signed difference of two timestamps (an error's duration).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Span {
    atto: i128,
    digits: u8,
}

/// A span that is not negative, split into whole seconds and the
/// attoseconds below them, to add to many times ([`Timestamp::checked_add_step`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    secs: u64,
    /// < 10^18.
    atto: u64,
    digits: u8,
}

/// A time as the integer its digits spell with the dot left out
/// (`1700000000.000100` is 1 700 000 000 000 100 with 6 digits): what a
/// reader's fixed layout yields in a few word operations, where a
/// [`Timestamp`] costs about 150 instructions a line (callgrind, a
/// heartbeat trace). Times of one layout carry the same digits, so their
/// values compare and subtract as the times do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ticks {
    /// The count of units of 10^-`digits` seconds.
    pub value: u64,
    /// Fraction digits, at most [`MAX_FRACTION_DIGITS`].
    pub digits: u8,
}

impl Ticks {
    /// `value` with `digits` fraction digits; `None` past 18 of them.
    pub fn new(value: u64, digits: u8) -> Option<Ticks> {
        (usize::from(digits) <= MAX_FRACTION_DIGITS).then_some(Ticks { value, digits })
    }

    /// The time these ticks are.
    pub fn timestamp(self) -> Timestamp {
        let digits = self.digits.min(MAX_FRACTION_DIGITS as u8);
        // candump writes 6 digits: a constant divisor is a multiplication.
        let (secs, frac) = if digits == 6 {
            (self.value / 1_000_000, self.value % 1_000_000)
        } else {
            let unit = pow10(usize::from(digits));
            (self.value / unit, self.value % unit)
        };
        Timestamp {
            secs,
            // frac < 10^digits: the product stays under 10^18.
            atto: frac * pow10(MAX_FRACTION_DIGITS - usize::from(digits)),
            digits,
        }
    }

    /// `n` ticks of this precision in attoseconds.
    pub fn attos(self, n: u64) -> i128 {
        let below = MAX_FRACTION_DIGITS.saturating_sub(usize::from(self.digits));
        i128::from(n) * i128::from(pow10(below))
    }

    /// `n` ticks of this precision in attoseconds when that fits in an
    /// `i64` (under 9.2 s), without 128-bit arithmetic.
    #[inline]
    pub fn attos_i64(self, n: u64) -> Option<i64> {
        let below = MAX_FRACTION_DIGITS.saturating_sub(usize::from(self.digits));
        n.checked_mul(pow10(below))
            .and_then(|a| i64::try_from(a).ok())
    }

    /// `n` ticks of this precision as a span (of these digits, as
    /// [`Timestamp::since`] gives between two times of them).
    pub fn span(self, n: u64) -> Span {
        Span {
            atto: self.attos(n),
            digits: self.digits,
        }
    }
}

/// 10^0 ..= 10^18.
const POW10: [u64; MAX_FRACTION_DIGITS + 1] = {
    let mut t = [1u64; MAX_FRACTION_DIGITS + 1];
    let mut i = 1;
    while i < t.len() {
        t[i] = t[i - 1] * 10;
        i += 1;
    }
    t
};

fn pow10(n: usize) -> u64 {
    POW10[n.min(MAX_FRACTION_DIGITS)]
}

impl Timestamp {
    /// Second zero with no fraction digits.
    pub const ZERO: Timestamp = Timestamp {
        secs: 0,
        atto: 0,
        digits: 0,
    };

    fn total(self) -> u128 {
        u128::from(self.secs) * ATTO_PER_SEC + u128::from(self.atto)
    }

    /// From total attoseconds; `None` beyond u64 seconds.
    fn from_total(total: u128, digits: u8) -> Option<Timestamp> {
        Some(Timestamp {
            secs: u64::try_from(total / ATTO_PER_SEC).ok()?,
            atto: (total % ATTO_PER_SEC) as u64,
            digits,
        })
    }

    /// Parses `int` `.` `frac` where both are ASCII digit strings (the caller
    /// has split at the dot). `frac` may be empty (no dot). Leading zeros of the
    /// integer part are accepted (`-tz` writes `000.123456`).
    pub fn from_decimal(int: &[u8], frac: &[u8]) -> Result<Timestamp, &'static str> {
        if int.is_empty() {
            return Err("timestamp has no integer part");
        }
        if frac.len() > MAX_FRACTION_DIGITS {
            return Err("timestamp has more than 18 fraction digits");
        }
        let mut secs: u64 = 0;
        for &b in int {
            let d = digit(b).ok_or("timestamp is not a decimal number")?;
            secs = secs
                .checked_mul(10)
                .and_then(|s| s.checked_add(u64::from(d)))
                .ok_or("timestamp seconds overflow 64 bits")?;
        }
        let mut f: u64 = 0;
        for &b in frac {
            let d = digit(b).ok_or("timestamp is not a decimal number")?;
            f = f * 10 + u64::from(d);
        }
        Ok(Timestamp::from_parts(secs, f, frac.len() as u8))
    }

    /// As [`Ticks`] of its own precision; `None` when they overflow.
    pub fn ticks(self) -> Option<Ticks> {
        let digits = usize::from(self.digits);
        let value = self
            .secs
            .checked_mul(pow10(digits))?
            .checked_add(self.atto / pow10(MAX_FRACTION_DIGITS - digits))?;
        Ticks::new(value, self.digits)
    }

    /// Parses `123`, `123.456` (the whole text must be the number).
    pub fn parse(text: &[u8]) -> Result<Timestamp, &'static str> {
        match memchr::memchr(b'.', text) {
            Some(dot) => {
                let frac = text.get(dot + 1..).unwrap_or_default();
                if frac.is_empty() {
                    return Err("timestamp ends with a dot");
                }
                Timestamp::from_decimal(&text[..dot], frac)
            }
            None => Timestamp::from_decimal(text, &[]),
        }
    }

    /// From whole seconds plus a fraction written with `digits` digits.
    /// `frac` must have at most `digits` digits (larger values are reduced).
    pub fn from_parts(secs: u64, frac: u64, digits: u8) -> Timestamp {
        let digits = digits.min(MAX_FRACTION_DIGITS as u8);
        let scale = pow10(MAX_FRACTION_DIGITS - usize::from(digits));
        let limit = pow10(usize::from(digits));
        // Callers pass at most `digits` digits; the check spares a division.
        let frac = if frac >= limit { frac % limit } else { frac };
        Timestamp {
            secs,
            atto: frac * scale,
            digits,
        }
    }

    /// Adds a delta (ASC `timestamps relative`, candump `-td`); the result
    /// keeps the finer of the two precisions. `None` on overflow.
    pub fn checked_add(self, delta: Timestamp) -> Option<Timestamp> {
        let total = self.total().checked_add(delta.total())?;
        Timestamp::from_total(total, self.digits.max(delta.digits))
    }

    /// `self + span` for a span that is not negative (a deadline), at the
    /// finer precision; `None` for a negative span or on overflow.
    pub fn checked_add_span(self, span: Span) -> Option<Timestamp> {
        self.checked_add_step(span.step()?)
    }

    /// `self + step`: [`Timestamp::checked_add_span`] with the span's split
    /// done once (a heartbeat's deadline is its time plus the same timeout,
    /// for every heartbeat). `None` on overflow.
    #[inline]
    pub fn checked_add_step(self, step: Step) -> Option<Timestamp> {
        let mut secs = self.secs.checked_add(step.secs)?;
        let mut atto = self.atto + step.atto;
        if u128::from(atto) >= ATTO_PER_SEC {
            atto -= ATTO_PER_SEC as u64;
            secs = secs.checked_add(1)?;
        }
        Some(Timestamp {
            secs,
            atto,
            digits: self.digits.max(step.digits),
        })
    }

    /// `self - earlier`, negative when the trace's clock went backwards.
    pub fn since(self, earlier: Timestamp) -> Span {
        Span {
            atto: self.total() as i128 - earlier.total() as i128,
            digits: self.digits.max(earlier.digits),
        }
    }

    /// Whole seconds.
    pub fn secs(self) -> u64 {
        self.secs
    }

    /// The parts as stored: (seconds, attoseconds within the second, digits).
    pub fn to_raw(self) -> (u64, u64, u8) {
        (self.secs, self.atto, self.digits)
    }

    /// Inverse of [`Timestamp::to_raw`]; `None` if the parts are out of range.
    pub fn from_raw(secs: u64, atto: u64, digits: u8) -> Option<Timestamp> {
        (u128::from(atto) < ATTO_PER_SEC && usize::from(digits) <= MAX_FRACTION_DIGITS)
            .then_some(Timestamp { secs, atto, digits })
    }

    /// Fraction digits as written in the trace.
    pub fn digits(self) -> u8 {
        self.digits
    }

    /// Seconds as `f64`, for layout only (never for output of values).
    pub fn as_f64(self) -> f64 {
        self.secs as f64 + self.atto as f64 / ATTO_PER_SEC as f64
    }
}

impl PartialOrd for Timestamp {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Timestamp {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        (self.secs, self.atto, self.digits).cmp(&(other.secs, other.atto, other.digits))
    }
}

impl Span {
    /// The value in attoseconds (whatever the digits it is shown with).
    pub fn attos(self) -> i128 {
        self.atto
    }

    /// The span split for adding; `None` when negative or over 2^64 s.
    pub fn step(self) -> Option<Step> {
        let atto = u128::try_from(self.atto).ok()?;
        // Heartbeat timeouts are under a second: no 128-bit division.
        let (secs, atto) = if atto < ATTO_PER_SEC {
            (0, atto as u64)
        } else {
            (
                u64::try_from(atto / ATTO_PER_SEC).ok()?,
                (atto % ATTO_PER_SEC) as u64,
            )
        };
        Some(Step {
            secs,
            atto,
            digits: self.digits,
        })
    }

    /// No time at all.
    pub const ZERO: Span = Span { atto: 0, digits: 0 };

    /// The sum, with the finer precision; `None` on overflow.
    pub fn checked_add(self, other: Span) -> Option<Span> {
        Some(Span {
            atto: self.atto.checked_add(other.atto)?,
            digits: self.digits.max(other.digits),
        })
    }

    /// `ms` milliseconds (an object dictionary time), written with three
    /// fraction digits.
    pub fn from_millis(ms: u64) -> Span {
        Span {
            atto: i128::from(ms) * (ATTO_PER_SEC / 1000) as i128,
            digits: 3,
        }
    }

    /// `us` microseconds (a measured period), written with six fraction
    /// digits; negative for a negative count.
    pub fn from_micros(us: i64) -> Span {
        Span {
            atto: i128::from(us) * (ATTO_PER_SEC / 1_000_000) as i128,
            digits: 6,
        }
    }

    /// `self * num / den` (a margin on a timeout, a multiple of a period),
    /// same precision; `None` for `den == 0` or on overflow.
    pub fn scaled(self, num: i128, den: i128) -> Option<Span> {
        Some(Span {
            atto: self.atto.checked_mul(num)?.checked_div(den)?,
            digits: self.digits,
        })
    }

    /// The later time came first: the trace's clock went backwards.
    pub fn is_negative(self) -> bool {
        self.atto < 0
    }

    /// Seconds as `f64`, for layout only (printing uses the exact digits).
    pub fn as_f64(self) -> f64 {
        self.atto as f64 / ATTO_PER_SEC as f64
    }
}

fn digit(b: u8) -> Option<u8> {
    b.is_ascii_digit().then(|| b - b'0')
}

/// Appends `secs.fraction` with `digits` fraction digits: the one way times
/// and spans become text (JSON, table, `Display`), in 64-bit arithmetic.
fn push_parts(out: &mut Vec<u8>, secs: u64, atto: u64, digits: u8) {
    out.extend_from_slice(itoa::Buffer::new().format(secs).as_bytes());
    push_fraction(out, atto, digits);
}

/// `.fraction` of `atto` attoseconds with `digits` digits (nothing for none).
pub fn push_fraction(out: &mut Vec<u8>, atto: u64, digits: u8) {
    let atto = atto % pow10(MAX_FRACTION_DIGITS);
    // Traces write milli-, micro- or nanoseconds: those widths divide by
    // constants (a multiply) and copy a constant length.
    match digits {
        3 => return push_fraction_of::<3>(out, atto),
        6 => return push_fraction_of::<6>(out, atto),
        9 => return push_fraction_of::<9>(out, atto),
        _ => {}
    }
    let digits = usize::from(digits).min(MAX_FRACTION_DIGITS);
    if digits == 0 {
        return;
    }
    let mut frac = atto / pow10(MAX_FRACTION_DIGITS - digits);
    let mut text = [b'0'; MAX_FRACTION_DIGITS + 1];
    text[0] = b'.';
    for d in text[1..=digits].iter_mut().rev() {
        *d = b'0' + (frac % 10) as u8;
        frac /= 10;
    }
    out.extend_from_slice(&text[..=digits]);
}

/// `"00"` to `"99"`.
const PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// [`push_fraction`] for `D` (at most 9) digits of `atto` (below 10^18).
fn push_fraction_of<const D: usize>(out: &mut Vec<u8>, atto: u64) {
    let mut frac = atto / pow10(MAX_FRACTION_DIGITS - D);
    let mut text = [b'.'; 10];
    let mut at = D + 1;
    while at > 2 {
        let pair = (frac % 100) as usize * 2;
        frac /= 100;
        at -= 2;
        if let (Some(d), Some(p)) = (text.get_mut(at..at + 2), PAIRS.get(pair..pair + 2)) {
            d.copy_from_slice(p);
        }
    }
    if at == 2
        && let Some(d) = text.get_mut(1)
    {
        *d = b'0' + (frac % 10) as u8;
    }
    out.extend_from_slice(text.get(..=D).unwrap_or_default());
}

/// The text of the last whole second written, for the next time: events
/// come in time order, most in the same second as the one before.
#[derive(Clone, Debug, Default)]
pub struct SecondsText {
    secs: u64,
    text: [u8; 20],
    /// 0 until a second is kept.
    len: u8,
}

impl SecondsText {
    fn push(&mut self, out: &mut Vec<u8>, secs: u64) {
        if self.len == 0 || self.secs != secs {
            let mut b = itoa::Buffer::new();
            let digits = b.format(secs).as_bytes();
            if let Some(to) = self.text.get_mut(..digits.len()) {
                to.copy_from_slice(digits);
            }
            self.secs = secs;
            self.len = digits.len() as u8;
        }
        // A constant-size copy cut back (no call for a variable length).
        let keep = out.len() + usize::from(self.len);
        out.extend_from_slice(&self.text);
        out.truncate(keep);
    }
}

impl Timestamp {
    /// Appends the text `Display` writes (the JSON and table hot paths).
    pub fn push_decimal(self, out: &mut Vec<u8>) {
        push_parts(out, self.secs, self.atto, self.digits);
    }

    /// [`Timestamp::push_decimal`], the seconds' text kept in `seconds`.
    pub fn push_decimal_with(self, out: &mut Vec<u8>, seconds: &mut SecondsText) {
        seconds.push(out, self.secs);
        push_fraction(out, self.atto, self.digits);
    }

    /// Appends `self.since(earlier)` as text, without the 128-bit division
    /// of [`Span::push_decimal`] (a duration per error in every report).
    pub fn push_since(self, earlier: Timestamp, out: &mut Vec<u8>) {
        let per_sec = pow10(MAX_FRACTION_DIGITS);
        let (later, sooner, negative) = if (self.secs, self.atto) >= (earlier.secs, earlier.atto) {
            (self, earlier, false)
        } else {
            (earlier, self, true)
        };
        let (secs, atto) = if later.atto >= sooner.atto {
            (later.secs - sooner.secs, later.atto - sooner.atto)
        } else {
            (
                later.secs - sooner.secs - 1,
                later.atto + per_sec - sooner.atto,
            )
        };
        if negative {
            out.push(b'-');
        }
        push_parts(out, secs, atto, self.digits.max(earlier.digits));
    }
}

impl Span {
    /// Appends the text `Display` writes.
    pub fn push_decimal(self, out: &mut Vec<u8>) {
        if self.atto < 0 {
            out.push(b'-');
        }
        let abs = self.atto.unsigned_abs();
        push_parts(
            out,
            (abs / ATTO_PER_SEC) as u64,
            (abs % ATTO_PER_SEC) as u64,
            self.digits,
        );
    }
}

/// Writes what `push` appends (ASCII digits, `-` and `.` only).
fn display(f: &mut fmt::Formatter<'_>, push: impl FnOnce(&mut Vec<u8>)) -> fmt::Result {
    let mut text = Vec::with_capacity(40);
    push(&mut text);
    f.write_str(std::str::from_utf8(&text).map_err(|_| fmt::Error)?)
}

/// Prints as a JSON-compatible decimal number with the trace's digit count.
impl fmt::Display for Timestamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        display(f, |out| self.push_decimal(out))
    }
}

impl fmt::Display for Span {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        display(f, |out| self.push_decimal(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unix_midnights_of_real_dates_only() {
        assert_eq!(unix_midnight(1970, 1, 1), Some(0));
        assert_eq!(unix_midnight(2023, 11, 14), Some(1_699_920_000));
        assert_eq!(unix_midnight(2024, 2, 29), Some(1_709_164_800));
        assert_eq!(unix_midnight(2023, 2, 29), None);
        assert_eq!(unix_midnight(1969, 12, 31), None);
        assert_eq!(unix_midnight(9999, 12, 31), Some(253_402_214_400));
        assert_eq!(unix_midnight(10000, 1, 1), None);
        assert_eq!(unix_midnight(2000, 2, 29), Some(951_782_400));
        assert_eq!(unix_midnight(2100, 2, 29), None);
        assert_eq!(unix_midnight(2023, 4, 31), None);
        assert_eq!(days_from_civil(1969, 12, 31), Some(-1));
        assert_eq!(days_from_civil(0, 3, 1), Some(-719_468));
        assert_eq!(unix_midnight(2023, 13, 1), None);
        assert_eq!(unix_midnight(2023, 0, 1), None);
        assert_eq!(unix_midnight(u64::MAX, 1, 1), None);
    }

    fn ts(s: &str) -> Timestamp {
        Timestamp::parse(s.as_bytes()).unwrap()
    }

    #[test]
    fn prints_exactly_what_was_read() {
        for s in [
            "1469439874.299654",
            "1469439874.299654123",
            "3.098426",
            "0.5",
            "12",
            "18446744073709551615.999999999999999999",
        ] {
            assert_eq!(ts(s).to_string(), s);
        }
    }

    #[test]
    fn spans_print_with_the_finer_precision_and_a_sign() {
        for (a, b, text) in [
            ("2.5", "1.25", "1.25"),
            ("1.0", "2.5", "-1.5"),
            ("3", "3", "0"),
            ("1700000003.000000", "1700000001.250000", "1.750000"),
            (
                "0",
                "18446744073709551615.999999999999999999",
                "-18446744073709551615.999999999999999999",
            ),
        ] {
            let (a, b) = (ts(a), ts(b));
            assert_eq!(a.since(b).to_string(), text);
            let mut v = Vec::new();
            a.push_since(b, &mut v);
            assert_eq!(String::from_utf8(v).unwrap(), text, "push_since");
        }
    }

    #[test]
    fn leading_zeros_are_normalised_for_json() {
        assert_eq!(ts("000.000100").to_string(), "0.000100");
        assert_eq!(ts("015.052211").to_string(), "15.052211");
    }

    #[test]
    fn short_fraction_is_a_fraction_not_microseconds() {
        // candump-parse reads (1.5) as 1 s + 5 us; it is 1.5 s.
        assert_eq!(ts("1.5").as_f64(), 1.5);
    }

    #[test]
    fn rejects_what_is_not_a_number() {
        for s in [
            "",
            ".5",
            "1.",
            "1.2.3",
            "a.1",
            "1.x",
            "-1.0",
            "1.0000000000000000000",
        ] {
            assert!(Timestamp::parse(s.as_bytes()).is_err(), "{s:?}");
        }
        assert_eq!(
            Timestamp::parse(b"18446744073709551616.0"),
            Err("timestamp seconds overflow 64 bits")
        );
    }

    #[test]
    fn relative_times_accumulate_exactly() {
        let t = ts("0.1").checked_add(ts("0.200000")).unwrap();
        assert_eq!(t.to_string(), "0.300000");
        assert!(
            ts("18446744073709551615.0")
                .checked_add(ts("1.0"))
                .is_none()
        );
    }

    #[test]
    fn spans_are_signed() {
        assert_eq!(ts("2.5").since(ts("1.25")).to_string(), "1.25");
        assert_eq!(ts("1.0").since(ts("2.5")).to_string(), "-1.5");
        assert!(ts("1.0").since(ts("2.5")).is_negative());
    }

    #[test]
    fn parts_keep_their_digits() {
        assert_eq!(Timestamp::from_parts(12, 5, 3).to_string(), "12.005");
        assert_eq!(Timestamp::from_parts(0, 0, 0).to_string(), "0");
        assert_eq!(
            Timestamp::from_parts(1, 123456789, 9).to_string(),
            "1.123456789"
        );
        assert_eq!(std::mem::size_of::<Option<Timestamp>>(), 32);
    }

    #[test]
    fn ordering_follows_time() {
        assert!(ts("1.5") < ts("1.6"));
        assert!(ts("10") > ts("9.999999"));
    }

    #[test]
    fn ticks_that_do_not_fit_are_none() {
        assert_eq!(Ticks::new(5, 19), None, "past 18 digits");
        assert_eq!(Timestamp::from_parts(u64::MAX / 10, 0, 6).ticks(), None);
        let t = Timestamp::from_parts(1_700_000_000, 123_456, 6);
        assert_eq!(t.ticks(), Ticks::new(1_700_000_000_123_456, 6));
    }

    proptest::proptest! {
        /// A time as ticks and back is the same time; ticks of one
        /// precision subtract as the times do (in attoseconds).
        #[test]
        fn ticks_are_the_time(
            secs in 0u64..4_000_000_000,
            frac in 0u64..1_000_000_000,
            later in 0u64..1_000_000_000,
            digits in 0u8..=9,
        ) {
            let unit = 10u64.pow(u32::from(digits));
            let t = Timestamp::from_parts(secs, frac % unit, digits);
            let ticks = t.ticks().expect("fits");
            proptest::prop_assert_eq!(ticks.digits, digits);
            proptest::prop_assert_eq!(ticks.timestamp(), t);
            let u = Ticks { value: ticks.value + later, digits };
            proptest::prop_assert_eq!(u.timestamp().since(t).attos(), ticks.attos(later));
        }

        /// Adding a span's step is adding the span: exact, carries into
        /// the seconds, keeps the finer precision.
        #[test]
        fn adding_a_step_adds_its_span(
            secs in 0u64..4_000_000_000,
            frac in 0u64..1_000_000,
            later_secs in 1u64..100_000,
            later_frac in 0u64..1_000_000_000,
        ) {
            let t = Timestamp::from_parts(secs, frac, 6);
            let later = Timestamp::from_parts(secs + later_secs, later_frac, 9);
            let span = later.since(t);
            let step = span.step().expect("not negative");
            proptest::prop_assert_eq!(t.checked_add_step(step), Some(later));
            proptest::prop_assert_eq!(t.checked_add_span(span), Some(later));
            proptest::prop_assert_eq!(t.since(later).step(), None);
        }

        /// Every width, the constant-division ones (3, 6, 9) included,
        /// writes the leading digits of the fraction, zero-padded.
        #[test]
        fn fraction_text_is_the_leading_digits(atto in 0u64..1_000_000_000_000_000_000, digits in 0u8..=18) {
            let mut out = Vec::new();
            push_fraction(&mut out, atto, digits);
            let d = usize::from(digits);
            let want = if d == 0 {
                String::new()
            } else {
                format!(".{:0d$}", atto / 10u64.pow(18 - u32::from(digits)))
            };
            proptest::prop_assert_eq!(String::from_utf8(out).unwrap(), want);
        }
    }

    #[test]
    fn kept_seconds_write_what_push_decimal_writes() {
        let mut kept = SecondsText::default();
        let times = [
            Timestamp::from_raw(1_700_000_000, 1_219_000_000_000_000, 6),
            Timestamp::from_raw(1_700_000_000, 999_999_000_000_000_000, 6),
            Timestamp::from_raw(1_700_000_001, 0, 6),
            Timestamp::from_raw(0, 5, 18),
            Timestamp::from_raw(u64::MAX, 0, 0),
            Timestamp::from_raw(7, 500_000_000_000_000_000, 1),
        ];
        for t in times.into_iter().map(Option::unwrap) {
            let (mut want, mut got) = (b"x".to_vec(), b"x".to_vec());
            t.push_decimal(&mut want);
            t.push_decimal_with(&mut got, &mut kept);
            assert_eq!(
                String::from_utf8(got).unwrap(),
                String::from_utf8(want).unwrap()
            );
        }
    }
}
