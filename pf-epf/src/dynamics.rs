//! The adaptive dynamic model (Section 1 and EPF step 2, ref. \[4\]): a target moves with a
//! velocity `v` and an acceleration `a` that are re-estimated from the spline through its
//! associated observations each time one is associated.
//!
//! Ref. \[4\] (El Abed et al. 2006) fits a cubic B-spline whose control points are the
//! available observations; the paper gives no formula. We take the spline's end derivatives
//! from its last three control points `(τ₀, P₀), (τ₁, P₁), (τ₂, P₂)` with knots at the
//! observation frames: the local quadratic through them, differentiated at `τ₂`,
//!
//! `a = 2·P[τ₂, τ₁, τ₀]`, `v = P[τ₂, τ₁] + P[τ₂, τ₁, τ₀]·(τ₂ − τ₁)` (divided differences),
//!
//! which is exact for uniformly accelerated motion at any frame spacing (on uniform knots it
//! is the second-order backward difference). With two control points, or with
//! [`SplineOrder::Linear`] (the default), `a = 0` and `v` is the last chord's slope: the
//! quadratic end multiplies the detection noise by √14 when it extrapolates one spacing
//! ahead, against √2 for the chord, and on our scenarios that noise costs more
//! associations than the curvature it captures (see the crate README).

use crate::geometry::Vec2;
use serde::{Deserialize, Serialize};

/// The polynomial order of the end behaviour used to extrapolate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SplineOrder {
    /// Constant velocity from the last two control points (`a = 0`); the default, because
    /// the quadratic's extrapolation multiplies detection noise by √14 at unit spacing
    /// (see [`SplineDynamics::displacement_noise_factor`]).
    #[default]
    Linear,
    /// Velocity and acceleration from the last three control points.
    Quadratic,
}

/// The dynamic model `x(t + Δ) = x(t) + v(t)·Δ + ½·a·Δ²` of one target, with its last
/// three control points `(frame, position)`. `Copy` and fixed-size: updating it never
/// allocates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplineDynamics {
    /// Control points, oldest first; only the first `len` are set.
    points: [(f64, Vec2); 3],
    len: usize,
    order: SplineOrder,
    /// `v` at the last control point's frame.
    v: Vec2,
    /// `a`.
    a: Vec2,
}

impl SplineDynamics {
    /// A model with no control point yet (it predicts no motion).
    pub fn new(order: SplineOrder) -> Self {
        SplineDynamics {
            points: [(0.0, Vec2::zeros()); 3],
            len: 0,
            order,
            v: Vec2::zeros(),
            a: Vec2::zeros(),
        }
    }

    /// Add an associated observation at `frame` and re-estimate `v` and `a` (EPF step 2).
    /// A control point at a frame not after the last one replaces the last one.
    pub fn push(&mut self, frame: f64, y: Vec2) {
        if self.len > 0 && frame <= self.points[self.len - 1].0 {
            self.points[self.len - 1] = (frame, y);
        } else if self.len < 3 {
            self.points[self.len] = (frame, y);
            self.len += 1;
        } else {
            self.points.rotate_left(1);
            self.points[2] = (frame, y);
        }
        self.estimate();
    }

    /// The model updated with `y` at `frame`, leaving `self` untouched (for Â₂(t+1)).
    pub fn updated(&self, frame: f64, y: Vec2) -> Self {
        let mut d = *self;
        d.push(frame, y);
        d
    }

    fn estimate(&mut self) {
        let pts = &self.points[..self.len];
        (self.v, self.a) = match (pts, self.order) {
            ([.., (t1, p1), (t2, p2)], SplineOrder::Linear) | ([(t1, p1), (t2, p2)], _) => {
                ((p2 - p1) / (t2 - t1), Vec2::zeros())
            }
            ([(t0, p0), (t1, p1), (t2, p2)], SplineOrder::Quadratic) => {
                let d21 = (p2 - p1) / (t2 - t1);
                let d10 = (p1 - p0) / (t1 - t0);
                let d210 = (d21 - d10) / (t2 - t0);
                (d21 + d210 * (t2 - t1), 2.0 * d210)
            }
            _ => (Vec2::zeros(), Vec2::zeros()),
        };
    }

    /// Number of control points held (at most 3).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no control point is held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The acceleration `a`.
    pub fn acceleration(&self) -> Vec2 {
        self.a
    }

