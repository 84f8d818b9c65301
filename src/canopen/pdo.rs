//! PDO mappings (CiA 301 §7.4.7): which objects a PDO carries at which bit
//! offsets, where a mapping came from, and reading an object's value out of
//! a PDO's bytes.
//!
//! A mapping is never guessed silently: each has a [`Source`]. The trace's
//! own SDO writes are learnt by [`Learner`] (fed the confirmed writes that
//! [`Downloads`] assembles, expedited and segmented), a DCF declares one
//! (`canopen::dcf`), the user gives one (`--pdo`, [`parse_spec`]), or the
//! user asks for the CiA 402 predefined one ([`assumed_cia402`]).
//!
//! The pipeline's part, per frame: SDO frames that [`Downloads::wants`] go
//! to [`Downloads::feed`], a confirmed write to [`Learner::confirmed`], the
//! PDO it changed to [`MappingTable::learnt`]; a frame whose id
//! [`MappingTable::fields`] knows is read with [`Cia402Fields::read`].

use std::collections::BTreeMap;

use super::NodeId;
use super::cia402;
use super::sdo::Downloads;
use super::sdo::{self, Object};

/// Where a mapping came from: the `source` of the report's mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Source {
    /// Learnt from SDO writes the node confirmed in the trace.
    Sdo,
    /// Declared by a DCF or EDS file (`--dcf`).
    Dcf,
    /// Given on the command line (`--pdo`).
    Option,
    /// The CiA 402 predefined mapping, used because the user asked for it.
    Assumed,
}

impl Source {
    /// The stable name in JSON.
    pub fn slug(self) -> &'static str {
        match self {
            Source::Sdo => "sdo",
            Source::Dcf => "dcf",
            Source::Option => "option",
            Source::Assumed => "assumed",
        }
    }
}

/// Transmit (node to master: statusword) or receive (master to node:
/// controlword), as seen from the node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Direction {
    Tpdo,
    Rpdo,
}

impl Direction {
    /// The stable name in JSON (`tpdo`, `rpdo`).
    pub fn slug(self) -> &'static str {
        match self {
            Direction::Tpdo => "tpdo",
            Direction::Rpdo => "rpdo",
        }
    }
}

/// Which PDO of which node: number 1 to 512 in each direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PdoId {
    pub node: NodeId,
    pub direction: Direction,
    pub number: u16,
}

impl PdoId {
    /// The PDO a communication or mapping parameter index configures, and
    /// whether the index is the mapping (else the communication) parameter.
    fn of_index(node: NodeId, index: u16) -> Option<(PdoId, bool)> {
        let (direction, mapping, base) = match index {
            0x1400..=0x15FF => (Direction::Rpdo, false, 0x1400),
            0x1600..=0x17FF => (Direction::Rpdo, true, 0x1600),
            0x1800..=0x19FF => (Direction::Tpdo, false, 0x1800),
            0x1A00..=0x1BFF => (Direction::Tpdo, true, 0x1A00),
            _ => return None,
        };
        let pdo = PdoId {
            node,
            direction,
            number: index - base + 1,
        };
        Some((pdo, mapping))
    }

    /// Whether an object index is a PDO communication or mapping parameter
    /// (0x1400-0x1BFF): a cheap first test for SDO frames worth assembling.
    pub fn is_pdo_parameter(index: u16) -> bool {
        (0x1400..=0x1BFF).contains(&index)
    }

    /// Whether an object decides a PDO's layout: a communication
    /// parameter's COB-ID (sub 1) or a mapping parameter's count or entry
    /// (sub 0-64). The [`Learner`] ignores every other object.
    pub fn shapes_mapping(object: Object) -> bool {
        match PdoId::of_index(1, object.index) {
            Some((_, true)) => object.sub <= MAX_ENTRIES,
            Some((_, false)) => object.sub == 1,
            None => false,
        }
    }

    /// The COB-ID of the predefined connection set (CiA 301 §7.3.5) for
    /// PDOs 1-4: what the PDO uses until a write says otherwise.
    pub fn default_cob_id(self) -> Option<CobId> {
        let base = match (self.direction, self.number) {
            (Direction::Tpdo, n @ 1..=4) => 0x080 + 0x100 * u32::from(n),
            (Direction::Rpdo, n @ 1..=4) => 0x100 + 0x100 * u32::from(n),
            _ => return None,
        };
        (1..=127).contains(&self.node).then(|| CobId {
            id: base + u32::from(self.node),
            extended: false,
        })
    }
}

/// A PDO's CAN identifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CobId {
    pub id: u32,
    pub extended: bool,
}

impl CobId {
    /// From a COB-ID parameter value (sub 1 of 0x1400/0x1800...); `None`
    /// when bit 31 says the PDO is not valid (switched off).
    pub fn of_parameter(value: u32) -> Option<CobId> {
        if value & 0x8000_0000 != 0 {
            return None;
        }
        Some(if value & 0x2000_0000 != 0 {
            CobId {
                id: value & 0x1FFF_FFFF,
                extended: true,
            }
        } else {
            CobId {
                id: value & 0x7FF,
                extended: false,
            }
        })
    }
}

/// One mapped object: a mapping entry `index << 16 | sub << 8 | bits`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Mapped {
    pub object: Object,
    pub bits: u8,
}

impl Mapped {
    /// From a mapping parameter entry (sub 1-64 of 0x1600/0x1A00...).
    pub fn of_entry(entry: u32) -> Mapped {
        Mapped {
            object: Object {
                index: (entry >> 16) as u16,
                sub: (entry >> 8) as u8,
            },
            bits: entry as u8,
        }
    }

    /// The entry value a DCF or SDO write would carry.
    #[cfg(test)] // Tests compare mappings by their entries.
    pub fn entry(self) -> u32 {
        u32::from(self.object.index) << 16 | u32::from(self.object.sub) << 8 | u32::from(self.bits)
    }
}

/// Where an object sits in a PDO's bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Field {
    /// Bits before it (byte 0 bit 0 is bit 0).
    pub offset: u16,
    /// 1 to 64.
    pub bits: u8,
}

