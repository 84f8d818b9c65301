//! The error history of one input: every closed interval, kept out of
//! memory once there are many.
//!
//! Node reports list every error a node ever raised, and a trace can raise
//! millions; memory must stay bounded by the number of nodes and active
//! errors. Closed intervals are buffered; past a threshold the buffer is
//! sorted in report order (channel name, node, raise order) and appended to an
//! anonymous temporary file as one sorted run. Reports read the runs back with
//! a k-way merge, node by node, so no renderer ever holds the whole history.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;
use std::collections::binary_heap::PeekMut;
use std::fs::File;
use std::io::{self, Write};
use std::sync::Arc;

use super::interval::{At, ClearedBy, Interval};
use crate::canopen::NodeId;
use crate::canopen::register::Register;
use crate::trace::Timestamp;

/// Closed intervals kept in memory before they go to disk (~100 bytes each).
pub const DEFAULT_SPILL_AT: usize = 16 * 1024;

/// (channel, node) buckets up to which spilling sorts by bucket (see
/// [`History::order`]): 256 channels.
const MAX_BUCKETS: usize = 256 * 256;

/// One interval with the node it belongs to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Record {
    pub channel: u32,
    pub node: NodeId,
    pub interval: Interval,
}

/// Collects an input's intervals while it is read.
pub struct History {
    /// Channel names by index; the sort key uses the name (report order).
    /// Shared with the caller, which knows its channels by them too.
    names: Vec<Arc<str>>,
    buffer: Vec<Record>,
    spill_at: usize,
    file: Option<File>,
    runs: Vec<Run>,
    /// Why spilling failed, if it did (the history then stays in memory).
    spill_error: Option<String>,
}

#[derive(Clone, Copy, Debug)]
struct Run {
    offset: u64,
    records: u64,
}

impl History {
    pub fn new(spill_at: usize) -> Self {
        History {
            names: Vec::new(),
            buffer: Vec::new(),
            spill_at: spill_at.max(1),
            file: None,
            runs: Vec::new(),
            spill_error: None,
        }
    }

    /// Registers a channel name; returns its index for [`History::push`].
    pub fn add_channel(&mut self, name: impl Into<Arc<str>>) -> u32 {
        self.names.push(name.into());
        (self.names.len() - 1) as u32
    }

    pub fn push(&mut self, channel: u32, node: NodeId, interval: Interval) {
        self.buffer.push(Record {
            channel,
            node,
            interval,
        });
        if self.buffer.len() >= self.spill_at
            && self.spill_error.is_none()
            && let Err(e) = self.spill()
        {
            self.spill_error = Some(e.to_string());
        }
    }

    /// The records' indices in report order. Records are large and names
    /// are strings, so what is sorted is indices, by integer keys (the
    /// channels' name order computed once per call).
    ///
    /// Records come in the order errors cleared: interleaved across nodes,
    /// nearly in raise order within one. So they are first spread into one
    /// bucket per (channel, node) in a single pass (counting sort), then each
    /// bucket is sorted by raise order, which for a nearly sorted bucket is a
    /// pass too (the stable sort merges runs it finds). Only a history with
    /// a great many channels falls back to one comparison sort.
    fn order(names: &[Arc<str>], records: &[Record]) -> Vec<u32> {
        let ranks = Ranks::of(names, records.iter().map(|r| r.channel));
        let seq = |i: &u32| records.get(*i as usize).map_or(0, |r| r.interval.seq);
        let buckets = ranks.channels.len().max(1) * 256;
        // Buckets are per CANopen node id (below 256); a history with an
        // EtherCAT station address past a byte sorts by comparison.
        if buckets > MAX_BUCKETS || records.iter().any(|r| r.node > 255) {
            let mut keys: Vec<(u128, u32)> = records
                .iter()
                .enumerate()
                .map(|(i, r)| (ranks.key(r), i as u32))
                .collect();
            // The index makes keys unique: unstable sorting gives the stable order.
            keys.sort_unstable();
            return keys.into_iter().map(|(_, i)| i).collect();
        }
        let bucket = |r: &Record| ranks.rank_of(r) as usize * 256 + usize::from(r.node);
        // starts[b] is where bucket b begins in the result.
        let mut starts = vec![0u32; buckets + 1];
        for r in records {
            if let Some(n) = starts.get_mut(bucket(r) + 1) {
                *n += 1;
            }
        }
        for b in 1..starts.len() {
            let before = starts.get(b - 1).copied().unwrap_or(0);
            if let Some(n) = starts.get_mut(b) {
                *n += before;
            }
        }
        let mut order = vec![0u32; records.len()];
        let mut fill = starts.clone();
        for (i, r) in records.iter().enumerate() {
            if let Some(at) = fill.get_mut(bucket(r)) {
                if let Some(slot) = order.get_mut(*at as usize) {
                    *slot = i as u32;
                }
                *at += 1;
            }
        }
        for w in starts.windows(2) {
            if let [start, end] = *w
                && end > start + 1
                && let Some(part) = order.get_mut(start as usize..end as usize)
            {
                part.sort_by_key(seq);
            }
        }
        order
    }

