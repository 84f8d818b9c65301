//! CAN error frames as Linux SocketCAN represents them (`linux/can/error.h`),
//! which every reader hands over: the identifier holds the error classes,
//! the eight data bytes the details. This is CAN, not CANopen, so it sits
//! with the readers, below everything that interprets a trace.

use std::fmt;

/// candump's flag for an error frame, left in the id by some readers.
pub const ERROR_FLAG: u32 = 0x2000_0000;

/// The error classes of `error.h` (the bits of the identifier).
pub mod class {
    pub const TX_TIMEOUT: u32 = 0x001;
    pub const LOST_ARBITRATION: u32 = 0x002;
    pub const CONTROLLER: u32 = 0x004;
    pub const PROTOCOL: u32 = 0x008;
    pub const TRANSCEIVER: u32 = 0x010;
    pub const NO_ACK: u32 = 0x020;
    pub const BUS_OFF: u32 = 0x040;
    pub const BUS_ERROR: u32 = 0x080;
    pub const RESTARTED: u32 = 0x100;
    /// The TX and RX error counters are in data bytes 6 and 7.
    pub const COUNTERS: u32 = 0x200;
}

/// The controller status bits of data byte 1 (`CAN_ERR_CRTL_*`).
mod controller {
    pub const RX_OVERFLOW: u8 = 0x01;
    pub const TX_OVERFLOW: u8 = 0x02;
    pub const RX_WARNING: u8 = 0x04;
    pub const TX_WARNING: u8 = 0x08;
    pub const RX_PASSIVE: u8 = 0x10;
    pub const TX_PASSIVE: u8 = 0x20;
    pub const ACTIVE: u8 = 0x40;
}

/// What one error frame reports; a frame may report several at once.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ErrorKind {
    TxTimeout,
    LostArbitration,
    /// A controller problem of no more specific kind.
    Controller,
    RxOverflow,
    TxOverflow,
    RxWarning,
    TxWarning,
    RxPassive,
    TxPassive,
    /// The controller is back to error active.
    BackToActive,
    ProtocolViolation,
    Transceiver,
    NoAck,
    BusOff,
    BusError,
    Restarted,
    /// An error frame that names no class (the text formats' plain "error
    /// frame").
    Unknown,
}

impl ErrorKind {
    /// Every kind, in the order reports list them.
    pub const ALL: [ErrorKind; 17] = [
        ErrorKind::TxTimeout,
        ErrorKind::LostArbitration,
        ErrorKind::Controller,
        ErrorKind::RxOverflow,
        ErrorKind::TxOverflow,
        ErrorKind::RxWarning,
        ErrorKind::TxWarning,
        ErrorKind::RxPassive,
        ErrorKind::TxPassive,
        ErrorKind::BackToActive,
        ErrorKind::ProtocolViolation,
        ErrorKind::Transceiver,
        ErrorKind::NoAck,
        ErrorKind::BusOff,
        ErrorKind::BusError,
        ErrorKind::Restarted,
        ErrorKind::Unknown,
    ];

    /// Its place in [`ErrorKind::ALL`], for counting in an array.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The stable name in JSON (`kinds` keys) and CSV.
    pub fn slug(self) -> &'static str {
        match self {
            ErrorKind::TxTimeout => "tx_timeout",
            ErrorKind::LostArbitration => "lost_arbitration",
            ErrorKind::Controller => "controller",
            ErrorKind::RxOverflow => "rx_overflow",
            ErrorKind::TxOverflow => "tx_overflow",
            ErrorKind::RxWarning => "rx_warning",
            ErrorKind::TxWarning => "tx_warning",
            ErrorKind::RxPassive => "rx_passive",
            ErrorKind::TxPassive => "tx_passive",
            ErrorKind::BackToActive => "back_to_active",
            ErrorKind::ProtocolViolation => "protocol_violation",
            ErrorKind::Transceiver => "transceiver",
            ErrorKind::NoAck => "no_ack",
            ErrorKind::BusOff => "bus_off",
            ErrorKind::BusError => "bus_error",
            ErrorKind::Restarted => "restarted",
            ErrorKind::Unknown => "unknown",
        }
    }

    /// In words, for the table.
    pub fn words(self) -> &'static str {
        match self {
            ErrorKind::TxTimeout => "TX timeout",
            ErrorKind::LostArbitration => "lost arbitration",
            ErrorKind::Controller => "controller problem",
            ErrorKind::RxOverflow => "RX buffer overflow",
            ErrorKind::TxOverflow => "TX buffer overflow",
            ErrorKind::RxWarning => "RX error warning",
            ErrorKind::TxWarning => "TX error warning",
            ErrorKind::RxPassive => "RX error passive",
            ErrorKind::TxPassive => "TX error passive",
            ErrorKind::BackToActive => "back to error active",
            ErrorKind::ProtocolViolation => "protocol violation",
            ErrorKind::Transceiver => "transceiver",
            ErrorKind::NoAck => "no ACK",
            ErrorKind::BusOff => "bus-off",
            ErrorKind::BusError => "bus error",
            ErrorKind::Restarted => "controller restarted",
            ErrorKind::Unknown => "unspecified",
        }
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.slug())
    }
}

