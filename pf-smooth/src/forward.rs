//! Forward-only smoothing of an additive functional (Del Moral, Doucet & Singh 2010): the
//! estimate that forward filtering–backward smoothing (FFBSm) gives, computed in one
//! forward pass. Not in Cappé & Moulines (2005); it is here as the reference their two
//! estimators are judged against, since it does not degenerate with `n`.
//!
//! Each particle carries `T_k^i`, the expectation of the functional under the filter's
//! backward kernel ending at `ξ_k^i`:
//!
//! - `T_0^i = s_0(ξ_0^i)`;
//! - `T_k^i = Σ_j β_k^{ij} [T_{k−1}^j + s_{k−1}(ξ_{k−1}^j, ξ_k^i)]`, with backward weights
//!   `β_k^{ij} ∝ W_{k−1}^j f_k(ξ_k^i | ξ_{k−1}^j)`, normalised over `j`;
//! - `τ̂_n = Σ_i W_n^i T_n^i`.
//!
//! The ancestors play no part, so any proposal and any resampling policy work. The price is
//! `N` transition densities per particle and step, O(N²) work, against O(N) for the
//! path-space and fixed-lag estimators; in return the variance grows linearly in `n`, not
//! quadratically (Del Moral, Doucet & Singh 2010, Theorem 6).
//!
//! ## References
//! - P. Del Moral, A. Doucet, S. S. Singh, "Forward smoothing using sequential Monte Carlo",
//!   Technical Report CUED/F-INFENG/TR 638, University of Cambridge, 2010.
//! - A. Doucet, S. Godsill, C. Andrieu, "On sequential Monte Carlo sampling methods for
//!   Bayesian filtering", *Statistics and Computing* 10, 2000 (FFBSm).

use crate::error::Result;
use crate::estimate::{copy_states, weighted_estimate};
use crate::functional::AdditiveFunctional;
use pf_core::TransitionDensity;
use pf_core::filter::{BatchObserver, BatchView};
use pf_core::mc::Par;
use pf_core::observe::{Observer, StepView};
use rayon::prelude::*;

/// Forward-only (FFBSm) estimator of `τ_n = E[Σ_k s_k | Y_{0:n}]`, as a pf-core [`Observer`].
///
/// It needs the model's transition density ([`TransitionDensity`]) for models without
/// inputs: an observer does not see the inputs `u_k`, and evaluating `f_k` without them
/// would be silently wrong. A step with `t = 0` restarts it. With [`Par::Rayon`] the rows
/// `T_k^i` are computed on the rayon pool, each exactly as on one thread, so the estimate
/// is the same to the last bit; nothing is allocated per step on [`Par::Seq`], and a few
/// scratch rows per rayon task on [`Par::Rayon`].
#[derive(Debug, Clone)]
pub struct ForwardSmoothing<M: TransitionDensity, F> {
    model: M,
    f: F,
    d: usize,
    par: Par,
    /// `ξ_{k−1}^j`.
    prev: Vec<M::State>,
    /// Normalised `log W_{k−1}^j`.
    log_w_prev: Vec<f64>,
    /// `T_k^i`, N×d, particle-major.
    tk: Vec<f64>,
    tk_next: Vec<f64>,
    /// `W_k^i`.
    weights: Vec<f64>,
    /// Scratch of [`Par::Seq`]: backward log-weights, weights and one increment.
    scratch: Row,
    /// A batch filter's step, copied out of its view.
    batch: BatchStep,
    t: Option<usize>,
}

/// A batch filter's particles (column 0), log-weights and weights, and the first error
/// met copying them.
#[derive(Debug, Clone, Default)]
struct BatchStep {
    x: Vec<f64>,
    log_w: Vec<f64>,
    w: Vec<f64>,
    error: Option<pf_core::CoreError>,
}

/// The scratch of one row `T_k^i`: backward log-weights and weights, and every
/// `s_{k−1}(ξ_{k−1}^j, x)`.
#[derive(Debug, Clone, Default)]
struct Row {
    log_beta: Vec<f64>,
    beta: Vec<f64>,
    /// N×d, particle-major.
    s: Vec<f64>,
}

impl Row {
    fn sized(n: usize, d: usize) -> Self {
        let mut row = Row::default();
        row.resize(n, d);
        row
    }

    fn resize(&mut self, n: usize, d: usize) {
        self.log_beta.resize(n, 0.0);
        self.beta.resize(n, 0.0);
        self.s.resize(n * d, 0.0);
    }
}

