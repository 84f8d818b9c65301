//! What the metadata blocks say about the records: data groups, their
//! channel groups and, for the CAN bus-logging groups (`CAN_DataFrame`,
//! `CAN_RemoteFrame`, `CAN_ErrorFrame`), where each field of a frame is and
//! how it converts. Built from the kept metadata blocks once every block it
//! links to has been read.

use std::collections::{HashMap, HashSet};

use super::block::{
    Block, CN_MASTER, CN_VIRTUAL_MASTER, CN_VLSD, Cg, Cn, Conversion, Dg, SYNC_TIME, dl_entries,
    text, uint,
};
use crate::FrameKind;

/// Blocks followed along one chain at most (a loop in the links ends it).
const MAX_CHAIN: usize = 1 << 16;
/// Blocks visited to build one layout at most: real files need hundreds;
/// links that share chains could otherwise make the walk quadratic.
const MAX_VISITS: usize = 1 << 20;

/// How to find a linked block.
pub trait Blocks {
    /// The block at `offset`, `Err(true)` when not read yet (ahead of the
    /// reader), `Err(false)` when it is not there (a broken link).
    fn block(&self, offset: u64) -> Result<Block<'_>, bool>;
}

/// A link could not be followed (yet).
#[derive(Debug, PartialEq, Eq)]
pub enum Missing {
    /// The block is further on in the file.
    Ahead,
}

/// A raw channel value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Raw {
    U(u64),
    I(i64),
    F(f64),
}

impl Raw {
    pub fn as_f64(self) -> f64 {
        match self {
            Raw::U(v) => v as f64,
            Raw::I(v) => v as f64,
            Raw::F(v) => v,
        }
    }

    /// The value as an exact integer, when it is one.
    pub fn integer(self) -> Option<i128> {
        match self {
            Raw::U(v) => Some(i128::from(v)),
            Raw::I(v) => Some(i128::from(v)),
            Raw::F(v) if v.is_finite() && v.fract() == 0.0 && v.abs() < 9.0e18 => Some(v as i128),
            Raw::F(_) => None,
        }
    }
}

/// Where one channel's value is in a record and how it converts.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub byte: usize,
    pub bit: u8,
    pub bits: u32,
    pub data_type: u8,
    /// The value is the record's index in its group (cn_type 3 and 6).
    pub virtual_: bool,
    pub conversion: Conversion,
    /// Variable-length data: the record holds an offset into `data`.
    pub vlsd: bool,
    /// Where VLSD data is: a VLSD channel group or an SD/DZ/DL block.
    pub data: u64,
    /// The conversion's [`Conversion::decimal_scale`], once.
    pub scale: Option<u8>,
}

impl Channel {
    pub fn raw(&self, record: &[u8], sample: u64) -> Option<Raw> {
        if self.virtual_ {
            return Some(Raw::U(sample));
        }
        let big = self.data_type % 2 == 1;
        match self.data_type {
            0 | 1 => Some(Raw::U(uint(record, self.byte, self.bit, self.bits, big)?)),
            2 | 3 if self.bits == 0 => Some(Raw::I(0)),
            2 | 3 => {
                let v = uint(record, self.byte, self.bit, self.bits, big)?;
                let shift = 64u32.checked_sub(self.bits)?;
                Some(Raw::I(((v << shift) as i64) >> shift))
            }
            4 | 5 => {
                let v = uint(record, self.byte, self.bit, self.bits, big)?;
                match self.bits {
                    64 => Some(Raw::F(f64::from_bits(v))),
                    32 => Some(Raw::F(f64::from(f32::from_bits(v as u32)))),
                    _ => None,
                }
            }
            _ => None,
        }
    }

    /// The converted value as an unsigned integer (ids, lengths, flags).
    pub fn uint(&self, record: &[u8], sample: u64) -> Option<u64> {
        let raw = self.raw(record, sample)?;
        if let (Conversion::Identity, Raw::U(v)) = (&self.conversion, raw) {
            return Some(v);
        }
        let v = self.conversion.apply(raw.as_f64()).round();
        (v.is_finite() && v >= 0.0 && v <= u64::MAX as f64).then_some(v as u64)
    }

    /// A byte array in the record: `len` bytes at its byte offset.
    pub fn bytes<'r>(&self, record: &'r [u8]) -> &'r [u8] {
        let n = (self.bits / 8) as usize;
        record
            .get(self.byte..)
            .map(|r| r.get(..n).unwrap_or(r))
            .unwrap_or_default()
    }
}

