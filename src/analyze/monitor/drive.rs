//! The drive monitor: CiA 402 drives. PDO mappings learnt from the
//! trace's SDO writes and reads (the SDO monitor assembles them) or given
//! (DCF, `--pdo`, `--assume-cia402-pdo`), the statuswords read out of PDOs
//! and SDO uploads, the controlwords the master writes (RPDO or SDO
//! download), and the `drive_state` / `fault_reset` events. Kept apart from the EMCY path: a
//! PDO on an id no mapping decodes costs one array lookup there.

use std::collections::BTreeMap;
use std::io::Write;

use super::context::{Emit, Fact, Facts, Learnt, Monitor, Seen, Step};
use crate::analyze::analysis::OutputError;
use crate::analyze::event::{DriveReport, Health, NodeReport};
use crate::analyze::nodes::Nodes;
use crate::analyze::options::Options;
use crate::canopen::NodeId;
use crate::canopen::cia402::{self, Command};
use crate::canopen::device_profile;
use crate::canopen::pdo::{
    self, Cia402Fields, Cia402Values, CobId, Learner, Mapping, MappingTable, Source,
};
use crate::canopen::sdo::{self, Object};
use crate::timeline::At;
use crate::timeline::drive::{DriveRecord, Via};
use crate::timeline::health::NodeHealth;
use crate::trace::{Fold, Interest};

/// Standard CAN ids: the per-PDO lookup is an index into this many slots.
const STANDARD_IDS: usize = 0x800;

/// Undecoded PDOs of a drive that make the note: a cyclic state stream
/// (ten frames are 10-100 ms of one), not the odd PDO of a trace recorded
/// for its EMCYs, which would make every such trace say it.
const UNMAPPED_NOTE_AT: u64 = 10;

/// What a PDO id decodes to: whose it is and where its words sit.
#[derive(Clone, Copy, Debug)]
pub(in crate::analyze) struct PdoSlot {
    node: NodeId,
    fields: Cia402Fields,
}

/// The last words a PDO id carried, and the time and statusword of the
/// latest repeat of them (equal in the bits a drive's state reads) not yet
/// told to the drive: nearly every PDO repeats the one before (a drive
/// sends its statusword every cycle), and a repeat changes nothing but the
/// drive's last time and statusword, which are needed only at the end.
#[derive(Clone, Debug)]
struct Last {
    channel: Box<[u8]>,
    values: Cia402Values,
    repeat: Option<(At, Option<u16>)>,
}

/// PDO mappings, what the monitor derived from them, and the events it
/// is about to hand out.
pub(in crate::analyze) struct DriveMonitor {
    table: MappingTable,
    learner: Learner,
    /// Slots by standard id, rebuilt when the table changes.
    by_id: Box<[Option<PdoSlot>]>,
    /// Slots of 29-bit ids (a `--pdo` or a DCF may give one).
    extended: Vec<(u32, PdoSlot)>,
    /// TPDO ids of CiA 402 drives (device type 402) with no known mapping,
    /// watched for the note that says how to give one.
    watched: BTreeMap<u32, NodeId>,
    /// The last words of each standard id decoded (29-bit ids are rare:
    /// not cached).
    last: Vec<Option<Last>>,
    /// Drives whose PDOs went by undecoded: the first such id, how many
    /// (counted up to [`UNMAPPED_NOTE_AT`]).
    unmapped: BTreeMap<NodeId, (u32, u64)>,
    /// A drive whose undecoded PDOs reached [`UNMAPPED_NOTE_AT`]: its ids
    /// are to leave the interest ([`DriveMonitor::unwatch`]).
    seen_enough: Option<NodeId>,
    /// Nodes `--assume-cia402-pdo` skips, as their device type says they
    /// are no drive: the device type, and whether states read before it
    /// came were withdrawn from the node's report.
    not_drives: BTreeMap<NodeId, (u32, bool)>,
    /// Buffer reused from frame to frame.
    events: Vec<(At, Health)>,
}

