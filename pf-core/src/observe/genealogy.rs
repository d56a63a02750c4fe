//! Records ancestor indices into a [`Genealogy`].

use super::{Observer, StepView};
use crate::genealogy::Genealogy;

/// Builds the [`Genealogy`] of a run.
#[derive(Debug, Clone, Default)]
pub struct GenealogyRecorder {
    genealogy: Genealogy,
}

impl GenealogyRecorder {
    /// An empty recorder.
    pub fn new() -> Self {
        Self::default()
    }

    /// The genealogy recorded so far.
    pub fn genealogy(&self) -> &Genealogy {
        &self.genealogy
    }

    /// Take the recorded genealogy.
    pub fn into_genealogy(self) -> Genealogy {
        self.genealogy
    }
}

impl<S> Observer<S> for GenealogyRecorder {
    fn on_start(&mut self, n: usize) {
        self.genealogy = Genealogy::new(n);
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        // The filter's ancestors always have length N and valid indices.
        let _ = self.genealogy.push(view.ancestors);
    }
}
