//! The consumer: the dispatcher that turns classified lines into counts
//! and hands each decoded frame to the monitors ([`monitor`]), in line
//! order. It owns what every monitor shares: the node table, the facts
//! they learnt, the input's counts, diagnostics and wanted ids.
//!
//! [`monitor`]: super::monitor

use std::collections::HashMap;
use std::io::Write;

use super::analysis::{Analysis, OutputError, Reading};
use super::bus::{MAX_CHANNELS, Told};
use super::classify::{FoldedRun, Foreign, LineSink};
use super::diagnostics::{DiagnosticLog, InputDiagnostics};
use super::event::{Bus, CodeTexts, Counts, EvidenceKind, InputReport};
use super::incident::Builder;
use super::interest::{Wanted, interest};
use super::monitor::context::{Emit, Fact, Facts, Learnt, Seen, Step};
use super::monitor::{Carried, Monitors, TakenFold};
use super::nodes::Nodes;
use super::options::Options;
use super::sink::Sink;
use super::traffic::{FrameTime, SyncMissed, Traffic};
use crate::canopen::profile::Profile;
use crate::canopen::{NodeId, emcy};
use crate::timeline::At;
use crate::trace::can_error::ErrorFrame;
use crate::trace::deltas::TimeMode;
use crate::trace::ethercat::CoeMessage;
use crate::trace::{
    FoldBuffers, Format, Frame, FrameKind, IdCounts, Interest, Reason, TimedLine, Timestamp,
};

/// Turns classified lines into timelines, events and counts, in line order.
pub(super) struct Consumer<'r, 'l, E: Write> {
    pub(super) file: &'r str,
    pub(super) opts: &'r Options,
    sink: &'r mut dyn Sink,
    pub(super) log: &'l mut DiagnosticLog<E>,
    pub(super) counts: Counts,
    pub(super) diags: InputDiagnostics,
    pub(super) decided: bool,
    /// Set when candump times are summed as deltas: said in the report.
    pub(super) timestamps: Option<TimeMode>,
    /// Lines before the current block.
    line_base: u64,
    /// First and last time of a decoded frame.
    first_time: Option<Timestamp>,
    last_time: Option<Timestamp>,
    /// First and last time of any frame, decoded or not, in line order:
    /// with the decoded ones', the input's span.
    frame_times: (Option<Timestamp>, Option<Timestamp>),
    /// The ids decoded now, and where the workers read them.
    pub(super) wanted: Wanted,
    pub(super) nodes: Nodes,
    pub(super) facts: Facts<'r>,
    pub(super) monitors: Monitors,
    /// Buffers of the fold fast path, reused from run to run.
    pub(super) taken_as: Vec<TakenFold>,
    pub(super) rebounds: Vec<(u32, Option<Timestamp>)>,
    /// The frames being taken are a folded run's, timed already as the
    /// lines it handed over (with `--timing` the reader hands over every
    /// folded line): the traffic does not time them again.
    pub(super) timed_as_lines: bool,
    /// The last block's fold vectors, for the next.
    spare_folds: FoldBuffers,
    /// How workers read the input, if they did.
    pub(super) reading: Reading,
    /// Bus events to tell, reused.
    told: Vec<Told>,
    pub(super) incidents: Builder,
    pub(super) traffic: Traffic,
    /// Every frame of the input by channel and id (the readers count
    /// those they only count; the classifier the rest).
    pub(super) ids: IdCounts,
    /// The bit rate the input records (a trace header), known at its end.
    pub(super) recorded_bit_rate: Option<u32>,
}

/// The monitors, the node table, the shared facts and an [`Emit`] over the
/// consumer's output, borrowed apart from one consumer.
macro_rules! parts {
    ($c:expr) => {
        (
            &mut $c.monitors,
            &mut $c.nodes,
            &$c.facts,
            &mut Emit {
                file: $c.file,
                opts: $c.opts,
                sink: &mut *$c.sink,
                log: &mut *$c.log,
                diags: &mut $c.diags,
                decided: $c.decided,
                summed_deltas: $c.timestamps.is_some(),
                counts: &mut $c.counts,
                wanted: &mut $c.wanted,
                incidents: &mut $c.incidents,
            },
        )
    };
}

