//! `baseline` and `check`: CI regression checks over CAN traces.
//!
//! `baseline` reads traces and records, per trace and per (channel, node),
//! which error codes were raised, how often, and which were still active at
//! the end, plus the trace's line counts. `check` reads the same traces
//! again, compares them with a recorded baseline and prints one finding per
//! line. The baseline file format and the rules for what is a regression are
//! in the README ("Use in CI"); this module is their single implementation.

use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::io::{self, Write};
use std::path::{Component, Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::analyze::{self, DiagnosticLog, EmcyId, Options, OutputError};
use crate::canopen::codes;
use crate::cli::{InputFormat, parse_emcy_id, parse_node};
use crate::report::table::printable;
use crate::report::{BootEvent, Diagnostic, EmcyEvent, InputReport, Renderer};
use crate::run::{EXIT_ERROR, EXIT_FAIL_ON, EXIT_OK};
use crate::trace::input::{ReadMode, Source};

/// The `baseline_version` this build writes and reads.
pub const VERSION: u32 = 1;

// ---- command line ----------------------------------------------------------------

/// Traces and how to read them; the same for `baseline` and `check`, so a
/// check reads its traces exactly as the baseline did.
#[derive(Args, Debug)]
pub struct TraceArgs {
    /// Trace files (`-` reads stdin); each is recorded under the path as given,
    /// normalized and relative
    #[arg(value_name = "TRACE", required = true)]
    pub traces: Vec<PathBuf>,

    /// Read traces as this format instead of detecting it
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub input_format: Option<InputFormat>,

    /// A node's EMCY id moved by object 0x1014: COBID=NODE, e.g. 0x1A5=5 (repeatable)
    #[arg(long, value_parser = parse_emcy_id, value_name = "COBID=NODE")]
    pub emcy_id: Vec<EmcyId>,

    /// Print at most N diagnostics (malformed lines...) per trace on stderr
    #[arg(long, default_value_t = 20, value_name = "N")]
    pub max_diagnostics: usize,

    /// Vendor profile for every node (NAME) or one node (NODE=NAME), as for decoding
    #[arg(long, value_parser = crate::cli::parse_profile_arg, value_name = "[NODE=]NAME")]
    pub profile: Vec<crate::cli::ProfileArg>,

    /// A user profile (TOML), as for decoding
    #[arg(long, value_name = "FILE.toml")]
    pub profile_file: Vec<PathBuf>,
}

#[derive(Args, Debug)]
pub struct BaselineArgs {
    #[command(flatten)]
    pub read: TraceArgs,

    /// Write the baseline to FILE (replaced atomically) instead of stdout
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

const CHECK_HELP: &str = "\
Output: one line per difference, `SEVERITY: FILE[ CHANNEL node N]: MESSAGE`,
sorted by file, channel, node and code, then a `check:` summary line.

Regressions (exit 1 unless --allow/--allow-node accepts them): a new error
code, an error still active at the end that the baseline had cleared, a new
node with errors, more malformed lines or undecodable EMCYs, a trace not in
the baseline, a baseline trace not given.
Improvements (exit 0): an error no longer raised, an error no longer active
at the end, fewer malformed lines. Changes (exit 0): a known error raised a
different number of times, a node gone, a new node without errors, another
format.

Exit status:
  0  no regression (or --update)
  1  at least one regression
  2  usage error, unreadable trace or baseline, baseline of another version";

#[derive(Args, Debug)]
#[command(after_help = CHECK_HELP)]
pub struct CheckArgs {
    /// The baseline to compare with (written by `emcy-decode baseline`)
    #[arg(long, short = 'b', value_name = "FILE")]
    pub baseline: PathBuf,

    #[command(flatten)]
    pub read: TraceArgs,

    /// Output format of the differences
    #[arg(long, short = 'f', value_enum, default_value_t = CheckFormat::Text)]
    pub format: CheckFormat,

    /// Accept new or newly active errors with this code (repeatable or comma list, hex)
    #[arg(long, value_delimiter = ',', value_parser = parse_code_arg, value_name = "CODE")]
    pub allow: Vec<u16>,

    /// Accept every difference of this node, on any channel (repeatable or comma list)
    #[arg(long, value_delimiter = ',', value_parser = parse_node, value_name = "N")]
    pub allow_node: Vec<u8>,

    /// Rewrite the baseline from these traces after printing the differences; exit 0
    #[arg(long)]
    pub update: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CheckFormat {
    /// One finding per line, then a summary line
    Text,
    /// One JSON document: findings and summary
    Json,
}

fn parse_code_arg(s: &str) -> Result<u16, String> {
    crate::explain::parse_code(s).map_err(|e| e.to_string())
}

// ---- the baseline file -------------------------------------------------------------

/// A baseline file. Serialized with sorted keys (struct fields are declared
/// in alphabetical order, maps are `BTreeMap`s) so the same traces always
/// give the same bytes.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Baseline {
    pub baseline_version: u32,
    /// By trace key (see [`trace_key`]).
    pub traces: BTreeMap<String, TraceEntry>,
}

#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TraceEntry {
    pub counts: CountsEntry,
    /// `candump`, `candump-screen`, `asc`, or null when no frame was found.
    pub format: Option<String>,
    /// Channel -> node -> what the node did.
    pub nodes: BTreeMap<String, BTreeMap<u8, NodeEntry>>,
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
    pub fn from_json(text: &str) -> Result<Baseline> {
        let value: serde_json::Value =
            serde_json::from_str(text).context("not a baseline (invalid JSON)")?;
        match value.get("baseline_version").map(serde_json::Value::as_u64) {
            Some(Some(v)) if v == u64::from(VERSION) => {}
            Some(Some(v)) => bail!(
                "baseline version {v} is not supported (this emcy-decode reads version \
                 {VERSION}); write it again with `emcy-decode baseline`"
            ),
            _ => bail!("not a baseline (no baseline_version number)"),
        }
        serde_json::from_value(value).context("not a baseline")
    }

    fn from_reports(traces: &[(String, InputReport)]) -> Baseline {
        let traces = traces
            .iter()
            .map(|(key, report)| (key.clone(), TraceEntry::from_report(report)))
            .collect();
        Baseline {
            baseline_version: VERSION,
            traces,
        }
    }
}

impl TraceEntry {
    fn from_report(report: &InputReport) -> TraceEntry {
        let c = report.counts;
        let mut nodes: BTreeMap<String, BTreeMap<u8, NodeEntry>> = BTreeMap::new();
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
            };
            nodes
                .entry(n.channel.clone())
                .or_default()
                .insert(n.node, entry);
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
        }
    }
}

