//! The text formats as a [`FrameSource`]: lines cut from blocks, each
//! classified by the [`Detector`] (which detects the format, or reads a
//! forced one).
//!
//! This is the record-by-record way in, for callers that want every line
//! (emcy-decode's `TraceReader`). The analysis reads text block by block
//! instead, through [`LineParser::run`](crate::LineParser::run) and on
//! several threads: its hot loop folds repeated frames and counts unwanted
//! ones without a call per line.

use std::io::{self, Read};

use crate::detect::Detector;
use crate::lines::{self, Block, BlockReader, RawLine, too_long};
use crate::{Format, FrameSource, Interest, Next, Parsed, Reason};

/// Reads a text trace line by line.
pub struct TextReader<R> {
    blocks: BlockReader<R>,
    detector: Detector,
    max_line: usize,
    /// The block being read, and where its next line starts.
    block: Block,
    at: usize,
    /// A block's too-long first line was returned.
    too_long_told: bool,
    /// What lines are parsed for when the caller gives no interest.
    all: Interest,
}

impl<R: Read> TextReader<R> {
    /// Reads `input` in blocks of `block_size` bytes; lines longer than
    /// `max_line` are malformed, never buffered.
    pub fn new(input: R, detector: Detector, block_size: usize, max_line: usize) -> Self {
        TextReader {
            blocks: BlockReader::new(input, block_size, max_line),
            detector,
            max_line,
            block: Block::default(),
            at: 0,
            too_long_told: true,
            all: Interest::all(),
        }
    }

    /// The detector, to set how candump times are read before the first
    /// line.
    pub fn detector_mut(&mut self) -> &mut Detector {
        &mut self.detector
    }

    /// Whether the current block has a line left; reads the next block
    /// when not. `Ok(false)` at the end of the input.
    fn fill(&mut self) -> io::Result<bool> {
        loop {
            if !self.too_long_told || self.at < self.block.text().len() {
                return Ok(true);
            }
            let buf = std::mem::take(&mut self.block.bytes);
            match self.blocks.next_block(buf)? {
                Some(block) => {
                    self.too_long_told = block.too_long_before.is_none();
                    self.block = block;
                    self.at = 0;
                }
                None => return Ok(false),
            }
        }
    }
}

impl<R: Read> FrameSource for TextReader<R> {
    fn format(&self) -> Option<Format> {
        self.detector.format()
    }

    fn bit_rate(&self) -> Option<u32> {
        self.detector.bit_rate()
    }

    fn next_item(&mut self, interest: Option<&Interest>) -> io::Result<Option<Next<'_>>> {
        if !self.fill()? {
            return Ok(None);
        }
        if !self.too_long_told {
            self.too_long_told = true;
            let n = self.block.too_long_before.unwrap_or(0);
            return Ok(Some(Next::Record(Parsed::Malformed(too_long(
                n,
                self.max_line,
            )))));
        }
        let Some((raw, next)) = lines::line_at(self.block.text(), self.at, self.max_line) else {
            return Ok(None);
        };
        self.at = next;
        let interest = interest.unwrap_or(&self.all);
        Ok(Some(Next::Record(match raw {
            RawLine::TooLong(n) => Parsed::Malformed(too_long(n, self.max_line)),
            RawLine::Text(text) => self.detector.parse(text, interest),
        })))
    }

    fn take_warning(&mut self) -> Option<Reason> {
        self.detector.take_warning()
    }

    fn take_annotated(&mut self) -> bool {
        self.detector.take_annotated()
    }
}
