//! What one input's analysis gives back, and the one error that stops it:
//! in a file of their own, so the parts that produce them need not import
//! the module that runs them.

use std::io;

use super::event::{Counts, InputReport};
use crate::timeline::history::ErrorHistory;

impl Analysis {
    /// An input that could not be opened: nothing read, the reason.
    pub fn unopened(file: String, error: String) -> Analysis {
        Analysis {
            report: InputReport {
                file,
                format: None,
                gzip: false,
                counts: Counts::default(),
                nodes: Vec::new(),
                history: ErrorHistory::default(),
                first_time: None,
                last_time: None,
                timestamps: None,
                error: Some(error),
                nmt_unanswered: Vec::new(),
                unmatched: None,
                bus_errors: Vec::new(),
                time_producer: None,
                incident_roots: Vec::new(),
                channels: Vec::new(),
            },
            errors_raised: 0,
            frames_with_warnings: 0,
            worst_category: None,
            incidents: 0,
            reading: Reading::default(),
        }
    }
}

/// Writing the report failed (typically a closed pipe): stop everything.
#[derive(Debug)]
pub struct OutputError(pub io::Error);

/// The result of one input: its report plus what `--fail-on` needs.
#[derive(Debug)]
pub struct Analysis {
    pub report: InputReport,
    /// Selected EMCY frames with an error code (not a reset).
    pub errors_raised: u64,
    /// Selected EMCY frames that carried a protocol warning.
    pub frames_with_warnings: u64,
    /// The lowest (most severe) profile category of a selected error EMCY.
    pub worst_category: Option<u8>,
    /// Incidents of the selected nodes and channels told.
    pub incidents: u64,
    /// How the input was read (for `--verbose`).
    pub reading: Reading,
}

/// How an input was read on several threads: what the workers parsed and
/// what the consumer had to read again in line order because the ids it
/// decodes widened after a worker had parsed a block (see
/// `docs/performance.md`). All zero when one thread read it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reading {
    /// Workers that parsed blocks.
    pub workers: usize,
    /// Blocks the workers parsed.
    pub blocks: u64,
    /// Of them, read again whole in order.
    pub blocks_read_again: u64,
    /// Of them, read again from a frame on which the interest widened.
    pub rests_read_again: u64,
    /// The consumer stopped the workers and read the rest alone, since
    /// blocks kept being read twice.
    pub fell_back: bool,
}
