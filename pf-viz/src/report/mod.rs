//! `pf-viz report`: run every section and assemble `summary.json`.
//!
//! A section is one paper (plus [`core`], the engine's own demo). It runs its experiments,
//! writes its figures and recordings into the output directory and returns a
//! [`SectionReport`]: every number behind them (for `summary.json`), plus the captions,
//! tables and notes that `index.html` and `REPORT.md` show. Adding a paper = one file in
//! `report/` plus one line in [`SECTIONS`].
//!
//! The report takes plain [`Options`] (the CLI converts its arguments into them). A section
//! that fails costs only itself: the others are still written, and the pages and
//! `summary.json` name the failure.

pub mod core;
pub mod dredge;
pub mod epf;
pub mod homotopy;
pub mod mpf;
pub mod smooth;

mod page;

use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::error::{Result, VizError, check_threads};
pub use crate::figure::Table;
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

/// Sections that every MPI rank runs whole ([`pf_core::mc::dist::local`]) instead of
/// dealing their studies to ranks: `mpf`, whose Table II sizes each partition's Monte
/// Carlo study by measured time, which differs between ranks. Its studies take seconds
/// at every scale.
pub const RANK_LOCAL: &[&str] = &["mpf"];

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

/// What `pf-viz report` is asked to do, however it was asked (the CLI converts its
/// arguments into this).
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// The output directory (created if missing; must be writable).
    pub out: PathBuf,
    /// The master seed; every section derives its random streams from it.
    pub seed: u64,
    /// How much Monte Carlo work to do.
    pub scale: Scale,
    /// The sections to run, by name; all of them when empty.
    pub only: Vec<String>,
    /// Worker threads for the Monte Carlo replications, 1 to
    /// [`MAX_THREADS`](crate::error::MAX_THREADS) (default: all cores). Results do not
    /// depend on it.
    pub jobs: Option<usize>,
    /// Whether to write Rerun `.rrd` recordings.
    pub rrd: RrdOutput,
}

/// Whether `.rrd` recordings are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RrdOutput {
    /// Write them (when pf-viz is built with the `rrd` feature).
    Write,
    /// Skip them.
    Skip,
}

impl RrdOutput {
    /// From the `--no-rrd` flag and the build: `Skip` if either says so.
    pub fn from_flag(no_rrd: bool) -> Self {
        if no_rrd || !cfg!(feature = "rrd") {
            RrdOutput::Skip
        } else {
            RrdOutput::Write
        }
    }
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

/// Progress bars on stderr, one per experiment, drawn only when stderr is a terminal and
/// only on MPI rank 0 (see [`Bar`]). Nothing ever goes to stdout.
#[derive(Debug, Default)]
pub struct Progress {
    multi: MultiProgress,
}

impl Progress {
    /// Bars drawn on stderr (hidden when it is not a terminal, and on MPI ranks other
    /// than 0).
    pub fn new() -> Self {
        let target = if pf_core::mc::dist::is_root() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        Progress {
            multi: MultiProgress::with_draw_target(target),
        }
    }

    /// A new bar of `len` units labelled `label`, with an ETA; finish it with
    /// [`Bar::finish_and_clear`].
    pub fn bar(&self, label: &str, len: u64) -> Bar {
        let style =
            ProgressStyle::with_template("{prefix:>18} [{bar:30}] {pos}/{len} {msg} (eta {eta})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
        let bar = self.multi.add(ProgressBar::new(len).with_style(style));
        bar.set_prefix(label.to_owned());
        Bar {
            bar,
            len,
            done: Mutex::new(0.0),
        }
    }
}

/// One progress bar. In an MPI run rank 0 sees only its own share of a study's
/// replications, so a tick counted while a study is dealt to ranks counts
/// [`progress_weight`](pf_core::mc::dist::progress_weight) times (the study's replications
/// over rank 0's share): the bar shows the whole study's progress, reaching its end when rank
/// 0's share is done. Without MPI every tick counts once.
#[derive(Debug)]
pub struct Bar {
    bar: ProgressBar,
    len: u64,
    /// Weighted ticks so far.
    done: Mutex<f64>,
}

impl Bar {
    /// Count `delta` ticks.
    pub fn inc(&self, delta: u64) {
        let w = pf_core::mc::dist::progress_weight();
        let mut done = self.done.lock().unwrap_or_else(PoisonError::into_inner);
        *done += delta as f64 * w;
        self.bar.set_position((done.round() as u64).min(self.len));
    }

