//! # pf-dredge: on-line estimation of overflow losses in a hopper dredger
//!
//! R. Babuška, Zs. Lendek, J. Braaksma, C. de Keizer, "Particle filtering for on-line
//! estimation of overflow losses in a hopper dredger", Proc. American Control Conference, 2006.
//!
//! A trailing suction hopper dredger logs its hopper volume `V_t`, hopper mass `m_t`, and the
//! incoming flow-rate `Q_i` and density `ρ_i`. The overflow flow-rate `Q_o` and density `ρ_o`
//! cannot be measured; this crate estimates them with a bootstrap particle filter on the
//! volume and mass balances (13), off-line from a data set or on-line sample by sample. It
//! also holds the paper's simulator (Section II) and the direct computation (15)–(16).
//!
//! | paper | module |
//! |---|---|
//! | Section II, eqs. (4)–(8): overflow, density profile, settling, scouring | [`sedimentation`] |
//! | Section II, eqs. (1)–(3), Figs. 3–4: simulator, three loading phases, PID | [`simulator`] |
//! | Section III, eqs. (9)–(13): the estimator's model | [`model`] |
//! | Section IV, Algs. 1–2: particle filter, off-line and on-line | [`estimator`] |
//! | Section V-A, eqs. (15)–(16): direct computation with zero-phase low-pass | [`direct`] |
//! | Section V, Figs. 3–8, and an `N` sweep | [`experiments`] |
//! | logged data (the CLI's CSV columns) | [`data`], [`logfile`] (CSV read/write, streaming) |
//!
//! ```
//! use pf_dredge::estimator::{EstimatorConfig, OnlineEstimator};
//! use pf_dredge::simulator::{SimConfig, simulate};
//! use pf_core::mc::stream_rng;
//!
//! // A short simulated cycle (phase 1 only), estimated on line with 200 particles.
//! let sim = SimConfig { t_end: 300.0, ..SimConfig::default() };
//! let data = simulate(&sim, &mut stream_rng(7, 1))?.to_data();
//! let mut online = OnlineEstimator::new(&EstimatorConfig::default().with_particles(200))?;
//! let mut rng = stream_rng(7, 0);
//! for k in 0..data.len() {
//!     let est = online.push(&data.sample(k), &mut rng)?;
//!     assert!(est.q_o.is_finite() && est.rho_o.is_finite());
//! }
//! # Ok::<(), pf_dredge::DredgeError>(())
//! ```

pub mod data;
pub mod direct;
pub mod error;
pub mod estimator;
pub mod experiments;
pub mod logfile;
pub mod model;
pub mod sedimentation;
pub mod simulator;

pub use data::{DredgeData, Sample, Truth};
pub use error::{DredgeError, Result};
pub use estimator::{
    EstimateConfig, EstimateOutput, EstimatorConfig, OnlineEstimate, OnlineEstimator, OnlineMean,
    estimate,
};
pub use simulator::{Cycle, SimConfig, simulate};

/// The README's example, compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
