//! `--fail-on`: conditions over what the inputs contained that fail a run
//! (exit 1 in the application), each met one named with what met it.

use super::analysis::Analysis;
use super::event::InputReport;

/// The `--fail-on` conditions of one or more flags, combined: any met fails.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FailOn {
    /// Any EMCY with an error code (not a reset).
    pub any: bool,
    /// A node ends the trace with an active error.
    pub active: bool,
    /// Any protocol warning on a reported EMCY.
    pub warning: bool,
    /// Any of these codes raised.
    pub codes: Vec<u16>,
    /// An error whose profile category is at most this (1 = most severe).
    pub category_at_most: Option<u8>,
    /// A node lost its heartbeat (an outage, or silent at the end).
    pub lost: bool,
    /// A node's CiA 402 drive entered fault.
    pub fault: bool,
    /// A controller went bus-off (the logging one, or a node inferred).
    pub bus_off: bool,
    /// Any error frame on the bus.
    pub bus_errors: bool,
    pub incident: bool,
}

impl FailOn {
    /// All flags given, merged.
    pub fn combine(flags: &[FailOn]) -> FailOn {
        let mut all = FailOn::default();
        for f in flags {
            all.any |= f.any;
            all.active |= f.active;
            all.warning |= f.warning;
            all.lost |= f.lost;
            all.fault |= f.fault;
            all.bus_off |= f.bus_off;
            all.bus_errors |= f.bus_errors;
            all.incident |= f.incident;
            all.codes.extend(&f.codes);
            all.category_at_most = match (all.category_at_most, f.category_at_most) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
        }
        all.codes.sort_unstable();
        all.codes.dedup();
        all
    }
}

/// What `--fail-on` needs of the inputs beside their reports, summed over
/// them (so the reports can go to the renderer without a copy).
#[derive(Clone, Copy, Debug, Default)]
pub struct Tally {
    errors_raised: u64,
    frames_with_warnings: u64,
    worst_category: Option<u8>,
    incidents: u64,
}

impl Tally {
    /// Adds one input's analysis.
    pub fn add(&mut self, a: &Analysis) {
        self.errors_raised += a.errors_raised;
        self.frames_with_warnings += a.frames_with_warnings;
        self.incidents += a.incidents;
        self.worst_category = match (self.worst_category, a.worst_category) {
            (Some(w), Some(c)) => Some(w.min(c)),
            (w, c) => w.or(c),
        };
    }
}

