//! The human report: per input, the EMCY events as they are decoded (streamed
//! with fixed columns, so a trace with a million events prints without holding
//! them), then the node states and error timeline; at the end the input counts.

use std::borrow::Cow;
use std::io::{self, Write};

use anstyle::{AnsiColor, Style};
use comfy_table::{CellAlignment, Table, presets};

use super::timefmt::{TimeFormat, TimeStyle};
use crate::analyze::{
    AxisReport, BootEvent, Diagnostic, EmcyEvent, Health, HealthEvent, HistoryReport, InputReport,
    NodeReport, Sink,
};
use crate::canopen::NodeId;
use crate::canopen::profile::{Decoded, FieldValue};
use crate::text::printable;
use crate::timeline::Interval;
use crate::timeline::axis::Via as AxisVia;
use crate::trace::Timestamp;
use unicode_width::UnicodeWidthStr;

const RED: Style = AnsiColor::Red.on_default().bold();
const YELLOW: Style = AnsiColor::Yellow.on_default();
const GREEN: Style = AnsiColor::Green.on_default();
const BOLD: Style = Style::new().bold();

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
}

#[derive(Clone, Copy)]
struct Layout {
    time: usize,
    channel: usize,
}

const REGISTER_WIDTH: usize = 16;
const MANUFACTURER_WIDTH: usize = 14;

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
        }
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

    /// One line per node: state, errors seen with counts, time in error,
    /// longest error, first and last EMCY.
    fn write_nodes(&mut self, input: &InputReport) -> io::Result<()> {
        // Two passes over the nodes, widths then rows, as for the timeline:
        // a trace can name a million nodes, and a table holding them all
        // took about 2.5 KB per node on top of the reports.
        self.times.set_origin(input.first_time);
        let times = self.times.clone();
        let mut cells: [String; 11] = Default::default();
        let mut widths = NODES_HEADER.map(str::len);
        for n in &input.nodes {
            for (w, c) in widths
                .iter_mut()
                .zip(node_cells(&mut cells, &times, input, n))
            {
                *w = (*w).max(c);
            }
        }
        writeln!(self.out, "{}", self.paint(BOLD, "Nodes"))?;
        write_row(&mut self.out, &NODES_HEADER, &widths, &NODES_RIGHT)?;
        let mut line = String::new();
        for n in &input.nodes {
            let cell_widths = node_cells(&mut cells, &times, input, n);
            push_row(&mut line, &cells, &cell_widths, &widths, &NODES_RIGHT);
            self.out.write_all(line.as_bytes())?;
        }
        Ok(())
    }

    /// The nodes' NMT state, heartbeat and error history, for the nodes the
    /// trace told any of (none: no section). Two passes, widths then rows,
    /// as for the nodes: no table of a million rows is held.
    fn write_health(&mut self, input: &InputReport) -> io::Result<()> {
        let told = |n: &&NodeReport| {
            n.nmt_state.is_some() || n.heartbeat.is_some() || n.error_history.is_some()
        };
        if !input.nodes.iter().any(|n| told(&n)) {
            return Ok(());
        }
        let times = self.times.clone();
        let mut cells: [String; 6] = Default::default();
        let mut widths = HEALTH_HEADER.map(str::len);
        for n in input.nodes.iter().filter(told) {
            for (w, c) in widths.iter_mut().zip(health_cells(&mut cells, &times, n)) {
                *w = (*w).max(c);
            }
        }
        writeln!(self.out)?;
        writeln!(self.out, "{}", self.paint(BOLD, "Node health"))?;
        write_row(&mut self.out, &HEALTH_HEADER, &widths, &HEALTH_RIGHT)?;
        let mut line = String::new();
        for n in input.nodes.iter().filter(told) {
            let cell_widths = health_cells(&mut cells, &times, n);
            push_row(&mut line, &cells, &cell_widths, &widths, &HEALTH_RIGHT);
            self.out.write_all(line.as_bytes())?;
        }
        Ok(())
    }

    /// The CiA 402 drives' axes (none: no section): state at the end,
    /// faults, where the mapping came from, and the summary's sentence.
    /// Drives are few: one comfy table.
    fn write_axes(&mut self, input: &InputReport) -> io::Result<()> {
        let axes: Vec<(&NodeReport, &AxisReport)> = input
            .nodes
            .iter()
            .filter_map(|n| n.axis.as_deref().map(|a| (n, a)))
            .collect();
        if axes.is_empty() {
            return Ok(());
        }
        let mut t = new_table(&[
            "CHANNEL",
            "NODE",
            "AXIS AT END",
            "FAULTS",
            "RESETS",
            "MAPPING",
            "SUMMARY",
        ]);
        for (n, a) in axes {
            let mapping: Vec<String> = a
                .mappings
                .iter()
                .map(|m| format!("0x{:03X} {}", m.cob_id.id, m.source.slug()))
                .collect();
            t.add_row(vec![
                printable(&n.channel).into_owned(),
                n.node.to_string(),
                a.state.map_or("-", |s| s.slug()).to_string(),
                a.fault_count.to_string(),
                a.fault_resets.to_string(),
                if mapping.is_empty() {
                    "-".to_string()
                } else {
                    mapping.join(", ")
                },
                a.fault_summary()
                    .unwrap_or_else(|| "never faulted".to_string()),
            ]);
        }
        right_align(&mut t, &[1, 3, 4]);
        writeln!(self.out)?;
        writeln!(self.out, "{}", self.paint(BOLD, "Drive axes (CiA 402)"))?;
        write_table(&mut self.out, &t)
    }

    /// The bus-level line: frames, EMCY rate, nodes with errors.
    fn write_bus_line(&mut self, input: &InputReport) -> io::Result<()> {
        let c = &input.counts;
        let span = match (input.first_time, input.last_time) {
            (Some(first), Some(last)) => format!(" over {} s", last.since(first)),
            _ => String::new(),
        };
        let rate = input
            .emcy_rate()
            .map_or_else(String::new, |r| format!(" ({r:.2}/s)"));
        // Said only when it happened: traces without outages read as before.
        let lost = input
            .nodes
            .iter()
            .filter(|n| n.heartbeat.as_ref().is_some_and(|h| h.lost > 0))
            .count();
        let lost = match lost {
            0 => String::new(),
            1 => ", 1 node lost its heartbeat".to_string(),
            n => format!(", {n} nodes lost their heartbeat"),
        };
        // An EtherCAT capture's frames are EtherCAT's, its EMCYs came by mailbox.
        let frames = match c.ethercat_frames {
            0 => format!("{} frames", c.frames),
            n => format!(
                "{n} EtherCAT frames ({} mailbox messages, {} {}, {} empty polls){}",
                c.mailbox_messages,
                c.mailbox_retries,
                if c.mailbox_retries == 1 {
                    "retry"
                } else {
                    "retries"
                },
                c.mailbox_empty_polls,
                match c.frames {
                    0 => String::new(),
                    n => format!(", {n} CAN frames"),
                }
            ),
        };
        // Lost frames may have been EMCYs: said where the counts are read.
        let dropped = match c.dropped {
            0 => String::new(),
            1 => ", 1 frame dropped (DROPCOUNT): EMCYs may be missing".to_string(),
            n => format!(", {n} frames dropped (DROPCOUNT): EMCYs may be missing"),
        };
        writeln!(
            self.out,
            "bus: {frames}, {} EMCY{rate}{span}, {} of {} nodes with errors{lost}, {} malformed{dropped}",
            c.emcy,
            input.nodes_with_errors(),
            input.nodes.len(),
            c.malformed,
        )
    }

    fn paint(&self, style: Style, text: &str) -> String {
        if self.color {
            format!("{}{text}{}", style.render(), style.render_reset())
        } else {
            text.to_string()
        }
    }

    fn layout_for(&mut self, time: Option<Timestamp>, channel: &str) -> io::Result<Layout> {
        if let Some(l) = self.layout {
            return Ok(l);
        }
        let l = Layout {
            time: time.map_or(1, |t| self.times.show(t).len()).max(4),
            channel: printable(channel).len().max(7),
        };
        self.layout = Some(l);
        let header = format!(
            "{:<tw$}  {:<cw$}  NODE  CODE    TR  {:<rw$}  {:<mw$}  DESCRIPTION",
            "TIME",
            "CHANNEL",
            "REGISTER",
            "MANUFACTURER",
            tw = l.time,
            cw = l.channel,
            rw = REGISTER_WIDTH,
            mw = MANUFACTURER_WIDTH,
        );
        writeln!(self.out, "{}", self.paint(BOLD, &header))?;
        Ok(l)
    }

    fn prefix(&self, l: Layout, time: Option<Timestamp>, channel: &str, node: NodeId) -> String {
        let mut s = String::with_capacity(64);
        self.push_prefix(&mut s, l, time, channel, node);
        s
    }

    /// `TIME  CHANNEL  NODE  ` padded to the layout, appended to `line`.
    fn push_prefix(
        &self,
        line: &mut String,
        l: Layout,
        time: Option<Timestamp>,
        channel: &str,
        node: NodeId,
    ) {
        let start = line.len();
        self.times.push_opt(line, time);
        pad_to(line, start + l.time);
        line.push_str("  ");
        let channel = printable(channel);
        line.push_str(&channel);
        for _ in channel.chars().count()..l.channel {
            line.push(' ');
        }
        line.push_str("  ");
        let mut digits = itoa::Buffer::new();
        let node = digits.format(node);
        for _ in node.len()..4 {
            line.push(' ');
        }
        line.push_str(node);
        line.push_str("  ");
    }

    fn description_indent(l: Layout) -> usize {
        l.time + 2 + l.channel + 2 + 6 + 8 + 4 + REGISTER_WIDTH + 2 + MANUFACTURER_WIDTH + 2
    }

    /// The error timeline, in two passes over the history (column widths,
    /// then rows): a trace with millions of errors needs no stored rows.
    fn write_timeline(&mut self, input: &InputReport) -> io::Result<()> {
        let mut widths = TIMELINE_HEADER.map(str::len);
        let mut rows = 0u64;
        let times = self.times.clone();
        for_each_timeline_row(input, &times, |_, cell_widths| {
            rows += 1;
            for (w, c) in widths.iter_mut().zip(cell_widths) {
                *w = (*w).max(*c);
            }
            Ok(())
        })?;
        if rows == 0 {
            return Ok(());
        }
        writeln!(self.out)?;
        writeln!(self.out, "{}", self.paint(BOLD, "Error timeline"))?;
        write_row(&mut self.out, &TIMELINE_HEADER, &widths, &TIMELINE_RIGHT)?;
        let out = &mut self.out;
        let mut line = String::new();
        for_each_timeline_row(input, &times, |cells, cell_widths| {
            push_row(&mut line, cells, cell_widths, &widths, &TIMELINE_RIGHT);
            out.write_all(line.as_bytes())
        })
    }

    fn end_event(&mut self) -> io::Result<()> {
        if self.flush_each {
            self.out.flush()?;
        }
        Ok(())
    }
}

