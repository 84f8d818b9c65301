//! `--format ndjson`: one object per line, events in trace order, then node
//! objects, then input objects. The stable machine format; streamable.

use std::io::{self, Write};

use serde::Serialize;

use super::{BootEvent, Diagnostic, EmcyEvent, InputReport, NodeJson, Renderer, to_io};

/// Events in trace order, then node objects, then input objects.
pub struct Ndjson<W: Write> {
    out: W,
    /// Flush after every event (live use: `candump -L can0 | emcy-decode -`).
    flush_each: bool,
}

impl<W: Write> Ndjson<W> {
    pub fn new(out: W, flush_each: bool) -> Self {
        Ndjson { out, flush_each }
    }

    fn line<T: Serialize>(&mut self, value: &T) -> io::Result<()> {
        serde_json::to_writer(&mut self.out, value).map_err(to_io)?;
        self.out.write_all(b"\n")?;
        if self.flush_each {
            self.out.flush()?;
        }
        Ok(())
    }
}

impl<W: Write> Renderer for Ndjson<W> {
    fn emcy(&mut self, event: &EmcyEvent<'_>) -> io::Result<()> {
        self.line(event)
    }

    fn boot(&mut self, event: &BootEvent<'_>) -> io::Result<()> {
        self.line(event)
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        for input in inputs {
            for node in &input.nodes {
                self.line(&NodeJson {
                    file: &input.file,
                    node,
                })?;
            }
        }
        for input in inputs {
            self.line(input)?;
        }
        self.out.flush()
    }
}