impl Field {
    /// The field's value, little endian as CANopen sends every number;
    /// `None` when the PDO is too short to hold it (a drive sending fewer
    /// bytes than its mapping says: the value is not there).
    pub fn read(self, data: &[u8]) -> Option<u64> {
        if self.bits == 0 || self.bits > 64 {
            return None;
        }
        let first = usize::from(self.offset / 8);
        let shift = u32::from(self.offset % 8);
        let end = (usize::from(self.offset) + usize::from(self.bits)).div_ceil(8);
        let bytes = data.get(first..end)?;
        // At most 9 bytes (64 bits at a bit offset): they fit in a u128.
        let mut raw: u128 = 0;
        for (i, &b) in bytes.iter().enumerate() {
            raw |= u128::from(b) << (8 * i);
        }
        let mask = (1u128 << self.bits) - 1;
        Some(((raw >> shift) & mask) as u64)
    }
}

/// A PDO's mapping: which objects it carries, in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mapping {
    /// The node the PDO belongs to, when known (not for `--pdo`).
    pub node: Option<NodeId>,
    /// Tpdo or Rpdo, when known.
    pub direction: Option<Direction>,
    pub cob_id: CobId,
    pub objects: Vec<Mapped>,
    pub source: Source,
}

impl Mapping {
    /// Where `object` sits in this PDO, if it is mapped.
    pub fn field(&self, object: Object) -> Option<Field> {
        let mut offset: u32 = 0;
        for m in &self.objects {
            if m.object == object {
                return Some(Field {
                    offset: u16::try_from(offset).ok()?,
                    bits: m.bits,
                });
            }
            offset += u32::from(m.bits);
        }
        None
    }

    /// Whether it maps one of the CiA 402 objects the decoder reads (only
    /// such PDOs are worth parsing).
    #[cfg(test)] // The table decides by Cia402Fields::of.
    pub fn maps_decoded(&self) -> bool {
        self.objects
            .iter()
            .any(|m| cia402::is_decoded(m.object.index))
    }
}

/// Where the CiA 402 objects sit in one PDO, worked out once per mapping:
/// reading a PDO is then a few shifts, no lookup and no allocation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cia402Fields {
    pub statusword: Option<Field>,
    pub controlword: Option<Field>,
    pub error_code: Option<Field>,
}

/// The CiA 402 words one PDO carried (a word mapped with fewer than 16
/// bits is read as its bits; more are cut to 16).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cia402Values {
    pub statusword: Option<u16>,
    pub controlword: Option<u16>,
    pub error_code: Option<u16>,
}

impl Cia402Values {
    /// The bits anything decoded depends on ([`cia402::STATUSWORD_BITS`],
    /// [`cia402::CONTROLWORD_BITS`], all of the error code): two PDOs
    /// equal here tell a drive the same.
    pub fn relevant(self) -> Cia402Values {
        Cia402Values {
            statusword: self.statusword.map(|w| w & cia402::STATUSWORD_BITS),
            controlword: self.controlword.map(|w| w & cia402::CONTROLWORD_BITS),
            error_code: self.error_code,
        }
    }
}

impl Cia402Fields {
    /// The bits of a PDO's data (its first 8 bytes as a little-endian word)
    /// that [`Cia402Values::relevant`] reads: two PDOs equal there are
    /// repeats. `None` when a field reaches past the 8th byte.
    pub fn relevant_bits(&self) -> Option<u64> {
        let mut mask = 0u64;
        for (field, bits) in [
            (self.statusword, cia402::STATUSWORD_BITS),
            (self.controlword, cia402::CONTROLWORD_BITS),
            (self.error_code, u16::MAX),
        ] {
            let Some(f) = field else { continue };
            // A word is read as its field's low 16 bits at most.
            let width = u32::from(f.bits.min(16));
            let low = u64::from(bits) & ((1u64 << width) - 1);
            if u32::from(f.offset) + width > 64 {
                return None;
            }
            // A field of no bits at bit 64 reads nothing.
            mask |= low.checked_shl(u32::from(f.offset)).unwrap_or(0);
        }
        Some(mask)
    }

    /// Where a mapping puts the objects; `None` when it maps none of them
    /// (the PDO is not worth parsing).
    pub fn of(mapping: &Mapping) -> Option<Cia402Fields> {
        let fields = Cia402Fields {
            statusword: mapping.field(object(cia402::STATUSWORD)),
            controlword: mapping.field(object(cia402::CONTROLWORD)),
            error_code: mapping.field(object(cia402::ERROR_CODE)),
        };
        (fields != Cia402Fields::default()).then_some(fields)
    }

    /// The words a PDO's bytes hold; a word the PDO is too short for is
    /// `None`.
    pub fn read(&self, data: &[u8]) -> Cia402Values {
        let word = |f: Option<Field>| f.and_then(|f| f.read(data)).map(|v| v as u16);
        Cia402Values {
            statusword: word(self.statusword),
            controlword: word(self.controlword),
            error_code: word(self.error_code),
        }
    }
}

impl Source {
    /// Precedence: the first source that maps a COB-ID wins (the trace's
    /// own configuration, then the DCF, the option, the assumption).
    fn rank(self) -> usize {
        match self {
            Source::Sdo => 0,
            Source::Dcf => 1,
            Source::Option => 2,
            Source::Assumed => 3,
        }
    }
}

/// The mappings of one COB-ID, one per source, and the fields of the one
/// in force.
#[derive(Clone, Debug, Default)]
struct Slots {
    by_source: [Option<Mapping>; 4],
    fields: Option<Cia402Fields>,
}

impl Slots {
    fn best(&self) -> Option<&Mapping> {
        self.by_source.iter().flatten().next()
    }

    fn refresh(&mut self) {
        self.fields = self.best().and_then(Cia402Fields::of);
    }
}

/// The mappings in force, by COB-ID: what the pipeline asks for every PDO
/// ([`MappingTable::fields`]) and what the report lists.
#[derive(Clone, Debug, Default)]
pub struct MappingTable {
    by_cob: BTreeMap<CobId, Slots>,
    /// Where each learnt PDO's mapping is filed, to move it when the trace
    /// gives the PDO another COB-ID or switches it off.
    learnt_at: BTreeMap<PdoId, CobId>,
}

impl MappingTable {
    pub fn new() -> Self {
        Self::default()
    }

