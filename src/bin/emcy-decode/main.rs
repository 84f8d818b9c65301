//! The `emcy-decode` program: the command line, one file per command, exit
//! codes, signals, progress bars, stdout and the threads policy. Only the
//! program knows about the process; it uses the library as any other Rust
//! program could, and the library never imports it. Its crates (clap,
//! indicatif, signal-hook, ...) come with the `application` feature, so a
//! program that depends on the library without it compiles none of them.
#![forbid(unsafe_code)]

mod baseline;
mod cli;
mod config;
mod decode;
mod diff;
mod explain;
mod man;
mod profiles;
mod signals;

use std::io::{self, Write};
use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use cli::{Cli, Command};
use emcy_decode::text::printable;

/// The exit codes of the contract in `--help`.
const EXIT_OK: u8 = 0;
const EXIT_FAIL_ON: u8 = 1;
const EXIT_ERROR: u8 = 2;

/// The whole program: parse the command line, run the command, map errors
/// to one `error:` line and exit 2.
fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage(&e),
    };
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            error_line(&format!("{e:#}"));
            ExitCode::from(EXIT_ERROR)
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Some(Command::Explain(args)) => explain::run(&args),
        Some(Command::Completions { shell }) => man::completions(shell),
        Some(Command::Man(args)) => man::run(&args),
        Some(Command::Profiles(args)) => profiles::run(&args),
        Some(Command::Baseline(args)) => baseline::baseline(&args),
        Some(Command::Check(args)) => baseline::check(&args),
        Some(Command::Diff(args)) => diff::run(&args),
        Some(Command::Config(args)) => config::run(&args),
        None => decode::run(&cli.decode),
    }
}

/// What clap has to say instead of a run: a usage error on stderr (exit 2),
/// or `--help`/`--version` on stdout (exit 0), unless stdout cannot take it
/// (a full disk: exit 2 with an `error:` line; a reader that went away is
/// fine, as for every output).
fn usage(e: &clap::Error) -> ExitCode {
    let code = u8::try_from(e.exit_code()).unwrap_or(EXIT_ERROR);
    match e.print() {
        Err(io) if e.use_stderr() || io.kind() != io::ErrorKind::BrokenPipe => {
            error_line(&format!("writing output: {io}"));
            ExitCode::from(EXIT_ERROR)
        }
        _ => ExitCode::from(code),
    }
}

/// Writes `error: MESSAGE` on stderr. A stderr that cannot take it (a full
/// disk, a closed descriptor) loses the line, never the exit code:
/// `eprintln!` would panic there and turn exit 2 into 101.
fn error_line(message: &str) {
    let _ = writeln!(io::stderr(), "error: {}", printable(message));
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
