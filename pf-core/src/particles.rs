//! Weighted means and covariances of a particle set in ℝ^d.

use crate::error::{CoreError, Result};
use crate::model::EuclideanState;
use nalgebra::{DMatrix, DVector};

fn dim_of<S: EuclideanState>(x: &[S], w: &[f64]) -> Result<usize> {
    let first = x.first().ok_or(CoreError::Empty {
        what: "particle set",
    })?;
    if w.len() != x.len() {
        return Err(CoreError::DimensionMismatch {
            what: "weights against particles",
            expected: x.len(),
            got: w.len(),
        });
    }
    let d = first.coords().len();
    // States of one type can still differ in length (`Vec<f64>`, `DVector`).
    if let Some(other) = x.iter().find(|xi| xi.coords().len() != d) {
        return Err(CoreError::DimensionMismatch {
            what: "a particle's dimension against the first particle's",
            expected: d,
            got: other.coords().len(),
        });
    }
    Ok(d)
}

/// `Σ_i W_i ξ_i` for normalised weights `W`.
///
/// # Errors
/// An empty set, weights of another length, or particles of different dimensions.
pub fn weighted_mean<S: EuclideanState>(x: &[S], w: &[f64]) -> Result<DVector<f64>> {
    let d = dim_of(x, w)?;
    let mut m = DVector::zeros(d);
    for (xi, &wi) in x.iter().zip(w) {
        for (mj, &c) in m.iter_mut().zip(xi.coords()) {
            *mj += wi * c;
        }
    }
    Ok(m)
}

/// `Σ_i W_i (ξ_i − m)(ξ_i − m)ᵀ` for normalised weights `W` (the plug-in estimate, no
/// small-sample correction, as a filter estimate of the posterior covariance).
///
/// # Errors
/// As [`weighted_mean`].
pub fn weighted_covariance<S: EuclideanState>(x: &[S], w: &[f64]) -> Result<DMatrix<f64>> {
    let m = weighted_mean(x, w)?;
    let d = m.len();
    let mut c = DMatrix::zeros(d, d);
    for (xi, &wi) in x.iter().zip(w) {
        let xi = xi.coords();
        for a in 0..d {
            let da = xi[a] - m[a];
            for b in 0..=a {
                c[(a, b)] += wi * da * (xi[b] - m[b]);
            }
        }
    }
    for a in 0..d {
        for b in 0..a {
            c[(b, a)] = c[(a, b)];
        }
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ragged states are an error for both, not an index panic or a mean over the shortest.
    #[test]
    fn particles_of_different_dimensions_are_an_error() {
        let x = vec![vec![1.0, 2.0], vec![1.0]];
        let mismatch = CoreError::DimensionMismatch {
            what: "a particle's dimension against the first particle's",
            expected: 2,
            got: 1,
        };
        assert_eq!(weighted_mean(&x, &[0.5, 0.5]), Err(mismatch.clone()));
        assert_eq!(weighted_covariance(&x, &[0.5, 0.5]), Err(mismatch));
    }

    #[test]
    fn mean_and_covariance_of_a_known_set() {
        let x = vec![[0.0, 0.0], [2.0, 0.0], [0.0, 4.0], [2.0, 4.0]];
        let w = [0.25; 4];
        let m = weighted_mean(&x, &w).unwrap();
        assert_eq!(m.as_slice(), &[1.0, 2.0]);
        let c = weighted_covariance(&x, &w).unwrap();
        assert_eq!(c[(0, 0)], 1.0);
        assert_eq!(c[(1, 1)], 4.0);
        assert_eq!(c[(0, 1)], 0.0);
        let w2 = [1.0, 0.0, 0.0, 0.0];
        assert_eq!(weighted_covariance(&x, &w2).unwrap(), DMatrix::zeros(2, 2));
    }

    #[test]
    fn errors_on_bad_shapes() {
        let x: Vec<f64> = vec![];
        assert!(matches!(
            weighted_mean(&x, &[]),
            Err(CoreError::Empty { .. })
        ));
        assert!(matches!(
            weighted_mean(&[1.0, 2.0], &[1.0]),
            Err(CoreError::DimensionMismatch { .. })
        ));
    }
}
