//! `--format csv`: one row per event, or with `--view summary` one row per
//! node, under a header row, for spreadsheets and data tools. The columns
//! are a contract ([`EVENT_COLUMNS`], [`NODE_COLUMNS`], docs/guide/output.md); quoted as
//! the `csv` crate quotes (RFC 4180: a field with a comma, a quote or a
//! line break is quoted; the tests read every output back with the crate).
//! A cell with several values separates them with
//! spaces (`4310h 3120h`, `4310h:2 3120h:1` for counts); the profile's
//! fields are the JSON object the JSON formats give them (their texts can
//! hold any separator).
//!
//! Text from outside (file and channel names, a user profile's texts) is
//! made harmless as in every other output: control characters escaped,
//! and a text a spreadsheet would run as a formula neutralised as OWASP's
//! CSV injection advice says ([`text`]). Numbers are written as numbers;
//! codes, device types and bytes are written so that DuckDB and pandas
//! guess them as text without options: codes in CiA 301's `4310h`
//! notation (both read `0x4310` or `0100` as a number), bytes as hex pairs
//! with spaces between (`10 43 08 01`).

use std::io::{self, Write};

use super::format::{CSV_LIST, cia_code, push_code_counts, push_codes, push_hex_spaced};
use super::jsonw::{JsonWriter, push_decoded};
use super::table::{bus_description, health_description};
use super::timefmt::{TimeFormat, TimeStyle};
use crate::analyze::{
    BootEvent, BusEvent, Diagnostic, EmcyEvent, HealthEvent, InputReport, NodeReport, Sink,
};
use crate::cache::{Cache, profile_key, slot};
use crate::canopen::device_profile;
use crate::canopen::register::Register;
use crate::text::printable;
use crate::trace::Timestamp;

/// The columns of an event row, in order.
pub const EVENT_COLUMNS: [&str; 22] = [
    "type",
    "file",
    "line",
    "time",
    "time_text",
    "channel",
    "node",
    "cob_id",
    "code",
    "class",
    "description",
    "register",
    "register_bits",
    "data",
    "manufacturer",
    "profile",
    "profile_fields",
    "transition",
    "state",
    "cleared",
    "warnings",
    "details",
];

/// The columns of a node row (`--view summary`), in order.
pub const NODE_COLUMNS: [&str; 18] = [
    "file",
    "channel",
    "node",
    "state",
    "active",
    "emcy_count",
    "errors_seen",
    "time_in_error",
    "longest_error_code",
    "longest_error_duration",
    "first_emcy",
    "first_emcy_text",
    "last_emcy",
    "last_emcy_text",
    "profile",
    "profile_source",
    "device_type",
    "device_profile",
];

pub struct Csv<W: Write> {
    out: W,
    summary: bool,
    /// Flush after every row (a live stream).
    live: bool,
    header: bool,
    /// ISO-8601 UTC for Unix times, else the seconds as written: the
    /// `_text` columns (exact, unlike a spreadsheet's reading of a number).
    times: TimeFormat,
    text: String,
    /// The row being built.
    row: Vec<u8>,
    /// The last event's file and its cell, and its channel and its cell,
    /// encoded once (`None` before the first event; an empty name is an
    /// empty cell, so emptiness cannot mean "not yet").
    file: Option<(String, Vec<u8>)>,
    channel: Option<(String, Vec<u8>)>,
    /// `code,...,profile_fields` per payload and profile, encoded once: a
    /// trace repeats a few payloads millions of times.
    payloads: Cache<PayloadKey, Vec<u8>, 64>,
    json: Vec<u8>,
    /// Health events' `details`.
    jsonw: JsonWriter,
}

#[derive(Clone, Copy, PartialEq, Eq)]
struct PayloadKey {
    bytes: [u8; 8],
    len: u8,
    profile: usize,
}

fn push_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(itoa::Buffer::new().format(v).as_bytes());
}

