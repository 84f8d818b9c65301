//! `--format ndjson`: one object per line, events in trace order, then node
//! objects, then per input its channel objects and its input object. The stable machine format; streamable.

use std::io::{self, Write};

use super::jsonw::{JsonTexts, JsonWriter, NODE_END};
use super::ordered::Ordered;
use crate::analyze::{BootEvent, BusEvent, Diagnostic, EmcyEvent, HealthEvent, InputReport, Sink};
use crate::timeline::Interval;

pub struct Ndjson<W: Write> {
    out: W,
    /// Flush after every event (live use: `candump -L can0 | emcy-decode -`).
    flush_each: bool,
    json: JsonWriter,
    buf: Vec<u8>,
    threads: usize,
}

impl<W: Write> Ndjson<W> {
    pub fn new(out: W, flush_each: bool) -> Self {
        Ndjson {
            out,
            flush_each,
            json: JsonWriter::new(),
            buf: Vec::with_capacity(CHUNK + 4096),
            threads: 1,
        }
    }

    /// Threads for the node objects' errors (1: this one only).
    pub fn threads(mut self, threads: usize) -> Self {
        self.threads = threads;
        self
    }

    /// The node objects. Errors go in batches; with more than one thread,
    /// helpers render the batches while this thread reads the history back,
    /// and the text is written in order (the same bytes either way).
    fn nodes(&mut self, inputs: &[InputReport]) -> io::Result<()> {
        let out: &mut dyn Write = &mut self.out;
        let (json, buf) = (&mut self.json, &mut self.buf);
        std::thread::scope(|scope| {
            let mut helpers = (self.threads > 1).then(|| {
                Ordered::start(
                    scope,
                    self.threads,
                    JsonWriter::new,
                    |json: &mut JsonWriter,
                     (texts, errors, first): ErrorBatch,
                     out: &mut Vec<u8>| {
                        json.errors(out, &texts, &errors, first);
                    },
                )
            });
            for input in inputs {
                let mut merge = input.history.merge();
                for node in &input.nodes {
                    json.node_head(buf, input, node);
                    let texts = JsonTexts::of(node);
                    put(&mut helpers, buf, out)?;
                    let mut first = true;
                    let mut batch = Vec::with_capacity(ERROR_BATCH);
                    let mut errors = merge.node_errors(&node.channel, node.node).peekable();
                    while errors.peek().is_some() {
                        batch.extend(errors.by_ref().take(ERROR_BATCH));
                        match &mut helpers {
                            Some(h) => {
                                let full =
                                    std::mem::replace(&mut batch, Vec::with_capacity(ERROR_BATCH));
                                h.job((texts.clone(), full, first), out)?;
                            }
                            None => {
                                json.errors(buf, &texts, &batch, first);
                                batch.clear();
                                put(&mut helpers, buf, out)?;
                            }
                        }
                        first = false;
                    }
                    buf.extend_from_slice(NODE_END);
                    buf.push(b'\n');
                    put(&mut helpers, buf, out)?;
                }
                if let Some(e) = merge.take_error() {
                    return Err(e);
                }
            }
            match helpers {
                Some(h) => h.finish(out),
                None => Ok(()),
            }
        })
    }

    /// Ends the line built in `buf`. Lines collect there and go out in
    /// chunks of [`CHUNK`] (written past the output's buffer, not copied
    /// into it once more), or one by one when live.
    fn line(&mut self) -> io::Result<()> {
        self.buf.push(b'\n');
        if self.flush_each {
            self.drain()?;
            self.out.flush()?;
        } else if self.buf.len() >= CHUNK {
            self.drain()?;
        }
        Ok(())
    }

    /// Writes the lines collected in `buf`.
    fn drain(&mut self) -> io::Result<()> {
        if !self.buf.is_empty() {
            self.out.write_all(&self.buf)?;
            self.buf.clear();
        }
        Ok(())
    }
}

/// Lines still collected are written even when the report is not finished
/// (an output error or an interrupt ends the run early).
impl<W: Write> Drop for Ndjson<W> {
    fn drop(&mut self) {
        let _ = self.drain();
        let _ = self.out.flush();
    }
}

/// Text made on this thread (`buf`, emptied): written now, or in its place
/// among the helpers' jobs.
fn put(
    helpers: &mut Option<Ordered<ErrorBatch>>,
    buf: &mut Vec<u8>,
    out: &mut dyn Write,
) -> io::Result<()> {
    let done = match helpers {
        Some(h) => h.text(buf, out),
        None => out.write_all(buf),
    };
    buf.clear();
    done
}

/// Errors of one node for a helper: its descriptions, the errors, and
/// whether they open the node's list.
type ErrorBatch = (JsonTexts, Vec<Interval>, bool);

/// Events are written in chunks of about this many bytes (the size of the
/// output's buffer, so a chunk bypasses it).
const CHUNK: usize = 64 * 1024;

/// Errors per batch: ~200 KiB of text.
const ERROR_BATCH: usize = 1024;

impl<W: Write> Sink for Ndjson<W> {
    fn emcy(&mut self, event: &EmcyEvent<'_>) -> io::Result<()> {
        self.json.emcy(&mut self.buf, event);
        self.line()
    }

    fn boot(&mut self, event: &BootEvent<'_>) -> io::Result<()> {
        self.json.boot(&mut self.buf, event);
        self.line()
    }

    fn health(&mut self, event: &HealthEvent<'_>) -> io::Result<()> {
        self.json.health(&mut self.buf, event);
        self.line()
    }

    fn bus(&mut self, event: &BusEvent<'_>) -> io::Result<()> {
        self.json.bus(&mut self.buf, event);
        self.line()
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        self.drain()?;
        self.nodes(inputs)?;
        // An input's channels before it: its object stays the last line.
        for input in inputs {
            for c in &input.channels {
                self.json.channel_traffic(&mut self.buf, input, c);
                self.line()?;
            }
            self.json.input(&mut self.buf, input);
            self.line()?;
        }
        self.drain()?;
        self.out.flush()
    }
}
