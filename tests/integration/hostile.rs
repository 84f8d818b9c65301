//! Hostile input, replayed through the real binary. One test (or a few) per
//! case of the issue "no panic, hang or unbounded memory on any byte sequence;
//! no EMCY lost or invented", so the list can be ticked off here:
//!
//! | case | test |
//! |---|---|
//! | random bytes | `random_bytes_never_panic_and_every_line_is_counted` |
//! | NUL bytes | `nul_bytes_are_malformed_lines_and_reading_goes_on`, `a_file_of_only_nul_bytes_is_an_unknown_format` |
//! | invalid UTF-8 | `invalid_utf8_is_read_as_bytes` |
//! | 100 MB line without a newline | `a_100_mib_line_is_skipped_in_flat_memory_and_the_next_line_is_read`, `long_lines_in_a_file_are_reported_with_file_and_line` |
//! | 10^6 hex digits after `#` | `a_million_hex_digits_after_the_hash_is_one_malformed_line`, `huge_frames_under_the_line_cap_are_malformed` |
//! | numbers overflowing u64 | `numbers_that_overflow_u64_are_malformed_never_wrapped`, `the_largest_timestamp_is_read_exactly`, `relative_asc_times_that_overflow_are_malformed` |
//! | timestamps going backwards | `timestamps_going_backwards_get_a_diagnostic_and_a_negative_duration` |
//! | truncated or corrupt gzip | `truncated_gzip_reports_what_was_read_then_exit_2`, `corrupt_gzip_reports_what_was_read_then_exit_2`, `gzip_with_a_bad_checksum_is_read_then_exit_2`, `gzip_with_trailing_garbage_is_read_then_exit_2`, `gzip_with_trailing_zero_padding_is_read_as_gzip_reads_it`, `gzip_magic_alone_is_an_error_with_a_named_file` |
//! | gzip bomb | `gzip_bomb_of_a_gib_of_zeros_streams_in_flat_memory`, `gzip_bomb_of_newlines_streams_in_flat_memory` |
//! | empty file | `empty_inputs_are_fine` |
//! | directory as FILE | `a_directory_is_an_error_and_other_files_are_still_read`, `a_directory_on_stdin_is_an_error` |
//! | FIFO/stdin closing early | `a_writer_closing_stdin_mid_line_ends_the_input_cleanly`, `a_fifo_closed_mid_line_ends_the_input_cleanly` |
//! | stdout closed early | `stdout_closed_early_is_exit_0_without_a_panic_message` |
//! | formats mixing | `every_pair_of_formats_mixes_only_with_a_warning`, `input_format_turns_mixing_off` |
//! | `forbid(unsafe_code)` | `the_library_and_the_binary_forbid_unsafe_code` |
//! | diagnostics name file:line, bounded | `every_diagnostic_names_file_and_line`, `max_diagnostics_bounds_printing_never_counting` |
//! | codes raised and never cleared | `never_cleared_codes_keep_every_event_bounded` |
//! | endless files that are no trace (`/dev/zero` as baseline, profile, DCF) | `files_that_are_no_trace_are_read_with_a_bound_in_the_error` |
//! | regressions found here | `many_distinct_channels_stay_linear_in_time_and_memory`, `channel_names_cannot_put_control_sequences_on_the_terminal`, `channel_names_that_read_the_same_are_one_channel` (fuzzing) |
//!
//! That no EMCY is lost or invented among garbage is a property test:
//! the library's `analyze::tests::conservation` (src/analyze/tests/).

use std::ffi::OsString;
use std::fs;
use std::io::{self, Read, Write};
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use crate::support::tracegen::Rng;
use crate::support::{binary, emcy_decode};
use serde_json::Value;

/// Peak resident memory the binary may reach on any streaming case. Its
/// buffers are ~0.6 MiB; a debug build runs in ~6 MiB.
const FLAT_LIMIT_KIB: u64 = 64 * 1024;

/// No case may take longer than this (a hang fails instead of blocking CI).
const TIMEOUT: Duration = Duration::from_secs(120);

const ERROR_LINE: &str = "(1.000000) can0 081#1043090100000000";
const RESET_LINE: &str = "(2.000000) can0 081#0000000000000000";

// ---- helpers ---------------------------------------------------------------------

fn ndjson(stdout: &[u8]) -> Vec<Value> {
    String::from_utf8(stdout.to_vec())
        .expect("ndjson is UTF-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("valid JSON line"))
        .collect()
}

fn of_type<'a>(objects: &'a [Value], kind: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == kind).collect()
}

/// The one input object of a single-input run, checked for the invariant
/// `lines = frames + skipped + malformed`.
fn input_of(objects: &[Value]) -> &Value {
    let inputs = of_type(objects, "input");
    assert_eq!(inputs.len(), 1, "{objects:?}");
    let input = inputs[0];
    let n = |k: &str| {
        input[k]
            .as_u64()
            .unwrap_or_else(|| panic!("{k} in {input}"))
    };
    assert_eq!(
        n("lines"),
        n("frames") + n("skipped") + n("malformed"),
        "every line is exactly one of frame, skipped, malformed: {input}"
    );
    input
}

/// Line numbers of the EMCY events.
fn emcy_lines(objects: &[Value]) -> Vec<u64> {
    of_type(objects, "emcy")
        .iter()
        .map(|e| e["line"].as_u64().unwrap())
        .collect()
}

fn assert_no_panic(stderr: &str) {
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!stderr.contains("RUST_BACKTRACE"), "{stderr}");
}

/// Runs the binary on `stdin` with ndjson output; returns (exit code, objects, stderr).
fn ndjson_run(args: &[&str], stdin: impl Into<Vec<u8>>) -> (i32, Vec<Value>, String) {
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .args(args)
        .write_stdin(stdin.into())
        .timeout(TIMEOUT)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_no_panic(&stderr);
    let code = out.status.code().expect("exited, not killed");
    (code, ndjson(&out.stdout), stderr)
}

/// A temporary directory removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!(
            "emcy-decode-hostile-{tag}-{}-{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos()
        ));
        fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

struct Measured {
    status: ExitStatus,
    stdout: Vec<u8>,
    stderr: String,
    /// Peak resident set size of the child in KiB (Linux), from `wait4`.
    peak_kib: Option<u64>,
}

type Feed = Box<dyn FnOnce(&mut dyn Write) -> io::Result<()> + Send>;

