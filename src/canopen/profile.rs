//! Vendor profiles: what a node's manufacturer-specific bytes (3-7) mean,
//! which code tables apply, the vendor's own code rows and register bit
//! names, and the rules the vendor's manual states (bytes that must be zero,
//! reserved register bits).
//!
//! Built-in profiles and user profiles share one TOML format and one loader:
//! the built-ins are the files in `src/canopen/profiles/`, compiled in, and
//! a user file names a built-in as its `base` and overrides or extends it.
//! The format is documented in the README ("Vendor profiles").

use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use serde::Deserialize;
use toml::Spanned;

use super::codes::{self, Class, CodeInfo, Tables};
use super::emcy::{Emcy, Warning};
use super::register;

/// The profile a node gets when nothing else chooses one.
pub const DEFAULT_PROFILE: &str = "cia402";

/// The first and last EMCY byte a manufacturer field may use.
const FIRST_BYTE: u8 = 3;
const LAST_BYTE: u8 = 7;

/// The built-in profiles in listing order. A built-in's `base` must come
/// earlier in this list.
const BUILTIN_FILES: [(&str, &str); 7] = [
    ("cia301.toml", include_str!("profiles/cia301.toml")),
    ("cia402.toml", include_str!("profiles/cia402.toml")),
    ("kollmorgen.toml", include_str!("profiles/kollmorgen.toml")),
    (
        "beckhoff-ax2000.toml",
        include_str!("profiles/beckhoff-ax2000.toml"),
    ),
    ("stoeber.toml", include_str!("profiles/stoeber.toml")),
    ("festo-cmmp.toml", include_str!("profiles/festo-cmmp.toml")),
    (
        "canopennode.toml",
        include_str!("profiles/canopennode.toml"),
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

    /// Reads and parses a user profile file (TOML, see the README); errors
    /// name the path and line.
    pub fn load(path: &Path) -> Result<Profile, ProfileError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ProfileError {
            origin: origin.clone(),
            line: None,
            message: e.to_string(),
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

// ---- The file format ----------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileDoc {
    name: Spanned<String>,
    summary: Option<String>,
    base: Option<Spanned<String>>,
    tables: Option<Spanned<String>>,
    zero_bytes: Option<Vec<Spanned<i64>>>,
    reserved_register_bits: Option<Vec<Spanned<i64>>>,
    manufacturer_low_bytes: Option<Spanned<Vec<i64>>>,
    register_generic_bit: Option<bool>,
    register_class_bits: Option<bool>,
    #[serde(default)]
    register_bits: BTreeMap<Spanned<String>, Spanned<String>>,
    #[serde(default, rename = "field")]
    fields: Vec<Spanned<FieldDoc>>,
    #[serde(default)]
    codes: BTreeMap<Spanned<String>, Spanned<CodeDoc>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FieldDoc {
    name: Spanned<String>,
    byte: Spanned<i64>,
    size: Option<Spanned<i64>>,
    role: Option<Spanned<String>>,
    #[serde(default)]
    values: BTreeMap<Spanned<String>, Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CodeDoc {
    text: Spanned<String>,
    category: Option<Spanned<i64>>,
    fault: Option<Spanned<String>>,
}

/// Builds errors with line numbers from byte offsets into one text.
struct Errors<'a> {
    origin: &'a str,
    text: &'a str,
}

impl Errors<'_> {
    fn at(&self, span: Range<usize>, message: impl Into<String>) -> ProfileError {
        let end = span.start.min(self.text.len());
        let before = self.text.get(..end).unwrap_or("");
        ProfileError {
            origin: self.origin.to_owned(),
            line: Some(before.bytes().filter(|b| *b == b'\n').count() + 1),
            message: message.into(),
        }
    }

    fn toml_error(&self, e: &toml::de::Error) -> ProfileError {
        let message = e.message().trim().to_owned();
        match e.span() {
            Some(span) => self.at(span, message),
            None => ProfileError {
                origin: self.origin.to_owned(),
                line: None,
                message,
            },
        }
    }
}

/// A number written as a TOML string key: decimal, or hex with `0x`.
fn parse_number(text: &str) -> Option<u64> {
    let text = text.trim();
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => text.parse().ok(),
    }
}

fn is_json_key(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_lowercase())
        && chars.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

fn is_profile_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
}

fn byte_list(
    errors: &Errors<'_>,
    what: &str,
    items: &[Spanned<i64>],
    range: std::ops::RangeInclusive<i64>,
) -> Result<u8, ProfileError> {
    let mut mask = 0u8;
    for item in items {
        let value = *item.get_ref();
        if !range.contains(&value) {
            return Err(errors.at(
                item.span(),
                format!(
                    "{what} {value} is out of range ({}-{})",
                    range.start(),
                    range.end()
                ),
            ));
        }
        // In 0-7 by the check above.
        mask |= 1 << (value as u8);
    }
    Ok(mask)
}

