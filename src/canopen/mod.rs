//! CANopen: EMCY decoding, code tables, error register bits.

pub mod codes;
pub mod emcy;
pub mod register;
pub mod sdo;
