//! A whole trace read into frames, one record per line: the library's way
//! in for a Rust program that wants the frames themselves. The analysis
//! does not use it (it decodes only the ids that matter, on several
//! threads); this reads every id of every line, in order, and owns what it
//! returns. (What a frame is to CANopen, e.g. [`CanFrame::emcy_node`], is
//! in `canopen`: this layer knows nothing above the frame.)

use std::collections::VecDeque;
use std::io::{self, Read};

use super::deltas::{self, TimeMode};
use super::detect::{Detector, sniff_binary};
use super::input::sniff_gzip_generic;
use super::lines::{DEFAULT_BLOCK, DEFAULT_MAX_LINE};
use super::text::TextReader;
use super::{AnyReader, Format, Frame, FrameKind, FrameSource, Next, Parsed, Timestamp};

/// One CAN frame of a trace, owned.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CanFrame {
    /// 1-based line of the trace (for BLF: the object's number; for pcap
    /// and pcapng: the packet's, as Wireshark numbers frames; for MF4: the
    /// record's, in file order).
    pub line: u64,
    /// Seconds as the trace wrote them; `None` when the trace has no times.
    pub time: Option<Timestamp>,
    /// Interface (candump), channel number (ASC, TRC, BLF) as written;
    /// bytes that are not UTF-8 become U+FFFD.
    pub channel: String,
    /// 11- or 29-bit identifier (for error frames, the error class bits
    /// of linux/can/error.h, without the error flag).
    pub id: u32,
    /// A 29-bit identifier.
    pub extended: bool,
    /// Data, remote, error or CAN FD.
    pub kind: FrameKind,
    /// The data bytes (none for remote frames; an error frame's are
    /// error.h's 8, or none when the trace does not say its class).
    pub data: Vec<u8>,
}

impl CanFrame {
    /// The owned copy of a parsed frame at `line`.
    pub(crate) fn of(line: u64, f: &Frame<'_>) -> CanFrame {
        CanFrame {
            line,
            time: f.time,
            channel: String::from_utf8_lossy(f.channel).into_owned(),
            id: f.id,
            extended: f.extended,
            kind: f.kind,
            data: f.data.as_slice().to_vec(),
        }
    }
}

/// What one line of a trace is. Every line is exactly one of these.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Record {
    /// A CAN frame.
    Frame(CanFrame),
    /// A known line that is not a frame: a header, comment, status line.
    Skipped {
        /// 1-based line.
        line: u64,
    },
    /// A line that is not what the format allows, with the reason.
    Malformed {
        /// 1-based line.
        line: u64,
        /// Why, e.g. `odd number of data digits`.
        reason: String,
    },
    /// Something about the trace as a whole worth telling, e.g. a BLF
    /// header whose start time is not a date, or a pcap whose SocketCAN
    /// ids are stored little-endian.
    Note(String),
    /// What the reader made good to read the frame of the same line, which
    /// comes next: e.g. a BLF CAN FD object storing fewer data bytes than
    /// it declares (read as zeros), or an ASC CANFD line whose flags lack
    /// FDF but whose 64 bytes only an FD frame carries. Not a line of its own.
    Warning {
        /// 1-based line (for BLF: the object's number), as its frame's.
        line: u64,
        /// What was wrong and how it was read.
        reason: String,
    },
}

/// Reads a trace into [`Record`]s, one per line, in order. The format is
/// detected from the content (candump log or screen output, Vector ASC,
/// PEAK TRC, BUSMASTER, Vector BLF, pcap, pcapng, MF4), or forced; gzip is
/// decompressed, known by its magic bytes. Lines longer than 64 KiB are
/// malformed, never buffered. The first 16 lines of a text trace are read
/// ahead to tell candump `-td` deltas (see [`TraceReader::with_timestamps`]).
///
/// An I/O error ends the iteration after it is returned.
pub struct TraceReader<'a> {
    source: Source<'a>,
    /// Records of the current block not yet returned.
    queue: VecDeque<Record>,
    /// Lines read so far.
    lines: u64,
    /// Why the candump times are read as `-td` deltas, when the first
    /// lines said so: the first record, unless [`TraceReader::with_timestamps`]
    /// says otherwise.
    deltas_seen: Option<String>,
}

enum Source<'a> {
    Reading(AnyReader<Box<dyn Read + 'a>>),
    Failed(io::Error),
    /// The end, with the format the input had.
    Done(Option<Format>),
}

impl<'a> TraceReader<'a> {
    /// A reader that detects the format.
    pub fn new(input: impl Read + 'a) -> Self {
        Self::open(input, None)
    }

