//! ASAM MDF 4 bus logging (CSS Electronics CANedge, Vector, python-can's
//! MF4Writer through asammdf), read as a forward-only stream.
//!
//! Why our own reader: the Rust MDF crates were tried on the seven real
//! CANedge files (2026-11): mf4-rs 3.8.0 refuses every unfinalized file
//! (`FileIdentifierError("UnFinMF ")`, 6 of 7) and mdf4-rs (0.6.0 needs
//! rustc 1.97; 0.3.3 tried) reads the unfinalized ones short (1794 records
//! of 2010, 5544 of 5588, 9474 of 9600, 1799 of 1815) and leaves the
//! `CAN_DataFrame` structure to the caller; both map or load the whole
//! file, where our input is a forward-only `Read` (stdin, gzip).
//!
//! What is read: the channel groups with a `CAN_DataFrame`,
//! `CAN_RemoteFrame` or `CAN_ErrorFrame` structure (or members named so),
//! with `BusChannel` (the channel name, as a number), `ID` (29 bits; bit 31
//! is the IDE bit when there is no `IDE` member), `IDE`, `DLC`,
//! `DataLength`, `DataBytes` (a fixed byte array, or VLSD: an offset into
//! a VLSD channel group's records or into SD blocks), `EDL`; members may be
//! virtual (their value is the record index, converted: CANedge keeps
//! constants so) and converted (linear, rational, value tables: CANedge's
//! DLC-to-length table). Sorted and unsorted data groups (record ids of 1,
//! 2, 4 or 8 bytes), DT, DZ (deflate and transposed deflate), DL and HL
//! lists, SD blocks. Unfinalized files (`UnFinMF `) whose last DT block's
//! length was not updated: that block's data runs to the end of the input.
//! Times: the header's start time (ns since the epoch, UTC unless its local
//! time flag says otherwise, then taken as it is with a note) plus the
//! master channel, exact when it counts units of 10^-k s (CANedge's 48-bit
//! microseconds, float nanoseconds), else to the nanosecond.
//!
//! Counting: each record is one "line", numbered in file order: a frame, a
//! skipped record (LIN, VLSD records, any other group) or a malformed one.
//! A record id the file does not declare makes the rest of that data block
//! unreadable (records have no other framing): one malformed line with its
//! byte offset, and reading goes on with the next block.
//!
//! Forward only: links are file offsets, and a block may link to one that
//! is behind the reader or not read yet. The metadata blocks the layout
//! needs (DG, CG, CN, CC, TX, DL, HL) are kept as they pass (at most
//! [`MAX_META`] bytes); comments, attachments and the like are skipped.
//! A data block streams through the decoder when everything it needs is
//! known; otherwise (CANedge's finalized files put data before the last
//! data groups, SD blocks after the records that point into them) it goes
//! to a temporary file, with every data block after it, and is decoded
//! from there at the end of the input, in file order. SD blocks always go
//! to the temporary file: records look their data up there. CANedge writes
//! a frame before the VLSD record holding its data bytes: the frame waits
//! for it (at most `MAX_WAITING` frames, `MAX_QUEUE` records queued).
//! Memory is bounded by the kept metadata, a few DZ blocks inflated (the
//! one decoded, one inflated ahead and their buffers; each at most
//! `block::MAX_INFLATED`), a 64 KiB chunk, one record and the last
//! [`VLSD_WINDOW`] VLSD records of each VLSD group; the disk by the input
//! (measured: a 200 MB CANedge-like file in 8 MiB peak RSS).
//!
//! Speed: with the caller's interest ([`FrameSource::next_item`]), data
//! frames on ids nobody wants are only counted, by a loop that reads just
//! ID, IDE, DataLength and EDL where a group stores them as they are, and
//! BusChannel for the channel they are counted on
//! ([`FrameSource::counted_ids`]); a DZ block is decoded where it was
//! inflated, and spooled DZ blocks are inflated ahead on a second thread
//! (`ahead`). 512 MiB of records:
//! 482 MB/s uncompressed; with transposed deflate 1.14x the time of
//! inflating the DZ blocks alone (docs/performance.md).

#[cfg(unix)]
mod ahead;
mod block;
mod layout;
#[cfg(test)]
mod tests;

use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom, Write};

use crate::error_frame::{ErrorFrame, class, location, protocol};
use crate::id_counts::CountedChannel;
use crate::read::{read_full, read_until_stopped};
use crate::{
    Counted, Format, Frame, FrameKind, FrameSource, IdCounts, Interest, Next, NumberedChannel,
    Parsed, Payload, Reason, Timestamp,
};
use block::{Block, HEADER, Header, ID_LEN, Id};
use layout::{Blocks, Channel, Layout, Raw};

pub use block::is_magic;

/// Metadata kept at most (real files: tens of KiB).
pub const MAX_META: usize = 64 * 1024 * 1024;
/// Largest metadata block kept.
const MAX_META_BLOCK: u64 = 16 * 1024 * 1024;
/// The most the temporary file of data blocks that wait for their
/// metadata may hold. Real files written data first (CANedge finalized,
/// asammdf, python-can) are split at tens to hundreds of MB; a gzip input
/// of a few MB can inflate to anything, and the temporary directory is
/// often memory (tmpfs), so it is bounded.
pub const MAX_SPOOL: u64 = 4 << 30;
/// Largest record (a VLSD record's length field is 32 bits).
pub const MAX_RECORD: usize = 16 * 1024 * 1024;
/// VLSD records of a group kept for the records that point back to them
/// (CANedge writes each just before its frame).
pub const VLSD_WINDOW: usize = 256;
/// Bytes of data decoded at a time.
const CHUNK: usize = 64 * 1024;
/// Records decoded before the queue is handed out.
const RUN: usize = 4096;
/// Bus channels (from 0) whose [`CountedIds`] channel is kept: a file has
/// a few; a damaged one may name any number, each then looked up by name.
const COUNTED_BUSES: usize = 256;
const ATTO: u128 = 1_000_000_000_000_000_000;

/// What one record is.
#[derive(Debug)]
enum Out {
    Frame(Decoded),
    Skipped,
    Malformed(Reason),
    /// A frame whose data bytes are in a VLSD record not read yet
    /// (CANedge writes it after the frame): data group, VLSD group, offset
    /// of the record, data length.
    Waiting(Decoded, Key, usize),
    /// Data frames on ids the caller does not want: only counted.
    Plain(u64),
}

/// A plain frame's time as stored: its group, its index there and the
/// bytes of its group's master channel, read as a time only when asked for
/// ([`FrameSource::plain_span`]; converting every plain frame's time cost
/// MF4 23% more instructions, reading its value 6%, copying its bytes 1%).
#[derive(Clone, Copy, Debug)]
struct PlainTime {
    dg: u32,
    gi: u32,
    sample: u64,
    /// The record's bytes from the master channel's first: a value of up
    /// to 64 bits at a bit offset under 8 fits in 9.
    bytes: [u8; 9],
}

impl PlainTime {
    #[inline]
    fn of(dg: usize, gi: usize, c: &Channel, record: &[u8], sample: u64) -> PlainTime {
        let mut bytes = [0u8; 9];
        // Nine bytes at once where the record has them (a fixed copy, no
        // call), else what it has.
        match record.get(c.byte..c.byte.saturating_add(9)) {
            Some(from) => bytes.copy_from_slice(from),
            None => {
                let from = record.get(c.byte..).unwrap_or_default();
                for (to, from) in bytes.iter_mut().zip(from) {
                    *to = *from;
                }
            }
        }
        PlainTime {
            dg: dg as u32,
            gi: gi as u32,
            sample,
            bytes,
        }
    }
}

/// The frames only counted, by channel and identifier
/// ([`FrameSource::counted_ids`]), and where each bus channel's are.
#[derive(Default)]
struct CountedIds {
    ids: IdCounts,
    /// By bus channel number.
    buses: Vec<CountedChannel>,
}

impl CountedIds {
    /// Where frames only counted on bus channel `bus` are counted: under
    /// its name as a frame's ([`NumberedChannel`]), looked up once.
    #[inline]
    fn channel(&mut self, bus: u64) -> CountedChannel {
        match usize::try_from(bus).ok().and_then(|b| self.buses.get(b)) {
            Some(&c) if c != CountedChannel::Unknown => c,
            _ => self.look_up(bus),
        }
    }

    #[inline(never)]
    fn look_up(&mut self, bus: u64) -> CountedChannel {
        let c = self
            .ids
            .counted_channel(NumberedChannel::default().name(bus));
        if let Ok(b) = usize::try_from(bus)
            && b < COUNTED_BUSES
        {
            if self.buses.len() <= b {
                self.buses.resize(b + 1, CountedChannel::Unknown);
            }
            if let Some(slot) = self.buses.get_mut(b) {
                *slot = c;
            }
        }
        c
    }

    /// One frame only counted.
    #[inline]
    fn count(&mut self, bus: u64, id: u32, extended: bool) {
        let c = self.channel(bus);
        self.ids.count_in(c, id, extended);
    }
}