impl<W: Write> Csv<W> {
    /// Event rows; with `summary`, node rows instead; `live` flushes
    /// every row.
    pub fn new(out: W, summary: bool, live: bool) -> Self {
        Csv {
            out,
            summary,
            live,
            header: false,
            times: TimeFormat::new(TimeStyle::Auto),
            text: String::new(),
            row: Vec::with_capacity(512),
            file: None,
            channel: None,
            payloads: Cache::default(),
            json: Vec::new(),
            jsonw: JsonWriter::new(),
        }
    }

    fn header(&mut self) -> io::Result<()> {
        if !self.header {
            self.header = true;
            let columns: &[&str] = if self.summary {
                &NODE_COLUMNS
            } else {
                &EVENT_COLUMNS
            };
            let mut line = encode(columns);
            line.push(b'\n');
            self.out.write_all(&line)?;
        }
        Ok(())
    }

    /// `type,file,line,time,time_text,channel,node,` of an event.
    fn head(
        &mut self,
        kind: &str,
        file: &str,
        line: u64,
        time: Option<Timestamp>,
        channel: &str,
        node: Option<u16>,
    ) {
        let file = cached_cell(&mut self.file, file);
        let channel = cached_cell(&mut self.channel, channel);
        let row = &mut self.row;
        row.clear();
        row.extend_from_slice(kind.as_bytes());
        row.push(b',');
        row.extend_from_slice(file);
        row.push(b',');
        push_u64(row, line);
        row.push(b',');
        if let Some(t) = time {
            // Digits, a point, a zone letter: never quoted.
            t.push_decimal(row);
            row.push(b',');
            self.text.clear();
            self.times.push(&mut self.text, t);
            row.extend_from_slice(self.text.as_bytes());
        } else {
            row.push(b',');
        }
        row.push(b',');
        row.extend_from_slice(channel);
        row.push(b',');
        // Empty for a bus event of no node.
        if let Some(node) = node {
            push_u64(row, u64::from(node));
        }
        row.push(b',');
    }

    fn end_row(&mut self) -> io::Result<()> {
        self.row.push(b'\n');
        self.out.write_all(&self.row)?;
        if self.live {
            self.out.flush()?;
        }
        Ok(())
    }

    /// `code,class,description,register,register_bits,data,manufacturer,
    /// profile,profile_fields` of an EMCY, from the cache.
    fn payload(&mut self, ev: &EmcyEvent<'_>) {
        let profile = ev.profile.profile;
        let len = ev.data.len().min(8);
        let mut key = PayloadKey {
            bytes: [0; 8],
            len: len as u8,
            profile: profile_key(profile),
        };
        key.bytes[..len].copy_from_slice(&ev.data[..len]);
        let at =
            slot(u64::from_le_bytes(key.bytes) ^ u64::from(key.len) ^ (key.profile as u64) << 8);
        let json = &mut self.json;
        match self.payloads.get(key, at, || payload_fragment(ev, json)) {
            Some(fragment) => self.row.extend_from_slice(fragment),
            None => {
                let fragment = payload_fragment(ev, &mut self.json);
                self.row.extend_from_slice(&fragment);
            }
        }
    }

