//! `pf-viz report`: run every section and assemble `summary.json`.
//!
//! A section is one paper (plus [`core`], the engine's own demo). It runs its experiment,
//! writes its figures and recordings into the output directory and returns a serde result
//! struct holding every number behind them. Adding a paper = one file in `report/` plus one
//! line in [`SECTIONS`].

pub mod core;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::cli::{ReportArgs, RrdOutput, Scale};
use crate::error::{Result, VizError};
use crate::io::{prepare_out_dir, write_json};

/// Every report section, in the order they run and appear in `summary.json`.
pub const SECTIONS: &[Section] = &[core::SECTION];

/// File name of the summary in the output directory.
pub const SUMMARY: &str = "summary.json";

/// One report section.
#[derive(Debug, Clone, Copy)]
pub struct Section {
    /// Key in `summary.json` and prefix of `--only` (lower case, no spaces).
    pub name: &'static str,
    /// Human-readable title.
    pub title: &'static str,
    /// Run the section: write its files, return its result as JSON.
    pub run: fn(&Context<'_>) -> Result<serde_json::Value>,
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
}

/// Run every section into `args.out` and write `summary.json` last.
///
/// The output directory is created and probed first, so an unwritable `--out` fails before
/// any work is done.
///
/// # Errors
/// The first failing section's error, or an I/O error naming the path at fault.
pub fn run(args: &ReportArgs) -> Result<Summary> {
    prepare_out_dir(&args.out)?;
    let ctx = Context {
        out_dir: &args.out,
        seed: args.seed,
        scale: Scale::Default,
        rrd: RrdOutput::from_flag(args.no_rrd),
    };
    // Drawn only on a terminal; redirected stderr stays clean.
    let bar = ProgressBar::new(SECTIONS.len() as u64).with_style(
        ProgressStyle::with_template("{pos}/{len} {wide_msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut sections = BTreeMap::new();
    for s in SECTIONS {
        bar.set_message(s.title);
        sections.insert(s.name, (s.run)(&ctx)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let summary = Summary {
        tool: "pf-viz",
        version: env!("CARGO_PKG_VERSION"),
        seed: ctx.seed,
        scale: ctx.scale,
        rrd: ctx.rrd,
        sections,
    };
    write_json(&ctx.path(SUMMARY), &summary)?;
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
