//! The fields after the id of a frame line: a CANFD body, classic data
//! bytes, the optional tail.

use crate::hex;
use crate::{FrameKind, Payload, Reason, split_token, trim_start};

use super::syntax::{
    Base, FD_LEN, FD_TAIL_FULL, FD_TAIL_MIN, FLAG_FDF, FLAG_RTR, Tokens, is_digits, is_hex,
    is_message_flag, parse_data_byte, parse_dlc, show, tail_key,
};

/// What one CANFD layout reads from the fields after the id (or name).
pub(super) struct FdBody {
    pub(super) kind: FrameKind,
    pub(super) len: u8,
    pub(super) data: Payload,
    /// Number of fields after the data bytes (tie-break between layouts).
    pub(super) after_data: usize,
    /// The flags and the byte count disagree; the byte count won.
    pub(super) warning: Option<Reason>,
}

impl FdBody {
    pub(super) fn same_frame(&self, other: &FdBody) -> bool {
        self.kind == other.kind && self.len == other.len && self.data == other.data
    }
}

/// `BRS ESI DLC DATALEN BYTE* DUR LEN FLAGS [CRC [BTC...]]`, fully validated
/// so that a wrong guess about the symbolic name fails.
pub(super) fn fd_body(mut toks: Tokens<'_>, base: Base, wanted: bool) -> Result<FdBody, Reason> {
    let mut brs = false;
    for flag in ["BRS", "ESI"] {
        let t = toks
            .next()
            .ok_or_else(|| format!("CANFD line ends before the {flag} flag"))?;
        if t != b"0" && t != b"1" {
            return Err(format!("{flag} flag '{}' is not 0 or 1", show(t)).into());
        }
        brs |= flag == "BRS" && t == b"1";
    }
    let dlc_tok = toks.next().ok_or("CANFD line ends before the DLC")?;
    let dlc = parse_dlc(dlc_tok, Base::Hex)
        .ok_or_else(|| format!("DLC '{}' is not a hex digit 0-F", show(dlc_tok)))?;
    let len_tok = toks
        .next()
        .ok_or("CANFD line ends before the data length")?;
    let data_len = hex::parse_dec_u32(len_tok)
        .and_then(|n| u8::try_from(n).ok())
        .filter(|n| *n <= 64)
        .ok_or_else(|| format!("data length '{}' is not a decimal 0-64", show(len_tok)))?;
    let fd_len = FD_LEN.get(usize::from(dlc)).copied().unwrap_or(0);
    let classic_len = dlc.min(8);
    // FD length, classic length, or 0 for a remote frame: nothing else fits the DLC.
    if data_len != fd_len && data_len != classic_len && data_len != 0 {
        return Err(
            format!("data length {data_len} does not match DLC {dlc:X} ({fd_len} bytes)").into(),
        );
    }

    let mut data = Payload::new();
    for i in 0..data_len {
        let t = toks
            .next()
            .ok_or_else(|| format!("CANFD line ends after {i} of {data_len} data bytes"))?;
        let b = parse_data_byte(t, base).ok_or_else(|| {
            format!(
                "data byte {} '{}' is not a {} byte",
                i + 1,
                show(t),
                base.name()
            )
        })?;
        if wanted {
            data.push(b);
        }
    }

    let after_data = toks.clone().count();
    if after_data < FD_TAIL_MIN {
        return Err(format!(
            "CANFD line ends early: {after_data} of the 3 fields after the data \
             (message duration, message length, flags)"
        )
        .into());
    }
    if after_data > FD_TAIL_FULL {
        return Err(format!(
            "CANFD line has {after_data} fields after {data_len} data bytes, at most 8 \
             (duration, length, flags, CRC, bit timings)"
        )
        .into());
    }
    for field in ["message duration", "message length"] {
        let t = toks.next().unwrap_or_default();
        if !is_digits(t) {
            return Err(format!("CANFD {field} '{}' is not a decimal number", show(t)).into());
        }
    }
    let flags_tok = toks.next().unwrap_or_default();
    let flags = hex::parse_u32(flags_tok)
        .ok_or_else(|| format!("CANFD flags '{}' is not a hex number", show(flags_tok)))?;
    if let Some(t) = toks.find(|t| !is_hex(t)) {
        return Err(format!(
            "unexpected '{}' after the CANFD flags (CRC and bit timings are hex)",
            show(t)
        )
        .into());
    }

    // Only FD frames switch bit rate; this also catches a flags field cut
    // short (`303000` -> `3`), which would otherwise read as a classic frame.
    // Over 8 bytes the frame is FD whatever the flags say (below).
    if brs && flags & FLAG_FDF == 0 && data_len <= 8 {
        return Err(format!(
            "BRS is 1 but flags {flags:X} lack FDF 1000 (only FD frames switch bit rate)"
        )
        .into());
    }
    let mut warning = None;
    let (kind, len) = if flags & FLAG_FDF != 0 {
        if data_len != fd_len {
            return Err(format!(
                "FD frame: data length {data_len} does not match DLC {dlc:X} ({fd_len} bytes)"
            )
            .into());
        }
        (FrameKind::Fd, data_len)
    } else if data_len > 8 {
        // Only a CAN FD frame carries more than 8 bytes (and then
        // `data_len` is the DLC's FD length, checked above). python-can
        // writes such lines with flags 0 and reads them as FD by the count.
        warning = Some(
            format!(
                "CANFD line: flags {flags:X} lack FDF 1000 but {data_len} data bytes (DLC \
                 {dlc:X}) only fit a CAN FD frame; read as one"
            )
            .into(),
        );
        (FrameKind::Fd, data_len)
    } else if flags & FLAG_RTR != 0 {
        if data_len != 0 {
            return Err(
                format!("remote frame (flags {flags:X}) carries {data_len} data bytes").into(),
            );
        }
        (FrameKind::Remote, 0)
    } else {
        if data_len != classic_len {
            return Err(format!(
                "classic frame (flags {flags:X} lack FDF 1000): data length {data_len} \
                 does not match DLC {dlc:X}"
            )
            .into());
        }
        (FrameKind::Data, data_len)
    };
    Ok(FdBody {
        kind,
        len,
        data,
        after_data,
        warning,
    })
}

