//! The human report: per input, the EMCY events as they are decoded (streamed
//! with fixed columns, so a trace with a million events prints without holding
//! them), then the node states and error timeline; at the end the input counts.

use comfy_table::{CellAlignment, Table, presets};
use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{self, Write};

use anstyle::{AnsiColor, Style};

use super::format::{
    TABLE_LIST, code_text, codes_list, push_code, push_code_counts, push_codes, push_hex,
};
use super::timefmt::{TimeFormat, TimeStyle};
use crate::analyze::{
    AxisReport, BootEvent, Diagnostic, EmcyEvent, Health, HealthEvent, HistoryReport, InputReport,
    NodeReport, Sink,
};
use crate::canopen::NodeId;
use crate::canopen::emcy::Warning;
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
    /// The terminal's width to fit (`None`: a pipe, full lines).
    width: Option<usize>,
    /// The date of the last time shown as a time of day (a narrow table).
    date: String,
    /// How often each node sent each warning about the form of its frames,
    /// by channel: said in full the first time, counted after.
    repeats: HashMap<String, HashMap<(NodeId, Warning), u64>>,
}

/// The event columns, fixed by the first event of an input. At a terminal
/// narrower than the full columns, the least useful give way first (see
/// [`TableReport::layout_for`]); in a pipe every column is there.
#[derive(Clone, Copy)]
struct Layout {
    time: usize,
    channel: usize,
    /// Times of day, the date on a line of its own when it changes.
    time_of_day: bool,
    transition: bool,
    /// The register's width: the hex and its bits, the hex alone, or none.
    register: Option<usize>,
    manufacturer: bool,
    /// Room for the description on the event's row (`None`: unlimited).
    description: Option<usize>,
}

impl Layout {
    /// Where the description starts: the columns before it.
    fn description_indent(&self) -> usize {
        self.code_column()
            + 8
            + if self.transition { 4 } else { 0 }
            + self.register.map_or(0, |w| w + 2)
            + if self.manufacturer {
                MANUFACTURER_WIDTH + 2
            } else {
                0
            }
    }

    /// Where the code (or an NMT event's tag) starts.
    fn code_column(&self) -> usize {
        self.time + 2 + self.channel + 2 + 6
    }
}

