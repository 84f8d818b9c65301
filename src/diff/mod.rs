//! A CANopen-level comparison of two traces, as `emcy-decode diff GOOD BAD`
//! prints it: each trace told as its nodes' stories ([`story`]), the
//! stories aligned node by node ([`compare`](mod@compare)), the result as text or JSON
//! ([`text`]). Times and process data are not part of a story, so two runs
//! that differ only in them compare equal. No command line and no process
//! I/O here: the application reads the traces and prints.

pub mod compare;
pub mod story;
pub mod text;

pub use compare::{Comparison, compare};
pub use story::{Recorder, Story};
