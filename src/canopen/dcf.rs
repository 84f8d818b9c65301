//! DCF and EDS files (CiA 306) for `--dcf NODE=FILE`: the identity a
//! device declares (vendor id, product code: they choose its profile, as
//! 0x1018 uploads do) and the PDO mappings it is configured with.
//!
//! The format is INI: `[1A00sub1]` sections holding `ParameterValue` (the
//! configured value, DCF) or else `DefaultValue` (EDS), integers in decimal,
//! `0x` hex or leading-zero octal, COB-IDs written as `$NODEID+0x180`.
//!
//! Our own reader rather than an INI crate (rust-ini was the candidate):
//! every value error must name its file line, and the crates keep no
//! positions of keys; CiA 306 also has no quoting or escapes for a crate to
//! get right, so the line reading is a few lines of code.
//!
//! Reading is tolerant: a malformed line is reported with its line number
//! and reading goes on; only the objects used are evaluated, so a broken
//! entry elsewhere in a vendor's file does not matter.

use std::collections::BTreeMap;
use std::path::Path;

use super::NodeId;
use super::pdo::{Learner, Mapping, PdoId, Source};
use super::sdo::{DEVICE_TYPE, IDENTITY, Object};

/// The largest file read: DCFs of real drives are tens to hundreds of
/// kilobytes; anything larger is not one.
pub const MAX_BYTES: u64 = 16 << 20;

/// Problems kept (the rest only counted): a binary file given by mistake
/// would otherwise yield one per line.
pub const MAX_PROBLEMS: usize = 100;

/// What a DCF says about its node.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Dcf {
    /// `[DeviceInfo]` VendorNumber, else 0x1018 sub 1.
    pub vendor_id: Option<u32>,
    /// `[DeviceInfo]` ProductNumber, else 0x1018 sub 2.
    pub product_code: Option<u32>,
    /// Object 0x1000 (device type): its ParameterValue, else DefaultValue.
    pub device_type: Option<u32>,
    /// `[DeviceComissioning]` NodeID (CiA 306 spells it so), for a check
    /// against the node the user named.
    pub node_id: Option<u32>,
    /// The valid PDO mappings it declares, source [`Source::Dcf`].
    pub mappings: Vec<Mapping>,
    /// Every object entry's `ParameterName`, and whether its `DataType`
    /// is VISIBLE_STRING: SDO transfers are named and shown by them.
    pub objects: BTreeMap<Object, Declared>,
    /// Malformed lines and values, in file order (the first
    /// [`MAX_PROBLEMS`]).
    pub problems: Vec<Problem>,
    /// All problems, kept or not.
    pub problem_count: u64,
}

/// What a DCF declares of one object entry.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Declared {
    pub name: Option<String>,
    /// `DataType=0x0009` (VISIBLE_STRING): its values are text.
    pub text: bool,
    /// `ParameterValue` and `DefaultValue` as written, with their lines.
    pub parameter: Option<Raw>,
    pub default: Option<Raw>,
}

impl Declared {
    /// The value the device is configured with: ParameterValue if written
    /// and not empty, else DefaultValue; as written, with its line.
    pub fn value(&self) -> Option<&Raw> {
        self.parameter
            .as_ref()
            .filter(|r| !r.text.is_empty())
            .or(self.default.as_ref())
    }
}

/// CiA 306 data type VISIBLE_STRING.
const VISIBLE_STRING: u32 = 0x0009;

/// A line that could not be read, or a value of a used object that is not
/// a number.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// 1-based line of the file.
    pub line: u64,
    pub reason: String,
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}: {}", self.line, self.reason)
    }
}

/// A value as written, with its line: evaluated only if used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Raw {
    pub text: String,
    pub line: u64,
}

/// The section being read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Section {
    DeviceInfo,
    Commissioning,
    /// An object entry (the decoder evaluates the values of the ones it
    /// uses, [`used`]).
    Entry(Object),
    /// Anything else: its keys are skipped.
    Other,
}

/// Whether the decoder uses an object of a DCF: device type, identity and
/// PDO parameters.
fn used(object: Object) -> bool {
    (object.index == DEVICE_TYPE && object.sub == 0)
        || (object.index == IDENTITY && matches!(object.sub, 1 | 2))
        || PdoId::shapes_mapping(object)
}

