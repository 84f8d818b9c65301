//! The README and the guide (docs/guide/) are true: every option of every
//! command's `--help` is in their option tables, every example command in
//! their `sh` blocks runs on the repository's fixtures, every jq recipe
//! prints something, and the README's first example output is what the
//! binary prints.

use std::path::{Path, PathBuf};

use crate::support::emcy_decode;

fn readme() -> String {
    std::fs::read_to_string("README.md").expect("README.md")
}

/// The README and every page of the guide, one after another: the manual
/// that the README's front door leads to is held to the same checks.
fn readme_and_guide() -> String {
    crate::support::documentation()
        .iter()
        .map(|path| std::fs::read_to_string(path).expect("documentation page"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The bodies of the README's fenced blocks of `lang`, each as its lines.
fn blocks(text: &str, lang: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut current: Option<Vec<String>> = None;
    let mut skipping = false;
    for line in text.lines() {
        // A fence of another language opens a block this skips.
        if skipping {
            skipping = !line.starts_with("```");
            continue;
        }
        match (&mut current, line.strip_prefix("```")) {
            (None, Some(info)) if info.trim() == lang => current = Some(Vec::new()),
            (None, Some(_)) => skipping = true,
            (Some(_), Some("")) => out.extend(current.take()),
            (Some(body), _) => body.push(line.to_string()),
            (None, None) => {}
        }
    }
    out
}

/// `--long` names of a command's options, from its `--help`.
fn options(subcommand: Option<&str>) -> Vec<String> {
    let mut cmd = emcy_decode();
    cmd.args(subcommand).arg("--help");
    let out = cmd.output().expect("runs");
    assert_eq!(out.status.code(), Some(0), "{subcommand:?} --help");
    let help = String::from_utf8(out.stdout).expect("UTF-8");
    help.lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l
                .strip_prefix('-')
                .filter(|_| !l.starts_with("--"))
                .map_or(l, |s| s.get(1..).unwrap_or("").trim_start_matches(", "));
            let name = l.strip_prefix("--")?;
            let end = name.find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'));
            Some(format!("--{}", &name[..end.unwrap_or(name.len())]))
        })
        .filter(|o| o != "--help" && o != "--version")
        .collect()
}

#[test]
fn every_option_of_every_command_is_in_the_readme_option_tables() {
    let text = readme_and_guide();
    let rows: Vec<&str> = text.lines().filter(|l| l.starts_with("| `")).collect();
    let mut missing = Vec::new();
    for sub in [
        None,
        Some("explain"),
        Some("profiles"),
        Some("baseline"),
        Some("check"),
        Some("diff"),
        Some("config"),
        Some("man"),
    ] {
        let opts = options(sub);
        assert!(
            !opts.is_empty() || sub == Some("man"),
            "{sub:?}: no options parsed"
        );
        for opt in opts {
            // A row names the option as `--opt` or in a list `--a`, `--opt`.
            let named = rows.iter().any(|r| {
                let cell = r.split(" | ").next().unwrap_or("");
                cell.match_indices(opt.as_str()).any(|(i, _)| {
                    !cell[i + opt.len()..]
                        .starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-')
                })
            });
            if !named {
                missing.push(format!("{} {opt}", sub.unwrap_or("emcy-decode")));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "not in an option table of the README or the guide: {missing:?}"
    );
}

/// A directory where the README's paths exist: `fixtures/` is the
/// repository's, `traces/` the baseline fixtures (the CI example's).
fn workdir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    std::os::unix::fs::symlink(repo.join("fixtures"), dir.path().join("fixtures")).unwrap();
    std::os::unix::fs::symlink(repo.join("fixtures/baseline"), dir.path().join("traces")).unwrap();
    dir
}

/// Runs `line` with bash (pipefail: a failing emcy-decode is not hidden by
/// jq), the binary under test first on PATH.
fn bash(dir: &Path, line: &str) -> std::process::Output {
    let bin = assert_cmd::cargo::cargo_bin("emcy-decode");
    let bin_dir = bin.parent().expect("binary dir");
    let path = std::env::join_paths(std::iter::once(bin_dir.to_path_buf()).chain(
        std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()),
    ))
    .expect("PATH");
    std::process::Command::new("bash")
        .args(["-o", "pipefail", "-c", line])
        .current_dir(dir)
        .env("PATH", path)
        .env("HOME", dir)
        .env_remove("NO_COLOR")
        .env_remove("COLUMNS")
        .env_remove("CI")
        .stdin(std::process::Stdio::null())
        .output()
        .expect("bash runs")
}

/// Example commands that cannot run here, and why.
fn needs_more_than_fixtures(line: &str) -> bool {
    // A bus (candump, tcpdump), a file still being written (--follow waits
    // for more), the build or the fuzzer.
    // `mkdir -p` runs: HOME is the work directory, where the completions
    // example must make the directories it writes into.
    !(line.starts_with("emcy-decode ") || line.starts_with("mkdir -p "))
        || line.contains("--follow")
}

#[test]
fn every_example_command_runs_on_the_fixtures() {
    let text = readme_and_guide();
    let dir = workdir();
    let mut ran = 0;
    for block in blocks(&text, "sh") {
        for line in block {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') || needs_more_than_fixtures(line) {
                continue;
            }
            let out = bash(dir.path(), line);
            assert!(
                matches!(out.status.code(), Some(0 | 1)),
                "`{line}` exits {:?}:\n{}",
                out.status.code(),
                String::from_utf8_lossy(&out.stderr)
            );
            // Exit 1 is a met `--fail-on` or a `check` regression, but a
            // shell that cannot open a redirection's file exits 1 too: a
            // line that writes a file must succeed.
            assert!(
                !line.contains("> ") || out.status.code() == Some(0),
                "`{line}` exits {:?}:\n{}",
                out.status.code(),
                String::from_utf8_lossy(&out.stderr)
            );
            // A recipe that prints nothing on the fixture it names teaches
            // nothing: the reader cannot tell a wrong filter from no match.
            assert!(
                !line.contains("| jq") || !out.stdout.is_empty(),
                "`{line}` prints nothing"
            );
            ran += 1;
        }
    }
    assert!(ran >= 10, "only {ran} example commands found");
}

