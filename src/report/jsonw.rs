//! The JSON objects of the public contract, written straight into a byte
//! buffer. serde + `core::fmt` cost ~4,800 instructions per EMCY event (hex
//! per byte through the formatter, times formatted and re-parsed to stay
//! exact); a trace that is 30% EMCY is bound by this, so the hot path writes
//! bytes. Escaping follows serde_json exactly (same golden output), and
//! [`pretty`] re-indents compact output the way serde_json's pretty printer
//! does, so both output formats come from this one module.

use std::collections::HashMap;
use std::io;
use std::ops::Range;
use std::sync::Arc;

use super::format;
use super::timefmt::{UNIX_FROM, calendar_second};
use crate::analyze::incident::{Incident, Occurrence};
use crate::analyze::traffic::ChannelReport;
use crate::analyze::{
    BootEvent, Bus, BusEvent, ChannelErrors, Counts, Diagnostic, DriveReport, EmcyEvent,
    EvidenceKind, Health, HealthEvent, HeartbeatReport, HistoryReport, InputReport, NodeIdentity,
    NodeReport, SdoTransfer, kind_counts,
};
use crate::cache::{Cache, profile_key, slot};
use crate::canopen::device_profile;
use crate::canopen::emcy::Warning;
use crate::canopen::lss::{self, Lss};
use crate::canopen::pdo::{Direction, Mapped};
use crate::canopen::profile::{Decoded, FieldValue};
use crate::canopen::register::Register;
use crate::canopen::sdo::transfer::Outcome;
use crate::timeline::Interval;
use crate::timeline::drive::Via as DriveVia;
use crate::trace::can_error::ErrorKind;
use crate::trace::time::SecondsText;
use crate::trace::{Format, Span, Timestamp};

/// A JSON string literal with serde_json's escaping: `"` `\` and control
/// characters; everything else (UTF-8 included) as is.
pub fn push_str(out: &mut Vec<u8>, s: &str) {
    out.push(b'"');
    let bytes = s.as_bytes();
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        let escape: &[u8] = match b {
            b'"' => b"\\\"",
            b'\\' => b"\\\\",
            b'\n' => b"\\n",
            b'\r' => b"\\r",
            b'\t' => b"\\t",
            0x08 => b"\\b",
            0x0C => b"\\f",
            0x00..=0x1F => b"",
            _ => continue,
        };
        out.extend_from_slice(&bytes[start..i]);
        if escape.is_empty() {
            out.extend_from_slice(b"\\u00");
            out.push(b"0123456789abcdef"[usize::from(b >> 4)]);
            out.push(b"0123456789abcdef"[usize::from(b & 15)]);
        } else {
            out.extend_from_slice(escape);
        }
        start = i + 1;
    }
    out.extend_from_slice(&bytes[start..]);
    out.push(b'"');
}

fn push_u64(out: &mut Vec<u8>, v: u64) {
    let mut b = itoa::Buffer::new();
    out.extend_from_slice(b.format(v).as_bytes());
}

/// `"0x4310"`
fn push_code(out: &mut Vec<u8>, code: u16) {
    let mut text = *b"\"0x0000\"";
    text[1..7].copy_from_slice(&format::code(code));
    out.extend_from_slice(&text);
}

/// `["0x4310","0x2310"]`
fn push_codes(out: &mut Vec<u8>, codes: &[u16]) {
    format::push_codes(out, codes.iter().copied(), &format::JSON_ARRAY);
}

/// `"1043080100000000"`
fn push_hex(out: &mut Vec<u8>, bytes: &[u8]) {
    out.push(b'"');
    format::push_hex(out, bytes);
    out.push(b'"');
}

/// A mapped object as `--pdo` writes one: `0x6041:16`, `0x6041.2:8`.
pub(crate) fn mapped_text(m: &Mapped) -> String {
    match m.object.sub {
        0 => format!("0x{:04X}:{}", m.object.index, m.bits),
        sub => format!("0x{:04X}.{sub}:{}", m.object.index, m.bits),
    }
}

/// `{"category":1,"category_text":"..."}` or `null`.
pub(crate) fn push_decoded(out: &mut Vec<u8>, decoded: Option<&Decoded>) {
    let Some(d) = decoded else {
        out.extend_from_slice(b"null");
        return;
    };
    let mut o = Obj::new(out);
    for (key, value) in &d.fields {
        match value {
            FieldValue::Int(n) => o.u64(key, *n),
            FieldValue::Text(t) => o.str(key, t),
        }
    }
    o.end();
}

/// `{"protocol_violation":3,"no_ack":1}`: the kinds seen, with counts.
fn kinds_object(out: &mut Vec<u8>, kinds: &[u64; ErrorKind::ALL.len()]) {
    let mut o = Obj::new(out);
    for (kind, n) in kind_counts(kinds) {
        o.u64(kind.slug(), n);
    }
    o.end();
}

fn optional_u8(out: &mut Vec<u8>, v: Option<u8>) {
    match v {
        Some(v) => push_u64(out, u64::from(v)),
        None => out.extend_from_slice(b"null"),
    }
}

/// A node's identity as it answered reads: each value in hex with the line
/// of the answer, the device type with the profile it names, the vendor id
/// with the vendor's name where our profiles know it.
fn identity(out: &mut Vec<u8>, id: &NodeIdentity) {
    let mut o = Obj::new(out);
    let fields = [
        ("device_type", id.device_type),
        ("vendor_id", id.vendor_id),
        ("product_code", id.product_code),
        ("revision", id.revision),
        ("serial", id.serial),
    ];
    for (key, field) in fields {
        let Some(f) = field else {
            o.null(key);
            continue;
        };
        let mut fo = Obj::new(o.key(key));
        fo.str("value", &format!("0x{:08X}", f.value));
        match key {
            "device_type" => fo.str("profile", &device_profile::describe(f.value)),
            "vendor_id" => match crate::canopen::profile::vendor_name(f.value) {
                Some(name) => fo.str("name", name),
                None => fo.null("name"),
            },
            _ => {}
        }
        fo.u64("line", f.line);
        fo.end();
    }
    let texts = [
        ("name", &id.name),
        ("hardware_version", &id.hardware_version),
        ("software_version", &id.software_version),
    ];
    for (key, text) in texts {
        match text {
            Some(t) => {
                let mut to = Obj::new(o.key(key));
                to.str("value", &t.text);
                to.u64("line", t.line);
                to.end();
            }
            None => o.null(key),
        }
    }
    o.end();
}

/// A number already formatted as JSON writes it.
fn push_str_raw(out: &mut Vec<u8>, number: &str) {
    out.extend_from_slice(number.as_bytes());
}

fn push_span(out: &mut Vec<u8>, s: Option<Span>) {
    match s {
        Some(s) => s.push_decimal(out),
        None => out.extend_from_slice(b"null"),
    }
}

/// Writes `"key":` (with the comma for every key but the first).
struct Obj<'a> {
    out: &'a mut Vec<u8>,
    first: bool,
}

