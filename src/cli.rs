//! Command-line definitions. Flag names, JSON keys and exit codes are the
//! contract users script against: change them only with a major version.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::analyze::EmcyId;
use crate::report::table::ColorChoice;
use crate::trace::Format;

const EXAMPLES_AND_EXIT_CODES: &str = "\
Examples:
  emcy-decode trace.log                         readable report: events, node timelines, counts
  emcy-decode --format ndjson trace.asc | jq 'select(.node==5)'
  candump -L can0 | emcy-decode -               decode live from a bus
  emcy-decode --fail-on active traces/*.log     fail a CI job when a node ends in error
  emcy-decode explain 4310                      what does code 0x4310 mean?
  emcy-decode explain --data \"10 43 09 01 00 00 00 00\"

Formats read (detected from content, .gz decompressed): candump log (-l/-L),
candump screen output (with or without -t/-x/-a), Vector ASC.

Exit status:
  0  success (also when the reader of stdout goes away, e.g. `| head -1`)
  1  the --fail-on condition was met
  2  usage error, unreadable input, unknown format, corrupt gzip,
     or malformed lines with --strict";

#[derive(Parser, Debug)]
#[command(
    name = "emcy-decode",
    version,
    about = "Decode CANopen emergency (EMCY) frames in CAN traces and rebuild each node's error timeline",
    after_help = EXAMPLES_AND_EXIT_CODES,
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,

    #[command(flatten)]
    pub decode: DecodeArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Explain an error code, or decode one raw 8-byte EMCY payload
    Explain(ExplainArgs),
    /// Record what traces contain (errors per node, line counts) for `check`
    Baseline(crate::baseline::BaselineArgs),
    /// Compare traces with a baseline: exit 1 on a regression
    Check(crate::baseline::CheckArgs),
}

#[derive(Args, Debug)]
pub struct DecodeArgs {
    /// Trace files to read; `-` or none reads stdin
    #[arg(value_name = "FILE")]
    pub files: Vec<PathBuf>,

    /// Output format
    #[arg(long, short = 'f', value_enum, default_value_t = OutputFormat::Table)]
    pub format: OutputFormat,

    /// Read inputs as this format instead of detecting it
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub input_format: Option<InputFormat>,

    /// Report only these nodes (repeatable or comma-separated; decimal or 0x hex)
    #[arg(long, value_delimiter = ',', value_parser = parse_node, value_name = "N")]
    pub node: Vec<u8>,

    /// Report only this channel (candump interface or ASC channel number; repeatable)
    #[arg(long, value_name = "NAME")]
    pub channel: Vec<String>,

    /// A node's EMCY id moved by object 0x1014: COBID=NODE, hex COB-ID (29-bit when over
    /// 0x7FF, 8 digits or with an x suffix), e.g. 0x1A5=5 (repeatable)
    #[arg(long, value_parser = parse_emcy_id, value_name = "COBID=NODE")]
    pub emcy_id: Vec<EmcyId>,

    /// Exit 1 when any error EMCY was seen (any) or a node ends with an active error (active)
    #[arg(long, value_enum, default_value_t = FailOn::Never, value_name = "WHEN")]
    pub fail_on: FailOn,

    /// Exit 2 when any line is malformed
    #[arg(long)]
    pub strict: bool,

    /// Print at most N diagnostics per input (counts stay exact)
    #[arg(long, default_value_t = 20, value_name = "N")]
    pub max_diagnostics: usize,

    /// Threads for reading large inputs (0 = automatic: all cores for files
    /// over 16 MiB and gzip input, one for small files and live streams)
    #[arg(long, short = 'j', default_value_t = 0, value_name = "N")]
    pub threads: usize,

    /// When to colour the table
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto, value_name = "WHEN")]
    pub color: ColorChoice,
}

#[derive(Args, Debug)]
pub struct ExplainArgs {
    /// Error code in hex, with or without 0x (e.g. 4310, 0x8130)
    #[arg(required_unless_present = "data", conflicts_with = "data")]
    pub code: Option<String>,

    /// A raw EMCY payload in hex: "10 43 09 01 00 00 00 00", "1043090100000000" or "10:43:09"
    #[arg(long, value_name = "HEX")]
    pub data: Option<String>,

    /// Output format
    #[arg(long, short = 'f', value_enum, default_value_t = ExplainFormat::Text)]
    pub format: ExplainFormat,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OutputFormat {
    /// Human-readable tables
    Table,
    /// One JSON document
    Json,
    /// One JSON object per line: events, then nodes, then inputs
    Ndjson,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExplainFormat {
    Text,
    Json,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum InputFormat {
    /// candump -l / -L log lines: (1469439874.299654) can0 081#1043...
    Candump,
    /// candump default screen output: can0  081   [8]  10 43 ...
    CandumpScreen,
    /// Vector ASC
    Asc,
}

impl From<InputFormat> for Format {
    fn from(f: InputFormat) -> Format {
        match f {
            InputFormat::Candump => Format::CandumpLog,
            InputFormat::CandumpScreen => Format::CandumpScreen,
            InputFormat::Asc => Format::Asc,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FailOn {
    /// Never fail because of what the trace contains
    Never,
    /// Fail when any EMCY with an error code (not a reset) was seen
    Any,
    /// Fail when any node ends the trace with an active error
    Active,
}

/// `0x1A5=5`, `000001A5=5` (29-bit by digit count), `1A5x=5` (29-bit).
pub(crate) fn parse_emcy_id(s: &str) -> Result<EmcyId, String> {
    let err = || format!("'{s}' is not COBID=NODE (e.g. 0x1A5=5 or 18FF0105x=5)");
    let (cob, node) = s.split_once('=').ok_or_else(err)?;
    let node = parse_node(node)?;
    let cob = cob.trim();
    let digits = cob
        .strip_prefix("0x")
        .or_else(|| cob.strip_prefix("0X"))
        .unwrap_or(cob);
    let (digits, x) = match digits.strip_suffix(['x', 'X']) {
        Some(d) => (d, true),
        None => (digits, false),
    };
    let id = u32::from_str_radix(digits, 16).map_err(|_| err())?;
    let extended = x || digits.len() == 8 || id > 0x7FF;
    if id > 0x1FFF_FFFF {
        return Err(format!("'{cob}' is more than 29 bits"));
    }
    Ok(EmcyId { id, extended, node })
}

/// A CANopen node id, 1..=127, decimal or 0x hex.
pub(crate) fn parse_node(s: &str) -> Result<u8, String> {
    let t = s.trim();
    let value = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => t.parse::<u8>(),
    };
    match value {
        Ok(n @ 1..=127) => Ok(n),
        _ => Err(format!("'{s}' is not a node id (1-127, decimal or 0x hex)")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn emcy_ids() {
        let e = |s: &str| parse_emcy_id(s).map(|e| (e.id, e.extended, e.node));
        assert_eq!(e("0x1A5=5"), Ok((0x1A5, false, 5)));
        assert_eq!(e("1a5=0x05"), Ok((0x1A5, false, 5)));
        assert_eq!(e("000001A5=5"), Ok((0x1A5, true, 5)));
        assert_eq!(e("1A5x=5"), Ok((0x1A5, true, 5)));
        assert_eq!(e("18FF0105=7"), Ok((0x18FF_0105, true, 7)));
        assert!(e("0x1A5").is_err());
        assert!(e("0x1A5=0").is_err());
        assert!(e("zz=5").is_err());
        assert!(e("3FFFFFFF=5").is_err());
    }

    #[test]
    fn node_ids() {
        assert_eq!(parse_node("5"), Ok(5));
        assert_eq!(parse_node("0x7F"), Ok(127));
        assert!(parse_node("0").is_err());
        assert!(parse_node("128").is_err());
        assert!(parse_node("x").is_err());
    }
}
