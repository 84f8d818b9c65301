//! One CiA 402 drive over a trace: the states its statusword showed,
//! its faults (from entering fault reaction or fault to leaving them), the
//! fault resets its master sent, and the time it spent in each state.
//!
//! The pipeline feeds every statusword and controlword it decodes (one per
//! PDO, thousands a second), so a call that changes nothing only compares a
//! word and stores a time: no allocation, no event. Closed faults are handed
//! back to the caller, as [`super::NodeTimeline`] hands back intervals: the
//! drive keeps only the open one, so its memory is constant.

use super::interval::At;
use crate::canopen::cia402::{self, Command, State};
use crate::trace::{Span, Timestamp};

/// What a statusword showed: a state of the standard's table, or a bit
/// pattern matching none of its rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DriveState {
    State(State),
    /// No row of the table matches (the drive booting, or broken).
    Unknown,
}

/// States plus unknown: the length of per-state arrays.
const SLOTS: usize = State::ALL.len() + 1;

impl DriveState {
    /// The state a statusword shows.
    pub fn of_statusword(statusword: u16) -> DriveState {
        State::of_statusword(statusword).map_or(DriveState::Unknown, DriveState::State)
    }

    /// The stable name in JSON: the state's (`operation_enabled`), or
    /// `unknown`.
    pub fn slug(self) -> &'static str {
        match self {
            DriveState::State(s) => s.slug(),
            DriveState::Unknown => "unknown",
        }
    }

    /// Whether the drive is in fault reaction active or fault.
    pub fn is_fault(self) -> bool {
        matches!(self, DriveState::State(s) if s.is_fault())
    }

    /// Its slot in per-state arrays: the state's index, unknown last.
    fn slot(self) -> usize {
        match self {
            DriveState::State(s) => s.index(),
            DriveState::Unknown => State::ALL.len(),
        }
    }

    fn of_slot(slot: usize) -> DriveState {
        State::ALL
            .get(slot)
            .copied()
            .map_or(DriveState::Unknown, DriveState::State)
    }
}

/// How a statusword reached us.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Via {
    /// In a PDO with this COB-ID.
    Pdo { cob_id: u32 },
    /// In an SDO upload (a read of 0x6041).
    Sdo,
}

impl Via {
    /// The stable name in JSON (`pdo`, `sdo`).
    pub fn slug(self) -> &'static str {
        match self {
            Via::Pdo { .. } => "pdo",
            Via::Sdo => "sdo",
        }
    }
}

/// One fault: from the statusword entering fault reaction active or fault
/// to the one showing a state outside them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fault {
    /// The statusword that entered it.
    pub start: At,
    /// The statusword that left it; `None` while the drive is in fault.
    pub end: Option<At>,
    /// The last fault reset (controlword bit 7 rising) sent while in fault:
    /// the one that cleared it, if a reset did. Earlier resets in the same
    /// fault did not take (the cause was still there). `None` when the drive
    /// left fault without one (a restart, a digital input).
    pub cleared_by: Option<At>,
    /// The EMCY code that came with the fault, when the caller attached one
    /// ([`Drive::attach_emcy`]): the pipeline knows which EMCY that is.
    pub emcy_code: Option<u16>,
    /// The first nonzero error code (0x603F) the drive reported in it.
    pub error_code: Option<u16>,
}

impl Fault {
    /// From entering fault to leaving it, at the finer precision of the two;
    /// `None` while in fault or without times.
    pub fn duration(&self) -> Option<Span> {
        Some(self.end?.time?.since(self.start.time?))
    }
}

/// A statusword that changed the drive's state.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Change {
    pub at: At,
    /// The state before; `None` for the drive's first statusword.
    pub from: Option<DriveState>,
    pub to: DriveState,
    /// The word as sent (reports print it: `0x0637`).
    pub statusword: u16,
    pub via: Via,
    /// The fault this change ended, handed over to the caller to keep.
    pub closed_fault: Option<Fault>,
    /// Whether it began a fault (not one going on through an unknown
    /// pattern): the fault is then [`Drive::open_fault`].
    pub opened_fault: bool,
}