impl<'a> Obj<'a> {
    fn new(out: &'a mut Vec<u8>) -> Self {
        out.push(b'{');
        Obj { out, first: true }
    }

    fn key(&mut self, key: &str) -> &mut Vec<u8> {
        if !self.first {
            self.out.push(b',');
        }
        self.first = false;
        self.out.push(b'"');
        self.out.extend_from_slice(key.as_bytes());
        self.out.extend_from_slice(b"\":");
        self.out
    }

    fn str(&mut self, key: &str, value: &str) {
        push_str(self.key(key), value);
    }

    fn u64(&mut self, key: &str, value: u64) {
        push_u64(self.key(key), value);
    }

    fn bool(&mut self, key: &str, value: bool) {
        self.key(key)
            .extend_from_slice(if value { b"true" } else { b"false" });
    }

    fn null(&mut self, key: &str) {
        self.key(key).extend_from_slice(b"null");
    }

    fn end(self) {
        self.out.push(b'}');
    }
}

/// A node's code descriptions as JSON strings, escaped once per node (its
/// error list can run to millions); shared with the helper threads that
/// render the errors.
#[derive(Clone, Default)]
pub struct JsonTexts(Arc<[(u16, Vec<u8>)]>);

impl JsonTexts {
    pub fn of(node: &NodeReport) -> JsonTexts {
        JsonTexts(
            node.descriptions
                .iter()
                .map(|(code, text)| {
                    let mut v = Vec::with_capacity(text.len() + 2);
                    push_str(&mut v, text);
                    (code, v)
                })
                .collect(),
        )
    }

    /// `code`'s description, quoted; `""` for a code the node never raised
    /// (its errors are all raised by it, so never).
    fn get(&self, code: u16) -> &[u8] {
        match self.0.binary_search_by_key(&code, |(c, _)| *c) {
            Ok(i) => self.0.get(i).map_or(b"\"\"", |(_, v)| v.as_slice()),
            Err(_) => b"\"\"",
        }
    }
}

/// The part of an EMCY event that depends only on its payload: `"code"` to
/// `"manufacturer"`. Real traces repeat the same few error frames.
#[derive(Clone, Copy, PartialEq)]
struct PayloadKey {
    bytes: [u8; 8],
    len: u8,
    /// The profile's address: it gives class, description and the decoded field.
    profile: usize,
}

/// Texts that repeat on every event, escaped once: descriptions, warnings,
/// payload fragments, the per-file prefix and channel names.
#[derive(Default)]
pub struct JsonWriter {
    /// Events indented as [`pretty`] at this level would (the JSON
    /// document), written directly: re-indenting compact text cost more than
    /// writing it. `None`: compact (ndjson).
    level: Option<usize>,
    warnings: HashMap<Warning, Vec<u8>>,
    payloads: Cache<PayloadKey, Vec<u8>, 256>,
    /// `{"type":"emcy","file":"…","line":` for the last file seen.
    emcy_prefix: (String, Vec<u8>),
    /// `,"channel":"…","node":` for the last channel seen.
    channel: (String, Vec<u8>),
    seconds: SecondsText,
    /// `YYYY-MM-DDTHH:MM:SS` of the last Unix seconds `_text`s showed, by
    /// second modulo 4: consecutive events share one, and the calendar is
    /// the costly part (an outage event names two times, seconds apart).
    iso_seconds: [Option<(u64, [u8; 19])>; 4],
}

/// `,"key":` of a member of the event object, one literal when compact.
macro_rules! key {
    ($writer:expr, $out:expr, $key:literal) => {
        match $writer.level {
            None => $out.extend_from_slice(concat!(",\"", $key, "\":").as_bytes()),
            Some(level) => JsonWriter::pretty_key($out, level, $key.as_bytes()),
        }
    };
}

impl JsonWriter {
    pub fn new() -> Self {
        Self::default()
    }

    /// EMCY events come out as `pretty(compact, level)` would give them.
    pub fn pretty(level: usize) -> Self {
        JsonWriter {
            level: Some(level),
            ..Self::default()
        }
    }

    /// A cached fragment in this writer's layout: `compact` as it is, or
    /// re-indented as it sits in the event (`inside` the object, or the
    /// object's start).
    fn layout(level: Option<usize>, inside: bool, compact: Vec<u8>) -> Vec<u8> {
        match level {
            None => compact,
            Some(level) => {
                let mut v = Vec::with_capacity(compact.len() * 2);
                Pretty::new(level + usize::from(inside)).feed(&compact, &mut v);
                v
            }
        }
    }

    /// `,"key": ` of a member of the indented event object.
    fn pretty_key(out: &mut Vec<u8>, level: usize, key: &[u8]) {
        out.push(b',');
        newline(out, level + 1);
        out.push(b'"');
        out.extend_from_slice(key);
        out.extend_from_slice(b"\": ");
    }

