use std::io::Write;

use proptest::prelude::*;

use super::*;
use crate::id_counts::testing::{self, assert_counts_add_up};

/// MF4 bytes block by block; links patched afterwards.
struct B {
    out: Vec<u8>,
}

impl B {
    fn new(ident: &[u8; 8], unfin: u16) -> B {
        let mut out = ident.to_vec();
        out.extend(b"4.11    TEST    ");
        out.resize(60, 0);
        out.extend(unfin.to_le_bytes());
        out.extend([0, 0]);
        B { out }
    }

    fn block(&mut self, id: &[u8; 2], links: &[u64], data: &[u8]) -> u64 {
        while !self.out.len().is_multiple_of(8) {
            self.out.push(0);
        }
        let at = self.out.len() as u64;
        self.out.extend(b"##");
        self.out.extend(id);
        self.out.extend([0; 4]);
        self.out
            .extend(((24 + 8 * links.len() + data.len()) as u64).to_le_bytes());
        self.out.extend((links.len() as u64).to_le_bytes());
        for l in links {
            self.out.extend(l.to_le_bytes());
        }
        self.out.extend(data);
        at
    }

    fn link(&mut self, at: u64, i: usize, v: u64) {
        let p = at as usize + 24 + 8 * i;
        self.out[p..p + 8].copy_from_slice(&v.to_le_bytes());
    }

    fn hd(&mut self, flags: u8) -> u64 {
        let mut d = (1_700_000_000u64 * 1_000_000_000).to_le_bytes().to_vec();
        d.extend([0, 0, 0, 0, flags, 0, 0, 0]);
        d.extend([0; 16]);
        self.block(b"HD", &[0; 6], &d)
    }

    fn tx(&mut self, s: &str) -> u64 {
        let mut d = s.as_bytes().to_vec();
        d.push(0);
        self.block(b"TX", &[], &d)
    }

    fn cc_linear(&mut self, offset: f64, factor: f64) -> u64 {
        let mut d = vec![1, 0, 0, 0, 0, 0, 2, 0];
        d.extend([0; 16]);
        d.extend(offset.to_le_bytes());
        d.extend(factor.to_le_bytes());
        self.block(b"CC", &[0; 4], &d)
    }

    #[allow(clippy::too_many_arguments)]
    fn cn(
        &mut self,
        name: &str,
        kind: u8,
        dtype: u8,
        byte: u32,
        bit: u8,
        bits: u32,
        cc: u64,
    ) -> u64 {
        let name = self.tx(name);
        let sync = u8::from(kind == 2);
        let mut d = vec![kind, sync, dtype, bit];
        d.extend(byte.to_le_bytes());
        d.extend(bits.to_le_bytes());
        d.extend([0; 12]);
        d.extend([0; 4]);
        d.extend([0; 48]);
        self.block(b"CN", &[0, 0, name, 0, cc, 0, 0, 0], &d)
    }

    fn chain(&mut self, cns: &[u64]) -> u64 {
        for w in cns.windows(2) {
            self.link(w[0], 0, w[1]);
        }
        cns.first().copied().unwrap_or(0)
    }

    fn cg(&mut self, name: &str, rid: u64, bytes: u32, cn_first: u64, flags: u16) -> u64 {
        let name = if name.is_empty() { 0 } else { self.tx(name) };
        let mut d = rid.to_le_bytes().to_vec();
        d.extend(0u64.to_le_bytes());
        d.extend(flags.to_le_bytes());
        d.extend([0; 6]);
        d.extend(bytes.to_le_bytes());
        d.extend(0u32.to_le_bytes());
        self.block(b"CG", &[0, cn_first, name, 0, 0, 0], &d)
    }

    fn dg(&mut self, rid_size: u8) -> u64 {
        let mut d = vec![rid_size];
        d.extend([0; 7]);
        self.block(b"DG", &[0; 4], &d)
    }
}