/// A controlword that gave a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Commanded {
    pub at: At,
    pub controlword: u16,
    /// [`Command::FaultReset`] is the `fault_reset` event.
    pub command: Command,
}

/// The state of one drive (one node's drive).
#[derive(Clone, Debug, Default)]
pub struct Drive {
    state: Option<DriveState>,
    /// The last statusword, so a repeat costs one comparison.
    statusword: Option<u16>,
    controlword: Option<u16>,
    open_fault: Option<Fault>,
    faults: u64,
    fault_resets: u64,
    /// Time spent in each state ([`DriveState::slot`]) over stays that ended.
    time: [Span; SLOTS],
    /// Which slots the drive has been in.
    visited: u16,
    /// The time of the first timed statusword.
    first_time: Option<Timestamp>,
    /// The time of the last timed statusword.
    last_time: Option<Timestamp>,
    /// Since when the current state is credited (the timed statusword that
    /// entered it, or the first timed one after an untimed change).
    since: Option<Timestamp>,
}

impl Drive {
    /// A drive nothing has been seen of.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds a statusword; a [`Change`] when the state it shows differs
    /// from the last one (only then: most statuswords repeat).
    ///
    /// Time in a state runs from the statusword that entered it to the one
    /// that left it (or the last one seen, for the state at the end), so the
    /// times add up to the span from the first timed statusword to the last.
    /// An untimed statusword moves no time: the time since the last timed
    /// change goes to the state in force at the next timed one.
    pub fn statusword(&mut self, at: At, statusword: u16, via: Via) -> Option<Change> {
        if let Some(t) = at.time {
            self.first_time.get_or_insert(t);
            self.since.get_or_insert(t);
            self.last_time = Some(t);
        }
        if self.statusword == Some(statusword) {
            return None;
        }
        self.statusword = Some(statusword);
        let to = DriveState::of_statusword(statusword);
        let from = self.state;
        if from == Some(to) {
            return None;
        }
        if let (Some(was), Some(t), Some(since)) = (from, at.time, self.since) {
            let slot = &mut self.time[was.slot()];
            *slot = slot.checked_add(t.since(since)).unwrap_or(*slot);
            self.since = Some(t);
        }
        self.state = Some(to);
        self.visited |= 1 << to.slot();
        let mut closed_fault = None;
        let mut opened_fault = false;
        if to.is_fault() {
            if self.open_fault.is_none() {
                opened_fault = true;
                self.faults += 1;
                self.open_fault = Some(Fault {
                    start: at,
                    end: None,
                    cleared_by: None,
                    emcy_code: None,
                    error_code: None,
                });
            }
        } else if to != DriveState::Unknown {
            // An unknown pattern inside a fault is not a way out of it (a
            // glitch would split one fault in two): a known state is.
            closed_fault = self.open_fault.take().map(|mut f| {
                f.end = Some(at);
                f
            });
        }
        Some(Change {
            at,
            from,
            to,
            statusword,
            via,
            closed_fault,
            opened_fault,
        })
    }

    /// Feeds a controlword the master wrote; the command it gives, if it
    /// gives one, when it differs from the last (a repeated word repeats
    /// no command).
    pub fn controlword(&mut self, at: At, controlword: u16) -> Option<Commanded> {
        let previous = self.controlword;
        if previous == Some(controlword) {
            return None;
        }
        self.controlword = Some(controlword);
        let state = match self.state {
            Some(DriveState::State(s)) => Some(s),
            _ => None,
        };
        let command = Command::of_controlword(controlword, previous, state)?;
        if command == Command::FaultReset {
            self.fault_resets += 1;
            if let Some(fault) = &mut self.open_fault {
                fault.cleared_by = Some(at);
            }
        }
        Some(Commanded {
            at,
            controlword,
            command,
        })
    }