impl DriveMonitor {
    fn with_mappings(opts: &Options) -> DriveMonitor {
        let mut table = MappingTable::new();
        for (_, dcf) in &opts.dcf {
            for m in &dcf.mappings {
                table.insert(m.clone());
            }
        }
        for m in &opts.pdo {
            table.insert(m.clone());
        }
        let mut not_drives = BTreeMap::new();
        if opts.assume_cia402_pdo {
            for (node, dcf) in &opts.dcf {
                if let Some(t) = dcf.device_type.filter(|&t| !device_profile::is_drive(t)) {
                    not_drives.insert(*node, (t, false));
                }
            }
            for node in 1..=127 {
                if not_drives.contains_key(&node) {
                    continue;
                }
                for m in pdo::assumed_cia402(node).into_iter().flatten() {
                    table.insert(m);
                }
            }
        }
        let mut d = DriveMonitor {
            table,
            learner: Learner::new(),
            by_id: vec![None; STANDARD_IDS].into_boxed_slice(),
            extended: Vec::new(),
            watched: BTreeMap::new(),
            unmapped: BTreeMap::new(),
            seen_enough: None,
            not_drives,
            last: vec![None; STANDARD_IDS],
            events: Vec::new(),
        };
        d.rebuild();
        d
    }

    /// The slots anew from the table: only COB-IDs whose mapping holds a
    /// word we decode, of a known node.
    fn rebuild(&mut self) {
        self.by_id.iter_mut().for_each(|s| *s = None);
        // Words cached under the old mappings may read otherwise now; their
        // last repeats were told first ([`DriveMonitor::flush_repeats`]).
        self.last.iter_mut().for_each(|l| *l = None);
        self.extended.clear();
        let ids: Vec<CobId> = self.table.decoded_ids().collect();
        for cob in ids {
            let (Some(m), Some(fields)) = (self.table.mapping(cob), self.table.fields(cob)) else {
                continue;
            };
            let Some(node) = m.node else { continue };
            let slot = PdoSlot {
                node,
                fields: *fields,
            };
            if cob.extended {
                self.extended.push((cob.id, slot));
            } else if let Some(s) = self.by_id.get_mut(cob.id as usize) {
                *s = Some(slot);
            }
        }
        // A watched id that a mapping now decodes is no longer unknown.
        let by_id = &self.by_id;
        self.watched
            .retain(|&id, _| by_id.get(id as usize).is_none_or(Option::is_none));
    }

    /// The slot of a frame's id: the per-frame call (one index for
    /// standard ids).
    #[inline]
    pub(in crate::analyze) fn slot(&self, id: u32, extended: bool) -> Option<PdoSlot> {
        if extended {
            if self.extended.is_empty() {
                return None;
            }
            return self
                .extended
                .iter()
                .find(|(i, _)| *i == id)
                .map(|(_, s)| *s);
        }
        self.by_id.get(id as usize).copied().flatten()
    }

    /// The words of a PDO on standard `id` whose `len` bytes are `word`
    /// (as [`Payload::word`](crate::trace::Payload::word) gives them), if
    /// its mapping decodes any.
    fn read_word(&self, id: u32, word: u64, len: u8) -> Option<Cia402Values> {
        let slot = self.slot(id, false)?;
        let bytes = word.to_le_bytes();
        Some(slot.fields.read(bytes.get(..usize::from(len))?))
    }

    /// Whether frames on standard `id` are a drive's PDOs of unknown
    /// mapping, only noted.
    pub(in crate::analyze) fn watches(&self, id: u32) -> bool {
        self.watched.contains_key(&id)
    }

    /// Adds the ids worth reading to `interest`: decoded PDOs, watched ones.
    /// On ids under the SDO/NMT content filter every frame matters.
    fn add_to(&self, interest: &mut Interest) {
        if !(self.by_id.iter().all(Option::is_none)
            && self.extended.is_empty()
            && self.watched.is_empty())
        {
            // An EMCY changes a drive's state, as its PDOs do: the
            // order of the two matters, so EMCYs end the runs again.
            interest.end_runs_at_frames();
        }
        for (id, slot) in self.by_id.iter().enumerate() {
            if let Some(slot) = slot {
                interest.add_standard(id as u32);
                interest.unfilter(id as u32);
                // Repeats in the bits a drive's state reads are folded by
                // the reader ([`DriveMonitor::takes_pdo_fold`] checks them).
                if let Some(mask) = slot.fields.relevant_bits() {
                    interest.fold_masked(id as u32, mask);
                }
            }
        }
        for (id, _) in &self.extended {
            interest.add_extended(*id);
        }
        for &id in self.watched.keys() {
            interest.add_standard(id);
            interest.unfilter(id);
            // Their frames are only noted ([`DriveMonitor::watched`]).
            interest.untime(id);
        }
    }

