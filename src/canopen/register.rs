//! The error register (object 0x1001), byte 2 of every EMCY.

use std::fmt;

/// JSON names of the register bits, bit 0 first.
pub const BIT_NAMES: [&str; 8] = [
    "generic",
    "current",
    "voltage",
    "temperature",
    "communication",
    "device_profile",
    "reserved",
    "manufacturer",
];

/// Short names for the table view, where width matters.
const SHORT_NAMES: [&str; 8] = ["gen", "cur", "volt", "temp", "comm", "prof", "res", "mfr"];

pub const GENERIC: u8 = 0;
pub const RESERVED: u8 = 6;

/// An error register value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Register(pub u8);

impl Register {
    /// Whether bit `bit` (0-7) is set.
    pub fn has(self, bit: u8) -> bool {
        bit < 8 && self.0 & (1 << bit) != 0
    }

    /// Names of the set bits, bit 0 first.
    pub fn names(self) -> impl Iterator<Item = &'static str> + Clone {
        (0..8u8)
            .filter(move |b| self.has(*b))
            .map(|b| BIT_NAMES[usize::from(b)])
    }

    /// `gen+temp`, for the table.
    pub(crate) fn short(self) -> ShortNames {
        ShortNames(self)
    }
}

pub struct ShortNames(Register);

impl fmt::Display for ShortNames {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        for b in (0..8u8).filter(|b| self.0.has(*b)) {
            if !first {
                f.write_str("+")?;
            }
            first = false;
            f.write_str(SHORT_NAMES[usize::from(b)])?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bit_has_its_name() {
        for (bit, name) in BIT_NAMES.iter().enumerate() {
            let r = Register(1 << bit);
            assert_eq!(r.names().collect::<Vec<_>>(), [*name]);
        }
    }

    #[test]
    fn names_in_bit_order() {
        assert_eq!(
            Register(0x89).names().collect::<Vec<_>>(),
            ["generic", "temperature", "manufacturer"]
        );
        assert_eq!(Register(0).names().count(), 0);
        assert_eq!(Register(0x09).short().to_string(), "gen+temp");
        assert_eq!(
            Register(0xFF).short().to_string(),
            "gen+cur+volt+temp+comm+prof+res+mfr"
        );
        assert!(!Register(0xFF).has(8));
    }
}
