//! CiA 301 / CiA 402 emergency error codes.
//!
//! The standards define codes as a hierarchy (class, group, subgroup, code), and
//! devices send many codes the tables only know up to some level, so a lookup
//! walks the hierarchy broadest first and keeps every level it finds: an
//! unlisted 0x4315 still reads "Temperature · drive · excess temperature
//! drive" up to where the tables stop. The full tables are CiA 301 plus the
//! CiA 402 drive profile; [`Tables::Cia301`] restricts a lookup to what CiA
//! 301 itself defines, for devices that are not drives (CiA 401 I/O reuses a
//! few drive codes with other meanings).
//!
//! Everything is `static` and sorted so a lookup is a handful of binary
//! searches with no allocation: it runs once per EMCY frame on multi-GB traces.

use std::fmt;

/// The class an error code belongs to. `slug()` is the stable name used in JSON.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Class {
    /// 0x00xx: error reset or no error.
    Reset,
    /// 0x10xx.
    Generic,
    /// 0x2xxx.
    Current,
    /// 0x3xxx.
    Voltage,
    /// 0x4xxx.
    Temperature,
    /// 0x50xx device hardware.
    Hardware,
    /// 0x6xxx device software.
    Software,
    /// 0x70xx additional modules (CiA 402: 71xx-76xx drive modules).
    Modules,
    /// 0x81xx/0x82xx: CAN communication and protocol errors.
    Communication,
    /// Other 0x8xxx monitoring (CiA 402: control loops, following error).
    Monitoring,
    /// 0x90xx.
    External,
    /// 0xF0xx.
    AdditionalFunctions,
    /// 0xFFxx device specific.
    Manufacturer,
    /// Not defined by CiA 301 or CiA 402.
    Undefined,
}

impl Class {
    /// The stable name in JSON (`temperature`).
    pub fn slug(self) -> &'static str {
        match self {
            Class::Reset => "reset",
            Class::Generic => "generic",
            Class::Current => "current",
            Class::Voltage => "voltage",
            Class::Temperature => "temperature",
            Class::Hardware => "hardware",
            Class::Software => "software",
            Class::Modules => "modules",
            Class::Communication => "communication",
            Class::Monitoring => "monitoring",
            Class::External => "external",
            Class::AdditionalFunctions => "additional_functions",
            Class::Manufacturer => "manufacturer",
            Class::Undefined => "undefined",
        }
    }

    /// The capitalised CiA 301 class name, also the first part of a description.
    /// `Communication` is a split-off of the monitoring class (for its own
    /// register bit), so descriptions of 81xx/82xx still start with "Monitoring".
    pub fn name(self) -> &'static str {
        match self {
            Class::Reset => "Error reset or no error",
            Class::Generic => "Generic error",
            Class::Current => "Current",
            Class::Voltage => "Voltage",
            Class::Temperature => "Temperature",
            Class::Hardware => "Device hardware",
            Class::Software => "Device software",
            Class::Modules => "Additional modules",
            Class::Communication => "Communication",
            Class::Monitoring => "Monitoring",
            Class::External => "External error",
            Class::AdditionalFunctions => "Additional functions",
            Class::Manufacturer => "Device specific",
            Class::Undefined => "Undefined",
        }
    }

    /// The error register bit (0x1001) CiA 301 ties this class to, if any.
    pub fn register_bit(self) -> Option<u8> {
        match self {
            Class::Current => Some(1),
            Class::Voltage => Some(2),
            Class::Temperature => Some(3),
            Class::Communication => Some(4),
            Class::Manufacturer => Some(7),
            _ => None,
        }
    }
}

/// Which code tables a lookup uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Tables {
    /// CiA 301 only: classes, the 21xx-63xx subgroups and the 81xx/82xx codes.
    Cia301,
    /// CiA 301 plus the CiA 402 drive codes (the default).
    #[default]
    Cia402,
}

impl Tables {
    /// The name a profile file uses (`cia301`, `cia402`).
    pub fn slug(self) -> &'static str {
        match self {
            Tables::Cia301 => "cia301",
            Tables::Cia402 => "cia402",
        }
    }

    pub(crate) fn from_slug(slug: &str) -> Option<Tables> {
        match slug {
            "cia301" => Some(Tables::Cia301),
            "cia402" => Some(Tables::Cia402),
            _ => None,
        }
    }
}

/// What the tables say about one code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodeInfo {
    /// The code looked up.
    pub code: u16,
    /// The tables the lookup used.
    pub tables: Tables,
    /// Its class (a range of codes).
    pub class: Class,
    /// The code itself has a table entry (not only its class or group).
    pub listed: bool,
    parts: [&'static str; 4],
    len: u8,
}

impl CodeInfo {
    /// The hierarchy of texts, broadest first.
    pub fn parts(&self) -> &[&'static str] {
        &self.parts[..usize::from(self.len)]
    }

    /// `Temperature · drive · excess temperature drive`.
    pub fn description(&self) -> Description {
        Description(*self)
    }

    /// At most four levels exist (class, FF00, FFF0, FFFF), so the array never
    /// overflows; `get_mut` keeps that from being a panic path regardless.
    fn push(&mut self, text: &'static str) {
        if let Some(slot) = self.parts.get_mut(usize::from(self.len)) {
            *slot = text;
            self.len += 1;
        }
    }
}

/// A code's description, written when displayed (no allocation):
/// `Temperature · drive · excess temperature drive`.
pub struct Description(CodeInfo);

impl fmt::Display for Description {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let info = &self.0;
        if info.class == Class::Undefined {
            return f.write_str(match info.tables {
                Tables::Cia301 => "undefined code (not in CiA 301)",
                Tables::Cia402 => "undefined code (not in CiA 301 or CiA 402)",
            });
        }
        for (i, part) in info.parts().iter().enumerate() {
            if i > 0 {
                f.write_str(" · ")?;
            }
            f.write_str(part)?;
        }
        if !info.listed {
            // Say so, or a reader takes the group text for the code's own meaning.
            write!(f, " (0x{:04X} not listed)", info.code)?;
        }
        Ok(())
    }
}