    /// Whether a node has a transmit PDO that decodes a word.
    fn has_tpdo(&self, node: NodeId) -> bool {
        self.by_id.iter().flatten().any(|s| s.node == node)
            || self.extended.iter().any(|(_, s)| s.node == node)
    }

    /// The node's mappings in force, transmit first (for its report).
    fn mappings_of(&self, node: NodeId) -> Vec<Mapping> {
        let mut out: Vec<Mapping> = self
            .table
            .in_force()
            .filter(|m| m.node == Some(node))
            .cloned()
            .collect();
        out.sort_by_key(|m| (m.direction, m.cob_id));
        out
    }
}

impl Monitor for DriveMonitor {
    fn new(opts: &Options) -> Self {
        DriveMonitor::with_mappings(opts)
    }

    /// A PDO some mapping decodes is taken.
    #[inline]
    fn frame<E: Write>(
        &mut self,
        frame: &Seen<'_>,
        nodes: &mut Nodes,
        _facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<Step, OutputError> {
        if let Some(slot) = self.slot(frame.id, frame.extended) {
            let node = slot.node;
            // A PDO with the statusword is one the drive sends.
            let sent_by_node = slot.fields.statusword.is_some();
            let repeat = self.pdo(
                frame.channel,
                frame.at,
                frame.id,
                slot,
                frame.data,
                nodes,
                emit,
            )?;
            let mut awaits_start = || {
                nodes
                    .known(frame.channel, node)
                    .and_then(|t| t.health())
                    .is_some_and(|h| h.nmt.awaits_start())
            };
            // Not on a repeat: the folds take repeats without this check,
            // and the answer must not depend on how the input was split.
            if sent_by_node && !repeat && awaits_start() {
                return Ok(Step::Learnt(Learnt {
                    produced: Some(Fact::Produced { node }),
                    ..Learnt::default()
                }));
            }
            return Ok(Step::Done);
        }
        Ok(Step::Pass)
    }

    /// The device type (0x1000); PDO parameters read or written; the
    /// statusword and error code read directly (0x6041, 0x603F); the
    /// controlword written (0x6040). A read of the controlword is no
    /// command, so never a fault reset, and it is not compared with the
    /// words written either: the master's RPDOs that follow it repeat the
    /// word before it, and their repeats are not fed again.
    fn learn<E: Write>(
        &mut self,
        raw: &[u8],
        at: At,
        fact: Fact,
        nodes: &mut Nodes,
        _facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        match fact {
            Fact::Holds {
                node,
                object,
                value,
                ..
            } if object.index == sdo::DEVICE_TYPE && object.sub == 0 => {
                self.device_type(raw, node, value, nodes, emit);
                Ok(())
            }
            Fact::Read {
                node,
                object,
                value,
            }
            | Fact::Written {
                node,
                object,
                value,
            } if pdo::PdoId::is_pdo_parameter(object.index) => {
                self.pdo_configuration(node, object, value, nodes, emit);
                Ok(())
            }
            Fact::Written {
                node,
                object,
                value,
            } if object.sub == 0 && object.index == cia402::CONTROLWORD => {
                let words = Words {
                    statusword: None,
                    controlword: Some(value as u16),
                    error_code: None,
                    via: Via::Sdo,
                };
                self.words(raw, node, at, words, nodes, emit)
            }
            Fact::Read {
                node,
                object,
                value,
            } if object.sub == 0 => {
                let word = Some(value as u16);
                let (statusword, error_code) = match object.index {
                    cia402::STATUSWORD => (word, None),
                    cia402::ERROR_CODE => (None, word),
                    _ => return Ok(()),
                };
                let words = Words {
                    statusword,
                    controlword: None,
                    error_code,
                    via: Via::Sdo,
                };
                self.words(raw, node, at, words, nodes, emit)
            }
            _ => Ok(()),
        }
    }

    /// The note for drives whose PDOs went undecoded, and PDO
    /// configurations not kept.
    fn finish<E: Write>(
        &mut self,
        _end: At,
        nodes: &mut Nodes,
        _facts: &Facts<'_>,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        self.flush_repeats(nodes);
        let unmapped: Vec<(NodeId, u32)> = self
            .unmapped
            .iter()
            .filter(|(n, (_, count))| *count >= UNMAPPED_NOTE_AT && !self.has_tpdo(**n))
            .map(|(n, (id, _))| (*n, *id))
            .collect();
        if let Some(&(node, id)) = unmapped.first() {
            let list: Vec<String> = unmapped
                .iter()
                .map(|(n, id)| format!("{n} (0x{id:03X})"))
                .collect();
            emit.note(&format!(
                "CiA 402 drive node {} sends PDOs whose mapping is unknown: its state is not \
                 decoded; give the mapping with --dcf {node}=FILE, --pdo 0x{id:03X}=0x6041 or \
                 --assume-cia402-pdo",
                list.join(", "),
            ));
        }
        if !self.not_drives.is_empty() {
            let list: Vec<String> = self
                .not_drives
                .iter()
                .map(|(n, (t, _))| format!("{n} (0x{t:08X}, {})", device_profile::describe(*t)))
                .collect();
            let withdrawn: Vec<String> = self
                .not_drives
                .iter()
                .filter(|(_, (_, w))| *w)
                .map(|(n, _)| n.to_string())
                .collect();
            let (one, verb, their) = if list.len() == 1 {
                ("node", "is not a drive", "its")
            } else {
                ("nodes", "are not drives", "their")
            };
            let mut note = format!(
                "--assume-cia402-pdo: {one} {} {verb} by {their} device type; {their} PDOs are \
                 not read as CiA 402",
                list.join(", ")
            );
            if !withdrawn.is_empty() {
                note.push_str(&format!(
                    " (the states read before the device type came are left out of the report \
                     of node {})",
                    withdrawn.join(", ")
                ));
            }
            emit.note(&note);
        }
        let dropped = self.learner.dropped();
        if dropped > 0 {
            emit.note(&format!(
                "{dropped} PDO configuration writes not followed: more than {} PDOs configured",
                pdo::MAX_LEARNT_PDOS
            ));
        }
        Ok(())
    }

    /// The drive object of a node's report, with its mappings; a node
    /// without a decoded word gets one only for a mapping the trace, a DCF
    /// or `--pdo` gave (not for the blanket assumption).
    fn report(&self, report: &mut NodeReport, health: Option<&NodeHealth>) {
        let mappings = self.mappings_of(report.node);
        match health.and_then(|h| h.drive.as_deref()) {
            Some(rec) => report.drive = Some(Box::new(drive_report(rec, mappings))),
            None if mappings.iter().any(|m| m.source != Source::Assumed) => {
                report.drive = Some(Box::new(DriveReport {
                    state: None,
                    statusword: None,
                    faults: Vec::new(),
                    fault_count: 0,
                    fault_resets: 0,
                    time_in_state: Vec::new(),
                    mappings,
                }));
            }
            None => {}
        }
    }

    fn interest(&self, interest: &mut Interest) {
        self.add_to(interest);
    }
}

/// The words one PDO or SDO upload carried to a drive, and how.
struct Words {
    statusword: Option<u16>,
    controlword: Option<u16>,
    error_code: Option<u16>,
    via: Via,
}

impl DriveMonitor {
    /// A PDO parameter's value the node confirmed writing or reported in
    /// an upload: a master that reads a mapping back learns it as surely
    /// as one that writes it.
    fn pdo_configuration<E: Write>(
        &mut self,
        node: NodeId,
        object: Object,
        value: u32,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) {
        let Some(pdo) = self.learner.confirmed(node, object, value) else {
            return;
        };
        let mapping = self.learner.mapping(pdo);
        self.flush_repeats(nodes);
        self.table.learnt(pdo, mapping);
        self.rebuild();
        emit.wanted.widen(|i| self.add_to(i));
    }

