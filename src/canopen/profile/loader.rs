//! The profile file format (TOML, documented in docs/guide/profiles.md, "Vendor
//! profiles") and its loader: reading a file into a [`Profile`], checking
//! it as it goes, and answering every mistake with its line.

use std::collections::BTreeMap;
use std::ops::Range;

use serde::Deserialize;
use toml::Spanned;

use super::{FIRST_BYTE, Field, LAST_BYTE, Profile, ProfileError, Role, VendorCode};
use crate::canopen::codes::Tables;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileDoc {
    name: Spanned<String>,
    summary: Option<String>,
    base: Option<Spanned<String>>,
    tables: Option<Spanned<String>>,
    zero_bytes: Option<Vec<Spanned<i64>>>,
    reserved_register_bits: Option<Vec<Spanned<i64>>>,
    manufacturer_low_bytes: Option<Spanned<Vec<i64>>>,
    register_generic_bit: Option<bool>,
    register_class_bits: Option<bool>,
    #[serde(default)]
    register_bits: BTreeMap<Spanned<String>, Spanned<String>>,
    #[serde(default, rename = "field")]
    fields: Vec<Spanned<FieldDoc>>,
    #[serde(default)]
    codes: BTreeMap<Spanned<String>, Spanned<CodeDoc>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FieldDoc {
    name: Spanned<String>,
    byte: Spanned<i64>,
    size: Option<Spanned<i64>>,
    role: Option<Spanned<String>>,
    #[serde(default)]
    values: BTreeMap<Spanned<String>, Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CodeDoc {
    text: Spanned<String>,
    category: Option<Spanned<i64>>,
    fault: Option<Spanned<String>>,
}

/// Builds errors with line numbers from byte offsets into one text.
struct Errors<'a> {
    origin: &'a str,
    text: &'a str,
}

impl Errors<'_> {
    fn at(&self, span: Range<usize>, message: impl Into<String>) -> ProfileError {
        let end = span.start.min(self.text.len());
        let before = self.text.get(..end).unwrap_or("");
        ProfileError {
            origin: self.origin.to_owned(),
            line: Some(before.bytes().filter(|b| *b == b'\n').count() + 1),
            message: message.into(),
        }
    }

    fn toml_error(&self, e: &toml::de::Error) -> ProfileError {
        let message = e.message().trim().to_owned();
        match e.span() {
            Some(span) => self.at(span, message),
            None => ProfileError {
                origin: self.origin.to_owned(),
                line: None,
                message,
            },
        }
    }
}

/// A number written as a TOML string key: decimal, or hex with `0x`.
fn parse_number(text: &str) -> Option<u64> {
    let text = text.trim();
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => text.parse().ok(),
    }
}

fn is_json_key(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_lowercase())
        && chars.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

fn is_profile_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
}

fn byte_list(
    errors: &Errors<'_>,
    what: &str,
    items: &[Spanned<i64>],
    range: std::ops::RangeInclusive<i64>,
) -> Result<u8, ProfileError> {
    let mut mask = 0u8;
    for item in items {
        let value = *item.get_ref();
        if !range.contains(&value) {
            return Err(errors.at(
                item.span(),
                format!(
                    "{what} {value} is out of range ({}-{})",
                    range.start(),
                    range.end()
                ),
            ));
        }
        // In 0-7 by the check above.
        mask |= 1 << (value as u8);
    }
    Ok(mask)
}