/// Reads exactly `expected` data bytes, stopping at the optional tail, and
/// names the exact count when it is wrong.
pub(super) fn classic_data(
    toks: &mut Tokens<'_>,
    expected: u8,
    base: Base,
    mut out: Option<&mut Payload>,
) -> Result<(), Reason> {
    let expected = usize::from(expected);
    let mut count = 0usize;
    loop {
        let mut peek = toks.clone();
        let Some(t) = peek.next() else { break };
        if tail_key(toks.rest()).is_some() || is_message_flag(t) {
            break;
        }
        match parse_data_byte(t, base) {
            Some(b) if count < expected => {
                if let Some(p) = out.as_deref_mut() {
                    p.push(b);
                }
            }
            Some(_) => {}
            None if count < expected => {
                return Err(format!(
                    "data byte {} '{}' is not a {} byte",
                    count.saturating_add(1),
                    show(t),
                    base.name()
                )
                .into());
            }
            // A word after the bytes: too many bytes or trailing junk.
            None => break,
        }
        count = count.saturating_add(1);
        *toks = peek;
    }
    if count != expected {
        return Err(format!("data has {count} bytes, DLC says {expected}").into());
    }
    Ok(())
}

/// The optional `Length = n BitCount = n [TE|WU|XX] ID = n[x]` fields; any
/// other text after the frame is an error.
pub(super) fn check_tail(mut s: &[u8]) -> Result<(), Reason> {
    loop {
        s = trim_start(s);
        if s.is_empty() {
            return Ok(());
        }
        let (token, after) = split_token(s);
        if is_message_flag(token) {
            s = after;
            continue;
        }
        let Some(key) = tail_key(s) else {
            return Err(format!("unexpected text after the frame: '{}'", show(token)).into());
        };
        let rest = trim_start(s.get(key.len()..).unwrap_or_default());
        let Some(rest) = rest.strip_prefix(b"=") else {
            return Err(format!("expected '=' after '{key}'").into());
        };
        let (value, after) = split_token(trim_start(rest));
        let digits = match key {
            // The id repeated in decimal, with `x` for 29-bit ids.
            "ID" => value
                .strip_suffix(b"x")
                .or_else(|| value.strip_suffix(b"X"))
                .unwrap_or(value),
            _ => value,
        };
        if !is_digits(digits) {
            return Err(format!("{key} value '{}' is not a decimal number", show(value)).into());
        }
        s = after;
    }
}