impl<'r, 'l, E: Write> Consumer<'r, 'l, E> {
    pub(super) fn new(
        file: &'r str,
        opts: &'r Options,
        sink: &'r mut dyn Sink,
        log: &'l mut DiagnosticLog<E>,
        decided: bool,
    ) -> Self {
        let monitors = Monitors::new(opts);
        let mut ids = interest(opts);
        monitors.interest(&mut ids);
        Consumer {
            file,
            opts,
            sink,
            decided,
            timestamps: None,
            log,
            counts: Counts::default(),
            diags: InputDiagnostics {
                file: file.to_string(),
                limit: opts.max_diagnostics,
                shown: 0,
                suppressed: 0,
                pending: Vec::new(),
            },
            line_base: 0,
            first_time: None,
            last_time: None,
            frame_times: (None, None),
            wanted: Wanted::new(ids, opts.timing),
            nodes: Nodes::new(opts.spill_at, opts.max_nodes),
            facts: Facts::new(opts),
            monitors,
            taken_as: Vec::new(),
            rebounds: Vec::new(),
            timed_as_lines: false,
            spare_folds: FoldBuffers::default(),
            reading: Reading::default(),
            told: Vec::new(),
            incidents: Builder::new(opts.incident_gap),
            traffic: Traffic::new(opts.timing),
            ids: IdCounts::new(),
            recorded_bit_rate: None,
        }
    }

