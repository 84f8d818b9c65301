//! What a run reports (events, nodes, inputs, diagnostics) and the renderers
//! that print it. The JSON key names here are a public contract (README).

pub mod json;
pub mod ndjson;
pub mod table;

use std::io;

use serde::Serialize;
use serde::ser::{SerializeSeq, Serializer};

use crate::canopen::codes::CodeInfo;
use crate::canopen::emcy::{Emcy, Warning};
use crate::timeline::{Interval, State};
use crate::trace::{Format, HexBytes, Timestamp};

/// One decoded EMCY frame, borrowed from the pipeline (no allocation per event).
pub struct EmcyEvent<'a> {
    pub file: &'a str,
    pub line: u64,
    pub time: Option<Timestamp>,
    pub channel: &'a str,
    pub node: u8,
    pub cob_id: u32,
    pub data: &'a [u8],
    pub emcy: &'a Emcy,
    pub info: &'a CodeInfo,
    pub transition: Option<u8>,
    pub state: State,
    pub active: &'a [u16],
    pub cleared: &'a [u16],
    pub warnings: &'a [Warning],
}

/// An NMT boot-up: the node restarted, its errors are gone.
pub struct BootEvent<'a> {
    pub file: &'a str,
    pub line: u64,
    pub time: Option<Timestamp>,
    pub channel: &'a str,
    pub node: u8,
    pub cleared: &'a [u16],
}

/// A node's state at the end of an input and its error history.
#[derive(Clone, Debug)]
pub struct NodeReport {
    pub channel: String,
    pub node: u8,
    pub state: State,
    pub active: Vec<u16>,
    pub emcy_count: u64,
    pub errors: Vec<Interval>,
}

/// Line counts of one input. Every line is exactly one of frame, skipped, malformed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Counts {
    pub lines: u64,
    pub frames: u64,
    pub emcy: u64,
    pub skipped: u64,
    pub malformed: u64,
    /// NMT boot-up frames.
    pub boot: u64,
    /// Frames on an EMCY id too short to decode (fewer than 3 bytes).
    pub emcy_invalid: u64,
    /// Frames read in another format than the one detected (mixed files).
    pub other_format: u64,
}

/// Everything known about one input after reading it.
#[derive(Clone, Debug)]
pub struct InputReport {
    pub file: String,
    pub format: Option<Format>,
    pub gzip: bool,
    pub counts: Counts,
    pub nodes: Vec<NodeReport>,
    /// Why reading stopped early (I/O error, corrupt gzip, unknown format).
    pub error: Option<String>,
}

/// A line that could not be read, or an EMCY that could not be decoded.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Diagnostic {
    pub file: String,
    pub line: u64,
    pub message: String,
}

impl std::fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.file, self.line, self.message)
    }
}

/// A renderer receives events as they are decoded, then the per-input and
/// final summaries. Output errors (a closed pipe) stop the run.
pub trait Renderer {
    fn begin_input(&mut self, _file: &str) -> io::Result<()> {
        Ok(())
    }
    fn emcy(&mut self, event: &EmcyEvent<'_>) -> io::Result<()>;
    fn boot(&mut self, event: &BootEvent<'_>) -> io::Result<()>;
    fn end_input(&mut self, _input: &InputReport) -> io::Result<()> {
        Ok(())
    }
    fn finish(&mut self, inputs: &[InputReport], diagnostics: &[Diagnostic]) -> io::Result<()>;
}

// ---- JSON shapes -------------------------------------------------------------

/// Keeps the kind of an underlying I/O error (a broken pipe must stay one).
fn to_io(e: serde_json::Error) -> io::Error {
    io::Error::from(e)
}

/// `"0x4310"`: codes are strings so that jq users compare them as written.
pub struct Code(pub u16);

impl Serialize for Code {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(&format_args!("0x{:04X}", self.0))
    }
}

fn serialize_codes<S: Serializer>(codes: &[u16], s: S) -> Result<S::Ok, S::Error> {
    let mut seq = s.serialize_seq(Some(codes.len()))?;
    for c in codes {
        seq.serialize_element(&Code(*c))?;
    }
    seq.end()
}

/// A time as a JSON number with exactly the trace's digits.
pub struct JsonTime(pub Timestamp);

impl Serialize for JsonTime {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        raw_number(s, format_args!("{}", self.0))
    }
}

/// Emits already-formatted decimal text as a JSON number (serde_json's
/// `RawValue`), so 1469439874.299654123 is not rounded through f64.
fn raw_number<S: Serializer>(s: S, value: std::fmt::Arguments<'_>) -> Result<S::Ok, S::Error> {
    use std::io::Write;
    let mut buf = [0u8; 64];
    let mut cursor = io::Cursor::new(&mut buf[..]);
    write!(cursor, "{value}").map_err(serde::ser::Error::custom)?;
    let len = cursor.position() as usize;
    let text = std::str::from_utf8(&buf[..len]).map_err(serde::ser::Error::custom)?;
    let raw: &serde_json::value::RawValue =
        serde_json::from_str(text).map_err(serde::ser::Error::custom)?;
    raw.serialize(s)
}

fn serialize_time<S: Serializer>(t: &Option<Timestamp>, s: S) -> Result<S::Ok, S::Error> {
    match t {
        Some(t) => JsonTime(*t).serialize(s),
        None => s.serialize_none(),
    }
}

