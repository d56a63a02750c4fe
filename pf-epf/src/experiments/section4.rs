//! The three tests of Section 4 (van–plane, Fig. 2; walking men, Fig. 3 and Table 1; ants,
//! Fig. 4 and Table 2), simulated, as `pf-viz report` shows them: per scenario the
//! comparisons of its clean and clutter/miss variants, the ablation of eq. (1), REC curves
//! (Fig. 4c), and one example run with its energies at the key frame.

use super::studies::{
    RADIUS_CAPS, RadiusSweep, SPLINE_CONFIGS, SplineRow, WrongFrame, first_wrong_frame,
    radius_sweep, spline_study,
};
use super::{Comparison, ComparisonConfig, Method, compare_with_progress, tracker_for};
use crate::error::Result;
use crate::metrics::rec_of;
use crate::scenario::{Scenario, ScenarioConfig, TruthTrack, simulate};
use crate::tracker::{EnergyTable, Record, TrackResult, energies_at, track};
use pf_core::mc::{Par, Scale, mean_and_se, stream_rng};
use pf_core::metrics::{RecCurve, tolerance_grid};
use pf_core::params::ParamError;
use serde::{Deserialize, Serialize};

/// The sizes of [`section4()`]. The paper states none of them (it shows one run per
/// sequence).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Section4Config {
    /// Replications per scenario variant.
    pub replications: usize,
    /// Particles per target `N`.
    pub n_particles: usize,
    /// `(clutter per frame, miss probability)` of each variant, at most 9; the first is the
    /// one the REC curves pool (the clean one in [`Section4Config::at_scale`]).
    pub variants: Vec<(f64, f64)>,
    /// Points of the REC tolerance grid.
    pub rec_points: usize,
    /// Replications of the studies (the dynamic model's end behaviour, the radius-cap
    /// sweep), each on the clean scenario; the runs searched for a wrong frame.
    #[serde(default = "default_study_replications")]
    pub study_replications: usize,
    /// Replications of each study on a stress scene ([`Scenario::STRESS`]; its sequences
    /// are 4 to 6 times as long as the paper's, and its differences large).
    #[serde(default = "default_stress_replications")]
    pub stress_replications: usize,
    /// The seed of every stream (see [the stream layout](super#random-streams)). Written
    /// once, as [`Section4Result::seed`], so it is not serialised here.
    #[serde(skip_serializing, default = "default_seed")]
    pub seed: u64,
    /// Where the replications run; the result does not depend on it.
    #[serde(skip)]
    pub par: Par,
}

fn default_seed() -> u64 {
    1
}

fn default_study_replications() -> usize {
    100
}

fn default_stress_replications() -> usize {
    25
}

/// The most variants: variant `v`'s comparison seed `seed + 1000·k + 100·v` must stay below
/// the ablation's `seed + 1000·k + 900`.
const MAX_VARIANTS: usize = 9;

impl Section4Config {
    /// The sizes for `scale`, seed 1, on the rayon pool: 6, 1000 or 5000 replications of
    /// 100, 300 or 500 particles per target; clean, (1 clutter, 10 % misses) and
    /// (3 clutter, 20 % misses).
    pub fn at_scale(scale: Scale) -> Self {
        let (replications, n_particles) = match scale {
            Scale::Quick => (6, 100),
            Scale::Default => (1000, 300),
            Scale::Full => (5000, 500),
        };
        Section4Config {
            replications,
            n_particles,
            variants: vec![(0.0, 0.0), (1.0, 0.1), (3.0, 0.2)],
            rec_points: 201,
            study_replications: match scale {
                Scale::Quick => 6,
                Scale::Default => default_study_replications(),
                Scale::Full => 1000,
            },
            stress_replications: match scale {
                Scale::Quick => 3,
                Scale::Default => default_stress_replications(),
                Scale::Full => 200,
            },
            seed: default_seed(),
            par: Par::Rayon,
        }
    }

    /// How many times [`section4_with_progress`] calls its `tick`: once per replication of
    /// every comparison, ablation and study.
    pub fn ticks(&self) -> u64 {
        let studies = SPLINE_CONFIGS.len() + RADIUS_CAPS.len();
        let per_scenario = self
            .replications
            .saturating_mul(self.variants.len() + 1)
            .saturating_add(self.study_replications.saturating_mul(studies));
        // A stress scene: the comparison, the dynamic-model study, EPF at the default cap.
        let per_stress = self
            .stress_replications
            .saturating_mul(1 + SPLINE_CONFIGS.len() + 1);
        per_scenario
            .saturating_mul(Scenario::ALL.len())
            .saturating_add(per_stress.saturating_mul(Scenario::STRESS.len())) as u64
    }

