//! Work set aside on the host while the queues at their limits cannot hold its breadth.
//!
//! A megakernel claims each queue oldest first, so a tree's levels fill its queues breadth
//! first; under a capacity limit (`max_capacity`, the largest binding, a `max_queue_bytes`
//! budget) a launch can end with every live item needing room that no queue has, and nothing
//! run. Rather than report a [`RunError::QueueOverflow`](crate::RunError::QueueOverflow), the
//! host then parks the oldest half of the live items (read back by the host compaction, in
//! ticket order) and relaunches with the newest half, whose descendants now have the room: the
//! run goes depth first under pressure, as the multi-passes' partial rounds do
//! (`multipass::partial`, docs/scheduler.md 5.3). Parked items come back, the most recently
//! parked first, each time a launch finishes all it was given. Only when a single live item
//! cannot run is the overflow reported. Items are independent work (a scheduler promises no
//! order), so the results are those of an unbounded run.

/// Parked items: a stack of chunks, each the items of every queue set aside by one split,
/// back to back in ticket order (`words[q]` words an item).
#[derive(Debug, Default)]
pub(super) struct Parked {
    chunks: Vec<Vec<Vec<u32>>>,
}

impl Parked {
    /// Splits `live` (per queue, items back to back, oldest first): parks the older half of
    /// each queue's items and returns the rest, to run next, with the count parked. With only
    /// single items per queue, parks every queue's item but the last queue's that has one.
    /// `None` when `live` holds at most one item: nothing can be set aside.
    pub(super) fn split(
        &mut self,
        mut live: Vec<Vec<u32>>,
        words: &[u32],
    ) -> Option<(Vec<Vec<u32>>, u64)> {
        let counts: Vec<usize> = (live.iter().zip(words))
            .map(|(l, &w)| l.len() / w as usize)
            .collect();
        if counts.iter().sum::<usize>() <= 1 {
            return None;
        }
        let mut park: Vec<usize> = counts.iter().map(|n| n / 2).collect();
        if park.iter().all(|&p| p == 0) {
            let last = counts.iter().rposition(|&n| n > 0)?;
            for (q, p) in park.iter_mut().enumerate() {
                *p = if q == last { 0 } else { counts[q] };
            }
        }
        let mut chunk = Vec::with_capacity(live.len());
        for (q, l) in live.iter_mut().enumerate() {
            let rest = l.split_off(park[q] * words[q] as usize);
            chunk.push(std::mem::replace(l, rest));
        }
        self.chunks.push(chunk);
        Some((live, park.iter().sum::<usize>() as u64))
    }

    /// The most recently parked chunk, to run when a launch has finished its own items.
    pub(super) fn take(&mut self) -> Option<Vec<Vec<u32>>> {
        self.chunks.pop()
    }
}

/// What to add to the error of a run that used up its launches after parking `parked_items`
/// items: parked work runs in launches of its own, the likely cause.
pub(super) fn launches_hint(parked_items: u64) -> String {
    match parked_items {
        0 => String::new(),
        n => format!(
            " ({n} items were parked on the host because queues at their limits could not \
             hold the work's breadth: a larger `max_launches`, `max_capacity` or memory budget \
             lets it finish)"
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::Parked;

    #[test]
    fn the_older_half_is_parked_and_comes_back_last_in_first_out() {
        let mut p = Parked::default();
        // Queue 0: items of two words (5 of them); queue 1: one word (1 item).
        let live = vec![(0..10).collect::<Vec<u32>>(), vec![100]];
        let (rest, parked) = p.split(live, &[2, 1]).unwrap();
        assert_eq!(parked, 2);
        assert_eq!(rest, vec![vec![4, 5, 6, 7, 8, 9], vec![100]]);
        let (rest, parked) = p.split(rest, &[2, 1]).unwrap();
        assert_eq!(parked, 1);
        assert_eq!(rest, vec![vec![6, 7, 8, 9], vec![100]]);
        assert_eq!(p.take().unwrap(), vec![vec![4, 5], vec![]]);
        assert_eq!(p.take().unwrap(), vec![vec![0, 1, 2, 3], vec![]]);
        assert_eq!(p.take(), None);
    }

    #[test]
    fn single_items_are_parked_but_one_and_one_item_is_not_split() {
        let mut p = Parked::default();
        let (rest, parked) = p.split(vec![vec![1], vec![2], vec![]], &[1, 1, 1]).unwrap();
        assert_eq!((rest, parked), (vec![vec![], vec![2], vec![]], 1));
        assert_eq!(p.split(vec![vec![], vec![2], vec![]], &[1, 1, 1]), None);
        assert_eq!(p.take().unwrap(), vec![vec![1], vec![], vec![]]);
    }
}
