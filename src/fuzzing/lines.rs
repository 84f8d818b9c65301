//! The per-line parsers as the analysis drives them, for the `parse`
//! benchmark (`benches/parse.rs`) and for tests of the id-first shortcut
//! (`scan`) that the public reader never takes. Thin wrappers: a parser and
//! the ids it decodes in full. Not API.

use std::ops::RangeInclusive;

use crate::trace::detect;
use crate::trace::reader::CanFrame;
use crate::trace::{AnyParser, Format, Interest, LineParser, Parsed, Scan, Timestamp};

/// Which identifiers a parser decodes in full (time and data); for the
/// others it only checks the line.
#[derive(Clone, Copy, Debug)]
pub enum Ids<'a> {
    /// Every standard and extended id.
    All,
    /// No id: every valid frame is only counted.
    None,
    /// These standard ids (no extended one).
    Standard(&'a [RangeInclusive<u32>]),
}

impl Ids<'_> {
    fn interest(self) -> Interest {
        match self {
            Ids::All => Interest::all(),
            Ids::None => Interest::none(),
            Ids::Standard(ranges) => {
                let mut interest = Interest::none();
                for r in ranges {
                    interest.add_standard_range(r.clone());
                }
                interest
            }
        }
    }
}

/// One text format's line parser (what [`Detector`] holds per format).
pub struct Parser {
    parser: AnyParser,
    interest: Interest,
}

impl Parser {
    /// The parser of `format`, decoding `ids`.
    pub fn new(format: Format, ids: Ids<'_>) -> Parser {
        Parser {
            parser: format.parser(),
            interest: ids.interest(),
        }
    }

    /// Classifies one line (without its newline).
    #[inline]
    pub fn parse<'a>(&mut self, line: &'a [u8]) -> Parsed<'a> {
        self.parser.parse(line, &self.interest)
    }
}

/// The format detector the analysis reads a trace with: every parser until
/// a line is a frame, then that format's (`--input-format`: one format).
pub struct Detector {
    detector: detect::Detector,
    interest: Interest,
}

/// What [`Detector::scan`] made of a line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Scanned {
    /// A valid frame on an id not wanted: only counted.
    Plain,
    /// A valid frame on a wanted id whose data the content filter rejects.
    Timed(Timestamp),
    /// A valid frame on a wanted id, as `parse` reads it (`line` is 0).
    Frame(CanFrame),
    /// Not the common shape of a frame line: `parse` must read it.
    Parse,
}

impl Detector {
    /// Detects the format from the lines; decodes `ids`.
    pub fn auto(ids: Ids<'_>) -> Detector {
        Detector {
            detector: detect::Detector::auto(),
            interest: ids.interest(),
        }
    }

    /// Reads every line as `format`; decodes `ids`.
    pub fn forced(format: Format, ids: Ids<'_>) -> Detector {
        Detector {
            detector: detect::Detector::forced(format),
            interest: ids.interest(),
        }
    }

    /// A copy in the current state (as for another thread), decoding `ids`.
    pub fn fork(&self, ids: Ids<'_>) -> Detector {
        Detector {
            detector: self.detector.fork(),
            interest: ids.interest(),
        }
    }

    /// The format, once known.
    pub fn format(&self) -> Option<Format> {
        self.detector.format()
    }

    /// Classifies one line (without its newline), detecting the format.
    #[inline]
    pub fn parse<'a>(&mut self, line: &'a [u8]) -> Parsed<'a> {
        self.detector.parse(line, &self.interest)
    }

    /// The id-first shortcut the analysis takes once the format is known.
    pub fn scan(&mut self, line: &[u8]) -> Scanned {
        match self.detector.scan(line, &self.interest) {
            Scan::Plain(_) => Scanned::Plain,
            Scan::Timed(t, _) => Scanned::Timed(t),
            Scan::Frame(f) => Scanned::Frame(CanFrame::of(0, &f)),
            Scan::Parse => Scanned::Parse,
        }
    }
}
