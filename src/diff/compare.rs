//! Two stories aligned teller by teller: the steps both tell in the same
//! order are equal, the rest are differences (removed: only the good trace
//! tells it; added: only the bad one; changed: each tells another step at
//! that point).

use std::collections::{BTreeSet, HashMap};

use similar::{Algorithm, DiffOp, capture_diff_slices};

use super::story::{NodeStory, Step, Story, Teller};

/// Steps of one teller aligned by an edit script at most, counting both
/// traces' steps between their common beginning and end. Myers' algorithm
/// costs (N+M)·D; past this the rest is aligned step by step, so a story
/// of millions of differing steps takes seconds, not hours.
pub const MAX_ALIGNED: usize = 20_000;

/// Differences kept per teller; the rest are counted.
pub const MAX_SHOWN: usize = 1_000;

/// A step of one trace: what and where.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Told {
    pub step: Step,
    pub line: u64,
}

/// One difference: `good` only (removed), `bad` only (added), or both
/// (the traces tell another step at this point).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Difference {
    pub good: Option<Told>,
    pub bad: Option<Told>,
    /// Where in the good trace the traces part here: the line of the good
    /// step, else of the next good step (`None` past its last step).
    pub at_good: Option<u64>,
}

impl Difference {
    /// `removed`, `added` or `changed`: the JSON name.
    pub fn kind(&self) -> &'static str {
        match (&self.good, &self.bad) {
            (Some(_), None) => "removed",
            (None, Some(_)) => "added",
            _ => "changed",
        }
    }
}

/// A fact of the end that differs (the NMT state, the errors still
/// active, ...); `None` where one trace does not have the node or the fact.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EndDifference {
    pub fact: &'static str,
    pub good: Option<String>,
    pub bad: Option<String>,
}

/// Which trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Good,
    Bad,
}

impl Side {
    pub fn slug(self) -> &'static str {
        match self {
            Side::Good => "good",
            Side::Bad => "bad",
        }
    }
}

/// How one teller's stories differ.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TellerDifference {
    pub teller: Teller,
    /// The teller speaks in one trace only.
    pub only_in: Option<Side>,
    /// Steps both traces tell alike before the first difference.
    pub equal_before: usize,
    /// The first [`MAX_SHOWN`] differences, in the good trace's order.
    pub differences: Vec<Difference>,
    pub differences_total: usize,
    /// Part of the story was past [`MAX_ALIGNED`] and aligned step by step.
    pub aligned_by_position: bool,
    pub end: Vec<EndDifference>,
}

impl TellerDifference {
    /// Where the traces part for this teller: the line of the good trace
    /// at its first difference, then the bad trace's.
    fn parts_at(&self) -> (u64, u64) {
        let Some(d) = self.differences.first() else {
            return (u64::MAX, u64::MAX);
        };
        let bad = d.bad.as_ref().map_or(u64::MAX, |t| t.line);
        (d.at_good.unwrap_or(u64::MAX), bad)
    }
}

/// The comparison of two traces.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Comparison {
    pub good: String,
    pub bad: String,
    /// Tellers that differ, the one where the traces part first first,
    /// then in teller order.
    pub tellers: Vec<TellerDifference>,
    /// Steps left out of either story past its bound.
    pub cut: u64,
}

impl Comparison {
    pub fn same(&self) -> bool {
        self.tellers.is_empty()
    }

    /// Differences in all, end facts included.
    pub fn total(&self) -> usize {
        self.tellers
            .iter()
            .map(|t| t.differences_total + t.end.len())
            .sum()
    }
}

