//! Which frames the analysis decodes: the ids that can matter, and on the
//! busy NMT and SDO ids, which contents matter. Everything else is only
//! counted, so most lines of a trace never get past the reader.

use std::sync::{Arc, RwLock};

use super::options::Options;
use crate::canopen::cia402;
use crate::canopen::cob_id;
use crate::canopen::emcy;
use crate::canopen::nmt;
use crate::canopen::pdo;
use crate::canopen::sdo;
use crate::trace::{ContentFilter, DataHead, Frame, Interest};

/// The ids whose frames are decoded; everything else is only counted:
/// EMCY, NMT commands, NMT error control (boot-up, heartbeats, guarding),
/// SDO (identity, moved EMCY ids, error history, heartbeat times, aborts)
/// and EMCY ids given on the command line. On the NMT and SDO ids only some
/// frames matter ([`content_matters`]); the readers only time the others.
pub(crate) fn interest(opts: &Options) -> Interest {
    let mut i = Interest::none();
    let filter = sdo_filter(false);
    let nmt = emcy::NMT_ERROR_CONTROL_BASE + 1..=emcy::NMT_ERROR_CONTROL_BASE + 127;
    let responses = sdo::RESPONSE_BASE + 1..=sdo::RESPONSE_BASE + 127;
    let requests = sdo::REQUEST_BASE + 1..=sdo::REQUEST_BASE + 127;
    i.add_standard_range(emcy::FIRST_EMCY_ID..=emcy::LAST_EMCY_ID);
    i.add_standard(nmt::COMMAND_ID);
    for ids in [nmt.clone(), responses, requests] {
        i.add_standard_range(ids.clone());
        i.filter_content(ids, filter);
    }
    // Steady heartbeats are taken a run at a time (the fold fast path,
    // `Consumer::take_folded_run`), and EMCYs, which change no node's
    // heartbeat or NMT state, do not end the run (they come every few
    // hundred lines on a busy bus).
    if folding() {
        i.fold(nmt);
        i.keep_inside(emcy::FIRST_EMCY_ID..=emcy::LAST_EMCY_ID);
    }
    for e in &opts.emcy_ids {
        add_emcy_id(&mut i, e.id, e.extended);
    }
    // Error frames are rare on a sound bus, and on a faulty one they are
    // the story.
    i.add_error_frames();
    // SYNC is timed always (a gap is a `sync_missed`): the candump hot
    // loop hands its lines over with their times, undecoded.
    i.hand_over(cob_id::SYNC_ID);
    i
}

/// Whether a frame on an NMT error control or SDO id can change more than
/// the input's first and last time: on 0x700 + node every frame of at most
/// one byte (boot-up, heartbeat, guarding request and reply: each moves a
/// node's heartbeat deadline or NMT state); on the SDO ids the frames
/// [`sdo_frame_matters`] keeps. SDO traffic for other objects, and the
/// segments of every transfer nobody follows (a firmware download's
/// thousands), skips all further work.
pub(super) fn content_matters(id: u32, data: DataHead) -> bool {
    matters::<false>(id, data)
}

/// [`content_matters`] while some node has a long segmented transfer going
/// on: its segments are not read, and its last one (c = 1) passes too.
/// Apart from that time the last segments stay out: their command bytes
/// (odd, under 0x20) are those of a block sub-block's segments 1 to 31,
/// which a block firmware download sends by the thousand.
fn content_matters_in_long_transfers(id: u32, data: DataHead) -> bool {
    matters::<true>(id, data)
}

/// The content filter: with the last segments of segmented transfers
/// (`long`) or without.
pub(super) fn sdo_filter(long: bool) -> ContentFilter {
    if long {
        ContentFilter(content_matters_in_long_transfers)
    } else {
        ContentFilter(content_matters)
    }
}

#[inline]
fn matters<const LAST_SEGMENTS: bool>(id: u32, data: DataHead) -> bool {
    if emcy::is_nmt_error_control(id) {
        data.len() <= 1
    } else if sdo::is_sdo_id(id) {
        // Asked of every SDO frame of a trace: the command is read once,
        // from the bytes the reader parsed.
        match *data.head() {
            [cmd, ..] => sdo_frame_matters(id, cmd, LAST_SEGMENTS),
            [] => false,
        }
    } else {
        true
    }
}

