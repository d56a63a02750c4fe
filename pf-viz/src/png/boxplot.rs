//! Box plots: one box per group (quartiles, whiskers to the most extreme value within
//! 1.5 IQR of the box, points beyond them), side by side, with labelled horizontal reference
//! lines (an exact value the boxes should straddle).

use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::render_png;
use super::style::{self, LegendPos, plot_err};
use crate::error::{Result, VizError};

/// One box.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxGroup {
    /// Label under the box.
    pub label: String,
    /// The replicated values.
    pub values: Vec<f64>,
}

/// A complete box plot.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxPlot {
    /// Figure title.
    pub title: String,
    /// Description of the groups (x axis).
    pub x_label: String,
    /// y-axis description, with units.
    pub y_label: String,
    /// The boxes, left to right.
    pub groups: Vec<BoxGroup>,
    /// Horizontal reference lines `(y, label)`.
    pub ref_lines: Vec<(f64, String)>,
    /// Legend position (for the reference lines).
    pub legend: LegendPos,
}

/// The five numbers of a box and its outliers.
struct Summary {
    q1: f64,
    median: f64,
    q3: f64,
    lo: f64,
    hi: f64,
    outliers: Vec<f64>,
}

/// Quantile with linear interpolation of a sorted slice.
fn quantile(sorted: &[f64], p: f64) -> f64 {
    let h = p * (sorted.len() - 1) as f64;
    let (i, f) = (h.floor() as usize, h - h.floor());
    if i + 1 < sorted.len() {
        sorted[i] + f * (sorted[i + 1] - sorted[i])
    } else {
        sorted[i]
    }
}

fn summarise(values: &[f64]) -> Summary {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let (q1, median, q3) = (quantile(&v, 0.25), quantile(&v, 0.5), quantile(&v, 0.75));
    let fence = 1.5 * (q3 - q1);
    let inside = |x: &&f64| **x >= q1 - fence && **x <= q3 + fence;
    let lo = v.iter().find(inside).copied().unwrap_or(q1);
    let hi = v.iter().rev().find(inside).copied().unwrap_or(q3);
    let outliers = v.iter().filter(|x| !inside(x)).copied().collect();
    Summary {
        q1,
        median,
        q3,
        lo,
        hi,
        outliers,
    }
}

impl BoxPlot {
    /// Check that every group has finite values.
    ///
    /// # Errors
    /// [`VizError::PlotData`] naming the first bad group.
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| {
            Err(VizError::PlotData {
                what: "box plot",
                message,
            })
        };
        if self.groups.is_empty() {
            return bad(format!("{:?}: no groups", self.title));
        }
        for g in &self.groups {
            if g.values.is_empty() || g.values.iter().any(|x| !x.is_finite()) {
                return bad(format!(
                    "{:?}: group {:?} is empty or not finite",
                    self.title, g.label
                ));
            }
        }
        if self.ref_lines.iter().any(|(y, _)| !y.is_finite()) {
            return bad(format!("{:?}: non-finite reference line", self.title));
        }
        Ok(())
    }
}

