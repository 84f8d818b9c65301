//! Decoding one EMCY payload (CiA 301 §7.2.7.3.1) and the checks that need
//! only the frame itself. Checks that need the node's history (a reset while
//! error-free) live in the timeline.

use std::fmt;

use super::NodeId;
use super::codes::{self, Class, CodeInfo};
use super::register::{self, Register};
use crate::trace::FrameKind;
use crate::trace::reader::CanFrame;

/// The lowest and highest standard ids of the pre-defined EMCY connection set.
pub const EMCY_BASE: u32 = 0x080;
pub const FIRST_EMCY_ID: u32 = 0x081;
pub const LAST_EMCY_ID: u32 = 0x0FF;

/// NMT error control (boot-up, heartbeat) ids are 0x700 + node.
pub const NMT_ERROR_CONTROL_BASE: u32 = 0x700;

/// The node an id of the pre-defined EMCY set belongs to.
pub fn emcy_node(id: u32) -> Option<NodeId> {
    (FIRST_EMCY_ID..=LAST_EMCY_ID)
        .contains(&id)
        .then(|| (id - EMCY_BASE) as NodeId)
}

/// Whether `id` is a node's NMT error control id (0x701-0x77F).
pub fn is_nmt_error_control(id: u32) -> bool {
    (NMT_ERROR_CONTROL_BASE + 1..=NMT_ERROR_CONTROL_BASE + 127).contains(&id)
}

/// The node a boot-up frame (0x700 + node, one byte 0x00) announces.
pub fn boot_node(id: u32, data: &[u8]) -> Option<NodeId> {
    let node = id.checked_sub(NMT_ERROR_CONTROL_BASE)?;
    ((1..=127).contains(&node) && data == [0x00]).then_some(node as NodeId)
}

/// What a frame read by [`crate::TraceReader`] is to CANopen.
impl CanFrame {
    /// The node whose EMCY this frame is, by the pre-defined connection
    /// set: a classic 11-bit data frame on 0x081-0x0FF (node = id - 0x80).
    pub fn emcy_node(&self) -> Option<NodeId> {
        if self.kind != FrameKind::Data || self.extended {
            return None;
        }
        emcy_node(self.id)
    }

    /// The node an NMT boot-up frame (0x700 + node, one byte 0x00) announces.
    pub fn boot_node(&self) -> Option<NodeId> {
        if self.kind != FrameKind::Data || self.extended {
            return None;
        }
        boot_node(self.id, &self.data)
    }
}

/// A decoded EMCY payload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Emcy {
    /// The emergency error code (bytes 0-1, little-endian); 0x0000 is a reset.
    pub code: u16,
    /// The error register (object 0x1001) sent with it (byte 2).
    pub register: Register,
    /// Bytes 3-7 as received (fewer on short frames).
    manufacturer: [u8; 5],
    manufacturer_len: u8,
    /// Data bytes the frame carried.
    pub len: u8,
}

/// An EMCY frame too short to carry code and register: its data bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooShort(pub usize);

impl std::error::Error for TooShort {}

impl fmt::Display for TooShort {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "EMCY frame has {} data byte{}; code and error register need 3",
            self.0,
            if self.0 == 1 { "" } else { "s" }
        )
    }
}

impl Emcy {
    /// Decodes what is there: code (bytes 0-1, little-endian) and register
    /// (byte 2) are required; bytes 3-7 are kept as received.
    pub fn decode(data: &[u8]) -> Result<Emcy, TooShort> {
        let [lo, hi, reg, rest @ ..] = data else {
            return Err(TooShort(data.len()));
        };
        let mut manufacturer = [0u8; 5];
        let n = rest.len().min(5);
        manufacturer[..n].copy_from_slice(&rest[..n]);
        Ok(Emcy {
            code: u16::from_le_bytes([*lo, *hi]),
            register: Register(*reg),
            manufacturer,
            manufacturer_len: n as u8,
            len: data.len().min(8) as u8,
        })
    }

    /// Code 0x0000: error reset or no error.
    pub fn is_reset(&self) -> bool {
        self.code == 0
    }

    /// The manufacturer-specific bytes 3-7 as received (fewer on short
    /// frames); a [`Profile`](crate::Profile) says what they mean.
    pub fn manufacturer(&self) -> &[u8] {
        &self.manufacturer[..usize::from(self.manufacturer_len)]
    }

    /// What the CiA 301 and CiA 402 tables say about the code (a vendor's
    /// own rows: [`Profile::info`](crate::Profile::info)).
    pub fn info(&self) -> CodeInfo {
        codes::lookup(self.code)
    }

    /// The checks of emcy.md §7 that the frame alone decides, in a fixed order.
    pub fn frame_warnings(&self, info: &CodeInfo, out: &mut Vec<Warning>) {
        if self.len != 8 {
            out.push(Warning::ShortFrame { len: self.len });
        }
        let reg = self.register;
        if reg.0 & 0xFE != 0 && !reg.has(register::GENERIC) {
            out.push(Warning::NoGenericBit { register: reg.0 });
        }
        if reg.has(register::RESERVED) {
            out.push(Warning::ReservedBit);
        }
        if self.code == 0 {
            return;
        }
        if self.code <= 0x00FF {
            out.push(Warning::OddResetCode { code: self.code });
        }
        if info.class == Class::Undefined {
            out.push(Warning::UndefinedCode { code: self.code });
        }
        if reg.0 == 0 {
            out.push(Warning::EmptyRegister);
        } else if let Some(bit) = info.class.register_bit()
            && !reg.has(bit)
        {
            out.push(Warning::ClassRegisterMismatch {
                class: info.class,
                bit,
            });
        }
    }
}

