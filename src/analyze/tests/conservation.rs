//! No EMCY is lost or invented, whatever surrounds it.
//!
//! Random frames (EMCY and not: standard and extended ids, 0x081..0x0FF and
//! `00000081`, remote, FD, error frames, short EMCY frames, boot-ups) are
//! rendered in one of the three formats with random valid variations, and
//! interleaved with garbage: random bytes, NUL runs, invalid UTF-8, valid
//! lines made invalid (cut short and poisoned, a non-hex id, an odd number of
//! hex digits), valid lines padded past the line cap, blank and comment
//! lines. The real pipeline (`analyze` with the NDJSON renderer, fed through
//! the real gzip sniffing, in random read sizes, sometimes gzip-compressed)
//! must report exactly:
//!
//! - the EMCY events of the valid classic 11-bit EMCY frames with >= 3 bytes,
//!   in order, with their line numbers, times, channels and data;
//! - the counts: lines, frames, skipped, malformed, emcy, emcy_invalid, boot;
//! - one diagnostic per malformed line and short EMCY (plus one per backwards
//!   clock jump), each naming file:line.
//!
//! Every garbage line is checked against each reader (and ASC in both number
//! bases) to be malformed, so the oracle never counts a line as garbage that
//! a reader could take for a frame.

use std::io::{self, Read, Write};

use super::frames::*;
use crate::analyze::Sink as Renderer;
use crate::analyze::{DiagnosticLog, Options, analyze};
use crate::canopen::NodeId;
use crate::report::ndjson::Ndjson;
use crate::trace::input::sniff_gzip;
use crate::trace::{Format, FrameKind, HexBytes, Interest, LineParser, Parsed};
use proptest::prelude::*;
use serde::Deserialize;
use serde_json::Value;
use serde_json::value::RawValue;

/// A small cap keeps over-long lines cheap; the mechanism is the same as at
/// the default 64 KiB (which the integration tests' `hostile` covers through
/// the binary).
const MAX_LINE: usize = 1024;
const FILE: &str = "trace";

// ---- what a generated file holds ---------------------------------------------------

#[derive(Clone, Debug)]
enum Style {
    Log(LogStyle),
    Screen(ScreenStyle),
    Asc(AscStyle),
}

