//! Histograms: one or more panels side by side, each from raw samples (binned here into equal
//! bins over their range) or from pre-binned counts, with the caller's summary statistics
//! (mean, std, max |·|) printed in the panel and the mean marked by a dashed line. The
//! statistics are the caller's: the renderer only bins and draws.

use std::path::Path;

use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::style::{self, plot_err};
use super::{Canvas, render_png};
use crate::error::{Result, VizError};
use pf_core::metrics::Histogram;

/// What a panel shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum HistData {
    /// Raw samples, binned into `bins` equal bins over `[min, max]`.
    Samples {
        /// The values.
        values: Vec<f64>,
        /// Number of bins (≥ 1).
        bins: usize,
    },
    /// Counts already binned: `counts[j]` lies in `[edges[j], edges[j+1])`.
    Binned {
        /// Bin edges, increasing, one more than `counts`.
        edges: Vec<f64>,
        /// Counts per bin.
        counts: Vec<usize>,
    },
}

/// Summary statistics printed in a panel (computed by the caller).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HistStats {
    /// Mean (also drawn as a dashed vertical line).
    pub mean: f64,
    /// Standard deviation.
    pub std: f64,
    /// Largest absolute value.
    pub max_abs: f64,
}

/// One histogram panel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HistPanel {
    /// Panel title.
    pub title: String,
    /// x-axis description, with units.
    pub x_label: String,
    /// y-axis description (usually "count").
    pub y_label: String,
    /// The data.
    pub data: HistData,
    /// Statistics to print, with their unit (e.g. `"kg/m³"`).
    pub stats: Option<(HistStats, String)>,
}

/// A figure of histogram panels in one row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HistogramPlot {
    /// Figure title (above all panels).
    pub title: String,
    /// Panels, left to right.
    pub panels: Vec<HistPanel>,
}

fn bad(message: String) -> VizError {
    VizError::PlotData {
        what: "histogram",
        message,
    }
}

/// Equal-width bins over `[min, max]` of `values` ([`Histogram::new`]): the bin edges and
/// counts.
///
/// # Errors
/// No values, a non-finite value, or `bins = 0`.
pub fn bin(values: &[f64], bins: usize) -> Result<(Vec<f64>, Vec<usize>)> {
    let h = Histogram::new(values, bins).map_err(|e| bad(e.to_string()))?;
    Ok((h.edges, h.counts))
}

impl HistPanel {
    /// The panel's bins: edges and counts.
    ///
    /// # Errors
    /// As [`bin`], or edges that are not one more than the counts, or not increasing.
    pub fn bins(&self) -> Result<(Vec<f64>, Vec<usize>)> {
        match &self.data {
            HistData::Samples { values, bins } => bin(values, *bins),
            HistData::Binned { edges, counts } => {
                if counts.is_empty() || edges.len() != counts.len() + 1 {
                    return Err(bad(format!(
                        "{}: {} edges for {} counts",
                        self.title,
                        edges.len(),
                        counts.len()
                    )));
                }
                if !edges.windows(2).all(|w| w[0] < w[1] && w[1].is_finite()) {
                    return Err(bad(format!("{}: edges not increasing", self.title)));
                }
                Ok((edges.clone(), counts.clone()))
            }
        }
    }
}

/// Draw `plot` to `path`.
///
/// # Errors
/// No panels, bad panel data ([`VizError::PlotData`]), or a drawing or I/O error.
pub fn render(path: &Path, plot: &HistogramPlot) -> Result<()> {
    if plot.panels.is_empty() {
        return Err(bad("no panels".into()));
    }
    let binned = plot
        .panels
        .iter()
        .map(HistPanel::bins)
        .collect::<Result<Vec<_>>>()?;
    render_png(path, |root| {
        let err = plot_err(path);
        let body = root.titled(&plot.title, style::title()).map_err(&err)?;
        let areas = body.split_evenly((1, plot.panels.len()));
        for ((area, panel), (edges, counts)) in areas.iter().zip(&plot.panels).zip(&binned) {
            draw_panel(area, path, panel, edges, counts)?;
        }
        Ok(())
    })
}

