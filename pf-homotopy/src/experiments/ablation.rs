//! Ablation beyond the paper: final RMS position error of the OHF and AOHF against the
//! number of λ steps (with the limit the HΔE converges to) and against the polar-grid
//! resolution.

use serde::{Deserialize, Serialize};

use super::Scale;
use super::rmse::{RmseConfig, final_squared_errors, validate_runs};
use crate::error::Result;
use crate::filters::{Algorithm, FilterSettings};
use crate::model::ScenarioConfig;
use crate::ohf::OhfConfig;
use pf_core::mc::rms_and_se;

/// Settings of the ablation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AblationConfig {
    /// The scenario.
    pub scenario: ScenarioConfig,
    /// Baseline filter settings (each sweep varies one thing).
    pub filters: FilterSettings,
    /// Number of realisations.
    pub realisations: usize,
    /// Seed (the same realisations for every setting).
    pub seed: u64,
    /// Numbers of λ steps `m` to try.
    pub lambda_steps: Vec<usize>,
    /// Polar grids `[n_β, n_r]` to try.
    pub grids: Vec<[usize; 2]>,
}

impl AblationConfig {
    /// Size presets: quick 4 realisations, default 24, full 200.
    pub fn at_scale(scale: Scale) -> Self {
        let realisations = match scale {
            Scale::Quick => 4,
            Scale::Default => 24,
            Scale::Full => 200,
        };
        Self {
            scenario: ScenarioConfig::default(),
            filters: FilterSettings::default(),
            realisations,
            seed: 1,
            lambda_steps: vec![10, 20, 40, 60, 120],
            grids: vec![[12, 6], [24, 12], [48, 24], [96, 48]],
        }
    }

    /// Check the settings.
    pub fn validate(&self) -> Result<()> {
        validate_runs(&self.scenario, &self.filters, self.realisations)
    }
}

impl Default for AblationConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Default)
    }
}

/// Final RMS position errors (m) of the ablation. A setting under which a filter failed on
/// some realisation (a coarse λ grid can lose positive definiteness for good: the paper's
/// "numerical implementation of (13) can be quite difficult") has `None`, and the failure
/// is listed in `failures`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AblationResult {
    /// The λ step counts tried.
    pub lambda_steps: Vec<usize>,
    /// OHF final RMS error per λ step count.
    pub ohf_by_steps: Vec<Option<f64>>,
    /// AOHF final RMS error per λ step count.
    pub aohf_by_steps: Vec<Option<f64>>,
    /// Final RMS error of the HΔE's limit, the KL-optimal Gaussian computed directly
    /// ([`Scheme::Direct`](crate::ohf::Scheme::Direct)): where `ohf_by_steps` should go.
    pub ohf_limit: f64,
    /// The grids `[n_β, n_r]` tried.
    pub grids: Vec<[usize; 2]>,
    /// OHF final RMS error per grid.
    pub ohf_by_grid: Vec<Option<f64>>,
    /// AOHF final RMS error per grid.
    pub aohf_by_grid: Vec<Option<f64>>,
    /// The largest single realisation's final error, `[OHF, AOHF]` per λ step count: an
    /// RMS over a few dozen realisations is set by its worst ones.
    pub worst_by_steps: Vec<[Option<f64>; 2]>,
    /// The same per grid.
    pub worst_by_grid: Vec<[Option<f64>; 2]>,
    /// The standard error of each final RMS error, `[OHF, AOHF]` per λ step count: the
    /// squared errors' mean's standard error through the square root, `se/(2·RMS)` (the
    /// delta method), so that settings can be told apart from noise.
    pub rms_se_by_steps: Vec<[Option<f64>; 2]>,
    /// The same per grid.
    pub rms_se_by_grid: Vec<[Option<f64>; 2]>,
    /// The settings that failed, with the first error of each.
    pub failures: Vec<String>,
}

/// One filter's final errors under one setting.
#[derive(Debug, Clone, Copy)]
struct Final {
    rms: f64,
    rms_se: f64,
    worst: f64,
}

/// Final errors of OHF and AOHF under `cfg`, each `None` (and the error recorded in
/// `failures`) when that filter fails on some realisation.
fn finals(cfg: &RmseConfig, setting: &str, failures: &mut Vec<String>) -> [Option<Final>; 2] {
    let mut out = [None; 2];
    for (o, alg) in out.iter_mut().zip([Algorithm::Ohf, Algorithm::Aohf]) {
        match final_squared_errors(cfg, &[alg]) {
            Ok(sq) => {
                let (rms, rms_se) = rms_and_se(&sq[0]);
                *o = Some(Final {
                    rms,
                    rms_se,
                    worst: sq[0].iter().copied().fold(0.0, f64::max).sqrt(),
                });
            }
            Err(e) => failures.push(format!("{} with {setting}: {e}", alg.name())),
        }
    }
    out
}

