//! Partial rounds: how both multi-pass strategies keep running when a queue at its capacity
//! limit (a memory budget, the device's largest binding) cannot hold a round's worst case.
//!
//! A round normally executes every input. When a target `t` at its limit would receive more
//! than half its capacity in the worst case (`sum_p n_p * emits[p][t]`), only the NEWEST
//! `k_p <= n_p` inputs of each queue `p` run; the older `n_p - k_p` are carried, unchanged, to
//! the front of the next round's inputs of `p`, and the outputs go after them. Running the
//! newest first makes the run go depth first under pressure, as the megakernel's priorities
//! do, so its live work stays near (depth x fanout) instead of the tree's widest level.
//!
//! The plan keeps, for every queue `t`, `(n_t - k_t) + sum_p k_p * emits[p][t] <= cap_t`, so
//! nothing is lost and no append passes a capacity. The `k_p` are chosen in priority order, the
//! last registered procedure first (the megakernel's default: consumers such as dicing before
//! producers such as splitting): each as many as keep every target within HALF its capacity,
//! and at least one when one fits at all. The other half is the room a depth-first descent
//! needs; filling the queues to the brim with inner nodes of one level would leave no room for
//! any of them to expand, a state no later round could leave.
//!
//! The plan makes progress (some `k_p > 0`) exactly when some input can run within the room;
//! otherwise the round is a real overflow and the run fails with `RunError::QueueOverflow`,
//! nothing lost. WGSL twin: `plan_round` in `shaders/multipass.wgsl`.

/// Per queue: true when its capacity has reached its limit (`max_cap`), so it cannot grow.
pub fn at_limit(capacity: &[u32], max_cap: &[u32]) -> Vec<bool> {
    capacity.iter().zip(max_cap).map(|(c, m)| c >= m).collect()
}

/// Per target `t`: the most items a round of `n[p]` inputs per queue may emit to it,
/// `sum_p n[p] * emits[p][t]` (`emits[p][t]`: declared worst case per input of `p`).
pub fn worst_case(n: &[u32], emits: &[Vec<u32>]) -> Vec<u64> {
    (0..n.len())
        .map(|t| (0..n.len()).map(|p| n[p] as u64 * emits[p][t] as u64).sum())
        .collect()
}

/// True when a round must run in part: a target at its limit (`at_limit[t]`) would receive
/// more than half its capacity in the worst case `m[t]`.
pub fn needs_partial(m: &[u64], cap: &[u32], at_limit: &[bool]) -> bool {
    (0..m.len()).any(|t| at_limit[t] && m[t] > (cap[t] / 2) as u64)
}

/// Inputs to run per queue (`k[q] <= n[q]`, the newest ones) so that carried inputs plus
/// worst-case outputs fit every queue's capacity. `n[q]`: inputs of queue `q` this round (each
/// `<= cap[q]`); `emits[p][t]`: declared worst-case items emitted to `t` per input of `p`.
/// `None` when no input of any queue can run within the room.
pub fn partial_round(n: &[u32], cap: &[u32], emits: &[Vec<u32>]) -> Option<Vec<u32>> {
    let nq = n.len();
    // used[t]: slots of t's next-round inputs taken: carried inputs plus planned outputs.
    let mut used: Vec<u64> = n.iter().map(|&x| x as u64).collect();
    let mut k = vec![0u32; nq];
    for p in (0..nq).rev() {
        let (mut hard, mut soft) = (n[p] as u64, n[p] as u64);
        for t in 0..nq {
            // Running one more input of p changes used[t] by emits[p][t] - [t == p].
            let grow = emits[p][t] as u64;
            let shrink = (t == p) as u64;
            if grow > shrink {
                let room = (cap[t] as u64).saturating_sub(used[t]);
                let half_room = (cap[t] as u64 / 2).saturating_sub(used[t]);
                hard = hard.min(room / (grow - shrink));
                soft = soft.min(half_room / (grow - shrink));
            }
        }
        let run = soft.max(hard.min(1));
        k[p] = run as u32;
        for t in 0..nq {
            used[t] += run * emits[p][t] as u64;
        }
        used[p] -= run;
    }
    k.iter().any(|&x| x > 0).then_some(k)
}

