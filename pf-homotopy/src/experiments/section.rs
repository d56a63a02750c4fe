//! Section 4 as one experiment under one seed: the scenario (Fig. 1), the ellipses (Fig. 2),
//! the RMS errors and cost (Fig. 3), the ablations, the turn direction and σ sweep, and the
//! information per bearing; and the recorded tracks of one realisation.

use serde::{Deserialize, Serialize};

use super::{
    AblationConfig, AblationResult, EllipsesConfig, EllipsesResult, GeometryConfig, GeometryResult,
    InformationConfig, InformationResult, PerAlgorithm, RmseConfig, RmseResult, Scale,
    ScenarioGeometry, ablation, ellipses, geometry, information, rmse, scenario_geometry,
};
use crate::error::Result;
use crate::filters::{Algorithm, FilterSettings, track};
use crate::model::{Realisation, ScenarioConfig};
use pf_core::mc::{mean_and_se, rms_and_se, stream_rng};

/// Every part of Section 4's experiments; [`HomotopyConfig::at_scale`] gives the parts'
/// presets, shrunk at `Quick` to a smoke test of seconds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HomotopyConfig {
    /// Fig. 1's scenario.
    pub scenario: ScenarioConfig,
    /// Fig. 2.
    pub ellipses: EllipsesConfig,
    /// Fig. 3 and the cost table.
    pub rmse: RmseConfig,
    /// The ablations.
    pub ablation: AblationConfig,
    /// Final errors against the unstated turn direction and σ.
    pub geometry: GeometryConfig,
    /// Information per bearing.
    pub information: InformationConfig,
    /// The seed of every part: it replaces the parts' own seeds.
    pub seed: u64,
}

impl Default for HomotopyConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Default)
    }
}

impl HomotopyConfig {
    /// Each part's preset at `scale`; at `Quick`, fewer realisations, λ steps, grids and σ
    /// than the parts' own quick presets, so that the whole runs in seconds in the dev
    /// profile (a smoke test of the pipeline, not a result). Seed 0.
    pub fn at_scale(scale: Scale) -> Self {
        let mut cfg = HomotopyConfig {
            scenario: ScenarioConfig::default(),
            ellipses: EllipsesConfig::at_scale(scale),
            rmse: RmseConfig::at_scale(scale),
            ablation: AblationConfig::at_scale(scale),
            geometry: GeometryConfig::at_scale(scale),
            information: InformationConfig::at_scale(scale),
            seed: 0,
        };
        if scale == Scale::Quick {
            cfg.rmse.realisations = 3;
            cfg.ablation.realisations = 1;
            cfg.ablation.lambda_steps = vec![10, 40];
            cfg.ablation.grids = vec![[12, 6], [48, 24]];
            cfg.geometry.base.realisations = 1;
            cfg.geometry.base.filters.particles = 500;
            cfg.geometry.sigmas_deg = vec![1.0];
        }
        cfg
    }

    /// The parts as they run: each with [`seed`](Self::seed).
    pub fn seeded(&self) -> Self {
        let mut c = self.clone();
        c.ellipses.seed = self.seed;
        c.rmse.seed = self.seed;
        c.ablation.seed = self.seed;
        c.geometry.base.seed = self.seed;
        c.information.seed = self.seed;
        c
    }

    /// How many times [`homotopy_with_progress`] ticks: once per part after Fig. 1.
    pub fn ticks(&self) -> u64 {
        5
    }
}

/// Every number behind Section 4's figures and tables.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HomotopyResult {
    /// The seed.
    pub seed: u64,
    /// Fig. 1.
    pub scenario: ScenarioGeometry,
    /// Fig. 2.
    pub ellipses: EllipsesResult,
    /// Fig. 3's configuration, as run.
    pub rmse_config: RmseConfig,
    /// Fig. 3 and the cost.
    pub rmse: RmseResult,
    /// The ablations.
    pub ablation: AblationResult,
    /// Final errors against the unstated turn direction and σ.
    pub geometry: GeometryResult,
    /// Information per bearing for each turn direction and σ.
    pub information: InformationResult,
}

