//! The particle filter of Section IV on model (13): Algorithm 1 (bootstrap proposal, weights
//! `w̃_k = w_{k−1} p(y_k | x_k)`), resampling by Algorithm 2 when `N_eff < N_T`, and the
//! weighted-mean estimate `x̂_k = Σ w_k^i x_k^i`.
//!
//! Algorithm 2 is systematic resampling: one `u_1 ~ U(0, 1/N)`, then `u_{i+1} = u_i + 1/N`,
//! each `u_i` mapped to the first particle whose cumulative weight reaches it. That is
//! [`pf_core::resample::Systematic`], which the default [`EstimatorConfig`] uses.
//!
//! Two ways in, giving identical numbers for the same random stream:
//! - off-line ([`run_filter`]): a whole [`DredgeData`] through [`ParticleFilter::run`];
//! - on-line ([`OnlineEstimator`]): one [`Sample`] at a time through [`ParticleFilter::step`],
//!   each estimate returned as soon as its sample arrives.
//!
//! Alg. 1 resamples right after the weight update when `N_eff < N_T`; pf-core takes the same
//! decision at the start of the next step, on the same weights, so the particle paths agree.
//! The estimate of step `k` is the weighted mean before that resampling (it has the same
//! expectation and less Monte Carlo noise).

use crate::data::{DredgeData, Sample};
use crate::direct::{DirectConfig, DirectEstimate, direct_computation, hold};
use crate::error::{DredgeError, Result};
use crate::model::{Inflow, M_T, Measurement, OverflowModel, Prior, Q_O, RHO_O, State, V_T};
use pf_core::CoreError;
use pf_core::filter::{EssThreshold, FilterConfig, ParticleFilter, ResamplePolicy};
use pf_core::mc::{Par, PfRng, stream_rng, try_replicate};
use pf_core::metrics::ResidualSummary;
use pf_core::observe::{Observer, StepView};
use pf_core::params::ParamError;
use pf_core::resample::Resampler;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Settings of the overflow particle filter. The `Default` is the paper's (Section V-B).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorConfig {
    /// `N`, the number of particles (1000).
    pub n_particles: usize,
    /// `N_T`, resample when `N_eff < N_T` (900, i.e. 0.9 N).
    pub n_t: f64,
    /// `σ(ε_x)` for `(V_t, m_t, Q_o, ρ_o)`: `[0, 3000, 0.2, 5]`.
    pub sigma_x: [f64; 4],
    /// `σ(ε_y)` for `(V_t, m_t)`: `[10, 12000]`.
    pub sigma_y: [f64; 2],
    /// `p(x_0)`, which the paper leaves unstated.
    pub prior: Prior,
    /// The resampling scheme (Algorithm 2 = systematic).
    pub resampler: Resampler,
    /// `T_s` for a step that has no input (s); the logged period of the data is used otherwise.
    pub t_s: f64,
}

impl Default for EstimatorConfig {
    fn default() -> Self {
        EstimatorConfig {
            n_particles: 1000,
            n_t: 900.0,
            sigma_x: [0.0, 3000.0, 0.2, 5.0],
            sigma_y: [10.0, 12000.0],
            prior: Prior::default(),
            resampler: Resampler::Systematic,
            t_s: 5.0,
        }
    }
}

impl EstimatorConfig {
    /// The same settings with `n` particles and `N_T` scaled to keep `N_T / N`.
    pub fn with_particles(mut self, n: usize) -> Self {
        if self.n_particles > 0 {
            self.n_t *= n as f64 / self.n_particles as f64;
        }
        self.n_particles = n;
        self
    }

    /// Check the settings.
    ///
    /// # Errors
    /// `N = 0`, `N_T` outside `[0, N]`, or bad noise levels or prior.
    pub fn validate(&self) -> Result<()> {
        if self.n_particles == 0 {
            return Err(DredgeError::Param(ParamError {
                name: "N",
                value: 0.0,
                reason: "at least one particle",
            }));
        }
        if !(self.n_t >= 0.0 && self.n_t <= self.n_particles as f64) {
            return Err(DredgeError::Param(ParamError {
                name: "N_T",
                value: self.n_t,
                reason: "the ESS threshold must lie in [0, N]",
            }));
        }
        // The model checks σ(ε_x), σ(ε_y), T_s and the prior.
        self.model((0.0, 0.0)).map(|_| ())
    }