/// Whether an SDO frame with command byte `cmd` can matter to the SDO
/// monitor:
///
/// - a command that carries an index (an initiate or its answer), of any
///   object: every transfer is told (`sdo` events), the monitor follows
///   those of objects some monitor learns from to their values;
/// - a command of the block transfers, an abort, or a segment that may be
///   a sub-block's first: the SDO monitor follows every block transfer
///   with these alone (a block's segments carry sequence numbers where
///   other frames carry commands, so it must know where one goes on to
///   read any frame of its node right);
/// - with `last_segments` (while a long segmented transfer goes on), a
///   segmented transfer's last segment (c = 1): a long transfer whose
///   segments are not read ends with it.
///
/// The other segments of segmented transfers never name an object, and
/// their data bytes are never read as one: the SDO monitor takes a node's
/// SDO ids out of the filter while it reads a segmented transfer's every
/// segment (a short one, or one of an object some monitor learns from),
/// and puts them back at its end. A firmware download's thousands of
/// segments stay behind the filter.
#[inline]
fn sdo_frame_matters(id: u32, cmd: u8, last_segments: bool) -> bool {
    let cs = cmd >> 5;
    (4..=6).contains(&cs)
        || cmd == FIRST_BLOCK_SEGMENT
        || is_initiate(id, cmd)
        || last_segments && cmd & 0xE1 == LAST_SEGMENT
}

/// Whether `cmd` on SDO id `id` is an initiate or its answer with the
/// bits CiA 301 leaves unused clear, as devices send them: the client's
/// download initiate (0x20-0x2F: n, e, s) and upload initiate (0x40), the
/// node's upload answer (0x40-0x4F) and download answer (0x60). A block
/// transfer's segments carry every sequence number in that byte: 17 of
/// 127 look like this, where 64 have command specifier 1 or 2 (measured:
/// a block firmware download 1.66x the time before this test, with the
/// specifier alone).
#[inline]
fn is_initiate(id: u32, cmd: u8) -> bool {
    if id >= sdo::REQUEST_BASE {
        cmd & 0xF0 == 0x20 || cmd == 0x40
    } else {
        cmd & 0xF0 == 0x40 || cmd == 0x60
    }
}

/// A segment's command byte, masked with 0xE1 (the command specifier and
/// the c bit), when it is its transfer's last: command specifier 0 (a
/// download segment from the client, an upload segment from the node)
/// with c = 1.
const LAST_SEGMENT: u8 = 0x01;

/// A sub-block's segment 1 when it is not the transfer's last: the block
/// monitor learns from it where a sub-block begins (and a kept value fits
/// in it). A last segment has bit 7 set, so command specifiers 4 to 7,
/// which pass as aborts and block commands but for 7.
const FIRST_BLOCK_SEGMENT: u8 = 0x01;

/// Whether command specifier `cs` on SDO id `id` is an initiate or an
/// initiate's response (the commands whose bytes 1-2 are an index, besides
/// aborts and block initiates): the client's download and upload
/// initiates (1, 2), the server's upload and download initiate responses
/// (2, 3).
#[inline]
fn carries_index(id: u32, cs: u8) -> bool {
    if id >= sdo::REQUEST_BASE {
        cs == 1 || cs == 2
    } else {
        cs == 2 || cs == 3
    }
}

fn index_of(lo: u8, hi: u8) -> u16 {
    u16::from_le_bytes([lo, hi])
}

/// Whether some monitor learns from `index`'s value: the followed objects,
/// PDO parameters, a drive's words, the texts a node names itself by.
/// Transfers of others are only counted.
#[inline]
pub(super) fn learns_from(index: u16) -> bool {
    sdo::is_followed(index)
        || pdo::PdoId::is_pdo_parameter(index)
        || cia402::is_decoded(index)
        || sdo::is_text(index)
}

