//! Deterministic generator of large, realistic CAN traces (a CANopen machine:
//! SYNC, PDOs, heartbeats, SDO traffic, and EMCY raise/reset cycles at a
//! chosen rate), shared by the throughput benchmark (`benches/throughput.rs`
//! includes this file) and the memory test; and the random numbers of the
//! tests that need the same bytes every run (hostile input).
#![allow(dead_code)]

use std::io::{self, Write};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceFormat {
    CandumpLog,
    /// `candump -L -td`: each time the delta to the previous frame.
    CandumpDelta,
    Asc,
    /// pcapng as dumpcap writes a SocketCAN interface: one LINUX_SLL
    /// interface, microsecond times, each frame a 16-byte `can_frame`.
    Pcapng,
    /// BUSMASTER log as 2.0 writes it: HEX, system time, ids as `0x181`.
    Busmaster,
    /// IXXAT MiniMon V3 ASCII trace: its header, then quoted `;` rows.
    Ixxat,
    /// MDF 4 as a CANedge logger writes it: unfinalized, the DT block's
    /// length 24 and its records to the end; one unsorted group (1-byte
    /// record ids) of `CAN_DataFrame` records (u64 microseconds, u32 ID
    /// with the IDE bit, u8 DataLength, 8 data bytes).
    Mf4,
    /// The same records without ids and without the file around them:
    /// what [`write_mf4_dz`] packs into DZ blocks.
    Mf4Records,
}

/// xorshift64*: deterministic and fast; quality is irrelevant here.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }
    pub fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
    pub fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

const HEX: &[u8; 16] = b"0123456789ABCDEF";

/// The nodes of [`write_trace`]'s bus (1 to this), each heartbeating every
/// 100 ms. Until 2026-11-26 their heartbeats came at random (a tenth of
/// the other frames): once heartbeats were decoded, that made an
/// outage every few beats, over a million events per GiB that no real bus
/// sends, and the bench measured rendering them (docs/performance.md).
const BUS_NODES: u32 = 8;

/// Writes about `bytes` bytes of trace; `emcy_per_mille` of the frames are
/// EMCY (alternating raise and reset per node); nodes 1-8 heartbeat every
/// 100 ms. Returns (lines, emcy frames).
pub fn write_trace<W: Write>(
    out: &mut W,
    format: TraceFormat,
    bytes: u64,
    emcy_per_mille: u64,
    seed: u64,
) -> io::Result<(u64, u64)> {
    write_trace_with(out, format, bytes, emcy_per_mille, seed, BUS_NODES)
}

/// [`write_trace`] on a bus where nodes 1..=`heartbeat_nodes` send their
/// heartbeat (operational) every 100 ms, as a commissioned machine does
/// (the heartbeat benchmark: 32 of them).
pub fn write_heartbeat_trace<W: Write>(
    out: &mut W,
    format: TraceFormat,
    bytes: u64,
    emcy_per_mille: u64,
    seed: u64,
    heartbeat_nodes: u32,
) -> io::Result<(u64, u64)> {
    write_trace_with(out, format, bytes, emcy_per_mille, seed, heartbeat_nodes)
}