    fn validate(&self) -> Result<()> {
        if self.variants.is_empty() || self.variants.len() > MAX_VARIANTS {
            return Err(ParamError::new(
                "variants",
                self.variants.len() as f64,
                "between 1 and 9 scenario variants (their seeds are 100 apart below the \
                 ablation's)",
            )
            .into());
        }
        Ok(())
    }
}

/// One method's REC curve for one target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TargetRec {
    /// The method.
    pub method: Method,
    /// Target id.
    pub target: usize,
    /// The curve.
    pub curve: RecCurve,
}

/// One detection of the example run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DetectionRow {
    /// Frame.
    pub frame: i64,
    /// Position.
    pub position: [f64; 2],
    /// True source (−1: clutter).
    pub target: i64,
}

impl DetectionRow {
    /// The true source, `None` for clutter.
    pub fn source(&self) -> Option<i64> {
        (self.target >= 0).then_some(self.target)
    }
}

/// Everything behind one scenario's figures and tables.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioResult {
    /// The scenario.
    pub scenario: Scenario,
    /// The ablation of eq. (1) on the clean scenario (EPF with components left out).
    pub ablation: Comparison,
    /// The comparison per variant: means and standard errors, per-run error rates (the
    /// pooled errors, per-run RMSE, OSPA and key-frame flags are dropped once the REC curves
    /// are drawn from them, which keeps the result to a few MB at the default scale).
    pub comparisons: Vec<Comparison>,
    /// REC curves of the first variant, EPF and NNSF, per target.
    pub rec: Vec<TargetRec>,
    /// The example run's energies at the key frame, under EPF.
    pub energies: EnergyTable,
    /// The example run's EPF and NNSF tracks, with particle clouds.
    pub example: Vec<(Method, TrackResult)>,
    /// The example run's observed frames.
    pub frames: Vec<i64>,
    /// The example run's true paths.
    pub truth: Vec<TruthTrack>,
    /// The example run's detections, in file order (the row indices of `energies` and
    /// `example` point here).
    pub detections: Vec<DetectionRow>,
    /// EPF and NNSF under each dynamic-model end behaviour ([`spline_study`]).
    #[serde(default)]
    pub splines: Vec<SplineRow>,
    /// The radius-cap sweep and the terms that decide EPF's wrong associations
    /// ([`radius_sweep`]).
    #[serde(default)]
    pub radius: RadiusSweep,
    /// Eq. (1) term by term at the first frame where EPF goes wrong ([`first_wrong_frame`]).
    #[serde(default)]
    pub wrong_frame: Option<WrongFrame>,
}

impl ScenarioResult {
    /// Whether each target's smallest E at the key frame is on its own detection
    /// ([`smallest_e`] of the example run).
    pub fn smallest_e(&self) -> SmallestE {
        smallest_e(&self.energies, |row| {
            self.detections.get(row).and_then(DetectionRow::source)
        })
    }

    /// EPF's loss to NNSF in each comparison where EPF's mean error rate is the higher
    /// ([`paired_loss`]), in `comparisons` order.
    pub fn losses_to_nnsf(&self) -> Vec<(ScenarioConfig, PairedLoss)> {
        self.comparisons
            .iter()
            .filter_map(|c| {
                let rates = |m: Method| {
                    c.methods
                        .iter()
                        .find(|x| x.method == m)
                        .map(|x| &x.error_rate)
                };
                let loss = paired_loss(rates(Method::Epf)?, rates(Method::Nnsf)?)?;
                Some((c.config.scenario, loss))
            })
            .collect()
    }
}

/// The result of [`section4()`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Section4Result {
    /// Sizes.
    pub config: Section4Config,
    /// Master seed, `config.seed`.
    pub seed: u64,
    /// Per scenario, in [`Scenario::ALL`] order.
    pub scenarios: Vec<ScenarioResult>,
    /// The association studies on each stress scene, in [`Scenario::STRESS`] order.
    #[serde(default)]
    pub stress: Vec<StressResult>,
}

