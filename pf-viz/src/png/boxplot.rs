//! Box plots: one or more panels side by side, each with one box per group (quartiles,
//! whiskers to the furthest value within 1.5·IQR, outliers as points) and labelled
//! horizontal reference lines (e.g. an exact value the boxes estimate).
//!
//! The renderer draws the [`BoxStats`] it is given, which pf-core's
//! [`BoxStats::new`](pf_core::metrics::BoxStats::new) computes from a sample.

use std::path::Path;

use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::line::RefLine;
use super::style::{self, plot_err};
use super::{Canvas, render_png};
use crate::error::{Result, VizError};
pub use pf_core::metrics::BoxStats;

/// The extent of a box's whiskers and outliers.
fn box_range(b: &BoxStats) -> (f64, f64) {
    b.outliers
        .iter()
        .fold((b.whisker_low, b.whisker_high), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

/// One box and its label on the x-axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoxGroup {
    /// Label under the box (e.g. `J2`).
    pub label: String,
    /// Its numbers.
    pub stats: BoxStats,
}

/// One panel: boxes on a common y-axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoxPanel {
    /// Panel title.
    pub title: String,
    /// x-axis description (what the groups are).
    pub x_label: String,
    /// y-axis description, with units.
    pub y_label: String,
    /// The boxes, left to right.
    pub groups: Vec<BoxGroup>,
    /// Horizontal reference lines, in the legend by their labels.
    pub ref_lines: Vec<RefLine>,
}

/// A figure of box-plot panels side by side under one title.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoxPlot {
    /// Figure title.
    pub title: String,
    /// The panels, left to right.
    pub panels: Vec<BoxPanel>,
}

impl BoxPlot {
    /// Check that there is something to draw and that every number is finite and ordered.
    ///
    /// # Errors
    /// [`VizError::PlotData`] saying what is wrong.
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| VizError::PlotData {
            what: "box plot",
            message,
        };
        if self.panels.is_empty() {
            return Err(bad("no panels".into()));
        }
        for p in &self.panels {
            if p.groups.is_empty() {
                return Err(bad(format!("panel `{}` has no groups", p.title)));
            }
            for g in &p.groups {
                let b = &g.stats;
                let v = [b.whisker_low, b.q1, b.median, b.q3, b.whisker_high];
                if v.iter().any(|x| !x.is_finite()) || v.windows(2).any(|w| w[0] > w[1]) {
                    return Err(bad(format!(
                        "group `{}` of panel `{}`: non-finite or unordered box numbers",
                        g.label, p.title
                    )));
                }
            }
            if p.ref_lines.iter().any(|r| !r.y.is_finite()) {
                return Err(bad(format!(
                    "panel `{}`: non-finite reference line",
                    p.title
                )));
            }
        }
        Ok(())
    }
}

/// Draw `plot` to the PNG file `path`.
///
/// # Errors
/// Inconsistent data ([`VizError::PlotData`]), or a plot or I/O error naming `path`.
pub fn render(path: &Path, plot: &BoxPlot) -> Result<()> {
    plot.validate()?;
    render_png(path, |root| {
        let err = plot_err(path);
        let body = root.titled(&plot.title, style::title()).map_err(&err)?;
        let areas = body.split_evenly((1, plot.panels.len()));
        for (area, panel) in areas.iter().zip(&plot.panels) {
            draw_panel(area, path, panel)?;
        }
        Ok(())
    })
}

