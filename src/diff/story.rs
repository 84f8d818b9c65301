//! A trace told as each node's CANopen story: the steps that mean something
//! at the CANopen level (boot-ups, NMT states, EMCY codes, CiA 402 drive
//! states, fault resets, SDO transfers and aborts, heartbeat losses,
//! bus-offs, LSS services), without their times and without process data, so that two
//! runs of the same machine can be compared step by step. [`Recorder`] is
//! the analysis [`Sink`] that writes it.

use std::collections::BTreeMap;
use std::fmt::{self, Write as _};
use std::io;

use crate::analyze::{BootEvent, Bus, BusEvent, Diagnostic, EmcyEvent, Health, HealthEvent};
use crate::analyze::{InputReport, NodeReport, Sink};
use crate::canopen::NodeId;
use crate::canopen::nmt::NmtState;
use crate::canopen::pdo::Mapping;
use crate::canopen::sdo::transfer::{Direction, Outcome, SHOWN_BYTES};
use crate::timeline::drive::DriveState;
use crate::timeline::nmt::Via;

/// Steps a story keeps at most, over all its nodes: a trace of millions of
/// EMCYs would otherwise be held whole. Past it the story says it was cut
/// and the comparison says so.
pub const MAX_STEPS: usize = 2_000_000;

/// One step of a node's story. Two steps are equal when they mean the same
/// at the CANopen level, whatever their times and lines.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Step {
    /// The node said it booted (NMT boot-up).
    Boot,
    /// The node's NMT state changed: said by the node (heartbeat, guarding,
    /// boot-up, PDOs) or assumed from a master's command it did not
    /// contradict (`commanded`).
    Nmt { state: NmtState, commanded: bool },
    /// An EMCY: its code (0x0000 is the node's error reset) and error
    /// register.
    Emcy { code: u16, register: u8 },
    /// A CiA 402 drive's statusword showed another state.
    DriveState(DriveState),
    /// The master reset a drive's fault (controlword bit 7).
    FaultReset,
    /// An SDO transfer was aborted.
    SdoAbort {
        index: u16,
        subindex: u8,
        abort_code: u32,
        by_server: bool,
    },
    /// An SDO transfer that did not abort (aborts are [`Step::SdoAbort`]):
    /// a download with the value written (its size and hash), an upload
    /// without the value read, which is the node's state of the moment
    /// (process data when the master polls it).
    Sdo {
        direction: Direction,
        index: u16,
        subindex: u8,
        written: Option<Written>,
        result: Outcome,
    },
    /// The node's heartbeat or guarding deadline passed.
    HeartbeatLost,
    /// A lost node was heard again (`restarted`: with a boot-up).
    HeartbeatBack { restarted: bool },
    /// A controller left the bus (the node's, or the logging one's in the
    /// bus's own story).
    BusOff,
    /// An LSS service, as words (the bus's own story).
    Lss(String),
}

impl Step {
    /// The JSON name of the step's kind: the event type that told it.
    pub fn kind(&self) -> &'static str {
        match self {
            Step::Boot => "boot",
            Step::Nmt { .. } => "nmt",
            Step::Emcy { .. } => "emcy",
            Step::DriveState(_) => "axis_state",
            Step::FaultReset => "fault_reset",
            Step::SdoAbort { .. } => "sdo_abort",
            Step::Sdo { .. } => "sdo",
            Step::HeartbeatLost => "heartbeat_lost",
            Step::HeartbeatBack { .. } => "heartbeat_back",
            Step::BusOff => "bus_off",
            Step::Lss(_) => "lss",
        }
    }
}

impl fmt::Display for Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Step::Boot => f.write_str("boot-up"),
            Step::Nmt { state, commanded } => {
                let how = if *commanded { "commanded" } else { "said" };
                write!(f, "NMT {} ({how})", state.slug())
            }
            Step::Emcy { code: 0, .. } => f.write_str("EMCY 0x0000 (error reset)"),
            Step::Emcy { code, register } => {
                write!(f, "EMCY {code:#06x} register {register:#04x}")
            }
            Step::DriveState(s) => write!(f, "drive {}", s.slug()),
            Step::FaultReset => f.write_str("fault reset"),
            Step::SdoAbort {
                index,
                subindex,
                abort_code,
                by_server,
            } => {
                let by = if *by_server { "node" } else { "client" };
                write!(
                    f,
                    "SDO {index:#06x}.{subindex:02x} aborted by the {by}: {abort_code:#010x} {}",
                    crate::canopen::sdo::abort::describe(*abort_code)
                )
            }
            Step::Sdo {
                direction,
                index,
                subindex,
                written,
                result,
            } => {
                write!(f, "SDO {} {index:#06x}.{subindex:02x}", direction.name())?;
                match written {
                    Some(w) if w.hex.is_empty() => write!(f, " of {} bytes", w.size)?,
                    Some(w) if w.size as usize <= SHOWN_BYTES => write!(f, " = {}", w.hex)?,
                    Some(w) => write!(
                        f,
                        " = {}... ({} bytes, hash {:016x})",
                        w.hex, w.size, w.hash
                    )?,
                    None => {}
                }
                write!(f, ": {}", result.name())
            }
            Step::HeartbeatLost => f.write_str("heartbeat lost"),
            Step::HeartbeatBack { restarted: true } => f.write_str("heard again, rebooted"),
            Step::HeartbeatBack { restarted: false } => f.write_str("heard again"),
            Step::BusOff => f.write_str("bus-off"),
            Step::Lss(words) => write!(f, "LSS {words}"),
        }
    }
}

