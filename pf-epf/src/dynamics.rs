//! The adaptive dynamic model (Section 1 and EPF step 2, ref. \[4\]): a target moves with a
//! velocity `v` and an acceleration `a` that are re-estimated from the spline through its
//! associated observations each time one is associated.
//!
//! Step 2 fits "the cubic B-spline which control points are extracted from the available
//! observations"; the paper gives no formula. Four end behaviours are kept, all from the
//! last three control points `(τ₋₂, P₋₂), (τ₋₁, P₋₁), (τ₀, P₀)` (frames and detections):
//!
//! - The uniform cubic B-spline whose control points are the detections. It approximates
//!   rather than interpolates: at its last knot it passes through
//!   `x_end = (P₋₂ + 4P₋₁ + P₀)/6` with, per unit of the spline parameter `u`,
//!   `x′ = (P₀ − P₋₂)/2` and `x″ = P₋₂ − 2P₋₁ + P₀`. Frame gaps are handled by fitting the
//!   same spline to the frames, `τ(u)` with control values `τ_i` (the B-spline of the
//!   space-time points `(τ_i, P_i)`), so the end lies at frame
//!   `τ_end = (τ₋₂ + 4τ₋₁ + τ₀)/6` and, per frame,
//!   `v = x′/τ′ = (P₀ − P₋₂)/(τ₀ − τ₋₂)`, `a = (x″ − v·τ″)/τ′²` with `τ′ = (τ₀ − τ₋₂)/2`,
//!   `τ″ = τ₋₂ − 2τ₋₁ + τ₀`; on evenly spaced frames `h` apart, `v = (P₀ − P₋₂)/(2h)` and
//!   `a = (P₋₂ − 2P₋₁ + P₀)/h²`. Two ways of using it are kept:
//!   - [`SplineOrder::CubicBSplineEnd`] (the default for the particles and the gates): the
//!     spline's end derivatives `v` and `a` are the re-estimated dynamic model, applied from
//!     the last detection, `x(τ₀ + Δ) = x(τ₀) + v·Δ + ½a·Δ²`. On evenly spaced frames its
//!     displacement over one gap is `v·h + ½a·h² = P₀ − P₋₁`, exactly the chord's, so it
//!     carries the chord's detection noise (`2r²`); over other spans, and on uneven frames,
//!     it differs.
//!   - [`SplineOrder::CubicBSpline`] (the default for E²'s predictions): the spline's curve
//!     continued past its end, `x(t) = x_end + v·(t − τ_end) + ½a·(t − τ_end)²`, whose
//!     velocity at `t` is `v + a·(t − τ_end)`. Carried from `τ_end = τ₋₁` to `τ₀` on evenly
//!     spaced frames, its `v` and `a` are the quadratic's end derivatives, so it
//!     extrapolates the quadratic's displacement and carries its noise (`14r²` one step
//!     ahead); it keeps the curvature E² compares.
//! - [`SplineOrder::Quadratic`]: the end derivatives of the quadratic through the three
//!   points, `a = 2·P[τ₀, τ₋₁, τ₋₂]`, `v = P[τ₀, τ₋₁] + P[τ₀, τ₋₁, τ₋₂]·(τ₀ − τ₋₁)`
//!   (divided differences), exact for uniformly accelerated motion at any spacing.
//! - [`SplineOrder::Linear`]: the chord, `a = 0`, `v = (P₀ − P₋₁)/(τ₀ − τ₋₁)`.
//!
//! With fewer than three points every order uses the chord. Both B-spline uses reproduce
//! straight uniform motion exactly at any spacing.
//! [`SplineDynamics::displacement_noise_factor`] gives how much detection noise each
//! extrapolation carries.

use crate::geometry::Vec2;
use serde::{Deserialize, Serialize};