    /// An array member of the event object, items written by `item`.
    #[inline(always)]
    fn array<T: Copy>(
        &mut self,
        out: &mut Vec<u8>,
        items: &[T],
        mut item: impl FnMut(&mut Self, &mut Vec<u8>, T),
    ) {
        out.push(b'[');
        if items.is_empty() {
            out.push(b']');
            return;
        }
        for (i, t) in items.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            if let Some(level) = self.level {
                newline(out, level + 2);
            }
            item(self, out, *t);
        }
        if let Some(level) = self.level {
            newline(out, level + 1);
        }
        out.push(b']');
    }

    /// A time's `_text` (docs/guide/output.md, the JSON contract), the time's number just
    /// written at `number` in `out`: a JSON string of ISO-8601 UTC for a
    /// Unix time, else the number's own digits; `null` for none. Exact
    /// where a JSON number read as a double is not. The fraction is copied
    /// from the number, so only the calendar second is computed (once per
    /// second).
    fn time_text(&mut self, out: &mut Vec<u8>, number: Range<usize>, t: Option<Timestamp>) {
        let Some(t) = t else {
            out.extend_from_slice(b"null");
            return;
        };
        out.push(b'"');
        let secs = t.secs();
        let slot = &mut self.iso_seconds[(secs % 4) as usize];
        let second = match *slot {
            Some((s, text)) if s == secs => Some(text),
            _ if secs < UNIX_FROM => None,
            _ => {
                let text = calendar_second(secs);
                *slot = text.map(|text| (secs, text));
                text
            }
        };
        match second {
            Some(second) => {
                out.extend_from_slice(&second);
                let dot = out
                    .get(number.clone())
                    .and_then(|n| n.iter().position(|&b| b == b'.'));
                if let Some(dot) = dot {
                    out.extend_from_within(number.start + dot..number.end);
                }
                out.push(b'Z');
            }
            None => out.extend_from_within(number),
        }
        out.push(b'"');
    }

    /// `"key":<time>,"key_text":"<time>"` in an object (`keys`: the two).
    fn time_pair(&mut self, o: &mut Obj<'_>, keys: [&str; 2], t: Option<Timestamp>) {
        let buf = o.key(keys[0]);
        let at = buf.len();
        self.time(buf, t);
        let number = at..buf.len();
        let buf = o.key(keys[1]);
        self.time_text(buf, number, t);
    }

    /// A time, `null` for none; the seconds' text is kept for the next one.
    fn time(&mut self, out: &mut Vec<u8>, t: Option<Timestamp>) {
        match t {
            Some(t) => t.push_decimal_with(out, &mut self.seconds),
            None => out.extend_from_slice(b"null"),
        }
    }

    fn warning(&mut self, out: &mut Vec<u8>, w: Warning) {
        let text = self.warnings.entry(w).or_insert_with(|| {
            let mut v = Vec::new();
            push_str(&mut v, &w.to_string());
            v
        });
        out.extend_from_slice(text);
    }

    /// `"code":…,"manufacturer":"…"` for this payload, from the cache.
    fn payload(&mut self, out: &mut Vec<u8>, ev: &EmcyEvent<'_>) {
        let profile = ev.profile.profile;
        let mut key = PayloadKey {
            bytes: [0; 8],
            len: ev.data.len().min(8) as u8,
            profile: profile_key(profile),
        };
        key.bytes[..usize::from(key.len)].copy_from_slice(&ev.data[..usize::from(key.len)]);
        let slot =
            slot(u64::from_le_bytes(key.bytes) ^ u64::from(key.len) ^ ((key.profile as u64) << 8));
        let fragment = {
            let level = self.level;
            self.payloads.get(key, slot, || {
                let mut v = Vec::with_capacity(256);
                v.extend_from_slice(b",\"code\":");
                push_code(&mut v, ev.emcy.code);
                v.extend_from_slice(b",\"class\":\"");
                v.extend_from_slice(ev.info.class.slug().as_bytes());
                v.extend_from_slice(b"\",\"description\":");
                push_str(&mut v, ev.description);
                v.extend_from_slice(b",\"register\":");
                push_u64(&mut v, u64::from(ev.emcy.register.0));
                v.extend_from_slice(b",\"register_bits\":[");
                for (i, name) in Register(ev.emcy.register.0).names().enumerate() {
                    if i > 0 {
                        v.push(b',');
                    }
                    push_str(&mut v, name);
                }
                v.extend_from_slice(b"],\"manufacturer\":");
                push_hex(&mut v, ev.emcy.manufacturer());
                v.extend_from_slice(b",\"manufacturer_decoded\":");
                push_decoded(&mut v, ev.decoded);
                v.extend_from_slice(b",\"profile\":");
                push_str(&mut v, profile.name());
                Self::layout(level, true, v)
            })
        };
        out.extend_from_slice(fragment.map_or(&[], Vec::as_slice));
    }

    fn emcy_prefix(&mut self, out: &mut Vec<u8>, file: &str) {
        if self.emcy_prefix.0 != file || self.emcy_prefix.1.is_empty() {
            let mut v = b"{\"type\":\"emcy\",\"file\":".to_vec();
            push_str(&mut v, file);
            v.extend_from_slice(b",\"line\":");
            self.emcy_prefix = (file.to_string(), Self::layout(self.level, false, v));
        }
        out.extend_from_slice(&self.emcy_prefix.1);
    }

    fn channel(&mut self, out: &mut Vec<u8>, channel: &str) {
        if self.channel.0 != channel || self.channel.1.is_empty() {
            let mut v = b",\"channel\":".to_vec();
            push_str(&mut v, channel);
            v.extend_from_slice(b",\"node\":");
            self.channel = (channel.to_string(), Self::layout(self.level, true, v));
        }
        out.extend_from_slice(&self.channel.1);
    }

    /// The hot path: one event, as fixed fragments between the values.
    pub fn emcy(&mut self, out: &mut Vec<u8>, ev: &EmcyEvent<'_>) {
        out.reserve(1024);
        self.emcy_prefix(out, ev.file);
        push_u64(out, ev.line);
        key!(self, out, "time");
        let at = out.len();
        self.time(out, ev.time);
        let number = at..out.len();
        key!(self, out, "time_text");
        self.time_text(out, number, ev.time);
        self.channel(out, ev.channel);
        push_u64(out, u64::from(ev.node));
        key!(self, out, "cob_id");
        match ev.cob_id {
            Some(id) => push_u64(out, u64::from(id)),
            // A CoE emergency came on no CAN id.
            None => out.extend_from_slice(b"null"),
        }
        key!(self, out, "data");
        push_hex(out, ev.data);
        self.payload(out, ev);
        key!(self, out, "profile_source");
        out.push(b'"');
        out.extend_from_slice(ev.profile.source.slug().as_bytes());
        out.push(b'"');
        key!(self, out, "transition");
        match ev.transition {
            Some(t) => push_u64(out, u64::from(t)),
            None => out.extend_from_slice(b"null"),
        }
        key!(self, out, "state");
        out.push(b'"');
        out.extend_from_slice(ev.state.slug().as_bytes());
        out.push(b'"');
        key!(self, out, "active");
        self.array(out, ev.active, |_, out, c| push_code(out, c));
        // `active` was cut (docs/guide/output.md, the JSON contract): how many are active.
        if ev.active_total > ev.active.len() {
            key!(self, out, "active_truncated");
            push_u64(out, ev.active_total as u64);
        }
        key!(self, out, "cleared");
        self.array(out, ev.cleared, |_, out, c| push_code(out, c));
        key!(self, out, "warnings");
        self.array(out, ev.warnings, |w, out, warning| w.warning(out, warning));
        // Only for a communication error that came with error frames.
        if let Some(start) = ev.bus_error {
            key!(self, out, "bus_error");
            let at = out.len();
            self.time(out, Some(start));
            let number = at..out.len();
            key!(self, out, "bus_error_text");
            self.time_text(out, number, Some(start));
        }
        if let Some(level) = self.level {
            newline(out, level);
        }
        out.push(b'}');
    }

    pub fn boot(&mut self, out: &mut Vec<u8>, ev: &BootEvent<'_>) {
        let mut o = Obj::new(out);
        o.str("type", "boot");
        o.str("file", ev.file);
        o.u64("line", ev.line);
        self.time_pair(&mut o, ["time", "time_text"], ev.time);
        o.str("channel", ev.channel);
        o.u64("node", u64::from(ev.node));
        push_codes(o.key("cleared"), ev.cleared);
        o.end();
    }

    /// An NMT, heartbeat, SDO abort or error history event (docs/guide/output.md, JSON
    /// contract): rare next to EMCYs, written plainly.
    pub fn health(&mut self, out: &mut Vec<u8>, ev: &HealthEvent<'_>) {
        let mut o = Obj::new(out);
        o.str("type", ev.health.slug());
        o.str("file", ev.file);
        o.u64("line", ev.line);
        self.time_pair(&mut o, ["time", "time_text"], ev.time);
        o.str("channel", ev.channel);
        o.u64("node", u64::from(ev.node));
        match ev.health {
            Health::Nmt { state, via } => {
                o.str("state", state.slug());
                o.str("via", via.slug());
            }
            Health::HeartbeatLost {
                last_seen,
                last_seen_line,
                timeout,
                timeout_source,
                via,
            } => {
                self.time_pair(&mut o, ["last_seen", "last_seen_text"], *last_seen);
                o.u64("last_seen_line", *last_seen_line);
                push_span(o.key("timeout"), Some(*timeout));
                o.str("timeout_source", timeout_source.slug());
                o.str("via", via.slug());
            }
            Health::HeartbeatBack {
                silent,
                restarted,
                via,
            } => {
                push_span(o.key("silent"), Some(*silent));
                o.bool("restarted", *restarted);
                o.str("via", via.slug());
            }
            Health::SdoAbort {
                index,
                subindex,
                abort_code,
                text,
                by_server,
            } => {
                push_code(o.key("index"), *index);
                o.u64("subindex", u64::from(*subindex));
                o.str("abort_code", &format!("0x{abort_code:08X}"));
                o.str("text", text);
                o.str("by", if *by_server { "server" } else { "client" });
            }
            Health::ErrorHistory(h) => history_members(&mut o, h),
            Health::ErrorHistoryCleared => {}
            Health::DriveState {
                state,
                from,
                statusword,
                via,
            } => {
                o.str("state", state.slug());
                match from {
                    Some(f) => o.str("from", f.slug()),
                    None => o.null("from"),
                }
                o.str("statusword", &format!("0x{statusword:04X}"));
                o.str("via", via.slug());
                match via {
                    DriveVia::Pdo { cob_id } => o.u64("cob_id", u64::from(*cob_id)),
                    DriveVia::Sdo => o.null("cob_id"),
                }
            }
            Health::FaultReset { controlword } => {
                o.str("controlword", &format!("0x{controlword:04X}"));
            }
        }
        o.end();
    }

    /// An incident's keys after the common ones (docs/guide/incidents.md).
    fn incident(&mut self, o: &mut Obj<'_>, i: &Incident) {
        o.null("node");
        self.time_pair(o, ["start", "start_text"], Some(i.start));
        self.time_pair(o, ["end", "end_text"], Some(i.end));
        let buf = o.key("nodes");
        buf.push(b'[');
        for (k, n) in i.nodes.iter().enumerate() {
            if k > 0 {
                buf.push(b',');
            }
            buf.extend_from_slice(n.to_string().as_bytes());
        }
        buf.push(b']');
        let root = &i.events[i.root.event];
        {
            let mut r = Obj::new(o.key("root"));
            self.occurrence(&mut r, root);
            r.str("reason", &i.root.reason);
            r.bool("decided", i.root.decided());
            let buf = r.key("candidates");
            buf.push(b'[');
            if !i.root.decided() {
                for (k, &c) in i.root.candidates.iter().enumerate() {
                    if k > 0 {
                        buf.push(b',');
                    }
                    let mut item = Obj::new(buf);
                    self.occurrence(&mut item, &i.events[c]);
                    item.end();
                }
            }
            buf.push(b']');
            r.end();
        }
        {
            let mut f = Obj::new(o.key("first"));
            self.occurrence(&mut f, &i.events[i.first]);
            f.end();
        }
        let buf = o.key("events");
        buf.push(b'[');
        for (k, e) in i.events.iter().enumerate() {
            if k > 0 {
                buf.push(b',');
            }
            let mut item = Obj::new(buf);
            self.occurrence(&mut item, e);
            item.bool("context", e.context);
            item.end();
        }
        buf.push(b']');
        o.u64("events_total", i.events_total);
        let buf = o.key("links");
        buf.push(b'[');
        for (k, l) in i.links.iter().enumerate() {
            if k > 0 {
                buf.push(b',');
            }
            let mut item = Obj::new(buf);
            for (key, at) in [("from", l.from), ("to", l.to)] {
                let e = &i.events[at];
                let mut side = Obj::new(item.key(key));
                match e.node {
                    Some(n) => side.u64("node", u64::from(n)),
                    None => side.null("node"),
                }
                side.str("kind", e.kind.slug());
                side.u64("line", e.line);
                side.end();
            }
            item.str("reason", &l.reason);
            item.end();
        }
        buf.push(b']');
        o.str("summary", &i.summary);
    }

    /// An SDO transfer's members (docs/guide/output.md): `value` is the
    /// data in hex, its first 64 bytes when longer (`size`
    /// says how long, `value_hash` tells two long values apart), `null`
    /// when no data moved or the segments were not read.
    fn sdo(&mut self, o: &mut Obj<'_>, t: &SdoTransfer) {
        o.u64("node", u64::from(t.node));
        o.str("direction", t.direction.name());
        push_code(o.key("index"), t.object.index);
        o.u64("subindex", u64::from(t.object.sub));
        match &t.name {
            Some(name) => o.str("name", name),
            None => o.null("name"),
        }
        let shown = t.data.filter(|d| d.whole);
        match t.data.map(|d| d.size).or(t.indicated) {
            Some(size) => o.u64("size", u64::from(size)),
            None => o.null("size"),
        }
        match shown {
            Some(d) => push_hex(o.key("value"), d.shown()),
            None => o.null("value"),
        }
        match shown.filter(|d| !d.complete()) {
            Some(d) => o.str("value_hash", &format!("fnv1a64:{:016x}", d.hash)),
            None => o.null("value_hash"),
        }
        match &t.text {
            Some(text) => o.str("text", text),
            None => o.null("text"),
        }
        match t.protocol {
            Some(p) => o.str("transfer", p.name()),
            None => o.null("transfer"),
        }
        o.str("result", t.outcome.name());
        match t.outcome {
            Outcome::Abort { code, by_server } => {
                o.str("abort_code", &format!("0x{code:08X}"));
                o.str("abort_text", t.abort_text.unwrap_or_default());
                o.str("by", if by_server { "server" } else { "client" });
            }
            _ => {
                o.null("abort_code");
                o.null("abort_text");
                o.null("by");
            }
        }
        // `time` and `line` are its end too: the frame that ended it.
        self.time_pair(o, ["start", "start_text"], t.start.time);
        o.u64("start_line", t.start.line);
        self.time_pair(o, ["end", "end_text"], t.end.time);
    }

    /// `node`, `kind`, `code`, `time`, `time_text`, `line` of an incident's event.
    fn occurrence(&mut self, o: &mut Obj<'_>, e: &Occurrence) {
        match e.node {
            Some(n) => o.u64("node", u64::from(n)),
            None => o.null("node"),
        }
        o.str("kind", e.kind.slug());
        match e.code {
            Some(c) => push_code(o.key("code"), c),
            None => o.null("code"),
        }
        self.time_pair(o, ["time", "time_text"], Some(e.time));
        o.u64("line", e.line);
    }

    /// An error burst or a bus-off (docs/guide/output.md, JSON contract).
    pub fn bus(&mut self, out: &mut Vec<u8>, ev: &BusEvent<'_>) {
        let mut o = Obj::new(out);
        o.str("type", ev.bus.slug());
        o.str("file", ev.file);
        o.u64("line", ev.line);
        self.time_pair(&mut o, ["time", "time_text"], ev.time);
        o.str("channel", ev.channel);
        match ev.bus {
            Bus::Incident(i) => self.incident(&mut o, i),
            Bus::SyncMissed(gap) => {
                o.null("node");
                self.time_pair(&mut o, ["start", "start_text"], gap.start.time);
                o.u64("start_line", gap.start.line);
                self.time_pair(&mut o, ["end", "end_text"], gap.end.and_then(|e| e.time));
                push_span(o.key("period"), Some(gap.period));
                o.u64("missed", gap.missed);
            }
            Bus::Errors(b) => {
                o.null("node");
                self.time_pair(&mut o, ["start", "start_text"], b.start);
                self.time_pair(&mut o, ["end", "end_text"], b.end);
                o.u64("frames", b.frames);
                kinds_object(o.key("kinds"), &b.kinds);
                optional_u8(o.key("tx_errors_max"), b.tx_errors_max);
                optional_u8(o.key("rx_errors_max"), b.rx_errors_max);
            }
            Bus::BusOff(off) => {
                match off.node {
                    Some(n) => o.u64("node", u64::from(n)),
                    None => o.null("node"),
                }
                self.time_pair(&mut o, ["start", "start_text"], off.start);
                self.time_pair(&mut o, ["end", "end_text"], off.end);
                let buf = o.key("evidence");
                buf.push(b'[');
                for (i, e) in off.evidence.iter().enumerate() {
                    if i > 0 {
                        buf.push(b',');
                    }
                    let mut item = Obj::new(buf);
                    item.str("kind", e.kind.slug());
                    if let EvidenceKind::Emcy(code) = e.kind {
                        push_code(item.key("code"), code);
                    }
                    self.time_pair(&mut item, ["time", "time_text"], e.time);
                    item.u64("line", e.line);
                    item.end();
                }
                buf.push(b']');
            }
            Bus::Sdo(t) => self.sdo(&mut o, t),
            Bus::Lss(l) => {
                match l.node {
                    Some(n) => o.u64("node", u64::from(n)),
                    None => o.null("node"),
                }
                o.str("service", l.lss.slug());
                o.str("from", if l.from_master { "master" } else { "node" });
                o.str("text", &l.lss.words());
                match l.lss {
                    Lss::Answer {
                        service,
                        error,
                        specific,
                    } => o.str("result", &lss::result_words(service, error, specific)),
                    _ => o.null("result"),
                }
                match l.identity {
                    Some(id) => {
                        let mut io = Obj::new(o.key("identity"));
                        for (key, v) in [
                            ("vendor_id", id.vendor_id),
                            ("product_code", id.product_code),
                            ("revision", id.revision),
                            ("serial", id.serial),
                        ] {
                            match v {
                                Some(v) => io.u64(key, u64::from(v)),
                                None => io.null(key),
                            }
                        }
                        io.end();
                    }
                    None => o.null("identity"),
                }
            }
        }
        o.end();
    }

    /// A node object; `errors` in the order they were raised.
    ///
    /// A node that raised millions of errors makes one huge object: `flush`
    /// is handed the bytes built so far whenever they pass [`FLUSH_AT`], so
    /// memory stays bounded (it must drain `out`).
    pub fn node(
        &mut self,
        out: &mut Vec<u8>,
        input: &InputReport,
        node: &NodeReport,
        errors: impl IntoIterator<Item = Interval>,
        flush: &mut dyn FnMut(&mut Vec<u8>) -> io::Result<()>,
    ) -> io::Result<()> {
        self.node_head(out, input, node);
        let texts = JsonTexts::of(node);
        for (i, iv) in errors.into_iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            self.interval(out, &texts, &iv);
            if out.len() >= FLUSH_AT {
                flush(out)?;
            }
        }
        out.extend_from_slice(NODE_END);
        Ok(())
    }

    /// A node object up to its errors: `{"type":"node",…,"errors":[`. The
    /// errors follow ([`JsonWriter::errors`]), then [`NODE_END`].
    pub fn node_head(&mut self, out: &mut Vec<u8>, input: &InputReport, node: &NodeReport) {
        let file = input.file.as_str();
        let mut o = Obj::new(out);
        o.str("type", "node");
        o.str("file", file);
        o.str("channel", &node.channel);
        o.u64("node", u64::from(node.node));
        o.str("state", node.state.slug());
        push_codes(o.key("active"), &node.active);
        o.u64("emcy_count", node.emcy_count);
        o.str("profile", node.profile.name());
        o.str("profile_source", node.profile_source.slug());
        match &node.profile_reason {
            Some(r) => o.str("profile_reason", r),
            None => o.key("profile_reason").extend_from_slice(b"null"),
        }
        match node.device_type {
            Some(t) => {
                o.str("device_type", &format::device_type(t));
                o.str("device_profile", &device_profile::describe(t));
            }
            None => {
                o.null("device_type");
                o.null("device_profile");
            }
        }
        match &node.identity {
            Some(id) => identity(o.key("identity"), id),
            None => o.null("identity"),
        }
        format::push_code_counts(
            o.key("errors_seen"),
            node.stats
                .raised
                .iter()
                .map(|(&code, &count)| (code, count)),
            &format::JSON_COUNTS,
        );
        push_span(o.key("time_in_error"), node.time_in_error(input.last_time));
        match node.stats.longest {
            Some((code, duration)) => {
                let l = o.key("longest_error");
                let mut lo = Obj::new(l);
                push_code(lo.key("code"), code);
                push_span(lo.key("duration"), Some(duration));
                lo.end();
            }
            None => o.key("longest_error").extend_from_slice(b"null"),
        }
        self.time_pair(
            &mut o,
            ["first_emcy", "first_emcy_text"],
            node.stats.first_emcy.and_then(|a| a.time),
        );
        self.time_pair(
            &mut o,
            ["last_emcy", "last_emcy_text"],
            node.stats.last_emcy.and_then(|a| a.time),
        );
        match node.nmt_state {
            Some(state) => o.str("nmt_state", state.slug()),
            None => o.null("nmt_state"),
        }
        match node.nmt_commanded {
            Some(state) => o.str("nmt_commanded", state.slug()),
            None => o.null("nmt_commanded"),
        }
        match &node.heartbeat {
            Some(hb) => self.heartbeat(o.key("heartbeat"), hb),
            None => o.null("heartbeat"),
        }
        match &node.error_history {
            Some(h) => {
                let mut ho = Obj::new(o.key("error_history"));
                history_members(&mut ho, h);
                self.time_pair(&mut ho, ["time", "time_text"], h.time);
                ho.u64("line", h.line);
                ho.end();
            }
            None => o.null("error_history"),
        }
        // Only nodes with a drive: other nodes' objects stay as they were.
        if let Some(drive) = &node.drive {
            self.drive(o.key("axis"), drive);
        }
        o.key("errors").push(b'[');
    }

    /// A node's `drive` object: its CiA 402 drive.
    fn drive(&mut self, out: &mut Vec<u8>, drive: &DriveReport) {
        let mut o = Obj::new(out);
        match drive.state {
            Some(s) => o.str("state", s.slug()),
            None => o.null("state"),
        }
        match drive.statusword {
            Some(w) => o.str("statusword", &format!("0x{w:04X}")),
            None => o.null("statusword"),
        }
        o.u64("fault_count", drive.fault_count);
        o.u64("fault_resets", drive.fault_resets);
        let list = o.key("faults");
        list.push(b'[');
        for (i, f) in drive.faults.iter().enumerate() {
            if i > 0 {
                list.push(b',');
            }
            let mut fo = Obj::new(list);
            self.time_pair(&mut fo, ["start", "start_text"], f.start.time);
            fo.u64("start_line", f.start.line);
            self.time_pair(&mut fo, ["end", "end_text"], f.end.and_then(|e| e.time));
            match f.end {
                Some(e) => fo.u64("end_line", e.line),
                None => fo.null("end_line"),
            }
            push_span(fo.key("duration"), f.duration());
            match f.emcy_code {
                Some(c) => push_code(fo.key("emcy_code"), c),
                None => fo.null("emcy_code"),
            }
            match f.error_code {
                Some(c) => push_code(fo.key("error_code"), c),
                None => fo.null("error_code"),
            }
            self.time_pair(
                &mut fo,
                ["cleared_by", "cleared_by_text"],
                f.cleared_by.and_then(|c| c.time),
            );
            fo.end();
        }
        list.push(b']');
        let times = o.key("time_in_state");
        times.push(b'{');
        for (i, (state, span)) in drive.time_in_state.iter().enumerate() {
            if i > 0 {
                times.push(b',');
            }
            push_str(times, state.slug());
            times.push(b':');
            push_span(times, Some(*span));
        }
        times.push(b'}');
        let mut mo = Obj::new(o.key("mapping"));
        for direction in [Direction::Tpdo, Direction::Rpdo] {
            let list = mo.key(direction.slug());
            list.push(b'[');
            let of = drive
                .mappings
                .iter()
                .filter(|m| m.direction == Some(direction));
            for (i, m) in of.enumerate() {
                if i > 0 {
                    list.push(b',');
                }
                let mut po = Obj::new(list);
                po.u64("cob_id", u64::from(m.cob_id.id));
                let objects = po.key("objects");
                objects.push(b'[');
                for (j, mapped) in m.objects.iter().enumerate() {
                    if j > 0 {
                        objects.push(b',');
                    }
                    push_str(objects, &mapped_text(mapped));
                }
                objects.push(b']');
                po.str("source", m.source.slug());
                po.end();
            }
            list.push(b']');
        }
        mo.end();
        o.end();
    }

    /// A node's `heartbeat` object.
    fn heartbeat(&mut self, out: &mut Vec<u8>, hb: &HeartbeatReport) {
        let mut o = Obj::new(out);
        o.str("via", hb.via.slug());
        push_span(o.key("period"), hb.period);
        push_span(o.key("configured_period"), hb.configured_period);
        o.bool("drifts", hb.drifts);
        push_span(o.key("timeout"), hb.timeout.map(|t| t.0));
        match hb.timeout {
            Some((_, source)) => o.str("timeout_source", source.slug()),
            None => o.null("timeout_source"),
        }
        o.u64("lost", hb.lost);
        let list = o.key("outages");
        list.push(b'[');
        for (i, outage) in hb.outages.iter().enumerate() {
            if i > 0 {
                list.push(b',');
            }
            let mut oo = Obj::new(list);
            self.time_pair(&mut oo, ["start", "start_text"], Some(outage.start));
            self.time_pair(&mut oo, ["end", "end_text"], outage.end);
            push_span(oo.key("duration"), outage.duration());
            oo.end();
        }
        list.push(b']');
        o.bool("silent_at_end", hb.silent_at_end);
        match &hb.guarding {
            Some(g) => {
                let mut go = Obj::new(o.key("guarding"));
                match g.life_time_factor {
                    Some(f) => go.u64("life_time_factor", u64::from(f)),
                    None => go.null("life_time_factor"),
                }
                go.u64("requests", g.counts.requests);
                go.u64("replies", g.counts.replies);
                go.u64("unanswered", g.counts.unanswered);
                go.u64("toggle_errors", g.counts.toggle_errors);
                go.end();
            }
            None => o.null("guarding"),
        }
        o.end();
    }

    /// Errors of a node object, after `first` or not (a comma before).
    pub fn errors(
        &mut self,
        out: &mut Vec<u8>,
        texts: &JsonTexts,
        errors: &[Interval],
        first: bool,
    ) {
        for (i, iv) in errors.iter().enumerate() {
            if i > 0 || !first {
                out.push(b',');
            }
            self.interval(out, texts, iv);
        }
    }

    /// One error of a node object (a trace can have millions): fixed
    /// fragments between the values, like [`JsonWriter::emcy`].
    fn interval(&mut self, out: &mut Vec<u8>, texts: &JsonTexts, iv: &Interval) {
        let end_time = iv.end.and_then(|e| e.time);
        out.extend_from_slice(b"{\"code\":");
        push_code(out, iv.code);
        out.extend_from_slice(b",\"description\":");
        out.extend_from_slice(texts.get(iv.code));
        out.extend_from_slice(b",\"start\":");
        let at = out.len();
        self.time(out, iv.start.time);
        let number = at..out.len();
        out.extend_from_slice(b",\"start_text\":");
        self.time_text(out, number, iv.start.time);
        out.extend_from_slice(b",\"end\":");
        let at = out.len();
        self.time(out, end_time);
        let number = at..out.len();
        out.extend_from_slice(b",\"end_text\":");
        self.time_text(out, number, end_time);
        out.extend_from_slice(b",\"duration\":");
        match (iv.start.time, end_time) {
            (Some(start), Some(end)) => end.push_since(start, out),
            _ => out.extend_from_slice(b"null"),
        }
        out.extend_from_slice(b",\"cleared_by\":");
        match iv.cleared_by {
            // Slugs are plain ASCII words: nothing to escape.
            Some(c) => {
                out.push(b'"');
                out.extend_from_slice(c.slug().as_bytes());
                out.push(b'"');
            }
            None => out.extend_from_slice(b"null"),
        }
        out.extend_from_slice(b",\"start_line\":");
        push_u64(out, iv.start.line);
        out.extend_from_slice(b",\"end_line\":");
        match iv.end {
            Some(e) => push_u64(out, e.line),
            None => out.extend_from_slice(b"null"),
        }
        out.push(b'}');
    }

    pub fn input(&mut self, out: &mut Vec<u8>, input: &InputReport) {
        let mut o = Obj::new(out);
        o.str("type", "input");
        o.str("file", &input.file);
        match input.format {
            Some(f) => o.str("format", Format::name(f)),
            None => o.key("format").extend_from_slice(b"null"),
        }
        o.key("gzip")
            .extend_from_slice(if input.gzip { b"true" } else { b"false" });
        let Counts {
            lines,
            frames,
            emcy,
            skipped,
            malformed,
            boot,
            emcy_invalid,
            other_format,
            ethercat_frames,
            mailbox_messages,
            mailbox_retries,
            mailbox_empty_polls,
            dropped,
            annotated,
        } = input.counts;
        o.u64("lines", lines);
        o.u64("frames", frames);
        o.u64("emcy", emcy);
        o.u64("skipped", skipped);
        o.u64("malformed", malformed);
        o.u64("boot", boot);
        o.u64("emcy_invalid", emcy_invalid);
        o.u64("other_format", other_format);
        // Only for captures with EtherCAT: CAN inputs' objects stay as
        // they were.
        if ethercat_frames > 0 {
            o.u64("ethercat_frames", ethercat_frames);
            o.u64("mailbox_messages", mailbox_messages);
            o.u64("mailbox_retries", mailbox_retries);
            o.u64("mailbox_empty_polls", mailbox_empty_polls);
        }
        // Only when frames were lost: other inputs' objects stay as they were.
        if dropped > 0 {
            o.u64("dropped", dropped);
        }
        // Only for pastes with notes after frames, likewise.
        if annotated > 0 {
            o.u64("annotated", annotated);
        }
        self.time_pair(&mut o, ["first_time", "first_time_text"], input.first_time);
        self.time_pair(&mut o, ["last_time", "last_time_text"], input.last_time);
        // Only where times were summed: the times are not as written.
        if let Some(mode) = input.timestamps {
            o.str("timestamps", mode.name());
        }
        match &input.error {
            Some(e) => o.str("error", e),
            None => o.key("error").extend_from_slice(b"null"),
        }
        // Only when the master addressed ids that never answered: other
        // inputs' objects stay as they were.
        if !input.nmt_unanswered.is_empty() {
            let list = o.key("nmt_unanswered");
            list.push(b'[');
            for (i, u) in input.nmt_unanswered.iter().enumerate() {
                if i > 0 {
                    list.push(b',');
                }
                let mut uo = Obj::new(list);
                uo.str("request", u.slug());
                uo.u64("sent", u.sent);
                uo.u64("ids", u.ids);
                uo.end();
            }
            list.push(b']');
        }
        // Only for inputs with TIME frames, likewise.
        if let Some(t) = &input.time_producer {
            let mut to = Obj::new(o.key("time_producer"));
            to.u64("frames", t.frames);
            self.time_pair(&mut to, ["first", "first_text"], Some(t.first));
            push_span(to.key("first_offset"), t.first_offset);
            push_span(to.key("last_offset"), t.last_offset);
            to.end();
        }
        // Only for inputs with error frames, likewise.
        if !input.bus_errors.is_empty() {
            let list = o.key("bus_errors");
            list.push(b'[');
            for (i, c) in input.bus_errors.iter().enumerate() {
                if i > 0 {
                    list.push(b',');
                }
                self.channel_errors(list, c);
            }
            list.push(b']');
        }
        o.end();
    }

    /// A channel's traffic over an input: the `channel` object.
    pub fn channel_traffic(&mut self, out: &mut Vec<u8>, input: &InputReport, c: &ChannelReport) {
        let mut o = Obj::new(out);
        o.str("type", "channel");
        o.str("file", &input.file);
        o.str("channel", &c.channel);
        o.u64("frames", c.frames);
        o.u64("error_frames", c.error_frames);
        match &c.load {
            Some(l) => {
                let mut lo = Obj::new(o.key("load"));
                lo.u64("bit_rate", u64::from(l.bit_rate));
                lo.u64("bits", l.bits);
                push_str_raw(lo.key("mean_percent"), &format!("{:.2}", l.mean_percent));
                push_str_raw(lo.key("peak_percent"), &format!("{:.2}", l.peak_percent));
                lo.end();
            }
            None => o.null("load"),
        }
        let list = o.key("ids");
        list.push(b'[');
        for (i, id) in c.ids.iter().enumerate() {
            if i > 0 {
                list.push(b',');
            }
            let mut io = Obj::new(list);
            io.u64("cob_id", u64::from(id.cob_id));
            io.bool("extended", id.extended);
            io.str("service", id.service);
            match id.node {
                Some(n) => io.u64("node", u64::from(n)),
                None => io.null("node"),
            }
            io.u64("count", id.count);
            push_span(io.key("period"), id.period);
            push_span(io.key("jitter"), id.jitter);
            push_span(io.key("max_gap"), id.max_gap);
            match id.missed {
                Some(n) => io.u64("missed", n),
                None => io.null("missed"),
            }
            io.end();
        }
        list.push(b']');
        if c.other_ids > 0 {
            o.u64("other_ids", c.other_ids);
        }
        o.end();
    }

    /// One channel's error frames and bus-offs over an input.
    fn channel_errors(&mut self, out: &mut Vec<u8>, c: &ChannelErrors) {
        let mut o = Obj::new(out);
        o.str("channel", &c.channel);
        o.u64("error_frames", c.frames);
        kinds_object(o.key("kinds"), &c.kinds);
        o.u64("bursts", c.bursts);
        optional_u8(o.key("tx_errors_max"), c.tx_errors_max);
        optional_u8(o.key("rx_errors_max"), c.rx_errors_max);
        o.u64("bus_off_count", c.bus_off_count);
        let list = o.key("bus_offs");
        list.push(b'[');
        for (i, b) in c.bus_offs.iter().enumerate() {
            if i > 0 {
                list.push(b',');
            }
            let mut bo = Obj::new(list);
            match b.node {
                Some(n) => bo.u64("node", u64::from(n)),
                None => bo.null("node"),
            }
            self.time_pair(&mut bo, ["start", "start_text"], b.start);
            self.time_pair(&mut bo, ["end", "end_text"], b.end);
            bo.end();
        }
        list.push(b']');
        o.end();
    }

    pub fn diagnostic(&mut self, out: &mut Vec<u8>, d: &Diagnostic) {
        let mut o = Obj::new(out);
        o.str("file", &d.file);
        o.u64("line", d.line);
        o.str("message", &d.message);
        o.end();
    }
}

