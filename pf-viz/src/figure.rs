//! Plain data that figures and recordings are drawn from.
//!
//! `png/` and `rrd/` draw these types and `report/` fills them, so neither drawing back-end
//! imports the report or the other back-end: every module that draws depends on this one
//! only.

pub use pf_core::genealogy::GenealogyData;
use serde::Serialize;

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

/// Check a genealogy figure's shapes and indices, so drawing never indexes out of bounds.
///
/// # Errors
/// [`VizError::PlotData`] naming the first inconsistency.
pub fn validate_genealogy(data: &GenealogyData) -> Result<()> {
    let bad = |message: String| {
        Err(VizError::PlotData {
            what: "genealogy figure",
            message,
        })
    };
    let (steps, n) = (data.n_steps(), data.n_particles());
    if steps == 0 || n == 0 {
        return bad(format!(
            "no particles to draw ({steps} steps of {n} particles)"
        ));
    }
    if data.ancestors.len() != steps || data.surviving.len() != steps {
        return bad(format!(
            "{steps} steps of positions but {} of ancestors and {} of survival flags",
            data.ancestors.len(),
            data.surviving.len()
        ));
    }
    if !data.ancestors[0].is_empty() {
        return bad("ancestors[0] must be empty: step 0 has no parents".into());
    }
    for k in 0..steps {
        if data.positions[k].len() != n || data.surviving[k].len() != n {
            return bad(format!("step {k}: rows must all hold N = {n} particles"));
        }
        if let Some((i, x)) = data.positions[k]
            .iter()
            .enumerate()
            .find(|(_, x)| !x.is_finite())
        {
            return bad(format!(
                "step {k}, particle {i}: position {x} is not finite"
            ));
        }
        if k > 0 {
            if data.ancestors[k].len() != n {
                return bad(format!(
                    "step {k}: {} ancestors for N = {n}",
                    data.ancestors[k].len()
                ));
            }
            if let Some(i) = data.ancestors[k].iter().position(|&a| a >= n) {
                return bad(format!(
                    "step {k}, particle {i}: ancestor index out of range"
                ));
            }
        }
    }
    if let Some(t) = data.coalescence_time
        && t >= steps
    {
        return bad(format!(
            "coalescence time {t} is past the last step {}",
            steps - 1
        ));
    }
    if let Some(x) = &data.truth
        && x.len() != steps
    {
        return bad(format!("truth has {} values for {steps} steps", x.len()));
    }
    Ok(())
}

/// Smallest and largest value on a genealogy figure's y-axis: every position and the true
/// state.
pub fn genealogy_y_extent(data: &GenealogyData) -> (f64, f64) {
    let all = data
        .positions
        .iter()
        .flatten()
        .chain(data.truth.iter().flatten());
    all.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
        (lo.min(x), hi.max(x))
    })
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
        validate_genealogy(&small()).unwrap();
    }

    #[test]
    fn inconsistent_data_are_rejected() {
        let mut d = small();
        d.ancestors[2][0] = 2;
        assert!(validate_genealogy(&d).is_err());
        let mut d = small();
        d.ancestors[0] = vec![0, 1];
        assert!(validate_genealogy(&d).is_err());
        let mut d = small();
        d.positions[1].pop();
        assert!(validate_genealogy(&d).is_err());
        let mut d = small();
        d.coalescence_time = Some(3);
        assert!(validate_genealogy(&d).is_err());
        let mut d = small();
        d.positions[0][0] = f64::NAN;
        assert!(validate_genealogy(&d).is_err());
    }
}