/// `1A00sub1` (hex index, `sub`, hex sub-index) or `1018`, case-insensitive.
fn object_of_section(name: &str) -> Option<Object> {
    let lower = name.to_ascii_lowercase();
    let (index, sub) = match lower.split_once("sub") {
        Some((i, s)) => (i, Some(s)),
        None => (lower.as_str(), None),
    };
    let hex = |t: &str| {
        (!t.is_empty() && t.len() <= 4 && t.bytes().all(|b| b.is_ascii_hexdigit()))
            .then(|| u16::from_str_radix(t, 16).ok())
            .flatten()
    };
    let index = hex(index)?;
    let sub = match sub {
        Some(s) => u8::try_from(hex(s)?).ok()?,
        None => 0,
    };
    Some(Object { index, sub })
}

/// An integer as CiA 306 writes them: `0x` hex, leading-zero octal, else
/// decimal; `$NODEID` terms (`$NODEID+0x180`) are `node`.
pub fn integer(text: &str, node: NodeId) -> Result<u32, String> {
    let mut sum: u32 = 0;
    for term in text.split('+') {
        let term = term.trim();
        let value = if term.eq_ignore_ascii_case("$NODEID") {
            u32::from(node)
        } else if let Some(hex) = term.strip_prefix("0x").or_else(|| term.strip_prefix("0X")) {
            u32::from_str_radix(hex, 16).map_err(|e| not_u32(term, "a hex number", &e))?
        } else if let Some(octal) = term.strip_prefix('0').filter(|o| !o.is_empty()) {
            u32::from_str_radix(octal, 8).map_err(|e| not_u32(term, "an octal number", &e))?
        } else {
            term.parse::<u32>()
                .map_err(|e| not_u32(term, "a number", &e))?
        };
        sum = sum
            .checked_add(value)
            .ok_or_else(|| format!("`{text}` is above 32 bits"))?;
    }
    Ok(sum)
}

/// Why `term` is no 32-bit value: too large, or not `what` at all.
fn not_u32(term: &str, what: &str, e: &std::num::ParseIntError) -> String {
    match e.kind() {
        std::num::IntErrorKind::PosOverflow => format!("`{term}` is above 32 bits"),
        _ => format!("`{term}` is not {what}"),
    }
}

/// Notes a problem (the first [`MAX_PROBLEMS`] kept).
fn problem(dcf: &mut Dcf, line: u64, reason: String) {
    dcf.problem_count += 1;
    if dcf.problems.len() < MAX_PROBLEMS {
        dcf.problems.push(Problem { line, reason });
    }
}

