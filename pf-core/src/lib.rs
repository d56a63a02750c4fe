//! # pf-core: the SMC engine
//!
//! Models, particle sets, resampling, the sequential importance sampling–resampling filter,
//! genealogy, observers, Gaussian tools, the Kalman family, Monte Carlo replications and
//! metrics. Every paper crate of the `pf` workspace stands on it. It never draws and never
//! writes files: observers hand plain data to whoever called.
//!
//! | module | holds |
//! |---|---|
//! | [`model`] | [`StateSpaceModel`] and the optional capabilities |
//! | [`models`] | ready-made models (the noisy AR(1)) |
//! | [`params`] | the parameter checks every crate uses, and their error |
//! | [`weights`] | the one log-sum-exp, normalisation and ESS |
//! | [`particles`] | weighted means and covariances of a particle set |
//! | [`resample`] | multinomial, systematic, stratified and residual schemes |
//! | [`simd`] | lock-step random lanes, vectorised ziggurat normals, run-time AVX2 dispatch |
//! | [`filter`] | the SIR filter, bootstrap and guided mutations, resampling policy |
//! | [`genealogy`] | ancestry: trajectories, surviving lineages, coalescence, a recorded run |
//! | [`experiments`] | the engine's own experiment: a bootstrap filter's genealogy |
//! | [`ancestry`] | pruned path storage: living trajectories in far less than `N·n` |
//! | [`geometry`] | angle wrapping for bearings |
//! | [`observe`] | the observer trait and recorders |
//! | [`gaussian`] | multivariate normals and error ellipses |
//! | [`kalman`] | linear-Gaussian model, Kalman filter, RTS smoother, UKF |
//! | [`mc`] | reproducible parallel Monte Carlo replications |
//! | [`metrics`] | RMSE, REC curves, residual summaries, histograms and box-plot numbers |

pub mod ancestry;
mod buffer;
pub mod error;
pub mod experiments;
pub mod filter;
pub mod gaussian;
pub mod genealogy;
pub mod geometry;
pub mod kalman;
pub mod limits;
pub mod mc;
pub mod metrics;
pub mod model;
pub mod models;
pub mod names;
pub mod observe;
pub mod params;
pub mod particles;
pub mod resample;
pub mod simd;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
pub mod weights;

pub use error::{CoreError, Result};
pub use model::{EuclideanState, Proposal, StateSpaceModel, StepAt, TransitionDensity};
pub use params::ParamError;
