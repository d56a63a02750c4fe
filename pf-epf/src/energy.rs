//! The three energies of Section 2 and their normalised magnitude, eq. (1).
//!
//! For target `k` (the paper's A) and detection `y_j` at frame `t`:
//! - `E¹(k, y_j) = √((y_j − Â)ᵀ Σ̂_k⁻¹ (y_j − Â))`, the Mahalanobis distance energy;
//! - `E²(k, y_j) = |S₁ − S₂|`, the absolute accuracy evolution energy: `S₁` is the
//!   intersection area of the circumcircles of `(Â(t−2), Â(t−1), Â(t))` and
//!   `(Â(t−1), Â(t), Â₁(t+1))`, `S₂` that of `(Â(t−2), Â(t−1), y_j)` and
//!   `(Â(t−1), y_j, Â₂(t+1))` (Fig. 1a–d);
//! - `E³(k, y_j) = 1/S`, the proximity evolution energy: `S` is the intersection area of the
//!   triangles `(Â(t−2), Â(t−1), y_j)` and `(Â(t−2), Â(t−1), Â(t))` (Fig. 1e);
//! - `E(k, y_j) = (1/√3)·√(Σ_l α_l² E^l(k, y_j)²)`, `α_l = 1/Σ_{k=1}^K E^l(k, y_j)` (eq. (1)).
//!
//! ## Reading of E¹
//! The paper says E¹ measures the distance between `y_j` and "the prediction of A at
//! (t−1)", and writes `Â(t−1)` in the formula. We take it literally: `Â(t−1)`, the
//! target's estimate at the previous frame ([`E1Reference::Previous`], the default). This
//! is also the only reading under which Section 4's claims hold: the van–plane detection
//! "closer to T₁" and the walking men's "equidistant" detection are judged by where the
//! targets were, while the dynamics enter through the gate (centred on `Â(t)`), E² and E³.
//! The other reading, the one-step prediction `Â(t)`, is [`E1Reference::Predicted`]; the
//! report shows the nearest-neighbour filter under it too.
//!
//! ## Degenerate geometry (never NaN)
//! - A circumcircle of collinear or coincident points, or of radius above
//!   `radius_cap ×` its triangle's longest side, is a straight line ("a circle at
//!   infinity"): it encloses no finite disc, and its intersection area with anything is 0.
//!   So straight motion gives `S₁ = 0`, and a detection that keeps it straight `S₂ = 0`.
//! - If the reference triangle `(Â(t−2), Â(t−1), Â(t))` is straight in that sense, the
//!   motion has no side to compare with and `E³ = 0` ("most of time the third energy is
//!   null … due to the presence of a linear displacement", Table 1).
//! - Otherwise an empty triangle intersection would make `E³ = 1/0`; `S` is floored at
//!   `e3_floor ×` the reference triangle's area, so `E³ ≤ 1/(e3_floor·area)`.
//! - When `Σ_k E^l(k, y_j) = 0` no target is distinguished by component `l`; its weighted
//!   terms `α_l E^l` are then 0 for every `k`.
//!
//! With these rules every `α_l E^l` lies in `[0, 1]`, so `E` lies in `[0, 1]` as the paper
//! states under eq. (1).

use crate::dynamics::SplineDynamics;
use crate::error::{EpfError, Result};
use crate::geometry::{
    Circle, Vec2, circle_intersection_area, circumcircle, triangle_area, triangle_intersection_area,
};
use nalgebra::Matrix2;
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// Which prediction E¹ (and the nearest-neighbour baseline) measures distance to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum E1Reference {
    /// `Â(t−1)`, the estimate at the previous frame (the paper's formula; default).
    #[default]
    Previous,
    /// `Â(t)`, the prediction made at `t − 1` for `t`.
    Predicted,
}

