//! The timeline chart (`--format svg`, `--format html`): golden files for
//! every fixture, and what must hold for any trace: well-formed XML, one lane
//! per node, open errors marked, thousands of errors in a small file, no
//! network references, trace text escaped.
//!
//! Refresh the golden files after an intended change with
//! `UPDATE_GOLDEN=1 cargo test --test integration -- chart::` and look at
//! the diff (and at the picture: `scripts/screenshot.sh fixtures/s300.log`).

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use crate::support::emcy_decode;
use crate::support::golden::{self, check, fixtures};
use serde_json::Value;

fn render(format: &str, args: &[&Path]) -> String {
    render_with(format, &[], args)
}

/// [`render`] with `flags` before the inputs.
fn render_with(format: &str, flags: &[&str], args: &[&Path]) -> String {
    let out = emcy_decode()
        .args(["--format", format])
        .args(flags)
        .args(args)
        .output()
        .expect("runs");
    assert!(
        matches!(out.status.code(), Some(0..=2)),
        "exit status {:?}",
        out.status
    );
    String::from_utf8(out.stdout).expect("utf-8 output")
}

#[test]
fn every_fixture_as_svg_and_html_matches_its_golden_file() {
    let mut failures = Vec::new();
    for fixture in fixtures() {
        // The same flags as the other goldens (a profile, a DCF).
        let flags = crate::golden::scenario_flags(&fixture);
        for format in ["svg", "html"] {
            let out = render_with(format, flags, &[&fixture]);
            check(&golden::path(&fixture, format), &out, &mut failures);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// The README's example image is the chart of the s300 fixture, kept in step.
#[test]
fn readme_example_is_the_current_rendering() {
    let out = render("svg", &[Path::new("fixtures/s300.log")]);
    let mut failures = Vec::new();
    check(Path::new("docs/timeline-s300.svg"), &out, &mut failures);
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

fn parse(svg: &str) -> roxmltree::Document<'_> {
    roxmltree::Document::parse(svg).unwrap_or_else(|e| panic!("not well-formed XML: {e}\n{svg}"))
}

fn has_class(n: &roxmltree::Node<'_, '_>, class: &str) -> bool {
    n.attribute("class")
        .is_some_and(|c| c.split(' ').any(|c| c == class))
}

fn count(doc: &roxmltree::Document<'_>, tag: &str, class: &str) -> usize {
    doc.descendants()
        .filter(|n| n.has_tag_name(tag) && has_class(n, class))
        .count()
}

/// The SVG of an HTML page, for the XML checks.
fn inline_svg(html: &str) -> &str {
    let start = html.find("<svg").expect("page has an svg");
    let end = html[start..].find("</svg>").expect("svg ends") + start + "</svg>".len();
    &html[start..end]
}

fn node_objects(fixture: &Path) -> Vec<Value> {
    render("ndjson", &[fixture])
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).expect("JSON line"))
        .filter(|o| o["type"] == "node")
        .collect()
}

#[test]
fn every_fixture_gives_well_formed_svg_with_one_lane_per_node_and_marked_open_errors() {
    for fixture in fixtures() {
        let svg = render("svg", &[&fixture]);
        let doc = parse(&svg);
        let nodes = node_objects(&fixture);
        let lanes: Vec<String> = doc
            .descendants()
            .filter(|n| n.has_tag_name("g") && has_class(n, "lane"))
            .map(|n| n.attribute("data-lane").expect("lane key").to_string())
            .collect();
        let expected: Vec<String> = nodes
            .iter()
            .map(|n| format!("{}/{}", n["channel"].as_str().unwrap(), n["node"]))
            .collect();
        assert_eq!(lanes, expected, "{}: one lane per node", fixture.display());

        let errors: Vec<&Value> = nodes
            .iter()
            .flat_map(|n| n["errors"].as_array().unwrap())
            .collect();
        let open = errors.iter().filter(|e| e["end_line"].is_null()).count();
        let bars = count(&doc, "rect", "b") - count_legend(&doc);
        assert_eq!(bars, errors.len(), "{}: a bar per error", fixture.display());
        assert_eq!(
            count(&doc, "rect", "o") - usize::from(open > 0),
            open,
            "{}: open errors are drawn open (plus one legend swatch)",
            fixture.display()
        );
        assert_eq!(
            count(&doc, "path", "oe") - usize::from(open > 0),
            open,
            "{}: each open error ends in an open marker",
            fixture.display()
        );
        // Every bar says what it is.
        for bar in doc
            .descendants()
            .filter(|n| n.has_tag_name("rect") && has_class(n, "b"))
            .filter(|n| !n.ancestors().any(|a| has_class(&a, "legend")))
        {
            let title = bar
                .children()
                .find(|c| c.has_tag_name("title"))
                .and_then(|t| t.text())
                .expect("bar has a tooltip");
            for part in ["0x", "start: ", "end: ", "duration: ", "cleared by: "] {
                assert!(title.contains(part), "{title:?} lacks {part:?}");
            }
        }
    }
}

fn count_legend(doc: &roxmltree::Document<'_>) -> usize {
    doc.descendants()
        .filter(|n| n.has_tag_name("g") && has_class(n, "legend"))
        .flat_map(|g| g.descendants())
        .filter(|n| n.has_tag_name("rect") && has_class(n, "b"))
        .count()
}

#[test]
fn markers_show_resets_partial_resets_and_boot_ups() {
    let doc_text = render("svg", &[Path::new("fixtures/s300.log")]);
    let doc = parse(&doc_text);
    let lane_marks = |class: &str| {
        doc.descendants()
            .filter(|n| n.has_tag_name("g") && has_class(n, "mk") && has_class(n, class))
            .filter(|n| n.ancestors().any(|a| has_class(&a, "lane")))
            .count()
    };
    // s300: one reset to 0x00, two partial resets, two boot-ups.
    assert_eq!(lane_marks("reset"), 1);
    assert_eq!(lane_marks("partial"), 2);
    assert_eq!(lane_marks("boot"), 2);
    // Wall-clock ticks for candump times, the date in the title.
    assert!(doc_text.contains(">22:13:22</text>"), "{doc_text}");
    // The span ends with the last frame, a TPDO nobody decodes.
    assert!(doc_text.contains("2023-11-14 22:13:20.000000 – 22:13:27.100000 UTC"));
    // ASC times are seconds from measurement start.
    let asc = render("svg", &[Path::new("fixtures/s300.asc")]);
    assert!(
        asc.contains(">2</text>") && asc.contains("time (s)"),
        "{asc}"
    );
}

/// The bars' `<rect>`s in lanes (not the legend's swatches).
fn lane_bars<'a, 'i>(doc: &'a roxmltree::Document<'i>) -> Vec<roxmltree::Node<'a, 'i>> {
    doc.descendants()
        .filter(|n| n.has_tag_name("rect") && has_class(n, "b"))
        .filter(|n| n.ancestors().any(|a| has_class(&a, "lane")))
        .collect()
}

fn width_of(n: &roxmltree::Node<'_, '_>) -> f64 {
    n.attribute("width")
        .expect("width")
        .parse()
        .expect("number")
}

#[test]
fn wide_bars_carry_their_code_and_the_legend_lists_every_code() {
    let svg = render("svg", &[Path::new("fixtures/s300.log")]);
    let doc = parse(&svg);
    // Each label follows its bar, names the bar's code and fits in it (9 px
    // digits are about 5 px wide; 0.6 em per character is the estimate).
    let mut labelled = Vec::new();
    for bar in lane_bars(&doc) {
        let code = bar.attribute("data-c").expect("bar names its code");
        let label = bar
            .next_sibling_element()
            .filter(|n| n.has_tag_name("text") && has_class(n, "bl"));
        match label {
            Some(l) => {
                let text = l.text().expect("label text");
                assert!(code.contains(text), "label {text:?} of a {code} bar");
                let needed = text.chars().count() as f64 * 9.0 * 0.6 + 4.0;
                assert!(
                    width_of(&bar) >= needed,
                    "{text:?} in {} px",
                    width_of(&bar)
                );
                labelled.push(text.to_string());
            }
            None => assert!(
                width_of(&bar) < 4.0 * 9.0 * 0.6 + 4.0,
                "a {} px bar of {code} without a label",
                width_of(&bar)
            ),
        }
    }
    // s300: three wide errors, and 0x5111, open till the last frame 0.1 s
    // after it, in a bar wide enough for its short label.
    assert_eq!(labelled, ["0x4310", "0x3120", "0x4210", "5111"]);

    // The legend: every code the node raised, with its profile's text, in
    // its class's row; the two temperature codes share the class colour's
    // hue in two lightnesses.
    let legend: Vec<String> = doc
        .descendants()
        .filter(|n| n.has_tag_name("g") && has_class(n, "legend"))
        .flat_map(|g| g.descendants())
        .filter(|n| n.has_tag_name("text"))
        .filter_map(|n| n.text().map(str::to_string))
        .collect();
    let events: Vec<Value> = render("ndjson", &[Path::new("fixtures/s300.log")])
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).expect("JSON line"))
        .filter(|o| o["type"] == "emcy" && o["code"] != "0x0000")
        .collect();
    assert_eq!(events.len(), 4);
    for ev in &events {
        let entry = format!(
            "{} {}",
            ev["code"].as_str().unwrap(),
            ev["description"].as_str().unwrap()
        );
        assert!(legend.contains(&entry), "{entry:?} not in {legend:?}");
    }
    let heads: Vec<&str> = legend
        .iter()
        .filter(|t| t.ends_with(':'))
        .map(String::as_str)
        .collect();
    assert_eq!(heads, ["voltage:", "temperature:", "hardware:"]);
    let swatch = |code: &str| {
        doc.descendants()
            .filter(|n| n.has_tag_name("g") && n.parent().is_some_and(|p| has_class(&p, "legend")))
            .find(|g| {
                g.descendants().any(|t| {
                    t.has_tag_name("text") && t.text().is_some_and(|x| x.starts_with(code))
                })
            })
            .and_then(|g| g.descendants().find(|r| r.has_tag_name("rect")))
            .and_then(|r| r.attribute("class"))
            .unwrap_or_default()
            .to_string()
    };
    assert_eq!(swatch("0x4210"), "b c-temperature");
    assert_eq!(swatch("0x4310"), "b c-temperature k1");
    assert!(
        svg.contains(".ec .c-temperature.k1{fill:#"),
        "a rule for the shade"
    );
    // Bars wear their code's colour.
    let bar_4310 = lane_bars(&doc)
        .into_iter()
        .find(|b| b.attribute("data-c") == Some("0x4310"))
        .expect("a 0x4310 bar");
    assert_eq!(bar_4310.attribute("class"), Some("b c-temperature k1"));
}

