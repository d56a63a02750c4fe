//! `dredge.rrd`: one simulated loading cycle estimated on line, on the `time` timeline (s).
//!
//! - `dredge/signals/…`: measured `V_t`, `m_t`, the inputs `Q_i`, `ρ_i`, and the simulated and
//!   PF-estimated `Q_o`, `ρ_o`, as scalar series;
//! - `dredge/cloud/…`: the particle cloud of `(Q_o, ρ_o)` after each update (every second
//!   sample), with the estimate and the simulated value. The plane's x is `Q_o × 100` and
//!   its y is `−ρ_o` (Rerun's y points down), both labelled by tick points. One view shows
//!   the whole plane, a second the cloud close up.

use std::path::Path;

use pf_dredge::experiments::OnlineResult;
use rerun::components::Radius;
use rerun::{Points2D, RecordingStream, Scalars, SeriesLines};

use super::layout::{self, Bounds, Corner, Node, View};
use super::{TIME, rrd_err, save_rrd};
use crate::error::Result;

const ROOT: &str = "dredge";
const BLUE: [u8; 4] = [60, 110, 220, 255];
const RED: [u8; 4] = [220, 60, 50, 255];
const GREY: [u8; 4] = [160, 160, 160, 255];
const GREEN: [u8; 4] = [60, 170, 90, 255];
/// Plane scale of `Q_o`, so that 1 m³/s spans as much as 100 kg/m³.
const Q_SCALE: f64 = 100.0;
/// The `ρ_o` (kg/m³) below the plane where the `Q_o` ticks sit, and the `Q_o` (m³/s) left of
/// it where the `ρ_o` ticks sit: apart enough that the corner labels do not overlap.
const Q_TICKS_AT: f64 = 950.0;
const RHO_TICKS_AT: f64 = -0.8;

fn at(q: f64, rho: f64) -> [f32; 2] {
    [(q * Q_SCALE) as f32, (-rho) as f32]
}

/// Record `run` (pf-dredge's [`online`](pf_dredge::experiments::online)) to `path`.
///
/// # Errors
/// A recording or I/O error naming `path`.
pub fn save(path: &Path, run: &OnlineResult) -> Result<()> {
    save_rrd(path, "dredge", |rec, path| log(rec, path, run))
}

fn series(
    rec: &RecordingStream,
    path: &Path,
    entity: &str,
    name: &str,
    color: [u8; 4],
) -> Result<()> {
    rec.log_static(
        format!("{ROOT}/signals/{entity}"),
        &SeriesLines::new()
            .with_names([name])
            .with_colors([color])
            .with_widths([2.0]),
    )
    .map_err(rrd_err(path))
}

