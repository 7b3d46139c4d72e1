//! One front door for both strategies, so workloads and benchmarks can name one and run it.

use crate::error::RunError;
use crate::gpu::Gpu;
use crate::megakernel::{Megakernel, MegakernelConfig};
use crate::multipass::{Multipass, MultipassConfig};
use crate::program::{Program, Seed};
use crate::stats::RunStats;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StrategyKind {
    Megakernel,
    Multipass,
}

impl StrategyKind {
    pub const ALL: [StrategyKind; 2] = [StrategyKind::Megakernel, StrategyKind::Multipass];

    pub fn name(self) -> &'static str {
        match self {
            StrategyKind::Megakernel => "megakernel",
            StrategyKind::Multipass => "multipass",
        }
    }

    pub fn parse(s: &str) -> Option<StrategyKind> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// A program compiled for one strategy, ready to run many times.
pub enum Scheduler {
    Megakernel(Megakernel),
    Multipass(Multipass),
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
        }
    }
}