/// A set of [`ErrorKind`]s, one bit each.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Kinds(u32);

impl Kinds {
    pub fn insert(&mut self, kind: ErrorKind) {
        self.0 |= 1 << kind.index();
    }

    pub fn contains(self, kind: ErrorKind) -> bool {
        self.0 & (1 << kind.index()) != 0
    }

    /// The kinds in the set, in [`ErrorKind::ALL`]'s order.
    pub fn iter(self) -> impl Iterator<Item = ErrorKind> {
        ErrorKind::ALL
            .into_iter()
            .filter(move |k| self.contains(*k))
    }
}

/// One error frame, decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ErrorFrame {
    /// The class bits, candump's flag and bits `error.h` does not define
    /// masked off.
    pub classes: u32,
    pub kinds: Kinds,
    /// A protocol violation's type (data byte 2) and location (byte 3).
    pub protocol: Option<(u8, u8)>,
    /// A transceiver status (data byte 4).
    pub transceiver: Option<u8>,
    /// The TX and RX error counters (data bytes 6 and 7), when the frame
    /// says they are valid.
    pub counters: Option<(u8, u8)>,
}

/// The class bits `error.h` defines.
const CLASSES: u32 = 0x3FF;

impl ErrorFrame {
    /// Decodes an error frame's identifier and data. Bytes missing from a
    /// short frame read as zero (unspecified), so nothing here can fail.
    pub fn decode(id: u32, data: &[u8]) -> ErrorFrame {
        let classes = id & CLASSES;
        let byte = |i: usize| data.get(i).copied().unwrap_or(0);
        let mut kinds = Kinds::default();
        let has = |bit: u32| classes & bit != 0;
        if has(class::TX_TIMEOUT) {
            kinds.insert(ErrorKind::TxTimeout);
        }
        if has(class::LOST_ARBITRATION) {
            kinds.insert(ErrorKind::LostArbitration);
        }
        if has(class::CONTROLLER) {
            let status = byte(1);
            let table = [
                (controller::RX_OVERFLOW, ErrorKind::RxOverflow),
                (controller::TX_OVERFLOW, ErrorKind::TxOverflow),
                (controller::RX_WARNING, ErrorKind::RxWarning),
                (controller::TX_WARNING, ErrorKind::TxWarning),
                (controller::RX_PASSIVE, ErrorKind::RxPassive),
                (controller::TX_PASSIVE, ErrorKind::TxPassive),
                (controller::ACTIVE, ErrorKind::BackToActive),
            ];
            let before = kinds;
            for (bit, kind) in table {
                if status & bit != 0 {
                    kinds.insert(kind);
                }
            }
            if kinds == before {
                kinds.insert(ErrorKind::Controller);
            }
        }
        let protocol = has(class::PROTOCOL).then(|| {
            kinds.insert(ErrorKind::ProtocolViolation);
            (byte(2), byte(3))
        });
        let transceiver = has(class::TRANSCEIVER).then(|| {
            kinds.insert(ErrorKind::Transceiver);
            byte(4)
        });
        for (bit, kind) in [
            (class::NO_ACK, ErrorKind::NoAck),
            (class::BUS_OFF, ErrorKind::BusOff),
            (class::BUS_ERROR, ErrorKind::BusError),
            (class::RESTARTED, ErrorKind::Restarted),
        ] {
            if has(bit) {
                kinds.insert(kind);
            }
        }
        let counters = has(class::COUNTERS).then(|| (byte(6), byte(7)));
        // Only the counters, or no class at all: still an error frame.
        if kinds == Kinds::default() {
            kinds.insert(ErrorKind::Unknown);
        }
        ErrorFrame {
            classes,
            kinds,
            protocol,
            transceiver,
            counters,
        }
    }

