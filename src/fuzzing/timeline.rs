//! The decoder and the timeline against a model: a fuzz input read as a
//! script of EMCY, boot-up and SDO frames, each step checked against what
//! the CiA 301 rules say it must do.

use crate::analyze::event::CodeTexts;
use crate::analyze::{BootEvent, Counts, EmcyEvent, InputReport, NodeReport, Sink};
use crate::canopen::NodeId;
use crate::canopen::emcy::{self, Emcy, Warning};
use crate::canopen::profile::Profile;
use crate::canopen::profile_choice::{Chosen, ProfileSource};
use crate::canopen::sdo;
use crate::report::ndjson::Ndjson;
use crate::report::table::TableReport;
use crate::timeline::history::History;
use crate::timeline::{At, ClearedBy, Interval, NodeTimeline, State, Step};
use crate::trace::Timestamp;

use super::checks::{check_emcy_event, check_node, ndjson_values, no_control_characters};

/// Bytes read front to back; past the end every read is 0.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    fn take(&mut self, n: usize) -> &[u8] {
        let (a, b) = self.0.split_at(n.min(self.0.len()));
        self.0 = b;
        a
    }

    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
}

const CHANNELS: [&str; 2] = ["can0", "can1"];
// 1001: an EtherCAT station address, past a byte (the spilled history keeps both).
const NODES: [NodeId; 5] = [1, 2, 3, 127, 1001];

/// One node of the model: its timeline and what the checks know about it.
struct ModelNode {
    channel: u32,
    node: NodeId,
    /// Every built-in profile decodes some node's frames.
    profile: &'static Profile,
    timeline: NodeTimeline,
    emcy: u64,
    /// Intervals opened / closed so far.
    opened: u64,
    closed: u64,
}

