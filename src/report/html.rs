//! `--format html`: one self-contained page (no network, no external
//! scripts, fonts or images; opens from disk) with the timeline chart of each
//! input and its events table below, filterable by node and sortable by
//! column. The chart is the SVG of [`super::chart`], inlined.
//!
//! The table is bounded: the first [`TABLE_ROWS`] events of each input are
//! listed and a note says how many more were left out (the chart still
//! draws all of them; `--format table` or `ndjson` list every event).

use super::table::codes_list;
use std::fmt::Write as _;
use std::io::{self, Write};

use super::chart::{self, Clock, Collector, Panel, esc};
use super::svg::{doc_title, document, style_sheet};
use super::table::health_description;
use super::timefmt::TimeFormat;
use crate::analyze::{BootEvent, Diagnostic, EmcyEvent, Health, HealthEvent, InputReport, Sink};
use crate::canopen::NodeId;
use crate::canopen::profile::{Decoded, FieldValue};
use crate::trace::Timestamp;

/// Events listed per input.
pub const TABLE_ROWS: usize = 1000;

/// What a row of the events table is.
enum Kind {
    /// An EMCY frame with its error code.
    Emcy(u16),
    Boot,
    /// A node-health event: its JSON `type` (`nmt`, `heartbeat_lost`, ...).
    Health(&'static str),
}

/// One row of the events table, kept until the input ends (the time
/// column's format depends on the whole input's span).
struct Row {
    time: Option<Timestamp>,
    line: u64,
    channel: String,
    node: NodeId,
    kind: Kind,
    register: u8,
    transition: Option<u8>,
    description: String,
    /// The manufacturer bytes as the profile reads them (the vendor's fault
    /// code, category), else the bytes themselves when not all zero.
    manufacturer: String,
    /// `(tag, text)` of each warning.
    warnings: Vec<(&'static str, String)>,
    cleared: Vec<u16>,
    state: &'static str,
}

/// A health event's description: the table's and CSV's words (times in
/// ISO-8601), and a read-out's entries, which the table lists on lines of
/// their own.
fn health_text(health: &Health) -> String {
    let mut text = health_description(health, &TimeFormat::default());
    if let Health::ErrorHistory(h) = health {
        for (i, e) in h.entries.iter().enumerate() {
            text.push_str(if i == 0 { ": " } else { "; " });
            let _ = write!(text, "0x{:04X} {}", e.code, e.description);
            if e.info != 0 {
                let _ = write!(text, " (info 0x{:04X})", e.info);
            }
            if e.before_trace {
                text.push_str(", before the trace");
            }
        }
    }
    text
}

/// The manufacturer cell: `category: 1 (cleared only by a reset); ...`
/// from the profile's fields (a `_text` field joins its number), else the
/// raw bytes 3-7.
fn manufacturer_cell(decoded: Option<&Decoded>, data: &[u8]) -> String {
    let Some(d) = decoded else {
        let raw = data.get(3..).unwrap_or_default();
        if raw.iter().all(|&b| b == 0) {
            return String::new();
        }
        return raw.iter().fold(String::new(), |mut s, b| {
            let _ = write!(s, "{b:02X}");
            s
        });
    };
    let mut parts: Vec<String> = Vec::with_capacity(d.fields.len());
    for (key, value) in &d.fields {
        let text = match value {
            FieldValue::Int(n) => n.to_string(),
            FieldValue::Text(t) => t.clone(),
        };
        // `category_text` after `category`: one item, `category: 1 (text)`.
        if let Some(base) = key.strip_suffix("_text")
            && let Some(last) = parts.last_mut()
            && last.starts_with(&format!("{base}: "))
        {
            let _ = write!(last, " ({text})");
            continue;
        }
        parts.push(format!("{key}: {text}"));
    }
    parts.join("; ")
}

struct Section {
    panel: Panel,
    rows: Vec<Row>,
    events: u64,
}

pub struct HtmlReport<W: Write> {
    out: W,
    collector: Collector,
    rows: Vec<Row>,
    events: u64,
    sections: Vec<Section>,
}

impl<W: Write> HtmlReport<W> {
    pub fn new(out: W) -> Self {
        HtmlReport {
            out,
            collector: Collector::default(),
            rows: Vec::new(),
            events: 0,
            sections: Vec::new(),
        }
    }

