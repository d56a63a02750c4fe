//! `index.html` and `REPORT.md`: every figure and table, grouped by paper, with captions and
//! the notes on where our numbers differ from the paper's.
//!
//! The HTML page embeds its PNGs as data URIs and its styling inline, so it is one file that
//! works opened from disk, with no network and no JavaScript. The Markdown links the PNGs
//! beside it.

use std::fmt::Write as _;
use std::path::Path;

use base64::Engine as _;

use super::{Outcome, RrdOutput, Section, Summary, Table};
use crate::error::{Result, VizError};
use crate::io::write_atomic;

/// Escape text for HTML element content and attribute values.
fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            _ => out.push(c),
        }
    }
    out
}

/// Escape a Markdown table cell.
fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

const CSS: &str = "body{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;max-width:1100px;\
margin:2em auto;padding:0 1em;color:#111;line-height:1.45}\
h1{border-bottom:2px solid #333}h2{margin-top:2.2em;border-bottom:1px solid #999}\
figure{margin:1.5em 0}figure img{max-width:100%;border:1px solid #ccc}\
figcaption{font-size:.95em;color:#333}\
table{border-collapse:collapse;margin:.8em 0;font-size:.92em}\
th,td{border:1px solid #999;padding:.25em .6em;text-align:right}\
th{background:#eee}caption{caption-side:top;text-align:left;font-weight:bold;padding:.3em 0}\
.note{background:#fff6d6;border-left:4px solid #c90;padding:.4em .8em;margin:.6em 0}\
.failed{background:#fde4e4;border-left:4px solid #c00;padding:.4em .8em;margin:.6em 0}\
nav a{margin-right:1em}code{background:#f3f3f3;padding:0 .2em}";

fn html_table(out: &mut String, t: &Table) {
    let _ = write!(out, "<table><caption>{}</caption><tr>", esc(&t.caption));
    for h in &t.header {
        let _ = write!(out, "<th>{}</th>", esc(h));
    }
    out.push_str("</tr>");
    for row in &t.rows {
        out.push_str("<tr>");
        for c in row {
            let _ = write!(out, "<td>{}</td>", esc(c));
        }
        out.push_str("</tr>");
    }
    out.push_str("</table>\n");
}

