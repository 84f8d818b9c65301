//! One input, start to finish: lines -> frames -> EMCY/boot -> timelines ->
//! events for the renderer. Reading never stops for a bad line; it stops only
//! at end of input, on an input I/O error (recorded in the report) or when the
//! output is gone (returned as [`OutputError`]).
//!
//! Lines are classified block by block by one loop ([`classify_block`]) into a
//! [`LineSink`]. Sequentially the sink is the [`Consumer`] itself. On large
//! inputs worker threads classify blocks into compact records (only the lines
//! that matter: EMCY/boot candidates and diagnostics) and the consumer
//! replays them in order, so output is identical whatever the thread count.

use std::collections::{BTreeMap, HashMap};
use std::io::{self, Read, Write};
use std::ops::Range;
use std::sync::mpsc::{self, Receiver};
use std::sync::{Arc, Mutex, RwLock};

use crate::cache::{Cache, profile_code_key};
use crate::canopen::codes::CodeInfo;
use crate::canopen::emcy::{self, Emcy, Warning};
use crate::canopen::sdo;
use crate::history::{DEFAULT_SPILL_AT, ErrorHistory, History, Record};
use crate::profile_choice::{NodeProfiles, ProfileChoice, ProfileSource, default_profile};
use crate::report::{BootEvent, Counts, Diagnostic, EmcyEvent, InputReport, NodeReport, Renderer};
use crate::timeline::{At, NodeTimeline, Step};
use crate::trace::blf;
use crate::trace::detect::Detector;
use crate::trace::input::{self, Opened, ReadMode, Source};
use crate::trace::lines::{self, Block, BlockReader, DEFAULT_BLOCK, RawLine};
use crate::trace::{
    ContentFilter, Format, Frame, FrameKind, Interest, Parsed, Payload, Reason, Scan, Timestamp,
};

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
    /// Threads classifying lines; 1 = all on the calling thread.
    pub threads: usize,
    /// Bytes per read / per block handed to a thread.
    pub block_size: usize,
    /// Closed error intervals kept in memory before they go to a temporary file.
    pub spill_at: usize,
    /// `--emcy-id`: EMCY COB-IDs moved by object 0x1014, to the node they belong to.
    pub emcy_ids: Vec<EmcyId>,
    /// `--profile`, `--profile-file`: which profile decodes which node.
    pub profiles: ProfileChoice,
}

/// A node's EMCY COB-ID other than 0x80 + node (object 0x1014).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EmcyId {
    pub id: u32,
    pub extended: bool,
    pub node: u8,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            input_format: None,
            nodes: Vec::new(),
            channels: Vec::new(),
            max_diagnostics: 20,
            max_line: crate::trace::lines::DEFAULT_MAX_LINE,
            threads: 1,
            block_size: DEFAULT_BLOCK,
            spill_at: DEFAULT_SPILL_AT,
            emcy_ids: Vec::new(),
            profiles: ProfileChoice::default(),
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
    /// Selected EMCY frames that carried a protocol warning.
    pub frames_with_warnings: u64,
    /// The lowest (most severe) profile category of a selected error EMCY.
    pub worst_category: Option<u8>,
}

/// Where diagnostics go: stderr as they happen (bounded per input) and a
/// copy for the JSON document.
pub struct DiagnosticLog<E: Write> {
    stderr: E,
    pub collected: Vec<Diagnostic>,
    /// `--quiet`: diagnostics and notes are collected, not printed.
    pub quiet: bool,
}

impl<E: Write> DiagnosticLog<E> {
    pub fn new(stderr: E) -> Self {
        DiagnosticLog {
            stderr,
            collected: Vec::new(),
            quiet: false,
        }
    }

    fn emit(&mut self, d: Diagnostic) {
        // A failing stderr must not stop decoding; the counts still record it.
        if !self.quiet {
            let _ = writeln!(self.stderr, "{d}");
        }
        self.collected.push(d);
    }

    /// Passes on what another log (an input read on another thread) wrote
    /// and collected.
    pub fn replay(&mut self, written: &[u8], collected: Vec<Diagnostic>) {
        let _ = self.stderr.write_all(written);
        self.collected.extend(collected);
    }

    /// The stderr this log wrote to.
    pub fn into_inner(self) -> E {
        self.stderr
    }

    /// A one-line `error:` message (not kept in the JSON diagnostics).
    pub fn error(&mut self, message: &str) {
        let _ = writeln!(self.stderr, "error: {message}");
    }

    pub fn note(&mut self, message: &str) {
        if !self.quiet {
            let _ = writeln!(self.stderr, "{message}");
        }
    }
}

/// The ids whose frames are decoded; everything else is only counted:
/// EMCY, NMT error control (boot-up), SDO (identity, moved EMCY ids) and
/// EMCY ids given on the command line. On the NMT and SDO ids only some
/// frames matter ([`content_matters`]); the readers only time the others.
pub(crate) fn interest(opts: &Options) -> Interest {
    let mut i = Interest::none();
    let filter = ContentFilter(content_matters);
    let nmt = emcy::NMT_ERROR_CONTROL_BASE + 1..=emcy::NMT_ERROR_CONTROL_BASE + 127;
    let responses = sdo::RESPONSE_BASE + 1..=sdo::RESPONSE_BASE + 127;
    let requests = sdo::REQUEST_BASE + 1..=sdo::REQUEST_BASE + 127;
    i.add_standard_range(emcy::FIRST_EMCY_ID..=emcy::LAST_EMCY_ID);
    for ids in [nmt, responses, requests] {
        i.add_standard_range(ids.clone());
        i.filter_content(ids, filter);
    }
    for e in &opts.emcy_ids {
        add_emcy_id(&mut i, e.id, e.extended);
    }
    i
}

