//! Splits a byte stream into blocks of whole lines, and blocks into lines,
//! without allocating per line.
//!
//! A [`Block`] is a buffer of whole lines (~1 MiB from a file, less from a
//! pipe: whatever one read returned, so live input is not delayed). Blocks are
//! the unit of parallel parsing. Lines longer than a cap are not buffered (a
//! 100 MB line without a newline must not take 100 MB): the reader measures
//! them, skips to the next newline and reports them as [`RawLine::TooLong`].
//! Bytes need not be UTF-8.

use std::io::{self, Read};

use super::cancel;

/// Lines longer than this are reported as too long and skipped. Real trace
/// lines are under 500 bytes (a 64-byte CAN FD frame in ASC is ~400).
pub const DEFAULT_MAX_LINE: usize = 64 * 1024;

/// Bytes asked of the input per read; also the usual block size.
pub const DEFAULT_BLOCK: usize = 1024 * 1024;

/// One line of input, terminator (`\n` or `\r\n`) removed.
#[derive(Debug, PartialEq, Eq)]
pub enum RawLine<'a> {
    /// The line's text.
    Text(&'a [u8]),
    /// A line longer than the cap; its full length in bytes (without terminator).
    TooLong(u64),
}

/// Whole lines of input.
#[derive(Debug, Default)]
pub struct Block {
    /// The buffer; the lines are `bytes[start..]` (the bytes before `start`
    /// are room the reader left to align its reads, see [`BlockReader`]).
    pub bytes: Vec<u8>,
    /// Where the lines start in `bytes`.
    pub start: usize,
    /// A too-long line that came right before the text (its length).
    pub too_long_before: Option<u64>,
}

impl Block {
    /// A block of exactly these lines.
    #[cfg(any(test, feature = "fuzzing"))]
    pub fn of(text: &[u8]) -> Block {
        Block {
            bytes: text.to_vec(),
            start: 0,
            too_long_before: None,
        }
    }

    /// Lines, each ending in `\n` except possibly the last line of the input.
    #[inline]
    pub fn text(&self) -> &[u8] {
        self.bytes.get(self.start..).unwrap_or_default()
    }

    /// The lines of this block, in order. The readers jump from line to
    /// line with [`line_at`]; this is what the tests and the fuzzer read
    /// blocks with to check them.
    #[cfg(any(test, feature = "fuzzing"))]
    pub fn lines(&self, max_line: usize) -> BlockLines<'_> {
        BlockLines::new(self.text(), self.too_long_before, max_line)
    }
}

/// One vectorised newline search over the whole block, not one call per line.
#[cfg(any(test, feature = "fuzzing"))]
pub struct BlockLines<'a> {
    bytes: &'a [u8],
    newlines: memchr::Memchr<'a>,
    start: usize,
    too_long: Option<u64>,
    max_line: usize,
}

#[cfg(any(test, feature = "fuzzing"))]
impl<'a> BlockLines<'a> {
    fn new(bytes: &'a [u8], too_long: Option<u64>, max_line: usize) -> Self {
        BlockLines {
            bytes,
            newlines: memchr::memchr_iter(b'\n', bytes),
            start: 0,
            too_long,
            max_line,
        }
    }

    /// Bytes of the block not yet returned as lines.
    #[cfg(test)]
    fn consumed(&self) -> usize {
        self.start
    }
}

#[cfg(any(test, feature = "fuzzing"))]
impl<'a> Iterator for BlockLines<'a> {
    type Item = RawLine<'a>;

    #[inline]
    fn next(&mut self) -> Option<RawLine<'a>> {
        if let Some(n) = self.too_long.take() {
            return Some(RawLine::TooLong(n));
        }
        let begin = self.start;
        let end = match self.newlines.next() {
            Some(pos) => {
                self.start = pos + 1;
                pos
            }
            None if begin < self.bytes.len() => {
                self.start = self.bytes.len();
                self.bytes.len()
            }
            None => return None,
        };
        Some(raw_line(
            self.bytes.get(begin..end).unwrap_or_default(),
            self.max_line,
        ))
    }
}

/// A line without its `\n`: too long, or its text without a final `\r`.
#[inline]
fn raw_line(line: &[u8], max_line: usize) -> RawLine<'_> {
    if line.len() > max_line {
        return RawLine::TooLong(line.len() as u64);
    }
    RawLine::Text(line.strip_suffix(b"\r").unwrap_or(line))
}

