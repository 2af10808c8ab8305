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
pub mod shell;
pub mod showcase;
pub mod snippet;
mod warnings;

use clap::Parser;

/// A command line that cannot run as given (options that conflict, a value out of range found
/// after parsing): exit status 2, like clap's own usage errors.
#[derive(Debug)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// `Err(UsageError(message))` unless `condition` holds.
pub fn usage_ensure(condition: bool, message: &str) -> Result<(), UsageError> {
    if condition {
        Ok(())
    } else {
        Err(UsageError(message.to_string()))
    }
}

/// `quadray compare` found the images different beyond its thresholds: exit status 1, as `cmp`
/// and `diff` do.
#[derive(Debug)]
pub struct ImagesDiffer(pub String);

impl std::fmt::Display for ImagesDiffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ImagesDiffer {}

/// The exit status for an error of a run (see [`args::EXIT_STATUS`]): 2 for usage errors (and,
/// for compare, for any trouble other than a difference), else 1.
pub fn exit_status(err: &anyhow::Error, command_is_compare: bool) -> u8 {
    if err.downcast_ref::<UsageError>().is_some() || err.downcast_ref::<clap::Error>().is_some() {
        2
    } else if err.downcast_ref::<ImagesDiffer>().is_some() {
        1
    } else if command_is_compare {
        2
    } else {
        1
    }
}

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
        args::Command::Completions(a) => shell::completions(&a),
        args::Command::Man => shell::man(),
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