#[derive(Clone, Debug)]
enum Item {
    /// A valid frame line (ASC: preceded by its `base` header line).
    Frame {
        frame: TestFrame,
        crlf: bool,
    },
    Garbage(Garbage),
    /// Blank or `//` comment: skipped by every reader.
    Blank(&'static str),
    /// `# comment`: a candump comment; ASC knows no such line, so in an ASC
    /// file it is skipped until the format is known and malformed after.
    HashComment,
}

#[derive(Clone, Debug)]
enum Garbage {
    /// `(` and a non-digit, then any bytes: never a timestamp, never a
    /// header keyword, so malformed in every format.
    Noise(Vec<u8>),
    Nul(usize),
    /// 0xFF (never UTF-8) then bytes 0x80..=0xFF, one token.
    NotUtf8(Vec<u8>),
    /// A valid line cut at `cut` (a fraction) with a byte no format accepts
    /// where it lands appended.
    Cut {
        frame: TestFrame,
        cut: f64,
        poison: u8,
    },
    /// A valid line whose id starts with `G`.
    BadId(TestFrame),
    /// candump log: one more hex digit right after `#` (odd digit count).
    OddHex(TestFrame),
    /// A valid line padded with blanks past the line cap: still not read.
    TooLong {
        frame: TestFrame,
        len: usize,
    },
    /// Random bytes past the line cap.
    LongNoise(Vec<u8>),
}

/// How each line must be classified.
#[derive(Clone, Debug)]
enum Expect {
    Frame(TestFrame, Option<String>, String),
    Skipped,
    Malformed,
    /// Skipped while no frame was read yet, malformed after.
    SkippedUntilDecided,
}

fn test_frame() -> impl Strategy<Value = TestFrame> {
    let id = prop_oneof![
        4 => (0x81u32..=0xFF, Just(false)),
        1 => (0x701u32..=0x77F, Just(false)),
        1 => (prop_oneof![Just(0x81u32), Just(0x80), Just(0x100), 0x81u32..=0xFF], Just(true)),
        1 => (0u32..=0x7FF, Just(false)),
        1 => (0u32..=0x1FFF_FFFF, Just(true)),
    ];
    (frame(), id, 0u8..5)
        .prop_map(|(mut f, (id, extended), shape)| {
            if f.kind != FrameKind::Error {
                f.id = id;
                f.extended = extended;
            }
            if f.kind == FrameKind::Data {
                match shape {
                    // Short EMCY frames (and short others).
                    0 => f.data.truncate(f.data.len().min(2)),
                    // Boot-ups on NMT ids.
                    1 if (0x701..=0x77F).contains(&f.id) => f.data = vec![0],
                    _ => {}
                }
            }
            f
        })
        // `date` first on a line is an ASC header: a poisoned screen line
        // on an interface named so would be skipped, not malformed.
        .prop_filter("interface named like an ASC header", |f| {
            !f.channel.eq_ignore_ascii_case("date")
        })
}

fn garbage() -> impl Strategy<Value = Garbage> {
    let line_byte = any::<u8>().prop_filter("no newline", |b| *b != b'\n');
    prop_oneof![
        (
            prop_oneof![
                Just(b'!'),
                Just(b'x'),
                Just(b'.'),
                Just(b'-'),
                Just(0u8),
                Just(0xFF)
            ],
            prop::collection::vec(line_byte.clone(), 0..120)
        )
            .prop_map(|(second, rest)| {
                let mut v = vec![b'(', second];
                v.extend(rest);
                Garbage::Noise(v)
            }),
        (1usize..200).prop_map(Garbage::Nul),
        prop::collection::vec(0x80u8..=0xFF, 0..80).prop_map(|rest| {
            let mut v = vec![0xFF];
            v.extend(rest);
            Garbage::NotUtf8(v)
        }),
        (
            test_frame(),
            0.0f64..=1.0,
            prop_oneof![Just(b'G'), Just(b'z'), Just(b'?'), Just(0u8), Just(0xFFu8)]
        )
            .prop_map(|(frame, cut, poison)| Garbage::Cut { frame, cut, poison }),
        test_frame().prop_map(Garbage::BadId),
        test_frame().prop_map(Garbage::OddHex),
        (test_frame(), MAX_LINE + 1..MAX_LINE * 3)
            .prop_map(|(frame, len)| Garbage::TooLong { frame, len }),
        prop::collection::vec(line_byte, MAX_LINE + 1..MAX_LINE * 3).prop_map(Garbage::LongNoise),
    ]
}

fn item() -> impl Strategy<Value = Item> {
    prop_oneof![
        6 => (test_frame(), any::<bool>()).prop_map(|(frame, crlf)| Item::Frame { frame, crlf }),
        5 => garbage().prop_map(Item::Garbage),
        1 => prop_oneof![Just(""), Just("  "), Just("\t \t"), Just("// note"), Just("\r")]
            .prop_map(Item::Blank),
        1 => Just(Item::HashComment),
    ]
}

fn style(format: Format) -> BoxedStrategy<Style> {
    match format {
        Format::CandumpLog => log_style().prop_map(Style::Log).boxed(),
        Format::CandumpScreen => screen_style().prop_map(Style::Screen).boxed(),
        Format::Asc => asc_style().prop_map(Style::Asc).boxed(),
        // TRC and BLF have their own property tests (the integration tests'
        // `trc` and `blf`).
        other => unreachable!("{other:?} is not generated here"),
    }
}

#[derive(Clone, Debug)]
struct Case {
    format: Format,
    /// One item and one rendering style per line.
    items: Vec<(Item, Style)>,
    final_newline: bool,
    gzip: bool,
    chunk_seed: u64,
}

fn case() -> impl Strategy<Value = Case> {
    prop_oneof![
        Just(Format::CandumpLog),
        Just(Format::CandumpScreen),
        Just(Format::Asc)
    ]
    .prop_flat_map(|format| {
        (
            prop::collection::vec((item(), style(format)), 0..40),
            any::<bool>(),
            prop::bool::weighted(0.2),
            any::<u64>(),
        )
            .prop_map(move |(items, final_newline, gzip, chunk_seed)| Case {
                format,
                items,
                final_newline,
                gzip,
                chunk_seed,
            })
    })
}

// ---- rendering and the oracle ------------------------------------------------------------

/// The frame line in the file's format, the ASC header before it if any,
/// and (time, channel) as the report must show them.
fn render(f: &TestFrame, style: &Style) -> (Option<String>, String, Option<String>, String) {
    match style {
        Style::Log(s) => (
            None,
            render_log(f, s),
            Some(f.time_text()),
            f.channel.clone(),
        ),
        Style::Screen(s) => (
            None,
            render_screen(f, s),
            s.time.then(|| f.time_text()),
            f.channel.clone(),
        ),
        Style::Asc(s) => {
            let mut lines = render_asc(f, s);
            let line = lines.pop().unwrap();
            (
                lines.pop(),
                line,
                Some(f.time_text()),
                s.channel.to_string(),
            )
        }
    }
}

/// Byte ranges of the blank-separated tokens of a line.
fn tokens(line: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, b) in line.iter().enumerate() {
        match (b == &b' ' || b == &b'\t', start) {
            (true, Some(s)) => {
                out.push((s, i));
                start = None;
            }
            (false, None) => start = Some(i),
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, line.len()));
    }
    out
}

