//! The rule the folders show, checked: every import points down.
//!
//! ```text
//! config     the configuration a trace wrote into its nodes
//! diff       two traces' CANopen stories and their comparison
//! baseline   CI baseline model and comparison
//! report     renderers (implement analyze's Sink)
//! analyze    the pipeline: events, reports, the Sink trait
//! timeline   per-node state machine, error history
//! canopen    EMCY, code tables, SDO, profiles
//! trace      bytes -> frames (imports nothing of ours)
//! ```
//!
//! The program (`src/bin/emcy-decode`, clap, one file per command, exit
//! codes, signals) stands on top, outside the library: Cargo lets it use
//! only what the library makes public and lets the library import nothing
//! of it, so it is not checked here.
//!
//! The trace readers are their own crate, `emcy-trace` in
//! `crates/emcy-trace`, which does not depend on this one: Cargo keeps them
//! from importing anything above them (a dependency back would be a cycle).
//! `src/trace` is what this crate adds in that layer (the owned-record
//! reader) and is checked here like the rest of `src`; the last test below
//! checks that the trace crate stays without this one.
//!
//! `cache`, `small_file` and `text` are utilities below everything (they
//! import nothing of ours);
//! `fuzzing` is the fuzz harness, which may use anything and which nothing
//! uses. A module may use its own layer and the layers below it. Tests are
//! not part of the house: a `tests` module (inline at the end of a file,
//! or a `tests/` folder) may check a layer through the ones above it. The
//! check reads the sources, so a `use crate::report` added to `analyze`
//! fails `cargo test` here with the file and line.

use std::path::{Path, PathBuf};

/// Bottom first.
const LAYERS: [&str; 8] = [
    "trace", "canopen", "timeline", "analyze", "report", "baseline", "diff", "config",
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
        ("cache" | "small_file" | "text", _) => {
            Some(format!("{from} is below everything and imports nothing"))
        }
        (_, "cache" | "small_file" | "text") => None,
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
        let Some(end) = block_end(after, open) else {
            return out;
        };
        // Keep the lines counted: the block's newlines stay.
        out.extend(after[..end].chars().filter(|c| *c == '\n'));
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// Where the block opened by the `{` at `open` ends (just past its `}`),
/// by brace depth; `None` when it is not closed.
fn block_end(text: &str, open: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (i, c) in text.get(open..)?.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth = depth.checked_sub(1)?;
                if depth == 0 {
                    return Some(open + i + 1);
                }
            }
            _ => {}
        }
    }
    None
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
        // The crate root wires the layers together; the program is a crate
        // of its own; this file names modules in its own tests.
        let Some(from) = module
            .first()
            .filter(|m| !matches!(m.as_str(), "lib" | "bin" | "layers"))
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
    let code = "use crate::trace::Frame;\n#[cfg(test)]\nmod tests {\n    use crate::report::x;\n}\nuse crate::baseline::y;\n";
    let checked = without_test_module(code);
    assert_eq!(
        checked,
        "use crate::trace::Frame;\n\n\n\n\nuse crate::baseline::y;\n"
    );
    assert_eq!(
        named_modules(&module("report/x.rs"), &checked),
        [(1, "trace".to_string()), (6, "baseline".to_string())]
    );
    assert!(violation("analyze", "report").is_some());
    assert!(violation("trace", "canopen").is_some());
    assert!(violation("report", "baseline").is_some());
    assert!(violation("cache", "trace").is_some());
    assert!(violation("baseline", "fuzzing").is_some());
    assert!(violation("report", "analyze").is_none());
    assert!(violation("baseline", "trace").is_none());
    assert!(violation("fuzzing", "baseline").is_none());
    assert!(violation("timeline", "cache").is_none());
    assert!(violation("analyze", "newthing").is_some());
}

// ---- circles between files ----------------------------------------------

/// The module a path names, resolved from the module `module` it is written
/// in: `crate::a::b::Item`, `super::x::Item`, `self::x::Item`, or
/// `child::Item` for a child module of the current one. The segments after
/// the prefix, longest first, are cut back to a module some file holds.
fn named_file(
    module: &[String],
    path: &[&str],
    files: &std::collections::BTreeMap<Vec<String>, PathBuf>,
) -> Option<PathBuf> {
    let (mut base, rest): (Vec<String>, &[&str]) = match path.first()? {
        &"crate" => (Vec::new(), &path[1..]),
        &"self" => (module.to_vec(), &path[1..]),
        &"super" => {
            let climbs = path.iter().take_while(|s| **s == "super").count();
            let keep = module.len().checked_sub(climbs)?;
            (module[..keep].to_vec(), &path[climbs..])
        }
        first => {
            let mut child = module.to_vec();
            child.push((*first).to_string());
            if !files.contains_key(&child) {
                return None;
            }
            (module.to_vec(), path)
        }
    };
    for segment in rest {
        base.push((*segment).to_string());
        if !files.contains_key(&base) {
            base.pop();
            break;
        }
    }
    files.get(&base).cloned()
}

