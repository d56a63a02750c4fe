//! One plain function per figure and table of Section 4 (plus the ablations): a config
//! struct (serde, the paper's values as `Default`, `XConfig::at_scale` the preset of a
//! [`Scale`]) in, a result struct of raw numbers out. Every run is deterministic for its
//! seed: realisation `r` uses `stream_rng(seed, r)`.
//!
//! | function | figure / table |
//! |---|---|
//! | [`scenario_geometry`] | Fig. 1, the scenario |
//! | [`ellipses()`] | Fig. 2, OHF error ellipses over λ (CLI `ellipses`) |
//! | [`rmse()`] | Fig. 3, RMS position error, and the cost table (CLI `rmse`) |
//! | [`ablation()`] | final RMS error against λ steps and polar-grid resolution |
//! | [`geometry()`] | final RMS error against the unstated turn direction and σ |
//! | [`information()`] | information per bearing for each turn direction (the evidence for ours) |
//! | [`homotopy()`] | all of the above under one seed (what `pf-viz report` draws) |
//! | [`tracks()`] | one realisation tracked by every filter (for recordings) |

mod ablation;
pub mod bench;
mod ellipses;
mod fig1;
mod geometry;
mod information;
mod rmse;
mod section;

pub use ablation::{AblationConfig, AblationResult, ablation};
pub use ellipses::{Ellipse, EllipsesConfig, EllipsesResult, ellipses};
pub use fig1::{ScenarioGeometry, scenario_geometry};
pub use geometry::{GeometryCell, GeometryConfig, GeometryResult, geometry};
pub use information::{InformationConfig, InformationResult, information};
pub use rmse::{PerAlgorithm, RmseConfig, RmseResult, final_squared_errors, rmse};
pub use section::{
    HomotopyConfig, HomotopyResult, OhfAgainstAohf, TracksConfig, TracksResult, homotopy,
    homotopy_with_progress, ohf_against_aohf, papers_ordering_holds, tracks,
};

/// The experiments' size presets, shared with the other paper crates.
pub use pf_core::mc::Scale;
