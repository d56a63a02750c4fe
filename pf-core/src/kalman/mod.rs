//! The Kalman family: the linear-Gaussian model, the Kalman filter, the RTS smoother and
//! the unscented Kalman filter.
//!
//! Why they live in the SMC engine: the linear-Gaussian model is the one state-space model
//! whose filtering and smoothing distributions and likelihood are known exactly, so every
//! particle method in the workspace is checked against [`kalman_filter`] and
//! [`rts_smoother`] (see also `pf_core::testing`, behind the `testing` feature). The
//! marginalized particle filter runs a Kalman filter per particle, and the UKF is both a
//! baseline and a proposal builder for the homotopy and energetic filters.
//!
//! | item | computes |
//! |---|---|
//! | [`LinearGaussian`] | the model `X_t = A X_{t−1} + B u_t + W`, `Y_t = C X_t + V` |
//! | [`KalmanState`] | one belief `N(m, P)` with `predict` / `update` steps |
//! | [`kalman_filter`] | predicted and filtered moments and the exact log-likelihood |
//! | [`rts_smoother`] | smoothed moments and lag-one cross-covariances |
//! | [`Ukf`] | the unscented filter for additive-noise nonlinear models |
//!
//! Conventions: time steps `t = 0..=n`; `y_0` is observed through the prior `N(m₀, P₀)`;
//! `ys[t] = None` marks a missing observation; `us[t]` is the input of the transition that
//! produces `X_t` (`us[0]` unused). Covariance updates are in Joseph form or as
//! `P − WᵀW`, and re-symmetrised after every step.
//!
//! ## References
//! - R. E. Kalman, "A new approach to linear filtering and prediction problems",
//!   *J. Basic Engineering* 82(1), 1960.
//! - H. E. Rauch, F. Tung, C. T. Striebel, "Maximum likelihood estimates of linear dynamic
//!   systems", *AIAA Journal* 3(8), 1965.
//! - S. J. Julier, J. K. Uhlmann, "A new extension of the Kalman filter to nonlinear
//!   systems", *Proc. SPIE* 3068, 1997; "Unscented filtering and nonlinear estimation",
//!   *Proc. IEEE* 92(3), 2004.
//! - E. A. Wan, R. van der Merwe, "The unscented Kalman filter for nonlinear estimation",
//!   *Proc. IEEE AS-SPCC*, 2000.
//! - R. H. Shumway, D. S. Stoffer, "An approach to time series smoothing and forecasting
//!   using the EM algorithm", *J. Time Series Analysis* 3(4), 1982 (lag-one covariances).

mod batch;
mod kf;
mod linear_gaussian;
mod rts;
mod ukf;

pub use batch::BatchLinearGaussian;
pub use kf::{KalmanOutput, KalmanState, kalman_filter};
pub use linear_gaussian::{LinearGaussian, Simulated};
pub use rts::{SmootherOutput, rts_smoother};
pub use ukf::{Ukf, UkfParams, plain_residual};
