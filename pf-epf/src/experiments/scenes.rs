//! The three stress scenes ([`Scenario::STRESS`]) run as a user would run `pf-viz epf track`
//! on them: default flags, so `q` and `r` estimated from the init tracks
//! ([`crate::data::NoiseEstimate`]); the tracker with energy and with nearest-neighbour
//! association, against a reference, a constant-velocity Kalman filter with
//! nearest-neighbour association ([`CvKalmanNn`]).
//!
//! Per scene and method, over seeded replications: the association error rate, the RMSE,
//! the fraction of target-frames without a detection and the fraction reported lost, each
//! with its standard error; the mean `q̂`, `r̂`; one example run for the figure.
//!
//! Streams: scene `k` (index in [`Scenario::STRESS`]), replication `r`: the simulation
//! draws from [`stream_rng`]`(seed + 7000 + 10k, r)`, method `i`'s tracking from
//! `(seed + 7001 + 10k + i, r)`; the example run is replication 0.

use crate::association::Association;
use crate::data::{Detections, Init, NoiseEstimate};
use crate::error::Result;
use crate::geometry::Vec2;
use crate::metrics::{
    association_errors, missing_fraction, position_errors, rmse_of, status_fraction,
};
use crate::scenario::{Scenario, ScenarioConfig, TruthTrack, simulate};
use crate::tracker::{
    NoiseChoice, Record, Track, TrackResult, TrackStatus, TrackerConfig, track, tracked_frames,
};
use nalgebra::{Matrix2, Matrix2x4, Matrix4, Vector4};
use pf_core::mc::{Par, Scale, mean_and_se, stream_rng, try_replicate};
use serde::{Deserialize, Serialize};

/// The methods of [`scenes()`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SceneMethod {
    /// `pf-viz epf track --association energy` with default flags.
    Energy,
    /// `pf-viz epf track --association nn` with default flags.
    Nn,
    /// The reference: [`CvKalmanNn`] with the same estimated `q`, `r`.
    CvKalman,
}

impl SceneMethod {
    /// Every method, in table order.
    pub const ALL: [SceneMethod; 3] = [SceneMethod::Energy, SceneMethod::Nn, SceneMethod::CvKalman];

    /// Label for tables and legends.
    pub fn label(self) -> &'static str {
        match self {
            SceneMethod::Energy => "EPF, energy",
            SceneMethod::Nn => "EPF, nn",
            SceneMethod::CvKalman => "CV Kalman + NN",
        }
    }
}

/// The sizes of [`scenes()`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenesConfig {
    /// Replications per scene.
    pub replications: usize,
    /// Particles per target.
    pub n_particles: usize,
    /// The seed of every stream (see the module docs).
    pub seed: u64,
    /// Where the replications run; the result does not depend on it.
    #[serde(skip)]
    pub par: Par,
}

impl ScenesConfig {
    /// 6, 300 or 1000 replications of 100, 300 or 500 particles per target, seed 1.
    pub fn at_scale(scale: Scale) -> Self {
        let (replications, n_particles) = match scale {
            Scale::Quick => (6, 100),
            Scale::Default => (300, 300),
            Scale::Full => (1000, 500),
        };
        ScenesConfig {
            replications,
            n_particles,
            seed: 1,
            par: Par::Rayon,
        }
    }

    /// How many times [`scenes_with_progress`] calls its `tick`.
    pub fn ticks(&self) -> u64 {
        (self.replications as u64).saturating_mul(Scenario::STRESS.len() as u64)
    }
}

/// One method on one scene, over the replications: `(mean, standard error)` pairs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SceneMethodSummary {
    /// The method.
    pub method: SceneMethod,
    /// Association error rate.
    pub error_rate: (f64, f64),
    /// RMSE of the estimates.
    pub rmse: (f64, f64),
    /// Fraction of target-frames without a detection.
    pub missing: (f64, f64),
    /// Fraction of target-frames reported lost.
    pub lost: (f64, f64),
}

