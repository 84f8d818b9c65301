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
            },
            errors_raised: 0,
            frames_with_warnings: 0,
            worst_category: None,
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
}
