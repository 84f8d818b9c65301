//! The command-line contract: exit codes, flags, stdin, errors. Hostile
//! input (directories, empty files, corrupt gzip, closed pipes, mixed
//! formats, bounded diagnostics) is `hostile`.

use std::io::Write;
use std::process::Stdio;

use crate::support::{binary, emcy_decode};
use predicates::prelude::*;
use serde_json::Value;

fn ndjson_objects(stdout: &[u8]) -> Vec<Value> {
    String::from_utf8_lossy(stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("valid JSON line"))
        .collect()
}

fn of_type<'a>(objects: &'a [Value], kind: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == kind).collect()
}

// ---- exit codes ----------------------------------------------------------------

#[test]
fn success_is_exit_0() {
    emcy_decode().arg("fixtures/s300.log").assert().code(0);
}

#[test]
fn fail_on_any_exits_1_when_an_error_code_was_seen() {
    emcy_decode()
        .args(["--fail-on", "any", "fixtures/s300.log"])
        .assert()
        .code(1);
}

#[test]
fn fail_on_any_ignores_traces_with_only_resets() {
    let trace = "(1.000000) can0 081#0000000000000000\n";
    emcy_decode()
        .args(["--fail-on", "any", "-"])
        .write_stdin(trace)
        .assert()
        .code(0);
}

#[test]
fn fail_on_active_exits_1_only_when_an_error_is_still_active() {
    // s300 ends with 0x5111 active; stoeber ends error-free.
    emcy_decode()
        .args(["--fail-on", "active", "fixtures/s300.log"])
        .assert()
        .code(1);
    emcy_decode()
        .args(["--fail-on", "active", "fixtures/stoeber.log"])
        .assert()
        .code(0);
    emcy_decode()
        .args(["--fail-on", "any", "fixtures/stoeber.log"])
        .assert()
        .code(1);
}

#[test]
fn fail_on_respects_the_node_filter() {
    // In edge.log node 3 ends without an active error, node 4 with three.
    emcy_decode()
        .args(["--fail-on", "active", "--node", "3", "fixtures/edge.log"])
        .assert()
        .code(0);
    emcy_decode()
        .args(["--fail-on", "active", "--node", "4", "fixtures/edge.log"])
        .assert()
        .code(1);
}

#[test]
fn missing_file_is_one_error_line_and_exit_2() {
    emcy_decode()
        .arg("fixtures/does-not-exist.log")
        .assert()
        .code(2)
        .stderr(predicate::eq(
            "error: fixtures/does-not-exist.log: No such file or directory\n",
        ));
}

#[test]
fn other_files_are_still_reported_when_one_is_missing() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "nope.log", "fixtures/stoeber.log"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let objects = ndjson_objects(&out.stdout);
    let inputs = of_type(&objects, "input");
    assert_eq!(inputs.len(), 2, "every argument has an input object");
    assert_eq!(inputs[0]["file"], "nope.log");
    assert_eq!(inputs[0]["error"], "No such file or directory");
    assert_eq!(inputs[1]["file"], "fixtures/stoeber.log");
    assert_eq!(inputs[1]["error"], Value::Null);
    assert!(
        !of_type(&objects, "emcy").is_empty(),
        "the other file is read"
    );
}

#[test]
fn unknown_format_is_one_error_line_and_exit_2() {
    let out = emcy_decode()
        .arg("-")
        .write_stdin("this is not a trace\nnor is this\n")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: <stdin>: cannot detect the trace format"));
    assert!(stderr.contains("--input-format"));
}

#[test]
fn asc_headers_make_unreadable_frame_lines_malformed_not_an_unknown_format() {
    // python-can's ASCWriter writes a 64-byte non-FD message as `d 40`, a
    // line no classic bus has: the file's only frame line. Its headers say
    // ASC, so the line is ASC's malformed line, with its place.
    let out = emcy_decode()
        .args(["--format", "ndjson", "-"])
        .write_stdin(
            "date Sat Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n\
             Begin Triggerblock Sat Sep 30 15:06:13.191 2017\n\
             \x20 0.000000 1  123x  Rx   d 40 00 01 02 03\nnot a line\nEnd TriggerBlock\n",
        )
        .output()
        .unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert_eq!(
        stderr,
        "<stdin>:4: DLC '40' is not a hex digit 0-F\n\
         <stdin>:5: unknown line: 'not' is neither a timestamp nor an ASC header keyword\n"
    );
    let objects = ndjson_objects(&out.stdout);
    let input = of_type(&objects, "input")[0];
    assert_eq!(input["format"], "asc");
    assert_eq!(
        (input["frames"].as_u64(), input["malformed"].as_u64()),
        (Some(0), Some(2))
    );
    // Malformed all the same: --strict fails.
    emcy_decode()
        .args(["--strict", "fixtures/no-frame.asc"])
        .assert()
        .code(2);
    // A `date` line alone does not make a file ASC (a pasted shell `date`).
    emcy_decode()
        .arg("-")
        .write_stdin("date Sat Sep 30 15:06:13 UTC 2017\nnor is this\n")
        .assert()
        .code(2)
        .stderr(predicate::str::contains("cannot detect the trace format"));
}

#[test]
fn a_canfd_line_read_against_its_flags_is_a_warning_not_malformed() {
    emcy_decode()
        .args(["--strict", "fixtures/canfd-no-fdf.asc"])
        .assert()
        .code(0)
        .stderr(predicate::str::contains(
            "fixtures/canfd-no-fdf.asc:8: CANFD line: flags 0 lack FDF 1000 but 64 data bytes",
        ));
}

#[test]
fn strict_makes_malformed_lines_exit_2() {
    // edge.log contains one malformed line and one 2-byte EMCY.
    emcy_decode().arg("fixtures/edge.log").assert().code(0);
    emcy_decode()
        .args(["--strict", "fixtures/edge.log"])
        .assert()
        .code(2);
    emcy_decode()
        .args(["--strict", "fixtures/stoeber.log"])
        .assert()
        .code(0);
}

#[test]
fn fail_on_code_fails_only_for_the_listed_codes() {
    // stoeber raises 0x4310 only.
    emcy_decode()
        .args(["--fail-on", "code=0x4310", "fixtures/stoeber.log"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "fail-on: code=0x4310: raised 1 time",
        ));
    emcy_decode()
        .args(["--fail-on", "code=0x2310,8611", "fixtures/stoeber.log"])
        .assert()
        .code(0)
        .stderr("");
}