/// What the description is given before columns give way to it.
const DESCRIPTION_ROOM: usize = 50;
/// The narrowest width fitted: below it columns cannot give way enough.
pub const MIN_WIDTH: usize = 40;
/// A channel column longer than this is cut when fitting.
const CHANNEL_MAX: usize = 16;

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

    /// An end table in two passes, widths then rows, so no table of a
    /// million rows is held: `rows` gives the rows again for each pass and
    /// `fill` puts a row's cells in `cells`, returning their display widths.
    /// `title` is written first (after a blank line with `blank`); no rows:
    /// nothing is written.
    fn write_in_two_passes<T, I, const N: usize>(
        &mut self,
        (title, blank): (&str, bool),
        (header, right, fit): (&[&str; N], &[bool; N], &Fit),
        rows: impl Fn() -> I,
        mut fill: impl FnMut(&mut [String; N], T) -> [usize; N],
    ) -> io::Result<()>
    where
        I: Iterator<Item = T>,
    {
        let mut cells: [String; N] = std::array::from_fn(|_| String::new());
        let mut widths = header.map(str::len);
        let mut any = false;
        for row in rows() {
            any = true;
            for (w, c) in widths.iter_mut().zip(fill(&mut cells, row)) {
                *w = (*w).max(c);
            }
        }
        if !any {
            return Ok(());
        }
        let shown = self.fit(&mut widths, header, fit);
        if blank {
            writeln!(self.out)?;
        }
        writeln!(self.out, "{}", self.paint(BOLD, title))?;
        write_row(&mut self.out, header, &widths, &shown, right)?;
        let mut line = String::new();
        for row in rows() {
            let cell_widths = fill(&mut cells, row);
            push_row(&mut line, &cells, &cell_widths, &widths, &shown, right);
            self.out.write_all(line.as_bytes())?;
        }
        Ok(())
    }

    /// One line per node: state, errors seen with counts, time in error,
    /// longest error, first and last EMCY.
    fn write_nodes(&mut self, input: &InputReport) -> io::Result<()> {
        // Two passes over the nodes, widths then rows, as for the timeline:
        // a trace can name a million nodes, and a table holding them all
        // took about 2.5 KB per node on top of the reports.
        self.times.set_origin(input.first_time);
        let times = self.times.clone();
        self.write_in_two_passes(
            ("Nodes", false),
            (&NODES_HEADER, &NODES_RIGHT, &NODES_FIT),
            || input.nodes.iter(),
            |cells, n| node_cells(cells, &times, input, n),
        )
    }

    /// The summary's codes: per node, each code it raised, how often, and
    /// what the node's profile says it is (the nodes' row gives codes
    /// only). Two passes, widths then rows, as for the nodes.
    fn write_codes(&mut self, input: &InputReport) -> io::Result<()> {
        let rows = || {
            input.nodes.iter().flat_map(|n| {
                let texts = NodeTexts::of(n);
                n.stats.raised.iter().map(move |(&code, &count)| {
                    let (text, width) = texts.get(code);
                    let cells = [
                        printable(&n.channel).into_owned(),
                        n.node.to_string(),
                        code_text(code),
                        count.to_string(),
                        text.to_owned(),
                    ];
                    let mut widths = cells.each_ref().map(|c| display_width(c));
                    widths[4] = width;
                    (cells, widths)
                })
            })
        };
        self.write_in_two_passes(
            ("Errors seen", true),
            (&CODES_HEADER, &CODES_RIGHT, &CODES_FIT),
            rows,
            |cells, (row, widths)| {
                *cells = row;
                widths
            },
        )
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
        self.write_in_two_passes(
            ("Node health", true),
            (&HEALTH_HEADER, &HEALTH_RIGHT, &HEALTH_FIT),
            || input.nodes.iter().filter(told),
            |cells, n| health_cells(cells, &times, n),
        )
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
        let rows: Vec<[String; 7]> = axes
            .iter()
            .map(|(n, a)| {
                let mapping: Vec<String> = a
                    .mappings
                    .iter()
                    .map(|m| format!("0x{:03X} {}", m.cob_id.id, m.source.slug()))
                    .collect();
                [
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
                ]
            })
            .collect();
        let mut widths = AXES_HEADER.map(str::len);
        for row in &rows {
            for (w, c) in widths.iter_mut().zip(row) {
                *w = (*w).max(display_width(c));
            }
        }
        let shown = self.fit(&mut widths, &AXES_HEADER, &AXES_FIT);
        writeln!(self.out)?;
        writeln!(self.out, "{}", self.paint(BOLD, "Drive axes (CiA 402)"))?;
        write_comfy_table(
            &mut self.out,
            &AXES_HEADER,
            &rows,
            &widths,
            &shown,
            &AXES_RIGHT,
        )
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
        let line = format!(
            "bus: {frames}, {} EMCY{rate}{span}, {} of {} nodes with errors{lost}, {} malformed{dropped}",
            c.emcy,
            input.nodes_with_errors(),
            input.nodes.len(),
            c.malformed,
        );
        self.write_wrapped(&line, 5)
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
        let time_text = time.map(|t| self.times.show(t));
        let time_width = time_text.as_ref().map_or(1, |t| t.len()).max(4);
        let mut l = Layout {
            time: time_width,
            channel: printable(channel).chars().count().max(7),
            time_of_day: false,
            transition: true,
            register: Some(REGISTER_WIDTH),
            manufacturer: true,
            description: None,
        };
        if let Some(width) = self.width {
            // The least useful columns give way first, until the description
            // has room: the register's bit names (its hex stays), the raw
            // manufacturer bytes (the profile's reading stays, as its line),
            // the date (on a line of its own), the transition (the colour
            // says it), the register.
            l.channel = l.channel.min(CHANNEL_MAX);
            let dated = time_text.as_deref().is_some_and(|t| iso_date(t).is_some());
            let mut step = 0;
            while l.description_indent() + DESCRIPTION_ROOM > width {
                match step {
                    0 => l.register = Some(3),
                    1 => l.manufacturer = false,
                    2 if dated => {
                        l.time_of_day = true;
                        l.time = (time_width - DATE_PREFIX).max(4);
                    }
                    3 => l.transition = false,
                    4 => l.register = None,
                    5 => break,
                    _ => {}
                }
                step += 1;
            }
            l.description = Some(width.saturating_sub(l.description_indent()).max(8));
        }
        self.layout = Some(l);
        let mut header = String::new();
        push_padded(&mut header, "TIME", l.time);
        push_padded(&mut header, "CHANNEL", l.channel);
        header.push_str("NODE  CODE    ");
        if l.transition {
            header.push_str("TR  ");
        }
        match l.register {
            Some(REGISTER_WIDTH) => push_padded(&mut header, "REGISTER", REGISTER_WIDTH),
            Some(w) => push_padded(&mut header, "REG", w),
            None => {}
        }
        if l.manufacturer {
            push_padded(&mut header, "MANUFACTURER", MANUFACTURER_WIDTH);
        }
        header.push_str("DESCRIPTION");
        writeln!(self.out, "{}", self.paint(BOLD, &header))?;
        Ok(l)
    }

    /// `TIME  CHANNEL  NODE  ` padded to the layout, appended to `line`;
    /// before it, for times of day, the date when it changed.
    fn push_prefix(
        &mut self,
        line: &mut String,
        l: Layout,
        time: Option<Timestamp>,
        channel: &str,
        node: NodeId,
    ) {
        let start = line.len();
        let mut row_start = start;
        self.times.push_opt(line, time);
        // `iso_date` checked the 11 ASCII bytes the ranges below remove.
        if l.time_of_day
            && let Some(date) = line.get(start..).and_then(iso_date)
        {
            if date != self.date {
                self.date.clear();
                self.date.push_str(date);
                let mut head = String::with_capacity(16);
                head.push_str(&self.paint(BOLD, date));
                head.push('\n');
                line.insert_str(start, &head);
                row_start = start + head.len();
                line.replace_range(row_start..row_start + DATE_PREFIX, "");
            } else {
                line.replace_range(start..start + DATE_PREFIX, "");
            }
        }
        pad_to(line, row_start + l.time);
        line.push_str("  ");
        let channel = printable(channel);
        match self.width {
            Some(_) => {
                let shown = push_cut(line, &channel, l.channel);
                line.push_str(&blanks(l.channel.saturating_sub(shown)));
            }
            None => {
                line.push_str(&channel);
                for _ in channel.chars().count()..l.channel {
                    line.push(' ');
                }
            }
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

    /// `text` in the description column: cut to the room there is (one row
    /// per event) when fitting.
    fn push_description(&self, line: &mut String, l: Layout, text: &str) {
        match l.description {
            Some(room) => {
                push_cut(line, text, room);
            }
            None => line.push_str(text),
        }
    }

    /// A line of detail under an event (the profile's reading, a warning),
    /// indented to `indent`; wrapped to the width when fitting.
    fn write_detail(&mut self, indent: usize, text: &str, style: Option<Style>) -> io::Result<()> {
        let lines = match self.width {
            Some(width) => textwrap::wrap(text, width.saturating_sub(indent).max(8)),
            None => vec![Cow::Borrowed(text)],
        };
        for piece in lines {
            self.out.write_all(blanks(indent).as_bytes())?;
            match style {
                Some(style) if self.color => write!(
                    self.out,
                    "{}{piece}{}",
                    style.render(),
                    style.render_reset()
                )?,
                _ => self.out.write_all(piece.as_bytes())?,
            }
            self.out.write_all(b"\n")?;
        }
        Ok(())
    }

    /// An NMT event's row: its tag in the code column, its text as the
    /// description.
    #[allow(clippy::too_many_arguments)]
    fn write_tagged(
        &mut self,
        l: Layout,
        time: Option<Timestamp>,
        channel: &str,
        node: NodeId,
        tag: &str,
        style: Option<Style>,
        what: &str,
    ) -> io::Result<()> {
        // The event line's buffer: NMT and heartbeat rows are many too.
        let mut line = std::mem::take(&mut self.line);
        line.clear();
        self.push_prefix(&mut line, l, time, channel, node);
        match style {
            Some(style) if self.color => {
                line.push_str(&self.paint(style, tag));
            }
            _ => line.push_str(tag),
        }
        let column = l.description_indent();
        line.push_str(&blanks(column.saturating_sub(l.code_column() + tag.len())));
        self.push_description(&mut line, l, what);
        line.push('\n');
        let written = self.out.write_all(line.as_bytes());
        self.line = line;
        written
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

    /// The error timeline, in two passes over the history (column widths,
    /// then rows): a trace with millions of errors needs no stored rows.
    fn write_timeline(&mut self, input: &InputReport) -> io::Result<()> {
        let times = self.times.clone();
        let Some(mut widths) = timeline_widths(input, &times)? else {
            return Ok(());
        };
        let shown = self.fit(&mut widths, &TIMELINE_HEADER, &TIMELINE_FIT);
        writeln!(self.out)?;
        writeln!(self.out, "{}", self.paint(BOLD, "Error timeline"))?;
        write_row(
            &mut self.out,
            &TIMELINE_HEADER,
            &widths,
            &shown,
            &TIMELINE_RIGHT,
        )?;
        let out = &mut self.out;
        let mut line = String::new();
        for_each_timeline_row(input, &times, |cells, cell_widths| {
            push_row(
                &mut line,
                cells,
                cell_widths,
                &widths,
                &shown,
                &TIMELINE_RIGHT,
            );
            out.write_all(line.as_bytes())
        })
    }

    /// The columns shown of a table with these widths, fitted to the
    /// terminal (all of them in a pipe).
    fn fit<const N: usize>(
        &self,
        widths: &mut [usize; N],
        header: &[&str; N],
        fit: &Fit,
    ) -> [bool; N] {
        let mut shown = [true; N];
        if let Some(width) = self.width {
            fit_columns(widths, &mut shown, header, fit, width);
        }
        shown
    }

    /// Counts `w` for the node; true when it was said for the node before
    /// and saying it again adds nothing: the form of a node's frames
    /// (register bits, byte counts, bytes that should be zero) is the same
    /// on every frame. What the state machine says of one frame (a reset
    /// that cleared nothing) is always said.
    fn repeated(&mut self, channel: &str, node: NodeId, w: &Warning) -> bool {
        let Some(key) = repeat_key(w) else {
            return false;
        };
        let nodes = match self.repeats.get_mut(channel) {
            Some(nodes) => nodes,
            None => self.repeats.entry(channel.to_owned()).or_default(),
        };
        let count = nodes.entry((node, key)).or_insert(0);
        *count += 1;
        *count > 1
    }

    /// The warnings said once per node above, with how often each came.
    fn write_repeats(&mut self) -> io::Result<()> {
        let mut rows: Vec<(&str, NodeId, &'static str, u64)> = self
            .repeats
            .iter()
            .flat_map(|(channel, nodes)| {
                nodes
                    .iter()
                    .filter(|(_, n)| **n > 1)
                    .map(move |((node, w), n)| (channel.as_str(), *node, w.tag(), *n))
            })
            .collect();
        if rows.is_empty() {
            return Ok(());
        }
        rows.sort_unstable();
        let cells: Vec<[String; 4]> = rows
            .iter()
            .map(|(channel, node, tag, n)| {
                [
                    printable(channel).into_owned(),
                    node.to_string(),
                    (*tag).to_string(),
                    n.to_string(),
                ]
            })
            .collect();
        let mut widths = REPEATS_HEADER.map(str::len);
        for row in &cells {
            for (w, c) in widths.iter_mut().zip(row) {
                *w = (*w).max(display_width(c));
            }
        }
        let shown = self.fit(&mut widths, &REPEATS_HEADER, &REPEATS_FIT);
        writeln!(self.out)?;
        let title = self.paint(BOLD, "Repeated warnings");
        self.write_wrapped(&format!("{title} (said once per node above)"), 0)?;
        write_row(
            &mut self.out,
            &REPEATS_HEADER,
            &widths,
            &shown,
            &REPEATS_RIGHT,
        )?;
        for row in &cells {
            write_row(&mut self.out, row, &widths, &shown, &REPEATS_RIGHT)?;
        }
        Ok(())
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
const HEALTH_FIT: Fit = Fit {
    drop: &[],
    flex: &[(3, 40, 12), (4, 40, 10), (5, 40, 12), (0, CHANNEL_MAX, 7)],
};

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

const CODES_HEADER: [&str; 5] = ["CHANNEL", "NODE", "CODE", "TIMES", "DESCRIPTION"];
const CODES_RIGHT: [bool; 5] = [false, true, false, true, false];
const CODES_FIT: Fit = Fit {
    drop: &[],
    flex: &[(4, usize::MAX, 12), (0, CHANNEL_MAX, 7)],
};

const REPEATS_HEADER: [&str; 4] = ["CHANNEL", "NODE", "WARNING", "FRAMES"];
const REPEATS_RIGHT: [bool; 4] = [false, true, false, true];
const REPEATS_FIT: Fit = Fit {
    drop: &[],
    flex: &[(0, CHANNEL_MAX, 7)],
};

/// What makes a warning a repeat of one said before for the node (`None`:
/// never one). The register, the bytes, the length may differ from frame
/// to frame; what the warning says of the node does not.
fn repeat_key(w: &Warning) -> Option<Warning> {
    Some(match *w {
        Warning::ShortFrame { .. } => Warning::ShortFrame { len: 0 },
        Warning::NoGenericBit { .. } => Warning::NoGenericBit { register: 0 },
        Warning::ManufacturerBytesNonZero { .. } => {
            Warning::ManufacturerBytesNonZero { first: 0, last: 0 }
        }
        Warning::ReservedBit
        | Warning::EmptyRegister
        | Warning::ProfileReservedBit { .. }
        | Warning::ClassRegisterMismatch { .. }
        | Warning::OddResetCode { .. }
        | Warning::UndefinedCode { .. } => *w,
        Warning::ResetWhileErrorFree
        | Warning::PartialResetWhileErrorFree
        | Warning::PartialResetUnattributed { .. } => return None,
    })
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

/// `YYYY-MM-DDT`: the date of an ISO-8601 time, which a narrow table shows
/// once on a line of its own.
const DATE_PREFIX: usize = 11;

/// The date of an ISO-8601 time text (`2023-11-14` of `2023-11-14T22:13:20Z`).
fn iso_date(time: &str) -> Option<&str> {
    let b = time.as_bytes();
    let shape = b.len() > DATE_PREFIX
        && b.iter().take(10).enumerate().all(|(i, c)| match i {
            4 | 7 => *c == b'-',
            _ => c.is_ascii_digit(),
        })
        && b.get(10) == Some(&b'T');
    if shape { time.get(..10) } else { None }
}

/// `n` blanks.
fn blanks(n: usize) -> Cow<'static, str> {
    const BLANKS: &str = "                                                                                                                                ";
    match BLANKS.get(..n) {
        Some(b) => Cow::Borrowed(b),
        None => Cow::Owned(" ".repeat(n)),
    }
}

/// `text` padded to `width` columns, then the two blanks between columns.
fn push_padded(line: &mut String, text: &str, width: usize) {
    line.push_str(text);
    line.push_str(&blanks(width.saturating_sub(display_width(text)) + 2));
}

/// Appends `text` cut to `width` columns, an ellipsis marking the cut;
/// returns the columns it took.
fn push_cut(line: &mut String, text: &str, width: usize) -> usize {
    let full = display_width(text);
    if full <= width {
        line.push_str(text);
        return full;
    }
    let mut used = 0;
    for c in text.chars() {
        let w = unicode_width::UnicodeWidthChar::width(c).unwrap_or(0);
        if used + w + 1 > width {
            break;
        }
        line.push(c);
        used += w;
    }
    if width > 0 {
        line.push('…');
        used += 1;
    }
    used
}

/// Pads `s` with blanks up to `width` bytes (ASCII columns).
fn pad_to(s: &mut String, width: usize) {
    while s.len() < width {
        s.push(' ');
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
        if l.transition {
            match ev.transition {
                Some(t) => {
                    line.push(' ');
                    line.push(char::from(b'0' + t % 10));
                }
                None => line.push_str(" -"),
            }
            line.push_str("  ");
        }
        let reg = ev.emcy.register.0;
        match l.register {
            Some(REGISTER_WIDTH) => {
                let register = self.registers[usize::from(reg)].get_or_insert_with(|| {
                    format!(
                        "{:<rw$}",
                        format!("{reg:02X} {}", ev.emcy.register.short()),
                        rw = REGISTER_WIDTH
                    )
                });
                line.push_str(register);
                line.push_str("  ");
            }
            Some(w) => {
                let start = line.len();
                push_hex(&mut line, &[reg]);
                pad_to(&mut line, start + w + 2);
            }
            None => {}
        }
        if l.manufacturer {
            let start = line.len();
            for (i, b) in ev.emcy.manufacturer().iter().enumerate() {
                if i > 0 {
                    line.push(' ');
                }
                push_hex(&mut line, std::slice::from_ref(b));
            }
            pad_to(&mut line, start + MANUFACTURER_WIDTH);
            line.push_str("  ");
        }
        let description = printable(ev.description);
        if ev.cleared.is_empty() {
            self.push_description(&mut line, l, &description);
        } else if l.description.is_none() {
            // Full lines (a pipe): straight into the line, no text to cut.
            line.push_str(&description);
            line.push_str(" (cleared ");
            push_codes(&mut line, ev.cleared.iter().copied(), &TABLE_LIST);
            line.push(')');
        } else {
            let mut text = String::with_capacity(description.len() + 16);
            text.push_str(&description);
            text.push_str(" (cleared ");
            push_codes(&mut text, ev.cleared.iter().copied(), &TABLE_LIST);
            text.push(')');
            self.push_description(&mut line, l, &text);
        }
        let trimmed = line.trim_end().len();
        line.truncate(trimmed);
        line.push('\n');
        self.out.write_all(line.as_bytes())?;
        self.line = line;
        let indent = l.description_indent();
        // A reset with bytes 3-7 zero, as the manuals say resets are: its
        // reading (`category: 0`) adds nothing.
        let plain_reset = ev.emcy.is_reset() && ev.emcy.manufacturer().iter().all(|b| *b == 0);
        if let Some(decoded) = ev.decoded.filter(|_| !plain_reset) {
            self.write_detail(indent, &decoded_text(decoded), None)?;
        }
        for w in ev.warnings {
            if self.repeated(ev.channel, ev.node, w) {
                continue;
            }
            self.write_detail(indent, &format!("warning: {w}"), Some(YELLOW))?;
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
        self.write_tagged(l, ev.time, ev.channel, ev.node, "boot", Some(GREEN), &what)?;
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
        self.write_tagged(
            l,
            ev.time,
            ev.channel,
            ev.node,
            tag,
            style,
            &printable(&what),
        )?;
        if let Health::ErrorHistory(h) = ev.health {
            let indent = l.description_indent() + 2;
            for e in &h.entries {
                let text = format!(
                    "0x{:04X} (info 0x{:04X}) {}{}",
                    e.code,
                    e.info,
                    printable(&e.description),
                    if e.before_trace {
                        " [before the trace]"
                    } else {
                        ""
                    }
                );
                self.write_detail(indent, &text, None)?;
            }
        }
        self.end_event()
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        if self.summary_only {
            if !input.nodes.is_empty() {
                self.write_nodes(input)?;
                self.write_codes(input)?;
                self.write_health(input)?;
                self.write_axes(input)?;
            }
            self.write_bus_line(input)?;
            return writeln!(self.out);
        }
        if self.layout.is_none() {
            writeln!(self.out, "no EMCY frames")?;
        } else {
            // The legend of a column a narrow terminal went without is not said.
            if self.layout.is_some_and(|l| l.transition) {
                self.write_wrapped(
                    "TR = transition: 1 first error, 2 one error reset, 3 further error, 4 all reset",
                    5,
                )?;
            }
        }
        self.write_repeats()?;
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
        let rows: Vec<[String; 8]> = inputs
            .iter()
            .map(|i| {
                let c = &i.counts;
                [
                    printable(&i.file).into_owned(),
                    i.format.map_or("-", |f| f.name()).to_string(),
                    c.lines.to_string(),
                    c.frames.to_string(),
                    c.emcy.to_string(),
                    c.boot.to_string(),
                    c.skipped.to_string(),
                    c.malformed.to_string(),
                ]
            })
            .collect();
        let mut widths = INPUTS_HEADER.map(str::len);
        for row in &rows {
            for (w, c) in widths.iter_mut().zip(row) {
                *w = (*w).max(display_width(c));
            }
        }
        let shown = self.fit(&mut widths, &INPUTS_HEADER, &INPUTS_FIT);
        writeln!(self.out, "{}", self.paint(BOLD, "Inputs"))?;
        write_comfy_table(
            &mut self.out,
            &INPUTS_HEADER,
            &rows,
            &widths,
            &shown,
            &INPUTS_RIGHT,
        )?;
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
/// First and last EMCY are in the events above, the profile is the
/// description's; the errors seen and the active ones are what the row is for.
const NODES_FIT: Fit = Fit {
    drop: &[9, 10, 6, 8, 7, 2],
    flex: &[(5, 40, 14), (4, 24, 8), (0, CHANNEL_MAX, 7)],
};

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
    push_codes(active, n.active.iter().copied(), &TABLE_LIST);
    if n.stats.raised.is_empty() {
        seen.push('-');
    }
    push_code_counts(
        seen,
        n.stats.raised.iter().map(|(&code, &count)| (code, count)),
        &TABLE_LIST,
    );
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
/// The end is the start plus the duration.
const TIMELINE_FIT: Fit = Fit {
    drop: &[7, 5],
    flex: &[(3, 40, 12), (0, CHANNEL_MAX, 7)],
};
const AXES_HEADER: [&str; 7] = [
    "CHANNEL",
    "NODE",
    "AXIS AT END",
    "FAULTS",
    "RESETS",
    "MAPPING",
    "SUMMARY",
];
const AXES_RIGHT: [bool; 7] = [false, true, false, true, true, false, false];
/// The summary sentence says the faults and the state at the end again.
const AXES_FIT: Fit = Fit {
    drop: &[5, 4, 3],
    flex: &[(6, 60, 20), (0, CHANNEL_MAX, 7)],
};
const INPUTS_HEADER: [&str; 8] = [
    "FILE",
    "FORMAT",
    "LINES",
    "FRAMES",
    "EMCY",
    "BOOT",
    "SKIPPED",
    "MALFORMED",
];
const INPUTS_RIGHT: [bool; 8] = [false, false, true, true, true, true, true, true];
const INPUTS_FIT: Fit = Fit {
    drop: &[5, 6, 2],
    flex: &[(0, 60, 12)],
};

/// How a table gives way to a terminal's width: columns are dropped, least
/// useful first, then the flexible ones cut (an ellipsis marks a cut cell).
struct Fit {
    drop: &'static [usize],
    /// Column, width kept before any column is dropped, narrowest width.
    flex: &'static [(usize, usize, usize)],
}

fn fit_columns(widths: &mut [usize], shown: &mut [bool], header: &[&str], fit: &Fit, width: usize) {
    let total = |widths: &[usize], shown: &[bool]| {
        let (sum, n) = widths
            .iter()
            .zip(shown)
            .filter(|(_, s)| **s)
            .fold((0usize, 0usize), |(sum, n), (w, _)| (sum + w, n + 1));
        sum + 2 * n.saturating_sub(1)
    };
    let least = |i: usize, min: usize| min.max(header.get(i).map_or(0, |h| h.len()));
    for &(i, keep, min) in fit.flex {
        if let Some(w) = widths.get_mut(i) {
            *w = (*w).min(keep.max(least(i, min)));
        }
    }
    for &d in fit.drop {
        if total(widths, shown) <= width {
            return;
        }
        if let Some(s) = shown.get_mut(d) {
            *s = false;
        }
    }
    // The widest flexible column gives a column at a time.
    while total(widths, shown) > width {
        let widest = fit
            .flex
            .iter()
            .filter(|&&(i, _, min)| widths.get(i).is_some_and(|w| *w > least(i, min)))
            .max_by_key(|&&(i, _, _)| widths.get(i).copied().unwrap_or(0));
        match widest.and_then(|&(i, _, _)| widths.get_mut(i)) {
            Some(w) => *w -= 1,
            None => break,
        }
    }
}

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

/// The timeline's column widths (`None`: no rows), measured without
/// writing the rows: the first of two passes over millions of errors, it
/// cost as much as writing them.
fn timeline_widths(input: &InputReport, times: &TimeFormat) -> io::Result<Option<[usize; 8]>> {
    let mut widths = TIMELINE_HEADER.map(str::len);
    let mut any = false;
    let mut merge = input.history.merge();
    let mut scratch = Vec::with_capacity(32);
    for n in &input.nodes {
        let texts = NodeTexts::of(n);
        let channel = display_width(&printable(&n.channel));
        let node = itoa::Buffer::new().format(n.node).len();
        for iv in merge.node_errors(&n.channel, n.node) {
            any = true;
            let end_time = iv.end.and_then(|e| e.time);
            let line_width = |line: u64| 5 + itoa::Buffer::new().format(line).len();
            let start = match iv.start.time {
                Some(t) => times.width(t),
                None => line_width(iv.start.line),
            };
            let (end, duration) = match (iv.end, iv.start.time, end_time) {
                (None, _, _) => ("active".len(), 1),
                (Some(_), Some(s), Some(e)) => {
                    scratch.clear();
                    e.push_since(s, &mut scratch);
                    (times.width(e), scratch.len())
                }
                (Some(e), _, _) => (line_width(e.line), 1),
            };
            let cleared_by = iv.cleared_by.map_or(1, |c| c.slug().len());
            let row = [
                channel,
                node,
                6,
                texts.get(iv.code).1,
                start,
                end,
                duration,
                cleared_by,
            ];
            for (w, c) in widths.iter_mut().zip(row) {
                *w = (*w).max(c);
            }
        }
    }
    merge.take_error().map_or(Ok(any.then_some(widths)), Err)
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

/// A small table (one row per input) laid out by comfy-table, the
/// project's table crate: the shown columns, cells cut to the widths a
/// terminal left them (see [`fit_columns`]), two blanks between columns and
/// no trailing blanks. The per-event rows are written by hand instead: they
/// stream, and a table crate would hold them all.
fn write_comfy_table<const N: usize>(
    out: &mut impl Write,
    header: &[&str; N],
    rows: &[[String; N]],
    widths: &[usize; N],
    shown: &[bool; N],
    right: &[bool; N],
) -> io::Result<()> {
    let columns: Vec<usize> = (0..N).filter(|&i| shown[i]).collect();
    let mut table = Table::new();
    table.load_style(presets::NOTHING);
    table.set_header(columns.iter().map(|&i| header[i]).collect::<Vec<_>>());
    for row in rows {
        table.add_row(columns.iter().map(|&i| {
            let cell = &row[i];
            if display_width(cell) > widths[i] {
                let mut cut = String::new();
                push_cut(&mut cut, cell, widths[i]);
                cut
            } else {
                cell.clone()
            }
        }));
    }
    for (column, &i) in table.column_iter_mut().zip(&columns) {
        column.set_padding((0, 2));
        if right[i] {
            column.set_cell_alignment(CellAlignment::Right);
        }
    }
    // comfy-table pads every cell; trailing blanks make golden files noisy.
    for line in table.lines() {
        writeln!(out, "{}", line.trim_end())?;
    }
    Ok(())
}

/// [`write_row`] into `line` (cleared first), with the cells' widths known.
fn push_row(
    line: &mut String,
    cells: &[String],
    cell_widths: &[usize],
    widths: &[usize],
    shown: &[bool],
    right: &[bool],
) {
    line.clear();
    for (i, cell) in cells.iter().enumerate() {
        if !shown.get(i).copied().unwrap_or(true) {
            continue;
        }
        let width = widths.get(i).copied().unwrap_or(0);
        let cell_width = cell_widths.get(i).copied().unwrap_or(0);
        push_cell(
            line,
            cell,
            cell_width,
            width,
            right.get(i).copied().unwrap_or(false),
        );
    }
    let trimmed = line.trim_end().len();
    line.truncate(trimmed);
    line.push('\n');
}

/// A cell padded to its column (cut to it when fitting), then the two
/// blanks between columns.
fn push_cell(line: &mut String, cell: &str, cell_width: usize, width: usize, right: bool) {
    if cell_width > width {
        push_cut(line, cell, width);
    } else if right {
        line.push_str(&blanks(width - cell_width));
        line.push_str(cell);
    } else {
        line.push_str(cell);
        line.push_str(&blanks(width - cell_width));
    }
    line.push_str("  ");
}

/// One aligned row: cells padded to their column, two blanks between
/// columns, no trailing blanks.
fn write_row(
    out: &mut impl Write,
    cells: &[impl AsRef<str>],
    widths: &[usize],
    shown: &[bool],
    right: &[bool],
) -> io::Result<()> {
    let cell_widths: Vec<usize> = cells.iter().map(|c| display_width(c.as_ref())).collect();
    let mut line = String::new();
    for (i, cell) in cells.iter().enumerate() {
        if !shown.get(i).copied().unwrap_or(true) {
            continue;
        }
        let width = widths.get(i).copied().unwrap_or(0);
        let cell_width = cell_widths.get(i).copied().unwrap_or(0);
        push_cell(
            &mut line,
            cell.as_ref(),
            cell_width,
            width,
            right.get(i).copied().unwrap_or(false),
        );
    }
    writeln!(out, "{}", line.trim_end())
}