    /// Sorts in report order.
    fn sort(names: &[Arc<str>], records: &mut Vec<Record>) {
        let order = Self::order(names, records);
        if order.windows(2).all(|w| w[0] < w[1]) {
            return;
        }
        let mut slots: Vec<Option<Record>> =
            std::mem::take(records).into_iter().map(Some).collect();
        records.extend(
            order
                .iter()
                .filter_map(|&i| slots.get_mut(i as usize).and_then(Option::take)),
        );
    }

    /// Writes the buffer as one sorted run.
    fn spill(&mut self) -> io::Result<()> {
        if self.buffer.is_empty() {
            return Ok(());
        }
        let order = Self::order(&self.names, &self.buffer);
        let file = match &mut self.file {
            Some(f) => f,
            None => self.file.insert(tempfile::tempfile()?),
        };
        let offset = self
            .runs
            .last()
            .map_or(0, |r| r.offset + r.records * RECORD as u64);
        let mut out = io::BufWriter::with_capacity(64 * 1024, &*file);
        let mut bytes = [0u8; RECORD];
        for r in order.iter().filter_map(|&i| self.buffer.get(i as usize)) {
            encode(r, &mut bytes);
            out.write_all(&bytes)?;
        }
        out.flush()?;
        self.runs.push(Run {
            offset,
            records: self.buffer.len() as u64,
        });
        self.buffer.clear();
        Ok(())
    }

    /// Ends collection; `open` are the intervals still active at the end.
    pub fn finish(mut self, open: impl IntoIterator<Item = Record>) -> ErrorHistory {
        self.buffer.extend(open);
        // A small remainder stays in memory; a large one goes to disk too,
        // so many inputs do not each keep a full buffer.
        if self.file.is_some()
            && self.buffer.len() > 1024
            && self.spill_error.is_none()
            && let Err(e) = self.spill()
        {
            self.spill_error = Some(e.to_string());
        }
        Self::sort(&self.names, &mut self.buffer);
        let ranks = Ranks::of(&self.names, 0..self.names.len() as u32);
        ErrorHistory {
            ranks: Arc::new(ranks),
            names: Arc::new(self.names),
            memory: Arc::new(self.buffer),
            file: self.file.map(Arc::new),
            runs: self.runs,
            spill_error: self.spill_error,
        }
    }
}

/// Report order (channel name, node, raise order) as integers: channels
/// ranked by name (equal names rank equal; a channel the names do not know
/// reads as `""`, like `ErrorHistory::channel_name`).
#[derive(Debug, Default)]
struct Ranks {
    /// (channel, rank), sorted by channel.
    by_channel: Vec<(u32, u32)>,
    /// Per rank, a channel with that name.
    channels: Vec<u32>,
}

fn name_of(names: &[Arc<str>], channel: u32) -> &str {
    names.get(channel as usize).map_or("", |n| n)
}

