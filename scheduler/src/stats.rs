//! What a run reports, whatever the strategy: [`RunStats`], and for a run recorded without host
//! waits, its [`Outcome`].

/// Statistics of one run. Counters that do not apply to a strategy are zero.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunStats {
    /// The strategy's name ([`crate::StrategyKind::name`]).
    pub strategy: String,
    /// How the queues held items ([`crate::ItemLayout::name`]: `interleaved` or `planar`).
    pub item_layout: String,
    /// Megakernel: how items reached their queue, `direct` or `outbox`
    /// (`MegakernelConfig::direct_enqueue`); empty for the other strategies.
    pub enqueue: String,
    /// Device-driven multi-pass: how a round's procedures were dispatched, as configured and
    /// resolved for the adapter (`fused`, `per-procedure`, `sinks-apart` or `sinks-first`;
    /// `MultipassConfig::fused_rounds` and its companions); empty for the other strategies.
    pub round_dispatch: String,
    /// Device-driven multi-pass: most workgroups of a procedure a round
    /// (`MultipassConfig::max_workgroups` resolved for the adapter); `None` for the other
    /// strategies and where there is no cap (CPU adapters).
    pub max_workgroups: Option<u32>,
    /// Items executed, per procedure (program order).
    pub executed: Vec<u64>,
    /// Multi-pass: rounds that ran some work.
    pub rounds: u64,
    /// Megakernel: batches run.
    pub batches: u64,
    /// Megakernel: items run from a workgroup's local queue ([`crate::Procedure::local`]),
    /// counted in `executed` too.
    pub local_items: u64,
    /// Megakernel: it ran with local queues (`MegakernelConfig::local_queues`, and the program
    /// declares a local emit that fits `local_bytes`), whether or not an item ran locally.
    pub local_queues: bool,
    /// Megakernel: bytes of workgroup memory its local area took
    /// (`MegakernelConfig::local_workgroup_bytes`); 0 where the area is in the slots buffer or
    /// there is none.
    pub local_workgroup_bytes: u32,
    /// Megakernel: its claims were guided by the pending items (`MegakernelConfig::guided_claims`).
    pub guided_claims: bool,
    /// Megakernel: the co-resident workgroups its probe found, of which it launched
    /// `workgroups` (all, or a `Workgroups::ProbeShare` of them); 0 with `Workgroups::Fixed`.
    pub probed_workgroups: u32,
    /// Megakernel under the priority policy: the procedures in the order its workgroups try
    /// their queues (`QueuePolicy::Priority`, the default order completed); empty under FIFO
    /// and for the other strategies.
    pub queue_order: Vec<String>,
    /// Megakernel: loop turns that found nothing to claim.
    pub idle_polls: u64,
    /// Kernel launches. Megakernel: persistent launches (a launch ends early at its loop bound or
    /// when a queue needs room; the device compaction that may precede one is not counted).
    /// Multi-pass (both): compute dispatches recorded, the device-driven variant's `mp_plan` and
    /// empty indirect dispatches included, wgpu's own indirect-validation dispatches not.
    pub launches: u64,
    /// Host round trips: submissions the host waited on. Megakernel: one per launch plus one per
    /// host compaction (and the co-residency probe, on a scheduler's first run); device-driven
    /// multi-pass: one per chunk of rounds; host-driven multi-pass: one per round. Uploads,
    /// clears, growth's copies and timestamps ride with these, so they are all of a run's
    /// submissions but the host-driven multi-pass's one after its last round (the caller's
    /// ranges and its last timestamps) and, with `MultipassConfig::stage_timing`, the
    /// device-driven multi-pass's read of each submission's stage timestamps
    /// ([`Gpu::submissions`](crate::Gpu::submissions) counts them all).
    pub submits: u64,
    /// Megakernel: relaunches whose live items went through the host (read back and written
    /// again): after a launch that ended with work left and grew no queue (one that grew moves
    /// them on the device). Each is one of `submits`.
    pub host_compactions: u64,
    /// Megakernel: slots whose bounded wait ran out and were handed to the next launch.
    pub abandoned: u64,
    /// Megakernel: slot flags (u32 words) cleared on the device before its launches. Only those
    /// an earlier launch on the same queues may have written (below its last reserve) are
    /// cleared, not the queues' whole capacity; 0 on new queues, which wgpu zero-initializes.
    pub flags_cleared: u64,
    /// Megakernel: live items set aside on the host, and run later, because queues at their
    /// capacity limits could not hold the work's breadth (`megakernel/park.rs`); 0 when the
    /// queues had room.
    pub parked_items: u64,
    /// Queues grown because live work did not fit.
    pub queue_growths: u64,
    /// Multi-pass (both): rounds that ran only part of their inputs because a queue at its
    /// capacity limit could not hold the whole round's worst case (`multipass::partial`).
    pub partial_rounds: u64,
    /// Most items waiting at once, per queue.
    pub peak_occupancy: Vec<u64>,
    /// Bytes of queue storage allocated at the end of the run.
    pub queue_bytes: u64,
    /// Megakernel: workgroups per launch (probed or configured); 0 for the multi-passes.
    pub workgroups: u32,
    /// Megakernel: threads per workgroup (`MegakernelConfig::workgroup_size`); 0 for the
    /// multi-passes.
    pub workgroup_size: u32,
    /// GPU time from timestamp queries, when the adapter has them.
    pub gpu_ms: Option<f64>,
    /// Multi-pass with stage timing: GPU ms per procedure (program order), then the queue
    /// work (planning, scan and compaction). Empty when not measured.
    pub stage_gpu_ms: Vec<f64>,
    /// Host wall time: upload, all submissions, read-backs.
    pub wall_ms: f64,
    /// Megakernel with `MegakernelConfig::turn_anatomy`: what its loop turns spent per phase.
    pub turn_anatomy: Option<crate::megakernel::anatomy::TurnAnatomy>,
}