    /// The end of the input: the monitors' ends, held diagnostics, node
    /// reports, the history; the sink gets the input's report.
    pub(super) fn finish(
        mut self,
        format: Option<Format>,
        gzip: bool,
        mut error: Option<String>,
    ) -> Result<Analysis, OutputError> {
        let file = self.file;
        let end = At {
            time: self.last_time,
            line: self.line_base,
        };
        let (monitors, nodes, facts, emit) = parts!(self);
        monitors.finish(end, nodes, facts, emit)?;
        let mut told = std::mem::take(&mut self.told);
        self.facts.bus.finish(&mut told);
        let input_end = self.input_span().1;
        for (channel, gap) in self.traffic.finish(input_end) {
            told.push(Told {
                channel,
                at: gap.start,
                bus: Bus::SyncMissed(gap),
            });
        }
        let (_, _, _, emit) = parts!(self);
        emit.bus(&mut told)?;
        emit.incidents.finish();
        emit.tell_incidents()?;
        if self.incidents.ignored > 0 {
            self.log.note(&format!(
                "{file}: {} fault-like events on channels past the first {} with an open                  incident were not grouped into incidents",
                self.incidents.ignored,
                super::incident::MAX_OPEN
            ));
        }
        let bus = std::mem::take(&mut self.facts.bus);
        if self.ids.others() > 0 {
            self.log.note(&format!(
                "{file}: {} frames on channels past the first {} were not counted per channel",
                self.ids.others(),
                crate::trace::id_counts::MAX_CHANNELS
            ));
        }
        if bus.ignored > 0 {
            self.log.note(&format!(
                "{file}: {} error frames on channels past the first {MAX_CHANNELS} with error \
                 frames were only counted",
                bus.ignored
            ));
        }
        let bus_errors = bus.into_report();
        let nmt_unanswered = self.monitors.nmt.take_unanswered();
        if format.is_none() && self.counts.malformed > 0 && error.is_none() {
            error = Some(
                "cannot detect the trace format: no line is a candump log, candump screen, \
             Vector ASC, PEAK TRC, BUSMASTER or IXXAT MiniMon frame and the input is not BLF, \
             pcap, pcapng or MF4 (force one with --input-format \
             candump|candump-screen|asc|trc|busmaster|ixxat|blf|pcap|mf4)"
                    .to_string(),
            );
        } else {
            self.diags.release(self.log);
            if self.diags.suppressed > 0 {
                self.log.note(&format!(
                    "{file}: {} more diagnostics not shown (--max-diagnostics {})",
                    self.diags.suppressed, self.opts.max_diagnostics
                ));
            }
        }
        let nodes_taken = std::mem::replace(&mut self.nodes, Nodes::new(1, 0));
        let monitors = &self.monitors;
        let (mut nodes, history, unmatched) =
            nodes_taken.into_reports(self.opts, |report, health| {
                monitors.report(report, health);
            });
        if let Some(note) = &unmatched
            && !self.opts.unmatched_filter_fails
        {
            self.log.note(&format!("{file}: {note}"));
        }
        // Nodes that raised the same codes under the same profile share
        // one set of descriptions (a trace with a million channels has a
        // million nodes, nearly all alike).
        let mut shared: HashMap<*const Profile, HashMap<Box<[u16]>, CodeTexts>> = HashMap::new();
        let mut codes = Vec::new();
        for n in &mut nodes {
            let chosen = self.facts.profiles.get(n.node);
            n.profile = chosen.profile;
            n.profile_source = chosen.source;
            n.profile_reason = self.facts.profiles.reason(n.node).map(str::to_string);
            n.device_type = self.facts.profiles.device_type(n.node);
            if let Some(h) = &mut n.error_history {
                for e in &mut h.entries {
                    e.description = n.profile.describe(e.code);
                }
            }
            codes.clear();
            codes.extend(n.stats.raised.keys().copied());
            let same = shared.entry(std::ptr::from_ref(n.profile)).or_default();
            n.descriptions = match same.get(codes.as_slice()) {
                Some(texts) => texts.clone(),
                None => {
                    let texts = CodeTexts::new(n.profile, codes.iter().copied());
                    same.insert(codes.as_slice().into(), texts.clone());
                    texts
                }
            };
        }
        drop(shared);
        if self.counts.dropped > 0 {
            self.log.note(&format!(
                "{file}: warning: candump reported {} dropped by the kernel (DROPCOUNT \
                 lines): EMCYs may be missing",
                match self.counts.dropped {
                    1 => "1 frame".to_string(),
                    n => format!("{n} frames"),
                }
            ));
        }
        if let Some(e) = history.spill_error() {
            self.log.note(&format!(
                "{file}: could not move the error history to a temporary file ({e}); kept in memory"
            ));
        }
        let report = InputReport {
            first_time: self.input_span().0,
            last_time: self.input_span().1,
            timestamps: self.timestamps,
            file: file.to_string(),
            format,
            gzip,
            counts: self.counts,
            nodes,
            history,
            error,
            nmt_unanswered,
            unmatched,
            bus_errors,
            time_producer: self.monitors.lss.time_producer(),
            incident_roots: std::mem::take(&mut self.incidents.roots)
                .into_iter()
                .collect(),
            channels: std::mem::replace(&mut self.traffic, Traffic::new(false))
                .into_report(&self.ids, self.opts.bit_rate.or(self.recorded_bit_rate)),
        };
        self.sink.end_input(&report).map_err(OutputError)?;
        let emcy = &self.monitors.emcy;
        Ok(Analysis {
            report,
            errors_raised: emcy.errors_raised,
            frames_with_warnings: emcy.frames_with_warnings,
            worst_category: emcy.worst_category,
            incidents: self.incidents.told,
            reading: self.reading,
        })
    }

    pub(super) fn line_no(&self, idx: u64) -> u64 {
        self.line_base + idx + 1
    }

    /// What an SDO access (or a CoE message) showed of a node, to the
    /// shared facts first (a profile, a moved EMCY id), then to every
    /// monitor.
    fn learnt(&mut self, channel: &[u8], at: At, learnt: Learnt) -> Result<(), OutputError> {
        if let Some(text) = &learnt.text {
            self.monitors.identity.text(channel, at, text);
        }
        for fact in [learnt.read, learnt.holds, learnt.written, learnt.produced]
            .into_iter()
            .flatten()
        {
            if let Fact::Holds {
                node,
                object,
                value,
                ..
            } = fact
                && let Some((id, extended)) = self.facts.holds(node, object, value)
            {
                self.wanted.add_emcy_id(id, extended);
            }
            let (monitors, nodes, facts, emit) = parts!(self);
            monitors.learn(channel, at, fact, nodes, facts, emit)?;
        }
        Ok(())
    }

