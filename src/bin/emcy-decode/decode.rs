//! `emcy-decode [FILE]...`: decode traces into the chosen report. Here is
//! the policy the library leaves to the application: which renderer, live
//! or finite reading, how many threads, small files side by side, progress
//! bars, and the exit code from the inputs and `--fail-on`.

use std::io::{self, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use globset::{Glob, GlobSet, GlobSetBuilder};

use super::cli::{ColorChoice, DecodeArgs, OutputFormat, Show, View};
use super::{EXIT_ERROR, EXIT_FAIL_ON, EXIT_OK, signals};
use emcy_decode::analyze::fail_on::{self, FailOn, Tally};
use emcy_decode::analyze::{
    self, Analysis, DiagnosticLog, InputReport, Options, OutputError, Reading, Sink, WithoutEvents,
    batch,
};
use emcy_decode::canopen::NodeId;
use emcy_decode::report::csv::Csv;
use emcy_decode::report::html::HtmlReport;
use emcy_decode::report::json::JsonDocument;
use emcy_decode::report::ndjson::Ndjson;
use emcy_decode::report::svg::SvgReport;
use emcy_decode::report::table::TableReport;
use emcy_decode::trace::cancel::Cancel;
use emcy_decode::trace::detect;
use emcy_decode::trace::input::{self, ReadMode, Source};

/// Reads every input into the chosen renderer; the exit code is the worst
/// of all inputs.
/// What to say on stderr when there is no FILE and stdin is a terminal: the
/// run waits for typed or pasted lines, which looks like a hang to someone
/// who forgot the file.
fn stdin_prompt(no_files: bool, stdin_is_terminal: bool, quiet: bool) -> Option<&'static str> {
    (no_files && stdin_is_terminal && !quiet).then_some(
        "reading a trace from stdin (no FILE given); end it with Ctrl-D, or stop with Ctrl-C",
    )
}

pub(super) fn run(args: &DecodeArgs) -> Result<ExitCode> {
    let mut opts = args.options()?;
    // A gate with a filter that selects nothing fails with one error line
    // that says what the input has, instead of a note beside it.
    opts.unmatched_filter_fails = FailOn::combine(&args.fail_on) != FailOn::default();
    // Before any input is read: an unknown --tz is a usage error.
    let time_style = args.time_style()?;
    let walk = Walk::new(args.recursive, args.follow_links, &args.glob)?;
    let mut log = DiagnosticLog::new(io::stderr());
    log.quiet = args.quiet;
    let inputs = walk.expand(&args.files, &opts.cancel, &mut log);
    if let Some(prompt) = stdin_prompt(args.files.is_empty(), io::stdin().is_terminal(), args.quiet)
    {
        log.note(prompt);
    }
    if args.follow && !matches!(inputs.as_slice(), [Input::Source(Source::Path(_))]) {
        anyhow::bail!("--follow takes exactly one FILE (not stdin, not a directory)");
    }
    let caught = signals::catch(&opts.cancel);
    // Reading a live stream (`candump -L can0 | emcy-decode -`, a FIFO
    // candump writes into, a followed file): each event must show up when
    // its line arrives, not when a buffer fills.
    let live = args.follow
        || match inputs.as_slice() {
            [Input::Source(Source::Stdin)] => input::stdin_is_stream(),
            [Input::Source(Source::Path(path))] => input::is_stream(path),
            _ => false,
        };
    let mode = if args.follow {
        ReadMode::Follow
    } else if live {
        ReadMode::Live
    } else {
        ReadMode::Finite
    };
    let out = io::BufWriter::with_capacity(64 * 1024, report_stdout());
    let summary = args.view == View::Summary;
    // Threads for the node objects at the end: -j, or every core.
    let report_threads = if args.threads > 0 {
        args.threads
    } else {
        cores()
    };
    let mut renderer: Box<dyn Sink> = match args.format {
        OutputFormat::Table => {
            let no_color = std::env::var_os("NO_COLOR");
            let term = std::env::var_os("TERM");
            let color = use_color(
                args.color,
                io::stdout().is_terminal(),
                no_color.as_deref(),
                term.as_deref(),
            );
            let width = table_width(
                args.width,
                io::stdout().is_terminal(),
                std::env::var_os("COLUMNS").as_deref(),
                || terminal_size::terminal_size().map(|(w, _)| usize::from(w.0)),
            );
            let table = TableReport::new(out, color, live)
                .time_style(time_style)
                .fit_width(width);
            let table = if summary { table.summary_only() } else { table };
            let table = if args.show.contains(&Show::Sdo) {
                table.show_sdo()
            } else {
                table
            };
            // A live table shows each input's header as it starts.
            if live {
                Box::new(table)
            } else {
                Box::new(OnlyWhatWasRead::new(table))
            }
        }
        OutputFormat::Json if summary => Box::new(WithoutEvents(JsonDocument::new(out))),
        OutputFormat::Json => Box::new(JsonDocument::new(out)),
        OutputFormat::Ndjson if summary => Box::new(WithoutEvents(
            Ndjson::new(out, live).threads(report_threads),
        )),
        OutputFormat::Ndjson => Box::new(Ndjson::new(out, live).threads(report_threads)),
        OutputFormat::Csv => Box::new(Csv::new(out, summary, live)),
        OutputFormat::Svg => Box::new(SvgReport::new(out)),
        OutputFormat::Html => Box::new(HtmlReport::new(out)),
    };
    let how = HowToRead {
        threads: args.threads,
        timing: opts.timing,
        live,
        mode,
        progress: progress_allowed(
            args.quiet,
            io::stderr().is_terminal(),
            std::env::var_os("CI").as_deref(),
        ),
        verbose: args.verbose,
    };

    let result = decode_all(&inputs, &opts, how, renderer.as_mut(), &mut log);
    let code = match result {
        Ok(outcome) => exit_code(args, &outcome, &mut log),
        // The reader of our output went away (`| head -1`): not an error.
        Err(OutputError(e)) if e.kind() == io::ErrorKind::BrokenPipe => EXIT_OK,
        Err(OutputError(e)) => {
            log.error(&format!("writing output: {e}"));
            EXIT_ERROR
        }
    };
    if let Some(stop) = caught.stopped() {
        log.note(&format!(
            "interrupted: the report covers what was read before {}",
            stop.name
        ));
        return Ok(ExitCode::from(stop.status));
    }
    Ok(ExitCode::from(code))
}

