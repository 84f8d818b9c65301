//! The analysis pipeline, one input start to finish: lines -> frames ->
//! EMCY/boot -> timelines -> events for a [`Sink`]. Reading never stops for
//! a bad line; it stops only at end of input, on an input I/O error
//! (recorded in the report), on a cancel, or when the output is gone
//! (returned as [`OutputError`]).
//!
//! Lines are classified block by block by one loop
//! ([`classify::classify_block`]) into a line sink. Sequentially that sink is
//! the [`consumer`] itself. On large inputs worker threads classify blocks
//! into compact records (only the lines that matter: EMCY/boot candidates
//! and diagnostics) and the consumer replays them in order ([`parallel`]),
//! so output is identical whatever the thread count. This layer owns the
//! event and report types ([`event`]) and the output trait ([`Sink`]); it
//! never knows which sink it feeds.

mod analysis;
pub mod batch;
mod bus;
mod classify;
mod consumer;
pub mod diagnostics;
pub mod event;
pub mod fail_on;
mod fold;
pub mod incident;
pub mod interest;
mod monitor;
mod nodes;
mod options;
mod parallel;
pub mod sink;
#[cfg(test)]
mod tests;
pub(crate) mod threads;
pub mod traffic;

use std::io::{self, Read, Write};

use crate::trace::Format;
use crate::trace::Parsed;
use crate::trace::any::Visit;
use crate::trace::deltas::{self, TimeMode};
use crate::trace::detect::{self, Detector};
use crate::trace::input::{self, Opened, ReadMode, Source};
use crate::trace::lines::BlockReader;
use crate::trace::{AnyReader, FrameSource, IdCounts, Next};

pub use analysis::{Analysis, OutputError, Reading};
use classify::{LineSink, classify_block, deliver};
use consumer::Consumer;
pub use diagnostics::DiagnosticLog;
pub use event::{
    BURST_GAP_MS, BootEvent, Bus, BusEvent, BusOff, BusOffRecord, ChannelErrors, Counts,
    Diagnostic, DriveReport, EmcyEvent, ErrorBurst, Evidence, EvidenceKind, GuardingReport, Health,
    HealthEvent, HeartbeatReport, HistoryReport, Identified, IdentifiedText, InputReport,
    LssIdentity, LssReport, NodeIdentity, NodeReport, SdoTransfer, TimeProducer, Unanswered,
    kind_counts,
};
use nodes::Capped;
pub use options::{EmcyId, MAX_NODES, Options};
pub use sink::{Discard, Sink, WithoutEvents};

/// Opens one source and reads it to the end ([`analyze`]); what stops it
/// (it cannot be opened, or reading failed part way) goes to the log as
/// `error: NAME: reason` and into the report's `error`. A source that could
/// not be opened still has a report (nothing read, its error), so every
/// input given is in the output; the sink sees no events for it.
/// `threads` picks the thread count from what was opened; `wrap` may wrap
/// the (decompressed) reader, e.g. to count progress.
pub fn analyze_source<E: Write>(
    source: &Source,
    mode: ReadMode,
    opts: &Options,
    threads: impl FnOnce(&Opened) -> usize,
    wrap: impl FnOnce(&Opened, Box<dyn Read + Send>) -> Box<dyn Read + Send>,
    sink: &mut dyn Sink,
    log: &mut DiagnosticLog<E>,
) -> Result<Analysis, OutputError> {
    let name = source.display_name();
    let mut opened = match input::open(source, mode, &opts.cancel) {
        Ok(o) => o,
        Err(e) => {
            let error = describe_io(&e);
            log.error(&format!("{name}: {error}"));
            return Ok(Analysis::unopened(name, error));
        }
    };
    let input_opts = Options {
        threads: threads(&opened),
        live: mode != ReadMode::Finite,
        ..opts.clone()
    };
    let reader = std::mem::replace(&mut opened.reader, Box::new(io::empty()));
    let reader = wrap(&opened, reader);
    let analysis = analyze(&name, reader, opened.gzip, &input_opts, sink, log)?;
    if let Some(err) = &analysis.report.error {
        log.error(&format!("{name}: {err}"));
    }
    Ok(analysis)
}

