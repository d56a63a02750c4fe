//! `pf-viz report`: run every section and assemble `summary.json`.
//!
//! A section is one paper (plus [`core`], the engine's own demo). It runs its experiments,
//! writes its figures and recordings into the output directory and returns a
//! [`SectionReport`]: every number behind them (for `summary.json`), plus the captions,
//! tables and notes that `index.html` and `REPORT.md` show. Adding a paper = one file in
//! `report/` plus one line in [`SECTIONS`].

pub mod core;
pub mod dredge;
pub mod epf;
pub mod homotopy;
pub mod mpf;
pub mod smooth;

mod page;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;

use crate::cli::{ReportArgs, RrdOutput};
use crate::error::{Result, VizError};
use crate::io::{check_writable, prepare_out_dir, write_json};
use pf_core::mc::Scale;

/// Every report section, in the order they run and appear in `summary.json`.
pub const SECTIONS: &[Section] = &[
    core::SECTION,
    smooth::SECTION,
    mpf::SECTION,
    homotopy::SECTION,
    dredge::SECTION,
    epf::SECTION,
];

/// The sample standard deviation of replicated values (divisor `R − 1`).
pub(crate) fn sd(v: &[f64]) -> f64 {
    let (_, se) = pf_core::mc::mean_and_se(v);
    se * (v.len() as f64).sqrt()
}

/// File name of the summary in the output directory.
pub const SUMMARY: &str = "summary.json";
/// File name of the self-contained HTML report.
pub const INDEX: &str = "index.html";
/// File name of the Markdown report.
pub const MARKDOWN: &str = "REPORT.md";

/// One report section.
#[derive(Debug, Clone, Copy)]
pub struct Section {
    /// Key in `summary.json` and prefix of `--only` (lower case, no spaces).
    pub name: &'static str,
    /// Human-readable title.
    pub title: &'static str,
    /// Run the section: write its files, return its numbers and captions.
    pub run: fn(&Context<'_>) -> Result<SectionReport>,
}

/// What a section hands back: the numbers for `summary.json` and the captions, tables and
/// notes for `index.html` / `REPORT.md`.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SectionReport {
    /// Every number behind the section's figures and tables, with the config and seed.
    pub result: serde_json::Value,
    /// The figures written, in reading order.
    pub figures: Vec<Figure>,
    /// Tables, each with the paper's values beside ours where the paper has them.
    pub tables: Vec<Table>,
    /// Where our results differ from the paper's, and why; also choices the paper left open.
    pub notes: Vec<String>,
    /// Other files written (`.rrd` recordings, CSV), relative to the output directory.
    pub files: Vec<String>,
    /// JSON pointers into `result` (e.g. `/rmse/seconds_per_run`) to the numbers that depend
    /// on measured wall-clock time (timings, and searches driven by them): the only parts of
    /// `summary.json` that differ between runs with the same seed.
    pub timing_dependent: Vec<String>,
}

/// A figure of the report: a PNG in the output directory and its caption.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Figure {
    /// File name relative to the output directory, e.g. `smooth-fig2-n500.png`.
    pub file: String,
    /// What the figure shows, with the paper's figure number.
    pub caption: String,
}

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

/// What every section gets to know about the run.
#[derive(Debug, Clone, Copy)]
pub struct Context<'a> {
    /// The output directory (already created and proven writable).
    pub out_dir: &'a Path,
    /// The master seed.
    pub seed: u64,
    /// How much work to do.
    pub scale: Scale,
    /// Whether to write `.rrd` recordings.
    pub rrd: RrdOutput,
    /// Progress bars on stderr.
    pub progress: &'a Progress,
}

/// Progress bars on stderr, one per experiment, drawn only when stderr is a terminal.
/// Nothing ever goes to stdout.
#[derive(Debug, Default)]
pub struct Progress {
    multi: MultiProgress,
}

impl Progress {
    /// Bars drawn on stderr (hidden when it is not a terminal).
    pub fn new() -> Self {
        Progress {
            multi: MultiProgress::with_draw_target(ProgressDrawTarget::stderr()),
        }
    }

    /// A new bar of `len` units labelled `label`, with an ETA; finish it with
    /// `finish_and_clear`.
    pub fn bar(&self, label: &str, len: u64) -> ProgressBar {
        let style =
            ProgressStyle::with_template("{prefix:>18} [{bar:30}] {pos}/{len} {msg} (eta {eta})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
        let bar = self.multi.add(ProgressBar::new(len).with_style(style));
        bar.set_prefix(label.to_owned());
        bar
    }
}

impl Context<'_> {
    /// The path of output file `name`.
    pub fn path(&self, name: &str) -> PathBuf {
        self.out_dir.join(name)
    }

    /// Whether `.rrd` recordings are to be written (never without the `rrd` feature).
    pub fn write_rrd(&self) -> bool {
        cfg!(feature = "rrd") && self.rrd == RrdOutput::Write
    }
}

