//! The genealogy of a particle system, drawn like Cappé & Moulines (2005), Fig. 1.
//!
//! x: time index `k`; y: particle position `ξ_k^i`. Every parent → child segment
//! `(k − 1, ξ_{k−1}^{A_k^i}) → (k, ξ_k^i)` is drawn thin and light grey; the segments of the
//! surviving lineages (particles with a descendant at the last step) are drawn thick and
//! dark; a dashed vertical line marks the coalescence time, the last step at which all
//! surviving lineages go through one particle. Left of it the path-space particle
//! approximation rests on a single trajectory.
//!
//! ## References
//! O. Cappé, E. Moulines, "On the use of particle filtering for maximum likelihood parameter
//! estimation", EUSIPCO 2005, Fig. 1.

use std::path::Path;

use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::style::{self, plot_err};
use super::{Canvas, render_png};
use crate::error::Result;
use crate::figure::{GenealogyData, genealogy_y_extent, validate_genealogy};

/// Extra y range above the data, as a fraction of the data range, that holds the legend.
const LEGEND_HEADROOM: f64 = 0.36;

/// Title and axis descriptions of a genealogy figure.
#[derive(Debug, Clone, PartialEq)]
pub struct GenealogyLabels {
    /// Figure title.
    pub title: String,
    /// x-axis description, with units.
    pub x: String,
    /// y-axis description, with units.
    pub y: String,
}

/// Draw `data` to the PNG file `path`.
///
/// # Errors
/// Inconsistent data ([`VizError::PlotData`](crate::VizError::PlotData)), or a plot or I/O
/// error naming `path`.
pub fn render(path: &Path, data: &GenealogyData, labels: &GenealogyLabels) -> Result<()> {
    validate_genealogy(data)?;
    render_png(path, |root| draw(root, path, data, labels))
}

fn draw(
    root: &Canvas<'_>,
    path: &Path,
    data: &GenealogyData,
    labels: &GenealogyLabels,
) -> Result<()> {
    let err = plot_err(path);
    let last = (data.n_steps() - 1) as f64;
    let (y_lo, y_hi) = genealogy_y_extent(data);
    let (y_lo, y_hi) = style::padded(y_lo, y_hi, 0.06);
    // Headroom for the legend, so it never hides data.
    let y_hi = y_hi + LEGEND_HEADROOM * (y_hi - y_lo);
    let mut chart = ChartBuilder::on(root)
        .caption(&labels.title, style::title())
        .margin(style::MARGIN_PX)
        .x_label_area_size(style::X_LABEL_AREA_PX)
        .y_label_area_size(style::Y_LABEL_AREA_PX)
        .build_cartesian_2d(-0.01 * last - 0.5..1.01 * last + 0.5, y_lo..y_hi)
        .map_err(&err)?;
    chart
        .configure_mesh()
        .x_desc(&labels.x)
        .y_desc(&labels.y)
        .axis_desc_style(style::text(style::LABEL_PX))
        .label_style(style::text(style::TICK_PX))
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_label_formatter(&|y| format!("{y:.1}"))
        .bold_line_style(style::GRID.stroke_width(1))
        .light_line_style(WHITE.stroke_width(0))
        .axis_style(style::INK.stroke_width(1))
        .draw()
        .map_err(&err)?;

    let x_of = |k: usize| k as f64;
    // Segments of step k, parent at k − 1 → child i at k, optionally only surviving children.
    let segments = |only_surviving: bool| {
        (1..data.n_steps()).flat_map(move |k| {
            (0..data.n_particles())
                .filter(move |&i| !only_surviving || data.surviving[k][i])
                .map(move |i| {
                    let a = data.ancestors[k][i];
                    vec![
                        (x_of(k - 1), data.positions[k - 1][a]),
                        (x_of(k), data.positions[k][i]),
                    ]
                })
        })
    };

    let thin = style::LIGHT_GREY.stroke_width(1);
    chart
        .draw_series(segments(false).map(|p| PathElement::new(p, thin)))
        .map_err(&err)?
        .label("all particle paths (parent → child)")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 30, y)], thin.stroke_width(2)));

    let dot = style::POINT_GREY.filled();
    chart
        .draw_series(
            data.positions
                .iter()
                .enumerate()
                .flat_map(|(k, row)| row.iter().map(move |&x| (x_of(k), x)))
                .map(|c| Circle::new(c, 2, dot)),
        )
        .map_err(&err)?
        .label("particle positions ξₖⁱ")
        .legend(move |(x, y)| Circle::new((x + 15, y), 4, dot));

    let thick = style::DARK_BLUE.stroke_width(3);
    chart
        .draw_series(segments(true).map(|p| PathElement::new(p, thick)))
        .map_err(&err)?
        .label("surviving lineages (descendant at the last step)")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 30, y)], thick));

    if let Some(truth) = &data.truth {
        let ref_style = style::INK.stroke_width(2);
        chart
            .draw_series(DashedLineSeries::new(
                truth.iter().enumerate().map(|(k, &x)| (x_of(k), x)),
                6,
                5,
                ref_style,
            ))
            .map_err(&err)?
            .label("true state xₖ")
            .legend(move |(x, y)| {
                DashedPathElement::new(vec![(x, y), (x + 30, y)], 6, 5, ref_style)
            });
    }

    if let Some(t) = data.coalescence_time {
        let marker = style::DARK_RED.stroke_width(3);
        let t = x_of(t);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(t, y_lo), (t, y_hi)],
                12,
                8,
                marker,
            ))
            .map_err(&err)?
            .label(format!("coalescence time τ = {t:.0}"))
            .legend(move |(x, y)| DashedPathElement::new(vec![(x, y), (x + 30, y)], 8, 5, marker));
        let label_style = style::text(style::LEGEND_PX).color(&style::DARK_RED);
        let label_x = if t < 0.8 * last {
            t + 0.01 * last
        } else {
            t - 0.12 * last
        };
        chart
            .draw_series(std::iter::once(Text::new(
                format!("τ = {t:.0}"),
                (label_x, y_lo + 0.04 * (y_hi - y_lo)),
                label_style,
            )))
            .map_err(&err)?;
    }

    style::draw_legend(
        &mut chart,
        path,
        style::LegendPos::UpperLeft,
        style::AxisFonts::FULL,
    )
}
