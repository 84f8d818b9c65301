//! The SDO monitor: SDO transfers (expedited, segmented and block) followed
//! to the values nodes hold and report (the facts other monitors need:
//! device type, identity, the EMCY id, the heartbeat times, PDO parameters,
//! a drive's words), aborts, the error history (0x1003) read-outs, and
//! every transfer told as an `sdo` event when it ends.

use std::borrow::Cow;
use std::io::Write;

use super::context::{Emit, Fact, Facts, Learnt, Monitor, Seen, Step};
use crate::analyze::analysis::OutputError;
use crate::analyze::event::{Bus, Health, HistoryItem, HistoryReport, NodeReport, SdoTransfer};
use crate::analyze::interest::{learns_from, sdo_filter};
use crate::analyze::nodes::Nodes;
use crate::analyze::options::Options;
use crate::canopen::sdo::abort as sdo_abort;
use crate::canopen::sdo::transfer::{Direction, Ended, Outcome, Transfers};
use crate::canopen::sdo::{self, BlockStep, Blocks, Confirmed, Downloads, Sdo, Uploads};
use crate::canopen::{NodeId, device_profile, dictionary};
use crate::timeline::At;
use crate::timeline::error_history::ReadOut;
use crate::timeline::health::NodeHealth;

pub(in crate::analyze) struct SdoMonitor {
    /// Expedited transfers of the followed objects, to the values they carry.
    tracker: sdo::Tracker,
    /// Block transfers going on: their frames are no other command.
    blocks: Blocks,
    /// Downloads (expedited and segmented) of the objects other monitors
    /// learn from writes ([`Downloads::wants`]).
    downloads: Downloads,
    /// Segmented uploads of the objects some monitor learns from.
    uploads: Uploads,
    /// Every transfer, to tell it when it ends.
    transfers: Transfers<At>,
    /// Whether the content filter lets the last segments of segmented
    /// transfers through: while some node has a long one going on.
    long_filter: bool,
    /// The channel each node's SDO frames came on last (by node id).
    channels: Vec<Vec<u8>>,
    /// Buffers reused from frame to frame.
    events: Vec<(At, Health)>,
    read_outs: Vec<ReadOut>,
    ended: Vec<Ended<At>>,
    /// The event told last, its box reused for the next: SDO-heavy buses
    /// tell hundreds of thousands.
    told: Option<Bus>,
}

impl Monitor for SdoMonitor {
    fn new(opts: &Options) -> Self {
        SdoMonitor {
            tracker: sdo::Tracker::default(),
            blocks: Blocks::default(),
            downloads: Downloads::default(),
            uploads: Uploads::default(),
            transfers: Transfers::new(opts.sdo_timeout),
            long_filter: false,
            channels: vec![Vec::new(); 128],
            events: Vec::new(),
            read_outs: Vec::new(),
            ended: Vec::new(),
            told: None,
        }
    }