/// The table of inputs that could not be read: nothing. An input that
/// could not be opened, or in which no frame was found (a binary file, a
/// wrong format), gets its `error:` line on stderr and no header or table of
/// zeros on stdout; when no input was read the Inputs table goes too, so the
/// error is all there is to read.
struct OnlyWhatWasRead<R> {
    inner: R,
    /// The input begun but not passed on until it shows it has something.
    pending: Option<String>,
}

impl<R: Sink> OnlyWhatWasRead<R> {
    fn new(inner: R) -> Self {
        OnlyWhatWasRead {
            inner,
            pending: None,
        }
    }

    fn begin_pending(&mut self) -> io::Result<()> {
        match self.pending.take() {
            Some(file) => self.inner.begin_input(&file),
            None => Ok(()),
        }
    }
}

/// An input with an error and no frame read: nothing to show but the error.
fn unread(input: &InputReport) -> bool {
    input.error.is_some() && input.counts.frames == 0
}

impl<R: Sink> Sink for OnlyWhatWasRead<R> {
    fn begin_input(&mut self, file: &str) -> io::Result<()> {
        self.begin_pending()?;
        self.pending = Some(file.to_string());
        Ok(())
    }
    fn emcy(&mut self, event: &analyze::EmcyEvent<'_>) -> io::Result<()> {
        self.begin_pending()?;
        self.inner.emcy(event)
    }
    fn boot(&mut self, event: &analyze::BootEvent<'_>) -> io::Result<()> {
        self.begin_pending()?;
        self.inner.boot(event)
    }
    fn health(&mut self, event: &analyze::HealthEvent<'_>) -> io::Result<()> {
        self.begin_pending()?;
        self.inner.health(event)
    }
    fn bus(&mut self, event: &analyze::BusEvent<'_>) -> io::Result<()> {
        self.begin_pending()?;
        self.inner.bus(event)
    }
    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        if unread(input) {
            self.pending = None;
            return Ok(());
        }
        self.begin_pending()?;
        self.inner.end_input(input)
    }
    fn finish(
        &mut self,
        inputs: &[InputReport],
        diagnostics: &[analyze::Diagnostic],
    ) -> io::Result<()> {
        self.begin_pending()?;
        if inputs.iter().all(unread) {
            return Ok(());
        }
        self.inner.finish(inputs, diagnostics)
    }
}

/// Standard output for a report, written in 64 KiB chunks by the caller's
/// buffer. Std's stdout puts a line buffer behind that, which searches every
/// chunk for its last newline (2% of a run that prints an event for 30% of
/// the lines); on Unix the descriptor is duplicated and written directly.
fn report_stdout() -> Box<dyn Write> {
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        if let Ok(fd) = io::stdout().as_fd().try_clone_to_owned() {
            return Box::new(std::fs::File::from(fd));
        }
    }
    Box::new(io::stdout().lock())
}

/// One input of the run, in argument order.
#[derive(Debug, PartialEq, Eq)]
pub(super) enum Input {
    Source(Source),
    /// A part of a `--recursive` directory that could not be listed (an
    /// unreadable subdirectory, a path too long): reported like a file that
    /// cannot be opened, while everything else is still read.
    Unlisted {
        name: String,
        error: String,
    },
}

/// How FILE arguments become inputs: `-r`, `-L` and the `--glob` patterns.
pub(super) struct Walk {
    recursive: bool,
    /// `-L`: symbolic links under a directory are followed (walkdir stops
    /// at a loop); without it they are named in a note, as ripgrep and
    /// find leave them by default.
    follow_links: bool,
    /// Files under a directory are read when they match one of these (or
    /// there are none)...
    include: Option<GlobSet>,
    /// ...and none of these (`--glob '!*.py'`, as in ripgrep).
    exclude: Option<GlobSet>,
    /// The patterns as given, for the error of a directory none selects.
    globs: Vec<String>,
}

/// How many names a note names; the count is always exact.
const SKIPPED_NAMED: usize = 3;

