//! A particle genealogy as a Rerun recording, scrubbable along the `step` timeline.
//!
//! | entity | archetype | at step `k` |
//! |---|---|---|
//! | `core/genealogy/all` | `LineStrips2D` | every parent → child segment up to `k`, thin light grey |
//! | `core/genealogy/particles` | `Points2D` | every particle position up to `k`, small grey |
//! | `core/genealogy/current` | `Points2D` | the particles of step `k`, area ∝ weight |
//! | `core/genealogy/lineage_<i>` | `LineStrips2D` | the ancestral line `ξ_{0:k}^i` of particle `i` at `k`, dark |
//! | `core/genealogy/coalescence` | `LineStrips2D` | the coalescence time, at the last step |
//! | `core/genealogy/axes` | `LineStrips2D`, `Points2D` | static axes with ticks in `k` and `ξ` |
//! | `core/ess` | `Scalars` | the effective sample size |
//!
//! At the last step the `lineage_<i>` strips are exactly the surviving lineages of the PNG
//! figure; earlier, they show how the ancestry of the current particles coalesces.
//!
//! Rerun's 2D view has its y-axis pointing down and equal scales on both axes, so a point is
//! logged at `(k, −c·ξ)`, with `c` chosen to give the picture a 5:2 aspect ratio; the axis
//! ticks are labelled in `k` and `ξ`, so `c` never needs to be known.

use std::path::Path;

use pf_core::genealogy::Genealogy;
use rerun::components::Radius;
use rerun::{LineStrips2D, Points2D, RecordingStream, Scalars, SeriesLines};

use super::layout::{self, Bounds, Node, View};
use super::{STEP, rrd_err, save_rrd};
use crate::error::{Result, VizError};
use crate::figure::{GenealogyData, validate_genealogy};

/// Root entity of the genealogy.
pub const ROOT: &str = "core/genealogy";
/// The paper prefix of the core recording's entities.
const PREFIX: &str = "core";
/// Entity of the ESS trace.
pub const ESS: &str = "core/ess";

const LIGHT: [u8; 4] = [130, 130, 130, 120];
const GREY: [u8; 4] = [110, 110, 110, 255];
const DARK_BLUE: [u8; 4] = [40, 90, 200, 255];
const CURRENT: [u8; 4] = [240, 170, 40, 255];
const RED: [u8; 4] = [220, 50, 50, 255];
const AXIS: [u8; 4] = [200, 200, 200, 255];

/// What a genealogy recording shows besides [`GenealogyData`].
#[derive(Debug, Clone, Copy)]
pub struct GenealogyExtras<'a> {
    /// The engine's genealogy (for the ancestral lines of every step).
    pub genealogy: &'a Genealogy,
    /// `weights[k][i] = W_k^i`, normalised.
    pub weights: &'a [Vec<f64>],
    /// Effective sample size of every step.
    pub ess: &'a [f64],
}

/// The picture's coordinates: `(k, −c·ξ)`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Frame {
    c: f64,
}

impl Frame {
    pub(super) fn new(data: &GenealogyData) -> Self {
        let (lo, hi) = data
            .positions
            .iter()
            .flatten()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
        let span = (hi - lo).max(1e-9);
        let width = (data.n_steps().max(2) - 1) as f64;
        Frame {
            c: 0.4 * width / span,
        }
    }

    pub(super) fn at(&self, k: usize, x: f64) -> [f32; 2] {
        [k as f32, (-self.c * x) as f32]
    }
}

/// Write the genealogy recording to `path` (atomically).
///
/// # Errors
/// Inconsistent data, or a Rerun or I/O error naming `path`.
pub fn save(path: &Path, data: &GenealogyData, extras: &GenealogyExtras<'_>) -> Result<()> {
    validate_genealogy(data)?;
    let (steps, n) = (data.n_steps(), data.n_particles());
    if extras.genealogy.n_steps() != steps
        || extras.genealogy.n_particles() != n
        || extras.weights.len() != steps
        || extras.ess.len() != steps
        || extras.weights.iter().any(|w| w.len() != n)
    {
        return Err(VizError::PlotData {
            what: "genealogy recording",
            message: format!(
                "shapes disagree: {steps}×{n} positions, genealogy {}×{}, {} weight rows, {} ESS values",
                extras.genealogy.n_steps(),
                extras.genealogy.n_particles(),
                extras.weights.len(),
                extras.ess.len()
            ),
        });
    }
    save_rrd(path, "pf-viz: particle genealogy", |rec, path| {
        layout::send(rec, &blueprint(frame_bounds(data)), None).map_err(rrd_err(path))?;
        log_genealogy(rec, path, data, extras, PREFIX)
    })
}