/// A data frame group: u64 microseconds, u32 ID (bit 31: IDE), u8
/// DataLength, 8 fixed data bytes; `vlsd`: the data bytes are a VLSD
/// offset into group `rid + 1` instead.
fn can_group(b: &mut B, rid: u64, vlsd: bool) -> (u64, u64) {
    let us = b.cc_linear(0.0, 1e-6);
    let t = b.cn("t", 2, 0, 0, 0, 64, us);
    let id = b.cn("CAN_DataFrame.ID", 0, 0, 8, 0, 32, 0);
    let len = b.cn("CAN_DataFrame.DataLength", 0, 0, 12, 0, 8, 0);
    let data = b.cn("CAN_DataFrame.DataBytes", u8::from(vlsd), 10, 13, 0, 64, 0);
    let first = b.chain(&[t, id, len, data]);
    let cg = b.cg("CAN_DataFrame", rid, 21, first, 6);
    let mut vg = 0;
    if vlsd {
        vg = b.cg("", rid + 1, 0, 0, 1);
        b.link(cg, 0, vg);
        b.link(data, 5, vg);
    }
    (cg, vg)
}

fn record(us: u64, id: u32, data: &[u8]) -> Vec<u8> {
    let mut r = us.to_le_bytes().to_vec();
    r.extend(id.to_le_bytes());
    r.push(data.len() as u8);
    let mut d = data.to_vec();
    d.resize(8, 0);
    r.extend(d);
    r
}

/// An unsorted file: header, one DG with the CAN group (id 1, VLSD 2),
/// the DT block's data given.
fn unsorted(ident: &[u8; 8], unfin: u16, vlsd: bool, dt_len_24: bool, data: &[u8]) -> Vec<u8> {
    let mut b = B::new(ident, unfin);
    let hd = b.hd(2);
    let dg = b.dg(1);
    let (cg, _) = can_group(&mut b, 1, vlsd);
    b.link(dg, 1, cg);
    b.link(hd, 0, dg);
    let dt = if dt_len_24 {
        let at = b.block(b"DT", &[], &[]);
        b.out.extend(data);
        at
    } else {
        b.block(b"DT", &[], data)
    };
    b.link(dg, 2, dt);
    b.out
}

#[derive(Debug, PartialEq)]
enum Line {
    F(String, u32, bool, FrameKind, Vec<u8>),
    S,
    M(String),
}

/// Reads `bytes` with each of the tests' interests: the frames only
/// counted, by channel and identifier, plus those handed on must be every
/// frame. Returns how many were only counted.
fn counts_add_up(bytes: &[u8], what: &str) -> u64 {
    let mut counted = 0;
    for (label, interest) in testing::interests() {
        let (Ok(mut all), Ok(mut some)) = (Mf4Reader::new(bytes), Mf4Reader::new(bytes)) else {
            return counted;
        };
        counted +=
            assert_counts_add_up(&mut all, &mut some, &interest, &format!("{what}, {label}"));
    }
    counted
}

/// Reads `bytes` record by record; the frames only counted must add up
/// ([`counts_add_up`]).
fn read(bytes: &[u8]) -> (Vec<Line>, Vec<String>) {
    counts_add_up(bytes, "a file built here");
    let mut r = Mf4Reader::new(bytes).expect("an MDF 4 file");
    let mut lines = Vec::new();
    let mut notes = Vec::new();
    loop {
        let next = r.next_record().expect("no I/O error");
        let Some(p) = next else { break };
        lines.push(match p {
            Parsed::Frame(f) => Line::F(
                f.time.map(|t| t.to_string()).unwrap_or_default(),
                f.id,
                f.extended,
                f.kind,
                f.data.as_slice().to_vec(),
            ),
            Parsed::Skipped => Line::S,
            Parsed::Malformed(m) => Line::M(m.into_owned()),
        });
        while let Some(n) = r.take_note() {
            notes.push(n);
        }
    }
    while let Some(n) = r.take_note() {
        notes.push(n);
    }
    (lines, notes)
}

fn f(us: u64, id: u32, ext: bool, data: &[u8]) -> Line {
    let t = Timestamp::from_raw(
        1_700_000_000 + us / 1_000_000,
        (us % 1_000_000) * 1_000_000_000_000,
        6,
    )
    .unwrap()
    .to_string();
    Line::F(t, id & 0x1FFF_FFFF, ext, FrameKind::Data, data.to_vec())
}

fn three() -> Vec<u8> {
    let mut d = vec![1];
    d.extend(record(1_000, 0x81, &[0x10, 0x43, 8]));
    d.push(1);
    d.extend(record(2_000, 0x8000_0085 | 0x1000_0000, &[1, 2, 3, 4]));
    d.push(1);
    d.extend(record(3_500_001, 0x701, &[5]));
    d
}

