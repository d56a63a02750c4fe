//! Plots in the plane with equal axes: paths, points, segments (bearing rays, association
//! lines), error ellipses and text labels.
//!
//! One metre is one metre in both directions unless the caller fixes the ranges or the x
//! axis is logarithmic, so trajectories and ellipses keep their true shape. Layers are drawn
//! in order: put context (particle clouds, clutter) first.

use std::path::Path;

use pf_core::gaussian::ErrorEllipse;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::render_png;
use super::style::{self, AxisFonts, AxisScale, Dash, LegendPos, Marker, plot_err};
use crate::error::{Result, VizError};

/// Points on each ellipse outline.
const ELLIPSE_POINTS: usize = 72;

/// How a layer looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum XyStyle {
    /// One of the four greyscale-safe series styles, [`style::SERIES`]`[i % 4]`.
    Series(usize),
    /// Light grey, thin, small markers: context drawn behind everything else.
    Context,
}

/// What a layer draws.
#[derive(Debug, Clone, PartialEq)]
pub enum LayerKind {
    /// A polyline through the points, in order (a trajectory).
    Path(Vec<[f64; 2]>),
    /// Markers at the points (detections, particles, estimates).
    Points(Vec<[f64; 2]>),
    /// Straight segments (bearing rays, association lines).
    Segments(Vec<[[f64; 2]; 2]>),
    /// Ellipse outlines (error ellipses, validation gates).
    Ellipses(Vec<ErrorEllipse>),
    /// Text annotations at points (target ids, sample numbers).
    Labels(Vec<([f64; 2], String)>),
}

/// One layer of an [`XyPlot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Legend entry; empty = no legend entry.
    pub name: String,
    /// Its look.
    pub style: XyStyle,
    /// What it draws.
    pub kind: LayerKind,
}

/// A complete plot in the plane.
#[derive(Debug, Clone, PartialEq)]
pub struct XyPlot {
    /// Figure (or panel) title.
    pub title: String,
    /// x-axis description, with units.
    pub x_label: String,
    /// How the x axis places its values; a log scale takes no ellipses (they would not
    /// stay ellipses) and keeps the axes' scales independent.
    pub x_scale: AxisScale,
    /// y-axis description, with units.
    pub y_label: String,
    /// Drawn in order (context layers first).
    pub layers: Vec<Layer>,
    /// Where the legend sits.
    pub legend: LegendPos,
    /// Fixed x range; `None` fits every layer with equal scale on both axes.
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range; `None` fits every layer with equal scale on both axes.
    pub y_range: Option<(f64, f64)>,
}

impl Layer {
    /// Every point the layer touches, for fitting the axes.
    fn points(&self) -> Vec<[f64; 2]> {
        match &self.kind {
            LayerKind::Path(p) | LayerKind::Points(p) => p.clone(),
            LayerKind::Segments(s) => s.iter().flatten().copied().collect(),
            LayerKind::Ellipses(e) => e.iter().flat_map(|e| e.points(16)).collect(),
            LayerKind::Labels(l) => l.iter().map(|(p, _)| *p).collect(),
        }
    }

    fn is_finite(&self) -> bool {
        let ok = |p: &[f64; 2]| p[0].is_finite() && p[1].is_finite();
        match &self.kind {
            LayerKind::Ellipses(e) => e.iter().all(|e| {
                ok(&e.centre) && ok(&e.semi_axes) && e.angle.is_finite() && e.semi_axes[1] >= 0.0
            }),
            _ => self.points().iter().all(ok),
        }
    }
}

