//! The command line, as clap derive types. Parsing only: [`crate::run`] acts on it.

use std::ffi::OsString;
use std::path::PathBuf;

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};

use crate::error::MAX_THREADS;
use crate::report::{Options, RrdOutput};

/// `pf-viz`: figures, tables and Rerun recordings for the pf papers.
#[derive(Debug, Parser)]
#[command(name = "pf-viz", version, about, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

impl Cli {
    /// The command tree, with negative numbers accepted as option values in every
    /// subcommand: without this clap reads `--sigma-deg -1` as a flag `-1`, and the user
    /// never sees the range check that explains what is wrong with the value.
    pub fn command_tree() -> clap::Command {
        fn allow(c: clap::Command) -> clap::Command {
            c.allow_negative_numbers(true).mut_subcommands(allow)
        }
        allow(Cli::command())
    }

    /// Parse `args` (the first is the program name) against [`Cli::command_tree`].
    ///
    /// # Errors
    /// clap's usage errors, and `--help` or `--version` (as clap reports them).
    pub fn try_parse_args<I, T>(args: I) -> Result<Cli, clap::Error>
    where
        I: IntoIterator<Item = T>,
        T: Into<OsString> + Clone,
    {
        let mut tree = Self::command_tree();
        let matches = tree.try_get_matches_from_mut(args)?;
        Cli::from_arg_matches(&matches).map_err(|e| e.format(&mut tree))
    }
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run every report section and write its figures, recordings and summary.json.
    Report(ReportArgs),
    /// Measure the speed of the engine on this machine.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Cappé & Moulines: smoothed sum functionals, EM, SEM and the score.
    #[command(subcommand)]
    Smooth(crate::cmd::smooth::SmoothCommand),
    /// Karlsson, Schön & Gustafsson: marginalized particle filter and its complexity.
    #[command(subcommand)]
    Mpf(crate::cmd::mpf::MpfCommand),
    /// Morelande et al.: optimal homotopy filter for bearings-only tracking.
    #[command(subcommand)]
    Homotopy(crate::cmd::homotopy::HomotopyCommand),
    /// Babuška et al.: overflow losses of a hopper dredger.
    #[command(subcommand)]
    Dredge(crate::cmd::dredge::DredgeCommand),
    /// El Abed et al.: energetic particle filter for multiple targets.
    #[command(subcommand)]
    Epf(crate::cmd::epf::EpfCommand),
}

/// `pf-viz bench …`.
#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// The AR(1)+noise bootstrap filter (φ=0.98, σ=0.2, ρ=1), resampling at every step.
    Bootstrap(BenchBootstrapArgs),
    /// Memory of pruned path storage (every living trajectory) over a long run.
    Genealogy(BenchGenealogyArgs),
    /// A papers' filter on the batch engine: the AR(1) bootstrap filter, Karlsson et al.'s
    /// radar PF (model (13), every state in the PF) or Morelande et al.'s bearings-only PF
    /// (linearised optimal proposal).
    Filter(BenchFilterArgs),
}

/// The models of `pf-viz bench filter`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchModel {
    /// Cappé & Moulines' AR(1)+noise (φ=0.98, σ=0.2, ρ=1), diffuse prior N(Y_0, ρ²).
    Ar1,
    /// Karlsson, Schön & Gustafsson's 6-state radar model (13), the standard PF (PPPPPP).
    Radar,
    /// Morelande et al.'s bearings-only scenario, the PF with the linearised optimal proposal.
    Bearings,
}

