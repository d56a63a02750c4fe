//! Beyond the paper: the filter checked against its own model, and the alignment of the
//! estimate with the truth.
//!
//! **Self-consistency.** Data are drawn from model (13) itself (the filter's own model): the
//! simulated cycle's phase-3 inputs `Q_i`, `ρ_i` and sampling times, `x_0` drawn from the
//! prior the filter is given, then `x_{k+1} = f(x_k, u_k) + ε_x`, `y_k = (x_1, x_2)_k + ε_y`
//! with the paper's `σ(ε_x)`, `σ(ε_y)`. On such data the filter's weighted mean and variance
//! are the posterior's (up to Monte Carlo error), so for each component `j ∈ {Q_o, ρ_o}` the
//! normalised estimation error squared `NEES_j = (x_j − x̂_j)² / Var̂(x_j | y_{0:k})` has mean
//! exactly 1, and the residuals' sd equals the posterior sd. The joint
//! `NEES = eᵀ Σ̂⁻¹ e` of `(Q_o, ρ_o)` has mean 2; it is reported divided by 2.
//!
//! **Alignment.** The truth at sample `k` is the average over `[t_k, t_{k+1})`, which drives
//! `V_k → V_{k+1}` (eqs. (9)–(10)); the estimate `x̂_k` has seen `y_k = (V_k, m_k)`, which depend
//! on `Q_o`, `ρ_o` of sample `k − 1`. Under the random walks (11)–(12),
//! `E[Q_o,k | y_{0:k}] = E[Q_o,k−1 | y_{0:k}]`: one number is both the filtered value of
//! sample `k − 1` and the one-step prediction of sample `k`. [`Alignment`] gives the residuals
//! against both.

use super::{Scale, filter_seed, phase3};
use crate::data::DredgeData;
use crate::error::{DredgeError, Result};
use crate::estimator::{EstimatorConfig, residuals_of, run_filter_observed};
use crate::model::{Inflow, M_T, OverflowModel, Prior, Q_O, RHO_O, State, V_T};
use crate::simulator::{Cycle, SimConfig};
use pf_core::StateSpaceModel;
use pf_core::mc::{Par, mean_and_se, try_replicate};
use pf_core::metrics::ResidualSummary;
use pf_core::observe::{Observer, StepView};
use pf_core::params::ParamError;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Settings of the self-consistency experiment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConsistencyConfig {
    /// The simulator whose phase-3 inputs and times drive the model-(13) data.
    pub sim: SimConfig,
    /// The filter (the paper's N = 1000, σ(ε_x), σ(ε_y), N_T = 900); its prior is replaced by
    /// the one the data are drawn from.
    pub filter: EstimatorConfig,
    /// `σ` of `Q_o,0` in the data's and the filter's prior (m³/s).
    pub q_o_prior_std: f64,
    /// `σ` of `ρ_o,0` in the data's and the filter's prior (kg/m³).
    pub rho_o_prior_std: f64,
    /// Time constant of the data's volume feedback (s), see [`model13_data`].
    pub volume_hold: f64,
    /// Samples per data set from the start of phase 3; `None` for the whole of phase 3.
    pub max_samples: Option<usize>,
    /// Independent data sets (each with its own filter run).
    pub runs: usize,
    /// Samples between two NEES values taken for the chi-square check, so that they are
    /// nearly independent (the `ρ_o` error forgets within about 20 samples).
    pub spacing: usize,
    /// Seed: the cycle's, and run `r` draws its data and filter on stream
    /// `(seed + 0x5eedf117 + 1, r)`.
    pub seed: u64,
}

impl Default for ConsistencyConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Default)
    }
}

