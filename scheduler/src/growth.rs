//! How a queue grows when its work does not fit: geometrically, so that a run started far too
//! small pays `O(log2(need / start))` growths, each followed by one relaunch (megakernel) or one
//! resumed round (multi-pass), instead of one relaunch per `start` items.

/// The capacity, in slots, of a queue of `capacity` slots that needs at least `need`: at least
/// double, straight to `need` when that is more, never past `limit` (and never smaller than
/// `capacity`). Doubling is the standard amortized growth of a dynamic array: the copies of all
/// growths together cost at most twice the final size, and `k` growths from `start` reach
/// `start × 2^k`.
pub fn grow(capacity: u32, need: u64, limit: u32) -> u32 {
    (capacity as u64 * 2)
        .max(need)
        .min(limit as u64)
        .max(capacity as u64) as u32
}

/// Slots a run allocates for a queue sized from what an earlier run needed (`need`): an eighth
/// more, within `limit`. A run's need varies a little from run to run where its work does (BFS
/// levels found in a different order append different counts), and every new buffer costs far
/// more than a small run (600-800 MB of queues took 22-45 ms to make on the H200, against
/// 0.4-3.4 ms of BFS; docs/results.md, 2026-12-02): with the slack, a run that needs a little
/// more than the last keeps its buffers ([`kept_capacity`]).
pub fn with_slack(need: u64, limit: u32) -> u32 {
    need.saturating_add(need / 8).min(limit as u64) as u32
}

/// The capacities of the queues kept from the last run (`kept`), when they hold at least
/// `need[q]` slots and at most `limit[q]` for every queue: a run that fits reuses them instead of
/// making buffers of its own size (the capacity of a queue is only room; a larger one changes no
/// result). `None` when there are none or one does not fit.
pub fn kept_capacity(kept: Option<&[u32]>, need: &[u32], limit: &[u32]) -> Option<Vec<u32>> {
    let kept = kept?;
    let fits = kept.len() == need.len()
        && (0..need.len()).all(|q| kept[q] >= need[q] && kept[q] <= limit[q]);
    fits.then(|| kept.to_vec())
}

/// The capacities a multi-pass run starts with: those of the queues kept from its last run
/// when `reuse` (`size_from_last_run`) and they hold `start` ([`kept_capacity`]), else `start`.
pub fn start_capacity(
    reuse: bool,
    kept: Option<&[u32]>,
    start: Vec<u32>,
    limit: &[u32],
) -> Vec<u32> {
    match reuse {
        true => kept_capacity(kept, &start, limit).unwrap_or(start),
        false => start,
    }
}

/// Growth of a multi-pass run's refused rounds, whose cost is a submission: the host waits for
/// it, makes new buffers, and the rounds encoded after the refused one run empty (about as
/// long as a small full round: their dispatches and barriers remain). Each refusal therefore
/// grows the queues for the rounds after it too, by the work's own growth per round measured
/// so far, over a horizon that doubles with every refusal (1, 2, 4, … rounds): work growing
/// geometrically from far too small a start is refused `O(log rounds)` times instead of once
/// every round or two, and the next submission encodes only the rounds the new capacity is
/// expected to hold ([`Anticipation::rounds_until_refusal`]).
#[derive(Debug, Clone)]
pub struct Anticipation {
    /// Worst-case items emitted (all targets) by the last round seen, and the round it was.
    last: (u64, u64),
    refusals: u32,
    /// Growth per round of the worst-case output, `>= 1`.
    per_round: f64,
}

impl Anticipation {
    /// Largest growth per round believed: a larger measured jump (one round of a huge fan-out)
    /// would otherwise grow the queues to their limit at once.
    pub const MAX_PER_ROUND: f64 = 16.0;

    /// Largest factor over the refused round's worst case: every byte of a growth is fresh
    /// device memory, which costs about as much as a refusal per 40 MB on the H200
    /// (docs/results.md, 2026-12-01), so anticipation stops at twice the plain `2 m`.
    pub const MAX_FACTOR: f64 = 4.0;

    /// Bytes a growth may anticipate beyond the plain `2 m` (over all queues).
    pub const MAX_EXTRA_BYTES: u64 = 64 << 20;

    /// Starts from the first round's worst-case output `m0` (from the seeds and the declared
    /// emits, known on the host).
    pub fn new(m0: u64) -> Anticipation {
        Anticipation {
            last: (m0.max(1), 0),
            refusals: 0,
            per_round: 1.0,
        }
    }

