//! Which frames the analysis decodes: the ids that can matter, and on the
//! busy NMT and SDO ids, which contents matter. Everything else is only
//! counted, so most lines of a trace never get past the reader.

use std::sync::{Arc, RwLock};

use super::options::Options;
use crate::canopen::cia402;
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
    let filter = ContentFilter(content_matters);
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
    i
}

/// Whether a frame on an NMT error control or SDO id can change more than
/// the input's first and last time: on 0x700 + node every frame of at most
/// one byte (boot-up, heartbeat, guarding request and reply: each moves a
/// node's heartbeat deadline or NMT state); on the SDO ids aborts and
/// frames naming an object the decoder follows. SDO traffic for other
/// objects, most frames on those ids, skips all further work.
pub(super) fn content_matters(id: u32, data: DataHead) -> bool {
    if emcy::is_nmt_error_control(id) {
        data.len() <= 1
    } else if sdo::is_sdo_id(id) {
        // What `names_followed_object || is_abort || concerns_drive` say
        // (a test holds them equal), reading the command and index once:
        // asked of every SDO frame of a trace.
        let head = data.head();
        match *head {
            [cmd, lo, hi] => {
                let index = index_of(lo, hi);
                sdo::is_abort(head) || sdo::is_followed(index) || names_drive_object(id, cmd, index)
            }
            _ => sdo::is_abort(head),
        }
    } else {
        true
    }
}

/// Whether an SDO frame can matter to a CiA 402 drive's decoding or to a
/// transfer: it names a PDO parameter (0x1400-0x1BFF) or one of
/// 0x6040/0x6041/0x603F, or it is a segment of a segmented download, a
/// segment's confirmation, or a block transfer's command (their frames
/// name no object; the SDO monitor keeps only those of a transfer it
/// follows). A segmented upload's segments are not among them: nearly
/// every one is of an object nobody learns from (a name, a string), and
/// decoding them all cost more than twice the instructions on an SDO-heavy
/// trace; the SDO monitor has its node's responses decoded from the upload
/// of an object it learns from on.
pub(super) fn concerns_drive(id: u32, data: &[u8]) -> bool {
    match *data {
        [cmd, lo, hi, ..] => names_drive_object(id, cmd, index_of(lo, hi)),
        _ => false,
    }
}

fn index_of(lo: u8, hi: u8) -> u16 {
    u16::from_le_bytes([lo, hi])
}

/// Command specifiers of the client's segments and block commands
/// (download segment 0, block upload 5, block download 6), a bit each.
const REQUEST_TRANSFER_CS: u8 = 1 << 0 | 1 << 5 | 1 << 6;
/// Command specifiers of the server's confirmations and block commands
/// (download segment 1, block download 5, block upload 6).
const RESPONSE_TRANSFER_CS: u8 = 1 << 1 | 1 << 5 | 1 << 6;

/// [`concerns_drive`] of a frame with command byte `cmd` naming `index`.
#[inline]
fn names_drive_object(id: u32, cmd: u8, index: u16) -> bool {
    let transfer = if id >= sdo::REQUEST_BASE {
        REQUEST_TRANSFER_CS
    } else {
        RESPONSE_TRANSFER_CS
    };
    pdo::PdoId::is_pdo_parameter(index)
        || cia402::is_decoded(index)
        || transfer >> (cmd >> 5) & 1 != 0
}

/// Whether a frame can widen the interest when the consumer reads it: an
/// SDO access of 0x1014 (moves an EMCY id), of 0x1000 (a CiA 402 drive's
/// PDOs get watched), one that can complete a PDO configuration (by any
/// transfer), or a node's answer that begins a segmented upload of an
/// object some monitor learns from (its node's answers get decoded). A
/// worker's block holding one is classified again on the consumer's thread.
pub(super) fn may_widen(frame: &Frame<'_>) -> bool {
    if frame.extended || !sdo::is_sdo_id(frame.id) {
        return false;
    }
    let data = frame.data.as_slice();
    sdo::names_object(frame.id, data, sdo::COB_ID_EMCY)
        || sdo::names_object(frame.id, data, sdo::DEVICE_TYPE)
        || concerns_drive(frame.id, data)
        || sdo::begins_segmented_upload(frame.id, data)
            && matches!(*data, [_, lo, hi, ..] if sdo::is_followed(index_of(lo, hi)))
}

/// The current interest and its generation, shared with workers: a block
/// parsed with an older generation is parsed again in order.
pub(super) type SharedInterest = Arc<RwLock<(u64, Interest)>>;

/// The ids the analysis decodes now. They only grow (an EMCY id moved, a
/// PDO mapping learnt, a drive to watch); each widening is a new
/// generation, published to the workers while they run.
pub(super) struct Wanted {
    pub(super) interest: Interest,
    pub(super) generation: u64,
    /// Set while workers run: where they read the interest from.
    pub(super) shared: Option<SharedInterest>,
}

impl Wanted {
    pub(super) fn new(interest: Interest) -> Self {
        Wanted {
            interest,
            generation: 0,
            shared: None,
        }
    }

    /// `add` may add ids: if it did, workers parse with the new interest
    /// and blocks parsed before are read again.
    pub(super) fn widen(&mut self, add: impl FnOnce(&mut Interest)) {
        let before = self.interest.clone();
        add(&mut self.interest);
        if self.interest != before {
            self.publish();
        }
    }

    /// A node's EMCY id moved (object 0x1014 seen in the trace): frames on
    /// it are decoded from here on.
    pub(super) fn add_emcy_id(&mut self, id: u32, extended: bool) {
        add_emcy_id(&mut self.interest, id, extended);
        self.publish();
    }

    fn publish(&mut self) {
        self.generation += 1;
        if let Some(shared) = &self.shared
            && let Ok(mut w) = shared.write()
        {
            *w = (self.generation, self.interest.clone());
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
        /// The one-pass filter says what its three questions say.
        #[test]
        fn content_matters_is_its_three_questions(
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
        ) {
            let [lo, hi] = index.to_le_bytes();
            let mut data = vec![cmd, lo, hi];
            data.extend(rest);
            data.truncate(len);
            let expected = if emcy::is_nmt_error_control(id) {
                data.len() <= 1
            } else if sdo::is_sdo_id(id) {
                sdo::names_followed_object(id, &data)
                    || sdo::is_abort(&data)
                    || concerns_drive(id, &data)
            } else {
                true
            };
            prop_assert_eq!(content_matters(id, DataHead::of(&data)), expected);
        }
    }
}