impl Ranks {
    /// Ranks of the given channels.
    fn of(names: &[Arc<str>], channels: impl Iterator<Item = u32>) -> Ranks {
        let mut ids: Vec<u32> = Vec::new();
        for c in channels {
            // Nearly every history has one or two channels.
            if ids.last() != Some(&c) {
                ids.push(c);
            }
        }
        ids.sort_unstable();
        ids.dedup();
        let mut by_name = ids.clone();
        by_name.sort_by(|&a, &b| name_of(names, a).cmp(name_of(names, b)));
        let mut by_channel = Vec::with_capacity(ids.len());
        let mut channels: Vec<u32> = Vec::new();
        for &c in &by_name {
            let same = channels
                .last()
                .is_some_and(|&p| name_of(names, p) == name_of(names, c));
            if !same {
                channels.push(c);
            }
            by_channel.push((c, channels.len().saturating_sub(1) as u32));
        }
        by_channel.sort_unstable();
        Ranks {
            by_channel,
            channels,
        }
    }

    fn rank(&self, channel: u32) -> u32 {
        match self.by_channel.binary_search_by_key(&channel, |&(c, _)| c) {
            Ok(i) => self.by_channel.get(i).map_or(0, |&(_, r)| r),
            Err(_) => 0,
        }
    }

    /// The rank of a record's channel (nearly always the only one).
    fn rank_of(&self, r: &Record) -> u32 {
        match self.by_channel.as_slice() {
            [(_, only)] => *only,
            _ => self.rank(r.channel),
        }
    }

    fn key(&self, r: &Record) -> u128 {
        (u128::from(self.rank_of(r)) << 80)
            | (u128::from(r.node) << 64)
            | u128::from(r.interval.seq)
    }

    /// Where `name` ranks: `Ok(rank)` if a channel has it, else `Err(rank)`
    /// of the first channel named after it.
    fn find(&self, names: &[Arc<str>], name: &str) -> Result<u32, u32> {
        let at = self.channels.partition_point(|&c| name_of(names, c) < name);
        let found = self
            .channels
            .get(at)
            .is_some_and(|&c| name_of(names, c) == name);
        if found { Ok(at as u32) } else { Err(at as u32) }
    }
}

/// A finished history: sorted runs on disk plus a sorted rest in memory.
#[derive(Clone, Debug)]
pub struct ErrorHistory {
    names: Arc<Vec<Arc<str>>>,
    ranks: Arc<Ranks>,
    /// Shared: reports are cloned whole (the caller keeps one, the
    /// renderer gets one), and this part can be most of the history.
    memory: Arc<Vec<Record>>,
    file: Option<Arc<File>>,
    runs: Vec<Run>,
    spill_error: Option<String>,
}

impl Default for ErrorHistory {
    fn default() -> Self {
        History::new(DEFAULT_SPILL_AT).finish([])
    }
}

impl ErrorHistory {
    /// Every interval in report order.
    pub fn merge(&self) -> Merge<'_> {
        let sources = self
            .runs
            .iter()
            .map(|run| RunReader::new(self.file.clone(), *run, chunk_records(self.runs.len())))
            .collect();
        let mut m = Merge {
            history: self,
            sources,
            memory: 0,
            heads: Vec::new(),
            heap: BinaryHeap::new(),
            pending: None,
            error: None,
        };
        m.heads = (0..m.sources.len()).map(|i| m.pull(i)).collect();
        m.heap = m
            .heads
            .iter()
            .enumerate()
            .filter_map(|(i, h)| h.as_ref().map(|r| Reverse((self.ranks.key(r), i))))
            .collect();
        m
    }

    /// Why the history could not go to disk (it was kept in memory).
    pub fn spill_error(&self) -> Option<&str> {
        self.spill_error.as_deref()
    }

    #[cfg(test)]
    pub fn channel_name(&self, channel: u32) -> &str {
        name_of(&self.names, channel)
    }
}

/// Reads one run back in chunks with positional reads (the file is shared).
struct RunReader {
    /// Records per read.
    chunk: usize,
    file: Option<Arc<File>>,
    next: u64,
    end: u64,
    buf: Vec<u8>,
    pos: usize,
}

/// Records per read: 512 (36 KiB) while there are few runs, fewer when
/// there are many, so that the read buffers of all runs together stay
/// within [`READ_BUDGET`] (a trace's length only adds runs).
const CHUNK_RECORDS: usize = 512;
const MIN_CHUNK_RECORDS: usize = 16;
const READ_BUDGET: usize = 4 << 20;

