//! Every input given is read or named: a file that cannot be opened and a
//! part of a `-r` directory that cannot be listed get an `error:` line, an
//! input object with their error in the JSON, and exit 2, while every other
//! input is still read and reported.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::support::emcy_decode;

fn emcy_line(t: u32) -> String {
    format!("({t}.000000) can0 081#1043090000000000\n")
}

/// Runs with ndjson: (exit code, input objects, EMCY event count, stderr).
fn run(args: &[&str]) -> (i32, Vec<Value>, usize, String) {
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .args(args)
        .output()
        .unwrap();
    let objects: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    let inputs = objects
        .iter()
        .filter(|o| o["type"] == "input")
        .cloned()
        .collect();
    let events = objects.iter().filter(|o| o["type"] == "emcy").count();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code().expect("exited"), inputs, events, stderr)
}

#[test]
fn a_file_that_cannot_be_opened_is_an_input_object_with_its_error() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.log");
    std::fs::write(&good, emcy_line(1)).unwrap();
    let missing = dir.path().join("missing.log");
    let (code, inputs, events, stderr) = run(&[missing.to_str().unwrap(), good.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert_eq!(events, 1, "the other file is read");
    assert_eq!(inputs.len(), 2, "every argument has an input object");
    assert_eq!(inputs[0]["file"], missing.to_str().unwrap());
    assert_eq!(inputs[0]["error"], "No such file or directory");
    assert_eq!(inputs[0]["lines"], 0);
    assert_eq!(inputs[0]["format"], Value::Null);
    assert_eq!(inputs[1]["error"], Value::Null);
    assert!(
        stderr.contains(&format!(
            "error: {}: No such file or directory",
            missing.display()
        )),
        "{stderr}"
    );
}

/// A directory tree deeper than PATH_MAX (4096 bytes): made with relative
/// paths from inside it, as nothing else can, and unreadable to anyone,
/// root included.
fn too_deep(root: &Path) {
    let part = "d".repeat(250);
    let script = format!(
        "cd '{}' && mkdir deep && cd deep && for i in $(seq 20); do mkdir {part} && cd -P {part} || exit 1; done && echo x > lost.log",
        root.display()
    );
    let status = Command::new("sh").args(["-c", &script]).status().unwrap();
    assert!(status.success(), "made the deep tree");
}

#[test]
fn a_recursive_directory_part_that_cannot_be_listed_is_reported_and_the_rest_read() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.log"), emcy_line(1)).unwrap();
    too_deep(dir.path());
    std::fs::write(dir.path().join("z.log"), emcy_line(2)).unwrap();
    let other = tempfile::tempdir().unwrap();
    std::fs::write(other.path().join("b.log"), emcy_line(3)).unwrap();
    let (code, inputs, events, stderr) = run(&[
        "-r",
        dir.path().to_str().unwrap(),
        other.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert_eq!(
        events, 3,
        "a.log, z.log and the other directory are read: {stderr}"
    );
    let failed: Vec<&Value> = inputs.iter().filter(|i| i["error"].is_string()).collect();
    assert_eq!(failed.len(), 1, "{inputs:?}");
    assert_eq!(failed[0]["error"], "File name too long");
    let name = failed[0]["file"].as_str().unwrap();
    assert!(name.starts_with(dir.path().to_str().unwrap()), "{name}");
    assert!(
        stderr.contains(&format!("error: {name}: File name too long")),
        "{stderr}"
    );
    let files: Vec<&str> = inputs.iter().map(|i| i["file"].as_str().unwrap()).collect();
    assert!(
        files[0].ends_with("a.log") && files[2].ends_with("z.log"),
        "{files:?}"
    );
}

/// Without root, a directory without read permission cannot be listed.
/// Root reads it anyway, so there only the tree above is checked.
#[cfg(unix)]
#[test]
fn an_unreadable_subdirectory_does_not_stop_its_siblings() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.log"), emcy_line(1)).unwrap();
    let locked = dir.path().join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::write(locked.join("x.log"), emcy_line(2)).unwrap();
    std::fs::write(dir.path().join("z.log"), emcy_line(3)).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o000)).unwrap();
    let can_read_anyway = std::fs::read_dir(&locked).is_ok();
    let (code, inputs, events, stderr) = run(&["-r", dir.path().to_str().unwrap()]);
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
    if can_read_anyway {
        eprintln!("note: running as root: the directory is readable, only the rest is checked");
        assert_eq!((code, events), (0, 3), "{stderr}");
        return;
    }
    assert_eq!(code, 2, "{stderr}");
    assert_eq!(events, 2, "a.log and z.log are read");
    assert_eq!(inputs.len(), 3);
    assert_eq!(inputs[1]["error"], "Permission denied");
}

#[test]
fn strict_says_why_it_exits_2() {
    emcy_decode()
        .args(["--strict", "fixtures/edge.log"])
        .assert()
        .code(2)
        .stderr(predicates::str::is_match(
            r"(?m)^error: --strict: \d+ malformed lines? and \d+ EMCY frames? too short to decode$",
        ).unwrap());
}