    /// A reader that reads every line as `format` (lines of other formats
    /// are malformed).
    pub fn with_format(input: impl Read + 'a, format: Format) -> Self {
        Self::open(input, Some(format))
    }

    fn open(input: impl Read + 'a, format: Option<Format>) -> Self {
        let (source, deltas_seen) = match Self::sniff(input, format) {
            Ok((source, evidence)) => (source, evidence.map(|e| e.note())),
            Err(e) => (Source::Failed(e), None),
        };
        TraceReader {
            source,
            queue: VecDeque::new(),
            lines: 0,
            deltas_seen,
        }
    }

    /// Says what candump times are instead of detecting `-td` deltas from
    /// the first lines: [`TimeMode::Delta`] sums them, the others read
    /// them as written. Call it before the first record.
    pub fn with_timestamps(mut self, mode: TimeMode) -> Self {
        self.deltas_seen = None;
        if let Source::Reading(AnyReader::Text(text)) = &mut self.source {
            text.detector_mut().set_deltas(mode == TimeMode::Delta);
        }
        self
    }

    /// The source for `input`, and for a text input that may be candump,
    /// whether its first lines prove `-td` deltas.
    fn sniff(
        input: impl Read + 'a,
        format: Option<Format>,
    ) -> io::Result<(Source<'a>, Option<deltas::Evidence>)> {
        let (input, _) = sniff_gzip_generic(input)?;
        let (input, magic) = sniff_binary(input);
        let magic = magic?;
        let input: Box<dyn Read + 'a> = Box::new(input);
        if let Some(binary) = format.map_or(magic, |f| f.is_binary().then_some(f)) {
            return Ok((Source::Reading(AnyReader::binary(binary, input)?), None));
        }
        let mut detector = match format {
            Some(f) => Detector::forced(f),
            None => Detector::auto(),
        };
        let (input, evidence): (Box<dyn Read + 'a>, _) = match format {
            None | Some(Format::CandumpLog | Format::CandumpScreen) => {
                let (input, evidence) = deltas::read_ahead(input);
                (Box::new(input), evidence)
            }
            Some(_) => (input, None),
        };
        detector.set_deltas(evidence.is_some());
        let text = TextReader::new(input, detector, DEFAULT_BLOCK, DEFAULT_MAX_LINE);
        let source = Source::Reading(AnyReader::Text(Box::new(text)));
        Ok((source, evidence))
    }

    /// The format: forced, or detected from the lines read so far.
    pub fn format(&self) -> Option<Format> {
        match &self.source {
            Source::Reading(reader) => reader.format(),
            Source::Failed(_) => None,
            Source::Done(format) => *format,
        }
    }

    /// The bit rate the input records in a header (IXXAT's `Baudrate:`),
    /// in bit/s, once the header was read.
    pub fn bit_rate(&self) -> Option<u32> {
        match &self.source {
            Source::Reading(reader) => reader.bit_rate(),
            Source::Failed(_) | Source::Done(_) => None,
        }
    }

    /// Fills the queue from the next item of the source; `Err` ends the
    /// input, `Ok(false)` at its end. Every format goes through this one
    /// loop: a record is one line, a note is no line.
    fn refill(&mut self) -> io::Result<bool> {
        if let Some(note) = self.deltas_seen.take() {
            self.queue.push_back(Record::Note(note));
            return Ok(true);
        }
        let Source::Reading(reader) = &mut self.source else {
            return Ok(false);
        };
        // Without an interest every record comes one by one, so nothing
        // is only counted; were something counted, it would still be lines.
        let parsed = match reader.next_item(None)? {
            None => return Ok(false),
            Some(Next::Note(note)) => {
                self.queue.push_back(Record::Note(note));
                return Ok(true);
            }
            Some(Next::Counted(counted)) => {
                self.lines += counted.lines();
                return Ok(true);
            }
            Some(Next::Record(parsed)) => parsed,
        };
        self.lines += 1;
        let line = self.lines;
        let record = match parsed {
            Parsed::Frame(f) => Record::Frame(CanFrame::of(line, &f)),
            Parsed::Skipped => Record::Skipped { line },
            Parsed::Malformed(reason) => Record::Malformed {
                line,
                reason: reason.into_owned(),
            },
        };
        // A warning is about the frame of its line, which comes after it.
        if let Record::Frame(_) = record
            && let Some(reason) = reader.take_warning()
        {
            self.queue.push_back(Record::Warning {
                line,
                reason: reason.into_owned(),
            });
        }
        self.queue.push_back(record);
        Ok(true)
    }
}

