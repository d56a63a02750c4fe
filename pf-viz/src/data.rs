//! Reading observation files: a CSV with a header and a `y` column.

use std::path::Path;

use crate::error::{Result, VizError};

/// Read the `y` column of a CSV file (other columns are ignored).
///
/// # Errors
/// [`VizError::Data`] naming the file, the line and the problem: a missing file, no `y`
/// column, a non-numeric or non-finite value, or fewer than `min_rows` values.
pub fn read_y(path: &Path, min_rows: usize) -> Result<Vec<f64>> {
    let bad = |line: Option<u64>, message: String| VizError::Data {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| bad(None, e.to_string()))?;
    let headers = reader.headers().map_err(|e| bad(Some(1), e.to_string()))?;
    let col = column(path, headers, "y")?;
    let mut ys = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map(|p| p.line());
            bad(line, e.to_string())
        })?;
        let line = record.position().map(|p| p.line());
        let field = record.get(col).unwrap_or("");
        let y: f64 = field
            .parse()
            .map_err(|_| bad(line, format!("`{field}` is not a number")))?;
        if !y.is_finite() {
            return Err(bad(line, format!("`{field}` is not a finite number")));
        }
        ys.push(y);
    }
    if ys.len() < min_rows {
        return Err(bad(
            None,
            format!(
                "{} observation(s) in the `y` column, at least {min_rows} needed",
                ys.len()
            ),
        ));
    }
    Ok(ys)
}

/// The index of the column `name` in a CSV file's `headers`. A missing column, or one named
/// twice (which of the two was meant?), is an error on line 1 of `path`.
///
/// # Errors
/// [`VizError::Data`] naming the file, line 1 and the column.
pub(crate) fn column(path: &Path, headers: &csv::StringRecord, name: &str) -> Result<usize> {
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
    }
}
