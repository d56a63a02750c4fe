//! Data association (EPF step 1): gating by validation ellipsoids, then energy
//! minimisation, or the nearest-neighbour standard filter (NNSF) as the baseline.
//!
//! - **Gate.** Detection `y_j` is validated for target `k` when it lies in the ellipsoid
//!   around the prediction `Â(t)` holding probability `P_G` of `N(Â(t), Σ̂_k)`:
//!   `(y_j − Â(t))ᵀ Σ̂_k⁻¹ (y_j − Â(t)) ≤ γ`, `γ = −2 ln(1 − P_G)` (the χ²₂ quantile). Its
//!   axes are the eigenvectors of `Σ̂_k`, its semi-axes `√(γλ)` (see
//!   [`pf_core::gaussian::error_ellipse`]). A detection outside every gate is clutter.
//! - **Energy, global** ([`Association::Energy`]). The abstract's "global minimization of
//!   an energy": each target takes at most one detection and each detection at most one
//!   target, minimising `Σ E(k, y_j)` over gated pairs plus [`MISS_COST`] per target left
//!   without one (Hungarian method).
//! - **Energy, per measurement** ([`Association::EnergyPerMeasurement`]). Eq. (1) read
//!   literally: `y_j → argmin_k E(k, y_j)` over the targets whose gate holds it; a target
//!   given several keeps the one of least energy.
//! - **NNSF** ([`Association::Nearest`]). Each detection goes to the validated target
//!   whose prediction is nearest (the Mahalanobis distance of E¹, from the same point); a
//!   target given several keeps the nearest (Li & Bar-Shalom 1996). This is how the paper
//!   applies it in Section 4 ("NNSF would associate M₂ to T₁").

use crate::assignment::Hungarian;
use crate::energy::{EnergyConfig, EnergyMatrix, TargetGeometry};
use crate::error::{EpfError, Result};
use crate::geometry::Vec2;
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// Cost of leaving a target without a detection in the global assignment. Every energy is
/// at most 1, so 2 makes one more assigned pair worth more than any reshuffle of one pair.
pub const MISS_COST: f64 = 2.0;

/// A cost that forbids a pair (outside the gate). Finite so the Hungarian arithmetic stays
/// exact; larger than any sum of real costs.
const FORBIDDEN: f64 = 1e9;

/// How detections are associated with targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Association {
    /// Global energy minimisation (optimal assignment on the E matrix).
    #[default]
    #[serde(rename = "energy")]
    Energy,
    /// The per-measurement argmin of eq. (1).
    #[serde(rename = "energy_per_measurement")]
    EnergyPerMeasurement,
    /// The nearest-neighbour standard filter.
    #[serde(rename = "nn")]
    Nearest,
}

impl Association {
    /// Every method.
    pub const ALL: [Association; 3] = [
        Association::Energy,
        Association::EnergyPerMeasurement,
        Association::Nearest,
    ];

    /// The name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Association::Energy => "energy",
            Association::EnergyPerMeasurement => "energy_per_measurement",
            Association::Nearest => "nn",
        }
    }
}

impl std::str::FromStr for Association {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        pf_core::names::parse_name("association", &Association::ALL, Association::name, s)
    }
}

/// `γ = −2 ln(1 − P_G)`: the squared Mahalanobis radius of the gate of probability `P_G`.
///
/// # Errors
/// [`EpfError::Param`] unless `0 < P_G < 1`.
pub fn gate_threshold(p_g: f64) -> Result<f64> {
    if !(p_g > 0.0 && p_g < 1.0) {
        return Err(EpfError::Param(ParamError {
            name: "P_G",
            value: p_g,
            reason: "the gate probability must lie in (0, 1)",
        }));
    }
    Ok(-2.0 * (-p_g).ln_1p())
}

