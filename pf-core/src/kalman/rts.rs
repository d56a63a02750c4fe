//! The Rauch–Tung–Striebel (1965) fixed-interval smoother.
//!
//! Backwards from `m_{n|n} = m_{n|n}`, `P_{n|n}`, for `k = n−1, …, 0`:
//! ```text
//! J_k     = P_{k|k} Aᵀ P_{k+1|k}⁻¹                  (solved, never inverted)
//! m_{k|n} = m_{k|k} + J_k (m_{k+1|n} − m_{k+1|k})
//! P_{k|n} = P_{k|k} + J_k (P_{k+1|n} − P_{k+1|k}) J_kᵀ
//! Cov(X_k, X_{k+1} | y_{0:n}) = J_k P_{k+1|n}
//! ```
//! The lag-one cross-covariances are what EM for linear-Gaussian models needs
//! (Shumway & Stoffer 1982), and what smoothed additive functionals are checked against.

use nalgebra::{DMatrix, DVector};

use super::{KalmanOutput, LinearGaussian};
use crate::error::{CoreError, Result};
use crate::gaussian::{cholesky_into, symmetrise};

/// Smoothed moments for `k = 0..=n`, given all of `y_{0:n}`.
#[derive(Debug, Clone, PartialEq)]
pub struct SmootherOutput {
    /// `m_{k|n} = E[X_k | y_{0:n}]`.
    pub means: Vec<DVector<f64>>,
    /// `P_{k|n} = Cov(X_k | y_{0:n})`.
    pub covs: Vec<DMatrix<f64>>,
    /// `Cov(X_k, X_{k+1} | y_{0:n}) = J_k P_{k+1|n}` for `k = 0..n` (n entries).
    pub cross_covs: Vec<DMatrix<f64>>,
}

