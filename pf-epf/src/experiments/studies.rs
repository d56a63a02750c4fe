//! The studies behind the report's choices and explanations: the dynamic model's end
//! behaviour (EPF step 2), the radius cap that decides when E³ is zero, and eq. (1) term by
//! term on a frame where the energy association goes wrong.

use super::{ComparisonConfig, Method, compare_with_progress};
use crate::association::{Association, Associator, gate_threshold};
use crate::dynamics::SplineOrder;
use crate::energy::{EnergyConfig, EnergyMatrix, EnergyTerms};
use crate::error::Result;
use crate::geometry::Vec2;
use crate::metrics::association_errors;
use crate::scenario::{ScenarioConfig, Simulation, simulate};
use crate::tracker::{TrackResult, Tracker, TrackerConfig, tracked_frames};
use pf_core::mc::{Par, mean_and_se, stream_rng, try_replicate};
use serde::{Deserialize, Serialize};

/// One dynamic-model configuration of [`spline_study`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SplineRow {
    /// The order that moves the particles and centres the gates (`TrackerConfig::spline`).
    pub spline: SplineOrder,
    /// The order behind E²'s `Â₁(t+1)`, `Â₂(t+1)` (`TrackerConfig::energy_spline`).
    pub energy_spline: SplineOrder,
    /// EPF's association error rate, mean and standard error over the runs.
    pub epf: (f64, f64),
    /// NNSF's.
    pub nnsf: (f64, f64),
    /// EPF's RMSE.
    pub epf_rmse: (f64, f64),
}

/// The dynamic-model configurations compared, `(spline, energy_spline)`: the default (the
/// B-spline's end derivatives move the particles, its curve shapes E²), the chord moving the
/// particles, the B-spline's curve for both, and the quadratic for both. On evenly spaced
/// frames the first two move the particles alike and the last two extrapolate alike
/// ([`crate::dynamics`]); they differ on uneven frames (the ants).
pub const SPLINE_CONFIGS: [(SplineOrder, SplineOrder); 4] = [
    (SplineOrder::CubicBSplineEnd, SplineOrder::CubicBSpline),
    (SplineOrder::Linear, SplineOrder::CubicBSpline),
    (SplineOrder::CubicBSpline, SplineOrder::CubicBSpline),
    (SplineOrder::Quadratic, SplineOrder::Quadratic),
];

/// EPF and NNSF under each of [`SPLINE_CONFIGS`] on the same `replications` simulations
/// (every configuration uses the comparison seed `seed`, so the runs are paired).
///
/// # Errors
/// As [`super::compare()`].
pub fn spline_study(
    scenario: ScenarioConfig,
    tracker: &TrackerConfig,
    replications: usize,
    seed: u64,
    par: Par,
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<SplineRow>> {
    SPLINE_CONFIGS
        .iter()
        .map(|&(spline, energy_spline)| {
            let c = compare_with_progress(
                &ComparisonConfig {
                    tracker: TrackerConfig {
                        spline,
                        energy_spline,
                        ..*tracker
                    },
                    methods: vec![Method::Epf, Method::Nnsf],
                    seed,
                    par,
                    ..ComparisonConfig::new(scenario, replications)
                },
                tick,
            )?;
            Ok(SplineRow {
                spline,
                energy_spline,
                epf: c.methods[0].error_rate_mean,
                nnsf: c.methods[1].error_rate_mean,
                epf_rmse: c.methods[0].rmse_mean,
            })
        })
        .collect()
}

/// One radius cap of [`radius_sweep`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RadiusRow {
    /// `radius_cap`: a circumcircle above this multiple of its triangle's longest side is a
    /// straight line.
    pub radius_cap: f64,
    /// The turn below which a triangle counts as straight, `asin(1/(2·radius_cap))`, degrees.
    pub straight_below_deg: f64,
    /// Share of target-frames whose reference triangle `(Â(t−2), Â(t−1), Â(t))` is curved,
    /// so that E³ is not zero.
    pub e3_active: f64,
    /// Share of target-frames whose association changes when E³ is left out of eq. (1) on
    /// the same frame (same predictions, same detections).
    pub e3_decides: f64,
    /// Share of target-frames whose association changes when E² is left out.
    pub e2_decides: f64,
    /// EPF's association error rate, mean and standard error over the runs.
    pub error_rate: (f64, f64),
}