/// One field of both filters' [`Final`]s.
fn pick(f: [Option<Final>; 2], field: fn(&Final) -> f64) -> [Option<f64>; 2] {
    f.map(|x| x.as_ref().map(field))
}

/// Run both sweeps.
///
/// # Errors
/// Invalid settings or a filter failure.
pub fn ablation(cfg: &AblationConfig) -> Result<AblationResult> {
    cfg.validate()?;
    let base = RmseConfig {
        scenario: cfg.scenario,
        filters: cfg.filters,
        realisations: cfg.realisations,
        seed: cfg.seed,
    };
    let mut res = AblationResult {
        lambda_steps: cfg.lambda_steps.clone(),
        ohf_by_steps: Vec::new(),
        aohf_by_steps: Vec::new(),
        ohf_limit: f64::NAN,
        grids: cfg.grids.clone(),
        ohf_by_grid: Vec::new(),
        aohf_by_grid: Vec::new(),
        worst_by_steps: Vec::new(),
        worst_by_grid: Vec::new(),
        rms_se_by_steps: Vec::new(),
        rms_se_by_grid: Vec::new(),
        failures: Vec::new(),
    };
    for &m in &cfg.lambda_steps {
        let mut c = base.clone();
        c.filters.ohf.lambda.steps = m;
        c.filters.aohf.lambda.steps = m;
        let f = finals(&c, &format!("{m} λ steps"), &mut res.failures);
        let [o, a] = pick(f, |f| f.rms);
        res.ohf_by_steps.push(o);
        res.aohf_by_steps.push(a);
        res.worst_by_steps.push(pick(f, |f| f.worst));
        res.rms_se_by_steps.push(pick(f, |f| f.rms_se));
    }
    let mut direct = base.clone();
    direct.filters.ohf = OhfConfig::direct();
    let sq = final_squared_errors(&direct, &[Algorithm::Ohf])?;
    res.ohf_limit = rms_and_se(&sq[0]).0;
    for &[nb, nr] in &cfg.grids {
        let mut c = base.clone();
        c.filters.grid.n_bearing = nb;
        c.filters.grid.n_range = nr;
        let f = finals(&c, &format!("a {nb} × {nr} grid"), &mut res.failures);
        let [o, a] = pick(f, |f| f.rms);
        res.ohf_by_grid.push(o);
        res.aohf_by_grid.push(a);
        res.worst_by_grid.push(pick(f, |f| f.worst));
        res.rms_se_by_grid.push(pick(f, |f| f.rms_se));
    }
    Ok(res)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every setting reports a worst final error and a standard error of its RMS. No worst
    /// is below its RMS (the largest of a set is at least its root mean square), and no
    /// standard error above half its RMS: for non-negative squared errors with mean `m` the
    /// sample variance is at most `R·m²`, so the mean's s.e. is at most `m = RMS²`, and the
    /// delta method's `se/(2·RMS)` at most `RMS/2`.
    #[test]
    fn worst_errors_cover_every_setting_and_bound_the_rms() {
        let cfg = AblationConfig {
            realisations: 3,
            lambda_steps: vec![20],
            grids: vec![[12, 6]],
            ..AblationConfig::at_scale(Scale::Quick)
        };
        let r = ablation(&cfg).unwrap();
        assert_eq!(r.worst_by_steps.len(), 1);
        assert_eq!(r.worst_by_grid.len(), 1);
        assert_eq!(r.rms_se_by_steps.len(), 1);
        assert_eq!(r.rms_se_by_grid.len(), 1);
        // Per setting and filter f: (RMS, worst, s.e. of the RMS).
        let steps = (0..2).map(|f| {
            let rms = [r.ohf_by_steps[0], r.aohf_by_steps[0]][f];
            (rms, r.worst_by_steps[0][f], r.rms_se_by_steps[0][f])
        });
        let grid = (0..2).map(|f| {
            let rms = [r.ohf_by_grid[0], r.aohf_by_grid[0]][f];
            (rms, r.worst_by_grid[0][f], r.rms_se_by_grid[0][f])
        });
        let triples: Vec<_> = steps.chain(grid).collect();
        assert_eq!(triples.len(), 4);
        for (rms, worst, se) in triples {
            let (rms, worst, se) = (rms.unwrap(), worst.unwrap(), se.unwrap());
            assert!(
                worst >= rms && worst.is_finite(),
                "worst {worst} < rms {rms}"
            );
            assert!(
                se > 0.0 && se <= 0.5 * rms * (1.0 + 1e-12),
                "se {se} of rms {rms}"
            );
        }
    }
}
