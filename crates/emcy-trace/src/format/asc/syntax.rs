//! The words of an ASC line: number bases, tokens, ids, DLCs, data bytes,
//! keywords and the events that are not frames.

use crate::hex;
use crate::{Reason, split_token, trim_start};

pub(super) const STANDARD_MAX: u32 = 0x7FF;
pub(super) const EXTENDED_MAX: u32 = 0x1FFF_FFFF;

/// CANFD line flags (log2asc/asc2log `ASC_F_*`): a CANFD line without FDF
/// carries a classic frame (`log2asc -f` writes classic frames this way).
pub(super) const FLAG_RTR: u32 = 0x10;
pub(super) const FLAG_FDF: u32 = 0x1000;

/// CAN FD DLC to payload length.
pub(super) const FD_LEN: [u8; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

/// Fields after the data of a CANFD line: message duration, message length
/// and flags are required; CRC and up to four bit-timing words may follow.
/// Vector, python-can and log2asc all write the full eight.
pub(super) const FD_TAIL_MIN: usize = 3;
pub(super) const FD_TAIL_FULL: usize = 8;

/// Optional key = value fields after the data of a classic frame line.
pub(super) const TAIL_KEYS: [&str; 3] = ["Length", "BitCount", "ID"];

/// Number base of ids and data bytes, set by the `base` header line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Base {
    Hex,
    Dec,
}

impl Base {
    pub(super) fn name(self) -> &'static str {
        match self {
            Base::Hex => "hexadecimal",
            Base::Dec => "decimal",
        }
    }
}

/// Whitespace-separated tokens that can be cloned to look ahead and that
/// expose the unread rest of the line (for the free-form tails).
#[derive(Clone)]
pub(super) struct Tokens<'a> {
    pub(super) rest: &'a [u8],
}

impl<'a> Tokens<'a> {
    pub(super) fn new(line: &'a [u8]) -> Self {
        Tokens { rest: line }
    }

    pub(super) fn rest(&self) -> &'a [u8] {
        trim_start(self.rest)
    }
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    fn next(&mut self) -> Option<&'a [u8]> {
        let s = trim_start(self.rest);
        if s.is_empty() {
            self.rest = s;
            return None;
        }
        let (token, rest) = split_token(s);
        self.rest = rest;
        Some(token)
    }
}

/// The tail keyword `s` starts with, if any (`Length =`, `Length=5`, ...).
pub(super) fn tail_key(s: &[u8]) -> Option<&'static str> {
    TAIL_KEYS.into_iter().find(|k| {
        s.starts_with(k.as_bytes()) && matches!(s.get(k.len()), None | Some(b' ' | b'\t' | b'='))
    })
}

/// Classic frame message flags (TE = transceiver error, WU = wake-up).
pub(super) fn is_message_flag(t: &[u8]) -> bool {
    matches!(t, b"TE" | b"WU" | b"XX")
}

/// `true` for TxRq (a transmit request, not a frame on the bus).
pub(super) fn is_tx_request(dir: &[u8]) -> Result<bool, Reason> {
    if is(dir, b"Rx") || is(dir, b"Tx") {
        Ok(false)
    } else if is(dir, b"TxRq") {
        Ok(true)
    } else {
        Err(format!(
            "unknown direction '{}' (expected Rx, Tx or TxRq)",
            show(dir)
        )
        .into())
    }
}

/// `ID` or `IDx` in the file's base; the `x` marks a 29-bit id.
pub(super) fn parse_id(token: &[u8], base: Base) -> Result<(u32, bool), Reason> {
    let (digits, extended) = match token.split_last() {
        Some((b'x' | b'X', head)) => (head, true),
        _ => (token, false),
    };
    let valid = !digits.is_empty()
        && match base {
            Base::Hex => digits.iter().all(|b| hex::nibble(*b).is_some()),
            Base::Dec => digits.iter().all(u8::is_ascii_digit),
        };
    if !valid {
        return Err(format!("id '{}' is not a {} number", show(token), base.name()).into());
    }
    let zeros = digits.iter().take_while(|b| **b == b'0').count();
    let significant = digits.get(zeros..).unwrap_or_default();
    let value = if significant.is_empty() {
        Some(0)
    } else {
        match base {
            Base::Hex => hex::parse_u32(significant),
            Base::Dec => hex::parse_dec_u32(significant),
        }
    };
    match value {
        Some(v) if extended && v <= EXTENDED_MAX => Ok((v, true)),
        Some(v) if !extended && v <= STANDARD_MAX => Ok((v, false)),
        _ if extended => Err(format!("extended id '{}' is above 1FFFFFFF", show(token)).into()),
        _ => Err(format!(
            "standard id '{}' is above 7FF (29-bit ids end in x)",
            show(token)
        )
        .into()),
    }
}