fn write_trace_with<W: Write>(
    out: &mut W,
    format: TraceFormat,
    bytes: u64,
    emcy_per_mille: u64,
    seed: u64,
    heartbeat_nodes: u32,
) -> io::Result<(u64, u64)> {
    // The next heartbeat of every node, staggered by a millisecond.
    let mut beats: Vec<(u64, u32)> = (1..=heartbeat_nodes)
        .map(|n| (u64::from(n) * 1000, n))
        .collect();
    let mut rng = Rng::new(seed);
    let mut written = 0u64;
    let mut lines = 0u64;
    let mut emcy = 0u64;
    let mut micros: u64 = 0;
    let mut previous: u64 = 0;
    let mut raised = [false; 128];
    let mut line = Vec::with_capacity(160);
    if format == TraceFormat::Asc {
        let header = b"date Tue Nov 14 22:13:20.000 2023\nbase hex  timestamps absolute\n\
internal events logged\n// version 9.0.0\nBegin Triggerblock Tue Nov 14 22:13:20.000 2023\n   0.000000 Start of measurement\n";
        out.write_all(header)?;
        written += header.len() as u64;
        lines += 6;
    }
    if format == TraceFormat::Busmaster {
        let header = b"***BUSMASTER Ver 2.0.0***\n***PROTOCOL CAN***\n\
***NOTE: PLEASE DO NOT EDIT THIS DOCUMENT***\n***[START LOGGING SESSION]***\n\
***START DATE AND TIME 14:11:2023 22:13:20:000***\n***HEX***\n***SYSTEM MODE***\n\
***<Time><Tx/Rx><Channel><CAN ID><Type><DLC><DataBytes>***\n";
        out.write_all(header)?;
        written += header.len() as u64;
        lines += 8;
    }
    if format == TraceFormat::Ixxat {
        let header = b"ASCII Trace IXXAT MiniMon V3  Version: 1.0.0.1271\nDate: 14.11.2023\n\
Start time: 22:13:20\nStop time: 23:59:59\nOverruns: 0\nBaudrate: 500 kbit/s\n\
\"Time\";\"Identifier (hex)\";\"Format\";\"Flags\";\"Data (hex)\"\n";
        out.write_all(header)?;
        written += header.len() as u64;
        lines += 7;
    }
    if format == TraceFormat::Mf4 {
        let (header, _) = mf4_header(true, 1);
        out.write_all(&header)?;
        written += header.len() as u64;
    }
    if format == TraceFormat::Pcapng {
        let header = pcapng_header();
        out.write_all(&header)?;
        written += header.len() as u64;
    }
    while written < bytes {
        micros += 100 + rng.below(400);
        let node = 1 + rng.below(8) as u8;
        let mut data = [0u8; 8];
        // A heartbeat that is due goes first (its own time, in order).
        let due = beats
            .iter_mut()
            .filter(|(at, _)| *at <= micros)
            .min_by_key(|(at, _)| *at);
        let (id, len) = if let Some((at, n)) = due {
            let id = 0x700 + *n;
            micros = micros.max(*at);
            *at += 100_000;
            (id, 1)
        } else if rng.below(1000) < emcy_per_mille {
            emcy += 1;
            let i = usize::from(node);
            if raised[i] {
                raised[i] = false;
                (0x080 + u32::from(node), 8) // reset: all zeros
            } else {
                raised[i] = true;
                let codes: [(u16, u8); 4] = [
                    (0x4310, 0x09),
                    (0x2310, 0x03),
                    (0x3210, 0x05),
                    (0x8611, 0x21),
                ];
                let (code, reg) = codes[rng.below(4) as usize];
                data[..2].copy_from_slice(&code.to_le_bytes());
                data[2] = reg;
                data[3] = rng.below(5) as u8 + 1;
                (0x080 + u32::from(node), 8)
            }
        } else {
            match rng.below(10) {
                0 => (0x080, 0),
                2 => (0x580 + u32::from(node), 8),
                3 => (0x600 + u32::from(node), 8),
                _ => {
                    let base = [0x180u32, 0x280, 0x380, 0x480][rng.below(4) as usize];
                    (base + u32::from(node), 1 + rng.below(8) as usize)
                }
            }
        };
        if id >= 0x700 {
            data[0] = 0x05;
        } else if !(0x081..=0x0FF).contains(&id) {
            for b in data.iter_mut().take(len) {
                *b = rng.next() as u8;
            }
        }
        if (0x581..=0x67F).contains(&id) {
            // SDO as a master reading and writing application objects:
            // real command bytes (random ones made every eighth frame an
            // abort) and indexes in the profile area, none the decoder
            // follows.
            let commands: [u8; 4] = if id >= 0x600 {
                [0x40, 0x40, 0x2B, 0x23]
            } else {
                [0x43, 0x4B, 0x4F, 0x60]
            };
            data[0] = commands[rng.below(4) as usize];
            let index = 0x2000 + rng.below(0x4000) as u16;
            data[1..3].copy_from_slice(&index.to_le_bytes());
        }
        line.clear();
        match format {
            TraceFormat::CandumpLog => candump_line(&mut line, micros, id, &data[..len]),
            TraceFormat::CandumpDelta => {
                let _ = write!(
                    line,
                    "({:03}.{:06})",
                    (micros - previous) / 1_000_000,
                    (micros - previous) % 1_000_000
                );
                candump_frame(&mut line, id, &data[..len]);
            }
            TraceFormat::Asc => asc_line(&mut line, micros, id, &data[..len]),
            TraceFormat::Pcapng => pcapng_packet(&mut line, micros, id, &data[..len]),
            TraceFormat::Busmaster => busmaster_line(&mut line, micros, id, &data[..len]),
            TraceFormat::Ixxat => ixxat_line(&mut line, micros, id, &data[..len]),
            TraceFormat::Mf4 => {
                line.push(1);
                mf4_record(&mut line, micros, id, &data[..len]);
            }
            TraceFormat::Mf4Records => mf4_record(&mut line, micros, id, &data[..len]),
        }
        out.write_all(&line)?;
        written += line.len() as u64;
        previous = micros;
        lines += 1;
    }
    if format == TraceFormat::Asc {
        out.write_all(b"End TriggerBlock\n")?;
        lines += 1;
    }
    Ok((lines, emcy))
}

fn push_hex(line: &mut Vec<u8>, b: u8) {
    line.push(HEX[usize::from(b >> 4)]);
    line.push(HEX[usize::from(b & 15)]);
}

/// `(1700000000.123456) can0 181#1122334455667788`
fn candump_line(line: &mut Vec<u8>, micros: u64, id: u32, data: &[u8]) {
    let secs = 1_700_000_000 + micros / 1_000_000;
    let _ = write!(line, "({secs}.{:06})", micros % 1_000_000);
    candump_frame(line, id, data);
}

/// ` can0 181#1122...` and the newline, after a candump time.
fn candump_frame(line: &mut Vec<u8>, id: u32, data: &[u8]) {
    line.extend_from_slice(b" can0 ");
    line.push(HEX[(id >> 8) as usize & 15]);
    line.push(HEX[(id >> 4) as usize & 15]);
    line.push(HEX[id as usize & 15]);
    line.push(b'#');
    for &b in data {
        push_hex(line, b);
    }
    line.push(b'\n');
}

/// `   0.123456 1  181             Rx   d 8 11 22 ...  Length = ... ID = 385`
fn asc_line(line: &mut Vec<u8>, micros: u64, id: u32, data: &[u8]) {
    let _ = write!(
        line,
        "{:>4}.{:06} 1  {:<15X} Rx   d {}",
        micros / 1_000_000,
        micros % 1_000_000,
        id,
        data.len()
    );
    for &b in data {
        line.push(b' ');
        push_hex(line, b);
    }
    let _ = writeln!(line, "  Length = 228000 BitCount = 118 ID = {id}");
}

/// `"00:00:01.25";"181";"Std";"";"11 22 33 44 55 66 77 88 "`: hundredths
/// since the start, as MiniMon writes them.
fn ixxat_line(line: &mut Vec<u8>, micros: u64, id: u32, data: &[u8]) {
    let secs = micros / 1_000_000;
    let _ = write!(
        line,
        "\"{:02}:{:02}:{:02}.{:02}\";\"{id:X}\";\"Std\";\"\";\"",
        secs / 3600,
        secs / 60 % 60,
        secs % 60,
        micros % 1_000_000 / 10_000
    );
    for &b in data {
        push_hex(line, b);
        line.push(b' ');
    }
    line.extend_from_slice(b"\"\n");
}

