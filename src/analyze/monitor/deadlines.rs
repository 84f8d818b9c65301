//! When monitored nodes may have passed their heartbeat deadline.
//!
//! Every timed frame asks "did the clock pass a deadline?", and a steady
//! heartbeat moves its node's deadline later. An ordered set of deadlines
//! updated per heartbeat cost about 900 instructions per heartbeat (a
//! remove and an insert, or a lazy entry coming due every two periods);
//! measured in docs/performance.md. Here nodes are kept in fixed groups,
//! each with a time no later than its members' earliest deadline. A
//! heartbeat that moves a deadline later changes nothing here (the bound
//! stays a bound); when a group's bound passes, its members are checked
//! and the bound is raised to their earliest real deadline. Nodes that
//! keep beating cost one look per group member every two periods or so;
//! a hostile trace with a million nodes costs at most one group scan per
//! node that goes silent.

use std::collections::BTreeSet;

use crate::canopen::NodeId;
use crate::trace::Timestamp;

/// Members per group: a scan is cheap, and a group's bound comes due about
/// once every two heartbeat periods of its earliest member.
const GROUP: usize = 32;

/// A node of the schedule: its channel's history id and its id.
pub(super) type Member = (u32, NodeId);

#[derive(Default)]
pub(super) struct Deadlines {
    /// Every node ever scheduled, in the order they were; node `i` is in
    /// group `i / GROUP`.
    members: Vec<Member>,
    /// Per group, no later than the earliest deadline of its members
    /// (`None`: none of them had a deadline at the last look).
    bound: Vec<Option<Timestamp>>,
    /// The groups with a bound, by bound.
    due: BTreeSet<(Timestamp, u32)>,
    /// The first bound, cached: every timed frame compares its time.
    next: Option<Timestamp>,
}

impl Deadlines {
    /// Whether the clock at `now` passed a group's bound (some node may be
    /// lost; [`Deadlines::due_groups`] says which to look at).
    #[inline]
    pub(super) fn passed(&self, now: Timestamp) -> bool {
        self.next.is_some_and(|d| now > d)
    }

    /// A node got a deadline or one earlier than before. `slot` is where
    /// the node is kept (`None` the first time: it is added and `slot`
    /// set). Deadlines that move later need no call.
    pub(super) fn schedule(&mut self, slot: &mut Option<u32>, member: Member, deadline: Timestamp) {
        let i = match *slot {
            Some(i) => i as usize,
            None => {
                let i = self.members.len();
                // More members than u32 holds cannot be: every member is a
                // node of a channel, and channels come from lines.
                let Ok(i32) = u32::try_from(i) else { return };
                self.members.push(member);
                if i.is_multiple_of(GROUP) {
                    self.bound.push(None);
                }
                *slot = Some(i32);
                i
            }
        };
        let g = i / GROUP;
        let Some(bound) = self.bound.get_mut(g) else {
            return;
        };
        if bound.is_some_and(|b| b <= deadline) {
            return;
        }
        if let Some(old) = bound.replace(deadline) {
            self.due.remove(&(old, g as u32));
        }
        self.due.insert((deadline, g as u32));
        self.next = self.due.first().map(|e| e.0);
    }

    /// Takes the groups whose bound `now` passed, leaving them without a
    /// bound: the caller looks at their members ([`Deadlines::members`])
    /// and puts each group back with [`Deadlines::rebound`].
    pub(super) fn due_groups(&mut self, now: Timestamp, groups: &mut Vec<u32>) {
        while let Some(&(bound, g)) = self.due.first() {
            if now <= bound {
                break;
            }
            self.due.pop_first();
            if let Some(b) = self.bound.get_mut(g as usize) {
                *b = None;
            }
            groups.push(g);
        }
        self.next = self.due.first().map(|e| e.0);
    }

