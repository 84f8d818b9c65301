//! Vector BLF (binary logging format), read as a stream.
//!
//! A file is a 144-byte `LOGG` header, then `LOBJ` objects. Most objects sit
//! in log containers (object type 10) whose data, plain or zlib-compressed,
//! is a stream of further objects; an object may start in one container and
//! end in the next. Objects are padded by `size % 4` bytes, but not every
//! writer pads every object type (CANoe writes some unpadded), so the next
//! object is the first `LOBJ` within `PAD_WINDOW` bytes of the last one's
//! end, as python-can finds it; `size % 4` when there is none.
//!
//! What is read: CAN messages (types 1 and 86), CAN error frames (2 and 73),
//! CAN FD messages (100 and 101; one without the EDL flag carries a classic
//! frame and can be an EMCY; one whose valid data bytes run past the data
//! stored, as TSMaster writes them, is read zero-padded, as CANoe and
//! python-can read it, with a warning), with object header version 1 or 2 and
//! timestamps in 10 us or 1 ns units, added to the header's start time
//! (a SYSTEMTIME, taken as UTC: the file does not say; all zero means
//! unknown, and times are then seconds since the measurement start). Every
//! other object type is skipped and counted.
//!
//! Counting: each object is one "line": log containers (skipped), the
//! objects inside them, and each run of bytes that is not an object (a
//! malformed "object"). A diagnostic's line number is the object's index
//! in reading order, from 1. An object with a sane declared size whose
//! content is wrong is reported and skipped by its size; a bad signature or
//! an insane size makes the reader look for the next `LOBJ` signature.
//!
//! Memory is bounded by one log container plus one object (each at most
//! [`MAX_OBJECT`] bytes), whatever the file's size.

use std::io::{self, Read};

use crate::error_frame::ErrorFrame;
use crate::format::vector;
use crate::read::{read_full, read_until_stopped};
use crate::time::{SECS_PER_DAY, days_from_civil};
use crate::{
    Format, Frame, FrameKind, FrameSource, IdCounts, Interest, Next, NumberedChannel, Parsed,
    Payload, Reason, Timestamp,
};

/// The file's magic bytes.
pub const MAGIC: &[u8; 4] = b"LOGG";
const OBJ_MAGIC: &[u8; 4] = b"LOBJ";
/// Largest object (and log container, compressed or not) read: real
/// containers hold 128 KiB; anything over this is taken as corruption.
pub const MAX_OBJECT: usize = 16 * 1024 * 1024;
/// Where the next object may start, from the last one's unpadded end: its
/// `LOBJ` within these bytes (at most 4 bytes on: 3 of padding plus one,
/// python-can's window).
const PAD_WINDOW: usize = 8;
/// Bytes of the file header read: up to the end of the start time.
const HEADER_PREFIX: usize = 72;
const BASE_HEADER: usize = 16;

const LOG_CONTAINER: u32 = 10;
const CAN_MESSAGE: u32 = 1;
const CAN_ERROR: u32 = 2;
const CAN_ERROR_EXT: u32 = 73;
const CAN_MESSAGE2: u32 = 86;
const CAN_FD_MESSAGE: u32 = 100;
const CAN_FD_MESSAGE_64: u32 = 101;

const ATTO: u128 = 1_000_000_000_000_000_000;

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// The 16 bytes every object starts with.
#[derive(Clone, Copy, Debug)]
struct Base {
    header_size: usize,
    header_version: u16,
    size: usize,
    kind: u32,
}

impl Base {
    /// `None` when the signature is not `LOBJ`.
    fn read(b: &[u8]) -> Option<Base> {
        if b.get(..4)? != OBJ_MAGIC {
            return None;
        }
        Some(Base {
            header_size: usize::from(u16_at(b, 4)?),
            header_version: u16_at(b, 6)?,
            size: u32_at(b, 8)? as usize,
            kind: u32_at(b, 12)?,
        })
    }

    /// Sizes a reader can trust enough to skip by.
    fn sane(&self) -> bool {
        self.size >= BASE_HEADER
            && self.size <= MAX_OBJECT
            && self.header_size >= BASE_HEADER
            && self.header_size <= self.size
    }
}

/// A decoded frame object, owning everything but the channel text.
struct Decoded {
    time: Timestamp,
    channel: u16,
    id: u32,
    extended: bool,
    kind: FrameKind,
    len: u8,
    data: Payload,
    /// Something the writer got wrong that the reader made good.
    warning: Option<Reason>,
}

/// What one object is.
enum Object {
    Frame(Decoded),
    Skipped,
    Malformed(Reason),
}

/// Reads a BLF stream object by object.
pub struct BlfReader<R> {
    input: R,
    /// Bytes read from `input` so far (for messages).
    offset: u64,
    /// Bytes put back in front of `input` (after a search for `LOBJ`).
    back: Vec<u8>,
    /// Measurement start, attoseconds since the Unix epoch, and its digits.
    start: (u128, u8),
    note: Option<String>,
    /// The object stream of the log containers read so far.
    buf: Vec<u8>,
    pos: usize,
    /// The last object of the stream ended at `pos` without its padding,
    /// which `size % 4` says is this long: where the next starts is still
    /// to find (see [`PAD_WINDOW`]).
    pad: Option<usize>,
    /// Where a broken container's data ends: objects may not cross it.
    cut: Option<usize>,
    /// Look for the next `LOBJ` instead of expecting one at `pos`.
    resync: bool,
    eof: bool,
    /// A cancel cut the input (`--follow`, a live pipe, then Ctrl-C): the
    /// objects read are reported to the end as at the end of a file, then
    /// this error; an object the stop cut is not reported.
    stopped: Option<io::Error>,
    /// The warning of the last frame returned, until taken.
    warning: Option<Reason>,
    channel: NumberedChannel,
}