fn draw_panel(
    area: &Canvas<'_>,
    path: &Path,
    panel: &HistPanel,
    edges: &[f64],
    counts: &[usize],
) -> Result<()> {
    let err = plot_err(path);
    let (x_lo, x_hi) = style::padded(edges[0], edges[edges.len() - 1], 0.03);
    let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.3;
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, style::text(style::LABEL_PX))
        .margin(style::MARGIN_PX / 2)
        .x_label_area_size(style::X_LABEL_AREA_PX)
        .y_label_area_size(style::Y_LABEL_AREA_PX)
        .build_cartesian_2d(x_lo..x_hi, 0.0..top)
        .map_err(&err)?;
    chart
        .configure_mesh()
        .x_desc(&panel.x_label)
        .y_desc(&panel.y_label)
        .axis_desc_style(style::text(style::LABEL_PX))
        .label_style(style::text(style::TICK_PX))
        .x_labels(6)
        // Counts: whole numbers without a trailing ".0" (plotters' default for f64 axes).
        .y_label_formatter(&|v| {
            if v.fract() == 0.0 {
                format!("{v:.0}")
            } else {
                format!("{v:.1}")
            }
        })
        .bold_line_style(style::GRID.stroke_width(1))
        .light_line_style(WHITE.stroke_width(0))
        .axis_style(style::INK.stroke_width(1))
        .draw()
        .map_err(&err)?;
    chart
        .draw_series(edges.windows(2).zip(counts).map(|(e, &c)| {
            Rectangle::new(
                [(e[0], 0.0), (e[1], c as f64)],
                style::DARK_BLUE.mix(0.55).filled(),
            )
        }))
        .map_err(&err)?;
    chart
        .draw_series(edges.windows(2).zip(counts).map(|(e, &c)| {
            Rectangle::new([(e[0], 0.0), (e[1], c as f64)], style::INK.stroke_width(1))
        }))
        .map_err(&err)?;
    if let Some((s, unit)) = &panel.stats {
        if s.mean.is_finite() && s.mean > x_lo && s.mean < x_hi {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(s.mean, 0.0), (s.mean, top)],
                    6,
                    4,
                    style::DARK_RED.stroke_width(2),
                ))
                .map_err(&err)?;
        }
        let lines = [
            format!("mean {} {unit} (dashed)", short(s.mean)),
            format!("std {} {unit}", short(s.std)),
            format!("max |·| {} {unit}", short(s.max_abs)),
        ];
        let (w, _) = area.dim_in_pixel();
        let x = (w as i32 - 285).max(style::Y_LABEL_AREA_PX as i32 + 10);
        // A backing box, so that the mean's dashed line never runs through the text.
        area.draw(&Rectangle::new(
            [(x - 6, 64), (x + 278, 70 + 26 * lines.len() as i32)],
            WHITE.mix(0.9).filled(),
        ))
        .map_err(&err)?;
        for (i, l) in lines.iter().enumerate() {
            area.draw(&Text::new(
                l.clone(),
                (x, 70 + 26 * i as i32),
                style::text(style::LEGEND_PX),
            ))
            .map_err(&err)?;
        }
    }
    Ok(())
}

/// Four significant digits at most, without trailing zeros.
fn short(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        return format!("{v:.3e}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binning_counts_every_value_once_and_edges_span_the_range() {
        let v = [0.0, 0.1, 0.5, 0.99, 1.0, 2.0];
        let (e, c) = bin(&v, 4).unwrap();
        assert_eq!(e, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
        assert_eq!(c, vec![2, 2, 1, 1]);
        assert!(bin(&[], 3).is_err() && bin(&[1.0], 0).is_err() && bin(&[f64::NAN], 2).is_err());
        assert_eq!(short(13.2264), "13.23");
        assert_eq!(short(-0.0234), "-0.0234");
    }

    #[test]
    fn renders_two_panels_and_rejects_ragged_bins() {
        let dir = std::env::temp_dir().join(format!("pf-viz-hist-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("h.png");
        let mut plot = HistogramPlot {
            title: "residuals".into(),
            panels: vec![
                HistPanel {
                    title: "a".into(),
                    x_label: "x (m)".into(),
                    y_label: "count".into(),
                    data: HistData::Samples {
                        values: (0..100).map(|i| (i as f64 * 0.37).sin()).collect(),
                        bins: 12,
                    },
                    stats: Some((
                        HistStats {
                            mean: 0.01,
                            std: 0.7,
                            max_abs: 1.0,
                        },
                        "m".into(),
                    )),
                },
                HistPanel {
                    title: "b".into(),
                    x_label: "y (kg)".into(),
                    y_label: "count".into(),
                    data: HistData::Binned {
                        edges: vec![0.0, 1.0, 2.0],
                        counts: vec![3, 5],
                    },
                    stats: None,
                },
            ],
        };
        render(&path, &plot).unwrap();
        let png = std::fs::read(&path).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        plot.panels[1].data = HistData::Binned {
            edges: vec![0.0, 1.0],
            counts: vec![3, 5],
        };
        assert!(render(&path, &plot).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
