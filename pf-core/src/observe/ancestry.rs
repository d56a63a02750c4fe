//! Records the pruned path storage of a run into an [`AncestryTree`].

use super::{Observer, StepView};
use crate::ancestry::AncestryTree;

/// Builds the [`AncestryTree`] of a run: the trajectories of the living particles in
/// memory that stays far below `N·n` (see [`crate::ancestry`]).
#[derive(Debug, Clone)]
pub struct AncestryRecorder<S> {
    tree: Option<AncestryTree<S>>,
}

impl<S> Default for AncestryRecorder<S> {
    fn default() -> Self {
        AncestryRecorder { tree: None }
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
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        // The filter's particles and ancestors always have length N and valid indices.
        match &mut self.tree {
            None => self.tree = AncestryTree::new(view.particles).ok(),
            Some(t) => {
                let _ = t.push(view.ancestors, view.particles);
            }
        }
    }
}
