//! `baseline` and `check`: the CI regression contract. Each test works in its
//! own temporary directory holding `traces/rig.log`; a baseline is made from
//! the reference run (`fixtures/baseline/rig.log`), then the trace is replaced
//! by a variant from `fixtures/baseline/` and checked.

use std::fs;
use std::path::{Path, PathBuf};

use crate::support::golden::first_difference;
use crate::support::{emcy_decode, readme_block};
use assert_cmd::Command;
use predicates::prelude::*;
use serde_json::Value;
use tempfile::TempDir;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/baseline")
        .join(name)
}

/// A temporary directory with `traces/rig.log` = the fixture `name`.
fn workspace(name: &str) -> TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    fs::create_dir(dir.path().join("traces")).expect("mkdir traces");
    put(&dir, name);
    dir
}

/// Replaces `traces/rig.log` with the fixture `name`.
fn put(dir: &TempDir, name: &str) {
    fs::copy(fixture(name), dir.path().join("traces/rig.log")).expect("copy fixture");
}

fn cmd_in(dir: &TempDir) -> Command {
    let mut cmd = emcy_decode();
    cmd.current_dir(dir.path());
    cmd
}

/// `baseline traces/rig.log -o baseline.json` in `dir`.
fn make_baseline(dir: &TempDir) {
    cmd_in(dir)
        .args(["baseline", "traces/rig.log", "-o", "baseline.json"])
        .assert()
        .code(0)
        .stdout("")
        .stderr("");
}

fn check(dir: &TempDir, extra: &[&str]) -> assert_cmd::assert::Assert {
    cmd_in(dir)
        .args(["check", "--baseline", "baseline.json", "traces/rig.log"])
        .args(extra)
        .assert()
}

/// A baseline of the reference run, then the trace replaced by `variant`.
fn checked_against_rig(variant: &str) -> TempDir {
    let dir = workspace("rig.log");
    make_baseline(&dir);
    put(&dir, variant);
    dir
}

// ---- clean match ---------------------------------------------------------------

#[test]
fn an_unchanged_trace_matches_with_exit_0() {
    let dir = checked_against_rig("rig.log");
    check(&dir, &[])
        .code(0)
        .stdout("check: 0 regressions, 0 improvements, 0 changes; 1 of 1 trace matched\n")
        .stderr("");
}

// ---- regressions: exit 1 ---------------------------------------------------------

#[test]
fn a_new_error_code_is_a_regression() {
    let dir = checked_against_rig("new-error.log");
    check(&dir, &[]).code(1).stdout(
        "regression: traces/rig.log can0 node 1: new error 0x2310 (1x): \
         Current · output side · continuous over current\n\
         check: 1 regression, 0 improvements, 0 changes; 0 of 1 trace matched\n",
    );
}

#[test]
fn an_error_that_stays_active_but_was_cleared_is_a_regression() {
    let dir = checked_against_rig("stays-active.log");
    check(&dir, &[])
        .code(1)
        .stdout(predicate::str::contains(
            "regression: traces/rig.log can0 node 1: error 0x4310 still active at end, \
             cleared in the baseline: Temperature · drive · excess temperature drive\n",
        ))
        .stdout(
            predicate::str::contains(
                "change: traces/rig.log can0 node 1: error 0x4310 raised 1x, baseline 2x",
            )
            .not(),
        )
        .stdout(predicate::str::ends_with(
            "check: 1 regression, 0 improvements, 0 changes; 0 of 1 trace matched\n",
        ));
}

#[test]
fn a_new_node_with_errors_is_a_regression() {
    let dir = checked_against_rig("new-node.log");
    check(&dir, &[]).code(1).stdout(predicate::str::starts_with(
        "regression: traces/rig.log can0 node 3: new node with errors \
         0x8130 (1x, still active at end)\n",
    ));
}

#[test]
fn more_malformed_lines_are_a_regression() {
    let dir = checked_against_rig("malformed.log");
    check(&dir, &["--max-diagnostics", "0"]).code(1).stdout(
        "regression: traces/rig.log: malformed lines 2, baseline 0\n\
         check: 1 regression, 0 improvements, 0 changes; 0 of 1 trace matched\n",
    );
}

#[test]
fn a_trace_not_in_the_baseline_and_a_baseline_trace_not_given_are_regressions() {
    let dir = checked_against_rig("rig.log");
    fs::copy(fixture("rig.log"), dir.path().join("traces/other.log")).expect("copy");
    cmd_in(&dir)
        .args(["check", "--baseline", "baseline.json", "traces/other.log"])
        .assert()
        .code(1)
        .stdout(
            "regression: traces/other.log: not in the baseline\n\
             regression: traces/rig.log: in the baseline but not given\n\
             check: 2 regressions, 0 improvements, 0 changes; 0 of 2 traces matched\n",
        );
}

// ---- reported, exit 0 ---------------------------------------------------------------

#[test]
fn errors_that_no_longer_appear_or_no_longer_stay_active_are_improvements() {
    let dir = checked_against_rig("improved.log");
    check(&dir, &[]).code(0).stdout(
        "improvement: traces/rig.log can0 node 1: error 0x4310 no longer appears \
         (baseline 2x): Temperature · drive · excess temperature drive\n\
         improvement: traces/rig.log can0 node 2: error 0x3120 cleared by the end, \
         active in the baseline: Voltage · mains · mains under-voltage\n\
         check: 0 regressions, 2 improvements, 0 changes; 1 of 1 trace matched\n",
    );
}

#[test]
fn a_node_that_disappeared_is_reported() {
    let dir = checked_against_rig("node-gone.log");
    check(&dir, &[]).code(0).stdout(
        "change: traces/rig.log can0 node 2: node no longer appears \
         (baseline: errors 0x3120 (1x, still active at end))\n\
         check: 0 regressions, 0 improvements, 1 change; 1 of 1 trace matched\n",
    );
}

#[test]
fn a_known_error_raised_more_often_is_a_change() {
    let dir = checked_against_rig("more-often.log");
    check(&dir, &[]).code(0).stdout(
        "change: traces/rig.log can0 node 1: error 0x4310 raised 3x, baseline 2x: \
         Temperature · drive · excess temperature drive\n\
         check: 0 regressions, 0 improvements, 1 change; 1 of 1 trace matched\n",
    );
}

// ---- accepting known differences -----------------------------------------------------

