//! The dispatchers: [`AnyParser`] holds the line parser of any text format,
//! [`AnyReader`] the frame source of any format. Each is an enum matched
//! per call: the set of formats is closed, and a match lets the hot path
//! inline where a trait object would not.

use std::io::{self, Read};

use crate::Timestamp;
use crate::ethercat::{EthercatCounts, EthercatPacket};
use crate::format::blf::BlfReader;
use crate::format::mf4::Mf4Reader;
use crate::format::pcap::PcapReader;
use crate::format::{asc, busmaster, candump_log, candump_screen, ixxat, trc};
use crate::text::TextReader;
use crate::{
    Folds, Format, FrameSource, IdCounts, Interest, LineParser, Next, Parsed, Reason, Run, Scan,
};

/// One parser of each text format, dispatched by `match`: the set is closed,
/// and a match lets the hot path inline where a trait object would not.
/// `Clone` is how a parser is forked for another thread.
#[derive(Clone)]
pub enum AnyParser {
    /// A candump `-l` log parser.
    CandumpLog(candump_log::CandumpLogParser),
    /// A candump screen output parser.
    CandumpScreen(candump_screen::CandumpScreenParser),
    /// A Vector ASC parser.
    Asc(asc::AscParser),
    /// A PEAK TRC parser.
    Trc(trc::TrcParser),
    /// A BUSMASTER log parser.
    Busmaster(busmaster::BusmasterParser),
    /// An IXXAT MiniMon V3 ASCII trace parser.
    Ixxat(ixxat::IxxatParser),
    /// The parser of a binary format, which reads no lines.
    Binary(BinaryParser),
}

impl LineParser for AnyParser {
    fn format(&self) -> Format {
        match self {
            AnyParser::CandumpLog(p) => p.format(),
            AnyParser::CandumpScreen(p) => p.format(),
            AnyParser::Asc(p) => p.format(),
            AnyParser::Trc(p) => p.format(),
            AnyParser::Busmaster(p) => p.format(),
            AnyParser::Ixxat(p) => p.format(),
            AnyParser::Binary(p) => p.format(),
        }
    }

    #[inline]
    fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        match self {
            AnyParser::CandumpLog(p) => p.parse(line, interest),
            AnyParser::CandumpScreen(p) => p.parse(line, interest),
            AnyParser::Asc(p) => p.parse(line, interest),
            AnyParser::Trc(p) => p.parse(line, interest),
            AnyParser::Busmaster(p) => p.parse(line, interest),
            AnyParser::Ixxat(p) => p.parse(line, interest),
            AnyParser::Binary(p) => p.parse(line, interest),
        }
    }

    fn take_warning(&mut self) -> Option<Reason> {
        match self {
            AnyParser::CandumpLog(p) => p.take_warning(),
            AnyParser::CandumpScreen(p) => p.take_warning(),
            AnyParser::Asc(p) => p.take_warning(),
            AnyParser::Trc(p) => p.take_warning(),
            AnyParser::Busmaster(p) => p.take_warning(),
            AnyParser::Ixxat(p) => p.take_warning(),
            AnyParser::Binary(p) => p.take_warning(),
        }
    }

    fn take_annotated(&mut self) -> bool {
        match self {
            AnyParser::CandumpLog(p) => p.take_annotated(),
            AnyParser::CandumpScreen(p) => p.take_annotated(),
            AnyParser::Asc(p) => p.take_annotated(),
            AnyParser::Trc(p) => p.take_annotated(),
            AnyParser::Busmaster(p) => p.take_annotated(),
            AnyParser::Ixxat(p) => p.take_annotated(),
            AnyParser::Binary(p) => p.take_annotated(),
        }
    }

    fn identified(&self) -> bool {
        match self {
            AnyParser::CandumpLog(p) => p.identified(),
            AnyParser::CandumpScreen(p) => p.identified(),
            AnyParser::Asc(p) => p.identified(),
            AnyParser::Trc(p) => p.identified(),
            AnyParser::Busmaster(p) => p.identified(),
            AnyParser::Ixxat(p) => p.identified(),
            AnyParser::Binary(p) => p.identified(),
        }
    }

    fn bit_rate(&self) -> Option<u32> {
        match self {
            AnyParser::CandumpLog(p) => p.bit_rate(),
            AnyParser::CandumpScreen(p) => p.bit_rate(),
            AnyParser::Asc(p) => p.bit_rate(),
            AnyParser::Trc(p) => p.bit_rate(),
            AnyParser::Busmaster(p) => p.bit_rate(),
            AnyParser::Ixxat(p) => p.bit_rate(),
            AnyParser::Binary(p) => p.bit_rate(),
        }
    }

    fn clock(&self) -> Option<Timestamp> {
        match self {
            AnyParser::CandumpLog(p) => p.clock(),
            AnyParser::CandumpScreen(p) => p.clock(),
            AnyParser::Asc(p) => p.clock(),
            AnyParser::Trc(p) => p.clock(),
            AnyParser::Busmaster(p) => p.clock(),
            AnyParser::Ixxat(p) => p.clock(),
            AnyParser::Binary(p) => p.clock(),
        }
    }

    fn context(&self) -> Option<u8> {
        match self {
            AnyParser::CandumpLog(p) => p.context(),
            AnyParser::CandumpScreen(p) => p.context(),
            AnyParser::Asc(p) => p.context(),
            AnyParser::Trc(p) => p.context(),
            AnyParser::Busmaster(p) => p.context(),
            AnyParser::Ixxat(p) => p.context(),
            AnyParser::Binary(p) => p.context(),
        }
    }

    #[inline]
    fn run<'a>(
        &mut self,
        bytes: &'a [u8],
        max_line: usize,
        interest: &Interest,
        folds: &mut Folds,
        ids: &mut IdCounts,
    ) -> Run<'a> {
        match self {
            AnyParser::CandumpLog(p) => p.run(bytes, max_line, interest, folds, ids),
            AnyParser::CandumpScreen(p) => p.run(bytes, max_line, interest, folds, ids),
            AnyParser::Asc(p) => p.run(bytes, max_line, interest, folds, ids),
            AnyParser::Trc(p) => p.run(bytes, max_line, interest, folds, ids),
            AnyParser::Busmaster(p) => p.run(bytes, max_line, interest, folds, ids),
            AnyParser::Ixxat(p) => p.run(bytes, max_line, interest, folds, ids),
            AnyParser::Binary(p) => p.run(bytes, max_line, interest, folds, ids),
        }
    }

    fn scan<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Scan<'a> {
        match self {
            AnyParser::CandumpLog(p) => p.scan(line, interest),
            AnyParser::CandumpScreen(p) => p.scan(line, interest),
            AnyParser::Asc(p) => p.scan(line, interest),
            AnyParser::Trc(p) => p.scan(line, interest),
            AnyParser::Busmaster(p) => p.scan(line, interest),
            AnyParser::Ixxat(p) => p.scan(line, interest),
            AnyParser::Binary(p) => p.scan(line, interest),
        }
    }
}