impl<R: Read> BlfReader<R> {
    /// Reads the file header. An error means this is not a readable BLF file.
    pub fn new(mut input: R) -> io::Result<BlfReader<R>> {
        let mut head = [0u8; HEADER_PREFIX];
        let got = read_full(&mut input, &mut head)?;
        let invalid = |m: String| io::Error::new(io::ErrorKind::InvalidData, m);
        if head.get(..4) != Some(MAGIC.as_slice()) {
            return Err(invalid(
                "not a BLF file: it does not start with LOGG".into(),
            ));
        }
        if got < HEADER_PREFIX {
            return Err(invalid(format!(
                "BLF file header cut off after {got} bytes"
            )));
        }
        let header_size = u32_at(&head, 4).unwrap_or(0) as usize;
        if !(HEADER_PREFIX..=64 * 1024).contains(&header_size) {
            return Err(invalid(format!(
                "BLF file header size {header_size} is not sane (144 expected)"
            )));
        }
        let rest = (header_size - HEADER_PREFIX) as u64;
        let skipped = io::copy(&mut (&mut input).take(rest), &mut io::sink())?;
        if skipped < rest {
            return Err(invalid("BLF file header cut off".into()));
        }
        let mut note = None;
        let start = match system_time(head.get(40..56).unwrap_or_default()) {
            Ok(Some(t)) => t,
            Ok(None) => (0, 0),
            Err(date) => {
                note = Some(format!(
                    "the BLF start time {date} is not a date; times are since the measurement start"
                ));
                (0, 0)
            }
        };
        Ok(BlfReader {
            input,
            offset: header_size as u64,
            back: Vec::new(),
            start,
            note,
            buf: Vec::new(),
            pos: 0,
            pad: None,
            cut: None,
            resync: false,
            eof: false,
            stopped: None,
            warning: None,
            channel: NumberedChannel::default(),
        })
    }

    /// Something about the header worth telling the user, once.
    pub fn take_note(&mut self) -> Option<String> {
        self.note.take()
    }