#[test]
fn allow_code_accepts_a_new_error() {
    let dir = checked_against_rig("new-error.log");
    check(&dir, &["--allow", "2310"]).code(0).stdout(
        "allowed: traces/rig.log can0 node 1: new error 0x2310 (1x): \
         Current · output side · continuous over current\n\
         check: 0 regressions (1 allowed), 0 improvements, 0 changes; 1 of 1 trace matched\n",
    );
    // Another code does not.
    check(&dir, &["--allow", "0x4310"]).code(1);
}

#[test]
fn allow_code_accepts_an_error_that_stays_active() {
    let dir = checked_against_rig("stays-active.log");
    check(&dir, &["--allow", "0x4310"]).code(0);
}

#[test]
fn allow_node_accepts_a_new_node_and_its_errors() {
    let dir = checked_against_rig("new-node.log");
    check(&dir, &["--allow-node", "3"])
        .code(0)
        .stdout(predicate::str::starts_with(
            "allowed: traces/rig.log can0 node 3: new node with errors",
        ));
    // Allowing every code of the new node accepts it too.
    check(&dir, &["--allow", "8130"]).code(0);
    check(&dir, &["--allow-node", "1,2"]).code(1);
}

#[test]
fn allow_does_not_accept_malformed_lines() {
    let dir = checked_against_rig("malformed.log");
    check(
        &dir,
        &[
            "--allow-node",
            "1,2",
            "--allow",
            "4310",
            "--max-diagnostics",
            "0",
        ],
    )
    .code(1);
}

// ---- --update ------------------------------------------------------------------------

#[test]
fn update_rewrites_the_baseline_and_the_next_check_passes() {
    let dir = checked_against_rig("new-error.log");
    check(&dir, &["--update"])
        .code(0)
        .stdout(predicate::str::starts_with(
            "regression: traces/rig.log can0 node 1: new error 0x2310",
        ))
        .stderr("check: wrote baseline.json\n");
    check(&dir, &[]).code(0);
    // The rewritten baseline is exactly what `baseline` writes.
    let updated = fs::read(dir.path().join("baseline.json")).expect("read");
    make_baseline(&dir);
    let fresh = fs::read(dir.path().join("baseline.json")).expect("read");
    assert_eq!(updated, fresh);
}

// ---- the baseline file -----------------------------------------------------------------

#[test]
fn the_baseline_is_byte_identical_across_runs_and_holds_no_absolute_path() {
    let a = workspace("new-node.log");
    let b = workspace("new-node.log");
    make_baseline(&a);
    // An absolute path inside the current directory is stored relative to it.
    let abs = b.path().join("traces/rig.log");
    cmd_in(&b)
        .args(["baseline", "-o", "baseline.json"])
        .arg(&abs)
        .assert()
        .code(0);
    let first = fs::read_to_string(a.path().join("baseline.json")).expect("read");
    let second = fs::read_to_string(b.path().join("baseline.json")).expect("read");
    assert_eq!(first, second);
    for dir in [&a, &b] {
        let root = dir.path().to_string_lossy().into_owned();
        assert!(!first.contains(&root), "absolute path in {first}");
    }
    assert!(first.ends_with("}\n") && !first.ends_with("\n\n"));
    // Stdout gives the same bytes.
    cmd_in(&a)
        .args(["baseline", "traces/rig.log"])
        .assert()
        .code(0)
        .stdout(first.clone());
}

#[test]
fn an_absolute_path_outside_the_current_directory_is_stored_as_its_file_name() {
    let dir = workspace("rig.log");
    let elsewhere = tempfile::tempdir().expect("temp dir");
    let out = cmd_in(&dir)
        .args(["baseline"])
        .arg(dir.path().join("traces/rig.log"))
        .current_dir(elsewhere.path())
        .assert()
        .code(0);
    let json: Value = serde_json::from_slice(&out.get_output().stdout).expect("JSON");
    let keys: Vec<&String> = json["traces"].as_object().expect("traces").keys().collect();
    assert_eq!(keys, ["rig.log"]);
}

#[test]
fn the_baseline_records_codes_active_codes_counts_and_input_counts() {
    let out = emcy_decode()
        .args(["baseline", "fixtures/baseline/rig.log"])
        .assert()
        .code(0);
    let json: Value = serde_json::from_slice(&out.get_output().stdout).expect("JSON");
    assert_eq!(json["baseline_version"], 1);
    let trace = &json["traces"]["fixtures/baseline/rig.log"];
    assert_eq!(trace["format"], "candump");
    assert_eq!(trace["counts"]["lines"], 9);
    assert_eq!(trace["counts"]["malformed"], 0);
    let node1 = &trace["nodes"]["can0"]["1"];
    assert_eq!(node1["errors"]["0x4310"]["raised"], 2);
    assert_eq!(node1["errors"]["0x4310"]["active_at_end"], false);
    let node2 = &trace["nodes"]["can0"]["2"];
    assert_eq!(node2["errors"]["0x3120"]["active_at_end"], true);
}

#[test]
fn the_same_trace_twice_is_a_usage_error() {
    emcy_decode()
        .args([
            "baseline",
            "fixtures/baseline/rig.log",
            "./fixtures/baseline/rig.log",
        ])
        .assert()
        .code(2)
        .stdout("")
        .stderr(
            predicate::str::starts_with("error: ").and(predicate::str::contains(
                "would both be recorded as 'fixtures/baseline/rig.log'",
            )),
        );
}

// ---- errors: exit 2 with one `error:` line -----------------------------------------------

fn one_error_line(stderr: &[u8]) -> String {
    let text = String::from_utf8_lossy(stderr).into_owned();
    assert_eq!(text.lines().count(), 1, "one line expected: {text}");
    assert!(text.starts_with("error: "), "{text}");
    text
}

#[test]
fn a_baseline_of_another_version_is_exit_2() {
    let dir = checked_against_rig("rig.log");
    let path = dir.path().join("baseline.json");
    let text = fs::read_to_string(&path).expect("read");
    fs::write(
        &path,
        text.replace("\"baseline_version\": 1", "\"baseline_version\": 2"),
    )
    .expect("write");
    let out = check(&dir, &[]).code(2).stdout("");
    let err = one_error_line(&out.get_output().stderr);
    assert!(
        err.contains("baseline.json: baseline version 2 is not supported"),
        "{err}"
    );
}

