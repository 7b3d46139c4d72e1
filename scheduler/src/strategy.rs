//! One front door for every strategy, so workloads and benchmarks can name one and run it.

use crate::error::RunError;
use crate::gpu::Gpu;
use crate::megakernel::{Megakernel, MegakernelConfig};
use crate::multipass::host::{HostMultipass, HostMultipassConfig};
use crate::multipass::{Multipass, MultipassConfig};
use crate::program::{Program, Seed};
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
}

impl StrategyKind {
    /// Every strategy, in the order reports list them.
    pub const ALL: [StrategyKind; 3] = [
        StrategyKind::Megakernel,
        StrategyKind::Multipass,
        StrategyKind::MultipassHost,
    ];

    pub fn name(self) -> &'static str {
        match self {
            StrategyKind::Megakernel => "megakernel",
            StrategyKind::Multipass => "multipass",
            StrategyKind::MultipassHost => "multipass-host",
        }
    }

    /// The strategy named `s` (as [`StrategyKind::name`] spells it), if any.
    pub fn parse(s: &str) -> Option<StrategyKind> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// A program compiled for one strategy, ready to run many times.
pub enum Scheduler {
    Megakernel(Megakernel),
    Multipass(Multipass),
    MultipassHost(HostMultipass),
}

impl Scheduler {
    pub fn megakernel(
        gpu: &Gpu,
        program: &Program,
        config: MegakernelConfig,
    ) -> Result<Self, RunError> {
        Ok(Scheduler::Megakernel(Megakernel::new(
            gpu, program, config,
        )?))
    }

    pub fn multipass(
        gpu: &Gpu,
        program: &Program,
        config: MultipassConfig,
    ) -> Result<Self, RunError> {
        Ok(Scheduler::Multipass(Multipass::new(gpu, program, config)?))
    }

    pub fn multipass_host(
        gpu: &Gpu,
        program: &Program,
        config: HostMultipassConfig,
    ) -> Result<Self, RunError> {
        Ok(Scheduler::MultipassHost(HostMultipass::new(
            gpu, program, config,
        )?))
    }

    /// Compiles with default settings for `kind`, queues starting at `initial_capacity` slots.
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
            StrategyKind::MultipassHost => Self::multipass_host(
                gpu,
                program,
                HostMultipassConfig {
                    initial_capacity,
                    ..Default::default()
                },
            ),
        }
    }

    /// Which strategy this is.
    pub fn kind(&self) -> StrategyKind {
        match self {
            Scheduler::Megakernel(_) => StrategyKind::Megakernel,
            Scheduler::Multipass(_) => StrategyKind::Multipass,
            Scheduler::MultipassHost(_) => StrategyKind::MultipassHost,
        }
    }

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
        match self {
            Scheduler::Megakernel(m) => m.run(gpu, seeds, user, max_queue_bytes),
            Scheduler::Multipass(m) => m.run(gpu, seeds, user, max_queue_bytes),
            Scheduler::MultipassHost(m) => m.run(gpu, seeds, user, max_queue_bytes),
        }
    }
}
