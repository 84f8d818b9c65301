//! `emcy-decode config TRACE`: the configuration the trace wrote into its
//! nodes, per node, as a DCF-style INI file or JSON, on stdout or into a
//! directory. The model and its rendering are library code
//! ([`emcy_decode::config`]); this file reads the trace and writes the
//! files, never over one it did not write.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};

use super::baseline::write_file;
use super::cli::{ConfigArgs, ConfigFormat};
use super::diff::read_whole;
use super::{EXIT_ERROR, EXIT_OK, error_line, signals, write_stdout};
use emcy_decode::analyze::DiagnosticLog;
use emcy_decode::canopen::NodeId;
use emcy_decode::canopen::dcf::Dcf;
use emcy_decode::config::render::{self, HEADER};
use emcy_decode::config::{Configuration, Recorder};

pub(super) fn run(args: &ConfigArgs) -> Result<ExitCode> {
    let opts = args.reading.options()?;
    let mut log = DiagnosticLog::new(io::stderr());
    let caught = signals::catch(&opts.cancel);
    let mut recorder = Recorder::new(&args.node);
    let whole = read_whole(&args.trace, &opts, &mut log, &mut recorder)?;
    if let Some(stop) = caught.stopped() {
        log.error(&format!("stopped by {}; nothing written", stop.name));
        return Ok(ExitCode::from(stop.status));
    }
    if !whole {
        // Half a trace's configuration would pass for the whole one.
        return Ok(ExitCode::from(EXIT_ERROR));
    }
    let config = recorder.into_configuration();
    let dcfs: Vec<(NodeId, String, &Dcf)> = args
        .reading
        .drive
        .dcf
        .iter()
        .zip(&opts.dcf)
        .map(|((node, path), (_, dcf))| (*node, path.display().to_string(), dcf))
        .collect();
    if config.nodes.is_empty() {
        log.note(&format!(
            "{}: no SDO download{}: no configuration to write",
            config.file,
            if args.node.is_empty() {
                String::new()
            } else {
                " to the nodes asked for".to_string()
            }
        ));
    }
    if config.cut > 0 {
        log.note(&format!(
            "{}: {} writes past {} objects left out",
            config.file,
            config.cut,
            emcy_decode::config::MAX_OBJECTS
        ));
    }
    match (&args.output, args.format) {
        (None, ConfigFormat::Json) => write_stdout(&render::json(&config, &dcfs)),
        (None, ConfigFormat::Dcf) => {
            let files: Vec<String> = config
                .nodes
                .iter()
                .map(|(key, objects)| render::ini(&config, key, objects, dcf_of(&dcfs, key.node)))
                .collect();
            write_stdout(&files.join("\n"))
        }
        (Some(dir), format) => write_dir(dir, format, &config, &dcfs),
    }
}

/// The DCF given for `node`, with the name it was given by.
fn dcf_of<'a>(dcfs: &'a [(NodeId, String, &'a Dcf)], node: NodeId) -> Option<(&'a str, &'a Dcf)> {
    dcfs.iter()
        .find(|(n, _, _)| *n == node)
        .map(|(_, name, dcf)| (name.as_str(), *dcf))
}

/// One file per node (`node3.dcf`; `can1-node3.dcf` when the trace has
/// several channels), or `config.json`, in `dir` (made if missing). A
/// file already there is written over only if this command wrote it (its
/// first line says so); any other is left as it is, with an `error:` line
/// and exit 2, and the other files are still written.
fn write_dir(
    dir: &Path,
    format: ConfigFormat,
    config: &Configuration,
    dcfs: &[(NodeId, String, &Dcf)],
) -> Result<ExitCode> {
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut files: Vec<(PathBuf, String)> = Vec::new();
    match format {
        ConfigFormat::Json => files.push((dir.join("config.json"), render::json(config, dcfs))),
        ConfigFormat::Dcf => {
            let channels: std::collections::BTreeSet<&str> =
                config.nodes.keys().map(|k| k.channel.as_str()).collect();
            for (key, objects) in &config.nodes {
                let name = if channels.len() > 1 {
                    format!("{}-node{}.dcf", safe(&key.channel), key.node)
                } else {
                    format!("node{}.dcf", key.node)
                };
                let text = render::ini(config, key, objects, dcf_of(dcfs, key.node));
                files.push((dir.join(name), text));
            }
        }
    }
    let mut status = EXIT_OK;
    for (path, text) in files {
        if !ours(&path, format) {
            error_line(&format!(
                "{} exists and was not written by emcy-decode config: left as it is",
                path.display()
            ));
            status = EXIT_ERROR;
            continue;
        }
        match write_file(&path, &text) {
            Ok(()) => eprintln_ok(&format!("wrote {}", path.display())),
            Err(e) => {
                error_line(&format!("{e:#}"));
                status = EXIT_ERROR;
            }
        }
    }
    Ok(ExitCode::from(status))
}

/// A channel name as part of a file name: what is not a letter, a digit,
/// `-` or `_` becomes `_`.
fn safe(channel: &str) -> String {
    channel
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Whether `path` may be written: it does not exist, or this command wrote
/// it (a DCF's first line is [`HEADER`]; the JSON's first member says so).
fn ours(path: &Path, format: ConfigFormat) -> bool {
    let Ok(text) = fs::read(path) else {
        return !path.exists();
    };
    let text = String::from_utf8_lossy(&text);
    match format {
        ConfigFormat::Dcf => text.starts_with(HEADER),
        ConfigFormat::Json => text.contains(render::JSON_MARK),
    }
}

/// A line on stderr that may be lost (a closed stderr) without failing.
fn eprintln_ok(message: &str) {
    use std::io::Write;
    let _ = writeln!(io::stderr(), "{message}");
}