impl ConsistencyConfig {
    /// Presets: `Quick` 8 runs of N = 300, `Default` 32 runs, `Full` 128 runs (N = 1000).
    pub fn at_scale(scale: Scale) -> Self {
        let (runs, filter) = match scale {
            Scale::Quick => (8, EstimatorConfig::default().with_particles(300)),
            Scale::Default => (32, EstimatorConfig::default()),
            Scale::Full => (128, EstimatorConfig::default()),
        };
        ConsistencyConfig {
            sim: SimConfig::default(),
            filter,
            q_o_prior_std: 1.0,
            rho_o_prior_std: 50.0,
            volume_hold: 60.0,
            max_samples: None,
            runs,
            spacing: 100,
            seed: 1,
        }
    }
}

/// Residuals of the estimate at `k` against the truth of sample `k` and of sample `k − 1`,
/// over the same samples (the first is dropped from both).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Alignment {
    /// `truth_k − x̂_k`.
    pub against_k: ResidualSummary,
    /// `truth_{k−1} − x̂_k`.
    pub against_k_minus_1: ResidualSummary,
}

impl Alignment {
    /// Compare `hat[k]` with `truth[k]` and with `truth[k − 1]` for `k = 1 … n − 1`.
    ///
    /// # Errors
    /// Fewer than two samples, or a non-finite residual.
    pub fn new(truth: &[f64], hat: &[f64]) -> Result<Self> {
        let n = truth.len().min(hat.len());
        if n < 2 {
            return Err(DredgeError::Param(ParamError {
                name: "samples",
                value: n as f64,
                reason: "the alignment needs at least two samples",
            }));
        }
        let at_k: Vec<f64> = (1..n).map(|k| truth[k] - hat[k]).collect();
        let before: Vec<f64> = (1..n).map(|k| truth[k - 1] - hat[k]).collect();
        Ok(Alignment {
            against_k: ResidualSummary::new(&at_k)?,
            against_k_minus_1: ResidualSummary::new(&before)?,
        })
    }
}

/// Per step: the weighted mean and covariance of `(Q_o, ρ_o)` (the filter's posterior).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MomentRecorder {
    /// `x̂` of `(Q_o, ρ_o)` per step.
    pub mean: Vec<[f64; 2]>,
    /// `(Var Q_o, Cov, Var ρ_o)` per step.
    pub cov: Vec<[f64; 3]>,
}

impl MomentRecorder {
    /// A recorder with room for `steps` steps, so that recording does not allocate.
    pub fn with_capacity(steps: usize) -> Self {
        MomentRecorder {
            mean: Vec::with_capacity(steps),
            cov: Vec::with_capacity(steps),
        }
    }
}

impl Observer<State> for MomentRecorder {
    fn on_start(&mut self, _n: usize) {
        self.mean.clear();
        self.cov.clear();
    }
    fn on_step(&mut self, view: &StepView<'_, State>) {
        let (x, w) = (view.particles, view.weights);
        let (mut mq, mut mr) = (0.0, 0.0);
        for (x, w) in x.iter().zip(w) {
            mq += w * x[Q_O];
            mr += w * x[RHO_O];
        }
        let (mut vq, mut c, mut vr) = (0.0, 0.0, 0.0);
        for (x, w) in x.iter().zip(w) {
            let (dq, dr) = (x[Q_O] - mq, x[RHO_O] - mr);
            vq += w * dq * dq;
            c += w * dq * dr;
            vr += w * dr * dr;
        }
        self.mean.push([mq, mr]);
        self.cov.push([vq, c, vr]);
    }
}