/// Runs the binary with `args`, streaming `feed` into its stdin from a thread
/// (nothing big is ever held by the test), and measures its peak memory.
fn run_measured(args: &[OsString], feed: Option<Feed>) -> Measured {
    let mut child = binary()
        .args(args)
        .stdin(if feed.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let writer = feed.map(|feed| {
        let mut stdin = child.stdin.take().unwrap();
        // A write error only means the child stopped reading; its exit says why.
        thread::spawn(move || {
            let _ = feed(&mut stdin);
        })
    });
    let stdout = drain(child.stdout.take().unwrap());
    let stderr = drain(child.stderr.take().unwrap());
    let (status, peak_kib) = wait_with_peak(&mut child);
    if let Some(w) = writer {
        w.join().unwrap();
    }
    let stderr = String::from_utf8_lossy(&stderr.join().unwrap()).into_owned();
    assert_no_panic(&stderr);
    Measured {
        status,
        stdout: stdout.join().unwrap(),
        stderr,
        peak_kib,
    }
}

fn drain(mut r: impl Read + Send + 'static) -> thread::JoinHandle<Vec<u8>> {
    thread::spawn(move || {
        let mut buf = Vec::new();
        let _ = r.read_to_end(&mut buf);
        buf
    })
}

/// Waits for the child, polling its peak resident memory (`VmHWM` in
/// /proc/<pid>/status, a high-water mark of the binary's own address space)
/// every 2 ms until it exits. (`wait4`'s `ru_maxrss` would be simpler but
/// counts the test process itself: the child is spawned from its memory.)
/// Kills the child and fails after [`TIMEOUT`].
fn wait_with_peak(child: &mut Child) -> (ExitStatus, Option<u64>) {
    let status_file = PathBuf::from(format!("/proc/{}/status", child.id()));
    let deadline = Instant::now() + TIMEOUT;
    let mut peak: Option<u64> = None;
    loop {
        // Read before reaping: the pid is still this child's.
        if let Some(kib) = vm_hwm_kib(&status_file) {
            peak = Some(peak.map_or(kib, |p| p.max(kib)));
        }
        if let Some(status) = child.try_wait().unwrap() {
            return (status, peak);
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the binary hung: killed after {TIMEOUT:?}");
        }
        thread::sleep(Duration::from_millis(2));
    }
}

/// `VmHWM:   5392 kB` -> 5392. `None` off Linux or once the child is a zombie.
fn vm_hwm_kib(status_file: &std::path::Path) -> Option<u64> {
    let text = fs::read_to_string(status_file).ok()?;
    let value = text.lines().find_map(|l| l.strip_prefix("VmHWM:"))?;
    value.trim().strip_suffix("kB")?.trim().parse().ok()
}

fn assert_flat(what: &str, peak_kib: Option<u64>) {
    if let Some(peak) = peak_kib {
        // Printed for the record (`cargo test -- --nocapture`).
        eprintln!("peak RSS for {what}: {peak} KiB");
        assert!(
            peak < FLAT_LIMIT_KIB,
            "{what}: peak RSS {peak} KiB, limit {FLAT_LIMIT_KIB} KiB"
        );
    }
}

fn os(args: &[&str]) -> Vec<OsString> {
    args.iter().map(OsString::from).collect()
}

/// Writes `n` bytes of `byte` in 1 MiB pieces.
fn write_repeated(w: &mut dyn Write, byte: u8, n: usize) -> io::Result<()> {
    let chunk = vec![byte; 1 << 20];
    let mut left = n;
    while left > 0 {
        let k = left.min(chunk.len());
        w.write_all(&chunk[..k])?;
        left -= k;
    }
    Ok(())
}

fn gzip(data: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(data).unwrap();
    enc.finish().unwrap()
}

/// A gzip file of `prefix`, then `unit` repeated `times`, then `suffix`,
/// built without compressing the repeats: `unit` is deflated once on its own
/// (ending in a sync flush, so it is byte-aligned, not final, and refers to
/// nothing before itself) and that block is repeated. CRC and size are
/// combined arithmetically. A GiB bomb costs milliseconds to make.
fn gzip_bomb(prefix: &[u8], unit: &[u8], times: usize, suffix: &[u8]) -> Vec<u8> {
    fn flushed(data: &[u8]) -> Vec<u8> {
        let mut enc = flate2::write::DeflateEncoder::new(Vec::new(), flate2::Compression::best());
        enc.write_all(data).unwrap();
        enc.flush().unwrap();
        enc.get_ref().clone()
    }
    let mut body = flushed(prefix);
    let block = flushed(unit);
    for _ in 0..times {
        body.extend_from_slice(&block);
    }
    let mut last = flate2::write::DeflateEncoder::new(Vec::new(), flate2::Compression::best());
    last.write_all(suffix).unwrap();
    body.extend(last.finish().unwrap());

    let mut crc = flate2::Crc::new();
    crc.update(prefix);
    let mut unit_crc = flate2::Crc::new();
    unit_crc.update(unit);
    for _ in 0..times {
        crc.combine(&unit_crc);
    }
    let mut suffix_crc = flate2::Crc::new();
    suffix_crc.update(suffix);
    crc.combine(&suffix_crc);

    let mut gz = vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 0xff];
    gz.extend(body);
    gz.extend(crc.sum().to_le_bytes());
    // ISIZE is the length modulo 2^32, as `amount` counts.
    gz.extend(crc.amount().to_le_bytes());
    gz
}

// ---- random bytes, NUL, invalid UTF-8 ----------------------------------------------

#[test]
fn random_bytes_never_panic_and_every_line_is_counted() {
    // The same bytes every run.
    let mut rng = Rng::new(0x9E37_79B9_7F4A_7C15);
    for case in 0..45 {
        let len = rng.below(1 << (case % 15)) as usize;
        let mut input = rng.bytes(len);
        if case % 3 == 0 {
            // Valid lines among the noise are still read.
            for _ in 0..3 {
                let at = rng.below(input.len() as u64 + 1) as usize;
                let line = format!("\n{ERROR_LINE}\n");
                input.splice(at..at, line.bytes());
            }
        }
        let expected_lines = input.split(|b| *b == b'\n').count() as u64
            - u64::from(input.is_empty() || input.ends_with(b"\n"));
        for format in ["ndjson", "json", "table"] {
            let out = emcy_decode()
                .args(["--format", format, "-"])
                .write_stdin(input.clone())
                .timeout(TIMEOUT)
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_no_panic(&stderr);
            let code = out.status.code().unwrap();
            assert!(code == 0 || code == 2, "case {case} {format}: exit {code}");
            if code == 2 {
                assert!(stderr.contains("error: <stdin>: "), "{stderr}");
            }
            let input_object = match format {
                "ndjson" => input_of(&ndjson(&out.stdout)).clone(),
                "json" => {
                    let doc: Value = serde_json::from_slice(&out.stdout).expect("one document");
                    let inputs = doc["inputs"].as_array().unwrap().clone();
                    input_of(&inputs).clone()
                }
                _ => continue,
            };
            assert_eq!(input_object["lines"], expected_lines, "case {case}");
        }
    }
}

#[test]
fn nul_bytes_are_malformed_lines_and_reading_goes_on() {
    let mut input = b"\0\0\0\0\n".to_vec();
    input.extend(format!("{ERROR_LINE}\n").bytes());
    input.extend(b"(1.500000) can0 081#10\x0043090100000000\n");
    input.extend(format!("{RESET_LINE}\n").bytes());
    input.extend(vec![0u8; 4096]);
    let (code, objects, stderr) = ndjson_run(&["-"], input);
    assert_eq!(code, 0);
    assert_eq!(emcy_lines(&objects), [2, 4]);
    let input = input_of(&objects);
    assert_eq!(
        (input["lines"].as_u64(), input["malformed"].as_u64()),
        (Some(5), Some(3))
    );
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 3, "{stderr}");
    for (line, n) in lines.iter().zip([1, 3, 5]) {
        assert!(line.starts_with(&format!("<stdin>:{n}: ")), "{stderr}");
        assert!(!line.contains('\0'), "no raw NUL on the terminal");
    }
}

