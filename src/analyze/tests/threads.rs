//! Threads the system will not start: every spawn of the pipeline falls
//! back to fewer threads, at least the calling one, and the output is what
//! the threads asked for would have given. (Spawns are refused with the
//! test hook `threads::spawn_limit`; the renderers' helpers are tested in
//! `report::ordered`.)

use std::fs;

use crate::analyze::batch;
use crate::analyze::threads::spawn_limit;
use crate::analyze::{DiagnosticLog, Options, Sink, analyze, analyze_source};
use crate::report::ndjson::Ndjson;
use crate::trace::input::{ReadMode, Source};

/// EMCYs that raise and clear, with a malformed line now and then.
fn trace(lines: u32, seed: u32) -> Vec<u8> {
    let mut t = Vec::new();
    for i in 0..lines {
        let node = 1 + (i + seed) % 5;
        let line = match i % 9 {
            0 => "garbage that is not a frame\n".to_string(),
            1 | 4 => format!(
                "({}.0) can0 {:03X}#1043090100000000\n",
                1000 + i,
                0x80 + node
            ),
            2 => format!(
                "({}.0) can0 {:03X}#0000000000000000\n",
                1000 + i,
                0x80 + node
            ),
            _ => format!("({}.0) can1 181#{:016X}\n", 1000 + i, u64::from(i) * 7919),
        };
        t.extend(line.bytes());
    }
    t
}

/// Stdout and stderr of one input read with `threads` threads, `allowed`
/// spawns let through.
fn read(trace: &[u8], threads: usize, allowed: Option<usize>) -> (String, String) {
    let opts = Options {
        threads,
        block_size: 256,
        max_diagnostics: 50,
        ..Options::default()
    };
    let (mut out, mut err) = (Vec::new(), Vec::new());
    {
        let mut renderer = Ndjson::new(&mut out, false);
        let mut log = DiagnosticLog::new(&mut err);
        spawn_limit::allow(allowed);
        let analysis = analyze("trace", trace, false, &opts, &mut renderer, &mut log);
        spawn_limit::allow(None);
        let analysis = analysis.expect("output to a Vec cannot fail");
        let collected = std::mem::take(&mut log.collected);
        renderer.finish(&[analysis.report], &collected).unwrap();
    }
    (
        String::from_utf8(out).unwrap(),
        String::from_utf8(err).unwrap(),
    )
}

#[test]
fn block_workers_that_cannot_start_are_done_without() {
    let trace = trace(3000, 0);
    let reference = read(&trace, 1, None);
    assert!(reference.0.contains("\"type\":\"emcy\""));
    assert!(
        reference.1.contains("trace:10: expected"),
        "{}",
        reference.1
    );
    // None, one or two of three workers start; the rest is done without.
    for allowed in [None, Some(0), Some(1), Some(2)] {
        let got = read(&trace, 3, allowed);
        assert_eq!(got.1, reference.1, "{allowed:?} of 3 workers started");
        assert!(got.0 == reference.0, "{allowed:?} of 3 workers started");
    }
}

/// Small files read side by side (`batch`), replayed into one renderer and
/// log: stdout and stderr, with `allowed` spawns let through.
fn read_side_by_side(
    sources: &[Source],
    threads: usize,
    quiet: bool,
    allowed: Option<usize>,
) -> (String, String) {
    let opts = Options::default();
    let (mut out, mut err) = (Vec::new(), Vec::new());
    {
        let mut renderer = Ndjson::new(&mut out, false);
        let mut log = DiagnosticLog::new(&mut err);
        log.quiet = quiet;
        let mut reports = Vec::new();
        spawn_limit::allow(allowed);
        let done = batch::run_parallel(sources, &opts, threads, quiet, |result| {
            reports.extend(result.replay(&mut renderer, &mut log)?.map(|a| a.report));
            Ok(())
        });
        spawn_limit::allow(None);
        done.expect("output to a Vec cannot fail");
        let collected = std::mem::take(&mut log.collected);
        renderer.finish(&reports, &collected).unwrap();
    }
    (
        String::from_utf8(out).unwrap(),
        String::from_utf8(err).unwrap(),
    )
}

/// The same files read one after another on this thread.
fn read_one_by_one(sources: &[Source], quiet: bool) -> (String, String) {
    let opts = Options::default();
    let (mut out, mut err) = (Vec::new(), Vec::new());
    {
        let mut renderer = Ndjson::new(&mut out, false);
        let mut log = DiagnosticLog::new(&mut err);
        log.quiet = quiet;
        let mut reports = Vec::new();
        for source in sources {
            let analysis = analyze_source(
                source,
                ReadMode::Finite,
                &opts,
                |_| 1,
                |_, reader| reader,
                &mut renderer,
                &mut log,
            )
            .expect("output to a Vec cannot fail");
            reports.push(analysis.report);
        }
        let collected = std::mem::take(&mut log.collected);
        renderer.finish(&reports, &collected).unwrap();
    }
    (
        String::from_utf8(out).unwrap(),
        String::from_utf8(err).unwrap(),
    )
}

fn small_files(dir: &tempfile::TempDir) -> Vec<Source> {
    (0..5u32)
        .map(|i| {
            let path = dir.path().join(format!("{i}.log"));
            fs::write(&path, trace(200 + 50 * i, i)).unwrap();
            Source::Path(path)
        })
        .collect()
}

#[test]
fn side_by_side_threads_that_cannot_start_are_done_without() {
    let dir = tempfile::tempdir().unwrap();
    let sources = small_files(&dir);
    let reference = read_one_by_one(&sources, false);
    assert!(
        reference.1.contains("0.log:10: expected"),
        "{}",
        reference.1
    );
    for allowed in [0, 1, 2] {
        assert!(
            read_side_by_side(&sources, 3, false, Some(allowed)) == reference,
            "{allowed} of 3 threads started"
        );
    }
}

/// `--quiet` holds for files read side by side as for files read in turn.
#[test]
fn side_by_side_reading_is_quiet_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let sources = small_files(&dir);
    let quiet = read_one_by_one(&sources, true);
    assert!(!quiet.1.contains(": expected"), "{}", quiet.1);
    assert_eq!(read_side_by_side(&sources, 2, true, None), quiet);
}
