//! A node's configuration as a DCF-style INI file (CiA 306 sections and
//! keys, `;` comments naming the lines) or JSON, and its differences from
//! the node's DCF.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde_json::{Value as Json, json};

use super::{Configuration, NodeKey, Refused, Value, Written};
use crate::canopen::dcf::{self, Dcf};
use crate::canopen::sdo::Object;
use crate::canopen::sdo::transfer::Outcome;
use crate::report::format::push_hex;

/// The first line of every file `config` writes: how it knows a file it
/// may write over is its own.
pub const HEADER: &str = "; emcy-decode config:";

/// The member of every JSON document `config` writes that says so: how it
/// knows a file it may write over is its own.
pub const JSON_MARK: &str = "\"written_by\": \"emcy-decode config\"";

/// An object the trace wrote whose value differs from the node's DCF (or
/// that the DCF does not have).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Difference {
    pub object: Object,
    /// The value the node confirmed, as the INI file writes it.
    pub trace: String,
    /// The DCF's value (ParameterValue, else DefaultValue) and its line;
    /// `None` when the file has no value for the object.
    pub file: Option<(String, u64)>,
}

/// The section CiA 306 gives an object: `[1A00sub1]`, and `[1017]` for
/// sub-index 0 of an object no other sub-index of which was written.
fn section(object: Object, alone: bool) -> String {
    if object.sub == 0 && alone {
        format!("{:04X}", object.index)
    } else {
        format!("{:04X}sub{:X}", object.index, object.sub)
    }
}

/// A value as `ParameterValue` writes it: a text as it is, a number of up
/// to four bytes in hex with two digits a byte (`0x60410010`, `0x01`);
/// `None` for longer data, which has no number.
pub fn parameter_value(v: &Value) -> Option<String> {
    if let Some(text) = &v.text {
        return Some(text.clone());
    }
    let n = v.data.number()?;
    Some(format!("0x{n:0width$X}", width = 2 * v.data.size as usize))
}

/// The data in hex (its first 64 bytes, `...` after when longer).
fn hex(data: &crate::canopen::sdo::transfer::Data) -> String {
    let mut out = Vec::new();
    push_hex(&mut out, data.shown());
    let more = if data.complete() { "" } else { "..." };
    format!("{}{more}", String::from_utf8_lossy(&out))
}

/// Why a write did not take, in words.
fn refusal(r: &Refused) -> String {
    let tried = r
        .data
        .filter(|d| d.whole && d.size > 0)
        .map(|d| format!(" of {}", hex(&d)))
        .unwrap_or_default();
    let how = match r.outcome {
        Outcome::Abort { code, by_server } => format!(
            "aborted by the {}, 0x{code:08X} {}",
            if by_server { "node" } else { "client" },
            r.text.unwrap_or_default()
        ),
        Outcome::Unanswered => "never answered".to_string(),
        Outcome::Incomplete => "not completed by the client".to_string(),
        Outcome::Ok => "not confirmed".to_string(),
    };
    format!("line {}: a write{tried} {how}; not applied", r.line)
}

/// Whether no other sub-index of `object`'s index was written.
fn alone(objects: &BTreeMap<Object, Written>, object: Object) -> bool {
    !objects
        .keys()
        .any(|o| o.index == object.index && o.sub != object.sub)
}

/// The objects the trace wrote whose values differ from `dcf`'s.
pub fn differences(
    objects: &BTreeMap<Object, Written>,
    dcf: &Dcf,
    node: crate::canopen::NodeId,
) -> Vec<Difference> {
    let mut out = Vec::new();
    for (&object, w) in objects {
        let Some(applied) = &w.applied else { continue };
        let Some(trace) = parameter_value(applied) else {
            continue;
        };
        let declared = dcf.objects.get(&object).and_then(|d| d.value());
        let same = declared.is_some_and(|raw| match applied.data.number() {
            Some(n) if applied.text.is_none() => dcf::integer(&raw.text, node) == Ok(n),
            _ => raw.text == trace,
        });
        if !same {
            out.push(Difference {
                object,
                trace,
                file: declared.map(|raw| (raw.text.clone(), raw.line)),
            });
        }
    }
    out
}

/// A node's configuration as a DCF-style INI file. `dcf` is the node's
/// DCF (its name and contents) to compare with.
pub fn ini(
    config: &Configuration,
    key: &NodeKey,
    objects: &BTreeMap<Object, Written>,
    dcf: Option<(&str, &Dcf)>,
) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{HEADER} node {} on {}, as {} wrote it and the node confirmed it",
        key.node,
        if key.channel.is_empty() {
            "its bus"
        } else {
            &key.channel
        },
        config.file
    );
    out.push_str(
        "; The last confirmed value of each object; writes the node did not take are\n\
         ; comments, never values.\n",
    );
    if let Some(e) = &config.error {
        let _ = writeln!(out, "; reading stopped early: {e}");
    }
    if let Some((name, dcf)) = dcf {
        let diffs = differences(objects, dcf, key.node);
        if diffs.is_empty() {
            let _ = writeln!(out, "; every value agrees with {name}");
        } else {
            let _ = writeln!(out, "; differences from {name}:");
            for d in &diffs {
                let file = match &d.file {
                    // A value written with `$NODEID` or in decimal, as the
                    // trace's is written too.
                    Some((v, line)) => match dcf::integer(v, key.node) {
                        Ok(n) if !v.eq_ignore_ascii_case(&format!("0x{n:08X}")) => {
                            format!("{v} = 0x{n:08X} (line {line})")
                        }
                        _ => format!("{v} (line {line})"),
                    },
                    None => "no value".to_string(),
                };
                let _ = writeln!(
                    out,
                    ";   [{}] trace {}, file {file}",
                    section(d.object, alone(objects, d.object)),
                    d.trace
                );
            }
        }
    }
    out.push_str("\n[DeviceComissioning]\n");
    let _ = writeln!(out, "NodeID={}", key.node);
    for (&object, w) in objects {
        let name = section(object, alone(objects, object));
        out.push('\n');
        match &w.applied {
            Some(v) => {
                let _ = writeln!(out, "[{name}]");
                if let Some(n) = &w.name {
                    let _ = writeln!(out, "ParameterName={n}");
                }
                match parameter_value(v) {
                    Some(value) => {
                        let _ = writeln!(out, "ParameterValue={value}");
                    }
                    None => {
                        let shown = if v.data.whole {
                            format!("{} (hash {:016x})", hex(&v.data), v.data.hash)
                        } else {
                            "its segments not read".to_string()
                        };
                        let _ = writeln!(out, "; {} bytes, no number: {shown}", v.data.size);
                    }
                }
                let writes = if w.writes > 1 {
                    format!(" (the last of {} writes)", w.writes)
                } else {
                    String::new()
                };
                let _ = writeln!(out, "; line {}{writes}", v.line);
            }
            None => {
                let _ = writeln!(out, "; [{name}] never applied");
            }
        }
        if let Some(r) = &w.refused {
            let _ = writeln!(out, "; {}", refusal(r));
        }
    }
    out
}

