//! The bus's traffic through the command line, on the SYNC fixture
//! (scripts/make_sync_fixtures.py): SYNC's gaps told once each, with
//! `--timing` or not, every identifier counted and timed, the load with a bit rate
//! given or recorded, and the same result on one thread and on two (split
//! anywhere: `analyze::tests::parallel`; folded or not:
//! `analyze::tests::folds`).

use serde_json::Value;

use crate::support::{emcy_decode, ndjson};

const TRACE: &str = "fixtures/sync-gaps.log";

fn of_type<'a>(objects: &'a [Value], t: &str) -> Vec<&'a Value> {
    objects.iter().filter(|o| o["type"] == t).collect()
}

fn id(channel: &Value, cob_id: u64) -> &Value {
    channel["ids"]
        .as_array()
        .and_then(|ids| ids.iter().find(|i| i["cob_id"] == cob_id))
        .unwrap_or_else(|| panic!("{cob_id:#x} in {channel}"))
}

#[test]
fn sync_gaps_are_events_once_per_gap() {
    let objects = ndjson(["--timing", TRACE]);
    let gaps = of_type(&objects, "sync_missed");
    assert_eq!(gaps.len(), 2, "{gaps:?}");
    // Four cycles skipped, ended by the SYNC at 1.05 s.
    assert_eq!(gaps[0]["missed"], 4);
    assert_eq!(gaps[0]["start_text"], "2023-11-14T22:13:21.000000Z");
    assert_eq!(gaps[0]["end_text"], "2023-11-14T22:13:21.050000Z");
    assert_eq!(gaps[0]["period"].as_f64(), Some(0.01));
    assert!(gaps[0]["node"].is_null());
    // Stopped for good at 1.8 s; the input goes on to 2.2 s.
    assert!(gaps[1]["end"].is_null());
    assert_eq!(gaps[1]["start_text"], "2023-11-14T22:13:21.800000Z");
    assert_eq!(gaps[1]["missed"], 39);
    let channels = of_type(&objects, "channel");
    assert_eq!(channels.len(), 1);
    let c = channels[0];
    assert!(c["load"].is_null(), "no bit rate");
    let sync = id(c, 0x80);
    assert_eq!(sync["service"], "sync");
    assert_eq!(sync["count"], 177);
    assert_eq!(sync["missed"], 2);
    assert_eq!(sync["max_gap"].as_f64(), Some(0.05));
    // The input object stays the last line.
    assert_eq!(objects.last().unwrap()["type"], "input");
    // Without --timing SYNC is timed all the same: the same gaps, told
    // where they were, and the same timing of its id; the channel object
    // counts every frame by id, the other ids' timing null.
    let plain = ndjson([TRACE]);
    assert_eq!(of_type(&plain, "sync_missed"), gaps);
    let channels = of_type(&plain, "channel");
    assert_eq!(channels.len(), 1);
    assert_eq!(channels[0]["frames"], c["frames"]);
    assert_eq!(id(channels[0], 0x80), sync, "SYNC timed always");
    let untimed = id(channels[0], 0x181);
    assert_eq!(untimed["count"], 177);
    for key in ["period", "jitter", "max_gap", "missed"] {
        assert!(untimed[key].is_null(), "{key} without --timing");
    }
    let order = |objects: &[Value]| {
        objects
            .iter()
            .filter(|o| o["type"] != "channel" && o["type"] != "input")
            .map(|o| (o["type"].clone(), o["line"].clone()))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        order(&plain),
        order(&objects),
        "the same events in the same order, timed or not"
    );
    let counts = |c: &Value| {
        let ids = c["ids"].as_array().cloned().unwrap_or_default();
        ids.iter()
            .map(|i| (i["cob_id"].clone(), i["count"].clone()))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        counts(channels[0]),
        counts(c),
        "the same counts, timed or not"
    );
}

#[test]
fn the_sync_error_follows_from_the_gap_in_its_incident() {
    for objects in [ndjson(["--timing", TRACE]), ndjson([TRACE])] {
        sync_error_follows_from_the_gap(&objects);
    }
}

fn sync_error_follows_from_the_gap(objects: &[Value]) {
    let incidents = of_type(objects, "incident");
    assert_eq!(incidents.len(), 1);
    let i = incidents[0];
    assert_eq!(i["root"]["kind"], "sync_missed");
    assert!(i["root"]["decided"].as_bool().unwrap());
    let reasons: Vec<&str> = i["links"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|l| l["reason"].as_str())
        .collect();
    assert!(
        reasons
            .iter()
            .any(|r| r.contains("0x8240") && r.contains("SYNC skipped")),
        "{reasons:?}"
    );
}