fn three_frames() -> Vec<Line> {
    vec![
        f(1_000, 0x81, false, &[0x10, 0x43, 8]),
        f(2_000, 0x1000_0085, true, &[1, 2, 3, 4]),
        f(3_500_001, 0x701, false, &[5]),
    ]
}

#[test]
fn the_fixtures_frames_only_counted_add_up_to_every_frame() {
    let mut counted = 0;
    for (name, bytes) in testing::fixtures(&["mf4"]) {
        counted += counts_add_up(&bytes, &name);
    }
    assert!(counted > 0, "some frames only counted");
}

/// How a test group stores its `BusChannel`.
#[derive(Clone, Copy)]
enum BusChannel {
    /// A byte of the record, as it is (the counting loop reads it).
    Stored,
    /// A virtual channel converted to this constant (CANedge's).
    Constant(u8),
    /// A byte of the record plus one (a conversion: records are decoded).
    Converted,
}

/// [`can_group`] with a `BusChannel` after the data bytes (22-byte
/// records) stored as `bus` says.
fn bus_group(b: &mut B, bus: BusChannel) -> u64 {
    let us = b.cc_linear(0.0, 1e-6);
    let t = b.cn("t", 2, 0, 0, 0, 64, us);
    let id = b.cn("CAN_DataFrame.ID", 0, 0, 8, 0, 32, 0);
    let len = b.cn("CAN_DataFrame.DataLength", 0, 0, 12, 0, 8, 0);
    let data = b.cn("CAN_DataFrame.DataBytes", 0, 10, 13, 0, 64, 0);
    let channel = match bus {
        BusChannel::Stored => b.cn("CAN_DataFrame.BusChannel", 0, 0, 21, 0, 8, 0),
        BusChannel::Constant(v) => {
            let constant = b.cc_linear(f64::from(v), 0.0);
            b.cn("CAN_DataFrame.BusChannel", 6, 0, 0, 0, 0, constant)
        }
        BusChannel::Converted => {
            let plus_one = b.cc_linear(1.0, 1.0);
            b.cn("CAN_DataFrame.BusChannel", 0, 0, 21, 0, 8, plus_one)
        }
    };
    let first = b.chain(&[t, id, len, data, channel]);
    b.cg("CAN_DataFrame", 1, 22, first, 6)
}

/// Frames only counted are counted under the channel their frame would
/// name, read from each record, constant for the group, or converted.
#[test]
fn frames_only_counted_are_counted_under_their_bus_channel() {
    let frames = [
        (0u8, 0x181, false),
        (1, 0x181, false),
        (1, 0x1000_0085, true),
        (0, 0x81, false),
        (0, 0x181, false),
    ];
    let mut records = Vec::new();
    for (i, &(bus, id, extended)) in frames.iter().enumerate() {
        records.push(1);
        let ide = if extended { 0x8000_0000 } else { 0 };
        records.extend(record(i as u64 * 1000, id | ide, &[1, 2]));
        records.push(bus);
    }
    let counted = |bus: BusChannel| {
        let mut b = B::new(b"MDF     ", 0);
        let hd = b.hd(2);
        let dg = b.dg(1);
        let cg = bus_group(&mut b, bus);
        b.link(dg, 1, cg);
        b.link(hd, 0, dg);
        let dt = b.block(b"DT", &[], &records);
        b.link(dg, 2, dt);
        assert_eq!(read(&b.out).0.len(), frames.len());
        let mut r = Mf4Reader::new(&b.out[..]).expect("an MDF 4 file");
        while r
            .next_item(Some(&Interest::none()))
            .expect("no I/O error")
            .is_some()
        {}
        let ids = r.counted_ids().expect("counts");
        ids.channels()
            .map(|c| {
                let name = String::from_utf8_lossy(c.name()).into_owned();
                (name, c.ids().collect::<Vec<_>>())
            })
            .collect::<Vec<_>>()
    };
    let on = |name: &str, ids: &[(u32, bool, u64)]| (name.to_string(), ids.to_vec());
    assert_eq!(
        counted(BusChannel::Stored),
        [
            on("0", &[(0x81, false, 1), (0x181, false, 2)]),
            on("1", &[(0x181, false, 1), (0x1000_0085, true, 1)]),
        ]
    );
    assert_eq!(
        counted(BusChannel::Constant(2)),
        [on(
            "2",
            &[(0x81, false, 1), (0x181, false, 3), (0x1000_0085, true, 1)]
        )]
    );
    assert_eq!(
        counted(BusChannel::Converted),
        [
            on("1", &[(0x81, false, 1), (0x181, false, 2)]),
            on("2", &[(0x181, false, 1), (0x1000_0085, true, 1)]),
        ]
    );
}

