//! What every monitor is given and what it gives back: the frame it sees
//! ([`Seen`]), the facts the others learnt ([`Facts`], read-only to it),
//! the facts it learnt itself ([`Step::Learnt`]), and [`Emit`], where its
//! events, diagnostics, counts and wanted ids go. The trait and the
//! context live apart from the list of monitors so that a monitor's file
//! imports this one and never the list, which imports it.

use std::collections::HashMap;
use std::io::Write;

use crate::analyze::analysis::OutputError;
use crate::analyze::bus::{BusErrors, Told};
use crate::analyze::diagnostics::{DiagnosticLog, InputDiagnostics};
use crate::analyze::event::{
    BootEvent, Bus, BusEvent, Counts, EmcyEvent, Health, HealthEvent, NodeReport,
};
use crate::analyze::incident;
use crate::analyze::interest::Wanted;
use crate::analyze::nodes::Nodes;
use crate::analyze::options::Options;
use crate::analyze::sink::Sink;
use crate::canopen::NodeId;
use crate::canopen::emcy;
use crate::canopen::profile_choice::NodeProfiles;
use crate::canopen::sdo::{self, Object};
use crate::timeline::At;
use crate::timeline::health::NodeHealth;
use crate::trace::Interest;

/// One CANopen service's view of the trace: its own state, fed the frames
/// the dispatcher hands it in the order of the list, the facts other
/// monitors learnt, and the end of the input.
pub(in crate::analyze) trait Monitor {
    fn new(opts: &Options) -> Self
    where
        Self: Sized;

    /// A decoded data frame that no monitor before this one in the list
    /// took. [`Step::Pass`] hands it on to the next.
    fn frame<E: Write>(
        &mut self,
        _frame: &Seen<'_>,
        _nodes: &mut Nodes,
        _facts: &Facts<'_>,
        _emit: &mut Emit<'_, E>,
    ) -> Result<Step, OutputError> {
        Ok(Step::Pass)
    }

    /// A fact a monitor learnt (on `channel`, at `at`): every monitor
    /// hears it, in the order of the list, after the shared facts took it.
    fn learn<E: Write>(
        &mut self,
        _channel: &[u8],
        _at: At,
        _fact: Fact,
        _nodes: &mut Nodes,
        _facts: &Facts<'_>,
        _emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        Ok(())
    }

    /// The end of the input, at `end` (the last time, the last line).
    fn finish<E: Write>(
        &mut self,
        _end: At,
        _nodes: &mut Nodes,
        _facts: &Facts<'_>,
        _emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        Ok(())
    }

    /// The monitor's part of a node's report, from what it kept in the
    /// node's health.
    fn report(&self, _report: &mut NodeReport, _health: Option<&NodeHealth>) {}

    /// Adds the ids whose frames the monitor needs decoded beyond the
    /// fixed ones ([`interest`](crate::analyze::interest::interest)).
    fn interest(&self, _interest: &mut Interest) {}
}

/// A decoded data frame as the monitors see it.
pub(in crate::analyze) struct Seen<'f> {
    pub(in crate::analyze) channel: &'f [u8],
    pub(in crate::analyze) id: u32,
    pub(in crate::analyze) extended: bool,
    pub(in crate::analyze) at: At,
    pub(in crate::analyze) data: &'f [u8],
}

/// What a monitor did with a frame.
pub(in crate::analyze) enum Step {
    /// Not its frame, or not only its: the next monitor sees it.
    Pass,
    /// Its frame: no later monitor sees it.
    Done,
    /// Its frame, and what it showed of the nodes: every monitor hears it.
    Learnt(Learnt),
}

/// What one SDO access showed: an object read directly, a value a node
/// holds, a write the node confirmed. Any of them, or none.
#[derive(Default)]
pub(in crate::analyze) struct Learnt {
    pub(in crate::analyze) read: Option<Fact>,
    pub(in crate::analyze) holds: Option<Fact>,
    pub(in crate::analyze) written: Option<Fact>,
    /// A PDO the node sent.
    pub(in crate::analyze) produced: Option<Fact>,
    /// A text a node named itself by, longer than four bytes (shorter ones
    /// are read as values).
    pub(in crate::analyze) text: Option<crate::canopen::sdo::Text>,
}

/// A fact about a node that one monitor learnt and others may need.
#[derive(Clone, Copy, Debug)]
pub(in crate::analyze) enum Fact {
    /// An SDO upload (expedited, segmented or block) of at most four
    /// bytes: `object` of `node` read directly.
    Read {
        node: NodeId,
        object: Object,
        value: u32,
    },
    /// `node` holds `value` in `object`: an upload, or a confirmed write
    /// (`written`) of an object the SDO monitor follows.
    Holds {
        node: NodeId,
        object: Object,
        value: u32,
        written: bool,
    },
    /// A download of at most four bytes to `object` (any object the SDO
    /// monitor assembles writes of) that `node` confirmed.
    Written {
        node: NodeId,
        object: Object,
        value: u32,
    },
    /// `node` sent a PDO while a start command to it waited for an answer
    /// (only then is it told: PDOs are many).
    Produced { node: NodeId },
}

