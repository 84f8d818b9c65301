//! The bodies of the cargo-fuzz targets in `fuzz/`, kept in the library so
//! that `cargo test` on stable replays the committed corpus and regressions
//! (`tests/integration/fuzz_corpus.rs`) through exactly the code the fuzzer
//! ran; and the per-line parsers for the `parse` benchmark ([`Parser`],
//! [`Detector`]).
//!
//! Each body panics when an invariant breaks, not only when the code under
//! test panics: a panic is what libFuzzer reports as a crash. Not part of the
//! public API.

mod checks;
mod lines;
mod timeline;

use checks::{check_emcy_event, check_node, codes, ndjson_values, no_control_characters};
pub use lines::{Detector, Ids, Parser, Scanned};
pub use timeline::decode_timeline;

use crate::canopen::NodeId;
use std::io::{self, Read};

use serde_json::Value;

use crate::analyze::{self, DiagnosticLog, Options};
use crate::analyze::{Counts, Diagnostic, InputReport, Sink};
use crate::report::json::JsonDocument;
use crate::report::ndjson::Ndjson;
use crate::report::table::TableReport;
use crate::trace::input::sniff_gzip;
use crate::trace::lines::Block;
use crate::trace::{Format, FrameKind, Interest, LineParser, Parsed, Scan};

// ---- readers: one trace through analyze ------------------------------------------

/// The `candump_log` target: [`reader`] with the format forced (and the
/// output the same with the reader's folding off).
pub fn candump_log(data: &[u8]) {
    reader(Some(Format::CandumpLog), data);
}

/// The `candump_screen` target: [`reader`] with the format forced.
pub fn candump_screen(data: &[u8]) {
    reader(Some(Format::CandumpScreen), data);
}

/// The `asc` target: [`reader`] with the format forced.
pub fn asc(data: &[u8]) {
    reader(Some(Format::Asc), data);
}

/// The `trc` target: the reader's own checks (well-formed frames, no endless
/// loop), then [`reader`] with the format forced.
pub fn trc(data: &[u8]) {
    crate::trace::format::trc::fuzz_trc(data);
    reader(Some(Format::Trc), data);
}

/// The `busmaster` target: the reader's own checks (well-formed frames, the
/// scan shortcut leaves the state `parse` does), then [`reader`] with the
/// format forced.
pub fn busmaster(data: &[u8]) {
    crate::trace::format::busmaster::fuzz_busmaster(data);
    reader(Some(Format::Busmaster), data);
}

/// The `ixxat` target: the reader's own checks (well-formed frames, the
/// title identifies the format), then [`reader`] with the format forced.
pub fn ixxat(data: &[u8]) {
    crate::trace::format::ixxat::fuzz_ixxat(data);
    reader(Some(Format::Ixxat), data);
}

/// The `blf` target: the reader's own checks (well-formed frames, no endless
/// loop, bounded buffers), then [`reader`] with the format forced.
pub fn blf(data: &[u8]) {
    crate::trace::format::blf::fuzz_blf(data);
    reader(Some(Format::Blf), data);
}

/// The `pcap` target: the reader's own checks (well-formed frames, no
/// endless loop, bounded buffers), then [`reader`] with the format forced
/// (as `--input-format pcap`: pcap or pcapng, as the magic says).
pub fn pcap(data: &[u8]) {
    crate::trace::format::pcap::fuzz_pcap(data);
    reader(Some(Format::Pcap), data);
}