    fn node(&mut self, input: &InputReport, n: &NodeReport) -> io::Result<()> {
        let mut active = Vec::new();
        push_codes(&mut active, n.active.iter().copied(), &CSV_LIST);
        let mut seen = Vec::new();
        push_code_counts(
            &mut seen,
            n.stats.raised.iter().map(|(&code, &count)| (code, count)),
            &CSV_LIST,
        );
        let span = |s: Option<crate::trace::Span>| {
            let mut v = Vec::new();
            if let Some(s) = s {
                s.push_decimal(&mut v);
            }
            v
        };
        let (longest_code, longest) = match n.stats.longest {
            Some((code, d)) => {
                let c = cia_code(code).to_vec();
                (c, span(Some(d)))
            }
            None => (Vec::new(), Vec::new()),
        };
        let time = |t: Option<Timestamp>| {
            let (mut number, mut text) = (Vec::new(), String::new());
            if let Some(t) = t {
                t.push_decimal(&mut number);
                self.times.push(&mut text, t);
            }
            (number, text.into_bytes())
        };
        let (first, first_text) = time(n.stats.first_emcy.and_then(|a| a.time));
        let (last, last_text) = time(n.stats.last_emcy.and_then(|a| a.time));
        let node = itoa::Buffer::new().format(n.node).to_string();
        let count = itoa::Buffer::new().format(n.emcy_count).to_string();
        // CiA 301's `h` notation, as the codes: `0x00020192` would be a number.
        let device_type = n
            .device_type
            .map(|v| format!("{v:08X}h"))
            .unwrap_or_default();
        let device_profile = n
            .device_type
            .map(device_profile::describe)
            .unwrap_or_default();
        let mut line = join([
            &text(&input.file)[..],
            &text(&n.channel),
            node.as_bytes(),
            n.state.slug().as_bytes(),
            &active,
            count.as_bytes(),
            &seen,
            &span(n.time_in_error(input.last_time)),
            &longest_code,
            &longest,
            &first,
            &first_text,
            &last,
            &last_text,
            &text(n.profile.name()),
            n.profile_source.slug().as_bytes(),
            device_type.as_bytes(),
            &text(&device_profile),
        ]);
        line.push(b'\n');
        self.out.write_all(&line)
    }
}

/// `fields` as the crate writes a record, without its line end: the
/// header row. Event and node rows are assembled from numbers, codes and
/// slugs, which never need quoting, and text and JSON cells quoted by
/// [`push_text`] and [`push_json`] as the crate would quote them.
fn encode<I, F>(fields: I) -> Vec<u8>
where
    I: IntoIterator<Item = F>,
    F: AsRef<[u8]>,
{
    let mut encoder = csv::WriterBuilder::new()
        .buffer_capacity(512)
        .from_writer(Vec::new());
    // Writing into a Vec cannot fail.
    let _ = encoder.write_record(fields);
    let mut bytes = encoder.into_inner().unwrap_or_default();
    bytes.pop();
    bytes
}

/// Characters that make a spreadsheet read a cell as a formula (OWASP, CSV
/// injection) when they come first. OWASP also names tab and carriage
/// return, which some spreadsheets skip before looking: those are control
/// characters, escaped before this is asked (`\t`), so a cell never starts
/// with them.
const FORMULA_FIRST: [char; 4] = ['=', '+', '-', '@'];

/// One text cell from outside (a file or channel name, a profile's
/// texts), appended to `out`. Control characters are escaped as the table
/// escapes them: `cat events.csv` must not run a terminal sequence hidden
/// in a channel name. A text a spreadsheet would take for a formula
/// (`=cmd|'/C calc'!A0`, `@SUM(1+1)`, `-2+3`) gets a `'` in front, which
/// shows it as text, and is quoted, as OWASP recommends; a reader that
/// wants the name drops a leading `'` of such a cell. An empty text is an
/// empty cell. Quoted as the `csv` crate quotes (a comma, a quote or a line
/// break), written straight into the row: a text cell is encoded for most
/// EMCYs of a trace whose payloads vary, and a crate writer per cell cost
/// 5% of a CSV run (callgrind, 30% EMCY).
fn push_text(out: &mut Vec<u8>, value: &str) {
    let shown = printable(value);
    let formula = shown.starts_with(FORMULA_FIRST);
    let special = |b: &u8| matches!(b, b',' | b'"' | b'\r' | b'\n');
    if !formula && !shown.as_bytes().iter().any(special) {
        out.extend_from_slice(shown.as_bytes());
        return;
    }
    out.push(b'"');
    if formula {
        out.push(b'\'');
    }
    push_quoted(out, shown.as_bytes());
    out.push(b'"');
}