/// Every selected node's configuration as one JSON document.
pub fn json(config: &Configuration, dcfs: &[(crate::canopen::NodeId, String, &Dcf)]) -> String {
    let nodes: Vec<Json> = config
        .nodes
        .iter()
        .map(|(key, objects)| {
            let items: Vec<Json> = objects
                .iter()
                .map(|(&object, w)| {
                    let applied = w.applied.as_ref();
                    json!({
                        "index": format!("0x{:04X}", object.index),
                        "subindex": object.sub,
                        "name": w.name,
                        "status": if applied.is_some() { "applied" } else { "not_applied" },
                        "value": applied.and_then(parameter_value),
                        "data": applied.filter(|v| v.data.whole).map(|v| hex(&v.data)),
                        "size": applied.map(|v| v.data.size),
                        "line": applied.map(|v| v.line),
                        "writes": w.writes,
                        "refused": w.refused.as_ref().map(|r| json!({
                            "result": r.outcome.name(),
                            "abort_code": match r.outcome {
                                Outcome::Abort { code, .. } => Some(format!("0x{code:08X}")),
                                _ => None,
                            },
                            "abort_text": r.text,
                            "line": r.line,
                            "text": refusal(r),
                        })),
                    })
                })
                .collect();
            let dcf = dcfs
                .iter()
                .find(|(n, _, _)| *n == key.node)
                .map(|(_, name, dcf)| {
                    let diffs: Vec<Json> = differences(objects, dcf, key.node)
                        .iter()
                        .map(|d| {
                            json!({
                                "index": format!("0x{:04X}", d.object.index),
                                "subindex": d.object.sub,
                                "trace": d.trace,
                                "file": d.file.as_ref().map(|(v, _)| v),
                                "file_line": d.file.as_ref().map(|(_, l)| l),
                            })
                        })
                        .collect();
                    json!({"file": name, "differences": diffs})
                });
            json!({
                "channel": key.channel,
                "node": key.node,
                "objects": items,
                "dcf": dcf,
            })
        })
        .collect();
    let doc = json!({
        "written_by": "emcy-decode config",
        "file": config.file,
        "nodes": nodes,
        "cut": config.cut,
        "error": config.error,
    });
    let mut text = serde_json::to_string_pretty(&doc).unwrap_or_default();
    text.push('\n');
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canopen::sdo::transfer::Data;

    fn value(bytes: &[u8], text: Option<&str>) -> Value {
        Value {
            data: Data::of(bytes),
            text: text.map(str::to_string),
            line: 1,
        }
    }

    #[test]
    fn sections_as_cia_306_names_them() {
        let o = |index, sub| Object { index, sub };
        assert_eq!(section(o(0x1A00, 1), true), "1A00sub1");
        assert_eq!(section(o(0x1A00, 0), false), "1A00sub0");
        assert_eq!(section(o(0x1017, 0), true), "1017");
        assert_eq!(section(o(0x2000, 0x1F), false), "2000sub1F");
    }

    #[test]
    fn values_as_parameter_value_writes_them() {
        assert_eq!(parameter_value(&value(&[1], None)).as_deref(), Some("0x01"));
        assert_eq!(
            parameter_value(&value(&[0xE8, 0x03], None)).as_deref(),
            Some("0x03E8")
        );
        assert_eq!(
            parameter_value(&value(&[0x10, 0, 0x41, 0x60], None)).as_deref(),
            Some("0x60410010")
        );
        assert_eq!(parameter_value(&value(&[1, 2, 3, 4, 5], None)), None);
        assert_eq!(
            parameter_value(&value(b"X12", Some("X12"))).as_deref(),
            Some("X12")
        );
    }

    #[test]
    fn refused_writes_say_why() {
        let r = Refused {
            outcome: Outcome::Abort {
                code: 0x0609_0030,
                by_server: true,
            },
            text: Some("invalid value"),
            data: Some(Data::of(&[0xE8, 0x03])),
            line: 9,
        };
        assert_eq!(
            refusal(&r),
            "line 9: a write of E803 aborted by the node, 0x06090030 invalid value; not applied"
        );
        let r = Refused {
            outcome: Outcome::Unanswered,
            text: None,
            data: None,
            line: 3,
        };
        assert_eq!(refusal(&r), "line 3: a write never answered; not applied");
    }
}