/// What walking one directory left out, for its notes and, when nothing
/// was left to read, its error.
#[derive(Default)]
struct LeftOut {
    /// Files no `--glob` selects (counted only: usually most of them).
    unselected: usize,
    /// Files with no known format in their first lines.
    no_trace: Vec<String>,
    /// Symbolic links not followed (no `-L`).
    links: Vec<String>,
    /// With `-L`: links back to a directory above them, not followed again.
    loops: Vec<String>,
    /// With `-L`: files read already under another path.
    twice: Vec<String>,
}

impl Walk {
    pub(super) fn new(recursive: bool, follow_links: bool, globs: &[String]) -> Result<Walk> {
        let mut include = GlobSetBuilder::new();
        let mut exclude = GlobSetBuilder::new();
        let (mut includes, mut excludes) = (0, 0);
        for pattern in globs {
            let (set, n, text) = match pattern.strip_prefix('!') {
                Some(rest) => (&mut exclude, &mut excludes, rest),
                None => (&mut include, &mut includes, pattern.as_str()),
            };
            let glob =
                Glob::new(text).map_err(|e| anyhow::anyhow!("--glob '{pattern}': {}", e.kind()))?;
            set.add(glob);
            *n += 1;
        }
        let build = |b: GlobSetBuilder, n: usize| -> Result<Option<GlobSet>> {
            Ok(if n == 0 { None } else { Some(b.build()?) })
        };
        Ok(Walk {
            recursive,
            follow_links,
            include: build(include, includes)?,
            exclude: build(exclude, excludes)?,
            globs: globs.to_vec(),
        })
    }

    /// `path` (relative to the directory walked) passes the `--glob`s.
    fn selects(&self, path: &Path) -> bool {
        self.include.as_ref().is_none_or(|g| g.is_match(path)) && !self.excludes(path)
    }

    fn excludes(&self, path: &Path) -> bool {
        self.exclude.as_ref().is_some_and(|g| g.is_match(path))
    }

    /// Whether a link not followed is worth naming: one to a file the
    /// `--glob`s would select (or a dangling one they would), one to a
    /// directory no `!GLOB` excludes (what is in it is unknown).
    fn names_link(&self, relative: &Path, path: &Path) -> bool {
        match std::fs::metadata(path) {
            Ok(meta) if meta.is_dir() => !self.excludes(relative),
            _ => self.selects(relative),
        }
    }

    /// FILE arguments to inputs: `-` is stdin, none is stdin; a directory
    /// is walked with `--recursive` (its files in name order, those
    /// `--glob` selects, files that are no trace skipped with one note per
    /// directory, symbolic links followed with `-L` and otherwise named in
    /// a note) and otherwise an error that names `-r`. A directory that
    /// yields no trace is an error that says why, so a `--glob` with a typo
    /// cannot pass a CI step by reading nothing.
    pub(super) fn expand(
        &self,
        files: &[PathBuf],
        cancel: &Cancel,
        log: &mut DiagnosticLog<io::Stderr>,
    ) -> Vec<Input> {
        if files.is_empty() {
            return vec![Input::Source(Source::Stdin)];
        }
        let mut inputs = Vec::new();
        for f in files {
            if !f.is_dir() {
                inputs.push(Input::Source(Source::from_arg(f)));
                continue;
            }
            if !self.recursive {
                inputs.push(Input::Unlisted {
                    name: f.display().to_string(),
                    error: "is a directory; -r (--recursive) reads the traces in it".into(),
                });
                continue;
            }
            let before = inputs.len();
            let left = self.walk(f, cancel, &mut inputs);
            for note in left.notes(f) {
                log.note(&note);
            }
            if inputs.len() == before {
                inputs.push(Input::Unlisted {
                    name: f.display().to_string(),
                    error: left.why_nothing(&self.globs),
                });
            }
        }
        inputs
    }

    /// The inputs under the directory `dir`, pushed in name order, and what
    /// was left out.
    fn walk(&self, dir: &Path, cancel: &Cancel, inputs: &mut Vec<Input>) -> LeftOut {
        let mut left = LeftOut::default();
        // With -L, the files read so far (device and inode), so a file two
        // links reach is read once.
        let mut seen = std::collections::HashSet::new();
        let walker = walkdir::WalkDir::new(dir)
            .follow_links(self.follow_links)
            .sort_by_file_name();
        for entry in walker {
            let entry = match entry {
                Ok(entry) => entry,
                Err(e) => {
                    let name = e.path().unwrap_or(dir);
                    match e.loop_ancestor() {
                        // Every file was read on the way down: nothing is
                        // lost by not going round again.
                        Some(_) => left.loops.push(shown(name)),
                        None => inputs.push(Input::Unlisted {
                            name: name.display().to_string(),
                            error: match e.io_error() {
                                Some(io) => analyze::describe_io(io),
                                None => e.to_string(),
                            },
                        }),
                    }
                    continue;
                }
            };
            let relative = entry.path().strip_prefix(dir).unwrap_or(entry.path());
            // The directory given may itself be a link: it was asked for.
            if entry.depth() > 0 && entry.path_is_symlink() && !self.follow_links {
                if self.names_link(relative, entry.path()) {
                    left.links.push(shown(entry.path()));
                }
                continue;
            }
            if !entry.file_type().is_file() {
                continue;
            }
            if !self.selects(relative) {
                left.unselected += 1;
                continue;
            }
            if self.follow_links && file_id(&entry).is_some_and(|id| !seen.insert(id)) {
                left.twice.push(shown(entry.path()));
                continue;
            }
            let source = Source::Path(entry.into_path());
            if is_no_trace(&source, cancel) {
                left.no_trace.push(source.display_name());
            } else {
                inputs.push(Input::Source(source));
            }
        }
        left
    }
}