/// `bytes` inside a quoted cell: each `"` doubled.
fn push_quoted(out: &mut Vec<u8>, bytes: &[u8]) {
    for part in bytes.split_inclusive(|&b| b == b'"') {
        out.extend_from_slice(part);
        if part.last() == Some(&b'"') {
            out.push(b'"');
        }
    }
}

/// [`push_text`] as a cell of its own.
fn text(value: &str) -> Vec<u8> {
    let mut cell = Vec::with_capacity(value.len() + 4);
    push_text(&mut cell, value);
    cell
}

/// A JSON object as a cell (`details`, `profile_fields`), appended to
/// `out`; nothing for none. JSON escapes only the C0 controls, so a name
/// with DEL or a C1 control (U+0080-U+009F, where U+009B is a terminal's
/// CSI) would reach the terminal through it: those become `\u007f`,
/// `\u009b`, the same JSON value, as every other cell escapes them. An
/// object always holds quotes, so the cell is always quoted.
fn push_json(out: &mut Vec<u8>, json: &[u8]) {
    if json.is_empty() {
        return;
    }
    out.push(b'"');
    let mut rest = json;
    while let Some(i) = rest.iter().position(|&b| b == 0x7F || b == 0xC2) {
        push_quoted(out, &rest[..i]);
        let c1 = rest
            .get(i + 1)
            .filter(|&&b| rest[i] == 0xC2 && (0x80..0xA0).contains(&b));
        match (rest[i], c1) {
            (0x7F, _) => {
                out.extend_from_slice(b"\\u007f");
                rest = &rest[i + 1..];
            }
            (_, Some(&c)) => {
                out.extend_from_slice(format!("\\u{c:04x}").as_bytes());
                rest = &rest[i + 2..];
            }
            // 0xC2 starting another character (`·` is 0xC2 0xB7).
            _ => {
                out.push(0xC2);
                rest = &rest[i + 1..];
            }
        }
    }
    push_quoted(out, rest);
    out.push(b'"');
}

/// The cell of `value`, encoded again only when it differs from the last.
fn cached_cell<'c>(last: &'c mut Option<(String, Vec<u8>)>, value: &str) -> &'c [u8] {
    if last.as_ref().is_none_or(|(name, _)| name != value) {
        *last = Some((value.to_string(), text(value)));
    }
    last.as_ref().map_or(&[], |(_, cell)| cell)
}

/// Cells already encoded, as one row (without its line end).
fn join<'a, I>(cells: I) -> Vec<u8>
where
    I: IntoIterator<Item = &'a [u8]>,
{
    let mut row = Vec::with_capacity(256);
    for (i, cell) in cells.into_iter().enumerate() {
        if i > 0 {
            row.push(b',');
        }
        row.extend_from_slice(cell);
    }
    row
}

/// The payload columns of an EMCY, encoded (see [`Csv::payload`]).
fn payload_fragment(ev: &EmcyEvent<'_>, json: &mut Vec<u8>) -> Vec<u8> {
    let mut row = Vec::with_capacity(256);
    row.extend_from_slice(&cia_code(ev.emcy.code));
    row.push(b',');
    row.extend_from_slice(ev.info.class.slug().as_bytes());
    row.push(b',');
    push_text(&mut row, ev.description);
    row.push(b',');
    push_u64(&mut row, u64::from(ev.emcy.register.0));
    row.push(b',');
    for (i, name) in Register(ev.emcy.register.0).names().enumerate() {
        if i > 0 {
            row.push(b' ');
        }
        row.extend_from_slice(name.as_bytes());
    }
    row.push(b',');
    push_hex_spaced(&mut row, ev.data);
    row.push(b',');
    push_hex_spaced(&mut row, ev.emcy.manufacturer());
    row.push(b',');
    push_text(&mut row, ev.profile.profile.name());
    row.push(b',');
    json.clear();
    if ev.decoded.is_some() {
        push_decoded(json, ev.decoded);
    }
    push_json(&mut row, json);
    row
}

