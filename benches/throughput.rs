//! End-to-end throughput: `cargo bench --bench throughput`.
//!
//! Generates large traces deterministically (cached under the target dir),
//! then times `wc -l` and `gzip -dc` (the ceilings) and emcy-decode on the same
//! files in the same run, and prints MB/s, the ratio to the ceiling and the
//! peak resident memory. Sizes: `BENCH_MB` (default 1024), `BENCH_GZ_MB`
//! (default 256); best of `BENCH_RUNS` (default 3). Words after `--` pick
//! the cases whose name contains one of them (`cargo bench --bench
//! throughput -- pcapng`): `candump log`, `candump -td`, `Vector ASC`,
//! `30% EMCY`, `gzip`, `pcapng` (both pcapng cases), `EtherCAT`,
//! `BUSMASTER`, `MF4` (both MF4 cases), `MF4 DZ`, `heartbeating` (32
//! nodes' heartbeats every 100 ms), `drives` (32 CiA 402 drives' TPDO1 at
//! 1 kHz, with and without `--assume-cia402-pdo`).
//!
//! `BENCH_COMPARE=/path/to/emcy-decode` holds another build against this
//! one: each emcy-decode case runs both, their runs interleaved and each
//! first every other run (so load from elsewhere falls on both alike), and
//! a row gives the other's figures and this build's time as a multiple of
//! its. Where `--timing` is measured, its cost follows as a multiple of the
//! default's time, the two interleaved the same way.

#[path = "../tests/integration/support/tracegen.rs"]
mod tracegen;

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use tracegen::{
    BusShape, TraceFormat, write_bus_trace, write_drive_trace, write_ethercat,
    write_heartbeat_trace, write_mf4_dz, write_trace,
};

/// The heartbeat case's label (and the word that picks it).
const HEARTBEATS: &str = "candump log, 32 nodes heartbeating";
/// The drives case: 32 CiA 402 drives' TPDO1 at 1 kHz.
const DRIVES: &str = "candump log, 32 drives TPDO1 1 kHz";

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Creates `path` with the generator unless it already exists.
fn ensure(path: &Path, format: TraceFormat, mb: u64, emcy_per_mille: u64, gzip: bool) {
    if path.exists() {
        return;
    }
    eprintln!("generating {} ...", path.display());
    let tmp = path.with_extension("tmp");
    let file = File::create(&tmp).expect("create trace");
    let bytes = mb * 1024 * 1024;
    if gzip {
        let enc = flate2::write::GzEncoder::new(
            BufWriter::with_capacity(1 << 20, file),
            flate2::Compression::default(),
        );
        let mut w = BufWriter::with_capacity(1 << 20, enc);
        write_trace(&mut w, format, bytes, emcy_per_mille, 42).expect("write");
        let enc = w.into_inner().map_err(|e| e.into_error()).expect("flush");
        enc.finish().expect("finish gzip").flush().expect("flush");
    } else {
        let mut w = BufWriter::with_capacity(1 << 20, file);
        write_trace(&mut w, format, bytes, emcy_per_mille, 42).expect("write");
        w.flush().expect("flush");
    }
    std::fs::rename(&tmp, path).expect("rename");
}

/// Reads `path` through, so a run finds it in the page cache. Needed before
/// every run: the CI machine keeps only ~1.7 GB of page cache, less than
/// the bench's files, and drops pages over seconds even when idle.
fn warm(path: &str) {
    let mut buf = vec![0u8; 1 << 20];
    if let Ok(mut f) = File::open(path) {
        while matches!(f.read(&mut buf), Ok(n) if n > 0) {}
    }
}

/// CPU time (user and system) of this process's waited-for children so
/// far, from `/proc/self/stat` (in clock ticks of 10 ms: the bench's runs
/// take tenths of seconds, so this is coarse but not useless).
fn children_cpu() -> Duration {
    let ticks = std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the command's closing parenthesis; cutime and
            // cstime are the 16th and 17th of the whole line.
            let rest = s.rsplit_once(')')?.1.to_string();
            let fields: Vec<u64> = rest
                .split_whitespace()
                .skip(1)
                .map(|f| f.parse().unwrap_or(0))
                .collect();
            Some(fields.get(12)? + fields.get(13)?)
        })
        .unwrap_or(0);
    Duration::from_millis(ticks * 10)
}

/// The least CPU time of the runs of the last [`measure`] on this thread.
fn last_cpu() -> Duration {
    LAST_CPU.with(std::cell::Cell::get)
}

