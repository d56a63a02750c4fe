//! The SIR particle filter: owns the particle set and its buffers.

use super::{Bootstrap, Guided, Mutation, ResamplePolicy, RunSummary, StepAt, StepReport};
use crate::error::{CoreError, Result};
use crate::limits::{
    PARTICLE_BUFFERS as PARTICLES, check_count, check_memory, try_filled, try_with_capacity,
};
use crate::model::{EuclideanState, Proposal, StateSpaceModel, TransitionDensity};
use crate::observe::{Observer, StepView};
use crate::params::ParamError;
use crate::particles;
use crate::resample::{Resample, Resampler};
use crate::weights;
use nalgebra::{DMatrix, DVector};
use rand::Rng;
use serde::{Deserialize, Serialize};

/// What every SIR filter needs to know besides the model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterConfig {
    /// Number of particles `N`.
    pub n_particles: usize,
    /// Resampling scheme.
    pub resampler: Resampler,
    /// When to resample.
    pub policy: ResamplePolicy,
}

impl FilterConfig {
    /// `n` particles, systematic resampling at every step.
    pub fn new(n: usize) -> Self {
        FilterConfig {
            n_particles: n,
            resampler: Resampler::Systematic,
            policy: ResamplePolicy::Always,
        }
    }

    /// Check that the configuration can run.
    pub fn validate(&self) -> Result<()> {
        if self.n_particles == 0 {
            return Err(CoreError::Param(ParamError {
                name: "N",
                value: 0.0,
                reason: "the number of particles must be at least 1",
            }));
        }
        check_count("the number of particles N", self.n_particles)?;
        self.policy.validate()
    }
}

/// `0, 1, …, n − 1`: the identity ancestry.
fn identity(n: usize) -> Result<Vec<usize>> {
    let mut a = try_with_capacity(PARTICLES, n)?;
    a.extend(0..n);
    Ok(a)
}

/// A sequential importance sampling–resampling filter, generic over the model `M` and the
/// mutation (proposal) `P`; the resampling scheme is the configuration's
/// [`FilterConfig::resampler`].
///
/// Step it online with [`step`](Self::step) or over a sequence with [`run`](Self::run). Its
/// buffers are allocated once; a step swaps them instead of reallocating. A step that fails
/// (all weights zero, a NaN weight) returns an error and leaves the filter as it was before
/// that step.
pub struct ParticleFilter<M: StateSpaceModel, P = Bootstrap> {
    model: M,
    mutation: P,
    resampler: Resampler,
    policy: ResamplePolicy,
    n: usize,
    /// `ξ_k^i`.
    x: Vec<M::State>,
    x_next: Vec<M::State>,
    /// Normalised `log W_k^i`.
    log_w: Vec<f64>,
    log_w_next: Vec<f64>,
    /// Normalised `W_k^i`.
    w: Vec<f64>,
    w_next: Vec<f64>,
    /// `A_k^i`: index at `k − 1` of the parent of particle `i` at `k`.
    ancestors: Vec<usize>,
    ancestors_next: Vec<usize>,
    last: Option<StepReport>,
}

impl<M: StateSpaceModel> ParticleFilter<M, Bootstrap> {
    /// The bootstrap filter (Gordon, Salmond & Smith 1993).
    pub fn bootstrap(model: M, config: FilterConfig) -> Result<Self> {
        Self::new(model, Bootstrap, config)
    }
}

impl<M: TransitionDensity, Q: Proposal<M>> ParticleFilter<M, Guided<Q>> {
    /// The guided filter with the proposal `q` and the configuration's resampler.
    pub fn guided(model: M, q: Q, config: FilterConfig) -> Result<Self> {
        Self::new(model, Guided(q), config)
    }
}

/// The configuration and the last step, not the particles.
impl<M: StateSpaceModel, P> std::fmt::Debug for ParticleFilter<M, P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParticleFilter")
            .field("n_particles", &self.n)
            .field("resampler", &self.resampler)
            .field("policy", &self.policy)
            .field("last", &self.last)
            .finish_non_exhaustive()
    }
}

