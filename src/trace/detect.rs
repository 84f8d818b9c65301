//! Format detection from content, never from the file name.
//!
//! Until a format is known every line goes to every parser (so ASC header
//! lines still set the base and timestamp mode); the first line that one of
//! them reads as a frame fixes the format for the rest of the input. Lines
//! before that are skipped when some format knows them as non-frame lines
//! and malformed when none does.

use super::{Format, Interest, LineParser, Parsed};

pub struct Detector {
    state: State,
}

enum State {
    Locked(Box<dyn LineParser>),
    Undecided(Vec<Box<dyn LineParser>>),
}

impl Detector {
    /// Detects the format from the lines as they come.
    pub fn auto() -> Detector {
        Detector {
            state: State::Undecided(Format::ALL.iter().map(|f| f.parser()).collect()),
        }
    }

    /// Reads every line as `format` (`--input-format`).
    pub fn forced(format: Format) -> Detector {
        Detector {
            state: State::Locked(format.parser()),
        }
    }

    /// The format, once known.
    pub fn format(&self) -> Option<Format> {
        match &self.state {
            State::Locked(p) => Some(p.format()),
            State::Undecided(_) => None,
        }
    }

    pub fn parse<'a>(&mut self, line: &'a [u8], interest: &Interest) -> Parsed<'a> {
        let parsers = match &mut self.state {
            State::Locked(p) => return p.parse(line, interest),
            State::Undecided(parsers) => parsers,
        };
        let mut skipped = false;
        let mut found = None;
        for (i, parser) in parsers.iter_mut().enumerate() {
            match parser.parse(line, interest) {
                Parsed::Frame(frame) => {
                    found = Some((i, frame));
                    break;
                }
                Parsed::Skipped => skipped = true,
                Parsed::Malformed(_) => {}
            }
        }
        if let Some((i, frame)) = found {
            let parser = parsers.swap_remove(i);
            self.state = State::Locked(parser);
            return Parsed::Frame(frame);
        }
        if skipped {
            Parsed::Skipped
        } else {
            Parsed::Malformed(
                "not a line of any format read (candump log, candump screen, Vector ASC)".into(),
            )
        }
    }
}
