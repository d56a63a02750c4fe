//! `smooth.rrd`: the genealogy of Fig. 1 on the `step` timeline and the SEM chains of Fig. 4
//! on the `iteration` timeline.
//!
//! | entity | archetype | what |
//! |---|---|---|
//! | `smooth/genealogy/…`, `smooth/ess` | as in [`rrd::genealogy`](super::genealogy) | the genealogy of Fig. 1 and its ESS on `step` (the shared logger) |
//! | `smooth/genealogy_final/{all,lineages}` | `LineStrips2D` | static: the whole genealogy and the surviving lineages |
//! | `smooth/genealogy_final/axes/…` | as in [`rrd::genealogy`](super::genealogy) | static: the same axes and ticks |
//! | `smooth/sem/<param>/chain_<c>` | `Scalars` | SEM chain `c` at each iteration |
//! | `smooth/sem/<param>/exact` | `Scalars` | the exact EM trajectory |
//!
//! The viewer opens on the `iteration` timeline (the SEM chains, and the static final
//! genealogy); the genealogy's own tab plays on the `step` timeline.
//!
//! As in `rrd::genealogy`, a point of the genealogy is logged at `(k, −c·ξ)` (Rerun's 2D
//! y-axis points down and both axes share one scale), `c` giving a 5:2 picture.

use std::path::Path;

use pf_smooth::Theta;
use pf_smooth::experiments::SemResult;
use rerun::components::Radius;
use rerun::{LineStrips2D, RecordingStream, Scalars, SeriesLines};

use super::genealogy::{Frame, GenealogyExtras, frame_bounds, log_axes, log_genealogy};
use super::layout::{self, Bounds, Corner, Node, View};
use super::{ITERATION, rrd_err, save_rrd};
use crate::error::Result;
use crate::figure::{GenealogyData, validate_genealogy};

/// Root entity of the genealogy.
pub const GENEALOGY: &str = "smooth/genealogy";
/// The genealogy at the last step, static, so that it is visible on every timeline.
pub const FINAL: &str = "smooth/genealogy_final";
/// Root entity of the SEM chains.
pub const SEM: &str = "smooth/sem";

const LIGHT: [u8; 4] = [130, 130, 130, 120];
const DARK_BLUE: [u8; 4] = [40, 90, 200, 255];
const CHAINS: [[u8; 4]; 4] = [
    [230, 120, 40, 255],
    [60, 170, 90, 255],
    [170, 80, 200, 255],
    [200, 60, 60, 255],
];
// Light: the viewer's background is dark.
const EXACT: [u8; 4] = [240, 240, 240, 255];

type Pick = fn(&Theta) -> f64;
const PARAMS: [(&str, &str, Pick); 3] = [
    ("phi", "φ", |t| t.phi),
    ("sigma2", "σ²", |t| t.sigma2),
    ("rho2", "ρ²", |t| t.rho2),
];

/// Write the recording to `path` (atomically).
///
/// # Errors
/// Inconsistent genealogy data, or a Rerun or I/O error naming `path`.
pub fn save(
    path: &Path,
    genealogy: &GenealogyData,
    extras: &GenealogyExtras<'_>,
    sem: &SemResult,
) -> Result<()> {
    validate_genealogy(genealogy)?;
    save_rrd(path, "pf-viz: smooth (Cappé & Moulines)", |rec, path| {
        let err = rrd_err(path);
        layout::send(rec, &blueprint(frame_bounds(genealogy)), Some(ITERATION)).map_err(&err)?;
        log_genealogy(rec, path, genealogy, extras, "smooth")?;
        log_final(rec, genealogy).map_err(&err)?;
        log_sem(rec, sem).map_err(&err)?;
        Ok(())
    })
}

