//! Error frames in one representation for every format: the Linux
//! SocketCAN one (`linux/can/error.h`). A [`Frame`] of kind
//! [`FrameKind::Error`] has the error class bits as its `id` (without the
//! `CAN_ERR_FLAG` 0x20000000) and the eight data bytes as error.h lays them
//! out. `id == 0` with no data is an error frame whose class the trace
//! does not say (a text format that writes only `ErrorFrame`).
//!
//! candump and SocketCAN pcap already write this; the other formats map
//! their own fields to it, each in one place in its folder, with the pieces
//! they share here: [`ErrorFrame`] to build the bits, the SJA1000 error code
//! capture register (Vector's and PEAK's fields are that register's
//! layout), and the segment codes, which are the SJA1000's too.

use crate::{Frame, FrameKind, Payload, Timestamp};

/// Class bits (`Frame::id` of an error frame, `CAN_ERR_*`).
pub mod class {
    /// TX timeout (by the driver).
    pub const TX_TIMEOUT: u32 = 0x001;
    /// Lost arbitration; data\[0\] the bit.
    pub const LOST_ARBITRATION: u32 = 0x002;
    /// Controller problems; data\[1\].
    pub const CONTROLLER: u32 = 0x004;
    /// Protocol violations; data\[2\] the type, data\[3\] the location.
    pub const PROTOCOL: u32 = 0x008;
    /// Transceiver status; data\[4\].
    pub const TRANSCEIVER: u32 = 0x010;
    /// No ACK received on transmission.
    pub const NO_ACK: u32 = 0x020;
    /// Bus off.
    pub const BUS_OFF: u32 = 0x040;
    /// Bus error (may flood).
    pub const BUS_ERROR: u32 = 0x080;
    /// Controller restarted.
    pub const RESTARTED: u32 = 0x100;
    /// TX and RX error counters in data\[6\] and data\[7\].
    pub const COUNTERS: u32 = 0x200;
}

/// Controller status bits (data\[1\], `CAN_ERR_CRTL_*`).
pub mod controller {
    /// RX buffer overflow.
    pub const RX_OVERFLOW: u8 = 0x01;
    /// TX buffer overflow.
    pub const TX_OVERFLOW: u8 = 0x02;
    /// Reached the warning level for RX errors.
    pub const RX_WARNING: u8 = 0x04;
    /// Reached the warning level for TX errors.
    pub const TX_WARNING: u8 = 0x08;
    /// Reached the error passive status for RX.
    pub const RX_PASSIVE: u8 = 0x10;
    /// Reached the error passive status for TX.
    pub const TX_PASSIVE: u8 = 0x20;
    /// Recovered to error active.
    pub const ACTIVE: u8 = 0x40;
}

/// Protocol violation types (data\[2\], `CAN_ERR_PROT_*`).
pub mod protocol {
    /// Unspecified.
    pub const UNSPECIFIED: u8 = 0x00;
    /// Single bit error.
    pub const BIT: u8 = 0x01;
    /// Frame format error.
    pub const FORM: u8 = 0x02;
    /// Bit stuffing error.
    pub const STUFF: u8 = 0x04;
    /// Unable to send a dominant bit.
    pub const BIT0: u8 = 0x08;
    /// Unable to send a recessive bit.
    pub const BIT1: u8 = 0x10;
    /// Bus overload.
    pub const OVERLOAD: u8 = 0x20;
    /// Active error announcement.
    pub const ACTIVE: u8 = 0x40;
    /// The error occurred on transmission.
    pub const TX: u8 = 0x80;
}

/// Protocol violation locations (data\[3\], `CAN_ERR_PROT_LOC_*`): the
/// SJA1000's segment codes, which Vector's and PEAK's fields also use.
pub mod location {
    /// Unspecified.
    pub const UNSPECIFIED: u8 = 0x00;
    /// Identifier bits 28-21 (standard 10-3).
    pub const ID28_21: u8 = 0x02;
    /// Start of frame.
    pub const SOF: u8 = 0x03;
    /// CRC sequence.
    pub const CRC_SEQUENCE: u8 = 0x08;
    /// Data field.
    pub const DATA: u8 = 0x0A;
    /// CRC delimiter.
    pub const CRC_DELIMITER: u8 = 0x18;
    /// ACK slot.
    pub const ACK_SLOT: u8 = 0x19;
    /// End of frame.
    pub const EOF: u8 = 0x1A;
    /// ACK delimiter.
    pub const ACK_DELIMITER: u8 = 0x1B;
}

/// Index of the controller status byte.
pub const CONTROLLER_BYTE: usize = 1;
/// Index of the protocol type byte.
pub const PROTOCOL_BYTE: usize = 2;
/// Index of the protocol location byte.
pub const LOCATION_BYTE: usize = 3;
/// Index of the TX error counter.
pub const TX_COUNTER_BYTE: usize = 6;
/// Index of the RX error counter.
pub const RX_COUNTER_BYTE: usize = 7;

/// An error frame's class bits and data, built from what a format records.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ErrorFrame {
    /// The class bits ([`class`]).
    pub class: u32,
    /// The data bytes as error.h lays them out.
    pub data: [u8; 8],
}

