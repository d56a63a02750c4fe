//! Logged on-board data as CSV: the format the CLI reads and writes, and the one a dredging
//! engineer's data acquisition logs.
//!
//! A header names the columns, in any order: `t` (s), `V_t` (m³), `m_t` (kg), `Q_i` (m³/s)
//! and `rho_i` (kg/m³), and optionally the truth columns `Q_o` (m³/s) and `rho_o` (kg/m³);
//! other columns are ignored. The sampling period is taken from `t`. An empty cell is a
//! missing measurement (the filter does not reweight on it); `t` is never empty, and the
//! first sample must be complete (the filter starts from it). Fields are plain numbers
//! separated by commas (no quoting).
//!
//! [`CsvSamples`] reads one row at a time from any [`BufRead`], so the on-line estimator can
//! take each sample as it arrives; [`read_csv`] reads a whole file into a [`DredgeData`].
//! Every error is [`DredgeError::Csv`] with the 1-based line number (the header is line 1).

use std::io::{BufRead, Write};

use crate::data::{DredgeData, Sample, Truth};
use crate::error::{DredgeError, Result};

/// The columns every file must have.
pub const REQUIRED: [&str; 5] = ["t", "V_t", "m_t", "Q_i", "rho_i"];
/// The optional truth columns.
pub const TRUTH: [&str; 2] = ["Q_o", "rho_o"];

fn csv_err(line: u64, message: impl Into<String>) -> DredgeError {
    DredgeError::Csv {
        line,
        message: message.into(),
    }
}

/// One data row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// The row's 1-based line number in the file (header = 1).
    pub line: u64,
    /// The measurements.
    pub sample: Sample,
    /// True `Q_o`, if the file has that column and the cell is not empty.
    pub q_o: Option<f64>,
    /// True `ρ_o`, likewise.
    pub rho_o: Option<f64>,
}

/// A streaming reader of the CSV format: the header is read by [`new`](Self::new), then one
/// [`Row`] per data line, checked as it comes (numbers, signs, increasing time).
#[derive(Debug)]
pub struct CsvSamples<R> {
    reader: R,
    line: u64,
    /// Index in a row of `t, V_t, m_t, Q_i, rho_i, Q_o, rho_o`.
    cols: [Option<usize>; 7],
    width: usize,
    buf: String,
    prev_t: Option<f64>,
    rows: usize,
    done: bool,
}

impl<R: BufRead> CsvSamples<R> {
    /// Read the header.
    ///
    /// # Errors
    /// An empty input, a missing required column, a duplicated column, or a read error.
    pub fn new(mut reader: R) -> Result<Self> {
        let mut buf = String::new();
        let n = reader
            .read_line(&mut buf)
            .map_err(|e| csv_err(1, format!("cannot read the header: {e}")))?;
        if n == 0 || buf.trim().is_empty() {
            return Err(csv_err(
                1,
                "the file is empty: expected a header `t,V_t,m_t,Q_i,rho_i`",
            ));
        }
        // A UTF-8 byte-order mark (spreadsheets write one) is not part of the first name.
        let names: Vec<&str> = buf
            .trim_start_matches('\u{feff}')
            .trim_end_matches(['\n', '\r'])
            .split(',')
            .map(str::trim)
            .collect();
        let mut cols = [None; 7];
        for (slot, want) in cols.iter_mut().zip(REQUIRED.iter().chain(TRUTH.iter())) {
            let mut hits = names.iter().enumerate().filter(|(_, n)| *n == want);
            *slot = hits.next().map(|(i, _)| i);
            if hits.next().is_some() {
                return Err(csv_err(1, format!("column `{want}` appears twice")));
            }
        }
        let missing: Vec<&str> = REQUIRED
            .iter()
            .zip(&cols)
            .filter(|(_, c)| c.is_none())
            .map(|(n, _)| *n)
            .collect();
        if !missing.is_empty() {
            return Err(csv_err(
                1,
                format!(
                    "missing column(s) {}: the header must name t, V_t, m_t, Q_i and rho_i",
                    missing.join(", ")
                ),
            ));
        }
        let width = names.len();
        buf.clear();
        Ok(CsvSamples {
            reader,
            line: 1,
            cols,
            width,
            buf,
            prev_t: None,
            rows: 0,
            done: false,
        })
    }

    /// Whether the file has the truth columns (either of them).
    pub fn has_truth(&self) -> bool {
        self.cols[5].is_some() || self.cols[6].is_some()
    }

