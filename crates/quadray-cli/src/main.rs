//! `quadray`: render scene files to PNG or HDR EXR from the command line.

use clap::Parser;
use std::io::Write;
use std::process::ExitCode;

fn main() -> ExitCode {
    remove_temporaries_on_signals();
    // clap prints its own usage errors and exits with status 2.
    let cli = quadray_cli::args::Cli::parse();
    quadray_cli::logging::init(quadray_cli::logging::level(cli.verbose));
    let is_compare = matches!(cli.command, quadray_cli::args::Command::Compare(_));
    let confined = quadray_cli::apply_confinement(cli.confine.as_deref());
    match confined.and_then(|()| quadray_cli::run(cli)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) if quadray_cli::is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            // `{:#}` prints the whole context chain on one line. A closed stderr loses the
            // message but not the exit status (`eprintln!` would panic: status 101).
            let mut stderr = std::io::stderr().lock();
            let safe = |text: String| quadray_cli::terminal_safe(&text).into_owned();
            let _ = writeln!(stderr, "error: {}", safe(format!("{err:#}")));
            if let Some(snippet) = quadray_cli::snippet::for_error(&err) {
                let _ = writeln!(stderr, "{}", safe(snippet.to_string()));
            }
            ExitCode::from(quadray_cli::exit_status(&err, is_compare))
        }
    }
}

/// Ends the process on SIGINT (Ctrl-C), SIGTERM (`kill`, `timeout`) or SIGHUP (a closed
/// terminal) as those signals would, with status 128 + the signal's number, after deleting the
/// temporary files of outputs being written: older outputs are untouched either way, and no
/// hidden half-written file is left beside them.
#[cfg(unix)]
fn remove_temporaries_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return; // the default actions then stay
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            quadray_loader::atomic_file::remove_pending();
            std::process::exit(128 + signal);
        }
    });
}

#[cfg(not(unix))]
fn remove_temporaries_on_signals() {}
