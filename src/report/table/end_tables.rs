//! The tables at the end of an input (nodes, errors seen, node health,
//! drives, repeated warnings, the bus line; the error timeline has its own
//! file) and of the run (inputs). Tables that can have a row per node are
//! written in two passes, widths then rows, so none is held.

use std::io::{self, Write};

use comfy_table::{CellAlignment, Table, presets};

use super::fit::{CHANNEL_MAX, Fit, display_width, push_cut};
use super::inventory::write_inventory;
use super::page::{BOLD, Page, write_in_two_passes};
use super::timeline::{NodeTexts, write_timeline};
use super::traffic::{period_text, shows_bus, write_bus, write_timing};
use crate::analyze::incident::Incident;
use crate::analyze::{DriveReport, HistoryReport, InputReport, NodeReport, kind_counts};
use crate::report::format::{TABLE_LIST, code_text, push_code, push_code_counts, push_codes};
use crate::report::timefmt::{SameDay, TimeFormat, human_span};
use crate::text::printable;
use crate::timeline::heartbeat::Supervision;
use crate::trace::Timestamp;

/// The end of an input, under its events' legend: the nodes, their
/// health and drives, the error timeline and the bus line.
pub(super) fn write_end_of_input<W: Write>(
    page: &mut Page<W>,
    input: &InputReport,
    incidents: &Incidents,
) -> io::Result<()> {
    if input.nodes.is_empty() {
        if !incidents.lines.is_empty() {
            writeln!(page.out)?;
            write_incidents(page, incidents)?;
        }
        write_bus_errors(page, input)?;
        write_bus(page, input)?;
        write_timing(page, input)?;
        if !input.bus_errors.is_empty() || shows_bus(input) {
            writeln!(page.out)?;
        }
        write_bus_line(page, input)?;
        return writeln!(page.out);
    }
    writeln!(page.out)?;
    write_incidents(page, incidents)?;
    write_nodes(page, input)?;
    write_inventory(page, input)?;
    write_health(page, input)?;
    write_drives(page, input)?;
    write_bus_errors(page, input)?;
    write_bus(page, input)?;
    write_timing(page, input)?;

    write_timeline(page, input)?;
    writeln!(page.out)?;
    write_bus_line(page, input)?;
    writeln!(page.out)
}

/// Incidents the section lists at most; the rest are counted.
const INCIDENTS_SHOWN: usize = 100;

/// An input's incidents as the section shows them: start, channel, summary.
#[derive(Debug, Default)]
pub(super) struct Incidents {
    lines: Vec<(Timestamp, String, String)>,
    more: u64,
}

impl Incidents {
    pub(super) fn push(&mut self, channel: &str, i: &Incident) {
        if self.lines.len() < INCIDENTS_SHOWN {
            self.lines.push((
                i.start,
                printable(channel).into_owned(),
                printable(&i.summary).into_owned(),
            ));
        } else {
            self.more += 1;
        }
    }
}

/// "Incidents": one line each, when, where, the root and what followed;
/// it opens the end of an input, the story before the tables.
pub(super) fn write_incidents<W: Write>(
    page: &mut Page<W>,
    incidents: &Incidents,
) -> io::Result<()> {
    if incidents.lines.is_empty() {
        return Ok(());
    }
    writeln!(page.out, "{}", page.paint(BOLD, "Incidents"))?;
    for (n, (start, channel, summary)) in incidents.lines.iter().enumerate() {
        let mut line = format!(
            "{:>3}. {}  {channel}  {summary}",
            n + 1,
            page.times.show(*start)
        );
        if let Some(width) = page.width {
            let mut cut = String::new();
            push_cut(&mut cut, &line, width);
            line = cut;
        }
        writeln!(page.out, "{line}")?;
    }
    if incidents.more > 0 {
        writeln!(page.out, "     ... and {} more", incidents.more)?;
    }
    writeln!(page.out)
}

/// The end of an input in the summary view: only the nodes' tables and the
/// bus line.
pub(super) fn write_summary<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    if !input.nodes.is_empty() {
        write_nodes(page, input)?;
        write_inventory(page, input)?;
        write_codes(page, input)?;
        write_health(page, input)?;
        write_drives(page, input)?;
    }
    write_bus_errors(page, input)?;
    write_bus(page, input)?;
    write_timing(page, input)?;
    if !input.bus_errors.is_empty() || shows_bus(input) {
        writeln!(page.out)?;
    }
    write_bus_line(page, input)?;
    writeln!(page.out)
}

