//! How the chart looks: the geometry every part lays out against (in px),
//! the style sheet with the colour of each error class, and the order the
//! legend lists classes in. One place for the look, so the drawing code only
//! names CSS classes and never repeats a style attribute (that is what keeps
//! a file with thousands of bars small).

use crate::canopen::codes::Class;

/// Width of the whole chart in px.
pub(in crate::report) const WIDTH: f64 = 960.0;
/// Left edge of the plot area (the lane labels are left of it).
pub(super) const X0: f64 = 170.0;
/// Right edge of the plot area.
pub(super) const X1: f64 = WIDTH - 28.0;
pub(super) const PLOT_W: f64 = X1 - X0;
/// Height of one bar row inside a lane, and of a bar.
pub(super) const ROW_H: f64 = 12.0;
pub(super) const BAR_H: f64 = 9.0;
pub(super) const LANE_MIN_H: f64 = 28.0;
/// Where the lanes start below the panel's top (title and subtitle above).
pub(super) const LANES_TOP: f64 = 52.0;

/// The CSS of the chart: one copy per document (the SVG's root, the HTML head).
pub(in crate::report) const STYLE: &str = "\
.ec text{font:11px system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;fill:#222}
.ec .t1{font-size:15px;font-weight:600}
.ec .t2{fill:#555}
.ec .lbl{font-weight:600}
.ec .lbl2{fill:#666;font-size:10px}
.ec .tick{fill:#444;text-anchor:middle}
.ec .cap{fill:#666;text-anchor:end}
.ec .bg{fill:#f3f4f6}
.ec .grid{stroke:#dcdfe4;stroke-width:1}
.ec .axis{stroke:#555;stroke-width:1}
.ec .end{stroke:#777;stroke-dasharray:4 3}
.ec .none{fill:#777}
.ec rect.b{stroke:#0006;stroke-width:.5}
.ec rect.b:hover{stroke:#000;stroke-width:1.5}
.ec text.bl{font-size:9px;fill:#000;pointer-events:none}
.ec text.bl.w{fill:#fff}
.ec rect.m{fill-opacity:.55;stroke-dasharray:2 1}
.ec rect.o{stroke:#000;stroke-width:1;stroke-dasharray:3 2}
.ec .oe{fill:#000}
.ec .mk line{stroke-width:1;stroke-opacity:.7}
.ec .reset line{stroke:#1b7837}
.ec .reset circle{fill:#1b7837}
.ec .partial line{stroke:#5aae61;stroke-dasharray:2 2}
.ec .partial circle{fill:#fff;stroke:#1b7837;stroke-width:1.2}
.ec .boot line{stroke:#2c4f9e}
.ec .boot path{fill:#2c4f9e}
.ec .mk rect{fill-opacity:.5}
.ec .reset rect{fill:#1b7837}
.ec .partial rect{fill:#5aae61}
.ec .boot rect{fill:#2c4f9e}
.ec .n-initialising{fill:#2c4f9e;fill-opacity:.10}
.ec .n-pre_operational{fill:#e8d21d;fill-opacity:.14}
.ec .n-operational{fill:#1b7837;fill-opacity:.08}
.ec .n-stopped{fill:#555;fill-opacity:.18}
.ec .out{fill:#d62728;fill-opacity:.28}
.ec .inc rect{fill:#d62728;fill-opacity:.10;stroke:#d62728;stroke-opacity:.6;stroke-width:1}
.ec .inc text{font-size:10px;font-weight:600;fill:#b2182b}
";

/// The bus strip's fills, only in documents whose trace had error frames
/// or SYNC gaps (every other chart's style sheet stays as it was).
const BUS_STYLE: &str = "\
.ec .bus .be{fill:#d62728;fill-opacity:.55}
.ec .bus .bo{fill:#67001f}
.ec .bus .sg{fill:#e69f00}
";

/// The drive state strips' fills, only in documents that have a CiA 402
/// drive (every other chart's style sheet stays as it was): disabled
/// states grey, ready and switched on light green, operation enabled
/// green, quick stop amber, fault reaction and fault red.
const DRIVE_STYLE: &str = "\
.ec .a-not_ready_to_switch_on{fill:#bbb}
.ec .a-switch_on_disabled{fill:#888}
.ec .a-ready_to_switch_on{fill:#a6dba0}
.ec .a-switched_on{fill:#5aae61}
.ec .a-operation_enabled{fill:#1b7837}
.ec .a-quick_stop_active{fill:#e69f00}
.ec .a-fault_reaction_active{fill:#f4a582}
.ec .a-fault{fill:#d62728}
.ec .a-unknown{fill:#fff;stroke:#888;stroke-width:.5}
.ec .fault{fill:#d62728;fill-opacity:.22}
";

/// Classes in legend order (the CiA 301 classes users look for first)
/// with the hue of each: colour-blind-safe where there are enough.
pub(super) const CLASS_COLOURS: [(Class, u32); 14] = [
    (Class::Current, 0xe69f00),
    (Class::Voltage, 0x0072b2),
    (Class::Temperature, 0xd55e00),
    (Class::Communication, 0x56b4e9),
    (Class::Hardware, 0xcc79a7),
    (Class::Software, 0x009e73),
    (Class::Monitoring, 0xe8d21d),
    (Class::Manufacturer, 0x8c564b),
    (Class::Generic, 0xa0a0a0),
    (Class::Modules, 0x9467bd),
    (Class::External, 0x7f7f00),
    (Class::AdditionalFunctions, 0xbcbd22),
    (Class::Reset, 0xc7c7c7),
    (Class::Undefined, 0x4d4d4d),
];

/// Lightness steps of the codes of one class, in the order codes get
/// them: the first code has the class colour, the next ones alternate
/// darker and lighter. More codes of one class than steps repeat them (the
/// legend still names each code).
const SHADE_STEPS: [f64; 6] = [0.0, -0.17, 0.16, -0.30, 0.27, -0.40];

/// How many colours one class has.
pub(super) const SHADES: usize = SHADE_STEPS.len();

pub(super) fn class_index(class: Class) -> usize {
    CLASS_COLOURS
        .iter()
        .position(|&(c, _)| c == class)
        .unwrap_or(0)
}

/// The fill of the `shade`th code of a class (as [`class_index`] gives
/// it): the class hue with its lightness moved by a step.
pub(super) fn code_colour(class: usize, shade: usize) -> u32 {
    let base = CLASS_COLOURS.get(class).map_or(0x808080, |c| c.1);
    let step = SHADE_STEPS.get(shade % SHADES).copied().unwrap_or(0.0);
    if step == 0.0 {
        return base;
    }
    let (h, s, l) = hsl(base);
    rgb(h, s, (l + step).clamp(0.12, 0.9))
}

/// Whether a label on this fill reads better white than black (relative
/// luminance, WCAG's formula without the gamma curve: close enough to
/// choose between two colours).
pub(super) fn dark(colour: u32) -> bool {
    let [_, r, g, b] = colour.to_be_bytes();
    let y = 0.2126 * f64::from(r) + 0.7152 * f64::from(g) + 0.0722 * f64::from(b);
    y < 110.0
}

fn hsl(c: u32) -> (f64, f64, f64) {
    let [_, r, g, b] = c.to_be_bytes();
    let (r, g, b) = (
        f64::from(r) / 255.0,
        f64::from(g) / 255.0,
        f64::from(b) / 255.0,
    );
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let l = (max + min) / 2.0;
    let d = max - min;
    if d == 0.0 {
        return (0.0, 0.0, l);
    }
    let s = d / (1.0 - (2.0 * l - 1.0).abs());
    let h = if max == r {
        ((g - b) / d).rem_euclid(6.0)
    } else if max == g {
        (b - r) / d + 2.0
    } else {
        (r - g) / d + 4.0
    };
    (h * 60.0, s, l)
}

fn rgb(h: f64, s: f64, l: f64) -> u32 {
    let c = (1.0 - (2.0 * l - 1.0).abs()) * s;
    let x = c * (1.0 - ((h / 60.0).rem_euclid(2.0) - 1.0).abs());
    let m = l - c / 2.0;
    let (r, g, b) = match (h / 60.0) as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let byte = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u32;
    (byte(r) << 16) | (byte(g) << 8) | byte(b)
}

/// The style sheet of a document: [`STYLE`], a fill per class, and a fill
/// per `(class, shade)` the panels use beyond the first shade.
/// With `drives`, the drive state strips' fills too.
pub(in crate::report) fn style_sheet(
    shades: &std::collections::BTreeSet<(usize, usize)>,
    drives: bool,
    bus: bool,
) -> String {
    use std::fmt::Write as _;
    let mut s = String::with_capacity(STYLE.len() + 1024);
    s.push_str(STYLE);
    if drives {
        s.push_str(DRIVE_STYLE);
    }
    if bus {
        s.push_str(BUS_STYLE);
    }
    for (class, colour) in CLASS_COLOURS {
        let _ = writeln!(s, ".ec .c-{}{{fill:#{colour:06x}}}", class.slug());
    }
    for &(class, shade) in shades {
        let Some((c, _)) = CLASS_COLOURS.get(class) else {
            continue;
        };
        if shade % SHADES == 0 {
            continue;
        }
        let _ = writeln!(
            s,
            ".ec .c-{}.k{}{{fill:#{:06x}}}",
            c.slug(),
            shade % SHADES,
            code_colour(class, shade)
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_of_a_class_share_its_hue_and_differ_in_lightness() {
        let (h0, _, l0) = hsl(code_colour(0, 0));
        assert_eq!(code_colour(0, 0), 0xe69f00);
        let mut seen = vec![code_colour(0, 0)];
        for shade in 1..SHADES {
            let c = code_colour(0, shade);
            let (h, _, l) = hsl(c);
            assert!((h - h0).abs() < 2.0, "shade {shade}: hue {h} vs {h0}");
            assert!((l - l0).abs() > 0.1, "shade {shade}: lightness {l} vs {l0}");
            assert!(!seen.contains(&c), "shade {shade} repeats a colour");
            seen.push(c);
        }
        // Past the steps, colours repeat rather than run out.
        assert_eq!(code_colour(0, SHADES), code_colour(0, 0));
        assert_eq!(rgb(0.0, 0.0, 0.5), 0x808080);
        assert!(dark(0x0072b2) && !dark(0xe8d21d));
    }
}
