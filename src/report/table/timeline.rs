//! The error timeline at the end of an input: one row per error of every
//! node, start to end. A trace can hold millions of errors, so the table
//! is written in two passes over the history (widths, then rows) and no
//! row is kept; the first pass measures without writing. The nodes' code
//! descriptions, measured once per node ([`NodeTexts`]), serve the errors
//! seen table too.

use std::borrow::Cow;
use std::io::{self, Write};

use super::fit::{CHANNEL_MAX, Fit, display_width, push_row, write_row};
use super::page::{BOLD, Page};
use crate::analyze::{InputReport, NodeReport};
use crate::report::format::push_code;
use crate::report::timefmt::{SameDay, TimeFormat, human_span};
use crate::text::printable;
use crate::timeline::Interval;

/// The error timeline under its title; nothing when no node erred.
pub(super) fn write_timeline<W: Write>(page: &mut Page<W>, input: &InputReport) -> io::Result<()> {
    let mut times = page.times.clone();
    let Some(measured) = timeline_widths(input, &times)? else {
        return Ok(());
    };
    // All on one day: the title says it once and the rows leave it out.
    let (mut widths, title) = match measured.day.day(&times) {
        Some(day) => {
            times.without_date = true;
            (measured.without_date, format!("Error timeline ({day})"))
        }
        None => (measured.dated, "Error timeline".to_string()),
    };
    let shown = page.fit(&mut widths, &TIMELINE_HEADER, &TIMELINE_FIT);
    writeln!(page.out)?;
    writeln!(page.out, "{}", page.paint(BOLD, &title))?;
    write_row(
        &mut page.out,
        &TIMELINE_HEADER,
        &widths,
        &shown,
        &TIMELINE_RIGHT,
    )?;
    let out = &mut page.out;
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
            duration.push_str(&human_span(e.since(s)));
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

/// The timeline's column widths, with the times' dates and without them,
/// and whether all its times fall on one day: measured in one pass, as
/// the day decides which widths hold.
struct Measured {
    dated: [usize; 8],
    without_date: [usize; 8],
    day: SameDay,
}

/// The timeline's column widths (`None`: no rows), measured without
/// writing the rows: the first of two passes over millions of errors, it
/// cost as much as writing them.
fn timeline_widths(input: &InputReport, times: &TimeFormat) -> io::Result<Option<Measured>> {
    let mut widths = TIMELINE_HEADER.map(str::len);
    let mut without_date = widths;
    let mut short = times.clone();
    short.without_date = true;
    let mut day = SameDay::default();
    let mut any = false;
    let mut merge = input.history.merge();
    for n in &input.nodes {
        let texts = NodeTexts::of(n);
        let channel = display_width(&printable(&n.channel));
        let node = itoa::Buffer::new().format(n.node).len();
        for iv in merge.node_errors(&n.channel, n.node) {
            any = true;
            let end_time = iv.end.and_then(|e| e.time);
            let line_width = |line: u64| 5 + itoa::Buffer::new().format(line).len();
            let (start, short_start) = match iv.start.time {
                Some(t) => {
                    day.see(times, t);
                    (times.width(t), short.width(t))
                }
                None => (line_width(iv.start.line), line_width(iv.start.line)),
            };
            let (end, short_end, duration) = match (iv.end, iv.start.time, end_time) {
                (None, _, _) => ("active".len(), "active".len(), 1),
                (Some(_), Some(s), Some(e)) => {
                    day.see(times, e);
                    (times.width(e), short.width(e), human_span(e.since(s)).len())
                }
                (Some(e), _, _) => (line_width(e.line), line_width(e.line), 1),
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
            let mut row = row;
            row[4] = short_start;
            row[5] = short_end;
            for (w, c) in without_date.iter_mut().zip(row) {
                *w = (*w).max(c);
            }
        }
    }
    let measured = Measured {
        dated: widths,
        without_date,
        day,
    };
    merge.take_error().map_or(Ok(any.then_some(measured)), Err)
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

/// A node's code descriptions with their display widths, measured once per
/// node (its timeline can have millions of rows; descriptions are rarely
/// ASCII, so measuring is not free).
pub(super) struct NodeTexts<'n>(Vec<(u16, Cow<'n, str>, usize)>);

impl<'n> NodeTexts<'n> {
    pub(super) fn of(node: &'n NodeReport) -> Self {
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
    pub(super) fn get(&self, code: u16) -> (&str, usize) {
        match self.0.binary_search_by_key(&code, |(c, _, _)| *c) {
            Ok(i) => self.0.get(i).map_or(("", 0), |(_, t, w)| (&**t, *w)),
            Err(_) => ("", 0),
        }
    }
}
