//! The host-driven multi-pass baseline, as Patney & Owens (2008) ran theirs: after every round
//! the host reads the per-queue counts back and launches exactly one dispatch, sized to its
//! inputs, per non-empty procedure queue. Compaction is fused into the producing pass (each
//! enqueue appends to the next round's input buffer with one atomic add), so a round is its
//! procedure dispatches and nothing else: no indirect dispatch, no empty dispatch, no scan. The
//! cost is one host round trip per round. Shader: `shaders/multipass_host.wgsl`; protocol and
//! capacity rules: `docs/scheduler.md` section 5.2.

mod floor;

use std::time::Instant;

use crate::error::RunError;
use crate::gpu::{Gpu, MAX_WORKGROUPS_PER_DIMENSION};
use crate::growth::{grow, start_capacity};
use crate::item_layout::ItemLayout;
use crate::multipass::partial::{at_limit, needs_partial, partial_round, worst_case};
use crate::pipeline::{Kernels, storage_entry};
use crate::program::{Program, Seed};
use crate::queue_layout::{QueueLayout, RunStart};
use crate::readback::{ReadRange, Readback, copy_ranges, ranges_words, split_ranges};
use crate::stats::RunStats;
use crate::timing::RunTimer;

pub(crate) const TEMPLATE: &str = include_str!("../../../shaders/multipass_host.wgsl");
/// The loop over one procedure's round inputs, instantiated per procedure (`rounds_source`).
const RUN: &str = include_str!("../../../shaders/multipass_host_run.wgsl");

// Words after the per-queue counts in each counts buffer (host twin of `H_*` in the shader).
const H_ERROR: usize = 0;
const H_ERR_A: usize = 1;
const H_ERR_B: usize = 2;
const ERR_EMIT: u32 = 1;
const ERR_ROOM: u32 = 2;
/// Error words, then per queue the inputs to skip (carried by a partial round).
const EXTRA_WORDS: usize = 3;
const H_SKIP: usize = EXTRA_WORDS;

/// Settings of [`HostMultipass::new`]; [`Default`] gives the documented defaults.
#[derive(Debug, Clone)]
pub struct HostMultipassConfig {
    /// Slots per queue at the start of a run (at least the seeds; default 65,536).
    pub initial_capacity: u32,
    /// A queue grows (at least doubling) up to this many slots; a round whose worst-case output
    /// to a queue at this limit would not fit is a [`RunError::QueueOverflow`].
    pub max_capacity: u32,
    /// Rounds before the run gives up with [`RunError::NoProgress`] (default 100,000).
    pub max_rounds: u32,
    /// How the round buffers hold items; `None` (the default) picks
    /// [`ItemLayout::for_program`].
    pub item_layout: Option<ItemLayout>,
    /// Start a run with the queues the last run of this scheduler ended with when they hold its
    /// start (default `true`): queues that had to grow are not made small again and grown anew
    /// (each growth a refused round and new buffers), which is how a multi-pass renderer or
    /// graph search that runs again keeps its storage. `false` starts every run at
    /// `initial_capacity` (tests use it to exercise growth run after run).
    pub size_from_last_run: bool,
    /// Time each procedure's dispatch as a pass of its own ([`RunStats::stage_gpu_ms`]: one
    /// entry per procedure, then one for queue work, always 0 here: the host plans the rounds),
    /// as `MultipassConfig::stage_timing` does for the device-driven multi-pass, so that the
    /// two can be compared procedure by procedure. Default `false`: a round is one pass.
    pub stage_timing: bool,
    /// The multi-pass floor (`multipass-floor`, `host/floor.rs`): a run of seeds this
    /// scheduler has run before replays every item that run executed in one round, each
    /// procedure's in one dispatch, so its GPU time is the bodies' work without the rounds'
    /// cost; a run of new seeds is a host-driven run that keeps its items (its statistics'
    /// `strategy` says `multipass-floor capture`). For benchmarks that repeat one piece of
    /// work only: a replay does the kept run's work whatever the user's inputs are now.
    /// Default `false`.
    pub replay_floor: bool,
}

impl Default for HostMultipassConfig {
    fn default() -> Self {
        HostMultipassConfig {
            initial_capacity: 1 << 16,
            max_capacity: 1 << 26,
            max_rounds: 100_000,
            item_layout: None,
            size_from_last_run: true,
            stage_timing: false,
            replay_floor: false,
        }
    }
}

