//! # pf-viz: figures and recordings for the pf papers
//!
//! The `pf-viz` binary runs the experiments of the paper crates and turns their result
//! structs into PNG figures (plotters, headless, embedded font), Rerun recordings (`.rrd`,
//! behind the default feature `rrd`) and one `summary.json`. It draws; it does no
//! statistics.
//!
//! | module | holds |
//! |---|---|
//! | [`cli`] | the clap command line |
//! | [`bench`](mod@bench) | `pf-viz bench bootstrap` |
//! | [`cmd`] | the paper subcommands, one module per paper |
//! | [`data`] | reading observation CSV files |
//! | [`report`] | `pf-viz report`: the registry of sections, one file per paper |
//! | [`figure`] | plain data types that `png` and `rrd` draw and `report` fills |
//! | [`png`] | plot kinds, each a function from plain data to a PNG |
//! | `rrd` | Rerun loggers (feature `rrd`) |
//! | [`io`] | atomic file writes |
//! | [`error`] | [`VizError`], printed by the binary as one line |
//!
//! Dependencies point one way: [`cli`] converts its arguments into [`report::Options`];
//! [`report`] runs the paper crates, fills [`figure`] types and hands them to [`png`] and
//! `rrd`, which depend on neither `report` nor each other. No two files import each other
//! (`tests/tests/module_imports.rs` checks it).

pub mod bench;
pub mod cli;
pub mod cmd;
pub mod data;
pub mod error;
pub mod figure;
pub mod io;
pub mod png;
pub mod report;
#[cfg(feature = "rrd")]
pub mod rrd;

pub use error::{Result, VizError};

use cli::{BenchCommand, Cli, Command};
use cmd::print_line;

/// Execute a parsed command line.
///
/// # Errors
/// Whatever the subcommand fails with; nothing half-written is left behind.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Report(args) => {
            let options = report::Options::from(args);
            let summary = report::run(&options)?;
            print_line(format_args!(
                "pf-viz: wrote {} section(s) to {}",
                summary.sections.len(),
                options.out.display()
            ))?;
            Ok(())
        }
        Command::Bench(BenchCommand::Bootstrap(args)) => {
            let r = bench::bootstrap(&args)?;
            if args.json {
                cmd::print_json(&r)?;
            } else {
                let runs = if r.repeat > 1 {
                    format!(
                        " (fastest of {}; median {:.3} s)",
                        r.repeat, r.seconds_median
                    )
                } else {
                    String::new()
                };
                print_line(format_args!(
                    "bootstrap AR(1): N = {}, n = {}, {} thread(s), {} kernels: {:.3} s{runs}, {:.2} ns per particle-step, log-likelihood {:.3}",
                    r.particles,
                    r.steps,
                    r.threads,
                    r.kernels,
                    r.seconds,
                    r.ns_per_particle_step,
                    r.loglik
                ))?;
            }
            Ok(())
        }
        Command::Bench(BenchCommand::Filter(args)) => {
            let r = bench::filter(&args)?;
            if args.json {
                cmd::print_json(&r)?;
            } else {
                print_line(format_args!(
                    "{} filter: N = {}, {} steps, {} thread(s), {} kernels: {:.3} s (fastest of {}; median {:.3} s), {:.2} ns per particle-step, log-likelihood {:.3}",
                    r.model,
                    r.run.particles,
                    r.run.steps,
                    r.run.threads,
                    r.run.kernels,
                    r.run.seconds,
                    r.run.repeat,
                    r.run.seconds_median,
                    r.run.ns_per_particle_step,
                    r.run.loglik
                ))?;
            }
            Ok(())
        }
        Command::Bench(BenchCommand::Genealogy(args)) => {
            let r = bench::genealogy(&args)?;
            if args.json {
                cmd::print_json(&r)?;
            } else {
                print_line(format_args!(
                    "pruned path storage, N = {}, n = {}: peak {} nodes ({:.1} MB) against {:.1} MB for full storage; peak RSS {}; {:.1} s",
                    r.particles,
                    r.steps,
                    r.peak_nodes,
                    r.tree_peak_bytes as f64 / 1e6,
                    r.full_storage_bytes as f64 / 1e6,
                    r.peak_rss_bytes
                        .map_or("unknown".into(), |b| format!("{:.1} MB", b as f64 / 1e6)),
                    r.seconds
                ))?;
            }
            Ok(())
        }
        Command::Smooth(c) => cmd::smooth::run(c),
        Command::Mpf(c) => cmd::mpf::run(c),
        Command::Homotopy(c) => cmd::homotopy::run(c),
        Command::Dredge(c) => cmd::dredge::run(c),
        Command::Epf(c) => cmd::epf::run(c),
    }
}
