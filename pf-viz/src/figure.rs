//! Plain data that figures and recordings are drawn from.
//!
//! `png/` and `rrd/` draw these types and `report/` fills them, so neither drawing back-end
//! imports the report or the other back-end: every module that draws depends on this one
//! only.

use pf_core::genealogy::Genealogy;
use pf_core::observe::CloudRecorder;
use serde::{Deserialize, Serialize};

use crate::error::{Result, VizError};

/// A table of the report. Cells are preformatted strings; put the paper's value in its own
/// column (e.g. `"N (paper)"`) so ours and theirs sit side by side.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Table {
    /// Short id, unique within the section; the table is also rendered to
    /// `<section>-<id>.png`.
    pub id: String,
    /// What the table shows, with the paper's table number.
    pub caption: String,
    /// Column headings.
    pub header: Vec<String>,
    /// Rows, each as long as `header`.
    pub rows: Vec<Vec<String>>,
}

/// Everything a genealogy figure shows, as plain numbers. Index `k` is the time step,
/// `i` the particle.
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
    /// The true hidden state `x_k`, drawn as a reference when present.
    pub truth: Option<Vec<f64>>,
}

impl GenealogyData {
    /// The figure's data from a filter run's recorders: the clouds' positions and the
    /// genealogy's parents, survivors and coalescence time.
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

    /// Check shapes and indices, so drawing never indexes out of bounds.
    ///
    /// # Errors
    /// [`VizError::PlotData`] naming the first inconsistency.
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| {
            Err(VizError::PlotData {
                what: "genealogy figure",
                message,
            })
        };
        let (steps, n) = (self.n_steps(), self.n_particles());
        if steps == 0 || n == 0 {
            return bad(format!(
                "no particles to draw ({steps} steps of {n} particles)"
            ));
        }
        if self.ancestors.len() != steps || self.surviving.len() != steps {
            return bad(format!(
                "{steps} steps of positions but {} of ancestors and {} of survival flags",
                self.ancestors.len(),
                self.surviving.len()
            ));
        }
        if !self.ancestors[0].is_empty() {
            return bad("ancestors[0] must be empty: step 0 has no parents".into());
        }
        for k in 0..steps {
            if self.positions[k].len() != n || self.surviving[k].len() != n {
                return bad(format!("step {k}: rows must all hold N = {n} particles"));
            }
            if let Some((i, x)) = self.positions[k]
                .iter()
                .enumerate()
                .find(|(_, x)| !x.is_finite())
            {
                return bad(format!(
                    "step {k}, particle {i}: position {x} is not finite"
                ));
            }
            if k > 0 {
                if self.ancestors[k].len() != n {
                    return bad(format!(
                        "step {k}: {} ancestors for N = {n}",
                        self.ancestors[k].len()
                    ));
                }
                if let Some(i) = self.ancestors[k].iter().position(|&a| a >= n) {
                    return bad(format!(
                        "step {k}, particle {i}: ancestor index out of range"
                    ));
                }
            }
        }
        if let Some(t) = self.coalescence_time
            && t >= steps
        {
            return bad(format!(
                "coalescence time {t} is past the last step {}",
                steps - 1
            ));
        }
        if let Some(x) = &self.truth
            && x.len() != steps
        {
            return bad(format!("truth has {} values for {steps} steps", x.len()));
        }
        Ok(())
    }

    /// Smallest and largest value on the y-axis: every position and the true state.
    pub fn y_extent(&self) -> (f64, f64) {
        let all = self
            .positions
            .iter()
            .flatten()
            .chain(self.truth.iter().flatten());
        all.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> GenealogyData {
        GenealogyData {
            positions: vec![vec![0.0, 1.0], vec![0.5, 1.5], vec![0.2, 0.4]],
            ancestors: vec![vec![], vec![0, 0], vec![1, 1]],
            surviving: vec![vec![true, false], vec![false, true], vec![true, true]],
            coalescence_time: Some(1),
            truth: None,
        }
    }

    #[test]
    fn consistent_data_validate() {
        small().validate().unwrap();
    }

    #[test]
    fn inconsistent_data_are_rejected() {
        let mut d = small();
        d.ancestors[2][0] = 2;
        assert!(d.validate().is_err());
        let mut d = small();
        d.ancestors[0] = vec![0, 1];
        assert!(d.validate().is_err());
        let mut d = small();
        d.positions[1].pop();
        assert!(d.validate().is_err());
        let mut d = small();
        d.coalescence_time = Some(3);
        assert!(d.validate().is_err());
        let mut d = small();
        d.positions[0][0] = f64::NAN;
        assert!(d.validate().is_err());
    }
}
