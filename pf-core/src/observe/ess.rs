//! The step reports of a run: ESS, resampling flags, log-likelihood increments.

use super::{Observer, StepView};
use crate::filter::StepReport;
use serde::{Deserialize, Serialize};

/// Records every [`StepReport`].
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EssRecorder {
    /// One report per step.
    pub reports: Vec<StepReport>,
}

impl EssRecorder {
    /// An empty recorder.
    pub fn new() -> Self {
        Self::default()
    }

    /// The ESS of each step.
    pub fn ess(&self) -> Vec<f64> {
        self.reports.iter().map(|r| r.ess).collect()
    }

    /// Whether each step resampled.
    pub fn resampled(&self) -> Vec<bool> {
        self.reports.iter().map(|r| r.resampled).collect()
    }
}

impl<S> Observer<S> for EssRecorder {
    fn on_start(&mut self, _n: usize) {
        self.reports.clear();
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        self.reports.push(view.report);
    }
}
