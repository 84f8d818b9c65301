//! SDO abort codes (CiA 301 §7.2.4.3.17, the full table), in our words.

/// `(code, meaning)`, ascending by code.
pub const ABORT_CODES: [(u32, &str); 31] = [
    (0x0503_0000, "toggle bit not alternated"),
    (0x0504_0000, "SDO protocol timed out"),
    (
        0x0504_0001,
        "client/server command specifier not valid or unknown",
    ),
    (0x0504_0002, "invalid block size (block mode only)"),
    (0x0504_0003, "invalid sequence number (block mode only)"),
    (0x0504_0004, "CRC error (block mode only)"),
    (0x0504_0005, "out of memory"),
    (0x0601_0000, "unsupported access to an object"),
    (0x0601_0001, "attempt to read a write-only object"),
    (0x0601_0002, "attempt to write a read-only object"),
    (
        0x0602_0000,
        "object does not exist in the object dictionary",
    ),
    (0x0604_0041, "object cannot be mapped to the PDO"),
    (
        0x0604_0042,
        "the number and length of the objects to be mapped would exceed the PDO length",
    ),
    (0x0604_0043, "general parameter incompatibility"),
    (
        0x0604_0047,
        "general internal incompatibility in the device",
    ),
    (0x0606_0000, "access failed because of a hardware error"),
    (
        0x0607_0010,
        "data type does not match: length of service parameter does not match",
    ),
    (
        0x0607_0012,
        "data type does not match: length of service parameter too high",
    ),
    (
        0x0607_0013,
        "data type does not match: length of service parameter too low",
    ),
    (0x0609_0011, "sub-index does not exist"),
    (0x0609_0030, "invalid value for parameter (download only)"),
    (
        0x0609_0031,
        "value of parameter written too high (download only)",
    ),
    (
        0x0609_0032,
        "value of parameter written too low (download only)",
    ),
    (0x0609_0036, "maximum value is less than minimum value"),
    (0x060A_0023, "resource not available: SDO connection"),
    (0x0800_0000, "general error"),
    (
        0x0800_0020,
        "data cannot be transferred or stored to the application",
    ),
    (
        0x0800_0021,
        "data cannot be transferred or stored to the application because of local control",
    ),
    (
        0x0800_0022,
        "data cannot be transferred or stored because of the present device state",
    ),
    (
        0x0800_0023,
        "object dictionary dynamic generation failed or no object dictionary is present",
    ),
    (0x0800_0024, "no data available"),
];

/// What an abort code means; `None` for a code the standard does not define
/// (manufacturers use some).
pub fn text(code: u32) -> Option<&'static str> {
    let i = ABORT_CODES.binary_search_by_key(&code, |(c, _)| *c).ok()?;
    ABORT_CODES.get(i).map(|(_, t)| *t)
}

/// [`text`], or a plain statement that the code is not a standard one.
pub fn describe(code: u32) -> &'static str {
    text(code).unwrap_or("abort code not defined by CiA 301 (manufacturer-specific?)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_sorted_and_unique() {
        for w in ABORT_CODES.windows(2) {
            assert!(w[0].0 < w[1].0, "{:#010x} before {:#010x}", w[0].0, w[1].0);
        }
    }

    #[test]
    fn every_code_is_found() {
        for (code, t) in ABORT_CODES {
            assert_eq!(text(code), Some(t));
            assert!(!t.is_empty());
        }
    }

    #[test]
    fn known_codes() {
        assert_eq!(
            text(0x0602_0000),
            Some("object does not exist in the object dictionary")
        );
        assert_eq!(
            text(0x0800_0022),
            Some("data cannot be transferred or stored because of the present device state")
        );
        assert_eq!(text(0x0609_0011), Some("sub-index does not exist"));
        assert_eq!(text(0x0800_0000), Some("general error"));
        assert_eq!(text(0x0503_0000), Some("toggle bit not alternated"));
    }

    #[test]
    fn unknown_codes() {
        assert_eq!(text(0), None);
        assert_eq!(text(0x0609_0012), None);
        assert_eq!(text(u32::MAX), None);
        assert!(describe(0x1234_5678).contains("not defined"));
    }
}