/// Run every part of Section 4.
///
/// # Errors
/// The first failing part's error.
pub fn homotopy(cfg: &HomotopyConfig) -> Result<HomotopyResult> {
    homotopy_with_progress(cfg, &|| {})
}

/// [`homotopy`], calling `tick` after each part ([`HomotopyConfig::ticks`] times).
///
/// # Errors
/// As [`homotopy`].
pub fn homotopy_with_progress(
    cfg: &HomotopyConfig,
    tick: &(dyn Fn() + Sync),
) -> Result<HomotopyResult> {
    let c = cfg.seeded();
    let scenario = scenario_geometry(&c.scenario)?;
    let ell = ellipses(&c.ellipses)?;
    tick();
    let r = rmse(&c.rmse)?;
    tick();
    let abl = ablation(&c.ablation)?;
    tick();
    let geo = geometry(&c.geometry)?;
    tick();
    let info = information(&c.information)?;
    tick();
    Ok(HomotopyResult {
        seed: c.seed,
        scenario,
        ellipses: ell,
        rmse_config: c.rmse,
        rmse: r,
        ablation: abl,
        geometry: geo,
        information: info,
    })
}

/// The paper's "OHF best by a significant margin" against the final errors of the same
/// realisations: each filter's final RMS with its standard error, and the standard error of
/// their paired difference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OhfAgainstAohf {
    /// The OHF's final RMS error (m).
    pub ohf: f64,
    /// Its standard error (m).
    pub ohf_se: f64,
    /// The AOHF's final RMS error (m).
    pub aohf: f64,
    /// Its standard error (m).
    pub aohf_se: f64,
    /// The standard error of `ohf − aohf` (m).
    pub difference_se: f64,
}

impl OhfAgainstAohf {
    /// Whether the two differ by more than 2 standard errors of their difference.
    pub fn distinguishable(&self) -> bool {
        (self.ohf - self.aohf).abs() > 2.0 * self.difference_se
    }
}

/// Compare the final errors of OHF and AOHF. Each RMS and its standard error come from the
/// squared errors' mean through the square root (delta method); both filters run on the
/// same realisations, so by the delta method each realisation adds
/// `e²_OHF/(2·RMS_OHF) − e²_AOHF/(2·RMS_AOHF)` to the difference, whose mean's standard
/// error is the difference's (the two RMS' errors combined in quadrature when the
/// realisations do not pair up or an RMS is 0).
pub fn ohf_against_aohf(finals: &PerAlgorithm<Vec<f64>>) -> OhfAgainstAohf {
    let squares = |e: &[f64]| e.iter().map(|x| x * x).collect::<Vec<_>>();
    let (o_sq, a_sq) = (squares(&finals.ohf), squares(&finals.aohf));
    let (ohf, ohf_se) = rms_and_se(&o_sq);
    let (aohf, aohf_se) = rms_and_se(&a_sq);
    let difference_se = if o_sq.len() == a_sq.len() && ohf > 0.0 && aohf > 0.0 {
        let d: Vec<f64> = o_sq
            .iter()
            .zip(&a_sq)
            .map(|(x, y)| x / (2.0 * ohf) - y / (2.0 * aohf))
            .collect();
        mean_and_se(&d).1
    } else {
        ohf_se.hypot(aohf_se)
    };
    OhfAgainstAohf {
        ohf,
        ohf_se,
        aohf,
        aohf_se,
        difference_se,
    }
}

impl RmseResult {
    /// [`ohf_against_aohf`] on this run's final errors.
    pub fn ohf_against_aohf(&self) -> OhfAgainstAohf {
        ohf_against_aohf(&self.final_errors)
    }
}

/// The paper's ordering: OHF and AOHF both below the UKF-LPC.
pub fn papers_ordering_holds(rms: &PerAlgorithm<f64>) -> bool {
    rms.ohf < rms.ukf_lpc && rms.aohf < rms.ukf_lpc
}