/// How the dynamic model is estimated from the last control points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SplineOrder {
    /// Constant velocity from the last two control points (`a = 0`): the chord.
    Linear,
    /// Velocity and acceleration of the quadratic through the last three control points.
    Quadratic,
    /// The uniform cubic B-spline whose control points are the detections (EPF step 2),
    /// continued past its end: the default for E²'s predictions.
    CubicBSpline,
    /// The same B-spline's end derivatives as the dynamic model, applied from the last
    /// detection (EPF step 2): the default for the particles and the gates.
    #[default]
    CubicBSplineEnd,
}

impl SplineOrder {
    /// Every order, the default first.
    pub const ALL: [SplineOrder; 4] = [
        SplineOrder::CubicBSplineEnd,
        SplineOrder::CubicBSpline,
        SplineOrder::Linear,
        SplineOrder::Quadratic,
    ];

    /// The name used in configs and tables.
    pub fn name(self) -> &'static str {
        match self {
            SplineOrder::Linear => "linear",
            SplineOrder::Quadratic => "quadratic",
            SplineOrder::CubicBSpline => "cubic_b_spline",
            SplineOrder::CubicBSplineEnd => "cubic_b_spline_end",
        }
    }
}

impl std::fmt::Display for SplineOrder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SplineOrder {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        pf_core::names::parse_name("spline order", &SplineOrder::ALL, SplineOrder::name, s)
    }
}