/// The class level (mask F000 for most classes). Rows are ranges rather than
/// value/mask pairs because CiA 301 gives 5000 and 7000 only mask FF00 while
/// CiA 402 adds sibling groups 51xx-55xx and 71xx-76xx under the same class:
/// the range is exactly the union of what the standards cover, so 56xx or 77xx
/// stay undefined while 5100 "supply" still gets "Device hardware" in front.
struct ClassRow {
    /// The class's own code (an exact, listed code) and the range start.
    first: u16,
    last: u16,
    class: Class,
    /// For ranges where every code is defined by the class alone (FFxx is
    /// wholly manufacturer-specific), the text all of them get.
    every_code: Option<&'static str>,
}

const fn class(first: u16, last: u16, class: Class) -> ClassRow {
    ClassRow {
        first,
        last,
        class,
        every_code: None,
    }
}

static CLASSES: [ClassRow; 12] = [
    class(0x0000, 0x00FF, Class::Reset),
    class(0x1000, 0x10FF, Class::Generic),
    class(0x2000, 0x2FFF, Class::Current),
    class(0x3000, 0x3FFF, Class::Voltage),
    class(0x4000, 0x4FFF, Class::Temperature),
    // CiA 301 5000/FF00 plus the CiA 402 groups 5100-5500.
    class(0x5000, 0x55FF, Class::Hardware),
    class(0x6000, 0x6FFF, Class::Software),
    // CiA 301 7000/FF00 plus the CiA 402 groups 7100-7600.
    class(0x7000, 0x76FF, Class::Modules),
    class(0x8000, 0x8FFF, Class::Monitoring),
    class(0x9000, 0x90FF, Class::External),
    class(0xF000, 0xF0FF, Class::AdditionalFunctions),
    ClassRow {
        first: 0xFF00,
        last: 0xFFFF,
        class: Class::Manufacturer,
        every_code: Some("manufacturer-specific"),
    },
];

/// CiA 301 ties these monitoring groups to error register bit 4, so they get
/// their own class.
const COMMUNICATION_GROUPS: [u16; 2] = [0x8100, 0x8200];

/// One row below the class level. `label` names the entry when it is an
/// ancestor of the looked-up code, `text` when it is the code itself: "drive"
/// reads right inside "Temperature · drive · excess temperature drive", but
/// 0x4300 alone needs "drive temperature".
struct Entry {
    value: u16,
    label: &'static str,
    text: &'static str,
}

/// An entry whose ancestor label is its own text.
const fn e(value: u16, text: &'static str) -> Entry {
    Entry {
        value,
        label: text,
        text,
    }
}

/// An entry with a shorter ancestor label.
const fn g(value: u16, label: &'static str, text: &'static str) -> Entry {
    Entry { value, label, text }
}

struct Level {
    mask: u16,
    entries: &'static [Entry],
}

/// Below the class, broadest first. Each value sits in exactly one level, the
/// one its alignment implies (4300 at FF00, 4310 at FFF0, 4311 at FFFF), so a
/// code never matches itself twice.
static LEVELS: [Level; 3] = [
    Level {
        mask: 0xFF00,
        entries: GROUPS,
    },
    Level {
        mask: 0xFFF0,
        entries: SUBGROUPS,
    },
    Level {
        mask: 0xFFFF,
        entries: CODES,
    },
];

/// Mask FF00: CiA 301 subgroups and CiA 402 groups.
static GROUPS: &[Entry] = &[
    e(0x2100, "device input side"),
    e(0x2200, "inside the device"),
    e(0x2300, "output side"),
    g(0x3100, "mains", "mains voltage"),
    e(0x3200, "inside the device"),
    g(0x3300, "output", "output voltage"),
    g(0x4100, "ambient", "ambient temperature"),
    g(0x4200, "device", "device temperature"),
    g(0x4300, "drive", "drive temperature"),
    g(0x4400, "supply", "supply temperature"),
    e(0x5100, "supply"),
    e(0x5200, "control"),
    e(0x5300, "operating unit"),
    e(0x5400, "power section"),
    e(0x5500, "hardware memory"),
    e(0x6100, "internal software"),
    e(0x6200, "user software"),
    e(0x6300, "data set"),
    e(0x7100, "power"),
    e(0x7200, "measurement circuit"),
    e(0x7300, "sensor"),
    e(0x7400, "computation circuit"),
    e(0x7500, "communication"),
    g(0x7600, "data storage", "data storage (external)"),
    e(0x8100, "communication"),
    e(0x8200, "protocol error"),
    e(0x8300, "torque control"),
    e(0x8400, "velocity speed controller"),
    e(0x8500, "position controller"),
    e(0x8600, "positioning controller"),
    e(0x8700, "sync controller"),
    e(0x8800, "winding controller"),
    e(0x8900, "process data monitoring"),
    e(0x8A00, "control"),
];