const HEALTH_HEADER: [&str; 6] = [
    "CHANNEL",
    "NODE",
    "NMT AT END",
    "HEARTBEAT",
    "OUTAGES",
    "ERROR HISTORY (1003h)",
];
const HEALTH_RIGHT: [bool; 6] = [false, true, false, false, false, false];

/// Fills the cells of one node health row; returns their display widths.
fn health_cells(cells: &mut [String; 6], times: &TimeFormat, n: &NodeReport) -> [usize; 6] {
    let [channel, node, nmt, heartbeat, outages, history] = cells;
    *channel = printable(&n.channel).into_owned();
    *node = n.node.to_string();
    *nmt = n.nmt_state.map_or("-", |s| s.slug()).to_string();
    *heartbeat = heartbeat_text(n);
    *outages = outages_text(times, n);
    *history = n
        .error_history
        .as_ref()
        .map_or_else(|| "-".to_string(), history_cell);
    let mut widths = [0; 6];
    for (w, c) in widths.iter_mut().zip(cells.iter()) {
        *w = display_width(c);
    }
    widths
}

/// `error history complete, 2 entries` (the event line).
fn history_head(h: &HistoryReport) -> String {
    let n = h.entries.len();
    format!(
        "error history {}, {n} entr{}",
        if h.complete { "complete" } else { "partial" },
        if n == 1 { "y" } else { "ies" }
    )
}