/// Whether a frame on an NMT error control or SDO id can change more than
/// the input's first and last time: only boot-ups, and only SDO frames
/// naming an object the decoder follows. Heartbeats and SDO traffic for
/// other objects, most frames on those ids, skip all further work.
fn content_matters(id: u32, data: &[u8]) -> bool {
    if emcy::is_nmt_error_control(id) {
        emcy::boot_node(id, data).is_some()
    } else if sdo::is_sdo_id(id) {
        sdo::names_followed_object(id, data)
    } else {
        true
    }
}

/// An EMCY id besides 0x80 + node (`--emcy-id`, or moved by object
/// 0x1014): decoded, and every frame on it matters whatever range it is in.
fn add_emcy_id(interest: &mut Interest, id: u32, extended: bool) {
    add_id(interest, id, extended);
    if !extended {
        interest.unfilter(id);
    }
}

fn add_id(interest: &mut Interest, id: u32, extended: bool) {
    if extended {
        interest.add_extended(id);
    } else {
        interest.add_standard(id);
    }
}

/// An SDO request or response naming object 0x1014 (COB-ID EMCY).
fn is_cob_id_emcy_access(frame: &Frame<'_>) -> bool {
    !frame.extended && sdo::names_object(frame.id, frame.data.as_slice(), sdo::COB_ID_EMCY)
}

/// The current interest and its generation, shared with workers: a block
/// parsed with an older generation is parsed again in order.
type SharedInterest = Arc<RwLock<(u64, Interest)>>;

// ---- classification -----------------------------------------------------------

/// A frame read in another format than the file's: (its format, the file's).
type Foreign = Option<(Format, Format)>;

/// Receives classified lines; `idx` is the line's 0-based index in its block.
trait LineSink {
    /// The ids to decode now (the consumer's can change mid-input).
    fn interest(&self) -> &Interest;
    /// Valid frames the consumer has no use for: counted only.
    fn plain_frames(&mut self, n: u64);
    /// `n` wanted frames that only move the input's first/last time (see
    /// [`content_matters`]), the first and last of their times.
    fn timed_frames(&mut self, n: u64, first: Timestamp, last: Timestamp);
    fn frame(&mut self, idx: u64, frame: &Frame<'_>, foreign: Foreign) -> Result<(), OutputError>;
    fn skipped(&mut self);
    fn malformed(&mut self, idx: u64, reason: Reason);
    fn lines(&mut self, n: u64);
}

fn too_long(n: u64, max_line: usize) -> Reason {
    format!("line of {n} bytes is longer than the {max_line} byte limit; skipped").into()
}

/// The one loop that classifies lines, sequentially or on a worker: runs
/// of common lines through the parser's hot loop, anything else a line at
/// a time.
fn classify_block(
    block: &Block,
    max_line: usize,
    detector: &mut Detector,
    sink: &mut impl LineSink,
) -> Result<(), OutputError> {
    let bytes = block.text();
    let mut idx = 0u64;
    let mut pos = 0usize;
    if let Some(n) = block.too_long_before {
        sink.malformed(idx, too_long(n, max_line));
        idx += 1;
    }
    loop {
        let run = detector.run(
            bytes.get(pos..).unwrap_or_default(),
            max_line,
            sink.interest(),
        );
        pos += run.bytes;
        if run.plain > 0 {
            sink.plain_frames(run.plain);
            idx += run.plain;
        }
        if let (Some(first), Some(last)) = (run.first_time, run.last_time) {
            sink.timed_frames(run.timed, first, last);
            idx += run.timed;
        }
        if let Some(frame) = run.frame {
            deliver(sink, idx, &frame, None)?;
            idx += 1;
            continue;
        }
        let Some((raw, next)) = lines::line_at(bytes, pos, max_line) else {
            break;
        };
        pos = next;
        match raw {
            RawLine::TooLong(n) => sink.malformed(idx, too_long(n, max_line)),
            RawLine::Text(text) => match detector.scan(text, sink.interest()) {
                Scan::Plain => sink.plain_frames(1),
                Scan::Timed(t) => sink.timed_frames(1, t, t),
                Scan::Frame(frame) => deliver(sink, idx, &frame, None)?,
                Scan::Parse => match detector.parse(text, sink.interest()) {
                    Parsed::Frame(frame) => {
                        let foreign = detector.take_foreign().zip(detector.format());
                        deliver(sink, idx, &frame, foreign)?;
                    }
                    Parsed::Skipped => sink.skipped(),
                    Parsed::Malformed(reason) => sink.malformed(idx, reason),
                },
            },
        }
        idx += 1;
    }
    sink.lines(idx);
    Ok(())
}

/// Hands a frame on as the consumer treats it: one it has no use for is
/// only counted, one that only moves the input's first/last time only timed
/// (so workers record neither); the rest, and every frame in another format
/// than the file's (its line gets a diagnostic), go to `frame`, which
/// applies the same rules in full.
fn deliver(
    sink: &mut impl LineSink,
    idx: u64,
    frame: &Frame<'_>,
    foreign: Foreign,
) -> Result<(), OutputError> {
    if foreign.is_none() {
        let interest = sink.interest();
        if frame.kind != FrameKind::Data || !interest.wants(frame.id, frame.extended) {
            sink.plain_frames(1);
            return Ok(());
        }
        if let Some(t) = frame.time
            && interest.timed_only(frame.id, frame.extended, frame.data.as_slice())
        {
            sink.timed_frames(1, t, t);
            return Ok(());
        }
    }
    sink.frame(idx, frame, foreign)
}

// ---- the consumer: timelines, events, counts, diagnostics ---------------------------

/// Per-channel node timelines. Channels are usually few, but every distinct
/// interface name in the trace is one, so a hostile trace can name a million:
/// lookup is hashed and a channel holds only the nodes it has seen, keeping
/// time and memory linear in the input.
struct Nodes {
    channels: Vec<ChannelNodes>,
    index: HashMap<Vec<u8>, usize>,
    /// Channels by name. Different bytes can read as one name (invalid
    /// UTF-8 becomes U+FFFD); reports and the history know a channel by its
    /// name, so those bytes are one channel.
    by_name: HashMap<String, usize>,
    /// The channel of the previous lookup: nearly every trace has one or two.
    last: Option<usize>,
    /// Closed intervals of every node (timelines keep only active ones).
    history: History,
}

struct ChannelNodes {
    raw: Vec<u8>,
    name: String,
    /// The channel's index in the history.
    id: u32,
    /// Sorted by node id (1..=127).
    nodes: Vec<(u8, NodeTimeline)>,
}

/// A node's timeline, borrowed with what an event needs around it.
struct NodeSlot<'n> {
    channel: &'n str,
    channel_id: u32,
    timeline: &'n mut NodeTimeline,
    history: &'n mut History,
}

