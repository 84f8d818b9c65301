//! candump screen reader (placeholder until implemented).
use super::{Format, Interest, LineParser, Parsed};

#[derive(Default)]
pub struct CandumpScreenParser;

impl CandumpScreenParser {
    pub fn new() -> Self {
        CandumpScreenParser
    }
}

impl LineParser for CandumpScreenParser {
    fn format(&self) -> Format {
        Format::CandumpScreen
    }
    fn parse<'a>(&mut self, _line: &'a [u8], _interest: &Interest) -> Parsed<'a> {
        Parsed::Malformed("candump screen reader not implemented".into())
    }
}
