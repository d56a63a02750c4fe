//! # pf-epf
//!
//! El Abed, Dubuisson & Béréziat, *Energetic particle filter for online multiple target
//! tracking* (ICIP 2007): data association by minimising an energy built from positions
//! alone, and the energetic particle filter (EPF) that uses it, against the
//! nearest-neighbour standard filter (NNSF).
//!
//! | paper | module |
//! |---|---|
//! | input: unlabelled detections per frame, each target's first positions | [`data`] |
//! | Section 2, Fig. 1: circumcircles, intersection areas | [`geometry`] |
//! | Section 2: E¹, E², E³ and eq. (1) | [`energy`] |
//! | Section 3 step 1: gates, eq. (1) per measurement (EPF), NNSF, and both under a global assignment | [`association`], [`assignment`] |
//! | Section 1 and step 2: the cubic B-spline dynamic-model update (ref. \[4\]), chord and quadratic | [`dynamics`] |
//! | Section 3 steps 3–6: one particle filter per target | [`model`], [`tracker`] |
//! | Section 4: van–plane, walking men, ants; the report's experiment | [`scenario`], [`experiments`] |
//! | Fig. 4c: REC curves; RMSE, association error rate, OSPA | [`metrics`] |
//!
//! ```
//! use pf_epf::scenario::{Scenario, ScenarioConfig, simulate};
//! use pf_epf::tracker::{Record, TrackerConfig, track};
//! use pf_epf::metrics::association_errors;
//! use pf_core::mc::stream_rng;
//!
//! let mut rng = stream_rng(7, 0);
//! let sim = simulate(&ScenarioConfig::new(Scenario::VanPlane), &mut rng)?;
//! let cfg = TrackerConfig { n_particles: 200, ..TrackerConfig::default() };
//! let result = track(&sim.detections, &sim.init, &cfg, Record::Tracks, &mut rng)?;
//! assert_eq!(result.tracks.len(), 2);
//! let errors = association_errors(&result, &sim.detections);
//! assert!(errors.rate() <= 1.0);
//! # Ok::<(), pf_epf::EpfError>(())
//! ```
//!
//! ## References
//! A. El Abed, S. Dubuisson, D. Béréziat, "Energetic particle filter for online multiple
//! target tracking", ICIP 2007.
pub mod assignment;
pub mod association;
pub mod data;
pub mod dynamics;
pub mod energy;
pub mod error;
pub mod experiments;
pub mod geometry;
pub mod metrics;
pub mod model;
pub mod scenario;
pub mod tracker;

pub use error::{EpfError, Result};

/// The README's example, compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
