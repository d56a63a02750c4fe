//! Line plots: one or more series against a common x-axis, each with an optional shaded band
//! (a confidence or Monte Carlo interval), plus labelled horizontal reference lines.

use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::style::{self, AxisFonts, AxisScale, Dash, LegendPos, Marker, plot_err};
use super::{Canvas, render_png};
use crate::error::{Result, VizError};

/// Series with more points than this are drawn without markers.
const MAX_MARKED_POINTS: usize = 60;

/// Series with this many points or fewer are a handful of measured settings joined by lines:
/// each point gets a marker, squares for the series whose style has none.
const FEW_POINTS: usize = 12;

/// A shaded band `lower[j] ≤ y ≤ upper[j]` at the series' x values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Band {
    /// Lower edge.
    pub lower: Vec<f64>,
    /// Upper edge.
    pub upper: Vec<f64>,
}

/// One series of a line plot. Its look is [`style::SERIES`]`[index % 4]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// x values.
    pub x: Vec<f64>,
    /// y values (same length as `x`).
    pub y: Vec<f64>,
    /// Optional band around the series.
    pub band: Option<Band>,
}

/// A labelled horizontal reference line (a threshold, a true value).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefLine {
    /// Height.
    pub y: f64,
    /// Legend entry.
    pub label: String,
}

/// A complete line plot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinePlot {
    /// Figure title.
    pub title: String,
    /// x-axis description, with units.
    pub x_label: String,
    /// How the x axis places its values.
    #[serde(default)]
    pub x_scale: AxisScale,
    /// y-axis description, with units.
    pub y_label: String,
    /// The series, in drawing order.
    pub series: Vec<Series>,
    /// Horizontal reference lines.
    pub ref_lines: Vec<RefLine>,
    /// Fixed y range; `None` fits the data, bands and reference lines, with room for the
    /// legend where a point would lie behind it.
    pub y_range: Option<(f64, f64)>,
    /// Where the legend sits; keep it clear of the data with `y_range` or the headroom.
    pub legend: LegendPos,
}