fn log(rec: &RecordingStream, path: &Path, run: &OnlineResult) -> Result<()> {
    let cycle = &run.cycle;
    let err = rrd_err(path);
    layout::send(rec, &blueprint(), Some(TIME)).map_err(&err)?;
    for (e, n, c) in [
        ("volume/measured", "Vₜ measured (m³)", GREY),
        ("volume/true", "Vₜ simulated (m³)", BLUE),
        ("mass/measured", "mₜ measured (kg)", GREY),
        ("mass/true", "mₜ simulated (kg)", BLUE),
        ("Q/Q_i", "Qᵢ (m³/s)", GREEN),
        ("Q/Q_o_true", "Qₒ simulated (m³/s)", BLUE),
        ("Q/Q_o_pf", "Qₒ PF estimate (m³/s)", RED),
        ("rho/rho_i", "ρᵢ (kg/m³)", GREEN),
        ("rho/rho_o_true", "ρₒ simulated (kg/m³)", BLUE),
        ("rho/rho_o_pf", "ρₒ PF estimate (kg/m³)", RED),
    ] {
        series(rec, path, e, n, c)?;
    }
    let (q_ticks, rho_ticks) = ticks();
    rec.log_static(
        format!("{ROOT}/cloud/axes/q"),
        &Points2D::new(q_ticks.iter().map(|&q| at(q, Q_TICKS_AT)))
            .with_labels(q_ticks.iter().map(|q| format!("Qₒ {q}")))
            .with_colors([GREY])
            .with_radii([Radius::new_ui_points(2.0)])
            .with_show_labels(true),
    )
    .map_err(&err)?;
    rec.log_static(
        format!("{ROOT}/cloud/axes/rho"),
        &Points2D::new(rho_ticks.iter().map(|&r| at(RHO_TICKS_AT, r)))
            .with_labels(rho_ticks.iter().map(|r| format!("ρₒ {r}")))
            .with_colors([GREY])
            .with_radii([Radius::new_ui_points(2.0)])
            .with_show_labels(true),
    )
    .map_err(&err)?;

    let mut clouds = run.clouds.iter().peekable();
    for (k, &[q_o, rho_o]) in run.estimates.iter().enumerate() {
        // Whole seconds as a sequence: the viewer then opens the series on the whole cycle
        // (a duration timeline opens them on the last minute).
        rec.set_time_sequence(TIME, cycle.t[k].round() as i64);
        let scalars = [
            ("volume/measured", cycle.y_v[k]),
            ("volume/true", cycle.v_t[k]),
            ("mass/measured", cycle.y_m[k]),
            ("mass/true", cycle.m_t[k]),
            ("Q/Q_i", cycle.q_i[k]),
            ("Q/Q_o_true", cycle.q_o[k]),
            ("Q/Q_o_pf", q_o),
            ("rho/rho_i", cycle.rho_i[k]),
            ("rho/rho_o_true", cycle.rho_o[k]),
            ("rho/rho_o_pf", rho_o),
        ];
        for (e, v) in scalars {
            rec.log(format!("{ROOT}/signals/{e}"), &Scalars::single(v))
                .map_err(&err)?;
        }
        if k % run.cloud_every == 0 {
            if let Some(cloud) = clouds.next_if(|c| c.k == k) {
                rec.log(
                    format!("{ROOT}/cloud/particles"),
                    &Points2D::new(cloud.points.iter().map(|&[q, rho]| at(q, rho)))
                        .with_colors([GREY])
                        .with_radii([Radius::new_ui_points(1.5)]),
                )
                .map_err(&err)?;
            }
            rec.log(
                format!("{ROOT}/cloud/estimate"),
                &Points2D::new([at(q_o, rho_o)])
                    .with_colors([RED])
                    .with_radii([Radius::new_ui_points(6.0)])
                    .with_labels(["PF estimate"]),
            )
            .map_err(&err)?;
            rec.log(
                format!("{ROOT}/cloud/simulated"),
                &Points2D::new([at(cycle.q_o[k], cycle.rho_o[k])])
                    .with_colors([BLUE])
                    .with_radii([Radius::new_ui_points(6.0)])
                    .with_labels(["simulated"]),
            )
            .map_err(&err)?;
        }
    }
    Ok(())
}

/// The cloud plane's axis ticks: `Q_o` (m³/s) and `ρ_o` (kg/m³).
fn ticks() -> (Vec<f64>, Vec<f64>) {
    (
        (0..=3).map(|j| 4.0 * j as f64).collect(),
        (0..=6).map(|j| 1000.0 + 100.0 * j as f64).collect(),
    )
}

/// Signals on the left (volume, mass, flows, densities), each over the whole cycle; the
/// cloud on the right, on a fixed frame around the axis ticks, so that its motion shows,
/// and below it close up.
fn blueprint() -> Node {
    let signal = |name: &str, entity: &str| {
        // The lower right is empty in all four: the curves start low and end high or flat.
        View::time_series(name, format!("{ROOT}/signals/{entity}"))
            .with_whole_time()
            .with_legend(Corner::RightBottom)
            .into()
    };
    let (q, rho) = ticks();
    let corners = [at(q[0], rho[0]), at(q[q.len() - 1], rho[rho.len() - 1])];
    let frame = corners.into_iter().chain([at(RHO_TICKS_AT, Q_TICKS_AT)]);
    layout::horizontal([
        layout::vertical([
            signal("hopper volume Vₜ (m³)", "volume"),
            signal("hopper mass mₜ (kg)", "mass"),
            signal("flow-rates Qᵢ, Qₒ (m³/s)", "Q"),
            signal("densities ρᵢ, ρₒ (kg/m³)", "rho"),
        ]),
        layout::vertical([
            View::spatial_2d(
                "particle cloud: x = Qₒ × 100 (m³/s), y = −ρₒ (kg/m³)",
                format!("{ROOT}/cloud"),
            )
            .with_bounds(Bounds::around(frame, 0.08))
            .into(),
            // The same cloud without the axes, which the viewer then frames on the cloud: in
            // the whole plane it spans a few pixels.
            View::spatial_2d(
                "the cloud close up, framed on it (same x = Qₒ × 100, y = −ρₒ)",
                format!("{ROOT}/cloud"),
            )
            .with_contents(
                ["particles", "estimate", "simulated"].map(|e| format!("+ {ROOT}/cloud/{e}")),
            )
            .into(),
        ]),
    ])
    .with_shares([1.0, 1.0])
}