/// `"entries":[…],"count":n,"complete":b` of a 0x1003 read-out.
fn history_members(o: &mut Obj<'_>, h: &HistoryReport) {
    let list = o.key("entries");
    list.push(b'[');
    for (i, e) in h.entries.iter().enumerate() {
        if i > 0 {
            list.push(b',');
        }
        let mut eo = Obj::new(list);
        push_code(eo.key("code"), e.code);
        push_code(eo.key("info"), e.info);
        eo.str("description", &e.description);
        eo.bool("before_trace", e.before_trace);
        eo.end();
    }
    list.push(b']');
    match h.count {
        Some(c) => o.u64("count", u64::from(c)),
        None => o.null("count"),
    }
    o.bool("complete", h.complete);
}

/// Re-indents compact JSON exactly as serde_json's pretty printer (two
/// spaces, `"key": value`, empty `[]`/`{}` kept on one line), starting at
/// `level` levels of indentation. Bytes inside strings are copied as they are.
pub fn pretty(compact: &[u8], level: usize, out: &mut Vec<u8>) {
    Pretty::new(level).feed(compact, out);
}

/// A line break and `level` levels of indentation (two blanks each).
#[inline(always)]
fn newline(out: &mut Vec<u8>, level: usize) {
    const BLANKS: &[u8; 64] = &[b' '; 64];
    out.push(b'\n');
    let mut n = 2 * level;
    while n > 0 {
        let k = n.min(BLANKS.len());
        out.extend_from_slice(&BLANKS[..k]);
        n -= k;
    }
}