/// Choices the paper leaves open in the energies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnergyConfig {
    /// The point E¹ is measured from.
    pub e1_reference: E1Reference,
    /// A circumcircle whose radius exceeds this multiple of its triangle's longest side `c`
    /// is a straight line. `R = c/(2 sin δ)` for a path turning by `δ` at the middle point,
    /// so this treats turns below `asin(1/(2·radius_cap))` as straight: 14.5° for the
    /// default 2. Smaller turns are within detection noise at our scenarios' spacings, and
    /// counting them made E² follow the noise (see the crate README).
    pub radius_cap: f64,
    /// Floor on the triangle intersection `S`, as a fraction of the reference triangle's
    /// area, so that `E³ = 1/S` stays finite. Default 1e-3.
    pub e3_floor: f64,
    /// Which of `E¹, E², E³` enter eq. (1); a component left out counts as 0 for every
    /// pair (for ablations such as the paper's "necessity of using the energy E³"). Default
    /// all three.
    #[serde(default = "all_components")]
    pub components: [bool; 3],
}

fn all_components() -> [bool; 3] {
    [true; 3]
}

impl Default for EnergyConfig {
    fn default() -> Self {
        EnergyConfig {
            e1_reference: E1Reference::Previous,
            radius_cap: 2.0,
            e3_floor: 1e-3,
            components: all_components(),
        }
    }
}

impl EnergyConfig {
    /// Check that the configuration can run.
    ///
    /// # Errors
    /// [`EpfError::Param`] for a non-positive or non-finite cap or floor.
    pub fn validate(&self) -> Result<()> {
        if !(self.radius_cap > 0.0 && self.radius_cap.is_finite()) {
            return Err(EpfError::Param(ParamError {
                name: "radius_cap",
                value: self.radius_cap,
                reason: "must be a positive finite multiple of the triangle's longest side",
            }));
        }
        if !(self.e3_floor > 0.0 && self.e3_floor <= 1.0) {
            return Err(EpfError::Param(ParamError {
                name: "e3_floor",
                value: self.e3_floor,
                reason: "must lie in (0, 1]",
            }));
        }
        Ok(())
    }
}

/// What the energies need to know about one target at frame `t` (Fig. 1 notation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetGeometry {
    /// `Â(t−2)`.
    pub a_tm2: Vec2,
    /// `Â(t−1)`.
    pub a_tm1: Vec2,
    /// `Â(t)`, predicted by the not-updated dynamic model.
    pub a_t: Vec2,
    /// `Â₁(t+1)`, predicted by the not-updated dynamic model.
    pub a1_tp1: Vec2,
    /// `Σ̂_k⁻¹`, the inverse of the target's covariance.
    pub cov_inv: Matrix2<f64>,
    /// The not-updated dynamic model, updated per detection for `Â₂(t+1)`.
    pub dynamics: SplineDynamics,
    /// Frame `t`.
    pub t: f64,
    /// Frames from `t` to `t + 1` (the next observation), for `Â(t+1)`.
    pub dt_next: f64,
}

impl TargetGeometry {
    /// `Â₂(t+1)`: the prediction after `y` is associated at `t` and the model updated.
    pub fn a2_tp1(&self, y: &Vec2) -> Vec2 {
        y + self
            .dynamics
            .updated(self.t, *y)
            .displacement(self.t, self.dt_next)
    }

    /// The point E¹ measures from.
    pub fn e1_centre(&self, r: E1Reference) -> Vec2 {
        match r {
            E1Reference::Predicted => self.a_t,
            E1Reference::Previous => self.a_tm1,
        }
    }

    /// Squared Mahalanobis distance of `y` from `centre` under `Σ̂_k`.
    pub fn mahalanobis_sq(&self, centre: &Vec2, y: &Vec2) -> f64 {
        let r = y - centre;
        (r.transpose() * self.cov_inv * r)[(0, 0)].max(0.0)
    }
}

/// A circumcircle, or `None` when it is a straight line in the sense of the module docs.
fn finite_circle(a: &Vec2, b: &Vec2, c: &Vec2, radius_cap: f64) -> Option<Circle> {
    let longest = (a - b).norm().max((b - c).norm()).max((c - a).norm());
    circumcircle(a, b, c).filter(|circ| circ.radius <= radius_cap * longest)
}