    /// Files a declared, given or assumed mapping (a second one of the same
    /// source and COB-ID replaces the first). Learnt ones go through
    /// [`MappingTable::learnt`].
    pub fn insert(&mut self, mapping: Mapping) {
        let slots = self.by_cob.entry(mapping.cob_id).or_default();
        let rank = mapping.source.rank();
        if let Some(slot) = slots.by_source.get_mut(rank) {
            *slot = Some(mapping);
        }
        slots.refresh();
    }

    /// Files what the [`Learner`] now says of `pdo` (`None`: no mapping in
    /// force, the PDO switched off or mid-configuration).
    pub fn learnt(&mut self, pdo: PdoId, mapping: Option<Mapping>) {
        if let Some(old) = self.learnt_at.remove(&pdo)
            && let Some(slots) = self.by_cob.get_mut(&old)
        {
            slots.by_source[0] = None;
            slots.refresh();
            if slots.best().is_none() {
                self.by_cob.remove(&old);
            }
        }
        if let Some(m) = mapping {
            self.learnt_at.insert(pdo, m.cob_id);
            self.insert(Mapping {
                source: Source::Sdo,
                ..m
            });
        }
    }

    /// Withdraws the assumed mappings of `node` (its device type says it is
    /// no drive); whether it had any.
    pub fn withdraw_assumed(&mut self, node: NodeId) -> bool {
        let rank = Source::Assumed.rank();
        let mut withdrew = false;
        self.by_cob.retain(|_, slots| {
            if let Some(slot) = slots.by_source.get_mut(rank)
                && slot.as_ref().is_some_and(|m| m.node == Some(node))
            {
                *slot = None;
                withdrew = true;
                slots.refresh();
            }
            slots.best().is_some()
        });
        withdrew
    }

    /// Where the CiA 402 words sit in PDOs on `cob_id`, if the mapping in
    /// force there maps any: the per-frame call.
    pub fn fields(&self, cob_id: CobId) -> Option<&Cia402Fields> {
        self.by_cob.get(&cob_id)?.fields.as_ref()
    }

    /// The mapping in force on `cob_id`.
    pub fn mapping(&self, cob_id: CobId) -> Option<&Mapping> {
        self.by_cob.get(&cob_id)?.best()
    }

    /// The mappings in force, by COB-ID.
    pub fn in_force(&self) -> impl Iterator<Item = &Mapping> + '_ {
        self.by_cob.values().filter_map(Slots::best)
    }

    /// The COB-IDs whose PDOs carry a CiA 402 word: the only PDO ids worth
    /// reading.
    pub fn decoded_ids(&self) -> impl Iterator<Item = CobId> + '_ {
        self.by_cob
            .iter()
            .filter(|(_, s)| s.fields.is_some())
            .map(|(&id, _)| id)
    }
}

/// An object at sub-index 0.
fn object(index: u16) -> Object {
    Object { index, sub: 0 }
}

/// The CiA 402 predefined mapping for `node` (1-127): TPDO1 (0x180 +
/// node) starts with the statusword, RPDO1 (0x200 + node) with the
/// controlword. Only when the user asks for it: reported as assumed.
pub fn assumed_cia402(node: NodeId) -> Option<[Mapping; 2]> {
    let tpdo1 = PdoId {
        node,
        direction: Direction::Tpdo,
        number: 1,
    };
    let rpdo1 = PdoId {
        direction: Direction::Rpdo,
        ..tpdo1
    };
    let one = |pdo: PdoId, index: u16| -> Option<Mapping> {
        Some(Mapping {
            node: Some(node),
            direction: Some(pdo.direction),
            cob_id: pdo.default_cob_id()?,
            objects: vec![Mapped {
                object: object(index),
                bits: 16,
            }],
            source: Source::Assumed,
        })
    };
    Some([
        one(tpdo1, cia402::STATUSWORD)?,
        one(rpdo1, cia402::CONTROLWORD)?,
    ])
}

/// The node and direction of a predefined connection set COB-ID.
fn direction_of_predefined(cob_id: u32) -> Option<(NodeId, Direction)> {
    let node = (cob_id & 0x7F) as NodeId;
    if node == 0 || cob_id > 0x57F {
        return None;
    }
    match cob_id & !0x7F {
        0x180 | 0x280 | 0x380 | 0x480 => Some((node, Direction::Tpdo)),
        0x200 | 0x300 | 0x400 | 0x500 => Some((node, Direction::Rpdo)),
        _ => None,
    }
}

/// The node and direction a COB-ID of the predefined connection set
/// implies (0x181 is node 1's TPDO1): for `--pdo` mappings, which name
/// only the COB-ID.
pub fn predefined_owner(cob_id: CobId) -> Option<(NodeId, Direction)> {
    if cob_id.extended {
        return None;
    }
    direction_of_predefined(cob_id.id)
}

/// Bits an object has when `--pdo` gives none: the CiA 402 words.
fn known_bits(index: u16) -> Option<u8> {
    match index {
        cia402::STATUSWORD | cia402::CONTROLWORD | cia402::ERROR_CODE => Some(16),
        _ => None,
    }
}

/// A number as users write them: `0x` hex, else decimal.
fn number(text: &str) -> Option<u32> {
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16).ok(),
        None => text.parse().ok(),
    }
}

/// Parses `--pdo COBID=OBJECT[:BITS],...`: a comma-separated list where an
/// item with `=` starts a PDO (`0x181=0x6041`) and one without adds the
/// next object to it (`0x6061:8`). OBJECT is an index in hex (`0x` optional:
/// CANopen writes indexes in hex everywhere), optionally `.SUB` (decimal or
/// `0x` hex); BITS is decimal, optional for 0x6040, 0x6041 and 0x603F (16).
/// The error is the text clap prints.
pub fn parse_spec(spec: &str) -> Result<Vec<Mapping>, String> {
    let mut out: Vec<Mapping> = Vec::new();
    for item in spec.split(',') {
        let item = item.trim();
        let obj_text = match item.split_once('=') {
            Some((cob, obj)) => {
                let raw = number(cob.trim())
                    .ok_or_else(|| format!("`{cob}` is not a COB-ID (0x181 or 385)"))?;
                if raw > 0x1FFF_FFFF {
                    return Err(format!("COB-ID {cob} is above 29 bits"));
                }
                // An id above 11 bits can only be a 29-bit one.
                let cob_id = CobId {
                    id: raw,
                    extended: raw > 0x7FF,
                };
                if out.iter().any(|m| m.cob_id == cob_id) {
                    return Err(format!("COB-ID {cob} is given twice"));
                }
                let owner = predefined_owner(cob_id);
                out.push(Mapping {
                    node: owner.map(|(n, _)| n),
                    direction: owner.map(|(_, d)| d),
                    cob_id,
                    objects: Vec::new(),
                    source: Source::Option,
                });
                obj
            }
            None => item,
        };
        let Some(mapping) = out.last_mut() else {
            return Err(format!(
                "`{item}` comes before any COB-ID: write COBID=OBJECT first (0x181=0x6041)"
            ));
        };
        let mapped = parse_object(obj_text.trim())?;
        mapping.objects.push(mapped);
        let total: u32 = mapping.objects.iter().map(|m| u32::from(m.bits)).sum();
        if total > 64 {
            return Err(format!(
                "the objects of COB-ID {:#x} add up to {total} bits: a CAN PDO holds 64",
                mapping.cob_id.id
            ));
        }
    }
    Ok(out)
}

