//! Tables rendered as images, so a report table can sit beside the figures (the HTML and
//! Markdown pages carry the same table as text).
//!
//! The canvas is sized to the content: columns as wide as their longest cell, a caption
//! wrapped to the table's width, alternate rows shaded for reading across.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::render_png_sized;
use super::style::{self, plot_err};
use crate::error::{Result, VizError};
use crate::figure::Table;

/// Cell text size, px.
const CELL_PX: u32 = 18;
/// Approximate advance of one character of DejaVu Sans at [`CELL_PX`], px (a wide estimate,
/// so text never overflows its cell).
const CHAR_W: f64 = 10.5;
/// Row height, px.
const ROW_H: u32 = 30;
/// Horizontal padding inside a cell, px.
const PAD: u32 = 12;

fn text_width(s: &str) -> u32 {
    (s.chars().count() as f64 * CHAR_W).ceil() as u32
}

/// Greedy word wrap of `s` into lines of at most `width` px.
fn wrap(s: &str, width: u32) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in s.split_whitespace() {
        let candidate = if line.is_empty() {
            word.to_owned()
        } else {
            format!("{line} {word}")
        };
        if text_width(&candidate) > width && !line.is_empty() {
            lines.push(std::mem::replace(&mut line, word.to_owned()));
        } else {
            line = candidate;
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// Render `table` to the PNG `path`.
///
/// # Errors
/// [`VizError::PlotData`] for a table without columns or with a row of the wrong length; a
/// plot or I/O error naming `path`.
pub fn render(path: &Path, table: &Table) -> Result<()> {
    let cols = table.header.len();
    if cols == 0 {
        return Err(VizError::PlotData {
            what: "table",
            message: format!("table {:?} has no columns", table.id),
        });
    }
    if let Some((i, r)) = table.rows.iter().enumerate().find(|(_, r)| r.len() != cols) {
        return Err(VizError::PlotData {
            what: "table",
            message: format!(
                "table {:?}: row {i} has {} cells, the header {cols}",
                table.id,
                r.len()
            ),
        });
    }
    let widths: Vec<u32> = (0..cols)
        .map(|j| {
            std::iter::once(&table.header[j])
                .chain(table.rows.iter().map(|r| &r[j]))
                .map(|c| text_width(c))
                .max()
                .unwrap_or(0)
                + 2 * PAD
        })
        .collect();
    let margin = style::MARGIN_PX;
    let table_w: u32 = widths.iter().sum();
    let width = (table_w + 2 * margin).max(600);
    let caption = wrap(&table.caption, width - 2 * margin);
    let caption_h = caption.len() as u32 * (ROW_H + 2) + 10;
    let height = margin * 2 + caption_h + ROW_H * (table.rows.len() as u32 + 1);

    render_png_sized(path, (width, height), |root| {
        let err = plot_err(path);
        let bold = (FontFamily::SansSerif, CELL_PX)
            .into_font()
            .style(FontStyle::Bold)
            .color(&style::INK);
        for (i, line) in caption.iter().enumerate() {
            let y = (margin + i as u32 * (ROW_H + 2)) as i32;
            root.draw(&Text::new(line.clone(), (margin as i32, y), bold.clone()))
                .map_err(&err)?;
        }
        let top = margin + caption_h;
        let cell = |j: usize, row: u32| {
            let x0 = margin + widths[..j].iter().sum::<u32>();
            let y0 = top + row * ROW_H;
            (
                x0 as i32,
                y0 as i32,
                (x0 + widths[j]) as i32,
                (y0 + ROW_H) as i32,
            )
        };
        let right = style::text(CELL_PX).pos(Pos::new(HPos::Right, VPos::Center));
        let header = bold.pos(Pos::new(HPos::Right, VPos::Center));
        // Header band and alternate-row shading.
        let x_end = (margin + table_w) as i32;
        root.draw(&Rectangle::new(
            [(margin as i32, top as i32), (x_end, (top + ROW_H) as i32)],
            style::LIGHT_GREY.filled(),
        ))
        .map_err(&err)?;
        for r in (1..table.rows.len() as u32 + 1).step_by(2).skip(1) {
            let y = (top + r * ROW_H) as i32;
            root.draw(&Rectangle::new(
                [(margin as i32, y), (x_end, y + ROW_H as i32)],
                style::GRID.filled(),
            ))
            .map_err(&err)?;
        }
        let rows = std::iter::once(&table.header).chain(&table.rows);
        for (r, row) in rows.enumerate() {
            for (j, c) in row.iter().enumerate() {
                let (_, y0, x1, y1) = cell(j, r as u32);
                let font = if r == 0 { &header } else { &right };
                root.draw(&Text::new(
                    c.clone(),
                    (x1 - PAD as i32, (y0 + y1) / 2),
                    font.clone(),
                ))
                .map_err(&err)?;
            }
        }
        // Rules: above and below the header, and at the bottom.
        for y in [
            top,
            top + ROW_H,
            top + ROW_H * (table.rows.len() as u32 + 1),
        ] {
            root.draw(&PathElement::new(
                vec![(margin as i32, y as i32), (x_end, y as i32)],
                style::INK.stroke_width(2),
            ))
            .map_err(&err)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_respects_width_and_keeps_words() {
        let lines = wrap("one two three four five six", text_width("one two three"));
        assert!(lines.len() >= 2);
        assert!(
            lines
                .iter()
                .all(|l| text_width(l) <= text_width("one two three"))
        );
        assert_eq!(lines.join(" "), "one two three four five six");
    }

    #[test]
    fn ragged_rows_are_an_error() {
        let t = Table {
            id: "t".into(),
            caption: "c".into(),
            header: vec!["a".into(), "b".into()],
            rows: vec![vec!["1".into()]],
        };
        let path = std::env::temp_dir().join("pf-viz-table-ragged.png");
        assert!(matches!(render(&path, &t), Err(VizError::PlotData { .. })));
        assert!(!path.exists());
    }
}