/// A node's last read-out in one cell: `0x4310*, 0x3120* (complete; * before the trace)`.
fn history_cell(h: &HistoryReport) -> String {
    let mut s = String::new();
    if h.entries.is_empty() {
        s.push_str("empty");
    }
    for (i, e) in h.entries.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        push_code(&mut s, e.code);
        if e.before_trace {
            s.push('*');
        }
    }
    s.push_str(if h.complete {
        " (complete"
    } else {
        " (partial"
    });
    if h.entries.iter().any(|e| e.before_trace) {
        s.push_str("; * before the trace");
    }
    s.push(')');
    s
}

/// `period 0.100 s, timeout 0.300 s (learnt), lost 1x, silent at end`.
fn heartbeat_text(n: &NodeReport) -> String {
    let Some(h) = &n.heartbeat else {
        return "-".to_string();
    };
    let mut parts = Vec::new();
    if let Some(p) = h.period {
        parts.push(format!("period {p} s"));
    }
    match h.timeout {
        Some((t, source)) => parts.push(format!("timeout {t} s ({})", source.slug())),
        None => parts.push("no timeout known".to_string()),
    }
    parts.push(if h.lost == 0 {
        "never lost".to_string()
    } else {
        format!("lost {}x", h.lost)
    });
    if h.silent_at_end {
        parts.push("silent at end".to_string());
    }
    parts.join(", ")
}

