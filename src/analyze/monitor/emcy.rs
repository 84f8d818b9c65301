//! The EMCY monitor: each node's error state from its EMCY frames (and
//! the boot-up, which clears it), the EMCY and boot-up events, and what
//! `--fail-on` needs. The hot path of an EMCY-heavy trace.

use std::io::Write;

use super::context::{Emit, Facts, Monitor, Seen, Step};
use crate::analyze::analysis::OutputError;
use crate::analyze::event::{BootEvent, EVENT_ACTIVE_MAX, EmcyEvent};
use crate::analyze::nodes::{NodeSlot, Nodes};
use crate::analyze::options::Options;
use crate::cache::{Cache, profile_code_key};
use crate::canopen::NodeId;
use crate::canopen::codes::CodeInfo;
use crate::canopen::emcy::{self, Emcy, Warning};
use crate::canopen::profile::Profile;
use crate::timeline::{At, Step as TimelineStep};
use crate::trace::Timestamp;
use crate::trace::deltas;

pub(in crate::analyze) struct EmcyMonitor {
    /// Selected EMCY frames with an error code (not a reset).
    pub(in crate::analyze) errors_raised: u64,
    /// Selected EMCY frames that carried a protocol warning.
    pub(in crate::analyze) frames_with_warnings: u64,
    /// The lowest (most severe) profile category of a selected error EMCY.
    pub(in crate::analyze) worst_category: Option<u8>,
    /// Time and line of the last EMCY or boot-up: the trace's clock as far
    /// as the timelines see it.
    clock: Option<(Timestamp, u64)>,
    warnings: Vec<Warning>,
    active: Vec<u16>,
    /// The last timeline step, handed back for its vectors.
    step_buffers: TimelineStep,
    /// What each (profile, code) means: the one code lookup of the run. A
    /// lookup is a few binary searches and a profile's description
    /// allocates, and an EMCY-heavy trace repeats a few codes millions of
    /// times on this thread, so the event carries both from here and no
    /// renderer looks a code up again.
    codes: Cache<(usize, u16), CodeEntry, 64>,
}

/// A code as a profile reads it.
struct CodeEntry {
    info: CodeInfo,
    description: String,
}

impl CodeEntry {
    fn of(profile: &Profile, code: u16) -> CodeEntry {
        CodeEntry {
            info: profile.info(code),
            description: profile.describe(code),
        }
    }
}

impl Monitor for EmcyMonitor {
    fn new(_opts: &Options) -> Self {
        EmcyMonitor {
            errors_raised: 0,
            frames_with_warnings: 0,
            worst_category: None,
            clock: None,
            warnings: Vec::new(),
            active: Vec::new(),
            step_buffers: TimelineStep::default(),
            codes: Cache::default(),
        }
    }