/// The association studies on one stress scene ([`Scenario::STRESS`]), each over
/// `stress_replications` runs of the clean scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StressResult {
    /// The scene.
    pub scenario: Scenario,
    /// The 2 × 2 of rule × cost and nearest neighbour to `Â(t−1)` ([`Method::ALL`],
    /// [`Method::NnPrevious`]); per-run details dropped.
    pub comparison: Comparison,
    /// EPF and NNSF under each dynamic-model end behaviour ([`spline_study`]).
    pub splines: Vec<SplineRow>,
    /// EPF at the default radius cap: how often E³ and E² decide, and which term decides
    /// each wrong association ([`radius_sweep`]).
    pub radius: RadiusSweep,
    /// Eq. (1) term by term at the first frame where EPF goes wrong ([`first_wrong_frame`]).
    pub wrong_frame: Option<WrongFrame>,
}

/// The paper's energy magnitudes `E(T_i, M_j)`, rows `T_i`, columns `M_j` (`M_j` being
/// `T_j`'s detection): van–plane from the equations of Section 4, walking men from Table 1,
/// ants from Table 2 (printed there ×100).
pub fn paper_energies(s: Scenario) -> Vec<Vec<f64>> {
    match s {
        Scenario::VanPlane => vec![vec![0.27, 0.68], vec![0.79, 0.43]],
        Scenario::WalkingMen => vec![
            vec![0.085, 0.51, 0.363],
            vec![0.53, 0.32, 0.455],
            vec![0.47, 0.37, 0.16],
        ],
        Scenario::Ants => [
            [3.9, 38.1, 14.9, 26.7, 40.1, 36.7],
            [13.7, 3.4, 18.9, 6.7, 32.6, 10.5],
            [17.5, 15.2, 2.6, 10.8, 14.0, 18.1],
            [25.9, 8.7, 20.4, 5.4, 17.6, 9.5],
            [44.4, 50.1, 54.7, 56.1, 7.1, 53.6],
            [16.6, 13.9, 19.4, 44.5, 8.7, 3.2],
        ]
        .iter()
        .map(|r| r.iter().map(|v| v / 100.0).collect())
        .collect(),
        Scenario::Crossing | Scenario::SparseAnts | Scenario::SimultaneousTurns => Vec::new(),
    }
}

/// The three tests of Section 4, each simulated; streams as [the layout](super#random-streams)
/// says.
///
/// # Errors
/// An invalid configuration (no or more than 9 variants, a bad variant, too few particles)
/// or a filter error.
pub fn section4(cfg: &Section4Config) -> Result<Section4Result> {
    section4_with_progress(cfg, &|| {})
}

/// [`section4()`], calling `tick` [`Section4Config::ticks`] times, once per replication.
///
/// # Errors
/// As [`section4()`].
pub fn section4_with_progress(
    cfg: &Section4Config,
    tick: &(dyn Fn() + Sync),
) -> Result<Section4Result> {
    cfg.validate()?;
    let scenarios = Scenario::ALL
        .iter()
        .enumerate()
        .map(|(k, &s)| scenario(cfg, k as u64, s, tick))
        .collect::<Result<Vec<_>>>()?;
    let stress = Scenario::STRESS
        .iter()
        .enumerate()
        .map(|(i, &s)| stress_scene(cfg, (Scenario::ALL.len() + i) as u64, s, tick))
        .collect::<Result<Vec<_>>>()?;
    Ok(Section4Result {
        config: cfg.clone(),
        seed: cfg.seed,
        scenarios,
        stress,
    })
}

/// Stress scene `s`, seeded as the `k`-th scenario would be.
fn stress_scene(
    cfg: &Section4Config,
    k: u64,
    s: Scenario,
    tick: &(dyn Fn() + Sync),
) -> Result<StressResult> {
    let mut tracker = tracker_for(s);
    tracker.n_particles = cfg.n_particles;
    let seed = cfg.seed.wrapping_add(1000 * k);
    let study = ScenarioConfig::new(s);
    let reps = cfg.stress_replications;
    let mut methods = Method::ALL.to_vec();
    methods.push(Method::NnPrevious);
    let mut comparison = compare_with_progress(
        &ComparisonConfig {
            tracker,
            seed,
            par: cfg.par,
            methods,
            ..ComparisonConfig::new(study, reps)
        },
        tick,
    )?;
    for m in &mut comparison.methods {
        m.errors_per_target.clear();
        m.rmse.clear();
        m.ospa.clear();
        m.key_frame_right.clear();
    }
    let splines = spline_study(study, &tracker, reps, seed.wrapping_add(950), cfg.par, tick)?;
    let radius = radius_sweep(
        study,
        &tracker,
        &[tracker.energy.radius_cap],
        reps,
        seed.wrapping_add(970),
        cfg.par,
        tick,
    )?;
    let wrong_frame = first_wrong_frame(
        study,
        &tracker,
        cfg.study_replications.saturating_mul(2),
        seed.wrapping_add(990),
        s.key_frame(),
    )?;
    Ok(StressResult {
        scenario: s,
        comparison,
        splines,
        radius,
        wrong_frame,
    })
}

