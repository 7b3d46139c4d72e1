//! The suite's view of a workload: problem sizes, the strategies it runs under, and one
//! verified, timed run at a time. [`ScheduledProblem`] adapts any workload in the shape of
//! `workloads::tree` (parameters with a CPU reference and a rayon twin, a GPU run of
//! one program) in a few lines; Reyes implements [`Workload`] itself (`crate::reyes`).

use crate::error::Error;
use crate::strategy::{GpuConfig, Strategy, compile};
use scheduler::{Gpu, MegakernelConfig, Program, RunError, RunStats, Scheduler};
use std::cell::RefCell;
use std::fmt::Debug;
use std::rc::Rc;
use std::time::Instant;

/// Characters of each result quoted in a mismatch message.
const MISMATCH_CHARS: usize = 300;

/// One timed run, checked against the workload's CPU reference.
#[derive(Debug, Clone, Default)]
pub struct Measurement {
    /// Items of work this run executed (the scheduler's count; the reference's for CPU runs).
    pub items: u64,
    pub verified: bool,
    /// What differed, when not verified.
    pub mismatch: Option<String>,
    /// GPU time from timestamp queries (none for CPU runs or adapters without timestamps).
    pub gpu_ms: Option<f64>,
    /// Host time of the whole run: uploads, submissions, waits and the result's read-back
    /// (for CPU runs, the computation).
    pub wall_ms: f64,
    /// Scheduler statistics, for scheduler runs.
    pub stats: Option<RunStats>,
    /// Edges traversed (graph workloads): GTEPS = edges / time.
    pub edges: Option<u64>,
}

/// A problem size a workload was prepared for.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The size's label in records and tables (e.g. `roots=4`, `320x240`).
    pub size: String,
    /// The workload's parameters in its own words.
    pub params: String,
    /// Items of work of the CPU reference at this size: the x axis of the plots.
    pub problem_items: u64,
}

/// A workload of the suite. The suite calls [`Workload::prepare`] for each size, then
/// [`Workload::run`] for each strategy, several times each.
pub trait Workload {
    /// Name in records, tables and file names: `tree-binary`, `reyes-teapot`, ...
    fn name(&self) -> String;
    /// The strategies it runs under, scheduler strategies first.
    fn strategies(&self) -> Vec<Strategy>;
    /// Labels of its problem sizes, smallest first.
    fn sizes(&self) -> Vec<String>;
    /// Prepares size `i` (index into [`Workload::sizes`]): builds its input and computes its CPU
    /// reference, untimed.
    fn prepare(&mut self, gpu: &Gpu, i: usize) -> Result<Prepared, Error>;
    /// One run of the prepared size under `strategy` (compiled on first use), verified.
    fn run(&mut self, gpu: &Gpu, strategy: &Strategy) -> Result<Measurement, Error>;
}

/// A workload in the shape of `workloads::tree`, adapted by [`ProblemWorkload`]:
/// `Self` is one problem size (the workload's parameters).
pub trait ScheduledProblem: Clone {
    /// What a run computes; GPU and CPU results must be equal.
    type Output: PartialEq + Debug;
    /// The GPU resources of one problem (its program, buffers and bind group).
    type Run;
    /// The problem as `gpu` runs it, called before anything else of a size: e.g. Mandelbrot's
    /// `fma` arithmetic, which decides its CPU reference, or a check that the input fits the
    /// device's bindings. Errors fail the size (recorded, the suite goes on). Default: unchanged.
    fn for_device(&self, _gpu: &Gpu) -> Result<Self, RunError> {
        Ok(self.clone())
    }
    /// The parameters in words (records' `params`).
    fn describe(&self) -> String;
    /// The CPU reference (may be single-threaded: it is not timed).
    fn reference(&self) -> Self::Output;
    /// The multi-threaded CPU implementation (rayon), timed as strategy `cpu`.
    fn cpu(&self) -> Self::Output;
    /// Items of work in a result (the x axis of plots; items/s).
    fn items(out: &Self::Output) -> u64;
    fn new_run(&self, gpu: &Gpu) -> Result<Self::Run, RunError>;
    fn program(run: &Self::Run) -> &Program;
    /// Runs once and reads the result back.
    fn run(
        run: &Self::Run,
        gpu: &Gpu,
        scheduler: &Scheduler,
    ) -> Result<(RunStats, Self::Output), RunError>;
    /// The workload's megakernel batch steps per procedure on `gpu`
    /// (`GpuConfig::procedure_steps` when the command line gives none); default none.
    fn procedure_steps(_gpu: &Gpu) -> Vec<(String, u32)> {
        Vec::new()
    }
    /// Whether the workload's megakernel claims are guided by what is pending on `gpu`
    /// (`GpuConfig::guided_claims` when the command line says neither way); default false.
    fn guided_claims(_gpu: &Gpu) -> bool {
        false
    }
    /// Whether the megakernel keeps this problem's declared-local emits in the workgroup
    /// (`GpuConfig::local_queues` when the command line says neither way); default false.
    fn local_queues(&self) -> bool {
        false
    }
    /// Bytes of workgroup memory for the megakernel's local area on `gpu` at `workgroup_size`
    /// threads a workgroup (`GpuConfig::local_workgroup_bytes` when the command line gives
    /// none); default 0, the slots buffer.
    fn local_workgroup_bytes(&self, _gpu: &Gpu, _workgroup_size: u32) -> u32 {
        0
    }
    /// The share (numerator, denominator) of the probed megakernel workgroups this problem
    /// launches on `gpu` with `local_workgroup_bytes` of local area in workgroup memory
    /// (`GpuConfig::workgroup_share` when the command line gives neither a share nor a count);
    /// default all, (1, 1).
    fn workgroup_share(&self, _gpu: &Gpu, _local_workgroup_bytes: u32) -> (u32, u32) {
        (1, 1)
    }