impl XyPlot {
    /// Check that there is something to draw and that every coordinate is finite.
    ///
    /// # Errors
    /// [`VizError::PlotData`] naming the first bad layer.
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| {
            Err(VizError::PlotData {
                what: "xy plot",
                message,
            })
        };
        if self.layers.iter().all(|l| l.points().is_empty()) {
            return bad(format!("{:?}: nothing to draw", self.title));
        }
        if let Some(l) = self.layers.iter().find(|l| !l.is_finite()) {
            return bad(format!(
                "{:?}: layer {:?} has non-finite values",
                self.title, l.name
            ));
        }
        for (what, r) in [("x", self.x_range), ("y", self.y_range)] {
            if let Some((lo, hi)) = r
                && !(lo.is_finite() && hi.is_finite() && lo < hi)
            {
                return bad(format!("{:?}: bad {what} range {lo}..{hi}", self.title));
            }
        }
        if self.x_scale == AxisScale::Log10 {
            if let Some(l) = self
                .layers
                .iter()
                .find(|l| matches!(l.kind, LayerKind::Ellipses(_)))
            {
                return bad(format!(
                    "{:?}: layer {:?} draws ellipses on a log scale",
                    self.title, l.name
                ));
            }
            let xs = self.layers.iter().flat_map(Layer::points).map(|p| p[0]);
            let range = self.x_range.iter().flat_map(|&(lo, hi)| [lo, hi]);
            if let Some(x) = self.x_scale.first_unplaceable(xs.chain(range)) {
                return bad(format!(
                    "{:?}: x value {x} on a log scale (must be positive)",
                    self.title
                ));
            }
        }
        Ok(())
    }

    /// The plot in the chart's coordinates: x mapped by its scale.
    fn drawn(&self) -> std::borrow::Cow<'_, XyPlot> {
        let scale = self.x_scale;
        if scale == AxisScale::Linear {
            return std::borrow::Cow::Borrowed(self);
        }
        let mut p = self.clone();
        let map = |q: &mut [f64; 2]| q[0] = scale.map(q[0]);
        for l in &mut p.layers {
            match &mut l.kind {
                LayerKind::Path(v) | LayerKind::Points(v) => v.iter_mut().for_each(map),
                LayerKind::Segments(v) => v.iter_mut().flatten().for_each(map),
                LayerKind::Labels(v) => v.iter_mut().for_each(|(q, _)| map(q)),
                // Refused by `validate` on a log scale.
                LayerKind::Ellipses(_) => {}
            }
        }
        p.x_range = self.x_range.map(|(lo, hi)| (scale.map(lo), scale.map(hi)));
        std::borrow::Cow::Owned(p)
    }

    /// The axis ranges: the fixed ones, or the layers' extent padded by 5 % and, on a linear
    /// x axis, widened in one direction so that a unit has the same length on both axes of a
    /// `w`×`h` px plot.
    fn ranges(&self, w: f64, h: f64) -> ((f64, f64), (f64, f64)) {
        let pts: Vec<[f64; 2]> = self.layers.iter().flat_map(Layer::points).collect();
        let extent = |i: usize| {
            pts.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[i]), hi.max(p[i]))
                })
        };
        let (x_lo, x_hi) = extent(0);
        let (y_lo, y_hi) = extent(1);
        let x = self
            .x_range
            .unwrap_or_else(|| style::padded(x_lo, x_hi, 0.05));
        let y = self
            .y_range
            .unwrap_or_else(|| style::padded(y_lo, y_hi, 0.05));
        if self.x_range.is_some() || self.y_range.is_some() || self.x_scale != AxisScale::Linear {
            return (x, y);
        }
        let per_px = ((x.1 - x.0) / w).max((y.1 - y.0) / h);
        let widen = |(lo, hi): (f64, f64), px: f64| {
            let c = 0.5 * (lo + hi);
            let half = 0.5 * per_px * px;
            (c - half, c + half)
        };
        (widen(x, w), widen(y, h))
    }
}

/// Render `plot` to the PNG `path`.
///
/// # Errors
/// [`VizError::PlotData`] for inconsistent data; a plot or I/O error naming `path`.
pub fn render(path: &Path, plot: &XyPlot) -> Result<()> {
    plot.validate()?;
    render_png(path, |root| draw(root, path, &plot.drawn(), Fonts::FULL))
}

/// Render several panels in a grid of `cols` columns, under one overall `title`.
///
/// # Errors
/// [`VizError::PlotData`] for no panels, `cols == 0` or an inconsistent panel; a plot or
/// I/O error naming `path`.
pub fn render_grid(path: &Path, title: &str, panels: &[XyPlot], cols: usize) -> Result<()> {
    if panels.is_empty() || cols == 0 {
        return Err(VizError::PlotData {
            what: "xy grid",
            message: format!("{title:?}: {} panels in {cols} columns", panels.len()),
        });
    }
    for p in panels {
        p.validate()?;
    }
    let cols = cols.min(panels.len());
    let rows = panels.len().div_ceil(cols);
    render_png(path, |root| {
        let err = plot_err(path);
        let inner = root.titled(title, style::title()).map_err(&err)?;
        let areas = inner.split_evenly((rows, cols));
        for (area, p) in areas.iter().zip(panels) {
            draw(area, path, &p.drawn(), Fonts::PANEL)?;
        }
        Ok(())
    })
}

/// Text sizes of a full figure or of a panel in a grid.
#[derive(Clone, Copy)]
struct Fonts {
    title: u32,
    label: u32,
    tick: u32,
    legend: u32,
    margin: u32,
    x_area: u32,
    y_area: u32,
}

