//! The progress output of the benches and the command line: one bar style and one spinner, so
//! every long step looks alike. Here rather than in `cli` so that the benches, a lower room, can
//! use them too.

use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// A progress bar of `len` steps (hidden when `quiet`): elapsed time, the bar, the count, the time
/// left and the message.
pub fn bar(quiet: bool, len: u64) -> ProgressBar {
    let pb = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(len)
    };
    pb.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} ({eta} left) {msg}")
            .expect("static template")
            .progress_chars("=> "),
    );
    pb
}

/// A spinner showing `msg` and the elapsed time (hidden when `quiet`), for a step of unknown
/// length.
pub fn spinner(quiet: bool, msg: String) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("static template"),
    );
    pb.set_message(msg);
    // Ticks on its own: the step it waits on reports no progress.
    pb.enable_steady_tick(Duration::from_millis(120));
    pb
}
