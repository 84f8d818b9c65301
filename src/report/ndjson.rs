//! `--format ndjson`: one object per line, events in trace order, then node
//! objects, then input objects. The stable machine format; streamable.

use std::io::{self, Write};

use super::jsonw::JsonWriter;
use super::{BootEvent, Diagnostic, EmcyEvent, InputReport, Renderer};

pub struct Ndjson<W: Write> {
    out: W,
    /// Flush after every event (live use: `candump -L can0 | emcy-decode -`).
    flush_each: bool,
    json: JsonWriter,
    buf: Vec<u8>,
}

impl<W: Write> Ndjson<W> {
    pub fn new(out: W, flush_each: bool) -> Self {
        Ndjson {
            out,
            flush_each,
            json: JsonWriter::new(),
            buf: Vec::with_capacity(1024),
        }
    }

    /// Writes the line built in `buf`.
    fn line(&mut self) -> io::Result<()> {
        self.buf.push(b'\n');
        self.out.write_all(&self.buf)?;
        self.buf.clear();
        if self.flush_each {
            self.out.flush()?;
        }
        Ok(())
    }
}

impl<W: Write> Renderer for Ndjson<W> {
    fn emcy(&mut self, event: &EmcyEvent<'_>) -> io::Result<()> {
        self.json.emcy(&mut self.buf, event);
        self.line()
    }

    fn boot(&mut self, event: &BootEvent<'_>) -> io::Result<()> {
        self.json.boot(&mut self.buf, event);
        self.line()
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        for input in inputs {
            let mut merge = input.history.merge();
            for node in &input.nodes {
                let errors = merge.node_errors(&node.channel, node.node);
                let out = &mut self.out;
                self.json
                    .node(&mut self.buf, input, node, errors, &mut |part| {
                        out.write_all(part)?;
                        part.clear();
                        Ok(())
                    })?;
                self.line()?;
            }
            if let Some(e) = merge.take_error() {
                return Err(e);
            }
        }
        for input in inputs {
            self.json.input(&mut self.buf, input);
            self.line()?;
        }
        self.out.flush()
    }
}
