//! Output never depends on how the input was split or how many threads read
//! it: every trace below is decoded with one thread and with several, with
//! blocks from 1 byte to 1 MiB, and stdout and stderr must be identical.

use crate::analyze::Sink as Renderer;
use crate::analyze::{DiagnosticLog, Options, analyze};
use crate::report::ndjson::Ndjson;

fn run(trace: &[u8], threads: usize, block_size: usize) -> (String, String) {
    run_with(
        trace,
        Options {
            threads,
            block_size,
            ..base_options()
        },
    )
}

pub(super) fn base_options() -> Options {
    Options {
        max_line: 200,
        max_diagnostics: 5,
        ..Options::default()
    }
}

pub(super) fn run_with(trace: &[u8], opts: Options) -> (String, String) {
    let mut out = Vec::new();
    let mut err = Vec::new();
    {
        let mut renderer = Ndjson::new(&mut out, false);
        let mut log = DiagnosticLog::new(&mut err);
        let analysis = analyze("trace", trace, false, &opts, &mut renderer, &mut log)
            .expect("output to a Vec cannot fail");
        let collected = std::mem::take(&mut log.collected);
        renderer
            .finish(&[analysis.report], &collected)
            .expect("finish");
    }
    (
        String::from_utf8(out).unwrap(),
        String::from_utf8(err).unwrap(),
    )
}

fn assert_split_independent(name: &str, trace: &[u8]) {
    let reference = run(trace, 1, 1 << 20);
    assert!(
        reference.0.contains("\"type\":\"emcy\""),
        "{name}: no EMCY decoded"
    );
    for threads in [1, 2, 3] {
        for block in [1, 7, 64, 300, 4096, 1 << 20] {
            let got = run(trace, threads, block);
            assert_eq!(
                got.0, reference.0,
                "{name}: stdout, {threads} threads, {block}-byte blocks"
            );
            assert_eq!(
                got.1, reference.1,
                "{name}: stderr, {threads} threads, {block}-byte blocks"
            );
        }
    }
}

fn candump_trace() -> Vec<u8> {
    let mut t = Vec::new();
    t.extend(b"# comment\n");
    for i in 0..300u32 {
        let node = 1 + i % 5;
        match i % 11 {
            0 => t.extend(
                format!(
                    "({}.000100) can0 {:03X}#1043090100000000\n",
                    1000 + i,
                    0x80 + node
                )
                .bytes(),
            ),
            1 => t.extend(
                format!(
                    "({}.000200) can0 {:03X}#0000000000000000\r\n",
                    1000 + i,
                    0x80 + node
                )
                .bytes(),
            ),
            2 => t.extend(b"garbage that is not a frame\n"),
            3 => {
                t.extend(vec![b'x'; 250 + i as usize]);
                t.push(b'\n');
            }
            4 => t.extend(
                format!(
                    "  can0  {:03X}   [8]  10 23 03 00 00 00 00 00\n",
                    0x80 + node
                )
                .bytes(),
            ),
            5 => t.extend(format!("({}.5) can0 70{node}#00\n", 1000 + i).bytes()),
            6 => t.extend(format!("({}.5) can0 08{node}#10\n", 1000 + i).bytes()),
            _ => t.extend(
                format!(
                    "({}.000300) can1 181#{:016X}\n",
                    1000 + i,
                    u64::from(i) * 7919
                )
                .bytes(),
            ),
        }
    }
    t.extend(b"(2000.0) can0 081#1043090100000000"); // no final newline
    t
}

#[test]
fn candump_log_with_garbage_long_lines_and_pasted_screen_lines() {
    assert_split_independent("candump", &candump_trace());
}