/// Adds `n` plain frames to the queue's last entry when that is plain
/// frames too, else queues them.
/// `span` widened to reach from `first` to `last`.
fn widen(
    span: Option<(Timestamp, Timestamp)>,
    first: Timestamp,
    last: Timestamp,
) -> (Timestamp, Timestamp) {
    match span {
        Some((a, b)) => (a.min(first), b.max(last)),
        None => (first, last),
    }
}

/// Plain frames of group `gi` of data group `dg`, a run from `first` to
/// `last` or one frame, into the group's span.
fn note_plain(states: &mut [DgState], dg: usize, gi: usize, first: PlainTime, last: PlainTime) {
    if let Some(span) = states.get_mut(dg).and_then(|s| s.plain.get_mut(gi)) {
        // The group's first is kept: only the last is stored again.
        match span {
            Some((_, l)) => *l = last,
            None => *span = Some((first, last)),
        }
    }
}

fn queue_plain(queue: &mut VecDeque<Out>, n: u64) {
    match queue.back_mut() {
        Some(Out::Plain(k)) => *k += n,
        _ => queue.push_back(Out::Plain(n)),
    }
}

impl<R: Read> FrameSource for Mf4Reader<R> {
    fn format(&self) -> Option<Format> {
        Some(Format::Mf4)
    }

    /// Notes go out before the next record is decoded: one found while
    /// decoding a record is told after that record, and those found at the
    /// end of the file before the end.
    #[inline]
    fn next_item(&mut self, interest: Option<&Interest>) -> io::Result<Option<Next<'_>>> {
        self.decode_next(interest, true)
    }

    /// Every frame's span, not only the plain frames': a sorted file's
    /// groups come one after another, so its last record need not be its
    /// latest (a CANedge file's last group ended a second before another's),
    /// and the span is the earliest and latest frame whatever was decoded.
    fn plain_span(&self) -> Option<(Timestamp, Timestamp)> {
        let plain = self.states.iter().flat_map(|s| s.plain.iter().flatten());
        plain.fold(self.handed_span, |span, (first, last)| {
            match (self.plain_time(*first), self.plain_time(*last)) {
                (Some(first), Some(last)) => Some(widen(span, first, last)),
                _ => span,
            }
        })
    }

    /// Every frame only counted so far, including those of the
    /// [`Next::Counted`] items still queued (counted as decoded, up to a
    /// chunk of records ahead of what was returned).
    fn counted_ids(&self) -> Option<&IdCounts> {
        Some(&self.counted_ids.ids)
    }
}

/// A VLSD record: data group, channel group, offset in the group's data.
type Key = (usize, usize, u64);

/// Frames that may wait for their data bytes at once; past that the
/// oldest is reported.
const MAX_WAITING: usize = 4096;
/// Records decoded ahead of a waiting frame at most.
const MAX_QUEUE: usize = 1 << 16;

#[derive(Debug)]
struct Decoded {
    time: Option<Timestamp>,
    channel: u64,
    id: u32,
    extended: bool,
    kind: FrameKind,
    len: u8,
    data: Payload,
}

/// The input with bytes put back in front, and its offset.
struct Input<R> {
    inner: R,
    back: Vec<u8>,
    at: usize,
    offset: u64,
    eof: bool,
    /// A cancel cut the input (`--follow`, a live pipe, then Ctrl-C): it
    /// ends there, as a file ends, so what was read is decoded (the spooled
    /// blocks too: data written before its metadata, as CANedge, asammdf
    /// and python-can write, would otherwise all be lost), then this error
    /// comes after the last record. A block the stop cut is not reported.
    stopped: Option<io::Error>,
}

impl<R: Read> Read for Input<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        Input::read(self, buf)
    }
}

impl<R: Read> Input<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = if self.at < self.back.len() {
            let rest = self.back.get(self.at..).unwrap_or_default();
            let n = rest.len().min(buf.len());
            if let (Some(d), Some(s)) = (buf.get_mut(..n), rest.get(..n)) {
                d.copy_from_slice(s);
            }
            self.at += n;
            n
        } else if self.stopped.is_some() {
            0
        } else {
            let (n, stopped) = read_until_stopped(&mut self.inner, buf)?;
            self.stopped = stopped;
            n
        };
        if n == 0 && !buf.is_empty() {
            self.eof = true;
        }
        self.offset += n as u64;
        Ok(n)
    }

    fn full(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let mut n = 0;
        while n < buf.len() {
            let k = self.read(buf.get_mut(n..).unwrap_or_default())?;
            if k == 0 {
                break;
            }
            n += k;
        }
        Ok(n)
    }

    fn unread(&mut self, bytes: &[u8]) {
        let mut v = bytes.to_vec();
        v.extend_from_slice(self.back.get(self.at..).unwrap_or_default());
        self.back = v;
        self.at = 0;
        self.offset -= bytes.len() as u64;
        self.eof = false;
    }

    /// Skips `n` bytes, keeping the first `keep` of them in `kept`; how
    /// many there were.
    fn skip_keeping(&mut self, n: u64, keep: u64, kept: &mut Vec<u8>) -> io::Result<u64> {
        let first = n.min(keep) as usize;
        kept.resize(first, 0);
        let got = self.full(kept)?;
        kept.truncate(got);
        if got < first {
            return Ok(got as u64);
        }
        Ok(got as u64 + self.skip(n - first as u64)?)
    }

    /// Skips `n` bytes; how many there were.
    fn skip(&mut self, n: u64) -> io::Result<u64> {
        let mut left = n;
        let mut buf = [0u8; 8192];
        while left > 0 {
            let want = left.min(buf.len() as u64) as usize;
            let k = self.read(buf.get_mut(..want).unwrap_or_default())?;
            if k == 0 {
                break;
            }
            left -= k as u64;
        }
        Ok(n - left)
    }
}

/// Data blocks kept in a temporary file until they can be decoded.
struct Spool {
    file: File,
    end: u64,
    /// The most it may hold ([`MAX_SPOOL`]).
    limit: u64,
    /// DT and DZ blocks in file order: (block offset, kind, position, length).
    items: Vec<(u64, [u8; 2], u64, u64)>,
    /// SD blocks (inflated when zipped): block offset -> (position, length).
    sd: HashMap<u64, (u64, u64)>,
}

impl Spool {
    fn new(limit: u64) -> io::Result<Spool> {
        // The error names the temporary directory: it is what failed, and
        // the caller puts the trace's name in front of the message.
        let file = tempfile::tempfile().map_err(|e| {
            io::Error::new(
                e.kind(),
                format!(
                    "cannot create a temporary file in {} (TMPDIR) for the MF4 data written \
                     before its metadata: {e}",
                    std::env::temp_dir().display()
                ),
            )
        })?;
        Ok(Spool {
            file,
            end: 0,
            limit,
            items: Vec::new(),
            sd: HashMap::new(),
        })
    }

    fn append(&mut self, bytes: &[u8]) -> io::Result<()> {
        if self.end.saturating_add(bytes.len() as u64) > self.limit {
            let limit = if self.limit.is_multiple_of(1 << 20) {
                format!("{} MiB", self.limit >> 20)
            } else {
                format!("{} bytes", self.limit)
            };
            return Err(io::Error::other(format!(
                "the MF4 data written before its metadata (kept in a temporary file until the \
                 metadata comes) is over {limit}: not read further"
            )));
        }
        self.file.seek(SeekFrom::Start(self.end))?;
        self.file.write_all(bytes)?;
        self.end += bytes.len() as u64;
        Ok(())
    }

    fn read_at(&mut self, pos: u64, buf: &mut [u8]) -> io::Result<usize> {
        self.file.seek(SeekFrom::Start(pos))?;
        read_full(&mut self.file, buf)
    }
}

/// The metadata blocks kept, by offset.
struct Meta {
    blocks: HashMap<u64, Vec<u8>>,
    bytes: usize,
    /// Blocks before this offset have been read (or skipped).
    read_up_to: u64,
    /// At the end of the input: nothing more will come.
    done: bool,
}

impl Blocks for Meta {
    fn block(&self, offset: u64) -> Result<Block<'_>, bool> {
        match self.blocks.get(&offset).and_then(|b| Block::new(b)) {
            Some(b) => Ok(b),
            None => Err(!self.done && offset >= self.read_up_to),
        }
    }
}

/// Where the data being decoded comes from.
enum Active {
    /// Block data straight from the input; `None`: to the end of the input.
    Input { dg: usize, left: Option<u64> },
    /// A spooled DT block's data.
    Spooled { dg: usize, pos: u64, left: u64 },
    /// An inflated DZ block.
    Inflated { dg: usize, data: Vec<u8> },
}

/// The last VLSD records of a group: (offset in the group's data, bytes).
type Window = VecDeque<(u64, Vec<u8>)>;

/// Decoding state of a data group.
#[derive(Default)]
struct DgState {
    /// The start of a record cut by the end of a block, while another
    /// group's block is decoded (DL lists may interleave).
    carry: Vec<u8>,
    /// The rest of the current block cannot be read (unknown record id).
    lost: bool,
    /// Records read per channel group (the value of virtual channels).
    samples: Vec<u64>,
    /// Per channel group: its first and last plain frames' times as stored
    /// (a group's records come in time order; the groups of a sorted file
    /// one after another, so the span is taken over them at the end).
    plain: Vec<Option<(PlainTime, PlainTime)>>,
    /// Per VLSD group: the offset of its next record, and its last records.
    vlsd: Vec<(u64, Window)>,
}

