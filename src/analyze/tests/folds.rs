//! Folding (the candump reader taking runs of steady heartbeats whole, see
//! `trace::fold`) never changes the output: each trace below is decoded
//! with folding and without it, with one thread and two, in blocks of many
//! sizes, and stdout and stderr must be identical. The traces are made so
//! that the consumer both takes folded runs and refuses them (a node lost
//! while the others beat, state changes, NMT commands, a boot-up, a clock
//! that goes back, a timeout shorter than the period), which the tally
//! checks: a test of only one path could not fail on the other.

use super::parallel::{base_options, run_with};
use crate::analyze::Options;
use crate::analyze::fold::fold_tally;
use crate::analyze::interest::set_folding;
use crate::trace::Span;

/// A small deterministic generator (the traces must be the same every run).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.0 >> 33
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// What a trace of `nodes` heartbeating nodes does besides beating.
#[derive(Clone, Copy, Default)]
struct Twists {
    /// Node 3 falls silent for this many periods from period 40.
    silence: u64,
    /// Node 3 stays silent from period 60 to the end.
    dies: bool,
    /// Node 2 goes pre-operational at period 30 and back at 50, an NMT
    /// command to all at 45, node 4 boots at 55 and again at 56.
    nmt: bool,
    /// The clock goes back by a second at period 70.
    clock_back: bool,
    /// A second channel with the same nodes.
    two_channels: bool,
    /// One heartbeat slot in this many has an EMCY after it (EMCYs stay
    /// inside the reader's runs); 0: one in 60.
    emcy_every: u64,
    /// The EMCYs' times are this many microseconds ahead of the lines
    /// around them (a gateway stamping them with its own clock): at one,
    /// reading line by line finds nodes lost that the heartbeats after it
    /// show back.
    emcy_ahead: u64,
}

/// `periods` heartbeat periods of 100 ms with jitter, `nodes` nodes, PDO and
/// SDO traffic between, an EMCY now and then (runs end at them).
fn trace(seed: u64, nodes: u32, periods: u64, twists: Twists) -> Vec<u8> {
    let mut rng = Lcg(seed);
    let mut t = Vec::new();
    let mut clock: u64 = 1_700_000_000_000_000; // microseconds
    let channels: &[&str] = if twists.two_channels {
        &["can0", "can1"]
    } else {
        &["can0"]
    };
    let line = |t: &mut Vec<u8>, clock: u64, channel: &str, frame: &str| {
        t.extend(
            format!(
                "({}.{:06}) {channel} {frame}\n",
                clock / 1_000_000,
                clock % 1_000_000
            )
            .bytes(),
        );
    };
    line(&mut t, clock, "can0", "085#1043090100000000");
    for period in 0..periods {
        if twists.clock_back && period == 70 {
            clock -= 1_000_000;
        }
        if twists.nmt && period == 45 {
            line(&mut t, clock, "can0", "000#0100");
        }
        for node in 1..=nodes {
            for &channel in channels {
                clock += 100_000 / u64::from(nodes * channels.len() as u32) + rng.below(500);
                let silent = node == 3
                    && ((40..40 + twists.silence).contains(&period)
                        || (twists.dies && period >= 60));
                if !silent {
                    let state = match (twists.nmt, node, period) {
                        (true, 2, 30..50) => "7F",
                        (true, 4, 55..57) => "00",
                        _ => "05",
                    };
                    line(
                        &mut t,
                        clock,
                        channel,
                        &format!("{:03X}#{state}", 0x700 + node),
                    );
                }
                for _ in 0..rng.below(4) {
                    clock += rng.below(200);
                    let frame = match rng.below(10) {
                        0 => format!("{:03X}#4000600000000000", 0x600 + rng.below(8) + 1),
                        1 => format!("{:03X}#4B00200037060000", 0x580 + rng.below(8) + 1),
                        _ => format!("{:03X}#1122334455667788", 0x180 + rng.below(8) + 1),
                    };
                    line(&mut t, clock, channel, &frame);
                }
                if rng.below(if twists.emcy_every == 0 {
                    60
                } else {
                    twists.emcy_every
                }) == 0
                {
                    let at = clock + twists.emcy_ahead;
                    line(&mut t, at, channel, "085#1043090100000000");
                }
            }
        }
    }
    t
}