/// The paths a file's code names, each as its segments, with `{a, b::c}`
/// groups expanded one level deep (`use super::{a::X, b}` names `super::a`
/// and `super::b`).
fn named_paths(code: &str) -> Vec<Vec<&str>> {
    let is_ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        // A path starts at a word not preceded by a word or by `::`.
        let after = i.checked_sub(1).map(|k| bytes[k] as char);
        // Only at an ASCII byte: a slice never starts inside a character.
        let starts_word = after.is_none_or(|c| !is_ident(c) && c != ':')
            && (bytes[i].is_ascii_alphabetic() || bytes[i] == b'_');
        if !starts_word {
            i += 1;
            continue;
        }
        let mut segments = Vec::new();
        let mut j = i;
        loop {
            let end = code[j..]
                .find(|c: char| !is_ident(c))
                .map_or(code.len(), |k| j + k);
            segments.push(&code[j..end]);
            j = end;
            if !code[j..].starts_with("::") {
                break;
            }
            j += 2;
            if code[j..].starts_with('{') {
                let close = code[j..].find('}').map_or(code.len(), |k| j + k);
                for item in code[j + 1..close].split(',') {
                    let item = item.trim();
                    let head: Vec<&str> = item
                        .split("::")
                        .map(str::trim)
                        .take_while(|s| !s.is_empty() && s.chars().all(is_ident))
                        .collect();
                    if !head.is_empty() {
                        out.push(segments.iter().copied().chain(head).collect());
                    }
                }
                j = close;
                segments.clear();
                break;
            }
            if !code[j..].starts_with(is_ident) {
                break;
            }
        }
        if segments.len() > 1 {
            out.push(segments);
        }
        i = j.max(i + 1);
    }
    out
}

/// The code with `super::` inside an inline `mod name { ... }` written as
/// `self::`: there it names the file's own module, not its parent.
fn inline_modules_own_supers(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(at) = rest.find("mod ") {
        let starts_word = rest[..at]
            .chars()
            .next_back()
            .is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        let after = &rest[at + 4..];
        let name_end = after
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(after.len());
        let opens = after[name_end..].trim_start().starts_with('{');
        if !starts_word || name_end == 0 || !opens {
            out.push_str(&rest[..at + 4]);
            rest = after;
            continue;
        }
        let open = at + 4 + name_end + after[name_end..].find('{').unwrap_or(0);
        let close = block_end(rest, open).unwrap_or(rest.len());
        out.push_str(&rest[..open]);
        out.push_str(&rest[open..close].replace("super::", "self::"));
        rest = &rest[close..];
    }
    out.push_str(rest);
    out
}

/// The code with `pub(in crate::x)` written as `pub`: it says who may see
/// an item and imports nothing.
fn without_visibility_paths(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(at) = rest.find("pub(in ") {
        out.push_str(&rest[..at + 3]);
        rest = &rest[at..];
        rest = rest.find(')').map_or("", |close| &rest[close + 1..]);
    }
    out.push_str(rest);
    out
}