/// Intersection area of the circumcircles of two triangles (0 if either is a line).
fn circles_area(t1: [&Vec2; 3], t2: [&Vec2; 3], cap: f64) -> f64 {
    match (
        finite_circle(t1[0], t1[1], t1[2], cap),
        finite_circle(t2[0], t2[1], t2[2], cap),
    ) {
        (Some(c1), Some(c2)) => circle_intersection_area(&c1, &c2),
        _ => 0.0,
    }
}

/// The raw components `[E¹, E², E³]` for target `g` and detection `y`.
pub fn components(g: &TargetGeometry, y: &Vec2, cfg: &EnergyConfig) -> [f64; 3] {
    let e1 = g.mahalanobis_sq(&g.e1_centre(cfg.e1_reference), y).sqrt();
    let s1 = circles_area(
        [&g.a_tm2, &g.a_tm1, &g.a_t],
        [&g.a_tm1, &g.a_t, &g.a1_tp1],
        cfg.radius_cap,
    );
    let a2 = g.a2_tp1(y);
    let s2 = circles_area([&g.a_tm2, &g.a_tm1, y], [&g.a_tm1, y, &a2], cfg.radius_cap);
    let e2 = (s1 - s2).abs();
    let e3 = if finite_circle(&g.a_tm2, &g.a_tm1, &g.a_t, cfg.radius_cap).is_none() {
        0.0
    } else {
        let area_ref = triangle_area(&g.a_tm2, &g.a_tm1, &g.a_t);
        let s = triangle_intersection_area(&[g.a_tm2, g.a_tm1, *y], &[g.a_tm2, g.a_tm1, g.a_t]);
        1.0 / s.max(cfg.e3_floor * area_ref)
    };
    let mut e = [e1, e2, e3].map(|e| if e.is_finite() { e } else { f64::MAX });
    for (e, used) in e.iter_mut().zip(cfg.components) {
        if !used {
            *e = 0.0;
        }
    }
    e
}

/// Eq. (1) for one pair `(k, y_j)`, term by term ([`EnergyMatrix::terms`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EnergyTerms {
    /// `[E¹, E², E³](k, y_j)`.
    pub raw: [f64; 3],
    /// `Σ_k E^l(k, y_j)` over all K targets, per component.
    pub column_sum: [f64; 3],
    /// `α_l = 1/Σ_k E^l(k, y_j)` (0 where the sum is 0: the component then distinguishes no
    /// target).
    pub alpha: [f64; 3],
    /// `α_l E^l(k, y_j)`.
    pub weighted: [f64; 3],
    /// `E(k, y_j) = (1/√3)·√(Σ_l (α_l E^l)²)`.
    pub e: f64,
}

/// The K × M energies of every target against every detection of one frame: raw
/// components, their normalised values `α_l E^l` and the magnitude `E` of eq. (1).
/// Row-major (`k·M + j`); buffers are reused from frame to frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EnergyMatrix {
    k: usize,
    m: usize,
    raw: Vec<[f64; 3]>,
    weighted: Vec<[f64; 3]>,
    e: Vec<f64>,
}

impl EnergyMatrix {
    /// An empty matrix.
    pub fn new() -> Self {
        Self::default()
    }

