//! The persistent megakernel strategy: one dispatch whose workgroups pull batches from the
//! procedure queues until no work is left. A launch is bounded (loop turns, waits); when one ends
//! with work left, the host compacts the queues (dropping consumed slots, keeping every live item),
//! grows a queue that lacked room, and launches again. Protocol: `docs/scheduler.md`.

pub mod anatomy;
mod claim;
mod compact;
mod config;
pub use config::*;
pub(crate) mod layout;
pub(crate) mod local;
mod park;
mod queues;
mod relaunch;
pub use local::LOCAL_MAX_BYTES;
pub(crate) mod record;
pub(crate) mod wgsl;

use std::borrow::Cow;
use std::time::Instant;

use layout::*;

use compact::{CompactionPass, DeviceCompaction};
use queues::DeviceQueues;

use crate::error::RunError;
use crate::gpu::Gpu;
use crate::growth::{kept_capacity, with_slack};
use crate::item_layout::ItemLayout;
use crate::pipeline::{Kernels, storage_entry};
use crate::program::{Program, Seed, WORKGROUP_SIZE};
use crate::queue_layout::{QueueLayout, RunStart};
use crate::readback::{ReadRange, Readback, TimedReadback};
use crate::stats::RunStats;

/// A program compiled for the persistent megakernel: one pipeline, queue buffers kept between
/// runs, and the workgroup count (probed on the first run). Usually reached through
/// [`crate::Scheduler`].
pub struct Megakernel {
    program: Program,
    config: MegakernelConfig,
    kernels: Kernels,
    /// Co-resident workgroups the probe found; 0 until the first run's probe (the probe needs
    /// the user's group), and always with `Workgroups::Fixed`. A launch's workgroups follow from
    /// it (`Workgroups::of_probed`).
    probed: std::sync::atomic::AtomicU32,
    outbox_stride: u32,
    ob_off: Vec<u32>,
    priority: Vec<u32>,
    /// Most items a batch of each queue holds ([`claim::batch_items`]).
    batch: Vec<u32>,
    /// Words of each workgroup's local area, past the queues in the slots buffer (0 without
    /// local queues; `local::LocalPlan`).
    local_wg_words: u32,
    /// The local area's bytes in workgroup memory (0: in the slots buffer, or none).
    local_workgroup_bytes: u32,
    /// Buffers of the last run, reused when the next run needs the same layout.
    cache: std::sync::Mutex<Option<DeviceQueues>>,
    /// The mapped buffer ctrl is read back through after each launch, and the timer whose
    /// timestamps come back with it, kept between runs (boxed: `Scheduler`'s variants stay
    /// near one size).
    readback: std::sync::Mutex<Option<Box<TimedReadback>>>,
    compaction: DeviceCompaction,
    /// Slots per queue that the largest run so far needed to finish in one launch (see
    /// [`Megakernel::run`]); the next run starts with at least this much, within its limits.
    one_launch_need: std::sync::Mutex<Vec<u64>>,
}

/// How the next launch gets its live items.
enum Start<'a> {
    /// Written by the host (seeds, or what [`compact::host_compact`] kept).
    Upload(Vec<Cow<'a, [u32]>>),
    /// Copied on the device from the previous launch's buffers, whose first `reserved[q]`
    /// tickets hold `live[q]` published, unconsumed items per queue.
    Compact {
        old: Box<DeviceQueues>,
        reserved: Vec<u32>,
        live: Vec<u32>,
    },
}