/// Scenario `s`, the `k`-th of [`Scenario::ALL`].
fn scenario(
    cfg: &Section4Config,
    k: u64,
    s: Scenario,
    tick: &(dyn Fn() + Sync),
) -> Result<ScenarioResult> {
    let mut tracker = tracker_for(s);
    tracker.n_particles = cfg.n_particles;
    let scenario_seed = cfg.seed.wrapping_add(1000 * k);
    let base = |scenario: ScenarioConfig, seed: u64| ComparisonConfig {
        tracker,
        seed,
        par: cfg.par,
        ..ComparisonConfig::new(scenario, cfg.replications)
    };
    let mut comparisons = cfg
        .variants
        .iter()
        .enumerate()
        .map(|(v, &(clutter, miss))| {
            let sc = ScenarioConfig {
                scenario: s,
                clutter,
                miss,
            };
            compare_with_progress(&base(sc, scenario_seed.wrapping_add(100 * v as u64)), tick)
        })
        .collect::<Result<Vec<_>>>()?;
    let mut ablation = compare_with_progress(
        &ComparisonConfig {
            methods: Method::ABLATIONS.to_vec(),
            ..base(ScenarioConfig::new(s), scenario_seed.wrapping_add(900))
        },
        tick,
    )?;

    let study = ScenarioConfig::new(s);
    let splines = spline_study(
        study,
        &tracker,
        cfg.study_replications,
        scenario_seed.wrapping_add(950),
        cfg.par,
        tick,
    )?;
    let radius = radius_sweep(
        study,
        &tracker,
        &RADIUS_CAPS,
        cfg.study_replications,
        scenario_seed.wrapping_add(970),
        cfg.par,
        tick,
    )?;
    let wrong_frame = first_wrong_frame(
        study,
        &tracker,
        cfg.study_replications.saturating_mul(2),
        scenario_seed.wrapping_add(990),
        s.key_frame(),
    )?;

    let shown = [Method::Epf, Method::Nnsf];
    let rec = rec_curves(&comparisons[0], &shown, cfg.rec_points)?;

    let sim = simulate(&ScenarioConfig::new(s), &mut stream_rng(cfg.seed, 50 + k))?;
    let example = shown
        .iter()
        .map(|&m| {
            let res = track(
                &sim.detections,
                &sim.init,
                &m.configure(&tracker),
                Record::Particles,
                &mut stream_rng(cfg.seed, 60 + k),
            )?;
            Ok((m, res))
        })
        .collect::<Result<Vec<_>>>()?;
    let energies = energies_at(
        &sim.detections,
        &sim.init,
        &Method::Epf.configure(&tracker),
        s.key_frame(),
        &mut stream_rng(cfg.seed, 60 + k),
    )?;

    for c in comparisons.iter_mut().chain(std::iter::once(&mut ablation)) {
        for m in &mut c.methods {
            m.errors_per_target.clear();
            m.rmse.clear();
            m.ospa.clear();
            m.key_frame_right.clear();
        }
    }
    Ok(ScenarioResult {
        scenario: s,
        ablation,
        comparisons,
        rec,
        energies,
        example,
        splines,
        radius,
        wrong_frame,
        frames: sim.frames,
        truth: sim.truth,
        detections: sim
            .detections
            .rows()
            .iter()
            .map(|d| DetectionRow {
                frame: d.frame,
                position: [d.position.x, d.position.y],
                target: d.target.unwrap_or(-1),
            })
            .collect(),
    })
}

/// REC curves of `methods` in `c`, per target, on one tolerance grid of `points` from 0 to
/// the largest error of any of them, so that every curve reaches 1.
fn rec_curves(c: &Comparison, methods: &[Method], points: usize) -> Result<Vec<TargetRec>> {
    let shown = || c.methods.iter().filter(|m| methods.contains(&m.method));
    let max_err = shown()
        .flat_map(|m| m.errors_per_target.iter().flatten().copied())
        .fold(0.0, f64::max);
    let grid = tolerance_grid(max_err.max(1e-9), points);
    let mut rec = Vec::new();
    for m in shown() {
        for (target, errs) in m.errors_per_target.iter().enumerate() {
            rec.push(TargetRec {
                method: m.method,
                target,
                curve: rec_of(errs, &grid)?,
            });
        }
    }
    Ok(rec)
}