/// `22:13:20:1234 Rx 1 0x181 s 8 11 22 33 44 55 66 77 88 ` (time of day
/// from 22:13:20, past midnight after 2 hours: those times the reader puts
/// on the next day).
fn busmaster_line(line: &mut Vec<u8>, micros: u64, id: u32, data: &[u8]) {
    let secs = (80_000 + micros / 1_000_000) % 86_400;
    let _ = write!(
        line,
        "{:02}:{:02}:{:02}:{:04} Rx 1 0x",
        secs / 3600,
        secs / 60 % 60,
        secs % 60,
        micros % 1_000_000 / 100
    );
    line.push(HEX[(id >> 8) as usize & 15]);
    line.push(HEX[(id >> 4) as usize & 15]);
    line.push(HEX[id as usize & 15]);
    let _ = write!(line, " s {} ", data.len());
    for &b in data {
        push_hex(line, b);
        line.push(b' ');
    }
    line.push(b'\n');
}

/// A pcapng section header and one LINUX_SLL interface named `can0`
/// (microseconds: no if_tsresol), little-endian.
fn pcapng_header() -> Vec<u8> {
    pcapng_head(113, b"can0")
}

/// A pcapng section header and one interface of `linktype` named `name`
/// (4 bytes; microseconds), little-endian.
fn pcapng_head(linktype: u16, name: &[u8; 4]) -> Vec<u8> {
    let mut h = Vec::new();
    let mut block = |kind: u32, body: &[u8]| {
        let len = 12 + body.len() as u32;
        h.extend(kind.to_le_bytes());
        h.extend(len.to_le_bytes());
        h.extend(body);
        h.extend(len.to_le_bytes());
    };
    let mut shb = 0x1A2B_3C4Du32.to_le_bytes().to_vec();
    shb.extend(1u16.to_le_bytes());
    shb.extend(0u16.to_le_bytes());
    shb.extend((-1i64).to_le_bytes());
    block(0x0A0D_0D0A, &shb);
    let mut idb = linktype.to_le_bytes().to_vec();
    idb.extend([0, 0]);
    idb.extend(262_144u32.to_le_bytes());
    idb.extend(2u16.to_le_bytes()); // if_name
    idb.extend(4u16.to_le_bytes());
    idb.extend(name);
    idb.extend([0; 4]); // opt_endofopt
    block(1, &idb);
    h
}

/// One enhanced packet block: a LINUX_SLL header and a 16-byte `can_frame`.
fn pcapng_packet(out: &mut Vec<u8>, micros: u64, id: u32, data: &[u8]) {
    let units = 1_700_000_000_000_000 + micros;
    out.extend(6u32.to_le_bytes());
    out.extend(64u32.to_le_bytes());
    out.extend(0u32.to_le_bytes());
    out.extend(((units >> 32) as u32).to_le_bytes());
    out.extend((units as u32).to_le_bytes());
    out.extend(32u32.to_le_bytes());
    out.extend(32u32.to_le_bytes());
    out.extend([0, 0, 0x01, 0x18]); // packet type, ARPHRD_CAN
    out.extend([0; 10]);
    out.extend(0x000Cu16.to_be_bytes());
    out.extend(id.to_le_bytes());
    out.extend([data.len() as u8, 0, 0, 0]);
    let mut bytes = [0u8; 8];
    bytes[..data.len()].copy_from_slice(data);
    out.extend(bytes);
    out.extend(64u32.to_le_bytes());
}

/// An MDF 4 record of the `CAN_DataFrame` group of [`mf4_header`].
fn mf4_record(out: &mut Vec<u8>, micros: u64, id: u32, data: &[u8]) {
    out.extend(micros.to_le_bytes());
    out.extend(id.to_le_bytes());
    out.push(data.len() as u8);
    let mut bytes = [0u8; 8];
    bytes[..data.len()].copy_from_slice(data);
    out.extend(bytes);
}

/// Bytes of an [`mf4_record`].
pub const MF4_RECORD: usize = 21;

