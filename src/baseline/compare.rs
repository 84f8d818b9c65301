//! Comparing a new record of traces with the baseline: one finding per
//! difference, each a regression, an improvement or a change.

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;

use super::{Baseline, Code, ErrorEntry, NodeEntry, TraceEntry};
use crate::canopen::NodeId;
use crate::canopen::codes;

/// Differences the user accepts (`--allow`, `--allow-node`).
#[derive(Clone, Debug, Default)]
pub struct Allow {
    pub codes: BTreeSet<u16>,
    pub nodes: BTreeSet<NodeId>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// Exit 1 unless allowed.
    Regression,
    /// Better than the baseline; exit 0.
    Improvement,
    /// Neither better nor worse; exit 0.
    Change,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    TraceNotInBaseline,
    TraceNotGiven,
    FormatChanged,
    MalformedGrew,
    MalformedFell,
    EmcyInvalidGrew,
    EmcyInvalidFell,
    NewNode,
    NewNodeWithoutErrors,
    NodeGone,
    NewError,
    NowActive,
    ErrorGone,
    NowCleared,
    CountChanged,
    /// The node lost its heartbeat; in the baseline it did not.
    HeartbeatLostNew,
    /// The baseline's node lost its heartbeat; now it does not.
    HeartbeatLostGone,
    /// The node's CiA 402 drive faulted more often than in the baseline.
    #[serde(rename = "axis_fault_new")]
    DriveFaultNew,
    /// The baseline's drive faulted; now it does not.
    #[serde(rename = "axis_fault_gone")]
    DriveFaultGone,
    /// A controller went bus-off (a node's, or the one that logged the
    /// trace); in the baseline it did not.
    BusOffNew,
    /// In the baseline it went bus-off; now it does not.
    BusOffGone,
    /// An incident whose root (node, kind and code) the baseline has not
    /// seen on that channel.
    IncidentNew,
    /// The baseline had incidents of this root; now there are none.
    IncidentGone,
}

impl Kind {
    fn severity(self) -> Severity {
        match self {
            Kind::TraceNotInBaseline
            | Kind::TraceNotGiven
            | Kind::MalformedGrew
            | Kind::EmcyInvalidGrew
            | Kind::NewNode
            | Kind::NewError
            | Kind::NowActive
            | Kind::HeartbeatLostNew
            | Kind::DriveFaultNew
            | Kind::BusOffNew
            | Kind::IncidentNew => Severity::Regression,
            Kind::MalformedFell
            | Kind::EmcyInvalidFell
            | Kind::ErrorGone
            | Kind::NowCleared
            | Kind::HeartbeatLostGone
            | Kind::DriveFaultGone
            | Kind::BusOffGone
            | Kind::IncidentGone => Severity::Improvement,
            Kind::FormatChanged
            | Kind::NewNodeWithoutErrors
            | Kind::NodeGone
            | Kind::CountChanged => Severity::Change,
        }
    }
}

/// One difference. Every finding has every key (null when it does not
/// apply), so `--format json` consumers see one shape.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Finding {
    pub severity: Severity,
    pub kind: Kind,
    /// Accepted by `--allow`/`--allow-node`: not counted as a regression.
    pub allowed: bool,
    pub file: String,
    pub channel: Option<String>,
    pub node: Option<NodeId>,
    pub code: Option<Code>,
    /// The number now (raised count, line count) and in the baseline.
    pub count: Option<u64>,
    pub baseline_count: Option<u64>,
    /// The text after `FILE [CHANNEL node N]: ` in the text output.
    pub message: String,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Summary {
    /// Regressions not allowed: exit 1 when over 0.
    pub regressions: u64,
    pub allowed: u64,
    pub improvements: u64,
    pub changes: u64,
    /// Traces given plus baseline traces not given.
    pub traces: u64,
    /// Traces in both with no regression (allowed ones do not count).
    pub matched: u64,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Diff {
    pub findings: Vec<Finding>,
    pub summary: Summary,
}

/// Where a finding is: a trace, or a node in it.
#[derive(Clone, Copy)]
struct Place<'a> {
    file: &'a str,
    node: Option<(&'a str, NodeId)>,
}

/// No counts.
const NONE: (Option<u64>, Option<u64>) = (None, None);

struct Collector<'a> {
    allow: &'a Allow,
    findings: Vec<Finding>,
}

