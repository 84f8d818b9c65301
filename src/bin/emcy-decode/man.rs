//! `emcy-decode completions SHELL` and `emcy-decode man`: generated from
//! the clap definitions, so they never disagree with `--help`. The manual
//! also carries what the README says of formats and exit codes, since the
//! README is not installed with the binary.

use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::CommandFactory;
use clap_mangen::Man;
use clap_mangen::roff::{Roff, roman};

use super::cli::{Cli, ENVIRONMENT, ManArgs};
use super::{EXIT_OK, write_stdout};

/// A completion script for `shell`.
pub(super) fn completions(shell: clap_complete::Shell) -> Result<ExitCode> {
    let mut out = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "emcy-decode", &mut out);
    write_stdout(&String::from_utf8_lossy(&out))
}

/// `man` prints the main page, `man CMD` a subcommand's page, `man --all
/// DIR` writes every page (emcy-decode.1, emcy-decode-CMD.1) into DIR.
pub(super) fn run(args: &ManArgs) -> Result<ExitCode> {
    let root = built();
    if let Some(dir) = &args.all {
        // As `install -d` would: ~/.local/share/man/man1 may not exist yet.
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        for (name, page) in pages(&root)? {
            let path = dir.join(format!("{name}.1"));
            std::fs::write(&path, page).with_context(|| format!("writing {}", path.display()))?;
        }
        return Ok(ExitCode::from(EXIT_OK));
    }
    let page = match &args.command {
        None => render(&root, true)?,
        Some(name) => match root.find_subcommand(name) {
            Some(sub) => render(sub, false)?,
            None => bail!(
                "no subcommand '{name}': {}",
                root.get_subcommands()
                    .map(|s| s.get_name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        },
    };
    write_stdout(&String::from_utf8_lossy(&page))
}

/// The command with display names set (`emcy-decode-explain`), which the
/// subcommand pages are titled and referred to by.
fn built() -> clap::Command {
    let mut cmd = Cli::command().disable_help_subcommand(true);
    cmd.build();
    cmd
}

/// Every page: the main one, then one per subcommand, with its file stem.
fn pages(root: &clap::Command) -> Result<Vec<(String, Vec<u8>)>> {
    let mut out = vec![("emcy-decode".to_string(), render(root, true)?)];
    for sub in root.get_subcommands().filter(|s| !s.is_hide_set()) {
        let name = sub.get_display_name().unwrap_or(sub.get_name()).to_string();
        out.push((name, render(sub, false)?));
    }
    Ok(out)
}

/// One page: clap_mangen's sections, with our own in place of its EXTRA
/// (the `--help` epilogue, which in a manual belongs under real headings).
fn render(cmd: &clap::Command, main: bool) -> Result<Vec<u8>> {
    // Subcommands have no version of their own: every page says the tool's.
    let man = Man::new(cmd.clone())
        .source(format!("emcy-decode {}", env!("CARGO_PKG_VERSION")))
        .manual("emcy-decode manual");
    let mut out = Vec::new();
    man.render_title(&mut out)?;
    man.render_name_section(&mut out)?;
    man.render_synopsis_section(&mut out)?;
    man.render_description_section(&mut out)?;
    if cmd.get_arguments().any(|a| !a.is_hide_set()) {
        man.render_options_section(&mut out)?;
    }
    if cmd.has_subcommands() {
        man.render_subcommands_section(&mut out)?;
    }
    let mut roff = Roff::new();
    if main {
        section(&mut roff, "EXAMPLES", EXAMPLES);
        section(&mut roff, "FORMATS", FORMATS);
        section(&mut roff, "EXIT STATUS", EXIT_STATUS);
        section(&mut roff, "ENVIRONMENT", ENVIRONMENT);
    } else if let Some(after) = cmd.get_after_long_help() {
        section(&mut roff, "DETAILS", &after.to_string());
    }
    section(&mut roff, "SEE ALSO", &see_also(cmd, main));
    roff.to_writer(&mut out)?;
    if cmd.get_version().is_some() {
        man.render_version_section(&mut out)?;
    }
    Ok(out)
}

/// A section of paragraphs (blank-line separated); lines starting with
/// spaces keep their line breaks (examples, tables).
fn section(roff: &mut Roff, title: &str, text: &str) {
    roff.control("SH", [title]);
    for para in text.split("\n\n") {
        let lines: Vec<&str> = para.lines().collect();
        if lines.iter().any(|l| l.starts_with(' ')) {
            // Indented relative to the least indented line: roff drops
            // the first line's leading spaces anyway.
            let indent = lines
                .iter()
                .map(|l| l.len() - l.trim_start().len())
                .min()
                .unwrap_or(0);
            roff.control("PP", []).control("nf", []);
            for line in lines {
                roff.text([roman(line.get(indent..).unwrap_or(line))]);
            }
            roff.control("fi", []);
        } else {
            roff.control("PP", []).text([roman(lines.join(" "))]);
        }
    }
}

fn see_also(cmd: &clap::Command, main: bool) -> String {
    let mut names: Vec<String> = Vec::new();
    if !main {
        names.push("emcy-decode(1)".into());
    }
    for sub in built().get_subcommands().filter(|s| !s.is_hide_set()) {
        let name = sub.get_display_name().unwrap_or(sub.get_name());
        if Some(name) != cmd.get_display_name() {
            names.push(format!("{name}(1)"));
        }
    }
    names.push("candump(1)".into());
    format!(
        "{}\n\nAll pages: emcy-decode man --all DIR (then man -l DIR/emcy-decode.1).",
        names.join(", ")
    )
}

// No `\` after the quote: it would eat the first line's indent.
const EXAMPLES: &str = "  emcy-decode trace.log
      readable report: events, node timelines, counts
  emcy-decode --format ndjson trace.asc | jq 'select(.node==5)'
      one JSON object per line, filtered with jq
  candump -L can0 | emcy-decode -
      decode live from a bus
  emcy-decode -r --glob '*.log' traces/
      every candump log under a directory
  emcy-decode --fail-on active traces/*.log
      fail a CI job when a node ends in error
  emcy-decode baseline traces/*.log -o baseline.json
  emcy-decode check --baseline baseline.json traces/*.log
      record what traces contain, then fail CI on a new error
  emcy-decode diff good.log bad.log
      where a good and a bad run part at the CANopen level
  emcy-decode explain 4310
  emcy-decode explain --data \"10 43 09 01 00 00 00 00\"
      what a code, or one raw EMCY payload, means";

const FORMATS: &str = "\
The format is detected from the content, never from the file name; gzip is \
detected by its magic bytes, also on stdin, and so are the binary formats \
(also inside gzip). --input-format names it instead. Until a text format is \
known every line goes to every reader; the first frame decides, or an ASC \
base or Begin Triggerblock header, or a ***BUSMASTER Ver ...*** header. \
Every record is a frame, a counted line that is no frame (comments, \
headers, status lines), or a malformed line reported as FILE:LINE: REASON; \
reading goes on.

candump log (candump -l, -L): (1469439874.299654) can0 081#1043...; 3-digit \
ids standard, 8-digit extended; #R remote, ## CAN FD, _DLC raw DLC; \
DROPCOUNT lines say the kernel dropped frames (reported: EMCYs may be \
missing); -tz and -td times (deltas summed, see --timestamps).

candump screen output (the default): can0  081   [8]  10 43 ..., with or \
without -ta/-td/-tz/-tA timestamps, -x RX/TX columns, [nn] CAN FD, {X} raw \
DLC, remote request, ERRORFRAME, -a ASCII column, -c colour codes.

Vector ASC: date, base hex|dec, timestamps absolute|relative, \
Begin/End Triggerblock; classic and CANFD lines (a CANFD line without flag \
0x1000 is a classic frame), x extended ids, r remote, ErrorFrame; status, \
statistic and other event lines skipped.

PEAK TRC 1.0 to 2.1 (;$FILEVERSION, ;$STARTTIME, ;$COLUMNS): DT, Rx/Tx, \
FD/FB/FE/BI (CAN FD), RR/RTR (remote), error frames; status rows skipped. \
Times are ;$STARTTIME (taken as UTC) plus the offset, else seconds since \
the start.

BUSMASTER log (versions 1.6 to 2.4): 14:19:11:4184 Tx 1 0x099 s 8 ...; \
***HEX***/***DEC*** (else decided by the first data byte), system, \
absolute and relative time modes, appended sessions, J1939 sessions.

IXXAT MiniMon V3 ASCII trace: \"00:02:20.66\";\"83\";\"Std\";\"\";\"00 01 \"; Std and \
Ext ids, Rtr remote requests; times are seconds since the measurement \
start; the title and header lines skipped.

Pasted candump text: indented lines, the candump command line, ... where \
lines were cut, blank lines and #, // notes are skipped; a note after a \
complete frame (< response) is counted as annotated, never an error.

Vector BLF (binary, LOGG): plain or zlib containers, object headers v1 and \
v2, CAN and CAN FD messages, error frames.

pcap and pcapng (binary): SocketCAN (DLT 227), LINUX_SLL and LINUX_SLL2 \
link types, either byte order, micro- or nanosecond times; EtherCAT \
captures: CoE emergencies are the EMCYs of the slave's station address.

ASAM MDF 4 bus logging (MF4: CANedge, Vector, python-can): sorted and \
unsorted data groups, compressed (##DZ) blocks; an MDF 3 file is refused \
with a one-line error.";

// No `\` after the quote: it would eat the first line's indent.
const EXIT_STATUS: &str = "  0    success, also when the reader of stdout goes away (| head -1)
  1    the --fail-on condition was met; check found a regression; diff
       found a difference
  2    usage error, unreadable or missing input (also a part of a -r
       directory that cannot be listed), a directory without -r, unknown
       format, corrupt gzip, malformed lines with --strict, output that
       cannot be written (a full disk, also for --help); for baseline and
       check also an unreadable baseline or one of another version
  129  stopped by SIGHUP; what was read is still reported
  130  stopped by Ctrl-C (SIGINT); what was read is still reported
  143  stopped by SIGTERM; what was read is still reported

A second SIGINT, SIGTERM or SIGHUP while the report is being written ends \
the process at once with that signal's status and no more output. baseline \
and check stopped by a signal while reading write and compare nothing.

Errors are one line on stderr starting error:. A missing file does not \
stop the other files; the exit code is the worst of all inputs (2 over 1 \
over 0).";

#[cfg(test)]
mod tests {
    use super::*;

    fn text(page: &[u8]) -> String {
        String::from_utf8_lossy(page).into_owned()
    }

    #[test]
    fn every_subcommand_the_main_page_refers_to_is_a_page() {
        let root = built();
        let pages = pages(&root).unwrap();
        let names: Vec<&str> = pages.iter().map(|(n, _)| n.as_str()).collect();
        assert!(names.contains(&"emcy-decode-explain"), "{names:?}");
        assert!(names.contains(&"emcy-decode-check"), "{names:?}");
        let main = text(&pages[0].1);
        for name in &names[1..] {
            let roff_name = name.replace('-', "\\-");
            assert!(
                main.contains(&format!("{roff_name}(1)")),
                "{name} not referred to"
            );
        }
        // A subcommand page is titled by its own name and points back.
        let (_, check) = pages
            .iter()
            .find(|(n, _)| n == "emcy-decode-check")
            .unwrap();
        let check = text(check);
        assert!(check.contains("\n.TH emcy-decode-check 1"), "{check}");
        assert!(check.contains("emcy\\-decode(1)"));
        assert!(
            check.contains("at least one regression"),
            "check's exit codes"
        );
    }

    #[test]
    fn the_main_page_has_the_formats_and_exit_codes_and_no_readme_pointer() {
        let main = text(&render(&built(), true).unwrap());
        for heading in [
            ".SH FORMATS",
            ".SH \"EXIT STATUS\"",
            ".SH EXAMPLES",
            ".SH ENVIRONMENT",
        ] {
            assert!(main.contains(heading), "{heading}");
        }
        assert!(main.contains("PEAK TRC") && main.contains("MDF 4"));
        assert!(main.contains("143"));
        for variable in ["NO_COLOR", "TERM", "COLUMNS", "CI", "TZ"] {
            assert!(
                main.contains(&format!("\n{variable} ")),
                "ENVIRONMENT lacks {variable}"
            );
        }
        assert!(!main.contains("README"), "the README is not installed");
        assert!(!main.contains(".SH EXTRA"));
    }
}