/// The blocks of an MDF 4 file up to its data: identification, header
/// (start 1700000000 s), one data group (record ids of `rec_id_size`
/// bytes) with one `CAN_DataFrame` group, and, when `unfinished`, an
/// `UnFinMF` DT block of length 24 whose records follow. Returns the bytes
/// and the data group's offset (its data link is at offset + 40).
pub fn mf4_header(unfinished: bool, rec_id_size: u8) -> (Vec<u8>, u64) {
    let mut out = if unfinished { b"UnFinMF " } else { b"MDF     " }.to_vec();
    out.extend(b"4.11    GEN     ");
    out.resize(60, 0);
    out.extend(if unfinished { 0x25u16 } else { 0 }.to_le_bytes());
    out.extend([0, 0]);
    let block = |out: &mut Vec<u8>, id: &[u8; 2], links: &[u64], data: &[u8]| -> u64 {
        while !out.len().is_multiple_of(8) {
            out.push(0);
        }
        let at = out.len() as u64;
        out.extend(b"##");
        out.extend(id);
        out.extend([0; 4]);
        out.extend(((24 + 8 * links.len() + data.len()) as u64).to_le_bytes());
        out.extend((links.len() as u64).to_le_bytes());
        for l in links {
            out.extend(l.to_le_bytes());
        }
        out.extend(data);
        at
    };
    let link = |out: &mut Vec<u8>, at: u64, i: usize, v: u64| {
        let p = at as usize + 24 + 8 * i;
        out[p..p + 8].copy_from_slice(&v.to_le_bytes());
    };
    let mut hd_data = (1_700_000_000u64 * 1_000_000_000).to_le_bytes().to_vec();
    hd_data.extend([0, 0, 0, 0, 2, 0, 0, 0]);
    hd_data.extend([0; 16]);
    let hd = block(&mut out, b"HD", &[0; 6], &hd_data);
    let mut cc = vec![1, 0, 0, 0, 0, 0, 2, 0];
    cc.extend([0; 16]);
    cc.extend(0f64.to_le_bytes());
    cc.extend(1e-6f64.to_le_bytes());
    let us = block(&mut out, b"CC", &[0; 4], &cc);
    let cn = |out: &mut Vec<u8>, name: &str, kind: u8, dtype: u8, byte: u32, bits: u32, cc: u64| {
        let mut t = name.as_bytes().to_vec();
        t.push(0);
        let name = block(out, b"TX", &[], &t);
        let mut d = vec![kind, u8::from(kind == 2), dtype, 0];
        d.extend(byte.to_le_bytes());
        d.extend(bits.to_le_bytes());
        d.extend([0; 68]);
        block(out, b"CN", &[0, 0, name, 0, cc, 0, 0, 0], &d)
    };
    let t = cn(&mut out, "Timestamp", 2, 0, 0, 64, us);
    let id = cn(&mut out, "CAN_DataFrame.ID", 0, 0, 8, 32, 0);
    let len = cn(&mut out, "CAN_DataFrame.DataLength", 0, 0, 12, 8, 0);
    let data = cn(&mut out, "CAN_DataFrame.DataBytes", 0, 10, 13, 64, 0);
    link(&mut out, t, 0, id);
    link(&mut out, id, 0, len);
    link(&mut out, len, 0, data);
    let mut name = b"CAN_DataFrame".to_vec();
    name.push(0);
    let name = block(&mut out, b"TX", &[], &name);
    let mut cg = 1u64.to_le_bytes().to_vec();
    cg.extend(0u64.to_le_bytes());
    cg.extend(6u16.to_le_bytes());
    cg.extend([0; 6]);
    cg.extend((MF4_RECORD as u32).to_le_bytes());
    cg.extend(0u32.to_le_bytes());
    let cg = block(&mut out, b"CG", &[0, t, name, 0, 0, 0], &cg);
    let mut dg_data = vec![rec_id_size];
    dg_data.extend([0; 7]);
    let dg = block(&mut out, b"DG", &[0, cg, 0, 0], &dg_data);
    link(&mut out, hd, 0, dg);
    if unfinished {
        let dt = block(&mut out, b"DT", &[], &[]);
        link(&mut out, dg, 2, dt);
    }
    (out, dg)
}

/// Bytes of records per DZ block (python-can's writer, through asammdf,
/// splits at 4 MiB), a whole number of records.
const DZ_RECORDS: usize = 4 * 1024 * 1024 / MF4_RECORD * MF4_RECORD;

/// An MDF 4 file of about `bytes` bytes of records as python-can's writer
/// (through asammdf) saves it with its default compression: one sorted
/// data group whose records are in DZ blocks (transposed deflate, 4 MiB
/// each) listed by a DL block written after them. Returns (records, EMCY
/// frames, bytes of records).
pub fn write_mf4_dz<W: Write + io::Seek>(
    out: &mut W,
    bytes: u64,
    emcy_per_mille: u64,
    seed: u64,
) -> io::Result<(u64, u64, u64)> {
    struct Packer<'w, W: Write> {
        out: &'w mut W,
        at: u64,
        block: Vec<u8>,
        blocks: Vec<u64>,
        raw: u64,
    }
    impl<W: Write> Packer<'_, W> {
        fn flush_block(&mut self) -> io::Result<()> {
            if self.block.is_empty() {
                return Ok(());
            }
            let rows = self.block.len() / MF4_RECORD;
            let mut t = vec![0u8; self.block.len()];
            for (i, b) in self.block.iter().enumerate() {
                let (row, col) = (i / MF4_RECORD, i % MF4_RECORD);
                t[col * rows + row] = *b;
            }
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(&t)?;
            let z = z.finish()?;
            let mut head = b"##DZ\0\0\0\0".to_vec();
            head.extend(((24 + 24 + z.len()) as u64).to_le_bytes());
            head.extend(0u64.to_le_bytes());
            head.extend(b"DT\x01\0");
            head.extend((MF4_RECORD as u32).to_le_bytes());
            head.extend((self.block.len() as u64).to_le_bytes());
            head.extend((z.len() as u64).to_le_bytes());
            self.blocks.push(self.at);
            self.out.write_all(&head)?;
            self.out.write_all(&z)?;
            let n = head.len() + z.len();
            let pad = (8 - n % 8) % 8;
            self.out.write_all(&[0; 8][..pad])?;
            self.at += (n + pad) as u64;
            self.block.clear();
            Ok(())
        }
    }
    impl<W: Write> Write for Packer<'_, W> {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            self.block.extend_from_slice(buf);
            self.raw += buf.len() as u64;
            if self.block.len() >= DZ_RECORDS {
                let rest = self.block.split_off(DZ_RECORDS);
                self.flush_block()?;
                self.block = rest;
            }
            Ok(buf.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }
    let (header, dg) = mf4_header(false, 0);
    out.write_all(&header)?;
    let mut p = Packer {
        at: header.len() as u64,
        out,
        block: Vec::with_capacity(DZ_RECORDS + 64),
        blocks: Vec::new(),
        raw: 0,
    };
    let (records, emcy) =
        write_trace(&mut p, TraceFormat::Mf4Records, bytes, emcy_per_mille, seed)?;
    p.flush_block()?;
    let (at, blocks, raw) = (p.at, p.blocks, p.raw);
    let mut dl = b"##DL\0\0\0\0".to_vec();
    let n = blocks.len() as u64;
    dl.extend((24 + 8 * (n + 1) + 8 + 8 * n).to_le_bytes());
    dl.extend((n + 1).to_le_bytes());
    dl.extend(0u64.to_le_bytes());
    for b in &blocks {
        dl.extend(b.to_le_bytes());
    }
    dl.extend([0, 0, 0, 0]);
    dl.extend((n as u32).to_le_bytes());
    for i in 0..n {
        dl.extend((i * DZ_RECORDS as u64).to_le_bytes());
    }
    out.write_all(&dl)?;
    out.seek(io::SeekFrom::Start(dg + 24 + 16))?;
    out.write_all(&at.to_le_bytes())?;
    out.seek(io::SeekFrom::End(0))?;
    Ok((records, emcy, raw))
}