    /// Points `run` at this problem when its compiled program serves it unchanged (so the
    /// schedulers compiled for it are kept); false (the default) builds a new run.
    fn retarget(&self, _run: &mut Self::Run) -> bool {
        false
    }
    /// Queue slots at the start of a run: enough for the whole problem up to 4M slots, so
    /// that timed runs rarely grow their queues.
    fn capacity(&self, reference: &Self::Output) -> u32 {
        Self::items(reference)
            .next_power_of_two()
            .clamp(1 << 12, 1 << 22) as u32
    }
    /// Edges traversed, for graph workloads (GTEPS).
    fn edges(&self, _out: &Self::Output) -> Option<u64> {
        None
    }
    /// Names of the workload's own baselines (e.g. BFS's hand-written frontier).
    fn baselines() -> &'static [&'static str] {
        &[]
    }
    /// Runs baseline `name` once: its statistics when it has them (their `gpu_ms` is used)
    /// and its result.
    fn baseline(
        &self,
        name: &str,
        _run: &Self::Run,
        _gpu: &Gpu,
    ) -> Result<(Option<RunStats>, Self::Output), RunError> {
        Err(RunError::Program(format!("no baseline `{name}`")))
    }
}

/// The GPU run of the program last prepared and the schedulers compiled for it, by strategy
/// name, initial queue capacity, local queues and workgroup share. Workloads whose problems share a program
/// (tree presets of one payload size and fan-out) can share one, so the suite compiles (and the
/// megakernel probes its workgroup count) once for all of them.
pub struct RunSlot<P: ScheduledProblem> {
    run: Option<P::Run>,
    schedulers: Vec<Compiled>,
}

/// A scheduler compiled for a strategy (`name`), an initial queue capacity, local queues on or
/// off, the local area's bytes of workgroup memory and a share of the probed workgroups.
struct Compiled {
    name: String,
    capacity: u32,
    local: bool,
    area: u32,
    share: (u32, u32),
    scheduler: Scheduler,
}

/// A [`Workload`] over sizes of a [`ScheduledProblem`]: keeps the GPU run and the schedulers
/// compiled for its program while sizes (and workloads sharing its [`RunSlot`]) can use them.
pub struct ProblemWorkload<P: ScheduledProblem> {
    name: String,
    sizes: Vec<(String, P)>,
    config: GpuConfig,
    current: Option<(P, P::Output)>,
    slot: Rc<RefCell<RunSlot<P>>>,
}

impl<P: ScheduledProblem> ProblemWorkload<P> {
    /// `sizes`: labels and problems, smallest first.
    pub fn new(name: impl Into<String>, sizes: Vec<(String, P)>, config: GpuConfig) -> Self {
        ProblemWorkload {
            name: name.into(),
            sizes,
            config,
            current: None,
            slot: Rc::new(RefCell::new(RunSlot {
                run: None,
                schedulers: Vec::new(),
            })),
        }
    }

    /// Shares `other`'s run and compiled schedulers (used while the program stays the same).
    pub fn sharing(mut self, other: &ProblemWorkload<P>) -> Self {
        self.slot = other.slot.clone();
        self
    }

