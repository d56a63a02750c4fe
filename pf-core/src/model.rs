//! State-space models (hidden Markov models) and the capabilities some algorithms need.
//!
//! The model is kept apart from how a filter moves particles: a [`StateSpaceModel`] only says
//! how to sample `X_0`, how to sample `X_t | X_{t−1}` and how likely `Y_t` is given `X_t`.
//! Optional capabilities ([`TransitionDensity`], [`Proposal`]) are separate traits, bound only
//! by the algorithms that use them.
//!
//! Time convention: `t` is the index of the state being produced, so `sample_transition(t, …)`
//! draws `X_t` given `X_{t−1}`, and `log_likelihood(t, x, y)` is `log g(y_t | x_t)`.

use rand::Rng;

/// A state-space model `X_0 ~ μ`, `X_t | X_{t−1} ~ f_t(· | X_{t−1}, u_t)`,
/// `Y_t | X_t ~ g_t(· | X_t)`.
///
/// Every stochastic method takes the RNG as an argument; models never store one.
pub trait StateSpaceModel: Sync {
    /// Hidden state `X_t`.
    type State: Clone + Send + Sync;
    /// Observation `Y_t`.
    type Obs: Sync;
    /// Exogenous input `u_t`; use `()` for models without one.
    type Input: Sync;

    /// Draw `X_0 ~ μ`.
    fn sample_initial<R: Rng + ?Sized>(&self, rng: &mut R) -> Self::State;

    /// Draw `X_t ~ f_t(· | x_prev, u)`; `u` is `None` when no input is given at step `t`.
    fn sample_transition<R: Rng + ?Sized>(
        &self,
        t: usize,
        x_prev: &Self::State,
        u: Option<&Self::Input>,
        rng: &mut R,
    ) -> Self::State;

    /// Draw `X_t ~ f_t(· | x_prev, u)` into `x`, whose earlier value is overwritten.
    ///
    /// The filters call this one. Override it when the state owns heap memory (a
    /// `DVector`, a `Vec`), so that a step reuses each particle's storage instead of
    /// allocating; the default assigns [`sample_transition`](Self::sample_transition)'s
    /// result.
    fn sample_transition_into<R: Rng + ?Sized>(
        &self,
        t: usize,
        x_prev: &Self::State,
        u: Option<&Self::Input>,
        x: &mut Self::State,
        rng: &mut R,
    ) {
        *x = self.sample_transition(t, x_prev, u, rng);
    }

    /// `log g_t(y | x)`. May return `−∞`; must not return NaN for valid `x`.
    fn log_likelihood(&self, t: usize, x: &Self::State, y: &Self::Obs) -> f64;
}

/// The transition density `log f_t(x | x_prev, u)`, for guided filters and smoothers.
pub trait TransitionDensity: StateSpaceModel {
    /// `log f_t(x | x_prev, u)`.
    fn log_transition_density(
        &self,
        t: usize,
        x_prev: &Self::State,
        x: &Self::State,
        u: Option<&Self::Input>,
    ) -> f64;
}

/// An importance (proposal) density `q_t(x | x_prev, y_t)` for transitions `t ≥ 1`.
///
/// A guided filter samples from it and corrects with `g·f/q`; see
/// [`Guided`](crate::filter::Guided). The initial state is always drawn from `μ`.
pub trait Proposal<M: StateSpaceModel>: Sync {
    /// Draw `X_t ~ q_t(· | x_prev, y_t)` into `x` and return `log q_t(x | x_prev, y_t)`.
    ///
    /// The density comes back with the draw because the two usually share their work (a
    /// linearisation, a gain); it must equal [`log_density`](Self::log_density) at the draw.
    /// `x` holds an earlier state, to be overwritten, so that heap storage can be reused.
    fn sample<R: Rng + ?Sized>(
        &self,
        model: &M,
        at: StepAt<'_, M>,
        x_prev: &M::State,
        x: &mut M::State,
        rng: &mut R,
    ) -> f64;

    /// `log q_t(x | x_prev, y_t)`.
    fn log_density(&self, model: &M, at: StepAt<'_, M>, x_prev: &M::State, x: &M::State) -> f64;
}

/// Where a particle moves: the index `t` of the state being drawn, the input `u_t` and the
/// observation `y_t` (`None` when missing), the same for every particle of a step.
#[derive(Debug)]
pub struct StepAt<'a, M: StateSpaceModel> {
    /// Index of the state being drawn.
    pub t: usize,
    /// The input `u_t`.
    pub u: Option<&'a M::Input>,
    /// The observation `y_t`.
    pub y: Option<&'a M::Obs>,
}

// By hand: a derive would ask `M: Copy`, and the fields are references and an index.
impl<M: StateSpaceModel> Clone for StepAt<'_, M> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<M: StateSpaceModel> Copy for StepAt<'_, M> {}

/// A model whose state is a point in ℝ^d, so weighted means and covariances make sense.
pub trait EuclideanState {
    /// The coordinates of the state.
    fn coords(&self) -> &[f64];
}

impl EuclideanState for f64 {
    fn coords(&self) -> &[f64] {
        std::slice::from_ref(self)
    }
}

impl<const D: usize> EuclideanState for [f64; D] {
    fn coords(&self) -> &[f64] {
        self
    }
}

impl EuclideanState for Vec<f64> {
    fn coords(&self) -> &[f64] {
        self
    }
}

impl<const D: usize> EuclideanState for nalgebra::SVector<f64, D> {
    fn coords(&self) -> &[f64] {
        self.as_slice()
    }
}

impl EuclideanState for nalgebra::DVector<f64> {
    fn coords(&self) -> &[f64] {
        self.as_slice()
    }
}
