//! The events of an input, one row each as they are decoded: the columns
//! are fixed by the first event (a narrow terminal's least useful ones
//! given up then), so no row waits for the ones after it. Lines under an
//! event (the profile's reading, warnings) follow it. Under the input's
//! events, their legend and the warnings said once per node.

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{self, Write};

use anstyle::Style;

use super::fit::{
    CHANNEL_MAX, Fit, blanks, display_width, pad_to, push_cut, push_padded, write_row,
};
use super::page::{BOLD, GREEN, Page, RED, YELLOW};
use crate::analyze::{
    BootEvent, Bus, BusEvent, EmcyEvent, Health, HealthEvent, HistoryReport, SdoTransfer,
};
use crate::canopen::NodeId;
use crate::canopen::emcy::Warning;
use crate::canopen::profile::{Decoded, FieldValue};
use crate::canopen::sdo::transfer::Outcome;
use crate::report::format::{
    TABLE_LIST, code_text, codes_list, push_code, push_codes, push_hex_byte,
};
use crate::report::timefmt::{TimeFormat, human_span};
use crate::text::printable;
use crate::timeline::drive::Via as DriveVia;
use crate::trace::Timestamp;

/// The event columns, fixed by the first event of an input. At a terminal
/// narrower than the full columns, the least useful give way first (see
/// [`EventLines::layout_for`]); in a pipe every column is there.
#[derive(Clone, Copy)]
pub(super) struct Layout {
    pub(super) time: usize,
    pub(super) channel: usize,
    /// Times of day, the date on a line of its own when it changes.
    pub(super) time_of_day: bool,
    pub(super) transition: bool,
    /// The register's width: the hex and its bits, the hex alone, or none.
    pub(super) register: Option<usize>,
    pub(super) manufacturer: bool,
    /// Room for the description on the event's row (`None`: unlimited).
    pub(super) description: Option<usize>,
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

/// The register column in full (its hex and its bits' short names) and the
/// manufacturer bytes (five, in hex).
const REGISTER_WIDTH: usize = 16;
const MANUFACTURER_WIDTH: usize = 14;

/// `YYYY-MM-DDT`: the date of an ISO-8601 time, which a narrow table shows
/// once on a line of its own.
const DATE_PREFIX: usize = 11;

/// How often each node sent each warning about the form of its frames, by
/// channel: said in full the first time, counted after.
type Repeats = HashMap<String, HashMap<(NodeId, Warning), u64>>;

/// The event rows of an input as they stream: the columns fixed by the
/// first, the buffers reused from row to row, and the warnings said once.
pub(super) struct EventLines {
    /// Column widths fixed by the first event of an input.
    layout: Option<Layout>,
    /// The event line being built, kept for its capacity.
    line: String,
    /// Register column texts, padded, by register value.
    registers: Vec<Option<String>>,
    /// The date of the last time shown as a time of day (a narrow table).
    date: String,
    repeats: Repeats,
}

impl EventLines {
    pub(super) fn new() -> Self {
        EventLines {
            layout: None,
            line: String::new(),
            registers: vec![None; 256],
            date: String::new(),
            repeats: HashMap::new(),
        }
    }

    /// A new input: its first event fixes the columns again.
    pub(super) fn begin_input(&mut self) {
        self.layout = None;
        self.date.clear();
        self.repeats.clear();
    }

    /// An EMCY's row, and under it the profile's reading and the warnings
    /// not said for the node before.
    pub(super) fn write_emcy<W: Write>(
        &mut self,
        page: &mut Page<W>,
        ev: &EmcyEvent<'_>,
    ) -> io::Result<()> {
        page.times.set_origin(ev.time);
        let l = self.layout_for(page, ev.time, ev.channel)?;
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
        self.push_prefix(page, &mut line, l, ev.time, ev.channel, Some(ev.node));
        if page.color {
            line.push_str(&page.paint(style, &code_text(ev.emcy.code)));
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
                push_hex_byte(&mut line, reg);
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
                push_hex_byte(&mut line, *b);
            }
            pad_to(&mut line, start + MANUFACTURER_WIDTH);
            line.push_str("  ");
        }
        let description = printable(ev.description);
        if ev.cleared.is_empty() {
            push_description(&mut line, l, &description);
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
            push_description(&mut line, l, &text);
        }
        let trimmed = line.trim_end().len();
        line.truncate(trimmed);
        line.push('\n');
        page.out.write_all(line.as_bytes())?;
        self.line = line;
        let indent = l.description_indent();
        // A reset with bytes 3-7 zero, as the manuals say resets are: its
        // reading (`category: 0`) adds nothing.
        let plain_reset = ev.emcy.is_reset() && ev.emcy.manufacturer().iter().all(|b| *b == 0);
        if let Some(decoded) = ev.decoded.filter(|_| !plain_reset) {
            write_detail(page, indent, &decoded_text(decoded), None)?;
        }
        for w in ev.warnings {
            if self.repeated(ev.channel, ev.node, w) {
                continue;
            }
            write_detail(page, indent, &format!("warning: {w}"), Some(YELLOW))?;
        }
        Ok(())
    }

