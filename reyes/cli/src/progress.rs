//! Progress bars of the command-line tools' long work (`reyes render` of several frames or
//! `--runs N`, `reyes measure`'s reference render, `reyes sweep`, `reyes bench`, the scheduler
//! benchmark suite): an `indicatif` bar with the elapsed time, the count done and an estimate
//! of the time left, drawn on stderr only when stderr is a terminal; otherwise hidden, so that
//! piped or redirected output holds no bar, carriage return or escape code.
//!
//! Every shown bar belongs to one process-wide `MultiProgress`, so that bars of nested work
//! (the sweep's settings and a scene's reference render) stack, and text written while bars
//! are shown goes above them instead of through them: the logger (`logging::init`) writes each
//! record inside [`suspend`], and other stderr lines go through [`note`]. Do not log inside
//! [`suspend`] or `ProgressBar::suspend` of these bars: the record would wait on the lock
//! that `suspend` holds.

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressFinish, ProgressStyle};
use std::io::IsTerminal;
use std::sync::LazyLock;

/// The bars shown at present, drawn on stderr (hidden when stderr is not a terminal).
static BARS: LazyLock<MultiProgress> = LazyLock::new(|| {
    MultiProgress::with_draw_target(if std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    })
});

/// What a bar shows: elapsed time, the bar, done/total, the estimate of the time left (from
/// the recent rate) and `what` is being counted.
pub const TEMPLATE: &str = "{elapsed_precise} [{bar:30}] {pos}/{len} ETA {eta} {wide_msg}";

/// A bar of `len` steps labelled `what` (a message the caller may change later): drawn on
/// stderr when stderr is a terminal, hidden otherwise. Hidden bars cost an atomic add per
/// step. Finish it with `finish_and_clear`; dropped unfinished (an error ended the work), it
/// clears itself too.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    bar_for(len, what, std::io::stderr().is_terminal())
}

/// [`bar`] for a stderr that is (`terminal`) or is not a terminal.
pub fn bar_for(len: u64, what: &str, terminal: bool) -> ProgressBar {
    let bar = styled(len, what);
    if terminal { BARS.add(bar) } else { bar }
}

/// A hidden bar of `len` steps with the style of [`TEMPLATE`].
fn styled(len: u64, what: &str) -> ProgressBar {
    ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden())
        .with_style(
            ProgressStyle::with_template(TEMPLATE)
                .expect("a valid template")
                .progress_chars("=> "),
        )
        .with_message(what.to_string())
        .with_finish(ProgressFinish::AndClear)
}

/// Runs `f` with the bars taken off the terminal, then draws them again; with no bars shown it
/// just runs `f`. For writing to stderr or stdout while bars may be shown.
pub fn suspend<R>(f: impl FnOnce() -> R) -> R {
    BARS.suspend(f)
}

/// Prints `line` on stderr, above the bars when some are shown.
pub fn note(line: impl std::fmt::Display) {
    suspend(|| eprintln!("{line}"));
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    #[test]
    fn hidden_when_stderr_is_not_a_terminal() {
        let b = bar_for(7, "frames", false);
        assert!(b.is_hidden());
        assert_eq!(b.length(), Some(7));
        b.inc(3);
        assert_eq!(b.position(), 3);
    }

    /// A terminal that keeps what is written to it.
    #[derive(Debug, Clone, Default)]
    struct Screen(Arc<Mutex<String>>);

    impl indicatif::TermLike for Screen {
        fn width(&self) -> u16 {
            100
        }
        fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn write_line(&self, s: &str) -> std::io::Result<()> {
            self.write_str(&format!("{s}\n"))
        }
        fn write_str(&self, s: &str) -> std::io::Result<()> {
            self.0.lock().unwrap().push_str(s);
            Ok(())
        }
        fn clear_line(&self) -> std::io::Result<()> {
            Ok(())
        }
        fn flush(&self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_shown_bar_has_the_count_and_an_estimate() {
        let screen = Screen::default();
        let b = styled(10, "frames");
        b.set_draw_target(ProgressDrawTarget::term_like(Box::new(screen.clone())));
        b.inc(3);
        b.abandon();
        let text = screen.0.lock().unwrap().clone();
        assert!(
            text.contains("3/10 ETA ") && text.contains("frames") && text.contains("[======"),
            "{text:?}"
        );
    }
}