    /// The controller went bus-off: the class says so, or the TX counter
    /// shows the controller at its limit. The counters are a byte, so the
    /// 256 at which a controller leaves the bus cannot be written: a TX
    /// count of 255 alongside TX error passive is the nearest a frame
    /// gets, and only the class is taken as proof.
    pub fn bus_off(&self) -> bool {
        self.kinds.contains(ErrorKind::BusOff)
    }

    /// The controller is back: restarted, or back to error active.
    pub fn recovered(&self) -> bool {
        self.kinds.contains(ErrorKind::Restarted) || self.kinds.contains(ErrorKind::BackToActive)
    }
}

/// A protocol violation's type (data byte 2, `CAN_ERR_PROT_*`) in words;
/// several bits may be set.
pub fn protocol_type_words(t: u8) -> String {
    const TYPES: [(u8, &str); 8] = [
        (0x01, "single bit error"),
        (0x02, "frame format error"),
        (0x04, "bit stuffing error"),
        (0x08, "unable to send dominant bit"),
        (0x10, "unable to send recessive bit"),
        (0x20, "bus overload"),
        (0x40, "active error announcement"),
        (0x80, "error on transmission"),
    ];
    let words: Vec<&str> = TYPES
        .iter()
        .filter(|(bit, _)| t & bit != 0)
        .map(|(_, w)| *w)
        .collect();
    if words.is_empty() {
        "unspecified".to_string()
    } else {
        words.join(", ")
    }
}

/// Where in the frame a protocol violation happened (data byte 3,
/// `CAN_ERR_PROT_LOC_*`).
pub fn location_words(loc: u8) -> &'static str {
    match loc {
        0x03 => "start of frame",
        0x02 => "ID bits 28-21",
        0x06 => "ID bits 20-18",
        0x04 => "substitute RTR",
        0x05 => "identifier extension",
        0x07 => "ID bits 17-13",
        0x0F => "ID bits 12-5",
        0x0E => "ID bits 4-0",
        0x0C => "RTR bit",
        0x0D => "reserved bit 1",
        0x09 => "reserved bit 0",
        0x0B => "data length code",
        0x0A => "data section",
        0x08 => "CRC sequence",
        0x18 => "CRC delimiter",
        0x19 => "ACK slot",
        0x1B => "ACK delimiter",
        0x1A => "end of frame",
        0x12 => "intermission",
        _ => "unspecified",
    }
}