#[test]
fn an_unreadable_or_invalid_baseline_is_exit_2() {
    let dir = workspace("rig.log");
    let out = check(&dir, &[]).code(2).stdout("");
    let err = one_error_line(&out.get_output().stderr);
    assert_eq!(err, "error: baseline.json: No such file or directory\n");

    fs::write(
        dir.path().join("baseline.json"),
        "{\"baseline_version\": 1, \"traces\": [",
    )
    .expect("write");
    let out = check(&dir, &[]).code(2).stdout("");
    let err = one_error_line(&out.get_output().stderr);
    assert!(
        err.starts_with("error: baseline.json: not a baseline"),
        "{err}"
    );

    fs::write(dir.path().join("baseline.json"), "{\"traces\": {}}").expect("write");
    let out = check(&dir, &[]).code(2);
    one_error_line(&out.get_output().stderr);
}

#[test]
fn a_missing_trace_is_exit_2_and_nothing_is_written() {
    let dir = checked_against_rig("rig.log");
    let before = fs::read(dir.path().join("baseline.json")).expect("read");
    for cmd in [
        vec![
            "check",
            "--baseline",
            "baseline.json",
            "traces/nope.log",
            "--update",
        ],
        vec!["baseline", "traces/nope.log", "-o", "baseline.json"],
    ] {
        let out = cmd_in(&dir).args(&cmd).assert().code(2).stdout("");
        let err = one_error_line(&out.get_output().stderr);
        assert_eq!(err, "error: traces/nope.log: No such file or directory\n");
    }
    let after = fs::read(dir.path().join("baseline.json")).expect("read");
    assert_eq!(before, after);
}

#[test]
fn usage_errors_are_exit_2() {
    emcy_decode()
        .args(["check", "fixtures/baseline/rig.log"])
        .assert()
        .code(2);
    emcy_decode().args(["baseline"]).assert().code(2);
    emcy_decode()
        .args([
            "check",
            "-b",
            "x.json",
            "--allow",
            "zz",
            "fixtures/baseline/rig.log",
        ])
        .assert()
        .code(2);
}

// ---- --format json -----------------------------------------------------------------------

#[test]
fn the_json_diff_parses_and_every_finding_has_the_same_keys() {
    let dir = checked_against_rig("new-node.log");
    let out = check(&dir, &["--format", "json"]).code(1);
    let json: Value = serde_json::from_slice(&out.get_output().stdout).expect("JSON");
    let keys =
        |v: &Value| -> Vec<String> { v.as_object().expect("object").keys().cloned().collect() };
    assert_eq!(keys(&json), ["findings", "summary"]);
    assert_eq!(
        keys(&json["summary"]),
        [
            "allowed",
            "changes",
            "improvements",
            "matched",
            "regressions",
            "traces"
        ]
    );
    let findings = json["findings"].as_array().expect("findings");
    assert_eq!(findings.len(), 1);
    let f = &findings[0];
    let mut expected = vec![
        "allowed",
        "baseline_count",
        "channel",
        "code",
        "count",
        "file",
        "kind",
        "message",
        "node",
        "severity",
    ];
    expected.sort_unstable();
    assert_eq!(keys(f), expected);
    assert_eq!(f["severity"], "regression");
    assert_eq!(f["kind"], "new_node");
    assert_eq!(f["file"], "traces/rig.log");
    assert_eq!(f["channel"], "can0");
    assert_eq!(f["node"], 3);
    assert_eq!(f["code"], Value::Null);
    assert_eq!(json["summary"]["regressions"], 1);

    let dir = checked_against_rig("new-error.log");
    let out = check(&dir, &["-f", "json", "--allow", "2310"]).code(0);
    let json: Value = serde_json::from_slice(&out.get_output().stdout).expect("JSON");
    let f = &json["findings"][0];
    assert_eq!(f["kind"], "new_error");
    assert_eq!(f["code"], "0x2310");
    assert_eq!(f["count"], 1);
    assert_eq!(f["baseline_count"], Value::Null);
    assert_eq!(f["allowed"], true);
    assert_eq!(json["summary"]["allowed"], 1);
}

// ---- the guide's CI example (docs/guide/ci.md) -------------------------------------------------

/// Runs a guide command line with `sh` in `dir`, the built binary first on
/// PATH (so `emcy-decode` and shell globs work as in CI).
#[cfg(unix)]
fn sh(dir: &Path, line: &str) -> std::process::Output {
    let bin = assert_cmd::cargo::cargo_bin("emcy-decode");
    let bin_dir = bin.parent().expect("binary dir");
    let path = std::env::join_paths(std::iter::once(bin_dir.to_path_buf()).chain(
        std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()),
    ))
    .expect("PATH");
    std::process::Command::new("sh")
        .args(["-c", line])
        .current_dir(dir)
        .env("PATH", path)
        .env_remove("NO_COLOR")
        .env_remove("COLUMNS")
        .output()
        .expect("sh runs")
}

#[cfg(unix)]
#[test]
fn the_readme_ci_example_works() {
    let lines = readme_block("ci-example");
    let commands: Vec<&String> = lines.iter().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(commands.len(), 2, "a two-line CI step: {lines:?}");
    let (make, check) = (commands[0], commands[1]);
    assert!(make.starts_with("emcy-decode baseline "), "{make}");
    assert!(check.starts_with("emcy-decode check "), "{check}");

    let dir = tempfile::tempdir().expect("temp dir");
    let traces = dir.path().join("traces");
    fs::create_dir(&traces).expect("mkdir");
    fs::copy(fixture("rig.log"), traces.join("rig.log")).expect("copy");
    fs::copy(fixture("node-gone.log"), traces.join("bench.log")).expect("copy");

    let out = sh(dir.path(), make);
    assert_eq!(out.status.code(), Some(0), "{make}: {out:?}");
    // A run like the recorded one passes...
    let out = sh(dir.path(), check);
    assert_eq!(out.status.code(), Some(0), "{check}: {out:?}");
    assert!(String::from_utf8_lossy(&out.stdout).ends_with("2 of 2 traces matched\n"));
    // ...a run with a new error fails the job.
    fs::copy(fixture("new-error.log"), traces.join("rig.log")).expect("copy");
    let out = sh(dir.path(), check);
    assert_eq!(out.status.code(), Some(1), "{check}: {out:?}");
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .starts_with("regression: traces/rig.log can0 node 1: new error 0x2310")
    );
}

#[test]
fn the_readme_baseline_example_is_what_baseline_writes() {
    let lines = readme_block("baseline-example");
    let (command, json) = lines.split_first().expect("a command, then the file");
    let command = command.strip_prefix("$ ").expect("`$ command` line");
    let args: Vec<&str> = command.split_whitespace().skip(1).collect();
    let out = emcy_decode().args(&args).assert().code(0);
    let expected = json.join("\n") + "\n";
    let actual = String::from_utf8_lossy(&out.get_output().stdout);
    assert!(
        actual == expected,
        "baseline example of docs/guide/ci.md is stale:\n{}",
        first_difference(&expected, &actual)
    );
}

