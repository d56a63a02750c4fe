//! Data association (EPF step 1): gating by validation ellipsoids, then a rule applied to a
//! cost: each measurement on its own (eq. (1)) or a global one-to-one assignment, on the
//! energy `E` or on the distance to the prediction `Â(t)` (the NNSF's).
//!
//! - **Gate.** Detection `y_j` is validated for target `k` when it lies in the ellipsoid
//!   around the prediction `Â(t)` holding probability `P_G` of `N(Â(t), Σ̂_k)`:
//!   `(y_j − Â(t))ᵀ Σ̂_k⁻¹ (y_j − Â(t)) ≤ γ`, `γ = −2 ln(1 − P_G)` (the χ²₂ quantile). Its
//!   axes are the eigenvectors of `Σ̂_k`, its semi-axes `√(γλ)` (see
//!   [`pf_core::gaussian::error_ellipse`]). A detection outside every gate is clutter.
//! - **Per measurement** (eq. (1), Section 3 step 1): `y_j → argmin_k cost(k, y_j)` over the
//!   targets whose gate holds `y_j`; a target given several keeps the one of least cost.
//! - **Global**: each target takes at most one detection and each detection at most one
//!   target, minimising the total cost over gated pairs plus a miss cost per target left
//!   without one (Hungarian method); the abstract's "global minimization of an energy".
//!
//! | name | rule | cost | paper |
//! |---|---|---|---|
//! | `energy_per_measurement` ([`Association::EnergyPerMeasurement`]) | per measurement | `E(k, y_j)`, eq. (1) | the EPF |
//! | `energy` ([`Association::Energy`], the tracker's default) | global | `E`, a miss costs [`MISS_COST`] | the abstract's "global minimization of an energy" |
//! | `nn` ([`Association::Nearest`]) | per measurement | Mahalanobis distance to `Â(t)` | the NNSF: "the closest validate measurement to a predicted target" (Li & Bar-Shalom 1996) |
//! | `nn_global` ([`Association::NearestGlobal`]) | global | squared Mahalanobis distance to `Â(t)`, a miss costs `2γ` | global nearest neighbour |
//! | `nn_previous` ([`Association::NearestPrevious`]) | per measurement | Mahalanobis distance to `Â(t−1)`, E¹'s | Section 4's "NNSF would associate M₂ to T₁" |
//!
//! `nn_previous` is kept because it is the distance under which Section 4's examples make
//! NNSF fail (the detection is judged by where the targets were, as `α₁E¹` is), and because
//! it is `energy_per_measurement` with E² and E³ left out up to the normalisation, which
//! isolates what the two geometric energies add. `energy` keeps the meaning it had (the
//! global assignment on E): it is the better of the two rules on every scene of the report.

use crate::assignment::Hungarian;
use crate::energy::{EnergyConfig, EnergyMatrix, TargetGeometry};
use crate::error::{EpfError, Result};
use crate::geometry::Vec2;
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// Cost of leaving a target without a detection in the global energy assignment. Every
/// energy is at most 1, so 2 makes one more assigned pair worth more than any reshuffle of
/// one pair.
pub const MISS_COST: f64 = 2.0;

/// A cost that forbids a pair (outside the gate). Finite so the Hungarian arithmetic stays
/// exact; larger than any sum of real costs.
const FORBIDDEN: f64 = 1e9;

/// How detections are associated with targets: a rule and a cost (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Association {
    /// Global energy minimisation (optimal assignment on the E matrix); the default.
    #[default]
    #[serde(rename = "energy")]
    Energy,
    /// Eq. (1): each measurement to the gated target of least energy (the paper's EPF).
    #[serde(rename = "energy_per_measurement")]
    EnergyPerMeasurement,
    /// The nearest-neighbour standard filter: each measurement to the gated target whose
    /// prediction `Â(t)` is nearest.
    #[serde(rename = "nn")]
    Nearest,
    /// Global nearest neighbour: optimal assignment on the squared distance to `Â(t)`.
    #[serde(rename = "nn_global")]
    NearestGlobal,
    /// Each measurement to the gated target whose previous estimate `Â(t−1)` is nearest
    /// (E¹'s distance).
    #[serde(rename = "nn_previous")]
    NearestPrevious,
}