    /// The model (13) with the prior centred on a first measurement `(V_t,0, m_t,0)`.
    ///
    /// # Errors
    /// As [`OverflowModel::new`].
    pub fn model(&self, y0: (f64, f64)) -> Result<OverflowModel> {
        OverflowModel::new(self.sigma_x, self.sigma_y, &self.prior, y0, self.t_s)
    }

    /// The engine's filter settings: `N`, the scheme, and `ESS < N_T`.
    pub fn filter_config(&self) -> FilterConfig {
        FilterConfig {
            n_particles: self.n_particles,
            resampler: self.resampler,
            policy: ResamplePolicy::EssBelow(EssThreshold::Absolute(self.n_t)),
        }
    }

    /// A ready filter for data whose first measurement is `y0`.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn build(&self, y0: (f64, f64)) -> Result<ParticleFilter<OverflowModel>> {
        self.validate()?;
        Ok(ParticleFilter::bootstrap(
            self.model(y0)?,
            self.filter_config(),
        )?)
    }
}

/// `Σ_i w^i x^i_j`, the weighted mean of component `j`, summed in particle order (so the
/// on-line and off-line paths give the same bits).
#[inline]
fn weighted_component(x: &[State], w: &[f64], j: usize) -> f64 {
    x.iter().zip(w).map(|(x, w)| w * x[j]).sum()
}

/// An observer that records the estimates `x̂_k` and the ESS of every step, without
/// allocating per step beyond pushing onto its vectors.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct OverflowRecorder {
    /// `V̂_t,k`.
    pub v_t: Vec<f64>,
    /// `m̂_t,k`.
    pub m_t: Vec<f64>,
    /// `Q̂_o,k`.
    pub q_o: Vec<f64>,
    /// `ρ̂_o,k`.
    pub rho_o: Vec<f64>,
    /// `N_eff` after the weight update of step `k`.
    pub ess: Vec<f64>,
    /// Whether step `k` began by resampling (decided on `N_eff` of step `k − 1`).
    pub resampled: Vec<bool>,
}

impl Observer<State> for OverflowRecorder {
    fn on_start(&mut self, n: usize) {
        let _ = n;
        self.v_t.clear();
        self.m_t.clear();
        self.q_o.clear();
        self.rho_o.clear();
        self.ess.clear();
        self.resampled.clear();
    }
    fn on_step(&mut self, view: &StepView<'_, State>) {
        let (x, w) = (view.particles, view.weights);
        self.v_t.push(weighted_component(x, w, V_T));
        self.m_t.push(weighted_component(x, w, M_T));
        self.q_o.push(weighted_component(x, w, Q_O));
        self.rho_o.push(weighted_component(x, w, RHO_O));
        self.ess.push(view.report.ess);
        self.resampled.push(view.report.resampled);
    }
}

/// One filter run over a data set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FilterRun {
    /// The estimates and ESS per sample.
    pub estimates: OverflowRecorder,
    /// The log-likelihood estimate `log p̂(y_{0:n})`.
    pub log_lik: f64,
}

/// Observations and inputs for [`ParticleFilter::run`]: `ys[k]` is `y_k` (`None` if both
/// measurements are missing), `us[k]` drives `x_{k−1} → x_k` (`us[0]` is unused).
///
/// # Errors
/// Invalid data.
pub fn filter_inputs(
    data: &DredgeData,
    t_s: f64,
) -> Result<(Vec<Option<Measurement>>, Vec<Inflow>)> {
    data.validate(1)?;
    let missing = |column| DredgeError::MissingFirstValue { column };
    let q_i = hold(&data.q_i).ok_or(missing("Q_i"))?;
    let rho_i = hold(&data.rho_i).ok_or(missing("rho_i"))?;
    let ys = (0..data.len())
        .map(|k| {
            let y = Measurement {
                v_t: data.v_t[k],
                m_t: data.m_t[k],
            };
            (y.v_t.is_some() || y.m_t.is_some()).then_some(y)
        })
        .collect();
    let us = (0..data.len())
        .map(|k| {
            let j = k.saturating_sub(1);
            Inflow {
                q_i: q_i[j],
                rho_i: rho_i[j],
                t_s: if k == 0 {
                    t_s
                } else {
                    data.t[k] - data.t[k - 1]
                },
            }
        })
        .collect();
    Ok((ys, us))
}

