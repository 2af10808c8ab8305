//! The quadray command line as a library: `main` parses arguments and calls [`run`]; tests call
//! [`run_args`] to exercise the same code in process.

/// `println!` that returns the write's error instead of panicking: a reader that closed the pipe
/// (`quadray check s.toml | head -1`) ends the command quietly, as in ripgrep (see
/// [`is_broken_pipe`]).
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// `eprintln!` that never panics: with stderr closed (a pipe whose reader has gone) the message
/// is lost and the command goes on, where `eprintln!` would abort it with exit status 101. Control
/// characters in the message are written as escapes ([`terminal_safe`]).
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let message = format!($($arg)*);
        let _ = writeln!(std::io::stderr().lock(), "{}", $crate::terminal_safe(&message));
    }};
}

/// `text` with every control character but the line break and the tab written as an escape
/// (`\u{1b}`): names from a scene (a material, a file, an OBJ group) are echoed in messages, and
/// a scene from a stranger must not be able to move the cursor, clear the screen or retitle the
/// terminal.
pub fn terminal_safe(text: &str) -> std::borrow::Cow<'_, str> {
    let harmful = |c: char| c.is_control() && c != '\n' && c != '\t';
    if !text.chars().any(harmful) {
        return text.into();
    }
    text.chars()
        .map(|c| match c {
            c if harmful(c) => c.escape_unicode().to_string(),
            c => c.to_string(),
        })
        .collect::<String>()
        .into()
}

// The application layer's modules, under the names this crate's commands use for them.
use quadray_app::{compare, exr_file, output, passes, showcase};
pub use quadray_app::{logging, snippet};

pub mod args;
// `quadray bench`: the accuracy oracle, the holes census, the image race and the ray throughput,
// behind the `bench` feature so the shipped binary does not link the test oracle.
#[cfg(feature = "bench")]
pub mod bench;
#[cfg(feature = "bench")]
pub mod bench_holes;
#[cfg(feature = "bench")]
pub mod bench_images;
#[cfg(feature = "bench")]
pub mod bench_rays;
mod check;
pub mod compare_cmd;
mod convert;
pub mod gallery;
mod label;
mod merge_cmd;
mod overwrite;
mod progress;
pub mod quadric_cmd;
pub mod render_cmd;
pub mod sampling_args;
pub mod shell;
pub mod tiles;
mod warnings;

use clap::Parser;

/// `n` and the noun, in the plural unless `n` is 1: "1 plane", "2 planes", "3 meshes".
pub fn counted(n: impl std::fmt::Display, noun: &str) -> String {
    let n = n.to_string();
    let ending = if n == "1" {
        ""
    } else if noun.ends_with("sh") || noun.ends_with("ch") || noun.ends_with('s') {
        "es"
    } else {
        "s"
    };
    format!("{n} {noun}{ending}")
}

/// An error that sets the exit status itself (see [`args::EXIT_STATUS`]); all others exit 1.
#[derive(Debug)]
pub struct StatusError {
    /// The exit status.
    pub status: u8,
    /// What went wrong.
    pub message: String,
}

impl StatusError {
    /// A command line that cannot run as given (options that conflict, a value out of range
    /// found after parsing): status 2, like clap's own usage errors.
    pub fn usage(message: impl Into<String>) -> StatusError {
        StatusError {
            status: 2,
            message: message.into(),
        }
    }