impl LinePlot {
    /// Check lengths and finiteness.
    ///
    /// # Errors
    /// [`VizError::PlotData`] naming the first bad series.
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| {
            Err(VizError::PlotData {
                what: "line plot",
                message,
            })
        };
        if self.series.iter().all(|s| s.x.is_empty()) {
            return bad("no data points".into());
        }
        for s in &self.series {
            if s.x.len() != s.y.len() {
                return bad(format!(
                    "series '{}': {} x values, {} y values",
                    s.name,
                    s.x.len(),
                    s.y.len()
                ));
            }
            if let Some(b) = &s.band
                && (b.lower.len() != s.x.len() || b.upper.len() != s.x.len())
            {
                return bad(format!(
                    "series '{}': band length differs from the series",
                    s.name
                ));
            }
            let values =
                s.x.iter()
                    .chain(&s.y)
                    .chain(s.band.iter().flat_map(|b| b.lower.iter().chain(&b.upper)));
            if let Some(v) = values.into_iter().find(|v| !v.is_finite()) {
                return bad(format!("series '{}': value {v} is not finite", s.name));
            }
            if let Some(v) = self.x_scale.first_unplaceable(s.x.iter().copied()) {
                return bad(format!(
                    "series '{}': x value {v} on a log scale (must be positive)",
                    s.name
                ));
            }
        }
        if let Some((lo, hi)) = self.y_range
            && (lo >= hi || lo.is_nan() || hi.is_nan())
        {
            return bad(format!("empty y range {lo}..{hi}"));
        }
        Ok(())
    }

    /// The plot in the chart's coordinates: x mapped by its scale.
    fn drawn(&self) -> std::borrow::Cow<'_, LinePlot> {
        if self.x_scale == AxisScale::Linear {
            return std::borrow::Cow::Borrowed(self);
        }
        let mut p = self.clone();
        for s in &mut p.series {
            s.x.iter_mut().for_each(|x| *x = self.x_scale.map(*x));
        }
        std::borrow::Cow::Owned(p)
    }

    fn extent(&self) -> ((f64, f64), (f64, f64)) {
        let fold = |it: &mut dyn Iterator<Item = f64>| {
            it.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
        };
        let x = fold(&mut self.series.iter().flat_map(|s| s.x.iter().copied()));
        let y = fold(
            &mut self
                .series
                .iter()
                .flat_map(|s| {
                    s.y.iter()
                        .chain(s.band.iter().flat_map(|b| b.lower.iter().chain(&b.upper)))
                })
                .copied()
                .chain(self.ref_lines.iter().map(|r| r.y)),
        );
        (x, y)
    }

    /// The y range `y` (the padded data) widened at the legend's edge until no point or
    /// band under the legend's box lies behind it. The box is estimated from the font size
    /// and the longest entry, as a share of a [`style::SIZE`] figure's plot area.
    fn fitted_y(&self, x: (f64, f64), y: (f64, f64)) -> (f64, f64) {
        let banded = " (shaded: band)".len();
        let chars = self
            .series
            .iter()
            .map(|s| s.name.chars().count() + if s.band.is_some() { banded } else { 0 })
            .chain(self.ref_lines.iter().map(|r| r.label.chars().count()))
            .max()
            .unwrap_or(0);
        let entries = self.series.len() + self.ref_lines.len();
        let (plot_w, plot_h) = (
            f64::from(style::SIZE.0 - 2 * style::MARGIN_PX - style::Y_LABEL_AREA_PX),
            f64::from(
                style::SIZE.1 - 2 * style::MARGIN_PX - style::X_LABEL_AREA_PX - 2 * style::TITLE_PX,
            ),
        );
        // Rows of about 1.2 font heights, the box's padding, and its 12 px margin.
        let legend_px = f64::from(style::LEGEND_PX);
        let h = ((entries as f64 * 1.2 * legend_px + 2.0 * legend_px + 12.0) / plot_h).min(0.8);
        let w = (f64::from(style::KEY_PX) + 40.0 + chars as f64 * 0.6 * legend_px) / plot_w;
        let (top, left) = match self.legend {
            LegendPos::UpperLeft => (true, true),
            LegendPos::UpperRight => (true, false),
            LegendPos::LowerLeft => (false, true),
            LegendPos::LowerRight => (false, false),
        };
        let span = x.1 - x.0;
        let (xa, xb) = if left {
            (x.0, x.0 + w * span)
        } else {
            (x.1 - w * span, x.1)
        };
        let under = self.series.iter().flat_map(|s| {
            let band = s.band.iter().flat_map(|b| {
                s.x.iter()
                    .zip(b.lower.iter().zip(&b.upper))
                    .flat_map(|(&x, (&l, &u))| [(x, l), (x, u)])
            });
            s.x.iter().copied().zip(s.y.iter().copied()).chain(band)
        });
        let ys = under.filter(|&(x, _)| x >= xa && x <= xb).map(|(_, y)| y);
        let (lo, hi) = y;
        if top {
            let m = ys.fold(f64::NEG_INFINITY, f64::max);
            // (m − lo) / (hi' − lo) ≤ 1 − h: the highest point stays below the box.
            let need = lo + (m - lo) / (1.0 - h);
            (lo, if need.is_finite() { hi.max(need) } else { hi })
        } else {
            let m = ys.fold(f64::INFINITY, f64::min);
            let need = hi - (hi - m) / (1.0 - h);
            (if need.is_finite() { lo.min(need) } else { lo }, hi)
        }
    }
}

/// Draw `plot` to the PNG file `path`.
///
/// # Errors
/// Inconsistent data ([`VizError::PlotData`]), or a plot or I/O error naming `path`.
pub fn render(path: &Path, plot: &LinePlot) -> Result<()> {
    plot.validate()?;
    render_png(path, |root| draw(root, path, &plot.drawn()))
}

