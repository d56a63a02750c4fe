//! Reading the CLI's input files: CSV tables with a header, read by name. This is the one
//! CSV reader of pf-viz (the `y` series, the radar measurements, the EPF's detections and
//! init tracks); pf-dredge reads its own log format, which it also streams.

use std::path::{Path, PathBuf};

use pf_mpf::radar::RadarObs;

use crate::error::{Result, VizError};

/// The named columns of a CSV file, row by row, with each row's line (1-based, the header
/// is line 1). Cells are trimmed; a byte-order mark before the header is ignored.
#[derive(Debug)]
pub(crate) struct Table {
    path: PathBuf,
    rows: Vec<Vec<String>>,
    lines: Vec<u64>,
    /// The first blank line before the last row, if any (the CSV reader skips blank lines).
    blank: Option<u64>,
}

impl Table {
    /// Read the `columns` of the CSV file at `path` (others are ignored).
    ///
    /// # Errors
    /// [`VizError::Data`] naming the file and, where there is one, the line: an unreadable
    /// file, a missing or doubled column, a malformed record.
    pub(crate) fn read(path: &Path, columns: &[&str]) -> Result<Table> {
        let bad = |line: Option<u64>, message: String| data_err(path, line, message);
        let bytes = std::fs::read(path).map_err(|e| bad(None, e.to_string()))?;
        let error_line = |p: Option<&csv::Position>| p.map(|p| line_of(&bytes, p).0);
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(bytes.as_slice());
        let headers = reader
            .headers()
            .map_err(|e| bad(Some(1), e.to_string()))?
            .clone();
        let idx = columns
            .iter()
            .map(|c| column(path, &headers, c))
            .collect::<Result<Vec<_>>>()?;
        let mut table = Table {
            path: path.to_path_buf(),
            rows: Vec::new(),
            lines: Vec::new(),
            blank: None,
        };
        for record in reader.records() {
            let record = record.map_err(|e| {
                let message = match e.kind() {
                    csv::ErrorKind::UnequalLengths {
                        expected_len, len, ..
                    } => format!("{len} field(s), but the header has {expected_len}"),
                    _ => e.to_string(),
                };
                bad(error_line(e.position()), message)
            })?;
            let (line, blank) = record.position().map_or((0, None), |p| line_of(&bytes, p));
            table.blank = table.blank.or(blank);
            table.rows.push(
                idx.iter()
                    .map(|&i| record.get(i).unwrap_or("").to_owned())
                    .collect(),
            );
            table.lines.push(line);
        }
        Ok(table)
    }

    /// The rows: each row's line and its cells, in the order of the requested columns.
    pub(crate) fn rows(&self) -> impl Iterator<Item = (u64, &[String])> {
        self.lines
            .iter()
            .copied()
            .zip(self.rows.iter().map(Vec::as_slice))
    }

    /// A [`VizError::Data`] for this file and `line`.
    pub(crate) fn error(&self, line: Option<u64>, message: impl Into<String>) -> VizError {
        data_err(&self.path, line, message)
    }

    /// The 1-based line of row `row`, if it exists.
    pub(crate) fn line(&self, row: usize) -> Option<u64> {
        self.lines.get(row).copied()
    }

    /// An error if a blank line lies among the rows of a file whose rows are time steps:
    /// skipping it would shift every later observation by a step.
    ///
    /// # Errors
    /// [`VizError::Data`] naming the blank line; `hint` says what to write instead.
    pub(crate) fn refuse_blank_lines(&self, hint: &str) -> Result<()> {
        match self.blank {
            Some(line) => Err(self.error(
                Some(line),
                format!("blank line among the observations: each row is one step ({hint})"),
            )),
            None => Ok(()),
        }
    }

    /// The finite number in a cell of column `col` on `line`.
    ///
    /// # Errors
    /// [`VizError::Data`] naming the line, the column and the text.
    pub(crate) fn number(&self, line: u64, col: &str, cell: &str) -> Result<f64> {
        let v: f64 = cell
            .parse()
            .map_err(|_| self.error(Some(line), format!("`{col}` = `{cell}` is not a number")))?;
        if !v.is_finite() {
            return Err(self.error(
                Some(line),
                format!("`{col}` = `{cell}` is not a finite number"),
            ));
        }
        Ok(v)
    }