    /// The next object, classified; `Ok(None)` at the end. An error is an
    /// I/O error of the input (a corrupt gzip stream): reading stops.
    pub fn next_object(&mut self) -> io::Result<Option<Parsed<'_>>> {
        self.warning = None;
        loop {
            let object = match self.inner() {
                Some(o) => o,
                None if self.eof => match self.leftover() {
                    Some(o) => o,
                    None => return self.stopped.take().map_or(Ok(None), Err),
                },
                None => match self.top()? {
                    Some(o) => o,
                    None => continue,
                },
            };
            return Ok(Some(match object {
                Object::Frame(d) => Parsed::Frame(self.frame(d)),
                Object::Skipped => Parsed::Skipped,
                Object::Malformed(r) => Parsed::Malformed(r),
            }));
        }
    }

    fn frame(&mut self, d: Decoded) -> Frame<'_> {
        self.warning = d.warning;
        Frame {
            time: Some(d.time),
            channel: self.channel.name(u64::from(d.channel)),
            id: d.id,
            extended: d.extended,
            kind: d.kind,
            len: d.len,
            data: d.data,
        }
    }

    /// The next object of the container stream, `None` when it needs more.
    fn inner(&mut self) -> Option<Object> {
        if let Some(c) = self.cut
            && self.pos >= c
        {
            // After a broken container, the next one may start mid-object.
            self.cut = None;
            self.resync = true;
        }
        let limit = self.cut.unwrap_or(self.buf.len());
        let avail = self.buf.get(self.pos..limit).unwrap_or_default();
        if self.resync {
            self.pad = None;
            match memchr::memmem::find(avail, OBJ_MAGIC) {
                Some(k) => {
                    self.pos += k;
                    self.resync = false;
                }
                None => {
                    // Keep a possible partial signature at the end.
                    let keep = if self.cut.is_some() { 0 } else { 3 };
                    self.pos += avail.len().saturating_sub(keep);
                    if let Some(c) = self.cut {
                        self.pos = c;
                    }
                    return None;
                }
            }
        }
        if let Some(pad) = self.pad {
            let window = avail.get(..PAD_WINDOW).unwrap_or(avail);
            match memchr::memmem::find(window, OBJ_MAGIC) {
                Some(k) => self.pos += k,
                // The bytes that decide are in the next container.
                None if window.len() < PAD_WINDOW && self.cut.is_none() && !self.eof => {
                    return None;
                }
                // No object there: padding by the rule, and what follows is
                // reported as bytes between objects.
                None => self.pos += pad.min(avail.len()),
            }
            self.pad = None;
        }
        let avail = self.buf.get(self.pos..limit).unwrap_or_default();
        let complete = match Base::read(avail) {
            _ if avail.len() < BASE_HEADER => None,
            None => {
                self.resync = true;
                self.pos += 1;
                return Some(Object::Malformed(
                    "no LOBJ signature where an object should start; skipped to the next object"
                        .into(),
                ));
            }
            Some(base) if !base.sane() => {
                self.resync = true;
                self.pos += 4;
                return Some(Object::Malformed(
                    format!(
                        "object of type {} declares {} bytes with a {}-byte header: not sane; \
                         skipped to the next object",
                        base.kind, base.size, base.header_size
                    )
                    .into(),
                ));
            }
            Some(base) if avail.len() >= base.size => Some(base),
            Some(_) => None,
        };
        let Some(base) = complete else {
            if self.cut.is_some() && !avail.is_empty() {
                let n = avail.len();
                self.pos = limit;
                return Some(Object::Malformed(
                    format!("object cut off after {n} bytes by a broken log container").into(),
                ));
            }
            return None;
        };
        let body = avail.get(BASE_HEADER..base.size).unwrap_or_default();
        let object = if base.kind == LOG_CONTAINER {
            Object::Malformed("log container inside a log container".into())
        } else {
            decode(base, body, self.start)
        };
        self.pos += base.size;
        self.pad = Some(base.size % 4);
        Some(object)
    }

    /// At the end of the file: bytes of an unfinished object.
    fn leftover(&mut self) -> Option<Object> {
        let rest = self.buf.len().saturating_sub(self.pos);
        self.buf.clear();
        self.pos = 0;
        self.cut = None;
        self.pad = None;
        if rest == 0 || self.resync || self.stopped.is_some() {
            return None;
        }
        Some(Object::Malformed(
            format!("the file ends inside an object ({rest} bytes of it read)").into(),
        ))
    }

    /// Reads the next top-level object: a log container's data goes to the
    /// stream (and the container is returned as skipped), any other object
    /// is decoded. `Ok(None)` at the end of the file.
    fn top(&mut self) -> io::Result<Option<Object>> {
        let at = self.offset;
        let mut head = [0u8; BASE_HEADER];
        let got = self.read(&mut head)?;
        if got == 0 {
            self.eof = true;
            return Ok(None);
        }
        if got < BASE_HEADER {
            self.eof = true;
            if self.stopped.is_some() {
                return Ok(None);
            }
            return Ok(Some(Object::Malformed(
                format!("the file ends inside an object header at byte {at}").into(),
            )));
        }
        let base = match Base::read(&head) {
            Some(b) if b.sane() => b,
            found => {
                let what = match found {
                    Some(b) => format!("an object of type {} with a size of {}", b.kind, b.size),
                    None => "no LOBJ signature".to_string(),
                };
                // In front of what a search put back before: bytes in order.
                self.back
                    .splice(0..0, head.get(1..).unwrap_or_default().iter().copied());
                self.offset -= (BASE_HEADER - 1) as u64;
                let skipped = 1 + self.find_object()?;
                return Ok(Some(Object::Malformed(
                    format!("{what} at byte {at}: {skipped} bytes skipped to the next object")
                        .into(),
                )));
            }
        };
        let mut body = vec![0u8; base.size - BASE_HEADER];
        let got = self.read(&mut body)?;
        if got < body.len() {
            self.eof = true;
            if self.stopped.is_some() {
                return Ok(None);
            }
            return Ok(Some(Object::Malformed(
                format!(
                    "the file ends inside the object at byte {at} ({} of {} bytes read)",
                    got + BASE_HEADER,
                    base.size
                )
                .into(),
            )));
        }
        self.skip_padding(base.size % 4)?;
        if base.kind != LOG_CONTAINER {
            return Ok(Some(decode(base, &body, self.start)));
        }
        Ok(Some(self.container(at, &body)))
    }

    /// Appends a log container's data to the stream.
    fn container(&mut self, at: u64, body: &[u8]) -> Object {
        // Drop what was consumed; keep an unfinished object.
        let consumed = self.pos.min(self.buf.len());
        self.buf.drain(..consumed);
        self.cut = self.cut.map(|c| c.saturating_sub(consumed));
        self.pos = 0;
        let method = u16_at(body, 0);
        // The declared inflated size (bytes 8..12) is not needed: zlib ends itself.
        let data = body.get(BASE_HEADER..).unwrap_or_default();
        let before = self.buf.len();
        let problem = match method {
            Some(0) => {
                self.buf.extend_from_slice(data);
                None
            }
            Some(2) => {
                let mut z = flate2::read::ZlibDecoder::new(data).take(MAX_OBJECT as u64 + 1);
                let result = z.read_to_end(&mut self.buf);
                let n = self.buf.len() - before;
                match result {
                    Err(e) => Some(format!("zlib data is corrupt after {n} bytes ({e})")),
                    Ok(_) if n > MAX_OBJECT => {
                        self.buf.truncate(before + MAX_OBJECT);
                        Some(format!("inflates to more than {MAX_OBJECT} bytes"))
                    }
                    Ok(_) => None,
                }
            }
            Some(m) => Some(format!("unknown compression method {m}")),
            None => Some("container header cut off".to_string()),
        };
        match problem {
            None => Object::Skipped,
            Some(p) => {
                // Objects read from this container so far are good; one that
                // crosses its end, or starts in the next, is not trusted.
                self.cut = Some(self.buf.len());
                Object::Malformed(format!("log container at byte {at}: {p}").into())
            }
        }
    }

    /// After a top-level object: skips to the first `LOBJ` within
    /// [`PAD_WINDOW`] bytes, or `pad` bytes (the padding by the rule) when
    /// there is none; what follows is put back for the next read.
    fn skip_padding(&mut self, pad: usize) -> io::Result<()> {
        let mut look = [0u8; PAD_WINDOW];
        let n = self.read(&mut look)?;
        let got = look.get(..n).unwrap_or_default();
        let next = memchr::memmem::find(got, OBJ_MAGIC).unwrap_or(pad.min(n));
        let rest = got.get(next..).unwrap_or_default();
        self.back.splice(0..0, rest.iter().copied());
        self.offset -= rest.len() as u64;
        Ok(())
    }

    /// Skips to the next `LOBJ` in the file (put back for the next read);
    /// returns the bytes skipped.
    fn find_object(&mut self) -> io::Result<u64> {
        let mut skipped = 0u64;
        let mut window = Vec::with_capacity(64 * 1024 + 3);
        loop {
            let keep = window.len();
            window.resize(keep + 64 * 1024, 0);
            let got = self.read(window.get_mut(keep..).unwrap_or_default())?;
            window.truncate(keep + got);
            if let Some(k) = memchr::memmem::find(&window, OBJ_MAGIC) {
                self.back
                    .splice(0..0, window.get(k..).unwrap_or_default().iter().copied());
                self.offset -= (window.len() - k) as u64;
                return Ok(skipped + k as u64);
            }
            if got == 0 {
                return Ok(skipped + window.len() as u64);
            }
            // Keep the last 3 bytes: a signature may straddle two reads.
            let drop = window.len().saturating_sub(3);
            skipped += drop as u64;
            window.drain(..drop);
        }
    }

    /// Reads until `buf` is full or the input ends; returns the bytes read.
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let mut n = 0;
        if !self.back.is_empty() {
            let k = self.back.len().min(buf.len());
            if let (Some(dst), Some(src)) = (buf.get_mut(..k), self.back.get(..k)) {
                dst.copy_from_slice(src);
            }
            self.back.drain(..k);
            n = k;
        }
        // After a stop, nothing more is read: the bytes held are the end.
        if self.stopped.is_none() {
            let (got, stopped) =
                read_until_stopped(&mut self.input, buf.get_mut(n..).unwrap_or_default())?;
            n += got;
            self.stopped = stopped;
        }
        self.offset += n as u64;
        Ok(n)
    }
}

impl<R: Read> FrameSource for BlfReader<R> {
    fn format(&self) -> Option<Format> {
        Some(Format::Blf)
    }

