//! Unit tests of the pcap reader on captures built here byte by byte.

use std::io::{self, Read};

use proptest::prelude::*;

use super::consts::{BOM, BUFFER};
use super::packet::Order;
use super::*;
use crate::id_counts::testing::{self, assert_counts_add_up};
use crate::{FrameKind, FrameSource, Interest, Next, Parsed};

// ---- writers -------------------------------------------------------------------------

fn u16s(o: Order, v: u16) -> [u8; 2] {
    match o {
        Order::Big => v.to_be_bytes(),
        Order::Little => v.to_le_bytes(),
    }
}

fn u32s(o: Order, v: u32) -> [u8; 4] {
    match o {
        Order::Big => v.to_be_bytes(),
        Order::Little => v.to_le_bytes(),
    }
}

/// A pcap file header.
fn pcap_header(o: Order, nanos: bool, linktype: u32) -> Vec<u8> {
    let magic = if nanos { 0xA1B2_3C4D } else { 0xA1B2_C3D4 };
    let mut h = u32s(o, magic).to_vec();
    h.extend(u16s(o, 2));
    h.extend(u16s(o, 4));
    h.extend([0; 8]);
    h.extend(u32s(o, 262_144));
    h.extend(u32s(o, linktype));
    h
}

fn record(o: Order, secs: u32, frac: u32, data: &[u8]) -> Vec<u8> {
    let mut r = u32s(o, secs).to_vec();
    r.extend(u32s(o, frac));
    r.extend(u32s(o, data.len() as u32));
    r.extend(u32s(o, data.len() as u32));
    r.extend(data);
    r
}

/// A pcapng block: type, length, body padded to 4 bytes, length.
fn block(o: Order, kind: u32, body: &[u8]) -> Vec<u8> {
    let mut padded = body.to_vec();
    padded.resize(body.len().div_ceil(4) * 4, 0);
    let len = 12 + padded.len() as u32;
    let mut b = u32s(o, kind).to_vec();
    b.extend(u32s(o, len));
    b.extend(padded);
    b.extend(u32s(o, len));
    b
}

fn options(o: Order, opts: &[(u16, &[u8])]) -> Vec<u8> {
    let mut v = Vec::new();
    for (code, value) in opts {
        v.extend(u16s(o, *code));
        v.extend(u16s(o, value.len() as u16));
        v.extend(*value);
        v.resize(v.len().div_ceil(4) * 4, 0);
    }
    if !opts.is_empty() {
        v.extend([0; 4]);
    }
    v
}

fn shb(o: Order) -> Vec<u8> {
    let mut body = u32s(o, BOM).to_vec();
    body.extend(u16s(o, 1));
    body.extend(u16s(o, 0));
    body.extend([0xFF; 8]); // section length: unknown
    block(o, 0x0A0D_0D0A, &body)
}

fn idb(o: Order, linktype: u16, opts: &[(u16, &[u8])]) -> Vec<u8> {
    let mut body = u16s(o, linktype).to_vec();
    body.extend([0, 0]);
    body.extend(u32s(o, 0));
    body.extend(options(o, opts));
    block(o, 1, &body)
}

fn epb(o: Order, iface: u32, units: u64, data: &[u8]) -> Vec<u8> {
    let mut body = u32s(o, iface).to_vec();
    body.extend(u32s(o, (units >> 32) as u32));
    body.extend(u32s(o, units as u32));
    body.extend(u32s(o, data.len() as u32));
    body.extend(u32s(o, data.len() as u32));
    body.extend(data);
    block(o, 6, &body)
}

/// A SocketCAN frame with its id word in `o`.
fn can(o: Order, word: u32, data: &[u8]) -> Vec<u8> {
    let mut f = u32s(o, word).to_vec();
    f.extend([data.len() as u8, 0, 0, 0]);
    f.extend(data);
    f
}

/// The same behind a LINUX_SLL header.
fn sll(protocol: u16, frame: &[u8]) -> Vec<u8> {
    let mut p = vec![0, 0, 0x01, 0x18];
    p.extend([0u8; 10]);
    p.extend(protocol.to_be_bytes());
    p.extend(frame);
    p
}

fn sll2(protocol: u16, frame: &[u8]) -> Vec<u8> {
    let mut p = protocol.to_be_bytes().to_vec();
    p.extend([0, 0, 0, 0, 0, 7, 0x01, 0x18, 0, 0]);
    p.extend([0u8; 8]);
    p.extend(frame);
    p
}

const EMCY: [u8; 8] = [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0];
const RESET: [u8; 8] = [0; 8];

// ---- reading -------------------------------------------------------------------------

#[derive(Debug, PartialEq)]
enum Got {
    Frame {
        time: String,
        channel: String,
        id: u32,
        extended: bool,
        kind: FrameKind,
        data: Vec<u8>,
    },
    Skipped,
    Malformed(String),
}

/// A reader that hands out `step` bytes a call (a pipe, a gzip stream).
struct Trickle<'a> {
    data: &'a [u8],
    step: usize,
}