impl Collector<'_> {
    /// Records a finding; `allowed` says it is accepted whatever the
    /// `--allow` lists hold.
    fn add(
        &mut self,
        at: Place<'_>,
        kind: Kind,
        code: Option<u16>,
        (count, baseline_count): (Option<u64>, Option<u64>),
        allowed: bool,
        message: String,
    ) {
        let node_allowed = at.node.is_some_and(|(_, n)| self.allow.nodes.contains(&n));
        let code_allowed = code.is_some_and(|c| self.allow.codes.contains(&c));
        let severity = kind.severity();
        self.findings.push(Finding {
            severity,
            kind,
            allowed: severity == Severity::Regression && (allowed || node_allowed || code_allowed),
            file: at.file.to_string(),
            channel: at.node.map(|(c, _)| c.to_string()),
            node: at.node.map(|(_, n)| n),
            code: code.map(Code),
            count,
            baseline_count,
            message,
        });
    }
}

fn describe(code: Code) -> String {
    codes::lookup(code.0).description().to_string()
}

fn times(n: u64, active: bool) -> String {
    if active {
        format!("{n}x, still active at end")
    } else {
        format!("{n}x")
    }
}

fn error_list(errors: &BTreeMap<Code, ErrorEntry>) -> String {
    let items: Vec<String> = errors
        .iter()
        .map(|(code, e)| format!("{code} ({})", times(e.raised, e.active_at_end)))
        .collect();
    items.join(", ")
}

/// Compares the traces of `new` with those of `old`.
pub fn compare(old: &Baseline, new: &Baseline, allow: &Allow) -> Diff {
    let mut c = Collector {
        allow,
        findings: Vec::new(),
    };
    let mut summary = Summary::default();
    let files: BTreeSet<&String> = old.traces.keys().chain(new.traces.keys()).collect();
    for file in files {
        summary.traces += 1;
        let at = Place { file, node: None };
        match (old.traces.get(file), new.traces.get(file)) {
            (Some(o), Some(n)) => {
                let before = c.findings.len();
                compare_trace(&mut c, file, o, n);
                let regressed = c
                    .findings
                    .get(before..)
                    .unwrap_or_default()
                    .iter()
                    .any(|f| f.severity == Severity::Regression && !f.allowed);
                if !regressed {
                    summary.matched += 1;
                }
            }
            (None, Some(_)) => c.add(
                at,
                Kind::TraceNotInBaseline,
                None,
                NONE,
                false,
                "not in the baseline".to_string(),
            ),
            (Some(_), None) => c.add(
                at,
                Kind::TraceNotGiven,
                None,
                NONE,
                false,
                "in the baseline but not given".to_string(),
            ),
            (None, None) => {}
        }
    }
    let mut findings = c.findings;
    findings.sort_by(|a, b| {
        (&a.file, &a.channel, a.node, a.code, a.kind)
            .cmp(&(&b.file, &b.channel, b.node, b.code, b.kind))
    });
    for f in &findings {
        match (f.severity, f.allowed) {
            (Severity::Regression, true) => summary.allowed += 1,
            (Severity::Regression, false) => summary.regressions += 1,
            (Severity::Improvement, _) => summary.improvements += 1,
            (Severity::Change, _) => summary.changes += 1,
        }
    }
    Diff { findings, summary }
}

/// Whether the trace shows what an incident root (`node 5 emcy 0x8130`,
/// `node 3 heartbeat_lost`, `bus bus_error`) names, outside incidents: the
/// node raised the code, lost its heartbeat, faulted, went bus-off. Roots
/// of other kinds (a reboot, an NMT change, error frames) have no finding
/// of their own: never "seen".
fn root_seen(root: &str, channel: &str, trace: &TraceEntry) -> bool {
    let words: Vec<&str> = root.split_whitespace().collect();
    let (node, kind, code) = match words.as_slice() {
        ["node", n, kind, rest @ ..] => (n.parse::<NodeId>().ok(), *kind, rest.first()),
        _ => return false,
    };
    let Some(entry) = node.and_then(|n| trace.nodes.get(channel)?.get(&n)) else {
        return false;
    };
    match kind {
        "emcy" => code
            .and_then(|c| u16::from_str_radix(c.trim_start_matches("0x"), 16).ok())
            .is_some_and(|c| entry.errors.contains_key(&Code(c))),
        "heartbeat_lost" => entry.heartbeat_lost > 0,
        "axis_fault" => entry.drive_faults > 0,
        "bus_off" => entry.bus_off > 0,
        _ => false,
    }
}