    /// Fill the matrix for `targets` × `ys`.
    pub fn compute(&mut self, targets: &[TargetGeometry], ys: &[Vec2], cfg: &EnergyConfig) {
        let (k, m) = (targets.len(), ys.len());
        self.k = k;
        self.m = m;
        self.raw.clear();
        for g in targets {
            for y in ys {
                self.raw.push(components(g, y, cfg));
            }
        }
        self.weighted.clear();
        self.weighted.resize(k * m, [0.0; 3]);
        self.e.clear();
        self.e.resize(k * m, 0.0);
        for j in 0..m {
            for l in 0..3 {
                // α_l = 1 / Σ_k E^l(k, y_j).
                let sum: f64 = (0..k).map(|i| self.raw[i * m + j][l]).sum();
                for i in 0..k {
                    let x = self.raw[i * m + j][l];
                    self.weighted[i * m + j][l] = if sum > 0.0 && sum.is_finite() {
                        (x / sum).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                }
            }
            for i in 0..k {
                let w = self.weighted[i * m + j];
                self.e[i * m + j] = ((w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) / 3.0).sqrt();
            }
        }
    }

    /// Number of targets `K`.
    pub fn n_targets(&self) -> usize {
        self.k
    }

    /// Number of detections `M`.
    pub fn n_detections(&self) -> usize {
        self.m
    }

    /// `[E¹, E², E³](k, y_j)`.
    pub fn raw(&self, k: usize, j: usize) -> [f64; 3] {
        self.raw[k * self.m + j]
    }

    /// `[α₁E¹, α₂E², α₃E³](k, y_j)`.
    pub fn weighted(&self, k: usize, j: usize) -> [f64; 3] {
        self.weighted[k * self.m + j]
    }

    /// `E(k, y_j)`, eq. (1).
    pub fn magnitude(&self, k: usize, j: usize) -> f64 {
        self.e[k * self.m + j]
    }

    /// Eq. (1) for the pair `(k, y_j)` term by term: the raw components, their column sums
    /// `Σ_k E^l(k, y_j)` over all K targets, `α_l`, `α_l E^l` and `E`.
    pub fn terms(&self, k: usize, j: usize) -> EnergyTerms {
        let raw = self.raw(k, j);
        let column_sum: [f64; 3] =
            std::array::from_fn(|l| (0..self.k).map(|i| self.raw(i, j)[l]).sum());
        EnergyTerms {
            raw,
            column_sum,
            alpha: column_sum.map(|c| {
                if c > 0.0 && c.is_finite() {
                    1.0 / c
                } else {
                    0.0
                }
            }),
            weighted: self.weighted(k, j),
            e: self.magnitude(k, j),
        }
    }

    /// All magnitudes, row-major.
    pub fn magnitudes(&self) -> &[f64] {
        &self.e
    }

    /// Component `l` (0-based) of the weighted energies as K rows of M values; `l = 3`
    /// gives `E`.
    pub fn rows(&self, l: usize) -> Vec<Vec<f64>> {
        (0..self.k)
            .map(|i| {
                (0..self.m)
                    .map(|j| {
                        if l < 3 {
                            self.weighted(i, j)[l]
                        } else {
                            self.magnitude(i, j)
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// Component `l` (0-based) of the raw energies as K rows of M values.
    pub fn raw_rows(&self, l: usize) -> Vec<Vec<f64>> {
        (0..self.k)
            .map(|i| (0..self.m).map(|j| self.raw(i, j)[l]).collect())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::SplineOrder;
    use rand::RngExt;

    fn geometry(pts: [Vec2; 3], cov_scale: f64) -> TargetGeometry {
        let mut dynamics = SplineDynamics::new(SplineOrder::Quadratic);
        for (i, p) in pts.iter().enumerate() {
            dynamics.push(i as f64, *p);
        }
        let a_t = pts[2] + dynamics.displacement(2.0, 1.0);
        TargetGeometry {
            a_tm2: pts[1],
            a_tm1: pts[2],
            a_t,
            a1_tp1: a_t + dynamics.displacement(3.0, 1.0),
            cov_inv: Matrix2::identity() / cov_scale,
            dynamics,
            t: 3.0,
            dt_next: 1.0,
        }
    }

    /// E ∈ [0, 1] and each α_l E^l column sums to 1 (or is all 0) over the targets, for
    /// random targets and detections, degenerate ones included (repeated and collinear
    /// points), and never NaN.
    #[test]
    fn energies_lie_in_the_unit_interval_and_alphas_normalise() {
        let mut rng = pf_core::mc::stream_rng(5, 0);
        let mut m = EnergyMatrix::new();
        let cfg = EnergyConfig::default();
        for trial in 0..300 {
            let k = rng.random_range(1..5);
            let n_y = rng.random_range(1..6);
            let mut pt = |s: f64| Vec2::new(rng.random_range(-s..s), rng.random_range(-s..s));
            let targets: Vec<TargetGeometry> = (0..k)
                .map(|i| {
                    let a = pt(10.0);
                    let pts = match (trial + i) % 4 {
                        // Straight motion.
                        0 => [a, a + Vec2::new(1.0, 1.0), a + Vec2::new(2.0, 2.0)],
                        // A target that has not moved.
                        1 => [a, a, a],
                        _ => [a, pt(10.0), pt(10.0)],
                    };
                    geometry(pts, 0.5 + (trial % 3) as f64)
                })
                .collect();
            let mut ys: Vec<Vec2> = (0..n_y).map(|_| pt(12.0)).collect();
            // A detection exactly on a prediction and one on the previous position.
            ys.push(targets[0].a_t);
            ys.push(targets[0].a_tm1);
            m.compute(&targets, &ys, &cfg);
            for j in 0..ys.len() {
                for l in 0..3 {
                    let col: f64 = (0..k).map(|i| m.weighted(i, j)[l]).sum();
                    assert!(
                        col.abs() < 1e-12 || (col - 1.0).abs() < 1e-12,
                        "Σ_k α_{l}E^{l} = {col}"
                    );
                    let raw: f64 = (0..k).map(|i| m.raw(i, j)[l]).sum();
                    assert_eq!(
                        raw > 0.0,
                        col > 0.5,
                        "α_l is 1/Σ_k E^l when the sum is positive"
                    );
                }
                for i in 0..k {
                    let e = m.magnitude(i, j);
                    assert!((0.0..=1.0).contains(&e), "E = {e}");
                    let t = m.terms(i, j);
                    for l in 0..3 {
                        let w = (t.alpha[l] * t.raw[l]).clamp(0.0, 1.0);
                        assert!((t.weighted[l] - w).abs() < 1e-12, "α_l E^l term by term");
                    }
                    assert_eq!(t.e, e);
                    let w = m.weighted(i, j);
                    let expected = ((w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) / 3.0).sqrt();
                    assert!((e - expected).abs() < 1e-15, "eq. (1)");
                }
            }
        }
    }

    /// Straight motion gives S₁ = 0 and E³ = 0; a detection continuing it gives E² = 0,
    /// one that bends it E² > 0 (the paper's reading of Fig. 1 and Table 1).
    #[test]
    fn straight_motion_zeroes_e3_and_e2_only_for_the_straight_detection() {
        let g = geometry(
            [
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(2.0, 0.0),
            ],
            1.0,
        );
        let cfg = EnergyConfig::default();
        let on = components(&g, &Vec2::new(3.0, 0.0), &cfg);
        let off = components(&g, &Vec2::new(3.0, 1.0), &cfg);
        assert_eq!(on[1], 0.0);
        assert!(off[1] > 0.0);
        assert_eq!(on[2], 0.0);
        assert_eq!(off[2], 0.0);
        // E¹ from Â(t−1) = (2, 0): 1 and √2 with Σ = I.
        assert!((on[0] - 1.0).abs() < 1e-12);
        assert!((off[0] - 2f64.sqrt()).abs() < 1e-12);
    }

    /// The α normalisation is relative among targets: where a component is 0 for every
    /// target but one (here E³, for a straight target and a turning one), that one gets
    /// α_l E^l = 1 whatever the size of its E^l, for every detection that keeps the straight
    /// target straight, its own included. This is the limit the report's term-by-term
    /// tables show deciding wrong associations.
    #[test]
    fn a_component_nonzero_for_one_target_only_weighs_one_whatever_its_size() {
        let v = Vec2::new;
        let turning = geometry([v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.6)], 1.0);
        let straight = geometry([v(0.0, 5.0), v(1.0, 5.0), v(2.0, 5.0)], 1.0);
        let ys = [v(3.0, 5.0), v(3.5, 5.0)];
        let mut m = EnergyMatrix::new();
        m.compute(&[turning, straight], &ys, &EnergyConfig::default());
        let (a, b) = (m.terms(0, 0), m.terms(0, 1));
        assert!(a.raw[2] > 0.0 && b.raw[2] > 0.0 && a.raw[2] != b.raw[2]);
        for j in 0..2 {
            assert_eq!(m.raw(1, j)[2], 0.0, "the straight target's E³");
            assert_eq!(m.weighted(0, j)[2], 1.0, "α₃E³ of the turning target");
            assert_eq!(m.weighted(1, j)[2], 0.0);
        }
    }
}
