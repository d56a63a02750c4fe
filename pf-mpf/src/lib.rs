//! # pf-mpf: the marginalized particle filter and its complexity
//!
//! R. Karlsson, T. Schön, F. Gustafsson, "Complexity analysis of the marginalized particle
//! filter", IEEE Trans. Signal Processing 53(11), 2005 (LiTH-ISY-R-2611).
//!
//! A model with a linear-Gaussian substructure, model (5), splits its state into `x^p`
//! (particle filter) and `x^k` (one Kalman filter per particle). [`mpf::Mpf`] runs that
//! filter for any partition on pf-core's batch engine (each particle's Kalman mean, and
//! with `C_t ≠ 0` its covariance, as more columns of the particle); [`complexity`] counts its cost in equivalent flops (EF),
//! eqs. (11)–(12); [`calibrate`] measures this machine's flop time and `c1, c2, c3`
//! (Section IV-A); [`advisor`] ranks partitions by predicted cost; [`experiments`]
//! reproduces Figs. 1–3 and Tables II–III on the radar example, eq. (13).
//!
//! | paper | module |
//! |---|---|
//! | eq. (5), model with linear substructure | [`model`] |
//! | Alg. 1 (`C_t = 0`), eqs. (6)–(10); ref. \[15\] (`C_t ≠ 0`) | [`mpf`] |
//! | Table I, eqs. (11), (12), (14) | [`complexity`] |
//! | Section IV-A calibration | [`calibrate`] |
//! | eq. (13), radar example, partitions `PPKKPP` … | [`radar`] |
//! | Figs. 1–3, Tables II–III | [`experiments`] |
//! | the standard PF on eq. (13) as a benchmark | [`experiments::bench`] |
//! | partition advisor (beyond the paper) | [`advisor`] |
//!
//! ```
//! use pf_mpf::mpf::{Mpf, MpfConfig};
//! use pf_mpf::radar::{Partition, RadarConfig};
//! use pf_mpf::complexity::{CtCase, EfCoefficients, particle_ratio};
//! use pf_core::mc::Par;
//!
//! // Eq. (11) with the paper's c1, c2, c3: full marginalization of the radar model buys
//! // 1.44 times the particles of the standard PF.
//! let r = particle_ratio(CtCase::Zero, 2, 4, 2000.0, &EfCoefficients::default());
//! assert!((r - 1.44).abs() < 0.005);
//!
//! // The fully marginalized filter PPKKKK on simulated radar data.
//! let cfg = RadarConfig { n_steps: 10, ..RadarConfig::default() };
//! let truth = cfg.truth();
//! let ys = cfg.measure(&truth, &mut pf_core::mc::stream_rng(1, 0));
//! let part: Partition = "PPKKKK".parse()?;
//! let seed = 7;
//! let mut mpf = Mpf::new(part.model::<2, 4>(&cfg)?, MpfConfig::new(500), seed, Par::Seq)?;
//! for y in &ys {
//!     mpf.step(y.as_ref())?;
//! }
//! let (pos, vel) = mpf.estimate()?; // x^p = [p_x p_y], x^k = [v_x v_y a_x a_y]
//! assert!((pos[0] - truth[9][0]).abs() < 100.0 && vel.iter().all(|v| v.is_finite()));
//! # Ok::<(), pf_mpf::error::MpfError>(())
//! ```
//!
//! ## References
//! - T. Schön, F. Gustafsson, P.-J. Nordlund, "Marginalized particle filters for mixed
//!   linear/nonlinear state-space models", IEEE Trans. Signal Processing 53(7), 2005.

pub mod advisor;
pub mod calibrate;
pub mod complexity;
pub mod error;
pub mod experiments;
pub mod model;
pub mod mpf;
pub mod radar;

pub use error::{MpfError, Result};

/// The README's example, compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