    /// A CoE message of an EtherCAT frame (a skipped line, counted by the
    /// caller) at line `idx` of the block: an emergency is an EMCY of the
    /// station, an SDO transfer goes the way of CAN's (identity, aborts,
    /// the 1003h history, heartbeat times).
    pub(super) fn coe(
        &mut self,
        idx: u64,
        time: Option<Timestamp>,
        channel: &[u8],
        m: &CoeMessage,
    ) -> Result<(), OutputError> {
        self.decide();
        let carried = self.monitors.coe.message(channel, m, &mut self.counts);
        if let Carried::Retry = carried {
            return Ok(());
        }
        if let Some(t) = time {
            self.time(t);
        }
        let at = At {
            time,
            line: self.line_no(idx),
        };
        let (monitors, nodes, facts, emit) = parts!(self);
        match carried {
            Carried::Emergency(data) => monitors
                .emcy
                .emcy(at, channel, m.station, None, data, nodes, facts, emit),
            Carried::Sdo(access) => {
                let learnt = monitors
                    .sdo
                    .access(channel, at, access, nodes, facts, emit)?;
                self.learnt(channel, at, learnt)
            }
            Carried::Retry | Carried::Nothing => Ok(()),
        }
    }

    /// EtherCAT seen in the input: frames, mailbox messages, empty polls.
    pub(super) fn ethercat(&mut self, frames: u64, mailbox_messages: u64, empty_polls: u64) {
        self.counts.ethercat_frames = frames;
        self.counts.mailbox_messages = mailbox_messages;
        self.counts.mailbox_empty_polls = empty_polls;
    }

    /// Skipped lines the reader only counted.
    pub(super) fn skipped_lines(&mut self, n: u64) {
        self.counts.skipped += n;
    }

    /// A frame was read: the format is known, held diagnostics go out.
    pub(super) fn decide(&mut self) {
        if !self.decided {
            self.decided = true;
            self.diags.release(self.log);
        }
    }

    /// A wanted frame's time: the input's first and last time.
    pub(super) fn time(&mut self, t: Timestamp) {
        self.first_time.get_or_insert(t);
        self.last_time = Some(t);
    }

    /// The first and last times of any frames in the next stretch of the
    /// input: the first of the input is kept, the last moves the end (in
    /// line order, as the decoded frames' last time: however the input is
    /// split, the end is its last frame's time).
    pub(super) fn frame_times(&mut self, first: Option<Timestamp>, last: Option<Timestamp>) {
        if self.frame_times.0.is_none() {
            self.frame_times.0 = first;
        }
        if last.is_some() {
            self.frame_times.1 = last;
        }
    }

    /// The input's first and last frame times. An input with no frame
    /// time has neither: an ASC file of relative times keeps a running
    /// time through malformed lines, which is no frame's (and read in
    /// blocks, no block's that had no frame).
    fn input_span(&self) -> (Option<Timestamp>, Option<Timestamp>) {
        let first = earliest(self.first_time, self.frame_times.0);
        (first, first.and(self.last_time.max(self.frame_times.1)))
    }

    /// The first and last times of the frames a binary reader only
    /// counted, known at the input's end: they came before, among and after
    /// the records, so the span reaches them where they lie outside it.
    pub(super) fn plain_span(&mut self, first: Timestamp, last: Timestamp) {
        self.frame_times.0 = earliest(self.frame_times.0, Some(first));
        self.frame_times.1 = self.frame_times.1.max(Some(last));
    }

    /// An error frame at `line`: into its channel's burst; what closed or
    /// ended goes out.
    fn error_frame(&mut self, line: u64, frame: &Frame<'_>) -> Result<(), OutputError> {
        self.traffic.error_frame(frame.channel, frame.time);
        let decoded = ErrorFrame::decode(frame.id, frame.data.as_slice());
        let at = At {
            time: frame.time,
            line,
        };
        let mut told = std::mem::take(&mut self.told);
        self.facts
            .bus
            .error_frame(frame.channel, at, &decoded, &mut told);
        let (_, _, _, emit) = parts!(self);
        emit.bus(&mut told)?;
        self.told = told;
        Ok(())
    }

