//! The experiments of Section 4 on the simulated scenarios: EPF against NNSF over seeded
//! replications, and the report's run of all three tests.
//!
//! | function | what |
//! |---|---|
//! | [`compare()`] | the methods on one scenario variant over `R` replications: association error rate, RMSE, OSPA, per-target errors for REC curves |
//! | [`section4()`] | per scenario: the comparisons of its clean and clutter/miss variants, the ablation of eq. (1), REC curves (Fig. 4c), one example run and its energies at the key frame (Tables 1–2) |
//!
//! ## Random streams
//!
//! Every stream is [`pf_core::mc::stream_rng`]`(seed, r)` of a config's `seed` (sums wrap),
//! so results do not depend on the thread count.
//!
//! | experiment | draws | stream |
//! |---|---|---|
//! | [`compare()`], seed `c` | replication `r`'s simulation | `(c, r)` |
//! | | method `i`'s tracking of that simulation | `(c + 1 + i, r)` |
//! | [`section4()`], seed `s`, scenario `k` (index in [`Scenario::ALL`]) | variant `v`'s comparison | [`compare()`] with `c = s + 1000·k + 100·v` (`v` < 9) |
//! | | the ablation of eq. (1) | [`compare()`] with `c = s + 1000·k + 900` |
//! | | the example run's simulation | `(s, 50 + k)` |
//! | | each example track, and the energies at the key frame | `(s, 60 + k)`, afresh for each |
//!
//! The example run's streams are not kept apart from the comparisons': `(s, 50 + k)` and
//! `(s, 60 + k)` are also simulation streams of van–plane's first comparison (replications
//! `50 + k` and `60 + k`), so van–plane's example is that comparison's replication 50 when
//! `R` > 50. They are kept so that the report's numbers stay as published.

mod comparison;
pub mod scenes;
mod section4;

pub use comparison::{Comparison, ComparisonConfig, MethodSummary, compare, compare_with_progress};
pub use section4::{
    DetectionRow, NotSmallest, PairedLoss, ScenarioResult, Section4Config, Section4Result,
    SmallestE, TargetRec, paired_loss, paper_energies, section4, section4_with_progress,
    smallest_e,
};

use crate::association::Association;
use crate::energy::E1Reference;
use crate::scenario::Scenario;
use crate::tracker::TrackerConfig;
use serde::{Deserialize, Serialize};

/// A tracker variant to compare.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// EPF: global energy minimisation (optimal assignment).
    Epf,
    /// EPF with the paper's per-measurement argmin of eq. (1).
    EpfArgmin,
    /// NNSF: nearest neighbour in E¹'s distance (the paper's baseline).
    Nnsf,
    /// Nearest neighbour to the dynamic model's prediction `Â(t)` (not in the paper).
    NnPredicted,
    /// EPF with E² left out of eq. (1) (ablation).
    EpfWithoutE2,
    /// EPF with E³ left out of eq. (1) (ablation: Table 2's "necessity of E³").
    EpfWithoutE3,
    /// EPF with E¹ alone: NNSF's distance under the global assignment (ablation).
    EpfE1Only,
}

impl Method {
    /// The ablations of eq. (1), EPF first and NNSF last.
    pub const ABLATIONS: [Method; 5] = [
        Method::Epf,
        Method::EpfWithoutE2,
        Method::EpfWithoutE3,
        Method::EpfE1Only,
        Method::Nnsf,
    ];

    /// EPF, its argmin variant and both nearest-neighbour filters.
    pub const ALL: [Method; 4] = [
        Method::Epf,
        Method::EpfArgmin,
        Method::Nnsf,
        Method::NnPredicted,
    ];

    /// Short label for tables and legends.
    pub fn label(self) -> &'static str {
        match self {
            Method::Epf => "EPF",
            Method::EpfArgmin => "EPF (argmin)",
            Method::Nnsf => "NNSF",
            Method::NnPredicted => "NN to Â(t)",
            Method::EpfWithoutE2 => "EPF without E²",
            Method::EpfWithoutE3 => "EPF without E³",
            Method::EpfE1Only => "EPF with E¹ only",
        }
    }

    /// `base` set up for this method.
    pub fn configure(self, base: &TrackerConfig) -> TrackerConfig {
        let mut c = *base;
        match self {
            Method::Epf => c.association = Association::Energy,
            Method::EpfArgmin => c.association = Association::EnergyPerMeasurement,
            Method::Nnsf => c.association = Association::Nearest,
            Method::NnPredicted => {
                c.association = Association::Nearest;
                c.energy.e1_reference = E1Reference::Predicted;
            }
            Method::EpfWithoutE2 => {
                c.association = Association::Energy;
                c.energy.components = [true, false, true];
            }
            Method::EpfWithoutE3 => {
                c.association = Association::Energy;
                c.energy.components = [true, true, false];
            }
            Method::EpfE1Only => {
                c.association = Association::Energy;
                c.energy.components = [true, false, false];
            }
        }
        c
    }
}

/// The tracker settings used for a scenario: `r` is the scenario's detection noise, `q`
/// covers its unmodelled motion (the ants' erratic walk needs a much wider `q`).
pub fn tracker_for(scenario: Scenario) -> TrackerConfig {
    let mut c = TrackerConfig {
        r: scenario.noise(),
        ..TrackerConfig::default()
    };
    c.q = match scenario {
        Scenario::VanPlane | Scenario::WalkingMen => 0.3,
        Scenario::Ants => 1.0,
        Scenario::Crossing | Scenario::SimultaneousTurns => 0.3,
        Scenario::SparseAnts => 1.0,
    };
    c
}