/// The `ethercat` target: the bytes after the first as an EtherCAT frame
/// (the walk's own checks), then inside a packet framed as the first byte
/// chooses (Ethernet, VLAN-tagged, LINUX_SLL, LINUX_SLL2, IPv4 UDP to port
/// 0x88A4, or the bytes as the whole Ethernet packet), three times in a
/// pcapng: the pcap reader's checks (the same with and without an
/// interest, the hot loop counting what the general path reads) and
/// [`reader`]'s.
pub fn ethercat(data: &[u8]) {
    let (mode, frame) = match data.split_first() {
        Some((mode, frame)) => (*mode, frame),
        None => (0, data),
    };
    crate::trace::ethercat::fuzz_walk(frame);
    let ether = |tags: &[u8], ethertype: [u8; 2], payload: &[u8]| {
        let mut p = vec![0xFF; 6];
        p.extend_from_slice(&[2, 0, 0, 0, 0, 1]);
        p.extend_from_slice(tags);
        p.extend_from_slice(&ethertype);
        p.extend_from_slice(payload);
        p
    };
    let (linktype, packet) = match mode % 6 {
        0 => (1, ether(&[], [0x88, 0xA4], frame)),
        1 => (1, ether(&[0x81, 0, 0, 5], [0x88, 0xA4], frame)),
        2 => {
            let mut p = vec![0, 0, 0, 1, 0, 6, 0, 0, 0, 0, 0, 0, 0, 0, 0x88, 0xA4];
            p.extend_from_slice(frame);
            (113, p)
        }
        3 => {
            let mut p = vec![0x88, 0xA4];
            p.resize(20, 0);
            p.extend_from_slice(frame);
            (276, p)
        }
        4 => {
            let udp_len = (8 + frame.len()) as u16;
            let mut ip = vec![0x45, 0, 0, 0, 0, 1, 0x40, 0, 64, 17, 0, 0];
            ip.extend_from_slice(&[10, 0, 0, 1, 10, 0, 0, 2, 0x88, 0xA4, 0x88, 0xA4]);
            ip.extend_from_slice(&udp_len.to_be_bytes());
            ip.extend_from_slice(&[0, 0]);
            ip.extend_from_slice(frame);
            (1, ether(&[], [0x08, 0x00], &ip))
        }
        _ => (1, frame.to_vec()),
    };
    let capture = crate::trace::format::pcap::capture_of(linktype, &packet, 3);
    crate::trace::format::pcap::fuzz_pcap(&capture);
    reader(Some(Format::Pcap), &capture);
}

/// The `dcf` target: the first byte picks the node (1-127), the rest is
/// read as a DCF (`canopen::dcf::parse`). Checks: kept problems bounded and
/// counted, on lines of the file; every mapping a DCF mapping of that node,
/// its direction known, at most 64 entries and 64 bits, a valid COB-ID;
/// the mappings file into a [`MappingTable`](crate::canopen::pdo::MappingTable)
/// whose decoded ids each read any PDO bytes without panicking. The text is
/// also a `--pdo` spec and a `--dcf` option (errors, never a panic; a spec
/// accepted keeps its bit total within 64).
pub fn dcf(data: &[u8]) {
    use crate::canopen::dcf;
    use crate::canopen::pdo::{self, MappingTable, Source};
    let (node, text) = match data.split_first() {
        Some((n, rest)) => ((n % 127 + 1) as NodeId, rest),
        None => (1, data),
    };
    let parsed = dcf::parse(text, node);
    assert!(parsed.problems.len() <= dcf::MAX_PROBLEMS);
    assert!(parsed.problem_count >= parsed.problems.len() as u64);
    let lines = text.split(|&b| b == b'\n').count() as u64;
    for p in &parsed.problems {
        assert!(
            p.line >= 1 && p.line <= lines,
            "problem on line {} of {lines}",
            p.line
        );
    }
    let mut table = MappingTable::new();
    for m in &parsed.mappings {
        assert_eq!(m.source, Source::Dcf);
        assert_eq!(m.node, Some(node));
        assert!(m.direction.is_some());
        assert!(!m.objects.is_empty() && m.objects.len() <= 64);
        if !m.cob_id.extended {
            assert!(m.cob_id.id <= 0x7FF);
        }
        table.insert(m.clone());
    }
    let ids: Vec<pdo::CobId> = table.decoded_ids().collect();
    for id in ids {
        let fields = table.fields(id).copied().expect("a decoded id has fields");
        for len in [0usize, 1, 2, 8] {
            let _ = fields.read(text.get(..len.min(text.len())).unwrap_or_default());
        }
    }
    let as_text = String::from_utf8_lossy(text);
    if let Ok(specs) = pdo::parse_spec(&as_text) {
        for m in specs {
            let bits: u32 = m.objects.iter().map(|o| u32::from(o.bits)).sum();
            assert!(bits <= 64, "{bits} bits accepted");
        }
    }
    if let Ok((n, _)) = dcf::parse_option(&as_text) {
        assert!((1..=127).contains(&n));
    }
}