impl Fonts {
    const FULL: Fonts = Fonts {
        title: style::TITLE_PX,
        label: style::LABEL_PX,
        tick: style::TICK_PX,
        legend: style::LEGEND_PX,
        margin: style::MARGIN_PX,
        x_area: style::X_LABEL_AREA_PX,
        y_area: style::Y_LABEL_AREA_PX,
    };
    const PANEL: Fonts = Fonts {
        title: 20,
        label: 17,
        tick: 15,
        legend: 15,
        margin: 12,
        x_area: 52,
        y_area: 72,
    };
}

fn draw(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    path: &Path,
    plot: &XyPlot,
    f: Fonts,
) -> Result<()> {
    let err = plot_err(path);
    let (w, h) = area.dim_in_pixel();
    // The plotting area left once margins, caption and label areas are taken.
    let pw = (f64::from(w) - f64::from(2 * f.margin + f.y_area)).max(10.0);
    let ph =
        (f64::from(h) - f64::from(2 * f.margin + f.x_area) - 1.6 * f64::from(f.title)).max(10.0);
    let ((x_lo, x_hi), (y_lo, y_hi)) = plot.ranges(pw, ph);
    let title = (FontFamily::SansSerif, f.title)
        .into_font()
        .style(FontStyle::Bold)
        .color(&style::INK);
    let mut chart = ChartBuilder::on(area)
        .caption(&plot.title, title)
        .margin(f.margin)
        .x_label_area_size(f.x_area)
        .y_label_area_size(f.y_area)
        .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)
        .map_err(&err)?;
    let axis_fonts = AxisFonts {
        label: f.label,
        tick: f.tick,
        legend: f.legend,
    };
    style::draw_mesh(
        &mut chart,
        path,
        (&plot.x_label, plot.x_scale),
        &plot.y_label,
        axis_fonts,
    )?;

    let mut any_legend = false;
    for layer in &plot.layers {
        let (look, context) = match layer.style {
            XyStyle::Series(i) => (style::SERIES[i % style::SERIES.len()], false),
            XyStyle::Context => (
                style::SeriesStyle {
                    color: style::LIGHT_GREY,
                    width: 1,
                    dash: Dash::Solid,
                    marker: Marker::Circle,
                },
                true,
            ),
        };
        let stroke = look.stroke();
        let dashed =
            |pts: Vec<(f64, f64)>| -> Vec<DynElement<'static, BitMapBackend<'_>, (f64, f64)>> {
                match look.dash {
                    Dash::Solid => vec![PathElement::new(pts, stroke).into_dyn()],
                    Dash::Dashed { on, off } => {
                        vec![DashedPathElement::new(pts, on, off, stroke).into_dyn()]
                    }
                }
            };
        let legend_marker = match &layer.kind {
            LayerKind::Path(p) => {
                let pts: Vec<(f64, f64)> = p.iter().map(|q| (q[0], q[1])).collect();
                chart.draw_series(dashed(pts)).map_err(&err)?;
                None
            }
            LayerKind::Segments(s) => {
                let elems = s
                    .iter()
                    .flat_map(|[a, b]| dashed(vec![(a[0], a[1]), (b[0], b[1])]));
                chart.draw_series(elems).map_err(&err)?;
                None
            }
            LayerKind::Ellipses(e) => {
                let elems = e.iter().flat_map(|e| {
                    let mut pts: Vec<(f64, f64)> = e
                        .points(ELLIPSE_POINTS)
                        .iter()
                        .map(|q| (q[0], q[1]))
                        .collect();
                    pts.push(pts[0]);
                    dashed(pts)
                });
                chart.draw_series(elems).map_err(&err)?;
                None
            }
            LayerKind::Points(p) => {
                let marker = if look.marker == Marker::None {
                    Marker::Circle
                } else {
                    look.marker
                };
                let r = if context { 2 } else { 5 };
                match marker {
                    Marker::Cross => {
                        chart
                            .draw_series(p.iter().map(|q| Cross::new((q[0], q[1]), r, stroke)))
                            .map_err(&err)?;
                    }
                    _ => {
                        chart
                            .draw_series(
                                p.iter()
                                    .map(|q| Circle::new((q[0], q[1]), r, look.color.filled())),
                            )
                            .map_err(&err)?;
                    }
                }
                Some(marker)
            }
            LayerKind::Labels(l) => {
                let font = style::text(f.tick).pos(Pos::new(HPos::Left, VPos::Bottom));
                chart
                    .draw_series(
                        l.iter()
                            .map(|(q, s)| Text::new(s.clone(), (q[0], q[1]), font.clone())),
                    )
                    .map_err(&err)?;
                continue;
            }
        };
        if layer.name.is_empty() {
            continue;
        }
        any_legend = true;
        // A legend entry needs a series to hang on: an empty one, drawn nowhere.
        let anno = chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(&err)?;
        let color = look.color;
        anno.label(layer.name.clone())
            .legend(move |(x, y)| match legend_marker {
                Some(Marker::Cross) => Cross::new((x + 15, y), 5, stroke).into_dyn(),
                Some(_) => Circle::new((x + 15, y), 5, color.filled()).into_dyn(),
                None => style::Key {
                    at: (x, y),
                    look: style::SeriesStyle {
                        marker: Marker::None,
                        ..look
                    },
                }
                .into_dyn(),
            });
    }
    if any_legend {
        style::draw_legend(&mut chart, path, plot.legend, axis_fonts)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plot() -> XyPlot {
        XyPlot {
            title: "t".into(),
            x_label: "x (m)".into(),
            x_scale: AxisScale::Linear,
            y_label: "y (m)".into(),
            layers: vec![
                Layer {
                    name: "path".into(),
                    style: XyStyle::Series(0),
                    kind: LayerKind::Path(vec![[0.0, 0.0], [100.0, 10.0]]),
                },
                Layer {
                    name: String::new(),
                    style: XyStyle::Context,
                    kind: LayerKind::Points(vec![[50.0, 5.0]]),
                },
            ],
            legend: LegendPos::UpperLeft,
            x_range: None,
            y_range: None,
        }
    }

    /// An ellipse layer (a validation gate).
    fn gate() -> Layer {
        Layer {
            name: "gate".into(),
            style: XyStyle::Series(3),
            kind: LayerKind::Ellipses(vec![ErrorEllipse {
                centre: [50.0, 5.0],
                semi_axes: [20.0, 5.0],
                angle: 0.3,
            }]),
        }
    }

    #[test]
    fn fitted_ranges_have_equal_scale_and_cover_the_data() {
        let p = plot();
        let ((x0, x1), (y0, y1)) = p.ranges(1000.0, 500.0);
        assert!((((x1 - x0) / 1000.0) - ((y1 - y0) / 500.0)).abs() < 1e-12);
        assert!(x0 < 0.0 && x1 > 100.0 && y0 < 0.0 && y1 > 10.0);
    }

    #[test]
    fn non_finite_layers_and_empty_plots_are_rejected() {
        let mut p = plot();
        p.validate().unwrap();
        p.layers[1].kind = LayerKind::Points(vec![[f64::NAN, 0.0]]);
        assert!(p.validate().is_err());
        p.layers.clear();
        assert!(p.validate().is_err());
        let mut q = plot();
        q.x_range = Some((1.0, 1.0));
        assert!(q.validate().is_err());
    }

    /// A log scale maps the x of every layer and of the fixed range, keeps y, and refuses
    /// ellipses and values it cannot place.
    #[test]
    fn log_scaled_layers_are_mapped_and_checked() {
        let mut p = plot();
        p.x_scale = AxisScale::Log10;
        p.layers[0].kind = LayerKind::Path(vec![[1.0, 0.0], [100.0, 10.0]]);
        p.layers[1].kind = LayerKind::Labels(vec![([10.0, 5.0], "a".into())]);
        p.x_range = Some((1.0, 1000.0));
        p.validate().unwrap();
        let d = p.drawn();
        assert_eq!(
            d.layers[0].kind,
            LayerKind::Path(vec![[0.0, 0.0], [2.0, 10.0]])
        );
        assert_eq!(
            d.layers[1].kind,
            LayerKind::Labels(vec![([1.0, 5.0], "a".into())])
        );
        assert_eq!(d.x_range, Some((0.0, 3.0)));
        let mut zero = p.clone();
        zero.x_range = Some((0.0, 1000.0));
        assert!(zero.validate().is_err());
        p.layers.push(gate());
        let err = p.validate().unwrap_err().to_string();
        assert!(err.contains("ellipses"), "{err}");
    }

    #[test]
    fn renders_single_and_grid() {
        let dir = std::env::temp_dir().join(format!("pf-viz-xy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut p = plot();
        p.layers.push(gate());
        render(&dir.join("one.png"), &p).unwrap();
        render_grid(&dir.join("grid.png"), "grid", &[p.clone(), p], 2).unwrap();
        for f in ["one.png", "grid.png"] {
            let bytes = std::fs::read(dir.join(f)).unwrap();
            assert_eq!(&bytes[1..4], b"PNG");
            assert!(bytes.len() > 5_000, "{f} is not blank");
        }
        if std::env::var_os("PF_VIZ_KEEP_PNG").is_none() {
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }
}
