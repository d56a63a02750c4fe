//! EPF against NNSF on one scenario variant over seeded replications (association error
//! rate, RMSE, OSPA, per-target errors for REC curves).

use super::{Method, tracker_for};
use crate::error::Result;
use crate::metrics::{association_errors, mean_ospa, position_errors, rmse_of};
use crate::scenario::{ScenarioConfig, simulate};
use crate::tracker::{Record, TrackerConfig, track};
use pf_core::mc::{Par, mean_and_se, stream_rng, try_replicate};
use serde::{Deserialize, Serialize};

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
    /// The seed of every stream (see [the stream layout](super#random-streams)). Written
    /// once, as [`Comparison::seed`], so it is not serialised here.
    #[serde(skip_serializing, default = "default_seed")]
    pub seed: u64,
    /// Where the replications run; the result does not depend on it.
    #[serde(skip)]
    pub par: Par,
}

fn default_seed() -> u64 {
    1
}

impl ComparisonConfig {
    /// EPF and both nearest-neighbour filters on `scenario`, `replications` runs, seed 1, on
    /// the rayon pool.
    pub fn new(scenario: ScenarioConfig, replications: usize) -> Self {
        ComparisonConfig {
            scenario,
            tracker: tracker_for(scenario.scenario),
            methods: Method::ALL.to_vec(),
            replications,
            ospa_c: 5.0,
            ospa_p: 2.0,
            seed: default_seed(),
            par: Par::Rayon,
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
    /// The seed, `config.seed`.
    pub seed: u64,
    /// Per method, in `config.methods` order.
    pub methods: Vec<MethodSummary>,
}

#[derive(Serialize, Deserialize)]
struct RunOutcome {
    key_frame_right: bool,
    error_rate: f64,
    rmse: f64,
    ospa: f64,
    errors: Vec<Vec<f64>>,
}

/// Run the comparison: replication `r` simulates with stream `(seed, r)`, and method `i`
/// tracks that simulation with stream `(seed + 1 + i, r)`, so the result is the same for
/// any thread count.
///
/// # Errors
/// An invalid configuration or a filter error.
pub fn compare(cfg: &ComparisonConfig) -> Result<Comparison> {
    compare_with_progress(cfg, &|| {})
}

/// [`compare()`], calling `tick` once per replication.
///
/// # Errors
/// As [`compare()`].
pub fn compare_with_progress(
    cfg: &ComparisonConfig,
    tick: &(dyn Fn() + Sync),
) -> Result<Comparison> {
    let seed = cfg.seed;
    cfg.scenario.validate()?;
    cfg.tracker.validate()?;
    let runs: Vec<Vec<RunOutcome>> = try_replicate(seed, cfg.replications, cfg.par, |r, rng| {
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
