//! The integration tests, one binary (one link, one run): the program
//! through its command line, and the library through its public API and
//! its fuzz target bodies (`emcy_decode::fuzzing`). One module per area;
//! what they share is in `support`.
//!
//! `cargo test --test integration` runs them all; a module or a test by
//! name filter, e.g. `cargo test --test integration -- trc::` or
//! `cargo test --test integration -- golden:: chart::`.

// `support/frames.rs` is also compiled inside the library (its unit tests)
// and names these as `crate::FrameKind`, `crate::Timestamp`.
use emcy_decode::{FrameKind, Timestamp};

mod support;

mod api;
mod baseline;
mod blf;
mod bus;
mod busmaster;
mod chart;
mod cia402;
mod cli;
mod config;
mod csv;
mod diff;
mod differential;
mod error_frames;
mod ethercat;
mod follow;
mod fuzz_corpus;
mod golden;
mod health;
mod hostile;
mod identity;
mod incidents;
mod inputs;
mod ixxat;
mod live;
mod memory;
mod mf4;
mod network;
mod output;
mod pasted;
mod pcap;
mod readme;
mod roundtrip;
mod sdo;
mod table;
mod timestamps;
mod traffic;
mod trc;