impl<M, F> ForwardSmoothing<M, F>
where
    M: TransitionDensity<Input = ()>,
    M::State: Clone,
    F: AdditiveFunctional<M::State>,
{
    /// An estimator of the functional `f` under `model`'s transition density, on one thread.
    pub fn new(model: M, f: F) -> Self {
        let d = f.dim();
        ForwardSmoothing {
            model,
            f,
            d,
            par: Par::Seq,
            prev: Vec::new(),
            log_w_prev: Vec::new(),
            tk: Vec::new(),
            tk_next: Vec::new(),
            weights: Vec::new(),
            scratch: Row::default(),
            batch: BatchStep::default(),
            t: None,
        }
    }

    /// The same, computing each step's rows on `par` (the estimate does not change).
    pub fn with_par(mut self, par: Par) -> Self {
        self.par = par;
        self
    }

    /// Time index of the last step seen.
    pub fn t(&self) -> Option<usize> {
        self.t
    }

    /// `T_k^i` of particle `i` (N×d, particle-major).
    pub fn t_stat(&self) -> &[f64] {
        &self.tk
    }

    /// Write `τ̂_k = Σ_i W_k^i T_k^i` into `out` (length d).
    ///
    /// # Errors
    /// [`SmoothError::NoSteps`](crate::SmoothError::NoSteps) before the first step, a length
    /// mismatch, or a non-finite component
    /// ([`SmoothError::NonFiniteEstimate`](crate::SmoothError::NonFiniteEstimate)), which is also what a particle with
    /// no backward weight (every `f_k(ξ_k^i | ξ_{k−1}^j)` zero) leads to.
    pub fn estimate_into(&self, out: &mut [f64]) -> Result<()> {
        let names = (
            "forward-only smoothing estimator",
            "forward-only smoothing estimate",
        );
        weighted_estimate(names, self.t, (&self.weights, &self.tk, self.d), out)
    }

    /// [`estimate_into`](Self::estimate_into) a new vector.
    ///
    /// # Errors
    /// As [`estimate_into`](Self::estimate_into).
    pub fn estimate(&self) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.d];
        self.estimate_into(&mut out)?;
        Ok(out)
    }
}

/// What every row of step `k` reads: the model, the functional, and step `k − 1`'s
/// particles, normalised log-weights and statistics `T_{k−1}` (`d` per particle).
struct BackwardStep<'a, M: TransitionDensity, F> {
    model: &'a M,
    f: &'a F,
    k: usize,
    prev: &'a [M::State],
    log_w_prev: &'a [f64],
    t_prev: &'a [f64],
}

impl<M, F> BackwardStep<'_, M, F>
where
    M: TransitionDensity<Input = ()>,
    F: AdditiveFunctional<M::State>,
{
    /// `row ← T_k^i = Σ_j β^{ij} [T_{k−1}^j + s_{k−1}(ξ_{k−1}^j, x)]` for the particle `x`,
    /// or NaN when no `j` has a positive backward weight; compiled with AVX2 where the CPU
    /// has it ([`pf_core::simd::vectorised`]), so that its loops over `j` run four lanes
    /// wide.
    fn row(&self, x: &M::State, scratch: &mut Row, row: &mut [f64]) {
        pf_core::simd::vectorised(
            #[inline(always)]
            || self.row_inline(x, scratch, row),
        );
    }

    /// [`row`](Self::row)'s body.
    #[inline(always)]
    fn row_inline(&self, x: &M::State, scratch: &mut Row, row: &mut [f64]) {
        let BackwardStep {
            model,
            f,
            k,
            prev,
            log_w_prev,
            t_prev,
        } = *self;
        let d = row.len();
        for ((lb, xj), lw) in scratch.log_beta.iter_mut().zip(prev).zip(log_w_prev) {
            *lb = lw + model.log_transition_density(k, xj, x, None);
        }
        if pf_core::weights::normalise_into(k, &scratch.log_beta, &mut scratch.beta).is_err() {
            row.fill(f64::NAN);
            return;
        }
        // Σ_j β^{ij} T_{k−1}^j, four components at a time in a local accumulator (summed in
        // the row itself, each `j` waited on the row's previous store).
        // A zero weight is skipped, not multiplied: `T_{k−1}^j` may be NaN (no backward weight
        // at an earlier step), and `0 · NaN` would spread it to every row.
        for (c0, out) in (0..d).step_by(4).zip(row.chunks_mut(4)) {
            let w = out.len();
            let mut acc = [0.0f64; 4];
            if w == 4 {
                // The common case in registers (a slice of run-time length kept `acc` on the
                // stack, a third of the row's time), over two interleaved partial sums (even
                // and odd `j`, added at the end) so that consecutive `j` do not wait on each
                // other's additions.
                let (mut even, mut odd) = ([0.0f64; 4], [0.0f64; 4]);
                let add = |a: &mut [f64; 4], b: f64, tj: &[f64]| {
                    if b != 0.0 {
                        let t4 = &tj[c0..c0 + 4];
                        for (a, t) in a.iter_mut().zip(t4) {
                            *a += b * t;
                        }
                    }
                };
                let mut rows = scratch.beta.iter().zip(t_prev.chunks_exact(d));
                while let Some((&b0, t0)) = rows.next() {
                    add(&mut even, b0, t0);
                    if let Some((&b1, t1)) = rows.next() {
                        add(&mut odd, b1, t1);
                    }
                }
                acc = std::array::from_fn(|l| even[l] + odd[l]);
            } else {
                for (&b, tj) in scratch.beta.iter().zip(t_prev.chunks_exact(d)) {
                    if b != 0.0 {
                        for (l, a) in acc[..w].iter_mut().enumerate() {
                            *a += b * tj[c0 + l];
                        }
                    }
                }
            }
            out.copy_from_slice(&acc[..w]);
        }
        // + Σ_j β^{ij} s_{k−1}(ξ_{k−1}^j, x), in the functional's closed form where it has one.
        f.add_weighted_increments(k, prev, &scratch.beta, x, &mut scratch.s, row);
    }
}