/// The end of the run: one row per input with its counts.
pub(super) fn write_inputs<W: Write>(page: &mut Page<W>, inputs: &[InputReport]) -> io::Result<()> {
    let rows: Vec<[String; 9]> = inputs
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
                c.annotated.to_string(),
            ]
        })
        .collect();
    // Frames with notes after them come only from pastes: the column is
    // there only when some input has one.
    let mut shown = [true; 9];
    shown[8] = inputs.iter().any(|i| i.counts.annotated > 0);
    let mut widths = INPUTS_HEADER.map(str::len);
    for row in &rows {
        for (w, c) in widths.iter_mut().zip(row) {
            *w = (*w).max(display_width(c));
        }
    }
    let shown = page.fit_shown(&mut widths, &INPUTS_HEADER, &INPUTS_FIT, shown);
    writeln!(page.out, "{}", page.paint(BOLD, "Inputs"))?;
    write_comfy_table(
        &mut page.out,
        &INPUTS_HEADER,
        &rows,
        &widths,
        &shown,
        &INPUTS_RIGHT,
    )?;
    page.out.flush()
}

/// One line per node: state, errors seen with counts, time in error,
/// longest error, first and last EMCY.
fn write_nodes<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    // Two passes over the nodes, widths then rows, as for the timeline:
    // a trace can name a million nodes, and a table holding them all
    // took about 2.5 KB per node on top of the reports.
    page.times.set_origin(input.first_time);
    let mut day = SameDay::default();
    for n in &input.nodes {
        for at in [n.stats.first_emcy, n.stats.last_emcy]
            .into_iter()
            .flatten()
        {
            if let Some(t) = at.time {
                day.see(&page.times, t);
            }
        }
    }
    let (title, times) = titled("Nodes", &page.times, day);
    write_in_two_passes(
        page,
        (&title, false),
        (&NODES_HEADER, &NODES_RIGHT, &NODES_FIT),
        || input.nodes.iter(),
        |cells, n| node_cells(cells, &times, input, n),
    )
}

/// The summary's codes: per node, each code it raised, how often, and
/// what the node's profile says it is (the nodes' row gives codes
/// only). Two passes, widths then rows, as for the nodes.
fn write_codes<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
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
    write_in_two_passes(
        page,
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
fn write_health<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    let told = |n: &&NodeReport| {
        n.nmt_state.is_some() || n.heartbeat.is_some() || n.error_history.is_some()
    };
    if !input.nodes.iter().any(|n| told(&n)) {
        return Ok(());
    }
    let mut day = SameDay::default();
    for n in input.nodes.iter().filter(told) {
        let outages = n.heartbeat.iter().flat_map(|h| &h.outages);
        for o in outages.take(OUTAGES_SHOWN) {
            day.see(&page.times, o.start);
        }
    }
    let (title, times) = titled("Node health", &page.times, day);
    write_in_two_passes(
        page,
        (&title, true),
        (&HEALTH_HEADER, &HEALTH_RIGHT, &HEALTH_FIT),
        || input.nodes.iter().filter(told),
        |cells, n| health_cells(cells, &times, n),
    )
}

/// A section's title and the times it shows: when they all fall on one
/// day, the title says it (`Nodes (2023-11-14)`) and the times leave it
/// out, so a date is not repeated on every row of a narrow terminal.
fn titled(title: &str, times: &TimeFormat, day: SameDay) -> (String, TimeFormat) {
    let mut times = times.clone();
    match day.day(&times) {
        Some(day) => {
            times.without_date = true;
            (format!("{title} ({day})"), times)
        }
        None => (title.to_string(), times),
    }
}