#[test]
fn stdin_is_recorded_as_stdin() {
    let trace = fs::read_to_string(fixture("rig.log")).expect("read");
    let out = emcy_decode()
        .args(["baseline", "-"])
        .write_stdin(trace)
        .assert()
        .code(0);
    let json: Value = serde_json::from_slice(&out.get_output().stdout).expect("JSON");
    assert!(json["traces"]["<stdin>"].is_object());
}

#[test]
fn help_lists_both_commands() {
    emcy_decode()
        .arg("--help")
        .assert()
        .code(0)
        .stdout(predicate::str::contains("baseline").and(predicate::str::contains("check")));
}

// ---- where the baseline is written: nothing but a regular file is replaced ----------------

/// The names in `dir`, sorted: a temporary file left behind would show.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort_unstable();
    names
}

/// What `baseline traces/rig.log` prints in `dir`.
fn expected_baseline(dir: &TempDir) -> Vec<u8> {
    let out = cmd_in(dir)
        .args(["baseline", "traces/rig.log"])
        .assert()
        .code(0);
    out.get_output().stdout.clone()
}

#[cfg(unix)]
fn mkfifo(path: &Path) {
    let status = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(status.success(), "mkfifo {}", path.display());
}

/// `mknod PATH TYPE MAJOR MINOR`; false where device nodes cannot be made
/// (not root, or a container without the capability).
#[cfg(unix)]
fn mknod(path: &Path, kind: &str, major: u32, minor: u32) -> bool {
    std::process::Command::new("mknod")
        .arg(path)
        .args([kind, &major.to_string(), &minor.to_string()])
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

#[cfg(unix)]
fn file_type(path: &Path) -> fs::FileType {
    fs::symlink_metadata(path).expect("stat").file_type()
}

/// Runs `baseline traces/rig.log -o out.fifo` with `cat` reading the FIFO
/// and returns what `cat` read. Fails (instead of hanging) when the FIFO was
/// renamed over: `cat` would wait on it for ever.
#[cfg(unix)]
fn written_into_fifo(dir: &TempDir, fifo: &str) -> Vec<u8> {
    use std::os::unix::fs::FileTypeExt;
    use std::process::Stdio;
    let path = dir.path().join(fifo);
    mkfifo(&path);
    let cat = std::process::Command::new("cat")
        .arg(&path)
        .stdout(Stdio::piped())
        .spawn()
        .expect("cat runs");
    let status = crate::support::binary()
        .current_dir(dir.path())
        .args(["baseline", "traces/rig.log", "-o", fifo])
        .status()
        .expect("runs");
    if !file_type(&path).is_fifo() {
        let mut cat = cat;
        let _ = cat.kill();
        let _ = cat.wait();
        panic!("the FIFO was replaced (exit {status})");
    }
    let out = cat.wait_with_output().expect("cat ends");
    assert_eq!(status.code(), Some(0));
    out.stdout
}

#[cfg(unix)]
#[test]
fn a_fifo_given_to_o_is_written_into_not_replaced() {
    let dir = workspace("rig.log");
    let expected = expected_baseline(&dir);
    let read = written_into_fifo(&dir, "out.fifo");
    assert_eq!(read, expected);
    assert_eq!(listing(dir.path()), ["out.fifo", "traces"]);
}

#[cfg(unix)]
#[test]
fn dev_null_and_other_character_devices_given_to_o_are_written_into_not_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let dir = workspace("rig.log");
    // First a FIFO: a build that renames over one would rename over
    // /dev/null below too, as root.
    written_into_fifo(&dir, "guard.fifo");
    let null = dir.path().join("null");
    if mknod(&null, "c", 1, 3) {
        cmd_in(&dir)
            .args(["baseline", "traces/rig.log", "-o", "null"])
            .assert()
            .code(0)
            .stdout("")
            .stderr("");
        assert!(file_type(&null).is_char_device(), "the device was replaced");
        assert_eq!(listing(dir.path()), ["guard.fifo", "null", "traces"]);
    } else {
        eprintln!("note: cannot mknod here; only /dev/null is tried");
    }
    cmd_in(&dir)
        .args(["baseline", "traces/rig.log", "-o", "/dev/null"])
        .assert()
        .code(0)
        .stdout("")
        .stderr("");
    assert!(file_type(Path::new("/dev/null")).is_char_device());
}

#[cfg(target_os = "linux")]
#[test]
fn dev_stdout_is_written_into_a_pipe_and_appended_to_a_file() {
    if !Path::new("/dev/stdout").exists() {
        eprintln!("skipped: no /dev/stdout");
        return;
    }
    let dir = workspace("rig.log");
    // As for /dev/null: a build that renames over a FIFO would replace
    // /dev/stdout, as root.
    written_into_fifo(&dir, "guard.fifo");
    let expected = expected_baseline(&dir);
    // The test captures stdout through a pipe.
    cmd_in(&dir)
        .args(["baseline", "traces/rig.log", "-o", "/dev/stdout"])
        .assert()
        .code(0)
        .stdout(expected.clone())
        .stderr("");
    // A file the shell opened with `>>` keeps what it had.
    fs::write(dir.path().join("log.txt"), "first\n").expect("write");
    let bin = assert_cmd::cargo::cargo_bin("emcy-decode");
    let status = std::process::Command::new("sh")
        .args([
            "-c",
            "\"$0\" baseline traces/rig.log -o /dev/stdout >> log.txt",
        ])
        .arg(&bin)
        .current_dir(dir.path())
        .status()
        .expect("sh runs");
    assert_eq!(status.code(), Some(0));
    let mut want = b"first\n".to_vec();
    want.extend_from_slice(&expected);
    assert_eq!(fs::read(dir.path().join("log.txt")).expect("read"), want);
    assert!(file_type(Path::new("/dev/stdout")).is_symlink());
}