/// Run the RTS smoother on the output of [`kalman_filter`](super::kalman_filter) for `model`.
///
/// Errors: an empty or inconsistent `kf` ([`CoreError::Empty`] /
/// [`CoreError::DimensionMismatch`]), or a predicted covariance `P_{k+1|k}` that is not
/// positive definite ([`CoreError::NotPositiveDefinite`]).
pub fn rts_smoother(model: &LinearGaussian, kf: &KalmanOutput) -> Result<SmootherOutput> {
    let n1 = kf.filtered_means.len();
    if n1 == 0 {
        return Err(CoreError::Empty {
            what: "Kalman output",
        });
    }
    for (what, len) in [
        ("Kalman output filtered covariances", kf.filtered_covs.len()),
        ("Kalman output predicted means", kf.predicted_means.len()),
        (
            "Kalman output predicted covariances",
            kf.predicted_covs.len(),
        ),
    ] {
        if len != n1 {
            return Err(CoreError::DimensionMismatch {
                what,
                expected: n1,
                got: len,
            });
        }
    }
    let d = model.state_dim();
    let bad_dim = |v: usize| CoreError::DimensionMismatch {
        what: "Kalman output state dimension",
        expected: d,
        got: v,
    };
    for k in 0..n1 {
        for v in [kf.filtered_means[k].len(), kf.predicted_means[k].len()] {
            if v != d {
                return Err(bad_dim(v));
            }
        }
        for p in [&kf.filtered_covs[k], &kf.predicted_covs[k]] {
            if p.shape() != (d, d) {
                return Err(bad_dim(p.nrows().max(p.ncols())));
            }
        }
    }

    let mut means = kf.filtered_means.clone();
    let mut covs = kf.filtered_covs.clone();
    let mut cross_covs = vec![DMatrix::zeros(d, d); n1 - 1];
    // Buffers reused across steps.
    let mut l = DMatrix::zeros(d, d);
    let mut jt = DMatrix::zeros(d, d);
    let mut j = DMatrix::zeros(d, d);
    let mut dp = DMatrix::zeros(d, d);
    let mut dm = DVector::zeros(d);
    let mut work = DVector::zeros(d);

    for k in (0..n1 - 1).rev() {
        // Jᵀ = P_{k+1|k}⁻¹ A P_{k|k}  (P's symmetric), by Cholesky of P_{k+1|k}.
        cholesky_into(
            "predicted covariance P_{k+1|k}",
            &kf.predicted_covs[k + 1],
            &mut l,
        )?;
        jt.gemm(1.0, model.a(), &kf.filtered_covs[k], 0.0);
        l.solve_lower_triangular_unchecked_mut(&mut jt);
        l.tr_solve_lower_triangular_unchecked_mut(&mut jt);
        j.tr_copy_from(&jt);

        let (head, tail) = means.split_at_mut(k + 1);
        dm.copy_from(&tail[0]);
        dm -= &kf.predicted_means[k + 1];
        head[k].gemv(1.0, &j, &dm, 1.0);

        let (head, tail) = covs.split_at_mut(k + 1);
        cross_covs[k].gemm(1.0, &j, &tail[0], 0.0);
        dp.copy_from(&tail[0]);
        dp -= &kf.predicted_covs[k + 1];
        head[k].quadform_tr_with_workspace(&mut work, 1.0, &j, &dp, 1.0);
        symmetrise(&mut head[k]);
    }
    Ok(SmootherOutput {
        means,
        covs,
        cross_covs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kalman::kalman_filter;
    use crate::kalman::kf::tests::{model_2d, observations};
    use crate::testing::joint_gaussian_posterior;

    #[test]
    fn smoother_matches_brute_force_joint_posterior() {
        let model = model_2d();
        let n = 8;
        let ys = observations(&model, n, &[3], 5);
        let kf = kalman_filter(&model, &ys, None).unwrap();
        let sm = rts_smoother(&model, &kf).unwrap();
        assert_eq!(
            (sm.means.len(), sm.covs.len(), sm.cross_covs.len()),
            (n + 1, n + 1, n)
        );
        let post = joint_gaussian_posterior(&model, &ys).unwrap();
        // Dense Cholesky of the 18×18 joint precision vs the recursion: both backward
        // stable, condition numbers O(10) for this model, so errors ≲ κ·N·ε ≈ 200ε;
        // 1e4·ε leaves a ×50 margin.
        let tol = 1e4 * f64::EPSILON;
        for k in 0..=n {
            let e = (&sm.means[k] - post.mean(k)).amax();
            assert!(e < tol, "mean {k}: {e}");
            let e = (&sm.covs[k] - post.cov(k, k)).amax();
            assert!(e < tol, "cov {k}: {e}");
        }
        for k in 0..n {
            let e = (&sm.cross_covs[k] - post.cov(k, k + 1)).amax();
            assert!(e < tol, "cross cov {k}: {e}");
        }
        // The last smoothed moments are the filtered ones, by definition.
        assert_eq!(sm.means[n], kf.filtered_means[n]);
        // A smoothed variance never exceeds the filtered one (more data).
        for k in 0..n {
            assert!(sm.covs[k][(0, 0)] <= kf.filtered_covs[k][(0, 0)] + tol);
        }
    }

    /// The RTS smoother on a window of steps `lo..=t` of one filter pass gives the same bits
    /// as on the filter's output for `y_{0:t}` (the steps before `lo` never enter the
    /// backward pass); a window past the end or reversed is an error.
    #[test]
    fn a_window_of_steps_smooths_as_the_prefix_does() {
        let model = model_2d();
        let n = 9;
        let ys = observations(&model, n, &[4], 7);
        let kf = kalman_filter(&model, &ys, None).unwrap();
        let (lo, t) = (3, 6);
        let prefix = kalman_filter(&model, &ys[..=t], None).unwrap();
        let full = rts_smoother(&model, &prefix).unwrap();
        let win = rts_smoother(&model, &kf.steps(lo, t).unwrap()).unwrap();
        assert_eq!(win.means[..], full.means[lo..=t]);
        assert_eq!(win.covs[..], full.covs[lo..=t]);
        assert_eq!(win.cross_covs[..], full.cross_covs[lo..t]);
        assert!(kf.steps(2, n + 1).is_err());
        assert!(kf.steps(5, 4).is_err());
    }

    #[test]
    fn inconsistent_output_is_an_error() {
        let model = model_2d();
        let ys = observations(&model, 3, &[], 1);
        let mut kf = kalman_filter(&model, &ys, None).unwrap();
        kf.predicted_covs.pop();
        assert!(matches!(
            rts_smoother(&model, &kf),
            Err(CoreError::DimensionMismatch { .. })
        ));
    }
}
