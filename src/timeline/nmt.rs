//! A node's NMT state, from what it says (heartbeats, boot-up, guarding
//! replies) and what the master asks of it (NMT commands).
//!
//! Rules:
//! - A command is what was asked: when it would change the state, the state
//!   becomes the command's target (`via` command) and the command waits for
//!   the node's next heartbeat or guarding reply.
//! - A heartbeat or guarding reply is what happened: the state becomes what
//!   it says (`via` heartbeat / guarding) when that is a change. A node that
//!   answers a waiting command in another state ignored it (a warning).
//! - A guarding reply's toggle bit alternates from one reply to the next,
//!   starting at 0 after a boot-up; one that does not is a warning.
//! - An event is a change of state only.

use crate::canopen::nmt::{Command, GuardReply, NmtState};

/// What told the decoder the state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Via {
    Heartbeat,
    Guarding,
    Command,
}

impl Via {
    /// The stable name in JSON.
    pub fn slug(self) -> &'static str {
        match self {
            Via::Heartbeat => "heartbeat",
            Via::Guarding => "guarding",
            Via::Command => "command",
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
    /// The node answered a command in another state than it asks for.
    IgnoredCommand { command: Command, state: NmtState },
    /// Two guarding replies in a row with the same toggle bit.
    ToggleNotAlternated { toggle: bool },
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
                "node guarding: the toggle bit did not alternate (two replies with {})",
                u8::from(*toggle)
            ),
        }
    }
}

/// The NMT side of one node.
#[derive(Clone, Debug, Default)]
pub struct NodeNmt {
    state: Option<NmtState>,
    /// A command still waiting for the node's answer.
    pending: Option<Command>,
    /// The toggle of the last guarding reply; `None` after a boot-up.
    toggle: Option<bool>,
    /// A remote request on the node's error control id waits for a reply.
    guard_asked: bool,
}

impl NodeNmt {
    /// The state as far as the trace tells; `None` before anything said.
    pub fn state(&self) -> Option<NmtState> {
        self.state
    }

    fn change(&mut self, state: NmtState, via: Via) -> Option<NmtChange> {
        (self.state != Some(state)).then(|| {
            self.state = Some(state);
            NmtChange { state, via }
        })
    }

    /// The master sent `command` to this node (or to all).
    pub fn command(&mut self, command: Command) -> Option<NmtChange> {
        self.pending = Some(command);
        self.change(command.target(), Via::Command)
    }

    /// The node's answer to a waiting command is `state`.
    fn answer(&mut self, state: NmtState, warnings: &mut Vec<NmtWarning>) {
        if let Some(command) = self.pending.take()
            && state != command.target()
        {
            warnings.push(NmtWarning::IgnoredCommand { command, state });
        }
    }

    /// A heartbeat (or boot-up, `Initialising`) said `state`.
    pub fn heartbeat(
        &mut self,
        state: NmtState,
        warnings: &mut Vec<NmtWarning>,
    ) -> Option<NmtChange> {
        self.answer(state, warnings);
        if state == NmtState::Initialising {
            self.toggle = None;
            self.guard_asked = false;
        }
        self.change(state, Via::Heartbeat)
    }

    /// Whether a heartbeat saying `state` would change nothing (no command
    /// waits, no guarding request, the same state).
    #[inline]
    pub fn steady(&self, state: NmtState) -> bool {
        self.state == Some(state) && self.pending.is_none() && !self.guard_asked
    }

    /// A remote request on the node's error control id: the next one-byte
    /// frame there is a guarding reply.
    pub fn guard_request(&mut self) {
        self.guard_asked = true;
    }

    /// Whether a guarding reply is awaited.
    pub fn guard_asked(&self) -> bool {
        self.guard_asked
    }

    /// A guarding reply.
    pub fn guard_reply(
        &mut self,
        reply: GuardReply,
        warnings: &mut Vec<NmtWarning>,
    ) -> Option<NmtChange> {
        self.guard_asked = false;
        if self.toggle == Some(reply.toggle) {
            warnings.push(NmtWarning::ToggleNotAlternated {
                toggle: reply.toggle,
            });
        }
        self.toggle = Some(reply.toggle);
        let state = reply.state?;
        self.answer(state, warnings);
        self.change(state, Via::Guarding)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn change(state: NmtState, via: Via) -> Option<NmtChange> {
        Some(NmtChange { state, via })
    }

    #[test]
    fn unknown_until_told() {
        assert_eq!(NodeNmt::default().state(), None);
    }

    #[test]
    fn heartbeats_change_state_only_when_it_changes() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        assert_eq!(
            n.heartbeat(NmtState::Initialising, &mut w),
            change(NmtState::Initialising, Via::Heartbeat)
        );
        assert_eq!(
            n.heartbeat(NmtState::PreOperational, &mut w),
            change(NmtState::PreOperational, Via::Heartbeat)
        );
        assert_eq!(n.heartbeat(NmtState::PreOperational, &mut w), None);
        assert_eq!(
            n.heartbeat(NmtState::Operational, &mut w),
            change(NmtState::Operational, Via::Heartbeat)
        );
        assert_eq!(
            n.heartbeat(NmtState::Stopped, &mut w),
            change(NmtState::Stopped, Via::Heartbeat)
        );
        assert_eq!(n.state(), Some(NmtState::Stopped));
        assert!(w.is_empty());
    }