fn compare_trace(c: &mut Collector<'_>, file: &str, old: &TraceEntry, new: &TraceEntry) {
    let at = Place { file, node: None };
    if old.format != new.format {
        let name = |f: &Option<String>| f.clone().unwrap_or_else(|| "none".to_string());
        let msg = format!(
            "format {}, baseline {}",
            name(&new.format),
            name(&old.format)
        );
        c.add(at, Kind::FormatChanged, None, NONE, false, msg);
    }
    let pairs = [
        (
            "malformed lines",
            old.counts.malformed,
            new.counts.malformed,
            Kind::MalformedGrew,
            Kind::MalformedFell,
        ),
        (
            "EMCY frames too short to decode",
            old.counts.emcy_invalid,
            new.counts.emcy_invalid,
            Kind::EmcyInvalidGrew,
            Kind::EmcyInvalidFell,
        ),
    ];
    for (what, was, now, grew, fell) in pairs {
        let kind = match now.cmp(&was) {
            std::cmp::Ordering::Greater => grew,
            std::cmp::Ordering::Less => fell,
            std::cmp::Ordering::Equal => continue,
        };
        let msg = format!("{what} {now}, baseline {was}");
        c.add(at, kind, None, (Some(now), Some(was)), false, msg);
    }

    let none = BTreeMap::new();
    let channels: BTreeSet<&String> = old.incidents.keys().chain(new.incidents.keys()).collect();
    for channel in channels {
        let was = old.incidents.get(channel).unwrap_or(&none);
        let now = new.incidents.get(channel).unwrap_or(&none);
        // A root that is itself new or gone (a new error code, a first
        // heartbeat loss, drive fault or bus-off of the node) has its own
        // finding: the incident would say it twice.
        let said = |root: &str, from: &TraceEntry, to: &TraceEntry| {
            !root_seen(root, channel, from) && root_seen(root, channel, to)
        };
        for (root, &n) in now
            .iter()
            .filter(|(r, _)| !was.contains_key(*r) && !said(r, old, new))
        {
            let msg = format!(
                "{channel}: {n} incident{} rooted in {root}, baseline none",
                if n == 1 { "" } else { "s" }
            );
            c.add(at, Kind::IncidentNew, None, (Some(n), Some(0)), false, msg);
        }
        for (root, &n) in was
            .iter()
            .filter(|(r, _)| !now.contains_key(*r) && !said(r, new, old))
        {
            let msg = format!("{channel}: no incident rooted in {root} now (baseline {n})");
            c.add(at, Kind::IncidentGone, None, (Some(0), Some(n)), false, msg);
        }
    }

    let controllers: BTreeSet<&String> = old.bus_off.keys().chain(new.bus_off.keys()).collect();
    for channel in controllers {
        let was = old.bus_off.get(channel).copied().unwrap_or(0);
        let now = new.bus_off.get(channel).copied().unwrap_or(0);
        let counts = (Some(now), Some(was));
        if now > 0 && was == 0 {
            let msg = format!("{channel}: the controller went bus-off {now}x, baseline never");
            c.add(at, Kind::BusOffNew, None, counts, false, msg);
        } else if now == 0 && was > 0 {
            let msg = format!("{channel}: the controller no longer goes bus-off (baseline {was}x)");
            c.add(at, Kind::BusOffGone, None, counts, false, msg);
        }
    }

    let empty = BTreeMap::new();
    let channels: BTreeSet<&String> = old.nodes.keys().chain(new.nodes.keys()).collect();
    for channel in channels {
        let o = old.nodes.get(channel).unwrap_or(&empty);
        let n = new.nodes.get(channel).unwrap_or(&empty);
        let ids: BTreeSet<NodeId> = o.keys().chain(n.keys()).copied().collect();
        for id in ids {
            let at = Place {
                file,
                node: Some((channel, id)),
            };
            compare_node(c, at, o.get(&id), n.get(&id));
        }
    }
}

