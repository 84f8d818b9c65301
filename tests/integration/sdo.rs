//! SDO transfers through the command line: on fixtures/sdo-block.log
//! (scripts/make_cia402_fixtures.py), block downloads and uploads of two
//! nodes interleaved, their segments never read as aborts, the value a
//! block upload carried learnt, and a real abort reported once; on
//! fixtures/sdo-startup.log (scripts/make_sdo_fixtures.py), every kind of
//! transfer told as one `sdo` event, checked against tshark's CANopen
//! dissector on the same frames (fixtures/sdo-startup.pcap).

use std::fs;
use std::process::Command;

use serde_json::Value;

use crate::support::{emcy_decode, ndjson, run};

const BLOCK: &str = "fixtures/sdo-block.log";
const STARTUP: &str = "fixtures/sdo-startup.log";
const STARTUP_PCAP: &str = "fixtures/sdo-startup.pcap";

fn of_type<'a>(objects: &'a [Value], t: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == t).collect()
}

#[test]
fn block_segments_are_no_aborts_and_the_real_abort_is_reported() {
    let objects = ndjson([BLOCK]);
    let aborts = of_type(&objects, "sdo_abort");
    // The last segment 0x85 of node 4's download is no client abort; the
    // node's abort of the second download is the only one.
    assert_eq!(aborts.len(), 1, "{aborts:?}");
    let a = aborts[0];
    assert_eq!(a["node"], 4);
    assert_eq!(a["index"], "0x1F50");
    assert_eq!(a["subindex"], 2);
    assert_eq!(a["abort_code"], "0x05040004");
    assert_eq!(a["by"], "server");
}

#[test]
fn a_block_upload_of_the_device_type_is_learnt() {
    let objects = ndjson([BLOCK]);
    let node = |n: u64| {
        objects
            .iter()
            .find(|o| o["type"] == "node" && o["node"] == n)
            .cloned()
            .unwrap_or(Value::Null)
    };
    assert_eq!(node(3)["device_type"], "0x000F0191");
    assert_eq!(node(3)["device_profile"], "CiA 401 I/O");
    assert_eq!(node(3)["profile_reason"], "device type 401 (not a drive)");
    // Node 4 only took a firmware download: nothing of it is a fact.
    assert_eq!(node(4)["device_type"], Value::Null);
    assert_eq!(node(4)["device_profile"], Value::Null);
}

#[test]
fn block_transfers_read_the_same_on_one_thread_and_two() {
    // Big enough for blocks on several threads: the trace 3000 times, each
    // copy 1 s later (a block transfer's frames then fall on both sides of
    // a block boundary somewhere).
    const COPIES: u64 = 3000;
    let dir = tempfile::tempdir().expect("temp dir");
    let text = fs::read_to_string(BLOCK).expect("fixture");
    let mut big = String::new();
    for copy in 0..COPIES {
        for line in text.lines() {
            let (time, rest) = line.split_once(')').expect("candump line");
            let secs: f64 = time.trim_start_matches('(').parse().expect("time");
            big.push_str(&format!("({:.6}){rest}\n", secs + copy as f64));
        }
    }
    let path = dir.path().join("big.log");
    fs::write(&path, big).expect("write");
    let run = |j: &str| {
        emcy_decode()
            .args(["--format", "ndjson", "-j", j])
            .arg(&path)
            .output()
            .expect("runs")
    };
    let one = run("1");
    let two = run("2");
    assert_eq!(one.stdout, two.stdout);
    assert_eq!(one.stderr, two.stderr);
    let text = String::from_utf8(one.stdout).expect("utf-8");
    assert_eq!(
        text.matches("\"type\":\"sdo_abort\"").count(),
        COPIES as usize
    );
}

