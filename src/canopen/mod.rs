//! CANopen: EMCY decoding, code tables, error register bits, SDO, vendor
//! profiles and which profile decodes which node. Uses trace types at most.

pub mod codes;
pub mod emcy;
pub mod profile;
pub mod profile_choice;
pub mod register;
pub mod sdo;
