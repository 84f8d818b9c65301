//! Names of object dictionary entries, for telling SDO transfers: the
//! communication objects every CANopen device has (CiA 301, with the
//! program download objects of CiA 302) and the drive objects of CiA 402.
//! A DCF or EDS given with `--dcf` names its device's own objects (the
//! analysis asks it first).
//!
//! The 0x6000-0x9FFF range is each device profile's own: 0x6040 is a
//! drive's controlword and something else on an I/O module. Those names
//! are given only for nodes known to be drives.

use super::sdo::Object;

/// The CiA 301 (and 302) name of `object`, if it is a communication object
/// this table knows. Sub-indices are named where they differ in meaning
/// (the identity's four numbers, an error history's count); otherwise the
/// object's name stands for each of its sub-indices.
pub fn communication_name(object: Object) -> Option<&'static str> {
    let Object { index, sub } = object;
    Some(match (index, sub) {
        (0x1000, _) => "Device type",
        (0x1001, _) => "Error register",
        (0x1002, _) => "Manufacturer status register",
        (0x1003, 0) => "Pre-defined error field: number of errors",
        (0x1003, _) => "Pre-defined error field",
        (0x1005, _) => "COB-ID SYNC",
        (0x1006, _) => "Communication cycle period",
        (0x1007, _) => "Synchronous window length",
        (0x1008, _) => "Manufacturer device name",
        (0x1009, _) => "Manufacturer hardware version",
        (0x100A, _) => "Manufacturer software version",
        (0x100C, _) => "Guard time",
        (0x100D, _) => "Life time factor",
        (0x1010, _) => "Store parameters",
        (0x1011, _) => "Restore default parameters",
        (0x1012, _) => "COB-ID TIME",
        (0x1013, _) => "High resolution time stamp",
        (0x1014, _) => "COB-ID EMCY",
        (0x1015, _) => "Inhibit time EMCY",
        (0x1016, _) => "Consumer heartbeat time",
        (0x1017, _) => "Producer heartbeat time",
        (0x1018, 1) => "Identity: vendor-ID",
        (0x1018, 2) => "Identity: product code",
        (0x1018, 3) => "Identity: revision number",
        (0x1018, 4) => "Identity: serial number",
        (0x1018, _) => "Identity object",
        (0x1019, _) => "Synchronous counter overflow value",
        (0x1020, _) => "Verify configuration",
        (0x1021, _) => "Store EDS",
        (0x1022, _) => "Store format",
        (0x1028, _) => "Emergency consumer",
        (0x1029, _) => "Error behavior",
        (0x1200..=0x127F, _) => "SDO server parameter",
        (0x1280..=0x12FF, _) => "SDO client parameter",
        (0x1400..=0x15FF, _) => "RPDO communication parameter",
        (0x1600..=0x17FF, _) => "RPDO mapping parameter",
        (0x1800..=0x19FF, _) => "TPDO communication parameter",
        (0x1A00..=0x1BFF, _) => "TPDO mapping parameter",
        (0x1F50, _) => "Program data",
        (0x1F51, _) => "Program control",
        (0x1F56, _) => "Program software identification",
        (0x1F57, _) => "Flash status identification",
        (0x1F80, _) => "NMT startup",
        (0x1F81, _) => "NMT slave assignment",
        (0x1F82, _) => "Request NMT",
        (0x1F89, _) => "Boot time",
        _ => return None,
    })
}