#[test]
fn fail_on_warning_needs_a_warned_frame_of_a_selected_node() {
    // festo's node 5 sends 0x4310 with a non-zero byte 6: no CiA 402
    // warning, but the Festo profile (chosen by the trace's vendor id) says
    // bytes 3-7 are zero.
    emcy_decode()
        .args([
            "--fail-on",
            "warning",
            "--profile",
            "cia402",
            "fixtures/festo.log",
        ])
        .assert()
        .code(0);
    emcy_decode()
        .args(["--fail-on", "warning", "fixtures/festo.log"])
        .assert()
        .code(1)
        .stderr(predicates::str::contains(
            "fail-on: warning: 1 EMCY frame with warnings",
        ));
    // edge.log's nodes warn (short frame, reserved bit, ...).
    emcy_decode()
        .args(["--fail-on", "warning", "fixtures/edge.log"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("fail-on: warning: "));
    // Node 1 on can0 warns about nothing.
    emcy_decode()
        .args(["--fail-on", "warning", "--node", "1", "--channel", "can0"])
        .arg("fixtures/edge.log")
        .assert()
        .code(0);
}

#[test]
fn fail_on_conditions_combine_and_each_met_one_is_named() {
    let out = emcy_decode()
        .args(["--fail-on", "active,code=0x5111", "--fail-on", "any"])
        .arg("fixtures/s300.log")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(
        stderr,
        "fail-on: any: 4 error EMCY frames\n\
         fail-on: active: 1 node ends with an active error\n\
         fail-on: code=0x5111: raised 1 time\n"
    );
}

#[test]
fn fail_on_rejects_unknown_conditions_with_exit_2() {
    emcy_decode()
        .args(["--fail-on", "sometimes", "fixtures/s300.log"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("not a condition"));
}

#[test]
fn summary_view_prints_no_events_in_any_format() {
    let table = emcy_decode()
        .args(["--view", "summary", "fixtures/s300.log"])
        .output()
        .unwrap();
    let text = String::from_utf8(table.stdout).unwrap();
    assert!(!text.contains("TR = transition"), "{text}");
    assert!(!text.contains("Error timeline"), "{text}");
    assert!(
        text.contains("0x3120 x1, 0x4210 x1, 0x4310 x1, 0x5111 x1"),
        "{text}"
    );
    assert!(text.contains("bus: 19 frames, 7 EMCY"), "{text}");

    let nd = emcy_decode()
        .args([
            "--view",
            "summary",
            "--format",
            "ndjson",
            "fixtures/s300.log",
        ])
        .output()
        .unwrap();
    let objects = ndjson_objects(&nd.stdout);
    assert!(of_type(&objects, "emcy").is_empty());
    assert!(of_type(&objects, "boot").is_empty());
    let node = of_type(&objects, "node")[0];
    assert_eq!(node["errors_seen"]["0x4310"], 1);
    assert_eq!(node["longest_error"]["code"], "0x4310");
    // In error 1.25-4.0, 5.0-6.0 (boot) and from 7.0 to the last frame
    // (the PDO at 7.1, which nothing decodes but still ends the input).
    assert_eq!(node["time_in_error"].as_f64(), Some(3.85));

    let json = emcy_decode()
        .args(["--view", "summary", "--format", "json", "fixtures/s300.log"])
        .output()
        .unwrap();
    let doc: Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(doc["events"].as_array().map(Vec::len), Some(0));
    assert_eq!(doc["nodes"].as_array().map(Vec::len), Some(1));
}

#[test]
fn errors_outrank_fail_on() {
    emcy_decode()
        .args(["--strict", "--fail-on", "any", "fixtures/edge.log"])
        .assert()
        .code(2);
}

#[test]
fn usage_errors_exit_2() {
    emcy_decode().arg("--format=xml").assert().code(2);
    emcy_decode().args(["--node", "0"]).assert().code(2);
    emcy_decode().args(["--node", "65536"]).assert().code(2);
    emcy_decode().arg("--no-such-flag").assert().code(2);
}

#[test]
fn help_documents_exit_codes_and_examples() {
    emcy_decode()
        .arg("--help")
        .assert()
        .code(0)
        .stdout(predicate::str::contains("Exit status:"))
        .stdout(predicate::str::contains(
            "1  the --fail-on condition was met",
        ))
        .stdout(predicate::str::contains("emcy-decode explain 4310"));
}

#[test]
fn short_help_is_brief_and_long_help_complete_both_grouped() {
    let run = |flag: &str| {
        let out = emcy_decode().arg(flag).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{flag}");
        String::from_utf8(out.stdout).unwrap()
    };
    let short = run("-h");
    let long = run("--help");
    for heading in [
        "Input options:",
        "Decoding options:",
        "Output options:",
        "CI options:",
        "Performance options:",
    ] {
        assert!(short.contains(heading), "-h lacks {heading}:\n{short}");
        assert!(long.contains(heading), "--help lacks {heading}");
    }
    // Headings in the order a reader needs them.
    let at = |h: &str| short.find(h).unwrap();
    assert!(at("Input options:") < at("Decoding options:"));
    assert!(at("Decoding options:") < at("Output options:"));
    assert!(at("Output options:") < at("CI options:"));
    assert!(at("CI options:") < at("Performance options:"));
    assert!(
        !short.contains("Examples:"),
        "-h repeats the examples:\n{short}"
    );
    assert!(short.contains("Exit status: 0"), "-h names the exit codes");
    assert!(long.contains("Examples:") && long.contains("Formats read"));
    // -h gives each option its summary, --help the details too.
    assert!(!short.contains("more than 4 per core"));
    assert!(long.contains("more than 4 per core"));
    assert!(short.lines().count() * 2 < long.lines().count());
}

/// The help text's sections by heading (`Options:`, `Input options:`...):
/// each heading with the lines below it up to the next heading.
fn help_sections(help: &str) -> Vec<(String, String)> {
    let mut sections: Vec<(String, String)> = Vec::new();
    for line in help.lines() {
        if !line.starts_with(' ') && line.ends_with(':') {
            sections.push((line.to_string(), String::new()));
        } else if let Some((_, body)) = sections.last_mut() {
            body.push_str(line);
            body.push('\n');
        }
    }
    sections
}

#[test]
fn short_help_names_every_fail_on_condition() {
    let out = emcy_decode().arg("-h").output().unwrap();
    let short = String::from_utf8(out.stdout).unwrap();
    // The option's line and the lines its summary wraps to.
    let line: String = short
        .lines()
        .skip_while(|l| !l.contains("--fail-on"))
        .enumerate()
        .take_while(|(i, l)| *i == 0 || !l.trim_start().starts_with('-'))
        .map(|(_, l)| l.trim())
        .collect::<Vec<_>>()
        .join(" ");
    assert!(line.contains("--fail-on"), "-h lists --fail-on:\n{short}");
    for condition in [
        "any",
        "active",
        "warning",
        "lost",
        "fault",
        "code=",
        "category<=",
        "never",
    ] {
        assert!(
            line.contains(condition),
            "-h --fail-on lacks {condition}: {line}"
        );
    }
}

#[test]
fn long_help_and_man_page_name_the_environment_variables() {
    let out = emcy_decode().arg("--help").output().unwrap();
    let long = String::from_utf8(out.stdout).unwrap();
    let sections = help_sections(&long);
    let (_, environment) = sections
        .iter()
        .find(|(heading, _)| heading == "Environment:")
        .unwrap_or_else(|| panic!("--help has no Environment section:\n{long}"));
    let man = emcy_decode().arg("man").output().unwrap();
    let man = String::from_utf8(man.stdout).unwrap();
    assert!(man.contains(".SH ENVIRONMENT"), "{man}");
    for variable in ["NO_COLOR", "TERM", "COLUMNS", "CI", "TZ"] {
        assert!(
            environment
                .lines()
                .any(|l| l.trim_start().starts_with(&format!("{variable} "))),
            "--help Environment lacks {variable}:\n{environment}"
        );
        assert!(
            man.contains(&format!("\n{variable} ")),
            "man lacks {variable}"
        );
    }
}

#[test]
fn check_help_puts_every_option_under_a_heading() {
    for flag in ["-h", "--help"] {
        let out = emcy_decode().args(["check", flag]).output().unwrap();
        let help = String::from_utf8(out.stdout).unwrap();
        let sections = help_sections(&help);
        let plain = sections
            .iter()
            .find(|(heading, _)| heading == "Options:")
            .map(|(_, body)| body.as_str())
            .unwrap_or_default();
        for option in [
            "--heartbeat-timeout",
            "--recursive",
            "--glob",
            "--follow-links",
            "--root",
            "--only-given",
        ] {
            assert!(
                !plain.contains(option),
                "check {flag} leaves {option} under plain Options:\n{plain}"
            );
            assert!(help.contains(option), "check {flag} lacks {option}");
        }
        // What is left under the plain heading is help and version only.
        assert!(!plain.contains("--baseline") && !plain.contains("--profile"));
    }
}

#[test]
fn bash_completes_profile_names_after_profile() {
    let out = emcy_decode()
        .args(["completions", "bash"])
        .output()
        .unwrap();
    let script = String::from_utf8(out.stdout).unwrap();
    // Every `--profile)` case of the script (decode, explain, baseline,
    // check) offers the built-in names, not `compgen -f` (file names).
    let cases: Vec<&str> = script
        .split("--profile)")
        .skip(1)
        .map(|rest| rest.split(";;").next().unwrap_or_default())
        .collect();
    assert!(cases.len() >= 4, "{} --profile cases", cases.len());
    for case in cases {
        assert!(
            case.contains("compgen -W \"cia301 cia402 kollmorgen"),
            "--profile completes no profile names:\n{case}"
        );
        assert!(!case.contains("compgen -f"), "{case}");
    }
    // The names are offered, not imposed: a user profile's name still works.
    emcy_decode()
        .args(["--profile", "nonesuch", "fixtures/s300.log"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("nonesuch"));
}

#[test]
fn man_all_writes_a_page_per_subcommand_and_man_cmd_prints_one() {
    let dir = tempfile::tempdir().unwrap();
    emcy_decode()
        .args(["man", "--all"])
        .arg(dir.path())
        .assert()
        .code(0);
    for name in [
        "emcy-decode",
        "emcy-decode-explain",
        "emcy-decode-check",
        "emcy-decode-baseline",
    ] {
        let page = std::fs::read_to_string(dir.path().join(format!("{name}.1"))).unwrap();
        assert!(page.contains(&format!("\n.TH {name} 1")), "{name}");
    }
    emcy_decode()
        .args(["man", "explain"])
        .assert()
        .code(0)
        .stdout(predicate::str::contains("\n.TH emcy-decode-explain 1"));
    emcy_decode().args(["man", "nope"]).assert().code(2);
    // A directory is created; a path through a file cannot be.
    emcy_decode()
        .args(["man", "--all"])
        .arg(dir.path().join("new/man1"))
        .assert()
        .code(0);
    assert!(dir.path().join("new/man1/emcy-decode-check.1").is_file());
    emcy_decode()
        .args(["man", "--all"])
        .arg(dir.path().join("emcy-decode.1/x"))
        .assert()
        .code(2);
}

#[test]
fn a_channel_or_node_filter_that_matches_nothing_names_what_the_input_has() {
    let stderr = |args: &[&str]| {
        let out = emcy_decode().args(args).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{args:?}");
        String::from_utf8(out.stderr).unwrap()
    };
    assert_eq!(
        stderr(&["--channel", "nope", "fixtures/s300.log"]),
        "fixtures/s300.log: --channel nope matches no channel; the channels with EMCY or \
         boot-up frames: can0\n"
    );
    assert_eq!(
        stderr(&["--node", "9,10", "fixtures/festo.asc"]),
        "fixtures/festo.asc: --node 9,10 matches no node; the nodes that sent EMCY or \
         boot-up frames: 5\n"
    );
    // Each input read side by side says it too.
    let both = stderr(&["--node", "9", "fixtures/s300.log", "fixtures/festo.asc"]);
    assert!(
        both.contains("fixtures/s300.log: --node 9 matches no node"),
        "{both}"
    );
    assert!(
        both.contains("fixtures/festo.asc: --node 9 matches no node"),
        "{both}"
    );
    // A filter that matches says nothing; nor does one in an input without nodes.
    assert_eq!(
        stderr(&["--node", "1", "--channel", "can0", "fixtures/s300.log"]),
        ""
    );
    let quiet = emcy_decode()
        .args(["--node", "9", "-"])
        .write_stdin("(1.0) can0 181#05\n")
        .output()
        .unwrap();
    assert_eq!(String::from_utf8(quiet.stderr).unwrap(), "");
}

#[test]
fn dropcount_lines_are_counted_as_dropped_frames_and_warned_about() {
    let trace = "(1.0) can0 081#1043090000000000\n\
                 DROPCOUNT: dropped 3 CAN frames on 'can0' socket (total drops 3)\n\
                 (2.0) can0 081#0000000000000000\n\
                 DROPCOUNT: dropped 1 CAN frame on 'can0' socket (total drops 4)\n";
    for threads in ["1", "2"] {
        let out = emcy_decode()
            .args(["-f", "ndjson", "-j", threads, "-"])
            .write_stdin(trace)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
        let input: Value = String::from_utf8(out.stdout)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str::<Value>(l).unwrap())
            .find(|o| o["type"] == "input")
            .unwrap();
        assert_eq!(input["dropped"], 4, "-j {threads}: the sum, not the total");
        assert_eq!(input["skipped"], 2, "the lines stay skipped lines");
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(
            stderr,
            "<stdin>: warning: candump reported 4 frames dropped by the kernel (DROPCOUNT \
             lines): EMCYs may be missing\n"
        );
    }
    emcy_decode()
        .arg("-")
        .write_stdin(trace)
        .assert()
        .stdout(predicate::str::contains(
            ", 4 frames dropped (DROPCOUNT): EMCYs may be missing\n",
        ));
    // Without drops, no key.
    let out = emcy_decode()
        .args(["-f", "ndjson", "fixtures/s300.log"])
        .output()
        .unwrap();
    assert!(!String::from_utf8(out.stdout).unwrap().contains("dropped"));
}

#[test]
fn local_times_in_the_tz_zone_or_the_system_one() {
    let third_line = |args: &[&str], tz: Option<&str>| {
        let mut cmd = emcy_decode();
        if let Some(tz) = tz {
            cmd.env("TZ", tz);
        }
        let out = cmd.args(args).arg("fixtures/s300.log").output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{args:?}");
        let text = String::from_utf8(out.stdout).unwrap();
        text.lines()
            .find(|l| l.contains(" 0x4310 "))
            .unwrap()
            .split_whitespace()
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(
        third_line(&["--tz", "Europe/Berlin"], None),
        "2023-11-14T23:13:21.250000+01:00"
    );
    assert_eq!(
        third_line(&["--time", "local"], Some("America/New_York")),
        "2023-11-14T17:13:21.250000-05:00"
    );
    assert_eq!(
        third_line(
            &["--time", "local", "--tz", "UTC"],
            Some("America/New_York")
        ),
        "2023-11-14T22:13:21.250000+00:00",
        "--tz wins over TZ"
    );
    emcy_decode()
        .args(["--tz", "Mars/Olympus", "fixtures/s300.log"])
        .assert()
        .code(2)
        .stdout("")
        .stderr(predicate::str::contains("--tz Mars/Olympus"));
    emcy_decode()
        .args(["--tz", "UTC", "--time", "relative", "fixtures/s300.log"])
        .assert()
        .code(2);
}

// ---- inputs ----------------------------------------------------------------------

#[test]
fn stdin_by_dash_and_by_default() {
    let trace = std::fs::read("fixtures/s300.log").unwrap();
    for args in [
        &["--format", "ndjson", "-"][..],
        &["--format", "ndjson"][..],
    ] {
        let out = emcy_decode()
            .args(args)
            .write_stdin(trace.clone())
            .output()
            .unwrap();
        let objects = ndjson_objects(&out.stdout);
        assert_eq!(of_type(&objects, "emcy").len(), 7);
        assert_eq!(of_type(&objects, "input")[0]["file"], "<stdin>");
    }
}

#[test]
fn gzip_on_stdin_is_decompressed() {
    let gz = std::fs::read("fixtures/s300.log.gz").unwrap();
    let out = emcy_decode()
        .args(["--format", "ndjson", "-"])
        .write_stdin(gz)
        .output()
        .unwrap();
    let objects = ndjson_objects(&out.stdout);
    assert_eq!(of_type(&objects, "emcy").len(), 7);
    assert_eq!(of_type(&objects, "input")[0]["gzip"], true);
}

#[test]
fn input_format_can_be_forced() {
    // A candump log read as ASC is all malformed, and that is what was asked.
    let out = emcy_decode()
        .args([
            "--format",
            "ndjson",
            "--input-format",
            "asc",
            "fixtures/stoeber.log",
        ])
        .output()
        .unwrap();
    let objects = ndjson_objects(&out.stdout);
    let input = of_type(&objects, "input")[0];
    assert_eq!(input["format"], "asc");
    assert_eq!(input["frames"], 0);
    assert_eq!(input["malformed"], input["lines"]);
    // The right forced format reads it.
    let out = emcy_decode()
        .args([
            "--format",
            "ndjson",
            "--input-format",
            "candump",
            "fixtures/stoeber.log",
        ])
        .output()
        .unwrap();
    assert_eq!(of_type(&ndjson_objects(&out.stdout), "emcy").len(), 2);
}

#[test]
fn malformed_lines_are_reported_with_file_and_line_then_counted() {
    let trace = "(1.0) can0 081#1043090100000000\nnot a frame\n(2.0) can0 081#00\n(3.0) can0 081#0000000000000000\n";
    let out = emcy_decode()
        .args(["--format", "ndjson", "-"])
        .write_stdin(trace)
        .output()
        .unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(
        stderr,
        "<stdin>:2: expected '(' and a timestamp at the start of the line\n\
         <stdin>:3: node 1: EMCY frame has 1 data byte; code and error register need 3\n"
    );
    let objects = ndjson_objects(&out.stdout);
    let input = of_type(&objects, "input")[0];
    assert_eq!(input["lines"], 4);
    assert_eq!(input["frames"], 3);
    assert_eq!(input["malformed"], 1);
    assert_eq!(input["emcy"], 2);
    assert_eq!(input["emcy_invalid"], 1);
    // The valid EMCY after the garbage was decoded and reset the error.
    let emcy = of_type(&objects, "emcy");
    assert_eq!(emcy[1]["transition"], 4);
}

// ---- filters ----------------------------------------------------------------------

#[test]
fn node_filter_accepts_lists_and_repeats() {
    for args in [
        &["--node", "1,3"][..],
        &["--node", "1", "--node", "3"][..],
        &["--node", "0x01,0x03"][..],
    ] {
        let out = emcy_decode()
            .args(["--format", "ndjson"])
            .args(args)
            .arg("fixtures/edge.log")
            .output()
            .unwrap();
        let objects = ndjson_objects(&out.stdout);
        // Inputs and their channels are no node's: they stay whole.
        for o in objects
            .iter()
            .filter(|o| o["type"] != "input" && o["type"] != "channel")
        {
            // The bus's own events (the logging controller's) concern every
            // node and stay.
            if o["node"].is_null() && o["type"] == "bus_error" {
                continue;
            }
            // An incident is shown whole when one of its nodes is selected.
            if o["type"] == "incident" {
                let nodes: Vec<u64> = o["nodes"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|n| n.as_u64().unwrap())
                    .collect();
                assert!(nodes.contains(&1) || nodes.contains(&3), "{o}");
                continue;
            }
            let node = o["node"].as_u64().unwrap();
            assert!(node == 1 || node == 3, "{o}");
        }
        assert!(!of_type(&objects, "emcy").is_empty());
    }
}

#[test]
fn channel_filter() {
    let out = emcy_decode()
        .args([
            "--format",
            "ndjson",
            "--channel",
            "can10",
            "fixtures/edge.log",
        ])
        .output()
        .unwrap();
    let objects = ndjson_objects(&out.stdout);
    let events = of_type(&objects, "emcy");
    assert_eq!(events.len(), 2);
    assert!(events.iter().all(|e| e["channel"] == "can10"));
}

// ---- output ------------------------------------------------------------------------

#[test]
fn json_is_one_document_with_the_four_arrays() {
    let out = emcy_decode()
        .args(["--format", "json", "fixtures/s300.log"])
        .output()
        .unwrap();
    let doc: Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
    for key in ["inputs", "events", "nodes", "diagnostics"] {
        assert!(doc[key].is_array(), "{key}");
    }
    // 7 EMCY and 2 boot-ups, the NMT state changes the heartbeats show,
    // and the two incidents the errors make (node 1's, 4 s apart).
    let events = doc["events"].as_array().unwrap();
    let of = |t: &str| events.iter().filter(|e| e["type"] == t).count();
    assert_eq!((of("emcy"), of("boot"), of("incident")), (7, 2, 2));
    // And the master's reads of node 1's device type and vendor id.
    assert_eq!(of("sdo"), 2);
    assert_eq!(of("nmt") + 13, events.len());
}

#[test]
fn times_are_exact_json_numbers() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "-"])
        .write_stdin("(1700000000.123456789) can0 081#1043090100000000\n")
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("\"time\":1700000000.123456789,"), "{text}");
}

