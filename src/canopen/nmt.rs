//! NMT (CiA 301 §7.2.8): node states, the error control frames a node sends
//! on 0x700 + node (boot-up, heartbeat, node-guarding reply) and the
//! commands the master sends on id 0x000.

use super::NodeId;

/// The NMT master's command id.
pub const COMMAND_ID: u32 = 0x000;

/// A node's NMT state, as its heartbeat or guarding reply encodes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NmtState {
    /// 0x00: boot-up (the node has just initialised).
    Initialising,
    /// 0x04.
    Stopped,
    /// 0x05.
    Operational,
    /// 0x7F.
    PreOperational,
}

impl NmtState {
    /// The state a heartbeat or guarding reply byte (bits 0-6) names.
    pub fn from_byte(b: u8) -> Option<NmtState> {
        match b {
            0x00 => Some(NmtState::Initialising),
            0x04 => Some(NmtState::Stopped),
            0x05 => Some(NmtState::Operational),
            0x7F => Some(NmtState::PreOperational),
            _ => None,
        }
    }

    /// The stable name in JSON (`pre_operational`).
    pub fn slug(self) -> &'static str {
        match self {
            NmtState::Initialising => "initialising",
            NmtState::Stopped => "stopped",
            NmtState::Operational => "operational",
            NmtState::PreOperational => "pre_operational",
        }
    }

    /// A short name for tables (`pre-op`).
    pub fn short(self) -> &'static str {
        match self {
            NmtState::Initialising => "init",
            NmtState::Stopped => "stopped",
            NmtState::Operational => "operational",
            NmtState::PreOperational => "pre-op",
        }
    }
}

/// An NMT node control command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Command {
    /// 0x01 start remote node.
    Start,
    /// 0x02 stop remote node.
    Stop,
    /// 0x80 enter pre-operational.
    EnterPreOperational,
    /// 0x81 reset node.
    ResetNode,
    /// 0x82 reset communication.
    ResetCommunication,
}

impl Command {
    pub fn from_byte(b: u8) -> Option<Command> {
        match b {
            0x01 => Some(Command::Start),
            0x02 => Some(Command::Stop),
            0x80 => Some(Command::EnterPreOperational),
            0x81 => Some(Command::ResetNode),
            0x82 => Some(Command::ResetCommunication),
            _ => None,
        }
    }

    /// The state a node that obeys is in next: a reset passes through
    /// initialising (the boot-up) on its way to pre-operational.
    pub fn target(self) -> NmtState {
        match self {
            Command::Start => NmtState::Operational,
            Command::Stop => NmtState::Stopped,
            Command::EnterPreOperational => NmtState::PreOperational,
            Command::ResetNode | Command::ResetCommunication => NmtState::Initialising,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Command::Start => "start",
            Command::Stop => "stop",
            Command::EnterPreOperational => "enter pre-operational",
            Command::ResetNode => "reset node",
            Command::ResetCommunication => "reset communication",
        }
    }

    /// The stable name in JSON (`reset_node`).
    pub fn slug(self) -> &'static str {
        match self {
            Command::Start => "start",
            Command::Stop => "stop",
            Command::EnterPreOperational => "enter_pre_operational",
            Command::ResetNode => "reset_node",
            Command::ResetCommunication => "reset_communication",
        }
    }

    /// Every command, in the order of their bytes.
    pub const ALL: [Command; 5] = [
        Command::Start,
        Command::Stop,
        Command::EnterPreOperational,
        Command::ResetNode,
        Command::ResetCommunication,
    ];

    /// The command's place in [`Command::ALL`], for tables of counts.
    pub fn index(self) -> usize {
        match self {
            Command::Start => 0,
            Command::Stop => 1,
            Command::EnterPreOperational => 2,
            Command::ResetNode => 3,
            Command::ResetCommunication => 4,
        }
    }

    /// Whether the command restarts the node (answered by a boot-up).
    pub fn is_reset(self) -> bool {
        matches!(self, Command::ResetNode | Command::ResetCommunication)
    }
}

/// Who an NMT command addresses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// Node 0: every node.
    All,
    Node(NodeId),
}

/// Reads an NMT command frame (id 0x000, two bytes: command, node).
pub fn parse_command(id: u32, data: &[u8]) -> Option<(Command, Target)> {
    if id != COMMAND_ID {
        return None;
    }
    let &[cs, node] = data else { return None };
    let command = Command::from_byte(cs)?;
    let target = match node {
        0 => Target::All,
        1..=127 => Target::Node(NodeId::from(node)),
        _ => return None,
    };
    Some((command, target))
}

/// What a data frame on 0x700 + node says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorControl {
    /// One byte, bit 7 clear: a heartbeat (0x00 is the boot-up).
    Heartbeat { node: NodeId, state: NmtState },
    /// One byte with a state the standard does not define (bits 0-6), or
    /// with bit 7 set outside guarding: only a guarding reply may toggle.
    Unknown { node: NodeId, byte: u8 },
}

/// The node of an NMT error control id (0x701-0x77F).
pub fn error_control_node(id: u32) -> Option<NodeId> {
    let node = id.checked_sub(super::emcy::NMT_ERROR_CONTROL_BASE)?;
    (1..=127).contains(&node).then_some(node as NodeId)
}

/// Reads a data frame on an NMT error control id; `None` for other ids and
/// for frames that are not one byte long.
pub fn parse_error_control(id: u32, data: &[u8]) -> Option<ErrorControl> {
    let node = error_control_node(id)?;
    let &[byte] = data else { return None };
    Some(match NmtState::from_byte(byte) {
        Some(state) => ErrorControl::Heartbeat { node, state },
        None => ErrorControl::Unknown { node, byte },
    })
}