/// A protocol oddity worth flagging; never fatal (real devices break all of
/// these). Printed as `tag: explanation`, the tag being stable for scripts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Warning {
    /// `short_frame`: fewer than 8 data bytes (CiA 301 says 8).
    ShortFrame {
        /// The data bytes the frame had.
        len: u8,
    },
    /// `no_generic_bit`: error bits set in the register, but not bit 0.
    NoGenericBit {
        /// The error register.
        register: u8,
    },
    /// `reserved_bit`: register bit 6, reserved by CiA 301, is set.
    ReservedBit,
    /// `odd_reset_code`: a code in 0x0001-0x00FF (the reset class has only 0x0000).
    OddResetCode {
        /// The code.
        code: u16,
    },
    /// `undefined_code`: the code is in no class of the tables.
    UndefinedCode {
        /// The code.
        code: u16,
    },
    /// `empty_register`: an error code with register 0.
    EmptyRegister,
    /// `class_register_mismatch`: the code's class has a register bit that is clear.
    ClassRegisterMismatch {
        /// The code's class.
        class: Class,
        /// The register bit of that class.
        bit: u8,
    },
    /// `reset_while_error_free`: a reset of a node with no active error.
    ResetWhileErrorFree,
    /// `partial_reset_while_error_free`: a partial reset of a node with no active error.
    PartialResetWhileErrorFree,
    /// `partial_reset_unattributed`: a partial reset whose register change
    /// names no active error.
    PartialResetUnattributed {
        /// The error register.
        register: u8,
    },
    /// `manufacturer_bytes_nonzero`: bytes the node's profile says are zero
    /// are not.
    ManufacturerBytesNonZero {
        /// The first such byte (3-7).
        first: u8,
        /// The last such byte (3-7).
        last: u8,
    },
    /// `profile_reserved_bit`: a register bit the node's profile reserves
    /// (must be 0) is set.
    ProfileReservedBit {
        /// The bit (0-7).
        bit: u8,
    },
}