/// Decodes `t` with folding and without, threads 1 and 2, blocks from 64
/// bytes to 1 MiB (runs of a line or two, of a period or a few, of the
/// whole trace): all the same, with `--timing` (every frame timed, the
/// folded ones as the lines the reader hands over) and without. Returns
/// the tally of folded runs taken and refused over the runs with folding.
fn assert_fold_independent(name: &str, t: &[u8], opts: &Options) -> (u64, u64) {
    // With `--timing` first: the frames kept inside runs (none then) are
    // tallied for the caller without it.
    let timed = assert_fold_independent_as(&format!("{name}, --timing"), t, opts, true);
    assert!(timed.0 + timed.1 > 0, "{name}: no run folded with --timing");
    let (taken, refused) = assert_fold_independent_as(name, t, opts, false);
    (taken + timed.0, refused + timed.1)
}

fn assert_fold_independent_as(name: &str, t: &[u8], opts: &Options, timing: bool) -> (u64, u64) {
    let with = |threads, block_size| Options {
        threads,
        block_size,
        heartbeat_timeout: opts.heartbeat_timeout,
        assume_cia402_pdo: opts.assume_cia402_pdo,
        timing,
        ..base_options()
    };
    set_folding(false);
    let reference = run_with(t, with(1, 1 << 20));
    set_folding(true);
    assert!(
        reference.0.contains("\"type\":\"emcy\""),
        "{name}: no EMCY decoded"
    );
    fold_tally::take();
    fold_tally::take_inner();
    let mut tally = (0, 0);
    for threads in [1, 2] {
        for block in [64, 4096, 16 << 10, 1 << 20] {
            let got = run_with(t, with(threads, block));
            assert_eq!(
                got.0, reference.0,
                "{name}: stdout, {threads} threads, {block}"
            );
            assert_eq!(
                got.1, reference.1,
                "{name}: stderr, {threads} threads, {block}"
            );
            let (taken, refused) = fold_tally::take();
            tally = (tally.0 + taken, tally.1 + refused);
        }
    }
    tally
}

/// An unanswered SDO transfer is told before the events after its timeout,
/// folding or not (the fold paths leave it to the next frame the frame
/// path reads, which tells it before its own events).
#[test]
fn unanswered_sdo_transfers_are_told_on_the_same_frame_with_folds() {
    let (taken, refused) = assert_fold_independent(
        "sdo-startup",
        include_bytes!("../../../fixtures/sdo-startup.log"),
        &base_options(),
    );
    assert!(taken + refused > 0, "{taken} taken, {refused} refused");
    // Four nodes beating every 100 ms for 10 s; node 1 is asked at 2.05 s
    // and never answers, and raises an EMCY at 3.15 s, after the timeout
    // passed (3.05 s): runs of heartbeats (with the EMCY inside) fold on
    // either side of it, and the transfer is told before the EMCY.
    let mut t: Vec<u8> = Vec::new();
    for tick in 0..100u32 {
        for node in 1..=4u32 {
            let at = format!("({}.{:03}0)", 1000 + tick / 10, tick % 10 * 100 + node);
            t.extend(format!("{at} can0 {:03X}#05\n", 0x700 + node).bytes());
        }
        if tick == 20 {
            t.extend(b"(1002.0500) can0 601#4000100000000000\n");
        }
        if tick == 31 {
            t.extend(b"(1003.1500) can0 081#1043090000000000\n");
        }
    }
    let (taken, _) = assert_fold_independent("unanswered", &t, &base_options());
    assert!(taken > 0, "runs folded");
    let out = run_with(&t, base_options()).0;
    let told = |what: &str| out.find(what).unwrap_or(usize::MAX);
    assert!(
        told("\"type\":\"sdo\"") < told("\"type\":\"emcy\""),
        "{out}"
    );
}

/// A burst of error frames closes where the frame path closes it, folding
/// or not: a run of steady heartbeats past the burst's end is refused.
#[test]
fn error_bursts_close_on_the_same_frame_with_folds() {
    let t = include_bytes!("../../../fixtures/bus-off.log");
    let (taken, refused) = assert_fold_independent("bus-off", t, &base_options());
    assert!(taken > 0 && refused > 0, "{taken} taken, {refused} refused");
}

#[test]
fn steady_heartbeats_are_folded_and_give_what_they_give_one_by_one() {
    let t = trace(1, 32, 40, Twists::default());
    let (taken, _) = assert_fold_independent("steady", &t, &base_options());
    assert!(taken > 50, "folded runs taken: {taken}");
    // EMCYs inside the runs taken after their folds.
    assert!(fold_tally::take_inner() > 20);
}

