//! Error frames read the same from every format (the SocketCAN
//! representation of linux/can/error.h), checked on our fixtures
//! (`fixtures/bus-errors.*`), against tshark's SocketCAN dissector (pcap)
//! and python-can (ASC, BLF: it reads error frames without their class,
//! so their number and times) when they are installed, and
//! on the third-party traces beside the project that hold error frames.

use std::path::Path;
use std::process::Command;

use emcy_decode::{FrameKind, Record, TraceReader};

/// (time, channel, class bits, data) of every error frame of a file.
fn error_frames(path: &Path) -> Vec<(String, String, u32, Vec<u8>)> {
    let file = std::fs::File::open(path).expect("fixture opens");
    TraceReader::new(std::io::BufReader::new(file))
        .filter_map(|r| match r.expect("readable") {
            Record::Frame(f) if f.kind == FrameKind::Error => Some((
                f.time.map(|t| t.to_string()).unwrap_or_default(),
                f.channel,
                f.id,
                f.data,
            )),
            _ => None,
        })
        .collect()
}

/// What the candump log says, as error.h lays it out: class and bytes.
fn socketcan() -> Vec<(u32, Vec<u8>)> {
    error_frames(Path::new("fixtures/bus-errors.log"))
        .into_iter()
        .map(|(_, _, id, data)| (id, data))
        .collect()
}

/// What a format that records only a protocol violation (Vector's ECC)
/// keeps of each: the violation without the counters; other classes
/// unknown.
fn violations_only(all: &[(u32, Vec<u8>)]) -> Vec<(u32, Vec<u8>)> {
    all.iter()
        .map(|(class, data)| {
            if class & 0x08 == 0 {
                return (0, Vec::new());
            }
            let mut d = data.clone();
            d[6] = 0;
            d[7] = 0;
            (class & !0x200, d)
        })
        .collect()
}

#[test]
fn every_format_gives_the_error_frames_of_the_candump_log() {
    let want = socketcan();
    assert_eq!(want.len(), 9);
    assert_eq!(want[0], (0x288, vec![0, 0, 0x04, 0x02, 0, 0, 8, 16]));
    let classes = |file: &str| -> Vec<(u32, Vec<u8>)> {
        error_frames(Path::new(file))
            .into_iter()
            .map(|(_, _, id, data)| (id, data))
            .collect()
    };
    assert_eq!(classes("fixtures/bus-errors.txt"), want);
    assert_eq!(classes("fixtures/bus-errors.pcap"), want);
    assert_eq!(classes("fixtures/bus-errors.asc"), violations_only(&want));
    assert_eq!(classes("fixtures/bus-errors.blf"), violations_only(&want));
    // PEAK records the counters with every error, and the violation's type,
    // direction and place; not the controller's state (passive, bus off).
    let peak: Vec<(u32, Vec<u8>)> = want
        .iter()
        .map(|(class, data)| {
            if class & 0x08 != 0 {
                (*class, data.clone())
            } else {
                (0x200, vec![0, 0, 0, 0, 0, 0, data[6], data[7]])
            }
        })
        .collect();
    assert_eq!(classes("fixtures/bus-errors.trc"), peak);
    assert_eq!(classes("fixtures/bus-errors.v1_1.trc"), peak);
    // MF4's ErrorType says the type (or CRC, ACK) and no place.
    let mf4 = classes("fixtures/bus-errors.mf4");
    let types: Vec<(u32, u8, u8)> = mf4
        .iter()
        .map(|(c, d)| {
            (
                *c,
                d.get(2).copied().unwrap_or(0),
                d.get(3).copied().unwrap_or(0),
            )
        })
        .collect();
    assert_eq!(
        types,
        [
            (0x88, 0x04, 0),
            (0x88, 0x02, 0),
            (0x88, 0x01, 0),
            (0xA8, 0x00, 0x19),
            (0x88, 0x00, 0x08),
            (0, 0, 0),
            (0xA8, 0x00, 0x19),
            (0, 0, 0),
            (0, 0, 0),
        ]
    );
    // The same times in every format.
    let times = |file: &str| -> Vec<String> {
        error_frames(Path::new(file))
            .into_iter()
            .map(|(t, _, _, _)| t.trim_end_matches('0').to_string())
            .collect()
    };
    let log_times = times("fixtures/bus-errors.log");
    for file in ["fixtures/bus-errors.txt", "fixtures/bus-errors.pcap"] {
        assert_eq!(times(file), log_times, "{file}");
    }
}

