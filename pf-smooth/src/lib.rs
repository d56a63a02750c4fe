//! # pf-smooth: particle estimates of smoothed additive functionals for maximum likelihood
//!
//! O. Cappé and E. Moulines, "On the use of particle filtering for maximum likelihood
//! parameter estimation", *EUSIPCO* 2005.
//!
//! EM and gradient-based maximum likelihood both need `τ_n = E[Σ_k s_k(X_k, X_{k+1}) | Y_{0:n}]`
//! (eq. (5)). For the noisy AR(1) model of Section 5 this crate estimates the four EM
//! statistics with the path-space estimator (eqs. (6)–(7)) and the fixed-lag one
//! (eqs. (8)–(9)) on pf-core's batch filter, each particle's sums and recent ancestral
//! states carried as columns of its state; and (beyond the paper) with forward-only
//! smoothing, the O(N²) reference free of path degeneracy, for any pf-core model with a
//! transition density and any vector-valued additive functional. It adds the EM
//! statistics, exact EM from the RTS smoother, particle EM (SEM, MCEM), the score by
//! Fisher's identity and the paper's experiments.
//!
//! | paper | module |
//! |---|---|
//! | eq. (5), the sum functional `s_k` | [`functional`] |
//! | eqs. (6)–(7), path-space estimator with `γ_k^i`; eqs. (8)–(9), fixed-lag estimator `τ̂_n^{δ,N}` | [`batch`] |
//! | beyond the paper: forward-only (FFBSm) smoothing, the O(N²) reference | [`forward`] |
//! | Section 5: model, `τ_{n,1…4}`, updates (10)–(12), Fisher's identity | [`ar1`] |
//! | exact EM / score from the Kalman filter and RTS smoother | [`exact`] |
//! | one filter run's estimates, SEM (Fig. 4) and Monte Carlo EM | [`em`] |
//! | the experiments behind `pf-viz smooth em|sem|score` and the figures | [`experiments`] |
//!
//! ```
//! use pf_core::filter::BatchFilter;
//! use pf_core::mc::stream_rng;
//! use pf_smooth::em::{batch_config, paper_filter_config};
//! use pf_smooth::{Ar1Data, FixedLagTerms, SmoothedAr1, Theta};
//!
//! // Simulate Section 5's data (n = 100), then estimate τ_{n,1…4} at θ = (0.8, 0.25, 4).
//! let truth = pf_core::models::NoisyAr1::new(0.98, 0.2, 1.0)?;
//! let (_, y) = truth.simulate(100, &mut stream_rng(1, 0));
//! let data = Ar1Data::new(y)?;
//! let theta = Theta::paper_start();
//! // The model carries the sums γ and the last δ = 20 states of each particle's line.
//! let model = SmoothedAr1::new(&theta, &data, 20)?;
//! let mut lagged = FixedLagTerms::new(&model, &[20])?;
//! let mut pf = BatchFilter::new(model, batch_config(paper_filter_config(200), 2))?;
//! pf.run_observed(None, &data.filter_input(), &mut lagged)?;
//! let view = pf.view().expect("a step was made");
//! let (_joint, fixed_lag) = lagged.estimates(&view)?;
//! let update = fixed_lag[0].m_step()?;
//! let exact = pf_smooth::exact::exact_em_step(&data, &theta)?;
//! assert!((update.phi - exact.phi).abs() < 0.1);
//! # Ok::<(), pf_smooth::SmoothError>(())
//! ```
//!
//! ## References
//! - O. Cappé, E. Moulines, "On the use of particle filtering for maximum likelihood
//!   parameter estimation", *Proc. EUSIPCO*, 2005.
//! - G. Celeux, J. Diebolt, "The SEM algorithm", *Comput. Statist. Quarterly* 2, 1985.
//! - R. H. Shumway, D. S. Stoffer, "An approach to time series smoothing and forecasting
//!   using the EM algorithm", *J. Time Series Analysis* 3(4), 1982.

pub mod ar1;
pub mod batch;
pub mod em;
pub mod error;
mod estimate;
pub mod exact;
pub mod experiments;
pub mod forward;
pub mod functional;

pub use ar1::{Ar1Data, Ar1Statistics, SuffStats, Theta, ThetaSamples};
pub use batch::{FixedLagTerms, SmoothedAr1};
pub use error::{Result, SmoothError};
pub use forward::ForwardSmoothing;
pub use functional::AdditiveFunctional;

/// The README's example, compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
