//! CANopen: EMCY decoding, code tables, error register bits, vendor profiles.

pub mod codes;
pub mod emcy;
pub mod profile;
pub mod register;
pub mod sdo;
