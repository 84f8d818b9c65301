//! Vendor profiles: what a node's manufacturer-specific bytes (3-7) mean,
//! which code tables apply, the vendor's own code rows and register bit
//! names, and the rules the vendor's manual states (bytes that must be zero,
//! reserved register bits).
//!
//! Built-in profiles and user profiles share one TOML format and one loader:
//! the built-ins are the files in `src/canopen/profiles/`, compiled in, and
//! a user file names a built-in as its `base` and overrides or extends it.
//! The format is documented in docs/guide/profiles.md; `loader`
//! reads it. This file holds what a profile is and what it answers.

use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use super::codes::{self, Class, CodeInfo, Tables};
use super::emcy::{Emcy, Warning};
use super::register;

mod loader;
#[cfg(test)]
mod tests;

use loader::parse_with;

/// The profile a node gets when nothing else chooses one.
pub const DEFAULT_PROFILE: &str = "cia402";

/// The largest user profile read: the built-ins are a few KiB of TOML; a
/// file beyond this is something else (`/dev/zero`, a trace given by
/// mistake) and an error, not memory.
pub const MAX_BYTES: u64 = 16 << 20;

/// The first and last EMCY byte a manufacturer field may use.
const FIRST_BYTE: u8 = 3;
const LAST_BYTE: u8 = 7;

/// The built-in profiles in listing order. A built-in's `base` must come
/// earlier in this list.
const BUILTIN_FILES: [(&str, &str); 7] = [
    ("cia301.toml", include_str!("../profiles/cia301.toml")),
    ("cia402.toml", include_str!("../profiles/cia402.toml")),
    (
        "kollmorgen.toml",
        include_str!("../profiles/kollmorgen.toml"),
    ),
    (
        "beckhoff-ax2000.toml",
        include_str!("../profiles/beckhoff-ax2000.toml"),
    ),
    ("stoeber.toml", include_str!("../profiles/stoeber.toml")),
    (
        "festo-cmmp.toml",
        include_str!("../profiles/festo-cmmp.toml"),
    ),
    (
        "canopennode.toml",
        include_str!("../profiles/canopennode.toml"),
    ),
];

/// Vendor ids (object 0x1018 sub 1) that select a built-in profile, with
/// where each id was confirmed:
/// - 0x6A Kollmorgen: S300/S700 CANopen manual, object 1018h sub 1 default
///   value "0x6Ah (Kollmorgen)"; the AKD2G documentation calls it the vendor
///   id registered with CiA. The Beckhoff AX2000/AX2500 CANopen manual gives
///   the same default (0000006Ah), so an AX2000 is identified as `kollmorgen`
///   (same layout; only the code numbering rule differs).
/// - 0xB9 STÖBER: STÖBER CANopen manual (SD6, ID 442637.01), appendix
///   "Supported communication objects", 1018 sub 1 "STOBER manufacturer ID:
///   B9 hex".
/// - 0x1D Festo: Festo CTEU-EC manual, appendix A.4.2 (1018 sub 1
///   0x0000001D), and the Festo EMCA-EC manual (object 1018h, 0000001Dh).
///
/// Left out on purpose: Beckhoff's own id 2 (Beckhoff bus coupler
/// documentation: "Beckhoff has vendor ID 2") is not what an AX2000 reports,
/// and Beckhoff's id-2 drives and I/O use other EMCY layouts. CANopenNode
/// has no vendor id of its own (each device sets its own).
const VENDORS: [(u32, &str, &str); 3] = [
    (0x0000_006A, "kollmorgen", "Kollmorgen"),
    (0x0000_00B9, "stoeber", "STÖBER"),
    (0x0000_001D, "festo-cmmp", "Festo"),
];

/// The vendor's name, for a vendor id our profiles know.
pub fn vendor_name(vendor_id: u32) -> Option<&'static str> {
    VENDORS
        .iter()
        .find(|(v, _, _)| *v == vendor_id)
        .map(|(_, _, name)| *name)
}

/// CiA 402 in the low 16 bits of object 0x1000: a drive.
const DRIVE_PROFILE_NUMBER: u32 = 402;

/// A vendor's own row for an error code.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VendorCode {
    /// The vendor's text for the code.
    pub text: String,
    /// The error category the vendor gives the code (Kollmorgen 1-5).
    pub category: Option<u8>,
    /// The fault number the device shows (front panel `F06`).
    pub fault: Option<String>,
}

