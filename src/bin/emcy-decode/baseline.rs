//! `emcy-decode baseline` and `emcy-decode check`: read the traces, then
//! write the baseline (never over anything but a regular file, and that
//! atomically) or compare with it and print the differences. The model and
//! the comparison are library code ([`emcy_decode::baseline`]); this file is their
//! process side.
//!
//! A signal (a CI timeout, Ctrl-C) while the traces are read stops reading:
//! a baseline or a comparison of part of the traces would be wrong, so
//! nothing is written or compared; an `error:` line says so and the exit
//! status is the signal's (130, 143, 129), as for decoding.

use std::collections::BTreeMap;
use std::fs::{self, OpenOptions, Permissions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, anyhow, bail};

use super::cli::{BaselineArgs, CheckArgs, CheckFormat, TraceArgs};
use super::decode::{Input, Walk, auto_threads};
use super::{EXIT_ERROR, EXIT_FAIL_ON, EXIT_OK, signals};
use emcy_decode::analyze::{self, DiagnosticLog, Discard, InputReport, OutputError, describe_io};
use emcy_decode::baseline::compare::{Allow, compare};
use emcy_decode::baseline::key::trace_key_under;
use emcy_decode::baseline::text::{JunitCase, junit_unread};
use emcy_decode::baseline::{self, Baseline};
use emcy_decode::small_file;
use emcy_decode::trace::input::{self, ReadMode, Source};

/// The traces as read: each one's key and report, and the seconds reading
/// it took (for JUnit's `time`).
struct Traces {
    reports: Vec<(String, InputReport)>,
    seconds: BTreeMap<String, f64>,
}

/// Reading stopped: the status to exit with, and every trace given as a
/// case for a JUnit report, with why it could not be read.
struct Unread {
    status: ExitCode,
    cases: Vec<JunitCase>,
}

/// Reads every trace through the decode pipeline. `Ok(Err(unread))` when a
/// trace could not be read (2) or a signal stopped reading (its status):
/// each has had its `error:` line (naming `unwritten`, what is then not
/// done) and the caller exits with that status without writing or
/// comparing anything.
fn read_traces(args: &TraceArgs, unwritten: &str) -> Result<Result<Traces, Unread>> {
    let cwd = std::env::current_dir().ok();
    let root = args.root.as_deref();
    let opts = args.reading.options()?;
    let mut log = DiagnosticLog::new(io::stderr());
    // Directories (-r) become their traces, in name order; a part that
    // cannot be listed is an unreadable trace.
    let mut traces: Vec<PathBuf> = Vec::new();
    let walk = Walk::new(args.recursive, args.follow_links, &args.glob)?;
    let mut unlisted = Vec::new();
    for input in walk.expand(&args.traces, &opts.cancel, &mut log) {
        match input {
            Input::Source(Source::Path(p)) => traces.push(p),
            Input::Source(Source::Stdin) => traces.push(PathBuf::from("-")),
            Input::Unlisted { name, error } => {
                log.error(&format!("{name}: {error}; {unwritten}"));
                unlisted.push(JunitCase::unread(name, error, 0.0));
            }
        }
    }
    if !unlisted.is_empty() {
        return Ok(Err(Unread {
            status: ExitCode::from(EXIT_ERROR),
            cases: unlisted,
        }));
    }
    let mut keys: BTreeMap<String, &Path> = BTreeMap::new();
    for arg in &traces {
        let key = trace_key_under(arg, cwd.as_deref(), root);
        if let Some(first) = keys.insert(key.clone(), arg) {
            bail!(
                "{} and {} would both be recorded as '{key}'; give each trace once",
                first.display(),
                arg.display()
            );
        }
    }
    let caught = signals::catch(&opts.cancel);
    let mut reports = Vec::new();
    let mut seconds = BTreeMap::new();
    let mut cases = Vec::new();
    let mut failed = false;
    for arg in &traces {
        let started = std::time::Instant::now();
        let key = trace_key_under(arg, cwd.as_deref(), root);
        let source = Source::from_arg(arg);
        // A pipe may be quiet for long: read so that a signal ends the wait.
        let mode = if matches!(source, Source::Stdin) && input::stdin_is_stream() {
            ReadMode::Live
        } else {
            ReadMode::Finite
        };
        let analysis = analyze::analyze_source(
            &source,
            mode,
            &opts,
            |opened| auto_threads(opened, opts.timing),
            |_, reader| reader,
            &mut Discard,
            &mut log,
        )
        .map_err(|OutputError(e)| anyhow::Error::from(e))?;
        let took = started.elapsed().as_secs_f64();
        if let Some(stop) = caught.stopped() {
            log.error(&format!(
                "stopped by {} while reading {}; {unwritten}",
                stop.name,
                source.display_name()
            ));
            let why = format!("stopped by {}", stop.name);
            cases.push(JunitCase::unread(key, why, took));
            return Ok(Err(Unread {
                status: ExitCode::from(stop.status),
                cases,
            }));
        }
        failed |= analysis.report.error.is_some();
        cases.push(JunitCase {
            trace: key.clone(),
            seconds: took,
            error: analysis.report.error.clone(),
        });
        seconds.insert(key.clone(), took);
        reports.push((key, analysis.report));
    }
    Ok(if failed {
        Err(Unread {
            status: ExitCode::from(EXIT_ERROR),
            cases,
        })
    } else {
        Ok(Traces { reports, seconds })
    })
}