/// One scene's results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneResult {
    /// The scene.
    pub scenario: Scenario,
    /// The simulator's detection noise sd (the `r` to recover).
    pub true_r: f64,
    /// The `q` used (`q̂`, or the default without an estimate) over the replications
    /// `(mean, se)`.
    pub q_hat: (f64, f64),
    /// The `r` used, as `q_hat`.
    pub r_hat: (f64, f64),
    /// Per method, in [`SceneMethod::ALL`] order.
    pub methods: Vec<SceneMethodSummary>,
    /// Replication 0's observed frames.
    pub frames: Vec<i64>,
    /// Replication 0's true paths.
    pub truth: Vec<TruthTrack>,
    /// Replication 0's tracks, per method.
    pub example: Vec<(SceneMethod, TrackResult)>,
}

/// The result of [`scenes()`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenesResult {
    /// Sizes.
    pub config: ScenesConfig,
    /// Per scene, in [`Scenario::STRESS`] order.
    pub scenes: Vec<SceneResult>,
}

/// The tracker settings `pf-viz epf track` uses without `--q`, `--r`: `q̂`, `r̂` from the
/// init tracks, or the defaults when they are too short.
pub fn default_flags(init: &Init, association: Association, n_particles: usize) -> TrackerConfig {
    NoiseChoice::new(init, None, None).apply(&TrackerConfig {
        association,
        n_particles,
        ..TrackerConfig::default()
    })
}

/// A constant-velocity Kalman filter per target with nearest-neighbour association: the
/// reference of the stress scenes. State `(x, y, ẋ, ẏ)`; between frames `Δ` apart the
/// velocity takes a white acceleration of variance `σ_a² = 2q²` per frame (the discrete
/// white-noise acceleration model, `Q = σ_a² G Gᵀ`, `G = (Δ²/2, Δ)`, whose second
/// differences have variance `σ_a²/2 = q²` at `Δ = 1`, the `q` of [`NoiseEstimate`]);
/// detections `N(position, r²I)`. Each filter is started by filtering its init track from
/// a flat velocity prior. Association: every gated (target, detection) pair, gate `P_G`
/// of the innovation covariance `S`, taken in increasing `d² + ln|S|` (the negative
/// log-likelihood, so that a coasting target's wide `S` does not make every detection look
/// near), each target and detection at most once.
#[derive(Debug, Clone)]
pub struct CvKalmanNn {
    q: f64,
    r: f64,
    gamma: f64,
    mean: Vec<Vector4<f64>>,
    cov: Vec<Matrix4<f64>>,
    last: Vec<i64>,
    pairs: Vec<(f64, usize, usize)>,
    taken: Vec<bool>,
}

const H: Matrix2x4<f64> = Matrix2x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0);

impl CvKalmanNn {
    /// Filters started from `init`'s tracks.
    ///
    /// # Errors
    /// A gate probability outside (0, 1).
    pub fn new(init: &Init, q: f64, r: f64, gate_probability: f64) -> Result<Self> {
        let mut f = CvKalmanNn {
            q,
            r,
            gamma: crate::association::gate_threshold(gate_probability)?,
            mean: Vec::new(),
            cov: Vec::new(),
            last: Vec::new(),
            pairs: Vec::new(),
            taken: Vec::new(),
        };
        for t in init.targets() {
            let (f0, y0) = t.points[0];
            let mut m = Vector4::new(y0.x, y0.y, 0.0, 0.0);
            let big = 1e6;
            let mut p = Matrix4::from_diagonal(&Vector4::new(r * r, r * r, big, big));
            let mut last = f0;
            for &(fr, y) in &t.points[1..] {
                f.predict_one(&mut m, &mut p, (fr - last) as f64);
                Self::update_one(&mut m, &mut p, y, r * r);
                last = fr;
            }
            f.mean.push(m);
            f.cov.push(p);
            f.last.push(last);
        }
        Ok(f)
    }

    fn predict_one(&self, m: &mut Vector4<f64>, p: &mut Matrix4<f64>, dt: f64) {
        let mut fm = Matrix4::identity();
        fm[(0, 2)] = dt;
        fm[(1, 3)] = dt;
        let s2 = 2.0 * self.q * self.q;
        let (a, b, c) = (dt.powi(4) / 4.0, dt.powi(3) / 2.0, dt * dt);
        let mut qm = Matrix4::zeros();
        for i in 0..2 {
            qm[(i, i)] = a * s2;
            qm[(i, i + 2)] = b * s2;
            qm[(i + 2, i)] = b * s2;
            qm[(i + 2, i + 2)] = c * s2;
        }
        *m = fm * *m;
        *p = fm * *p * fm.transpose() + qm;
    }