#[test]
fn a_file_of_only_nul_bytes_is_an_unknown_format() {
    let (code, objects, stderr) = ndjson_run(&["-"], vec![0u8; 100_000]);
    assert_eq!(code, 2);
    assert!(
        stderr.starts_with("error: <stdin>: cannot detect the trace format"),
        "{stderr}"
    );
    let input = input_of(&objects);
    assert_eq!(input["malformed"], 1);
    assert_eq!(input["format"], Value::Null);
}

#[test]
fn invalid_utf8_is_read_as_bytes() {
    let mut input = b"\xff\xfe\xfd\n".to_vec();
    input.extend(b"(1.0) can\xff 081#1043090100000000\n");
    input.extend(b"\xc3\x28 not a frame \xe2\x82\n");
    input.extend(b"(2.0) can\xff 081#0000000000000000\n");
    let (code, objects, stderr) = ndjson_run(&["-"], input.clone());
    assert_eq!(code, 0);
    assert_eq!(emcy_lines(&objects), [2, 4]);
    let events = of_type(&objects, "emcy");
    assert_eq!(events[0]["channel"], "can\u{FFFD}");
    // Same raw channel, same node: the reset closes the error.
    assert_eq!(events[1]["transition"], 4);
    assert_eq!(stderr.lines().count(), 2, "{stderr}");
    // The table prints it too.
    emcy_decode()
        .arg("-")
        .write_stdin(input)
        .timeout(TIMEOUT)
        .assert()
        .code(0)
        .stdout(predicates::str::contains("can\u{FFFD}"));
}

// ---- long lines --------------------------------------------------------------------

#[test]
fn a_100_mib_line_is_skipped_in_flat_memory_and_the_next_line_is_read() {
    const LEN: usize = 100 << 20;
    let run = run_measured(
        &os(&["--format", "ndjson", "-"]),
        Some(Box::new(|w: &mut dyn Write| {
            writeln!(w, "{ERROR_LINE}")?;
            write_repeated(w, b'7', LEN)?;
            writeln!(w)?;
            writeln!(w, "{RESET_LINE}")
        })),
    );
    assert_eq!(run.status.code(), Some(0), "{}", run.stderr);
    assert_eq!(
        run.stderr,
        format!("<stdin>:2: line of {LEN} bytes is longer than the 65536 byte limit; skipped\n")
    );
    let objects = ndjson(&run.stdout);
    assert_eq!(emcy_lines(&objects), [1, 3]);
    assert_eq!(of_type(&objects, "emcy")[1]["transition"], 4);
    let input = input_of(&objects);
    assert_eq!(input["lines"], 3);
    assert_eq!(input["malformed"], 1);
    assert_flat("a 100 MiB line", run.peak_kib);
}

#[test]
fn long_lines_in_a_file_are_reported_with_file_and_line() {
    let dir = TempDir::new("long");
    let path = dir.path("long.log");
    let mut data = format!("{ERROR_LINE}\n").into_bytes();
    data.extend(vec![b'x'; 1 << 20]);
    data.extend(format!("\n{RESET_LINE}\n").bytes());
    // The last line is long and has no newline at all.
    data.extend(vec![b'y'; 200 * 1024]);
    fs::write(&path, data).unwrap();
    let name = path.display().to_string();
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .arg(&path)
        .timeout(TIMEOUT)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        format!(
            "{name}:2: line of 1048576 bytes is longer than the 65536 byte limit; skipped\n\
             {name}:4: line of 204800 bytes is longer than the 65536 byte limit; skipped\n"
        )
    );
    let objects = ndjson(&out.stdout);
    assert_eq!(emcy_lines(&objects), [1, 3]);
    assert_eq!(input_of(&objects)["lines"], 4);
}

#[test]
fn a_million_hex_digits_after_the_hash_is_one_malformed_line() {
    for (head, tail) in [
        ("(1.5) can0 081#", ""),
        ("(1.5) can0 081##1", ""),
        ("(1.5) can0 ", "#00"),
    ] {
        let line = format!("{head}{}{tail}", "A".repeat(1_000_000));
        let input = format!("{ERROR_LINE}\n{line}\n{RESET_LINE}\n");
        let (code, objects, stderr) = ndjson_run(&["-"], input);
        assert_eq!(code, 0);
        assert_eq!(
            stderr,
            format!(
                "<stdin>:2: line of {} bytes is longer than the 65536 byte limit; skipped\n",
                line.len()
            )
        );
        assert_eq!(emcy_lines(&objects), [1, 3]);
        assert_eq!(input_of(&objects)["malformed"], 1);
    }
}

#[test]
fn huge_frames_under_the_line_cap_are_malformed() {
    let asc_first = "   0.500000 1  81  Rx   d 3 10 43 09";
    let asc_last = "   2.000000 1  81  Rx   d 8 00 00 00 00 00 00 00 00";
    let screen_first = " (0.500000)  can0  081   [3]  10 43 09";
    let screen_last = " (2.000000)  can0  081   [8]  00 00 00 00 00 00 00 00";
    let cases = [
        (
            ERROR_LINE,
            format!("(1.5) can0 081#{}", "1".repeat(60_000)),
            RESET_LINE,
            "more than 8 data bytes",
        ),
        (
            ERROR_LINE,
            format!("(1.5) can0 {}#00", "1".repeat(60_000)),
            RESET_LINE,
            "id has 60000 digits; candump writes 3 (standard) or 8 (extended)",
        ),
        (
            ERROR_LINE,
            format!("(1.5) can0 081##1{}", "1".repeat(60_000)),
            RESET_LINE,
            "more than 64 data bytes",
        ),
        (
            screen_first,
            format!(" (1.5)  can0  081   [8]  {}", "00 ".repeat(20_000)),
            screen_last,
            "[8] but 20000 data bytes",
        ),
        (
            asc_first,
            format!("   1.500000 1  81  Rx   d 8 {}", "00 ".repeat(20_000)),
            asc_last,
            "data has 20000 bytes, DLC says 8",
        ),
    ];
    for (first, hostile, last, reason) in cases {
        let (code, objects, stderr) = ndjson_run(&["-"], format!("{first}\n{hostile}\n{last}\n"));
        assert_eq!(code, 0);
        assert_eq!(stderr, format!("<stdin>:2: {reason}\n"));
        assert_eq!(emcy_lines(&objects), [1, 3]);
        assert_eq!(input_of(&objects)["malformed"], 1);
    }
}

// ---- numbers -------------------------------------------------------------------------