/// Reads an MDF 4 stream record by record.
pub struct Mf4Reader<R> {
    input: Input<R>,
    unfinished_dt: bool,
    dg_first: u64,
    /// Start time, attoseconds since the epoch, and its digits.
    start: (u128, u8),
    meta: Meta,
    layout: Option<Layout>,
    /// The metadata a failed layout build had: retried only when it grew.
    tried: Option<(usize, bool)>,
    owners: HashMap<u64, usize>,
    owners_stale: bool,
    states: Vec<DgState>,
    spool: Option<Spool>,
    /// The most the spool may hold ([`MAX_SPOOL`]; smaller in tests).
    spool_limit: u64,
    /// The spooled DZ blocks inflated ahead on another thread, while they
    /// are replayed ([`ahead`]).
    #[cfg(unix)]
    ahead: Option<ahead::Ahead>,
    /// A DT/DZ block went to the spool: all later ones follow (file order).
    spooling: bool,
    replay: Option<usize>,
    active: Option<Active>,
    /// Records decoded, not yet taken (at most one chunk's).
    queue: VecDeque<Out>,
    /// The earliest and latest times of the frames handed on.
    handed_span: Option<(Timestamp, Timestamp)>,
    /// Every plain frame by channel and identifier.
    counted_ids: CountedIds,
    /// Records taken from the queue so far (queue positions of waiters).
    popped: u64,
    /// Waiting frames by the VLSD record they need: their queue position.
    waiting: HashMap<Key, u64>,
    notes: VecDeque<String>,
    told: std::collections::HashSet<String>,
    finished: bool,
    channel: NumberedChannel,
    buf: Vec<u8>,
    /// A DZ block's bytes, its inflated data and the transposed bytes:
    /// kept from block to block.
    zbuf: Vec<u8>,
    spare: Vec<u8>,
    scratch: Vec<u8>,
    /// Data bytes of group `win_dg` being split into records, from `win_pos`.
    win: Vec<u8>,
    win_pos: usize,
    win_dg: usize,
    /// Decoding stopped after a wanted frame (the caller's interest may
    /// change with it): go on in the window before reading more.
    resume: bool,
}

impl<R: Read> Mf4Reader<R> {
    /// Reads the identification and header blocks. An error means this is
    /// not a readable MDF 4 file (MDF 3 included).
    pub fn new(inner: R) -> io::Result<Mf4Reader<R>> {
        let invalid = |m: String| io::Error::new(io::ErrorKind::InvalidData, m);
        let mut input = Input {
            inner,
            back: Vec::new(),
            at: 0,
            offset: 0,
            eof: false,
            stopped: None,
        };
        let mut id = [0u8; ID_LEN];
        let got = input.full(&mut id)?;
        let unfinished_flags = match block::identify(id.get(..got).unwrap_or_default()) {
            Id::NotMdf => {
                return Err(invalid(
                    "not an MDF file: it does not start with \"MDF     \" or \"UnFinMF \"".into(),
                ));
            }
            Id::OtherVersion(v) => {
                return Err(invalid(format!(
                    "MDF version {v} is not read, only MDF 4 (asammdf converts: mdf.convert('4.11'))"
                )));
            }
            Id::Mdf4 { unfinished, flags } => unfinished.then_some(flags),
        };
        if got < ID_LEN {
            return Err(invalid(format!(
                "MDF identification block cut off after {got} bytes"
            )));
        }
        let mut head = [0u8; HEADER];
        let n = input.full(&mut head)?;
        let header = Header::read(head.get(..n).unwrap_or_default())
            .filter(|h| h.is(b"HD") && h.sane() && h.len <= 4096)
            .ok_or_else(|| invalid("no MDF header block (HD) at byte offset 64".into()))?;
        let mut hd = head.to_vec();
        hd.resize(header.len as usize, 0);
        let n = input.full(hd.get_mut(HEADER..).unwrap_or_default())?;
        let hd_block = Block::new(&hd)
            .filter(|_| n + HEADER == hd.len())
            .and_then(block::HeaderBlock::read)
            .ok_or_else(|| invalid("MDF header block (HD) cut off".into()))?;
        let mut notes = VecDeque::new();
        if hd_block.local() {
            notes.push_back(
                "the MDF start time is local time of an unknown zone; times are read as UTC"
                    .to_string(),
            );
        }
        let start_ns = u128::from(hd_block.start_ns);
        let start_digits = if start_ns % 1_000_000_000 == 0 { 0 } else { 9 };
        Ok(Mf4Reader {
            unfinished_dt: unfinished_flags.is_some_and(|f| f & block::UNFIN_LAST_DT_LENGTH != 0),
            dg_first: hd_block.dg_first,
            start: (start_ns * 1_000_000_000, start_digits),
            meta: Meta {
                blocks: HashMap::new(),
                bytes: 0,
                read_up_to: input.offset,
                done: false,
            },
            input,
            layout: None,
            tried: None,
            owners: HashMap::new(),
            owners_stale: false,
            states: Vec::new(),
            spool: None,
            spool_limit: MAX_SPOOL,
            #[cfg(unix)]
            ahead: None,
            spooling: false,
            replay: None,
            active: None,
            queue: VecDeque::new(),
            handed_span: None,
            counted_ids: CountedIds::default(),
            popped: 0,
            waiting: HashMap::new(),
            notes,
            told: Default::default(),
            finished: false,
            channel: NumberedChannel::default(),
            buf: vec![0; CHUNK],
            zbuf: Vec::new(),
            spare: Vec::new(),
            scratch: Vec::new(),
            win: Vec::new(),
            win_pos: 0,
            win_dg: 0,
            resume: false,
        })
    }

    /// Something about the file worth telling the user, once each.
    pub fn take_note(&mut self) -> Option<String> {
        self.notes.pop_front()
    }

    fn note(&mut self, text: String) {
        if self.told.len() < 64 && self.told.insert(text.clone()) {
            self.notes.push_back(text);
        }
    }