/// The line of a block's `bytes` that starts at `begin`, and where the next
/// one starts; `None` past the end. For callers that jump ahead (a
/// parser's run of lines) rather than iterate with `Block::lines`.
#[inline]
pub fn line_at(bytes: &[u8], begin: usize, max_line: usize) -> Option<(RawLine<'_>, usize)> {
    let rest = bytes.get(begin..).filter(|r| !r.is_empty())?;
    let (end, next) = match memchr::memchr(b'\n', rest) {
        Some(i) => (begin + i, begin + i + 1),
        None => (bytes.len(), bytes.len()),
    };
    Some((
        raw_line(bytes.get(begin..end).unwrap_or_default(), max_line),
        next,
    ))
}

/// Cuts a stream into [`Block`]s at line boundaries.
///
/// Reads land at the same offset within a 4 KiB page as the bytes have in
/// the file: the kernel copies page-cache pages into a buffer about four
/// times faster when the two line up (measured on the CI machine: 1 GiB in
/// 0.10 s instead of 0.42 s, a third of the CPU time of the whole decode).
/// The unfinished line kept between reads is moved to make that so.
pub struct BlockReader<R> {
    inner: R,
    /// Bytes read but not yet handed out (the start of an unfinished line)
    /// are `carry[begin..filled]`; the rest is reusable space, never re-zeroed.
    carry: Vec<u8>,
    begin: usize,
    filled: usize,
    block: usize,
    max_line: usize,
    eof: bool,
    /// The input was cut by a cancel, not ended (see `cancel`): an unfinished
    /// line at the end is not a line.
    cut: bool,
    /// Length so far of a too-long line being skipped.
    skipping: Option<u64>,
    /// A too-long line that ended; goes in front of the next block.
    too_long: Option<u64>,
    /// A read error held back until the too-long line before it is out.
    error: Option<io::Error>,
    bytes_read: u64,
    /// Bytes to ask for next: doubles while reads come back full (files),
    /// follows short reads down (pipes hand out 64 KiB), so buffers are not
    /// grown and zeroed far beyond what a read fills.
    read_size: usize,
}

/// First read size, and the floor for the adaptive size.
const MIN_READ: usize = 64 * 1024;

/// The largest block and line length a reader takes: a block then holds
/// fewer lines than a `u32` counts, as a run's timed lines do
/// ([`TimedLine::idx`](crate::TimedLine::idx)).
pub const MAX_BLOCK: usize = 1 << 30;

/// Reads are aligned to the input's offset within a page of this size.
const PAGE: usize = 4096;

impl<R: Read> BlockReader<R> {
    /// Cuts `inner` into blocks of about `block` bytes; lines longer than
    /// `max_line` are only measured. Both are taken as at most
    /// [`MAX_BLOCK`].
    pub fn new(inner: R, block: usize, max_line: usize) -> Self {
        BlockReader {
            inner,
            carry: Vec::new(),
            begin: 0,
            filled: 0,
            block: block.clamp(1, MAX_BLOCK),
            max_line: max_line.clamp(1, MAX_BLOCK),
            eof: false,
            cut: false,
            skipping: None,
            too_long: None,
            error: None,
            bytes_read: 0,
            read_size: MIN_READ,
        }
    }

    #[cfg(test)]
    fn max_line(&self) -> usize {
        self.max_line
    }

    /// Bytes consumed from the underlying reader so far.
    #[cfg(test)]
    fn bytes_read(&self) -> u64 {
        self.bytes_read
    }

