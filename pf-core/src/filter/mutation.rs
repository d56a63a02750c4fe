//! How particles move and are reweighted: the Feynman–Kac view of a model.
//!
//! The filter sees only a [`Mutation`]: draw `ξ_k` from `ξ_{k−1}` and return the incremental
//! log-weight. [`Bootstrap`] moves with the model's own transition and weighs by the
//! likelihood; [`Guided`] moves with a proposal and corrects by `g·f/q`.

use crate::model::{Proposal, StateSpaceModel, TransitionDensity};
use rand::Rng;

/// Move one particle and return its incremental log-weight.
pub trait Mutation<M: StateSpaceModel>: Sync {
    /// Draw `ξ_t` given `ξ_{t−1} = x_prev` and return `(ξ_t, log w̃_t)`.
    fn mutate<R: Rng + ?Sized>(
        &self,
        model: &M,
        t: usize,
        x_prev: &M::State,
        u: Option<&M::Input>,
        y: Option<&M::Obs>,
        rng: &mut R,
    ) -> (M::State, f64);

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
        t: usize,
        x_prev: &M::State,
        u: Option<&M::Input>,
        y: Option<&M::Obs>,
        rng: &mut R,
    ) -> (M::State, f64) {
        let x = model.sample_transition(t, x_prev, u, rng);
        let lw = y.map_or(0.0, |y| model.log_likelihood(t, &x, y));
        (x, lw)
    }
}

/// A guided filter: `ξ_t ~ q_t`, weight `g_t(y_t|ξ_t) f_t(ξ_t|ξ_{t−1}) / q_t(ξ_t|ξ_{t−1}, y_t)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Guided<P>(pub P);

impl<M: TransitionDensity, P: Proposal<M>> Mutation<M> for Guided<P> {
    fn mutate<R: Rng + ?Sized>(
        &self,
        model: &M,
        t: usize,
        x_prev: &M::State,
        u: Option<&M::Input>,
        y: Option<&M::Obs>,
        rng: &mut R,
    ) -> (M::State, f64) {
        let x = self.0.sample(model, t, x_prev, u, y, rng);
        let log_g = y.map_or(0.0, |y| model.log_likelihood(t, &x, y));
        let log_f = model.log_transition_density(t, x_prev, &x, u);
        let log_q = self.0.log_density(model, t, x_prev, &x, u, y);
        (x, log_g + log_f - log_q)
    }
}
