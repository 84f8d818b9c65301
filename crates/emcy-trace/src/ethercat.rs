//! EtherCAT (ETG.1000, IEC 61158 type 12) in captured Ethernet packets: the
//! walk from a packet to the mailbox messages in it, and the CANopen over
//! EtherCAT (CoE) emergencies and SDO transfers among them. Drives like
//! STÖBER's send their EMCYs this way: the same 8 bytes as on CAN, read by
//! the master from the slave's mailbox.
//!
//! Where EtherCAT is: EtherType 0x88A4 behind an Ethernet header (link type
//! 1), after up to [`MAX_TAGS`] VLAN tags; behind a Linux cooked header
//! (113, 276) whose protocol is that EtherType; or in an unfragmented IPv4
//! UDP datagram to port 0x88A4.
//!
//! An EtherCAT frame is a 2-byte header (11 bits of length, 4 bits of type;
//! type 1 carries datagrams), then datagrams: each a 10-byte header
//! (command, index, address, 11 bits of length with the "more follows"
//! bit 15, IRQ), its data and a 2-byte working counter.
//!
//! Which datagrams hold a mailbox message, as Wireshark's EtherCAT
//! dissector decides: a write (FPWR, APWR) or a read (FPRD, APRD) at a
//! slave address from 0x1000 (the sync managers' memory, above the
//! registers), of at least a mailbox header's 6 bytes, whose mailbox type
//! is one the standard defines (AoE, EoE, CoE, FoE, SoE). Unlike Wireshark
//! (which asks it only of reads), the working counter must not be zero for
//! writes either: a capture at the master sees each frame on its way out,
//! working counter 0, and again on its way back, and a write no slave took
//! did not happen. A read at those addresses with working counter 0 is an
//! empty poll: the slave had nothing to say.
//!
//! Nothing here allocates or keeps state: a packet is walked in place.

use std::collections::HashMap;

use super::{Reason, Timestamp};

/// LINKTYPE_ETHERNET.
pub const LINKTYPE_ETHERNET: u16 = 1;
/// The EtherType of EtherCAT, and its UDP port.
pub const ETHERTYPE: u16 = 0x88A4;
const UDP_PORT: u16 = 0x88A4;
const ETHERTYPE_IPV4: u16 = 0x0800;
/// Whether an EtherType is a VLAN tag's protocol id: 802.1Q, 802.1ad or
/// the older QinQ one.
#[inline]
fn is_vlan(ethertype: u16) -> bool {
    matches!(ethertype, 0x8100 | 0x88A8 | 0x9100)
}
/// VLAN tags read in front of the EtherType (QinQ has two).
pub const MAX_TAGS: usize = 4;
const IPPROTO_UDP: u8 = 17;
const LINUX_SLL: u16 = 113;
const LINUX_SLL2: u16 = 276;

/// The EtherCAT frame type that carries datagrams.
const TYPE_DATAGRAMS: u8 = 1;
const DATAGRAM_HEADER: usize = 10;
const WORKING_COUNTER: usize = 2;
const MAILBOX_HEADER: usize = 6;
/// Slave addresses below this are registers, not mailbox memory.
const MAILBOX_MEMORY: u16 = 0x1000;
/// Longest mailbox message Wireshark reads (its data bytes).
const MAX_MAILBOX: usize = 1500;

/// Datagram commands that can carry a mailbox message.
const APRD: u8 = 1;
const APWR: u8 = 2;
const FPRD: u8 = 4;
const FPWR: u8 = 5;

/// Mailbox types (ETG.1000.6): AoE, EoE, CoE, FoE, SoE.
pub const MAILBOX_COE: u8 = 3;
const MAILBOX_TYPES: std::ops::RangeInclusive<u8> = 1..=5;

/// CoE services (the top 4 bits of the CoE header).
const COE_EMERGENCY: u8 = 1;
const COE_SDO_REQUEST: u8 = 2;
const COE_SDO_RESPONSE: u8 = 3;
const COE_HEADER: usize = 2;
/// An emergency's and an expedited SDO's bytes after the CoE header: the
/// same 8 bytes as the CAN frame.
pub const COE_BYTES: usize = 8;