/// The facts about the bus every monitor may read and none owns: which
/// profile decodes each node, and the EMCY ids moved by object 0x1014.
/// Only the dispatcher changes them, from facts the monitors learnt.
pub(in crate::analyze) struct Facts<'r> {
    pub(in crate::analyze) profiles: NodeProfiles<'r>,
    /// EMCY ids other than 0x80 + node, to their node.
    emcy_ids: HashMap<(u32, bool), NodeId>,
    /// The error frames so far: bursts, bus-offs.
    pub(in crate::analyze) bus: BusErrors,
}

impl<'r> Facts<'r> {
    /// The facts the options give: `--emcy-id`, the profiles chosen, and
    /// the DCFs' device types and identities, as if the trace had shown
    /// 0x1000 and 0x1018 (they choose the node's profile).
    pub(in crate::analyze) fn new(opts: &'r Options) -> Self {
        let mut profiles = NodeProfiles::new(&opts.profiles);
        for (node, dcf) in &opts.dcf {
            if let Some(v) = dcf.device_type {
                let object = Object {
                    index: sdo::DEVICE_TYPE,
                    sub: 0,
                };
                profiles.object_value(*node, object, v);
            }
            if let Some(v) = dcf.vendor_id {
                let object = Object {
                    index: sdo::IDENTITY,
                    sub: 1,
                };
                profiles.object_value(*node, object, v);
            }
        }
        Facts {
            profiles,
            emcy_ids: opts
                .emcy_ids
                .iter()
                .map(|e| ((e.id, e.extended), e.node))
                .collect(),
            bus: BusErrors::default(),
        }
    }

    /// The node a data frame's EMCY id belongs to: a moved id first, then
    /// the pre-defined set (standard ids 0x081-0x0FF).
    #[inline]
    pub(in crate::analyze) fn emcy_node(&self, id: u32, extended: bool) -> Option<NodeId> {
        // Nearly always empty: no hashing per frame then.
        let moved = if self.emcy_ids.is_empty() {
            None
        } else {
            self.emcy_ids.get(&(id, extended)).copied()
        };
        moved.or_else(|| if extended { None } else { emcy::emcy_node(id) })
    }

    /// Whether a standard id of the pre-defined sets (a heartbeat's) may
    /// be an EMCY id now: only when some EMCY id moved.
    #[inline]
    pub(in crate::analyze) fn moved_emcy(&self, id: u32) -> bool {
        !self.emcy_ids.is_empty() && self.emcy_node(id, false).is_some()
    }

    /// A node holds `value` in `object`: its profile may follow from it,
    /// or its EMCY id may have moved. `Some` with the EMCY id when it moved
    /// to one not known before for the node: frames on it are decoded from
    /// here on.
    pub(in crate::analyze) fn holds(
        &mut self,
        node: NodeId,
        object: Object,
        value: u32,
    ) -> Option<(u32, bool)> {
        self.profiles.object_value(node, object, value);
        if object.index != sdo::COB_ID_EMCY || object.sub != 0 {
            return None;
        }
        let (id, extended) = sdo::cob_id_emcy(value)?;
        (self.emcy_ids.insert((id, extended), node) != Some(node)).then_some((id, extended))
    }
}

/// Where a monitor's output goes: events to the sink, diagnostics to the
/// input's bounded log, counts, and the ids it wants decoded. Built by the
/// dispatcher for each call, so no monitor threads the sink, the file and
/// the options through its own calls.
pub(in crate::analyze) struct Emit<'a, E: Write> {
    pub(in crate::analyze) file: &'a str,
    pub(in crate::analyze) opts: &'a Options,
    pub(in crate::analyze) sink: &'a mut dyn Sink,
    pub(in crate::analyze) log: &'a mut DiagnosticLog<E>,
    pub(in crate::analyze) diags: &'a mut InputDiagnostics,
    /// Whether the format is known (diagnostics are held back till then).
    pub(in crate::analyze) decided: bool,
    /// Whether candump times are summed as deltas (`-td` detected).
    pub(in crate::analyze) summed_deltas: bool,
    pub(in crate::analyze) counts: &'a mut Counts,
    pub(in crate::analyze) wanted: &'a mut Wanted,
    /// Every event goes here too, before the filters.
    pub(in crate::analyze) incidents: &'a mut incident::Builder,
}