    /// Attaches the EMCY code that came with the open fault (the first one
    /// attached stays); `false` when no fault is open or one is attached.
    pub fn attach_emcy(&mut self, code: u16) -> bool {
        match &mut self.open_fault {
            Some(f) if f.emcy_code.is_none() => {
                f.emcy_code = Some(code);
                true
            }
            _ => false,
        }
    }

    /// Feeds the error code object (0x603F) where a PDO maps it or an SDO
    /// reads it: the first nonzero code in a fault is the fault's. Feed a
    /// PDO's statusword before its error code, so a fault entered in that
    /// PDO gets it.
    pub fn error_code(&mut self, code: u16) {
        if let Some(f) = &mut self.open_fault
            && code != 0
        {
            f.error_code.get_or_insert(code);
        }
    }

    /// The state the last statusword showed; `None` before any.
    pub fn state(&self) -> Option<DriveState> {
        self.state
    }

    /// The last statusword seen.
    pub fn last_statusword(&self) -> Option<u16> {
        self.statusword
    }

    /// Whether the last statusword had its warning bit set.
    pub fn warning(&self) -> bool {
        self.statusword.is_some_and(cia402::warning)
    }

    /// The fault the drive is in now, if it is.
    pub fn open_fault(&self) -> Option<&Fault> {
        self.open_fault.as_ref()
    }

    /// Faults entered ("faulted 2 times").
    pub fn fault_count(&self) -> u64 {
        self.faults
    }

    /// Fault resets the master sent (bit 7 rising edges).
    pub fn fault_reset_count(&self) -> u64 {
        self.fault_resets
    }

    /// The time spent in `state`, the stay in the current state counted to
    /// the last statusword.
    pub fn time_in(&self, state: DriveState) -> Span {
        let ended = self.time.get(state.slot()).copied().unwrap_or_default();
        match (self.state, self.since, self.last_time) {
            (Some(now), Some(since), Some(last)) if now == state => {
                ended.checked_add(last.since(since)).unwrap_or(ended)
            }
            _ => ended,
        }
    }

    /// The states the drive was in, in the standard's order (unknown last),
    /// with the time spent in each: `time_in_state` of the report.
    pub fn time_in_state(&self) -> impl Iterator<Item = (DriveState, Span)> + '_ {
        (0..SLOTS)
            .filter(|slot| self.visited & (1 << slot) != 0)
            .map(|slot| {
                let state = DriveState::of_slot(slot);
                (state, self.time_in(state))
            })
    }

    /// The time of the last timed statusword.
    pub fn last_time(&self) -> Option<Timestamp> {
        self.last_time
    }

    /// From the first timed statusword to the last: what the times in
    /// state add up to.
    pub fn span(&self) -> Option<Span> {
        Some(self.last_time?.since(self.first_time?))
    }
}

/// Closed faults a node keeps for its report; later ones are only counted
/// ([`Drive::fault_count`]): a drive flapping in and out of fault for hours
/// must not grow memory without bound.
pub const MAX_FAULTS_KEPT: usize = 1000;

/// How near (before or after) the fault's entry an EMCY of the same node
/// must be to count as the one that came with it: drives send the EMCY
/// within a cycle or two of the statusword, 1 s leaves room for slow ones
/// and busy buses without pairing unrelated events.
const EMCY_NEAR_MILLIS: u64 = 1000;

/// One node's drive with what the report needs of it: the closed faults and
/// the last EMCY (to pair with a fault entered just after it).
#[derive(Clone, Debug, Default)]
pub struct DriveRecord {
    pub drive: Drive,
    /// Closed faults, oldest first (the first [`MAX_FAULTS_KEPT`]).
    pub faults: Vec<Fault>,
    /// The node's last error EMCY: when, and its code.
    last_emcy: Option<(Timestamp, u16)>,
}

/// Whether two times are within [`EMCY_NEAR_MILLIS`] of each other.
fn near(a: Timestamp, b: Timestamp) -> bool {
    let gap = if a >= b { a.since(b) } else { b.since(a) };
    gap.as_f64() * 1000.0 <= EMCY_NEAR_MILLIS as f64
}

