//! The multi-pass baseline (Patney & Owens 2008), device-driven: rounds of one indirect
//! dispatch per dispatch group (every procedure alone; all together, fused rounds, the default
//! on GPUs; or the producers and the sinks apart), sized on the device by a plan that the last
//! workgroup of the round before runs from its counts; children are appended to the next
//! round's inputs with one atomic add each (compaction fused into the producer, no scan).
//! Rounds are encoded in chunks, the first as
//! long as the previous run needed, so a repeated run is one submission; the host reads back
//! only between chunks. A round whose outputs would not fit is refused on the device with its
//! inputs intact; the host grows every queue that lacked room and resumes. [`host`] is the
//! host-driven variant: exact direct dispatches, one read-back per round.

pub mod host;
pub(crate) mod layout;
pub mod partial;
pub(crate) mod record;
pub(crate) mod wgsl;

use std::time::Instant;

use layout::*;

use crate::error::RunError;
use crate::gpu::Gpu;
use crate::growth::{Anticipation, grow, start_capacity};
use crate::item_layout::ItemLayout;
use crate::pipeline::{Kernels, storage_entry};
use crate::program::{Program, Seed};
use crate::queue_layout::{QueueLayout, RunStart};
use crate::readback::{ReadRange, TimedReadback};
use crate::stats::RunStats;
use crate::timing::StageTimer;

/// Settings of [`Multipass::new`]; [`Default`] gives the documented defaults.
#[derive(Debug, Clone)]
pub struct MultipassConfig {
    /// Rounds encoded per submission after the first (default 16); the host checks for
    /// completion between chunks. The first submission encodes as many rounds as the previous
    /// run of this [`Multipass`] needed (at most [`MAX_LEARNED_ROUNDS`]), or this many.
    pub rounds_per_submit: u32,
    /// Rounds encoded per run, empty ones included, before it stops with
    /// [`RunError::NoProgress`] (default 100,000).
    pub max_rounds: u32,
    /// Slots per queue at the start of a run (at least the seeds; default 65,536).
    pub initial_capacity: u32,
    /// A queue grows (at least doubling) up to this many slots, and never past its share of the
    /// largest storage binding or 65,535 × 1,024; a refused round whose target is at its limit is
    /// a [`RunError::QueueOverflow`].
    pub max_capacity: u32,
    /// Time each procedure's dispatches as their own passes ([`RunStats::stage_gpu_ms`]);
    /// the extra pass boundaries cost a little, so it is off for benchmarks of the whole.
    pub stage_timing: bool,
    /// How the round buffers hold items; `None` (the default) picks
    /// [`ItemLayout::for_program`], as the host-driven multi-pass does.
    pub item_layout: Option<ItemLayout>,
    /// Start a run with the queues the last run of this scheduler ended with when they hold its
    /// start (default `true`): queues that had to grow are not made small again and grown anew
    /// (each growth a refused round and new buffers), which is how a multi-pass renderer or
    /// graph search that runs again keeps its storage. `false` starts every run at
    /// `initial_capacity` (tests use it to exercise growth run after run).
    pub size_from_last_run: bool,
    /// Dispatch a round's procedures together, one indirect dispatch a round
    /// (`mp_round` in `shaders/multipass.wgsl`: each workgroup finds its procedure from the
    /// plan's workgroup counts), instead of one indirect dispatch per procedure. Fewer dispatches
    /// and barriers (and fewer of wgpu's indirect-validation dispatches), one kernel holding
    /// every procedure's code. `None` (the default): fused on GPUs, a dispatch per procedure on
    /// CPU adapters. On the H200 fused rounds were faster on all but two workloads, e.g. the
    /// teapot frame 2.18 -> 1.43 ms, the deep tree 4.48 -> 3.01; the large-payload tree and BFS
    /// at scale 20 2-3% slower (docs/results.md, 2026-12-02, "Fused rounds"). On lavapipe the
    /// kernel holding every procedure ran 1.25-2x slower (docs/scheduler.md 5.1). Ignored with
    /// `stage_timing`, which times each procedure's dispatches apart (docs/scheduler.md 5.1).
    pub fused_rounds: Option<bool>,
    /// With fused rounds, dispatch the sinks (procedures that emit nothing: Reyes' DiceShade
    /// and DiceSmall, the tree's leaves) apart from the producers: two indirect dispatches a
    /// round, each kernel reaching only its own procedures' bodies, so the driver sizes the
    /// sinks' registers without the producers' (the host-driven Reyes passes: Bound 127
    /// registers, DiceShade 80; one kernel for all takes the larger, docs/scheduler.md 5.1).
    /// Default `false`: on the H200 Killeroo gained 1.5-2% and the teapot lost 14-16%
    /// (docs/results.md, 2026-12-05). Ignored without fused rounds, or when every procedure is
    /// a sink or none is.
    pub fused_sinks_apart: bool,
    /// With fused rounds (the sinks not apart), give the sinks the round's first workgroups
    /// and the producers the last. A GPU starts a grid's workgroups roughly in order, so a
    /// round's longest workgroups (Reyes' dice-and-shade of a whole grid) start first instead
    /// of forming its tail (longest processing time first, Graham 1969). Default `false`: on
    /// the H200 it changed nothing measurable (Killeroo -0.8%, the deep tree +2.3%;
    /// docs/results.md, 2026-12-05). Ignored without fused rounds or with the sinks apart.
    pub fused_sinks_first: bool,
    /// Most workgroups a procedure's share of a round's dispatch may have (and never more than
    /// 65,535 / the procedures sharing the dispatch); past that, the procedure's workgroups go
    /// over its items grid-stride. Every device-driven workgroup plans its round before its
    /// items (`mp_begin`), and each append that begins a step of its target's items adds a
    /// workgroup to the next round's arguments with an atomic: fewer workgroups, each with
    /// more steps, pay both less often. `None` (the default): [`DEFAULT_MAX_WORKGROUPS`] on
    /// GPUs; no cap on CPU adapters, where a workgroup's invocations are coroutines and
    /// lavapipe cuts every loop of an invocation after 65,535 iterations in all (the items of
    /// many steps would add up their bodies' loops; docs/scheduler.md 4). At least 1.
    pub max_workgroups: Option<u32>,
}