#[test]
fn numbers_that_overflow_u64_are_malformed_never_wrapped() {
    let log = (
        ERROR_LINE,
        &[
            (
                "(18446744073709551616.000000) can0 081#0000000000000000",
                "timestamp seconds overflow 64 bits",
            ),
            (
                "(340282366920938463463374607431768211456.0) can0 081#0000000000000000",
                "timestamp seconds overflow 64 bits",
            ),
            (
                "(1.0000000000000000001) can0 081#0000000000000000",
                "timestamp has more than 18 fraction digits",
            ),
            (
                "(1.5) can0 FFFFFFFFFFFFFFFFFFFFFFFF#0000000000000000",
                "id has 24 digits; candump writes 3 (standard) or 8 (extended)",
            ),
            (
                "(1.5) can0 FFFFFFFF#0000000000000000",
                "extended id FFFFFFFF has bits above 29 set",
            ),
            (
                "(1.5) can0 081#R18446744073709551616",
                "remote frame length must be one digit 0-8",
            ),
            (
                "(1.5) can0 081#0000000000000000_18446744073709551616",
                "raw DLC suffix must be _9.._F after 8 data bytes",
            ),
        ][..],
        RESET_LINE,
    );
    let screen = (
        " (1.000000)  can0  081   [3]  10 43 09",
        &[
            (
                " (18446744073709551616.000000)  can0  081   [8]  00 00 00 00 00 00 00 00",
                "timestamp seconds overflow 64 bits",
            ),
            (
                "  can0  FFFFFFFFFFFFFFFFFFFF   [8]  00 00 00 00 00 00 00 00",
                "id 'FFFFFFFFFFFFFFFFFFFF' has 20 digits; candump writes 3 (standard) or 8 (extended)",
            ),
            (
                "  can0  081   [18446744073709551616]  00 00 00",
                "length field '[18446744073709551616]' is not [n], [nn] or {X}",
            ),
            (
                "  can0  081   {18446744073709551616}  00 00 00",
                "length field '{18446744073709551616}' is not [n], [nn] or {X}",
            ),
            (
                " (99999-01-01 00:00:00.000000)  can0  081   [3]  00 00 00",
                "date timestamp is not (YYYY-MM-DD HH:MM:SS.uuuuuu)",
            ),
        ][..],
        " (2.000000)  can0  081   [8]  00 00 00 00 00 00 00 00",
    );
    let asc = (
        "   1.000000 1  81  Rx   d 3 10 43 09",
        &[
            (
                "18446744073709551616.000000 1  81  Rx d 8 00 00 00 00 00 00 00 00",
                "timestamp seconds overflow 64 bits: '18446744073709551616.000000'",
            ),
            (
                "   1.500000 1  FFFFFFFFFFFFFFFFFFFFFFFFx  Rx d 0",
                "extended id 'FFFFFFFFFFFFFFFFFFFFFFFFx' is above 1FFFFFFF",
            ),
            (
                "   1.500000 1  18446744073709551616  Rx d 0",
                "standard id '18446744073709551616' is above 7FF (29-bit ids end in x)",
            ),
            (
                "   1.500000 1  81  Rx d 18446744073709551616 00 00 00",
                "DLC '18446744073709551616' is not a hex digit 0-F",
            ),
            (
                "   1.500000 CANFD 1 Rx 81 1 0 8 18446744073709551616 00 00 00 00 00 00 00 00 0 0 1000",
                "data length '18446744073709551616' is not a decimal 0-64",
            ),
            (
                "   1.500000 1  81  Rx d 3 18446744073709551616 00 00",
                "data byte 1 '18446744073709551616' is not a hexadecimal byte",
            ),
        ][..],
        "   2.000000 1  81  Rx   d 8 00 00 00 00 00 00 00 00",
    );
    for (first, hostile, last) in [log, screen, asc] {
        let mut input = format!("{first}\n");
        for (line, _) in hostile {
            input.push_str(line);
            input.push('\n');
        }
        input.push_str(last);
        input.push('\n');
        let (code, objects, stderr) = ndjson_run(&["--max-diagnostics", "100", "-"], input);
        assert_eq!(code, 0);
        let expected: String = hostile
            .iter()
            .enumerate()
            .map(|(i, (_, reason))| format!("<stdin>:{}: {reason}\n", i + 2))
            .collect();
        assert_eq!(stderr, expected);
        let n = hostile.len() as u64;
        assert_eq!(emcy_lines(&objects), [1, n + 2]);
        let input = input_of(&objects);
        assert_eq!(input["malformed"], n);
        // Only the two real frames: nothing wrapped around into an EMCY id.
        assert_eq!(input["frames"], 2);
    }
}

#[test]
fn the_largest_timestamp_is_read_exactly() {
    // u64::MAX seconds with 18 fraction digits is the largest time there is;
    // an ASC channel number far beyond u64 is just a name.
    let max = "18446744073709551615.999999999999999999";
    let input = format!("({max}) can0 081#1043090100000000\n(0.0) can0 081#0000000000000000\n");
    let out = emcy_decode()
        .args(["--format", "ndjson", "-"])
        .write_stdin(input)
        .timeout(TIMEOUT)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains(&format!("\"time\":{max},")), "{text}");
    assert!(text.contains(&format!("\"duration\":-{max},")), "{text}");
    ndjson(text.as_bytes());

    let channel = "340282366920938463463374607431768211456";
    let (code, objects, _) = ndjson_run(
        &["-"],
        format!("   1.000000 {channel}  81  Rx   d 3 10 43 09\n"),
    );
    assert_eq!(code, 0);
    assert_eq!(of_type(&objects, "emcy")[0]["channel"], channel);
}

#[test]
fn relative_asc_times_that_overflow_are_malformed() {
    let input = "base hex  timestamps relative\n\
                 18446744073709551615.000000 1  81  Rx   d 3 10 43 09\n\
                 1.000000 1  81  Rx   d 8 00 00 00 00 00 00 00 00\n\
                 0.000000 1  81  Rx   d 8 00 00 00 00 00 00 00 00\n";
    let (code, objects, stderr) = ndjson_run(&["-"], input);
    assert_eq!(code, 0);
    assert_eq!(
        stderr,
        "<stdin>:3: relative timestamps add up past 2^64 seconds\n"
    );
    assert_eq!(emcy_lines(&objects), [2, 4]);
}

#[test]
fn timestamps_going_backwards_get_a_diagnostic_and_a_negative_duration() {
    let input = "(10.000000) can0 081#1043090100000000\n\
                 (4.500000) can0 081#0000000000000000\n\
                 (4.5) can0 082#1043090100000000\n\
                 (4.50) can0 082#0000000000000000\n\
                 (4.50) can0 703#00\n";
    let out = emcy_decode()
        .args(["--format", "ndjson", "-"])
        .write_stdin(input)
        .timeout(TIMEOUT)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    // One diagnostic, where the clock jumped; equal times written with other
    // digit counts are not earlier.
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        "<stdin>:2: time 4.500000 is earlier than 10.000000 at line 1: the trace's clock \
         went backwards (durations across this line are negative); if these are candump -td \
         deltas, --timestamps delta sums them\n"
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("\"duration\":-5.500000,"), "{text}");
    let objects = ndjson(text.as_bytes());
    assert_eq!(emcy_lines(&objects), [1, 2, 3, 4]);
    // The table shows the same signed duration, with its unit.
    emcy_decode()
        .arg("-")
        .write_stdin(input)
        .timeout(TIMEOUT)
        .assert()
        .code(0)
        .stdout(predicates::str::contains("-5.5 s"));
}

// ---- gzip ------------------------------------------------------------------------------

/// 200 EMCY frames, alternating error and reset.
fn gzip_trace() -> String {
    (0..200)
        .map(|i| {
            let data = if i % 2 == 0 {
                "1043090100000000"
            } else {
                "0000000000000000"
            };
            format!("({i}.000000) can0 081#{data}\n")
        })
        .collect()
}