/// Writes `text` where `given` says ([`destination`]): over a regular file
/// or a new path through a temporary file in the same directory, so a reader
/// (or a crash) never sees half a baseline; into a FIFO or character device
/// as it is; `-` is stdout.
pub(super) fn write_file(given: &Path, text: &str) -> Result<()> {
    let fail = |e: io::Error| anyhow!("writing {}: {}", given.display(), describe_io(&e));
    match destination(given)? {
        Dest::Stdout => write_stdout(text),
        Dest::Replace { path, old } => replace(&path, old, text).map_err(fail),
        Dest::Stream(path) => stream(&path, text).map_err(fail),
    }
}

/// Where a baseline written to a path goes. Only a regular file is ever
/// renamed over, so a device node, a FIFO or a symbolic link survives.
#[derive(Debug)]
enum Dest {
    /// `-`.
    Stdout,
    /// A regular file or a path that does not exist yet (the link's target
    /// when the path is a symbolic link): replaced atomically with the old
    /// file's permissions, owner and group (`None`: a new file).
    Replace {
        path: PathBuf,
        old: Option<fs::Metadata>,
    },
    /// A FIFO or character device (`/dev/null`, `/dev/stdout` to a pipe or
    /// a terminal): written into as it is, as the shell's `>` would.
    Stream(PathBuf),
}

/// Symbolic links followed at most, as Linux's `MAXSYMLINKS`.
const MAX_LINKS: usize = 40;