/// Data drawn from `model` (13) itself over the samples of `cycle` from `from` on:
/// `x_0 ~ p(x_0)`, `y_k = (V_t, m_t)_k + ε_y`, `x_{k+1} ~ p(x_{k+1} | x_k, u_k)`, with the
/// cycle's `ρ_i` and sampling times. The data carry no truth columns (a drawn `Q_o` may go
/// below zero, which a data file may not hold); the drawn `Q_o,k`, `ρ_o,k`, which drive
/// `V_k → V_{k+1}` as the simulator's sample averages do, come back beside them.
///
/// The inflow is the cycle's plus a feedback on the measured volume,
/// `Q_i,k = max(0, Q_i,k^cycle + (V_k^cycle − y_V,k) / hold)`: the random walk (11) lets `Q_o`
/// wander by several m³/s over phase 3, and without it the volume would leave any physical
/// range (below zero). The feedback uses measurements only, as an operator's or a
/// controller's does, so the input tells the filter nothing the measurements do not, and
/// the filter's posterior stays the exact one.
///
/// # Errors
/// `from` outside the cycle, or a non-positive `hold`.
pub fn model13_data<R: Rng + ?Sized>(
    cycle: &Cycle,
    from: usize,
    hold: f64,
    model: &OverflowModel,
    rng: &mut R,
) -> Result<Model13Data> {
    if from >= cycle.len() {
        return Err(DredgeError::Param(ParamError {
            name: "from",
            value: from as f64,
            reason: "the first sample must lie inside the cycle",
        }));
    }
    pf_core::params::positive("hold", hold)?;
    let n = cycle.len() - from;
    let mut d = DredgeData {
        t: cycle.t[from..].to_vec(),
        v_t: Vec::with_capacity(n),
        m_t: Vec::with_capacity(n),
        q_i: Vec::with_capacity(n),
        rho_i: cycle.rho_i[from..].iter().copied().map(Some).collect(),
        truth: None,
    };
    let mut q_o = Vec::with_capacity(n);
    let mut rho_o = Vec::with_capacity(n);
    let mut x = model.sample_initial(rng);
    for k in 0..n {
        let (e_v, e_m): (f64, f64) = (StandardNormal.sample(rng), StandardNormal.sample(rng));
        let y_v = x[V_T] + model.sigma_y[0] * e_v;
        // With the volume held, masses stay far from zero; the clamp keeps a pathological
        // draw within the data's validation.
        d.v_t.push(Some(y_v.max(0.0)));
        d.m_t.push(Some((x[M_T] + model.sigma_y[1] * e_m).max(0.0)));
        q_o.push(x[Q_O]);
        rho_o.push(x[RHO_O]);
        let q_i = (cycle.q_i[from + k] + (cycle.v_t[from + k] - y_v) / hold).max(0.0);
        d.q_i.push(Some(q_i));
        if k + 1 < n {
            let u = Inflow {
                q_i,
                rho_i: cycle.rho_i[from + k],
                t_s: d.t[k + 1] - d.t[k],
            };
            x = model.sample_transition(k + 1, &x, Some(&u), rng);
        }
    }
    Ok(Model13Data {
        data: d,
        q_o,
        rho_o,
    })
}

/// Data drawn by [`model13_data`] and their hidden `Q_o`, `ρ_o`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Model13Data {
    /// Measurements and inputs (no truth columns).
    pub data: DredgeData,
    /// The drawn `Q_o,k` (m³/s).
    pub q_o: Vec<f64>,
    /// The drawn `ρ_o,k` (kg/m³).
    pub rho_o: Vec<f64>,
}

/// One filter run on one model-(13) data set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConsistencyRun {
    /// `Q_o` residual (truth − estimate).
    pub q_o: ResidualSummary,
    /// `ρ_o` residual.
    pub rho_o: ResidualSummary,
    /// `√(mean posterior variance)` of `Q_o` over the run (m³/s).
    pub q_o_posterior_sd: f64,
    /// The same for `ρ_o` (kg/m³).
    pub rho_o_posterior_sd: f64,
    /// Mean `NEES` of `Q_o` over the run.
    pub q_o_nees: f64,
    /// Mean `NEES` of `ρ_o` over the run.
    pub rho_o_nees: f64,
    /// Mean joint `NEES / 2` of `(Q_o, ρ_o)` over the run.
    pub joint_nees: f64,
    /// `NEES` of `Q_o`, `ρ_o` and joint `NEES / 2` at samples `spacing, 2·spacing, …`.
    pub spaced_nees: Vec<[f64; 3]>,
    /// Alignment of `Q̂_o` with the truth of `k` and `k − 1`.
    pub q_o_alignment: Alignment,
    /// Alignment of `ρ̂_o`.
    pub rho_o_alignment: Alignment,
}

