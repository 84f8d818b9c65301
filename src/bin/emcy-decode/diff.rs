//! `emcy-decode diff GOOD BAD`: read both traces into their CANopen stories
//! and print how they differ. The stories and their comparison are library
//! code ([`emcy_decode::diff`]); this file reads the traces and chooses the
//! exit status, as diff(1) does: 0 the same, 1 different, 2 trouble.

use std::io;
use std::path::Path;
use std::process::ExitCode;

use anyhow::{Result, bail};

use super::cli::{DiffArgs, ExplainFormat};
use super::decode::auto_threads;
use super::{EXIT_ERROR, EXIT_FAIL_ON, EXIT_OK, signals, write_stdout};
use emcy_decode::analyze::{self, DiagnosticLog, Options, OutputError, Sink};
use emcy_decode::diff::{self, Recorder, Story};
use emcy_decode::trace::input::{self, ReadMode, Source};

pub(super) fn run(args: &DiffArgs) -> Result<ExitCode> {
    if args.good.as_os_str() == "-" && args.bad.as_os_str() == "-" {
        bail!("GOOD and BAD cannot both be stdin (`-`)");
    }
    let opts = args.reading.options()?;
    let mut log = DiagnosticLog::new(io::stderr());
    let caught = signals::catch(&opts.cancel);
    // Both traces are read even when the first cannot be, so one run names
    // every input in trouble.
    let good = read(&args.good, &opts, &mut log)?;
    if let Some(stop) = caught.stopped() {
        log.error(&format!("stopped by {}; nothing compared", stop.name));
        return Ok(ExitCode::from(stop.status));
    }
    let bad = read(&args.bad, &opts, &mut log)?;
    if let Some(stop) = caught.stopped() {
        log.error(&format!("stopped by {}; nothing compared", stop.name));
        return Ok(ExitCode::from(stop.status));
    }
    let (Some(good), Some(bad)) = (good, bad) else {
        return Ok(ExitCode::from(EXIT_ERROR));
    };
    let comparison = diff::compare(&good, &bad);
    let text = match args.format {
        ExplainFormat::Text => diff::text::render(&comparison),
        ExplainFormat::Json => diff::text::render_json(&comparison),
    };
    write_stdout(&text)?;
    Ok(ExitCode::from(if comparison.same() {
        EXIT_OK
    } else {
        EXIT_FAIL_ON
    }))
}

/// One trace's story; `None` when it could not be read whole (its
/// `error:` line is out): half a trace would differ from a whole one.
fn read<E: io::Write>(
    path: &Path,
    opts: &Options,
    log: &mut DiagnosticLog<E>,
) -> Result<Option<Story>> {
    let mut recorder = Recorder::new();
    let whole = read_whole(path, opts, log, &mut recorder)?;
    Ok(whole.then(|| recorder.into_story()))
}

/// Reads the trace at `path` (`-`: stdin) into `sink`; whether it was read
/// whole (when not, its `error:` line is out).
pub(super) fn read_whole<E: io::Write>(
    path: &Path,
    opts: &Options,
    log: &mut DiagnosticLog<E>,
    sink: &mut dyn Sink,
) -> Result<bool> {
    let source = Source::from_arg(path);
    // A pipe may be quiet for long: read so that a signal ends the wait.
    let mode = if matches!(source, Source::Stdin) && input::stdin_is_stream() {
        ReadMode::Live
    } else {
        ReadMode::Finite
    };
    let analysis = analyze::analyze_source(
        &source,
        mode,
        opts,
        |opened| auto_threads(opened, opts.timing),
        |_, reader| reader,
        sink,
        log,
    )
    .map_err(|OutputError(e)| anyhow::Error::from(e))?;
    Ok(analysis.report.error.is_none())
}