/// The `decode_timeline` target: the bytes are a script of frames (EMCY,
/// EMCY with an error status bit, boot-up, SDO, raw ids) for four nodes on
/// two channels. Every EMCY is decoded, run through the node's timeline,
/// checked against the state machine's rules and rendered (ndjson and
/// table); closed intervals go to an error history that spills to disk
/// early; at the end the history must give back every interval exactly
/// once, in report order, ending after it started.
pub fn decode_timeline(data: &[u8]) {
    let mut input = Bytes(data);
    let spill_at = [1, 2, 5, 1000][usize::from(input.u8() & 3)];
    let mut history = History::new(spill_at);
    for name in CHANNELS {
        history.add_channel(name);
    }
    let mut nodes: Vec<ModelNode> = (0..2u32)
        .flat_map(|channel| {
            NODES.iter().enumerate().map(move |(i, &node)| ModelNode {
                channel,
                node,
                profile: &Profile::builtins()
                    [(i + 4 * channel as usize) % Profile::builtins().len()],
                timeline: NodeTimeline::new(),
                emcy: 0,
                opened: 0,
                closed: 0,
            })
        })
        .collect();
    let mut ndjson_out = Vec::new();
    let mut table_out = Vec::new();
    let mut ndjson = Ndjson::new(&mut ndjson_out, false);
    let mut table = TableReport::new(&mut table_out, false, false);
    let mut tracker = sdo::Tracker::default();
    let mut clock = Timestamp::from_parts(1_700_000_000, 0, 6);
    let mut line = 0u64;
    let mut events = 0u64;
    let mut warnings = Vec::new();
    let mut first_time = None;
    let mut last_time = None;

    while !input.0.is_empty() {
        let op = input.u8();
        line += 1 + u64::from(op >> 7);
        let time = next_time(&mut input, &mut clock);
        if let Some(t) = time {
            first_time.get_or_insert(t);
            last_time = Some(t);
        }
        let at = At { time, line };
        match op % 5 {
            0 | 1 => {
                let slot = usize::from(input.u8()) % nodes.len();
                let bit = (op % 5 == 1).then(|| input.u8());
                let len = usize::from(input.u8() % 9);
                let payload = input.take(len).to_vec();
                let Some(e) = decode_emcy(&payload) else {
                    continue;
                };
                let m = &mut nodes[slot];
                warnings.clear();
                let info = m.profile.info(e.code);
                e.frame_warnings(&info, &mut warnings);
                m.profile.frame_warnings(&e, &mut warnings);
                let decoded = m.profile.decode_manufacturer(&e);
                if let Some(d) = &decoded {
                    for (key, _) in &d.fields {
                        assert!(!key.is_empty(), "decoded field without a key");
                    }
                }
                if let Some(c) = m.profile.category(&e) {
                    assert!((1..=5).contains(&c), "built-in categories are 1-5, got {c}");
                }
                assert!(
                    !m.profile.describe(e.code).is_empty(),
                    "every code is described"
                );
                let before = m.timeline.active().to_vec();
                let was = m.timeline.state();
                let step = match bit {
                    Some(bit) => m.timeline.emcy_with_status_bit(&e, at, bit, &mut warnings),
                    None => m.timeline.emcy(&e, at, &mut warnings),
                };
                m.emcy += 1;
                check_step(&e, bit, was, &before, &step, m, at);
                m.opened += (m.timeline.active().len() + step.closed.len())
                    .saturating_sub(before.len()) as u64;
                m.closed += step.closed.len() as u64;
                for iv in &step.closed {
                    history.push(m.channel, m.node, iv.clone());
                }
                for w in &warnings {
                    let _ = (w.tag(), w.to_string());
                }
                let active: Vec<u16> = m.timeline.active_codes().collect();
                let description = m.profile.describe(e.code);
                let event = EmcyEvent {
                    file: "fuzz",
                    line,
                    time,
                    channel: CHANNELS[m.channel as usize],
                    node: m.node,
                    cob_id: Some(emcy::EMCY_BASE + u32::from(m.node)),
                    data: &payload,
                    emcy: &e,
                    info: &info,
                    description: &description,
                    transition: step.transition,
                    state: step.state,
                    active: &active,
                    active_total: active.len(),
                    cleared: &step.cleared,
                    warnings: &warnings,
                    profile: Chosen {
                        profile: m.profile,
                        source: ProfileSource::Flag,
                    },
                    decoded: decoded.as_ref(),
                    bus_error: None,
                };
                ndjson.emcy(&event).expect("Vec");
                table.emcy(&event).expect("Vec");
                events += 1;
            }
            2 => {
                let slot = usize::from(input.u8()) % nodes.len();
                let m = &mut nodes[slot];
                let before = m.timeline.active().to_vec();
                let closed = m.timeline.boot(at);
                assert_eq!(m.timeline.state(), State::ErrorFree, "boot: error-free");
                assert!(m.timeline.active().is_empty(), "boot closes everything");
                assert_eq!(closed.len(), before.len(), "boot closes every active error");
                for (iv, old) in closed.iter().zip(&before) {
                    assert_eq!(iv.seq, old.seq);
                    assert_eq!(iv.cleared_by, Some(ClearedBy::Boot));
                    check_closed(iv, at);
                }
                m.closed += closed.len() as u64;
                let cleared: Vec<u16> = closed.iter().map(|iv| iv.code).collect();
                for iv in closed {
                    history.push(m.channel, m.node, iv);
                }
                let event = BootEvent {
                    file: "fuzz",
                    line,
                    time,
                    channel: CHANNELS[m.channel as usize],
                    node: m.node,
                    cleared: &cleared,
                };
                ndjson.boot(&event).expect("Vec");
                table.boot(&event).expect("Vec");
                events += 1;
            }
            3 => {
                let pick = input.u8();
                let base = if pick & 0x80 == 0 {
                    sdo::RESPONSE_BASE
                } else {
                    sdo::REQUEST_BASE
                };
                let id = base + u32::from(pick & 0x7F);
                let len = if input.u8() & 7 == 0 { 7 } else { 8 };
                let payload = input.take(len).to_vec();
                check_sdo(&mut tracker, id, &payload);
            }
            _ => {
                let id = input.u32() & if op & 0x40 != 0 { 0x7FF } else { u32::MAX };
                let len = usize::from(input.u8() % 3);
                let payload = input.take(len);
                check_ids(id, payload);
                let _ = sdo::parse(id, payload);
            }
        }
    }

    // Every interval once, in report order, ending after it started.
    let opened: u64 = nodes.iter().map(|m| m.opened).sum();
    let mut open = Vec::new();
    for m in &nodes {
        assert_eq!(m.timeline.emcy_count(), m.emcy, "EMCY count");
        let raised: u64 = m.timeline.stats().raised.values().sum();
        assert_eq!(raised, m.opened, "stats.raised counts every raise");
        assert_eq!(
            m.opened - m.closed,
            m.timeline.active().len() as u64,
            "opened = closed + active"
        );
        open.extend(
            m.timeline
                .active()
                .iter()
                .map(|iv| crate::timeline::history::Record {
                    channel: m.channel,
                    node: m.node,
                    interval: iv.clone(),
                }),
        );
    }
    let finished = history.finish(open);
    let mut merge = finished.merge();
    let mut seen = 0u64;
    let mut previous: Option<(u32, NodeId, u64)> = None;
    while let Some(r) = merge.next_record() {
        seen += 1;
        let key = (r.channel, r.node, r.interval.seq);
        if let Some(p) = previous {
            assert!(p < key, "history out of report order: {p:?} then {key:?}");
        }
        previous = Some(key);
        if let Some(end) = r.interval.end {
            assert!(end.line >= r.interval.start.line, "ends before it starts");
        }
    }
    assert!(merge.take_error().is_none(), "history read back");
    assert_eq!(seen, opened, "the history holds every interval once");

    // The node reports render.
    let reports: Vec<NodeReport> = nodes
        .iter()
        .map(|m| NodeReport {
            channel: CHANNELS[m.channel as usize].to_string(),
            node: m.node,
            state: m.timeline.state(),
            active: m.timeline.active_codes().collect(),
            emcy_count: m.timeline.emcy_count(),
            stats: Box::new(m.timeline.stats().clone()),
            profile: m.profile,
            profile_source: ProfileSource::Flag,
            profile_reason: None,
            device_type: None,
            identity: None,
            descriptions: CodeTexts::new(m.profile, m.timeline.stats().raised.keys().copied()),
            nmt_state: None,
            nmt_commanded: None,
            heartbeat: None,
            error_history: None,
            drive: None,
        })
        .collect();
    let report = InputReport {
        file: "fuzz".to_string(),
        format: None,
        gzip: false,
        counts: Counts::default(),
        nodes: reports,
        history: finished,
        first_time,
        last_time,
        timestamps: None,
        error: None,
        nmt_unanswered: Vec::new(),
        unmatched: None,
        bus_errors: Vec::new(),
        time_producer: None,
        incident_roots: Vec::new(),
        channels: Vec::new(),
    };
    let inputs = std::slice::from_ref(&report);
    ndjson.end_input(&report).expect("Vec");
    ndjson.finish(inputs, &[]).expect("Vec");
    table.end_input(&report).expect("Vec");
    table.finish(inputs, &[]).expect("Vec");
    drop(ndjson);
    let values = ndjson_values(&ndjson_out);
    let mut rendered_events = 0;
    for v in &values {
        match v["type"].as_str() {
            Some("emcy") => {
                rendered_events += 1;
                // check_step checked each step against the exact rules.
                check_emcy_event(v, false);
            }
            Some("boot") => rendered_events += 1,
            Some("node") => check_node(v),
            _ => {}
        }
    }
    assert_eq!(rendered_events, events);
    no_control_characters("table", &table_out);
}

