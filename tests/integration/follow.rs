//! `--follow FILE` follows the name, like `tail -F`: logs rotated by rename
//! and recreate, deleted and recreated, truncated (also rewritten larger
//! between two looks, and `copytruncate`), a line cut by a truncation, a
//! path gone for a while. Each test is a writer (this thread) and the
//! binary; a change is made only once the binary has printed the event of
//! the line before it (or, on Linux, read the file to a given byte), then
//! Ctrl-C ends the run, and every EMCY written must be reported exactly
//! once, in order, nothing else.
#![cfg(unix)]

use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::mpsc::Receiver;

use serde_json::Value;

use crate::live::{WAIT, exit_within_wait, interrupt, lines_of, spawn};

/// The line of EMCY number `i`: its own time and data.
fn emcy(i: u32) -> String {
    format!("({}.000000) can0 085#{}\n", 1_700_000_000 + i, data(i))
}

fn data(i: u32) -> String {
    format!("104309{i:010X}")
}

fn emcys(range: std::ops::RangeInclusive<u32>) -> String {
    range.map(emcy).collect()
}

/// `--follow --format ndjson` on a file in a temporary directory.
struct Followed {
    child: Child,
    out: Receiver<String>,
    err: Receiver<String>,
    /// Objects printed so far, and stderr lines.
    objects: Vec<Value>,
    notes: Vec<String>,
    path: PathBuf,
    _dir: tempfile::TempDir,
}

impl Followed {
    fn start(initial: &str) -> Followed {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("can.log");
        fs::write(&path, initial).unwrap();
        let mut child = spawn(&["--follow", "--format", "ndjson", path.to_str().unwrap()]);
        let out = lines_of(child.stdout.take().unwrap());
        let err = lines_of(child.stderr.take().unwrap());
        Followed {
            child,
            out,
            err,
            objects: Vec::new(),
            notes: Vec::new(),
            path,
            _dir: dir,
        }
    }

    fn dir(&self) -> &Path {
        self.path.parent().unwrap()
    }

    /// Waits until the event of EMCY `i` is printed.
    fn wait_for(&mut self, i: u32) {
        let want = data(i);
        while !self.objects.iter().any(|o| o["data"] == want.as_str()) {
            let Ok(line) = self.out.recv_timeout(WAIT) else {
                panic!(
                    "EMCY {i} never came; got {:?}, stderr {:?}",
                    self.objects,
                    self.err.try_iter().collect::<Vec<_>>()
                );
            };
            self.objects.push(serde_json::from_str(&line).unwrap());
        }
    }

    /// Waits until stderr has a line containing `text`.
    fn wait_note(&mut self, text: &str) {
        while !self.notes.iter().any(|n| n.contains(text)) {
            let Ok(line) = self.err.recv_timeout(WAIT) else {
                panic!("no note {text:?} on stderr: {:?}", self.notes);
            };
            self.notes.push(line);
        }
    }

    /// On Linux, waits until the binary has read the file at the path to
    /// its current end (its offset in /proc/PID/fdinfo): a line without a
    /// newline prints nothing to wait for.
    #[cfg(target_os = "linux")]
    fn wait_read_to_end(&self) {
        wait_read_to_end(&self.child, &self.path);
    }

    /// Ctrl-C; the whole output, stderr lines, and the input object.
    fn finish(mut self) -> (Vec<Value>, Vec<String>, Value) {
        interrupt(&self.child);
        assert_eq!(exit_within_wait(&mut self.child, "ctrl-c"), Some(130));
        self.objects
            .extend(self.out.iter().map(|l| serde_json::from_str(&l).unwrap()));
        self.notes.extend(self.err.iter());
        let input = self.objects.last().cloned().unwrap();
        assert_eq!(input["type"], "input");
        (self.objects, self.notes, input)
    }
}