/// Whether the consumer may widen the interest when it reads `frame`, one
/// a worker handed over: then the lines after it may hold frames that
/// interest filtered out, and the consumer reads them again if it did
/// widen (`parallel::consume_in_order`). Widening comes from SDO alone: a
/// moved EMCY id (0x1014), a device type (0x1000: a drive's PDOs watched),
/// a PDO parameter, or a transfer the SDO monitor starts to follow (its
/// node's segments unfiltered). So: frames naming those objects, every
/// frame that is not an initiate (aborts, block commands: they may end or
/// complete a transfer being followed) and every frame on an SDO id out of
/// the filter (a transfer being followed). An expedited access of any
/// other object (a poll of a drive's statusword, say) widens nothing.
pub(super) fn may_widen(frame: &Frame<'_>, interest: &Interest) -> bool {
    if frame.extended || !sdo::is_sdo_id(frame.id) {
        return false;
    }
    if !interest.filters(frame.id) {
        return true;
    }
    match *frame.data.as_slice() {
        [cmd, lo, hi, ..] if carries_index(frame.id, cmd >> 5) => {
            let index = index_of(lo, hi);
            index == sdo::COB_ID_EMCY
                || index == sdo::DEVICE_TYPE
                || pdo::PdoId::is_pdo_parameter(index)
                || sdo::begins_segmented_transfer(frame.id, frame.data.as_slice())
        }
        _ => true,
    }
}

/// The current interest and its generation, shared with workers: a block
/// parsed with an older generation is parsed again in order.
pub(super) type SharedInterest = Arc<RwLock<(u64, Interest)>>;

/// The ids the analysis decodes now. They grow (an EMCY id moved, a PDO
/// mapping learnt, a drive to watch) and shrink (a drive watched long
/// enough); each change is a new generation, published to the workers
/// while they run.
pub(super) struct Wanted {
    pub(super) interest: Interest,
    pub(super) generation: u64,
    /// The generation of the last change that may have added to the
    /// interest: a worker's block parsed with this one or a later one
    /// holds every frame the consumer wants (and perhaps some it no longer
    /// does, which it skips).
    pub(super) widened: u64,
    /// Set while workers run: where they read the interest from.
    pub(super) shared: Option<SharedInterest>,
    /// `--timing`: what the readers read, the analysis's interest with
    /// every frame timed ([`Interest::every_frame`]), kept in step with it.
    pub(super) reading: Option<Interest>,
}

impl Wanted {
    pub(super) fn new(interest: Interest, every_frame: bool) -> Self {
        Wanted {
            generation: 0,
            widened: 0,
            shared: None,
            reading: every_frame.then(|| interest.every_frame()),
            interest,
        }
    }

    /// What the readers decode: the analysis's interest, or every frame.
    #[inline]
    pub(super) fn reading(&self) -> &Interest {
        self.reading.as_ref().unwrap_or(&self.interest)
    }

    /// `add` may add ids: if it did, workers parse with the new interest
    /// and blocks parsed before are read again.
    pub(super) fn widen(&mut self, add: impl FnOnce(&mut Interest)) {
        let before = self.interest.clone();
        add(&mut self.interest);
        if self.interest != before {
            self.changed(true);
        }
    }

    /// `remove` may take ids or contents out of the interest, and says
    /// whether it did (without a copy to compare with: it is asked often
    /// and nearly always says no). Workers get the narrower interest; what
    /// they parsed with the wider one stays good.
    pub(super) fn narrow(&mut self, remove: impl FnOnce(&mut Interest) -> bool) {
        if remove(&mut self.interest) {
            self.changed(false);
        }
    }

    /// A node's EMCY id moved (object 0x1014 seen in the trace): frames on
    /// it are decoded from here on.
    pub(super) fn add_emcy_id(&mut self, id: u32, extended: bool) {
        add_emcy_id(&mut self.interest, id, extended);
        self.changed(true);
    }

    /// The interest grew: blocks read before may lack frames it wants
    /// decoded (with every frame timed, they have them only timed), so
    /// they are read again.
    fn widened_now(&mut self) {
        self.widened = self.generation;
    }

