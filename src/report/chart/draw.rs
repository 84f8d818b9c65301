//! Drawing: one input's panel as SVG elements (title, lane backgrounds,
//! lanes with their labels, bars with tooltips, markers, the legend). Only
//! writes what layout ([`super::Panel`]), binning ([`super::bars`]) and the
//! markers ([`super::marks`]) decided; the time scale draws itself ([`super::time_scale`]).

use std::fmt::{self, Write as _};

use super::bars::{Bar, CLEARED_SLUGS, SMALL_PX};
use super::lane::{Lane, lane_key, lane_label};
use super::legend::{CodeKey, CodeKeys};
use super::marks::{Clusters, MARKS, Mark, Streamed};
use super::style::{BAR_H, CLASS_COLOURS, LANES_TOP, ROW_H, WIDTH, X0};
use super::text::{N, clip, esc, plural, short_number};
use super::time_scale::{Clock, Measure, Scale, wall_clock, write_time_scale};
use crate::analyze::{InputReport, NodeReport};
use crate::canopen::codes::{self, Class};
use crate::timeline::ClearedBy;

/// Markers of one kind closer than this are drawn as one.
const MARKER_GAP_PX: f64 = 3.0;
/// Font size of a bar's code label (`text.bl` in the style sheet).
pub(super) const LABEL_PX: f64 = 9.0;
/// Width of a character of a label as a fraction of the font size: hex
/// digits in the usual sans-serif fonts are about 0.55 em, a little more
/// keeps a label off the bar's end.
const LABEL_EM: f64 = 0.6;
/// Codes the legend names; more are counted in one item.
const LEGEND_CODES: usize = 40;
/// Characters of a code's description in the legend (its tooltip has all).
const LEGEND_TEXT: usize = 60;
/// Estimated width of a legend character (11 px sans-serif, mixed case).
const LEGEND_CHAR_PX: f64 = 6.1;

/// The width a bar needs to hold `label`, by its character count (no font
/// metrics here: the estimate errs wide so a label never spills).
pub(super) fn label_fits(label: &str, width: f64) -> bool {
    label.chars().count() as f64 * LABEL_PX * LABEL_EM + 4.0 <= width
}