/// EMCYs stay inside the reader's runs; the consumer takes them after the
/// run's folds only when that gives what line by line order gives. An
/// EMCY stamped ahead of the lines after it ends its run (a run's times
/// only go forward), and one a second ahead finds every node lost there.
#[test]
fn emcys_inside_runs_are_taken_as_in_line_order() {
    for (seed, emcy_ahead, emcy_every) in [(13, 0, 5), (14, 1_000, 5), (15, 1_000_000, 20)] {
        let twists = Twists {
            emcy_ahead,
            emcy_every,
            ..Twists::default()
        };
        let mut t = trace(seed, 8, 60, twists);
        // The last line an EMCY right after the last line, taken after
        // the run's folds: its time is the input's last.
        let text = String::from_utf8_lossy(&t).into_owned();
        let last = text.lines().last().and_then(|l| l.get(1..18)).unwrap_or("");
        let micros: u64 = last.replace('.', "").parse().unwrap_or(0) + 100;
        let end = format!(
            "({}.{:06}) can0 085#0000000000000000\n",
            micros / 1_000_000,
            micros % 1_000_000
        );
        t.extend_from_slice(end.as_bytes());
        let (taken, _) = assert_fold_independent("EMCYs", &t, &base_options());
        assert!(taken > 0, "{seed}");
        // A second ahead, every run with an EMCY is refused: the nodes
        // are lost at it.
        let far_ahead = emcy_ahead == 1_000_000;
        let inner = fold_tally::take_inner();
        assert_eq!(
            inner == 0,
            far_ahead,
            "{seed}: {inner} taken after the folds"
        );
        let (out, err) = run_with(&t, base_options());
        assert_eq!(
            out.contains("\"type\":\"heartbeat_lost\""),
            far_ahead,
            "{seed}"
        );
        // The heartbeats after it end those outages before they began.
        assert_eq!(
            err.contains("ends a heartbeat outage that began later"),
            far_ahead,
            "{seed}: {err}"
        );
    }
}

#[test]
fn a_node_lost_while_others_beat_is_found_where_it_was_one_by_one() {
    // (seed, periods silent, EMCY every, silent to the end): long runs
    // (EMCYs rare) hold a node's gap inside one fold; the last case goes
    // silent after its last heartbeat of a run while the others beat on.
    let cases = [
        (2, 5, 0, false),
        (3, 30, 0, false),
        (6, 4, 600, false),
        (7, 8, 600, false),
        (8, 0, 600, true),
    ];
    for (seed, silence, emcy_every, dies) in cases {
        let twists = Twists {
            silence,
            emcy_every,
            dies,
            ..Twists::default()
        };
        let t = trace(seed, 8, 100, twists);
        let (taken, refused) = assert_fold_independent("silence", &t, &base_options());
        assert!(
            taken > 0 && refused > 0,
            "{silence}: {taken} taken, {refused} refused"
        );
        let (out, _) = run_with(&t, base_options());
        assert!(out.contains("\"type\":\"heartbeat_lost\""), "{silence}");
    }
}

/// State changes, an NMT command the node ignores, a boot-up, the clock
/// going back and silence to the end; with runs of a few lines (a state
/// change is then often a node's first heartbeat of a run, its fold
/// refused) and of many, on one channel and on two (lines of two
/// channels alternating end the reader's runs at every line).
#[test]
fn nmt_changes_boot_ups_clock_jumps_and_silence_to_the_end() {
    for (seed, emcy_every, two_channels) in [(4, 0, true), (9, 3, false), (10, 40, false)] {
        let twists = Twists {
            dies: true,
            nmt: true,
            clock_back: true,
            two_channels,
            emcy_every,
            ..Twists::default()
        };
        let t = trace(seed, 6, 90, twists);
        let (taken, refused) = assert_fold_independent("twists", &t, &base_options());
        assert!(
            taken > 0 && refused > 0,
            "{seed}: {taken} taken, {refused} refused"
        );
        let (out, err) = run_with(&t, base_options());
        assert!(out.contains("\"state\":\"pre_operational\""), "{seed}");
        assert!(out.contains("\"via\":\"boot_up\""), "{seed}");
        assert!(out.contains("\"silent_at_end\":true"), "{seed}");
        assert!(err.contains("ignored the NMT command"), "{seed}: {err}");
        assert!(err.contains("clock went backwards"), "{seed}: {err}");
    }
}

#[test]
fn a_timeout_shorter_than_the_period_refuses_every_fold() {
    let opts = Options {
        heartbeat_timeout: Some(Span::from_millis(50)),
        ..base_options()
    };
    let t = trace(5, 4, 30, Twists::default());
    let (taken, refused) = assert_fold_independent("short timeout", &t, &opts);
    assert_eq!(taken, 0, "every heartbeat is an outage's end");
    assert!(refused > 0);
}