/// The first outages: `start-end (duration s)`, then how many more.
fn outages_text(times: &TimeFormat, n: &NodeReport) -> String {
    const SHOWN: usize = 3;
    let Some(h) = &n.heartbeat else {
        return "-".to_string();
    };
    if h.outages.is_empty() {
        return "-".to_string();
    }
    let mut items: Vec<String> = h
        .outages
        .iter()
        .take(SHOWN)
        .map(|o| match (o.end, o.duration()) {
            (Some(end), Some(d)) => {
                format!("{}-{} ({d} s)", times.show(o.start), times.show(end))
            }
            _ => format!("{}-end", times.show(o.start)),
        })
        .collect();
    let more = h.lost.saturating_sub(SHOWN as u64);
    if more > 0 {
        items.push(format!("+{more} more"));
    }
    items.join(", ")
}

/// The manufacturer bytes as the profile reads them: `key: value; ...`.
fn decoded_text(d: &Decoded) -> String {
    let fields: Vec<String> = d
        .fields
        .iter()
        .map(|(k, v)| match v {
            FieldValue::Int(n) => format!("{k}: {n}"),
            FieldValue::Text(t) => format!("{k}: {}", printable(t)),
        })
        .collect();
    format!("manufacturer: {}", fields.join("; "))
}

/// A node's code descriptions with their display widths, measured once per
/// node (its timeline can have millions of rows; descriptions are rarely
/// ASCII, so measuring is not free).
struct NodeTexts<'n>(Vec<(u16, Cow<'n, str>, usize)>);

impl<'n> NodeTexts<'n> {
    fn of(node: &'n NodeReport) -> Self {
        NodeTexts(
            node.descriptions
                .iter()
                .map(|(code, text)| {
                    let text = printable(text);
                    let width = display_width(&text);
                    (code, text, width)
                })
                .collect(),
        )
    }

    /// `code`'s description and width; empty for a code the node never
    /// raised (its errors are all raised by it, so never).
    fn get(&self, code: u16) -> (&str, usize) {
        match self.0.binary_search_by_key(&code, |(c, _, _)| *c) {
            Ok(i) => self.0.get(i).map_or(("", 0), |(_, t, w)| (&**t, *w)),
            Err(_) => ("", 0),
        }
    }
}

/// Columns a text takes on a terminal; ASCII (nearly every cell) needs no
/// Unicode tables.
fn display_width(s: &str) -> usize {
    if s.is_ascii() {
        s.len()
    } else {
        UnicodeWidthStr::width(s)
    }
}

fn code_text(code: u16) -> String {
    let mut s = String::with_capacity(6);
    push_code(&mut s, code);
    s
}

/// `0x4310`
fn push_code(s: &mut String, code: u16) {
    s.push_str("0x");
    for shift in [12, 8, 4, 0] {
        s.push(hex_digit((code >> shift) as u8));
    }
}

fn hex_digit(nibble: u8) -> char {
    char::from(b"0123456789ABCDEF"[usize::from(nibble & 0xF)])
}

fn push_hex_byte(s: &mut String, b: u8) {
    s.push(hex_digit(b >> 4));
    s.push(hex_digit(b));
}

/// Pads `s` with blanks up to `width` bytes (ASCII columns).
fn pad_to(s: &mut String, width: usize) {
    while s.len() < width {
        s.push(' ');
    }
}

pub(crate) fn codes_list(codes: &[u16]) -> String {
    let mut s = String::with_capacity(codes.len() * 8);
    push_codes(&mut s, codes);
    s
}

