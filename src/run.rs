//! Runs a parsed command line and decides the exit code.

use std::io::{self, IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;

use crate::analyze::{self, Analysis, DiagnosticLog, Options, OutputError};
use crate::cli::{
    Cli, Command, DecodeArgs, ExplainArgs, ExplainFormat, FailOn, OutputFormat, View,
};
use crate::explain;
use crate::report::html::HtmlReport;
use crate::report::json::JsonDocument;
use crate::report::ndjson::Ndjson;
use crate::report::svg::SvgReport;
use crate::report::table::{TableReport, use_color};
use crate::report::{InputReport, Renderer, WithoutEvents};
use crate::trace::input::{self, Source};

/// The exit codes of the contract in `--help`.
pub const EXIT_OK: u8 = 0;
pub const EXIT_FAIL_ON: u8 = 1;
pub const EXIT_ERROR: u8 = 2;

pub fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Some(Command::Explain(args)) => explain_command(&args),
        None => decode_command(&cli.decode),
    }
}

fn explain_command(args: &ExplainArgs) -> Result<ExitCode> {
    let text = match (&args.data, &args.code, args.format) {
        (Some(data), _, ExplainFormat::Text) => {
            explain::payload_text(&explain::parse_payload(data)?)?
        }
        (Some(data), _, ExplainFormat::Json) => {
            format!(
                "{:#}\n",
                explain::payload_json(&explain::parse_payload(data)?)?
            )
        }
        (None, Some(code), ExplainFormat::Text) => explain::code_text(explain::parse_code(code)?),
        (None, Some(code), ExplainFormat::Json) => {
            format!("{:#}\n", explain::code_json(explain::parse_code(code)?))
        }
        (None, None, _) => anyhow::bail!("give a CODE or --data"),
    };
    let mut out = io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Err(e) if e.kind() != io::ErrorKind::BrokenPipe => return Err(e.into()),
        _ => {}
    }
    Ok(ExitCode::from(EXIT_OK))
}

fn decode_command(args: &DecodeArgs) -> Result<ExitCode> {
    let opts = Options {
        input_format: args.input_format.map(Into::into),
        nodes: args.node.clone(),
        channels: args.channel.clone(),
        max_diagnostics: args.max_diagnostics,
        emcy_ids: args.emcy_id.clone(),
        ..Options::default()
    };
    let sources: Vec<Source> = if args.files.is_empty() {
        vec![Source::Stdin]
    } else {
        args.files
            .iter()
            .map(|p: &PathBuf| Source::from_arg(p))
            .collect()
    };
    let stdout = io::stdout();
    // Reading a live stream (`candump -L can0 | emcy-decode -`): each event
    // must show up when its line arrives, not when a buffer fills.
    let live = sources == [Source::Stdin] && input::stdin_is_stream();
    let out = io::BufWriter::with_capacity(64 * 1024, stdout.lock());
    let summary = args.view == View::Summary;
    let mut renderer: Box<dyn Renderer> = match args.format {
        OutputFormat::Table => {
            let no_color = std::env::var_os("NO_COLOR");
            let color = use_color(args.color, io::stdout().is_terminal(), no_color.as_deref());
            let table = TableReport::new(out, color, live);
            Box::new(if summary { table.summary_only() } else { table })
        }
        OutputFormat::Json if summary => Box::new(WithoutEvents(JsonDocument::new(out))),
        OutputFormat::Json => Box::new(JsonDocument::new(out)),
        OutputFormat::Ndjson if summary => Box::new(WithoutEvents(Ndjson::new(out, live))),
        OutputFormat::Ndjson => Box::new(Ndjson::new(out, live)),
        OutputFormat::Svg => Box::new(SvgReport::new(out)),
        OutputFormat::Html => Box::new(HtmlReport::new(out)),
    };
    let mut log = DiagnosticLog::new(io::stderr());
    let threads = Threads {
        requested: args.threads,
        live,
    };

    match decode_all(&sources, &opts, threads, renderer.as_mut(), &mut log) {
        Ok(outcome) => Ok(ExitCode::from(exit_code(args, &outcome, &mut log))),
        // The reader of our output went away (`| head -1`): not an error.
        Err(OutputError(e)) if e.kind() == io::ErrorKind::BrokenPipe => Ok(ExitCode::from(EXIT_OK)),
        Err(OutputError(e)) => {
            log.error(&format!("writing output: {e}"));
            Ok(ExitCode::from(EXIT_ERROR))
        }
    }
}

/// What all inputs amounted to.
pub struct Outcome {
    pub analyses: Vec<Analysis>,
    /// Inputs that could not be opened.
    pub open_failures: usize,
}

