//! A node's NMT state, from what it says (heartbeats, boot-up, guarding
//! replies) and what the master asks of it (NMT commands).
//!
//! Rules (CiA 301 §7.3.2):
//! - The state is what the node said last. A boot-up is sent on entering
//!   pre-operational, so after one the node is pre-operational (`via`
//!   boot-up), whatever it was before.
//! - A command is what was asked, never the node's state: it waits for the
//!   node's answer (its next heartbeat, guarding reply or, for a reset, its
//!   boot-up), and is said as an event (`via` command) when it asks for
//!   another state than the node is in and than the command waiting asks.
//! - A heartbeat or guarding reply within [`COMMAND_GRACE_MS`] of the command
//!   that contradicts it is not its answer: the node queued it before it
//!   acted on the command. One after the grace that still contradicts it
//!   means the node ignored the command (a warning).
//! - A guarding reply's toggle bit alternates from one reply to the next,
//!   starting at 0 after a boot-up; one that does not is a warning. A guard
//!   request sent while the one before still waits for its reply is a
//!   request that got none (counted; the first of a run is a warning).
//! - An event is a change of state only.

use crate::canopen::nmt::{Command, GuardReply, NmtState};
use crate::trace::{Span, Timestamp};

/// How long after an NMT command a heartbeat or guarding reply that
/// contradicts it is still taken for one the node queued before it acted
/// on the command. CiA 301 sets no bound on how fast a node acts; the
/// stacks seen in real traces act within a few milliseconds, and a frame
/// queued in the node's controller waits a few more behind higher
/// priorities on a loaded bus (heartbeats a few ms after a start still say
/// pre-operational). 100 ms covers both with a wide margin, and is still
/// shorter than any heartbeat period commonly configured, so a node that
/// really ignored the command is told at its next heartbeat or the one
/// after. Fixed rather than a share of the heartbeat period: the queueing
/// does not scale with the period, and a node guarded or never beating
/// has none.
pub const COMMAND_GRACE_MS: u64 = 100;

/// What told the decoder the state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Via {
    Heartbeat,
    Guarding,
    Command,
    /// The node's boot-up: it entered pre-operational.
    BootUp,
    /// A PDO the node sent after a start command: CiA 301 nodes send PDOs
    /// only when operational.
    Pdo,
}

impl Via {
    /// The stable name in JSON.
    pub fn slug(self) -> &'static str {
        match self {
            Via::Heartbeat => "heartbeat",
            Via::Guarding => "guarding",
            Via::Command => "command",
            Via::BootUp => "boot_up",
            Via::Pdo => "pdo",
        }
    }
}

/// A change of NMT state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NmtChange {
    pub state: NmtState,
    pub via: Via,
}

/// Something about a node's NMT behaviour worth the user's attention.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NmtWarning {
    /// The node answered a command, after the grace, in another state
    /// than it asks for.
    IgnoredCommand { command: Command, state: NmtState },
    /// A guarding reply whose toggle bit is the one expected's opposite.
    ToggleNotAlternated { toggle: bool },
    /// A guard request was sent while the one at `line` had no reply.
    GuardUnanswered { line: u64 },
}

impl std::fmt::Display for NmtWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NmtWarning::IgnoredCommand { command, state } => write!(
                f,
                "ignored the NMT command {} (it reports {}, not {})",
                command.name(),
                state.slug(),
                command.target().slug()
            ),
            NmtWarning::ToggleNotAlternated { toggle } => write!(
                f,
                "node guarding: toggle bit error (the reply has {}, expected {})",
                u8::from(*toggle),
                u8::from(!*toggle)
            ),
            NmtWarning::GuardUnanswered { line } => write!(
                f,
                "node guarding: no reply to the guard request at line {line} (the master asked again)"
            ),
        }
    }
}

/// A command waiting for the node's answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Pending {
    command: Command,
    /// When it was sent (`None`: the trace has no times, so the next frame
    /// is its answer).
    at: Option<Timestamp>,
}

