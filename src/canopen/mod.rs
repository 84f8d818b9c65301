//! CANopen: EMCY decoding, code tables, error register bits, SDO, vendor
//! profiles and which profile decodes which node. Uses trace types at most.

pub mod cia402;
pub mod cob_id;
pub mod codes;
pub mod dcf;
pub mod device_profile;
pub mod dictionary;
pub mod emcy;
pub mod lss;
pub mod nmt;
pub mod pdo;
pub mod profile;
pub mod profile_choice;
pub mod register;
pub mod sdo;
pub mod time;

/// A node: a CANopen node id (1 to 127, from the COB-ID), or an EtherCAT
/// slave's station address for CANopen over EtherCAT (e.g. 1001), which
/// does not fit a byte.
pub type NodeId = u16;
