//! The genealogy of a particle system: who descends from whom.
//!
//! Resampling makes particles share ancestors. Followed backwards from the last step, the
//! number of distinct ancestors shrinks until, at the *coalescence time*, all surviving
//! trajectories go through one particle (Cappé & Moulines, Fig. 1). Before that time the
//! path-space estimate of a smoothed functional rests on a single trajectory, which is why
//! its variance grows with `n` and why the fixed-lag estimator exists.

use crate::error::{CoreError, Result};
use crate::filter::{Mutation, ParticleFilter};
use crate::model::StateSpaceModel;
use crate::observe::{CloudRecorder, EssRecorder, GenealogyRecorder};
use crate::params::ParamError;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Ancestor indices of every step: `A_k^i` for `k = 1, …, n`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Genealogy {
    n_particles: usize,
    n_steps: usize,
    /// `parents[k − 1][i] = A_k^i`.
    parents: Vec<Vec<usize>>,
}

impl Genealogy {
    /// An empty genealogy of `n_particles` particles.
    pub fn new(n_particles: usize) -> Self {
        Genealogy {
            n_particles,
            n_steps: 0,
            parents: Vec::new(),
        }
    }

    /// Record the next step, with its ancestors (ignored for the first step, `k = 0`).
    ///
    /// # Errors
    /// Ancestors of the wrong length or out of range.
    pub fn push(&mut self, ancestors: &[usize]) -> Result<()> {
        if ancestors.len() != self.n_particles {
            return Err(CoreError::DimensionMismatch {
                what: "ancestor vector",
                expected: self.n_particles,
                got: ancestors.len(),
            });
        }
        if let Some(bad) = ancestors.iter().position(|&a| a >= self.n_particles) {
            return Err(CoreError::Param(ParamError {
                name: "ancestor index",
                value: bad as f64,
                reason: "ancestor index out of range at this position",
            }));
        }
        if self.n_steps > 0 {
            self.parents.push(ancestors.to_vec());
        }
        self.n_steps += 1;
        Ok(())
    }

    /// Number of recorded steps (steps are `0..n_steps`).
    pub fn n_steps(&self) -> usize {
        self.n_steps
    }

    /// Number of particles `N`.
    pub fn n_particles(&self) -> usize {
        self.n_particles
    }

    /// `A_k`, for `1 ≤ k < n_steps`.
    pub fn ancestors(&self, k: usize) -> Option<&[usize]> {
        k.checked_sub(1)
            .and_then(|j| self.parents.get(j))
            .map(Vec::as_slice)
    }

    /// Indices at steps `0..=k` of the ancestors of particle `i` at step `k`: the trajectory
    /// `ξ_{0:k}^i` is `positions[j][lineage[j]]`.
    ///
    /// # Errors
    /// `k` or `i` out of range.
    pub fn lineage_at(&self, k: usize, i: usize) -> Result<Vec<usize>> {
        if k >= self.n_steps {
            return Err(CoreError::DimensionMismatch {
                what: "step of a lineage (must be < n_steps)",
                expected: self.n_steps,
                got: k,
            });
        }
        if i >= self.n_particles {
            return Err(CoreError::DimensionMismatch {
                what: "particle of a lineage (must be < N)",
                expected: self.n_particles,
                got: i,
            });
        }
        let mut out = vec![0; k + 1];
        let mut idx = i;
        out[k] = idx;
        for j in (1..=k).rev() {
            idx = self.parents[j - 1][idx];
            out[j - 1] = idx;
        }
        Ok(out)
    }

    /// [`lineage_at`](Self::lineage_at) the last step.
    ///
    /// # Errors
    /// An empty genealogy or `i` out of range.
    pub fn lineage(&self, i: usize) -> Result<Vec<usize>> {
        self.lineage_at(self.n_steps.saturating_sub(1), i)
    }