/// A node-guarding reply: bit 7 the toggle, bits 0-6 the state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GuardReply {
    pub toggle: bool,
    pub state: Option<NmtState>,
}

/// Reads the byte of a guarding reply (a frame answering a remote request).
pub fn guard_reply(byte: u8) -> GuardReply {
    GuardReply {
        toggle: byte & 0x80 != 0,
        state: NmtState::from_byte(byte & 0x7F),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn states_by_byte() {
        assert_eq!(NmtState::from_byte(0x00), Some(NmtState::Initialising));
        assert_eq!(NmtState::from_byte(0x04), Some(NmtState::Stopped));
        assert_eq!(NmtState::from_byte(0x05), Some(NmtState::Operational));
        assert_eq!(NmtState::from_byte(0x7F), Some(NmtState::PreOperational));
        for b in [0x01, 0x02, 0x03, 0x06, 0x7E, 0x80, 0x85, 0xFF] {
            assert_eq!(NmtState::from_byte(b), None, "{b:#x}");
        }
        assert_eq!(NmtState::PreOperational.slug(), "pre_operational");
        assert_eq!(NmtState::Initialising.slug(), "initialising");
        assert_eq!(NmtState::Operational.slug(), "operational");
        assert_eq!(NmtState::Stopped.slug(), "stopped");
    }

    #[test]
    fn command_table_indexes_every_command_once() {
        for (i, c) in Command::ALL.iter().enumerate() {
            assert_eq!(c.index(), i, "{c:?}");
        }
        assert_eq!(Command::ResetNode.slug(), "reset_node");
        assert!(Command::ResetCommunication.is_reset());
        assert!(!Command::Start.is_reset());
    }

    #[test]
    fn commands_and_targets() {
        assert_eq!(
            parse_command(0, &[0x01, 0x00]),
            Some((Command::Start, Target::All))
        );
        assert_eq!(
            parse_command(0, &[0x02, 0x05]),
            Some((Command::Stop, Target::Node(5)))
        );
        assert_eq!(
            parse_command(0, &[0x80, 0x7F]),
            Some((Command::EnterPreOperational, Target::Node(127)))
        );
        assert_eq!(
            parse_command(0, &[0x81, 3]),
            Some((Command::ResetNode, Target::Node(3)))
        );
        assert_eq!(
            parse_command(0, &[0x82, 3]),
            Some((Command::ResetCommunication, Target::Node(3)))
        );
        assert_eq!(parse_command(0, &[0x03, 0]), None, "no such command");
        assert_eq!(parse_command(0, &[0x01, 0x80]), None, "node 128");
        assert_eq!(parse_command(0, &[0x01]), None, "short");
        assert_eq!(parse_command(0, &[0x01, 0, 0]), None, "long");
        assert_eq!(parse_command(0x001, &[0x01, 0]), None, "other id");
    }

    #[test]
    fn command_targets_are_the_states_an_obedient_node_reaches() {
        assert_eq!(Command::Start.target(), NmtState::Operational);
        assert_eq!(Command::Stop.target(), NmtState::Stopped);
        assert_eq!(
            Command::EnterPreOperational.target(),
            NmtState::PreOperational
        );
        assert_eq!(Command::ResetNode.target(), NmtState::Initialising);
        assert_eq!(Command::ResetCommunication.target(), NmtState::Initialising);
    }

    #[test]
    fn error_control_frames() {
        assert_eq!(
            parse_error_control(0x705, &[0x05]),
            Some(ErrorControl::Heartbeat {
                node: 5,
                state: NmtState::Operational
            })
        );
        assert_eq!(
            parse_error_control(0x77F, &[0x00]),
            Some(ErrorControl::Heartbeat {
                node: 127,
                state: NmtState::Initialising
            })
        );
        assert_eq!(
            parse_error_control(0x701, &[0x85]),
            Some(ErrorControl::Unknown {
                node: 1,
                byte: 0x85
            })
        );
        assert_eq!(parse_error_control(0x700, &[0x05]), None);
        assert_eq!(parse_error_control(0x780, &[0x05]), None);
        assert_eq!(parse_error_control(0x705, &[]), None);
        assert_eq!(parse_error_control(0x705, &[0x05, 0]), None);
    }

    #[test]
    fn guard_replies_carry_toggle_and_state() {
        assert_eq!(
            guard_reply(0x85),
            GuardReply {
                toggle: true,
                state: Some(NmtState::Operational)
            }
        );
        assert_eq!(
            guard_reply(0x7F),
            GuardReply {
                toggle: false,
                state: Some(NmtState::PreOperational)
            }
        );
        assert_eq!(guard_reply(0x83).state, None);
    }

    proptest::proptest! {
        /// Any frame: a command exactly when id 0 carries two bytes, a
        /// known command and a node 0-127.
        #[test]
        fn command_parse_matches_its_definition(
            id in 0u32..0x800,
            data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..9),
        ) {
            let expected = id == 0
                && data.len() == 2
                && Command::from_byte(data[0]).is_some()
                && data[1] <= 127;
            proptest::prop_assert_eq!(parse_command(id, &data).is_some(), expected);
        }

        /// Any frame: error control exactly for one byte on 0x701-0x77F,
        /// a heartbeat exactly when the byte names a state.
        #[test]
        fn error_control_parse_matches_its_definition(
            id in 0u32..0x800,
            data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..9),
        ) {
            let got = parse_error_control(id, &data);
            let ours = (0x701..=0x77F).contains(&id) && data.len() == 1;
            proptest::prop_assert_eq!(got.is_some(), ours);
            if let Some(ErrorControl::Heartbeat { node, state }) = got {
                proptest::prop_assert_eq!(u32::from(node), id - 0x700);
                proptest::prop_assert_eq!(NmtState::from_byte(data[0]), Some(state));
            }
        }
    }
}