    /// `quadray compare` found the images different beyond its thresholds: status 1, as `cmp`
    /// and `diff` do.
    pub fn images_differ(message: impl Into<String>) -> StatusError {
        StatusError {
            status: 1,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for StatusError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for StatusError {}

/// A usage error ([`StatusError::usage`]) unless `condition` holds.
pub fn usage_ensure(condition: bool, message: &str) -> Result<(), StatusError> {
    if condition {
        Ok(())
    } else {
        Err(StatusError::usage(message))
    }
}

/// The exit status for an error of a run (see [`args::EXIT_STATUS`]): 2 for usage errors (and,
/// for compare, for any trouble other than a difference), else 1.
pub fn exit_status(err: &anyhow::Error, command_is_compare: bool) -> u8 {
    if let Some(e) = err.downcast_ref::<StatusError>() {
        e.status
    } else if err.downcast_ref::<clap::Error>().is_some()
        || err
            .downcast_ref::<quadray_app::scene_file::UsageError>()
            .is_some()
        || command_is_compare
        || is_override_error(err)
    {
        2
    } else {
        1
    }
}

/// Whether `err` is a `--set` override that names no place of its scene: a usage error.
fn is_override_error(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        cause
            .downcast_ref::<quadray_loader::LoadError>()
            .is_some_and(|e| matches!(e.kind, quadray_loader::LoadErrorKind::Override { .. }))
    })
}

/// `printed`, with a reader that closed the pipe taken as success: for output printed before
/// work that must still happen (a comparison's verdict, a report's files).
pub fn unless_pipe_closed(printed: std::io::Result<()>) -> std::io::Result<()> {
    match printed {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => other,
    }
}

/// Whether `err` comes from writing to a pipe whose reader has gone: the command's output is
/// unwanted, not wrong, so `main` exits quietly with success, as ripgrep does.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Confines the process's file access as `--confine DIR` or, without it, the `QUADRAY_CONFINE`
/// environment variable asks ([`quadray_loader::confine`]); a folder that does not exist is a
/// usage error. Called by `main` only: the setting holds for the whole process.
pub fn apply_confinement(flag: Option<&std::path::Path>) -> anyhow::Result<()> {
    let from_env = std::env::var_os(quadray_loader::confine::ENV).filter(|v| !v.is_empty());
    let dir = match (flag, &from_env) {
        (Some(dir), _) => dir.to_path_buf(),
        (None, Some(dir)) => std::path::PathBuf::from(dir),
        (None, None) => return Ok(()),
    };
    let root =
        quadray_loader::confine::confine_to(&dir).map_err(|e| StatusError::usage(e.to_string()))?;
    log::info!("confined to {}", root.display());
    Ok(())
}

/// Runs a parsed command line.
pub fn run(cli: args::Cli) -> anyhow::Result<()> {
    check_simd_variable()?;
    match cli.command {
        args::Command::Render(a) => render_cmd::run(&a),
        args::Command::Check(a) => check::run(&a),
        args::Command::Convert(a) => convert::run(&a),
        #[cfg(feature = "bench")]
        args::Command::Bench(b) => bench::run(&b),
        args::Command::Quadric(a) => quadric_cmd::run(&a),
        args::Command::Gallery(a) => gallery::run(&a),
        args::Command::Compare(a) => compare_cmd::run(&a),
        args::Command::Merge(a) => merge_cmd::run(&a),
        args::Command::Completions(a) => shell::completions(&a),
        args::Command::Man => shell::man(),
    }
}

/// Refuses a `QUADRAY_SIMD` other than `baseline` or `auto` (or empty), which would otherwise be
/// ignored without a word: a usage error, as a malformed `QUADRAY_AVAILABLE_MEMORY` is.
fn check_simd_variable() -> Result<(), StatusError> {
    match std::env::var_os("QUADRAY_SIMD") {
        Some(v) if !(v.is_empty() || v == "baseline" || v == "auto") => {
            Err(StatusError::usage(format!(
                "QUADRAY_SIMD={}: its values are `baseline` (the baseline code where AVX2 code \
                 would run) and `auto` (the fastest path the CPU has, as when it is unset)",
                terminal_safe(&v.to_string_lossy())
            )))
        }
        _ => Ok(()),
    }
}

/// Parses `args` (without the program name) and runs them; usage errors become errors too.
/// `--confine` is applied by `main` only (it holds for the whole process): in process it is
/// parsed and ignored.
pub fn run_args<I, S>(args: I) -> anyhow::Result<()>
where
    I: IntoIterator<Item = S>,
    S: Into<std::ffi::OsString> + Clone,
{
    let argv = std::iter::once(std::ffi::OsString::from("quadray"))
        .chain(args.into_iter().map(Into::into));
    run(args::Cli::try_parse_from(argv)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Escapes and other control characters from a scene come out as text; line breaks and
    /// plain text stay.
    #[test]
    fn control_characters_are_written_as_escapes() {
        assert_eq!(
            terminal_safe("plain\nlines\tand tabs"),
            "plain\nlines\tand tabs"
        );
        let hostile = "\u{1b}[2J\u{1b}]0;title\u{7}boom\r";
        let safe = terminal_safe(hostile);
        assert!(!safe.chars().any(|c| c.is_control()), "{safe}");
        assert!(
            safe.contains("\\u{1b}[2J") && safe.contains("boom"),
            "{safe}"
        );
    }

    #[test]
    fn counts_agree_with_their_nouns() {
        assert_eq!(super::counted(1, "plane"), "1 plane");
        assert_eq!(super::counted(0, "plane"), "0 planes");
        assert_eq!(super::counted(3, "mesh"), "3 meshes");
        assert_eq!(super::counted(1, "mesh"), "1 mesh");
    }
}
