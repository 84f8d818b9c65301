//! `emcy-decode explain` rendered: what a code means, or what one raw
//! payload says (what users read off an EtherCAT master or a drive's
//! display), as text or JSON.

use std::fmt::Write as _;

use anyhow::Result;
use serde_json::json;

use crate::canopen::emcy::Emcy;
use crate::canopen::profile::{FieldValue, Profile};
use crate::canopen::register::{self, Register};
use crate::text::printable;

/// The text with each line escaped: profile texts come from user files.
fn printable_lines(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        out.push_str(&printable(line));
        out.push('\n');
    }
    out
}

fn register_bit_text(bit: Option<u8>) -> String {
    match bit {
        Some(b) => format!("bit {b} ({})", register::BIT_NAMES[usize::from(b & 7)]),
        None => "none (only bit 0, generic)".to_string(),
    }
}

/// `explain CODE` as text.
pub fn code_text(profile: &Profile, code: u16) -> String {
    let info = profile.info(code);
    let mut s = String::new();
    let _ = writeln!(s, "code         0x{code:04X}");
    let _ = writeln!(s, "profile      {}", profile.name());
    let _ = writeln!(s, "class        {}", info.class.slug());
    let _ = writeln!(s, "description  {}", profile.describe(code));
    if let Some(v) = profile.vendor_code(code) {
        if let Some(c) = v.category {
            let _ = writeln!(s, "category     {c}");
        }
        if let Some(f) = &v.fault {
            let _ = writeln!(s, "fault        {f}");
        }
    }
    let _ = writeln!(
        s,
        "register     {}",
        register_bit_text(info.class.register_bit())
    );
    let _ = writeln!(s, "listed       {}", if info.listed { "yes" } else { "no" });
    printable_lines(&s)
}

pub fn code_json(profile: &Profile, code: u16) -> serde_json::Value {
    let info = profile.info(code);
    let vendor = profile.vendor_code(code);
    json!({
        "code": format!("0x{code:04X}"),
        "profile": profile.name(),
        "class": info.class.slug(),
        "description": profile.describe(code),
        "category": vendor.and_then(|v| v.category),
        "fault": vendor.and_then(|v| v.fault.clone()),
        "register_bit": info.class.register_bit(),
        "listed": info.listed,
    })
}

/// `explain --data` as text.
pub fn payload_text(profile: &Profile, data: &[u8]) -> Result<String> {
    let emcy = decode(data)?;
    let info = profile.info(emcy.code);
    let mut warnings = Vec::new();
    emcy.frame_warnings(&info, &mut warnings);
    profile.frame_warnings(&emcy, &mut warnings);
    let mut s = String::new();
    let hex: Vec<String> = data.iter().map(|b| format!("{b:02X}")).collect();
    let _ = writeln!(s, "data          {}", hex.join(" "));
    let _ = writeln!(s, "profile       {}", profile.name());
    let _ = writeln!(s, "code          0x{:04X}", emcy.code);
    let _ = writeln!(s, "class         {}", info.class.slug());
    let _ = writeln!(s, "description   {}", profile.describe(emcy.code));
    let names: Vec<&str> = emcy.register.names().collect();
    let _ = writeln!(
        s,
        "register      0x{:02X} ({})",
        emcy.register.0,
        if names.is_empty() {
            "no bits".to_string()
        } else {
            names.join(", ")
        }
    );
    let mfr: Vec<String> = emcy
        .manufacturer()
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect();
    let _ = writeln!(
        s,
        "manufacturer  {}",
        if mfr.is_empty() {
            "-".to_string()
        } else {
            mfr.join(" ")
        }
    );
    if let Some(d) = profile.decode_manufacturer(&emcy) {
        // Values line up with the lines above (column 14) unless a key is
        // longer: then after it and a blank, never run into it.
        let width = d
            .fields
            .iter()
            .map(|(key, _)| key.chars().count() + 1)
            .max()
            .unwrap_or(0)
            .max(12);
        for (key, value) in &d.fields {
            let value = match value {
                FieldValue::Int(n) => n.to_string(),
                FieldValue::Text(t) => t.clone(),
            };
            let _ = writeln!(s, "  {key:<width$}{value}");
        }
    }
    if warnings.is_empty() {
        let _ = writeln!(s, "warnings      none");
    }
    for w in &warnings {
        let _ = writeln!(s, "warning       {w}");
    }
    Ok(printable_lines(&s))
}

pub fn payload_json(profile: &Profile, data: &[u8]) -> Result<serde_json::Value> {
    let emcy = decode(data)?;
    let info = profile.info(emcy.code);
    let mut warnings = Vec::new();
    emcy.frame_warnings(&info, &mut warnings);
    profile.frame_warnings(&emcy, &mut warnings);
    let decoded = profile.decode_manufacturer(&emcy).map(|d| {
        d.fields
            .into_iter()
            .map(|(k, v)| {
                let v = match v {
                    FieldValue::Int(n) => json!(n),
                    FieldValue::Text(t) => json!(t),
                };
                (k, v)
            })
            .collect::<serde_json::Map<_, _>>()
    });
    Ok(json!({
        "data": crate::trace::HexBytes(data).to_string(),
        "profile": profile.name(),
        "code": format!("0x{:04X}", emcy.code),
        "class": info.class.slug(),
        "description": profile.describe(emcy.code),
        "register": emcy.register.0,
        "register_bits": Register(emcy.register.0).names().collect::<Vec<_>>(),
        "manufacturer": crate::trace::HexBytes(emcy.manufacturer()).to_string(),
        "manufacturer_decoded": decoded,
        "warnings": warnings.iter().map(|w| w.to_string()).collect::<Vec<_>>(),
    }))
}

fn decode(data: &[u8]) -> Result<Emcy> {
    Emcy::decode(data).map_err(|e| anyhow::anyhow!("{e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cia402() -> &'static Profile {
        crate::canopen::profile_choice::default_profile()
    }

    #[test]
    fn payload_needs_three_bytes() {
        let err = payload_text(cia402(), &[0x10, 0x43])
            .unwrap_err()
            .to_string();
        assert!(err.contains("need 3"), "{err}");
    }

    #[test]
    fn codes() {
        assert!(code_text(cia402(), 0x4310).contains("bit 3 (temperature)"));
        assert_eq!(code_json(cia402(), 0x4310)["register_bit"], 3);
    }
}