/// A candump log in which node 5 raises and clears `n` errors (0.2 ms each,
/// one every 10 ms) and node 6 has a few long ones.
fn many_errors_trace(n: u64) -> String {
    let mut s = String::new();
    let t0 = 1_700_000_000u64;
    for i in 0..n {
        let us = i * 10_000;
        let codes = ["1043", "2023", "3031", "8181"];
        let code = codes[(i % 4) as usize];
        let _ = writeln!(
            s,
            "({}.{:06}) can0 085#{code}090000000000",
            t0 + us / 1_000_000,
            us % 1_000_000
        );
        let us = us + 200;
        let _ = writeln!(
            s,
            "({}.{:06}) can0 085#0000000000000000",
            t0 + us / 1_000_000,
            us % 1_000_000
        );
        if i % 2_000 == 0 {
            let _ = writeln!(
                s,
                "({}.{:06}) can0 086#{}",
                t0 + us / 1_000_000,
                us % 1_000_000,
                if i % 4_000 == 0 {
                    "1043090000000000"
                } else {
                    "0000000000000000"
                }
            );
        }
    }
    s
}

#[test]
fn ten_thousand_errors_stay_small_and_merged_bars_say_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let trace = dir.path().join("many.log");
    fs::write(&trace, many_errors_trace(10_000)).expect("write trace");
    let svg = render("svg", &[&trace]);
    let doc = parse(&svg);
    assert!(
        svg.len() < 150_000,
        "10 000 errors gave {} bytes of SVG",
        svg.len()
    );
    let merged: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("rect") && has_class(n, "m"))
        .filter(|n| !n.ancestors().any(|a| has_class(&a, "legend")))
        .filter_map(|n| n.children().find(|c| c.has_tag_name("title")))
        .filter_map(|t| t.text())
        .collect();
    assert!(!merged.is_empty(), "no merged bars");
    for title in &merged {
        assert!(title.contains("errors merged into one bar"), "{title}");
    }
    // Every error is in some bar: merged counts add up.
    let in_merged: u64 = merged
        .iter()
        .map(|t| t.split(' ').next().unwrap().parse::<u64>().unwrap())
        .sum();
    let single = doc
        .descendants()
        .filter(|n| n.has_tag_name("rect") && has_class(n, "b") && !has_class(n, "m"))
        .filter(|n| n.ancestors().any(|a| has_class(&a, "lane")))
        .count() as u64;
    assert_eq!(in_merged + single, 10_000 + 3);
    // Resets: 10 000 of them, drawn as far fewer merged markers.
    let resets = count(&doc, "g", "reset");
    assert!(resets < 1_000, "{resets} reset markers");

    let html = render("html", &[&trace]);
    // 20 005 events: past 10 000 the page carries every 2nd, past 20 000
    // every 4th, so 5 002 rows spread over the whole trace.
    assert!(html.len() < 3_000_000, "{} bytes of HTML", html.len());
    let rows = table_rows(&html);
    assert_eq!(rows.len(), 5_002);
    assert!(
        html.contains("lists every 4th event of this input (5002 of 20005)"),
        "the page says it is thinned"
    );
    assert!(html.contains("<table class=\"ev\" data-every=\"4th\">"));
    // The rows run from the first event to the last few: the list follows
    // a zoom anywhere in the trace.
    let lines: Vec<u64> = rows
        .iter()
        .map(|(_, cells)| cells[1].parse().expect("a line number"))
        .collect();
    assert_eq!(lines[0], 1);
    assert!(*lines.last().unwrap() > 19_990, "{:?}", lines.last());
    assert!(lines.windows(2).all(|w| w[0] < w[1]), "in order");
    let whole = render("html", &[Path::new("fixtures/s300.log")]);
    assert!(whole.contains("<table class=\"ev\">"));
    assert!(!whole.contains("lists every"));
}

