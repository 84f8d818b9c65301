//! At the machine and in the shell: live streams, Ctrl-C and the other
//! stopping signals, --follow (rotation: `follow.rs`), several files side by
//! side, directories, completions and the man page.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel, sync_channel};
use std::time::{Duration, Instant};

use crate::support::{binary, emcy_decode};
use serde_json::Value;

/// Patience for one event to come through: generous for a loaded CI
/// machine, but far below "waited for the end of input".
pub(crate) const WAIT: Duration = Duration::from_secs(20);

pub(crate) fn spawn(args: &[&str]) -> Child {
    binary()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawns")
}

/// [`spawn`], then one EMCY line written to its stdin (kept open): the
/// child, its stdin, its stdout and stderr lines.
fn spawn_with_one_emcy(
    args: &[&str],
) -> (
    Child,
    std::process::ChildStdin,
    Receiver<String>,
    Receiver<String>,
) {
    let mut child = spawn(args);
    let mut stdin = child.stdin.take().unwrap();
    let out = lines_of(child.stdout.take().unwrap());
    let err = lines_of(child.stderr.take().unwrap());
    stdin
        .write_all(emcy_line(1, "1043090000000000").as_bytes())
        .unwrap();
    stdin.flush().unwrap();
    (child, stdin, out, err)
}

/// Lines of the child's stdout (or stderr) as they arrive.
pub(crate) fn lines_of(stdout: impl std::io::Read + Send + 'static) -> Receiver<String> {
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { return };
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    rx
}

fn next_json(rx: &Receiver<String>) -> Value {
    let line = rx
        .recv_timeout(WAIT)
        .expect("a line arrives while the input is still open");
    serde_json::from_str(&line).expect("ndjson")
}

fn emcy_line(t: u32, data: &str) -> String {
    format!("({}.000000) can0 085#{data}\n", 1_700_000_000 + t)
}

#[cfg(unix)]
pub(crate) fn interrupt(child: &Child) {
    signal(child, "INT");
}

/// Sends the signal `name` (`INT`, `TERM`, `HUP`) to the child.
#[cfg(unix)]
pub(crate) fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
}