/// The `mf4` target: the reader's own checks (well-formed frames, no
/// endless loop, bounded queues and metadata), then [`reader`] with the
/// format forced (as `--input-format mf4`).
pub fn mf4(data: &[u8]) {
    crate::trace::format::mf4::fuzz_mf4(data);
    reader(Some(Format::Mf4), data);
}

/// The `candump_log`, `candump_screen` and `asc` targets (`Some(format)`,
/// forced as with `--input-format`), and the plain-bytes half of `detect`.
///
/// Checks, per line, that the parser classifies the same whatever the
/// wanted ids (id-first filtering only skips decoding) and that the scan
/// shortcut only ever skips valid frames nobody wants and only times frames
/// the content filter rejects; then, through the whole
/// pipeline, the count, event, node and history invariants of [`check_run`].
pub fn reader(format: Option<Format>, data: &[u8]) {
    if let Some(format) = format {
        lines_agree(format, data);
    }
    let opts = Options {
        input_format: format,
        max_line: 512,
        max_diagnostics: 20,
        block_size: 64 * 1024,
        spill_at: 16,
        ..Options::default()
    };
    let run = run(data, false, &opts, Output::Ndjson);
    check_run(&run, format, Some(data));
    if format == Some(Format::CandumpLog) {
        // Only the candump reader folds repeats: reading the lines one by
        // one must give the same, and with `--timing` (where it hands the
        // folded lines over to be timed) too.
        let timed_opts = Options {
            timing: true,
            bit_rate: Some(500_000),
            ..opts.clone()
        };
        let timed = self::run(data, false, &timed_opts, Output::Ndjson);
        for (what, opts, folded) in [("", &opts, &run), (" with --timing", &timed_opts, &timed)] {
            crate::analyze::interest::set_folding(false);
            let unfolded = self::run(data, false, opts, Output::Ndjson);
            crate::analyze::interest::set_folding(true);
            assert_eq!(
                String::from_utf8_lossy(&unfolded.out),
                String::from_utf8_lossy(&folded.out),
                "ndjson differs without folding{what}"
            );
            assert_eq!(
                unfolded.err, folded.err,
                "stderr differs without folding{what}"
            );
        }
    }
}

