//! [`PcapReader`]: the stream read block by block, the hot loop, the
//! resync after damage, and the packets held until link type 227's byte
//! order is known.

use std::collections::VecDeque;
use std::io::{self, Read};
use std::sync::{Arc, Mutex, PoisonError};

use pcap_parser::traits::PcapReaderIterator;
use pcap_parser::{LegacyPcapReader, PcapBlockOwned, PcapError, PcapNGReader};

use crate::ethercat::{CoeMessage, EthercatCounts, EthercatPacket};
use crate::id_counts::CountedChannel;
use crate::read::read_full;
use crate::{Format, Frame, FrameSource, IdCounts, Interest, Next, Parsed, Timestamp};

use super::clock::Clock;
use super::consts::{
    BUFFER, CHANNEL, EPB, MAX_BLOCK, MAX_HELD, MAX_HELD_BYTES, MAX_PACKET, PCAP_MAGICS, PLAIN_RUN,
    SAMPLE, bom, file_header, is_pcapng_block_type, sane_block,
};
use super::counted::{Counted, Hot, RawTime};
use super::decode::{Candidate, Decoder, Outcome};
use super::items::{Interface, Item, Ts};
use super::packet::{self, CAN_SOCKETCAN, Can, Order, Packet, Shape};
use super::stream::{Stream, Tap};

impl<R: Read> FrameSource for PcapReader<R> {
    /// [`Format::Pcap`] or [`Format::Pcapng`].
    fn format(&self) -> Option<Format> {
        Some(self.format)
    }

    /// What [`PcapReader::advance`] read, in the order the caller must
    /// learn it: the notes it led to, then the frames it only counted
    /// (they came before the packet), then the packet, or the error or
    /// end it met.
    fn next_item(&mut self, interest: Option<&Interest>) -> io::Result<Option<Next<'_>>> {
        loop {
            if self.advanced.is_none() {
                self.advanced = Some(self.advance(interest));
            }
            if let Some(note) = self.take_note() {
                return Ok(Some(Next::Note(note)));
            }
            let skipped = self.take_quiet();
            let (counted, timed) = self.take_counted();
            if counted + skipped > 0 {
                let timed_n = timed.map_or(0, |(n, _, _)| n);
                return Ok(Some(Next::Counted(crate::Counted {
                    plain: counted.saturating_sub(timed_n),
                    timed,
                    skipped,
                })));
            }
            match self.advanced.take() {
                Some(Ok(true)) => {
                    if self.ready.is_some() {
                        return Ok(self.take().map(Next::Record));
                    }
                }
                Some(Err(e)) => return Err(e),
                Some(Ok(false)) | None => return Ok(None),
            }
        }
    }

    fn take_ethercat(&mut self) -> Option<(Box<EthercatPacket>, &[u8])> {
        PcapReader::take_ethercat(self)
    }

    fn ethercat_counts(&self) -> Option<EthercatCounts> {
        Some(PcapReader::ethercat_counts(self))
    }

    fn plain_span(&self) -> Option<(Timestamp, Timestamp)> {
        PcapReader::plain_span(self)
    }

    /// Every frame only counted so far, including those of a
    /// [`Next::Counted`] not returned yet (counted before the packet now
    /// ready).
    fn counted_ids(&self) -> Option<&IdCounts> {
        Some(&self.counted.ids)
    }
}

/// What the crate's error means for a block whose bytes are all there.
pub(super) fn describe(e: &PcapError<&[u8]>) -> String {
    match e {
        PcapError::NomError(_, kind) => format!("its content is not valid ({kind:?})"),
        PcapError::OwnedNomError(_, kind) => format!("its content is not valid ({kind:?})"),
        PcapError::Incomplete(_) | PcapError::BufferTooSmall | PcapError::UnexpectedEof => {
            "a field of it runs past its end".to_string()
        }
        other => other.to_string(),
    }
}

