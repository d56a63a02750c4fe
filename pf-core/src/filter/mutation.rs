//! How particles move and are reweighted: the Feynman–Kac view of a model.
//!
//! The filter sees only a [`Mutation`]: draw `ξ_k` from `ξ_{k−1}` and return the incremental
//! log-weight. [`Bootstrap`] moves with the model's own transition and weighs by the
//! likelihood; [`Guided`] moves with a proposal and corrects by `g·f/q`.

use crate::model::{Proposal, StateSpaceModel, StepAt, TransitionDensity};
use rand::Rng;

/// Move one particle and return its incremental log-weight.
pub trait Mutation<M: StateSpaceModel>: Sync {
    /// Draw `ξ_t` given `ξ_{t−1} = x_prev` into `x` and return `log w̃_t`.
    ///
    /// `x` holds an earlier state (its value is to be overwritten, not read): writing into it
    /// lets a state that owns heap memory reuse it, so a step need not allocate per particle.
    fn mutate<R: Rng + ?Sized>(
        &self,
        model: &M,
        at: StepAt<'_, M>,
        x_prev: &M::State,
        x: &mut M::State,
        rng: &mut R,
    ) -> f64;

    /// Whether a step with no observation still changes the weights (a guided proposal's
    /// `f/q` does; the bootstrap filter's does not, so its weights are carried exactly).
    fn reweights_without_observation(&self) -> bool {
        true
    }

    /// Weight of an initial particle `ξ_0 ~ μ` given `y_0`.
    fn initial_log_weight(&self, model: &M, x0: &M::State, y0: Option<&M::Obs>) -> f64 {
        y0.map_or(0.0, |y| model.log_likelihood(0, x0, y))
    }
}

/// The bootstrap filter: `q = f`, so the incremental weight is `g_t(y_t | ξ_t)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Bootstrap;

impl<M: StateSpaceModel> Mutation<M> for Bootstrap {
    fn reweights_without_observation(&self) -> bool {
        false
    }

    #[inline]
    fn mutate<R: Rng + ?Sized>(
        &self,
        model: &M,
        at: StepAt<'_, M>,
        x_prev: &M::State,
        x: &mut M::State,
        rng: &mut R,
    ) -> f64 {
        model.sample_transition_into(at.t, x_prev, at.u, x, rng);
        at.y.map_or(0.0, |y| model.log_likelihood(at.t, x, y))
    }
}

/// A guided filter: `ξ_t ~ q_t`, weight `g_t(y_t|ξ_t) f_t(ξ_t|ξ_{t−1}) / q_t(ξ_t|ξ_{t−1}, y_t)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Guided<P>(pub P);

impl<M: TransitionDensity, P: Proposal<M>> Mutation<M> for Guided<P> {
    fn mutate<R: Rng + ?Sized>(
        &self,
        model: &M,
        at: StepAt<'_, M>,
        x_prev: &M::State,
        x: &mut M::State,
        rng: &mut R,
    ) -> f64 {
        let log_q = self.0.sample(model, at, x_prev, x, rng);
        let log_g = at.y.map_or(0.0, |y| model.log_likelihood(at.t, x, y));
        let log_f = model.log_transition_density(at.t, x_prev, x, at.u);
        log_g + log_f - log_q
    }
}