thread_local! {
    static LAST_CPU: std::cell::Cell<Duration> = const { std::cell::Cell::new(Duration::ZERO) };
}

/// Best wall time of `runs` runs of `program` on `input` (warmed before
/// each run) and the highest peak RSS (KiB) seen; [`last_cpu`] the least
/// CPU time.
fn measure(runs: u64, input: &str, program: &str, args: &[&str]) -> (Duration, u64) {
    try_measure(runs, input, program, args).unwrap_or_else(|| panic!("{program} {args:?} failed"))
}

/// [`measure`], `None` when a run fails (`wc` never does: it only counts).
fn try_measure(runs: u64, input: &str, program: &str, args: &[&str]) -> Option<(Duration, u64)> {
    let mut best = Duration::MAX;
    let mut peak = 0;
    let mut cpu = Duration::MAX;
    for _ in 0..runs {
        warm(input);
        let cpu_before = children_cpu();
        let start = Instant::now();
        let mut child = Command::new(program)
            .args(args)
            .stdout(File::create("/dev/null").expect("/dev/null"))
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn");
        let status_path = format!("/proc/{}/status", child.id());
        loop {
            if let Ok(Some(status)) = child.try_wait() {
                if !(status.success() || program == "wc") {
                    return None;
                }
                break;
            }
            if let Ok(s) = std::fs::read_to_string(&status_path)
                && let Some(kib) = s
                    .lines()
                    .find(|l| l.starts_with("VmHWM:"))
                    .and_then(|l| l.split_whitespace().nth(1))
                    .and_then(|v| v.parse::<u64>().ok())
            {
                peak = peak.max(kib);
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        best = best.min(start.elapsed());
        cpu = cpu.min(children_cpu().saturating_sub(cpu_before));
    }
    LAST_CPU.with(|c| c.set(cpu));
    Some((best, peak))
}

/// [`measure`] of `program` and, when given, of `other` with the same
/// arguments, their runs interleaved (`None` for the other when it fails:
/// an older build may not have the case's flags).
fn measure_both(
    runs: u64,
    input: &str,
    program: &str,
    other: Option<&str>,
    args: &[&str],
) -> ((Duration, u64), Option<(Duration, u64)>) {
    let Some(other) = other else {
        return (measure(runs, input, program, args), None);
    };
    let (mut this, mut that) = ((Duration::MAX, 0), Some((Duration::MAX, 0)));
    let mut cpu = Duration::MAX;
    for run in 0..runs {
        // Each goes first every other run: on 2 cores the second of a pair
        // ran up to 10% faster or slower than the first, which the best of
        // runs in one order took for a difference between the builds.
        let other_first = run % 2 == 1;
        let mut theirs = || {
            that = that
                .zip(try_measure(1, input, other, args))
                .map(|((best, most), (t, peak))| (best.min(t), most.max(peak)));
        };
        if other_first {
            theirs();
        }
        let (t, peak) = measure(1, input, program, args);
        cpu = cpu.min(last_cpu());
        this = (this.0.min(t), this.1.max(peak));
        if !other_first {
            theirs();
        }
    }
    // This build's, as [`last_cpu`] promises.
    LAST_CPU.with(|c| c.set(cpu));
    (this, that)
}

/// `--timing`'s best time over the default's (`args` without the flag),
/// `runs` of each with this build, each going first every other run: the
/// figure the flag's cost is stated in, free of the drift between cases
/// measured one after the other.
fn timing_cost(runs: u64, input: &str, program: &str, args: &[&str]) -> f64 {
    let timed: Vec<&str> = args.iter().copied().chain(["--timing"]).collect();
    let (mut default, mut timing) = (Duration::MAX, Duration::MAX);
    for run in 0..runs {
        let order = if run % 2 == 0 {
            [false, true]
        } else {
            [true, false]
        };
        for timed_now in order {
            let (t, _) = measure(1, input, program, if timed_now { &timed } else { args });
            if timed_now {
                timing = timing.min(t);
            } else {
                default = default.min(t);
            }
        }
    }
    timing.as_secs_f64() / default.as_secs_f64()
}

fn mb_per_s(bytes: u64, t: Duration) -> f64 {
    bytes as f64 / 1e6 / t.as_secs_f64()
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} cores")
}

fn main() {
    // `cargo bench` passes --bench; `cargo test --benches` passes nothing
    // useful either: only run the real thing under `cargo bench`.
    if !std::env::args().any(|a| a == "--bench") {
        eprintln!("throughput: run with `cargo bench --bench throughput`");
        return;
    }
    let mb = env_u64("BENCH_MB", 1024);
    let gz_mb = env_u64("BENCH_GZ_MB", 256);
    let runs = env_u64("BENCH_RUNS", 3);
    let bin = env!("CARGO_BIN_EXE_emcy-decode");
    let compare = std::env::var("BENCH_COMPARE").ok();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-data");
    std::fs::create_dir_all(&dir).expect("bench dir");

    // Words that are not flags choose the cases (all when none is given).
    let words: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let chosen = |case: &str| words.is_empty() || words.iter().any(|w| case.contains(w.as_str()));

    // `write_trace`'s files, named by the generator's version: a file
    // cached by an older one must not be measured as if it were this one's
    // (v2: nodes heartbeat every 100 ms, no longer at random).
    let log = dir.join(format!("candump-{mb}MB.v2.log"));
    let delta = dir.join(format!("candump-td-{mb}MB.v2.log"));
    let asc = dir.join(format!("asc-{mb}MB.v2.asc"));
    let emcy30 = dir.join(format!("candump-emcy30-{mb}MB.v2.log"));
    let gz = dir.join(format!("candump-{gz_mb}MB.v2.log.gz"));
    let pcapng = dir.join(format!("pcapng-{mb}MB.v2.pcapng"));
    let busmaster = dir.join(format!("busmaster-{mb}MB.v2.log"));
    let ixxat = dir.join(format!("ixxat-{mb}MB.v2.trc"));
    let mf4 = dir.join(format!("canedge-{mb}MB.v2.mf4"));
    let mf4_dz = dir.join(format!("dz-{mb}MB.v2.mf4"));
    let ethercat = dir.join(format!("ethercat-{mb}MB.pcapng"));
    let files = [
        ("candump log", &log, TraceFormat::CandumpLog, 2),
        (
            "candump -td (deltas summed)",
            &delta,
            TraceFormat::CandumpDelta,
            2,
        ),
        ("Vector ASC", &asc, TraceFormat::Asc, 2),
        (
            "candump log, 30% EMCY",
            &emcy30,
            TraceFormat::CandumpLog,
            300,
        ),
        ("pcapng, LINUX_SLL", &pcapng, TraceFormat::Pcapng, 2),
        ("BUSMASTER HEX", &busmaster, TraceFormat::Busmaster, 2),
        ("IXXAT MiniMon", &ixxat, TraceFormat::Ixxat, 2),
        ("MF4, CANedge unfinalized", &mf4, TraceFormat::Mf4, 2),
    ];
    for (label, file, format, emcy) in files {
        if chosen(label) {
            ensure(file, format, mb, emcy, false);
        }
    }
    if chosen("gzip") {
        ensure(&gz, TraceFormat::CandumpLog, gz_mb, 2, true);
    }
    let ethercat_label = "pcapng, EtherCAT 32 x 1 kHz";
    if chosen(ethercat_label) && !ethercat.exists() {
        eprintln!("generating {} ...", ethercat.display());
        let tmp = ethercat.with_extension("tmp");
        let mut w = BufWriter::with_capacity(1 << 20, File::create(&tmp).expect("create"));
        // An emergency in 2 of 1000 cycles: as many as the CAN traces' EMCYs.
        write_ethercat(&mut w, mb * 1024 * 1024, 2, 42).expect("write");
        w.flush().expect("flush");
        drop(w);
        std::fs::rename(&tmp, &ethercat).expect("rename");
    }
    // 32 nodes heartbeating every 100 ms (about a tenth of the
    // frames), every heartbeat decoded.
    let heartbeats = dir.join(format!("candump-hb32-{mb}MB.log"));
    if chosen(HEARTBEATS) && !heartbeats.exists() {
        eprintln!("generating {} ...", heartbeats.display());
        let tmp = heartbeats.with_extension("tmp");
        let mut w = BufWriter::with_capacity(1 << 20, File::create(&tmp).expect("create"));
        write_heartbeat_trace(&mut w, TraceFormat::CandumpLog, mb * 1024 * 1024, 2, 42, 32)
            .expect("write");
        w.flush().expect("flush");
        drop(w);
        std::fs::rename(&tmp, &heartbeats).expect("rename");
    }
    // 32 drives sending TPDO1 every millisecond (nearly every
    // frame), measured with --assume-cia402-pdo (every PDO decoded) and
    // without (the EMCY-only path, the PDOs only counted).
    let drives = dir.join(format!("candump-drives32-{mb}MB.log"));
    if chosen(DRIVES) && !drives.exists() {
        eprintln!("generating {} ...", drives.display());
        let tmp = drives.with_extension("tmp");
        let mut w = BufWriter::with_capacity(1 << 20, File::create(&tmp).expect("create"));
        write_drive_trace(&mut w, mb * 1024 * 1024, 2, 42, 32).expect("write");
        w.flush().expect("flush");
        drop(w);
        std::fs::rename(&tmp, &drives).expect("rename");
    }
    // Real machine buses (`BusShape`), each measured with and without
    // --assume-cia402-pdo, on two threads and on one.
    let shapes = [
        (
            "bus: commissioning, 8 drives",
            BusShape::Commissioning,
            "commissioning",
        ),
        (
            "bus: firmware, segmented SDO",
            BusShape::FirmwareSegmented,
            "firmware-segmented",
        ),
        (
            "bus: firmware, block SDO",
            BusShape::FirmwareBlock,
            "firmware-block",
        ),
        ("bus: noisy, 4 drives 12 I/O HMI", BusShape::Noisy, "noisy"),
    ];
    let shape_files: Vec<(&str, PathBuf)> = shapes
        .iter()
        .map(|(label, _, name)| (*label, dir.join(format!("bus-{name}-{mb}MB.log"))))
        .collect();
    for ((label, shape, _), (_, file)) in shapes.iter().zip(&shape_files) {
        if chosen(label) && !file.exists() {
            eprintln!("generating {} ...", file.display());
            let tmp = file.with_extension("tmp");
            let mut w = BufWriter::with_capacity(1 << 20, File::create(&tmp).expect("create"));
            write_bus_trace(&mut w, *shape, mb * 1024 * 1024, 42).expect("write");
            w.flush().expect("flush");
            drop(w);
            std::fs::rename(&tmp, file).expect("rename");
        }
    }
    if chosen("MF4 DZ") && !mf4_dz.exists() {
        eprintln!("generating {} ...", mf4_dz.display());
        let tmp = mf4_dz.with_extension("tmp");
        let mut w = BufWriter::with_capacity(1 << 20, File::create(&tmp).expect("create"));
        write_mf4_dz(&mut w, mb * 1024 * 1024, 2, 42).expect("write");
        w.flush().expect("flush");
        drop(w);
        std::fs::rename(&tmp, &mf4_dz).expect("rename");
    }

    println!("machine: {}", machine());
    println!("best of {runs} runs, output to /dev/null, warm page cache\n");
    println!(
        "{:<52} {:>9} {:>9} {:>10} {:>12} {:>9} {:>7}",
        "case", "MB", "seconds", "MB/s", "vs ceiling", "peak RSS", "CPU s"
    );
    let size = |p: &Path| std::fs::metadata(p).map_or(0, |m| m.len());
    let path = |p: &Path| p.to_str().expect("utf-8 path").to_string();

    // The CPU column is the least CPU time of the runs just measured (this
    // build's, on a BENCH_COMPARE row too: the other's is not kept).
    let row = |name: &str, bytes: u64, t: Duration, ceiling: Option<Duration>, peak: u64| {
        let ratio = ceiling.map_or("ceiling".to_string(), |c| {
            format!("{:.2}x time", t.as_secs_f64() / c.as_secs_f64())
        });
        println!(
            "{name:<52} {:>9.0} {:>9.3} {:>10.0} {ratio:>12} {:>6} MiB {:>7.2}",
            bytes as f64 / 1e6,
            t.as_secs_f64(),
            mb_per_s(bytes, t),
            peak / 1024,
            last_cpu().as_secs_f64()
        );
    };

    let measured = files
        .iter()
        .map(|(label, file, _, _)| (*label, *file))
        .chain([
            (ethercat_label, &ethercat),
            (HEARTBEATS, &heartbeats),
            (DRIVES, &drives),
        ])
        .chain(shape_files.iter().map(|(label, file)| (*label, file)));
    for (label, file) in measured {
        if !chosen(label) {
            continue;
        }
        let bytes = size(file);
        let f = path(file);
        // Only reading the file (one thread, 1 MiB reads): how much of the
        // ceiling is the kernel's copy out of the page cache.
        let (dd, dd_peak) = measure(
            runs,
            &f,
            "dd",
            &["bs=1M", "of=/dev/null", &format!("if={f}")],
        );
        let (wc, wc_peak) = measure(runs, &f, "wc", &["-l", &f]);
        row(
            &format!("dd, read only ({label})"),
            bytes,
            dd,
            Some(wc),
            dd_peak,
        );
        row(&format!("wc -l ({label})"), bytes, wc, None, wc_peak);
        let mut cases = vec![
            ("ndjson", vec!["--format", "ndjson", &f]),
            ("table", vec!["--format", "table", &f]),
            ("csv", vec!["--format", "csv", &f]),
        ];
        // Binary traces are read on one thread whatever -j says.
        if !label.starts_with("pcapng") && !label.starts_with("MF4") {
            cases.push(("ndjson -j1", vec!["--format", "ndjson", "-j1", &f]));
        }
        // Every frame counted and timed per id: its cost against the
        // default's on the same file (a build without the flag gets no row).
        if label == "candump log" || label.starts_with("bus:") {
            cases.push((
                "ndjson --timing",
                vec!["--format", "ndjson", "--timing", &f],
            ));
        }
        if label == DRIVES || label.starts_with("bus:") {
            let assume = "--assume-cia402-pdo";
            cases.push(("ndjson axis", vec!["--format", "ndjson", assume, &f]));
            cases.push((
                "ndjson -j1 axis",
                vec!["--format", "ndjson", "-j1", assume, &f],
            ));
        }
        let timed = cases.iter().any(|(case, _)| *case == "ndjson --timing");
        for (case, args) in cases {
            let ((t, peak), other) = measure_both(runs, &f, bin, compare.as_deref(), &args);
            row(
                &format!("emcy-decode {case} ({label})"),
                bytes,
                t,
                Some(wc),
                peak,
            );
            if let Some((o, other_peak)) = other {
                row(
                    &format!("  BENCH_COMPARE {case} ({label})"),
                    bytes,
                    o,
                    Some(wc),
                    other_peak,
                );
                println!(
                    "  this build's time: {:.3}x the other's",
                    t.as_secs_f64() / o.as_secs_f64()
                );
            }
        }
        if timed {
            let cost = timing_cost(runs, &f, bin, &["--format", "ndjson", &f]);
            println!("  --timing's time: {cost:.2}x the default ndjson's (runs interleaved)");
        }
        println!();
    }

    if chosen("MF4 DZ") {
        // The ceiling: inflating the file's DZ blocks (flate2, as the
        // reader does), nothing else; best of `runs`, in this process.
        let bytes = size(&mf4_dz);
        let f = path(&mf4_dz);
        let mut inflate = Duration::MAX;
        let mut inflated = 0;
        for _ in 0..runs {
            warm(&f);
            let start = Instant::now();
            inflated = inflate_dz_blocks(&mf4_dz);
            inflate = inflate.min(start.elapsed());
        }
        row("inflate DZ blocks (MF4 DZ)", bytes, inflate, None, 0);
        for (case, args) in [
            ("ndjson", vec!["--format", "ndjson", &f]),
            ("table", vec!["--format", "table", &f]),
        ] {
            let (t, peak) = measure(runs, &f, bin, &args);
            row(
                &format!("emcy-decode {case} (MF4 DZ)"),
                bytes,
                t,
                Some(inflate),
                peak,
            );
        }
        println!(
            "(MF4 DZ: {:.0} MB of records inflated)\n",
            inflated as f64 / 1e6
        );
    }

    if !chosen("gzip") {
        return;
    }
    let bytes = size(&gz);
    let g = path(&gz);
    let (gunzip, gpeak) = measure(runs, &g, "gzip", &["-dc", &g]);
    row("gzip -dc (gzip candump)", bytes, gunzip, None, gpeak);
    let (t, peak) = measure(runs, &g, bin, &["--format", "ndjson", &g]);
    row(
        "emcy-decode ndjson (gzip candump)",
        bytes,
        t,
        Some(gunzip),
        peak,
    );
    println!("\n(MB/s of the gzip rows are compressed bytes.)");
}

/// Inflates every DZ block of an MF4 file (walking its blocks by their
/// lengths): the bytes inflated.
fn inflate_dz_blocks(path: &Path) -> u64 {
    let data = std::fs::read(path).expect("read MF4");
    let mut at = 64usize;
    let mut total = 0u64;
    let mut out = Vec::new();
    while let Some(head) = data.get(at..at + 24) {
        let len = u64::from_le_bytes(head[8..16].try_into().unwrap()) as usize;
        if len < 24 {
            break;
        }
        if &head[..4] == b"##DZ" {
            let body = &data[at + 24..at + len];
            let original = u64::from_le_bytes(body[8..16].try_into().unwrap());
            out.clear();
            out.reserve(original as usize);
            flate2::read::ZlibDecoder::new(&body[24..])
                .read_to_end(&mut out)
                .expect("inflate");
            total += out.len() as u64;
        }
        at = (at + len).div_ceil(8) * 8;
    }
    total
}