impl<W: Write> Sink for Csv<W> {
    fn emcy(&mut self, ev: &EmcyEvent<'_>) -> io::Result<()> {
        if self.summary {
            return Ok(());
        }
        self.header()?;
        self.head("emcy", ev.file, ev.line, ev.time, ev.channel, Some(ev.node));
        if let Some(id) = ev.cob_id {
            push_u64(&mut self.row, u64::from(id));
        }
        self.row.push(b',');
        self.payload(ev);
        let row = &mut self.row;
        row.push(b',');
        if let Some(t) = ev.transition {
            push_u64(row, u64::from(t));
        }
        row.push(b',');
        row.extend_from_slice(ev.state.slug().as_bytes());
        row.push(b',');
        push_codes(row, ev.cleared.iter().copied(), &CSV_LIST);
        row.push(b',');
        for (i, w) in ev.warnings.iter().enumerate() {
            if i > 0 {
                row.push(b' ');
            }
            row.extend_from_slice(w.tag().as_bytes());
        }
        row.push(b',');
        self.end_row()
    }

    fn boot(&mut self, ev: &BootEvent<'_>) -> io::Result<()> {
        if self.summary {
            return Ok(());
        }
        self.header()?;
        self.head("boot", ev.file, ev.line, ev.time, ev.channel, Some(ev.node));
        // cob_id .. state: nothing for a boot-up.
        self.row.extend_from_slice(&[b','; 12]);
        push_codes(&mut self.row, ev.cleared.iter().copied(), &CSV_LIST);
        self.row.extend_from_slice(b",,");
        self.end_row()
    }

    /// NMT, heartbeat, SDO abort and error history events: `description`
    /// says what happened as the table does, `details` is the event's
    /// JSON object (its own keys: `state`, `silent`, `abort_code`,
    /// `entries`...).
    fn health(&mut self, ev: &HealthEvent<'_>) -> io::Result<()> {
        if self.summary {
            return Ok(());
        }
        self.header()?;
        self.head(
            ev.health.slug(),
            ev.file,
            ev.line,
            ev.time,
            ev.channel,
            Some(ev.node),
        );
        let description = health_description(ev.health, &self.times);
        self.json.clear();
        self.jsonw.health(&mut self.json, ev);
        // cob_id .. class empty, description, register .. warnings empty.
        self.row.extend_from_slice(b",,,");
        push_text(&mut self.row, &description);
        self.row.extend_from_slice(&[b','; 11]);
        push_json(&mut self.row, &self.json);
        self.end_row()
    }

    /// Error bursts and bus-offs: `description` as the table says it,
    /// `details` the event's JSON object (`kinds`, `evidence`, ...).
    fn bus(&mut self, ev: &BusEvent<'_>) -> io::Result<()> {
        if self.summary {
            return Ok(());
        }
        self.header()?;
        self.head(
            ev.bus.slug(),
            ev.file,
            ev.line,
            ev.time,
            ev.channel,
            ev.bus.node(),
        );
        let description = bus_description(ev.bus, &self.times);
        self.json.clear();
        self.jsonw.bus(&mut self.json, ev);
        // cob_id .. class empty, description, register .. warnings empty.
        self.row.extend_from_slice(b",,,");
        push_text(&mut self.row, &description);
        self.row.extend_from_slice(&[b','; 11]);
        push_json(&mut self.row, &self.json);
        self.end_row()
    }

