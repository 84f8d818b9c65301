//! Format detection from content, never from the file name.
//!
//! Until a format is known every line goes to every parser (so ASC header
//! lines still set the base and timestamp mode); the first line that one of
//! them reads as a frame fixes the format, or a header only one format
//! writes (ASC `base`, `Begin Triggerblock`): a file of such headers whose
//! frame lines are all unreadable is that format with malformed lines, not
//! an unknown format. Lines before that are skipped when
//! some format knows them as non-frame lines and malformed when none does.
//!
//! Formats can mix (a pasted screen excerpt inside a log, two files
//! concatenated): a line that is malformed in the detected format but a frame
//! in another one is still read, and [`Detector::take_foreign`] says so, so the
//! caller warns. No EMCY is lost because a file changed its mind.

use std::io::{self, Read};

use super::deltas::{self, DeltaClock};
use super::format::blf;
use super::format::{mf4, pcap};
use super::read::read_full;
use super::{
    AnyParser, Folds, Format, IdCounts, Interest, LineParser, Parsed, Run, Scan, Timestamp,
};

/// The input with the bytes [`sniff_binary`] read put back in front.
pub type Sniffed<R> = io::Chain<io::Cursor<Vec<u8>>, R>;

/// Looks at the first bytes for the magic of a binary format: `LOGG`
/// (BLF), a pcap magic number in either byte order, or a pcapng section
/// header (its block type and byte-order magic: 12 bytes, read only when
/// the first 4 are the block type), or an MDF identification block
/// (`MDF     ` or `UnFinMF `: 8 bytes, read only when the first 4 start
/// one; MDF 3 too, which its reader refuses with a clear error). The
/// bytes read are put back in front
/// of the stream: `(stream, Ok(the binary format, if any))`.
pub fn sniff_binary<R: Read>(mut input: R) -> (Sniffed<R>, io::Result<Option<Format>>) {
    let mut head = [0u8; 12];
    let mut n = 0;
    let mut result = read_full(&mut input, head.get_mut(..4).unwrap_or_default());
    if let Ok(k) = result {
        n = k;
        let more = match head.get(..4) {
            Some(b"MDF " | b"UnFi") if n == 4 => 8,
            _ if n == 4 && pcap::is_pcapng_block_type(&head) => 12,
            _ => n,
        };
        if more > n {
            result = read_full(&mut input, head.get_mut(4..more).unwrap_or_default());
            if let Ok(k) = result {
                n += k;
            }
        }
    }
    let format = result.map(|_| {
        let head = head.get(..n).unwrap_or_default();
        if head == blf::MAGIC {
            Some(Format::Blf)
        } else if mf4::is_magic(head) {
            Some(Format::Mf4)
        } else {
            pcap::sniff(head)
        }
    });
    let prefix = head.get(..n).unwrap_or_default().to_vec();
    (io::Cursor::new(prefix).chain(input), format)
}

/// How much of a file [`looks_like_trace`] reads.
const TRACE_SNIFF_BYTES: u64 = 64 * 1024;
const TRACE_SNIFF_LINES: usize = 64;

/// Whether `input` (gzip already decoded) starts like a trace: a binary
/// format's magic, or a line among its first 64 (or 64 KiB) that a text
/// format reads as a frame or as a header only it writes. For skipping
/// files that are no trace (a script, a README) in a directory read with
/// `-r`; an input named on its own is always read, so its errors show.
pub fn looks_like_trace<R: Read>(input: R) -> io::Result<bool> {
    let (rest, binary) = sniff_binary(input);
    if binary?.is_some() {
        return Ok(true);
    }
    let mut head = Vec::new();
    rest.take(TRACE_SNIFF_BYTES).read_to_end(&mut head)?;
    let mut detector = Detector::auto();
    let interest = Interest::all();
    for line in head.split(|&b| b == b'\n').take(TRACE_SNIFF_LINES) {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if matches!(detector.parse(line, &interest), Parsed::Frame(_))
            || detector.format().is_some()
        {
            return Ok(true);
        }
    }
    Ok(false)
}