    /// A boot-up's row.
    pub(super) fn write_boot<W: Write>(
        &mut self,
        page: &mut Page<W>,
        ev: &BootEvent<'_>,
    ) -> io::Result<()> {
        page.times.set_origin(ev.time);
        let l = self.layout_for(page, ev.time, ev.channel)?;
        let what = if ev.cleared.is_empty() {
            "NMT boot-up".to_string()
        } else {
            format!("NMT boot-up (cleared {})", codes_list(ev.cleared))
        };
        self.write_tagged(
            page,
            l,
            ev.time,
            ev.channel,
            Some(ev.node),
            "boot",
            Some(GREEN),
            &what,
        )
    }

    /// A health event's row (NMT, heartbeat, SDO abort, error history read
    /// out, drive state), and an error history's entries under it.
    pub(super) fn write_health_event<W: Write>(
        &mut self,
        page: &mut Page<W>,
        ev: &HealthEvent<'_>,
    ) -> io::Result<()> {
        page.times.set_origin(ev.time);
        let l = self.layout_for(page, ev.time, ev.channel)?;
        let what = health_description(ev.health, &page.times);
        let (tag, style) = match ev.health {
            Health::Nmt { .. } => ("nmt", None),
            Health::HeartbeatLost { .. } => ("lost", Some(RED)),
            Health::HeartbeatBack { .. } => ("back", Some(GREEN)),
            Health::SdoAbort { .. } => ("abort", Some(YELLOW)),
            Health::ErrorHistory(_) | Health::ErrorHistoryCleared => ("1003h", None),
            Health::DriveState { state, .. } if state.is_fault() => ("axis", Some(RED)),
            Health::DriveState { .. } => ("axis", None),
            Health::FaultReset { .. } => ("reset", Some(GREEN)),
        };
        self.write_tagged(
            page,
            l,
            ev.time,
            ev.channel,
            Some(ev.node),
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
                write_detail(page, indent, &text, None)?;
            }
        }
        Ok(())
    }

    /// A bus event's row: an error burst, a bus-off (with its evidence
    /// under it).
    pub(super) fn write_bus_event<W: Write>(
        &mut self,
        page: &mut Page<W>,
        ev: &BusEvent<'_>,
    ) -> io::Result<()> {
        page.times.set_origin(ev.time);
        let l = self.layout_for(page, ev.time, ev.channel)?;
        let what = bus_description(ev.bus, &page.times);
        let (tag, node, style) = match ev.bus {
            Bus::Errors(_) => ("errors", None, Some(RED)),
            Bus::BusOff(off) => ("busoff", off.node, Some(RED)),
            Bus::Lss(l) => ("lss", l.node, None),
            Bus::Incident(_) => ("incident", None, Some(RED)),
            Bus::SyncMissed(_) => ("sync", None, Some(YELLOW)),
            Bus::Sdo(t) => match t.outcome {
                Outcome::Ok => ("sdo", Some(t.node), None),
                Outcome::Abort { .. } => ("sdo", Some(t.node), Some(RED)),
                Outcome::Unanswered | Outcome::Incomplete => ("sdo", Some(t.node), Some(YELLOW)),
            },
        };
        self.write_tagged(
            page,
            l,
            ev.time,
            ev.channel,
            node,
            tag,
            style,
            &printable(&what),
        )?;
        if let Bus::BusOff(off) = ev.bus {
            let indent = l.description_indent() + 2;
            for e in &off.evidence {
                let text = format!(
                    "{} at {} (line {})",
                    e.kind.words(),
                    page.times.show_opt(e.time),
                    e.line
                );
                write_detail(page, indent, &text, None)?;
            }
        }
        Ok(())
    }

    pub(super) fn layout_for<W: Write>(
        &mut self,
        page: &mut Page<W>,
        time: Option<Timestamp>,
        channel: &str,
    ) -> io::Result<Layout> {
        if let Some(l) = self.layout {
            return Ok(l);
        }
        let time_text = time.map(|t| page.times.show(t));
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
        if let Some(width) = page.width {
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
        writeln!(page.out, "{}", page.paint(BOLD, &header))?;
        Ok(l)
    }

    /// `TIME  CHANNEL  NODE  ` padded to the layout, appended to `line`;
    /// before it, for times of day, the date when it changed.
    fn push_prefix<W: Write>(
        &mut self,
        page: &Page<W>,
        line: &mut String,
        l: Layout,
        time: Option<Timestamp>,
        channel: &str,
        node: Option<NodeId>,
    ) {
        let start = line.len();
        let mut row_start = start;
        page.times.push_opt(line, time);
        // `iso_date` checked the 11 ASCII bytes the ranges below remove.
        if l.time_of_day
            && let Some(date) = line.get(start..).and_then(iso_date)
        {
            if date != self.date {
                self.date.clear();
                self.date.push_str(date);
                let mut head = String::with_capacity(16);
                head.push_str(&page.paint(BOLD, date));
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
        match page.width {
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
        // A bus event of no node (an error burst, the logging
        // controller's bus-off) shows a dash.
        let node = node.map_or("-", |n| digits.format(n));
        for _ in node.len()..4 {
            line.push(' ');
        }
        line.push_str(node);
        line.push_str("  ");
    }

    /// An NMT event's row: its tag in the code column, its text as the
    /// description.
    #[allow(clippy::too_many_arguments)]
    fn write_tagged<W: Write>(
        &mut self,
        page: &mut Page<W>,
        l: Layout,
        time: Option<Timestamp>,
        channel: &str,
        node: Option<NodeId>,
        tag: &str,
        style: Option<Style>,
        what: &str,
    ) -> io::Result<()> {
        // The event line's buffer: NMT and heartbeat rows are many too.
        let mut line = std::mem::take(&mut self.line);
        line.clear();
        self.push_prefix(page, &mut line, l, time, channel, node);
        match style {
            Some(style) if page.color => {
                line.push_str(&page.paint(style, tag));
            }
            _ => line.push_str(tag),
        }
        let column = l.description_indent();
        line.push_str(&blanks(column.saturating_sub(l.code_column() + tag.len())));
        push_description(&mut line, l, what);
        line.push('\n');
        let written = page.out.write_all(line.as_bytes());
        self.line = line;
        written
    }

    /// Under the input's events, the legend of their columns (not of one
    /// a narrow terminal went without), then the warnings said once per
    /// node, with how often each came.
    pub(super) fn write_end<W: Write>(&self, page: &mut Page<W>) -> io::Result<()> {
        match self.layout {
            None => writeln!(page.out, "no EMCY frames")?,
            Some(l) if l.transition => page.write_wrapped(
                "TR = transition: 1 first error, 2 one error reset, 3 further error, 4 all reset",
                5,
            )?,
            Some(_) => {}
        }
        self.write_repeats(page)
    }

    /// The warnings said once per node above, with how often each came.
    fn write_repeats<W: Write>(&self, page: &mut Page<W>) -> io::Result<()> {
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
        let shown = page.fit(&mut widths, &REPEATS_HEADER, &REPEATS_FIT);
        writeln!(page.out)?;
        let title = page.paint(BOLD, "Repeated warnings");
        page.write_wrapped(&format!("{title} (said once per node above)"), 0)?;
        write_row(
            &mut page.out,
            &REPEATS_HEADER,
            &widths,
            &shown,
            &REPEATS_RIGHT,
        )?;
        for row in &cells {
            write_row(&mut page.out, row, &widths, &shown, &REPEATS_RIGHT)?;
        }
        Ok(())
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
}

/// `text` in the description column: cut to the room there is (one row
/// per event) when fitting.
fn push_description(line: &mut String, l: Layout, text: &str) {
    match l.description {
        Some(room) => {
            push_cut(line, text, room);
        }
        None => line.push_str(text),
    }
}

/// A line of detail under an event (the profile's reading, a warning),
/// indented to `indent`; wrapped to the width when fitting.
fn write_detail<W: Write>(
    page: &mut Page<W>,
    indent: usize,
    text: &str,
    style: Option<Style>,
) -> io::Result<()> {
    let lines = match page.width {
        Some(width) => textwrap::wrap(text, width.saturating_sub(indent).max(8)),
        None => vec![Cow::Borrowed(text)],
    };
    for piece in lines {
        page.out.write_all(blanks(indent).as_bytes())?;
        match style {
            Some(style) if page.color => write!(
                page.out,
                "{}{piece}{}",
                style.render(),
                style.render_reset()
            )?,
            _ => page.out.write_all(piece.as_bytes())?,
        }
        page.out.write_all(b"\n")?;
    }
    Ok(())
}

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

/// `error history complete, 2 entries` (the event line).
fn history_head(h: &HistoryReport) -> String {
    let n = h.entries.len();
    format!(
        "error history {}, {n} entr{}",
        if h.complete { "complete" } else { "partial" },
        if n == 1 { "y" } else { "ies" }
    )
}

/// A health event's text, as the table's description column and the CSV
/// `description` column give it.
/// A bus event in words: "12 error frames over 0.8 s: protocol_violation
/// 10, no_ack 2 (TX errors up to 128)", "node 5 bus-off until 3.2 s".
pub(crate) fn bus_description(bus: &Bus, times: &TimeFormat) -> String {
    match bus {
        Bus::Incident(i) => format!("incident: {}", i.summary),
        Bus::SyncMissed(gap) => {
            let cycles = if gap.missed == 1 { "cycle" } else { "cycles" };
            match gap.end {
                Some(end) => format!(
                    "SYNC missed {} {cycles} (period {}): none from {} to {}",
                    gap.missed,
                    human_span(gap.period),
                    times.show_opt(gap.start.time),
                    times.show_opt(end.time)
                ),
                None => format!(
                    "SYNC stopped: none after {} (period {}), {} {cycles} to the end",
                    times.show_opt(gap.start.time),
                    human_span(gap.period),
                    gap.missed
                ),
            }
        }
        Bus::Errors(b) => {
            let over = match (b.start, b.end) {
                (Some(s), Some(e)) if b.frames > 1 => format!(" over {}", human_span(e.since(s))),
                _ => String::new(),
            };
            let kinds: Vec<String> = b
                .kinds()
                .map(|(k, n)| format!("{} {n}", k.slug()))
                .collect();
            let mut text = format!(
                "{} error frame{}{over}: {}",
                b.frames,
                if b.frames == 1 { "" } else { "s" },
                kinds.join(", ")
            );
            let counters: Vec<String> = [("TX", b.tx_errors_max), ("RX", b.rx_errors_max)]
                .iter()
                .filter_map(|(name, max)| max.map(|m| format!("{name} errors up to {m}")))
                .collect();
            if !counters.is_empty() {
                text.push_str(&format!(" ({})", counters.join(", ")));
            }
            text
        }
        Bus::BusOff(off) => {
            let who = match off.node {
                Some(n) => format!("node {n}"),
                None => "controller".to_string(),
            };
            let until = match off.end {
                Some(end) => match off.start {
                    Some(start) => format!(
                        " for {}, back at {}",
                        human_span(end.since(start)),
                        times.show(end)
                    ),
                    None => format!(", back at {}", times.show(end)),
                },
                None => ", still off at the end".to_string(),
            };
            format!("{who} bus-off{until}")
        }
        Bus::Sdo(t) => sdo_description(t),
        Bus::Lss(l) => {
            let mut text = format!(
                "LSS {}: {}",
                if l.from_master { "master" } else { "node" },
                l.lss.words()
            );
            if let Some(id) = l.identity {
                let parts: Vec<String> = [
                    ("vendor", id.vendor_id),
                    ("product", id.product_code),
                    ("revision", id.revision),
                    ("serial", id.serial),
                ]
                .iter()
                .filter_map(|(name, v)| v.map(|v| format!("{name} 0x{v:08X}")))
                .collect();
                text.push_str(&format!(" ({})", parts.join(", ")));
            }
            text
        }
    }
}

/// An SDO transfer in words: "SDO download 0x1017.0 Producer heartbeat
/// time = e803 (2 bytes, expedited): ok".
fn sdo_description(t: &SdoTransfer) -> String {
    let mut text = format!(
        "SDO {} 0x{:04X}.{}",
        t.direction.name(),
        t.object.index,
        t.object.sub
    );
    if let Some(name) = &t.name {
        text.push(' ');
        text.push_str(name);
    }
    match (&t.text, t.data) {
        (Some(s), _) => text.push_str(&format!(" = \"{s}\"")),
        (None, Some(d)) if d.whole && d.size > 0 => {
            let mut hex = Vec::new();
            crate::report::format::push_hex(&mut hex, d.shown());
            let more = if d.complete() { "" } else { "..." };
            text.push_str(&format!(" = {}{more}", String::from_utf8_lossy(&hex)));
        }
        _ => {}
    }
    let size = t
        .data
        .map(|d| d.size)
        .or(t.indicated)
        .map(|n| format!("{n} byte{}", if n == 1 { "" } else { "s" }));
    let how: Vec<String> = size
        .into_iter()
        .chain(t.protocol.map(|p| p.name().to_string()))
        .collect();
    if !how.is_empty() {
        text.push_str(&format!(" ({})", how.join(", ")));
    }
    match t.outcome {
        Outcome::Abort { code, by_server } => text.push_str(&format!(
            ": aborted by the {}, 0x{code:08X} {}",
            if by_server { "node" } else { "client" },
            t.abort_text.unwrap_or_default()
        )),
        Outcome::Unanswered => text.push_str(": unanswered"),
        Outcome::Incomplete => text.push_str(": incomplete (the client did not go on)"),
        Outcome::Ok => text.push_str(": ok"),
    }
    text
}

pub(crate) fn health_description(health: &Health, times: &TimeFormat) -> String {
    match health {
        Health::Nmt { state, via } => format!("NMT {} (via {})", state.slug(), via.slug()),
        Health::HeartbeatLost {
            last_seen,
            timeout,
            timeout_source,
            via,
            ..
        } => format!(
            "{} lost: silent since {} (timeout {}, {})",
            via.words(),
            times.show_opt(*last_seen),
            human_span(*timeout),
            timeout_source.slug()
        ),
        Health::HeartbeatBack {
            silent,
            restarted,
            via,
        } => format!(
            "{} back after {silent} s{}",
            via.words(),
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
        Health::DriveState {
            state,
            from,
            statusword,
            via,
        } => {
            let source = match via {
                DriveVia::Pdo { cob_id } => format!("PDO 0x{cob_id:03X}"),
                DriveVia::Sdo => "SDO".to_string(),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::table::TableReport;
    use crate::report::table::fit::MIN_WIDTH;

    /// The page of a report fitted to `width`, as `--width` makes it.
    fn page(width: Option<usize>) -> Page<Vec<u8>> {
        TableReport::new(Vec::new(), false, false)
            .fit_width(width)
            .page
    }

    /// The event columns at `width` for a trace with Unix times (shown as
    /// `2023-11-14T22:13:21.250000Z`, 27 columns) on `can0` (7, the
    /// header's). Full, the description starts at column 90.
    fn layout(width: Option<usize>, time: &str) -> Layout {
        let t = Timestamp::parse(time.as_bytes()).expect("a time");
        EventLines::new()
            .layout_for(&mut page(width), Some(t), "can0")
            .expect("written to memory")
    }

    /// The columns given way as `(register width, manufacturer, date on its
    /// own line, transition)` and the description's room.
    fn given_way(l: Layout) -> ((Option<usize>, bool, bool, bool), Option<usize>) {
        (
            (l.register, l.manufacturer, l.time_of_day, l.transition),
            l.description,
        )
    }

    #[test]
    fn event_columns_give_way_in_the_readme_order() {
        let unix = "1700000001.250000";
        let at = |width| given_way(layout(Some(width), unix));
        // All columns and 50 for the description.
        assert_eq!(at(140), ((Some(16), true, false, true), Some(50)));
        // The register's bit names first (its hex stays)...
        assert_eq!(at(139), ((Some(3), true, false, true), Some(62)));
        assert_eq!(at(127), ((Some(3), true, false, true), Some(50)));
        // ...then the manufacturer bytes...
        assert_eq!(at(126), ((Some(3), false, false, true), Some(65)));
        // ...then the date, on a line of its own...
        assert_eq!(at(110), ((Some(3), false, true, true), Some(60)));
        assert_eq!(at(100), ((Some(3), false, true, true), Some(50)));
        // ...then the transition...
        assert_eq!(at(99), ((Some(3), false, true, false), Some(53)));
        // ...then the register; the description takes what is left.
        assert_eq!(at(95), ((None, false, true, false), Some(54)));
        assert_eq!(at(60), ((None, false, true, false), Some(19)));
    }

    #[test]
    fn a_pipe_gets_every_column_and_the_whole_description() {
        assert_eq!(
            given_way(layout(None, "1700000001.250000")),
            ((Some(16), true, false, true), None)
        );
    }

    #[test]
    fn times_without_a_date_keep_their_column() {
        // Seconds since the start of the trace have no date to move out.
        let l = layout(Some(60), "12.500");
        assert!(!l.time_of_day);
        assert_eq!(l.register, None);
    }

    #[test]
    fn nothing_is_fitted_below_forty_columns() {
        assert_eq!(page(Some(10)).width, Some(MIN_WIDTH));
        assert_eq!(page(Some(39)).width, Some(40));
        assert_eq!(page(Some(41)).width, Some(41));
        assert_eq!(page(None).width, None);
        // At the floor the description still has its 8 columns.
        let narrowest = layout(Some(40), "1700000001.250000");
        assert_eq!(narrowest.description, Some(8));
        assert_eq!(
            given_way(layout(Some(10), "1700000001.250000")),
            given_way(narrowest)
        );
    }
}
