//! The shared look of every pf-viz figure.
//!
//! 1200×800 px on white, DejaVu Sans embedded in the binary (no system font is read), a
//! title of 28 px, axis descriptions of 22 px, tick labels and legends of 18 px. Series are
//! told apart by lightness *and* by dash pattern or marker, so a figure survives greyscale
//! printing.

use std::sync::OnceLock;

use plotters::element::{Circle, Cross, DashedPathElement, Drawable, PointCollection, Rectangle};
use plotters::style::{
    Color, FontFamily, FontStyle, IntoFont, RGBColor, ShapeStyle, TextStyle, register_font,
};
use plotters_backend::{BackendCoord, DrawingBackend, DrawingErrorKind};

use crate::error::{Result, VizError};

/// Figure size in pixels, width × height.
pub const SIZE: (u32, u32) = (1200, 800);
/// Title font size, px.
pub const TITLE_PX: u32 = 28;
/// Axis description font size, px.
pub const LABEL_PX: u32 = 22;
/// Tick label font size, px.
pub const TICK_PX: u32 = 18;
/// Legend font size, px.
pub const LEGEND_PX: u32 = 18;
/// Outer margin, px.
pub const MARGIN_PX: u32 = 24;
/// Space reserved below the plot for tick labels and the x-axis description, px.
pub const X_LABEL_AREA_PX: u32 = 70;
/// Space reserved left of the plot for tick labels and the y-axis description, px.
pub const Y_LABEL_AREA_PX: u32 = 90;

/// Near-black, for the series that carries the message.
pub const INK: RGBColor = RGBColor(25, 25, 25);
/// Dark blue: the emphasised series (dark in greyscale too).
pub const DARK_BLUE: RGBColor = RGBColor(20, 60, 140);
/// Dark red: markers and thresholds (mid-dark in greyscale; always drawn dashed).
pub const DARK_RED: RGBColor = RGBColor(180, 30, 30);
/// Mid grey: secondary series.
pub const MID_GREY: RGBColor = RGBColor(120, 120, 120);
/// Grey of scatter points drawn as context.
pub const POINT_GREY: RGBColor = RGBColor(150, 150, 150);
/// Light grey: context drawn behind everything else.
pub const LIGHT_GREY: RGBColor = RGBColor(200, 200, 200);
/// Grid lines.
pub const GRID: RGBColor = RGBColor(232, 232, 232);

/// The font family name the embedded font is registered under.
const FAMILY: &str = "sans-serif";

static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
static DEJAVU_SANS_BOLD: &[u8] = include_bytes!("../../assets/DejaVuSans-Bold.ttf");

/// Register the embedded fonts with plotters, once per process. Every renderer calls this
/// before drawing text.
///
/// # Errors
/// [`VizError::PlotData`] if the embedded font cannot be parsed (a build defect).
pub fn init_fonts() -> Result<()> {
    static DONE: OnceLock<Result<(), String>> = OnceLock::new();
    DONE.get_or_init(|| {
        register_font(FAMILY, FontStyle::Normal, DEJAVU_SANS)
            .and_then(|()| register_font(FAMILY, FontStyle::Bold, DEJAVU_SANS_BOLD))
            .map_err(|_| "the embedded DejaVu Sans font cannot be parsed".to_owned())
    })
    .clone()
    .map_err(|message| VizError::PlotData {
        what: "font",
        message,
    })
}

/// Text in the embedded font at `px` pixels.
pub fn text(px: u32) -> TextStyle<'static> {
    (FontFamily::SansSerif, px).into_font().color(&INK)
}

/// The figure title style.
pub fn title() -> TextStyle<'static> {
    (FontFamily::SansSerif, TITLE_PX)
        .into_font()
        .style(FontStyle::Bold)
        .color(&INK)
}

/// How a line series is stroked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dash {
    /// A continuous line.
    Solid,
    /// Dashes of `on` px separated by `off` px.
    Dashed {
        /// Dash length, px.
        on: u32,
        /// Gap length, px.
        off: u32,
    },
}

/// A marker drawn at every data point of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// No marker.
    None,
    /// A filled circle.
    Circle,
    /// An upright cross.
    Cross,
    /// A filled square: what a series without a marker of its own shows at each of a few
    /// measured points (see `png::line`).
    Square,
}

/// The complete look of one line series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeriesStyle {
    /// Line colour.
    pub color: RGBColor,
    /// Line width, px.
    pub width: u32,
    /// Stroke pattern.
    pub dash: Dash,
    /// Point marker.
    pub marker: Marker,
}