    /// A node's frame that shows it back on the bus (EMCY 0x8140, a
    /// boot-up), once error frames were seen: a bus-off of the node if its
    /// silence and a burst go together. Asked before the monitors see the
    /// frame, while the node's last sign of life is the one before it.
    fn node_back(&mut self, seen: &Seen<'_>) -> Result<(), OutputError> {
        let back = match (self.facts.emcy_node(seen.id, false), seen.data) {
            (Some(node), [lo, hi, ..])
                if u16::from_le_bytes([*lo, *hi]) == RECOVERED_FROM_BUS_OFF =>
            {
                Some((node, EvidenceKind::Emcy(RECOVERED_FROM_BUS_OFF)))
            }
            (None, [0]) if emcy::is_nmt_error_control(seen.id) => Some((
                (seen.id - emcy::NMT_ERROR_CONTROL_BASE) as NodeId,
                EvidenceKind::BootUp,
            )),
            _ => None,
        };
        let Some((node, via)) = back else {
            return Ok(());
        };
        // Heard last: by its heartbeat or by an EMCY, whichever came later
        // (a node that sends EMCYs is on the bus, whatever its heartbeat).
        let last_seen = self.nodes.known(seen.channel, node).and_then(|n| {
            let heartbeat = n.health().and_then(|h| h.heartbeat.last_seen());
            let emcy = n.last_emcy().filter(|a| a.time.is_some());
            heartbeat
                .into_iter()
                .chain(emcy)
                .max_by_key(|a| (a.time, a.line))
        });
        if let Some(told) = self
            .facts
            .bus
            .node_back(seen.channel, node, seen.at, via, last_seen)
        {
            let mut told = vec![told];
            let (_, _, _, emit) = parts!(self);
            emit.bus(&mut told)?;
        }
        Ok(())
    }

    /// A frame for the channel's traffic (SYNC, or any with `--timing`):
    /// timed there, a gap in SYNC told. `true` when that is all the frame
    /// is for (one the analysis does not decode, or wants for its time
    /// alone): it is then counted as a frame, and nothing else happens.
    fn traffic(&mut self, idx: u64, frame: &Frame<'_>) -> Result<bool, OutputError> {
        let line = self.line_no(idx);
        let at = At {
            time: frame.time,
            line,
        };
        let gap = self.traffic.frame(
            frame.channel,
            frame.id,
            frame.extended,
            frame.kind,
            frame.len,
            at,
        );
        if let Some(gap) = gap {
            self.sync_missed(frame.channel, at, gap)?;
        }
        let interest = &self.wanted.interest;
        Ok(!interest.wants(frame.id, frame.extended)
            || interest.hands_over(frame.id, frame.extended))
    }

    /// A line handed over for its time ([`LineSink::timed_lines`]), line
    /// `l.idx` from `idx`, on `channel` (the traffic's channel `c`).
    #[inline]
    pub(super) fn timed_line(
        &mut self,
        idx: u64,
        c: usize,
        channel: &[u8],
        l: &TimedLine,
    ) -> Result<(), OutputError> {
        let line = self.line_no(idx + u64::from(l.idx));
        let time = l.time().map(FrameTime::Ticks);
        match self
            .traffic
            .frame_in(c, l.id(), false, FrameKind::Data, l.len, time, line)
        {
            Some(gap) => {
                let at = gap.end.unwrap_or(At { time: None, line });
                self.sync_missed(channel, at, gap)
            }
            None => Ok(()),
        }
    }

    /// A gap in SYNC, ended at `at`: told.
    fn sync_missed(&mut self, channel: &[u8], at: At, gap: SyncMissed) -> Result<(), OutputError> {
        let mut told = vec![Told {
            channel: String::from_utf8_lossy(channel).into_owned(),
            at,
            bus: Bus::SyncMissed(gap),
        }];
        let (_, _, _, emit) = parts!(self);
        emit.bus(&mut told)
    }

