//! Records the pruned path storage of a run into an [`AncestryTree`].

use super::{Observer, StepView};
use crate::ancestry::AncestryTree;
use crate::error::{CoreError, Result};

/// Builds the [`AncestryTree`] of a run: the trajectories of the living particles in
/// memory that stays far below `N·n` (see [`crate::ancestry`]). A step it cannot record
/// ends the recording; the error comes out of [`on_finish`](Observer::on_finish).
#[derive(Debug, Clone)]
pub struct AncestryRecorder<S> {
    tree: Option<AncestryTree<S>>,
    error: Option<CoreError>,
}

impl<S> Default for AncestryRecorder<S> {
    fn default() -> Self {
        AncestryRecorder {
            tree: None,
            error: None,
        }
    }
}

impl<S> AncestryRecorder<S> {
    /// An empty recorder.
    pub fn new() -> Self {
        Self::default()
    }

    /// The tree recorded so far (`None` before the first step).
    pub fn tree(&self) -> Option<&AncestryTree<S>> {
        self.tree.as_ref()
    }
}

impl<S: Clone> Observer<S> for AncestryRecorder<S> {
    fn on_start(&mut self, _n: usize) {
        self.tree = None;
        self.error = None;
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        if self.error.is_some() {
            return;
        }
        let recorded = match &mut self.tree {
            None => AncestryTree::new(view.particles).map(|t| self.tree = Some(t)),
            Some(t) => t.push(view.ancestors, view.particles),
        };
        if let Err(e) = recorded {
            self.error = Some(e.at_step(view.report.t));
        }
    }
    fn on_finish(&mut self) -> Result<()> {
        self.error.clone().map_or(Ok(()), Err)
    }
}