/// The radius caps swept.
pub const RADIUS_CAPS: [f64; 5] = [1.0, 2.0, 5.0, 20.0, 1e6];

/// Per-run counts of the instrumented EPF run.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
struct Counts {
    target_frames: usize,
    e3_active: usize,
    e3_decides: usize,
    e2_decides: usize,
    /// Wrong associations (a target given another target's detection) by the term that
    /// pushes the pair the wrong way most (index 0–2), [`decisive_term`].
    decisive: [usize; 3],
    wrong: usize,
}

/// EPF (`tracker` with `association` from [`Method::Epf`]) on `sim`, counting per frame
/// whether E³ is active and whether leaving E³ or E² out of eq. (1) would change the
/// association, and which term decides each wrong association.
fn instrumented_run(
    sim: &Simulation,
    tracker: &TrackerConfig,
    rng: &mut impl rand::Rng,
) -> Result<(TrackResult, Counts)> {
    let cfg = Method::Epf.configure(tracker);
    let frames = tracked_frames(&sim.detections, &sim.init)?;
    let mut t = Tracker::new(&sim.init, &cfg, rng)?;
    let k = t.ids().len();
    let mut counts = Counts::default();
    let mut other = Associator::new();
    let mut full = vec![None; k];
    let mut alt = vec![None; k];
    let mut e = EnergyMatrix::new();
    let mut ys = Vec::new();
    let gamma = gate_threshold(cfg.gate_probability)?;
    let mut res = TrackResult {
        frames: frames.clone(),
        tracks: t
            .ids()
            .iter()
            .map(|&target| crate::tracker::Track {
                target,
                position: Vec::new(),
                detection: Vec::new(),
                status: Vec::new(),
            })
            .collect(),
        records: Vec::new(),
    };
    for &f in &frames {
        let rows = sim.detections.positions_into(f, &mut ys);
        let out = t.step(f, &ys, rng)?.to_vec();
        // Eq. (1) on every target at once (the tracker may associate in two rounds, see
        // `tracker`; the counts are of the one-round rule on the same frame).
        e.compute(t.geometry(), &ys, &cfg.energy);
        other.associate(
            t.geometry(),
            &ys,
            gamma,
            Association::EnergyPerMeasurement,
            &cfg.energy,
            &mut full,
        );
        counts.target_frames += k;
        for i in 0..k {
            if (0..ys.len()).any(|j| e.raw(i, j)[2] > 0.0) {
                counts.e3_active += 1;
            }
        }
        for (l, slot) in [(2, &mut counts.e3_decides), (1, &mut counts.e2_decides)] {
            let mut ec = cfg.energy;
            ec.components[l] = false;
            other.associate(
                t.geometry(),
                &ys,
                gamma,
                Association::EnergyPerMeasurement,
                &ec,
                &mut alt,
            );
            *slot += full.iter().zip(&alt).filter(|(a, b)| a != b).count();
        }
        let source = |j: usize| sim.detections.rows()[rows.start + j].target;
        for (i, o) in out.iter().enumerate() {
            let id = t.ids()[i];
            let Some(j) = *o else { continue };
            let Some(src) = source(j) else { continue };
            if src == id {
                continue;
            }
            counts.wrong += 1;
            // The detection's true target, whose E the wrong target's undercut.
            if let Some(owner) = t.ids().iter().position(|&x| x == src) {
                let l = decisive_term(&e.terms(owner, j), &e.terms(i, j));
                counts.decisive[l] += 1;
            }
        }
        for (i, tr) in res.tracks.iter_mut().enumerate() {
            let p = t.estimate(i);
            tr.position.push([p.x, p.y]);
            tr.detection.push(out[i].map(|j| rows.start + j));
            tr.status.push(t.status()[i]);
        }
    }
    Ok((res, counts))
}

/// Which term pushes eq. (1) most towards the wrong target: with `own` the terms of the
/// detection's true target and `wrong` those of the target that took it, `E² ∝ Σ_l
/// (α_l E^l)²`, and the term `l` with the largest `(α_l E^l)²(own) − (α_l E^l)²(wrong)` is
/// the one that made the wrong target's E the smaller (index 0, 1, 2 for E¹, E², E³).
pub fn decisive_term(own: &EnergyTerms, wrong: &EnergyTerms) -> usize {
    let d: [f64; 3] = std::array::from_fn(|l| own.weighted[l].powi(2) - wrong.weighted[l].powi(2));
    (0..3).max_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap_or(0)
}