/// `No such file or directory` without Rust's `(os error 2)` suffix.
pub fn describe_io(e: &io::Error) -> String {
    let text = e.to_string();
    match text.find(" (os error") {
        Some(i) => text.get(..i).unwrap_or(&text).to_string(),
        None => text,
    }
}

/// Reads one input to the end and reports it.
pub fn analyze<R: Read + Send, E: Write>(
    file: &str,
    reader: R,
    gzip: bool,
    opts: &Options,
    sink: &mut dyn Sink,
    log: &mut DiagnosticLog<E>,
) -> Result<Analysis, OutputError> {
    sink.begin_input(file).map_err(OutputError)?;
    let mut detector = match opts.input_format {
        Some(f) => Detector::forced(f),
        None => Detector::auto(),
    };
    let mut consumer = Consumer::new(file, opts, sink, log, detector.format().is_some());
    let reader = Capped::new(reader, &consumer.nodes);

    // BLF, pcap, pcapng and MDF 4 are binary: known by their magic (or forced),
    // read record by record.
    let (reader, magic) = detect::sniff_binary(reader);
    let magic = match magic {
        Ok(magic) => magic,
        Err(e) => return consumer.finish(None, gzip, read_error(&e)),
    };
    let binary = match opts.input_format {
        Some(forced) => forced.is_binary().then_some(forced),
        None => magic,
    };
    if let Some(format) = binary {
        consumer.decided = true;
        // pcap or pcapng as the magic says; forced on neither, as forced.
        let format = match format {
            Format::Pcap | Format::Pcapng => magic
                .filter(|m| matches!(m, Format::Pcap | Format::Pcapng))
                .unwrap_or(format),
            other => other,
        };
        let error = match AnyReader::binary(format, reader) {
            Ok(mut source) => source.visit(ReadRecords(&mut consumer))?,
            Err(e) => read_error(&e),
        };
        return consumer.finish(Some(format), gzip, error);
    }
    // What candump times mean is decided before any frame is read: said by
    // the user, or seen in the first lines of a (possibly) candump input.
    let candump = matches!(
        opts.input_format,
        None | Some(Format::CandumpLog | Format::CandumpScreen)
    );
    let reader: Box<dyn Read + Send + '_> = match opts.timestamps {
        Some(TimeMode::Delta) => {
            detector.read_deltas();
            Box::new(reader)
        }
        None if candump && !opts.live => {
            let (reader, evidence) = deltas::read_ahead(reader);
            if let Some(evidence) = evidence {
                detector.read_deltas();
                consumer
                    .log
                    .note(&format!("{}: {}", consumer.file, evidence.note()));
            }
            Box::new(reader)
        }
        _ => Box::new(reader),
    };
    if detector.reads_deltas() {
        consumer.timestamps = Some(TimeMode::Delta);
    }
    let mut blocks = BlockReader::new(reader, opts.block_size, opts.max_line);

    // Sequential until the format is known (and for inputs whose lines chain,
    // or when one thread was asked for); then, if allowed, in parallel.
    let mut error = None;
    let mut buf = Vec::new();
    let format = loop {
        if opts.threads > 1 && detector.format().is_some() && detector.context().is_some() {
            let (read_error, detector) = parallel::run(blocks, detector, &mut consumer)?;
            error = read_error;
            consumer.recorded_bit_rate = detector.bit_rate();
            break detector.format();
        }
        match blocks.next_block(buf) {
            Ok(Some(block)) => {
                classify_block(&block, opts.max_line, &mut detector, &mut consumer)?;
                buf = block.bytes;
            }
            Ok(None) => {
                consumer.recorded_bit_rate = detector.bit_rate();
                break detector.format();
            }
            Err(e) => {
                error = Some(e.to_string());
                consumer.recorded_bit_rate = detector.bit_rate();
                break detector.format();
            }
        }
    };
    consumer.finish(format, gzip, error)
}