/// Reads a damaged gzip: exit 2 with one `error:` line last, and every line
/// that reached the reader intact is reported exactly as in the intact file.
/// (gzip checks its CRC only at the end of a member: lines decompressed from
/// damaged deflate data are read like any others before the error says the
/// input is corrupt, and may be wrong; the README says so.) Returns how
/// many lines were intact.
fn check_corrupt_gzip(gz: Vec<u8>) -> u64 {
    let original = gzip_trace();
    let mut seen = Vec::new();
    let _ = flate2::read::MultiGzDecoder::new(&gz[..]).read_to_end(&mut seen);
    let same = original
        .bytes()
        .zip(&seen)
        .take_while(|(a, b)| a == *b)
        .count();
    let intact = original[..same].matches('\n').count() as u64;

    let (_, reference, _) = ndjson_run(&["-"], gzip(original.as_bytes()));
    let (code, objects, stderr) = ndjson_run(&["--max-diagnostics", "0", "-"], gz);
    assert_eq!(code, 2, "{stderr}");
    let last = stderr.lines().last().unwrap_or_default();
    assert!(last.starts_with("error: <stdin>: "), "{stderr}");
    let up_to = |objects: &[Value], n: u64| -> Vec<Value> {
        of_type(objects, "emcy")
            .into_iter()
            .filter(|e| e["line"].as_u64().unwrap() <= n)
            .cloned()
            .collect()
    };
    let read = up_to(&objects, intact);
    assert!(
        !read.is_empty(),
        "what was read before the error is reported"
    );
    assert_eq!(read, up_to(&reference, intact));
    let input = input_of(&objects);
    assert_eq!(input["gzip"], true);
    assert!(input["error"].is_string(), "{input}");
    assert!(input["lines"].as_u64().unwrap() >= intact);
    if intact == 200 {
        // The data was whole (only the trailer or what follows is bad).
        assert_eq!(of_type(&objects, "emcy"), of_type(&reference, "emcy"));
    }
    intact
}

#[test]
fn truncated_gzip_reports_what_was_read_then_exit_2() {
    let gz = gzip(gzip_trace().as_bytes());
    assert!(check_corrupt_gzip(gz[..gz.len() / 2].to_vec()) < 200);
    // The fixture, cut short by its trailer.
    let gz = fs::read("fixtures/s300.log.gz").unwrap();
    let (code, objects, stderr) = ndjson_run(&["-"], gz[..gz.len() - 30].to_vec());
    assert_eq!(code, 2);
    assert!(stderr.starts_with("error: <stdin>: "), "{stderr}");
    assert!(input_of(&objects)["error"].is_string());
}

#[test]
fn corrupt_gzip_reports_what_was_read_then_exit_2() {
    // Damage in the last 100 bytes of deflate data.
    let mut gz = gzip(gzip_trace().as_bytes());
    let at = gz.len() - 100;
    gz[at] ^= 0xFF;
    gz[at + 1] ^= 0x55;
    assert!(check_corrupt_gzip(gz) < 200);
}

#[test]
fn gzip_with_a_bad_checksum_is_read_then_exit_2() {
    let mut gz = gzip(gzip_trace().as_bytes());
    let crc = gz.len() - 8;
    gz[crc] ^= 1;
    assert_eq!(check_corrupt_gzip(gz), 200);
}

#[test]
fn gzip_with_trailing_garbage_is_read_then_exit_2() {
    for junk in [&b"garbage\n"[..], &[0, 0, 0, 9][..]] {
        let mut gz = gzip(gzip_trace().as_bytes());
        gz.extend_from_slice(junk);
        assert_eq!(check_corrupt_gzip(gz), 200);
    }
}

/// Tape and block devices pad a gzip file with zeros; GNU gzip reads it
/// without a word, and so do we (exit 0, every line read).
#[test]
fn gzip_with_trailing_zero_padding_is_read_as_gzip_reads_it() {
    let mut gz = gzip(gzip_trace().as_bytes());
    gz.extend_from_slice(&[0u8; 4096]);
    let (code, objects, stderr) = ndjson_run(&["-"], gz);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    let (_, reference, _) = ndjson_run(&["-"], gzip(gzip_trace().as_bytes()));
    assert_eq!(objects, reference);
    assert_eq!(input_of(&objects)["lines"], 200);
}

#[test]
fn gzip_magic_alone_is_an_error_with_a_named_file() {
    let dir = TempDir::new("magic");
    let path = dir.path("magic.log.gz");
    fs::write(&path, [0x1f, 0x8b]).unwrap();
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .arg(&path)
        .timeout(TIMEOUT)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.starts_with(&format!("error: {}: ", path.display())),
        "{stderr}"
    );
    let objects = ndjson(&out.stdout);
    assert_eq!(input_of(&objects)["lines"], 0);
}

#[test]
fn gzip_bomb_of_a_gib_of_zeros_streams_in_flat_memory() {
    let gz = gzip_bomb(
        format!("{ERROR_LINE}\n").as_bytes(),
        &vec![0u8; 1 << 20],
        1024,
        format!("\n{RESET_LINE}\n").as_bytes(),
    );
    assert!(gz.len() < 2 << 20, "{} bytes", gz.len());
    let run = run_measured(
        &os(&["--format", "ndjson", "-"]),
        Some(Box::new(move |w: &mut dyn Write| w.write_all(&gz))),
    );
    assert_eq!(run.status.code(), Some(0), "{}", run.stderr);
    assert_eq!(
        run.stderr,
        "<stdin>:2: line of 1073741824 bytes is longer than the 65536 byte limit; skipped\n"
    );
    let objects = ndjson(&run.stdout);
    assert_eq!(emcy_lines(&objects), [1, 3]);
    assert_eq!(input_of(&objects)["gzip"], true);
    assert_flat("a gzip bomb of 1 GiB of zeros", run.peak_kib);
}

#[test]
fn gzip_bomb_of_newlines_streams_in_flat_memory() {
    const MIB: usize = 8;
    let gz = gzip_bomb(
        format!("{ERROR_LINE}\n").as_bytes(),
        &vec![b'\n'; 1 << 20],
        MIB,
        format!("{RESET_LINE}\n").as_bytes(),
    );
    let run = run_measured(
        &os(&["--format", "ndjson", "-"]),
        Some(Box::new(move |w: &mut dyn Write| w.write_all(&gz))),
    );
    assert_eq!(run.status.code(), Some(0), "{}", run.stderr);
    assert_eq!(run.stderr, "");
    let blank = (MIB << 20) as u64;
    let objects = ndjson(&run.stdout);
    assert_eq!(emcy_lines(&objects), [1, blank + 2]);
    let input = input_of(&objects);
    assert_eq!(input["skipped"], blank);
    assert_eq!(input["lines"], blank + 2);
    assert_flat("a gzip bomb of 8 Mi newlines", run.peak_kib);
}

// ---- empty, directories, streams ---------------------------------------------------------