fn step_error(e: CoreError) -> DredgeError {
    match e {
        CoreError::AllWeightsZero { t } | CoreError::NonFiniteWeight { t, .. } => {
            DredgeError::FilterStep {
                index: t,
                source: e,
            }
        }
        other => DredgeError::Core(other),
    }
}

/// Run the filter over a whole data set, telling `observer` about every step too (for
/// particle clouds, genealogies …).
///
/// # Errors
/// Invalid data or settings, or a filter step whose weights all vanish
/// ([`DredgeError::FilterStep`] with the sample index).
pub fn run_filter_observed<R: Rng + ?Sized, O: Observer<State>>(
    data: &DredgeData,
    cfg: &EstimatorConfig,
    rng: &mut R,
    observer: &mut O,
) -> Result<FilterRun> {
    let (ys, us) = filter_inputs(data, cfg.t_s)?;
    let y0 = (
        data.v_t[0].ok_or(DredgeError::MissingFirstValue { column: "V_t" })?,
        data.m_t[0].ok_or(DredgeError::MissingFirstValue { column: "m_t" })?,
    );
    let mut pf = cfg.build(y0)?;
    let mut rec = OverflowRecorder::default();
    let summary = pf
        .run(&ys, Some(&us), rng, &mut (&mut rec, observer))
        .map_err(step_error)?;
    Ok(FilterRun {
        estimates: rec,
        log_lik: summary.log_lik,
    })
}

/// [`run_filter_observed`] without an extra observer.
///
/// # Errors
/// As [`run_filter_observed`].
pub fn run_filter<R: Rng + ?Sized>(
    data: &DredgeData,
    cfg: &EstimatorConfig,
    rng: &mut R,
) -> Result<FilterRun> {
    run_filter_observed(data, cfg, rng, &mut ())
}

/// One on-line estimate, emitted as soon as its sample arrives.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OnlineEstimate {
    /// `t_k` (s).
    pub t: f64,
    /// `Q̂_o,k` (m³/s).
    #[serde(rename = "Q_o")]
    pub q_o: f64,
    /// `ρ̂_o,k` (kg/m³).
    #[serde(rename = "rho_o")]
    pub rho_o: f64,
}

/// The on-line estimator: feed it samples one at a time with [`push`](Self::push).
///
/// The filter is built at the first sample (its prior is centred on that sample's `V_t`,
/// `m_t`), then stepped once per sample with [`ParticleFilter::step`]. Missing `Q_i`, `ρ_i`
/// are held at their last value; missing `V_t`/`m_t` are not weighed. After an error the
/// estimator is unchanged, so a bad sample can be skipped.
pub struct OnlineEstimator {
    cfg: EstimatorConfig,
    pf: Option<ParticleFilter<OverflowModel>>,
    /// `(t_{k−1}, Q_i,k−1, ρ_i,k−1)`.
    prev: Option<(f64, f64, f64)>,
    index: usize,
}

