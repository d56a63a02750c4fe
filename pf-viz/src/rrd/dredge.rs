//! `dredge.rrd`: one filter run over the simulated loading cycle, on the `time` timeline
//! (seconds).
//!
//! Scalar series under `dredge/signals/…`: measured and estimated volume and mass, true and
//! estimated `Q_o` and `ρ_o`, the inputs, and the ESS. The particle cloud of `(Q_o, ρ_o)`
//! (`dredge/cloud/particles`, sized by weight) with the truth and the estimate. The
//! blueprint puts the time series on the left and the cloud on the right.

use std::path::Path;

use pf_core::observe::CloudRecorder;
use pf_dredge::Cycle;
use pf_dredge::estimator::FilterRun;
use pf_dredge::model::{Q_O, RHO_O, State};
use rerun::blueprint::{
    Blueprint, BlueprintActivation, Horizontal, Spatial2DView, TimeSeriesView, Vertical,
};
use rerun::components::Radius;
use rerun::{Points2D, RecordingStream, Scalars, SeriesLines};

use super::{TIME, rrd_err, save_rrd};
use crate::error::{Result, VizError};

const GREY: [u8; 4] = [150, 150, 150, 255];
const BLUE: [u8; 4] = [40, 90, 200, 255];
const RED: [u8; 4] = [220, 50, 50, 255];
const AMBER: [u8; 4] = [240, 170, 40, 255];

/// Write `dredge.rrd`.
///
/// # Errors
/// A run whose length does not match the cycle, or a Rerun or I/O error naming `path`.
pub fn save(
    path: &Path,
    cycle: &Cycle,
    run: &FilterRun,
    clouds: &CloudRecorder<State>,
) -> Result<()> {
    let n = cycle.len();
    if run.estimates.q_o.len() != n || clouds.clouds.len() != n {
        return Err(VizError::PlotData {
            what: "dredge recording",
            message: format!(
                "{} estimates and {} clouds for {} samples",
                run.estimates.q_o.len(),
                clouds.clouds.len(),
                n
            ),
        });
    }
    save_rrd(
        path,
        "pf-viz: hopper dredger overflow losses",
        |rec, path| log(rec, cycle, run, clouds).map_err(rrd_err(path)),
    )
}

/// (entity, legend, colour) of every scalar series.
const SERIES: [(&str, &str, [u8; 4]); 10] = [
    ("dredge/signals/volume/measured", "V_t measured (m³)", GREY),
    (
        "dredge/signals/volume/estimated",
        "V_t estimated (m³)",
        BLUE,
    ),
    ("dredge/signals/mass/measured", "m_t measured (t)", GREY),
    ("dredge/signals/mass/estimated", "m_t estimated (t)", BLUE),
    ("dredge/signals/q_o/true", "Q_o simulated (m³/s)", RED),
    ("dredge/signals/q_o/estimated", "Q_o estimated (m³/s)", BLUE),
    ("dredge/signals/rho_o/true", "ρ_o simulated (kg/m³)", RED),
    (
        "dredge/signals/rho_o/estimated",
        "ρ_o estimated (kg/m³)",
        BLUE,
    ),
    ("dredge/signals/inputs/q_i", "Q_i (m³/s)", AMBER),
    ("dredge/signals/ess", "effective sample size", GREY),
];

fn log(
    rec: &RecordingStream,
    c: &Cycle,
    run: &FilterRun,
    clouds: &CloudRecorder<State>,
) -> rerun::RecordingStreamResult<()> {
    blueprint().send(rec, BlueprintActivation::default())?;
    for (entity, name, color) in SERIES {
        rec.log_static(
            entity,
            &SeriesLines::new()
                .with_names([name])
                .with_colors([color])
                .with_widths([2.0]),
        )?;
    }
    let e = &run.estimates;
    for k in 0..c.len() {
        rec.set_duration_secs(TIME, c.t[k]);
        let values = [
            c.y_v[k],
            e.v_t[k],
            c.y_m[k] / 1000.0,
            e.m_t[k] / 1000.0,
            c.q_o[k],
            e.q_o[k],
            c.rho_o[k],
            e.rho_o[k],
            c.q_i[k],
            e.ess[k],
        ];
        for ((entity, _, _), v) in SERIES.iter().zip(values) {
            rec.log(*entity, &Scalars::single(v))?;
        }
        let cloud = &clouds.clouds[k];
        let np = cloud.particles.len() as f64;
        rec.log(
            "dredge/cloud/particles",
            &Points2D::new(
                cloud
                    .particles
                    .iter()
                    .map(|x| [x[Q_O] as f32, x[RHO_O] as f32]),
            )
            .with_colors([GREY])
            .with_radii(
                cloud.weights.iter().map(|&w| {
                    Radius::new_ui_points((2.0 * (np * w).sqrt()).clamp(0.8, 8.0) as f32)
                }),
            ),
        )?;
        rec.log(
            "dredge/cloud/truth",
            &Points2D::new([[c.q_o[k] as f32, c.rho_o[k] as f32]])
                .with_colors([RED])
                .with_radii([Radius::new_ui_points(5.0)])
                .with_labels(["simulated"]),
        )?;
        rec.log(
            "dredge/cloud/estimate",
            &Points2D::new([[e.q_o[k] as f32, e.rho_o[k] as f32]])
                .with_colors([BLUE])
                .with_radii([Radius::new_ui_points(5.0)])
                .with_labels(["estimate"]),
        )?;
    }
    Ok(())
}

fn blueprint() -> Blueprint {
    Blueprint::new(
        Horizontal::new([
            Vertical::new([
                TimeSeriesView::new("overflow flow-rate Q_o (m³/s)")
                    .with_origin("dredge/signals/q_o")
                    .into(),
                TimeSeriesView::new("overflow density ρ_o (kg/m³)")
                    .with_origin("dredge/signals/rho_o")
                    .into(),
                TimeSeriesView::new("hopper volume V_t (m³)")
                    .with_origin("dredge/signals/volume")
                    .into(),
                TimeSeriesView::new("hopper mass m_t (t)")
                    .with_origin("dredge/signals/mass")
                    .into(),
            ])
            .into(),
            Spatial2DView::new("particle cloud: x = Q_o (m³/s), y = ρ_o (kg/m³)")
                .with_origin("dredge/cloud")
                .into(),
        ])
        .with_column_shares([3.0, 2.0]),
    )
}
