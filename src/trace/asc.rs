//! Vector ASC reader (placeholder until implemented).
use super::{Format, Interest, LineParser, Parsed};

#[derive(Default)]
pub struct AscParser;

impl AscParser {
    pub fn new() -> Self {
        AscParser
    }
}

impl LineParser for AscParser {
    fn format(&self) -> Format {
        Format::Asc
    }
    fn parse<'a>(&mut self, _line: &'a [u8], _interest: &Interest) -> Parsed<'a> {
        Parsed::Malformed("ASC reader not implemented".into())
    }
}