#[test]
fn an_unfinalized_last_dt_runs_to_the_end_of_the_input() {
    let file = unsorted(b"UnFinMF ", 0x25, false, true, &three());
    assert_eq!(read(&file).0, three_frames());
    // Without the flag the block is empty, and what follows is no block.
    let file = unsorted(b"MDF     ", 0, false, true, &three());
    let (lines, _) = read(&file);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        matches!(&lines[0], Line::M(m) if m.contains("are no MDF block")),
        "{lines:?}"
    );
}

#[test]
fn a_finalized_dt_holds_its_records_and_the_id_bit_31_is_ide() {
    let file = unsorted(b"MDF     ", 0, false, false, &three());
    assert_eq!(read(&file).0, three_frames());
}

#[test]
fn vlsd_data_before_or_after_its_frame_and_missing() {
    let vlsd = |data: &[u8]| {
        let mut v = vec![2];
        v.extend((data.len() as u32).to_le_bytes());
        v.extend(data);
        v
    };
    let frame = |offset: u64, len: u8| {
        let mut r = vec![1];
        r.extend(record(10, 0x81, &[]));
        r[13] = len;
        r[14..22].copy_from_slice(&offset.to_le_bytes());
        r
    };
    // Frame first (CANedge), then data first (the specification's order).
    let mut d = frame(0, 3);
    d.extend(vlsd(&[1, 2, 3]));
    d.extend(vlsd(&[4, 5]));
    d.extend(frame(7, 2));
    // A frame whose record never comes.
    d.extend(frame(500, 2));
    d.extend(vlsd(&[6]));
    let file = unsorted(b"UnFinMF ", 0x25, true, true, &d);
    let (lines, _) = read(&file);
    assert_eq!(
        lines,
        vec![
            f(10, 0x81, false, &[1, 2, 3]),
            Line::S,
            Line::S,
            f(10, 0x81, false, &[4, 5]),
            Line::M("no VLSD record at offset 500 for the frame's data bytes".into()),
            Line::S,
        ]
    );
}

#[test]
fn an_undeclared_record_id_loses_the_rest_of_its_block_only() {
    let mut d = three();
    d.insert(0, 7);
    let file = unsorted(b"MDF     ", 0, false, false, &d);
    let (lines, _) = read(&file);
    assert_eq!(lines.len(), 1);
    assert!(matches!(&lines[0], Line::M(m) if m.contains("record id 7 is not declared")));
}

#[test]
fn record_ids_of_2_4_and_8_bytes() {
    for size in [2u8, 4, 8] {
        let mut b = B::new(b"MDF     ", 0);
        let hd = b.hd(2);
        let dg = b.dg(size);
        let (cg, _) = can_group(&mut b, 0x0102, false);
        b.link(dg, 1, cg);
        b.link(hd, 0, dg);
        let mut d = 0x0102u64.to_le_bytes()[..size as usize].to_vec();
        d.extend(record(1_000, 0x81, &[0x10, 0x43, 8]));
        let dt = b.block(b"DT", &[], &d);
        b.link(dg, 2, dt);
        assert_eq!(
            read(&b.out).0,
            vec![f(1_000, 0x81, false, &[0x10, 0x43, 8])],
            "{size}"
        );
    }
}

fn zipped(plain: &[u8], transposed_columns: Option<usize>) -> Vec<u8> {
    let mut stored = plain.to_vec();
    if let Some(cols) = transposed_columns {
        let rows = plain.len() / cols;
        let whole = rows * cols;
        let mut t: Vec<u8> = (0..cols)
            .flat_map(|c| (0..rows).map(move |r| r * cols + c))
            .map(|i| plain[i])
            .collect();
        t.extend(&plain[whole..]);
        stored = t;
    }
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&stored).unwrap();
    let z = z.finish().unwrap();
    let mut d = b"DT".to_vec();
    d.push(u8::from(transposed_columns.is_some()));
    d.push(0);
    d.extend((transposed_columns.unwrap_or(0) as u32).to_le_bytes());
    d.extend((plain.len() as u64).to_le_bytes());
    d.extend((z.len() as u64).to_le_bytes());
    d.extend(z);
    d
}

