//! What a candump trace's times mean: `-ta` absolute, `-tz` since the first
//! frame, or `-td` the delta to the previous frame.
//!
//! candump writes all three in the same `(sss.uuuuuu)` shape, in log lines
//! (`-L`) and on the screen. Absolute and zero-based times are read as
//! written; deltas must be summed, frame by frame, or every duration is
//! wrong and the clock "goes backwards" all the time. The user can say which
//! (`--timestamps`); otherwise the first block of the input decides
//! ([`sniff`]): deltas only where the times prove it.
//!
//! Summing makes every line depend on the one before, so a trace read as
//! deltas is parsed on one thread, and every frame's time is read (not only
//! the wanted ones'): slower, and only for such traces.

use std::io::{self, Read};

use super::Timestamp;

/// What `--timestamps` says a trace's times are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TimeMode {
    /// Read as written (`candump -ta`, every other format's own times).
    Absolute,
    /// Each time is the delta to the previous frame (`candump -td`): summed.
    Delta,
    /// Seconds since the first frame (`candump -tz`): read as written.
    Zero,
}

impl TimeMode {
    /// The name on the command line and in the JSON `timestamps` key.
    pub fn name(self) -> &'static str {
        match self {
            TimeMode::Absolute => "absolute",
            TimeMode::Delta => "delta",
            TimeMode::Zero => "zero",
        }
    }
}

/// Lines at the start of the input looked at: enough to see deltas jitter.
/// The sample is the same however the input arrives (a block or a byte at
/// a time), so the decision is too.
pub const SAMPLE_LINES: usize = 16;
/// Bytes at the start of the input the sample lines must lie in: what
/// [`read_ahead`] reads at most.
pub const SAMPLE_BYTES: usize = 64 * 1024;
/// Times needed before the sample can prove anything.
const MIN_TIMES: usize = 8;
/// A time at or above this is a date (Unix time), never a delta: candump
/// prints deltas with 3 integer digits, and a gap of over a day between two
/// frames is not what a `-td` trace is made of.
pub const DELTA_BELOW_SECS: u64 = 100_000;

/// Why a sample was read as deltas: how many of its consecutive times
/// decreased, out of how many pairs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Evidence {
    /// Consecutive times that decreased.
    pub decreases: usize,
    /// Consecutive times compared.
    pub pairs: usize,
}

impl Evidence {
    /// The note that tells the user what was decided and how to override it.
    pub fn note(self) -> String {
        format!(
            "times read as candump -td deltas and summed: {} of the first {} time steps go \
             backwards, which only deltas do (--timestamps absolute reads them as written)",
            self.decreases, self.pairs
        )
    }
}

/// Decides from the first [`SAMPLE_LINES`] lines of a text trace (within
/// its first [`SAMPLE_BYTES`]) whether its candump times are deltas: `Some`
/// when at least `MIN_TIMES` lines start with a candump time, all below
/// [`DELTA_BELOW_SECS`], and at least two and at least a tenth of their
/// consecutive pairs decrease. Absolute and zero-based times never
/// decrease (a capture of several interfaces may, rarely); deltas of a real
/// bus jitter, so about half their steps do. A trace of perfectly equal
/// deltas is not recognised: `--timestamps delta` says it.
pub fn sniff(text: &[u8]) -> Option<Evidence> {
    let mut previous: Option<Timestamp> = None;
    let mut times = 0usize;
    let mut decreases = 0usize;
    let text = text.get(..SAMPLE_BYTES).unwrap_or(text);
    for line in text.split(|b| *b == b'\n').take(SAMPLE_LINES) {
        let Some(t) = leading_time(line) else {
            continue;
        };
        if t.secs() >= DELTA_BELOW_SECS {
            return None;
        }
        times += 1;
        if previous.is_some_and(|p| t < p) {
            decreases += 1;
        }
        previous = Some(t);
    }
    let pairs = times.saturating_sub(1);
    (times >= MIN_TIMES && decreases >= 2 && decreases * 10 >= pairs)
        .then_some(Evidence { decreases, pairs })
}

/// An input with its first lines read ahead for [`sniff`] and put back in
/// front; a read error met while reading ahead comes after them.
pub struct ReadAhead<R> {
    head: io::Cursor<Vec<u8>>,
    error: Option<io::Error>,
    rest: R,
}

impl<R: Read> Read for ReadAhead<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.head.read(buf)?;
        if n > 0 || buf.is_empty() {
            return Ok(n);
        }
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.rest.read(buf)
    }
}