// ---- trace keys --------------------------------------------------------------------

/// The key a trace is recorded under: the path as given, without `.`
/// components or doubled separators, with `/` separators. An absolute path
/// inside the current directory is made relative to it; any other absolute
/// path is reduced to its file name, so no baseline holds a machine's
/// directory layout. `-` is `<stdin>`.
pub fn trace_key(arg: &Path, cwd: Option<&Path>) -> String {
    if arg.as_os_str() == "-" {
        return "<stdin>".to_string();
    }
    let relative: Cow<'_, Path> = if arg.is_absolute() {
        match cwd.and_then(|cwd| inside(arg, cwd)) {
            Some(rel) => Cow::Owned(rel),
            None => Cow::Borrowed(arg.file_name().map_or(arg, Path::new)),
        }
    } else {
        Cow::Borrowed(arg)
    };
    let parts: Vec<Cow<'_, str>> = relative
        .components()
        .filter_map(|c| match c {
            Component::Normal(s) => Some(s.to_string_lossy()),
            Component::ParentDir => Some(Cow::Borrowed("..")),
            Component::CurDir | Component::RootDir | Component::Prefix(_) => None,
        })
        .collect();
    if parts.is_empty() {
        return ".".to_string();
    }
    parts.join("/")
}

/// `path` relative to `dir` when it is inside it, comparing as written and
/// then with symbolic links resolved (a shell's `$PWD` may differ from the
/// resolved current directory).
fn inside(path: &Path, dir: &Path) -> Option<PathBuf> {
    if let Ok(rel) = path.strip_prefix(dir) {
        return Some(rel.to_path_buf());
    }
    let path = path.canonicalize().ok()?;
    let dir = dir.canonicalize().ok()?;
    path.strip_prefix(&dir).ok().map(Path::to_path_buf)
}

// ---- reading traces ----------------------------------------------------------------

/// Receives events and throws them away: these commands need only the
/// per-input report.
struct Discard;