impl<M: StateSpaceModel, P: Mutation<M>> ParticleFilter<M, P> {
    /// A filter with the given mutation, resampling with `config.resampler`.
    pub fn new(model: M, mutation: P, config: FilterConfig) -> Result<Self> {
        config.validate()?;
        let n = config.n_particles;
        // Two arrays of states, four of weights and two of ancestors, before any is taken.
        let per_particle =
            2 * size_of::<M::State>() + 4 * size_of::<f64>() + 2 * size_of::<usize>();
        check_memory(PARTICLES, n, n.saturating_mul(per_particle))?;
        Ok(ParticleFilter {
            model,
            mutation,
            resampler: config.resampler,
            policy: config.policy,
            n,
            x: try_with_capacity(PARTICLES, n)?,
            x_next: try_with_capacity(PARTICLES, n)?,
            log_w: try_filled(PARTICLES, n, 0.0)?,
            log_w_next: try_filled(PARTICLES, n, 0.0)?,
            w: try_filled(PARTICLES, n, 0.0)?,
            w_next: try_filled(PARTICLES, n, 0.0)?,
            ancestors: identity(n)?,
            ancestors_next: identity(n)?,
            last: None,
        })
    }

    /// The model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// Number of particles `N`.
    pub fn n_particles(&self) -> usize {
        self.n
    }

    /// Forget everything; the next step is `k = 0` again.
    pub fn reset(&mut self) {
        self.x.clear();
        self.last = None;
    }

    /// Time index of the current particles, `None` before the first step.
    pub fn t(&self) -> Option<usize> {
        self.last.map(|r| r.t)
    }

    /// The report of the last step.
    pub fn last_report(&self) -> Option<&StepReport> {
        self.last.as_ref()
    }

    /// Running log-likelihood estimate `Σ log ĉ_k` (0 before the first step).
    pub fn log_likelihood(&self) -> f64 {
        self.last.map_or(0.0, |r| r.log_lik)
    }

    /// Current particles `ξ_k^i`.
    pub fn particles(&self) -> &[M::State] {
        &self.x
    }

    /// Current normalised weights `W_k^i` (empty before the first step, like the particles).
    pub fn weights(&self) -> &[f64] {
        self.current(&self.w)
    }

    /// Current normalised log-weights `log W_k^i` (empty before the first step).
    pub fn log_weights(&self) -> &[f64] {
        self.current(&self.log_w)
    }

    /// `A_k^i` of the last step (the identity at `k = 0` or when it did not resample; empty
    /// before the first step).
    pub fn ancestors(&self) -> &[usize] {
        self.current(&self.ancestors)
    }

