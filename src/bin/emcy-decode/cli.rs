//! Command-line definitions. Flag names, JSON keys and exit codes are the
//! contract users script against: change them only with a major version.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::builder::{PossibleValue, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};

use emcy_decode::analyze::fail_on::FailOn;
use emcy_decode::analyze::{EmcyId, Options};
use emcy_decode::baseline::ReadOptions;
use emcy_decode::canopen::NodeId;
use emcy_decode::canopen::profile::Profile;
use emcy_decode::canopen::profile_choice::{self, ProfileRequest};
use emcy_decode::report::timefmt::TimeStyle;
use emcy_decode::trace::deltas::TimeMode;
use emcy_decode::trace::{Format, Span, Timestamp, hex};

/// What `-h` ends with: the exit codes in one line, and where the rest is.
const SHORT_AFTER_HELP: &str = "\
Exit status: 0 success, 1 the --fail-on condition was met, 2 error; 129/130/143 signals.
`--help` shows every option in full, the formats read and examples.";

const EXAMPLES_AND_EXIT_CODES: &str = "\
Examples:
  emcy-decode trace.log                         readable report: events, node timelines, counts
  emcy-decode --format ndjson trace.asc | jq 'select(.node==5)'
  candump -L can0 | emcy-decode -               decode live from a bus
  emcy-decode --fail-on active traces/*.log     fail a CI job when a node ends in error
  emcy-decode explain 4310                      what does code 0x4310 mean?
  emcy-decode check --baseline baseline.json traces/*.log   fail CI on a new error
  emcy-decode diff good.log bad.log             where two runs part at the CANopen level
  emcy-decode explain --data \"10 43 09 01 00 00 00 00\"

Formats read (detected from content, .gz decompressed): candump log (-l/-L),
candump screen output (with or without -t/-x/-a), Vector ASC, PEAK TRC
(1.0-2.1), BUSMASTER log (HEX or DEC, system/absolute/relative times),
IXXAT MiniMon V3 ASCII trace, Vector BLF, pcap and pcapng (SocketCAN, LINUX_SLL, LINUX_SLL2), ASAM MDF 4
bus logging (MF4: CANedge, Vector, python-can).

Exit status:
  0  success (also when the reader of stdout goes away, e.g. `| head -1`)
  1  the --fail-on condition was met (check: a regression against the baseline)
  2  usage error, unreadable input, unknown format, corrupt gzip,
     or malformed lines with --strict
  129  stopped by SIGHUP
  130  stopped by Ctrl-C (SIGINT)
  143  stopped by SIGTERM
       (what was read is still reported; a second signal ends at once, without it)";

/// The variables the program reads, for `--help` and the man page's
/// ENVIRONMENT section: a person whose table looks wrong in one terminal
/// and right in another needs to know that these change it.
pub(super) const ENVIRONMENT: &str =
    "  NO_COLOR  set and not empty: no colour in the table (--color always still colours)
  TERM      dumb: no colour in the table, as for NO_COLOR
  COLUMNS   the table's width at a terminal, before the terminal's own size (--width
            overrides both; in a pipe the table keeps full lines)
  CI        set and not empty: no progress bar
  TZ        the zone of --time local when --tz is not given (else /etc/localtime)";

#[derive(Parser, Debug)]
#[command(
    name = "emcy-decode",
    version,
    about = "Decode CANopen emergency (EMCY) frames in CAN traces and rebuild each node's error timeline",
    after_help = SHORT_AFTER_HELP,
    after_long_help = format!("{EXAMPLES_AND_EXIT_CODES}\n\nEnvironment:\n{ENVIRONMENT}"),
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
    /// Print the man page (roff), a subcommand's page, or write them all with --all DIR
    Man(ManArgs),
    /// List the built-in vendor profiles, one line each; --toml NAME prints one as a file
    Profiles(ProfilesArgs),
    /// Record what traces contain (errors per node, line counts) for `check`
    Baseline(BaselineArgs),
    /// Compare traces with a baseline: exit 1 on a regression
    Check(CheckArgs),
    /// Compare two traces by CANopen meaning: exit 0 same, 1 different, 2 trouble
    #[command(after_help = DIFF_HELP)]
    Diff(DiffArgs),
    /// The configuration a trace wrote into its nodes, per node, as a DCF or JSON
    #[command(after_help = CONFIG_HELP)]
    Config(ConfigArgs),
}

/// Headings of `--help`, grouped as ripgrep groups its options.
const INPUT: &str = "Input options";
const DECODING: &str = "Decoding options";
const OUTPUT: &str = "Output options";
const CI: &str = "CI options";
const PERFORMANCE: &str = "Performance options";

#[derive(Args, Debug)]
pub struct DecodeArgs {
    /// Trace files to read; `-` or none reads stdin
    #[arg(value_name = "FILE")]
    pub files: Vec<PathBuf>,

    /// Read inputs as this format instead of detecting it
    #[arg(long, value_enum, value_name = "FORMAT", help_heading = INPUT)]
    pub input_format: Option<InputFormat>,

    /// What candump times are: as written, or deltas (candump -td)
    ///
    /// What candump times are: as written (absolute, or zero for -tz), or the delta to the
    /// previous frame (delta, candump -td: summed). Without it, deltas are detected from
    /// the first lines, with a note
    #[arg(long, value_enum, value_name = "MODE", help_heading = INPUT)]
    pub timestamps: Option<TimestampsArg>,

    /// Report only these nodes (repeatable or comma-separated)
    ///
    /// Report only these nodes (repeatable or comma-separated; decimal or 0x hex; EtherCAT
    /// slaves by station address)
    #[arg(long, value_delimiter = ',', value_parser = parse_node, value_name = "N", help_heading = DECODING)]
    pub node: Vec<NodeId>,

    /// Report only this channel (repeatable)
    ///
    /// Report only this channel (candump interface or ASC channel number; repeatable)
    #[arg(long, value_name = "NAME", help_heading = DECODING)]
    pub channel: Vec<String>,

    /// A node's EMCY id moved by object 0x1014, e.g. 0x1A5=5 (repeatable)
    ///
    /// A node's EMCY id moved by object 0x1014: COBID=NODE, hex COB-ID (29-bit when over
    /// 0x7FF, 8 digits or with an x suffix), e.g. 0x1A5=5 (repeatable)
    #[arg(long, value_parser = parse_emcy_id, value_name = "COBID=NODE", help_heading = DECODING)]
    pub emcy_id: Vec<EmcyId>,

    /// Heartbeat timeout for every node, in seconds (e.g. 0.5)
    ///
    /// Heartbeat timeout for every node, in seconds (e.g. 0.5): a node silent for longer
    /// has lost its heartbeat. Without it, the consumer (0x1016) or producer (0x1017)
    /// heartbeat time the trace sets by SDO, else 3x the node's typical interval
    #[arg(long, value_parser = parse_seconds, value_name = "SECONDS", help_heading = DECODING)]
    pub heartbeat_timeout: Option<Span>,

    /// An SDO transfer the node does not answer within this many seconds is unanswered [default: 1]
    ///
    /// An SDO transfer whose node gives no answer this many seconds after the client's
    /// frame (or before the client asks something else, or the trace ends) is told with
    /// result `unanswered` (default 1)
    #[arg(long, value_parser = parse_seconds, value_name = "SECONDS", help_heading = DECODING)]
    pub sdo_timeout: Option<Span>,

    /// Fault-like events further apart than this (seconds) start a new incident [default: 2]
    ///
    /// Fault-like events of any node or the bus (an error EMCY, a heartbeat loss, a reboot
    /// nobody commanded, a node leaving operational on its own, a drive fault, error
    /// frames, a bus-off) that follow each other within this many seconds on a channel are
    /// one incident, told with its root cause when its gap has passed (default 2)
    #[arg(long, value_parser = parse_seconds, value_name = "SECONDS", help_heading = DECODING)]
    pub incident_gap: Option<Span>,

    /// Time every frame per channel and id: period, jitter, gaps, missed cycles
    ///
    /// Time every frame per channel and identifier: each id's period (median interval),
    /// jitter, largest gap and missed cycles, in the `channel` objects and the Timing
    /// table. The readers then read every line's time, which the default path spares
    /// (see the manual for the cost). Without it every frame is still counted per
    /// channel and identifier, and SYNC is timed (its gaps are `sync_missed` events)
    #[arg(long, help_heading = DECODING)]
    pub timing: bool,

    /// The bus's bit rate (500k, 1M, 250000): the load in percent; implies --timing
    ///
    /// The bus's bit rate (500k, 1M, 250000, "250 kbit/s"): the load in percent, mean and
    /// busiest second, from each frame's bits and a worst-case stuffing estimate. Implies
    /// --timing. Without it, a trace that records its bit rate (IXXAT) gives the load
    /// with --timing
    #[arg(long, value_parser = parse_bitrate, value_name = "RATE", help_heading = DECODING)]
    pub bitrate: Option<u32>,

    /// Vendor profile for every node (NAME) or one node (NODE=NAME); repeatable
    ///
    /// Vendor profile for every node (NAME) or one node (NODE=NAME); repeatable, a node's
    /// own wins. Without one, the trace's SDO identity answers choose, else cia402.
    /// `emcy-decode profiles` lists them
    #[arg(long, value_parser = ProfileNames(parse_profile_arg), hide_possible_values = true, value_name = "[NODE=]NAME", help_heading = DECODING)]
    pub profile: Vec<ProfileRequest>,

    /// A user profile (TOML, see the manual); repeatable
    ///
    /// A user profile (TOML; `emcy-decode profiles --toml NAME` prints one to start from): used for every node not chosen by --profile,
    /// or only where --profile names it (repeatable)
    #[arg(long, value_name = "FILE.toml", help_heading = DECODING)]
    pub profile_file: Vec<PathBuf>,

    #[command(flatten)]
    pub drive: DriveArgs,

    /// Output format
    #[arg(long, short = 'f', value_enum, default_value_t = OutputFormat::Table, help_heading = OUTPUT)]
    pub format: OutputFormat,

    /// Exit 1 when a condition is met: any, active, warning, lost, fault, bus-off, bus-errors, incident, code=..., category<=N, never
    ///
    /// Exit 1 when a condition is met (repeatable or comma-separated; any met fails):
    /// `any` error EMCY, a node ends with an `active` error, any protocol `warning`,
    /// `code=0x4310,0x8611` raised, `category<=N` (profiles with categories), a node
    /// `lost` its heartbeat, a CiA 402 drive entered `fault`, a controller went
    /// `bus-off`, any error frame (`bus-errors`), an `incident`, `never`
    #[arg(long, value_parser = parse_fail_on, value_name = "WHEN", help_heading = CI)]
    pub fail_on: Vec<FailOn>,

    /// What to print: every event (full) or a line per node (summary)
    ///
    /// What to print: every event and the timeline (full), or one line per node
    /// and per bus (summary)
    #[arg(long, value_enum, default_value_t = View::Full, value_name = "VIEW", help_heading = OUTPUT)]
    pub view: View,

    /// Table rows beyond the default: sdo (every SDO transfer)
    ///
    /// Table rows beyond the default: `sdo`, every SDO transfer (the table shows
    /// unanswered ones always, aborts as `sdo_abort` rows). The JSON formats always
    /// hold every transfer
    #[arg(long, value_enum, value_delimiter = ',', value_name = "WHAT", help_heading = OUTPUT)]
    pub show: Vec<Show>,

    /// Exit 2 when any line is malformed
    #[arg(long, help_heading = CI)]
    pub strict: bool,

    /// Print at most N diagnostics per input (counts stay exact)
    #[arg(long, default_value_t = 20, value_name = "N", help_heading = OUTPUT)]
    pub max_diagnostics: usize,

    /// Threads for reading large inputs (0 = automatic)
    ///
    /// Threads for reading large inputs, and for writing the errors listed
    /// in ndjson node objects (0 = automatic: all cores for files over 16 MiB
    /// and gzip input, one for small files and live streams; all cores for
    /// the node objects). At most 1024; more than 4 per core counts as 4 per
    /// core. With --timing a big input gets one worker more than the cores
    #[arg(long, short = 'j', default_value_t = 0, value_name = "N", value_parser = parse_threads, help_heading = PERFORMANCE)]
    pub threads: usize,

    /// When to colour the table
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto, value_name = "WHEN", help_heading = OUTPUT)]
    pub color: ColorChoice,

    /// How the table shows times
    #[arg(long, value_enum, default_value_t = TimeArg::Auto, value_name = "STYLE", help_heading = OUTPUT)]
    pub time: TimeArg,

    /// Show table times in this IANA time zone, e.g. Europe/Berlin (implies --time local)
    #[arg(long, value_name = "ZONE", help_heading = OUTPUT)]
    pub tz: Option<String>,

    /// Fit the table to N columns (default: the terminal's width at a terminal, full lines in a pipe; 0: full lines)
    ///
    /// Fit the table to N columns: narrower columns give way first (register bit names,
    /// manufacturer bytes, the date, the transition), then the description is cut and details
    /// wrap. Default: at a terminal, `COLUMNS` if set, else the terminal's width; in a pipe, full
    /// lines. 0: full lines. Below 40, 40
    #[arg(long, value_name = "N", help_heading = OUTPUT)]
    pub width: Option<usize>,

    /// Keep reading FILE as it grows (like tail -f); Ctrl-C prints the summary
    #[arg(long, requires = "files", help_heading = INPUT)]
    pub follow: bool,

    /// Read directories given as FILE recursively (files in name order)
    ///
    /// Read directories given as FILE recursively, their files in name order. Files
    /// with no known format in their first lines (scripts, profiles, notes) are skipped,
    /// with one note per directory
    #[arg(long, short = 'r', help_heading = INPUT)]
    pub recursive: bool,

    /// Under -r, read only files matching GLOB; !GLOB excludes (repeatable)
    ///
    /// Under -r, read only the files whose path below the directory matches GLOB
    /// (`*.log`, `bench3/**/*.asc`; `*` also crosses `/`); a GLOB starting with `!`
    /// excludes. Repeatable: any match selects, any `!` match excludes
    #[arg(long, value_name = "GLOB", requires = "recursive", help_heading = INPUT)]
    pub glob: Vec<String>,

    /// Under -r, follow symbolic links (not followed by default: each is named in a note)
    ///
    /// Under -r, follow symbolic links to files and directories. Without it they are
    /// not read, and one note per directory names them. A link back to a directory
    /// above it (a loop) is named in a note and not followed again; a file that links
    /// reach twice is read once
    #[arg(long, short = 'L', requires = "recursive", help_heading = INPUT)]
    pub follow_links: bool,

    /// No progress bar and no per-line diagnostics on stderr (counts stay exact)
    #[arg(long, short = 'q', help_heading = OUTPUT)]
    pub quiet: bool,

    /// Say on stderr how each input was read (threads, blocks read twice)
    ///
    /// After each input, a note on stderr: how many worker threads parsed it in
    /// how many blocks, and how many of them the thread that keeps the
    /// timelines had to read again because the decoded ids widened after a
    /// worker had parsed them (a PDO mapping or device type learnt from SDO);
    /// and whether that happened so often that the rest was read on one
    /// thread (docs/performance.md)
    #[arg(long, short = 'v', conflicts_with = "quiet", help_heading = OUTPUT)]
    pub verbose: bool,
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
    #[arg(long, value_parser = ProfileNames(clap::builder::NonEmptyStringValueParser::new()), hide_possible_values = true, value_name = "NAME")]
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
    /// One CSV row per event (--view summary: per node) under a header row
    Csv,
    /// The error timeline as an SVG image: a lane per node, errors as bars
    Svg,
    /// One self-contained HTML page: the timeline chart and the events table
    Html,
}

#[derive(Args, Debug)]
pub struct ProfilesArgs {
    /// Print this built-in profile as the TOML file it is made from: a starting point for a
    /// user profile (--profile-file) of a drive the built-ins do not know
    #[arg(long, value_name = "NAME")]
    pub toml: Option<String>,
}

#[derive(Args, Debug)]
pub struct ManArgs {
    /// The subcommand whose page to print (e.g. check); none prints the main page
    #[arg(value_name = "COMMAND", conflicts_with = "all")]
    pub command: Option<String>,

    /// Write every page (emcy-decode.1, emcy-decode-COMMAND.1) into DIR
    #[arg(long, value_name = "DIR")]
    pub all: Option<std::path::PathBuf>,
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
    /// BUSMASTER log: ***BUSMASTER Ver ...***, 14:19:11:4184 Tx 1 0x099 s 8 ...
    Busmaster,
    /// IXXAT MiniMon V3 ASCII trace: "00:02:20.66";"83";"Std";"";"00 01 "
    Ixxat,
    /// Vector BLF (binary)
    Blf,
    /// pcap or pcapng capture (binary; SocketCAN, LINUX_SLL, LINUX_SLL2)
    #[value(alias = "pcapng")]
    Pcap,
    /// ASAM MDF 4 bus logging (binary; CANedge, Vector, python-can)
    Mf4,
}

impl From<InputFormat> for Format {
    fn from(f: InputFormat) -> Format {
        match f {
            InputFormat::Candump => Format::CandumpLog,
            InputFormat::CandumpScreen => Format::CandumpScreen,
            InputFormat::Asc => Format::Asc,
            InputFormat::Trc => Format::Trc,
            InputFormat::Busmaster => Format::Busmaster,
            InputFormat::Ixxat => Format::Ixxat,
            InputFormat::Blf => Format::Blf,
            InputFormat::Pcap => Format::Pcap,
            InputFormat::Mf4 => Format::Mf4,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TimestampsArg {
    /// As written: Unix time (candump -ta, the default), or each format's own
    Absolute,
    /// Each time is the delta to the previous frame (candump -td): summed
    Delta,
    /// Seconds since the first frame (candump -tz): as written
    Zero,
}

impl From<TimestampsArg> for TimeMode {
    fn from(t: TimestampsArg) -> TimeMode {
        match t {
            TimestampsArg::Absolute => TimeMode::Absolute,
            TimestampsArg::Delta => TimeMode::Delta,
            TimestampsArg::Zero => TimeMode::Zero,
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

/// `--show`: rows the table leaves out by default.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Show {
    /// Every SDO transfer
    Sdo,
}

/// `--color`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColorChoice {
    Auto,
    Always,
    Never,
}

/// `--time`: how the table shows times.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum TimeArg {
    /// ISO-8601 UTC for Unix times (after 2001-09-09), else seconds as written
    #[default]
    Auto,
    /// Seconds exactly as the trace wrote them
    Absolute,
    /// Seconds since the input's first reported event
    Relative,
    /// ISO-8601 UTC, every time taken as Unix time
    Iso,
    /// ISO-8601 in the local time zone (TZ, else /etc/localtime; --tz names
    /// another), with its offset, daylight saving time followed
    Local,
}

impl DecodeArgs {
    /// `--time` and `--tz` as the table's time style: `--tz` alone means
    /// local times in that zone. An unknown zone is a usage error.
    pub(super) fn time_style(&self) -> Result<TimeStyle> {
        let zone = match (&self.tz, self.time) {
            (Some(name), TimeArg::Auto | TimeArg::Local) => {
                jiff::tz::TimeZone::get(name).map_err(|e| anyhow::anyhow!("--tz {name}: {e}"))?
            }
            (Some(_), _) => bail!(
                "--tz applies to --time local (or auto), not --time {}",
                format!("{:?}", self.time).to_lowercase()
            ),
            // The TZ variable or /etc/localtime, read once, before any
            // thread starts; jiff falls back to UTC where neither says.
            (None, TimeArg::Local) => jiff::tz::TimeZone::system(),
            (None, TimeArg::Auto) => return Ok(TimeStyle::Auto),
            (None, TimeArg::Absolute) => return Ok(TimeStyle::Absolute),
            (None, TimeArg::Relative) => return Ok(TimeStyle::Relative),
            (None, TimeArg::Iso) => return Ok(TimeStyle::Iso),
        };
        // One zone per run: leaked, so the style stays `Copy`.
        Ok(TimeStyle::Local(Box::leak(Box::new(zone))))
    }
}

/// CiA 402 drive decoding: where PDO mappings come from besides
/// the trace's own SDO writes. The same for decoding, `baseline` and
/// `check`.
#[derive(Args, Debug, Default)]
pub struct DriveArgs {
    /// PDO mapping for CiA 402 decoding: COBID=OBJECT[:BITS],... e.g. 0x181=0x6041,0x603F
    ///
    /// A PDO mapping for CiA 402 decoding, for a trace that does not configure its
    /// PDOs: COBID=OBJECT[:BITS], further objects of the same PDO after commas
    /// (0x181=0x6041,0x6061:8); OBJECT is a hex index (.SUB optional), BITS defaults
    /// to 16 for 0x6040/0x6041/0x603F. The COB-ID must be a predefined PDO id
    /// (0x181-0x57F), which names its node. Repeatable; the trace's own SDO writes
    /// and a --dcf win over it
    #[arg(long, value_parser = parse_pdo, value_name = "COBID=OBJECT[:BITS],...", help_heading = DECODING)]
    pub pdo: Vec<PdoSpec>,

    /// A node's DCF or EDS file: its PDO mappings, device type and identity, NODE=FILE (repeatable)
    ///
    /// A node's DCF or EDS file, NODE=FILE (repeatable): the PDO mappings it declares
    /// decode the node's statusword and controlword (the trace's own SDO writes win),
    /// its vendor id and device type choose its profile as uploads of 0x1018 and
    /// 0x1000 do, and a device type other than 402 keeps --assume-cia402-pdo off it
    #[arg(long, value_parser = parse_dcf, value_name = "NODE=FILE", help_heading = DECODING)]
    pub dcf: Vec<(NodeId, PathBuf)>,

    /// Assume the CiA 402 predefined PDO mapping (TPDO1 statusword, RPDO1 controlword)
    ///
    /// Assume the CiA 402 predefined PDO mapping where nothing else maps a PDO: TPDO1
    /// (0x180 + node) starts with the statusword, RPDO1 (0x200 + node) with the
    /// controlword. Reported with source `assumed`. Not for a node whose device type
    /// (0x1000, read in the trace or given by its DCF) says it is no drive
    #[arg(long, help_heading = DECODING)]
    pub assume_cia402_pdo: bool,
}

/// A `--pdo` flag: its text (as a baseline records it) and its mappings.
#[derive(Clone, Debug)]
pub struct PdoSpec {
    pub text: String,
    pub mappings: Vec<emcy_decode::canopen::pdo::Mapping>,
}

fn parse_pdo(s: &str) -> Result<PdoSpec, String> {
    let mappings = emcy_decode::canopen::pdo::parse_spec(s)?;
    if let Some(m) = mappings.iter().find(|m| m.node.is_none()) {
        return Err(format!(
            "COB-ID {:#x} is no predefined PDO id (0x181-0x57F): its node is unknown",
            m.cob_id.id
        ));
    }
    Ok(PdoSpec {
        text: s.to_string(),
        mappings,
    })
}

fn parse_dcf(s: &str) -> Result<(NodeId, PathBuf), String> {
    emcy_decode::canopen::dcf::parse_option(s)
}

/// A usable DCF's problems, one `warning:` line each with its file and
/// line, and how many were not shown: a value that is no number is left out
/// (a PDO's COB-ID then stays the predefined one), which must not pass
/// unsaid. Written before any trace is read; a failing stderr does not stop
/// the run.
fn warn_dcf_problems(path: &std::path::Path, dcf: &emcy_decode::canopen::dcf::Dcf) {
    use std::io::Write;
    let mut err = std::io::stderr().lock();
    let shown = path.display().to_string();
    let name = emcy_decode::text::printable(&shown);
    for p in &dcf.problems {
        let _ = writeln!(
            err,
            "warning: --dcf {name}:{}: {}",
            p.line,
            emcy_decode::text::printable(&p.reason)
        );
    }
    let more = dcf.problem_count.saturating_sub(dcf.problems.len() as u64);
    if more > 0 {
        let _ = writeln!(
            err,
            "warning: --dcf {name}: {more} more problems not shown ({} in all)",
            dcf.problem_count
        );
    }
}

impl DriveArgs {
    /// Sets the drive options: DCFs read here (a missing or unreadable one
    /// is an error before any trace is read).
    fn apply(&self, opts: &mut Options) -> Result<()> {
        for spec in &self.pdo {
            opts.pdo.extend(spec.mappings.iter().cloned());
        }
        for (node, path) in &self.dcf {
            let dcf = emcy_decode::canopen::dcf::load(path, *node)
                .map_err(|e| anyhow::anyhow!("--dcf {e}"))?;
            if dcf.mappings.is_empty() && dcf.vendor_id.is_none() && dcf.device_type.is_none() {
                bail!(
                    "--dcf {}: no PDO mapping, device type or identity in it: not a DCF or EDS \
                     file{}",
                    path.display(),
                    dcf.problems
                        .first()
                        .map(|p| format!(" ({p})"))
                        .unwrap_or_default()
                );
            }
            warn_dcf_problems(path, &dcf);
            opts.dcf.push((*node, dcf));
        }
        opts.assume_cia402_pdo = self.assume_cia402_pdo;
        Ok(())
    }

    /// As a baseline records them.
    fn recorded(&self) -> (Vec<String>, Vec<String>, bool) {
        (
            self.pdo.iter().map(|p| p.text.clone()).collect(),
            self.dcf
                .iter()
                .map(|(n, p)| {
                    let name = p.file_name().map(|f| f.to_string_lossy().into_owned());
                    format!("{n}={}", name.unwrap_or_default())
                })
                .collect(),
            self.assume_cia402_pdo,
        )
    }
}

const DIFF_HELP: &str = "\
Each trace is told as its nodes' stories: boot-ups, NMT states (said by the
node, or commanded), EMCY codes, CiA 402 drive states, fault resets, SDO
transfers (a download with its value, an upload without it) and aborts,
heartbeat losses, bus-offs and LSS services, in order, without their times
and without process data. The stories are aligned node by node; the
output names where the traces part first, then every difference per node,
then what differs in how each node ended (NMT state, active errors, PDO
mappings). Traces that differ only in timing or process data are the same.

Exit status: 0 the same, 1 different, 2 trouble (an input that cannot be
read), as diff(1).";

/// `diff GOOD BAD`.
#[derive(Args, Debug)]
pub struct DiffArgs {
    /// The trace that shows the machine working (`-` reads stdin)
    #[arg(value_name = "GOOD")]
    pub good: PathBuf,

    /// The trace to compare with it (`-` reads stdin)
    #[arg(value_name = "BAD")]
    pub bad: PathBuf,

    #[command(flatten)]
    pub reading: ReadArgs,

    /// Output format of the differences
    #[arg(long, short = 'f', value_enum, default_value_t = ExplainFormat::Text, help_heading = OUTPUT)]
    pub format: ExplainFormat,
}

const CONFIG_HELP: &str = "\
Every object an SDO download of the trace wrote and the node confirmed, per
node: the last confirmed value wins; writes the node aborted, never answered
or the client left incomplete are comments, never values. As a DCF-style INI
file ([1A00sub1], ParameterName, ParameterValue=0x60410010, `;` comments
naming the lines) or JSON (-f json). With --dcf NODE=FILE, the objects whose
values differ from the file's (ParameterValue, else DefaultValue) are listed.

With -o DIR, one file per node (node3.dcf; can1-node3.dcf when the trace has
several channels) or config.json; a file there that this command did not
write is left as it is (an error line, exit 2).

Exit status: 0 written, 2 trouble (a trace that cannot be read whole, a file
that cannot be written).";

/// `config TRACE`.
#[derive(Args, Debug)]
pub struct ConfigArgs {
    /// The trace (`-` reads stdin)
    #[arg(value_name = "TRACE")]
    pub trace: PathBuf,

    /// Only these nodes (repeatable or comma list)
    #[arg(long, value_delimiter = ',', value_parser = parse_node, value_name = "N", help_heading = OUTPUT)]
    pub node: Vec<NodeId>,

    /// Write the files into DIR (made if missing) instead of stdout
    #[arg(long, short = 'o', value_name = "DIR", help_heading = OUTPUT)]
    pub output: Option<PathBuf>,

    /// Output format: a DCF-style INI file per node, or one JSON document
    #[arg(long, short = 'f', value_enum, default_value_t = ConfigFormat::Dcf, help_heading = OUTPUT)]
    pub format: ConfigFormat,

    #[command(flatten)]
    pub reading: ReadArgs,
}

/// `config -f`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ConfigFormat {
    /// A DCF-style INI file per node
    Dcf,
    /// One JSON document
    Json,
}

/// How to read a trace: the same for `baseline`, `check` and `diff`, so a
/// check reads its traces exactly as the baseline did.
#[derive(Args, Debug)]
pub struct ReadArgs {
    /// Read traces as this format instead of detecting it
    #[arg(long, value_enum, value_name = "FORMAT", help_heading = INPUT)]
    pub input_format: Option<InputFormat>,

    /// What candump times are (absolute, zero, delta), as for decoding
    #[arg(long, value_enum, value_name = "MODE", help_heading = INPUT)]
    pub timestamps: Option<TimestampsArg>,

    /// A node's EMCY id moved by object 0x1014: COBID=NODE, e.g. 0x1A5=5 (repeatable)
    #[arg(long, value_parser = parse_emcy_id, value_name = "COBID=NODE", help_heading = DECODING)]
    pub emcy_id: Vec<EmcyId>,

    /// Print at most N diagnostics (malformed lines...) per trace on stderr
    #[arg(long, default_value_t = 20, value_name = "N", help_heading = OUTPUT)]
    pub max_diagnostics: usize,

    /// Heartbeat timeout for every node in seconds, as for decoding
    #[arg(long, value_parser = parse_seconds, value_name = "SECONDS", help_heading = DECODING)]
    pub heartbeat_timeout: Option<Span>,

    /// Vendor profile for every node (NAME) or one node (NODE=NAME), as for decoding
    #[arg(long, value_parser = ProfileNames(parse_profile_arg), hide_possible_values = true, value_name = "[NODE=]NAME", help_heading = DECODING)]
    pub profile: Vec<ProfileRequest>,

    /// A user profile (TOML), as for decoding
    #[arg(long, value_name = "FILE.toml", help_heading = DECODING)]
    pub profile_file: Vec<PathBuf>,

    #[command(flatten)]
    pub drive: DriveArgs,
}

/// Traces and how to read them; the same for `baseline` and `check`, so a
/// check reads its traces exactly as the baseline did.
#[derive(Args, Debug)]
pub struct TraceArgs {
    /// Trace files (`-` reads stdin); each is recorded under the path as given,
    /// normalized and relative
    #[arg(value_name = "TRACE", required = true)]
    pub traces: Vec<PathBuf>,

    #[command(flatten)]
    pub reading: ReadArgs,

    /// Record and look up traces by their path relative to DIR, not to the current directory
    /// (the same keys wherever baseline and check run)
    #[arg(long, value_name = "DIR", help_heading = INPUT)]
    pub root: Option<PathBuf>,

    /// Read directories given as TRACE recursively, as for decoding (files that are no trace
    /// skipped with a note)
    #[arg(long, short = 'r', help_heading = INPUT)]
    pub recursive: bool,

    /// Under -r, read only files whose path below the directory matches GLOB (`!GLOB`
    /// excludes; repeatable), as for decoding
    #[arg(long, value_name = "GLOB", requires = "recursive", help_heading = INPUT)]
    pub glob: Vec<String>,

    /// Under -r, follow symbolic links, as for decoding
    #[arg(long, short = 'L', requires = "recursive", help_heading = INPUT)]
    pub follow_links: bool,
}

#[derive(Args, Debug)]
pub struct BaselineArgs {
    #[command(flatten)]
    pub read: TraceArgs,

    /// Write the baseline to FILE instead of stdout (a regular file is replaced
    /// atomically; a FIFO or device is written into)
    #[arg(long, short = 'o', value_name = "FILE", help_heading = OUTPUT)]
    pub output: Option<PathBuf>,
}

const CHECK_HELP: &str = "\
Output: one line per difference, `SEVERITY: FILE[ CHANNEL node N]: MESSAGE`,
sorted by file, channel, node and code, then a `check:` summary line.

Regressions (exit 1 unless --allow/--allow-node accepts them): a new error
code, an error still active at the end that the baseline had cleared, a new
node with errors, more malformed lines or undecodable EMCYs, a node that lost
its heartbeat where the baseline's did not, a trace not in the baseline, a
baseline trace not given.
Improvements (exit 0): an error no longer raised, an error no longer active
at the end, fewer malformed lines, a node no longer losing its heartbeat. Changes (exit 0): a known error raised a
different number of times, a node gone, a new node without errors, another
format.

Exit status:
  0  no regression (or --update)
  1  at least one regression
  2  usage error, unreadable trace or baseline, baseline of another version
  129, 130, 143  stopped by SIGHUP, Ctrl-C or SIGTERM: nothing compared or written";

#[derive(Args, Debug)]
#[command(
    after_help = "Exit status: 0 no regression, 1 a regression, 2 error. `--help` says what each \
                  difference is.",
    after_long_help = CHECK_HELP
)]
pub struct CheckArgs {
    #[command(flatten)]
    pub read: TraceArgs,

    /// Output format of the differences
    #[arg(long, short = 'f', value_enum, default_value_t = CheckFormat::Text, help_heading = OUTPUT)]
    pub format: CheckFormat,

    /// The baseline to compare with (written by `emcy-decode baseline`)
    #[arg(long, short = 'b', value_name = "FILE", help_heading = CI)]
    pub baseline: PathBuf,

    /// Accept new or newly active errors with this code (repeatable or comma list, hex)
    #[arg(long, value_delimiter = ',', value_parser = parse_code_arg, value_name = "CODE", help_heading = CI)]
    pub allow: Vec<u16>,

    /// Accept every difference of this node, on any channel (repeatable or comma list)
    #[arg(long, value_delimiter = ',', value_parser = parse_node, value_name = "N", help_heading = CI)]
    pub allow_node: Vec<NodeId>,

    /// Rewrite the baseline from these traces after printing the differences; exit 0
    #[arg(long, help_heading = CI)]
    pub update: bool,

    /// Compare only the traces given: the baseline's other traces are not "not given"
    /// regressions (with --update, only the given traces' records are replaced)
    #[arg(long, help_heading = CI)]
    pub only_given: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CheckFormat {
    /// One finding per line, then a summary line
    Text,
    /// One JSON document: findings and summary
    Json,
    /// JUnit XML: a test case per trace, a failure per regression (GitLab, Jenkins, GitHub)
    Junit,
    /// GitHub Actions annotations: an ::error line per regression, then the summary
    Github,
}

/// `-j` above this is a mistake, not a machine: a usage error.
const MAX_THREADS: usize = 1024;

/// Threads per core `-j` is cut to: more only wait for a turn, each with its
/// buffers (and a thread that cannot be started used to end the run).
const THREADS_PER_CORE: usize = 4;

fn parse_threads(s: &str) -> Result<usize, String> {
    let n: usize = s
        .parse()
        .map_err(|_| format!("`{s}` is not a thread count (0 = automatic, 1-{MAX_THREADS})"))?;
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    threads_within(n, cores)
}

/// `-j N` on a machine with `cores` cores: N up to [`THREADS_PER_CORE`]
/// per core, absurd values refused.
fn threads_within(n: usize, cores: usize) -> Result<usize, String> {
    if n > MAX_THREADS {
        return Err(format!(
            "{n} threads is more than {MAX_THREADS} (this machine has {cores} cores)"
        ));
    }
    Ok(n.min(THREADS_PER_CORE.saturating_mul(cores.max(1))))
}

fn parse_code_arg(s: &str) -> Result<u16, String> {
    parse_code(s).map_err(|e| e.to_string())
}

impl DecodeArgs {
    /// The library's options for these flags (user profiles are loaded here).
    pub(super) fn options(&self) -> Result<Options> {
        Ok(Options {
            input_format: self.input_format.map(Into::into),
            timestamps: self.timestamps.map(Into::into),
            nodes: self.node.clone(),
            channels: self.channel.clone(),
            max_diagnostics: self.max_diagnostics,
            emcy_ids: self.emcy_id.clone(),
            profiles: profile_choice::resolve(&self.profile, &self.profile_file)?,
            heartbeat_timeout: self.heartbeat_timeout,
            sdo_timeout: self.sdo_timeout.unwrap_or(Options::default().sdo_timeout),
            incident_gap: self.incident_gap.unwrap_or(Options::default().incident_gap),
            timing: self.timing || self.bitrate.is_some(),
            bit_rate: self.bitrate,
            ..Options::default()
        })
        .and_then(|mut o| {
            self.drive.apply(&mut o)?;
            Ok(o)
        })
    }
}

impl ReadArgs {
    /// The decoding options as a baseline records them, normalized (the
    /// `--profile-file` profiles by name: paths differ between machines).
    pub(super) fn recorded(&self) -> Result<ReadOptions> {
        let mut profile_file = Vec::new();
        for f in &self.profile_file {
            profile_file.push(Profile::load(f)?.name().to_string());
        }
        Ok(ReadOptions {
            input_format: self
                .input_format
                .and_then(|f| f.to_possible_value())
                .map(|v| v.get_name().to_string()),
            timestamps: self
                .timestamps
                .and_then(|t| t.to_possible_value())
                .map(|v| v.get_name().to_string()),
            emcy_id: self
                .emcy_id
                .iter()
                .map(|e| {
                    let digits = if e.extended { 8 } else { 3 };
                    format!("0x{:0digits$X}={}", e.id, e.node)
                })
                .collect(),
            profile: self
                .profile
                .iter()
                .map(|p| match p.node {
                    Some(n) => format!("{n}={}", p.name),
                    None => p.name.clone(),
                })
                .collect(),
            heartbeat_timeout: self.heartbeat_timeout.map(|s| s.to_string()),
            profile_file,
            pdo: self.drive.recorded().0,
            dcf: self.drive.recorded().1,
            assume_cia402_pdo: self.drive.recorded().2,
        })
    }

    /// The library's options for these flags, as `decode` would make them.
    pub(super) fn options(&self) -> Result<Options> {
        Ok(Options {
            input_format: self.input_format.map(Into::into),
            timestamps: self.timestamps.map(Into::into),
            max_diagnostics: self.max_diagnostics,
            emcy_ids: self.emcy_id.clone(),
            profiles: profile_choice::resolve(&self.profile, &self.profile_file)?,
            heartbeat_timeout: self.heartbeat_timeout,
            ..Options::default()
        })
        .and_then(|mut o| {
            self.drive.apply(&mut o)?;
            Ok(o)
        })
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
            f.codes.push(fail_on_code(code)?);
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
            "lost" => f.lost = true,
            "fault" | "faults" => f.fault = true,
            "bus-off" | "bus_off" => f.bus_off = true,
            "bus-errors" | "bus_errors" => f.bus_errors = true,
            "incident" | "incidents" => f.incident = true,
            _ if in_codes => {
                f.codes.push(fail_on_code(item)?);
                continue;
            }
            _ => {
                return Err(format!(
                    "'{item}' is not a condition: never, any, active, warning, lost, fault, \
                     bus-off, bus-errors, incident, code=CODE[,CODE...], category<=N"
                ));
            }
        }
        in_codes = false;
    }
    Ok(f)
}

/// `--heartbeat-timeout`: seconds as a decimal (`0.5`, `2`), above zero.
fn parse_seconds(s: &str) -> Result<Span, String> {
    let t = Timestamp::parse(s.trim().as_bytes())
        .map_err(|_| format!("`{s}` is not a number of seconds (e.g. 0.5)"))?;
    let span = t.since(Timestamp::ZERO);
    if span == Span::ZERO || t.secs() > 1_000_000_000 {
        return Err(format!(
            "`{s}`: a timeout is above 0 and at most 1e9 seconds"
        ));
    }
    Ok(span)
}

/// A bit rate as people write one (`500k`, `1M`, `125000`).
fn parse_bitrate(s: &str) -> Result<u32, String> {
    emcy_decode::trace::parse_bit_rate(s.as_bytes())
        .ok_or_else(|| format!("`{s}` is not a bit rate (e.g. 500k, 1M, 250000)"))
}

/// An error code in hex, with or without 0x.
fn fail_on_code(s: &str) -> Result<u16, String> {
    emcy_decode::trace::hex::parse_code(s)
        .ok_or_else(|| format!("'{s}' is not an error code (1-4 hex digits)"))
}

/// A parser of a profile argument that also offers the built-in profiles'
/// names, so shell completion of `--profile` completes names, not files.
/// It accepts any name: a `--profile-file` may define more.
#[derive(Clone)]
struct ProfileNames<P>(P);

impl<P: TypedValueParser> TypedValueParser for ProfileNames<P> {
    type Value = P::Value;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<Self::Value, clap::Error> {
        self.0.parse_ref(cmd, arg, value)
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(
            Profile::builtins()
                .iter()
                .map(|p| PossibleValue::new(p.name())),
        ))
    }
}

/// `--profile NAME` or `--profile NODE=NAME`.
fn parse_profile_arg(s: &str) -> Result<ProfileRequest, String> {
    let (node, name) = match s.split_once('=') {
        Some((node, name)) => (Some(parse_node(node)?), name.trim()),
        None => (None, s.trim()),
    };
    if name.is_empty() {
        return Err(format!("'{s}' names no profile"));
    }
    Ok(ProfileRequest {
        node,
        name: name.to_string(),
    })
}

/// `0x1A5=5`, `000001A5=5` (29-bit by digit count), `1A5x=5` (29-bit).
fn parse_emcy_id(s: &str) -> Result<EmcyId, String> {
    let err = || format!("'{s}' is not COBID=NODE (e.g. 0x1A5=5 or 18FF0105x=5)");
    let (cob, node) = s.split_once('=').ok_or_else(err)?;
    let node = parse_can_node(node)?;
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

/// A node: a CANopen node id, 1..=127, or an EtherCAT slave's station
/// address, up to 65535; decimal or 0x hex.
fn parse_node(s: &str) -> Result<NodeId, String> {
    match number(s) {
        Some(n @ 1..) => Ok(n),
        _ => Err(format!(
            "'{s}' is not a node (a CANopen node id 1-127 or an EtherCAT station address up \
             to 65535, decimal or 0x hex)"
        )),
    }
}

/// A CANopen node id, 1..=127 (the node an EMCY id belongs to).
fn parse_can_node(s: &str) -> Result<NodeId, String> {
    match number(s) {
        Some(n @ 1..=127) => Ok(n),
        _ => Err(format!(
            "'{s}' is not a CANopen node id (1-127, decimal or 0x hex)"
        )),
    }
}

fn number(s: &str) -> Option<NodeId> {
    let t = s.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => NodeId::from_str_radix(hex, 16).ok(),
        None => t.parse::<NodeId>().ok(),
    }
}

/// Parses `10 43 09 01`, `1043090100000000`, `10:43:09`, `0x10,0x43` into bytes.
pub(super) fn parse_payload(text: &str) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    for token in text
        .split(|c: char| c.is_whitespace() || matches!(c, ':' | ',' | '-' | '.'))
        .filter(|t| !t.is_empty())
    {
        let digits = token
            .strip_prefix("0x")
            .or_else(|| token.strip_prefix("0X"))
            .unwrap_or(token);
        let digits = digits.as_bytes();
        if digits.len() == 1 {
            match hex::nibble(digits[0]) {
                Some(v) => bytes.push(v),
                None => bail!("'{token}' is not a hex byte"),
            }
            continue;
        }
        if digits.is_empty() || digits.len() % 2 != 0 {
            bail!("'{token}' is not a whole number of hex bytes");
        }
        for pair in digits.chunks_exact(2) {
            match hex::parse_byte(pair[0], pair[1]) {
                Some(b) => bytes.push(b),
                None => bail!("'{token}' is not hexadecimal"),
            }
        }
    }
    if bytes.len() > 8 {
        bail!("an EMCY payload has at most 8 bytes; got {}", bytes.len());
    }
    Ok(bytes)
}

/// An error code in hex, with or without 0x (`explain`, `--allow`).
pub(super) fn parse_code(text: &str) -> Result<u16> {
    match hex::parse_code(text) {
        Some(c) => Ok(c),
        None => bail!("'{text}' is not an error code (1-4 hex digits, optional 0x)"),
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
    fn thread_counts_are_bounded_by_the_cores_and_absurd_ones_refused() {
        assert_eq!(threads_within(0, 2), Ok(0), "0 stays automatic");
        assert_eq!(threads_within(3, 2), Ok(3));
        assert_eq!(threads_within(8, 2), Ok(8));
        assert_eq!(threads_within(9, 2), Ok(8));
        assert_eq!(threads_within(1024, 2), Ok(8));
        assert_eq!(threads_within(1024, 512), Ok(1024));
        assert_eq!(threads_within(5, 0), Ok(4), "no core count: one core");
        assert!(threads_within(1025, 512).is_err());
        assert!(threads_within(usize::MAX, 2).is_err());
        assert!(parse_threads("18446744073709551616").is_err());
        assert!(parse_threads("-1").is_err());
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
        assert_eq!(
            f("bus-off,bus-errors"),
            Ok(FailOn {
                bus_off: true,
                bus_errors: true,
                ..FailOn::default()
            })
        );
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
        assert_eq!(FailOn::combine(&[]), FailOn::default());
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
    fn payload_spellings() {
        let want = vec![0x10, 0x43, 0x09, 0x01, 0, 0, 0, 0];
        for text in [
            "10 43 09 01 00 00 00 00",
            "1043090100000000",
            "10:43:09:01:00:00:00:00",
            "0x10,0x43,0x09,0x01,0x00,0x00,0x00,0x00",
            "10-43-09-01 00000000",
        ] {
            assert_eq!(parse_payload(text).unwrap(), want, "{text}");
        }
        assert_eq!(parse_payload("0 0 0").unwrap(), [0, 0, 0]);
        assert!(parse_payload("104").is_err());
        assert!(parse_payload("zz").is_err());
        assert!(parse_payload("00 00 00 00 00 00 00 00 00").is_err());
    }

    #[test]
    fn explain_codes() {
        assert_eq!(parse_code("4310").unwrap(), 0x4310);
        assert!(parse_code("43100").is_err());
    }

    #[test]
    fn node_ids() {
        assert_eq!(parse_node("5"), Ok(5));
        assert_eq!(parse_node("0x7F"), Ok(127));
        // EtherCAT station addresses.
        assert_eq!(parse_node("1001"), Ok(1001));
        assert_eq!(parse_node("0xFFFF"), Ok(65535));
        assert!(parse_node("0").is_err());
        assert!(parse_node("65536").is_err());
        assert!(parse_node("x").is_err());
        assert_eq!(parse_can_node("127"), Ok(127));
        assert!(parse_can_node("128").is_err());
        assert!(parse_can_node("0").is_err());
    }
}