/// A path under a walked directory as a note shows it: as the files read
/// are named, the directory given included.
fn shown(path: &Path) -> String {
    path.display().to_string()
}

/// The file an entry is (its device and inode), links followed.
#[cfg(unix)]
fn file_id(entry: &walkdir::DirEntry) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    entry.metadata().ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn file_id(_: &walkdir::DirEntry) -> Option<(u64, u64)> {
    None
}

/// A file under a `-r` directory with no known format in its first lines
/// (a script, a profile, a README). One that cannot be opened or read is
/// kept, so its error is reported as for any input.
fn is_no_trace(source: &Source, cancel: &Cancel) -> bool {
    input::open(source, ReadMode::Finite, cancel)
        .and_then(|opened| detect::looks_like_trace(opened.reader))
        .is_ok_and(|trace| !trace)
}

impl LeftOut {
    /// One note per kind of thing left out: `DIR: skipped 5 files that are
    /// no trace (no known format in the first lines): a.py, b.toml, c.md,
    /// ...`, `DIR: skipped 1 symbolic link (-L follows it): DIR/latest.log`.
    fn notes(&self, dir: &Path) -> Vec<String> {
        let kinds: [(&[String], &str, &str, &str); 4] = [
            (
                &self.no_trace,
                "file",
                "that {is} no trace (no known format in the first lines)",
                "skipped",
            ),
            (
                &self.links,
                "symbolic link",
                "(-L follows {them})",
                "skipped",
            ),
            (
                &self.loops,
                "symbolic link",
                "that point{s} back to a directory above {it}, a loop (the files there were \
                 read once)",
                "did not follow",
            ),
            (
                &self.twice,
                "file",
                "that links reach again (read once, under {its} first path)",
                "skipped",
            ),
        ];
        kinds
            .into_iter()
            .filter(|(names, ..)| !names.is_empty())
            .map(|(names, noun, why, verb)| {
                let one = names.len() == 1;
                let why = why
                    .replace("{is}", if one { "is" } else { "are" })
                    .replace("{it}", if one { "it" } else { "them" })
                    .replace("{its}", if one { "its" } else { "their" })
                    .replace("{them}", if one { "it" } else { "them" })
                    .replace("{s}", if one { "s" } else { "" });
                format!(
                    "{}: {verb} {} {why}: {}",
                    dir.display(),
                    counted(names.len(), noun),
                    named(names)
                )
            })
            .collect()
    }

    /// Why a directory gave no trace to read: `no trace under it (3 files
    /// not selected by --glob '*.lgo')`.
    fn why_nothing(&self, globs: &[String]) -> String {
        let mut why = Vec::new();
        if self.unselected > 0 {
            let patterns: Vec<String> = globs.iter().map(|g| format!("--glob '{g}'")).collect();
            why.push(format!(
                "{} not selected by {}",
                counted(self.unselected, "file"),
                patterns.join(" ")
            ));
        }
        if !self.no_trace.is_empty() {
            why.push(format!(
                "{} with no known format",
                counted(self.no_trace.len(), "file")
            ));
        }
        if !self.links.is_empty() {
            why.push(format!(
                "{} not followed without -L",
                counted(self.links.len(), "symbolic link")
            ));
        }
        if why.is_empty() {
            why.push("no file in it".into());
        }
        format!("no trace under it ({})", why.join(", "))
    }
}

/// `1 file`, `3 files`.
fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// The first [`SKIPPED_NAMED`] names, `, ...` when there are more.
fn named(names: &[String]) -> String {
    let first = names.get(..SKIPPED_NAMED).unwrap_or(names);
    let more = if names.len() > first.len() {
        ", ..."
    } else {
        ""
    };
    format!("{}{more}", first.join(", "))
}

/// What all inputs amounted to, in argument order (inputs that could not
/// be opened included, with their error).
struct Outcome {
    reports: Vec<InputReport>,
    /// What `--fail-on` needs beside the reports.
    tally: Tally,
}

/// How inputs are read.
#[derive(Clone, Copy)]
struct HowToRead {
    /// `-j N`; 0 = automatic.
    threads: usize,
    /// `--timing` (or `--bitrate`): automatic gives a big input a worker more.
    timing: bool,
    /// A live stream: events must not wait for a block to fill.
    live: bool,
    mode: ReadMode,
    /// A progress bar for big files is allowed (stderr is a terminal, not
    /// CI, not --quiet).
    progress: bool,
    /// `--verbose`: say how each input was read.
    verbose: bool,
}

/// `--verbose`'s note on how `file` was read.
fn reading_note(file: &str, r: &Reading) -> String {
    if r.workers == 0 {
        return format!("{file}: read on one thread");
    }
    let mut note = format!(
        "{file}: {} blocks parsed by {} worker threads; read again in order: {} whole, {} from \
         a frame that widened the decoded ids",
        r.blocks, r.workers, r.blocks_read_again, r.rests_read_again
    );
    if r.fell_back {
        note.push_str("; that came so often that the rest was read on one thread");
    }
    note
}

