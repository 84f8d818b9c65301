//! A lane, one (channel, node) of an input: what is drawn in it (bars,
//! markers, bands), its label and its key in the HTML filter, and the bands
//! of its NMT states and heartbeat outages (the drive's are [`super::drive`]'s).

use super::bars::Bars;
use super::marks::LaneMarks;
use super::time_scale::{Clock, Scale};
use crate::analyze::NodeReport;
use crate::canopen::NodeId;
use crate::canopen::nmt::NmtState;
use crate::timeline::At;

/// One (channel, node) of an input, laid out: its bars, markers and bands.
pub(super) struct Lane<'a> {
    pub(super) node: &'a NodeReport,
    pub(super) bars: Bars,
    pub(super) marks: Option<LaneMarks>,
    /// NMT states and heartbeat outages, drawn under the bars.
    pub(super) shades: Vec<Shade>,
    pub(super) height: f64,
}

/// A band across a lane: an NMT state, or a heartbeat outage.
pub(super) struct Shade {
    pub(super) x0: f64,
    pub(super) x1: f64,
    /// The CSS class (`n-operational`, `out`, `a-fault`).
    pub(super) class: &'static str,
    pub(super) title: String,
    /// A strip along the lane's foot (the drive's state) rather than
    /// the lane's whole height (NMT state, outages, faults).
    pub(super) strip: bool,
}

/// The CSS class of an NMT state's band.
fn nmt_class(state: NmtState) -> &'static str {
    match state {
        NmtState::Initialising => "n-initialising",
        NmtState::PreOperational => "n-pre_operational",
        NmtState::Operational => "n-operational",
        NmtState::Stopped => "n-stopped",
    }
}

/// A lane's bands: each NMT state from its change to the next (the last to
/// the end of the trace), then each heartbeat outage over them.
pub(super) fn shades(
    clock: &Clock,
    scale: Scale,
    node: &NodeReport,
    nmt: &[(At, NmtState)],
) -> Vec<Shade> {
    let mut out = Vec::new();
    let end = scale.x(scale.end);
    for (i, (at, state)) in nmt.iter().enumerate() {
        let Some(v) = clock.value(at) else { continue };
        let x1 = nmt
            .get(i + 1)
            .and_then(|(next, _)| clock.value(next))
            .map_or(end, |n| scale.x(n));
        let x0 = scale.x(v);
        if x1 > x0 {
            out.push(Shade {
                x0,
                x1,
                class: nmt_class(*state),
                title: format!("NMT {} from {}", state.slug(), clock.at(at)),
                strip: false,
            });
        }
    }
    if let Some(hb) = &node.heartbeat {
        for o in &hb.outages {
            let at = |t| At {
                time: Some(t),
                line: 0,
            };
            let Some(v0) = clock.value(&at(o.start)) else {
                continue;
            };
            let x1 = o
                .end
                .and_then(|e| clock.value(&at(e)))
                .map_or(end, |v| scale.x(v));
            let x0 = scale.x(v0);
            let title = match (o.end, o.duration()) {
                (Some(e), Some(d)) => format!(
                    "heartbeat lost from {} to {} ({d} s)",
                    clock.at(&at(o.start)),
                    clock.at(&at(e))
                ),
                _ => format!(
                    "heartbeat lost from {} to the end of the trace",
                    clock.at(&at(o.start))
                ),
            };
            out.push(Shade {
                x0,
                x1: x1.max(x0 + 1.0),
                class: "out",
                title,
                strip: false,
            });
        }
    }
    out
}

/// The label of a lane: `can0 · node 5`, and a second line.
pub(super) struct LaneLabel {
    pub(super) main: String,
    pub(super) detail: Option<String>,
}

/// The one place a lane's label is made: channel and node, then the node's
/// profile and why it has it.
pub(super) fn lane_label(node: &NodeReport) -> LaneLabel {
    LaneLabel {
        main: format!("{} · node {}", node.channel, node.node),
        detail: Some(format!(
            "{} ({})",
            node.profile.name(),
            node.profile_source.slug()
        )),
    }
}

/// Key of a lane in the HTML filter: `channel/node`.
pub(in crate::report) fn lane_key(channel: &str, node: NodeId) -> String {
    format!("{channel}/{node}")
}
