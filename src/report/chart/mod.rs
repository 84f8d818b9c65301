//! The timeline chart shared by `--format svg` and `--format html`: one lane
//! per (channel, node), error intervals as bars coloured by class, resets and
//! boot-ups as markers, a time axis, a legend.
//!
//! Plain SVG text, not a plotting crate. What the chart needs is a `<title>`
//! tooltip on every bar, CSS classes instead of repeated style attributes
//! (that is what keeps a file with thousands of bars small), exact control of
//! number formatting (golden tests compare bytes) and escaping of
//! trace-controlled text. plotters' SVG backend gives none of the first three
//! (every element carries inline styles, no child elements for tooltips) and
//! brings a font stack for text measurement we do not need; the chart is a
//! few rectangles and lines, so writing them directly is less code than
//! adapting a backend.
//!
//! Memory stays bounded by pixels, not by the trace: markers (resets, partial
//! resets, boot-ups) are coalesced while they stream in
//! ([`marks::Clusters`]), and the error intervals are read once from the
//! input's history at the end and folded into at most a few thousand bars
//! per lane ([`bars::Bars`]); intervals narrower than [`bars::SMALL_PX`]
//! that follow each other within a pixel become one bar whose tooltip says
//! how many errors it merges.
//!
//! The parts, one concern each, each importing only those above it in
//! this list: [`style`] (geometry and CSS), [`text`] (escaping and number
//! formatting), [`time_scale`] (the time axis, its scale from values to
//! pixels, ticks and calendar), [`marks`] (markers as they stream in),
//! [`bars`] (intervals binned into bars), [`lane`] (a lane: its bars,
//! markers, bands and label), [`drive`] (a CiA 402 drive's bands),
//! [`legend`] (the codes' colours), [`draw`] (the SVG elements). This file
//! is the surface `svg.rs` and `html.rs` use: the [`Collector`] and the
//! [`Panel`] it lays out; it imports the parts and none imports it.

mod bars;
mod draw;
mod drive;
mod lane;
mod legend;
mod marks;
mod style;
mod text;
mod time_scale;

use std::collections::{BTreeMap, BTreeSet};
use std::io;

use crate::analyze::{BootEvent, Bus, BusEvent, EmcyEvent, Health, HealthEvent, InputReport};
use crate::canopen::NodeId;
use crate::canopen::nmt::NmtState;
use crate::timeline::At;
use crate::timeline::drive::DriveState;
use crate::trace::Format;

use bars::Bars;
use draw::write_panel;
use lane::{Lane, lane_label, shades};
use legend::CodeKeys;
use marks::{BusMark, Mark, Streamed};
use style::{LANE_MIN_H, ROW_H, X0, X1};
use time_scale::{Measure, Scale};

pub(super) use lane::lane_key;
pub(super) use style::{WIDTH, style_sheet};
pub(super) use text::{N, esc};
pub(super) use time_scale::Clock;

/// Room right of the last frame, as a fraction of the span.
const END_ROOM: f64 = 0.03;
/// Times from this Unix second on (1973) are wall-clock times.
const UNIX_FROM: u64 = 100_000_000;

/// NMT state changes a lane keeps for its shading; later ones are not
/// drawn (a node that flaps that often is one grey band at any zoom).
const MAX_NMT_CHANGES: usize = 1024;

/// Collects one input at a time and lays it out as a [`Panel`].
#[derive(Debug, Default)]
pub(super) struct Collector {
    current: Streamed,
    /// Per lane, the NMT state changes in trace order.
    nmt: BTreeMap<(String, NodeId), Vec<(At, NmtState)>>,
    /// Per lane, the CiA 402 drive state changes in trace order.
    drive: BTreeMap<(String, NodeId), Vec<(At, DriveState)>>,
}

impl Collector {
    pub(super) fn begin_input(&mut self) {
        self.current = Streamed::default();
        self.nmt.clear();
        self.drive.clear();
    }

    /// NMT and drive state changes shade the lane; outages and faults
    /// come from the report.
    pub(super) fn health(&mut self, ev: &HealthEvent<'_>) {
        let at = At {
            time: ev.time,
            line: ev.line,
        };
        let lane = || (ev.channel.to_string(), ev.node);
        match ev.health {
            Health::Nmt { state, .. } => {
                push_change(self.nmt.entry(lane()).or_default(), at, *state)
            }
            Health::DriveState { state, .. } => {
                push_change(self.drive.entry(lane()).or_default(), at, *state)
            }
            _ => {}
        }
    }

