//! Which frames the analysis decodes: the ids that can matter, and on the
//! busy NMT and SDO ids, which contents matter. Everything else is only
//! counted, so most lines of a trace never get past the reader.

use super::Options;
use crate::canopen::emcy;
use crate::canopen::nmt;
use crate::canopen::sdo;
use crate::trace::{ContentFilter, Frame, Interest};

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
    for ids in [nmt, responses, requests] {
        i.add_standard_range(ids.clone());
        i.filter_content(ids, filter);
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
pub(super) fn content_matters(id: u32, data: &[u8]) -> bool {
    if emcy::is_nmt_error_control(id) {
        data.len() <= 1
    } else if sdo::is_sdo_id(id) {
        sdo::names_followed_object(id, data) || sdo::is_abort(data)
    } else {
        true
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

/// An SDO request or response naming object 0x1014 (COB-ID EMCY).
pub(super) fn is_cob_id_emcy_access(frame: &Frame<'_>) -> bool {
    !frame.extended && sdo::names_object(frame.id, frame.data.as_slice(), sdo::COB_ID_EMCY)
}
