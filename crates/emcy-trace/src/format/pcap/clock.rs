//! Packet times to exact [`Timestamp`]s: a count of units since the Unix
//! epoch, the unit a power of ten or of two of a second (pcapng
//! `if_tsresol`), plus whole seconds (`if_tsoffset`). A time prints with
//! as many fraction digits as its unit needs: 6 for microseconds, 9 for
//! nanoseconds, 10 for 2^-10 s (0.0009765625 is exact), at most 18
//! (attoseconds, the finest a [`Timestamp`] holds; finer units are cut
//! there).

use crate::Timestamp;

const ATTO: u128 = 1_000_000_000_000_000_000;
const MAX_DIGITS: u8 = 18;

/// How an interface counts time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Clock {
    /// `if_tsresol`: bit 7 clear, 10^-n s; set, 2^-n s (n the low 7 bits).
    resolution: u8,
    /// `if_tsoffset`: seconds added to every time.
    offset: i64,
}

impl Default for Clock {
    /// Microseconds, no offset (a pcapng interface without the options).
    fn default() -> Self {
        Clock::new(6, 0)
    }
}

impl Clock {
    pub fn new(resolution: u8, offset: i64) -> Clock {
        Clock { resolution, offset }
    }

    /// Whether every count of units is a time: a power of ten down to an
    /// attosecond, no offset (the usual micro- and nanoseconds).
    pub fn infallible(self) -> bool {
        self.resolution <= MAX_DIGITS && self.offset == 0
    }

    /// Whether the unit is finer than an attosecond (times are cut to it).
    pub fn finer_than_atto(self) -> bool {
        let n = self.resolution & 0x7F;
        n > MAX_DIGITS
    }

    /// The resolution as written in messages: `10^-9 s`, `2^-10 s`.
    pub fn describe(self) -> String {
        let n = self.resolution & 0x7F;
        if self.resolution & 0x80 == 0 {
            format!("10^-{n} s")
        } else {
            format!("2^-{n} s")
        }
    }

    /// The time of `units` ticks; `None` when the offset takes it before
    /// 1970 or past what a [`Timestamp`] holds.
    pub fn time(self, units: u64) -> Option<Timestamp> {
        let n = u32::from(self.resolution & 0x7F);
        if self.resolution <= MAX_DIGITS && self.offset == 0 {
            // The usual case (micro- or nanoseconds), in 64 bits.
            let per_sec = 10u64.pow(n);
            return Some(Timestamp::from_parts(
                units / per_sec,
                units % per_sec,
                self.resolution,
            ));
        }
        let units = u128::from(units);
        let (secs, atto, digits) = if self.resolution & 0x80 == 0 {
            // 10^-n: 10^38 is the largest power of ten in a u128; any u64
            // count of a unit that fine is under a second.
            match 10u128.checked_pow(n) {
                Some(per_sec) => {
                    let frac = units % per_sec;
                    let atto = if n <= u32::from(MAX_DIGITS) {
                        frac * 10u128.pow(u32::from(MAX_DIGITS) - n)
                    } else {
                        frac / 10u128.pow(n - u32::from(MAX_DIGITS))
                    };
                    (units / per_sec, atto, n)
                }
                None => (0, 0, n),
            }
        } else {
            // 2^-n: the fraction times 10^18 fits a u128 (< 2^64 * 2^60).
            let whole = if n >= 64 { 0 } else { units >> n };
            let frac = if n >= 64 {
                units
            } else {
                units & ((1 << n) - 1)
            };
            ((whole), (frac * ATTO) >> n, n)
        };
        let digits = digits.min(u32::from(MAX_DIGITS)) as u8;
        let secs = i128::try_from(secs).ok()? + i128::from(self.offset);
        let secs = u64::try_from(secs).ok()?;
        Timestamp::from_raw(secs, u64::try_from(atto).ok()?, digits)
    }
}