impl Renderer for Discard {
    fn emcy(&mut self, _: &EmcyEvent<'_>) -> io::Result<()> {
        Ok(())
    }
    fn boot(&mut self, _: &BootEvent<'_>) -> io::Result<()> {
        Ok(())
    }
    fn finish(&mut self, _: &[InputReport], _: &[Diagnostic]) -> io::Result<()> {
        Ok(())
    }
}

/// Reads every trace through the decode pipeline. `Ok(None)` when a trace
/// could not be read: each failure has had its `error:` line and the caller
/// exits 2 without writing or comparing anything.
fn read_traces(args: &TraceArgs) -> Result<Option<Vec<(String, InputReport)>>> {
    let cwd = std::env::current_dir().ok();
    let mut keys: BTreeMap<String, &Path> = BTreeMap::new();
    for arg in &args.traces {
        let key = trace_key(arg, cwd.as_deref());
        if let Some(first) = keys.insert(key.clone(), arg) {
            bail!(
                "{} and {} would both be recorded as '{key}'; give each trace once",
                first.display(),
                arg.display()
            );
        }
    }
    let opts = Options {
        input_format: args.input_format.map(Into::into),
        max_diagnostics: args.max_diagnostics,
        emcy_ids: args.emcy_id.clone(),
        profiles: crate::profile_choice::resolve(&args.profile, &args.profile_file)?,
        ..Options::default()
    };
    let mut log = DiagnosticLog::new(io::stderr());
    let mut reports = Vec::new();
    let mut failed = false;
    for arg in &args.traces {
        let source = Source::from_arg(arg);
        let analysis = analyze::analyze_source(
            &source,
            ReadMode::Finite,
            &opts,
            crate::run::auto_threads,
            |_, reader| reader,
            &mut Discard,
            &mut log,
        )
        .map_err(|OutputError(e)| anyhow::Error::from(e))?;
        let Some(analysis) = analysis else {
            failed = true;
            continue;
        };
        failed |= analysis.report.error.is_some();
        reports.push((trace_key(arg, cwd.as_deref()), analysis.report));
    }
    Ok((!failed).then_some(reports))
}