/// `0x4310, 0x2310`
fn push_codes(s: &mut String, codes: &[u16]) {
    for (i, &code) in codes.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        push_code(s, code);
    }
}

impl<W: Write> Sink for TableReport<W> {
    fn begin_input(&mut self, file: &str) -> io::Result<()> {
        self.layout = None;
        self.times.origin = None;
        writeln!(
            self.out,
            "{}",
            self.paint(BOLD, &format!("== {}", printable(file)))
        )
    }

    fn emcy(&mut self, ev: &EmcyEvent<'_>) -> io::Result<()> {
        if self.summary_only {
            return Ok(());
        }
        self.times.set_origin(ev.time);
        let l = self.layout_for(ev.time, ev.channel)?;
        let style = match ev.transition {
            Some(1 | 3) => RED,
            Some(2) => YELLOW,
            Some(4) => GREEN,
            _ => Style::new(),
        };
        // One reused buffer and cached texts: the table is the default
        // output, and traces with many EMCY print a line per frame.
        let mut line = std::mem::take(&mut self.line);
        line.clear();
        self.push_prefix(&mut line, l, ev.time, ev.channel, ev.node);
        if self.color {
            line.push_str(&self.paint(style, &code_text(ev.emcy.code)));
        } else {
            push_code(&mut line, ev.emcy.code);
        }
        line.push_str("  ");
        match ev.transition {
            Some(t) => {
                line.push(' ');
                line.push(char::from(b'0' + t % 10));
            }
            None => line.push_str(" -"),
        }
        line.push_str("  ");
        let reg = ev.emcy.register.0;
        let register = self.registers[usize::from(reg)].get_or_insert_with(|| {
            format!(
                "{:<rw$}",
                format!("{reg:02X} {}", ev.emcy.register.short()),
                rw = REGISTER_WIDTH
            )
        });
        line.push_str(register);
        line.push_str("  ");
        let start = line.len();
        for (i, b) in ev.emcy.manufacturer().iter().enumerate() {
            if i > 0 {
                line.push(' ');
            }
            push_hex_byte(&mut line, *b);
        }
        pad_to(&mut line, start + MANUFACTURER_WIDTH);
        line.push_str("  ");
        line.push_str(&printable(ev.description));
        if !ev.cleared.is_empty() {
            line.push_str(" (cleared ");
            for (i, &c) in ev.cleared.iter().enumerate() {
                if i > 0 {
                    line.push_str(", ");
                }
                push_code(&mut line, c);
            }
            line.push(')');
        }
        let trimmed = line.trim_end().len();
        line.truncate(trimmed);
        line.push('\n');
        self.out.write_all(line.as_bytes())?;
        self.line = line;
        let indent = Self::description_indent(l);
        if let Some(decoded) = ev.decoded {
            writeln!(self.out, "{:indent$}{}", "", decoded_text(decoded))?;
        }
        for w in ev.warnings {
            let text = self.paint(YELLOW, &format!("warning: {w}"));
            writeln!(self.out, "{:indent$}{text}", "")?;
        }
        self.end_event()
    }

    fn boot(&mut self, ev: &BootEvent<'_>) -> io::Result<()> {
        if self.summary_only {
            return Ok(());
        }
        self.times.set_origin(ev.time);
        let l = self.layout_for(ev.time, ev.channel)?;
        let what = if ev.cleared.is_empty() {
            "NMT boot-up".to_string()
        } else {
            format!("NMT boot-up (cleared {})", codes_list(ev.cleared))
        };
        let indent = Self::description_indent(l) - (l.time + 2 + l.channel + 2 + 6);
        writeln!(
            self.out,
            "{}{}{:pad$}{what}",
            self.prefix(l, ev.time, ev.channel, ev.node),
            self.paint(GREEN, "boot  "),
            "",
            pad = indent - 6,
        )?;
        self.end_event()
    }