    /// The analysis's interest changed (`widened`: it may have grown):
    /// the workers read with the new one, and blocks read before it grew
    /// are read again. With `--timing` the readers' interest follows it,
    /// and when that stays the same (a content filter changed, which it
    /// has none of) nothing else changes.
    fn changed(&mut self, widened: bool) {
        if let Some(reading) = &mut self.reading {
            let follows = self.interest.every_frame();
            if *reading == follows {
                return;
            }
            *reading = follows;
        }
        self.publish();
        if widened {
            self.widened_now();
        }
    }

    fn publish(&mut self) {
        self.generation += 1;
        if let Some(shared) = &self.shared
            && let Ok(mut w) = shared.write()
        {
            *w = (self.generation, self.reading().clone());
        }
    }
}

/// An EMCY id besides 0x80 + node (`--emcy-id`, or moved by object
/// 0x1014): decoded, and every frame on it matters whatever range it is in.
pub(super) fn add_emcy_id(interest: &mut Interest, id: u32, extended: bool) {
    add_id(interest, id, extended);
    if !extended {
        interest.unfilter(id);
    }
}

fn add_id(interest: &mut Interest, id: u32, extended: bool) {
    if extended {
        interest.add_extended(id);
    } else {
        interest.add_standard(id);
    }
}

/// Whether readers may fold repeated frames; tests and fuzz targets turn
/// it off on their thread to check that the result never depends on
/// folding.
#[cfg(not(any(test, feature = "fuzzing")))]
fn folding() -> bool {
    true
}

#[cfg(any(test, feature = "fuzzing"))]
pub(crate) use test_folding::{folding, set_folding};

#[cfg(any(test, feature = "fuzzing"))]
mod test_folding {
    use std::cell::Cell;

    thread_local! {
        static FOLDING: Cell<bool> = const { Cell::new(true) };
    }

    pub(crate) fn folding() -> bool {
        FOLDING.with(Cell::get)
    }

    pub(crate) fn set_folding(on: bool) {
        FOLDING.with(|f| f.set(on));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The one-pass filter says what CiA 301's commands say, spelt out
        /// by direction: every initiate and its answer, every block
        /// command, abort and possible first block segment, and while a
        /// long transfer goes on a segmented transfer's last segment; no
        /// other segment.
        #[test]
        fn content_matters_is_the_command_table(
            id in prop_oneof![0u32..0x800, 0x581u32..0x600, 0x601u32..0x680, 0x701u32..0x780],
            cmd in any::<u8>(),
            index in prop_oneof![
                any::<u16>(),
                0x1000u16..0x1020,
                0x1400u16..0x1C00,
                0x603Fu16..0x6042,
            ],
            rest in prop::collection::vec(any::<u8>(), 0..6),
            len in 0usize..9,
            long in any::<bool>(),
        ) {
            let [lo, hi] = index.to_le_bytes();
            let mut data = vec![cmd, lo, hi];
            data.extend(rest);
            data.truncate(len);
            let expected = if emcy::is_nmt_error_control(id) {
                data.len() <= 1
            } else if sdo::is_sdo_id(id) {
                let client = id >= 0x600;
                let initiate = match client {
                    true => (0x20..=0x2F).contains(&cmd) || cmd == 0x40,
                    false => (0x40..=0x4F).contains(&cmd) || cmd == 0x60,
                };
                let last_segment = long && cmd >> 5 == 0 && cmd & 0x01 == 1;
                !data.is_empty()
                    && (matches!(cmd >> 5, 4..=6) || cmd == 0x01 || initiate || last_segment)
            } else {
                true
            };
            prop_assert_eq!((sdo_filter(long).0)(id, DataHead::of(&data)), expected);
        }
    }