#[test]
fn html_is_self_contained() {
    for fixture in fixtures() {
        let html = render("html", &[&fixture]);
        let without_xmlns = html.replace("xmlns=\"http://www.w3.org/2000/svg\"", "");
        assert!(
            !without_xmlns.contains("http:") && !without_xmlns.contains("https:"),
            "{}: network reference",
            fixture.display()
        );
        for external in ["<link", " src=", "@import", "url(", "@font-face"] {
            assert!(
                !html.contains(external),
                "{}: {external}",
                fixture.display()
            );
        }
        assert!(html.starts_with("<!DOCTYPE html>"));
        parse(inline_svg(&html));
    }
}

#[test]
fn html_events_table_filters_by_node() {
    let html = render("html", &[Path::new("fixtures/edge.log")]);
    for lane in ["can0/1", "can0/127", "can10/2"] {
        assert!(
            html.contains(&format!("<option value=\"{lane}\">")),
            "{lane}"
        );
        assert!(
            html.contains(&format!("<tr data-lane=\"{lane}\" data-v=")),
            "{lane}"
        );
    }
    assert!(html.contains("<select>"));
}

/// The type and the cells of each row of an HTML page's events table.
fn table_rows(html: &str) -> Vec<(String, Vec<String>)> {
    let start = html.find("<tbody>").expect("a table");
    let end = html.find("</tbody>").expect("table ends");
    let doc = roxmltree::Document::parse(&html[start..end + "</tbody>".len()])
        .expect("the table body is well-formed");
    doc.root_element()
        .children()
        .filter(|n| n.has_tag_name("tr"))
        .map(|tr| {
            let cells = tr
                .children()
                .filter(|c| c.has_tag_name("td"))
                .map(|td| {
                    td.descendants()
                        .filter(|t| t.is_text())
                        .filter_map(|t| t.text())
                        .collect::<String>()
                })
                .collect();
            (tr.attribute("class").unwrap_or_default().to_string(), cells)
        })
        .collect()
}