impl<M, F> ForwardSmoothing<M, F>
where
    M: TransitionDensity<Input = ()>,
    M::State: Clone,
    F: AdditiveFunctional<M::State>,
{
    /// One step of the recursion: the particles `ξ_k^i` of step `k`, their normalised
    /// log-weights and weights.
    fn update(&mut self, k: usize, particles: &[M::State], log_weights: &[f64], weights: &[f64]) {
        let n = particles.len();
        let d = self.d;
        if k == 0 || self.t.is_none() {
            self.tk.clear();
            self.tk.resize(n * d, 0.0);
            for (x0, t0) in particles.iter().zip(self.tk.chunks_exact_mut(d)) {
                self.f.initial(x0, t0);
            }
        } else {
            self.tk_next.resize(n * d, 0.0);
            let step = BackwardStep {
                model: &self.model,
                f: &self.f,
                k,
                prev: &self.prev[..],
                log_w_prev: &self.log_w_prev[..],
                t_prev: &self.tk[..],
            };
            let m = step.prev.len();
            match self.par {
                Par::Seq => {
                    self.scratch.resize(m, d);
                    for (x, row) in particles.iter().zip(self.tk_next.chunks_exact_mut(d)) {
                        step.row(x, &mut self.scratch, row);
                    }
                }
                Par::Rayon => self
                    .tk_next
                    .par_chunks_exact_mut(d)
                    .zip(particles.par_iter())
                    .for_each_init(|| Row::sized(m, d), |s, (row, x)| step.row(x, s, row)),
            }
            std::mem::swap(&mut self.tk, &mut self.tk_next);
        }
        copy_states(&mut self.prev, particles);
        self.log_w_prev.clear();
        self.log_w_prev.extend_from_slice(log_weights);
        self.weights.clear();
        self.weights.extend_from_slice(weights);
        self.t = Some(k);
    }
}

impl<M, F> Observer<M::State> for ForwardSmoothing<M, F>
where
    M: TransitionDensity<Input = ()>,
    M::State: Clone,
    F: AdditiveFunctional<M::State>,
{
    fn on_step(&mut self, view: &StepView<'_, M::State>) {
        self.update(
            view.report.t,
            view.particles,
            view.log_weights,
            view.weights,
        );
    }
}

