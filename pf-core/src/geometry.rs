//! Small geometric helpers shared by the tracking papers.

use std::f64::consts::PI;

/// Wrap an angle to `(−π, π]`, as every bearing residual must be before it is weighed.
pub fn wrap_angle(a: f64) -> f64 {
    // Most residuals are in range already: returned as they are, exactly, where the round
    // trip through `rem_euclid` (a call to `fmod`) moves a negative one by an ulp.
    if a > -PI && a <= PI {
        return a;
    }
    let r = a.rem_euclid(2.0 * PI);
    if r > PI { r - 2.0 * PI } else { r }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_into_the_half_open_interval() {
        assert_eq!(wrap_angle(0.0), 0.0);
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-15);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert!((wrap_angle(-7.0 * PI / 2.0) - PI / 2.0).abs() < 1e-14);
        for k in -5..=5 {
            let a = 0.3 + 2.0 * PI * k as f64;
            assert!((wrap_angle(a) - 0.3).abs() < 1e-13);
        }
        // Angles in range come back exactly, negative ones too.
        for a in [-3.1, -0.1, -1e-300, 1e-12, 2.5] {
            assert_eq!(wrap_angle(a), a);
        }
    }
}
