//! What the long runs show on a terminal: a progress bar on stderr.

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar over `len` units on stderr when `show` and stderr is a terminal; hidden
/// otherwise.
pub(crate) fn progress(len: u64, show: bool, what: &str) -> ProgressBar {
    use std::io::IsTerminal;
    if !show || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    let style = ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} {msg}")
        .expect("a valid template")
        .progress_chars("=> ");
    bar.set_style(style);
    bar.set_prefix(what.to_string());
    bar
}
