//! Bearings: wrapping to (−π, π], the measurement function (22).

/// Wrap an angle to (−π, π]: pf-core's one implementation. Every bearing residual in the
/// crate goes through it.
pub use pf_core::geometry::wrap_angle as wrap;

/// The bearing `h(x, ρ) = atan2(y − ζ, x − ξ)` of eq. (22): angle of the target position
/// `p` seen from the observer `ρ`, counter-clockwise from the x-axis, in (−π, π]. The
/// paper's `arctan((y − ζ)/(x − ξ))` is taken in its four-quadrant form.
pub fn bearing(p: [f64; 2], rho: [f64; 2]) -> f64 {
    (p[1] - rho[1]).atan2(p[0] - rho[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn wrap_is_in_half_open_interval() {
        assert_eq!(wrap(PI), PI);
        assert_eq!(wrap(-PI), PI);
        assert!((wrap(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert!((wrap(-7.0 * PI + 0.1) - (-PI + 0.1)).abs() < 1e-12);
        // (a + π) mod 2π − π rounds: a few ε·π.
        assert!((wrap(0.3) - 0.3).abs() < 8.0 * f64::EPSILON);
    }
}