/// Arguments of `pf-viz bench filter`.
#[derive(Debug, Clone, Args)]
pub struct BenchFilterArgs {
    /// Which filter.
    #[arg(long, value_enum)]
    pub model: BenchModel,
    /// Data to filter instead of a simulated scenario: for `ar1` a CSV with a `y` column
    /// (Y_0…Y_n), for `radar` one with `range` and `azimuth` columns (one row per step; a
    /// row with both empty is a missing measurement). Other columns are ignored.
    #[arg(long, value_name = "FILE.csv")]
    pub data: Option<PathBuf>,
    /// Number of particles N.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub particles: usize,
    /// Steps n (default: 500 for ar1, 100 for radar, 40 for bearings, or all the data).
    #[arg(long, value_name = "n")]
    pub steps: Option<usize>,
    /// Worker threads within each step (1 to 1024).
    #[arg(long, value_name = "T", default_value_t = 1, value_parser = thread_count())]
    pub threads: usize,
    /// Seed of the simulated data and of the filter's streams.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Runs of the filter, each from the start with the same seed (so the same estimate):
    /// `seconds` is the fastest.
    #[arg(long, value_name = "R", default_value_t = 1)]
    pub repeat: usize,
    /// Which compiled kernels run: `auto` (the widest this CPU runs: AVX-512, else AVX2 with
    /// FMA, else portable), at most `avx2`, or `portable`, to see what a CPU without the
    /// wider ones pays. The estimate is the same bits; the JSON's `kernels` says which ran.
    #[arg(long, value_name = "KERNELS", default_value_t = pf_core::simd::Simd::Auto)]
    pub simd: pf_core::simd::Simd,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz bench genealogy`.
#[derive(Debug, Clone, Args)]
pub struct BenchGenealogyArgs {
    /// Number of particles N.
    #[arg(long, value_name = "N", default_value_t = 100_000)]
    pub particles: usize,
    /// Number of steps n.
    #[arg(long, value_name = "n", default_value_t = 10_000)]
    pub steps: usize,
    /// Seed of the simulated data and of the filter.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz bench bootstrap`.
#[derive(Debug, Clone, Args)]
pub struct BenchBootstrapArgs {
    /// CSV file with a `y` column holding Y_0…Y_n; without it, n observations are simulated.
    #[arg(long, value_name = "FILE.csv")]
    pub data: Option<PathBuf>,
    /// Number of particles N.
    #[arg(long, value_name = "N", default_value_t = 100_000)]
    pub particles: usize,
    /// Number of steps n after Y_0 (default 500, or all the data).
    #[arg(long, value_name = "n")]
    pub steps: Option<usize>,
    /// Worker threads within each step (1 to 1024).
    #[arg(long, value_name = "T", default_value_t = 1, value_parser = thread_count())]
    pub threads: usize,
    /// Resampling scheme.
    #[arg(long, default_value = "systematic")]
    pub resampler: pf_core::resample::Resampler,
    /// Seed of the simulated data and of the filter's streams.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Runs of the filter, each from the start with the same seed (so the same estimate):
    /// `seconds` is the fastest, which is the least disturbed by other work on the machine.
    #[arg(long, value_name = "R", default_value_t = 1)]
    pub repeat: usize,
    /// Which compiled kernels run: `auto` (the widest this CPU runs: AVX-512, else AVX2 with
    /// FMA, else portable), at most `avx2`, or `portable`, to see what a CPU without the
    /// wider ones pays. The estimate is the same bits; the JSON's `kernels` says which ran.
    #[arg(long, value_name = "KERNELS", default_value_t = pf_core::simd::Simd::Auto)]
    pub simd: pf_core::simd::Simd,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `pf-viz report`.
#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Output directory (created if missing; must be writable).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Master seed; every section derives its random streams from it.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// How much Monte Carlo work to do: `quick` (a smoke test: seconds, noisy figures),
    /// `default` (the standard report) or `full` (the papers' own replication counts).
    #[arg(long, value_name = "SCALE", default_value = "default")]
    pub scale: pf_core::mc::Scale,
    /// Run only these sections (comma-separated): `core` (the engine's genealogy),
    /// `smooth`, `mpf`, `homotopy`, `dredge`, `epf`; e.g. `smooth,epf`.
    #[arg(long, value_name = "SECTIONS", value_delimiter = ',')]
    pub only: Vec<String>,
    /// Worker threads for Monte Carlo replications, 1 to 1024 (default: all cores).
    /// Results do not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_THREADS as i64))]
    pub jobs: Option<u32>,
    /// Do not write Rerun `.rrd` recordings.
    #[arg(long)]
    pub no_rrd: bool,
}

impl From<ReportArgs> for Options {
    fn from(a: ReportArgs) -> Self {
        Options {
            out: a.out,
            seed: a.seed,
            scale: a.scale,
            only: a.only,
            jobs: a.jobs.map(|j| j as usize),
            rrd: RrdOutput::from_flag(a.no_rrd),
        }
    }
}

/// The parser of `--threads`: 1 to [`MAX_THREADS`], refused by clap as a usage error.
fn thread_count() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::new().range(1..=MAX_THREADS as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cli_is_well_formed() {
        Cli::command_tree().debug_assert();
    }

    /// A negative number reaches the value's own check (here u64 parsing), never clap's
    /// "unexpected argument" for a flag of that name.
    #[test]
    fn negative_numbers_are_values() {
        let e =
            Cli::try_parse_args(["pf-viz", "report", "--out", "x", "--seed", "-1"]).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::ValueValidation, "{e}");
    }

    #[test]
    fn report_defaults() {
        let cli = Cli::try_parse_args(["pf-viz", "report", "--out", "x"]).unwrap();
        let Command::Report(a) = cli.command else {
            panic!("parsed as another subcommand")
        };
        assert_eq!(a.seed, 1);
        assert!(!a.no_rrd);
        let o = Options::from(a);
        assert_eq!((o.seed, o.jobs, o.only.len()), (1, None, 0));
        assert_eq!(o.rrd, RrdOutput::from_flag(false));
        assert!(Cli::try_parse_args(["pf-viz", "report"]).is_err());
        assert!(Cli::try_parse_args(["pf-viz", "report", "--out", "x", "--seed", "-3"]).is_err());
    }

    /// Thread counts beyond [`MAX_THREADS`] are usage errors, before any pool is built.
    #[test]
    fn thread_counts_are_bounded() {
        let parse = |args: &[&str]| Cli::try_parse_args([&["pf-viz"][..], args].concat());
        let max = MAX_THREADS.to_string();
        let over = (MAX_THREADS + 1).to_string();
        assert!(parse(&["bench", "bootstrap", "--threads", &max]).is_ok());
        assert!(parse(&["report", "--out", "x", "--jobs", &max]).is_ok());
        for args in [
            &["bench", "bootstrap", "--threads", &over][..],
            &["bench", "bootstrap", "--threads", "0"][..],
            &["report", "--out", "x", "--jobs", &over][..],
            &["report", "--out", "x", "--jobs", "4294967295"][..],
        ] {
            let e = parse(args).unwrap_err();
            assert_eq!(e.kind(), clap::error::ErrorKind::ValueValidation, "{e}");
        }
    }
}