    fn health(&mut self, ev: &HealthEvent<'_>) -> io::Result<()> {
        if self.summary_only {
            return Ok(());
        }
        self.times.set_origin(ev.time);
        let l = self.layout_for(ev.time, ev.channel)?;
        let what = health_description(ev.health, &self.times);
        let (tag, style) = match ev.health {
            Health::Nmt { .. } => ("nmt", None),
            Health::HeartbeatLost { .. } => ("lost", Some(RED)),
            Health::HeartbeatBack { .. } => ("back", Some(GREEN)),
            Health::SdoAbort { .. } => ("abort", Some(YELLOW)),
            Health::ErrorHistory(_) | Health::ErrorHistoryCleared => ("1003h", None),
            Health::AxisState { state, .. } if state.is_fault() => ("axis", Some(RED)),
            Health::AxisState { .. } => ("axis", None),
            Health::FaultReset { .. } => ("reset", Some(GREEN)),
        };
        let indent = Self::description_indent(l) - (l.time + 2 + l.channel + 2 + 6);
        let tag = format!("{tag:<6}");
        let tag = match style {
            Some(style) => self.paint(style, &tag),
            None => tag,
        };
        writeln!(
            self.out,
            "{}{tag}{:pad$}{}",
            self.prefix(l, ev.time, ev.channel, ev.node),
            "",
            printable(&what),
            pad = indent - 6,
        )?;
        if let Health::ErrorHistory(h) = ev.health {
            let indent = Self::description_indent(l) + 2;
            for e in &h.entries {
                writeln!(
                    self.out,
                    "{:indent$}0x{:04X} (info 0x{:04X}) {}{}",
                    "",
                    e.code,
                    e.info,
                    printable(&e.description),
                    if e.before_trace {
                        " [before the trace]"
                    } else {
                        ""
                    }
                )?;
            }
        }
        self.end_event()
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        if self.summary_only {
            if !input.nodes.is_empty() {
                self.write_nodes(input)?;
                self.write_health(input)?;
                self.write_axes(input)?;
            }
            self.write_bus_line(input)?;
            return writeln!(self.out);
        }
        if self.layout.is_none() {
            writeln!(self.out, "no EMCY frames")?;
        } else {
            writeln!(
                self.out,
                "TR = transition: 1 first error, 2 one error reset, 3 further error, 4 all reset"
            )?;
        }
        if input.nodes.is_empty() {
            self.write_bus_line(input)?;
            return writeln!(self.out);
        }
        writeln!(self.out)?;
        self.write_nodes(input)?;
        self.write_health(input)?;
        self.write_axes(input)?;

        self.write_timeline(input)?;
        writeln!(self.out)?;
        self.write_bus_line(input)?;
        writeln!(self.out)
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        let mut t = new_table(&[
            "FILE",
            "FORMAT",
            "LINES",
            "FRAMES",
            "EMCY",
            "BOOT",
            "SKIPPED",
            "MALFORMED",
        ]);
        for i in inputs {
            let c = &i.counts;
            t.add_row(vec![
                printable(&i.file).into_owned(),
                i.format.map_or("-", |f| f.name()).to_string(),
                c.lines.to_string(),
                c.frames.to_string(),
                c.emcy.to_string(),
                c.boot.to_string(),
                c.skipped.to_string(),
                c.malformed.to_string(),
            ]);
        }
        right_align(&mut t, &[2, 3, 4, 5, 6, 7]);
        writeln!(self.out, "{}", self.paint(BOLD, "Inputs"))?;
        write_table(&mut self.out, &t)?;
        self.out.flush()
    }
}

/// A health event's text, as the table's description column and the CSV
/// `description` column give it.
pub(crate) fn health_description(health: &Health, times: &TimeFormat) -> String {
    match health {
        Health::Nmt { state, via } => format!("NMT {} (via {})", state.slug(), via.slug()),
        Health::HeartbeatLost {
            last_seen,
            timeout,
            timeout_source,
            ..
        } => format!(
            "heartbeat lost: silent since {} (timeout {timeout} s, {})",
            times.show_opt(*last_seen),
            timeout_source.slug()
        ),
        Health::HeartbeatBack { silent, restarted } => format!(
            "heartbeat back after {silent} s{}",
            if *restarted {
                ", restarted (boot-up)"
            } else {
                ""
            }
        ),
        Health::SdoAbort {
            index,
            subindex,
            abort_code,
            text,
            by_server,
        } => format!(
            "SDO abort 0x{index:04X} sub {subindex} by {}: 0x{abort_code:08X} {text}",
            if *by_server { "server" } else { "client" }
        ),
        Health::ErrorHistory(h) => history_head(h),
        Health::ErrorHistoryCleared => "error history cleared".to_string(),
        Health::AxisState {
            state,
            from,
            statusword,
            via,
        } => {
            let source = match via {
                AxisVia::Pdo { cob_id } => format!("PDO 0x{cob_id:03X}"),
                AxisVia::Sdo => "SDO".to_string(),
            };
            match from {
                Some(f) => format!(
                    "axis {} -> {} (statusword 0x{statusword:04X}, {source})",
                    f.slug(),
                    state.slug()
                ),
                None => format!(
                    "axis {} (statusword 0x{statusword:04X}, {source})",
                    state.slug()
                ),
            }
        }
        Health::FaultReset { controlword } => {
            format!("fault reset (controlword 0x{controlword:04X})")
        }
    }
}