impl Megakernel {
    /// Compiles `program` for the megakernel on `gpu`.
    ///
    /// On lavapipe (adapter name `llvmpipe`) `max_iterations` and `spin_limit` are lowered to
    /// [`LAVAPIPE_MAX_ITERATIONS`] and [`LAVAPIPE_SPIN_LIMIT`], and `idle_backoff` to 0. Errors:
    /// [`RunError::Program`] for `max_iterations` or `spin_limit` outside `1..=30000`,
    /// `idle_backoff` above 30,000, a [`Workgroups::ProbeShare`] of 0 or above 1, an unknown
    /// procedure name in [`QueuePolicy::Priority`], or WGSL that does not compile with the generated code (e.g.
    /// user WGSL that reuses a template identifier).
    pub fn new(
        gpu: &Gpu,
        program: &Program,
        mut config: MegakernelConfig,
    ) -> Result<Megakernel, RunError> {
        if gpu.is_lavapipe() {
            // lavapipe's loop limiter is one counter per invocation for a whole outermost loop
            // and everything nested in it: after 65,535 iterations in total, every loop exits at
            // its first test. A persistent launch must stay far below that, bodies included.
            config.max_iterations = config.max_iterations.min(LAVAPIPE_MAX_ITERATIONS);
            config.spin_limit = config.spin_limit.min(LAVAPIPE_SPIN_LIMIT);
            config.idle_backoff = 0;
        }
        if config.idle_backoff > 30_000 {
            return Err(RunError::Program("idle_backoff must be 0..=30000".into()));
        }
        if config.max_iterations == 0 || config.max_iterations > 30_000 {
            return Err(RunError::Program(
                "max_iterations must be 1..=30000 (lavapipe cuts loops at 65,535)".into(),
            ));
        }
        if config.spin_limit == 0 || config.spin_limit > 30_000 {
            return Err(RunError::Program("spin_limit must be 1..=30000".into()));
        }
        if let Workgroups::ProbeShare {
            numerator,
            denominator,
            ..
        } = config.workgroups
            && (numerator == 0 || numerator > denominator)
        {
            return Err(RunError::Program(format!(
                "a workgroup share of {numerator}/{denominator}: it must be more than 0 and at \
                 most 1"
            )));
        }
        let most = gpu.device.limits().max_compute_invocations_per_workgroup;
        if config.workgroup_size > most {
            return Err(RunError::Program(format!(
                "megakernel workgroup size {} is more than {} allows ({most} invocations)",
                config.workgroup_size,
                gpu.adapter_name()
            )));
        }
        // The megakernel's own view of the program: items per step and `.shared` arrays for
        // its workgroup size.
        let program = &program.with_workgroup_size(config.workgroup_size)?;
        let nq = program.queue_count();
        let priority = claim::priority_order(program, &config.policy)?;
        let batch = claim::batch_items(program, &config)?;
        // Outbox: per source queue, room for a whole batch's worst-case output to each target.
        let mut ob_off = vec![0u32; nq * nq];
        let mut outbox_stride = 1;
        // Direct enqueue: per source queue, where each target's part of the batch's ticket list
        // starts (items), and the longest list.
        let mut es_off = vec![0u32; nq * nq];
        let mut emit_slots = 1;
        for (q, p) in program.procs.iter().enumerate() {
            let batch = batch[q];
            let (mut off, mut es) = (0, 0);
            for t in 0..nq {
                ob_off[q * nq + t] = off;
                es_off[q * nq + t] = es;
                // 16-byte aligned parts, so items that move by vec4 stay aligned.
                off += (batch * p.emits[t] * program.procs[t].words()).next_multiple_of(4);
                es += batch * p.emits[t];
            }
            outbox_stride = outbox_stride.max(off).next_multiple_of(4);
            emit_slots = emit_slots.max(es);
        }
        // Tickets a batch may list: MAX_DIRECT_EMITS per 256 threads (the list grows with the
        // batch), and only while the whole kernel's workgroup memory fits the device's limit
        // (checked on the generated source below).
        let most_tickets = MAX_DIRECT_EMITS * (program.workgroup_size() / WORKGROUP_SIZE);
        let wanted = config.direct_enqueue.unwrap_or(true);
        let mut direct = wanted && emit_slots <= most_tickets;
        if config.direct_enqueue == Some(true) && !direct {
            log::warn!(
                "megakernel: direct enqueue was asked for, but a batch may emit {emit_slots} \
                 items, more than the {most_tickets} tickets it can list: enqueueing \
                 through the outbox (fewer batch steps would fit)"
            );
        }
        let items = config
            .item_layout
            .unwrap_or_else(|| ItemLayout::for_program(gpu, program));
        config.item_layout = Some(items);
        if config.subgroups == Some(true) && !gpu.subgroups {
            return Err(RunError::Program(format!(
                "subgroups asked for, but {} lacks wgpu's SUBGROUP feature",
                gpu.adapter_name()
            )));
        }
        let subgroups = config.subgroups.unwrap_or(gpu.subgroups);
        config.subgroups = Some(subgroups);
        let limit = gpu.device.limits().max_compute_workgroup_storage_size;
        let generate = |plan: &local::LocalPlan, direct: bool| {
            wgsl::source(
                program,
                gpu.coherent,
                items,
                direct.then_some((emit_slots, es_off.as_slice())),
                wgsl::Switches {
                    anatomy: config.turn_anatomy,
                    subgroups,
                    guided_claims: config.guided_claims,
                },
                plan,
            )
        };
        let mut plan = local::LocalPlan::none(nq);
        let mut source = generate(&plan, direct);
        if direct && local::workgroup_bytes(&source)? > limit {
            if config.direct_enqueue == Some(true) {
                log::warn!(
                    "megakernel: direct enqueue was asked for, but its list of {emit_slots} \
                     tickets does not fit {}'s {limit} bytes of workgroup memory beside the \
                     rest: enqueueing through the outbox",
                    gpu.adapter_name()
                );
            }
            direct = false;
            source = generate(&plan, direct);
        }
        if direct {
            // Items go straight to their slots: no outbox.
            outbox_stride = 4;
        }
        config.direct_enqueue = Some(direct);
        log::debug!(
            "megakernel: {} enqueue (a batch emits at most {emit_slots} items; direct up to \
             {most_tickets})",
            if direct { "direct" } else { "outbox" }
        );
        local::LocalPlan::warn_unused(&config);
        if config.local_queues && !program.has_local() {
            log::warn!(
                "megakernel: local queues are on, but no procedure keeps an emit local \
                 (Procedure::local): running without them"
            );
        }
        let bytes = local::LocalPlan::bytes_for(&config);
        if config.local_queues && program.has_local() {
            plan = local::LocalPlan::for_config(program, &batch, &config);
            if plan.active() {
                source = generate(&plan, direct);
            } else {
                log::warn!(
                    "megakernel: local queues are on, but {bytes} bytes per workgroup \
                     (local_bytes, local_workgroup_bytes) hold no item of any local target: \
                     running without them"
                );
            }
            log::debug!(
                "megakernel: local queues of {:?} items per buffer ({} bytes per workgroup)",
                plan.cap,
                plan.wg_words * 4
            );
        }
        config.local_queues = plan.active();
        // Checked here, with the sizes that made it: neither wgpu nor every driver refuses a
        // kernel that declares more (lavapipe ran one of 52 KB against its 32 KB).
        let used = local::workgroup_bytes(&source)?;
        plan.warn_partial_steps(program, bytes, used, limit);
        if used > limit {
            let why = plan.workgroup_overflow_hint(used, limit);
            return Err(RunError::Program(format!(
                "megakernel: {used} bytes of workgroup memory at {} threads per workgroup, more \
                 than {}'s {limit} ({why})",
                program.workgroup_size(),
                gpu.adapter_name()
            )));
        }
        let entries = [
            storage_entry(0, false),
            storage_entry(1, false),
            storage_entry(2, false),
            storage_entry(3, false),
            storage_entry(4, true),
        ];
        let kernels = Kernels::new(
            gpu,
            program,
            "megakernel",
            &source,
            &entries,
            &["megakernel"],
            None,
        )?;
        Ok(Megakernel {
            program: program.clone(),
            config,
            kernels,
            probed: std::sync::atomic::AtomicU32::new(0),
            outbox_stride,
            ob_off,
            priority,
            batch,
            cache: Default::default(),
            readback: Default::default(),
            compaction: DeviceCompaction::new(gpu)?,
            one_launch_need: std::sync::Mutex::new(vec![0; nq]),
            local_wg_words: plan.wg_words,
            local_workgroup_bytes: plan.workgroup_area_bytes(),
        })
    }