/// Lines never reach this parser: binary input (BLF, pcap) goes to its own
/// reader. It exists so that every [`Format`] has a parser.
#[derive(Clone, Copy, Debug)]
pub struct BinaryParser(pub Format);

impl LineParser for BinaryParser {
    fn format(&self) -> Format {
        self.0
    }

    fn parse<'a>(&mut self, _line: &'a [u8], _interest: &Interest) -> Parsed<'a> {
        Parsed::Malformed(format!("{} is a binary format, not read line by line", self.0).into())
    }

    fn context(&self) -> Option<u8> {
        Some(0)
    }
}

/// The frame source of any format: one arm per format that has a reader
/// of its own, and one for the text formats, read through their line
/// parsers. A caller's read loop is written once, over
/// [`FrameSource`], and a new binary format is one more arm here.
pub enum AnyReader<R: Read> {
    /// Every text format, detected or forced.
    Text(Box<TextReader<R>>),
    /// Vector BLF.
    Blf(Box<BlfReader<R>>),
    /// pcap and pcapng.
    Pcap(Box<PcapReader<R>>),
    /// ASAM MDF 4.
    Mf4(Box<Mf4Reader<R>>),
}

impl<R: Read> AnyReader<R> {
    /// The reader of binary `format` on `input`, past its header. An error
    /// means the input is not a readable file of that format.
    pub fn binary(format: Format, input: R) -> io::Result<AnyReader<R>> {
        Ok(match format {
            Format::Blf => AnyReader::Blf(Box::new(BlfReader::new(input)?)),
            Format::Pcap | Format::Pcapng => AnyReader::Pcap(Box::new(PcapReader::new(input)?)),
            Format::Mf4 => AnyReader::Mf4(Box::new(Mf4Reader::new(input)?)),
            Format::CandumpLog
            | Format::CandumpScreen
            | Format::Asc
            | Format::Trc
            | Format::Busmaster
            | Format::Ixxat => {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!("{format} is a text format, read line by line"),
                ));
            }
        })
    }
}

/// A read loop written once over [`FrameSource`], to run on the reader an
/// [`AnyReader`] holds ([`AnyReader::visit`]).
pub trait Visit {
    /// What the loop returns.
    type Output;
    /// Runs the loop on `source`.
    fn visit<S: FrameSource>(self, source: &mut S) -> Self::Output;
}

/// Calls `$method` on whichever reader `$self` holds.
macro_rules! each_reader {
    ($self:expr, $r:ident => $call:expr) => {
        match $self {
            AnyReader::Text($r) => $call,
            AnyReader::Blf($r) => $call,
            AnyReader::Pcap($r) => $call,
            AnyReader::Mf4($r) => $call,
        }
    };
}

impl<R: Read> AnyReader<R> {
    /// Runs `v` on the reader this holds, compiled for that reader: the
    /// format is matched once per input, not once per record, so a hot
    /// loop calls its reader directly (MF4 records cost about 75 ns each,
    /// and a match and a copy more per record showed in the bench).
    pub fn visit<V: Visit>(&mut self, v: V) -> V::Output {
        each_reader!(self, r => v.visit(&mut **r))
    }
}

impl<R: Read> FrameSource for AnyReader<R> {
    fn format(&self) -> Option<Format> {
        each_reader!(self, r => FrameSource::format(&**r))
    }

    #[inline]
    fn next_item(&mut self, interest: Option<&Interest>) -> io::Result<Option<Next<'_>>> {
        each_reader!(self, r => FrameSource::next_item(&mut **r, interest))
    }

    fn take_warning(&mut self) -> Option<Reason> {
        each_reader!(self, r => FrameSource::take_warning(&mut **r))
    }

    fn take_annotated(&mut self) -> bool {
        each_reader!(self, r => FrameSource::take_annotated(&mut **r))
    }

    fn take_ethercat(&mut self) -> Option<(Box<EthercatPacket>, &[u8])> {
        each_reader!(self, r => FrameSource::take_ethercat(&mut **r))
    }

    fn ethercat_counts(&self) -> Option<EthercatCounts> {
        each_reader!(self, r => FrameSource::ethercat_counts(&**r))
    }

    fn bit_rate(&self) -> Option<u32> {
        each_reader!(self, r => FrameSource::bit_rate(&**r))
    }
}