    /// An EMCY is taken; a boot-up clears the node's errors and goes on to
    /// the NMT monitor.
    #[inline]
    fn frame<E: Write>(
        &mut self,
        frame: &Seen<'_>,
        nodes: &mut Nodes,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<Step, OutputError> {
        if let Some(node) = facts.emcy_node(frame.id, frame.extended) {
            let cob_id = Some(frame.id);
            self.emcy(
                frame.at,
                frame.channel,
                node,
                cob_id,
                frame.data,
                nodes,
                facts,
                emit,
            )?;
            return Ok(Step::Done);
        }
        if !frame.extended
            && let Some(node) = emcy::boot_node(frame.id, frame.data)
        {
            self.boot(frame.at, frame.channel, node, nodes, emit)?;
        }
        Ok(Step::Pass)
    }
}

/// For a communication error (0x81xx: overrun, error passive, recovered
/// from bus-off, ...), the start of the burst of error frames it came in
/// or right after on its channel: drives report the wire late and
/// indirectly, and the burst is what they report.
fn bus_error_of(emcy: &Emcy, channel: &[u8], at: At, facts: &Facts<'_>) -> Option<Timestamp> {
    if emcy.code & 0xFF00 != 0x8100 || !facts.bus.any() {
        return None;
    }
    facts.bus.burst_of(channel, at.time?)
}

impl EmcyMonitor {
    /// An EMCY of `node` (on CAN id `cob_id`; `None` for a CoE emergency):
    /// its timeline step, counts and event.
    #[allow(clippy::too_many_arguments)]
    pub(in crate::analyze) fn emcy<E: Write>(
        &mut self,
        at: At,
        channel_bytes: &[u8],
        node: NodeId,
        cob_id: Option<u32>,
        data: &[u8],
        nodes: &mut Nodes,
        facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        let emcy = match Emcy::decode(data) {
            Ok(e) => e,
            Err(short) => {
                emit.counts.emcy_invalid += 1;
                emit.diagnostic(at.line, format!("node {node}: {short}"));
                return Ok(());
            }
        };
        emit.counts.emcy += 1;
        self.check_clock(at, emit);
        let chosen = facts.profiles.get(node);
        let profile = chosen.profile;
        let (key, slot) = profile_code_key(profile, emcy.code);
        let looked_up;
        let entry = match self
            .codes
            .get(key, slot, || CodeEntry::of(profile, emcy.code))
        {
            Some(entry) => entry,
            None => {
                looked_up = CodeEntry::of(profile, emcy.code);
                &looked_up
            }
        };
        let info = &entry.info;
        self.warnings.clear();
        emcy.frame_warnings(info, &mut self.warnings);
        profile.frame_warnings(&emcy, &mut self.warnings);
        let NodeSlot {
            channel,
            channel_id,
            timeline,
            history,
        } = nodes.get(channel_bytes, node);
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
        // An error EMCY of a drive: the fault it came with.
        if !emcy.is_reset()
            && let Some(rec) = timeline.drive_mut()
        {
            rec.emcy(at, emcy.code);
        }
        // Incidents hear every node, shown or not.
        let burst = bus_error_of(&emcy, channel_bytes, at, facts);
        emit.incidents.emcy(channel, node, emcy.code, at, burst);
        emit.tell_incidents()?;
        if !emit.opts.selects(channel, node) {
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
        // The first few: an event's size must not grow with the node's
        // active errors (a trace can leave thousands active).
        self.active.clear();
        self.active
            .extend(timeline.active_codes().take(EVENT_ACTIVE_MAX));
        let decoded = profile.decode_manufacturer(&emcy);
        let event = EmcyEvent {
            file: emit.file,
            line: at.line,
            time: at.time,
            channel,
            node,
            cob_id,
            data,
            emcy: &emcy,
            info,
            description: &entry.description,
            transition: step.transition,
            state: step.state,
            active: &self.active,
            active_total: timeline.active().len(),
            cleared: &step.cleared,
            warnings: &self.warnings,
            profile: chosen,
            decoded: decoded.as_ref(),
            bus_error: bus_error_of(&emcy, channel_bytes, at, facts),
        };
        emit.emcy(&event)?;
        self.step_buffers = step;
        Ok(())
    }

    /// A boot-up: the node's active errors close, and its event.
    fn boot<E: Write>(
        &mut self,
        at: At,
        channel_bytes: &[u8],
        node: NodeId,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        emit.counts.boot += 1;
        self.check_clock(at, emit);
        let heard = nodes.known(channel_bytes, node).is_some();
        let NodeSlot {
            channel,
            channel_id,
            timeline,
            history,
        } = nodes.get(channel_bytes, node);
        let closed = timeline.boot(at);
        let cleared: Vec<u16> = closed.iter().map(|iv| iv.code).collect();
        for iv in closed {
            history.push(channel_id, node, iv);
        }
        emit.incidents.boot(channel, node, heard, at);
        emit.tell_incidents()?;
        if emit.opts.selects(channel, node) {
            let event = BootEvent {
                file: emit.file,
                line: at.line,
                time: at.time,
                channel,
                node,
                cleared: &cleared,
            };
            emit.boot(&event)?;
        }
        Ok(())
    }

    /// A time earlier than the previous EMCY's or boot-up's (two logs
    /// concatenated, a clock reset) gets a diagnostic: durations across this
    /// line come out negative, and the user should know why.
    fn check_clock<E: Write>(&mut self, at: At, emit: &mut Emit<'_, E>) {
        let Some(time) = at.time else { return };
        if let Some((previous, line)) = self.clock
            && time.since(previous).is_negative()
        {
            let hint = if emit.opts.timestamps.is_none()
                && !emit.summed_deltas
                && time.secs() < deltas::DELTA_BELOW_SECS
            {
                "; if these are candump -td deltas, --timestamps delta sums them"
            } else {
                ""
            };
            emit.diagnostic(
                at.line,
                format!(
                    "time {time} is earlier than {previous} at line {line}: the trace's clock \
                     went backwards (durations across this line are negative){hint}"
                ),
            );
        }
        self.clock = Some((time, at.line));
    }
}
