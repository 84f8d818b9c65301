//! The CI baseline: what a set of traces contained, per trace and per
//! (channel, node): which error codes were raised, how often, and which
//! were still active at the end, plus the trace's line counts. `check`
//! compares a new record with a recorded one ([`compare`]) and prints one
//! finding per line ([`text`]). The file format and the rules for what is a
//! regression are in docs/guide/ci.md; this module is their single
//! implementation. No command line and no process I/O here: the
//! application reads the traces and writes the files.

pub mod compare;
pub mod key;
pub mod text;

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt;

use anyhow::{Context, Result, bail};
use serde::de::IgnoredAny;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::value::RawValue;

use crate::analyze::InputReport;
use crate::canopen::NodeId;

/// The `baseline_version` this build writes and reads.
pub const VERSION: u32 = 1;

/// The largest baseline `check` reads: about 200 bytes per node of each
/// trace, so room for a fleet of hundreds of thousands of trace nodes; a
/// file beyond this (`/dev/zero`, a trace given by mistake) is an error,
/// not memory.
pub const MAX_BYTES: u64 = 64 << 20;

/// A baseline file. Serialized with sorted keys (struct fields are declared
/// in alphabetical order, maps are `BTreeMap`s) so the same traces always
/// give the same bytes.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Baseline {
    pub baseline_version: u32,
    /// The decoding options the traces were read with (absent: none), so
    /// a check with other ones is refused, not compared.
    #[serde(default, skip_serializing_if = "ReadOptions::is_none")]
    pub options: ReadOptions,
    /// By trace key (see [`key::trace_key`]).
    pub traces: BTreeMap<String, TraceEntry>,
}

/// The options that change what a trace decodes to, as the command line
/// gave them (normalized): `--input-format`, `--timestamps`, `--emcy-id`,
/// `--heartbeat-timeout`, `--profile`, and the names of `--profile-file`
/// profiles.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReadOptions {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input_format: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timestamps: Option<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub emcy_id: Vec<String>,
    /// Seconds, as `--heartbeat-timeout` gave them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heartbeat_timeout: Option<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub profile: Vec<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub profile_file: Vec<String>,
    /// `--pdo` specs as given.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pdo: Vec<String>,
    /// `--dcf` as NODE=file name (paths differ between machines).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dcf: Vec<String>,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub assume_cia402_pdo: bool,
}

impl ReadOptions {
    pub fn is_none(&self) -> bool {
        *self == ReadOptions::default()
    }
}

impl std::fmt::Display for ReadOptions {
    /// As flags: `--input-format asc --profile 1=kollmorgen`, or `no
    /// decoding options`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.is_none() {
            return f.write_str("no decoding options");
        }
        let mut flags: Vec<String> = Vec::new();
        if let Some(v) = &self.input_format {
            flags.push(format!("--input-format {v}"));
        }
        if let Some(v) = &self.timestamps {
            flags.push(format!("--timestamps {v}"));
        }
        flags.extend(self.emcy_id.iter().map(|v| format!("--emcy-id {v}")));
        if let Some(v) = &self.heartbeat_timeout {
            flags.push(format!("--heartbeat-timeout {v}"));
        }
        flags.extend(self.profile.iter().map(|v| format!("--profile {v}")));
        flags.extend(
            self.profile_file
                .iter()
                .map(|v| format!("--profile-file (profile {v})")),
        );
        flags.extend(self.pdo.iter().map(|v| format!("--pdo {v}")));
        flags.extend(self.dcf.iter().map(|v| format!("--dcf {v}")));
        if self.assume_cia402_pdo {
            flags.push("--assume-cia402-pdo".to_string());
        }
        f.write_str(&flags.join(" "))
    }
}

#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TraceEntry {
    pub counts: CountsEntry,
    /// `candump`, `candump-screen`, `asc`, or null when no frame was found.
    pub format: Option<String>,
    /// Channel -> node -> what the node did.
    pub nodes: BTreeMap<String, BTreeMap<NodeId, NodeEntry>>,
    /// Channel -> bus-offs of the controller that logged the trace; left
    /// out when none, so baselines of traces without them read and write
    /// as before.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub bus_off: BTreeMap<String, u64>,
    /// Channel -> the roots of its incidents (`node 3 heartbeat_lost`,
    /// `node 5 emcy 0x8130`, `bus bus_error`) -> how many incidents each
    /// started; left out when none.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub incidents: BTreeMap<String, BTreeMap<String, u64>>,
}