/// Length of a legend key, px.
pub const KEY_PX: i32 = 30;
/// Radius of a circle marker, px.
pub const CIRCLE_PX: i32 = 4;
/// Half-width of a cross marker, px.
pub const CROSS_PX: i32 = 5;

impl SeriesStyle {
    /// The plotters stroke of this series.
    pub fn stroke(&self) -> ShapeStyle {
        self.color.stroke_width(self.width)
    }
}

/// Series styles in the order figures use them: each differs from the others in greyscale
/// (lightness) and in pattern, so no colour is needed to tell them apart.
pub const SERIES: [SeriesStyle; 4] = [
    SeriesStyle {
        color: DARK_BLUE,
        width: 3,
        dash: Dash::Solid,
        marker: Marker::None,
    },
    SeriesStyle {
        color: MID_GREY,
        width: 3,
        dash: Dash::Dashed { on: 12, off: 8 },
        marker: Marker::None,
    },
    SeriesStyle {
        color: INK,
        width: 2,
        dash: Dash::Solid,
        marker: Marker::Circle,
    },
    SeriesStyle {
        color: DARK_RED,
        width: 2,
        dash: Dash::Dashed { on: 4, off: 6 },
        marker: Marker::Cross,
    },
];

/// The legend key of a series at `at`: its stroke, dash pattern and marker, so that the
/// key looks like the line it names. (An element of its own: plotters' composed elements
/// carry the backend's lifetime, which a legend closure may not return.)
#[derive(Debug, Clone, Copy)]
pub struct Key {
    /// The key's left end, in pixels.
    pub at: BackendCoord,
    /// The series drawn.
    pub look: SeriesStyle,
}

impl<'a> PointCollection<'a, BackendCoord> for &'a Key {
    type Point = &'a BackendCoord;
    type IntoIter = std::iter::Once<&'a BackendCoord>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.at)
    }
}

impl<DB: DrawingBackend> Drawable<DB> for Key {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut pos: I,
        backend: &mut DB,
        dim: (u32, u32),
    ) -> std::result::Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = pos.next() else {
            return Ok(());
        };
        let stroke = self.look.stroke();
        // A solid key is one dash as long as the key.
        let (on, off) = match self.look.dash {
            Dash::Solid => (KEY_PX as u32, 0),
            Dash::Dashed { on, off } => (on, off),
        };
        let line = [(x, y), (x + KEY_PX, y)];
        DashedPathElement::new(line, on, off, stroke).draw(line.into_iter(), backend, dim)?;
        let mid = std::iter::once((x + KEY_PX / 2, y));
        match self.look.marker {
            Marker::None => Ok(()),
            Marker::Circle => {
                Circle::new((0, 0), CIRCLE_PX, self.look.color.filled()).draw(mid, backend, dim)
            }
            Marker::Cross => Cross::new((0, 0), CROSS_PX, stroke).draw(mid, backend, dim),
            Marker::Square => {
                // A rectangle draws from its two corners, in pixels here.
                let (cx, r) = (x + KEY_PX / 2, CIRCLE_PX);
                let corners = [(cx - r, y - r), (cx + r, y + r)];
                Rectangle::new(corners, self.look.color.filled()).draw(
                    corners.into_iter(),
                    backend,
                    dim,
                )
            }
        }
    }
}

/// Shaded bands (confidence or Monte Carlo intervals) use the series colour at this opacity.
pub const BAND_ALPHA: f64 = 0.18;

/// Where a legend sits inside the plot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LegendPos {
    /// Top left corner.
    #[default]
    UpperLeft,
    /// Top right corner.
    UpperRight,
    /// Bottom left corner.
    LowerLeft,
    /// Bottom right corner.
    LowerRight,
}

impl LegendPos {
    /// The plotters position.
    pub fn to_plotters(self) -> plotters::chart::SeriesLabelPosition {
        use plotters::chart::SeriesLabelPosition as P;
        match self {
            LegendPos::UpperLeft => P::UpperLeft,
            LegendPos::UpperRight => P::UpperRight,
            LegendPos::LowerLeft => P::LowerLeft,
            LegendPos::LowerRight => P::LowerRight,
        }
    }
}