const NODES_HEADER: [&str; 11] = [
    "CHANNEL",
    "NODE",
    "EMCY",
    "STATE AT END",
    "ACTIVE",
    "ERRORS SEEN",
    "PROFILE",
    "IN ERROR",
    "LONGEST",
    "FIRST EMCY",
    "LAST EMCY",
];
const NODES_RIGHT: [bool; 11] = [
    false, true, true, false, false, false, false, true, false, false, false,
];

/// Fills the cells of one node row; returns their display widths.
fn node_cells(
    cells: &mut [String; 11],
    times: &TimeFormat,
    input: &InputReport,
    n: &NodeReport,
) -> [usize; 11] {
    use std::fmt::Write as _;
    for c in cells.iter_mut() {
        c.clear();
    }
    let [
        channel,
        node,
        emcy,
        state,
        active,
        seen,
        profile,
        in_error,
        longest,
        first,
        last,
    ] = cells;
    channel.push_str(&printable(&n.channel));
    node.push_str(itoa::Buffer::new().format(n.node));
    emcy.push_str(itoa::Buffer::new().format(n.emcy_count));
    state.push_str(n.state.slug());
    if n.active.is_empty() {
        active.push('-');
    }
    push_codes(active, &n.active);
    if n.stats.raised.is_empty() {
        seen.push('-');
    }
    for (i, (&code, count)) in n.stats.raised.iter().enumerate() {
        if i > 0 {
            seen.push_str(", ");
        }
        push_code(seen, code);
        seen.push_str(" x");
        seen.push_str(itoa::Buffer::new().format(*count));
    }
    let _ = write!(
        profile,
        "{} ({})",
        n.profile.name(),
        n.profile_source.slug()
    );
    match n.time_in_error(input.last_time) {
        Some(span) => {
            let _ = write!(in_error, "{span}");
        }
        None => in_error.push('-'),
    }
    match n.stats.longest {
        Some((code, span)) => {
            push_code(longest, code);
            let _ = write!(longest, " {span}");
        }
        None => longest.push('-'),
    }
    first.push_str(&times.show_opt(n.stats.first_emcy.and_then(|a| a.time)));
    last.push_str(&times.show_opt(n.stats.last_emcy.and_then(|a| a.time)));
    let mut widths = [0; 11];
    for (w, c) in widths.iter_mut().zip(cells.iter()) {
        *w = display_width(c);
    }
    widths
}

const TIMELINE_HEADER: [&str; 8] = [
    "CHANNEL",
    "NODE",
    "CODE",
    "DESCRIPTION",
    "START",
    "END",
    "DURATION",
    "CLEARED BY",
];
const TIMELINE_RIGHT: [bool; 8] = [false, true, false, false, false, false, true, false];

/// Fills the cells of one error timeline row; returns their display widths.
fn timeline_cells(
    cells: &mut [String; 8],
    times: &TimeFormat,
    texts: &NodeTexts<'_>,
    n: &NodeReport,
    iv: &Interval,
) -> [usize; 8] {
    let (channel, node) = (n.channel.as_str(), n.node);
    for c in cells.iter_mut() {
        c.clear();
    }
    let [
        channel_cell,
        node_cell,
        code,
        description,
        start,
        end,
        duration,
        cleared_by,
    ] = cells;
    let end_time = iv.end.and_then(|e| e.time);
    channel_cell.push_str(&printable(channel));
    node_cell.push_str(itoa::Buffer::new().format(node));
    push_code(code, iv.code);
    let (text, description_width) = texts.get(iv.code);
    description.push_str(text);
    match iv.start.time {
        Some(t) => times.push(start, t),
        None => {
            start.push_str("line ");
            start.push_str(itoa::Buffer::new().format(iv.start.line));
        }
    }
    match (iv.end, iv.start.time, end_time) {
        (None, _, _) => {
            end.push_str("active");
            duration.push('-');
        }
        (Some(_), Some(s), Some(e)) => {
            times.push(end, e);
            let mut text = Vec::with_capacity(32);
            e.push_since(s, &mut text);
            duration.push_str(std::str::from_utf8(&text).unwrap_or_default());
        }
        (Some(e), _, _) => {
            end.push_str("line ");
            end.push_str(itoa::Buffer::new().format(e.line));
            duration.push('-');
        }
    }
    cleared_by.push_str(iv.cleared_by.map_or("-", |c| c.slug()));
    let mut widths = [0; 8];
    for (i, (w, c)) in widths.iter_mut().zip(cells.iter()).enumerate() {
        // The description's width is cached with it (it is rarely ASCII).
        *w = if i == 3 {
            description_width
        } else {
            display_width(c)
        };
    }
    widths
}