#[cfg(unix)]
#[test]
fn a_symlink_given_to_o_is_written_through_to_its_target_with_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = workspace("rig.log");
    let expected = expected_baseline(&dir);
    let store = dir.path().join("store");
    fs::create_dir(&store).expect("mkdir");
    fs::write(store.join("baseline.json"), "old\n").expect("write");
    fs::set_permissions(
        store.join("baseline.json"),
        fs::Permissions::from_mode(0o640),
    )
    .expect("chmod");
    std::os::unix::fs::symlink("store/baseline.json", dir.path().join("baseline.json"))
        .expect("symlink");

    cmd_in(&dir)
        .args(["baseline", "traces/rig.log", "-o", "baseline.json"])
        .assert()
        .code(0)
        .stdout("")
        .stderr("");
    let link = dir.path().join("baseline.json");
    assert!(file_type(&link).is_symlink(), "the link was replaced");
    assert_eq!(
        fs::read_link(&link).expect("readlink"),
        Path::new("store/baseline.json")
    );
    assert_eq!(
        fs::read(store.join("baseline.json")).expect("read"),
        expected
    );
    let mode = fs::metadata(store.join("baseline.json"))
        .expect("stat")
        .permissions();
    assert_eq!(mode.mode() & 0o777, 0o640);
    assert_eq!(listing(dir.path()), ["baseline.json", "store", "traces"]);
    assert_eq!(listing(&store), ["baseline.json"]);

    // `check --update` rewrites the baseline through the link as well.
    put(&dir, "new-error.log");
    check(&dir, &["--update"]).code(0);
    assert!(file_type(&link).is_symlink(), "--update replaced the link");
    assert_ne!(
        fs::read(store.join("baseline.json")).expect("read"),
        expected
    );
    assert_eq!(listing(&store), ["baseline.json"]);
    check(&dir, &[]).code(0);
}

/// Root replacing another user's baseline (a CI job run as root, a `sudo`)
/// keeps the file that user's: owner and group as they were, for both
/// `baseline -o` and `check --update`. Needs root to give a file away;
/// skipped otherwise.
#[cfg(unix)]
#[test]
fn root_replacing_a_users_baseline_keeps_its_owner_and_group() {
    use std::os::unix::fs::MetadataExt;
    let dir = workspace("rig.log");
    let path = dir.path().join("baseline.json");
    fs::write(&path, "old\n").expect("write");
    if fs::metadata(&path).expect("stat").uid() != 0 {
        eprintln!("note: not root, a file cannot be given away; skipped");
        return;
    }
    let nobody = 65534;
    std::os::unix::fs::chown(&path, Some(nobody), Some(nobody)).expect("chown");
    cmd_in(&dir)
        .args(["baseline", "traces/rig.log", "-o", "baseline.json"])
        .assert()
        .code(0);
    let owner = |path: &Path| {
        let meta = fs::metadata(path).expect("stat");
        (meta.uid(), meta.gid())
    };
    assert_eq!(owner(&path), (nobody, nobody), "baseline -o");
    assert_ne!(fs::read(&path).expect("read"), b"old\n");
    put(&dir, "new-error.log");
    check(&dir, &["--update"]).code(0);
    assert_eq!(owner(&path), (nobody, nobody), "check --update");
    // A new file is the process's own.
    cmd_in(&dir)
        .args(["baseline", "traces/rig.log", "-o", "new.json"])
        .assert()
        .code(0);
    assert_eq!(owner(&dir.path().join("new.json")), (0, 0));
    assert_eq!(listing(dir.path()), ["baseline.json", "new.json", "traces"]);
}

#[cfg(unix)]
#[test]
fn a_dangling_symlink_given_to_o_gets_its_target_created() {
    use std::os::unix::fs::PermissionsExt;
    let dir = workspace("rig.log");
    let expected = expected_baseline(&dir);
    fs::create_dir(dir.path().join("store")).expect("mkdir");
    std::os::unix::fs::symlink("store/new.json", dir.path().join("baseline.json"))
        .expect("symlink");
    cmd_in(&dir)
        .args(["baseline", "traces/rig.log", "-o", "baseline.json"])
        .assert()
        .code(0);
    assert!(file_type(&dir.path().join("baseline.json")).is_symlink());
    let target = dir.path().join("store/new.json");
    assert_eq!(fs::read(&target).expect("read"), expected);
    let mode = fs::metadata(&target).expect("stat").permissions().mode();
    assert_eq!(mode & 0o777, 0o644);
    assert_eq!(listing(&dir.path().join("store")), ["new.json"]);
}

#[cfg(unix)]
#[test]
fn a_directory_socket_block_device_or_link_loop_given_to_o_is_refused_and_left_alone() {
    let dir = workspace("rig.log");
    fs::create_dir(dir.path().join("out")).expect("mkdir");
    fs::write(dir.path().join("out/keep"), "keep\n").expect("write");
    std::os::unix::fs::symlink("out", dir.path().join("to-dir")).expect("symlink");
    let _socket =
        std::os::unix::net::UnixListener::bind(dir.path().join("sock")).expect("bind socket");
    std::os::unix::fs::symlink("loop-b", dir.path().join("loop-a")).expect("symlink");
    std::os::unix::fs::symlink("loop-a", dir.path().join("loop-b")).expect("symlink");
    let mut cases = vec![
        ("out", "out is a directory"),
        ("to-dir", "to-dir (a link to out) is a directory"),
        ("sock", "sock is a socket"),
        ("loop-a", "too many symbolic links"),
    ];
    // Never written, but refused before anything could be.
    if mknod(&dir.path().join("blk"), "b", 7, 200) {
        cases.push(("blk", "blk is a block device"));
    } else {
        eprintln!("note: cannot mknod here; no block device tried");
    }
    let before = listing(dir.path());
    let types: Vec<fs::FileType> = before
        .iter()
        .map(|n| file_type(&dir.path().join(n)))
        .collect();
    for (out, message) in cases {
        for args in [
            vec!["baseline", "traces/rig.log", "-o", out],
            vec!["check", "-b", out, "traces/rig.log", "--update"],
        ] {
            let run = cmd_in(&dir).args(&args).assert().code(2).stdout("");
            let err = one_error_line(&run.get_output().stderr);
            if args[0] == "baseline" {
                assert!(err.contains(message), "{args:?}: {err}");
            }
        }
        let after: Vec<fs::FileType> = listing(dir.path())
            .iter()
            .map(|n| file_type(&dir.path().join(n)))
            .collect();
        assert_eq!(listing(dir.path()), before, "-o {out}");
        assert_eq!(after, types, "-o {out}");
    }
    assert_eq!(listing(&dir.path().join("out")), ["keep"]);
}

/// Runs `args` in `dir` and checks that it fails with one `error:` line
/// containing `message`, leaving `baseline.json` as it was and no file
/// behind.
fn fails_and_keeps_the_baseline(dir: &TempDir, cmd: &mut Command, message: &str) {
    let path = dir.path().join("baseline.json");
    let before = fs::read(&path).expect("read");
    let names = listing(dir.path());
    let out = cmd.assert().code(2).stdout("");
    let err = one_error_line(&out.get_output().stderr);
    assert!(err.contains(message), "{err}");
    assert_eq!(fs::read(&path).expect("read"), before);
    assert_eq!(listing(dir.path()), names);
}