#[test]
fn table_has_no_colour_unless_asked() {
    emcy_decode()
        .arg("fixtures/s300.log")
        .assert()
        .stdout(predicate::str::contains("\u{1b}[").not());
    emcy_decode()
        .args(["--color", "always", "fixtures/s300.log"])
        .assert()
        .stdout(predicate::str::contains("\u{1b}["));
}

/// At a terminal (a pseudo-terminal from util-linux's `script`; skipped
/// where it is missing), auto colour is on unless `TERM` is `dumb`.
#[test]
fn a_dumb_terminal_gets_no_colour() {
    let binary = assert_cmd::cargo::cargo_bin("emcy-decode");
    let at_terminal = |term: &str| {
        let command = format!("{} fixtures/s300.log", binary.display());
        std::process::Command::new("script")
            .args(["-qc", &command, "/dev/null"])
            .env("TERM", term)
            .env_remove("NO_COLOR")
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
    };
    let Some(xterm) = at_terminal("xterm") else {
        eprintln!("skipped: no `script` to run the program at a terminal");
        return;
    };
    assert!(
        xterm.contains("\u{1b}["),
        "a terminal is coloured:\n{xterm}"
    );
    let dumb = at_terminal("dumb").expect("script ran once");
    assert!(!dumb.contains("\u{1b}["), "TERM=dumb is coloured:\n{dumb}");
    assert!(dumb.contains("0x4310"));
}

