//! The consumer's CiA 402 side (issue 19): PDO mappings learnt from the
//! trace's SDO writes or given (DCF, `--pdo`, `--assume-cia402-pdo`), the
//! statuswords and controlwords read out of PDOs and SDO uploads, and the
//! `axis_state` / `fault_reset` events. Kept apart from the EMCY path: a
//! PDO on an id no mapping decodes costs one array lookup there.

use std::collections::BTreeMap;
use std::io::Write;

use super::Consumer;
use super::health::emit;
use crate::analyze::event::{AxisReport, Health};
use crate::analyze::{Options, OutputError};
use crate::canopen::NodeId;
use crate::canopen::cia402::{self, Command};
use crate::canopen::pdo::{
    self, Cia402Fields, Cia402Values, CobId, Downloads, Learner, Mapping, MappingTable, Source,
};
use crate::canopen::sdo::{self, Sdo};
use crate::timeline::At;
use crate::timeline::axis::{AxisRecord, Via};
use crate::trace::{Fold, Interest};

/// Standard CAN ids: the per-PDO lookup is an index into this many slots.
const STANDARD_IDS: usize = 0x800;

/// Undecoded PDOs of a drive that make the note: a cyclic state stream
/// (ten frames are 10-100 ms of one), not the odd PDO of a trace recorded
/// for its EMCYs, which would make every such trace say it.
const UNMAPPED_NOTE_AT: u64 = 10;

/// Profile number of CiA 402 in the low 16 bits of the device type (0x1000).
const CIA402_PROFILE: u32 = 402;

/// What a PDO id decodes to: whose it is and where its words sit.
#[derive(Clone, Copy, Debug)]
pub(in crate::analyze) struct PdoSlot {
    node: NodeId,
    fields: Cia402Fields,
}

/// The last words a PDO id carried, and the time and statusword of the
/// latest repeat of them (equal in the bits an axis reads) not yet told to
/// the axis: nearly every PDO repeats the one before (a drive sends its
/// statusword every cycle), and a repeat changes nothing but the axis's
/// last time and statusword, which are needed only at the end.
#[derive(Clone, Debug)]
struct Last {
    channel: Box<[u8]>,
    values: Cia402Values,
    repeat: Option<(At, Option<u16>)>,
}

/// Mappings and what the consumer derived from them.
pub(in crate::analyze) struct Drives {
    table: MappingTable,
    learner: Learner,
    downloads: Downloads,
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
    /// Drives whose PDOs went by undecoded: the first such id, how many.
    unmapped: BTreeMap<NodeId, (u32, u64)>,
}

impl Drives {
    pub(in crate::analyze) fn new(opts: &Options) -> Drives {
        let mut table = MappingTable::new();
        for (_, dcf) in &opts.dcf {
            for m in &dcf.mappings {
                table.insert(m.clone());
            }
        }
        for m in &opts.pdo {
            table.insert(m.clone());
        }
        if opts.assume_cia402_pdo {
            for node in 1..=127 {
                for m in pdo::assumed_cia402(node).into_iter().flatten() {
                    table.insert(m);
                }
            }
        }
        let mut d = Drives {
            table,
            learner: Learner::new(),
            downloads: Downloads::new(),
            by_id: vec![None; STANDARD_IDS].into_boxed_slice(),
            extended: Vec::new(),
            watched: BTreeMap::new(),
            unmapped: BTreeMap::new(),
            last: vec![None; STANDARD_IDS],
        };
        d.rebuild();
        d
    }