/// [`read_records`] compiled for each reader, then the EtherCAT counts.
struct ReadRecords<'c, 'a, 'b, E: Write>(&'c mut Consumer<'a, 'b, E>);

impl<E: Write> Visit for ReadRecords<'_, '_, '_, E> {
    type Output = Result<Option<String>, OutputError>;

    fn visit<S: FrameSource>(self, source: &mut S) -> Self::Output {
        let mut ids = std::mem::take(&mut self.0.ids);
        let result = read_records(source, self.0, &mut ids);
        if let Some(counted) = source.counted_ids() {
            ids.add(counted);
        }
        self.0.ids = ids;
        if let Some((first, last)) = source.plain_span() {
            self.0.plain_span(first, last);
        }
        self.0.recorded_bit_rate = source.bit_rate();
        if let Some(e) = source.ethercat_counts() {
            self.0.ethercat(e.frames, e.mailbox_messages, e.empty_polls);
        }
        result
    }
}

/// A record-by-record source (BLF, pcap, pcapng, MF4) into the consumer:
/// each record counts as a line, its number in the file is its line
/// number (a BLF object's index in reading order, a pcap packet's as
/// Wireshark numbers frames, an MF4 record's in file order).
fn read_records<S: FrameSource, E: Write>(
    source: &mut S,
    consumer: &mut Consumer<'_, '_, E>,
    ids: &mut IdCounts,
) -> Result<Option<String>, OutputError> {
    loop {
        let why = match source.next_item(Some(consumer.interest())) {
            Ok(Some(Next::Note(note))) => {
                consumer.log.note(&format!("{}: {note}", consumer.file));
                continue;
            }
            Ok(Some(Next::Counted(counted))) => {
                // Known non-frames only counted (EtherCAT frames without a
                // mailbox message): skipped lines.
                if counted.skipped > 0 {
                    consumer.decide();
                    consumer.skipped_lines(counted.skipped);
                    consumer.lines(counted.skipped);
                }
                // Frames only counted (ids nobody wants) or only timed
                // (the content filter rejects their data).
                if counted.plain > 0 {
                    consumer.plain_frames(counted.plain);
                }
                if let Some((n, first, last)) = counted.timed {
                    consumer.timed_frames(n, first, last);
                }
                let frames = counted.lines() - counted.skipped;
                if frames > 0 {
                    consumer.lines(frames);
                }
                continue;
            }
            Ok(Some(Next::Record(Parsed::Frame(f)))) => {
                // Every frame's time, decoded or not, spans the input.
                consumer.frame_times(f.time, f.time);
                deliver(consumer, ids, 0, &f, None)?;
                None
            }
            Ok(Some(Next::Record(Parsed::Skipped))) => Some(None),
            Ok(Some(Next::Record(Parsed::Malformed(reason)))) => Some(Some(reason)),
            Ok(None) => return Ok(None),
            Err(e) => return Ok(read_error(&e)),
        };
        match why {
            // A warning is about the frame just delivered.
            None => {
                if let Some(warning) = source.take_warning() {
                    consumer.warning(0, warning);
                }
                if source.take_annotated() {
                    consumer.annotated();
                }
            }
            Some(why) => {
                // An EtherCAT frame's CoE messages, all on this line, even
                // those before damage that makes the line malformed.
                if let Some((packet, channel)) = source.take_ethercat() {
                    consumer.decide();
                    for m in &packet.messages {
                        consumer.coe(0, packet.time, channel, m)?;
                    }
                }
                match why {
                    None => consumer.skipped(),
                    Some(why) => consumer.malformed(0, why),
                }
            }
        }
        consumer.lines(1);
    }
}

/// What a read error means for the input's report: a stop by a signal
/// (the cancel token) is the end of what was read, not an error; an object
/// it cut is not counted, as a line it cut is not.
fn read_error(e: &io::Error) -> Option<String> {
    (!crate::trace::cancel::is_cancelled(e)).then(|| e.to_string())
}
