//! A row progress bar on stderr, drawn only when stderr is a terminal; an adaptive render
//! restarts it each round and shows the error still to go.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Shows rendering progress as rows finished.
pub struct RowBar(ProgressBar);

impl RowBar {
    /// A bar over `rows` rows; hidden when `quiet` or when stderr is not a terminal.
    pub fn new(rows: u32, quiet: bool) -> RowBar {
        let target = if quiet {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        };
        let bar = ProgressBar::with_draw_target(Some(rows as u64), target);
        if let Ok(style) = ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} rows, eta {eta} {msg}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        RowBar(bar)
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.0.finish_and_clear();
    }
}

impl quadray::Progress for RowBar {
    fn row_done(&self) {
        self.0.inc(1);
    }

    /// Starts the bar over for the next adaptive round, showing the error still to go.
    fn round_done(&self, round: &quadray::adaptive::RoundSummary) {
        if round.active == 0 {
            return;
        }
        let share = 100.0 * round.active as f64 / round.pixels.max(1) as f64;
        self.0.set_message(match round.rule {
            quadray::adaptive::ErrorRule::Image => format!(
                "round {}: refining {share:.1}% of pixels, estimated error {:.2e} (target {})",
                round.round + 1,
                round.estimated_error,
                round.target_error
            ),
            quadray::adaptive::ErrorRule::Pixel => format!(
                "round {}: {share:.1}% of pixels above error {} (worst {:.3})",
                round.round + 1,
                round.target_error,
                round.worst_error
            ),
        });
        self.0.set_position(0);
    }
}