/// Where the EtherCAT frame (its 2-byte header first) is in a packet of
/// `linktype`; `None` when the packet carries no EtherCAT.
#[inline]
pub fn locate(linktype: u16, packet: &[u8]) -> Option<&[u8]> {
    let (ethertype, payload) = match linktype {
        LINKTYPE_ETHERNET => {
            let mut at = 12;
            let mut ethertype = be16(packet, at)?;
            for _ in 0..MAX_TAGS {
                if !is_vlan(ethertype) {
                    break;
                }
                at += 4;
                ethertype = be16(packet, at)?;
            }
            (ethertype, packet.get(at + 2..)?)
        }
        LINUX_SLL => (be16(packet, 14)?, packet.get(16..)?),
        LINUX_SLL2 => (be16(packet, 0)?, packet.get(20..)?),
        _ => return None,
    };
    // A cooked header keeps a VLAN tag in front of the EtherType.
    let (ethertype, payload) = match is_vlan(ethertype) {
        true => (be16(payload, 2)?, payload.get(4..)?),
        false => (ethertype, payload),
    };
    match ethertype {
        ETHERTYPE => Some(payload),
        ETHERTYPE_IPV4 => udp(payload),
        _ => None,
    }
}

/// The payload of an unfragmented IPv4 UDP datagram to EtherCAT's port.
fn udp(ip: &[u8]) -> Option<&[u8]> {
    let &first = ip.first()?;
    let header = usize::from(first & 0x0F) * 4;
    let flags_offset = be16(ip, 6)?;
    // More fragments, or a fragment past the first: not read.
    if first >> 4 != 4 || header < 20 || flags_offset & 0x3FFF != 0 {
        return None;
    }
    if *ip.get(9)? != IPPROTO_UDP {
        return None;
    }
    let udp = ip.get(header..)?;
    if be16(udp, 2)? != UDP_PORT {
        return None;
    }
    let len = usize::from(be16(udp, 4)?);
    let end = len.clamp(8, udp.len().max(8));
    udp.get(8..end)
}

fn be16(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn le16(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

/// One mailbox message a datagram carried.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mailbox<'f> {
    /// The slave's configured station address (FPRD/FPWR); `None` for
    /// position addressing (APRD/APWR), which names no station.
    pub station: Option<u16>,
    /// Written by the master to the slave (else read from the slave).
    pub to_slave: bool,
    /// The mailbox type (3 = CoE).
    pub kind: u8,
    /// The 3-bit counter a slave steps for each new message; a message
    /// repeated with the same counter is a retry. 0: not used.
    pub counter: u8,
    /// The message's data after the mailbox header (cut to what the
    /// datagram holds).
    pub body: &'f [u8],
}

/// A CoE service this crate reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CoeService {
    /// A CoE emergency message.
    Emergency,
    /// An SDO request (master to slave).
    SdoRequest,
    /// An SDO response (slave to master).
    SdoResponse,
}

impl<'f> Mailbox<'f> {
    /// The CoE service and its bytes after the CoE header, for an
    /// emergency or an SDO transfer; `None` for another mailbox type or
    /// CoE service.
    pub fn coe(&self) -> Option<(CoeService, &'f [u8])> {
        if self.kind != MAILBOX_COE {
            return None;
        }
        let service = match le16(self.body, 0)? >> 12 {
            s if s == u16::from(COE_EMERGENCY) => CoeService::Emergency,
            s if s == u16::from(COE_SDO_REQUEST) => CoeService::SdoRequest,
            s if s == u16::from(COE_SDO_RESPONSE) => CoeService::SdoResponse,
            _ => return None,
        };
        Some((service, self.body.get(COE_HEADER..)?))
    }
}

/// A CoE emergency or SDO transfer of a station, owned: its first
/// [`COE_BYTES`] bytes after the CoE header (all an emergency or an
/// expedited SDO has; a longer SDO transfer's further bytes are not kept).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CoeMessage {
    /// The station address of the slave the message is from or to.
    pub station: u16,
    /// Written by the master to the slave (else read from the slave).
    pub to_slave: bool,
    /// The mailbox counter, which tells a repeated message from a new one.
    pub counter: u8,
    /// The CoE service.
    pub service: CoeService,
    len: u8,
    bytes: [u8; COE_BYTES],
}

impl CoeMessage {
    /// The CoE emergency or SDO transfer a mailbox message is, if it is
    /// one and names its station.
    pub fn of(m: &Mailbox<'_>) -> Option<CoeMessage> {
        let (service, body) = m.coe()?;
        let mut bytes = [0; COE_BYTES];
        let len = body.len().min(COE_BYTES);
        bytes[..len].copy_from_slice(&body[..len]);
        Some(CoeMessage {
            station: m.station?,
            to_slave: m.to_slave,
            counter: m.counter,
            service,
            len: len as u8,
            bytes,
        })
    }