/// On Linux, waits until `child` has read the file at `path` to its current
/// end (its offset in /proc/PID/fdinfo).
#[cfg(target_os = "linux")]
fn wait_read_to_end(child: &Child, path: &Path) {
    let want = fs::metadata(path).unwrap().len();
    let target = fs::canonicalize(path).unwrap();
    let pid = child.id();
    let deadline = std::time::Instant::now() + WAIT;
    loop {
        for fd in fs::read_dir(format!("/proc/{pid}/fd")).unwrap().flatten() {
            if fs::read_link(fd.path()).ok().as_deref() != Some(target.as_path()) {
                continue;
            }
            let info = format!("/proc/{pid}/fdinfo/{}", fd.file_name().to_string_lossy());
            let pos = fs::read_to_string(info).unwrap_or_default();
            let pos = pos
                .lines()
                .find_map(|l| l.strip_prefix("pos:"))
                .and_then(|p| p.trim().parse::<u64>().ok());
            if pos == Some(want) {
                return;
            }
        }
        assert!(
            std::time::Instant::now() < deadline,
            "the file was never read to byte {want}"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// Every EMCY in `want`, once each, in that order, and nothing else.
fn assert_exactly(objects: &[Value], want: std::ops::RangeInclusive<u32>) {
    let got: Vec<&str> = objects
        .iter()
        .filter(|o| o["type"] == "emcy")
        .map(|o| o["data"].as_str().unwrap())
        .collect();
    let want: Vec<String> = want.map(data).collect();
    assert_eq!(got, want);
    let node = objects.iter().find(|o| o["type"] == "node").unwrap();
    assert_eq!(node["emcy_count"].as_u64(), Some(want.len() as u64));
}

fn append(path: &Path, text: &str) {
    let mut f = OpenOptions::new().append(true).open(path).unwrap();
    f.write_all(text.as_bytes()).unwrap();
}

#[test]
fn a_log_rotated_by_rename_and_recreate_is_followed_to_the_new_file() {
    // Before, reading stayed on the renamed file: every new line was lost.
    let mut run = Followed::start(&emcys(1..=3));
    run.wait_for(3);
    let old = run.dir().join("can.log.1");
    fs::rename(&run.path, &old).unwrap();
    // The writer writes on into its open file until it reopens the path.
    append(&old, &emcys(4..=5));
    fs::write(&run.path, emcys(6..=8)).unwrap();
    run.wait_for(8);
    append(&run.path, &emcy(9));
    run.wait_for(9);
    let (objects, notes, input) = run.finish();
    assert_exactly(&objects, 1..=9);
    assert_eq!(input["malformed"], 0);
    assert!(
        notes.iter().any(|n| n.ends_with(
            "can.log: a new file at this path (rotated or recreated); reading it from its start"
        )),
        "{notes:?}"
    );
}

#[test]
fn a_deleted_log_is_waited_for_and_read_when_it_comes_back() {
    // Before, the deleted file was followed: the new one was never read.
    let mut run = Followed::start(&emcys(1..=2));
    run.wait_for(2);
    fs::remove_file(&run.path).unwrap();
    run.wait_note("gone (removed or renamed); waiting for a file at this path");
    assert!(run.child.try_wait().unwrap().is_none(), "still waiting");
    fs::write(&run.path, emcys(3..=4)).unwrap();
    run.wait_for(4);
    let (objects, _, input) = run.finish();
    assert_exactly(&objects, 1..=4);
    assert_eq!(input["malformed"], 0);
}

#[test]
fn a_log_truncated_and_rewritten_larger_is_read_again_from_its_start() {
    // Before, only a file smaller than what was read counted as truncated:
    // rewritten larger between two looks, its first part was skipped.
    let mut run = Followed::start(&emcys(1..=3));
    run.wait_for(3);
    fs::write(&run.path, emcys(4..=9)).unwrap();
    run.wait_for(9);
    let (objects, notes, input) = run.finish();
    assert_exactly(&objects, 1..=9);
    assert_eq!(input["malformed"], 0);
    assert!(
        notes
            .iter()
            .any(|n| n.ends_with("can.log: truncated; reading it from its start")),
        "{notes:?}"
    );
}

#[test]
fn copytruncate_loses_nothing() {
    // logrotate's copytruncate: the log is copied away and truncated, and
    // the writer (appending) goes on at its start, here past the old size.
    let mut run = Followed::start("");
    let mut writer = OpenOptions::new().append(true).open(&run.path).unwrap();
    writer.write_all(emcys(1..=3).as_bytes()).unwrap();
    run.wait_for(3);
    fs::copy(&run.path, run.dir().join("can.log.1")).unwrap();
    OpenOptions::new()
        .write(true)
        .open(&run.path)
        .unwrap()
        .set_len(0)
        .unwrap();
    writer.write_all(emcys(4..=9).as_bytes()).unwrap();
    run.wait_for(9);
    let (objects, _, input) = run.finish();
    assert_exactly(&objects, 1..=9);
    assert_eq!(input["malformed"], 0);
}

#[cfg(target_os = "linux")]
#[test]
fn a_half_line_left_by_a_truncation_is_a_line_of_its_own() {
    // Before, the half line was glued to the first line written after the
    // truncation: that EMCY was lost and a false malformed line reported.
    let mut run = Followed::start(&emcys(1..=2));
    run.wait_for(2);
    // One byte of data: read as it stands, an EMCY too short to decode.
    append(&run.path, "(1700000099.000000) can0 085#10");
    run.wait_read_to_end();
    OpenOptions::new()
        .write(true)
        .open(&run.path)
        .unwrap()
        .set_len(0)
        .unwrap();
    append(&run.path, &emcys(3..=4));
    run.wait_for(4);
    let (objects, notes, input) = run.finish();
    assert_exactly(&objects, 1..=4);
    assert_eq!(
        (input["lines"].as_u64(), input["malformed"].as_u64()),
        (Some(5), Some(0))
    );
    assert_eq!(input["emcy_invalid"], 1, "the half line, on its own");
    assert!(
        notes.iter().any(|n| n.ends_with(
            "truncated; reading it from its start; its last line before that (31 bytes, no newline) is read as a line of its own"
        )),
        "{notes:?}"
    );
    assert!(notes.iter().any(|n| n.contains(":3: ")), "{notes:?}");
}

#[cfg(target_os = "linux")]
#[test]
fn ctrl_c_while_a_followed_line_is_unfinished_does_not_decode_it() {
    // Before, the unfinished line was decoded as the last line of the
    // input: here an EMCY too short to decode.
    let mut run = Followed::start(&emcys(1..=2));
    run.wait_for(2);
    append(&run.path, "(1700000099.000000) can0 085#10");
    run.wait_read_to_end();
    let (objects, notes, input) = run.finish();
    assert_exactly(&objects, 1..=2);
    assert_eq!(
        (
            input["lines"].as_u64(),
            input["malformed"].as_u64(),
            input["emcy_invalid"].as_u64()
        ),
        (Some(2), Some(0), Some(0))
    );
    assert!(
        notes.iter().any(|n| n.ends_with(
            "can.log: stopped inside a line: its 31 bytes read so far (no newline yet) are not read"
        )),
        "{notes:?}"
    );
}

/// `--follow` on a binary capture already complete, then Ctrl-C: the
/// report is the one of reading the file to its end. Before, the cancel's
/// error threw away what the reader held: a BLF's last log container (it
/// waited for the bytes after the container's padding), and everything of
/// an MF4 whose data comes before its metadata (CANedge, asammdf and
/// python-can write them so): 0 frames of 22.
#[cfg(target_os = "linux")]
#[test]
fn ctrl_c_on_a_followed_binary_capture_reports_all_of_it() {
    for fixture in [
        "s300.blf",
        "s300.plain.blf",
        "edge.blf",
        "canedge.mf4",
        "sorted-sd.mf4",
        "s300.dz.mf4",
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(fixture);
        fs::copy(Path::new("fixtures").join(fixture), &path).unwrap();
        let whole = crate::support::emcy_decode()
            .args(["--format", "ndjson", path.to_str().unwrap()])
            .output()
            .unwrap();
        let mut child = spawn(&["--follow", "--format", "ndjson", path.to_str().unwrap()]);
        let out = lines_of(child.stdout.take().unwrap());
        wait_read_to_end(&child, &path);
        interrupt(&child);
        assert_eq!(
            exit_within_wait(&mut child, "ctrl-c"),
            Some(130),
            "{fixture}"
        );
        let followed: Vec<String> = out.iter().collect();
        let want: Vec<&str> = std::str::from_utf8(&whole.stdout)
            .unwrap()
            .lines()
            .collect();
        assert!(
            want.iter().any(|l| l.contains("\"type\":\"emcy\"")),
            "{fixture}"
        );
        assert_eq!(followed, want, "{fixture}");
    }
}