#[test]
fn ndjson_order_is_events_then_nodes_then_inputs() {
    let out = emcy_decode()
        .args([
            "--format",
            "ndjson",
            "fixtures/s300.log",
            "fixtures/festo.log",
        ])
        .output()
        .unwrap();
    let kinds: Vec<String> = ndjson_objects(&out.stdout)
        .iter()
        .map(|o| o["type"].as_str().unwrap().to_string())
        .collect();
    let rank = |k: &str| match k {
        "emcy"
        | "boot"
        | "nmt"
        | "heartbeat_lost"
        | "heartbeat_back"
        | "sdo_abort"
        | "sdo"
        | "error_history"
        | "error_history_cleared"
        | "incident" => 0,
        "node" => 1,
        // Each input's channels come right before it.
        "channel" | "input" => 2,
        other => panic!("unknown type {other}"),
    };
    assert!(
        kinds.windows(2).all(|w| rank(&w[0]) <= rank(&w[1])),
        "{kinds:?}"
    );
    assert_eq!(kinds.iter().filter(|k| *k == "input").count(), 2);
}

// ---- explain -------------------------------------------------------------------------

#[test]
fn explain_code() {
    for code in ["4310", "0x4310", "0X4310"] {
        emcy_decode()
            .args(["explain", code])
            .assert()
            .code(0)
            .stdout(predicate::str::contains(
                "description  Temperature · drive · excess temperature drive",
            ))
            .stdout(predicate::str::contains("register     bit 3 (temperature)"));
    }
    emcy_decode()
        .args(["explain", "xyz"])
        .assert()
        .code(2)
        .stderr(predicate::str::starts_with(
            "error: 'xyz' is not an error code",
        ));
}

