//! emcy-decode: read CAN traces, decode CANopen emergency (EMCY) frames and
//! rebuild each node's error-state timeline.
#![forbid(unsafe_code)]

pub mod canopen;
pub mod trace;