/// Reads a pcap or pcapng stream packet by packet.
pub struct PcapReader<R: Read> {
    stream: Stream<R>,
    /// The input's read error, kept by the [`Tap`].
    error: Arc<Mutex<Option<io::Error>>>,
    pub(super) format: Format,
    /// The buffer's size (it grows for a long block).
    pub(super) capacity: usize,
    decoder: Decoder,
    /// Link type 227 evidence so far: impossible read big-endian, read
    /// little-endian, packets that told.
    evidence: [u32; 2],
    sampled: u32,
    /// Items held while the byte order of link type 227 is not known, with
    /// the channel of each frame.
    pub(super) held: VecDeque<(Item, Box<[u8]>)>,
    held_bytes: usize,
    /// The item [`PcapReader::take`] returns, and whether it was held (its
    /// channel is then in `channel`).
    ready: Option<(Item, bool)>,
    channel: Box<[u8]>,
    /// Packets only counted since the caller last asked, and all EtherCAT.
    counted: Counted,
    /// The EtherCAT frame [`PcapReader::take`] returned, for
    /// [`PcapReader::take_ethercat`].
    taken_ethercat: Option<Box<EthercatPacket>>,
    /// What the last [`PcapReader::advance`] returned, while the notes and
    /// counts it led to go out first ([`FrameSource::next_item`]).
    advanced: Option<io::Result<bool>>,
    /// The input ended (or failed: the error, returned after the held items).
    ended: bool,
    failed: Option<io::Error>,
}

impl<R: Read> PcapReader<R> {
    /// Reads the file header (pcap) or the first section header (pcapng).
    /// An error means this is not a readable pcap or pcapng file.
    pub fn new(mut input: R) -> io::Result<PcapReader<R>> {
        let invalid = |m: String| io::Error::new(io::ErrorKind::InvalidData, m);
        let mut head = vec![0u8; 12];
        let got = read_full(&mut input, head.get_mut(..4).unwrap_or_default())?;
        let magic = head.get(..4).unwrap_or_default();
        let error = Arc::new(Mutex::new(None));
        if let Some(&(_, order, nanos)) = PCAP_MAGICS.iter().find(|(m, _, _)| m == magic) {
            head.resize(24, 0);
            let got = 4 + read_full(&mut input, head.get_mut(4..).unwrap_or_default())?;
            if got < 24 {
                return Err(invalid(format!(
                    "pcap file header cut off after {got} of 24 bytes"
                )));
            }
            let linktype = order.u32(&head, 20).unwrap_or(0) & 0xFFFF;
            let tap = Tap::new(head, input, error.clone());
            let mut reader = LegacyPcapReader::new(BUFFER, tap)
                .map_err(|e| invalid(format!("pcap file header: {}", describe(&e))))?;
            // The first block is the file header.
            reader.consume(24);
            return Ok(PcapReader::with(
                Stream::Legacy(reader),
                error,
                Format::Pcap,
                BUFFER,
                Decoder {
                    order,
                    nanos,
                    interfaces: vec![Interface::new(
                        linktype as u16,
                        CHANNEL.as_bytes().into(),
                        true,
                        Clock::default(),
                        0,
                    )],
                    socketcan: None,
                    notes: VecDeque::new(),
                    fine_noted: false,
                },
            ));
        }
        if got == 4 && is_pcapng_block_type(&head) {
            let got = 4 + read_full(&mut input, head.get_mut(4..12).unwrap_or_default())?;
            let Some(order) = bom(&head) else {
                return Err(invalid(if got < 12 {
                    format!("pcapng section header cut off after {got} bytes")
                } else {
                    "not a pcapng file: its section header has no byte-order magic".to_string()
                }));
            };
            let len = order.u32(&head, 4).unwrap_or(0) as usize;
            if !sane_block(len) || len < 28 {
                return Err(invalid(format!(
                    "pcapng section header of {len} bytes: not sane (28 to {MAX_BLOCK}, \
                     a multiple of 4)"
                )));
            }
            head.resize(len, 0);
            let got = 12 + read_full(&mut input, head.get_mut(12..).unwrap_or_default())?;
            if got < len {
                return Err(invalid(format!(
                    "pcapng section header cut off after {got} of {len} bytes"
                )));
            }
            let capacity = BUFFER.max(len);
            let tap = Tap::new(head, input, error.clone());
            let reader = PcapNGReader::new(capacity, tap)
                .map_err(|e| invalid(format!("pcapng section header: {}", describe(&e))))?;
            return Ok(PcapReader::with(
                Stream::Ng(reader),
                error,
                Format::Pcapng,
                capacity,
                Decoder {
                    order,
                    nanos: false,
                    interfaces: Vec::new(),
                    socketcan: None,
                    notes: VecDeque::new(),
                    fine_noted: false,
                },
            ));
        }
        let shown: Vec<String> = head
            .get(..got)
            .unwrap_or_default()
            .iter()
            .map(|b| format!("{b:02X}"))
            .collect();
        Err(invalid(format!(
            "not a pcap or pcapng file: it starts with {}",
            if shown.is_empty() {
                "nothing".to_string()
            } else {
                shown.join(" ")
            }
        )))
    }

