//! `--format svg`: the error timeline as one standalone SVG image, one
//! panel per input. Layout and drawing are in [`super::chart`]; this writes
//! the document around the panels. Nothing is written before the last input
//! ends (a chart needs the whole time span); memory stays bounded by the
//! chart's pixels, not the trace (see the chart module).

use std::io::{self, Write};

use super::chart::{self, Collector, N, Panel};
use crate::analyze::{BootEvent, BusEvent, Diagnostic, EmcyEvent, HealthEvent, InputReport, Sink};

/// Space between the panels of several inputs.
pub(crate) const PANEL_GAP: f64 = 24.0;

pub struct SvgReport<W: Write> {
    out: W,
    collector: Collector,
    panels: Vec<Panel>,
}

impl<W: Write> SvgReport<W> {
    pub fn new(out: W) -> Self {
        SvgReport {
            out,
            collector: Collector::default(),
            panels: Vec::new(),
        }
    }
}

/// The `<svg>` element of one or more panels, stacked; `standalone` adds
/// the XML declaration and the style sheet (HTML has its style in the head).
pub(super) fn document(panels: &[&Panel], title: &str, standalone: bool) -> String {
    let mut height: f64 = panels.iter().map(|p| p.height).sum::<f64>()
        + PANEL_GAP * panels.len().saturating_sub(1) as f64;
    if panels.is_empty() {
        height = 40.0;
    }
    let mut s = String::with_capacity(panels.iter().map(|p| p.svg.len()).sum::<usize>() + 4096);
    if standalone {
        s.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    }
    s.push_str(&format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"ec\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n",
        w = N(chart::WIDTH),
        h = N(height),
    ));
    if !title.is_empty() {
        s.push_str(&format!("<title>{}</title>\n", chart::esc(title)));
    }
    if standalone {
        s.push_str("<style>\n");
        s.push_str(&style_sheet(panels));
        s.push_str("</style>\n");
    }
    // Opaque: viewers with a dark background would hide the black text.
    s.push_str("<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n");
    if panels.is_empty() {
        s.push_str("<text x=\"10\" y=\"24\">no input could be read</text>\n");
    }
    let mut y = 0.0;
    for (i, p) in panels.iter().enumerate() {
        if i > 0 {
            s.push_str(&format!(
                "<line x1=\"0\" y1=\"{y}\" x2=\"{w}\" y2=\"{y}\" stroke=\"#bbb\"/>\n",
                y = N(y - PANEL_GAP / 2.0),
                w = N(chart::WIDTH)
            ));
        }
        s.push_str(&format!(
            "<g class=\"panel\" transform=\"translate(0,{})\"{}>\n",
            N(y),
            p.view
        ));
        s.push_str(&p.svg);
        s.push_str("</g>\n");
        y += p.height + PANEL_GAP;
    }
    s.push_str("</svg>\n");
    s
}

/// The chart's style sheet for these panels (the colours their codes use).
pub(super) fn style_sheet(panels: &[&Panel]) -> String {
    let shades = panels
        .iter()
        .flat_map(|p| p.shades.iter().copied())
        .collect();
    chart::style_sheet(
        &shades,
        panels.iter().any(|p| p.drives),
        panels.iter().any(|p| p.bus),
    )
}

/// `EMCY timeline: a.log, b.asc`.
pub(crate) fn doc_title(inputs: &[InputReport]) -> String {
    let files: Vec<&str> = inputs.iter().map(|i| i.file.as_str()).collect();
    format!("EMCY timeline: {}", files.join(", "))
}

impl<W: Write> Sink for SvgReport<W> {
    fn begin_input(&mut self, _file: &str) -> io::Result<()> {
        self.collector.begin_input();
        Ok(())
    }

    fn emcy(&mut self, event: &EmcyEvent<'_>) -> io::Result<()> {
        self.collector.emcy(event);
        Ok(())
    }

    fn health(&mut self, event: &HealthEvent<'_>) -> io::Result<()> {
        self.collector.health(event);
        Ok(())
    }

    fn boot(&mut self, event: &BootEvent<'_>) -> io::Result<()> {
        self.collector.boot(event);
        Ok(())
    }

    fn bus(&mut self, event: &BusEvent<'_>) -> io::Result<()> {
        self.collector.bus(event);
        Ok(())
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        let panel = self.collector.end_input(input)?;
        self.panels.push(panel);
        Ok(())
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        let panels: Vec<&Panel> = self.panels.iter().collect();
        let doc = document(&panels, &doc_title(inputs), true);
        self.out.write_all(doc.as_bytes())?;
        self.out.flush()
    }
}