/// A time for the next frame: none, forwards, backwards, or near the end of
/// u64 seconds.
fn next_time(input: &mut Bytes<'_>, clock: &mut Timestamp) -> Option<Timestamp> {
    let t = input.u8();
    match t {
        0xFF => return None,
        0xFE => *clock = Timestamp::from_parts(u64::MAX - u64::from(input.u8()), 999_999, 6),
        0xFD => *clock = Timestamp::from_parts(0, 0, 0),
        0xFC => {
            let digits = input.u8() % 20;
            *clock = Timestamp::from_parts(clock.secs(), u64::from(input.u32()), digits);
        }
        _ if t & 0x80 != 0 => {
            *clock = Timestamp::from_parts(clock.secs().saturating_sub(u64::from(t & 0x7F)), 0, 3)
        }
        _ => {
            let delta = Timestamp::from_parts(u64::from(t >> 4), u64::from(t & 0xF), 3);
            *clock = clock.checked_add(delta).unwrap_or(*clock);
        }
    }
    Some(*clock)
}

/// `Emcy::decode` against the frame layout.
fn decode_emcy(data: &[u8]) -> Option<Emcy> {
    match Emcy::decode(data) {
        Err(short) => {
            assert!(data.len() < 3, "{} bytes are enough", data.len());
            assert_eq!(short.0, data.len());
            let _ = short.to_string();
            None
        }
        Ok(e) => {
            assert!(data.len() >= 3);
            assert_eq!(e.code, u16::from_le_bytes([data[0], data[1]]));
            assert_eq!(e.register.0, data[2]);
            assert_eq!(e.manufacturer(), &data[3..data.len().min(8)]);
            assert_eq!(usize::from(e.len), data.len().min(8));
            assert_eq!(e.is_reset(), e.code == 0);
            let mut w = Vec::new();
            e.frame_warnings(&e.info(), &mut w);
            assert_eq!(
                w.iter().any(|w| matches!(w, Warning::ShortFrame { .. })),
                e.len != 8
            );
            Some(e)
        }
    }
}

fn check_closed(iv: &Interval, at: At) {
    assert_eq!(iv.end, Some(at), "closed at this frame");
    assert!(at.line >= iv.start.line, "closed before it was raised");
    assert!(iv.cleared_by.is_some());
}