/// `y_j → argmin_k cost(k, j)` over the targets whose gate holds `y_j` (ties to the lower
/// `k`); a target given several detections keeps the one of least cost. `cost` and `gated`
/// are K × M, row-major.
fn per_measurement_argmin(
    k: usize,
    m: usize,
    cost: &[f64],
    gated: &[bool],
    out: &mut [Option<usize>],
) {
    for j in 0..m {
        let best = (0..k)
            .filter(|&i| gated[i * m + j])
            .min_by(|&a, &b| cost[a * m + j].total_cmp(&cost[b * m + j]));
        if let Some(i) = best {
            let c = cost[i * m + j];
            if out[i].is_none_or(|jj| cost[i * m + jj] > c) {
                out[i] = Some(j);
            }
        }
    }
}

/// Association buffers, reused from frame to frame.
#[derive(Debug, Clone, Default)]
pub struct Associator {
    energy: EnergyMatrix,
    gated: Vec<bool>,
    cost: Vec<f64>,
    cols: Vec<usize>,
    hungarian: Hungarian,
}

impl Associator {
    /// Empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// The energies of the last [`associate`](Self::associate) call with an energy method.
    pub fn energy(&self) -> &EnergyMatrix {
        &self.energy
    }

    /// Whether detection `j` fell in target `k`'s gate in the last call.
    pub fn is_gated(&self, k: usize, j: usize, m: usize) -> bool {
        self.gated[k * m + j]
    }