/// Log the genealogy under `{prefix}/genealogy` and the ESS trace under `{prefix}/ess`
/// into an open recording, on the `step` timeline (no blueprint: the caller lays out its
/// recording). `path` only names the file in errors.
///
/// # Errors
/// A Rerun error naming `path`, or an inconsistent genealogy.
pub fn log_genealogy(
    rec: &RecordingStream,
    path: &Path,
    data: &GenealogyData,
    extras: &GenealogyExtras<'_>,
    prefix: &str,
) -> Result<()> {
    let err = rrd_err(path);
    let frame = Frame::new(data);
    let (steps, n) = (data.n_steps(), data.n_particles());
    let root = format!("{prefix}/genealogy");
    let ess_entity = format!("{prefix}/ess");

    log_axes(rec, data, frame, &root).map_err(&err)?;
    rec.log_static(
        ess_entity.as_str(),
        &SeriesLines::new()
            .with_names(["effective sample size"])
            .with_colors([DARK_BLUE])
            .with_widths([2.0]),
    )
    .map_err(&err)?;

    let mut segments: Vec<[[f32; 2]; 2]> = Vec::with_capacity(n * steps);
    let mut points: Vec<[f32; 2]> = Vec::with_capacity(n * steps);
    for k in 0..steps {
        rec.set_time_sequence(STEP, k as i64);
        if k > 0 {
            for i in 0..n {
                let a = data.ancestors[k][i];
                segments.push([
                    frame.at(k - 1, data.positions[k - 1][a]),
                    frame.at(k, data.positions[k][i]),
                ]);
            }
            rec.log(
                format!("{root}/all"),
                &LineStrips2D::new(segments.iter().map(|s| s.to_vec()))
                    .with_colors([LIGHT])
                    .with_radii([Radius::new_ui_points(0.5)])
                    .with_draw_order(10.0),
            )
            .map_err(&err)?;
        }
        points.extend(data.positions[k].iter().map(|&x| frame.at(k, x)));
        rec.log(
            format!("{root}/particles"),
            &Points2D::new(points.iter().copied())
                .with_colors([GREY])
                .with_radii([Radius::new_ui_points(1.5)])
                .with_draw_order(20.0),
        )
        .map_err(&err)?;
        // Area ∝ weight: radius ∝ √(N·W), so equal weights give the base size.
        let radii = extras.weights[k]
            .iter()
            .map(|&w| Radius::new_ui_points((2.5 * (n as f64 * w).sqrt()).clamp(1.0, 12.0) as f32));
        rec.log(
            format!("{root}/current"),
            &Points2D::new(data.positions[k].iter().map(|&x| frame.at(k, x)))
                .with_colors([CURRENT])
                .with_radii(radii)
                .with_draw_order(40.0),
        )
        .map_err(&err)?;
        for i in 0..n {
            let line = extras
                .genealogy
                .lineage_at(k, i)
                .map_err(VizError::core("rrd genealogy"))?;
            let strip: Vec<[f32; 2]> = line
                .iter()
                .enumerate()
                .map(|(j, &idx)| frame.at(j, data.positions[j][idx]))
                .collect();
            rec.log(
                format!("{root}/lineage_{i}"),
                &LineStrips2D::new([strip])
                    .with_colors([DARK_BLUE])
                    .with_radii([Radius::new_ui_points(1.5)])
                    .with_draw_order(30.0),
            )
            .map_err(&err)?;
        }
        rec.log(ess_entity.as_str(), &Scalars::single(extras.ess[k]))
            .map_err(&err)?;
    }
    if let Some(t) = data.coalescence_time {
        let (lo, hi) = y_extent(data, frame);
        rec.log(
            format!("{root}/coalescence"),
            &LineStrips2D::new([[[t as f32, lo], [t as f32, hi]]])
                .with_colors([RED])
                .with_radii([Radius::new_ui_points(2.0)])
                .with_labels([format!("coalescence τ = {t}")])
                .with_draw_order(50.0),
        )
        .map_err(&err)?;
    }
    Ok(())
}

/// Lowest and highest picture y, padded a little.
fn y_extent(data: &GenealogyData, frame: Frame) -> (f32, f32) {
    let ys = data.positions.iter().flatten().map(|&x| frame.at(0, x)[1]);
    let (lo, hi) = ys.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), y| {
        (lo.min(y), hi.max(y))
    });
    let pad = 0.04 * (hi - lo).max(1e-6);
    (lo - pad, hi + pad)
}