fn have(cmd: &str, args: &[&str]) -> bool {
    Command::new(cmd)
        .args(args)
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn tshark_reads_the_pcap_error_frames_as_we_do() {
    if !have("tshark", &["--version"]) {
        eprintln!("tshark is not installed: the cross-check is skipped");
        return;
    }
    let fields = [
        "can.err.tx_timeout",
        "can.err.lostarb",
        "can.err.ctrl",
        "can.err.prot",
        "can.err.trx",
        "can.err.ack",
        "can.err.busoff",
        "can.err.buserror",
        "can.err.restarted",
        "can.err.prot.location",
        "can.err.prot.type.tx",
        "can.err.ctrl.tx_passive",
    ];
    let mut cmd = Command::new("tshark");
    cmd.args(["-r", "fixtures/bus-errors.pcap", "-Y", "can.flags.err == 1"])
        .args(["-T", "fields", "-E", "separator=,"]);
    for f in fields {
        cmd.args(["-e", f]);
    }
    let out = cmd.output().expect("tshark runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let theirs: Vec<String> = text.lines().map(str::to_string).collect();
    let ours: Vec<String> = socketcan()
        .iter()
        .map(|(class, d)| {
            let bit = |b: u32| u32::from(class & b != 0).to_string();
            let prot = class & 0x08 != 0;
            let ctrl = class & 0x04 != 0;
            [
                bit(0x1),
                bit(0x2),
                bit(0x4),
                bit(0x8),
                bit(0x10),
                bit(0x20),
                bit(0x40),
                bit(0x80),
                bit(0x100),
                if prot {
                    d[3].to_string()
                } else {
                    String::new()
                },
                if prot {
                    u8::from(d[2] & 0x80 != 0).to_string()
                } else {
                    String::new()
                },
                if ctrl {
                    u8::from(d[1] & 0x20 != 0).to_string()
                } else {
                    String::new()
                },
            ]
            .join(",")
        })
        .collect();
    assert_eq!(theirs, ours);
}

/// (seconds, channel) of every error frame python-can reads from `path`.
fn python_can(path: &Path) -> Option<Vec<(String, String)>> {
    let script = "import can,sys\n\
        for m in can.LogReader(sys.argv[1]):\n\
        \x20   if m.is_error_frame: print(f'{m.timestamp:.6f} {m.channel}')\n";
    let out = Command::new("python3")
        .args(["-c", script])
        .arg(path)
        .output()
        .ok()
        .filter(|o| o.status.success())?;
    Some(
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| l.split_once(' '))
            .map(|(t, c)| (t.to_string(), c.to_string()))
            .collect(),
    )
}

#[test]
fn python_can_finds_the_same_error_frames() {
    if !have("python3", &["-c", "import can"]) {
        eprintln!("python-can is not installed: the cross-check is skipped");
        return;
    }
    let shared = Path::new("../shared/realworld-traces/python-can");
    // python-can 4.6 reads no TRC error row (it skips them): TRC is checked
    // by the unit tests of PEAK's fields and by the candump log above.
    let mut files: Vec<std::path::PathBuf> = ["asc", "blf"]
        .iter()
        .map(|ext| Path::new("fixtures").join(format!("bus-errors.{ext}")))
        .collect();
    for name in [
        "test_CanErrorFrames.asc",
        "logfile_errorframes.asc",
        "test_CanErrorFrameExt.blf",
    ] {
        if shared.join(name).exists() {
            files.push(shared.join(name));
        }
    }
    for file in files {
        let Some(theirs) = python_can(&file) else {
            panic!("python-can cannot read {}", file.display());
        };
        let ours = error_frames(&file);
        assert_eq!(ours.len(), theirs.len(), "{}", file.display());
        for ((t, _, _, _), (their_t, _)) in ours.iter().zip(&theirs) {
            // python-can gives TRC and BLF times as floats since the epoch,
            // ASC ones since the start: compare the fractions of a second.
            let frac = |s: &str| {
                let f: f64 = s.parse().unwrap_or(f64::NAN);
                ((f.fract() * 1e4).round() as i64).rem_euclid(10_000)
            };
            assert_eq!(frac(t), frac(their_t), "{}: {t} {their_t}", file.display());
        }
    }
}

/// The analysis reads with a narrow interest, through each reader's
/// id-first scan path, not the whole-record path above: every format's
/// error frames must reach it there too (TRC's error rows once did not).
#[test]
fn the_analysis_gets_every_formats_error_frames() {
    for entry in std::fs::read_dir("fixtures").expect("fixtures") {
        let path = entry.expect("entry").path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        if !name.starts_with("bus-errors.") {
            continue;
        }
        let objects = crate::support::ndjson([path.as_os_str()]);
        let input = objects
            .iter()
            .find(|o| o["type"] == "input")
            .expect("input object");
        assert_eq!(input["bus_errors"][0]["error_frames"], 9, "{name}");
        let bursts = objects.iter().filter(|o| o["type"] == "bus_error").count();
        assert_eq!(bursts, 1, "{name}");
    }
}