    /// A frame on a CAN SDO id.
    fn frame<E: Write>(
        &mut self,
        frame: &Seen<'_>,
        nodes: &mut Nodes,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<Step, OutputError> {
        if frame.extended || !sdo::is_sdo_id(frame.id) {
            return Ok(Step::Pass);
        }
        let (id, data) = (frame.id, frame.data);
        let node = (id & 0x7F) as NodeId;
        if let Some(channel) = self.channels.get_mut(usize::from(node))
            && channel.as_slice() != frame.channel
        {
            channel.clear();
            channel.extend_from_slice(frame.channel);
        }
        match self.blocks.feed(id, data, learns_from) {
            BlockStep::Other => {}
            BlockStep::Part => {
                // Only the client's initiate leaves a transfer just begun.
                if id >= sdo::REQUEST_BASE
                    && let Some((upload, object, size)) = self.blocks.begun(node)
                {
                    let direction = if upload {
                        Direction::Upload
                    } else {
                        Direction::Download
                    };
                    let cut = self
                        .transfers
                        .block_begun(node, direction, object, size, frame.at);
                    self.ended.extend(cut);
                    self.tell(facts, emit)?;
                }
                return Ok(Step::Done);
            }
            BlockStep::Done {
                upload,
                value,
                size,
                ..
            } => {
                let kept = value.map(|c| (c.value, c.len));
                let done = self.transfers.block_done(node, size, kept, frame.at);
                self.ended.extend(done);
                self.tell(facts, emit)?;
                let mut learnt = Learnt::default();
                if let Some(c) = value {
                    completed(&mut learnt, c, upload);
                }
                return Ok(Step::Learnt(learnt));
            }
        }
        let following = self.following(id);
        let long = self.transfers.is_long(id);
        let told = self.transfers.feed(id, data, frame.at);
        self.ended.extend(told);
        if long != self.transfers.is_long(id) {
            self.sync_filter(emit);
        }
        let mut learnt = Learnt::default();
        if self.downloads.wants(id, data)
            && let Some(c) = self.downloads.feed(id, data)
        {
            learnt.written = Some(Fact::Written {
                node: c.node,
                object: c.object,
                value: c.value,
            });
        }
        if self.uploads_wanted(id, data) {
            if let Some(c) = self.uploads.feed(id, data) {
                completed(&mut learnt, c, true);
            }
            learnt.text = self.uploads.take_text();
        }
        if following != self.following(id) {
            // Segments name no object, so the content filter keeps them
            // back: the node's SDO frames are all read while a transfer
            // of an object some monitor learns from goes on, and filtered
            // again after it.
            let node = id & 0x7F;
            let ids = [sdo::REQUEST_BASE + node, sdo::RESPONSE_BASE + node];
            if following {
                emit.wanted.narrow(|i| {
                    ids.iter().for_each(|&id| i.refilter(id));
                    true
                });
            } else {
                emit.wanted
                    .widen(|i| ids.iter().for_each(|&id| i.unfilter(id)));
            }
        }
        if let Some(access) = sdo::parse(id, data) {
            let more = self.access(frame.channel, frame.at, access, nodes, facts, emit)?;
            learnt.read = learnt.read.or(more.read);
            learnt.holds = learnt.holds.or(more.holds);
        }
        self.tell(facts, emit)?;
        Ok(Step::Learnt(learnt))
    }

    /// A value of the error history (0x1003) a node holds.
    fn learn<E: Write>(
        &mut self,
        raw: &[u8],
        at: At,
        fact: Fact,
        nodes: &mut Nodes,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        let Fact::Holds {
            node,
            object,
            value,
            written,
        } = fact
        else {
            return Ok(());
        };
        if object.index != sdo::ERROR_HISTORY {
            return Ok(());
        }
        let timeout = emit.opts.heartbeat_timeout;
        let slot = nodes.get(raw, node);
        let h = slot.timeline.health_mut(timeout);
        let done = &mut self.read_outs;
        match (object.sub, written) {
            (0, true) if value == 0 => {
                h.history.cleared(done);
                self.events.push((at, Health::ErrorHistoryCleared));
            }
            (0, true) => {}
            (0, false) => h.history.count(value, at, done),
            (sub, false) => h.history.entry(sub, value, at, done),
            (_, true) => {}
        }
        let cleared = written && object.sub == 0 && value == 0;
        let id = slot.channel_id;
        self.read_outs_out(id, node, at, nodes, facts, emit);
        if cleared {
            // Known empty from here.
            nodes
                .get(raw, node)
                .timeline
                .health_mut(timeout)
                .last_read_out = Some(ReadOut {
                entries: Vec::new(),
                count: Some(0),
                complete: true,
                at,
            });
        }
        let slot = nodes.get(raw, node);
        emit.health(slot.channel, node, &mut self.events)
    }

    /// Read-outs going on end as partial (their events at the last line,
    /// after every event before; the node keeps the read-out's own line);
    /// transfers going on end unanswered or incomplete.
    fn finish<E: Write>(
        &mut self,
        end: At,
        nodes: &mut Nodes,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        self.transfers.finish(&mut self.ended);
        self.tell(facts, emit)?;
        let reading = nodes.picked(|tl| tl.health().is_some_and(|h| h.history.is_reading()));
        for (id, node) in reading {
            let Some(slot) = nodes.slot_by_id(id, node) else {
                continue;
            };
            slot.timeline
                .health_mut(emit.opts.heartbeat_timeout)
                .history
                .flush(&mut self.read_outs);
            self.read_outs_out(id, node, end, nodes, facts, emit);
            let Some(slot) = nodes.slot_by_id(id, node) else {
                continue;
            };
            emit.health(slot.channel, node, &mut self.events)?;
        }
        Ok(())
    }

    /// The last read-out; its codes are described with the node's profile
    /// once the report has it.
    fn report(&self, report: &mut NodeReport, health: Option<&NodeHealth>) {
        report.error_history = health
            .and_then(|h| h.last_read_out.as_ref())
            .map(|r| history_report(r, |_| String::new()));
    }
}

/// What a segmented or block transfer that completed showed: an upload is
/// a read, a download a confirmed write; of a followed object, a value the
/// node holds.
fn completed(learnt: &mut Learnt, c: Confirmed, upload: bool) {
    let Confirmed {
        node,
        object,
        value,
        ..
    } = c;
    if !learns_from(object.index) {
        return;
    }
    if upload {
        learnt.read = Some(Fact::Read {
            node,
            object,
            value,
        });
    } else {
        learnt.written = Some(Fact::Written {
            node,
            object,
            value,
        });
    }
    if sdo::is_followed(object.index) {
        learnt.holds = Some(Fact::Holds {
            node,
            object,
            value,
            written: !upload,
        });
    }
}

impl SdoMonitor {
    /// Whether the node of SDO id `id` has a segmented transfer going on
    /// that this monitor follows (of an object some monitor learns from).
    fn following(&self, id: u32) -> bool {
        self.downloads.in_segments(id)
            || self.uploads.in_progress(id)
            || self.transfers.reads_segments(id)
    }