/// A counts buffer whose round runs all of `n` (no error, nothing skipped).
fn first_counts(n: &[u32]) -> Vec<u32> {
    let mut c = vec![0u32; 2 * n.len() + EXTRA_WORDS];
    c[..n.len()].copy_from_slice(n);
    c
}

/// A program compiled for the host-driven multi-pass strategy: one pipeline per procedure,
/// buffers kept between runs. Usually reached through [`crate::Scheduler`].
pub struct HostMultipass {
    program: Program,
    config: HostMultipassConfig,
    kernels: Kernels,
    /// Buffers of the last run, reused when the next run starts with the same layout.
    cache: std::sync::Mutex<Option<HostRounds>>,
    /// The mapped buffer the counts come back through, kept between runs.
    readback: std::sync::Mutex<Option<Readback>>,
    /// Runs kept for the floor's replays (`config.replay_floor`).
    floors: floor::Floors,
}

/// Buffers of one queue layout: `items[p]` and `counts[p]` are the inputs of rounds of parity `p`
/// and the outputs of the others.
struct HostRounds {
    layout: QueueLayout,
    counts: [wgpu::Buffer; 2],
    items: [wgpu::Buffer; 2],
    /// `bind[p]`: reads `counts[p]` and `items[p]`, appends to `counts[1 - p]` and `items[1 - p]`.
    bind: [wgpu::BindGroup; 2],
}

/// The WGSL of the host-driven multi-pass: shared program code, append-style enqueue functions,
/// one entry point per procedure (`mp_host_<name>`) with its own loop (`run_procedure_<t>`,
/// reaching only that procedure's body), then the template.
pub(crate) fn source(program: &Program, items: ItemLayout) -> String {
    let args = "@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>, \
                @builtin(num_workgroups) nwg: vec3<u32>";
    super::wgsl::rounds_source(
        program,
        items,
        "mp_host",
        args,
        &|t| format!("run_procedure_{t}({t}u, lid, wid.x, nwg.x);"),
        RUN,
        false,
    ) + TEMPLATE
}

impl HostMultipass {
    /// The program this multi-pass runs.
    pub fn program(&self) -> &Program {
        &self.program
    }

    /// Whether this is the multi-pass floor ([`HostMultipassConfig::replay_floor`]).
    pub fn replays_floor(&self) -> bool {
        self.config.replay_floor
    }

    /// How its round buffers hold items (the configured layout, or the adapter's).
    pub fn item_layout(&self) -> ItemLayout {
        self.config.item_layout.unwrap_or_default()
    }

    /// Compiles `program` for the host-driven multi-pass on `gpu`. Errors:
    /// [`RunError::Program`] for more than 16 procedures or WGSL that does not compile with the
    /// generated code.
    pub fn new(
        gpu: &Gpu,
        program: &Program,
        mut config: HostMultipassConfig,
    ) -> Result<HostMultipass, RunError> {
        let items = config
            .item_layout
            .unwrap_or_else(|| ItemLayout::for_program(gpu, program));
        config.item_layout = Some(items);
        if program.queue_count() > 16 {
            return Err(RunError::Program(
                "the multi-pass strategy supports at most 16 procedures".into(),
            ));
        }
        let entries: Vec<_> = (0..5).map(|b| storage_entry(b, b == 0 || b == 4)).collect();
        let eps: Vec<String> = program
            .procs
            .iter()
            .map(|p| format!("mp_host_{}", p.proc.name))
            .collect();
        let eps: Vec<&str> = eps.iter().map(|s| s.as_str()).collect();
        let kernels = Kernels::new(
            gpu,
            program,
            "multipass-host",
            &source(program, items),
            &entries,
            &eps,
            None,
        )?;
        Ok(HostMultipass {
            program: program.clone(),
            config,
            kernels,
            cache: Default::default(),
            readback: Default::default(),
            floors: Default::default(),
        })
    }