#[test]
fn timing_counts_and_times_every_identifier() {
    let objects = ndjson(["--timing", TRACE]);
    let c = of_type(&objects, "channel")[0];
    assert_eq!(c["frames"], 932);
    assert_eq!(c["error_frames"], 0);
    assert!(c["load"].is_null(), "no bit rate");
    let total: u64 = c["ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["count"].as_u64().unwrap())
        .sum();
    assert_eq!(total, 932, "every frame under its id");
    let tpdo = id(c, 0x181);
    assert_eq!(
        (tpdo["service"].as_str(), tpdo["node"].as_u64()),
        (Some("tpdo1"), Some(1))
    );
    assert_eq!(tpdo["count"], 177);
    assert_eq!(tpdo["missed"], 1);
    // Five of every seven intervals are 0.1 ms long by the fixture's jitter.
    assert_eq!(tpdo["period"].as_f64(), Some(0.0101));
    assert!(tpdo["jitter"].as_f64().unwrap() > 0.0);
    let heartbeat = id(c, 0x701);
    assert_eq!(heartbeat["period"].as_f64(), Some(0.1));
    assert_eq!(heartbeat["missed"], 0);
    let emcy = id(c, 0x82);
    assert!(emcy["period"].is_null(), "an EMCY is no cycle");
    // The analysis is the same with and without --timing, but for what
    // SYNC's gaps add.
    let plain = ndjson([TRACE]);
    let events = |o: &[Value]| -> Vec<Value> {
        o.iter()
            .filter(|v| {
                !matches!(
                    v["type"].as_str(),
                    Some("channel" | "sync_missed" | "incident")
                )
            })
            .cloned()
            .collect()
    };
    assert_eq!(events(&objects), events(&plain));
}

#[test]
fn a_bit_rate_gives_the_load_and_implies_timing() {
    let objects = ndjson(["--bitrate", "500k", TRACE]);
    let c = of_type(&objects, "channel")[0];
    assert_eq!(c["frames"], 932);
    let load = &c["load"];
    assert_eq!(load["bit_rate"], 500_000);
    // Per 10 ms cycle: SYNC 55 bits, two 8-byte TPDOs 135 each, two
    // 4-byte RPDOs 95 each: 515 bits, 10.3% of 500 kbit/s.
    let peak = load["peak_percent"].as_f64().unwrap();
    assert!((10.3..11.0).contains(&peak), "{load}");
    let mean = load["mean_percent"].as_f64().unwrap();
    assert!(mean < peak && mean > 5.0, "{load}");
    let out = emcy_decode()
        .args(["--bitrate", "fast", TRACE])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a bit rate"));
}

#[test]
fn a_recorded_bit_rate_gives_the_load_with_timing() {
    let objects = ndjson(["--timing", "fixtures/s300.ixxat.trc"]);
    let c = of_type(&objects, "channel")[0];
    assert_eq!(c["load"]["bit_rate"], 250_000, "the header's Baudrate");
    // Given on the command line, the flag wins over the header.
    let objects = ndjson(["--bitrate", "1M", "fixtures/s300.ixxat.trc"]);
    let c = of_type(&objects, "channel")[0];
    assert_eq!(c["load"]["bit_rate"], 1_000_000);
}

#[test]
fn the_same_traffic_on_one_thread_and_on_two() {
    for flags in [&[][..], &["--timing"][..]] {
        let one = ndjson([flags, &["-j1", TRACE]].concat());
        let two = ndjson([flags, &["-j2", TRACE]].concat());
        assert!(!one.is_empty());
        assert_eq!(one, two, "{flags:?}");
    }
}

#[test]
fn the_tables_say_the_bus() {
    let out = emcy_decode()
        .env_remove("NO_COLOR")
        .env_remove("COLUMNS")
        .args(["--bitrate", "500k", TRACE])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("SYNC missed 4 cycles (period 10 ms)"),
        "{text}"
    );
    assert!(text.contains("SYNC stopped"), "{text}");
    assert!(text.contains("\nBus\n"), "{text}");
    assert!(text.contains("\nTiming\n"), "{text}");
    assert!(
        text.contains("bus: 932 frames, SYNC every 10 ms (2 gaps), load 8.6% (peak 10.6%)"),
        "{text}"
    );
    // Without --timing, the Bus table for SYNC's timing, no Timing table.
    let out = emcy_decode()
        .env_remove("NO_COLOR")
        .env_remove("COLUMNS")
        .arg(TRACE)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        !text.contains("\nTiming\n") && text.contains("\nBus\n"),
        "{text}"
    );
    assert!(
        text.contains("SYNC missed 4 cycles (period 10 ms)"),
        "{text}"
    );
    assert!(
        text.contains("bus: 932 frames, SYNC every 10 ms (2 gaps), 1 EMCY"),
        "{text}"
    );
}