    /// Whether a transfer waiting for its node may have run out by `now`.
    #[inline]
    pub(in crate::analyze) fn passed(&self, now: crate::trace::Timestamp) -> bool {
        self.transfers.passed(now)
    }

    /// Transfers whose node did not answer in time by `now` are told as
    /// unanswered.
    pub(in crate::analyze) fn expire<E: Write>(
        &mut self,
        now: crate::trace::Timestamp,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        self.transfers.expire(now, &mut self.ended);
        self.sync_filter(emit);
        self.tell(facts, emit)
    }

    /// The content filter with the last segments of segmented transfers
    /// while a long one goes on, without them otherwise (see
    /// [`sdo_filter`]).
    fn sync_filter<E: Write>(&mut self, emit: &mut Emit<'_, E>) {
        let long = self.transfers.any_long();
        if long == self.long_filter {
            return;
        }
        self.long_filter = long;
        if long {
            emit.wanted.widen(|i| {
                i.set_content(sdo_filter(true));
            });
        } else {
            emit.wanted.narrow(|i| i.set_content(sdo_filter(false)));
        }
    }

    /// The transfers that ended, told as `sdo` events.
    fn tell<E: Write>(
        &mut self,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        if self.ended.is_empty() {
            return Ok(());
        }
        for e in self.ended.drain(..) {
            let channel = self
                .channels
                .get(usize::from(e.node))
                .map(|c| String::from_utf8_lossy(c))
                .unwrap_or_default();
            let report = transfer_report(e, facts, emit.opts);
            match &mut self.told {
                Some(Bus::Sdo(told)) => **told = report,
                _ => self.told = Some(Bus::Sdo(Box::new(report))),
            }
            if let Some(bus) = &self.told {
                emit.bus_event(&channel, e.end, bus)?;
            }
        }
        Ok(())
    }

    /// Whether a frame can matter to a segmented upload: the server's
    /// answer naming an object some monitor learns from, or any frame of a
    /// node whose upload is going on.
    fn uploads_wanted(&self, id: u32, data: &[u8]) -> bool {
        self.uploads.in_progress(id)
            || matches!(*data, [_, lo, hi, ..] if learns_from(u16::from_le_bytes([lo, hi])))
    }