/// Mask FFF0. Labels drop qualifiers the group already says ("(input)").
static SUBGROUPS: &[Entry] = &[
    e(0x2110, "short circuit/earth leakage (input)"),
    g(0x2120, "earth leakage", "earth leakage (input)"),
    g(0x2130, "short circuit", "short circuit (input)"),
    g(
        0x2220,
        "continuous over current",
        "continuous over current (device internal)",
    ),
    e(0x2230, "short circuit/earth leakage (device internal)"),
    e(0x2240, "earth leakage (device internal)"),
    e(0x2250, "short circuit (device internal)"),
    e(0x2310, "continuous over current"),
    e(0x2320, "short circuit/earth leakage (motor side)"),
    g(0x2330, "earth leakage", "earth leakage (motor side)"),
    g(0x2340, "short circuit", "short circuit (motor side)"),
    g(
        0x2350,
        "load level",
        "load level fault (I2t, thermal state)",
    ),
    e(0x3110, "mains over-voltage"),
    e(0x3120, "mains under-voltage"),
    e(0x3130, "phase failure"),
    e(0x3140, "mains frequency"),
    e(0x3210, "DC link over-voltage"),
    e(0x3220, "DC link under-voltage"),
    e(0x3230, "load error"),
    e(0x3310, "output over-voltage"),
    e(0x3320, "armature circuit"),
    e(0x3330, "field circuit"),
    e(0x4110, "excess ambient temperature"),
    e(0x4120, "too low ambient temperature"),
    e(0x4130, "supply air temperature"),
    e(0x4140, "air outlet temperature"),
    e(0x4210, "excess temperature device"),
    e(0x4220, "too low temperature device"),
    e(0x4310, "excess temperature drive"),
    e(0x4320, "too low temperature drive"),
    e(0x4410, "excess temperature supply"),
    e(0x4420, "too low temperature supply"),
    g(0x5110, "low voltage", "supply low voltage"),
    e(0x5120, "supply intermediate circuit"),
    e(0x5210, "measurement circuit"),
    e(0x5220, "computing circuit"),
    e(0x5410, "output stages"),
    e(0x5420, "chopper"),
    e(0x5430, "input stages"),
    e(0x5440, "contacts"),
    e(0x5450, "fuses"),
    e(0x5510, "RAM"),
    e(0x5520, "ROM/EPROM"),
    e(0x5530, "EEPROM"),
    e(0x6010, "software reset (watchdog)"),
    e(0x6310, "loss of parameters"),
    e(0x6320, "parameter error"),
    e(0x7110, "brake chopper"),
    e(0x7120, "motor"),
    e(0x7310, "speed"),
    e(0x7320, "position"),
    e(0x7510, "serial interface no.1"),
    e(0x7520, "serial interface no.2"),
    e(0x8110, "CAN overrun (objects lost)"),
    e(0x8120, "CAN in error passive mode"),
    e(0x8130, "life guard or heartbeat error"),
    e(0x8140, "recovered from bus off"),
    e(0x8150, "CAN-ID collision"),
    g(
        0x8210,
        "PDO length error",
        "PDO not processed due to length error",
    ),
    e(0x8220, "PDO length exceeded"),
    e(
        0x8230,
        "DAM MPDO not processed, destination object not available",
    ),
    e(0x8240, "unexpected SYNC data length"),
    e(0x8250, "RPDO timeout"),
];

/// Mask FFFF. Ranges in the standards ("2121-2123 phase L1-L3") are spelled
/// out one row per code so each code gets its own text.
static CODES: &[Entry] = &[
    e(0x2121, "earth leakage phase L1"),
    e(0x2122, "earth leakage phase L2"),
    e(0x2123, "earth leakage phase L3"),
    e(0x2131, "short circuit phases L1-L2"),
    e(0x2132, "short circuit phases L2-L3"),
    e(0x2133, "short circuit phases L3-L1"),
    e(0x2211, "internal current no.1"),
    e(0x2212, "internal current no.2"),
    e(0x2213, "over-current in ramp function"),
    e(0x2214, "over-current in the sequence"),
    e(0x2221, "continuous over current no.1"),
    e(0x2222, "continuous over current no.2"),
    e(0x2311, "continuous over current no.1"),
    e(0x2312, "continuous over current no.2"),
    e(0x2331, "earth leakage phase U"),
    e(0x2332, "earth leakage phase V"),
    e(0x2333, "earth leakage phase W"),
    e(0x2341, "short circuit phases U-V"),
    e(0x2342, "short circuit phases V-W"),
    e(0x2343, "short circuit phases W-U"),
    e(0x2351, "load level warning"),
    e(0x3111, "mains over-voltage phase L1"),
    e(0x3112, "mains over-voltage phase L2"),
    e(0x3113, "mains over-voltage phase L3"),
    e(0x3121, "mains under-voltage phase L1"),
    e(0x3122, "mains under-voltage phase L2"),
    e(0x3123, "mains under-voltage phase L3"),
    e(0x3131, "phase failure L1"),
    e(0x3132, "phase failure L2"),
    e(0x3133, "phase failure L3"),
    e(0x3134, "phase sequence"),
    e(0x3141, "mains frequency too great"),
    e(0x3142, "mains frequency too small"),
    e(0x3211, "DC link over-voltage no.1"),
    e(0x3212, "DC link over-voltage no.2"),
    e(0x3221, "DC link under-voltage no.1"),
    e(0x3222, "DC link under-voltage no.2"),
    e(0x3311, "output over-voltage phase U"),
    e(0x3312, "output over-voltage phase V"),
    e(0x3313, "output over-voltage phase W"),
    e(0x3321, "armature circuit interrupted"),
    e(0x3331, "field circuit interrupted"),
    e(0x5111, "U1 = supply +/-15 V"),
    e(0x5112, "U2 = supply +24 V"),
    e(0x5113, "U3 = supply +5 V"),
    e(0x5114, "U4 manufacturer specific"),
    e(0x5115, "U5 manufacturer specific"),
    e(0x5116, "U6 manufacturer specific"),
    e(0x5117, "U7 manufacturer specific"),
    e(0x5118, "U8 manufacturer specific"),
    e(0x5119, "U9 manufacturer specific"),
    e(0x5441, "contact 1 (manufacturer specific)"),
    e(0x5442, "contact 2 (manufacturer specific)"),
    e(0x5443, "contact 3 (manufacturer specific)"),
    e(0x5444, "contact 4 (manufacturer specific)"),
    e(0x5445, "contact 5 (manufacturer specific)"),
    e(0x5451, "S1 = L1"),
    e(0x5452, "S2 = L2"),
    e(0x5453, "S3 = L3"),
    e(0x5454, "S4 manufacturer specific"),
    e(0x5455, "S5 manufacturer specific"),
    e(0x5456, "S6 manufacturer specific"),
    e(0x5457, "S7 manufacturer specific"),
    e(0x5458, "S8 manufacturer specific"),
    e(0x5459, "S9 manufacturer specific"),
    e(0x6301, "data record no.1"),
    e(0x6302, "data record no.2"),
    e(0x6303, "data record no.3"),
    e(0x6304, "data record no.4"),
    e(0x6305, "data record no.5"),
    e(0x6306, "data record no.6"),
    e(0x6307, "data record no.7"),
    e(0x6308, "data record no.8"),
    e(0x6309, "data record no.9"),
    e(0x630A, "data record no.10"),
    e(0x630B, "data record no.11"),
    e(0x630C, "data record no.12"),
    e(0x630D, "data record no.13"),
    e(0x630E, "data record no.14"),
    e(0x630F, "data record no.15"),
    e(0x7111, "failure brake chopper"),
    e(0x7112, "over current brake chopper"),
    e(0x7113, "protective circuit brake chopper"),
    e(0x7121, "motor blocked"),
    e(0x7122, "motor error or commutation malfunction"),
    e(0x7123, "motor tilted"),
    e(0x7301, "tacho fault"),
    e(0x7302, "tacho wrong polarity"),
    e(0x7303, "resolver 1 fault"),
    e(0x7304, "resolver 2 fault"),
    e(0x7305, "incremental sensor 1 fault"),
    e(0x7306, "incremental sensor 2 fault"),
    e(0x7307, "incremental sensor 3 fault"),
    // 8211-8254: per-PDO variants some stacks send; not in CiA 301 itself.
    e(0x8211, "PDO 1 not processed due to length error"),
    e(0x8212, "PDO 2 not processed due to length error"),
    e(0x8213, "PDO 3 not processed due to length error"),
    e(0x8214, "PDO 4 not processed due to length error"),
    e(0x8221, "PDO 1 length exceeded"),
    e(0x8222, "PDO 2 length exceeded"),
    e(0x8223, "PDO 3 length exceeded"),
    e(0x8224, "PDO 4 length exceeded"),
    e(0x8251, "RPDO 1 timeout"),
    e(0x8252, "RPDO 2 timeout"),
    e(0x8253, "RPDO 3 timeout"),
    e(0x8254, "RPDO 4 timeout"),
    e(0x8311, "excess torque"),
    e(0x8312, "difficult start up"),
    e(0x8313, "standstill torque"),
    e(0x8321, "insufficient torque"),
    e(0x8331, "torque fault"),
    e(0x8611, "following error"),
    e(0x8612, "reference limit"),
    e(0xF001, "deceleration"),
    e(0xF002, "sub-synchronous run"),
    e(0xF003, "stroke operation"),
    e(0xF004, "control"),
];

