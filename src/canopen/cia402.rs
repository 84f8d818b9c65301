//! CiA 402 (drives and motion control): the statusword (0x6041) read as the
//! drive's state, the controlword (0x6040) read as the master's command.
//!
//! Pure functions of one 16-bit word, no allocation: the pipeline calls them
//! for every PDO that carries a word (thousands a second per drive).

/// Object 0x6040: controlword (master to drive).
pub const CONTROLWORD: u16 = 0x6040;
/// Object 0x6041: statusword (drive to master).
pub const STATUSWORD: u16 = 0x6041;
/// Object 0x603F: error code (the drive's last fault, often the EMCY code).
pub const ERROR_CODE: u16 = 0x603F;

/// The objects of this profile the decoder reads out of PDOs and SDOs.
/// Whether `index` is an object the drive state is decoded from: the
/// statusword, controlword and error code. A `match`: asked of every SDO
/// frame (a slice search cost some 35 instructions a frame).
#[inline]
pub fn is_decoded(index: u16) -> bool {
    matches!(index, STATUSWORD | CONTROLWORD | ERROR_CODE)
}

/// A state of the CiA 402 power drive state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum State {
    NotReadyToSwitchOn,
    SwitchOnDisabled,
    ReadyToSwitchOn,
    SwitchedOn,
    OperationEnabled,
    QuickStopActive,
    FaultReactionActive,
    Fault,
}

/// The statusword masks and values of CiA 402 (bits 0-3, 5, 6): states
/// that do not look at bit 5 (quick stop) use the narrower mask 0x004F.
/// Bit patterns matching no row are not a state ([`State::of_statusword`]
/// answers `None`): drives send them while booting or when broken.
const STATUS_TABLE: [(u16, u16, State); 8] = [
    (0x004F, 0x0000, State::NotReadyToSwitchOn),
    (0x004F, 0x0040, State::SwitchOnDisabled),
    (0x006F, 0x0021, State::ReadyToSwitchOn),
    (0x006F, 0x0023, State::SwitchedOn),
    (0x006F, 0x0027, State::OperationEnabled),
    (0x006F, 0x0007, State::QuickStopActive),
    (0x004F, 0x000F, State::FaultReactionActive),
    (0x004F, 0x0008, State::Fault),
];

/// Statusword bit 7: a warning (the drive runs on; not a fault).
const WARNING_BIT: u16 = 1 << 7;

/// The statusword bits anything decoded depends on: the state masks of
/// [`State::of_statusword`] (0x6F) and the warning bit. A drive toggles
/// others many times a second (target reached, set-point acknowledge); a
/// word differing only there repeats the one before.
pub const STATUSWORD_BITS: u16 = 0x006F | WARNING_BIT;

/// The controlword bits [`Command::of_controlword`] reads: 0-3 and the
/// fault reset bit 7.
pub const CONTROLWORD_BITS: u16 = 0x008F;

impl State {
    /// Every state, in the order of the standard's table (and of
    /// [`State::index`]).
    pub const ALL: [State; 8] = [
        State::NotReadyToSwitchOn,
        State::SwitchOnDisabled,
        State::ReadyToSwitchOn,
        State::SwitchedOn,
        State::OperationEnabled,
        State::QuickStopActive,
        State::FaultReactionActive,
        State::Fault,
    ];

    /// The state a statusword shows, by the standard's masks; `None` for a
    /// bit pattern that is no state (e.g. 0x0041, 0x0002).
    pub fn of_statusword(statusword: u16) -> Option<State> {
        STATUS_TABLE
            .iter()
            .find(|&&(mask, value, _)| statusword & mask == value)
            .map(|&(_, _, state)| state)
    }

    /// The stable name in JSON (`operation_enabled`): the contract users
    /// script against.
    pub fn slug(self) -> &'static str {
        match self {
            State::NotReadyToSwitchOn => "not_ready_to_switch_on",
            State::SwitchOnDisabled => "switch_on_disabled",
            State::ReadyToSwitchOn => "ready_to_switch_on",
            State::SwitchedOn => "switched_on",
            State::OperationEnabled => "operation_enabled",
            State::QuickStopActive => "quick_stop_active",
            State::FaultReactionActive => "fault_reaction_active",
            State::Fault => "fault",
        }
    }

    /// The words a summary sentence uses ("operation enabled").
    pub fn words(self) -> &'static str {
        match self {
            State::NotReadyToSwitchOn => "not ready to switch on",
            State::SwitchOnDisabled => "switch on disabled",
            State::ReadyToSwitchOn => "ready to switch on",
            State::SwitchedOn => "switched on",
            State::OperationEnabled => "operation enabled",
            State::QuickStopActive => "quick stop active",
            State::FaultReactionActive => "fault reaction active",
            State::Fault => "fault",
        }
    }

    /// 0-7, the position in [`State::ALL`]: per-state totals live in arrays.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Fault reaction active or fault: the drive has faulted and waits
    /// (after the reaction) for a fault reset.
    pub fn is_fault(self) -> bool {
        matches!(self, State::FaultReactionActive | State::Fault)
    }
}

