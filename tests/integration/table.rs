//! The table at a terminal fits its width (`--width`, as a terminal's width
//! is given); in a pipe it keeps its full lines whatever `COLUMNS` says.
//! What repeats on every frame of a node is said once.

use unicode_width::UnicodeWidthStr;

use crate::support::emcy_decode;

/// Fixtures with long descriptions, warnings, profiles' readings, NMT and
/// several nodes or channels.
const FIXTURES: [&str; 6] = [
    "fixtures/s300.log",
    "fixtures/stoeber.log",
    "fixtures/festo.log",
    "fixtures/commissioning.log",
    "fixtures/cia402-commissioning.log",
    "fixtures/mixed.pcapng",
];

fn table(args: &[&str]) -> String {
    let out = emcy_decode().args(args).output().unwrap();
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The event rows (not the lines under an event, nor a date line), as
/// node and code (or NMT tag): what a reader scans the table for.
fn event_rows(table: &str) -> Vec<(String, String)> {
    table
        .lines()
        .skip_while(|l| !l.starts_with("TIME"))
        .skip(1)
        .take_while(|l| !l.is_empty() && !l.starts_with("TR =") && !l.starts_with("no EMCY"))
        .filter(|l| !l.starts_with(' ') && !is_date(l))
        .map(|l| {
            let cols: Vec<&str> = l.split_whitespace().collect();
            (cols[2].to_string(), cols[3].to_string())
        })
        .collect()
}

fn is_date(line: &str) -> bool {
    line.len() == 10 && line.as_bytes()[4] == b'-' && line.as_bytes()[7] == b'-'
}

#[test]
fn no_line_is_wider_than_the_terminal() {
    for fixture in FIXTURES {
        for width in [80, 120, 200] {
            let text = table(&["--width", &width.to_string(), fixture]);
            for line in text.lines() {
                assert!(
                    line.width() <= width,
                    "{fixture} at {width}: {} columns: {line}",
                    line.width()
                );
            }
            let summary = table(&["--width", &width.to_string(), "--view", "summary", fixture]);
            for line in summary.lines() {
                assert!(
                    line.width() <= width,
                    "{fixture} summary at {width}: {line}"
                );
            }
        }
    }
}

#[test]
fn every_event_is_one_row_from_120_columns() {
    for fixture in FIXTURES {
        let full = table(&[fixture]);
        let rows = event_rows(&full);
        assert!(!rows.is_empty(), "{fixture}: no event rows read");
        // Full lines are wider than 120 on these fixtures: the fit is tested.
        assert!(full.lines().any(|l| l.width() > 120), "{fixture}");
        for width in ["120", "200"] {
            let fitted = table(&["--width", width, fixture]);
            assert_eq!(event_rows(&fitted), rows, "{fixture} at {width}");
            // Nothing under the event rows but its details, indented.
            let events = fitted.lines().skip(2).take_while(|l| !l.is_empty());
            for line in events.filter(|l| !l.starts_with(' ') && !l.starts_with("TR =")) {
                assert!(
                    line.contains("  "),
                    "{fixture} at {width}: a wrapped row: {line}"
                );
            }
        }
        // At 80 a row can lose columns, never an event.
        let narrow = table(&["--width", "80", fixture]);
        assert_eq!(event_rows(&narrow).len(), rows.len(), "{fixture} at 80");
    }
}

#[test]
fn narrow_terminals_lose_columns_in_order() {
    let at = |w: &str| table(&["--width", w, "fixtures/s300.log"]);
    let header = |t: &str| t.lines().nth(1).unwrap().to_string();
    assert_eq!(
        header(&at("200")).split_whitespace().collect::<Vec<_>>(),
        [
            "TIME",
            "CHANNEL",
            "NODE",
            "CODE",
            "TR",
            "REGISTER",
            "MANUFACTURER",
            "DESCRIPTION"
        ]
    );
    assert_eq!(
        header(&at("120")).split_whitespace().collect::<Vec<_>>(),
        [
            "TIME",
            "CHANNEL",
            "NODE",
            "CODE",
            "TR",
            "REG",
            "DESCRIPTION"
        ]
    );
    let narrow = at("80");
    assert_eq!(
        header(&narrow).split_whitespace().collect::<Vec<_>>(),
        ["TIME", "CHANNEL", "NODE", "CODE", "DESCRIPTION"]
    );
    // The date goes to a line of its own, once; rows show the time of day.
    assert_eq!(narrow.lines().filter(|l| *l == "2023-11-14").count(), 1);
    assert!(narrow.contains("\n22:13:21.250000Z  can0        1  0x4310  F06 motor temperature"));
    // The legend of a dropped column is not said.
    assert!(!narrow.contains("TR = transition"));
    assert!(at("120").contains("TR = transition"));
}

#[test]
fn a_pipe_keeps_full_lines_whatever_columns_says() {
    let full = table(&["fixtures/s300.log"]);
    let with_columns = emcy_decode()
        .env("COLUMNS", "80")
        .arg("fixtures/s300.log")
        .output()
        .unwrap();
    assert_eq!(String::from_utf8(with_columns.stdout).unwrap(), full);
    assert_eq!(table(&["--width", "0", "fixtures/s300.log"]), full);
    assert!(full.lines().any(|l| l.width() > 200));
}

/// A node whose frames all lack the generic bit (no profile says it never
/// sets it), with a reset that cleared nothing in between: the form of its
/// frames is said once, what the state machine says of one frame each time.
#[test]
fn a_warning_about_a_nodes_frames_is_said_once_per_node_then_counted() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("repeats.log");
    let mut trace = String::new();
    for (i, node) in [5, 5, 6, 5, 6, 5].iter().enumerate() {
        trace.push_str(&format!(
            "({}.000000) can0 08{node}#1043080000000000\n",
            i + 1
        ));
    }
    trace.push_str("(9.000000) can0 085#0000000000000000\n");
    trace.push_str("(10.000000) can0 085#0000000000000000\n");
    std::fs::write(&path, trace).unwrap();
    let path = path.to_str().unwrap();
    let text = table(&[path]);
    let said: Vec<&str> = text
        .lines()
        .filter(|l| l.trim_start().starts_with("warning: no_generic_bit"))
        .collect();
    assert_eq!(said.len(), 2, "once for node 5, once for node 6:\n{text}");
    assert_eq!(
        text.lines()
            .filter(|l| l
                .trim_start()
                .starts_with("warning: reset_while_error_free"))
            .count(),
        1,
        "{text}"
    );
    let repeats: Vec<Vec<&str>> = text
        .lines()
        .skip_while(|l| !l.starts_with("Repeated warnings"))
        .skip(2)
        .take_while(|l| !l.is_empty())
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(
        repeats,
        [
            ["can0", "5", "no_generic_bit", "4"],
            ["can0", "6", "no_generic_bit", "2"]
        ]
    );
    // The machine outputs keep every warning on its event.
    let events = crate::support::ndjson([path]);
    let no_generic = events
        .iter()
        .filter(|e| e["type"] == "emcy")
        .filter(|e| {
            e["warnings"].as_array().is_some_and(|w| {
                w.iter()
                    .any(|w| w.as_str().is_some_and(|w| w.starts_with("no_generic_bit:")))
            })
        })
        .count();
    assert_eq!(no_generic, 6);
}

