//! One input, start to finish: lines -> frames -> EMCY/boot -> timelines ->
//! events for the renderer. Reading never stops for a bad line; it stops only
//! at end of input, on an input I/O error (recorded in the report) or when the
//! output is gone (returned as [`OutputError`]).

use std::collections::HashMap;
use std::io::{self, Read, Write};

use crate::canopen::emcy::{self, Emcy, Warning};
use crate::report::{BootEvent, Counts, Diagnostic, EmcyEvent, InputReport, NodeReport, Renderer};
use crate::timeline::{At, NodeTimeline};
use crate::trace::detect::Detector;
use crate::trace::lines::{LineReader, RawLine};
use crate::trace::{Format, FrameKind, Interest, Parsed, Timestamp};

/// What the user asked for that shapes reading and selection.
#[derive(Clone, Debug)]
pub struct Options {
    /// `--input-format`: skip detection.
    pub input_format: Option<Format>,
    /// `--node`: report only these nodes (empty = all).
    pub nodes: Vec<u8>,
    /// `--channel`: report only these channels (empty = all).
    pub channels: Vec<String>,
    /// Diagnostics printed per input; the counts stay exact beyond it.
    pub max_diagnostics: usize,
    /// Lines longer than this are reported and skipped.
    pub max_line: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            input_format: None,
            nodes: Vec::new(),
            channels: Vec::new(),
            max_diagnostics: 20,
            max_line: crate::trace::lines::DEFAULT_MAX_LINE,
        }
    }
}

impl Options {
    fn selects(&self, channel: &str, node: u8) -> bool {
        (self.nodes.is_empty() || self.nodes.contains(&node))
            && (self.channels.is_empty() || self.channels.iter().any(|c| c == channel))
    }
}

/// Writing the report failed (typically a closed pipe): stop everything.
#[derive(Debug)]
pub struct OutputError(pub io::Error);

/// The result of one input: its report plus what `--fail-on` needs.
#[derive(Debug)]
pub struct Analysis {
    pub report: InputReport,
    /// Selected EMCY frames with an error code (not a reset).
    pub errors_raised: u64,
}

/// Where diagnostics go: stderr as they happen (bounded per input) and a
/// copy for the JSON document.
pub struct DiagnosticLog<E: Write> {
    stderr: E,
    pub collected: Vec<Diagnostic>,
}

impl<E: Write> DiagnosticLog<E> {
    pub fn new(stderr: E) -> Self {
        DiagnosticLog {
            stderr,
            collected: Vec::new(),
        }
    }

    fn emit(&mut self, d: Diagnostic) {
        // A failing stderr must not stop decoding; the counts still record it.
        let _ = writeln!(self.stderr, "{d}");
        self.collected.push(d);
    }

    /// A one-line `error:` message (not kept in the JSON diagnostics).
    pub fn error(&mut self, message: &str) {
        let _ = writeln!(self.stderr, "error: {message}");
    }

    fn note(&mut self, message: &str) {
        let _ = writeln!(self.stderr, "{message}");
    }
}

/// The ids whose frames are decoded; everything else is only counted.
fn interest() -> Interest {
    let mut i = Interest::none();
    i.add_standard_range(emcy::FIRST_EMCY_ID..=emcy::LAST_EMCY_ID);
    i.add_standard_range(emcy::NMT_ERROR_CONTROL_BASE + 1..=emcy::NMT_ERROR_CONTROL_BASE + 127);
    i
}

/// Per-channel node timelines. Channels are usually few, but every distinct
/// interface name in the trace is one, so a hostile trace can name a million:
/// lookup is hashed and a channel holds only the nodes it has seen, keeping
/// time and memory linear in the input.
#[derive(Default)]
struct Nodes {
    channels: Vec<ChannelNodes>,
    index: HashMap<Vec<u8>, usize>,
}

struct ChannelNodes {
    name: String,
    /// Sorted by node id (1..=127).
    nodes: Vec<(u8, NodeTimeline)>,
}