/// Title line two: the time span, what the chart shows.
fn subtitle(input: &InputReport, clock: &Clock, lanes: &[Lane<'_>], streamed: &Streamed) -> String {
    let mut s = match (clock.measure, input.first_time, input.last_time) {
        (Measure::Wall, Some(a), Some(b)) => {
            let (da, ca) = wall_clock(a);
            let (db, cb) = wall_clock(b);
            let to = if da == db { cb } else { format!("{db} {cb}") };
            format!("{da} {ca} – {to} UTC ({} s)", b.since(a))
        }
        (Measure::Seconds, Some(a), Some(b)) => format!("{a} s – {b} s ({} s)", b.since(a)),
        _ => format!(
            "lines 1–{} (the trace has no timestamps)",
            input.counts.lines
        ),
    };
    let errors: u64 = lanes
        .iter()
        .flat_map(|l| &l.bars.bars)
        .map(|b| b.count)
        .sum();
    let open: u64 = lanes
        .iter()
        .flat_map(|l| &l.bars.bars)
        .map(|b| b.open)
        .sum();
    let _ = write!(
        s,
        " · {} node{} · {errors} error{}",
        lanes.len(),
        plural(lanes.len() as u64),
        plural(errors)
    );
    if open > 0 {
        let _ = write!(s, " ({open} still active)");
    }
    for (mark, n) in MARKS.iter().zip(streamed.counts) {
        if n > 0 {
            let _ = write!(
                s,
                " · {n} {}",
                match mark {
                    Mark::Reset => "reset",
                    Mark::Partial => "partial reset",
                    Mark::Boot => "boot-up",
                }
            );
            s.push_str(plural(n));
        }
    }
    let unplaced = streamed.unplaced + lanes.iter().map(|l| l.bars.unplaced).sum::<u64>();
    if unplaced > 0 {
        let _ = write!(s, " · {unplaced} without a time not drawn");
    }
    s
}

/// Writes one input's chart; returns its height.
pub(super) fn write_panel(
    out: &mut String,
    input: &InputReport,
    clock: &Clock,
    scale: Scale,
    lanes: &[Lane<'_>],
    keys: &CodeKeys,
    streamed: &Streamed,
) -> Result<f64, fmt::Error> {
    writeln!(
        out,
        "<text class=\"t1\" x=\"10\" y=\"20\">{}</text>",
        esc(&input.file)
    )?;
    writeln!(
        out,
        "<text class=\"t2\" x=\"10\" y=\"38\">{}</text>",
        esc(&subtitle(input, clock, lanes, streamed))
    )?;
    if lanes.is_empty() {
        let why = match &input.error {
            Some(e) => format!("nothing to draw: {e}"),
            None => "no EMCY or boot-up frames".to_string(),
        };
        writeln!(
            out,
            "<text class=\"none\" x=\"{}\" y=\"{}\">{}</text>",
            N(X0),
            N(LANES_TOP + 16.0),
            esc(&why)
        )?;
        return Ok(LANES_TOP + 32.0);
    }
    // The bus's strip, when the bus had anything to show, above the lanes.
    let bus_h = if streamed.bus.is_empty() { 0.0 } else { BUS_H };
    let lanes_top = LANES_TOP + bus_h;
    let lanes_h: f64 = lanes.iter().map(|l| l.height).sum();
    let time_scale_y = lanes_top + lanes_h;

    // Alternate lane backgrounds, then the grid over them, then the lanes.
    let mut y = lanes_top;
    for (i, lane) in lanes.iter().enumerate() {
        if i % 2 == 0 {
            writeln!(
                out,
                "<rect class=\"bg\" x=\"0\" y=\"{}\" width=\"{}\" height=\"{}\"/>",
                N(y),
                N(WIDTH),
                N(lane.height)
            )?;
        }
        y += lane.height;
    }
    write_time_scale(out, clock, scale, time_scale_y)?;
    write_bus_strip(out, clock, scale, streamed)?;
    let mut y = lanes_top;
    for lane in lanes {
        write_lane(out, clock, scale, lane, keys, y)?;
        y += lane.height;
    }
    write_incident_bands(out, clock, scale, streamed, time_scale_y)?;
    let incidents = !streamed.incidents.is_empty();
    let mut bus = [false; 3];
    for m in &streamed.bus {
        if let Some(i) = BUS_KEYS.iter().position(|(class, _)| *class == m.class) {
            bus[i] = true;
        }
    }
    let legend_h = write_legend(out, lanes, keys, (incidents, bus), time_scale_y + 44.0)?;
    Ok(time_scale_y + 44.0 + legend_h)
}

/// The height of the bus strip above the lanes.
const BUS_H: f64 = 16.0;

/// The bus strip's bands: CSS class and what the legend calls them.
const BUS_KEYS: [(&str, &str); 3] = [
    ("be", "error frames"),
    ("bo", "bus-off"),
    ("sg", "SYNC gap"),
];

/// The bus strip: its label and a band per burst of error frames, bus-off
/// and SYNC gap (at least 2 px; one still going at the end runs to it),
/// each with its tooltip.
fn write_bus_strip(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    streamed: &Streamed,
) -> fmt::Result {
    if streamed.bus.is_empty() {
        return Ok(());
    }
    writeln!(
        out,
        "<g class=\"bus\" transform=\"translate(0,{})\">",
        N(LANES_TOP)
    )?;
    let label = match streamed.bus_not_drawn {
        0 => "bus".to_string(),
        n => format!("bus ({n} more not drawn)"),
    };
    writeln!(
        out,
        "<text class=\"lbl2\" x=\"10\" y=\"{}\">{}</text>",
        N(BUS_H / 2.0 + 4.0),
        esc(&label)
    )?;
    for m in &streamed.bus {
        let Some(a) = clock.value(&m.start) else {
            continue;
        };
        let b = match &m.end {
            Some(end) => clock.value(end).unwrap_or(a),
            None => scale.end,
        };
        let x0 = scale.x(a);
        let x1 = scale.x(b.max(a)).max(x0 + 2.0);
        // Bursts along the top half, what they caused (a bus-off, a SYNC
        // gap) along the bottom: a bus-off spans its burst and would hide
        // it.
        let y = if m.class == "be" {
            2.0
        } else {
            BUS_H / 2.0 + 1.0
        };
        writeln!(
            out,
            "<rect class=\"{}\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"><title>{}</title></rect>",
            m.class,
            N(x0),
            N(y),
            N(x1 - x0),
            N(BUS_H / 2.0 - 3.0),
            esc(&m.title)
        )?;
    }
    out.push_str("</g>\n");
    Ok(())
}

/// Incidents as numbered bands over every lane, from the first event to
/// the last (at least 2 px), the number above the lanes and the summary in
/// the tooltip; the table and the JSON number them alike.
fn write_incident_bands(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    streamed: &Streamed,
    bottom: f64,
) -> fmt::Result {
    for (k, (start, end, summary)) in streamed.incidents.iter().enumerate() {
        let (Some(a), Some(b)) = (clock.value(start), clock.value(end)) else {
            continue;
        };
        let x0 = scale.x(a);
        let x1 = scale.x(b).max(x0 + 2.0);
        writeln!(
            out,
            "<g class=\"inc\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"><title>incident {}: {}</title></rect>\
             <text x=\"{}\" y=\"{}\">{}</text></g>",
            N(x0),
            N(LANES_TOP),
            N(x1 - x0),
            N(bottom - LANES_TOP),
            k + 1,
            esc(summary),
            N(x0 + 1.0),
            N(LANES_TOP - 3.0),
            k + 1
        )?;
    }
    Ok(())
}

fn write_lane(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    lane: &Lane<'_>,
    keys: &CodeKeys,
    y: f64,
) -> fmt::Result {
    let node = lane.node;
    let label = lane_label(node);
    writeln!(
        out,
        "<g class=\"lane\" data-lane=\"{}\" transform=\"translate(0,{})\">",
        esc(&lane_key(&node.channel, node.node)),
        N(y)
    )?;
    let mid = lane.height / 2.0;
    match &label.detail {
        None => writeln!(
            out,
            "<text class=\"lbl\" x=\"10\" y=\"{}\">{}</text>",
            N(mid + 4.0),
            esc(&clip(&label.main, 24))
        )?,
        Some(detail) => writeln!(
            out,
            "<text class=\"lbl\" x=\"10\" y=\"{}\">{}</text>\
             <text class=\"lbl2\" x=\"10\" y=\"{}\">{}</text>",
            N(mid - 1.0),
            esc(&clip(&label.main, 24)),
            N(mid + 10.0),
            esc(&clip(detail, 28))
        )?,
    }
    for shade in &lane.shades {
        // A drive state is a strip along the lane's foot, under the bars.
        let (y, height) = if shade.strip {
            (lane.height - DRIVE_STRIP_H, DRIVE_STRIP_H)
        } else {
            (0.0, lane.height)
        };
        writeln!(
            out,
            "<rect class=\"{}\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"><title>{}</title></rect>",
            shade.class,
            N(shade.x0),
            N(y),
            N(shade.x1 - shade.x0),
            N(height),
            esc(&shade.title)
        )?;
    }
    let rows = lane.bars.rows.len().max(1) as f64;
    let top = (lane.height - rows * ROW_H) / 2.0 + (ROW_H - BAR_H) / 2.0;
    for bar in &lane.bars.bars {
        write_bar(out, clock, scale, lane, keys, bar, top)?;
    }
    if let Some(marks) = &lane.marks {
        for (mark, clusters) in MARKS.iter().zip(&marks.marks) {
            write_marks(out, clock, scale, *mark, clusters, lane.height)?;
        }
    }
    out.push_str("</g>\n");
    Ok(())
}

fn write_bar(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    lane: &Lane<'_>,
    keys: &CodeKeys,
    bar: &Bar,
    top: f64,
) -> fmt::Result {
    let y = top + bar.row as f64 * ROW_H;
    let w = (bar.x1 - bar.x0).max(1.0);
    let code = bar.code();
    let key = keys.codes.get(&code);
    let mut class = match key {
        Some(k) => format!("b {}", k.css(bar.class().slug())),
        None => format!("b c-{}", bar.class().slug()),
    };
    if bar.count > 1 {
        class.push_str(" m");
    } else if bar.open > 0 {
        class.push_str(" o");
    }
    // The label the bar would carry when wide enough (the HTML page's
    // zoom labels bars as they widen): the code, and how many errors a
    // merged bar holds.
    let label = if bar.count > 1 {
        format!("0x{code:04X} ×{}", bar.count)
    } else {
        format!("0x{code:04X}")
    };
    writeln!(
        out,
        "<rect class=\"{class}\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" data-c=\"{label}\"><title>{}</title></rect>",
        N(bar.x0),
        N(y),
        N(w),
        N(BAR_H),
        esc(&bar_title(clock, scale, lane.node, bar))
    )?;
    // The whole label, else the bare code, else none.
    let short = format!("{code:04X}");
    let text = [label.as_str(), short.as_str()]
        .into_iter()
        .find(|l| label_fits(l, w));
    if let Some(text) = text {
        let white = if key.is_some_and(CodeKey::dark) {
            " w"
        } else {
            ""
        };
        writeln!(
            out,
            "<text class=\"bl{white}\" x=\"{}\" y=\"{}\">{text}</text>",
            N(bar.x0 + 2.0),
            N(y + BAR_H - 1.5)
        )?;
    }
    if bar.open > 0 {
        // The open end: a triangle past the end of the plot area.
        let x = N(bar.x1 + 1.0);
        writeln!(
            out,
            "<path class=\"oe\" d=\"M{x} {}l7 {}l-7 {}z\"><title>still active at the end of the trace</title></path>",
            N(y - 1.0),
            N(BAR_H / 2.0 + 1.0),
            N(BAR_H / 2.0 + 1.0),
        )?;
    }
    Ok(())
}

fn bar_title(clock: &Clock, scale: Scale, node: &NodeReport, bar: &Bar) -> String {
    let label = lane_label(node).main;
    let iv = &bar.first;
    if bar.count == 1 {
        let (end, duration, cleared) = match iv.end {
            Some(e) => (
                clock.at(&e),
                match (e.time, iv.start.time) {
                    (Some(b), Some(a)) if clock.measure != Measure::Lines => {
                        format!("{} s", b.since(a))
                    }
                    _ => "-".to_string(),
                },
                iv.cleared_by.map_or("-", ClearedBy::slug),
            ),
            None => (
                "still active at the end of the trace".to_string(),
                "open".to_string(),
                "-",
            ),
        };
        let lines = match iv.end {
            Some(e) => format!("lines {}–{}", iv.start.line, e.line),
            None => format!("line {}", iv.start.line),
        };
        return format!(
            "0x{:04X} {}\n{label}\nstart: {}\nend: {end}\nduration: {duration}\ncleared by: {cleared}\n{lines}",
            iv.code,
            node.describe(iv.code),
            clock.at(&iv.start),
        );
    }
    let mut s = format!(
        "{} errors merged into one bar (each shorter than {} px, about {} {} at this scale)\n{label}\n",
        bar.count,
        N(SMALL_PX),
        short_number(scale.per_px() * SMALL_PX),
        match clock.measure {
            Measure::Lines => "lines",
            _ => "s",
        }
    );
    let mut codes_sorted = bar.codes.clone();
    codes_sorted.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    for (code, n) in codes_sorted {
        let _ = writeln!(s, "0x{code:04X} ×{n} {}", node.describe(code));
    }
    if bar.other_codes > 0 {
        let _ = writeln!(s, "{} more of other codes", bar.other_codes);
    }
    let _ = write!(s, "from: {}\nto: ", clock.at(&iv.start));
    match (bar.open, bar.last_end) {
        (0, Some(e)) => s.push_str(&clock.at(&e)),
        _ => s.push_str("still active at the end of the trace"),
    }
    let cleared: Vec<String> = CLEARED_SLUGS
        .iter()
        .zip(bar.cleared)
        .filter(|(_, n)| *n > 0)
        .map(|(slug, n)| format!("{slug} ×{n}"))
        .collect();
    if !cleared.is_empty() {
        let _ = write!(s, "\ncleared by: {}", cleared.join(", "));
    }
    if bar.open > 0 {
        let _ = write!(s, "\n{} still active", bar.open);
    }
    s
}

fn write_marks(
    out: &mut String,
    clock: &Clock,
    scale: Scale,
    mark: Mark,
    clusters: &Clusters,
    height: f64,
) -> fmt::Result {
    // Markers closer than a few pixels are one marker at this scale.
    let mut merged = clusters.clone();
    merged.coarsen(scale.per_px() * MARKER_GAP_PX);
    for c in &merged.items {
        let (x_lo, x_hi) = (scale.x(c.lo), scale.x(c.hi));
        let title = if c.count == 1 {
            format!("{} at {}", mark.noun(1), clock.at(&c.first))
        } else {
            format!(
                "{} {} from {} to {} (merged: closer than {} px)",
                c.count,
                mark.noun(c.count),
                clock.at(&c.first),
                clock.at(&c.last),
                N(MARKER_GAP_PX)
            )
        };
        write!(
            out,
            "<g class=\"mk {}\"><title>{}</title>",
            mark.css(),
            esc(&title)
        )?;
        let bottom = N(height - 2.0);
        if x_hi - x_lo < MARKER_GAP_PX {
            let x = N((x_lo + x_hi) / 2.0);
            write!(
                out,
                "<line x1=\"{x}\" y1=\"2\" x2=\"{x}\" y2=\"{bottom}\"/>"
            )?;
            match mark {
                Mark::Reset | Mark::Partial => {
                    write!(out, "<circle cx=\"{x}\" cy=\"4\" r=\"3\"/>")?
                }
                Mark::Boot => write!(out, "<path d=\"M{x} 0l4 4l-4 4l-4-4z\"/>")?,
            }
        } else {
            // Many markers over a stretch: a band from the first to the last.
            let (a, b) = (N(x_lo), N(x_hi));
            write!(
                out,
                "<line x1=\"{a}\" y1=\"2\" x2=\"{a}\" y2=\"{bottom}\"/>\
                 <line x1=\"{b}\" y1=\"2\" x2=\"{b}\" y2=\"{bottom}\"/>\
                 <rect x=\"{a}\" y=\"1\" width=\"{}\" height=\"4\"/>",
                N(x_hi - x_lo)
            )?;
        }
        out.push_str("</g>\n");
    }
    Ok(())
}

/// The legend: classes drawn in this panel, then the marker kinds.
/// The lane bands the legend explains, in its order.
const SHADES: [(&str, &str); 15] = [
    ("n-initialising", "NMT initialising"),
    ("n-pre_operational", "NMT pre-operational"),
    ("n-operational", "NMT operational"),
    ("n-stopped", "NMT stopped"),
    ("out", "heartbeat lost"),
    ("fault", "axis faulted"),
    ("a-not_ready_to_switch_on", "axis not ready to switch on"),
    ("a-switch_on_disabled", "axis switch on disabled"),
    ("a-ready_to_switch_on", "axis ready to switch on"),
    ("a-switched_on", "axis switched on"),
    ("a-operation_enabled", "axis operation enabled"),
    ("a-quick_stop_active", "axis quick stop active"),
    ("a-fault_reaction_active", "axis fault reaction active"),
    ("a-fault", "axis fault"),
    ("a-unknown", "axis state unknown"),
];

/// The height of the drive state strip along a lane's foot.
const DRIVE_STRIP_H: f64 = 4.0;

fn write_legend(
    out: &mut String,
    lanes: &[Lane<'_>],
    keys: &CodeKeys,
    (incidents, bus): (bool, [bool; 3]),
    y: f64,
) -> Result<f64, fmt::Error> {
    let (mut merged, mut open) = (false, false);
    let mut marks = [false; 3];
    for lane in lanes {
        for bar in &lane.bars.bars {
            merged |= bar.count > 1;
            open |= bar.open > 0;
        }
        if let Some(m) = &lane.marks {
            for (seen, c) in marks.iter_mut().zip(&m.marks) {
                *seen |= !c.items.is_empty();
            }
        }
    }
    let y0 = y;
    let mut x = 10.0;
    let mut y = y;
    // An item: a glyph (or none), its text, and the whole text as a
    // tooltip where the text is cut.
    // `row`: start a new row (each class does, and the other keys after
    // the codes).
    let mut entry = |out: &mut String,
                     row: bool,
                     glyph: &str,
                     text: &str,
                     class: &str,
                     title: Option<&str>|
     -> fmt::Result {
        let left = if glyph.is_empty() { 0.0 } else { 16.0 };
        let w = left + text.chars().count() as f64 * LEGEND_CHAR_PX + 14.0;
        if x > 10.0 && (row || x + w > WIDTH - 10.0) {
            x = 10.0;
            y += 18.0;
        }
        // `r`: the HTML page re-flows the legend to its width.
        let r = if row { " class=\"r\"" } else { "" };
        write!(out, "<g{r} transform=\"translate({},{})\">", N(x), N(y))?;
        if let Some(t) = title {
            write!(out, "<title>{}</title>", esc(t))?;
        }
        writeln!(
            out,
            "{glyph}<text{class} x=\"{}\" y=\"9\">{}</text></g>",
            N(left),
            esc(text)
        )?;
        x += w;
        Ok(())
    };
    out.push_str("<g class=\"legend\">\n");
    // By code, grouped by class: the class's name, then each of its codes
    // in its shade of the class colour.
    let mut last_class = None;
    let listed = keys.in_legend_order();
    for (code, key) in listed.iter().take(LEGEND_CODES) {
        let class = CLASS_COLOURS
            .get(key.class)
            .map_or(codes::lookup(*code).class, |c| c.0);
        if last_class != Some(key.class) {
            last_class = Some(key.class);
            let name = match class {
                // 0x00xx other than 0x0000: an error, not a reset marker.
                Class::Reset => "00xx (not a reset)".to_string(),
                c => c.slug().replace('_', " "),
            };
            entry(out, true, "", &format!("{name}:"), " class=\"lbl\"", None)?;
        }
        let whole = key.texts.join(" | ");
        let text = format!("0x{code:04X} {}", clip(&whole, LEGEND_TEXT));
        let glyph = format!(
            "<rect class=\"b {}\" width=\"11\" height=\"{}\"/>",
            key.css(class.slug()),
            N(BAR_H)
        );
        let title = format!("0x{code:04X} {whole}");
        entry(out, false, &glyph, &text, "", Some(&title))?;
    }
    if let Some(more) = listed.len().checked_sub(LEGEND_CODES).filter(|&n| n > 0) {
        let text = format!("{more} more code{}", plural(more as u64));
        entry(out, false, "", &text, "", None)?;
    }
    // The other keys on a row of their own.
    let mut row = !listed.is_empty();
    if open {
        let glyph = format!(
            "<rect class=\"b o c-generic\" width=\"5\" height=\"{}\"/><path class=\"oe\" d=\"M6 -1l6 5.5l-6 5.5z\"/>",
            N(BAR_H)
        );
        entry(
            out,
            std::mem::take(&mut row),
            &glyph,
            "still active at end",
            "",
            None,
        )?;
    }
    if merged {
        let glyph = format!(
            "<rect class=\"b m c-generic\" width=\"11\" height=\"{}\"/>",
            N(BAR_H)
        );
        entry(
            out,
            std::mem::take(&mut row),
            &glyph,
            "merged short errors",
            "",
            None,
        )?;
    }
    for (class, text) in SHADES {
        if lanes
            .iter()
            .any(|l| l.shades.iter().any(|s| s.class == class))
        {
            let glyph = format!(
                "<rect class=\"{class}\" width=\"11\" height=\"{}\"/>",
                N(BAR_H)
            );
            entry(out, std::mem::take(&mut row), &glyph, text, "", None)?;
        }
    }
    for (mark, _) in MARKS.iter().zip(marks).filter(|(_, seen)| *seen) {
        let glyph = match mark {
            Mark::Reset | Mark::Partial => {
                "<line x1=\"5\" y1=\"-1\" x2=\"5\" y2=\"11\"/><circle cx=\"5\" cy=\"1\" r=\"3\"/>"
            }
            Mark::Boot => {
                "<line x1=\"5\" y1=\"-1\" x2=\"5\" y2=\"11\"/><path d=\"M5 -3l4 4l-4 4l-4-4z\"/>"
            }
        };
        let text = match mark {
            Mark::Reset => "reset",
            Mark::Partial => "partial reset",
            Mark::Boot => "boot-up",
        };
        let glyph = format!("<g class=\"mk {}\">{glyph}</g>", mark.css());
        entry(out, std::mem::take(&mut row), &glyph, text, "", None)?;
    }
    if incidents {
        let glyph = format!(
            "<g class=\"inc key\"><rect width=\"11\" height=\"{}\"/></g>",
            N(BAR_H)
        );
        entry(
            out,
            std::mem::take(&mut row),
            &glyph,
            "incident (numbered as in the table)",
            "",
            None,
        )?;
    }
    for ((class, text), _) in BUS_KEYS.iter().zip(bus).filter(|(_, seen)| *seen) {
        let glyph = format!(
            "<g class=\"bus\"><rect class=\"{class}\" width=\"11\" height=\"{}\"/></g>",
            N(BAR_H)
        );
        entry(out, std::mem::take(&mut row), &glyph, text, "", None)?;
    }
    out.push_str("</g>\n");
    Ok(y - y0 + 18.0)
}