#[cfg(unix)]
#[test]
fn a_read_only_directory_keeps_the_old_baseline_and_no_temporary_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = workspace("rig.log");
    fs::create_dir(dir.path().join("ro")).expect("mkdir");
    fs::write(dir.path().join("ro/baseline.json"), "old\n").expect("write");
    let ro = dir.path().join("ro");
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).expect("chmod");
    // As root permission bits do not stop a write: then there is nothing
    // to see here (the write that fails part way is the next test).
    let probe = ro.join("probe");
    if fs::write(&probe, "").is_ok() {
        let _ = fs::remove_file(&probe);
        eprintln!("note: permission bits do not stop writes here (root); skipped");
    } else {
        for args in [
            vec!["baseline", "traces/rig.log", "-o", "ro/baseline.json"],
            vec![
                "check",
                "-b",
                "ro/baseline.json",
                "traces/rig.log",
                "--update",
            ],
        ] {
            let out = cmd_in(&dir).args(&args).assert().code(2);
            let err = one_error_line(&out.get_output().stderr);
            assert!(err.contains("ro/baseline.json"), "{err}");
            assert_eq!(fs::read(ro.join("baseline.json")).expect("read"), b"old\n");
            assert_eq!(listing(&ro), ["baseline.json"]);
        }
    }
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).expect("chmod back");
}

/// A write that fails half way (the file size limit at 0, which also binds
/// root) leaves the old baseline and no temporary file.
#[cfg(unix)]
#[test]
fn a_write_that_fails_keeps_the_old_baseline_and_no_temporary_file() {
    let dir = checked_against_rig("new-error.log");
    let bin = assert_cmd::cargo::cargo_bin("emcy-decode");
    for args in [
        "baseline traces/rig.log -o baseline.json",
        "check -b baseline.json traces/rig.log --update",
    ] {
        // SIGXFSZ ignored, so the write fails with EFBIG instead of the
        // signal ending the process.
        let line = format!("trap '' XFSZ; ulimit -f 0; exec \"$0\" {args} >/dev/null");
        let mut cmd = Command::new("sh");
        cmd.args(["-c", &line]).arg(&bin).current_dir(dir.path());
        let path = dir.path().join("baseline.json");
        let before = fs::read(&path).expect("read");
        let names = listing(dir.path());
        let out = cmd.assert().code(2);
        let err = one_error_line(&out.get_output().stderr);
        assert!(err.starts_with("error: writing baseline.json: "), "{err}");
        assert_eq!(fs::read(&path).expect("read"), before);
        assert_eq!(listing(dir.path()), names);
    }
}

#[cfg(unix)]
#[test]
fn a_trace_that_cannot_be_read_keeps_the_old_baseline_behind_a_link() {
    let dir = checked_against_rig("rig.log");
    fs::create_dir(dir.path().join("store")).expect("mkdir");
    fs::rename(
        dir.path().join("baseline.json"),
        dir.path().join("store/baseline.json"),
    )
    .expect("move");
    std::os::unix::fs::symlink("store/baseline.json", dir.path().join("baseline.json"))
        .expect("symlink");
    // A gzip cut short: read in part, then an error.
    let gz =
        fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/s300.log.gz")).expect("read");
    fs::write(dir.path().join("traces/cut.log.gz"), &gz[..gz.len() / 2]).expect("write");
    for args in [
        vec!["baseline", "traces/nope.log", "-o", "baseline.json"],
        vec!["baseline", "traces/cut.log.gz", "-o", "baseline.json"],
        vec![
            "check",
            "-b",
            "baseline.json",
            "traces/nope.log",
            "--update",
        ],
        vec![
            "check",
            "-b",
            "baseline.json",
            "traces/cut.log.gz",
            "--update",
        ],
    ] {
        let before = fs::read(dir.path().join("store/baseline.json")).expect("read");
        let names = listing(dir.path());
        let out = cmd_in(&dir).args(&args).assert().code(2).stdout("");
        let stderr = String::from_utf8_lossy(&out.get_output().stderr).into_owned();
        assert!(stderr.contains("error: traces/"), "{args:?}: {stderr}");
        assert!(file_type(&dir.path().join("baseline.json")).is_symlink());
        assert_eq!(
            fs::read(dir.path().join("store/baseline.json")).expect("read"),
            before,
            "{args:?}"
        );
        assert_eq!(listing(dir.path()), names);
        assert_eq!(listing(&dir.path().join("store")), ["baseline.json"]);
    }
}

#[test]
fn the_baseline_is_never_written_over_a_trace_or_profile_file_given_with_it() {
    let dir = checked_against_rig("rig.log");
    let trace = fs::read(dir.path().join("traces/rig.log")).expect("read");
    fs::write(dir.path().join("vendor.toml"), "# a profile\n").expect("write");
    fs::hard_link(
        dir.path().join("traces/rig.log"),
        dir.path().join("alias.log"),
    )
    .expect("hard link");
    let mut cases = vec![
        (
            vec!["baseline", "traces/rig.log", "-o", "traces/rig.log"],
            "traces/rig.log is also given as a trace;",
        ),
        (
            vec!["baseline", "traces/rig.log", "-o", "./traces//rig.log"],
            "./traces//rig.log is also given as a trace (as traces/rig.log);",
        ),
        (
            vec!["baseline", "traces/rig.log", "-o", "alias.log"],
            "alias.log is also given as a trace (as traces/rig.log);",
        ),
        (
            vec![
                "baseline",
                "traces/rig.log",
                "--profile-file",
                "vendor.toml",
                "-o",
                "vendor.toml",
            ],
            "vendor.toml is also given as a profile file;",
        ),
        (
            vec![
                "check",
                "-b",
                "baseline.json",
                "traces/rig.log",
                "baseline.json",
                "--update",
            ],
            "baseline.json is also given as a trace;",
        ),
    ];
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("traces/rig.log", dir.path().join("link.log")).expect("symlink");
        cases.push((
            vec!["baseline", "traces/rig.log", "-o", "link.log"],
            "link.log is also given as a trace (as traces/rig.log);",
        ));
    }
    for (args, message) in cases {
        let mut cmd = cmd_in(&dir);
        cmd.args(&args);
        fails_and_keeps_the_baseline(&dir, &mut cmd, message);
        assert_eq!(
            fs::read(dir.path().join("traces/rig.log")).expect("read"),
            trace,
            "{args:?}"
        );
        assert_eq!(
            fs::read(dir.path().join("vendor.toml")).expect("read"),
            b"# a profile\n"
        );
    }
}

