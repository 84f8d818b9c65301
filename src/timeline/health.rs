//! A node's health besides its EMCYs: NMT state, heartbeat outages and the
//! read-outs of its error history, kept with its error timeline.

use super::drive::DriveRecord;
use super::error_history::{HistoryReader, ReadOut};
use super::heartbeat::HeartbeatMonitor;
use super::nmt::NodeNmt;
use crate::trace::Span;

/// Allocated for a node once it sends or is sent something of these.
#[derive(Clone, Debug, Default)]
pub struct NodeHealth {
    pub nmt: NodeNmt,
    pub heartbeat: HeartbeatMonitor,
    pub history: HistoryReader,
    /// The last read-out of 0x1003 (an empty one after a clear).
    pub last_read_out: Option<ReadOut>,
    /// Where the caller's deadline schedule keeps the node, once it has
    /// had a deadline.
    pub schedule_slot: Option<u32>,
    /// Its CiA 402 drive, once a statusword or controlword of it was
    /// decoded.
    pub drive: Option<Box<DriveRecord>>,
}

impl NodeHealth {
    /// `timeout`: `--heartbeat-timeout`, if given.
    pub fn new(timeout: Option<Span>) -> Self {
        NodeHealth {
            heartbeat: HeartbeatMonitor::new(timeout),
            ..Self::default()
        }
    }
}