    /// The trajectory `ξ_{0:k}^i` of particle `i` at step `k`, read from recorded positions.
    ///
    /// # Errors
    /// Out-of-range indices or positions that do not cover the steps.
    pub fn trajectory<S: Clone>(&self, k: usize, i: usize, positions: &[Vec<S>]) -> Result<Vec<S>> {
        let lineage = self.lineage_at(k, i)?;
        if positions.len() <= k {
            return Err(CoreError::DimensionMismatch {
                what: "recorded steps of positions",
                expected: k + 1,
                got: positions.len(),
            });
        }
        lineage
            .iter()
            .enumerate()
            .map(|(j, &idx)| {
                positions[j]
                    .get(idx)
                    .cloned()
                    .ok_or(CoreError::DimensionMismatch {
                        what: "particles recorded at a step",
                        expected: self.n_particles,
                        got: positions[j].len(),
                    })
            })
            .collect()
    }

    /// For every step, a flag per particle: does it have a descendant at the last step?
    /// These are the lineages a genealogy plot highlights.
    pub fn alive_per_step(&self) -> Vec<Vec<bool>> {
        let n = self.n_particles;
        let mut alive = vec![vec![false; n]; self.n_steps];
        if let Some(last) = alive.last_mut() {
            last.fill(true);
        }
        for k in (1..self.n_steps).rev() {
            let (before, after) = alive.split_at_mut(k);
            let prev = &mut before[k - 1];
            for (i, &a) in after[0].iter().enumerate() {
                if a {
                    prev[self.parents[k - 1][i]] = true;
                }
            }
        }
        alive
    }

    /// Sorted indices at step `k` that have a descendant at the last step.
    pub fn surviving_at(&self, k: usize) -> Vec<usize> {
        self.alive_per_step()
            .get(k)
            .map(|a| (0..a.len()).filter(|&i| a[i]).collect())
            .unwrap_or_default()
    }

    /// Number of distinct surviving ancestors at each step.
    pub fn surviving_counts(&self) -> Vec<usize> {
        self.alive_per_step()
            .iter()
            .map(|a| a.iter().filter(|&&b| b).count())
            .collect()
    }

    /// The coalescence time: the most recent step at which all surviving trajectories share
    /// one ancestor. `None` if they never coalesce within the recorded steps.
    pub fn coalescence_time(&self) -> Option<usize> {
        self.surviving_counts().iter().rposition(|&c| c == 1)
    }
}

/// A scalar filter run's particles and genealogy as plain numbers, what a genealogy figure
/// draws (Cappé & Moulines, Fig. 1): index `k` is the step, `i` the particle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GenealogyData {
    /// `positions[k][i] = ξ_k^i`, for `k = 0 … n` (every row of the same length `N`).
    pub positions: Vec<Vec<f64>>,
    /// `ancestors[k][i] = A_k^i`, the index at step `k − 1` of the parent of particle `i` at
    /// step `k`. `ancestors[0]` is empty (step 0 has no parents).
    pub ancestors: Vec<Vec<usize>>,
    /// `surviving[k][i]`: particle `i` at step `k` has a descendant at the last step.
    pub surviving: Vec<Vec<bool>>,
    /// The most recent step at which all surviving lineages share one ancestor, if any.
    pub coalescence_time: Option<usize>,
    /// The true hidden state `x_k`, where it is known (simulated data).
    pub truth: Option<Vec<f64>>,
}

impl GenealogyData {
    /// From a run's recorders: the clouds' positions and the genealogy's parents, survivors
    /// and coalescence time.
    pub fn recorded(clouds: &CloudRecorder<f64>, g: &Genealogy, truth: Option<Vec<f64>>) -> Self {
        GenealogyData {
            positions: clouds.positions(),
            ancestors: (0..g.n_steps())
                .map(|k| g.ancestors(k).map(<[usize]>::to_vec).unwrap_or_default())
                .collect(),
            surviving: g.alive_per_step(),
            coalescence_time: g.coalescence_time(),
            truth,
        }
    }

    /// Number of steps `n + 1`.
    pub fn n_steps(&self) -> usize {
        self.positions.len()
    }

    /// Number of particles `N`.
    pub fn n_particles(&self) -> usize {
        self.positions.first().map_or(0, Vec::len)
    }
}