/// Writes `text` to `path` through a temporary file in the same directory,
/// so a reader (or a crash) never sees half a baseline. `-` is stdout.
fn write_file(path: &Path, text: &str) -> Result<()> {
    if path.as_os_str() == "-" {
        return write_stdout(text);
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let fail = || format!("writing {}", path.display());
    let mut tmp = tempfile::NamedTempFile::new_in(dir).with_context(fail)?;
    tmp.write_all(text.as_bytes()).with_context(fail)?;
    // A temporary file is private (0600); a baseline is an ordinary file.
    let perms = match std::fs::metadata(path) {
        Ok(meta) => Some(meta.permissions()),
        Err(_) => default_permissions(),
    };
    if let Some(perms) = perms {
        tmp.as_file().set_permissions(perms).with_context(fail)?;
    }
    tmp.persist(path).map_err(|e| e.error).with_context(fail)?;
    Ok(())
}

#[cfg(unix)]
fn default_permissions() -> Option<std::fs::Permissions> {
    use std::os::unix::fs::PermissionsExt;
    Some(std::fs::Permissions::from_mode(0o644))
}

#[cfg(not(unix))]
fn default_permissions() -> Option<std::fs::Permissions> {
    None
}

fn write_stdout(text: &str) -> Result<()> {
    crate::run::write_stdout(text).map(|_| ())
}

// ---- commands ----------------------------------------------------------------------

/// `emcy-decode baseline TRACE... [-o FILE]`.
pub fn baseline_command(args: &BaselineArgs) -> Result<ExitCode> {
    let Some(reports) = read_traces(&args.read)? else {
        return Ok(ExitCode::from(EXIT_ERROR));
    };
    let text = Baseline::from_reports(&reports).to_json()?;
    write_file(args.output.as_deref().unwrap_or(Path::new("-")), &text)?;
    Ok(ExitCode::from(EXIT_OK))
}

/// `emcy-decode check --baseline FILE TRACE...`.
pub fn check_command(args: &CheckArgs) -> Result<ExitCode> {
    let name = args.baseline.display();
    let text = std::fs::read_to_string(&args.baseline)
        .map_err(|e| anyhow::anyhow!("{name}: {}", analyze::describe_io(&e)))?;
    let old = Baseline::from_json(&text).with_context(|| name.to_string())?;
    let Some(reports) = read_traces(&args.read)? else {
        return Ok(ExitCode::from(EXIT_ERROR));
    };
    let new = Baseline::from_reports(&reports);
    let allow = Allow {
        codes: args.allow.iter().copied().collect(),
        nodes: args.allow_node.iter().copied().collect(),
    };
    let diff = compare(&old, &new, &allow);
    let out = match args.format {
        CheckFormat::Text => diff.text(),
        CheckFormat::Json => diff.json()?,
    };
    write_stdout(&out)?;
    if args.update {
        write_file(&args.baseline, &new.to_json()?)?;
        eprintln!("check: wrote {name}");
        return Ok(ExitCode::from(EXIT_OK));
    }
    let code = if diff.summary.regressions > 0 {
        EXIT_FAIL_ON
    } else {
        EXIT_OK
    };
    Ok(ExitCode::from(code))
}

// ---- comparing ---------------------------------------------------------------------

/// Differences the user accepts (`--allow`, `--allow-node`).
#[derive(Clone, Debug, Default)]
pub struct Allow {
    pub codes: BTreeSet<u16>,
    pub nodes: BTreeSet<u8>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// Exit 1 unless allowed.
    Regression,
    /// Better than the baseline; exit 0.
    Improvement,
    /// Neither better nor worse; exit 0.
    Change,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    TraceNotInBaseline,
    TraceNotGiven,
    FormatChanged,
    MalformedGrew,
    MalformedFell,
    EmcyInvalidGrew,
    EmcyInvalidFell,
    NewNode,
    NewNodeWithoutErrors,
    NodeGone,
    NewError,
    NowActive,
    ErrorGone,
    NowCleared,
    CountChanged,
}

impl Kind {
    fn severity(self) -> Severity {
        match self {
            Kind::TraceNotInBaseline
            | Kind::TraceNotGiven
            | Kind::MalformedGrew
            | Kind::EmcyInvalidGrew
            | Kind::NewNode
            | Kind::NewError
            | Kind::NowActive => Severity::Regression,
            Kind::MalformedFell | Kind::EmcyInvalidFell | Kind::ErrorGone | Kind::NowCleared => {
                Severity::Improvement
            }
            Kind::FormatChanged
            | Kind::NewNodeWithoutErrors
            | Kind::NodeGone
            | Kind::CountChanged => Severity::Change,
        }
    }
}

/// One difference. Every finding has every key (null when it does not
/// apply), so `--format json` consumers see one shape.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Finding {
    pub severity: Severity,
    pub kind: Kind,
    /// Accepted by `--allow`/`--allow-node`: not counted as a regression.
    pub allowed: bool,
    pub file: String,
    pub channel: Option<String>,
    pub node: Option<u8>,
    pub code: Option<Code>,
    /// The number now (raised count, line count) and in the baseline.
    pub count: Option<u64>,
    pub baseline_count: Option<u64>,
    /// The text after `FILE [CHANNEL node N]: ` in the text output.
    pub message: String,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Summary {
    /// Regressions not allowed: exit 1 when over 0.
    pub regressions: u64,
    pub allowed: u64,
    pub improvements: u64,
    pub changes: u64,
    /// Traces given plus baseline traces not given.
    pub traces: u64,
    /// Traces in both with no regression (allowed ones do not count).
    pub matched: u64,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Diff {
    pub findings: Vec<Finding>,
    pub summary: Summary,
}

/// Where a finding is: a trace, or a node in it.
#[derive(Clone, Copy)]
struct Place<'a> {
    file: &'a str,
    node: Option<(&'a str, u8)>,
}

/// No counts.
const NONE: (Option<u64>, Option<u64>) = (None, None);

struct Collector<'a> {
    allow: &'a Allow,
    findings: Vec<Finding>,
}

impl Collector<'_> {
    /// Records a finding; `allowed` says it is accepted whatever the
    /// `--allow` lists hold.
    fn add(
        &mut self,
        at: Place<'_>,
        kind: Kind,
        code: Option<u16>,
        (count, baseline_count): (Option<u64>, Option<u64>),
        allowed: bool,
        message: String,
    ) {
        let node_allowed = at.node.is_some_and(|(_, n)| self.allow.nodes.contains(&n));
        let code_allowed = code.is_some_and(|c| self.allow.codes.contains(&c));
        let severity = kind.severity();
        self.findings.push(Finding {
            severity,
            kind,
            allowed: severity == Severity::Regression && (allowed || node_allowed || code_allowed),
            file: at.file.to_string(),
            channel: at.node.map(|(c, _)| c.to_string()),
            node: at.node.map(|(_, n)| n),
            code: code.map(Code),
            count,
            baseline_count,
            message,
        });
    }
}