/// How many threads an input gets.
#[derive(Clone, Copy)]
struct Threads {
    /// `-j N`; 0 = automatic.
    requested: usize,
    /// A live stream: events must not wait for a block to fill.
    live: bool,
}

/// Inputs below this size are read on one thread: starting workers costs
/// more than it saves.
const PARALLEL_MIN_BYTES: u64 = 16 * 1024 * 1024;

impl Threads {
    fn for_input(self, opened: &input::Opened) -> usize {
        if self.requested > 0 {
            return self.requested;
        }
        let big = opened.gzip || opened.size.is_some_and(|s| s >= PARALLEL_MIN_BYTES);
        if self.live || !big {
            return 1;
        }
        std::thread::available_parallelism().map_or(1, |n| n.get().min(8))
    }
}

fn decode_all(
    sources: &[Source],
    opts: &Options,
    threads: Threads,
    renderer: &mut dyn Renderer,
    log: &mut DiagnosticLog<io::Stderr>,
) -> Result<Outcome, OutputError> {
    let mut analyses = Vec::new();
    let mut open_failures = 0;
    for source in sources {
        let name = source.display_name();
        let opened = match input::open(source) {
            Ok(o) => o,
            Err(e) => {
                log.error(&format!("{name}: {}", describe_io(&e)));
                open_failures += 1;
                continue;
            }
        };
        let input_opts = Options {
            threads: threads.for_input(&opened),
            ..opts.clone()
        };
        let analysis = analyze::analyze(
            &name,
            opened.reader,
            opened.gzip,
            &input_opts,
            renderer,
            log,
        )?;
        if let Some(err) = &analysis.report.error {
            log.error(&format!("{name}: {err}"));
        }
        analyses.push(analysis);
    }
    let reports: Vec<InputReport> = analyses.iter().map(|a| a.report.clone()).collect();
    renderer
        .finish(&reports, &log.collected)
        .map_err(OutputError)?;
    Ok(Outcome {
        analyses,
        open_failures,
    })
}

/// `No such file or directory` without Rust's `(os error 2)` suffix.
fn describe_io(e: &io::Error) -> String {
    let text = e.to_string();
    match text.find(" (os error") {
        Some(i) => text[..i].to_string(),
        None => text,
    }
}

fn exit_code(args: &DecodeArgs, outcome: &Outcome, log: &mut DiagnosticLog<io::Stderr>) -> u8 {
    let reports = outcome.analyses.iter().map(|a| &a.report);
    let input_failed = outcome.open_failures > 0 || reports.clone().any(|r| r.error.is_some());
    let strict_failed = args.strict
        && reports
            .clone()
            .any(|r| r.counts.malformed > 0 || r.counts.emcy_invalid > 0);
    if input_failed || strict_failed {
        return EXIT_ERROR;
    }
    let met = fail_on_met(&FailOn::combine(&args.fail_on), &outcome.analyses);
    for reason in &met {
        log.note(&format!("fail-on: {reason}"));
    }
    if met.is_empty() {
        EXIT_OK
    } else {
        EXIT_FAIL_ON
    }
}

/// The `--fail-on` conditions the inputs met, each with what met it.
pub fn fail_on_met(fail_on: &FailOn, analyses: &[Analysis]) -> Vec<String> {
    let mut met = Vec::new();
    let nodes = || analyses.iter().flat_map(|a| &a.report.nodes);
    if fail_on.any {
        let n: u64 = analyses.iter().map(|a| a.errors_raised).sum();
        if n > 0 {
            met.push(format!("any: {n} error EMCY frame{}", plural(n)));
        }
    }
    if fail_on.active {
        let n = nodes().filter(|n| !n.active.is_empty()).count() as u64;
        if n > 0 {
            met.push(format!(
                "active: {n} node{} end{} with an active error",
                plural(n),
                if n == 1 { "s" } else { "" }
            ));
        }
    }
    if fail_on.warning {
        let n: u64 = analyses.iter().map(|a| a.frames_with_warnings).sum();
        if n > 0 {
            met.push(format!(
                "warning: {n} EMCY frame{} with warnings",
                plural(n)
            ));
        }
    }
    for &code in &fail_on.codes {
        let n: u64 = nodes().filter_map(|n| n.stats.raised.get(&code)).sum();
        if n > 0 {
            met.push(format!("code=0x{code:04X}: raised {n} time{}", plural(n)));
        }
    }
    if let Some(bound) = fail_on.category_at_most {
        let worst = analyses.iter().filter_map(|a| a.worst_category).min();
        if let Some(worst) = worst.filter(|&w| w <= bound) {
            met.push(format!("category<={bound}: an error of category {worst}"));
        }
    }
    met
}

fn plural(n: u64) -> &'static str {
    if n == 1 { "" } else { "s" }
}
