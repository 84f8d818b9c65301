//! One folder per trace format, and [`Format`], the list of them.
//!
//! A text format's folder holds its [`LineParser`](crate::LineParser);
//! a binary format's holds its reader, a
//! [`FrameSource`](crate::FrameSource). Adding a format means adding
//! a folder here, a [`Format`] variant, and an arm to the dispatchers in
//! [`any`](crate::any).

pub mod asc;
pub mod blf;
pub mod busmaster;
pub mod candump_log;
pub mod candump_screen;
pub mod ixxat;
pub mod mf4;
pub mod pcap;
pub mod trc;
pub mod vector;

use std::fmt;

use crate::any::{AnyParser, BinaryParser};

/// The text formats we read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// `candump -l` / `-L` log lines: `(1469439874.299654) can0 081#1043080100000000`.
    CandumpLog,
    /// candump's default screen output: `  can0  081   [8]  10 43 08 01 00 00 00 00`.
    CandumpScreen,
    /// Vector ASC (CANalyzer/CANoe, log2asc).
    Asc,
    /// PEAK TRC (PCAN-View, PCAN-Explorer), versions 1.0 to 2.1.
    Trc,
    /// BUSMASTER log (`***BUSMASTER Ver 2.0.0***`, `14:19:11:4184 Tx 1 0x099 s 8 ...`).
    Busmaster,
    /// IXXAT MiniMon V3 ASCII trace (`"00:02:20.66";"83";"Std";"";"00 01 "`).
    Ixxat,
    /// Vector BLF, binary: read object by object, not line by line, and
    /// detected by its `LOGG` magic, so it is not in [`Format::ALL`].
    Blf,
    /// libpcap capture file (tcpdump, scapy, Wireshark's "pcap"), binary:
    /// read packet by packet, detected by its magic number.
    Pcap,
    /// pcapng capture file (Wireshark, dumpcap), binary: read packet by
    /// packet, detected by its section header block.
    Pcapng,
    /// ASAM MDF 4 bus logging (CANedge, Vector, python-can), binary: read
    /// record by record, detected by its identification block.
    Mf4,
}

impl Format {
    /// The text formats, read line by line and detected from their lines.
    pub const ALL: [Format; 6] = [
        Format::CandumpLog,
        Format::CandumpScreen,
        Format::Asc,
        Format::Trc,
        Format::Busmaster,
        Format::Ixxat,
    ];

    /// The name used on the command line and in the `format` JSON key.
    pub fn name(self) -> &'static str {
        match self {
            Format::CandumpLog => "candump",
            Format::CandumpScreen => "candump-screen",
            Format::Asc => "asc",
            Format::Trc => "trc",
            Format::Busmaster => "busmaster",
            Format::Ixxat => "ixxat",
            Format::Blf => "blf",
            Format::Pcap => "pcap",
            Format::Pcapng => "pcapng",
            Format::Mf4 => "mf4",
        }
    }

    /// A binary format: read record by record by its own reader (its
    /// "lines" are BLF objects or pcap packets), never by the line parsers.
    pub fn is_binary(self) -> bool {
        matches!(
            self,
            Format::Blf | Format::Pcap | Format::Pcapng | Format::Mf4
        )
    }

    /// A parser of this format in its state before the first line (a binary
    /// format's reads no lines).
    pub fn parser(self) -> AnyParser {
        match self {
            Format::CandumpLog => AnyParser::CandumpLog(candump_log::CandumpLogParser::new()),
            Format::CandumpScreen => {
                AnyParser::CandumpScreen(candump_screen::CandumpScreenParser::new())
            }
            Format::Asc => AnyParser::Asc(asc::AscParser::new()),
            Format::Trc => AnyParser::Trc(trc::TrcParser::new()),
            Format::Busmaster => AnyParser::Busmaster(busmaster::BusmasterParser::new()),
            Format::Ixxat => AnyParser::Ixxat(ixxat::IxxatParser::new()),
            Format::Blf | Format::Pcap | Format::Pcapng | Format::Mf4 => {
                AnyParser::Binary(BinaryParser(self))
            }
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
