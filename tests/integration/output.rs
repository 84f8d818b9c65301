//! What reaches a terminal is safe and what cannot be written is said:
//! control characters from file names and user profiles are escaped as
//! trace text is, and output that cannot be written fails the run.

use std::fs;

use crate::support::emcy_decode;

fn no_escape(what: &str, bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    assert!(
        !text.chars().any(|c| c.is_control() && c != '\n'),
        "{what} holds a control character: {text:?}"
    );
}

#[cfg(unix)]
#[test]
fn file_names_cannot_put_control_sequences_on_the_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace\x1b]0;owned\x07.log");
    fs::write(
        &path,
        "(1.000000) can0 081#1043090000000000\n(2.000000) can0 081#zz\n",
    )
    .unwrap();
    let missing = dir.path().join("gone\x1b[2J.log");
    let out = emcy_decode().arg(&path).arg(&missing).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    no_escape("the table", &out.stdout);
    no_escape("stderr", &out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stdout.contains(r"== "), "{stdout}");
    assert!(stdout.contains(r"trace\u{1b}]0;owned\u{7}.log"), "{stdout}");
    assert!(
        stderr.contains(r"trace\u{1b}]0;owned\u{7}.log:2: "),
        "{stderr}"
    );
    assert!(stderr.contains(r"error: "), "{stderr}");
    assert!(
        stderr.contains(r"gone\u{1b}[2J.log: No such file"),
        "{stderr}"
    );
    // JSON escapes them its own way and keeps the name exact.
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .arg(&path)
        .output()
        .unwrap();
    no_escape("ndjson", &out.stdout);
    assert!(String::from_utf8_lossy(&out.stdout).contains(r"trace\u001b]0;owned\u0007.log"));
}

#[test]
fn profile_texts_cannot_put_control_sequences_on_the_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let profile = dir.path().join("evil.toml");
    fs::write(
        &profile,
        "name = \"evil\"\nbase = \"cia402\"\n[codes]\n\"0x4310\" = { text = \"hot\\u001b[31m red\", fault = \"F\\u0007\" }\n",
    )
    .unwrap();
    let trace = dir.path().join("t.log");
    fs::write(&trace, "(1.000000) can0 081#1043090000000000\n").unwrap();
    let out = emcy_decode()
        .arg("--profile-file")
        .arg(&profile)
        .arg(&trace)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    no_escape("the table", &out.stdout);
    assert!(String::from_utf8_lossy(&out.stdout).contains(r"F\u{7} hot\u{1b}[31m red"));
    for args in [
        &["explain", "4310"][..],
        &["explain", "--data", "1043090000000000"],
    ] {
        let out = emcy_decode()
            .args(args)
            .arg("--profile-file")
            .arg(&profile)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
        no_escape("explain", &out.stdout);
        assert!(String::from_utf8_lossy(&out.stdout).contains(r"hot\u{1b}[31m red"));
    }
}

/// A stderr that cannot be written (a full disk) loses the `error:` line
/// but not the exit code: a usage error, an error of the run and
/// `check`'s notes exit as they would with a stderr, never panic (101).
#[cfg(target_os = "linux")]
#[test]
fn errors_while_stderr_is_full_keep_their_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let baseline = dir.path().join("b.json");
    emcy_decode()
        .args(["baseline", "fixtures/s300.log", "-o"])
        .arg(&baseline)
        .assert()
        .code(0);
    let baseline = baseline.to_str().unwrap();
    let runs: [(&[&str], i32); 6] = [
        (&["--no-such-flag"], 2),
        (&["--format", "yaml", "fixtures/s300.log"], 2),
        (&["--tz", "Nowhere/Atlantis", "fixtures/s300.log"], 2),
        (
            &[
                "check",
                "--baseline",
                "/nonexistent/b.json",
                "fixtures/s300.log",
            ],
            2,
        ),
        // Another trace: the notes that no trace matched and of the update.
        (
            &["check", "--baseline", baseline, "fixtures/stoeber.log"],
            1,
        ),
        (
            &[
                "check",
                "--update",
                "--baseline",
                baseline,
                "fixtures/stoeber.log",
            ],
            0,
        ),
    ];
    for (args, code) in runs {
        let full = fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let out = crate::support::binary()
            .args(args)
            .stderr(full)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(code), "{args:?}");
    }
}

/// `--help` and `--version` into a full disk fail like any output that
/// cannot be written; into a reader that goes away they succeed.
#[cfg(target_os = "linux")]
#[test]
fn help_and_version_that_cannot_be_written_exit_2() {
    for flag in ["--help", "--version"] {
        let full = fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let out = crate::support::binary()
            .arg(flag)
            .stdout(full)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{flag}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.starts_with("error: writing output: "), "{stderr}");
        emcy_decode().arg(flag).assert().code(0);
    }
}

/// U+FFFE and U+FFFF (and C0 controls) cannot be in XML at all: a channel
/// name or a profile's text holding them made the chart a file no viewer
/// opens. The SVG and HTML charts put U+FFFD there, as JUnit does, and
/// stay well-formed XML.
#[test]
fn noncharacters_in_names_and_profile_texts_keep_the_chart_valid_xml() {
    let dir = tempfile::tempdir().unwrap();
    let profile = dir.path().join("odd.toml");
    fs::write(
        &profile,
        "name = \"odd\"\nbase = \"cia402\"\n[codes]\n\"0x4310\" = { text = \"hot\\uFFFF drive\\uFFFE\" }\n",
    )
    .unwrap();
    let trace = dir.path().join("t.log");
    fs::write(
        &trace,
        "(1.000000) can\u{FFFE}0 081#1043090000000000\n\
         (2.000000) \u{FFFF} 082#1043090000000000\n",
    )
    .unwrap();
    for format in ["svg", "html"] {
        let out = emcy_decode()
            .args(["--format", format, "--profile-file"])
            .arg(&profile)
            .arg(&trace)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{format}");
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(
            !text.contains(['\u{FFFE}', '\u{FFFF}']),
            "{format}: a noncharacter is left"
        );
        assert!(text.contains("can\u{FFFD}0"), "{format}");
        assert!(text.contains("hot\u{FFFD} drive\u{FFFD}"), "{format}");
        if format == "svg" {
            roxmltree::Document::parse(&text).expect("the SVG is XML");
        }
    }
}
