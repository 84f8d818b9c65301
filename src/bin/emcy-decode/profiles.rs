//! `emcy-decode profiles`: the built-in vendor profiles, one line each, or
//! one of them as its TOML file (`--toml NAME`).

use std::process::ExitCode;

use anyhow::{Result, bail};

use super::cli::ProfilesArgs;
use super::write_stdout;
use emcy_decode::canopen::profile::{self, Profile};

/// Lists the built-ins, the default marked; or prints one's TOML.
pub(super) fn run(args: &ProfilesArgs) -> Result<ExitCode> {
    if let Some(name) = &args.toml {
        let Some(text) = Profile::builtin_toml(name) else {
            let known: Vec<&str> = Profile::builtins().iter().map(Profile::name).collect();
            bail!("unknown profile '{name}' (known: {})", known.join(", "));
        };
        return write_stdout(&format!(
            "# The built-in profile \"{name}\" as emcy-decode ships it (emcy-decode profiles \
             --toml {name}).\n# Edit it and load it with --profile-file FILE: a user profile \
             named like a built-in replaces it;\n# rename it (name = \"...\") to keep both. \
             The format is in docs/guide/profiles.md (\"Vendor profiles\").\n\n{text}"
        ));
    }
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
