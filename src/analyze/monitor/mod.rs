//! The monitors: one per CANopen service, each in its own file with its
//! own state, all fed by the dispatcher ([`Consumer`]) through one trait
//! ([`Monitor`]). A monitor keeps what it knows of a node in the node's
//! timeline ([`Nodes`]); what other monitors need of it goes through the
//! dispatcher as a [`Fact`] or the shared [`Facts`], never by one monitor
//! importing another.
//!
//! Adding a service is a file here implementing [`Monitor`], its `mod`
//! line, and a line in the list below: where it stands in the list says
//! which frames it sees before the others.
//!
//! [`Consumer`]: crate::analyze::consumer::Consumer
//! [`Nodes`]: crate::analyze::nodes::Nodes

mod coe;
pub(in crate::analyze) mod context;
mod deadlines;
mod drive;
mod emcy;
mod identity;
mod lss;
mod nmt;
mod sdo;

use std::io::Write;

pub(in crate::analyze) use coe::{Carried, CoeMonitor};
use context::{Emit, Fact, Facts, Monitor, Seen, Step};
pub(in crate::analyze) use drive::DriveMonitor;
pub(in crate::analyze) use emcy::EmcyMonitor;
pub(in crate::analyze) use identity::IdentityMonitor;
pub(in crate::analyze) use lss::LssMonitor;
pub(in crate::analyze) use nmt::{NmtMonitor, TakenFold};
pub(in crate::analyze) use sdo::SdoMonitor;

use super::analysis::OutputError;
use super::event::NodeReport;
use super::nodes::Nodes;
use super::options::Options;
use crate::timeline::At;
use crate::timeline::health::NodeHealth;
use crate::trace::Interest;

/// The list of monitors, in the order they see a frame: a monitor takes a
/// frame ([`Step::Done`]) or hands it on, so the order says which service
/// owns an id two could claim. It is also the order in which they hear a
/// fact, finish, and fill a node's report.
macro_rules! monitors {
    ($($(#[$doc:meta])* $name:ident: $monitor:ty,)*) => {
        pub(in crate::analyze) struct Monitors {
            $($(#[$doc])* pub(in crate::analyze) $name: $monitor,)*
        }

        impl Monitors {
            pub(in crate::analyze) fn new(opts: &Options) -> Self {
                Monitors {
                    $($name: <$monitor as Monitor>::new(opts),)*
                }
            }

            /// A decoded data frame, to each monitor in turn until one
            /// takes it.
            #[inline]
            pub(in crate::analyze) fn frame<E: Write>(
                &mut self,
                frame: &Seen<'_>,
                nodes: &mut Nodes,
                facts: &Facts<'_>,
                emit: &mut Emit<'_, E>,
            ) -> Result<Step, OutputError> {
                $(
                    match self.$name.frame(frame, nodes, facts, emit)? {
                        Step::Pass => {}
                        step => return Ok(step),
                    }
                )*
                Ok(Step::Pass)
            }

            /// A fact, to every monitor.
            pub(in crate::analyze) fn learn<E: Write>(
                &mut self,
                channel: &[u8],
                at: At,
                fact: Fact,
                nodes: &mut Nodes,
                facts: &Facts<'_>,
                emit: &mut Emit<'_, E>,
            ) -> Result<(), OutputError> {
                $(self.$name.learn(channel, at, fact, nodes, facts, emit)?;)*
                Ok(())
            }

            /// The end of the input, to every monitor.
            pub(in crate::analyze) fn finish<E: Write>(
                &mut self,
                end: At,
                nodes: &mut Nodes,
                facts: &Facts<'_>,
                emit: &mut Emit<'_, E>,
            ) -> Result<(), OutputError> {
                $(self.$name.finish(end, nodes, facts, emit)?;)*
                Ok(())
            }

            /// Every monitor's part of a node's report.
            pub(in crate::analyze) fn report(
                &self,
                report: &mut NodeReport,
                health: Option<&NodeHealth>,
            ) {
                $(self.$name.report(report, health);)*
            }

            /// The ids every monitor needs decoded.
            pub(in crate::analyze) fn interest(&self, interest: &mut Interest) {
                $(self.$name.interest(interest);)*
            }
        }
    };
}

monitors! {
    /// CiA 402 drives: first, as a PDO mapping may decode any id.
    drive: DriveMonitor,
    /// EMCY frames, and the boot-up's clearing of errors.
    emcy: EmcyMonitor,
    /// NMT commands, boot-ups, heartbeats, node guarding.
    nmt: NmtMonitor,
    /// SDO transfers and the error history read-outs.
    sdo: SdoMonitor,
    /// What each node said it is (0x1000, 0x1018).
    identity: IdentityMonitor,
    /// Layer setting services and the TIME object.
    lss: LssMonitor,
    /// CANopen over EtherCAT (fed its mailbox messages, not frames).
    coe: CoeMonitor,
}