impl Read for Trickle<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.step.min(buf.len()).min(self.data.len());
        buf[..n].copy_from_slice(&self.data[..n]);
        self.data = &self.data[n..];
        Ok(n)
    }
}

fn read_with(input: impl Read) -> (Vec<Got>, Vec<String>) {
    let mut r = PcapReader::new(input).expect("a pcap or pcapng header");
    let mut got = Vec::new();
    let mut notes = Vec::new();
    loop {
        let more = r.advance(None).expect("no I/O error");
        while let Some(n) = r.take_note() {
            notes.push(n);
        }
        if !more {
            break;
        }
        got.push(match r.take().expect("a packet after advance") {
            Parsed::Frame(f) => Got::Frame {
                time: f.time.map(|t| t.to_string()).unwrap_or_default(),
                channel: String::from_utf8_lossy(f.channel).into_owned(),
                id: f.id,
                extended: f.extended,
                kind: f.kind,
                data: f.data.as_slice().to_vec(),
            },
            Parsed::Skipped => Got::Skipped,
            Parsed::Malformed(r) => Got::Malformed(r.into_owned()),
        });
    }
    (got, notes)
}

/// Reads `bytes` whole and in small pieces: both must agree; and the
/// frames only counted must add up ([`counts_add_up`]).
fn read(bytes: &[u8]) -> (Vec<Got>, Vec<String>) {
    let whole = read_with(bytes);
    for step in [1, 3, 64] {
        assert_eq!(
            read_with(Trickle { data: bytes, step }),
            whole,
            "{step}-byte reads"
        );
    }
    counts_add_up(bytes, "a capture built here");
    whole
}

/// Reads `bytes` with each of the tests' interests, whole (the hot loop
/// takes most packets) and 3 bytes at a time (the general path takes
/// most): the frames only counted, by channel and identifier, plus those
/// handed on must be every frame. Returns how many were only counted.
fn counts_add_up(bytes: &[u8], what: &str) -> u64 {
    let mut counted = 0;
    for (label, interest) in testing::interests() {
        for step in [usize::MAX, 3] {
            let source = || PcapReader::new(Trickle { data: bytes, step }).expect("a header");
            counted += assert_counts_add_up(
                &mut source(),
                &mut source(),
                &interest,
                &format!("{what}, {label}, {step}-byte reads"),
            );
        }
    }
    counted
}

fn frame(time: &str, channel: &str, id: u32, data: &[u8]) -> Got {
    Got::Frame {
        time: time.into(),
        channel: channel.into(),
        id,
        extended: false,
        kind: FrameKind::Data,
        data: data.to_vec(),
    }
}

fn malformed(got: &Got) -> &str {
    match got {
        Got::Malformed(r) => r,
        other => panic!("not malformed: {other:?}"),
    }
}

// ---- tests ---------------------------------------------------------------------------

#[test]
fn unwanted_frames_are_only_counted_and_the_rest_read_as_without_interest() {
    let o = Order::Little;
    let mut f = shb(o);
    f.extend(idb(o, 113, &[(2, b"can0")]));
    let ids = [0x181, 0x81, 0x281, 0x701, 0x8000_0081, 0x82, 0x182];
    for (i, id) in ids.iter().enumerate() {
        f.extend(epb(o, 0, i as u64, &sll(0x0C, &can(o, *id, &EMCY))));
    }
    f.extend(epb(o, 0, 9, &sll(0x0C, &can(o, 0x181, &[0; 9])))); // malformed
    let mut interest = Interest::none();
    interest.add_standard_range(0x81..=0xFF);
    let mut r = PcapReader::new(&f[..]).unwrap();
    let mut got = Vec::new();
    loop {
        let more = r.advance(Some(&interest)).unwrap();
        got.push(format!("plain {}", r.take_counted().0));
        if !more {
            break;
        }
        got.push(match r.take() {
            Some(Parsed::Frame(f)) => format!("frame {:X}", f.id),
            Some(Parsed::Malformed(_)) => "malformed".into(),
            other => format!("{other:?}"),
        });
    }
    assert_eq!(
        got,
        [
            "plain 1",
            "frame 81",
            "plain 3",
            "frame 82",
            "plain 1",
            "malformed",
            "plain 0"
        ]
    );
}

#[test]
fn the_fixtures_frames_only_counted_add_up_to_every_frame() {
    let mut counted = 0;
    for (name, bytes) in testing::fixtures(&["pcap", "pcapng"]) {
        counted += counts_add_up(&bytes, &name);
    }
    assert!(counted > 0, "some frames only counted");
}