    fn check(&self, out: &P::Output) -> (bool, Option<String>) {
        let reference = &self.current.as_ref().expect("prepared").1;
        if out == reference {
            return (true, None);
        }
        // Outputs may be large (a BFS's levels): keep the record's line short.
        let short = |v: &P::Output| {
            let s = format!("{v:?}");
            match s.char_indices().nth(MISMATCH_CHARS) {
                Some((at, _)) => format!("{}...", &s[..at]),
                None => s,
            }
        };
        (
            false,
            Some(format!(
                "got {}, the reference is {}",
                short(out),
                short(reference)
            )),
        )
    }
}

impl<P: ScheduledProblem> Workload for ProblemWorkload<P> {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn strategies(&self) -> Vec<Strategy> {
        Strategy::all_for(P::baselines())
    }

    fn sizes(&self) -> Vec<String> {
        self.sizes.iter().map(|s| s.0.clone()).collect()
    }

    fn prepare(&mut self, gpu: &Gpu, i: usize) -> Result<Prepared, Error> {
        let (label, p) = self.sizes[i].clone();
        let p = p.for_device(gpu)?;
        let reference = p.reference();
        let mut slot = self.slot.borrow_mut();
        let reused = slot.run.as_mut().is_some_and(|r| p.retarget(r));
        if !reused {
            // The old buffers go before the new ones are made.
            slot.run = None;
            slot.schedulers.clear();
            slot.run = Some(p.new_run(gpu)?);
        }
        let prepared = Prepared {
            size: label,
            params: p.describe(),
            problem_items: P::items(&reference),
        };
        self.current = Some((p, reference));
        Ok(prepared)
    }

    fn run(&mut self, gpu: &Gpu, strategy: &Strategy) -> Result<Measurement, Error> {
        let (p, reference) = self.current.as_ref().expect("prepare before run");
        let mut slot = self.slot.borrow_mut();
        let RunSlot { run, schedulers } = &mut *slot;
        let run = run.as_ref().expect("prepared");
        let (stats, out, gpu_ms, wall_ms) = match strategy {
            Strategy::Cpu => {
                let start = Instant::now();
                let out = p.cpu();
                (None, out, None, ms_since(start))
            }
            Strategy::Baseline(name) => {
                let start = Instant::now();
                let (stats, out) = p.baseline(name, run, gpu)?;
                let gpu_ms = stats.as_ref().and_then(|s| s.gpu_ms);
                (stats, out, gpu_ms, ms_since(start))
            }
            Strategy::Scheduler { .. } => {
                // Compiled per initial capacity: a scheduler sized for a smaller problem would
                // grow its queues in every timed run.
                let name = strategy.name();
                let capacity = self.config.capacity.unwrap_or(p.capacity(reference));
                let local = self.config.local_queues.unwrap_or(p.local_queues());
                let threads = (self.config.workgroup_size)
                    .unwrap_or(MegakernelConfig::default().workgroup_size);
                // The area in effect: none without local queues, whatever was asked for (the
                // megakernel then warns that the option does nothing).
                let area = match local {
                    true => (self.config.local_workgroup_bytes)
                        .unwrap_or_else(|| p.local_workgroup_bytes(gpu, threads)),
                    false => 0,
                };
                let share = self
                    .config
                    .workgroup_share
                    .unwrap_or(p.workgroup_share(gpu, area));
                let have = |s: &&Compiled| {
                    s.name == name
                        && s.capacity == capacity
                        && s.local == local
                        && s.area == area
                        && s.share == share
                };
                if !schedulers.iter().any(|s| have(&s)) {
                    let config = (self.config.clone())
                        .or_procedure_steps(P::procedure_steps(gpu))
                        .or_guided_claims(P::guided_claims(gpu))
                        .or_local_queues(local)
                        .or_local_workgroup_bytes(area)
                        .or_workgroup_share(share);
                    let s = compile(gpu, P::program(run), strategy, &config, capacity)?;
                    schedulers.push(Compiled {
                        name: name.clone(),
                        capacity,
                        local,
                        area,
                        share,
                        scheduler: s,
                    });
                }
                let scheduler = &schedulers.iter().find(have).unwrap().scheduler;
                let start = Instant::now();
                let (stats, out) = P::run(run, gpu, scheduler)?;
                let wall = ms_since(start);
                (Some(stats.clone()), out, stats.gpu_ms, wall)
            }
        };
        drop(slot);
        let (verified, mismatch) = self.check(&out);
        Ok(Measurement {
            items: stats.as_ref().map_or(P::items(&out), |s| s.items()),
            verified,
            mismatch,
            gpu_ms,
            wall_ms,
            edges: p.edges(&out),
            stats,
        })
    }
}

pub fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