pub(super) fn parse_with(
    origin: &str,
    text: &str,
    bases: &[Profile],
) -> Result<Profile, ProfileError> {
    let errors = Errors { origin, text };
    let doc: FileDoc = toml::from_str(text).map_err(|e| errors.toml_error(&e))?;

    let name = doc.name.get_ref().trim().to_owned();
    if !is_profile_name(&name) {
        return Err(errors.at(
            doc.name.span(),
            format!("profile name {name:?} must be letters, digits, '-', '_' or '.'"),
        ));
    }

    let mut profile = match &doc.base {
        Some(base) => {
            let Some(found) = bases.iter().find(|p| p.name == *base.get_ref()) else {
                let known: Vec<&str> = bases.iter().map(|p| p.name.as_str()).collect();
                return Err(errors.at(
                    base.span(),
                    format!(
                        "unknown base profile {:?} (built-ins: {})",
                        base.get_ref(),
                        known.join(", ")
                    ),
                ));
            };
            let mut p = found.clone();
            p.base = Some(found.name.clone());
            p.name = name.clone();
            p
        }
        None => Profile::empty(name.clone(), Tables::default()),
    };
    profile.summary = match &doc.summary {
        Some(summary) => summary.trim().to_owned(),
        None => match &profile.base {
            Some(base) => format!("user profile based on {base}"),
            None => "user profile".to_owned(),
        },
    };

    if let Some(tables) = &doc.tables {
        profile.tables = Tables::from_slug(tables.get_ref()).ok_or_else(|| {
            errors.at(
                tables.span(),
                format!(
                    "unknown tables {:?} (use \"cia301\" or \"cia402\")",
                    tables.get_ref()
                ),
            )
        })?;
    }

    if let Some(range) = &doc.manufacturer_low_bytes {
        let (lo, hi) = match range.get_ref().as_slice() {
            [lo, hi] if (0..=0xFF).contains(lo) && (*lo..=0xFF).contains(hi) => (*lo, *hi),
            _ => {
                return Err(errors.at(
                    range.span(),
                    "manufacturer_low_bytes must be [first, last] with 0 <= first <= last <= 0xFF",
                ));
            }
        };
        // Both in 0-255 by the match guard.
        profile.manufacturer_low_bytes = Some((lo as u8, hi as u8));
    }

    if let Some(bits) = &doc.reserved_register_bits {
        profile.reserved_bits = byte_list(&errors, "register bit", bits, 0..=7)?;
    }
    if let Some(set) = doc.register_generic_bit {
        profile.generic_bit = set;
    }
    if let Some(set) = doc.register_class_bits {
        profile.class_bits = set;
    }

    for (key, value) in &doc.register_bits {
        let bit = parse_number(key.get_ref())
            .filter(|bit| *bit <= 7)
            .ok_or_else(|| {
                errors.at(
                    key.span(),
                    format!("register bit {:?} is not a bit number 0-7", key.get_ref()),
                )
            })?;
        let text = value.get_ref().trim();
        if text.is_empty() {
            return Err(errors.at(value.span(), "register bit name is empty"));
        }
        if let Some(slot) = profile.bit_names.get_mut(bit as usize) {
            *slot = Some(text.to_owned());
        }
    }

    for (key, row) in &doc.codes {
        let code = key
            .get_ref()
            .trim()
            .strip_prefix("0x")
            .and_then(|hex| u16::from_str_radix(hex, 16).ok())
            .ok_or_else(|| {
                errors.at(
                    key.span(),
                    format!(
                        "error code {:?} must be hexadecimal with 0x, 0x0000-0xFFFF (e.g. \"0x4310\")",
                        key.get_ref()
                    ),
                )
            })?;
        let row = row.get_ref();
        let text = row.text.get_ref().trim();
        if text.is_empty() {
            return Err(errors.at(row.text.span(), "code text is empty"));
        }
        let category = match &row.category {
            Some(c) => Some(u8::try_from(*c.get_ref()).map_err(|_| {
                errors.at(
                    c.span(),
                    format!("category {} is out of range (0-255)", c.get_ref()),
                )
            })?),
            None => None,
        };
        let fault = match &row.fault {
            Some(f) if f.get_ref().trim().is_empty() => {
                return Err(errors.at(f.span(), "fault number is empty"));
            }
            Some(f) => Some(f.get_ref().trim().to_owned()),
            None => None,
        };
        profile.codes.insert(
            code,
            VendorCode {
                text: text.to_owned(),
                category,
                fault,
            },
        );
    }

    // Fields: a field named like an inherited one replaces it in place;
    // others are appended. Each new field is then checked against the rest.
    let mut spans: Vec<Option<Range<usize>>> = vec![None; profile.fields.len()];
    for doc_field in &doc.fields {
        let field = parse_field(&errors, doc_field)?;
        match profile.fields.iter().position(|f| f.name == field.name) {
            Some(i) => {
                if let (Some(slot), Some(span)) = (profile.fields.get_mut(i), spans.get_mut(i)) {
                    *slot = field;
                    *span = Some(doc_field.span());
                }
            }
            None => {
                profile.fields.push(field);
                spans.push(Some(doc_field.span()));
            }
        }
    }
    check_layout(&errors, &profile.fields, &spans)?;
    let field_bytes = profile
        .fields
        .iter()
        .flat_map(Field::bytes)
        .fold(0u8, |mask, byte| mask | (1 << byte));

    match &doc.zero_bytes {
        Some(list) => {
            let mask = byte_list(
                &errors,
                "byte",
                list,
                i64::from(FIRST_BYTE)..=i64::from(LAST_BYTE),
            )?;
            if let Some(item) = list
                .iter()
                .find(|item| field_bytes & (1 << (*item.get_ref() as u8)) != 0)
            {
                return Err(errors.at(
                    item.span(),
                    format!(
                        "byte {} is in zero_bytes but a field uses it",
                        item.get_ref()
                    ),
                ));
            }
            profile.zero_bytes = mask;
        }
        // Inherited: a field on a byte the base says is zero takes it over.
        None => profile.zero_bytes &= !field_bytes,
    }

    Ok(profile)
}

