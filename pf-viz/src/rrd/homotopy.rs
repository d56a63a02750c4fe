//! `homotopy.rrd`: the OHF correction as λ goes from 0 to 1, and one tracking run.
//!
//! - `lambda` timeline (λ in thousandths, 0…1000): the error ellipse of the OHF's Gaussian
//!   parameterisation at sample 17 (`homotopy/ellipse/lambda`) and the true position.
//! - `step` timeline: target and observer with their trails, the measured bearing as a ray
//!   from the observer (`homotopy/scene/bearing`), and every filter's estimate
//!   (`homotopy/scene/estimate/<filter>`). The last sample is logged again at λ = 0, so
//!   that the `lambda` timeline shows the finished run beside the ellipse.
//!
//! The blueprint shows the two as side-by-side 2-D views, each on a fixed frame, and opens
//! on the `lambda` timeline.

use std::path::Path;

use pf_homotopy::experiments::EllipsesResult;
use pf_homotopy::model::Realisation;
use rerun::components::Radius;
use rerun::{LineStrips2D, Points2D, RecordingStream};

use super::layout::{self, Bounds, Node, View};
use super::{LAMBDA, STEP, rrd_err, save_rrd};
use crate::error::{Result, VizError};

const RED: [u8; 4] = [220, 50, 50, 255];
const GREY: [u8; 4] = [170, 170, 170, 255];
const OBSERVER: [u8; 4] = [240, 170, 40, 255];
/// One colour per filter, in the order of `Algorithm::ALL`.
const FILTERS: [[u8; 4]; 4] = [
    [90, 160, 255, 255],
    [120, 220, 120, 255],
    [230, 90, 230, 255],
    [240, 240, 240, 255],
];
/// Length of a drawn bearing ray (m).
const RAY: f64 = 15_000.0;

/// Write `homotopy.rrd` from the ellipses over λ and one realisation with each filter's
/// position estimates (`(name, estimate per sample)`).
///
/// # Errors
/// Estimates whose length does not match the realisation, or a Rerun or I/O error naming
/// `path`.
pub fn save(
    path: &Path,
    ellipses: &EllipsesResult,
    real: &Realisation,
    estimates: &[(&str, Vec<[f64; 2]>)],
) -> Result<()> {
    let n = real.target.len();
    if real.observer.len() != n || estimates.iter().any(|(_, e)| e.len() != n) {
        return Err(VizError::PlotData {
            what: "homotopy recording",
            message: format!("estimates do not cover the {n} samples of the realisation"),
        });
    }
    save_rrd(path, "pf-viz: optimal homotopy filter", |rec, path| {
        log(rec, ellipses, real, estimates).map_err(rrd_err(path))
    })
}