fn asc_trace(relative: bool) -> Vec<u8> {
    let mut t = Vec::new();
    let mode = if relative { "relative" } else { "absolute" };
    t.extend(format!("date Tue Nov 14 22:13:20.000 2023\nbase hex  timestamps {mode}\n").bytes());
    for i in 0..400u32 {
        if i == 200 {
            // A second recording appended: decimal from here on.
            t.extend(format!("base dec  timestamps {mode}\n").bytes());
        }
        let time = if relative {
            "0.001000".to_string()
        } else {
            format!("{}.{:06}", i / 10, i % 10)
        };
        let dec = i >= 200;
        let id = 0x81 + i % 3;
        let id_text = if dec {
            id.to_string()
        } else {
            format!("{id:X}")
        };
        let bytes = if i % 2 == 0 {
            [0x10, 0x43, 0x09, 0x01]
        } else {
            [0, 0, 0, 0]
        };
        let data: Vec<String> = bytes
            .iter()
            .map(|b| {
                if dec {
                    b.to_string()
                } else {
                    format!("{b:02X}")
                }
            })
            .collect();
        t.extend(format!("{time:>11} 1  {id_text:<15} Rx   d 4 {}\n", data.join(" ")).bytes());
        if i % 50 == 7 {
            t.extend(b"   9.999 1  not an asc line at all\n");
        }
        if i % 40 == 9 {
            // FD by its 12 bytes, classic by its flags: a frame and a
            // warning, which shares the diagnostics limit.
            let zeros = " 0".repeat(12);
            t.extend(format!("{time:>11} CANFD 1 Rx 100 0 0 9 12{zeros} 1 1 0\n").bytes());
        }
    }
    t.extend(b"End TriggerBlock\n");
    t
}

#[test]
fn asc_with_a_base_change_in_the_middle() {
    let trace = asc_trace(false);
    // The decimal half must decode as decimal (ids 129.. are 0x81..).
    let (out, err) = run(&trace, 1, 1 << 20);
    assert_eq!(out.matches("\"type\":\"emcy\"").count(), 400);
    assert!(err.contains("lack FDF 1000"), "{err}");
    assert_split_independent("asc absolute", &trace);
}

#[test]
fn asc_with_relative_times() {
    assert_split_independent("asc relative", &asc_trace(true));
}