/// Mean and standard error over the runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanSe {
    /// Mean over runs.
    pub mean: f64,
    /// Its standard error.
    pub se: f64,
}

impl MeanSe {
    fn of(runs: &[ConsistencyRun], f: impl Fn(&ConsistencyRun) -> f64) -> Self {
        let v: Vec<f64> = runs.iter().map(f).collect();
        let (mean, se) = mean_and_se(&v);
        MeanSe { mean, se }
    }
}

/// Summary over runs of one signal on model-(13) data.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConsistencySignal {
    /// Residual mean.
    pub residual_mean: MeanSe,
    /// Residual std.
    pub residual_std: MeanSe,
    /// Posterior sd, `√(mean variance)`.
    pub posterior_sd: MeanSe,
    /// Mean NEES.
    pub nees: MeanSe,
    /// Residual std against the truth of `k − 1`.
    pub residual_std_k_minus_1: MeanSe,
}

/// The self-consistency experiment's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConsistencyResult {
    /// Samples per data set (the cycle's phase 3).
    pub samples: usize,
    /// The prior the data are drawn from and the filter is given.
    pub prior: Prior,
    /// `Q_o` over runs.
    pub q_o: ConsistencySignal,
    /// `ρ_o` over runs.
    pub rho_o: ConsistencySignal,
    /// Joint `NEES / 2` over runs.
    pub joint_nees: MeanSe,
    /// Mean of the spaced `NEES` values over every run: `Q_o`, `ρ_o`, joint `/ 2`.
    pub spaced_nees_mean: [f64; 3],
    /// How many spaced values each mean has.
    pub spaced_count: usize,
    /// Every run.
    pub runs: Vec<ConsistencyRun>,
}

fn nees(e: [f64; 2], c: [f64; 3]) -> [f64; 3] {
    let [vq, cqr, vr] = c;
    let det = vq * vr - cqr * cqr;
    let joint = (e[0] * e[0] * vr - 2.0 * e[0] * e[1] * cqr + e[1] * e[1] * vq) / det;
    [e[0] * e[0] / vq, e[1] * e[1] / vr, joint / 2.0]
}

fn one_run<R: Rng + ?Sized>(
    cycle: &Cycle,
    from: usize,
    filter: &EstimatorConfig,
    spacing: usize,
    hold: f64,
    rng: &mut R,
) -> Result<ConsistencyRun> {
    let model = filter.model((cycle.v_t[from], cycle.m_t[from]))?;
    let Model13Data {
        data,
        q_o: tq,
        rho_o: tr,
    } = model13_data(cycle, from, hold, &model, rng)?;
    let mut rec = MomentRecorder::with_capacity(data.len());
    let run = run_filter_observed(&data, filter, rng, &mut rec)?;
    let e = &run.estimates;
    let some = |v: &[f64]| v.iter().copied().map(Some).collect::<Vec<_>>();
    let n = tq.len();
    let (mut sq, mut sr, mut sj) = (0.0, 0.0, 0.0);
    let (mut vq, mut vr) = (0.0, 0.0);
    let mut spaced = Vec::with_capacity(n / spacing.max(1));
    for k in 0..n {
        let c = rec.cov[k];
        let v = nees([tq[k] - rec.mean[k][0], tr[k] - rec.mean[k][1]], c);
        if v.iter().any(|x| !x.is_finite()) {
            return Err(DredgeError::Param(ParamError {
                name: "posterior variance",
                value: c[0].min(c[2]),
                reason: "the particle cloud collapsed: NEES is undefined",
            }));
        }
        sq += v[0];
        sr += v[1];
        sj += v[2];
        vq += c[0];
        vr += c[2];
        if spacing > 0 && k > 0 && k % spacing == 0 {
            spaced.push(v);
        }
    }
    let nf = n as f64;
    Ok(ConsistencyRun {
        q_o: ResidualSummary::new(&residuals_of(&some(&tq), &e.q_o))?,
        rho_o: ResidualSummary::new(&residuals_of(&some(&tr), &e.rho_o))?,
        q_o_posterior_sd: (vq / nf).sqrt(),
        rho_o_posterior_sd: (vr / nf).sqrt(),
        q_o_nees: sq / nf,
        rho_o_nees: sr / nf,
        joint_nees: sj / nf,
        spaced_nees: spaced,
        q_o_alignment: Alignment::new(&tq, &e.q_o)?,
        rho_o_alignment: Alignment::new(&tr, &e.rho_o)?,
    })
}

