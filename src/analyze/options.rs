//! What the user asked for that shapes reading and selection, in a file of
//! its own: every part of the analysis reads it, and none of them should
//! have to import the module that runs them.

use crate::canopen::NodeId;
use crate::canopen::dcf::Dcf;
use crate::canopen::pdo::Mapping;
use crate::canopen::profile_choice::ProfileChoice;
use crate::timeline::history::DEFAULT_SPILL_AT;
use crate::trace::Format;
use crate::trace::Span;
use crate::trace::cancel::Cancel;
use crate::trace::deltas::TimeMode;
use crate::trace::lines::{DEFAULT_BLOCK, DEFAULT_MAX_LINE};

/// The most nodes (pairs of channel and node id) one input may name. A real
/// network has 127 CANopen nodes (or some hundreds of EtherCAT slaves) on a
/// few channels; a hostile trace naming a million channels took 1.03 GB
/// and aborted under a 768 MB address-space limit. Each node costs about a
/// KiB (its timeline, report and history), so this bounds the table at
/// about 100 MB; past it, reading stops with an error and what was read is
/// reported.
pub const MAX_NODES: usize = 100_000;

/// `--sdo-timeout`'s default, in ms: CANopenNode's and most masters' SDO
/// client timeouts are 500 ms to 1 s, so a node silent for a second did
/// not answer.
pub const DEFAULT_SDO_TIMEOUT_MS: u64 = 1000;

/// What the user asked for that shapes reading and selection.
#[derive(Clone, Debug)]
pub struct Options {
    /// `--input-format`: skip detection.
    pub input_format: Option<Format>,
    /// `--timestamps`: what candump times are; `None` detects `-td` deltas.
    pub timestamps: Option<TimeMode>,
    /// The input is a live stream or a followed file: nothing is read ahead
    /// (it would wait for lines), so `-td` deltas are not detected.
    pub live: bool,
    /// `--node`: report only these nodes (empty = all).
    pub nodes: Vec<NodeId>,
    /// `--channel`: report only these channels (empty = all).
    pub channels: Vec<String>,
    /// Diagnostics printed per input; the counts stay exact beyond it.
    pub max_diagnostics: usize,
    /// Lines longer than this are reported and skipped.
    pub max_line: usize,
    /// Threads classifying lines; 1 = all on the calling thread.
    pub threads: usize,
    /// Bytes per read / per block handed to a thread.
    pub block_size: usize,
    /// Closed error intervals kept in memory before they go to a temporary file.
    pub spill_at: usize,
    /// Nodes (pairs of channel and node id) one input may name before
    /// reading stops with an error ([`MAX_NODES`]; smaller in tests).
    pub max_nodes: usize,
    /// `--emcy-id`: EMCY COB-IDs moved by object 0x1014, to the node they belong to.
    pub emcy_ids: Vec<EmcyId>,
    /// `--profile`, `--profile-file`: which profile decodes which node.
    pub profiles: ProfileChoice,
    /// Ends reading when cancelled (Ctrl-C): what was read is reported.
    pub cancel: Cancel,
    /// `--heartbeat-timeout`: every node's heartbeat timeout.
    pub heartbeat_timeout: Option<Span>,
    /// `--sdo-timeout`: an SDO transfer whose node gives no answer this
    /// long after the client's frame is unanswered.
    pub sdo_timeout: Span,
    /// `--pdo`: PDO mappings the user gives (source `option`).
    pub pdo: Vec<Mapping>,
    /// `--dcf NODE=FILE`, read: mappings (source `dcf`) and identities.
    pub dcf: Vec<(NodeId, Dcf)>,
    /// `--assume-cia402-pdo`: the predefined CiA 402 mapping for PDOs no
    /// other source maps (source `assumed`).
    pub assume_cia402_pdo: bool,
    /// A `--node`/`--channel` that selects nothing fails the run (a
    /// `--fail-on` gate): the input's note on it is kept in its report
    /// ([`InputReport::unmatched`]) for the run's error line, not printed.
    ///
    /// [`InputReport::unmatched`]: super::InputReport::unmatched
    pub unmatched_filter_fails: bool,
    /// `--incident-gap`: fault-like events further apart on a channel
    /// belong to different incidents.
    pub incident_gap: Span,
    /// `--timing`: every frame is counted and timed per channel and id.
    pub timing: bool,
    /// `--bitrate`: the bus's bit rate in bit/s, for the load (else the
    /// one the trace records, if any).
    pub bit_rate: Option<u32>,
}

/// A node's EMCY COB-ID other than 0x80 + node (object 0x1014).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EmcyId {
    pub id: u32,
    pub extended: bool,
    pub node: NodeId,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            input_format: None,
            timestamps: None,
            live: false,
            nodes: Vec::new(),
            channels: Vec::new(),
            max_diagnostics: 20,
            max_line: DEFAULT_MAX_LINE,
            threads: 1,
            block_size: DEFAULT_BLOCK,
            spill_at: DEFAULT_SPILL_AT,
            max_nodes: MAX_NODES,
            emcy_ids: Vec::new(),
            profiles: ProfileChoice::default(),
            cancel: Cancel::new(),
            heartbeat_timeout: None,
            sdo_timeout: Span::from_millis(DEFAULT_SDO_TIMEOUT_MS),
            pdo: Vec::new(),
            dcf: Vec::new(),
            assume_cia402_pdo: false,
            unmatched_filter_fails: false,
            incident_gap: Span::from_millis(super::incident::DEFAULT_GAP_MS),
            timing: false,
            bit_rate: None,
        }
    }
}

impl Options {
    pub(crate) fn selects(&self, channel: &str, node: NodeId) -> bool {
        (self.nodes.is_empty() || self.nodes.contains(&node))
            && (self.channels.is_empty() || self.channels.iter().any(|c| c == channel))
    }
}
