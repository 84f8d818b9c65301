//! The application: the command line, one file per command, exit codes,
//! signals, progress bars, stdout and the threads policy. Only this layer
//! knows about the process; the library below never imports it.

mod baseline;
mod cli;
mod decode;
mod explain;
mod man;
mod profiles;
mod signals;

use std::io::{self, Write};
use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use cli::{Cli, Command};

/// The exit codes of the contract in `--help`.
const EXIT_OK: u8 = 0;
const EXIT_FAIL_ON: u8 = 1;
const EXIT_ERROR: u8 = 2;

/// The whole program: parse the command line, run the command, map errors
/// to one `error:` line and exit 2. Clap exits 2 on usage errors and 0 for
/// `--help`/`--version` itself.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(EXIT_ERROR)
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Some(Command::Explain(args)) => explain::run(&args),
        Some(Command::Completions { shell }) => man::completions(shell),
        Some(Command::Man) => man::man_page(),
        Some(Command::Profiles) => profiles::run(),
        Some(Command::Baseline(args)) => baseline::baseline(&args),
        Some(Command::Check(args)) => baseline::check(&args),
        None => decode::run(&cli.decode),
    }
}

/// Writes a whole short output; a reader that went away is not an error.
fn write_stdout(text: &str) -> Result<ExitCode> {
    let mut out = io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Err(e) if e.kind() != io::ErrorKind::BrokenPipe => return Err(e.into()),
        _ => {}
    }
    Ok(ExitCode::from(EXIT_OK))
}