/// The CiA 402 drives (none: no section): state at the end,
/// faults, where the mapping came from, and the summary's sentence.
/// Drives are few: one comfy table.
fn write_drives<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    let drives: Vec<(&NodeReport, &DriveReport)> = input
        .nodes
        .iter()
        .filter_map(|n| n.drive.as_deref().map(|a| (n, a)))
        .collect();
    if drives.is_empty() {
        return Ok(());
    }
    let rows: Vec<[String; 7]> = drives
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
    let mut widths = DRIVES_HEADER.map(str::len);
    let mut said = [false; 7];
    for row in &rows {
        for (w, c) in widths.iter_mut().zip(row) {
            *w = (*w).max(display_width(c));
        }
        for (s, c) in said.iter_mut().zip(row) {
            *s |= c != "-";
        }
    }
    let shown = page.fit_shown(&mut widths, &DRIVES_HEADER, &DRIVES_FIT, said);
    writeln!(page.out)?;
    writeln!(page.out, "{}", page.paint(BOLD, "Drive axes (CiA 402)"))?;
    write_comfy_table(
        &mut page.out,
        &DRIVES_HEADER,
        &rows,
        &widths,
        &shown,
        &DRIVES_RIGHT,
    )
}

/// The error frames per channel (none: no section): how many, in how many
/// bursts, by kind, the highest counters, and the bus-offs with who went
/// off. Channels are few: one comfy table.
fn write_bus_errors<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    if input.bus_errors.is_empty() {
        return Ok(());
    }
    let rows: Vec<[String; 6]> = input
        .bus_errors
        .iter()
        .map(|c| {
            let kinds: Vec<String> = kind_counts(&c.kinds)
                .map(|(k, n)| format!("{} {n}", k.words()))
                .collect();
            let counters = match (c.tx_errors_max, c.rx_errors_max) {
                (None, None) => "-".to_string(),
                (tx, rx) => format!(
                    "{}/{}",
                    tx.map_or("-".to_string(), |v| v.to_string()),
                    rx.map_or("-".to_string(), |v| v.to_string())
                ),
            };
            let mut offs: Vec<String> = c
                .bus_offs
                .iter()
                .map(|b| match b.node {
                    Some(n) => format!("node {n}"),
                    None => "controller".to_string(),
                })
                .collect();
            if c.bus_off_count > c.bus_offs.len() as u64 {
                offs.push(format!(
                    "{} more",
                    c.bus_off_count - c.bus_offs.len() as u64
                ));
            }
            [
                printable(&c.channel).into_owned(),
                c.frames.to_string(),
                c.bursts.to_string(),
                kinds.join(", "),
                counters,
                if offs.is_empty() {
                    "-".to_string()
                } else {
                    offs.join(", ")
                },
            ]
        })
        .collect();
    let mut widths = BUS_ERRORS_HEADER.map(str::len);
    let mut said = [false; 6];
    for row in &rows {
        for (w, c) in widths.iter_mut().zip(row) {
            *w = (*w).max(display_width(c));
        }
        for (s, c) in said.iter_mut().zip(row) {
            *s |= c != "-";
        }
    }
    let shown = page.fit_shown(&mut widths, &BUS_ERRORS_HEADER, &BUS_ERRORS_FIT, said);
    writeln!(page.out)?;
    writeln!(page.out, "{}", page.paint(BOLD, "Bus errors"))?;
    write_comfy_table(
        &mut page.out,
        &BUS_ERRORS_HEADER,
        &rows,
        &widths,
        &shown,
        &BUS_ERRORS_RIGHT,
    )
}

