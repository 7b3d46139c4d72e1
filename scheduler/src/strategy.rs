//! One front door for every strategy, so workloads and benchmarks can name one and run it.

use crate::error::RunError;
use crate::gpu::Gpu;
use crate::item_layout::ItemLayout;
use crate::megakernel::{Megakernel, MegakernelConfig};
use crate::multipass::host::{HostMultipass, HostMultipassConfig};
use crate::multipass::{Multipass, MultipassConfig};
use crate::program::{Program, Seed};
use crate::readback::ReadRange;
use crate::stats::RunStats;

/// The scheduling strategies, by the names the command lines and reports use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StrategyKind {
    /// `megakernel`: persistent workgroups pulling batches from on-device queues.
    Megakernel,
    /// `multipass`: rounds planned on the device (indirect dispatches), scan/compact per target.
    Multipass,
    /// `multipass-host`: rounds planned by the host from read-back counts (exact direct
    /// dispatches), compaction fused into the producing pass.
    MultipassHost,
    /// `multipass-floor`: a reference, not a strategy to deploy: the host-driven multi-pass
    /// replaying the items of an earlier run of the same seeds in one round
    /// ([`HostMultipassConfig::replay_floor`]), so its GPU time is the bodies' work without
    /// the rounds' cost, a floor for any multi-pass. Not in [`StrategyKind::ALL`].
    MultipassFloor,
}

impl StrategyKind {
    /// Every strategy, in the order reports list them.
    pub const ALL: [StrategyKind; 3] = [
        StrategyKind::Megakernel,
        StrategyKind::Multipass,
        StrategyKind::MultipassHost,
    ];

    /// Every strategy a command line may name: [`StrategyKind::ALL`] and the floor.
    pub const NAMED: [StrategyKind; 4] = [
        StrategyKind::Megakernel,
        StrategyKind::Multipass,
        StrategyKind::MultipassHost,
        StrategyKind::MultipassFloor,
    ];

    /// The name command lines and reports use: `megakernel`, `multipass`, `multipass-host`,
    /// `multipass-floor`.
    pub fn name(self) -> &'static str {
        match self {
            StrategyKind::Megakernel => "megakernel",
            StrategyKind::Multipass => "multipass",
            StrategyKind::MultipassHost => "multipass-host",
            StrategyKind::MultipassFloor => "multipass-floor",
        }
    }

    /// The strategy named `s` (as [`StrategyKind::name`] spells it), if any.
    pub fn parse(s: &str) -> Option<StrategyKind> {
        Self::NAMED.into_iter().find(|k| k.name() == s)
    }
}

/// A program compiled for one strategy, ready to run many times (buffers are kept between runs
/// and regrown as needed).
///
/// ```
/// # fn main() -> Result<(), scheduler::RunError> {
/// use scheduler::{Gpu, ItemType, Procedure, Program, Scheduler, Seed, StrategyKind, UserBindings};
/// let gpu = Gpu::from_env()?;
/// let word = ItemType::new("Word", "struct Word { v: u32 }");
/// let count = Procedure::new("count", word, 1)
///     .emits("count", 1)
///     .body("fn count_execute(item: Word, inv: Invocation) { if item.v > 0u { enqueue_count(Word(item.v - 1u)); } }");
/// let program = Program::new(vec![count], UserBindings::none())?;
/// let scheduler = Scheduler::new(&gpu, &program, StrategyKind::Megakernel, 1024)?;
/// let stats = scheduler.run(&gpu, &[Seed::new("count", &[10u32, 20])], None)?;
/// assert_eq!(stats.executed, [11 + 21]);
/// # Ok(()) }
/// ```
pub enum Scheduler {
    /// The persistent megakernel (`megakernel`).
    Megakernel(Megakernel),
    /// The device-driven multi-pass baseline (`multipass`).
    Multipass(Multipass),
    /// The host-driven multi-pass baseline (`multipass-host`), or with
    /// [`HostMultipassConfig::replay_floor`] the multi-pass floor (`multipass-floor`).
    MultipassHost(HostMultipass),
}

impl Scheduler {
    /// The megakernel with a full configuration ([`Megakernel::new`]).
    pub fn megakernel(
        gpu: &Gpu,
        program: &Program,
        config: MegakernelConfig,
    ) -> Result<Self, RunError> {
        Ok(Scheduler::Megakernel(Megakernel::new(
            gpu, program, config,
        )?))
    }

    /// The device-driven multi-pass with a full configuration ([`Multipass::new`]).
    pub fn multipass(
        gpu: &Gpu,
        program: &Program,
        config: MultipassConfig,
    ) -> Result<Self, RunError> {
        Ok(Scheduler::Multipass(Multipass::new(gpu, program, config)?))
    }

    /// The host-driven multi-pass with a full configuration ([`HostMultipass::new`]).
    pub fn multipass_host(
        gpu: &Gpu,
        program: &Program,
        config: HostMultipassConfig,
    ) -> Result<Self, RunError> {
        Ok(Scheduler::MultipassHost(HostMultipass::new(
            gpu, program, config,
        )?))
    }

