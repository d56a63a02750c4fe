//! Observers: what an analysis records from each step, with no I/O in the engine.
//!
//! An [`Observer`] is passed as `&mut`, so the caller keeps it and reads what it recorded
//! afterwards. Observers compose as tuples, and [`Every`] decimates them. A recorder that
//! cannot record a step keeps the first such error and returns it from
//! [`on_finish`](Observer::on_finish), which [`ParticleFilter::run`] passes on.
//!
//! [`ParticleFilter::run`]: crate::filter::ParticleFilter::run

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

use crate::error::Result;
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
    /// After the last step: the first error met while recording, if any (a recorder does
    /// not stop the run; it reports here, and [`ParticleFilter::run`] returns the error).
    ///
    /// [`ParticleFilter::run`]: crate::filter::ParticleFilter::run
    ///
    /// # Errors
    /// What the observer could not record, with the step at which it happened.
    fn on_finish(&mut self) -> Result<()> {
        Ok(())
    }
}

impl<S> Observer<S> for () {}

impl<S, O: Observer<S> + ?Sized> Observer<S> for &mut O {
    fn on_start(&mut self, n: usize) {
        (**self).on_start(n)
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        (**self).on_step(view)
    }
    fn on_finish(&mut self) -> Result<()> {
        (**self).on_finish()
    }
}

/// An observer that may be absent: `None` records nothing, so optional analyses can share
/// one run (`fixed_lag.as_mut()` in a tuple).
impl<S, O: Observer<S>> Observer<S> for Option<O> {
    fn on_start(&mut self, n: usize) {
        if let Some(o) = self {
            o.on_start(n)
        }
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        if let Some(o) = self {
            o.on_step(view)
        }
    }
    fn on_finish(&mut self) -> Result<()> {
        match self {
            Some(o) => o.on_finish(),
            None => Ok(()),
        }
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
            /// Finishes every member, then returns the first member's error.
            fn on_finish(&mut self) -> Result<()> {
                let mut first = Ok(());
                $(
                    let r = self.$idx.on_finish();
                    if first.is_ok() {
                        first = r;
                    }
                )+
                first
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
    fn on_finish(&mut self) -> Result<()> {
        self.inner.on_finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts what it is told.
    #[derive(Default)]
    struct Count {
        starts: usize,
        steps: Vec<usize>,
        finishes: usize,
    }

    impl Observer<f64> for Count {
        fn on_start(&mut self, _n: usize) {
            self.starts += 1;
        }
        fn on_step(&mut self, view: &StepView<'_, f64>) {
            self.steps.push(view.report.t);
        }
        fn on_finish(&mut self) -> Result<()> {
            self.finishes += 1;
            Ok(())
        }
    }

    fn feed(o: &mut impl Observer<f64>, steps: usize) {
        feed_with(o, 1, steps, &[0.0], &[0]).unwrap();
    }

    /// `steps` steps of one particle set `x` with ancestors `a`, announced as `n` particles.
    fn feed_with(
        o: &mut impl Observer<f64>,
        n: usize,
        steps: usize,
        x: &[f64],
        a: &[usize],
    ) -> Result<()> {
        let w = vec![1.0 / x.len().max(1) as f64; x.len()];
        let lw: Vec<f64> = w.iter().map(|w| w.ln()).collect();
        o.on_start(n);
        for t in 0..steps {
            let report = StepReport {
                t,
                log_lik_increment: 0.0,
                log_lik: 0.0,
                ess: 1.0,
                resampled: false,
            };
            o.on_step(&StepView {
                report,
                particles: x,
                log_weights: &lw,
                weights: &w,
                ancestors: a,
            });
        }
        o.on_finish()
    }

    /// A recorder that cannot record a step says so when the run finishes, with the step,
    /// and a tuple passes the first error on after finishing every member.
    #[test]
    fn recorder_errors_reach_the_caller() {
        use crate::error::CoreError;
        // Ancestors of 2 particles where the genealogy was started with 3.
        let mut g = GenealogyRecorder::new();
        let e = feed_with(&mut g, 3, 2, &[0.0, 1.0], &[0, 1]).unwrap_err();
        assert!(matches!(e, CoreError::AtStep { t: 0, .. }), "{e}");
        // The same recorder, restarted with a consistent run, is clean again.
        feed_with(&mut g, 2, 3, &[0.0, 1.0], &[1, 1]).unwrap();
        assert_eq!(g.genealogy().n_steps(), 3);
        // An ancestry tree cannot start from no particles.
        let mut tree = AncestryRecorder::new();
        let e = feed_with(&mut tree, 0, 2, &[], &[]).unwrap_err();
        assert!(matches!(e, CoreError::AtStep { t: 0, .. }), "{e}");
        assert!(tree.tree().is_none());
        // In a tuple, the count still finishes and the error still comes out.
        let mut pair = (Count::default(), GenealogyRecorder::new());
        assert!(feed_with(&mut pair, 3, 2, &[0.0], &[0]).is_err());
        assert_eq!(pair.0.finishes, 1);
    }

    /// `Some` passes every call through, `None` swallows them, and either composes in a
    /// tuple beside an observer that is always there.
    #[test]
    fn optional_observers_pass_through_or_record_nothing() {
        let (mut always, mut maybe) = (Count::default(), Count::default());
        let mut absent: Option<Count> = None;
        feed(&mut (&mut always, Some(&mut maybe), absent.as_mut()), 4);
        for c in [&always, &maybe] {
            assert_eq!(
                (c.starts, c.steps.as_slice(), c.finishes),
                (1, &[0, 1, 2, 3][..], 1)
            );
        }
        feed(&mut absent, 2);
        assert!(absent.is_none());
        let mut every = Every::new(2, Some(Count::default()));
        feed(&mut every, 5);
        let inner = every.inner.expect("still there");
        assert_eq!(inner.steps, [0, 2, 4]);
    }
}