#[test]
fn check_update_with_a_baseline_file_named_dash_rewrites_that_file() {
    let dir = checked_against_rig("rig.log");
    fs::rename(dir.path().join("baseline.json"), dir.path().join("-")).expect("rename");
    put(&dir, "new-error.log");
    cmd_in(&dir)
        .args(["check", "-b", "-", "traces/rig.log", "--update"])
        .assert()
        .code(0)
        .stdout(
            predicate::str::starts_with("regression: ").and(predicate::str::contains("{").not()),
        )
        .stderr("check: wrote -\n");
    let updated = fs::read(dir.path().join("-")).expect("read");
    assert_eq!(updated, expected_baseline(&dir));
}

// ---- JUnit and GitHub reports ------------------------------------------------------

/// Two traces in the baseline; then `rig.log` gains a new error and
/// `other.log` loses its errors (improvements); `args` added to check.
fn two_traces_checked(format: &str, args: &[&str]) -> (Option<i32>, String) {
    let dir = workspace("rig.log");
    fs::copy(fixture("rig.log"), dir.path().join("traces/other.log")).unwrap();
    cmd_in(&dir)
        .args([
            "baseline",
            "traces/rig.log",
            "traces/other.log",
            "-o",
            "baseline.json",
        ])
        .assert()
        .code(0);
    put(&dir, "new-error.log");
    fs::copy(fixture("improved.log"), dir.path().join("traces/other.log")).unwrap();
    let out = cmd_in(&dir)
        .args(["check", "--baseline", "baseline.json", "-f", format])
        .args(["traces/rig.log", "traces/other.log"])
        .args(args)
        .output()
        .unwrap();
    (out.status.code(), String::from_utf8(out.stdout).unwrap())
}