    /// The groups whose bound `now` passed, left as they are (a look that
    /// changes nothing).
    pub(super) fn passed_groups(&self, now: Timestamp) -> impl Iterator<Item = u32> + '_ {
        self.due
            .iter()
            .take_while(move |&&(bound, _)| now > bound)
            .map(|&(_, g)| g)
    }

    /// The members of group `g`.
    pub(super) fn members(&self, g: u32) -> &[Member] {
        let start = (g as usize).saturating_mul(GROUP);
        let end = start.saturating_add(GROUP).min(self.members.len());
        self.members.get(start..end).unwrap_or_default()
    }

    /// Group `g`'s members' earliest deadline after a look (`None`: none
    /// has one).
    pub(super) fn rebound(&mut self, g: u32, earliest: Option<Timestamp>) {
        let Some(bound) = self.bound.get_mut(g as usize) else {
            return;
        };
        // A member scheduled during the look may have set one already.
        let new = match (*bound, earliest) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        if let Some(old) = *bound {
            self.due.remove(&(old, g));
        }
        *bound = new;
        if let Some(b) = new {
            self.due.insert((b, g));
        }
        self.next = self.due.first().map(|e| e.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(ms: u64) -> Timestamp {
        Timestamp::from_parts(ms / 1000, ms % 1000, 3)
    }

    #[test]
    fn nothing_scheduled_nothing_passes() {
        let d = Deadlines::default();
        assert!(!d.passed(t(1_000_000)));
    }

    #[test]
    fn a_bound_passes_only_after_it() {
        let mut d = Deadlines::default();
        let mut slot = None;
        d.schedule(&mut slot, (0, 5), t(300));
        assert_eq!(slot, Some(0));
        assert!(!d.passed(t(300)), "at the deadline is still in time");
        assert!(d.passed(t(301)));
        let mut groups = Vec::new();
        d.due_groups(t(301), &mut groups);
        assert_eq!(groups, [0]);
        assert_eq!(d.members(0), [(0, 5)]);
        assert!(
            !d.passed(t(10_000)),
            "taken groups are not due until rebound"
        );
        d.rebound(0, Some(t(600)));
        assert!(!d.passed(t(600)));
        assert!(d.passed(t(601)));
    }

    #[test]
    fn a_later_deadline_keeps_the_bound_an_earlier_one_lowers_it() {
        let mut d = Deadlines::default();
        let mut slot = None;
        d.schedule(&mut slot, (0, 1), t(300));
        d.schedule(&mut slot, (0, 1), t(900));
        assert!(d.passed(t(301)), "the bound stays at the earlier time");
        let mut other = None;
        d.schedule(&mut other, (0, 2), t(100));
        assert_eq!(other, Some(1));
        assert!(
            d.passed(t(101)),
            "an earlier member lowers its group's bound"
        );
    }

    #[test]
    fn groups_hold_at_most_group_members_and_come_due_in_order() {
        let mut d = Deadlines::default();
        let mut slots = vec![None; GROUP + 3];
        for (i, slot) in slots.iter_mut().enumerate() {
            // The second group's members are due first.
            let due = if i < GROUP { 1_000 } else { 500 };
            d.schedule(slot, (0, (i % 127) as NodeId + 1), t(due + i as u64));
        }
        assert_eq!(d.members(0).len(), GROUP);
        assert_eq!(d.members(1).len(), 3);
        assert!(d.members(2).is_empty());
        let mut groups = Vec::new();
        d.due_groups(t(600), &mut groups);
        assert_eq!(groups, [1]);
        groups.clear();
        d.due_groups(t(2_000), &mut groups);
        assert_eq!(groups, [0]);
        assert!(!d.passed(t(1_000_000)));
    }

    #[test]
    fn rebound_keeps_a_bound_set_during_the_look() {
        let mut d = Deadlines::default();
        let mut slot = None;
        d.schedule(&mut slot, (0, 1), t(100));
        let mut groups = Vec::new();
        d.due_groups(t(200), &mut groups);
        d.schedule(&mut slot, (0, 1), t(250));
        d.rebound(0, Some(t(400)));
        assert!(d.passed(t(251)), "the earlier of the two stands");
        d.due_groups(t(251), &mut groups);
        d.rebound(0, None);
        assert!(
            !d.passed(t(1_000_000)),
            "no member with a deadline: never due"
        );
    }
}
