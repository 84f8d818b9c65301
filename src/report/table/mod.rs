//! The human report. Per input, the events as they are decoded
//! ([`events`]: one row each, streamed with columns fixed by the first, so
//! a trace with a million events prints without holding them), then the
//! node tables ([`end_tables`]) and the error timeline ([`timeline`]); at
//! the end of the run, the input counts ([`end_tables`]). [`fit`] is how
//! all of them give way to a terminal's width. This file holds the report's
//! state and the [`Sink`] methods, which only dispatch.

use std::collections::HashMap;
use std::io::{self, Write};

use anstyle::{AnsiColor, Style};

use super::timefmt::{TimeFormat, TimeStyle};
use crate::analyze::{BootEvent, Diagnostic, EmcyEvent, HealthEvent, InputReport, Sink};
use crate::canopen::NodeId;
use crate::canopen::emcy::Warning;
use crate::text::printable;

mod end_tables;
mod events;
mod fit;
mod timeline;

use events::Layout;
pub(crate) use events::health_description;
use fit::{MIN_WIDTH, blanks, push_cut};

const RED: Style = AnsiColor::Red.on_default().bold();
const YELLOW: Style = AnsiColor::Yellow.on_default();
const GREEN: Style = AnsiColor::Green.on_default();
const BOLD: Style = Style::new().bold();

/// The table report (`--format table`, the default), written to `out`.
pub struct TableReport<W: Write> {
    out: W,
    color: bool,
    /// Column widths fixed by the first event of an input.
    layout: Option<Layout>,
    flush_each: bool,
    /// `--view summary`: no events, no timeline; one line per node and bus.
    summary_only: bool,
    times: TimeFormat,
    /// The event line being built, kept for its capacity.
    line: String,
    /// Register column texts, padded, by register value.
    registers: Vec<Option<String>>,
    /// The terminal's width to fit (`None`: a pipe, full lines).
    width: Option<usize>,
    /// The date of the last time shown as a time of day (a narrow table).
    date: String,
    /// How often each node sent each warning about the form of its frames,
    /// by channel: said in full the first time, counted after.
    repeats: HashMap<String, HashMap<(NodeId, Warning), u64>>,
}

impl<W: Write> TableReport<W> {
    pub fn new(out: W, color: bool, flush_each: bool) -> Self {
        TableReport {
            out,
            color,
            layout: None,
            flush_each,
            summary_only: false,
            times: TimeFormat::default(),
            line: String::new(),
            registers: vec![None; 256],
            width: None,
            date: String::new(),
            repeats: HashMap::new(),
        }
    }

    /// Fits the table to `width` columns (a terminal's); `None` keeps the
    /// full lines (a pipe: scripts grep them).
    pub fn fit_width(mut self, width: Option<usize>) -> Self {
        self.width = width.map(|w| w.max(MIN_WIDTH));
        self
    }

    /// `--time`.
    pub fn time_style(mut self, style: TimeStyle) -> Self {
        self.times = TimeFormat::new(style);
        self
    }

    /// The summary view: what a CI log should show.
    pub fn summary_only(mut self) -> Self {
        self.summary_only = true;
        self
    }

    fn paint(&self, style: Style, text: &str) -> String {
        if self.color {
            format!("{}{text}{}", style.render(), style.render_reset())
        } else {
            text.to_string()
        }
    }

    /// A line of its own (legend, bus line), wrapped to the width when
    /// fitting, its continuation indented by `hang`.
    fn write_wrapped(&mut self, text: &str, hang: usize) -> io::Result<()> {
        match self.width {
            Some(width) => {
                let indent = blanks(hang);
                let options = textwrap::Options::new(width).subsequent_indent(&indent);
                for piece in textwrap::wrap(text, options) {
                    writeln!(self.out, "{piece}")?;
                }
                Ok(())
            }
            None => writeln!(self.out, "{text}"),
        }
    }

    fn end_event(&mut self) -> io::Result<()> {
        if self.flush_each {
            self.out.flush()?;
        }
        Ok(())
    }
}

impl<W: Write> Sink for TableReport<W> {
    fn begin_input(&mut self, file: &str) -> io::Result<()> {
        self.layout = None;
        self.times.origin = None;
        self.date.clear();
        self.repeats.clear();
        let mut head = String::from("== ");
        match self.width {
            Some(width) => {
                push_cut(&mut head, &printable(file), width - 3);
            }
            None => head.push_str(&printable(file)),
        }
        writeln!(self.out, "{}", self.paint(BOLD, &head))
    }

    fn emcy(&mut self, ev: &EmcyEvent<'_>) -> io::Result<()> {
        self.write_emcy(ev)
    }

    fn boot(&mut self, ev: &BootEvent<'_>) -> io::Result<()> {
        self.write_boot(ev)
    }

    fn health(&mut self, ev: &HealthEvent<'_>) -> io::Result<()> {
        self.write_health_event(ev)
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        self.write_end_of_input(input)
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        self.write_inputs(inputs)
    }
}