/// A legacy pcap record's time: seconds and a fraction in microseconds or
/// nanoseconds (6 or 9 digits). A fraction of a second or more (not
/// written by libpcap) is carried into the seconds, never wrapped.
pub fn legacy(secs: u32, frac: u32, nanos: bool) -> Timestamp {
    let (per_sec, digits) = if nanos {
        (1_000_000_000, 9)
    } else {
        (1_000_000, 6)
    };
    let secs = u64::from(secs) + u64::from(frac / per_sec);
    Timestamp::from_parts(secs, u64::from(frac % per_sec), digits)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(resolution: u8, offset: i64, units: u64) -> String {
        Clock::new(resolution, offset)
            .time(units)
            .map_or("none".into(), |t| t.to_string())
    }

    #[test]
    fn powers_of_ten_keep_their_digits() {
        assert_eq!(at(6, 0, 1_700_000_001_250_000), "1700000001.250000");
        assert_eq!(at(9, 0, 1_700_000_001_250_000_001), "1700000001.250000001");
        assert_eq!(at(3, 0, 1_700_000_001_250), "1700000001.250");
        assert_eq!(at(0, 0, 1_700_000_001), "1700000001");
        assert_eq!(at(18, 0, u64::MAX), "18.446744073709551615");
        // Finer than an attosecond: cut to 18 digits.
        assert_eq!(at(19, 0, u64::MAX), "1.844674407370955161");
        assert_eq!(at(20, 0, u64::MAX), "0.184467440737095516");
        assert_eq!(at(38, 0, u64::MAX), "0.000000000000000000");
        assert_eq!(at(39, 0, u64::MAX), "0.000000000000000000");
        assert_eq!(at(127, 0, u64::MAX), "0.000000000000000000");
        assert!(Clock::new(19, 0).finer_than_atto());
        assert!(!Clock::new(9, 0).finer_than_atto());
    }

    #[test]
    fn powers_of_two_are_exact_in_decimal() {
        // 2^-10 s: 1024 ticks a second, 10 digits.
        assert_eq!(
            at(0x80 | 10, 0, 1024 * 1_700_000_000 + 1),
            "1700000000.0009765625"
        );
        assert_eq!(at(0x80 | 10, 0, 1024 * 5 + 512), "5.5000000000");
        assert_eq!(at(0x80, 0, 7), "7");
        assert_eq!(at(0x80 | 1, 0, 3), "1.5");
        // 2^-20 s: 20 digits would be needed; cut to 18.
        assert_eq!(at(0x80 | 20, 0, (1 << 20) + 1), "1.000000953674316406");
        assert_eq!(at(0x80 | 64, 0, 1 << 63), "0.500000000000000000");
        assert_eq!(at(0x80 | 127, 0, u64::MAX), "0.000000000000000000");
        assert_eq!(at(0x80 | 63, 0, u64::MAX), "1.999999999999999999");
    }

    #[test]
    fn the_offset_adds_seconds_and_never_goes_before_1970() {
        assert_eq!(at(6, 1_700_000_000, 1_250_000), "1700000001.250000");
        assert_eq!(at(6, -1, 1_250_000), "0.250000");
        assert_eq!(at(6, -2, 1_250_000), "none");
        assert_eq!(at(0, i64::MAX, u64::MAX), "none");
        assert_eq!(at(0, i64::MIN, 0), "none");
    }

    #[test]
    fn legacy_times_carry_an_overlong_fraction() {
        assert_eq!(
            legacy(1_700_000_001, 250_000, false).to_string(),
            "1700000001.250000"
        );
        assert_eq!(
            legacy(1_700_000_001, 5, true).to_string(),
            "1700000001.000000005"
        );
        assert_eq!(legacy(1, 2_500_000, false).to_string(), "3.500000");
        assert_eq!(
            legacy(u32::MAX, u32::MAX, true).to_string(),
            "4294967299.294967295"
        );
    }
}