/// The `detect` target: the format is detected; gzip is read when the bytes
/// start with its magic. The same input is read once sequentially as the
/// reference, then with 2-4 threads and tiny blocks, with a line cap, a
/// diagnostics limit and a spill threshold chosen from the first byte and
/// the length: ndjson output and diagnostics must be identical, the JSON
/// document (tiny blocks) must hold the same values, and the table (tiny
/// blocks) must be UTF-8 without terminal control characters.
pub fn detect(data: &[u8]) {
    let seed = data.first().copied().unwrap_or(0) ^ (data.len() as u8);
    const BLOCKS: [usize; 8] = [1, 2, 3, 7, 16, 64, 300, 4096];
    const MAX_LINE: [usize; 4] = [16, 64, 200, 4096];
    const MAX_DIAGS: [usize; 4] = [0, 1, 5, 20];
    let base = Options {
        max_line: MAX_LINE[usize::from(seed >> 5 & 3)],
        max_diagnostics: MAX_DIAGS[usize::from(seed >> 3 & 3)],
        spill_at: 1 + usize::from(seed >> 7) * 8,
        ..Options::default()
    };
    let small = Options {
        threads: 2 + usize::from(seed % 3),
        block_size: BLOCKS[usize::from(seed >> 2 & 7)],
        ..base.clone()
    };
    let gzip = data.starts_with(&[0x1f, 0x8b]);
    let plain = (!gzip).then_some(data);

    let reference = run(data, gzip, &base, Output::Ndjson);
    check_run(&reference, None, plain);

    let split = run(data, gzip, &small, Output::Ndjson);
    check_run(&split, None, plain);
    assert_eq!(
        String::from_utf8_lossy(&split.out),
        String::from_utf8_lossy(&reference.out),
        "ndjson differs with {} threads and {}-byte blocks",
        small.threads,
        small.block_size
    );
    assert_eq!(
        String::from_utf8_lossy(&split.err),
        String::from_utf8_lossy(&reference.err),
        "diagnostics differ with {} threads and {}-byte blocks",
        small.threads,
        small.block_size
    );
    assert_eq!(split.report.counts, reference.report.counts);
    assert_eq!(split.errors_raised, reference.errors_raised);

    // --timing: every frame counted once on its channel, split or not, and
    // the analysis the same but for what SYNC's gaps add.
    let timing = |o: &Options| Options {
        timing: true,
        bit_rate: Some(500_000),
        ..o.clone()
    };
    let timed = run(data, gzip, &timing(&base), Output::Ndjson);
    check_run(&timed, None, plain);
    let timed_split = run(data, gzip, &timing(&small), Output::Ndjson);
    assert_eq!(
        String::from_utf8_lossy(&timed_split.out),
        String::from_utf8_lossy(&timed.out),
        "--timing ndjson differs with {} threads and {}-byte blocks",
        small.threads,
        small.block_size
    );
    // Every frame is counted once on its channel, by its id, whether it
    // was timed or not.
    for (what, r) in [("default", &reference), ("--timing", &timed)] {
        let counted: u64 = r.report.channels.iter().map(|c| c.frames).sum();
        let by_id: u64 = r
            .report
            .channels
            .iter()
            .map(|c| c.error_frames + c.other_ids + c.ids.iter().map(|i| i.count).sum::<u64>())
            .sum();
        let ignored_channels = r.report.channels.len() >= crate::trace::id_counts::MAX_CHANNELS;
        assert!(
            counted == r.report.counts.frames || ignored_channels,
            "{what} counted {counted} of {} frames",
            r.report.counts.frames
        );
        assert_eq!(counted, by_id, "{what}: a channel's frames are its ids'");
    }
    // A channel's name, frames, and (id, extended, frames) per id.
    type Counts = Vec<(String, u64, Vec<(u32, bool, u64)>)>;
    let counts = |r: &Run| -> Counts {
        r.report
            .channels
            .iter()
            .map(|c| {
                let ids = c.ids.iter().map(|i| (i.cob_id, i.extended, i.count));
                (c.channel.clone(), c.frames, ids.collect())
            })
            .collect()
    };
    assert_eq!(
        counts(&timed),
        counts(&reference),
        "--timing changes the counts"
    );
    // SYNC is timed on every run: its timing, its gaps and the incidents
    // they join are the same with --timing or without.
    type SyncTiming = Vec<(String, Vec<String>)>;
    let sync = |r: &Run| -> SyncTiming {
        r.report
            .channels
            .iter()
            .map(|c| {
                let ids = c.ids.iter().filter(|i| i.cob_id == 0x80 && !i.extended);
                let timing =
                    ids.map(|i| format!("{:?}", (i.period, i.jitter, i.max_gap, i.missed)));
                (c.channel.clone(), timing.collect())
            })
            .collect()
    };
    assert_eq!(
        sync(&timed),
        sync(&reference),
        "--timing changes SYNC's timing"
    );
    let story = |out: &[u8]| -> Vec<Value> {
        ndjson_values(out)
            .into_iter()
            .filter(|v| v["type"] != "channel")
            .collect()
    };
    assert_eq!(
        story(&timed.out),
        story(&reference.out),
        "--timing changes the analysis"
    );

    // Threads are tested above; one each is enough for the other renderers
    // (thread start-up would dominate the time per input).
    let small = Options {
        threads: 1,
        ..small
    };
    let json = run(data, gzip, &small, Output::Json);
    let doc: Value = serde_json::from_slice(&json.out).expect("the JSON document parses");
    let lines = ndjson_values(&reference.out);
    let of_type = |t: &str| -> Vec<Value> {
        lines
            .iter()
            .filter(|v| v["type"] == t)
            .cloned()
            .collect::<Vec<_>>()
    };
    let events: Vec<Value> = lines
        .iter()
        .filter(|v| !matches!(v["type"].as_str(), Some("node" | "input" | "channel")))
        .cloned()
        .collect();
    assert_eq!(
        doc["events"],
        Value::Array(events.clone()),
        "json events = ndjson"
    );
    assert_eq!(doc["nodes"], Value::Array(of_type("node")), "json nodes");
    assert_eq!(doc["inputs"], Value::Array(of_type("input")), "json inputs");
    assert_eq!(
        doc["channels"],
        Value::Array(of_type("channel")),
        "json channels"
    );
    let diags = doc["diagnostics"].as_array().expect("diagnostics array");
    assert_eq!(diags.len(), reference.diagnostics.len());

    let table = run(data, gzip, &small, Output::Table);
    no_control_characters("table", &table.out);

    // CSV: a header and one row of every column per event, the same
    // events in the same order as the ndjson.
    let csv_run = run(data, gzip, &small, Output::Csv);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(csv_run.out.as_slice());
    let rows: Vec<csv::StringRecord> = reader
        .records()
        .map(|r| r.expect("the CSV output parses"))
        .collect();
    assert_eq!(rows.len(), 1 + events.len(), "a row per event");
    // Names from the trace reach neither the terminal nor a spreadsheet's
    // formula engine.
    no_control_characters("csv", &csv_run.out);
    for row in rows.iter().skip(1) {
        let channel = row.get(5).unwrap_or_default();
        assert!(
            !channel.starts_with(['=', '+', '-', '@']),
            "a CSV channel cell a spreadsheet runs: {channel:?}"
        );
    }
    for (row, ev) in rows.iter().skip(1).zip(&events) {
        assert_eq!(row.len(), crate::report::csv::EVENT_COLUMNS.len());
        assert_eq!(row.get(0), ev["type"].as_str());
        assert_eq!(row.get(2), Some(ev["line"].to_string().as_str()));
        // An event of no node (a burst of error frames): an empty cell.
        let node = match &ev["node"] {
            serde_json::Value::Null => String::new(),
            n => n.to_string(),
        };
        assert_eq!(row.get(6), Some(node.as_str()));
    }
}

