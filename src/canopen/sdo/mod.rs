//! Just enough SDO (CiA 301 §7.2.4) to learn object values a trace shows.
//! Each part of the protocol the decoder reads has its own file:
//!
//! - [`frame`]: reading one frame (expedited uploads and downloads, their
//!   confirmations, aborts) and cheap tests of what a frame names;
//! - [`tracker`]: following writes of the objects the decoder follows to
//!   their confirmation;
//! - [`segmented`]: assembling downloads of any object, expedited and
//!   segmented, and segmented uploads, for PDO mapping learning;
//! - [`block`]: following block transfers, so that their segments are
//!   never read as commands, and the small values they carry;
//! - [`transfer`]: every transfer, from its first frame to its end, for
//!   the user (the others learn values for the decoder);
//! - [`abort`]: what abort codes mean.

pub mod abort;
mod access;
pub mod block;
mod frame;
pub mod segmented;
mod tracker;
pub mod transfer;

pub use access::{
    COB_ID_EMCY, CONSUMER_HEARTBEAT, DEVICE_TYPE, ERROR_HISTORY, GUARD_TIME, IDENTITY,
    LIFE_TIME_FACTOR, Object, PRODUCER_HEARTBEAT, REQUEST_BASE, RESPONSE_BASE, Sdo, cob_id_emcy,
    is_followed, is_sdo_id,
};
pub use block::{BlockStep, Blocks};
#[cfg(test)]
pub use frame::names_followed_object;
pub use frame::{begins_segmented_transfer, is_abort, names_object, parse, parse_payload};
pub use segmented::{Confirmed, Downloads, TEXT_BYTES, Text, Uploads, is_text};
pub use tracker::Tracker;