/// The fields of a CAN bus-logging group.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CanFields {
    pub bus: Option<Channel>,
    pub id: Option<Channel>,
    pub ide: Option<Channel>,
    pub dlc: Option<Channel>,
    pub data_length: Option<Channel>,
    pub data_bytes: Option<Channel>,
    pub edl: Option<Channel>,
    /// An error frame's `ErrorType` ([`super::error_frame`]).
    pub error_type: Option<Channel>,
    /// `Dir`: 0 received, 1 transmitted.
    pub dir: Option<Channel>,
}

/// A field read as it is stored: an unsigned little-endian integer, not
/// converted, not virtual.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    pub byte: usize,
    pub bit: u8,
    pub bits: u32,
}

impl Field {
    fn of(c: &Channel) -> Option<Field> {
        (c.data_type == 0 && !c.virtual_ && !c.vlsd && c.conversion == Conversion::Identity)
            .then_some(Field {
                byte: c.byte,
                bit: c.bit,
                bits: c.bits,
            })
    }

    #[inline]
    pub fn get(self, record: &[u8]) -> Option<u64> {
        uint(record, self.byte, self.bit, self.bits, false)
    }
}

/// A frame's bus channel as the counting loop reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bus {
    /// Stored as it is in each record (python-can's layout).
    Stored(Field),
    /// The same for every record: no `BusChannel` (channel 0), or a
    /// virtual one converted to a constant (CANedge's).
    Constant(u64),
}

impl Bus {
    fn of(bus: Option<&Channel>) -> Option<Bus> {
        let Some(c) = bus else {
            return Some(Bus::Constant(0));
        };
        if let Some(f) = Field::of(c) {
            return Some(Bus::Stored(f));
        }
        // A virtual channel's value is the record's index, converted: a
        // linear conversion without factor makes it a constant, which the
        // decoder reads as it reads it for any record.
        match c.conversion {
            Conversion::Linear { factor, .. } if c.virtual_ && factor == 0.0 => {
                Some(Bus::Constant(c.uint(&[], 0).unwrap_or(0)))
            }
            _ => None,
        }
    }

    #[inline]
    pub fn get(self, record: &[u8]) -> u64 {
        match self {
            Bus::Stored(f) => f.get(record).unwrap_or(0),
            Bus::Constant(v) => v,
        }
    }
}

/// The fields a data frame on an unwanted id is counted by, when all are
/// stored as they are (python-can's and asammdf's layout): the counting
/// loop reads only these.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counting {
    /// Read only for the frames counted, for their channel.
    pub bus: Bus,
    pub id: Field,
    pub ide: Option<Field>,
    pub data_length: Field,
    pub edl: Option<Field>,
    /// Where the fixed data bytes are, and how many.
    pub data_at: usize,
    pub data_bytes: usize,
}

impl Counting {
    fn of(fields: &CanFields) -> Option<Counting> {
        let opt = |c: &Option<Channel>| match c {
            None => Some(None),
            Some(c) => Field::of(c).map(Some),
        };
        let data = fields.data_bytes.as_ref()?;
        if data.vlsd || data.virtual_ {
            return None;
        }
        Some(Counting {
            bus: Bus::of(fields.bus.as_ref())?,
            id: Field::of(fields.id.as_ref()?)?,
            ide: opt(&fields.ide)?,
            data_length: Field::of(fields.data_length.as_ref()?)?,
            edl: opt(&fields.edl)?,
            data_at: data.byte,
            data_bytes: (data.bits / 8) as usize,
        })
    }
}

/// One channel group.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// The CG block's offset (VLSD channels link to it).
    pub offset: u64,
    pub record_id: u64,
    /// Bytes of a record after its id (data and invalidation bytes).
    pub size: usize,
    pub vlsd: bool,
    /// The frames a CAN group holds, with their fields.
    pub can: Option<(FrameKind, CanFields)>,
    pub time: Option<Channel>,
    /// For a data frame group stored plainly: how to count its frames.
    pub counting: Option<Counting>,
}

/// One data group.
#[derive(Clone, Debug, PartialEq)]
pub struct DataGroup {
    pub rec_id_size: u8,
    pub groups: Vec<Group>,
    pub data: u64,
}

impl DataGroup {
    pub fn group(&self, record_id: u64) -> Option<usize> {
        if self.rec_id_size == 0 {
            return (!self.groups.is_empty()).then_some(0);
        }
        self.groups.iter().position(|g| g.record_id == record_id)
    }
}

