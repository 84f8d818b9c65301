//! The rule the folders show, checked: every import points down.
//!
//! ```text
//! app        the program: clap, one file per command, exit codes, signals
//! baseline   CI baseline model and comparison
//! report     renderers (implement analyze's Sink)
//! analyze    the pipeline: events, reports, the Sink trait
//! timeline   per-node state machine, error history
//! canopen    EMCY, code tables, SDO, profiles
//! trace      bytes -> frames (imports nothing of ours)
//! ```
//!
//! The trace readers are their own crate, `emcy-trace` in
//! `crates/emcy-trace`, which does not depend on this one: Cargo keeps them
//! from importing anything above them (a dependency back would be a cycle).
//! `src/trace` is what this crate adds in that layer (the owned-record
//! reader) and is checked here like the rest of `src`; the last test below
//! checks that the trace crate stays without this one.
//!
//! `cache` and `text` are utilities below everything (they import nothing
//! of ours);
//! `fuzzing` is the fuzz harness, which may use anything and which nothing
//! uses. A module may use its own layer and the layers below it. Tests are
//! not part of the house: a `tests` module (inline at the end of a file,
//! or a `tests/` folder) may check a layer through the ones above it. The
//! check reads the sources, so a `use crate::report` added to `analyze`
//! fails `cargo test` here with the file and line.

use std::path::{Path, PathBuf};

/// Bottom first.
const LAYERS: [&str; 7] = [
    "trace", "canopen", "timeline", "analyze", "report", "baseline", "app",
];

/// The rank of a top-level module; `None` for ones outside the stack.
fn rank(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| *l == module)
}

/// Why `from` may not name `to`, if it may not.
fn violation(from: &str, to: &str) -> Option<String> {
    if from == to {
        return None;
    }
    match (from, to) {
        (_, "fuzzing") => Some("nothing may use the fuzz harness".into()),
        ("fuzzing", _) => None,
        ("cache" | "text", _) => Some(format!("{from} is below everything and imports nothing")),
        (_, "cache" | "text") => None,
        _ => match (rank(from), rank(to)) {
            (Some(f), Some(t)) if t > f => Some(format!("{from} is below {to}")),
            (Some(_), Some(_)) => None,
            _ => Some(format!("{to} is not a known layer (add it to LAYERS)")),
        },
    }
}

/// The module path of a source file below src/: `src/analyze/consumer.rs`
/// is `["analyze", "consumer"]`, `src/analyze/mod.rs` is `["analyze"]`.
fn module_path(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The top-level modules a file's code names, with their lines:
/// `crate::x`, `crate::{x, y::z}`, and `super` chains that climb to the
/// crate root (`super::super::x` in a submodule). Line comments are
/// skipped (doc links name modules without importing them).
fn named_modules(module: &[String], text: &str) -> Vec<(usize, String)> {
    let code: String = text
        .lines()
        .map(|l| l.split("//").next().unwrap_or_default())
        .collect::<Vec<_>>()
        .join("\n");
    let line_at = |i: usize| code[..i].matches('\n').count() + 1;
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    // The names of `path::x` or of each item of `path::{x, y::z}`.
    let mut after_root = |at: usize, tail: &str| {
        if let Some(group) = tail.strip_prefix('{') {
            let mut depth = 0usize;
            let mut item_start = true;
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => item_start = true,
                    c if c.is_whitespace() => {}
                    _ if item_start && depth == 0 => {
                        item_start = false;
                        let name = ident(&group[k..]);
                        if !name.is_empty() && name != "self" {
                            out.push((line_at(at), name));
                        }
                    }
                    _ => {}
                }
            }
        } else {
            let name = ident(tail);
            if !name.is_empty() {
                out.push((line_at(at), name));
            }
        }
    };
    for (at, _) in code.match_indices("crate::") {
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // `foo_crate::`, not our crate
        }
        after_root(at, &code[at + 7..]);
    }
    let mut search = 0;
    while let Some(found) = code[search..].find("super::") {
        let at = search + found;
        let mut tail = &code[at..];
        let mut climbs = 0;
        while let Some(t) = tail.strip_prefix("super::") {
            climbs += 1;
            tail = t;
        }
        if climbs >= module.len() {
            after_root(at, tail);
        }
        search = at + 7 * climbs;
    }
    out
}