impl OnlineEstimator {
    /// An estimator waiting for its first sample.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn new(cfg: &EstimatorConfig) -> Result<Self> {
        cfg.validate()?;
        Ok(OnlineEstimator {
            cfg: *cfg,
            pf: None,
            prev: None,
            index: 0,
        })
    }

    /// Number of samples taken so far.
    pub fn samples_seen(&self) -> usize {
        self.index
    }

    /// The filter, once the first sample has arrived (for its particles and weights).
    pub fn filter(&self) -> Option<&ParticleFilter<OverflowModel>> {
        self.pf.as_ref()
    }

    /// Take sample `k` and return `x̂_k`'s overflow components.
    ///
    /// # Errors
    /// A bad sample (non-finite, negative, time not increasing, incomplete first sample), or a
    /// filter step whose weights all vanish. The estimator is left as it was.
    pub fn push<R: Rng + ?Sized>(&mut self, s: &Sample, rng: &mut R) -> Result<OnlineEstimate> {
        let k = self.index;
        s.validate(k)?;
        let y = Measurement {
            v_t: s.v_t,
            m_t: s.m_t,
        };
        let y = (y.v_t.is_some() || y.m_t.is_some()).then_some(y);
        let pf = match (&mut self.pf, self.prev) {
            (Some(pf), Some((t_prev, q_i, rho_i))) => {
                if s.t <= t_prev {
                    return Err(DredgeError::TimeNotIncreasing {
                        index: k,
                        t_prev,
                        t: s.t,
                    });
                }
                let u = Inflow {
                    q_i,
                    rho_i,
                    t_s: s.t - t_prev,
                };
                pf.step(Some(&u), y.as_ref(), rng).map_err(step_error)?;
                pf
            }
            _ => {
                let first =
                    |v: Option<f64>, column| v.ok_or(DredgeError::MissingFirstValue { column });
                let y0 = (first(s.v_t, "V_t")?, first(s.m_t, "m_t")?);
                first(s.q_i, "Q_i")?;
                first(s.rho_i, "rho_i")?;
                let mut pf = self.cfg.build(y0)?;
                let u0 = Inflow {
                    q_i: s.q_i.unwrap_or_default(),
                    rho_i: s.rho_i.unwrap_or_default(),
                    t_s: self.cfg.t_s,
                };
                pf.step(Some(&u0), y.as_ref(), rng).map_err(step_error)?;
                self.pf.insert(pf)
            }
        };
        let (x, w) = (pf.particles(), pf.weights());
        let est = OnlineEstimate {
            t: s.t,
            q_o: weighted_component(x, w, Q_O),
            rho_o: weighted_component(x, w, RHO_O),
        };
        let (_, q_prev, rho_prev) = self.prev.unwrap_or((s.t, 0.0, 0.0));
        self.prev = Some((s.t, s.q_i.unwrap_or(q_prev), s.rho_i.unwrap_or(rho_prev)));
        self.index += 1;
        Ok(est)
    }
}

/// What `pf-viz dredge estimate` runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimateConfig {
    /// The filter.
    pub filter: EstimatorConfig,
    /// The direct computation reported beside it.
    pub direct: DirectConfig,
    /// Independent filter runs `R`; the reported estimate is their mean.
    pub runs: usize,
    /// Seed: run `r` uses [`pf_core::mc::stream_rng`]`(seed, r)`.
    pub seed: u64,
}

impl Default for EstimateConfig {
    fn default() -> Self {
        EstimateConfig {
            filter: EstimatorConfig::default(),
            direct: DirectConfig::default(),
            runs: 1,
            seed: 0,
        }
    }
}

/// Residual statistics, truth − estimate, over the samples that have truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Residuals {
    /// For `Q_o` (m³/s); `None` if no sample has a true `Q_o`.
    #[serde(rename = "Q_o")]
    pub q_o: Option<ResidualSummary>,
    /// For `ρ_o` (kg/m³); `None` if no sample has a true `ρ_o`.
    #[serde(rename = "rho_o")]
    pub rho_o: Option<ResidualSummary>,
}

/// The JSON of `pf-viz dredge estimate --json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateOutput {
    /// `t_k` (s).
    pub t: Vec<f64>,
    /// `Q̂_o,k`, the mean over the runs (m³/s).
    #[serde(rename = "Q_o")]
    pub q_o: Vec<f64>,
    /// `ρ̂_o,k`, the mean over the runs (kg/m³).
    #[serde(rename = "rho_o")]
    pub rho_o: Vec<f64>,
    /// The direct computation (15)–(16).
    pub direct: DirectEstimate,
    /// Only when the data have truth columns.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub residuals: Option<Residuals>,
}