/// The decoded manufacturer-specific bytes, in layout order; the keys are
/// the JSON keys (`category`, `category_text`, ...).
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// (JSON key, value), in the profile's layout order.
    pub fields: Vec<(String, FieldValue)>,
}

impl Decoded {
    /// The value of one key (`category`).
    pub fn get(&self, key: &str) -> Option<&FieldValue> {
        self.fields.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
}

/// One decoded value: the number in the bytes, or its name.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldValue {
    /// The field's bytes as a little-endian number.
    Int(u64),
    /// The name the profile gives that number (the `_text` keys).
    Text(String),
}

/// What a field means to the decoder beyond its value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// The error category (`--fail-on category<=N`).
    Category,
    /// The error status bit a frame sets or clears (CANopenNode).
    StatusBit,
}

/// A named run of bytes in 3-7, little-endian, with optional value names.
#[derive(Clone, Debug, PartialEq)]
struct Field {
    name: String,
    text_key: String,
    first: u8,
    size: u8,
    role: Option<Role>,
    /// Inclusive value ranges and their names, sorted, not overlapping.
    values: Vec<(u64, u64, String)>,
}

impl Field {
    fn bytes(&self) -> Range<u8> {
        self.first..self.first + self.size
    }

    /// The field's value, if the frame carries all its bytes.
    fn read(&self, emcy: &Emcy) -> Option<u64> {
        let start = usize::from(self.first - FIRST_BYTE);
        let bytes = emcy
            .manufacturer()
            .get(start..start + usize::from(self.size))?;
        Some(
            bytes
                .iter()
                .rev()
                .fold(0u64, |acc, b| (acc << 8) | u64::from(*b)),
        )
    }

    fn value_text(&self, value: u64) -> Option<&str> {
        self.values
            .iter()
            .find(|(lo, hi, _)| (*lo..=*hi).contains(&value))
            .map(|(_, _, text)| text.as_str())
    }
}

/// A vendor profile: how a vendor describes its codes and what its EMCY
/// manufacturer bytes mean. Built-ins come from [`Profile::builtin`], user
/// profiles from [`Profile::load`] or [`Profile::parse`].
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    name: String,
    summary: String,
    base: Option<String>,
    tables: Tables,
    codes: BTreeMap<u16, VendorCode>,
    fields: Vec<Field>,
    /// Bit n set: EMCY byte n must be zero (n in 3-7).
    zero_bytes: u8,
    /// Bit n set: error register bit n is reserved (must be 0).
    reserved_bits: u8,
    bit_names: [Option<String>; 8],
    /// Codes whose low byte falls in this range are manufacturer-specific.
    manufacturer_low_bytes: Option<(u8, u8)>,
    /// The vendor's drives set register bit 0 (generic) with an error
    /// (`register_generic_bit`; false: its manual shows them never doing so).
    generic_bit: bool,
    /// The register carries the bit of the code's class
    /// (`register_class_bits`; false: its manual shows codes without it).
    class_bits: bool,
}

impl Profile {
    fn empty(name: String, tables: Tables) -> Profile {
        Profile {
            name,
            summary: String::new(),
            base: None,
            tables,
            codes: BTreeMap::new(),
            fields: Vec::new(),
            zero_bytes: 0,
            reserved_bits: 0,
            bit_names: Default::default(),
            manufacturer_low_bytes: None,
            generic_bit: true,
            class_bits: true,
        }
    }