/// A sorted file whose data is an HL -> DL of a DT and two DZ blocks
/// (deflate, transposed) with records split across them; the metadata
/// after the data when `meta_last` (the reader spools then).
fn sorted(meta_last: bool) -> Vec<u8> {
    let mut records = Vec::new();
    for i in 0..10u64 {
        records.extend(record(i * 1000, 0x81 + i as u32, &[i as u8; 8]));
    }
    let mut b = B::new(b"MDF     ", 0);
    let hd = b.hd(2);
    let meta = |b: &mut B| {
        let dg = b.dg(0);
        let (cg, _) = can_group(b, 0, false);
        b.link(dg, 1, cg);
        dg
    };
    let early = (!meta_last).then(|| meta(&mut b));
    let dt = b.block(b"DT", &[], &records[..30]);
    let dz1 = b.block(b"DZ", &[], &zipped(&records[30..100], None));
    let dz2 = b.block(b"DZ", &[], &zipped(&records[100..], Some(21)));
    let mut dl_data = vec![0, 0, 0, 0];
    dl_data.extend(3u32.to_le_bytes());
    for o in [0u64, 30, 100] {
        dl_data.extend(o.to_le_bytes());
    }
    let dl = b.block(b"DL", &[0, dt, dz1, dz2], &dl_data);
    let hl = b.block(b"HL", &[dl], &[0; 8]);
    let dg = early.unwrap_or_else(|| meta(&mut b));
    b.link(dg, 2, hl);
    b.link(hd, 0, dg);
    b.out
}

#[test]
fn dl_and_hl_lists_of_dt_and_dz_blocks_with_records_across_them() {
    let want: Vec<Line> = (0..10u64)
        .map(|i| f(i * 1000, 0x81 + i as u32, false, &[i as u8; 8]))
        .collect();
    assert_eq!(read(&sorted(false)).0, want);
    // Metadata after the data: spooled, then read in the same order.
    assert_eq!(read(&sorted(true)).0, want);
}

/// `bytes`, then the error of a cancel (Ctrl-C under `--follow`).
struct ThenCancelled<'a>(&'a [u8]);

impl io::Read for ThenCancelled<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.0.is_empty() {
            return Err(crate::cancel::cancelled());
        }
        self.0.read(buf)
    }
}

/// A cancel after the whole file, whose data comes before its metadata: the
/// spooled data is decoded as at the end of the file (before, nothing was),
/// then the cancel's error comes.
#[test]
fn a_cancel_after_data_before_its_metadata_loses_nothing() {
    let bytes = sorted(true);
    let mut r = Mf4Reader::new(ThenCancelled(&bytes)).expect("an MDF 4 file");
    let mut frames = 0;
    let err = loop {
        match r.next_record() {
            Ok(Some(Parsed::Frame(_))) => frames += 1,
            Ok(Some(Parsed::Malformed(m))) => panic!("{m}"),
            Ok(Some(_)) => {}
            Ok(None) => panic!("the cancel is not the end of the file"),
            Err(e) => break e,
        }
    };
    assert_eq!(frames, 10);
    assert!(crate::cancel::is_cancelled(&err), "{err}");
}

/// The temporary file of data waiting for its metadata is bounded: past
/// the bound, reading stops with an error that says the bound (a gzip
/// input of a few MB filled 1.18 GB of the temporary directory).
#[test]
fn the_spool_of_data_before_its_metadata_is_bounded() {
    let bytes = sorted(true);
    let read_with_limit = |limit: u64| {
        let mut r = Mf4Reader::new(&bytes[..]).expect("an MDF 4 file");
        r.spool_limit = limit;
        let mut frames = 0;
        loop {
            match r.next_record() {
                Ok(Some(Parsed::Frame(_))) => frames += 1,
                Ok(Some(_)) => {}
                Ok(None) => return Ok(frames),
                Err(e) => return Err(e.to_string()),
            }
        }
    };
    assert_eq!(read_with_limit(MAX_SPOOL), Ok(10));
    // The DT block's 30 bytes fit, the first DZ block does not.
    assert_eq!(
        read_with_limit(40),
        Err(
            "the MF4 data written before its metadata (kept in a temporary file until the \
             metadata comes) is over 40 bytes: not read further"
                .into()
        )
    );
}