/// An enhanced packet block with options is read outside the hot loop:
/// a frame only counted there is the input's first or last frame all the
/// same (a real capture whose every block had options said it had no
/// time at all).
#[test]
fn frames_only_counted_outside_the_hot_loop_give_the_input_its_span() {
    let o = Order::Little;
    let mut f = shb(o);
    f.extend(idb(o, 113, &[(2, b"can0")]));
    let with_options = |units: u64| {
        let mut b = epb(o, 0, units, &sll(0x0C, &can(o, 0x281, &EMCY)));
        let opts = options(o, &[(1, b"note")]);
        let len = b.len() + opts.len();
        b.truncate(b.len() - 4);
        b.extend(&opts);
        b.extend(u32s(o, len as u32));
        b[4..8].copy_from_slice(&u32s(o, len as u32));
        b
    };
    for units in [1_000_000, 2_000_000, 3_500_000] {
        f.extend(with_options(units));
    }
    let mut reader = PcapReader::new(&f[..]).expect("a header");
    let mut only_counted = 0;
    while let Ok(Some(next)) = reader.next_item(Some(&Interest::none())) {
        if let Next::Counted(c) = next {
            only_counted += c.plain;
        }
    }
    assert_eq!(only_counted, 3);
    let (first, last) = reader.plain_span().expect("the counted frames' span");
    assert_eq!(
        (first.to_string(), last.to_string()),
        ("1.000000".into(), "3.500000".into())
    );
}

/// Frames only counted outside the hot loop (an enhanced packet block
/// with options, simple and obsolete packet blocks) and in it, on a
/// device of an `any` capture and on interfaces of two sections, each
/// under the channel and identifier its frame would have.
#[test]
fn frames_only_counted_are_counted_under_their_frames_channel_and_id() {
    let o = Order::Little;
    let emcy = |word: u32| sll(0x0C, &can(o, word, &EMCY));
    let mut f = shb(o);
    f.extend(idb(o, 113, &[(2, b"can0")]));
    f.extend(idb(o, 276, &[(2, b"any")]));
    // Hot: the EPBs without options.
    f.extend(epb(o, 0, 1, &emcy(0x181)));
    f.extend(epb(o, 0, 2, &emcy(0x8000_0181)));
    f.extend(epb(o, 1, 3, &sll2(0x0C, &can(o, 0x181, &EMCY))));
    let mut fd = can(o, 0x81, &[0x11; 12]);
    fd.resize(72, 0);
    f.extend(epb(o, 0, 4, &sll(0x0D, &fd)));
    f.extend(epb(o, 0, 5, &emcy(0x2000_0004)));
    // General: an EPB with a comment, an SPB and an obsolete PB.
    let mut with_options = epb(o, 0, 6, &emcy(0x281));
    let opts = options(o, &[(1, b"note")]);
    let len = with_options.len() + opts.len();
    with_options.truncate(with_options.len() - 4);
    with_options.extend(&opts);
    with_options.extend(u32s(o, len as u32));
    with_options[4..8].copy_from_slice(&u32s(o, len as u32));
    f.extend(with_options);
    let packet = emcy(0x381);
    let mut spb = u32s(o, packet.len() as u32).to_vec();
    spb.extend(&packet);
    f.extend(block(o, 3, &spb));
    let mut pb = u16s(o, 1).to_vec();
    pb.extend(u16s(o, 0));
    pb.extend(u32s(o, 0));
    pb.extend(u32s(o, 7));
    let packet = sll2(0x0C, &can(o, 0x481, &EMCY));
    pb.extend(u32s(o, packet.len() as u32));
    pb.extend(u32s(o, packet.len() as u32));
    pb.extend(&packet);
    f.extend(block(o, 2, &pb));
    // A second section names its first interface as the first did.
    f.extend(shb(Order::Big));
    f.extend(idb(Order::Big, 113, &[(2, b"can0")]));
    f.extend(epb(
        Order::Big,
        0,
        8,
        &sll(0x0C, &can(Order::Big, 0x181, &EMCY)),
    ));

    let mut r = PcapReader::new(&f[..]).expect("a pcapng header");
    while r
        .next_item(Some(&Interest::none()))
        .expect("no I/O error")
        .is_some()
    {}
    let counted = r.counted_ids().expect("counts");
    let got: Vec<_> = counted
        .channels()
        .map(|c| {
            (
                String::from_utf8_lossy(c.name()).into_owned(),
                c.ids().collect::<Vec<_>>(),
            )
        })
        .collect();
    assert_eq!(
        got,
        [
            (
                "can0".to_string(),
                vec![
                    (0x81, false, 1),
                    (0x181, false, 2),
                    (0x281, false, 1),
                    (0x381, false, 1),
                    (0x181, true, 1)
                ]
            ),
            (
                "any:7".to_string(),
                vec![(0x181, false, 1), (0x481, false, 1)]
            ),
        ]
    );
    assert_eq!(counted.channels().map(|c| c.error_frames()).sum::<u64>(), 0);
    read(&f);
}

