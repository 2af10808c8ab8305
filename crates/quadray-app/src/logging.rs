//! `-v`: a log of what was loaded and how long each phase took, through the `log` facade (the
//! loader logs what it reads; the commands log their phases) and `env_logger` on stderr.

use log::LevelFilter;
use std::io::Write;
use std::time::Instant;

/// The log level `-v` given `count` times asks for: none, info (phases and their timing), debug
/// (every file read), trace.
pub fn level(count: u8) -> LevelFilter {
    match count {
        0 => LevelFilter::Off,
        1 => LevelFilter::Info,
        2 => LevelFilter::Debug,
        _ => LevelFilter::Trace,
    }
}

/// Sends quadray's own log records at `level` to stderr, each line stamped with the seconds since
/// this call (so phase durations read off the log); other crates' records stay silent. Calling it
/// again keeps the first logger.
pub fn init(level: LevelFilter) {
    if level == LevelFilter::Off {
        return;
    }
    let start = Instant::now();
    let _ = env_logger::Builder::new()
        .filter_level(LevelFilter::Off)
        // A prefix: covers quadray, quadray_loader and quadray_cli.
        .filter_module("quadray", level)
        .format(move |out, record| {
            writeln!(
                out,
                "[{:>8.3} s] {}: {}",
                start.elapsed().as_secs_f64(),
                record.level().as_str().to_ascii_lowercase(),
                record.args()
            )
        })
        .target(env_logger::Target::Stderr)
        .try_init();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_v_adds_detail() {
        assert_eq!(level(0), LevelFilter::Off);
        assert_eq!(level(1), LevelFilter::Info);
        assert_eq!(level(2), LevelFilter::Debug);
        assert_eq!(level(7), LevelFilter::Trace);
    }
}