/// One realisation tracked by every filter, for recordings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TracksConfig {
    /// The scenario.
    pub scenario: ScenarioConfig,
    /// The filters.
    pub filters: FilterSettings,
    /// Seed: the realisation and the filters draw from the stream `(seed, 11)`, in that
    /// order.
    pub seed: u64,
}

impl Default for TracksConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Default)
    }
}

impl TracksConfig {
    /// Fig. 3's scenario and filters at `scale`, the PF capped at 10 000 particles (enough to
    /// see the cloud, few enough to record). Seed 0.
    pub fn at_scale(scale: Scale) -> Self {
        let r = RmseConfig::at_scale(scale);
        let mut filters = r.filters;
        filters.particles = filters.particles.min(10_000);
        TracksConfig {
            scenario: r.scenario,
            filters,
            seed: 0,
        }
    }
}

/// The realisation and each filter's position estimates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TracksResult {
    /// The realisation.
    pub realisation: Realisation,
    /// `(filter name, [x, y] per instant)`, in the order of [`Algorithm::ALL`].
    pub estimates: Vec<(String, Vec<[f64; 2]>)>,
}

/// Simulate one realisation and track it with every filter.
///
/// # Errors
/// Invalid settings or a failing filter.
pub fn tracks(cfg: &TracksConfig) -> Result<TracksResult> {
    let mut rng = stream_rng(cfg.seed, 11);
    let realisation = cfg.scenario.simulate(&mut rng)?;
    let mut estimates = Vec::with_capacity(Algorithm::ALL.len());
    for alg in Algorithm::ALL {
        let est = track(alg, &cfg.scenario, &cfg.filters, &realisation, &mut rng)?;
        estimates.push((alg.name().to_owned(), est));
    }
    Ok(TracksResult {
        realisation,
        estimates,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn finals(ohf: Vec<f64>, aohf: Vec<f64>) -> PerAlgorithm<Vec<f64>> {
        PerAlgorithm {
            ohf,
            aohf,
            ukf_lpc: vec![],
            pf: vec![],
        }
    }

    /// The two tell apart only when the paired difference is beyond 2 s.e.: errors 3, 4
    /// against 30, 40 (either way round) are; 3, 5 against 3, 4 (RMS 4.12 and 3.54, paired
    /// s.e. 0.47) are not.
    #[test]
    fn the_ohf_comparison_follows_the_final_errors() {
        let best = ohf_against_aohf(&finals(vec![3.0, 4.0], vec![30.0, 40.0]));
        assert!(best.distinguishable() && best.ohf < best.aohf, "{best:?}");
        let beaten = ohf_against_aohf(&finals(vec![30.0, 40.0], vec![3.0, 4.0]));
        assert!(
            beaten.distinguishable() && beaten.ohf > beaten.aohf,
            "{beaten:?}"
        );
        let tied = ohf_against_aohf(&finals(vec![3.0, 5.0], vec![3.0, 4.0]));
        assert!(!tied.distinguishable(), "{tied:?}");
        assert!((tied.ohf - 17f64.sqrt()).abs() < 1e-12, "{tied:?}");
        assert!((tied.aohf - 12.5f64.sqrt()).abs() < 1e-12, "{tied:?}");
        assert!((2.0 * tied.difference_se - 0.95).abs() < 0.01, "{tied:?}");
    }

    /// The quick preset shrinks the parts below their own quick presets, and seeding
    /// reaches every part.
    #[test]
    fn the_quick_preset_is_small_and_the_seed_reaches_every_part() {
        let q = HomotopyConfig::at_scale(Scale::Quick);
        assert!(q.rmse.realisations < RmseConfig::at_scale(Scale::Quick).realisations);
        assert_eq!(q.geometry.sigmas_deg, vec![1.0]);
        let d = HomotopyConfig::at_scale(Scale::Default);
        assert_eq!(d.rmse, RmseConfig::at_scale(Scale::Default));
        let s = HomotopyConfig { seed: 9, ..d }.seeded();
        assert_eq!(
            [
                s.ellipses.seed,
                s.rmse.seed,
                s.ablation.seed,
                s.geometry.base.seed,
                s.information.seed
            ],
            [9; 5]
        );
    }
}