#[test]
fn the_first_example_output_is_what_the_binary_prints() {
    let text = readme();
    let shown = blocks(&text, "text")
        .into_iter()
        .next()
        .expect("a text block");
    assert_eq!(
        shown.first().map(String::as_str),
        Some("== fixtures/s300.log")
    );
    let out = emcy_decode().arg("fixtures/s300.log").output().unwrap();
    let real = String::from_utf8(out.stdout).unwrap();
    let real: Vec<&str> = real.lines().map(str::trim_end).collect();
    // `...` abridges: each run of lines between them is a run of the
    // real output, in order.
    let mut from = 0;
    for run in shown.split(|l| l.trim() == "...") {
        if run.is_empty() {
            continue;
        }
        let run: Vec<&str> = run.iter().map(|l| l.trim_end()).collect();
        let at = (from..=real.len().saturating_sub(run.len()))
            .find(|&i| real.get(i..i + run.len()) == Some(&run[..]));
        let Some(at) = at else {
            panic!(
                "README lines not in the output (in order):\n{}\n\noutput:\n{}",
                run.join("\n"),
                real.join("\n")
            );
        };
        from = at + run.len();
    }
}

/// The README's test command is the one CI runs: a new user who runs it
/// builds against the same Cargo.lock versions the CI tested.
#[test]
fn the_readme_test_command_is_the_one_ci_runs() {
    let text = readme();
    let commands: Vec<String> = blocks(&text, "sh")
        .into_iter()
        .flatten()
        .filter(|l| l.starts_with("cargo test"))
        .collect();
    assert!(!commands.is_empty(), "no `cargo test` in the README");
    let ci = std::fs::read_to_string(".ci/run").expect(".ci/run");
    for command in commands {
        assert!(
            ci.lines().any(|l| l.trim() == command.trim()),
            "`{command}` is not a line of .ci/run"
        );
    }
    for line in [
        "cargo fmt --check",
        "cargo clippy --all-targets -- -D warnings",
    ] {
        assert!(
            ci.lines().any(|l| l.trim() == line),
            ".ci/run lacks `{line}`"
        );
    }
}

/// Every install line installs from the lock file: without `--locked`,
/// `cargo install` resolves the newest compatible versions, which no test
/// ran with.
#[test]
fn every_install_line_uses_the_lock_file() {
    let mut docs = vec![
        PathBuf::from("docs/fleet.md"),
        PathBuf::from("CONTRIBUTING.md"),
    ];
    docs.extend(crate::support::documentation());
    for doc in docs {
        let text = std::fs::read_to_string(&doc).expect("doc");
        for (i, line) in text.lines().enumerate() {
            assert!(
                !line.contains("cargo install --path"),
                "{}:{}: `cargo install` without --locked: {line}",
                doc.display(),
                i + 1
            );
        }
    }
}

/// GitHub's anchor of a heading: lower case, punctuation other than `-`
/// and `_` dropped, spaces as `-`.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The text of a Markdown file outside its fenced code blocks.
fn prose(text: &str) -> Vec<&str> {
    let mut fenced = false;
    text.lines()
        .filter(|l| {
            if l.starts_with("```") {
                fenced = !fenced;
                return false;
            }
            !fenced
        })
        .collect()
}

/// Every relative link of the README, the guide and the contributor
/// documents reaches a file, and a `#fragment` a heading of it: the manual
/// is split over pages, and a section that moves must take its links along.
#[test]
fn every_link_between_the_documents_resolves() {
    let mut docs = crate::support::documentation();
    docs.extend(
        [
            "ARCHITECTURE.md",
            "CONTRIBUTING.md",
            "docs/fleet.md",
            "docs/performance.md",
        ]
        .map(PathBuf::from),
    );
    let mut broken = Vec::new();
    let mut checked = 0;
    for doc in &docs {
        let text = std::fs::read_to_string(doc).expect("document");
        let dir = doc.parent().expect("a directory");
        for line in prose(&text) {
            for (at, _) in line.match_indices("](") {
                let rest = &line[at + 2..];
                let Some(end) = rest.find(')') else { continue };
                let target = &rest[..end];
                if target.contains("://") || target.starts_with("mailto:") {
                    continue;
                }
                let (path, fragment) = target.split_once('#').unwrap_or((target, ""));
                let file = if path.is_empty() {
                    doc.clone()
                } else {
                    dir.join(path)
                };
                checked += 1;
                if !file.exists() {
                    broken.push(format!("{}: {target}: no such file", doc.display()));
                    continue;
                }
                if fragment.is_empty() || file.extension().is_none_or(|e| e != "md") {
                    continue;
                }
                let page = std::fs::read_to_string(&file).expect("linked page");
                let known = prose(&page)
                    .into_iter()
                    .filter_map(|l| {
                        l.trim_start_matches('#')
                            .strip_prefix(' ')
                            .filter(|_| l.starts_with('#'))
                    })
                    .any(|h| anchor(h) == fragment);
                if !known {
                    broken.push(format!("{}: {target}: no such heading", doc.display()));
                }
            }
        }
    }
    assert!(checked >= 20, "only {checked} links found");
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}