/// `truth − estimate` where the truth is known.
pub fn residuals_of(truth: &[Option<f64>], estimate: &[f64]) -> Vec<f64> {
    truth
        .iter()
        .zip(estimate)
        .filter_map(|(t, e)| t.map(|t| t - e))
        .collect()
}

/// Summary of `truth − estimate`, or `None` when no truth is known.
///
/// # Errors
/// A non-finite residual (cannot happen with validated data and a working filter).
pub fn summarise(truth: &[Option<f64>], estimate: &[f64]) -> Result<Option<ResidualSummary>> {
    let r = residuals_of(truth, estimate);
    if r.is_empty() {
        return Ok(None);
    }
    Ok(Some(ResidualSummary::new(&r)?))
}

/// The on-line twin of [`estimate`]: `cfg.runs` on-line estimators, run `r` on the stream
/// `(seed, r)` as [`estimate`]'s, each sample pushed through all of them and their mean
/// returned at once. The mean is accumulated in [`estimate`]'s order, so the two print the
/// same numbers.
pub struct OnlineMean {
    filters: Vec<(OnlineEstimator, PfRng)>,
}

impl OnlineMean {
    /// One estimator per run, nothing pushed yet.
    ///
    /// # Errors
    /// An invalid filter configuration, or no runs.
    pub fn new(cfg: &EstimateConfig) -> Result<Self> {
        if cfg.runs == 0 {
            return Err(ParamError::new("runs", 0.0, "at least one filter run").into());
        }
        let filters = (0..cfg.runs)
            .map(|r| {
                Ok((
                    OnlineEstimator::new(&cfg.filter)?,
                    stream_rng(cfg.seed, r as u64),
                ))
            })
            .collect::<Result<_>>()?;
        Ok(OnlineMean { filters })
    }

    /// Push the next sample through every run; the mean of their estimates.
    ///
    /// # Errors
    /// As [`OnlineEstimator::push`], from the first run that fails.
    pub fn push(&mut self, s: &Sample) -> Result<OnlineEstimate> {
        let r = self.filters.len() as f64;
        let mut est = OnlineEstimate {
            t: s.t,
            q_o: 0.0,
            rho_o: 0.0,
        };
        for (f, rng) in &mut self.filters {
            let e = f.push(s, rng)?;
            est.q_o += e.q_o / r;
            est.rho_o += e.rho_o / r;
        }
        Ok(est)
    }
}

/// Estimate `Q_o` and `ρ_o` from a data set: `R` filter runs (in parallel, deterministic for
/// the seed), their mean, the direct computation, and residuals when the truth is known.
///
/// # Errors
/// Invalid data (fewer than 2 samples, NaN, negative flows, time not increasing, an
/// incomplete first sample) or settings (`runs = 0`, …), or a failed filter step.
pub fn estimate(data: &DredgeData, cfg: &EstimateConfig) -> Result<EstimateOutput> {
    cfg.filter.validate()?;
    if cfg.runs == 0 {
        return Err(DredgeError::Param(ParamError {
            name: "runs",
            value: 0.0,
            reason: "at least one filter run",
        }));
    }
    let direct = direct_computation(data, &cfg.direct)?;
    let runs = try_replicate(cfg.seed, cfg.runs, Par::Rayon, |_, rng| {
        run_filter(data, &cfg.filter, rng)
    })?;
    let n = data.len();
    let r = runs.len() as f64;
    let mut q_o = vec![0.0; n];
    let mut rho_o = vec![0.0; n];
    for run in &runs {
        for k in 0..n {
            q_o[k] += run.estimates.q_o[k] / r;
            rho_o[k] += run.estimates.rho_o[k] / r;
        }
    }
    let residuals = match &data.truth {
        Some(tr) => Some(Residuals {
            q_o: summarise(&tr.q_o, &q_o)?,
            rho_o: summarise(&tr.rho_o, &rho_o)?,
        }),
        None => None,
    };
    Ok(EstimateOutput {
        t: data.t.clone(),
        q_o,
        rho_o,
        direct,
        residuals,
    })
}