/// Node guarding of one node, counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GuardCounts {
    /// Remote requests on the node's error control id.
    pub requests: u64,
    /// Replies to them.
    pub replies: u64,
    /// Requests the master sent again without a reply to the one before.
    pub unanswered: u64,
    /// Replies whose toggle bit did not alternate.
    pub toggle_errors: u64,
}

/// The NMT side of one node.
#[derive(Clone, Debug, Default)]
pub struct NodeNmt {
    /// What the node said last.
    state: Option<NmtState>,
    /// A command still waiting for the node's answer.
    pending: Option<Pending>,
    /// The toggle the next guarding reply must not have; `None` before the
    /// first reply when no boot-up was seen (any toggle may come first).
    toggle: Option<bool>,
    /// The line of a remote request on the node's error control id that
    /// waits for its reply.
    guard_asked: Option<u64>,
    /// A request without a reply was said since the last reply.
    unanswered_said: bool,
    guard: GuardCounts,
}

impl NodeNmt {
    /// The state the node last said; `None` before it said any.
    pub fn state(&self) -> Option<NmtState> {
        self.state
    }

    /// The state a command asks for that the node has not confirmed yet.
    pub fn commanded(&self) -> Option<NmtState> {
        self.pending.map(|p| p.command.target())
    }

    /// Node guarding so far.
    pub fn guard_counts(&self) -> GuardCounts {
        self.guard
    }

    fn change(&mut self, state: NmtState, via: Via) -> Option<NmtChange> {
        (self.state != Some(state)).then(|| {
            self.state = Some(state);
            NmtChange { state, via }
        })
    }

    /// The master sent `command` to this node (or to all) at `at`: an
    /// event when it asks for a state the node is not in and no command
    /// waiting asks for already.
    pub fn command(&mut self, command: Command, at: Option<Timestamp>) -> Option<NmtChange> {
        let target = command.target();
        let new = self.state != Some(target) && self.commanded() != Some(target);
        self.pending = Some(Pending { command, at });
        new.then_some(NmtChange {
            state: target,
            via: Via::Command,
        })
    }

    /// The node said `state` at `now`: the answer to a waiting command
    /// unless it contradicts it within the grace.
    fn answer(&mut self, state: NmtState, now: Option<Timestamp>, warnings: &mut Vec<NmtWarning>) {
        let Some(p) = self.pending else { return };
        if state == p.command.target() {
            self.pending = None;
            return;
        }
        if let (Some(sent), Some(now)) = (p.at, now)
            && now.since(sent).attos() <= Span::from_millis(COMMAND_GRACE_MS).attos()
        {
            // Queued before the node acted on the command.
            return;
        }
        self.pending = None;
        warnings.push(NmtWarning::IgnoredCommand {
            command: p.command,
            state,
        });
    }

    /// The node sent a PDO (one it produces): CiA 301 nodes send PDOs only
    /// when operational, so it answers a waiting start. Without one it
    /// changes nothing: a PDO queued before a stop or a reset may still
    /// follow it, and heartbeats or guarding say the state outright.
    pub fn produced(&mut self) -> Option<NmtChange> {
        if self.commanded() != Some(NmtState::Operational) {
            return None;
        }
        self.pending = None;
        self.change(NmtState::Operational, Via::Pdo)
    }

    /// Whether a PDO from the node would confirm a waiting start
    /// ([`NodeNmt::produced`]).
    pub fn awaits_start(&self) -> bool {
        self.commanded() == Some(NmtState::Operational)
    }

    /// A heartbeat at `now` said `state` (not a boot-up: see
    /// [`NodeNmt::boot_up`]).
    pub fn heartbeat(
        &mut self,
        state: NmtState,
        now: Option<Timestamp>,
        warnings: &mut Vec<NmtWarning>,
    ) -> Option<NmtChange> {
        self.answer(state, now, warnings);
        self.change(state, Via::Heartbeat)
    }

    /// A boot-up: the node restarted and entered pre-operational. It
    /// answers a waiting reset; any other waiting command is void (the
    /// node restarted without acting on it). Always an event: the node
    /// passed through initialising even when it was pre-operational before.
    pub fn boot_up(&mut self) -> NmtChange {
        self.pending = None;
        self.toggle = Some(true);
        self.guard_asked = None;
        self.state = Some(NmtState::PreOperational);
        NmtChange {
            state: NmtState::PreOperational,
            via: Via::BootUp,
        }
    }