/// Where writing `given` goes; a directory, socket, block device or anything
/// else that is no file is refused, before anything is written. Symbolic
/// links are followed one by one (by hand: `canonicalize` fails on a
/// dangling link); a dangling one gets its target created, as the shell's
/// `>` does.
fn destination(given: &Path) -> Result<Dest> {
    if given.as_os_str() == "-" {
        return Ok(Dest::Stdout);
    }
    let refuse = |path: &Path, what: &str| {
        let via = if path == given {
            String::new()
        } else {
            format!(" (a link to {})", path.display())
        };
        anyhow!(
            "{}{via} {what}; a baseline is written to a regular file, a FIFO or a \
             character device",
            given.display()
        )
    };
    let mut path = given.to_path_buf();
    for _ in 0..=MAX_LINKS {
        let meta = match fs::symlink_metadata(&path) {
            Ok(meta) => meta,
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                return Ok(Dest::Replace { path, old: None });
            }
            Err(e) => bail!("{}: {}", given.display(), describe_io(&e)),
        };
        match Kind::of(meta.file_type()) {
            Kind::File => {
                return Ok(Dest::Replace {
                    path,
                    old: Some(meta),
                });
            }
            Kind::Stream => return Ok(Dest::Stream(path)),
            Kind::Other(what) => return Err(refuse(&path, what)),
            Kind::Link if is_proc_link(&path) => {
                // The kernel's link to an open file (`/dev/stdout`,
                // `/dev/fd/1`): its text (`pipe:[123]`, a file the shell
                // opened with `>>`) is no path to rename over; write into
                // what it is open on.
                let meta = fs::metadata(&path)
                    .map_err(|e| anyhow!("{}: {}", given.display(), describe_io(&e)))?;
                return match Kind::of(meta.file_type()) {
                    Kind::File | Kind::Stream => Ok(Dest::Stream(path)),
                    Kind::Other(what) => Err(refuse(&path, what)),
                    Kind::Link => Err(refuse(&path, "is not a file")),
                };
            }
            Kind::Link => {
                let target = fs::read_link(&path)
                    .map_err(|e| anyhow!("{}: {}", given.display(), describe_io(&e)))?;
                // A relative target is relative to the link's directory;
                // `join` keeps an absolute one as it is.
                path = path.parent().unwrap_or(Path::new("")).join(target);
            }
        }
    }
    Err(refuse(&path, "is behind too many symbolic links"))
}

/// What kind of node a path is, for [`destination`].
enum Kind {
    File,
    Link,
    /// A FIFO or a character device: written into, never renamed over.
    Stream,
    /// Refused: why.
    Other(&'static str),
}

impl Kind {
    fn of(t: fs::FileType) -> Kind {
        if t.is_file() {
            Kind::File
        } else if t.is_symlink() {
            Kind::Link
        } else if t.is_dir() {
            Kind::Other("is a directory")
        } else {
            Kind::special(t)
        }
    }

    #[cfg(unix)]
    fn special(t: fs::FileType) -> Kind {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() || t.is_char_device() {
            Kind::Stream
        } else if t.is_socket() {
            Kind::Other("is a socket")
        } else if t.is_block_device() {
            Kind::Other("is a block device")
        } else {
            Kind::Other("is not a file")
        }
    }

