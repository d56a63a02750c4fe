//! The experiments of Section 4 on the simulated scenarios: EPF against NNSF over seeded
//! replications, and the report's run of all three tests.
//!
//! | function | what |
//! |---|---|
//! | [`compare()`] | the methods on one scenario variant over `R` replications: association error rate, RMSE, OSPA, per-target errors for REC curves |
//! | [`section4()`] | per scenario: the comparisons of its clean and clutter/miss variants, the ablation of eq. (1), REC curves (Fig. 4c), one example run and its energies at the key frame (Tables 1–2), and the studies below |
//! | [`spline_study()`] | EPF and NNSF under each end behaviour of the dynamic model (B-spline, chord, quadratic) |
//! | [`radius_sweep()`] | EPF at each radius cap: how often E³ is non-zero and how often it (or E²) decides an association; which term decides EPF's wrong associations |
//! | [`first_wrong_frame()`] | eq. (1) term by term (E¹, E², E³, the α normalisation) at the first frame where EPF goes wrong |
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
//! | | the dynamic-model study, every configuration | [`compare()`] with `c = s + 1000·k + 950` |
//! | | the radius-cap sweep, replication `r`, every cap | simulation `(s + 1000·k + 970, r)`, tracking `(s + 1000·k + 971, r)` |
//! | | the search for a wrong frame, run `r` | simulation `(s + 1000·k + 990, r)`, tracking `(s + 1000·k + 991, r)` |
//! | [`section4()`], stress scene `i` (index in [`Scenario::STRESS`]), `k = 3 + i` | the 2 × 2 comparison | [`compare()`] with `c = s + 1000·k` |
//! | | the dynamic-model study, the default cap's counts, the wrong frame | as for a scenario: `+ 950`, `+ 970`, `+ 990` |
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
mod studies;

pub use comparison::{Comparison, ComparisonConfig, MethodSummary, compare, compare_with_progress};
pub use section4::{
    DetectionRow, NotSmallest, PairedLoss, ScenarioResult, Section4Config, Section4Result,
    SmallestE, StressResult, TargetRec, paired_loss, paper_energies, section4,
    section4_with_progress, smallest_e,
};
pub use studies::{
    DecisiveTerms, RADIUS_CAPS, RadiusRow, RadiusSweep, SPLINE_CONFIGS, SplineRow, TermRow,
    WrongFrame, decisive_term, first_wrong_frame, radius_sweep, spline_study,
};

use crate::association::Association;
use crate::scenario::Scenario;
use crate::tracker::TrackerConfig;
use serde::{Deserialize, Serialize};

/// A tracker variant to compare.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// The paper's EPF: eq. (1), each measurement to the target of least energy
    /// ([`Association::EnergyPerMeasurement`]).
    Epf,
    /// The same as [`Method::Epf`] (the name of the per-measurement rule when EPF meant the
    /// global assignment; kept so that configs naming it still read).
    EpfArgmin,
    /// The paper's NNSF: each measurement to the target whose prediction `Â(t)` is nearest
    /// ([`Association::Nearest`]).
    Nnsf,
    /// The same as [`Method::Nnsf`] (the name of nearest neighbour to `Â(t)` when NNSF
    /// measured from `Â(t−1)`; kept so that configs naming it still read).
    NnPredicted,
    /// EPF with E² left out of eq. (1) (ablation).
    EpfWithoutE2,
    /// EPF with E³ left out of eq. (1) (ablation: Table 2's "necessity of E³").
    EpfWithoutE3,
    /// EPF with E¹ alone (ablation).
    EpfE1Only,
    /// The energy E under the global one-to-one assignment ([`Association::Energy`], the
    /// tracker's default).
    EpfGlobal,
    /// The distance to `Â(t)` under the global one-to-one assignment
    /// ([`Association::NearestGlobal`]).
    NnGlobal,
    /// Each measurement to the target whose previous estimate `Â(t−1)` is nearest, E¹'s
    /// distance ([`Association::NearestPrevious`]).
    NnPrevious,
}

impl Method {
    /// The ablations of eq. (1), EPF first and nearest neighbour to `Â(t−1)` (E¹'s distance,
    /// unnormalised) last.
    pub const ABLATIONS: [Method; 5] = [
        Method::Epf,
        Method::EpfWithoutE2,
        Method::EpfWithoutE3,
        Method::EpfE1Only,
        Method::NnPrevious,
    ];

    /// The headline 2 × 2, rule (eq. (1) per measurement, global assignment) × cost (E,
    /// distance to `Â(t)`), then nearest neighbour to `Â(t−1)`.
    pub const ALL: [Method; 5] = [
        Method::Epf,
        Method::EpfGlobal,
        Method::Nnsf,
        Method::NnGlobal,
        Method::NnPrevious,
    ];

    /// Short label for tables and legends.
    pub fn label(self) -> &'static str {
        match self {
            Method::Epf | Method::EpfArgmin => "EPF",
            Method::Nnsf | Method::NnPredicted => "NNSF",
            Method::EpfWithoutE2 => "EPF without E²",
            Method::EpfWithoutE3 => "EPF without E³",
            Method::EpfE1Only => "EPF with E¹ only",
            Method::EpfGlobal => "E, global",
            Method::NnGlobal => "NN to Â(t), global",
            Method::NnPrevious => "NN to Â(t−1)",
        }
    }

    /// The association rule and cost this method uses.
    pub fn association(self) -> Association {
        match self {
            Method::Epf
            | Method::EpfArgmin
            | Method::EpfWithoutE2
            | Method::EpfWithoutE3
            | Method::EpfE1Only => Association::EnergyPerMeasurement,
            Method::Nnsf | Method::NnPredicted => Association::Nearest,
            Method::EpfGlobal => Association::Energy,
            Method::NnGlobal => Association::NearestGlobal,
            Method::NnPrevious => Association::NearestPrevious,
        }
    }

    /// `base` set up for this method.
    pub fn configure(self, base: &TrackerConfig) -> TrackerConfig {
        let mut c = *base;
        c.association = self.association();
        match self {
            Method::EpfWithoutE2 => c.energy.components = [true, false, true],
            Method::EpfWithoutE3 => c.energy.components = [true, true, false],
            Method::EpfE1Only => c.energy.components = [true, false, false],
            _ => {}
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
