//! The library's public API (`emcy_decode::*`), checked against what the
//! program reports for the same fixtures, and the guide's example (docs/guide/library.md).

use std::fs::File;

use emcy_decode::{At, Emcy, NodeTimeline, Profile, Record, State, TraceReader};
use serde_json::Value;

use crate::support::golden::fixtures;
use crate::support::{ndjson, readme_block};

/// The guide's "As a library" block is examples/node_timeline.rs, which
/// `cargo test` builds: the guide cannot show code that does not compile.
#[test]
fn the_readme_library_example_is_the_example_file() {
    let example = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/node_timeline.rs"),
    )
    .expect("examples/node_timeline.rs");
    let code: Vec<&str> = example
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with("//!"))
        .collect();
    assert_eq!(readme_block("library-example"), code);
}

/// `TraceReader` classifies every line of every fixture as the program
/// counts them: one record per line, frames, skipped and malformed lines.
#[test]
fn the_trace_reader_counts_every_fixture_as_the_program_does() {
    for fixture in fixtures() {
        let (mut lines, mut frames, mut skipped, mut malformed) = (0u64, 0u64, 0u64, 0u64);
        let mut reader = TraceReader::new(File::open(&fixture).expect("fixture"));
        for record in reader.by_ref() {
            match record.expect("fixtures read without I/O errors") {
                Record::Frame(_) => frames += 1,
                Record::Skipped { .. } => skipped += 1,
                Record::Malformed { .. } => malformed += 1,
                // About the frame of the same line, not a line of its own.
                Record::Note(_) | Record::Warning { .. } => continue,
                _ => unreachable!("a record kind this test does not know"),
            }
            lines += 1;
        }
        let objects = ndjson([fixture.as_os_str()]);
        let input = objects
            .iter()
            .find(|o| o["type"] == "input")
            .expect("an input object");
        let counts = input;
        let name = fixture.display();
        assert_eq!(counts["lines"], Value::from(lines), "{name}: lines");
        assert_eq!(counts["frames"], Value::from(frames), "{name}: frames");
        assert_eq!(counts["skipped"], Value::from(skipped), "{name}: skipped");
        assert_eq!(
            counts["malformed"],
            Value::from(malformed),
            "{name}: malformed"
        );
        assert_eq!(
            reader.format().map(|f| f.name().to_string()),
            input["format"].as_str().map(str::to_string),
            "{name}: format"
        );
    }
}

/// Decoding every EMCY of a node into a `NodeTimeline` gives the node the
/// program reports: the same state and active codes at the end, the same
/// descriptions with the same profile.
#[test]
fn a_node_timeline_ends_where_the_program_says() {
    let kollmorgen = Profile::builtin("kollmorgen").expect("built-in");
    let mut timeline = NodeTimeline::new();
    let mut descriptions = Vec::new();
    for record in TraceReader::new(File::open("fixtures/s300.log").expect("fixture")) {
        let Record::Frame(frame) = record.expect("readable") else {
            continue;
        };
        let at = At {
            time: frame.time,
            line: frame.line,
        };
        if frame.boot_node() == Some(1) {
            timeline.boot(at);
        }
        if frame.emcy_node() != Some(1) {
            continue;
        }
        let emcy = Emcy::decode(&frame.data).expect("a whole EMCY");
        descriptions.push(kollmorgen.describe(emcy.code));
        timeline.emcy(&emcy, at, &mut Vec::new());
    }
    let objects = ndjson(["--profile", "kollmorgen", "fixtures/s300.log"]);
    let program: Vec<&str> = objects
        .iter()
        .filter(|o| o["type"] == "emcy" && o["node"] == 1)
        .map(|o| o["description"].as_str().expect("a description"))
        .collect();
    assert_eq!(descriptions, program);
    let node = objects
        .iter()
        .find(|o| o["type"] == "node" && o["node"] == 1)
        .expect("node 1");
    assert_eq!(node["state"], timeline.state().slug());
    assert_ne!(
        timeline.state(),
        State::ErrorFree,
        "the fixture ends in error"
    );
    let active: Vec<String> = timeline
        .active_codes()
        .map(|c| format!("0x{c:04X}"))
        .collect();
    assert_eq!(node["active"], serde_json::json!(active));
}

/// The program's crates come only with the `application` feature: a Rust
/// program that depends on the library with `default-features = false`
/// compiles none of them. Asked of Cargo's own resolution of the manifest,
/// so a dependency made non-optional again, or a feature that pulls one
/// in, fails here.
#[test]
fn the_library_alone_depends_on_none_of_the_programs_crates() {
    let tree = |features: &[&str]| -> String {
        let out = std::process::Command::new(env!("CARGO"))
            .args(["tree", "--offline", "--edges", "normal", "--prefix", "none"])
            .args(["--format", "{p}", "--package", "emcy-decode"])
            .args(features)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .expect("cargo tree runs");
        assert!(
            out.status.success(),
            "cargo tree: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).expect("cargo tree prints UTF-8")
    };
    let program_crates = [
        "clap ",
        "clap_complete ",
        "clap_mangen ",
        "globset ",
        "indicatif ",
        "same-file ",
        "signal-hook ",
        "terminal_size ",
        "walkdir ",
    ];
    let library = tree(&["--no-default-features"]);
    let program = tree(&[]);
    for name in program_crates {
        let listed = |tree: &str| tree.lines().any(|l| l.starts_with(name));
        assert!(!listed(&library), "the library alone depends on {name}");
        assert!(listed(&program), "the program no longer depends on {name}");
    }
}