    /// The integer in a cell of column `col` on `line` (`3` or `3.0`, not `3.5`).
    ///
    /// # Errors
    /// [`VizError::Data`] naming the line, the column and the text.
    pub(crate) fn integer(&self, line: u64, col: &str, cell: &str) -> Result<i64> {
        if let Ok(v) = cell.parse::<i64>() {
            return Ok(v);
        }
        let v = self.number(line, col, cell)?;
        if v.fract() != 0.0 || v.abs() > 9.0e15 {
            return Err(self.error(Some(line), format!("`{col}` = `{cell}` is not an integer")));
        }
        Ok(v as i64)
    }
}

/// The line a record starts on, and the first blank line before it if there is one. The
/// CSV reader gives the position where it began to read the record: before the blank lines
/// it skips, and before the `\n` of a previous record that ended in `\r\n`.
fn line_of(bytes: &[u8], p: &csv::Position) -> (u64, Option<u64>) {
    let mut i = usize::try_from(p.byte())
        .unwrap_or(usize::MAX)
        .min(bytes.len());
    let mut line = p.line();
    if i > 0 && bytes[i - 1] == b'\r' && bytes.get(i) == Some(&b'\n') {
        i += 1;
        line += 1;
    }
    let first = line;
    for &b in bytes[i..].iter().take_while(|&&b| b == b'\n' || b == b'\r') {
        line += u64::from(b == b'\n');
    }
    (line, (line > first).then_some(first))
}