/// Write `index.html` into the directory of `path`, embedding the figures found there.
///
/// # Errors
/// An I/O error naming the figure that cannot be read or the page that cannot be written.
pub fn write_html(path: &Path, summary: &Summary, reports: &[(Section, Outcome)]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut out = String::new();
    let _ = write!(
        out,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>pf report</title><style>{CSS}</style></head><body>\n\
         <h1>pf: particle-filtering papers, reproduced</h1>\n\
         <p>pf-viz {}, seed {}, scale <code>{}</code>. Every number behind these figures is \
         in <code>summary.json</code>; {}.</p>\n<nav>",
        esc(summary.version),
        summary.seed,
        scale_name(summary),
        esc(recordings(summary)),
    );
    for (s, _) in reports {
        let _ = write!(out, "<a href=\"#{}\">{}</a>", s.name, esc(s.name));
    }
    out.push_str("</nav>\n");
    if let Some(line) = failures(summary) {
        let _ = writeln!(out, "<p class=\"failed\">{}</p>", esc(&line));
    }
    for (s, r) in reports {
        let _ = writeln!(out, "<h2 id=\"{}\">{}</h2>", s.name, esc(s.title));
        let r = match r {
            Ok(r) => r,
            Err(e) => {
                let _ = writeln!(
                    out,
                    "<p class=\"failed\">This section failed: {}</p>",
                    esc(e)
                );
                continue;
            }
        };
        for note in &r.notes {
            let _ = writeln!(out, "<p class=\"note\">{}</p>", esc(note));
        }
        for f in &r.figures {
            let png = std::fs::read(dir.join(&f.file)).map_err(VizError::io(dir.join(&f.file)))?;
            let data = base64::engine::general_purpose::STANDARD.encode(png);
            let _ = writeln!(
                out,
                "<figure><img alt=\"{}\" src=\"data:image/png;base64,{data}\">\
                 <figcaption><b>{}</b>: {}</figcaption></figure>",
                esc(&f.file),
                esc(&f.file),
                esc(&f.caption)
            );
        }
        for t in &r.tables {
            html_table(&mut out, t);
        }
        if !r.files.is_empty() {
            let _ = writeln!(
                out,
                "<p>Other files: {}</p>",
                r.files
                    .iter()
                    .map(|f| format!("<code>{}</code>", esc(f)))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    out.push_str("</body></html>\n");
    write_atomic(path, |w| {
        w.write_all(out.as_bytes()).map_err(VizError::io(path))
    })
}

/// What the report says of its recordings: where they open, or why there are none.
fn recordings(summary: &Summary) -> &'static str {
    match summary.rrd {
        RrdOutput::Write => "the recordings (`*.rrd`) open in the Rerun viewer",
        RrdOutput::Skip => {
            "no recordings were written (`--no-rrd`, or a build without the `rrd` feature)"
        }
    }
}

/// The line that heads the pages when sections failed, naming them.
fn failures(summary: &Summary) -> Option<String> {
    (!summary.failed.is_empty()).then(|| {
        let names: Vec<&str> = summary.failed.keys().copied().collect();
        format!(
            "Failed sections (each shows its error below, and summary.json lists them under \
             \"failed\"): {}.",
            names.join(", ")
        )
    })
}

/// Write `REPORT.md`, linking the figures beside it.
///
/// # Errors
/// An I/O error naming `path`.
pub fn write_markdown(
    path: &Path,
    summary: &Summary,
    reports: &[(Section, Outcome)],
) -> Result<()> {
    let mut out = String::new();
    let _ = write!(
        out,
        "# pf: particle-filtering papers, reproduced\n\n\
         pf-viz {}, seed {}, scale `{}`. Every number behind these figures is in \
         `summary.json`; {}.\n",
        summary.version,
        summary.seed,
        scale_name(summary),
        recordings(summary),
    );
    if let Some(line) = failures(summary) {
        let _ = write!(out, "\n> **{line}**\n");
    }
    for (s, r) in reports {
        let _ = write!(out, "\n## {}\n\n", s.title);
        let r = match r {
            Ok(r) => r,
            Err(e) => {
                let _ = writeln!(out, "> **This section failed:** {e}");
                continue;
            }
        };
        for note in &r.notes {
            let _ = write!(out, "> **Note.** {note}\n\n");
        }
        for f in &r.figures {
            let _ = write!(out, "![{0}]({0})\n\n*{0}*: {1}\n\n", f.file, f.caption);
        }
        for t in &r.tables {
            let _ = write!(out, "**{}**\n\n", md_cell(&t.caption));
            let _ = writeln!(
                out,
                "| {} |",
                t.header
                    .iter()
                    .map(|h| md_cell(h))
                    .collect::<Vec<_>>()
                    .join(" | ")
            );
            let _ = writeln!(out, "|{}", "---:|".repeat(t.header.len()));
            for row in &t.rows {
                let _ = writeln!(
                    out,
                    "| {} |",
                    row.iter()
                        .map(|c| md_cell(c))
                        .collect::<Vec<_>>()
                        .join(" | ")
                );
            }
            out.push('\n');
        }
        if !r.files.is_empty() {
            let _ = writeln!(
                out,
                "Other files: {}",
                r.files
                    .iter()
                    .map(|f| format!("`{f}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    write_atomic(path, |w| {
        w.write_all(out.as_bytes()).map_err(VizError::io(path))
    })
}

fn scale_name(summary: &Summary) -> String {
    serde_json::to_value(summary.scale)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn html_escaping_covers_markup() {
        assert_eq!(esc("a<b & \"c\">"), "a&lt;b &amp; &quot;c&quot;&gt;");
        assert_eq!(md_cell("a|b\nc"), "a\\|b c");
    }
}