    fn update_one(m: &mut Vector4<f64>, p: &mut Matrix4<f64>, y: Vec2, r2: f64) {
        let s = H * *p * H.transpose() + Matrix2::identity() * r2;
        let Some(si) = s.try_inverse() else { return };
        let k = *p * H.transpose() * si;
        let innov = y - H * *m;
        *m += k * innov;
        *p = (Matrix4::identity() - k * H) * *p;
    }

    /// Predict every target to `frame`, associate `ys`, update; `out[k]` is target `k`'s
    /// detection.
    pub fn step(&mut self, frame: i64, ys: &[Vec2], out: &mut [Option<usize>]) {
        let r2 = self.r * self.r;
        self.pairs.clear();
        for k in 0..self.mean.len() {
            let (mut m, mut p) = (self.mean[k], self.cov[k]);
            self.predict_one(&mut m, &mut p, (frame - self.last[k]) as f64);
            self.mean[k] = m;
            self.cov[k] = p;
            self.last[k] = frame;
            let s = H * p * H.transpose() + Matrix2::identity() * r2;
            let Some(si) = s.try_inverse() else { continue };
            let log_det = s.determinant().ln();
            for (j, y) in ys.iter().enumerate() {
                let v = y - H * m;
                let d2 = (v.transpose() * si * v)[(0, 0)];
                if d2 <= self.gamma {
                    self.pairs.push((d2 + log_det, k, j));
                }
            }
        }
        self.pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        out.fill(None);
        self.taken.clear();
        self.taken.resize(ys.len(), false);
        for &(_, k, j) in &self.pairs {
            if out[k].is_none() && !self.taken[j] {
                out[k] = Some(j);
                self.taken[j] = true;
            }
        }
        for (k, o) in out.iter().enumerate() {
            if let Some(j) = *o {
                let (mut m, mut p) = (self.mean[k], self.cov[k]);
                Self::update_one(&mut m, &mut p, ys[j], r2);
                self.mean[k] = m;
                self.cov[k] = p;
            }
        }
    }

    /// Target `k`'s position estimate.
    pub fn position(&self, k: usize) -> Vec2 {
        Vec2::new(self.mean[k][0], self.mean[k][1])
    }
}

/// Run [`CvKalmanNn`] through `detections` as [`track`] runs the tracker (statuses: a target
/// without a detection for more than `lost_after` tracked frames in a row is lost).
///
/// # Errors
/// Nothing to track; a bad gate probability.
pub fn track_cv_kalman(
    detections: &Detections,
    init: &Init,
    q: f64,
    r: f64,
    cfg: &TrackerConfig,
) -> Result<TrackResult> {
    let frames = tracked_frames(detections, init)?;
    let mut kf = CvKalmanNn::new(init, q, r, cfg.gate_probability)?;
    let k = init.targets().len();
    let mut tracks: Vec<Track> = init
        .targets()
        .iter()
        .map(|t| Track {
            target: t.id,
            position: Vec::with_capacity(frames.len()),
            detection: Vec::with_capacity(frames.len()),
            status: Vec::with_capacity(frames.len()),
        })
        .collect();
    let mut out = vec![None; k];
    let mut misses = vec![0usize; k];
    let mut ys = Vec::new();
    for &f in &frames {
        let rows = detections.positions_into(f, &mut ys);
        kf.step(f, &ys, &mut out);
        for (i, tr) in tracks.iter_mut().enumerate() {
            let p = kf.position(i);
            tr.position.push([p.x, p.y]);
            tr.detection.push(out[i].map(|j| rows.start + j));
            misses[i] = if out[i].is_some() { 0 } else { misses[i] + 1 };
            tr.status.push(match misses[i] {
                0 => TrackStatus::Associated,
                n if n > cfg.lost_after => TrackStatus::Lost,
                _ => TrackStatus::Coasting,
            });
        }
    }
    Ok(TrackResult {
        frames,
        tracks,
        records: Vec::new(),
    })
}

/// Replication 0's observed frames and true paths, for the figure.
type ExampleTruth = Option<(Vec<i64>, Vec<TruthTrack>)>;