    /// Show `msg` beside the bar.
    pub fn set_message(&self, msg: impl Into<std::borrow::Cow<'static, str>>) {
        self.bar.set_message(msg);
    }

    /// Remove the bar.
    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
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
    /// The sections that failed, each with its one-line error; absent when none did.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub failed: BTreeMap<&'static str, String>,
}

/// What became of one section: its report, or the one-line error it failed with.
pub type Outcome = std::result::Result<SectionReport, String>;

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

/// Run the selected sections into `opts.out`, then write `summary.json`, `index.html` and
/// `REPORT.md`.
///
/// The options are checked and the output directory is created and probed first, so a bad
/// `--only` or `--jobs` or an unwritable `--out` fails before any work is done. `--jobs`
/// sizes the rayon pool the Monte Carlo replications run on; results do not depend on it.
///
/// A failing section (an error or a panic) does not stop the others: every section runs,
/// every one that succeeded is written, and the pages and `summary.json` (under `failed`)
/// give each failure's one-line error.
///
/// # Errors
/// An I/O error naming the path at fault; [`VizError::Sections`], after everything else is
/// written, when any section failed.
pub fn run(opts: &Options) -> Result<Summary> {
    let selected = select(&opts.only)?;
    if let Some(jobs) = opts.jobs {
        check_threads("--jobs", jobs)?;
    }
    prepare_out_dir(&opts.out)?;
    // The pages are written last: a name among them that cannot be written fails the run
    // before any figure is replaced.
    let pages = [SUMMARY, INDEX, MARKDOWN].map(|f| opts.out.join(f));
    check_writable(pages.iter().map(PathBuf::as_path))?;
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(jobs) = opts.jobs {
        pool = pool.num_threads(jobs);
    }
    let pool = pool.build().map_err(|e| VizError::Argument {
        message: format!("--jobs: cannot start the worker threads: {e}"),
    })?;
    let summary = pool.install(|| run_sections(opts, &selected))?;
    if summary.failed.is_empty() {
        Ok(summary)
    } else {
        Err(VizError::Sections {
            out: opts.out.clone(),
            ran: selected.len(),
            failed: selected
                .iter()
                .filter_map(|s| Some((s.name.to_owned(), summary.failed.get(s.name)?.clone())))
                .collect(),
        })
    }
}

/// Run `section` and render its tables; an error or a panic becomes its one-line message.
fn run_section(ctx: &Context<'_>, section: &Section) -> Outcome {
    let run = || -> Result<SectionReport> {
        let mut report = (section.run)(ctx)?;
        for t in &report.tables {
            let file = format!("{}-{}.png", section.name, t.id);
            crate::png::table::render(&ctx.path(&file), t)?;
            report.files.push(file);
        }
        Ok(report)
    };
    match catch_unwind(AssertUnwindSafe(run)) {
        Ok(Ok(report)) => Ok(report),
        Ok(Err(e)) => Err(one_line(&e.to_string())),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown cause".to_owned());
            Err(one_line(&format!("{}: panicked: {what}", section.name)))
        }
    }
}

/// `s` on one line.
fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

fn run_sections(opts: &Options, selected: &[&'static Section]) -> Result<Summary> {
    let progress = Progress::new();
    let ctx = Context {
        out_dir: &opts.out,
        seed: opts.seed,
        scale: opts.scale,
        rrd: opts.rrd,
        progress: &progress,
    };
    let overall = progress.bar("report", selected.len() as u64);
    let mut outcomes: Vec<(Section, Outcome)> = Vec::with_capacity(selected.len());
    for s in selected {
        overall.set_message(s.title);
        let outcome = if RANK_LOCAL.contains(&s.name) {
            pf_core::mc::dist::local(|| run_section(&ctx, s))
        } else {
            run_section(&ctx, s)
        };
        outcomes.push((**s, outcome));
        overall.inc(1);
    }
    overall.finish_and_clear();
    let done = || {
        outcomes
            .iter()
            .filter_map(|(s, o)| o.as_ref().ok().map(|r| (s, r)))
    };
    let summary = Summary {
        tool: "pf-viz",
        version: env!("CARGO_PKG_VERSION"),
        seed: ctx.seed,
        scale: ctx.scale,
        rrd: ctx.rrd,
        sections: done().map(|(s, r)| (s.name, r.result.clone())).collect(),
        timing_dependent: done()
            .filter(|(_, r)| !r.timing_dependent.is_empty())
            .map(|(s, r)| (s.name, r.timing_dependent.clone()))
            .collect(),
        failed: outcomes
            .iter()
            .filter_map(|(s, o)| o.as_ref().err().map(|e| (s.name, e.clone())))
            .collect(),
    };
    // Only rank 0 writes (the other ranks' figures were never written, and the HTML page
    // reads them back).
    if pf_core::mc::dist::is_root() {
        write_json(&ctx.path(SUMMARY), &summary)?;
        page::write_html(&ctx.path(INDEX), &summary, &outcomes)?;
        page::write_markdown(&ctx.path(MARKDOWN), &summary, &outcomes)?;
    }
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

    fn failing(_: &Context<'_>) -> Result<SectionReport> {
        Err(VizError::Argument {
            message: "broken: failed on purpose\nover two lines".into(),
        })
    }

    fn panicking(_: &Context<'_>) -> Result<SectionReport> {
        panic!("panicked on purpose")
    }

    static BROKEN: Section = Section {
        name: "broken",
        title: "a section that fails",
        run: failing,
    };
    static PANICS: Section = Section {
        name: "panics",
        title: "a section that panics",
        run: panicking,
    };

    /// An error and a panic each cost only their own section: the sections around them are
    /// written, and the summary and both pages give each failure on one line.
    #[test]
    fn a_failing_section_costs_only_itself() {
        let out = std::env::temp_dir().join(format!("pf-viz-failing-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(&out).unwrap();
        let opts = Options {
            out: out.clone(),
            seed: 1,
            scale: Scale::Quick,
            only: Vec::new(),
            jobs: Some(1),
            rrd: RrdOutput::Skip,
        };
        let summary = run_sections(&opts, &[&BROKEN, &core::SECTION, &PANICS]).unwrap();
        assert_eq!(
            summary.sections.keys().copied().collect::<Vec<_>>(),
            ["core"]
        );
        assert_eq!(
            summary.failed.get("broken").map(String::as_str),
            Some("broken: failed on purpose over two lines")
        );
        assert_eq!(
            summary.failed.get("panics").map(String::as_str),
            Some("panics: panicked: panicked on purpose")
        );
        for f in ["genealogy.png", "ess.png", SUMMARY, INDEX, MARKDOWN] {
            assert!(out.join(f).is_file(), "{f} missing");
        }
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(SUMMARY)).unwrap()).unwrap();
        assert_eq!(
            json["failed"]["panics"],
            "panics: panicked: panicked on purpose"
        );
        assert!(json["sections"]["core"].is_object());
        let html = std::fs::read_to_string(out.join(INDEX)).unwrap();
        let md = std::fs::read_to_string(out.join(MARKDOWN)).unwrap();
        for page in [&html, &md] {
            assert!(page.contains("broken: failed on purpose over two lines"));
            assert!(page.contains("panics: panicked: panicked on purpose"));
            assert!(page.contains("genealogy.png"));
        }
        std::fs::remove_dir_all(&out).unwrap();
    }

    /// With nothing failed, `summary.json` has no `failed` key: its shape is unchanged.
    #[test]
    fn no_failed_key_without_failures() {
        let summary = Summary {
            tool: "pf-viz",
            version: "0",
            seed: 1,
            scale: Scale::Quick,
            rrd: RrdOutput::Skip,
            sections: BTreeMap::new(),
            timing_dependent: BTreeMap::new(),
            failed: BTreeMap::new(),
        };
        let json = serde_json::to_value(&summary).unwrap();
        let mut keys: Vec<&str> = json
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        keys.sort_unstable();
        assert_eq!(
            keys,
            [
                "rrd",
                "scale",
                "sections",
                "seed",
                "timing_dependent",
                "tool",
                "version"
            ]
        );
    }
}