/// The CiA 402 name of a drive's `index`, if this table knows it.
pub fn drive_name(index: u16) -> Option<&'static str> {
    Some(match index {
        0x603F => "Error code",
        0x6040 => "Controlword",
        0x6041 => "Statusword",
        0x605A => "Quick stop option code",
        0x605B => "Shutdown option code",
        0x605C => "Disable operation option code",
        0x605D => "Halt option code",
        0x605E => "Fault reaction option code",
        0x6060 => "Modes of operation",
        0x6061 => "Modes of operation display",
        0x6062 => "Position demand value",
        0x6063 => "Position actual internal value",
        0x6064 => "Position actual value",
        0x6065 => "Following error window",
        0x6066 => "Following error time out",
        0x6067 => "Position window",
        0x6068 => "Position window time",
        0x6069 => "Velocity sensor actual value",
        0x606B => "Velocity demand value",
        0x606C => "Velocity actual value",
        0x606D => "Velocity window",
        0x606E => "Velocity window time",
        0x6071 => "Target torque",
        0x6072 => "Max torque",
        0x6073 => "Max current",
        0x6074 => "Torque demand",
        0x6075 => "Motor rated current",
        0x6076 => "Motor rated torque",
        0x6077 => "Torque actual value",
        0x6078 => "Current actual value",
        0x6079 => "DC link circuit voltage",
        0x607A => "Target position",
        0x607C => "Home offset",
        0x607D => "Software position limit",
        0x607E => "Polarity",
        0x607F => "Max profile velocity",
        0x6080 => "Max motor speed",
        0x6081 => "Profile velocity",
        0x6083 => "Profile acceleration",
        0x6084 => "Profile deceleration",
        0x6085 => "Quick stop deceleration",
        0x6086 => "Motion profile type",
        0x6087 => "Torque slope",
        0x6098 => "Homing method",
        0x6099 => "Homing speeds",
        0x609A => "Homing acceleration",
        0x60B0 => "Position offset",
        0x60B1 => "Velocity offset",
        0x60B2 => "Torque offset",
        0x60C1 => "Interpolation data record",
        0x60C2 => "Interpolation time period",
        0x60F4 => "Following error actual value",
        0x60FD => "Digital inputs",
        0x60FE => "Digital outputs",
        0x60FF => "Target velocity",
        0x6502 => "Supported drive modes",
        _ => return None,
    })
}

/// A VISIBLE_STRING's bytes as text. CiA 301 means ASCII; devices also
/// send UTF-8, and (German machine builders among them) Latin-1, whose
/// bytes over 0x7F are no valid UTF-8: read as Latin-1 then, so
/// "Sonderger\u{e4}t" is not a replacement character. Padding (NULs and
/// spaces at the end) is no part of the text.
pub fn visible_string(bytes: &[u8]) -> String {
    let text = match std::str::from_utf8(bytes) {
        Ok(text) => text.to_string(),
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect(),
    };
    text.trim_end_matches(['\0', ' ']).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn o(index: u16, sub: u8) -> Object {
        Object { index, sub }
    }

    #[test]
    fn communication_objects_by_index_and_sub() {
        assert_eq!(
            communication_name(o(0x1017, 0)),
            Some("Producer heartbeat time")
        );
        assert_eq!(
            communication_name(o(0x1018, 2)),
            Some("Identity: product code")
        );
        assert_eq!(communication_name(o(0x1018, 0)), Some("Identity object"));
        assert_eq!(
            communication_name(o(0x1003, 0)),
            Some("Pre-defined error field: number of errors")
        );
        assert_eq!(
            communication_name(o(0x1003, 3)),
            Some("Pre-defined error field")
        );
        assert_eq!(
            communication_name(o(0x1A03, 1)),
            Some("TPDO mapping parameter")
        );
        assert_eq!(communication_name(o(0x1C00, 0)), None);
        assert_eq!(communication_name(o(0x1F50, 1)), Some("Program data"));
        assert_eq!(communication_name(o(0x2000, 0)), None);
        assert_eq!(
            communication_name(o(0x6041, 0)),
            None,
            "profile objects apart"
        );
    }

    #[test]
    fn drive_objects() {
        assert_eq!(drive_name(0x6040), Some("Controlword"));
        assert_eq!(drive_name(0x6041), Some("Statusword"));
        assert_eq!(drive_name(0x6502), Some("Supported drive modes"));
        assert_eq!(drive_name(0x6000), None);
        assert_eq!(drive_name(0x1000), None);
    }

    #[test]
    fn texts_are_utf8_else_latin1_without_padding() {
        assert_eq!(visible_string(b"AKD"), "AKD");
        assert_eq!(visible_string("Gerät".as_bytes()), "Gerät");
        assert_eq!(visible_string(b"Ger\xe4t"), "Gerät");
        assert_eq!(visible_string(b"V1.2\0\0 "), "V1.2");
        assert_eq!(visible_string(b""), "");
    }
}
