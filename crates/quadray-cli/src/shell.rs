//! `quadray completions SHELL` and `quadray man`: the shell completion script and the man page,
//! generated from the same clap definitions as the parser, so they never fall out of date.

use crate::args::Cli;
use anyhow::{Context, Result};
use clap::{Args, CommandFactory};
use std::io::Write;

/// Arguments of `quadray completions`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct CompletionsArgs {
    /// The shell to complete for.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// Prints the completion script for `args.shell` on stdout, e.g.
/// `quadray completions bash > ~/.local/share/bash-completion/completions/quadray`.
pub fn completions(args: &CompletionsArgs) -> Result<()> {
    let mut command = Cli::command();
    let mut out = Vec::new();
    clap_complete::generate(args.shell, &mut command, "quadray", &mut out);
    std::io::stdout()
        .write_all(&out)
        .context("writing the completion script")
}

/// Prints the man page (roff) on stdout, e.g. `quadray man > ~/.local/share/man/man1/quadray.1`.
pub fn man() -> Result<()> {
    let mut out = Vec::new();
    clap_mangen::Man::new(Cli::command())
        .render(&mut out)
        .context("rendering the man page")?;
    std::io::stdout()
        .write_all(&out)
        .context("writing the man page")
}