    /// Whether a heartbeat saying `state` would change nothing (no command
    /// waits, no guarding request, the same state).
    #[inline]
    pub fn steady(&self, state: NmtState) -> bool {
        self.state == Some(state) && self.pending.is_none() && self.guard_asked.is_none()
    }

    /// A remote request on the node's error control id at `line`: the next
    /// one-byte frame there is a guarding reply. One while the request
    /// before still waits was not answered.
    pub fn guard_request(&mut self, line: u64, warnings: &mut Vec<NmtWarning>) {
        self.guard.requests += 1;
        if let Some(before) = self.guard_asked.replace(line) {
            self.guard.unanswered += 1;
            if !self.unanswered_said {
                self.unanswered_said = true;
                warnings.push(NmtWarning::GuardUnanswered { line: before });
            }
        }
    }

    /// Whether a guarding reply is awaited.
    pub fn guard_asked(&self) -> bool {
        self.guard_asked.is_some()
    }

    /// A guarding reply at `now`.
    pub fn guard_reply(
        &mut self,
        reply: GuardReply,
        now: Option<Timestamp>,
        warnings: &mut Vec<NmtWarning>,
    ) -> Option<NmtChange> {
        self.guard_asked = None;
        self.unanswered_said = false;
        self.guard.replies += 1;
        if self.toggle == Some(reply.toggle) {
            self.guard.toggle_errors += 1;
            warnings.push(NmtWarning::ToggleNotAlternated {
                toggle: reply.toggle,
            });
        }
        self.toggle = Some(reply.toggle);
        let state = reply.state?;
        self.answer(state, now, warnings);
        self.change(state, Via::Guarding)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn change(state: NmtState, via: Via) -> Option<NmtChange> {
        Some(NmtChange { state, via })
    }

    fn ms(ms: u64) -> Option<Timestamp> {
        Some(Timestamp::from_parts(ms / 1000, ms % 1000, 3))
    }

    fn reply(toggle: bool, state: NmtState) -> GuardReply {
        GuardReply {
            toggle,
            state: Some(state),
        }
    }

    #[test]
    fn unknown_until_told() {
        assert_eq!(NodeNmt::default().state(), None);
        assert_eq!(NodeNmt::default().commanded(), None);
    }

    #[test]
    fn heartbeats_change_state_only_when_it_changes() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        assert_eq!(
            n.heartbeat(NmtState::PreOperational, ms(0), &mut w),
            change(NmtState::PreOperational, Via::Heartbeat)
        );
        assert_eq!(n.heartbeat(NmtState::PreOperational, ms(1), &mut w), None);
        assert_eq!(
            n.heartbeat(NmtState::Operational, ms(2), &mut w),
            change(NmtState::Operational, Via::Heartbeat)
        );
        assert_eq!(
            n.heartbeat(NmtState::Stopped, ms(3), &mut w),
            change(NmtState::Stopped, Via::Heartbeat)
        );
        assert_eq!(n.state(), Some(NmtState::Stopped));
        assert!(w.is_empty());
    }

    #[test]
    fn boot_up_enters_pre_operational() {
        let mut n = NodeNmt::default();
        assert_eq!(
            Some(n.boot_up()),
            change(NmtState::PreOperational, Via::BootUp)
        );
        assert_eq!(n.state(), Some(NmtState::PreOperational));
        // Again from pre-operational: still an event, it restarted.
        assert_eq!(n.boot_up().via, Via::BootUp);
    }

