//! Replays the fuzz corpus and the inputs of every crash the fuzzers found
//! (`fuzz/corpus/<target>/`, `fuzz/regressions/<target>/`) through the same
//! library functions the cargo-fuzz targets call (`emcy_decode::fuzzing`),
//! on stable Rust: a fixed bug that comes back, or an invariant that stops
//! holding, fails here without nightly or cargo-fuzz.

use std::fs;
use std::panic;
use std::path::{Path, PathBuf};

use emcy_decode::fuzzing;

/// A fuzz target's body.
type Body = fn(&[u8]);

/// The fuzz targets (`fuzz/fuzz_targets/`) and the bodies they run.
const TARGETS: [(&str, Body); 13] = [
    ("candump_log", fuzzing::candump_log),
    ("candump_screen", fuzzing::candump_screen),
    ("asc", fuzzing::asc),
    ("trc", fuzzing::trc),
    ("busmaster", fuzzing::busmaster),
    ("ixxat", fuzzing::ixxat),
    ("blf", fuzzing::blf),
    ("pcap", fuzzing::pcap),
    ("ethercat", fuzzing::ethercat),
    ("mf4", fuzzing::mf4),
    ("detect", fuzzing::detect),
    ("decode_timeline", fuzzing::decode_timeline),
    ("dcf", fuzzing::dcf),
];

fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut out: Vec<PathBuf> = entries
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.is_file())
        .collect();
    out.sort();
    out
}

/// Runs every file of `fuzz/<kind>/<target>/` through its target, and with
/// `also_detect` through `detect` too (any bytes are a trace to it); returns
/// how many ran. Failures are collected so one run names them all.
fn replay(kind: &str, also_detect: bool) -> usize {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz")
        .join(kind);
    let mut ran = 0;
    let mut failed = Vec::new();
    for (target, body) in TARGETS {
        for path in files(&root.join(target)) {
            let data = fs::read(&path).expect("readable input");
            ran += 1;
            if panic::catch_unwind(|| body(&data)).is_err() {
                failed.push(format!("{} ({target})", path.display()));
            }
            if also_detect
                && target != "detect"
                && panic::catch_unwind(|| fuzzing::detect(&data)).is_err()
            {
                failed.push(format!("{} (detect)", path.display()));
            }
        }
    }
    assert!(failed.is_empty(), "fuzz inputs that fail: {failed:#?}");
    ran
}

#[test]
fn every_regression_input_passes_its_target() {
    let ran = replay("regressions", true);
    assert!(
        ran >= 5,
        "the regression corpus is in the repo ({ran} inputs)"
    );
}

#[test]
fn the_committed_corpus_passes_its_target() {
    let ran = replay("corpus", false);
    assert!(ran >= 5, "the corpus is in the repo ({ran} inputs)");
}
