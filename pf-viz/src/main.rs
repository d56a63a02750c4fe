//! The `pf-viz` binary: parse the command line, run, and report any error on one line.

use std::process::ExitCode;

use clap::error::ErrorKind;
use pf_viz::cli::Cli;

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

fn main() -> ExitCode {
    let cli = match Cli::try_parse_args(std::env::args_os()) {
        Ok(cli) => cli,
        Err(e) => match e.kind() {
            ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => e.exit(),
            // Bad arguments: one line, exit status 2 (clap's convention for usage errors).
            _ => {
                eprintln!("{}", one_line(&e));
                return ExitCode::from(2);
            }
        },
    };
    match pf_viz::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let msg = e.to_string().replace(['\n', '\r'], " ");
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