/// A value an SDO download wrote, as the story compares it: its size and
/// hash, and its bytes in hex (the first 64) to show.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Written {
    pub size: u32,
    pub hash: u64,
    pub hex: String,
}

impl Written {
    /// A value whose segments were not read (a long download) is known by
    /// its size alone.
    fn of(data: &crate::canopen::sdo::transfer::Data) -> Written {
        if !data.whole {
            return Written {
                size: data.size,
                hash: 0,
                hex: String::new(),
            };
        }
        let mut hex = Vec::new();
        crate::report::format::push_hex(&mut hex, data.shown());
        Written {
            size: data.size,
            hash: data.hash,
            hex: String::from_utf8_lossy(&hex).into_owned(),
        }
    }
}

/// Whose story: a node on a channel, or the bus of a channel (`node`
/// `None`: bus-offs of the logging controller, LSS services).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Teller {
    pub channel: String,
    pub node: Option<NodeId>,
}

impl fmt::Display for Teller {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.node {
            Some(n) => write!(f, "node {n}")?,
            None => f.write_str("the bus")?,
        }
        if !self.channel.is_empty() {
            write!(f, " on {}", self.channel)?;
        }
        Ok(())
    }
}

/// One teller's steps, in the trace's order, with the line each came from.
#[derive(Clone, Debug, Default)]
pub struct NodeStory {
    pub steps: Vec<Step>,
    pub lines: Vec<u64>,
    /// What the node was at the end of the trace, as (fact, value) pairs
    /// in a fixed order: its NMT state, device type, the errors still
    /// active, its PDO mappings.
    pub end: Vec<(&'static str, String)>,
}

/// A trace's stories, by teller.
#[derive(Clone, Debug, Default)]
pub struct Story {
    pub file: String,
    pub tellers: BTreeMap<Teller, NodeStory>,
    /// Steps left out past [`MAX_STEPS`].
    pub cut: u64,
    /// Why reading stopped early, as the analysis said.
    pub error: Option<String>,
}

/// The [`Sink`] that records a [`Story`].
#[derive(Debug, Default)]
pub struct Recorder {
    story: Story,
    steps: usize,
}

impl Recorder {
    pub fn new() -> Recorder {
        Recorder::default()
    }

    /// The story, its steps in line order per teller (bus events are told
    /// when they close, after later lines).
    pub fn into_story(mut self) -> Story {
        for told in self.story.tellers.values_mut() {
            if told.lines.is_sorted() {
                continue;
            }
            let mut pairs: Vec<(u64, Step)> =
                told.lines.drain(..).zip(told.steps.drain(..)).collect();
            pairs.sort_by_key(|&(line, _)| line);
            (told.lines, told.steps) = pairs.into_iter().unzip();
        }
        self.story
    }

    /// The last step told of a teller.
    fn last_step(&self, channel: &str, node: Option<NodeId>) -> Option<&Step> {
        let teller = Teller {
            channel: channel.to_string(),
            node,
        };
        self.story.tellers.get(&teller)?.steps.last()
    }

    fn push(&mut self, channel: &str, node: Option<NodeId>, line: u64, step: Step) {
        if self.steps >= MAX_STEPS {
            self.story.cut += 1;
            return;
        }
        self.steps += 1;
        let teller = Teller {
            channel: channel.to_string(),
            node,
        };
        let told = self.story.tellers.entry(teller).or_default();
        told.steps.push(step);
        told.lines.push(line);
    }
}

impl Sink for Recorder {
    fn begin_input(&mut self, file: &str) -> io::Result<()> {
        self.story.file = file.to_string();
        Ok(())
    }

    fn emcy(&mut self, e: &EmcyEvent<'_>) -> io::Result<()> {
        let step = Step::Emcy {
            code: e.emcy.code,
            register: e.emcy.register.0,
        };
        self.push(e.channel, Some(e.node), e.line, step);
        Ok(())
    }

    fn boot(&mut self, e: &BootEvent<'_>) -> io::Result<()> {
        self.push(e.channel, Some(e.node), e.line, Step::Boot);
        Ok(())
    }