fn describe(code: Code) -> String {
    codes::lookup(code.0).description().to_string()
}

fn times(n: u64, active: bool) -> String {
    if active {
        format!("{n}x, still active at end")
    } else {
        format!("{n}x")
    }
}

fn error_list(errors: &BTreeMap<Code, ErrorEntry>) -> String {
    let items: Vec<String> = errors
        .iter()
        .map(|(code, e)| format!("{code} ({})", times(e.raised, e.active_at_end)))
        .collect();
    items.join(", ")
}

/// Compares the traces of `new` with those of `old`.
pub fn compare(old: &Baseline, new: &Baseline, allow: &Allow) -> Diff {
    let mut c = Collector {
        allow,
        findings: Vec::new(),
    };
    let mut summary = Summary::default();
    let files: BTreeSet<&String> = old.traces.keys().chain(new.traces.keys()).collect();
    for file in files {
        summary.traces += 1;
        let at = Place { file, node: None };
        match (old.traces.get(file), new.traces.get(file)) {
            (Some(o), Some(n)) => {
                let before = c.findings.len();
                compare_trace(&mut c, file, o, n);
                let regressed = c
                    .findings
                    .get(before..)
                    .unwrap_or_default()
                    .iter()
                    .any(|f| f.severity == Severity::Regression && !f.allowed);
                if !regressed {
                    summary.matched += 1;
                }
            }
            (None, Some(_)) => c.add(
                at,
                Kind::TraceNotInBaseline,
                None,
                NONE,
                false,
                "not in the baseline".to_string(),
            ),
            (Some(_), None) => c.add(
                at,
                Kind::TraceNotGiven,
                None,
                NONE,
                false,
                "in the baseline but not given".to_string(),
            ),
            (None, None) => {}
        }
    }
    let mut findings = c.findings;
    findings.sort_by(|a, b| {
        (&a.file, &a.channel, a.node, a.code, a.kind)
            .cmp(&(&b.file, &b.channel, b.node, b.code, b.kind))
    });
    for f in &findings {
        match (f.severity, f.allowed) {
            (Severity::Regression, true) => summary.allowed += 1,
            (Severity::Regression, false) => summary.regressions += 1,
            (Severity::Improvement, _) => summary.improvements += 1,
            (Severity::Change, _) => summary.changes += 1,
        }
    }
    Diff { findings, summary }
}

fn compare_trace(c: &mut Collector<'_>, file: &str, old: &TraceEntry, new: &TraceEntry) {
    let at = Place { file, node: None };
    if old.format != new.format {
        let name = |f: &Option<String>| f.clone().unwrap_or_else(|| "none".to_string());
        let msg = format!(
            "format {}, baseline {}",
            name(&new.format),
            name(&old.format)
        );
        c.add(at, Kind::FormatChanged, None, NONE, false, msg);
    }
    let pairs = [
        (
            "malformed lines",
            old.counts.malformed,
            new.counts.malformed,
            Kind::MalformedGrew,
            Kind::MalformedFell,
        ),
        (
            "EMCY frames too short to decode",
            old.counts.emcy_invalid,
            new.counts.emcy_invalid,
            Kind::EmcyInvalidGrew,
            Kind::EmcyInvalidFell,
        ),
    ];
    for (what, was, now, grew, fell) in pairs {
        let kind = match now.cmp(&was) {
            std::cmp::Ordering::Greater => grew,
            std::cmp::Ordering::Less => fell,
            std::cmp::Ordering::Equal => continue,
        };
        let msg = format!("{what} {now}, baseline {was}");
        c.add(at, kind, None, (Some(now), Some(was)), false, msg);
    }

    let empty = BTreeMap::new();
    let channels: BTreeSet<&String> = old.nodes.keys().chain(new.nodes.keys()).collect();
    for channel in channels {
        let o = old.nodes.get(channel).unwrap_or(&empty);
        let n = new.nodes.get(channel).unwrap_or(&empty);
        let ids: BTreeSet<u8> = o.keys().chain(n.keys()).copied().collect();
        for id in ids {
            let at = Place {
                file,
                node: Some((channel, id)),
            };
            compare_node(c, at, o.get(&id), n.get(&id));
        }
    }
}