impl DriveRecord {
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds a statusword (see [`Drive::statusword`]); a fault it closes is
    /// kept, a fault it opens gets the EMCY sent just before it.
    pub fn statusword(&mut self, at: At, statusword: u16, via: Via) -> Option<Change> {
        let mut change = self.drive.statusword(at, statusword, via)?;
        if let Some(f) = change.closed_fault.take() {
            self.keep(f.clone());
            change.closed_fault = Some(f);
        }
        if change.opened_fault
            && let (Some((t, code)), Some(now)) = (self.last_emcy, at.time)
            && near(t, now)
        {
            self.drive.attach_emcy(code);
        }
        Some(change)
    }

    /// An error EMCY of the node (not a reset): attached to the open fault
    /// if it came near the fault's entry, else remembered for the next one.
    pub fn emcy(&mut self, at: At, code: u16) {
        if let Some(t) = at.time {
            self.last_emcy = Some((t, code));
        }
        let start = self.drive.open_fault().and_then(|f| f.start.time);
        if let (Some(start), Some(now)) = (start, at.time)
            && near(start, now)
        {
            self.drive.attach_emcy(code);
        }
    }

    fn keep(&mut self, f: Fault) {
        if self.faults.len() < MAX_FAULTS_KEPT {
            self.faults.push(f);
        }
    }

    /// Every fault, closed ones then the open one.
    pub fn all_faults(&self) -> impl Iterator<Item = &Fault> + '_ {
        self.faults.iter().chain(self.drive.open_fault())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PDO: Via = Via::Pdo { cob_id: 0x181 };

    fn at(secs: u64) -> At {
        At {
            time: Some(Timestamp::from_parts(secs, 0, 3)),
            line: secs,
        }
    }

    fn st(s: State) -> DriveState {
        DriveState::State(s)
    }

    fn secs(s: Span) -> f64 {
        s.as_f64()
    }

    #[test]
    fn only_changes_of_state_are_reported() {
        let mut a = Drive::new();
        let first = a.statusword(at(1), 0x0250, PDO).expect("first statusword");
        assert_eq!(first.from, None);
        assert_eq!(first.to, st(State::SwitchOnDisabled));
        assert_eq!(first.statusword, 0x0250);
        assert_eq!(a.statusword(at(2), 0x0250, PDO), None, "same word");
        // Another word, same state (bits 4, 7-15 differ).
        assert_eq!(a.statusword(at(3), 0x0270, PDO), None, "same state");
        let c = a.statusword(at(4), 0x0231, Via::Sdo).expect("a change");
        assert_eq!(c.from, Some(st(State::SwitchOnDisabled)));
        assert_eq!(c.to, st(State::ReadyToSwitchOn));
        assert_eq!(c.via, Via::Sdo);
        assert_eq!(c.at, at(4));
        assert_eq!(a.state(), Some(st(State::ReadyToSwitchOn)));
        assert_eq!(a.last_statusword(), Some(0x0231));
    }

    /// The enable sequence, then every transition of the standard's diagram
    /// as the statusword shows it.
    #[test]
    fn every_transition_is_a_change() {
        use State::*;
        let path = [
            (0x0000, NotReadyToSwitchOn),
            (0x0040, SwitchOnDisabled),    // 1
            (0x0021, ReadyToSwitchOn),     // 2
            (0x0023, SwitchedOn),          // 3
            (0x0027, OperationEnabled),    // 4
            (0x0023, SwitchedOn),          // 5
            (0x0021, ReadyToSwitchOn),     // 6
            (0x0040, SwitchOnDisabled),    // 7
            (0x0021, ReadyToSwitchOn),     // 2
            (0x0027, OperationEnabled),    // 3 + 4 at once
            (0x0021, ReadyToSwitchOn),     // 8
            (0x0023, SwitchedOn),          // 3
            (0x0040, SwitchOnDisabled),    // 10
            (0x0021, ReadyToSwitchOn),     // 2
            (0x0023, SwitchedOn),          // 3
            (0x0027, OperationEnabled),    // 4
            (0x0007, QuickStopActive),     // 11
            (0x0027, OperationEnabled),    // 16
            (0x0040, SwitchOnDisabled),    // 9
            (0x000F, FaultReactionActive), // 13
            (0x0008, Fault),               // 14
            (0x0040, SwitchOnDisabled),    // 15
        ];
        let mut a = Drive::new();
        let mut seen = Vec::new();
        for (i, (word, _)) in path.iter().enumerate() {
            if let Some(c) = a.statusword(at(i as u64), *word, PDO) {
                seen.push(c.to);
            }
        }
        let expected: Vec<DriveState> = path.iter().map(|&(_, s)| st(s)).collect();
        assert_eq!(seen, expected);
        assert_eq!(a.fault_count(), 1);
    }