/// Pad a data range by `frac` of its width on both sides (and widen a degenerate range), so
/// nothing is drawn on the frame.
pub fn padded(lo: f64, hi: f64, frac: f64) -> (f64, f64) {
    let (lo, hi) = if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (0.0, 1.0)
    };
    let w = hi - lo;
    if w <= f64::EPSILON * lo.abs().max(hi.abs()).max(1.0) {
        let h = lo.abs().max(1.0) * 0.5;
        (lo - h, hi + h)
    } else {
        (lo - frac * w, hi + frac * w)
    }
}

/// A tick label without trailing zeros: `20`, `0.5`, `1e-3`.
pub fn tick_label(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if v.abs() >= 1e5 || v.abs() < 1e-3 {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_owned()
}

/// A chart on f64 axes, as every plot kind draws.
pub type Chart<'a, 'b> = plotters::chart::ChartContext<
    'a,
    plotters::prelude::BitMapBackend<'b>,
    plotters::coord::cartesian::Cartesian2d<
        plotters::coord::types::RangedCoordf64,
        plotters::coord::types::RangedCoordf64,
    >,
>;

/// Text sizes of the axes and legend: [`AxisFonts::FULL`] for a figure, smaller for a panel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AxisFonts {
    /// Axis descriptions, px.
    pub label: u32,
    /// Tick labels, px.
    pub tick: u32,
    /// Legend entries, px.
    pub legend: u32,
}

impl AxisFonts {
    /// The sizes of a full figure.
    pub const FULL: AxisFonts = AxisFonts {
        label: LABEL_PX,
        tick: TICK_PX,
        legend: LEGEND_PX,
    };
}

/// How an x axis places its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisScale {
    /// Evenly.
    #[default]
    Linear,
    /// By their base-10 logarithm, for sweeps over decades (lags, particle counts); every
    /// value must be positive. The ticks show the values, one per decade.
    Log10,
}

impl AxisScale {
    /// Where `x` is drawn. The charts stay linear in what they draw: plotters' own log
    /// coordinates would give a log-scaled chart a type of its own, which every renderer's
    /// drawing code would then have to be generic over.
    pub fn map(self, x: f64) -> f64 {
        match self {
            AxisScale::Linear => x,
            AxisScale::Log10 => x.log10(),
        }
    }

    /// The value drawn at `t`, for its tick label.
    fn unmap(self, t: f64) -> f64 {
        match self {
            AxisScale::Linear => t,
            // Decades exactly, so that ticks read 10 and 100, not 99.99999999999997.
            AxisScale::Log10 if t == t.round() => 10f64.powi(t as i32),
            AxisScale::Log10 => 10f64.powf(t),
        }
    }

    /// The first value that cannot be drawn on this scale (≤ 0 or NaN on a log scale).
    pub fn first_unplaceable(self, xs: impl IntoIterator<Item = f64>) -> Option<f64> {
        match self {
            AxisScale::Linear => None,
            AxisScale::Log10 => xs.into_iter().find(|&x| x.is_nan() || x <= 0.0),
        }
    }
}

/// Draw the shared mesh: light grid, ink axes, short tick labels, axis descriptions. On a
/// [`AxisScale::Log10`] x axis the chart's x coordinates are logarithms: the ticks sit at
/// the whole decades in the range, where it holds any, and show their values.
///
/// # Errors
/// A plot error naming `path`.
pub fn draw_mesh(
    chart: &mut Chart<'_, '_>,
    path: &std::path::Path,
    (x_label, x_scale): (&str, AxisScale),
    y_label: &str,
    fonts: AxisFonts,
) -> Result<()> {
    use plotters::style::Color;
    let x_ticks = match x_scale {
        AxisScale::Linear => 10,
        AxisScale::Log10 => {
            let r = chart.x_range();
            // One label per whole decade in the range (plotters then puts them there).
            (r.end.floor() - r.start.ceil()).max(0.0) as usize + 1
        }
    };
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .axis_desc_style(text(fonts.label))
        .label_style(text(fonts.tick))
        .x_labels(x_ticks)
        .x_label_formatter(&|x| tick_label(x_scale.unmap(*x)))
        .y_label_formatter(&|y| tick_label(*y))
        .bold_line_style(GRID.stroke_width(1))
        .light_line_style(plotters::style::WHITE.stroke_width(0))
        .axis_style(INK.stroke_width(1))
        .draw()
        .map_err(plot_err(path))
}