fn chunk_records(runs: usize) -> usize {
    (READ_BUDGET / RECORD / runs.max(1)).clamp(MIN_CHUNK_RECORDS, CHUNK_RECORDS)
}

impl RunReader {
    fn new(file: Option<Arc<File>>, run: Run, chunk: usize) -> Self {
        RunReader {
            chunk,
            file,
            next: run.offset,
            end: run.offset + run.records * RECORD as u64,
            buf: Vec::new(),
            pos: 0,
        }
    }

    fn next(&mut self) -> io::Result<Option<Record>> {
        if self.pos >= self.buf.len() {
            let left = self.end.saturating_sub(self.next);
            if left == 0 {
                return Ok(None);
            }
            let n = left.min((self.chunk * RECORD) as u64) as usize;
            self.buf.resize(n, 0);
            let Some(file) = &self.file else {
                return Ok(None);
            };
            read_exact_at(file, &mut self.buf, self.next)?;
            self.next += n as u64;
            self.pos = 0;
        }
        let bytes: &[u8; RECORD] = self
            .buf
            .get(self.pos..self.pos + RECORD)
            .and_then(|b| b.try_into().ok())
            .ok_or_else(|| {
                io::Error::new(io::ErrorKind::InvalidData, "short record in error history")
            })?;
        self.pos += RECORD;
        decode(bytes).map(Some)
    }
}

#[cfg(unix)]
fn read_exact_at(file: &File, buf: &mut [u8], offset: u64) -> io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

#[cfg(windows)]
fn read_exact_at(file: &File, mut buf: &mut [u8], mut offset: u64) -> io::Result<()> {
    use std::os::windows::fs::FileExt;
    while !buf.is_empty() {
        match file.seek_read(buf, offset)? {
            0 => return Err(io::ErrorKind::UnexpectedEof.into()),
            n => {
                buf = &mut buf[n..];
                offset += n as u64;
            }
        }
    }
    Ok(())
}

/// The k-way merge of a history's runs and its in-memory rest.
pub struct Merge<'h> {
    history: &'h ErrorHistory,
    sources: Vec<RunReader>,
    memory: usize,
    heads: Vec<Option<Record>>,
    /// The heads' keys and sources, least first.
    heap: BinaryHeap<Reverse<(u128, usize)>>,
    /// A record read one too far by [`NodeErrors`] (the next node's first).
    pending: Option<Record>,
    error: Option<io::Error>,
}

impl<'h> Merge<'h> {
    fn pull(&mut self, i: usize) -> Option<Record> {
        pull(&mut self.sources, &mut self.error, i)
    }

    /// A read error of the temporary file, once the merge is done.
    pub fn take_error(&mut self) -> Option<io::Error> {
        self.error.take()
    }

    /// The next record in report order.
    pub fn next_record(&mut self) -> Option<Record> {
        if let Some(r) = self.pending.take() {
            return Some(r);
        }
        let history = self.history;
        let from_memory = history.memory.get(self.memory);
        let take_memory = match (from_memory, self.heap.peek()) {
            (Some(m), Some(Reverse((head, _)))) => history.ranks.key(m) <= *head,
            (Some(_), None) => true,
            (None, _) => false,
        };
        if take_memory {
            self.memory += 1;
            return from_memory.cloned();
        }
        // The run that gave the least record usually gives the next one
        // too (runs overlap little): its new head replaces the top in place,
        // which settles in a compare or two instead of a pop and a push.
        let mut top = self.heap.peek_mut()?;
        let Reverse((_, i)) = *top;
        let record = self.heads.get_mut(i).and_then(Option::take);
        match (
            pull(&mut self.sources, &mut self.error, i),
            self.heads.get_mut(i),
        ) {
            (Some(next), Some(head)) => {
                *top = Reverse((history.ranks.key(&next), i));
                *head = Some(next);
            }
            _ => {
                PeekMut::pop(top);
            }
        }
        record
    }

    /// The intervals of one node, skipping any before it (unselected nodes).
    pub fn node_errors<'m>(&'m mut self, channel: &'m str, node: NodeId) -> NodeErrors<'m, 'h> {
        let history = self.history;
        NodeErrors {
            merge: self,
            channel: history.ranks.find(&history.names, channel),
            node,
        }
    }
}

