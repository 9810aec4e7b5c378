//! Progress on stderr for long work (issue 17): a bar over counted work (`vclay pde --frames`,
//! the steps and pictures of `vclay render SCENARIO`) or a spinner with the elapsed time for
//! one long call (`vclay subdivide` at level 3 and above).
//!
//! Drawn only when stderr is a terminal and `--quiet` is not given; otherwise the bars are
//! hidden and cost nothing. Nothing goes to stdout, so results piped from stdout are the same
//! with and without a bar. A bar is cleared when its work ends.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::Duration;

/// Time between redraws of a spinner.
const TICK: Duration = Duration::from_millis(120);

/// Whether progress is drawn: not `--quiet`, and stderr is a terminal.
pub(crate) fn shown() -> bool {
    shown_for(crate::quiet(), std::io::stderr().is_terminal())
}

/// [`shown`] for given `--quiet` and terminal states.
fn shown_for(quiet: bool, stderr_is_terminal: bool) -> bool {
    !quiet && stderr_is_terminal
}

/// A bar over `len` units of work, labelled `what`; hidden unless [`shown`].
pub(crate) fn bar(len: u64, what: &str) -> ProgressBar {
    if !shown() {
        return ProgressBar::hidden();
    }
    let style = ProgressStyle::with_template(
        "{msg} [{bar:30}] {pos}/{len} {elapsed_precise} (about {eta} left)",
    )
    .map_or_else(
        |_| ProgressStyle::default_bar(),
        |s| s.progress_chars("=> "),
    );
    let pb = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    pb.set_style(style);
    pb.set_message(what.to_string());
    pb
}

/// A spinner with the elapsed time for one long call, labelled `what`; hidden unless
/// [`shown`].
pub(crate) fn spinner(what: &str) -> ProgressBar {
    if !shown() {
        return ProgressBar::hidden();
    }
    let style = ProgressStyle::with_template("{spinner} {msg} {elapsed_precise}")
        .unwrap_or_else(|_| ProgressStyle::default_spinner());
    let pb = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    pb.set_style(style);
    pb.set_message(what.to_string());
    pb.enable_steady_tick(TICK);
    pb
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shown_only_on_a_terminal_without_quiet() {
        assert!(shown_for(false, true));
        assert!(!shown_for(true, true));
        assert!(!shown_for(false, false));
        assert!(!shown_for(true, false));
    }

    #[test]
    fn hidden_bars_take_updates() {
        // In tests stderr is captured (not a terminal): the bars are hidden but usable.
        let b = bar(10, "x");
        b.inc(3);
        assert_eq!(b.position(), 3);
        assert!(b.is_hidden());
        b.finish_and_clear();
        let s = spinner("y");
        assert!(s.is_hidden());
        s.finish_and_clear();
    }
}
