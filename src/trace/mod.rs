//! The trace readers: the `emcy-trace` crate (`crates/emcy-trace`), whose
//! paths this keeps under `crate::trace`, and [`reader`], which reads a
//! whole trace into owned records for a Rust program. The reader stays in
//! this crate because what its frames are to CANopen
//! ([`CanFrame::emcy_node`](reader::CanFrame::emcy_node)) is said in
//! `canopen`, and only the crate that defines a type can add methods to it.

pub use emcy_trace::*;

pub mod can_error;
pub mod reader;