impl Nodes {
    fn new(spill_at: usize) -> Self {
        Nodes {
            channels: Vec::new(),
            index: HashMap::new(),
            by_name: HashMap::new(),
            last: None,
            history: History::new(spill_at),
        }
    }

    fn get(&mut self, raw: &[u8], node: u8) -> NodeSlot<'_> {
        let cached = self.last.filter(|&i| {
            self.channels
                .get(i)
                .is_some_and(|c| c.raw.as_slice() == raw)
        });
        let idx = match cached.or_else(|| self.index.get(raw).copied()) {
            Some(i) => i,
            None => {
                let name = String::from_utf8_lossy(raw).into_owned();
                let i = match self.by_name.get(&name) {
                    Some(&i) => i,
                    None => {
                        let id = self.history.add_channel(&name);
                        self.by_name.insert(name.clone(), self.channels.len());
                        self.channels.push(ChannelNodes {
                            raw: raw.to_vec(),
                            name,
                            id,
                            nodes: Vec::new(),
                        });
                        self.channels.len() - 1
                    }
                };
                self.index.insert(raw.to_vec(), i);
                i
            }
        };
        self.last = Some(idx);
        let Nodes {
            channels, history, ..
        } = self;
        let ch = &mut channels[idx];
        let slot = match ch.nodes.binary_search_by_key(&node, |(n, _)| *n) {
            Ok(i) => i,
            Err(i) => {
                ch.nodes.insert(i, (node, NodeTimeline::new()));
                i
            }
        };
        NodeSlot {
            channel: &ch.name,
            channel_id: ch.id,
            timeline: &mut ch.nodes[slot].1,
            history,
        }
    }

    /// Node reports sorted by channel name, then node, and the history with
    /// the still-active intervals added.
    fn into_reports(self, opts: &Options) -> (Vec<NodeReport>, ErrorHistory) {
        let mut out = Vec::new();
        let mut open = Vec::new();
        let mut channels = self.channels;
        channels.sort_by(|a, b| a.name.cmp(&b.name));
        for ch in channels {
            for (node, tl) in ch.nodes {
                open.extend(tl.active().iter().map(|iv| Record {
                    channel: ch.id,
                    node,
                    interval: iv.clone(),
                }));
                if !opts.selects(&ch.name, node) {
                    continue;
                }
                out.push(NodeReport {
                    channel: ch.name.clone(),
                    node,
                    state: tl.state(),
                    active: tl.active_codes().collect(),
                    emcy_count: tl.emcy_count(),
                    stats: tl.stats().clone(),
                    profile: default_profile(),
                    profile_source: ProfileSource::Default,
                    profile_reason: None,
                });
            }
        }
        (out, self.history.finish(open))
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

/// Turns classified lines into timelines, events and counts, in line order.
struct Consumer<'r, 'l, E: Write> {
    file: &'r str,
    opts: &'r Options,
    renderer: &'r mut dyn Renderer,
    log: &'l mut DiagnosticLog<E>,
    counts: Counts,
    nodes: Nodes,
    diags: InputDiagnostics,
    errors_raised: u64,
    frames_with_warnings: u64,
    worst_category: Option<u8>,
    decided: bool,
    /// Lines before the current block.
    line_base: u64,
    /// Time and line of the last EMCY or boot-up: the trace's clock as far
    /// as the timelines see it.
    clock: Option<(Timestamp, u64)>,
    /// EMCY ids other than 0x80 + node, to their node.
    emcy_ids: HashMap<(u32, bool), u8>,
    /// First and last time of a decoded frame.
    first_time: Option<Timestamp>,
    last_time: Option<Timestamp>,
    interest: Interest,
    interest_gen: u64,
    /// Set while workers run: where they read the interest from.
    shared_interest: Option<SharedInterest>,
    warnings: Vec<Warning>,
    active: Vec<u16>,
    sdo: sdo::Tracker,
    profiles: NodeProfiles<'r>,
    /// The last timeline step, handed back for its vectors.
    step_buffers: Step,
    /// Code table entries by (profile, code): the profile's lookup goes
    /// through a thread-local cache whose access and by-value copy showed
    /// as stalls on this thread.
    infos: Cache<(usize, u16), CodeInfo, 64>,
}

impl<E: Write> Consumer<'_, '_, E> {
    fn line_no(&self, idx: u64) -> u64 {
        self.line_base + idx + 1
    }

    /// The node a data frame's EMCY id belongs to: a moved id first, then
    /// the pre-defined set (standard ids 0x081-0x0FF).
    fn emcy_node(&self, id: u32, extended: bool) -> Option<u8> {
        self.emcy_ids
            .get(&(id, extended))
            .copied()
            .or_else(|| if extended { None } else { emcy::emcy_node(id) })
    }

    /// A node holds `value` in `object` (SDO upload or confirmed download).
    fn object_value(&mut self, node: u8, object: sdo::Object, value: u32) {
        self.profiles.object_value(node, object, value);
        if object.index == sdo::COB_ID_EMCY
            && object.sub == 0
            && let Some((id, extended)) = sdo::cob_id_emcy(value)
        {
            self.map_emcy_id(id, extended, node);
        }
    }

    /// A node's EMCY id moved (object 0x1014 seen in the trace): decode
    /// frames on it from here on.
    fn map_emcy_id(&mut self, id: u32, extended: bool, node: u8) {
        if self.emcy_ids.insert((id, extended), node) == Some(node) {
            return;
        }
        add_emcy_id(&mut self.interest, id, extended);
        self.interest_gen += 1;
        if let Some(shared) = &self.shared_interest
            && let Ok(mut w) = shared.write()
        {
            *w = (self.interest_gen, self.interest.clone());
        }
    }

    /// A frame was read: the format is known, held diagnostics go out.
    fn decide(&mut self) {
        if !self.decided {
            self.decided = true;
            self.diags.release(self.log);
        }
    }

    /// A wanted frame's time: the input's first and last time.
    fn time(&mut self, t: Timestamp) {
        self.first_time.get_or_insert(t);
        self.last_time = Some(t);
    }

    /// A time earlier than the previous EMCY's or boot-up's (two logs
    /// concatenated, a clock reset) gets a diagnostic: durations across this
    /// line come out negative, and the user should know why.
    fn check_clock(&mut self, at: At) {
        let Some(time) = at.time else { return };
        if let Some((previous, line)) = self.clock
            && time.since(previous).is_negative()
        {
            self.diags.report(
                self.log,
                self.decided,
                at.line,
                format!(
                    "time {time} is earlier than {previous} at line {line}: the trace's clock \
                     went backwards (durations across this line are negative)"
                ),
            );
        }
        self.clock = Some((time, at.line));
    }
}

impl<E: Write> LineSink for Consumer<'_, '_, E> {
    fn interest(&self) -> &Interest {
        &self.interest
    }

    fn plain_frames(&mut self, n: u64) {
        self.counts.frames += n;
        self.decide();
    }

    fn timed_frames(&mut self, n: u64, first: Timestamp, last: Timestamp) {
        self.counts.frames += n;
        self.decide();
        self.time(first);
        self.time(last);
    }

    fn lines(&mut self, n: u64) {
        self.counts.lines += n;
        self.line_base += n;
    }

    fn skipped(&mut self) {
        self.counts.skipped += 1;
    }

    fn malformed(&mut self, idx: u64, reason: Reason) {
        self.counts.malformed += 1;
        let line = self.line_no(idx);
        self.diags
            .report(self.log, self.decided, line, reason.into_owned());
    }

    fn frame(&mut self, idx: u64, frame: &Frame<'_>, foreign: Foreign) -> Result<(), OutputError> {
        self.counts.frames += 1;
        let line_no = self.line_no(idx);
        self.decide();
        if let Some((other, primary)) = foreign {
            self.counts.other_format += 1;
            let msg = format!(
                "line is in {} format, not {} like the rest; read anyway",
                other.name(),
                primary.name()
            );
            self.diags.report(self.log, true, line_no, msg);
        }
        if frame.kind != FrameKind::Data {
            return Ok(());
        }
        // Only wanted ids count: workers may hand over frames the sequential
        // reader only counts, and the result must not depend on the path.
        if !self.interest.wants(frame.id, frame.extended) {
            return Ok(());
        }
        if let Some(t) = frame.time {
            self.time(t);
        }
        if self
            .interest
            .timed_only(frame.id, frame.extended, frame.data.as_slice())
        {
            return Ok(());
        }
        let at = At {
            time: frame.time,
            line: line_no,
        };
        let data = frame.data.as_slice();
        if let Some(node) = self.emcy_node(frame.id, frame.extended) {
            let emcy = match Emcy::decode(data) {
                Ok(e) => e,
                Err(short) => {
                    self.counts.emcy_invalid += 1;
                    self.diags
                        .report(self.log, true, line_no, format!("node {node}: {short}"));
                    return Ok(());
                }
            };
            self.counts.emcy += 1;
            self.check_clock(at);
            let chosen = self.profiles.get(node);
            let profile = chosen.profile;
            let (key, slot) = profile_code_key(profile, emcy.code);
            let looked_up;
            let info = match self.infos.get(key, slot, || profile.info(emcy.code)) {
                Some(info) => info,
                None => {
                    looked_up = profile.info(emcy.code);
                    &looked_up
                }
            };
            self.warnings.clear();
            emcy.frame_warnings(info, &mut self.warnings);
            profile.frame_warnings(&emcy, &mut self.warnings);
            let NodeSlot {
                channel,
                channel_id,
                timeline,
                history,
            } = self.nodes.get(frame.channel, node);
            let step = timeline.apply(
                &emcy,
                at,
                profile.status_bit(&emcy),
                &mut self.warnings,
                std::mem::take(&mut self.step_buffers),
            );
            for iv in &step.closed {
                history.push(channel_id, node, iv.clone());
            }
            if !self.opts.selects(channel, node) {
                self.step_buffers = step;
                return Ok(());
            }
            if !emcy.is_reset() {
                self.errors_raised += 1;
                if let Some(c) = profile.category(&emcy) {
                    self.worst_category = Some(self.worst_category.map_or(c, |w| w.min(c)));
                }
            }
            if !self.warnings.is_empty() {
                self.frames_with_warnings += 1;
            }
            self.active.clear();
            self.active.extend(timeline.active_codes());
            let decoded = profile.decode_manufacturer(&emcy);
            let event = EmcyEvent {
                file: self.file,
                line: line_no,
                time: frame.time,
                channel,
                node,
                cob_id: frame.id,
                data,
                emcy: &emcy,
                info,
                transition: step.transition,
                state: step.state,
                active: &self.active,
                cleared: &step.cleared,
                warnings: &self.warnings,
                profile: chosen,
                decoded: decoded.as_ref(),
            };
            self.renderer.emcy(&event).map_err(OutputError)?;
            self.step_buffers = step;
        } else if frame.extended {
            return Ok(());
        } else if let Some(access) = sdo::parse(frame.id, data) {
            if let Some((node, object, value)) = self.sdo.feed(access) {
                self.object_value(node, object, value);
            }
        } else if let Some(node) = emcy::boot_node(frame.id, data) {
            self.counts.boot += 1;
            self.check_clock(at);
            let NodeSlot {
                channel,
                channel_id,
                timeline,
                history,
            } = self.nodes.get(frame.channel, node);
            let closed = timeline.boot(at);
            let cleared: Vec<u16> = closed.iter().map(|iv| iv.code).collect();
            for iv in closed {
                history.push(channel_id, node, iv);
            }
            if self.opts.selects(channel, node) {
                let event = BootEvent {
                    file: self.file,
                    line: line_no,
                    time: frame.time,
                    channel,
                    node,
                    cleared: &cleared,
                };
                self.renderer.boot(&event).map_err(OutputError)?;
            }
        }
        Ok(())
    }
}

// ---- worker records -------------------------------------------------------------

/// What a worker keeps of a line for the consumer.
enum BlockRecord {
    Frame {
        idx: u64,
        time: Option<Timestamp>,
        channel: Range<usize>,
        id: u32,
        kind: FrameKind,
        extended: bool,
        len: u8,
        data: Payload,
        foreign: Foreign,
    },
    Malformed {
        idx: u64,
        reason: Reason,
    },
    /// A wanted frame that only moves the input's first/last time (already
    /// counted in `plain_frames`).
    Time(Timestamp),
}

/// A worker's summary of one block.
struct BlockResult {
    seq: u64,
    /// The worker that read and parsed it, which gets the buffer back.
    worker: usize,
    block: Block,
    /// The detector state the block was parsed from, and the one after it.
    start_context: Option<u64>,
    /// The interest generation it was parsed with.
    interest_gen: u64,
    /// The block holds an SDO access to 0x1014 (COB-ID EMCY): the wanted ids
    /// may change inside it, so it is classified again in order.
    moves_emcy_id: bool,
    end: Detector,
    lines: u64,
    /// Frames the consumer would ignore (not EMCY/boot candidates), counted only.
    plain_frames: u64,
    skipped: u64,
    /// Malformed lines beyond the diagnostics limit: counted, not reported.
    unreported: u64,
    records: Vec<BlockRecord>,
    /// Channel names of the frame records, back to back.
    channels: Vec<u8>,
}

/// The worker-side sink: keeps only what the consumer needs.
struct Recorder {
    interest: Interest,
    /// Frames that only move the input's first/last time are collapsed: the
    /// block's first one is recorded, of each later run only the last.
    time_kept: bool,
    time_pending: Option<Timestamp>,
    limit: usize,
    result: BlockResult,
    malformed_kept: usize,
}

impl LineSink for Recorder {
    fn interest(&self) -> &Interest {
        &self.interest
    }

    fn plain_frames(&mut self, n: u64) {
        self.result.plain_frames += n;
    }

    fn timed_frames(&mut self, n: u64, first: Timestamp, last: Timestamp) {
        self.result.plain_frames += n;
        self.time_only(first);
        self.time_only(last);
    }

    fn lines(&mut self, n: u64) {
        self.result.lines += n;
    }

    fn skipped(&mut self) {
        self.result.skipped += 1;
    }

    fn malformed(&mut self, idx: u64, reason: Reason) {
        // The consumer shows at most `limit` per input, in line order, so no
        // block needs to keep more than that.
        if self.malformed_kept < self.limit {
            self.malformed_kept += 1;
            self.result
                .records
                .push(BlockRecord::Malformed { idx, reason });
        } else {
            self.result.unreported += 1;
        }
    }

    fn frame(&mut self, idx: u64, frame: &Frame<'_>, foreign: Foreign) -> Result<(), OutputError> {
        self.flush_time();
        if is_cob_id_emcy_access(frame) {
            self.result.moves_emcy_id = true;
        }
        let start = self.result.channels.len();
        self.result.channels.extend_from_slice(frame.channel);
        self.result.records.push(BlockRecord::Frame {
            idx,
            time: frame.time,
            channel: start..self.result.channels.len(),
            id: frame.id,
            kind: frame.kind,
            extended: frame.extended,
            len: frame.len,
            data: frame.data.clone(),
            foreign,
        });
        Ok(())
    }
}

impl Recorder {
    /// A time-only frame's time: the block's first is recorded, of each
    /// later run only the last (see [`Recorder::flush_time`]).
    fn time_only(&mut self, t: Timestamp) {
        if self.time_kept {
            self.time_pending = Some(t);
        } else {
            self.time_kept = true;
            self.result.records.push(BlockRecord::Time(t));
        }
    }

    /// Records the last time of a run of time-only frames (before the next
    /// frame record, and at the end of the block).
    fn flush_time(&mut self) {
        if let Some(t) = self.time_pending.take() {
            self.result.records.push(BlockRecord::Time(t));
        }
    }
}

impl<E: Write> Consumer<'_, '_, E> {
    /// Replays a worker's block result as if its lines had been read here.
    fn replay(&mut self, r: BlockResult) -> Result<Block, OutputError> {
        self.counts.frames += r.plain_frames;
        self.counts.skipped += r.skipped;
        self.counts.malformed += r.unreported;
        self.diags.suppressed += r.unreported;
        for record in r.records {
            match record {
                BlockRecord::Malformed { idx, reason } => self.malformed(idx, reason),
                BlockRecord::Time(t) => self.time(t),
                BlockRecord::Frame {
                    idx,
                    time,
                    channel,
                    id,
                    kind,
                    extended,
                    len,
                    data,
                    foreign,
                } => {
                    let frame = Frame {
                        time,
                        channel: r.channels.get(channel).unwrap_or_default(),
                        id,
                        extended,
                        kind,
                        len,
                        data,
                    };
                    self.frame(idx, &frame, foreign)?;
                }
            }
        }
        self.lines(r.lines);
        Ok(r.block)
    }
}

// ---- drivers ---------------------------------------------------------------------

/// Opens one source and reads it to the end ([`analyze`]); what stops it
/// (it cannot be opened, or reading failed part way) goes to the log as
/// `error: NAME: reason`. `None` when the source could not be opened.
/// `threads` picks the thread count from what was opened; `wrap` may wrap
/// the (decompressed) reader, e.g. to count progress.
pub fn analyze_source<E: Write>(
    source: &Source,
    mode: ReadMode,
    opts: &Options,
    threads: impl FnOnce(&Opened) -> usize,
    wrap: impl FnOnce(&Opened, Box<dyn Read + Send>) -> Box<dyn Read + Send>,
    renderer: &mut dyn Renderer,
    log: &mut DiagnosticLog<E>,
) -> Result<Option<Analysis>, OutputError> {
    let name = source.display_name();
    let mut opened = match input::open_as(source, mode) {
        Ok(o) => o,
        Err(e) => {
            log.error(&format!("{name}: {}", describe_io(&e)));
            return Ok(None);
        }
    };
    let input_opts = Options {
        threads: threads(&opened),
        ..opts.clone()
    };
    let reader = std::mem::replace(&mut opened.reader, Box::new(io::empty()));
    let reader = wrap(&opened, reader);
    let analysis = analyze(&name, reader, opened.gzip, &input_opts, renderer, log)?;
    if let Some(err) = &analysis.report.error {
        log.error(&format!("{name}: {err}"));
    }
    Ok(Some(analysis))
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
    renderer: &mut dyn Renderer,
    log: &mut DiagnosticLog<E>,
) -> Result<Analysis, OutputError> {
    renderer.begin_input(file).map_err(OutputError)?;
    let mut detector = match opts.input_format {
        Some(f) => Detector::forced(f),
        None => Detector::auto(),
    };
    let mut consumer = Consumer {
        file,
        opts,
        renderer,
        decided: detector.format().is_some(),
        log,
        counts: Counts::default(),
        nodes: Nodes::new(opts.spill_at),
        diags: InputDiagnostics {
            file: file.to_string(),
            limit: opts.max_diagnostics,
            shown: 0,
            suppressed: 0,
            pending: Vec::new(),
        },
        errors_raised: 0,
        frames_with_warnings: 0,
        worst_category: None,
        line_base: 0,
        clock: None,
        first_time: None,
        last_time: None,
        emcy_ids: opts
            .emcy_ids
            .iter()
            .map(|e| ((e.id, e.extended), e.node))
            .collect(),
        interest: interest(opts),
        interest_gen: 0,
        shared_interest: None,
        warnings: Vec::new(),
        active: Vec::new(),
        sdo: sdo::Tracker::default(),
        profiles: NodeProfiles::new(&opts.profiles),
        step_buffers: Step::default(),
        infos: Cache::default(),
    };

    // BLF is binary: known by its magic (or forced), read object by object.
    let (reader, magic) = blf::sniff(reader);
    match magic {
        Err(e) => return finish(consumer, None, gzip, Some(e.to_string())),
        Ok(magic) if opts.input_format.map_or(magic, |f| f == Format::Blf) => {
            consumer.decided = true;
            let error = read_blf(reader, &mut consumer)?;
            return finish(consumer, Some(Format::Blf), gzip, error);
        }
        Ok(_) => {}
    }
    let mut blocks = BlockReader::new(reader, opts.block_size, opts.max_line);

    // Sequential until the format is known (and for inputs whose lines chain,
    // or when one thread was asked for); then, if allowed, in parallel.
    let mut error = None;
    let mut buf = Vec::new();
    let format = loop {
        if opts.threads > 1 && detector.format().is_some() && detector.context().is_some() {
            let (read_error, detector) = parallel(blocks, detector, &mut consumer)?;
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
    finish(consumer, format, gzip, error)
}

/// Vector BLF into the same consumer: each object counts as a line, its
/// index in reading order is its line number.
fn read_blf<R: Read, E: Write>(
    reader: R,
    consumer: &mut Consumer<'_, '_, E>,
) -> Result<Option<String>, OutputError> {
    let mut reader = match blf::BlfReader::new(reader) {
        Ok(r) => r,
        Err(e) => return Ok(Some(e.to_string())),
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
            Err(e) => return Ok(Some(e.to_string())),
        }
        consumer.lines(1);
    }
}

fn finish<E: Write>(
    mut consumer: Consumer<'_, '_, E>,
    format: Option<Format>,
    gzip: bool,
    mut error: Option<String>,
) -> Result<Analysis, OutputError> {
    let file = consumer.file;
    if format.is_none() && consumer.counts.malformed > 0 && error.is_none() {
        error = Some(
            "cannot detect the trace format: no line is a candump log, candump screen, \
             Vector ASC or PEAK TRC frame and the input is not BLF (force one with \
             --input-format candump|candump-screen|asc|trc|blf)"
                .to_string(),
        );
    } else {
        consumer.diags.release(consumer.log);
        if consumer.diags.suppressed > 0 {
            consumer.log.note(&format!(
                "{file}: {} more diagnostics not shown (--max-diagnostics {})",
                consumer.diags.suppressed, consumer.opts.max_diagnostics
            ));
        }
    }
    let nodes_taken = std::mem::replace(&mut consumer.nodes, Nodes::new(1));
    let (mut nodes, history) = nodes_taken.into_reports(consumer.opts);
    for n in &mut nodes {
        let chosen = consumer.profiles.get(n.node);
        n.profile = chosen.profile;
        n.profile_source = chosen.source;
        n.profile_reason = consumer.profiles.reason(n.node).map(str::to_string);
    }
    if let Some(e) = history.spill_error() {
        consumer.log.note(&format!(
            "{file}: could not move the error history to a temporary file ({e}); kept in memory"
        ));
    }
    let report = InputReport {
        first_time: consumer.first_time,
        last_time: consumer.last_time,
        file: file.to_string(),
        format,
        gzip,
        counts: consumer.counts,
        nodes,
        history,
        error,
    };
    consumer.renderer.end_input(&report).map_err(OutputError)?;
    Ok(Analysis {
        report,
        errors_raised: consumer.errors_raised,
        frames_with_warnings: consumer.frames_with_warnings,
        worst_category: consumer.worst_category,
    })
}

enum Message {
    Result(Box<BlockResult>),
    /// Reading failed after `seq` blocks.
    ReadError(u64, io::Error),
}

/// Workers classify blocks; the calling thread consumes their results in
/// order. A block whose start state differs from the state the previous
/// block ended in (an ASC header changed the base mid-file), or that was
/// parsed for an older set of wanted ids (an EMCY id moved by 0x1014), is
/// classified again here, so the result never depends on the split. Returns
/// the read error, if any, and the detector's final state.
fn parallel<R: Read + Send, E: Write>(
    blocks: BlockReader<R>,
    detector: Detector,
    consumer: &mut Consumer<'_, '_, E>,
) -> Result<(Option<String>, Detector), OutputError> {
    let threads = consumer.opts.threads.max(1);
    let max_line = consumer.opts.max_line;
    let limit = consumer.opts.max_diagnostics;
    let mut current = detector;
    let shared: SharedInterest = Arc::new(RwLock::new((
        consumer.interest_gen,
        consumer.interest.clone(),
    )));
    consumer.shared_interest = Some(Arc::clone(&shared));
    let feed = Mutex::new(Feed {
        blocks,
        seq: 0,
        done: false,
    });
    let feed = &feed;
    let outcome = std::thread::scope(|scope| {
        let (result_tx, result_rx) = mpsc::channel::<Message>();
        let mut recycle = Vec::new();
        for worker in 0..threads {
            let (recycle_tx, recycle_rx) = mpsc::channel::<Vec<u8>>();
            recycle.push(recycle_tx);
            let mut det = current.fork();
            let tx = result_tx.clone();
            let shared = Arc::clone(&shared);
            scope.spawn(move || {
                let mut out = 0usize;
                while let Some((seq, block)) = next_job(feed, &recycle_rx, &mut out, &tx) {
                    let start_context = det.context();
                    let Ok((interest_gen, interest)) = shared.read().map(|g| g.clone()) else {
                        return;
                    };
                    let mut rec = Recorder {
                        interest,
                        limit,
                        time_kept: false,
                        time_pending: None,
                        malformed_kept: 0,
                        result: BlockResult {
                            seq,
                            worker,
                            block: Block::default(),
                            start_context,
                            interest_gen,
                            moves_emcy_id: false,
                            end: det.fork(),
                            lines: 0,
                            plain_frames: 0,
                            skipped: 0,
                            unreported: 0,
                            records: Vec::new(),
                            channels: Vec::new(),
                        },
                    };
                    // A recorder never fails: it only collects.
                    let _ = classify_block(&block, max_line, &mut det, &mut rec);
                    rec.flush_time();
                    let mut result = rec.result;
                    result.end = det.fork();
                    result.block = block;
                    if tx.send(Message::Result(Box::new(result))).is_err() {
                        return;
                    }
                }
            });
        }
        drop(result_tx);

        consume_in_order(result_rx, &recycle, &mut current, consumer, max_line)
    });
    consumer.shared_interest = None;
    outcome.map(|error| (error, current))
}

/// The input, read a block at a time by whichever worker is free. The
/// worker that reads a block parses it, into a buffer it had before: no
/// reader thread, and the bytes are in the parsing core's cache (no faster
/// on the 2-core CI machine than a reader thread, but 4 blocks in flight
/// instead of 5: peak memory on a 30% EMCY trace 24 -> 17 MiB).
struct Feed<R> {
    blocks: BlockReader<R>,
    seq: u64,
    done: bool,
}

/// Blocks a worker may have out at once: one being parsed, one waiting to
/// be consumed. A block comes back (recycled) once consumed; waiting for
/// one keeps a slow consumer (30% EMCY) from letting parsed blocks pile up
/// in memory. A parsed EMCY-heavy block holds about as much in records as
/// in text (~1 MiB each), so this limit is what peak memory is made of.
const BLOCKS_PER_WORKER: usize = 2;

/// The next block for a worker, read into a buffer it had before; `None`
/// at the end of the input or after a read error (sent to the consumer).
fn next_job<R: Read>(
    feed: &Mutex<Feed<R>>,
    recycled: &Receiver<Vec<u8>>,
    out: &mut usize,
    tx: &mpsc::Sender<Message>,
) -> Option<(u64, Block)> {
    let buf = match recycled.try_recv() {
        Ok(b) => Some(b),
        Err(_) if *out < BLOCKS_PER_WORKER => None,
        Err(_) => Some(recycled.recv().ok()?),
    };
    let buf = match buf {
        Some(b) => {
            *out -= 1;
            b
        }
        None => Vec::new(),
    };
    let mut feed = feed.lock().ok()?;
    if feed.done {
        return None;
    }
    match feed.blocks.next_block(buf) {
        Ok(Some(block)) => {
            let seq = feed.seq;
            feed.seq += 1;
            *out += 1;
            Some((seq, block))
        }
        Ok(None) => {
            feed.done = true;
            None
        }
        Err(e) => {
            feed.done = true;
            let _ = tx.send(Message::ReadError(feed.seq, e));
            None
        }
    }
}

fn consume_in_order<E: Write>(
    results: Receiver<Message>,
    recycle: &[mpsc::Sender<Vec<u8>>],
    current: &mut Detector,
    consumer: &mut Consumer<'_, '_, E>,
    max_line: usize,
) -> Result<Option<String>, OutputError> {
    let mut next = 0u64;
    let mut pending: BTreeMap<u64, BlockResult> = BTreeMap::new();
    let mut read_error: Option<(u64, io::Error)> = None;
    for message in results {
        match message {
            Message::Result(r) => {
                pending.insert(r.seq, *r);
            }
            Message::ReadError(seq, e) => read_error = Some((seq, e)),
        }
        while let Some(r) = pending.remove(&next) {
            let r_worker = r.worker;
            let valid = r.start_context.is_some()
                && r.start_context == current.context()
                && r.interest_gen == consumer.interest_gen
                && !r.moves_emcy_id;
            let block = if valid {
                let mut r = r;
                std::mem::swap(current, &mut r.end);
                consumer.replay(r)?
            } else {
                classify_block(&r.block, max_line, current, consumer)?;
                r.block
            };
            if let Some(worker) = recycle.get(r_worker) {
                let _ = worker.send(block.bytes);
            }
            next += 1;
        }
    }
    Ok(read_error.map(|(_, e)| e.to_string()))
}