#[test]
fn times_exact_and_the_local_time_flag_is_noted() {
    let mut file = unsorted(b"UnFinMF ", 0x25, false, true, &three());
    // HD time flags (byte 12 of its data, after 6 links): local time.
    file[64 + 24 + 48 + 12] = 1;
    let (lines, notes) = read(&file);
    assert_eq!(lines, three_frames());
    assert!(notes.iter().any(|n| n.contains("local time")), "{notes:?}");
}

#[test]
fn not_mdf_and_mdf_3_are_errors() {
    let e = |b: &[u8]| {
        Mf4Reader::new(b)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    assert!(e(b"LOGG").contains("not an MDF file"));
    assert!(e(b"MDF     3.30    ").contains("MDF version 3.30 is not read"));
    let file = unsorted(b"MDF     ", 0, false, false, &three());
    assert!(e(&file[..70]).contains("no MDF header block"));
    assert!(e(&file[..100]).contains("cut off"));
}

#[test]
fn a_group_of_zero_byte_records_is_reported_not_looped_on() {
    let mut b = B::new(b"MDF     ", 0);
    let hd = b.hd(2);
    let dg = b.dg(0);
    let cg = b.cg("Other", 0, 0, 0, 0);
    b.link(dg, 1, cg);
    b.link(hd, 0, dg);
    let dt = b.block(b"DT", &[], &[1, 2, 3]);
    b.link(dg, 2, dt);
    let (lines, _) = read(&b.out);
    assert_eq!(
        lines,
        vec![Line::M(
            "records of 0 bytes: the data block cannot be read".into()
        )]
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any damage to a valid file: reading ends, never panics, and every
    /// record read is a frame, a skipped record or a malformed one.
    #[test]
    fn damaged_files_never_panic(
        which in 0usize..3,
        flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..8),
        cut in any::<usize>(),
    ) {
        let mut file = match which {
            0 => unsorted(b"UnFinMF ", 0x25, true, true, &three()),
            1 => sorted(false),
            _ => sorted(true),
        };
        for (at, v) in flips {
            let n = file.len();
            file[at % n] ^= v;
        }
        file.truncate(64 + cut % file.len());
        if let Ok(mut r) = Mf4Reader::new(&file[..]) {
            let mut n = 0;
            while let Ok(Some(_)) = r.next_record() {
                n += 1;
                prop_assert!(n < 1_000_000);
            }
        }
        counts_add_up(&file, "a damaged file");
    }

    /// Block parsers take any bytes.
    #[test]
    fn block_parsers_take_any_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = block::identify(&bytes);
        if let Some(b) = Block::new(&bytes) {
            let _ = block::HeaderBlock::read(b);
            let _ = block::Dg::read(b);
            let _ = block::Cg::read(b);
            let _ = block::Cn::read(b);
            let _ = block::Conversion::read(b).map(|c| c.apply(3.0));
            let _ = block::dl_entries(b);
            let _ = block::text(b);
            let _ = block::Dz::read(b.data()).map(|d| d.inflate(b.data()));
        }
        for bits in [0u32, 1, 7, 29, 64, 65] {
            let _ = block::uint(&bytes, 3, 5, bits, false);
            let _ = block::uint(&bytes, 3, 5, bits, true);
        }
    }
}

#[test]
fn every_error_type_and_direction() {
    use crate::error_frame::{LOCATION_BYTE, PROTOCOL_BYTE};
    let of = |t, d| {
        let e = error_frame(t, d);
        (e.class, e.data[PROTOCOL_BYTE], e.data[LOCATION_BYTE])
    };
    assert_eq!(of(Some(1), Some(0)), (0x88, protocol::BIT, 0));
    assert_eq!(of(Some(2), None), (0x88, protocol::FORM, 0));
    assert_eq!(
        of(Some(3), Some(1)),
        (0x88, protocol::STUFF | protocol::TX, 0)
    );
    assert_eq!(of(Some(4), None), (0x88, 0, location::CRC_SEQUENCE));
    assert_eq!(
        of(Some(5), Some(1)),
        (0xA8, protocol::TX, location::ACK_SLOT)
    );
    assert_eq!(of(Some(0), Some(1)), (0, 0, 0));
    assert_eq!(of(None, None), (0, 0, 0));
    assert_eq!(of(Some(9), None), (0, 0, 0));
}