fn parse_with(origin: &str, text: &str, bases: &[Profile]) -> Result<Profile, ProfileError> {
    let errors = Errors { origin, text };
    let doc: FileDoc = toml::from_str(text).map_err(|e| errors.toml_error(&e))?;

    let name = doc.name.get_ref().trim().to_owned();
    if !is_profile_name(&name) {
        return Err(errors.at(
            doc.name.span(),
            format!("profile name {name:?} must be letters, digits, '-', '_' or '.'"),
        ));
    }

    let mut profile = match &doc.base {
        Some(base) => {
            let Some(found) = bases.iter().find(|p| p.name == *base.get_ref()) else {
                let known: Vec<&str> = bases.iter().map(|p| p.name.as_str()).collect();
                return Err(errors.at(
                    base.span(),
                    format!(
                        "unknown base profile {:?} (built-ins: {})",
                        base.get_ref(),
                        known.join(", ")
                    ),
                ));
            };
            let mut p = found.clone();
            p.base = Some(found.name.clone());
            p.name = name.clone();
            p
        }
        None => Profile::empty(name.clone(), Tables::default()),
    };
    profile.summary = match &doc.summary {
        Some(summary) => summary.trim().to_owned(),
        None => match &profile.base {
            Some(base) => format!("user profile based on {base}"),
            None => "user profile".to_owned(),
        },
    };

    if let Some(tables) = &doc.tables {
        profile.tables = Tables::from_slug(tables.get_ref()).ok_or_else(|| {
            errors.at(
                tables.span(),
                format!(
                    "unknown tables {:?} (use \"cia301\" or \"cia402\")",
                    tables.get_ref()
                ),
            )
        })?;
    }

    if let Some(range) = &doc.manufacturer_low_bytes {
        let (lo, hi) = match range.get_ref().as_slice() {
            [lo, hi] if (0..=0xFF).contains(lo) && (*lo..=0xFF).contains(hi) => (*lo, *hi),
            _ => {
                return Err(errors.at(
                    range.span(),
                    "manufacturer_low_bytes must be [first, last] with 0 <= first <= last <= 0xFF",
                ));
            }
        };
        // Both in 0-255 by the match guard.
        profile.manufacturer_low_bytes = Some((lo as u8, hi as u8));
    }

    if let Some(bits) = &doc.reserved_register_bits {
        profile.reserved_bits = byte_list(&errors, "register bit", bits, 0..=7)?;
    }
    if let Some(set) = doc.register_generic_bit {
        profile.generic_bit = set;
    }
    if let Some(set) = doc.register_class_bits {
        profile.class_bits = set;
    }

    for (key, value) in &doc.register_bits {
        let bit = parse_number(key.get_ref())
            .filter(|bit| *bit <= 7)
            .ok_or_else(|| {
                errors.at(
                    key.span(),
                    format!("register bit {:?} is not a bit number 0-7", key.get_ref()),
                )
            })?;
        let text = value.get_ref().trim();
        if text.is_empty() {
            return Err(errors.at(value.span(), "register bit name is empty"));
        }
        if let Some(slot) = profile.bit_names.get_mut(bit as usize) {
            *slot = Some(text.to_owned());
        }
    }

    for (key, row) in &doc.codes {
        let code = key
            .get_ref()
            .trim()
            .strip_prefix("0x")
            .and_then(|hex| u16::from_str_radix(hex, 16).ok())
            .ok_or_else(|| {
                errors.at(
                    key.span(),
                    format!(
                        "error code {:?} must be hexadecimal with 0x, 0x0000-0xFFFF (e.g. \"0x4310\")",
                        key.get_ref()
                    ),
                )
            })?;
        let row = row.get_ref();
        let text = row.text.get_ref().trim();
        if text.is_empty() {
            return Err(errors.at(row.text.span(), "code text is empty"));
        }
        let category = match &row.category {
            Some(c) => Some(u8::try_from(*c.get_ref()).map_err(|_| {
                errors.at(
                    c.span(),
                    format!("category {} is out of range (0-255)", c.get_ref()),
                )
            })?),
            None => None,
        };
        let fault = match &row.fault {
            Some(f) if f.get_ref().trim().is_empty() => {
                return Err(errors.at(f.span(), "fault number is empty"));
            }
            Some(f) => Some(f.get_ref().trim().to_owned()),
            None => None,
        };
        profile.codes.insert(
            code,
            VendorCode {
                text: text.to_owned(),
                category,
                fault,
            },
        );
    }

    // Fields: a field named like an inherited one replaces it in place;
    // others are appended. Each new field is then checked against the rest.
    let mut spans: Vec<Option<Range<usize>>> = vec![None; profile.fields.len()];
    for doc_field in &doc.fields {
        let field = parse_field(&errors, doc_field)?;
        match profile.fields.iter().position(|f| f.name == field.name) {
            Some(i) => {
                if let (Some(slot), Some(span)) = (profile.fields.get_mut(i), spans.get_mut(i)) {
                    *slot = field;
                    *span = Some(doc_field.span());
                }
            }
            None => {
                profile.fields.push(field);
                spans.push(Some(doc_field.span()));
            }
        }
    }
    check_layout(&errors, &profile.fields, &spans)?;
    let field_bytes = profile
        .fields
        .iter()
        .flat_map(Field::bytes)
        .fold(0u8, |mask, byte| mask | (1 << byte));

    match &doc.zero_bytes {
        Some(list) => {
            let mask = byte_list(
                &errors,
                "byte",
                list,
                i64::from(FIRST_BYTE)..=i64::from(LAST_BYTE),
            )?;
            if let Some(item) = list
                .iter()
                .find(|item| field_bytes & (1 << (*item.get_ref() as u8)) != 0)
            {
                return Err(errors.at(
                    item.span(),
                    format!(
                        "byte {} is in zero_bytes but a field uses it",
                        item.get_ref()
                    ),
                ));
            }
            profile.zero_bytes = mask;
        }
        // Inherited: a field on a byte the base says is zero takes it over.
        None => profile.zero_bytes &= !field_bytes,
    }

    Ok(profile)
}

