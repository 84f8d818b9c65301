//! A [`Comparison`] as `diff` prints it: readable text (where the traces
//! part, then every difference grouped per node) or one JSON document.

use std::fmt::Write as _;

use serde_json::{Map, Value, json};

use super::compare::{Comparison, Difference, Side, TellerDifference, Told};
use super::story::Step;

/// The text report; ends with a `diff:` summary line.
pub fn render(c: &Comparison) -> String {
    let mut out = String::new();
    let (good, bad) = (&c.good, &c.bad);
    let Some(lead) = c.tellers.first() else {
        let _ = writeln!(out, "{good} and {bad} tell the same CANopen story");
        cut_note(&mut out, c);
        return out;
    };
    if let Some(d) = lead.differences.first() {
        let where_ = match (&d.good, &d.bad) {
            (Some(g), Some(b)) => format!("{good}:{} and {bad}:{}", g.line, b.line),
            (Some(g), None) => format!("{good}:{}", g.line),
            (None, Some(b)) => format!("{bad}:{}", b.line),
            (None, None) => String::new(),
        };
        let _ = writeln!(out, "The traces part at {}, {where_}:", lead.teller);
        difference_lines(&mut out, c, d, "  ", 0);
    } else if let Some(e) = lead.end.first() {
        let _ = writeln!(
            out,
            "The traces tell {} alike but it ends otherwise: {} {} in {good}, {} in {bad}",
            lead.teller,
            e.fact,
            e.good.as_deref().unwrap_or("-"),
            e.bad.as_deref().unwrap_or("-"),
        );
    }
    for t in &c.tellers {
        out.push('\n');
        teller(&mut out, c, t);
    }
    let nodes = c.tellers.len();
    let _ = writeln!(
        out,
        "\ndiff: {} difference{} in {nodes} node{} ({good} -> {bad})",
        c.total(),
        plural(c.total()),
        plural(nodes)
    );
    cut_note(&mut out, c);
    out
}

fn cut_note(out: &mut String, c: &Comparison) {
    if c.cut > 0 {
        let _ = writeln!(
            out,
            "note: {} steps past the bound of {} per trace were not compared",
            c.cut,
            super::story::MAX_STEPS
        );
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

fn teller(out: &mut String, c: &Comparison, t: &TellerDifference) {
    match t.only_in {
        Some(side) => {
            let file = if side == Side::Good { &c.good } else { &c.bad };
            let _ = writeln!(out, "{}: only in {file}", t.teller);
        }
        None => {
            let n = t.differences_total;
            let _ = write!(out, "{}: {n} difference{}", t.teller, plural(n));
            if n > 0 {
                let _ = write!(
                    out,
                    " after {} equal step{}",
                    t.equal_before,
                    plural(t.equal_before)
                );
            }
            out.push('\n');
        }
    }
    let width = t
        .differences
        .iter()
        .flat_map(|d| [(&c.good, &d.good), (&c.bad, &d.bad)])
        .filter_map(|(file, told)| told.as_ref().map(|t| file.len() + 1 + digits(t.line)))
        .max()
        .unwrap_or(0);
    for d in &t.differences {
        difference_lines(out, c, d, "  ", width);
    }
    let more = t.differences_total - t.differences.len();
    if more > 0 {
        let _ = writeln!(out, "  ... and {more} more");
    }
    if t.aligned_by_position {
        let _ = writeln!(
            out,
            "  (too many differences to align: the rest compared step by step)"
        );
    }
    for e in &t.end {
        let _ = writeln!(
            out,
            "  at the end: {} {} -> {}",
            e.fact,
            e.good.as_deref().unwrap_or("-"),
            e.bad.as_deref().unwrap_or("-")
        );
    }
}

fn digits(n: u64) -> usize {
    n.checked_ilog10().map_or(1, |d| d as usize + 1)
}

fn difference_lines(out: &mut String, c: &Comparison, d: &Difference, indent: &str, width: usize) {
    for (sign, file, told) in [("-", &c.good, &d.good), ("+", &c.bad, &d.bad)] {
        if let Some(t) = told {
            let at = format!("{file}:{}", t.line);
            let _ = writeln!(out, "{indent}{sign} {at:<width$}  {}", t.step);
        }
    }
}

/// The JSON document (docs/guide/diff.md lists its keys).
pub fn render_json(c: &Comparison) -> String {
    let first = c.tellers.first().and_then(|t| {
        t.differences.first().map(|d| {
            let mut v = difference_json(d);
            v.insert("channel".into(), json!(t.teller.channel));
            v.insert("node".into(), json!(t.teller.node));
            v
        })
    });
    let nodes: Vec<Value> = c.tellers.iter().map(teller_json).collect();
    let doc = json!({
        "good": c.good,
        "bad": c.bad,
        "same": c.same(),
        "differences": c.total(),
        "first": first,
        "nodes": nodes,
        "cut": c.cut,
    });
    let mut s = serde_json::to_string_pretty(&doc).unwrap_or_default();
    s.push('\n');
    s
}

fn teller_json(t: &TellerDifference) -> Value {
    let differences: Vec<Value> = t
        .differences
        .iter()
        .map(|d| Value::Object(difference_json(d)))
        .collect();
    let end: Vec<Value> = t
        .end
        .iter()
        .map(|e| json!({"fact": e.fact, "good": e.good, "bad": e.bad}))
        .collect();
    json!({
        "channel": t.teller.channel,
        "node": t.teller.node,
        "only_in": t.only_in.map(Side::slug),
        "equal_before": t.equal_before,
        "differences": differences,
        "differences_total": t.differences_total,
        "aligned_by_position": t.aligned_by_position,
        "end": end,
    })
}

fn difference_json(d: &Difference) -> Map<String, Value> {
    let mut m = Map::new();
    m.insert("kind".into(), json!(d.kind()));
    m.insert(
        "good".into(),
        d.good.as_ref().map_or(Value::Null, told_json),
    );
    m.insert("bad".into(), d.bad.as_ref().map_or(Value::Null, told_json));
    m
}

/// A step with its line, kind, words and the fields a script selects on.
fn told_json(t: &Told) -> Value {
    let mut m = Map::new();
    m.insert("line".into(), json!(t.line));
    m.insert("kind".into(), json!(t.step.kind()));
    match &t.step {
        Step::Emcy { code, register } => {
            m.insert("code".into(), json!(format!("{code:#06x}")));
            m.insert("register".into(), json!(format!("{register:#04x}")));
        }
        Step::Nmt { state, commanded } => {
            m.insert("state".into(), json!(state.slug()));
            m.insert("commanded".into(), json!(commanded));
        }
        Step::DriveState(s) => {
            m.insert("state".into(), json!(s.slug()));
        }
        Step::SdoAbort {
            index,
            subindex,
            abort_code,
            ..
        } => {
            m.insert("index".into(), json!(format!("{index:#06x}")));
            m.insert("subindex".into(), json!(subindex));
            m.insert("abort_code".into(), json!(format!("{abort_code:#010x}")));
        }
        _ => {}
    }
    m.insert("text".into(), json!(t.step.to_string()));
    Value::Object(m)
}