    fn rounds_buffers(&self, gpu: &Gpu, layout: QueueLayout) -> Result<HostRounds, RunError> {
        let nq = self.program.queue_count();
        let count_words = (2 * nq + EXTRA_WORDS) as u64;
        let counts = [
            gpu.storage_buffer("round counts a", count_words)?,
            gpu.storage_buffer("round counts b", count_words)?,
        ];
        let items = [
            gpu.storage_buffer("round items a", layout.total_words)?,
            gpu.storage_buffer("round items b", layout.total_words)?,
        ];
        let mut params = vec![0u32; 4 * nq];
        for q in 0..nq {
            params[4 * q] = layout.capacity[q];
            params[4 * q + 1] = layout.slot_base[q];
        }
        let params_buf = gpu.storage_buffer("round params", params.len() as u64)?;
        gpu.queue
            .write_buffer(&params_buf, 0, bytemuck::cast_slice(&params));
        let bind = [0, 1].map(|p| {
            self.kernels.bind_group0(
                gpu,
                &[
                    (0, &counts[p]),
                    (1, &counts[1 - p]),
                    (2, &items[p]),
                    (3, &items[1 - p]),
                    (4, &params_buf),
                ],
            )
        });
        Ok(HostRounds {
            layout,
            counts,
            items,
            bind,
        })
    }