/// The `--fail-on` conditions the inputs met, each with what met it.
pub fn met(fail_on: &FailOn, tally: &Tally, reports: &[InputReport]) -> Vec<String> {
    let mut met = Vec::new();
    let nodes = || reports.iter().flat_map(|r| &r.nodes);
    if fail_on.any {
        let n = tally.errors_raised;
        if n > 0 {
            met.push(format!("any: {n} error EMCY frame{}", plural(n)));
        }
    }
    if fail_on.active {
        let n = nodes().filter(|n| !n.active.is_empty()).count() as u64;
        if n > 0 {
            met.push(format!(
                "active: {n} node{} end{} with an active error",
                plural(n),
                if n == 1 { "s" } else { "" }
            ));
        }
    }
    if fail_on.warning {
        let n = tally.frames_with_warnings;
        if n > 0 {
            met.push(format!(
                "warning: {n} EMCY frame{} with warnings",
                plural(n)
            ));
        }
    }
    if fail_on.lost {
        let n = nodes()
            .filter(|n| n.heartbeat.as_ref().is_some_and(|h| h.lost > 0))
            .count() as u64;
        if n > 0 {
            met.push(format!(
                "lost: {n} node{} lost {} heartbeat",
                plural(n),
                if n == 1 { "its" } else { "their" }
            ));
        }
    }
    if fail_on.fault {
        let faults: u64 = nodes()
            .filter_map(|n| n.drive.as_ref())
            .map(|a| a.fault_count)
            .sum();
        let drives = nodes()
            .filter(|n| n.drive.as_ref().is_some_and(|a| a.fault_count > 0))
            .count() as u64;
        if faults > 0 {
            met.push(format!(
                "fault: {drives} drive{} faulted {faults} time{}",
                plural(drives),
                plural(faults)
            ));
        }
    }
    let channels = || reports.iter().flat_map(|r| &r.bus_errors);
    if fail_on.bus_off {
        let n: u64 = channels().map(|c| c.bus_off_count).sum();
        if n > 0 {
            let nodes = channels()
                .flat_map(|c| &c.bus_offs)
                .filter(|b| b.node.is_some())
                .count();
            met.push(format!(
                "bus-off: {n} bus-off{} ({nodes} of a node, as far as kept)",
                plural(n)
            ));
        }
    }
    if fail_on.bus_errors {
        let frames: u64 = channels().map(|c| c.frames).sum();
        let bursts: u64 = channels().map(|c| c.bursts).sum();
        if frames > 0 {
            met.push(format!(
                "bus-errors: {frames} error frame{} in {bursts} burst{}",
                plural(frames),
                plural(bursts)
            ));
        }
    }
    if fail_on.incident && tally.incidents > 0 {
        let n = tally.incidents;
        met.push(format!("incident: {n} incident{}", plural(n)));
    }
    for &code in &fail_on.codes {
        let n: u64 = nodes().filter_map(|n| n.stats.raised.get(&code)).sum();
        if n > 0 {
            met.push(format!("code=0x{code:04X}: raised {n} time{}", plural(n)));
        }
    }
    if let (Some(bound), Some(worst)) = (fail_on.category_at_most, tally.worst_category)
        && worst <= bound
    {
        met.push(format!("category<={bound}: an error of category {worst}"));
    }
    met
}

fn plural(n: u64) -> &'static str {
    if n == 1 { "" } else { "s" }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyze::event::{BusOffRecord, ChannelErrors};

    fn with_bus(frames: u64, bus_offs: &[Option<u16>]) -> InputReport {
        let mut report = Analysis::unopened("t.log".into(), String::new()).report;
        report.bus_errors.push(ChannelErrors {
            channel: "can0".into(),
            frames,
            bursts: u64::from(frames > 0),
            bus_off_count: bus_offs.len() as u64,
            bus_offs: bus_offs
                .iter()
                .map(|&node| BusOffRecord {
                    node,
                    start: None,
                    end: None,
                })
                .collect(),
            ..ChannelErrors::default()
        });
        report
    }

    #[test]
    fn bus_off_is_met_by_any_bus_off() {
        let f = FailOn {
            bus_off: true,
            ..FailOn::default()
        };
        let tally = Tally::default();
        assert!(met(&f, &tally, &[with_bus(12, &[])]).is_empty());
        assert_eq!(
            met(&f, &tally, &[with_bus(12, &[Some(5), None])]),
            ["bus-off: 2 bus-offs (1 of a node, as far as kept)"]
        );
    }

    #[test]
    fn bus_errors_is_met_by_any_error_frame() {
        let f = FailOn {
            bus_errors: true,
            ..FailOn::default()
        };
        let tally = Tally::default();
        assert!(met(&f, &tally, &[with_bus(0, &[])]).is_empty());
        assert_eq!(
            met(&f, &tally, &[with_bus(1, &[])]),
            ["bus-errors: 1 error frame in 1 burst"]
        );
        // Not asked: not met.
        assert!(met(&FailOn::default(), &tally, &[with_bus(9, &[None])]).is_empty());
    }

    #[test]
    fn bus_conditions_combine() {
        let a = FailOn {
            bus_off: true,
            ..FailOn::default()
        };
        let b = FailOn {
            bus_errors: true,
            ..FailOn::default()
        };
        let all = FailOn::combine(&[a, b]);
        assert!(all.bus_off && all.bus_errors);
    }
}
