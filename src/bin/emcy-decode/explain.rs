//! `emcy-decode explain`: what a code means, or what one raw payload says.

use std::process::ExitCode;

use anyhow::Result;

use super::cli::{ExplainArgs, ExplainFormat, parse_code, parse_payload};
use super::write_stdout;
use emcy_decode::canopen::profile::Profile;
use emcy_decode::canopen::profile_choice;
use emcy_decode::report::explain;

/// Reads the code or payload with the chosen profile, as text or JSON.
pub(super) fn run(args: &ExplainArgs) -> Result<ExitCode> {
    let user = args
        .profile_file
        .as_deref()
        .map(Profile::load)
        .transpose()?;
    let profile: &Profile = match (&args.profile, &user) {
        (Some(name), Some(u)) if u.name() == name => u,
        (Some(name), _) => Profile::builtin(name).ok_or_else(|| {
            anyhow::anyhow!("unknown profile '{name}' (`emcy-decode profiles` lists them)")
        })?,
        (None, Some(u)) => u,
        (None, None) => profile_choice::default_profile(),
    };
    let text = match (&args.data, &args.code, args.format) {
        (Some(data), _, ExplainFormat::Text) => {
            explain::payload_text(profile, &parse_payload(data)?)?
        }
        (Some(data), _, ExplainFormat::Json) => {
            format!(
                "{:#}\n",
                explain::payload_json(profile, &parse_payload(data)?)?
            )
        }
        (None, Some(code), ExplainFormat::Text) => explain::code_text(profile, parse_code(code)?),
        (None, Some(code), ExplainFormat::Json) => {
            format!("{:#}\n", explain::code_json(profile, parse_code(code)?))
        }
        (None, None, _) => anyhow::bail!("give a CODE or --data"),
    };
    write_stdout(&text)
}