#[test]
fn html_events_table_lists_health_events_warnings_and_manufacturer_fields() {
    // Every node-health event of the commissioning trace is a row, in
    // trace order with the EMCYs, named by its JSON type.
    let fixture = Path::new("fixtures/commissioning.log");
    let html = render("html", &[fixture]);
    let rows = table_rows(&html);
    let health = [
        "nmt",
        "heartbeat_lost",
        "heartbeat_back",
        "sdo_abort",
        "error_history",
        "error_history_cleared",
    ];
    let events: Vec<Value> = render("ndjson", &[fixture])
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).expect("JSON line"))
        .filter(|o| o["line"].is_u64())
        .collect();
    for kind in health {
        let json = events.iter().filter(|e| e["type"] == kind).count();
        let html_rows: Vec<&Vec<String>> = rows
            .iter()
            .filter(|(c, _)| c == kind)
            .map(|(_, cells)| cells)
            .collect();
        assert!(json > 0, "the fixture has no {kind}");
        assert_eq!(html_rows.len(), json, "{kind} rows");
        for cells in html_rows {
            assert_eq!(cells[4], kind, "the event column names the type");
        }
    }
    let lines: Vec<u64> = rows.iter().map(|(_, c)| c[1].parse().unwrap()).collect();
    assert!(
        lines.windows(2).all(|w| w[0] <= w[1]),
        "rows in trace order"
    );
    let text_of = |kind: &str| {
        rows.iter()
            .find(|(c, _)| c == kind)
            .map(|(_, cells)| cells[7].clone())
            .unwrap()
    };
    assert!(text_of("sdo_abort").contains("0x06090011 sub-index does not exist"));
    assert!(text_of("heartbeat_lost").starts_with("heartbeat lost: silent since"));
    let history = text_of("error_history");
    assert!(
        history.contains("3 entries: 0x4310") && history.contains("before the trace"),
        "{history}"
    );

    // Kollmorgen: the category from the manufacturer bytes, and the
    // warning's tag with its text on hover.
    let html = render("html", &[Path::new("fixtures/s300.log")]);
    let rows = table_rows(&html);
    let first = rows
        .iter()
        .find(|(_, c)| c[4] == "0x4310")
        .map(|(_, c)| c)
        .expect("a 0x4310 row");
    assert!(
        first[8].starts_with("category: 1 (cleared only by a reset"),
        "{first:?}"
    );
    // The Kollmorgen profile says its drives leave the generic bit clear.
    assert_eq!(first[9], "");
    let html = render("html", &[Path::new("fixtures/edge.log")]);
    let rows = table_rows(&html);
    assert!(
        rows.iter().any(|(_, c)| c[9].starts_with("no_generic_bit")),
        "a row with the warning's tag"
    );
    assert!(html.contains(
        "<span title=\"no_generic_bit: error register 0x08 has error bits but not bit 0 (generic)\">no_generic_bit</span>"
    ));
    // Without a profile that reads them, the bytes themselves.
    let html = render("html", &[Path::new("fixtures/canopennode.log")]);
    assert!(
        table_rows(&html)
            .iter()
            .any(|(_, c)| c[4] == "0x8130" && c[8] == "1B05000000"),
        "raw manufacturer bytes"
    );
}

#[test]
fn trace_text_is_escaped() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A file name and a channel name full of markup and a control character.
    let trace = dir.path().join("a&b<c>'d\".log");
    fs::write(
        &trace,
        "(1700000000.000000) c<a&n\"0' 081#1043090000000000\n\
         (1700000000.500000) c\u{1b}]0;x\u{7} 082#1043090000000000\n\
         (1700000001.000000) c<a&n\"0' 081#0000000000000000\n",
    )
    .expect("write trace");
    let svg = render("svg", &[&trace]);
    let doc = parse(&svg);
    let lanes: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("g") && has_class(n, "lane"))
        .filter_map(|n| n.attribute("data-lane"))
        .collect();
    // Report order: channel names sorted ("c\x1b" before "c<").
    assert_eq!(lanes, ["c\\u{1b}]0;x\\u{7}/2", "c<a&n\"0'/1"]);
    assert!(svg.contains("a&amp;b&lt;c&gt;&#39;d&quot;.log"));
    assert!(!svg.contains('\u{1b}'));
    let html = render("html", &[&trace]);
    parse(inline_svg(&html));
    assert!(!html.contains("c<a&n"));
    assert!(!html.contains('\u{1b}'));
    assert!(html.contains("c&lt;a&amp;n&quot;0&#39;"));
}

