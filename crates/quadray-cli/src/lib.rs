//! The quadray command line as a library: `main` parses arguments and calls [`run`]; tests call
//! [`run_args`] to exercise the same code in process.

pub mod args;
pub mod bench;
pub mod bench_holes;
pub mod bench_images;
pub mod bench_rays;
mod check;
pub mod compare;
pub mod compare_cmd;
mod convert;
pub mod gallery;
mod label;
pub mod output;
pub mod passes;
mod progress;
pub mod quadric_cmd;
mod render_cmd;
pub mod showcase;

use clap::Parser;

/// Runs a parsed command line.
pub fn run(cli: args::Cli) -> anyhow::Result<()> {
    match cli.command {
        args::Command::Render(a) => render_cmd::run(&a),
        args::Command::Check(a) => check::run(&a),
        args::Command::Convert(a) => convert::run(&a),
        args::Command::Bench(b) => bench::run(&b),
        args::Command::Quadric(a) => quadric_cmd::run(&a),
        args::Command::Gallery(a) => gallery::run(&a),
        args::Command::Compare(a) => compare_cmd::run(&a),
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