/// How [`run`] renders.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Output {
    Ndjson,
    Json,
    Table,
    Csv,
}

/// One input through `analyze` and a renderer, captured.
struct Run {
    out: Vec<u8>,
    err: Vec<u8>,
    report: InputReport,
    errors_raised: u64,
    diagnostics: Vec<Diagnostic>,
    /// What the pipeline read (after gzip), measured as it went by.
    seen: Seen,
    opts: Options,
}

/// Newlines and bytes that went through a reader.
#[derive(Clone, Copy, Default)]
struct Seen {
    bytes: u64,
    newlines: u64,
    last: Option<u8>,
}

impl Seen {
    fn lines(&self) -> u64 {
        self.newlines + u64::from(self.last.is_some_and(|b| b != b'\n'))
    }
}

struct Counting<R> {
    inner: R,
    seen: std::sync::Arc<std::sync::Mutex<Seen>>,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        let got = buf.get(..n).unwrap_or_default();
        if let Ok(mut s) = self.seen.lock() {
            s.bytes += n as u64;
            s.newlines += memchr::memchr_iter(b'\n', got).count() as u64;
            if let Some(&b) = got.last() {
                s.last = Some(b);
            }
        }
        Ok(n)
    }
}

fn run(data: &[u8], gzip: bool, opts: &Options, output: Output) -> Run {
    let seen = std::sync::Arc::new(std::sync::Mutex::new(Seen::default()));
    let opened =
        sniff_gzip(Box::new(io::Cursor::new(data.to_vec()))).expect("reading a Vec cannot fail");
    assert_eq!(opened.gzip, gzip, "gzip sniffed from the magic");
    let reader = Counting {
        inner: opened.reader,
        seen: std::sync::Arc::clone(&seen),
    };
    let mut out = Vec::new();
    let mut err = Vec::new();
    let mut renderer: Box<dyn Sink + '_> = match output {
        // The node objects' errors on as many helpers as the read has
        // threads: the parallel run's ndjson must equal the sequential one.
        Output::Ndjson => Box::new(Ndjson::new(&mut out, false).threads(opts.threads)),
        Output::Json => Box::new(JsonDocument::new(&mut out)),
        Output::Table => Box::new(TableReport::new(&mut out, false, false)),
        Output::Csv => Box::new(crate::report::csv::Csv::new(&mut out, false, false)),
    };
    let mut log = DiagnosticLog::new(&mut err);
    let analysis = analyze::analyze("fuzz", reader, gzip, opts, renderer.as_mut(), &mut log)
        .expect("output to a Vec cannot fail");
    let diagnostics = std::mem::take(&mut log.collected);
    drop(log);
    renderer
        .finish(std::slice::from_ref(&analysis.report), &diagnostics)
        .expect("finishing into a Vec cannot fail");
    drop(renderer);
    let seen = *seen.lock().expect("not poisoned");
    Run {
        out,
        err,
        report: analysis.report,
        errors_raised: analysis.errors_raised,
        diagnostics,
        seen,
        opts: opts.clone(),
    }
}

