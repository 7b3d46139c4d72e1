//! Breadth-first search (`workloads::bfs`) as a suite workload: Graph500 R-MAT graphs
//! by scale, the scheduler's strategies against the hand-written level-synchronous frontier
//! BFS (`workloads::frontier_bfs`), every run's levels equal to the CPU BFS's. Runs
//! record the Graph500 traversed edges, so the report gives GTEPS.

use crate::error::Error;
use crate::scale::Scale;
use crate::strategy::GpuConfig;
use crate::workload::{ProblemWorkload, ScheduledProblem};
use scheduler::{Gpu, Program, RunError, RunStats, Scheduler};
use std::cell::OnceCell;
use workloads::bfs::{BfsParams, BfsRun, UNREACHED, bfs_levels_rayon};
use workloads::frontier_bfs::FrontierBfs;

/// The seed of every suite graph (the source is drawn from it too).
pub const SEED: u64 = 1;

/// The baseline's name in records and `--strategy`.
pub const FRONTIER: &str = "frontier";

/// One graph's GPU resources: the scheduler program's run and, once the baseline first runs,
/// the frontier BFS (its own copy of the graph).
pub struct BfsRuns {
    pub run: BfsRun,
    frontier: OnceCell<FrontierBfs>,
}

impl ScheduledProblem for BfsParams {
    /// The level of every vertex (`UNREACHED` where the source does not reach).
    type Output = Vec<u32>;
    type Run = BfsRuns;

    /// Refuses a graph whose adjacency exceeds the device's storage binding limit.
    fn for_device(&self, gpu: &Gpu) -> Result<BfsParams, RunError> {
        self.fits(gpu.max_binding_bytes())?;
        Ok(self.clone())
    }

    fn procedure_steps(gpu: &Gpu) -> Vec<(String, u32)> {
        workloads::bfs::megakernel_procedure_steps(gpu)
    }

    fn guided_claims(gpu: &Gpu) -> bool {
        workloads::bfs::megakernel_guided_claims(gpu)
    }

    fn describe(&self) -> String {
        BfsParams::describe(self)
    }

    fn reference(&self) -> Vec<u32> {
        BfsParams::reference(self)
    }

    fn cpu(&self) -> Vec<u32> {
        bfs_levels_rayon(self.graph(), self.source)
    }

    /// Vertices reached, the source included.
    fn items(levels: &Vec<u32>) -> u64 {
        levels.iter().filter(|&&l| l != UNREACHED).count() as u64
    }

    fn new_run(&self, gpu: &Gpu) -> Result<BfsRuns, RunError> {
        Ok(BfsRuns {
            run: BfsRun::new(gpu, self.clone())?,
            frontier: OnceCell::new(),
        })
    }

    fn program(run: &BfsRuns) -> &Program {
        &run.run.program
    }

    fn run(
        run: &BfsRuns,
        gpu: &Gpu,
        scheduler: &Scheduler,
    ) -> Result<(RunStats, Vec<u32>), RunError> {
        run.run.run(gpu, scheduler)
    }

    fn edges(&self, levels: &Vec<u32>) -> Option<u64> {
        Some(self.traversed_edges(levels))
    }

    fn baselines() -> &'static [&'static str] {
        &[FRONTIER]
    }

    /// The frontier BFS, built on first use. Its statistics in the scheduler's terms: executed
    /// = vertices reached, rounds = levels expanded, submits and times as measured; launches
    /// are not counted by the baseline and stay 0.
    fn baseline(
        &self,
        name: &str,
        run: &BfsRuns,
        gpu: &Gpu,
    ) -> Result<(Option<RunStats>, Vec<u32>), RunError> {
        if name != FRONTIER {
            return Err(RunError::Program(format!("no baseline `{name}`")));
        }
        if run.frontier.get().is_none() {
            let f = FrontierBfs::new(gpu, run.run.params.clone())?;
            let _ = run.frontier.set(f);
        }
        let (f, levels) = run.frontier.get().expect("built above").run(gpu)?;
        let stats = RunStats {
            strategy: FRONTIER.into(),
            executed: vec![f.reached],
            rounds: f.levels as u64,
            submits: f.submits as u64,
            gpu_ms: f.gpu_ms,
            wall_ms: f.wall_ms,
            ..RunStats::default()
        };
        Ok((Some(stats), levels))
    }
}

/// The suite's R-MAT scales, smallest first. At `Full`, multi-pass still fits its queues
/// (chunk 16 holds a level up to scale 23; beyond, it reports a queue overflow, which the
/// suite records as a failed run).
pub fn scales(scale: Scale) -> Vec<u32> {
    match scale {
        Scale::Small => vec![8, 10],
        Scale::Full => vec![16, 20, 22],
    }
}

/// The suite workload `bfs`, sized `scale=S`. Generates every graph (untimed): at `Full` the
/// largest, scale 22, is about 134M directed edges (0.5 GiB of adjacency) in host memory.
pub fn suite_workload(
    scale: Scale,
    config: GpuConfig,
) -> Result<ProblemWorkload<BfsParams>, Error> {
    let sizes = scales(scale)
        .into_iter()
        .map(|s| graph(s).map(|p| (format!("scale={s}"), p)))
        .collect::<Result<_, _>>()?;
    Ok(ProblemWorkload::new("bfs", sizes, config))
}

/// One graph of the command line's scale: `bfs`, one size.
pub fn single_workload(scale: u32, config: GpuConfig) -> Result<ProblemWorkload<BfsParams>, Error> {
    Ok(ProblemWorkload::new(
        "bfs",
        vec![(format!("scale={scale}"), graph(scale)?)],
        config,
    ))
}

fn graph(scale: u32) -> Result<BfsParams, Error> {
    BfsParams::graph500(scale, SEED).map_err(|source| Error::Graph { scale, source })
}