/// The input counts of the JSON contract, in alphabetical order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CountsEntry {
    pub boot: u64,
    pub emcy: u64,
    pub emcy_invalid: u64,
    pub frames: u64,
    pub lines: u64,
    pub malformed: u64,
    pub other_format: u64,
    pub skipped: u64,
}

#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct NodeEntry {
    /// EMCY frames of this node, resets included.
    pub emcy: u64,
    /// Every error code raised, by code.
    pub errors: BTreeMap<Code, ErrorEntry>,
    /// Heartbeat outages (silent at the end included); left out when none,
    /// so baselines of traces without outages read and write as before.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub heartbeat_lost: u64,
    /// CiA 402 faults its drive entered; left out when none. The key keeps
    /// the name baselines were written with.
    #[serde(default, skip_serializing_if = "is_zero", rename = "axis_faults")]
    pub drive_faults: u64,
    /// Bus-offs of the node (inferred from its silence across error
    /// frames); left out when none.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub bus_off: u64,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ErrorEntry {
    /// Still active when the trace ended.
    pub active_at_end: bool,
    /// Times it was raised (a repeat while active is not a raise).
    pub raised: u64,
}

/// An error code, written `0x4310` (always `0x` and four upper-case digits,
/// so string order is numeric order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Code(pub u16);

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "0x{:04X}", self.0)
    }
}

impl Serialize for Code {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for Code {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Code, D::Error> {
        let text: Cow<'de, str> = Deserialize::deserialize(d)?;
        let code = text
            .strip_prefix("0x")
            .filter(|h| h.len() == 4)
            .and_then(|h| u16::from_str_radix(h, 16).ok())
            .map(Code)
            .filter(|c| c.to_string() == text);
        code.ok_or_else(|| {
            serde::de::Error::custom(format!("'{text}' is not an error code like 0x4310"))
        })
    }
}

impl Baseline {
    /// The exact bytes of the file: pretty JSON, two-space indent, one
    /// trailing newline.
    pub fn to_json(&self) -> Result<String> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        Ok(text)
    }

    /// Reads a baseline file's text; the version is checked before the rest,
    /// so a newer format is named as such, not as a syntax error.
    ///
    /// Never through a `serde_json::Value`: that tree of a 68 MB baseline
    /// took 1.5 GB. The two first passes allocate almost nothing (syntax
    /// only; then the top-level keys with their values left as slices of
    /// `text`), the last goes straight into the types.
    pub fn from_json(text: &str) -> Result<Baseline> {
        serde_json::from_str::<IgnoredAny>(text).context("not a baseline (invalid JSON)")?;
        let top: Option<BTreeMap<String, &RawValue>> = serde_json::from_str(text).ok();
        let version = top
            .as_ref()
            .and_then(|top| top.get("baseline_version"))
            .and_then(|raw| serde_json::from_str::<u64>(raw.get()).ok());
        match version {
            Some(v) if v == u64::from(VERSION) => {}
            Some(v) => bail!(
                "baseline version {v} is not supported (this emcy-decode reads version \
                 {VERSION}); write it again with `emcy-decode baseline`"
            ),
            None => bail!("not a baseline (no baseline_version number)"),
        }
        serde_json::from_str(text).context("not a baseline")
    }

    /// The record of the given traces, by key.
    pub fn from_reports(traces: &[(String, InputReport)]) -> Baseline {
        let traces = traces
            .iter()
            .map(|(key, report)| (key.clone(), TraceEntry::from_report(report)))
            .collect();
        Baseline {
            baseline_version: VERSION,
            options: ReadOptions::default(),
            traces,
        }
    }
}