    /// The velocity `v(t) = v(τ_last) + a·(t − τ_last)` at frame `t`.
    pub fn velocity_at(&self, t: f64) -> Vec2 {
        match self.len {
            0 => Vec2::zeros(),
            n => self.v + self.a * (t - self.points[n - 1].0),
        }
    }

    /// How much detection noise the displacement carries: `d = P(t + Δ) − P(t)` with `P`
    /// the polynomial through the control points used (the last two for
    /// [`SplineOrder::Linear`], three for [`SplineOrder::Quadratic`]), so
    /// `d = Σ_i c_i P_i` with `c_i = L_i(t + Δ) − L_i(t)` (Lagrange basis), and independent
    /// detection noise of variance `r²` per coordinate gives `Var d = r² Σ_i c_i²`. Returns
    /// `Σ_i c_i²` (0 with fewer than two points). It widens the gate around `Â(t)`.
    pub fn displacement_noise_factor(&self, t: f64, dt: f64) -> f64 {
        let used = match (self.order, self.len) {
            (_, 0 | 1) => return 0.0,
            (SplineOrder::Linear, _) | (_, 2) => 2,
            (SplineOrder::Quadratic, _) => 3,
        };
        let taus: Vec<f64> = self.points[self.len - used..self.len]
            .iter()
            .map(|p| p.0)
            .collect();
        let basis = |tau: f64, i: usize| -> f64 {
            taus.iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &tj)| (tau - tj) / (taus[i] - tj))
                .product()
        };
        (0..used)
            .map(|i| (basis(t + dt, i) - basis(t, i)).powi(2))
            .sum()
    }

    /// The displacement `v(t)·Δ + ½·a·Δ²` from frame `t` to `t + Δ`.
    pub fn displacement(&self, t: f64, dt: f64) -> Vec2 {
        self.velocity_at(t) * dt + self.a * (0.5 * dt * dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniformly_accelerated_motion_is_reproduced_exactly_on_uneven_frames() {
        // x(t) = x₀ + v₀t + ½at², observed at frames 10, 25, 35 (the paper's ants spacing).
        let (x0, v0, a) = (
            Vec2::new(3.0, -1.0),
            Vec2::new(0.5, 2.0),
            Vec2::new(-0.02, 0.01),
        );
        let x = |t: f64| x0 + v0 * t + a * (0.5 * t * t);
        let mut d = SplineDynamics::new(SplineOrder::Quadratic);
        for t in [10.0, 25.0, 35.0] {
            d.push(t, x(t));
        }
        assert!((d.acceleration() - a).norm() < 1e-12);
        assert!((d.velocity_at(35.0) - (v0 + a * 35.0)).norm() < 1e-12);
        let pred = x(35.0) + d.displacement(35.0, 10.0);
        assert!((pred - x(45.0)).norm() < 1e-10);
    }

    #[test]
    fn linear_order_and_two_points_use_the_chord() {
        let mut d = SplineDynamics::new(SplineOrder::Quadratic);
        d.push(0.0, Vec2::new(0.0, 0.0));
        d.push(2.0, Vec2::new(4.0, 2.0));
        assert_eq!(d.velocity_at(2.0), Vec2::new(2.0, 1.0));
        assert_eq!(d.acceleration(), Vec2::zeros());
        let mut l = SplineDynamics::new(SplineOrder::Linear);
        for (t, x) in [(0.0, 0.0), (1.0, 1.0), (2.0, 4.0)] {
            l.push(t, Vec2::new(x, 0.0));
        }
        assert_eq!(l.velocity_at(5.0), Vec2::new(3.0, 0.0));
        // Linear, spacing 1, Δ = 1: d = P₂ − P₁, Σc² = 2.
        assert!((l.displacement_noise_factor(2.0, 1.0) - 2.0).abs() < 1e-12);
        // Quadratic on uniform spacing, Δ = 1: extrapolation weights (1, −3, 3) minus the
        // last point: (1, −3, 2), Σc² = 14.
        let mut q = SplineDynamics::new(SplineOrder::Quadratic);
        for t in [0.0, 1.0, 2.0] {
            q.push(t, Vec2::zeros());
        }
        assert!((q.displacement_noise_factor(2.0, 1.0) - 14.0).abs() < 1e-12);
        // `updated` leaves the original alone.
        let u = l.updated(3.0, Vec2::new(9.0, 0.0));
        assert_eq!(u.velocity_at(3.0), Vec2::new(5.0, 0.0));
        assert_eq!(l.velocity_at(3.0), Vec2::new(3.0, 0.0));
    }
}