#[test]
fn explain_data() {
    emcy_decode()
        .args(["explain", "--data", "10 43 09 01 00 00 00 00"])
        .assert()
        .code(0)
        .stdout(predicate::eq(
            "data          10 43 09 01 00 00 00 00\n\
             profile       cia402\n\
             code          0x4310\n\
             class         temperature\n\
             description   Temperature · drive · excess temperature drive\n\
             register      0x09 (generic, temperature)\n\
             manufacturer  01 00 00 00 00\n\
             warnings      none\n",
        ));
    let out = emcy_decode()
        .args(["explain", "--format", "json", "--data", "1043080100000000"])
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["code"], "0x4310");
    assert_eq!(
        v["warnings"][0].as_str().unwrap().split(':').next(),
        Some("no_generic_bit")
    );
    emcy_decode()
        .args(["explain", "--data", "10 43"])
        .assert()
        .code(2);
    // A profile's field names longer than the column keep a blank after
    // them (`category_text` ran into its value).
    emcy_decode()
        .args([
            "explain",
            "--profile",
            "kollmorgen",
            "--data",
            "1043080100000000",
        ])
        .assert()
        .code(0)
        .stdout(predicate::str::contains(
            "manufacturer  01 00 00 00 00\n  \
             category      1\n  \
             category_text cleared only by a reset",
        ));
}