#[test]
fn several_inputs_give_one_panel_each() {
    let svg = render(
        "svg",
        &[
            Path::new("fixtures/s300.log"),
            Path::new("fixtures/festo.asc"),
        ],
    );
    let doc = parse(&svg);
    let titles: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("text") && has_class(n, "t1"))
        .filter_map(|n| n.text())
        .collect();
    assert_eq!(titles, ["fixtures/s300.log", "fixtures/festo.asc"]);
    let html = render(
        "html",
        &[
            Path::new("fixtures/s300.log"),
            Path::new("fixtures/festo.asc"),
        ],
    );
    assert_eq!(html.matches("<section class=\"input\">").count(), 2);
}

#[test]
fn output_is_deterministic() {
    let a = render("html", &[Path::new("fixtures/edge.asc")]);
    let b = render("html", &[Path::new("fixtures/edge.asc")]);
    assert_eq!(a, b);
}

/// The Chromium binary, or `None` (with a message) when it is not
/// installed; under CI (`.ci/run` installs it) a missing Chromium fails.
fn chromium() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| {
            std::process::Command::new(b)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        });
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "Chromium is not installed (apt-get install chromium)"
        );
        eprintln!("skipped: no Chromium (apt-get install -y chromium to run this check)");
    }
    found
}

/// Renders the HTML of a fixture in headless Chromium (skips with a
/// message when it is not installed): the page must load from disk and
/// paint.
#[test]
fn chromium_renders_the_html_when_present() {
    if chromium().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let png = dir.path().join("s300.png");
    let out = std::process::Command::new("sh")
        .arg("scripts/screenshot.sh")
        .arg("fixtures/s300.log")
        .arg(&png)
        .env("EMCY_DECODE", assert_cmd::cargo::cargo_bin("emcy-decode"))
        .output()
        .expect("runs the script");
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = fs::read(&png).expect("a PNG was written");
    assert!(bytes.starts_with(b"\x89PNG"), "not a PNG");
    assert!(bytes.len() > 10_000, "a blank page? {} bytes", bytes.len());
}

/// Three nodes over a minute, an error of 2 to 8 s every 10 s each: bars
/// wide enough for labels at some widths only.
fn minute_trace() -> String {
    let mut s = String::new();
    let t0 = 1_700_000_000u64;
    let codes = ["1043", "2023", "3031", "1042", "8181"];
    for node in 1..=3u64 {
        for k in 0..6u64 {
            let start = k * 10_000 + node * 700;
            let end = start + 2_000 + (k * 977 + node * 331) % 6_000;
            let code = codes[((k + node) % 5) as usize];
            for (ms, data) in [
                (start, format!("{code}090000000000")),
                (end, "0000000000000000".to_string()),
            ] {
                let _ = writeln!(
                    s,
                    "({}.{:06}) can0 {:03X}#{data}",
                    t0 + ms / 1000,
                    (ms % 1000) * 1000,
                    0x80 + node
                );
            }
        }
    }
    // A boot-up at the end, so the trace runs to 60 s.
    let _ = writeln!(s, "({}.000000) can0 701#00", t0 + 60);
    let mut lines: Vec<&str> = s.lines().collect();
    lines.sort();
    lines.join("\n") + "\n"
}

/// The page after Chromium ran its script (and `extra`, a script appended
/// to the body) in a window of `width`×`height`.
fn browser_dom(browser: &str, html: &str, extra: &str, width: u32, height: u32) -> String {
    let dir = tempfile::tempdir().expect("tempdir");
    let page = dir.path().join("page.html");
    let html = html.replacen("</body>", &format!("<script>{extra}</script>\n</body>"), 1);
    fs::write(&page, html).expect("write page");
    let out = std::process::Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
        ])
        .arg(format!(
            "--user-data-dir={}",
            dir.path().join("profile").display()
        ))
        .args(["--no-first-run", "--no-default-browser-check"])
        .arg(format!("--window-size={width},{height}"))
        // Lets the page's requestAnimationFrame redraws run before the dump.
        .arg("--virtual-time-budget=5000")
        // The page's console on stderr: a script error fails the test.
        .args(["--enable-logging=stderr", "--v=0"])
        .arg("--dump-dom")
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("runs chromium");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(
        !log.lines().any(|l| l.contains("Uncaught")),
        "the page's script failed:\n{log}"
    );
    String::from_utf8(out.stdout).expect("utf-8 DOM")
}

/// One page of several inputs (one without frames, one without times, an
/// ASC and a candump log): the script lays out every chart it has and
/// throws on none.
#[test]
fn chromium_runs_the_page_script_on_every_kind_of_input() {
    let Some(browser) = chromium() else { return };
    let inputs = [
        "fixtures/no-frame.asc",
        "fixtures/canopennode.txt",
        "fixtures/festo.asc",
        "fixtures/s300.log",
    ];
    let mut paths: Vec<&Path> = inputs.iter().map(Path::new).collect();
    // Times past the years a JavaScript Date holds.
    let dir = tempfile::tempdir().expect("tempdir");
    let far = dir.path().join("far.log");
    fs::write(
        &far,
        "(99999999999999.500000) can0 081#1043090000000000\n\
         (99999999999999.750000) can0 081#0000000000000000\n",
    )
    .expect("write trace");
    paths.push(&far);
    let html = render("html", &paths);
    let dom = browser_dom(browser, &html, "", 1100, 800);
    let sections: Vec<&str> = dom.split("<section class=\"input\"").skip(1).collect();
    assert_eq!(sections.len(), 5);
    // No lanes, no drive to lay out; each of the others laid out and zoomable.
    assert!(!sections[0].contains("data-view="));
    let names = inputs.iter().copied().chain(["far.log"]);
    for (input, section) in names.zip(&sections).skip(1) {
        assert!(
            section.contains("data-view=\"0 ") || section.contains("data-view=\"1 "),
            "{input}"
        );
        assert!(section.contains("<p class=\"zoom\">"), "{input}");
        assert!(
            section.contains("width=\"1068\""),
            "{input}: not laid out to the window"
        );
    }
    // The drive without times counts lines.
    assert!(sections[1].contains("trace line"));
}