/// Render `plot` to the PNG `path`.
///
/// # Errors
/// [`VizError::PlotData`] for inconsistent data; a plot or I/O error naming `path`.
pub fn render(path: &Path, plot: &BoxPlot) -> Result<()> {
    plot.validate()?;
    let boxes: Vec<Summary> = plot.groups.iter().map(|g| summarise(&g.values)).collect();
    let (lo, hi) = plot
        .groups
        .iter()
        .flat_map(|g| g.values.iter().copied())
        .chain(plot.ref_lines.iter().map(|r| r.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    let (y_lo, y_hi) = style::padded(lo, hi, 0.08);
    let n = plot.groups.len();
    render_png(path, |root| {
        let err = plot_err(path);
        let labels: Vec<String> = plot.groups.iter().map(|g| g.label.clone()).collect();
        let mut chart = ChartBuilder::on(root)
            .caption(&plot.title, style::title())
            .margin(style::MARGIN_PX)
            .x_label_area_size(style::X_LABEL_AREA_PX)
            .y_label_area_size(style::Y_LABEL_AREA_PX)
            .build_cartesian_2d(-0.6..(n as f64 - 0.4), y_lo..y_hi)
            .map_err(&err)?;
        chart
            .configure_mesh()
            .x_desc(&plot.x_label)
            .y_desc(&plot.y_label)
            .axis_desc_style(style::text(style::LABEL_PX))
            .label_style(style::text(style::TICK_PX))
            .x_labels(n)
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < labels.len() {
                    labels[i as usize].clone()
                } else {
                    String::new()
                }
            })
            .y_label_formatter(&|y| style::tick_label(*y))
            .disable_x_mesh()
            .bold_line_style(style::GRID.stroke_width(1))
            .light_line_style(WHITE.stroke_width(0))
            .axis_style(style::INK.stroke_width(1))
            .draw()
            .map_err(&err)?;
        for (i, b) in boxes.iter().enumerate() {
            let x = i as f64;
            let w = 0.3;
            let ink = style::INK.stroke_width(2);
            chart
                .draw_series([
                    Rectangle::new([(x - w, b.q1), (x + w, b.q3)], style::LIGHT_GREY.filled()),
                    Rectangle::new([(x - w, b.q1), (x + w, b.q3)], ink),
                ])
                .map_err(&err)?;
            chart
                .draw_series([
                    PathElement::new(
                        vec![(x - w, b.median), (x + w, b.median)],
                        style::INK.stroke_width(4),
                    ),
                    PathElement::new(vec![(x, b.q3), (x, b.hi)], ink),
                    PathElement::new(vec![(x, b.q1), (x, b.lo)], ink),
                    PathElement::new(vec![(x - w / 2.0, b.hi), (x + w / 2.0, b.hi)], ink),
                    PathElement::new(vec![(x - w / 2.0, b.lo), (x + w / 2.0, b.lo)], ink),
                ])
                .map_err(&err)?;
            chart
                .draw_series(
                    b.outliers
                        .iter()
                        .map(|&y| Circle::new((x, y), 3, style::MID_GREY.stroke_width(1))),
                )
                .map_err(&err)?;
        }
        for (j, (y, label)) in plot.ref_lines.iter().enumerate() {
            let look = if j == 0 {
                style::DARK_RED.stroke_width(2)
            } else {
                style::DARK_BLUE.stroke_width(2)
            };
            chart
                .draw_series(std::iter::once(DashedPathElement::new(
                    vec![(-0.6, *y), (n as f64 - 0.4, *y)],
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
            style::draw_legend(&mut chart, path, plot.legend, style::AxisFonts::FULL)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quartiles_whiskers_and_outliers() {
        let v: Vec<f64> = (1..=9).map(f64::from).chain([100.0]).collect();
        let s = summarise(&v);
        assert_eq!(s.median, 5.5);
        assert_eq!((s.q1, s.q3), (3.25, 7.75));
        assert_eq!(
            s.hi, 9.0,
            "the whisker stops at the last value inside the fence"
        );
        assert_eq!(s.outliers, vec![100.0]);
    }

    #[test]
    fn renders_and_rejects_bad_groups() {
        let mut p = BoxPlot {
            title: "t".into(),
            x_label: "N".into(),
            y_label: "φ".into(),
            groups: vec![
                BoxGroup {
                    label: "10".into(),
                    values: vec![0.1, 0.2, 0.3, 0.5],
                },
                BoxGroup {
                    label: "100".into(),
                    values: vec![0.25, 0.3, 0.31],
                },
            ],
            ref_lines: vec![(0.3, "exact".into())],
            legend: LegendPos::UpperRight,
        };
        let path = std::env::temp_dir().join(format!("pf-viz-box-{}.png", std::process::id()));
        render(&path, &p).unwrap();
        assert!(std::fs::read(&path).unwrap().len() > 5_000);
        std::fs::remove_file(&path).unwrap();
        p.groups[1].values.push(f64::NAN);
        assert!(p.validate().is_err());
    }
}
