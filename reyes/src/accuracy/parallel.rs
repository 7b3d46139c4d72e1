//! The CPU metrics' one way of using every core: chunks of a range handed out to a thread per
//! core as each becomes free (chunks differ in cost: a band of sky against a band of
//! silhouettes).

use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Runs `work` on `0..n` in chunks of `chunk`, on all cores; returns each chunk's start and
/// result, in no particular order.
pub fn in_chunks<T: Send>(
    n: usize,
    chunk: usize,
    work: impl Fn(Range<usize>) -> T + Sync,
) -> Vec<(usize, T)> {
    let chunk = chunk.max(1);
    let next = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .min(n.div_ceil(chunk))
        .max(1);
    std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let at = next.fetch_add(chunk, Ordering::Relaxed);
                        if at >= n {
                            break done;
                        }
                        done.push((at, work(at..(at + chunk).min(n))));
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("a metric worker panicked"))
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_index_is_worked_on_once() {
        let mut parts = in_chunks(1003, 10, |r| r.collect::<Vec<_>>());
        parts.sort_by_key(|p| p.0);
        assert!(parts.iter().all(|(at, r)| r.first() == Some(at)));
        let all: Vec<usize> = parts.into_iter().flat_map(|p| p.1).collect();
        assert_eq!(all, (0..1003).collect::<Vec<_>>());
        assert!(in_chunks(0, 4, |r| r.len()).is_empty());
    }
}