/// How many bytes of one JSON value are built before they are written.
pub const FLUSH_AT: usize = 64 * 1024;

/// The end of a node object after its errors.
pub const NODE_END: &[u8] = b"]}";

/// [`pretty`] in pieces: compact JSON may be fed in chunks split anywhere.
pub struct Pretty {
    depth: usize,
    in_string: bool,
    escaped: bool,
    /// An opening bracket whose next byte decides `[]` or a new line.
    open: Option<u8>,
}

impl Pretty {
    pub fn new(level: usize) -> Self {
        Pretty {
            depth: level,
            in_string: false,
            escaped: false,
            open: None,
        }
    }

    fn newline(&self, out: &mut Vec<u8>) {
        newline(out, self.depth);
    }

    /// Copies runs of plain bytes at once (string contents, numbers): only
    /// quotes, backslashes and structural characters stop the scan.
    pub fn feed(&mut self, compact: &[u8], out: &mut Vec<u8>) {
        out.reserve(compact.len() + compact.len() / 2);
        let mut rest = compact;
        while let Some((&b, tail)) = rest.split_first() {
            if let Some(open) = self.open.take() {
                let close = if open == b'{' { b'}' } else { b']' };
                out.push(open);
                if b == close {
                    out.push(close);
                    rest = tail;
                    continue;
                }
                self.depth += 1;
                self.newline(out);
            }
            if self.in_string {
                if self.escaped {
                    self.escaped = false;
                    out.push(b);
                    rest = tail;
                    continue;
                }
                let n = memchr::memchr2(b'"', b'\\', rest).unwrap_or(rest.len());
                let (run, after) = rest.split_at(n);
                out.extend_from_slice(run);
                rest = after;
                if let Some((&q, tail)) = rest.split_first() {
                    out.push(q);
                    if q == b'\\' {
                        self.escaped = true;
                    } else {
                        self.in_string = false;
                    }
                    rest = tail;
                }
                continue;
            }
            rest = tail;
            match b {
                b'"' => {
                    self.in_string = true;
                    out.push(b);
                }
                b'{' | b'[' => self.open = Some(b),
                b'}' | b']' => {
                    self.depth = self.depth.saturating_sub(1);
                    self.newline(out);
                    out.push(b);
                }
                b',' => {
                    out.push(b);
                    self.newline(out);
                }
                b':' => out.extend_from_slice(b": "),
                _ => out.push(b),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn json_str(s: &str) -> String {
        let mut v = Vec::new();
        push_str(&mut v, s);
        String::from_utf8(v).unwrap()
    }

    proptest::proptest! {
        #[test]
        fn numbers_are_written_as_std_writes_them(v in prop_oneof![
            0u64..1000,
            proptest::num::u64::ANY,
            (0u32..20).prop_map(|e| 10u64.pow(e)),
            (1u32..20).prop_map(|e| 10u64.pow(e) - 1),
        ]) {
            let mut out = b"x".to_vec();
            push_u64(&mut out, v);
            proptest::prop_assert_eq!(out, format!("x{v}").into_bytes());
        }

        #[test]
        fn hex_is_written_as_std_writes_it(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..20)) {
            let mut out = Vec::new();
            push_hex(&mut out, &bytes);
            let want: String = bytes.iter().map(|b| format!("{b:02X}")).collect();
            proptest::prop_assert_eq!(String::from_utf8(out).unwrap(), format!("\"{want}\""));
        }
    }

    #[test]
    fn every_byte_of_a_classic_payload_in_hex() {
        for b in 0..=255u8 {
            let mut out = Vec::new();
            push_hex(&mut out, &[b, 0, 0, 0, 0, 0, 0, b]);
            assert_eq!(out, format!("\"{b:02X}000000000000{b:02X}\"").into_bytes());
        }
    }

    #[test]
    fn escaping_matches_serde_json_for_every_byte_below_128() {
        for b in 0u8..128 {
            let s = (b as char).to_string();
            assert_eq!(
                json_str(&s),
                serde_json::to_string(&s).unwrap(),
                "byte {b:#x}"
            );
        }
        let s = "Temperature · drive \"q\" \\ \u{1b}[31m ok";
        assert_eq!(json_str(s), serde_json::to_string(s).unwrap());
    }

    #[test]
    fn pretty_in_chunks_equals_pretty_at_once() {
        let compact = br#"{"a":[],"b":{},"c":[1,{"d":"x,\"y[]"}],"e":{"f":[]}}"#;
        let mut whole = Vec::new();
        pretty(compact, 1, &mut whole);
        for split in 0..=compact.len() {
            let mut p = Pretty::new(1);
            let mut got = Vec::new();
            p.feed(&compact[..split], &mut got);
            p.feed(&compact[split..], &mut got);
            assert_eq!(
                String::from_utf8_lossy(&got),
                String::from_utf8_lossy(&whole),
                "split at {split}"
            );
        }
    }

    #[test]
    fn pretty_matches_serde_json_pretty() {
        let v = serde_json::json!({
            "a": [1, 2, {"b": [], "c": {}}],
            "s": "x,y:{[\"]}",
            "n": null,
            "e": [],
            "o": {"k": [true, false]}
        });
        let compact = serde_json::to_vec(&v).unwrap();
        let mut got = Vec::new();
        pretty(&compact, 0, &mut got);
        assert_eq!(
            String::from_utf8(got).unwrap(),
            serde_json::to_string_pretty(&v).unwrap()
        );
    }

    #[test]
    fn codes_and_hex() {
        let mut v = Vec::new();
        push_code(&mut v, 0x4310);
        push_codes(&mut v, &[0xFF01, 0x0001]);
        push_hex(&mut v, &[0x10, 0xAB]);
        assert_eq!(v, b"\"0x4310\"[\"0xFF01\",\"0x0001\"]\"10AB\"");
    }
}