/// The picture with its axes and their labels, and a margin, for a view to open on.
pub(super) fn frame_bounds(data: &GenealogyData) -> Option<Bounds> {
    let frame = Frame::new(data);
    let (top, bottom) = y_extent(data, frame);
    let last = data.n_steps().saturating_sub(1) as f32;
    // The ξ labels reach about 8 % of the width left of the axis, the k labels 6 % of the
    // height below it.
    let corners = [
        [-0.08 * last.max(1.0), top],
        [last, bottom + 0.06 * (bottom - top)],
    ];
    Bounds::around(corners, 0.03)
}

/// Static axes: a frame, ticks every ~10 % in `k`, and ticks at round values of `ξ`.
pub(super) fn log_axes(
    rec: &RecordingStream,
    data: &GenealogyData,
    frame: Frame,
    root: &str,
) -> rerun::RecordingStreamResult<()> {
    let last = data.n_steps() - 1;
    let (top, bottom) = y_extent(data, frame);
    let left = -0.02 * last.max(1) as f32;
    let right = last as f32;
    rec.log_static(
        format!("{root}/axes/frame"),
        &LineStrips2D::new([vec![[left, top], [left, bottom], [right, bottom]]])
            .with_colors([AXIS])
            .with_radii([Radius::new_ui_points(0.75)])
            .with_draw_order(1.0),
    )?;
    let k_step = nice_step(last as f64 / 8.0).max(1.0) as usize;
    let k_ticks: Vec<usize> = (0..=last).step_by(k_step).collect();
    let tick_len = 0.015 * (bottom - top);
    rec.log_static(
        format!("{root}/axes/k"),
        &Points2D::new(k_ticks.iter().map(|&k| [k as f32, bottom + 2.0 * tick_len]))
            .with_labels(k_ticks.iter().map(|k| format!("k = {k}")))
            .with_colors([AXIS])
            .with_radii([Radius::new_ui_points(2.0)])
            .with_show_labels(true),
    )?;
    let (x_lo, x_hi) = data
        .positions
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        });
    let x_step = nice_step((x_hi - x_lo) / 8.0);
    let first = (x_lo / x_step).ceil() as i64;
    let last_tick = (x_hi / x_step).floor() as i64;
    let x_ticks: Vec<f64> = (first..=last_tick).map(|j| j as f64 * x_step).collect();
    rec.log_static(
        format!("{root}/axes/xi"),
        &Points2D::new(x_ticks.iter().map(|&x| [left, frame.at(0, x)[1]]))
            .with_labels(x_ticks.iter().map(|x| format!("ξ = {}", fmt_tick(*x))))
            .with_colors([AXIS])
            .with_radii([Radius::new_ui_points(2.0)])
            .with_show_labels(true),
    )?;
    // Faint horizontal grid lines at the ξ ticks.
    rec.log_static(
        format!("{root}/axes/grid"),
        &LineStrips2D::new(x_ticks.iter().map(|&x| {
            let y = frame.at(0, x)[1];
            vec![[left, y], [right, y]]
        }))
        .with_colors([[70, 70, 70, 255]])
        .with_radii([Radius::new_ui_points(0.5)])
        .with_draw_order(2.0),
    )?;
    Ok(())
}

/// 1, 2 or 5 times a power of ten, at least `raw`.
fn nice_step(raw: f64) -> f64 {
    if !(raw > 0.0 && raw.is_finite()) {
        return 1.0;
    }
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * p)
}

fn fmt_tick(x: f64) -> String {
    let s = format!("{x:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// The layout the viewer opens on: the genealogy above, the ESS trace below.
fn blueprint(bounds: Option<Bounds>) -> Node {
    layout::vertical([
        View::spatial_2d(
            "particle genealogy (x: step k, y: position ξ, ticks labelled)",
            ROOT,
        )
        .with_bounds(bounds)
        .into(),
        View::time_series("effective sample size", ESS).into(),
    ])
    .with_shares([3.0, 1.0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps() {
        assert_eq!(nice_step(12.5), 20.0);
        assert_eq!(nice_step(0.7), 1.0);
        assert_eq!(nice_step(0.3), 0.5);
        assert_eq!(nice_step(0.0), 1.0);
        assert_eq!(fmt_tick(-0.0), "0");
        assert_eq!(fmt_tick(1.5), "1.5");
    }
}