/// Run the filter on `cfg.runs` data sets drawn from model (13) over the phase 3 of the
/// cycle of `cfg.seed`, its prior centred on the cycle's true `Q_o`, `ρ_o` at the start of
/// phase 3 (the data's `x_0` is drawn from the same prior).
///
/// # Errors
/// Invalid settings, no phase 3, no runs, or a failed filter step.
pub fn consistency(cfg: &ConsistencyConfig) -> Result<ConsistencyResult> {
    if cfg.runs == 0 {
        return Err(DredgeError::Param(ParamError {
            name: "runs",
            value: 0.0,
            reason: "at least one run",
        }));
    }
    let mut c = super::cycle::simulated(&cfg.sim, cfg.seed)?;
    let from = phase3(&c)?.start;
    if let Some(m) = cfg.max_samples {
        if m < 2 {
            return Err(DredgeError::Param(ParamError {
                name: "max_samples",
                value: m as f64,
                reason: "at least two samples",
            }));
        }
        truncate(&mut c, from + m);
    }
    let prior = Prior {
        q_o_mean: c.q_o[from],
        q_o_std: cfg.q_o_prior_std,
        rho_o_mean: c.rho_o[from],
        rho_o_std: cfg.rho_o_prior_std,
    };
    let filter = EstimatorConfig {
        prior,
        ..cfg.filter
    };
    filter.validate()?;
    let seed = filter_seed(cfg.seed).wrapping_add(1);
    let runs = try_replicate(seed, cfg.runs, Par::Rayon, |_, rng| {
        one_run(&c, from, &filter, cfg.spacing, cfg.volume_hold, rng)
    })?;
    let signal =
        |pick: fn(&ConsistencyRun) -> (&ResidualSummary, f64, f64, &Alignment)| ConsistencySignal {
            residual_mean: MeanSe::of(&runs, |r| pick(r).0.mean),
            residual_std: MeanSe::of(&runs, |r| pick(r).0.std),
            posterior_sd: MeanSe::of(&runs, |r| pick(r).1),
            nees: MeanSe::of(&runs, |r| pick(r).2),
            residual_std_k_minus_1: MeanSe::of(&runs, |r| pick(r).3.against_k_minus_1.std),
        };
    let q_o = signal(|r| (&r.q_o, r.q_o_posterior_sd, r.q_o_nees, &r.q_o_alignment));
    let rho_o = signal(|r| {
        (
            &r.rho_o,
            r.rho_o_posterior_sd,
            r.rho_o_nees,
            &r.rho_o_alignment,
        )
    });
    let all: Vec<[f64; 3]> = runs.iter().flat_map(|r| r.spaced_nees.clone()).collect();
    let mut spaced_nees_mean = [0.0; 3];
    for v in &all {
        for j in 0..3 {
            spaced_nees_mean[j] += v[j] / all.len().max(1) as f64;
        }
    }
    Ok(ConsistencyResult {
        samples: c.len() - from,
        prior,
        q_o,
        rho_o,
        joint_nees: MeanSe::of(&runs, |r| r.joint_nees),
        spaced_nees_mean,
        spaced_count: all.len(),
        runs,
    })
}

/// Keep the first `len` samples of the per-sample columns the experiment reads.
fn truncate(c: &mut Cycle, len: usize) {
    let columns = [
        &mut c.t,
        &mut c.v_t,
        &mut c.m_t,
        &mut c.q_i,
        &mut c.rho_i,
        &mut c.q_o,
        &mut c.rho_o,
    ];
    for v in columns {
        v.truncate(len);
    }
}

