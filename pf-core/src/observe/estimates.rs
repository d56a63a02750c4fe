//! Filter estimates: weighted mean and covariance at each step.

use super::{Observer, StepView};
use crate::model::EuclideanState;
use crate::particles::{weighted_covariance, weighted_mean};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Records `E[X_k | y_{0:k}]` and `Cov[X_k | y_{0:k}]` as estimated by the particles.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EstimateRecorder {
    /// Time index of each estimate.
    pub t: Vec<usize>,
    /// Weighted means.
    pub means: Vec<DVector<f64>>,
    /// Weighted covariances.
    pub covariances: Vec<DMatrix<f64>>,
}

impl EstimateRecorder {
    /// An empty recorder.
    pub fn new() -> Self {
        Self::default()
    }
}

impl<S: EuclideanState> Observer<S> for EstimateRecorder {
    fn on_start(&mut self, _n: usize) {
        *self = Self::default();
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        // A step view always holds a non-empty set with matching weights, so these succeed.
        if let (Ok(m), Ok(c)) = (
            weighted_mean(view.particles, view.weights),
            weighted_covariance(view.particles, view.weights),
        ) {
            self.t.push(view.report.t);
            self.means.push(m);
            self.covariances.push(c);
        }
    }
}