    /// The next record, classified; `Ok(None)` at the end. An error is an
    /// I/O error of the input (or of the temporary file): reading stops.
    #[cfg(any(test, feature = "fuzzing"))]
    pub fn next_record(&mut self) -> io::Result<Option<Parsed<'_>>> {
        // Without an interest every frame is a record (never `Plain`).
        Ok(self.decode_next(None, false)?.map(|next| match next {
            Next::Record(parsed) => parsed,
            Next::Counted(_) | Next::Note(_) => Parsed::Skipped,
        }))
    }

    /// The next record, or a run of data frames on ids `interest` does not
    /// want (only counted: their time and data are not decoded); decoding
    /// stops after each wanted frame, so an interest that changes with it
    /// applies from the next record on.
    ///
    /// With `notes`, the notes found so far come first, and those found at
    /// the end before the end ([`FrameSource::next_item`]); without, they
    /// wait for [`Mf4Reader::take_note`]. The record is built in place: a
    /// heartbeat every few records makes this the per-record path, where
    /// one more copy of a frame showed in the bench.
    fn decode_next(
        &mut self,
        interest: Option<&Interest>,
        notes: bool,
    ) -> io::Result<Option<Next<'_>>> {
        if notes && let Some(note) = self.take_note() {
            return Ok(Some(Next::Note(note)));
        }
        loop {
            if let Some(Out::Waiting(_, key, _)) = self.queue.front() {
                let key = *key;
                let passed = self
                    .states
                    .get(key.0)
                    .and_then(|s| s.vlsd.get(key.1))
                    .is_some_and(|(next, _)| *next > key.2);
                let crowded = self.waiting.len() > MAX_WAITING || self.queue.len() > MAX_QUEUE;
                if passed || crowded || self.finished {
                    self.waiting.remove(&key);
                    if let Some(front) = self.queue.front_mut() {
                        *front = Out::Malformed(
                            format!(
                                "no VLSD record at offset {} for the frame's data bytes",
                                key.2
                            )
                            .into(),
                        );
                    }
                } else {
                    self.step(interest)?;
                    continue;
                }
            }
            if let Some(out) = self.queue.pop_front() {
                self.popped += 1;
                return Ok(Some(match out {
                    Out::Frame(d) => Next::Record(Parsed::Frame(self.frame(d))),
                    Out::Skipped => Next::Record(Parsed::Skipped),
                    Out::Malformed(r) => Next::Record(Parsed::Malformed(r)),
                    Out::Plain(n) => Next::Counted(Counted {
                        plain: n,
                        ..Counted::default()
                    }),
                    Out::Waiting(..) => {
                        Next::Record(Parsed::Malformed("frame without its data bytes".into()))
                    }
                }));
            }
            if self.finished {
                if notes && let Some(note) = self.take_note() {
                    return Ok(Some(Next::Note(note)));
                }
                return self.input.stopped.take().map_or(Ok(None), Err);
            }
            self.step(interest)?;
        }
    }

    /// A plain frame's time from its stored value.
    fn plain_time(&self, t: PlainTime) -> Option<Timestamp> {
        let layout = self.layout.as_ref()?;
        let group = layout
            .groups
            .get(t.dg as usize)?
            .groups
            .get(t.gi as usize)?;
        // The channel read from the copied bytes, which start at its first.
        let c = Channel {
            byte: 0,
            ..group.time.clone()?
        };
        time(&c, &t.bytes, t.sample, self.start)
    }

    fn frame(&mut self, d: Decoded) -> Frame<'_> {
        if let Some(t) = d.time {
            self.handed_span = Some(widen(self.handed_span, t, t));
        }
        Frame {
            time: d.time,
            channel: self.channel.name(d.channel),
            id: d.id,
            extended: d.extended,
            kind: d.kind,
            len: d.len,
            data: d.data,
        }
    }

    /// Does one piece of work: decodes a chunk, or reads a block.
    fn step(&mut self, interest: Option<&Interest>) -> io::Result<()> {
        if self.resume {
            self.resume = false;
            return self.records(interest);
        }
        if let Some(active) = self.active.take() {
            return self.decode_chunk(active, interest);
        }
        if let Some(i) = self.replay {
            return self.replay_next(i);
        }
        if self.input.eof {
            return self.at_end();
        }
        self.next_block()
    }

    /// Reads the block at the reader's position (after padding or bytes
    /// that are no block, which are reported).
    fn next_block(&mut self) -> io::Result<()> {
        let at = self.input.offset;
        let mut head = [0u8; HEADER];
        let n = self.input.full(&mut head)?;
        let got = head.get(..n).unwrap_or_default();
        if n < HEADER {
            if got.iter().any(|b| *b != 0) && self.input.stopped.is_none() {
                self.queue.push_back(Out::Malformed(
                    format!("{n} bytes at byte offset {at} at the end are no MDF block").into(),
                ));
            }
            self.input.eof = true;
            return Ok(());
        }
        let header = match Header::read(got).filter(Header::sane) {
            Some(h) => h,
            None => return self.resync(at, head),
        };
        self.meta.read_up_to = at + 1;
        let body = header.len - HEADER as u64;
        match &header.id {
            b"DG" | b"CG" | b"CN" | b"CC" | b"TX" | b"DL" | b"HL"
                if header.len <= MAX_META_BLOCK =>
            {
                let mut bytes = head.to_vec();
                bytes.resize(header.len as usize, 0);
                let k = self
                    .input
                    .full(bytes.get_mut(HEADER..).unwrap_or_default())?;
                if (k as u64) < body {
                    if self.input.stopped.is_some() {
                        return Ok(());
                    }
                    bytes.truncate(HEADER + k);
                    bytes.drain(..HEADER);
                    self.past_the_end(at, &header, k as u64, bytes);
                    return Ok(());
                }
                if self.meta.bytes + bytes.len() > MAX_META {
                    self.note(format!(
                        "MDF metadata over {MAX_META} bytes: blocks past it are not read"
                    ));
                } else {
                    if matches!(&header.id, b"DL" | b"HL") {
                        self.owners_stale = true;
                    }
                    self.meta.bytes += bytes.len();
                    self.meta.blocks.insert(at, bytes);
                }
                self.meta.read_up_to = self.input.offset;
                Ok(())
            }
            b"DT" | b"DZ" | b"SD" | b"DV" => self.data_block(at, header),
            _ => {
                // Its first bytes are kept: should the file end inside it,
                // its length was wrong, and the blocks after its real end
                // are read from them.
                let mut kept = Vec::new();
                let got = self.input.skip_keeping(body, MAX_META_BLOCK, &mut kept)?;
                if got < body && self.input.stopped.is_none() {
                    self.past_the_end(at, &header, got, kept);
                    return Ok(());
                }
                self.meta.read_up_to = self.input.offset;
                Ok(())
            }
        }
    }

    /// A block at `at` whose length runs past the end of the file (a
    /// comment claiming 1 MiB in a file of 1.5 KB, a CG claiming 2^62
    /// bytes): `got` bytes of its body were there, and `kept` holds the
    /// first of them. Reading all of them as the block would swallow the
    /// blocks after its real end in silence, so it is malformed, and reading
    /// goes on at the first block header in what was kept.
    fn past_the_end(&mut self, at: u64, header: &Header, got: u64, kept: Vec<u8>) {
        let body_at = at + HEADER as u64;
        let next = memchr::memmem::find_iter(&kept, b"##").find(|&p| {
            kept.get(p..)
                .and_then(Header::read)
                .is_some_and(|h| h.sane())
        });
        let lost = got.saturating_sub(kept.len() as u64);
        let then = match next {
            Some(p) if lost == 0 => format!(
                "read on from the block at byte offset {}",
                body_at + p as u64
            ),
            Some(p) => format!(
                "read on from the block at byte offset {} (the {lost} bytes after the first {} of it are not read)",
                body_at + p as u64,
                kept.len()
            ),
            None => format!("no block after it ({got} bytes not read)"),
        };
        self.queue.push_back(Out::Malformed(
            format!(
                "{} block at byte offset {at} declares {} bytes, but the file ends {got} bytes \
                 into its body: {then}",
                id(header),
                header.len
            )
            .into(),
        ));
        match next {
            Some(p) => {
                self.input.unread(kept.get(p..).unwrap_or_default());
                self.meta.read_up_to = body_at + p as u64;
            }
            None => self.meta.read_up_to = self.input.offset,
        }
    }

    /// Bytes at `at` are no block header: skip zero padding quietly, any
    /// other bytes with a diagnostic, up to the next sane block header.
    fn resync(&mut self, at: u64, head: [u8; HEADER]) -> io::Result<()> {
        let mut window = head.to_vec();
        let mut skipped = 0u64;
        let mut nonzero = false;
        while let Some(first) = window.first().copied() {
            nonzero |= first != 0;
            window.remove(0);
            skipped += 1;
            let mut b = [0u8; 1];
            if self.input.read(&mut b)? == 0 {
                nonzero |= window.iter().any(|b| *b != 0);
                skipped += window.len() as u64;
                window.clear();
                break;
            }
            window.push(b[0]);
            if Header::read(&window).is_some_and(|h| h.sane()) {
                break;
            }
        }
        if !window.is_empty() {
            self.input.unread(&window);
        }
        if nonzero {
            self.queue.push_back(Out::Malformed(
                format!("{skipped} bytes at byte offset {at} are no MDF block; skipped").into(),
            ));
        }
        Ok(())
    }

    /// The layout, once every block it links to has been read.
    fn layout_ready(&mut self) -> bool {
        let known = (self.meta.blocks.len(), self.meta.done);
        if self.layout.is_none() && self.tried != Some(known) {
            self.tried = Some(known);
            match layout::build(&self.meta, self.dg_first) {
                Ok(l) => {
                    for p in &l.problems {
                        let text = format!("MDF layout: {p}");
                        self.note(text);
                    }
                    self.states = l
                        .groups
                        .iter()
                        .map(|dg| DgState {
                            samples: vec![0; dg.groups.len()],
                            plain: vec![None; dg.groups.len()],
                            vlsd: vec![(0, VecDeque::new()); dg.groups.len()],
                            ..DgState::default()
                        })
                        .collect();
                    self.layout = Some(l);
                    self.owners_stale = true;
                }
                Err(layout::Missing::Ahead) => return false,
            }
        }
        if self.layout.is_none() {
            return false;
        }
        if self.owners_stale
            && let Some(l) = &self.layout
        {
            self.owners = layout::owners(&self.meta, l);
            self.owners_stale = false;
        }
        true
    }

    /// Whether the SD blocks data group `dg` points into are all spooled.
    fn signal_data_ready(&self, dg: usize) -> bool {
        let Some(l) = &self.layout else {
            return false;
        };
        let Some(g) = l.groups.get(dg) else {
            return true;
        };
        for group in &g.groups {
            let Some(data) = group
                .can
                .as_ref()
                .and_then(|(_, f)| f.data_bytes.as_ref())
                .filter(|c| c.vlsd)
            else {
                continue;
            };
            if g.groups.iter().any(|o| o.offset == data.data) {
                continue; // a VLSD channel group: its records come inline
            }
            match layout::data_blocks(&self.meta, data.data) {
                Ok(list) => {
                    let spooled =
                        |b: &u64| self.spool.as_ref().is_some_and(|s| s.sd.contains_key(b));
                    if !list.iter().all(spooled) {
                        return false;
                    }
                }
                Err(_) => return false,
            }
        }
        true
    }

    /// A DT, DZ or SD block at `at`: decoded now, or spooled.
    fn data_block(&mut self, at: u64, header: Header) -> io::Result<()> {
        let body = header.len - HEADER as u64;
        // An unfinalized file's last DT block: its data runs to the end.
        let to_end = header.is(b"DT") && body == 0 && self.unfinished_dt;
        if header.is(b"SD") || (header.is(b"DZ") && self.dz_of(b"SD")?) {
            return self.spool_sd(at, header);
        }
        let direct = !self.spooling && self.layout_ready();
        let owner = self.owners.get(&at).copied();
        if direct
            && let Some(dg) = owner
            && self.signal_data_ready(dg)
        {
            self.start_block(dg);
            if header.is(b"DZ") {
                let read = self.read_body(at, body)?;
                self.meta.read_up_to = self.input.offset;
                if read {
                    self.inflate(dg, at);
                }
            } else {
                self.meta.read_up_to = at + header.len;
                self.active = Some(Active::Input {
                    dg,
                    left: (!to_end).then_some(body),
                });
            }
            return Ok(());
        }
        if direct && owner.is_none() && self.layout.is_some() && !self.could_own() {
            // No data group's data: not records anyone reads.
            self.input.skip(if to_end { u64::MAX } else { body })?;
            self.meta.read_up_to = self.input.offset;
            return Ok(());
        }
        // Not decodable yet: to the spool, with everything after it.
        self.spooling = true;
        let pos = self.spool()?.end;
        let len = self.copy_to_spool(if to_end { None } else { Some(body) })?;
        let kind = header.id;
        if let Some(s) = &mut self.spool {
            s.items.push((at, kind, pos, len));
        }
        self.meta.read_up_to = self.input.offset;
        Ok(())
    }

    /// Whether a data block nobody owns yet may still turn out to be listed
    /// by a DL block not read yet.
    fn could_own(&self) -> bool {
        self.layout.as_ref().is_some_and(|l| {
            l.groups.iter().any(|g| {
                g.data != 0
                    && !self.meta.blocks.contains_key(&g.data)
                    && matches!(self.meta.block(g.data), Err(true))
            })
        })
    }

    /// Whether the DZ block whose header was just read replaces an `orig`
    /// block: peeks at its first bytes and puts them back.
    fn dz_of(&mut self, orig: &[u8; 2]) -> io::Result<bool> {
        let mut two = [0u8; 2];
        let n = self.input.full(&mut two)?;
        self.input.unread(two.get(..n).unwrap_or_default());
        Ok(&two == orig)
    }

    fn spool(&mut self) -> io::Result<&mut Spool> {
        if self.spool.is_none() {
            self.spool = Some(Spool::new(self.spool_limit)?);
        }
        self.spool
            .as_mut()
            .ok_or_else(|| io::Error::other("no spool"))
    }

    /// Copies block data (or all the rest) from the input to the spool.
    fn copy_to_spool(&mut self, len: Option<u64>) -> io::Result<u64> {
        let mut left = len.unwrap_or(u64::MAX);
        let mut buf = std::mem::take(&mut self.buf);
        let mut total = 0;
        while left > 0 {
            let want = left.min(buf.len() as u64) as usize;
            let k = self.input.read(buf.get_mut(..want).unwrap_or_default())?;
            if k == 0 {
                break;
            }
            self.spool()?.append(buf.get(..k).unwrap_or_default())?;
            total += k as u64;
            left -= k as u64;
        }
        self.buf = buf;
        Ok(total)
    }

    /// Reads a DZ block's data into `zbuf` (bounded by its limit).
    fn read_body(&mut self, at: u64, body: u64) -> io::Result<bool> {
        if body > block::MAX_INFLATED {
            self.input.skip(body)?;
            self.queue.push_back(Out::Malformed(
                format!("DZ block at byte offset {at} of {body} bytes is too large to read").into(),
            ));
            return Ok(false);
        }
        let mut bytes = std::mem::take(&mut self.zbuf);
        bytes.clear();
        let n = (&mut self.input).take(body).read_to_end(&mut bytes);
        self.zbuf = bytes;
        let n = n?;
        if (n as u64) < body {
            if self.input.stopped.is_none() {
                self.queue.push_back(Out::Malformed(
                    format!("DZ block at byte offset {at} cut off by the end").into(),
                ));
            }
            return Ok(false);
        }
        Ok(true)
    }

    /// An SD block (or a DZ holding one) goes to the spool, inflated.
    fn spool_sd(&mut self, at: u64, header: Header) -> io::Result<()> {
        let body = header.len - HEADER as u64;
        let data = if header.is(b"DZ") {
            if !self.read_body(at, body)? {
                return Ok(());
            }
            match inflate(&self.zbuf) {
                Ok(d) => Some(d),
                Err(e) => {
                    self.queue.push_back(Out::Malformed(
                        format!("DZ block at byte offset {at}: {e}").into(),
                    ));
                    return Ok(());
                }
            }
        } else {
            None
        };
        let pos = self.spool()?.end;
        let len = match data {
            Some(d) => {
                self.spool()?.append(&d)?;
                d.len() as u64
            }
            None => self.copy_to_spool(Some(body))?,
        };
        self.spool()?.sd.insert(at, (pos, len));
        self.meta.read_up_to = self.input.offset;
        Ok(())
    }

    /// A new data block of `dg` begins: records may go on from the last
    /// block of the group (DL lists), unless that one was lost.
    fn start_block(&mut self, dg: usize) {
        self.switch(dg);
        if let Some(s) = self.states.get_mut(dg)
            && s.lost
        {
            s.lost = false;
            self.win.clear();
            self.win_pos = 0;
        }
    }

    /// Makes `dg` the window's group: what is left of another group's
    /// record waits in that group's carry.
    fn switch(&mut self, dg: usize) {
        if self.win_dg == dg {
            return;
        }
        let left = self.win.get(self.win_pos..).unwrap_or_default().to_vec();
        if let Some(s) = self.states.get_mut(self.win_dg) {
            s.carry = left;
        }
        self.win = self
            .states
            .get_mut(dg)
            .map(|s| std::mem::take(&mut s.carry))
            .unwrap_or_default();
        self.win_pos = 0;
        self.win_dg = dg;
    }

    /// Appends data bytes of group `dg` to the window, after what is left
    /// of a record.
    fn feed(&mut self, dg: usize, bytes: &[u8]) {
        self.switch(dg);
        if self.win_pos > 0 {
            self.win.drain(..self.win_pos.min(self.win.len()));
            self.win_pos = 0;
        }
        self.win.extend_from_slice(bytes);
    }

    /// Inflates the DZ block in `zbuf` for group `dg`.
    fn inflate(&mut self, dg: usize, at: u64) {
        let mut out = std::mem::take(&mut self.spare);
        let mut scratch = std::mem::take(&mut self.scratch);
        let done = block::Dz::read(&self.zbuf).and_then(|dz| {
            let end = 24usize.saturating_add(usize::try_from(dz.len).unwrap_or(usize::MAX));
            let zipped = self
                .zbuf
                .get(24..end.min(self.zbuf.len()))
                .unwrap_or_default();
            dz.inflate_into(zipped, &mut out, &mut scratch)
        });
        self.scratch = scratch;
        match done {
            Ok(()) => self.active = Some(Active::Inflated { dg, data: out }),
            Err(e) => {
                self.spare = out;
                self.queue.push_back(Out::Malformed(
                    format!("DZ block at byte offset {at}: {e}").into(),
                ));
            }
        }
    }

    fn decode_chunk(&mut self, active: Active, interest: Option<&Interest>) -> io::Result<()> {
        let mut buf = std::mem::take(&mut self.buf);
        match active {
            Active::Input { dg, left } => {
                let want = left.map_or(buf.len(), |l| l.min(buf.len() as u64) as usize);
                let n = self.input.read(buf.get_mut(..want).unwrap_or_default())?;
                let left = left.map(|l| l - n as u64);
                self.meta.read_up_to = self.input.offset;
                self.feed(dg, buf.get(..n).unwrap_or_default());
                if n > 0 && left != Some(0) {
                    self.active = Some(Active::Input { dg, left });
                }
            }
            Active::Spooled { dg, pos, left } => {
                let want = left.min(buf.len() as u64) as usize;
                let n = self
                    .spool()?
                    .read_at(pos, buf.get_mut(..want).unwrap_or_default())?;
                let left = left - n as u64;
                self.feed(dg, buf.get(..n).unwrap_or_default());
                if n > 0 && left > 0 {
                    let pos = pos + n as u64;
                    self.active = Some(Active::Spooled { dg, pos, left });
                }
            }
            Active::Inflated { dg, data, .. } => {
                self.switch(dg);
                if self.win_pos >= self.win.len() {
                    // Nothing left of a record: the block becomes the
                    // window, no copy (records stop every RUN of them).
                    let old = std::mem::replace(&mut self.win, data);
                    self.win_pos = 0;
                    self.spare = old;
                } else {
                    self.feed(dg, &data);
                    self.spare = data;
                }
            }
        }
        self.buf = buf;
        self.records(interest)
    }

    /// Splits the window into records and decodes them, up to a record it
    /// holds only part of, or (with an interest) after a wanted frame.
    fn records(&mut self, interest: Option<&Interest>) -> io::Result<()> {
        let dg = self.win_dg;
        if self.states.get(dg).is_none_or(|s| s.lost) {
            self.win.clear();
            self.win_pos = 0;
            return Ok(());
        }
        let win = std::mem::take(&mut self.win);
        let mut pos = self.win_pos;
        let mut result = Ok(());
        let mut n = 0;
        loop {
            if let Some(interest) = interest {
                pos += self.count_plain(dg, win.get(pos..).unwrap_or_default(), interest);
            }
            let Some(rest) = win.get(pos..).filter(|r| !r.is_empty()) else {
                break;
            };
            n += 1;
            if n > RUN {
                // The queue stays short whatever the window's size.
                self.resume = true;
                break;
            }
            match self.record(dg, rest, interest) {
                Err(e) => {
                    result = Err(e);
                    break;
                }
                Ok(Ok(Some((used, wanted)))) => {
                    pos += used;
                    if wanted && interest.is_some() {
                        self.resume = true;
                        break;
                    }
                }
                Ok(Ok(None)) => break,
                Ok(Err(why)) => {
                    self.queue.push_back(Out::Malformed(why.into()));
                    if let Some(s) = self.states.get_mut(dg) {
                        s.lost = true;
                    }
                    pos = win.len();
                    break;
                }
            }
        }
        self.win = win;
        self.win_pos = pos;
        if self.states.get(dg).is_some_and(|s| s.lost) {
            self.win.clear();
            self.win_pos = 0;
        }
        result
    }

    /// The hot loop: counts the data frames at the start of `data` on ids
    /// `interest` does not want, of a group whose fields are stored as they
    /// are, exactly as [`Mf4Reader::decode`] would count them, and stops
    /// at any other record: the bytes counted.
    fn count_plain(&mut self, dg: usize, data: &[u8], interest: &Interest) -> usize {
        let Some(g) = self.layout.as_ref().and_then(|l| l.groups.get(dg)) else {
            return 0;
        };
        // The group whose records lead (sorted: the only one).
        let id_size = usize::from(g.rec_id_size);
        let Some(rid) = block::uint(data, 0, 0, 8 * id_size as u32, false) else {
            return 0;
        };
        let Some(gi) = g.group(rid) else {
            return 0;
        };
        let Some((group, c)) = g
            .groups
            .get(gi)
            .and_then(|gr| Some((gr, gr.counting?)))
            .filter(|(gr, _)| !gr.vlsd && gr.size > 0)
        else {
            return 0;
        };
        let step = id_size + group.size;
        let mut pos = 0;
        let mut n = 0u64;
        while let Some(rest) = data.get(pos..pos + step) {
            if id_size > 0 && block::uint(rest, 0, 0, 8 * id_size as u32, false) != Some(rid) {
                break;
            }
            let record = rest.get(id_size..).unwrap_or_default();
            let (Some(raw_id), Some(len)) = (c.id.get(record), c.data_length.get(record)) else {
                break;
            };
            let id = (raw_id & 0x1FFF_FFFF) as u32;
            let extended = id > 0x7FF
                || match c.ide {
                    Some(f) => f.get(record).is_some_and(|v| v != 0),
                    None => raw_id & 0x8000_0000 != 0,
                };
            let fd = match c.edl {
                Some(f) => f.get(record).is_none_or(|v| v != 0),
                None => false,
            };
            // As `decode` reads them: bytes the record holds, up to the width.
            let stored = record.len().saturating_sub(c.data_at).min(c.data_bytes);
            if fd || len > 8 || len as usize > stored || interest.wants(id, extended) {
                break;
            }
            // Under the channel its frame would name.
            self.counted_ids.count(c.bus.get(record), id, extended);
            n += 1;
            pos += step;
        }
        if n > 0 {
            // Only the run's first and last records are timed: the span is
            // all the report needs of them.
            if let Some(s) = self.states.get_mut(dg).and_then(|s| s.samples.get_mut(gi)) {
                let at = |i: u64| {
                    let offset = usize::try_from(i).ok()?.checked_mul(step)? + id_size;
                    let record = data.get(offset..offset - id_size + step)?;
                    let c = group.time.as_ref()?;
                    Some(PlainTime::of(dg, gi, c, record, *s + i))
                };
                // Only the run's first and last records: the span is all
                // the report needs of them.
                let run = at(0).zip(at(n - 1));
                *s += n;
                if let Some((first, last)) = run {
                    note_plain(&mut self.states, dg, gi, first, last);
                }
            }
            queue_plain(&mut self.queue, n);
        }
        pos
    }

    /// Decodes the record at the start of `rest`: its length and whether
    /// it was a wanted frame, `None` when it needs more bytes, `Err` when
    /// the rest of the block is lost.
    fn record(
        &mut self,
        dg: usize,
        rest: &[u8],
        interest: Option<&Interest>,
    ) -> io::Result<Result<Option<(usize, bool)>, String>> {
        let Some(g) = self.layout.as_ref().and_then(|l| l.groups.get(dg)) else {
            return Ok(Ok(None));
        };
        let id_size = usize::from(g.rec_id_size);
        let Some(record_id) = block::uint(rest, 0, 0, 8 * id_size as u32, false) else {
            return Ok(Ok(None));
        };
        let Some(gi) = g.group(record_id) else {
            return Ok(Err(format!(
                "record id {record_id} is not declared by its data group; \
                 the rest of the data block cannot be read"
            )));
        };
        let Some(group) = g.groups.get(gi) else {
            return Ok(Ok(None));
        };
        let vlsd = group.vlsd;
        let size = if vlsd {
            let Some(len) = block::u32_at(rest, id_size) else {
                return Ok(Ok(None));
            };
            4 + len as usize
        } else {
            group.size
        };
        if size > MAX_RECORD {
            return Ok(Err(format!(
                "record of {size} bytes (id {record_id}) is larger than {MAX_RECORD}; \
                 the rest of the data block cannot be read"
            )));
        }
        let used = id_size + size;
        if used == 0 {
            return Ok(Err(
                "records of 0 bytes: the data block cannot be read".to_string()
            ));
        }
        let Some(record) = rest.get(id_size..used) else {
            return Ok(Ok(None));
        };
        let Some(state) = self.states.get_mut(dg) else {
            return Ok(Ok(None));
        };
        let sample = state.samples.get(gi).copied().unwrap_or(0);
        if let Some(s) = state.samples.get_mut(gi) {
            *s += 1;
        }
        if vlsd {
            let bytes = record.get(4..).unwrap_or_default();
            if let Some((next, window)) = state.vlsd.get_mut(gi) {
                let offset = *next;
                window.push_back((offset, bytes.to_vec()));
                if window.len() > VLSD_WINDOW {
                    window.pop_front();
                }
                *next += record.len() as u64;
                self.resolve((dg, gi, offset), bytes);
            }
            self.queue.push_back(Out::Skipped);
            return Ok(Ok(Some((used, false))));
        }
        let out = self.decode(dg, gi, record, sample, interest)?;
        let wanted = matches!(out, Out::Frame(_) | Out::Waiting(..));
        match out {
            Out::Plain(n) => queue_plain(&mut self.queue, n),
            Out::Waiting(_, key, _) => {
                self.waiting
                    .insert(key, self.popped + self.queue.len() as u64);
                self.queue.push_back(out);
            }
            out => self.queue.push_back(out),
        }
        Ok(Ok(Some((used, wanted))))
    }

    /// The VLSD record `key` came: the frame waiting for it gets its data.
    fn resolve(&mut self, key: Key, bytes: &[u8]) {
        let Some(seq) = self.waiting.remove(&key) else {
            return;
        };
        let Some(slot) = usize::try_from(seq - self.popped.min(seq))
            .ok()
            .and_then(|i| self.queue.get_mut(i))
        else {
            return;
        };
        if let Out::Waiting(d, k, len) = slot
            && *k == key
        {
            let len = *len;
            let frame = std::mem::replace(
                d,
                Decoded {
                    time: None,
                    channel: 0,
                    id: 0,
                    extended: false,
                    kind: FrameKind::Data,
                    len: 0,
                    data: Payload::new(),
                },
            );
            *slot = match take(bytes, len) {
                Ok(data) => Out::Frame(Decoded {
                    len: len as u8,
                    data,
                    ..frame
                }),
                Err(why) => Out::Malformed(why.into()),
            };
        }
    }

    fn decode(
        &mut self,
        dg: usize,
        gi: usize,
        record: &[u8],
        sample: u64,
        interest: Option<&Interest>,
    ) -> io::Result<Out> {
        let Some(group) = self
            .layout
            .as_ref()
            .and_then(|l| l.groups.get(dg))
            .and_then(|g| g.groups.get(gi))
        else {
            return Ok(Out::Skipped);
        };
        let Some((kind, f)) = &group.can else {
            return Ok(Out::Skipped);
        };
        let get = |c: &Option<Channel>| c.as_ref().and_then(|c| c.uint(record, sample));
        let raw_id = get(&f.id).unwrap_or(0);
        let id = (raw_id & 0x1FFF_FFFF) as u32;
        // An id over 11 bits is extended whatever a broken IDE says.
        let extended = id > 0x7FF
            || match get(&f.ide) {
                Some(v) => v != 0,
                None => raw_id & 0x8000_0000 != 0,
            };
        let edl = get(&f.edl).is_some_and(|v| v != 0);
        let dlc = get(&f.dlc);
        let len = match (get(&f.data_length), dlc) {
            (Some(l), _) => l,
            (None, Some(d)) if edl => dlc_len(d),
            (None, Some(d)) => d.min(8),
            (None, None) => 0,
        };
        let mut kind = *kind;
        if kind == FrameKind::Data && (edl || len > 8) {
            kind = FrameKind::Fd;
        }
        // A frame on an id nobody wants is only counted, when that is all
        // it can be: the same checks as below, without time and data (a
        // VLSD frame's data may not have come yet: decoded in full).
        if let Some(interest) = interest
            && matches!(kind, FrameKind::Data | FrameKind::Fd)
            && !interest.wants(id, extended)
            && len <= 64
            && f.data_bytes.as_ref().map_or(len == 0, |c| {
                !c.vlsd && c.bytes(record).len() >= len as usize
            })
        {
            if let Some(c) = group.time.as_ref() {
                let time = PlainTime::of(dg, gi, c, record, sample);
                note_plain(&mut self.states, dg, gi, time, time);
            }
            // Under the channel its frame would name: the one field read
            // for it beyond those that decided it is only counted.
            self.counted_ids
                .count(get(&f.bus).unwrap_or(0), id, extended);
            return Ok(Out::Plain(1));
        }
        let time = group
            .time
            .as_ref()
            .and_then(|c| time(c, record, sample, self.start));
        let channel = get(&f.bus).unwrap_or(0);
        let base = Decoded {
            time,
            channel,
            id,
            extended,
            kind,
            len: 0,
            data: Payload::new(),
        };
        if kind == FrameKind::Error {
            let e = error_frame(get(&f.error_type), get(&f.dir));
            let frame = e.frame(None, &[]);
            return Ok(Out::Frame(Decoded {
                id: frame.id,
                extended: false,
                len: frame.len,
                data: frame.data,
                ..base
            }));
        }
        if kind == FrameKind::Remote {
            // No data, as every reader here gives these frames.
            return Ok(Out::Frame(base));
        }
        if len > 64 {
            return Ok(Out::Malformed(
                format!("CAN frame of {len} data bytes: more than 64").into(),
            ));
        }
        let len = len as usize;
        let (link, offset) = match &f.data_bytes {
            None if len == 0 => return Ok(Out::Frame(base)),
            None => {
                return Ok(Out::Malformed(
                    format!("a frame of {len} data bytes in a group without DataBytes").into(),
                ));
            }
            Some(c) if c.vlsd => {
                let Some(offset) = block::uint(record, c.byte, c.bit, c.bits.min(64), false) else {
                    return Ok(Out::Malformed("record too short for its data bytes".into()));
                };
                (c.data, offset)
            }
            Some(c) => {
                return Ok(match take(c.bytes(record), len) {
                    Ok(data) => Out::Frame(Decoded {
                        len: len as u8,
                        data,
                        ..base
                    }),
                    Err(why) => Out::Malformed(why.into()),
                });
            }
        };
        Ok(match self.signal_data(dg, link, offset, len)? {
            Ok(Some(data)) => Out::Frame(Decoded {
                len: len as u8,
                data,
                ..base
            }),
            Ok(None) => {
                let gi = self.vlsd_group(dg, link).unwrap_or(0);
                Out::Waiting(base, (dg, gi, offset), len)
            }
            Err(why) => Out::Malformed(why.into()),
        })
    }

    /// The first `len` bytes of the VLSD entry at `offset` of the signal
    /// data `link` leads to: a VLSD channel group of the same data group,
    /// or SD blocks in the spool.
    fn signal_data(
        &mut self,
        dg: usize,
        link: u64,
        offset: u64,
        len: usize,
    ) -> io::Result<Result<Option<Payload>, String>> {
        if let Some(gi) = self.vlsd_group(dg, link) {
            let Some((next, window)) = self.states.get(dg).and_then(|s| s.vlsd.get(gi)) else {
                return Ok(Err("no VLSD group".into()));
            };
            if offset >= *next {
                return Ok(Ok(None)); // not read yet: the frame waits
            }
            let found = window.iter().rev().find(|(o, _)| *o == offset);
            return Ok(match found {
                Some((_, bytes)) => take(bytes, len).map(Some),
                None => Err(format!(
                    "no VLSD record at offset {offset} among the last {VLSD_WINDOW} of its group"
                )),
            });
        }
        let list = layout::data_blocks(&self.meta, link).unwrap_or_default();
        let Some(spool) = self.spool.as_mut() else {
            return Ok(Err(format!("no signal data block at byte offset {link}")));
        };
        let mut start = 0u64;
        for sd in list {
            let Some(&(pos, size)) = spool.sd.get(&sd) else {
                return Ok(Err(format!("no signal data block at byte offset {sd}")));
            };
            if offset < start + size {
                let at = pos + (offset - start);
                let mut head = [0u8; 4];
                if spool.read_at(at, &mut head)? < 4 || offset - start + 4 > size {
                    break;
                }
                let n = u32::from_le_bytes(head) as usize;
                if offset - start + 4 + n as u64 > size {
                    return Ok(Err(format!(
                        "signal data entry at offset {offset} runs past its block"
                    )));
                }
                let mut bytes = vec![0u8; n.min(len)];
                spool.read_at(at + 4, &mut bytes)?;
                return Ok(take(&bytes, len).map(Some));
            }
            start += size;
        }
        Ok(Err(format!("signal data offset {offset} is past its data")))
    }

    /// The VLSD channel group of `dg` that `link` points to.
    fn vlsd_group(&self, dg: usize, link: u64) -> Option<usize> {
        self.layout
            .as_ref()
            .and_then(|l| l.groups.get(dg))
            .and_then(|g| g.groups.iter().position(|o| o.offset == link && o.vlsd))
    }

    /// At the end of the input: the spooled blocks, then what is left.
    fn at_end(&mut self) -> io::Result<()> {
        self.meta.done = true;
        self.owners_stale = true;
        self.layout_ready();
        if self.spool.as_ref().is_some_and(|s| !s.items.is_empty()) {
            self.replay = Some(0);
            self.spooling = false;
            self.inflate_ahead();
            return Ok(());
        }
        self.finish();
        Ok(())
    }

    /// Starts inflating the spooled DZ blocks that [`Mf4Reader::replay_next`]
    /// will decode on another thread, in the order it asks for them.
    #[cfg(unix)]
    fn inflate_ahead(&mut self) {
        let Some(spool) = &self.spool else { return };
        let jobs: Vec<ahead::Job> = spool
            .items
            .iter()
            .enumerate()
            .filter(|(_, (at, kind, _, len))| {
                kind == b"DZ" && *len <= block::MAX_INFLATED + 24 && self.owners.contains_key(at)
            })
            .map(|(i, &(_, _, pos, len))| (i, pos, len))
            .collect();
        if jobs.is_empty() {
            return;
        }
        if let Ok(file) = spool.file.try_clone() {
            self.ahead = ahead::Ahead::start(file, jobs);
        }
    }

    #[cfg(not(unix))]
    fn inflate_ahead(&mut self) {}

    /// Spooled DZ block `i` from the thread inflating ahead: `true` when it
    /// came (as data to decode or as a malformed line); `false` when the
    /// reader must inflate it itself (no such thread, or it is out of step).
    #[cfg(unix)]
    fn inflated_ahead(&mut self, i: usize, dg: usize, at: u64) -> bool {
        let Some(ahead) = &self.ahead else {
            return false;
        };
        match ahead.next() {
            Some((j, Ok((stored, columns)))) if j == i => {
                // Buffers go round: the worker's back to it, the window's
                // spare into the window.
                let data = match columns {
                    Some(columns) => {
                        let mut out = std::mem::take(&mut self.spare);
                        block::untranspose_into(&stored, &mut out, columns);
                        ahead.give_back(stored);
                        out
                    }
                    None => {
                        ahead.give_back(std::mem::take(&mut self.spare));
                        stored
                    }
                };
                self.active = Some(Active::Inflated { dg, data });
                true
            }
            Some((j, Err(e))) if j == i => {
                self.queue.push_back(Out::Malformed(
                    format!("DZ block at byte offset {at}: {e}").into(),
                ));
                true
            }
            _ => {
                self.ahead = None;
                false
            }
        }
    }

    #[cfg(not(unix))]
    fn inflated_ahead(&mut self, _i: usize, _dg: usize, _at: u64) -> bool {
        false
    }

    fn replay_next(&mut self, i: usize) -> io::Result<()> {
        let Some(&(at, kind, pos, len)) = self.spool.as_ref().and_then(|s| s.items.get(i)) else {
            self.replay = None;
            if let Some(s) = &mut self.spool {
                s.items.clear();
            }
            self.finish();
            return Ok(());
        };
        self.replay = Some(i + 1);
        let Some(dg) = self.owners.get(&at).copied() else {
            return Ok(());
        };
        self.start_block(dg);
        if &kind == b"DZ" {
            if len > block::MAX_INFLATED + 24 {
                self.queue.push_back(Out::Malformed(
                    format!("DZ block at byte offset {at} of {len} bytes is too large to read")
                        .into(),
                ));
                return Ok(());
            }
            if self.inflated_ahead(i, dg, at) {
                return Ok(());
            }
            let mut zipped = std::mem::take(&mut self.zbuf);
            zipped.clear();
            let spool = self.spool()?;
            spool.file.seek(SeekFrom::Start(pos))?;
            let read = (&mut spool.file).take(len).read_to_end(&mut zipped);
            self.zbuf = zipped;
            read?;
            self.inflate(dg, at);
        } else {
            self.active = Some(Active::Spooled { dg, pos, left: len });
        }
        Ok(())
    }

    /// Records cut off by the end of their data.
    fn finish(&mut self) {
        let left = self.win.len().saturating_sub(self.win_pos);
        if left > 0 && self.states.get(self.win_dg).is_some_and(|s| !s.lost) {
            self.queue.push_back(Out::Malformed(
                format!("record cut off by the end of its data ({left} bytes)").into(),
            ));
        }
        self.win.clear();
        self.win_pos = 0;
        for s in &mut self.states {
            if !s.carry.is_empty() && !s.lost {
                let n = s.carry.len();
                s.carry.clear();
                self.queue.push_back(Out::Malformed(
                    format!("record cut off by the end of its data ({n} bytes)").into(),
                ));
            }
        }
        if self.layout.as_ref().is_none_or(|l| l.groups.is_empty()) {
            self.note("the MDF file has no data group".to_string());
        }
        self.finished = true;
    }
}

