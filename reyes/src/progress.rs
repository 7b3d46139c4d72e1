//! How long work reports its steps to whoever shows them: a frame of a sequence finished, a
//! timed frame done, a band of a reference image's rows rendered. The library draws nothing
//! itself; the command-line tools pass a callback that advances their progress bar.

/// Receives "`n` more steps are done" from long work. Any `Fn(u64) + Sync` closure is one
/// (`&|n| bar.inc(n)`); [`NoProgress`] ignores the reports. Calls may come from several
/// threads at once (rows of a reference image are rendered in parallel).
pub trait Progress: Sync {
    /// `n` more steps are done.
    fn advance(&self, n: u64);
}

impl<F: Fn(u64) + Sync> Progress for F {
    fn advance(&self, n: u64) {
        self(n)
    }
}

/// Progress that nobody watches.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn advance(&self, _: u64) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    #[test]
    fn a_closure_receives_every_step_and_no_progress_ignores_them() {
        let done = AtomicU64::new(0);
        let count = |n: u64| {
            done.fetch_add(n, Ordering::Relaxed);
        };
        let p: &dyn Progress = &count;
        p.advance(3);
        p.advance(4);
        NoProgress.advance(5);
        assert_eq!(done.load(Ordering::Relaxed), 7);
    }
}