/// Index of the id token in a rendered frame line, if it has one.
fn id_token(style: &Style, f: &TestFrame) -> Option<usize> {
    match style {
        Style::Log(_) => Some(2),
        Style::Screen(s) => Some(usize::from(s.time) + 1 + if s.extra { 3 } else { 0 }),
        Style::Asc(_) if f.kind == FrameKind::Error => None,
        Style::Asc(s)
            if f.kind == FrameKind::Fd || (f.kind == FrameKind::Data && s.canfd_classic) =>
        {
            Some(4)
        }
        Style::Asc(_) => Some(2),
    }
}

fn cut_and_poison(line: &str, cut: f64, poison: u8) -> Vec<u8> {
    let at = ((line.len() as f64) * cut) as usize;
    let mut v = line.as_bytes()[..at.min(line.len())].to_vec();
    // The poison is glued to what the cut left: after a blank, a sign
    // following a complete candump frame is a pasted note, which is read.
    while v.last().is_some_and(|b| *b == b' ' || *b == b'\t') {
        v.pop();
    }
    v.push(poison);
    v
}

fn garbage_bytes(g: &Garbage, style: &Style) -> Vec<u8> {
    match g {
        Garbage::Noise(v) | Garbage::NotUtf8(v) | Garbage::LongNoise(v) => v.clone(),
        Garbage::Nul(n) => vec![0; *n],
        Garbage::Cut { frame, cut, poison } => {
            cut_and_poison(&render(frame, style).1, *cut, *poison)
        }
        Garbage::BadId(frame) => {
            let line = render(frame, style).1;
            match id_token(style, frame) {
                Some(k) => {
                    let mut v = line.into_bytes();
                    let (start, _) = tokens(&v)[k];
                    v[start] = b'G';
                    v
                }
                None => cut_and_poison(&line, 0.5, b'G'),
            }
        }
        Garbage::OddHex(frame) => {
            let line = render(frame, style).1;
            match (style, line.find('#')) {
                (Style::Log(_), Some(hash)) => {
                    let mut v = line.into_bytes();
                    v.insert(hash + 1, b'A');
                    v
                }
                _ => cut_and_poison(&line, 0.7, b'?'),
            }
        }
        Garbage::TooLong { frame, len } => {
            let mut v = render(frame, style).1.into_bytes();
            while v.len() < *len {
                v.push(if v.len().is_multiple_of(2) {
                    b' '
                } else {
                    b'\t'
                });
            }
            v
        }
    }
}

