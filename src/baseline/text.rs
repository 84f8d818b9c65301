//! `check`'s output: one line per finding and a summary line, or JSON.

use anyhow::Result;

use super::compare::{Diff, Finding, Severity};
use crate::text::{is_xml_char, printable};

/// The word a finding's line starts with.
fn severity_word(f: &Finding) -> &'static str {
    match (f.severity, f.allowed) {
        (Severity::Regression, true) => "allowed",
        (Severity::Regression, false) => "regression",
        (Severity::Improvement, _) => "improvement",
        (Severity::Change, _) => "change",
    }
}

fn plural(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// One trace in a JUnit report of traces that were not all read.
#[derive(Clone, Debug, PartialEq)]
pub struct JunitCase {
    pub trace: String,
    /// Seconds spent reading it.
    pub seconds: f64,
    /// Why it could not be read; `None` for a trace that was read.
    pub error: Option<String>,
}

impl JunitCase {
    pub fn unread(trace: String, error: String, seconds: f64) -> JunitCase {
        JunitCase {
            trace,
            seconds,
            error: Some(error),
        }
    }
}

/// A JUnit report for a check that compared nothing because a trace could
/// not be read: that trace is a case with an `<error>`, the traces read are
/// skipped cases (nothing was compared), so the CI report still parses and
/// says what went wrong.
pub fn junit_unread(traces: &[JunitCase]) -> String {
    let mut cases = String::new();
    let mut errors = 0;
    for case in traces {
        cases.push_str(&format!(
            "    <testcase classname=\"emcy-decode.check\" name=\"{}\" time=\"{:.3}\">\n",
            xml(&printable(&case.trace)),
            case.seconds
        ));
        match &case.error {
            Some(why) => {
                errors += 1;
                let line = format!("{}: {}", printable(&case.trace), why);
                cases.push_str(&format!(
                    "      <error message=\"{}\" type=\"unreadable\">{}</error>\n",
                    xml(&line),
                    xml(&line)
                ));
            }
            None => cases.push_str(
                "      <skipped message=\"nothing compared: another trace could not be read\"/>\n",
            ),
        }
        cases.push_str("    </testcase>\n");
    }
    let total = traces.iter().map(|c| c.seconds).sum();
    let skipped = traces.len() as u64 - errors;
    let counts = Counts {
        tests: traces.len() as u64,
        failures: 0,
        errors,
        skipped,
    };
    junit_document(counts, total, &cases)
}

/// A JUnit suite's counts of cases.
struct Counts {
    tests: u64,
    failures: u64,
    errors: u64,
    skipped: u64,
}

/// The JUnit envelope around `cases`: one suite, its counts and seconds.
fn junit_document(counts: Counts, seconds: f64, cases: &str) -> String {
    let Counts {
        tests,
        failures,
        errors,
        skipped,
    } = counts;
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
         <testsuites name=\"emcy-decode check\" tests=\"{tests}\" failures=\"{failures}\" \
         errors=\"{errors}\" time=\"{seconds:.3}\">\n  \
         <testsuite name=\"emcy-decode check\" tests=\"{tests}\" failures=\"{failures}\" \
         errors=\"{errors}\" skipped=\"{skipped}\" time=\"{seconds:.3}\">\n{cases}  </testsuite>\n\
         </testsuites>\n"
    )
}

impl Diff {
    /// One line per finding, `SEVERITY: FILE[ CHANNEL node N]: MESSAGE`,
    /// sorted by file, channel, node and code; then the summary line.
    pub fn text(&self) -> String {
        let mut out = String::new();
        for f in &self.findings {
            out.push_str(severity_word(f));
            out.push_str(": ");
            out.push_str(&printable(&f.file));
            if let (Some(channel), Some(node)) = (&f.channel, f.node) {
                out.push(' ');
                out.push_str(&printable(channel));
                out.push_str(&format!(" node {node}"));
            }
            out.push_str(": ");
            out.push_str(&printable(&f.message));
            out.push('\n');
        }
        let s = &self.summary;
        let allowed = if s.allowed > 0 {
            format!(" ({} allowed)", s.allowed)
        } else {
            String::new()
        };
        out.push_str(&format!(
            "check: {}{allowed}, {}, {}; {} of {} matched\n",
            plural(s.regressions, "regression", "regressions"),
            plural(s.improvements, "improvement", "improvements"),
            plural(s.changes, "change", "changes"),
            s.matched,
            plural(s.traces, "trace", "traces"),
        ));
        out
    }

    /// `{"findings": [...], "summary": {...}}`, pretty, one trailing newline.
    pub fn json(&self) -> Result<String> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        Ok(text)
    }
}

/// `&`, `<`, `>`, `"` and `'` as XML entities; characters XML 1.0 cannot
/// hold (controls other than tab and line feed) as U+FFFD.
fn xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' | '\n' => out.push(c),
            c if c.is_control() || !is_xml_char(c) => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

/// A GitHub Actions workflow command's message: `%`, CR and LF escaped.
fn github_data(text: &str) -> String {
    text.replace('%', "%25")
        .replace('\r', "%0D")
        .replace('\n', "%0A")
}

/// ... and a property value: also `:` and `,`.
fn github_property(text: &str) -> String {
    github_data(text).replace(':', "%3A").replace(',', "%2C")
}