/// On the batch filter, for a scalar state in column 0 (such as
/// [`SmoothedAr1`](crate::batch::SmoothedAr1)'s): the particles and weights are copied out
/// of each step's view into buffers kept between steps.
impl<M, F> BatchObserver for ForwardSmoothing<M, F>
where
    M: TransitionDensity<Input = (), State = f64>,
    F: AdditiveFunctional<f64>,
{
    fn on_step(&mut self, view: &BatchView<'_>) {
        let mut b = std::mem::take(&mut self.batch);
        let n = view.n();
        b.x.resize(n, 0.0);
        b.w.resize(n, 0.0);
        b.log_w.resize(n, 0.0);
        let copied = view
            .column_into(0, &mut b.x)
            .and_then(|()| view.weights_into(&mut b.w));
        match copied {
            Ok(()) => {
                for (l, w) in b.log_w.iter_mut().zip(&b.w) {
                    *l = w.ln();
                }
                self.update(view.report().t, &b.x, &b.log_w, &b.w);
            }
            Err(e) => {
                b.error.get_or_insert(e);
            }
        }
        self.batch = b;
    }

    fn on_finish(&mut self) -> pf_core::Result<()> {
        self.batch.error.take().map_or(Ok(()), Err)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SmoothError;
    use crate::ar1::{Ar1Data, Ar1Statistics, Theta};
    use pf_core::filter::{FilterConfig, ParticleFilter};
    use pf_core::mc::stream_rng;

    /// `X_k ~ U(X_{k−1} − 1, X_{k−1} + 1)`: a transition density that is zero off a window.
    struct Window;

    impl pf_core::StateSpaceModel for Window {
        type State = f64;
        type Obs = f64;
        type Input = ();
        fn sample_initial<R: rand::Rng + ?Sized>(&self, _rng: &mut R) -> f64 {
            0.0
        }
        fn sample_transition<R: rand::Rng + ?Sized>(
            &self,
            _t: usize,
            x: &f64,
            _u: Option<&()>,
            _rng: &mut R,
        ) -> f64 {
            *x
        }
        fn log_likelihood(&self, _t: usize, _x: &f64, _y: &f64) -> f64 {
            0.0
        }
    }

    impl TransitionDensity for Window {
        fn log_transition_density(&self, _t: usize, p: &f64, x: &f64, _u: Option<&()>) -> f64 {
            if (x - p).abs() < 1.0 {
                -(2f64.ln())
            } else {
                f64::NEG_INFINITY
            }
        }
    }

    /// `s(x) = x` at step 0, `s(x_{k−1}, x_k) = x_k` after: the sum of the path.
    struct PathSum;

    impl AdditiveFunctional<f64> for PathSum {
        fn dim(&self) -> usize {
            1
        }
        fn initial(&self, x0: &f64, out: &mut [f64]) {
            out[0] += x0;
        }
        fn increment(&self, _k: usize, _p: &f64, x: &f64, out: &mut [f64]) {
            out[0] += x;
        }
    }

    fn step(fs: &mut ForwardSmoothing<Window, PathSum>, t: usize, x: &[f64], w: &[f64]) {
        let log_w: Vec<f64> = w.iter().map(|w| w.ln()).collect();
        let report = pf_core::filter::StepReport {
            t,
            log_lik_increment: 0.0,
            log_lik: 0.0,
            ess: 1.0,
            resampled: false,
        };
        let a: Vec<usize> = (0..x.len()).collect();
        Observer::on_step(
            fs,
            &StepView {
                report,
                particles: x,
                log_weights: &log_w,
                weights: w,
                ancestors: &a,
            },
        );
    }

    /// A particle no earlier particle can reach has no backward weight: while it carries
    /// weight the estimate is an error, never NaN; once no later particle descends from it,
    /// the estimate is a number again, the backward paths' sums exactly.
    #[test]
    fn a_particle_without_backward_weight_is_an_error_not_a_nan() {
        let mut fs = ForwardSmoothing::new(Window, PathSum);
        step(&mut fs, 0, &[0.0, 10.0], &[0.5, 0.5]);
        assert_eq!(fs.estimate().unwrap(), [5.0]);
        // 0.5 is reachable from 0 only; 100 from neither.
        step(&mut fs, 1, &[0.5, 100.0], &[0.5, 0.5]);
        assert_eq!(fs.t_stat()[0], 0.5);
        assert!(fs.t_stat()[1].is_nan());
        assert!(matches!(
            fs.estimate(),
            Err(SmoothError::NonFiniteEstimate {
                t: 1,
                component: 0,
                ..
            })
        ));
        // Both reachable from 0.5 only: T = 0.5 + x, the NaN row left behind.
        step(&mut fs, 2, &[1.0, 0.0], &[0.25, 0.75]);
        assert_eq!(fs.t_stat(), [1.5, 0.5]);
        assert_eq!(fs.estimate().unwrap(), [0.25 * 1.5 + 0.75 * 0.5]);
    }

    #[test]
    fn no_estimate_before_the_first_step() {
        let data = Ar1Data::new(vec![0.1, 0.2, 0.3]).unwrap();
        let model = Theta::paper_start().model(0.1).unwrap();
        let fs = ForwardSmoothing::new(model, Ar1Statistics::new(&data));
        assert!(matches!(fs.estimate(), Err(SmoothError::NoSteps { .. })));
        let mut short = [0.0; 3];
        assert!(fs.estimate_into(&mut short).is_err());
    }

    /// The rows are computed alike on one thread and on the pool: the same bits.
    #[test]
    fn the_pool_gives_the_same_estimate_to_the_last_bit() {
        let truth = pf_core::models::NoisyAr1::new(0.98, 0.2, 1.0).unwrap();
        let data = Ar1Data::new(truth.simulate(40, &mut stream_rng(4, 0)).1).unwrap();
        let theta = Theta::paper_start();
        let run = |par: Par| {
            let model = theta.model(data.y()[0]).unwrap();
            let mut fs = ForwardSmoothing::new(model, Ar1Statistics::new(&data)).with_par(par);
            let mut pf = ParticleFilter::bootstrap(model, FilterConfig::new(300)).unwrap();
            pf.run(&data.filter_input(), None, &mut stream_rng(5, 0), &mut fs)
                .unwrap();
            fs.estimate().unwrap()
        };
        let (seq, pool) = (run(Par::Seq), run(Par::Rayon));
        assert_eq!(
            seq.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            pool.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
    }
}