/// A DLC 0..=15: one hex digit, or two digits (hex, or decimal 10..15 in a
/// `base dec` file).
pub(super) fn parse_dlc(token: &[u8], base: Base) -> Option<u8> {
    let value = match (token, base) {
        ([d], _) => u32::from(hex::nibble(*d)?),
        ([_, _], Base::Hex) => hex::parse_u32(token)?,
        ([_, _], Base::Dec) => hex::parse_dec_u32(token)?,
        _ => return None,
    };
    u8::try_from(value).ok().filter(|v| *v <= 15)
}

/// One data byte: 1-2 hex digits, or a decimal 0..=255 in a `base dec` file.
pub(super) fn parse_data_byte(token: &[u8], base: Base) -> Option<u8> {
    match base {
        Base::Hex => match *token {
            [lo] => hex::nibble(lo),
            [hi, lo] => hex::parse_byte(hi, lo),
            _ => None,
        },
        Base::Dec if token.len() <= 3 => {
            hex::parse_dec_u32(token).and_then(|v| u8::try_from(v).ok())
        }
        Base::Dec => None,
    }
}

/// `Start of measurement` (English) / `Start der Messung` (German CANoe).
pub(super) fn start_of_measurement(toks: Tokens<'_>) -> bool {
    words(toks.clone(), &[b"Start", b"of", b"measurement"])
        || words(toks, &[b"Start", b"der", b"Messung"])
}

/// Documented Vector events that are not CAN frames (after `T`): LIN,
/// FlexRay, MOST, K-Line, Ethernet, AFDX, J1939 transport, variables, GPS,
/// comments, logging triggers.
pub(super) fn is_other_event(what: &[u8], mut rest: Tokens<'_>) -> bool {
    const KEYWORDS: [&[u8]; 8] = [
        b"SV:",
        b"GPS-Device:",
        b"Comment:",
        b"ETH",
        b"AFDX",
        b"Fr",
        b"J1939TP",
        b"DiagRequest",
    ];
    if KEYWORDS.iter().any(|k| is(what, k)) {
        return true;
    }
    if is(what, b"log") {
        // `log trigger event`, `log direct start (Nms)`, `log direct stop (Nms)`
        return rest
            .next()
            .is_some_and(|t| is(t, b"trigger") || is(t, b"direct"));
    }
    match what {
        // LIN channel: `L1`, `Li` (LIN_Channel "L"[xdigit i *]{1,4}).
        [b'L', tail @ ..] => {
            (1..=4).contains(&tail.len())
                && tail
                    .iter()
                    .all(|b| b.is_ascii_hexdigit() || *b == b'i' || *b == b'*')
        }
        // MOST channel: `M1`.
        [b'M', tail @ ..] => {
            (1..=2).contains(&tail.len()) && tail.iter().all(u8::is_ascii_hexdigit)
        }
        // K-Line port: `COM1`, `KL1`.
        [b'C', b'O', b'M', tail @ ..] | [b'K', b'L', tail @ ..] => {
            (1..=3).contains(&tail.len()) && is_digits(tail)
        }
        _ => false,
    }
}

/// True when the tokens are exactly `expect` (ASCII case-insensitive).
pub(super) fn words(mut toks: Tokens<'_>, expect: &[&[u8]]) -> bool {
    expect.iter().all(|w| toks.next().is_some_and(|t| is(t, w))) && toks.next().is_none()
}

pub(super) fn is(token: &[u8], word: &[u8]) -> bool {
    token.eq_ignore_ascii_case(word)
}

pub(super) fn starts_with_ic(token: &[u8], prefix: &[u8]) -> bool {
    token
        .get(..prefix.len())
        .is_some_and(|head| head.eq_ignore_ascii_case(prefix))
}

pub(super) fn is_digits(token: &[u8]) -> bool {
    !token.is_empty() && token.iter().all(u8::is_ascii_digit)
}

pub(super) fn is_hex(token: &[u8]) -> bool {
    !token.is_empty() && token.iter().all(u8::is_ascii_hexdigit)
}

/// A token for a reason: at most 32 bytes, non-printable bytes escaped so a
/// hostile trace cannot put control sequences on the terminal.
pub(super) fn show(token: &[u8]) -> String {
    const MAX: usize = 32;
    let cut = token.get(..MAX).unwrap_or(token);
    let mut s = cut.escape_ascii().to_string();
    if token.len() > MAX {
        s.push_str("...");
    }
    s
}