/// A [`VizError::Data`] for `path` and `line`.
fn data_err(path: &Path, line: Option<u64>, message: impl Into<String>) -> VizError {
    VizError::Data {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

/// Read the `y` column of a CSV file (other columns are ignored): `Y_0…Y_n`, one row per
/// step.
///
/// # Errors
/// [`VizError::Data`] naming the file, the line and the problem: a missing file, no `y`
/// column, a non-numeric or non-finite value, a blank line among the rows, or fewer than
/// `min_rows` values.
pub fn read_y(path: &Path, min_rows: usize) -> Result<Vec<f64>> {
    let table = Table::read(path, &["y"])?;
    table.refuse_blank_lines("these filters take no missing observation")?;
    let ys = table
        .rows()
        .map(|(line, cells)| table.number(line, "y", &cells[0]))
        .collect::<Result<Vec<f64>>>()?;
    if ys.len() < min_rows {
        return Err(data_err(
            path,
            None,
            format!(
                "{} observation(s) in the `y` column, at least {min_rows} needed",
                ys.len()
            ),
        ));
    }
    Ok(ys)
}

/// Read radar measurements from a CSV file with `range` and `azimuth` columns (other columns
/// are ignored), one row per step; a row whose two cells are empty is a missing measurement.
///
/// # Errors
/// [`VizError::Data`] naming the file, the line and the problem: a missing column, one cell
/// empty and not the other, a cell that is not a finite number, a blank line among the rows,
/// or no row at all.
pub fn read_radar(path: &Path) -> Result<Vec<Option<RadarObs>>> {
    let table = Table::read(path, &["range", "azimuth"])?;
    table.refuse_blank_lines("write a missing measurement as `,`")?;
    let ys = table
        .rows()
        .map(|(line, cells)| match (cells[0].is_empty(), cells[1].is_empty()) {
            (true, true) => Ok(None),
            (false, false) => Ok(Some(RadarObs::new(
                table.number(line, "range", &cells[0])?,
                table.number(line, "azimuth", &cells[1])?,
            ))),
            _ => Err(table.error(
                Some(line),
                "`range` and `azimuth` must both be given, or both be empty (a missing measurement)",
            )),
        })
        .collect::<Result<Vec<_>>>()?;
    if ys.is_empty() {
        return Err(data_err(path, None, "no measurement rows after the header"));
    }
    Ok(ys)
}

/// The index of the column `name` in a CSV file's `headers`. A missing column, or one named
/// twice (which of the two was meant?), is an error on line 1 of `path`.
///
/// # Errors
/// [`VizError::Data`] naming the file, line 1 and the column.
fn column(path: &Path, headers: &csv::StringRecord, name: &str) -> Result<usize> {
    let bad = |message: String| VizError::Data {
        path: path.to_path_buf(),
        line: Some(1),
        message,
    };
    let mut hits = headers.iter().enumerate().filter(|(_, h)| *h == name);
    let (first, _) = hits
        .next()
        .ok_or_else(|| bad(format!("no `{name}` column in the header")))?;
    if hits.next().is_some() {
        return Err(bad(format!("column `{name}` appears twice in the header")));
    }
    Ok(first)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("pf-viz-data-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn reads_the_y_column_and_names_bad_lines() {
        let ok = file("ok.csv", "t,y\n0,1.5\n1,-2\n");
        assert_eq!(read_y(&ok, 2).unwrap(), vec![1.5, -2.0]);
        let nan = file("nan.csv", "y\n1\nNaN\n");
        let e = read_y(&nan, 1).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("finite"), "{e}");
        let text = file("text.csv", "y\n1\nabc\n");
        assert!(read_y(&text, 1).unwrap_err().to_string().contains("line 3"));
        let noy = file("noy.csv", "x\n1\n");
        assert!(
            read_y(&noy, 1)
                .unwrap_err()
                .to_string()
                .contains("no `y` column")
        );
        let short = file("short.csv", "y\n1\n");
        assert!(
            read_y(&short, 2)
                .unwrap_err()
                .to_string()
                .contains("at least 2")
        );
        assert!(read_y(Path::new("/nonexistent/x.csv"), 1).is_err());
        let twice = file("twice.csv", "y,y\n1,2\n");
        let e = read_y(&twice, 1).unwrap_err().to_string();
        assert!(
            e.contains("line 1") && e.contains("`y` appears twice"),
            "{e}"
        );
        // A spreadsheet's byte-order mark is not part of the first column's name.
        let bom = file("bom.csv", "\u{feff}y\n1\n");
        assert_eq!(read_y(&bom, 1).unwrap(), vec![1.0]);
        // Windows line ends and trailing blank lines are fine.
        let crlf = file("crlf.csv", "y\r\n1\r\n2\r\n\r\n\n");
        assert_eq!(read_y(&crlf, 1).unwrap(), vec![1.0, 2.0]);
    }

    #[test]
    fn a_blank_line_among_the_steps_is_an_error_not_a_skipped_step() {
        // Line 4 is blank: skipping it would make 3.0 the observation of step 2.
        let gap = file("gap.csv", "y\n1\n2\n\n3\n");
        let e = read_y(&gap, 1).unwrap_err().to_string();
        assert!(
            e.contains("gap.csv, line 4") && e.contains("blank line"),
            "{e}"
        );
        let crlf = file("gap-crlf.csv", "y\r\n1\r\n\r\n2\r\n");
        let e = read_y(&crlf, 1).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("blank line"), "{e}");
        let head = file("gap-head.csv", "y\n\n1\n2\n");
        let e = read_y(&head, 1).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("blank line"), "{e}");
        let radar = file("gap-radar.csv", "range,azimuth\n1,0.5\n\n2,0.6\n");
        let e = read_radar(&radar).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("`,`"), "{e}");
        // The EPF's rows carry their frame, so a blank line there loses nothing.
        let t = Table::read(
            &file("gap-det.csv", "frame,x,y\n0,1,2\n\n1,3,4\n"),
            &["frame", "x", "y"],
        )
        .unwrap();
        assert_eq!(t.rows().map(|(line, _)| line).collect::<Vec<_>>(), [2, 4]);
    }

    #[test]
    fn reads_radar_measurements_and_gaps_and_names_the_bad_line() {
        let ok = file(
            "radar.csv",
            "\u{feff}range,azimuth,note\r\n2500.5,0.64,a\r\n,,gap\r\n2490,-0.1,b\r\n",
        );
        let ys = read_radar(&ok).unwrap();
        assert_eq!(
            ys,
            [
                Some(RadarObs::new(2500.5, 0.64)),
                None,
                Some(RadarObs::new(2490.0, -0.1))
            ]
        );
        // Columns are found by name, in any order.
        let swapped = file("swapped.csv", "azimuth,range\n0.64,2500.5\n");
        assert_eq!(
            read_radar(&swapped).unwrap(),
            [Some(RadarObs::new(2500.5, 0.64))]
        );
        let cases = [
            (
                "range,azimuth\n1,2\n3,x\n",
                "line 3",
                "`azimuth` = `x` is not a number",
            ),
            ("range,azimuth\n1,\n", "line 2", "both be given"),
            (
                "range,azimuth\nNaN,2\n",
                "line 2",
                "`range` = `NaN` is not a finite number",
            ),
            (
                "range,azimuth\n1,2\n\n1,2,3\n",
                "line 4",
                "3 field(s), but the header has 2",
            ),
            ("r,a\n1,2\n", "line 1", "no `range` column"),
            ("range,azimuth\n", "radar", "no measurement rows"),
        ];
        for (i, (text, line, what)) in cases.into_iter().enumerate() {
            let e = read_radar(&file(&format!("radar-bad-{i}.csv"), text))
                .unwrap_err()
                .to_string();
            assert!(e.contains(line) && e.contains(what), "{text:?}: {e}");
        }
    }
}
