//! Layer setting services and the TIME object: the bus-wide services a
//! master uses to set nodes up and to tell them the time. LSS frames are
//! few (a commissioning session), so each is an event; TIME frames come
//! every second or so, so they are summed into the input's report (how
//! far the producer's clock was from the trace's) and no event each.

use std::io::Write;

use super::context::{Emit, Facts, Monitor, Seen, Step};
use crate::analyze::analysis::OutputError;
use crate::analyze::bus::Told;
use crate::analyze::event::{Bus, LssIdentity, LssReport, TimeProducer};
use crate::analyze::nodes::Nodes;
use crate::analyze::options::Options;
use crate::canopen::NodeId;
use crate::canopen::lss::{self, Lss, Part, Service};
use crate::canopen::time::{TIME_ID, TimeOfDay};
use crate::timeline::At;
use crate::trace::{Interest, Timestamp};

#[derive(Default)]
pub(in crate::analyze) struct LssMonitor {
    /// The identity the master selected (switch state selective) or
    /// inquired since the nodes last went back to waiting.
    identity: LssIdentity,
    /// The node-id a configure request asked for, waiting for its answer.
    asked: Option<NodeId>,
    time: Option<TimeProducer>,
    told: Vec<Told>,
}

impl Monitor for LssMonitor {
    fn new(_opts: &Options) -> Self {
        Self::default()
    }

    fn frame<E: Write>(
        &mut self,
        frame: &Seen<'_>,
        _nodes: &mut Nodes,
        _facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<Step, OutputError> {
        if frame.extended {
            return Ok(Step::Pass);
        }
        match frame.id {
            lss::MASTER_ID | lss::SLAVE_ID => {
                let from_master = frame.id == lss::MASTER_ID;
                let decoded = Lss::decode(from_master, frame.data);
                let report = self.lss(decoded, from_master);
                self.told.push(Told {
                    channel: String::from_utf8_lossy(frame.channel).into_owned(),
                    at: frame.at,
                    bus: Bus::Lss(report),
                });
                let mut told = std::mem::take(&mut self.told);
                emit.bus(&mut told)?;
                self.told = told;
                Ok(Step::Done)
            }
            TIME_ID => {
                if let Some(stamp) = TimeOfDay::decode(frame.data) {
                    self.time_stamp(stamp, frame.at);
                }
                Ok(Step::Done)
            }
            _ => Ok(Step::Pass),
        }
    }

    fn interest(&self, interest: &mut Interest) {
        interest.add_standard(lss::MASTER_ID);
        interest.add_standard(lss::SLAVE_ID);
        interest.add_standard(TIME_ID);
    }
}

impl LssMonitor {
    /// The TIME producer over the input, if it sent a stamp.
    pub(in crate::analyze) fn time_producer(&self) -> Option<TimeProducer> {
        self.time
    }

    /// What an LSS frame says with what came before it.
    fn lss(&mut self, lss: Lss, from_master: bool) -> LssReport {
        let mut node = None;
        let mut identity = None;
        match lss {
            Lss::SwitchGlobal {
                configuration: false,
            } => {
                self.identity = LssIdentity::default();
                self.asked = None;
            }
            Lss::SwitchSelective { part, value } => {
                // A new selection begins with the vendor id.
                if part == Part::Vendor {
                    self.identity = LssIdentity::default();
                }
                self.set(part, value);
            }
            Lss::SwitchSelectiveAnswer => identity = Some(self.identity),
            Lss::ConfigureNodeId { node: n } => {
                self.asked = Some(NodeId::from(n));
                node = self.asked;
                identity = self.known();
            }
            Lss::Answer {
                service: Service::ConfigureNodeId,
                ..
            } => {
                node = self.asked.take();
                identity = self.known();
            }
            Lss::InquireAnswer { part, value } => {
                if part == Part::NodeId {
                    node = NodeId::try_from(value).ok();
                } else {
                    self.set(part, value);
                }
                identity = self.known();
            }
            _ => {}
        }
        LssReport {
            lss,
            from_master,
            node,
            identity,
        }
    }