/// Inputs below this size are read on one thread: starting workers costs
/// more than it saves. Several of them are read side by side instead.
const PARALLEL_MIN_BYTES: u64 = 16 * 1024 * 1024;

/// Files from this size get a progress bar (when allowed).
const PROGRESS_MIN_BYTES: u64 = 50 * 1024 * 1024;

/// Worker threads for one input by its size: all cores for big files and
/// gzip (its decompression runs beside the parsing), one for small ones.
///
/// With `--timing` (`timing`), a big input gets one worker more than there
/// are cores. The thread that keeps the timelines then does a quarter of the
/// work (every frame's interval and load), and a worker waits for its blocks
/// to come back while that thread waits for another worker's block: with as
/// many workers as cores, a core stood idle for a third of the run. One more
/// worker fills it (2 cores, 512 MiB bus traces: commissioning 307 -> 277 ms,
/// segmented firmware 293 -> 269 ms); the default path is not helped by it
/// (one worker more cost it 5%).
pub(super) fn auto_threads(opened: &input::Opened, timing: bool) -> usize {
    let big = opened.gzip || opened.size.is_some_and(|s| s >= PARALLEL_MIN_BYTES);
    if big {
        cores() + usize::from(timing)
    } else {
        1
    }
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get().min(8))
}

impl HowToRead {
    fn threads_for(self, opened: &input::Opened) -> usize {
        if self.threads > 0 {
            return self.threads;
        }
        if self.live {
            return 1;
        }
        auto_threads(opened, self.timing)
    }

    /// Whether a source is small enough to be read beside others.
    fn side_by_side(self, source: &Source) -> bool {
        match source {
            Source::Stdin => false,
            Source::Path(p) => {
                !self.live
                    && std::fs::metadata(p)
                        .is_ok_and(|m| m.is_file() && m.len() < PARALLEL_MIN_BYTES)
            }
        }
    }
}

fn decode_all(
    inputs: &[Input],
    opts: &Options,
    how: HowToRead,
    renderer: &mut dyn Sink,
    log: &mut DiagnosticLog<io::Stderr>,
) -> Result<Outcome, OutputError> {
    let mut analyses = Vec::new();
    let workers = if how.threads > 0 {
        how.threads
    } else {
        cores()
    };
    let mut i = 0;
    while i < inputs.len() && !opts.cancel.is_cancelled() {
        // A run of small files: side by side, replayed in order.
        let run: Vec<Source> = inputs[i..]
            .iter()
            .map_while(|input| match input {
                Input::Source(s) if how.side_by_side(s) => Some(s.clone()),
                _ => None,
            })
            .collect();
        if run.len() >= 2 && workers >= 2 {
            batch::run_parallel(&run, opts, workers, log.quiet, |result| {
                analyses.extend(result.replay(renderer, log)?);
                Ok(())
            })?;
            i += run.len();
            continue;
        }
        let source = match &inputs[i] {
            Input::Source(source) => source,
            Input::Unlisted { name, error } => {
                log.error(&format!("{name}: {error}"));
                analyses.push(Analysis::unopened(name.clone(), error.clone()));
                i += 1;
                continue;
            }
        };
        i += 1;
        let mut bar = None;
        let analysis = analyze::analyze_source(
            source,
            how.mode,
            opts,
            |opened| how.threads_for(opened),
            |opened, reader| match progress_bar(how, opened.size.filter(|_| !opened.gzip)) {
                Some(b) => Box::new(bar.insert(b).wrap_read(reader)),
                None => reader,
            },
            renderer,
            log,
        );
        if let Some(bar) = bar {
            bar.finish_and_clear();
        }
        let analysis = analysis?;
        if how.verbose {
            log.note(&reading_note(&analysis.report.file, &analysis.reading));
        }
        analyses.push(analysis);
    }
    let mut tally = Tally::default();
    let reports: Vec<InputReport> = analyses
        .into_iter()
        .map(|a| {
            tally.add(&a);
            a.report
        })
        .collect();
    renderer
        .finish(&reports, &log.collected)
        .map_err(OutputError)?;
    Ok(Outcome { reports, tally })
}

/// A bar on stderr for a big regular file, counting the bytes read (after
/// gzip: the uncompressed size is unknown, so gzip files get none).
fn progress_bar(how: HowToRead, size: Option<u64>) -> Option<indicatif::ProgressBar> {
    let size = size.filter(|&s| wants_progress(how.progress, s))?;
    let bar = indicatif::ProgressBar::new(size);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {bytes}/{total_bytes} {bytes_per_sec}{eta}",
    ) {
        bar.set_style(style.with_key(
            "eta",
            |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                if eta_is_known(state.elapsed(), state.fraction()) {
                    let _ = write!(w, " eta {}", indicatif::HumanDuration(state.eta()));
                }
            },
        ));
    }
    Some(bar)
}

/// Whether the rate seen so far predicts the end: the first blocks are
/// read while the disk cache and the threads warm up, and an estimate from
/// them said "eta 31h" for a file read in a minute. So the bar shows an
/// estimate only after a second and a twentieth of the file.
fn eta_is_known(elapsed: std::time::Duration, fraction: f32) -> bool {
    elapsed >= std::time::Duration::from_secs(1) && fraction >= 0.05
}

