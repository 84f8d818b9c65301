//! At the machine and in the shell: live streams, Ctrl-C, --follow, several
//! files side by side, directories, completions and the man page.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

use crate::support::{binary, emcy_decode};
use serde_json::Value;

/// Patience for one event to come through: generous for a loaded CI
/// machine, but far below "waited for the end of input".
const WAIT: Duration = Duration::from_secs(20);

fn spawn(args: &[&str]) -> Child {
    binary()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawns")
}

/// Lines of the child's stdout as they arrive.
fn lines_of(stdout: ChildStdout) -> Receiver<String> {
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
fn interrupt(child: &Child) {
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
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
    let expected: Vec<String> = files
        .iter()
        .filter(|f| !f.ends_with("missing.log"))
        .cloned()
        .collect();
    assert_eq!(inputs, expected);
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