    /// The header's note first, then object by object: BLF has no index
    /// to skip by, so the interest is not needed.
    fn next_item(&mut self, _interest: Option<&Interest>) -> io::Result<Option<Next<'_>>> {
        if let Some(note) = self.take_note() {
            return Ok(Some(Next::Note(note)));
        }
        Ok(self.next_object()?.map(Next::Record))
    }

    /// What the reader made good in the last frame [`BlfReader::next_object`]
    /// returned (data bytes the object lacks, read as zeros); a diagnostic
    /// for that object, which is still a frame. Cleared by the call and by
    /// the next object.
    fn take_warning(&mut self) -> Option<Reason> {
        self.warning.take()
    }

    /// `None`: every frame is handed on (see [`FrameSource::next_item`]),
    /// so the caller's count of them is every frame already. A reader that
    /// came to count frames on ids nobody wants would count them here.
    fn counted_ids(&self) -> Option<&IdCounts> {
        None
    }
}

/// A `CAN_ERROR_EXT` object's content in the SocketCAN representation:
/// channel (0), length (2), flags (4), ECC (8), position (9), DLC (10),
/// frame length in ns (12), id (16), extended flags (20), read as Vector
/// defines them ([`vector::error_frame`]). A `CAN_ERROR` object has only
/// the channel and length: an error frame of unknown class.
fn error_ext(d: &[u8]) -> ErrorFrame {
    vector::error_frame(
        u32_at(d, 4).unwrap_or(0),
        d.get(8).copied().unwrap_or(0),
        u16_at(d, 20),
    )
}

/// Decodes one object that is not a log container.
fn decode(base: Base, body: &[u8], start: (u128, u8)) -> Object {
    let name = match base.kind {
        CAN_MESSAGE => "CAN message",
        CAN_MESSAGE2 => "CAN message 2",
        CAN_ERROR => "CAN error frame",
        CAN_ERROR_EXT => "CAN error frame ext",
        CAN_FD_MESSAGE => "CAN FD message",
        CAN_FD_MESSAGE_64 => "CAN FD message 64",
        _ => return Object::Skipped,
    };
    match decode_can(base, body, start) {
        Ok(Some(d)) => Object::Frame(d),
        Ok(None) => Object::Skipped,
        Err(why) => Object::Malformed(
            format!(
                "{name} object (type {}) of {} bytes: {why}",
                base.kind, base.size
            )
            .into(),
        ),
    }
}

fn decode_can(base: Base, body: &[u8], start: (u128, u8)) -> Result<Option<Decoded>, String> {
    // Version 1: flags, client index, object version, timestamp (16 bytes);
    // version 2 adds the original timestamp (24). The timestamp is at 8 in both.
    let need = match base.header_version {
        1 => 32,
        2 => 40,
        v => return Err(format!("unknown object header version {v}")),
    };
    if base.header_size < need {
        return Err(format!(
            "a version {} object header needs {need} bytes, not {}",
            base.header_version, base.header_size
        ));
    }
    let flags = u32_at(body, 0).ok_or("header cut off")?;
    let ticks = u128::from(u64_at(body, 8).ok_or("header cut off")?);
    let (atto, digits) = match flags {
        1 => (ticks * 10_000_000_000_000, 6),
        2 => (ticks * 1_000_000_000, 9),
        f => return Err(format!("unknown timestamp unit flags 0x{f:X}")),
    };
    let total = start.0 + atto;
    let time = u64::try_from(total / ATTO)
        .ok()
        .and_then(|s| Timestamp::from_raw(s, (total % ATTO) as u64, digits.max(start.1)))
        .ok_or("timestamp out of range")?;
    let d = body
        .get(base.header_size - BASE_HEADER..)
        .unwrap_or_default();
    let short = |n: usize| -> Result<(), String> {
        if d.len() < n {
            Err(format!("{} bytes of content, {n} needed", d.len()))
        } else {
            Ok(())
        }
    };
    let frame = match base.kind {
        CAN_ERROR | CAN_ERROR_EXT => {
            short(4)?;
            // A field the object is too short to hold reads as not valid.
            let e = if base.kind == CAN_ERROR_EXT {
                error_ext(d)
            } else {
                ErrorFrame::default()
            };
            let f = e.frame(None, &[]);
            Decoded {
                time,
                channel: u16_at(d, 0).unwrap_or(0),
                id: f.id,
                extended: false,
                kind: FrameKind::Error,
                len: f.len,
                data: f.data,
                warning: None,
            }
        }
        CAN_MESSAGE | CAN_MESSAGE2 => {
            short(16)?;
            let flags = d.get(2).copied().unwrap_or(0);
            let dlc = d.get(3).copied().unwrap_or(0);
            let remote = flags & 0x80 != 0;
            let len = classic_len(dlc)?;
            let data = d.get(8..8 + usize::from(len)).unwrap_or_default();
            build(time, u16_at(d, 0), u32_at(d, 4), remote, false, len, data)?
        }
        CAN_FD_MESSAGE => {
            short(20)?;
            let flags = d.get(2).copied().unwrap_or(0);
            let dlc = d.get(3).copied().unwrap_or(0);
            let fd = d.get(13).copied().unwrap_or(0) & 0x01 != 0;
            let valid = d.get(14).copied().unwrap_or(0);
            let len = if fd {
                fd_len(valid)?
            } else {
                classic_len(dlc)?
            };
            short(20 + usize::from(len))?;
            let data = d.get(20..20 + usize::from(len)).unwrap_or_default();
            build(
                time,
                u16_at(d, 0),
                u32_at(d, 4),
                flags & 0x80 != 0,
                fd,
                len,
                data,
            )?
        }
        CAN_FD_MESSAGE_64 => {
            short(40)?;
            let dlc = d.get(1).copied().unwrap_or(0);
            let valid = d.get(2).copied().unwrap_or(0);
            let flags = u32_at(d, 12).unwrap_or(0);
            if flags & 0x80 != 0 {
                // A transmit request, not a frame on the bus.
                return Ok(None);
            }
            let fd = flags & 0x1000 != 0;
            let len = if fd {
                fd_len(valid)?
            } else {
                classic_len(dlc)?
            };
            // The data runs to the extended data (its offset counted from
            // the object's start; 0 = none) or to the object's end.
            let ext = usize::from(d.get(35).copied().unwrap_or(0));
            let end = ext
                .checked_sub(base.header_size)
                .filter(|e| ext != 0 && (40..=d.len()).contains(e))
                .unwrap_or(d.len());
            let stored = d.get(40..end).unwrap_or_default();
            let want = usize::from(len);
            let n = stored.len().min(want);
            let remote = flags & 0x10 != 0 && !fd;
            // Missing bytes of a classic frame would be invented EMCY bytes.
            if n < want && !fd && !remote {
                return Err(format!(
                    "{n} data bytes stored, DLC {dlc} needs {want} (a classic frame is not read \
                     zero-padded: it could be an EMCY)"
                ));
            }
            // TSMaster declares 64 valid bytes and stores fewer. CANoe shows
            // such a frame with the bytes not stored as zeros, and python-can
            // reads it so too: a reader that refused it would lose frames
            // both tools show.
            let mut data = [0u8; Payload::MAX];
            if let (Some(dst), Some(src)) = (data.get_mut(..n), stored.get(..n)) {
                dst.copy_from_slice(src);
            }
            let channel = d.first().map(|c| u16::from(*c));
            let mut frame = build(
                time,
                channel,
                u32_at(d, 4),
                remote,
                fd,
                len,
                data.get(..want).unwrap_or_default(),
            )?;
            if n < want && fd {
                frame.warning = Some(
                    format!(
                        "CAN FD message 64 object (type {}) of {} bytes: {want} valid data bytes \
                         but {n} stored; read with the other {} as zeros, as CANoe does",
                        base.kind,
                        base.size,
                        want - n
                    )
                    .into(),
                );
            }
            frame
        }
        _ => return Ok(None),
    };
    Ok(Some(frame))
}

