//! `--format json`: one document. Events are streamed as they are decoded,
//! so memory does not grow with the number of events.

use std::io::{self, Write};

use serde::Serialize;

use super::{BootEvent, Diagnostic, EmcyEvent, InputReport, NodeJson, Renderer, to_io};

/// `{"events":[...],"nodes":[...],"inputs":[...],"diagnostics":[...]}`,
/// pretty-printed, events streamed as they come.
pub struct JsonDocument<W: Write> {
    out: W,
    events: usize,
}

impl<W: Write> JsonDocument<W> {
    pub fn new(out: W) -> Self {
        JsonDocument { out, events: 0 }
    }

    /// Writes one array element pretty-printed and indented one level under
    /// its key. JSON strings cannot hold a raw newline, so indenting after
    /// every newline byte is safe.
    fn element<T: Serialize>(&mut self, first: bool, value: &T) -> io::Result<()> {
        let text = serde_json::to_vec_pretty(value).map_err(to_io)?;
        self.out
            .write_all(if first { b"\n    " } else { b",\n    " })?;
        for chunk in text.split_inclusive(|b| *b == b'\n') {
            self.out.write_all(chunk)?;
            if chunk.ends_with(b"\n") {
                self.out.write_all(b"    ")?;
            }
        }
        Ok(())
    }

    fn event<T: Serialize>(&mut self, value: &T) -> io::Result<()> {
        if self.events == 0 {
            self.out.write_all(b"{\n  \"events\": [")?;
        }
        self.element(self.events == 0, value)?;
        self.events += 1;
        Ok(())
    }

    fn close_array(&mut self, count: usize) -> io::Result<()> {
        self.out.write_all(if count == 0 { b"]" } else { b"\n  ]" })
    }
}

impl<W: Write> Renderer for JsonDocument<W> {
    fn emcy(&mut self, event: &EmcyEvent<'_>) -> io::Result<()> {
        self.event(event)
    }

    fn boot(&mut self, event: &BootEvent<'_>) -> io::Result<()> {
        self.event(event)
    }

    fn finish(&mut self, inputs: &[InputReport], diagnostics: &[Diagnostic]) -> io::Result<()> {
        if self.events == 0 {
            self.out.write_all(b"{\n  \"events\": [")?;
        }
        self.close_array(self.events)?;

        self.out.write_all(b",\n  \"nodes\": [")?;
        let mut n = 0;
        for input in inputs {
            for node in &input.nodes {
                self.element(
                    n == 0,
                    &NodeJson {
                        file: &input.file,
                        node,
                    },
                )?;
                n += 1;
            }
        }
        self.close_array(n)?;

        self.out.write_all(b",\n  \"inputs\": [")?;
        for (i, input) in inputs.iter().enumerate() {
            self.element(i == 0, input)?;
        }
        self.close_array(inputs.len())?;

        self.out.write_all(b",\n  \"diagnostics\": [")?;
        for (i, d) in diagnostics.iter().enumerate() {
            self.element(i == 0, d)?;
        }
        self.close_array(diagnostics.len())?;
        self.out.write_all(b"\n}\n")?;
        self.out.flush()
    }
}