fn compare_node(
    c: &mut Collector<'_>,
    at: Place<'_>,
    old: Option<&NodeEntry>,
    new: Option<&NodeEntry>,
) {
    match (old, new) {
        (None, Some(n)) if n.errors.is_empty() => {
            let msg = "new node, no errors".to_string();
            c.add(at, Kind::NewNodeWithoutErrors, None, NONE, false, msg);
        }
        (None, Some(n)) => {
            // The node's errors are what makes it a regression: allowed when
            // every one of them is.
            let all_allowed = n.errors.keys().all(|k| c.allow.codes.contains(&k.0));
            let msg = format!("new node with errors {}", error_list(&n.errors));
            c.add(at, Kind::NewNode, None, NONE, all_allowed, msg);
        }
        (Some(o), None) => {
            let msg = if o.errors.is_empty() {
                "node no longer appears (baseline: no errors)".to_string()
            } else {
                format!(
                    "node no longer appears (baseline: errors {})",
                    error_list(&o.errors)
                )
            };
            c.add(at, Kind::NodeGone, None, NONE, false, msg);
        }
        (Some(o), Some(n)) => compare_errors(c, at, &o.errors, &n.errors),
        (None, None) => {}
    }
}

fn compare_errors(
    c: &mut Collector<'_>,
    at: Place<'_>,
    old: &BTreeMap<Code, ErrorEntry>,
    new: &BTreeMap<Code, ErrorEntry>,
) {
    let codes: BTreeSet<Code> = old.keys().chain(new.keys()).copied().collect();
    for code in codes {
        let desc = describe(code);
        let now = new.get(&code);
        let was = old.get(&code);
        let counts = (now.map(|e| e.raised), was.map(|e| e.raised));
        let mut add = |kind, msg| c.add(at, kind, Some(code.0), counts, false, msg);
        match (was, now) {
            (None, Some(n)) => {
                let msg = format!(
                    "new error {code} ({}): {desc}",
                    times(n.raised, n.active_at_end)
                );
                add(Kind::NewError, msg);
            }
            (Some(o), None) => {
                let msg = format!(
                    "error {code} no longer appears (baseline {}x): {desc}",
                    o.raised
                );
                add(Kind::ErrorGone, msg);
            }
            (Some(o), Some(n)) => {
                if n.active_at_end && !o.active_at_end {
                    let msg = format!(
                        "error {code} still active at end, cleared in the baseline: {desc}"
                    );
                    add(Kind::NowActive, msg);
                }
                if !n.active_at_end && o.active_at_end {
                    let msg =
                        format!("error {code} cleared by the end, active in the baseline: {desc}");
                    add(Kind::NowCleared, msg);
                }
                if n.raised != o.raised {
                    let msg = format!(
                        "error {code} raised {}x, baseline {}x: {desc}",
                        n.raised, o.raised
                    );
                    add(Kind::CountChanged, msg);
                }
            }
            (None, None) => {}
        }
    }
}

// ---- output ------------------------------------------------------------------------