/// The data groups, and what the layout could not make sense of.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layout {
    pub groups: Vec<DataGroup>,
    pub problems: Vec<String>,
}

/// What building a layout found wrong, and the blocks it visited.
#[derive(Default)]
pub struct Cx {
    problems: Vec<String>,
    visits: usize,
}

/// Follows a chain of blocks by their "next" link.
fn chain<B: Blocks, T>(
    blocks: &B,
    first: u64,
    what: &str,
    read: impl Fn(Block<'_>) -> Option<T>,
    next: impl Fn(&T) -> u64,
    cx: &mut Cx,
) -> Result<Vec<(u64, T)>, Missing> {
    let mut out = Vec::new();
    let mut seen = HashSet::new();
    let mut at = first;
    while at != 0 && out.len() < MAX_CHAIN && seen.insert(at) {
        cx.visits += 1;
        if cx.visits > MAX_VISITS {
            cx.problems
                .push("more linked blocks than read at most".into());
            break;
        }
        match blocks.block(at) {
            Ok(b) => match read(b) {
                Some(t) => {
                    let n = next(&t);
                    out.push((at, t));
                    at = n;
                }
                None => {
                    cx.problems
                        .push(format!("{what} block at byte offset {at} is not one"));
                    break;
                }
            },
            Err(true) => return Err(Missing::Ahead),
            Err(false) => {
                cx.problems
                    .push(format!("no {what} block at byte offset {at}"));
                break;
            }
        }
    }
    Ok(out)
}

fn named<B: Blocks>(blocks: &B, link: u64) -> Result<String, Missing> {
    if link == 0 {
        return Ok(String::new());
    }
    match blocks.block(link) {
        Ok(b) if b.header.is(b"TX") => Ok(text(b)),
        Ok(_) | Err(false) => Ok(String::new()),
        Err(true) => Err(Missing::Ahead),
    }
}

/// The channel (with its conversion) of a CN block.
fn channel<B: Blocks>(blocks: &B, cn: &Cn, cx: &mut Cx) -> Result<Channel, Missing> {
    let conversion = match cn.conversion {
        0 => Conversion::Identity,
        at => match blocks.block(at) {
            Ok(b) if b.header.is(b"CC") => match Conversion::read(b) {
                Ok(c) => c,
                Err(kind) => {
                    cx.problems.push(format!(
                        "conversion of type {kind} at byte offset {at} is not numeric; \
                         the raw value is used"
                    ));
                    Conversion::Identity
                }
            },
            Ok(_) | Err(false) => Conversion::Identity,
            Err(true) => return Err(Missing::Ahead),
        },
    };
    Ok(Channel {
        scale: conversion.decimal_scale(),
        byte: cn.byte_offset as usize,
        bit: cn.bit_offset,
        bits: cn.bit_count,
        data_type: cn.data_type,
        virtual_: cn.is_virtual(),
        conversion,
        vlsd: cn.kind == CN_VLSD,
        data: cn.data,
    })
}

/// The channels of a group by name, with the members of structures
/// (composition) as `Parent.Member` names as the writers give them.
fn channels<B: Blocks>(blocks: &B, first: u64, cx: &mut Cx) -> Result<Vec<(String, Cn)>, Missing> {
    let mut out = Vec::new();
    let mut todo = vec![(first, 0u8)];
    while let Some((at, depth)) = todo.pop() {
        for (_, cn) in chain(blocks, at, "CN", Cn::read, |c| c.next, cx)? {
            let name = named(blocks, cn.name)?;
            if cn.composition != 0 && depth < 4 {
                // A CA block (array) is no structure: its link leads nowhere here.
                if matches!(blocks.block(cn.composition), Ok(b) if b.header.is(b"CN")) {
                    todo.push((cn.composition, depth + 1));
                }
            }
            out.push((name, cn));
            if out.len() > MAX_CHAIN {
                return Ok(out);
            }
        }
    }
    Ok(out)
}

const KINDS: [(&str, FrameKind); 3] = [
    ("CAN_DataFrame", FrameKind::Data),
    ("CAN_RemoteFrame", FrameKind::Remote),
    ("CAN_ErrorFrame", FrameKind::Error),
];

fn group<B: Blocks>(blocks: &B, offset: u64, cg: &Cg, cx: &mut Cx) -> Result<Group, Missing> {
    let cns = channels(blocks, cg.cn_first, cx)?;
    let mut time = None;
    for (_, cn) in &cns {
        if matches!(cn.kind, CN_MASTER | CN_VIRTUAL_MASTER) && cn.sync == SYNC_TIME {
            time = Some(channel(blocks, cn, cx)?);
            break;
        }
    }
    // A bus-logging group: its structure channel or its members say which.
    let kind = KINDS.iter().find(|(name, _)| {
        cns.iter()
            .any(|(n, _)| n == name || n.strip_prefix(name).is_some_and(|rest| rest == ".ID"))
    });
    let can = match kind {
        Some((name, kind)) => {
            let mut fields = CanFields::default();
            for (n, cn) in &cns {
                let Some(member) = n.strip_prefix(name).and_then(|r| r.strip_prefix('.')) else {
                    continue;
                };
                let slot = match member {
                    "BusChannel" => &mut fields.bus,
                    "ID" => &mut fields.id,
                    "IDE" => &mut fields.ide,
                    "DLC" => &mut fields.dlc,
                    "DataLength" => &mut fields.data_length,
                    "DataBytes" => &mut fields.data_bytes,
                    "EDL" => &mut fields.edl,
                    "ErrorType" => &mut fields.error_type,
                    "Dir" => &mut fields.dir,
                    _ => continue,
                };
                if slot.is_none() {
                    *slot = Some(channel(blocks, cn, cx)?);
                }
            }
            Some((*kind, fields))
        }
        None => None,
    };
    let counting = match &can {
        Some((FrameKind::Data, fields)) => Counting::of(fields),
        _ => None,
    };
    Ok(Group {
        counting,
        offset,
        record_id: cg.record_id,
        size: cg.data_bytes as usize + cg.inval_bytes as usize,
        vlsd: cg.vlsd(),
        can,
        time,
    })
}

/// The layout the blocks describe, from the header's first data group;
/// `Err` while a block it needs is still ahead of the reader.
pub fn build<B: Blocks>(blocks: &B, dg_first: u64) -> Result<Layout, Missing> {
    let mut layout = Layout::default();
    let mut cx = Cx::default();
    let cx = &mut cx;
    for (_, dg) in chain(blocks, dg_first, "DG", Dg::read, |d| d.next, cx)? {
        let mut groups = Vec::new();
        for (at, cg) in chain(blocks, dg.cg_first, "CG", Cg::read, |c| c.next, cx)? {
            groups.push(group(blocks, at, &cg, cx)?);
        }
        if dg.rec_id_size == 0 && groups.len() > 1 {
            cx.problems.push(format!(
                "a data group without record ids has {} channel groups; only the first is read",
                groups.len()
            ));
        }
        if !matches!(dg.rec_id_size, 0 | 1 | 2 | 4 | 8) {
            cx.problems.push(format!(
                "record ids of {} bytes: the data group is not read",
                dg.rec_id_size
            ));
            continue;
        }
        layout.groups.push(DataGroup {
            rec_id_size: dg.rec_id_size,
            groups,
            data: dg.data,
        });
    }
    layout.problems = std::mem::take(&mut cx.problems);
    Ok(layout)
}

/// The data blocks (DT, DZ, SD) a link leads to, in list order: the block
/// itself, or the blocks of a DL chain (through an HL block).
pub fn data_blocks<B: Blocks>(blocks: &B, link: u64) -> Result<Vec<u64>, Missing> {
    let mut out = Vec::new();
    let mut at = link;
    if let Ok(b) = blocks.block(at)
        && b.header.is(b"HL")
    {
        at = b.link(0);
    }
    let mut seen = HashSet::new();
    while at != 0 && seen.insert(at) && out.len() < MAX_CHAIN * 16 {
        match blocks.block(at) {
            Ok(b) if b.header.is(b"DL") => {
                let (next, entries) = dl_entries(b);
                out.extend(entries.into_iter().filter(|&e| e != 0));
                at = next;
            }
            // A data block (read as a stream, never kept), or not yet seen.
            Ok(_) | Err(false) => {
                out.push(at);
                break;
            }
            Err(true) if seen.len() == 1 => {
                // Ahead: a data block streams when it comes; a DL would
                // have to be read first, so the caller decides.
                out.push(at);
                break;
            }
            Err(true) => return Err(Missing::Ahead),
        }
    }
    Ok(out)
}

/// Which data group each data block belongs to.
pub fn owners<B: Blocks>(blocks: &B, layout: &Layout) -> HashMap<u64, usize> {
    let mut owners = HashMap::new();
    for (i, dg) in layout.groups.iter().enumerate() {
        if let Ok(list) = data_blocks(blocks, dg.data) {
            for at in list {
                owners.entry(at).or_insert(i);
            }
        }
    }
    owners
}