    /// The next row, `None` at the end of the input.
    ///
    /// # Errors
    /// A read error, a row with the wrong number of fields, a non-numeric, non-finite or
    /// negative value, an empty `t`, a time that does not increase, an incomplete first row,
    /// or an input with a header and no rows. After an error the reader is finished.
    pub fn next_row(&mut self) -> Option<Result<Row>> {
        if self.done {
            return None;
        }
        let r = self.read_row();
        if !matches!(r, Some(Ok(_))) {
            self.done = true;
        }
        r
    }

    fn read_row(&mut self) -> Option<Result<Row>> {
        loop {
            self.buf.clear();
            self.line += 1;
            let line = self.line;
            match self.reader.read_line(&mut self.buf) {
                Err(e) => return Some(Err(csv_err(line, format!("cannot read: {e}")))),
                Ok(0) => {
                    return (self.rows == 0)
                        .then(|| Err(csv_err(line, "no data rows after the header")));
                }
                Ok(_) => {}
            }
            if !self.buf.trim().is_empty() {
                break;
            }
        }
        Some(self.parse())
    }

    fn parse(&mut self) -> Result<Row> {
        let line = self.line;
        let fields: Vec<&str> = self
            .buf
            .trim_end_matches(['\n', '\r'])
            .split(',')
            .map(str::trim)
            .collect();
        if fields.len() != self.width {
            return Err(csv_err(
                line,
                format!(
                    "{} field(s), but the header has {}",
                    fields.len(),
                    self.width
                ),
            ));
        }
        let names = REQUIRED.iter().chain(TRUTH.iter());
        let mut v = [None; 7];
        for ((slot, col), name) in v.iter_mut().zip(self.cols).zip(names) {
            let Some(col) = col else { continue };
            let f = fields[col];
            if f.is_empty() {
                continue;
            }
            let x: f64 = f
                .parse()
                .map_err(|_| csv_err(line, format!("{name} = `{f}` is not a number")))?;
            if !x.is_finite() {
                return Err(csv_err(
                    line,
                    format!("{name} = `{f}` is not a finite number"),
                ));
            }
            if *name != "t" && x < 0.0 {
                return Err(csv_err(
                    line,
                    format!(
                        "{name} = `{f}` is negative: volumes, masses, flows and densities cannot be"
                    ),
                ));
            }
            *slot = Some(x);
        }
        let t = v[0].ok_or_else(|| csv_err(line, "t is empty: every sample needs its time"))?;
        if let Some(prev) = self.prev_t
            && t <= prev
        {
            return Err(csv_err(
                line,
                format!("time does not increase: t = {t} after t = {prev}"),
            ));
        }
        if self.rows == 0 {
            for (name, x) in REQUIRED.iter().zip(&v).skip(1) {
                if x.is_none() {
                    return Err(csv_err(
                        line,
                        format!("the first sample has no {name}: the filter starts from it"),
                    ));
                }
            }
        }
        self.prev_t = Some(t);
        self.rows += 1;
        Ok(Row {
            line,
            sample: Sample {
                t,
                v_t: v[1],
                m_t: v[2],
                q_i: v[3],
                rho_i: v[4],
            },
            q_o: v[5],
            rho_o: v[6],
        })
    }
}

impl<R: BufRead> Iterator for CsvSamples<R> {
    type Item = Result<Row>;
    fn next(&mut self) -> Option<Result<Row>> {
        self.next_row()
    }
}

/// Read a whole file into a [`DredgeData`] (truth only if the file has a truth column).
///
/// # Errors
/// As [`CsvSamples`], with the line at fault.
pub fn read_csv<R: BufRead>(reader: R) -> Result<DredgeData> {
    let mut rows = CsvSamples::new(reader)?;
    let truth = rows.has_truth();
    let mut d = DredgeData {
        t: Vec::new(),
        v_t: Vec::new(),
        m_t: Vec::new(),
        q_i: Vec::new(),
        rho_i: Vec::new(),
        truth: truth.then(|| Truth {
            q_o: Vec::new(),
            rho_o: Vec::new(),
        }),
    };
    for row in &mut rows {
        let Row {
            sample: s,
            q_o,
            rho_o,
            ..
        } = row?;
        d.t.push(s.t);
        d.v_t.push(s.v_t);
        d.m_t.push(s.m_t);
        d.q_i.push(s.q_i);
        d.rho_i.push(s.rho_i);
        if let Some(tr) = &mut d.truth {
            tr.q_o.push(q_o);
            tr.rho_o.push(rho_o);
        }
    }
    Ok(d)
}