/// By how much EPF's mean error rate is above NNSF's, from paired replications.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairedLoss {
    /// Mean of the paired differences EPF − NNSF (> 0).
    pub mean: f64,
    /// Twice their standard error.
    pub two_se: f64,
    /// Whether `mean` exceeds `two_se`.
    pub beyond_noise: bool,
}

/// EPF's loss to NNSF where its mean error rate is the higher, weighed against twice the
/// standard error of the paired differences (both methods run on the same data in each
/// replication, so the pairs, not the two spreads, measure the noise of the difference).
/// `None` where EPF does at least as well, or the replications do not pair up (unequal
/// lengths, or fewer than 2).
pub fn paired_loss(epf: &[f64], nnsf: &[f64]) -> Option<PairedLoss> {
    if epf.len() != nnsf.len() || epf.len() < 2 {
        return None;
    }
    let d: Vec<f64> = epf.iter().zip(nnsf).map(|(e, n)| e - n).collect();
    let (mean, se) = mean_and_se(&d);
    (mean > 0.0).then_some(PairedLoss {
        mean,
        two_se: 2.0 * se,
        beyond_noise: mean > 2.0 * se,
    })
}

/// Why a target's smallest E is not on its own detection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NotSmallest {
    /// The target's detection is missed at this frame.
    Missed,
    /// The target's own detection lies outside its gate.
    OutsideGate,
    /// The target's gate holds no detection.
    EmptyGate,
    /// A smaller E is on another detection.
    Elsewhere {
        /// The source of that detection (`None`: clutter).
        on: Option<i64>,
        /// Its E.
        e: f64,
        /// The E of the target's own detection.
        own: f64,
    },
}

/// Whether each target's smallest E among the detections in its gate is on its own
/// detection, as in the paper's Tables 1–2, and where the table's assignment is wrong.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SmallestE {
    /// Targets whose smallest E is on their own detection (a tie counts for it).
    pub right: Vec<i64>,
    /// The other targets, with the reason, in table order.
    pub wrong: Vec<(i64, NotSmallest)>,
    /// Targets assigned a detection of another source: `(target, source)`, `None` for
    /// clutter.
    pub misassigned: Vec<(i64, Option<i64>)>,
}

