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

/// The input objects' file names, relative to `dir`.
fn names(inputs: &[Value], dir: &Path) -> Vec<String> {
    inputs
        .iter()
        .map(|i| {
            let file = Path::new(i["file"].as_str().unwrap());
            file.strip_prefix(dir).unwrap().display().to_string()
        })
        .collect()
}

#[test]
fn files_under_r_that_are_no_trace_are_skipped_with_one_note() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.log"), emcy_line(1)).unwrap();
    // Traces by content whatever their names; the rest whatever theirs.
    std::fs::write(d.join("bench.py"), emcy_line(2)).unwrap();
    std::fs::write(d.join("make.py"), "#!/usr/bin/env python3\nimport struct\n").unwrap();
    std::fs::write(
        d.join("notes.log"),
        "Rig 3, second shift: nothing to report\n",
    )
    .unwrap();
    std::fs::write(d.join("empty.log"), "").unwrap();
    std::fs::create_dir(d.join("profiles")).unwrap();
    std::fs::write(d.join("profiles/acme.toml"), "name = \"acme\"\n").unwrap();
    let (code, inputs, events, stderr) = run(&["-r", d.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(events, 2);
    assert_eq!(names(&inputs, d), ["a.log", "bench.py"]);
    let notes: Vec<&str> = stderr.lines().filter(|l| l.contains("skipped")).collect();
    assert_eq!(notes.len(), 1, "{stderr}");
    let dir_name = d.display().to_string();
    assert!(
        notes[0].starts_with(&format!("{dir_name}: skipped 4 files that are no trace")),
        "{stderr}"
    );
    // A few names, not all: the count is what matters.
    assert!(
        notes[0].contains("empty.log") && notes[0].ends_with(", ..."),
        "{stderr}"
    );
    assert!(!notes[0].contains("acme.toml"), "{stderr}");
    // Named on its own, a file is read (and its trouble shown), never skipped.
    let notes_log = d.join("notes.log");
    let (code, _, _, stderr) = run(&[notes_log.to_str().unwrap()]);
    assert_eq!(code, 2, "{stderr}");
}

#[test]
fn glob_selects_files_under_r_and_a_bang_excludes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("rig")).unwrap();
    for (name, t) in [
        ("a.log", 1),
        ("b.asc.log", 2),
        ("rig/c.log", 3),
        ("rig/d.txt", 4),
    ] {
        std::fs::write(d.join(name), emcy_line(t)).unwrap();
    }
    let dir_arg = d.to_str().unwrap();
    let read = |globs: &[&str]| {
        let mut args = vec!["-r", dir_arg];
        for g in globs {
            args.extend(["--glob", g]);
        }
        let (code, inputs, _, stderr) = run(&args);
        assert_eq!(code, 0, "{globs:?}: {stderr}");
        names(&inputs, d)
    };
    assert_eq!(read(&["*.log"]), ["a.log", "b.asc.log", "rig/c.log"]);
    assert_eq!(read(&["rig/*"]), ["rig/c.log", "rig/d.txt"]);
    assert_eq!(read(&["*.txt", "a.*"]), ["a.log", "rig/d.txt"]);
    assert_eq!(read(&["*.log", "!rig/**"]), ["a.log", "b.asc.log"]);
    assert_eq!(read(&["!*.asc.log"]), ["a.log", "rig/c.log", "rig/d.txt"]);
    // A pattern that is no glob, or a glob without -r: usage errors.
    emcy_decode()
        .args(["-r", dir_arg, "--glob", "["])
        .assert()
        .code(2);
    emcy_decode()
        .args(["--glob", "*.log", dir_arg])
        .assert()
        .code(2);
}