    /// The next block, built in `buf` (a recycled buffer; its contents are
    /// discarded). `Ok(None)` at end of input, or where a cancel stopped it
    /// (then without the unfinished line it cut). An I/O error (corrupt gzip)
    /// is returned once; the unfinished line before it is dropped.
    pub fn next_block(&mut self, mut buf: Vec<u8>) -> io::Result<Option<Block>> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        // The first read of a call goes into the caller's buffer: the one it
        // just finished with, so likely in its core's cache (blocks are read
        // by the thread that parses them).
        let mut into_buf = true;
        loop {
            if self.skipping.is_some() {
                self.skip_long_line()?;
                continue;
            }
            let data = self.carry.get(self.begin..self.filled).unwrap_or_default();
            // Whole lines already buffered: hand them out, keep the rest.
            if let Some(last_nl) = memchr::memrchr(b'\n', data) {
                let end = self.begin + last_nl + 1;
                let rest = self.filled - end;
                if buf.len() < rest {
                    buf.resize(rest, 0);
                }
                buf[..rest].copy_from_slice(&self.carry[end..self.filled]);
                std::mem::swap(&mut buf, &mut self.carry);
                buf.truncate(end);
                let start = std::mem::replace(&mut self.begin, 0);
                self.filled = rest;
                return Ok(Some(Block {
                    bytes: buf,
                    start,
                    too_long_before: self.too_long.take(),
                }));
            }
            if self.eof {
                if self.filled == self.begin && self.too_long.is_none() {
                    return Ok(None);
                }
                std::mem::swap(&mut buf, &mut self.carry);
                buf.truncate(self.filled);
                let start = std::mem::replace(&mut self.begin, 0);
                self.filled = 0;
                return Ok(Some(Block {
                    bytes: buf,
                    start,
                    too_long_before: self.too_long.take(),
                }));
            }
            if self.filled - self.begin > self.max_line {
                // A too-long line still waiting to be handed out goes first,
                // or the next one would overwrite it.
                if let Some(n) = self.too_long.take() {
                    buf.clear();
                    return Ok(Some(Block {
                        bytes: buf,
                        start: 0,
                        too_long_before: Some(n),
                    }));
                }
                // No newline within the cap: measure and skip the rest of the line.
                self.skipping = Some((self.filled - self.begin) as u64);
                self.begin = 0;
                self.filled = 0;
                continue;
            }
            let spare = std::mem::take(&mut into_buf).then_some(&mut buf);
            if let Err(e) = self.read_more(spare) {
                // A too-long line that ended before the error is a complete
                // line: hand it out first, as when it came in the same read
                // as the lines before it, so the count never depends on
                // where reads split the input.
                let Some(n) = self.too_long.take() else {
                    return Err(e);
                };
                self.error = Some(e);
                buf.clear();
                return Ok(Some(Block {
                    bytes: buf,
                    start: 0,
                    too_long_before: Some(n),
                }));
            }
        }
    }

    /// One read appended to `carry[begin..filled]` (a pipe returns what it
    /// has, so live lines are not held back waiting for a full block). A
    /// short unfinished line is first moved so the read lands page-aligned
    /// with the input (see [`BlockReader`]); with a `spare` buffer, it moves
    /// there and the spare becomes `carry` (the old one goes back in its place).
    fn read_more(&mut self, spare: Option<&mut Vec<u8>>) -> io::Result<()> {
        let kept = self.filled - self.begin;
        let want = self.read_size.min(self.block).max(self.max_line + 1).max(1);
        if kept <= PAGE {
            let mut old = spare;
            if let Some(spare) = old.as_deref_mut() {
                std::mem::swap(spare, &mut self.carry);
            }
            // Grown first: growing may move the buffer.
            let end = PAGE + kept + want;
            if self.carry.len() < end {
                // Only the part never used before is zeroed.
                self.carry.resize(end, 0);
            }
            let at = self.carry.as_ptr() as usize + kept;
            let begin = (self.bytes_read as usize).wrapping_sub(at) % PAGE;
            let from = self.begin..self.filled;
            match old {
                Some(old) => {
                    self.carry[begin..begin + kept].copy_from_slice(&old[from]);
                }
                None => self.carry.copy_within(from, begin),
            }
            self.begin = begin;
            self.filled = begin + kept;
        }
        let start = self.filled;
        let end = start + want;
        if self.carry.len() < end {
            self.carry.resize(end, 0);
        }
        loop {
            match self.inner.read(&mut self.carry[start..end]) {
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) if cancel::is_cancelled(&e) => {
                    // Stopped, not ended: the bytes after the last newline
                    // are part of a line that was never read to its end.
                    self.filled = self.begin;
                    self.eof = true;
                    self.cut = true;
                    return Ok(());
                }
                Err(e) => return Err(e),
                Ok(n) => {
                    self.filled += n;
                    self.bytes_read += n as u64;
                    self.eof = n == 0;
                    self.read_size = if n == end - start {
                        self.read_size.saturating_mul(2)
                    } else {
                        n.max(MIN_READ)
                    };
                    return Ok(());
                }
            }
        }
    }

    /// Discards bytes up to the next newline, counting them.
    fn skip_long_line(&mut self) -> io::Result<()> {
        let Some(mut len) = self.skipping else {
            return Ok(());
        };
        self.begin = 0;
        self.filled = 0;
        self.read_more(None)?;
        let data = self.carry.get(self.begin..self.filled).unwrap_or_default();
        match memchr::memchr(b'\n', data) {
            Some(pos) => {
                len += pos as u64;
                self.begin += pos + 1;
                self.skipping = None;
                self.too_long = Some(len);
            }
            None if self.eof => {
                self.skipping = None;
                // Cut by a cancel: it never ended, so it is no line at all.
                self.too_long = (!self.cut).then_some(len);
            }
            None => {
                len += data.len() as u64;
                self.begin = 0;
                self.filled = 0;
                self.skipping = Some(len);
            }
        }
        Ok(())
    }
}

