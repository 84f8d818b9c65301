//! The TIME object (CiA 301, COB-ID 0x100): a producer's time of day as
//! milliseconds after midnight (28 bits) and days since 1984-01-01.

/// The TIME object's pre-defined COB-ID.
pub const TIME_ID: u32 = 0x100;

/// Days from 1970-01-01 to 1984-01-01 (14 years, 3 of them leap years).
const DAYS_1970_TO_1984: u64 = 14 * 365 + 3;

/// A TIME stamp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimeOfDay {
    pub millis: u32,
    pub days: u16,
}

impl TimeOfDay {
    /// The six bytes of a TIME frame; `None` for fewer (the bits past the
    /// 28 of the milliseconds are reserved and ignored).
    pub fn decode(data: &[u8]) -> Option<TimeOfDay> {
        let b = data.get(..6)?;
        Some(TimeOfDay {
            millis: u32::from_le_bytes([b[0], b[1], b[2], b[3]]) & 0x0FFF_FFFF,
            days: u16::from_le_bytes([b[4], b[5]]),
        })
    }

    /// Milliseconds since the Unix epoch.
    pub fn unix_millis(self) -> u64 {
        (u64::from(self.days) + DAYS_1970_TO_1984) * 86_400_000 + u64::from(self.millis)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_time_stamp_is_days_since_1984_and_millis_since_midnight() {
        // 2023-11-14T22:13:20Z is 1700000000 s after the epoch: day 19675
        // after 1970, so 14562 after 1984, and 80000 s into the day.
        let t = TimeOfDay::decode(&[0x00, 0xB4, 0xC4, 0x04, 0xE2, 0x38]).unwrap();
        assert_eq!(
            t,
            TimeOfDay {
                millis: 80_000_000,
                days: 14_562
            }
        );
        assert_eq!(t.unix_millis(), 1_700_000_000_000);
        // The reserved top bits are not milliseconds.
        let r = TimeOfDay::decode(&[0x00, 0xB4, 0xC4, 0xF4, 0xE2, 0x38]).unwrap();
        assert_eq!(r.millis, 80_000_000);
        assert_eq!(TimeOfDay::decode(&[0; 5]), None);
        assert_eq!(
            TimeOfDay::decode(&[0; 6]).unwrap().unix_millis(),
            441_763_200_000
        );
    }
}
