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

/// Writes about `bytes` bytes of trace; `emcy_per_mille` of the frames are
/// EMCY (alternating raise and reset per node). Returns (lines, emcy frames).
pub fn write_trace<W: Write>(
    out: &mut W,
    format: TraceFormat,
    bytes: u64,
    emcy_per_mille: u64,
    seed: u64,
) -> io::Result<(u64, u64)> {
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
    if format == TraceFormat::Pcapng {
        let header = pcapng_header();
        out.write_all(&header)?;
        written += header.len() as u64;
    }
    while written < bytes {
        micros += 100 + rng.below(400);
        let node = 1 + rng.below(8) as u8;
        let mut data = [0u8; 8];
        let (id, len) = if rng.below(1000) < emcy_per_mille {
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
                1 => (0x700 + u32::from(node), 1),
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
    let mut idb = 113u16.to_le_bytes().to_vec();
    idb.extend([0, 0]);
    idb.extend(262_144u32.to_le_bytes());
    idb.extend(2u16.to_le_bytes()); // if_name
    idb.extend(4u16.to_le_bytes());
    idb.extend(b"can0");
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
