//! The CPU metrics' one way of using every core: chunks of a range worked on by rayon's
//! thread pool, each chunk taken by whichever thread is free (chunks differ in cost: a band of
//! sky against a band of silhouettes).

use rayon::prelude::*;
use std::ops::Range;

/// Runs `work` on `0..n` in chunks of `chunk` (at least 1), on all cores; returns each chunk's
/// start and result, in order of the starts.
pub fn in_chunks<T: Send>(
    n: usize,
    chunk: usize,
    work: impl Fn(Range<usize>) -> T + Sync,
) -> Vec<(usize, T)> {
    let chunk = chunk.max(1);
    (0..n.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let at = c * chunk;
            (at, work(at..(at + chunk).min(n)))
        })
        .collect()
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
