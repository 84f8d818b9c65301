//! Command-line definitions. Flag names, JSON keys and exit codes are the
//! contract users script against: change them only with a major version.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::analyze::EmcyId;
use crate::report::table::ColorChoice;
use crate::report::timefmt::TimeStyle;
use crate::trace::Format;

const EXAMPLES_AND_EXIT_CODES: &str = "\
Examples:
  emcy-decode trace.log                         readable report: events, node timelines, counts
  emcy-decode --format ndjson trace.asc | jq 'select(.node==5)'
  candump -L can0 | emcy-decode -               decode live from a bus
  emcy-decode --fail-on active traces/*.log     fail a CI job when a node ends in error
  emcy-decode explain 4310                      what does code 0x4310 mean?
  emcy-decode check --baseline baseline.json traces/*.log   fail CI on a new error
  emcy-decode explain --data \"10 43 09 01 00 00 00 00\"

Formats read (detected from content, .gz decompressed): candump log (-l/-L),
candump screen output (with or without -t/-x/-a), Vector ASC, PEAK TRC
(1.0-2.1), Vector BLF.

Exit status:
  0  success (also when the reader of stdout goes away, e.g. `| head -1`)
  1  the --fail-on condition was met (check: a regression against the baseline)
  2  usage error, unreadable input, unknown format, corrupt gzip,
     or malformed lines with --strict
  130  stopped by Ctrl-C (what was read is still reported)";

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
    /// Print a shell completion script (bash, zsh, fish, powershell, elvish)
    Completions {
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the man page (roff) to stdout
    Man,
    /// List the built-in vendor profiles, one line each
    Profiles,
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

    /// Vendor profile for every node (NAME) or one node (NODE=NAME); repeatable, a node's
    /// own wins. Without one, the trace's SDO identity answers choose, else cia402.
    /// `emcy-decode profiles` lists them
    #[arg(long, value_parser = parse_profile_arg, value_name = "[NODE=]NAME")]
    pub profile: Vec<ProfileArg>,

    /// A user profile (TOML, see README): used for every node not chosen by --profile,
    /// or only where --profile names it (repeatable)
    #[arg(long, value_name = "FILE.toml")]
    pub profile_file: Vec<PathBuf>,

    /// Exit 1 when a condition is met (repeatable or comma-separated; any met fails):
    /// `any` error EMCY, a node ends with an `active` error, any protocol `warning`,
    /// `code=0x4310,0x8611` raised, `category<=N` (profiles with categories), `never`
    #[arg(long, value_parser = parse_fail_on, value_name = "WHEN")]
    pub fail_on: Vec<FailOn>,

    /// What to print: every event and the timeline (full), or one line per node
    /// and per bus (summary)
    #[arg(long, value_enum, default_value_t = View::Full, value_name = "VIEW")]
    pub view: View,

    /// Exit 2 when any line is malformed
    #[arg(long)]
    pub strict: bool,

    /// Print at most N diagnostics per input (counts stay exact)
    #[arg(long, default_value_t = 20, value_name = "N")]
    pub max_diagnostics: usize,

    /// Threads for reading large inputs, and for writing the errors listed
    /// in ndjson node objects (0 = automatic: all cores for files over 16 MiB
    /// and gzip input, one for small files and live streams; all cores for
    /// the node objects)
    #[arg(long, short = 'j', default_value_t = 0, value_name = "N")]
    pub threads: usize,

    /// When to colour the table
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto, value_name = "WHEN")]
    pub color: ColorChoice,

    /// How the table shows times
    #[arg(long, value_enum, default_value_t = TimeStyle::Auto, value_name = "STYLE")]
    pub time: TimeStyle,

    /// Keep reading FILE as it grows (like tail -f); Ctrl-C prints the summary
    #[arg(long, requires = "files")]
    pub follow: bool,

    /// Read directories given as FILE recursively (files in name order)
    #[arg(long, short = 'r')]
    pub recursive: bool,

    /// No progress bar and no per-line diagnostics on stderr (counts stay exact)
    #[arg(long, short = 'q')]
    pub quiet: bool,
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

    /// Read the code and payload with this profile (default cia402)
    #[arg(long, value_name = "NAME")]
    pub profile: Option<String>,

    /// A user profile (TOML); --profile defaults to its name
    #[arg(long, value_name = "FILE.toml")]
    pub profile_file: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OutputFormat {
    /// Human-readable tables
    Table,
    /// One JSON document
    Json,
    /// One JSON object per line: events, then nodes, then inputs
    Ndjson,
    /// The error timeline as an SVG image: a lane per node, errors as bars
    Svg,
    /// One self-contained HTML page: the timeline chart and the events table
    Html,
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
    /// PEAK TRC, versions 1.0 to 2.1
    Trc,
    /// Vector BLF (binary)
    Blf,
}

impl From<InputFormat> for Format {
    fn from(f: InputFormat) -> Format {
        match f {
            InputFormat::Candump => Format::CandumpLog,
            InputFormat::CandumpScreen => Format::CandumpScreen,
            InputFormat::Asc => Format::Asc,
            InputFormat::Trc => Format::Trc,
            InputFormat::Blf => Format::Blf,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum View {
    /// Events as decoded, node states, the error timeline, input counts
    Full,
    /// One line per node (state, errors seen, time in error, longest error,
    /// first/last EMCY) and a bus line per input
    Summary,
}

/// The `--fail-on` conditions of one or more flags, combined: any met fails.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FailOn {
    /// Any EMCY with an error code (not a reset).
    pub any: bool,
    /// A node ends the trace with an active error.
    pub active: bool,
    /// Any protocol warning on a reported EMCY.
    pub warning: bool,
    /// Any of these codes raised.
    pub codes: Vec<u16>,
    /// An error whose profile category is at most this (1 = most severe).
    pub category_at_most: Option<u8>,
}

impl FailOn {
    /// All flags given, merged.
    pub fn combine(flags: &[FailOn]) -> FailOn {
        let mut all = FailOn::default();
        for f in flags {
            all.any |= f.any;
            all.active |= f.active;
            all.warning |= f.warning;
            all.codes.extend(&f.codes);
            all.category_at_most = match (all.category_at_most, f.category_at_most) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
        }
        all.codes.sort_unstable();
        all.codes.dedup();
        all
    }

    pub fn is_never(&self) -> bool {
        *self == FailOn::default()
    }
}

/// `any`, `active`, `warning`, `never`, `code=0x4310,0x8611` (the codes run
/// to the next word), `category<=2`; comma-separated.
fn parse_fail_on(s: &str) -> Result<FailOn, String> {
    let mut f = FailOn::default();
    let mut in_codes = false;
    for item in s.split(',').map(str::trim) {
        let lower = item.to_ascii_lowercase();
        if let Some(code) = lower.strip_prefix("code=") {
            f.codes.push(parse_code(code)?);
            in_codes = true;
            continue;
        }
        if let Some(n) = lower.strip_prefix("category<=") {
            let n: u8 = n
                .trim()
                .parse()
                .map_err(|_| format!("'{item}': category<=N needs a number 0-255"))?;
            f.category_at_most = Some(n);
            in_codes = false;
            continue;
        }
        match lower.as_str() {
            // The default, kept so `--fail-on never` in scripts stays valid.
            "never" => {}
            "any" => f.any = true,
            "active" => f.active = true,
            "warning" | "warnings" => f.warning = true,
            _ if in_codes => {
                f.codes.push(parse_code(item)?);
                continue;
            }
            _ => {
                return Err(format!(
                    "'{item}' is not a condition: never, any, active, warning, \
                     code=CODE[,CODE...], category<=N"
                ));
            }
        }
        in_codes = false;
    }
    Ok(f)
}

/// An error code in hex, with or without 0x.
fn parse_code(s: &str) -> Result<u16, String> {
    crate::trace::hex::parse_code(s)
        .ok_or_else(|| format!("'{s}' is not an error code (1-4 hex digits)"))
}

/// `--profile NAME` or `--profile NODE=NAME`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProfileArg {
    pub node: Option<u8>,
    pub name: String,
}

pub(crate) fn parse_profile_arg(s: &str) -> Result<ProfileArg, String> {
    let (node, name) = match s.split_once('=') {
        Some((node, name)) => (Some(parse_node(node)?), name.trim()),
        None => (None, s.trim()),
    };
    if name.is_empty() {
        return Err(format!("'{s}' names no profile"));
    }
    Ok(ProfileArg {
        node,
        name: name.to_string(),
    })
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
    fn fail_on_conditions() {
        let f = |s: &str| parse_fail_on(s);
        assert_eq!(f("never"), Ok(FailOn::default()));
        assert_eq!(
            f("any"),
            Ok(FailOn {
                any: true,
                ..FailOn::default()
            })
        );
        assert_eq!(
            f("active,warning"),
            Ok(FailOn {
                active: true,
                warning: true,
                ..FailOn::default()
            })
        );
        // Codes run to the next condition word.
        assert_eq!(
            f("code=0x4310,8611,active"),
            Ok(FailOn {
                active: true,
                codes: vec![0x4310, 0x8611],
                ..FailOn::default()
            })
        );
        assert_eq!(
            f("category<=2"),
            Ok(FailOn {
                category_at_most: Some(2),
                ..FailOn::default()
            })
        );
        assert!(
            f("8611").is_err(),
            "a code outside code= is not a condition"
        );
        assert!(f("code=0x12345").is_err());
        assert!(f("code=").is_err());
        assert!(f("category<=x").is_err());
        assert!(f("sometimes").is_err());
    }

    #[test]
    fn fail_on_flags_combine() {
        let a = parse_fail_on("code=4310,any").unwrap();
        let b = parse_fail_on("code=0x2310,0x4310,category<=1").unwrap();
        let c = parse_fail_on("category<=3").unwrap();
        let all = FailOn::combine(&[a, b, c]);
        assert!(all.any);
        assert!(!all.active);
        assert_eq!(all.codes, [0x2310, 0x4310]);
        assert_eq!(all.category_at_most, Some(3), "the widest bound wins");
        assert!(FailOn::combine(&[]).is_never());
    }

    #[test]
    fn profile_args() {
        let p = |s: &str| parse_profile_arg(s).map(|a| (a.node, a.name));
        assert_eq!(p("kollmorgen"), Ok((None, "kollmorgen".into())));
        assert_eq!(p("5=festo-cmmp"), Ok((Some(5), "festo-cmmp".into())));
        assert_eq!(p("0x14=canopennode"), Ok((Some(20), "canopennode".into())));
        assert!(p("0=cia402").is_err());
        assert!(p("5=").is_err());
        assert!(p("").is_err());
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
