//! Ctrl-C (SIGINT), SIGTERM and SIGHUP end reading, not the process: what
//! was read is reported (the per-node summary a user at the machine wants),
//! then the exit status is 128 + the signal (130, 143, 129), as shells
//! report a process the signal killed. The handler only sets flags: it
//! cancels the token the readers were given and records which signal came.
//!
//! A second signal ends the process at once, with that signal's status and
//! no more output: the report after the first may be long, or stuck on a
//! full pipe, and whoever signals twice wants it gone.
//!
//! signal-hook rather than ctrlc: ctrlc (with its "termination" feature)
//! catches SIGTERM and SIGHUP too but does not say which came, and the exit
//! status must; signal-hook's flags also give the second-signal exit.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use signal_hook::consts::signal::{SIGINT, SIGTERM};
use signal_hook::flag;

use emcy_decode::trace::cancel::Cancel;

#[cfg(unix)]
use signal_hook::consts::signal::SIGHUP;

/// The signals that stop a run (no SIGHUP outside Unix).
#[cfg(unix)]
const SIGNALS: [i32; 3] = [SIGINT, SIGTERM, SIGHUP];
#[cfg(not(unix))]
const SIGNALS: [i32; 2] = [SIGINT, SIGTERM];

/// What stopped a run.
pub(super) struct Stop {
    /// 128 + the signal.
    pub(super) status: u8,
    /// For the note after the report, e.g. `Ctrl-C`.
    pub(super) name: &'static str,
}

/// Which signal came first, once [`catch`] is in place.
pub(super) struct Caught {
    first: Arc<AtomicUsize>,
    cancel: Cancel,
}

impl Caught {
    /// The signal that stopped the run, if one did.
    pub(super) fn stopped(&self) -> Option<Stop> {
        if !self.cancel.is_cancelled() {
            return None;
        }
        // 0: cancelled by no signal here (no caller does that); read as Ctrl-C.
        let signal = i32::try_from(self.first.load(Ordering::SeqCst)).unwrap_or(0);
        Some(stop_for(signal))
    }
}

fn stop_for(signal: i32) -> Stop {
    #[cfg(unix)]
    if signal == SIGHUP {
        return Stop {
            status: 129,
            name: "SIGHUP",
        };
    }
    if signal == SIGTERM {
        return Stop {
            status: 143,
            name: "SIGTERM",
        };
    }
    Stop {
        status: 130,
        name: "Ctrl-C",
    }
}

/// Catches the stopping signals from here on: the first cancels `cancel`,
/// a second exits. Without a handler (it failed to install) the default
/// applies: the process ends at once.
pub(super) fn catch(cancel: &Cancel) -> Caught {
    let first = Arc::new(AtomicUsize::new(0));
    let stopped = cancel.flag();
    for signal in SIGNALS {
        let status = i32::from(stop_for(signal).status);
        // signal-hook runs a signal's actions in the order registered: a
        // second signal finds the token cancelled and exits before anything
        // else; the first records which it was, then cancels. Only the first
        // is recorded: a later one exits, it never gets that far.
        let _ = flag::register_conditional_shutdown(signal, status, Arc::clone(&stopped));
        let _ = flag::register_usize(signal, Arc::clone(&first), signal as usize);
        let _ = flag::register(signal, Arc::clone(&stopped));
    }
    Caught {
        first,
        cancel: cancel.clone(),
    }
}

#[cfg(test)]
mod tests {
    // The signals themselves are sent to the binary (tests/integration/live.rs).
    use super::*;

    #[test]
    fn each_signal_has_its_shell_status() {
        assert_eq!(stop_for(SIGINT).status, 130);
        assert_eq!(stop_for(SIGTERM).status, 143);
        #[cfg(unix)]
        assert_eq!(stop_for(SIGHUP).status, 129);
    }
}
