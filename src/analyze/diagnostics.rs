//! Where diagnostics go: stderr as they happen, bounded per input, and a
//! copy for the JSON document. What goes to stderr is escaped: file names
//! and trace text must not put control sequences on a terminal.

use std::io::Write;

use super::event::Diagnostic;
use crate::text::printable;

/// Where diagnostics go: stderr as they happen (bounded per input) and a
/// copy for the JSON document.
pub struct DiagnosticLog<E: Write> {
    stderr: E,
    pub collected: Vec<Diagnostic>,
    /// `--quiet`: diagnostics and notes are collected, not printed.
    pub quiet: bool,
}

impl<E: Write> DiagnosticLog<E> {
    pub fn new(stderr: E) -> Self {
        DiagnosticLog {
            stderr,
            collected: Vec::new(),
            quiet: false,
        }
    }

    pub(super) fn emit(&mut self, d: Diagnostic) {
        // A failing stderr must not stop decoding; the counts still record it.
        if !self.quiet {
            let _ = writeln!(self.stderr, "{}", printable(&d.to_string()));
        }
        self.collected.push(d);
    }

    /// Passes on what another log (an input read on another thread) wrote
    /// and collected.
    pub fn replay(&mut self, written: &[u8], collected: Vec<Diagnostic>) {
        let _ = self.stderr.write_all(written);
        self.collected.extend(collected);
    }

    /// The stderr this log wrote to.
    pub fn into_inner(self) -> E {
        self.stderr
    }

    /// A one-line `error:` message (not kept in the JSON diagnostics).
    pub fn error(&mut self, message: &str) {
        let _ = writeln!(self.stderr, "error: {}", printable(message));
    }

    pub fn note(&mut self, message: &str) {
        if !self.quiet {
            let _ = writeln!(self.stderr, "{}", printable(message));
        }
    }
}

/// Bounded diagnostics for one input. While the format is unknown they are
/// held back: if no format is ever found the input gets one `error:` line
/// instead of a screenful of "not a frame".
pub(super) struct InputDiagnostics {
    pub(super) file: String,
    pub(super) limit: usize,
    pub(super) shown: usize,
    pub(super) suppressed: u64,
    pub(super) pending: Vec<Diagnostic>,
}

impl InputDiagnostics {
    pub(super) fn report<E: Write>(
        &mut self,
        log: &mut DiagnosticLog<E>,
        decided: bool,
        line: u64,
        message: String,
    ) {
        if self.shown >= self.limit {
            self.suppressed += 1;
            return;
        }
        self.shown += 1;
        let d = Diagnostic {
            file: self.file.clone(),
            line,
            message,
        };
        if decided {
            log.emit(d);
        } else {
            self.pending.push(d);
        }
    }

    pub(super) fn release<E: Write>(&mut self, log: &mut DiagnosticLog<E>) {
        for d in self.pending.drain(..) {
            log.emit(d);
        }
    }
}
