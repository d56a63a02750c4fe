//! REC curves (regression error characteristic, Bi & Bennett 2003): accuracy, the fraction
//! of errors within a tolerance, against the tolerance. One panel per group (e.g. per
//! target), one curve per method in each, styled by [`style::SERIES`] so methods differ in
//! greyscale and in pattern. Curves are drawn as the step functions they are.

use std::path::Path;

use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::style::{self, Dash, LegendPos, plot_err};
use super::{Canvas, render_png};
use crate::error::{Result, VizError};

/// One REC curve: `accuracy[i]` of errors within `tolerance[i]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecSeries {
    /// Legend entry (the method).
    pub name: String,
    /// Tolerances, increasing.
    pub tolerance: Vec<f64>,
    /// Accuracies in `[0, 1]`, one per tolerance.
    pub accuracy: Vec<f64>,
}

/// One panel: a title (the target) and its curves; curve `i` gets `style::SERIES[i]`, so
/// give every panel its methods in the same order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecPanel {
    /// Panel title.
    pub title: String,
    /// The curves.
    pub curves: Vec<RecSeries>,
}

/// A REC figure: panels in a grid of `cols` columns under one title.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecPlot {
    /// Figure title.
    pub title: String,
    /// x-axis description, with units (the error's).
    pub x_label: String,
    /// The panels, row by row.
    pub panels: Vec<RecPanel>,
    /// Columns of the grid (≥ 1).
    pub cols: usize,
    /// Where each panel's legend sits.
    pub legend: LegendPos,
}

impl RecPlot {
    /// Check shapes and ranges.
    ///
    /// # Errors
    /// [`VizError::PlotData`] naming the first bad curve.
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| {
            Err(VizError::PlotData {
                what: "REC plot",
                message,
            })
        };
        if self.panels.is_empty() || self.cols == 0 {
            return bad("no panels, or zero columns".into());
        }
        for p in &self.panels {
            for c in &p.curves {
                let who = format!("panel '{}', curve '{}'", p.title, c.name);
                if c.tolerance.is_empty() || c.tolerance.len() != c.accuracy.len() {
                    return bad(format!(
                        "{who}: {} tolerances, {} accuracies",
                        c.tolerance.len(),
                        c.accuracy.len()
                    ));
                }
                if c.tolerance.iter().any(|t| !t.is_finite())
                    || c.tolerance.windows(2).any(|w| w[1] < w[0])
                {
                    return bad(format!("{who}: tolerances must be finite and increasing"));
                }
                if c.accuracy.iter().any(|a| !(0.0..=1.0).contains(a)) {
                    return bad(format!("{who}: accuracies must lie in [0, 1]"));
                }
            }
        }
        Ok(())
    }

    fn x_max(&self) -> f64 {
        self.panels
            .iter()
            .flat_map(|p| p.curves.iter().flat_map(|c| c.tolerance.iter().copied()))
            .fold(0.0, f64::max)
    }
}

/// Draw `plot` to the PNG file `path`.
///
/// # Errors
/// Inconsistent data ([`VizError::PlotData`]), or a plot or I/O error naming `path`.
pub fn render(path: &Path, plot: &RecPlot) -> Result<()> {
    plot.validate()?;
    render_png(path, |root| draw(root, path, plot))
}

/// The step function through `(t_i, a_i)`: flat until the next tolerance, then up.
fn steps(c: &RecSeries) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(2 * c.tolerance.len());
    for (i, (&t, &a)) in c.tolerance.iter().zip(&c.accuracy).enumerate() {
        if i > 0 {
            out.push((t, c.accuracy[i - 1]));
        }
        out.push((t, a));
    }
    out
}