/// A client's abort is the master speaking: to an id that never answered
/// it makes no node and is said once at its line; to a node that spoke it
/// is that node's `sdo_abort`.
#[test]
fn a_client_abort_to_a_silent_id_makes_no_node() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace = dir.path().join("aborts.log");
    fs::write(
        &trace,
        "(1.000) can0 705#00\n\
         (1.100) can0 605#4000100000000000\n\
         (1.200) can0 605#8000100000000405\n\
         (1.300) can0 606#4000100000000000\n\
         (1.400) can0 606#8000100000000405\n",
    )
    .expect("write");
    let out = emcy_decode()
        .args(["--format", "ndjson"])
        .arg(&trace)
        .output()
        .expect("runs");
    let objects: Vec<Value> = String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect();
    let nodes: Vec<&Value> = of_type(&objects, "node");
    assert_eq!(nodes.len(), 1, "{nodes:?}");
    assert_eq!(nodes[0]["node"], 5);
    let aborts = of_type(&objects, "sdo_abort");
    assert_eq!(aborts.len(), 1, "{aborts:?}");
    assert_eq!(
        (&aborts[0]["node"], &aborts[0]["by"]),
        (&5.into(), &"client".into())
    );
    let stderr = String::from_utf8(out.stderr).expect("utf-8");
    assert!(
        stderr.contains("aborts.log:5: the SDO client aborted its transfer of 0x1000 sub 0 to node 6, which never answered"),
        "{stderr}"
    );
}

/// An `sdo` event in short: first and last line, node, direction, object,
/// size, what it showed (text, else hex value), protocol, result.
fn transfer(e: &Value) -> String {
    let shown = match (&e["text"], &e["value"]) {
        (Value::String(t), _) => format!("{t:?}"),
        (_, Value::String(v)) if v.len() > 16 => format!("{}...", &v[..16]),
        (_, Value::String(v)) => v.clone(),
        _ => "-".to_string(),
    };
    format!(
        "{}-{} node {} {} {}.{} {} {} {} {}",
        e["start_line"],
        e["line"],
        e["node"],
        e["direction"].as_str().unwrap_or("?"),
        e["index"].as_str().unwrap_or("?"),
        e["subindex"],
        e["size"],
        shown,
        e["transfer"].as_str().unwrap_or("null"),
        e["result"].as_str().unwrap_or("?"),
    )
}

#[test]
fn every_transfer_of_a_start_up_is_one_event_with_how_it_ended() {
    let objects = ndjson([STARTUP]);
    let told: Vec<String> = of_type(&objects, "sdo").into_iter().map(transfer).collect();
    let expected = [
        "3-4 node 3 upload 0x1000.0 4 92010200 expedited ok",
        "5-6 node 3 upload 0x1018.1 4 9A000000 expedited ok",
        "7-8 node 4 upload 0x1000.0 4 91010F00 expedited ok",
        "9-10 node 4 upload 0x1018.1 4 9A000000 expedited ok",
        "11-16 node 3 upload 0x1008.0 9 \"Servo X12\" segmented ok",
        "17-18 node 4 upload 0x1008.0 3 \"IO4\" expedited ok",
        // The block's segments are not read: its size is what node 3
        // acknowledged.
        "19-26 node 3 download 0x2010.1 20 - block ok",
        "27-28 node 3 download 0x1800.1 4 83010080 expedited ok",
        "29-30 node 3 download 0x1A00.0 1 00 expedited ok",
        "31-32 node 3 download 0x1A00.1 4 10004160 expedited ok",
        "33-34 node 3 download 0x1A00.0 1 01 expedited ok",
        "35-36 node 3 download 0x1800.1 4 83010000 expedited ok",
        "37-58 node 3 download 0x2000.0 70 0001020304050607... segmented ok",
        "59-60 node 4 download 0x6200.1 1 FF expedited abort",
        // 4100 bytes: counted from the initiate, its segments not read.
        "61-1238 node 4 download 0x1F50.1 4100 - segmented ok",
        // The node chooses the protocol of an upload; these never did.
        "1239-1239 node 3 upload 0x2001.0 null - null unanswered",
        "1243-1243 node 9 upload 0x1000.0 null - null unanswered",
        "1250-1251 node 3 upload 0x1000.0 4 92010200 expedited ok",
    ];
    assert_eq!(told, expected);
    let sdo = of_type(&objects, "sdo");
    // Names from the CiA tables, none for manufacturer objects.
    assert_eq!(sdo[4]["name"], "Manufacturer device name");
    assert_eq!(sdo[9]["name"], "TPDO mapping parameter");
    assert_eq!(sdo[14]["name"], "Program data");
    assert!(sdo[12]["name"].is_null());
    // A value over 64 bytes: its first 64 and a hash of all 70.
    assert_eq!(sdo[12]["value"].as_str().map(str::len), Some(128));
    assert!(
        sdo[12]["value_hash"]
            .as_str()
            .is_some_and(|h| h.starts_with("fnv1a64:")),
        "{}",
        sdo[12]
    );
    assert!(sdo[11]["value_hash"].is_null());
    // The abort, with its code and meaning, and its own sdo_abort event.
    assert_eq!(sdo[13]["abort_code"], "0x06020000");
    assert_eq!(sdo[13]["by"], "server");
    assert!(
        sdo[13]["abort_text"]
            .as_str()
            .is_some_and(|t| t.contains("object does not exist"))
    );
    assert_eq!(of_type(&objects, "sdo_abort").len(), 1);
    // The start is the first frame's time, the end the last's.
    assert_eq!(sdo[4]["start_text"], "2023-11-14T22:13:20.015000Z");
    assert_eq!(sdo[4]["time_text"], "2023-11-14T22:13:20.022000Z");
    assert_eq!(sdo[4]["end"], sdo[4]["time"]);
}