    /// Runs the program to completion from `seeds`; `user` is bind group 1, if the program has
    /// one; `max_queue_bytes` bounds the item storage of this run (two copies of every queue).
    /// `reads`: buffer ranges read back once after the last round into the kept read-back
    /// buffer, with the timestamps not yet read (one submission and wait), one vector per
    /// range (a copy every round, to save that one wait, cost more: H200, the deep tree's 201
    /// rounds 19.9 -> 21.9 ms of wall time; docs/results.md, 2026-12-04 (third session)).
    /// Errors: every [`RunError`] but `NoAdapter` (see `docs/scheduler.md`, section 6).
    pub fn run(
        &self,
        gpu: &Gpu,
        seeds: &[Seed],
        user: Option<&wgpu::BindGroup>,
        max_queue_bytes: Option<u64>,
        reads: &[ReadRange],
    ) -> Result<(RunStats, Vec<Vec<u32>>), RunError> {
        self.kernels.check_user_group(user)?;
        let start = Instant::now();
        let nq = self.program.queue_count();
        // The floor: a replay of the items a run of these seeds executed, else a run that keeps
        // them.
        let floor_key = self.config.replay_floor.then(|| floor::seeds_key(seeds));
        if let Some(c) = floor_key.and_then(|k| self.floors.take(k)) {
            let replayed = self.replay(gpu, &c, user, reads, start);
            self.floors.keep(c);
            return replayed;
        }
        let mut capture = floor_key.map(|_| floor::Capturer::new(nq));
        // Two copies of the items per slot; run_start adds a flag word, which this strategy
        // does not have, so the budget is kept with a little to spare.
        let RunStart {
            live,
            seeded: mut n,
            max_cap,
        } = QueueLayout::run_start(
            &self.program,
            seeds,
            gpu.max_binding_bytes(),
            self.config.max_capacity,
            max_queue_bytes,
            2,
        )?;
        let mut capacity: Vec<u32> = (0..nq)
            .map(|q| {
                self.config
                    .initial_capacity
                    .min(max_cap[q])
                    .max(n[q])
                    .max(1)
            })
            .collect();
        let mut stats = RunStats {
            strategy: match floor_key {
                Some(_) => "multipass-floor capture".into(),
                None => "multipass-host".into(),
            },
            item_layout: self.item_layout().name().into(),
            executed: vec![0; nq],
            peak_occupancy: vec![0; nq],
            ..Default::default()
        };
        // The caller's ranges follow the counts.
        let count_words = (nq + EXTRA_WORDS) as u64;
        let kept = self.readback.lock().unwrap().take();
        // Timestamps come back once per 64 rounds.
        let mut timer = self.run_timer(gpu, 64);
        let words = count_words + ranges_words(reads) + timer.words();
        let rb = Readback::reuse(kept, gpu, "round counts read-back", words);
        let cached = self.cache.lock().unwrap().take();
        let kept = cached.as_ref().map(|d| d.layout.capacity.as_slice());
        capacity = start_capacity(self.config.size_from_last_run, kept, capacity, &max_cap);
        let layout = QueueLayout::new(&self.program, capacity.clone())?;
        let mut d = match cached {
            Some(d) if d.layout == layout => d,
            _ => self.rounds_buffers(gpu, layout)?,
        };
        // Seeds: the inputs of the first round, at parity 0.
        let items = self.item_layout();
        for (q, seed) in live.iter().enumerate() {
            items.write_items(&gpu.queue, &d.items[0], &d.layout, q, seed);
        }
        gpu.queue
            .write_buffer(&d.counts[0], 0, bytemuck::cast_slice(&first_counts(&n)));
        let emits: Vec<Vec<u32>> = self.program.procs.iter().map(|p| p.emits.clone()).collect();
        let mut par = 0;
        while n.iter().any(|&k| k > 0) {
            if stats.rounds >= self.config.max_rounds as u64 {
                return Err(RunError::NoProgress(format!(
                    "work left after {} host-driven multi-pass rounds",
                    stats.rounds
                )));
            }
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            // Room for the round's worst case in every target, before it runs: a target that
            // lacks it grows; one that cannot (at its limit) makes this a partial round.
            let worst = worst_case(&n, &emits);
            let mut grown = capacity.clone();
            for (t, cap) in grown.iter_mut().enumerate() {
                if worst[t] > *cap as u64 && *cap < max_cap[t] {
                    *cap = grow(*cap, worst[t], max_cap[t]);
                    stats.queue_growths += 1;
                }
            }
            if grown != capacity {
                // New buffers; this round's inputs move there on the device, ahead of the round.
                capacity = grown;
                let new =
                    self.rounds_buffers(gpu, QueueLayout::new(&self.program, capacity.clone())?)?;
                for (q, &k) in n.iter().enumerate() {
                    items.encode_copy(
                        &mut enc,
                        (&d.items[par], &d.layout),
                        (&new.items[0], &new.layout),
                        q,
                        k,
                    );
                }
                gpu.queue
                    .write_buffer(&new.counts[0], 0, bytemuck::cast_slice(&first_counts(&n)));
                d = new;
                par = 0;
            }
            // Inputs this round runs; the rest are carried to the front of the next round's.
            let at_limit = at_limit(&capacity, &max_cap);
            let run = if needs_partial(&worst, &capacity, &at_limit) {
                partial_round(&n, &capacity, &emits).ok_or_else(|| {
                    let t = (0..nq)
                        .max_by_key(|&t| worst[t] * at_limit[t] as u64)
                        .unwrap();
                    RunError::QueueOverflow {
                        queue: self.program.procs[t].proc.name.clone(),
                        capacity: capacity[t] as u64,
                        needed_more_than: worst[t],
                    }
                })?
            } else {
                n.clone()
            };
            if run == n {
                enc.clear_buffer(&d.counts[1 - par], 0, None);
            } else {
                stats.partial_rounds += 1;
                // The newest inputs run (depth first, so live work stays bounded); the older
                // ones stay at the front, copied to the next round's buffer.
                let mut inputs = vec![0u32; 2 * nq + EXTRA_WORDS];
                let mut carried = vec![0u32; 2 * nq + EXTRA_WORDS];
                for q in 0..nq {
                    let keep = n[q] - run[q];
                    inputs[q] = run[q];
                    inputs[nq + H_SKIP + q] = keep;
                    carried[q] = keep;
                    items.encode_copy(
                        &mut enc,
                        (&d.items[par], &d.layout),
                        (&d.items[1 - par], &d.layout),
                        q,
                        keep,
                    );
                }
                gpu.queue
                    .write_buffer(&d.counts[par], 0, bytemuck::cast_slice(&inputs));
                gpu.queue
                    .write_buffer(&d.counts[1 - par], 0, bytemuck::cast_slice(&carried));
            }
            self.encode_round(&mut enc, (&d, par), &run, user, &mut timer, &mut stats);
            rb.copy(&mut enc, &d.counts[1 - par], 0, 0, count_words);
            // A full query set's timestamps come back after the counts, in the same wait.
            let stamps = timer.end_submission(&mut enc, &rb, count_words);
            gpu.submit(enc);
            let out = rb.read(gpu, count_words + stamps)?;
            timer.after_wait(&out[count_words as usize..]);
            stats.submits += 1;
            stats.rounds += 1;
            for q in 0..nq {
                stats.executed[q] += run[q] as u64;
                stats.peak_occupancy[q] = stats.peak_occupancy[q].max(n[q] as u64);
            }
            self.round_error(&out)?;
            if let Some(c) = capture.as_mut() {
                c.keep_round(gpu, items, (&d.items[par], &d.layout), &n, &run)?;
            }
            n.copy_from_slice(&out[..nq]);
            par = 1 - par;
        }
        stats.queue_bytes = d.layout.total_words * 4 * 2;
        let results = self.finish_reads(gpu, &rb, timer, reads, count_words, &mut stats)?;
        if let (Some(key), Some(c)) = (floor_key, capture) {
            self.floors.keep(c.finish(gpu, self, key)?);
        }
        stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        *self.cache.lock().unwrap() = Some(d);
        *self.readback.lock().unwrap() = Some(rb);
        Ok((stats, results))
    }