/// One EMCY's step against the rules in `timeline.rs`.
fn check_step(
    e: &Emcy,
    bit: Option<u8>,
    was: State,
    before: &[Interval],
    step: &Step,
    m: &ModelNode,
    at: At,
) {
    let tl = &m.timeline;
    let active = tl.active();
    assert_eq!(step.state, tl.state());
    assert_eq!(
        step.cleared,
        step.closed.iter().map(|iv| iv.code).collect::<Vec<_>>()
    );
    for iv in &step.closed {
        check_closed(iv, at);
        assert!(
            before.iter().any(|b| b.seq == iv.seq),
            "closed an inactive error"
        );
    }
    // Active: still open, unique codes, raise order, never code 0.
    for (i, iv) in active.iter().enumerate() {
        assert!(iv.end.is_none() && iv.cleared_by.is_none());
        assert_ne!(iv.code, 0, "a reset code is never active");
        if let Some(next) = active.get(i + 1) {
            assert!(iv.seq < next.seq, "active in raise order");
            assert!(
                active[i + 1..].iter().all(|o| o.code != iv.code),
                "code twice"
            );
        }
    }
    // Nothing lost: before = still active + closed (+ at most one new).
    let kept = before
        .iter()
        .filter(|b| active.iter().any(|a| a.seq == b.seq))
        .count();
    assert_eq!(kept + step.closed.len(), before.len(), "an error vanished");
    if tl.state() == State::ErrorFree {
        assert!(active.is_empty(), "error-free with active errors");
    }
    if !e.is_reset() {
        assert_eq!(
            step.transition,
            Some(if was == State::ErrorFree { 1 } else { 3 })
        );
        assert_eq!(tl.state(), State::ErrorOccurred);
        assert!(step.closed.is_empty());
        let raised = active.iter().find(|iv| iv.code == e.code);
        let raised = raised.expect("the raised code is active");
        if let Some(bit) = bit
            && !before.iter().any(|b| b.code == e.code)
        {
            assert_eq!(raised.status_bit, Some(bit));
        }
        return;
    }
    match bit {
        Some(bit) => {
            let expect: Vec<u64> = before
                .iter()
                .filter(|b| b.status_bit == Some(bit))
                .map(|b| b.seq)
                .collect();
            let got: Vec<u64> = step.closed.iter().map(|iv| iv.seq).collect();
            assert_eq!(got, expect, "a status-bit reset closes exactly its bit");
            let want = if got.is_empty() {
                None
            } else if active.is_empty() {
                Some(4)
            } else {
                Some(2)
            };
            assert_eq!(step.transition, want);
            if got.is_empty() {
                assert_eq!(tl.state(), was, "an information report changes nothing");
            }
        }
        None if e.register.0 == 0 => {
            assert!(active.is_empty(), "reset closes everything");
            assert_eq!(step.closed.len(), before.len());
            assert_eq!(tl.state(), State::ErrorFree);
            let want = (was == State::ErrorOccurred).then_some(4);
            assert_eq!(step.transition, want);
        }
        None => {
            assert_eq!(tl.state(), State::ErrorOccurred);
            let want = (was == State::ErrorOccurred).then_some(2);
            assert_eq!(step.transition, want);
            for iv in &step.closed {
                assert_eq!(iv.cleared_by, Some(ClearedBy::PartialReset));
            }
        }
    }
}

/// SDO parsing and the write tracker.
fn check_sdo(tracker: &mut sdo::Tracker, id: u32, data: &[u8]) {
    let parsed = sdo::parse(id, data);
    let node_ok = |node: NodeId| (1..=127).contains(&node);
    let Some(access) = parsed else {
        return;
    };
    assert_eq!(data.len(), 8, "SDO frames are 8 bytes");
    match access {
        sdo::Sdo::Uploaded { node, .. }
        | sdo::Sdo::Writing { node, .. }
        | sdo::Sdo::Written { node, .. }
        | sdo::Sdo::Aborted { node, .. } => {
            assert!(node_ok(node));
            let base = id - u32::from(node);
            assert!(base == sdo::RESPONSE_BASE || base == sdo::REQUEST_BASE);
        }
    }
    if let Some((node, object, value)) = tracker.feed(access) {
        assert!(node_ok(node));
        let _ = object;
        if let Some((emcy_id, extended)) = sdo::cob_id_emcy(value) {
            assert!(value & 0x8000_0000 == 0);
            let max = if extended { 0x1FFF_FFFF } else { 0x7FF };
            assert!(emcy_id <= max);
        }
    }
}

/// EMCY and boot-up id arithmetic.
fn check_ids(id: u32, data: &[u8]) {
    match emcy::emcy_node(id) {
        Some(node) => {
            assert!((emcy::FIRST_EMCY_ID..=emcy::LAST_EMCY_ID).contains(&id));
            assert_eq!(emcy::EMCY_BASE + u32::from(node), id);
            assert!((1..=127).contains(&node));
        }
        None => assert!(!(emcy::FIRST_EMCY_ID..=emcy::LAST_EMCY_ID).contains(&id)),
    }
    if let Some(node) = emcy::boot_node(id, data) {
        assert_eq!(data, [0]);
        assert_eq!(emcy::NMT_ERROR_CONTROL_BASE + u32::from(node), id);
        assert!((1..=127).contains(&node));
    }
}