    /// The built-in's name (`kollmorgen`), or the user profile's `name`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The built-in profiles, in listing order.
    pub fn builtins() -> &'static [Profile] {
        builtins()
    }

    /// The built-in profile of this name.
    pub fn builtin(name: &str) -> Option<&'static Profile> {
        builtins().iter().find(|p| p.name == name)
    }

    /// The TOML file a built-in profile is made from, as shipped (with its
    /// comments and sources): a starting point for a user profile.
    pub fn builtin_toml(name: &str) -> Option<&'static str> {
        let i = builtins().iter().position(|p| p.name == name)?;
        BUILTIN_FILES.get(i).map(|(_, text)| *text)
    }

    /// Reads and parses a user profile file (TOML, see docs/guide/profiles.md; at most
    /// [`MAX_BYTES`]); errors name the path and line.
    pub fn load(path: &Path) -> Result<Profile, ProfileError> {
        let origin = path.display().to_string();
        let text =
            crate::small_file::read_to_string(path, MAX_BYTES, "a profile").map_err(|e| {
                ProfileError {
                    origin: origin.clone(),
                    line: None,
                    message: e.to_string(),
                }
            })?;
        Profile::parse(&origin, &text)
    }

    /// Parses a user profile's text; `origin` names it in errors (usually
    /// the path). Its `base` may be any built-in.
    pub fn parse(origin: &str, text: &str) -> Result<Profile, ProfileError> {
        parse_with(origin, text, builtins())
    }

    /// One line for `emcy-decode profiles`.
    pub fn summary(&self) -> &str {
        &self.summary
    }

    /// The built-in this profile extends, if any.
    pub fn base(&self) -> Option<&str> {
        self.base.as_deref()
    }

    /// The CiA code tables this profile describes codes with.
    pub fn tables(&self) -> Tables {
        self.tables
    }

    /// The vendor row's text with its fault number (`F06 motor temperature`)
    /// if the profile has one; else, for a code the profile's numbering rule
    /// makes manufacturer-specific, its class and that; else the CiA
    /// description from the profile's tables.
    pub fn describe(&self, code: u16) -> String {
        if let Some(row) = self.codes.get(&code) {
            return match &row.fault {
                Some(fault) => format!("{fault} {}", row.text),
                None => row.text.clone(),
            };
        }
        let info = self.info(code);
        if let Some((lo, hi)) = self.manufacturer_low_bytes
            && (lo..=hi).contains(&((code & 0x00FF) as u8))
            && !matches!(info.class, Class::Reset | Class::Manufacturer)
        {
            let rule = format!("manufacturer-specific (low byte 0x{lo:02X}-0x{hi:02X})");
            return match info.class {
                Class::Undefined => rule,
                class => format!("{} · {rule}", class.name()),
            };
        }
        info.description().to_string()
    }

    /// What the profile's CiA tables say about `code`.
    pub fn info(&self, code: u16) -> CodeInfo {
        codes::lookup_in(code, self.tables)
    }

    /// The vendor's own row for `code`, if the profile has one.
    pub fn vendor_code(&self, code: u16) -> Option<&VendorCode> {
        self.codes.get(&code)
    }

    /// Every vendor row, ascending by code.
    pub fn vendor_codes(&self) -> impl Iterator<Item = (u16, &VendorCode)> {
        self.codes.iter().map(|(code, row)| (*code, row))
    }

    /// The manufacturer-specific bytes decoded by the profile's layout; None
    /// when the profile has no layout (`cia301`, `cia402`, `festo-cmmp`) or
    /// the frame is too short for any of its fields. A field whose bytes the
    /// frame lacks is left out; a value with a name gets `<field>_text` too.
    pub fn decode_manufacturer(&self, emcy: &Emcy) -> Option<Decoded> {
        let mut fields = Vec::new();
        for field in &self.fields {
            let Some(value) = field.read(emcy) else {
                continue;
            };
            fields.push((field.name.clone(), FieldValue::Int(value)));
            if let Some(text) = field.value_text(value) {
                fields.push((field.text_key.clone(), FieldValue::Text(text.to_owned())));
            }
        }
        (!fields.is_empty()).then_some(Decoded { fields })
    }

    /// The profile's own frame rules, after the CiA 301 checks of
    /// [`Emcy::frame_warnings`]: bytes that must be zero (one warning naming
    /// the first and last offending byte) and reserved register bits. Bit 6
    /// is left to the CiA 301 check (`reserved_bit`), which always applies.
    ///
    /// Where the vendor's manual shows its drives never setting the generic
    /// bit, or sending codes without their class bit, the CiA 301 warnings
    /// about it are taken back: what the manual shows as normal is no news
    /// on every frame.
    pub fn frame_warnings(&self, emcy: &Emcy, out: &mut Vec<Warning>) {
        if !self.generic_bit || !self.class_bits {
            out.retain(|w| match w {
                Warning::NoGenericBit { .. } => self.generic_bit,
                Warning::ClassRegisterMismatch { .. } => self.class_bits,
                _ => true,
            });
        }
        let nonzero: Vec<u8> = (FIRST_BYTE..)
            .zip(emcy.manufacturer())
            .filter(|(byte, value)| self.zero_bytes & (1 << byte) != 0 && **value != 0)
            .map(|(byte, _)| byte)
            .collect();
        if let (Some(&first), Some(&last)) = (nonzero.first(), nonzero.last()) {
            out.push(Warning::ManufacturerBytesNonZero { first, last });
        }
        for bit in 0..8u8 {
            if bit != register::RESERVED
                && self.reserved_bits & (1 << bit) != 0
                && emcy.register.has(bit)
            {
                out.push(Warning::ProfileReservedBit { bit });
            }
        }
    }

    /// The profile's own name for error register bit `bit` (Festo: bit 1 is
    /// "I2t"); None where the CiA 301 name applies.
    pub fn register_bit_name(&self, bit: u8) -> Option<&str> {
        self.bit_names.get(usize::from(bit))?.as_deref()
    }

    /// The error status bit the frame sets or clears, under a profile that
    /// has one (CANopenNode: byte 3), when the frame carries that byte.
    pub fn status_bit(&self, emcy: &Emcy) -> Option<u8> {
        let field = self.field_with(Role::StatusBit)?;
        u8::try_from(field.read(emcy)?).ok()
    }

    /// The error category: the category field's value when the frame carries
    /// one the profile names (a reset's 0 is no category), else the vendor
    /// row's category for the code.
    pub fn category(&self, emcy: &Emcy) -> Option<u8> {
        let from_field = self.field_with(Role::Category).and_then(|field| {
            let value = field.read(emcy)?;
            let known = if field.values.is_empty() {
                value != 0
            } else {
                field.value_text(value).is_some()
            };
            known.then(|| u8::try_from(value).ok()).flatten()
        });
        from_field.or_else(|| self.codes.get(&emcy.code)?.category)
    }

    /// Whether any EMCY can have a category under this profile (a category
    /// field, or a code row with one): `--fail-on category<=N` means
    /// nothing for nodes without.
    pub fn has_categories(&self) -> bool {
        self.field_with(Role::Category).is_some()
            || self.codes.values().any(|c| c.category.is_some())
    }

    fn field_with(&self, role: Role) -> Option<&Field> {
        self.fields.iter().find(|f| f.role == Some(role))
    }
}