#[test]
fn events_from_a_pipe_arrive_before_the_writer_finishes() {
    // `candump -L can0 | emcy-decode --format ndjson -`: the event must be
    // printed while stdin is still open.
    use std::io::BufRead;
    let mut child = binary()
        .args(["--format", "ndjson", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut lines = std::io::BufReader::new(stdout).lines();
        while let Some(Ok(line)) = lines.next() {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    stdin
        .write_all(b"(1.0) can0 081#1043090100000000\n")
        .unwrap();
    stdin.flush().unwrap();
    let first = rx
        .recv_timeout(std::time::Duration::from_secs(30))
        .expect("the event arrived while stdin was still open");
    let v: Value = serde_json::from_str(&first).unwrap();
    assert_eq!(v["code"], "0x4310");
    drop(stdin);
    assert!(child.wait().unwrap().success());
}

// ---- EMCY ids other than 0x80 + node ---------------------------------------------

#[test]
fn emcy_id_flag_decodes_a_moved_id_from_the_first_line() {
    // Without the flag, the frame on 0x3F5 before the SDO write is a plain frame.
    let plain = emcy_decode()
        .args(["--format", "ndjson", "fixtures/sdo-emcy-id.log"])
        .output()
        .unwrap();
    let objects = ndjson_objects(&plain.stdout);
    assert_eq!(of_type(&objects, "emcy").len(), 3);

    let mapped = emcy_decode()
        .args([
            "--format",
            "ndjson",
            "--emcy-id",
            "0x3F5=5",
            "--emcy-id",
            "00000106=6",
            "fixtures/sdo-emcy-id.log",
        ])
        .output()
        .unwrap();
    assert_eq!(mapped.status.code(), Some(0));
    let objects = ndjson_objects(&mapped.stdout);
    let emcy = of_type(&objects, "emcy");
    let lines: Vec<(i64, i64)> = emcy
        .iter()
        .map(|e| (e["line"].as_i64().unwrap(), e["node"].as_i64().unwrap()))
        .collect();
    // Line 2 (before the write) and line 10 (the extended id of node 6) now count.
    assert_eq!(lines, [(2, 5), (7, 5), (10, 6), (11, 5), (12, 5)]);
}

/// Frames on the heartbeat and SDO ids are only timed unless they
/// can matter; an EMCY id given there makes every frame on it matter.
#[test]
fn emcy_id_on_a_heartbeat_id_decodes_every_frame_on_it() {
    let trace = "(1.000000) can0 705#1043090100000000\n(2.000000) can0 705#05\n\
                 (3.000000) can0 706#05\n";
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("heartbeat-id.log");
    std::fs::write(&path, trace).unwrap();
    for threads in ["1", "2"] {
        let out = emcy_decode()
            .args(["--emcy-id", "0x705=5", "--format", "ndjson", "-j", threads])
            .arg(&path)
            .output()
            .unwrap();
        let objects = ndjson_objects(&out.stdout);
        assert_eq!(of_type(&objects, "emcy").len(), 1);
        let input = of_type(&objects, "input")[0];
        assert_eq!(
            (input["frames"].as_u64(), input["emcy_invalid"].as_u64()),
            (Some(3), Some(1))
        );
        assert_eq!(
            input["last_time"].as_f64(),
            Some(3.0),
            "the heartbeat of node 6 is timed"
        );
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(":2: node 5: EMCY frame has 1 data byte")
        );
    }
}

#[test]
fn emcy_id_flag_rejects_nonsense_with_exit_2() {
    emcy_decode()
        .args(["--emcy-id", "0x3F5", "fixtures/s300.log"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--emcy-id"));
}

// ---- vendor profiles ----------------------------------------------------------------

fn node_object(args: &[&str]) -> Value {
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .args(args)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{args:?}");
    let objects = ndjson_objects(&out.stdout);
    of_type(&objects, "node")[0].clone()
}

#[test]
fn profiles_lists_every_builtin_once_with_the_default_marked() {
    let out = emcy_decode().arg("profiles").output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).unwrap();
    let names: Vec<&str> = text
        .lines()
        .map(|l| l.split_whitespace().next().unwrap_or_default())
        .collect();
    assert_eq!(
        names,
        [
            "cia301",
            "cia402",
            "kollmorgen",
            "beckhoff-ax2000",
            "stoeber",
            "festo-cmmp",
            "canopennode"
        ]
    );
    assert!(
        text.lines()
            .any(|l| l.starts_with("cia402") && l.ends_with("(default)"))
    );
    assert!(
        text.lines().all(|l| l.matches("(default)").count() <= 1),
        "a line says (default) twice:\n{text}"
    );
}

#[test]
fn the_trace_identity_chooses_the_profile_and_says_why() {
    let node = node_object(&["fixtures/s300.log"]);
    assert_eq!(node["profile"], "kollmorgen");
    assert_eq!(node["profile_source"], "trace");
    assert!(
        node["profile_reason"]
            .as_str()
            .is_some_and(|r| r.contains("0x0000006A")),
        "{node}"
    );
    // The same trace without its SDO answers: the default.
    let no_sdo: String = std::fs::read_to_string("fixtures/s300.log")
        .unwrap()
        .lines()
        .filter(|l| !l.contains(" 58") && !l.contains(" 60"))
        .map(|l| format!("{l}\n"))
        .collect();
    let out = emcy_decode()
        .args(["--format", "ndjson", "-"])
        .write_stdin(no_sdo)
        .output()
        .unwrap();
    let objects = ndjson_objects(&out.stdout);
    let node = of_type(&objects, "node")[0];
    assert_eq!(node["profile"], "cia402");
    assert_eq!(node["profile_source"], "default");
    assert_eq!(node["profile_reason"], Value::Null);
}

#[test]
fn profile_flags_override_the_trace_node_flag_first() {
    let node = node_object(&["--profile", "cia301", "fixtures/s300.log"]);
    assert_eq!(
        (node["profile"].clone(), node["profile_source"].clone()),
        ("cia301".into(), "flag".into())
    );
    let node = node_object(&[
        "--profile",
        "cia301",
        "--profile",
        "1=stoeber",
        "fixtures/s300.log",
    ]);
    assert_eq!(node["profile"], "stoeber");
}

#[test]
fn kollmorgen_category_is_decoded_and_fails_category_bounds() {
    let out = emcy_decode()
        .args(["--format", "ndjson", "fixtures/s300.log"])
        .output()
        .unwrap();
    let objects = ndjson_objects(&out.stdout);
    let first = of_type(&objects, "emcy")[0];
    assert_eq!(first["code"], "0x4310");
    assert_eq!(first["manufacturer_decoded"]["category"], 1);
    assert_eq!(first["profile_source"], "trace");
    emcy_decode()
        .args(["--fail-on", "category<=1", "fixtures/s300.log"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "category<=1: an error of category 1",
        ));
    emcy_decode()
        .args(["--fail-on", "category<=0", "fixtures/s300.log"])
        .assert()
        .code(0)
        .stderr(predicate::str::contains("never").not());
    // A bound no node's profile can meet passes, but not silently.
    emcy_decode()
        .args(["--fail-on", "category<=1", "fixtures/festo.log"])
        .assert()
        .code(0)
        .stderr(predicate::str::contains(
            "fail-on: category<=1 can never be met: no node's profile gives error \
             categories (festo-cmmp)",
        ));
}

#[test]
fn unknown_profiles_and_broken_profile_files_exit_2_with_one_line() {
    emcy_decode()
        .args(["--profile", "5=nope", "fixtures/s300.log"])
        .assert()
        .code(2)
        .stdout("")
        .stderr(predicate::str::starts_with("error: unknown profile 'nope'"));
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "name = \"x\"\nbase = \"cia402\"\n[codes\n").unwrap();
    let out = emcy_decode()
        .arg("--profile-file")
        .arg(&bad)
        .arg("fixtures/s300.log")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(
        stderr.contains("bad.toml:3"),
        "names file and line: {stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

#[test]
fn explain_reads_a_payload_with_a_profile() {
    let out = emcy_decode()
        .args(["explain", "--profile", "stoeber", "--format", "json"])
        .args(["--data", "10 43 01 29 00 00 00 00"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["profile"], "stoeber");
    assert_eq!(v["manufacturer_decoded"]["event"], 41);
    emcy_decode()
        .args(["explain", "--profile", "kollmorgen", "4310"])
        .assert()
        .code(0)
        .stdout(predicate::str::contains("F06"));
    emcy_decode()
        .args(["explain", "--profile", "nope", "4310"])
        .assert()
        .code(2);
}

/// A node with megabytes of errors is written in pieces; the pieces must
/// still make one valid object, the same in ndjson and the JSON document.
#[test]
fn a_node_with_many_errors_is_one_valid_object_in_both_json_formats() {
    let mut trace = String::new();
    for i in 0..6000u32 {
        let data = if i % 2 == 0 {
            "1043090000000000"
        } else {
            "0000000000000000"
        };
        trace.push_str(&format!(
            "({}.{:06}) can0 085#{data}\n",
            1_700_000_000 + i / 10,
            i
        ));
    }
    let nd = emcy_decode()
        .args(["--format", "ndjson", "--view", "summary", "-"])
        .write_stdin(trace.clone())
        .output()
        .unwrap();
    let objects = ndjson_objects(&nd.stdout);
    let node = of_type(&objects, "node")[0].clone();
    assert_eq!(node["errors"].as_array().map(Vec::len), Some(3000));
    let doc = emcy_decode()
        .args(["--format", "json", "-"])
        .write_stdin(trace)
        .output()
        .unwrap();
    let doc: Value = serde_json::from_slice(&doc.stdout).expect("one valid document");
    assert_eq!(doc["nodes"][0], node);
}

// ---- threads (-j) ----------------------------------------------------------------

/// `-j 40000` once ended in a panic when a thread could not be
/// started, `-j 18446744073709551615` grew for minutes. Absurd counts are a
/// usage error; large plausible ones are cut to 4 per core (the report is
/// the same whatever the count).
#[test]
fn absurd_thread_counts_are_a_usage_error() {
    for n in [
        "1025",
        "40000",
        "18446744073709551615",
        "18446744073709551616",
    ] {
        emcy_decode()
            .args(["-j", n, "fixtures/s300.log.gz"])
            .assert()
            .code(2)
            .stdout("")
            .stderr(predicate::str::contains("--threads").and(predicate::str::contains(n)));
    }
}

#[test]
fn large_thread_counts_give_the_report_of_one_thread() {
    let run = |j: &str| {
        let out = emcy_decode()
            .args(["-j", j, "--format", "ndjson", "fixtures/s300.log.gz"])
            .args(["fixtures/s300.log", "fixtures/edge.log"])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "-j {j}");
        (out.stdout, out.stderr)
    };
    let one = run("1");
    assert!(!one.0.is_empty());
    for j in ["64", "1024"] {
        assert!(run(j) == one, "-j {j}");
    }
}

/// `-q` holds when small files are read side by side (`-j 2`) as when they
/// are read one after another (`-j 1`): it was ignored, and stderr depended
/// on the thread count.
#[test]
fn quiet_is_quiet_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for i in 0..4 {
        let path = dir.path().join(format!("{i}.log"));
        std::fs::write(
            &path,
            format!(
                "(1.0) can0 081#1043090100000000\nnot a frame {i}\n(2.0) can0 081#0000000000000000\n"
            ),
        )
        .unwrap();
        files.push(path);
    }
    files.push(dir.path().join("missing.log"));
    let stderr = |j: &str| {
        let out = emcy_decode()
            .args(["-q", "-j", j])
            .args(&files)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "-j {j}: a file is missing");
        String::from_utf8(out.stderr).unwrap()
    };
    let one = stderr("1");
    assert!(one.contains("missing.log"), "error lines stay: {one}");
    assert!(!one.contains(".log:2:"), "no diagnostics with -q: {one}");
    assert_eq!(stderr("2"), one);
}

/// `profiles --toml NAME` prints a file that loads as a user profile and
/// reads every fixture's EMCYs exactly as the built-in does.
#[test]
fn profiles_toml_prints_a_user_profile_that_decodes_like_the_builtin() {
    let dir = tempfile::tempdir().unwrap();
    let names = String::from_utf8(emcy_decode().arg("profiles").output().unwrap().stdout).unwrap();
    let names: Vec<&str> = names
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert_eq!(names.len(), 7, "{names:?}");
    for name in names {
        let out = emcy_decode()
            .args(["profiles", "--toml", name])
            .output()
            .unwrap();
        assert!(out.status.success());
        let file = dir.path().join(format!("{name}.toml"));
        std::fs::write(&file, &out.stdout).unwrap();
        for trace in [
            "fixtures/stoeber.log",
            "fixtures/s300.log",
            "fixtures/festo.log",
        ] {
            let decode = |args: &[&std::ffi::OsStr]| -> Vec<serde_json::Value> {
                crate::support::ndjson(args.iter().chain([std::ffi::OsStr::new(trace)].iter()))
                    .into_iter()
                    .filter(|o| o["type"] == "emcy")
                    .map(|mut o| {
                        o.as_object_mut().unwrap().remove("profile_source");
                        o
                    })
                    .collect()
            };
            let builtin = decode(&["--profile".as_ref(), name.as_ref()]);
            let user = decode(&["--profile-file".as_ref(), file.as_os_str()]);
            assert!(!builtin.is_empty());
            assert_eq!(user, builtin, "{name} on {trace}");
        }
    }
    emcy_decode()
        .args(["profiles", "--toml", "nope"])
        .assert()
        .code(2)
        .stderr(predicates::str::contains(
            "unknown profile 'nope' (known: cia301",
        ));
}

/// `--verbose` says after each input how it was read; without it, nothing
/// of the kind; it cannot go with `--quiet`.
#[test]
fn verbose_says_how_each_input_was_read() {
    let out = emcy_decode()
        .args(["-v", "-j1", "--format", "ndjson", "fixtures/acme-servo.log"])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("fixtures/acme-servo.log: read on one thread"),
        "{err}"
    );
    let out = emcy_decode()
        .args(["-v", "-j2", "--format", "ndjson", "fixtures/acme-servo.log"])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("blocks parsed by 2 worker threads; read again in order: 0 whole, 0 from"),
        "{err}"
    );
    let out = emcy_decode()
        .args(["-j2", "--format", "ndjson", "fixtures/acme-servo.log"])
        .output()
        .expect("run");
    assert!(!String::from_utf8_lossy(&out.stderr).contains("worker"));
    emcy_decode()
        .args(["-v", "-q", "fixtures/acme-servo.log"])
        .assert()
        .code(2);
}