/// Garbage must be malformed for every reader, whatever state it is in.
fn assert_malformed_everywhere(line: &[u8]) -> Result<(), TestCaseError> {
    let mut parsers: Vec<_> = Format::ALL.iter().map(|f| f.parser()).collect();
    let mut asc_dec = Format::Asc.parser();
    let header = asc_dec.parse(b"base dec  timestamps absolute", &Interest::all());
    prop_assert_eq!(header, Parsed::Skipped);
    parsers.push(asc_dec);
    for p in &mut parsers {
        let parsed = p.parse(line, &Interest::all());
        prop_assert!(
            matches!(parsed, Parsed::Malformed(_)),
            "garbage {:?} is {:?} for {:?}",
            String::from_utf8_lossy(line),
            parsed,
            p.format()
        );
    }
    Ok(())
}

struct Built {
    bytes: Vec<u8>,
    expect: Vec<Expect>,
}

fn build(case: &Case) -> Result<Built, TestCaseError> {
    let mut lines: Vec<(Vec<u8>, Expect)> = Vec::new();
    for (item, style) in &case.items {
        match item {
            Item::Frame { frame, crlf } => {
                let (header, line, time, channel) = render(frame, style);
                if let Some(h) = header {
                    lines.push((h.into_bytes(), Expect::Skipped));
                }
                let mut bytes = line.into_bytes();
                prop_assert!(bytes.len() < MAX_LINE);
                if *crlf {
                    bytes.push(b'\r');
                }
                lines.push((bytes, Expect::Frame(frame.clone(), time, channel)));
            }
            Item::Garbage(g) => {
                let bytes = garbage_bytes(g, style);
                if bytes.len() > MAX_LINE {
                    // Malformed by length whatever it holds.
                } else {
                    assert_malformed_everywhere(&bytes)?;
                }
                lines.push((bytes, Expect::Malformed));
            }
            Item::Blank(text) => lines.push((text.as_bytes().to_vec(), Expect::Skipped)),
            Item::HashComment => {
                let expect = if case.format == Format::Asc {
                    Expect::SkippedUntilDecided
                } else {
                    Expect::Skipped
                };
                lines.push((b"# comment".to_vec(), expect));
            }
        }
    }
    // Without a final newline an empty last line is no line at all.
    let final_newline = case.final_newline || lines.last().is_some_and(|(b, _)| b.is_empty());
    let mut bytes = Vec::new();
    for (i, (line, _)) in lines.iter().enumerate() {
        bytes.extend_from_slice(line);
        if i + 1 < lines.len() || final_newline {
            bytes.push(b'\n');
        }
    }
    Ok(Built {
        bytes,
        expect: lines.into_iter().map(|(_, e)| e).collect(),
    })
}

/// A reader that hands out the input in random small pieces.
struct Chunked {
    data: Vec<u8>,
    pos: usize,
    rng: u64,
}