fn num(n: &roxmltree::Node<'_, '_>, attr: &str) -> f64 {
    n.attribute(attr)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{attr} of {n:?}"))
}

/// What the laid-out page shows: the chart's width, the plot's right edge,
/// the labels drawn, every bar's extent, the legend items' right ends.
struct Laid {
    width: f64,
    plot_end: f64,
    labels: Vec<String>,
    bars: Vec<(f64, f64)>,
    legend_right: f64,
    ticks: Vec<String>,
}

fn laid_out(dom: &str) -> Laid {
    let doc = parse(inline_svg(dom));
    let svg = doc.root_element();
    let in_lane = |n: &roxmltree::Node<'_, '_>| n.ancestors().any(|a| has_class(&a, "lane"));
    let shown = |n: &roxmltree::Node<'_, '_>| {
        !n.attribute("style")
            .is_some_and(|s| s.contains("display: none"))
    };
    Laid {
        width: num(&svg, "width"),
        plot_end: doc
            .descendants()
            .find(|n| n.has_tag_name("line") && has_class(n, "axis"))
            .map(|n| num(&n, "x2"))
            .expect("an axis"),
        labels: doc
            .descendants()
            .filter(|n| n.has_tag_name("text") && has_class(n, "bl") && in_lane(n))
            .filter_map(|n| n.text().map(str::to_string))
            .collect(),
        bars: doc
            .descendants()
            .filter(|n| n.has_tag_name("rect") && has_class(n, "b") && in_lane(n) && shown(n))
            .map(|n| (num(&n, "x"), num(&n, "x") + num(&n, "width")))
            .collect(),
        legend_right: doc
            .descendants()
            .filter(|n| n.has_tag_name("g") && n.parent().is_some_and(|p| has_class(&p, "legend")))
            .map(|g| {
                let t = g.attribute("transform").expect("placed");
                let x: f64 = t["translate(".len()..t.find(',').expect("x,y")]
                    .parse()
                    .expect("x");
                let text = g
                    .descendants()
                    .filter(|n| n.is_text())
                    .filter(|n| n.parent().is_some_and(|p| p.has_tag_name("text")))
                    .filter_map(|n| n.text())
                    .collect::<String>();
                x + text.chars().count() as f64 * 4.0
            })
            .fold(0.0, f64::max),
        ticks: doc
            .descendants()
            .filter(|n| n.has_tag_name("text") && has_class(n, "tick"))
            .filter_map(|n| n.text().map(str::to_string))
            .collect(),
    }
}

/// In Chromium at two window sizes, the chart takes the window's width:
/// the plot ends 28 px from the right, bars stay inside it, labels appear
/// on the bars the width makes wide enough, the legend re-flows inside.
#[test]
fn chromium_lays_the_chart_out_to_the_window() {
    let Some(browser) = chromium() else { return };
    let dir = tempfile::tempdir().expect("tempdir");
    let trace = dir.path().join("minute.log");
    fs::write(&trace, minute_trace()).expect("write trace");
    let html = render("html", &[&trace]);
    let narrow = laid_out(&browser_dom(browser, &html, "", 800, 700));
    let wide = laid_out(&browser_dom(browser, &html, "", 1700, 700));
    for (window, laid) in [(800.0, &narrow), (1700.0, &wide)] {
        // The body's margins are 16 px each side.
        assert!(
            (laid.width - (window - 32.0)).abs() <= 1.0,
            "a {window} px window: chart {} px wide",
            laid.width
        );
        assert_eq!(laid.plot_end, laid.width - 28.0);
        assert_eq!(laid.bars.len(), 18, "every error a bar");
        for &(x0, x1) in &laid.bars {
            assert!(x0 >= 169.0 && x1 <= laid.plot_end + 8.0, "bar {x0}-{x1}");
        }
        assert!(
            laid.legend_right <= laid.width,
            "legend reaches {} of {}",
            laid.legend_right,
            laid.width
        );
        assert!(laid.ticks.len() >= 3, "{:?}", laid.ticks);
    }
    // Wider bars: more of them carry their code, at least one in full.
    assert!(
        wide.labels.len() > narrow.labels.len(),
        "{:?} vs {:?}",
        wide.labels,
        narrow.labels
    );
    assert!(
        wide.labels.iter().any(|l| l.starts_with("0x")),
        "{:?}",
        wide.labels
    );
    // A wider plot has room for more ticks.
    assert!(wide.ticks.len() > narrow.ticks.len());
}