/// `OBJECT[:BITS]` of a `--pdo` item.
fn parse_object(text: &str) -> Result<Mapped, String> {
    let (obj, bits) = match text.split_once(':') {
        Some((o, b)) => (o, Some(b)),
        None => (text, None),
    };
    let (index_text, sub_text) = match obj.split_once('.') {
        Some((i, s)) => (i, Some(s)),
        None => (obj, None),
    };
    let hex = index_text
        .strip_prefix("0x")
        .or_else(|| index_text.strip_prefix("0X"))
        .unwrap_or(index_text);
    let index = u16::from_str_radix(hex, 16)
        .map_err(|_| format!("`{obj}` is not an object index (hex, like 0x6041)"))?;
    let sub = match sub_text {
        Some(s) => number(s)
            .and_then(|n| u8::try_from(n).ok())
            .ok_or_else(|| format!("`{s}` is not a sub-index (0 to 255)"))?,
        None => 0,
    };
    let bits = match bits {
        Some(b) => b
            .parse::<u8>()
            .ok()
            .filter(|n| (1..=64).contains(n))
            .ok_or_else(|| format!("`{b}` is not a bit length (1 to 64)"))?,
        None => known_bits(index)
            .ok_or_else(|| format!("give the length of {obj} in bits ({obj}:8, {obj}:32, ...)"))?,
    };
    Ok(Mapped {
        object: Object { index, sub },
        bits,
    })
}

/// The most PDOs the [`Learner`] keeps configurations of: 127 nodes could
/// configure 1024 each; a trace doing that is broken, and memory stays
/// bounded (further PDOs are counted, not kept).
pub const MAX_LEARNT_PDOS: usize = 4096;

/// Mapping entries a PDO may have (sub 1-64).
const MAX_ENTRIES: u8 = 64;

/// What the trace has configured of one PDO so far.
#[derive(Clone, Debug, Default)]
struct Config {
    /// The last COB-ID parameter written (raw, bit 31 included).
    cob_id: Option<u32>,
    /// Sub 0 of the mapping parameter: how many entries are in force.
    count: Option<u8>,
    /// Entries by sub-index - 1; `None` for one never written.
    entries: Vec<Option<u32>>,
}

/// Learns PDO mappings from the SDO writes a node confirmed, in the order
/// it confirmed them: a master writes the COB-ID with bit 31 set, sub 0 =
/// 0, the entries, sub 0 = count, and the COB-ID valid again.
#[derive(Clone, Debug, Default)]
pub struct Learner {
    configs: BTreeMap<PdoId, Config>,
    dropped: u64,
}

impl Learner {
    pub fn new() -> Self {
        Self::default()
    }

    /// Applies a confirmed write; the PDO whose configuration it changed
    /// (the caller then asks for its [`Learner::mapping`] anew), `None` for
    /// writes to anything but a PDO parameter.
    pub fn confirmed(&mut self, node: NodeId, object: Object, value: u32) -> Option<PdoId> {
        let (pdo, is_mapping) = PdoId::of_index(node, object.index)?;
        // Transmission type, inhibit time, event timer: not the layout.
        if !PdoId::shapes_mapping(object) {
            return None;
        }
        if !self.configs.contains_key(&pdo) && self.configs.len() >= MAX_LEARNT_PDOS {
            self.dropped += 1;
            return None;
        }
        let config = self.configs.entry(pdo).or_default();
        match (is_mapping, object.sub) {
            (false, _) => config.cob_id = Some(value),
            (true, 0) => config.count = Some(value.min(u32::from(MAX_ENTRIES)) as u8),
            (true, sub) => {
                let at = usize::from(sub - 1);
                if config.entries.len() <= at {
                    config.entries.resize(at + 1, None);
                }
                if let Some(e) = config.entries.get_mut(at) {
                    *e = Some(value);
                }
            }
        }
        Some(pdo)
    }

    /// The mapping in force for `pdo` as the trace configured it, if it is
    /// known and the PDO is valid: the count written (sub 0), every entry
    /// up to it written, and a valid COB-ID (written, or the predefined one
    /// of PDOs 1-4 when only the mapping was written).
    pub fn mapping(&self, pdo: PdoId) -> Option<Mapping> {
        let config = self.configs.get(&pdo)?;
        let cob_id = match config.cob_id {
            Some(raw) => CobId::of_parameter(raw)?,
            None => pdo.default_cob_id()?,
        };
        let count = usize::from(config.count?);
        if count == 0 {
            return None;
        }
        let objects = config
            .entries
            .get(..count)?
            .iter()
            .map(|e| e.map(Mapped::of_entry))
            .collect::<Option<Vec<Mapped>>>()?;
        Some(Mapping {
            node: Some(pdo.node),
            direction: Some(pdo.direction),
            cob_id,
            objects,
            source: Source::Sdo,
        })
    }

    /// Every mapping in force, in PDO order.
    pub fn mappings(&self) -> impl Iterator<Item = Mapping> + '_ {
        self.configs.keys().filter_map(|&pdo| self.mapping(pdo))
    }

    /// PDO configurations not kept (beyond [`MAX_LEARNT_PDOS`]).
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