/// The error history goes to a temporary file past a threshold; what is
/// reported must not change. Table and ndjson both read it back.
/// EMCY frames that raise and clear errors in turn (register and code
/// change with `i % 4`); `at(i)` gives the node and channel of line `i`.
fn raising_and_clearing(lines: u32, at: impl Fn(u32) -> (u32, &'static str)) -> Vec<u8> {
    let mut trace = Vec::new();
    for i in 0..lines {
        let (node, ch) = at(i);
        let data = match i % 4 {
            0 => "1043090100000000",
            1 => "1023030000000000",
            2 => "0000090000000000",
            _ => "0000000000000000",
        };
        trace.extend(
            format!(
                "({}.{:06}) {ch} {:03X}#{data}\n",
                1000 + i / 10,
                i,
                0x80 + node
            )
            .bytes(),
        );
    }
    trace
}

/// Stdout of `renderer` (made over the output buffer) after reading `trace`.
fn report_with<'o>(
    trace: &[u8],
    opts: &Options,
    out: &'o mut Vec<u8>,
    renderer: impl FnOnce(&'o mut Vec<u8>) -> Box<dyn Renderer + 'o>,
) {
    let mut err = Vec::new();
    let mut r = renderer(out);
    let mut log = DiagnosticLog::new(&mut err);
    let a = analyze("trace", trace, false, opts, r.as_mut(), &mut log).unwrap();
    r.finish(&[a.report], &[]).unwrap();
}

fn spilling_every(spill_at: usize) -> Options {
    Options {
        spill_at,
        ..base_options()
    }
}

#[test]
fn error_history_on_disk_reads_back_identically() {
    let trace = raising_and_clearing(2000, |i| {
        (1 + i % 7, if i % 3 == 0 { "can1" } else { "can0" })
    });
    let reference = run_with(&trace, base_options());
    let closed = reference.0.matches("\"cleared_by\":\"").count();
    assert!(closed > 300, "only {closed} closed errors");
    for spill_at in [1, 3, 100] {
        let got = run_with(&trace, spilling_every(spill_at));
        assert_eq!(got, reference, "spill every {spill_at}");
    }
    // The table reads the history twice (widths, then rows).
    let table = |spill_at| {
        let mut out = Vec::new();
        report_with(&trace, &spilling_every(spill_at), &mut out, |o| {
            Box::new(crate::report::table::TableReport::new(o, false, false))
        });
        String::from_utf8(out).unwrap()
    };
    assert_eq!(table(2), table(usize::MAX));
}

/// Node objects list every error; with more than one thread their errors
/// are rendered by helpers in batches (1024 errors each) and written in
/// order: byte for byte what one thread writes, also from a spilled history.
#[test]
fn node_errors_rendered_on_helper_threads_are_identical() {
    // Node 3 raises and clears ~3000 errors (three batches and a bit),
    // nodes 4 and 5 a few, on two channels.
    let trace = raising_and_clearing(12_000, |i| match i % 10 {
        0 => (4, "can1"),
        1 => (5, "can0"),
        _ => (3, "can0"),
    });
    let render = |threads: usize, spill_at: usize| {
        let mut out = Vec::new();
        report_with(&trace, &spilling_every(spill_at), &mut out, |o| {
            Box::new(Ndjson::new(o, false).threads(threads))
        });
        String::from_utf8(out).unwrap()
    };
    let reference = render(1, usize::MAX);
    let node3 = reference
        .lines()
        .find(|l| l.contains("\"type\":\"node\"") && l.contains("\"node\":3,"))
        .expect("node 3");
    let errors = node3.matches("\"cleared_by\":").count();
    assert!(errors > 3 * 1024, "only {errors} errors for node 3");
    for threads in [2, 3] {
        for spill_at in [usize::MAX, 500] {
            assert!(
                render(threads, spill_at) == reference,
                "{threads} threads, spill every {spill_at}"
            );
        }
    }
}

/// An SDO write to 0x1014 moves node 5's EMCY id mid-trace: frames on the new
/// id before the confirmation are plain frames, after it EMCYs, however the
/// blocks fall (workers parse with the old set of wanted ids and the block
/// holding the write is classified again in order).
#[test]
fn emcy_id_moved_by_sdo_mid_trace() {
    let mut trace = Vec::new();
    for i in 0..600u32 {
        let t = 1000 + i;
        match i {
            300 => trace.extend(format!("({t}.0) can0 605#23141000F5030000\n").bytes()),
            301 => trace.extend(format!("({t}.0) can0 585#6014100000000000\n").bytes()),
            _ => {
                let data = if i % 2 == 0 {
                    "1043090000000000"
                } else {
                    "0000000000000000"
                };
                trace.extend(format!("({t}.0) can0 3F5#{data}\n").bytes());
                if i % 10 == 0 {
                    trace.extend(format!("({t}.5) can0 085#{data}\n").bytes());
                }
            }
        }
    }
    let (out, _) = run(&trace, 1, 1 << 20);
    // (The channel object lists 0x3F5 too, with its frame count.)
    let on_moved = out
        .lines()
        .filter(|l| !l.contains("\"type\":\"channel\""))
        .map(|l| l.matches("\"cob_id\":1013").count())
        .sum::<usize>();
    assert_eq!(on_moved, 298, "EMCYs on 0x3F5 after the write");
    assert_split_independent("moved emcy id", &trace);
}

/// SDO traffic for objects the decoder does not follow only moves the
/// input's first and last time (workers collapse it); heartbeats are
/// decoded and the SDO upload of a vendor id still chooses the profile.
/// Here they come first and last, and in runs across block boundaries.
#[test]
fn heartbeats_and_other_sdo_traffic_only_move_the_time_span() {
    let mut t = Vec::new();
    t.extend(b"(999.250000) can0 705#05\n");
    for i in 0..400u32 {
        let time = format!("({}.{:06})", 1000 + i / 10, i);
        let line = match i % 8 {
            0 => format!("{time} can0 705#05\n"),
            1 => format!("{time} can0 605#4000600000000000\n"),
            2 => format!("{time} can0 585#4B00600000020000\n"),
            3 if i == 3 => format!("{time} can0 585#43181001B9000000\n"),
            4 => format!("{time} can0 085#1043090100000000\n"),
            5 => format!("{time} can0 085#0000000000000000\n"),
            6 if i % 48 == 6 => format!("{time} can0 705#00\n"),
            _ => format!("{time} can0 183#0102\n"),
        };
        t.extend(line.bytes());
    }
    t.extend(b"(2000.125000) can0 605#2340600006000000\n");
    assert_split_independent("heartbeats", &t);
    let (out, _) = run(&t, 2, 64);
    assert!(
        out.contains("\"first_time\":999.250000,") && out.contains("\"last_time\":2000.125000,"),
        "{out}"
    );
    assert!(
        out.contains("\"profile\":\"stoeber\""),
        "vendor id 0xB9 read"
    );
    assert!(out.contains("\"type\":\"boot\""));
}

/// The NMT and heartbeat commissioning fixture: heartbeats, guarding requests and
/// replies, NMT commands, 1003h read-outs, aborts and a read-out the input
/// ends in, split anywhere: deadlines, guarding and read-outs carry across
/// blocks, and the events are the same.
#[test]
fn nmt_heartbeats_and_error_history_across_blocks() {
    let trace = include_bytes!("../../../fixtures/commissioning.log");
    assert_split_independent("commissioning", trace);
    let (out, err) = run(trace, 2, 64);
    for t in [
        "heartbeat_lost",
        "heartbeat_back",
        "error_history",
        "sdo_abort",
    ] {
        assert!(out.contains(&format!("\"type\":\"{t}\"")), "{t}");
    }
    assert!(out.contains("\"via\":\"guarding\""));
    assert!(err.contains("toggle bit error"), "{err}");
}

/// Error frames, split anywhere and on any thread count: bursts close on
/// the same frame, and a node's bus-off is found from the same silence.
#[test]
fn error_bursts_and_bus_offs_across_blocks() {
    let trace = include_bytes!("../../../fixtures/bus-off.log");
    assert_split_independent("bus-off", trace);
    let (out, _) = run(trace, 2, 64);
    assert_eq!(out.matches("\"type\":\"bus_error\"").count(), 3, "{out}");
    assert_eq!(out.matches("\"type\":\"bus_off\"").count(), 3, "{out}");
}

/// The network fixtures (a reset scan of absent ids, node guarding, the
/// command grace), split anywhere: what the master sent to ids that had
/// not spoken yet, a guard request waiting and a command waiting carry
/// across blocks, and ids that never spoke stay no nodes.
#[test]
fn nodes_exist_when_they_speak_across_blocks() {
    let traces: [(&str, &[u8]); 3] = [
        (
            "reset scan",
            include_bytes!("../../../fixtures/network-reset-scan.log"),
        ),
        (
            "guarding",
            include_bytes!("../../../fixtures/network-guarding.log"),
        ),
        (
            "grace",
            include_bytes!("../../../fixtures/network-nmt-grace.log"),
        ),
    ];
    for (name, trace) in traces {
        let reference = run(trace, 1, 1 << 20);
        for threads in [1, 2, 3] {
            for block_size in [64, 333, 4096] {
                assert_eq!(
                    run(trace, threads, block_size),
                    reference,
                    "{name}: {threads} threads, blocks of {block_size}"
                );
            }
        }
    }
    let (scan, err) = run(traces[0].1, 2, 64);
    let nodes = scan.matches("\"type\":\"node\"").count();
    assert_eq!(nodes, 3, "only the ids that spoke");
    assert!(!scan.contains("\"state\":\"initialising\""), "{scan}");
    assert!(
        scan.contains("\"nmt_unanswered\":[{\"request\":\"reset_node\",\"sent\":248,\"ids\":124}]"),
        "{scan}"
    );
    assert!(
        err.contains("trace:315: NMT reset node sent 248 times to 124 ids that never answered (the first at line 1)"),
        "{err}"
    );
    let (guarded, err) = run(traces[1].1, 2, 64);
    assert!(guarded.contains("\"timeout_source\":\"life_time\",\"via\":\"guarding\""));
    assert!(err.contains("toggle bit error"), "{err}");
    let (_, err) = run(traces[2].1, 2, 64);
    assert_eq!(err.matches("ignored the NMT command").count(), 1, "{err}");
    // Guarded before it ever spoke: its first frame answers the request
    // waiting, so it is a guarding reply, not a heartbeat.
    let first_reply = b"(1.000000) can0 70B#R\n(1.001000) can0 70B#05\n\
        (1.100000) can0 70B#R\n(1.101000) can0 70B#85\n";
    let (out, err) = run(first_reply, 1, 1 << 20);
    assert!(
        out.contains("\"node\":11,\"state\":\"operational\",\"via\":\"guarding\""),
        "{out}"
    );
    assert!(err.is_empty(), "{err}");
}

/// A drive's TPDO made valid by a segmented download of its COB-ID, its
/// statuswords right after the confirmation (the interest widens between
/// two frames of one block): split anywhere, with any number of threads,
/// the PDOs are decoded the same.
#[test]
fn a_segmented_download_completing_a_mapping_across_blocks() {
    let frames = [
        "605#2300180185010080", // TPDO1 COB-ID 0x185, not valid yet
        "585#6000180100000000",
        "605#2F001A0000000000",
        "585#60001A0000000000",
        "605#23001A0110004160", // the statusword, 16 bits
        "585#60001A0100000000",
        "605#2F001A0001000000",
        "585#60001A0000000000",
        "605#2100180104000000", // segmented: 4 bytes
        "585#6000180100000000",
        "605#0785010000000000", // the last segment: 0x00000185, valid
        "585#2000000000000000",
        "185#4002",
        "185#2102",
        "185#3302",
        "185#3702",
        "085#1032010000000000", // an EMCY (the split check wants one)
    ];
    let trace: String = frames
        .iter()
        .enumerate()
        .map(|(i, f)| format!("(1700000000.{:06}) can0 {f}\n", i * 1000))
        .collect();
    assert_split_independent("segmented COB-ID", trace.as_bytes());
    let (out, _) = run(trace.as_bytes(), 2, 64);
    assert_eq!(out.matches("\"type\":\"axis_state\"").count(), 4, "{out}");
}

/// The drive commissioning fixture: PDO mappings learnt mid-trace (one
/// COB-ID by a segmented download) widen the interest; split anywhere, the
/// drive's states, fault and fault reset are the same. The unknown-mapping
/// trace's watched ids too.
#[test]
fn cia402_mappings_learnt_mid_trace_across_blocks() {
    let trace = include_bytes!("../../../fixtures/cia402-commissioning.log");
    assert_split_independent("cia402 commissioning", trace);
    let (out, _) = run(trace, 2, 64);
    assert_eq!(out.matches("\"type\":\"axis_state\"").count(), 10);
    assert_eq!(out.matches("\"type\":\"fault_reset\"").count(), 1);
    let unknown = include_bytes!("../../../fixtures/cia402-unknown.log");
    let reference = run(unknown, 1, 1 << 20);
    assert!(
        reference.1.contains("mapping is unknown"),
        "{}",
        reference.1
    );
    for (threads, block) in [(2, 64), (3, 300), (2, 7)] {
        assert_eq!(run(unknown, threads, block), reference);
    }
}

/// The input's span runs from its first frame to its last, decoded or
/// not, however the input is split and however many threads read it: here
/// both ends are frames nobody decodes, behind comments.
#[test]
fn the_span_reaches_the_frames_nobody_decodes_at_both_ends() {
    let mut trace = b"# recorded on the test bench\n(500.250000) can1 181#00\n".to_vec();
    trace.extend(candump_trace());
    trace.extend(b"\n(2500.750000) can1 381#0102\n# end of recording\n");
    for threads in [1, 2, 3] {
        for block in [1, 7, 64, 300, 4096, 1 << 20] {
            let (out, _) = run(&trace, threads, block);
            let input = out.lines().last().expect("the input object");
            assert!(
                input.contains("\"first_time\":500.250000,")
                    && input.contains("\"last_time\":2500.750000,"),
                "{threads} threads, {block}-byte blocks: {input}"
            );
        }
    }
}

/// Reads `trace` as [`run_with`] does and gives how it was read too.
fn reading_of(trace: &[u8], threads: usize, block_size: usize) -> crate::analyze::Reading {
    let opts = Options {
        threads,
        block_size,
        ..base_options()
    };
    let mut renderer = Ndjson::new(Vec::new(), false);
    let mut log = DiagnosticLog::new(Vec::new());
    analyze("trace", trace, false, &opts, &mut renderer, &mut log)
        .expect("output to a Vec cannot fail")
        .reading
}

/// A master that uploads node 5's identity in segments over and over: each
/// transfer takes the node's SDO ids out of the content filter and puts
/// them back, so blocks the workers parsed before keep being read again.
/// The consumer stops the workers and reads the rest alone; the output is
/// still that of one thread.
#[test]
fn blocks_read_twice_too_often_fall_back_to_one_thread() {
    let mut trace = Vec::new();
    for i in 0..3000u32 {
        let t = 1000 + i;
        let frames: &[&str] = match i % 6 {
            0 => &["605#4018100400000000", "585#4118100404000000"],
            1 => &["605#6000000000000000", "585#0B11223344000000"],
            _ if i % 50 == 7 => &["085#1043090000000000"],
            _ if i % 50 == 8 => &["085#0000000000000000"],
            _ => &["185#3702"],
        };
        for f in frames {
            trace.extend(format!("({t}.0) can0 {f}\n").bytes());
        }
    }
    let reference = run(&trace, 1, 1 << 20);
    for (threads, block) in [(2, 300), (3, 64)] {
        assert_eq!(
            run(&trace, threads, block),
            reference,
            "{threads} threads, {block}"
        );
        let reading = reading_of(&trace, threads, block);
        assert!(reading.fell_back, "{reading:?}");
        assert!(reading.blocks >= 64, "{reading:?}");
    }
    // A trace without such transfers keeps its workers.
    let calm = candump_trace();
    let reading = reading_of(&calm, 2, 64);
    assert!(!reading.fell_back && reading.workers == 2, "{reading:?}");
    assert_eq!(reading.blocks_read_again + reading.rests_read_again, 0);
}

/// Incidents, split anywhere and read on several threads: the same
/// incidents with the same roots, told at the same place in the output
/// (an incident closes on events, which come in one order however the
/// input is split).
#[test]
fn incidents_across_blocks() {
    let traces: [(&str, &[u8], usize); 5] = [
        (
            "silent producer",
            include_bytes!("../../../fixtures/incident-silent-producer.log"),
            1,
        ),
        (
            "repeated",
            include_bytes!("../../../fixtures/incident-repeated.log"),
            2,
        ),
        (
            "rpdo timeout",
            include_bytes!("../../../fixtures/incident-rpdo-timeout.log"),
            1,
        ),
        (
            "under-voltage",
            include_bytes!("../../../fixtures/incident-undervoltage.log"),
            1,
        ),
        // A SYNC error (SYNC itself is followed only with --timing).
        (
            "sync gaps",
            include_bytes!("../../../fixtures/sync-gaps.log"),
            1,
        ),
    ];
    for (name, trace, incidents) in traces {
        assert_split_independent(name, trace);
        let (out, _) = run(trace, 3, 300);
        assert_eq!(
            out.matches("\"type\":\"incident\"").count(),
            incidents,
            "{name}: {out}"
        );
    }
}

/// `--timing` and a bit rate, split anywhere and read on several threads:
/// every frame counted and timed once, the same channel objects and the
/// same events as without the flag.
#[test]
fn timing_across_blocks() {
    let trace = include_bytes!("../../../fixtures/sync-gaps.log");
    let timed = |threads, block_size| {
        run_with(
            trace,
            Options {
                threads,
                block_size,
                timing: true,
                bit_rate: Some(500_000),
                ..base_options()
            },
        )
    };
    let reference = timed(1, 1 << 20);
    assert!(reference.0.contains("\"frames\":932"), "{}", reference.0);
    for threads in [1, 2, 3] {
        for block in [1, 64, 300, 4096] {
            assert_eq!(
                timed(threads, block),
                reference,
                "{threads} threads, {block}-byte blocks"
            );
        }
    }
    let without = run(trace, 1, 1 << 20).0;
    // The same but for what SYNC's gaps add.
    let events = |out: &str| -> Vec<String> {
        out.lines()
            .filter(|l| {
                !["channel", "sync_missed", "incident"]
                    .iter()
                    .any(|t| l.starts_with(&format!("{{\"type\":\"{t}\"")))
            })
            .map(str::to_string)
            .collect()
    };
    assert!(reference.0.contains("\"type\":\"sync_missed\""));
    assert_eq!(
        events(&reference.0),
        events(&without),
        "the analysis is the same"
    );
}

/// A node's identity, split anywhere and read on several threads: the
/// segmented upload of its name widens the interest mid-block, and the
/// texts and values come out the same.
#[test]
fn identity_across_blocks() {
    let trace = include_bytes!("../../../fixtures/identity.log");
    let reference = same_on_any_split(trace);
    assert!(
        reference.contains("\"name\":{\"value\":\"AKD Servo Drive\""),
        "{reference}"
    );
}

/// The output of `trace` on one thread in one block, checked to be the
/// same on 1-3 threads in blocks of 1 byte to 4 KiB.
fn same_on_any_split(trace: &[u8]) -> String {
    let reference = run(trace, 1, 1 << 20).0;
    for threads in [1, 2, 3] {
        for block in [1, 7, 64, 300, 4096] {
            assert_eq!(
                run(trace, threads, block).0,
                reference,
                "{threads} threads, {block}-byte blocks"
            );
        }
    }
    reference
}

/// Every kind of SDO transfer, split anywhere and read on several threads:
/// short segmented transfers take their node's ids out of the filter
/// mid-block, the long one does not, unanswered ones are told when their
/// timeout passes; the events come out the same.
#[test]
fn sdo_transfers_across_blocks() {
    let reference = same_on_any_split(include_bytes!("../../../fixtures/sdo-startup.log"));
    assert_eq!(reference.matches("\"type\":\"sdo\"").count(), 18);
}