impl RunStats {
    /// Adds another run of the same program (e.g. the next screen bucket): counts and times
    /// add up, peaks and allocated bytes keep the maximum.
    pub fn absorb(&mut self, o: &RunStats) {
        let add = |a: &mut Vec<u64>, b: &[u64], f: fn(u64, u64) -> u64| {
            a.resize(a.len().max(b.len()), 0);
            for (x, y) in a.iter_mut().zip(b) {
                *x = f(*x, *y);
            }
        };
        add(&mut self.executed, &o.executed, |x, y| x + y);
        add(&mut self.peak_occupancy, &o.peak_occupancy, u64::max);
        let mut stage = std::mem::take(&mut self.stage_gpu_ms);
        stage.resize(stage.len().max(o.stage_gpu_ms.len()), 0.0);
        for (x, y) in stage.iter_mut().zip(&o.stage_gpu_ms) {
            *x += y;
        }
        self.stage_gpu_ms = stage;
        self.rounds += o.rounds;
        self.batches += o.batches;
        self.local_items += o.local_items;
        self.local_queues |= o.local_queues;
        self.local_workgroup_bytes = self.local_workgroup_bytes.max(o.local_workgroup_bytes);
        self.guided_claims |= o.guided_claims;
        self.probed_workgroups = self.probed_workgroups.max(o.probed_workgroups);
        self.max_workgroups = self.max_workgroups.or(o.max_workgroups);
        if self.queue_order.is_empty() {
            self.queue_order = o.queue_order.clone();
        }
        self.idle_polls += o.idle_polls;
        self.launches += o.launches;
        self.submits += o.submits;
        self.host_compactions += o.host_compactions;
        self.parked_items += o.parked_items;
        self.abandoned += o.abandoned;
        self.flags_cleared += o.flags_cleared;
        self.queue_growths += o.queue_growths;
        self.partial_rounds += o.partial_rounds;
        self.queue_bytes = self.queue_bytes.max(o.queue_bytes);
        self.workgroups = self.workgroups.max(o.workgroups);
        self.workgroup_size = self.workgroup_size.max(o.workgroup_size);
        self.gpu_ms = self.gpu_ms.zip(o.gpu_ms).map(|(a, b)| a + b);
        self.wall_ms += o.wall_ms;
        match (&mut self.turn_anatomy, &o.turn_anatomy) {
            (Some(a), Some(b)) => a.absorb(b),
            (None, Some(b)) => self.turn_anatomy = Some(b.clone()),
            _ => {}
        }
    }
}

/// What a recorded run's status copy says ([`crate::RecordedRun::outcome`]).
#[derive(Debug, Clone, PartialEq)]
#[allow(
    clippy::large_enum_variant,
    reason = "one per record, read once; callers match `Done(stats)` without a box"
)]
pub enum Outcome {
    /// The run finished: every item was executed. `launches` and `rounds` are those recorded;
    /// `submits` is 0 (the run cost no host round trip of its own), `gpu_ms` and `wall_ms` are
    /// the caller's to measure.
    Done(RunStats),
    /// The run stopped with work left, why in words (a queue name and its capacity, or the
    /// bound that ended it); the user results are partial: run the work again with
    /// [`crate::Scheduler::run`].
    Incomplete(String),
}

/// Median and median absolute deviation (the spread measure robust to the odd slow run) of
/// repeated timings; the median of an even count is the mean of the middle two.
pub fn median_and_mad(v: &[f64]) -> (f64, f64) {
    fn median(mut v: Vec<f64>) -> f64 {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            (v[n / 2 - 1] + v[n / 2]) / 2.0
        }
    }
    let m = median(v.to_vec());
    (m, median(v.iter().map(|x| (x - m).abs()).collect()))
}

impl RunStats {
    /// Items executed, all procedures together.
    pub fn items(&self) -> u64 {
        self.executed.iter().sum()
    }
}