    /// The bytes after the CoE header (at most [`COE_BYTES`]).
    pub fn data(&self) -> &[u8] {
        self.bytes.get(..usize::from(self.len)).unwrap_or_default()
    }
}

/// Tells a retry from a new message: a slave that repeats a message (the
/// master asked again after a lost read) sends it with the same counter,
/// and so does a master that writes again. A message with the counter and
/// bytes of the last one of its station, channel and direction is a
/// retry; counter 0 (not used) never is.
#[derive(Debug, Default)]
pub struct Retries {
    /// By channel, then by station and direction: the last message.
    last: HashMap<Box<[u8]>, Stations>,
    stations: usize,
}

/// A channel's stations: by station and direction, the last message.
type Stations = HashMap<(u16, bool), Last>;
type Last = (u8, CoeService, u8, [u8; COE_BYTES]);

/// Stations remembered at most; past that the memory starts again (one
/// retry may then pass as a message).
const MAX_STATIONS: usize = 1 << 16;

impl Retries {
    /// Whether `m`, on `channel`, repeats the message before it.
    pub fn is_retry(&mut self, channel: &[u8], m: &CoeMessage) -> bool {
        let this = (m.counter, m.service, m.len, m.bytes);
        let key = (m.station, m.to_slave);
        if let Some(last) = self.last.get_mut(channel).and_then(|c| c.get_mut(&key)) {
            let retry = m.counter != 0 && *last == this;
            *last = this;
            return retry;
        }
        if self.stations >= MAX_STATIONS {
            self.last.clear();
            self.stations = 0;
        }
        self.stations += 1;
        match self.last.get_mut(channel) {
            Some(c) => {
                c.insert(key, this);
            }
            None => {
                self.last
                    .insert(channel.into(), HashMap::from([(key, this)]));
            }
        }
        false
    }
}

/// What a frame's walk found besides its mailbox messages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Walked {
    /// Datagrams walked.
    pub datagrams: u32,
    /// Mailbox messages found in them.
    pub mailboxes: u32,
    /// Reads of mailbox memory no slave answered.
    pub empty_polls: u32,
}

/// Walks an EtherCAT frame's datagrams, handing each mailbox message to
/// `each`. An error says where the frame is cut short or inconsistent;
/// the messages before that point were handed over.
#[inline]
pub fn walk<'f>(frame: &'f [u8], each: impl FnMut(Mailbox<'f>)) -> Result<Walked, Reason> {
    let mut walked = Walked::default();
    walk_into(frame, &mut walked, each).map(|()| walked)
}

/// [`walk`], counting into `walked`: on an error it holds what was walked
/// before the damage (datagrams, messages, empty polls).
#[inline]
pub fn walk_into<'f>(
    frame: &'f [u8],
    walked: &mut Walked,
    mut each: impl FnMut(Mailbox<'f>),
) -> Result<(), Reason> {
    let Some(header) = le16(frame, 0) else {
        return Err("EtherCAT frame shorter than its 2-byte header".into());
    };
    if (header >> 12) as u8 != TYPE_DATAGRAMS {
        // Network variables, mailbox gateway: EtherCAT, but no datagrams.
        return Ok(());
    }
    // Ethernet pads short frames: the header's length says where the
    // datagrams end.
    let declared = 2 + usize::from(header & 0x07FF);
    let frame = frame.get(..declared).unwrap_or(frame);
    let mut at = 2;
    loop {
        let n = walked.datagrams + 1;
        let Some(head) = frame.get(at..at + DATAGRAM_HEADER) else {
            return Err(format!(
                "EtherCAT datagram {n}: its header is cut off at byte {} of the frame",
                frame.len()
            )
            .into());
        };
        let (cmd, adp, ado) = (head[0], le16(head, 2), le16(head, 4));
        let len_field = le16(head, 6).unwrap_or(0);
        let len = usize::from(len_field & 0x07FF);
        let data_at = at + DATAGRAM_HEADER;
        let end = data_at + len + WORKING_COUNTER;
        let (Some(data), Some(wkc)) = (frame.get(data_at..data_at + len), le16(frame, end - 2))
        else {
            return Err(format!(
                "EtherCAT datagram {n} ({}) of {len} data bytes runs past the end of the \
                 frame ({} bytes)",
                command_name(cmd),
                frame.len()
            )
            .into());
        };
        walked.datagrams = n;
        let to_slave = matches!(cmd, FPWR | APWR);
        if matches!(cmd, FPRD | APRD | FPWR | APWR)
            && ado.unwrap_or(0) >= MAILBOX_MEMORY
            && len >= MAILBOX_HEADER
        {
            if wkc == 0 {
                if !to_slave {
                    walked.empty_polls += 1;
                }
            } else if let Some(m) = mailbox(data, to_slave, matches!(cmd, FPRD | FPWR), adp) {
                walked.mailboxes += 1;
                each(m);
            }
        }
        at = end;
        if len_field & 0x8000 == 0 || at >= frame.len() {
            return Ok(());
        }
    }
}