/// The genealogy at its last step, static, so that it shows on the `iteration` timeline too,
/// in the same frame and with the same axes as the step-by-step one.
fn log_final(rec: &RecordingStream, data: &GenealogyData) -> rerun::RecordingStreamResult<()> {
    let (steps, n) = (data.n_steps(), data.n_particles());
    let frame = Frame::new(data);
    log_axes(rec, data, frame, FINAL)?;
    let at = |k: usize, x: f64| frame.at(k, x);
    let at_idx = |j: usize, idx: usize| at(j, data.positions[j][idx]);
    let mut segments: Vec<[[f32; 2]; 2]> = Vec::with_capacity(n * steps);
    // lineages[i][j]: index at step j of the ancestor of particle i of the current step.
    let mut lineages: Vec<Vec<usize>> = (0..n).map(|i| vec![i]).collect();
    for k in 1..steps {
        for i in 0..n {
            let a = data.ancestors[k][i];
            segments.push([
                at(k - 1, data.positions[k - 1][a]),
                at(k, data.positions[k][i]),
            ]);
        }
        lineages = (0..n)
            .map(|i| {
                let mut l = lineages[data.ancestors[k][i]].clone();
                l.push(i);
                l
            })
            .collect();
    }
    rec.log_static(format!("{FINAL}/all"), &all_paths(&segments))?;
    rec.log_static(
        format!("{FINAL}/lineages"),
        &lineage_strips(&lineages, &at_idx),
    )?;
    Ok(())
}

/// Every parent → child segment, thin and light.
fn all_paths(segments: &[[[f32; 2]; 2]]) -> LineStrips2D {
    LineStrips2D::new(segments.iter().map(|s| s.to_vec()))
        .with_colors([LIGHT])
        .with_radii([Radius::new_ui_points(0.5)])
        .with_draw_order(10.0)
}

/// The ancestral lines `lineages[i][j]` (index at step j), dark.
fn lineage_strips(lineages: &[Vec<usize>], at: &dyn Fn(usize, usize) -> [f32; 2]) -> LineStrips2D {
    LineStrips2D::new(lineages.iter().map(|l| {
        l.iter()
            .enumerate()
            .map(|(j, &idx)| at(j, idx))
            .collect::<Vec<_>>()
    }))
    .with_colors([DARK_BLUE])
    .with_radii([Radius::new_ui_points(1.5)])
    .with_draw_order(30.0)
}

fn log_sem(rec: &RecordingStream, sem: &SemResult) -> rerun::RecordingStreamResult<()> {
    // On `iteration` alone: the genealogy left the `step` timeline at its last step.
    rec.reset_time();
    for (p, _, _) in PARAMS {
        for c in 0..sem.sem.len() {
            rec.log_static(
                format!("{SEM}/{p}/chain_{c}"),
                &SeriesLines::new()
                    .with_names([format!("SEM chain {c}")])
                    .with_colors([CHAINS[c % CHAINS.len()]])
                    .with_widths([1.5]),
            )?;
        }
        rec.log_static(
            format!("{SEM}/{p}/exact"),
            &SeriesLines::new()
                .with_names(["exact EM"])
                .with_colors([EXACT])
                .with_widths([3.0]),
        )?;
    }
    for (i, exact) in sem.exact.iter().enumerate() {
        rec.set_time_sequence(ITERATION, i as i64);
        for (p, _, pick) in PARAMS {
            rec.log(format!("{SEM}/{p}/exact"), &Scalars::single(pick(exact)))?;
            for (c, chain) in sem.sem.iter().enumerate() {
                if let Some(t) = chain.get(i) {
                    rec.log(format!("{SEM}/{p}/chain_{c}"), &Scalars::single(pick(t)))?;
                }
            }
        }
    }
    Ok(())
}

/// The genealogy on the left (final picture; a tab plays it on `step`), the three SEM
/// parameters stacked on the right, on the `iteration` timeline.
fn blueprint(genealogy: Option<Bounds>) -> Node {
    let genealogy_view =
        |name: &str, origin: &str| View::spatial_2d(name, origin).with_bounds(genealogy).into();
    layout::horizontal([
        layout::tabs([
            genealogy_view(
                "genealogy, N = 50, all steps (x: step k, y: position ξ)",
                FINAL,
            ),
            genealogy_view(
                "genealogy step by step (select the `step` timeline)",
                GENEALOGY,
            ),
        ]),
        layout::vertical(PARAMS.iter().zip(LEGENDS).map(|((p, name, _), corner)| {
            View::time_series(
                format!("SEM chains and exact EM: {name}"),
                format!("{SEM}/{p}"),
            )
            .with_legend(corner)
            .into()
        })),
    ])
    .with_shares([3.0, 2.0])
}

/// Where each parameter's legend covers no curve: φ rises from its start, σ² and ρ² fall.
const LEGENDS: [Corner; 3] = [Corner::RightBottom, Corner::RightTop, Corner::RightTop];
