//! What Vector's ASC and BLF share: the fields of an error frame (BLF's
//! `CAN_ERROR_EXT`, which ASC writes as `Flags`, `CodeExt` and `Code`),
//! mapped to the SocketCAN representation ([`crate::error_frame`]).
//!
//! `Flags` says which fields hold something: 1 the ECC is the SJA1000's
//! error code capture register, 2 it is Vector's CAN-Core error code, 4 the
//! bit position, 8 the frame's length in ns. The CAN-Core code has the
//! error type in bits 0-5 and the direction in bits 6-7; the extended flags
//! (`CodeExt`) have the SJA1000 segment in bits 0-4, the direction (1 =
//! receiving) in bit 5, the type in bits 6-11 and the extended direction in
//! bits 12-13. The bit position is not mapped: it counts bits of the frame
//! as the controller saw them, stuff bits or not, which the files do not
//! say, so no segment follows from it.

use crate::error_frame::{ErrorFrame, location, protocol};

/// `Flags` bit: the ECC is the SJA1000's register.
pub const ECC_IS_SJA1000: u32 = 0x1;
/// `Flags` bit: the ECC is Vector's CAN-Core error code.
pub const ECC_IS_CAN_CORE: u32 = 0x2;

/// The error frame the fields say: `flags`, the ECC (`Code`) and the
/// extended flags (`CodeExt`, when the record has them).
pub fn error_frame(flags: u32, ecc: u8, ext: Option<u16>) -> ErrorFrame {
    if flags & ECC_IS_SJA1000 != 0 {
        return ErrorFrame::from_sja1000_ecc(ecc);
    }
    let mut e = ErrorFrame::default();
    if flags & ECC_IS_CAN_CORE != 0 {
        core_code(&mut e, ecc & 0x3F);
        direction(&mut e, ecc >> 6);
    } else if let Some(ext) = ext.filter(|x| *x != 0) {
        core_code(&mut e, ((ext >> 6) & 0x3F) as u8);
        direction(&mut e, ((ext >> 12) & 0x3) as u8);
    }
    e
}

/// The CAN-Core error type. A CRC error has no type in error.h: its place,
/// the CRC sequence, says it; an ACK delimiter error is a form error there.
fn core_code(e: &mut ErrorFrame, code: u8) {
    match code {
        0 => e.violation(protocol::BIT),
        1 => e.violation(protocol::FORM),
        2 => e.violation(protocol::STUFF),
        4 => e.at(location::CRC_SEQUENCE),
        5 => e.violation(protocol::FORM).at(location::ACK_DELIMITER),
        _ => e.violation(protocol::UNSPECIFIED),
    };
}

/// The CAN-Core direction: 0 receiving, no ACK; 1 transmitting, no ACK;
/// 2 receiving; 3 transmitting.
fn direction(e: &mut ErrorFrame, dir: u8) {
    if dir & 1 != 0 {
        e.transmitting();
    }
    if dir == 1 {
        e.class |= crate::error_frame::class::NO_ACK;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error_frame::{LOCATION_BYTE, PROTOCOL_BYTE};

    fn read(flags: u32, ecc: u8, ext: Option<u16>) -> (u32, u8, u8) {
        let e = error_frame(flags, ecc, ext);
        (e.class, e.data[PROTOCOL_BYTE], e.data[LOCATION_BYTE])
    }

    #[test]
    fn every_can_core_code_and_direction() {
        let rx = 2 << 6;
        let tx = 3 << 6;
        let rows = [
            (rx, (0x88, protocol::BIT, 0)),
            (1 | rx, (0x88, protocol::FORM, 0)),
            (2 | rx, (0x88, protocol::STUFF, 0)),
            (3 | rx, (0x88, protocol::UNSPECIFIED, 0)),
            (
                4 | rx,
                (0x88, protocol::UNSPECIFIED, location::CRC_SEQUENCE),
            ),
            (5 | rx, (0x88, protocol::FORM, location::ACK_DELIMITER)),
            (2 | tx, (0x88, protocol::STUFF | protocol::TX, 0)),
            (3 | (1 << 6), (0xA8, protocol::TX, 0)),
            (3, (0x88, protocol::UNSPECIFIED, 0)),
        ];
        for (ecc, want) in rows {
            assert_eq!(read(ECC_IS_CAN_CORE, ecc, None), want, "code {ecc:#x}");
        }
    }

    #[test]
    fn the_flags_choose_the_reading_of_the_ecc() {
        // python-can's example line: Flags = 0xe CodeExt = 0x20a2 Code = 0x82.
        assert_eq!(read(0xE, 0x82, Some(0x20A2)), (0x88, protocol::STUFF, 0));
        // The same byte as an SJA1000 register: stuff, transmitting, ID28-21.
        assert_eq!(
            read(0x1, 0x82, None),
            (0x88, protocol::STUFF | protocol::TX, location::ID28_21)
        );
        // Only the extended flags: a form error while transmitting.
        assert_eq!(
            read(0, 0, Some((1 << 6) | (3 << 12))),
            (0x88, protocol::FORM | protocol::TX, 0)
        );
        // Nothing valid: a class we cannot say.
        assert_eq!(read(0, 0x82, None), (0, 0, 0));
        assert_eq!(read(0, 0, Some(0)), (0, 0, 0));
    }
}