/// Invariants of one ndjson run. `plain` is the input when it was not gzip.
fn check_run(run: &Run, forced: Option<Format>, plain: Option<&[u8]>) {
    let report = &run.report;
    let c: Counts = report.counts;
    assert_eq!(
        c.lines,
        c.frames + c.skipped + c.malformed,
        "lines = frames + skipped + malformed: {c:?}"
    );
    // A CoE emergency is a mailbox message of an EtherCAT frame (a skipped
    // or malformed line), not a CAN frame; a retry is not read again.
    assert!(
        c.emcy + c.emcy_invalid + c.boot <= c.frames + c.mailbox_messages - c.mailbox_retries,
        "EMCY and boot frames are frames or mailbox messages: {c:?}"
    );
    assert!(c.mailbox_retries <= c.mailbox_messages, "{c:?}");
    assert!(c.ethercat_frames <= c.skipped + c.malformed, "{c:?}");
    assert!(c.other_format <= c.frames, "{c:?}");
    // BLF and pcap are binary: their "lines" are objects and packets, not newlines.
    if report.error.is_none() && !report.format.is_some_and(Format::is_binary) {
        assert_eq!(c.lines, run.seen.lines(), "every line read is counted");
    }
    // A fatal input error (a BLF file header that is not one) ends reading.
    if let Some(data) = plain
        && report.error.is_none()
    {
        assert_eq!(
            run.seen.bytes,
            data.len() as u64,
            "the input is read to its end"
        );
    }
    if let Some(f) = forced {
        // Forced pcap reads pcapng too, and says which it was.
        let flavour = if f == Format::Pcap {
            report.format.filter(|r| *r == Format::Pcapng).unwrap_or(f)
        } else {
            f
        };
        assert_eq!(report.format, Some(flavour));
        assert_eq!(c.other_format, 0, "a forced format reads nothing else");
    }
    if report.format.is_none() {
        assert_eq!(c.frames, 0, "no format, no frame: {c:?}");
    }

    // Diagnostics: bounded, in line order, naming a line of the input.
    assert!(run.diagnostics.len() <= run.opts.max_diagnostics);
    let mut previous = 0;
    for d in &run.diagnostics {
        assert!(
            d.line >= 1 && d.line <= c.lines.max(1),
            "diagnostic names line {} of {}",
            d.line,
            c.lines
        );
        assert!(d.line >= previous, "diagnostics in line order");
        previous = d.line;
    }
    no_control_characters("diagnostics", &run.err);

    let values = ndjson_values(&run.out);
    let (mut emcy, mut boot, mut raised, mut nodes, mut inputs) = (0, 0, 0, 0, 0);
    let mut last_line = 0;
    let mut node_emcy = 0;
    for v in &values {
        match v["type"].as_str() {
            Some("emcy") => {
                emcy += 1;
                let line = v["line"].as_u64().expect("line");
                // Only an EtherCAT frame holds several events.
                let same_ok = c.ethercat_frames > 0 && line == last_line;
                assert!(
                    (line > last_line || same_ok) && line <= c.lines,
                    "events in line order"
                );
                last_line = line;
                check_emcy_event(v, true);
                if v["code"] != "0x0000" {
                    raised += 1;
                }
            }
            Some("boot") => {
                boot += 1;
                let line = v["line"].as_u64().expect("line");
                // Only an EtherCAT frame holds several events.
                let same_ok = c.ethercat_frames > 0 && line == last_line;
                assert!(
                    (line > last_line || same_ok) && line <= c.lines,
                    "events in line order"
                );
                last_line = line;
                let _ = codes(&v["cleared"]);
            }
            Some(
                "nmt"
                | "heartbeat_lost"
                | "heartbeat_back"
                | "sdo_abort"
                | "error_history"
                | "error_history_cleared"
                | "axis_state"
                | "fault_reset",
            ) => {
                // Several can share a line with each other and with the
                // EMCY or boot-up event of that line.
                let line = v["line"].as_u64().expect("line");
                assert!(line >= last_line && line <= c.lines, "events in line order");
                for key in ["file", "time", "channel", "node"] {
                    assert!(v.get(key).is_some(), "{key} in {v}");
                }
            }
            Some("channel") => {
                // A channel's counts are a share of the input's frames.
                let error_frames = v["error_frames"].as_u64().expect("error_frames");
                let timed: u64 = v["ids"]
                    .as_array()
                    .expect("ids")
                    .iter()
                    .map(|id| id["count"].as_u64().expect("count"))
                    .sum();
                assert!(error_frames + timed <= c.frames, "channel counts: {v}");
                if let Some(frames) = v["frames"].as_u64() {
                    assert!(error_frames + timed <= frames && frames <= c.frames, "{v}");
                }
            }
            Some("bus_error" | "bus_off" | "lss" | "incident" | "sync_missed") => {
                // Told where they began, which a burst closed later (or a
                // node's silence before its bus-off) puts before events
                // already written: only within the input.
                let line = v["line"].as_u64().expect("line");
                assert!(line <= c.lines, "bus event within the input");
                for key in ["file", "time", "channel", "node"] {
                    assert!(v.get(key).is_some(), "{key} in {v}");
                }
            }
            Some("sdo") => {
                // Told at its end, by the line that ended it: within the
                // input, at or after its first line; what it shows is what
                // it carried, at most 64 bytes.
                let start = v["start_line"].as_u64().expect("start_line");
                let end = v["line"].as_u64().expect("line");
                assert!(start <= end && end <= c.lines, "sdo lines: {v}");
                let result = v["result"].as_str().expect("result");
                assert!(
                    ["ok", "abort", "unanswered", "incomplete"].contains(&result),
                    "{v}"
                );
                assert_eq!(v["abort_code"].is_null(), result != "abort", "{v}");
                if let Some(hex) = v["value"].as_str() {
                    let size = v["size"].as_u64().expect("a value has a size");
                    assert_eq!(hex.len() as u64, 2 * size.min(64), "{v}");
                    assert_eq!(v["value_hash"].is_null(), size <= 64, "{v}");
                }
                let node = v["node"].as_u64().expect("node");
                assert!((1..=127).contains(&node), "{v}");
            }
            Some("node") => {
                nodes += 1;
                node_emcy += v["emcy_count"].as_u64().expect("emcy_count");
                check_node(v);
            }
            Some("input") => {
                inputs += 1;
                for (key, n) in [
                    ("lines", c.lines),
                    ("frames", c.frames),
                    ("emcy", c.emcy),
                    ("skipped", c.skipped),
                    ("malformed", c.malformed),
                    ("boot", c.boot),
                    ("emcy_invalid", c.emcy_invalid),
                    ("other_format", c.other_format),
                ] {
                    assert_eq!(v[key].as_u64(), Some(n), "input.{key}");
                }
            }
            other => panic!("unknown ndjson object type {other:?}"),
        }
    }
    assert_eq!(emcy, c.emcy, "one event per decoded EMCY");
    assert_eq!(boot, c.boot, "one event per boot-up");
    assert_eq!(
        raised, run.errors_raised,
        "errors raised = events with a code"
    );
    assert_eq!(nodes, report.nodes.len() as u64);
    assert_eq!(node_emcy, c.emcy, "node EMCY counts add up");
    assert_eq!(inputs, 1);
}