    /// The common heartbeat ([`NmtMonitor::steady_heartbeat`]), counted
    /// and timed. `false`: not that case, nothing was changed.
    /// Whether something is due by `t` that the frame path tells at the
    /// first frame after it (a burst of error frames to close, an
    /// incident's gap passed, an SDO transfer run out): a frame at `t`
    /// then takes that path, never a shortcut (a steady heartbeat, a folded
    /// run taken whole), so where such an event is told among the others
    /// does not depend on which frames take the shortcuts, nor on folding.
    /// The one list of them: each shortcut asks here.
    #[inline]
    pub(super) fn frame_path_due(&self, t: Timestamp) -> bool {
        self.facts.bus.passed(t) || self.incidents.passed(t) || self.monitors.sdo.passed(t)
    }

    #[inline]
    fn steady_heartbeat(&mut self, idx: u64, frame: &Frame<'_>) -> bool {
        if frame.time.is_some_and(|t| self.frame_path_due(t)) {
            return false;
        }
        let line_base = self.line_base;
        let Some(time) = self.monitors.nmt.steady_heartbeat(
            frame,
            || line_base + idx + 1,
            self.decided,
            &self.wanted.interest,
            &self.facts,
            &mut self.nodes,
        ) else {
            return false;
        };
        self.counts.frames += 1;
        self.time(time);
        true
    }
}

impl<E: Write> LineSink for Consumer<'_, '_, E> {
    fn interest(&self) -> &Interest {
        self.wanted.reading()
    }

    fn plain_frames(&mut self, n: u64) {
        self.counts.frames += n;
        self.decide();
    }

    fn frame_times(&mut self, first: Option<Timestamp>, last: Option<Timestamp>) {
        Consumer::frame_times(self, first, last);
    }

    fn timed_frames(&mut self, n: u64, first: Timestamp, last: Timestamp) {
        self.counts.frames += n;
        self.decide();
        self.time(first);
        self.time(last);
    }

    fn folded(&mut self, idx: u64, run: &FoldedRun<'_>) -> Result<(), OutputError> {
        self.take_folded_run(idx, run)
    }

    fn fold_buffers(&mut self) -> FoldBuffers {
        std::mem::take(&mut self.spare_folds)
    }

    fn block_folds(&mut self, folds: FoldBuffers) {
        self.spare_folds = folds;
    }

    fn take_id_counts(&mut self) -> IdCounts {
        std::mem::take(&mut self.ids)
    }

    fn put_id_counts(&mut self, ids: IdCounts) {
        self.ids = ids;
    }

    fn timed_lines(
        &mut self,
        idx: u64,
        channel: &[u8],
        lines: &[TimedLine],
        _at: usize,
    ) -> Result<(), OutputError> {
        let Some(c) = self.traffic.channel_index(channel) else {
            return Ok(());
        };
        let mut rest = lines;
        while !rest.is_empty() {
            let timed = self.traffic.lines_until_gap(c, self.line_no(idx), rest);
            // The line that ends a gap, with its event.
            let Some((l, after)) = rest.get(timed..).and_then(|r| r.split_first()) else {
                break;
            };
            self.timed_line(idx, c, channel, l)?;
            rest = after;
        }
        Ok(())
    }

    fn lines(&mut self, n: u64) {
        self.counts.lines += n;
        self.line_base += n;
    }

    fn skipped(&mut self) {
        self.counts.skipped += 1;
    }

    fn dropped(&mut self, n: u64) {
        self.counts.dropped = self.counts.dropped.saturating_add(n);
    }

    fn annotated(&mut self) {
        self.counts.annotated += 1;
    }

    fn malformed(&mut self, idx: u64, reason: Reason) {
        self.counts.malformed += 1;
        let line = self.line_no(idx);
        self.diags
            .report(self.log, self.decided, line, reason.into_owned());
    }

    fn warning(&mut self, idx: u64, reason: Reason) {
        let line = self.line_no(idx);
        self.diags
            .report(self.log, self.decided, line, reason.into_owned());
    }

    fn format_known(&mut self) {
        self.decide();
    }