/// How often each term decides a wrong association of EPF, over a scenario's runs.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct DecisiveTerms {
    /// Wrong associations (a target given another target's detection) counted.
    pub wrong: usize,
    /// Of those, how many the term `α₁E¹`, `α₂E²`, `α₃E³` pushed most ([`decisive_term`]).
    pub by_term: [usize; 3],
}

/// The radius-cap sweep of one scenario, and the decisive terms at `tracker`'s own cap.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RadiusSweep {
    /// One row per cap swept.
    pub rows: Vec<RadiusRow>,
    /// Over the runs at `tracker`'s own cap.
    pub decisive: DecisiveTerms,
}

/// EPF at each cap of `caps` (the report sweeps [`RADIUS_CAPS`]) on the same `replications`
/// simulations: replication `r` simulates with stream `(seed, r)` and tracks with
/// `(seed + 1, r)` at every cap.
///
/// # Errors
/// As [`super::compare()`].
pub fn radius_sweep(
    scenario: ScenarioConfig,
    tracker: &TrackerConfig,
    caps: &[f64],
    replications: usize,
    seed: u64,
    par: Par,
    tick: &(dyn Fn() + Sync),
) -> Result<RadiusSweep> {
    let mut out = RadiusSweep::default();
    for &cap in caps {
        let cfg = TrackerConfig {
            energy: EnergyConfig {
                radius_cap: cap,
                ..tracker.energy
            },
            ..*tracker
        };
        let runs = try_replicate(seed, replications, par, |r, rng| {
            let sim = simulate(&scenario, rng)?;
            let mut trng = stream_rng(seed.wrapping_add(1), r as u64);
            let (res, counts) = instrumented_run(&sim, &cfg, &mut trng)?;
            tick();
            Ok::<_, crate::EpfError>((association_errors(&res, &sim.detections).rate(), counts))
        })?;
        let rates: Vec<f64> = runs.iter().map(|r| r.0).collect();
        let sum = |f: fn(&Counts) -> usize| runs.iter().map(|r| f(&r.1)).sum::<usize>();
        let n = sum(|c| c.target_frames).max(1) as f64;
        out.rows.push(RadiusRow {
            radius_cap: cap,
            straight_below_deg: (1.0 / (2.0 * cap)).min(1.0).asin().to_degrees(),
            e3_active: sum(|c| c.e3_active) as f64 / n,
            e3_decides: sum(|c| c.e3_decides) as f64 / n,
            e2_decides: sum(|c| c.e2_decides) as f64 / n,
            error_rate: mean_and_se(&rates),
        });
        if cap == tracker.energy.radius_cap {
            out.decisive = DecisiveTerms {
                wrong: sum(|c| c.wrong),
                by_term: std::array::from_fn(|l| runs.iter().map(|r| r.1.decisive[l]).sum()),
            };
        }
    }
    Ok(out)
}

/// One target × detection of [`WrongFrame`]: eq. (1) term by term, and the NNSF's distance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TermRow {
    /// Target id.
    pub target: i64,
    /// The detection's true source (−1: clutter).
    pub source: i64,
    /// Whether the detection is in the target's gate.
    pub gated: bool,
    /// Eq. (1)'s terms.
    pub terms: EnergyTerms,
    /// Mahalanobis distance to the prediction `Â(t)` (the NNSF's).
    pub d_predicted: f64,
    /// Whether EPF gave this detection to this target.
    pub assigned: bool,
}

/// Eq. (1) term by term at the first frame, at or after a given frame, where EPF gives a
/// target another target's detection in a run that had associated every detection right
/// until that frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WrongFrame {
    /// Whether every association before `from_frame` was right in this run.
    pub clean_before: bool,
    /// The replication searched up to and found in.
    pub replication: usize,
    /// The frame `t`.
    pub frame: i64,
    /// Every target × detection, targets outer.
    pub rows: Vec<TermRow>,
    /// Target headings (degrees) from `Â(t−2)` to `Â(t−1)` and from `Â(t−1)` to `Â(t)`.
    pub turn_deg: Vec<[f64; 2]>,
}