impl TraceEntry {
    fn from_report(report: &InputReport) -> TraceEntry {
        let c = report.counts;
        let mut nodes: BTreeMap<String, BTreeMap<NodeId, NodeEntry>> = BTreeMap::new();
        for n in &report.nodes {
            let mut errors: BTreeMap<Code, ErrorEntry> = n
                .stats
                .raised
                .iter()
                .map(|(&code, &raised)| {
                    let entry = ErrorEntry {
                        active_at_end: false,
                        raised,
                    };
                    (Code(code), entry)
                })
                .collect();
            for &code in &n.active {
                errors.entry(Code(code)).or_default().active_at_end = true;
            }
            let entry = NodeEntry {
                emcy: n.emcy_count,
                errors,
                heartbeat_lost: n.heartbeat.as_ref().map_or(0, |h| h.lost),
                drive_faults: n.drive.as_ref().map_or(0, |a| a.fault_count),
                bus_off: 0,
            };
            nodes
                .entry(n.channel.clone())
                .or_default()
                .insert(n.node, entry);
        }
        let mut bus_off: BTreeMap<String, u64> = BTreeMap::new();
        for c in &report.bus_errors {
            for b in &c.bus_offs {
                match b.node {
                    Some(node) => {
                        let entry = nodes.entry(c.channel.clone()).or_default();
                        entry.entry(node).or_default().bus_off += 1;
                    }
                    None => *bus_off.entry(c.channel.clone()).or_default() += 1,
                }
            }
        }
        let mut incidents: BTreeMap<String, BTreeMap<String, u64>> = BTreeMap::new();
        for (root, n) in &report.incident_roots {
            *incidents
                .entry(root.channel.clone())
                .or_default()
                .entry(root.words())
                .or_default() += n;
        }
        TraceEntry {
            counts: CountsEntry {
                boot: c.boot,
                emcy: c.emcy,
                emcy_invalid: c.emcy_invalid,
                frames: c.frames,
                lines: c.lines,
                malformed: c.malformed,
                other_format: c.other_format,
                skipped: c.skipped,
            },
            format: report.format.map(|f| f.name().to_string()),
            nodes,
            bus_off,
            incidents,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_read_back_only_in_their_one_spelling() {
        let code = |s: &str| serde_json::from_str::<Code>(s).ok();
        assert_eq!(code("\"0x4310\""), Some(Code(0x4310)));
        assert_eq!(code("\"0xFF01\""), Some(Code(0xFF01)));
        assert_eq!(code("\"0xff01\""), None);
        assert_eq!(code("\"4310\""), None);
        assert_eq!(code("\"0x431\""), None);
        assert_eq!(code("17168"), None);
        assert_eq!(
            serde_json::to_string(&Code(0x00A1)).ok().as_deref(),
            Some("\"0x00A1\"")
        );
    }

    #[test]
    fn version_is_checked_before_the_shape() {
        let err = |s: &str| Baseline::from_json(s).err().map(|e| format!("{e:#}"));
        assert!(
            err(r#"{"baseline_version": 2, "x": []}"#).is_some_and(|e| e.contains("version 2"))
        );
        assert!(err(r#"{"traces": {}}"#).is_some_and(|e| e.contains("no baseline_version")));
        assert!(err("[1,").is_some_and(|e| e.contains("invalid JSON")));
        assert!(err(r#"{"baseline_version": 1}"#).is_some_and(|e| e.contains("not a baseline")));
        // What is not a whole number is no version, as it always was.
        for text in [
            "[1, 2]",
            "1",
            r#"{"baseline_version": "1", "traces": {}}"#,
            r#"{"baseline_version": -1, "traces": {}}"#,
            r#"{"baseline_version": 1.0, "traces": {}}"#,
        ] {
            assert!(
                err(text).is_some_and(|e| e.contains("no baseline_version number")),
                "{text}"
            );
        }
        // The version is named even when the rest is of another shape...
        assert!(
            err(r#"{"traces": 5, "baseline_version": 3}"#).is_some_and(|e| e.contains("version 3"))
        );
        // ...but a syntax error anywhere is a syntax error.
        assert!(
            err(r#"{"baseline_version": 3, "traces": {"a": tru}}"#)
                .is_some_and(|e| e.contains("invalid JSON"))
        );
        assert_eq!(
            Baseline::from_json(r#"{"baseline_version": 1, "traces": {}}"#).ok(),
            Some(Baseline {
                baseline_version: 1,
                options: ReadOptions::default(),
                traces: BTreeMap::new()
            })
        );
    }
}
