//! How the batch filter moves and weighs a chunk: the bootstrap (the model's own
//! transition) or a guided proposal.

use super::model::{BatchModel, BatchProposal, BatchTransitionDensity, Cols, ColsMut};
use crate::filter::{Bootstrap, Guided};

/// The mutation of a [`BatchFilter`](super::BatchFilter): draw `X_t` for a chunk and add
/// its incremental log-weights. Implemented by [`Bootstrap`] (`w̃ = g_t(y_t | x_t)`) and by
/// [`Guided`] over a [`BatchProposal`] (`w̃ = g f / q`), as the generic filter's mutations.
pub trait BatchMutation<M: BatchModel>: Send + Sync {
    /// Standard normals each particle draws per step.
    fn noise_dim(&self, model: &M) -> usize;

    /// New states `x` from `parents` and normals `z`; `lw[i] += log w̃_t^i`. `scratch`
    /// holds at least one value per particle of the chunk.
    #[allow(clippy::too_many_arguments)]
    fn mutate(
        &self,
        model: &M,
        t: usize,
        u: &M::Input,
        y: Option<&M::Obs>,
        parents: Cols<'_>,
        z: Cols<'_>,
        x: ColsMut<'_>,
        lw: &mut [f64],
        scratch: &mut [f64],
    );
}

impl<M: BatchModel> BatchMutation<M> for Bootstrap {
    #[inline(always)]
    fn noise_dim(&self, model: &M) -> usize {
        model.noise_dim()
    }

    #[inline(always)]
    fn mutate(
        &self,
        model: &M,
        t: usize,
        u: &M::Input,
        y: Option<&M::Obs>,
        parents: Cols<'_>,
        z: Cols<'_>,
        x: ColsMut<'_>,
        lw: &mut [f64],
        _scratch: &mut [f64],
    ) {
        model.propagate_weighed(t, u, y, parents, z, x, lw);
    }
}

/// `log w̃ = log g_t(y_t | x_t) + log f_t(x_t | x_{t−1}) − log q_t(x_t | x_{t−1}, y_t)`,
/// without `g` when `y_t` is missing.
impl<M: BatchTransitionDensity, Q: BatchProposal<M>> BatchMutation<M> for Guided<Q> {
    #[inline(always)]
    fn noise_dim(&self, model: &M) -> usize {
        self.0.noise_dim(model)
    }

    #[inline(always)]
    fn mutate(
        &self,
        model: &M,
        t: usize,
        u: &M::Input,
        y: Option<&M::Obs>,
        parents: Cols<'_>,
        z: Cols<'_>,
        mut x: ColsMut<'_>,
        lw: &mut [f64],
        scratch: &mut [f64],
    ) {
        let log_q = &mut scratch[..lw.len()];
        self.0
            .propose(model, t, u, y, parents, z, x.reborrow(), log_q);
        for (l, &q) in lw.iter_mut().zip(log_q.iter()) {
            *l -= q;
        }
        model.add_log_transition(t, u, parents, x.as_cols(), lw);
        if let Some(y) = y {
            model.add_log_likelihood(t, y, x.as_cols(), lw);
        }
    }
}
