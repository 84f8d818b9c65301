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
.ec rect.m{fill-opacity:.55;stroke-dasharray:2 1}
.ec rect.o{stroke:#000;stroke-width:1;stroke-dasharray:3 2}
.ec .oe{fill:#000}
.ec .mk line{stroke-width:1.5}
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
.ec .c-current{fill:#e69f00}
.ec .c-voltage{fill:#0072b2}
.ec .c-temperature{fill:#d55e00}
.ec .c-communication{fill:#56b4e9}
.ec .c-hardware{fill:#cc79a7}
.ec .c-software{fill:#009e73}
.ec .c-monitoring{fill:#e8d21d}
.ec .c-manufacturer{fill:#8c564b}
.ec .c-generic{fill:#a0a0a0}
.ec .c-modules{fill:#9467bd}
.ec .c-external{fill:#7f7f00}
.ec .c-additional_functions{fill:#bcbd22}
.ec .c-reset{fill:#c7c7c7}
.ec .c-undefined{fill:#4d4d4d}
";

/// Classes in legend order: the CiA 301 classes users look for first.
pub(super) const LEGEND_ORDER: [Class; 14] = [
    Class::Current,
    Class::Voltage,
    Class::Temperature,
    Class::Communication,
    Class::Hardware,
    Class::Software,
    Class::Monitoring,
    Class::Manufacturer,
    Class::Generic,
    Class::Modules,
    Class::External,
    Class::AdditionalFunctions,
    Class::Reset,
    Class::Undefined,
];

pub(super) fn class_index(class: Class) -> usize {
    LEGEND_ORDER.iter().position(|&c| c == class).unwrap_or(0)
}