#[cfg(test)]
mod tests {
    use super::{needs_partial, partial_round, worst_case};

    /// Carried inputs plus worst-case outputs of the plan, per queue.
    fn used(n: &[u32], k: &[u32], emits: &[Vec<u32>]) -> Vec<u64> {
        let out = worst_case(k, emits);
        (0..n.len())
            .map(|t| (n[t] - k[t]) as u64 + out[t])
            .collect()
    }

    #[test]
    fn a_round_that_fits_in_half_runs_whole() {
        let emits = vec![vec![0, 2], vec![0, 0]];
        assert_eq!(partial_round(&[3, 5], &[16, 16], &emits), Some(vec![3, 5]));
        assert!(!needs_partial(&[6, 0], &[16, 16], &[true, true]));
        assert!(needs_partial(&[9, 0], &[16, 16], &[true, true]));
        assert!(!needs_partial(&[9, 0], &[16, 16], &[false, true]));
    }

    #[test]
    fn a_split_queue_runs_only_what_its_children_fit_and_consumers_go_first() {
        // Queue 0 splits into two of itself and one of queue 1; queue 1 consumes.
        let emits = vec![vec![2, 1], vec![0, 0]];
        let (n, cap) = ([10, 16], [16, 16]);
        let k = partial_round(&n, &cap, &emits).unwrap();
        assert_eq!(k[1], 16, "the consumer runs all its inputs first");
        // Queue 0 is past half full already: one input, which fits, keeps the run going.
        assert_eq!(k[0], 1);
        for (u, c) in used(&n, &k, &emits).iter().zip(cap) {
            assert!(*u <= c as u64);
        }
        // Each split adds one net item to queue 0: 10 + k0 <= 16 (half of 32).
        let k = partial_round(&[10, 0], &[32, 32], &emits).unwrap();
        assert_eq!(k, vec![6, 0]);
    }

    #[test]
    fn no_room_for_any_input_is_none() {
        // A full queue whose every input emits two into a full consumer queue that cannot run.
        let emits = vec![vec![0, 2], vec![0, 2]];
        assert_eq!(partial_round(&[4, 4], &[4, 4], &emits), None);
    }

    #[test]
    fn plans_always_fit_and_progress_when_one_input_can_run() {
        let mut s = 12345u32;
        let mut rand = |m: u32| {
            s = crate::hash::lowbias32(s);
            s % m
        };
        for _ in 0..2000 {
            let nq = 1 + rand(4) as usize;
            let cap: Vec<u32> = (0..nq).map(|_| 1 + rand(40)).collect();
            let n: Vec<u32> = cap.iter().map(|&c| rand(c + 1)).collect();
            let emits: Vec<Vec<u32>> = (0..nq)
                .map(|_| (0..nq).map(|_| rand(4)).collect())
                .collect();
            match partial_round(&n, &cap, &emits) {
                Some(k) => {
                    for (u, &c) in used(&n, &k, &emits).iter().zip(&cap) {
                        assert!(*u <= c as u64, "{n:?} {cap:?} {emits:?} -> {k:?}");
                    }
                    assert!(k.iter().zip(&n).all(|(k, n)| k <= n));
                }
                None => {
                    // No single input of any queue fits on its own.
                    for p in 0..nq {
                        if n[p] == 0 {
                            continue;
                        }
                        let mut one = vec![0; nq];
                        one[p] = 1;
                        let fits = used(&n, &one, &emits)
                            .iter()
                            .zip(&cap)
                            .all(|(u, &c)| *u <= c as u64);
                        assert!(!fits, "{n:?} {cap:?} {emits:?}: queue {p} could run one");
                    }
                }
            }
        }
    }
}
