//! What the integration tests share: the binary with a neutral
//! environment, golden files, the trace generator and its random numbers,
//! and the proptest strategies for frames in every text format.

pub mod frames;
pub mod golden;
pub mod tracegen;

use emcy_decode::{CanFrame, Format, Record, TraceReader};
use proptest::prelude::*;
use serde_json::Value;

/// The binary as a plain process (for a pid, a stream, a child to signal)
/// with a neutral terminal environment, so output never depends on who
/// runs the tests.
pub fn binary() -> std::process::Command {
    let mut cmd = std::process::Command::new(assert_cmd::cargo::cargo_bin("emcy-decode"));
    cmd.env_remove("COLUMNS")
        .env_remove("NO_COLOR")
        .env_remove("CLICOLOR_FORCE")
        .env_remove("CI");
    cmd
}

/// [`binary`] as an `assert_cmd` command (`.assert()`, `.write_stdin()`,
/// `.timeout()`).
pub fn emcy_decode() -> assert_cmd::Command {
    assert_cmd::Command::from_std(binary())
}

/// The objects the binary prints with `--format ndjson` and `args` (flags,
/// then the trace).
pub fn ndjson<I, S>(args: I) -> Vec<Value>
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .args(args)
        .output()
        .expect("runs");
    String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("valid JSON line"))
        .collect()
}

/// `object` without the `keys` that depend on the trace format (file, line,
/// channel, times...), also in the errors of a node object: what must be the
/// same whichever format a scenario was recorded in.
pub fn without(object: &Value, keys: &[&str]) -> Value {
    let mut v = object.clone();
    if let Some(o) = v.as_object_mut() {
        for k in keys {
            o.remove(*k);
        }
        if let Some(Value::Array(errors)) = o.get_mut("errors") {
            for e in errors.iter_mut() {
                *e = without(e, keys);
            }
        }
        // A node's identity names the lines of its answers.
        if let Some(Value::Object(identity)) = o.get_mut("identity") {
            for value in identity.values_mut() {
                *value = without(value, keys);
            }
        }
    }
    v
}

/// The event and node objects of a run (not the input object), each
/// [`without`] `keys`.
///
/// Formats record an error frame in more or less detail (its classes and
/// counters, a bus-off, only that there was one) or not at all, and the
/// fixtures of one scenario in several formats hold what each format can:
/// the bus's own events (`bus_error`, a controller's `bus_off`) are left out
/// here, and so are incidents, which are made of them and name lines.
/// `error_frames.rs` compares them on fixtures that record them alike.
pub fn semantic(objects: &[Value], keys: &[&str]) -> Vec<Value> {
    objects
        .iter()
        // An input's and its channels' counts: what a format records (an
        // error frame, a SYNC one writer adds) differs, and the callers
        // compare those counts themselves.
        .filter(|o| o["type"] != "input" && o["type"] != "channel")
        .filter(|o| o["type"] != "bus_error" && !(o["type"] == "bus_off" && o["node"].is_null()))
        .filter(|o| o["type"] != "incident")
        .map(|o| {
            // What a format records of an error frame beyond its being
            // one differs (candump logs its class bits and counters, ASC
            // only that it came), and an EMCY's burst is a time.
            let mut v = without(&without(o, keys), &ERROR_FRAME_DETAIL);
            without_time_texts(&mut v);
            v
        })
        .collect()
}

/// Keys whose values depend on how much a format records of error frames.
pub const ERROR_FRAME_DETAIL: [&str; 4] = ["kinds", "tx_errors_max", "rx_errors_max", "bus_error"];

/// What depends on where a trace is and how its lines are laid out.
pub const PLACE: [&str; 5] = ["file", "line", "channel", "start_line", "end_line"];

/// What depends on how a format writes times.
pub const TIMES: [&str; 13] = [
    "time",
    "time_text",
    "start",
    "start_text",
    "end",
    "end_text",
    "duration",
    "time_in_error",
    "longest_error",
    "first_emcy",
    "first_emcy_text",
    "last_emcy",
    "last_emcy_text",
];

/// Reads `lines` as one trace, the format detected ([`TraceReader::new`]):
/// every line but the last must be skipped (headers), the last a frame.
/// Returns that frame and the format the reader detected.
pub fn read_last(lines: &[String]) -> Result<(CanFrame, Option<Format>), TestCaseError> {
    let text = lines.join("\n");
    let mut reader = TraceReader::new(text.as_bytes());
    let records: Vec<Record> = reader
        .by_ref()
        .collect::<Result<_, _>>()
        .map_err(|e| TestCaseError::fail(format!("{text:?}: {e}")))?;
    prop_assert_eq!(records.len(), lines.len(), "{:?}: {:?}", text, records);
    let (last, header) = records.split_last().expect("at least one line");
    for (i, h) in header.iter().enumerate() {
        prop_assert_eq!(h, &Record::Skipped { line: i as u64 + 1 }, "{}", lines[i]);
    }
    match last {
        Record::Frame(got) => Ok((got.clone(), reader.format())),
        other => Err(TestCaseError::fail(format!(
            "{:?} -> {other:?}",
            lines.last()
        ))),
    }
}