fn parse_field(errors: &Errors<'_>, doc: &Spanned<FieldDoc>) -> Result<Field, ProfileError> {
    let d = doc.get_ref();
    let name = d.name.get_ref().trim().to_owned();
    if !is_json_key(&name) {
        return Err(errors.at(
            d.name.span(),
            format!(
                "field name {name:?} must start with a-z and use only a-z, 0-9 and '_' (it is a JSON key)"
            ),
        ));
    }
    let first = *d.byte.get_ref();
    if !(i64::from(FIRST_BYTE)..=i64::from(LAST_BYTE)).contains(&first) {
        return Err(errors.at(
            d.byte.span(),
            format!("byte {first} is outside the manufacturer bytes 3-7"),
        ));
    }
    let size = d.size.as_ref().map_or(1, |s| *s.get_ref());
    if !(1..=5).contains(&size) || first + size - 1 > i64::from(LAST_BYTE) {
        let span = d.size.as_ref().map_or(d.byte.span(), Spanned::span);
        return Err(errors.at(
            span,
            format!("a field of {size} byte(s) at byte {first} does not fit in bytes 3-7"),
        ));
    }
    let role = match &d.role {
        None => None,
        Some(role) => Some(match role.get_ref().as_str() {
            "category" => Role::Category,
            "status_bit" => Role::StatusBit,
            other => {
                return Err(errors.at(
                    role.span(),
                    format!("unknown role {other:?} (use \"category\" or \"status_bit\")"),
                ));
            }
        }),
    };
    if role.is_some() && size != 1 {
        return Err(errors.at(
            doc.span(),
            format!("a field with a role is one byte; {name:?} has {size}"),
        ));
    }
    let max = if size >= 8 {
        u64::MAX
    } else {
        (1u64 << (8 * size)) - 1
    };
    let mut values: Vec<(u64, u64, String, Range<usize>)> = Vec::new();
    for (key, text) in &d.values {
        let key_text = key.get_ref().trim();
        let (lo, hi) = match key_text.split_once('-') {
            Some((lo, hi)) => (parse_number(lo), parse_number(hi)),
            None => (parse_number(key_text), parse_number(key_text)),
        };
        let (Some(lo), Some(hi)) = (lo, hi) else {
            return Err(errors.at(
                key.span(),
                format!(
                    "value {key_text:?} is not a number or range (e.g. \"41\", \"0x1E\", \"0x30-0x3F\")"
                ),
            ));
        };
        if lo > hi || hi > max {
            return Err(errors.at(
                key.span(),
                format!("value {key_text:?} does not fit field {name:?} (0-{max})"),
            ));
        }
        let text = text.get_ref().trim();
        if text.is_empty() {
            return Err(errors.at(key.span(), format!("value {key_text:?} has no text")));
        }
        values.push((lo, hi, text.to_owned(), key.span()));
    }
    values.sort_by_key(|(lo, ..)| *lo);
    for pair in values.windows(2) {
        if let [a, b] = pair
            && b.0 <= a.1
        {
            let (span_a, span_b) = (a.3.clone(), b.3.clone());
            // Report the later of the two in the file.
            let span = if span_a.start > span_b.start {
                span_a
            } else {
                span_b
            };
            return Err(errors.at(span, format!("values of field {name:?} overlap")));
        }
    }
    Ok(Field {
        text_key: format!("{name}_text"),
        name,
        first: first as u8,
        size: size as u8,
        role,
        values: values
            .into_iter()
            .map(|(lo, hi, text, _)| (lo, hi, text))
            .collect(),
    })
}

/// Fields must not share bytes, keys or roles. `spans` says where each field
/// was written in this file (None: inherited); an error is reported at the
/// field of this file involved.
fn check_layout(
    errors: &Errors<'_>,
    fields: &[Field],
    spans: &[Option<Range<usize>>],
) -> Result<(), ProfileError> {
    for (i, a) in fields.iter().enumerate() {
        for (j, b) in fields.iter().enumerate().skip(i + 1) {
            let problem = if a.bytes().any(|byte| b.bytes().contains(&byte)) {
                Some(format!("fields {:?} and {:?} share a byte", a.name, b.name))
            } else if [&a.name, &a.text_key].contains(&&b.name)
                || [&a.name, &a.text_key].contains(&&b.text_key)
            {
                Some(format!(
                    "fields {:?} and {:?} give the same JSON key",
                    a.name, b.name
                ))
            } else if a.role.is_some() && a.role == b.role {
                Some(format!(
                    "fields {:?} and {:?} have the same role",
                    a.name, b.name
                ))
            } else {
                None
            };
            if let Some(message) = problem {
                let span = spans
                    .get(j)
                    .cloned()
                    .flatten()
                    .or_else(|| spans.get(i).cloned().flatten())
                    .unwrap_or(0..0);
                return Err(errors.at(span, message));
            }
        }
    }
    Ok(())
}