    #[test]
    fn a_fault_from_reaction_to_reset() {
        let mut a = Drive::new();
        a.statusword(at(10), 0x0637, PDO);
        a.controlword(at(10), 0x000F);
        let entered = a.statusword(at(12), 0x061F, PDO).expect("fault reaction");
        assert!(entered.opened_fault);
        assert_eq!(entered.to, st(State::FaultReactionActive));
        assert!(a.attach_emcy(0x2310));
        a.error_code(0x0000);
        a.error_code(0x2310);
        a.error_code(0x7500);
        assert!(!a.attach_emcy(0x1000), "the first code stays");
        let fault = a.statusword(at(13), 0x0618, PDO).expect("fault");
        assert!(!fault.opened_fault, "the same fault goes on");
        assert_eq!(fault.closed_fault, None);
        assert_eq!(a.fault_count(), 1);
        // A reset that does not take, then one that does.
        let r1 = a.controlword(at(14), 0x0080).expect("reset");
        assert_eq!(r1.command, Command::FaultReset);
        assert_eq!(a.controlword(at(14), 0x0080), None, "held high");
        a.controlword(at(15), 0x0000);
        a.controlword(at(16), 0x0080);
        assert_eq!(a.fault_reset_count(), 2);
        let open = a.open_fault().expect("still in fault");
        assert_eq!(open.cleared_by, Some(at(16)));
        let out = a.statusword(at(17), 0x0650, PDO).expect("left fault");
        let closed = out.closed_fault.expect("the fault ends");
        assert_eq!(closed.start, at(12));
        assert_eq!(closed.end, Some(at(17)));
        assert_eq!(closed.cleared_by, Some(at(16)));
        assert_eq!(closed.emcy_code, Some(0x2310));
        assert_eq!(closed.error_code, Some(0x2310), "the first nonzero");
        assert_eq!(closed.duration().map(secs), Some(5.0));
        assert_eq!(a.open_fault(), None);
        assert!(!a.attach_emcy(0x2310), "no fault open");
    }

    #[test]
    fn a_fault_left_without_a_reset_has_no_clearer() {
        let mut a = Drive::new();
        a.error_code(0x3210);
        a.statusword(at(1), 0x0008, PDO);
        assert!(a.open_fault().is_some(), "first word a fault");
        assert_eq!(
            a.open_fault().and_then(|f| f.error_code),
            None,
            "a code from before the fault is not its"
        );
        // A reset before the fault does not count for a later one.
        let out = a.statusword(at(2), 0x0000, PDO).expect("reboot");
        let f = out.closed_fault.expect("closed");
        assert_eq!(f.cleared_by, None);
        a.controlword(at(3), 0x0080);
        a.statusword(at(4), 0x0008, PDO);
        assert_eq!(a.open_fault().and_then(|f| f.cleared_by), None);
        assert_eq!(a.fault_count(), 2);
    }