fn plural(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

impl Diff {
    /// One line per finding, `SEVERITY: FILE[ CHANNEL node N]: MESSAGE`,
    /// sorted by file, channel, node and code; then the summary line.
    pub fn text(&self) -> String {
        let mut out = String::new();
        for f in &self.findings {
            let severity = match (f.severity, f.allowed) {
                (Severity::Regression, true) => "allowed",
                (Severity::Regression, false) => "regression",
                (Severity::Improvement, _) => "improvement",
                (Severity::Change, _) => "change",
            };
            out.push_str(severity);
            out.push_str(": ");
            out.push_str(&printable(&f.file));
            if let (Some(channel), Some(node)) = (&f.channel, f.node) {
                out.push(' ');
                out.push_str(&printable(channel));
                out.push_str(&format!(" node {node}"));
            }
            out.push_str(": ");
            out.push_str(&printable(&f.message));
            out.push('\n');
        }
        let s = &self.summary;
        let allowed = if s.allowed > 0 {
            format!(" ({} allowed)", s.allowed)
        } else {
            String::new()
        };
        out.push_str(&format!(
            "check: {}{allowed}, {}, {}; {} of {} matched\n",
            plural(s.regressions, "regression", "regressions"),
            plural(s.improvements, "improvement", "improvements"),
            plural(s.changes, "change", "changes"),
            s.matched,
            plural(s.traces, "trace", "traces"),
        ));
        out
    }

    /// `{"findings": [...], "summary": {...}}`, pretty, one trailing newline.
    pub fn json(&self) -> Result<String> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        Ok(text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_relative_and_normalized() {
        let cwd = Path::new("/home/ci/project");
        let key = |p: &str| trace_key(Path::new(p), Some(cwd));
        assert_eq!(key("traces/a.log"), "traces/a.log");
        assert_eq!(key("./traces//a.log"), "traces/a.log");
        assert_eq!(key("../other/a.log"), "../other/a.log");
        assert_eq!(key("/home/ci/project/traces/a.log"), "traces/a.log");
        assert_eq!(key("/tmp/x/a.log"), "a.log");
        assert_eq!(key("-"), "<stdin>");
        assert_eq!(trace_key(Path::new("/tmp/a.log"), None), "a.log");
    }

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
        assert_eq!(
            Baseline::from_json(r#"{"baseline_version": 1, "traces": {}}"#).ok(),
            Some(Baseline {
                baseline_version: 1,
                traces: BTreeMap::new()
            })
        );
    }

    fn node(errors: &[(u16, u64, bool)]) -> NodeEntry {
        NodeEntry {
            emcy: 0,
            errors: errors
                .iter()
                .map(|&(c, raised, active_at_end)| {
                    (
                        Code(c),
                        ErrorEntry {
                            active_at_end,
                            raised,
                        },
                    )
                })
                .collect(),
        }
    }

    fn one(nodes: &[(u8, NodeEntry)]) -> Baseline {
        let mut trace = TraceEntry::default();
        trace
            .nodes
            .insert("can0".to_string(), nodes.iter().cloned().collect());
        Baseline {
            baseline_version: VERSION,
            traces: [("t.log".to_string(), trace)].into_iter().collect(),
        }
    }

    #[test]
    fn each_difference_has_its_severity() {
        let old = one(&[
            (
                1,
                node(&[(0x4310, 2, false), (0x3120, 1, true), (0x5111, 1, false)]),
            ),
            (2, node(&[])),
        ]);
        let new = one(&[
            (
                1,
                node(&[(0x4310, 3, true), (0x3120, 1, false), (0x2310, 1, false)]),
            ),
            (3, node(&[(0x8130, 1, true)])),
        ]);
        let diff = compare(&old, &new, &Allow::default());
        let kinds: Vec<(Option<u8>, Option<Code>, Kind, Severity)> = diff
            .findings
            .iter()
            .map(|f| (f.node, f.code, f.kind, f.severity))
            .collect();
        use Kind::*;
        use Severity::*;
        assert_eq!(
            kinds,
            vec![
                (Some(1), Some(Code(0x2310)), NewError, Regression),
                (Some(1), Some(Code(0x3120)), NowCleared, Improvement),
                (Some(1), Some(Code(0x4310)), NowActive, Regression),
                (Some(1), Some(Code(0x4310)), CountChanged, Change),
                (Some(1), Some(Code(0x5111)), ErrorGone, Improvement),
                (Some(2), None, NodeGone, Change),
                (Some(3), None, NewNode, Regression),
            ]
        );
        assert_eq!(diff.summary.regressions, 3);
        assert_eq!(diff.summary.matched, 0);

        let allow = Allow {
            codes: [0x2310, 0x8130].into_iter().collect(),
            nodes: [1].into_iter().collect(),
        };
        let diff = compare(&old, &new, &allow);
        assert_eq!(diff.summary.regressions, 0);
        assert_eq!(diff.summary.allowed, 3);
        assert_eq!(diff.summary.matched, 1);
    }

    #[test]
    fn a_new_node_without_errors_is_only_a_change() {
        let old = one(&[]);
        let new = one(&[(4, node(&[]))]);
        let diff = compare(&old, &new, &Allow::default());
        assert_eq!(diff.findings.len(), 1);
        assert_eq!(diff.findings[0].kind, Kind::NewNodeWithoutErrors);
        assert_eq!(diff.findings[0].severity, Severity::Change);
        assert_eq!(diff.summary.regressions, 0);
    }

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable("can\u{1b}]0"), "can\\u{1b}]0");
        assert_eq!(printable("can0"), "can0");
    }
}
