//! `emcy-decode profiles`: the built-in vendor profiles, one line each.

use std::process::ExitCode;

use anyhow::Result;

use super::write_stdout;
use crate::canopen::profile::{self, Profile};

/// Lists the built-ins, the default marked.
pub(super) fn run() -> Result<ExitCode> {
    let mut text = String::new();
    let width = Profile::builtins()
        .iter()
        .map(|p| p.name().len())
        .max()
        .unwrap_or(0);
    for p in Profile::builtins() {
        let default = if p.name() == profile::DEFAULT_PROFILE {
            " (default)"
        } else {
            ""
        };
        text.push_str(&format!("{:<width$}  {}{default}\n", p.name(), p.summary()));
    }
    write_stdout(&text)
}