/// A `-r` directory that yields nothing to read (a `--glob` with a typo, an
/// empty directory, only files that are no trace) must not pass a CI step
/// by reading nothing: an `error:` line that says why, an input object with
/// that error, exit 2; other inputs are still read. `baseline` and `check`
/// write and compare nothing.
#[test]
fn a_directory_under_r_that_yields_no_trace_is_an_error_that_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for name in ["rig/a.log", "rig/b.log", "empty/.keep", "scripts/make.py"] {
        std::fs::create_dir_all(d.join(name).parent().unwrap()).unwrap();
    }
    std::fs::write(d.join("rig/a.log"), emcy_line(1)).unwrap();
    std::fs::write(d.join("rig/b.log"), emcy_line(2)).unwrap();
    std::fs::write(d.join("scripts/make.py"), "import struct\n").unwrap();
    std::fs::remove_dir(d.join("empty/.keep")).ok();
    let rig = d.join("rig");
    let rig = rig.to_str().unwrap();
    let (code, inputs, events, stderr) = run(&["-r", "--glob", "*.lgo", "--fail-on", "any", rig]);
    assert_eq!((code, events), (2, 0), "{stderr}");
    let why = "no trace under it (2 files not selected by --glob '*.lgo')";
    assert_eq!(stderr, format!("error: {rig}: {why}\n"));
    assert_eq!(inputs.len(), 1);
    assert_eq!(inputs[0]["file"], rig);
    assert_eq!(inputs[0]["error"], why);

    for (sub, why) in [
        ("empty", "no trace under it (no file in it)"),
        ("scripts", "no trace under it (1 file with no known format)"),
    ] {
        let path = d.join(sub);
        let path = path.to_str().unwrap();
        let (code, inputs, events, stderr) = run(&["-r", path, rig]);
        assert_eq!(
            (code, events),
            (2, 2),
            "the other directory is read: {stderr}"
        );
        assert!(
            stderr.contains(&format!("error: {path}: {why}\n")),
            "{stderr}"
        );
        assert_eq!(inputs[0]["error"], why);
    }

    // A glob that selects something is fine.
    let (code, _, events, stderr) = run(&["-r", "--glob", "*.log", rig]);
    assert_eq!((code, events), (0, 2), "{stderr}");

    let out = emcy_decode()
        .args(["baseline", "-r", "--glob", "*.lgo", rig])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        format!(
            "error: {rig}: no trace under it (2 files not selected by --glob '*.lgo'); no \
             baseline written\n"
        )
    );
}

/// Symbolic links under `-r` are not followed unless `-L` says so, as in
/// ripgrep and find, but never skipped silently: one note per directory
/// names them. With `-L` a link to a file outside is read, a loop back up
/// is named and not followed again, and a file two paths reach is read once.
#[cfg(unix)]
#[test]
fn symbolic_links_under_r_are_named_without_l_and_followed_with_it() {
    use std::os::unix::fs::symlink;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("run.log"), emcy_line(1)).unwrap();
    let traces = d.join("traces");
    std::fs::create_dir_all(traces.join("rig")).unwrap();
    std::fs::write(traces.join("rig/a.log"), emcy_line(2)).unwrap();
    symlink("../run.log", traces.join("latest.log")).unwrap();
    symlink("rig/a.log", traces.join("z-again.log")).unwrap();
    symlink("..", traces.join("rig/up")).unwrap();
    let t = traces.to_str().unwrap();

    let (code, inputs, events, stderr) = run(&["-r", t]);
    assert_eq!((code, events), (0, 1), "{stderr}");
    assert_eq!(names(&inputs, &traces), ["rig/a.log"]);
    assert_eq!(
        stderr,
        format!(
            "{t}: skipped 3 symbolic links (-L follows them): {t}/latest.log, {t}/rig/up, \
             {t}/z-again.log\n"
        )
    );

    for flag in ["-L", "--follow-links"] {
        let (code, inputs, events, stderr) = run(&["-r", flag, t]);
        assert_eq!((code, events), (0, 2), "{stderr}");
        assert_eq!(names(&inputs, &traces), ["latest.log", "rig/a.log"]);
        assert_eq!(
            stderr,
            format!(
                "{t}: did not follow 1 symbolic link that points back to a directory above \
                 it, a loop (the files there were read once): {t}/rig/up\n\
                 {t}: skipped 1 file that links reach again (read once, under its first \
                 path): {t}/z-again.log\n"
            )
        );
    }

    // baseline and check read the same traces.
    let out = emcy_decode()
        .current_dir(d)
        .args(["baseline", "-r", "-L", "traces", "-o", "b.json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let baseline: Value =
        serde_json::from_slice(&std::fs::read(d.join("b.json")).unwrap()).expect("a baseline");
    let keys: Vec<&String> = baseline["traces"].as_object().unwrap().keys().collect();
    assert_eq!(keys, ["traces/latest.log", "traces/rig/a.log"]);
    emcy_decode()
        .current_dir(d)
        .args(["check", "-b", "b.json", "-r", "-L", "traces"])
        .assert()
        .code(0);
    // Without -L the link is missing from the traces: a regression.
    emcy_decode()
        .current_dir(d)
        .args(["check", "-b", "b.json", "-r", "traces"])
        .assert()
        .code(1);
    // -L means nothing without -r.
    emcy_decode().args(["-L", t]).assert().code(2);
}
