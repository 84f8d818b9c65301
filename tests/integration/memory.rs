//! Memory stays flat however long the trace: a 200 MB generated trace is
//! streamed through the binary and its peak resident size is checked. Not a
//! timing test: it passes on a slow machine too.

use std::io::{BufWriter, Write};
use std::process::Stdio;

use crate::support::binary;
use crate::support::tracegen::{TraceFormat, write_trace};

const TRACE_BYTES: u64 = 200 * 1024 * 1024;
const LIMIT_KIB: u64 = 32 * 1024;

/// Peak resident set of a live process, from /proc (Linux only).
fn peak_rss_kib(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn peak_while_streaming(args: &[&str], format: TraceFormat) -> Option<u64> {
    peak_with_emcy(args, format, TRACE_BYTES, 2)
}

/// `cmd` with `-` as its trace, spawned with a buffered writer to its
/// stdin (its output discarded).
fn reading_stdin(
    cmd: &mut std::process::Command,
) -> (std::process::Child, BufWriter<std::process::ChildStdin>) {
    let mut child = cmd
        .arg("-")
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    let stdin = child.stdin.take().expect("stdin");
    (child, BufWriter::with_capacity(1 << 20, stdin))
}

fn peak_with_emcy(
    args: &[&str],
    format: TraceFormat,
    bytes: u64,
    emcy_per_mille: u64,
) -> Option<u64> {
    let (mut child, mut writer) = reading_stdin(binary().args(args));
    let pid = child.id();
    let (lines, emcy) =
        write_trace(&mut writer, format, bytes, emcy_per_mille, 7).expect("write trace");
    writer.flush().expect("flush");
    assert!(
        lines > 1_000_000 && emcy > 1_000,
        "{lines} lines, {emcy} EMCY"
    );
    // Everything is written; the process is alive waiting for more input.
    let peak = peak_rss_kib(pid);
    drop(writer);
    assert!(child.wait().expect("wait").success());
    peak
}

#[test]
fn a_200_mb_trace_is_read_in_bounded_memory() {
    if !std::path::Path::new("/proc/self/status").exists() {
        eprintln!("skipped: no /proc to read peak memory from");
        return;
    }
    for (args, format) in [
        (
            &["--format", "ndjson", "-j", "1"][..],
            TraceFormat::CandumpLog,
        ),
        (
            &["--format", "ndjson", "-j", "2"][..],
            TraceFormat::CandumpLog,
        ),
        (&["--format", "table", "-j", "2"][..], TraceFormat::Asc),
        (&["--format", "ndjson"][..], TraceFormat::Pcapng),
        (&["--format", "ndjson"][..], TraceFormat::Mf4),
    ] {
        let peak = peak_while_streaming(args, format).expect("VmHWM readable");
        assert!(
            peak < LIMIT_KIB,
            "{args:?} {format:?}: peak RSS {peak} KiB exceeds {LIMIT_KIB} KiB"
        );
        eprintln!("{args:?} {format:?}: peak RSS {peak} KiB");
    }
}

/// A trace where 30% of the frames are EMCY closes an error on every other
/// one: the history of closed errors grows with the trace, memory must not.
#[test]
fn an_emcy_heavy_trace_keeps_its_error_history_out_of_memory() {
    if !std::path::Path::new("/proc/self/status").exists() {
        eprintln!("skipped: no /proc to read peak memory from");
        return;
    }
    for format in ["ndjson", "table", "json"] {
        let args = ["--format", format, "-j", "2"];
        let peak = peak_with_emcy(&args, TraceFormat::CandumpLog, 60 * 1024 * 1024, 300)
            .expect("VmHWM readable");
        eprintln!("{format}, 30% EMCY: peak RSS {peak} KiB");
        assert!(
            peak < LIMIT_KIB,
            "{format}: peak RSS {peak} KiB exceeds {LIMIT_KIB} KiB"
        );
    }
}

/// `check` reads a big baseline straight into its types: a 100k-trace
/// baseline (18 MB) took 265 MB through a `serde_json::Value`, 76 MB so.
/// The peak is read once the baseline is parsed: the trace on stdin is read
/// only after it, and writing 4 MB into the pipe returns only once most of
/// it has been read.
#[test]
fn check_reads_a_big_baseline_in_bounded_memory() {
    const BASELINE_LIMIT_KIB: u64 = 128 * 1024;
    if !std::path::Path::new("/proc/self/status").exists() {
        eprintln!("skipped: no /proc to read peak memory from");
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("baseline.json");
    let mut out = BufWriter::new(std::fs::File::create(&path).expect("create"));
    write!(out, "{{\"baseline_version\":1,\"traces\":{{").expect("write");
    for i in 0..100_000 {
        let nodes = if i % 5 == 0 {
            format!(
                "{{\"can0\":{{\"{}\":{{\"emcy\":4,\"errors\":{{\"0x4310\":\
                 {{\"active_at_end\":false,\"raised\":2}}}}}}}}}}",
                1 + i % 3
            )
        } else {
            "{}".to_string()
        };
        let sep = if i == 0 { "" } else { "," };
        write!(
            out,
            "{sep}\"traces/run{i:06}.log\":{{\"counts\":{{\"boot\":2,\"emcy\":5,\
             \"emcy_invalid\":0,\"frames\":7,\"lines\":9,\"malformed\":0,\
             \"other_format\":0,\"skipped\":2}},\"format\":\"candump\",\"nodes\":{nodes}}}"
        )
        .expect("write");
    }
    write!(out, "}}}}").expect("write");
    out.into_inner().expect("flush").sync_all().expect("sync");

    let (mut child, mut writer) = reading_stdin(binary().arg("check").arg("-b").arg(&path));
    let pid = child.id();
    write_trace(&mut writer, TraceFormat::CandumpLog, 4 * 1024 * 1024, 2, 7).expect("write");
    writer.flush().expect("flush");
    let peak = peak_rss_kib(pid).expect("VmHWM readable");
    drop(writer);
    // 1: every baseline trace is "not given".
    assert_eq!(child.wait().expect("wait").code(), Some(1));
    eprintln!("check with a 100k-trace baseline: peak RSS {peak} KiB");
    assert!(
        peak < BASELINE_LIMIT_KIB,
        "peak RSS {peak} KiB exceeds {BASELINE_LIMIT_KIB} KiB"
    );
}

/// A candump log naming a million channels (49 MB) under a 768 MiB
/// address-space limit: before, 1.03 GB and an abort (`memory allocation of
/// 352000000 bytes failed`, no report, no `error:` line). Now the node
/// table's bound ends reading with one `error:` line, exit 2, and the
/// report of what was read. Skipped where `prlimit` is missing.
#[test]
fn a_million_channels_end_in_an_error_and_a_report_under_a_memory_limit() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("channels.log");
    {
        let mut w = BufWriter::new(std::fs::File::create(&path).expect("create"));
        for i in 0..1_000_000u32 {
            writeln!(
                w,
                "(1700000000.{:06}) c{i:07} 081#1043080100000000",
                i % 1_000_000
            )
            .expect("write");
        }
        w.flush().expect("flush");
    }
    // The binary's neutral environment, under prlimit.
    let plain = binary();
    let mut cmd = std::process::Command::new("prlimit");
    cmd.arg(format!("--as={}", 768u64 << 20))
        .arg(plain.get_program())
        .args(plain.get_args())
        .args(["--format", "ndjson"])
        .arg(&path);
    for (key, value) in plain.get_envs() {
        match value {
            Some(v) => cmd.env(key, v),
            None => cmd.env_remove(key),
        };
    }
    let out = match cmd.output() {
        Ok(out) => out,
        Err(e) => {
            eprintln!("skipped: prlimit cannot run ({e})");
            return;
        }
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if stderr.starts_with("prlimit:") {
        eprintln!("skipped: {stderr}");
        return;
    }
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("memory allocation"), "{stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0].contains("more than 100000 nodes (pairs of channel and node id)"),
        "{stderr}"
    );
    let stdout = String::from_utf8(out.stdout).expect("utf-8");
    let input: serde_json::Value =
        serde_json::from_str(stdout.lines().last().expect("the report")).expect("JSON");
    assert_eq!(input["type"], "input");
    assert!(input["emcy"].as_u64().expect("count") > 100_000, "{input}");
}