/// The formats whose times may be `-td` deltas.
fn is_candump(format: Option<Format>) -> bool {
    matches!(format, Some(Format::CandumpLog | Format::CandumpScreen))
}

/// Classifies lines in the format detected from them (or forced), and says
/// which format that is.
pub struct Detector {
    parsers: Vec<AnyParser>,
    /// Index of the detected format's parser.
    primary: Option<usize>,
    /// `--input-format`: no fallback to other formats.
    forced: bool,
    /// The format of the last frame when it was not the primary one.
    foreign: Option<Format>,
    /// Index of the parser that read the last frame `parse` returned.
    reader: usize,
    /// Candump times are `-td` deltas, summed here (see [`super::deltas`]).
    deltas: Option<DeltaClock>,
}

impl Detector {
    /// Detects the format from the lines as they come.
    pub fn auto() -> Detector {
        Detector {
            parsers: Format::ALL.iter().map(|f| f.parser()).collect(),
            primary: None,
            forced: false,
            foreign: None,
            reader: 0,
            deltas: None,
        }
    }

    /// Reads every line as `format` (`--input-format`), nothing else.
    pub fn forced(format: Format) -> Detector {
        Detector {
            parsers: vec![format.parser()],
            primary: Some(0),
            forced: true,
            foreign: None,
            reader: 0,
            deltas: None,
        }
    }

    /// A copy in the current state (all parsers forked), for another thread.
    pub fn fork(&self) -> Detector {
        Detector {
            parsers: self.parsers.clone(),
            primary: self.primary,
            forced: self.forced,
            foreign: None,
            reader: 0,
            deltas: self.deltas,
        }
    }

    /// From now on, candump times are deltas to the previous frame
    /// (`candump -td`): each frame's time is the sum so far. Lines then
    /// chain, so [`Detector::context`] is `None`, and every frame is parsed
    /// in full for its time.
    pub fn read_deltas(&mut self) {
        self.set_deltas(true);
    }

    /// [`Detector::read_deltas`] or not; before the first line only.
    pub fn set_deltas(&mut self, on: bool) {
        self.deltas = on.then(DeltaClock::default);
    }

    /// Whether candump times are summed as deltas.
    pub fn reads_deltas(&self) -> bool {
        self.deltas.is_some()
    }

    /// The combined [`LineParser::context`] of every parser plus the detected
    /// format; `None` when some parser chains lines (parse sequentially).
    pub fn context(&self) -> Option<u64> {
        if self.deltas.is_some() {
            return None;
        }
        let mut ctx = u64::from(self.primary.map_or(0xFF, |p| p as u8));
        for p in &self.parsers {
            ctx = (ctx << 8) | u64::from(p.context()?);
        }
        Some(ctx)
    }

    /// The bit rate the detected format's header recorded, once read.
    pub fn bit_rate(&self) -> Option<u32> {
        self.primary
            .and_then(|i| self.parsers.get(i))
            .and_then(|p| p.bit_rate())
    }

    /// The format, once known.
    pub fn format(&self) -> Option<Format> {
        self.primary
            .and_then(|i| self.parsers.get(i))
            .map(|p| p.format())
    }

    /// After a frame: `Some(format)` when it was read by another format than
    /// the detected one. Cleared by the call.
    pub fn take_foreign(&mut self) -> Option<Format> {
        self.foreign.take()
    }

    /// After a frame: what the parser that read it made good in the line
    /// (see [`LineParser::take_warning`]). Cleared by the call.
    pub fn take_warning(&mut self) -> Option<super::Reason> {
        // Only the parser that read the frame has one: every parser clears
        // its own when it parses a line.
        self.parsers.iter_mut().find_map(|p| p.take_warning())
    }