#[test]
fn pcap_in_both_byte_orders_and_both_units() {
    for o in [Order::Little, Order::Big] {
        for nanos in [false, true] {
            let mut f = pcap_header(o, nanos, 227);
            f.extend(record(
                o,
                1_700_000_001,
                250_000,
                &can(Order::Big, 0x81, &EMCY),
            ));
            f.extend(record(
                o,
                1_700_000_002,
                5,
                &can(Order::Big, 0x81, &RESET[..3]),
            ));
            let (got, notes) = read(&f);
            let (t1, t2) = if nanos {
                ("1700000001.000250000", "1700000002.000000005")
            } else {
                ("1700000001.250000", "1700000002.000005")
            };
            assert_eq!(
                got,
                [
                    frame(t1, "0", 0x81, &EMCY),
                    frame(t2, "0", 0x81, &RESET[..3])
                ],
                "{o:?} nanos {nanos}"
            );
            assert!(notes.is_empty(), "{notes:?}");
            assert_eq!(
                PcapReader::new(&f[..]).unwrap().format(),
                Some(Format::Pcap)
            );
        }
    }
}

#[test]
fn pcapng_interfaces_are_channels_with_their_own_clocks() {
    for o in [Order::Little, Order::Big] {
        let mut f = shb(o);
        f.extend(idb(o, 113, &[(2, b"can0"), (9, &[9])]));
        f.extend(idb(o, 212, &[(2, b"lin0")])); // LIN: not CAN
        // No name: its index, and the device's (7) for LINUX_SLL2.
        f.extend(idb(o, 276, &[(9, &[0x80 | 10])]));
        let offset = u64::to_be_bytes(1_700_000_000);
        let offset = match o {
            Order::Big => offset,
            Order::Little => u64::to_le_bytes(1_700_000_000),
        };
        f.extend(idb(o, 227, &[(2, b"vcan 1"), (14, &offset)]));
        f.extend(epb(
            o,
            0,
            1_700_000_001_250_000_001,
            &sll(0x0C, &can(o, 0x81, &EMCY)),
        ));
        f.extend(epb(o, 1, 5, &[0x3C, 1, 2, 3]));
        f.extend(epb(
            o,
            2,
            1024 * 1_700_000_002 + 1,
            &sll2(0x0C, &can(o, 0x82, &EMCY)),
        ));
        f.extend(epb(o, 3, 2_500_000, &can(Order::Big, 0x83, &EMCY)));
        f.extend(block(o, 5, &[0; 12])); // statistics: not a line
        f.extend(epb(
            o,
            0,
            1_700_000_003_000_000_000,
            &sll(0x0800, &[0x45; 20]),
        ));
        let (got, notes) = read(&f);
        assert_eq!(
            got,
            [
                frame("1700000001.250000001", "can0", 0x81, &EMCY),
                Got::Skipped,
                frame("1700000002.0009765625", "2:7", 0x82, &EMCY),
                frame("1700000002.500000", "vcan 1", 0x83, &EMCY),
                Got::Skipped,
            ],
            "{o:?}"
        );
        assert!(notes.is_empty(), "{notes:?}");
    }
}

/// `tcpdump -i any` / `dumpcap -i any` write LINUX_SLL2 on one interface
/// for every device: the device's interface index tells the buses apart,
/// so node 1 on two buses is two nodes. A named device keeps its name.
#[test]
fn the_devices_of_an_any_capture_are_channels_of_their_own() {
    let o = Order::Little;
    let sll2_on = |index: u8, frame: &[u8]| {
        let mut p = sll2(0x0C, frame);
        p[7] = index;
        p
    };
    let mut f = shb(o);
    f.extend(idb(o, 276, &[(2, b"any")]));
    f.extend(idb(o, 276, &[(2, b"can9")]));
    f.extend(epb(o, 0, 1, &sll2_on(3, &can(o, 0x81, &EMCY))));
    f.extend(epb(o, 0, 2, &sll2_on(4, &can(o, 0x81, &EMCY))));
    f.extend(epb(o, 1, 3, &sll2_on(5, &can(o, 0x81, &EMCY))));
    let (got, notes) = read(&f);
    assert_eq!(
        got,
        [
            frame("0.000001", "any:3", 0x81, &EMCY),
            frame("0.000002", "any:4", 0x81, &EMCY),
            frame("0.000003", "can9", 0x81, &EMCY),
        ]
    );
    assert!(notes.is_empty(), "{notes:?}");
}

#[test]
fn a_new_section_starts_new_interfaces_in_its_own_byte_order() {
    let mut f = shb(Order::Little);
    f.extend(idb(Order::Little, 113, &[(2, b"a")]));
    f.extend(epb(
        Order::Little,
        0,
        1,
        &sll(0x0C, &can(Order::Little, 0x81, &EMCY)),
    ));
    f.extend(shb(Order::Big));
    f.extend(idb(Order::Big, 113, &[(2, b"b")]));
    f.extend(epb(
        Order::Big,
        0,
        2,
        &sll(0x0C, &can(Order::Big, 0x81, &EMCY)),
    ));
    let (got, _) = read(&f);
    assert_eq!(
        got,
        [
            frame("0.000001", "a", 0x81, &EMCY),
            frame("0.000002", "b", 0x81, &EMCY)
        ]
    );
}