/// Progress bars only for a person at a terminal: not with --quiet, not
/// into a pipe or file, not in CI (`CI` set and not empty).
fn progress_allowed(quiet: bool, stderr_is_terminal: bool, ci: Option<&std::ffi::OsStr>) -> bool {
    !quiet && stderr_is_terminal && ci.is_none_or(|v| v.is_empty())
}

/// A progress bar only where someone watches: allowed (terminal, not CI,
/// not --quiet) and a file big enough to wait for.
fn wants_progress(allowed: bool, size: u64) -> bool {
    allowed && size >= PROGRESS_MIN_BYTES
}

fn exit_code(args: &DecodeArgs, outcome: &Outcome, log: &mut DiagnosticLog<io::Stderr>) -> u8 {
    let reports = outcome.reports.iter();
    let input_failed = reports.clone().any(|r| r.error.is_some());
    let (malformed, invalid) = reports.fold((0, 0), |(m, i), r| {
        (m + r.counts.malformed, i + r.counts.emcy_invalid)
    });
    let strict_failed = args.strict && malformed + invalid > 0;
    if strict_failed {
        log.error(&format!(
            "--strict: {malformed} malformed line{} and {invalid} EMCY frame{} too short \
             to decode",
            if malformed == 1 { "" } else { "s" },
            if invalid == 1 { "" } else { "s" },
        ));
    }
    if input_failed || strict_failed {
        return EXIT_ERROR;
    }
    let fail_on = FailOn::combine(&args.fail_on);
    let gate = fail_on != FailOn::default();
    if let Some(problem) = filter_problem(&args.node, &args.channel, gate, &outcome.reports) {
        log.error(&problem);
        return EXIT_ERROR;
    }
    if let Some(bound) = fail_on.category_at_most {
        let nodes = || outcome.reports.iter().flat_map(|r| &r.nodes);
        if !nodes().any(|n| n.profile.has_categories()) {
            let mut names: Vec<&str> = nodes().map(|n| n.profile.name()).collect();
            names.sort_unstable();
            names.dedup();
            log.note(&format!(
                "fail-on: category<={bound} can never be met: no node's profile gives \
                 error categories{}",
                if names.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", names.join(", "))
                }
            ));
        }
    }
    let met = fail_on::met(&fail_on, &outcome.tally, &outcome.reports);
    for reason in &met {
        log.note(&format!("fail-on: {reason}"));
    }
    if met.is_empty() {
        EXIT_OK
    } else {
        EXIT_FAIL_ON
    }
}

/// What makes `--node`/`--channel` a usage error once the inputs are read:
/// a node over 127 where no input holds EtherCAT (only station addresses go
/// that high, so it is a typo that would select nothing), or, under a
/// `--fail-on` gate, filters that selected no node of any input. Such a run
/// checked nothing, and a CI gate must not turn green on it.
fn filter_problem(
    nodes: &[NodeId],
    channels: &[String],
    gate: bool,
    reports: &[InputReport],
) -> Option<String> {
    let ethercat = reports.iter().any(|r| r.counts.ethercat_frames > 0);
    if let Some(n) = nodes.iter().find(|&&n| n > 127)
        && !ethercat
    {
        return Some(format!(
            "--node {n} is no CANopen node id (1-127) and no input holds EtherCAT, whose \
             station addresses go higher"
        ));
    }
    let filtered = !nodes.is_empty() || !channels.is_empty();
    if gate && filtered && reports.iter().all(|r| r.nodes.is_empty()) {
        if let [only] = reports
            && let Some(note) = &only.unmatched
        {
            return Some(format!("{}: {note}; --fail-on checked nothing", only.file));
        }
        let mut given = Vec::new();
        if !nodes.is_empty() {
            let list: Vec<String> = nodes.iter().map(ToString::to_string).collect();
            given.push(format!("--node {}", list.join(",")));
        }
        if !channels.is_empty() {
            given.push(format!("--channel {}", channels.join(",")));
        }
        // Of several inputs the first that names what it has instead.
        let example = reports
            .iter()
            .find_map(|r| Some(format!(" (first: {}: {})", r.file, r.unmatched.as_ref()?)))
            .unwrap_or_default();
        return Some(format!(
            "{} matches no node in the input{}, so --fail-on checked nothing{example}",
            given.join(" "),
            if reports.len() == 1 { "" } else { "s" }
        ));
    }
    None
}

/// The width to fit the table to: `--width` (0: none), else at a terminal
/// `COLUMNS` (as shells export it; a resized window updates it), else the
/// terminal's size; in a pipe none, so scripts get full lines. The size is
/// asked of the `terminal_size` crate, already built for clap's help.
fn table_width(
    flag: Option<usize>,
    is_terminal: bool,
    columns: Option<&std::ffi::OsStr>,
    terminal: impl FnOnce() -> Option<usize>,
) -> Option<usize> {
    match flag {
        Some(0) => None,
        Some(n) => Some(n),
        None if !is_terminal => None,
        None => columns
            .and_then(|c| c.to_str())
            .and_then(|c| c.trim().parse::<usize>().ok())
            .filter(|&c| c > 0)
            .or_else(terminal),
    }
}

