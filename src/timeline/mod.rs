//! The per-node error state machine (CiA 301 EMCY transitions 0-4, as the
//! S200/S300/AX2000 manuals describe it) and the error intervals it yields.
//!
//! Rules, exactly:
//! - A node starts error-free.
//! - code != 0x0000: transition 1 from error-free, 3 otherwise; the code becomes
//!   active (a repeat of an active code does not open a second interval).
//! - code == 0x0000, register != 0: transition 2 if error-occurred (else none
//!   and a warning); the node is error-occurred. An active error closes
//!   (partial reset) when its class bit was set in the register when it was
//!   raised and is clear now. Errors that cannot be attributed stay active.
//! - code == 0x0000, register == 0: transition 4 if error-occurred (else none
//!   and a warning); every active error closes (reset); error-free.
//! - NMT boot-up closes every active error (boot) and returns to error-free.
//!
//! [`history`] keeps the closed intervals of every node of an input.

pub mod drive;
pub mod error_history;
pub mod health;
pub mod heartbeat;
pub mod history;
pub mod interval;
pub mod nmt;
pub mod node;

pub use interval::{At, ClearedBy, Interval};
pub use node::{NodeEnd, NodeStats, NodeTimeline, State, Step};
