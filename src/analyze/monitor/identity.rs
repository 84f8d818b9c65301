//! The identity monitor: what each node said it is, from the SDO reads a
//! master makes at start-up: its device type (0x1000), its identity object
//! (0x1018: vendor id, product code, revision, serial number) and the
//! texts it names itself by (0x1008 device name, 0x1009 hardware version,
//! 0x100A software version), each with the line that showed it. Reads
//! only: a node's answer is what it is, a write to these read-only objects
//! is not.

use std::collections::HashMap;
use std::io::Write;

use super::context::{Emit, Fact, Facts, Monitor};
use crate::analyze::analysis::OutputError;
use crate::analyze::event::{Identified, IdentifiedText, NodeIdentity, NodeReport};
use crate::analyze::nodes::Nodes;
use crate::analyze::options::Options;
use crate::canopen::sdo::{DEVICE_TYPE, IDENTITY, Object, Text};
use crate::canopen::{NodeId, dictionary};
use crate::timeline::At;
use crate::timeline::health::NodeHealth;

/// Nodes whose identity is kept; reads of more are not (a hostile input
/// could name a million channels).
const MAX_NODES: usize = 4096;

#[derive(Default)]
pub(in crate::analyze) struct IdentityMonitor {
    /// By channel and node.
    nodes: HashMap<(String, NodeId), NodeIdentity>,
}

impl Monitor for IdentityMonitor {
    fn new(_opts: &Options) -> Self {
        IdentityMonitor::default()
    }

    /// A value a node answered a read with (a confirmed write of these
    /// read-only objects says nothing of the node).
    fn learn<E: Write>(
        &mut self,
        channel: &[u8],
        at: At,
        fact: Fact,
        _nodes: &mut Nodes,
        _facts: &Facts<'_>,
        _emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        let (node, object, value) = match fact {
            Fact::Read {
                node,
                object,
                value,
            }
            | Fact::Holds {
                node,
                object,
                value,
                written: false,
            } => (node, object, value),
            _ => return Ok(()),
        };
        // A text of at most four bytes came as a value: its bytes, to the
        // first NUL (a short text's padding).
        if text_of(object).is_some() {
            let bytes = value.to_le_bytes();
            let len = bytes.iter().position(|b| *b == 0).unwrap_or(bytes.len());
            self.text_bytes(
                channel,
                at,
                node,
                object,
                bytes.get(..len).unwrap_or_default(),
            );
            return Ok(());
        }
        let Some(field) = Field::of(object.index, object.sub) else {
            return Ok(());
        };
        if let Some(identity) = self.node(channel, node) {
            // The last answer wins (a node read twice answers alike).
            *field.of_node(identity) = Some(Identified {
                value,
                line: at.line,
            });
        }
        Ok(())
    }

    fn report(&self, report: &mut NodeReport, _health: Option<&NodeHealth>) {
        if self.nodes.is_empty() {
            return;
        }
        report.identity = self
            .nodes
            .get(&(report.channel.clone(), report.node))
            .map(|id| Box::new(id.clone()));
    }
}

impl IdentityMonitor {
    /// A text longer than four bytes a node answered a read with.
    pub(in crate::analyze) fn text(&mut self, channel: &[u8], at: At, text: &Text) {
        self.text_bytes(channel, at, text.node, text.object, &text.bytes);
    }

    fn text_bytes(&mut self, channel: &[u8], at: At, node: NodeId, object: Object, bytes: &[u8]) {
        let Some(field) = text_of(object) else {
            return;
        };
        if let Some(identity) = self.node(channel, node) {
            let text = dictionary::visible_string(bytes);
            *field(identity) = Some(IdentifiedText {
                text,
                line: at.line,
            });
        }
    }

    /// The identity of `node` on `channel`, made when there is room.
    fn node(&mut self, channel: &[u8], node: NodeId) -> Option<&mut NodeIdentity> {
        let key = (String::from_utf8_lossy(channel).into_owned(), node);
        let full = self.nodes.len() >= MAX_NODES;
        match self.nodes.get_mut(&key) {
            Some(_) => self.nodes.get_mut(&key),
            None if full => None,
            None => Some(self.nodes.entry(key).or_default()),
        }
    }
}

/// Where a text object goes in a node's identity.
fn text_of(object: Object) -> Option<fn(&mut NodeIdentity) -> &mut Option<IdentifiedText>> {
    match (object.index, object.sub) {
        (0x1008, 0) => Some(|id| &mut id.name),
        (0x1009, 0) => Some(|id| &mut id.hardware_version),
        (0x100A, 0) => Some(|id| &mut id.software_version),
        _ => None,
    }
}

/// Which value of a node's identity an object is.
#[derive(Clone, Copy)]
enum Field {
    DeviceType,
    VendorId,
    ProductCode,
    Revision,
    Serial,
}

impl Field {
    fn of(index: u16, sub: u8) -> Option<Field> {
        Some(match (index, sub) {
            (DEVICE_TYPE, 0) => Field::DeviceType,
            (IDENTITY, 1) => Field::VendorId,
            (IDENTITY, 2) => Field::ProductCode,
            (IDENTITY, 3) => Field::Revision,
            (IDENTITY, 4) => Field::Serial,
            _ => return None,
        })
    }

    fn of_node(self, id: &mut NodeIdentity) -> &mut Option<Identified> {
        match self {
            Field::DeviceType => &mut id.device_type,
            Field::VendorId => &mut id.vendor_id,
            Field::ProductCode => &mut id.product_code,
            Field::Revision => &mut id.revision,
            Field::Serial => &mut id.serial,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_objects_and_texts_by_index_and_sub() {
        assert!(Field::of(0x1000, 0).is_some());
        assert!(Field::of(0x1000, 1).is_none());
        for sub in 1..=4 {
            assert!(Field::of(0x1018, sub).is_some(), "{sub}");
        }
        assert!(Field::of(0x1018, 0).is_none() && Field::of(0x1018, 5).is_none());
        for index in 0x1008..=0x100A {
            assert!(text_of(Object { index, sub: 0 }).is_some());
            assert!(text_of(Object { index, sub: 1 }).is_none());
        }
        assert!(
            text_of(Object {
                index: 0x1007,
                sub: 0
            })
            .is_none()
        );
    }
}