    pub(super) fn emcy(&mut self, ev: &EmcyEvent<'_>) {
        if !ev.emcy.is_reset() {
            // Errors are drawn from the history, which has their ends; the
            // event only fixes whether the trace is timed.
            self.current.timed.get_or_insert(ev.time.is_some());
            if let (Some(t), None) = (ev.time, self.current.origin) {
                self.current.origin = Some(t);
            }
            return;
        }
        let mark = if ev.emcy.register.0 == 0 {
            Mark::Reset
        } else {
            Mark::Partial
        };
        self.current
            .mark(ev.channel, ev.node, ev.time, ev.line, mark);
    }

    /// An incident becomes a numbered band over the lanes; error bursts,
    /// bus-offs and SYNC gaps bands in the bus strip above them.
    pub(super) fn bus(&mut self, ev: &BusEvent<'_>) {
        let at = |time| At {
            time,
            line: ev.line,
        };
        let mark = match ev.bus {
            Bus::Errors(b) => Some(BusMark {
                class: "be",
                start: at(b.start),
                end: Some(at(b.end)),
                title: format!(
                    "{}: {} error frame{}",
                    ev.channel,
                    b.frames,
                    if b.frames == 1 { "" } else { "s" }
                ),
            }),
            Bus::BusOff(off) => Some(BusMark {
                class: "bo",
                start: at(off.start),
                end: off.end.map(|t| at(Some(t))),
                title: match off.node {
                    Some(n) => format!("{}: node {n} bus-off", ev.channel),
                    None => format!("{}: the logging controller bus-off", ev.channel),
                },
            }),
            Bus::SyncMissed(g) => Some(BusMark {
                class: "sg",
                start: g.start,
                end: g.end,
                title: format!(
                    "{}: SYNC missed {} cycle{}",
                    ev.channel,
                    g.missed,
                    if g.missed == 1 { "" } else { "s" }
                ),
            }),
            Bus::Lss(_) | Bus::Incident(_) | Bus::Sdo(_) => None,
        };
        if let Some(mark) = mark {
            let c = &mut self.current;
            if c.bus.len() < marks::MAX_BUS_MARKS {
                c.bus.push(mark);
            } else {
                c.bus_not_drawn += 1;
            }
            return;
        }
        let Bus::Incident(i) = ev.bus else { return };
        let incidents = &mut self.current.incidents;
        if incidents.len() >= marks::MAX_INCIDENT_BANDS {
            return;
        }
        let last = i.events.iter().map(|e| e.line).max().unwrap_or(ev.line);
        incidents.push((
            At {
                time: Some(i.start),
                line: ev.line,
            },
            At {
                time: Some(i.end),
                line: last,
            },
            i.summary.clone(),
        ));
    }

    pub(super) fn boot(&mut self, ev: &BootEvent<'_>) {
        self.current
            .mark(ev.channel, ev.node, ev.time, ev.line, Mark::Boot);
    }

    /// Lays out the input that just ended.
    pub(super) fn end_input(&mut self, input: &InputReport) -> io::Result<Panel> {
        let streamed = std::mem::take(&mut self.current);
        let changes = Changes {
            nmt: std::mem::take(&mut self.nmt),
            drive: std::mem::take(&mut self.drive),
        };
        Panel::build(input, streamed, changes)
    }
}

/// A lane's state changes, up to [`MAX_NMT_CHANGES`].
fn push_change<S>(changes: &mut Vec<(At, S)>, at: At, state: S) {
    if changes.len() < MAX_NMT_CHANGES {
        changes.push((at, state));
    }
}

/// The state changes an input's lanes are shaded by.
struct Changes {
    nmt: BTreeMap<(String, NodeId), Vec<(At, NmtState)>>,
    drive: BTreeMap<(String, NodeId), Vec<(At, DriveState)>>,
}

/// One input laid out: the SVG fragment (without `<svg>` and style), its
/// height, and the clock its times are shown with. `pub(crate)` only because
/// `svg::document`, which takes panels, is.
pub(in crate::report) struct Panel {
    pub(super) svg: String,
    pub(super) height: f64,
    pub(super) clock: Clock,
    /// `(key, label)` per lane, for the HTML filter.
    pub(super) lanes: Vec<(String, String)>,
    /// The `(class, shade)` colours its codes use beyond the class colours
    /// (the document's style sheet has a rule for each).
    pub(super) shades: BTreeSet<(usize, usize)>,
    /// A lane has a CiA 402 drive state strip (the style sheet then has
    /// their fills).
    pub(super) drives: bool,
    /// It has a bus strip (the style sheet then has its fills).
    pub(super) bus: bool,
    /// The attributes of the panel's `<g>` that let the HTML page re-lay
    /// the time axis (fill the window, zoom, pan): the plot's edges in px,
    /// the axis values at them, what the axis measures and its origin.
    pub(super) view: String,
}