    fn health(&mut self, e: &HealthEvent<'_>) -> io::Result<()> {
        let step = match e.health {
            // The boot-up is its own step; the pre-operational it implies
            // would say it twice.
            Health::Nmt {
                via: Via::BootUp, ..
            } => return Ok(()),
            &Health::Nmt { state, via } => Step::Nmt {
                state,
                commanded: via == Via::Command,
            },
            Health::HeartbeatLost { .. } => Step::HeartbeatLost,
            &Health::HeartbeatBack { restarted, .. } => Step::HeartbeatBack { restarted },
            &Health::SdoAbort {
                index,
                subindex,
                abort_code,
                by_server,
                ..
            } => Step::SdoAbort {
                index,
                subindex,
                abort_code,
                by_server,
            },
            &Health::DriveState { state, .. } => Step::DriveState(state),
            Health::FaultReset { .. } => Step::FaultReset,
            // A read-out of the error history repeats EMCYs already told.
            Health::ErrorHistory(_) | Health::ErrorHistoryCleared => return Ok(()),
        };
        self.push(e.channel, Some(e.node), e.line, step);
        Ok(())
    }

    fn bus(&mut self, e: &BusEvent<'_>) -> io::Result<()> {
        let (node, step) = match e.bus {
            Bus::BusOff(off) => (off.node, Step::BusOff),
            Bus::Lss(lss) => (None, Step::Lss(lss.lss.words())),
            // Error frames come and go with the wiring and the noise of
            // the day: a difference of timing, not of meaning.
            Bus::Errors(_) => return Ok(()),
            // An incident retells the steps above.
            Bus::Incident(_) => return Ok(()),
            // A late SYNC is timing.
            Bus::SyncMissed(_) => return Ok(()),
            // An abort is its own step (`sdo_abort`).
            Bus::Sdo(t) if matches!(t.outcome, Outcome::Abort { .. }) => return Ok(()),
            Bus::Sdo(t) => {
                let step = Step::Sdo {
                    direction: t.direction,
                    index: t.object.index,
                    subindex: t.object.sub,
                    written: t
                        .data
                        .filter(|_| t.direction == Direction::Download)
                        .map(|d| Written::of(&d)),
                    result: t.outcome,
                };
                // A master polling an object repeats the same step as
                // often as the trace is long: once is the story.
                if self.last_step(e.channel, Some(t.node)) == Some(&step) {
                    return Ok(());
                }
                (Some(t.node), step)
            }
        };
        self.push(e.channel, node, e.line, step);
        Ok(())
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        self.story.error = input.error.clone();
        for node in &input.nodes {
            let teller = Teller {
                channel: node.channel.clone(),
                node: Some(node.node),
            };
            self.story.tellers.entry(teller).or_default().end = end_facts(node);
        }
        Ok(())
    }

    fn finish(&mut self, _: &[InputReport], _: &[Diagnostic]) -> io::Result<()> {
        Ok(())
    }
}

/// What a node was at the end, in the order the comparison reports it.
fn end_facts(node: &NodeReport) -> Vec<(&'static str, String)> {
    let mut facts = Vec::new();
    let nmt = node.nmt_state.map_or("unknown", NmtState::slug);
    facts.push(("nmt_state", nmt.to_string()));
    if let Some(t) = node.device_type {
        facts.push(("device_type", format!("{t:#010x}")));
    }
    // Who the node said it is: a replaced device or new firmware shows here.
    if let Some(id) = &node.identity {
        let values = [
            ("vendor_id", id.vendor_id),
            ("product_code", id.product_code),
            ("revision", id.revision),
            ("serial", id.serial),
        ];
        for (key, v) in values {
            if let Some(v) = v {
                facts.push((key, format!("{:#010x}", v.value)));
            }
        }
        let texts = [
            ("name", &id.name),
            ("hardware_version", &id.hardware_version),
            ("software_version", &id.software_version),
        ];
        for (key, t) in texts {
            if let Some(t) = t {
                facts.push((key, t.text.clone()));
            }
        }
    }
    let active: Vec<String> = node.active.iter().map(|c| format!("{c:#06x}")).collect();
    facts.push(("active", words_or_none(&active)));
    if let Some(drive) = &node.drive {
        let maps: Vec<String> = drive.mappings.iter().map(mapping_words).collect();
        facts.push(("pdo_mappings", words_or_none(&maps)));
    }
    facts
}

fn words_or_none(items: &[String]) -> String {
    if items.is_empty() {
        "none".to_string()
    } else {
        items.join(", ")
    }
}

/// `0x181 [0x6041.00/16 0x6061.00/8]`
fn mapping_words(m: &Mapping) -> String {
    let mut s = format!("{:#05x} [", m.cob_id.id);
    for (i, o) in m.objects.iter().enumerate() {
        if i > 0 {
            s.push(' ');
        }
        let _ = write!(s, "{:#06x}.{:02x}/{}", o.object.index, o.object.sub, o.bits);
    }
    s.push(']');
    s
}