/// Line by line over a [`BlockReader`], for the tests below.
#[cfg(test)]
struct LineReader<R> {
    blocks: BlockReader<R>,
    block: Block,
    pos: usize,
    line_no: u64,
}

#[cfg(test)]
impl<R: Read> LineReader<R> {
    fn new(inner: R) -> Self {
        Self::with_max_line(inner, DEFAULT_MAX_LINE)
    }

    fn with_max_line(inner: R, max_line: usize) -> Self {
        LineReader {
            blocks: BlockReader::new(inner, DEFAULT_BLOCK, max_line),
            block: Block::default(),
            pos: 0,
            line_no: 0,
        }
    }

    /// 1-based number of the line last returned.
    fn line_no(&self) -> u64 {
        self.line_no
    }

    /// Bytes consumed from the underlying reader so far.
    fn bytes_read(&self) -> u64 {
        self.blocks.bytes_read()
    }

    /// The next line, `Ok(None)` at end of input.
    fn next_line(&mut self) -> io::Result<Option<RawLine<'_>>> {
        loop {
            if let Some(n) = self.block.too_long_before.take() {
                self.line_no += 1;
                return Ok(Some(RawLine::TooLong(n)));
            }
            if self.pos < self.block.text().len() {
                break;
            }
            let buf = std::mem::take(&mut self.block.bytes);
            match self.blocks.next_block(buf)? {
                Some(block) => {
                    self.block = block;
                    self.pos = 0;
                }
                None => return Ok(None),
            }
        }
        let rest = self.block.text().get(self.pos..).unwrap_or_default();
        let mut lines = BlockLines::new(rest, None, self.blocks.max_line());
        let line = lines.next();
        self.pos += lines.consumed();
        self.line_no += 1;
        Ok(line)
    }
}