    fn set(&mut self, part: Part, value: u32) {
        let slot = match part {
            Part::Vendor => &mut self.identity.vendor_id,
            Part::Product => &mut self.identity.product_code,
            Part::Revision => &mut self.identity.revision,
            Part::Serial => &mut self.identity.serial,
            _ => return,
        };
        *slot = Some(value);
    }

    /// The identity, if any part of it is known.
    fn known(&self) -> Option<LssIdentity> {
        (self.identity != LssIdentity::default()).then_some(self.identity)
    }

    fn time_stamp(&mut self, stamp: TimeOfDay, at: At) {
        let ms = stamp.unix_millis();
        let bus = Timestamp::from_parts(ms / 1000, ms % 1000, 3);
        let offset = at.time.map(|t| bus.since(t));
        match &mut self.time {
            Some(p) => {
                p.frames += 1;
                p.last_offset = offset;
            }
            None => {
                self.time = Some(TimeProducer {
                    frames: 1,
                    first: bus,
                    first_offset: offset,
                    last_offset: offset,
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(frames: &[(bool, &[u8])]) -> Vec<LssReport> {
        let mut m = LssMonitor::default();
        frames
            .iter()
            .map(|(from_master, data)| m.lss(Lss::decode(*from_master, data), *from_master))
            .collect()
    }

    #[test]
    fn a_configured_node_id_is_told_with_the_identity_selected() {
        let r = run(&[
            (true, &[0x40, 0x78, 0x56, 0x34, 0x12]),
            (true, &[0x41, 2, 0, 0, 0]),
            (true, &[0x42, 3, 0, 0, 0]),
            (true, &[0x43, 4, 0, 0, 0]),
            (false, &[0x44]),
            (true, &[0x11, 5]),
            (false, &[0x11, 0]),
            (true, &[0x04, 0]),
            (false, &[0x11, 0]),
        ]);
        let identity = LssIdentity {
            vendor_id: Some(0x1234_5678),
            product_code: Some(2),
            revision: Some(3),
            serial: Some(4),
        };
        assert_eq!(r[4].identity, Some(identity));
        assert_eq!((r[5].node, r[5].identity), (Some(5), Some(identity)));
        assert_eq!((r[6].node, r[6].identity), (Some(5), Some(identity)));
        assert!(!r[6].from_master);
        // Back to waiting: what was selected is forgotten; an answer with
        // no request before it names no node.
        assert_eq!((r[8].node, r[8].identity), (None, None));
    }

    #[test]
    fn inquired_parts_fill_the_identity() {
        let r = run(&[
            (true, &[0x04, 1]),
            (true, &[0x5A]),
            (false, &[0x5A, 9, 0, 0, 0]),
            (true, &[0x5E]),
            (false, &[0x5E, 7]),
        ]);
        assert_eq!(r[2].identity.and_then(|i| i.vendor_id), Some(9));
        assert_eq!(r[4].node, Some(7));
    }

    #[test]
    fn time_stamps_give_the_producer_clock_offset() {
        let mut m = LssMonitor::default();
        let at = |s: u64, ms: u64| At {
            time: Some(Timestamp::from_parts(s, ms, 3)),
            line: 1,
        };
        // The producer says 1700000000.000; the trace 1700000000.250.
        let stamp = TimeOfDay::decode(&[0x00, 0xB4, 0xC4, 0x04, 0xE2, 0x38]).unwrap();
        m.time_stamp(stamp, at(1_700_000_000, 250));
        m.time_stamp(stamp, at(1_699_999_999, 0));
        let p = m.time_producer().unwrap();
        assert_eq!(p.frames, 2);
        assert_eq!(
            p.first_offset.map(|s| s.attos()),
            Some(-250_000_000_000_000_000)
        );
        assert_eq!(
            p.last_offset.map(|s| s.attos()),
            Some(1_000_000_000_000_000_000)
        );
    }
}
