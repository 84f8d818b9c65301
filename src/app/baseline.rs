//! `emcy-decode baseline` and `emcy-decode check`: read the traces, then
//! write the baseline (atomically) or compare with it and print the
//! differences. The model and the comparison are library code
//! ([`crate::baseline`]); this file is their process side.

use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::Path;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};

use super::cli::{BaselineArgs, CheckArgs, CheckFormat, TraceArgs};
use super::decode::auto_threads;
use super::{EXIT_ERROR, EXIT_FAIL_ON, EXIT_OK};
use crate::analyze::{self, DiagnosticLog, Discard, InputReport, OutputError};
use crate::baseline::Baseline;
use crate::baseline::compare::{Allow, compare};
use crate::baseline::key::trace_key;
use crate::trace::input::{ReadMode, Source};

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
    let opts = args.options()?;
    let mut log = DiagnosticLog::new(io::stderr());
    let mut reports = Vec::new();
    let mut failed = false;
    for arg in &args.traces {
        let source = Source::from_arg(arg);
        let analysis = analyze::analyze_source(
            &source,
            ReadMode::Finite,
            &opts,
            auto_threads,
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
    super::write_stdout(text).map(|_| ())
}

/// `emcy-decode baseline TRACE... [-o FILE]`.
pub(super) fn baseline(args: &BaselineArgs) -> Result<ExitCode> {
    let Some(reports) = read_traces(&args.read)? else {
        return Ok(ExitCode::from(EXIT_ERROR));
    };
    let text = Baseline::from_reports(&reports).to_json()?;
    write_file(args.output.as_deref().unwrap_or(Path::new("-")), &text)?;
    Ok(ExitCode::from(EXIT_OK))
}

/// `emcy-decode check --baseline FILE TRACE...`.
pub(super) fn check(args: &CheckArgs) -> Result<ExitCode> {
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
