//! emcy-decode: read CAN traces, decode CANopen emergency (EMCY) frames and
//! rebuild each node's error-state timeline.
//!
//! Pipeline: [`trace`] turns lines into frames, [`canopen`] decodes EMCY
//! payloads, [`timeline`] runs each node's error state machine, [`report`]
//! renders; [`analyze`] wires one input through all of them.
#![forbid(unsafe_code)]

pub mod analyze;
pub mod baseline;
pub mod batch;
pub mod cache;
pub mod canopen;
pub mod cli;
pub mod explain;
#[doc(hidden)]
pub mod fuzzing;
pub mod history;
pub mod interrupt;
pub mod profile_choice;
pub mod report;
pub mod run;
pub mod timeline;
pub mod trace;
