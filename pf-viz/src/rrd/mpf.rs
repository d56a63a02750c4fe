//! `mpf.rrd`: one run of each partition of the radar example, on the `step` timeline.
//!
//! For each partition (`mpf/PPKKKK/…`), the position view shows the particles `[p_x p_y]`,
//! sized by weight, the filter's estimate and the true position with a short trail; the KF view
//! shows the mean that each particle's Kalman filter holds for its first two linear states
//! (velocities, or accelerations for `PPPPKK`), with the true values. The standard PF
//! (`PPPPPP`) has no KF view. The blueprint lays the partitions out side by side, and fills
//! the last cell with the whole true track (`mpf/track/truth`, static) and each partition's
//! estimated track up to the current step (`mpf/track/<partition>`).

use std::path::Path;

use pf_mpf::radar::{RadarState, RunTrace};
use rerun::components::Radius;
use rerun::{LineStrips2D, Points2D, RecordingStream};

use super::layout::{self, Bounds, Node, View};
use super::{STEP, rrd_err, save_rrd};
use crate::error::{Result, VizError};

const PARTICLE: [u8; 4] = [150, 150, 150, 255];
const ESTIMATE: [u8; 4] = [40, 90, 200, 255];
const TRUTH: [u8; 4] = [220, 50, 50, 255];
/// The estimated tracks in the overview, one colour per partition, named in the view's title
/// (the 2-D view has no legend, and labels on tracks this close overlap).
const TRACKS: [(&str, [u8; 4]); 4] = [
    ("blue", [90, 160, 255, 255]),
    ("green", [120, 220, 120, 255]),
    ("magenta", [230, 90, 230, 255]),
    ("white", [240, 240, 240, 255]),
];
/// Steps of true trajectory drawn behind the current position: one, since the view frames
/// everything it shows, and a step is about as long as the cloud is wide (with four, the
/// cloud took a sixth of the view).
const TRAIL: usize = 1;

/// Index of each state name in `[p_x p_y v_x v_y a_x a_y]`.
fn state_index(name: &str) -> Option<usize> {
    ["px", "py", "vx", "vy", "ax", "ay"]
        .iter()
        .position(|&s| s == name)
}

/// Write `mpf.rrd` from the true trajectory and one traced run per partition.
///
/// # Errors
/// Traces that do not match the trajectory, or a Rerun or I/O error naming `path`.
pub fn save(path: &Path, truth: &[RadarState], runs: &[(String, RunTrace)]) -> Result<()> {
    for (name, tr) in runs {
        if tr.positions.len() != truth.len()
            || tr.kf_means.len() != truth.len()
            || tr.weights.len() != truth.len()
        {
            return Err(VizError::PlotData {
                what: "mpf recording",
                message: format!(
                    "{name}: {} traced steps for {} true states",
                    tr.positions.len(),
                    truth.len()
                ),
            });
        }
    }
    save_rrd(path, "pf-viz: marginalized particle filter", |rec, path| {
        log(rec, truth, runs).map_err(rrd_err(path))
    })
}

