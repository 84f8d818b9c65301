//! `emcy-decode completions SHELL` and `emcy-decode man`: generated from
//! the clap definitions, so they never disagree with `--help`.

use std::process::ExitCode;

use anyhow::Result;
use clap::CommandFactory;

use super::cli::Cli;
use super::write_stdout;

/// A completion script for `shell`.
pub(super) fn completions(shell: clap_complete::Shell) -> Result<ExitCode> {
    let mut out = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "emcy-decode", &mut out);
    write_stdout(&String::from_utf8_lossy(&out))
}

/// The man page (roff).
pub(super) fn man_page() -> Result<ExitCode> {
    let mut out = Vec::new();
    clap_mangen::Man::new(Cli::command()).render(&mut out)?;
    write_stdout(&String::from_utf8_lossy(&out))
}
