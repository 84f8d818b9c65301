//! What a node's device type (object 0x1000) says it is: the device
//! profile number in its low 16 bits (CiA 301 §7.5.2.1; the high 16 bits
//! are the profile's additional information), named in our words.

/// Profile number of CiA 402 (drives and motion control).
pub const DRIVE: u16 = 402;

/// `(profile number, what a node of it is)`, ascending by number: the CiA
/// device profiles a CANopen bus commonly carries.
pub const PROFILES: [(u16, &str); 10] = [
    (401, "CiA 401 I/O"),
    (DRIVE, "CiA 402 drive"),
    (404, "CiA 404 measuring device"),
    (406, "CiA 406 encoder"),
    (408, "CiA 408 hydraulic drive"),
    (410, "CiA 410 inclinometer"),
    (417, "CiA 417 lift"),
    (418, "CiA 418 battery module"),
    (419, "CiA 419 battery charger"),
    (447, "CiA 447 car add-on device"),
];

/// The device profile number of a device type.
pub fn number(device_type: u32) -> u16 {
    (device_type & 0xFFFF) as u16
}

/// Whether a device type says the node is a CiA 402 drive.
pub fn is_drive(device_type: u32) -> bool {
    number(device_type) == DRIVE
}

/// What a device type says the node is: a profile of [`PROFILES`] by its
/// name, another CiA profile number (400-499) as `CiA 4xx`, profile 0 (the
/// standard's value for a device that follows no profile) and any other
/// number as manufacturer-specific.
pub fn describe(device_type: u32) -> String {
    let n = number(device_type);
    match PROFILES.binary_search_by_key(&n, |(p, _)| *p) {
        Ok(i) => PROFILES
            .get(i)
            .map_or_else(String::new, |(_, t)| (*t).to_string()),
        Err(_) if (400..500).contains(&n) => format!("CiA {n}"),
        Err(_) => "manufacturer-specific".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_sorted_and_unique() {
        for w in PROFILES.windows(2) {
            assert!(w[0].0 < w[1].0, "{} before {}", w[0].0, w[1].0);
        }
    }

    #[test]
    fn every_entry_is_described_by_its_name() {
        for (n, text) in PROFILES {
            assert!(text.starts_with(&format!("CiA {n} ")), "{text}");
            // The high word (additional information) changes nothing.
            assert_eq!(describe(u32::from(n)), text);
            assert_eq!(describe(0xABCD_0000 | u32::from(n)), text);
        }
    }

    #[test]
    fn known_device_types() {
        assert_eq!(describe(0x0002_0192), "CiA 402 drive");
        assert_eq!(describe(0x000F_0191), "CiA 401 I/O");
        assert_eq!(describe(0x0001_0196), "CiA 406 encoder");
        assert!(is_drive(0x0002_0192));
        assert!(!is_drive(0x000F_0191));
        assert!(!is_drive(0x0192_0000), "the profile is the low word");
    }

    #[test]
    fn numbers_not_in_the_table() {
        assert_eq!(describe(0x0000_01A7), "CiA 423");
        assert_eq!(describe(0x0000_0190), "CiA 400");
        assert_eq!(describe(0x0000_01F3), "CiA 499");
        assert_eq!(describe(0), "manufacturer-specific");
        assert_eq!(describe(0x0000_01F4), "manufacturer-specific");
        assert_eq!(describe(0x1234_8001), "manufacturer-specific");
    }
}