fn compare_node(
    c: &mut Collector<'_>,
    at: Place<'_>,
    old: Option<&NodeEntry>,
    new: Option<&NodeEntry>,
) {
    let lost = |e: Option<&NodeEntry>| e.map_or(0, |e| e.heartbeat_lost);
    let (was, now) = (lost(old), lost(new));
    if now > 0 && was == 0 {
        let msg = format!("lost its heartbeat {now}x, baseline never");
        c.add(
            at,
            Kind::HeartbeatLostNew,
            None,
            (Some(now), Some(was)),
            false,
            msg,
        );
    } else if now == 0 && was > 0 && new.is_some() {
        let msg = format!("no longer loses its heartbeat (baseline {was}x)");
        c.add(
            at,
            Kind::HeartbeatLostGone,
            None,
            (Some(now), Some(was)),
            false,
            msg,
        );
    }
    let bus_offs = |e: Option<&NodeEntry>| e.map_or(0, |e| e.bus_off);
    let (was, now) = (bus_offs(old), bus_offs(new));
    let counts = (Some(now), Some(was));
    if now > 0 && was == 0 {
        let msg = format!("went bus-off {now}x, baseline never");
        c.add(at, Kind::BusOffNew, None, counts, false, msg);
    } else if now == 0 && was > 0 && new.is_some() {
        let msg = format!("no longer goes bus-off (baseline {was}x)");
        c.add(at, Kind::BusOffGone, None, counts, false, msg);
    }
    let faults = |e: Option<&NodeEntry>| e.map_or(0, |e| e.drive_faults);
    let (was, now) = (faults(old), faults(new));
    if now > was {
        let msg = format!("axis faulted {now}x, baseline {was}x");
        c.add(
            at,
            Kind::DriveFaultNew,
            None,
            (Some(now), Some(was)),
            false,
            msg,
        );
    } else if now == 0 && was > 0 && new.is_some() {
        let msg = format!("axis no longer faults (baseline {was}x)");
        c.add(
            at,
            Kind::DriveFaultGone,
            None,
            (Some(now), Some(was)),
            false,
            msg,
        );
    }
    match (old, new) {
        (None, Some(n)) if n.errors.is_empty() => {
            let msg = "new node, no errors".to_string();
            c.add(at, Kind::NewNodeWithoutErrors, None, NONE, false, msg);
        }
        (None, Some(n)) => {
            // The node's errors are what makes it a regression: allowed when
            // every one of them is.
            let all_allowed = n.errors.keys().all(|k| c.allow.codes.contains(&k.0));
            let msg = format!("new node with errors {}", error_list(&n.errors));
            c.add(at, Kind::NewNode, None, NONE, all_allowed, msg);
        }
        (Some(o), None) => {
            let msg = if o.errors.is_empty() {
                "node no longer appears (baseline: no errors)".to_string()
            } else {
                format!(
                    "node no longer appears (baseline: errors {})",
                    error_list(&o.errors)
                )
            };
            c.add(at, Kind::NodeGone, None, NONE, false, msg);
        }
        (Some(o), Some(n)) => compare_errors(c, at, &o.errors, &n.errors),
        (None, None) => {}
    }
}

