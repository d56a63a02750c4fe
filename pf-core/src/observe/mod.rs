//! Observers: what an analysis records from each step, with no I/O in the engine.
//!
//! An [`Observer`] is passed as `&mut`, so the caller keeps it and reads what it recorded
//! afterwards. Observers compose as tuples, and [`Every`] decimates them.

mod ancestry;
mod cloud;
mod ess;
mod estimates;
mod genealogy;

pub use ancestry::AncestryRecorder;
pub use cloud::{Cloud, CloudRecorder};
pub use ess::EssRecorder;
pub use estimates::EstimateRecorder;
pub use genealogy::GenealogyRecorder;

use crate::filter::StepReport;

/// Everything about one step, borrowed from the filter.
#[derive(Debug, Clone, Copy)]
pub struct StepView<'a, S> {
    /// The step's report.
    pub report: StepReport,
    /// `ξ_k^i`.
    pub particles: &'a [S],
    /// Normalised `log W_k^i`.
    pub log_weights: &'a [f64],
    /// Normalised `W_k^i`.
    pub weights: &'a [f64],
    /// `A_k^i` (the identity at `k = 0` and on steps without resampling).
    pub ancestors: &'a [usize],
}

/// Receives each step of a run. Every method defaults to doing nothing.
pub trait Observer<S> {
    /// Before the first step.
    fn on_start(&mut self, _n_particles: usize) {}
    /// After every step.
    fn on_step(&mut self, _view: &StepView<'_, S>) {}
    /// After the last step.
    fn on_finish(&mut self) {}
}

impl<S> Observer<S> for () {}

impl<S, O: Observer<S> + ?Sized> Observer<S> for &mut O {
    fn on_start(&mut self, n: usize) {
        (**self).on_start(n)
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        (**self).on_step(view)
    }
    fn on_finish(&mut self) {
        (**self).on_finish()
    }
}

macro_rules! tuple_observer {
    ($($name:ident . $idx:tt),+) => {
        impl<S, $($name: Observer<S>),+> Observer<S> for ($($name,)+) {
            fn on_start(&mut self, n: usize) {
                $(self.$idx.on_start(n);)+
            }
            fn on_step(&mut self, view: &StepView<'_, S>) {
                $(self.$idx.on_step(view);)+
            }
            fn on_finish(&mut self) {
                $(self.$idx.on_finish();)+
            }
        }
    };
}

tuple_observer!(A.0);
tuple_observer!(A.0, B.1);
tuple_observer!(A.0, B.1, C.2);
tuple_observer!(A.0, B.1, C.2, D.3);

/// Passes to the inner observer only the steps with `t % every == 0` (and start/finish).
///
/// Not for [`GenealogyRecorder`], which needs every step's ancestors.
#[derive(Debug, Clone)]
pub struct Every<O> {
    every: usize,
    /// The decimated observer.
    pub inner: O,
}

impl<O> Every<O> {
    /// Every `every`-th step (`0` is treated as 1).
    pub fn new(every: usize, inner: O) -> Self {
        Every {
            every: every.max(1),
            inner,
        }
    }
}

impl<S, O: Observer<S>> Observer<S> for Every<O> {
    fn on_start(&mut self, n: usize) {
        self.inner.on_start(n)
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        if view.report.t.is_multiple_of(self.every) {
            self.inner.on_step(view)
        }
    }
    fn on_finish(&mut self) {
        self.inner.on_finish()
    }
}