    /// Associate `ys` with `targets`: `out[k]` becomes the index of target `k`'s detection,
    /// or `None`. `gamma` is the gate's squared Mahalanobis radius ([`gate_threshold`]).
    pub fn associate(
        &mut self,
        targets: &[TargetGeometry],
        ys: &[Vec2],
        gamma: f64,
        method: Association,
        cfg: &EnergyConfig,
        out: &mut [Option<usize>],
    ) {
        let (k, m) = (targets.len(), ys.len());
        self.gated.clear();
        for g in targets {
            for y in ys {
                self.gated.push(g.mahalanobis_sq(&g.a_t, y) <= gamma);
            }
        }
        out.fill(None);
        if method != Association::Nearest {
            self.energy.compute(targets, ys, cfg);
        }
        match method {
            Association::Nearest => {
                // Each detection goes to the nearest validated prediction (E¹'s distance).
                self.cost.clear();
                for g in targets {
                    let c = g.e1_centre(cfg.e1_reference);
                    self.cost.extend(ys.iter().map(|y| g.mahalanobis_sq(&c, y)));
                }
                per_measurement_argmin(k, m, &self.cost, &self.gated, out);
            }
            Association::EnergyPerMeasurement => {
                per_measurement_argmin(k, m, self.energy.magnitudes(), &self.gated, out);
            }
            Association::Energy => {
                // Columns: the M detections, then one "missed" column per target.
                let w = m + k;
                self.cost.clear();
                self.cost.resize(k * w, FORBIDDEN);
                for i in 0..k {
                    for j in 0..m {
                        if self.gated[i * m + j] {
                            self.cost[i * w + j] = self.energy.magnitude(i, j);
                        }
                    }
                    self.cost[i * w + m + i] = MISS_COST;
                }
                self.cols.clear();
                self.cols.resize(k, 0);
                if self
                    .hungarian
                    .solve(k, w, &self.cost, &mut self.cols)
                    .is_some()
                {
                    for (i, (o, &j)) in out.iter_mut().zip(&self.cols).enumerate() {
                        if j < m && self.gated[i * m + j] {
                            *o = Some(j);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::{SplineDynamics, SplineOrder};
    use nalgebra::Matrix2;

    /// A target seen at frames 3, 4, 5 at `p`, predicted at 6 by its straight motion, with
    /// covariance σ²I.
    fn target(p: [Vec2; 3], sigma: f64) -> TargetGeometry {
        let mut dynamics = SplineDynamics::new(SplineOrder::Quadratic);
        for (i, x) in p.iter().enumerate() {
            dynamics.push(3.0 + i as f64, *x);
        }
        let a_t = p[2] + dynamics.displacement(5.0, 1.0);
        TargetGeometry {
            a_tm2: p[1],
            a_tm1: p[2],
            a_t,
            a1_tp1: a_t + dynamics.displacement(6.0, 1.0),
            cov_inv: Matrix2::identity() / (sigma * sigma),
            dynamics,
            t: 6.0,
            dt_next: 1.0,
        }
    }

    fn run(targets: &[TargetGeometry], ys: &[Vec2], method: Association) -> Vec<Option<usize>> {
        let mut out = vec![None; targets.len()];
        Associator::new().associate(
            targets,
            ys,
            gate_threshold(0.99).unwrap(),
            method,
            &EnergyConfig::default(),
            &mut out,
        );
        out
    }

    /// Fig. 2: the plane's detection M₂ is √2 from the van's last position and 6 from the
    /// plane's, so NNSF gives it to the van; both targets move straight, and only the true
    /// pairing keeps both motions straight, so the energy gets it right.
    #[test]
    fn van_plane_energy_is_right_where_nnsf_must_fail() {
        let v = Vec2::new;
        let van = target([v(6.0, 0.0), v(8.0, 0.0), v(10.0, 0.0)], 0.6);
        let plane = target([v(10.85, 19.0), v(10.9, 13.0), v(10.95, 7.0)], 0.6);
        let ys = [v(12.0, 0.0), v(11.0, 1.0)];
        // The construction: M₂ is nearer the van's Â(t−1) than the plane's.
        assert!((ys[1] - van.a_tm1).norm() < (ys[1] - plane.a_tm1).norm());
        let targets = [van, plane];
        let nn = run(&targets, &ys, Association::Nearest);
        assert_eq!(nn, [Some(1), None], "NNSF gives M₂ to the van");
        for m in [Association::Energy, Association::EnergyPerMeasurement] {
            assert_eq!(run(&targets, &ys, m), [Some(0), Some(1)], "{m:?}");
        }
    }

    /// Fig. 3: T₂ and T₃ converge and cross; at t their detections are a metre apart and
    /// each is nearer the *other* man's last position (the occlusion makes them almost
    /// equidistant), so NNSF swaps or drops them; T₁ walks elsewhere.
    #[test]
    fn walking_men_energy_is_right_where_nnsf_must_fail() {
        let v = Vec2::new;
        let t1 = target([v(10.0, 7.0), v(11.5, 7.6), v(12.5, 8.2)], 0.7);
        let t2 = target([v(6.0, 3.0), v(8.0, 2.0), v(10.0, 1.0)], 0.7);
        let t3 = target([v(7.0, -3.0), v(9.0, -2.0), v(11.0, -1.0)], 0.7);
        let ys = [v(13.4, 8.8), v(12.0, 0.0), v(13.0, 0.0)];
        // M₂ (T₂'s) is nearer T₃'s last position than T₂'s.
        assert!((ys[1] - t3.a_tm1).norm() < (ys[1] - t2.a_tm1).norm());
        let targets = [t1, t2, t3];
        let nn = run(&targets, &ys, Association::Nearest);
        assert_ne!(nn[1], Some(1), "NNSF must not give T₂ its own detection");
        assert_ne!(nn[2], Some(2), "NNSF must not give T₃ its own detection");
        for m in [Association::Energy, Association::EnergyPerMeasurement] {
            assert_eq!(run(&targets, &ys, m), [Some(0), Some(1), Some(2)], "{m:?}");
        }
    }

    #[test]
    fn gate_threshold_is_the_chi2_quantile() {
        // χ²₂ CDF 1 − e^{−γ/2}: P_G = 1 − e^{−1} ⇔ γ = 2.
        assert!((gate_threshold(1.0 - (-1f64).exp()).unwrap() - 2.0).abs() < 1e-12);
        assert!(gate_threshold(1.0).is_err());
        assert!(gate_threshold(0.0).is_err());
    }
}