    /// Compiles with default settings for `kind`, queues starting at `initial_capacity` slots
    /// (items) each. Errors: [`RunError::Program`] when the generated WGSL does not compile or
    /// the program does not suit the strategy (more than 16 procedures for multi-pass).
    pub fn new(
        gpu: &Gpu,
        program: &Program,
        kind: StrategyKind,
        initial_capacity: u32,
    ) -> Result<Self, RunError> {
        match kind {
            StrategyKind::Megakernel => Self::megakernel(
                gpu,
                program,
                MegakernelConfig {
                    initial_capacity,
                    ..Default::default()
                },
            ),
            StrategyKind::Multipass => Self::multipass(
                gpu,
                program,
                MultipassConfig {
                    initial_capacity,
                    ..Default::default()
                },
            ),
            StrategyKind::MultipassHost | StrategyKind::MultipassFloor => Self::multipass_host(
                gpu,
                program,
                HostMultipassConfig {
                    initial_capacity,
                    replay_floor: kind == StrategyKind::MultipassFloor,
                    ..Default::default()
                },
            ),
        }
    }

    /// The program this scheduler runs.
    pub fn program(&self) -> &Program {
        match self {
            Scheduler::Megakernel(m) => m.program(),
            Scheduler::Multipass(m) => m.program(),
            Scheduler::MultipassHost(m) => m.program(),
        }
    }

    /// How its queues hold items: as configured, or as [`ItemLayout::for_program`] chose.
    pub fn item_layout(&self) -> ItemLayout {
        match self {
            Scheduler::Megakernel(m) => m.item_layout(),
            Scheduler::Multipass(m) => m.item_layout(),
            Scheduler::MultipassHost(m) => m.item_layout(),
        }
    }

    /// Which strategy this is.
    pub fn kind(&self) -> StrategyKind {
        match self {
            Scheduler::Megakernel(_) => StrategyKind::Megakernel,
            Scheduler::Multipass(_) => StrategyKind::Multipass,
            Scheduler::MultipassHost(m) if m.replays_floor() => StrategyKind::MultipassFloor,
            Scheduler::MultipassHost(_) => StrategyKind::MultipassHost,
        }
    }

    /// Runs the program to completion from `seeds`, with `user` as bind group 1 (`Some` exactly
    /// when the program declares user bindings; see [`crate::UserBindings::bind_group`]). Blocks
    /// until done; every wait is bounded by [`Gpu::timeout`]. Returns the run's statistics; user
    /// results are in the user's buffers. Errors: every [`RunError`] but `NoAdapter`
    /// (`docs/scheduler.md`, section 6); after an error the scheduler can run again.
    pub fn run(
        &self,
        gpu: &Gpu,
        seeds: &[Seed],
        user: Option<&wgpu::BindGroup>,
    ) -> Result<RunStats, RunError> {
        self.run_within(gpu, seeds, user, None)
    }

    /// [`Scheduler::run`] with the queue storage bounded by `max_queue_bytes` (all queues
    /// together, shared equally): work that does not fit is a [`RunError::QueueOverflow`],
    /// never dropped, so a caller can split its work (e.g. screen buckets) and run again.
    pub fn run_within(
        &self,
        gpu: &Gpu,
        seeds: &[Seed],
        user: Option<&wgpu::BindGroup>,
        max_queue_bytes: Option<u64>,
    ) -> Result<RunStats, RunError> {
        Ok(self.run_reading(gpu, seeds, user, max_queue_bytes, &[])?.0)
    }

    /// [`Scheduler::run_within`] that also reads `reads` back: `(buffer, first word, words)`
    /// ranges, returned as one vector of words per range, as the run left them (a run of no
    /// seeds: as they were). The megakernel copies them into each launch's read-back and the
    /// device-driven multi-pass into each submission's, so they cost no host round trip of
    /// their own (on the H200 about 0.09 ms, as much as a small run's GPU time; docs/results.md,
    /// 2026-12-04 (third session)), but a copy per launch or submission (usually one); the
    /// host-driven multi-pass reads them once after its last round, with the timestamps it
    /// has not read yet, in one wait of their own. The
    /// read-back buffer grows to the largest request and is kept with the scheduler. Errors: as
    /// [`Scheduler::run_within`], and [`RunError::Program`] before anything runs for a range
    /// past its buffer's end or a buffer without `COPY_SRC` ([`Gpu::storage_buffer`]'s have it).
    pub fn run_reading(
        &self,
        gpu: &Gpu,
        seeds: &[Seed],
        user: Option<&wgpu::BindGroup>,
        max_queue_bytes: Option<u64>,
        reads: &[ReadRange],
    ) -> Result<(RunStats, Vec<Vec<u32>>), RunError> {
        for (i, &(buf, first, words)) in reads.iter().enumerate() {
            let label = format!("read range {i} (words {first}..{})", first + words);
            if !buf.usage().contains(wgpu::BufferUsages::COPY_SRC) {
                return Err(RunError::Program(format!(
                    "{label}: its buffer lacks COPY_SRC usage"
                )));
            }
            if (first + words) * 4 > buf.size() {
                return Err(RunError::Program(format!(
                    "{label}: past the end of its buffer of {} words",
                    buf.size() / 4
                )));
            }
        }
        match self {
            Scheduler::Megakernel(m) => m.run(gpu, seeds, user, max_queue_bytes, reads),
            Scheduler::Multipass(m) => m.run(gpu, seeds, user, max_queue_bytes, reads),
            Scheduler::MultipassHost(m) => m.run(gpu, seeds, user, max_queue_bytes, reads),
        }
    }
}
