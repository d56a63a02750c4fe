//! `homotopy.rrd`: the OHF ellipses θ_K(λ) on the `lambda` timeline (sequence in thousandths
//! of λ), and target, observer, bearing rays and every filter's estimate on the `step`
//! timeline, all in one plane (metres, x east, y north drawn upwards).
//! Switch the timeline to `lambda` to see the ellipse flow from prediction (λ = 0) to
//! posterior (λ = 1).

use std::path::Path;

use rerun::blueprint::{Blueprint, BlueprintActivation, Horizontal, Spatial2DView};
use rerun::components::Radius;
use rerun::{LineStrips2D, Points2D, RecordingStream};

use super::{LAMBDA, STEP, rrd_err, save_rrd};
use crate::error::Result;

const ROOT: &str = "homotopy";
const COLOURS: [[u8; 4]; 4] = [
    [40, 90, 200, 255],
    [220, 120, 30, 255],
    [40, 160, 80, 255],
    [200, 50, 60, 255],
];

/// Everything the recording shows.
pub struct HomotopyRrd<'a> {
    /// True target positions at k = 1..K.
    pub target: &'a [[f64; 2]],
    /// Observer positions at k = 1..K.
    pub observer: &'a [[f64; 2]],
    /// Bearings, rad, counter-clockwise from the x-axis.
    pub bearings: &'a [f64],
    /// Filter name and its position estimates at k = 1..K.
    pub estimates: &'a [(&'a str, Vec<[f64; 2]>)],
    /// Sample K of the ellipses, its λ values and the ellipses (centre, semi-axes, angle).
    pub ellipse_step: usize,
    /// λ values of `ellipses`.
    pub lambda: &'a [f64],
    /// `(centre, semi_axes, angle)` per λ.
    pub ellipses: &'a [([f64; 2], [f64; 2], f64)],
    /// True position at sample K.
    pub truth: [f64; 2],
}

/// Write the recording to `path` (atomically).
///
/// # Errors
/// A recording or file error.
pub fn save(path: &Path, d: &HomotopyRrd<'_>) -> Result<()> {
    save_rrd(
        path,
        "pf-viz: homotopy (bearings-only tracking)",
        |rec, path| log(rec, d).map_err(rrd_err(path)),
    )
}

/// The viewer's 2-D y-axis points down: negate y so that north is up, as in the figures.
fn pt(p: [f64; 2]) -> [f32; 2] {
    [p[0] as f32, -p[1] as f32]
}

fn outline(c: [f64; 2], ax: [f64; 2], angle: f64) -> Vec<[f32; 2]> {
    let (s, co) = angle.sin_cos();
    (0..=64)
        .map(|i| {
            let t = i as f64 / 64.0 * std::f64::consts::TAU;
            let (u, v) = (ax[0] * t.cos(), ax[1] * t.sin());
            pt([c[0] + co * u - s * v, c[1] + s * u + co * v])
        })
        .collect()
}

fn log(rec: &RecordingStream, d: &HomotopyRrd<'_>) -> rerun::RecordingStreamResult<()> {
    blueprint().send(rec, BlueprintActivation::default())?;
    let width = Radius::new_ui_points(1.5);
    rec.log_static(
        format!("{ROOT}/tracks/target_path"),
        &LineStrips2D::new([d.target.iter().map(|&p| pt(p)).collect::<Vec<_>>()])
            .with_colors([[120, 120, 120, 255]])
            .with_radii([Radius::new_ui_points(0.75)]),
    )?;
    rec.log_static(
        format!("{ROOT}/tracks/observer_path"),
        &LineStrips2D::new([d.observer.iter().map(|&p| pt(p)).collect::<Vec<_>>()])
            .with_colors([[90, 90, 90, 255]])
            .with_radii([Radius::new_ui_points(0.75)]),
    )?;
    let reach = d
        .target
        .iter()
        .zip(d.observer)
        .map(|(t, o)| (t[0] - o[0]).hypot(t[1] - o[1]))
        .fold(0.0, f64::max)
        * 1.3;
    for k in 0..d.target.len() {
        rec.set_time_sequence(STEP, (k + 1) as i64);
        rec.log(
            format!("{ROOT}/tracks/target"),
            &Points2D::new([pt(d.target[k])])
                .with_colors([[0, 0, 0, 255]])
                .with_radii([Radius::new_ui_points(5.0)])
                .with_labels(["target"]),
        )?;
        rec.log(
            format!("{ROOT}/tracks/observer"),
            &Points2D::new([pt(d.observer[k])])
                .with_colors([[90, 90, 90, 255]])
                .with_radii([Radius::new_ui_points(5.0)])
                .with_labels(["observer"]),
        )?;
        let o = d.observer[k];
        let b = d.bearings[k];
        rec.log(
            format!("{ROOT}/tracks/bearing_ray"),
            &LineStrips2D::new([vec![
                pt(o),
                pt([o[0] + reach * b.cos(), o[1] + reach * b.sin()]),
            ]])
            .with_colors([[160, 160, 160, 255]])
            .with_radii([width]),
        )?;
        for (i, (name, est)) in d.estimates.iter().enumerate() {
            rec.log(
                format!("{ROOT}/tracks/estimates/{name}"),
                &Points2D::new([pt(est[k])])
                    .with_colors([COLOURS[i % 4]])
                    .with_radii([Radius::new_ui_points(4.0)])
                    .with_labels([*name]),
            )?;
        }
    }
    rec.reset_time();
    rec.log_static(
        format!("{ROOT}/ellipses/truth"),
        &Points2D::new([pt(d.truth)])
            .with_colors([[0, 0, 0, 255]])
            .with_radii([Radius::new_ui_points(5.0)])
            .with_labels([format!("true position, k = {}", d.ellipse_step)]),
    )?;
    for (l, (c, ax, a)) in d.lambda.iter().zip(d.ellipses) {
        rec.set_time_sequence(LAMBDA, (l * 1000.0).round() as i64);
        rec.log(
            format!("{ROOT}/ellipses/theta"),
            &LineStrips2D::new([outline(*c, *ax, *a)])
                .with_colors([COLOURS[0]])
                .with_radii([width])
                .with_labels([format!("θ(λ = {l:.2})")]),
        )?;
        rec.log(
            format!("{ROOT}/ellipses/mean"),
            &Points2D::new([pt(*c)])
                .with_colors([COLOURS[0]])
                .with_radii([Radius::new_ui_points(3.0)]),
        )?;
    }
    Ok(())
}

/// The tracks on the left (scrub `step`), the λ-flow of the ellipse on the right
/// (scrub `lambda`).
fn blueprint() -> Blueprint {
    Blueprint::new(Horizontal::new([
        Spatial2DView::new("target, observer, bearing ray and estimates (step)")
            .with_origin(format!("{ROOT}/tracks"))
            .into(),
        Spatial2DView::new("OHF ellipse θ(λ) at sample K (lambda, in thousandths)")
            .with_origin(format!("{ROOT}/ellipses"))
            .into(),
    ]))
}
