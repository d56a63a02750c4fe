//! How well tracks follow the truth: position errors (for REC curves, Fig. 4c, and RMSE),
//! the association error rate, the fractions of target-frames without a detection or
//! lost, and OSPA (Schuhmacher, Vo & Vo 2008), which the paper does
//! not use but which is the field's standard multi-target metric.

use crate::assignment::Hungarian;
use crate::data::Detections;
use crate::error::{EpfError, Result};
use crate::geometry::Vec2;
use crate::scenario::Simulation;
use crate::tracker::{TrackResult, TrackStatus};
use pf_core::metrics::{RecCurve, rec_curve, rmse};
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// `‖X̂_{k,t} − X_{k,t}‖` per target (rows, in init order) and tracked frame (columns).
///
/// # Errors
/// [`EpfError::UnknownFrame`] if a tracked frame has no truth.
pub fn position_errors(result: &TrackResult, sim: &Simulation) -> Result<Vec<Vec<f64>>> {
    result
        .tracks
        .iter()
        .enumerate()
        .map(|(k, tr)| {
            result
                .frames
                .iter()
                .zip(&tr.position)
                .map(|(&f, p)| {
                    let x = sim.truth_at(k, f).ok_or_else(|| EpfError::UnknownFrame {
                        frame: f,
                        tracked: sim.frames.clone(),
                    })?;
                    Ok((Vec2::new(p[0], p[1]) - x).norm())
                })
                .collect()
        })
        .collect()
}

/// RMSE over every target and tracked frame: `√(mean ‖X̂ − X‖²)`.
///
/// # Errors
/// No errors, or a non-finite one.
pub fn rmse_of(errors: &[Vec<f64>]) -> Result<f64> {
    let sq: Vec<Vec<f64>> = errors
        .iter()
        .map(|r| r.iter().map(|e| e * e).collect())
        .collect();
    Ok(rmse(&sq)?)
}

/// The REC curve of one target's errors (`pf_core::metrics::rec_curve`).
///
/// # Errors
/// No errors, or a non-finite error or tolerance.
pub fn rec_of(errors: &[f64], tolerances: &[f64]) -> Result<RecCurve> {
    Ok(rec_curve(errors, tolerances)?)
}

/// Association errors of a run: over every target × tracked frame, the associated detection
/// is compared with the one the target truly produced (`None` when it was missed).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct AssociationErrors {
    /// Target-frames whose association differs from the truth.
    pub errors: usize,
    /// Target-frames counted.
    pub total: usize,
}

impl AssociationErrors {
    /// `errors / total` (0 when nothing was counted).
    pub fn rate(&self) -> f64 {
        if self.total == 0 {
            0.0
        } else {
            self.errors as f64 / self.total as f64
        }
    }
}

/// Count association errors against the `target` labels of `detections`; track `k` is
/// target `result.tracks[k].target`.
pub fn association_errors(result: &TrackResult, detections: &Detections) -> AssociationErrors {
    let mut out = AssociationErrors::default();
    for tr in &result.tracks {
        for (&f, &assigned) in result.frames.iter().zip(&tr.detection) {
            let rows = detections.frame_rows(f);
            let truth = rows
                .clone()
                .find(|&j| detections.rows()[j].target == Some(tr.target));
            out.total += 1;
            if assigned != truth {
                out.errors += 1;
            }
        }
    }
    out
}

/// The fraction of target × tracked frames without an associated detection (0 for an
/// empty result).
pub fn missing_fraction(result: &TrackResult) -> f64 {
    let (mut none, mut total) = (0usize, 0usize);
    for t in &result.tracks {
        none += t.detection.iter().filter(|d| d.is_none()).count();
        total += t.detection.len();
    }
    if total == 0 {
        0.0
    } else {
        none as f64 / total as f64
    }
}

/// The fraction of target × tracked frames with `status` (0 for an empty result).
pub fn status_fraction(result: &TrackResult, status: TrackStatus) -> f64 {
    let (mut hit, mut total) = (0usize, 0usize);
    for t in &result.tracks {
        hit += t.status.iter().filter(|&&s| s == status).count();
        total += t.status.len();
    }
    if total == 0 {
        0.0
    } else {
        hit as f64 / total as f64
    }
}