    /// After a frame: whether a note followed it on its line (see
    /// [`LineParser::take_annotated`]). Cleared by the call.
    pub fn take_annotated(&mut self) -> bool {
        // Only the parser that read the frame is asked: a flag another
        // parser set on an earlier line is cleared by its next `parse`,
        // before it could read a frame again.
        self.parsers
            .get_mut(self.reader)
            .is_some_and(|p| p.take_annotated())
    }

    /// See [`LineParser::run`]; only once the format is known (nothing
    /// read before), and only for the detected format.
    #[inline]
    pub fn run<'a>(
        &mut self,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        folds: &mut Folds,
        ids: &mut IdCounts,
    ) -> Run<'a> {
        if self.deltas.is_some() {
            return Run::default();
        }
        match self.primary.and_then(|i| self.parsers.get_mut(i)) {
            Some(p) => p.run(bytes, max_line, interest, folds, ids),
            None => Run::default(),
        }
    }

    /// See [`LineParser::scan`]; only once the format is known, and only
    /// for the detected format (a frame it returns is never foreign).
    #[inline]
    pub fn scan<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Scan<'a> {
        let scan = match self.primary.and_then(|i| self.parsers.get_mut(i)) {
            Some(p) => p.scan(line, interest),
            None => Scan::Parse,
        };
        if self.deltas.is_none() {
            return scan;
        }
        match scan {
            // Not decoded, but its delta moves the clock all the same.
            Scan::Plain(key) => {
                self.sum(self.format(), line, None);
                Scan::Plain(key)
            }
            Scan::Timed(delta, key) => Scan::Timed(
                self.sum(self.format(), line, Some(delta)).unwrap_or(delta),
                key,
            ),
            Scan::Frame(mut frame) => {
                frame.time = self.sum(self.format(), line, frame.time).or(frame.time);
                Scan::Frame(frame)
            }
            Scan::Parse => Scan::Parse,
        }
    }

    /// Classifies one line: by the detected format once it is known, by every
    /// format before (see the module's documentation).
    #[inline]
    pub fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        let mut parsed = self.parse_line(line, interest);
        if self.deltas.is_some()
            && let Parsed::Frame(frame) = &mut parsed
        {
            let format = self.foreign.or(self.format());
            // A frame nobody wants has no time decoded: it only moves the clock.
            let summed = self.sum(format, line, frame.time);
            if frame.time.is_some() {
                frame.time = summed.or(frame.time);
            }
        }
        parsed
    }

    /// Moves the `-td` clock by a candump frame's delta (`time` when its
    /// parser read it, else read from the line) and returns the sum;
    /// `None` for other formats' frames and frames without a time.
    fn sum(
        &mut self,
        format: Option<Format>,
        line: &[u8],
        time: Option<Timestamp>,
    ) -> Option<Timestamp> {
        let clock = self.deltas.as_mut().filter(|_| is_candump(format))?;
        let delta = time.or_else(|| deltas::leading_time(line))?;
        Some(clock.next(delta))
    }

    /// The time of the first frame in `bytes`, of any id and kind, read
    /// from this detector's state before the block: the input's start,
    /// when this is its first block with a frame. The hot loops skip the
    /// times of frames nobody decodes (most of a real bus), so the span is
    /// found at the blocks' edges instead, on a fork: a line or two from
    /// each end, unless a block ends in lines that are no frames.
    pub fn first_frame_time(&self, bytes: &[u8], max_line: usize) -> Option<Timestamp> {
        let mut fork = self.fork();
        let all = Interest::all();
        bytes
            .split(|b| *b == b'\n')
            .find_map(|line| fork.frame_time(line, max_line, &all))
    }

    /// The time of the last frame in `bytes`, of any id and kind, read from this detector's state after the block (see
    /// [`Detector::first_frame_time`]). Where times chain (`-td` deltas,
    /// relative times) every frame's time was read: the sum so far is it.
    pub fn last_frame_time(&self, bytes: &[u8], max_line: usize) -> Option<Timestamp> {
        if let Some(clock) = &self.deltas {
            return clock.sum();
        }
        let primary = self.primary.and_then(|i| self.parsers.get(i));
        if let Some(now) = primary.and_then(|p| p.clock()) {
            return Some(now);
        }
        let mut fork = self.fork();
        let all = Interest::all();
        bytes
            .rsplit(|b| *b == b'\n')
            .find_map(|line| fork.frame_time(line, max_line, &all))
    }

    /// A frame line's time (the `-td` clock moves on), else `None`.
    fn frame_time(&mut self, line: &[u8], max_line: usize, all: &Interest) -> Option<Timestamp> {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.is_empty() || line.len() > max_line {
            return None;
        }
        match self.parse(line, all) {
            Parsed::Frame(frame) => frame.time,
            _ => None,
        }
    }

    fn parse_line<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        self.foreign = None;
        let Some(primary) = self.primary else {
            return self.parse_undecided(line, interest);
        };
        let reason = match self
            .parsers
            .get_mut(primary)
            .map(|p| p.parse(line, interest))
        {
            Some(Parsed::Malformed(reason)) => reason,
            Some(other) => {
                self.reader = primary;
                return other;
            }
            None => return Parsed::Malformed("no parser".into()),
        };
        if !self.forced {
            for (i, parser) in self.parsers.iter_mut().enumerate() {
                if i == primary {
                    continue;
                }
                if let Parsed::Frame(frame) = parser.parse(line, interest) {
                    self.foreign = Some(parser.format());
                    self.reader = i;
                    return Parsed::Frame(frame);
                }
            }
        }
        Parsed::Malformed(reason)
    }

    fn parse_undecided<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        let mut skipped = false;
        // A line that tells its format (a PEAK `;$STARTTIME=`) but that the
        // format cannot read: reported, even if another format would take
        // it for a comment.
        let mut told = None;
        for (i, parser) in self.parsers.iter_mut().enumerate() {
            match parser.parse(line, interest) {
                Parsed::Frame(frame) => {
                    self.primary = Some(i);
                    self.reader = i;
                    return Parsed::Frame(frame);
                }
                Parsed::Skipped => skipped = true,
                Parsed::Malformed(reason) => {
                    if told.is_none() && parser.identified() {
                        told = Some((i, reason));
                    }
                }
            }
        }
        if let Some(i) = self.parsers.iter().position(|p| p.identified()) {
            self.primary = Some(i);
        }
        if let Some((i, reason)) = told {
            self.primary = Some(i);
            self.reader = i;
            return Parsed::Malformed(reason);
        }
        if skipped {
            Parsed::Skipped
        } else {
            Parsed::Malformed(
                "not a line of any format read (candump log, candump screen, Vector ASC, PEAK TRC, BUSMASTER, IXXAT MiniMon)"
                    .into(),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn traces_are_told_from_other_files_by_their_first_lines() {
        let is = |b: &[u8]| looks_like_trace(b).unwrap();
        assert!(is(b"(1469439874.299654) can0 081#1043090100000000\n"));
        assert!(is(
            b"# a comment\r\n  can0  081   [8]  10 43 09 01 00 00 00 00\r\n"
        ));
        assert!(is(
            b"date Wed Nov 15 10:00:00 2023\nbase hex  timestamps absolute\n"
        ));
        assert!(is(b"LOGG\0\0\0\0"), "BLF by its magic");
        assert!(!is(
            b"#!/usr/bin/env python3\nimport struct\n\nprint('hi')\n"
        ));
        assert!(!is(b"name = \"acme\"\n[codes]\n"));
        assert!(!is(b""));
        // Only the first lines count: a frame after 64 lines of prose is no trace.
        let mut late = b"prose\n".repeat(64);
        late.extend_from_slice(b"(1.0) can0 081#10430901\n");
        assert!(!is(&late));
    }

    use super::*;

    fn kinds(lines: &[&str], detector: &mut Detector) -> Vec<(String, Option<Format>)> {
        lines
            .iter()
            .map(|l| {
                let p = detector.parse(l.as_bytes(), &Interest::all());
                let kind = match p {
                    Parsed::Frame(_) => "frame".to_string(),
                    Parsed::Skipped => "skipped".to_string(),
                    Parsed::Malformed(_) => "malformed".to_string(),
                };
                (kind, detector.take_foreign())
            })
            .collect()
    }

    #[test]
    fn a_note_after_a_frame_is_told_once_by_the_parser_that_read_it() {
        let mut d = Detector::auto();
        let all = Interest::all();
        let mut read = |line: &str| {
            let frame = matches!(d.parse(line.as_bytes(), &all), Parsed::Frame(_));
            (frame, d.take_annotated(), d.take_annotated())
        };
        // Undecided, then as the detected format, then as a foreign one.
        assert_eq!(read("  can0  701   [1]  00   // boot"), (true, true, false));
        assert_eq!(read("  can0  701   [1]  05"), (true, false, false));
        assert_eq!(read("(1.0) can0 701#05 < response"), (true, true, false));
        assert_eq!(
            read("  can0  701   [1]  05  < heartbeat"),
            (true, true, false)
        );
        assert_eq!(d.format(), Some(Format::CandumpScreen));
    }

    #[test]
    fn first_frame_decides() {
        let mut d = Detector::auto();
        assert_eq!(d.format(), None);
        let got = kinds(&["", "garbage", "(1.0) can0 081#00"], &mut d);
        assert_eq!(got[0].0, "skipped");
        assert_eq!(got[1].0, "malformed");
        assert_eq!(got[2].0, "frame");
        assert_eq!(d.format(), Some(Format::CandumpLog));
    }

    #[test]
    fn asc_header_before_the_first_frame_is_applied() {
        let mut d = Detector::auto();
        d.parse(b"base dec  timestamps absolute", &Interest::all());
        match d.parse(b"   1.000000 1  129  Rx   d 3 16 67 9", &Interest::all()) {
            Parsed::Frame(f) => {
                assert_eq!(f.id, 0x81);
                assert_eq!(f.data.as_slice(), [0x10, 0x43, 0x09]);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(d.format(), Some(Format::Asc));
    }

    #[test]
    fn a_line_of_another_format_is_read_and_flagged() {
        let mut d = Detector::auto();
        let got = kinds(
            &[
                "(1.0) can0 081#00",
                "  can0  081   [1]  00",
                "(2.0) can0 081#00",
                "neither",
            ],
            &mut d,
        );
        assert_eq!(got[0], ("frame".to_string(), None));
        assert_eq!(got[1], ("frame".to_string(), Some(Format::CandumpScreen)));
        assert_eq!(got[2], ("frame".to_string(), None));
        assert_eq!(got[3], ("malformed".to_string(), None));
        assert_eq!(d.format(), Some(Format::CandumpLog));
    }

    #[test]
    fn asc_headers_make_the_format_known_before_any_frame() {
        let mut d = Detector::auto();
        let got = kinds(&["date Sat Sep 30 15:06:13.191 2017", "garbage"], &mut d);
        assert_eq!(got[0].0, "skipped");
        assert_eq!(
            d.format(),
            None,
            "`date` alone could be a pasted shell `date`"
        );
        d.parse(b"base hex  timestamps absolute", &Interest::all());
        assert_eq!(d.format(), Some(Format::Asc));
        // A line no format reads is ASC's to explain.
        match d.parse(b" 0.000000 1  123x  Rx   d 40 00 01", &Interest::all()) {
            Parsed::Malformed(r) => assert!(r.contains("DLC '40'"), "{r}"),
            other => panic!("{other:?}"),
        }
        let mut d = Detector::auto();
        d.parse(
            b"Begin Triggerblock Sat Sep 30 15:06:13.191 2017",
            &Interest::all(),
        );
        assert_eq!(d.format(), Some(Format::Asc));
        // Another format's frames are still read, and flagged.
        let got = kinds(&["(1.0) can0 081#00"], &mut d);
        assert_eq!(got[0], ("frame".to_string(), Some(Format::CandumpLog)));
    }

    #[test]
    fn the_warning_of_a_frame_is_taken_once() {
        let mut d = Detector::auto();
        let line = format!("1.0 CANFD 1 Rx 123 0 0 9 12{} 1 1 0", " 00".repeat(12));
        assert!(matches!(
            d.parse(line.as_bytes(), &Interest::all()),
            Parsed::Frame(_)
        ));
        assert!(d.take_warning().is_some_and(|w| w.contains("lack FDF")));
        assert!(d.take_warning().is_none());
    }

    #[test]
    fn binary_formats_are_known_by_their_magic_and_the_bytes_put_back() {
        let sniff = |bytes: &[u8]| {
            let (mut stream, format) = sniff_binary(bytes);
            let mut back = Vec::new();
            stream.read_to_end(&mut back).unwrap();
            assert_eq!(back, bytes);
            format.unwrap()
        };
        assert_eq!(sniff(b"LOGG\x90\0\0\0"), Some(Format::Blf));
        for magic in [
            [0xD4, 0xC3, 0xB2, 0xA1],
            [0xA1, 0xB2, 0xC3, 0xD4],
            [0x4D, 0x3C, 0xB2, 0xA1],
            [0xA1, 0xB2, 0x3C, 0x4D],
        ] {
            assert_eq!(sniff(&magic), Some(Format::Pcap), "{magic:02X?}");
        }
        let shb = b"\x0A\x0D\x0D\x0A\x1C\0\0\0\x4D\x3C\x2B\x1A";
        assert_eq!(sniff(shb), Some(Format::Pcapng));
        let shb_be = b"\x0A\x0D\x0D\x0A\0\0\0\x1C\x1A\x2B\x3C\x4D";
        assert_eq!(sniff(shb_be), Some(Format::Pcapng));
        // The block type without the byte-order magic: blank lines with CRs.
        assert_eq!(sniff(b"\n\r\r\n(1.0) can0 081#00\n"), None);
        assert_eq!(sniff(b"\n\r\r\n"), None);
        assert_eq!(sniff(b"(1.0) can0 081#00\n"), None);
        assert_eq!(sniff(b"LO"), None);
        assert_eq!(sniff(b"MDF     4.11    "), Some(Format::Mf4));
        assert_eq!(sniff(b"UnFinMF 4.11    "), Some(Format::Mf4));
        // MDF 3 is known, to be refused by its reader with a clear error.
        assert_eq!(sniff(b"MDF     3.30    "), Some(Format::Mf4));
        assert_eq!(sniff(b"MDF (1.0) can0 081#00\n"), None);
        assert_eq!(sniff(b"UnFi"), None);
        assert_eq!(sniff(b""), None);
    }

    #[test]
    fn deltas_sum_candump_times_only_and_chain_every_line() {
        let mut d = Detector::auto();
        assert!(d.context().is_some());
        d.read_deltas();
        assert!(d.reads_deltas());
        assert_eq!(d.context(), None, "every line depends on the one before");
        fn at(d: &mut Detector, line: &str, interest: &Interest) -> Option<String> {
            match d.parse(line.as_bytes(), interest) {
                Parsed::Frame(f) => f.time.map(|t| t.to_string()),
                other => panic!("{other:?}"),
            }
        }
        let mut time = |line: &str, interest: &Interest| at(&mut d, line, interest);
        // Frames nobody wants get no time, but move the clock.
        assert_eq!(time("(000.500000) can0 701#05", &Interest::none()), None);
        assert_eq!(
            time("(000.250000) can0 081#00", &Interest::all()),
            Some("0.750000".into())
        );
        assert_eq!(
            time(" (001.000001)  can0  081   [1]  00", &Interest::all()),
            Some("1.750001".into()),
            "a screen line of the same trace sums on"
        );
        // Another format's own times are not candump deltas.
        assert_eq!(
            time(
                "   0.100000 1  081             Rx   d 1 00",
                &Interest::all()
            ),
            Some("0.100000".into())
        );
        assert_eq!(
            time("(000.000009) can0 081#00", &Interest::all()),
            Some("1.750010".into())
        );
        // The id-first scan: plain frames move the clock, wanted ones get the sum.
        let mut wanted = Interest::none();
        wanted.add_standard(0x81);
        assert!(matches!(
            d.scan(b"(000.100000) can0 701#05", &wanted),
            Scan::Plain(key) if key == crate::FrameKey::new(b"can0", 0x701, false)
        ));
        match d.scan(b"(000.100000) can0 081#00", &wanted) {
            Scan::Frame(f) => assert_eq!(f.time.map(|t| t.to_string()), Some("1.950010".into())),
            other => panic!("{other:?}"),
        }
        // The hot loop cannot report each line's time: it is never run.
        assert_eq!(
            d.run(
                b"(000.1) can0 701#05\n",
                100,
                &Interest::none(),
                &mut Folds::default(),
                &mut IdCounts::new()
            )
            .bytes,
            0
        );
        d.set_deltas(false);
        let line = "(000.500000) can0 081#00";
        assert_eq!(at(&mut d, line, &Interest::all()), Some("0.500000".into()));
    }

    #[test]
    fn forced_format_reads_nothing_else() {
        let mut d = Detector::forced(Format::CandumpLog);
        let got = kinds(&["  can0  081   [1]  00"], &mut d);
        assert_eq!(got[0], ("malformed".to_string(), None));
    }

    /// Reads `text` line by line as the analysis does, then asks for the
    /// block's edge times: the first from the state before it, the last
    /// from the state after.
    fn edges(detector: &mut Detector, text: &str) -> (Option<String>, Option<String>) {
        let first = detector.first_frame_time(text.as_bytes(), 200);
        for line in text.lines() {
            detector.parse(line.as_bytes(), &Interest::none());
        }
        let last = detector.last_frame_time(text.as_bytes(), 200);
        (first.map(|t| t.to_string()), last.map(|t| t.to_string()))
    }

    #[test]
    fn a_blocks_edge_times_are_its_first_and_last_frames_of_any_id() {
        let some = |s: &str| Some(s.to_string());
        // Comments and junk at the edges do not move the span; frames
        // nobody decodes do.
        let text = "# a comment\n\n(10.5) can0 181#00\n(11.0) can0 081#00\n\
                    (12.25) can0 7FF#\nnot a frame\n";
        let mut d = Detector::auto();
        assert_eq!(edges(&mut d, text), (some("10.5"), some("12.25")));
        // A block with no frame has no edges.
        assert_eq!(edges(&mut d, "# only talk\n"), (None, None));
        // `-td` deltas: the first frame is at its own delta, the last at
        // the sum of them all.
        let mut d = Detector::forced(Format::CandumpLog);
        d.read_deltas();
        let deltas = "(0.5) can0 181#00\n(1.0) can0 181#00\n(0.25) can0 181#00\n";
        assert_eq!(edges(&mut d, deltas), (some("0.5"), some("1.75")));
        // Relative ASC times chain the same way: the parser's running time
        // is the last frame's.
        let asc = "base hex  timestamps relative\n   1.000000 1  181  Rx   d 1 00\n\
                   2.000000 1  181  Rx   d 1 00\n";
        let mut d = Detector::auto();
        assert_eq!(edges(&mut d, asc), (some("1.000000"), some("3.000000")));
    }
}