/// Compares the good trace's story with the bad one's. When each trace
/// has one channel, their names are ignored (a candump `can0` and an ASC
/// channel `1` are the same bus); otherwise tellers are matched by channel
/// name and node.
pub fn compare(good: &Story, bad: &Story) -> Comparison {
    let good_channels = channels(good);
    let bad_channels = channels(bad);
    let rename = (good_channels.len() == 1 && bad_channels.len() == 1)
        .then(|| (bad_channels[0].clone(), good_channels[0].clone()));
    let as_good = |t: &Teller| match &rename {
        Some((from, to)) if &t.channel == from => Teller {
            channel: to.clone(),
            node: t.node,
        },
        _ => t.clone(),
    };
    let bad_by: std::collections::BTreeMap<Teller, &NodeStory> =
        bad.tellers.iter().map(|(t, s)| (as_good(t), s)).collect();
    let all: BTreeSet<&Teller> = good.tellers.keys().chain(bad_by.keys()).collect();
    let empty = NodeStory::default();
    let mut tellers = Vec::new();
    for teller in all {
        let g = good.tellers.get(teller);
        let b = bad_by.get(teller).copied();
        let only_in = match (g, b) {
            (Some(_), None) => Some(Side::Good),
            (None, Some(_)) => Some(Side::Bad),
            _ => None,
        };
        let d = compare_teller(
            teller.clone(),
            g.unwrap_or(&empty),
            b.unwrap_or(&empty),
            only_in,
        );
        if d.differences_total > 0 || !d.end.is_empty() || d.only_in.is_some() {
            tellers.push(d);
        }
    }
    // The teller where the traces part first leads; the others keep their
    // order (channel, bus before nodes, node number).
    if let Some(first) = (0..tellers.len()).min_by_key(|&i| tellers[i].parts_at()) {
        let lead = tellers.remove(first);
        tellers.insert(0, lead);
    }
    Comparison {
        good: good.file.clone(),
        bad: bad.file.clone(),
        tellers,
        cut: good.cut + bad.cut,
    }
}

fn channels(story: &Story) -> Vec<String> {
    let set: BTreeSet<&String> = story.tellers.keys().map(|t| &t.channel).collect();
    set.into_iter().cloned().collect()
}

fn compare_teller<'a>(
    teller: Teller,
    good: &'a NodeStory,
    bad: &'a NodeStory,
    only_in: Option<Side>,
) -> TellerDifference {
    let (g, b) = (&good.steps[..], &bad.steps[..]);
    let prefix = g.iter().zip(b).take_while(|(x, y)| x == y).count();
    let suffix = g[prefix..]
        .iter()
        .rev()
        .zip(b[prefix..].iter().rev())
        .take_while(|(x, y)| x == y)
        .count();
    let (g_mid, b_mid) = (prefix..g.len() - suffix, prefix..b.len() - suffix);
    let mut out = Differences::new(good, bad);
    let aligned_by_position = g_mid.len() + b_mid.len() > MAX_ALIGNED;
    if aligned_by_position {
        let common = g_mid.len().min(b_mid.len());
        for k in 0..common {
            if g[g_mid.start + k] != b[b_mid.start + k] {
                out.push(
                    Some(g_mid.start + k),
                    Some(b_mid.start + k),
                    g_mid.start + k,
                );
            }
        }
        for i in g_mid.start + common..g_mid.end {
            out.push(Some(i), None, i);
        }
        for j in b_mid.start + common..b_mid.end {
            out.push(None, Some(j), g_mid.end);
        }
    } else {
        // Steps as small numbers, equal steps the same number: the
        // alignment compares numbers, not steps with their strings.
        let mut ids: HashMap<&Step, u32> = HashMap::new();
        let mut intern = |s: &'a [Step]| -> Vec<u32> {
            s.iter()
                .map(|step| {
                    let next = ids.len() as u32;
                    *ids.entry(step).or_insert(next)
                })
                .collect()
        };
        let (g_ids, b_ids) = (intern(&g[g_mid.clone()]), intern(&b[b_mid.clone()]));
        for op in capture_diff_slices(Algorithm::Myers, &g_ids, &b_ids) {
            let (i, j) = (g_mid.start, b_mid.start);
            match op {
                DiffOp::Equal { .. } => {}
                DiffOp::Delete {
                    old_index, old_len, ..
                } => (0..old_len)
                    .for_each(|k| out.push(Some(i + old_index + k), None, i + old_index + k)),
                DiffOp::Insert {
                    old_index,
                    new_index,
                    new_len,
                } => (0..new_len)
                    .for_each(|k| out.push(None, Some(j + new_index + k), i + old_index)),
                DiffOp::Replace {
                    old_index,
                    old_len,
                    new_index,
                    new_len,
                } => {
                    // Pairs first (a step told differently), then what one
                    // side tells more.
                    for k in 0..old_len.max(new_len) {
                        let gi = (k < old_len).then_some(i + old_index + k);
                        let bj = (k < new_len).then_some(j + new_index + k);
                        out.push(gi, bj, gi.unwrap_or(i + old_index + old_len));
                    }
                }
            }
        }
    }
    TellerDifference {
        teller,
        only_in,
        equal_before: prefix,
        differences: out.shown,
        differences_total: out.total,
        aligned_by_position,
        end: end_differences(good, bad, only_in),
    }
}