/// A scalar filter's run with everything a genealogy figure and its recording show: the
/// paths, the engine's genealogy, and each step's weights, ESS and resampling decision.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedRun {
    /// Positions, ancestors, survivors, coalescence time and (when known) the true states.
    pub paths: GenealogyData,
    /// The engine's genealogy.
    pub lineage: Genealogy,
    /// `weights[k][i] = W_k^i`, normalised.
    pub weights: Vec<Vec<f64>>,
    /// The effective sample size of every step, after reweighting.
    pub ess: Vec<f64>,
    /// Whether each step resampled.
    pub resampled: Vec<bool>,
    /// The filter's log-likelihood estimate `log p̂(y_{0:n})`.
    pub log_lik: f64,
}

impl RecordedRun {
    /// Run `pf` over `ys` (no inputs) with its clouds, genealogy and ESS recorded; `truth`
    /// is the hidden state path where it is known.
    ///
    /// # Errors
    /// The filter's errors ([`ParticleFilter::run`]) and a recorder's.
    pub fn of<M, P, R>(
        pf: &mut ParticleFilter<M, P>,
        ys: &[Option<M::Obs>],
        rng: &mut R,
        truth: Option<Vec<f64>>,
    ) -> Result<Self>
    where
        M: StateSpaceModel<State = f64>,
        P: Mutation<M>,
        R: Rng + ?Sized,
    {
        let mut observers = (
            CloudRecorder::new(),
            GenealogyRecorder::new(),
            EssRecorder::new(),
        );
        let summary = pf.run(ys, None, rng, &mut observers)?;
        let (clouds, genealogy, ess) = observers;
        let lineage = genealogy.into_genealogy();
        Ok(RecordedRun {
            paths: GenealogyData::recorded(&clouds, &lineage, truth),
            weights: clouds.clouds.into_iter().map(|c| c.weights).collect(),
            ess: ess.ess(),
            resampled: ess.resampled(),
            log_lik: summary.log_lik,
            lineage,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three particles over four steps, drawn by hand:
    /// step 1 parents [0, 0, 1]; step 2 parents [1, 1, 2]; step 3 parents [0, 1, 1].
    fn example() -> Genealogy {
        let mut g = Genealogy::new(3);
        g.push(&[0, 1, 2]).unwrap();
        g.push(&[0, 0, 1]).unwrap();
        g.push(&[1, 1, 2]).unwrap();
        g.push(&[0, 1, 1]).unwrap();
        g
    }

    #[test]
    fn lineages_trace_parents_back() {
        let g = example();
        assert_eq!(g.n_steps(), 4);
        // Particle 2 at step 3 ← 1 at step 2 ← 1 at step 1 ← 0 at step 0.
        assert_eq!(g.lineage(2).unwrap(), vec![0, 1, 1, 2]);
        // Particle 0 at step 3 ← 0 at step 2 ← 1 at step 1 ← 0 at step 0.
        assert_eq!(g.lineage(0).unwrap(), vec![0, 1, 0, 0]);
        let pos = vec![
            vec![10, 11, 12],
            vec![20, 21, 22],
            vec![30, 31, 32],
            vec![40, 41, 42],
        ];
        assert_eq!(g.trajectory(3, 2, &pos).unwrap(), vec![10, 21, 31, 42]);
        assert!(g.lineage(3).is_err());
    }

    #[test]
    fn surviving_lineages_and_coalescence() {
        let g = example();
        assert_eq!(g.surviving_at(3), vec![0, 1, 2]);
        assert_eq!(g.surviving_at(2), vec![0, 1]);
        assert_eq!(g.surviving_at(1), vec![1]);
        assert_eq!(g.surviving_at(0), vec![0]);
        assert_eq!(g.surviving_counts(), vec![1, 1, 2, 3]);
        // Step 1 is the most recent step with a single surviving ancestor.
        assert_eq!(g.coalescence_time(), Some(1));
        let mut no = Genealogy::new(2);
        no.push(&[0, 1]).unwrap();
        no.push(&[0, 1]).unwrap();
        assert_eq!(no.coalescence_time(), None);
    }

    #[test]
    fn bad_ancestors_are_rejected() {
        let mut g = Genealogy::new(2);
        assert!(g.push(&[0]).is_err());
        assert!(g.push(&[0, 2]).is_err());
    }
}