/// Drives sending TPDO1 (statusword and position) every millisecond, the
/// statusword's bits 10 and 12 toggling, a fault with its EMCY and a
/// reset on RPDO1, heartbeats between: PDO repeats are folded with the
/// heartbeats, and the drive ends on the last statusword sent.
fn drive_trace(seed: u64, drives: u32, millis: u64, emcy_every: u64) -> Vec<u8> {
    let mut rng = Lcg(seed);
    let mut t = Vec::new();
    let mut clock: u64 = 1_700_000_000_000_000;
    let mut line = |clock: u64, frame: String| {
        t.extend(
            format!(
                "({}.{:06}) can0 {frame}\n",
                clock / 1_000_000,
                clock % 1_000_000
            )
            .bytes(),
        );
    };
    line(clock, "085#1043090100000000".into());
    for ms in 0..millis {
        for d in 1..=drives {
            clock += 1_000 / u64::from(drives);
            let toggles = ((ms / 25) % 4) as u16;
            let mut word = 0x0637u16 | (toggles & 1) << 10 | (toggles >> 1) << 12;
            // Drive 2 faults from 300 ms to its reset at 340 ms.
            if d == 2 && (300..345).contains(&ms) {
                word = 0x0618;
            }
            if d == 2 && ms == 300 {
                line(clock, "082#1043090100000000".into());
            }
            let position = (ms * 17 + u64::from(d)) as u32;
            let [w0, w1] = word.to_le_bytes();
            let [p0, p1, p2, p3] = position.to_le_bytes();
            line(
                clock,
                format!(
                    "{:03X}#{w0:02X}{w1:02X}{p0:02X}{p1:02X}{p2:02X}{p3:02X}",
                    0x180 + d
                ),
            );
            if d == 2 && (340..342).contains(&ms) {
                let cw = if ms == 340 { "8000" } else { "0F00" };
                line(clock, format!("{:03X}#{cw}", 0x200 + d));
            }
            if ms % 100 == u64::from(d) {
                line(clock, format!("{:03X}#05", 0x700 + d));
            }
            if rng.below(emcy_every) == 0 {
                line(clock, "085#0000000000000000".into());
            }
        }
    }
    t
}

#[test]
fn pdo_repeats_are_folded_and_give_what_they_give_one_by_one() {
    for (seed, emcy_every) in [(11, 40), (12, 2_000)] {
        let t = drive_trace(seed, 4, 600, emcy_every);
        let opts = Options {
            assume_cia402_pdo: true,
            ..base_options()
        };
        let (taken, refused) = assert_fold_independent("drives", &t, &opts);
        assert!(
            taken > 0 && refused > 0,
            "{seed}: {taken} taken, {refused} refused"
        );
        let (out, _) = run_with(&t, opts);
        assert!(out.contains("\"type\":\"fault_reset\""), "{seed}");
        // The last statusword of 599 ms: bits 10 and 12 both set.
        assert_eq!(
            out.matches("\"statusword\":\"0x1637\"").count(),
            4,
            "{seed}"
        );
    }
}

/// An SDO transfer that runs out among steady heartbeats is told at the
/// first frame after its timeout, folding or not: before a heartbeat loss
/// found later. (Folded runs taken whole left it to the next frame off the
/// fold path, which told the loss first.)
#[test]
fn an_sdo_transfer_running_out_among_steady_heartbeats_is_told_in_time() {
    // Four nodes beating every 100 ms; node 1 is asked at 2.05 s and never
    // answers (out at 3.05 s); node 4 beats for the last time at 2.804 s
    // (lost at 3.104 s); an EMCY at 4.15 s.
    let mut t: Vec<u8> = Vec::new();
    for tick in 0..60u32 {
        for node in 1..=4u32 {
            if node == 4 && tick > 28 {
                continue;
            }
            let at = format!("({}.{:03}0)", 1000 + tick / 10, tick % 10 * 100 + node);
            t.extend(format!("{at} can0 {:03X}#05\n", 0x700 + node).bytes());
        }
        if tick == 20 {
            t.extend(b"(1002.0500) can0 601#4000100000000000\n");
        }
        if tick == 41 {
            t.extend(b"(1004.1500) can0 081#1043090000000000\n");
        }
    }
    let (taken, _) = assert_fold_independent("unanswered before lost", &t, &base_options());
    assert!(taken > 0, "runs folded");
    let out = run_with(&t, base_options()).0;
    let told = |what: &str| out.find(what).unwrap_or(usize::MAX);
    assert!(
        told("\"result\":\"unanswered\"") < told("\"type\":\"heartbeat_lost\""),
        "{out}"
    );
}