/// In a narrow window (600 px; 500 px, headless Chromium's narrowest) the
/// page is no wider than the window: the chart scales down, to a phone's
/// 320 px too, without clipping its plot, titles or legend, and the events
/// table wraps its cells.
#[test]
fn chromium_fits_narrow_windows_without_a_horizontal_scroll() {
    let Some(browser) = chromium() else { return };
    let dir = tempfile::tempdir().expect("tempdir");
    let trace = dir.path().join("minute.log");
    fs::write(&trace, minute_trace()).expect("write trace");
    let html = render("html", &[&trace, Path::new("fixtures/s300.log")]);
    // The page's width after its layout ran (a timer: layouts wait a frame).
    // And how far the charts' titles reach past their chart's width.
    let measure = "setTimeout(function(){document.body.setAttribute('data-scroll-width',\
                   document.documentElement.scrollWidth);var over=0;\
                   document.querySelectorAll('svg').forEach(function(svg){\
                   svg.querySelectorAll('text.t1,text.t2').forEach(function(t){var b=t.getBBox();\
                   over=Math.max(over,b.x+b.width-(+svg.getAttribute('width')));});});\
                   document.body.setAttribute('data-title-over',Math.ceil(over));},1000);";
    // A phone's width, given to the chart's box as a narrower window would.
    let phone = "document.querySelectorAll('.chart').forEach(function(b){b.style.width='320px';});\
                 window.dispatchEvent(new Event('resize'));";
    for (window, chart) in [(1280u32, None), (600, None), (500, Some(320.0))] {
        let extra = match chart {
            Some(_) => format!("{phone}{measure}"),
            None => measure.to_string(),
        };
        let dom = browser_dom(browser, &html, &extra, window, 700);
        let scroll: f64 = dom
            .split("data-scroll-width=\"")
            .nth(1)
            .and_then(|rest| rest.split('"').next())
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("{window}: not measured"));
        assert!(
            scroll <= f64::from(window),
            "a {window} px window: the page is {scroll} px wide"
        );
        let over: f64 = dom
            .split("data-title-over=\"")
            .nth(1)
            .and_then(|rest| rest.split('"').next())
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("{window}: titles not measured"));
        assert!(
            over <= 0.0,
            "a {window} px window: a title is clipped by {over} px"
        );
        let laid = laid_out(&dom);
        let expected = chart.unwrap_or(f64::from(window) - 32.0);
        assert!(
            (laid.width - expected).abs() <= 1.0,
            "a {window} px window: chart {} px wide",
            laid.width
        );
        assert_eq!(laid.plot_end, laid.width - 28.0);
        assert!(laid.legend_right <= laid.width, "{window}: legend clipped");
        for &(x0, x1) in &laid.bars {
            assert!(x0 >= 169.0 && x1 <= laid.plot_end + 8.0, "bar {x0}-{x1}");
        }
    }
}

/// The time range a laid-out page shows (its section's `data-view`).
fn view_of(dom: &str) -> (f64, f64) {
    let at = dom.find("data-view=\"").expect("the page says its range") + 11;
    let text = &dom[at..at + dom[at..].find('"').unwrap()];
    let (a, b) = text.split_once(' ').expect("two values");
    (a.parse().unwrap(), b.parse().unwrap())
}

/// How many rows of a laid-out page's events table are inside and outside
/// the range `a..=b`; fails unless exactly those inside are shown.
fn rows_in_view(dom: &str, a: f64, b: f64) -> (usize, usize) {
    let body_at = dom.find("<tbody>").expect("a table");
    let body_end = dom.find("</tbody>").expect("table ends") + "</tbody>".len();
    let body = roxmltree::Document::parse(&dom[body_at..body_end]).expect("rows");
    let (mut inside, mut outside) = (0, 0);
    for tr in body
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("tr"))
    {
        let v = num(&tr, "data-v");
        let hidden = tr.attribute("hidden").is_some();
        if v >= a && v <= b {
            assert!(!hidden, "row at {v} in {a}-{b} hidden");
            inside += 1;
        } else {
            assert!(hidden, "row at {v} outside {a}-{b} shown");
            outside += 1;
        }
    }
    (inside, outside)
}