    #[test]
    fn segments_pass_only_when_last_while_a_long_transfer_goes_on() {
        // A download segment whose data reads as 0x1A00, its confirmation,
        // an upload segment request and a server's upload segment.
        for (id, data) in [
            (0x605, [0x00, 0x00, 0x1A, 0x01, 0x10, 0x00, 0x41, 0x60]),
            (0x605, [0x10, 0x40, 0x60, 0, 0, 0, 0, 0]),
            (0x585, [0x20, 0x00, 0x1A, 0, 0, 0, 0, 0]),
            (0x605, [0x60, 0x41, 0x60, 0, 0, 0, 0, 0]),
            (0x585, [0x0E, 0x00, 0x10, 0, 0, 0, 0, 0]),
        ] {
            assert!(
                !content_matters(id, DataHead::of(&data)),
                "{id:X} {data:02X?}"
            );
        }
        // Initiates of any object pass: every transfer is told.
        assert!(content_matters(0x605, DataHead::of(&[0x21, 0x00, 0x1A, 1])));
        assert!(content_matters(0x585, DataHead::of(&[0x4B, 0x41, 0x60, 0])));
        assert!(content_matters(0x605, DataHead::of(&[0x21, 0x50, 0x1F, 1])));
        // A download's and an upload's last segment end a long transfer:
        // they pass while one goes on (they read as block segments 11 and
        // 29 otherwise, which stay out).
        let long = sdo_filter(true).0;
        let last = [
            (0x605, [0x0B, 1, 2, 3, 4, 0, 0, 0]),
            (0x585, [0x1D, 1, 0, 0, 0, 0, 0, 0]),
        ];
        for (id, data) in last {
            assert!(long(id, DataHead::of(&data)));
            assert!(!content_matters(id, DataHead::of(&data)));
        }
    }

    #[test]
    fn widening_frames_are_the_objects_that_move_ids() {
        let i = interest(&Options::default());
        let frame = |id: u32, data: &[u8]| Frame {
            time: None,
            channel: b"can0",
            id,
            extended: false,
            kind: crate::trace::FrameKind::Data,
            len: data.len() as u8,
            data: crate::trace::Payload::from_slice(data).unwrap_or_default(),
        };
        // Expedited reads of a drive's statusword and position widen
        // nothing; of a device type, a PDO mapping or 0x1014 they may.
        assert!(!may_widen(
            &frame(0x581, &[0x4B, 0x41, 0x60, 0, 0x37, 0x02, 0, 0]),
            &i
        ));
        assert!(!may_widen(
            &frame(0x601, &[0x40, 0x41, 0x60, 0, 0, 0, 0, 0]),
            &i
        ));
        assert!(may_widen(
            &frame(0x581, &[0x43, 0x00, 0x10, 0, 0x92, 1, 2, 0]),
            &i
        ));
        assert!(may_widen(
            &frame(0x581, &[0x60, 0x00, 0x1A, 1, 0, 0, 0, 0]),
            &i
        ));
        assert!(may_widen(
            &frame(0x581, &[0x43, 0x14, 0x10, 0, 0x81, 0, 0, 0]),
            &i
        ));
        // A segmented upload of a learnt object begins: followed from here.
        assert!(may_widen(
            &frame(0x581, &[0x41, 0x18, 0x10, 1, 4, 0, 0, 0]),
            &i
        ));
        assert!(may_widen(
            &frame(0x601, &[0x21, 0x41, 0x60, 0, 2, 0, 0, 0]),
            &i
        ));
        // Any segmented transfer short enough to be read segment by segment.
        assert!(may_widen(
            &frame(0x601, &[0x21, 0x00, 0x20, 0, 12, 0, 0, 0]),
            &i
        ));
        assert!(!may_widen(
            &frame(0x601, &[0x2B, 0x40, 0x60, 0, 0x0F, 0, 0, 0]),
            &i
        ));
        assert!(!may_widen(
            &frame(0x581, &[0x60, 0x40, 0x60, 0, 0, 0, 0, 0]),
            &i
        ));
        // Aborts and block commands may end a followed transfer.
        assert!(may_widen(
            &frame(0x601, &[0x80, 0x41, 0x60, 0, 0, 0, 0, 0]),
            &i
        ));
        assert!(may_widen(
            &frame(0x581, &[0xA2, 127, 127, 0, 0, 0, 0, 0]),
            &i
        ));
        // Any frame on an id out of the filter: a transfer being followed.
        let mut followed = i.clone();
        followed.unfilter(0x581);
        assert!(may_widen(
            &frame(0x581, &[0x20, 0, 0, 0, 0, 0, 0, 0]),
            &followed
        ));
        assert!(!may_widen(&frame(0x181, &[0x37, 0x02]), &i));
    }
}