#[test]
fn empty_inputs_are_fine() {
    let dir = TempDir::new("empty");
    let empty = dir.path("empty.log");
    fs::write(&empty, "").unwrap();
    let sources: [(&[&str], &str); 3] = [
        (&["-"], ""),
        (&[empty.to_str().unwrap()], ""),
        (&["/dev/null"], ""),
    ];
    for (args, stdin) in sources {
        let (code, objects, stderr) = ndjson_run(args, stdin);
        assert_eq!(code, 0);
        assert_eq!(stderr, "");
        let input = input_of(&objects);
        assert_eq!(input["lines"], 0);
        assert_eq!(input["format"], Value::Null);
        assert_eq!(input["error"], Value::Null);
    }
    // Only blank lines and comments: nothing to detect, nothing wrong.
    let (code, objects, stderr) = ndjson_run(&["-"], "\n\n# only comments\n\r\n");
    assert_eq!((code, stderr.as_str()), (0, ""));
    assert_eq!(input_of(&objects)["skipped"], 4);
    emcy_decode().arg("-").write_stdin("").assert().code(0);
}

#[test]
fn a_directory_is_an_error_and_other_files_are_still_read() {
    emcy_decode()
        .arg("fixtures")
        .assert()
        .code(2)
        .stderr(predicates::str::diff(
            "error: fixtures: is a directory; -r (--recursive) reads the traces in it\n",
        ));
    let out = emcy_decode()
        .args(["--format", "ndjson", "fixtures", "fixtures/stoeber.log"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        "error: fixtures: is a directory; -r (--recursive) reads the traces in it\n"
    );
    let objects = ndjson(&out.stdout);
    assert_eq!(of_type(&objects, "emcy").len(), 2);
    let inputs = of_type(&objects, "input");
    assert_eq!(inputs.len(), 2, "every argument has an input object");
    assert_eq!(
        (&inputs[0]["file"], &inputs[0]["error"]),
        (
            &Value::from("fixtures"),
            &Value::from("is a directory; -r (--recursive) reads the traces in it")
        )
    );
    assert_eq!(inputs[1]["file"], "fixtures/stoeber.log");
    assert_eq!(inputs[1]["error"], Value::Null);
}

#[test]
fn a_directory_on_stdin_is_an_error() {
    let out = binary()
        .arg("-")
        .stdin(fs::File::open("fixtures").unwrap())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_no_panic(&stderr);
    assert!(stderr.starts_with("error: <stdin>: "), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

/// What a writer that dies in the middle of line 2 leaves: line 1 decoded,
/// the half line reported, exit 0, no hang.
fn check_half_line(out: std::process::Output, name: &str) {
    assert_eq!(out.status.code(), Some(0));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(
        stderr,
        format!("{name}:2: odd number of hex digits in data\n")
    );
    let objects = ndjson(&out.stdout);
    assert_eq!(emcy_lines(&objects), [1]);
    let input = input_of(&objects);
    assert_eq!(
        (input["lines"].as_u64(), input["malformed"].as_u64()),
        (Some(2), Some(1))
    );
}

const HALF: &str = "(1.000000) can0 081#1043090100000000\n(2.000000) can0 081#00000";

#[test]
fn a_writer_closing_stdin_mid_line_ends_the_input_cleanly() {
    let mut writer = Command::new("sh")
        .args(["-c", &format!("printf '%s' '{HALF}'")])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut child = binary()
        .args(["--format", "ndjson", "-"])
        .stdin(writer.stdout.take().unwrap())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = drain(child.stdout.take().unwrap());
    let stderr = drain(child.stderr.take().unwrap());
    let (status, _) = wait_with_peak(&mut child);
    assert!(writer.wait().unwrap().success());
    check_half_line(
        std::process::Output {
            status,
            stdout: stdout.join().unwrap(),
            stderr: stderr.join().unwrap(),
        },
        "<stdin>",
    );
}

#[cfg(unix)]
#[test]
fn a_fifo_closed_mid_line_ends_the_input_cleanly() {
    let dir = TempDir::new("fifo");
    let fifo = dir.path("live.log");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let mut child = binary()
        .args(["--format", "ndjson"])
        .arg(&fifo)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A separate process writes half a line into the FIFO and exits.
    let writer = Command::new("sh")
        .args([
            "-c",
            &format!("printf '%s' '{HALF}' > \"$0\""),
            fifo.to_str().unwrap(),
        ])
        .status()
        .unwrap();
    assert!(writer.success());
    let stdout = drain(child.stdout.take().unwrap());
    let stderr = drain(child.stderr.take().unwrap());
    let (status, _) = wait_with_peak(&mut child);
    check_half_line(
        std::process::Output {
            status,
            stdout: stdout.join().unwrap(),
            stderr: stderr.join().unwrap(),
        },
        &fifo.display().to_string(),
    );
}

#[test]
fn stdout_closed_early_is_exit_0_without_a_panic_message() {
    // A long trace into a reader that goes away after the first bytes
    // (`emcy-decode trace.log | head -1`), in every output format.
    let dir = TempDir::new("pipe");
    let path = dir.path("long.log");
    let trace: String = (0..50_000)
        .map(|i| format!("({i}.000000) can0 081#1043090100000000\n"))
        .collect();
    fs::write(&path, trace).unwrap();
    for format in ["table", "json", "ndjson"] {
        let mut child = binary()
            .args(["--format", format])
            .arg(&path)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        {
            let mut stdout = child.stdout.take().unwrap();
            let mut first = [0u8; 16];
            stdout.read_exact(&mut first).unwrap();
        } // dropped: the pipe closes
        let stderr = drain(child.stderr.take().unwrap());
        let (status, _) = wait_with_peak(&mut child);
        let stderr = String::from_utf8(stderr.join().unwrap()).unwrap();
        assert_eq!(status.code(), Some(0), "{format}: {stderr}");
        assert_eq!(stderr, "", "{format}");
    }
}

// ---- formats mixing ------------------------------------------------------------------------

/// One EMCY (error 0x4310 on node 1) and one reset in each format.
fn line_in(format: &str, reset: bool) -> &'static str {
    match (format, reset) {
        ("candump", false) => "(1.000000) can0 081#1043090100000000",
        ("candump", true) => "(3.000000) can0 081#0000000000000000",
        ("candump-screen", false) => " (1.000000)  can0  081   [8]  10 43 09 01 00 00 00 00",
        ("candump-screen", true) => " (3.000000)  can0  081   [8]  00 00 00 00 00 00 00 00",
        ("asc", false) => "   1.000000 1  81  Rx   d 8 10 43 09 01 00 00 00 00",
        ("asc", true) => "   3.000000 1  81  Rx   d 8 00 00 00 00 00 00 00 00",
        _ => unreachable!(),
    }
}

const FORMATS: [&str; 3] = ["candump", "candump-screen", "asc"];

/// Line 2 is a 2.0 s EMCY written in `other` format.
fn mixed(primary: &str, other: &str) -> String {
    let foreign = line_in(other, false).replace("1.000000", "2.000000");
    format!(
        "{}\n{foreign}\n{}\n",
        line_in(primary, false),
        line_in(primary, true)
    )
}

#[test]
fn every_pair_of_formats_mixes_only_with_a_warning() {
    for primary in FORMATS {
        for other in FORMATS.into_iter().filter(|f| *f != primary) {
            let (code, objects, stderr) = ndjson_run(&["-"], mixed(primary, other));
            assert_eq!(code, 0, "{primary} + {other}");
            assert_eq!(
                stderr,
                format!(
                    "<stdin>:2: line is in {other} format, not {primary} like the rest; read anyway\n"
                )
            );
            // The foreign line is read: no EMCY lost.
            assert_eq!(emcy_lines(&objects), [1, 2, 3], "{primary} + {other}");
            let input = input_of(&objects);
            assert_eq!(input["format"], primary);
            assert_eq!(input["other_format"], 1);
            assert_eq!(input["malformed"], 0);
        }
    }
}

#[test]
fn input_format_turns_mixing_off() {
    for primary in FORMATS {
        for other in FORMATS.into_iter().filter(|f| *f != primary) {
            let (code, objects, stderr) =
                ndjson_run(&["--input-format", primary, "-"], mixed(primary, other));
            assert_eq!(code, 0, "{primary} + {other}");
            assert!(stderr.starts_with("<stdin>:2: "), "{stderr}");
            assert!(!stderr.contains("read anyway"), "{stderr}");
            assert_eq!(stderr.lines().count(), 1, "{stderr}");
            assert_eq!(emcy_lines(&objects), [1, 3], "{primary} + {other}");
            let input = input_of(&objects);
            assert_eq!(input["other_format"], 0);
            assert_eq!(input["malformed"], 1);
        }
    }
}

// ---- guarantees about the code and the diagnostics ---------------------------------------------

#[test]
fn the_library_and_the_binary_forbid_unsafe_code() {
    // `forbid` cannot be overridden by an inner `allow`: as long as these
    // lines stay, no unsafe code compiles in src/.
    for root in ["src/lib.rs", "src/bin/emcy-decode/main.rs"] {
        let text = fs::read_to_string(root).unwrap();
        assert!(
            text.lines().any(|l| l.trim() == "#![forbid(unsafe_code)]"),
            "{root} must keep #![forbid(unsafe_code)]"
        );
    }
}

/// A trace with one of every kind of diagnostic.
fn troubled_trace() -> String {
    [
        "garbage before the first frame",
        "(5.000000) can0 081#1043090100000000",
        "(5.100000) can0 081#10",
        "not a frame",
        "(5.200000) can0 08G#1043090100000000",
        "  can0  081   [8]  10 43 09 01 00 00 00 00",
        "(1.000000) can0 081#0000000000000000",
        &"x".repeat(70_000),
        "(6.000000) can0 081#1043",
    ]
    .join("\n")
}

#[test]
fn every_diagnostic_names_file_and_line() {
    let dir = TempDir::new("diag");
    let a = dir.path("a.log");
    let b = dir.path("b.log");
    fs::write(&a, troubled_trace()).unwrap();
    fs::write(&b, format!("{}\n", troubled_trace())).unwrap();
    let out = emcy_decode()
        .args(["--format", "json"])
        .arg(&a)
        .arg(&b)
        .timeout(TIMEOUT)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let stderr = String::from_utf8(out.stderr).unwrap();
    let names = [a.display().to_string(), b.display().to_string()];
    let expected_lines = [1, 3, 4, 5, 6, 7, 8, 9];
    let mut count = 0;
    for line in stderr.lines() {
        let (file, rest) = names
            .iter()
            .find_map(|n| line.strip_prefix(n.as_str()).map(|r| (n, r)))
            .unwrap_or_else(|| panic!("no file name: {line}"));
        let rest = rest
            .strip_prefix(':')
            .unwrap_or_else(|| panic!("no ':': {line}"));
        let (n, message) = rest.split_once(": ").unwrap();
        let n: u64 = n
            .parse()
            .unwrap_or_else(|_| panic!("no line number: {line}"));
        assert!(expected_lines.contains(&n), "{file}: {line}");
        assert!(!message.is_empty());
        count += 1;
    }
    assert_eq!(count, 2 * expected_lines.len(), "{stderr}");
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    let diagnostics = doc["diagnostics"].as_array().unwrap();
    assert_eq!(diagnostics.len(), count);
    for d in diagnostics {
        assert!(names.iter().any(|n| d["file"] == n.as_str()), "{d}");
        assert!(expected_lines.contains(&d["line"].as_u64().unwrap()), "{d}");
    }
}

#[test]
fn max_diagnostics_bounds_printing_never_counting() {
    let trace = "garbage\n".repeat(30) + ERROR_LINE + "\n" + "(3.0) can0 081#00\n";
    for n in [0usize, 1, 3, 31, 1000] {
        let out = emcy_decode()
            .args(["--format", "json", "--max-diagnostics", &n.to_string(), "-"])
            .write_stdin(trace.clone())
            .timeout(TIMEOUT)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
        let stderr = String::from_utf8(out.stderr).unwrap();
        // 30 malformed lines and one short EMCY: 31 diagnostics.
        let shown = n.min(31);
        let mut lines = stderr.lines();
        for (i, line) in lines.by_ref().take(shown).enumerate() {
            let at = if i < 30 { i + 1 } else { 32 };
            assert!(line.starts_with(&format!("<stdin>:{at}: ")), "{line}");
        }
        if shown < 31 {
            assert_eq!(
                lines.next(),
                Some(
                    format!(
                        "<stdin>: {} more diagnostics not shown (--max-diagnostics {n})",
                        31 - shown
                    )
                    .as_str()
                )
            );
        }
        assert_eq!(lines.next(), None, "{stderr}");
        let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(doc["diagnostics"].as_array().unwrap().len(), shown);
        let input = input_of(doc["inputs"].as_array().unwrap());
        assert_eq!(input["malformed"], 30);
        assert_eq!(input["emcy_invalid"], 1);
        assert_eq!(input["emcy"], 1);
        assert_eq!(input["lines"], 32);
    }
}

// ---- regressions ----------------------------------------------------------------------------------

#[test]
fn many_distinct_channels_stay_linear_in_time_and_memory() {
    // Every interface name is a channel, each with one node. A channel used
    // to cost 128 node slots (8 KiB) and a linear search; then a node cost
    // about 2.8 KiB in ndjson and 3.7 KiB in the table (its report was
    // copied for the renderer, the table held every row): 100k names took
    // 280 and 380 MB. Now about 0.8 KiB, whatever the format.
    const CHANNELS: u64 = 100_000;
    const BASE_KIB: u64 = 16 * 1024;
    const PER_NODE_BYTES: u64 = 1200;
    let dir = TempDir::new("channels");
    let path = dir.path("channels.log");
    let trace: String = (0..CHANNELS)
        .map(|i| format!("(1.0) c{i} 081#1043090100000000\n"))
        .collect();
    fs::write(&path, trace).unwrap();
    let limit = BASE_KIB + CHANNELS * PER_NODE_BYTES / 1024;
    for format in ["ndjson", "table"] {
        let started = Instant::now();
        let run = run_measured(
            &[
                OsString::from("--format"),
                format.into(),
                path.clone().into(),
            ],
            None,
        );
        assert_eq!(run.status.code(), Some(0));
        if format == "ndjson" {
            let objects = ndjson(&run.stdout);
            assert_eq!(of_type(&objects, "node").len(), CHANNELS as usize);
        } else {
            let table = String::from_utf8(run.stdout).unwrap();
            assert!(
                table.contains("\nc99999      1     1  error_occurred"),
                "one row per node"
            );
        }
        if let Some(peak) = run.peak_kib {
            eprintln!("peak RSS for {CHANNELS} channels ({format}): {peak} KiB");
            assert!(
                peak < limit,
                "{format}: peak RSS {peak} KiB, limit {limit} KiB"
            );
        }
        assert!(started.elapsed() < Duration::from_secs(60));
    }
}

#[test]
fn channel_names_cannot_put_control_sequences_on_the_terminal() {
    // A valid candump log line whose interface name sets the terminal title.
    let input = "(1.0) \x1b]0;pwned\x07 081#1043090100000000\n";
    let out = emcy_decode()
        .arg("-")
        .write_stdin(input)
        .timeout(TIMEOUT)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(
        !table.contains('\x1b') && !table.contains('\x07'),
        "{table:?}"
    );
    assert!(table.contains("\\u{1b}]0;pwned\\u{7}"), "{table}");
    // JSON keeps the name exactly (escaped by JSON itself).
    let (_, objects, _) = ndjson_run(&["-"], input);
    assert_eq!(of_type(&objects, "emcy")[0]["channel"], "\x1b]0;pwned\x07");
}

#[test]
fn channel_names_that_read_the_same_are_one_channel() {
    // Found by fuzzing (fuzz/regressions/candump_screen/same-name-different-bytes):
    // two interface names that differ only in invalid UTF-8 both read as
    // "\u{FFFD}can0". They were two channels with one name, and the node
    // report of the first got the errors of both.
    let mut input = Vec::new();
    input.extend_from_slice(b"(1.0) \xffcan0 082#1043012900000000\n");
    input.extend_from_slice(b"(2.0) \xfecan0 082#1043012900000000\n");
    let (code, objects, _) = ndjson_run(&["-"], input);
    assert_eq!(code, 0);
    let nodes = of_type(&objects, "node");
    assert_eq!(nodes.len(), 1, "{nodes:?}");
    assert_eq!(nodes[0]["channel"], "\u{FFFD}can0");
    assert_eq!(nodes[0]["emcy_count"], 2);
    assert_eq!(nodes[0]["active"], serde_json::json!(["0x4310"]));
    assert_eq!(nodes[0]["errors"].as_array().map(Vec::len), Some(1));
    // The second frame repeats an active error: no second raise.
    assert_eq!(of_type(&objects, "emcy")[1]["transition"], 3);
}

/// 200 000 distinct codes raised and never cleared (four nodes, 50 000
/// each): every event used to list all of its node's active codes, and the
/// node checked each new code against all of them: 48 MB of such input gave
/// 36 GB of ndjson. An event lists at most 64 and counts the rest; each line
/// is bounded, the whole output linear in the input (the node objects list
/// every error once).
#[test]
fn never_cleared_codes_keep_every_event_bounded() {
    const NODES: u32 = 4;
    const CODES: u32 = 50_000;
    const EVENT_MAX: usize = 2048;
    const ERROR_MAX: usize = 256;
    let dir = TempDir::new("active");
    let path = dir.path("active.log");
    let mut trace = io::BufWriter::new(fs::File::create(&path).unwrap());
    for code in 1..=CODES {
        let [lo, hi] = (code as u16).to_le_bytes();
        for node in 1..=NODES {
            writeln!(
                trace,
                "({code}.{node}) can0 {:03X}#{lo:02X}{hi:02X}0100000000",
                0x80 + node
            )
            .unwrap();
        }
    }
    trace.into_inner().unwrap().sync_all().unwrap();
    let events = (NODES * CODES) as usize;
    let mut child = binary()
        .args(["--format", "ndjson"])
        .arg(&path)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut stdout = io::BufReader::new(child.stdout.take().unwrap());
    let (mut line, mut total, mut seen) = (Vec::new(), 0usize, 0usize);
    let mut nodes = Vec::new();
    let failure = loop {
        line.clear();
        match io::BufRead::read_until(&mut stdout, b'\n', &mut line) {
            Ok(0) => break None,
            Ok(n) => total += n,
            Err(e) => break Some(format!("reading stdout: {e}")),
        }
        if line.starts_with(br#"{"type":"emcy""#) {
            seen += 1;
            if line.len() > EVENT_MAX {
                break Some(format!("event {seen} is {} bytes", line.len()));
            }
            // A sample is read in full: the first codes, the count.
            if seen % 9973 == 0 {
                let event: Value = serde_json::from_slice(&line).unwrap();
                let active = event["active"].as_array().unwrap().len();
                let node_total = (seen - 1) / NODES as usize + 1;
                assert_eq!(active, node_total.min(64), "event {seen}");
                if node_total > 64 {
                    assert_eq!(event["active_truncated"], node_total, "event {seen}");
                }
            }
        } else if line.starts_with(br#"{"type":"node""#) {
            if line.len() > CODES as usize * ERROR_MAX {
                break Some(format!("a node object of {} bytes", line.len()));
            }
            nodes.push(serde_json::from_slice::<Value>(&line).unwrap());
        }
    };
    if failure.is_some() {
        let _ = child.kill();
    }
    let status = child.wait().unwrap();
    if let Some(failure) = failure {
        panic!("{failure} (the output must stay linear in the input)");
    }
    assert!(status.success());
    assert_eq!(seen, events);
    assert!(total <= events * (EVENT_MAX + ERROR_MAX), "{total} bytes");
    assert_eq!(nodes.len(), NODES as usize);
    for node in &nodes {
        assert_eq!(
            node["active"].as_array().map(Vec::len),
            Some(CODES as usize)
        );
        assert_eq!(
            node["errors"].as_array().map(Vec::len),
            Some(CODES as usize)
        );
    }
}

/// A baseline, profile or DCF given as `/dev/zero` (or any endless or huge
/// file) is read up to its bound, then one `error:` line naming the bound,
/// exit 2; never gigabytes. Run under a 1 GiB address-space limit (the
/// shell's `ulimit -v`), so reading without a bound fails fast here instead
/// of filling the machine.
#[cfg(target_os = "linux")]
#[test]
fn files_that_are_no_trace_are_read_with_a_bound_in_the_error() {
    let program = binary().get_program().to_owned();
    let runs: [(&[&str], &str); 5] = [
        (
            &["check", "--baseline", "/dev/zero", "fixtures/s300.log"],
            "error: /dev/zero: larger than 64 MiB: not a baseline",
        ),
        (
            &[
                "check",
                "--update",
                "--baseline",
                "/dev/zero",
                "fixtures/s300.log",
            ],
            "error: /dev/zero: larger than 64 MiB: not a baseline",
        ),
        (
            &["--profile-file", "/dev/zero", "fixtures/s300.log"],
            "error: /dev/zero: larger than 16 MiB: not a profile",
        ),
        (
            &["explain", "--profile-file", "/dev/zero", "4310"],
            "error: /dev/zero: larger than 16 MiB: not a profile",
        ),
        (
            &["--dcf", "5=/dev/zero", "fixtures/s300.log"],
            "error: --dcf /dev/zero: larger than 16 MiB: not a DCF",
        ),
    ];
    for (args, message) in runs {
        let out = assert_cmd::Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 1048576 && exec \"$0\" \"$@\"")
            .arg(&program)
            .args(args)
            .timeout(Duration::from_secs(60))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().collect::<Vec<_>>(), [message], "{args:?}");
    }
}