impl Read for Chunked {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        let want = 1 + (self.rng % 700) as usize;
        let n = want.min(buf.len()).min(self.data.len() - self.pos);
        buf[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

#[derive(Deserialize)]
struct EmcyOut<'a> {
    file: String,
    line: u64,
    #[serde(borrow)]
    time: &'a RawValue,
    channel: String,
    node: NodeId,
    cob_id: u32,
    data: String,
}

#[derive(Debug, PartialEq)]
struct Event {
    line: u64,
    time: String,
    channel: String,
    node: NodeId,
    cob_id: u32,
    data: String,
}

fn is_emcy(f: &TestFrame) -> bool {
    f.kind == FrameKind::Data && !f.extended && (0x81..=0xFF).contains(&f.id)
}

fn is_boot(f: &TestFrame) -> bool {
    f.kind == FrameKind::Data && !f.extended && (0x701..=0x77F).contains(&f.id) && f.data == [0]
}

fn check(case: &Case) -> Result<(), TestCaseError> {
    let built = build(case)?;
    let input = if case.gzip {
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(&built.bytes).unwrap();
        enc.finish().unwrap()
    } else {
        built.bytes.clone()
    };
    let reader = Chunked {
        data: input,
        pos: 0,
        rng: case.chunk_seed | 1,
    };
    let opened = sniff_gzip(Box::new(reader)).unwrap();
    prop_assert_eq!(opened.gzip, case.gzip);
    let opts = Options {
        max_diagnostics: usize::MAX,
        max_line: MAX_LINE,
        ..Options::default()
    };
    let mut out = Vec::new();
    let mut stderr = Vec::new();
    let mut renderer = Ndjson::new(&mut out, false);
    let mut log = DiagnosticLog::new(&mut stderr);
    let analysis = analyze(
        FILE,
        opened.reader,
        opened.gzip,
        &opts,
        &mut renderer,
        &mut log,
    )
    .map_err(|e| TestCaseError::fail(format!("output error {:?}", e.0)))?;
    let collected = std::mem::take(&mut log.collected);
    drop(log);
    // NMT warnings (undefined states, ignored commands, guarding toggles)
    // and a client's aborts to ids that never answered are checked by the
    // network tests; this oracle follows EMCYs and lines.
    let is_nmt =
        |m: &str| m.contains("NMT") || m.contains("node guarding") || m.contains("never answered");
    let collected: Vec<_> = collected
        .into_iter()
        .filter(|d| !is_nmt(&d.message))
        .collect();
    // Node and input objects come at the end of the run, as in src/bin/emcy-decode/decode.rs.
    renderer
        .finish(std::slice::from_ref(&analysis.report), &collected)
        .unwrap();

    // The oracle.
    let mut decided = false;
    let (mut frames, mut skipped, mut malformed) = (0u64, 0u64, 0u64);
    let (mut emcy, mut emcy_invalid, mut boot) = (0u64, 0u64, 0u64);
    let mut events = Vec::new();
    let mut diagnostic_lines = Vec::new();
    let mut clock: Option<crate::trace::Timestamp> = None;
    for (i, expect) in built.expect.iter().enumerate() {
        let line = i as u64 + 1;
        match expect {
            Expect::Skipped => skipped += 1,
            Expect::SkippedUntilDecided if !decided => skipped += 1,
            Expect::Malformed | Expect::SkippedUntilDecided => {
                malformed += 1;
                diagnostic_lines.push(line);
            }
            Expect::Frame(f, time, channel) => {
                frames += 1;
                decided = true;
                let timed = time.as_ref().map(|_| f.time());
                let tick = |clock: &mut Option<_>, diagnostic_lines: &mut Vec<u64>| {
                    if let Some(t) = timed {
                        if clock.is_some_and(|c| t.since(c).is_negative()) {
                            diagnostic_lines.push(line);
                        }
                        *clock = Some(t);
                    }
                };
                if is_emcy(f) && f.data.len() < 3 {
                    emcy_invalid += 1;
                    diagnostic_lines.push(line);
                } else if is_emcy(f) {
                    emcy += 1;
                    tick(&mut clock, &mut diagnostic_lines);
                    events.push(Event {
                        line,
                        time: time.clone().unwrap_or_else(|| "null".to_string()),
                        channel: channel.clone(),
                        node: (f.id - 0x80) as NodeId,
                        cob_id: f.id,
                        data: HexBytes(&f.data).to_string(),
                    });
                } else if is_boot(f) {
                    boot += 1;
                    tick(&mut clock, &mut diagnostic_lines);
                }
            }
        }
    }

    // What the pipeline reported.
    drop(renderer);
    let text = String::from_utf8(out).unwrap();
    let mut got = Vec::new();
    let mut inputs = Vec::new();
    for l in text.lines() {
        let v: Value = serde_json::from_str(l).unwrap();
        match v["type"].as_str() {
            Some("emcy") => {
                let e: EmcyOut<'_> = serde_json::from_str(l).unwrap();
                prop_assert_eq!(&e.file, FILE);
                got.push(Event {
                    line: e.line,
                    time: e.time.get().to_string(),
                    channel: e.channel,
                    node: e.node,
                    cob_id: e.cob_id,
                    data: e.data,
                });
            }
            Some("input") => inputs.push(v),
            _ => {}
        }
    }
    // Exactly the valid EMCY frames: none lost, none invented.
    prop_assert_eq!(&got, &events);
    // A valid line right after a malformed one is read.
    for e in &events {
        let before = e.line.checked_sub(2).map(|i| &built.expect[i as usize]);
        if matches!(before, Some(Expect::Malformed)) {
            prop_assert!(got.iter().any(|g| g.line == e.line));
        }
    }

    let counts = analysis.report.counts;
    let lines = built.expect.len() as u64;
    prop_assert_eq!(counts.lines, lines);
    prop_assert_eq!(
        counts.lines,
        counts.frames + counts.skipped + counts.malformed
    );
    prop_assert_eq!(
        (counts.frames, counts.skipped, counts.malformed),
        (frames, skipped, malformed)
    );
    prop_assert_eq!(
        (counts.emcy, counts.emcy_invalid, counts.boot),
        (emcy, emcy_invalid, boot)
    );
    prop_assert_eq!(counts.other_format, 0);
    // The input object says the same.
    prop_assert_eq!(inputs.len(), 1);
    let input = &inputs[0];
    for (key, value) in [
        ("lines", lines),
        ("frames", frames),
        ("skipped", skipped),
        ("malformed", malformed),
        ("emcy", emcy),
        ("emcy_invalid", emcy_invalid),
        ("boot", boot),
    ] {
        prop_assert_eq!(input[key].as_u64(), Some(value), "{}", key);
    }

    if frames == 0 {
        prop_assert_eq!(analysis.report.format, None);
        prop_assert_eq!(analysis.report.error.is_some(), malformed > 0);
        prop_assert!(collected.is_empty());
    } else {
        prop_assert_eq!(analysis.report.format, Some(case.format));
        prop_assert_eq!(&analysis.report.error, &None);
        // One diagnostic per malformed line, short EMCY and clock jump, in
        // order, each naming file:line, on stderr and in the log.
        diagnostic_lines.sort_unstable();
        let lines: Vec<u64> = collected.iter().map(|d| d.line).collect();
        prop_assert_eq!(&lines, &diagnostic_lines);
        prop_assert!(collected.iter().all(|d| d.file == FILE));
        let stderr = String::from_utf8(stderr).unwrap();
        let printed: Vec<&str> = stderr.lines().filter(|l| !is_nmt(l)).collect();
        prop_assert_eq!(printed.len(), diagnostic_lines.len());
        for (p, n) in printed.iter().zip(&diagnostic_lines) {
            let prefix = format!("{FILE}:{n}: ");
            prop_assert!(p.starts_with(&prefix), "{}", p);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn no_emcy_is_lost_or_invented(case in case()) {
        check(&case)?;
    }
}

/// The poisoned and mutated lines really are garbage for every reader: the
/// property above relies on it (and asserts it per line), this pins a few.
#[test]
fn garbage_generators_make_lines_no_reader_accepts() {
    for line in [
        &b"(!(1.0) can0 081#1043090100000000"[..],
        b"(\xff 081 [3] 10 43 09",
        b"\x00\x00\x00",
        b"\xff\xfe",
        b"(1.0) can0 G81#1043090100000000",
        b"(1.0) can0 081#A1043090100000000",
        b" (1.0)  can0  G81   [3]  10 43 09",
        b"   1.000000 1  G1  Rx   d 3 10 43 09",
        b"   1.000000 1  ErrorFrameG",
        b"   1.000000 1  81  Rx   d 3 10 43 0?",
    ] {
        assert_malformed_everywhere(line).unwrap();
    }
}