    /// `v` once a step has been made, nothing before (or after [`reset`](Self::reset)), so
    /// that a reset filter shows no leftovers of its last run.
    fn current<'a, T>(&self, v: &'a [T]) -> &'a [T] {
        if self.last.is_some() { v } else { &[] }
    }

    /// Effective sample size of the current weights.
    pub fn ess(&self) -> f64 {
        self.last.map_or(self.n as f64, |r| r.ess)
    }

    /// `Σ_i W_k^i φ(ξ_k^i)`: the filter estimate of `E[φ(X_k) | y_{0:k}]`.
    pub fn expectation(&self, phi: impl Fn(&M::State) -> f64) -> f64 {
        self.x.iter().zip(&self.w).map(|(x, w)| w * phi(x)).sum()
    }

    /// A view of the current step, as observers see it.
    pub fn view(&self) -> Option<StepView<'_, M::State>> {
        self.last.map(|report| StepView {
            report,
            particles: &self.x,
            log_weights: &self.log_w,
            weights: &self.w,
            ancestors: &self.ancestors,
        })
    }

    /// Advance one step: `k = 0` on the first call, then `k + 1`. `u` is the input `u_k` and
    /// `y` the observation `y_k` (`None`: missing, so the weights are carried unchanged).
    ///
    /// # Errors
    /// [`CoreError::AllWeightsZero`] or [`CoreError::NonFiniteWeight`] at step `k`; the filter
    /// then stays at `k − 1`.
    pub fn step<R: Rng + ?Sized>(
        &mut self,
        u: Option<&M::Input>,
        y: Option<&M::Obs>,
        rng: &mut R,
    ) -> Result<StepReport> {
        let n = self.n;
        let log_n = (n as f64).ln();
        let (t, resampled, prior_log_lik) = match self.last {
            None => {
                self.x_next.clear();
                for (i, lw) in self.log_w_next.iter_mut().enumerate() {
                    let x0 = self.model.sample_initial(rng);
                    *lw = self.mutation.initial_log_weight(&self.model, &x0, y) - log_n;
                    self.x_next.push(x0);
                    self.ancestors_next[i] = i;
                }
                (0, false, 0.0)
            }
            Some(last) => {
                let t = last.t + 1;
                let resample = self.policy.should_resample(last.ess, n);
                if resample {
                    self.resampler
                        .resample(&self.w, rng, &mut self.ancestors_next);
                } else {
                    for (i, a) in self.ancestors_next.iter_mut().enumerate() {
                        *a = i;
                    }
                }
                if self.x_next.len() != n {
                    // The first move: storage for the new states, reused from then on.
                    self.x_next.clone_from(&self.x);
                }
                let at = StepAt { t, u, y };
                for i in 0..n {
                    let a = self.ancestors_next[i];
                    let x = &mut self.x_next[i];
                    let lw = self.mutation.mutate(&self.model, at, &self.x[a], x, rng);
                    let prior = if resample { -log_n } else { self.log_w[i] };
                    self.log_w_next[i] = prior + lw;
                }
                (t, resample, last.log_lik)
            }
        };
        let log_c = if y.is_none() && !self.mutation.reweights_without_observation() {
            // Nothing to weigh against: carry the weights exactly (uniform at the start or
            // after resampling).
            if resampled || t == 0 {
                self.w_next.fill(1.0 / n as f64);
            } else {
                self.w_next.copy_from_slice(&self.w);
            }
            0.0
        } else {
            weights::normalise(t, &mut self.log_w_next, &mut self.w_next)?
        };
        std::mem::swap(&mut self.x, &mut self.x_next);
        std::mem::swap(&mut self.log_w, &mut self.log_w_next);
        std::mem::swap(&mut self.w, &mut self.w_next);
        std::mem::swap(&mut self.ancestors, &mut self.ancestors_next);
        let report = StepReport {
            t,
            log_lik_increment: log_c,
            log_lik: prior_log_lik + log_c,
            ess: weights::ess(&self.w),
            resampled,
        };
        self.last = Some(report);
        Ok(report)
    }

    /// Filter a whole sequence `y_0, …, y_n` from the start, telling `observer` about every
    /// step. `us`, if given, must have one input per observation.
    ///
    /// # Errors
    /// A length mismatch between `ys` and `us`, an empty `ys`, or any step error.
    pub fn run<R: Rng + ?Sized, O: Observer<M::State>>(
        &mut self,
        ys: &[Option<M::Obs>],
        us: Option<&[M::Input]>,
        rng: &mut R,
        observer: &mut O,
    ) -> Result<RunSummary> {
        if ys.is_empty() {
            return Err(CoreError::Empty {
                what: "observation sequence",
            });
        }
        if let Some(us) = us
            && us.len() != ys.len()
        {
            return Err(CoreError::DimensionMismatch {
                what: "inputs u_k against observations y_k",
                expected: ys.len(),
                got: us.len(),
            });
        }
        self.reset();
        observer.on_start(self.n);
        let mut reports = Vec::with_capacity(ys.len());
        for (k, y) in ys.iter().enumerate() {
            let u = us.map(|us| &us[k]);
            let report = self.step(u, y.as_ref(), rng)?;
            if let Some(view) = self.view() {
                observer.on_step(&view);
            }
            reports.push(report);
        }
        observer.on_finish()?;
        Ok(RunSummary {
            log_lik: self.log_likelihood(),
            reports,
        })
    }
}