/// The class row covering `code`, if any: the last row starting at or before it.
fn class_row(code: u16) -> Option<&'static ClassRow> {
    let starting_before = CLASSES.partition_point(|row| row.first <= code);
    let row = CLASSES.get(starting_before.checked_sub(1)?)?;
    (code <= row.last).then_some(row)
}

/// [`class_row`] as CiA 301 alone has it: device hardware (5000) and
/// additional modules (7000) are only mask FF00 there; the 51xx-55xx and
/// 71xx-76xx groups are CiA 402's.
fn class_row_in(code: u16, tables: Tables) -> Option<&'static ClassRow> {
    let row = class_row(code)?;
    let narrow = tables == Tables::Cia301
        && matches!(row.class, Class::Hardware | Class::Modules)
        && code & 0xFF00 != row.first;
    (!narrow).then_some(row)
}

/// Whether a row below the class level is CiA 301's own (emcy.md §4): the
/// current, voltage, temperature and software subgroups and the
/// communication (81xx) and protocol (82xx) codes. The per-PDO 8211-8254
/// variants are not CiA 301's but come from CANopen stacks, not from the
/// drive profile, so they stay with the communication codes.
fn in_cia301(value: u16) -> bool {
    match value & 0xFF00 {
        0x2100 | 0x2200 | 0x2300 | 0x3100 | 0x3200 | 0x3300 | 0x4100 | 0x4200 | 0x6100 | 0x6200
        | 0x6300 => value & 0x00FF == 0,
        0x8100 | 0x8200 => true,
        _ => false,
    }
}