/// Slaves of [`write_ethercat`]'s segment (station addresses 1001..).
pub const ETHERCAT_SLAVES: u16 = 32;

/// Writes about `bytes` bytes of an EtherCAT capture as a master's port
/// sees it: pcapng, one Ethernet interface `eth0`, a frame every
/// millisecond (1 kHz) with the process data of [`ETHERCAT_SLAVES`] slaves
/// (one LRW of 8 bytes each) and a poll of one slave's mailbox, in turn;
/// in `emcy_per_mille` of the cycles the polled slave answers with a CoE
/// emergency (raise and reset in turn per slave), else the poll is empty.
/// Returns (packets, emergencies).
pub fn write_ethercat<W: Write>(
    out: &mut W,
    bytes: u64,
    emcy_per_mille: u64,
    seed: u64,
) -> io::Result<(u64, u64)> {
    let mut rng = Rng::new(seed);
    let h = pcapng_head(1, b"eth0"); // LINKTYPE_ETHERNET
    out.write_all(&h)?;
    let mut written = h.len() as u64;
    let (mut packets, mut emcy) = (0u64, 0u64);
    let mut raised = [false; ETHERCAT_SLAVES as usize];
    let mut counter = [1u8; ETHERCAT_SLAVES as usize];
    let mut frame = Vec::with_capacity(512);
    let mut packet = Vec::with_capacity(512);
    let mailbox = 48usize;
    while written < bytes {
        let cycle = packets;
        let slave = (cycle % u64::from(ETHERCAT_SLAVES)) as usize;
        // The EtherCAT frame: LRW (more follows), then FPRD of the mailbox.
        frame.clear();
        frame.extend([12u8, 0, 0, 0, 0, 0]);
        frame.extend((256u16 | 0x8000).to_le_bytes());
        frame.extend([0, 0]);
        frame.extend(rng.bytes(256));
        frame.extend((3 * ETHERCAT_SLAVES).to_le_bytes());
        frame.extend([4u8, 0]);
        frame.extend((1001 + slave as u16).to_le_bytes());
        frame.extend(0x1080u16.to_le_bytes());
        frame.extend((mailbox as u16).to_le_bytes());
        frame.extend([0, 0]);
        let mut mbx = vec![0u8; mailbox];
        let answered = rng.below(1000) < emcy_per_mille;
        if answered {
            emcy += 1;
            let emcy_bytes: [u8; 8] = if raised[slave] {
                [0, 0, 0, 0x1E, 0, 0, 0, 0]
            } else {
                [0x10, 0x43, 0x01, 0x29, 0, 0, 0, 0]
            };
            raised[slave] = !raised[slave];
            let c = counter[slave];
            counter[slave] = c % 7 + 1;
            mbx[..6].copy_from_slice(&[10, 0, 0, 0, 0, 3 | c << 4]);
            mbx[6..8].copy_from_slice(&0x1000u16.to_le_bytes());
            mbx[8..16].copy_from_slice(&emcy_bytes);
        }
        frame.extend(&mbx);
        frame.extend(u16::from(answered).to_le_bytes());
        packet.clear();
        packet.extend([0xFF; 6]);
        packet.extend([2, 0, 0, 0, 0, 1]);
        packet.extend(0x88A4u16.to_be_bytes());
        packet.extend((frame.len() as u16 | 0x1000).to_le_bytes());
        packet.extend(&frame);
        let units = 1_700_000_000_000_000 + cycle * 1000;
        let padded = packet.len().next_multiple_of(4);
        let len = 32 + padded as u32;
        let mut epb = Vec::with_capacity(len as usize);
        epb.extend(6u32.to_le_bytes());
        epb.extend(len.to_le_bytes());
        epb.extend(0u32.to_le_bytes());
        epb.extend(((units >> 32) as u32).to_le_bytes());
        epb.extend((units as u32).to_le_bytes());
        epb.extend((packet.len() as u32).to_le_bytes());
        epb.extend((packet.len() as u32).to_le_bytes());
        epb.extend(&packet);
        epb.resize(epb.len() + padded - packet.len(), 0);
        epb.extend(len.to_le_bytes());
        out.write_all(&epb)?;
        written += epb.len() as u64;
        packets += 1;
    }
    Ok((packets, emcy))
}