fn classic_len(dlc: u8) -> Result<u8, String> {
    if dlc > 15 {
        return Err(format!("DLC {dlc} is over 15"));
    }
    Ok(dlc.min(8))
}

fn fd_len(valid: u8) -> Result<u8, String> {
    if valid > 64 {
        return Err(format!("{valid} valid data bytes, at most 64"));
    }
    Ok(valid)
}

fn build(
    time: Timestamp,
    channel: Option<u16>,
    raw_id: Option<u32>,
    remote: bool,
    fd: bool,
    len: u8,
    data: &[u8],
) -> Result<Decoded, String> {
    let raw_id = raw_id.ok_or("content cut off")?;
    let extended = raw_id & 0x8000_0000 != 0;
    let id = raw_id & 0x7FFF_FFFF;
    if extended && id > 0x1FFF_FFFF || !extended && id > 0x7FF {
        return Err(format!("id 0x{raw_id:08X} is not a CAN id"));
    }
    let (kind, len, data) = match (remote, fd) {
        (true, false) => (FrameKind::Remote, 0, &[][..]),
        (_, true) => (FrameKind::Fd, len, data),
        (false, false) => (FrameKind::Data, len, data),
    };
    Ok(Decoded {
        time,
        channel: channel.ok_or("content cut off")?,
        id,
        extended,
        kind,
        len,
        data: Payload::from_slice(data).ok_or("more than 64 data bytes")?,
        warning: None,
    })
}

/// A SYSTEMTIME (year, month, day of week, day, hour, minute, second, ms)
/// to attoseconds since the Unix epoch; `Ok(None)` when all zero, `Err`
/// with the date as written when it is not one.
fn system_time(b: &[u8]) -> Result<Option<(u128, u8)>, String> {
    let f = |i: usize| u16_at(b, i * 2).unwrap_or(0);
    let (y, mo, d, h, mi, s, ms) = (f(0), f(1), f(3), f(4), f(5), f(6), f(7));
    if (y, mo, d, h, mi, s, ms) == (0, 0, 0, 0, 0, 0, 0) {
        return Ok(None);
    }
    let text = format!("{y:04}-{mo:02}-{d:02} {h:02}:{mi:02}:{s:02}.{ms:03}");
    if y < 1970 || h > 23 || mi > 59 || s > 59 || ms > 999 {
        return Err(text);
    }
    // A SYSTEMTIME's year goes to 65535, which the calendar takes whole.
    let days = days_from_civil(u64::from(y), u64::from(mo), u64::from(d)).ok_or(text)?;
    // From 1970 on: not negative.
    let days = days.unsigned_abs();
    let secs = days * SECS_PER_DAY + u64::from(h) * 3600 + u64::from(mi) * 60 + u64::from(s);
    let digits = if ms == 0 { 0 } else { 3 };
    Ok(Some((
        u128::from(secs) * ATTO + u128::from(ms) * 1_000_000_000_000_000,
        digits,
    )))
}

