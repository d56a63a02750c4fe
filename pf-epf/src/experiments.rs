//! The experiments of Section 4 on the synthetic scenarios: EPF against NNSF over seeded
//! replications (association error rate, RMSE, OSPA, per-target errors for REC curves).

use crate::association::Association;
use crate::energy::E1Reference;
use crate::error::Result;
use crate::metrics::{association_errors, mean_ospa, position_errors, rmse_of};
use crate::scenario::{Scenario, ScenarioConfig, simulate};
use crate::tracker::{Record, TrackerConfig, track};
use pf_core::mc::{Par, mean_and_se, stream_rng, try_replicate};
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
    };
    c
}

/// One comparison: a scenario, a tracker, the methods and the replications.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComparisonConfig {
    /// The scenario and its clutter and miss rates.
    pub scenario: ScenarioConfig,
    /// The tracker (its `association` is set per method).
    pub tracker: TrackerConfig,
    /// Methods to compare.
    pub methods: Vec<Method>,
    /// Replications `R` (each a fresh simulation, shared by all methods).
    pub replications: usize,
    /// OSPA cut-off `c` (scene units) and order `p`.
    pub ospa_c: f64,
    /// OSPA order `p`.
    pub ospa_p: f64,
}

impl ComparisonConfig {
    /// EPF and both nearest-neighbour filters on `scenario`, `replications` runs.
    pub fn new(scenario: ScenarioConfig, replications: usize) -> Self {
        ComparisonConfig {
            scenario,
            tracker: tracker_for(scenario.scenario),
            methods: Method::ALL.to_vec(),
            replications,
            ospa_c: 5.0,
            ospa_p: 2.0,
        }
    }
}

/// One method's results over the replications.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodSummary {
    /// The method.
    pub method: Method,
    /// Association error rate per replication.
    pub error_rate: Vec<f64>,
    /// RMSE per replication.
    pub rmse: Vec<f64>,
    /// Mean OSPA per replication.
    pub ospa: Vec<f64>,
    /// Mean and standard error of the three.
    pub error_rate_mean: (f64, f64),
    /// Mean and standard error of the RMSE.
    pub rmse_mean: (f64, f64),
    /// Mean and standard error of the OSPA.
    pub ospa_mean: (f64, f64),
    /// Position errors per target, pooled over replications and frames (for REC curves).
    pub errors_per_target: Vec<Vec<f64>>,
    /// Per replication, whether every target took its own detection at the scenario's key
    /// frame `t` (the paper's claim for its Figs. 2–4).
    pub key_frame_right: Vec<bool>,
    /// The fraction of replications with every association right at the key frame.
    pub key_frame_right_rate: f64,
}

/// The comparison's results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// The configuration.
    pub config: ComparisonConfig,
    /// The seed.
    pub seed: u64,
    /// Per method, in `config.methods` order.
    pub methods: Vec<MethodSummary>,
}

struct RunOutcome {
    key_frame_right: bool,
    error_rate: f64,
    rmse: f64,
    ospa: f64,
    errors: Vec<Vec<f64>>,
}

/// Run the comparison: replication `r` simulates with stream `(seed, r)`, and method `i`
/// tracks that simulation with stream `(seed + 1 + i, r)`, so the result is the same for
/// any thread count. `tick` is called once per replication.
///
/// # Errors
/// An invalid configuration or a filter error.
pub fn compare(
    cfg: &ComparisonConfig,
    seed: u64,
    par: Par,
    tick: &(dyn Fn() + Sync),
) -> Result<Comparison> {
    cfg.scenario.validate()?;
    cfg.tracker.validate()?;
    let runs: Vec<Vec<RunOutcome>> = try_replicate(seed, cfg.replications, par, |r, rng| {
        let sim = simulate(&cfg.scenario, rng)?;
        let out = cfg
            .methods
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let mut trng = stream_rng(seed.wrapping_add(1 + i as u64), r as u64);
                let res = track(
                    &sim.detections,
                    &sim.init,
                    &m.configure(&cfg.tracker),
                    Record::Tracks,
                    &mut trng,
                )?;
                let errors = position_errors(&res, &sim)?;
                let key = cfg.scenario.scenario.key_frame();
                let key_frame_right = match res.frames.iter().position(|&f| f == key) {
                    Some(i) => res.tracks.iter().all(|t| {
                        let rows = sim.detections.frame_rows(key);
                        let truth = rows
                            .clone()
                            .find(|&j| sim.detections.rows()[j].target == Some(t.target));
                        t.detection[i] == truth
                    }),
                    None => false,
                };
                Ok(RunOutcome {
                    key_frame_right,
                    error_rate: association_errors(&res, &sim.detections).rate(),
                    rmse: rmse_of(&errors)?,
                    ospa: mean_ospa(&res, &sim, cfg.ospa_c, cfg.ospa_p)?,
                    errors,
                })
            })
            .collect::<Result<Vec<_>>>();
        tick();
        out
    })?;
    let methods = cfg
        .methods
        .iter()
        .enumerate()
        .map(|(i, &method)| {
            let pick =
                |f: fn(&RunOutcome) -> f64| runs.iter().map(|r| f(&r[i])).collect::<Vec<_>>();
            let error_rate = pick(|o| o.error_rate);
            let rmse = pick(|o| o.rmse);
            let ospa = pick(|o| o.ospa);
            let k = runs.first().map_or(0, |r| r[i].errors.len());
            let errors_per_target = (0..k)
                .map(|t| {
                    runs.iter()
                        .flat_map(|r| r[i].errors[t].iter().copied())
                        .collect()
                })
                .collect();
            let key_frame_right: Vec<bool> = runs.iter().map(|r| r[i].key_frame_right).collect();
            let key_frame_right_rate = key_frame_right.iter().filter(|&&b| b).count() as f64
                / key_frame_right.len().max(1) as f64;
            MethodSummary {
                method,
                key_frame_right,
                key_frame_right_rate,
                error_rate_mean: mean_and_se(&error_rate),
                rmse_mean: mean_and_se(&rmse),
                ospa_mean: mean_and_se(&ospa),
                error_rate,
                rmse,
                ospa,
                errors_per_target,
            }
        })
        .collect();
    Ok(Comparison {
        config: cfg.clone(),
        seed,
        methods,
    })
}