fn log(
    rec: &RecordingStream,
    ell: &EllipsesResult,
    real: &Realisation,
    estimates: &[(&str, Vec<[f64; 2]>)],
) -> rerun::RecordingStreamResult<()> {
    let f = north_up;
    let outlines: Vec<Vec<[f32; 2]>> = ell
        .ellipses
        .iter()
        .map(|e| {
            let outline = pf_core::gaussian::ErrorEllipse {
                centre: e.center,
                semi_axes: e.semi_axes,
                angle: e.angle,
            }
            .points(72);
            let mut strip: Vec<[f32; 2]> = outline.iter().map(|&p| f(p)).collect();
            strip.push(strip[0]);
            strip
        })
        .collect();
    // Fixed frames: every ellipse with the truth, and both whole tracks, so that the views
    // show the motion instead of following it.
    let ellipse_frame = outlines.iter().flatten().copied().chain([f(ell.truth)]);
    let track_frame =
        (real.target.iter().map(|x| f([x[0], x[1]]))).chain(real.observer.iter().map(|o| f(o.pos)));
    layout::send(
        rec,
        &blueprint(
            Bounds::around(track_frame, 0.06),
            Bounds::around(ellipse_frame, 0.06),
        ),
        Some(LAMBDA),
    )?;
    rec.log_static(
        "homotopy/ellipse/truth",
        &Points2D::new([f(ell.truth)])
            .with_colors([RED])
            .with_radii([Radius::new_ui_points(5.0)])
            .with_labels(["true position"]),
    )?;
    for ((l, e), strip) in ell.lambda.iter().zip(&ell.ellipses).zip(outlines) {
        rec.set_time_sequence(LAMBDA, (l * 1000.0).round() as i64);
        rec.log(
            "homotopy/ellipse/lambda",
            &LineStrips2D::new([strip])
                .with_colors([FILTERS[0]])
                .with_radii([Radius::new_ui_points(2.0)])
                .with_labels([format!("λ = {l}")]),
        )?;
        rec.log(
            "homotopy/ellipse/mean",
            &Points2D::new([f(e.center)])
                .with_colors([FILTERS[0]])
                .with_radii([Radius::new_ui_points(3.0)]),
        )?;
    }
    // The run on `step` alone; its last sample again at λ = 0, so that on the `lambda`
    // timeline the tracking view holds the finished run while the ellipse changes.
    rec.reset_time();
    let n = real.target.len();
    for k in 0..n {
        rec.set_time_sequence(STEP, k as i64 + 1);
        log_sample(rec, real, estimates, k)?;
    }
    if let Some(last) = n.checked_sub(1) {
        rec.set_time_sequence(LAMBDA, 0);
        log_sample(rec, real, estimates, last)?;
    }
    Ok(())
}

/// Picture coordinates of a position: Rerun's 2-D y axis points down, so north is negated
/// to put it up.
fn north_up(p: [f64; 2]) -> [f32; 2] {
    [p[0] as f32, -p[1] as f32]
}

/// Sample `k` of the tracking run: target, observer, their trails, the bearing and every
/// filter's estimate, at the current time.
fn log_sample(
    rec: &RecordingStream,
    real: &Realisation,
    estimates: &[(&str, Vec<[f64; 2]>)],
    k: usize,
) -> rerun::RecordingStreamResult<()> {
    let f = north_up;
    let o = real.observer[k].pos;
    // A moving body: its position, labelled, and its trail so far.
    let body = |name: &str, trail: Vec<[f32; 2]>, color| -> rerun::RecordingStreamResult<()> {
        let at = trail.last().copied().unwrap_or_default();
        rec.log(
            format!("homotopy/scene/{name}"),
            &Points2D::new([at])
                .with_colors([color])
                .with_radii([Radius::new_ui_points(5.0)])
                .with_labels([name]),
        )?;
        rec.log(
            format!("homotopy/scene/{name}_trail"),
            &LineStrips2D::new([trail]).with_colors([color]),
        )
    };
    body(
        "target",
        real.target[..=k].iter().map(|x| f([x[0], x[1]])).collect(),
        RED,
    )?;
    body(
        "observer",
        real.observer[..=k].iter().map(|o| f(o.pos)).collect(),
        OBSERVER,
    )?;
    let b = real.bearings[k];
    rec.log(
        "homotopy/scene/bearing",
        &LineStrips2D::new([[f(o), f([o[0] + RAY * b.cos(), o[1] + RAY * b.sin()])]])
            .with_colors([GREY]),
    )?;
    for ((name, est), color) in estimates.iter().zip(FILTERS) {
        rec.log(
            format!("homotopy/scene/estimate/{name}"),
            &Points2D::new([f(est[k])])
                .with_colors([color])
                .with_radii([Radius::new_ui_points(4.0)])
                .with_labels([*name]),
        )?;
    }
    Ok(())
}

fn blueprint(track: Option<Bounds>, ellipses: Option<Bounds>) -> Node {
    layout::horizontal([
        View::spatial_2d(
            "tracking run: target, observer, bearing, estimates (m, north up; step)",
            "homotopy/scene",
        )
        .with_bounds(track)
        .into(),
        View::spatial_2d(
            "OHF ellipse at sample 17 as λ goes 0 → 1 (m, north up; lambda × 1000)",
            "homotopy/ellipse",
        )
        .with_bounds(ellipses)
        .into(),
    ])
}