impl Nodes {
    fn get(&mut self, raw: &[u8], node: u8) -> (&str, &mut NodeTimeline) {
        let idx = match self.index.get(raw) {
            Some(&i) => i,
            None => {
                self.channels.push(ChannelNodes {
                    name: String::from_utf8_lossy(raw).into_owned(),
                    nodes: Vec::new(),
                });
                self.index.insert(raw.to_vec(), self.channels.len() - 1);
                self.channels.len() - 1
            }
        };
        let ch = &mut self.channels[idx];
        let slot = match ch.nodes.binary_search_by_key(&node, |(n, _)| *n) {
            Ok(i) => i,
            Err(i) => {
                ch.nodes.insert(i, (node, NodeTimeline::new()));
                i
            }
        };
        (&ch.name, &mut ch.nodes[slot].1)
    }

    /// Node reports sorted by channel name, then node.
    fn into_reports(self, opts: &Options) -> Vec<NodeReport> {
        let mut out = Vec::new();
        let mut channels = self.channels;
        channels.sort_by(|a, b| a.name.cmp(&b.name));
        for ch in channels {
            for (node, tl) in ch.nodes {
                if !opts.selects(&ch.name, node) {
                    continue;
                }
                out.push(NodeReport {
                    channel: ch.name.clone(),
                    node,
                    state: tl.state(),
                    active: tl.active_codes().collect(),
                    emcy_count: tl.emcy_count(),
                    errors: tl.intervals().to_vec(),
                });
            }
        }
        out
    }
}

/// Bounded diagnostics for one input. While the format is unknown they are
/// held back: if no format is ever found the input gets one `error:` line
/// instead of a screenful of "not a frame".
struct InputDiagnostics {
    file: String,
    limit: usize,
    shown: usize,
    suppressed: u64,
    pending: Vec<Diagnostic>,
}

impl InputDiagnostics {
    fn report<E: Write>(
        &mut self,
        log: &mut DiagnosticLog<E>,
        decided: bool,
        line: u64,
        message: String,
    ) {
        if self.shown >= self.limit {
            self.suppressed += 1;
            return;
        }
        self.shown += 1;
        let d = Diagnostic {
            file: self.file.clone(),
            line,
            message,
        };
        if decided {
            log.emit(d);
        } else {
            self.pending.push(d);
        }
    }

    fn release<E: Write>(&mut self, log: &mut DiagnosticLog<E>) {
        for d in self.pending.drain(..) {
            log.emit(d);
        }
    }
}

/// A time earlier than the previous EMCY's or boot-up's (two logs
/// concatenated, a clock reset) gets a diagnostic: durations across this line
/// come out negative, and the user should know why.
fn check_clock<E: Write>(
    clock: &mut Option<(Timestamp, u64)>,
    at: At,
    diags: &mut InputDiagnostics,
    log: &mut DiagnosticLog<E>,
    decided: bool,
) {
    let Some(time) = at.time else { return };
    if let Some((previous, line)) = *clock
        && time.since(previous).is_negative()
    {
        diags.report(
            log,
            decided,
            at.line,
            format!(
                "time {time} is earlier than {previous} at line {line}: the trace's clock \
                 went backwards (durations across this line are negative)"
            ),
        );
    }
    *clock = Some((time, at.line));
}