    /// A node's device type (0x1000): a CiA 402 drive without a known
    /// transmit PDO mapping gets its TPDO ids watched; a node of another
    /// profile is no drive, and `--assume-cia402-pdo` does not read its
    /// PDOs as one. What was read of it as a drive before is withdrawn
    /// from its report when nothing but that assumption decoded it: the
    /// words were read from a layout the node does not have, and a report
    /// of a drive state for an I/O module would mislead (the events
    /// already written stay, the note says so).
    fn device_type<E: Write>(
        &mut self,
        raw: &[u8],
        node: NodeId,
        value: u32,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) {
        if !(1..=127).contains(&node) {
            return;
        }
        if !device_profile::is_drive(value) {
            if emit.opts.assume_cia402_pdo && self.table.withdraw_assumed(node) {
                // Its ids as the assumption decoded them (the slots are
                // rebuilt below).
                let assumed: Vec<u32> = (0..STANDARD_IDS as u32)
                    .filter(|&id| self.slot(id, false).is_some_and(|s| s.node == node))
                    .collect();
                self.flush_repeats(nodes);
                self.rebuild();
                // No longer decoded, they leave the interest: the reader
                // folded them for a drive, and a run holding a fold the
                // consumer cannot take is taken frame by frame (a bus of
                // I/O modules' event PDOs made every drive PDO a trip to
                // the consumer).
                emit.wanted.narrow(|i| {
                    let mut removed = false;
                    for &id in &assumed {
                        if self.slot(id, false).is_none() && !self.watched.contains_key(&id) {
                            i.remove_standard(id);
                            removed = true;
                        }
                    }
                    removed
                });
                let withdrawn = self.mappings_of(node).is_empty()
                    && nodes
                        .get(raw, node)
                        .timeline
                        .health_if_any()
                        .and_then(|h| h.drive.take())
                        .is_some();
                self.not_drives.insert(node, (value, withdrawn));
            }
            return;
        }
        if self.has_tpdo(node) {
            return;
        }
        for base in [0x180, 0x280, 0x380, 0x480] {
            self.watched.insert(base + u32::from(node), node);
        }
        emit.wanted.widen(|i| self.add_to(i));
    }