    /// An SDO access (on a CAN SDO id, or parsed from another transport by
    /// [`sdo::parse_payload`]) on channel `raw` at `at`: an abort, and
    /// what the access showed of the node.
    pub(in crate::analyze) fn access<E: Write>(
        &mut self,
        raw: &[u8],
        at: At,
        access: Sdo,
        nodes: &mut Nodes,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<Learnt, OutputError> {
        let mut learnt = Learnt::default();
        match access {
            // Only objects some monitor learns from are worth a fact: every
            // monitor hears each one.
            Sdo::Uploaded {
                node,
                object,
                value,
            } if learns_from(object.index) => {
                learnt.read = Some(Fact::Read {
                    node,
                    object,
                    value,
                });
            }
            Sdo::Aborted {
                node,
                object,
                code,
                by_server,
            } => self.abort(raw, node, object, code, by_server, at, nodes, facts, emit)?,
            _ => {}
        }
        let written = matches!(access, Sdo::Written { .. });
        if let Some((node, object, value)) = self.tracker.feed(access) {
            learnt.holds = Some(Fact::Holds {
                node,
                object,
                value,
                written,
            });
        }
        Ok(learnt)
    }

    #[allow(clippy::too_many_arguments)]
    fn abort<E: Write>(
        &mut self,
        raw: &[u8],
        node: NodeId,
        object: sdo::Object,
        code: u32,
        by_server: bool,
        at: At,
        nodes: &mut Nodes,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        // A client's abort is the master speaking: to an id that never
        // answered it makes no node, only a diagnostic at its line.
        if !by_server && nodes.known(raw, node).is_none() {
            emit.diagnostic(
                at.line,
                format!(
                    "the SDO client aborted its transfer of 0x{:04X} sub {} to node {node}, \
                     which never answered ({}); no node",
                    object.index,
                    object.sub,
                    sdo_abort::describe(code)
                ),
            );
            return Ok(());
        }
        let slot = nodes.get(raw, node);
        self.events.push((
            at,
            Health::SdoAbort {
                index: object.index,
                subindex: object.sub,
                abort_code: code,
                text: sdo_abort::describe(code),
                by_server,
            },
        ));
        if object.index == sdo::ERROR_HISTORY {
            // The read-out going on will not finish.
            let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
            h.history.flush(&mut self.read_outs);
        }
        let id = slot.channel_id;
        self.read_outs_out(id, node, at, nodes, facts, emit);
        let slot = nodes.get(raw, node);
        emit.health(slot.channel, node, &mut self.events)
    }

    /// Read-outs finished by the frame at `now` become events at it (one
    /// it interrupted ended there, after the events before: events stay in
    /// line order) and the node's last read-out (which keeps its own
    /// line): codes the node never raised in the trace are marked as older
    /// than it.
    fn read_outs_out<E: Write>(
        &mut self,
        channel_id: u32,
        node: NodeId,
        now: At,
        nodes: &mut Nodes,
        facts: &Facts<'_>,
        emit: &Emit<'_, E>,
    ) {
        if self.read_outs.is_empty() {
            return;
        }
        let profile = facts.profiles.get(node).profile;
        let Some(slot) = nodes.slot_by_id(channel_id, node) else {
            return;
        };
        for mut r in self.read_outs.drain(..) {
            for e in &mut r.entries {
                e.before_trace = !slot.timeline.has_raised(e.code);
            }
            let report = history_report(&r, |code| profile.describe(code));
            self.events.push((now, Health::ErrorHistory(report)));
            slot.timeline
                .health_mut(emit.opts.heartbeat_timeout)
                .last_read_out = Some(r);
        }
    }
}

/// A transfer as told: named by the node's DCF, else the CiA tables (a
/// drive's objects only for a node known to be a drive), its data as text
/// when the object holds one.
fn transfer_report(e: Ended<At>, facts: &Facts<'_>, opts: &Options) -> SdoTransfer {
    let object = e.object;
    let declared = opts
        .dcf
        .iter()
        .find(|(n, _)| *n == e.node)
        .and_then(|(_, dcf)| {
            let whole = sdo::Object { sub: 0, ..object };
            dcf.objects.get(&object).or_else(|| dcf.objects.get(&whole))
        });
    let drive = || {
        facts
            .profiles
            .device_type(e.node)
            .is_some_and(device_profile::is_drive)
    };
    let name = declared
        .and_then(|d| d.name.clone())
        .map(Cow::Owned)
        .or_else(|| dictionary::communication_name(object).map(Cow::Borrowed))
        .or_else(|| {
            drive()
                .then(|| dictionary::drive_name(object.index))
                .flatten()
                .map(Cow::Borrowed)
        });
    let is_text = sdo::is_text(object.index) || declared.is_some_and(|d| d.text);
    let text = e
        .data
        .filter(|d| is_text && d.complete())
        .map(|d| dictionary::visible_string(d.shown()));
    let abort_text = match e.outcome {
        Outcome::Abort { code, .. } => Some(sdo_abort::describe(code)),
        _ => None,
    };
    SdoTransfer {
        node: e.node,
        direction: e.direction,
        object,
        name,
        protocol: e.protocol,
        indicated: e.indicated,
        data: e.data,
        text,
        outcome: e.outcome,
        abort_text,
        start: e.start,
        end: e.end,
    }
}

/// A read-out as reported, each code described by `describe`.
fn history_report(r: &ReadOut, describe: impl Fn(u16) -> String) -> HistoryReport {
    HistoryReport {
        entries: r
            .entries
            .iter()
            .map(|e| HistoryItem {
                code: e.code,
                info: e.info,
                description: describe(e.code),
                before_trace: e.before_trace,
            })
            .collect(),
        count: r.count,
        complete: r.complete,
        time: r.at.time,
        line: r.at.line,
    }
}
