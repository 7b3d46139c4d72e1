//! Turn anatomy: what a megakernel loop turn spends per phase, counted on the GPU
//! (`MegakernelConfig::turn_anatomy`). WGSL has no clock, so the shader counts, per phase, the
//! global memory operations or loop trips on the turn's critical path (the leader's chain, or the
//! busiest lane's loop); with the run's GPU time and workgroup count these give the mean turn
//! and a latency model (a phase costs about its dependent global round trips times the device's
//! atomic latency). Counters live in lane 0's registers and are added to ctrl words `G_AN..`
//! once per workgroup when it leaves its loop; host twin of the `AN_*` constants in
//! `shaders/megakernel.wgsl`. What each count means: `docs/scheduler.md`, "Turn anatomy".

use super::layout::AN_WORDS;

/// Per-phase counts of a run's megakernel turns, summed over workgroups and launches.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TurnAnatomy {
    /// Loop turns of all workgroups: batches, idle turns and each workgroup's exit turn.
    pub turns: u64,
    /// Global atomics of the claims (idle turns' failed claims included).
    pub claim: u64,
    /// Flag polls before a batch's slots were all published (the slowest lane's, per batch).
    pub wait: u64,
    /// Workgroup steps of procedure bodies.
    pub execute: u64,
    /// Direct enqueue: ticket atomics taken item by item inside the bodies (all lanes).
    pub enqueue: u64,
    /// Global atomics after a batch and before its copy on the longest lane's path (the
    /// outbox's ticket add, a refund of unused promised room), the pending atomic and the FIFO
    /// sequence; the peak statistic's loads are folded in at the next batch, off the path.
    pub reserve: u64,
    /// Loop trips of a lane copying outbox items to the queues.
    pub copy: u64,
    /// Flag-store trips of a lane plus the leader's global atomics that publish (counts, pending).
    pub publish: u64,
}

impl TurnAnatomy {
    /// Adds one launch's counters (the `AN_WORDS` ctrl words from `G_AN`).
    pub(crate) fn add_launch(&mut self, words: &[u32]) {
        debug_assert_eq!(words.len(), AN_WORDS);
        let w = |i: usize| words[i] as u64;
        self.turns += w(0);
        self.claim += w(1);
        self.wait += w(2);
        self.execute += w(3);
        self.enqueue += w(4);
        self.reserve += w(5);
        self.copy += w(6);
        self.publish += w(7);
    }

    /// Adds another run's counters.
    pub fn absorb(&mut self, o: &TurnAnatomy) {
        self.turns += o.turns;
        self.claim += o.claim;
        self.wait += o.wait;
        self.execute += o.execute;
        self.enqueue += o.enqueue;
        self.reserve += o.reserve;
        self.copy += o.copy;
        self.publish += o.publish;
    }

    /// The phases as (name, what is counted, count).
    pub fn phases(&self) -> [(&'static str, &'static str, u64); 7] {
        [
            ("claim", "global atomics", self.claim),
            ("wait", "flag polls", self.wait),
            ("execute", "workgroup steps", self.execute),
            ("enqueue", "ticket atomics", self.enqueue),
            ("reserve", "global atomics", self.reserve),
            ("copy", "loop trips", self.copy),
            ("publish", "trips + atomics", self.publish),
        ]
    }

    /// The counts back from (name, count) pairs as [`TurnAnatomy::phases`] names them, plus
    /// `turns` (what a benchmark record keeps); `None` when a name is unknown.
    pub fn from_named<'a>(pairs: impl IntoIterator<Item = (&'a str, u64)>) -> Option<TurnAnatomy> {
        let mut a = TurnAnatomy::default();
        for (name, n) in pairs {
            *match name {
                "turns" => &mut a.turns,
                "claim" => &mut a.claim,
                "wait" => &mut a.wait,
                "execute" => &mut a.execute,
                "enqueue" => &mut a.enqueue,
                "reserve" => &mut a.reserve,
                "copy" => &mut a.copy,
                "publish" => &mut a.publish,
                _ => return None,
            } = n;
        }
        Some(a)
    }

    /// A table for people: per phase the count per batch and per turn; then the mean turn and
    /// batch times, from `gpu_ms` (the run's GPU time) and `workgroups` (each runs its turns one
    /// after another, so a turn's mean time is GPU time x workgroups / turns).
    pub fn table(&self, batches: u64, workgroups: u32, gpu_ms: Option<f64>) -> String {
        let per = |x: u64, n: u64| {
            if n == 0 {
                "n/a".to_string()
            } else {
                format!("{:.2}", x as f64 / n as f64)
            }
        };
        let mut s = format!(
            "turn anatomy: {} turns, {} batches, {} idle or exit turns, {} workgroup{}\n",
            self.turns,
            batches,
            self.turns.saturating_sub(batches),
            workgroups,
            if workgroups == 1 { "" } else { "s" }
        );
        s += &format!(
            "{:<8} {:<16} {:>12} {:>10} {:>10}\n",
            "phase", "counted", "total", "per batch", "per turn"
        );
        for (name, what, n) in self.phases() {
            s += &format!(
                "{name:<8} {what:<16} {n:>12} {:>10} {:>10}\n",
                per(n, batches),
                per(n, self.turns)
            );
        }
        if let Some(ms) = gpu_ms {
            let busy = ms * 1e3 * workgroups as f64;
            let mean = |n: u64| {
                if n == 0 {
                    "n/a".to_string()
                } else {
                    format!("{:.2} us", busy / n as f64)
                }
            };
            s += &format!(
                "mean turn: {} (GPU time x workgroups / turns); per batch: {}\n",
                mean(self.turns),
                mean(batches)
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn launches_add_up_and_the_table_divides_by_batches_and_turns() {
        let mut a = TurnAnatomy::default();
        a.add_launch(&[10, 40, 8, 6, 0, 30, 4, 12]);
        a.add_launch(&[10, 40, 8, 6, 0, 30, 4, 12]);
        assert_eq!(a.turns, 20);
        assert_eq!(a.claim, 80);
        let t = a.table(16, 2, Some(1.0));
        assert!(
            t.contains("claim    global atomics             80       5.00       4.00"),
            "{t}"
        );
        // 1 ms x 2 workgroups over 20 turns.
        assert!(t.contains("mean turn: 100.00 us"), "{t}");
        assert!(a.table(0, 1, None).contains("n/a"));
        let mut named: Vec<(&str, u64)> = a.phases().iter().map(|p| (p.0, p.2)).collect();
        named.push(("turns", a.turns));
        assert_eq!(TurnAnatomy::from_named(named), Some(a));
        assert_eq!(TurnAnatomy::from_named([("nap", 1)]), None);
    }
}