/// Fuzz target body: any bytes must read to the end without a panic or an
/// endless loop, and every frame must be well-formed.
#[cfg(feature = "fuzzing")]
pub fn fuzz_blf(data: &[u8]) {
    let Ok(mut r) = BlfReader::new(data) else {
        return;
    };
    let mut objects = 0usize;
    while let Ok(Some(parsed)) = r.next_object() {
        objects += 1;
        // Every object consumes at least one byte of input or of inflated data.
        assert!(objects <= data.len() + 16 * MAX_OBJECT, "no progress");
        if let Parsed::Frame(f) = parsed {
            assert!(usize::from(f.len) <= Payload::MAX);
            if matches!(f.kind, FrameKind::Data | FrameKind::Fd) {
                assert_eq!(f.data.len(), usize::from(f.len));
            }
            if f.kind == FrameKind::Data {
                assert!(f.len <= 8);
            }
            assert!(f.id <= if f.extended { 0x1FFF_FFFF } else { 0x7FF });
            assert!(f.time.is_some());
            assert!(!f.channel.is_empty());
        }
    }
    assert!(r.buf.len() <= 2 * MAX_OBJECT + 64);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::id_counts::testing::{self, assert_counts_add_up};

    #[test]
    fn error_ext_fields() {
        use crate::error_frame::{LOCATION_BYTE, PROTOCOL_BYTE};
        let object = |flags: u32, ecc: u8, ext: u16| {
            let mut d = vec![0u8; 32];
            d[4..8].copy_from_slice(&flags.to_le_bytes());
            d[8] = ecc;
            d[20..22].copy_from_slice(&ext.to_le_bytes());
            let e = error_ext(&d);
            (e.class, e.data[PROTOCOL_BYTE], e.data[LOCATION_BYTE])
        };
        // SJA1000 ECC: bit error while transmitting, at the ACK slot.
        assert_eq!(object(1, 0x19, 0), (0xA8, 0x81, 0x19));
        // CAN-Core code: CRC error, receiving.
        assert_eq!(object(0xE, 4 | (2 << 6), 0), (0x88, 0, 0x08));
        // Only the extended flags: stuff error, transmitting.
        assert_eq!(object(0, 0, (2 << 6) | (3 << 12)), (0x88, 0x84, 0));
        // Nothing valid, or an object too short for the fields.
        assert_eq!(object(0, 0x19, 0), (0, 0, 0));
        assert_eq!(error_ext(&[1, 0, 0, 0]), ErrorFrame::default());
    }

    /// An object with a version 1 header (1 ns ticks), padded as the rule
    /// says or, with `padded` false, not at all.
    fn object(kind: u32, content: &[u8], padded: bool) -> Vec<u8> {
        let size = 32 + content.len();
        let mut o = b"LOBJ".to_vec();
        o.extend(32u16.to_le_bytes());
        o.extend(1u16.to_le_bytes());
        o.extend((size as u32).to_le_bytes());
        o.extend(kind.to_le_bytes());
        o.extend(2u32.to_le_bytes()); // 1 ns
        o.extend([0u8; 4]);
        o.extend(1_000_000_000u64.to_le_bytes());
        o.extend(content);
        if padded {
            o.extend(vec![0u8; size % 4]);
        }
        o
    }

    /// An EMCY of node 1 as a CAN message (type 1).
    fn emcy(code: u16) -> Vec<u8> {
        let mut c = 1u16.to_le_bytes().to_vec();
        c.extend([0, 8]);
        c.extend(0x81u32.to_le_bytes());
        c.extend(code.to_le_bytes());
        c.extend([1, 0, 0, 0, 0, 0]);
        object(CAN_MESSAGE, &c, true)
    }

    /// A CAN FD message 64 (type 101) declaring `valid` data bytes and
    /// storing `stored`, with extended data at `ext` (0 = none).
    fn fd64(valid: u8, stored: &[u8], ext: u8) -> Vec<u8> {
        fd64_with(0x3000, 15, valid, stored, ext) // EDL, BRS
    }

    fn fd64_with(flags: u32, dlc: u8, valid: u8, stored: &[u8], ext: u8) -> Vec<u8> {
        let mut c = vec![1, dlc, valid, 0];
        c.extend(0x6A9u32.to_le_bytes());
        c.extend([0u8; 4]);
        c.extend(flags.to_le_bytes());
        c.extend([0u8; 19]);
        c.push(ext);
        c.extend([0u8; 4]);
        c.extend(stored);
        object(CAN_FD_MESSAGE_64, &c, true)
    }

    fn container(data: &[u8]) -> Vec<u8> {
        let size = 32 + data.len();
        let mut c = b"LOBJ".to_vec();
        c.extend(16u16.to_le_bytes());
        c.extend(1u16.to_le_bytes());
        c.extend((size as u32).to_le_bytes());
        c.extend(LOG_CONTAINER.to_le_bytes());
        c.extend([0u8; 8]);
        c.extend((data.len() as u32).to_le_bytes());
        c.extend([0u8; 4]);
        c.extend(data);
        c.extend(vec![0u8; size % 4]);
        c
    }

    fn file(top: &[u8]) -> Vec<u8> {
        let mut f = b"LOGG".to_vec();
        f.extend(144u32.to_le_bytes());
        f.resize(144, 0);
        f.extend(top);
        f
    }

    /// Frames (id, data, warning), skipped and malformed objects, in order.
    #[derive(Debug, PartialEq)]
    enum Got {
        Frame(u32, Vec<u8>, Option<String>),
        Skipped,
        Malformed(String),
    }

    /// Reads `bytes` with each of the tests' interests: the frames only
    /// counted (none, while BLF hands every frame on), by channel and
    /// identifier, plus those handed on must be every frame.
    fn counts_add_up(bytes: &[u8], what: &str) {
        for (label, interest) in testing::interests() {
            let (Ok(mut all), Ok(mut some)) = (BlfReader::new(bytes), BlfReader::new(bytes)) else {
                return;
            };
            assert_counts_add_up(&mut all, &mut some, &interest, &format!("{what}, {label}"));
        }
    }

    #[test]
    fn the_fixtures_frames_only_counted_add_up_to_every_frame() {
        for (name, bytes) in testing::fixtures(&["blf"]) {
            counts_add_up(&bytes, &name);
        }
    }

    /// Reads `bytes` object by object; the frames only counted must add up
    /// ([`counts_add_up`]).
    fn read(bytes: &[u8]) -> Vec<Got> {
        counts_add_up(bytes, "a file built here");
        let mut r = BlfReader::new(bytes).expect("a BLF header");
        let mut out = Vec::new();
        loop {
            let got = match r.next_object().expect("no I/O error") {
                None => return out,
                Some(Parsed::Frame(f)) => Got::Frame(f.id, f.data.as_slice().to_vec(), None),
                Some(Parsed::Skipped) => Got::Skipped,
                Some(Parsed::Malformed(m)) => Got::Malformed(m.into_owned()),
            };
            out.push(match got {
                Got::Frame(id, data, _) => {
                    Got::Frame(id, data, r.take_warning().map(|w| w.into_owned()))
                }
                other => other,
            });
            assert!(r.take_warning().is_none(), "taken once");
        }
    }

    #[test]
    fn fd64_data_not_stored_is_read_as_zeros_with_a_warning() {
        let stored: Vec<u8> = (1..=48).collect();
        let mut stream = fd64(64, &stored, 0);
        stream.extend(fd64(12, &[7; 12], 0));
        let got = read(&file(&container(&stream)));
        let mut padded = stored.clone();
        padded.resize(64, 0);
        assert_eq!(got[0], Got::Skipped, "{got:?}");
        assert_eq!(
            got[1],
            Got::Frame(
                0x6A9,
                padded,
                Some(
                    "CAN FD message 64 object (type 101) of 120 bytes: 64 valid data bytes \
                     but 48 stored; read with the other 16 as zeros, as CANoe does"
                        .into()
                )
            )
        );
        // The next object, whole, has no warning.
        assert_eq!(got[2], Got::Frame(0x6A9, vec![7; 12], None));
        assert_eq!(got.len(), 3);
    }

    #[test]
    fn fd64_data_ends_where_the_extended_data_starts() {
        // 16 bytes stored, then 8 of extended data at 32 + 40 + 16 = 88.
        let mut content: Vec<u8> = (1..=16).collect();
        content.extend([0xEE; 8]);
        let got = read(&file(&fd64(24, &content, 88)));
        let mut want: Vec<u8> = (1..=16).collect();
        want.resize(24, 0);
        match &got[..] {
            [Got::Frame(0x6A9, data, Some(w))] => {
                assert_eq!(data, &want);
                assert!(w.contains("24 valid data bytes but 16 stored"), "{w}");
            }
            other => panic!("{other:?}"),
        }
        // An offset inside the fixed fields is not one: the object's end is.
        let got = read(&file(&fd64(24, &content, 40)));
        assert!(
            matches!(&got[..], [Got::Frame(_, data, None)] if *data == content),
            "{got:?}"
        );
    }

    #[test]
    fn a_classic_frame_missing_data_bytes_is_not_padded() {
        // Without EDL the frame is classic and could be an EMCY: zeros in
        // place of its bytes would invent a code or a register.
        let got = read(&file(&fd64_with(0, 8, 8, &[0x10, 0x43], 0)));
        match &got[..] {
            [Got::Malformed(m)] => assert!(
                m.contains("2 data bytes stored, DLC 8 needs 8 (a classic frame is not read"),
                "{m}"
            ),
            other => panic!("{other:?}"),
        }
        // A remote frame carries none: nothing is missing.
        let got = read(&file(&fd64_with(0x10, 4, 0, &[], 0)));
        assert_eq!(got, [Got::Frame(0x6A9, Vec::new(), None)]);
    }

    #[test]
    fn an_object_written_without_padding_does_not_hide_the_next() {
        // Type 118 of 270 bytes, as CANoe writes it: no 2 padding bytes.
        let unpadded = object(118, &[0x55; 238], false);
        assert_eq!(unpadded.len() % 4, 2);
        let mut stream = emcy(0x4310);
        stream.extend(&unpadded);
        stream.extend(emcy(0x0000));
        stream.extend(object(118, &[0x55; 238], true));
        stream.extend(emcy(0x2310));
        let want_frames = 3;
        // In one container, in containers cut anywhere, and at the top level.
        let mut files = vec![file(&container(&stream)), file(&stream)];
        for cut in [1, 3, 17, 49, 300, 318, 319, 320, 321, 322, 323, 330] {
            let top: Vec<u8> = stream.chunks(cut).flat_map(container).collect();
            files.push(file(&top));
        }
        for f in files {
            let got = read(&f);
            let frames = got.iter().filter(|g| matches!(g, Got::Frame(..))).count();
            assert_eq!(frames, want_frames, "{got:?}");
            assert!(
                !got.iter().any(|g| matches!(g, Got::Malformed(_))),
                "{got:?}"
            );
        }
    }

    /// `bytes`, then the error of a cancel (Ctrl-C under `--follow`).
    struct ThenCancelled<'a>(&'a [u8]);

    impl io::Read for ThenCancelled<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            if self.0.is_empty() {
                return Err(crate::cancel::cancelled());
            }
            let n = self.0.read(buf)?;
            Ok(n)
        }
    }

    /// A cancel after the whole file: every object, as at the end of the
    /// file (the last container was lost waiting for the bytes after its
    /// padding), then the cancel's error; an object it cut is not reported.
    #[test]
    fn a_cancel_after_the_last_container_loses_nothing() {
        let mut stream = emcy(0x4310);
        stream.extend(emcy(0x0000));
        let whole = file(&container(&stream));
        let mut r = BlfReader::new(ThenCancelled(&whole)).expect("a BLF header");
        let mut frames = 0;
        let err = loop {
            match r.next_object() {
                Ok(Some(Parsed::Frame(_))) => frames += 1,
                Ok(Some(_)) => {}
                Ok(None) => panic!("the cancel is not the end of the file"),
                Err(e) => break e,
            }
        };
        assert_eq!(frames, 2);
        assert!(crate::cancel::is_cancelled(&err), "{err}");
        // Cut inside the container: no malformed object for the cut.
        let cut = &whole[..whole.len() - 10];
        let mut r = BlfReader::new(ThenCancelled(cut)).expect("a BLF header");
        loop {
            match r.next_object() {
                Ok(Some(Parsed::Malformed(m))) => panic!("{m}"),
                Ok(Some(_)) => {}
                Ok(None) => panic!("the cancel is not the end of the file"),
                Err(e) => break assert!(crate::cancel::is_cancelled(&e), "{e}"),
            }
        }
    }

    #[test]
    fn bytes_past_the_padding_window_are_still_reported() {
        // 5 bytes after an object padded by the rule to 4: the next LOBJ
        // is past the window, so the bytes are reported, not skipped.
        let mut stream = emcy(0x4310);
        stream.extend(b"12345");
        stream.extend(emcy(0x0000));
        for f in [file(&container(&stream)), file(&stream)] {
            let got = read(&f);
            let malformed = got
                .iter()
                .filter(|g| matches!(g, Got::Malformed(_)))
                .count();
            assert_eq!(malformed, 1, "{got:?}");
            let frames = got.iter().filter(|g| matches!(g, Got::Frame(..))).count();
            assert_eq!(frames, 2, "{got:?}");
        }
        // Within the window (up to 4 bytes on), they are padding.
        let mut stream = emcy(0x4310);
        stream.extend(b"1234");
        stream.extend(emcy(0x0000));
        let got = read(&file(&container(&stream)));
        assert_eq!(
            got.iter().filter(|g| matches!(g, Got::Frame(..))).count(),
            2
        );
        assert!(!got.iter().any(|g| matches!(g, Got::Malformed(_))));
    }

    #[test]
    fn a_bad_object_after_a_search_keeps_the_bytes_in_order() {
        // Garbage, then an object of insane size, at the top level: the
        // search after the garbage put the rest back, and the bad header's
        // bytes must go back in front of it, not after it.
        let mut insane = emcy(0x1000);
        insane[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        let mut top = b"xx".to_vec();
        top.extend(insane);
        top.extend(emcy(0x4310));
        top.extend(emcy(0x0000));
        let got = read(&file(&top));
        let frames = got.iter().filter(|g| matches!(g, Got::Frame(..))).count();
        assert_eq!(frames, 2, "{got:?}");
        assert_eq!(
            got.len(),
            4,
            "the garbage, the bad object, two frames: {got:?}"
        );
    }

    #[test]
    fn padding_at_the_end_of_the_file_is_not_an_object() {
        // The last object's padding ends the last container's data, or the
        // file: nothing is left over.
        let last = object(118, &[0x55; 238], true);
        assert_eq!(last.len(), 272);
        for f in [file(&container(&last)), file(&last)] {
            assert_eq!(read(&f).last(), Some(&Got::Skipped));
            assert!(!read(&f).iter().any(|g| matches!(g, Got::Malformed(_))));
        }
    }

    /// [`system_time`] of a SYSTEMTIME's eight fields: year, month, day of
    /// week, day, hour, minute, second, millisecond.
    fn systemtime(fields: [u16; 8]) -> Result<Option<(u128, u8)>, String> {
        let bytes: Vec<u8> = fields.iter().flat_map(|f| f.to_le_bytes()).collect();
        system_time(&bytes)
    }

    /// `secs` and `ms` as [`system_time`] returns them.
    fn at(secs: u128, ms: u128) -> Result<Option<(u128, u8)>, String> {
        Ok(Some((
            secs * ATTO + ms * (ATTO / 1000),
            if ms == 0 { 0 } else { 3 },
        )))
    }

    #[test]
    fn start_times_at_calendar_edges_are_exact() {
        // All zero: no start time.
        assert_eq!(systemtime([0; 8]), Ok(None));
        assert_eq!(systemtime([1970, 1, 4, 1, 0, 0, 0, 0]), at(0, 0));
        assert_eq!(systemtime([1970, 1, 4, 1, 0, 0, 0, 1]), at(0, 1));
        assert_eq!(
            systemtime([1999, 12, 5, 31, 23, 59, 59, 999]),
            at(946_684_799, 999)
        );
        // 2000 is a leap year (divisible by 400).
        assert_eq!(systemtime([2000, 2, 2, 29, 0, 0, 0, 0]), at(951_782_400, 0));
        assert_eq!(
            systemtime([2024, 2, 4, 29, 23, 59, 59, 500]),
            at(1_709_251_199, 500)
        );
        assert_eq!(
            systemtime([2023, 4, 0, 30, 23, 59, 59, 0]),
            at(1_682_899_199, 0)
        );
        assert_eq!(
            systemtime([9999, 12, 5, 31, 23, 59, 59, 999]),
            at(253_402_300_799, 999)
        );
        // Past 9999 (a SYSTEMTIME's year goes to 65535).
        assert_eq!(
            systemtime([10000, 1, 6, 1, 0, 0, 0, 0]),
            at(253_402_300_800, 0)
        );
        assert_eq!(
            systemtime([10400, 2, 0, 29, 0, 0, 0, 0]),
            at(266_030_179_200, 0)
        );
        assert_eq!(
            systemtime([65535, 12, 0, 31, 23, 59, 59, 999]),
            at(2_005_949_145_599, 999)
        );
        // The day of the week is not checked.
        assert_eq!(systemtime([1970, 1, 6, 1, 0, 0, 0, 0]), at(0, 0));
    }

    #[test]
    fn impossible_start_times_are_errors_as_written() {
        for (fields, written) in [
            // 2100 and 10100 are divisible by 100, not by 400: common years.
            ([2100, 2, 1, 29, 0, 0, 0, 0], "2100-02-29 00:00:00.000"),
            ([10100, 2, 0, 29, 0, 0, 0, 0], "10100-02-29 00:00:00.000"),
            ([2023, 2, 3, 29, 0, 0, 0, 0], "2023-02-29 00:00:00.000"),
            // The 31st of the 30-day months.
            ([2023, 4, 0, 31, 0, 0, 0, 0], "2023-04-31 00:00:00.000"),
            ([2023, 6, 0, 31, 0, 0, 0, 0], "2023-06-31 00:00:00.000"),
            ([2023, 9, 0, 31, 0, 0, 0, 0], "2023-09-31 00:00:00.000"),
            ([2023, 11, 0, 31, 0, 0, 0, 0], "2023-11-31 00:00:00.000"),
            // Month 0 and 13, day 0, days past any month.
            ([2023, 0, 0, 10, 0, 0, 0, 0], "2023-00-10 00:00:00.000"),
            ([2023, 13, 0, 10, 0, 0, 0, 0], "2023-13-10 00:00:00.000"),
            ([2023, 1, 0, 0, 0, 0, 0, 0], "2023-01-00 00:00:00.000"),
            ([2023, 1, 0, 32, 0, 0, 0, 0], "2023-01-32 00:00:00.000"),
            ([2023, 1, 0, 300, 0, 0, 0, 0], "2023-01-300 00:00:00.000"),
            // Before 1970.
            (
                [1969, 12, 3, 31, 23, 59, 59, 999],
                "1969-12-31 23:59:59.999",
            ),
            ([0, 0, 0, 0, 0, 0, 0, 1], "0000-00-00 00:00:00.001"),
            // One past the last hour, minute, second, millisecond.
            ([2023, 1, 0, 1, 24, 0, 0, 0], "2023-01-01 24:00:00.000"),
            ([2023, 1, 0, 1, 23, 60, 0, 0], "2023-01-01 23:60:00.000"),
            ([2023, 1, 0, 1, 23, 59, 60, 0], "2023-01-01 23:59:60.000"),
            (
                [2023, 1, 0, 1, 23, 59, 59, 1000],
                "2023-01-01 23:59:59.1000",
            ),
            ([2023, 1, 0, 1, 256, 0, 0, 0], "2023-01-01 256:00:00.000"),
        ] {
            assert_eq!(systemtime(fields), Err(written.to_string()), "{fields:?}");
        }
    }
}
