//! How the table gives way to a terminal's width (`--width`, docs/guide/usage.md): the
//! end tables drop their least useful columns and cut the widest cells
//! ([`fit_columns`]); the event rows give up columns in the order
//! `EventLines::layout_for` states. A cut cell ends in `…`.

use std::borrow::Cow;
use std::io::{self, Write};

use unicode_width::UnicodeWidthStr;

/// The narrowest width fitted: below it columns cannot give way enough.
pub const MIN_WIDTH: usize = 40;

/// A channel column longer than this is cut when fitting.
pub(super) const CHANNEL_MAX: usize = 16;

/// How a table gives way to a terminal's width: columns are dropped, least
/// useful first, then the flexible ones cut (an ellipsis marks a cut cell).
pub(super) struct Fit {
    /// Columns dropped while the table is too wide, least useful first.
    pub(super) drop: &'static [usize],
    /// Column, width kept before any column is dropped, narrowest width.
    pub(super) flex: &'static [(usize, usize, usize)],
}

/// Fits a table's column `widths` to `width`: each flexible column is
/// first capped at the width it keeps, then columns are dropped in order
/// (`shown` false) while the table is too wide, then the widest flexible
/// column gives up a column at a time, never below its minimum or its
/// header. A table that cannot fit is left as narrow as that allows.
pub(super) fn fit_columns(
    widths: &mut [usize],
    shown: &mut [bool],
    header: &[&str],
    fit: &Fit,
    width: usize,
) {
    let total = |widths: &[usize], shown: &[bool]| {
        let (sum, n) = widths
            .iter()
            .zip(shown)
            .filter(|(_, s)| **s)
            .fold((0usize, 0usize), |(sum, n), (w, _)| (sum + w, n + 1));
        sum + 2 * n.saturating_sub(1)
    };
    let least = |i: usize, min: usize| min.max(header.get(i).map_or(0, |h| h.len()));
    for &(i, keep, min) in fit.flex {
        if let Some(w) = widths.get_mut(i) {
            *w = (*w).min(keep.max(least(i, min)));
        }
    }
    for &d in fit.drop {
        if total(widths, shown) <= width {
            return;
        }
        if let Some(s) = shown.get_mut(d) {
            *s = false;
        }
    }
    // The widest flexible column gives a column at a time.
    while total(widths, shown) > width {
        let widest = fit
            .flex
            .iter()
            .filter(|&&(i, _, min)| widths.get(i).is_some_and(|w| *w > least(i, min)))
            .max_by_key(|&&(i, _, _)| widths.get(i).copied().unwrap_or(0));
        match widest.and_then(|&(i, _, _)| widths.get_mut(i)) {
            Some(w) => *w -= 1,
            None => break,
        }
    }
}

/// Columns a text takes on a terminal; ASCII (nearly every cell) needs no
/// Unicode tables.
pub(super) fn display_width(s: &str) -> usize {
    if s.is_ascii() {
        s.len()
    } else {
        UnicodeWidthStr::width(s)
    }
}

/// `n` blanks.
pub(super) fn blanks(n: usize) -> Cow<'static, str> {
    const BLANKS: &str = "                                                                                                                                ";
    match BLANKS.get(..n) {
        Some(b) => Cow::Borrowed(b),
        None => Cow::Owned(" ".repeat(n)),
    }
}

/// `text` padded to `width` columns, then the two blanks between columns.
pub(super) fn push_padded(line: &mut String, text: &str, width: usize) {
    line.push_str(text);
    line.push_str(&blanks(width.saturating_sub(display_width(text)) + 2));
}

/// Appends `text` cut to `width` columns, an ellipsis marking the cut;
/// returns the columns it took.
pub(super) fn push_cut(line: &mut String, text: &str, width: usize) -> usize {
    let full = display_width(text);
    if full <= width {
        line.push_str(text);
        return full;
    }
    let mut used = 0;
    for c in text.chars() {
        let w = unicode_width::UnicodeWidthChar::width(c).unwrap_or(0);
        if used + w + 1 > width {
            break;
        }
        line.push(c);
        used += w;
    }
    if width > 0 {
        line.push('…');
        used += 1;
    }
    used
}

/// Pads `s` with blanks up to `width` bytes (ASCII columns).
pub(super) fn pad_to(s: &mut String, width: usize) {
    while s.len() < width {
        s.push(' ');
    }
}

/// [`write_row`] into `line` (cleared first), with the cells' widths known.
pub(super) fn push_row(
    line: &mut String,
    cells: &[String],
    cell_widths: &[usize],
    widths: &[usize],
    shown: &[bool],
    right: &[bool],
) {
    line.clear();
    for (i, cell) in cells.iter().enumerate() {
        if !shown.get(i).copied().unwrap_or(true) {
            continue;
        }
        let width = widths.get(i).copied().unwrap_or(0);
        let cell_width = cell_widths.get(i).copied().unwrap_or(0);
        push_cell(
            line,
            cell,
            cell_width,
            width,
            right.get(i).copied().unwrap_or(false),
        );
    }
    let trimmed = line.trim_end().len();
    line.truncate(trimmed);
    line.push('\n');
}

/// A cell padded to its column (cut to it when fitting), then the two
/// blanks between columns.
fn push_cell(line: &mut String, cell: &str, cell_width: usize, width: usize, right: bool) {
    if cell_width > width {
        push_cut(line, cell, width);
    } else if right {
        line.push_str(&blanks(width - cell_width));
        line.push_str(cell);
    } else {
        line.push_str(cell);
        line.push_str(&blanks(width - cell_width));
    }
    line.push_str("  ");
}