/// Whether the statusword's warning bit (7) is set.
pub fn warning(statusword: u16) -> bool {
    statusword & WARNING_BIT != 0
}

/// A device-control command of the controlword (bits 0-3 and 7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Command {
    /// 0xxx x110: to ready to switch on.
    Shutdown,
    /// 0xxx 0111 outside operation enabled: to switched on.
    SwitchOn,
    /// 0xxx 1111 in ready to switch on: switched on and enabled at once.
    SwitchOnEnableOperation,
    /// 0xxx xx0x: to switch on disabled.
    DisableVoltage,
    /// 0xxx x01x: to quick stop active.
    QuickStop,
    /// 0xxx 0111 in operation enabled: back to switched on.
    DisableOperation,
    /// 0xxx 1111: to operation enabled.
    EnableOperation,
    /// Bit 7 rising: leave fault for switch on disabled.
    FaultReset,
}

/// Controlword bit 7: fault reset, acted on at its rising edge.
const FAULT_RESET_BIT: u16 = 1 << 7;

impl Command {
    /// The stable name in JSON (`enable_operation`).
    pub fn slug(self) -> &'static str {
        match self {
            Command::Shutdown => "shutdown",
            Command::SwitchOn => "switch_on",
            Command::SwitchOnEnableOperation => "switch_on_enable_operation",
            Command::DisableVoltage => "disable_voltage",
            Command::QuickStop => "quick_stop",
            Command::DisableOperation => "disable_operation",
            Command::EnableOperation => "enable_operation",
            Command::FaultReset => "fault_reset",
        }
    }

    /// The command a controlword gives, given the word before it (`None`
    /// for the first one seen) and the drive's state as last reported.
    ///
    /// Fault reset is the rising edge of bit 7, so it needs the word before;
    /// while bit 7 stays set no other command is given (the standard's rows
    /// all have bit 7 clear). Switch on and disable operation share a bit
    /// pattern (0x07), as do enable operation and switch on + enable
    /// operation (0x0F): the state tells them apart.
    pub fn of_controlword(
        controlword: u16,
        previous: Option<u16>,
        state: Option<State>,
    ) -> Option<Command> {
        if controlword & FAULT_RESET_BIT != 0 {
            let rising = previous.is_none_or(|p| p & FAULT_RESET_BIT == 0);
            return rising.then_some(Command::FaultReset);
        }
        // Bit 1 (enable voltage) clear: disable voltage whatever else.
        if controlword & 0b0010 == 0 {
            return Some(Command::DisableVoltage);
        }
        // Bit 2 (quick stop, active low) clear: quick stop.
        if controlword & 0b0100 == 0 {
            return Some(Command::QuickStop);
        }
        // Bits 2 and 1 set: bit 0 (switch on) and bit 3 (enable operation).
        Some(match controlword & 0b1001 {
            0b0000 | 0b1000 => Command::Shutdown,
            0b0001 if state == Some(State::OperationEnabled) => Command::DisableOperation,
            0b0001 => Command::SwitchOn,
            _ if state == Some(State::ReadyToSwitchOn) => Command::SwitchOnEnableOperation,
            _ => Command::EnableOperation,
        })
    }
}

