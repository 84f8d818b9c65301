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
mod classify;
mod consumer;
pub mod diagnostics;
pub mod event;
pub mod fail_on;
mod fold;
pub mod interest;
mod monitor;
mod nodes;
mod options;
mod parallel;
pub mod sink;
#[cfg(test)]
mod tests;
pub(crate) mod threads;

use std::io::{self, Read, Write};

use crate::trace::Format;
use crate::trace::Parsed;
use crate::trace::blf;
use crate::trace::deltas::{self, TimeMode};
use crate::trace::detect::{self, Detector};
use crate::trace::input::{self, Opened, ReadMode, Source};
use crate::trace::lines::BlockReader;
use crate::trace::mf4;
use crate::trace::pcap;

pub use analysis::{Analysis, OutputError};
use classify::{LineSink, classify_block, deliver};
use consumer::Consumer;
pub use diagnostics::DiagnosticLog;
pub use event::{
    BootEvent, Counts, Diagnostic, DriveReport, EmcyEvent, Health, HealthEvent, HeartbeatReport,
    HistoryReport, InputReport, NodeReport,
};
pub use options::{EmcyId, Options};
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
    match binary {
        Some(Format::Blf) => {
            consumer.decided = true;
            let error = read_blf(reader, &mut consumer)?;
            return consumer.finish(Some(Format::Blf), gzip, error);
        }
        Some(forced @ (Format::Pcap | Format::Pcapng)) => {
            consumer.decided = true;
            // pcap or pcapng as the magic says; forced on neither, as forced.
            let flavour = magic.filter(|m| matches!(m, Format::Pcap | Format::Pcapng));
            let error = read_pcap(reader, &mut consumer)?;
            return consumer.finish(Some(flavour.unwrap_or(forced)), gzip, error);
        }
        Some(Format::Mf4) => {
            consumer.decided = true;
            let error = read_mf4(reader, &mut consumer)?;
            return consumer.finish(Some(Format::Mf4), gzip, error);
        }
        _ => {}
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
            break detector.format();
        }
        match blocks.next_block(buf) {
            Ok(Some(block)) => {
                classify_block(&block, opts.max_line, &mut detector, &mut consumer)?;
                buf = block.bytes;
            }
            Ok(None) => break detector.format(),
            Err(e) => {
                error = Some(e.to_string());
                break detector.format();
            }
        }
    };
    consumer.finish(format, gzip, error)
}

/// Vector BLF into the same consumer: each object counts as a line, its
/// index in reading order is its line number.
fn read_blf<R: Read, E: Write>(
    reader: R,
    consumer: &mut Consumer<'_, '_, E>,
) -> Result<Option<String>, OutputError> {
    let mut reader = match blf::BlfReader::new(reader) {
        Ok(r) => r,
        Err(e) => return Ok(read_error(&e)),
    };
    if let Some(note) = reader.take_note() {
        consumer.log.note(&format!("{}: {note}", consumer.file));
    }
    loop {
        match reader.next_object() {
            Ok(Some(Parsed::Frame(f))) => {
                deliver(consumer, 0, &f, None)?;
            }
            Ok(Some(Parsed::Skipped)) => consumer.skipped(),
            Ok(Some(Parsed::Malformed(reason))) => consumer.malformed(0, reason),
            Ok(None) => return Ok(None),
            Err(e) => return Ok(read_error(&e)),
        }
        if let Some(warning) = reader.take_warning() {
            consumer.warning(0, warning);
        }
        consumer.lines(1);
    }
}

/// pcap and pcapng into the same consumer: each packet counts as a line,
/// its number in the file is its line number (as Wireshark numbers frames).
fn read_pcap<R: Read, E: Write>(
    reader: R,
    consumer: &mut Consumer<'_, '_, E>,
) -> Result<Option<String>, OutputError> {
    let mut reader = match pcap::PcapReader::new(reader) {
        Ok(r) => r,
        Err(e) => return Ok(read_error(&e)),
    };
    let result = read_packets(&mut reader, consumer);
    let e = reader.ethercat_counts();
    consumer.ethercat(e.frames, e.mailbox_messages, e.empty_polls);
    result
}

fn read_packets<R: Read, E: Write>(
    reader: &mut pcap::PcapReader<R>,
    consumer: &mut Consumer<'_, '_, E>,
) -> Result<Option<String>, OutputError> {
    loop {
        let more = reader.advance(Some(consumer.interest()));
        while let Some(note) = reader.take_note() {
            consumer.log.note(&format!("{}: {note}", consumer.file));
        }
        // EtherCAT frames without a mailbox message: skipped lines.
        let quiet = reader.take_quiet();
        if quiet > 0 {
            consumer.decide();
            consumer.skipped_lines(quiet);
            consumer.lines(quiet);
        }
        // Frames before the packet read that are only counted (ids nobody
        // wants) or timed (the content filter rejects their data).
        let (counted, timed) = reader.take_counted();
        if counted > 0 {
            let timed_n = timed.map_or(0, |(n, _, _)| n);
            if counted > timed_n {
                consumer.plain_frames(counted - timed_n);
            }
            if let Some((n, first, last)) = timed {
                consumer.timed_frames(n, first, last);
            }
            consumer.lines(counted);
        }
        match more {
            Ok(true) => {}
            Ok(false) => return Ok(None),
            Err(e) => return Ok(read_error(&e)),
        }
        let taken = match reader.take() {
            Some(Parsed::Frame(f)) => {
                deliver(consumer, 0, &f, None)?;
                None
            }
            Some(Parsed::Skipped) => Some(None),
            Some(Parsed::Malformed(reason)) => Some(Some(reason)),
            None => continue,
        };
        if let Some(why) = taken {
            // An EtherCAT frame's CoE messages, all on this line, even
            // those before damage that makes the line malformed.
            if let Some((packet, channel)) = reader.take_ethercat() {
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
        consumer.lines(1);
    }
}

/// MDF 4 into the same consumer: each record counts as a line, numbered
/// in file order.
fn read_mf4<R: Read, E: Write>(
    reader: R,
    consumer: &mut Consumer<'_, '_, E>,
) -> Result<Option<String>, OutputError> {
    let mut reader = match mf4::Mf4Reader::new(reader) {
        Ok(r) => r,
        Err(e) => return Ok(read_error(&e)),
    };
    loop {
        while let Some(note) = reader.take_note() {
            consumer.log.note(&format!("{}: {note}", consumer.file));
        }
        match reader.next_item(Some(consumer.interest())) {
            Ok(Some(mf4::Next::Plain(n))) => {
                // Frames on ids nobody wants: only counted.
                consumer.plain_frames(n);
                consumer.lines(n);
                continue;
            }
            Ok(Some(mf4::Next::Record(Parsed::Frame(f)))) => deliver(consumer, 0, &f, None)?,
            Ok(Some(mf4::Next::Record(Parsed::Skipped))) => consumer.skipped(),
            Ok(Some(mf4::Next::Record(Parsed::Malformed(reason)))) => consumer.malformed(0, reason),
            Ok(None) => {
                while let Some(note) = reader.take_note() {
                    consumer.log.note(&format!("{}: {note}", consumer.file));
                }
                return Ok(None);
            }
            Err(e) => return Ok(read_error(&e)),
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