/// A section result as `summary.json` holds it.
///
/// # Errors
/// [`VizError::Json`] if the result cannot be represented as JSON (a non-string map key).
pub fn to_json<T: Serialize>(ctx: &Context<'_>, result: &T) -> Result<serde_json::Value> {
    serde_json::to_value(result).map_err(|source| VizError::Json {
        path: ctx.path(SUMMARY),
        source,
    })
}

/// The contents of `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// `"pf-viz"`.
    pub tool: &'static str,
    /// pf-viz's version.
    pub version: &'static str,
    /// The master seed.
    pub seed: u64,
    /// The scale of the run.
    pub scale: Scale,
    /// Whether `.rrd` recordings were written.
    pub rrd: RrdOutput,
    /// Each section's result, by name.
    pub sections: BTreeMap<&'static str, serde_json::Value>,
    /// Per section, JSON pointers into its result to the numbers that depend on measured
    /// time; everything else is identical for the same seed, whatever `--jobs`.
    pub timing_dependent: BTreeMap<&'static str, Vec<String>>,
}

/// The sections `--only` selects, in registry order; all of them when it is empty.
///
/// # Errors
/// [`VizError::Argument`] naming an unknown section and listing the known ones.
pub fn select(only: &[String]) -> Result<Vec<&'static Section>> {
    for name in only {
        if !SECTIONS.iter().any(|s| s.name == name.trim()) {
            let known: Vec<&str> = SECTIONS.iter().map(|s| s.name).collect();
            return Err(VizError::Argument {
                message: format!(
                    "--only: unknown section {:?}; known sections are {}",
                    name,
                    known.join(",")
                ),
            });
        }
    }
    Ok(SECTIONS
        .iter()
        .filter(|s| only.is_empty() || only.iter().any(|n| n.trim() == s.name))
        .collect())
}

/// Run the selected sections into `args.out`, then write `summary.json`, `index.html` and
/// `REPORT.md`.
///
/// The arguments are checked and the output directory is created and probed first, so bad
/// arguments or an unwritable `--out` fail before any work is done. `--jobs` sizes the rayon
/// pool the Monte Carlo replications run on; results do not depend on it.
///
/// # Errors
/// The first failing section's error, or an I/O error naming the path at fault.
pub fn run(args: &ReportArgs) -> Result<Summary> {
    let selected = select(&args.only)?;
    if let Some(jobs) = args.jobs {
        crate::cli::check_threads("--jobs", jobs as usize)?;
    }
    prepare_out_dir(&args.out)?;
    // The pages are written last: a name among them that cannot be written fails the run
    // before any figure is replaced.
    let pages = [SUMMARY, INDEX, MARKDOWN].map(|f| args.out.join(f));
    check_writable(pages.iter().map(PathBuf::as_path))?;
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(jobs) = args.jobs {
        pool = pool.num_threads(jobs as usize);
    }
    let pool = pool.build().map_err(|e| VizError::Argument {
        message: format!("--jobs: cannot start the worker threads: {e}"),
    })?;
    pool.install(|| run_sections(args, &selected))
}

fn run_sections(args: &ReportArgs, selected: &[&'static Section]) -> Result<Summary> {
    let progress = Progress::new();
    let ctx = Context {
        out_dir: &args.out,
        seed: args.seed,
        scale: args.scale,
        rrd: RrdOutput::from_flag(args.no_rrd),
        progress: &progress,
    };
    let overall = progress.bar("report", selected.len() as u64);
    let mut reports = Vec::with_capacity(selected.len());
    for s in selected {
        overall.set_message(s.title);
        let mut report = (s.run)(&ctx)?;
        for t in &report.tables {
            let file = format!("{}-{}.png", s.name, t.id);
            crate::png::table::render(&ctx.path(&file), t)?;
            report.files.push(file);
        }
        reports.push((**s, report));
        overall.inc(1);
    }
    overall.finish_and_clear();
    let summary = Summary {
        tool: "pf-viz",
        version: env!("CARGO_PKG_VERSION"),
        seed: ctx.seed,
        scale: ctx.scale,
        rrd: ctx.rrd,
        sections: reports
            .iter()
            .map(|(s, r)| (s.name, r.result.clone()))
            .collect(),
        timing_dependent: reports
            .iter()
            .filter(|(_, r)| !r.timing_dependent.is_empty())
            .map(|(s, r)| (s.name, r.timing_dependent.clone()))
            .collect(),
    };
    write_json(&ctx.path(SUMMARY), &summary)?;
    page::write_html(&ctx.path(INDEX), &summary, &reports)?;
    page::write_markdown(&ctx.path(MARKDOWN), &summary, &reports)?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn section_names_are_unique_keys() {
        let mut names: Vec<&str> = SECTIONS.iter().map(|s| s.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), SECTIONS.len());
        assert!(
            names
                .iter()
                .all(|n| n.chars().all(|c| c.is_ascii_lowercase() || c == '_'))
        );
    }
}
