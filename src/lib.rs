//! emcy-decode: read CAN traces, decode CANopen emergency (EMCY) frames and
//! rebuild each node's error-state timeline.
#![forbid(unsafe_code)]

pub mod analyze;
mod app;
pub mod baseline;
pub(crate) mod cache;
pub mod canopen;
#[cfg(any(test, feature = "fuzzing"))]
#[doc(hidden)]
pub mod fuzzing;
pub mod report;
pub mod timeline;
pub mod trace;

/// The `emcy-decode` program; `src/main.rs` only calls this. Not API.
#[doc(hidden)]
pub fn cli_main() -> std::process::ExitCode {
    app::main()
}