#[test]
fn the_chart_has_a_bus_strip_where_the_bus_had_trouble() {
    let svg = |args: &[&str]| {
        let out = emcy_decode()
            .args(["--format", "svg"])
            .args(args)
            .output()
            .unwrap();
        String::from_utf8(out.stdout).unwrap()
    };
    let count =
        |text: &str, class: &str| text.matches(&format!("<rect class=\"{class}\" x=")).count();
    // Three bursts, three bus-offs (two nodes', the controller's).
    let bus_off = svg(&["fixtures/bus-off.log"]);
    assert_eq!((count(&bus_off, "be"), count(&bus_off, "bo")), (3, 3));
    assert!(
        bus_off.contains(">error frames<"),
        "the legend names the bands"
    );
    assert!(bus_off.contains(".ec .bus .bo{"), "the strip's style");
    // SYNC's two gaps, timed or not.
    assert_eq!(count(&svg(&["--timing", TRACE]), "sg"), 2);
    assert_eq!(count(&svg(&[TRACE]), "sg"), 2);
    // A quiet bus: no strip, no style for it.
    let quiet = svg(&["fixtures/s300.log"]);
    assert!(!quiet.contains("class=\"bus\"") && !quiet.contains(".ec .bus"));
}

/// Every frame of every fixture is counted once on its channel, by its id,
/// whatever the reader and whether the analysis decoded it or only counted
/// it: the channels' frames add up to the input's, and each channel's to
/// its ids'; timing every frame counts the same, channels in the same order.
#[test]
fn every_frame_of_every_fixture_is_counted_by_channel_and_id() {
    // Each channel's name, frames, and (cob_id, count) per id.
    type Counts = Vec<(Value, Value, Vec<(Value, Value)>)>;
    let counts = |objects: &[Value]| -> Counts {
        of_type(objects, "channel")
            .iter()
            .map(|c| {
                let ids = c["ids"].as_array().cloned().unwrap_or_default();
                let ids = ids
                    .iter()
                    .map(|i| (i["cob_id"].clone(), i["count"].clone()));
                (c["channel"].clone(), c["frames"].clone(), ids.collect())
            })
            .collect()
    };
    for fixture in crate::support::golden::fixtures() {
        let path = fixture.to_string_lossy().into_owned();
        let objects = ndjson([path.as_str()]);
        let timed = ndjson(["--timing", path.as_str()]);
        assert_eq!(
            counts(&objects),
            counts(&timed),
            "{path}: --timing counts otherwise"
        );
        let input = objects
            .iter()
            .rev()
            .find(|o| o["type"] == "input")
            .unwrap_or_else(|| panic!("{path}: no input object"));
        let channels = of_type(&objects, "channel");
        let frames: u64 = channels.iter().filter_map(|c| c["frames"].as_u64()).sum();
        assert_eq!(Some(frames), input["frames"].as_u64(), "{path}");
        for c in channels {
            let ids = c["ids"].as_array().cloned().unwrap_or_default();
            let by_id: u64 = ids.iter().filter_map(|i| i["count"].as_u64()).sum::<u64>()
                + c["error_frames"].as_u64().unwrap_or(0)
                + c["other_ids"].as_u64().unwrap_or(0);
            assert_eq!(c["frames"].as_u64(), Some(by_id), "{path}: {c}");
        }
    }
}

/// With `--timing`, the candump hot loop hands the lines it only counts
/// over with their times instead of decoding them; the pcap reader decodes
/// every frame. The same frames in either must time the same: every
/// identifier's count, period, jitter, largest gap and misses, and the load.
#[test]
fn timing_is_the_same_from_the_hot_loop_and_from_decoded_frames() {
    for twin in [
        "fixtures/sync-gaps",
        "fixtures/network-guarding",
        "fixtures/sdo-startup",
    ] {
        let (log, pcap) = (format!("{twin}.log"), format!("{twin}.pcap"));
        let timing = |path: &str| {
            let objects = ndjson(["--bitrate", "500k", path]);
            let channels = of_type(&objects, "channel");
            assert_eq!(channels.len(), 1, "{path}");
            let c = channels[0].clone();
            let gaps: Vec<_> = of_type(&objects, "sync_missed")
                .iter()
                .map(|g| {
                    (
                        g["line"].clone(),
                        g["start_line"].clone(),
                        g["missed"].clone(),
                    )
                })
                .collect();
            (
                c["ids"].clone(),
                c["load"].clone(),
                c["frames"].clone(),
                gaps,
            )
        };
        let got = timing(&log);
        assert!(!got.1.is_null(), "{log}: a load with a bit rate");
        if twin.ends_with("sync-gaps") {
            let periods = got.0.as_array().map_or(0, |ids| {
                ids.iter().filter(|i| !i["period"].is_null()).count()
            });
            assert!(periods > 1, "{log}: ids with periods");
            assert_eq!(got.3.len(), 2, "{log}: the two SYNC gaps");
        }
        assert_eq!(got, timing(&pcap), "{twin}");
    }
}