impl Iterator for TraceReader<'_> {
    type Item = io::Result<Record>;

    fn next(&mut self) -> Option<io::Result<Record>> {
        loop {
            if let Some(record) = self.queue.pop_front() {
                return Some(Ok(record));
            }
            let result = match &self.source {
                Source::Failed(_) => Ok(false),
                _ => self.refill(),
            };
            match result {
                Ok(true) => {}
                Ok(false) => {
                    let end = Source::Done(self.format());
                    return match std::mem::replace(&mut self.source, end) {
                        Source::Failed(e) => Some(Err(e)),
                        _ => None,
                    };
                }
                Err(e) => {
                    self.source = Source::Done(self.format());
                    return Some(Err(e));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn records(text: &[u8]) -> Vec<Record> {
        TraceReader::new(text).map(|r| r.unwrap()).collect()
    }

    #[test]
    fn every_line_is_one_record_in_order() {
        let got = records(
            b"(1.000000) can0 081#1043080100000000\n\
              # a comment\n\
              (2.000000) can0 081#10zz\n\
              (3.000000) can0 701#00\n",
        );
        assert_eq!(got.len(), 4);
        let Record::Frame(f) = &got[0] else {
            panic!("{got:?}")
        };
        assert_eq!((f.line, f.id, f.emcy_node()), (1, 0x81, Some(1)));
        assert_eq!(f.data, [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
        assert_eq!(f.time.map(|t| t.to_string()), Some("1.000000".into()));
        assert_eq!(got[1], Record::Skipped { line: 2 });
        assert!(matches!(&got[2], Record::Malformed { line: 3, .. }));
        let Record::Frame(boot) = &got[3] else {
            panic!("{got:?}")
        };
        assert_eq!((boot.boot_node(), boot.emcy_node()), (Some(1), None));
    }

    #[test]
    fn gzip_is_read_and_the_format_known() {
        use std::io::Write;
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(b"date Mon Jan 1 00:00:00 2024\nbase hex  timestamps absolute\n   1.000000 1  81  Rx   d 8 10 43 08 01 00 00 00 00\n")
            .unwrap();
        let gz = enc.finish().unwrap();
        let mut r = TraceReader::new(&gz[..]);
        let frames: Vec<CanFrame> = r
            .by_ref()
            .filter_map(|x| match x.unwrap() {
                Record::Frame(f) => Some(f),
                _ => None,
            })
            .collect();
        assert_eq!(r.format(), Some(Format::Asc));
        assert_eq!(frames.len(), 1);
        assert_eq!((frames[0].line, frames[0].channel.as_str()), (3, "1"));
    }

    #[test]
    fn a_warning_comes_before_its_frame_with_the_same_line() {
        let text = format!(
            "base hex  timestamps absolute\n1.0 CANFD 1 Rx 123 0 0 9 12{} 1 1 0\n",
            " 00".repeat(12)
        );
        let got = records(text.as_bytes());
        assert!(
            matches!(&got[1], Record::Warning { line: 2, reason } if reason.contains("lack FDF")),
            "{got:?}"
        );
        assert!(
            matches!(&got[2], Record::Frame(f) if f.line == 2 && f.kind == FrameKind::Fd),
            "{got:?}"
        );
        assert_eq!(got.len(), 3);
    }

    #[test]
    fn asc_headers_without_a_readable_frame_are_asc() {
        let text = b"date Sat Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n\
                     Begin Triggerblock Sat Sep 30 15:06:13.191 2017\n\
                     0.000000 1  123x  Rx   d 40 00 01\nEnd TriggerBlock\n";
        let mut r = TraceReader::new(&text[..]);
        let got: Vec<Record> = r.by_ref().map(|x| x.unwrap()).collect();
        assert_eq!(r.format(), Some(Format::Asc));
        assert!(
            matches!(&got[3], Record::Malformed { line: 4, reason } if reason.contains("DLC '40'")),
            "{got:?}"
        );
    }

    #[test]
    fn a_forced_format_makes_other_formats_malformed() {
        let line = b"(1.000000) can0 081#1043080100000000\n";
        let got: Vec<Record> = TraceReader::with_format(&line[..], Format::Asc)
            .map(|r| r.unwrap())
            .collect();
        assert!(
            matches!(&got[..], [Record::Malformed { line: 1, .. }]),
            "{got:?}"
        );
    }

    #[test]
    fn a_read_error_is_returned_once_then_the_end() {
        struct Failing;
        impl Read for Failing {
            fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
                Err(io::Error::other("device gone"))
            }
        }
        let mut r = TraceReader::new(Failing);
        assert_eq!(r.next().unwrap().unwrap_err().to_string(), "device gone");
        assert!(r.next().is_none());
    }
}
