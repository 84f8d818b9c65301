//! emcy-decode reads CAN bus traces, decodes CANopen emergency (EMCY)
//! frames and rebuilds each node's error-state timeline. This is the
//! library under the `emcy-decode` program; what it offers a Rust program:
//!
//! - [`TraceReader`]: a trace (candump log or screen output, Vector ASC,
//!   PEAK TRC, BUSMASTER log, Vector BLF, pcap; gzip too; the format detected
//!   from the content)
//!   read into [`Record`]s, one per line, each frame a [`CanFrame`];
//! - [`Emcy::decode`]: an EMCY payload into its code, error register and
//!   manufacturer bytes;
//! - [`Profile`]: how a vendor describes a code ([`Profile::describe`]) and
//!   what its manufacturer bytes mean ([`Profile::decode_manufacturer`]);
//!   the built-ins by name ([`Profile::builtin`]) or a user profile file;
//! - [`NodeTimeline`]: one node's error state machine (CiA 301 transitions
//!   1-4, boot-ups) and the error [`Interval`]s it closes.
//!
//! ```
//! use emcy_decode::{At, Emcy, NodeTimeline, Profile, Record, State, TraceReader};
//!
//! let trace = "\
//! (1700000001.250000) can0 081#1043080100000000
//! (1700000002.000000) can0 181#1122
//! (1700000004.000000) can0 081#0000000000000000
//! ";
//! let kollmorgen = Profile::builtin("kollmorgen").expect("a built-in profile");
//! let mut timeline = NodeTimeline::new();
//! let mut said = Vec::new();
//! for record in TraceReader::new(trace.as_bytes()) {
//!     let Record::Frame(frame) = record? else { continue };
//!     let Some(node) = frame.emcy_node() else { continue };
//!     let emcy = Emcy::decode(&frame.data)?;
//!     said.push(format!("node {node}: {:#06x} {}", emcy.code, kollmorgen.describe(emcy.code)));
//!     let step = timeline.emcy(&emcy, At { time: frame.time, line: frame.line }, &mut Vec::new());
//!     for closed in &step.closed {
//!         said.push(format!("{:#06x} lasted {}", closed.code, closed.duration().unwrap()));
//!     }
//! }
//! assert_eq!(said, [
//!     "node 1: 0x4310 F06 motor temperature (AKD: F235)",
//!     "node 1: 0x0000 Error reset or no error",
//!     "0x4310 lasted 2.750000",
//! ]);
//! assert_eq!(timeline.state(), State::ErrorFree);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Everything else is the program's own and not API.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// The hidden layers' notes link to their private items: they are read with
// `cargo doc --document-private-items`, where those links resolve.
#![allow(rustdoc::private_intra_doc_links)]

// The layers below are public for the `emcy-decode` program
// (src/bin/emcy-decode), which uses the library as any other program would,
// but they are not API: hidden from the documentation and free to change.
// The API is the items re-exported below.
#[doc(hidden)]
pub mod analyze;
#[doc(hidden)]
pub mod baseline;
pub(crate) mod cache;
#[doc(hidden)]
pub mod canopen;
#[doc(hidden)]
pub mod config;
#[doc(hidden)]
pub mod diff;
#[cfg(feature = "fuzzing")]
#[doc(hidden)]
pub mod fuzzing;
#[cfg(test)]
mod layers;
#[doc(hidden)]
pub mod report;
#[doc(hidden)]
pub mod small_file;
#[doc(hidden)]
pub mod text;
#[doc(hidden)]
pub mod timeline;
#[doc(hidden)]
pub mod trace;

pub use canopen::codes::{Class, CodeInfo, Description, Tables};
pub use canopen::emcy::{Emcy, TooShort, Warning};
pub use canopen::profile::{Decoded, FieldValue, Profile, ProfileError, VendorCode};
pub use canopen::register::Register;
pub use timeline::{At, ClearedBy, Interval, NodeTimeline, State, Step};
pub use trace::deltas::TimeMode;
pub use trace::reader::{CanFrame, Record, TraceReader};
pub use trace::{Format, FrameKind, Span, Timestamp};
