//! # pf-homotopy: the optimal homotopy filter for bearings-only tracking
//!
//! M. R. Morelande, L. Svensson, J. Hagmar, M. Jirstrand, "Optimal posterior density
//! approximation for bearings-only tracking".
//!
//! The optimal homotopy filter (OHF) replaces the Bayes correction (3) by the KL-optimal
//! Gaussian approximation (6) of the posterior, found by following the parameters θ(λ) of
//! that approximation along the homotopy (7) `g^λ f(·; θ_{k|k−1})` from λ = 0 to 1 (the
//! ODE (12)). The crate offers that correction as a reusable Gaussian measurement update
//! ([`ohf::correct`], any dimension, any likelihood with a [`quadrature::TemperedQuadrature`])
//! and the paper's bearings-only tracking study: OHF and AOHF against UKF-LPC and a PF with
//! the linearised optimal importance density.
//!
//! | paper | module |
//! |---|---|
//! | §2, eqs. (7)–(17): homotopy, λ-ODE, HΔE, AHΔE | [`ohf`] |
//! | §3, Gaussian f(·; θ), r = 5, derivatives of (25)–(28) | [`param`] |
//! | §3, polar change of variables and grid for (25), (26), (28) | [`quadrature`] |
//! | §3, eqs. (18)–(22): model; §4: scenario (Fig. 1) | [`model`] |
//! | §4: prior from the first bearing | [`prior`] |
//! | §3: OHF tracker (prediction, position homotopy, conditioning) | [`filters::ohf_tracker`] |
//! | §4: UKF-LPC benchmark (refs. \[2\], \[8\]) | [`filters::ukf_lpc`] |
//! | §4: PF with the linearised optimal importance density (ref. \[3\]) | [`filters::pf`] |
//! | §4: Figs. 1–3, cost, ablations | [`experiments`] |
//! | bearings (22); wrapping is `pf_core::geometry::wrap_angle` | [`model::bearing`] |
//!
//! ## Example: one OHF correction with a bearing
//!
//! ```
//! use nalgebra::{Matrix2, Vector2};
//! use pf_homotopy::ohf::{OhfConfig, OhfWorkspace, correct};
//! use pf_homotopy::param::Gaussian;
//! use pf_homotopy::quadrature::{PolarGrid, PolarGridConfig};
//!
//! // Prior over the target position, 5 km north-east, range badly known.
//! let prior = Gaussian::new(Vector2::new(3500.0, 3500.0), Matrix2::new(1e6, 9e5, 9e5, 1e6));
//! // A bearing of 50° (σ = 1°) from an observer at the origin.
//! let quad = PolarGrid::new(PolarGridConfig::default(), [0.0, 0.0], 50f64.to_radians(), 1f64.to_radians());
//! let cfg = OhfConfig::ohf();
//! let mut ws = OhfWorkspace::new();
//! let (post, _diag) =
//!     correct(&prior, &quad, cfg.scheme, &cfg.lambda.nodes(), cfg.max_halvings, 1, &mut ws, |_, _| {})?;
//! // The posterior is pulled onto the 50° line of sight and is narrower across it.
//! let bearing = post.mean[1].atan2(post.mean[0]).to_degrees();
//! assert!((bearing - 50.0).abs() < 1.0);
//! assert!(post.cov.determinant() < prior.cov.determinant());
//! # Ok::<(), pf_homotopy::HomotopyError>(())
//! ```
//!
//! ## References
//! - M. R. Morelande, L. Svensson, J. Hagmar, M. Jirstrand, "Optimal posterior density
//!   approximation for bearings-only tracking", *ICASSP*.
//! - J. Hagmar, M. Jirstrand, L. Svensson, M. Morelande, "Optimal parameterization of
//!   posterior densities using homotopy", *Fusion* 2011.

pub mod error;
pub mod experiments;
pub mod filters;
pub mod model;
pub mod ohf;
pub mod param;
pub mod prior;
pub mod quadrature;

pub use error::{HomotopyError, Result};

/// The README's example, compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