impl Default for MultipassConfig {
    fn default() -> Self {
        MultipassConfig {
            rounds_per_submit: 16,
            max_rounds: 100_000,
            initial_capacity: 1 << 16,
            max_capacity: 1 << 26,
            stage_timing: false,
            item_layout: None,
            size_from_last_run: true,
            fused_rounds: None,
            fused_sinks_apart: false,
            fused_sinks_first: false,
            max_workgroups: None,
        }
    }
}

/// [`MultipassConfig::max_workgroups`] on GPUs: four per SM of the H100 and H200's 132. H100,
/// against no cap (docs/results.md, 2026-12-05 (sixth session)): Killeroo 1920x1080 1.208 ->
/// 1.123 ms, teapot 0.868 -> 0.848, binary tree 0.190 -> 0.186, large payload 0.618 -> 0.607,
/// deep unchanged; 264 gave the frames the same, 1,056 less (measured before the round plan
/// left lane 0's registers, `084b9cd`, which took the frames to 0.865 and 0.704 with it).
pub const DEFAULT_MAX_WORKGROUPS: u32 = 528;

/// The dispatch groups of `program`'s rounds: every procedure alone without `fused`; with it
/// all together (with `sinks_first`, the sinks, procedures that emit nothing, before the
/// producers), or with `sinks_apart` the producers, then the sinks, where there are both.
fn dispatch_groups(
    program: &Program,
    fused: bool,
    sinks_apart: bool,
    sinks_first: bool,
) -> wgsl::DispatchGroups {
    let all: Vec<usize> = (0..program.queue_count()).collect();
    if !fused {
        return all.into_iter().map(|q| vec![q]).collect();
    }
    let (sinks, producers): (Vec<usize>, Vec<usize>) =
        all.iter().partition(|&&q| program.procs[q].is_sink());
    if sinks_apart && !sinks.is_empty() && !producers.is_empty() {
        vec![producers, sinks]
    } else if sinks_first {
        vec![[sinks, producers].concat()]
    } else {
        vec![all]
    }
}

