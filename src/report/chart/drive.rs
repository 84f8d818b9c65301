//! A CiA 402 drive's faults on its lane: one band per fault,
//! from entering fault reaction active or fault to leaving it (the end of
//! the trace for one still open), titled with its EMCY and reset. Kept in
//! its own function: the lane's other bands are the NMT states and
//! heartbeat outages of `shades`.

use super::lane::Shade;
use super::time_scale::{Clock, Scale};
use crate::analyze::NodeReport;
use crate::canopen::cia402::State;
use crate::timeline::At;
use crate::timeline::drive::DriveState;

/// The fault bands of a node with a drive; none for other nodes.
pub(super) fn fault_shades(clock: &Clock, scale: Scale, node: &NodeReport) -> Vec<Shade> {
    let Some(drive) = &node.drive else {
        return Vec::new();
    };
    let end = scale.x(scale.end);
    let mut out = Vec::new();
    for f in &drive.faults {
        let Some(v0) = clock.value(&f.start) else {
            continue;
        };
        let x0 = scale.x(v0);
        let x1 = f
            .end
            .as_ref()
            .and_then(|e| clock.value(e))
            .map_or(end, |v| scale.x(v));
        let mut title = match (&f.end, f.duration()) {
            (Some(e), Some(d)) => format!(
                "axis fault from {} to {} ({d} s)",
                clock.at(&f.start),
                clock.at(e)
            ),
            _ => format!(
                "axis fault from {} to the end of the trace",
                clock.at(&f.start)
            ),
        };
        if let Some(code) = f.emcy_code {
            title.push_str(&format!(", EMCY 0x{code:04X}"));
        }
        if let Some(reset) = &f.cleared_by {
            title.push_str(&format!(
                ", cleared by a fault reset at {}",
                clock.at(reset)
            ));
        }
        out.push(Shade {
            x0,
            x1: x1.max(x0 + 1.0),
            class: "fault",
            title,
            strip: false,
        });
    }
    out
}

/// The CSS class of a drive state's strip.
pub(super) fn drive_class(state: DriveState) -> &'static str {
    let DriveState::State(state) = state else {
        return "a-unknown";
    };
    match state {
        State::NotReadyToSwitchOn => "a-not_ready_to_switch_on",
        State::SwitchOnDisabled => "a-switch_on_disabled",
        State::ReadyToSwitchOn => "a-ready_to_switch_on",
        State::SwitchedOn => "a-switched_on",
        State::OperationEnabled => "a-operation_enabled",
        State::QuickStopActive => "a-quick_stop_active",
        State::FaultReactionActive => "a-fault_reaction_active",
        State::Fault => "a-fault",
    }
}

/// The drive states along the lane's foot: each from its change to the
/// next (the last to the end of the trace).
pub(super) fn drive_shades(
    clock: &Clock,
    scale: Scale,
    changes: &[(At, DriveState)],
) -> Vec<Shade> {
    let end = scale.x(scale.end);
    let mut out = Vec::new();
    for (i, (at, state)) in changes.iter().enumerate() {
        let Some(v) = clock.value(at) else { continue };
        let x0 = scale.x(v);
        let x1 = changes
            .get(i + 1)
            .and_then(|(next, _)| clock.value(next))
            .map_or(end, |n| scale.x(n));
        if x1 > x0 {
            out.push(Shade {
                x0,
                x1,
                class: drive_class(*state),
                title: format!("axis state {} from {}", state.slug(), clock.at(at)),
                strip: true,
            });
        }
    }
    out
}
