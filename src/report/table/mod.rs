//! The human report. Per input, the events as they are decoded
//! ([`events`]: one row each, streamed with columns fixed by the first, so
//! a trace with a million events prints without holding them), then the
//! node tables ([`end_tables`]) and the error timeline ([`timeline`]); at
//! the end of the run, the input counts ([`end_tables`]). [`fit`] is how
//! all of them give way to a terminal's width; [`page`] is where they are
//! written and how (colour, width, times).
//!
//! Each file imports only the ones below it in this list: `mod.rs` (the
//! [`TableReport`], whose [`Sink`] methods only dispatch), `end_tables`,
//! `traffic`, `inventory`, `timeline`, `events`, `page`, `fit`.

use std::io::{self, Write};

use super::timefmt::{TimeFormat, TimeStyle};
use crate::analyze::{
    BootEvent, Bus, BusEvent, Diagnostic, EmcyEvent, HealthEvent, InputReport, Sink,
};
use crate::canopen::sdo::transfer::Outcome;
use crate::text::printable;

mod end_tables;
mod events;
mod fit;
mod inventory;
mod page;
mod timeline;
mod traffic;

use events::EventLines;
pub(crate) use events::{bus_description, health_description};
use fit::{MIN_WIDTH, push_cut};
use page::{BOLD, Page};

/// The table report (`--format table`, the default), written to `out`.
pub struct TableReport<W: Write> {
    page: Page<W>,
    events: EventLines,
    flush_each: bool,
    /// `--view summary`: no events, no timeline; one line per node and bus.
    summary_only: bool,
    /// The input's incidents so far, for the section that opens its end.
    incidents: end_tables::Incidents,
    /// `--show sdo`: a row for every SDO transfer, not only unanswered ones.
    show_sdo: bool,
}

impl<W: Write> TableReport<W> {
    pub fn new(out: W, color: bool, flush_each: bool) -> Self {
        TableReport {
            page: Page {
                out,
                color,
                width: None,
                times: TimeFormat::default(),
            },
            events: EventLines::new(),
            flush_each,
            summary_only: false,
            incidents: end_tables::Incidents::default(),
            show_sdo: false,
        }
    }

    /// Fits the table to `width` columns (a terminal's); `None` keeps the
    /// full lines (a pipe: scripts grep them).
    pub fn fit_width(mut self, width: Option<usize>) -> Self {
        self.page.width = width.map(|w| w.max(MIN_WIDTH));
        self
    }

    /// `--time`.
    pub fn time_style(mut self, style: TimeStyle) -> Self {
        self.page.times = TimeFormat::new(style);
        self
    }

    /// The summary view: what a CI log should show.
    pub fn summary_only(mut self) -> Self {
        self.summary_only = true;
        self
    }

    /// A row for every SDO transfer (`--show sdo`).
    pub fn show_sdo(mut self) -> Self {
        self.show_sdo = true;
        self
    }

    fn end_event(&mut self) -> io::Result<()> {
        if self.flush_each {
            self.page.out.flush()?;
        }
        Ok(())
    }
}

impl<W: Write> Sink for TableReport<W> {
    fn begin_input(&mut self, file: &str) -> io::Result<()> {
        self.events.begin_input();
        self.incidents = end_tables::Incidents::default();
        self.page.times.origin = None;
        let mut head = String::from("== ");
        match self.page.width {
            Some(width) => {
                push_cut(&mut head, &printable(file), width - 3);
            }
            None => head.push_str(&printable(file)),
        }
        writeln!(self.page.out, "{}", self.page.paint(BOLD, &head))
    }

    fn emcy(&mut self, ev: &EmcyEvent<'_>) -> io::Result<()> {
        if self.summary_only {
            return Ok(());
        }
        self.events.write_emcy(&mut self.page, ev)?;
        self.end_event()
    }

    fn boot(&mut self, ev: &BootEvent<'_>) -> io::Result<()> {
        if self.summary_only {
            return Ok(());
        }
        self.events.write_boot(&mut self.page, ev)?;
        self.end_event()
    }

    fn health(&mut self, ev: &HealthEvent<'_>) -> io::Result<()> {
        if self.summary_only {
            return Ok(());
        }
        self.events.write_health_event(&mut self.page, ev)?;
        self.end_event()
    }

    fn bus(&mut self, ev: &BusEvent<'_>) -> io::Result<()> {
        if let Bus::Incident(i) = ev.bus {
            self.incidents.push(ev.channel, i);
        }
        if self.summary_only {
            return Ok(());
        }
        // A transfer that went through is detail; one the node never
        // answered is a warning (an abort has its own row).
        if let Bus::Sdo(t) = ev.bus
            && !self.show_sdo
            && !matches!(t.outcome, Outcome::Unanswered | Outcome::Incomplete)
        {
            return Ok(());
        }
        self.events.write_bus_event(&mut self.page, ev)?;
        self.end_event()
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        if self.summary_only {
            end_tables::write_incidents(&mut self.page, &self.incidents)?;
            return end_tables::write_summary(&mut self.page, input);
        }
        self.events.write_end(&mut self.page)?;
        end_tables::write_end_of_input(&mut self.page, input, &self.incidents)
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        end_tables::write_inputs(&mut self.page, inputs)
    }
}