impl Diff {
    /// A finding's line without its severity: `FILE[ CHANNEL node N]: MESSAGE`.
    fn place_and_message(f: &Finding) -> String {
        let mut out = printable(&f.file).into_owned();
        if let (Some(channel), Some(node)) = (&f.channel, f.node) {
            out.push_str(&format!(" {} node {node}", printable(channel)));
        }
        out.push_str(": ");
        out.push_str(&printable(&f.message));
        out
    }

    /// JUnit XML as GitLab, Jenkins and GitHub test reporters read it: one
    /// test suite for the run, one test case per trace (`traces`: every
    /// trace given or in the baseline), a `<failure>` per regression with
    /// its line of text; a trace whose regressions were all allowed passes,
    /// its allowed regressions, improvements and changes in `<system-out>`.
    pub fn junit<'t>(
        &self,
        traces: impl IntoIterator<Item = &'t str>,
        seconds: impl Fn(&str) -> Option<f64>,
    ) -> String {
        let mut cases = String::new();
        let (mut tests, mut failures) = (0u64, 0u64);
        let mut total = 0.0;
        for trace in traces {
            tests += 1;
            // A trace only the baseline names was not read: no time spent.
            let time = seconds(trace).unwrap_or(0.0);
            total += time;
            let mine: Vec<_> = self.findings.iter().filter(|f| f.file == trace).collect();
            let failed: Vec<_> = mine
                .iter()
                .filter(|f| f.severity == Severity::Regression && !f.allowed)
                .collect();
            if !failed.is_empty() {
                failures += 1;
            }
            cases.push_str(&format!(
                "    <testcase classname=\"emcy-decode.check\" name=\"{}\" time=\"{time:.3}\">\n",
                xml(&printable(trace))
            ));
            for f in &failed {
                let line = format!("regression: {}", Self::place_and_message(f));
                let kind = serde_json::to_value(f.kind)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_default();
                cases.push_str(&format!(
                    "      <failure message=\"{}\" type=\"{kind}\">{}</failure>\n",
                    xml(&line),
                    xml(&line)
                ));
            }
            let notes: Vec<String> = mine
                .iter()
                .filter(|f| f.severity != Severity::Regression || f.allowed)
                .map(|f| format!("{}: {}", severity_word(f), Self::place_and_message(f)))
                .collect();
            if !notes.is_empty() {
                cases.push_str(&format!(
                    "      <system-out>{}</system-out>\n",
                    xml(&notes.join("\n"))
                ));
            }
            cases.push_str("    </testcase>\n");
        }
        let counts = Counts {
            tests,
            failures,
            errors: 0,
            skipped: 0,
        };
        junit_document(counts, total, &cases)
    }

    /// GitHub Actions workflow commands: `::error` per regression (on its
    /// trace file), `::notice` per allowed regression, then the summary
    /// line as plain text.
    pub fn github(&self) -> String {
        let mut out = String::new();
        for f in &self.findings {
            let level = match (f.severity, f.allowed) {
                (Severity::Regression, false) => "error",
                (Severity::Regression, true) => "notice",
                _ => continue,
            };
            let title = if f.allowed {
                "emcy-decode check: allowed regression"
            } else {
                "emcy-decode check: regression"
            };
            out.push_str(&format!(
                "::{level} file={},title={}::{}\n",
                github_property(&printable(&f.file)),
                github_property(title),
                github_data(&Self::place_and_message(f))
            ));
        }
        let text = self.text();
        if let Some(summary) = text.lines().last() {
            out.push_str(summary);
            out.push('\n');
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_escapes_markup_and_replaces_what_xml_cannot_hold() {
        assert_eq!(xml("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&apos;");
        assert_eq!(xml("tab\tline\nbell\u{7}"), "tab\tline\nbell\u{FFFD}");
        assert!(roxmltree::Document::parse(&format!("<a>{}</a>", xml("\u{0}\u{1B}x"))).is_ok());
    }

    #[test]
    fn an_unread_check_is_a_suite_of_errors_and_skipped_cases() {
        let cases = [
            JunitCase::unread("a<1>.log".into(), "No such file".into(), 0.25),
            JunitCase {
                trace: "b.log".into(),
                seconds: 1.5,
                error: None,
            },
        ];
        let text = junit_unread(&cases);
        let doc = roxmltree::Document::parse(&text).expect("well-formed");
        let suite = doc
            .descendants()
            .find(|n| n.has_tag_name("testsuite"))
            .unwrap();
        let counts =
            ["tests", "failures", "errors", "skipped", "time"].map(|a| suite.attribute(a).unwrap());
        assert_eq!(counts, ["2", "0", "1", "1", "1.750"]);
        let error = doc.descendants().find(|n| n.has_tag_name("error")).unwrap();
        assert_eq!(error.attribute("message"), Some("a<1>.log: No such file"));
        assert_eq!(error.parent().unwrap().attribute("time"), Some("0.250"));
    }

    #[test]
    fn github_commands_escape_their_separators() {
        assert_eq!(github_data("50% a\r\nb"), "50%25 a%0D%0Ab");
        assert_eq!(github_property("a:b,c%"), "a%3Ab%2Cc%25");
    }
}
