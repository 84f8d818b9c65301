//! Where the report is written and how: the output, whether in colour, the
//! terminal's width to fit and the times' format; the colours the tables
//! share. Every part of the table writes through a [`Page`].

use std::io::{self, Write};

use anstyle::{AnsiColor, Style};

use super::fit::{Fit, blanks, fit_columns, push_row, write_row};
use crate::report::timefmt::TimeFormat;

pub(super) const RED: Style = AnsiColor::Red.on_default().bold();
pub(super) const YELLOW: Style = AnsiColor::Yellow.on_default();
pub(super) const GREEN: Style = AnsiColor::Green.on_default();
pub(super) const BOLD: Style = Style::new().bold();

/// The output and how it is written.
pub(super) struct Page<W> {
    pub(super) out: W,
    pub(super) color: bool,
    /// The terminal's width to fit (`None`: a pipe, full lines).
    pub(super) width: Option<usize>,
    pub(super) times: TimeFormat,
}

impl<W: Write> Page<W> {
    /// `text` in `style` when in colour.
    pub(super) fn paint(&self, style: Style, text: &str) -> String {
        if self.color {
            format!("{}{text}{}", style.render(), style.render_reset())
        } else {
            text.to_string()
        }
    }

    /// A line of its own (legend, bus line), wrapped to the width when
    /// fitting, its continuation indented by `hang`.
    pub(super) fn write_wrapped(&mut self, text: &str, hang: usize) -> io::Result<()> {
        match self.width {
            Some(width) => {
                let indent = blanks(hang);
                let options = textwrap::Options::new(width).subsequent_indent(&indent);
                for piece in textwrap::wrap(text, options) {
                    writeln!(self.out, "{piece}")?;
                }
                Ok(())
            }
            None => writeln!(self.out, "{text}"),
        }
    }

    /// The columns shown of a table with these widths, fitted to the
    /// terminal (all of them in a pipe).
    pub(super) fn fit<const N: usize>(
        &self,
        widths: &mut [usize; N],
        header: &[&str; N],
        fit: &Fit,
    ) -> [bool; N] {
        self.fit_shown(widths, header, fit, [true; N])
    }

    /// [`Page::fit`] of the columns `shown` already keeps (a column only
    /// some inputs need is left out before fitting).
    pub(super) fn fit_shown<const N: usize>(
        &self,
        widths: &mut [usize; N],
        header: &[&str; N],
        fit: &Fit,
        mut shown: [bool; N],
    ) -> [bool; N] {
        if let Some(width) = self.width {
            fit_columns(widths, &mut shown, header, fit, width);
        }
        shown
    }
}

/// An end table in two passes, widths then rows, so no table of a
/// million rows is held: `rows` gives the rows again for each pass and
/// `fill` puts a row's cells in `cells`, returning their display widths.
/// `title` is written first (after a blank line with `blank`); no rows:
/// nothing is written. A column that is `-` in every row says nothing and
/// is left out: a terminal's width goes to the columns that say something.
pub(super) fn write_in_two_passes<W: Write, T, I, const N: usize>(
    page: &mut Page<W>,
    (title, blank): (&str, bool),
    (header, right, fit): (&[&str; N], &[bool; N], &Fit),
    rows: impl Fn() -> I,
    mut fill: impl FnMut(&mut [String; N], T) -> [usize; N],
) -> io::Result<()>
where
    I: Iterator<Item = T>,
{
    let mut cells: [String; N] = std::array::from_fn(|_| String::new());
    let mut widths = header.map(str::len);
    let mut any = false;
    let mut said = [false; N];
    for row in rows() {
        any = true;
        for (w, c) in widths.iter_mut().zip(fill(&mut cells, row)) {
            *w = (*w).max(c);
        }
        for (s, c) in said.iter_mut().zip(&cells) {
            *s |= c != "-";
        }
    }
    if !any {
        return Ok(());
    }
    let shown = page.fit_shown(&mut widths, header, fit, said);
    if blank {
        writeln!(page.out)?;
    }
    writeln!(page.out, "{}", page.paint(BOLD, title))?;
    write_row(&mut page.out, header, &widths, &shown, right)?;
    let mut line = String::new();
    for row in rows() {
        let cell_widths = fill(&mut cells, row);
        push_row(&mut line, &cells, &cell_widths, &widths, &shown, right);
        page.out.write_all(line.as_bytes())?;
    }
    Ok(())
}