/// The child's exit status once it ends; killed and a failure when it has
/// not ended after [`WAIT`] (the test would hang otherwise).
pub(crate) fn exit_within_wait(child: &mut Child, what: &str) -> Option<i32> {
    let deadline = Instant::now() + WAIT;
    loop {
        if let Some(status) = child.try_wait().expect("waits") {
            return status.code();
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what}: still running after {WAIT:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn each_event_arrives_while_the_writer_is_still_writing() {
    let mut child = spawn(&["--format", "ndjson", "-"]);
    let mut stdin = child.stdin.take().unwrap();
    let rx = lines_of(child.stdout.take().unwrap());
    stdin
        .write_all(emcy_line(1, "1043090000000000").as_bytes())
        .unwrap();
    stdin.flush().unwrap();
    let first = next_json(&rx);
    assert_eq!(
        (first["type"].as_str(), first["code"].as_str()),
        (Some("emcy"), Some("0x4310"))
    );
    stdin
        .write_all(emcy_line(2, "0000000000000000").as_bytes())
        .unwrap();
    stdin.flush().unwrap();
    let second = next_json(&rx);
    assert_eq!(second["transition"], 4);
    drop(stdin);
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(0));
    let rest: Vec<Value> = rx
        .iter()
        .map(|l| serde_json::from_str(&l).unwrap())
        .collect();
    assert_eq!(rest.iter().filter(|o| o["type"] == "node").count(), 1);
    assert_eq!(rest.iter().filter(|o| o["type"] == "input").count(), 1);
}

#[test]
fn the_live_table_prints_each_event_as_it_comes() {
    let mut child = spawn(&["-"]);
    let mut stdin = child.stdin.take().unwrap();
    let rx = lines_of(child.stdout.take().unwrap());
    stdin
        .write_all(emcy_line(1, "1043090000000000").as_bytes())
        .unwrap();
    stdin.flush().unwrap();
    let header = rx.recv_timeout(WAIT).unwrap();
    assert!(header.starts_with("== <stdin>"), "{header}");
    let columns = rx.recv_timeout(WAIT).unwrap();
    assert!(columns.starts_with("TIME"), "{columns}");
    let event = rx.recv_timeout(WAIT).unwrap();
    assert!(event.contains("0x4310"), "{event}");
    assert!(event.starts_with("2023-11-14T22:13:21.000000Z"), "{event}");
    drop(stdin);
    assert_eq!(child.wait().unwrap().code(), Some(0));
}

#[cfg(unix)]
#[test]
fn ctrl_c_prints_the_summary_and_exits_130() {
    let mut child = spawn(&["--format", "ndjson", "-"]);
    let mut stdin = child.stdin.take().unwrap();
    let rx = lines_of(child.stdout.take().unwrap());
    stdin
        .write_all(emcy_line(1, "1043090000000000").as_bytes())
        .unwrap();
    stdin.flush().unwrap();
    assert_eq!(next_json(&rx)["type"], "emcy");
    // The writer stays open (a quiet bus): only Ctrl-C ends the run.
    interrupt(&child);
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    let rest: Vec<Value> = rx
        .iter()
        .map(|l| serde_json::from_str(&l).unwrap())
        .collect();
    let node = rest
        .iter()
        .find(|o| o["type"] == "node")
        .expect("node summary");
    assert_eq!(node["active"][0], "0x4310");
    drop(stdin);
}

#[cfg(unix)]
#[test]
fn sigterm_and_sighup_print_the_report_like_ctrl_c_then_exit_143_and_129() {
    // Killed by the signal before: no status code, no report.
    for (name, code) in [("TERM", 143), ("HUP", 129)] {
        let (mut child, stdin, rx, err) = spawn_with_one_emcy(&["--format", "ndjson", "-"]);
        assert_eq!(next_json(&rx)["type"], "emcy");
        signal(&child, name);
        assert_eq!(exit_within_wait(&mut child, name), Some(code), "SIG{name}");
        let rest: Vec<Value> = rx
            .iter()
            .map(|l| serde_json::from_str(&l).unwrap())
            .collect();
        let node = rest
            .iter()
            .find(|o| o["type"] == "node")
            .unwrap_or_else(|| panic!("SIG{name}: node summary in {rest:?}"));
        assert_eq!(node["active"][0], "0x4310");
        assert_eq!(rest.last().unwrap()["type"], "input", "SIG{name}");
        let stderr: Vec<String> = err.iter().collect();
        assert_eq!(
            stderr,
            [format!(
                "interrupted: the report covers what was read before SIG{name}"
            )]
        );
        drop(stdin);
    }
}

/// `--format ndjson -` fed `lines` by a thread; stdout comes through a
/// channel that holds one line, so the child blocks on a full pipe as soon
/// as the test stops receiving.
#[cfg(unix)]
fn spawn_fed(lines: String) -> (Child, Receiver<String>) {
    let mut child = spawn(&["--format", "ndjson", "-"]);
    let mut stdin = child.stdin.take().unwrap();
    let stdout = child.stdout.take().unwrap();
    // The writer stays open: only signals end this run.
    std::thread::spawn(move || {
        let _ = stdin.write_all(lines.as_bytes());
        let _ = stdin.flush();
        std::thread::park();
        drop(stdin);
    });
    let (tx, rx) = sync_channel(1);
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { return };
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    (child, rx)
}

#[cfg(unix)]
#[test]
fn a_second_signal_while_the_report_is_written_ends_the_process_at_once() {
    // 2000 nodes each with an active error: a report of some MB after the
    // first signal, far more than the pipe holds.
    let mut lines = String::new();
    for channel in 0..20 {
        for node in 1..=100u32 {
            lines.push_str(&format!(
                "(1700000001.000000) can{channel} {:03X}#1043090000000000\n",
                0x80 + node
            ));
        }
    }
    for second in ["INT", "TERM"] {
        let (mut child, rx) = spawn_fed(lines.clone());
        for _ in 0..2000 {
            let line = rx.recv_timeout(WAIT).expect("every event arrives");
            assert!(line.starts_with(r#"{"type":"emcy""#), "{line}");
        }
        interrupt(&child);
        // The report has begun: the first signal was taken.
        // Incidents close at the end of the input, before the report.
        let first = loop {
            let line = rx.recv_timeout(WAIT).expect("the report begins");
            if !line.starts_with(r#"{"type":"incident""#) {
                break line;
            }
        };
        assert!(first.starts_with(r#"{"type":"node""#), "{first}");
        // Its output is no longer read: it fills the pipe and waits there.
        // Before, the second signal was ignored like the first and the
        // process waited on the pipe forever.
        signal(&child, second);
        let code = if second == "INT" { 130 } else { 143 };
        assert_eq!(
            exit_within_wait(&mut child, "after the second signal"),
            Some(code)
        );
        let mut stderr = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
        assert_eq!(stderr, "", "no note: the report was not finished");
    }
}

/// A trace of `n` EMCY lines of 47 bytes each (an odd length, so reads of
/// powers of two end inside lines), each with its own data.
fn numbered_emcy(i: u64) -> String {
    format!(
        "({}.{:06}) vcan0 085#{}\n",
        1_700_000_000 + i / 1000,
        i % 1000 * 1000,
        numbered_data(i)
    )
}

fn numbered_data(i: u64) -> String {
    format!("104309{i:010X}")
}

#[cfg(unix)]
#[test]
fn ctrl_c_in_the_middle_of_a_file_decodes_no_cut_line() {
    // Before, the line cut by the interrupted read was decoded as the
    // last line of the input: an EMCY of a few bytes with a false
    // short_frame warning, or a false malformed line.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.log");
    let n = 450_000u64; // 21 MB: read in parallel by default
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        for i in 0..n {
            w.write_all(numbered_emcy(i).as_bytes()).unwrap();
        }
        w.flush().unwrap();
    }
    for threads in ["1", "2"] {
        let mut child = binary()
            .args(["--format", "ndjson", "-j", threads])
            .arg(&path)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stderr = lines_of(child.stderr.take().unwrap());
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        // The first event is out; then the output is not read, so the run
        // stops on the full pipe with most of the file unread: the signal
        // comes in the middle of reading.
        let mut first = String::new();
        stdout.read_line(&mut first).unwrap();
        assert!(first.starts_with(r#"{"type":"emcy""#), "{first}");
        interrupt(&child);
        let rest: Vec<Value> = stdout
            .lines()
            .map(|l| serde_json::from_str(&l.unwrap()).unwrap())
            .collect();
        assert_eq!(exit_within_wait(&mut child, "ctrl-c"), Some(130));
        let input = rest.last().unwrap();
        assert_eq!(input["type"], "input");
        let read = input["lines"].as_u64().unwrap();
        assert!(
            read < n,
            "-j {threads}: stopped before the end ({read} lines)"
        );
        assert_eq!(
            (input["malformed"].as_u64(), input["emcy_invalid"].as_u64()),
            (Some(0), Some(0)),
            "-j {threads}: {input}"
        );
        assert_eq!(input["emcy"].as_u64(), Some(read), "-j {threads}");
        let events: Vec<Value> = std::iter::once(serde_json::from_str(&first).unwrap())
            .chain(rest.into_iter().filter(|o| o["type"] == "emcy"))
            .collect();
        assert_eq!(events.len() as u64, read, "-j {threads}");
        for (k, e) in events.iter().enumerate() {
            let line = e["line"].as_u64().unwrap();
            assert_eq!(line, k as u64 + 1, "-j {threads}: in order");
            assert_eq!(
                e["data"].as_str(),
                Some(numbered_data(line - 1).as_str()),
                "-j {threads}: line {line} is the file's line"
            );
        }
        let notes: Vec<String> = stderr.iter().collect();
        assert_eq!(
            notes,
            ["interrupted: the report covers what was read before Ctrl-C"]
        );
    }
}

#[cfg(unix)]
#[test]
fn follow_reads_a_growing_file_until_ctrl_c() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grow.log");
    std::fs::write(&path, emcy_line(1, "1043090000000000")).unwrap();
    let mut child = spawn(&["--follow", "--format", "ndjson", path.to_str().unwrap()]);
    let rx = lines_of(child.stdout.take().unwrap());
    assert_eq!(next_json(&rx)["code"], "0x4310");
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(&path)
        .unwrap();
    f.write_all(emcy_line(2, "2032050000000000").as_bytes())
        .unwrap();
    f.flush().unwrap();
    assert_eq!(next_json(&rx)["code"], "0x3220");
    interrupt(&child);
    assert_eq!(child.wait().unwrap().code(), Some(130));
    let rest: Vec<Value> = rx
        .iter()
        .map(|l| serde_json::from_str(&l).unwrap())
        .collect();
    let node = rest
        .iter()
        .find(|o| o["type"] == "node")
        .expect("node summary");
    assert_eq!(node["emcy_count"], 2);
}

#[test]
fn follow_needs_one_file() {
    emcy_decode()
        .args(["--follow", "-"])
        .assert()
        .code(2)
        .stderr(predicates::str::contains("--follow takes exactly one FILE"));
}

// ---- several files ---------------------------------------------------------------

/// Writes `n` small traces with distinct content; names out of sort order.
fn many_traces(dir: &Path, n: u32) -> Vec<String> {
    (0..n)
        .map(|i| {
            let path = dir.join(format!("t{:02}.log", (i * 7) % n));
            let mut text = String::new();
            for k in 0..(20 + i) {
                let data = if k % 3 == 0 {
                    "0000000000000000"
                } else {
                    "1043090000000000"
                };
                text.push_str(&format!(
                    "({}.{:06}) can{} {:03X}#{data}\n",
                    1_700_000_000 + k,
                    i,
                    i % 3,
                    0x80 + 1 + (k + i) % 9
                ));
            }
            if i % 4 == 0 {
                text.push_str("not a frame\n");
            }
            std::fs::write(&path, text).unwrap();
            path.display().to_string()
        })
        .collect()
}

#[test]
fn several_files_side_by_side_give_the_output_of_one_by_one_in_argument_order() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = many_traces(dir.path(), 13);
    files.push(dir.path().join("missing.log").display().to_string());
    files.swap(3, 13);
    for format in ["ndjson", "table", "json"] {
        let run = |j: &str| {
            emcy_decode()
                .args(["--format", format, "-j", j])
                .args(&files)
                .output()
                .unwrap()
        };
        let one = run("1");
        let many = run("4");
        assert_eq!(one.status.code(), Some(2), "a missing file is exit 2");
        assert_eq!(many.status.code(), one.status.code());
        assert_eq!(
            String::from_utf8_lossy(&many.stdout),
            String::from_utf8_lossy(&one.stdout),
            "{format}"
        );
        assert_eq!(
            String::from_utf8_lossy(&many.stderr),
            String::from_utf8_lossy(&one.stderr),
            "{format}"
        );
    }
    let out = emcy_decode()
        .args(["--format", "ndjson", "-j", "4"])
        .args(&files)
        .output()
        .unwrap();
    let inputs: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .filter(|o| o["type"] == "input")
        .map(|o| o["file"].as_str().unwrap().to_string())
        .collect();
    // Every argument, the missing one too, in argument order.
    assert_eq!(inputs, files);
}

#[test]
fn directories_are_read_recursively_in_name_order_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("b")).unwrap();
    std::fs::write(dir.path().join("b/2.log"), emcy_line(2, "1043090000000000")).unwrap();
    std::fs::write(dir.path().join("a.log"), emcy_line(1, "1043090000000000")).unwrap();
    std::fs::write(dir.path().join("c.log"), emcy_line(3, "1043090000000000")).unwrap();
    let d = dir.path().to_str().unwrap();
    let out = emcy_decode()
        .args(["--format", "ndjson", "-r", d])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let files: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .filter(|o| o["type"] == "input")
        .map(|o| {
            let file = o["file"].as_str().unwrap();
            let rel = Path::new(file).strip_prefix(d).unwrap();
            rel.to_str().unwrap().replace('\\', "/")
        })
        .collect();
    assert_eq!(files, ["a.log", "b/2.log", "c.log"]);
    emcy_decode()
        .arg(d)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("is a directory"));
}

// ---- terminal niceties -----------------------------------------------------------

#[test]
fn quiet_prints_no_diagnostics_but_counts_them() {
    let out = emcy_decode()
        .args(["--quiet", "--format", "ndjson", "fixtures/edge.log"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
    let input: Value = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .find(|o| o["type"] == "input")
        .unwrap();
    assert_eq!(input["malformed"], 1);
}

#[test]
fn time_styles_in_the_table() {
    let first_event = |style: &str| {
        let out = emcy_decode()
            .args(["--time", style, "fixtures/s300.log"])
            .output()
            .unwrap();
        let text = String::from_utf8(out.stdout).unwrap();
        text.lines()
            .find(|l| l.contains("0x4310"))
            .map(|l| l.split_whitespace().next().unwrap().to_string())
            .unwrap()
    };
    assert_eq!(first_event("auto"), "2023-11-14T22:13:21.250000Z");
    assert_eq!(first_event("iso"), "2023-11-14T22:13:21.250000Z");
    assert_eq!(first_event("absolute"), "1700000001.250000");
    // From the first event shown, the boot-up at 0.0.
    assert_eq!(first_event("relative"), "1.250000");
}

#[test]
fn completions_for_every_shell_and_a_man_page() {
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let out = emcy_decode().args(["completions", shell]).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{shell}");
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.contains("emcy-decode"), "{shell}");
        assert!(text.contains("fail-on"), "{shell} completes flags");
    }
    let man = emcy_decode().arg("man").output().unwrap();
    assert_eq!(man.status.code(), Some(0));
    let text = String::from_utf8(man.stdout).unwrap();
    assert!(text.contains(".TH emcy-decode 1"), "{text}");
    assert!(text.contains("fail\\-on"), "{text}");
    emcy_decode().args(["completions", "tcsh"]).assert().code(2);
}

/// Waits until the child catches `signo` (Linux: `SigCgt` in its status), so
/// a signal sent next meets the handler, not the default action.
#[cfg(target_os = "linux")]
fn wait_until_caught(child: &Child, signo: u32) {
    let deadline = Instant::now() + WAIT;
    let status = format!("/proc/{}/status", child.id());
    loop {
        let caught = std::fs::read_to_string(&status)
            .ok()
            .and_then(|s| {
                let mask = s.lines().find_map(|l| l.strip_prefix("SigCgt:"))?;
                u64::from_str_radix(mask.trim(), 16).ok()
            })
            .is_some_and(|mask| mask & (1 << (signo - 1)) != 0);
        if caught {
            return;
        }
        assert!(Instant::now() < deadline, "signal {signo} never caught");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A CI timeout once killed `baseline` and `check` with no word, and
/// could leave a temporary file beside the baseline. A signal while the
/// traces are read writes and compares nothing: an `error:` line, the
/// signal's status, the old baseline byte for byte, no file left behind.
#[cfg(target_os = "linux")]
#[test]
fn a_signal_while_baseline_or_check_reads_writes_nothing() {
    const SIGHUP: u32 = 1;
    const SIGTERM: u32 = 15;
    let dir = tempfile::tempdir().unwrap();
    let old = dir.path().join("old.json");
    let made = emcy_decode()
        .args(["baseline", "fixtures/stoeber.log", "-o"])
        .arg(&old)
        .output()
        .unwrap();
    assert_eq!(made.status.code(), Some(0));
    let old_bytes = std::fs::read(&old).unwrap();
    let new = dir.path().join("new.json");
    let (new, old_path) = (new.to_str().unwrap(), old.to_str().unwrap());
    let runs: [(&[&str], &str, u32, i32, &str); 2] = [
        (
            &["baseline", "-o", new, "-"],
            "TERM",
            SIGTERM,
            143,
            "error: stopped by SIGTERM while reading <stdin>; no baseline written",
        ),
        (
            &["check", "--update", "-b", old_path, "-"],
            "HUP",
            SIGHUP,
            129,
            "error: stopped by SIGHUP while reading <stdin>; nothing compared, the baseline \
             left as it was",
        ),
    ];
    for (args, name, signo, code, message) in runs {
        let (mut child, stdin, out, err) = spawn_with_one_emcy(args);
        wait_until_caught(&child, signo);
        signal(&child, name);
        assert_eq!(exit_within_wait(&mut child, name), Some(code), "SIG{name}");
        drop(stdin);
        assert_eq!(
            out.iter().collect::<Vec<_>>(),
            Vec::<String>::new(),
            "SIG{name}"
        );
        assert_eq!(err.iter().collect::<Vec<_>>(), [message.to_string()]);
        let mut left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        left.sort();
        assert_eq!(
            left,
            ["old.json"],
            "SIG{name}: nothing new beside the baseline"
        );
        assert!(
            std::fs::read(&old).unwrap() == old_bytes,
            "SIG{name}: baseline unchanged"
        );
    }
}

/// A FIFO made in a temporary directory.
#[cfg(unix)]
fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(status.success());
}

/// A FIFO given by name is a live stream too, and may be quiet for as long
/// as the bus is: SIGTERM from a service manager ends the wait at once with
/// the report and exit 143, whether a writer holds the FIFO open (events
/// came and were printed as they came) or none ever opened it (opening it
/// waits). `baseline` stops the same way, writing nothing.
#[cfg(target_os = "linux")]
#[test]
fn sigterm_ends_an_idle_fifo_at_once_with_the_report() {
    const SIGTERM: u32 = 15;
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("can0.fifo");
    mkfifo(&fifo);
    let name = fifo.to_str().unwrap();

    // A writer that wrote one EMCY and holds the FIFO open, silent.
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut w = std::fs::OpenOptions::new().write(true).open(fifo).unwrap();
            w.write_all(emcy_line(1, "1043090000000000").as_bytes())
                .unwrap();
            w
        })
    };
    let mut child = spawn(&["--format", "ndjson", name]);
    let out = lines_of(child.stdout.take().unwrap());
    let err = lines_of(child.stderr.take().unwrap());
    assert_eq!(next_json(&out)["type"], "emcy", "printed as it came");
    let held = writer.join().unwrap();
    wait_until_caught(&child, SIGTERM);
    signal(&child, "TERM");
    assert_eq!(exit_within_wait(&mut child, "idle FIFO"), Some(143));
    let rest: Vec<Value> = out
        .iter()
        .map(|l| serde_json::from_str(&l).unwrap())
        .collect();
    let node = rest.iter().find(|o| o["type"] == "node").expect("a node");
    assert_eq!(node["active"][0], "0x4310");
    assert_eq!(rest.last().unwrap()["lines"], 1);
    assert_eq!(
        err.iter().collect::<Vec<_>>(),
        ["interrupted: the report covers what was read before SIGTERM"]
    );
    drop(held);

    // No writer ever: the open itself waits.
    let mut child = spawn(&["--format", "ndjson", name]);
    let out = lines_of(child.stdout.take().unwrap());
    wait_until_caught(&child, SIGTERM);
    signal(&child, "TERM");
    assert_eq!(exit_within_wait(&mut child, "unopened FIFO"), Some(143));
    let input: Value = serde_json::from_str(&out.iter().last().expect("a report")).unwrap();
    assert_eq!(
        (input["type"].as_str(), input["lines"].as_u64()),
        (Some("input"), Some(0))
    );

    let mut child = spawn(&["baseline", name]);
    let err = lines_of(child.stderr.take().unwrap());
    wait_until_caught(&child, SIGTERM);
    signal(&child, "TERM");
    assert_eq!(exit_within_wait(&mut child, "baseline"), Some(143));
    assert_eq!(
        err.iter().collect::<Vec<_>>(),
        [format!(
            "error: stopped by SIGTERM while reading {name}; no baseline written"
        )]
    );
}
