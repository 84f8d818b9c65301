//! Splits a byte stream into lines without allocating per line.
//!
//! One large buffer, `memchr` for the newline, slices handed out borrowed.
//! Lines longer than a cap are not buffered (a 100 MB line without a newline
//! must not take 100 MB): the reader reports their length and skips to the
//! next newline. Bytes need not be UTF-8.

use std::io::{self, Read};

/// Lines longer than this are reported as too long and skipped. Real trace
/// lines are under 500 bytes (a 64-byte CAN FD frame in ASC is ~400).
pub const DEFAULT_MAX_LINE: usize = 64 * 1024;

const READ_CHUNK: usize = 256 * 1024;

/// One line of input, terminator (`\n` or `\r\n`) removed.
#[derive(Debug, PartialEq, Eq)]
pub enum RawLine<'a> {
    Text(&'a [u8]),
    /// A line longer than the cap; its full length in bytes (without terminator).
    TooLong(u64),
}

pub struct LineReader<R> {
    inner: R,
    buf: Vec<u8>,
    start: usize,
    end: usize,
    eof: bool,
    max_line: usize,
    line_no: u64,
    bytes_read: u64,
}

impl<R: Read> LineReader<R> {
    pub fn new(inner: R) -> Self {
        Self::with_max_line(inner, DEFAULT_MAX_LINE)
    }

    pub fn with_max_line(inner: R, max_line: usize) -> Self {
        let max_line = max_line.max(1);
        LineReader {
            inner,
            buf: vec![0; max_line + READ_CHUNK],
            start: 0,
            end: 0,
            eof: false,
            max_line,
            line_no: 0,
            bytes_read: 0,
        }
    }

    /// 1-based number of the line last returned.
    pub fn line_no(&self) -> u64 {
        self.line_no
    }

    /// Bytes consumed from the underlying reader so far.
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read
    }

    /// The next line, `Ok(None)` at end of input. An I/O error (a corrupt
    /// gzip member, a vanished file) is returned once; lines before it were
    /// all delivered.
    pub fn next_line(&mut self) -> io::Result<Option<RawLine<'_>>> {
        loop {
            if let Some(pos) = memchr::memchr(b'\n', &self.buf[self.start..self.end]) {
                let begin = self.start;
                let stop = begin + pos;
                self.start = stop + 1;
                self.line_no += 1;
                if pos > self.max_line {
                    return Ok(Some(RawLine::TooLong(pos as u64)));
                }
                return Ok(Some(RawLine::Text(strip_cr(&self.buf[begin..stop]))));
            }
            let pending = self.end - self.start;
            if self.eof {
                if pending == 0 {
                    return Ok(None);
                }
                let begin = self.start;
                self.start = self.end;
                self.line_no += 1;
                return Ok(Some(RawLine::Text(strip_cr(&self.buf[begin..self.end]))));
            }
            if pending > self.max_line {
                let len = self.skip_long_line()?;
                self.line_no += 1;
                return Ok(Some(RawLine::TooLong(len)));
            }
            self.fill()?;
        }
    }

    /// Moves the partial line to the front and reads more after it.
    fn fill(&mut self) -> io::Result<()> {
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        loop {
            match self.inner.read(&mut self.buf[self.end..]) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(());
                }
                Ok(n) => {
                    self.end += n;
                    self.bytes_read += n as u64;
                    return Ok(());
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            }
        }
    }

    /// Discards the current over-long line up to and including its newline;
    /// returns its length. Memory stays at one buffer however long it is.
    fn skip_long_line(&mut self) -> io::Result<u64> {
        let mut len = (self.end - self.start) as u64;
        self.start = 0;
        self.end = 0;
        loop {
            self.fill()?;
            if let Some(pos) = memchr::memchr(b'\n', &self.buf[..self.end]) {
                len += pos as u64;
                self.start = pos + 1;
                return Ok(len);
            }
            len += self.end as u64;
            self.end = 0;
            if self.eof {
                return Ok(len);
            }
        }
    }
}

fn strip_cr(line: &[u8]) -> &[u8] {
    line.strip_suffix(b"\r").unwrap_or(line)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collect(input: &[u8], max: usize) -> Vec<String> {
        let mut r = LineReader::with_max_line(input, max);
        let mut out = Vec::new();
        while let Some(line) = r.next_line().unwrap() {
            out.push(match line {
                RawLine::Text(t) => String::from_utf8_lossy(t).into_owned(),
                RawLine::TooLong(n) => format!("<too long {n}>"),
            });
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
        let mut r = LineReader::with_max_line(Trickle(input), 12);
        let mut out = Vec::new();
        while let Some(line) = r.next_line().unwrap() {
            out.push(format!("{line:?}"));
        }
        assert_eq!(out.len(), 4);
        assert_eq!(out[2], "TooLong(13)");
    }
}