/// Whether controlword bit 7 rises from `previous` to `controlword`: a
/// fault reset. The first word seen (`previous` is `None`) counts when its
/// bit is set, since the trace may start between two words.
#[cfg(test)] // The pipeline gets the edge from Command::of_controlword.
pub fn fault_reset_edge(previous: Option<u16>, controlword: u16) -> bool {
    controlword & FAULT_RESET_BIT != 0 && previous.is_none_or(|p| p & FAULT_RESET_BIT == 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row of the standard's statusword table, with bits the row
    /// ignores set both ways.
    #[test]
    fn statusword_table_rows() {
        let rows: [(u16, State); 16] = [
            (0x0000, State::NotReadyToSwitchOn),
            (0x0020, State::NotReadyToSwitchOn),
            (0x0040, State::SwitchOnDisabled),
            (0x0060, State::SwitchOnDisabled),
            (0x0021, State::ReadyToSwitchOn),
            (0x0031, State::ReadyToSwitchOn),
            (0x0023, State::SwitchedOn),
            (0x0233, State::SwitchedOn),
            (0x0027, State::OperationEnabled),
            (0x0637, State::OperationEnabled),
            (0x0007, State::QuickStopActive),
            (0x0217, State::QuickStopActive),
            (0x000F, State::FaultReactionActive),
            (0x002F, State::FaultReactionActive),
            (0x0008, State::Fault),
            (0x0228, State::Fault),
        ];
        for (word, state) in rows {
            assert_eq!(State::of_statusword(word), Some(state), "{word:#06x}");
            // Bits 4, 7-15 are never part of the state.
            assert_eq!(
                State::of_statusword(word | 0xFF90),
                Some(state),
                "{word:#06x}"
            );
        }
    }

    #[test]
    fn patterns_no_row_matches_are_no_state() {
        // Bit 6 with a nonzero low nibble; ready-like nibbles without bit 5
        // (except quick stop's 0111); nibbles no row has.
        for word in [
            0x0041, 0x0047, 0x004F, 0x0048, 0x0001, 0x0003, 0x0002, 0x0004, 0x0005, 0x0006, 0x0009,
            0x000A, 0x000B, 0x000C, 0x000D, 0x000E, 0x0061, 0x0067,
        ] {
            assert_eq!(State::of_statusword(word), None, "{word:#06x}");
        }
    }

    /// The table decides every word: exactly one row or none matches.
    #[test]
    fn rows_never_overlap() {
        for word in 0..=u16::MAX {
            let matching = STATUS_TABLE
                .iter()
                .filter(|&&(mask, value, _)| word & mask == value)
                .count();
            assert!(matching <= 1, "{word:#06x} matches {matching} rows");
        }
    }

    #[test]
    fn slugs_are_the_json_contract() {
        let slugs: Vec<&str> = State::ALL.iter().map(|s| s.slug()).collect();
        assert_eq!(
            slugs,
            [
                "not_ready_to_switch_on",
                "switch_on_disabled",
                "ready_to_switch_on",
                "switched_on",
                "operation_enabled",
                "quick_stop_active",
                "fault_reaction_active",
                "fault",
            ]
        );
        for (i, s) in State::ALL.iter().enumerate() {
            assert_eq!(s.index(), i);
            assert_eq!(s.words(), s.slug().replace('_', " "));
        }
    }

    #[test]
    fn fault_states() {
        let faults: Vec<State> = State::ALL.into_iter().filter(|s| s.is_fault()).collect();
        assert_eq!(faults, [State::FaultReactionActive, State::Fault]);
    }

    #[test]
    fn warning_is_bit_7() {
        assert!(warning(0x00A7));
        assert!(!warning(0x0027));
        assert!(!warning(0xFF7F));
        // The warning does not change the state.
        assert_eq!(State::of_statusword(0x00A7), Some(State::OperationEnabled));
    }

    fn cmd(word: u16, state: Option<State>) -> Option<Command> {
        Command::of_controlword(word, Some(0), state)
    }

    #[test]
    fn controlword_table_rows() {
        use Command::*;
        let any = None;
        assert_eq!(cmd(0x0006, any), Some(Shutdown));
        assert_eq!(cmd(0x000E, any), Some(Shutdown), "bit 3 ignored");
        assert_eq!(cmd(0x0007, Some(State::SwitchOnDisabled)), Some(SwitchOn));
        assert_eq!(cmd(0x0007, Some(State::ReadyToSwitchOn)), Some(SwitchOn));
        assert_eq!(cmd(0x0007, any), Some(SwitchOn));
        assert_eq!(
            cmd(0x0007, Some(State::OperationEnabled)),
            Some(DisableOperation)
        );
        assert_eq!(
            cmd(0x000F, Some(State::ReadyToSwitchOn)),
            Some(SwitchOnEnableOperation)
        );
        assert_eq!(cmd(0x000F, Some(State::SwitchedOn)), Some(EnableOperation));
        assert_eq!(
            cmd(0x000F, Some(State::QuickStopActive)),
            Some(EnableOperation)
        );
        assert_eq!(cmd(0x000F, any), Some(EnableOperation));
        for word in [0x0000, 0x0001, 0x0004, 0x0005, 0x0008, 0x000D] {
            assert_eq!(cmd(word, any), Some(DisableVoltage), "{word:#06x}");
        }
        for word in [0x0002, 0x0003, 0x000A, 0x000B] {
            assert_eq!(cmd(word, any), Some(QuickStop), "{word:#06x}");
        }
        // Mode-specific and manufacturer bits (4-6, 8-15) change nothing.
        assert_eq!(cmd(0xFF7F, Some(State::SwitchedOn)), Some(EnableOperation));
        assert_eq!(cmd(0x0106, any), Some(Shutdown));
    }

    #[test]
    fn fault_reset_is_the_rising_edge_of_bit_7() {
        assert_eq!(
            Command::of_controlword(0x0080, Some(0x0000), Some(State::Fault)),
            Some(Command::FaultReset)
        );
        assert_eq!(
            Command::of_controlword(0x0086, Some(0x0006), None),
            Some(Command::FaultReset)
        );
        // Held high: no command, not a second reset.
        assert_eq!(
            Command::of_controlword(0x0080, Some(0x0080), Some(State::Fault)),
            None
        );
        assert_eq!(Command::of_controlword(0x008F, Some(0x0080), None), None);
        // The first word seen counts.
        assert_eq!(
            Command::of_controlword(0x0080, None, None),
            Some(Command::FaultReset)
        );
        assert!(fault_reset_edge(Some(0x0000), 0x0080));
        assert!(fault_reset_edge(None, 0x0080));
        assert!(!fault_reset_edge(Some(0x0080), 0x0080));
        assert!(!fault_reset_edge(Some(0x0080), 0x0000));
        assert!(!fault_reset_edge(Some(0x0000), 0x000F));
    }

    #[test]
    fn command_slugs() {
        assert_eq!(Command::FaultReset.slug(), "fault_reset");
        assert_eq!(
            Command::SwitchOnEnableOperation.slug(),
            "switch_on_enable_operation"
        );
    }
}