/// Draw the legend of the labelled series, in the shared frame.
///
/// # Errors
/// A plot error naming `path`.
pub fn draw_legend<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    path: &std::path::Path,
    position: LegendPos,
    fonts: AxisFonts,
) -> Result<()> {
    use plotters::style::Color;
    chart
        .configure_series_labels()
        .position(position.to_plotters())
        .margin(12)
        .legend_area_size(40)
        .label_font(text(fonts.legend))
        .background_style(plotters::style::WHITE.mix(0.88))
        .border_style(MID_GREY)
        .draw()
        .map_err(plot_err(path))
}

/// Map a plotters drawing error to [`VizError::Plot`] for the figure at `path`.
pub fn plot_err<E: std::fmt::Display>(path: &std::path::Path) -> impl Fn(E) -> VizError + '_ {
    move |e| VizError::Plot {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Which pixels of a 40×20 canvas a legend key at (5, 10) inks.
    fn key_ink(look: SeriesStyle) -> impl Fn(u32, u32) -> bool {
        use plotters::prelude::{BitMapBackend, IntoDrawingArea};
        let (w, h) = (40u32, 20u32);
        let mut buf = vec![255u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            root.draw(&Key { at: (5, 10), look }).unwrap();
            root.present().unwrap();
        }
        move |x, y| buf[((y * w + x) * 3) as usize..][..3] != [255, 255, 255]
    }

    /// A key shows its series' dash pattern and marker: a solid key is inked through the
    /// middle of its length, a dashed one has a gap there (its first 12 px dash ends at
    /// x = 17, the 8 px gap runs to 25), and only a series with a cross has ink on the
    /// cross's arm above the line.
    #[test]
    fn legend_keys_look_like_their_series() {
        let solid = key_ink(SERIES[0]);
        let dashed = key_ink(SERIES[1]);
        let crossed = key_ink(SERIES[3]);
        assert!(solid(21, 10) && solid(8, 10) && solid(33, 10));
        assert!(dashed(8, 10) && !dashed(21, 10) && dashed(30, 10));
        let arm = (5 + KEY_PX as u32 / 2 - 3, 10 - 3);
        assert!(crossed(arm.0, arm.1));
        assert!(!solid(arm.0, arm.1) && !dashed(arm.0, arm.1));
        // A square's corner is inked off the line, where a circle's is not.
        let squared = key_ink(SeriesStyle {
            marker: Marker::Square,
            ..SERIES[0]
        });
        let circled = key_ink(SeriesStyle {
            marker: Marker::Circle,
            ..SERIES[0]
        });
        // One pixel inside the square's corner: √18 px from the centre, beyond the circle.
        let corner = (
            5 + KEY_PX as u32 / 2 + CIRCLE_PX as u32 - 1,
            10 - CIRCLE_PX as u32 + 1,
        );
        assert!(squared(corner.0, corner.1) && !circled(corner.0, corner.1));
        assert!(!solid(corner.0, corner.1));
    }

    #[test]
    fn fonts_register_and_repeat() {
        init_fonts().unwrap();
        init_fonts().unwrap();
    }

    /// A log axis draws decades at whole numbers and labels them with the exact values;
    /// it cannot place zero, negative or NaN values, and a linear axis places everything.
    #[test]
    fn log_axes_map_decades_and_refuse_what_they_cannot_place() {
        let log = AxisScale::Log10;
        assert_eq!(log.map(1000.0), 3.0);
        for (t, label) in [(0.0, "1"), (1.0, "10"), (2.0, "100"), (4.0, "10000")] {
            assert_eq!(tick_label(log.unmap(t)), label);
        }
        assert_eq!(tick_label(log.unmap(0.5)), "3.162");
        assert_eq!(log.first_unplaceable([3.0, 0.0, -1.0]), Some(0.0));
        assert!(log.first_unplaceable([f64::NAN]).is_some_and(f64::is_nan));
        assert_eq!(log.first_unplaceable([1e-300, 5.0]), None);
        assert_eq!(AxisScale::Linear.first_unplaceable([0.0, -1.0]), None);
        assert_eq!(AxisScale::Linear.unmap(-2.5), -2.5);
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(20.0), "20");
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(-1.25), "-1.25");
        assert_eq!(tick_label(0.0), "0");
    }

    #[test]
    fn padding_widens_and_handles_degenerate_ranges() {
        assert_eq!(padded(0.0, 10.0, 0.1), (-1.0, 11.0));
        let (lo, hi) = padded(3.0, 3.0, 0.1);
        assert!(lo < 3.0 && hi > 3.0);
        assert_eq!(padded(f64::NAN, 1.0, 0.0), (0.0, 1.0));
    }
}