fn id(h: &Header) -> String {
    format!("##{}", String::from_utf8_lossy(&h.id))
}

/// Inflates a DZ block's data (its parameters, then the zipped bytes).
fn inflate(body: &[u8]) -> Result<Vec<u8>, String> {
    let dz = block::Dz::read(body)?;
    let end = 24usize.saturating_add(usize::try_from(dz.len).unwrap_or(usize::MAX));
    let zipped = body
        .get(24..end.min(body.len()))
        .ok_or("DZ block too short")?;
    dz.inflate(zipped)
}

fn take(bytes: &[u8], len: usize) -> Result<Payload, String> {
    match bytes.get(..len) {
        Some(b) if len <= 8 => {
            let mut inline = [0u8; 8];
            if let Some(d) = inline.get_mut(..len) {
                d.copy_from_slice(b);
            }
            Ok(Payload::inline(inline, len as u8))
        }
        Some(b) => Payload::from_slice(b).ok_or_else(|| "more than 64 data bytes".to_string()),
        None => Err(format!(
            "DataLength {len} is more than the {} data bytes stored",
            bytes.len()
        )),
    }
}

/// CAN FD's DLC to data length.
fn dlc_len(dlc: u64) -> u64 {
    match dlc {
        0..=8 => dlc,
        9 => 12,
        10 => 16,
        11 => 20,
        12 => 24,
        13 => 32,
        14 => 48,
        _ => 64,
    }
}