/// The next record of run `i`; a read error is kept in `error`.
fn pull(sources: &mut [RunReader], error: &mut Option<io::Error>, i: usize) -> Option<Record> {
    match sources.get_mut(i).map(RunReader::next) {
        Some(Ok(r)) => r,
        Some(Err(e)) => {
            error.get_or_insert(e);
            None
        }
        None => None,
    }
}

/// Iterator over one node's intervals from a [`Merge`].
pub struct NodeErrors<'m, 'h> {
    merge: &'m mut Merge<'h>,
    /// The channel's rank, or where it would rank.
    channel: Result<u32, u32>,
    node: NodeId,
}

impl Iterator for NodeErrors<'_, '_> {
    type Item = Interval;

    fn next(&mut self) -> Option<Interval> {
        loop {
            let r = self.merge.next_record()?;
            let rank = self.merge.history.ranks.rank(r.channel);
            let order = match self.channel {
                Ok(channel) => (rank, r.node).cmp(&(channel, self.node)),
                Err(at) if rank < at => Ordering::Less,
                Err(_) => Ordering::Greater,
            };
            match order {
                Ordering::Less => continue,
                Ordering::Equal => return Some(r.interval),
                Ordering::Greater => {
                    self.merge.pending = Some(r);
                    return None;
                }
            }
        }
    }
}

// ---- the record encoding ------------------------------------------------------

/// channel u32, node's low byte, code u16, cleared_by u8, register u8, seq
/// u64, start line u64, end line u64 (+ flag u8), start time and end time
/// (flag u8, digits u8, secs u64, atto u64 each), status bit (flag u8, u8),
/// node's high byte (an EtherCAT station address is 16 bits).
const RECORD: usize = 4 + 1 + 2 + 1 + 1 + 8 + 8 + 9 + 18 + 18 + 2 + 1;

fn put_time(out: &mut [u8], t: Option<Timestamp>) {
    match t {
        Some(t) => {
            let (secs, atto, digits) = t.to_raw();
            out[0] = 1;
            out[1] = digits;
            out[2..10].copy_from_slice(&secs.to_le_bytes());
            out[10..18].copy_from_slice(&atto.to_le_bytes());
        }
        None => out[..18].fill(0),
    }
}

fn encode(r: &Record, out: &mut [u8; RECORD]) {
    let iv = &r.interval;
    out[0..4].copy_from_slice(&r.channel.to_le_bytes());
    let [node_low, node_high] = r.node.to_le_bytes();
    out[4] = node_low;
    out[5..7].copy_from_slice(&iv.code.to_le_bytes());
    out[7] = match iv.cleared_by {
        None => 0,
        Some(ClearedBy::Reset) => 1,
        Some(ClearedBy::PartialReset) => 2,
        Some(ClearedBy::Boot) => 3,
        Some(ClearedBy::StatusBit) => 4,
    };
    out[8] = iv.raised_register.0;
    out[9..17].copy_from_slice(&iv.seq.to_le_bytes());
    out[17..25].copy_from_slice(&iv.start.line.to_le_bytes());
    out[25] = u8::from(iv.end.is_some());
    out[26..34].copy_from_slice(&iv.end.map_or(0, |e| e.line).to_le_bytes());
    put_time(&mut out[34..52], iv.start.time);
    put_time(&mut out[52..70], iv.end.and_then(|e| e.time));
    out[70] = u8::from(iv.status_bit.is_some());
    out[71] = iv.status_bit.unwrap_or(0);
    out[72] = node_high;
}

fn corrupt() -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        "corrupt record in error history",
    )
}

fn get_u64(b: &[u8; RECORD], at: usize) -> u64 {
    let mut bytes = [0u8; 8];
    if let Some(s) = b.get(at..at + 8) {
        bytes.copy_from_slice(s);
    }
    u64::from_le_bytes(bytes)
}