/// A candump log of `drives` CiA 402 drives (nodes 1..=drives) each sending
/// TPDO1 (0x180 + node: statusword, 32-bit position) every millisecond, as
/// a motion controller's cyclic bus does (the drives benchmark). About
/// `emcy_per_mille` of the frames are EMCYs, each raise with the drive's
/// statusword in fault until the reset 20 ms later; the statusword's
/// bits 10 and 12 (target reached, set-point acknowledge) toggle as a
/// moving drive's do. Decoded with `--assume-cia402-pdo`; without it the
/// PDOs are only counted (the EMCY-only path). Returns (lines, emcy frames).
pub fn write_drive_trace<W: Write>(
    out: &mut W,
    bytes: u64,
    emcy_per_mille: u64,
    seed: u64,
    drives: u32,
) -> io::Result<(u64, u64)> {
    let mut rng = Rng::new(seed);
    let mut written = 0u64;
    let mut lines = 0u64;
    let mut emcy = 0u64;
    let mut line = Vec::with_capacity(64);
    // Per drive: fault until this cycle (0: none), position.
    let mut fault_until = vec![0u64; drives as usize + 1];
    let mut position = vec![0u32; drives as usize + 1];
    let mut cycle: u64 = 0;
    let frame = |line: &mut Vec<u8>, micros: u64, id: u32, data: &[u8]| {
        line.clear();
        line.extend_from_slice(
            format!(
                "({}.{:06}) can0 {:03X}#",
                1_700_000_000 + micros / 1_000_000,
                micros % 1_000_000,
                id
            )
            .as_bytes(),
        );
        for b in data {
            line.push(HEX[usize::from(b >> 4)]);
            line.push(HEX[usize::from(b & 15)]);
        }
        line.push(b'\n');
    };
    while written < bytes {
        cycle += 1;
        for node in 1..=drives {
            let micros = cycle * 1000 + u64::from(node) * 20;
            let n = node as usize;
            let mut extra = None;
            if fault_until[n] == cycle {
                fault_until[n] = 0;
                extra = Some([0u8; 8]);
            } else if fault_until[n] == 0 && rng.below(1000) < emcy_per_mille {
                fault_until[n] = cycle + 20;
                extra = Some([0x10, 0x43, 0x09, 0, 0, 0, 0, 0]);
            }
            let statusword: u16 = if fault_until[n] != 0 {
                0x0238
            } else {
                // Moving: target reached and set-point acknowledge come and go.
                0x0237 | if cycle % 50 < 25 { 0x0400 } else { 0x1000 }
            };
            position[n] = position[n].wrapping_add(100 + rng.below(8) as u32);
            let sw = statusword.to_le_bytes();
            let p = position[n].to_le_bytes();
            let data = [sw[0], sw[1], p[0], p[1], p[2], p[3]];
            frame(&mut line, micros, 0x180 + node, &data);
            out.write_all(&line)?;
            written += line.len() as u64;
            lines += 1;
            if let Some(e) = extra {
                frame(&mut line, micros + 5, 0x80 + node, &e);
                out.write_all(&line)?;
                written += line.len() as u64;
                lines += 1;
                emcy += 1;
            }
        }
    }
    Ok((lines, emcy))
}

/// The shapes of real machine buses the throughput bench measures (all
/// candump logs, 1 kHz SYNC, RPDO1 and TPDO1 of every CiA 402 drive,
/// heartbeats every 100 ms with 2 ms of jitter).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BusShape {
    /// 8 drives; a fault every 40 s or so (EMCY, statusword in fault, the
    /// master's fault reset and re-enable); one SDO read-out of 1000
    /// objects of node 1 (its PDO mapping among them) early on.
    Commissioning,
    /// 4 drives, flashed one after another by a 2 MB segmented SDO
    /// download of 0x1F50.
    FirmwareSegmented,
    /// The same by SDO block download, 127 segments a block.
    FirmwareBlock,
    /// 4 drives, 12 I/O nodes sending event PDOs, an HMI polling objects
    /// by SDO 20 times a second, one I/O node silent for 1 s a minute.
    Noisy,
}

/// The bytes of one firmware image the firmware shapes download.
const FIRMWARE_BYTES: u64 = 2 * 1024 * 1024;

/// CRC-16 of CiA 301's block transfers (CCITT polynomial 0x1021, start 0),
/// one byte at a time.
fn crc16_step(mut crc: u16, byte: u8) -> u16 {
    crc ^= u16::from(byte) << 8;
    for _ in 0..8 {
        crc = if crc & 0x8000 != 0 {
            crc << 1 ^ 0x1021
        } else {
            crc << 1
        };
    }
    crc
}

/// A firmware download in progress, one SDO frame at a time.
struct Flash {
    node: u32,
    block: bool,
    sent: u64,
    toggle: u8,
    /// Block transfers: the segment's number in its sub-block (1-127).
    seq: u8,
    crc: u16,
    /// The server's answer to the frame just sent, owed next.
    answer: Option<[u8; 8]>,
    step: FlashStep,
}

#[derive(PartialEq)]
enum FlashStep {
    Initiate,
    Data,
    End,
    Done,
}

impl Flash {
    fn new(node: u32, block: bool) -> Self {
        Flash {
            node,
            block,
            sent: 0,
            toggle: 0,
            seq: 0,
            crc: 0,
            answer: None,
            step: FlashStep::Initiate,
        }
    }