/// Which writes the decoder learns from is a question about PDOs and
/// drives, so it is answered here rather than beside the assembly.
impl Downloads {
    /// Whether a frame can matter to a write the decoder learns from: an
    /// SDO frame naming a PDO parameter or the controlword (a drive's
    /// fault reset is a write), or any SDO frame of a node with a download
    /// in progress (segments name no object). A cheap test, so the pipeline
    /// feeds only these.
    pub fn wants(&self, id: u32, data: &[u8]) -> bool {
        self.in_progress(id)
            || sdo::is_sdo_id(id)
                && matches!(data, [_, lo, hi, ..] if {
                    let index = u16::from_le_bytes([*lo, *hi]);
                    PdoId::is_pdo_parameter(index) || index == cia402::CONTROLWORD
                })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(offset: u16, bits: u8) -> Field {
        Field { offset, bits }
    }

    #[test]
    fn reads_little_endian_at_bit_offsets() {
        let data = [0x37, 0x06, 0xA5, 0x10, 0x32, 0x54, 0x76, 0x98];
        assert_eq!(field(0, 16).read(&data), Some(0x0637));
        assert_eq!(field(16, 8).read(&data), Some(0xA5));
        assert_eq!(field(16, 16).read(&data), Some(0x10A5));
        // Not on a byte boundary: bits 4-15.
        assert_eq!(field(4, 12).read(&data), Some(0x063));
        // One bit.
        assert_eq!(field(0, 1).read(&data), Some(1));
        assert_eq!(field(3, 1).read(&data), Some(0));
        assert_eq!(field(0, 64).read(&data), Some(0x9876_5432_10A5_0637));
        // 64 bits spanning 9 bytes (CAN FD payloads).
        let wide = [0xF0, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x0A];
        assert_eq!(field(4, 64).read(&wide), Some(0xAFFF_FFFF_FFFF_FFFF));
    }

    #[test]
    fn a_pdo_too_short_for_its_mapping_has_no_value() {
        assert_eq!(field(0, 16).read(&[0x37]), None);
        assert_eq!(field(16, 16).read(&[0, 0, 1]), None);
        assert_eq!(field(0, 8).read(&[]), None);
        assert_eq!(field(0, 0).read(&[1]), None, "zero bits");
        assert_eq!(field(0, 65).read(&[0xFF; 9]), None, "over 64 bits");
        assert_eq!(field(u16::MAX, 64).read(&[0; 8]), None);
    }

    #[test]
    fn mapping_entries() {
        let m = Mapped::of_entry(0x6041_0010);
        assert_eq!(m.object, object(0x6041));
        assert_eq!(m.bits, 16);
        let m = Mapped::of_entry(0x2000_0308);
        assert_eq!(
            m.object,
            Object {
                index: 0x2000,
                sub: 3
            }
        );
        assert_eq!(m.bits, 8);
        assert_eq!(m.entry(), 0x2000_0308);
    }

    #[test]
    fn cob_id_parameters() {
        let std = |id| CobId {
            id,
            extended: false,
        };
        assert_eq!(CobId::of_parameter(0x0000_0181), Some(std(0x181)));
        assert_eq!(CobId::of_parameter(0x4000_0181), Some(std(0x181)), "no RTR");
        assert_eq!(CobId::of_parameter(0x8000_0181), None, "not valid");
        assert_eq!(
            CobId::of_parameter(0x2012_3456),
            Some(CobId {
                id: 0x0012_3456,
                extended: true
            })
        );
    }

    #[test]
    fn pdo_parameters_and_predefined_ids() {
        let t = |number| PdoId {
            node: 5,
            direction: Direction::Tpdo,
            number,
        };
        let r = |number| PdoId {
            direction: Direction::Rpdo,
            ..t(number)
        };
        assert_eq!(PdoId::of_index(5, 0x1800), Some((t(1), false)));
        assert_eq!(PdoId::of_index(5, 0x1A03), Some((t(4), true)));
        assert_eq!(PdoId::of_index(5, 0x1BFF), Some((t(512), true)));
        assert_eq!(PdoId::of_index(5, 0x1400), Some((r(1), false)));
        assert_eq!(PdoId::of_index(5, 0x1601), Some((r(2), true)));
        assert_eq!(PdoId::of_index(5, 0x1C00), None);
        assert_eq!(PdoId::of_index(5, 0x13FF), None);
        let ids: Vec<u32> = (1..=4)
            .flat_map(|n| [t(n), r(n)])
            .map(|p| p.default_cob_id().expect("predefined").id)
            .collect();
        assert_eq!(
            ids,
            [0x185, 0x205, 0x285, 0x305, 0x385, 0x405, 0x485, 0x505]
        );
        assert_eq!(t(5).default_cob_id(), None);
        assert_eq!(PdoId { node: 0, ..t(1) }.default_cob_id(), None);
        assert_eq!(PdoId { node: 128, ..t(1) }.default_cob_id(), None);
        assert!(PdoId::is_pdo_parameter(0x1A00));
        let shapes = |index, sub| PdoId::shapes_mapping(Object { index, sub });
        assert!(shapes(0x1800, 1) && shapes(0x15FF, 1));
        assert!(!shapes(0x1800, 2) && !shapes(0x1400, 0) && !shapes(0x1800, 5));
        assert!(shapes(0x1A00, 0) && shapes(0x1BFF, 64) && shapes(0x1600, 1));
        assert!(!shapes(0x1A00, 65) && !shapes(0x1C00, 1) && !shapes(0x1018, 1));
        assert!(!PdoId::is_pdo_parameter(0x1018));
        for (cob, owner) in [
            (0x181, Some((1, Direction::Tpdo))),
            (0x4FF, Some((127, Direction::Tpdo))),
            (0x205, Some((5, Direction::Rpdo))),
            (0x57F, Some((127, Direction::Rpdo))),
            (0x180, None),
            (0x085, None),
            (0x585, None),
        ] {
            let id = CobId {
                id: cob,
                extended: false,
            };
            assert_eq!(predefined_owner(id), owner, "{cob:#x}");
        }
        assert_eq!(
            predefined_owner(CobId {
                id: 0x181,
                extended: true
            }),
            None
        );
    }

    /// The writes a master makes to remap TPDO1 of node 5 to statusword +
    /// error code + an 8-bit object, on COB-ID 0x285.
    fn remap_tpdo1(l: &mut Learner) -> Vec<Option<PdoId>> {
        let o = |index, sub| Object { index, sub };
        vec![
            l.confirmed(5, o(0x1800, 1), 0x8000_0185),
            l.confirmed(5, o(0x1A00, 0), 0),
            l.confirmed(5, o(0x1A00, 1), 0x6041_0010),
            l.confirmed(5, o(0x1A00, 2), 0x603F_0010),
            l.confirmed(5, o(0x1A00, 3), 0x6061_0008),
            l.confirmed(5, o(0x1A00, 0), 3),
            l.confirmed(5, o(0x1800, 1), 0x0000_0285),
        ]
    }

    #[test]
    fn learns_the_standard_configuration_sequence() {
        let mut l = Learner::new();
        let tpdo1 = PdoId {
            node: 5,
            direction: Direction::Tpdo,
            number: 1,
        };
        let changed = remap_tpdo1(&mut l);
        assert!(changed.iter().all(|c| *c == Some(tpdo1)));
        let m = l.mapping(tpdo1).expect("a mapping");
        assert_eq!(m.source, Source::Sdo);
        assert_eq!(m.node, Some(5));
        assert_eq!(m.direction, Some(Direction::Tpdo));
        assert_eq!(m.cob_id.id, 0x285);
        let entries: Vec<u32> = m.objects.iter().map(|o| o.entry()).collect();
        assert_eq!(entries, [0x6041_0010, 0x603F_0010, 0x6061_0008]);
        assert!(m.maps_decoded());
        assert_eq!(m.field(object(0x6041)), Some(field(0, 16)));
        assert_eq!(m.field(object(0x603F)), Some(field(16, 16)));
        assert_eq!(m.field(object(0x6061)), Some(field(32, 8)));
        assert_eq!(m.field(object(0x6040)), None);
        let pdo = [0x37, 0x06, 0x10, 0x23, 0x08];
        assert_eq!(
            m.field(object(0x603F)).and_then(|f| f.read(&pdo)),
            Some(0x2310)
        );
        assert_eq!(l.mappings().count(), 1);
    }

    #[test]
    fn a_mapping_is_known_only_once_complete_and_valid() {
        let o = |index, sub| Object { index, sub };
        let tpdo1 = PdoId {
            node: 5,
            direction: Direction::Tpdo,
            number: 1,
        };
        let mut l = Learner::new();
        // Mid-configuration: disabled, then count 0.
        l.confirmed(5, o(0x1800, 1), 0x8000_0185);
        assert_eq!(l.mapping(tpdo1), None, "only a COB-ID");
        l.confirmed(5, o(0x1A00, 0), 0);
        l.confirmed(5, o(0x1A00, 1), 0x6041_0010);
        assert_eq!(l.mapping(tpdo1), None, "count 0, disabled");
        l.confirmed(5, o(0x1A00, 0), 2);
        assert_eq!(l.mapping(tpdo1), None, "entry 2 never written");
        l.confirmed(5, o(0x1A00, 2), 0x6061_0008);
        assert_eq!(l.mapping(tpdo1), None, "COB-ID not valid");
        l.confirmed(5, o(0x1800, 1), 0x185);
        assert_eq!(l.mapping(tpdo1).map(|m| m.objects.len()), Some(2));
        // Other communication parameters change nothing.
        assert_eq!(l.confirmed(5, o(0x1800, 2), 0xFF), None);
        assert_eq!(l.confirmed(5, o(0x1800, 5), 100), None);
        assert_eq!(l.confirmed(5, o(0x1018, 1), 0x6A), None);
        assert_eq!(l.confirmed(5, o(0x1A00, 65), 0x6041_0010), None);
    }

    #[test]
    fn a_mapping_without_a_written_cob_id_uses_the_predefined_one() {
        let o = |index, sub| Object { index, sub };
        let mut l = Learner::new();
        l.confirmed(7, o(0x1600, 0), 0);
        l.confirmed(7, o(0x1600, 1), 0x6040_0010);
        let rpdo1 = l.confirmed(7, o(0x1600, 0), 1).expect("an rpdo");
        let m = l.mapping(rpdo1).expect("a mapping");
        assert_eq!(m.cob_id.id, 0x207);
        assert_eq!(m.direction, Some(Direction::Rpdo));
        // PDO 5 has no predefined COB-ID: not known.
        l.confirmed(7, o(0x1A04, 1), 0x6041_0010);
        let tpdo5 = l.confirmed(7, o(0x1A04, 0), 1).expect("a tpdo");
        assert_eq!(l.mapping(tpdo5), None);
    }

    #[test]
    fn learnt_pdos_are_bounded() {
        let mut l = Learner::new();
        let mut kept = 0;
        for node in 1..=127u16 {
            for pdo in 0..64u16 {
                let obj = Object {
                    index: 0x1A00 + pdo,
                    sub: 0,
                };
                if l.confirmed(node, obj, 1).is_some() {
                    kept += 1;
                }
            }
        }
        assert_eq!(kept, MAX_LEARNT_PDOS);
        assert_eq!(l.dropped(), 127 * 64 - MAX_LEARNT_PDOS as u64);
        // A PDO already kept is still updated.
        let first = Object {
            index: 0x1A00,
            sub: 0,
        };
        assert!(l.confirmed(1, first, 2).is_some());
    }

    #[test]
    fn wants_pdo_parameters_and_transfers_in_progress() {
        let mut d = Downloads::new();
        assert!(d.wants(0x605, &[0x23, 0x00, 0x1A, 0x01]));
        assert!(d.wants(0x585, &[0x60, 0x00, 0x14, 0x01]));
        assert!(!d.wants(0x605, &[0x23, 0x18, 0x10, 0x01]), "identity");
        assert!(d.wants(0x605, &[0x2B, 0x40, 0x60, 0x00]), "controlword");
        assert!(!d.wants(0x605, &[0x2B, 0x41, 0x60, 0x00]), "statusword");
        assert!(!d.wants(0x185, &[0x23, 0x00, 0x1A, 0x01]), "not SDO");
        assert!(!d.wants(0x605, &[0x00]), "a segment, nothing going");
        d.feed(0x605, &[0x21, 0x00, 0x18, 0x01, 4, 0, 0, 0]);
        assert!(d.wants(0x605, &[0x00]), "a segment of a transfer");
        assert!(d.wants(0x585, &[0x20]));
        assert!(!d.wants(0x606, &[0x00]), "another node");
    }

    #[test]
    fn sdo_frames_end_to_end_give_the_statusword() {
        let mut d = Downloads::new();
        let mut l = Learner::new();
        let frames: [(u32, [u8; 8]); 8] = [
            (0x601, [0x23, 0x00, 0x18, 0x01, 0x81, 0x01, 0x00, 0x80]),
            (0x581, [0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0]),
            (0x601, [0x2F, 0x00, 0x1A, 0x00, 0x01, 0, 0, 0]),
            (0x581, [0x60, 0x00, 0x1A, 0x00, 0, 0, 0, 0]),
            (0x601, [0x23, 0x00, 0x1A, 0x01, 0x10, 0x00, 0x41, 0x60]),
            (0x581, [0x60, 0x00, 0x1A, 0x01, 0, 0, 0, 0]),
            (0x601, [0x23, 0x00, 0x18, 0x01, 0x81, 0x01, 0x00, 0x00]),
            (0x581, [0x60, 0x00, 0x18, 0x01, 0, 0, 0, 0]),
        ];
        let mut changed = None;
        for (id, data) in frames {
            if let Some(c) = d.feed(id, &data) {
                changed = l.confirmed(c.node, c.object, c.value).or(changed);
            }
        }
        let m = l.mapping(changed.expect("a pdo")).expect("a mapping");
        assert_eq!(m.cob_id.id, 0x181);
        let sw = m.field(object(cia402::STATUSWORD)).expect("mapped");
        assert_eq!(sw.read(&[0x37, 0x06]), Some(0x0637));
    }

    #[test]
    fn spec_parsing() {
        let m = parse_spec("0x181=0x6041").expect("valid");
        assert_eq!(m.len(), 1);
        assert_eq!(m[0].cob_id.id, 0x181);
        assert_eq!(m[0].node, Some(1));
        assert_eq!(m[0].direction, Some(Direction::Tpdo));
        assert_eq!(m[0].source, Source::Option);
        assert_eq!(m[0].objects, [Mapped::of_entry(0x6041_0010)]);
        let m = parse_spec("0x181=6041,0x6061:8,0x2000.3:32, 0x201=0x6040 ,386=0x603F:16")
            .expect("valid");
        let entries: Vec<Vec<u32>> = m
            .iter()
            .map(|m| m.objects.iter().map(|o| o.entry()).collect())
            .collect();
        assert_eq!(
            entries,
            [
                vec![0x6041_0010, 0x6061_0008, 0x2000_0320],
                vec![0x6040_0010],
                vec![0x603F_0010],
            ]
        );
        assert_eq!(m[2].cob_id.id, 386);
        let ext = parse_spec("0x18FF0001=0x6041").expect("29-bit");
        assert!(ext[0].cob_id.extended);
        assert_eq!(ext[0].node, None);
    }

    #[test]
    fn spec_errors_say_what_is_wrong() {
        let err = |s: &str| parse_spec(s).expect_err(s);
        assert!(err("0x6041").contains("before any COB-ID"));
        assert!(err("").contains("before any COB-ID"));
        assert!(err("zz=0x6041").contains("not a COB-ID"));
        assert!(err("0x181=0x6061").contains("length of 0x6061 in bits"));
        assert!(err("0x181=0x6061:0").contains("not a bit length"));
        assert!(err("0x181=0x6061:65").contains("not a bit length"));
        assert!(err("0x181=0xG041").contains("not an object index"));
        assert!(err("0x181=0x6041.300").contains("not a sub-index"));
        assert!(err("0x40000000=0x6041").contains("above 29 bits"));
        assert!(err("0x181=0x6041:32,0x6061:32,0x6062:8").contains("72 bits"));
        assert!(err("0x181=0x6041,385=0x6040").contains("given twice"));
    }

    #[test]
    fn assumed_mapping_is_tpdo1_statusword_and_rpdo1_controlword() {
        let mut table = MappingTable::new();
        for node in [3, 4] {
            for m in assumed_cia402(node).into_iter().flatten() {
                table.insert(m);
            }
        }
        let tpdo3 = CobId {
            id: 0x183,
            extended: false,
        };
        assert!(table.fields(tpdo3).is_some());
        assert!(table.withdraw_assumed(3));
        assert!(!table.withdraw_assumed(3), "withdrawn already");
        assert!(table.fields(tpdo3).is_none());
        assert_eq!(table.in_force().count(), 2, "node 4's stay");
        let [t, r] = assumed_cia402(3).expect("node 3");
        assert_eq!(t.cob_id.id, 0x183);
        assert_eq!(t.direction, Some(Direction::Tpdo));
        assert_eq!(t.field(object(0x6041)), Some(field(0, 16)));
        assert_eq!(r.cob_id.id, 0x203);
        assert_eq!(r.field(object(0x6040)), Some(field(0, 16)));
        assert!(t.source == Source::Assumed && r.source == Source::Assumed);
        assert_eq!(assumed_cia402(0), None);
        assert_eq!(assumed_cia402(1001), None, "no predefined set");
        assert_eq!(
            [Source::Sdo, Source::Dcf, Source::Option, Source::Assumed].map(Source::slug),
            ["sdo", "dcf", "option", "assumed"]
        );
    }

    fn std_id(id: u32) -> CobId {
        CobId {
            id,
            extended: false,
        }
    }

    #[test]
    fn cia402_fields_of_a_mapping() {
        let m = parse_spec("0x185=0x6061:8,0x6041,0x603F")
            .expect("valid")
            .remove(0);
        let f = Cia402Fields::of(&m).expect("maps the statusword");
        assert_eq!(f.statusword, Some(field(8, 16)));
        assert_eq!(f.error_code, Some(field(24, 16)));
        assert_eq!(f.controlword, None);
        let v = f.read(&[0x01, 0x37, 0x06, 0x10, 0x23]);
        assert_eq!(
            v,
            Cia402Values {
                statusword: Some(0x0637),
                controlword: None,
                error_code: Some(0x2310),
            }
        );
        // Too short for the error code: the statusword is still read.
        assert_eq!(f.read(&[0x01, 0x37, 0x06]).error_code, None);
        assert_eq!(f.read(&[0x01, 0x37, 0x06]).statusword, Some(0x0637));
        let other = parse_spec("0x185=0x6064:32").expect("valid").remove(0);
        assert_eq!(Cia402Fields::of(&other), None);
        assert!(!other.maps_decoded());
    }

    #[test]
    fn relevant_bits_are_the_state_command_and_error_code_bits() {
        let m = parse_spec("0x185=0x6061:8,0x6041,0x603F")
            .expect("valid")
            .remove(0);
        let f = Cia402Fields::of(&m).expect("maps the statusword");
        // Statusword bits 0-3, 5-7 at bit 8, the error code at bits 24-39.
        assert_eq!(f.relevant_bits(), Some(0x00FF_FF00_EF00));
        let rpdo = parse_spec("0x205=0x6040:16").expect("valid").remove(0);
        let f = Cia402Fields::of(&rpdo).expect("maps the controlword");
        assert_eq!(f.relevant_bits(), Some(0x008F));
        // A statusword of 8 bits: only those.
        let short = parse_spec("0x185=0x6041:8").expect("valid").remove(0);
        assert_eq!(
            Cia402Fields::of(&short).and_then(|f| f.relevant_bits()),
            Some(0xEF)
        );
        // Past the 8th byte (a CAN FD PDO): not foldable.
        let far = Cia402Fields {
            statusword: Some(field(56, 16)),
            ..Cia402Fields::default()
        };
        assert_eq!(far.relevant_bits(), None);
        let empty = Cia402Fields {
            statusword: Some(field(64, 0)),
            ..Cia402Fields::default()
        };
        assert_eq!(empty.relevant_bits(), Some(0), "no bits, no panic");
        // Words differing only in other bits are the same to a drive.
        let a = Cia402Values {
            statusword: Some(0x0637),
            controlword: Some(0x000F),
            error_code: Some(0),
        };
        let b = Cia402Values {
            statusword: Some(0x1237),
            controlword: Some(0x001F),
            error_code: Some(0),
        };
        assert_eq!(a.relevant(), b.relevant());
        let warning = Cia402Values {
            statusword: Some(0x06B7),
            ..a
        };
        assert_ne!(a.relevant(), warning.relevant());
    }

    #[test]
    fn the_first_source_wins_per_cob_id() {
        let mut t = MappingTable::new();
        let [assumed, _] = assumed_cia402(5).expect("node 5");
        t.insert(assumed);
        assert_eq!(
            t.mapping(std_id(0x185)).map(|m| m.source),
            Some(Source::Assumed)
        );
        let option = parse_spec("0x185=0x6061:8,0x6041")
            .expect("valid")
            .remove(0);
        t.insert(option);
        assert_eq!(
            t.mapping(std_id(0x185)).map(|m| m.source),
            Some(Source::Option)
        );
        assert_eq!(
            t.fields(std_id(0x185)).and_then(|f| f.statusword),
            Some(field(8, 16))
        );
        // The trace's own configuration beats both.
        let mut l = Learner::new();
        for (sub, value) in [(0u8, 0u32), (1, 0x6041_0010), (2, 0x603F_0010), (0, 2)] {
            l.confirmed(5, Object { index: 0x1A00, sub }, value);
        }
        let tpdo1 = l
            .confirmed(
                5,
                Object {
                    index: 0x1800,
                    sub: 1,
                },
                0x185,
            )
            .expect("tpdo1");
        t.learnt(tpdo1, l.mapping(tpdo1));
        assert_eq!(
            t.mapping(std_id(0x185)).map(|m| m.source),
            Some(Source::Sdo)
        );
        assert_eq!(
            t.fields(std_id(0x185)).and_then(|f| f.statusword),
            Some(field(0, 16))
        );
        // The trace moves TPDO1 to 0x285: the option is in force on 0x185
        // again, the learnt mapping on 0x285.
        l.confirmed(
            5,
            Object {
                index: 0x1800,
                sub: 1,
            },
            0x285,
        );
        t.learnt(tpdo1, l.mapping(tpdo1));
        assert_eq!(
            t.mapping(std_id(0x185)).map(|m| m.source),
            Some(Source::Option)
        );
        assert_eq!(
            t.mapping(std_id(0x285)).map(|m| m.source),
            Some(Source::Sdo)
        );
        // Switched off: nothing learnt is left.
        l.confirmed(
            5,
            Object {
                index: 0x1800,
                sub: 1,
            },
            0x8000_0285,
        );
        t.learnt(tpdo1, l.mapping(tpdo1));
        assert_eq!(t.mapping(std_id(0x285)), None);
        let ids: Vec<u32> = t.decoded_ids().map(|c| c.id).collect();
        assert_eq!(ids, [0x185]);
        assert_eq!(t.in_force().count(), 1);
    }

    #[test]
    fn a_table_lists_only_ids_that_carry_a_word() {
        let mut t = MappingTable::new();
        for m in parse_spec("0x181=0x6064:32,0x182=0x6041").expect("valid") {
            t.insert(m);
        }
        let ids: Vec<u32> = t.decoded_ids().map(|c| c.id).collect();
        assert_eq!(ids, [0x182]);
        assert_eq!(t.fields(std_id(0x181)), None);
        assert!(t.mapping(std_id(0x181)).is_some());
        assert_eq!(t.in_force().count(), 2);
    }

    proptest::proptest! {
        /// Any frames on SDO ids: no panic, and whatever is confirmed was
        /// on a node's ids.
        #[test]
        fn downloads_never_panic(
            frames in proptest::collection::vec(
                (0x580u32..0x680, proptest::collection::vec(proptest::num::u8::ANY, 0..9)),
                0..200),
        ) {
            let mut d = Downloads::new();
            let mut l = Learner::new();
            for (id, data) in frames {
                if let Some(c) = d.feed(id, &data) {
                    proptest::prop_assert!((1..=127).contains(&c.node));
                    proptest::prop_assert!(c.len <= 4);
                    l.confirmed(c.node, c.object, c.value);
                }
            }
            for m in l.mappings() {
                proptest::prop_assert!(!m.objects.is_empty());
            }
        }

        #[test]
        fn spec_parsing_never_panics(spec in "\\PC{0,40}") {
            let _ = parse_spec(&spec);
        }

        #[test]
        fn fields_never_panic_and_fit_their_bits(
            offset in 0u16..600, bits in 0u8..70,
            data in proptest::collection::vec(proptest::num::u8::ANY, 0..65),
        ) {
            if let Some(v) = field(offset, bits).read(&data) {
                proptest::prop_assert!(bits == 64 || v < 1u64 << bits);
            }
        }
    }
}