/// With `--assume-cia402-pdo`, an I/O module whose device type says it is
/// no drive sends event PDOs among the drives' repeats: its ids leave the
/// interest once its device type is read, so the runs that hold them
/// fold the drives' repeats as before instead of being refused whole.
#[test]
fn an_io_module_among_drives_does_not_refuse_their_folds() {
    let mut t = Vec::new();
    let mut line = |micros: u64, frame: &str| {
        t.extend(format!("(1700000000.{micros:06}) can0 {frame}\n").bytes());
    };
    line(0, "081#1043090100000000");
    // Node 0x21's device type: CiA 401, an I/O module.
    line(100, "621#4000100000000000");
    line(200, "5A1#4300100091010F00");
    for ms in 1..400u64 {
        for d in 1..=2u64 {
            line(ms * 1000 + d * 100, &format!("{:03X}#37060000", 0x180 + d));
        }
        if ms % 7 == 0 {
            line(ms * 1000 + 500, &format!("1A1#{:02X}", ms % 251));
        }
        if ms % 100 == 50 {
            line(ms * 1000 + 600, "701#05");
        }
    }
    let opts = Options {
        assume_cia402_pdo: true,
        ..base_options()
    };
    let (taken, refused) = assert_fold_independent("drives and an I/O module", &t, &opts);
    assert!(taken > 5 * refused, "{taken} taken, {refused} refused");
}

/// Incidents close where the frame path closes them, folding or not: the
/// steady heartbeats of the incident fixtures fold into runs, and the
/// incidents come out the same and in the same place.
#[test]
fn incidents_are_the_same_with_folds() {
    for (name, t) in [
        (
            "silent producer",
            &include_bytes!("../../../fixtures/incident-silent-producer.log")[..],
        ),
        (
            "repeated",
            &include_bytes!("../../../fixtures/incident-repeated.log")[..],
        ),
        // Heartbeats among a 1 kHz SYNC and its PDOs.
        (
            "sync gaps",
            &include_bytes!("../../../fixtures/sync-gaps.log")[..],
        ),
    ] {
        let (taken, _) = assert_fold_independent(name, t, &base_options());
        assert!(taken > 0, "{name}: no run was folded");
    }
}

/// SYNC every 10 ms among heartbeats, PDOs and EMCYs, with gaps of a few
/// cycles to two seconds, and now and then a drive's SYNC error after one.
/// The reader hands SYNC lines over inside runs of folded heartbeats: a
/// gap is an event, told in line order among the EMCYs kept inside the
/// run, so a run that holds one is taken one by one.
fn sync_trace(seed: u64, millis: u64) -> Vec<u8> {
    let mut rng = Lcg(seed);
    let mut t = Vec::new();
    let mut line = |micros: u64, frame: &str| {
        t.extend(
            format!(
                "({}.{:06}) can0 {frame}\n",
                micros / 1_000_000,
                micros % 1_000_000
            )
            .bytes(),
        );
    };
    let start: u64 = 1_700_000_000_000_000;
    let mut silent_until = 0;
    for ms in 0..millis {
        let now = start + ms * 1000;
        if ms % 10 == 0 && ms >= silent_until {
            line(now, "080#");
            if rng.below(150) == 0 {
                silent_until = ms + 10 * (3 + rng.below(200));
            }
        }
        for node in 1..=4u64 {
            if ms % 100 == node * 20 {
                line(
                    now + 50 + rng.below(200),
                    &format!("{:03X}#05", 0x700 + node),
                );
            }
        }
        if ms % 10 == 1 {
            for node in 1..=4u64 {
                line(
                    now + 100 * node,
                    &format!("{:03X}#{:016X}", 0x180 + node, rng.next()),
                );
            }
        }
        if ms % 10 == 5 && rng.below(70) == 0 {
            let code = if ms < silent_until { "4082" } else { "0010" };
            line(
                now + 300,
                &format!("{:03X}#{code}110000000000", 0x80 + 1 + rng.below(4)),
            );
        }
    }
    t
}

#[test]
fn sync_gaps_are_told_in_line_order_with_folds() {
    let mut gaps = 0;
    for seed in [21, 22, 23] {
        let t = sync_trace(seed, 20_000);
        fold_tally::take_gaps();
        let (taken, refused) = assert_fold_independent("SYNC", &t, &base_options());
        gaps += fold_tally::take_gaps();
        assert!(
            taken > 0 && refused > 0,
            "{seed}: {taken} taken, {refused} refused"
        );
        let (out, _) = run_with(&t, base_options());
        assert!(out.contains("\"type\":\"sync_missed\""), "{seed}");
        assert!(
            out.contains("\"kind\":\"sync_missed\""),
            "{seed}: in an incident"
        );
    }
    assert!(gaps > 0, "no gap inside a folded run");
}