impl Panel {
    fn build(
        input: &InputReport,
        mut streamed: Streamed,
        mut changes: Changes,
    ) -> io::Result<Panel> {
        let timed = streamed.timed.unwrap_or(input.first_time.is_some());
        let origin = input.first_time.or(streamed.origin);
        let wall = matches!(
            input.format,
            Some(
                Format::CandumpLog
                    | Format::CandumpScreen
                    | Format::Pcap
                    | Format::Pcapng
                    | Format::Busmaster
                    | Format::Mf4
            )
        ) && origin.is_some_and(|t| t.secs() >= UNIX_FROM);
        let measure = match (timed, wall) {
            (false, _) => Measure::Lines,
            (true, true) => Measure::Wall,
            (true, false) => Measure::Seconds,
        };
        let one_day = match (input.first_time, input.last_time) {
            (Some(a), Some(b)) => a.secs() / 86_400 == b.secs() / 86_400,
            _ => true,
        };
        let clock = Clock {
            measure,
            origin,
            one_day,
        };
        // Streamed marker values are relative to the first event's time;
        // the axis is relative to the input's first frame.
        let shift = match (streamed.origin, origin) {
            (Some(s), Some(o)) if timed => s.since(o).as_f64(),
            _ => 0.0,
        };
        for nodes in streamed.lanes.values_mut() {
            for lane in nodes.values_mut() {
                for c in lane.marks.iter_mut().flat_map(|m| m.items.iter_mut()) {
                    c.lo += shift;
                    c.hi += shift;
                }
            }
        }
        let (mut lo, mut hi): (f64, f64) = match measure {
            Measure::Lines => (1.0, input.counts.lines.max(1) as f64),
            _ => (
                0.0,
                match (input.last_time, origin) {
                    (Some(l), Some(o)) => l.since(o).as_f64(),
                    _ => 0.0,
                },
            ),
        };
        if let (Some(a), Some(b)) = (streamed.lo, streamed.hi) {
            lo = lo.min(a + shift);
            hi = hi.max(b + shift);
        }
        // An empty span (one frame, or no times): one unit wide.
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            hi = lo + 1.0;
        }
        // Room right of the last frame, so an error still active there
        // visibly runs on to the edge.
        let scale = Scale {
            lo,
            hi: hi + (hi - lo) * END_ROOM,
            end: hi,
        };

        let mut lanes = Vec::with_capacity(input.nodes.len());
        let mut merge = input.history.merge();
        for node in &input.nodes {
            let mut bars = Bars::default();
            for iv in merge.node_errors(&node.channel, node.node) {
                let start = clock.value(&iv.start);
                let end = match iv.end {
                    Some(e) => clock.value(&e),
                    None => Some(scale.hi),
                };
                let (Some(s), Some(e)) = (start, end) else {
                    bars.unplaced += 1;
                    continue;
                };
                let (x0, x1) = (scale.x(s), scale.x(e.max(s)));
                bars.push(iv, x0, x1);
            }
            let marks = streamed
                .lanes
                .get_mut(node.channel.as_str())
                .and_then(|n| n.remove(&node.node));
            let rows = bars.rows.len().max(1) as f64;
            let lane = (node.channel.clone(), node.node);
            let nmt = changes.nmt.remove(&lane).unwrap_or_default();
            let drive = changes.drive.remove(&lane).unwrap_or_default();
            lanes.push(Lane {
                node,
                bars,
                marks,
                shades: {
                    let mut s = shades(&clock, scale, node, &nmt);
                    s.extend(drive::fault_shades(&clock, scale, node));
                    s.extend(drive::drive_shades(&clock, scale, &drive));
                    s
                },
                height: (rows * ROW_H + 10.0).max(LANE_MIN_H),
            });
        }
        if let Some(e) = merge.take_error() {
            return Err(e);
        }
        let keys = CodeKeys::of(&lanes);
        let view = format!(
            " data-x0=\"{}\" data-x1=\"{}\" data-lo=\"{}\" data-hi=\"{}\" data-axis=\"{}\" data-base=\"{}\" data-oneday=\"{}\"",
            N(X0),
            N(X1),
            scale.lo,
            scale.hi,
            measure.slug(),
            clock.base(),
            u8::from(one_day)
        );
        let bus = !streamed.bus.is_empty();
        let mut svg = String::new();
        let height = write_panel(&mut svg, input, &clock, scale, &lanes, &keys, &streamed)
            .map_err(|_| io::Error::other("formatting the chart failed"))?;
        let drives = lanes
            .iter()
            .any(|l| l.shades.iter().any(|s| s.strip || s.class == "fault"));
        let lanes = lanes
            .iter()
            .map(|l| {
                (
                    lane_key(&l.node.channel, l.node.node),
                    lane_label(l.node).main,
                )
            })
            .collect();
        Ok(Panel {
            svg,
            height,
            clock,
            lanes,
            shades: keys.shades(),
            drives,
            bus,
            view,
        })
    }
}