/// Most rounds the first submission of a run encodes from what the previous run needed.
pub const MAX_LEARNED_ROUNDS: u32 = 1024;
/// Most rounds one submission of a run encodes (the dispatch arguments' slots).
const MAX_CHUNK: u32 = 1024;

/// A program compiled for the device-driven multi-pass strategy: the plan's pipeline and one
/// per procedure, buffers kept between runs. Usually reached through [`crate::Scheduler`].
pub struct Multipass {
    program: Program,
    config: MultipassConfig,
    kernels: Kernels,
    /// The round's indirect dispatches: the procedures of each ([`wgsl::DispatchGroups`]).
    groups: wgsl::DispatchGroups,
    /// The pipeline (index into `kernels.pipelines`) of each dispatch group.
    group_pipelines: Vec<usize>,
    /// Buffers of the last run, reused when the next run needs the same layout.
    cache: std::sync::Mutex<Option<DeviceRounds>>,
    /// Rounds the last finished run executed (0 before the first): the next run's first
    /// submission encodes that many.
    learned_rounds: std::sync::atomic::AtomicU32,
    /// Each submission's counters, GPU time and the caller's ranges, kept between runs.
    readback: std::sync::Mutex<Option<TimedReadback>>,
}

struct DeviceRounds {
    layout: QueueLayout,
    at_limit: Vec<bool>,
    ctrl: wgpu::Buffer,
    items: [wgpu::Buffer; 2],
    /// Dispatch arguments: round k of a chunk reads its own from `args[k % 2]` (slot
    /// `(k / 2) × NQ + g` for dispatch group g) and may plan round k + 1 into
    /// `args[(k + 1) % 2]`.
    args: [wgpu::Buffer; 2],
    /// `args_bind[j]`: `args[j]` as storage and the round indices (group 2).
    args_bind: [wgpu::BindGroup; 2],
    /// Bytes between round indices in `round_index`: round k binds group 2 at offset
    /// `k × index_stride` (`mp_k`, a dynamic offset).
    index_stride: u32,
    /// Rounds a chunk may hold (the arguments' slots).
    max_chunk: u32,
    /// `bind[parity]`: round r reads `items[r % 2]` and writes `items[(r + 1) % 2]`.
    bind: [wgpu::BindGroup; 2],
}

