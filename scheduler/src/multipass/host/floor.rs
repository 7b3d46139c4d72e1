//! The multi-pass floor (`multipass-floor`): the host-driven multi-pass with perfect foresight.
//!
//! A run of new seeds is an ordinary host-driven run that also reads back, round by round,
//! the items each procedure executed. A later run of the same seeds replays them: every item
//! the first run executed, each procedure's in one dispatch, all in one round (one pass, or one
//! pass per procedure with stage timing). Children are still appended, as in any round, but no
//! round follows, so every item runs exactly once, as in the run that was kept, and the user's
//! results are the same wherever a body's effects do not depend on the order items run in
//! (the tree's leaf counts, Reyes' depth-tested samples). The replay's GPU time is the work of
//! the bodies with the scheduling taken out: no rounds, no dispatch per round and procedure, no
//! tail of a small round. No multi-pass running these bodies can be faster, so it says how much
//! of a multi-pass's time its rounds cost and what a scheduler could gain over it at most
//! (a megakernel can still beat it by overlapping procedures and using items while they are in
//! cache; docs/scheduler.md 5.4).
//!
//! It is a reference for benchmarks, not a strategy to render with: a replay does the work of
//! the kept run, whatever the user's inputs are now (a moved camera renders the old frame), so
//! only runs that repeat one piece of work may use it (`schedbench`, `reyes render --runs`);
//! recorded runs and `reyes bench`'s moving frames refuse it.

use std::sync::Mutex;
use std::time::Instant;

use super::{EXTRA_WORDS, HostMultipass, HostRounds, first_counts};
use crate::error::RunError;
use crate::gpu::Gpu;
use crate::item_layout::ItemLayout;
use crate::multipass::partial::worst_case;
use crate::program::Seed;
use crate::queue_layout::QueueLayout;
use crate::readback::{ReadRange, Readback};
use crate::stats::RunStats;

/// Kept runs per scheduler: a frame rendered in buckets runs once per bucket, each with seeds
/// of its own. The oldest is dropped past this.
const KEPT: usize = 256;

/// A hash of `seeds` (procedure names and words, in order): which kept run a run replays.
pub(super) fn seeds_key(seeds: &[Seed]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for s in seeds {
        s.procedure.hash(&mut h);
        s.words.hash(&mut h);
    }
    h.finish()
}

/// The items one run executed, per queue, read back round by round.
pub(super) struct Capturer {
    /// Per queue: items back to back, as seeds hold them.
    items: Vec<Vec<u32>>,
    executed: Vec<u32>,
}

impl Capturer {
    pub fn new(queues: usize) -> Capturer {
        Capturer {
            items: vec![Vec::new(); queues],
            executed: vec![0; queues],
        }
    }

    /// Reads back the items a round just executed: of queue `q`'s `n[q]` inputs in `buf` (of
    /// `layout`), the last `run[q]` (a partial round runs the newest and carries the rest).
    /// One bounded wait per queue.
    pub fn keep_round(
        &mut self,
        gpu: &Gpu,
        items: ItemLayout,
        (buf, layout): (&wgpu::Buffer, &QueueLayout),
        n: &[u32],
        run: &[u32],
    ) -> Result<(), RunError> {
        for q in 0..n.len() {
            let (first, k, w) = (
                (n[q] - run[q]) as u64,
                run[q] as u64,
                layout.words[q] as u64,
            );
            if k == 0 {
                continue;
            }
            let cap = layout.capacity[q] as u64;
            let base = layout.slot_base[q] as u64;
            let out = &mut self.items[q];
            match items {
                ItemLayout::Interleaved => {
                    let bytes = gpu.read_buffer(buf, (base + first * w) * 4, k * w * 4)?;
                    out.extend_from_slice(bytemuck::cast_slice(&bytes));
                }
                ItemLayout::Planar => {
                    // Word j of slot s at base + j * cap + s: one read over the planes.
                    let span = (w - 1) * cap + k;
                    let bytes = gpu.read_buffer(buf, (base + first) * 4, span * 4)?;
                    let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
                    for s in 0..k {
                        out.extend((0..w).map(|j| words[(j * cap + s) as usize]));
                    }
                }
            }
            self.executed[q] += run[q];
        }
        Ok(())
    }