/// Per line: the same classification whatever the interest, and the scan
/// shortcut only skips valid frames that are not wanted and returns wanted
/// ones exactly as `parse` does.
fn lines_agree(format: Format, data: &[u8]) {
    let wanted = analyze::interest::interest(&Options::default());
    let all = Interest::all();
    let mut p_all = format.parser();
    let mut p_wanted = format.parser();
    let mut p_scan = format.parser();
    let block = Block::of(data);
    for raw in block.lines(512) {
        let crate::trace::lines::RawLine::Text(line) = raw else {
            continue;
        };
        let a = p_all.parse(line, &all);
        let w = p_wanted.parse(line, &wanted);
        let mut timed = None;
        let mut key = None;
        let q = match p_scan.scan(line, &wanted) {
            Scan::Plain(k) => {
                key = Some(k);
                None
            }
            Scan::Timed(t, k) => {
                timed = Some(t);
                key = Some(k);
                Some(w.clone())
            }
            Scan::Frame(f) => Some(Parsed::Frame(f)),
            Scan::Parse => Some(p_scan.parse(line, &wanted)),
        };
        let shown = || String::from_utf8_lossy(line).into_owned();
        if let Some(t) = timed {
            // Only a frame on a filtered id whose data the filter rejects,
            // at the time the full parser reads.
            let Parsed::Frame(f) = &w else {
                panic!("scan timed a line that is not a frame: {:?}", shown());
            };
            assert!(
                wanted.timed_only(f.id, f.extended, f.data.as_slice()),
                "{:?}",
                shown()
            );
            assert_eq!(f.time, Some(t), "{:?}", shown());
        }
        match (&a, &w) {
            (Parsed::Frame(fa), Parsed::Frame(fw)) => {
                assert_eq!(
                    (fa.id, fa.extended, fa.kind, fa.len, fa.channel),
                    (fw.id, fw.extended, fw.kind, fw.len, fw.channel),
                    "the interest changed the frame: {:?}",
                    shown()
                );
                if fw.kind == FrameKind::Data && wanted.wants(fw.id, fw.extended) {
                    assert_eq!(fa.data, fw.data, "{:?}", shown());
                    assert_eq!(fa.time, fw.time, "{:?}", shown());
                }
                check_frame(fa, line);
            }
            (Parsed::Skipped, Parsed::Skipped) | (Parsed::Malformed(_), Parsed::Malformed(_)) => {}
            _ => panic!(
                "the interest changed the classification of {:?}: {a:?} vs {w:?}",
                shown()
            ),
        }
        if let (Some(key), Parsed::Frame(f)) = (key, &a) {
            assert_eq!(key, f.key(), "counted under another key: {:?}", shown());
        }
        match q {
            None => {
                let Parsed::Frame(f) = &a else {
                    panic!("scan skipped a line that is not a frame: {:?}", shown());
                };
                assert!(
                    !wanted.wants(f.id, f.extended),
                    "scan skipped a wanted frame: {:?}",
                    shown()
                );
            }
            Some(q) => assert_eq!(q, w, "scan (then parse) = parse: {:?}", shown()),
        }
        assert_eq!(p_all.context(), p_wanted.context(), "{:?}", shown());
        assert_eq!(p_all.context(), p_scan.context(), "{:?}", shown());
    }
}

fn check_frame(f: &crate::trace::Frame<'_>, line: &[u8]) {
    let shown = String::from_utf8_lossy(line);
    match f.kind {
        FrameKind::Data => {
            assert!(f.len <= 8, "classic frame of {} bytes: {shown:?}", f.len);
            assert_eq!(f.data.len(), usize::from(f.len), "{shown:?}");
        }
        FrameKind::Fd => {
            assert!(f.len <= 64, "FD frame of {} bytes: {shown:?}", f.len);
            assert_eq!(f.data.len(), usize::from(f.len), "{shown:?}");
        }
        FrameKind::Remote => assert!(f.data.is_empty(), "{shown:?}"),
        FrameKind::Error => return,
    }
    let max = if f.extended { 0x1FFF_FFFF } else { 0x7FF };
    assert!(f.id <= max, "id {:#X} out of range: {shown:?}", f.id);
}