/// Which cost an [`Association`] minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cost {
    /// `E(k, y_j)`, eq. (1).
    Energy,
    /// The squared Mahalanobis distance from the prediction `Â(t)`.
    DistancePredicted,
    /// The squared Mahalanobis distance from the previous estimate `Â(t−1)`.
    DistancePrevious,
}

impl Association {
    /// Every method.
    pub const ALL: [Association; 5] = [
        Association::Energy,
        Association::EnergyPerMeasurement,
        Association::Nearest,
        Association::NearestGlobal,
        Association::NearestPrevious,
    ];

    /// The name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Association::Energy => "energy",
            Association::EnergyPerMeasurement => "energy_per_measurement",
            Association::Nearest => "nn",
            Association::NearestGlobal => "nn_global",
            Association::NearestPrevious => "nn_previous",
        }
    }

    /// Whether the rule is the global assignment (otherwise per measurement, eq. (1)).
    pub fn is_global(self) -> bool {
        matches!(self, Association::Energy | Association::NearestGlobal)
    }

    /// The cost the rule minimises.
    pub fn cost(self) -> Cost {
        match self {
            Association::Energy | Association::EnergyPerMeasurement => Cost::Energy,
            Association::Nearest | Association::NearestGlobal => Cost::DistancePredicted,
            Association::NearestPrevious => Cost::DistancePrevious,
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

/// Eq. (1)'s rule: `y_j → argmin_k cost(k, j)` over the targets whose gate holds `y_j`
/// (ties to the lower `k`); a target given several detections keeps the one of least cost.
/// `cost` and `gated` are K × M, row-major; `out` has K entries.
pub fn per_measurement_argmin(
    k: usize,
    m: usize,
    cost: &[f64],
    gated: &[bool],
    out: &mut [Option<usize>],
) {
    out.fill(None);
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
    padded: Vec<f64>,
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

    /// The global rule: the optimal assignment on `cost` (K × M, row-major) over gated
    /// pairs, a target left without a detection costing `miss`; `out[k]` its detection.
    pub fn global_assignment(
        &mut self,
        k: usize,
        m: usize,
        cost: &[f64],
        gated: &[bool],
        miss: f64,
        out: &mut [Option<usize>],
    ) {
        out.fill(None);
        // Columns: the M detections, then one "missed" column per target.
        let w = m + k;
        self.padded.clear();
        self.padded.resize(k * w, FORBIDDEN);
        for i in 0..k {
            for j in 0..m {
                if gated[i * m + j] {
                    self.padded[i * w + j] = cost[i * m + j];
                }
            }
            self.padded[i * w + m + i] = miss;
        }
        self.cols.clear();
        self.cols.resize(k, 0);
        if self
            .hungarian
            .solve(k, w, &self.padded, &mut self.cols)
            .is_some()
        {
            for (i, (o, &j)) in out.iter_mut().zip(&self.cols).enumerate() {
                if j < m && gated[i * m + j] {
                    *o = Some(j);
                }
            }
        }
    }

    /// Associate `ys` with `targets`: `out[k]` becomes the index of target `k`'s detection,
    /// or `None`. `gamma` is the gate's squared Mahalanobis radius ([`gate_threshold`]).
    /// The energies are computed only for the energy methods.
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
        let mut cost = std::mem::take(&mut self.cost);
        cost.clear();
        let miss = match method.cost() {
            Cost::Energy => {
                self.energy.compute(targets, ys, cfg);
                cost.extend_from_slice(self.energy.magnitudes());
                MISS_COST
            }
            Cost::DistancePredicted | Cost::DistancePrevious => {
                for g in targets {
                    let c = if method.cost() == Cost::DistancePredicted {
                        g.a_t
                    } else {
                        g.a_tm1
                    };
                    cost.extend(ys.iter().map(|y| g.mahalanobis_sq(&c, y)));
                }
                // Every gated pair has a squared distance to Â(t) of at most γ.
                2.0 * gamma
            }
        };
        if method.is_global() {
            let gated = std::mem::take(&mut self.gated);
            self.global_assignment(k, m, &cost, &gated, miss, out);
            self.gated = gated;
        } else {
            per_measurement_argmin(k, m, &cost, &self.gated, out);
        }
        self.cost = cost;
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
        let nn = run(&targets, &ys, Association::NearestPrevious);
        assert_eq!(nn, [Some(1), None], "NN to Â(t−1) gives M₂ to the van");
        // The energies, and nearest neighbour to the predictions Â(t), are right.
        for m in [
            Association::Energy,
            Association::EnergyPerMeasurement,
            Association::Nearest,
            Association::NearestGlobal,
        ] {
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
        let nn = run(&targets, &ys, Association::NearestPrevious);
        assert_ne!(
            nn[1],
            Some(1),
            "NN to Â(t−1) must not give T₂ its own detection"
        );
        assert_ne!(
            nn[2],
            Some(2),
            "NN to Â(t−1) must not give T₃ its own detection"
        );
        for m in [
            Association::Energy,
            Association::EnergyPerMeasurement,
            Association::Nearest,
            Association::NearestGlobal,
        ] {
            assert_eq!(run(&targets, &ys, m), [Some(0), Some(1), Some(2)], "{m:?}");
        }
    }

    /// A frame where eq. (1)'s per-measurement rule and the global assignment disagree: both
    /// detections are nearest to A, so per measurement A keeps the nearer and B gets
    /// none; globally A-M₁ + B-M₂ (1 + 1.8² = 4.24) beats A-M₂ + B-M₁ (1.2² + 2² = 5.44) and
    /// any miss (2γ ≈ 18.4). The same on a hand-made energy matrix.
    #[test]
    fn per_measurement_and_global_rules_disagree_on_a_constructed_frame() {
        let v = Vec2::new;
        let at = |p: Vec2| TargetGeometry {
            a_tm2: p - v(0.0, 2.0),
            a_tm1: p - v(0.0, 1.0),
            a_t: p,
            a1_tp1: p + v(0.0, 1.0),
            cov_inv: Matrix2::identity(),
            dynamics: SplineDynamics::new(SplineOrder::CubicBSpline),
            t: 6.0,
            dt_next: 1.0,
        };
        let targets = [at(v(0.0, 0.0)), at(v(3.0, 0.0))];
        let ys = [v(1.0, 0.0), v(1.2, 0.0)];
        assert_eq!(run(&targets, &ys, Association::Nearest), [Some(0), None]);
        assert_eq!(
            run(&targets, &ys, Association::NearestGlobal),
            [Some(0), Some(1)]
        );
        let cost = [0.1, 0.2, 0.3, 0.35];
        let gated = [true; 4];
        let mut out = [None; 2];
        per_measurement_argmin(2, 2, &cost, &gated, &mut out);
        assert_eq!(out, [Some(0), None]);
        Associator::new().global_assignment(2, 2, &cost, &gated, MISS_COST, &mut out);
        assert_eq!(out, [Some(0), Some(1)]);
        // A pair outside the gate is never taken, whatever its cost.
        let gated = [true, false, true, true];
        Associator::new().global_assignment(2, 2, &cost, &gated, MISS_COST, &mut out);
        assert_eq!(out, [Some(0), Some(1)]);
        per_measurement_argmin(2, 2, &cost, &gated, &mut out);
        assert_eq!(out, [Some(0), Some(1)]);
    }

    #[test]
    fn names_parse_and_serialise_alike() {
        for a in Association::ALL {
            assert_eq!(a.name().parse::<Association>(), Ok(a));
            let json = serde_json::to_string(&a).unwrap();
            assert_eq!(json, format!("\"{}\"", a.name()));
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