impl Multipass {
    /// Compiles `program` for the device-driven multi-pass on `gpu`. Errors:
    /// [`RunError::Program`] for more than 16 procedures (its workgroup memory holds a counter
    /// per item and target) or WGSL that does not compile with the generated code.
    pub fn new(
        gpu: &Gpu,
        program: &Program,
        mut config: MultipassConfig,
    ) -> Result<Multipass, RunError> {
        let items = config
            .item_layout
            .unwrap_or_else(|| ItemLayout::for_program(gpu, program));
        config.item_layout = Some(items);
        if program.queue_count() > 16 {
            return Err(RunError::Program(
                "the multi-pass strategy supports at most 16 procedures".into(),
            ));
        }
        let fused = config.fused_rounds.unwrap_or(!gpu.is_cpu_adapter()) && !config.stage_timing;
        config.fused_rounds = Some(fused);
        let groups = dispatch_groups(
            program,
            fused,
            config.fused_sinks_apart,
            config.fused_sinks_first,
        );
        config.fused_sinks_apart = fused && groups.len() == 2;
        config.fused_sinks_first =
            fused && groups.len() == 1 && groups[0].iter().copied().ne(0..program.queue_count());
        config.max_workgroups = match config.max_workgroups {
            None if gpu.is_cpu_adapter() => None,
            None => Some(DEFAULT_MAX_WORKGROUPS),
            Some(n) => Some(n.max(1)),
        };
        let max_workgroups = config.max_workgroups.unwrap_or(u32::MAX);
        let source = wgsl::source(program, items, &groups, max_workgroups);
        let entries: Vec<_> = (0..4).map(|b| storage_entry(b, b == 3)).collect();
        let names = wgsl::entry_points(program, &groups);
        let group_pipelines = (0..groups.len())
            .map(|g| {
                let e = wgsl::group_entry(program, &groups, g);
                names
                    .iter()
                    .position(|n| *n == e)
                    .expect("every group has an entry point")
            })
            .collect();
        let eps: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
        // The next round's arguments, and the round's index within its chunk (`mp_k`, a
        // uniform at a dynamic offset per round).
        let group2 = [
            storage_entry(0, false),
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(16),
                },
                count: None,
            },
        ];
        let kernels = Kernels::new(
            gpu,
            program,
            "multipass",
            &source,
            &entries,
            &eps,
            Some((&group2, &eps)),
        )?;
        Ok(Multipass {
            program: program.clone(),
            config,
            kernels,
            groups,
            group_pipelines,
            cache: Default::default(),
            learned_rounds: Default::default(),
            readback: Default::default(),
        })
    }

    /// The program this multi-pass runs.
    pub fn program(&self) -> &Program {
        &self.program
    }

    /// How its round buffers hold items (the configured layout, or the adapter's).
    pub fn item_layout(&self) -> ItemLayout {
        self.config.item_layout.unwrap_or_default()
    }

    /// How a round's procedures are dispatched, resolved for the adapter: `fused`,
    /// `per-procedure`, `sinks-apart` or `sinks-first` ([`RunStats::round_dispatch`]).
    pub fn round_dispatch(&self) -> &'static str {
        match (
            self.config.fused_rounds,
            self.config.fused_sinks_apart,
            self.config.fused_sinks_first,
        ) {
            (Some(false) | None, ..) => "per-procedure",
            (_, true, _) => "sinks-apart",
            (_, _, true) => "sinks-first",
            _ => "fused",
        }
    }

    /// Buffers of one layout; `at_limit[q]`: queue q cannot grow, so a round it cannot hold
    /// runs in part ([`partial`]) instead of halting for growth.
    /// `max_chunk`: the most rounds one submission or record encodes.
    fn device_rounds(
        &self,
        gpu: &Gpu,
        layout: QueueLayout,
        at_limit: Vec<bool>,
        max_chunk: u32,
    ) -> Result<DeviceRounds, RunError> {
        let nq = self.program.queue_count();
        let ctrl = gpu.storage_buffer("mp_ctrl", ctrl_words(nq) as u64)?;
        let items = [
            gpu.storage_buffer("items a", layout.total_words)?,
            gpu.storage_buffer("items b", layout.total_words)?,
        ];
        let mut params = vec![0u32; nq * P_QSTRIDE];
        for q in 0..nq {
            let p = &mut params[q * P_QSTRIDE..];
            p[0] = layout.capacity[q];
            p[1] = layout.slot_base[q];
            p[2] = at_limit[q] as u32;
        }
        let params_buf = gpu.storage_buffer("mp params", params.len() as u64)?;
        gpu.queue
            .write_buffer(&params_buf, 0, bytemuck::cast_slice(&params));
        let args = [0, 1].map(|_| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("round dispatch args"),
                size: (max_chunk.div_ceil(2) as usize * nq * 12) as u64,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::INDIRECT
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let bind = [0, 1].map(|par| {
            self.kernels.bind_group0(
                gpu,
                &[
                    (0, &ctrl),
                    (1, &items[par]),
                    (2, &items[1 - par]),
                    (3, &params_buf),
                ],
            )
        });
        let index_stride = gpu
            .device
            .limits()
            .min_uniform_buffer_offset_alignment
            .max(16);
        let indices: Vec<u32> = (0..max_chunk)
            .flat_map(|k| {
                let mut entry = vec![0u32; index_stride as usize / 4];
                entry[0] = k;
                entry
            })
            .collect();
        // Round k's index within its chunk at byte k × index_stride, for every round a chunk
        // may hold (the bind groups keep the buffer).
        let round_index = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("round indices"),
            size: (indices.len() * 4) as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        gpu.queue
            .write_buffer(&round_index, 0, bytemuck::cast_slice(&indices));
        let args_bind = [0, 1].map(|j| {
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("round dispatch args"),
                layout: self.kernels.group2.as_ref().expect("multipass has group 2"),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: args[j].as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &round_index,
                            offset: 0,
                            size: wgpu::BufferSize::new(16),
                        }),
                    },
                ],
            })
        });
        Ok(DeviceRounds {
            layout,
            at_limit,
            ctrl,
            items,
            args,
            args_bind,
            index_stride,
            max_chunk,
            bind,
        })
    }

    /// Makes `live` (per queue, words back to back) the inputs of the next round, at parity 0.
    fn upload(&self, gpu: &Gpu, d: &DeviceRounds, live: &[std::borrow::Cow<[u32]>]) {
        let nq = self.program.queue_count();
        let mut ctrl = vec![0u32; ctrl_words(nq)];
        for (q, items) in live.iter().enumerate() {
            ctrl[c(q, C_APPEND)] = (items.len() / d.layout.words[q] as usize) as u32;
            self.item_layout()
                .write_items(&gpu.queue, &d.items[0], &d.layout, q, items);
        }
        gpu.queue
            .write_buffer(&d.ctrl, 0, bytemuck::cast_slice(&ctrl));
    }

    /// Makes the `counts[q]` inputs in `from.items[parity]` the inputs of the next round in `to`
    /// (parity 0), copied on the device: growth moves no item through the host. The copies go
    /// into `enc`, the next chunk's encoder (no submission of their own); `to`'s ctrl is a
    /// queue write, which lands before that submission.
    fn move_inputs(
        &self,
        gpu: &Gpu,
        from: &DeviceRounds,
        parity: usize,
        to: &DeviceRounds,
        counts: &[u32],
        enc: &mut wgpu::CommandEncoder,
    ) {
        let nq = self.program.queue_count();
        let mut ctrl = vec![0u32; ctrl_words(nq)];
        for (q, &n) in counts.iter().enumerate() {
            ctrl[c(q, C_APPEND)] = n;
            self.item_layout().encode_copy(
                enc,
                (&from.items[parity], &from.layout),
                (&to.items[0], &to.layout),
                q,
                n,
            );
        }
        gpu.queue
            .write_buffer(&to.ctrl, 0, bytemuck::cast_slice(&ctrl));
    }

    /// Indirect dispatches of one round: one per procedure, one with fused rounds, two with
    /// the sinks apart.
    fn dispatches_per_round(&self) -> u64 {
        self.groups.len() as u64
    }

    /// Encodes a chunk of `rounds` rounds (at most `d.max_chunk`): the arguments cleared, the
    /// first round's plan (one thread, a direct dispatch), then per round one indirect dispatch
    /// per dispatch group (each procedure, all of them with fused rounds, or producers and
    /// sinks); the last workgroup of each round plans the next (`shaders/multipass.wgsl`), so
    /// the chunk is `1 + rounds × groups` dispatches. `mp_ctrl`'s `G_CHUNK` must hold `rounds`.
    /// With `stages`, each procedure's dispatches are timed as their own passes and the plan is
    /// counted to the last stage; else one pass.
    #[allow(clippy::too_many_arguments)]
    fn encode_rounds(
        &self,
        enc: &mut wgpu::CommandEncoder,
        d: &DeviceRounds,
        rounds: u32,
        first_round: u64,
        timer: Option<&TimedReadback>,
        stages: Option<&StageTimer>,
        user: Option<&wgpu::BindGroup>,
    ) {
        debug_assert!(rounds <= d.max_chunk);
        let nq = self.program.queue_count();
        let p = &self.kernels.pipelines;
        for a in &d.args {
            enc.clear_buffer(a, 0, None);
        }
        let begin = |enc: &mut wgpu::CommandEncoder, stage: usize| {
            let writes = match stages {
                Some(st) => st.writes(stage),
                None => timer.and_then(|t| t.pass_writes()),
            };
            let mut pass = enc
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("multipass rounds"),
                    timestamp_writes: writes,
                })
                .forget_lifetime();
            if let Some(u) = user {
                pass.set_bind_group(1, u, &[]);
            }
            pass
        };
        // Round k: its items' parity, the arguments it may plan, where its own are.
        let round = |pass: &mut wgpu::ComputePass, k: usize| {
            pass.set_bind_group(0, &d.bind[(first_round as usize + k) % 2], &[]);
            pass.set_bind_group(2, &d.args_bind[(k + 1) % 2], &[k as u32 * d.index_stride]);
        };
        let args = |k: usize, q: usize| ((k / 2 * nq + q) * 12) as u64;
        let plan = |pass: &mut wgpu::ComputePass| {
            pass.set_bind_group(0, &d.bind[first_round as usize % 2], &[]);
            pass.set_bind_group(2, &d.args_bind[0], &[0]);
            pass.set_pipeline(&p[0]);
            pass.dispatch_workgroups(1, 1, 1);
        };
        if stages.is_some() {
            plan(&mut begin(enc, nq));
            for k in 0..rounds as usize {
                for q in 0..nq {
                    let mut pass = begin(enc, q);
                    round(&mut pass, k);
                    pass.set_pipeline(&p[1 + q]);
                    pass.dispatch_workgroups_indirect(&d.args[k % 2], args(k, q));
                }
            }
            return;
        }
        let mut pass = begin(enc, 0);
        plan(&mut pass);
        for k in 0..rounds as usize {
            round(&mut pass, k);
            for (g, &pipeline) in self.group_pipelines.iter().enumerate() {
                pass.set_pipeline(&p[pipeline]);
                pass.dispatch_workgroups_indirect(&d.args[k % 2], args(k, g));
            }
        }
    }

    /// Sets up the next chunk before its submission: none of its rounds ran yet (`G_RAN`),
    /// its first round's inputs are in count window `base` (`G_BASE`), and it has `rounds`
    /// rounds (`G_CHUNK`).
    fn set_chunk(&self, gpu: &Gpu, d: &DeviceRounds, base: usize, rounds: u32) {
        let at = g(self.program.queue_count(), G_RAN) as u64 * 4;
        let words = [0, base as u32, rounds];
        gpu.queue
            .write_buffer(&d.ctrl, at, bytemuck::cast_slice(&words));
    }

    /// Runs the program to completion from `seeds`; `user` is bind group 1, if the program has
    /// one; `max_queue_bytes` bounds the item, emit and flag storage of this run. `reads`:
    /// buffer ranges copied into the counters' read-back at the end of every submission,
    /// returned (one vector per range) as the last one left them. Errors: every [`RunError`] but `NoAdapter` (see
    /// `docs/scheduler.md`, section 6).
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
        let RunStart {
            live,
            seeded,
            max_cap,
        } = QueueLayout::run_start(
            &self.program,
            seeds,
            gpu.max_binding_bytes(),
            self.config.max_capacity,
            max_queue_bytes,
            2,
        )?;
        // The first round's worst-case output is known here: queues too small for it grow
        // before the first submission rather than after a refused one.
        let first_emits: Vec<u64> = (0..nq)
            .map(|t| {
                (0..nq)
                    .map(|p| seeded[p] as u64 * self.program.procs[p].emits[t] as u64)
                    .sum()
            })
            .collect();
        let capacity: Vec<u32> = (0..nq)
            .map(|q| {
                let n = seeded[q];
                self.config.initial_capacity.min(max_cap[q]).max(n).max(1)
            })
            .collect();
        let mut capacity: Vec<u32> = (0..nq)
            .map(|t| match first_emits[t] > capacity[t] as u64 {
                true => grow(capacity[t], 2 * first_emits[t], max_cap[t]),
                false => capacity[t],
            })
            .collect();
        let mut anticipation = Anticipation::new(first_emits.iter().sum());
        let rounds_per_submit = self.config.rounds_per_submit.clamp(1, MAX_CHUNK);
        // Rounds of the next submission: as many as the last run needed (so a repeated run is
        // one submission and no empty round), else a chunk; fewer while queues grow.
        let learned = self
            .learned_rounds
            .load(std::sync::atomic::Ordering::Relaxed);
        let mut rounds = match learned {
            0 => rounds_per_submit,
            n => n.min(MAX_LEARNED_ROUNDS),
        };
        let mut stats = RunStats {
            strategy: "multipass".into(),
            item_layout: self.item_layout().name().into(),
            round_dispatch: self.round_dispatch().into(),
            max_workgroups: self.config.max_workgroups,
            executed: vec![0; nq],
            peak_occupancy: vec![0; nq],
            ..Default::default()
        };
        let mut stage_timer = self
            .config
            .stage_timing
            .then(|| StageTimer::new(gpu, nq + 1, rounds.max(rounds_per_submit) * nq as u32 + 1));
        let mut encoded = 0u64;
        // Each submission's counters come back in its own read-back, with its GPU time (no
        // wait of its own) and the caller's ranges after them.
        let kept = self.readback.lock().unwrap().take();
        let rb = TimedReadback::reuse(
            kept,
            gpu,
            "multi-pass read-back",
            ctrl_words(nq) as u64,
            reads,
        );
        let mut gpu_ms = gpu.timestamps.then_some(0.0);
        let results;
        // Rounds encoded since the last upload: round r reads items[r % 2].
        let mut since_upload = 0u64;
        let cached = self.cache.lock().unwrap().take();
        let kept = cached.as_ref().map(|d| d.layout.capacity.as_slice());
        capacity = start_capacity(self.config.size_from_last_run, kept, capacity, &max_cap);
        let layout = QueueLayout::new(&self.program, capacity.clone())?;
        let at_limit = partial::at_limit(&capacity, &max_cap);
        let mut d = match cached {
            Some(d) if d.layout == layout && d.at_limit == at_limit => d,
            _ => self.device_rounds(gpu, layout, at_limit, MAX_CHUNK)?,
        };
        self.upload(gpu, &d, &live);
        // The encoder of the next chunk, when a growth already recorded its inputs' move.
        let mut moved: Option<wgpu::CommandEncoder> = None;
        loop {
            if encoded >= self.config.max_rounds as u64 {
                return Err(RunError::NoProgress(format!(
                    "work left after {encoded} multi-pass rounds"
                )));
            }
            let mut enc = moved
                .take()
                .unwrap_or_else(|| gpu.device.create_command_encoder(&Default::default()));
            // Round r since the upload reads items[r % 2] and count window r % 3.
            let base = (since_upload % WINDOWS as u64) as usize;
            let first_round = since_upload;
            self.set_chunk(gpu, &d, base, rounds);
            self.encode_rounds(
                &mut enc,
                &d,
                rounds,
                since_upload,
                Some(&rb),
                stage_timer.as_ref(),
                user,
            );
            rb.copy(&mut enc, Some(&d.ctrl), stage_timer.is_none(), reads);
            if let Some(st) = &stage_timer {
                st.resolve(&mut enc);
            }
            gpu.submit(enc);
            stats.submits += 1;
            stats.launches += 1 + rounds as u64 * self.dispatches_per_round();
            encoded += rounds as u64;
            since_upload += rounds as u64;
            let words = rb.read(gpu, reads)?;
            let ctrl = rb.counters(&words);
            if let Some(st) = &mut stage_timer {
                st.collect(gpu)?;
            } else {
                rb.add_ms(&words, &mut gpu_ms);
            }
            let error = ctrl[g(nq, G_ERROR)];
            let (a, b) = (ctrl[g(nq, G_ERR_A)] as usize, ctrl[g(nq, G_ERR_B)]);
            if error == ERR_EMIT {
                return Err(RunError::EmitLimit {
                    procedure: self.program.procs[a].proc.name.clone(),
                    target: self.program.procs[b as usize].proc.name.clone(),
                    declared: self.program.procs[a].emits[b as usize],
                });
            }
            if error == ERR_ROOM {
                return Err(RunError::Device(format!(
                    "device-driven multi-pass: an append past the capacity the plan made room \
                     for (queue {a}, slot {b})"
                )));
            }
            let halted = error == ERR_OVERFLOW;
            // The inputs of the round after the last that ran (or of the refused round).
            let ran = ctrl[g(nq, G_RAN)] as u64;
            let pending = pending_window(nq, ctrl, base);
            let next: Vec<u32> = (0..nq).map(|q| window_count(ctrl, q, pending)).collect();
            if !halted && next.iter().all(|&n| n == 0) {
                self.accumulate(&mut stats, ctrl);
                results = rb.ranges(&words, reads);
                break;
            }
            if !halted {
                rounds = (rounds * 2).min(rounds_per_submit);
            } else {
                // The refused round's inputs are intact in items[planned % 2]. Every target whose
                // worst case m did not fit grows and the inputs move to the new buffers on the
                // device. A refusal costs a submission, so the growth leaves room for the rounds
                // after as well ([`Anticipation`]): at least doubling, at least 2 m, and m times
                // the work's measured growth over a horizon that doubles with each refusal.
                self.accumulate(&mut stats, ctrl);
                let m: Vec<u64> = (0..nq).map(|t| ctrl[c(t, C_EMITS)] as u64).collect();
                let factor = anticipation.refused(stats.rounds, m.iter().sum());
                // A target at its limit runs in part instead of halting: a refusal with nothing
                // to grow is a real overflow (not one input fits), named by the plan.
                let mut grown = capacity.clone();
                for t in 0..nq {
                    if m[t] > capacity[t] as u64 && capacity[t] < max_cap[t] {
                        grown[t] = grow(capacity[t], 2 * m[t], max_cap[t]);
                    }
                }
                let refused_grew = grown != capacity;
                for t in 0..nq {
                    // Per slot: its item in both parities.
                    let slot_bytes = d.layout.words[t] as u64 * 8;
                    let extra = Anticipation::MAX_EXTRA_BYTES / slot_bytes / nq as u64;
                    let need = ((m[t] as f64 * factor) as u64).min(2 * m[t] + extra);
                    if need > grown[t] as u64 {
                        grown[t] = grow(grown[t], need, max_cap[t]);
                    }
                }
                stats.queue_growths += (0..nq).filter(|&t| grown[t] != capacity[t]).count() as u64;
                let held = (0..nq)
                    .filter(|&t| m[t] > 0)
                    .map(|t| grown[t] as f64 / m[t] as f64)
                    .fold(f64::INFINITY, f64::min);
                rounds = anticipation.rounds_until_refusal(held, rounds_per_submit);
                if !refused_grew {
                    return Err(RunError::QueueOverflow {
                        queue: self.program.procs[a].proc.name.clone(),
                        capacity: capacity[a] as u64,
                        needed_more_than: b as u64,
                    });
                }
                capacity = grown;
                let parity = ((first_round + ran) % 2) as usize;
                let new = self.device_rounds(
                    gpu,
                    QueueLayout::new(&self.program, capacity.clone())?,
                    partial::at_limit(&capacity, &max_cap),
                    MAX_CHUNK,
                )?;
                let mut enc = gpu.device.create_command_encoder(&Default::default());
                self.move_inputs(gpu, &d, parity, &new, &next, &mut enc);
                moved = Some(enc);
                d = new;
                since_upload = 0;
            }
        }
        stats.queue_bytes = d.layout.total_words * 4 * 2;
        self.learned_rounds.store(
            stats.rounds.clamp(1, MAX_LEARNED_ROUNDS as u64) as u32,
            std::sync::atomic::Ordering::Relaxed,
        );
        stats.gpu_ms = gpu_ms;
        if let Some(ms) = stage_timer.and_then(|st| st.stage_ms()) {
            stats.gpu_ms = Some(ms.iter().sum());
            stats.stage_gpu_ms = ms;
        }
        stats.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        *self.cache.lock().unwrap() = Some(d);
        *self.readback.lock().unwrap() = Some(rb);
        Ok((stats, results))
    }

    fn accumulate(&self, stats: &mut RunStats, ctrl: &[u32]) {
        let nq = self.program.queue_count();
        for q in 0..nq {
            stats.executed[q] += ctrl[c(q, C_EXEC)] as u64;
            stats.peak_occupancy[q] = stats.peak_occupancy[q].max(ctrl[c(q, C_PEAK)] as u64);
        }
        stats.rounds += ctrl[g(nq, G_ROUNDS)] as u64;
        stats.partial_rounds += ctrl[g(nq, G_PARTIAL)] as u64;
    }
}