    #[test]
    fn an_unknown_pattern_is_a_state_but_does_not_end_a_fault() {
        let mut a = Drive::new();
        a.statusword(at(1), 0x0008, PDO);
        let odd = a.statusword(at(2), 0x0041, PDO).expect("unknown");
        assert_eq!(odd.to, DriveState::Unknown);
        assert_eq!(odd.closed_fault, None);
        assert!(a.open_fault().is_some());
        // Back into fault from unknown: the same fault.
        let back = a.statusword(at(3), 0x0008, PDO).expect("fault again");
        assert!(!back.opened_fault);
        assert_eq!(a.fault_count(), 1);
        let out = a.statusword(at(4), 0x0040, PDO).expect("cleared");
        assert_eq!(out.closed_fault.map(|f| f.start), Some(at(1)));
        assert_eq!(DriveState::Unknown.slug(), "unknown");
    }

    #[test]
    fn commands_are_reported_once_per_new_word() {
        let mut a = Drive::new();
        a.statusword(at(0), 0x0021, PDO);
        let c = a.controlword(at(1), 0x000F).expect("a command");
        assert_eq!(c.command, Command::SwitchOnEnableOperation);
        assert_eq!(a.controlword(at(2), 0x000F), None);
        a.statusword(at(3), 0x0027, PDO);
        let c = a.controlword(at(4), 0x0007).expect("a command");
        assert_eq!(c.command, Command::DisableOperation);
        assert_eq!(c.controlword, 0x0007);
        assert_eq!(a.fault_reset_count(), 0);
    }

    #[test]
    fn time_in_each_state() {
        let mut a = Drive::new();
        a.statusword(at(10), 0x0040, PDO);
        a.statusword(at(11), 0x0040, PDO);
        a.statusword(at(12), 0x0021, PDO);
        a.statusword(at(15), 0x0027, PDO);
        a.statusword(at(20), 0x0027, PDO);
        a.statusword(at(21), 0x0021, PDO);
        a.statusword(at(30), 0x0027, PDO);
        a.statusword(at(34), 0x0027, PDO);
        let times: Vec<(&str, f64)> = a
            .time_in_state()
            .map(|(s, t)| (s.slug(), secs(t)))
            .collect();
        assert_eq!(
            times,
            [
                ("switch_on_disabled", 2.0),
                ("ready_to_switch_on", 12.0),
                ("operation_enabled", 6.0 + 4.0),
            ]
        );
        assert_eq!(a.span().map(secs), Some(24.0));
        assert_eq!(a.time_in(st(State::Fault)), Span::ZERO);
        // Exact, with the trace's digits.
        assert_eq!(a.time_in(st(State::SwitchOnDisabled)).to_string(), "2.000");
    }

    #[test]
    fn untimed_statuswords_move_no_time() {
        let untimed = |line| At { time: None, line };
        let mut a = Drive::new();
        a.statusword(untimed(1), 0x0040, PDO);
        a.statusword(at(5), 0x0040, PDO);
        a.statusword(untimed(6), 0x0021, PDO);
        a.statusword(at(9), 0x0021, PDO);
        assert_eq!(a.span().map(secs), Some(4.0));
        // The stay that began untimed is credited from the first time seen
        // to the state in force when time went on.
        let total: f64 = a.time_in_state().map(|(_, t)| secs(t)).sum();
        assert_eq!(total, 4.0);
    }

    #[test]
    fn nothing_seen_is_nothing() {
        let a = Drive::new();
        assert_eq!(a.state(), None);
        assert_eq!(a.span(), None);
        assert_eq!(a.time_in_state().count(), 0);
        assert!(!a.warning());
    }

    #[test]
    fn warning_follows_the_last_statusword() {
        let mut a = Drive::new();
        a.statusword(at(1), 0x00A7, PDO);
        assert!(a.warning());
        assert_eq!(a.statusword(at(2), 0x0027, PDO), None, "same state");
        assert!(!a.warning());
    }

    #[test]
    fn via_slugs() {
        assert_eq!(PDO.slug(), "pdo");
        assert_eq!(Via::Sdo.slug(), "sdo");
    }

