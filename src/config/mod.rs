//! The configuration a trace wrote into its nodes, as `emcy-decode config
//! TRACE` prints it: every object an SDO download wrote, the value the node
//! confirmed last, and the writes it never took (aborted, unanswered), per
//! node ([`Recorder`], the analysis [`Sink`] that keeps them); rendered as
//! a DCF-style INI file or JSON ([`render`]), and compared with a node's
//! DCF when one is given. No command line and no process I/O here: the
//! application reads the trace and writes the files.

pub mod render;

use std::collections::BTreeMap;
use std::io;

use crate::analyze::{BootEvent, Bus, BusEvent, Diagnostic, EmcyEvent, InputReport, Sink};
use crate::canopen::NodeId;
use crate::canopen::sdo::Object;
use crate::canopen::sdo::transfer::{Data, Direction, Outcome};

/// Objects kept at most over all nodes: 127 nodes writing every sub-index
/// of a few hundred objects stay far below it; a hostile trace writing
/// millions of distinct objects is cut (and says so).
pub const MAX_OBJECTS: usize = 200_000;

/// A node on a channel.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeKey {
    pub channel: String,
    pub node: NodeId,
}

/// What the trace wrote to one object of a node.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Written {
    /// The object's name, as the analysis named it.
    pub name: Option<String>,
    /// The last value the node confirmed, and the line of its confirmation.
    pub applied: Option<Value>,
    /// How many confirmed writes there were (the last one wins).
    pub writes: u64,
    /// A write after the last confirmed one that the node did not take:
    /// it never became the object's value.
    pub refused: Option<Refused>,
}

/// A value a download carried.
#[derive(Clone, Debug, PartialEq)]
pub struct Value {
    pub data: Data,
    /// The data as text (a VISIBLE_STRING object).
    pub text: Option<String>,
    pub line: u64,
}

/// A write the node did not take.
#[derive(Clone, Debug, PartialEq)]
pub struct Refused {
    pub outcome: Outcome,
    /// An abort code's meaning.
    pub text: Option<&'static str>,
    /// What the client tried to write, if the trace showed it.
    pub data: Option<Data>,
    pub line: u64,
}

/// The configuration of every node a trace wrote to.
#[derive(Clone, Debug, Default)]
pub struct Configuration {
    pub file: String,
    pub nodes: BTreeMap<NodeKey, BTreeMap<Object, Written>>,
    /// Writes left out past [`MAX_OBJECTS`].
    pub cut: u64,
    /// Why reading stopped early, as the analysis said.
    pub error: Option<String>,
}

/// The [`Sink`] that keeps what SDO downloads wrote: only `sdo` events of
/// downloads, of the nodes `only` names (all when empty).
#[derive(Debug, Default)]
pub struct Recorder {
    config: Configuration,
    only: Vec<NodeId>,
    objects: usize,
}

impl Recorder {
    /// Keeps the writes to the nodes in `only` (every node when empty).
    pub fn new(only: &[NodeId]) -> Recorder {
        Recorder {
            only: only.to_vec(),
            ..Recorder::default()
        }
    }

    pub fn into_configuration(self) -> Configuration {
        self.config
    }
}

impl Sink for Recorder {
    fn begin_input(&mut self, file: &str) -> io::Result<()> {
        self.config.file = file.to_string();
        Ok(())
    }

    fn emcy(&mut self, _: &EmcyEvent<'_>) -> io::Result<()> {
        Ok(())
    }

    fn boot(&mut self, _: &BootEvent<'_>) -> io::Result<()> {
        Ok(())
    }

    fn bus(&mut self, ev: &BusEvent<'_>) -> io::Result<()> {
        let Bus::Sdo(t) = ev.bus else {
            return Ok(());
        };
        if t.direction != Direction::Download
            || !(self.only.is_empty() || self.only.contains(&t.node))
        {
            return Ok(());
        }
        let key = NodeKey {
            channel: ev.channel.to_string(),
            node: t.node,
        };
        let objects = self.config.nodes.entry(key).or_default();
        let entry = match objects.get_mut(&t.object) {
            Some(entry) => entry,
            None if self.objects >= MAX_OBJECTS => {
                self.config.cut += 1;
                return Ok(());
            }
            None => {
                self.objects += 1;
                objects.entry(t.object).or_default()
            }
        };
        if entry.name.is_none() {
            entry.name = t.name.as_deref().map(str::to_string);
        }
        match (t.outcome, t.data) {
            (Outcome::Ok, Some(data)) => {
                entry.applied = Some(Value {
                    data,
                    text: t.text.clone(),
                    line: ev.line,
                });
                entry.writes += 1;
                entry.refused = None;
            }
            (outcome, data) => {
                entry.refused = Some(Refused {
                    outcome,
                    text: t.abort_text,
                    data,
                    line: ev.line,
                });
            }
        }
        Ok(())
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        self.config.error = input.error.clone();
        Ok(())
    }

    fn finish(&mut self, _: &[InputReport], _: &[Diagnostic]) -> io::Result<()> {
        Ok(())
    }
}