/// The text without inline `#[cfg(test)] mod tests { ... }` blocks (found
/// by brace depth; an unbalanced block runs to the end of the file).
fn without_test_module(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find("#[cfg(test)]") {
        let after = &rest[at + "#[cfg(test)]".len()..];
        if !after.trim_start().starts_with("mod tests") {
            out.push_str(&rest[..at + 1]);
            rest = &rest[at + 1..];
            continue;
        }
        out.push_str(&rest[..at]);
        let Some(open) = after.find('{') else {
            return out;
        };
        let mut depth = 0usize;
        let mut end = None;
        for (i, c) in after[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = Some(open + i + 1);
                        break;
                    }
                }
                _ => {}
            }
        }
        let Some(end) = end else {
            return out;
        };
        // Keep the lines counted: the block's newlines stay.
        out.extend(after[..end].chars().filter(|c| *c == '\n'));
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// Every import that points up, as `file:line: from -> to (why)`.
fn upward_imports(src: &Path) -> Vec<String> {
    let mut files = Vec::new();
    sources(src, &mut files);
    files.sort();
    let mut found = Vec::new();
    for file in files {
        let Ok(rel) = file.strip_prefix(src) else {
            continue;
        };
        let module = module_path(rel);
        // The crate root and the binary wire the layers together; this
        // file names modules in its own tests.
        let Some(from) = module
            .first()
            .filter(|m| !matches!(m.as_str(), "lib" | "main" | "layers"))
        else {
            continue;
        };
        if module.iter().any(|m| m == "tests") {
            continue;
        }
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        let text = without_test_module(&text);
        for (line, to) in named_modules(&module, &text) {
            if let Some(why) = violation(from, &to) {
                found.push(format!("{}:{line}: {from} -> {to} ({why})", file.display()));
            }
        }
    }
    found
}

#[test]
fn every_import_points_down() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let found = upward_imports(&src);
    assert!(
        found.is_empty(),
        "imports that point up:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_check_sees_what_it_must() {
    let module = |s: &str| module_path(Path::new(s));
    assert_eq!(module("analyze/mod.rs"), ["analyze"]);
    assert_eq!(
        module("analyze/tests/parallel.rs"),
        ["analyze", "tests", "parallel"]
    );
    let names = |m: &str, text: &str| -> Vec<String> {
        named_modules(&module(m), text)
            .into_iter()
            .map(|(_, n)| n)
            .collect()
    };
    assert_eq!(
        names("analyze/consumer.rs", "use crate::report::table;"),
        ["report"]
    );
    assert_eq!(
        names(
            "analyze/consumer.rs",
            "use crate::{\n    trace::Frame,\n    report::{a, b},\n};"
        ),
        ["trace", "report"]
    );
    assert_eq!(
        names("analyze/consumer.rs", "use super::super::report::x;"),
        ["report"]
    );
    assert_eq!(
        names("analyze/consumer.rs", "use super::sink::Sink;"),
        Vec::<String>::new()
    );
    assert_eq!(names("analyze/mod.rs", "use super::report::x;"), ["report"]);
    assert_eq!(
        names("trace/x.rs", "// crate::report in a comment"),
        Vec::<String>::new()
    );
    // A test module may name anything; code after it is still checked,
    // on its own line.
    let code = "use crate::trace::Frame;\n#[cfg(test)]\nmod tests {\n    use crate::report::x;\n}\nuse crate::app::y;\n";
    let checked = without_test_module(code);
    assert_eq!(
        checked,
        "use crate::trace::Frame;\n\n\n\n\nuse crate::app::y;\n"
    );
    assert_eq!(
        named_modules(&module("report/x.rs"), &checked),
        [(1, "trace".to_string()), (6, "app".to_string())]
    );
    assert!(violation("analyze", "report").is_some());
    assert!(violation("trace", "canopen").is_some());
    assert!(violation("report", "app").is_some());
    assert!(violation("cache", "trace").is_some());
    assert!(violation("app", "fuzzing").is_some());
    assert!(violation("report", "analyze").is_none());
    assert!(violation("app", "trace").is_none());
    assert!(violation("fuzzing", "app").is_none());
    assert!(violation("timeline", "cache").is_none());
    assert!(violation("analyze", "newthing").is_some());
}

#[test]
fn the_trace_crate_stays_below_everything() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/emcy-trace");
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).expect("the trace crate");
    // A dependency on this crate, in any of the ways a manifest says one.
    let depends = manifest.lines().map(str::trim).any(|l| {
        l.starts_with("emcy-decode")
            || l.starts_with("[dependencies.emcy-decode")
            || l.contains("\"emcy-decode\"")
    });
    assert!(
        !depends,
        "crates/emcy-trace/Cargo.toml depends on emcy-decode"
    );
    let mut files = Vec::new();
    sources(&root.join("src"), &mut files);
    assert!(files.len() > 20, "{} trace sources found", files.len());
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        assert!(
            !text.contains("emcy_decode"),
            "{} names emcy_decode",
            file.display()
        );
    }
}