fn draw(root: &Canvas<'_>, path: &Path, plot: &RecPlot) -> Result<()> {
    let err = plot_err(path);
    let area = root.titled(&plot.title, style::title()).map_err(&err)?;
    let cols = plot.cols.min(plot.panels.len()).max(1);
    let rows = plot.panels.len().div_ceil(cols);
    let cells = area.split_evenly((rows, cols));
    let x_hi = plot.x_max().max(f64::MIN_POSITIVE) * 1.02;
    // Smaller type in multi-panel grids, so ticks do not collide.
    let small = rows * cols > 2;
    let (label_px, tick_px, legend_px) = if small {
        (16, 14, 14)
    } else {
        (style::LABEL_PX, style::TICK_PX, style::LEGEND_PX)
    };
    for (panel, cell) in plot.panels.iter().zip(cells.iter()) {
        let mut chart = ChartBuilder::on(cell)
            .caption(&panel.title, style::text(label_px))
            .margin(style::MARGIN_PX / 2)
            .x_label_area_size(if small { 45 } else { style::X_LABEL_AREA_PX })
            .y_label_area_size(if small { 60 } else { style::Y_LABEL_AREA_PX })
            .build_cartesian_2d(0.0..x_hi, 0.0..1.04)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .x_desc(&plot.x_label)
            .y_desc("accuracy")
            .axis_desc_style(style::text(label_px))
            .label_style(style::text(tick_px))
            .x_labels(6)
            .y_labels(6)
            .bold_line_style(style::GRID.stroke_width(1))
            .light_line_style(WHITE.stroke_width(0))
            .axis_style(style::INK.stroke_width(1))
            .draw()
            .map_err(&err)?;
        for (j, c) in panel.curves.iter().enumerate() {
            let look = style::SERIES[j % style::SERIES.len()];
            let stroke = look.stroke();
            let pts = steps(c);
            let anno = match look.dash {
                Dash::Solid => chart.draw_series(LineSeries::new(pts, stroke)),
                Dash::Dashed { on, off } => {
                    chart.draw_series(DashedLineSeries::new(pts, on, off, stroke))
                }
            }
            .map_err(&err)?;
            anno.label(c.name.clone())
                .legend(move |at| style::Key { at, look });
        }
        chart
            .configure_series_labels()
            .position(plot.legend.to_plotters())
            .margin(8)
            .legend_area_size(36)
            .label_font(style::text(legend_px))
            .background_style(WHITE.mix(0.88))
            .border_style(style::MID_GREY)
            .draw()
            .map_err(&err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(name: &str, acc: Vec<f64>) -> RecSeries {
        RecSeries {
            name: name.into(),
            tolerance: (0..acc.len()).map(|i| i as f64).collect(),
            accuracy: acc,
        }
    }

    fn plot() -> RecPlot {
        RecPlot {
            title: "REC".into(),
            x_label: "tolerance (m)".into(),
            panels: (0..3)
                .map(|k| RecPanel {
                    title: format!("target {k}"),
                    curves: vec![
                        curve("EPF", vec![0.0, 0.5, 0.9, 1.0]),
                        curve("NNSF", vec![0.0, 0.25, 0.6, 1.0]),
                    ],
                })
                .collect(),
            cols: 3,
            legend: LegendPos::LowerRight,
        }
    }

    #[test]
    fn steps_rise_only_at_tolerances() {
        let s = steps(&curve("a", vec![0.0, 0.5, 1.0]));
        assert_eq!(
            s,
            vec![(0.0, 0.0), (1.0, 0.0), (1.0, 0.5), (2.0, 0.5), (2.0, 1.0)]
        );
    }

    #[test]
    fn validates_and_renders_a_png() {
        let mut p = plot();
        p.validate().unwrap();
        let dir = std::env::temp_dir().join(format!("pf-viz-rec-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("rec.png");
        render(&file, &p).unwrap();
        let bytes = std::fs::read(&file).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        // A drawn grid of panels with text is tens of KB; a blank canvas well under 10 KB.
        assert!(bytes.len() > 20_000, "{} bytes", bytes.len());
        let _ = std::fs::remove_dir_all(&dir);
        // Bad data are rejected, not drawn.
        p.panels[0].curves[0].accuracy[1] = 1.5;
        assert!(p.validate().is_err());
        let mut p = plot();
        p.panels[1].curves[1].tolerance = vec![0.0, 2.0, 1.0, 3.0];
        assert!(p.validate().is_err());
        let mut p = plot();
        p.panels[2].curves[0].accuracy.pop();
        assert!(p.validate().is_err());
        let mut p = plot();
        p.cols = 0;
        assert!(p.validate().is_err());
    }
}