/// A transceiver status (data byte 4, `CAN_ERR_TRX_*`).
pub fn transceiver_words(status: u8) -> &'static str {
    match status {
        0x04 => "CAN_H no wire",
        0x05 => "CAN_H short to BAT",
        0x06 => "CAN_H short to VCC",
        0x07 => "CAN_H short to GND",
        0x40 => "CAN_L no wire",
        0x50 => "CAN_L short to BAT",
        0x60 => "CAN_L short to VCC",
        0x70 => "CAN_L short to GND",
        0x80 => "CAN_L short to CAN_H",
        _ => "unspecified",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(id: u32, data: &[u8]) -> Vec<&'static str> {
        ErrorFrame::decode(id, data)
            .kinds
            .iter()
            .map(ErrorKind::slug)
            .collect()
    }

    #[test]
    fn every_class_bit_is_its_kind() {
        let rows: [(u32, &str); 8] = [
            (class::TX_TIMEOUT, "tx_timeout"),
            (class::LOST_ARBITRATION, "lost_arbitration"),
            (class::PROTOCOL, "protocol_violation"),
            (class::TRANSCEIVER, "transceiver"),
            (class::NO_ACK, "no_ack"),
            (class::BUS_OFF, "bus_off"),
            (class::BUS_ERROR, "bus_error"),
            (class::RESTARTED, "restarted"),
        ];
        for (bit, slug) in rows {
            assert_eq!(kinds(bit, &[0; 8]), [slug], "{bit:#x}");
            // candump's flag changes nothing.
            assert_eq!(kinds(bit | ERROR_FLAG, &[0; 8]), [slug], "{bit:#x}");
        }
    }

    #[test]
    fn every_controller_status_bit_is_its_kind() {
        let rows: [(u8, &str); 7] = [
            (0x01, "rx_overflow"),
            (0x02, "tx_overflow"),
            (0x04, "rx_warning"),
            (0x08, "tx_warning"),
            (0x10, "rx_passive"),
            (0x20, "tx_passive"),
            (0x40, "back_to_active"),
        ];
        for (bit, slug) in rows {
            assert_eq!(
                kinds(class::CONTROLLER, &[0, bit, 0, 0, 0, 0, 0, 0]),
                [slug]
            );
        }
        // No status bit: a controller problem of no known kind.
        assert_eq!(kinds(class::CONTROLLER, &[0; 8]), ["controller"]);
        // Both directions passive at once.
        assert_eq!(
            kinds(class::CONTROLLER, &[0, 0x30, 0, 0, 0, 0, 0, 0]),
            ["rx_passive", "tx_passive"]
        );
    }

    #[test]
    fn details_come_from_their_bytes() {
        let f = ErrorFrame::decode(
            class::PROTOCOL | class::TRANSCEIVER | class::COUNTERS,
            &[0, 0, 0x04, 0x0A, 0x40, 0, 97, 12],
        );
        assert_eq!(f.protocol, Some((0x04, 0x0A)));
        assert_eq!(protocol_type_words(0x04), "bit stuffing error");
        assert_eq!(location_words(0x0A), "data section");
        assert_eq!(f.transceiver, Some(0x40));
        assert_eq!(transceiver_words(0x40), "CAN_L no wire");
        assert_eq!(f.counters, Some((97, 12)));
        assert_eq!(
            protocol_type_words(0x81),
            "single bit error, error on transmission"
        );
        assert_eq!(protocol_type_words(0), "unspecified");
        assert_eq!(location_words(0x19), "ACK slot");
        assert_eq!(transceiver_words(0x80), "CAN_L short to CAN_H");
    }

    #[test]
    fn counters_only_when_the_class_says_so() {
        assert_eq!(
            ErrorFrame::decode(class::BUS_ERROR, &[0, 0, 0, 0, 0, 0, 9, 9]).counters,
            None
        );
        let f = ErrorFrame::decode(class::COUNTERS, &[0, 0, 0, 0, 0, 0, 130, 4]);
        assert_eq!(f.counters, Some((130, 4)));
        // Counters alone name no kind of error.
        assert_eq!(kinds(class::COUNTERS, &[0; 8]), ["unknown"]);
    }

    #[test]
    fn an_error_frame_without_class_or_data_is_unknown() {
        assert_eq!(kinds(0, &[]), ["unknown"]);
        // Short data reads as unspecified, never out of bounds.
        let f = ErrorFrame::decode(class::PROTOCOL | class::COUNTERS, &[0, 0, 0x02]);
        assert_eq!(f.protocol, Some((0x02, 0)));
        assert_eq!(f.counters, Some((0, 0)));
    }

    #[test]
    fn bus_off_and_recovery() {
        assert!(ErrorFrame::decode(class::BUS_OFF, &[]).bus_off());
        assert!(!ErrorFrame::decode(class::CONTROLLER, &[0, 0x20, 0, 0, 0, 0, 0, 0]).bus_off());
        assert!(ErrorFrame::decode(class::RESTARTED, &[]).recovered());
        assert!(ErrorFrame::decode(class::CONTROLLER, &[0, 0x40, 0, 0, 0, 0, 0, 0]).recovered());
        assert!(!ErrorFrame::decode(class::BUS_ERROR, &[]).recovered());
    }

    proptest::proptest! {
        /// Any class bits and data, short or long: a frame of at least one
        /// kind, with a detail exactly when its class says it has one.
        #[test]
        fn every_error_frame_decodes_to_a_kind(
            id in proptest::prelude::any::<u32>(),
            data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..9),
        ) {
            let f = ErrorFrame::decode(id, &data);
            proptest::prop_assert!(f.kinds.iter().next().is_some());
            proptest::prop_assert_eq!(f.classes, id & 0x3FF);
            proptest::prop_assert_eq!(f.protocol.is_some(), id & class::PROTOCOL != 0);
            proptest::prop_assert_eq!(f.transceiver.is_some(), id & class::TRANSCEIVER != 0);
            proptest::prop_assert_eq!(f.counters.is_some(), id & class::COUNTERS != 0);
            proptest::prop_assert_eq!(f.bus_off(), id & class::BUS_OFF != 0);
        }
    }

    #[test]
    fn kinds_list_in_one_order() {
        for (i, k) in ErrorKind::ALL.iter().enumerate() {
            assert_eq!(k.index(), i);
        }
    }
}