fn parse_field(errors: &Errors<'_>, doc: &Spanned<FieldDoc>) -> Result<Field, ProfileError> {
    let d = doc.get_ref();
    let name = d.name.get_ref().trim().to_owned();
    if !is_json_key(&name) {
        return Err(errors.at(
            d.name.span(),
            format!(
                "field name {name:?} must start with a-z and use only a-z, 0-9 and '_' (it is a JSON key)"
            ),
        ));
    }
    let first = *d.byte.get_ref();
    if !(i64::from(FIRST_BYTE)..=i64::from(LAST_BYTE)).contains(&first) {
        return Err(errors.at(
            d.byte.span(),
            format!("byte {first} is outside the manufacturer bytes 3-7"),
        ));
    }
    let size = d.size.as_ref().map_or(1, |s| *s.get_ref());
    if !(1..=5).contains(&size) || first + size - 1 > i64::from(LAST_BYTE) {
        let span = d.size.as_ref().map_or(d.byte.span(), Spanned::span);
        return Err(errors.at(
            span,
            format!("a field of {size} byte(s) at byte {first} does not fit in bytes 3-7"),
        ));
    }
    let role = match &d.role {
        None => None,
        Some(role) => Some(match role.get_ref().as_str() {
            "category" => Role::Category,
            "status_bit" => Role::StatusBit,
            other => {
                return Err(errors.at(
                    role.span(),
                    format!("unknown role {other:?} (use \"category\" or \"status_bit\")"),
                ));
            }
        }),
    };
    if role.is_some() && size != 1 {
        return Err(errors.at(
            doc.span(),
            format!("a field with a role is one byte; {name:?} has {size}"),
        ));
    }
    let max = if size >= 8 {
        u64::MAX
    } else {
        (1u64 << (8 * size)) - 1
    };
    let mut values: Vec<(u64, u64, String, Range<usize>)> = Vec::new();
    for (key, text) in &d.values {
        let key_text = key.get_ref().trim();
        let (lo, hi) = match key_text.split_once('-') {
            Some((lo, hi)) => (parse_number(lo), parse_number(hi)),
            None => (parse_number(key_text), parse_number(key_text)),
        };
        let (Some(lo), Some(hi)) = (lo, hi) else {
            return Err(errors.at(
                key.span(),
                format!(
                    "value {key_text:?} is not a number or range (e.g. \"41\", \"0x1E\", \"0x30-0x3F\")"
                ),
            ));
        };
        if lo > hi || hi > max {
            return Err(errors.at(
                key.span(),
                format!("value {key_text:?} does not fit field {name:?} (0-{max})"),
            ));
        }
        let text = text.get_ref().trim();
        if text.is_empty() {
            return Err(errors.at(key.span(), format!("value {key_text:?} has no text")));
        }
        values.push((lo, hi, text.to_owned(), key.span()));
    }
    values.sort_by_key(|(lo, ..)| *lo);
    for pair in values.windows(2) {
        if let [a, b] = pair
            && b.0 <= a.1
        {
            let (span_a, span_b) = (a.3.clone(), b.3.clone());
            // Report the later of the two in the file.
            let span = if span_a.start > span_b.start {
                span_a
            } else {
                span_b
            };
            return Err(errors.at(span, format!("values of field {name:?} overlap")));
        }
    }
    Ok(Field {
        text_key: format!("{name}_text"),
        name,
        first: first as u8,
        size: size as u8,
        role,
        values: values
            .into_iter()
            .map(|(lo, hi, text, _)| (lo, hi, text))
            .collect(),
    })
}