    fn keep(&mut self, row: impl FnOnce() -> Row) {
        self.events += 1;
        if self.rows.len() < TABLE_ROWS {
            self.rows.push(row());
        }
    }
}

const PAGE_STYLE: &str = "\
body{font:14px system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;margin:16px;color:#222;background:#fff}
h1{font-size:20px;margin:0 0 12px}
h2{font-size:16px;margin:18px 0 6px}
section.input{margin-bottom:36px}
.chart{overflow-x:auto}
.chart svg{display:block}
.ec g.lane{cursor:pointer}
table.ev{border-collapse:collapse;font-size:12px}
table.ev th{background:#eceef1;text-align:left;padding:4px 8px;cursor:pointer;position:sticky;top:0;user-select:none}
table.ev th[data-dir=asc]::after{content:' \\25B2'}
table.ev th[data-dir=desc]::after{content:' \\25BC'}
table.ev td{padding:2px 8px;border-bottom:1px solid #eee;white-space:nowrap}
table.ev td.n{text-align:right;font-variant-numeric:tabular-nums}
table.ev td.t{white-space:normal;min-width:14em;max-width:36em}
table.ev tr.boot td{color:#2c4f9e}
table.ev tr.reset td{color:#1b7837}
table.ev tr.nmt td,table.ev tr.error_history td,table.ev tr.error_history_cleared td{color:#555}
table.ev tr.heartbeat_lost td{color:#b2182b;font-weight:600}
table.ev tr.heartbeat_back td{color:#1b7837}
table.ev tr.sdo_abort td{color:#a6611a}
table.ev td.w{color:#a6611a}
.note{color:#555}
";

/// Filter by node (select or a click on a lane) and sort by a column
/// header. Plain DOM, no library; the page works without it too.
const SCRIPT: &str = "\
document.querySelectorAll('section.input').forEach(function(sec){
var sel=sec.querySelector('select'),tb=sec.querySelector('tbody'),shown=sec.querySelector('.shown');
if(!sel||!tb)return;
function apply(){var n=0;Array.prototype.forEach.call(tb.rows,function(r){r.hidden=sel.value!==''&&r.getAttribute('data-lane')!==sel.value;if(!r.hidden)n++;});
sec.querySelectorAll('g.lane').forEach(function(g){g.style.opacity=sel.value===''||g.getAttribute('data-lane')===sel.value?'':'0.3';});
shown.textContent=n+' row'+(n===1?'':'s')+' shown';}
sel.addEventListener('change',apply);
sec.querySelectorAll('g.lane').forEach(function(g){g.addEventListener('click',function(){var v=g.getAttribute('data-lane');sel.value=sel.value===v?'':v;apply();});});
var heads=sec.querySelectorAll('th');
heads.forEach(function(th,i){th.addEventListener('click',function(){
var up=th.getAttribute('data-dir')!=='asc';heads.forEach(function(h){h.removeAttribute('data-dir');});th.setAttribute('data-dir',up?'asc':'desc');
function key(r){var c=r.cells[i];return c.hasAttribute('data-k')?c.getAttribute('data-k'):c.textContent;}
var rows=Array.prototype.slice.call(tb.rows);
rows.sort(function(a,b){var x=key(a),y=key(b),nx=parseFloat(x),ny=parseFloat(y),d;
d=(!isNaN(nx)&&!isNaN(ny)&&String(nx)===x&&String(ny)===y)?nx-ny:x.localeCompare(y);return up?d:-d;});
rows.forEach(function(r){tb.appendChild(r);});});});
apply();});
";

fn write_section(s: &mut String, sec: &Section) -> std::fmt::Result {
    s.push_str("<section class=\"input\">\n<div class=\"chart\">\n");
    s.push_str(&document(&[&sec.panel], "", false));
    s.push_str("</div>\n<h2>Events</h2>\n");
    if sec.events == 0 {
        s.push_str("<p class=\"note\">No EMCY, boot-up or node-health events.</p>\n</section>\n");
        return Ok(());
    }
    s.push_str("<p><label>Node: <select><option value=\"\">all</option>");
    for (key, label) in &sec.panel.lanes {
        write!(s, "<option value=\"{}\">{}</option>", esc(key), esc(label))?;
    }
    s.push_str("</select></label> <span class=\"shown note\"></span></p>\n");
    write!(
        s,
        "<table class=\"ev\"><thead><tr><th>{}</th><th>line</th><th>channel</th><th>node</th>\
         <th>event</th><th title=\"transition: 1 first error, 2 one error reset, 3 further error, 4 all reset\">TR</th>\
         <th>register</th><th>description</th><th>manufacturer</th><th>warnings</th><th>cleared</th><th>state after</th></tr></thead>\n<tbody>\n",
        sec.panel.clock.heading()
    )?;
    for r in &sec.rows {
        write_row(s, &sec.panel.clock, r)?;
    }
    s.push_str("</tbody></table>\n");
    let shown = sec.rows.len() as u64;
    if sec.events > shown {
        writeln!(
            s,
            "<p class=\"note\">The first {shown} of {} events are listed; {} more not shown. \
             The chart draws all of them; <code>--format table</code> or <code>--format ndjson</code> lists every event.</p>",
            sec.events,
            sec.events - shown
        )?;
    }
    s.push_str("</section>\n");
    Ok(())
}

fn write_row(s: &mut String, clock: &Clock, r: &Row) -> std::fmt::Result {
    let (class, event) = match r.kind {
        Kind::Boot => (" class=\"boot\"", "boot-up".to_string()),
        Kind::Emcy(0) => (" class=\"reset\"", "0x0000".to_string()),
        Kind::Emcy(c) => ("", format!("0x{c:04X}")),
        Kind::Health(slug) => ("", slug.to_string()),
    };
    let class = match r.kind {
        Kind::Health(slug) => format!(" class=\"{slug}\""),
        _ => class.to_string(),
    };
    let register = match r.kind {
        Kind::Emcy(_) => format!("0x{:02X}", r.register),
        _ => String::new(),
    };
    write!(
        s,
        "<tr{class} data-lane=\"{}\"><td data-k=\"{}\">{}</td><td class=\"n\">{}</td><td>{}</td><td class=\"n\">{}</td>\
         <td>{event}</td><td class=\"n\">{}</td><td>{register}</td><td class=\"t\">{}</td><td class=\"t\">{}</td><td class=\"w\">",
        esc(&chart::lane_key(&r.channel, r.node)),
        r.line,
        esc(&clock.cell(r.time)),
        r.line,
        esc(&r.channel),
        r.node,
        r.transition
            .map_or_else(|| "-".to_string(), |t| t.to_string()),
        esc(&r.description),
        esc(&r.manufacturer),
    )?;
    // The tag in the cell, the whole text on hover.
    for (i, (tag, text)) in r.warnings.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        write!(s, "<span title=\"{}\">{tag}</span>", esc(text))?;
    }
    writeln!(
        s,
        "</td><td>{}</td><td>{}</td></tr>",
        codes_list(&r.cleared),
        r.state
    )
}

impl<W: Write> Sink for HtmlReport<W> {
    fn begin_input(&mut self, _file: &str) -> io::Result<()> {
        self.collector.begin_input();
        self.rows.clear();
        self.events = 0;
        Ok(())
    }

    fn emcy(&mut self, ev: &EmcyEvent<'_>) -> io::Result<()> {
        self.collector.emcy(ev);
        self.keep(|| Row {
            time: ev.time,
            line: ev.line,
            channel: ev.channel.to_string(),
            node: ev.node,
            kind: Kind::Emcy(ev.emcy.code),
            register: ev.emcy.register.0,
            transition: ev.transition,
            description: ev.description.to_string(),
            manufacturer: manufacturer_cell(ev.decoded, ev.data),
            warnings: ev
                .warnings
                .iter()
                .map(|w| (w.tag(), w.to_string()))
                .collect(),
            cleared: ev.cleared.to_vec(),
            state: ev.state.slug(),
        });
        Ok(())
    }

    fn health(&mut self, ev: &HealthEvent<'_>) -> io::Result<()> {
        self.collector.health(ev);
        self.keep(|| Row {
            time: ev.time,
            line: ev.line,
            channel: ev.channel.to_string(),
            node: ev.node,
            kind: Kind::Health(ev.health.slug()),
            register: 0,
            transition: None,
            // The same words as the table and CSV (times there in ISO-8601).
            description: health_text(ev.health),
            manufacturer: String::new(),
            warnings: Vec::new(),
            cleared: Vec::new(),
            // The column is the error state; an NMT state is in the text.
            state: "",
        });
        Ok(())
    }

    fn boot(&mut self, ev: &BootEvent<'_>) -> io::Result<()> {
        self.collector.boot(ev);
        self.keep(|| Row {
            time: ev.time,
            line: ev.line,
            channel: ev.channel.to_string(),
            node: ev.node,
            kind: Kind::Boot,
            register: 0,
            transition: None,
            description: "NMT boot-up: the node restarted".to_string(),
            manufacturer: String::new(),
            warnings: Vec::new(),
            cleared: ev.cleared.to_vec(),
            state: "error_free",
        });
        Ok(())
    }

    fn end_input(&mut self, input: &InputReport) -> io::Result<()> {
        let panel = self.collector.end_input(input)?;
        self.sections.push(Section {
            panel,
            rows: std::mem::take(&mut self.rows),
            events: self.events,
        });
        Ok(())
    }

    fn finish(&mut self, inputs: &[InputReport], _diagnostics: &[Diagnostic]) -> io::Result<()> {
        let title = doc_title(inputs);
        let mut s = String::with_capacity(64 * 1024);
        s.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        s.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        s.push_str(&format!("<title>{}</title>\n<style>\n", esc(&title)));
        s.push_str(PAGE_STYLE);
        let panels: Vec<&Panel> = self.sections.iter().map(|s| &s.panel).collect();
        s.push_str(&style_sheet(&panels));
        s.push_str("</style>\n</head>\n<body>\n<h1>EMCY timeline</h1>\n");
        if self.sections.is_empty() {
            s.push_str("<p class=\"note\">No input could be read.</p>\n");
        }
        for sec in &self.sections {
            write_section(&mut s, sec)
                .map_err(|_| io::Error::other("formatting the page failed"))?;
        }
        s.push_str("<script>\n");
        s.push_str(SCRIPT);
        s.push_str("</script>\n</body>\n</html>\n");
        self.out.write_all(s.as_bytes())?;
        self.out.flush()
    }
}
