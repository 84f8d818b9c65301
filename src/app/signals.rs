//! Ctrl-C ends reading, not the process: what was read is reported (the
//! per-node summary a user at the machine wants), then the exit status is
//! 130. The handler only cancels the token the readers were given.

use crate::trace::cancel::Cancel;

/// The exit status of a run stopped by Ctrl-C (128 + SIGINT), as shells use.
pub(super) const EXIT_INTERRUPTED: u8 = 130;

/// Catches Ctrl-C from here on: it cancels `cancel`. Without a handler (it
/// failed to install) the default applies: the process ends at once.
pub(super) fn catch(cancel: &Cancel) {
    let cancel = cancel.clone();
    let _ = ctrlc::set_handler(move || cancel.cancel());
}