#[test]
fn a_request_to_an_id_that_never_speaks_makes_no_node() {
    let objects = ndjson([STARTUP]);
    let nodes: Vec<u64> = of_type(&objects, "node")
        .iter()
        .filter_map(|n| n["node"].as_u64())
        .collect();
    assert_eq!(nodes, [3, 4]);
    let to_nine = of_type(&objects, "sdo")
        .into_iter()
        .filter(|e| e["node"] == 9)
        .count();
    assert_eq!(to_nine, 1, "told, as an unanswered transfer");
    // And `--node` selects transfers by their node.
    let only = ndjson(["--node", "4", STARTUP]);
    let sdo = of_type(&only, "sdo");
    assert_eq!(sdo.len(), 5);
    assert!(sdo.iter().all(|e| e["node"] == 4));
}

/// Where in the output an unanswered transfer is told: once its timeout
/// has passed (at the next frame decoded after it), so before node 4's
/// EMCY 0.5 s after the request with a 0.2 s timeout, after it with the
/// default 1 s.
#[test]
fn an_unanswered_transfer_is_told_when_its_timeout_passes() {
    let order = |flags: &[&str]| -> Vec<String> {
        let mut args: Vec<&str> = flags.to_vec();
        args.push(STARTUP);
        ndjson(args)
            .iter()
            .filter(|o| o["type"] == "emcy" || o["type"] == "sdo" && o["result"] == "unanswered")
            .map(|o| format!("{} {}", o["type"].as_str().unwrap_or("?"), o["line"]))
            .collect()
    };
    assert_eq!(order(&[]), ["emcy 1242", "sdo 1239", "sdo 1243"]);
    assert_eq!(
        order(&["--sdo-timeout", "0.2"]),
        ["sdo 1239", "emcy 1242", "sdo 1243"]
    );
    // Longer than the rest of the trace: the next request to node 3 cuts
    // it short, and the end of the input node 9's.
    assert_eq!(
        order(&["--sdo-timeout", "60"]),
        ["emcy 1242", "sdo 1239", "sdo 1243"]
    );
    let (_, err, code) = run(&["--sdo-timeout", "0", STARTUP], b"");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--sdo-timeout"), "{err}");
}

#[test]
fn the_table_shows_every_transfer_with_show_sdo_and_unanswered_always() {
    let table = |flags: &[&str]| {
        let out = emcy_decode()
            .env_remove("NO_COLOR")
            .env_remove("COLUMNS")
            .args(flags)
            .arg(STARTUP)
            .output()
            .expect("runs");
        String::from_utf8(out.stdout).expect("utf-8")
    };
    let plain = table(&[]);
    assert!(plain.contains("SDO upload 0x2001.0: unanswered"), "{plain}");
    assert!(plain.contains("SDO upload 0x1000.0 Device type: unanswered"));
    assert!(!plain.contains("Servo X12\" (9 bytes"), "{plain}");
    assert!(
        plain.contains("SDO abort 0x6200 sub 1"),
        "aborts keep their row"
    );
    let shown = table(&["--show", "sdo"]);
    for row in [
        "SDO upload 0x1008.0 Manufacturer device name = \"Servo X12\" (9 bytes, segmented): ok",
        "SDO download 0x2010.1 (20 bytes, block): ok",
        "SDO download 0x1F50.1 Program data (4100 bytes, segmented): ok",
        "SDO download 0x6200.1 = FF (1 byte, expedited): aborted by the node, 0x06020000",
    ] {
        assert!(shown.contains(row), "{row} in {shown}");
    }
}