    /// The next frame of the transfer, client's or server's.
    fn next(&mut self, rng: &mut Rng) -> Option<(u32, [u8; 8], usize)> {
        let (client, server) = (0x600 + self.node, 0x580 + self.node);
        if let Some(answer) = self.answer.take() {
            return Some((server, answer, 8));
        }
        let size = (FIRMWARE_BYTES as u32).to_le_bytes();
        let mut d = [0u8; 8];
        match self.step {
            FlashStep::Initiate => {
                d = [
                    if self.block { 0xC6 } else { 0x21 },
                    0x50,
                    0x1F,
                    0x01,
                    size[0],
                    size[1],
                    size[2],
                    size[3],
                ];
                self.answer = Some(if self.block {
                    [0xA4, 0x50, 0x1F, 0x01, 127, 0, 0, 0]
                } else {
                    [0x60, 0x50, 0x1F, 0x01, 0, 0, 0, 0]
                });
                self.step = FlashStep::Data;
            }
            FlashStep::Data => {
                let n = (FIRMWARE_BYTES - self.sent).min(7) as usize;
                for b in d[1..=n].iter_mut() {
                    *b = rng.next() as u8;
                    self.crc = crc16_step(self.crc, *b);
                }
                self.sent += n as u64;
                let last = self.sent == FIRMWARE_BYTES;
                if self.block {
                    self.seq += 1;
                    d[0] = self.seq | if last { 0x80 } else { 0 };
                    if last || self.seq == 127 {
                        self.answer = Some([0xA2, self.seq, 127, 0, 0, 0, 0, 0]);
                        self.seq = 0;
                    }
                    if last {
                        // Unused bytes of the last segment, for the end frame.
                        self.toggle = (7 - n) as u8;
                        self.step = FlashStep::End;
                    }
                } else {
                    d[0] = self.toggle << 4 | ((7 - n) as u8) << 1 | u8::from(last);
                    self.answer = Some([0x20 | self.toggle << 4, 0, 0, 0, 0, 0, 0, 0]);
                    self.toggle ^= 1;
                    if last {
                        self.step = FlashStep::Done;
                    }
                }
            }
            FlashStep::End => {
                let crc = self.crc.to_le_bytes();
                d = [0xC1 | self.toggle << 2, crc[0], crc[1], 0, 0, 0, 0, 0];
                self.answer = Some([0xA1, 0, 0, 0, 0, 0, 0, 0]);
                self.step = FlashStep::Done;
            }
            FlashStep::Done => return None,
        }
        Some((client, d, 8))
    }
}