    /// The kept run: its items written once into round buffers of their own, as one round's
    /// inputs, with room for that round's worst case (its inputs times the declared emits,
    /// as any host-driven round) where that fits the device's largest binding; else for as
    /// many children again per queue as the kept run made and a quarter more, and a replay
    /// whose bodies emit more (emits that depend on the order items run in) is an error
    /// ([`HostMultipass::replay`]), never lost work.
    pub fn finish(self, gpu: &Gpu, mp: &HostMultipass, key: u64) -> Result<Floor, RunError> {
        let emits: Vec<Vec<u32>> = mp.program.procs.iter().map(|p| p.emits.clone()).collect();
        let worst: Vec<u32> = worst_case(&self.executed, &emits)
            .into_iter()
            .zip(&self.executed)
            .map(|(w, &k)| w.max(k as u64).clamp(1, u32::MAX as u64) as u32)
            .collect();
        let kept: Vec<u32> = self
            .executed
            .iter()
            .map(|&k| k.saturating_add(k / 4).max(1))
            .collect();
        let roomy = QueueLayout::new(&mp.program, worst)?;
        let layout = match roomy.total_words * 4 <= gpu.max_binding_bytes() {
            true => roomy,
            false => QueueLayout::new(&mp.program, kept)?,
        };
        let rounds = mp.rounds_buffers(gpu, layout)?;
        for (q, words) in self.items.iter().enumerate() {
            mp.item_layout()
                .write_items(&gpu.queue, &rounds.items[0], &rounds.layout, q, words);
        }
        Ok(Floor {
            key,
            rounds,
            executed: self.executed,
        })
    }
}

/// A kept run, ready to replay: its items as the inputs of one round (`rounds`, parity 0).
pub(super) struct Floor {
    key: u64,
    rounds: HostRounds,
    executed: Vec<u32>,
}

/// The kept runs of one scheduler, newest last.
#[derive(Default)]
pub(super) struct Floors(Mutex<Vec<Floor>>);

impl Floors {
    /// The kept run of seeds `key`, taken out (put it back with [`Floors::keep`]).
    pub fn take(&self, key: u64) -> Option<Floor> {
        let mut v = self.0.lock().unwrap();
        let i = v.iter().position(|f| f.key == key)?;
        Some(v.remove(i))
    }

    /// Keeps `f` as the newest, replacing a run of the same seeds and dropping the oldest past
    /// [`KEPT`].
    pub fn keep(&self, f: Floor) {
        let mut v = self.0.lock().unwrap();
        v.retain(|o| o.key != f.key);
        if v.len() == KEPT {
            v.remove(0);
        }
        v.push(f);
    }
}

impl HostMultipass {
    /// Replays kept run `f`: one round of every item it executed. Statistics: that round (one
    /// round, none for a run of no items; one submission; one launch per procedure with
    /// items), `strategy` `multipass-floor`.
    pub(super) fn replay(
        &self,
        gpu: &Gpu,
        f: &Floor,
        user: Option<&wgpu::BindGroup>,
        reads: &[ReadRange],
        start: Instant,
    ) -> Result<(RunStats, Vec<Vec<u32>>), RunError> {
        let nq = self.program.queue_count();
        let mut stats = RunStats {
            strategy: "multipass-floor".into(),
            item_layout: self.item_layout().name().into(),
            executed: f.executed.iter().map(|&k| k as u64).collect(),
            peak_occupancy: f.executed.iter().map(|&k| k as u64).collect(),
            rounds: f.executed.iter().any(|&k| k > 0) as u64,
            submits: 1,
            queue_bytes: f.rounds.layout.total_words * 4 * 2,
            ..Default::default()
        };
        let count_words = (nq + EXTRA_WORDS) as u64;
        let mut timer = self.run_timer(gpu, 1);
        let kept = self.readback.lock().unwrap().take();
        let rb = Readback::reuse(
            kept,
            gpu,
            "round counts read-back",
            count_words + crate::readback::ranges_words(reads) + timer.words(),
        );
        let d = &f.rounds;
        gpu.queue.write_buffer(
            &d.counts[0],
            0,
            bytemuck::cast_slice(&first_counts(&f.executed)),
        );
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&d.counts[1], 0, None);
        self.encode_round(&mut enc, (d, 0), &f.executed, user, &mut timer, &mut stats);
        rb.copy(&mut enc, &d.counts[1], 0, 0, count_words);
        gpu.submit(enc);
        let out = rb.read(gpu, count_words)?;
        let checked = match out[nq + super::H_ERROR] {
            super::ERR_ROOM => Err(RunError::Device(format!(
                "multipass-floor: the replay's bodies emitted more children to queue `{}` \
                 than the kept run did and a quarter more: their emits depend on the order \
                 items run in, which a replay of all of them at once changes; the floor \
                 cannot time this workload at this size",
                self.program
                    .procs
                    .get(out[nq + super::H_ERR_A] as usize)
                    .map_or("?", |p| p.proc.name.as_str())
            ))),
            _ => self.round_error(&out),
        };
        let results = checked
            .and_then(|()| self.finish_reads(gpu, &rb, timer, reads, count_words, &mut stats));
        *self.readback.lock().unwrap() = Some(rb);
        stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok((stats, results?))
    }
}