/// The bus-level line: frames, EMCY rate, nodes with errors.
fn write_bus_line<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    let c = &input.counts;
    let span = match (input.first_time, input.last_time) {
        (Some(first), Some(last)) => format!(" over {}", human_span(last.since(first))),
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
    // Notes pasted after frames were read past: said, so the count of
    // frames is not a surprise.
    let frames = match c.annotated {
        0 => frames,
        n => format!("{frames} ({n} annotated)"),
    };
    // Said only when error frames came: other traces read as before.
    let errors: u64 = input.bus_errors.iter().map(|b| b.frames).sum();
    let bursts: u64 = input.bus_errors.iter().map(|b| b.bursts).sum();
    let offs: u64 = input.bus_errors.iter().map(|b| b.bus_off_count).sum();
    let plural = |n: u64, one: &str, many: &str| {
        if n == 1 {
            format!("1 {one}")
        } else {
            format!("{n} {many}")
        }
    };
    let frames = match (errors, offs) {
        (0, _) => frames,
        (e, o) => format!(
            "{frames}, {} in {}{}",
            plural(e, "error frame", "error frames"),
            plural(bursts, "burst", "bursts"),
            match o {
                0 => String::new(),
                o => format!(", {}", plural(o, "bus-off", "bus-offs")),
            }
        ),
    };
    // The TIME producer's clock against the trace's, when it sent any.
    let frames = match &input.time_producer {
        Some(t) => match t.last_offset {
            Some(offset) => format!(
                "{frames}, {} TIME stamps (producer clock {}{} from the trace's)",
                t.frames,
                if offset.is_negative() { "" } else { "+" },
                human_span(offset)
            ),
            None => format!("{frames}, {} TIME stamps", t.frames),
        },
        None => frames,
    };
    // SYNC and the load, when one channel has them (the Bus table says
    // each channel's).
    let frames = match input.channels.as_slice() {
        [one] => {
            let mut frames = frames;
            if let Some(sync) = one
                .ids
                .iter()
                .find(|i| i.service == "sync" && i.period.is_some())
            {
                frames.push_str(&format!(", SYNC every {}", period_text(sync)));
                if let Some(n) = sync.missed.filter(|n| *n > 0) {
                    frames.push_str(&format!(" ({})", plural(n, "gap", "gaps")));
                }
            }
            if let Some(l) = &one.load {
                frames.push_str(&format!(
                    ", load {:.1}% (peak {:.1}%)",
                    l.mean_percent, l.peak_percent
                ));
            }
            frames
        }
        _ => frames,
    };
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
    page.write_wrapped(&line, 5)?;
    // Ids the master addressed that never answered are no nodes: one line
    // says them all, instead of a row each.
    if !input.nmt_unanswered.is_empty() {
        let said: Vec<String> = input.nmt_unanswered.iter().map(|u| u.sentence()).collect();
        page.write_wrapped(&format!("unanswered: {}", said.join("; ")), 12)?;
    }
    Ok(())
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
    flex: &[
        (3, 40, 12),
        (4, 40, 10),
        (5, 40, 12),
        (2, 40, 15),
        (0, CHANNEL_MAX, 7),
    ],
};