/// Every set of library files that import each other round a circle (a
/// file naming another, directly or through others, that names it back),
/// each as its files' paths below src/, sorted.
fn import_circles(src: &Path) -> Vec<Vec<String>> {
    use std::collections::{BTreeMap, BTreeSet};
    let mut paths = Vec::new();
    sources(src, &mut paths);
    let mut files = BTreeMap::new();
    for path in &paths {
        let Ok(rel) = path.strip_prefix(src) else {
            continue;
        };
        let module = module_path(rel);
        if module.first().is_some_and(|m| m == "bin") || module.iter().any(|m| m == "tests") {
            continue;
        }
        let module = if module == ["lib"] {
            Vec::new()
        } else {
            module
        };
        files.insert(module, path.clone());
    }
    let mut edges: BTreeMap<PathBuf, BTreeSet<PathBuf>> = BTreeMap::new();
    for (module, path) in &files {
        let text = std::fs::read_to_string(path).unwrap_or_default();
        let code: String = without_test_module(&text)
            .lines()
            .map(|l| l.split("//").next().unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n");
        let code = without_visibility_paths(&inline_modules_own_supers(&code));
        let named = edges.entry(path.clone()).or_default();
        for segments in named_paths(&code) {
            if let Some(to) = named_file(module, &segments, &files)
                && &to != path
                && !to.ends_with("lib.rs")
            {
                named.insert(to);
            }
        }
    }
    // Tarjan's strongly connected components, by an explicit stack.
    let nodes: Vec<&PathBuf> = edges.keys().collect();
    let index_of: BTreeMap<&PathBuf, usize> =
        nodes.iter().enumerate().map(|(i, p)| (*p, i)).collect();
    let next: Vec<Vec<usize>> = nodes
        .iter()
        .map(|p| {
            edges[*p]
                .iter()
                .filter_map(|to| index_of.get(to).copied())
                .collect()
        })
        .collect();
    let n = nodes.len();
    let (mut index, mut low) = (vec![usize::MAX; n], vec![0; n]);
    let (mut on_stack, mut stack, mut counter) = (vec![false; n], Vec::new(), 0);
    let mut circles = Vec::new();
    for root in 0..n {
        if index[root] != usize::MAX {
            continue;
        }
        let mut work = vec![(root, 0usize)];
        while let Some(&mut (v, ref mut k)) = work.last_mut() {
            if *k == 0 && index[v] == usize::MAX {
                index[v] = counter;
                low[v] = counter;
                counter += 1;
                stack.push(v);
                on_stack[v] = true;
            }
            if let Some(&w) = next[v].get(*k) {
                *k += 1;
                if index[w] == usize::MAX {
                    work.push((w, 0));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            work.pop();
            if let Some(&(parent, _)) = work.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut circle = Vec::new();
                while let Some(w) = stack.pop() {
                    on_stack[w] = false;
                    circle.push(w);
                    if w == v {
                        break;
                    }
                }
                if circle.len() > 1 {
                    let mut names: Vec<String> = circle
                        .iter()
                        .map(|&w| {
                            let rel = nodes[w].strip_prefix(src).unwrap_or(nodes[w]);
                            rel.display().to_string()
                        })
                        .collect();
                    names.sort();
                    circles.push(names);
                }
            }
        }
    }
    circles.sort();
    circles
}

#[test]
fn no_files_import_each_other_round_a_circle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut shown = Vec::new();
    for src in ["src", "crates/emcy-trace/src"] {
        for circle in import_circles(&root.join(src)) {
            let files: Vec<String> = circle.iter().map(|f| format!("{src}/{f}")).collect();
            shown.push(files.join(" <-> "));
        }
    }
    assert!(
        shown.is_empty(),
        "files that import each other:\n{}",
        shown.join("\n")
    );
}

#[test]
fn the_circle_check_sees_what_it_must() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let write = |rel: &str, text: &str| {
        let path = dir.path().join(rel);
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("a folder");
        std::fs::write(path, text).expect("a source file");
    };
    write("lib.rs", "mod a;\nmod b;\nmod c;\nmod d;\n");
    write("d/e.rs", "use crate::d::inner;\n");
    // a <-> a/child through `super` and a child path; b -> c -> b through
    // a `crate::{...}` group; test modules and comments name nothing.
    write("a/mod.rs", "mod child;\nfn f() { child::g(); }\n");
    write("a/child.rs", "use super::f;\n");
    write("b.rs", "use crate::{c::X, a};\n// crate::c is a comment\n");
    write("c.rs", "pub struct X;\nfn g() { crate::b::h(); }\n");
    // An inline module's `super` is its own file.
    write(
        "d.rs",
        "const N: u8 = 1;\nmod inner {\n    fn n() -> u8 { super::N }\n}\n",
    );
    write(
        "lone.rs",
        "#[cfg(test)]\nmod tests {\n    use crate::b::x;\n}\n",
    );
    assert_eq!(
        import_circles(dir.path()),
        [vec!["a/child.rs", "a/mod.rs"], vec!["b.rs", "c.rs"]]
    );
    write("c.rs", "pub struct X;\n");
    assert_eq!(import_circles(dir.path()), [vec!["a/child.rs", "a/mod.rs"]]);
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