impl Warning {
    /// The stable tag scripts can match on.
    pub fn tag(&self) -> &'static str {
        match self {
            Warning::ShortFrame { .. } => "short_frame",
            Warning::NoGenericBit { .. } => "no_generic_bit",
            Warning::ReservedBit => "reserved_bit",
            Warning::OddResetCode { .. } => "odd_reset_code",
            Warning::UndefinedCode { .. } => "undefined_code",
            Warning::EmptyRegister => "empty_register",
            Warning::ClassRegisterMismatch { .. } => "class_register_mismatch",
            Warning::ResetWhileErrorFree => "reset_while_error_free",
            Warning::PartialResetWhileErrorFree => "partial_reset_while_error_free",
            Warning::PartialResetUnattributed { .. } => "partial_reset_unattributed",
            Warning::ManufacturerBytesNonZero { .. } => "manufacturer_bytes_nonzero",
            Warning::ProfileReservedBit { .. } => "profile_reserved_bit",
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: ", self.tag())?;
        match *self {
            Warning::ShortFrame { len } => {
                write!(f, "{len} data bytes; CiA 301 EMCY frames carry 8")
            }
            Warning::NoGenericBit { register } => write!(
                f,
                "error register 0x{register:02X} has error bits but not bit 0 (generic)"
            ),
            Warning::ReservedBit => f.write_str("error register bit 6 (reserved) is set"),
            Warning::OddResetCode { code } => write!(
                f,
                "0x{code:04X} is in the reset class but only 0x0000 resets; treated as an error"
            ),
            Warning::UndefinedCode { code } => {
                write!(f, "0x{code:04X} is not defined by CiA 301 or CiA 402")
            }
            Warning::EmptyRegister => f.write_str("error code sent with error register 0x00"),
            Warning::ClassRegisterMismatch { class, bit } => write!(
                f,
                "{} error code but error register bit {bit} ({}) is not set",
                class.slug(),
                register::BIT_NAMES[usize::from(bit & 7)]
            ),
            Warning::ResetWhileErrorFree => {
                f.write_str("reset (0x0000, register 0x00) while the node is already error-free")
            }
            Warning::PartialResetWhileErrorFree => f.write_str(
                "partial reset (0x0000 with register bits set) while the node is error-free",
            ),
            Warning::PartialResetUnattributed { register } => write!(
                f,
                "partial reset with register 0x{register:02X} clears no active error by its class bit; which error ended is unknown"
            ),
            Warning::ManufacturerBytesNonZero { first, last } if first == last => write!(
                f,
                "byte {first} should be zero for this node's profile but is not"
            ),
            Warning::ManufacturerBytesNonZero { first, last } => write!(
                f,
                "bytes {first}-{last} should be zero for this node's profile but are not"
            ),
            Warning::ProfileReservedBit { bit } => write!(
                f,
                "error register bit {bit} is reserved (0) in this node's profile but is set"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warnings(data: &[u8]) -> Vec<&'static str> {
        let e = Emcy::decode(data).unwrap();
        let mut out = Vec::new();
        e.frame_warnings(&e.info(), &mut out);
        out.iter().map(Warning::tag).collect()
    }

    #[test]
    fn ids() {
        assert_eq!(emcy_node(0x080), None, "0x080 is SYNC");
        assert_eq!(emcy_node(0x081), Some(1));
        assert_eq!(emcy_node(0x0FF), Some(127));
        assert_eq!(emcy_node(0x100), None);
        assert_eq!(boot_node(0x705, &[0]), Some(5));
        assert_eq!(boot_node(0x705, &[0x05]), None, "heartbeat, not boot-up");
        assert_eq!(boot_node(0x705, &[0, 0]), None);
        assert_eq!(boot_node(0x700, &[0]), None);
        assert_eq!(boot_node(0x780, &[0]), None);
        assert_eq!(boot_node(0x77F, &[0]), Some(127));
        assert_eq!(boot_node(0x005, &[0]), None);
    }

    #[test]
    fn decodes_the_s300_example() {
        let e = Emcy::decode(&[0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]).unwrap();
        assert_eq!(e.code, 0x4310);
        assert_eq!(e.register, Register(0x08));
        assert_eq!(e.manufacturer(), [1, 0, 0, 0, 0]);
        assert_eq!(e.len, 8);
        assert!(!e.is_reset());
    }

    #[test]
    fn short_frames_decode_what_is_there() {
        let e = Emcy::decode(&[0x00, 0x00, 0x00]).unwrap();
        assert!(e.is_reset());
        assert!(e.manufacturer().is_empty());
        assert_eq!(Emcy::decode(&[0x10, 0x43]), Err(TooShort(2)));
        assert_eq!(Emcy::decode(&[]), Err(TooShort(0)));
        assert_eq!(
            TooShort(1).to_string(),
            "EMCY frame has 1 data byte; code and error register need 3"
        );
        assert_eq!(warnings(&[0x10, 0x43, 0x09, 0x01]), ["short_frame"]);
    }

    #[test]
    fn clean_frames_have_no_warnings() {
        assert!(warnings(&[0x10, 0x43, 0x09, 1, 0, 0, 0, 0]).is_empty());
        assert!(warnings(&[0, 0, 0, 0, 0, 0, 0, 0]).is_empty());
        assert!(warnings(&[0x00, 0xFF, 0x81, 0, 0, 0, 0, 0]).is_empty());
    }

    #[test]
    fn each_frame_check() {
        // Register 0x08 without the generic bit (the S300 sends exactly this).
        assert_eq!(
            warnings(&[0x10, 0x43, 0x08, 1, 0, 0, 0, 0]),
            ["no_generic_bit"]
        );
        assert_eq!(
            warnings(&[0x10, 0x43, 0x49, 0, 0, 0, 0, 0]),
            ["reserved_bit"]
        );
        // A current error with only the voltage bit.
        assert_eq!(
            warnings(&[0x10, 0x23, 0x05, 0, 0, 0, 0, 0]),
            ["class_register_mismatch"]
        );
        assert_eq!(
            warnings(&[0x30, 0x81, 0x01, 0, 0, 0, 0, 0]),
            ["class_register_mismatch"]
        );
        assert_eq!(
            warnings(&[0x12, 0x00, 0x01, 0, 0, 0, 0, 0]),
            ["odd_reset_code"]
        );
        assert_eq!(
            warnings(&[0x10, 0x43, 0x00, 0, 0, 0, 0, 0]),
            ["empty_register"]
        );
        assert_eq!(
            warnings(&[0x34, 0x12, 0x01, 0, 0, 0, 0, 0]),
            ["undefined_code"]
        );
    }

    #[test]
    fn warning_texts_start_with_their_tag() {
        let all = [
            Warning::ShortFrame { len: 5 },
            Warning::NoGenericBit { register: 8 },
            Warning::ReservedBit,
            Warning::OddResetCode { code: 0x12 },
            Warning::UndefinedCode { code: 0x1234 },
            Warning::EmptyRegister,
            Warning::ClassRegisterMismatch {
                class: Class::Current,
                bit: 1,
            },
            Warning::ResetWhileErrorFree,
            Warning::PartialResetWhileErrorFree,
            Warning::PartialResetUnattributed { register: 8 },
            Warning::ManufacturerBytesNonZero { first: 4, last: 7 },
            Warning::ProfileReservedBit { bit: 7 },
        ];
        for w in all {
            let text = w.to_string();
            assert!(text.starts_with(&format!("{}: ", w.tag())), "{text}");
        }
        assert_eq!(
            Warning::ClassRegisterMismatch {
                class: Class::Current,
                bit: 1
            }
            .to_string(),
            "class_register_mismatch: current error code but error register bit 1 (current) is not set"
        );
    }
}