fn find(entries: &'static [Entry], value: u16) -> Option<&'static Entry> {
    let i = entries
        .binary_search_by_key(&value, |entry| entry.value)
        .ok()?;
    entries.get(i)
}

/// Looks `code` up in the full (CiA 301 + CiA 402) tables.
pub fn lookup(code: u16) -> CodeInfo {
    lookup_in(code, Tables::Cia402)
}

/// Looks `code` up level by level, broadest first, keeping each level's hit.
pub fn lookup_in(code: u16, tables: Tables) -> CodeInfo {
    let mut info = CodeInfo {
        code,
        tables,
        class: Class::Undefined,
        listed: false,
        parts: [""; 4],
        len: 0,
    };
    let Some(row) = class_row_in(code, tables) else {
        return info;
    };
    info.class = if COMMUNICATION_GROUPS.contains(&(code & 0xFF00)) {
        Class::Communication
    } else {
        row.class
    };
    info.push(row.class.name());
    if let Some(text) = row.every_code {
        info.push(text);
        info.listed = true;
        return info;
    }
    info.listed = code == row.first;
    for level in &LEVELS {
        let hit = find(level.entries, code & level.mask)
            .filter(|entry| tables == Tables::Cia402 || in_cia301(entry.value));
        if let Some(entry) = hit {
            if entry.value == code {
                info.push(entry.text);
                info.listed = true;
            } else {
                info.push(entry.label);
            }
        }
    }
    info
}

/// Whether `code` has a row of its own (class, group, subgroup or code).
#[cfg(test)]
fn has_row(code: u16) -> bool {
    CLASSES.iter().any(|row| row.first == code)
        || LEVELS
            .iter()
            .any(|level| find(level.entries, code).is_some())
}

/// Every code with a row of its own, ascending, for listing the tables. A
/// whole-range class (FFxx) shows once, as its first code.
#[cfg(test)]
fn all_entries() -> impl Iterator<Item = CodeInfo> {
    (0..=u16::MAX).filter(|&code| has_row(code)).map(lookup)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn describe(code: u16) -> String {
        lookup(code).description().to_string()
    }

    #[test]
    fn hierarchical_descriptions() {
        assert_eq!(
            describe(0x4310),
            "Temperature · drive · excess temperature drive"
        );
        assert_eq!(describe(0x4300), "Temperature · drive temperature");
        assert_eq!(describe(0x4000), "Temperature");
        assert_eq!(
            describe(0x2310),
            "Current · output side · continuous over current"
        );
        assert_eq!(
            describe(0x8611),
            "Monitoring · positioning controller · following error"
        );
        assert_eq!(
            describe(0x8130),
            "Monitoring · communication · life guard or heartbeat error"
        );
        assert_eq!(lookup(0x8130).class, Class::Communication);
        assert_eq!(
            describe(0x8250),
            "Monitoring · protocol error · RPDO timeout"
        );
        assert_eq!(
            describe(0x8252),
            "Monitoring · protocol error · RPDO timeout · RPDO 2 timeout"
        );
        assert_eq!(
            describe(0x5530),
            "Device hardware · hardware memory · EEPROM"
        );
        assert!(describe(0x5530).ends_with("EEPROM"));
        assert_eq!(
            describe(0x2122),
            "Current · device input side · earth leakage · earth leakage phase L2"
        );
        assert_eq!(
            describe(0x5111),
            "Device hardware · supply · low voltage · U1 = supply +/-15 V"
        );
        assert_eq!(
            describe(0x630F),
            "Device software · data set · data record no.15"
        );
        assert_eq!(describe(0xF001), "Additional functions · deceleration");
        assert_eq!(
            lookup(0x4310).parts(),
            ["Temperature", "drive", "excess temperature drive"]
        );
    }

    #[test]
    fn reset_class() {
        let zero = lookup(0x0000);
        assert_eq!(zero.class, Class::Reset);
        assert!(zero.listed);
        assert_eq!(describe(0x0000), "Error reset or no error");
        for code in 0x0001..=0x00FF {
            let info = lookup(code);
            assert_eq!(info.class, Class::Reset, "{code:#06x}");
            assert!(!info.listed, "{code:#06x}");
        }
        assert_eq!(
            describe(0x0001),
            "Error reset or no error (0x0001 not listed)"
        );
    }

    #[test]
    fn manufacturer_range_is_all_listed() {
        for code in 0xFF00..=0xFFFF {
            let info = lookup(code);
            assert_eq!(info.class, Class::Manufacturer, "{code:#06x}");
            assert!(info.listed, "{code:#06x}");
            assert_eq!(
                info.description().to_string(),
                "Device specific · manufacturer-specific"
            );
        }
    }

    #[test]
    fn unlisted_codes_keep_their_ancestors() {
        let info = lookup(0x4315);
        assert!(!info.listed);
        assert_eq!(info.class, Class::Temperature);
        assert_eq!(
            describe(0x4315),
            "Temperature · drive · excess temperature drive (0x4315 not listed)"
        );
        assert_eq!(describe(0x4350), "Temperature · drive (0x4350 not listed)");
        assert_eq!(describe(0x4F00), "Temperature (0x4F00 not listed)");
        assert_eq!(describe(0x8A05), "Monitoring · control (0x8A05 not listed)");
        assert_eq!(describe(0x50FF), "Device hardware (0x50FF not listed)");
        assert_eq!(
            describe(0x8115),
            "Monitoring · communication · CAN overrun (objects lost) (0x8115 not listed)"
        );
    }

    #[test]
    fn undefined_codes() {
        for code in [
            0x0100, 0x0FFF, 0x1100, 0x1FFF, 0x5600, 0x7700, 0x9100, 0xA000, 0xEFFF,
        ] {
            let info = lookup(code);
            assert_eq!(info.class, Class::Undefined, "{code:#06x}");
            assert!(!info.listed);
            assert!(info.parts().is_empty());
            assert_eq!(
                info.description().to_string(),
                "undefined code (not in CiA 301 or CiA 402)"
            );
        }
    }

    #[test]
    fn classes_of_ranges_and_boundaries() {
        use Class::*;
        let cases = [
            (0x0000, Reset),
            (0x00FF, Reset),
            (0x0100, Undefined),
            (0x0FFF, Undefined),
            (0x1000, Generic),
            (0x10FF, Generic),
            (0x1100, Undefined),
            (0x1FFF, Undefined),
            (0x2000, Current),
            (0x2FFF, Current),
            (0x3000, Voltage),
            (0x3FFF, Voltage),
            (0x4000, Temperature),
            (0x4FFF, Temperature),
            (0x5000, Hardware),
            (0x50FF, Hardware),
            (0x5100, Hardware),
            (0x55FF, Hardware),
            (0x5600, Undefined),
            (0x5FFF, Undefined),
            (0x6000, Software),
            (0x6FFF, Software),
            (0x7000, Modules),
            (0x70FF, Modules),
            (0x7100, Modules),
            (0x76FF, Modules),
            (0x7700, Undefined),
            (0x7FFF, Undefined),
            (0x8000, Monitoring),
            (0x80FF, Monitoring),
            (0x8100, Communication),
            (0x81FF, Communication),
            (0x8200, Communication),
            (0x82FF, Communication),
            (0x8300, Monitoring),
            (0x8A00, Monitoring),
            (0x8FFF, Monitoring),
            (0x9000, External),
            (0x90FF, External),
            (0x9100, Undefined),
            (0xA000, Undefined),
            (0xEFFF, Undefined),
            (0xF000, AdditionalFunctions),
            (0xF0FF, AdditionalFunctions),
            (0xF100, Undefined),
            (0xFEFF, Undefined),
            (0xFF00, Manufacturer),
            (0xFFFF, Manufacturer),
        ];
        for (code, class) in cases {
            assert_eq!(lookup(code).class, class, "{code:#06x}");
        }
    }

    #[test]
    fn register_bits_follow_the_class() {
        assert_eq!(lookup(0x2310).class.register_bit(), Some(1));
        assert_eq!(lookup(0x3110).class.register_bit(), Some(2));
        assert_eq!(lookup(0x4310).class.register_bit(), Some(3));
        assert_eq!(lookup(0x8110).class.register_bit(), Some(4));
        assert_eq!(lookup(0x8250).class.register_bit(), Some(4));
        assert_eq!(lookup(0x8611).class.register_bit(), None);
        assert_eq!(lookup(0xFF42).class.register_bit(), Some(7));
        assert_eq!(lookup(0x0000).class.register_bit(), None);
    }

    /// The CiA 301 class code/mask pairs, written out independently of `CLASSES`.
    const CIA301_CLASSES: [(u16, u16); 12] = [
        (0x0000, 0xFF00),
        (0x1000, 0xFF00),
        (0x2000, 0xF000),
        (0x3000, 0xF000),
        (0x4000, 0xF000),
        (0x5000, 0xFF00),
        (0x6000, 0xF000),
        (0x7000, 0xFF00),
        (0x8000, 0xF000),
        (0x9000, 0xFF00),
        (0xF000, 0xFF00),
        (0xFF00, 0xFF00),
    ];

    fn covered(code: u16) -> bool {
        CIA301_CLASSES
            .iter()
            .any(|&(value, mask)| code & mask == value)
            || LEVELS.iter().any(|level| {
                level
                    .entries
                    .iter()
                    .any(|entry| code & level.mask == entry.value)
            })
    }

    #[test]
    fn every_code_looks_up_and_is_undefined_iff_uncovered() {
        for code in 0..=u16::MAX {
            let info = lookup(code);
            assert_eq!(info.code, code);
            assert_eq!(
                info.class == Class::Undefined,
                !covered(code),
                "{code:#06x}"
            );
            assert!(info.parts().len() <= 4);
            if info.class == Class::Undefined {
                assert!(!info.listed && info.parts().is_empty(), "{code:#06x}");
            } else {
                assert!(!info.parts().is_empty(), "{code:#06x}");
                assert_eq!(info.listed, has_row(code) || code >= 0xFF00, "{code:#06x}");
            }
            let text = info.description().to_string();
            assert_eq!(
                text.contains("not listed"),
                !info.listed && info.class != Class::Undefined
            );
        }
    }

    /// Whether CiA 301 alone defines `code` at all: its class code/mask
    /// pairs decide (every lower row sits inside one of them).
    fn covered_301(code: u16) -> bool {
        CIA301_CLASSES
            .iter()
            .any(|&(value, mask)| code & mask == value)
    }

    #[test]
    fn cia301_tables_know_only_cia301() {
        for code in 0..=u16::MAX {
            let info = lookup_in(code, Tables::Cia301);
            assert_eq!(info.tables, Tables::Cia301);
            assert_eq!(
                info.class == Class::Undefined,
                !covered_301(code),
                "{code:#06x}"
            );
            // Never more text than the full tables, and the same class
            // wherever CiA 301 defines the code at all.
            let full = lookup(code);
            assert!(info.parts().len() <= full.parts().len(), "{code:#06x}");
            if info.class != Class::Undefined {
                assert_eq!(info.class, full.class, "{code:#06x}");
                assert!(full.parts().starts_with(info.parts()), "{code:#06x}");
            }
        }
        let d = |code| lookup_in(code, Tables::Cia301).description().to_string();
        assert_eq!(d(0x4310), "Temperature (0x4310 not listed)");
        assert_eq!(d(0x4210), "Temperature · device (0x4210 not listed)");
        assert_eq!(d(0x2310), "Current · output side (0x2310 not listed)");
        assert_eq!(
            d(0x8130),
            "Monitoring · communication · life guard or heartbeat error"
        );
        assert_eq!(
            d(0x8252),
            "Monitoring · protocol error · RPDO timeout · RPDO 2 timeout"
        );
        assert_eq!(d(0x5000), "Device hardware");
        assert_eq!(d(0x5100), "undefined code (not in CiA 301)");
        assert_eq!(d(0x7120), "undefined code (not in CiA 301)");
        assert_eq!(d(0x70FF), "Additional modules (0x70FF not listed)");
        assert_eq!(d(0x8611), "Monitoring (0x8611 not listed)");
        assert_eq!(d(0xFF01), "Device specific · manufacturer-specific");
        assert!(lookup_in(0x5530, Tables::Cia402).listed);
        assert!(!lookup_in(0x5530, Tables::Cia301).listed);
    }

    #[test]
    fn the_tables_differ_and_their_slugs_read_back() {
        assert_eq!(lookup_in(0x5100, Tables::Cia402).class, Class::Hardware);
        assert_eq!(lookup_in(0x5100, Tables::Cia301).class, Class::Undefined);
        assert_eq!(lookup_in(0x5100, Tables::Cia402), lookup(0x5100));
        assert_eq!(Tables::from_slug("cia301"), Some(Tables::Cia301));
        assert_eq!(
            Tables::from_slug(Tables::Cia402.slug()),
            Some(Tables::Cia402)
        );
        assert_eq!(Tables::from_slug("cia401"), None);
    }

    #[test]
    fn tables_are_sorted_and_aligned() {
        for pair in CLASSES.windows(2) {
            if let [a, b] = pair {
                assert!(a.last < b.first, "{:#06x}", b.first);
            }
        }
        for row in &CLASSES {
            assert!(row.first <= row.last);
            assert_eq!(row.first & 0x00FF, 0, "{:#06x}", row.first);
            assert_eq!(row.last & 0x00FF, 0x00FF, "{:#06x}", row.last);
        }
        // (mask, the next coarser mask): an entry must be aligned to its own
        // mask but not to the coarser one, so no value lives in two levels.
        let coarser = [0xF000u16, 0xFF00, 0xFFF0];
        for (level, coarse) in LEVELS.iter().zip(coarser) {
            assert!(!level.entries.is_empty());
            for pair in level.entries.windows(2) {
                if let [a, b] = pair {
                    assert!(a.value < b.value, "{:#06x} after {:#06x}", b.value, a.value);
                }
            }
            for entry in level.entries {
                assert_eq!(entry.value & !level.mask, 0, "{:#06x}", entry.value);
                assert_ne!(entry.value & !coarse, 0, "{:#06x}", entry.value);
                // Every entry needs a class above it or it could never be found.
                assert!(class_row(entry.value).is_some(), "{:#06x}", entry.value);
                for text in [entry.label, entry.text] {
                    assert!(!text.is_empty(), "{:#06x}", entry.value);
                    assert_eq!(text.trim(), text, "{:#06x}", entry.value);
                    assert!(!text.contains('·'), "{:#06x}", entry.value);
                }
            }
        }
    }

    #[test]
    fn all_entries_lists_each_row_once() {
        let entries: Vec<CodeInfo> = all_entries().collect();
        let rows = CLASSES.len() + LEVELS.iter().map(|l| l.entries.len()).sum::<usize>();
        assert_eq!(entries.len(), rows);
        assert!(entries.iter().all(|info| info.listed));
        assert!(
            entries
                .windows(2)
                .all(|w| matches!(w, [a, b] if a.code < b.code))
        );
        assert_eq!(entries.first().map(|i| i.code), Some(0x0000));
        assert_eq!(entries.last().map(|i| i.code), Some(0xFF00));
    }

    /// Every row of the tables (emcy.md §4 classes, subgroups and exact codes,
    /// §5 CiA 402 codes with ranges spelled out) with the text it must end in.
    /// Written out by hand so a broken or missing table row fails here.
    const ALL_ROWS: &[(u16, &str)] = &[
        // CiA 301 classes.
        (0x0000, "Error reset or no error"),
        (0x1000, "Generic error"),
        (0x2000, "Current"),
        (0x3000, "Voltage"),
        (0x4000, "Temperature"),
        (0x5000, "Device hardware"),
        (0x6000, "Device software"),
        (0x7000, "Additional modules"),
        (0x8000, "Monitoring"),
        (0x9000, "External error"),
        (0xF000, "Additional functions"),
        (0xFF00, "manufacturer-specific"),
        // Current.
        (0x2100, "device input side"),
        (0x2110, "short circuit/earth leakage (input)"),
        (0x2120, "earth leakage (input)"),
        (0x2121, "earth leakage phase L1"),
        (0x2122, "earth leakage phase L2"),
        (0x2123, "earth leakage phase L3"),
        (0x2130, "short circuit (input)"),
        (0x2131, "short circuit phases L1-L2"),
        (0x2132, "short circuit phases L2-L3"),
        (0x2133, "short circuit phases L3-L1"),
        (0x2200, "inside the device"),
        (0x2211, "internal current no.1"),
        (0x2212, "internal current no.2"),
        (0x2213, "over-current in ramp function"),
        (0x2214, "over-current in the sequence"),
        (0x2220, "continuous over current (device internal)"),
        (0x2221, "continuous over current no.1"),
        (0x2222, "continuous over current no.2"),
        (0x2230, "short circuit/earth leakage (device internal)"),
        (0x2240, "earth leakage (device internal)"),
        (0x2250, "short circuit (device internal)"),
        (0x2300, "output side"),
        (0x2310, "continuous over current"),
        (0x2311, "continuous over current no.1"),
        (0x2312, "continuous over current no.2"),
        (0x2320, "short circuit/earth leakage (motor side)"),
        (0x2330, "earth leakage (motor side)"),
        (0x2331, "earth leakage phase U"),
        (0x2332, "earth leakage phase V"),
        (0x2333, "earth leakage phase W"),
        (0x2340, "short circuit (motor side)"),
        (0x2341, "short circuit phases U-V"),
        (0x2342, "short circuit phases V-W"),
        (0x2343, "short circuit phases W-U"),
        (0x2350, "load level fault (I2t, thermal state)"),
        (0x2351, "load level warning"),
        // Voltage.
        (0x3100, "mains voltage"),
        (0x3110, "mains over-voltage"),
        (0x3111, "mains over-voltage phase L1"),
        (0x3112, "mains over-voltage phase L2"),
        (0x3113, "mains over-voltage phase L3"),
        (0x3120, "mains under-voltage"),
        (0x3121, "mains under-voltage phase L1"),
        (0x3122, "mains under-voltage phase L2"),
        (0x3123, "mains under-voltage phase L3"),
        (0x3130, "phase failure"),
        (0x3131, "phase failure L1"),
        (0x3132, "phase failure L2"),
        (0x3133, "phase failure L3"),
        (0x3134, "phase sequence"),
        (0x3140, "mains frequency"),
        (0x3141, "mains frequency too great"),
        (0x3142, "mains frequency too small"),
        (0x3200, "inside the device"),
        (0x3210, "DC link over-voltage"),
        (0x3211, "DC link over-voltage no.1"),
        (0x3212, "DC link over-voltage no.2"),
        (0x3220, "DC link under-voltage"),
        (0x3221, "DC link under-voltage no.1"),
        (0x3222, "DC link under-voltage no.2"),
        (0x3230, "load error"),
        (0x3300, "output voltage"),
        (0x3310, "output over-voltage"),
        (0x3311, "output over-voltage phase U"),
        (0x3312, "output over-voltage phase V"),
        (0x3313, "output over-voltage phase W"),
        (0x3320, "armature circuit"),
        (0x3321, "armature circuit interrupted"),
        (0x3330, "field circuit"),
        (0x3331, "field circuit interrupted"),
        // Temperature.
        (0x4100, "ambient temperature"),
        (0x4110, "excess ambient temperature"),
        (0x4120, "too low ambient temperature"),
        (0x4130, "supply air temperature"),
        (0x4140, "air outlet temperature"),
        (0x4200, "device temperature"),
        (0x4210, "excess temperature device"),
        (0x4220, "too low temperature device"),
        (0x4300, "drive temperature"),
        (0x4310, "excess temperature drive"),
        (0x4320, "too low temperature drive"),
        (0x4400, "supply temperature"),
        (0x4410, "excess temperature supply"),
        (0x4420, "too low temperature supply"),
        // Device hardware.
        (0x5100, "supply"),
        (0x5110, "supply low voltage"),
        (0x5111, "U1 = supply +/-15 V"),
        (0x5112, "U2 = supply +24 V"),
        (0x5113, "U3 = supply +5 V"),
        (0x5114, "U4 manufacturer specific"),
        (0x5115, "U5 manufacturer specific"),
        (0x5116, "U6 manufacturer specific"),
        (0x5117, "U7 manufacturer specific"),
        (0x5118, "U8 manufacturer specific"),
        (0x5119, "U9 manufacturer specific"),
        (0x5120, "supply intermediate circuit"),
        (0x5200, "control"),
        (0x5210, "measurement circuit"),
        (0x5220, "computing circuit"),
        (0x5300, "operating unit"),
        (0x5400, "power section"),
        (0x5410, "output stages"),
        (0x5420, "chopper"),
        (0x5430, "input stages"),
        (0x5440, "contacts"),
        (0x5441, "contact 1 (manufacturer specific)"),
        (0x5442, "contact 2 (manufacturer specific)"),
        (0x5443, "contact 3 (manufacturer specific)"),
        (0x5444, "contact 4 (manufacturer specific)"),
        (0x5445, "contact 5 (manufacturer specific)"),
        (0x5450, "fuses"),
        (0x5451, "S1 = L1"),
        (0x5452, "S2 = L2"),
        (0x5453, "S3 = L3"),
        (0x5454, "S4 manufacturer specific"),
        (0x5455, "S5 manufacturer specific"),
        (0x5456, "S6 manufacturer specific"),
        (0x5457, "S7 manufacturer specific"),
        (0x5458, "S8 manufacturer specific"),
        (0x5459, "S9 manufacturer specific"),
        (0x5500, "hardware memory"),
        (0x5510, "RAM"),
        (0x5520, "ROM/EPROM"),
        (0x5530, "EEPROM"),
        // Device software.
        (0x6010, "software reset (watchdog)"),
        (0x6100, "internal software"),
        (0x6200, "user software"),
        (0x6300, "data set"),
        (0x6301, "data record no.1"),
        (0x6302, "data record no.2"),
        (0x6303, "data record no.3"),
        (0x6304, "data record no.4"),
        (0x6305, "data record no.5"),
        (0x6306, "data record no.6"),
        (0x6307, "data record no.7"),
        (0x6308, "data record no.8"),
        (0x6309, "data record no.9"),
        (0x630A, "data record no.10"),
        (0x630B, "data record no.11"),
        (0x630C, "data record no.12"),
        (0x630D, "data record no.13"),
        (0x630E, "data record no.14"),
        (0x630F, "data record no.15"),
        (0x6310, "loss of parameters"),
        (0x6320, "parameter error"),
        // Additional modules.
        (0x7100, "power"),
        (0x7110, "brake chopper"),
        (0x7111, "failure brake chopper"),
        (0x7112, "over current brake chopper"),
        (0x7113, "protective circuit brake chopper"),
        (0x7120, "motor"),
        (0x7121, "motor blocked"),
        (0x7122, "motor error or commutation malfunction"),
        (0x7123, "motor tilted"),
        (0x7200, "measurement circuit"),
        (0x7300, "sensor"),
        (0x7301, "tacho fault"),
        (0x7302, "tacho wrong polarity"),
        (0x7303, "resolver 1 fault"),
        (0x7304, "resolver 2 fault"),
        (0x7305, "incremental sensor 1 fault"),
        (0x7306, "incremental sensor 2 fault"),
        (0x7307, "incremental sensor 3 fault"),
        (0x7310, "speed"),
        (0x7320, "position"),
        (0x7400, "computation circuit"),
        (0x7500, "communication"),
        (0x7510, "serial interface no.1"),
        (0x7520, "serial interface no.2"),
        (0x7600, "data storage (external)"),
        // Monitoring: CiA 301 communication and protocol errors.
        (0x8100, "communication"),
        (0x8110, "CAN overrun (objects lost)"),
        (0x8120, "CAN in error passive mode"),
        (0x8130, "life guard or heartbeat error"),
        (0x8140, "recovered from bus off"),
        (0x8150, "CAN-ID collision"),
        (0x8200, "protocol error"),
        (0x8210, "PDO not processed due to length error"),
        (0x8211, "PDO 1 not processed due to length error"),
        (0x8212, "PDO 2 not processed due to length error"),
        (0x8213, "PDO 3 not processed due to length error"),
        (0x8214, "PDO 4 not processed due to length error"),
        (0x8220, "PDO length exceeded"),
        (0x8221, "PDO 1 length exceeded"),
        (0x8222, "PDO 2 length exceeded"),
        (0x8223, "PDO 3 length exceeded"),
        (0x8224, "PDO 4 length exceeded"),
        (
            0x8230,
            "DAM MPDO not processed, destination object not available",
        ),
        (0x8240, "unexpected SYNC data length"),
        (0x8250, "RPDO timeout"),
        (0x8251, "RPDO 1 timeout"),
        (0x8252, "RPDO 2 timeout"),
        (0x8253, "RPDO 3 timeout"),
        (0x8254, "RPDO 4 timeout"),
        // Monitoring: CiA 402 control loops.
        (0x8300, "torque control"),
        (0x8311, "excess torque"),
        (0x8312, "difficult start up"),
        (0x8313, "standstill torque"),
        (0x8321, "insufficient torque"),
        (0x8331, "torque fault"),
        (0x8400, "velocity speed controller"),
        (0x8500, "position controller"),
        (0x8600, "positioning controller"),
        (0x8611, "following error"),
        (0x8612, "reference limit"),
        (0x8700, "sync controller"),
        (0x8800, "winding controller"),
        (0x8900, "process data monitoring"),
        (0x8A00, "control"),
        // Additional functions.
        (0xF001, "deceleration"),
        (0xF002, "sub-synchronous run"),
        (0xF003, "stroke operation"),
        (0xF004, "control"),
    ];

    #[test]
    fn every_row_is_listed_with_its_text() {
        for &(code, text) in ALL_ROWS {
            let info = lookup(code);
            assert!(info.listed, "{code:#06x} not listed");
            assert_ne!(info.class, Class::Undefined, "{code:#06x}");
            assert_eq!(info.parts().last(), Some(&text), "{code:#06x}");
        }
        // Nothing in the tables escapes the list above.
        let listed: Vec<u16> = all_entries().map(|info| info.code).collect();
        let mut expected: Vec<u16> = ALL_ROWS.iter().map(|&(code, _)| code).collect();
        expected.sort_unstable();
        let before_dedup = expected.len();
        expected.dedup();
        assert_eq!(expected.len(), before_dedup, "a code is in ALL_ROWS twice");
        assert_eq!(listed, expected);
    }
}