    proptest::proptest! {
        /// Whatever the words and times (clocks going backwards, frames
        /// without a time), the times in state add up exactly to the span
        /// of the statuswords seen.
        #[test]
        fn time_in_state_sums_to_the_span(
            digits in 0u8..=9,
            frames in proptest::collection::vec(
                (proptest::option::weighted(0.9, (0u64..1_000, 0u64..1_000_000_000)),
                 proptest::sample::select(vec![
                     0x0000u16, 0x0040, 0x0021, 0x0023, 0x0027, 0x0007, 0x000F,
                     0x0008, 0x0041, 0x00A7,
                 ]),
                 proptest::bool::ANY),
                0..60),
        ) {
            let mut a = Drive::new();
            for (line, (time, word, reset)) in frames.into_iter().enumerate() {
                let at = At {
                    time: time.map(|(s, f)| Timestamp::from_parts(s, f, digits)),
                    line: line as u64,
                };
                a.statusword(at, word, PDO);
                a.controlword(at, if reset { 0x0080 } else { 0x000F });
            }
            let total = a
                .time_in_state()
                .try_fold(Span::ZERO, |sum, (_, t)| sum.checked_add(t));
            match a.span() {
                Some(span) => {
                    let total = total.expect("no overflow");
                    // Equal in value (the precision of ZERO is 0 digits).
                    proptest::prop_assert_eq!(total.to_string(), span.to_string());
                }
                None => proptest::prop_assert_eq!(total, Some(Span::ZERO)),
            }
            proptest::prop_assert!(a.fault_count() >= u64::from(a.open_fault().is_some()));
        }
    }
}

#[cfg(test)]
mod record_tests {
    use super::*;

    const PDO: Via = Via::Pdo { cob_id: 0x185 };

    fn at_ms(ms: u64) -> At {
        At {
            time: Some(Timestamp::from_parts(ms / 1000, ms % 1000, 3)),
            line: ms,
        }
    }

    #[test]
    fn an_emcy_just_before_or_after_the_fault_is_its_emcy() {
        // Before: the EMCY 2 ms ahead of the statusword.
        let mut r = DriveRecord::new();
        r.statusword(at_ms(0), 0x0237, PDO);
        r.emcy(at_ms(998), 0x7305);
        r.statusword(at_ms(1000), 0x0238, PDO);
        assert_eq!(r.drive.open_fault().and_then(|f| f.emcy_code), Some(0x7305));
        // After: the first one attached stays.
        let mut r = DriveRecord::new();
        r.statusword(at_ms(0), 0x0237, PDO);
        r.statusword(at_ms(1000), 0x0238, PDO);
        r.emcy(at_ms(1001), 0x2310);
        r.emcy(at_ms(1002), 0x7305);
        assert_eq!(r.drive.open_fault().and_then(|f| f.emcy_code), Some(0x2310));
        // Closed, it is kept with its EMCY.
        let c = r.statusword(at_ms(1500), 0x0250, PDO).expect("change");
        assert_eq!(c.closed_fault.and_then(|f| f.emcy_code), Some(0x2310));
        assert_eq!(r.faults.len(), 1);
    }

    #[test]
    fn an_emcy_far_from_the_fault_is_not_its_emcy() {
        let mut r = DriveRecord::new();
        r.statusword(at_ms(0), 0x0237, PDO);
        r.emcy(at_ms(100), 0x7305);
        r.statusword(at_ms(5000), 0x0238, PDO);
        r.emcy(at_ms(9000), 0x2310);
        assert_eq!(r.drive.open_fault().map(|f| f.emcy_code), Some(None));
        assert_eq!(r.all_faults().count(), 1);
    }

    #[test]
    fn closed_faults_kept_are_bounded_and_all_counted() {
        let mut r = DriveRecord::new();
        for i in 0..(MAX_FAULTS_KEPT as u64 + 5) {
            r.statusword(at_ms(i * 10), 0x0238, PDO);
            r.statusword(at_ms(i * 10 + 5), 0x0250, PDO);
        }
        assert_eq!(r.faults.len(), MAX_FAULTS_KEPT);
        assert_eq!(r.drive.fault_count(), MAX_FAULTS_KEPT as u64 + 5);
    }
}