#[test]
fn a_reset_with_zero_bytes_says_no_category() {
    let text = table(&["fixtures/s300.log"]);
    assert!(!text.contains("category: 0"), "{text}");
    // A reading that says something stays (STÖBER's E82 "no error").
    assert!(table(&["fixtures/stoeber.log"]).contains("event_text: no error"));
}

#[test]
fn the_summary_names_each_code_by_the_nodes_profile() {
    let text = table(&[
        "--view",
        "summary",
        "fixtures/s300.log",
        "fixtures/festo.log",
    ]);
    let rows: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("can0 ") && l.contains("0x4310"))
        .filter(|l| !l.contains(" x1"))
        .collect();
    // The same code, each node's profile's words for it.
    assert_eq!(rows.len(), 2, "{text}");
    assert!(
        rows[0].ends_with("1  0x4310      1  F06 motor temperature (AKD: F235)"),
        "{}",
        rows[0]
    );
    assert!(
        rows[1].ends_with("5  0x4310      1  Temperature · drive · excess temperature drive"),
        "{}",
        rows[1]
    );
    // No events in the summary.
    assert!(!text.contains("TIME "));
}

/// The lines of a section of the end tables: its title line (which may
/// carry the day) up to the blank line after it.
fn section<'t>(table: &'t str, title: &str) -> Vec<&'t str> {
    let mut lines = table.lines().skip_while(|l| !l.starts_with(title));
    let mut out: Vec<&str> = lines.next().into_iter().collect();
    out.extend(lines.take_while(|l| !l.is_empty()));
    out
}