/// The mailbox message at the start of a datagram's data (at least
/// [`MAILBOX_HEADER`] bytes), if its type is one the standard defines.
#[inline]
fn mailbox(data: &[u8], to_slave: bool, fixed: bool, adp: Option<u16>) -> Option<Mailbox<'_>> {
    let length = usize::from(le16(data, 0)?);
    let &control = data.get(5)?;
    let kind = control & 0x0F;
    if !MAILBOX_TYPES.contains(&kind) || length > MAX_MAILBOX {
        return None;
    }
    let rest = data.get(MAILBOX_HEADER..)?;
    Some(Mailbox {
        station: if fixed { adp } else { None },
        to_slave,
        kind,
        counter: (control >> 4) & 0x07,
        body: rest.get(..length).unwrap_or(rest),
    })
}

/// A datagram command's name, as ETG.1000 spells it.
pub fn command_name(cmd: u8) -> &'static str {
    const NAMES: [&str; 15] = [
        "NOP", "APRD", "APWR", "APRW", "FPRD", "FPWR", "FPRW", "BRD", "BWR", "BRW", "LRD", "LWR",
        "LRW", "ARMW", "FRMW",
    ];
    NAMES.get(usize::from(cmd)).copied().unwrap_or("command")
}

/// Fuzz target body: any bytes as an EtherCAT frame walk without a panic,
/// every message inside the frame and counted, CoE messages read from them
/// at most [`COE_BYTES`] long.
#[cfg(feature = "fuzzing")]
pub fn fuzz_walk(frame: &[u8]) {
    let range = frame.as_ptr_range();
    let mut seen = 0u32;
    let mut retries = Retries::default();
    let walked = walk(frame, |m| {
        seen += 1;
        let body = m.body.as_ptr_range();
        assert!(m.body.is_empty() || (range.start <= body.start && body.end <= range.end));
        assert!(m.counter < 8 && m.kind < 16);
        if let Some(c) = CoeMessage::of(&m) {
            assert!(c.data().len() <= COE_BYTES);
            assert_eq!(Some(c.station), m.station);
            // A message is never a retry of itself the first time.
            let first = retries.is_retry(b"f", &c);
            let again = retries.is_retry(b"f", &c);
            assert!(!first || c.counter != 0);
            assert_eq!(again, c.counter != 0);
        }
    });
    if let Ok(w) = walked {
        assert_eq!(w.mailboxes, seen);
        assert!(w.mailboxes + w.empty_polls <= w.datagrams);
    }
}

/// What an EtherCAT frame held: its counts, the CoE messages the caller
/// reads, and why its walk stopped early, if it did.
#[derive(Debug, Default)]
pub struct EthercatPacket {
    /// The packet's time, if the capture has one.
    pub time: Option<Timestamp>,
    /// What the walk through its datagrams found.
    pub walked: Walked,
    /// The CoE emergencies and SDO transfers it carried.
    pub messages: Vec<CoeMessage>,
    /// Why the walk stopped before the frame's end, if it did: the line is then
    /// malformed.
    pub error: Option<Reason>,
}

impl EthercatPacket {
    /// No mailbox message and no damage: only counted where the caller
    /// has an interest (the hot loop's EtherCAT frames).
    pub fn quiet(&self) -> bool {
        self.walked.mailboxes == 0 && self.error.is_none()
    }
}

/// EtherCAT seen in an input so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EthercatCounts {
    /// EtherCAT frames read.
    pub frames: u64,
    /// Mailbox messages in them.
    pub mailbox_messages: u64,
    /// Reads of mailbox memory no slave answered.
    pub empty_polls: u64,
}