/// One aligned row: cells padded to their column, two blanks between
/// columns, no trailing blanks.
pub(super) fn write_row(
    out: &mut impl Write,
    cells: &[impl AsRef<str>],
    widths: &[usize],
    shown: &[bool],
    right: &[bool],
) -> io::Result<()> {
    let cell_widths: Vec<usize> = cells.iter().map(|c| display_width(c.as_ref())).collect();
    let mut line = String::new();
    for (i, cell) in cells.iter().enumerate() {
        if !shown.get(i).copied().unwrap_or(true) {
            continue;
        }
        let width = widths.get(i).copied().unwrap_or(0);
        let cell_width = cell_widths.get(i).copied().unwrap_or(0);
        push_cell(
            &mut line,
            cell.as_ref(),
            cell_width,
            width,
            right.get(i).copied().unwrap_or(false),
        );
    }
    writeln!(out, "{}", line.trim_end())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The narrowest a flexible column gets when nothing forbids it: tests
    /// give it 0 so the header decides.
    const NO_MIN: usize = 0;

    fn fitted<const N: usize>(
        widths: [usize; N],
        header: &[&str; N],
        fit: &Fit,
        width: usize,
    ) -> ([usize; N], [bool; N]) {
        let mut widths = widths;
        let mut shown = [true; N];
        fit_columns(&mut widths, &mut shown, header, fit, width);
        (widths, shown)
    }

    const HEADER: [&str; 4] = ["A", "B", "C", "D"];

    #[test]
    fn a_table_that_fits_is_left_alone() {
        let fit = Fit {
            drop: &[3, 1],
            flex: &[(2, 60, NO_MIN)],
        };
        // 10 + 10 + 10 + 10 and three gaps of 2: 46 columns.
        assert_eq!(fitted([10; 4], &HEADER, &fit, 46), ([10; 4], [true; 4]));
    }

    #[test]
    fn columns_are_dropped_in_order_until_the_table_fits() {
        let fit = Fit {
            drop: &[3, 1],
            flex: &[],
        };
        // Without D: 34 columns; without D and B: 22.
        assert_eq!(
            fitted([10; 4], &HEADER, &fit, 45),
            ([10; 4], [true, true, true, false])
        );
        assert_eq!(
            fitted([10; 4], &HEADER, &fit, 34),
            ([10; 4], [true, true, true, false])
        );
        assert_eq!(
            fitted([10; 4], &HEADER, &fit, 33),
            ([10; 4], [true, false, true, false])
        );
    }

    #[test]
    fn the_widest_flexible_column_gives_way_after_the_drops() {
        let fit = Fit {
            drop: &[3],
            flex: &[(0, 60, NO_MIN), (2, 60, NO_MIN)],
        };
        // Without D: 20 + 10 + 30 + 4 = 64; 4 columns too many come off C,
        // the widest, and no more.
        assert_eq!(
            fitted([20, 10, 30, 10], &HEADER, &fit, 60),
            ([20, 10, 26, 10], [true, true, true, false])
        );
        // 14 too many: C gives 10, then A and C take turns, widest first.
        assert_eq!(
            fitted([20, 10, 30, 10], &HEADER, &fit, 50),
            ([18, 10, 18, 10], [true, true, true, false])
        );
    }

    #[test]
    fn a_flexible_column_is_capped_before_anything_is_dropped() {
        let fit = Fit {
            drop: &[3],
            flex: &[(2, 12, NO_MIN)],
        };
        // C is cut to 12 at any width fitted, and then the table fits.
        assert_eq!(
            fitted([10, 10, 30, 10], &HEADER, &fit, 200),
            ([10, 10, 12, 10], [true; 4])
        );
    }

    #[test]
    fn a_flexible_column_keeps_its_minimum_and_its_header() {
        let header = ["A", "B", "DESCRIPTION", "D"];
        let fit = Fit {
            drop: &[],
            flex: &[(0, 60, 7), (2, 60, 8)],
        };
        // Far too narrow: A stops at 7, C at its header's 11; the table is
        // left wider than asked rather than cut below them.
        assert_eq!(
            fitted([20, 10, 30, 10], &header, &fit, 10),
            ([7, 10, 11, 10], [true; 4])
        );
    }

    #[test]
    fn cut_text_ends_in_an_ellipsis_within_the_width() {
        let cut = |text: &str, width: usize| {
            let mut line = String::new();
            let used = push_cut(&mut line, text, width);
            (line, used)
        };
        assert_eq!(
            cut("motor overtemperature", 30),
            ("motor overtemperature".into(), 21)
        );
        assert_eq!(
            cut("motor overtemperature", 21),
            ("motor overtemperature".into(), 21)
        );
        assert_eq!(
            cut("motor overtemperature", 20),
            ("motor overtemperatu…".into(), 20)
        );
        assert_eq!(cut("motor", 1), ("…".into(), 1));
        assert_eq!(cut("motor", 0), (String::new(), 0));
        // Wide characters count two columns and are not split.
        assert_eq!(cut("温度温度", 6), ("温度…".into(), 5));
    }

    #[test]
    fn cells_are_padded_cut_and_aligned() {
        let cells = ["can0", "5", "overcurrent in phase U"];
        let widths = cells.map(display_width);
        let mut line = String::new();
        push_row(
            &mut line,
            &cells.map(String::from),
            &widths,
            &[6, 4, 12],
            &[true; 3],
            &[false, true, false],
        );
        assert_eq!(line, "can0       5  overcurrent…\n");
        push_row(
            &mut line,
            &cells.map(String::from),
            &widths,
            &[6, 4, 30],
            &[true, false, true],
            &[false, true, false],
        );
        assert_eq!(
            line, "can0    overcurrent in phase U\n",
            "no trailing blanks"
        );
    }
}