#[test]
fn end_tables_keep_status_units_and_one_date_at_80_and_120_columns() {
    // Several nodes, outages (one still open at the end), guarding, an
    // error history, errors and a drive.
    for width in ["80", "120"] {
        let text = table(&[
            "--width",
            width,
            "fixtures/commissioning.log",
            "fixtures/cia402-commissioning.log",
        ]);
        let health = section(&text, "Node health");
        // The day once, in the title; no row repeats it.
        assert_eq!(health[0], "Node health (2023-11-14)", "{width}");
        let row = |node: &str| {
            health
                .iter()
                .find(|l| l.split_whitespace().nth(1) == Some(node))
                .copied()
                .unwrap_or_else(|| panic!("{width}: no health row of node {node}:\n{text}"))
        };
        // The outcome before the settings: a cut cell keeps it.
        assert!(row("2").contains("lost 1x"), "{width}: {}", row("2"));
        assert!(row("3").contains("lost 1x, sile"), "{width}: {}", row("3"));
        assert!(row("4").contains("never lost, 1"), "{width}: {}", row("4"));
        if width == "120" {
            assert!(row("3").contains("lost 1x, silent at end"), "{}", row("3"));
            assert!(
                row("4").contains("never lost, 1 toggle error"),
                "{}",
                row("4")
            );
        }
        // The outage's duration is kept, its start shown without the date.
        assert!(row("2").contains("848 ms"), "{width}: {}", row("2"));
        for section_title in ["Nodes", "Node health", "Error timeline"] {
            for line in section(&text, section_title).iter().skip(1) {
                assert!(
                    !line.contains("2023-11-14T"),
                    "{width} {section_title}: a date on a row: {line}"
                );
            }
        }
        let timeline = section(&text, "Error timeline");
        assert_eq!(timeline[0], "Error timeline (2023-11-14)");
        assert!(
            timeline.iter().any(|l| l.contains("22:13:20.800000Z")),
            "{width}: {timeline:?}"
        );
        // Durations carry their unit.
        assert!(
            timeline.iter().any(|l| l.contains(" 100 ms")),
            "{width}: {timeline:?}"
        );
        let nodes = section(&text, "Nodes");
        assert!(
            nodes.iter().any(|l| l.contains("0x3120 x1")),
            "{width}: {nodes:?}"
        );
        for line in text.lines() {
            assert!(line.width() <= width.parse().unwrap(), "{width}: {line}");
        }
    }
    // A column that is `-` in every row is left out: the drive's trace
    // has no error history.
    let drive = table(&["--width", "120", "fixtures/cia402-commissioning.log"]);
    let health = section(&drive, "Node health");
    assert!(!health[1].contains("ERROR HISTORY"), "{health:?}");
    assert!(!health[1].contains("OUTAGES"), "{health:?}");
    assert!(section(&drive, "Nodes")[1].contains("IN ERROR"));
    assert!(
        section(&drive, "Nodes")
            .iter()
            .any(|l| l.contains("211 ms")),
        "{drive}"
    );
}