    fn with(
        stream: Stream<R>,
        error: Arc<Mutex<Option<io::Error>>>,
        format: Format,
        capacity: usize,
        decoder: Decoder,
    ) -> Self {
        PcapReader {
            stream,
            error,
            format,
            capacity,
            decoder,
            evidence: [0; 2],
            sampled: 0,
            held: VecDeque::new(),
            held_bytes: 0,
            ready: None,
            channel: Box::default(),
            counted: Counted::default(),
            taken_ethercat: None,
            advanced: None,
            ended: false,
            failed: None,
        }
    }

    /// Something about the input worth telling the user, once each (a
    /// byte order other than the link type's, time units finer than a
    /// [`Timestamp`] holds). Ask after each [`PcapReader::advance`].
    pub fn take_note(&mut self) -> Option<String> {
        self.decoder.notes.pop_front()
    }

    /// The next packet (or unreadable run of bytes), classified;
    /// `Ok(None)` at the end. An error is an I/O error of the input (a
    /// corrupt gzip stream): reading stops.
    #[cfg(any(test, feature = "fuzzing"))]
    pub fn next_packet(&mut self) -> io::Result<Option<Parsed<'_>>> {
        if !self.advance(None)? {
            return Ok(None);
        }
        Ok(self.take())
    }

    /// Reads up to the next packet, which [`PcapReader::take`] then
    /// returns; `Ok(false)` at the end. Notes it leads to are ready for
    /// [`PcapReader::take_note`] before the packet is taken. With
    /// `interest`, valid frames it does not want are only counted, for
    /// [`PcapReader::take_counted`], up to the next other packet (or a
    /// long run of them: then there is no packet to take).
    pub fn advance(&mut self, interest: Option<&Interest>) -> io::Result<bool> {
        loop {
            if (self.decoder.socketcan.is_some() || self.ended)
                && let Some((item, channel)) = self.held.pop_front()
            {
                self.held_bytes = self.held_bytes.saturating_sub(held_size(&item, &channel));
                self.channel = channel;
                self.ready = Some((item, true));
                return Ok(true);
            }
            if self.ended {
                return match self.failed.take() {
                    Some(e) => Err(e),
                    None => Ok(false),
                };
            }
            // Held packets wait for their order: what follows them too.
            let interest = if self.held.is_empty() { interest } else { None };
            match self.read_item(interest) {
                // A long run of plain frames (counted by the reader).
                Ok(Some(Item::Run)) => return Ok(true),
                Ok(Some(item)) => {
                    if self.held.is_empty() && !matches!(item, Item::Undecided { .. }) {
                        self.ready = Some((item, false));
                        return Ok(true);
                    }
                    self.hold(item);
                }
                Ok(None) => self.end(None),
                Err(e) => self.end(Some(e)),
            }
        }
    }

    /// How many frames [`PcapReader::advance`] only counted (they come
    /// before the packet it read), and how many of them, with which first
    /// and last time, it only timed (wanted ids whose data the interest's
    /// content filter rejects): `(counted, Some((timed, first, last)))`.
    /// The counts start again from 0.
    pub fn take_counted(&mut self) -> (u64, Option<(u64, Timestamp, Timestamp)>) {
        let timed = std::mem::take(&mut self.counted.timed);
        let last = timed.last.and_then(RawTime::get);
        let times = timed.first.zip(last).map(|(f, l)| (timed.n, f, l));
        (std::mem::take(&mut self.counted.plain), times)
    }

    /// The first and last times of the frames only counted so far.
    pub fn plain_span(&self) -> Option<(Timestamp, Timestamp)> {
        let (first, last) = self.counted.span?;
        let time = |(iface, ts)| self.decoder.raw_time(iface, ts).and_then(RawTime::get);
        time(first).zip(time(last))
    }

    /// EtherCAT frames [`PcapReader::advance`] only counted (they carried
    /// no mailbox message): skipped lines before the packet it read. The
    /// count starts again from 0.
    pub fn take_quiet(&mut self) -> u64 {
        std::mem::take(&mut self.counted.quiet)
    }

    /// The EtherCAT frame [`PcapReader::take`] just returned as skipped
    /// (or malformed), with its CoE messages and the channel they came on.
    pub fn take_ethercat(&mut self) -> Option<(Box<EthercatPacket>, &[u8])> {
        let packet = self.taken_ethercat.take()?;
        Some((packet, &self.channel))
    }

    /// EtherCAT seen so far: frames, mailbox messages, empty polls.
    pub fn ethercat_counts(&self) -> EthercatCounts {
        self.counted.ethercat
    }

    /// The packet [`PcapReader::advance`] read.
    pub fn take(&mut self) -> Option<Parsed<'_>> {
        self.taken_ethercat = None;
        let (item, held) = self.ready.take()?;
        if let Item::Ethercat { iface, packet } = item {
            self.counted.ethercat.add(packet.walked);
            if !held {
                self.channel = self.decoder.interface_name(iface);
            }
            let parsed = match &packet.error {
                Some(why) => Parsed::Malformed(why.clone()),
                None => Parsed::Skipped,
            };
            self.taken_ethercat = Some(packet);
            return Some(parsed);
        }
        if let Item::Frame {
            iface,
            device: Some(device),
            ..
        } = &item
            && !held
        {
            self.channel = self.decoder.device_channel(*iface, *device);
        }
        let channel: &[u8] = match &item {
            Item::Frame { device: None, .. } | Item::Undecided { .. } if !held => {
                let iface = match &item {
                    Item::Frame { iface, .. } | Item::Undecided { iface, .. } => *iface,
                    _ => 0,
                };
                self.decoder
                    .interfaces
                    .get(iface)
                    .map_or(&[][..], |i| &i.name)
            }
            _ => &self.channel,
        };
        let frame = |time: Option<Timestamp>, can: Can| Frame {
            time,
            channel,
            id: can.id,
            extended: can.extended,
            kind: can.kind,
            len: can.len,
            data: can.data,
        };
        Some(match item {
            Item::Frame { time, can, .. } => Parsed::Frame(frame(time, can)),
            Item::Undecided {
                time,
                bytes,
                reported,
                ..
            } => {
                let order = self.decoder.socketcan.unwrap_or(Order::Big);
                match packet::frame(CAN_SOCKETCAN, &bytes, reported, order, Shape::Guess, None) {
                    Packet::Can(can) => Parsed::Frame(frame(time, can)),
                    Packet::Malformed(why) => Parsed::Malformed(why),
                    Packet::NotCan | Packet::Plain(_) | Packet::Undecided(_) => Parsed::Skipped,
                }
            }
            Item::Skipped | Item::Plain { .. } | Item::Run | Item::Ethercat { .. } => {
                Parsed::Skipped
            }
            Item::Malformed(why) => Parsed::Malformed(why),
        })
    }

    fn end(&mut self, error: Option<io::Error>) {
        self.ended = true;
        self.failed = error;
        if self.decoder.socketcan.is_none() && !self.held.is_empty() {
            self.decide();
        }
    }

    /// Holds an item until the byte order of link type 227 is known.
    fn hold(&mut self, item: Item) {
        let channel: Box<[u8]> = match &item {
            Item::Frame {
                iface,
                device: Some(device),
                ..
            } => self.decoder.device_channel(*iface, *device),
            Item::Frame { iface, .. }
            | Item::Undecided { iface, .. }
            | Item::Ethercat { iface, .. } => self.decoder.interface_name(*iface),
            _ => Box::default(),
        };
        if let Item::Undecided { bytes, .. } = &item
            && let Some([big, little]) = packet::evidence(bytes)
        {
            self.evidence[0] += u32::from(big);
            self.evidence[1] += u32::from(little);
            self.sampled += 1;
        }
        self.held_bytes += held_size(&item, &channel);
        self.held.push_back((item, channel));
        let [big, little] = self.evidence;
        // Clear evidence decides at once, so that a live capture or a
        // followed file is not held for 32 packets: no impossible packet in
        // one order and at least two in the other.
        let clear = (big == 0 && little >= 2) || (little == 0 && big >= 2);
        if clear
            || self.sampled >= SAMPLE
            || self.held.len() >= MAX_HELD
            || self.held_bytes >= MAX_HELD_BYTES
        {
            self.decide();
        }
    }

    /// Fixes the byte order of link type 227 from the evidence: little-endian
    /// when fewer packets are impossible read little-endian than read
    /// big-endian and at least two are impossible read big-endian (one odd
    /// extended id proves nothing); big-endian, as the link type defines,
    /// otherwise.
    fn decide(&mut self) {
        let [big, little] = self.evidence;
        let order = if little < big && big >= 2 {
            Order::Little
        } else {
            Order::Big
        };
        self.decoder.socketcan = Some(order);
        if order == Order::Little {
            self.decoder.notes.push_back(format!(
                "the CAN ids of the CAN_SOCKETCAN packets are stored little-endian, not \
                 big-endian as the link type defines ({big} of the first {} packets read \
                 big-endian have flags or an id no CAN frame has, {little} read little-endian); \
                 read as little-endian",
                self.sampled
            ));
        }
    }

    /// The next item that is not a plain frame (those are counted in
    /// `plain`; [`Item::Run`] when a long run of them ends the call).
    fn read_item(&mut self, interest: Option<&Interest>) -> io::Result<Option<Item>> {
        loop {
            self.hot(interest);
            if self.counted.run() >= PLAIN_RUN {
                return Ok(Some(Item::Run));
            }
            let item = match self.stream {
                Stream::Legacy(_) => self.read_record(interest)?,
                Stream::Ng(_) => self.read_block(interest)?,
            };
            match item {
                Some(Item::Plain {
                    iface,
                    ts,
                    device,
                    ident,
                }) => {
                    // Counted outside the hot loop (a block with options,
                    // say), it may be the input's first or last frame too.
                    self.counted.saw(iface, ts);
                    let channel =
                        self.decoder
                            .counted_channel(&mut self.counted.ids, iface, device);
                    self.counted.count(channel, ident);
                    self.counted.plain += 1;
                }
                // As the hot loop counts them.
                Some(Item::Ethercat { packet, .. }) if interest.is_some() && packet.quiet() => {
                    self.counted.add(Hot::Ethercat(packet.walked));
                }
                other => return Ok(other),
            }
        }
    }

    /// The hot loop: packets whole in the buffer, read by the crate's
    /// packet parsers directly, while they are plain frames (counted).
    /// Anything else (a packet the caller wants, another block, a block
    /// that is not whole or not sane) is left for the general path.
    fn hot(&mut self, interest: Option<&Interest>) {
        let Some(interest) = interest else {
            return;
        };
        let order = self.decoder.order;
        match &mut self.stream {
            Stream::Ng(reader) => loop {
                // An enhanced packet block without options, whole in the
                // buffer: its fixed fields are read here (the crate's
                // parser costs some 250 instructions a packet, most of the
                // time of a capture of small CAN packets). Any other block,
                // or anything unusual, goes to the general path and the
                // crate; the fuzz target checks both read alike.
                let data = reader.data();
                let Some(fixed) = data.first_chunk::<28>() else {
                    return;
                };
                let field = |at: usize| order.u32(fixed, at).unwrap_or(0);
                let (len, caplen) = (field(4) as usize, field(20) as usize);
                if field(0) != EPB
                    || caplen > MAX_PACKET
                    || len != 32 + caplen.next_multiple_of(4)
                    || order.u32(data, len - 4) != Some(len as u32)
                {
                    return;
                }
                let Some(packet) = data.get(28..28 + caplen) else {
                    return;
                };
                let units = u64::from(field(12)) << 32 | u64::from(field(16));
                let iface = field(8) as usize;
                let Some(hot) =
                    self.decoder
                        .quick(iface, Ts::Units(units), packet, field(24), interest)
                else {
                    return;
                };
                if let Hot::Plain(ident, channel, _) = hot {
                    self.counted.saw(iface, Ts::Units(units));
                    let channel = match channel {
                        CountedChannel::Unknown => {
                            self.decoder
                                .counted_channel_of(&mut self.counted.ids, iface, packet)
                        }
                        known => known,
                    };
                    self.counted.count(channel, ident);
                }
                reader.consume_noshift(len);
                if !self.counted.add(hot) {
                    return;
                }
            },
            Stream::Legacy(reader) => loop {
                let data = reader.data();
                let Some(caplen) = order.u32(data, 8) else {
                    return;
                };
                let len = 16 + caplen as usize;
                if caplen as usize > MAX_PACKET || data.len() < len {
                    return;
                }
                let parsed = match order {
                    Order::Little => pcap_parser::parse_pcap_frame(data),
                    Order::Big => pcap_parser::parse_pcap_frame_be(data),
                };
                let Ok((_, b)) = parsed else {
                    return;
                };
                let ts = Ts::Legacy {
                    secs: b.ts_sec,
                    frac: b.ts_usec,
                };
                let Some(hot) = self.decoder.quick(0, ts, b.data, b.origlen, interest) else {
                    return;
                };
                if let Hot::Plain(ident, channel, _) = hot {
                    self.counted.saw(0, ts);
                    let channel = match channel {
                        CountedChannel::Unknown => {
                            self.decoder
                                .counted_channel_of(&mut self.counted.ids, 0, b.data)
                        }
                        known => known,
                    };
                    self.counted.count(channel, ident);
                }
                reader.consume_noshift(len);
                if !self.counted.add(hot) {
                    return;
                }
            },
        }
    }

    /// The input's error, kept by the tap.
    fn take_error(&self) -> io::Error {
        self.error
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
            .unwrap_or_else(|| io::Error::other("read error"))
    }

    /// Makes `need` bytes available (growing the buffer to hold them);
    /// `Ok(false)` when the input ends first.
    fn fill(&mut self, need: usize) -> io::Result<bool> {
        loop {
            let it = self.stream.it();
            if it.data().len() >= need {
                return Ok(true);
            }
            if it.reader_exhausted() {
                return Ok(false);
            }
            if need > self.capacity {
                it.grow(need);
                self.capacity = need;
            }
            if it.refill().is_err() {
                return Err(self.take_error());
            }
        }
    }

    /// The rest of the input (fewer than `need` bytes) as one malformed line.
    fn cut_off(&mut self, what: &str, at: u64, need: usize) -> Option<Item> {
        let it = self.stream.it();
        let rest = it.data().len();
        if rest == 0 {
            return None;
        }
        it.consume_noshift(rest);
        Some(Item::Malformed(
            format!("the file ends inside {what} at byte {at} ({rest} of {need} bytes)").into(),
        ))
    }

    /// The next pcap record.
    fn read_record(&mut self, interest: Option<&Interest>) -> io::Result<Option<Item>> {
        let mut at = self.stream.it().consumed() as u64;
        if !self.fill(16)? {
            return Ok(self.cut_off("a packet record header", at, 16));
        }
        while self.restart_at_file_header(at)? {
            at = self.stream.it().consumed() as u64;
            if !self.fill(16)? {
                return Ok(self.cut_off("a packet record header", at, 16));
            }
        }
        let header = self.stream.it().data();
        let caplen = self.decoder.order.u32(header, 8).unwrap_or(0) as usize;
        if caplen > MAX_PACKET {
            let skipped = self.resync()?;
            return Ok(Some(Item::Malformed(
                format!(
                    "packet record at byte {at} declares {caplen} captured bytes (at most \
                     {MAX_PACKET} are read): {skipped} bytes skipped to the next record"
                )
                .into(),
            )));
        }
        let need = 16 + caplen;
        if !self.fill(need)? {
            return Ok(self.cut_off("the packet", at, need));
        }
        let it = self.stream.it();
        // In the decoder's byte order, not the crate reader's: a new file
        // header (`restart_at_file_header`) may have changed it.
        let parsed = match self.decoder.order {
            Order::Little => pcap_parser::parse_pcap_frame(it.data()),
            Order::Big => pcap_parser::parse_pcap_frame_be(it.data()),
        };
        let item = match parsed {
            Ok((_, b)) => self.decoder.packet(
                0,
                Ts::Legacy {
                    secs: b.ts_sec,
                    frac: b.ts_usec,
                },
                b.data,
                b.origlen,
                interest,
            ),
            Err(pcap_parser::nom::Err::Error(e) | pcap_parser::nom::Err::Failure(e)) => {
                Item::Malformed(format!("packet record at byte {at}: {}", describe(&e)).into())
            }
            Err(pcap_parser::nom::Err::Incomplete(_)) => Item::Malformed(
                format!("packet record at byte {at}: a field of it runs past its end").into(),
            ),
        };
        it.consume_noshift(need);
        Ok(Some(item))
    }

    /// A pcap file header where a record should start: the file was
    /// truncated or replaced under `--follow` (a restarted tcpdump writes a
    /// new header), so reading goes on with the new file's byte order,
    /// time unit and link type, after a note. Read as a record, the header
    /// would be an empty packet from 2055 and its last 8 bytes the start of
    /// a record whose captured length is the first packet's time: every
    /// packet after it would be lost to the resync. pcapng needs none of
    /// this, as a new section header is a block like any other.
    fn restart_at_file_header(&mut self, at: u64) -> io::Result<bool> {
        let magic = self.stream.it().data().get(..4).unwrap_or_default();
        if !PCAP_MAGICS.iter().any(|(m, _, _)| m == magic) {
            return Ok(false);
        }
        // Only now, as a followed file's last record may be shorter than a
        // header and is not to wait for more.
        if !self.fill(24)? {
            return Ok(false);
        }
        let head = self.stream.it().data();
        let Some((order, nanos)) = file_header(head) else {
            return Ok(false);
        };
        let linktype = order.u32(head, 20).unwrap_or(0) & 0xFFFF;
        self.stream.it().consume_noshift(24);
        self.decoder.order = order;
        self.decoder.nanos = nanos;
        if let Some(interface) = self.decoder.interfaces.first_mut() {
            interface.linktype = linktype as u16;
        }
        self.decoder.notes.push_back(format!(
            "a new pcap file header at byte {at} (the file was truncated or replaced, as by a \
             restarted capture): reading on with it"
        ));
        Ok(true)
    }

    /// The next pcapng block that is a line.
    fn read_block(&mut self, interest: Option<&Interest>) -> io::Result<Option<Item>> {
        loop {
            let at = self.stream.it().consumed() as u64;
            if !self.fill(12)? {
                return Ok(self.cut_off("a block header", at, 12));
            }
            let head = self.stream.it().data();
            let order = if is_pcapng_block_type(head) {
                match bom(head) {
                    Some(o) => o,
                    None => {
                        let skipped = self.resync()?;
                        return Ok(Some(Item::Malformed(
                            format!(
                                "section header at byte {at} without a byte-order magic: \
                                 {skipped} bytes skipped to the next block"
                            )
                            .into(),
                        )));
                    }
                }
            } else {
                self.decoder.order
            };
            let kind = order.u32(head, 0).unwrap_or(0);
            let len = order.u32(head, 4).unwrap_or(0) as usize;
            if !sane_block(len) {
                let skipped = self.resync()?;
                return Ok(Some(Item::Malformed(
                    format!(
                        "block of type 0x{kind:08X} at byte {at} declares {len} bytes (a multiple \
                         of 4 from 12 to {MAX_BLOCK} is read): {skipped} bytes skipped to the next \
                         block"
                    )
                    .into(),
                )));
            }
            if !self.fill(len)? {
                return Ok(self.cut_off(&format!("the block of type 0x{kind:08X}"), at, len));
            }
            let trailer = order.u32(self.stream.it().data(), len - 4).unwrap_or(0) as usize;
            if trailer != len {
                let skipped = self.resync()?;
                return Ok(Some(Item::Malformed(
                    format!(
                        "block of type 0x{kind:08X} at byte {at} declares {len} bytes but ends \
                         with {trailer}: {skipped} bytes skipped to the next block"
                    )
                    .into(),
                )));
            }
            let it = self.stream.it();
            let outcome = match it.next() {
                Ok((_, PcapBlockOwned::NG(block))) => self.decoder.block(block, at, interest),
                Ok(_) => Outcome::Nothing,
                Err(e) => Outcome::Item(Item::Malformed(
                    format!(
                        "block of type 0x{kind:08X} at byte {at} ({len} bytes): {}",
                        describe(&e)
                    )
                    .into(),
                )),
            };
            it.consume_noshift(len);
            if let Outcome::Item(item) = outcome {
                return Ok(Some(item));
            }
        }
    }

    /// Skips from the current position (at least one byte) to the next
    /// block or record that is one; returns the bytes skipped.
    fn resync(&mut self) -> io::Result<u64> {
        let mut skipped = 0u64;
        let mut from = 1;
        loop {
            let it = self.stream.it();
            let end = it.reader_exhausted();
            let data = it.data();
            let mut verdict = None;
            for p in from..data.len() {
                let rest = data.get(p..).unwrap_or_default();
                let candidate = match self.format {
                    // A record cut short by a truncation ends where the
                    // new file's header starts.
                    Format::Pcap if file_header(rest).is_some() => Candidate::Yes,
                    Format::Pcap => self.decoder.record_at(rest, end),
                    _ => self.decoder.block_at(rest, end),
                };
                match candidate {
                    Candidate::No => {}
                    Candidate::Yes => {
                        verdict = Some((p, None));
                        break;
                    }
                    Candidate::More(need) => {
                        verdict = Some((p, Some(need)));
                        break;
                    }
                }
            }
            match verdict {
                Some((p, None)) => {
                    it.consume_noshift(p);
                    return Ok(skipped + p as u64);
                }
                Some((p, Some(need))) => {
                    it.consume_noshift(p);
                    skipped += p as u64;
                    from = 0;
                    self.fill(need)?;
                }
                None => {
                    let n = data.len();
                    it.consume_noshift(n);
                    skipped += n as u64;
                    from = 0;
                    if !self.fill(1)? {
                        return Ok(skipped);
                    }
                }
            }
        }
    }
}

pub(super) fn held_size(item: &Item, channel: &[u8]) -> usize {
    let bytes = match item {
        Item::Undecided { bytes, .. } => bytes.len(),
        Item::Malformed(why) => why.len(),
        Item::Ethercat { packet, .. } => {
            std::mem::size_of::<CoeMessage>() * packet.messages.len()
                + packet.error.as_ref().map_or(0, |w| w.len())
        }
        _ => 0,
    };
    64 + channel.len() + bytes
}
