//! The fuzz targets' side of the reader: a capture built from one packet,
//! and the body of the `pcap` target.

use crate::id_counts::testing::{count_frame, table};
use crate::{Format, FrameSource, IdCounts, Interest, Parsed};

use super::consts::{BOM, BUFFER, EPB, MAX_BLOCK, MAX_HELD};
use super::reader::PcapReader;

/// A pcapng capture of `packet`, `copies` times, on one interface of
/// `linktype` (nanosecond times): what the `ethercat` fuzz target reads.
#[cfg(feature = "fuzzing")]
pub fn capture_of(linktype: u16, packet: &[u8], copies: u32) -> Vec<u8> {
    fn block(out: &mut Vec<u8>, kind: u32, body: &[u8]) {
        let padded = body.len().next_multiple_of(4);
        let len = (12 + padded) as u32;
        out.extend_from_slice(&kind.to_le_bytes());
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(body);
        out.resize(out.len() + padded - body.len(), 0);
        out.extend_from_slice(&len.to_le_bytes());
    }
    let mut out = Vec::new();
    let mut shb = BOM.to_le_bytes().to_vec();
    shb.extend_from_slice(&[1, 0, 0, 0]);
    shb.extend_from_slice(&(-1i64).to_le_bytes());
    block(&mut out, 0x0A0D_0D0A, &shb);
    let mut idb = u32::from(linktype).to_le_bytes().to_vec();
    idb.extend_from_slice(&0u32.to_le_bytes());
    // if_tsresol 9: nanoseconds.
    idb.extend_from_slice(&[9, 0, 1, 0, 9, 0, 0, 0, 0, 0, 0, 0]);
    block(&mut out, 1, &idb);
    for i in 0..copies {
        let units = 1_700_000_000_000_000_000u64 + u64::from(i) * 1_000_000;
        let mut epb = 0u32.to_le_bytes().to_vec();
        epb.extend_from_slice(&((units >> 32) as u32).to_le_bytes());
        epb.extend_from_slice(&(units as u32).to_le_bytes());
        epb.extend_from_slice(&(packet.len() as u32).to_le_bytes());
        epb.extend_from_slice(&(packet.len() as u32).to_le_bytes());
        epb.extend_from_slice(packet);
        block(&mut out, EPB, &epb);
    }
    out
}

/// Fuzz target body: any bytes must read to the end without a panic or an
/// endless loop, every frame well-formed, the buffers bounded.
#[cfg(feature = "fuzzing")]
pub fn fuzz_pcap(data: &[u8]) {
    use crate::{FrameKind, Payload};
    let Ok(mut r) = PcapReader::new(data) else {
        return;
    };
    let mut packets = 0usize;
    let timed = r.format == Format::Pcap;
    while let Ok(Some(parsed)) = r.next_packet() {
        packets += 1;
        // Every line consumes at least one byte of input.
        assert!(packets <= data.len(), "no progress");
        if let Parsed::Frame(f) = parsed {
            assert!(usize::from(f.len) <= Payload::MAX);
            match f.kind {
                FrameKind::Data => {
                    assert!(f.len <= 8);
                    assert_eq!(f.data.len(), usize::from(f.len));
                }
                FrameKind::Fd => assert_eq!(f.data.len(), usize::from(f.len)),
                FrameKind::Remote => assert!(f.data.is_empty()),
                FrameKind::Error => assert!(!f.extended && f.id & 0x2000_0000 == 0),
            }
            if f.kind != FrameKind::Error {
                assert!(f.id <= if f.extended { 0x1FFF_FFFF } else { 0x7FF });
            }
            assert!(!f.channel.is_empty());
            if timed {
                assert!(f.time.is_some());
            }
        }
        assert!(r.held.len() <= MAX_HELD);
    }
    assert!(r.capacity <= MAX_BLOCK.max(BUFFER) + 32);
    while r.take_note().is_some() {}

    // Read again with the EMCY ids as the interest: the frames it does not
    // want are only counted, everything else comes out as without it.
    let mut interest = Interest::none();
    interest.add_standard_range(0x81..=0xFF);
    let wanted = |p: &Parsed<'_>| match p {
        Parsed::Frame(f) => match f.kind {
            FrameKind::Data | FrameKind::Remote => interest.wants(f.id, f.extended),
            FrameKind::Fd => interest.wants_fd_on(f.id, f.extended),
            FrameKind::Error => false,
        },
        _ => true,
    };
    // What a packet shows (an EtherCAT frame's messages are part of it),
    // pushed with the count of plain ones before it; plain ones (and quiet
    // EtherCAT frames, only counted under an interest) only counted.
    let classify = |r: &mut PcapReader<&[u8]>,
                    want: bool,
                    text: String,
                    seen: &mut Vec<(u64, String)>,
                    plain: &mut u64| {
        let ethercat = r
            .take_ethercat()
            .map(|(e, channel)| (e.quiet(), format!("{e:?} on {channel:?}")));
        let shown = match ethercat {
            Some((true, _)) => None,
            Some((false, e)) => Some(format!("{text} {e}")),
            None => want.then_some(text),
        };
        match shown {
            Some(shown) => seen.push((std::mem::take(plain), shown)),
            None => *plain += 1,
        }
    };
    let shown = |p: &Parsed<'_>| format!("{p:?}");
    let mut full = PcapReader::new(data).expect("read once");
    let mut expected = Vec::new();
    let mut plain = 0u64;
    // Every frame, by channel and identifier.
    let mut every = IdCounts::new();
    while let Ok(Some(p)) = full.next_packet() {
        if let Parsed::Frame(f) = &p {
            count_frame(&mut every, f);
        }
        let (want, text) = (wanted(&p), shown(&p));
        classify(&mut full, want, text, &mut expected, &mut plain);
    }
    let mut fast = PcapReader::new(data).expect("read once");
    let mut got = Vec::new();
    let mut counted = 0u64;
    let mut handed_on = IdCounts::new();
    while let Ok(more) = fast.advance(Some(&interest)) {
        counted += fast.take_counted().0 + fast.take_quiet();
        if !more {
            break;
        }
        // Held packets (link type 227 before its byte order is known)
        // come out whole: the caller's own check makes them plain (and
        // the quiet EtherCAT frames among them).
        if let Some(p) = fast.take() {
            if let Parsed::Frame(f) = &p {
                count_frame(&mut handed_on, f);
            }
            let (want, text) = (wanted(&p), shown(&p));
            classify(&mut fast, want, text, &mut got, &mut counted);
        }
    }
    counted += fast.take_counted().0 + fast.take_quiet();
    assert_eq!(
        fast.ethercat_counts(),
        full.ethercat_counts(),
        "the same EtherCAT counts with and without the interest"
    );
    assert_eq!(
        got, expected,
        "the same packets with and without the interest"
    );
    assert_eq!(
        counted, plain,
        "the same plain frames after the last packet"
    );
    if let Some(ids) = fast.counted_ids() {
        handed_on.add(ids);
    }
    assert_eq!(
        table(&handed_on),
        table(&every),
        "the frames handed on and those only counted are every frame, by channel and id"
    );
}