#[test]
fn a_dcf_names_the_objects_of_its_node() {
    let dir = tempfile::tempdir().expect("temp dir");
    let dcf = dir.path().join("drive.dcf");
    fs::write(
        &dcf,
        "[DeviceInfo]\nVendorNumber=0x9A\n[1000]\nParameterName=Device type\nDefaultValue=0x00020192\n\
         [2001]\nParameterName=Brake test result\nDataType=0x0007\n\
         [2010sub1]\nParameterName=Cam table\n",
    )
    .expect("write");
    let spec = format!("3={}", dcf.display());
    let objects = ndjson(["--dcf", spec.as_str(), STARTUP]);
    let name = |node: u64, index: &str| -> Value {
        of_type(&objects, "sdo")
            .into_iter()
            .find(|e| e["node"] == node && e["index"] == index)
            .map(|e| e["name"].clone())
            .unwrap_or(Value::Null)
    };
    assert_eq!(name(3, "0x2001"), "Brake test result");
    assert_eq!(name(3, "0x2010"), "Cam table");
    assert_eq!(
        name(3, "0x1018"),
        "Identity: vendor-ID",
        "the CiA table still names the rest"
    );
    assert!(name(4, "0x6200").is_null(), "node 4 has no DCF");
}

#[test]
fn block_transfers_are_events_with_the_size_acknowledged() {
    let objects = ndjson([BLOCK]);
    let told: Vec<String> = of_type(&objects, "sdo").into_iter().map(transfer).collect();
    assert_eq!(
        told,
        [
            "4-20 node 3 upload 0x1000.0 4 91010F00 block ok",
            "3-25 node 4 download 0x1F50.1 33 - block ok",
            // Aborted: the size its initiate gave, nothing shown.
            "26-34 node 4 download 0x1F50.2 100 - block abort",
        ]
    );
}