/// Calls `row` for every error of the selected nodes, in report order,
/// with the cells' display widths.
fn for_each_timeline_row(
    input: &InputReport,
    times: &TimeFormat,
    mut row: impl FnMut(&[String; 8], &[usize; 8]) -> io::Result<()>,
) -> io::Result<()> {
    let mut cells: [String; 8] = Default::default();
    let mut merge = input.history.merge();
    for n in &input.nodes {
        let texts = NodeTexts::of(n);
        for iv in merge.node_errors(&n.channel, n.node) {
            let widths = timeline_cells(&mut cells, times, &texts, n, &iv);
            row(&cells, &widths)?;
        }
    }
    merge.take_error().map_or(Ok(()), Err)
}

/// [`write_row`] into `line` (cleared first), with the cells' widths known.
fn push_row(
    line: &mut String,
    cells: &[String],
    cell_widths: &[usize],
    widths: &[usize],
    right: &[bool],
) {
    const BLANKS: &str = "                                                                ";
    fn pad(line: &mut String, mut n: usize) {
        while n > 0 {
            let k = n.min(BLANKS.len());
            line.push_str(BLANKS.get(..k).unwrap_or_default());
            n -= k;
        }
    }
    line.clear();
    for (i, cell) in cells.iter().enumerate() {
        let n = widths
            .get(i)
            .copied()
            .unwrap_or(0)
            .saturating_sub(cell_widths.get(i).copied().unwrap_or(0));
        if right.get(i).copied().unwrap_or(false) {
            pad(line, n);
            line.push_str(cell);
        } else {
            line.push_str(cell);
            pad(line, n);
        }
        line.push_str("  ");
    }
    let trimmed = line.trim_end().len();
    line.truncate(trimmed);
    line.push('\n');
}

/// One aligned row: cells padded to their column, two blanks between
/// columns, no trailing blanks (the same layout as the comfy-table tables).
fn write_row(
    out: &mut impl Write,
    cells: &[impl AsRef<str>],
    widths: &[usize],
    right: &[bool],
) -> io::Result<()> {
    let mut line = String::new();
    for (i, cell) in cells.iter().enumerate() {
        let cell = cell.as_ref();
        let pad = widths
            .get(i)
            .copied()
            .unwrap_or(0)
            .saturating_sub(display_width(cell));
        if right.get(i).copied().unwrap_or(false) {
            line.extend(std::iter::repeat_n(' ', pad));
            line.push_str(cell);
        } else {
            line.push_str(cell);
            line.extend(std::iter::repeat_n(' ', pad));
        }
        line.push_str("  ");
    }
    writeln!(out, "{}", line.trim_end())
}

fn new_table(header: &[&str]) -> Table {
    let mut t = Table::new();
    t.load_style(presets::NOTHING);
    t.set_header(header.to_vec());
    for c in t.column_iter_mut() {
        c.set_padding((0, 2));
    }
    t
}

/// comfy-table pads every cell; trailing blanks make golden files noisy.
fn write_table(out: &mut impl Write, table: &Table) -> io::Result<()> {
    for line in table.lines() {
        writeln!(out, "{}", line.trim_end())?;
    }
    Ok(())
}

fn right_align(t: &mut Table, columns: &[usize]) {
    for &i in columns {
        if let Some(c) = t.column_mut(i) {
            c.set_cell_alignment(CellAlignment::Right);
        }
    }
}