/// Whether to colour: `--color always|never`, or auto = a terminal, no
/// (non-empty) `NO_COLOR` (per no-color.org) and a `TERM` that is not
/// `dumb`: a dumb terminal (Emacs' shell, some CI consoles) prints escape
/// codes as text, and ripgrep does not colour there either.
fn use_color(
    choice: ColorChoice,
    is_terminal: bool,
    no_color: Option<&std::ffi::OsStr>,
    term: Option<&std::ffi::OsStr>,
) -> bool {
    match choice {
        ColorChoice::Always => true,
        ColorChoice::Never => false,
        ColorChoice::Auto => {
            is_terminal && no_color.is_none_or(|v| v.is_empty()) && term != Some("dumb".as_ref())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsStr;

    #[test]
    fn timing_gives_a_big_input_one_worker_more_than_cores() {
        let opened = |gzip, size| input::Opened {
            reader: Box::new(io::empty()),
            gzip,
            size,
        };
        let big = opened(false, Some(PARALLEL_MIN_BYTES));
        assert_eq!(auto_threads(&big, false), cores());
        assert_eq!(auto_threads(&big, true), cores() + 1);
        assert_eq!(auto_threads(&opened(true, None), true), cores() + 1);
        // Small inputs stay on one thread, timed or not.
        let small = opened(false, Some(PARALLEL_MIN_BYTES - 1));
        assert_eq!(auto_threads(&small, false), 1);
        assert_eq!(auto_threads(&small, true), 1);
        assert_eq!(auto_threads(&opened(false, None), true), 1);
    }

    #[test]
    fn the_stdin_prompt_only_at_a_terminal_without_files_and_quiet() {
        assert!(stdin_prompt(true, true, false).is_some_and(|p| p.contains("Ctrl-D")));
        assert_eq!(stdin_prompt(false, true, false), None, "a FILE given");
        assert_eq!(stdin_prompt(true, false, false), None, "a pipe");
        assert_eq!(stdin_prompt(true, true, true), None, "--quiet");
    }

    /// Records what reaches the table.
    #[derive(Default)]
    struct Seen(Vec<String>);

    impl Sink for Seen {
        fn begin_input(&mut self, file: &str) -> io::Result<()> {
            self.0.push(format!("begin {file}"));
            Ok(())
        }
        fn emcy(&mut self, _: &analyze::EmcyEvent<'_>) -> io::Result<()> {
            self.0.push("emcy".into());
            Ok(())
        }
        fn boot(&mut self, _: &analyze::BootEvent<'_>) -> io::Result<()> {
            self.0.push("boot".into());
            Ok(())
        }
        fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
            self.0.push(format!("end {}", input.file));
            Ok(())
        }
        fn finish(&mut self, inputs: &[InputReport], _: &[analyze::Diagnostic]) -> io::Result<()> {
            self.0.push(format!("finish {}", inputs.len()));
            Ok(())
        }
    }

    #[test]
    fn inputs_that_could_not_be_read_leave_the_table_empty() {
        let report = |file: &str, error: Option<&str>, frames: u64| {
            let mut r = read_input(0);
            r.file = file.into();
            r.error = error.map(str::to_string);
            r.counts.frames = frames;
            r
        };
        let unreadable = report("bin", Some("cannot detect the trace format"), 0);
        let mut only = OnlyWhatWasRead::new(Seen::default());
        only.begin_input("bin").unwrap();
        only.end_input(&unreadable).unwrap();
        only.finish(std::slice::from_ref(&unreadable), &[]).unwrap();
        assert!(only.inner.0.is_empty(), "{:?}", only.inner.0);

        // Beside a trace that was read, the unread input is in the Inputs
        // table only; a trace that broke off part way keeps its header.
        let good = report("good", None, 4);
        let cut = report("cut", Some("gzip stream corrupt"), 2);
        let mut only = OnlyWhatWasRead::new(Seen::default());
        for r in [&unreadable, &good, &cut] {
            only.begin_input(&r.file).unwrap();
            only.end_input(r).unwrap();
        }
        only.finish(&[unreadable, good, cut], &[]).unwrap();
        assert_eq!(
            only.inner.0,
            ["begin good", "end good", "begin cut", "end cut", "finish 3"]
        );
    }

    /// A read input without nodes; `ethercat` frames in it or not.
    fn read_input(ethercat: u64) -> InputReport {
        let mut report = Analysis::unopened("t.log".into(), String::new()).report;
        report.error = None;
        report.counts.ethercat_frames = ethercat;
        report
    }

    #[test]
    fn a_node_over_127_needs_ethercat_in_the_input() {
        let can = [read_input(0)];
        let problem = filter_problem(&[5, 200], &[], false, &can).expect("200 on CAN");
        assert!(
            problem.starts_with("--node 200 is no CANopen node id"),
            "{problem}"
        );
        assert_eq!(filter_problem(&[127], &[], false, &can), None);
        let mixed = [read_input(0), read_input(3)];
        assert_eq!(filter_problem(&[200], &[], false, &mixed), None);
    }

    #[test]
    fn filters_that_select_nothing_fail_only_a_gate() {
        let one = [read_input(0)];
        assert_eq!(filter_problem(&[5], &[], false, &one), None, "no --fail-on");
        assert_eq!(filter_problem(&[], &[], true, &one), None, "no filter");
        assert_eq!(
            filter_problem(&[5, 6], &["can1".into()], true, &one).as_deref(),
            Some(
                "--node 5,6 --channel can1 matches no node in the input, so --fail-on checked nothing"
            )
        );
        // The input's note on what it has goes into the one line.
        let mut noted = read_input(0);
        noted.unmatched = Some("--node 5 matches no node; the nodes ...: 7".into());
        assert_eq!(
            filter_problem(&[5], &[], true, std::slice::from_ref(&noted)).as_deref(),
            Some("t.log: --node 5 matches no node; the nodes ...: 7; --fail-on checked nothing")
        );
        let problem = filter_problem(&[5], &[], true, &[read_input(0), noted]).unwrap();
        assert!(
            problem.ends_with("nothing (first: t.log: --node 5 matches no node; the nodes ...: 7)"),
            "{problem}"
        );
        let two = [read_input(0), read_input(0)];
        let problem = filter_problem(&[], &["can9".into()], true, &two).expect("no channel");
        assert!(problem.contains("in the inputs,"), "{problem}");
    }

    fn names(n: usize) -> Vec<String> {
        (1..=n).map(|i| format!("d/{i}.log")).collect()
    }

    #[test]
    fn a_directory_that_yields_nothing_says_every_reason() {
        let globs = ["*.lgo".to_string(), "!old/**".to_string()];
        assert_eq!(
            LeftOut::default().why_nothing(&[]),
            "no trace under it (no file in it)"
        );
        let left = LeftOut {
            unselected: 12,
            no_trace: names(1),
            links: names(2),
            ..LeftOut::default()
        };
        assert_eq!(
            left.why_nothing(&globs),
            "no trace under it (12 files not selected by --glob '*.lgo' --glob '!old/**', \
             1 file with no known format, 2 symbolic links not followed without -L)"
        );
    }

    #[test]
    fn one_note_per_kind_left_out_naming_three_at_most() {
        assert!(LeftOut::default().notes(Path::new("d")).is_empty());
        let left = LeftOut {
            unselected: 5,
            no_trace: names(4),
            links: names(1),
            loops: names(2),
            twice: names(1),
        };
        assert_eq!(
            left.notes(Path::new("d")),
            [
                "d: skipped 4 files that are no trace (no known format in the first lines): \
                 d/1.log, d/2.log, d/3.log, ...",
                "d: skipped 1 symbolic link (-L follows it): d/1.log",
                "d: did not follow 2 symbolic links that point back to a directory above \
                 them, a loop (the files there were read once): d/1.log, d/2.log",
                "d: skipped 1 file that links reach again (read once, under its first path): \
                 d/1.log",
            ]
        );
    }

    #[test]
    fn progress_only_for_big_files_on_a_terminal_outside_ci_without_quiet() {
        assert!(progress_allowed(false, true, None));
        assert!(progress_allowed(false, true, Some(OsStr::new(""))));
        assert!(!progress_allowed(true, true, None), "--quiet");
        assert!(!progress_allowed(false, false, None), "a pipe");
        assert!(
            !progress_allowed(false, true, Some(OsStr::new("true"))),
            "CI"
        );
        assert!(wants_progress(true, PROGRESS_MIN_BYTES));
        assert!(!wants_progress(true, PROGRESS_MIN_BYTES - 1));
        assert!(!wants_progress(false, u64::MAX));
    }

    #[test]
    fn the_eta_waits_for_a_second_and_a_twentieth_of_the_file() {
        use std::time::Duration;
        assert!(!eta_is_known(Duration::from_millis(300), 0.5), "too soon");
        assert!(
            !eta_is_known(Duration::from_secs(5), 0.01),
            "too little read"
        );
        assert!(eta_is_known(Duration::from_secs(1), 0.05));
        assert!(eta_is_known(Duration::from_secs(30), 0.9));
    }

    #[test]
    fn the_table_fits_a_terminal_only() {
        let none = || None;
        let term = || Some(132);
        // A pipe: full lines, whatever COLUMNS says.
        assert_eq!(table_width(None, false, Some(OsStr::new("80")), term), None);
        assert_eq!(
            table_width(None, true, Some(OsStr::new("80")), term),
            Some(80)
        );
        assert_eq!(table_width(None, true, None, term), Some(132));
        assert_eq!(
            table_width(None, true, Some(OsStr::new("wide")), term),
            Some(132)
        );
        assert_eq!(table_width(None, true, Some(OsStr::new("0")), none), None);
        assert_eq!(table_width(Some(100), false, None, none), Some(100));
        assert_eq!(
            table_width(Some(0), true, Some(OsStr::new("80")), term),
            None
        );
    }

    #[test]
    fn colour_only_on_a_terminal_without_no_color_or_a_dumb_term() {
        let xterm = Some(OsStr::new("xterm-256color"));
        let dumb = Some(OsStr::new("dumb"));
        assert!(use_color(ColorChoice::Auto, true, None, xterm));
        assert!(use_color(ColorChoice::Auto, true, None, None));
        assert!(!use_color(ColorChoice::Auto, false, None, xterm));
        assert!(!use_color(
            ColorChoice::Auto,
            true,
            Some(OsStr::new("1")),
            xterm
        ));
        assert!(use_color(
            ColorChoice::Auto,
            true,
            Some(OsStr::new("")),
            xterm
        ));
        assert!(!use_color(ColorChoice::Auto, true, None, dumb), "TERM=dumb");
        assert!(use_color(
            ColorChoice::Always,
            false,
            Some(OsStr::new("1")),
            dumb
        ));
        assert!(!use_color(ColorChoice::Never, true, None, xterm));
    }
}