    /// The program this megakernel runs.
    pub fn program(&self) -> &Program {
        &self.program
    }

    /// Whether its procedures enqueue straight into the slots (`MegakernelConfig::direct_enqueue`
    /// and the batch's worst case within [`MAX_DIRECT_EMITS`]) or through the outbox.
    pub fn direct_enqueue(&self) -> bool {
        self.config.direct_enqueue == Some(true)
    }

    /// Whether enqueue tickets are taken once per subgroup (`MegakernelConfig::subgroups`).
    pub fn subgroups(&self) -> bool {
        self.config.subgroups == Some(true)
    }

    fn enqueue_name(&self) -> &'static str {
        if self.direct_enqueue() {
            "direct"
        } else {
            "outbox"
        }
    }

    /// How its queues hold items (the configured layout, or the program's).
    pub fn item_layout(&self) -> ItemLayout {
        self.config.item_layout.unwrap_or_default()
    }

    /// Workgroups per launch, probing on first use (the probe launch needs the user's bind
    /// group, as a run does). Errors: those of a run ([`RunError::Timeout`], [`RunError::Device`]).
    pub fn workgroups(&self, gpu: &Gpu, user: Option<&wgpu::BindGroup>) -> Result<u32, RunError> {
        if self.needs_probe() {
            let (Workgroups::Probe { max } | Workgroups::ProbeShare { max, .. }) =
                self.config.workgroups
            else {
                unreachable!()
            };
            let start = Instant::now();
            let probed = self.probe(gpu, max.max(1), user)?;
            let n = self.config.workgroups.of_probed(probed);
            log::debug!(
                "megakernel co-residency probe: {probed} workgroups of at most {max}, {n} \
                 launched, {:.1} ms (the first launch: includes the driver's deferred compile)",
                start.elapsed().as_secs_f64() * 1e3
            );
            self.probed
                .store(probed, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(self.config.workgroups.of_probed(self.probed_workgroups()))
    }

    /// Whether the next run probes the workgroup count first (a probing configuration's first).
    fn needs_probe(&self) -> bool {
        !matches!(self.config.workgroups, Workgroups::Fixed(_)) && self.probed_workgroups() == 0
    }

    /// Co-resident workgroups the probe found (0 before the first run, and with
    /// [`Workgroups::Fixed`]).
    pub fn probed_workgroups(&self) -> u32 {
        self.probed.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Counts workgroups that run at the same time (see `probe` in the shader). A CPU adapter
    /// (lavapipe) runs at most one workgroup per hardware thread at once, and runs the probe's
    /// spinning workgroups one after another: probing more than that many only costs time
    /// (seconds on two cores), so its `max` is capped there.
    fn probe(&self, gpu: &Gpu, max: u32, user: Option<&wgpu::BindGroup>) -> Result<u32, RunError> {
        let max = if gpu.is_cpu_adapter() {
            let threads = std::thread::available_parallelism().map_or(1, |n| n.get() as u32);
            max.min(threads)
        } else {
            max
        };
        let nq = self.program.queue_count();
        let layout = QueueLayout::new(&self.program, vec![1; nq])?;
        let mut params = self.params(&layout);
        params[P_PROBE] = 1;
        params[P_SPIN] = 20_000;
        let dq = self.device_queues(gpu, layout, &params, 1, None)?;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.kernels.pipelines[0]);
            pass.set_bind_group(0, &dq.bind, &[]);
            if let Some(u) = user {
                pass.set_bind_group(1, u, &[]);
            }
            pass.dispatch_workgroups(max, 1, 1);
        }
        let words = ctrl_words(nq) as u64;
        let rb = Readback::new(gpu, "probe read-back", words);
        rb.copy(&mut enc, &dq.ctrl, 0, 0, words);
        gpu.submit(enc);
        let ctrl = rb.read(gpu, words)?;
        Ok(ctrl[g(nq, G_PROBE_RESIDENT)].clamp(1, max))
    }

    /// Most bytes the queues' slots may take in the slots binding: the device's limit less the
    /// workgroups' local areas that follow them.
    fn queue_binding_bytes(&self, gpu: &Gpu, workgroups: u32) -> u64 {
        gpu.max_binding_bytes()
            .saturating_sub(self.local_area_words(workgroups) * 4)
    }

    /// Words of the local areas of `workgroups` workgroups, past the queues in the slots buffer.
    fn local_area_words(&self, workgroups: u32) -> u64 {
        workgroups as u64 * self.local_wg_words as u64
    }

    /// The workgroups a run within `max_queue_bytes` launches: every one, unless their local
    /// areas would take more than half of the budget; then as many as half of it holds (at
    /// least one, which may then overflow), with a warning. The local areas are a fixed size per workgroup (compiled
    /// in), so a budget that suits the queues would otherwise fail on a GPU that runs many
    /// workgroups (H200, 660 workgroups: a small tree's run under 1 MiB overflowed).
    fn workgroups_within(&self, workgroups: u32, max_queue_bytes: Option<u64>) -> u32 {
        let area = self.local_wg_words as u64 * 4;
        let Some(budget) = max_queue_bytes else {
            return workgroups;
        };
        if area * workgroups as u64 <= budget / 2 {
            return workgroups;
        }
        let fit = (budget / 2 / area).min(workgroups as u64) as u32;
        if fit == 0 {
            log::warn!(
                "megakernel: a queue memory budget of {budget} bytes is less than twice one \
                 workgroup's local queue area ({area} bytes): this run launches 1 workgroup, \
                 and its queues may not fit (raise the budget or lower local_bytes)"
            );
            return 1;
        }
        log::warn!(
            "megakernel: a queue memory budget of {budget} bytes holds the local queue areas \
             ({area} bytes each) of {fit} of the {workgroups} workgroups in half of it: this \
             run launches {fit} (raise the budget or lower local_bytes to run them all)"
        );
        fit
    }

    /// What of a run's queue storage budget the queues may take: the budget less the
    /// workgroups' local areas.
    fn queue_budget(&self, max_queue_bytes: Option<u64>, workgroups: u32) -> Option<u64> {
        max_queue_bytes.map(|b| b.saturating_sub(self.local_area_words(workgroups) * 4))
    }

    fn params(&self, layout: &QueueLayout) -> Vec<u32> {
        let nq = self.program.queue_count();
        let mut p = vec![0u32; P_QUEUES + nq * 5 + nq * nq];
        p[P_MAX_ITERS] = self.config.max_iterations;
        p[P_SPIN] = self.config.spin_limit;
        p[P_POLICY] = matches!(self.config.policy, QueuePolicy::Fifo) as u32;
        p[P_OUTBOX_STRIDE] = self.outbox_stride;
        p[P_IDLE_BACKOFF] = self.config.idle_backoff;
        p[P_PAUSE_LINK] = 0; // the pause's chain stays on this word
        p[P_LOCAL_BASE] = layout.total_words as u32;
        for q in 0..nq {
            p[P_QUEUES + q * 4] = layout.capacity[q];
            p[P_QUEUES + q * 4 + 1] = layout.slot_base[q];
            p[P_QUEUES + q * 4 + 2] = layout.flag_base[q];
            p[P_QUEUES + q * 4 + 3] = self.batch[q];
            p[P_QUEUES + nq * 4 + q] = self.priority[q];
        }
        p[P_QUEUES + nq * 5..].copy_from_slice(&self.ob_off);
        p
    }

    /// Runs the program to completion from `seeds`. `user` is bind group 1, if the program has
    /// one. `max_queue_bytes` bounds the queue storage (slots, the workgroups' local areas and
    /// flags) of this run. `reads`: buffer ranges copied after every launch into its counters'
    /// read-back, returned (one vector per range) as the last launch left them: results come
    /// back with the run's own last host wait. Errors:
    /// every [`RunError`] but `NoAdapter` (see `docs/scheduler.md`, section 6).
    pub fn run(
        &self,
        gpu: &Gpu,
        seeds: &[Seed],
        user: Option<&wgpu::BindGroup>,
        max_queue_bytes: Option<u64>,
        reads: &[ReadRange],
    ) -> Result<(RunStats, Vec<Vec<u32>>), RunError> {
        self.kernels.check_user_group(user)?;
        // A first run probes the workgroup count: one submission and wait more.
        let probed = self.needs_probe();
        let workgroups = self.workgroups_within(self.workgroups(gpu, user)?, max_queue_bytes);
        let start_time = Instant::now();
        let nq = self.program.queue_count();
        let RunStart {
            live,
            seeded,
            max_cap,
        } = QueueLayout::run_start(
            &self.program,
            seeds,
            self.queue_binding_bytes(gpu, workgroups),
            self.config.max_capacity,
            self.queue_budget(max_queue_bytes, workgroups),
            1,
        )?;
        // A queue holds every ticket of a launch, so a run grows its queues (each growth a
        // relaunch with a host round trip) unless they start with room for all it appends. What
        // an earlier run of this program needed is the best estimate the host has: start there.
        let known = match self.config.size_from_last_run {
            true => self.one_launch_need.lock().unwrap().clone(),
            false => vec![0; nq],
        };
        let need: Vec<u32> = (0..nq)
            .map(|q| {
                let n = seeded[q];
                let want = self.config.initial_capacity.max(n.saturating_mul(2)).max(1);
                let want = want.max(known[q].min(u32::MAX as u64) as u32);
                want.min(max_cap[q]).max(n)
            })
            .collect();
        let mut dq: Option<DeviceQueues> = self.cache.lock().unwrap().take();
        // The last run's queues when they hold this run's need (no new buffers), else new ones
        // with slack where the need came from an earlier run.
        let kept = dq.as_ref().map(|d| d.layout.capacity.as_slice());
        let mut capacity = kept_capacity(kept, &need, &max_cap).unwrap_or_else(|| {
            (0..nq)
                .map(|q| match known[q] >= need[q] as u64 && known[q] > 0 {
                    true => with_slack(need[q] as u64, max_cap[q]).max(need[q]),
                    false => need[q],
                })
                .collect()
        });
        let mut stats = RunStats {
            strategy: "megakernel".into(),
            item_layout: self.item_layout().name().into(),
            enqueue: self.enqueue_name().into(),
            executed: vec![0; nq],
            peak_occupancy: vec![0; nq],
            workgroups,
            probed_workgroups: self.probed_workgroups(),
            workgroup_size: self.config.workgroup_size,
            local_queues: self.local_wg_words > 0,
            local_workgroup_bytes: self.local_workgroup_bytes,
            guided_claims: self.config.guided_claims,
            queue_order: match self.config.policy {
                QueuePolicy::Priority(_) => (self.priority.iter())
                    .map(|&q| self.program.procs[q as usize].proc.name.clone())
                    .collect(),
                QueuePolicy::Fifo => Vec::new(),
            },
            turn_anatomy: self.config.turn_anatomy.then(anatomy::TurnAnatomy::default),
            submits: probed as u64,
            ..Default::default()
        };
        // Each launch's GPU time and the caller's ranges come back with its counters (one
        // read-back, no extra wait).
        let mut gpu_ms = gpu.timestamps.then_some(0.0);
        let kept = self.readback.lock().unwrap().take().map(|k| *k);
        let rb = TimedReadback::reuse(kept, gpu, "ctrl read-back", ctrl_words(nq) as u64, reads);
        let results;
        let mut start = Start::Upload(live);
        // Live items set aside while the queues at their limits cannot hold them (park.rs).
        let mut parked = park::Parked::default();
        loop {
            let layout = QueueLayout::new(&self.program, capacity.clone())?;
            if dq
                .as_ref()
                .is_none_or(|d| d.layout != layout || d.workgroups != workgroups)
            {
                let outbox = match &start {
                    Start::Compact { old, .. } => Some(old.outbox.clone()),
                    Start::Upload(_) => None,
                };
                dq = Some(self.device_queues(
                    gpu,
                    layout.clone(),
                    &self.params(&layout),
                    workgroups,
                    outbox,
                )?);
            }
            let d = dq.as_mut().unwrap();
            if stats.launches >= self.config.max_launches as u64 {
                return Err(RunError::NoProgress(format!(
                    "work left after {} megakernel launches{}",
                    stats.launches,
                    park::launches_hint(stats.parked_items)
                )));
            }
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            let compaction: Option<CompactionPass> = match &start {
                Start::Upload(live) => {
                    stats.flags_cleared += self.upload(gpu, d, live, &mut enc);
                    None
                }
                Start::Compact {
                    old,
                    reserved,
                    live,
                } => {
                    self.write_ctrl(gpu, &d.ctrl, live);
                    Some(
                        self.compaction
                            .prepare(gpu, old, d, reserved, self.item_layout())?,
                    )
                }
            };
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("megakernel"),
                    timestamp_writes: rb.pass_writes(),
                });
                if let Some(c) = &compaction {
                    self.compaction.record(&mut pass, c);
                }
                pass.set_pipeline(&self.kernels.pipelines[0]);
                pass.set_bind_group(0, &d.bind, &[]);
                if let Some(u) = user {
                    pass.set_bind_group(1, u, &[]);
                }
                pass.dispatch_workgroups(workgroups, 1, 1);
            }
            rb.copy(&mut enc, Some(&d.ctrl), true, reads);
            gpu.submit(enc);
            let words = rb.read(gpu, reads)?;
            rb.add_ms(&words, &mut gpu_ms);
            let ctrl = rb.counters(&words);
            d.launched(ctrl);
            stats.launches += 1;
            stats.submits += 1;
            if let Start::Compact { live, .. } = &start {
                compact::check(&self.program, ctrl, live)?;
            }
            if ctrl[g(nq, G_ERROR)] == ERR_EMIT {
                let (p, t) = (ctrl[g(nq, G_ERR_A)] as usize, ctrl[g(nq, G_ERR_B)] as usize);
                return Err(RunError::EmitLimit {
                    procedure: self.program.procs[p].proc.name.clone(),
                    target: self.program.procs[t].proc.name.clone(),
                    declared: self.program.procs[p].emits[t],
                });
            }
            let mut progress = 0;
            for q in 0..nq {
                let local = ctrl[layout::q(q, Q_LOCAL)] as u64;
                stats.executed[q] += ctrl[layout::q(q, Q_EXECUTED)] as u64 + local;
                stats.local_items += local;
                progress += ctrl[layout::q(q, Q_EXECUTED)] as u64 + local;
                stats.batches += ctrl[layout::q(q, Q_BATCHES)] as u64;
                stats.peak_occupancy[q] =
                    stats.peak_occupancy[q].max(ctrl[layout::q(q, Q_PEAK)] as u64);
            }
            stats.idle_polls += ctrl[g(nq, G_IDLE)] as u64;
            if let Some(a) = stats.turn_anatomy.as_mut() {
                a.add_launch(&ctrl[g(nq, G_AN)..g(nq, G_AN) + AN_WORDS]);
            }
            stats.abandoned += ctrl[g(nq, G_ABANDONED)] as u64;
            if ctrl[g(nq, G_PENDING)] == 0 && ctrl[g(nq, G_ABANDONED)] == 0 {
                if let Some(chunk) = parked.take() {
                    start = Start::Upload(chunk.into_iter().map(Cow::Owned).collect());
                    continue;
                }
                results = rb.ranges(&words, reads);
                break;
            }
            // Work is left: live items per queue, and the queues grown for the next launch.
            let relaunch::Sizing {
                reserved,
                live,
                grew,
                stuck,
            } = relaunch::size(gpu, nq, ctrl, &mut capacity, &max_cap, &mut stats)?;
            if progress == 0 && !grew && stuck.is_none() && ctrl[g(nq, G_ABANDONED)] == 0 {
                return Err(RunError::NoProgress(
                    "a megakernel launch executed no item".into(),
                ));
            }
            start = if grew {
                // New buffers; the live items move there on the device, in the next launch's pass.
                Start::Compact {
                    old: Box::new(dq.take().expect("buffers of the launch")),
                    reserved,
                    live,
                }
            } else {
                stats.submits += 1;
                stats.host_compactions += 1;
                let mut items =
                    compact::host_compact(gpu, &self.program, d, ctrl, self.item_layout())?;
                if progress == 0
                    && let Some((q, needed, _)) = stuck
                {
                    // The queues at their limits hold the work's breadth: the oldest half of
                    // it waits on the host while the newest runs, depth first (park.rs).
                    let Some((rest, n)) = parked.split(items, &d.layout.words) else {
                        return Err(RunError::QueueOverflow {
                            queue: self.program.procs[q].proc.name.clone(),
                            capacity: capacity[q] as u64,
                            needed_more_than: needed,
                        });
                    };
                    stats.parked_items += n;
                    items = rest;
                }
                Start::Upload(items.into_iter().map(Cow::Owned).collect())
            };
        }
        // Room for one launch of this run: every item it appended to a queue (the executed ones:
        // all ran) plus the worst case that running batches may have promised at once.
        {
            let mut known = self.one_launch_need.lock().unwrap();
            for (t, need) in known.iter_mut().enumerate() {
                let promised: u64 = (0..nq)
                    .map(|q| {
                        let p = &self.program.procs[q];
                        workgroups as u64 * self.batch[q] as u64 * p.emits[t] as u64
                    })
                    .sum();
                *need = (*need).max(stats.executed[t] + promised);
            }
        }
        // The slots buffer holds the workgroups' local areas too.
        stats.queue_bytes = dq
            .as_ref()
            .map_or(0, |d| d.slots.size() + d.layout.total_slots * 4);
        stats.gpu_ms = gpu_ms;
        stats.wall_ms = start_time.elapsed().as_secs_f64() * 1e3;
        // Keep the device queues and the read-back buffer for the next run.
        *self.cache.lock().unwrap() = dq;
        *self.readback.lock().unwrap() = Some(Box::new(rb));
        Ok((stats, results))
    }
}
