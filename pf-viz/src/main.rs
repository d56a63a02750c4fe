//! The `pf-viz` binary: parse the command line, run, and report any error on one line.
//!
//! Built with the `mpi` feature and started by `mpirun`/`srun`, every rank runs this same
//! program; the Monte Carlo studies are dealt to ranks ([`pf_core::mc::dist`]) and only rank
//! 0 prints and writes files.

use std::process::ExitCode;
use std::time::Duration;

use clap::error::ErrorKind;
use pf_core::mc::dist;
use pf_viz::cli::{Cli, Command};
use pf_viz::cmd::dredge::DredgeCommand;
use pf_viz::cmd::mpf::MpfCommand;
use pf_viz::{Result, VizError};

/// clap's message without its usage block and `--help` tip, on one line.
fn one_line(e: &clap::Error) -> String {
    e.to_string()
        .lines()
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Whether every rank runs `cmd`'s studies whole rather than dealing them out: Table II
/// sizes its studies by measured time, which differs between ranks.
fn rank_local(cmd: &Command) -> bool {
    matches!(cmd, Command::Mpf(MpfCommand::Table2(_)))
}

/// Refuse what cannot run on several ranks: input from stdin reaches rank 0 alone.
fn check_ranks(cmd: &Command) -> Result<()> {
    if dist::size() > 1
        && let Command::Dredge(DredgeCommand::Estimate(a)) = cmd
        && (a.data.as_os_str() == "-" || a.online)
    {
        return Err(VizError::Argument {
            message: "dredge estimate under MPI: --data must be a file (stdin reaches rank 0 \
                      only), and --online needs one process"
                .into(),
        });
    }
    Ok(())
}

/// How long a rank that failed waits for the others before ending the run itself.
const GRACE: Duration = Duration::from_secs(10);

fn main() -> ExitCode {
    // Kept to the end of `main`: dropping it finalises MPI.
    let session = match dist::install() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let root = dist::is_root();
    let cli = match Cli::try_parse_args(std::env::args_os()) {
        Ok(cli) => cli,
        Err(e) => match e.kind() {
            ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                if root {
                    let _ = e.print();
                }
                return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(1));
            }
            // Bad arguments: one line, exit status 2 (clap's convention for usage errors).
            // Every rank parses the same arguments, so every rank stops here.
            _ => {
                if root {
                    eprintln!("{}", one_line(&e));
                }
                return ExitCode::from(2);
            }
        },
    };
    let local = rank_local(&cli.command);
    let outcome = check_ranks(&cli.command).and_then(|()| {
        if local {
            dist::local(|| pf_viz::run(cli))
        } else {
            pf_viz::run(cli)
        }
    });
    // Every rank meets the others here; one still inside a study means this rank stopped
    // early on an error of its own, and the run is ended for all.
    let together = dist::finish();
    match outcome {
        Ok(()) if together => ExitCode::SUCCESS,
        Ok(()) => {
            if root {
                eprintln!("error: MPI: another rank failed");
            }
            std::thread::sleep(GRACE);
            dist::abort(1)
        }
        Err(e) => {
            let msg = e.to_string().replace(['\n', '\r'], " ");
            if root {
                eprintln!("error: {msg}");
            }
            if together {
                // Every rank failed the same way (a replication's error reaches every rank).
                drop(session);
                return ExitCode::FAILURE;
            }
            if !root {
                // Rank 0 is still inside a study and will not print this rank's error.
                eprintln!("error: MPI rank {}: {msg}", dist::rank());
            }
            dist::abort(1)
        }
    }
}