    #[test]
    fn a_command_is_asked_not_the_state_until_the_node_confirms() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::PreOperational, ms(0), &mut w);
        assert_eq!(
            n.command(Command::Start, ms(1000)),
            change(NmtState::Operational, Via::Command)
        );
        assert_eq!(n.state(), Some(NmtState::PreOperational), "not confirmed");
        assert_eq!(n.commanded(), Some(NmtState::Operational));
        // The same command again is no new event.
        assert_eq!(n.command(Command::Start, ms(1001)), None);
        assert_eq!(
            n.heartbeat(NmtState::Operational, ms(1010), &mut w),
            change(NmtState::Operational, Via::Heartbeat)
        );
        assert_eq!(n.commanded(), None);
        assert!(w.is_empty());
    }

    #[test]
    fn a_contradicting_heartbeat_within_the_grace_was_queued() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::PreOperational, ms(0), &mut w);
        n.command(Command::Start, ms(1000));
        // 3 ms and exactly the grace after: queued before the start.
        assert_eq!(
            n.heartbeat(NmtState::PreOperational, ms(1003), &mut w),
            None
        );
        assert_eq!(
            n.heartbeat(NmtState::PreOperational, ms(1100), &mut w),
            None
        );
        assert!(w.is_empty());
        assert_eq!(n.commanded(), Some(NmtState::Operational), "still waits");
        // Then it confirms: one change, no flicker.
        assert_eq!(
            n.heartbeat(NmtState::Operational, ms(1150), &mut w),
            change(NmtState::Operational, Via::Heartbeat)
        );
        assert!(w.is_empty());
    }

    #[test]
    fn a_contradicting_heartbeat_after_the_grace_ignored_the_command() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::PreOperational, ms(0), &mut w);
        n.command(Command::Start, ms(1000));
        assert_eq!(
            n.heartbeat(NmtState::PreOperational, ms(1101), &mut w),
            None
        );
        assert_eq!(
            w,
            [NmtWarning::IgnoredCommand {
                command: Command::Start,
                state: NmtState::PreOperational
            }]
        );
        assert_eq!(n.commanded(), None, "answered");
        w.clear();
        n.heartbeat(NmtState::PreOperational, ms(2000), &mut w);
        assert!(w.is_empty(), "said once");
    }

    #[test]
    fn without_times_the_next_heartbeat_answers() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::Operational, None, &mut w);
        n.command(Command::Stop, None);
        n.heartbeat(NmtState::Operational, None, &mut w);
        assert_eq!(w.len(), 1);
    }

    #[test]
    fn command_to_the_current_state_is_no_event() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::Operational, ms(0), &mut w);
        assert_eq!(n.command(Command::Start, ms(1)), None);
        assert_eq!(n.heartbeat(NmtState::Operational, ms(2), &mut w), None);
        assert!(w.is_empty());
    }

    #[test]
    fn reset_is_answered_by_the_boot_up() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::Operational, ms(0), &mut w);
        for reset in [Command::ResetNode, Command::ResetCommunication] {
            assert_eq!(
                n.command(reset, ms(1000)),
                change(NmtState::Initialising, Via::Command)
            );
            assert_eq!(
                Some(n.boot_up()),
                change(NmtState::PreOperational, Via::BootUp)
            );
            assert_eq!(n.commanded(), None);
            assert!(w.is_empty(), "{reset:?}");
            n.heartbeat(NmtState::Operational, ms(1500), &mut w);
        }
        // A reset answered after the grace by a heartbeat of the old state
        // was ignored.
        n.command(Command::ResetNode, ms(2000));
        n.heartbeat(NmtState::Operational, ms(2050), &mut w);
        assert!(w.is_empty(), "within the grace");
        n.heartbeat(NmtState::Operational, ms(3000), &mut w);
        assert_eq!(w.len(), 1);
    }

    #[test]
    fn a_pdo_answers_a_waiting_start_and_nothing_else() {
        let mut n = NodeNmt::default();
        n.boot_up();
        // No command waits: a PDO says nothing of the state.
        assert!(!n.awaits_start());
        assert_eq!(n.produced(), None);
        assert_eq!(n.state(), Some(NmtState::PreOperational));
        // A waiting stop is not answered by a PDO (one may be queued).
        n.command(Command::Stop, ms(0));
        assert_eq!(n.produced(), None);
        assert_eq!(n.commanded(), Some(NmtState::Stopped));
        // A waiting start is.
        n.command(Command::Start, ms(10));
        assert!(n.awaits_start());
        assert_eq!(n.produced(), change(NmtState::Operational, Via::Pdo));
        assert_eq!(n.commanded(), None);
        assert_eq!(n.produced(), None, "answered once");
        assert_eq!(Via::Pdo.slug(), "pdo");
    }

    #[test]
    fn command_before_any_heartbeat_is_commanded_only() {
        let mut n = NodeNmt::default();
        assert_eq!(
            n.command(Command::EnterPreOperational, ms(0)),
            change(NmtState::PreOperational, Via::Command)
        );
        assert_eq!(n.state(), None);
        assert_eq!(n.commanded(), Some(NmtState::PreOperational));
    }

    #[test]
    fn guarding_replies_alternate_their_toggle() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.guard_request(1, &mut w);
        assert!(n.guard_asked());
        assert_eq!(
            n.guard_reply(reply(false, NmtState::PreOperational), ms(0), &mut w),
            change(NmtState::PreOperational, Via::Guarding)
        );
        assert!(!n.guard_asked());
        assert_eq!(
            n.guard_reply(reply(true, NmtState::PreOperational), ms(1), &mut w),
            None
        );
        assert_eq!(
            n.guard_reply(reply(false, NmtState::Operational), ms(2), &mut w),
            change(NmtState::Operational, Via::Guarding)
        );
        assert!(w.is_empty());
        // Same toggle twice: a warning, the state still counts.
        assert_eq!(
            n.guard_reply(reply(false, NmtState::Stopped), ms(3), &mut w),
            change(NmtState::Stopped, Via::Guarding)
        );
        assert_eq!(w, [NmtWarning::ToggleNotAlternated { toggle: false }]);
        assert_eq!(n.guard_counts().toggle_errors, 1);
        assert_eq!(n.guard_counts().replies, 4);
    }

    #[test]
    fn the_first_reply_after_a_boot_up_has_toggle_0() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        // No boot-up seen: the first reply may have either toggle.
        n.guard_reply(reply(true, NmtState::Operational), ms(0), &mut w);
        assert!(w.is_empty());
        n.boot_up();
        n.guard_reply(reply(false, NmtState::PreOperational), ms(1), &mut w);
        assert!(w.is_empty(), "0 after the boot-up");
        n.boot_up();
        n.guard_reply(reply(true, NmtState::PreOperational), ms(2), &mut w);
        assert_eq!(w, [NmtWarning::ToggleNotAlternated { toggle: true }]);
    }

    #[test]
    fn unanswered_guard_requests_are_counted_and_said_once_a_run() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.guard_request(10, &mut w);
        n.guard_request(20, &mut w);
        n.guard_request(30, &mut w);
        assert_eq!(w, [NmtWarning::GuardUnanswered { line: 10 }]);
        assert_eq!(n.guard_counts().unanswered, 2);
        assert_eq!(n.guard_counts().requests, 3);
        n.guard_reply(reply(false, NmtState::Operational), ms(0), &mut w);
        n.guard_request(40, &mut w);
        n.guard_request(50, &mut w);
        assert_eq!(w.len(), 2, "a new run is said again");
        assert_eq!(w[1], NmtWarning::GuardUnanswered { line: 40 });
    }

    #[test]
    fn guarding_reply_answers_a_command() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::PreOperational, ms(0), &mut w);
        n.command(Command::Start, ms(100));
        n.guard_reply(reply(true, NmtState::PreOperational), ms(500), &mut w);
        assert_eq!(
            w,
            [NmtWarning::IgnoredCommand {
                command: Command::Start,
                state: NmtState::PreOperational
            }]
        );
        assert_eq!(n.state(), Some(NmtState::PreOperational));
    }

    #[test]
    fn warnings_read_well() {
        let w = NmtWarning::IgnoredCommand {
            command: Command::Stop,
            state: NmtState::Operational,
        };
        assert_eq!(
            w.to_string(),
            "ignored the NMT command stop (it reports operational, not stopped)"
        );
        assert_eq!(
            NmtWarning::ToggleNotAlternated { toggle: true }.to_string(),
            "node guarding: toggle bit error (the reply has 1, expected 0)"
        );
        assert!(
            NmtWarning::GuardUnanswered { line: 7 }
                .to_string()
                .contains("line 7")
        );
    }
}
