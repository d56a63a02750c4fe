//! Logged on-board data in memory: the columns of the CLI's CSV format, already parsed.
//!
//! `t` (s), `V_t` (m³), `m_t` (kg), `Q_i` (m³/s), `rho_i` (kg/m³), and optionally the truth
//! columns `Q_o`, `rho_o`. A `None` is an empty cell: a missing measurement. Reading the file
//! (and naming its line numbers) is the CLI's job; checking the values is done here.

use crate::error::{DredgeError, Result};
use serde::{Deserialize, Serialize};

/// True overflow values, when the data are simulated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Truth {
    /// `Q_o` per sample (m³/s).
    pub q_o: Vec<Option<f64>>,
    /// `ρ_o` per sample (kg/m³); empty where nothing overflows.
    pub rho_o: Vec<Option<f64>>,
}

/// One data set: a column per quantity, all of the same length.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DredgeData {
    /// Sample times `t_k` (s), strictly increasing.
    pub t: Vec<f64>,
    /// Measured total volume `V_t` (m³).
    pub v_t: Vec<Option<f64>>,
    /// Measured total mass `m_t` (kg).
    pub m_t: Vec<Option<f64>>,
    /// Incoming flow-rate `Q_i` (m³/s).
    pub q_i: Vec<Option<f64>>,
    /// Incoming density `ρ_i` (kg/m³).
    pub rho_i: Vec<Option<f64>>,
    /// Truth columns, if any.
    pub truth: Option<Truth>,
}

/// One sample as it arrives on line: the on-line estimator's input.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sample {
    /// `t_k` (s).
    pub t: f64,
    /// Measured `V_t` (m³), `None` if missing.
    pub v_t: Option<f64>,
    /// Measured `m_t` (kg), `None` if missing.
    pub m_t: Option<f64>,
    /// `Q_i` (m³/s), `None` if missing (the last value is held).
    pub q_i: Option<f64>,
    /// `ρ_i` (kg/m³), `None` if missing (the last value is held).
    pub rho_i: Option<f64>,
}

/// Check one value: finite, and non-negative if it is a flow or density.
pub(crate) fn check_value(
    column: &'static str,
    index: usize,
    v: f64,
    non_negative: bool,
) -> Result<()> {
    if !v.is_finite() {
        return Err(DredgeError::NonFinite {
            column,
            index,
            value: v,
        });
    }
    if non_negative && v < 0.0 {
        return Err(DredgeError::Negative {
            column,
            index,
            value: v,
        });
    }
    Ok(())
}

impl Sample {
    /// Check the sample's own values (the time order is checked by whoever sees two samples).
    ///
    /// # Errors
    /// A non-finite value, or a negative flow, density, volume or mass.
    pub fn validate(&self, index: usize) -> Result<()> {
        check_value("t", index, self.t, false)?;
        let cols = [
            ("V_t", self.v_t),
            ("m_t", self.m_t),
            ("Q_i", self.q_i),
            ("rho_i", self.rho_i),
        ];
        for (name, v) in cols {
            if let Some(v) = v {
                check_value(name, index, v, true)?;
            }
        }
        Ok(())
    }
}

impl DredgeData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Sample `k` as the on-line estimator sees it.
    ///
    /// # Panics
    /// If `k` is out of range or the columns are ragged; call [`validate`](Self::validate)
    /// first.
    pub fn sample(&self, k: usize) -> Sample {
        Sample {
            t: self.t[k],
            v_t: self.v_t[k],
            m_t: self.m_t[k],
            q_i: self.q_i[k],
            rho_i: self.rho_i[k],
        }
    }

    /// Check the data set: at least `needed` samples, equal column lengths, finite values,
    /// non-negative flows and densities, strictly increasing time, and a complete first
    /// sample (the filter starts from it).
    ///
    /// # Errors
    /// The first problem found, naming the column and the sample index.
    pub fn validate(&self, needed: usize) -> Result<()> {
        let n = self.len();
        if n < needed.max(1) {
            return Err(DredgeError::TooFewSamples {
                needed: needed.max(1),
                got: n,
            });
        }
        let lens = [
            ("V_t", self.v_t.len()),
            ("m_t", self.m_t.len()),
            ("Q_i", self.q_i.len()),
            ("rho_i", self.rho_i.len()),
        ];
        let truth_lens = self
            .truth
            .as_ref()
            .map(|tr| [("Q_o", tr.q_o.len()), ("rho_o", tr.rho_o.len())]);
        for (column, got) in lens.into_iter().chain(truth_lens.into_iter().flatten()) {
            if got != n {
                return Err(DredgeError::ColumnLength {
                    column,
                    expected: n,
                    got,
                });
            }
        }
        for k in 0..n {
            self.sample(k).validate(k)?;
            if k > 0 && self.t[k] <= self.t[k - 1] {
                return Err(DredgeError::TimeNotIncreasing {
                    index: k,
                    t_prev: self.t[k - 1],
                    t: self.t[k],
                });
            }
            if let Some(tr) = &self.truth {
                if let Some(q) = tr.q_o[k] {
                    check_value("Q_o", k, q, true)?;
                }
                if let Some(r) = tr.rho_o[k] {
                    check_value("rho_o", k, r, true)?;
                }
            }
        }
        let first = self.sample(0);
        for (column, v) in [
            ("V_t", first.v_t),
            ("m_t", first.m_t),
            ("Q_i", first.q_i),
            ("rho_i", first.rho_i),
        ] {
            if v.is_none() {
                return Err(DredgeError::MissingFirstValue { column });
            }
        }
        Ok(())
    }
}
