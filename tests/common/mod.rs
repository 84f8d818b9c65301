//! Shared helpers for the CLI tests.
#![allow(dead_code)]

pub mod frames;

use assert_cmd::Command;

/// The binary with a neutral terminal environment, so output never depends
/// on who runs the tests.
pub fn emcy_decode() -> Command {
    let mut cmd = Command::cargo_bin("emcy-decode").expect("binary built");
    cmd.env_remove("COLUMNS")
        .env_remove("NO_COLOR")
        .env_remove("CLICOLOR_FORCE")
        .env_remove("CI");
    cmd
}

/// The first differing line of two texts, for readable failures.
pub fn first_difference(expected: &str, actual: &str) -> String {
    let mut e = expected.lines();
    let mut a = actual.lines();
    let mut n = 1;
    loop {
        match (e.next(), a.next()) {
            (None, None) => return "texts differ only in line endings".to_string(),
            (x, y) if x == y => n += 1,
            (x, y) => {
                return format!(
                    "line {n}:\n  expected: {}\n  actual:   {}",
                    x.unwrap_or("<end>"),
                    y.unwrap_or("<end>")
                );
            }
        }
    }
}
pub mod tracegen;
