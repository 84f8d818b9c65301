//! `--format json`: one document. Events are streamed as they are decoded,
//! so memory does not grow with the number of events.

use std::io::{self, Write};

use super::jsonw::{JsonWriter, Pretty, pretty};
use crate::analyze::{BootEvent, BusEvent, Diagnostic, EmcyEvent, HealthEvent, InputReport, Sink};

/// `{"events":[...],"nodes":[...],"inputs":[...],"diagnostics":[...]}`,
/// pretty-printed, events streamed as they come.
pub struct JsonDocument<W: Write> {
    out: W,
    events: usize,
    json: JsonWriter,
    compact: Vec<u8>,
    text: Vec<u8>,
}

impl<W: Write> JsonDocument<W> {
    pub fn new(out: W) -> Self {
        JsonDocument {
            out,
            events: 0,
            json: JsonWriter::pretty(2),
            compact: Vec::new(),
            text: Vec::new(),
        }
    }

    /// Writes the element built in `compact` as an array element two levels
    /// deep (inside the document and its array).
    fn element(&mut self, first: bool) -> io::Result<()> {
        self.text.clear();
        self.text
            .extend_from_slice(if first { b"\n    " } else { b",\n    " });
        pretty(&self.compact, 2, &mut self.text);
        self.compact.clear();
        self.out.write_all(&self.text)
    }

    fn event(&mut self) -> io::Result<()> {
        if self.events == 0 {
            self.out.write_all(b"{\n  \"events\": [")?;
        }
        self.element(self.events == 0)?;
        self.events += 1;
        Ok(())
    }

    fn close_array(&mut self, count: usize) -> io::Result<()> {
        self.out.write_all(if count == 0 { b"]" } else { b"\n  ]" })
    }
}

impl<W: Write> Sink for JsonDocument<W> {
    fn emcy(&mut self, event: &EmcyEvent<'_>) -> io::Result<()> {
        // Written indented as it goes, not re-indented (the hot path).
        if self.events == 0 {
            self.out.write_all(b"{\n  \"events\": [")?;
        }
        self.text.clear();
        self.text.extend_from_slice(if self.events == 0 {
            b"\n    "
        } else {
            b",\n    "
        });
        self.json.emcy(&mut self.text, event);
        self.events += 1;
        self.out.write_all(&self.text)
    }

    fn boot(&mut self, event: &BootEvent<'_>) -> io::Result<()> {
        self.json.boot(&mut self.compact, event);
        self.event()
    }

    fn health(&mut self, event: &HealthEvent<'_>) -> io::Result<()> {
        self.json.health(&mut self.compact, event);
        self.event()
    }

    fn bus(&mut self, event: &BusEvent<'_>) -> io::Result<()> {
        self.json.bus(&mut self.compact, event);
        self.event()
    }

    fn finish(&mut self, inputs: &[InputReport], diagnostics: &[Diagnostic]) -> io::Result<()> {
        if self.events == 0 {
            self.out.write_all(b"{\n  \"events\": [")?;
        }
        self.close_array(self.events)?;

        self.out.write_all(b",\n  \"nodes\": [")?;
        let mut n = 0;
        for input in inputs {
            let mut merge = input.history.merge();
            for node in &input.nodes {
                let errors = merge.node_errors(&node.channel, node.node);
                // Streamed: a node's errors can be millions.
                self.out
                    .write_all(if n == 0 { b"\n    " } else { b",\n    " })?;
                let mut pretty = Pretty::new(2);
                let (out, text) = (&mut self.out, &mut self.text);
                self.json
                    .node(&mut self.compact, input, node, errors, &mut |part| {
                        text.clear();
                        pretty.feed(part, text);
                        part.clear();
                        out.write_all(text)
                    })?;
                self.text.clear();
                pretty.feed(&self.compact, &mut self.text);
                self.compact.clear();
                self.out.write_all(&self.text)?;
                n += 1;
            }
            if let Some(e) = merge.take_error() {
                return Err(e);
            }
        }
        self.close_array(n)?;

        self.out.write_all(b",\n  \"inputs\": [")?;
        for (i, input) in inputs.iter().enumerate() {
            self.json.input(&mut self.compact, input);
            self.element(i == 0)?;
        }
        self.close_array(inputs.len())?;

        self.out.write_all(b",\n  \"channels\": [")?;
        let mut n = 0;
        for input in inputs {
            for c in &input.channels {
                self.json.channel_traffic(&mut self.compact, input, c);
                self.element(n == 0)?;
                n += 1;
            }
        }
        self.close_array(n)?;

        self.out.write_all(b",\n  \"diagnostics\": [")?;
        for (i, d) in diagnostics.iter().enumerate() {
            self.json.diagnostic(&mut self.compact, d);
            self.element(i == 0)?;
        }
        self.close_array(diagnostics.len())?;
        self.out.write_all(b"\n}\n")?;
        self.out.flush()
    }
}