    /// A frame on an id some mapping decodes; whether it repeated the
    /// words its id carried last (only its time is kept).
    #[allow(clippy::too_many_arguments)]
    fn pdo<E: Write>(
        &mut self,
        raw: &[u8],
        at: At,
        cob_id: u32,
        slot: PdoSlot,
        data: &[u8],
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) -> Result<bool, OutputError> {
        let values = slot.fields.read(data);
        // A repeat on the same channel (in the bits a drive's state reads):
        // only its time is kept.
        if let Some(Some(last)) = self.last.get_mut(cob_id as usize) {
            if last.values.relevant() == values.relevant() && *last.channel == *raw {
                last.repeat = Some((at, values.statusword));
                return Ok(true);
            }
            self.flush_repeat(cob_id, slot.node, nodes);
        }
        if let Some(l) = self.last.get_mut(cob_id as usize) {
            *l = Some(Last {
                channel: raw.into(),
                values,
                repeat: None,
            });
        }
        let words = Words {
            statusword: values.statusword,
            controlword: values.controlword,
            error_code: values.error_code,
            via: Via::Pdo { cob_id },
        };
        self.words(raw, slot.node, at, words, nodes, emit)?;
        Ok(false)
    }

    /// Whether PDOs the reader folded on `channel` ([`Fold`]) all repeat
    /// the words their id carried last ([`DriveMonitor::pdo`] would keep
    /// only their time).
    pub(in crate::analyze) fn takes_pdo_fold(&self, channel: &[u8], f: &Fold) -> bool {
        let Some(values) = self.read_word(f.id, f.data(), f.len()) else {
            return false;
        };
        matches!(
            self.last.get(f.id as usize),
            Some(Some(last)) if last.values.relevant() == values.relevant()
                && *last.channel == *channel
        )
    }

    /// Takes the PDOs of a fold [`DriveMonitor::takes_pdo_fold`] accepted,
    /// the last at `at`: as many repeats.
    pub(in crate::analyze) fn fold_pdos(&mut self, f: &Fold, at: At) {
        let statusword = self
            .read_word(f.id, f.last_data(), f.len())
            .and_then(|v| v.statusword);
        if let Some(Some(last)) = self.last.get_mut(f.id as usize) {
            last.repeat = Some((at, statusword));
        }
    }