/// The record's time: the start plus the master channel, exact when the
/// master counts units of 10^-k s. Inlined into the decoding of every
/// wanted record, where a call cost 5% of an MF4 input's time once the
/// compiler stopped inlining it on its own.
#[inline]
fn time(c: &Channel, record: &[u8], sample: u64, start: (u128, u8)) -> Option<Timestamp> {
    time_of(c, c.raw(record, sample)?, start)
}

/// The time of a master channel's raw value (see [`time`]).
#[inline(always)]
fn time_of(c: &Channel, raw: Raw, start: (u128, u8)) -> Option<Timestamp> {
    // Float seconds without a scale are no count of units (python-can).
    let counts = !matches!((raw, c.scale), (Raw::F(_), Some(0)));
    let (offset, digits): (i128, u8) = match (c.scale, raw.integer()) {
        (Some(k), Some(units)) if counts => {
            let scale = 10i128.pow(18 - u32::from(k));
            (units.checked_mul(scale)?, k)
        }
        _ => {
            let secs = c.conversion.apply(raw.as_f64());
            if !secs.is_finite() || secs.abs() > 1.0e12 {
                return None;
            }
            // Float seconds (python-can, asammdf) to the nanosecond; six
            // digits when that is what they hold (microsecond loggers).
            let ns = (secs * 1e9).round() as i128;
            (ns * 1_000_000_000, if ns % 1000 == 0 { 6 } else { 9 })
        }
    };
    let total = u128::try_from(i128::try_from(start.0).ok()?.checked_add(offset)?).ok()?;
    Timestamp::from_raw(
        u64::try_from(total / ATTO).ok()?,
        (total % ATTO) as u64,
        digits.max(start.1),
    )
}