    fn frame(&mut self, idx: u64, frame: &Frame<'_>, foreign: Foreign) -> Result<(), OutputError> {
        let only_traffic = frame.kind != FrameKind::Error
            && !self.timed_as_lines
            && (self.traffic.wants() || self.wanted.interest.hands_over(frame.id, frame.extended))
            && self.traffic(idx, frame)?;
        // Heartbeats are the most frequent frames decoded.
        if !only_traffic && foreign.is_none() && self.steady_heartbeat(idx, frame) {
            return Ok(());
        }
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
        if only_traffic {
            return Ok(());
        }
        let interest = &self.wanted.interest;
        if frame.kind != FrameKind::Data {
            if frame.kind == FrameKind::Error {
                if interest.wants_error_frames() {
                    self.error_frame(line_no, frame)?;
                }
                return Ok(());
            }
            if frame.kind == FrameKind::Remote && !frame.extended && interest.wants(frame.id, false)
            {
                // A guard request's time is checked against the deadlines,
                // so a guarded node that stopped replying is found lost
                // while the master keeps asking. It is not the input's
                // first or last time, which stays that of data frames.
                if let Some(t) = frame.time
                    && self.monitors.nmt.passed(t)
                {
                    let (monitors, nodes, _, emit) = parts!(self);
                    monitors.nmt.deadlines_passed(t, line_no, nodes, emit)?;
                }
                let (monitors, nodes, _, emit) = parts!(self);
                monitors
                    .nmt
                    .remote_frame(frame.channel, frame.id, line_no, nodes, emit);
            }
            return Ok(());
        }
        // Only wanted ids count: workers may hand over frames the sequential
        // reader only counts, and the result must not depend on the path.
        if !interest.wants(frame.id, frame.extended) {
            return Ok(());
        }
        // A drive's PDO of unknown mapping is only noted: it moves no time,
        // as when it was not wanted.
        if self.monitors.drive.watched(frame.id, frame.extended) {
            let drive = &mut self.monitors.drive;
            self.wanted.narrow(|i| drive.unwatch(i));
            return Ok(());
        }
        if let Some(t) = frame.time {
            self.time(t);
            if self.monitors.nmt.passed(t) {
                let (monitors, nodes, _, emit) = parts!(self);
                monitors.nmt.deadlines_passed(t, line_no, nodes, emit)?;
            }
            if self.monitors.sdo.passed(t) {
                let (monitors, _, facts, emit) = parts!(self);
                monitors.sdo.expire(t, facts, emit)?;
            }
            if self.facts.bus.passed(t) {
                let mut told = std::mem::take(&mut self.told);
                self.facts.bus.close_until(t, &mut told);
                let (_, _, _, emit) = parts!(self);
                emit.bus(&mut told)?;
                self.told = told;
            }
            // An incident whose gap has passed is told now, on a quiet bus
            // too (live input, --follow); the fold paths leave such a frame
            // to this path, so where it is told does not depend on the split.
            if self.incidents.passed(t) {
                let (_, _, _, emit) = parts!(self);
                emit.incidents.tick(Some(t));
                emit.tell_incidents()?;
            }
        }
        if self
            .wanted
            .interest
            .timed_only(frame.id, frame.extended, frame.data.as_slice())
        {
            return Ok(());
        }
        let seen = Seen {
            channel: frame.channel,
            id: frame.id,
            extended: frame.extended,
            at: At {
                time: frame.time,
                line: line_no,
            },
            data: frame.data.as_slice(),
        };
        if self.facts.bus.any() && !seen.extended {
            self.node_back(&seen)?;
        }
        let (monitors, nodes, facts, emit) = parts!(self);
        if let Step::Learnt(learnt) = monitors.frame(&seen, nodes, facts, emit)? {
            self.learnt(seen.channel, seen.at, learnt)?;
        }
        Ok(())
    }
}

/// EMCY 0x8140, "recovered from bus-off" (CiA 301).
const RECOVERED_FROM_BUS_OFF: u16 = 0x8140;

/// The earlier of two times, either of which may be unknown.
fn earliest(a: Option<Timestamp>, b: Option<Timestamp>) -> Option<Timestamp> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}