impl EthercatCounts {
    /// Counts one more frame and what its walk found.
    pub fn add(&mut self, w: Walked) {
        self.frames += 1;
        self.mailbox_messages += u64::from(w.mailboxes);
        self.empty_polls += u64::from(w.empty_polls);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A datagram: command, station (ADP), offset (ADO), data, working
    /// counter; `more` sets the "more follows" bit.
    pub fn datagram(cmd: u8, adp: u16, ado: u16, data: &[u8], wkc: u16, more: bool) -> Vec<u8> {
        let mut d = vec![cmd, 0];
        d.extend_from_slice(&adp.to_le_bytes());
        d.extend_from_slice(&ado.to_le_bytes());
        let len = data.len() as u16 | if more { 0x8000 } else { 0 };
        d.extend_from_slice(&len.to_le_bytes());
        d.extend_from_slice(&[0, 0]);
        d.extend_from_slice(data);
        d.extend_from_slice(&wkc.to_le_bytes());
        d
    }

    pub fn frame(datagrams: &[Vec<u8>]) -> Vec<u8> {
        let body: Vec<u8> = datagrams.concat();
        let header = body.len() as u16 | (u16::from(TYPE_DATAGRAMS) << 12);
        let mut f = header.to_le_bytes().to_vec();
        f.extend_from_slice(&body);
        f
    }

    /// A CoE mailbox message of `service` with `bytes` after the CoE header.
    pub fn coe(service: u8, counter: u8, bytes: &[u8]) -> Vec<u8> {
        let mut body = (u16::from(service) << 12).to_le_bytes().to_vec();
        body.extend_from_slice(bytes);
        let mut m = (body.len() as u16).to_le_bytes().to_vec();
        m.extend_from_slice(&[0, 0, 0, MAILBOX_COE | counter << 4]);
        m.extend_from_slice(&body);
        m
    }

    fn ethernet(tags: &[u16], ethertype: u16, payload: &[u8]) -> Vec<u8> {
        let mut p = vec![0xFF; 6];
        p.extend_from_slice(&[2, 0, 0, 0, 0, 1]);
        for &t in tags {
            p.extend_from_slice(&t.to_be_bytes());
            p.extend_from_slice(&[0, 5]);
        }
        p.extend_from_slice(&ethertype.to_be_bytes());
        p.extend_from_slice(payload);
        p
    }

    fn all(frame: &[u8]) -> (Result<Walked, Reason>, Vec<Mailbox<'_>>) {
        let mut seen = Vec::new();
        let walked = walk(frame, |m| seen.push(m));
        (walked, seen)
    }

    const EMCY: [u8; 8] = [0x10, 0x43, 0x08, 0x01, 0x02, 0, 0, 0];

    #[test]
    fn finds_ethercat_behind_ethernet_vlan_cooked_headers_and_udp() {
        let f = frame(&[datagram(12, 0, 0, &[0; 4], 3, false)]);
        assert_eq!(locate(1, &ethernet(&[], ETHERTYPE, &f)), Some(&f[..]));
        assert_eq!(
            locate(1, &ethernet(&[0x88A8, 0x8100], ETHERTYPE, &f)),
            Some(&f[..])
        );
        assert_eq!(locate(1, &ethernet(&[], 0x0806, &f)), None);
        let mut sll = vec![0, 0, 0, 1, 0, 6];
        sll.extend_from_slice(&[0; 8]);
        sll.extend_from_slice(&ETHERTYPE.to_be_bytes());
        sll.extend_from_slice(&f);
        assert_eq!(locate(113, &sll), Some(&f[..]));
        let mut sll2 = ETHERTYPE.to_be_bytes().to_vec();
        sll2.extend_from_slice(&[0; 18]);
        sll2.extend_from_slice(&f);
        assert_eq!(locate(276, &sll2), Some(&f[..]));
        // UDP to port 0x88A4 over IPv4, padded after the datagram.
        let mut ip = vec![0x45, 0, 0, 0, 0, 0, 0x40, 0, 64, IPPROTO_UDP, 0, 0];
        ip.extend_from_slice(&[10, 0, 0, 1, 10, 0, 0, 2]);
        ip.extend_from_slice(&0x88A4u16.to_be_bytes());
        ip.extend_from_slice(&UDP_PORT.to_be_bytes());
        ip.extend_from_slice(&(8 + f.len() as u16).to_be_bytes());
        ip.extend_from_slice(&[0, 0]);
        ip.extend_from_slice(&f);
        let mut padded = ip.clone();
        padded.extend_from_slice(&[0; 6]);
        assert_eq!(
            locate(1, &ethernet(&[], ETHERTYPE_IPV4, &padded)),
            Some(&f[..])
        );
        // Another port, a later fragment: not EtherCAT.
        let mut other = ip.clone();
        other[22] = 0x12;
        assert_eq!(locate(1, &ethernet(&[], ETHERTYPE_IPV4, &other)), None);
        let mut fragment = ip;
        fragment[7] = 8;
        assert_eq!(locate(1, &ethernet(&[], ETHERTYPE_IPV4, &fragment)), None);
        assert_eq!(locate(227, &f), None);
    }

    #[test]
    fn mailbox_reads_with_data_are_messages_empty_polls_and_process_data_are_not() {
        let emcy = coe(COE_EMERGENCY, 2, &EMCY);
        let f = frame(&[
            // Process data: a logical read/write.
            datagram(12, 0, 0, &[1; 32], 3, true),
            // An empty poll of slave 1002's mailbox.
            datagram(FPRD, 1002, 0x1180, &[0; 16], 0, true),
            // Slave 1001's emergency, padded to its mailbox size.
            datagram(
                FPRD,
                1001,
                0x1180,
                &[emcy.clone(), vec![0; 8]].concat(),
                1,
                true,
            ),
            // A register read (address below 0x1000).
            datagram(FPRD, 1001, 0x0130, &[0; 16], 1, false),
        ]);
        let (walked, seen) = all(&f);
        assert_eq!(
            walked,
            Ok(Walked {
                datagrams: 4,
                mailboxes: 1,
                empty_polls: 1
            })
        );
        let m = seen[0];
        assert_eq!(
            (m.station, m.to_slave, m.kind, m.counter),
            (Some(1001), false, 3, 2)
        );
        assert_eq!(m.coe(), Some((CoeService::Emergency, &EMCY[..])));
    }

    #[test]
    fn writes_count_only_when_a_slave_took_them() {
        let request = coe(COE_SDO_REQUEST, 1, &[0x40, 0x18, 0x10, 1, 0, 0, 0, 0]);
        let out = frame(&[datagram(FPWR, 1001, 0x1000, &request, 0, false)]);
        assert_eq!(all(&out).1, vec![]);
        assert_eq!(all(&out).0.map(|w| w.empty_polls), Ok(0));
        let back = frame(&[datagram(FPWR, 1001, 0x1000, &request, 1, false)]);
        let seen = all(&back).1;
        assert_eq!(seen.len(), 1);
        assert!(seen[0].to_slave);
        assert_eq!(seen[0].coe().map(|c| c.0), Some(CoeService::SdoRequest));
    }

    #[test]
    fn position_addressing_names_no_station() {
        let emcy = coe(COE_EMERGENCY, 1, &EMCY);
        let f = frame(&[datagram(APRD, 0xFFFF, 0x1180, &emcy, 1, false)]);
        let seen = all(&f).1;
        assert_eq!(seen[0].station, None);
    }

    #[test]
    fn other_mailbox_types_and_coe_services_are_not_read_as_coe() {
        let mut eoe = coe(COE_EMERGENCY, 1, &EMCY);
        eoe[5] = 2 | 1 << 4;
        let tx_pdo = coe(4, 1, &EMCY);
        let f = frame(&[
            datagram(FPRD, 1, 0x1180, &eoe, 1, true),
            datagram(FPRD, 1, 0x1180, &tx_pdo, 1, false),
        ]);
        let (walked, seen) = all(&f);
        assert_eq!(walked.map(|w| w.mailboxes), Ok(2));
        assert!(seen.iter().all(|m| m.coe().is_none()));
        // Mailbox type 0 (an error reply) and 6.. are no message at all.
        let mut none = coe(COE_EMERGENCY, 1, &EMCY);
        none[5] = 0;
        let f = frame(&[datagram(FPRD, 1, 0x1180, &none, 1, false)]);
        assert_eq!(all(&f).0.map(|w| w.mailboxes), Ok(0));
    }

    #[test]
    fn short_and_inconsistent_frames_are_errors_after_what_was_read() {
        assert!(walk(&[0x10], |_| {}).is_err());
        let emcy = coe(COE_EMERGENCY, 1, &EMCY);
        let mut f = frame(&[
            datagram(FPRD, 7, 0x1180, &emcy, 1, true),
            datagram(FPRD, 8, 0x1180, &emcy, 1, false),
        ]);
        f.truncate(f.len() - 3);
        // The header still claims the full length: the cut shows.
        let (walked, seen) = all(&f);
        let why = walked.unwrap_err();
        assert!(why.contains("datagram 2 (FPRD)"), "{why}");
        assert_eq!(seen.len(), 1);
        // What was walked before the damage is counted.
        let mut counted = Walked::default();
        assert!(walk_into(&f, &mut counted, |_| {}).is_err());
        assert_eq!((counted.datagrams, counted.mailboxes), (1, 1));
        // A mailbox length past the datagram is cut to it.
        let mut long = emcy.clone();
        long[0] = 200;
        let f = frame(&[datagram(FPRD, 7, 0x1180, &long, 1, false)]);
        assert_eq!(all(&f).1[0].body.len(), emcy.len() - MAILBOX_HEADER);
    }

    #[test]
    fn padding_after_the_declared_length_is_not_a_datagram() {
        let mut f = frame(&[datagram(12, 0, 0, &[0; 4], 1, true)]);
        f.extend_from_slice(&[0xAA; 30]);
        assert_eq!(all(&f).0.map(|w| w.datagrams), Ok(1));
        // Frames that are not datagrams (type 4, network variables).
        assert_eq!(all(&[0x00, 0x40, 1, 2]).0, Ok(Walked::default()));
    }

    fn message(station: u16, counter: u8, code: u8) -> CoeMessage {
        let body = coe(COE_EMERGENCY, counter, &[code, 0x43, 1, 0x29, 0, 0, 0, 0]);
        let f = frame(&[datagram(FPRD, station, 0x1180, &body, 1, false)]);
        let mut out = None;
        walk(&f, |m| out = CoeMessage::of(&m)).unwrap();
        out.unwrap()
    }

    #[test]
    fn a_repeat_with_the_same_counter_and_bytes_is_a_retry() {
        let mut r = Retries::default();
        assert!(!r.is_retry(b"eth0", &message(1001, 2, 0x10)));
        assert!(r.is_retry(b"eth0", &message(1001, 2, 0x10)));
        // Another station, another channel: their own last message.
        assert!(!r.is_retry(b"eth0", &message(1002, 2, 0x10)));
        assert!(!r.is_retry(b"eth1", &message(1001, 2, 0x10)));
        // The next counter, or other bytes under the same counter: new.
        assert!(!r.is_retry(b"eth0", &message(1001, 3, 0x10)));
        assert!(!r.is_retry(b"eth0", &message(1001, 3, 0x20)));
        // Counter 0 is "not used": never a retry.
        assert!(!r.is_retry(b"eth0", &message(1001, 0, 0x10)));
        assert!(!r.is_retry(b"eth0", &message(1001, 0, 0x10)));
    }

    #[test]
    fn coe_messages_keep_eight_bytes_and_need_a_station() {
        let m = message(1001, 1, 0x10);
        assert_eq!(m.data(), &[0x10, 0x43, 1, 0x29, 0, 0, 0, 0]);
        assert_eq!(
            (m.station, m.service, m.to_slave),
            (1001, CoeService::Emergency, false)
        );
        // A longer SDO transfer keeps its first eight bytes.
        let long = coe(COE_SDO_RESPONSE, 1, &[7; 20]);
        let f = frame(&[datagram(FPRD, 5, 0x1180, &long, 1, false)]);
        let mut got = None;
        walk(&f, |m| got = CoeMessage::of(&m)).unwrap();
        assert_eq!(got.unwrap().data(), &[7; 8]);
        let f = frame(&[datagram(APRD, 0, 0x1180, &long, 1, false)]);
        let mut got = Some(m);
        walk(&f, |m| got = CoeMessage::of(&m)).unwrap();
        assert_eq!(got, None);
    }

    proptest::proptest! {
        #[test]
        fn walk_never_panics_and_messages_lie_inside_the_frame(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            let mut n = 0;
            let walked = walk(&bytes, |m| {
                n += 1;
                assert!(m.body.len() <= bytes.len());
                let _ = m.coe();
            });
            if let Ok(w) = walked {
                proptest::prop_assert_eq!(w.mailboxes, n);
            }
            let _ = locate(1, &bytes);
            let _ = locate(113, &bytes);
            let _ = locate(276, &bytes);
        }
    }
}