impl ErrorFrame {
    /// A protocol violation of `kind` ([`protocol`]); a bus error too, as
    /// the kernel's drivers report every violation they see on the bus.
    pub fn violation(&mut self, kind: u8) -> &mut Self {
        self.class |= class::PROTOCOL | class::BUS_ERROR;
        self.data[PROTOCOL_BYTE] |= kind;
        self
    }

    /// Where the violation was ([`location`]).
    pub fn at(&mut self, location: u8) -> &mut Self {
        self.violation(protocol::UNSPECIFIED);
        self.data[LOCATION_BYTE] = location;
        self
    }

    /// The violation happened while the logging controller transmitted.
    pub fn transmitting(&mut self) -> &mut Self {
        self.violation(protocol::TX)
    }

    /// Controller status bits ([`controller`]).
    pub fn controller(&mut self, status: u8) -> &mut Self {
        self.class |= class::CONTROLLER;
        self.data[CONTROLLER_BYTE] |= status;
        self
    }

    /// The controller's TX and RX error counters.
    pub fn counters(&mut self, tx: u8, rx: u8) -> &mut Self {
        self.class |= class::COUNTERS;
        self.data[TX_COUNTER_BYTE] = tx;
        self.data[RX_COUNTER_BYTE] = rx;
        self
    }

    /// A transmitter that saw an error in the ACK slot got no ACK: the
    /// class says so, as drivers that know it (flexcan, m_can) do, so that
    /// every format's "no ACK" reads the same.
    pub fn with_ack_inferred(&mut self) -> &mut Self {
        if self.class & class::PROTOCOL != 0
            && self.data[PROTOCOL_BYTE] & protocol::TX != 0
            && self.data[LOCATION_BYTE] == location::ACK_SLOT
        {
            self.class |= class::NO_ACK;
        }
        self
    }

    /// The SJA1000's error code capture register: bits 7-6 the type (bit,
    /// form, stuff, other), bit 5 the direction (1 = receiving), bits 4-0
    /// the segment, which error.h's locations copy.
    pub fn from_sja1000_ecc(ecc: u8) -> ErrorFrame {
        let mut e = ErrorFrame::default();
        e.violation(match ecc >> 6 {
            0 => protocol::BIT,
            1 => protocol::FORM,
            2 => protocol::STUFF,
            _ => protocol::UNSPECIFIED,
        });
        e.at(ecc & 0x1F);
        if ecc & 0x20 == 0 {
            e.transmitting();
        }
        *e.with_ack_inferred()
    }

    /// The frame: 8 data bytes (`CAN_ERR_DLC`) when a class is known, none
    /// when it is not.
    pub fn frame(self, time: Option<Timestamp>, channel: &[u8]) -> Frame<'_> {
        if self.class == 0 {
            return Frame::error(time, channel);
        }
        Frame {
            time,
            channel,
            id: self.class,
            extended: false,
            kind: FrameKind::Error,
            len: 8,
            data: Payload::inline(self.data, 8),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sja1000_error_type_and_the_direction() {
        // (ECC, class, type byte, location)
        let rows = [
            (0x02, 0x88, protocol::BIT | protocol::TX, location::ID28_21),
            (0x62, 0x88, protocol::FORM, location::ID28_21),
            (0xA2, 0x88, protocol::STUFF, location::ID28_21),
            (
                0x88,
                0x88,
                protocol::STUFF | protocol::TX,
                location::CRC_SEQUENCE,
            ),
            (0xF9, 0x88, protocol::UNSPECIFIED, location::ACK_SLOT),
            (0xD9, 0xA8, protocol::TX, location::ACK_SLOT),
        ];
        for (ecc, class, kind, at) in rows {
            let e = ErrorFrame::from_sja1000_ecc(ecc);
            assert_eq!(
                (e.class, e.data[PROTOCOL_BYTE], e.data[LOCATION_BYTE]),
                (class, kind, at),
                "ECC {ecc:08b}"
            );
        }
    }

    #[test]
    fn an_unknown_class_is_an_empty_frame_and_a_known_one_has_eight_bytes() {
        let unknown = ErrorFrame::default().frame(None, b"1");
        assert_eq!((unknown.id, unknown.len), (0, 0));
        let mut e = ErrorFrame::default();
        e.counters(130, 7).controller(controller::TX_PASSIVE);
        let f = e.frame(None, b"1");
        assert_eq!((f.kind, f.id, f.len), (FrameKind::Error, 0x204, 8));
        assert_eq!(f.data.as_slice(), [0, 0x20, 0, 0, 0, 0, 130, 7]);
    }

    #[test]
    fn no_ack_is_inferred_only_for_a_transmitter_at_the_ack_slot() {
        let mut rx = ErrorFrame::default();
        rx.at(location::ACK_SLOT).with_ack_inferred();
        assert_eq!(rx.class & class::NO_ACK, 0);
        let mut tx_elsewhere = ErrorFrame::default();
        tx_elsewhere
            .at(location::DATA)
            .transmitting()
            .with_ack_inferred();
        assert_eq!(tx_elsewhere.class & class::NO_ACK, 0);
    }
}
