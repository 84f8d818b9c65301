//! Exact trace timestamps.
//!
//! Traces write times as decimal text (`1469439874.299654`, `3.098426`,
//! nanosecond `-N` logs). Users diff our JSON against the trace, so a time is
//! kept exactly as written: an integer count of attoseconds plus the number of
//! fraction digits the trace used, which is how it is printed back. `f64` would
//! round a nanosecond Unix time.

use std::fmt;

/// Most fraction digits a timestamp may carry (attosecond resolution).
pub const MAX_FRACTION_DIGITS: usize = 18;

const ATTO_PER_SEC: u128 = 1_000_000_000_000_000_000;

/// A point in time: seconds since the trace's epoch (Unix time for candump,
/// measurement start for ASC), exact to the digits the trace wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Timestamp {
    atto: u128,
    digits: u8,
}

/// A signed difference of two timestamps (an error's duration).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Span {
    atto: i128,
    digits: u8,
}

fn pow10(n: usize) -> u128 {
    10u128.pow(n as u32)
}

impl Timestamp {
    pub const ZERO: Timestamp = Timestamp { atto: 0, digits: 0 };

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
        let mut f: u128 = 0;
        for &b in frac {
            let d = digit(b).ok_or("timestamp is not a decimal number")?;
            f = f * 10 + u128::from(d);
        }
        let atto = u128::from(secs) * ATTO_PER_SEC + f * pow10(MAX_FRACTION_DIGITS - frac.len());
        Ok(Timestamp {
            atto,
            digits: frac.len() as u8,
        })
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
    pub fn from_parts(secs: u64, frac: u64, digits: u8) -> Timestamp {
        let digits = digits.min(MAX_FRACTION_DIGITS as u8);
        let scale = pow10(MAX_FRACTION_DIGITS - usize::from(digits));
        Timestamp {
            atto: u128::from(secs) * ATTO_PER_SEC + u128::from(frac) * scale,
            digits,
        }
    }

    /// Adds a delta (ASC `timestamps relative`, candump `-td`); the result
    /// keeps the finer of the two precisions. `None` on overflow.
    pub fn checked_add(self, delta: Timestamp) -> Option<Timestamp> {
        let atto = self.atto.checked_add(delta.atto)?;
        // Stay within what `from_decimal` can produce so printing never overflows u64 seconds.
        if atto / ATTO_PER_SEC > u128::from(u64::MAX) {
            return None;
        }
        Some(Timestamp {
            atto,
            digits: self.digits.max(delta.digits),
        })
    }

    /// `self - earlier`, negative when the trace's clock went backwards.
    pub fn since(self, earlier: Timestamp) -> Span {
        Span {
            atto: self.atto as i128 - earlier.atto as i128,
            digits: self.digits.max(earlier.digits),
        }
    }

    pub fn secs(self) -> u64 {
        (self.atto / ATTO_PER_SEC) as u64
    }

    /// Fraction digits as written in the trace.
    pub fn digits(self) -> u8 {
        self.digits
    }

    /// Seconds as `f64`, for layout only (never for output of values).
    pub fn as_f64(self) -> f64 {
        self.atto as f64 / ATTO_PER_SEC as f64
    }
}

impl PartialOrd for Timestamp {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Timestamp {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.atto
            .cmp(&other.atto)
            .then(self.digits.cmp(&other.digits))
    }
}

impl Span {
    pub fn is_negative(self) -> bool {
        self.atto < 0
    }
    pub fn as_f64(self) -> f64 {
        self.atto as f64 / ATTO_PER_SEC as f64
    }
}

fn digit(b: u8) -> Option<u8> {
    b.is_ascii_digit().then(|| b - b'0')
}

fn write_decimal(f: &mut fmt::Formatter<'_>, atto: u128, digits: u8) -> fmt::Result {
    let secs = atto / ATTO_PER_SEC;
    if digits == 0 {
        return write!(f, "{secs}");
    }
    let frac = (atto % ATTO_PER_SEC) / pow10(MAX_FRACTION_DIGITS - usize::from(digits));
    write!(f, "{secs}.{frac:0width$}", width = usize::from(digits))
}

/// Prints as a JSON-compatible decimal number with the trace's digit count.
impl fmt::Display for Timestamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_decimal(f, self.atto, self.digits)
    }
}

impl fmt::Display for Span {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.atto < 0 {
            f.write_str("-")?;
        }
        write_decimal(f, self.atto.unsigned_abs(), self.digits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn ordering_follows_time() {
        assert!(ts("1.5") < ts("1.6"));
        assert!(ts("10") > ts("9.999999"));
    }
}