/// Wheel events over the plot (as a user's wheel sends them) narrow the
/// visible range around the pointer: ticks get finer, the events table
/// hides rows outside the range and keeps those inside; a double-click
/// shows the whole trace again.
#[test]
fn chromium_zooms_the_time_axis_and_the_table_follows() {
    let Some(browser) = chromium() else { return };
    let dir = tempfile::tempdir().expect("tempdir");
    let trace = dir.path().join("minute.log");
    fs::write(&trace, minute_trace()).expect("write trace");
    let html = render("html", &[&trace]);
    // Four notches of the wheel at a third of the plot's width.
    let wheel = "var s=document.querySelector('section.input svg'),r=s.getBoundingClientRect(),\
        x=r.left+170+(r.width-198)/3;\
        for(var i=0;i<4;i++)s.dispatchEvent(new WheelEvent('wheel',\
        {deltaY:-240,clientX:x,clientY:r.top+80,bubbles:true,cancelable:true}));";
    let before = browser_dom(browser, &html, "", 1200, 700);
    let after = browser_dom(browser, &html, wheel, 1200, 700);
    let (a0, b0) = view_of(&before);
    let (a1, b1) = view_of(&after);
    assert_eq!(a0, 0.0);
    assert!(b0 > 60.0, "the whole minute and the room after it: {b0}");
    assert!(
        a1 > a0 && b1 < b0 && (b1 - a1) < (b0 - a0) / 4.0,
        "zoomed {a1}-{b1} from {a0}-{b0}"
    );
    // Around the pointer: a third of the way in stays a third of the way in.
    let third = a0 + (b0 - a0) / 3.0;
    assert!(
        ((third - a1) / (b1 - a1) - 1.0 / 3.0).abs() < 0.02,
        "{a1}-{b1}"
    );
    assert!(after.contains("showing 22:13:"), "the range is shown");
    let (lb, la) = (laid_out(&before), laid_out(&after));
    assert_ne!(la.ticks, lb.ticks, "ticks redrawn");
    // The bars in view are wider now, and each one wide enough carries its
    // whole label (`0x1043`: 6 characters of 0.6 em at 9 px, and 4 px).
    let widest = |l: &Laid| l.bars.iter().map(|(a, b)| b - a).fold(0.0, f64::max);
    assert!(widest(&la) > 2.0 * widest(&lb), "bars widen");
    let doc = parse(inline_svg(&after));
    let mut full = 0;
    for bar in lane_bars(&doc) {
        let shown = !bar
            .attribute("style")
            .is_some_and(|s| s.contains("display: none"));
        if shown && width_of(&bar) >= 6.0 * 9.0 * 0.6 + 4.0 {
            let label = bar
                .next_sibling_element()
                .filter(|n| has_class(n, "bl"))
                .and_then(|n| n.text());
            assert_eq!(
                label,
                bar.attribute("data-c"),
                "a {} px bar",
                width_of(&bar)
            );
            full += 1;
        }
    }
    assert!(full > 0, "no bar in view is wide");
    let (inside, outside) = rows_in_view(&after, a1, b1);
    assert!(
        inside > 0 && outside > 0,
        "{inside} inside, {outside} outside"
    );
    assert!(after.contains(&format!(
        "{inside} row{} shown (in the visible time range)",
        if inside == 1 { "" } else { "s" }
    )));
    // A double-click goes back to the whole trace, every row shown.
    let reset = format!(
        "{wheel}document.querySelector('section.input svg').dispatchEvent(new MouseEvent('dblclick',{{bubbles:true}}));"
    );
    let back = browser_dom(browser, &html, &reset, 1200, 700);
    assert_eq!(view_of(&back), (a0, b0));
    assert!(!back.contains("<tr hidden") && !back.contains("hidden=\"\""));
}

/// Zoomed into the last seconds of a trace with more events than a page
/// carries in full, the events list still shows the events there (the page
/// carries every 4th event over the whole trace, and says so).
#[test]
fn chromium_lists_events_anywhere_a_long_trace_is_zoomed() {
    let Some(browser) = chromium() else { return };
    let dir = tempfile::tempdir().expect("tempdir");
    let trace = dir.path().join("many.log");
    fs::write(&trace, many_errors_trace(10_000)).expect("write trace");
    let html = render("html", &[&trace]);
    // Ten notches of the wheel near the plot's right end.
    let wheel = "var s=document.querySelector('section.input svg'),r=s.getBoundingClientRect(),\
        x=r.left+170+(r.width-198)*0.95;\
        for(var i=0;i<10;i++)s.dispatchEvent(new WheelEvent('wheel',\
        {deltaY:-240,clientX:x,clientY:r.top+80,bubbles:true,cancelable:true}));";
    let dom = browser_dom(browser, &html, wheel, 1200, 700);
    let (a, b) = view_of(&dom);
    assert!(a > 80.0 && b - a < 5.0, "zoomed into {a}-{b}");
    let (inside, outside) = rows_in_view(&dom, a, b);
    assert!(inside > 10, "{inside} rows in {a}-{b}");
    assert!(outside > 4_000, "{outside} rows outside");
    assert!(
        dom.contains(&format!(
            "{inside} rows shown (in the visible time range); the page carries every 4th event"
        )),
        "the count says the page is thinned"
    );
}

/// More than 1,000 rows in view are shown a page of 1,000 at a time: the
/// first page at first, the second after a click on "next".
#[test]
fn chromium_pages_the_events_list_past_a_thousand_rows() {
    let Some(browser) = chromium() else { return };
    let dir = tempfile::tempdir().expect("tempdir");
    let trace = dir.path().join("many.log");
    fs::write(&trace, many_errors_trace(10_000)).expect("write trace");
    let html = render("html", &[&trace]);
    let shown_rows = |dom: &str| -> Vec<usize> {
        let at = dom.find("<tbody>").expect("a table");
        let end = dom.find("</tbody>").expect("table ends") + "</tbody>".len();
        let body = roxmltree::Document::parse(&dom[at..end]).expect("rows");
        body.root_element()
            .children()
            .filter(|n| n.has_tag_name("tr"))
            .enumerate()
            .filter(|(_, tr)| tr.attribute("hidden").is_none())
            .map(|(i, _)| i)
            .collect()
    };
    let first = browser_dom(browser, &html, "", 1280, 700);
    assert_eq!(shown_rows(&first), (0..1000).collect::<Vec<_>>());
    assert!(
        first.contains("rows 1\u{2013}1000 of 5002 shown; the page carries every 4th event"),
        "the count names the page"
    );
    let turned = browser_dom(
        browser,
        &html,
        "document.querySelector('button.next').click();",
        1280,
        700,
    );
    assert_eq!(shown_rows(&turned), (1000..2000).collect::<Vec<_>>());
    assert!(turned.contains("rows 1001\u{2013}2000 of 5002 shown"));
}
