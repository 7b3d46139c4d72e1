//! Runs recorded into the caller's command encoder, with no host wait: for frames pipelined on
//! the GPU (the next one recorded and submitted while the GPU runs this one).
//!
//! [`Scheduler::run`] grows its queues and relaunches as the work demands, reading counters back
//! between launches; that costs a host round trip per launch or chunk of rounds. A
//! [`RecordedRun`] instead fixes its queue capacities (and, for multi-pass, its round count) in
//! advance, from a [`Scheduler::run`] of similar work ([`RecordedRun::new`]); its buffers are
//! allocated once and reused by every [`RecordedRun::record`]. Seeds come from device buffers
//! (copied into the queues on the device), and the run's whole control block is copied into a
//! buffer of the caller's (a mapped staging ring, read a frame late). [`RecordedRun::outcome`]
//! reads that copy: [`Outcome::Done`] when the run finished within its fixed sizes, or
//! [`Outcome::Incomplete`] when it did not (a queue out of room, the megakernel's launch at its
//! loop bound, multi-pass out of rounds); then the user results of that run are partial and the
//! caller must run the work again with [`Scheduler::run`] (which grows as needed) and may build
//! a larger `RecordedRun` from its statistics ([`RecordedRun::new`] again). Nothing is ever
//! dropped silently: an incomplete run says so.
//!
//! Strategies: the megakernel (one launch) and the device-driven multi-pass (a fixed number of
//! rounds, one pass); the host-driven multi-pass plans each round on the host and cannot be
//! recorded ([`RunError::Program`]).

use crate::error::RunError;
use crate::gpu::Gpu;
use crate::megakernel::record::RecordedLaunch;
use crate::multipass::record::RecordedRounds;
use crate::program::Program;
use crate::stats::{Outcome, RunStats};
use crate::strategy::{Scheduler, StrategyKind};

/// Seeds of one procedure already on the device: `count` items back to back from byte 0 of
/// `buffer` (which needs `COPY_SRC` usage), in the procedure's item layout.
pub struct DeviceSeeds<'a> {
    /// The procedure the items are for.
    pub procedure: &'a str,
    /// Holds the items (at least `count` of them).
    pub buffer: &'a wgpu::Buffer,
    /// Items to seed; the same for every record of one [`RecordedRun`].
    pub count: u32,
}

/// Fixed sizes of a [`RecordedRun`]: queue slots per procedure (program order) and, for the
/// device-driven multi-pass, rounds per record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedSize {
    /// Slots per queue. Megakernel: every item enqueued to that queue in the run (a launch
    /// never reuses a slot), seeds included; [`RecordedRun::new`] adds room for the worst-case
    /// output of one batch per workgroup (a batch runs only when that fits). Multi-pass: the
    /// most items one round's inputs may emit to the queue (a round runs only when that fits).
    pub capacity: Vec<u32>,
    /// Multi-pass rounds encoded per record (0 for the megakernel).
    pub rounds: u32,
}

impl RecordedSize {
    /// Sizes for work like that of `stats` (a [`Scheduler::run`] of `program` with strategy
    /// `kind`): what it needed times `headroom` (at least 1; e.g. 1.5 for frames of a moving
    /// camera), each queue at least its `seeds` and one slot. Megakernel: the items executed per
    /// queue. Multi-pass: a round is refused unless every target has room for the most its
    /// inputs may emit (the declared `emits` per item), so each queue gets the sum over sources
    /// of their peak inputs times their declared emits to it; rounds are the run's plus 2 (no
    /// factor: an empty round is not free).
    /// [`RecordedRun::new`] lowers capacities to the device's and the budget's limits.
    pub fn from_stats(
        program: &Program,
        kind: StrategyKind,
        stats: &RunStats,
        seeds: &[u32],
        headroom: f64,
    ) -> RecordedSize {
        let h = headroom.max(1.0);
        let nq = program.queue_count();
        let at = |v: &Vec<u64>, q: usize| v.get(q).copied().unwrap_or(0) as f64;
        let capacity = (0..nq)
            .map(|t| {
                let need = match kind {
                    StrategyKind::Megakernel => at(&stats.executed, t),
                    _ => (0..nq)
                        .map(|p| at(&stats.peak_occupancy, p) * program.procs[p].emits[t] as f64)
                        .sum::<f64>()
                        .max(at(&stats.peak_occupancy, t)),
                };
                let seeded = seeds.get(t).copied().unwrap_or(0);
                ((need * h).ceil().min(u32::MAX as f64) as u32)
                    .max(seeded)
                    .max(1)
            })
            .collect();
        // Rounds follow the split depth, which varies little between similar runs, and each
        // empty round still costs a plan and its empty indirect dispatches: no headroom factor.
        let rounds = match kind {
            StrategyKind::Megakernel => 0,
            _ => (stats.rounds.min(u32::MAX as u64 - 2) as u32) + 2,
        };
        RecordedSize { capacity, rounds }
    }

    /// The larger of two sizes, queue by queue.
    pub fn max(&self, o: &RecordedSize) -> RecordedSize {
        RecordedSize {
            capacity: (self.capacity.iter().zip(&o.capacity))
                .map(|(a, b)| *a.max(b))
                .collect(),
            rounds: self.rounds.max(o.rounds),
        }
    }
}

/// A run of fixed sizes, recorded into the caller's encoder as often as wanted; see the module
/// documentation. Made by [`RecordedRun::new`] for one [`Scheduler`], which every call must be
/// given.
pub struct RecordedRun {
    pub(crate) inner: Inner,
    /// The sizes after the device's and the budget's limits.
    pub size: RecordedSize,
    /// Seed items per queue of every record.
    pub(crate) seeded: Vec<u32>,
}