/// Why a line too long to read is malformed: the one wording of every
/// reader of lines (the analysis's blocks and `TextReader`).
pub fn too_long(n: u64, max_line: usize) -> crate::Reason {
    format!("line of {n} bytes is longer than the {max_line} byte limit; skipped").into()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn describe(line: RawLine<'_>) -> String {
        match line {
            RawLine::Text(t) => String::from_utf8_lossy(t).into_owned(),
            RawLine::TooLong(n) => format!("<too long {n}>"),
        }
    }

    fn collect(input: &[u8], max: usize) -> Vec<String> {
        let mut r = LineReader::with_max_line(input, max);
        let mut out = Vec::new();
        while let Some(line) = r.next_line().unwrap() {
            out.push(describe(line));
        }
        out
    }

    /// Lines via blocks of a given size, as the parallel reader sees them.
    fn collect_blocks<R: Read>(input: R, block: usize, max: usize) -> Vec<String> {
        let mut r = BlockReader::new(input, block, max);
        let mut out = Vec::new();
        while let Some(b) = r.next_block(Vec::new()).unwrap() {
            out.extend(b.lines(max).map(describe));
        }
        out
    }

    #[test]
    fn splits_lf_crlf_and_last_line_without_newline() {
        assert_eq!(collect(b"a\nb\r\n\nc", 100), ["a", "b", "", "c"]);
        assert_eq!(collect(b"", 100), Vec::<String>::new());
        assert_eq!(collect(b"\n", 100), [""]);
    }

    #[test]
    fn long_lines_are_skipped_and_measured() {
        let mut input = vec![b'x'; 1000];
        input.extend_from_slice(b"\nok\n");
        input.extend(vec![b'y'; 50]);
        assert_eq!(
            collect(&input, 10),
            ["<too long 1000>", "ok", "<too long 50>"]
        );
    }

    #[test]
    fn line_at_exactly_the_cap_is_kept() {
        let mut input = vec![b'z'; 10];
        input.push(b'\n');
        assert_eq!(collect(&input, 10), ["zzzzzzzzzz"]);
    }

    #[test]
    fn counts_lines() {
        let mut r = LineReader::new(&b"a\nb\n"[..]);
        r.next_line().unwrap();
        r.next_line().unwrap();
        assert_eq!(r.line_no(), 2);
        assert!(r.next_line().unwrap().is_none());
        assert_eq!(r.bytes_read(), 4);
    }

    /// A reader that hands out one byte per call exercises every refill path.
    struct Trickle<'a>(&'a [u8]);
    impl Read for Trickle<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            match (self.0.split_first(), buf.first_mut()) {
                (Some((&b, rest)), Some(slot)) => {
                    *slot = b;
                    self.0 = rest;
                    Ok(1)
                }
                _ => Ok(0),
            }
        }
    }

    #[test]
    fn byte_at_a_time_reader_gives_the_same_lines() {
        let input = b"first\r\nsecond\n0123456789abc\nlast";
        let want = ["first", "second", "<too long 13>", "last"];
        let mut r = LineReader::with_max_line(Trickle(input), 12);
        let mut out = Vec::new();
        while let Some(line) = r.next_line().unwrap() {
            out.push(describe(line));
        }
        assert_eq!(out, want);
        assert_eq!(collect_blocks(Trickle(input), 3, 12), want);
    }

    /// Records where each read lands, relative to its offset in the input.
    struct AlignProbe<'a> {
        data: &'a [u8],
        pos: usize,
        misaligned: Vec<(usize, usize)>,
    }

    impl Read for AlignProbe<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            let n = buf.len().min(self.data.len() - self.pos);
            if n > 0 && buf.as_ptr() as usize % PAGE != self.pos % PAGE {
                self.misaligned
                    .push((self.pos, buf.as_ptr() as usize % PAGE));
            }
            buf[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
            self.pos += n;
            Ok(n)
        }
    }

    #[test]
    fn reads_land_at_the_inputs_offset_within_a_page() {
        // Lines of odd lengths, so every block leaves a different tail.
        let mut input = Vec::new();
        let mut i = 0usize;
        while input.len() < 3 << 20 {
            input.extend(b"x".repeat(i % 97));
            input.push(b'\n');
            i += 1;
        }
        for block in [4096, 65536, 1 << 20] {
            let mut probe = AlignProbe {
                data: &input,
                pos: 0,
                misaligned: Vec::new(),
            };
            let mut r = BlockReader::new(&mut probe, block, 512);
            let mut buf = Vec::new();
            let mut total = 0;
            while let Some(b) = r.next_block(buf).unwrap() {
                total += b.text().len();
                buf = b.bytes;
            }
            assert_eq!(total, input.len());
            assert_eq!(probe.misaligned, [], "block {block}");
        }
    }

    #[test]
    fn any_block_size_gives_the_same_lines() {
        let mut input = Vec::new();
        for i in 0..200 {
            input.extend(format!("line {i}\r\n").bytes());
            if i % 37 == 0 {
                input.extend(vec![b'L'; 100 + i]);
                input.push(b'\n');
            }
        }
        input.extend(b"tail");
        let want = collect(&input, 64);
        assert!(want.iter().any(|l| l.starts_with("<too long")));
        for block in [1, 2, 7, 64, 65, 1000, 1 << 20] {
            assert_eq!(collect_blocks(&input[..], block, 64), want, "block {block}");
        }
    }

    /// Reads of 1..=`max` bytes, varying.
    struct Chunks<'a> {
        data: &'a [u8],
        step: usize,
        max: usize,
    }
    impl Read for Chunks<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            self.step = self.step * 7 % 13 + 1;
            let n = (self.step * self.max / 13)
                .max(1)
                .min(buf.len())
                .min(self.data.len());
            buf[..n].copy_from_slice(&self.data[..n]);
            self.data = &self.data[n..];
            Ok(n)
        }
    }

    #[test]
    fn consecutive_long_lines_are_each_reported() {
        // Found by the conservation property test: the second long line's
        // length overwrote the first's before a block carried it out.
        let mut input = vec![b'a'; 1188];
        input.push(b'\n');
        input.extend(vec![b'b'; 2465]);
        for max in [1, 100, 700, 5000] {
            let got = collect_blocks(
                Chunks {
                    data: &input,
                    step: 3,
                    max,
                },
                DEFAULT_BLOCK,
                1024,
            );
            assert_eq!(
                got,
                ["<too long 1188>", "<too long 2465>"],
                "reads up to {max}"
            );
        }
    }

    #[test]
    fn a_long_line_at_the_end_is_still_reported() {
        let input = vec![b'q'; 300];
        assert_eq!(collect_blocks(&input[..], 16, 20), ["<too long 300>"]);
    }

    #[test]
    fn read_errors_surface_after_the_complete_lines() {
        struct Failing(u8);
        impl Read for Failing {
            fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
                self.0 += 1;
                match self.0 {
                    1 => {
                        let data = b"one\ntw";
                        buf[..data.len()].copy_from_slice(data);
                        Ok(data.len())
                    }
                    _ => Err(io::Error::other("corrupt")),
                }
            }
        }
        let mut r = LineReader::new(Failing(0));
        assert_eq!(
            r.next_line().unwrap().map(describe),
            Some("one".to_string())
        );
        assert!(r.next_line().is_err());
    }

    /// Hands out `parts` one per read and cancels `cancel` after the
    /// `cancel_after`th, as Ctrl-C between two reads would.
    struct CancelMidway {
        parts: Vec<&'static [u8]>,
        cancel_after: usize,
        cancel: cancel::Cancel,
    }
    impl Read for CancelMidway {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            if self.parts.is_empty() {
                return Ok(0);
            }
            let part = self.parts.remove(0);
            buf[..part.len()].copy_from_slice(part);
            self.cancel_after = self.cancel_after.saturating_sub(1);
            if self.cancel_after == 0 {
                self.cancel.cancel();
            }
            Ok(part.len())
        }
    }

    fn lines_until_cancel(parts: Vec<&'static [u8]>, cancel_after: usize) -> Vec<String> {
        let token = cancel::Cancel::new();
        let source = CancelMidway {
            parts,
            cancel_after,
            cancel: token.clone(),
        };
        collect_blocks(cancel::StopOnCancel::new(source, token), DEFAULT_BLOCK, 16)
    }

    #[test]
    fn a_line_cut_by_a_cancel_is_not_read() {
        // Ctrl-C between the `t` and the `w` of `two`: only `one` was read
        // to its newline. The end of the input is still the end.
        assert_eq!(lines_until_cancel(vec![b"one\nt", b"wo\n"], 1), ["one"]);
        assert_eq!(
            lines_until_cancel(vec![b"one\nt", b"wo\nlast"], 2),
            ["one", "two"]
        );
        assert_eq!(
            lines_until_cancel(vec![b"one\nt", b"wo\nlast"], 9),
            ["one", "two", "last"]
        );
        // Cut right after a newline: nothing is lost either.
        assert_eq!(lines_until_cancel(vec![b"one\n", b"two\n"], 1), ["one"]);
        // A too-long line cut by a cancel never ended: no line.
        let long: &'static [u8] = b"0123456789abcdefghij";
        assert_eq!(
            lines_until_cancel(vec![b"one\n", long, long, b"\n"], 3),
            ["one"]
        );
    }

    #[test]
    fn a_long_line_ended_before_a_read_error_is_still_reported() {
        // Found by fuzzing (fuzz/regressions/detect/gzip-bad-checksum-after-long-lines):
        // a too-long line whose newline came in the last read before an
        // error was dropped with small reads and counted with large ones.
        struct Failing(u8);
        impl Read for Failing {
            fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
                self.0 += 1;
                let data: &[u8] = match self.0 {
                    1 => b"ok\nxxxxxxxx",
                    2 => b"xxxx\nyy",
                    _ => return Err(io::Error::other("corrupt")),
                };
                buf[..data.len()].copy_from_slice(data);
                Ok(data.len())
            }
        }
        let mut r = LineReader::with_max_line(Failing(0), 4);
        let mut got = Vec::new();
        let err = loop {
            match r.next_line() {
                Ok(Some(line)) => got.push(describe(line)),
                Ok(None) => panic!("the error is reported"),
                Err(e) => break e,
            }
        };
        assert_eq!(got, ["ok", "<too long 12>"]);
        assert_eq!(err.to_string(), "corrupt");
    }
}
