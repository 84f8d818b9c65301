//! Trace readers: one line parser per text format, one reader per binary
//! format (BLF, pcap/pcapng, MF4), all yielding [`Frame`].
//!
//! Every line is classified as exactly one of: a frame, a known non-frame line
//! (header, comment, status, blank: "skipped"), or a malformed line with a
//! reason. Parsers never panic and never stop: the caller counts and reports.
//! (A binary format's "line" is its record: a BLF object, a pcap packet,
//! an MF4 record.)
//!
//! This file is the table of contents. The shared types live in their own
//! files ([`frame`], [`interest`], [`traits`], [`time`]); each format has a
//! folder under `format`; [`any`] dispatches to them. A caller writes its
//! read loop once, over [`FrameSource`], and runs it on an [`AnyReader`].
//!
//! This crate is the bottom of emcy-decode and imports nothing of it: what
//! a frame means to CANopen is said above it.
//!
//! ```
//! use emcy_trace::{Format, Interest, LineParser, Parsed};
//!
//! let mut parser = Format::CandumpLog.parser();
//! let everything = Interest::all();
//! let Parsed::Frame(frame) =
//!     parser.parse(b"(1700000001.250000) can0 081#1043080100000000", &everything)
//! else {
//!     panic!("a candump log line is a frame");
//! };
//! assert_eq!((frame.channel, frame.id), (&b"can0"[..], 0x081));
//! assert_eq!(frame.data.as_slice(), [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
//! assert_eq!(frame.time.map(|t| t.to_string()).as_deref(), Some("1700000001.250000"));
//! assert!(matches!(parser.parse(b"garbage", &everything), Parsed::Malformed(_)));
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod any;
pub mod bit_rate;
pub mod cancel;
pub mod deltas;
pub mod detect;
pub mod error_frame;
pub mod ethercat;
pub mod fold;
pub mod follow;
pub mod format;
pub mod frame;
pub mod hex;
pub mod id_counts;
pub mod input;
pub mod interest;
pub mod lines;
pub mod read;
pub mod scan;
pub mod text;
pub mod time;
pub mod token;
pub mod traits;

pub use any::{AnyParser, AnyReader};
pub use bit_rate::parse_bit_rate;
pub use error_frame::ErrorFrame;
pub use fold::{Fold, FoldBuffers, FoldRule, Folded, Folds, HexText, Inner};
pub use format::Format;
pub use frame::NumberedChannel;
pub use frame::{Frame, FrameKind, HexBytes, Payload};
pub use id_counts::{FrameKey, IdCounts, TimedLine};
pub use interest::{ContentFilter, DataHead, Interest};
pub use time::{Span, Step, Ticks, Timestamp};
pub use token::{is_blank, show_token, split_token, trim_end, trim_start};
pub use traits::{Counted, FrameSource, LineParser, Next, Parsed, Reason, Run, Scan};