/// Fuzz target body: any bytes must read to the end without a panic or an
/// endless loop, every frame well-formed, the memory bounded.
#[cfg(feature = "fuzzing")]
pub fn fuzz_mf4(data: &[u8]) {
    use crate::id_counts::testing::{count_frame, table};
    let Ok(mut r) = Mf4Reader::new(data) else {
        return;
    };
    let mut records = 0usize;
    loop {
        let next = r.next_record();
        let Ok(Some(parsed)) = next else {
            break;
        };
        records += 1;
        // A record is at least one byte of input (or one of a DZ block's
        // inflated bytes, at most 1032 of them a byte).
        assert!(
            records <= data.len().saturating_mul(1032).max(64),
            "no progress"
        );
        if let Parsed::Frame(f) = parsed {
            assert!(usize::from(f.len) <= Payload::MAX);
            match f.kind {
                FrameKind::Data => {
                    assert!(f.len <= 8);
                    assert_eq!(f.data.as_slice().len(), usize::from(f.len));
                }
                FrameKind::Fd => assert_eq!(f.data.as_slice().len(), usize::from(f.len)),
                FrameKind::Remote => assert!(f.data.as_slice().is_empty()),
                // An error frame carries the SocketCAN error class in its id and
                // error.h's eight data bytes (or none when the record says no
                // more than that it is one).
                FrameKind::Error => {
                    assert!(!f.extended && f.id < 0x2000_0000);
                    assert!(matches!(f.data.as_slice().len(), 0 | 8));
                }
            }
            assert!(f.id <= if f.extended { 0x1FFF_FFFF } else { 0x7FF });
            assert!(!f.channel.is_empty());
        }
        assert!(r.queue.len() <= MAX_QUEUE + CHUNK + 16);
        assert!(r.waiting.len() <= MAX_WAITING + CHUNK + 16);
        assert!(r.meta.bytes <= MAX_META);
        assert!(
            r.states
                .iter()
                .all(|s| s.carry.len() <= MAX_RECORD + CHUNK + 8)
        );
    }
    while r.take_note().is_some() {}

    // Read again with the EMCY ids as the interest: the frames it does not
    // want are only counted, everything else comes out as without it.
    let mut interest = Interest::none();
    interest.add_standard_range(0x81..=0xFF);
    let summary = |p: &Parsed<'_>| match p {
        Parsed::Frame(f)
            if matches!(f.kind, FrameKind::Data | FrameKind::Fd)
                && !interest.wants(f.id, f.extended) =>
        {
            "plain".to_string()
        }
        other => format!("{other:?}"),
    };
    let (Ok(mut all), Ok(mut some)) = (Mf4Reader::new(data), Mf4Reader::new(data)) else {
        return;
    };
    let mut without = Vec::new();
    // Every frame, by channel and identifier.
    let mut every = IdCounts::new();
    while let Ok(Some(p)) = all.next_record() {
        if let Parsed::Frame(f) = &p {
            count_frame(&mut every, f);
        }
        without.push(summary(&p));
    }
    let mut with = Vec::new();
    let mut handed_on = IdCounts::new();
    while let Ok(Some(next)) = some.decode_next(Some(&interest), false) {
        match next {
            Next::Counted(c) => {
                with.extend((0..c.plain).map(|_| "plain".to_string()));
                assert!(
                    with.len() <= without.len(),
                    "more plain frames than records"
                );
            }
            Next::Record(p) => {
                if let Parsed::Frame(f) = &p {
                    count_frame(&mut handed_on, f);
                }
                with.push(summary(&p));
            }
            Next::Note(_) => {}
        }
    }
    assert_eq!(with, without, "the interest changes what is read");
    handed_on.add(&some.counted_ids.ids);
    assert_eq!(
        table(&handed_on),
        table(&every),
        "the frames handed on and those only counted are every frame, by channel and id"
    );
}

/// A `CAN_ErrorFrame` record in the SocketCAN representation: the one
/// place that says what its members mean. `ErrorType` as ASAM's bus
/// logging defines it: 1 bit, 2 form, 3 stuff, 4 CRC (error.h's CRC
/// sequence location), 5 ACK (no ACK, at the ACK slot); 0 or none is an
/// error frame of unknown class. `Dir` 1 (transmitted) marks the
/// violation as the logger's own transmission.
fn error_frame(error_type: Option<u64>, dir: Option<u64>) -> ErrorFrame {
    let mut e = ErrorFrame::default();
    match error_type {
        Some(1) => e.violation(protocol::BIT),
        Some(2) => e.violation(protocol::FORM),
        Some(3) => e.violation(protocol::STUFF),
        Some(4) => e.at(location::CRC_SEQUENCE),
        Some(5) => {
            e.class |= class::NO_ACK;
            e.at(location::ACK_SLOT)
        }
        _ => return e,
    };
    if dir == Some(1) {
        e.transmitting();
    }
    e
}