#[derive(Serialize)]
struct EmcyJson<'a> {
    r#type: &'static str,
    file: &'a str,
    line: u64,
    #[serde(serialize_with = "serialize_time")]
    time: Option<Timestamp>,
    channel: &'a str,
    node: u8,
    cob_id: u32,
    #[serde(serialize_with = "serialize_hex")]
    data: &'a [u8],
    code: Code,
    class: &'static str,
    #[serde(serialize_with = "serialize_description")]
    description: &'a CodeInfo,
    register: u8,
    #[serde(serialize_with = "serialize_register_bits")]
    register_bits: u8,
    #[serde(serialize_with = "serialize_hex")]
    manufacturer: &'a [u8],
    transition: Option<u8>,
    state: &'static str,
    #[serde(serialize_with = "serialize_codes")]
    active: &'a [u16],
    #[serde(serialize_with = "serialize_codes")]
    cleared: &'a [u16],
    #[serde(serialize_with = "serialize_warnings")]
    warnings: &'a [Warning],
}

impl Serialize for EmcyEvent<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        EmcyJson {
            r#type: "emcy",
            file: self.file,
            line: self.line,
            time: self.time,
            channel: self.channel,
            node: self.node,
            cob_id: self.cob_id,
            data: self.data,
            code: Code(self.emcy.code),
            class: self.info.class.slug(),
            description: self.info,
            register: self.emcy.register.0,
            register_bits: self.emcy.register.0,
            manufacturer: self.emcy.manufacturer(),
            transition: self.transition,
            state: self.state.slug(),
            active: self.active,
            cleared: self.cleared,
            warnings: self.warnings,
        }
        .serialize(s)
    }
}

#[derive(Serialize)]
struct BootJson<'a> {
    r#type: &'static str,
    file: &'a str,
    line: u64,
    #[serde(serialize_with = "serialize_time")]
    time: Option<Timestamp>,
    channel: &'a str,
    node: u8,
    #[serde(serialize_with = "serialize_codes")]
    cleared: &'a [u16],
}

impl Serialize for BootEvent<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        BootJson {
            r#type: "boot",
            file: self.file,
            line: self.line,
            time: self.time,
            channel: self.channel,
            node: self.node,
            cleared: self.cleared,
        }
        .serialize(s)
    }
}

/// A node object needs its input's file name, which the report keeps once.
pub struct NodeJson<'a> {
    pub file: &'a str,
    pub node: &'a NodeReport,
}

#[derive(Serialize)]
struct NodeJsonShape<'a> {
    r#type: &'static str,
    file: &'a str,
    channel: &'a str,
    node: u8,
    state: &'static str,
    #[serde(serialize_with = "serialize_codes")]
    active: &'a [u16],
    emcy_count: u64,
    errors: Vec<ErrorJson<'a>>,
}

struct ErrorJson<'a>(&'a Interval);

impl Serialize for ErrorJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let iv = self.0;
        let info = crate::canopen::codes::lookup(iv.code);
        let end_time = iv.end.and_then(|e| e.time);
        let duration = match (iv.start.time, end_time) {
            (Some(start), Some(end)) => Some(end.since(start)),
            _ => None,
        };
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("code", &Code(iv.code))?;
        m.serialize_entry("description", &DisplayStr(&info.description()))?;
        m.serialize_entry("start", &iv.start.time.map(JsonTime))?;
        m.serialize_entry("end", &end_time.map(JsonTime))?;
        m.serialize_entry("duration", &duration.map(JsonSpan))?;
        m.serialize_entry("cleared_by", &iv.cleared_by.map(|c| c.slug()))?;
        m.serialize_entry("start_line", &iv.start.line)?;
        m.serialize_entry("end_line", &iv.end.map(|e| e.line))?;
        m.end()
    }
}

struct JsonSpan(crate::trace::Span);

impl Serialize for JsonSpan {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        raw_number(s, format_args!("{}", self.0))
    }
}

struct DisplayStr<'a, T: std::fmt::Display>(&'a T);

impl<T: std::fmt::Display> Serialize for DisplayStr<'_, T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self.0)
    }
}

impl Serialize for NodeJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        NodeJsonShape {
            r#type: "node",
            file: self.file,
            channel: &self.node.channel,
            node: self.node.node,
            state: self.node.state.slug(),
            active: &self.node.active,
            emcy_count: self.node.emcy_count,
            errors: self.node.errors.iter().map(ErrorJson).collect(),
        }
        .serialize(s)
    }
}

#[derive(Serialize)]
struct InputJsonShape<'a> {
    r#type: &'static str,
    file: &'a str,
    format: Option<&'static str>,
    gzip: bool,
    #[serde(flatten)]
    counts: &'a Counts,
    error: Option<&'a str>,
}

impl Serialize for InputReport {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        InputJsonShape {
            r#type: "input",
            file: &self.file,
            format: self.format.map(Format::name),
            gzip: self.gzip,
            counts: &self.counts,
            error: self.error.as_deref(),
        }
        .serialize(s)
    }
}

fn serialize_hex<S: Serializer>(bytes: &&[u8], s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(&HexBytes(bytes))
}

fn serialize_description<S: Serializer>(info: &&CodeInfo, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(&info.description())
}

fn serialize_register_bits<S: Serializer>(register: &u8, s: S) -> Result<S::Ok, S::Error> {
    let names = crate::canopen::register::Register(*register).names();
    s.collect_seq(names)
}

fn serialize_warnings<S: Serializer>(warnings: &&[Warning], s: S) -> Result<S::Ok, S::Error> {
    let mut seq = s.serialize_seq(Some(warnings.len()))?;
    for w in warnings.iter() {
        seq.serialize_element(&DisplayStr(w))?;
    }
    seq.end()
}