#[derive(Serialize, Deserialize)]
struct Outcome {
    noise: Option<NoiseEstimate>,
    per_method: Vec<[f64; 4]>,
    example: Vec<TrackResult>,
}

/// Run every stress scene.
///
/// # Errors
/// A filter error.
pub fn scenes(cfg: &ScenesConfig) -> Result<ScenesResult> {
    scenes_with_progress(cfg, &|| {})
}

/// [`scenes()`], calling `tick` [`ScenesConfig::ticks`] times.
///
/// # Errors
/// As [`scenes()`].
pub fn scenes_with_progress(cfg: &ScenesConfig, tick: &(dyn Fn() + Sync)) -> Result<ScenesResult> {
    let mut out = Vec::with_capacity(Scenario::STRESS.len());
    for (k, &s) in Scenario::STRESS.iter().enumerate() {
        let seed = cfg.seed.wrapping_add(7000 + 10 * k as u64);
        let sc = ScenarioConfig::new(s);
        let runs: Vec<(Outcome, ExampleTruth)> =
            try_replicate(seed, cfg.replications, cfg.par, |r, rng| {
                let sim = simulate(&sc, rng)?;
                let noise = sim.init.estimate_noise();
                let mut per_method = Vec::with_capacity(3);
                let mut example = Vec::new();
                for (i, m) in SceneMethod::ALL.iter().enumerate() {
                    let mut trng = stream_rng(seed.wrapping_add(1 + i as u64), r as u64);
                    let res = match m {
                        SceneMethod::Energy | SceneMethod::Nn => {
                            let a = if *m == SceneMethod::Energy {
                                Association::Energy
                            } else {
                                Association::Nearest
                            };
                            let c = default_flags(&sim.init, a, cfg.n_particles);
                            track(&sim.detections, &sim.init, &c, Record::Tracks, &mut trng)?
                        }
                        SceneMethod::CvKalman => {
                            let c = default_flags(&sim.init, Association::Nearest, 1);
                            track_cv_kalman(&sim.detections, &sim.init, c.q, c.r, &c)?
                        }
                    };
                    let errors = position_errors(&res, &sim)?;
                    per_method.push([
                        association_errors(&res, &sim.detections).rate(),
                        rmse_of(&errors)?,
                        missing_fraction(&res),
                        status_fraction(&res, TrackStatus::Lost),
                    ]);
                    if r == 0 {
                        example.push(res);
                    }
                }
                tick();
                let ex = (r == 0).then(|| (sim.frames.clone(), sim.truth.clone()));
                Ok::<_, crate::EpfError>((
                    Outcome {
                        noise,
                        per_method,
                        example,
                    },
                    ex,
                ))
            })?;
        let methods = SceneMethod::ALL
            .iter()
            .enumerate()
            .map(|(i, &method)| {
                let col = |c: usize| {
                    mean_and_se(
                        &runs
                            .iter()
                            .map(|(o, _)| o.per_method[i][c])
                            .collect::<Vec<_>>(),
                    )
                };
                SceneMethodSummary {
                    method,
                    error_rate: col(0),
                    rmse: col(1),
                    missing: col(2),
                    lost: col(3),
                }
            })
            .collect();
        // The q and r used: the estimates, or the defaults where there were none.
        let d = TrackerConfig::default();
        let est = |f: fn(&NoiseEstimate) -> f64, fallback: f64| {
            let v: Vec<f64> = runs
                .iter()
                .map(|(o, _)| o.noise.as_ref().map_or(fallback, f))
                .collect();
            mean_and_se(&v)
        };
        let (frames, truth) = runs
            .first()
            .and_then(|(_, ex)| ex.clone())
            .unwrap_or_default();
        let (q_hat, r_hat) = (est(|e| e.q, d.q), est(|e| e.r, d.r));
        let example = runs
            .into_iter()
            .next()
            .map(|(o, _)| SceneMethod::ALL.into_iter().zip(o.example).collect())
            .unwrap_or_default();
        out.push(SceneResult {
            scenario: s,
            true_r: s.noise(),
            q_hat,
            r_hat,
            methods,
            frames,
            truth,
            example,
        });
    }
    Ok(ScenesResult {
        config: cfg.clone(),
        scenes: out,
    })
}