/// Fills the cells of one node health row; returns their display widths.
fn health_cells(cells: &mut [String; 6], times: &TimeFormat, n: &NodeReport) -> [usize; 6] {
    let [channel, node, nmt, heartbeat, outages, history] = cells;
    *channel = printable(&n.channel).into_owned();
    *node = n.node.to_string();
    *nmt = nmt_text(n);
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

/// The NMT state the node said last, and a commanded state it did not
/// confirm: `pre_operational (operational commanded)`.
fn nmt_text(n: &NodeReport) -> String {
    let said = n.nmt_state.map_or("-", |s| s.slug());
    match n.nmt_commanded {
        Some(asked) => format!("{said} ({} commanded)", asked.slug()),
        None => said.to_string(),
    }
}

/// `lost 1x, silent at end, period 1.44 s (configured 1.4 s: drifts),
/// timeout 2.1 s (producer)`: what happened first, then the supervision's
/// settings, so a cell cut to a terminal's width keeps the outcome. A
/// guarded node's counts its unanswered requests and toggle errors with
/// the outcome and says `guarding 100 ms x 3` with the settings.
fn heartbeat_text(n: &NodeReport) -> String {
    let Some(h) = &n.heartbeat else {
        return "-".to_string();
    };
    let mut parts = Vec::new();
    parts.push(if h.lost == 0 {
        "never lost".to_string()
    } else {
        format!("lost {}x", h.lost)
    });
    if h.silent_at_end {
        parts.push("silent at end".to_string());
    }
    if let Some(g) = &h.guarding {
        let c = g.counts;
        if c.unanswered > 0 {
            parts.push(format!("{} unanswered", c.unanswered));
        }
        match c.toggle_errors {
            0 => {}
            1 => parts.push("1 toggle error".to_string()),
            e => parts.push(format!("{e} toggle errors")),
        }
    }
    if let Some(g) = &h.guarding {
        let mut text = "guarding".to_string();
        if h.via == Supervision::Guarding
            && let Some(guard) = h.configured_period
        {
            text.push_str(&format!(" {}", human_span(guard)));
            if let Some(f) = g.life_time_factor {
                text.push_str(&format!(" x {f}"));
            }
        }
        parts.push(text);
    }
    if let Some(p) = h.period {
        let mut text = format!("period {}", human_span(p));
        if let Some(c) = h.configured_period
            && h.drifts
        {
            text.push_str(&format!(" (configured {}: drifts)", human_span(c)));
        }
        parts.push(text);
    }
    match h.timeout {
        Some((t, source)) => parts.push(format!("timeout {} ({})", human_span(t), source.slug())),
        None => parts.push("no timeout known".to_string()),
    }
    parts.join(", ")
}

const CODES_HEADER: [&str; 5] = ["CHANNEL", "NODE", "CODE", "TIMES", "DESCRIPTION"];

const CODES_RIGHT: [bool; 5] = [false, true, false, true, false];

const CODES_FIT: Fit = Fit {
    drop: &[],
    flex: &[(4, usize::MAX, 12), (0, CHANNEL_MAX, 7)],
};

/// Outages a node health cell lists; the rest are counted.
const OUTAGES_SHOWN: usize = 3;

/// The first outages, each `848 ms from START` (one still open at the end:
/// `open since START`), then how many more: the duration first, as
/// it is what a cut cell must keep, and no end time, as start and
/// duration give it.
fn outages_text(times: &TimeFormat, n: &NodeReport) -> String {
    const SHOWN: usize = OUTAGES_SHOWN;
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
        .map(|o| match o.duration() {
            Some(d) => format!("{} from {}", human_span(d), times.show(o.start)),
            None => format!("open since {}", times.show(o.start)),
        })
        .collect();
    let more = h.lost.saturating_sub(SHOWN as u64);
    if more > 0 {
        items.push(format!("+{more} more"));
    }
    items.join(", ")
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
    // Durations with their unit, to the millisecond (JSON keeps the
    // trace's digits): `1963.059 s` says what `1963.058675` did not.
    match n.time_in_error(input.last_time) {
        Some(span) => in_error.push_str(&human_span(span)),
        None => in_error.push('-'),
    }
    match n.stats.longest {
        Some((code, span)) => {
            push_code(longest, code);
            longest.push(' ');
            longest.push_str(&human_span(span));
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

const DRIVES_HEADER: [&str; 7] = [
    "CHANNEL",
    "NODE",
    "AXIS AT END",
    "FAULTS",
    "RESETS",
    "MAPPING",
    "SUMMARY",
];

const DRIVES_RIGHT: [bool; 7] = [false, true, false, true, true, false, false];

/// The summary sentence says the faults and the state at the end again.
const DRIVES_FIT: Fit = Fit {
    drop: &[5, 4, 3],
    flex: &[(6, 60, 20), (0, CHANNEL_MAX, 7)],
};

const BUS_ERRORS_HEADER: [&str; 6] = [
    "CHANNEL",
    "ERROR FRAMES",
    "BURSTS",
    "KINDS",
    "TX/RX MAX",
    "BUS-OFF",
];

const BUS_ERRORS_RIGHT: [bool; 6] = [false, true, true, false, true, false];

/// The kinds go first when narrow: the count and the bus-offs say most.
const BUS_ERRORS_FIT: Fit = Fit {
    drop: &[4, 2, 3],
    flex: &[(3, 60, 20), (0, CHANNEL_MAX, 7)],
};

const INPUTS_HEADER: [&str; 9] = [
    "FILE",
    "FORMAT",
    "LINES",
    "FRAMES",
    "EMCY",
    "BOOT",
    "SKIPPED",
    "MALFORMED",
    "ANNOTATED",
];

const INPUTS_RIGHT: [bool; 9] = [false, false, true, true, true, true, true, true, true];

const INPUTS_FIT: Fit = Fit {
    drop: &[8, 5, 6, 2],
    flex: &[(0, 60, 12)],
};

/// A small table (one row per input) laid out by comfy-table, the
/// project's table crate: the shown columns, cells cut to the widths a
/// terminal left them (see [`super::fit::fit_columns`]), two blanks between columns and
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
