//! The `pf-viz` binary: parse the command line, run, and report any error on one line.

use std::process::ExitCode;

use clap::Parser;
use pf_viz::cli::Cli;

fn main() -> ExitCode {
    // Bad arguments: clap prints its own message and exits with status 2.
    let cli = Cli::parse();
    match pf_viz::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let msg = e.to_string().replace(['\n', '\r'], " ");
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