/// The client's initiates tshark's CANopen dissector finds in `trace`
/// (ccs 1 and 2, and the block commands 5 and 6 with cs 0, on 0x600 +
/// node), as (line, node, index, subindex), and the lines of the node's
/// upload initiate answers (scs 2 on 0x580 + node) with theirs. The trace
/// is read with our reader and written as a SocketCAN pcap (its data
/// frames; frame k is the k-th), so tshark sees the frames we decoded.
/// Also the lines of the block initiates with the CRC bit (`0xC4`-`0xC6`
/// for a download, `0xA4` for an upload), which tshark 4.0 leaves
/// undecoded. `None` when tshark is not installed.
#[allow(clippy::type_complexity)]
fn tshark_initiates(
    trace: &std::path::Path,
) -> Option<(
    Vec<(u64, u64, String, u64)>,
    Vec<(u64, u64, String, u64)>,
    Vec<u64>,
)> {
    use emcy_decode::{FrameKind, Record, TraceReader};
    let file = fs::File::open(trace).expect("trace opens");
    let mut lines = Vec::new();
    let mut crc_blocks = Vec::new();
    let mut pcap: Vec<u8> = Vec::new();
    // pcap header: microseconds, little-endian, LINKTYPE_CAN_SOCKETCAN.
    for word in [0xA1B2_C3D4u32, 0x0004_0002, 0, 0, 262_144, 227] {
        pcap.extend(word.to_le_bytes());
    }
    for record in TraceReader::new(std::io::BufReader::new(file)) {
        let Ok(Record::Frame(f)) = record else {
            continue;
        };
        if f.kind != FrameKind::Data || f.extended || f.data.len() > 8 {
            continue;
        }
        lines.push(f.line);
        let client = (0x601..=0x67F).contains(&f.id);
        if client && matches!(f.data.first(), Some(c) if matches!(c & 0xE5, 0xC4 | 0xA4)) {
            crc_blocks.push(f.line);
        }
        let mut frame = f.id.to_be_bytes().to_vec();
        frame.extend([f.data.len() as u8, 0, 0, 0]);
        frame.extend(&f.data);
        let n = lines.len() as u32;
        for word in [n, 0, frame.len() as u32, frame.len() as u32] {
            pcap.extend(word.to_le_bytes());
        }
        pcap.extend(frame);
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("trace.pcap");
    fs::write(&path, pcap).expect("pcap written");
    let Ok(out) = Command::new("tshark")
        .arg("-r")
        .arg(&path)
        .args(["-d", "can.subdissector,canopen", "-Y", "canopen.sdo.cmd"])
        .args(["-T", "fields", "-E", "separator=,"])
        .args([
            "-e",
            "frame.number",
            "-e",
            "can.id",
            "-e",
            "canopen.sdo.ccs",
        ])
        .args(["-e", "canopen.sdo.scs", "-e", "canopen.sdo.cs"])
        .args(["-e", "canopen.sdo.main_idx", "-e", "canopen.sdo.sub_idx"])
        .output()
    else {
        // .ci/run installs tshark; without it here, say so loudly.
        assert!(
            std::env::var_os("CI").is_none(),
            "tshark is not installed (apt-get install tshark)"
        );
        eprintln!("tshark is not installed: the SDO cross-check is skipped");
        return None;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let number = |s: &str| -> u64 {
        let s = s.trim();
        match s.strip_prefix("0x") {
            Some(hex) => u64::from_str_radix(hex, 16).unwrap_or(u64::MAX),
            None => s.parse().unwrap_or(u64::MAX),
        }
    };
    let (mut initiates, mut answers) = (Vec::new(), Vec::new());
    for row in String::from_utf8_lossy(&out.stdout).lines() {
        let f: Vec<&str> = row.split(',').collect();
        let [frame, id, ccs, scs, cs, index, sub] = f[..] else {
            panic!("tshark row {row}");
        };
        let (id, frame) = (number(id), number(frame));
        let line = lines[(frame - 1) as usize];
        let object = (format!("0x{:04X}", number(index)), number(sub));
        if (0x601..=0x67F).contains(&id) {
            let begins = match number(ccs) {
                1 | 2 => true,
                5 | 6 => number(cs) == 0,
                _ => false,
            };
            if begins {
                initiates.push((line, id - 0x600, object.0, object.1));
            }
        } else if (0x581..=0x5FF).contains(&id) && number(scs) == 2 {
            answers.push((line, id - 0x580, object.0, object.1));
        }
    }
    Some((initiates, answers, crc_blocks))
}

/// Our `sdo` events against tshark's reading of the same frames: every
/// client initiate tshark finds begins one of our transfers, naming the
/// same node and object; each of our transfers begins at such an initiate
/// or at a node's answer to an upload whose request the trace did not
/// show (or at a block initiate tshark does not decode). On every fixture
/// and on the machine networks beside the project (when present).
#[test]
fn tshark_reads_every_initiate_as_we_do() {
    let shared = std::path::Path::new("../shared/realworld-traces/canopen");
    // Every fixture our reader reads (the SDO ones, and the start-ups of
    // the others), then the networks.
    let mut traces = crate::support::golden::fixtures();
    for name in [
        "hilch_pcan1.trc",
        "hilch_pcan2.trc",
        "hilch_pcan3.trc",
        "hilch_ixxat1.trc",
        "canopendemo_sdo_block.txt",
    ] {
        if shared.join(name).exists() {
            traces.push(shared.join(name));
        }
    }
    for trace in &traces {
        let Some((initiates, answers, crc_blocks)) = tshark_initiates(trace) else {
            return;
        };
        let objects = ndjson([trace.as_os_str()]);
        let mut ours: Vec<(u64, u64, String, u64)> = of_type(&objects, "sdo")
            .iter()
            .map(|e| {
                (
                    e["start_line"].as_u64().unwrap_or(0),
                    e["node"].as_u64().unwrap_or(0),
                    e["index"].as_str().unwrap_or("").to_string(),
                    e["subindex"].as_u64().unwrap_or(0),
                )
            })
            .collect();
        ours.sort();
        let name = trace.display();
        for i in &initiates {
            assert!(
                ours.contains(i),
                "{name}: tshark's initiate {i:?} begins none of ours"
            );
        }
        for o in &ours {
            assert!(
                initiates.contains(o) || answers.contains(o) || crc_blocks.contains(&o.0),
                "{name}: our transfer {o:?} begins at no initiate or answer tshark reads"
            );
        }
        if trace.ends_with(STARTUP_PCAP) {
            assert_eq!((initiates.len(), ours.len()), (18, 18));
        }
        eprintln!(
            "{name}: {} transfers, {} initiates",
            ours.len(),
            initiates.len()
        );
    }
}