/// Reads a DCF for `node` (the node the user named: `$NODEID`).
pub fn parse(bytes: &[u8], node: NodeId) -> Dcf {
    let mut dcf = Dcf::default();
    let mut info: BTreeMap<&'static str, Raw> = BTreeMap::new();
    let mut section = Section::Other;
    for (n, raw_line) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = n as u64 + 1;
        // Vendors' files are often Latin-1 in names and comments; the
        // parts read here are ASCII either way.
        let text = String::from_utf8_lossy(raw_line);
        let line = text.trim();
        if line.is_empty() || line.starts_with(';') || line.starts_with('#') {
            continue;
        }
        if let Some(rest) = line.strip_prefix('[') {
            let Some(name) = rest.strip_suffix(']') else {
                problem(&mut dcf, line_no, "a section name without `]`".into());
                section = Section::Other;
                continue;
            };
            let name = name.trim();
            section = if name.eq_ignore_ascii_case("DeviceInfo") {
                Section::DeviceInfo
            } else if name.eq_ignore_ascii_case("DeviceComissioning")
                || name.eq_ignore_ascii_case("DeviceCommissioning")
            {
                Section::Commissioning
            } else {
                match object_of_section(name) {
                    Some(o) => Section::Entry(o),
                    None => Section::Other,
                }
            };
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            problem(
                &mut dcf,
                line_no,
                format!("`{line}` is not a [section], a key=value or a ; comment"),
            );
            continue;
        };
        let key = key.trim();
        let raw = || Raw {
            text: value.trim().to_string(),
            line: line_no,
        };
        match section {
            Section::Entry(object) if key.eq_ignore_ascii_case("ParameterName") => {
                dcf.objects.entry(object).or_default().name = Some(raw().text);
            }
            Section::Entry(object) if key.eq_ignore_ascii_case("DataType") => {
                // A type that is no number names no string; the object's
                // values stay hex.
                dcf.objects.entry(object).or_default().text =
                    integer(value.trim(), node) == Ok(VISIBLE_STRING);
            }
            Section::Entry(object)
                if key.eq_ignore_ascii_case("ParameterValue")
                    || key.eq_ignore_ascii_case("DefaultValue") =>
            {
                let parameter = key.eq_ignore_ascii_case("ParameterValue");
                let declared = dcf.objects.entry(object).or_default();
                let slot = if parameter {
                    &mut declared.parameter
                } else {
                    &mut declared.default
                };
                *slot = Some(raw());
            }
            Section::DeviceInfo if key.eq_ignore_ascii_case("VendorNumber") => {
                info.insert("vendor", raw());
            }
            Section::DeviceInfo if key.eq_ignore_ascii_case("ProductNumber") => {
                info.insert("product", raw());
            }
            Section::Commissioning if key.eq_ignore_ascii_case("NodeID") => {
                info.insert("node", raw());
            }
            _ => {}
        }
    }
    // A value that is no number is left out, as if the file did not set
    // it, and the problem says so: a PDO whose COB-ID is left out keeps
    // the predefined one, which must not happen unsaid.
    let eval = |dcf: &mut Dcf, raw: Option<&Raw>, what: &str| -> Option<u32> {
        let raw = raw?;
        match integer(&raw.text, node) {
            Ok(v) => Some(v),
            Err(reason) => {
                problem(dcf, raw.line, format!("{reason}: {what}"));
                None
            }
        }
    };
    let declared = |dcf: &Dcf, index, sub| {
        dcf.objects
            .get(&Object { index, sub })
            .and_then(Declared::value)
            .cloned()
    };
    let vendor = info.get("vendor").cloned().or(declared(&dcf, IDENTITY, 1));
    dcf.vendor_id = eval(
        &mut dcf,
        vendor.as_ref(),
        "the vendor id is not read from this file",
    );
    let product = info.get("product").cloned().or(declared(&dcf, IDENTITY, 2));
    dcf.product_code = eval(
        &mut dcf,
        product.as_ref(),
        "the product code is not read from this file",
    );
    dcf.node_id = eval(
        &mut dcf,
        info.get("node"),
        "the node id is not read from this file",
    );
    let device_type = declared(&dcf, DEVICE_TYPE, 0);
    dcf.device_type = eval(
        &mut dcf,
        device_type.as_ref(),
        "the device type (0x1000) is not read from this file",
    );
    // The declared values, applied as if the node had confirmed them in
    // index order: the same rules as a mapping learnt from the trace.
    let mut learner = Learner::new();
    let values: Vec<(Object, Raw)> = dcf
        .objects
        .iter()
        .filter(|(o, _)| used(**o) && o.index != IDENTITY && o.index != DEVICE_TYPE)
        .filter_map(|(&o, d)| Some((o, d.value()?.clone())))
        .collect();
    for (Object { index, sub }, raw) in values {
        // Communication parameters: 0x1400-0x15FF (receive), 0x1800-0x19FF (transmit).
        let cob_id = sub == 1 && matches!(index, 0x1400..=0x15FF | 0x1800..=0x19FF);
        let what = if cob_id {
            format!(
                "0x{index:04X} sub {sub} is not read from this file: the PDO keeps its \
                 predefined COB-ID"
            )
        } else {
            format!("0x{index:04X} sub {sub} is not read from this file")
        };
        if let Some(value) = eval(&mut dcf, Some(&raw), &what) {
            learner.confirmed(node, Object { index, sub }, value);
        }
    }
    dcf.mappings = learner
        .mappings()
        .map(|m| Mapping {
            source: Source::Dcf,
            ..m
        })
        .collect();
    dcf
}

/// Reads the file at `path` (at most [`MAX_BYTES`]) for `node`.
pub fn load(path: &Path, node: NodeId) -> Result<Dcf, String> {
    let bytes = crate::small_file::read(path, MAX_BYTES, "a DCF")
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(parse(&bytes, node))
}