fn compare_errors(
    c: &mut Collector<'_>,
    at: Place<'_>,
    old: &BTreeMap<Code, ErrorEntry>,
    new: &BTreeMap<Code, ErrorEntry>,
) {
    let codes: BTreeSet<Code> = old.keys().chain(new.keys()).copied().collect();
    for code in codes {
        let desc = describe(code);
        let now = new.get(&code);
        let was = old.get(&code);
        let counts = (now.map(|e| e.raised), was.map(|e| e.raised));
        let mut add = |kind, msg| c.add(at, kind, Some(code.0), counts, false, msg);
        match (was, now) {
            (None, Some(n)) => {
                let msg = format!(
                    "new error {code} ({}): {desc}",
                    times(n.raised, n.active_at_end)
                );
                add(Kind::NewError, msg);
            }
            (Some(o), None) => {
                let msg = format!(
                    "error {code} no longer appears (baseline {}x): {desc}",
                    o.raised
                );
                add(Kind::ErrorGone, msg);
            }
            (Some(o), Some(n)) => {
                if n.active_at_end && !o.active_at_end {
                    let msg = format!(
                        "error {code} still active at end, cleared in the baseline: {desc}"
                    );
                    add(Kind::NowActive, msg);
                }
                if !n.active_at_end && o.active_at_end {
                    let msg =
                        format!("error {code} cleared by the end, active in the baseline: {desc}");
                    add(Kind::NowCleared, msg);
                }
                if n.raised != o.raised {
                    let msg = format!(
                        "error {code} raised {}x, baseline {}x: {desc}",
                        n.raised, o.raised
                    );
                    add(Kind::CountChanged, msg);
                }
            }
            (None, None) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::baseline::VERSION;

    fn node(errors: &[(u16, u64, bool)]) -> NodeEntry {
        NodeEntry {
            emcy: 0,
            errors: errors
                .iter()
                .map(|&(c, raised, active_at_end)| {
                    (
                        Code(c),
                        ErrorEntry {
                            active_at_end,
                            raised,
                        },
                    )
                })
                .collect(),
            heartbeat_lost: 0,
            drive_faults: 0,
            bus_off: 0,
        }
    }

    fn faulted(n: u64) -> NodeEntry {
        NodeEntry {
            drive_faults: n,
            ..node(&[])
        }
    }

    #[test]
    fn more_drive_faults_than_the_baseline_regress_none_improve() {
        let old = one(&[
            (1, node(&[])),
            (2, faulted(1)),
            (3, faulted(2)),
            (5, faulted(2)),
        ]);
        let new = one(&[
            (1, faulted(1)),
            (2, node(&[])),
            (3, faulted(2)),
            (5, faulted(3)),
        ]);
        let diff = compare(&old, &new, &Allow::default());
        let found: Vec<(Option<NodeId>, Kind)> = diff
            .findings
            .iter()
            .filter(|f| matches!(f.kind, Kind::DriveFaultNew | Kind::DriveFaultGone))
            .map(|f| (f.node, f.kind))
            .collect();
        assert_eq!(
            found,
            [
                (Some(1), Kind::DriveFaultNew),
                (Some(2), Kind::DriveFaultGone),
                (Some(5), Kind::DriveFaultNew),
            ]
        );
        assert_eq!(
            serde_json::to_value(Kind::DriveFaultNew).ok(),
            Some(serde_json::json!("axis_fault_new"))
        );
    }

    fn lost(n: u64) -> NodeEntry {
        NodeEntry {
            heartbeat_lost: n,
            ..node(&[])
        }
    }

    #[test]
    fn lost_heartbeats_where_the_baseline_had_none_regress() {
        let old = one(&[(1, node(&[])), (2, lost(1)), (3, lost(2))]);
        let new = one(&[(1, lost(2)), (2, node(&[])), (3, lost(5)), (4, lost(1))]);
        let diff = compare(&old, &new, &Allow::default());
        let kinds: Vec<(Option<NodeId>, Kind, Severity, Option<u64>)> = diff
            .findings
            .iter()
            .map(|f| (f.node, f.kind, f.severity, f.count))
            .collect();
        use Kind::*;
        use Severity::*;
        assert_eq!(
            kinds,
            vec![
                (Some(1), HeartbeatLostNew, Regression, Some(2)),
                (Some(2), HeartbeatLostGone, Improvement, Some(0)),
                (Some(4), NewNodeWithoutErrors, Change, None),
                (Some(4), HeartbeatLostNew, Regression, Some(1)),
            ]
        );
        assert_eq!(diff.summary.regressions, 2);
        assert_eq!(
            serde_json::to_value(HeartbeatLostNew).ok(),
            Some(serde_json::json!("heartbeat_lost_new"))
        );
        // --allow-node accepts it.
        let allow = Allow {
            nodes: [1, 4].into_iter().collect(),
            ..Allow::default()
        };
        assert_eq!(compare(&old, &new, &allow).summary.regressions, 0);
    }

    #[test]
    fn baselines_without_outages_keep_their_bytes() {
        let b = one(&[(1, node(&[]))]);
        let text = b.to_json().unwrap_or_default();
        assert!(!text.contains("heartbeat_lost"), "{text}");
        assert_eq!(Baseline::from_json(&text).ok(), Some(b));
        let b = one(&[(1, lost(3))]);
        let text = b.to_json().unwrap_or_default();
        assert!(text.contains("\"heartbeat_lost\": 3"), "{text}");
        assert_eq!(Baseline::from_json(&text).ok(), Some(b));
    }

    fn off(n: u64) -> NodeEntry {
        NodeEntry {
            bus_off: n,
            ..node(&[])
        }
    }

    #[test]
    fn bus_offs_where_the_baseline_had_none_regress() {
        let mut old = one(&[(1, node(&[])), (2, off(1)), (3, off(1))]);
        let mut new = one(&[(1, off(2)), (2, node(&[])), (3, off(4))]);
        if let Some(t) = new.traces.get_mut("t.log") {
            t.bus_off.insert("can0".to_string(), 1);
        }
        if let Some(t) = old.traces.get_mut("t.log") {
            t.bus_off.insert("can1".to_string(), 2);
        }
        let diff = compare(&old, &new, &Allow::default());
        let found: Vec<(Option<NodeId>, Kind, Severity)> = diff
            .findings
            .iter()
            .filter(|f| matches!(f.kind, Kind::BusOffNew | Kind::BusOffGone))
            .map(|f| (f.node, f.kind, f.severity))
            .collect();
        use Kind::*;
        use Severity::*;
        assert_eq!(
            found,
            [
                (None, BusOffNew, Regression),
                (None, BusOffGone, Improvement),
                (Some(1), BusOffNew, Regression),
                (Some(2), BusOffGone, Improvement),
            ]
        );
        assert_eq!(
            serde_json::to_value(BusOffNew).ok(),
            Some(serde_json::json!("bus_off_new"))
        );
        // Baselines without bus-offs keep their bytes; with them they read back.
        let plain = one(&[(1, node(&[]))]).to_json().unwrap_or_default();
        assert!(!plain.contains("bus_off"), "{plain}");
        let text = new.to_json().unwrap_or_default();
        assert_eq!(Baseline::from_json(&text).ok(), Some(new));
    }

    fn one(nodes: &[(NodeId, NodeEntry)]) -> Baseline {
        let mut trace = TraceEntry::default();
        trace
            .nodes
            .insert("can0".to_string(), nodes.iter().cloned().collect());
        Baseline {
            baseline_version: VERSION,
            options: Default::default(),
            traces: [("t.log".to_string(), trace)].into_iter().collect(),
        }
    }

    #[test]
    fn each_difference_has_its_severity() {
        let old = one(&[
            (
                1,
                node(&[(0x4310, 2, false), (0x3120, 1, true), (0x5111, 1, false)]),
            ),
            (2, node(&[])),
        ]);
        let new = one(&[
            (
                1,
                node(&[(0x4310, 3, true), (0x3120, 1, false), (0x2310, 1, false)]),
            ),
            (3, node(&[(0x8130, 1, true)])),
        ]);
        let diff = compare(&old, &new, &Allow::default());
        let kinds: Vec<(Option<NodeId>, Option<Code>, Kind, Severity)> = diff
            .findings
            .iter()
            .map(|f| (f.node, f.code, f.kind, f.severity))
            .collect();
        use Kind::*;
        use Severity::*;
        assert_eq!(
            kinds,
            vec![
                (Some(1), Some(Code(0x2310)), NewError, Regression),
                (Some(1), Some(Code(0x3120)), NowCleared, Improvement),
                (Some(1), Some(Code(0x4310)), NowActive, Regression),
                (Some(1), Some(Code(0x4310)), CountChanged, Change),
                (Some(1), Some(Code(0x5111)), ErrorGone, Improvement),
                (Some(2), None, NodeGone, Change),
                (Some(3), None, NewNode, Regression),
            ]
        );
        assert_eq!(diff.summary.regressions, 3);
        assert_eq!(diff.summary.matched, 0);

        let allow = Allow {
            codes: [0x2310, 0x8130].into_iter().collect(),
            nodes: [1].into_iter().collect(),
        };
        let diff = compare(&old, &new, &allow);
        assert_eq!(diff.summary.regressions, 0);
        assert_eq!(diff.summary.allowed, 3);
        assert_eq!(diff.summary.matched, 1);
    }

    #[test]
    fn a_new_node_without_errors_is_only_a_change() {
        let old = one(&[]);
        let new = one(&[(4, node(&[]))]);
        let diff = compare(&old, &new, &Allow::default());
        assert_eq!(diff.findings.len(), 1);
        assert_eq!(diff.findings[0].kind, Kind::NewNodeWithoutErrors);
        assert_eq!(diff.findings[0].severity, Severity::Change);
        assert_eq!(diff.summary.regressions, 0);
    }
}
