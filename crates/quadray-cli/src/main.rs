//! `quadray`: render scene files to PNG or HDR EXR from the command line.

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = quadray_cli::args::Cli::parse();
    match quadray_cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // `{:#}` prints the whole context chain on one line.
            eprintln!("error: {err:#}");
            ExitCode::from(1)
        }
    }
}