/// Parses `--dcf NODE=FILE` (NODE 1-127, decimal or `0x` hex); the error is
/// the text clap prints.
pub fn parse_option(spec: &str) -> Result<(NodeId, std::path::PathBuf), String> {
    let (node, file) = spec
        .split_once('=')
        .ok_or_else(|| format!("`{spec}` is not NODE=FILE (5=drive.dcf)"))?;
    let node_text = node.trim();
    let parsed = match node_text
        .strip_prefix("0x")
        .or_else(|| node_text.strip_prefix("0X"))
    {
        Some(hex) => u16::from_str_radix(hex, 16).ok(),
        None => node_text.parse::<u16>().ok(),
    };
    let node = parsed
        .filter(|n| (1..=127).contains(n))
        .ok_or_else(|| format!("`{node_text}` is not a node id (1 to 127)"))?;
    if file.is_empty() {
        return Err(format!("`{spec}` names no file after `=`"));
    }
    Ok((node, std::path::PathBuf::from(file)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canopen::pdo::Direction;

    /// A DCF as commissioning tools write one: TPDO1 remapped to statusword
    /// and error code, RPDO1 the controlword, TPDO2 switched off.
    const DRIVE: &str = "\
; written by hand for the tests
[FileInfo]
FileName=drive.dcf

[DeviceInfo]
VendorName=Example Drives
VendorNumber=0x0000006A
ProductNumber=4660

[DeviceComissioning]
NodeID=5

[1018sub1]
ParameterName=Vendor-ID
DefaultValue=0x00000001

[1400sub1]
ParameterName=COB-ID used by RPDO
DefaultValue=$NODEID+0x200

[1600sub0]
DefaultValue=0
ParameterValue=1
[1600sub1]
DefaultValue=0x60400010

[1800sub1]
DefaultValue=$NODEID+0x180
ParameterValue=0x180 + $NodeId
[1800sub2]
DefaultValue=not a number, and not used
[1A00sub0]
ParameterValue=2
DefaultValue=1
[1A00sub1]
ParameterValue=0x60410010
[1A00sub2]
ParameterValue=
DefaultValue=0x603F0010

[1801sub1]
DefaultValue=0x80000280
[1A01sub0]
DefaultValue=1
[1a01SUB1]
DefaultValue=0x60640020
";

    #[test]
    fn reads_identity_and_pdo_mappings() {
        let dcf = parse(DRIVE.as_bytes(), 5);
        assert_eq!(dcf.problems, []);
        assert_eq!(dcf.vendor_id, Some(0x6A), "DeviceInfo before 0x1018");
        assert_eq!(dcf.product_code, Some(4660));
        assert_eq!(dcf.node_id, Some(5));
        let pdos: Vec<(Option<Direction>, u32, Vec<u32>)> = dcf
            .mappings
            .iter()
            .map(|m| {
                assert_eq!(m.source, Source::Dcf);
                assert_eq!(m.node, Some(5));
                (
                    m.direction,
                    m.cob_id.id,
                    m.objects.iter().map(|o| o.entry()).collect(),
                )
            })
            .collect();
        assert_eq!(
            pdos,
            [
                (Some(Direction::Tpdo), 0x185, vec![0x6041_0010, 0x603F_0010]),
                (Some(Direction::Rpdo), 0x205, vec![0x6040_0010]),
            ]
        );
    }

    #[test]
    fn object_names_and_string_types() {
        let text = "[2001]\nParameterName=Axis label\nDataType=0x0009\n\
                    [2002sub3]\nDataType=7\nParameterName=Gain\n[2003]\nDataType=x\n";
        let dcf = parse(text.as_bytes(), 5);
        let declared = |index, sub| dcf.objects.get(&Object { index, sub }).cloned();
        assert_eq!(
            declared(0x2001, 0),
            Some(Declared {
                name: Some("Axis label".into()),
                text: true,
                ..Declared::default()
            })
        );
        assert_eq!(
            declared(0x2002, 3),
            Some(Declared {
                name: Some("Gain".into()),
                text: false,
                ..Declared::default()
            })
        );
        assert_eq!(declared(0x2003, 0), Some(Declared::default()));
        assert_eq!(
            parse(DRIVE.as_bytes(), 5)
                .objects
                .get(&Object {
                    index: 0x1018,
                    sub: 1
                })
                .and_then(|d| d.name.as_deref()),
            Some("Vendor-ID")
        );
        // Every object's value as written, ParameterValue first.
        let drive = parse(DRIVE.as_bytes(), 5);
        let value = |index, sub| {
            drive
                .objects
                .get(&Object { index, sub })
                .and_then(|d| d.value())
                .map(|r| r.text.clone())
        };
        assert_eq!(value(0x1800, 1).as_deref(), Some("0x180 + $NodeId"));
        assert_eq!(
            value(0x1A00, 2).as_deref(),
            Some("0x603F0010"),
            "empty parameter"
        );
        assert_eq!(value(0x1018, 1).as_deref(), Some("0x00000001"));
    }

    #[test]
    fn nodeid_is_the_node_the_user_named() {
        let dcf = parse(DRIVE.as_bytes(), 9);
        let ids: Vec<u32> = dcf.mappings.iter().map(|m| m.cob_id.id).collect();
        assert_eq!(ids, [0x189, 0x209]);
        assert_eq!(dcf.node_id, Some(5), "the file's own, for a check");
    }

    #[test]
    fn identity_from_0x1018_without_device_info() {
        let text = "[1018sub1]\nDefaultValue=0x0000009A\n[1018sub2]\nParameterValue=017\n";
        let dcf = parse(text.as_bytes(), 1);
        assert_eq!(dcf.vendor_id, Some(0x9A));
        assert_eq!(dcf.product_code, Some(0o17), "octal");
        assert_eq!(dcf.mappings, []);
    }

    #[test]
    fn device_type_parameter_value_before_default() {
        let text = "[1000]\nDefaultValue=0x00000000\nParameterValue=0x000F0191\n";
        assert_eq!(parse(text.as_bytes(), 3).device_type, Some(0x000F_0191));
        let text = "[1000]\nDefaultValue=0x00020192\n";
        assert_eq!(parse(text.as_bytes(), 3).device_type, Some(0x0002_0192));
        let text = "[1000sub1]\nDefaultValue=0x00020192\n";
        assert_eq!(parse(text.as_bytes(), 3).device_type, None, "sub 0 only");
        assert_eq!(parse(b"[1018sub1]\nDefaultValue=1\n", 3).device_type, None);
    }

    #[test]
    fn integers_as_cia_306_writes_them() {
        assert_eq!(integer("0x1A", 1), Ok(26));
        assert_eq!(integer("0X1a", 1), Ok(26));
        assert_eq!(integer("010", 1), Ok(8));
        assert_eq!(integer("0", 1), Ok(0));
        assert_eq!(integer("42", 1), Ok(42));
        assert_eq!(integer("$NODEID+0x180", 3), Ok(0x183));
        assert_eq!(integer("0x180+$nodeid", 3), Ok(0x183));
        assert_eq!(integer(" $NODEID + 384 ", 3), Ok(387));
        assert!(integer("08", 1).unwrap_err().contains("octal"));
        assert!(integer("0xZZ", 1).unwrap_err().contains("hex"));
        assert!(integer("", 1).unwrap_err().contains("not a number"));
        assert!(integer("-1", 1).is_err());
        assert!(integer("0xFFFFFFFF+1", 1).unwrap_err().contains("32 bits"));
        assert_eq!(
            integer("$NODEID+0xFFFFFFFFFFFFFFFF", 1),
            Err("`0xFFFFFFFFFFFFFFFF` is above 32 bits".into())
        );
        assert_eq!(
            integer("99999999999", 1),
            Err("`99999999999` is above 32 bits".into())
        );
    }

    /// A COB-ID that is no number leaves the PDO on its predefined COB-ID:
    /// the problem says so, with its line.
    #[test]
    fn a_cob_id_that_is_no_number_is_a_problem_that_says_what_it_means() {
        let text = "[1800sub1]\nParameterValue=$NODEID+0xFFFFFFFFFFFFFFFF\n\
                    [1A00sub0]\nParameterValue=1\n[1A00sub1]\nParameterValue=0x60410010\n";
        let dcf = parse(text.as_bytes(), 5);
        let problems: Vec<String> = dcf.problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(
            problems,
            [
                "line 2: `0xFFFFFFFFFFFFFFFF` is above 32 bits: 0x1800 sub 1 is not read from \
              this file: the PDO keeps its predefined COB-ID"
            ]
        );
        assert_eq!(dcf.problem_count, 1);
    }

    #[test]
    fn malformed_lines_are_problems_with_their_line() {
        let text = "[DeviceInfo]\r\nVendorNumber=0x6A\r\nthis line is junk\r\n[1A00sub0\r\n\
                    [1A00sub0]\r\nDefaultValue=1\r\n[1A00sub1]\r\nDefaultValue=0xZZ\r\n";
        let dcf = parse(text.as_bytes(), 5);
        let problems: Vec<String> = dcf.problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(
            problems,
            [
                "line 3: `this line is junk` is not a [section], a key=value or a ; comment",
                "line 4: a section name without `]`",
                "line 8: `0xZZ` is not a hex number: 0x1A00 sub 1 is not read from this file",
            ]
        );
        // Reading went on: CRLF lines, the vendor read.
        assert_eq!(dcf.vendor_id, Some(0x6A));
        assert_eq!(dcf.problem_count, 3);
    }

    #[test]
    fn problems_kept_are_bounded() {
        let text = "junk\n".repeat(MAX_PROBLEMS + 50);
        let dcf = parse(text.as_bytes(), 1);
        assert_eq!(dcf.problems.len(), MAX_PROBLEMS);
        assert_eq!(dcf.problem_count, MAX_PROBLEMS as u64 + 50);
    }

    #[test]
    fn section_names() {
        let o = |index, sub| Some(Object { index, sub });
        assert_eq!(object_of_section("1A00sub1"), o(0x1A00, 1));
        assert_eq!(object_of_section("1a00SUB1A"), o(0x1A00, 0x1A));
        assert_eq!(object_of_section("1018"), o(0x1018, 0));
        assert_eq!(object_of_section("1A00sub"), None);
        assert_eq!(object_of_section("1A00sub100"), None);
        assert_eq!(object_of_section("DeviceInfo"), None);
        assert_eq!(object_of_section("+1A0"), None);
        assert_eq!(object_of_section("12345"), None);
    }

    #[test]
    fn dcf_option() {
        assert_eq!(parse_option("5=drive.dcf"), Ok((5, "drive.dcf".into())));
        assert_eq!(parse_option("0x7F=a=b.dcf"), Ok((127, "a=b.dcf".into())));
        assert!(parse_option("drive.dcf").unwrap_err().contains("NODE=FILE"));
        assert!(parse_option("0=d.dcf").unwrap_err().contains("1 to 127"));
        assert!(parse_option("128=d.dcf").unwrap_err().contains("1 to 127"));
        assert!(parse_option("5=").unwrap_err().contains("no file"));
    }

    #[test]
    fn load_reads_a_file_and_refuses_a_huge_one() {
        let dir = tempfile::tempdir().expect("a temp dir");
        let path = dir.path().join("drive.dcf");
        std::fs::write(&path, DRIVE).expect("written");
        let dcf = load(&path, 5).expect("loaded");
        assert_eq!(dcf.mappings.len(), 2);
        let missing = load(&dir.path().join("none.dcf"), 5).unwrap_err();
        assert!(missing.contains("none.dcf"), "{missing}");
        let big = dir.path().join("big.dcf");
        let file = std::fs::File::create(&big).expect("created");
        file.set_len(MAX_BYTES + 1).expect("sized");
        assert!(load(&big, 5).unwrap_err().contains("not a DCF"));
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_any_text(text in "(\\PC|\n|\\[|\\]|=|\\$NODEID|sub|0x){0,200}", node in 0u16..200) {
            let dcf = parse(text.as_bytes(), node);
            proptest::prop_assert!(dcf.problems.len() <= MAX_PROBLEMS);
        }

        #[test]
        fn never_panics_on_any_bytes(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..300)) {
            let _ = parse(&bytes, 5);
        }

        /// Lines shaped like a DCF's, values anything.
        #[test]
        fn never_panics_on_dcf_shaped_lines(
            lines in proptest::collection::vec(
                proptest::prop_oneof![
                    "\\[1[4-9ABab][0-9A-Fa-f]{2}sub[0-9A-Fa-f]{1,2}\\]",
                    "(ParameterValue|DefaultValue)=[-+$NODEIDx0-9a-fA-F ]{0,20}",
                ],
                0..60),
        ) {
            let text = lines.join("\n");
            let dcf = parse(text.as_bytes(), 5);
            for m in &dcf.mappings {
                proptest::prop_assert!(!m.objects.is_empty());
            }
        }
    }
}