fn draw(root: &Canvas<'_>, path: &Path, plot: &LinePlot) -> Result<()> {
    let err = plot_err(path);
    let ((x_lo, x_hi), (y_lo, y_hi)) = plot.extent();
    let (x_lo, x_hi) = style::padded(x_lo, x_hi, 0.01);
    let (y_lo, y_hi) = plot
        .y_range
        .unwrap_or_else(|| plot.fitted_y((x_lo, x_hi), style::padded(y_lo, y_hi, 0.06)));
    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, style::title())
        .margin(style::MARGIN_PX)
        .x_label_area_size(style::X_LABEL_AREA_PX)
        .y_label_area_size(style::Y_LABEL_AREA_PX)
        .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)
        .map_err(&err)?;
    style::draw_mesh(
        &mut chart,
        path,
        (&plot.x_label, plot.x_scale),
        &plot.y_label,
        AxisFonts::FULL,
    )?;

    // Bands first, so every line stays visible on top of every band.
    for (j, s) in plot.series.iter().enumerate() {
        if let Some(b) = &s.band {
            let look = style::SERIES[j % style::SERIES.len()];
            let outline: Vec<(f64, f64)> =
                s.x.iter()
                    .zip(&b.upper)
                    .map(|(&x, &y)| (x, y))
                    .chain(s.x.iter().zip(&b.lower).rev().map(|(&x, &y)| (x, y)))
                    .collect();
            chart
                .draw_series(std::iter::once(Polygon::new(
                    outline,
                    look.color.mix(style::BAND_ALPHA).filled(),
                )))
                .map_err(&err)?;
        }
    }

    for (j, s) in plot.series.iter().enumerate() {
        let look = style::SERIES[j % style::SERIES.len()];
        let stroke = look.stroke();
        let points: Vec<(f64, f64)> = s.x.iter().copied().zip(s.y.iter().copied()).collect();
        let dense = points.len() > MAX_MARKED_POINTS;
        // A marked solid series that is too dense for markers is dotted instead.
        let dash = match (dense, look.marker, look.dash) {
            (true, Marker::Circle | Marker::Cross, Dash::Solid) => Dash::Dashed { on: 3, off: 4 },
            (_, _, d) => d,
        };
        let anno = match dash {
            Dash::Solid => chart.draw_series(LineSeries::new(points.clone(), stroke)),
            Dash::Dashed { on, off } => {
                chart.draw_series(DashedLineSeries::new(points.clone(), on, off, stroke))
            }
        }
        .map_err(&err)?;
        let name = match &s.band {
            Some(_) => format!("{} (shaded: band)", s.name),
            None => s.name.clone(),
        };
        // Markers on a dense series would merge into a thick line: beyond this many
        // points the dash pattern alone tells the series apart.
        let marker = match look.marker {
            _ if dense => Marker::None,
            Marker::None if points.len() <= FEW_POINTS => Marker::Square,
            m => m,
        };
        let drawn = style::SeriesStyle {
            dash,
            marker,
            ..look
        };
        anno.label(name)
            .legend(move |at| style::Key { at, look: drawn });
        match marker {
            Marker::None => {}
            Marker::Circle => {
                chart
                    .draw_series(
                        points
                            .iter()
                            .map(|&c| Circle::new(c, style::CIRCLE_PX, look.color.filled())),
                    )
                    .map_err(&err)?;
            }
            Marker::Cross => {
                chart
                    .draw_series(
                        points
                            .iter()
                            .map(|&c| Cross::new(c, style::CROSS_PX, stroke)),
                    )
                    .map_err(&err)?;
            }
            Marker::Square => {
                let r = style::CIRCLE_PX;
                chart
                    .draw_series(points.iter().map(|&c| {
                        EmptyElement::at(c)
                            + Rectangle::new([(-r, -r), (r, r)], look.color.filled())
                    }))
                    .map_err(&err)?;
            }
        }
    }

    for r in &plot.ref_lines {
        let look = style::INK.stroke_width(1);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x_lo, r.y), (x_hi, r.y)],
                3,
                5,
                look,
            ))
            .map_err(&err)?
            .label(r.label.clone())
            .legend(move |(x, y)| {
                DashedPathElement::new(vec![(x, y), (x + style::KEY_PX, y)], 3, 4, look)
            });
    }

    style::draw_legend(&mut chart, path, plot.legend, AxisFonts::FULL)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(legend: LegendPos, rising: bool) -> LinePlot {
        let x: Vec<f64> = (0..=10).map(f64::from).collect();
        let y = x
            .iter()
            .map(|&v| if rising { v } else { 10.0 - v })
            .collect();
        LinePlot {
            title: "t".into(),
            x_label: "x".into(),
            x_scale: AxisScale::Linear,
            y_label: "y".into(),
            series: vec![Series {
                name: "a series".into(),
                x,
                y,
                band: None,
            }],
            ref_lines: vec![],
            y_range: None,
            legend,
        }
    }

    /// A legend in the corner the data run into gets room; one over empty space does not.
    #[test]
    fn the_legend_gets_room_only_where_data_would_lie_behind_it() {
        let padded = style::padded(0.0, 10.0, 0.06);
        for (legend, rising, grows) in [
            (LegendPos::UpperRight, true, true),
            (LegendPos::UpperLeft, false, true),
            (LegendPos::LowerRight, false, true),
            (LegendPos::LowerLeft, true, true),
            (LegendPos::UpperRight, false, false),
            (LegendPos::LowerLeft, false, false),
        ] {
            let p = ramp(legend, rising);
            let (lo, hi) = p.fitted_y((0.0, 10.0), padded);
            let wider = (lo, hi) != padded;
            assert_eq!(wider, grows, "{legend:?}, rising {rising}: {lo}..{hi}");
            if grows {
                // The extreme point now sits at least a legend's height from the edge.
                let frac = if matches!(legend, LegendPos::UpperLeft | LegendPos::UpperRight) {
                    (hi - 10.0) / (hi - lo)
                } else {
                    (0.0 - lo) / (hi - lo)
                };
                assert!(frac > 0.1, "{legend:?}: {frac}");
            }
        }
    }

    #[test]
    fn bad_lengths_are_rejected() {
        let mut p = LinePlot {
            title: "t".into(),
            x_label: "x".into(),
            x_scale: AxisScale::Linear,
            y_label: "y".into(),
            series: vec![Series {
                name: "s".into(),
                x: vec![0.0, 1.0],
                y: vec![1.0, 2.0],
                band: None,
            }],
            ref_lines: vec![],
            y_range: None,
            legend: LegendPos::UpperLeft,
        };
        p.validate().unwrap();
        p.series[0].band = Some(Band {
            lower: vec![0.0],
            upper: vec![1.0, 2.0],
        });
        assert!(p.validate().is_err());
        p.series[0].band = None;
        p.series[0].y.push(3.0);
        assert!(p.validate().is_err());
    }

    /// On a log scale a series is drawn at the logarithms of its x values, and an x of 0
    /// is refused with the series named rather than drawn at −∞.
    #[test]
    fn log_scaled_series_are_drawn_at_their_logarithms() {
        let mut p = ramp(LegendPos::UpperRight, true);
        p.x_scale = AxisScale::Log10;
        p.series[0].x = (0..=10).map(|k| 10f64.powi(k)).collect();
        p.validate().unwrap();
        let drawn = p.drawn();
        assert_eq!(
            drawn.series[0].x,
            (0..=10).map(f64::from).collect::<Vec<_>>()
        );
        assert_eq!(drawn.series[0].y, p.series[0].y);
        p.series[0].x[3] = 0.0;
        let err = p.validate().unwrap_err().to_string();
        assert!(
            err.contains("'a series'") && err.contains("log scale"),
            "{err}"
        );
    }
}