fn get_time(b: &[u8; RECORD], at: usize) -> io::Result<Option<Timestamp>> {
    match b.get(at) {
        Some(0) => Ok(None),
        Some(1) => {
            let digits = b.get(at + 1).copied().unwrap_or(u8::MAX);
            Timestamp::from_raw(get_u64(b, at + 2), get_u64(b, at + 10), digits)
                .map(Some)
                .ok_or_else(corrupt)
        }
        _ => Err(corrupt()),
    }
}

/// A record from its bytes (fixed size: the offsets are constants, checked
/// when compiled; the values are checked here).
fn decode(b: &[u8; RECORD]) -> io::Result<Record> {
    let channel = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let code = u16::from_le_bytes([b[5], b[6]]);
    let cleared_by = match b[7] {
        0 => None,
        1 => Some(ClearedBy::Reset),
        2 => Some(ClearedBy::PartialReset),
        3 => Some(ClearedBy::Boot),
        4 => Some(ClearedBy::StatusBit),
        _ => return Err(corrupt()),
    };
    let end = match b[25] {
        0 => None,
        _ => Some(At {
            time: get_time(b, 52)?,
            line: get_u64(b, 26),
        }),
    };
    Ok(Record {
        channel,
        node: NodeId::from_le_bytes([b[4], b[72]]),
        interval: Interval {
            seq: get_u64(b, 9),
            code,
            start: At {
                time: get_time(b, 34)?,
                line: get_u64(b, 17),
            },
            end,
            cleared_by,
            raised_register: Register(b[8]),
            status_bit: match b[70] {
                0 => None,
                _ => Some(b[71]),
            },
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn interval(seq: u64, code: u16, closed: bool) -> Interval {
        Interval {
            seq,
            code,
            start: At {
                time: Timestamp::from_raw(
                    seq.wrapping_add(1_700_000_000),
                    123_000_000_000_000_000,
                    6,
                ),
                line: seq.wrapping_mul(10).wrapping_add(1),
            },
            end: closed.then_some(At {
                time: None,
                line: seq.wrapping_mul(10).wrapping_add(5),
            }),
            cleared_by: closed.then_some(ClearedBy::StatusBit),
            raised_register: Register(0x09),
            status_bit: closed.then_some(0x1B),
        }
    }

    #[test]
    fn records_survive_the_encoding() {
        for closed in [false, true] {
            let r = Record {
                channel: 7,
                node: 127,
                interval: interval(u64::MAX - 1, 0xFF01, closed),
            };
            let mut b = [0u8; RECORD];
            encode(&r, &mut b);
            assert_eq!(decode(&b).unwrap(), r);
        }
        assert!(decode(&[0xFF; RECORD]).is_err());
    }

    /// Pushes intervals of three nodes on two channels in close order and
    /// reads them back; the order must be the report order whatever spilled.
    fn roundtrip(spill_at: usize) -> Vec<(String, NodeId, u64)> {
        let mut h = History::new(spill_at);
        let b = h.add_channel("can1");
        let a = h.add_channel("can0");
        let mut open = Vec::new();
        for seq in (0..300u64).rev() {
            // 1001: a station address, whose high byte the spilled record keeps.
            for (ch, node) in [(b, 1001), (a, 9), (a, 2)] {
                let rec = Record {
                    channel: ch,
                    node,
                    interval: interval(seq, 0x4310, seq % 50 != 0),
                };
                if seq % 50 == 0 {
                    open.push(rec);
                } else {
                    h.push(ch, node, rec.interval);
                }
            }
        }
        read_back(&h.finish(open))
    }

    /// (channel name, node, raise order) of every record, as merged.
    fn read_back(hist: &ErrorHistory) -> Vec<(String, NodeId, u64)> {
        let mut m = hist.merge();
        let mut out = Vec::new();
        while let Some(r) = m.next_record() {
            out.push((
                hist.channel_name(r.channel).to_string(),
                r.node,
                r.interval.seq,
            ));
        }
        assert!(m.take_error().is_none());
        out
    }

    #[test]
    fn merge_gives_report_order_whether_or_not_it_spilled() {
        let in_memory = roundtrip(usize::MAX);
        assert_eq!(in_memory.len(), 900);
        assert_eq!(in_memory[0], ("can0".to_string(), 2, 0));
        assert_eq!(in_memory[300], ("can0".to_string(), 9, 0));
        assert_eq!(in_memory[899], ("can1".to_string(), 1001, 299));
        let mut sorted = in_memory.clone();
        sorted.sort();
        assert_eq!(in_memory, sorted);
        for spill_at in [1, 7, 100, 1000] {
            assert_eq!(roundtrip(spill_at), in_memory, "spill every {spill_at}");
        }
    }

    #[test]
    fn node_errors_of_a_channel_without_errors_take_nothing_from_the_next() {
        let mut h = History::new(2);
        let c = h.add_channel("c");
        let a = h.add_channel("a");
        for seq in 0..5 {
            h.push(c, 1, interval(seq, 0x2310, true));
            h.push(a, 1, interval(seq, 0x2310, true));
        }
        let hist = h.finish([]);
        let mut m = hist.merge();
        assert_eq!(m.node_errors("", 1).count(), 0);
        assert_eq!(m.node_errors("a", 1).count(), 5);
        assert_eq!(m.node_errors("b", 1).count(), 0);
        assert_eq!(m.node_errors("c", 0).count(), 0);
        assert_eq!(m.node_errors("c", 1).count(), 5);
        assert!(m.next_record().is_none());
    }

    #[test]
    fn node_errors_walk_node_by_node_and_skip_unselected_nodes() {
        let mut h = History::new(5);
        let ch = h.add_channel("can0");
        for seq in 0..20 {
            for node in [1, 2, 3] {
                h.push(ch, node, interval(seq, 0x2310, true));
            }
        }
        let hist = h.finish([]);
        let mut m = hist.merge();
        // Node 1 is not selected: node 2 and 3 are read, node 1 is skipped.
        let two: Vec<u64> = m.node_errors("can0", 2).map(|iv| iv.seq).collect();
        assert_eq!(two, (0..20).collect::<Vec<_>>());
        let three = m.node_errors("can0", 3).count();
        assert_eq!(three, 20);
        assert_eq!(m.node_errors("can0", 4).count(), 0);
    }

    /// Any push order, spill size and channel set (also more channels than
    /// the bucket sort takes, and channels sharing a name) reads back in
    /// report order: (channel name, node, raise order).
    fn merged_in_report_order(pushes: &[(usize, NodeId)], channels: usize, spill_at: usize) {
        let mut h = History::new(spill_at);
        let ids: Vec<u32> = (0..channels)
            .map(|c| h.add_channel(format!("can{}", c % 300)))
            .collect();
        let mut want = Vec::new();
        for (seq, &(c, node)) in pushes.iter().enumerate() {
            let ch = ids[c % ids.len()];
            // Raise order differs from push order: seq counts down in pairs.
            let seq = (pushes.len() - seq) as u64 ^ 1;
            h.push(ch, node, interval(seq, 0x1000, true));
            want.push((format!("can{}", (c % ids.len()) % 300), node, seq));
        }
        want.sort();
        assert_eq!(read_back(&h.finish([])), want);
    }

    #[test]
    fn many_channels_sort_without_buckets() {
        let pushes: Vec<(usize, NodeId)> = (0..2000)
            .map(|i| (i * 7 % 400, (i % 5) as NodeId * 300))
            .collect();
        merged_in_report_order(&pushes, 400, 300);
        merged_in_report_order(&pushes, 400, usize::MAX);
    }

    proptest::proptest! {
        #[test]
        fn any_history_merges_in_report_order(
            pushes in proptest::collection::vec((0usize..8, 0u16..1100), 0..400),
            channels in 1usize..5,
            spill_at in 1usize..64,
        ) {
            merged_in_report_order(&pushes, channels, spill_at);
        }
    }

    #[test]
    fn read_buffers_stay_within_the_budget_whatever_the_run_count() {
        assert_eq!(chunk_records(1), CHUNK_RECORDS);
        for runs in [100, 134, 268, 1000, 3000] {
            let n = chunk_records(runs);
            assert!((MIN_CHUNK_RECORDS..=CHUNK_RECORDS).contains(&n));
            assert!(n * RECORD * runs <= READ_BUDGET, "{runs} runs");
        }
        assert_eq!(chunk_records(1_000_000), MIN_CHUNK_RECORDS);
    }
}