    /// A timer of `submissions` rounds between read-backs: one pass a round, or with stage
    /// timing one per procedure (stages 0..nq; stage nq, queue work, has no pass here).
    fn run_timer(&self, gpu: &Gpu, submissions: u32) -> RunTimer {
        let nq = self.program.queue_count();
        match self.config.stage_timing {
            true => RunTimer::new(gpu, nq + 1, nq as u32, submissions),
            false => RunTimer::new(gpu, 1, 1, submissions),
        }
    }

    /// Records a round's dispatches: one per procedure with inputs (`run[q]` of them), sized to
    /// them, in one pass, or with stage timing one pass per procedure; reads `rounds.0`'s
    /// buffers of parity `rounds.1`.
    fn encode_round(
        &self,
        enc: &mut wgpu::CommandEncoder,
        (d, par): (&HostRounds, usize),
        run: &[u32],
        user: Option<&wgpu::BindGroup>,
        timer: &mut RunTimer,
        stats: &mut RunStats,
    ) {
        let stages = self.config.stage_timing;
        let dispatches: Vec<(usize, u32)> = run
            .iter()
            .enumerate()
            .filter(|&(_, &k)| k > 0)
            .map(|(q, &k)| {
                let per_step = self.program.procs[q].items_per_step;
                (q, k.div_ceil(per_step).min(MAX_WORKGROUPS_PER_DIMENSION))
            })
            .collect();
        let passes: Vec<&[(usize, u32)]> = match stages {
            true => dispatches.chunks(1).collect(),
            false => vec![&dispatches[..]],
        };
        for group in passes {
            let stage = if stages { group[0].0 } else { 0 };
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("multipass-host round"),
                timestamp_writes: timer.writes(stage),
            });
            pass.set_bind_group(0, &d.bind[par], &[]);
            if let Some(u) = user {
                pass.set_bind_group(1, u, &[]);
            }
            for &(q, wgs) in group {
                pass.set_pipeline(&self.kernels.pipelines[q]);
                pass.dispatch_workgroups(wgs, 1, 1);
                stats.launches += 1;
            }
        }
    }

    /// The error a round's read-back counts (`out`: the next round's counts, then the error
    /// words) report, if any.
    fn round_error(&self, out: &[u32]) -> Result<(), RunError> {
        let nq = self.program.queue_count();
        let (a, b) = (out[nq + H_ERR_A] as usize, out[nq + H_ERR_B] as usize);
        match out[nq + H_ERROR] {
            0 => Ok(()),
            ERR_EMIT => Err(RunError::EmitLimit {
                procedure: self.program.procs[a].proc.name.clone(),
                target: self.program.procs[b].proc.name.clone(),
                declared: self.program.procs[a].emits[b],
            }),
            ERR_ROOM => Err(RunError::Device(format!(
                "host-driven multi-pass: an append past the capacity the host made room for \
                 (queue {a}, slot {b})"
            ))),
            e => Err(RunError::Device(format!(
                "host-driven multi-pass: unknown error code {e} (words {a}, {b})"
            ))),
        }
    }

    /// The run's last read: the caller's ranges (from word `at` of `rb`) and the timestamps
    /// not yet read, in one submission and one wait (none when there is neither); sets the
    /// run's GPU times in `stats`. Returns one vector per range.
    fn finish_reads(
        &self,
        gpu: &Gpu,
        rb: &Readback,
        timer: RunTimer,
        reads: &[ReadRange],
        at: u64,
        stats: &mut RunStats,
    ) -> Result<Vec<Vec<u32>>, RunError> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        copy_ranges(rb, &mut enc, reads, at);
        let stamps_at = at + ranges_words(reads);
        let stamps = timer.copy_rest(&mut enc, rb, stamps_at);
        let words = match reads.is_empty() && stamps == 0 {
            true => Vec::new(),
            false => {
                gpu.submit(enc);
                rb.read(gpu, stamps_at + stamps)?
            }
        };
        let results = match reads.is_empty() {
            true => Vec::new(),
            false => split_ranges(&words[at as usize..], reads),
        };
        let stage_ms = timer.finish(words.get(stamps_at as usize..).unwrap_or(&[]));
        stats.gpu_ms = stage_ms.as_ref().map(|ms| ms.iter().sum());
        if self.config.stage_timing {
            stats.stage_gpu_ms = stage_ms.unwrap_or_default();
        }
        Ok(results)
    }
}