    fn finish(&mut self, inputs: &[InputReport], _: &[Diagnostic]) -> io::Result<()> {
        self.header()?;
        if self.summary {
            for input in inputs {
                for n in &input.nodes {
                    self.node(input, n)?;
                }
            }
        }
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(value: &str) -> String {
        String::from_utf8(text(value)).unwrap()
    }

    #[test]
    fn plain_names_are_encoded_as_the_crate_encodes_them() {
        assert_eq!(cell("can0"), "can0");
        assert_eq!(cell("rig 3, bench"), "\"rig 3, bench\"");
        assert_eq!(cell("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(cell(""), "");
        // Inside a name, the characters are harmless.
        assert_eq!(cell("a=b-c+d@e"), "a=b-c+d@e");
    }

    #[test]
    fn json_cells_escape_del_and_c1_controls_as_json_does_c0() {
        let cell = |json: &str| {
            let mut cell = Vec::new();
            push_json(&mut cell, json.as_bytes());
            String::from_utf8(cell).unwrap()
        };
        assert_eq!(cell(""), "");
        assert_eq!(cell(r#"{"a":"b"}"#), r#""{""a"":""b""}""#);
        assert_eq!(
            cell("{\"a\":\"x\u{7f}y\u{9b}z\u{a0}·\"}"),
            r#""{""a"":""x\u007fy\u009bz"#.to_string() + "\u{a0}·\"\"}\""
        );
        let value: serde_json::Value = serde_json::from_str(r#"{"a":"x\u007fy\u009b"}"#).unwrap();
        assert_eq!(value["a"], "x\u{7f}y\u{9b}");
    }

    /// The one cell of a row, as the csv crate reads it back.
    fn read_back(row: &[u8]) -> String {
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(row);
        let record = reader.records().next().expect("a row").expect("valid CSV");
        assert_eq!(record.len(), 1, "one cell: {row:?}");
        record[0].to_string()
    }

    proptest::proptest! {
        /// Any text reads back as what the table shows, with a `'` in
        /// front of a formula, and never holds a control character.
        #[test]
        fn any_text_reads_back_escaped_and_neutralised(value in "(\\PC|[\\x00-\\x1f\\x7f-\\x9f\",=+@-]){0,40}") {
            let mut row = text(&value);
            let shown = printable(&value).into_owned();
            proptest::prop_assert!(!String::from_utf8_lossy(&row).chars().any(char::is_control));
            row.extend_from_slice(b",x\n");
            let want = if shown.starts_with(FORMULA_FIRST) { format!("'{shown}") } else { shown };
            let mut reader = csv::ReaderBuilder::new().has_headers(false).from_reader(&row[..]);
            let record = reader.records().next().expect("a row").expect("valid CSV");
            proptest::prop_assert_eq!(&record[0], want.as_str());
            proptest::prop_assert_eq!(&record[1], "x");
        }

        /// Any JSON object reads back as the same JSON value, without a
        /// control character in the cell.
        #[test]
        fn any_json_reads_back_as_the_same_value(value in "(\\PC|[\\x00-\\x1f\\x7f-\\x9f\",·]){0,40}") {
            let json = serde_json::json!({ "name": value }).to_string();
            let mut cell = Vec::new();
            push_json(&mut cell, json.as_bytes());
            proptest::prop_assert!(!String::from_utf8_lossy(&cell).chars().any(char::is_control));
            let back: serde_json::Value = serde_json::from_str(&read_back(&cell)).expect("JSON");
            proptest::prop_assert_eq!(back["name"].as_str(), Some(value.as_str()));
        }
    }

    #[test]
    fn formulas_get_a_quote_mark_in_front_and_are_quoted() {
        assert_eq!(cell("=1+1"), "\"'=1+1\"");
        assert_eq!(cell("+1"), "\"'+1\"");
        assert_eq!(cell("-1"), "\"'-1\"");
        assert_eq!(cell("@SUM(A1)"), "\"'@SUM(A1)\"");
        assert_eq!(
            cell("=HYPERLINK(\"http://x\")"),
            "\"'=HYPERLINK(\"\"http://x\"\")\""
        );
    }

    /// Tab and carriage return first are formulas to OWASP; escaped as
    /// control characters they start with a backslash and are no longer.
    #[test]
    fn control_characters_are_escaped_tab_and_cr_first_included() {
        assert_eq!(cell("\u{1b}[2J"), "\\u{1b}[2J");
        assert_eq!(cell("\t=1"), "\\t=1");
        assert_eq!(cell("\r=1"), "\\r=1");
        assert_eq!(cell("a\u{85}b"), "a\\u{85}b");
    }
}