/// Fields must not share bytes, keys or roles. `spans` says where each field
/// was written in this file (None: inherited); an error is reported at the
/// field of this file involved.
fn check_layout(
    errors: &Errors<'_>,
    fields: &[Field],
    spans: &[Option<Range<usize>>],
) -> Result<(), ProfileError> {
    for (i, a) in fields.iter().enumerate() {
        for (j, b) in fields.iter().enumerate().skip(i + 1) {
            let problem = if a.bytes().any(|byte| b.bytes().contains(&byte)) {
                Some(format!("fields {:?} and {:?} share a byte", a.name, b.name))
            } else if [&a.name, &a.text_key].contains(&&b.name)
                || [&a.name, &a.text_key].contains(&&b.text_key)
            {
                Some(format!(
                    "fields {:?} and {:?} give the same JSON key",
                    a.name, b.name
                ))
            } else if a.role.is_some() && a.role == b.role {
                Some(format!(
                    "fields {:?} and {:?} have the same role",
                    a.name, b.name
                ))
            } else {
                None
            };
            if let Some(message) = problem {
                let span = spans
                    .get(j)
                    .cloned()
                    .flatten()
                    .or_else(|| spans.get(i).cloned().flatten())
                    .unwrap_or(0..0);
                return Err(errors.at(span, message));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(data: &[u8]) -> Emcy {
        Emcy::decode(data).expect("test frames carry code and register")
    }

    fn int(v: u64) -> FieldValue {
        FieldValue::Int(v)
    }

    fn text(t: &str) -> FieldValue {
        FieldValue::Text(t.to_owned())
    }

    fn profile(name: &str) -> &'static Profile {
        Profile::builtin(name).unwrap_or_else(|| panic!("no built-in {name}"))
    }

    #[test]
    fn only_profiles_with_a_category_field_or_rows_have_categories() {
        assert!(profile("kollmorgen").has_categories());
        for name in ["cia301", "cia402", "canopennode"] {
            assert!(!profile(name).has_categories(), "{name}");
        }
    }

    /// The CiA 301 checks, then the profile's, as the consumer runs them.
    fn all_warnings(p: &Profile, data: &[u8]) -> Vec<&'static str> {
        let emcy = frame(data);
        let mut out = Vec::new();
        emcy.frame_warnings(&p.info(emcy.code), &mut out);
        p.frame_warnings(&emcy, &mut out);
        out.iter().map(Warning::tag).collect()
    }

    #[test]
    fn profiles_take_back_what_their_manual_shows_as_normal() {
        // The S300 manual's 10 43 08 01: the temperature bit without bit 0.
        let s300 = [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0];
        assert_eq!(all_warnings(profile("cia402"), &s300), ["no_generic_bit"]);
        assert!(all_warnings(profile("kollmorgen"), &s300).is_empty());
        // STÖBER's 0x4310 with register 0x01, E82 = 41.
        let stoeber = [0x10, 0x43, 0x01, 0x29, 0, 0, 0, 0];
        assert_eq!(
            all_warnings(profile("cia402"), &stoeber),
            ["class_register_mismatch"]
        );
        assert!(all_warnings(profile("stoeber"), &stoeber).is_empty());
        // Each profile keeps the other check.
        assert_eq!(
            all_warnings(profile("kollmorgen"), &[0x10, 0x43, 0x04, 0x01, 0, 0, 0, 0]),
            ["class_register_mismatch"]
        );
        assert_eq!(
            all_warnings(profile("stoeber"), &[0x10, 0x43, 0x08, 0x29, 0, 0, 0, 0]),
            ["no_generic_bit"]
        );
    }

    #[test]
    fn register_keys_are_inherited_and_can_be_set_back() {
        let s300 = [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0];
        let child = Profile::parse("t", "name = \"x\"\nbase = \"kollmorgen\"\n").unwrap();
        assert!(all_warnings(&child, &s300).is_empty());
        let strict = Profile::parse(
            "t",
            "name = \"x\"\nbase = \"kollmorgen\"\nregister_generic_bit = true\n",
        )
        .unwrap();
        assert_eq!(all_warnings(&strict, &s300), ["no_generic_bit"]);
        let lax = Profile::parse("t", "name = \"x\"\nregister_class_bits = false\n").unwrap();
        assert!(all_warnings(&lax, &[0x10, 0x43, 0x01, 0, 0, 0, 0, 0]).is_empty());
        assert!(Profile::parse("t", "name = \"x\"\nregister_class_bits = \"no\"\n").is_err());
    }

    fn warnings(p: &Profile, data: &[u8]) -> Vec<Warning> {
        let mut out = Vec::new();
        p.frame_warnings(&frame(data), &mut out);
        out
    }

    fn parse_err(text: &str) -> ProfileError {
        match Profile::parse("bad.toml", text) {
            Ok(p) => panic!("parsed: {p:?}"),
            Err(e) => e,
        }
    }

    #[test]
    fn every_builtin_parses_in_listing_order() {
        let names: Vec<&str> = Profile::builtins().iter().map(Profile::name).collect();
        assert_eq!(
            names,
            [
                "cia301",
                "cia402",
                "kollmorgen",
                "beckhoff-ax2000",
                "stoeber",
                "festo-cmmp",
                "canopennode"
            ]
        );
        for (file, text) in BUILTIN_FILES {
            let p = Profile::parse(file, text).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(format!("{}.toml", p.name()), file);
            // The same profile whichever way it was loaded.
            assert_eq!(Profile::builtin(p.name()), Some(&p));
            assert!(!p.summary().is_empty() && !p.summary().contains('\n'));
        }
        assert_eq!(
            Profile::builtin(DEFAULT_PROFILE).map(Profile::tables),
            Some(Tables::Cia402)
        );
        assert!(Profile::builtin("nonsense").is_none());
        assert!(Profile::builtin("").is_none());
    }

    #[test]
    fn generic_profiles_decode_nothing_and_keep_the_cia_text() {
        let cia402 = profile("cia402");
        let cia301 = profile("cia301");
        let e = frame(&[0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
        for p in [cia301, cia402] {
            assert_eq!(p.decode_manufacturer(&e), None);
            assert_eq!(p.category(&e), None);
            assert_eq!(p.status_bit(&e), None);
            assert_eq!(p.vendor_code(0x4310), None);
            assert_eq!(p.register_bit_name(1), None);
            assert!(warnings(p, &[0x10, 0x43, 0x89, 1, 2, 3, 4, 5]).is_empty());
        }
        // cia402 describes exactly as codes.rs does.
        for code in [0x4310, 0x5100, 0x8130, 0xFF01, 0x1234, 0x0000] {
            assert_eq!(
                cia402.describe(code),
                codes::lookup(code).description().to_string()
            );
            assert_eq!(cia402.info(code), codes::lookup(code));
        }
        assert_eq!(cia301.describe(0x4310), "Temperature (0x4310 not listed)");
        assert_eq!(cia301.info(0x5100).class, Class::Undefined);
        assert_eq!(cia402.info(0x5100).class, Class::Hardware);
    }

    #[test]
    fn kollmorgen_s300_example() {
        let p = profile("kollmorgen");
        let e = frame(&[0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
        let d = p.decode_manufacturer(&e).expect("category byte");
        assert_eq!(
            d.fields,
            [
                ("category".to_owned(), int(1)),
                (
                    "category_text".to_owned(),
                    text(
                        "cleared only by a reset (COLDSTART command or control word bit 7); the front panel blinks Fxx"
                    )
                ),
            ]
        );
        assert_eq!(p.category(&e), Some(1));
        assert_eq!(p.describe(0x4310), "F06 motor temperature (AKD: F235)");
        assert_eq!(
            p.vendor_code(0x4310),
            Some(&VendorCode {
                text: "motor temperature (AKD: F235)".to_owned(),
                category: Some(1),
                fault: Some("F06".to_owned()),
            })
        );
        assert_eq!(p.describe(0x1080), "no BTB/RTO (AKD: general warning)");
        // Codes without a row keep the CiA 402 text.
        assert_eq!(
            p.describe(0x8611),
            codes::lookup(0x8611).description().to_string()
        );
        assert!(warnings(p, &[0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]).is_empty());
        assert_eq!(
            warnings(p, &[0x10, 0x43, 0x08, 0x01, 0, 7, 0, 9]),
            [Warning::ManufacturerBytesNonZero { first: 5, last: 7 }]
        );

        // The reset that follows: category byte 0 is no category.
        let reset = frame(&[0, 0, 0x08, 0, 0, 0, 0, 0]);
        assert_eq!(
            p.decode_manufacturer(&reset).map(|d| d.fields),
            Some(vec![("category".to_owned(), int(0))])
        );
        assert_eq!(p.category(&reset), None);
        // A short frame without byte 3 falls back to the code row's category.
        let short = frame(&[0x10, 0x43, 0x08]);
        assert_eq!(p.decode_manufacturer(&short), None);
        assert_eq!(p.category(&short), Some(1));
        assert_eq!(p.category(&frame(&[0x10, 0x43, 0x08, 9])), Some(1));
        assert_eq!(p.category(&frame(&[0x10, 0x43, 0x08, 5])), Some(5));
    }

    #[test]
    fn beckhoff_ax2000_numbering_rule() {
        let p = profile("beckhoff-ax2000");
        let e = frame(&[0x80, 0x43, 0x09, 0x02, 0, 0, 0, 0]);
        assert_eq!(p.category(&e), Some(2));
        assert_eq!(
            p.decode_manufacturer(&e)
                .and_then(|d| d.get("category_text").cloned()),
            Some(text("cleared by control word bit 11"))
        );
        assert_eq!(
            p.describe(0x4380),
            "Temperature · manufacturer-specific (low byte 0x80-0xFF)"
        );
        assert_eq!(
            p.describe(0x1180),
            "manufacturer-specific (low byte 0x80-0xFF)"
        );
        assert_eq!(
            p.describe(0x4310),
            codes::lookup(0x4310).description().to_string()
        );
        assert_eq!(
            p.describe(0x0080),
            codes::lookup(0x0080).description().to_string()
        );
        assert_eq!(
            p.describe(0xFF80),
            codes::lookup(0xFF80).description().to_string()
        );
        // The Kollmorgen numbering does not have the rule.
        assert_eq!(
            profile("kollmorgen").describe(0x4380),
            codes::lookup(0x4380).description().to_string()
        );
    }

    #[test]
    fn stoeber_fault_41_and_its_exit() {
        let p = profile("stoeber");
        let enter = frame(&[0x10, 0x43, 0x01, 0x29, 0, 0, 0, 0]);
        assert_eq!(
            p.decode_manufacturer(&enter).map(|d| d.fields),
            Some(vec![
                ("event".to_owned(), int(41)),
                ("event_text".to_owned(), text("Temperature motor TMS")),
                ("cause".to_owned(), int(0)),
            ])
        );
        let exit = frame(&[0x00, 0x00, 0x00, 0x1E, 0, 0, 0, 0]);
        assert_eq!(
            p.decode_manufacturer(&exit).map(|d| d.fields),
            Some(vec![
                ("event".to_owned(), int(0x1E)),
                ("event_text".to_owned(), text("no error")),
                ("cause".to_owned(), int(0)),
            ])
        );
        assert_eq!(p.category(&enter), None);
        assert!(warnings(p, &[0x10, 0x43, 0x01, 0x29, 0x03, 0, 0, 0]).is_empty());
        assert_eq!(
            warnings(p, &[0x10, 0x43, 0x01, 0x29, 0, 0, 1, 0]),
            [Warning::ManufacturerBytesNonZero { first: 6, last: 6 }]
        );
        // An event number the profile does not name: number only.
        assert_eq!(
            p.decode_manufacturer(&frame(&[0x10, 0x43, 0x01, 0x30]))
                .map(|d| d.fields),
            Some(vec![("event".to_owned(), int(0x30))])
        );
    }

    #[test]
    fn festo_rules() {
        let p = profile("festo-cmmp");
        // fixtures/festo.log: byte 6 is 0x12.
        assert_eq!(
            warnings(p, &[0x10, 0x43, 0x09, 0, 0, 0, 0x12, 0]),
            [Warning::ManufacturerBytesNonZero { first: 6, last: 6 }]
        );
        assert_eq!(
            warnings(p, &[0x10, 0x43, 0x09, 1, 0, 0, 0, 0]),
            [Warning::ManufacturerBytesNonZero { first: 3, last: 3 }]
        );
        assert!(warnings(p, &[0x10, 0x43, 0x09, 0, 0, 0, 0, 0]).is_empty());
        assert!(
            warnings(p, &[0x10, 0x43, 0x09]).is_empty(),
            "short: nothing to check"
        );
        // Bit 7 is Festo's reserved bit; bit 6 is left to the CiA 301 check.
        assert_eq!(
            warnings(p, &[0x10, 0x43, 0xC9, 0, 0, 0, 0, 0]),
            [Warning::ProfileReservedBit { bit: 7 }]
        );
        assert_eq!(p.register_bit_name(1), Some("I2t"));
        assert_eq!(p.register_bit_name(2), Some("voltage monitoring"));
        assert_eq!(p.register_bit_name(3), Some("motor over-temperature"));
        assert_eq!(p.register_bit_name(0), None);
        assert_eq!(p.register_bit_name(8), None);
        assert_eq!(
            p.decode_manufacturer(&frame(&[0x10, 0x43, 0x09, 0, 0, 0, 0, 0])),
            None
        );
    }

    #[test]
    fn canopennode_status_bits() {
        let p = profile("canopennode");
        let warning = frame(&[0x00, 0x00, 0x11, 0x01, 0, 0, 0, 0]);
        assert_eq!(p.status_bit(&warning), Some(0x01));
        assert_eq!(
            p.decode_manufacturer(&warning).map(|d| d.fields),
            Some(vec![
                ("status_bit".to_owned(), int(1)),
                (
                    "status_bit_text".to_owned(),
                    text("CAN bus warning limit reached")
                ),
                ("info_code".to_owned(), int(0)),
            ])
        );
        // Heartbeat consumer timeout with info code 5 (little-endian).
        let hb = frame(&[0x30, 0x81, 0x11, 0x1B, 0x05, 0x00, 0x00, 0x01]);
        assert_eq!(p.status_bit(&hb), Some(0x1B));
        let d = p.decode_manufacturer(&hb).expect("fields");
        assert_eq!(
            d.get("status_bit_text"),
            Some(&text("heartbeat consumer timeout"))
        );
        assert_eq!(d.get("info_code"), Some(&int(0x0100_0005)));
        assert_eq!(
            p.decode_manufacturer(&frame(&[0, 0, 0, 0x35]))
                .map(|d| d.fields),
            Some(vec![
                ("status_bit".to_owned(), int(0x35)),
                (
                    "status_bit_text".to_owned(),
                    text("manufacturer error (information)")
                ),
            ])
        );
        assert_eq!(p.status_bit(&frame(&[0, 0, 0])), None);
        assert_eq!(p.tables(), Tables::Cia301);
        assert!(warnings(p, &[0, 0, 0, 1, 1, 2, 3, 4]).is_empty());
        for other in Profile::builtins()
            .iter()
            .filter(|p| p.name() != "canopennode")
        {
            assert_eq!(other.status_bit(&warning), None, "{}", other.name());
        }
    }

    #[test]
    fn identity_picks_a_profile() {
        let pick = |dt, vid| for_identity(dt, vid).map(|(p, why)| (p.name(), why));
        assert_eq!(
            pick(Some(0x0002_0192), Some(0x6A)),
            Some(("kollmorgen", "vendor id 0x0000006A (Kollmorgen)".to_owned()))
        );
        assert_eq!(
            pick(None, Some(0xB9)),
            Some(("stoeber", "vendor id 0x000000B9 (STÖBER)".to_owned()))
        );
        assert_eq!(
            pick(Some(402), Some(0x1D)),
            Some(("festo-cmmp", "vendor id 0x0000001D (Festo)".to_owned()))
        );
        assert_eq!(
            pick(Some(0x0002_0192), Some(0x1234)),
            Some(("cia402", "device type 402 (drive)".to_owned()))
        );
        // A Festo valve terminal (device type 5001) is not a CMMP drive.
        assert_eq!(
            pick(Some(5001), Some(0x1D)),
            Some(("cia301", "device type 5001 (not a drive)".to_owned()))
        );
        assert_eq!(
            pick(Some(0x000F_0191), None),
            Some(("cia301", "device type 401 (not a drive)".to_owned()))
        );
        assert_eq!(pick(None, Some(0x1234)), None);
        assert_eq!(pick(None, Some(2)), None, "Beckhoff's id is not mapped");
        assert_eq!(pick(None, None), None);
    }

    const ACME: &str = include_str!("../../fixtures/profiles/acme-servo.toml");

    #[test]
    fn the_example_user_profile_extends_kollmorgen() {
        let p = Profile::parse("acme-servo.toml", ACME).unwrap_or_else(|e| panic!("{e}"));
        let base = profile("kollmorgen");
        assert_eq!(p.name(), "acme-servo");
        assert_eq!(p.base(), Some("kollmorgen"));
        assert_eq!(p.tables(), Tables::Cia402);
        // Overridden row.
        assert_eq!(p.describe(0x4310), "F06 motor winding over-temperature");
        // Added row.
        assert_eq!(
            p.vendor_code(0xFF01),
            Some(&VendorCode {
                text: "brake feedback lost".to_owned(),
                category: Some(2),
                fault: Some("E17".to_owned()),
            })
        );
        // Inherited row.
        assert_eq!(p.vendor_code(0x3110), base.vendor_code(0x3110));
        // The category field is inherited; the axis field takes byte 4 out
        // of the base's zero bytes.
        let e = frame(&[0x10, 0x43, 0x89, 0x01, 0x02, 0, 0, 0]);
        assert_eq!(
            p.decode_manufacturer(&e).map(|d| d.fields),
            Some(vec![
                ("category".to_owned(), int(1)),
                (
                    "category_text".to_owned(),
                    text(
                        "cleared only by a reset (COLDSTART command or control word bit 7); the front panel blinks Fxx"
                    )
                ),
                ("axis".to_owned(), int(2)),
                ("axis_text".to_owned(), text("axis B")),
            ])
        );
        assert!(warnings(&p, &[0x10, 0x43, 0x89, 0x01, 0x02, 0, 0, 0]).is_empty());
        assert_eq!(
            warnings(base, &[0x10, 0x43, 0x89, 0x01, 0x02, 0, 0, 0]),
            [Warning::ManufacturerBytesNonZero { first: 4, last: 4 }]
        );
        assert_eq!(
            warnings(&p, &[0x10, 0x43, 0x89, 0x01, 0x02, 0, 0, 0x40]),
            [Warning::ManufacturerBytesNonZero { first: 7, last: 7 }]
        );
        assert_eq!(p.register_bit_name(7), Some("drive fault"));
        assert_eq!(p.category(&frame(&[0x01, 0xFF, 0x81])), Some(2));
        // The user profile does not change the built-in.
        assert_eq!(base.describe(0x4310), "F06 motor temperature (AKD: F235)");
    }

    #[test]
    fn load_file_reads_and_names_the_path() {
        let dir = tempfile::tempdir().expect("temp dir");
        let good = dir.path().join("acme.toml");
        std::fs::write(&good, ACME).expect("write");
        assert_eq!(
            Profile::load(&good).map(|p| p.name().to_owned()),
            Ok("acme-servo".to_owned())
        );

        let bad = dir.path().join("bad.toml");
        std::fs::write(&bad, "name = \"x\"\nbase = \"cia402\"\nsize = 3\n").expect("write");
        let e = Profile::load(&bad).expect_err("unknown key");
        assert_eq!(e.line(), Some(3));
        assert!(
            e.to_string().starts_with(&format!("{}:3: ", bad.display())),
            "{e}"
        );

        let missing = dir.path().join("missing.toml");
        let e = Profile::load(&missing).expect_err("no file");
        assert_eq!(e.line(), None);
        assert!(
            e.to_string()
                .starts_with(&format!("{}: ", missing.display())),
            "{e}"
        );
    }

    #[test]
    fn errors_name_the_line() {
        let cases: &[(&str, usize, &str)] = &[
            // TOML syntax.
            ("name = \"x\"\nbase = \"cia402\"\n[codes\n", 3, ""),
            // A required key missing: reported at the top of the document.
            ("base = \"cia402\"\n", 1, "name"),
            // An unknown key.
            ("name = \"x\"\n\nbsae = \"cia402\"\n", 3, "bsae"),
            // Wrong type.
            ("name = \"x\"\nzero_bytes = \"4-7\"\n", 2, ""),
            (
                "name = \"x\"\nbase = \"kollmorgne\"\n",
                2,
                "unknown base profile",
            ),
            ("name = \"x\"\ntables = \"cia401\"\n", 2, "unknown tables"),
            ("name = \"bad name\"\n", 1, "profile name"),
            (
                "name = \"x\"\n[codes]\n\"0x4310\" = { text = \"a\" }\n\"4311\" = { text = \"b\" }\n",
                4,
                "hexadecimal",
            ),
            (
                "name = \"x\"\n[codes]\n\"0x4310\" = { text = \"a\", category = 300 }\n",
                3,
                "category 300",
            ),
            (
                "name = \"x\"\n[codes]\n\"0x4310\" = { text = \"a\", colour = 1 }\n",
                3,
                "colour",
            ),
            (
                "name = \"x\"\n\n[[field]]\nname = \"a\"\nbyte = 8\n",
                5,
                "outside the manufacturer bytes",
            ),
            (
                "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 6\nsize = 4\n",
                5,
                "does not fit",
            ),
            (
                "name = \"x\"\n[[field]]\nname = \"Bad-Key\"\nbyte = 3\n",
                3,
                "JSON key",
            ),
            (
                "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\nrole = \"severity\"\n",
                5,
                "unknown role",
            ),
            (
                "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\n[field.values]\n\"1\" = \"one\"\n\"two\" = \"2\"\n",
                7,
                "not a number",
            ),
            (
                "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\n[field.values]\n\"0x100\" = \"big\"\n",
                6,
                "does not fit",
            ),
            (
                "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\n[field.values]\n\"0x30-0x3F\" = \"r\"\n\"0x35\" = \"in r\"\n",
                7,
                "overlap",
            ),
            // The second field collides with the inherited category byte.
            (
                "name = \"x\"\nbase = \"kollmorgen\"\n\n[[field]]\nname = \"axis\"\nbyte = 3\n",
                4,
                "share a byte",
            ),
            (
                "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\n[[field]]\nname = \"a_text\"\nbyte = 4\n",
                5,
                "same JSON key",
            ),
            (
                "name = \"x\"\nbase = \"stoeber\"\nzero_bytes = [5, 3]\n",
                3,
                "byte 3 is in zero_bytes but a field uses it",
            ),
            ("name = \"x\"\nzero_bytes = [2]\n", 2, "out of range"),
            (
                "name = \"x\"\nreserved_register_bits = [8]\n",
                2,
                "out of range",
            ),
            (
                "name = \"x\"\n[register_bits]\n\"9\" = \"nine\"\n",
                3,
                "bit number",
            ),
            (
                "name = \"x\"\nmanufacturer_low_bytes = [0x90, 0x80]\n",
                2,
                "first <= last",
            ),
        ];
        for (text, line, needle) in cases {
            let e = parse_err(text);
            assert_eq!(e.line(), Some(*line), "{text:?}: {e}");
            assert!(e.message().contains(needle), "{text:?}: {e}");
            assert!(
                e.to_string().starts_with(&format!("bad.toml:{line}: ")),
                "{e}"
            );
        }
    }

    #[test]
    fn user_profiles_without_base_start_from_cia402() {
        let p = Profile::parse(
            "plain.toml",
            "name = \"plain\"\n[[field]]\nname = \"code\"\nbyte = 3\nsize = 2\n",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.base(), None);
        assert_eq!(p.tables(), Tables::Cia402);
        assert_eq!(p.summary(), "user profile");
        assert_eq!(
            p.decode_manufacturer(&frame(&[0x10, 0x43, 0x09, 0x34, 0x12]))
                .map(|d| d.fields),
            Some(vec![("code".to_owned(), int(0x1234))])
        );
        // Too short for the two-byte field: nothing decoded.
        assert_eq!(
            p.decode_manufacturer(&frame(&[0x10, 0x43, 0x09, 0x34])),
            None
        );
        // A category field without value names: any non-zero value counts.
        let p = Profile::parse(
            "cat.toml",
            "name = \"cat\"\nbase = \"cia301\"\n[[field]]\nname = \"severity\"\nbyte = 7\nrole = \"category\"\n",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.summary(), "user profile based on cia301");
        assert_eq!(p.tables(), Tables::Cia301);
        assert_eq!(
            p.category(&frame(&[0x10, 0x43, 0x09, 0, 0, 0, 0, 3])),
            Some(3)
        );
        assert_eq!(p.category(&frame(&[0x10, 0x43, 0x09, 0, 0, 0, 0, 0])), None);
    }

    #[test]
    fn arbitrary_frames_never_panic() {
        let user = Profile::parse("acme.toml", ACME).unwrap_or_else(|e| panic!("{e}"));
        let all: Vec<&Profile> = Profile::builtins().iter().chain([&user]).collect();
        for len in 3..=8usize {
            for fill in [0x00u8, 0x01, 0x7F, 0x80, 0xFF] {
                let data: Vec<u8> = (0..len).map(|i| fill.wrapping_add(i as u8)).collect();
                let e = frame(&data);
                for p in &all {
                    let _ = p.decode_manufacturer(&e);
                    let _ = p.category(&e);
                    let _ = p.status_bit(&e);
                    let _ = p.describe(e.code);
                    let mut out = Vec::new();
                    p.frame_warnings(&e, &mut out);
                }
            }
        }
        for bit in 0..=255u8 {
            for p in &all {
                let _ = p.register_bit_name(bit);
            }
        }
    }
}
