//! CiA 301 / CiA 402 emergency error codes (placeholder interface; the full
//! tables land in their own change).

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

/// What the tables say about one code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodeInfo {
    pub code: u16,
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
}

pub struct Description(CodeInfo);

impl fmt::Display for Description {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let info = &self.0;
        if info.class == Class::Undefined {
            return f.write_str("undefined code (not in CiA 301 or CiA 402)");
        }
        for (i, part) in info.parts().iter().enumerate() {
            if i > 0 {
                f.write_str(" · ")?;
            }
            f.write_str(part)?;
        }
        Ok(())
    }
}

pub fn lookup(code: u16) -> CodeInfo {
    let (class, text) = match code >> 12 {
        0x0 if code <= 0xFF => (Class::Reset, "Error reset or no error"),
        0x2 => (Class::Current, "Current"),
        0x3 => (Class::Voltage, "Voltage"),
        0x4 => (Class::Temperature, "Temperature"),
        _ => (Class::Undefined, ""),
    };
    CodeInfo {
        code,
        class,
        listed: false,
        parts: [text, "", "", ""],
        len: u8::from(class != Class::Undefined),
    }
}
