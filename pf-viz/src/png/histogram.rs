//! Histograms of pre-binned samples, with summary statistics written in the corner and
//! labelled vertical reference lines (zero, a mean). The binning is the caller's: renderers
//! compute no statistics.

use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::render_png;
use super::style::{self, AxisFonts, LegendPos, plot_err};
use crate::error::{Result, VizError};

/// A histogram: `counts[i]` samples in `[edges[i], edges[i+1])`.
#[derive(Debug, Clone, PartialEq)]
pub struct HistogramPlot {
    /// Figure title.
    pub title: String,
    /// x-axis description, with units.
    pub x_label: String,
    /// Bin edges, increasing, one more than the counts.
    pub edges: Vec<f64>,
    /// Samples per bin.
    pub counts: Vec<usize>,
    /// Lines of text drawn in the upper right corner (mean, std, max |·|, the paper's).
    pub annotation: Vec<String>,
    /// Labelled vertical reference lines `(x, label)`.
    pub ref_lines: Vec<(f64, String)>,
}

impl HistogramPlot {
    /// Check the shape and finiteness.
    ///
    /// # Errors
    /// [`VizError::PlotData`] naming what is wrong.
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| {
            Err(VizError::PlotData {
                what: "histogram",
                message,
            })
        };
        if self.counts.is_empty() || self.edges.len() != self.counts.len() + 1 {
            return bad(format!(
                "{:?}: {} edges for {} bins",
                self.title,
                self.edges.len(),
                self.counts.len()
            ));
        }
        if !self
            .edges
            .windows(2)
            .all(|w| w[0].is_finite() && w[1] > w[0])
        {
            return bad(format!("{:?}: edges must increase", self.title));
        }
        if self.ref_lines.iter().any(|(x, _)| !x.is_finite()) {
            return bad(format!("{:?}: non-finite reference line", self.title));
        }
        Ok(())
    }
}

/// Render `plot` to the PNG `path`.
///
/// # Errors
/// [`VizError::PlotData`] for inconsistent data; a plot or I/O error naming `path`.
pub fn render(path: &Path, plot: &HistogramPlot) -> Result<()> {
    plot.validate()?;
    render_png(path, |root| {
        let err = plot_err(path);
        let lo = plot.edges[0].min(
            plot.ref_lines
                .iter()
                .map(|r| r.0)
                .fold(f64::INFINITY, f64::min),
        );
        let hi = plot.edges[plot.edges.len() - 1].max(
            plot.ref_lines
                .iter()
                .map(|r| r.0)
                .fold(f64::NEG_INFINITY, f64::max),
        );
        let (x_lo, x_hi) = style::padded(lo, hi, 0.03);
        let top = plot.counts.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.25;
        let mut chart = ChartBuilder::on(root)
            .caption(&plot.title, style::title())
            .margin(style::MARGIN_PX)
            .x_label_area_size(style::X_LABEL_AREA_PX)
            .y_label_area_size(style::Y_LABEL_AREA_PX)
            .build_cartesian_2d(x_lo..x_hi, 0.0..top)
            .map_err(&err)?;
        style::draw_mesh(
            &mut chart,
            path,
            &plot.x_label,
            "number of samples",
            AxisFonts::FULL,
        )?;
        chart
            .draw_series(plot.counts.iter().enumerate().map(|(i, &c)| {
                Rectangle::new(
                    [(plot.edges[i], 0.0), (plot.edges[i + 1], c as f64)],
                    style::MID_GREY.filled(),
                )
            }))
            .map_err(&err)?;
        chart
            .draw_series(plot.counts.iter().enumerate().map(|(i, &c)| {
                Rectangle::new(
                    [(plot.edges[i], 0.0), (plot.edges[i + 1], c as f64)],
                    style::INK.stroke_width(1),
                )
            }))
            .map_err(&err)?;
        for (j, (x, label)) in plot.ref_lines.iter().enumerate() {
            let look = if j == 0 {
                style::DARK_RED.stroke_width(2)
            } else {
                style::DARK_BLUE.stroke_width(2)
            };
            chart
                .draw_series(std::iter::once(DashedPathElement::new(
                    vec![(*x, 0.0), (*x, top / 1.25)],
                    8,
                    5,
                    look,
                )))
                .map_err(&err)?
                .label(label.clone())
                .legend(move |(px, py)| {
                    DashedPathElement::new(vec![(px, py), (px + 30, py)], 6, 4, look)
                });
        }
        if !plot.ref_lines.is_empty() {
            style::draw_legend(&mut chart, path, LegendPos::UpperLeft, AxisFonts::FULL)?;
        }
        let (w, _) = root.dim_in_pixel();
        let font = style::text(style::LEGEND_PX).pos(Pos::new(HPos::Right, VPos::Top));
        for (i, line) in plot.annotation.iter().enumerate() {
            root.draw(&Text::new(
                line.clone(),
                (w as i32 - style::MARGIN_PX as i32 - 20, 80 + 26 * i as i32),
                font.clone(),
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
    fn shapes_are_checked_and_a_histogram_renders() {
        let mut h = HistogramPlot {
            title: "residuals".into(),
            x_label: "residual (m³/s)".into(),
            edges: vec![-1.0, -0.5, 0.0, 0.5, 1.0],
            counts: vec![3, 10, 12, 2],
            annotation: vec!["mean 0.01".into(), "std 0.4".into()],
            ref_lines: vec![(0.0, "zero".into())],
        };
        h.validate().unwrap();
        let path = std::env::temp_dir().join(format!("pf-viz-hist-{}.png", std::process::id()));
        render(&path, &h).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        assert!(bytes.len() > 5_000);
        std::fs::remove_file(&path).unwrap();
        h.edges.pop();
        assert!(h.validate().is_err());
        h.edges = vec![0.0, 0.0, 1.0, 2.0, 3.0];
        assert!(h.validate().is_err());
    }
}