/// The dynamic model `x(t + Δ) = x(t) + v(t)·Δ + ½·a·Δ²` of one target, with its last
/// three control points `(frame, position)`. `v` and `a` are linear in the control points:
/// `v = Σ_i cv_i P_i`, `a = Σ_i ca_i P_i`, with weights that depend on the frames only.
/// `Copy` and fixed-size: updating it never allocates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplineDynamics {
    /// Control points, oldest first; only the first `len` are set.
    points: [(f64, Vec2); 3],
    len: usize,
    order: SplineOrder,
    /// `v` at frame `t_ref`.
    v: Vec2,
    /// `a`.
    a: Vec2,
    /// The frame `v` is the velocity at: the last control point's, or `τ_end` for the
    /// B-spline's curve.
    t_ref: f64,
    /// Weights of `v` and `a` on the held control points (oldest first; zero beyond `len`).
    cv: [f64; 3],
    ca: [f64; 3],
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
            t_ref: 0.0,
            cv: [0.0; 3],
            ca: [0.0; 3],
        }
    }

    /// The order this model estimates with.
    pub fn order(&self) -> SplineOrder {
        self.order
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
        let n = self.len;
        let (cv, ca, t_ref) = match (n, self.order) {
            (0, _) => ([0.0; 3], [0.0; 3], 0.0),
            (1, _) => ([0.0; 3], [0.0; 3], self.points[0].0),
            (2, _) | (_, SplineOrder::Linear) => {
                let (t1, t2) = (self.points[n - 2].0, self.points[n - 1].0);
                let mut cv = [0.0; 3];
                cv[n - 2] = -1.0 / (t2 - t1);
                cv[n - 1] = 1.0 / (t2 - t1);
                (cv, [0.0; 3], t2)
            }
            (_, SplineOrder::Quadratic) => {
                let [t0, t1, t2] = self.points.map(|p| p.0);
                // P[τ₂, τ₁] = (P₂ − P₁)/(τ₂ − τ₁), P[τ₁, τ₀] likewise,
                // P[τ₂, τ₁, τ₀] = (P[τ₂, τ₁] − P[τ₁, τ₀])/(τ₂ − τ₀).
                let d21 = [0.0, -1.0 / (t2 - t1), 1.0 / (t2 - t1)];
                let d10 = [-1.0 / (t1 - t0), 1.0 / (t1 - t0), 0.0];
                let d210: [f64; 3] = std::array::from_fn(|i| (d21[i] - d10[i]) / (t2 - t0));
                (
                    std::array::from_fn(|i| d21[i] + d210[i] * (t2 - t1)),
                    d210.map(|c| 2.0 * c),
                    t2,
                )
            }
            (_, order @ (SplineOrder::CubicBSpline | SplineOrder::CubicBSplineEnd)) => {
                let [t0, t1, t2] = self.points.map(|p| p.0);
                let tau_d1 = 0.5 * (t2 - t0);
                let tau_d2 = t0 - 2.0 * t1 + t2;
                let cv = [-1.0 / (t2 - t0), 0.0, 1.0 / (t2 - t0)];
                let second = [1.0, -2.0, 1.0];
                let ca = std::array::from_fn(|i| (second[i] - cv[i] * tau_d2) / (tau_d1 * tau_d1));
                let t_ref = match order {
                    SplineOrder::CubicBSpline => (t0 + 4.0 * t1 + t2) / 6.0,
                    _ => t2,
                };
                (cv, ca, t_ref)
            }
        };
        self.cv = cv;
        self.ca = ca;
        self.t_ref = t_ref;
        let combine = |c: &[f64; 3]| (0..n).fold(Vec2::zeros(), |s, i| s + self.points[i].1 * c[i]);
        self.v = combine(&cv);
        self.a = combine(&ca);
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

    /// The frame the model's `v` refers to: the last control point's, or, for the B-spline's
    /// curve, its end `τ_end = (τ₋₂ + 4τ₋₁ + τ₀)/6` once it holds three.
    pub fn reference_frame(&self) -> f64 {
        self.t_ref
    }

    /// The B-spline's end point `(P₋₂ + 4P₋₁ + P₀)/6` (with three control points and either
    /// B-spline order); otherwise the last control point.
    pub fn end_point(&self) -> Option<Vec2> {
        match (self.len, self.order) {
            (0, _) => None,
            (3, SplineOrder::CubicBSpline | SplineOrder::CubicBSplineEnd) => {
                let p = self.points.map(|p| p.1);
                Some((p[0] + p[1] * 4.0 + p[2]) / 6.0)
            }
            (n, _) => Some(self.points[n - 1].1),
        }
    }

    /// The velocity `v(t) = v(t_ref) + a·(t − t_ref)` at frame `t`.
    pub fn velocity_at(&self, t: f64) -> Vec2 {
        match self.len {
            0 => Vec2::zeros(),
            _ => self.v + self.a * (t - self.t_ref),
        }
    }

    /// How much detection noise the displacement carries: `d = v(t)·Δ + ½a·Δ²` is
    /// `Σ_i c_i P_i` with `c_i = cv_i·Δ + ca_i·((t − t_ref)·Δ + ½Δ²)`, so independent
    /// detection noise of variance `r²` per coordinate gives `Var d = r² Σ_i c_i²`. Returns
    /// `Σ_i c_i²` (0 with fewer than two points). It widens the gate around `Â(t)`. At unit
    /// spacing and `Δ = 1`: 2 for the chord and the B-spline's end derivatives, 14 for the
    /// quadratic and the B-spline's curve.
    pub fn displacement_noise_factor(&self, t: f64, dt: f64) -> f64 {
        let s = (t - self.t_ref) * dt + 0.5 * dt * dt;
        (0..self.len)
            .map(|i| (self.cv[i] * dt + self.ca[i] * s).powi(2))
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

    /// The uniform cubic B-spline segment `C(u) = Σ_i B_i(u)·Q_i` with the standard basis
    /// `B₀ = (1−u)³/6`, `B₁ = (3u³ − 6u² + 4)/6`, `B₂ = (−3u³ + 3u² + 3u + 1)/6`,
    /// `B₃ = u³/6`, evaluated directly (not through the closed forms under test).
    fn segment(q: [f64; 4], u: f64) -> f64 {
        let b = [
            (1.0 - u).powi(3) / 6.0,
            (3.0 * u.powi(3) - 6.0 * u * u + 4.0) / 6.0,
            (-3.0 * u.powi(3) + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
            u.powi(3) / 6.0,
        ];
        (0..4).map(|i| b[i] * q[i]).sum()
    }

    /// The B-spline's end point, velocity and acceleration per frame against the closed form
    /// `(P₋₂ + 4P₋₁ + P₀)/6`, `(P₀ − P₋₂)/(2h)`, `(P₋₂ − 2P₋₁ + P₀)/h²` on frames `h = 3`
    /// apart, and against the space-time spline evaluated from its basis (central finite
    /// differences in `u` at the last knot, chain rule to frames) on uneven frames.
    #[test]
    fn cubic_b_spline_end_matches_the_closed_form_including_uneven_gaps() {
        let p = [
            Vec2::new(1.0, -2.0),
            Vec2::new(4.0, 0.5),
            Vec2::new(6.5, 4.0),
        ];
        let mut d = SplineDynamics::new(SplineOrder::CubicBSpline);
        for (t, x) in [4.0, 7.0, 10.0].into_iter().zip(p) {
            d.push(t, x);
        }
        let end = (p[0] + p[1] * 4.0 + p[2]) / 6.0;
        assert!((d.end_point().unwrap() - end).norm() < 1e-14);
        assert_eq!(d.reference_frame(), 7.0);
        assert!((d.velocity_at(7.0) - (p[2] - p[0]) / 6.0).norm() < 1e-14);
        assert!((d.acceleration() - (p[0] - p[1] * 2.0 + p[2]) / 9.0).norm() < 1e-14);

        // Uneven gaps (the ants' 10, 25, 35), a phantom first control point whose weight
        // and derivatives vanish at the last knot u = 1.
        let taus = [10.0, 25.0, 35.0];
        let mut d = SplineDynamics::new(SplineOrder::CubicBSpline);
        for (t, x) in taus.into_iter().zip(p) {
            d.push(t, x);
        }
        // Five-point first and three-point second differences: exact for a cubic up to
        // rounding (about 1e-16·35/ε² = 4e-9 for the second).
        let eps = 1e-3;
        let d1 = |f: &dyn Fn(f64) -> f64| {
            (8.0 * (f(1.0 + eps) - f(1.0 - eps)) - (f(1.0 + 2.0 * eps) - f(1.0 - 2.0 * eps)))
                / (12.0 * eps)
        };
        let d2 =
            |f: &dyn Fn(f64) -> f64| (f(1.0 + eps) - 2.0 * f(1.0) + f(1.0 - eps)) / (eps * eps);
        let curve = |c: [f64; 3], u: f64| segment([-50.0, c[0], c[1], c[2]], u);
        let tau = |u: f64| curve(taus, u);
        let (t1, t2) = (d1(&tau), d2(&tau));
        assert!((d.reference_frame() - tau(1.0)).abs() < 1e-12);
        for axis in 0..2 {
            let x = |u: f64| curve(p.map(|q| q[axis]), u);
            let (x1, x2) = (d1(&x), d2(&x));
            let v = x1 / t1;
            let a = (x2 * t1 - x1 * t2) / t1.powi(3);
            assert!((d.end_point().unwrap()[axis] - x(1.0)).abs() < 1e-12);
            assert!((d.velocity_at(tau(1.0))[axis] - v).abs() < 1e-8, "v {axis}");
            assert!((d.acceleration()[axis] - a).abs() < 1e-8, "a {axis}");
        }
    }

    /// Straight uniform motion is reproduced exactly by the B-spline at uneven frames; on
    /// even frames its displacement from the last detection equals the quadratic's (and so
    /// does its noise factor, 14 at unit spacing).
    #[test]
    fn cubic_b_spline_keeps_straight_motion_and_matches_the_quadratic_on_even_frames() {
        assert_keeps_straight_motion(SplineOrder::CubicBSpline);

        let mut b = SplineDynamics::new(SplineOrder::CubicBSpline);
        let mut q = SplineDynamics::new(SplineOrder::Quadratic);
        for (t, x) in [(0.0, 0.0), (1.0, 1.0), (2.0, 5.0)] {
            b.push(t, Vec2::new(x, -x));
            q.push(t, Vec2::new(x, -x));
        }
        assert!((b.displacement(2.0, 1.0) - q.displacement(2.0, 1.0)).norm() < 1e-12);
        assert!((b.displacement_noise_factor(2.0, 1.0) - 14.0).abs() < 1e-12);
        // Two points: the chord, whatever the order.
        let mut two = SplineDynamics::new(SplineOrder::CubicBSpline);
        two.push(0.0, Vec2::zeros());
        two.push(2.0, Vec2::new(4.0, 2.0));
        assert_eq!(two.velocity_at(2.0), Vec2::new(2.0, 1.0));
        assert_eq!(two.acceleration(), Vec2::zeros());
        assert_eq!(
            "cubic_b_spline".parse::<SplineOrder>(),
            Ok(SplineOrder::CubicBSpline)
        );
        assert_eq!(SplineOrder::default(), SplineOrder::CubicBSplineEnd);
        for order in SplineOrder::ALL {
            assert_eq!(order.to_string().parse::<SplineOrder>(), Ok(order));
        }
    }

    /// The B-spline's end derivatives applied from the last detection: the closed forms
    /// `v = (P₀ − P₋₂)/(2h)`, `a = (P₋₂ − 2P₋₁ + P₀)/h²` at `τ₀`, a one-gap displacement equal
    /// to the chord's `P₀ − P₋₁` (noise factor 2), a two-gap one of `2(P₀ − P₋₁) + a·h²`, and
    /// straight motion kept exactly on uneven frames.
    #[test]
    fn cubic_b_spline_end_derivatives_give_the_chord_over_one_gap() {
        let p = [
            Vec2::new(1.0, -2.0),
            Vec2::new(4.0, 0.5),
            Vec2::new(6.5, 4.0),
        ];
        let h = 3.0;
        let mut d = SplineDynamics::new(SplineOrder::CubicBSplineEnd);
        for (t, x) in [4.0, 7.0, 10.0].into_iter().zip(p) {
            d.push(t, x);
        }
        let (v, a) = (
            (p[2] - p[0]) / (2.0 * h),
            (p[0] - p[1] * 2.0 + p[2]) / (h * h),
        );
        assert_eq!(d.reference_frame(), 10.0);
        assert!((d.velocity_at(10.0) - v).norm() < 1e-14);
        assert!((d.acceleration() - a).norm() < 1e-14);
        assert!((d.displacement(10.0, h) - (p[2] - p[1])).norm() < 1e-13);
        assert!(
            (d.displacement(10.0, 2.0 * h) - ((p[2] - p[1]) * 2.0 + a * (h * h))).norm() < 1e-13
        );
        assert!((d.displacement_noise_factor(10.0, h) - 2.0).abs() < 1e-12);
        assert_eq!(
            "cubic_b_spline_end".parse::<SplineOrder>(),
            Ok(SplineOrder::CubicBSplineEnd)
        );
        assert_keeps_straight_motion(SplineOrder::CubicBSplineEnd);
    }

    /// Straight uniform motion seen at uneven frames: no acceleration, and the next position
    /// extrapolated exactly.
    fn assert_keeps_straight_motion(order: SplineOrder) {
        let (x0, v0) = (Vec2::new(3.0, -1.0), Vec2::new(0.5, 2.0));
        let mut d = SplineDynamics::new(order);
        for t in [10.0, 25.0, 35.0] {
            d.push(t, x0 + v0 * t);
        }
        assert!(d.acceleration().norm() < 1e-12, "{order:?}");
        let next = x0 + v0 * 35.0 + d.displacement(35.0, 10.0);
        assert!((next - (x0 + v0 * 45.0)).norm() < 1e-10, "{order:?}");
    }
}