impl<M, P> ParticleFilter<M, P>
where
    M: StateSpaceModel,
    M::State: EuclideanState,
{
    /// Weighted mean of the current particles.
    ///
    /// # Errors
    /// [`CoreError::Empty`] before the first step.
    pub fn mean(&self) -> Result<DVector<f64>> {
        particles::weighted_mean(&self.x, &self.w)
    }

    /// Weighted covariance of the current particles.
    ///
    /// # Errors
    /// [`CoreError::Empty`] before the first step.
    pub fn covariance(&self) -> Result<DMatrix<f64>> {
        particles::weighted_covariance(&self.x, &self.w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::EssThreshold;
    use crate::mc::stream_rng;
    use crate::model::{Proposal, TransitionDensity};
    use crate::models::NoisyAr1;
    use crate::observe::{EssRecorder, GenealogyRecorder};

    fn ar1() -> NoisyAr1 {
        NoisyAr1::new(0.9, 0.5, 1.0).unwrap()
    }

    fn data(n: usize) -> Vec<Option<f64>> {
        let (_, ys) = ar1().simulate(n, &mut stream_rng(1, 0));
        ys.into_iter().map(Some).collect()
    }

    /// A model whose likelihood is exactly zero everywhere: every weight underflows.
    struct Hopeless;
    impl StateSpaceModel for Hopeless {
        type State = f64;
        type Obs = f64;
        type Input = ();
        fn sample_initial<R: Rng + ?Sized>(&self, _rng: &mut R) -> f64 {
            0.0
        }
        fn sample_transition<R: Rng + ?Sized>(
            &self,
            _: usize,
            x: &f64,
            _: Option<&()>,
            _: &mut R,
        ) -> f64 {
            *x
        }
        fn log_likelihood(&self, _t: usize, x: &f64, y: &f64) -> f64 {
            // The density computed on the natural scale, as much user code does: far from
            // the data it underflows to 0, so its log is −∞ for every particle.
            (-0.5 * ((y - x) / 1e-3).powi(2)).exp().ln()
        }
    }

    #[test]
    fn particle_counts_no_machine_can_hold_are_errors() {
        // The last is within the count limit, but its buffers (2³² particles, 256 GiB) are
        // beyond the machine's memory.
        let counts = [usize::MAX, crate::limits::MAX_COUNT + 1];
        #[cfg(target_os = "linux")]
        let counts = [counts[0], counts[1], crate::limits::MAX_COUNT];
        for n in counts {
            assert!(matches!(
                ParticleFilter::bootstrap(ar1(), FilterConfig::new(n)).map(|_| ()),
                Err(CoreError::TooLarge { .. })
            ));
        }
    }

    #[test]
    fn degenerate_weights_are_an_error_not_nan() {
        let mut pf = ParticleFilter::bootstrap(Hopeless, FilterConfig::new(100)).unwrap();
        let mut rng = stream_rng(0, 0);
        pf.step(None, Some(&0.0), &mut rng).unwrap();
        let before = pf.weights().to_vec();
        let err = pf.step(None, Some(&1e9), &mut rng).unwrap_err();
        assert_eq!(err, CoreError::AllWeightsZero { t: 1 });
        // The failed step lost nothing: the filter is still at t = 0 with its weights.
        assert_eq!(pf.t(), Some(0));
        assert_eq!(pf.weights(), &before[..]);
        assert!(pf.mean().unwrap()[0].is_finite());
    }

    #[test]
    fn missing_observations_propagate_without_reweighting() {
        let cfg = FilterConfig {
            n_particles: 200,
            resampler: Resampler::Systematic,
            policy: ResamplePolicy::Never,
        };
        let mut pf = ParticleFilter::bootstrap(ar1(), cfg).unwrap();
        let mut rng = stream_rng(2, 0);
        pf.step(None, Some(&0.3), &mut rng).unwrap();
        let w_before = pf.weights().to_vec();
        let x_before = pf.particles().to_vec();
        let r = pf.step(None, None, &mut rng).unwrap();
        assert_eq!(r.log_lik_increment, 0.0);
        assert_eq!(pf.weights(), &w_before[..]);
        assert_ne!(pf.particles(), &x_before[..], "particles must still move");
        // A run with gaps works end to end, and the gaps contribute nothing.
        let mut ys = data(30);
        for k in [3, 4, 10, 29] {
            ys[k] = None;
        }
        let mut rec = EssRecorder::new();
        let s = pf.run(&ys, None, &mut rng, &mut rec).unwrap();
        for k in [3, 4, 10, 29] {
            assert_eq!(s.reports[k].log_lik_increment, 0.0);
        }
        assert!(s.log_lik.is_finite());
    }

    #[test]
    fn a_missing_first_observation_leaves_uniform_weights() {
        let mut pf = ParticleFilter::bootstrap(ar1(), FilterConfig::new(8)).unwrap();
        let r = pf.step(None, None, &mut stream_rng(0, 0)).unwrap();
        assert_eq!(r.log_lik_increment, 0.0);
        assert!(pf.weights().iter().all(|&w| w == 0.125));
        assert_eq!(r.ess, 8.0);
    }

    #[test]
    fn ess_policy_resamples_only_below_threshold() {
        let cfg = FilterConfig {
            n_particles: 500,
            resampler: Resampler::Residual,
            policy: ResamplePolicy::EssBelow(EssThreshold::Fraction(0.5)),
        };
        let mut pf = ParticleFilter::bootstrap(ar1(), cfg).unwrap();
        let mut rec = EssRecorder::new();
        let s = pf
            .run(&data(100), None, &mut stream_rng(3, 0), &mut rec)
            .unwrap();
        let mut count = 0;
        for k in 1..s.reports.len() {
            let should = s.reports[k - 1].ess < 250.0;
            assert_eq!(s.reports[k].resampled, should, "step {k}");
            count += usize::from(should);
        }
        assert!(
            count > 0 && count < 100,
            "the test must exercise both branches"
        );
    }

    /// An observer's error (here one that always fails) comes out of `run`, after the
    /// other members of the tuple finished.
    #[test]
    fn run_returns_an_observers_error() {
        struct Fails;
        impl<S> Observer<S> for Fails {
            fn on_finish(&mut self) -> Result<()> {
                Err(CoreError::Empty {
                    what: "test observer",
                })
            }
        }
        let mut pf = ParticleFilter::bootstrap(ar1(), FilterConfig::new(8)).unwrap();
        let mut obs = (EssRecorder::new(), Fails);
        let e = pf
            .run(&data(5), None, &mut stream_rng(1, 0), &mut obs)
            .unwrap_err();
        assert_eq!(
            e,
            CoreError::Empty {
                what: "test observer"
            }
        );
        assert_eq!(obs.0.ess().len(), data(5).len());
    }

    #[test]
    fn same_seed_same_run() {
        let run = || {
            let mut pf = ParticleFilter::bootstrap(ar1(), FilterConfig::new(64)).unwrap();
            let mut g = GenealogyRecorder::new();
            let s = pf
                .run(&data(50), None, &mut stream_rng(9, 4), &mut g)
                .unwrap();
            (s, g.into_genealogy())
        };
        assert_eq!(run(), run());
    }

    /// Before the first step and after a reset the filter shows no particle set at all:
    /// no weights, log-weights or ancestors left from a run, and no view.
    #[test]
    fn a_reset_filter_shows_no_leftovers() {
        let mut pf = ParticleFilter::bootstrap(ar1(), FilterConfig::new(16)).unwrap();
        let empty = |pf: &ParticleFilter<NoisyAr1>| {
            pf.particles().is_empty()
                && pf.weights().is_empty()
                && pf.log_weights().is_empty()
                && pf.ancestors().is_empty()
                && pf.view().is_none()
        };
        assert!(empty(&pf));
        pf.run(&data(5), None, &mut stream_rng(2, 0), &mut ())
            .unwrap();
        assert_eq!(
            (
                pf.weights().len(),
                pf.log_weights().len(),
                pf.ancestors().len()
            ),
            (16, 16, 16)
        );
        pf.reset();
        assert!(empty(&pf));
        assert!(format!("{pf:?}").contains("n_particles: 16"));
    }

    /// The transition used as a proposal: the guided weights must equal the bootstrap ones.
    struct PriorProposal;
    impl Proposal<NoisyAr1> for PriorProposal {
        fn sample<R: Rng + ?Sized>(
            &self,
            m: &NoisyAr1,
            at: StepAt<'_, NoisyAr1>,
            xp: &f64,
            x: &mut f64,
            rng: &mut R,
        ) -> f64 {
            *x = m.sample_transition(at.t, xp, at.u, rng);
            m.log_transition_density(at.t, xp, x, at.u)
        }
        fn log_density(&self, m: &NoisyAr1, at: StepAt<'_, NoisyAr1>, xp: &f64, x: &f64) -> f64 {
            m.log_transition_density(at.t, xp, x, at.u)
        }
    }

    #[test]
    fn guided_with_the_prior_as_proposal_is_the_bootstrap_filter() {
        let ys = data(40);
        let cfg = FilterConfig::new(100);
        let mut boot = ParticleFilter::bootstrap(ar1(), cfg).unwrap();
        let mut guided = ParticleFilter::guided(ar1(), PriorProposal, cfg).unwrap();
        let a = boot.run(&ys, None, &mut stream_rng(5, 0), &mut ()).unwrap();
        let b = guided
            .run(&ys, None, &mut stream_rng(5, 0), &mut ())
            .unwrap();
        // Same draws; log f − log q cancels up to rounding of two equal numbers.
        assert!((a.log_lik - b.log_lik).abs() < 1e-9 * a.log_lik.abs());
        assert_eq!(boot.particles(), guided.particles());
    }

    #[test]
    fn bad_configuration_and_inputs_are_errors() {
        assert!(ParticleFilter::bootstrap(ar1(), FilterConfig::new(0)).is_err());
        let cfg = FilterConfig {
            policy: ResamplePolicy::EssBelow(EssThreshold::Fraction(1.5)),
            ..FilterConfig::new(10)
        };
        assert!(ParticleFilter::bootstrap(ar1(), cfg).is_err());
        let mut pf = ParticleFilter::bootstrap(ar1(), FilterConfig::new(10)).unwrap();
        let mut rng = stream_rng(0, 0);
        assert!(matches!(
            pf.run(&[], None, &mut rng, &mut ()),
            Err(CoreError::Empty { .. })
        ));
        let us = [(), ()];
        assert!(matches!(
            pf.run(&data(5), Some(&us), &mut rng, &mut ()),
            Err(CoreError::DimensionMismatch { .. })
        ));
    }
}