    /// Tells the drive the last repeat of `cob_id`'s words (moves its last
    /// time, changes nothing else), unless a later statusword already did.
    fn flush_repeat(&mut self, cob_id: u32, node: NodeId, nodes: &mut Nodes) {
        let Some(Some(last)) = self.last.get_mut(cob_id as usize) else {
            return;
        };
        let Some((at, Some(word))) = last.repeat.take() else {
            return;
        };
        let slot = nodes.get(&last.channel, node);
        let Some(rec) = slot.timeline.drive_mut() else {
            return;
        };
        if at.time > rec.drive.last_time() {
            rec.drive.statusword(at, word, Via::Pdo { cob_id });
        }
    }

    /// Every id's last repeat told to its drive.
    fn flush_repeats(&mut self, nodes: &mut Nodes) {
        for id in 0..STANDARD_IDS as u32 {
            if let Some(slot) = self.slot(id, false) {
                self.flush_repeat(id, slot.node, nodes);
            }
        }
    }

    /// A frame on a watched id: a drive's PDO whose mapping is unknown.
    /// Asked of every decoded frame, and nearly always `false` at the
    /// first test: always inlined (a call cost 20 instructions a frame).
    #[inline(always)]
    pub(in crate::analyze) fn watched(&mut self, id: u32, extended: bool) -> bool {
        if extended || self.watched.is_empty() {
            return false;
        }
        let Some(&node) = self.watched.get(&id) else {
            return false;
        };
        let count = &mut self.unmapped.entry(node).or_insert((id, 0)).1;
        *count += 1;
        if *count == UNMAPPED_NOTE_AT {
            self.seen_enough = Some(node);
        }
        true
    }

    /// Takes the ids of a drive whose undecoded PDOs are enough for the
    /// note out of `interest`: a drive sends them every cycle, and each
    /// was a trip to the consumer that told nothing new (on a bus of 8
    /// drives at 1 kHz whose device types were read, 3.5x the time of
    /// the same trace without). A mapping learnt later adds them again.
    /// `false` when no drive got there since the last call.
    pub(in crate::analyze) fn unwatch(&mut self, interest: &mut Interest) -> bool {
        let Some(node) = self.seen_enough.take() else {
            return false;
        };
        self.watched.retain(|&id, &mut n| {
            if n == node {
                interest.remove_standard(id);
            }
            n != node
        });
        true
    }

    /// Feeds a node's drive the words one PDO or upload carried: the
    /// statusword first (a fault entered gets the error code of the same
    /// PDO), then the error code, then the controlword.
    fn words<E: Write>(
        &mut self,
        raw: &[u8],
        node: NodeId,
        at: At,
        words: Words,
        nodes: &mut Nodes,
        emit: &mut Emit<'_, E>,
    ) -> Result<(), OutputError> {
        let slot = nodes.get(raw, node);
        let h = slot.timeline.health_mut(emit.opts.heartbeat_timeout);
        let rec = h.drive.get_or_insert_with(|| Box::new(DriveRecord::new()));
        let events = &mut self.events;
        if let Some(word) = words.statusword
            && let Some(change) = rec.statusword(at, word, words.via)
        {
            events.push((
                at,
                Health::DriveState {
                    state: change.to,
                    from: change.from,
                    statusword: change.statusword,
                    via: change.via,
                },
            ));
        }
        if let Some(code) = words.error_code {
            rec.drive.error_code(code);
        }
        if let Some(word) = words.controlword
            && let Some(c) = rec.drive.controlword(at, word)
            && c.command == Command::FaultReset
        {
            events.push((at, Health::FaultReset { controlword: word }));
        }
        if events.is_empty() {
            return Ok(());
        }
        emit.health(slot.channel, node, events)
    }
}

/// A drive's report, with its mappings in force.
fn drive_report(rec: &DriveRecord, mappings: Vec<Mapping>) -> DriveReport {
    DriveReport {
        state: rec.drive.state(),
        statusword: rec.drive.last_statusword(),
        faults: rec.all_faults().cloned().collect(),
        fault_count: rec.drive.fault_count(),
        fault_resets: rec.drive.fault_reset_count(),
        time_in_state: rec.drive.time_in_state().collect(),
        mappings,
    }
}