/// [`SmallestE`] of an energy table; `source(row)` is the true source of detection row `row`
/// (`None`: clutter).
pub fn smallest_e(t: &EnergyTable, source: impl Fn(usize) -> Option<i64>) -> SmallestE {
    let source = |j: usize| source(t.detections[j]);
    let mut verdict = SmallestE::default();
    for (k, &id) in t.targets.iter().enumerate() {
        let own = (0..t.detections.len()).find(|&j| source(j) == Some(id));
        let best = (0..t.detections.len())
            .filter(|&j| t.gated[k][j])
            .min_by(|&a, &b| t.e[k][a].total_cmp(&t.e[k][b]));
        match (own, best) {
            (None, _) => verdict.wrong.push((id, NotSmallest::Missed)),
            (Some(o), _) if !t.gated[k][o] => verdict.wrong.push((id, NotSmallest::OutsideGate)),
            (Some(o), Some(b)) if t.e[k][o] <= t.e[k][b] => verdict.right.push(id),
            (Some(o), Some(b)) => verdict.wrong.push((
                id,
                NotSmallest::Elsewhere {
                    on: source(b),
                    e: t.e[k][b],
                    own: t.e[k][o],
                },
            )),
            (Some(_), None) => verdict.wrong.push((id, NotSmallest::EmptyGate)),
        }
    }
    verdict.misassigned = t
        .targets
        .iter()
        .enumerate()
        .filter_map(|(k, &id)| {
            let a = t.assignment[k]?;
            let j = t.detections.iter().position(|&d| d == a)?;
            (source(j) != Some(id)).then(|| (id, source(j)))
        })
        .collect();
    verdict
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::EpfError;

    /// Two targets and their detections 0 (of T1) and 1 (of T2), with the energies `e`, the
    /// gates `gated` and the assignment `a`.
    fn table(e: [[f64; 2]; 2], gated: [[bool; 2]; 2], a: [Option<usize>; 2]) -> EnergyTable {
        let zero = vec![vec![0.0; 2]; 2];
        EnergyTable {
            frame: 3,
            targets: vec![0, 1],
            detections: vec![0, 1],
            positions: vec![[0.0; 2]; 2],
            raw: [zero.clone(), zero.clone(), zero.clone()],
            weighted: [zero.clone(), zero.clone(), zero],
            e: e.iter().map(|r| r.to_vec()).collect(),
            gated: gated.iter().map(|r| r.to_vec()).collect(),
            assignment: a.to_vec(),
        }
    }

    /// Row `j` is target `j`'s detection.
    fn own(row: usize) -> Option<i64> {
        Some(row as i64)
    }

    /// A loss is reported only where EPF's rate is above NNSF's, and called beyond the noise
    /// only past twice the paired differences' standard error: a small loss that every
    /// replication shares is real, the same mean loss from scattered pairs is not.
    #[test]
    fn losses_to_nnsf_are_weighed_against_their_noise() {
        assert_eq!(paired_loss(&[0.2, 0.3], &[0.25, 0.35]), None);
        assert_eq!(paired_loss(&[0.3], &[0.2]), None);
        assert_eq!(paired_loss(&[0.3, 0.4], &[0.2]), None);
        let steady = paired_loss(&[0.21, 0.31, 0.41], &[0.2, 0.3, 0.4]).unwrap();
        assert!(steady.beyond_noise, "{steady:?}");
        assert!((steady.mean - 0.01).abs() < 1e-12, "{steady:?}");
        assert!(steady.two_se < 1e-12, "{steady:?}");
        let scattered = paired_loss(&[0.3, 0.2, 0.43], &[0.2, 0.3, 0.4]).unwrap();
        assert!((scattered.mean - 0.01).abs() < 1e-12, "{scattered:?}");
        assert!(!scattered.beyond_noise, "{scattered:?}");
        assert!(scattered.two_se > scattered.mean, "{scattered:?}");
    }

    /// The verdict follows the energies: true pairs smallest, a wrong smallest named with
    /// both values, an own detection outside the gate, and wrong assignments.
    #[test]
    fn the_smallest_e_claim_follows_the_table() {
        let all = [[true; 2]; 2];
        let right = smallest_e(
            &table([[0.1, 0.9], [0.8, 0.2]], all, [Some(0), Some(1)]),
            own,
        );
        assert_eq!(
            right,
            SmallestE {
                right: vec![0, 1],
                ..SmallestE::default()
            }
        );
        let swapped = smallest_e(
            &table([[0.1, 0.9], [0.3, 0.5]], all, [Some(0), Some(0)]),
            own,
        );
        assert_eq!(swapped.right, [0]);
        assert_eq!(
            swapped.wrong,
            [(
                1,
                NotSmallest::Elsewhere {
                    on: Some(0),
                    e: 0.3,
                    own: 0.5
                }
            )]
        );
        assert_eq!(swapped.misassigned, [(1, Some(0))]);
        let outside = smallest_e(
            &table(
                [[0.1, 0.9], [0.8, 0.2]],
                [[true, true], [true, false]],
                [Some(0), None],
            ),
            own,
        );
        assert_eq!(outside.right, [0]);
        assert_eq!(outside.wrong, [(1, NotSmallest::OutsideGate)]);
        assert!(outside.misassigned.is_empty());
        let clutter = smallest_e(
            &table([[0.1, 0.9], [0.8, 0.2]], all, [Some(1), Some(0)]),
            |row| (row == 0).then_some(0),
        );
        assert_eq!(clutter.wrong, [(1, NotSmallest::Missed)]);
        assert_eq!(clutter.misassigned, [(0, None), (1, Some(0))]);
    }

    /// More than 9 variants would give a variant the ablation's seed; none gives no REC
    /// curves to pool.
    #[test]
    fn the_variant_count_is_checked() {
        let mut cfg = Section4Config::at_scale(Scale::Quick);
        cfg.variants = vec![(0.0, 0.0); 10];
        assert!(matches!(
            section4(&cfg),
            Err(EpfError::Param(ParamError {
                name: "variants",
                ..
            }))
        ));
        cfg.variants.clear();
        assert!(matches!(
            section4(&cfg),
            Err(EpfError::Param(ParamError {
                name: "variants",
                ..
            }))
        ));
    }
}