    /// Records a refusal of `round` (rounds run before it in the whole run) whose worst-case
    /// output was `m` items (all targets), and returns the factor by which that output should
    /// be multiplied to size the queues: `2 × g^(2^h)` for the `h`-th refusal (from 0) and the
    /// measured growth per round `g`, at most [`Self::MAX_FACTOR`].
    pub fn refused(&mut self, round: u64, m: u64) -> f64 {
        let (m_prev, r_prev) = self.last;
        let rounds = round.saturating_sub(r_prev).max(1) as f64;
        let measured = (m.max(1) as f64 / m_prev as f64).powf(1.0 / rounds);
        self.per_round = measured.clamp(1.0, Self::MAX_PER_ROUND);
        self.last = (m.max(1), round);
        let horizon = 2f64.powi(self.refusals.min(8) as i32);
        self.refusals += 1;
        (2.0 * self.per_round.powf(horizon)).min(Self::MAX_FACTOR)
    }

    /// Rounds a submission should encode after a refused round of worst-case output `m` was
    /// given `capacity` slots (the smallest over its targets, relative to their share of `m`):
    /// the round the growth is expected to be refused next, at most `max`, at least 2; `max`
    /// when the work is not growing.
    pub fn rounds_until_refusal(&self, capacity_over_m: f64, max: u32) -> u32 {
        if self.per_round <= 1.0 + 1e-9 || !capacity_over_m.is_finite() {
            return max;
        }
        let held = (capacity_over_m.max(1.0).ln() / self.per_round.ln()).floor();
        (held + 2.0).clamp(2.0, max as f64) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::{Anticipation, grow, kept_capacity, start_capacity, with_slack};

    #[test]
    fn kept_queues_are_reused_only_when_they_hold_the_need_within_the_limit() {
        let limit = [1000, 1000];
        assert_eq!(kept_capacity(None, &[1, 1], &limit), None);
        assert_eq!(
            kept_capacity(Some(&[512, 64]), &[500, 64], &limit),
            Some(vec![512, 64])
        );
        // One queue short of its need: new buffers.
        assert_eq!(kept_capacity(Some(&[512, 64]), &[500, 65], &limit), None);
        // A budget below the kept room (a run with less memory): new buffers within it.
        assert_eq!(kept_capacity(Some(&[512, 64]), &[1, 1], &[256, 1000]), None);
        assert_eq!(kept_capacity(Some(&[512]), &[1, 1], &limit), None);
        // A multi-pass run: the kept queues when reused and they fit, else its own start.
        let kept: &[u32] = &[512, 64];
        assert_eq!(
            start_capacity(true, Some(kept), vec![16, 16], &limit),
            [512, 64]
        );
        assert_eq!(
            start_capacity(false, Some(kept), vec![16, 16], &limit),
            [16, 16]
        );
        assert_eq!(
            start_capacity(true, Some(kept), vec![16, 128], &limit),
            [16, 128]
        );
        assert_eq!(with_slack(800, 1 << 20), 900);
        assert_eq!(with_slack(800, 850), 850);
        assert_eq!(with_slack(u64::MAX, u32::MAX), u32::MAX);
    }

    #[test]
    fn refusals_anticipate_geometric_growth_over_a_doubling_horizon() {
        // Output doubling per round, first round 160 items.
        let mut a = Anticipation::new(160);
        // Refused at round 2 with 640: growth 2 per round measured; 2 × 2^1.
        assert_eq!(a.refused(2, 640), 4.0);
        // The capacity 4 m holds two more doublings: refusal expected at the 4th round.
        assert_eq!(a.rounds_until_refusal(4.0, 16), 4);
        // Next refusal: horizon 2 rounds, 2 × 2^2.
        assert_eq!(a.refused(5, 5120), Anticipation::MAX_FACTOR);
        assert_eq!(a.refused(8, 40960), Anticipation::MAX_FACTOR);
        // Not growing: full submissions.
        let mut flat = Anticipation::new(100);
        assert_eq!(flat.refused(3, 100), 2.0);
        assert_eq!(flat.rounds_until_refusal(2.0, 16), 16);
        // A huge jump is believed only up to MAX_PER_ROUND per round.
        let mut jump = Anticipation::new(1);
        assert_eq!(jump.refused(1, 1 << 30), Anticipation::MAX_FACTOR);
        // Slow growth anticipates little: 2 x 1.2.
        let mut slow = Anticipation::new(1000);
        assert!((slow.refused(1, 1200) - 2.4).abs() < 1e-12);
    }

    #[test]
    fn growth_doubles_jumps_to_the_need_and_stops_at_the_limit() {
        assert_eq!(grow(16, 0, 1 << 20), 32);
        assert_eq!(grow(16, 17, 1 << 20), 32);
        assert_eq!(grow(16, 1000, 1 << 20), 1000);
        assert_eq!(grow(16, 1000, 500), 500);
        assert_eq!(grow(600, 0, 500), 600);
        assert_eq!(grow(u32::MAX, 0, u32::MAX), u32::MAX);
    }
}
