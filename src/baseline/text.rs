//! `check`'s output: one line per finding and a summary line, or JSON.

use anyhow::Result;

use super::compare::{Diff, Severity};
use crate::text::printable;

fn plural(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

impl Diff {
    /// One line per finding, `SEVERITY: FILE[ CHANNEL node N]: MESSAGE`,
    /// sorted by file, channel, node and code; then the summary line.
    pub fn text(&self) -> String {
        let mut out = String::new();
        for f in &self.findings {
            let severity = match (f.severity, f.allowed) {
                (Severity::Regression, true) => "allowed",
                (Severity::Regression, false) => "regression",
                (Severity::Improvement, _) => "improvement",
                (Severity::Change, _) => "change",
            };
            out.push_str(severity);
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