/// The built-in profiles, in listing order.
fn builtins() -> &'static [Profile] {
    static BUILTINS: OnceLock<Vec<Profile>> = OnceLock::new();
    BUILTINS.get_or_init(|| {
        let mut loaded: Vec<Profile> = Vec::with_capacity(BUILTIN_FILES.len());
        for (file, text) in BUILTIN_FILES {
            let origin = format!("built-in profile {file}");
            // Every built-in is parsed by a unit test, so this only fires on
            // a broken edit of src/canopen/profiles/.
            match parse_with(&origin, text, &loaded) {
                Ok(profile) => loaded.push(profile),
                Err(e) => panic!("{e}"),
            }
        }
        loaded
    })
}

/// Which built-in profile the trace's identity objects select, and why.
/// `device_type` is object 0x1000, `vendor_id` object 0x1018 sub 1.
///
/// A known vendor id picks the vendor's profile unless the device type says
/// the node is not a drive (all vendor profiles here are drive profiles).
/// Otherwise the device type decides: profile number 402 is `cia402`, any
/// other number `cia301` (CiA 401 I/O reuses drive codes with other
/// meanings). None when neither object is known or says anything.
pub fn for_identity(
    device_type: Option<u32>,
    vendor_id: Option<u32>,
) -> Option<(&'static Profile, String)> {
    let profile_number = device_type.map(|dt| dt & 0xFFFF);
    let is_drive = profile_number.is_none_or(|n| n == DRIVE_PROFILE_NUMBER);
    if let Some(id) = vendor_id
        && is_drive
        && let Some((_, name, vendor)) = VENDORS.iter().find(|(v, _, _)| *v == id)
        && let Some(profile) = Profile::builtin(name)
    {
        return Some((profile, format!("vendor id 0x{id:08X} ({vendor})")));
    }
    let number = profile_number?;
    if number == DRIVE_PROFILE_NUMBER {
        let profile = Profile::builtin("cia402")?;
        return Some((profile, format!("device type {number} (drive)")));
    }
    let profile = Profile::builtin("cia301")?;
    Some((profile, format!("device type {number} (not a drive)")))
}

/// An error in a profile file: `origin:line: message`, or `origin: message`
/// when there is no line (the file could not be read).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProfileError {
    origin: String,
    line: Option<usize>,
    message: String,
}

impl ProfileError {
    /// The line of the file, when the error is at one.
    pub fn line(&self) -> Option<usize> {
        self.line
    }

    /// What is wrong, without the file and line.
    pub fn message(&self) -> &str {
        &self.message
    }
}

impl fmt::Display for ProfileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}: {}", self.origin, self.message),
            None => write!(f, "{}: {}", self.origin, self.message),
        }
    }
}

impl std::error::Error for ProfileError {}