/// Reads the sample of [`sniff`] from the start of `input` (its first
/// [`SAMPLE_LINES`] lines, or [`SAMPLE_BYTES`], or to the end, however
/// the reads come) and decides: the input as it was, and the evidence when
/// its times are deltas. For inputs that are read to their end: a live
/// stream would wait here for 16 lines before its first event.
pub fn read_ahead<R: Read>(mut input: R) -> (ReadAhead<R>, Option<Evidence>) {
    let mut head = Vec::new();
    let mut error = None;
    let mut chunk = [0u8; 4096];
    let mut lines = 0;
    while lines < SAMPLE_LINES && head.len() < SAMPLE_BYTES {
        match input.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => {
                let got = chunk.get(..n).unwrap_or_default();
                lines += memchr::memchr_iter(b'\n', got).count();
                head.extend_from_slice(got);
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => {
                error = Some(e);
                break;
            }
        }
    }
    let evidence = sniff(&head);
    let ahead = ReadAhead {
        head: io::Cursor::new(head),
        error,
        rest: input,
    };
    (ahead, evidence)
}

/// The `(sec.frac)` a candump log or screen line starts with (after blanks
/// and colour codes), if any.
pub fn leading_time(line: &[u8]) -> Option<Timestamp> {
    let mut rest = line;
    loop {
        match rest.first()? {
            b' ' | b'\t' => rest = rest.get(1..)?,
            // `-c`: an ANSI colour sequence, ESC [ ... m.
            0x1B => {
                let end = rest.iter().position(|b| *b == b'm')?;
                rest = rest.get(end + 1..)?;
            }
            b'(' => break,
            _ => return None,
        }
    }
    let close = memchr::memchr(b')', rest)?;
    let inside = rest.get(1..close)?;
    let dot = memchr::memchr(b'.', inside)?;
    let (int, frac) = (inside.get(..dot)?, inside.get(dot + 1..)?);
    if frac.is_empty() || !int.iter().chain(frac).all(u8::is_ascii_digit) {
        return None;
    }
    Timestamp::from_decimal(int, frac).ok()
}

/// The running sum of a `-td` trace's deltas; the first frame is at its
/// own delta (candump prints 0 for it), so times are seconds since the
/// frame before the first one read.
#[derive(Clone, Copy, Debug, Default)]
pub struct DeltaClock {
    sum: Option<Timestamp>,
}

impl DeltaClock {
    /// The time of the last frame summed (`None` before the first).
    pub fn sum(&self) -> Option<Timestamp> {
        self.sum
    }

    /// The time of a frame whose delta is `delta`. A sum past u64 seconds
    /// (only a hostile input gets there) stays where it was.
    pub fn next(&mut self, delta: Timestamp) -> Timestamp {
        let t = match self.sum {
            Some(sum) => sum.checked_add(delta).unwrap_or(sum),
            None => delta,
        };
        self.sum = Some(t);
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ts(s: &str) -> Timestamp {
        Timestamp::parse(s.as_bytes()).unwrap()
    }

    fn screen(times: &[&str]) -> String {
        times
            .iter()
            .map(|t| format!(" ({t})  can0  701   [1]  05\n"))
            .collect()
    }

    fn log(times: &[&str]) -> String {
        times
            .iter()
            .map(|t| format!("({t}) can0 701#05\n"))
            .collect()
    }

    const JITTER: [&str; 10] = [
        "000.000000",
        "000.010012",
        "000.009987",
        "000.010003",
        "000.009999",
        "000.010020",
        "000.009980",
        "000.010001",
        "000.010000",
        "000.009995",
    ];

    #[test]
    fn jittering_small_times_are_deltas_in_either_layout() {
        let e = sniff(screen(&JITTER).as_bytes()).expect("deltas");
        assert_eq!(
            e,
            Evidence {
                decreases: 5,
                pairs: 9
            }
        );
        assert_eq!(sniff(log(&JITTER).as_bytes()), Some(e));
        assert!(e.note().contains("5 of the first 9"));
    }

    #[test]
    fn zero_based_and_absolute_times_are_not() {
        let zero = [
            "000.000000",
            "000.010012",
            "000.020000",
            "000.030003",
            "000.040000",
            "000.050020",
            "000.060000",
            "000.070001",
            "000.080000",
        ];
        assert_eq!(sniff(screen(&zero).as_bytes()), None);
        // Dates never are, even when they go backwards.
        let absolute: Vec<String> = JITTER
            .iter()
            .map(|t| format!("1700000{}", t.trim_start_matches('0')))
            .collect();
        let absolute: Vec<&str> = absolute.iter().map(String::as_str).collect();
        assert_eq!(sniff(log(&absolute).as_bytes()), None);
    }

    #[test]
    fn rare_small_steps_back_of_several_interfaces_are_not() {
        // One step back in 19: below a tenth.
        let mut times: Vec<String> = (0..20).map(|i| format!("000.{:06}", i * 1000)).collect();
        times.swap(10, 11);
        let times: Vec<&str> = times.iter().map(String::as_str).collect();
        assert_eq!(sniff(log(&times).as_bytes()), None);
    }

    #[test]
    fn too_few_times_prove_nothing() {
        assert_eq!(sniff(screen(&JITTER[..7]).as_bytes()), None);
        assert_eq!(sniff(b""), None);
        // Lines without candump times (ASC, TRC, screen without -t) count for nothing.
        let asc = "   0.010000 1  701  Rx   d 1 05\n   0.009000 1  701  Rx   d 1 05\n";
        assert_eq!(sniff(asc.repeat(10).as_bytes()), None);
    }

    #[test]
    fn leading_time_accepts_blanks_and_colour_and_nothing_else() {
        assert_eq!(leading_time(b"(1.5) can0 081#00"), Some(ts("1.5")));
        assert_eq!(leading_time(b" \t(001.000250)  can0"), Some(ts("1.000250")));
        assert_eq!(
            leading_time(b"\x1b[1;31m (000.000001)  can0"),
            Some(ts("0.000001"))
        );
        for bad in [
            &b"(1.) can0"[..],
            b"(.5) can0",
            b"(1,5) can0",
            b"(15) can0",
            b"(2018-12-06 09:31:30.572475)",
            b"x (1.5)",
            b"(1.5",
            b"\x1b[1;31",
        ] {
            assert_eq!(leading_time(bad), None, "{}", String::from_utf8_lossy(bad));
        }
    }

    /// A reader that hands out `n` bytes per read, then fails.
    struct Trickle<'a>(&'a [u8], usize);