/// Search runs `r = 0, 1, …, max_runs − 1` (simulation stream `(seed, r)`, tracking
/// `(seed + 1, r)`) for the first frame `t ≥ from_frame` where EPF gives a target another
/// target's detection, in a run whose associations before `from_frame` were all right (a
/// run that goes wrong earlier is passed over), and return eq. (1) there term by term;
/// if none does, the first such frame in any run (`clean_before` says which); `None` if no
/// run goes wrong from `from_frame` on.
///
/// # Errors
/// A simulation or filter error.
pub fn first_wrong_frame(
    scenario: ScenarioConfig,
    tracker: &TrackerConfig,
    max_runs: usize,
    seed: u64,
    from_frame: i64,
) -> Result<Option<WrongFrame>> {
    for clean in [true, false] {
        if let Some(w) = search_wrong_frame(scenario, tracker, max_runs, seed, from_frame, clean)? {
            return Ok(Some(w));
        }
    }
    Ok(None)
}

/// [`first_wrong_frame`]'s search, passing over runs that go wrong before `from_frame` when
/// `clean`.
fn search_wrong_frame(
    scenario: ScenarioConfig,
    tracker: &TrackerConfig,
    max_runs: usize,
    seed: u64,
    from_frame: i64,
    clean: bool,
) -> Result<Option<WrongFrame>> {
    let cfg = Method::Epf.configure(tracker);
    for r in 0..max_runs {
        let sim = simulate(&scenario, &mut stream_rng(seed, r as u64))?;
        let mut rng = stream_rng(seed.wrapping_add(1), r as u64);
        let frames = tracked_frames(&sim.detections, &sim.init)?;
        let mut t = Tracker::new(&sim.init, &cfg, &mut rng)?;
        let mut ys: Vec<Vec2> = Vec::new();
        for &f in &frames {
            let rows = sim.detections.positions_into(f, &mut ys);
            let out = t.step(f, &ys, &mut rng)?.to_vec();
            let source = |j: usize| sim.detections.rows()[rows.start + j].target;
            let wrong = out
                .iter()
                .enumerate()
                .any(|(i, o)| o.is_some_and(|j| source(j).is_some_and(|s| s != t.ids()[i])));
            if f < from_frame {
                let right = out
                    .iter()
                    .enumerate()
                    .all(|(i, o)| *o == (0..ys.len()).find(|&j| source(j) == Some(t.ids()[i])));
                if right || !clean {
                    continue;
                }
                break;
            }
            if !wrong {
                continue;
            }
            let mut e = EnergyMatrix::new();
            e.compute(t.geometry(), &ys, &cfg.energy);
            let gamma = gate_threshold(cfg.gate_probability)?;
            let m = ys.len();
            let mut rows_out = Vec::with_capacity(t.ids().len() * m);
            for (i, g) in t.geometry().iter().enumerate() {
                for (j, y) in ys.iter().enumerate() {
                    rows_out.push(TermRow {
                        target: t.ids()[i],
                        source: source(j).unwrap_or(-1),
                        gated: g.mahalanobis_sq(&g.a_t, y) <= gamma,
                        terms: e.terms(i, j),
                        d_predicted: g.mahalanobis_sq(&g.a_t, y).sqrt(),
                        assigned: out[i] == Some(j),
                    });
                }
            }
            let heading = |a: Vec2, b: Vec2| (b - a).y.atan2((b - a).x).to_degrees();
            let turn_deg = t
                .geometry()
                .iter()
                .map(|g| [heading(g.a_tm2, g.a_tm1), heading(g.a_tm1, g.a_t)])
                .collect();
            return Ok(Some(WrongFrame {
                clean_before: clean,
                replication: r,
                frame: f,
                rows: rows_out,
                turn_deg,
            }));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn terms(weighted: [f64; 3]) -> EnergyTerms {
        EnergyTerms {
            raw: weighted,
            column_sum: [1.0; 3],
            alpha: [1.0; 3],
            weighted,
            e: 0.0,
        }
    }

    /// The decisive term is the one whose squared weighted value the true target exceeds the
    /// wrong one by most.
    #[test]
    fn the_decisive_term_is_the_largest_squared_excess() {
        assert_eq!(
            decisive_term(&terms([0.5, 0.9, 0.0]), &terms([0.5, 0.1, 0.0])),
            1
        );
        assert_eq!(
            decisive_term(&terms([0.6, 0.2, 0.0]), &terms([0.4, 0.8, 0.0])),
            0
        );
        assert_eq!(
            decisive_term(&terms([0.1, 0.1, 1.0]), &terms([0.9, 0.2, 0.0])),
            2
        );
    }
}