/// Writes about `bytes` bytes of a candump log shaped as `shape`. Returns
/// the lines written.
pub fn write_bus_trace<W: Write>(
    out: &mut W,
    shape: BusShape,
    bytes: u64,
    seed: u64,
) -> io::Result<u64> {
    let mut rng = Rng::new(seed);
    let drives: u32 = if shape == BusShape::Commissioning {
        8
    } else {
        4
    };
    // I/O nodes 0x20-0x2B (noisy only).
    let io_nodes: Vec<u32> = if shape == BusShape::Noisy {
        (0x20..0x2C).collect()
    } else {
        Vec::new()
    };
    let mut next_beat: Vec<(u32, u64)> = (1..=drives)
        .chain(io_nodes.iter().copied())
        .map(|n| (n, u64::from(n) * 1_000))
        .collect();
    let mut io_next: Vec<u64> = io_nodes.iter().map(|_| rng.below(50_000)).collect();
    let mut io_value: Vec<u8> = io_nodes.iter().map(|_| 0).collect();
    let mut position = vec![0u32; drives as usize + 1];
    let mut statusword = vec![0u16; drives as usize + 1];
    // Every node, as the master reads their device types at the start.
    let all_nodes: Vec<u32> = (1..=drives).chain(io_nodes.iter().copied()).collect();
    // Per drive: the cycle its fault began (0: none).
    let mut fault_at = vec![0u64; drives as usize + 1];
    let mut next_fault = 40_000 + rng.below(5_000);
    let mut readout = 0u32;
    let mut flash: Option<Flash> = None;
    let mut flashed = 0u32;
    let mut events: Vec<(u64, u32, [u8; 8], usize)> = Vec::new();
    let mut line = Vec::with_capacity(64);
    let (mut written, mut lines) = (0u64, 0u64);
    let mut cycle = 0u64;
    while written < bytes {
        cycle += 1;
        let t0 = cycle * 1_000;
        events.clear();
        events.push((t0, 0x080, [0; 8], 0));
        if shape == BusShape::Commissioning && cycle == next_fault {
            let node = 1 + rng.below(u64::from(drives)) as usize;
            fault_at[node] = cycle;
            next_fault = cycle + 38_000 + rng.below(4_000);
        }
        for node in 1..=drives {
            let n = node as usize;
            // The master's controlword: enable operation, a fault reset
            // 30 ms into a fault, then shutdown and enable again.
            let since = if fault_at[n] == 0 {
                u64::MAX
            } else {
                cycle - fault_at[n]
            };
            let (control, status): (u16, u16) = match since {
                0..30 => (0x000F, 0x0218),
                30..32 => (0x0080, 0x0218),
                32..40 => (0x0006, 0x0240),
                40..48 => (0x0006, 0x0221),
                48..56 => (0x0007, 0x0233),
                _ => (
                    0x000F,
                    0x0237 | if cycle % 50 < 25 { 0x0400 } else { 0x1000 },
                ),
            };
            if since == 56 {
                fault_at[n] = 0;
            }
            position[n] = position[n].wrapping_add(100 + rng.below(8) as u32);
            statusword[n] = status;
            let p = position[n].to_le_bytes();
            let (c, s) = (control.to_le_bytes(), status.to_le_bytes());
            let at = t0 + 30 + u64::from(node) * 40;
            events.push((
                at,
                0x200 + node,
                [c[0], c[1], p[0], p[1], p[2], p[3], 0, 0],
                6,
            ));
            events.push((
                at + 20,
                0x180 + node,
                [s[0], s[1], p[0], p[1], p[2], p[3], 0, 0],
                6,
            ));
            if since == 0 {
                events.push((at + 25, 0x080 + node, [0x10, 0x43, 0x09, 0, 0, 0, 0, 0], 8));
            } else if since == 32 {
                events.push((at + 25, 0x080 + node, [0; 8], 8));
            }
        }
        // Heartbeats, 100 ms apart with up to 2 ms of jitter; the noisy
        // bus's first I/O node is silent for a second every minute.
        for (node, at) in next_beat.iter_mut() {
            if *at < t0 + 1_000 {
                let silent =
                    shape == BusShape::Noisy && *node == 0x20 && (*at / 1_000) % 60_000 >= 59_000;
                if !silent {
                    events.push((*at, 0x700 + *node, [0x05, 0, 0, 0, 0, 0, 0, 0], 1));
                }
                *at += 98_000 + rng.below(4_001);
            }
        }
        // The master reads every node's device type at the start (a
        // drive says CiA 402, an I/O node CiA 401), one every 2 ms.
        if let Some(&node) = all_nodes.get((cycle as usize).wrapping_sub(10) / 2)
            && cycle >= 10
            && cycle.is_multiple_of(2)
        {
            let device_type: u32 = if node <= drives {
                0x0002_0192
            } else {
                0x000F_0191
            };
            let v = device_type.to_le_bytes();
            events.push((t0 + 700, 0x600 + node, [0x40, 0x00, 0x10, 0, 0, 0, 0, 0], 8));
            events.push((
                t0 + 800,
                0x580 + node,
                [0x43, 0x00, 0x10, 0, v[0], v[1], v[2], v[3]],
                8,
            ));
        }
        match shape {
            BusShape::Commissioning => {
                // Node 1's read-out, an object every 2 ms from 5 s on.
                if (5_000..7_000).contains(&cycle) && cycle.is_multiple_of(2) && readout < 1000 {
                    let (index, sub) = match readout {
                        0 => (0x1000u16, 0u8),
                        1..=4 => (0x1018, readout as u8),
                        5..=7 => (0x1A00, readout as u8 - 5),
                        8..=10 => (0x1800, readout as u8 - 7),
                        r => (0x2000 + (r / 16) as u16, (r % 16) as u8),
                    };
                    let value: u32 = match (index, sub) {
                        (0x1000, _) => 0x0002_0192,
                        (0x1A00, 0) => 2,
                        (0x1A00, 1) => 0x6041_0010,
                        (0x1A00, 2) => 0x6064_0020,
                        (0x1800, 1) => 0x181,
                        (0x1800, 2) => 1,
                        _ => rng.next() as u32,
                    };
                    let [lo, hi] = index.to_le_bytes();
                    let v = value.to_le_bytes();
                    events.push((t0 + 700, 0x601, [0x40, lo, hi, sub, 0, 0, 0, 0], 8));
                    events.push((
                        t0 + 800,
                        0x581,
                        [0x43, lo, hi, sub, v[0], v[1], v[2], v[3]],
                        8,
                    ));
                    readout += 1;
                }
            }
            BusShape::FirmwareSegmented | BusShape::FirmwareBlock => {
                // Six SDO frames a cycle after the process data, once the
                // device types are read (one transfer at a time on a
                // node's SDO channel).
                if flash.is_none() && cycle >= 100 {
                    flash = Some(Flash::new(
                        1 + flashed % drives,
                        shape == BusShape::FirmwareBlock,
                    ));
                    flashed += 1;
                }
                for k in 0..6 {
                    match flash.as_mut().and_then(|f| f.next(&mut rng)) {
                        Some((id, data, len)) => {
                            events.push((t0 + 400 + k * 100, id, data, len));
                        }
                        None => {
                            flash = None;
                            break;
                        }
                    }
                }
            }
            BusShape::Noisy => {
                for (k, &node) in io_nodes.iter().enumerate() {
                    let silent = node == 0x20 && (cycle % 60_000) >= 59_000;
                    if io_next[k] <= cycle && !silent {
                        io_value[k] = io_value[k].wrapping_add(1 + rng.below(3) as u8);
                        let v = io_value[k];
                        let at = t0 + 400 + k as u64 * 30;
                        events.push((at, 0x180 + node, [v, v ^ 0x5A, 0, 0, 0, 0, 0, 0], 2));
                        io_next[k] = cycle + 5 + rng.below(40);
                    }
                }
                // The HMI's poll, 20 times a second: each drive's
                // statusword and position, two I/O nodes' inputs.
                if cycle.is_multiple_of(50) {
                    let polls: [(u32, u16); 10] = [
                        (1, 0x6041),
                        (1, 0x6064),
                        (2, 0x6041),
                        (2, 0x6064),
                        (3, 0x6041),
                        (3, 0x6064),
                        (4, 0x6041),
                        (4, 0x6064),
                        (0x21, 0x6000),
                        (0x22, 0x2100),
                    ];
                    for (k, &(node, index)) in polls.iter().enumerate() {
                        let [lo, hi] = index.to_le_bytes();
                        let n = node as usize;
                        let value = match index {
                            0x6041 => u32::from(statusword[n]),
                            0x6064 => position[n],
                            _ => rng.next() as u32,
                        };
                        let v = value.to_le_bytes();
                        // The statusword is 16 bits: two bytes (0x4B).
                        let cmd = if index == 0x6041 { 0x4B } else { 0x43 };
                        let at = t0 + 420 + k as u64 * 50;
                        events.push((at, 0x600 + node, [0x40, lo, hi, 0, 0, 0, 0, 0], 8));
                        events.push((
                            at + 25,
                            0x580 + node,
                            [cmd, lo, hi, 0, v[0], v[1], v[2], v[3]],
                            8,
                        ));
                    }
                }
            }
        }
        events.sort_by_key(|e| e.0);
        for (micros, id, data, len) in &events {
            line.clear();
            candump_line(&mut line, *micros, *id, &data[..*len]);
            out.write_all(&line)?;
            written += line.len() as u64;
            lines += 1;
        }
    }
    Ok(lines)
}
