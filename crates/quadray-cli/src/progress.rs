//! A row progress bar on stderr, drawn only when stderr is a terminal.

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
        if let Ok(style) =
            ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} rows, eta {eta}")
        {
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
}