/// Differences collected in order, the first [`MAX_SHOWN`] kept.
struct Differences<'a> {
    good: &'a NodeStory,
    bad: &'a NodeStory,
    shown: Vec<Difference>,
    total: usize,
}

impl<'a> Differences<'a> {
    fn new(good: &'a NodeStory, bad: &'a NodeStory) -> Self {
        Differences {
            good,
            bad,
            shown: Vec::new(),
            total: 0,
        }
    }

    /// Records the good trace's step `gi` against the bad trace's `bj`;
    /// `at` is the good trace's step where they part (for an added step,
    /// the good step it comes before).
    fn push(&mut self, gi: Option<usize>, bj: Option<usize>, at: usize) {
        self.total += 1;
        if self.shown.len() >= MAX_SHOWN {
            return;
        }
        let told = |s: &NodeStory, i: usize| Told {
            step: s.steps[i].clone(),
            line: s.lines[i],
        };
        let at_good = self.good.lines.get(at).copied();
        self.shown.push(Difference {
            good: gi.map(|i| told(self.good, i)),
            bad: bj.map(|j| told(self.bad, j)),
            at_good,
        });
    }
}

fn end_differences(good: &NodeStory, bad: &NodeStory, only_in: Option<Side>) -> Vec<EndDifference> {
    // A teller of one trace only is told as such; its facts are not
    // differences one by one.
    if only_in.is_some() {
        return Vec::new();
    }
    let mut facts: Vec<&'static str> = Vec::new();
    for (f, _) in good.end.iter().chain(&bad.end) {
        if !facts.contains(f) {
            facts.push(f);
        }
    }
    let value = |s: &NodeStory, fact: &str| {
        s.end
            .iter()
            .find(|(f, _)| *f == fact)
            .map(|(_, v)| v.clone())
    };
    facts
        .into_iter()
        .filter_map(|fact| {
            let (g, b) = (value(good, fact), value(bad, fact));
            (g != b).then_some(EndDifference {
                fact,
                good: g,
                bad: b,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canopen::nmt::NmtState;

    fn story(file: &str, tellers: &[(&str, Option<u16>, &[Step])]) -> Story {
        let mut s = Story {
            file: file.to_string(),
            ..Story::default()
        };
        for (channel, node, steps) in tellers {
            let t = Teller {
                channel: channel.to_string(),
                node: *node,
            };
            let told = s.tellers.entry(t).or_default();
            for (i, step) in steps.iter().enumerate() {
                told.steps.push(step.clone());
                told.lines.push(10 * (i as u64 + 1));
            }
        }
        s
    }

    const OP: Step = Step::Nmt {
        state: NmtState::Operational,
        commanded: false,
    };
    const PREOP: Step = Step::Nmt {
        state: NmtState::PreOperational,
        commanded: false,
    };
    fn emcy(code: u16) -> Step {
        Step::Emcy { code, register: 1 }
    }

    #[test]
    fn equal_stories_are_the_same() {
        let a = story("a", &[("can0", Some(5), &[Step::Boot, OP, emcy(0x4310)])]);
        let b = story("b", &[("can0", Some(5), &[Step::Boot, OP, emcy(0x4310)])]);
        assert!(compare(&a, &b).same());
    }

    #[test]
    fn one_channel_each_is_one_bus_whatever_its_name() {
        let a = story("a", &[("can0", Some(5), &[Step::Boot])]);
        let b = story("b", &[("1", Some(5), &[Step::Boot])]);
        assert!(compare(&a, &b).same());
        let two = story("b", &[("1", Some(5), &[Step::Boot]), ("2", Some(6), &[])]);
        assert!(
            !compare(&a, &two).same(),
            "channels named apart when there are several"
        );
    }

    #[test]
    fn a_changed_step_is_one_difference_with_both_sides() {
        let a = story("a", &[("c", Some(5), &[Step::Boot, OP, emcy(0x4310)])]);
        let b = story("b", &[("c", Some(5), &[Step::Boot, PREOP, emcy(0x4310)])]);
        let c = compare(&a, &b);
        assert_eq!(c.tellers.len(), 1);
        let t = &c.tellers[0];
        assert_eq!(t.equal_before, 1);
        assert_eq!(t.differences_total, 1);
        let d = &t.differences[0];
        assert_eq!(d.kind(), "changed");
        assert_eq!(d.good.as_ref().unwrap().step, OP);
        assert_eq!(d.bad.as_ref().unwrap().step, PREOP);
        assert_eq!(d.at_good, Some(20));
    }

    #[test]
    fn an_added_step_parts_at_the_next_good_step() {
        let a = story("a", &[("c", Some(5), &[Step::Boot, OP])]);
        let b = story("b", &[("c", Some(5), &[Step::Boot, emcy(0x8130), OP])]);
        let c = compare(&a, &b);
        let d = &c.tellers[0].differences;
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].kind(), "added");
        assert_eq!(d[0].at_good, Some(20));
        let removed = compare(&b, &a);
        assert_eq!(removed.tellers[0].differences[0].kind(), "removed");
    }

    #[test]
    fn the_teller_where_the_traces_part_first_leads() {
        let a = story(
            "a",
            &[
                ("c", Some(3), &[Step::Boot, OP, OP, emcy(1)]),
                ("c", Some(9), &[Step::Boot, OP]),
            ],
        );
        let b = story(
            "b",
            &[
                ("c", Some(3), &[Step::Boot, OP, OP, emcy(2)]),
                ("c", Some(9), &[Step::Boot, PREOP]),
            ],
        );
        let c = compare(&a, &b);
        let order: Vec<_> = c.tellers.iter().map(|t| t.teller.node).collect();
        assert_eq!(
            order,
            [Some(9), Some(3)],
            "node 9 parts at line 20, node 3 at 40"
        );
    }

    #[test]
    fn a_node_of_one_trace_only_says_which() {
        let a = story("a", &[("c", Some(5), &[Step::Boot])]);
        let b = story(
            "b",
            &[("c", Some(5), &[Step::Boot]), ("c", Some(7), &[Step::Boot])],
        );
        let c = compare(&a, &b);
        assert_eq!(c.tellers.len(), 1);
        assert_eq!(c.tellers[0].only_in, Some(Side::Bad));
        assert_eq!(c.tellers[0].differences[0].kind(), "added");
    }

    #[test]
    fn end_facts_that_differ_are_differences() {
        let mut a = story("a", &[("c", Some(5), &[Step::Boot])]);
        let mut b = a.clone();
        let t = Teller {
            channel: "c".into(),
            node: Some(5),
        };
        a.tellers.get_mut(&t).unwrap().end = vec![("nmt_state", "operational".into())];
        b.tellers.get_mut(&t).unwrap().end = vec![("nmt_state", "pre_operational".into())];
        let c = compare(&a, &b);
        assert_eq!(c.total(), 1);
        assert_eq!(c.tellers[0].end[0].fact, "nmt_state");
    }

    #[test]
    fn long_differing_stories_are_aligned_by_position_and_counted() {
        let many: Vec<Step> = (0..MAX_ALIGNED as u16).map(emcy).collect();
        let other: Vec<Step> = (0..MAX_ALIGNED as u16).map(|c| emcy(c ^ 0x8000)).collect();
        let a = story("a", &[("c", Some(5), &many)]);
        let b = story("b", &[("c", Some(5), &other)]);
        let c = compare(&a, &b);
        let t = &c.tellers[0];
        assert!(t.aligned_by_position);
        assert_eq!(t.differences_total, MAX_ALIGNED);
        assert_eq!(t.differences.len(), MAX_SHOWN);
    }
}
