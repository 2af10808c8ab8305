//! The quadray command line as a library: `main` parses arguments and calls [`run`]; tests call
//! [`run_args`] to exercise the same code in process.

pub mod args;
pub mod bench;
mod check;
mod convert;
pub mod output;
mod progress;
mod render_cmd;

use clap::Parser;

/// Runs a parsed command line.
pub fn run(cli: args::Cli) -> anyhow::Result<()> {
    match cli.command {
        args::Command::Render(a) => render_cmd::run(&a),
        args::Command::Check(a) => check::run(&a),
        args::Command::Convert(a) => convert::run(&a),
        args::Command::Bench(b) => bench::run(&b),
    }
}

/// Parses `args` (without the program name) and runs them; usage errors become errors too.
pub fn run_args<I, S>(args: I) -> anyhow::Result<()>
where
    I: IntoIterator<Item = S>,
    S: Into<std::ffi::OsString> + Clone,
{
    let argv = std::iter::once(std::ffi::OsString::from("quadray"))
        .chain(args.into_iter().map(Into::into));
    run(args::Cli::try_parse_from(argv)?)
}