/// The README, then the guide's pages (docs/guide/*.md) in name order.
pub fn documentation() -> Vec<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut guide: Vec<_> = std::fs::read_dir(root.join("docs/guide"))
        .expect("docs/guide")
        .map(|e| e.expect("docs/guide entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    guide.sort();
    std::iter::once(root.join("README.md"))
        .chain(guide)
        .collect()
}

/// The lines of the code block between `<!-- NAME:start -->` and
/// `<!-- NAME:end -->` in the README or a page of the guide, without the
/// fences.
pub fn readme_block(name: &str) -> Vec<String> {
    let start = format!("<!-- {name}:start -->");
    let end = format!("<!-- {name}:end -->");
    let readme = documentation()
        .iter()
        .map(|p| std::fs::read_to_string(p).expect("documentation page"))
        .find(|text| text.contains(&start))
        .expect("start marker");
    let from = readme.find(&start).expect("start marker") + start.len();
    let to = readme[from..].find(&end).expect("end marker") + from;
    readme[from..to]
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with("```"))
        .map(str::to_string)
        .collect()
}

/// The input object of an ndjson run.
pub fn input(v: &[Value]) -> &Value {
    v.iter()
        .find(|o| o["type"] == "input")
        .expect("input object")
}

/// [`semantic`] without the place keys, times as text with 6 decimals:
/// what a scenario must give whatever the format's time precision (a
/// nanosecond pcap prints 9 digits, an MF4 master channel 6 or 9).
pub fn semantic_6(objects: &[Value]) -> Vec<Value> {
    let mut v = semantic(objects, &PLACE);
    v.iter_mut().for_each(six_decimals);
    v
}

/// The `_text` twins of times (README, JSON contract), at any depth: they
/// say the number's digits, which differ between formats in their count.
pub const TIME_TEXTS: [&str; 8] = [
    "time_text",
    "start_text",
    "end_text",
    "first_emcy_text",
    "last_emcy_text",
    "last_seen_text",
    "first_time_text",
    "last_time_text",
];

/// `v` without the [`TIME_TEXTS`] keys, at any depth.
pub fn without_time_texts(v: &mut Value) {
    match v {
        Value::Array(a) => a.iter_mut().for_each(without_time_texts),
        Value::Object(o) => {
            for k in TIME_TEXTS {
                o.remove(k);
            }
            o.values_mut().for_each(without_time_texts);
        }
        _ => {}
    }
}

fn six_decimals(v: &mut Value) {
    match v {
        Value::Number(n) => {
            if let Some(f) = n.as_f64()
                && n.to_string().contains('.')
            {
                *v = Value::String(format!("{f:.6}"));
            }
        }
        Value::Array(a) => a.iter_mut().for_each(six_decimals),
        Value::Object(o) => o.values_mut().for_each(six_decimals),
        _ => {}
    }
}

/// Runs the binary with `args`, `stdin` on its standard input:
/// (stdout, stderr, exit code).
pub fn run(args: &[&str], stdin: &[u8]) -> (String, String, i32) {
    let out = emcy_decode()
        .args(args)
        .write_stdin(stdin.to_vec())
        .output()
        .expect("runs");
    (
        String::from_utf8(out.stdout).expect("utf-8"),
        String::from_utf8(out.stderr).expect("utf-8"),
        out.status.code().unwrap_or(-1),
    )
}

/// A CI rig as a user's pipeline has one: `rig.log` in a temporary folder,
/// a baseline `base.json` recorded from it, later checked against it.
pub struct Rig {
    dir: tempfile::TempDir,
}

impl Rig {
    /// A rig whose trace is `text`.
    pub fn new(text: &str) -> Rig {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join("rig.log"), text).expect("write");
        Rig { dir }
    }

    /// The trace becomes the file at `path`.
    pub fn trace_from(&self, path: &str) {
        std::fs::copy(path, self.dir.path().join("rig.log")).expect("copy");
    }

    /// Records the baseline (with `options`); returns its text.
    pub fn baseline(&self, options: &[&str]) -> String {
        emcy_decode()
            .current_dir(self.dir.path())
            .arg("baseline")
            .args(options)
            .args(["-o", "base.json", "rig.log"])
            .assert()
            .success();
        std::fs::read_to_string(self.dir.path().join("base.json")).expect("baseline")
    }

    /// Checks the trace against the baseline: the exit code and the JSON
    /// report's findings of `kind`.
    pub fn check(&self, kind: &str) -> (Option<i32>, Vec<Value>) {
        let out = emcy_decode()
            .current_dir(self.dir.path())
            .args(["check", "-b", "base.json", "--format", "json", "rig.log"])
            .output()
            .expect("runs");
        let doc: Value = serde_json::from_slice(&out.stdout).expect("json");
        let found = doc["findings"]
            .as_array()
            .map(|f| f.iter().filter(|f| f["kind"] == kind).cloned().collect())
            .unwrap_or_default();
        (out.status.code(), found)
    }
}