    /// The slots anew from the table: only COB-IDs whose mapping holds a
    /// word we decode, of a known node.
    fn rebuild(&mut self) {
        self.by_id.iter_mut().for_each(|s| *s = None);
        // Words cached under the old mappings may read otherwise now; their
        // last repeats were told first (`Consumer::flush_repeats`).
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
    pub(in crate::analyze) fn add_to(&self, interest: &mut Interest) {
        if !(self.by_id.iter().all(Option::is_none)
            && self.extended.is_empty()
            && self.watched.is_empty())
        {
            // An EMCY changes a drive's axis state, as its PDOs do: the
            // order of the two matters, so EMCYs end the runs again.
            interest.end_runs_at_frames();
        }
        for (id, slot) in self.by_id.iter().enumerate() {
            if let Some(slot) = slot {
                interest.add_standard(id as u32);
                interest.unfilter(id as u32);
                // Repeats in the bits an axis reads are folded by the
                // reader (`Consumer::takes_folds` checks them).
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
            // Their frames are only noted (`Consumer::watched`).
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

impl<E: Write> Consumer<'_, '_, E> {
    /// The DCFs' identities, as if the trace had shown 0x1018: they choose
    /// the node's profile.
    pub(super) fn dcf_identities(&mut self) {
        for (node, dcf) in &self.opts.dcf {
            if let Some(v) = dcf.vendor_id {
                let object = sdo::Object {
                    index: sdo::IDENTITY,
                    sub: 1,
                };
                self.profiles.object_value(*node, object, v);
            }
        }
    }

    /// The interest grew (a mapping learnt, a drive to watch): workers
    /// parse with the new one, blocks parsed before are read again.
    fn widen_interest(&mut self) {
        let before = self.interest.clone();
        self.drives.add_to(&mut self.interest);
        if self.interest == before {
            return;
        }
        self.interest_gen += 1;
        if let Some(shared) = &self.shared_interest
            && let Ok(mut w) = shared.write()
        {
            *w = (self.interest_gen, self.interest.clone());
        }
    }

    /// An SDO frame on a CAN SDO id that may configure a PDO: followed to
    /// the node's confirmation, then learnt.
    pub(super) fn pdo_configuration(&mut self, id: u32, data: &[u8]) {
        if !self.drives.downloads.wants(id, data) {
            return;
        }
        let Some(c) = self.drives.downloads.feed(id, data) else {
            return;
        };
        let Some(pdo) = self.drives.learner.confirmed(c.node, c.object, c.value) else {
            return;
        };
        let mapping = self.drives.learner.mapping(pdo);
        self.flush_repeats();
        self.drives.table.learnt(pdo, mapping);
        self.drives.rebuild();
        self.widen_interest();
    }

    /// A node's device type (0x1000): a CiA 402 drive without a known
    /// transmit PDO mapping gets its TPDO ids watched.
    pub(super) fn device_type(&mut self, node: NodeId, value: u32) {
        if value & 0xFFFF != CIA402_PROFILE || !(1..=127).contains(&node) {
            return;
        }
        if self.drives.has_tpdo(node) {
            return;
        }
        for base in [0x180, 0x280, 0x380, 0x480] {
            self.drives.watched.insert(base + u32::from(node), node);
        }
        self.widen_interest();
    }

    /// A frame on an id some mapping decodes.
    pub(super) fn pdo(
        &mut self,
        raw: &[u8],
        at: At,
        cob_id: u32,
        slot: PdoSlot,
        data: &[u8],
    ) -> Result<(), OutputError> {
        let values = slot.fields.read(data);
        // A repeat on the same channel (in the bits an axis reads): only
        // its time is kept.
        if let Some(Some(last)) = self.drives.last.get_mut(cob_id as usize) {
            if last.values.relevant() == values.relevant() && *last.channel == *raw {
                last.repeat = Some((at, values.statusword));
                return Ok(());
            }
            self.flush_repeat(cob_id, slot.node);
        }
        if let Some(l) = self.drives.last.get_mut(cob_id as usize) {
            *l = Some(Last {
                channel: raw.into(),
                values,
                repeat: None,
            });
        }
        let via = Via::Pdo { cob_id };
        self.axis_words(
            raw,
            slot.node,
            at,
            values.statusword,
            values.controlword,
            values.error_code,
            via,
        )
    }

    /// Whether PDOs the reader folded on `channel` ([`Fold`]) all repeat
    /// the words their id carried last ([`Consumer::pdo`] would keep only
    /// their time).
    pub(super) fn takes_pdo_fold(&self, channel: &[u8], f: &Fold) -> bool {
        let Some(values) = self.drives.read_word(f.id, f.data(), f.len()) else {
            return false;
        };
        matches!(
            self.drives.last.get(f.id as usize),
            Some(Some(last)) if last.values.relevant() == values.relevant()
                && *last.channel == *channel
        )
    }

    /// Takes the PDOs of a fold [`Consumer::takes_pdo_fold`] accepted, the
    /// last at `at`: as many repeats.
    pub(super) fn fold_pdos(&mut self, f: &Fold, at: At) {
        let statusword = self
            .drives
            .read_word(f.id, f.last_data(), f.len())
            .and_then(|v| v.statusword);
        if let Some(Some(last)) = self.drives.last.get_mut(f.id as usize) {
            last.repeat = Some((at, statusword));
        }
    }

    /// Tells the axis the last repeat of `cob_id`'s words (moves its last
    /// time, changes nothing else), unless a later statusword already did.
    fn flush_repeat(&mut self, cob_id: u32, node: NodeId) {
        let Some(Some(last)) = self.drives.last.get_mut(cob_id as usize) else {
            return;
        };
        let Some((at, Some(word))) = last.repeat.take() else {
            return;
        };
        let channel = last.channel.clone();
        let slot = self.nodes.get(&channel, node);
        let Some(rec) = slot.timeline.axis_mut() else {
            return;
        };
        if at.time > rec.axis.last_time() {
            rec.axis.statusword(at, word, Via::Pdo { cob_id });
        }
    }

    /// Every id's last repeat told to its axis.
    fn flush_repeats(&mut self) {
        for id in 0..STANDARD_IDS as u32 {
            if let Some(slot) = self.drives.slot(id, false) {
                self.flush_repeat(id, slot.node);
            }
        }
    }

    /// A frame on a watched id: a drive's PDO whose mapping is unknown.
    #[inline]
    pub(super) fn watched(&mut self, id: u32, extended: bool) -> bool {
        if extended || self.drives.watched.is_empty() {
            return false;
        }
        let Some(&node) = self.drives.watched.get(&id) else {
            return false;
        };
        self.drives.unmapped.entry(node).or_insert((id, 0)).1 += 1;
        true
    }

    /// An SDO upload of 0x6041, 0x6040 or 0x603F: the object read directly.
    pub(super) fn axis_sdo(&mut self, raw: &[u8], at: At, access: &Sdo) -> Result<(), OutputError> {
        let Sdo::Uploaded {
            node,
            object,
            value,
        } = *access
        else {
            return Ok(());
        };
        if object.sub != 0 {
            return Ok(());
        }
        let word = Some(value as u16);
        match object.index {
            cia402::STATUSWORD => self.axis_words(raw, node, at, word, None, None, Via::Sdo),
            cia402::CONTROLWORD => self.axis_words(raw, node, at, None, word, None, Via::Sdo),
            cia402::ERROR_CODE => self.axis_words(raw, node, at, None, None, word, Via::Sdo),
            _ => Ok(()),
        }
    }

    /// Feeds a node's axis the words one PDO or upload carried: the
    /// statusword first (a fault entered gets the error code of the same
    /// PDO), then the error code, then the controlword.
    #[allow(clippy::too_many_arguments)]
    fn axis_words(
        &mut self,
        raw: &[u8],
        node: NodeId,
        at: At,
        statusword: Option<u16>,
        controlword: Option<u16>,
        error_code: Option<u16>,
        via: Via,
    ) -> Result<(), OutputError> {
        let slot = self.nodes.get(raw, node);
        let h = slot.timeline.health_mut(self.opts.heartbeat_timeout);
        let rec = h.axis.get_or_insert_with(|| Box::new(AxisRecord::new()));
        let events = &mut self.health.events;
        if let Some(word) = statusword
            && let Some(change) = rec.statusword(at, word, via)
        {
            events.push((
                at,
                Health::AxisState {
                    state: change.to,
                    from: change.from,
                    statusword: change.statusword,
                    via: change.via,
                },
            ));
        }
        if let Some(code) = error_code {
            rec.axis.error_code(code);
        }
        if let Some(word) = controlword
            && let Some(c) = rec.axis.controlword(at, word)
            && c.command == Command::FaultReset
        {
            events.push((at, Health::FaultReset { controlword: word }));
        }
        if events.is_empty() {
            return Ok(());
        }
        emit(self.sink, self.file, self.opts, slot.channel, node, events)
    }

    /// An error EMCY of a node with an axis: the fault it came with.
    #[inline]
    pub(super) fn axis_emcy(rec: Option<&mut AxisRecord>, at: At, code: u16) {
        if let Some(rec) = rec {
            rec.emcy(at, code);
        }
    }

    /// The end of the input: the note for drives whose PDOs went undecoded,
    /// and PDO configurations not kept.
    pub(super) fn finish_axes(&mut self) {
        let file = self.file;
        self.flush_repeats();
        let unmapped: Vec<(NodeId, u32)> = self
            .drives
            .unmapped
            .iter()
            .filter(|(n, (_, count))| *count >= UNMAPPED_NOTE_AT && !self.drives.has_tpdo(**n))
            .map(|(n, (id, _))| (*n, *id))
            .collect();
        if let Some(&(node, id)) = unmapped.first() {
            let list: Vec<String> = unmapped
                .iter()
                .map(|(n, id)| format!("{n} (0x{id:03X})"))
                .collect();
            self.log.note(&format!(
                "{file}: CiA 402 drive node {} sends PDOs whose mapping is unknown: its \
                 state is not decoded; give the mapping with --dcf {node}=FILE, --pdo \
                 0x{id:03X}=0x6041 or --assume-cia402-pdo",
                list.join(", "),
            ));
        }
        let dropped = self.drives.learner.dropped();
        if dropped > 0 {
            self.log.note(&format!(
                "{file}: {dropped} PDO configuration writes not followed: more than {} PDOs \
                 configured",
                pdo::MAX_LEARNT_PDOS
            ));
        }
    }

    /// The axis object of a node's report, with its mappings; a node
    /// without a decoded word gets one only for a mapping the trace, a DCF
    /// or `--pdo` gave (not for the blanket assumption).
    pub(super) fn axis_report(&self, node: NodeId, report: &mut Option<Box<AxisReport>>) {
        let mappings = self.drives.mappings_of(node);
        match report {
            Some(r) => r.mappings = mappings,
            None if mappings.iter().any(|m| m.source != Source::Assumed) => {
                *report = Some(Box::new(AxisReport {
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
}

/// The axis half of a node's report (its mappings are added by the
/// consumer, which holds them).
pub(super) fn report_axis(rec: &AxisRecord) -> AxisReport {
    AxisReport {
        state: rec.axis.state(),
        statusword: rec.axis.last_statusword(),
        faults: rec.all_faults().cloned().collect(),
        fault_count: rec.axis.fault_count(),
        fault_resets: rec.axis.fault_reset_count(),
        time_in_state: rec.axis.time_in_state().collect(),
        mappings: Vec::new(),
    }
}
