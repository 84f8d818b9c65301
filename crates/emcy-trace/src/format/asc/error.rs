//! An ASC error frame's fields, mapped to the SocketCAN representation
//! ([`crate::error_frame`]): the one place that says what each ASC
//! error-frame line means.
//!
//! | the line after `ErrorFrame` | error.h |
//! |---|---|
//! | nothing | class unknown (id 0, no data) |
//! | `ECC: 10100010` (binary) | the SJA1000 register ([`ErrorFrame::from_sja1000_ecc`]) |
//! | `Flags = .. CodeExt = .. Code = ..` | Vector's fields ([`vector::error_frame`]) |
//! | CAN FD: the error's text (`Stuff error, ...`) | [`TEXTS`], and `Tx` as the direction |

use crate::error_frame::{ErrorFrame, class, location, protocol};
use crate::format::vector;
use crate::hex;

use super::syntax::{Tokens, is};

/// The phrases a CAN FD `ErrorFrame` line's text starts with, first match
/// wins (so `Bit0 error` is not a `Bit error`), and what each sets.
pub(super) const TEXTS: [(&[u8], Reading); 7] = [
    (b"Not Acknowledge error", Reading::NoAck),
    (b"Bit0 error", Reading::Type(protocol::BIT0)),
    (b"Bit1 error", Reading::Type(protocol::BIT1)),
    (b"Bit error", Reading::Type(protocol::BIT)),
    (b"Stuff error", Reading::Type(protocol::STUFF)),
    (b"Form error", Reading::Type(protocol::FORM)),
    (b"CRC error", Reading::At(location::CRC_SEQUENCE)),
];

/// What a text says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Reading {
    /// A violation of this type.
    Type(u8),
    /// A violation at this place.
    At(u8),
    /// No ACK: a violation at the ACK slot, and the class that says it.
    NoAck,
}

/// A classic `T CH ErrorFrame ...` line's fields (`toks` after `ErrorFrame`).
pub(super) fn classic(mut toks: Tokens<'_>) -> ErrorFrame {
    let mut flags = None;
    let mut code = None;
    let mut code_ext = None;
    while let Some(t) = toks.next() {
        if is(t, b"ECC:") {
            if let Some(ecc) = toks.next().and_then(binary_byte) {
                return ErrorFrame::from_sja1000_ecc(ecc);
            }
            continue;
        }
        let slot = if is(t, b"Flags") {
            &mut flags
        } else if is(t, b"Code") {
            &mut code
        } else if is(t, b"CodeExt") {
            &mut code_ext
        } else {
            continue;
        };
        let mut ahead = toks.clone();
        if ahead.next() == Some(b"=")
            && let Some(value) = ahead.next().and_then(hex_value)
        {
            *slot = Some(value);
            toks = ahead;
        }
    }
    match (flags, code) {
        (None, None) if code_ext.is_none() => ErrorFrame::default(),
        _ => vector::error_frame(
            flags.unwrap_or(0),
            code.and_then(|c| u8::try_from(c).ok()).unwrap_or(0),
            code_ext.and_then(|c| u16::try_from(c).ok()),
        ),
    }
}

/// A `CANFD CH DIR ErrorFrame TEXT ...` line: the text after `ErrorFrame`.
pub(super) fn fd(transmitting: bool, text: &[u8]) -> ErrorFrame {
    let mut e = ErrorFrame::default();
    let found = TEXTS.iter().find(|(phrase, _)| {
        text.get(..phrase.len())
            .is_some_and(|head| head.eq_ignore_ascii_case(phrase))
    });
    match found.map(|(_, r)| *r) {
        Some(Reading::Type(kind)) => {
            e.violation(kind);
        }
        Some(Reading::At(place)) => {
            e.at(place);
        }
        Some(Reading::NoAck) => {
            e.at(location::ACK_SLOT).class |= class::NO_ACK;
        }
        None => return e,
    }
    if transmitting {
        e.transmitting();
    }
    e
}

/// `0xe` or `e` (Vector writes the prefix; a hand-made file may not).
fn hex_value(t: &[u8]) -> Option<u32> {
    let digits = t
        .strip_prefix(b"0x")
        .or_else(|| t.strip_prefix(b"0X"))
        .unwrap_or(t);
    if digits.is_empty() || digits.len() > 8 {
        return None;
    }
    hex::parse_u32(digits)
}

/// `10100010`: eight binary digits.
fn binary_byte(t: &[u8]) -> Option<u8> {
    if t.len() != 8 {
        return None;
    }
    t.iter().try_fold(0u8, |acc, b| match b {
        b'0' => Some(acc << 1),
        b'1' => Some((acc << 1) | 1),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error_frame::{LOCATION_BYTE, PROTOCOL_BYTE};

    fn of(e: ErrorFrame) -> (u32, u8, u8) {
        (e.class, e.data[PROTOCOL_BYTE], e.data[LOCATION_BYTE])
    }

    #[test]
    fn classic_lines() {
        let read = |s: &str| of(classic(Tokens::new(s.as_bytes())));
        assert_eq!(read(""), (0, 0, 0));
        assert_eq!(
            read("ECC: 10100010"),
            (0x88, protocol::STUFF, location::ID28_21)
        );
        assert_eq!(read("ECC: 1010"), (0, 0, 0));
        assert_eq!(
            read(
                "Flags = 0xe CodeExt = 0x20a2 Code = 0x82 ID = 0 DLC = 0 Position = 5 Length = 11300"
            ),
            (0x88, protocol::STUFF, 0)
        );
        assert_eq!(
            read("Flags = 0x1 Code = 0x02"),
            (0x88, protocol::BIT | protocol::TX, location::ID28_21)
        );
        assert_eq!(
            read("CodeExt = 0x3040"),
            (0x88, protocol::FORM | protocol::TX, 0)
        );
        assert_eq!(read("Flags = zz"), (0, 0, 0));
    }

    #[test]
    fn every_fd_text() {
        let rows: [(&str, bool, (u32, u8, u8)); 9] = [
            (
                "Not Acknowledge error, dominant error flag fffe",
                true,
                (0xA8, protocol::TX, location::ACK_SLOT),
            ),
            ("Bit0 error", false, (0x88, protocol::BIT0, 0)),
            (
                "Bit1 error, x",
                true,
                (0x88, protocol::BIT1 | protocol::TX, 0),
            ),
            ("Bit error", false, (0x88, protocol::BIT, 0)),
            ("stuff error", false, (0x88, protocol::STUFF, 0)),
            ("Form error", false, (0x88, protocol::FORM, 0)),
            ("CRC error", false, (0x88, 0, location::CRC_SEQUENCE)),
            ("Something else", true, (0, 0, 0)),
            ("", false, (0, 0, 0)),
        ];
        for (text, tx, want) in rows {
            assert_eq!(of(fd(tx, text.as_bytes())), want, "{text}");
        }
    }
}