impl<E: Write> Emit<'_, E> {
    /// Hands `events` (emptied) to the sink as the node's events, if the
    /// options select the node (`--channel`, `--node`).
    pub(in crate::analyze) fn health(
        &mut self,
        channel: &str,
        node: NodeId,
        events: &mut Vec<(At, Health)>,
    ) -> Result<(), OutputError> {
        let selected = events.is_empty() || self.opts.selects(channel, node);
        for (at, health) in events.iter() {
            self.hear(channel, node, *at, health);
        }
        for (at, health) in events.drain(..) {
            if selected {
                self.sink
                    .health(&HealthEvent {
                        file: self.file,
                        line: at.line,
                        time: at.time,
                        channel,
                        node,
                        health: &health,
                    })
                    .map_err(OutputError)?;
            }
        }
        self.tell_incidents()
    }

    /// A node's health event, for the incidents.
    fn hear(&mut self, channel: &str, node: NodeId, at: At, health: &Health) {
        use crate::canopen::nmt::NmtState;
        use crate::timeline::nmt::Via;
        let b = &mut *self.incidents;
        b.tick(at.time);
        match health {
            // The boot-up is told as a boot.
            Health::Nmt {
                via: Via::BootUp, ..
            } => {}
            &Health::Nmt { state, via } => {
                let commanded = via == Via::Command;
                let reset = commanded && state == NmtState::Initialising;
                b.nmt(
                    channel,
                    node,
                    state == NmtState::Operational,
                    commanded,
                    reset,
                    at,
                );
            }
            Health::HeartbeatLost { .. } => b.heartbeat_lost(channel, node, at),
            &Health::DriveState { state, from, .. }
                if state.is_fault() && !from.is_some_and(|f| f.is_fault()) =>
            {
                b.axis_fault(channel, node, at)
            }
            Health::FaultReset { .. } => b.fault_reset(channel, node, at),
            _ => {}
        }
    }

    /// Incidents that closed, to the sink: those with a node the options
    /// select, or of a channel they select when they name no node.
    pub(in crate::analyze) fn tell_incidents(&mut self) -> Result<(), OutputError> {
        if self.incidents.closed.is_empty() {
            return Ok(());
        }
        let closed = std::mem::take(&mut self.incidents.closed);
        for incident in closed {
            let channel_selected =
                self.opts.channels.is_empty() || self.opts.channels.contains(&incident.channel);
            let node_selected = self.opts.nodes.is_empty()
                || incident.nodes.iter().any(|n| self.opts.nodes.contains(n));
            if !(channel_selected && node_selected) {
                continue;
            }
            self.incidents.told += 1;
            let r = &incident.events[incident.root.event];
            let key = incident::RootKey {
                channel: incident.channel.clone(),
                node: r.node,
                kind: r.kind.slug(),
                code: r.code,
            };
            let roots = &mut self.incidents.roots;
            if let Some(n) = roots.get_mut(&key) {
                *n += 1;
            } else if roots.len() < incident::MAX_ROOTS {
                roots.insert(key, 1);
            }
            let line = incident.events[incident.first].line;
            let time = Some(incident.start);
            let channel = incident.channel.clone();
            let bus = Bus::Incident(Box::new(incident));
            self.sink
                .bus(&BusEvent {
                    file: self.file,
                    line,
                    time,
                    channel: &channel,
                    bus: &bus,
                })
                .map_err(OutputError)?;
        }
        Ok(())
    }

    pub(in crate::analyze) fn emcy(&mut self, event: &EmcyEvent<'_>) -> Result<(), OutputError> {
        self.sink.emcy(event).map_err(OutputError)
    }

    pub(in crate::analyze) fn boot(&mut self, event: &BootEvent<'_>) -> Result<(), OutputError> {
        self.sink.boot(event).map_err(OutputError)
    }

    /// Bus events (emptied) to the sink, those of a node only if the
    /// options select it, those of a channel if they select the channel.
    pub(in crate::analyze) fn bus(&mut self, told: &mut Vec<Told>) -> Result<(), OutputError> {
        for t in told.iter() {
            match &t.bus {
                Bus::Errors(_) => self.incidents.bus_error(&t.channel, t.at),
                Bus::BusOff(off) => self.incidents.bus_off(&t.channel, off.node, t.at),
                Bus::SyncMissed(_) => self.incidents.sync_missed(&t.channel, t.at),
                _ => {}
            }
        }
        for t in told.drain(..) {
            self.bus_event(&t.channel, t.at, &t.bus)?;
        }
        self.tell_incidents()
    }

    /// One bus event to the sink, if the options select it; what the
    /// incidents hear of it is [`Emit::bus`]'s part (an SDO transfer, told
    /// here directly, is nothing to them).
    pub(in crate::analyze) fn bus_event(
        &mut self,
        channel: &str,
        at: At,
        bus: &Bus,
    ) -> Result<(), OutputError> {
        let selected = match bus.node() {
            Some(node) => self.opts.selects(channel, node),
            // An event of no node (a burst, the logging controller's
            // bus-off) is no node's: `--node` leaves it out.
            None => {
                self.opts.nodes.is_empty()
                    && (self.opts.channels.is_empty()
                        || self.opts.channels.iter().any(|c| c == channel))
            }
        };
        if selected {
            self.sink
                .bus(&BusEvent {
                    file: self.file,
                    line: at.line,
                    time: at.time,
                    channel,
                    bus,
                })
                .map_err(OutputError)?;
        }
        Ok(())
    }

    /// A diagnostic at `line` of the input.
    pub(in crate::analyze) fn diagnostic(&mut self, line: u64, message: String) {
        self.diags.report(self.log, self.decided, line, message);
    }

    /// A note about the input as a whole, after its name.
    pub(in crate::analyze) fn note(&mut self, message: &str) {
        self.log.note(&format!("{}: {message}", self.file));
    }
}