#[test]
fn can_fd_remote_error_and_extended_frames() {
    let o = Order::Little;
    let mut f = shb(o);
    f.extend(idb(o, 113, &[]));
    let mut fd = can(o, 0x81, &[0x11; 12]);
    fd.resize(72, 0);
    f.extend(epb(o, 0, 1, &sll(0x0D, &fd)));
    f.extend(epb(o, 0, 2, &sll(0x0C, &can(o, 0x4000_0081, &[]))));
    f.extend(epb(o, 0, 3, &sll(0x0C, &can(o, 0x2000_0004, &[0; 8]))));
    f.extend(epb(o, 0, 4, &sll(0x0C, &can(o, 0x8000_0081, &EMCY))));
    let (got, _) = read(&f);
    let kinds: Vec<_> = got
        .iter()
        .map(|g| match g {
            Got::Frame {
                kind,
                id,
                extended,
                data,
                ..
            } => (*kind, *id, *extended, data.len()),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(
        kinds,
        [
            (FrameKind::Fd, 0x81, false, 12),
            (FrameKind::Remote, 0x81, false, 0),
            (FrameKind::Error, 0x004, false, 8),
            (FrameKind::Data, 0x81, true, 8),
        ]
    );
    let Got::Frame { channel, .. } = &got[0] else {
        unreachable!()
    };
    assert_eq!(channel, "0", "an interface without if_name is its index");
}

#[test]
fn simple_and_obsolete_packet_blocks_are_packets() {
    let o = Order::Little;
    let mut f = shb(o);
    f.extend(idb(o, 227, &[(2, b"can0")]));
    let frame_bytes = can(Order::Big, 0x81, &EMCY);
    let mut spb = u32s(o, frame_bytes.len() as u32).to_vec();
    spb.extend(&frame_bytes);
    f.extend(block(o, 3, &spb));
    let mut pb = u16s(o, 0).to_vec();
    pb.extend(u16s(o, 0));
    pb.extend(u32s(o, 0));
    pb.extend(u32s(o, 7_000_000));
    pb.extend(u32s(o, frame_bytes.len() as u32));
    pb.extend(u32s(o, frame_bytes.len() as u32));
    pb.extend(&frame_bytes);
    f.extend(block(o, 2, &pb));
    let (got, _) = read(&f);
    assert_eq!(
        got,
        [
            frame("", "can0", 0x81, &EMCY),
            frame("7.000000", "can0", 0x81, &EMCY)
        ]
    );
}

/// Link type 227 written little-endian, as scapy writes it.
fn scapy(ids: &[u32]) -> Vec<u8> {
    let mut f = pcap_header(Order::Little, false, 227);
    for (i, id) in ids.iter().enumerate() {
        let data = if (0x81..=0xFF).contains(id) {
            &EMCY[..]
        } else {
            &RESET[..2]
        };
        f.extend(record(
            Order::Little,
            1,
            i as u32,
            &can(Order::Little, *id, data),
        ));
    }
    f
}

#[test]
fn little_endian_socketcan_ids_are_detected_and_noted_once() {
    let ids: Vec<u32> = (0..100)
        .map(|i| [0x81, 0x701, 0x181, 0x000][i % 4])
        .collect();
    let (got, notes) = read(&scapy(&ids));
    assert_eq!(got.len(), 100);
    for (g, id) in got.iter().zip(&ids) {
        match g {
            Got::Frame {
                id: got_id,
                extended,
                kind,
                ..
            } => assert_eq!((*got_id, *extended, *kind), (*id, false, FrameKind::Data)),
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].contains("little-endian"), "{notes:?}");
    // Only EMCYs (ids that read as extended ids either way): still told apart.
    let (got, notes) = read(&scapy(&[0x81, 0x82, 0x81]));
    assert!(
        matches!(
            got[1],
            Got::Frame {
                id: 0x82,
                extended: false,
                ..
            }
        ),
        "{got:?}"
    );
    assert_eq!(notes.len(), 1);
    // One packet proves nothing: read as the link type says.
    let (got, notes) = read(&scapy(&[0x82]));
    assert!(
        matches!(
            got[0],
            Got::Frame {
                id: 0x0200_0000,
                extended: true,
                ..
            }
        ),
        "{got:?}"
    );
    assert!(notes.is_empty());
    let (got, notes) = read(&scapy(&[0x82, 0x82]));
    assert!(
        matches!(
            got[1],
            Got::Frame {
                id: 0x82,
                extended: false,
                ..
            }
        ),
        "{got:?}"
    );
    assert_eq!(notes.len(), 1);
}

#[test]
fn big_endian_socketcan_ids_are_read_as_the_link_type_says() {
    let mut f = pcap_header(Order::Little, false, 227);
    for id in [0x81, 0x701, 0x8123_4567, 0x2000_0004, 0] {
        let data = if id == 0x2000_0004 {
            &RESET[..]
        } else {
            &EMCY[..]
        };
        f.extend(record(Order::Little, 1, 0, &can(Order::Big, id, data)));
    }
    let (got, notes) = read(&f);
    assert!(notes.is_empty(), "{notes:?}");
    let ids: Vec<u32> = got
        .iter()
        .map(|g| match g {
            Got::Frame { id, .. } => *id,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(ids, [0x81, 0x701, 0x0123_4567, 0x004, 0]);
}

#[test]
fn held_packets_keep_their_order_and_channels() {
    // SLL packets on one interface between little-endian 227 packets on
    // another: all held until the order is known, then in file order.
    let o = Order::Little;
    let mut f = shb(o);
    f.extend(idb(o, 227, &[(2, b"swapped")]));
    f.extend(idb(o, 113, &[(2, b"cooked")]));
    let mut want = Vec::new();
    for i in 0..40u64 {
        let iface = (i % 2) as u32;
        let id = 0x81 + (i % 3) as u32;
        let packet = if iface == 0 {
            can(Order::Little, id, &EMCY)
        } else {
            sll(0x0C, &can(o, id, &EMCY))
        };
        f.extend(epb(o, iface, i, &packet));
        want.push(frame(
            &format!("0.{i:06}"),
            ["swapped", "cooked"][iface as usize],
            id,
            &EMCY,
        ));
        if i == 20 {
            // A new section while packets are held: they keep their channels.
            f.extend(shb(o));
            f.extend(idb(o, 227, &[(2, b"swapped")]));
            f.extend(idb(o, 113, &[(2, b"cooked")]));
        }
    }
    let (got, notes) = read(&f);
    assert_eq!(got, want);
    assert_eq!(notes.len(), 1);
}

#[test]
fn insane_lengths_are_diagnostics_and_reading_goes_on() {
    let o = Order::Little;
    let good = |t: u64| epb(o, 0, t, &sll(0x0C, &can(o, 0x81, &EMCY)));
    let mut f = shb(o);
    f.extend(idb(o, 113, &[]));
    f.extend(good(1));
    let at = f.len();
    // A block declaring 4 GiB: never buffered.
    let mut huge = good(2);
    huge[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
    f.extend(&huge);
    f.extend(good(3));
    // Garbage between blocks.
    f.extend(b"garbage!");
    f.extend(good(4));
    // A trailing length that differs.
    let mut bad_trailer = good(5);
    let n = bad_trailer.len();
    bad_trailer[n - 4] ^= 0x40;
    f.extend(&bad_trailer);
    f.extend(good(6));
    let (got, _) = read(&f);
    let times: Vec<&str> = got
        .iter()
        .filter_map(|g| match g {
            Got::Frame { time, .. } => Some(time.as_str()),
            _ => None,
        })
        .collect();
    assert_eq!(
        times,
        ["0.000001", "0.000003", "0.000004", "0.000006"],
        "{got:?}"
    );
    let reasons: Vec<&str> = got
        .iter()
        .filter_map(|g| match g {
            Got::Malformed(r) => Some(r.as_str()),
            _ => None,
        })
        .collect();
    assert_eq!(reasons.len(), 3, "{got:?}");
    assert!(
        reasons[0].starts_with(&format!(
            "block of type 0x00000006 at byte {at} declares 4294967295 bytes"
        )),
        "{reasons:?}"
    );
    assert!(
        reasons[0].ends_with(&format!("{} bytes skipped to the next block", huge.len())),
        "{reasons:?}"
    );
    assert!(reasons[1].contains("8 bytes skipped"), "{reasons:?}");
    assert!(reasons[2].contains("but ends with"), "{reasons:?}");
    let mut r = PcapReader::new(&f[..]).unwrap();
    while r.next_packet().unwrap().is_some() {}
    assert_eq!(
        r.capacity, BUFFER,
        "no buffer grew for a length that is not sane"
    );
}

#[test]
fn a_block_whose_content_is_wrong_is_skipped_by_its_length() {
    let o = Order::Little;
    let mut f = shb(o);
    f.extend(idb(o, 113, &[]));
    // An EPB whose captured length runs past its block.
    let mut body = u32s(o, 0).to_vec();
    body.extend([0; 8]);
    body.extend(u32s(o, 1000));
    body.extend(u32s(o, 1000));
    body.extend([0; 8]);
    f.extend(block(o, 6, &body));
    // A packet on an interface nobody described.
    f.extend(epb(o, 9, 1, &sll(0x0C, &can(o, 0x81, &EMCY))));
    // A CAN frame with 9 bytes.
    f.extend(epb(o, 0, 1, &sll(0x0C, &can(o, 0x81, &[0; 9]))));
    f.extend(epb(o, 0, 2, &sll(0x0C, &can(o, 0x81, &EMCY))));
    let (got, _) = read(&f);
    assert_eq!(got.len(), 4, "{got:?}");
    assert!(malformed(&got[0]).contains("runs past its end"), "{got:?}");
    assert!(malformed(&got[1]).contains("interface 9"), "{got:?}");
    assert!(
        malformed(&got[2]).contains("LINUX_SLL packet: classic CAN frame of 9 bytes"),
        "{got:?}"
    );
    assert_eq!(got[3], frame("0.000002", "0", 0x81, &EMCY));
}

#[test]
fn a_pcap_record_too_long_to_be_one_is_skipped_to_the_next_record() {
    let o = Order::Big;
    let mut f = pcap_header(o, false, 227);
    f.extend(record(o, 1, 0, &can(Order::Big, 0x81, &EMCY)));
    let mut bad = record(o, 2, 0, &can(Order::Big, 0x81, &EMCY));
    bad[8..12].copy_from_slice(&u32::MAX.to_be_bytes());
    f.extend(&bad);
    f.extend(record(o, 3, 0, &can(Order::Big, 0x81, &EMCY)));
    f.extend(record(o, 4, 0, &can(Order::Big, 0x81, &EMCY)));
    let (got, _) = read(&f);
    assert_eq!(got.len(), 4, "{got:?}");
    assert!(
        malformed(&got[1])
            .starts_with("packet record at byte 56 declares 4294967295 captured bytes"),
        "{got:?}"
    );
    assert!(
        malformed(&got[1]).ends_with("32 bytes skipped to the next record"),
        "{got:?}"
    );
    assert_eq!(got[2], frame("3.000000", "0", 0x81, &EMCY));
}

/// A followed capture truncated or replaced by a restarted writer: the new
/// file's header where a record should be starts it over, in its own byte
/// order, time unit and link type.
#[test]
fn a_new_file_header_in_the_stream_starts_a_new_file() {
    let mut f = pcap_header(Order::Big, false, 227);
    f.extend(record(Order::Big, 1, 0, &can(Order::Big, 0x81, &EMCY)));
    let at = f.len();
    f.extend(pcap_header(Order::Little, true, 113));
    f.extend(record(
        Order::Little,
        1_700_000_000,
        5,
        &sll(0x0C, &can(Order::Little, 0x82, &EMCY)),
    ));
    let (got, notes) = read(&f);
    assert_eq!(
        got,
        [
            frame("1.000000", "0", 0x81, &EMCY),
            frame("1700000000.000000005", "0", 0x82, &EMCY)
        ]
    );
    assert_eq!(
        notes,
        [format!(
            "a new pcap file header at byte {at} (the file was truncated or replaced, as by a \
             restarted capture): reading on with it"
        )]
    );
    // A file cut inside a record: the record is damage, and the resync
    // stops at the new header.
    let mut cut = pcap_header(Order::Little, false, 227);
    let mut half = record(Order::Little, 1, 0, &can(Order::Big, 0x81, &EMCY));
    half[8..12].copy_from_slice(&300_000u32.to_le_bytes());
    cut.extend(&half[..20]);
    cut.extend(pcap_header(Order::Little, false, 227));
    cut.extend(record(Order::Little, 2, 0, &can(Order::Big, 0x82, &EMCY)));
    let (got, notes) = read(&cut);
    assert_eq!(got.len(), 2, "{got:?}");
    assert!(malformed(&got[0]).contains("20 bytes skipped"), "{got:?}");
    assert_eq!(got[1], frame("2.000000", "0", 0x82, &EMCY));
    assert_eq!(notes.len(), 1, "{notes:?}");
}

#[test]
fn a_truncated_file_reports_the_cut_packet() {
    let o = Order::Little;
    let mut f = shb(o);
    f.extend(idb(o, 113, &[]));
    f.extend(epb(o, 0, 1, &sll(0x0C, &can(o, 0x81, &EMCY))));
    let whole = f.len();
    f.extend(epb(o, 0, 2, &sll(0x0C, &can(o, 0x81, &EMCY))));
    for cut in [whole + 5, whole + 20, f.len() - 1] {
        let (got, _) = read(&f[..cut]);
        assert_eq!(got.len(), 2, "{got:?}");
        assert!(
            malformed(&got[1]).starts_with("the file ends inside"),
            "{got:?}"
        );
        assert!(
            malformed(&got[1]).contains(&format!("at byte {whole}")),
            "{got:?}"
        );
    }
    let mut p = pcap_header(o, false, 227);
    p.extend(record(o, 1, 0, &can(Order::Big, 0x81, &EMCY)));
    let (got, _) = read(&p[..p.len() - 3]);
    assert!(
        malformed(&got[0]).contains("ends inside the packet at byte 24 (29 of 32 bytes)"),
        "{got:?}"
    );
}

#[test]
fn headers_that_are_not_ones_are_errors() {
    let err = |b: &[u8]| PcapReader::new(b).err().expect("an error").to_string();
    assert!(
        err(b"(1.0) can0 081#00")
            .starts_with("not a pcap or pcapng file: it starts with 28 31 2E 30")
    );
    assert!(err(b"").contains("starts with nothing"));
    assert!(err(&pcap_header(Order::Little, false, 227)[..20]).contains("cut off after 20 of 24"));
    assert!(err(&shb(Order::Little)[..12]).contains("cut off after 12 of 28"));
    let mut no_bom = shb(Order::Little);
    no_bom[8] = 0;
    assert!(err(&no_bom).contains("no byte-order magic"));
    let mut huge = shb(Order::Little);
    huge[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(err(&huge).contains("not sane"));
}

#[test]
fn a_read_error_comes_after_the_packets_read_before_it() {
    struct Failing<'a>(&'a [u8]);
    impl Read for Failing<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            if self.0.is_empty() {
                return Err(io::Error::other("device gone"));
            }
            let n = buf.len().min(self.0.len());
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }
    // Held 227 packets (the order not known yet) are not lost either.
    let f = scapy(&[0x81, 0x82]);
    let mut r = PcapReader::new(Failing(&f)).unwrap();
    let mut frames = 0;
    let error = loop {
        match r.next_packet() {
            Ok(Some(Parsed::Frame(_))) => frames += 1,
            Ok(other) => panic!("{other:?}"),
            Err(e) => break e,
        }
    };
    assert_eq!((frames, error.to_string().as_str()), (2, "device gone"));
    assert!(r.next_packet().unwrap().is_none());
}

#[test]
fn a_long_block_grows_the_buffer_as_far_as_it_needs() {
    let o = Order::Little;
    let mut f = shb(o);
    f.extend(idb(o, 113, &[]));
    f.extend(block(o, 0x0BAD, &vec![7u8; 3 * BUFFER])); // a custom block
    f.extend(epb(o, 0, 1, &sll(0x0C, &can(o, 0x81, &EMCY))));
    let mut r = PcapReader::new(&f[..]).unwrap();
    assert!(matches!(r.next_packet().unwrap(), Some(Parsed::Frame(_))));
    assert!(
        r.capacity >= 3 * BUFFER && r.capacity <= 4 * BUFFER,
        "{}",
        r.capacity
    );
}

#[cfg(feature = "fuzzing")]
#[test]
fn the_fixtures_pass_the_fuzz_target_body() {
    for name in [
        "s300.pcap",
        "s300.ns-be.pcap",
        "s300.swapped.pcap",
        "s300.pcapng",
        "mixed.pcapng",
    ] {
        // The fixtures are the workspace's, two folders up.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures")
            .join(name);
        fuzz_pcap(&std::fs::read(path).expect("fixture"));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// Random classic frames written in any flavour read back as written,
    /// in any read sizes.
    #[test]
    fn random_frames_round_trip(
        frames in prop::collection::vec(
            (any::<bool>(), 0u32..0x2000_0000, prop::collection::vec(any::<u8>(), 0..=8), any::<u32>()),
            0..40,
        ),
        big in any::<bool>(),
        ng in any::<bool>(),
        link in 0usize..3,
        step in 1usize..100,
    ) {
        let o = if big { Order::Big } else { Order::Little };
        let linktype = [227u16, 113, 276][link];
        let packet = |word: u32, data: &[u8]| match linktype {
            227 => can(Order::Big, word, data),
            113 => sll(0x0C, &can(o, word, data)),
            _ => sll2(0x0C, &can(o, word, data)),
        };
        let mut f = if ng {
            let mut f = shb(o);
            f.extend(idb(o, linktype, &[(2, b"bus")]));
            f
        } else {
            pcap_header(o, false, u32::from(linktype))
        };
        let mut want = Vec::new();
        for (extended, id, data, ticks) in &frames {
            let id = if *extended { *id } else { id & 0x7FF };
            let word = id | if *extended { 0x8000_0000 } else { 0 };
            if ng {
                f.extend(epb(o, 0, u64::from(*ticks), &packet(word, data)));
            } else {
                f.extend(record(o, ticks / 1_000_000, ticks % 1_000_000, &packet(word, data)));
            }
            want.push(Got::Frame {
                time: format!("{}.{:06}", ticks / 1_000_000, ticks % 1_000_000),
                // SLL2 without an interface name (pcap): several devices.
                channel: match (ng, linktype) {
                    (true, _) => "bus",
                    (false, 276) => "0:7",
                    (false, _) => "0",
                }
                .into(),
                id,
                extended: *extended,
                kind: FrameKind::Data,
                data: data.clone(),
            });
        }
        let (got, notes) = read_with(Trickle { data: &f, step });
        prop_assert_eq!(got, want);
        prop_assert!(notes.is_empty());
        counts_add_up(&f, "random frames");
        // The hot path (with an interest) reads them as the general one.
        #[cfg(feature = "fuzzing")]
        fuzz_pcap(&f);
    }

    /// Any bytes after a valid header: no panic, no endless loop, frames
    /// well-formed (the fuzz target's body).
    #[test]
    fn any_bytes_are_read_to_the_end(body in prop::collection::vec(any::<u8>(), 0..400), ng in any::<bool>()) {
        let mut f = if ng {
            let mut f = shb(Order::Little);
            f.extend(idb(Order::Little, 227, &[]));
            f
        } else {
            pcap_header(Order::Little, false, 113)
        };
        f.extend(&body);
        let _ = read_with(&f[..]);
        #[cfg(feature = "fuzzing")]
        fuzz_pcap(&f);
    }
}