/// Reads one input to the end and reports it.
pub fn analyze<R: Read, E: Write>(
    file: &str,
    reader: R,
    gzip: bool,
    opts: &Options,
    renderer: &mut dyn Renderer,
    log: &mut DiagnosticLog<E>,
) -> Result<Analysis, OutputError> {
    renderer.begin_input(file).map_err(OutputError)?;
    let interest = interest();
    let mut detector = match opts.input_format {
        Some(f) => Detector::forced(f),
        None => Detector::auto(),
    };
    let mut lines = LineReader::with_max_line(reader, opts.max_line);
    let mut counts = Counts::default();
    let mut nodes = Nodes::default();
    let mut diags = InputDiagnostics {
        file: file.to_string(),
        limit: opts.max_diagnostics,
        shown: 0,
        suppressed: 0,
        pending: Vec::new(),
    };
    let mut errors_raised = 0u64;
    let mut warnings: Vec<Warning> = Vec::new();
    let mut active: Vec<u16> = Vec::new();
    let mut error = None;
    let mut decided = detector.format().is_some();
    // Time and line of the last EMCY or boot-up: the trace's clock as far as
    // the timelines see it.
    let mut clock: Option<(Timestamp, u64)> = None;

    loop {
        let raw = match lines.next_line() {
            Ok(Some(raw)) => raw,
            Ok(None) => break,
            Err(e) => {
                error = Some(e.to_string());
                break;
            }
        };
        counts.lines += 1;
        let line_no = counts.lines;
        let text = match raw {
            RawLine::Text(t) => t,
            RawLine::TooLong(n) => {
                counts.malformed += 1;
                let msg = format!(
                    "line of {n} bytes is longer than the {} byte limit; skipped",
                    opts.max_line
                );
                diags.report(log, decided, line_no, msg);
                continue;
            }
        };
        let frame = match detector.parse(text, &interest) {
            Parsed::Frame(f) => f,
            Parsed::Skipped => {
                counts.skipped += 1;
                continue;
            }
            Parsed::Malformed(reason) => {
                counts.malformed += 1;
                diags.report(log, decided, line_no, reason.into_owned());
                continue;
            }
        };
        counts.frames += 1;
        if !decided {
            decided = true;
            diags.release(log);
        }
        if let Some(other) = detector.take_foreign() {
            counts.other_format += 1;
            let primary = detector.format().map_or("?", Format::name);
            let msg = format!(
                "line is in {} format, not {primary} like the rest; read anyway",
                other.name()
            );
            diags.report(log, decided, line_no, msg);
        }
        if frame.kind != FrameKind::Data || frame.extended {
            continue;
        }
        let at = At {
            time: frame.time,
            line: line_no,
        };
        let data = frame.data.as_slice();
        if let Some(node) = emcy::emcy_node(frame.id) {
            let emcy = match Emcy::decode(data) {
                Ok(e) => e,
                Err(short) => {
                    counts.emcy_invalid += 1;
                    diags.report(log, decided, line_no, format!("node {node}: {short}"));
                    continue;
                }
            };
            counts.emcy += 1;
            check_clock(&mut clock, at, &mut diags, log, decided);
            let info = emcy.info();
            warnings.clear();
            emcy.frame_warnings(&info, &mut warnings);
            let (channel, timeline) = nodes.get(frame.channel, node);
            let step = timeline.emcy(&emcy, at, &mut warnings);
            if !opts.selects(channel, node) {
                continue;
            }
            if !emcy.is_reset() {
                errors_raised += 1;
            }
            active.clear();
            active.extend(timeline.active_codes());
            let event = EmcyEvent {
                file,
                line: line_no,
                time: frame.time,
                channel,
                node,
                cob_id: frame.id,
                data,
                emcy: &emcy,
                info: &info,
                transition: step.transition,
                state: step.state,
                active: &active,
                cleared: &step.cleared,
                warnings: &warnings,
            };
            renderer.emcy(&event).map_err(OutputError)?;
        } else if let Some(node) = emcy::boot_node(frame.id, data) {
            counts.boot += 1;
            check_clock(&mut clock, at, &mut diags, log, decided);
            let (channel, timeline) = nodes.get(frame.channel, node);
            let cleared = timeline.boot(at);
            if opts.selects(channel, node) {
                let event = BootEvent {
                    file,
                    line: line_no,
                    time: frame.time,
                    channel,
                    node,
                    cleared: &cleared,
                };
                renderer.boot(&event).map_err(OutputError)?;
            }
        }
    }

    let format = detector.format();
    if format.is_none() && counts.malformed > 0 && error.is_none() {
        error = Some(
            "cannot detect the trace format: no line is a candump log, candump screen or \
             Vector ASC frame (force one with --input-format candump|candump-screen|asc)"
                .to_string(),
        );
    } else {
        diags.release(log);
        if diags.suppressed > 0 {
            log.note(&format!(
                "{file}: {} more diagnostics not shown (--max-diagnostics {})",
                diags.suppressed, opts.max_diagnostics
            ));
        }
    }
    let report = InputReport {
        file: file.to_string(),
        format,
        gzip,
        counts,
        nodes: nodes.into_reports(opts),
        error,
    };
    renderer.end_input(&report).map_err(OutputError)?;
    Ok(Analysis {
        report,
        errors_raised,
    })
}