/// OSPA distance of order `p` with cut-off `c` between estimates `x` and truths `y`:
/// `(1/n (min_π Σ_{i≤m} min(c, ‖x_i − y_π(i)‖)^p + c^p (n − m)))^{1/p}`, `m ≤ n` the smaller
/// and larger set sizes (0 when both are empty).
///
/// # Errors
/// [`EpfError::Param`] unless `c > 0` and `p ≥ 1`.
pub fn ospa(x: &[Vec2], y: &[Vec2], c: f64, p: f64, h: &mut Hungarian) -> Result<f64> {
    if !(c > 0.0 && c.is_finite()) {
        return Err(EpfError::Param(ParamError {
            name: "c",
            value: c,
            reason: "the OSPA cut-off must be positive and finite",
        }));
    }
    if !(p >= 1.0 && p.is_finite()) {
        return Err(EpfError::Param(ParamError {
            name: "p",
            value: p,
            reason: "the OSPA order must be at least 1",
        }));
    }
    let (a, b) = if x.len() <= y.len() { (x, y) } else { (y, x) };
    let (m, n) = (a.len(), b.len());
    if n == 0 {
        return Ok(0.0);
    }
    let cost: Vec<f64> = a
        .iter()
        .flat_map(|u| b.iter().map(move |v| (u - v).norm().min(c).powf(p)))
        .collect();
    let mut cols = vec![0; m];
    let matched = if m == 0 {
        0.0
    } else {
        h.solve(m, n, &cost, &mut cols)
            .unwrap_or(c.powf(p) * m as f64)
    };
    Ok(((matched + c.powf(p) * (n - m) as f64) / n as f64).powf(1.0 / p))
}

/// Mean OSPA over the tracked frames of a run (cut-off `c`, order `p`).
///
/// # Errors
/// As [`ospa`]; a tracked frame without truth.
pub fn mean_ospa(result: &TrackResult, sim: &Simulation, c: f64, p: f64) -> Result<f64> {
    let mut h = Hungarian::new();
    let mut total = 0.0;
    for (i, &f) in result.frames.iter().enumerate() {
        let x: Vec<Vec2> = result
            .tracks
            .iter()
            .map(|t| Vec2::new(t.position[i][0], t.position[i][1]))
            .collect();
        let y: Vec<Vec2> = (0..sim.truth.len())
            .filter_map(|k| sim.truth_at(k, f))
            .collect();
        total += ospa(&x, &y, c, p, &mut h)?;
    }
    Ok(total / result.frames.len().max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ospa_closed_forms() {
        let mut h = Hungarian::new();
        let v = |x: f64, y: f64| Vec2::new(x, y);
        // Same sets in another order: 0 (labels do not matter).
        let a = [v(0.0, 0.0), v(5.0, 0.0)];
        let b = [v(5.0, 0.0), v(0.0, 0.0)];
        assert_eq!(ospa(&a, &b, 10.0, 2.0, &mut h).unwrap(), 0.0);
        // One point off by 3, p = 1: (0 + 3)/2.
        let b = [v(0.0, 3.0), v(5.0, 0.0)];
        assert!((ospa(&a, &b, 10.0, 1.0, &mut h).unwrap() - 1.5).abs() < 1e-12);
        // A missing estimate costs c: ((0 + c²)/2)^{1/2} with p = 2.
        let c = 4.0;
        assert!((ospa(&a[..1], &a, c, 2.0, &mut h).unwrap() - (c * c / 2.0).sqrt()).abs() < 1e-12);
        // Distances are cut at c.
        let far = [v(100.0, 0.0)];
        assert!((ospa(&far, &a[..1], c, 2.0, &mut h).unwrap() - c).abs() < 1e-12);
        assert_eq!(ospa(&[], &[], c, 2.0, &mut h).unwrap(), 0.0);
        assert!(ospa(&a, &b, 0.0, 2.0, &mut h).is_err());
    }
}