/// The strategy's part of a recorded run.
pub(crate) enum Inner {
    Megakernel(RecordedLaunch),
    Multipass(RecordedRounds),
}

impl RecordedRun {
    /// Allocates a run of `size` for `scheduler` with `seeds` items per procedure `(name,
    /// count)` (absent procedures get none) and queue storage within `max_queue_bytes` (as
    /// [`Scheduler::run_within`]; capacities above it are lowered, so that such a run reports
    /// [`Outcome::Incomplete`] instead). `user` is the bind group the runs will use (the
    /// megakernel's first use probes its workgroup count with it). Errors:
    /// [`RunError::Program`] for the host-driven multi-pass, an unknown procedure, or `size` of
    /// the wrong length; [`RunError::QueueOverflow`] when the seeds alone exceed a queue's
    /// limit; the errors of the megakernel's co-residency probe.
    pub fn new(
        gpu: &Gpu,
        scheduler: &Scheduler,
        seeds: &[(&str, u32)],
        size: &RecordedSize,
        user: Option<&wgpu::BindGroup>,
        max_queue_bytes: Option<u64>,
    ) -> Result<RecordedRun, RunError> {
        let program = scheduler.program();
        let nq = program.queue_count();
        if size.capacity.len() != nq {
            return Err(RunError::Program(format!(
                "recorded run: {} capacities for {nq} procedures",
                size.capacity.len()
            )));
        }
        let mut seeded = vec![0u32; nq];
        for (name, n) in seeds {
            let q = program
                .index_of(name)
                .ok_or_else(|| RunError::Program(format!("seed for unknown procedure `{name}`")))?;
            seeded[q] += n;
        }
        let (inner, size) = match scheduler {
            Scheduler::Megakernel(m) => {
                let (r, capacity) =
                    m.recorded_launch(gpu, &seeded, &size.capacity, user, max_queue_bytes)?;
                let size = RecordedSize {
                    capacity,
                    rounds: 0,
                };
                (Inner::Megakernel(r), size)
            }
            Scheduler::Multipass(m) => {
                let (r, capacity) =
                    m.recorded_rounds(gpu, &seeded, &size.capacity, size.rounds, max_queue_bytes)?;
                let size = RecordedSize {
                    capacity,
                    rounds: r.rounds(),
                };
                (Inner::Multipass(r), size)
            }
            Scheduler::MultipassHost(_) => {
                return Err(RunError::Program(
                    "the host-driven multi-pass plans every round on the host: it cannot be \
                     recorded without host waits"
                        .into(),
                ));
            }
        };
        Ok(RecordedRun {
            inner,
            size,
            seeded,
        })
    }

    /// Words of the status [`RecordedRun::record`] copies (the run's control block).
    pub fn status_words(&self) -> u64 {
        match &self.inner {
            Inner::Megakernel(r) => r.status_words(),
            Inner::Multipass(r) => r.status_words(),
        }
    }

    /// Records one run into `enc`: the seeds copied into the queues, the queues' control block
    /// reset, the launch (megakernel) or rounds (multi-pass) as one compute pass, then the
    /// control block copied to `status` (which needs `COPY_DST`) at word `status_word`
    /// ([`RecordedRun::status_words`] words). `seeds` must give every procedure the counts
    /// given to [`RecordedRun::new`]; `user` is bind group 1. Errors: [`RunError::Program`]
    /// for seeds other than those, or a user group where the program declares none (or the
    /// reverse). Nothing waits; the caller submits.
    pub fn record(
        &self,
        scheduler: &Scheduler,
        enc: &mut wgpu::CommandEncoder,
        seeds: &[DeviceSeeds],
        user: Option<&wgpu::BindGroup>,
        status: &wgpu::Buffer,
        status_word: u64,
    ) -> Result<(), RunError> {
        let program = scheduler.program();
        let mut counts = vec![0u32; program.queue_count()];
        let mut by_queue = Vec::new();
        for s in seeds {
            let q = program.index_of(s.procedure).ok_or_else(|| {
                RunError::Program(format!("seed for unknown procedure `{}`", s.procedure))
            })?;
            counts[q] += s.count;
            if s.count > 0 {
                by_queue.push((q, s.buffer, s.count));
            }
        }
        if counts != self.seeded || by_queue.len() > counts.iter().filter(|&&n| n > 0).count() {
            return Err(RunError::Program(format!(
                "recorded run seeded with {counts:?} items per queue (one buffer each), made \
                 for {:?}",
                self.seeded
            )));
        }
        match (&self.inner, scheduler) {
            (Inner::Megakernel(r), Scheduler::Megakernel(m)) => {
                r.record(m, enc, &by_queue, user, status, status_word)
            }
            (Inner::Multipass(r), Scheduler::Multipass(m)) => {
                r.record(m, enc, &by_queue, user, status, status_word)
            }
            _ => Err(RunError::Program(
                "recorded run used with another scheduler than its own".into(),
            )),
        }
    }

    /// What the status copy of one record says ([`Outcome`]). Errors:
    /// [`RunError::EmitLimit`] when a procedure emitted more than it declared (a bug of the
    /// program, as in [`Scheduler::run`]); [`RunError::Program`] for a status of the wrong
    /// length.
    pub fn outcome(&self, program: &Program, status: &[u32]) -> Result<Outcome, RunError> {
        if status.len() as u64 != self.status_words() {
            return Err(RunError::Program(format!(
                "recorded run: a status of {} words, not {}",
                status.len(),
                self.status_words()
            )));
        }
        match &self.inner {
            Inner::Megakernel(r) => r.outcome(program, &self.size.capacity, status),
            Inner::Multipass(r) => r.outcome(program, &self.size.capacity, status),
        }
    }
}
