//! The sequential importance sampling–resampling (SIR) filter.
//!
//! One step, at time `k ≥ 1`:
//! 1. if the [`ResamplePolicy`] says so, judged on the weights `W_{k−1}`, draw ancestors
//!    `A_k` with the [`Resample`](crate::resample::Resample) scheme (else `A_k^i = i`);
//! 2. mutate: `ξ_k^i` from `ξ_{k−1}^{A_k^i}` with the [`Mutation`] (bootstrap or guided);
//! 3. reweight: `log w_k^i = log W̄_{k−1}^i + log w̃_k^i`, where `W̄` is uniform after
//!    resampling;
//! 4. normalise by log-sum-exp; the log normalising constant is `log ĉ_k`.
//!
//! At `k = 0` the particles are drawn from `μ` and weighted by `g_0(y_0|ξ_0)`.
//! The log-likelihood estimate is `Σ_k log ĉ_k` (Cappé & Moulines, eq. (3)); with adaptive
//! resampling `ĉ_k = Σ_i W̄_{k−1}^i w̃_k^i` keeps it unbiased on the natural scale.

pub mod batch;
mod mutation;
mod policy;
mod report;
mod sir;

pub use crate::model::StepAt;
pub use batch::{
    BatchBootstrap, BatchConfig, BatchFilter, BatchModel, BatchMutation, BatchObserver,
    BatchProposal, BatchTransitionDensity, BatchView, Cols, ColsMut, MomentRecorder, ScalarModel,
    default_chunk,
};
pub use mutation::{Bootstrap, Guided, Mutation};
pub use policy::{EssThreshold, ResamplePolicy};
pub use report::{RunSummary, StepReport};
pub use sir::{FilterConfig, ParticleFilter};