#[test]
fn junit_has_a_test_case_per_trace_and_a_failure_per_regression() {
    let (code, xml) = two_traces_checked("junit", &[]);
    assert_eq!(code, Some(1));
    let doc = roxmltree::Document::parse(&xml).expect("well-formed XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "testsuites");
    let suites: Vec<_> = root.children().filter(|n| n.is_element()).collect();
    assert_eq!(suites.len(), 1);
    let suite = suites[0];
    assert_eq!(suite.tag_name().name(), "testsuite");
    assert_eq!(suite.attribute("tests"), Some("2"));
    assert_eq!(suite.attribute("failures"), Some("1"));
    let cases: Vec<_> = suite
        .children()
        .filter(|n| n.has_tag_name("testcase"))
        .collect();
    let names: Vec<_> = cases.iter().map(|c| c.attribute("name").unwrap()).collect();
    assert_eq!(names, ["traces/other.log", "traces/rig.log"]);
    // other.log improved: passes, its improvements noted.
    assert!(cases[0].children().all(|n| !n.has_tag_name("failure")));
    let out = cases[0]
        .children()
        .find(|n| n.has_tag_name("system-out"))
        .and_then(|n| n.text())
        .unwrap();
    assert!(out.starts_with("improvement: traces/other.log"), "{out}");
    // rig.log: one failure, the regression's line of text.
    let failures: Vec<_> = cases[1]
        .children()
        .filter(|n| n.has_tag_name("failure"))
        .collect();
    assert_eq!(failures.len(), 1);
    assert_eq!(failures[0].attribute("type"), Some("new_error"));
    assert_eq!(
        failures[0].attribute("message"),
        Some(
            "regression: traces/rig.log can0 node 1: new error 0x2310 (1x): \
             Current · output side · continuous over current"
        )
    );
}

#[test]
fn junit_cases_and_suites_say_how_long_they_took() {
    let (_, xml) = two_traces_checked("junit", &[]);
    let doc = roxmltree::Document::parse(&xml).unwrap();
    for tag in ["testsuites", "testsuite", "testcase"] {
        for node in doc.descendants().filter(|n| n.has_tag_name(tag)) {
            let time = node
                .attribute("time")
                .unwrap_or_else(|| panic!("{tag}: {xml}"));
            let seconds: f64 = time.parse().expect("seconds");
            assert!((0.0..60.0).contains(&seconds), "{tag} time {time}");
        }
    }
}

#[test]
fn junit_with_an_unreadable_trace_is_valid_xml_with_an_error_case() {
    let dir = workspace("rig.log");
    make_baseline(&dir);
    let out = cmd_in(&dir)
        .args(["check", "--baseline", "baseline.json", "-f", "junit"])
        .args(["traces/rig.log", "traces/gone.log"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let xml = String::from_utf8(out.stdout).unwrap();
    let doc = roxmltree::Document::parse(&xml).expect("well-formed XML");
    let suite = doc
        .descendants()
        .find(|n| n.has_tag_name("testsuite"))
        .unwrap();
    assert_eq!(suite.attribute("tests"), Some("2"));
    assert_eq!(suite.attribute("errors"), Some("1"));
    assert_eq!(suite.attribute("skipped"), Some("1"));
    let case = |name: &str| {
        doc.descendants()
            .find(|n| n.has_tag_name("testcase") && n.attribute("name") == Some(name))
            .unwrap_or_else(|| panic!("{name}: {xml}"))
    };
    let error = case("traces/gone.log")
        .children()
        .find(|n| n.has_tag_name("error"))
        .expect("an error element");
    assert!(
        error
            .attribute("message")
            .unwrap()
            .starts_with("traces/gone.log: "),
        "{xml}"
    );
    assert!(
        case("traces/rig.log")
            .children()
            .any(|n| n.has_tag_name("skipped"))
    );
    // A directory with no trace under it is an unreadable case too.
    let out = cmd_in(&dir)
        .args(["check", "--baseline", "baseline.json", "-f", "junit", "-r"])
        .args(["--glob", "*.nope", "traces"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let xml = String::from_utf8(out.stdout).unwrap();
    let doc = roxmltree::Document::parse(&xml).expect("well-formed XML");
    assert_eq!(
        doc.descendants()
            .filter(|n| n.has_tag_name("error"))
            .count(),
        1
    );
}

#[test]
fn junit_shows_an_allowed_regression_as_a_passed_case_with_a_note() {
    let (code, xml) = two_traces_checked("junit", &["--allow", "0x2310"]);
    assert_eq!(code, Some(0));
    let doc = roxmltree::Document::parse(&xml).unwrap();
    assert!(doc.descendants().all(|n| !n.has_tag_name("failure")));
    let rig = doc
        .descendants()
        .find(|n| n.attribute("name") == Some("traces/rig.log"))
        .unwrap();
    let note = rig
        .children()
        .find(|n| n.has_tag_name("system-out"))
        .unwrap();
    assert!(
        note.text()
            .unwrap()
            .starts_with("allowed: traces/rig.log can0 node 1: new error 0x2310")
    );
}

#[test]
fn github_annotates_each_regression_on_its_trace() {
    let (code, text) = two_traces_checked("github", &[]);
    assert_eq!(code, Some(1));
    assert_eq!(
        text,
        "::error file=traces/rig.log,title=emcy-decode check%3A regression::traces/rig.log can0 \
         node 1: new error 0x2310 (1x): Current · output side · continuous over current\n\
         check: 1 regression, 2 improvements, 0 changes; 1 of 2 traces matched\n"
    );
}

// ---- decoding options, --root, --only-given -----------------------------------------

#[test]
fn a_baseline_records_its_decoding_options_and_check_refuses_others() {
    let dir = workspace("rig.log");
    cmd_in(&dir)
        .args([
            "baseline",
            "traces/rig.log",
            "--profile",
            "1=kollmorgen",
            "-o",
            "baseline.json",
        ])
        .assert()
        .code(0);
    let text = fs::read_to_string(dir.path().join("baseline.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        v["options"],
        serde_json::json!({"profile": ["1=kollmorgen"]})
    );
    check(&dir, &["--profile", "1=kollmorgen"]).code(0);
    check(&dir, &[]).code(2).stdout("").stderr(
        "error: baseline.json was made with --profile 1=kollmorgen, this check reads with no \
         decoding options: give the same decoding options (or --update to record these)\n",
    );
    // --update records the options it read with.
    check(&dir, &["--update"]).code(0);
    let v: Value =
        serde_json::from_str(&fs::read_to_string(dir.path().join("baseline.json")).unwrap())
            .unwrap();
    assert!(v.get("options").is_none(), "{v}");
    check(&dir, &[]).code(0);
}

#[test]
fn root_gives_the_same_keys_from_another_directory() {
    let dir = checked_against_rig("rig.log");
    fs::create_dir(dir.path().join("ci")).unwrap();
    let from_ci = |args: &[&str]| {
        let out = emcy_decode()
            .current_dir(dir.path().join("ci"))
            .args([
                "check",
                "--baseline",
                "../baseline.json",
                "../traces/rig.log",
            ])
            .args(args)
            .output()
            .unwrap();
        (out.status.code(), String::from_utf8(out.stderr).unwrap())
    };
    let (code, stderr) = from_ci(&[]);
    assert_eq!(code, Some(1));
    assert!(
        stderr.contains(
            "check: no trace matched the baseline: it records traces by their path relative to \
             where it was made ('traces/rig.log'), this run gave '../traces/rig.log'"
        ),
        "{stderr}"
    );
    assert_eq!(from_ci(&["--root", ".."]), (Some(0), String::new()));
}

#[test]
fn only_given_checks_a_subset_and_updates_only_it() {
    let dir = workspace("rig.log");
    fs::copy(fixture("rig.log"), dir.path().join("traces/other.log")).unwrap();
    cmd_in(&dir)
        .args([
            "baseline",
            "traces/rig.log",
            "traces/other.log",
            "-o",
            "baseline.json",
        ])
        .assert()
        .code(0);
    // Without it the other trace is a regression: not given.
    check(&dir, &[]).code(1);
    check(&dir, &["--only-given"])
        .code(0)
        .stdout("check: 0 regressions, 0 improvements, 0 changes; 1 of 1 trace matched\n");
    put(&dir, "new-error.log");
    check(&dir, &["--only-given", "--update"]).code(0);
    let v: Value =
        serde_json::from_str(&fs::read_to_string(dir.path().join("baseline.json")).unwrap())
            .unwrap();
    let traces = v["traces"].as_object().unwrap();
    assert_eq!(traces.len(), 2, "the other trace's record is kept");
    assert!(traces["traces/rig.log"]["nodes"]["can0"]["1"]["errors"]["0x2310"].is_object());
}

#[test]
fn baseline_and_check_read_directories_with_r_as_decoding_does() {
    let dir = workspace("rig.log");
    fs::create_dir(dir.path().join("traces/more")).unwrap();
    fs::copy(
        fixture("improved.log"),
        dir.path().join("traces/more/other.log"),
    )
    .unwrap();
    fs::write(dir.path().join("traces/notes.md"), "# not a trace\n").unwrap();
    cmd_in(&dir)
        .args(["baseline", "-r", "traces", "-o", "baseline.json"])
        .assert()
        .code(0)
        .stderr(predicate::str::contains("skipped 1 file that is no trace"));
    let v: Value =
        serde_json::from_str(&fs::read_to_string(dir.path().join("baseline.json")).unwrap())
            .unwrap();
    let keys: Vec<&String> = v["traces"].as_object().unwrap().keys().collect();
    assert_eq!(keys, ["traces/more/other.log", "traces/rig.log"]);
    cmd_in(&dir)
        .args(["check", "--baseline", "baseline.json", "-r", "traces"])
        .assert()
        .code(0);
    // --glob picks a subset; with --only-given it is checked alone.
    cmd_in(&dir)
        .args(["check", "--baseline", "baseline.json", "-r", "traces"])
        .args(["--glob", "more/*", "--only-given"])
        .assert()
        .code(0)
        .stdout("check: 0 regressions, 0 improvements, 0 changes; 1 of 1 trace matched\n");
    // Without -r a directory is refused, nothing compared.
    cmd_in(&dir)
        .args(["check", "--baseline", "baseline.json", "traces"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "is a directory; -r (--recursive) reads",
        ));
}

#[test]
fn the_heartbeat_timeout_is_a_recorded_decoding_option() {
    let dir = workspace("rig.log");
    cmd_in(&dir)
        .args(["baseline", "traces/rig.log", "--heartbeat-timeout", "0.5"])
        .args(["-o", "baseline.json"])
        .assert()
        .code(0);
    let v: Value =
        serde_json::from_str(&fs::read_to_string(dir.path().join("baseline.json")).unwrap())
            .unwrap();
    assert_eq!(v["options"]["heartbeat_timeout"], "0.5");
    check(&dir, &["--heartbeat-timeout", "0.5"]).code(0);
    check(&dir, &["--heartbeat-timeout", "2"])
        .code(2)
        .stderr(predicate::str::contains(
            "was made with --heartbeat-timeout 0.5, this check reads with --heartbeat-timeout 2",
        ));
}