fn draw_panel(area: &Canvas<'_>, path: &Path, p: &BoxPanel) -> Result<()> {
    let err = plot_err(path);
    let (lo, hi) = p
        .groups
        .iter()
        .map(|g| box_range(&g.stats))
        .chain(p.ref_lines.iter().map(|r| (r.y, r.y)))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (c, d)| {
            (a.min(c), b.max(d))
        });
    // Headroom above the data for the legend.
    let (y_lo, y_hi) = style::padded(lo, hi + 0.25 * (hi - lo), 0.05);
    let k = p.groups.len();
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, style::text(style::LABEL_PX))
        .margin(style::MARGIN_PX / 2)
        .x_label_area_size(style::X_LABEL_AREA_PX)
        .y_label_area_size(style::Y_LABEL_AREA_PX)
        .build_cartesian_2d(-0.5..(k as f64 - 0.5), y_lo..y_hi)
        .map_err(&err)?;
    let labels: Vec<String> = p.groups.iter().map(|g| g.label.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(2 * k + 1)
        .x_label_formatter(&|x| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < labels.len() {
                labels[i as usize].clone()
            } else {
                String::new()
            }
        })
        .y_label_formatter(&|y| style::tick_label(*y))
        .x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .axis_desc_style(style::text(style::LABEL_PX))
        .label_style(style::text(style::TICK_PX))
        .bold_line_style(style::GRID.stroke_width(1))
        .light_line_style(WHITE.stroke_width(0))
        .axis_style(style::INK.stroke_width(1))
        .draw()
        .map_err(&err)?;

    // Reference lines behind the boxes, so the boxes stay readable where they overlap.
    for (j, r) in p.ref_lines.iter().enumerate() {
        let look = style::SERIES[j % style::SERIES.len()];
        let stroke = look.color.stroke_width(2);
        chart
            .draw_series(LineSeries::new(
                vec![(-0.5, r.y), (k as f64 - 0.5, r.y)],
                stroke,
            ))
            .map_err(&err)?
            .label(r.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 30, y)], stroke));
    }

    let ink = style::INK.stroke_width(2);
    let half = 0.28;
    for (i, g) in p.groups.iter().enumerate() {
        let x = i as f64;
        let b = &g.stats;
        chart
            .draw_series([
                Rectangle::new([(x - half, b.q1), (x + half, b.q3)], style::GRID.filled()),
                Rectangle::new([(x - half, b.q1), (x + half, b.q3)], ink),
            ])
            .map_err(&err)?;
        let segments = [
            vec![(x - half, b.median), (x + half, b.median)],
            vec![(x, b.q3), (x, b.whisker_high)],
            vec![(x, b.q1), (x, b.whisker_low)],
            vec![
                (x - half / 2.0, b.whisker_high),
                (x + half / 2.0, b.whisker_high),
            ],
            vec![
                (x - half / 2.0, b.whisker_low),
                (x + half / 2.0, b.whisker_low),
            ],
        ];
        chart
            .draw_series(segments.into_iter().enumerate().map(|(s, pts)| {
                PathElement::new(
                    pts,
                    if s == 0 {
                        style::INK.stroke_width(4)
                    } else {
                        ink
                    },
                )
            }))
            .map_err(&err)?;
        chart
            .draw_series(
                b.outliers
                    .iter()
                    .map(|&v| Circle::new((x, v), 3, style::MID_GREY.stroke_width(1))),
            )
            .map_err(&err)?;
    }

    if !p.ref_lines.is_empty() {
        style::draw_legend(
            &mut chart,
            path,
            style::LegendPos::UpperRight,
            style::AxisFonts::FULL,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_a_png_and_rejects_bad_data() {
        let group = |label: &str, shift: f64| BoxGroup {
            label: label.into(),
            stats: BoxStats::new(
                &(0..50)
                    .map(|i| shift + f64::from(i).sin())
                    .chain([shift + 5.0])
                    .collect::<Vec<_>>(),
            )
            .unwrap(),
        };
        let mut plot = BoxPlot {
            title: "test".into(),
            panels: vec![BoxPanel {
                title: "φ".into(),
                x_label: "estimator".into(),
                y_label: "value (units)".into(),
                groups: vec![group("J1", 0.0), group("J2", 1.0)],
                ref_lines: vec![RefLine {
                    y: 0.5,
                    label: "exact".into(),
                }],
            }],
        };
        let path = std::env::temp_dir().join(format!("pf-viz-box-{}.png", std::process::id()));
        render(&path, &plot).unwrap();
        let img = image::open(&path).unwrap();
        assert_eq!((img.width(), img.height()), style::SIZE);
        let _ = std::fs::remove_file(&path);
        plot.panels[0].groups[0].stats.q1 = 10.0; // above the median
        assert!(render(&path, &plot).is_err());
        plot.panels[0].groups.clear();
        assert!(plot.validate().is_err());
    }
}
