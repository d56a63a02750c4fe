//! What one filter step reports.

use serde::{Deserialize, Serialize};

/// The outcome of one step. Small and `Copy`: the ancestor indices of the step are borrowed
/// from the filter ([`ParticleFilter::ancestors`](super::ParticleFilter::ancestors)) or seen
/// by observers in the [`StepView`](crate::observe::StepView), so nothing is allocated.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StepReport {
    /// Time index `k` of the particles `ξ_k` this step produced.
    pub t: usize,
    /// `log ĉ_k`, the estimate of `log p(y_k | y_{0:k−1})`. When `y_k` is missing it is 0
    /// for the bootstrap filter; a guided one still weighs by `f/q`
    /// (`Mutation::reweights_without_observation`), so its increment is the log of an
    /// unbiased estimate of 1: near 0, not 0.
    pub log_lik_increment: f64,
    /// `Σ_{j≤k} log ĉ_j`: the running log-likelihood estimate (Cappé & Moulines, eq. (3)).
    pub log_lik: f64,
    /// Effective sample size of the new weights.
    pub ess: f64,
    /// Whether the particles were resampled before being propagated in this step.
    pub resampled: bool,
}

/// The result of running a filter over a whole sequence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// The final log-likelihood estimate.
    pub log_lik: f64,
    /// One report per step, in order.
    pub reports: Vec<StepReport>,
}