    #[test]
    fn obeyed_command_changes_state_once() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::PreOperational, &mut w);
        assert_eq!(
            n.command(Command::Start),
            change(NmtState::Operational, Via::Command)
        );
        // The node confirms: no second event, no warning.
        assert_eq!(n.heartbeat(NmtState::Operational, &mut w), None);
        assert!(w.is_empty());
    }

    #[test]
    fn ignored_command_is_a_warning_and_the_heartbeat_wins() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::Operational, &mut w);
        assert_eq!(
            n.command(Command::Stop),
            change(NmtState::Stopped, Via::Command)
        );
        assert_eq!(
            n.heartbeat(NmtState::Operational, &mut w),
            change(NmtState::Operational, Via::Heartbeat)
        );
        assert_eq!(
            w,
            [NmtWarning::IgnoredCommand {
                command: Command::Stop,
                state: NmtState::Operational
            }]
        );
        // Answered: the next heartbeat says nothing new.
        w.clear();
        assert_eq!(n.heartbeat(NmtState::Operational, &mut w), None);
        assert!(w.is_empty());
    }

    #[test]
    fn command_to_the_current_state_is_no_event() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::Operational, &mut w);
        assert_eq!(n.command(Command::Start), None);
        assert_eq!(n.heartbeat(NmtState::Operational, &mut w), None);
        assert!(w.is_empty());
    }

    #[test]
    fn reset_is_answered_by_the_boot_up() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::Operational, &mut w);
        for reset in [Command::ResetNode, Command::ResetCommunication] {
            assert_eq!(
                n.command(reset),
                change(NmtState::Initialising, Via::Command)
            );
            assert_eq!(n.heartbeat(NmtState::Initialising, &mut w), None);
            assert_eq!(
                n.heartbeat(NmtState::PreOperational, &mut w),
                change(NmtState::PreOperational, Via::Heartbeat)
            );
            assert!(w.is_empty(), "{reset:?}");
        }
        // A reset answered by a heartbeat of the old state was ignored.
        n.command(Command::ResetNode);
        n.heartbeat(NmtState::PreOperational, &mut w);
        assert_eq!(w.len(), 1);
    }

    #[test]
    fn command_before_any_heartbeat_sets_the_state() {
        let mut n = NodeNmt::default();
        assert_eq!(
            n.command(Command::EnterPreOperational),
            change(NmtState::PreOperational, Via::Command)
        );
        assert_eq!(n.state(), Some(NmtState::PreOperational));
    }

    #[test]
    fn guarding_replies_alternate_their_toggle() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.guard_request();
        assert!(n.guard_asked());
        let reply = |toggle, state| GuardReply {
            toggle,
            state: Some(state),
        };
        assert_eq!(
            n.guard_reply(reply(false, NmtState::PreOperational), &mut w),
            change(NmtState::PreOperational, Via::Guarding)
        );
        assert!(!n.guard_asked());
        assert_eq!(
            n.guard_reply(reply(true, NmtState::PreOperational), &mut w),
            None
        );
        assert_eq!(
            n.guard_reply(reply(false, NmtState::Operational), &mut w),
            change(NmtState::Operational, Via::Guarding)
        );
        assert!(w.is_empty());
        // Same toggle twice: a warning, the state still counts.
        assert_eq!(
            n.guard_reply(reply(false, NmtState::Stopped), &mut w),
            change(NmtState::Stopped, Via::Guarding)
        );
        assert_eq!(w, [NmtWarning::ToggleNotAlternated { toggle: false }]);
    }

    #[test]
    fn boot_up_restarts_the_toggle() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.guard_reply(
            GuardReply {
                toggle: false,
                state: Some(NmtState::Operational),
            },
            &mut w,
        );
        n.heartbeat(NmtState::Initialising, &mut w);
        n.guard_reply(
            GuardReply {
                toggle: false,
                state: Some(NmtState::PreOperational),
            },
            &mut w,
        );
        assert!(w.is_empty());
    }

    #[test]
    fn guarding_reply_answers_a_command() {
        let mut n = NodeNmt::default();
        let mut w = Vec::new();
        n.heartbeat(NmtState::PreOperational, &mut w);
        n.command(Command::Start);
        n.guard_reply(
            GuardReply {
                toggle: true,
                state: Some(NmtState::PreOperational),
            },
            &mut w,
        );
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
        assert!(
            NmtWarning::ToggleNotAlternated { toggle: true }
                .to_string()
                .contains("with 1")
        );
    }
}