/// Write a data set in the CSV format (truth columns if it has them). Numbers are written in
/// Rust's shortest round-trip form, so [`read_csv`] gives back the same bits; `None` is an
/// empty cell.
///
/// # Errors
/// The writer's error; ragged columns ([`DredgeData::validate`]).
pub fn write_csv<W: Write>(data: &DredgeData, mut w: W) -> Result<()> {
    data.validate(1)?;
    let io = |e: std::io::Error| DredgeError::Io {
        message: e.to_string(),
    };
    let cell = |x: Option<f64>| x.map(|x| x.to_string()).unwrap_or_default();
    let header = if data.truth.is_some() {
        "t,V_t,m_t,Q_i,rho_i,Q_o,rho_o"
    } else {
        "t,V_t,m_t,Q_i,rho_i"
    };
    writeln!(w, "{header}").map_err(io)?;
    for k in 0..data.len() {
        write!(
            w,
            "{},{},{},{},{}",
            data.t[k],
            cell(data.v_t[k]),
            cell(data.m_t[k]),
            cell(data.q_i[k]),
            cell(data.rho_i[k])
        )
        .map_err(io)?;
        if let Some(tr) = &data.truth {
            write!(w, ",{},{}", cell(tr.q_o[k]), cell(tr.rho_o[k])).map_err(io)?;
        }
        writeln!(w).map_err(io)?;
    }
    w.flush().map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        read_csv(text.as_bytes()).unwrap_err().to_string()
    }

    #[test]
    fn round_trip_is_exact_and_empty_cells_are_missing() {
        let d = crate::simulator::simulate(
            &crate::SimConfig {
                t_end: 200.0,
                ..Default::default()
            },
            &mut pf_core::mc::stream_rng(3, 0),
        )
        .unwrap()
        .to_data();
        let mut out = Vec::new();
        write_csv(&d, &mut out).unwrap();
        assert_eq!(read_csv(out.as_slice()).unwrap(), d);
        // A spreadsheet's byte-order mark before the header is not part of its first name.
        let bom = read_csv("\u{feff}t,V_t,m_t,Q_i,rho_i\n0,1,2,3,4\n".as_bytes()).unwrap();
        assert_eq!(bom.t, vec![0.0]);
        let d = read_csv("rho_i,Q_i,t,m_t,V_t,extra\n1,2,0,4,5,x\n1,,5,,6,y\n".as_bytes()).unwrap();
        assert_eq!(d.t, vec![0.0, 5.0]);
        assert_eq!(d.v_t, vec![Some(5.0), Some(6.0)]);
        assert_eq!(d.m_t, vec![Some(4.0), None]);
        assert_eq!(d.q_i, vec![Some(2.0), None]);
        assert!(d.truth.is_none());
    }

    #[test]
    fn each_bad_input_names_its_line_and_problem() {
        let h = "t,V_t,m_t,Q_i,rho_i\n";
        assert!(err("").contains("line 1") && err("").contains("empty"));
        let e = err("t,V_t,Q_i,rho_i\n0,1,2,3\n");
        assert!(
            e.contains("line 1") && e.contains("missing column(s) m_t"),
            "{e}"
        );
        let e = err(&format!("{h}0,1,2,3,4\n5,1,abc,3,4\n"));
        assert!(e.contains("line 3") && e.contains("not a number"), "{e}");
        let e = err(&format!("{h}0,1,2,3,4\n0,1,2,3,4\n"));
        assert!(
            e.contains("line 3") && e.contains("time does not increase"),
            "{e}"
        );
        let e = err(&format!("{h}0,1,2,3,4\n5,1,2,-3,4\n"));
        assert!(
            e.contains("line 3") && e.contains("Q_i = `-3` is negative"),
            "{e}"
        );
        let e = err(&format!("{h}0,1,2,3,-4\n"));
        assert!(
            e.contains("line 2") && e.contains("rho_i = `-4` is negative"),
            "{e}"
        );
        let e = err(h);
        assert!(e.contains("line 2") && e.contains("no data rows"), "{e}");
        let e = err(&format!("{h}0,1,2,3\n"));
        assert!(e.contains("line 2") && e.contains("4 field(s)"), "{e}");
        let e = err(&format!("{h}0,,2,3,4\n"));
        assert!(
            e.contains("line 2") && e.contains("first sample has no V_t"),
            "{e}"
        );
        let e = err(&format!("{h}0,1,2,3,inf\n"));
        assert!(e.contains("not a finite number"), "{e}");
    }
}