    impl Read for Trickle<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            if self.0.is_empty() {
                return Err(io::Error::other("gone"));
            }
            let n = self.1.min(buf.len()).min(self.0.len());
            let (head, rest) = self.0.split_at(n);
            buf[..n].copy_from_slice(head);
            self.0 = rest;
            Ok(n)
        }
    }

    #[test]
    fn read_ahead_decides_the_same_however_the_bytes_come_and_gives_them_all_back() {
        let mut text = screen(&JITTER);
        text.push_str(&screen(&["000.010000"; 30]));
        let (_, whole) = read_ahead(text.as_bytes());
        assert!(whole.is_some());
        for step in [1, 3, 40, 4096] {
            let (mut ahead, evidence) = read_ahead(Trickle(text.as_bytes(), step));
            assert_eq!(evidence, whole, "{step} bytes a read");
            // Only the sample is read ahead.
            let sample: usize = text
                .split_inclusive('\n')
                .take(SAMPLE_LINES)
                .map(str::len)
                .sum();
            assert!(ahead.head.get_ref().len() >= sample.min(text.len()));
            assert!(ahead.head.get_ref().len() < sample + step);
            let mut back = Vec::new();
            let err = ahead
                .read_to_end(&mut back)
                .expect_err("the error comes after the bytes");
            assert_eq!(err.to_string(), "gone");
            assert_eq!(back, text.as_bytes());
        }
        // An error on the first read comes back after nothing.
        let (mut ahead, evidence) = read_ahead(Trickle(b"", 1));
        assert_eq!(evidence, None);
        assert!(ahead.read(&mut [0u8; 4]).is_err());
        // Only the first 16 lines count: jitter after them proves nothing.
        let mut late = screen(&["000.010000"; 16]);
        late.push_str(&screen(&JITTER));
        assert_eq!(read_ahead(late.as_bytes()).1, None);
    }

    #[test]
    fn the_clock_sums_exactly_and_keeps_the_finer_precision() {
        let mut c = DeltaClock::default();
        assert_eq!(c.next(ts("0.000000")), ts("0.000000"));
        assert_eq!(c.next(ts("0.250000")), ts("0.250000"));
        assert_eq!(c.next(ts("0.750000")), ts("1.000000"));
        assert_eq!(c.next(ts("0.000000001")).to_string(), "1.000000001");
        let mut c = DeltaClock::default();
        assert_eq!(
            c.next(ts("5.5")),
            ts("5.5"),
            "a cut trace starts at its delta"
        );
        let mut c = DeltaClock::default();
        let max = Timestamp::from_parts(u64::MAX, 0, 0);
        assert_eq!(c.next(max), max);
        assert_eq!(c.next(ts("1.0")), max, "overflow stays put, no panic");
    }
}