/// The alignment of a Fig. 5 run on the simulator (phase 3): `Q̂_o` and `ρ̂_o` against the
/// truth of `k` and of `k − 1`.
///
/// # Errors
/// Fewer than two phase-3 samples.
pub fn fig5_alignment(f: &super::Fig56Result) -> Result<[Alignment; 2]> {
    Ok([
        Alignment::new(&f.q_o_true, &f.q_o_hat)?,
        Alignment::new(&f.rho_o_true, &f.rho_o_hat)?,
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use pf_core::mc::stream_rng;

    /// A truth that moves by 1 per sample and an estimate one sample late: against `k − 1`
    /// the residual is 0, against `k` it is 1 throughout.
    #[test]
    fn alignment_pairs_the_estimate_with_both_truths() {
        let truth: Vec<f64> = (0..10).map(f64::from).collect();
        let late: Vec<f64> = (0..10).map(|k| f64::from(k.max(1) - 1)).collect();
        let a = Alignment::new(&truth, &late).unwrap();
        assert_eq!(a.against_k_minus_1.max_abs, 0.0);
        assert_eq!((a.against_k.mean, a.against_k.std), (1.0, 0.0));
        assert!(Alignment::new(&[1.0], &[1.0]).is_err());
    }

    /// The joint NEES of a diagonal covariance is the mean of the two scalar ones, and a
    /// correlation along the error lowers it.
    #[test]
    fn joint_nees_matches_its_closed_form() {
        let v = nees([1.0, 2.0], [4.0, 0.0, 16.0]);
        assert_eq!(v, [0.25, 0.25, 0.25]);
        // Σ = [[1, .5], [.5, 1]], e = (1, 1): eᵀΣ⁻¹e = 2 / 1.5.
        let w = nees([1.0, 1.0], [1.0, 0.5, 1.0]);
        assert!((w[2] - 1.0 / 1.5).abs() < 1e-12);
    }

    /// Model-(13) data obey (9) exactly: `V_{k+1} − V_k = T_s (Q_i,k − Q_o,k)` on the truth
    /// (σ(ε_x1) = 0), and their measurements scatter around it with σ(ε_y).
    #[test]
    fn model13_data_follow_the_volume_balance() {
        let cfg = ConsistencyConfig::at_scale(Scale::Quick);
        let c = crate::experiments::cycle::simulated(&cfg.sim, 1).unwrap();
        let from = c.phase3_start.unwrap();
        let model = cfg.filter.model((c.v_t[from], c.m_t[from])).unwrap();
        let mut rng = stream_rng(3, 0);
        let Model13Data { data: d, q_o, .. } =
            model13_data(&c, from, cfg.volume_hold, &model, &mut rng).unwrap();
        assert_eq!(d.len(), c.len() - from);
        assert!(model13_data(&c, c.len(), 60.0, &model, &mut rng).is_err());
        assert!(model13_data(&c, from, 0.0, &model, &mut rng).is_err());
        // Reconstruct V from the balance and compare with the measured volume: the
        // differences are ε_y1 plus the x_0 draw, sd √2·10 at the start, σ_y after.
        let mut v = c.v_t[from];
        let mut dev = Vec::new();
        for k in 1..d.len() {
            v += (d.t[k] - d.t[k - 1]) * (d.q_i[k - 1].unwrap() - q_o[k - 1]);
            dev.push(d.v_t[k].unwrap() - v);
        }
        // Every deviation is the constant x_0 offset plus N(0, 10²) noise: their sd is σ_y
        // within 5 σ of its sampling error (relative sd √(1/(2n))).
        let s = ResidualSummary::new(&dev).unwrap();
        let n = dev.len() as f64;
        assert!(
            (s.std / 10.0 - 1.0).abs() < 5.0 / (2.0 * n).sqrt(),
            "{}",
            s.std
        );
    }
}