fn log(
    rec: &RecordingStream,
    truth: &[RadarState],
    runs: &[(String, RunTrace)],
) -> rerun::RecordingStreamResult<()> {
    let xy = |x: &RadarState| [x[0] as f32, x[1] as f32];
    let track: Vec<[f32; 2]> = truth.iter().map(xy).collect();
    layout::send(
        rec,
        &blueprint(runs, Bounds::around(track.iter().copied(), 0.05)),
        Some(STEP),
    )?;
    rec.log_static(
        "mpf/track/truth",
        &LineStrips2D::new([track])
            .with_colors([TRUTH])
            .with_radii([Radius::new_ui_points(1.0)]),
    )?;
    for (t, x) in truth.iter().enumerate() {
        rec.set_time_sequence(STEP, t as i64);
        rec.log(
            "mpf/track/target",
            &Points2D::new([xy(x)])
                .with_colors([TRUTH])
                .with_radii([Radius::new_ui_points(4.0)]),
        )?;
        for ((name, tr), (_, color)) in runs.iter().zip(TRACKS.iter().cycle()) {
            rec.log(
                format!("mpf/track/{name}"),
                &LineStrips2D::new([tr.estimates[..=t]
                    .iter()
                    .map(|e| [e[0] as f32, e[1] as f32])
                    .collect::<Vec<_>>()])
                .with_colors([*color])
                .with_radii([Radius::new_ui_points(1.0)]),
            )?;
        }
    }
    for (name, tr) in runs {
        // The first two KF states, when they form a pair (vx vy or ax ay).
        let kf_pair = match tr.kf_states.as_slice() {
            [a, b, ..] => state_index(a).zip(state_index(b)),
            _ => None,
        };
        for (t, x) in truth.iter().enumerate() {
            rec.set_time_sequence(STEP, t as i64);
            let n = tr.positions[t].len();
            let radii = tr.weights[t].iter().map(|&w| {
                Radius::new_ui_points((2.0 * (n as f64 * w).sqrt()).clamp(0.8, 8.0) as f32)
            });
            rec.log(
                format!("mpf/{name}/position/particles"),
                &Points2D::new(tr.positions[t].iter().map(|p| [p[0] as f32, p[1] as f32]))
                    .with_colors([PARTICLE])
                    .with_radii(radii),
            )?;
            let e = tr.estimates[t];
            rec.log(
                format!("mpf/{name}/position/estimate"),
                &Points2D::new([[e[0] as f32, e[1] as f32]])
                    .with_colors([ESTIMATE])
                    .with_radii([Radius::new_ui_points(5.0)])
                    .with_labels(["estimate"]),
            )?;
            rec.log(
                format!("mpf/{name}/position/truth"),
                &Points2D::new([[x[0] as f32, x[1] as f32]])
                    .with_colors([TRUTH])
                    .with_radii([Radius::new_ui_points(5.0)])
                    .with_labels(["truth"]),
            )?;
            // A short trail, so the view zooms on the particle cloud, not the whole track.
            let trail: Vec<[f32; 2]> = truth[t.saturating_sub(TRAIL)..=t]
                .iter()
                .map(|x| [x[0] as f32, x[1] as f32])
                .collect();
            rec.log(
                format!("mpf/{name}/position/trail"),
                &LineStrips2D::new([trail])
                    .with_colors([TRUTH])
                    .with_radii([Radius::new_ui_points(1.0)]),
            )?;
            if let Some((a, b)) = kf_pair {
                rec.log(
                    format!("mpf/{name}/kf/means"),
                    &Points2D::new(tr.kf_means[t].iter().map(|m| [m[0] as f32, m[1] as f32]))
                        .with_colors([PARTICLE])
                        .with_radii([Radius::new_ui_points(1.5)]),
                )?;
                rec.log(
                    format!("mpf/{name}/kf/truth"),
                    &Points2D::new([[x[a] as f32, x[b] as f32]])
                        .with_colors([TRUTH])
                        .with_radii([Radius::new_ui_points(5.0)])
                        .with_labels(["truth"]),
                )?;
            }
        }
    }
    Ok(())
}

/// Position views in the first row, KF views in the second, then the whole track with every
/// partition's estimates on a fixed frame. The position and KF views follow the cloud (the
/// viewer's own framing): the target crosses kilometres, the cloud spans metres.
fn blueprint(runs: &[(String, RunTrace)], track: Option<Bounds>) -> Node {
    let positions = runs.iter().map(|(name, _)| {
        View::spatial_2d(
            format!("{name}: particles [px, py] (m)"),
            format!("mpf/{name}/position"),
        )
        .into()
    });
    let kf = runs
        .iter()
        .filter(|(_, tr)| tr.kf_states.len() >= 2)
        .map(|(name, tr)| {
            View::spatial_2d(
                format!(
                    "{name}: KF means [{}, {}]",
                    tr.kf_states[0], tr.kf_states[1]
                ),
                format!("mpf/{name}/kf"),
            )
            .into()
        });
    let key: Vec<String> = runs
        .iter()
        .zip(TRACKS.iter().cycle())
        .map(|((name, _), (colour, _))| format!("{name} {colour}"))
        .collect();
    let overview = View::spatial_2d(
        format!("track (m): truth red; {}", key.join(", ")),
        "mpf/track",
    )
    .with_bounds(track)
    .into();
    layout::grid(
        runs.len().max(1) as u32,
        positions.chain(kf).chain([overview]).collect::<Vec<Node>>(),
    )
}
