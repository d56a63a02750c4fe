//! Particle clouds: positions and weights at each step.

use super::{Observer, StepView};
use serde::{Deserialize, Serialize};

/// The weighted particle set of one step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cloud<S> {
    /// Time index.
    pub t: usize,
    /// `ξ_t^i`.
    pub particles: Vec<S>,
    /// Normalised `W_t^i`.
    pub weights: Vec<f64>,
}

/// Records every step's cloud (O(N·n) memory: decimate with [`Every`](super::Every) for long runs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CloudRecorder<S> {
    /// One cloud per recorded step.
    pub clouds: Vec<Cloud<S>>,
}

impl<S> Default for CloudRecorder<S> {
    fn default() -> Self {
        CloudRecorder { clouds: Vec::new() }
    }
}

impl<S> CloudRecorder<S> {
    /// An empty recorder.
    pub fn new() -> Self {
        Self::default()
    }

    /// The positions of each recorded step, as
    /// [`Genealogy::trajectory`](crate::genealogy::Genealogy::trajectory) wants them.
    pub fn positions(&self) -> Vec<Vec<S>>
    where
        S: Clone,
    {
        self.clouds.iter().map(|c| c.particles.clone()).collect()
    }
}

impl<S: Clone> Observer<S> for CloudRecorder<S> {
    fn on_start(&mut self, _n: usize) {
        self.clouds.clear();
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        self.clouds.push(Cloud {
            t: view.report.t,
            particles: view.particles.to_vec(),
            weights: view.weights.to_vec(),
        });
    }
}
