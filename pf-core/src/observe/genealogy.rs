//! Records ancestor indices into a [`Genealogy`].

use super::{Observer, StepView};
use crate::error::{CoreError, Result};
use crate::genealogy::Genealogy;

/// Builds the [`Genealogy`] of a run. A step it cannot record (ancestors that do not fit the
/// particle count it was started with) ends the recording; the error comes out of
/// [`on_finish`](Observer::on_finish).
#[derive(Debug, Clone, Default)]
pub struct GenealogyRecorder {
    genealogy: Genealogy,
    error: Option<CoreError>,
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
        self.error = None;
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        if self.error.is_none()
            && let Err(e) = self.genealogy.push(view.ancestors)
        {
            self.error = Some(e.at_step(view.report.t));
        }
    }
    fn on_finish(&mut self) -> Result<()> {
        self.error.clone().map_or(Ok(()), Err)
    }
}