#[test]
fn a_node_over_127_on_a_trace_without_ethercat_is_a_usage_error() {
    let out = emcy_decode()
        .args([
            "-q",
            "--node",
            "200",
            "--fail-on",
            "any",
            "fixtures/acme-servo.log",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.starts_with("error: --node 200 is no CANopen node id (1-127)"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

#[test]
fn a_filter_that_selects_nothing_fails_a_fail_on_gate_even_with_quiet() {
    let run = |args: &[&str]| {
        let out = emcy_decode().args(args).output().unwrap();
        (out.status.code(), String::from_utf8(out.stderr).unwrap())
    };
    for filter in [["--node", "9"], ["--channel", "can7"]] {
        let mut args = vec!["-q", "--fail-on", "any", "fixtures/acme-servo.log"];
        args.extend(filter);
        let (code, stderr) = run(&args);
        assert_eq!(code, Some(2), "{args:?}");
        assert!(
            stderr.starts_with(&format!(
                "error: fixtures/acme-servo.log: {} {} matches no ",
                filter[0], filter[1]
            )),
            "{stderr}"
        );
        assert!(
            stderr.ends_with("; --fail-on checked nothing\n"),
            "{stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
    // Without -q the same one line: the input's note is in it.
    let (code, stderr) = run(&["--node", "9", "--fail-on", "any", "fixtures/acme-servo.log"]);
    assert_eq!(code, Some(2));
    assert_eq!(
        stderr,
        "error: fixtures/acme-servo.log: --node 9 matches no node; the nodes that sent EMCY \
         or boot-up frames: 7; --fail-on checked nothing\n"
    );
    // Node 7 is there: the gate decides as before (its errors fail it).
    let (code, stderr) = run(&[
        "-q",
        "--node",
        "7",
        "--fail-on",
        "any",
        "fixtures/acme-servo.log",
    ]);
    assert_eq!((code, stderr.as_str()), (Some(1), ""));
    // Without a gate a filter that matches nothing stays a note.
    let (code, _) = run(&["-q", "--node", "9", "fixtures/acme-servo.log"]);
    assert_eq!(code, Some(0));
    // A --glob that selects nothing under a directory was already an error.
    let (code, stderr) = run(&[
        "-q",
        "-r",
        "--glob",
        "*.nope",
        "--fail-on",
        "any",
        "fixtures/profiles",
    ]);
    assert_eq!(code, Some(2));
    assert!(stderr.starts_with("error: "), "{stderr}");
}

#[test]
fn an_input_that_cannot_be_read_prints_only_its_error_line_in_table_mode() {
    let dir = tempfile::tempdir().unwrap();
    let binary = dir.path().join("firmware.bin");
    std::fs::write(
        &binary,
        [0u8, 159, 146, 150, 255, 10, 1, 2, 3, 10].repeat(50),
    )
    .unwrap();
    for file in [dir.path().join("nosuch.log"), binary] {
        let out = emcy_decode().arg(&file).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{file:?}");
        assert_eq!(String::from_utf8_lossy(&out.stdout), "", "{file:?}");
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert!(stderr.starts_with("error: "), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
    // Beside a trace that was read, the Inputs table still names it.
    let out = emcy_decode()
        .arg(dir.path().join("nosuch.log"))
        .arg("fixtures/s300.log")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.contains("nosuch.log "), "{stdout}");
    // The JSON contract keeps its document with the input's error.
    let out = emcy_decode()
        .args(["-f", "json"])
        .arg(dir.path().join("nosuch.log"))
        .output()
        .unwrap();
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(doc["inputs"][0]["error"].is_string(), "{doc}");
}