    #[cfg(not(unix))]
    fn special(_: fs::FileType) -> Kind {
        Kind::Other("is not a file")
    }
}

/// Whether `link` is in /proc (`/dev/stdout` leads to `/proc/self/fd/1`,
/// `/dev/fd` is `/proc/self/fd`): there, links name open files.
#[cfg(target_os = "linux")]
fn is_proc_link(link: &Path) -> bool {
    parent_dir(link)
        .canonicalize()
        .is_ok_and(|dir| dir.starts_with("/proc"))
}

#[cfg(not(target_os = "linux"))]
fn is_proc_link(_: &Path) -> bool {
    false
}

/// The directory `path` is in (`.` for a bare name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Replaces (or creates) the regular file `path` atomically: a temporary
/// file in its directory, renamed over it once complete, with the old
/// file's permissions, owner and group.
fn replace(path: &Path, old: Option<fs::Metadata>, text: &str) -> io::Result<()> {
    // Deleted when dropped, so on every error below.
    let mut tmp = tempfile::Builder::new()
        .prefix(".emcy-decode-")
        .suffix(".tmp")
        .tempfile_in(parent_dir(path))?;
    tmp.write_all(text.as_bytes())?;
    // A temporary file is private (0600); a baseline is an ordinary file.
    if let Some(perms) = old
        .as_ref()
        .map(fs::Metadata::permissions)
        .or_else(default_permissions)
    {
        tmp.as_file().set_permissions(perms)?;
    }
    if let Some(old) = &old {
        keep_owner(tmp.as_file(), old)?;
    }
    // On disk before the name points at it: after a crash the baseline is
    // the old one or the new one, never an empty file.
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Gives the new file the old one's owner and group before it takes its
/// name, so it never shows with another owner (root running `baseline -o`
/// over a user's file would otherwise make it root's). Only root may give
/// a file away, and a user only to a group of theirs: where the process may
/// not, the file stays the process's own, as a copy would.
#[cfg(unix)]
fn keep_owner(new: &fs::File, old: &fs::Metadata) -> io::Result<()> {
    use std::os::unix::fs::MetadataExt;
    let mine = new.metadata()?;
    if (mine.uid(), mine.gid()) == (old.uid(), old.gid()) {
        return Ok(());
    }
    match std::os::unix::fs::fchown(new, Some(old.uid()), Some(old.gid())) {
        Err(e) if e.kind() == io::ErrorKind::PermissionDenied => {
            // The group alone may still be ours to give (a user's shared
            // group), as `cp -p` keeps what it can.
            match std::os::unix::fs::fchown(new, None, Some(old.gid())) {
                Err(e) if e.kind() == io::ErrorKind::PermissionDenied => Ok(()),
                other => other,
            }
        }
        other => other,
    }
}

#[cfg(not(unix))]
fn keep_owner(_: &fs::File, _: &fs::Metadata) -> io::Result<()> {
    Ok(())
}

/// Writes into a FIFO or character device without replacing it.
fn stream(path: &Path, text: &str) -> io::Result<()> {
    // Appending never truncates: through `/dev/stdout`, a file the shell
    // opened with `>>` keeps what it had.
    let mut file = OpenOptions::new().append(true).open(path)?;
    // What was opened, not what was looked at: the path may have changed.
    if let Kind::Other(what) = Kind::of(file.metadata()?.file_type()) {
        return Err(io::Error::other(what));
    }
    match file.write_all(text.as_bytes()).and_then(|()| file.flush()) {
        // A reader that went away, as for stdout.
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(()),
        other => other,
    }
}

/// Refuses to write the baseline over a file it is made from (a trace or a
/// profile file given with it), which would be lost. Only a regular file
/// can be: a stream is written into, a new path is no input.
fn refuse_overwriting_inputs(out: &Path, read: &TraceArgs) -> Result<()> {
    if out.as_os_str() == "-" || !fs::metadata(out).is_ok_and(|m| m.is_file()) {
        return Ok(());
    }
    let traces = read.traces.iter().map(|p| (p, "a trace"));
    let profiles = read
        .reading
        .profile_file
        .iter()
        .map(|p| (p, "a profile file"));
    for (input, what) in traces.chain(profiles) {
        if input.as_os_str() != "-" && same_file(out, input) {
            let alias = if input == out {
                String::new()
            } else {
                format!(" (as {})", input.display())
            };
            bail!(
                "{} is also given as {what}{alias}; the baseline is not written over what it \
                 is made from",
                out.display()
            );
        }
    }
    Ok(())
}

/// Whether two paths are one file (through links, hard links too); a path
/// that cannot be read is no input to protect.
fn same_file(a: &Path, b: &Path) -> bool {
    same_file::is_same_file(a, b).unwrap_or(false)
}

#[cfg(unix)]
fn default_permissions() -> Option<Permissions> {
    use std::os::unix::fs::PermissionsExt;
    Some(Permissions::from_mode(0o644))
}

#[cfg(not(unix))]
fn default_permissions() -> Option<Permissions> {
    None
}

fn write_stdout(text: &str) -> Result<()> {
    super::write_stdout(text).map(|_| ())
}

/// `emcy-decode baseline TRACE... [-o FILE]`.
pub(super) fn baseline(args: &BaselineArgs) -> Result<ExitCode> {
    let out = args.output.as_deref().unwrap_or(Path::new("-"));
    // Refused before the traces are read, not after.
    destination(out)?;
    refuse_overwriting_inputs(out, &args.read)?;
    let reports = match read_traces(&args.read, "no baseline written")? {
        Ok(traces) => traces.reports,
        Err(unread) => return Ok(unread.status),
    };
    let mut record = Baseline::from_reports(&reports);
    record.options = args.read.reading.recorded()?;
    write_file(out, &record.to_json()?)?;
    Ok(ExitCode::from(EXIT_OK))
}

/// `emcy-decode check --baseline FILE TRACE...`.
pub(super) fn check(args: &CheckArgs) -> Result<ExitCode> {
    let name = args.baseline.display();
    // `-b -` reads a file named `-`, so `--update` writes that file, not
    // stdout.
    let path = if args.baseline.as_os_str() == "-" {
        Path::new(".").join("-")
    } else {
        args.baseline.clone()
    };
    let old = {
        // Dropped once parsed: the text of a big baseline is not kept while
        // the traces are read.
        let text = small_file::read_to_string(&path, baseline::MAX_BYTES, "a baseline")
            .map_err(|e| anyhow!("{name}: {}", describe_io(&e)))?;
        Baseline::from_json(&text).with_context(|| name.to_string())?
    };
    if args.update {
        destination(&path)?;
        refuse_overwriting_inputs(&path, &args.read)?;
    }
    let unwritten = if args.update {
        "nothing compared, the baseline left as it was"
    } else {
        "nothing compared"
    };
    let options = args.read.reading.recorded()?;
    // Traces decoded with other options decode to other things: comparing
    // them would report the options as regressions.
    if options != old.options && !args.update {
        bail!(
            "{name} was made with {}, this check reads with {}: give the same decoding \
             options (or --update to record these)",
            old.options,
            options
        );
    }
    let Traces { reports, seconds } = match read_traces(&args.read, unwritten)? {
        Ok(traces) => traces,
        Err(unread) => {
            // The CI job's test report must still parse and name the
            // trace that could not be read, not vanish with the run.
            if args.format == CheckFormat::Junit {
                write_stdout(&junit_unread(&unread.cases))?;
            }
            return Ok(unread.status);
        }
    };
    let mut new = Baseline::from_reports(&reports);
    new.options = options;
    // Only the traces given: the others are neither compared nor dropped.
    let mut old = old;
    let mut kept = BTreeMap::new();
    if args.only_given {
        let (given, other) = std::mem::take(&mut old.traces)
            .into_iter()
            .partition(|(key, _)| new.traces.contains_key(key));
        old.traces = given;
        kept = other;
    }
    let allow = Allow {
        codes: args.allow.iter().copied().collect(),
        nodes: args.allow_node.iter().copied().collect(),
    };
    let diff = compare(&old, &new, &allow);
    let out = match args.format {
        CheckFormat::Text => diff.text(),
        CheckFormat::Json => diff.json()?,
        CheckFormat::Junit => {
            // Every trace given or recorded: one test case each.
            let traces: std::collections::BTreeSet<&str> = old
                .traces
                .keys()
                .chain(new.traces.keys())
                .map(String::as_str)
                .collect();
            diff.junit(traces, |trace| seconds.get(trace).copied())
        }
        CheckFormat::Github => diff.github(),
    };
    write_stdout(&out)?;
    // No key in common: most likely keys relative to another directory.
    if let (Some(recorded), Some(given)) = (old.traces.keys().next(), new.traces.keys().next())
        && !new.traces.keys().any(|k| old.traces.contains_key(k))
    {
        // A stderr that cannot take a note loses it, never the exit code.
        let _ = writeln!(
            io::stderr(),
            "check: no trace matched the baseline: it records traces by their path relative \
             to where it was made ('{}'), this run gave '{}'; run check from that directory or \
             give both the same --root DIR",
            emcy_decode::text::printable(recorded),
            emcy_decode::text::printable(given)
        );
    }
    if args.update {
        new.traces.extend(kept);
        write_file(&path, &new.to_json()?)?;
        let _ = writeln!(io::stderr(), "check: wrote {name}");
        return Ok(ExitCode::from(EXIT_OK));
    }
    let code = if diff.summary.regressions > 0 {
        EXIT_FAIL_ON
    } else {
        EXIT_OK
    };
    Ok(ExitCode::from(code))
}
