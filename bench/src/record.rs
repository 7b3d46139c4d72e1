//! One run as a JSON object: a line of `schedbench --json` and of the suite's `runs.jsonl`.

use crate::strategy::Strategy;
use crate::workload::{Measurement, Prepared};
use scheduler::Gpu;
use serde::{Deserialize, Serialize};

/// A run, verified or not. Times in milliseconds; scheduler counters are zero where they do not
/// apply (see `scheduler::RunStats`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// `tree-binary`, `reyes-teapot`, ... (`tree` for a tree given on the command line).
    pub workload: String,
    /// `megakernel`, `megakernel-fifo`, `multipass`, ..., `cpu`, or a workload's baseline.
    pub strategy: String,
    /// The megakernel's queue policy.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub policy: Option<String>,
    /// The problem size's label (`roots=4`, `320x240`).
    pub size: String,
    /// The workload's parameters in its own words.
    pub params: String,
    /// How the queues held items (`interleaved`, `planar`); absent for CPU runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub item_layout: Option<String>,
    /// The megakernel's enqueue (`direct`, `outbox`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub enqueue: Option<String>,
    /// The megakernel's threads per workgroup (`--workgroup-size`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub workgroup_size: Option<u32>,
    pub adapter: String,
    /// Index of the timed run (0-based; the untimed warm-up run is not recorded).
    pub run: u32,
    /// Items this run executed.
    pub items: u64,
    /// Items of the CPU reference at this size (the plots' x axis).
    pub problem_items: u64,
    /// The result equals the CPU reference (within the workload's stated tolerance).
    pub verified: bool,
    /// What differed, or the error that stopped the run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// GPU time from timestamp queries; null for CPU runs and adapters without timestamps.
    pub gpu_ms: Option<f64>,
    /// Host time of the whole run, result read-back included; null when the run failed.
    pub wall_ms: Option<f64>,
    /// Items per second of GPU time (null without it).
    pub items_per_s: Option<f64>,
    /// Items per second of wall time.
    pub items_per_s_wall: Option<f64>,
    /// Graph workloads: giga traversed edges per second (GPU time where measured, else wall).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gteps: Option<f64>,
    pub executed: Vec<u64>,
    pub rounds: u64,
    pub launches: u64,
    pub batches: u64,
    /// Megakernel: items run from workgroups' local queues (`RunStats::local_items`).
    #[serde(default)]
    pub local_items: u64,
    /// Megakernel: it ran with local queues (`RunStats::local_queues`); absent for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub local_queues: Option<bool>,
    /// Megakernel: bytes of workgroup memory its local area took
    /// (`RunStats::local_workgroup_bytes`); absent where it is in the slots buffer or none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub local_workgroup_bytes: Option<u32>,
    /// Megakernel: its claims were guided (`RunStats::guided_claims`); absent for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guided_claims: Option<bool>,
    /// Megakernel under the priority policy: the order its workgroups try the queues
    /// (`RunStats::queue_order`, `schedbench --priority`); absent for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub queue_order: Option<Vec<String>>,
    /// Strategies that dispatch indirectly (`multipass`, `frontier`): wgpu's indirect-call
    /// validation was on (`WGPU_VALIDATION_INDIRECT_CALL`, `scheduler::gpu::instance_flags`;
    /// off by default); absent for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indirect_validation: Option<bool>,
    /// Device-driven multi-pass: how its rounds were dispatched (`RunStats::round_dispatch`:
    /// `fused`, `per-procedure`, `sinks-apart`, `sinks-first`; `--fused-rounds` resolved for
    /// the adapter); absent for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub round_dispatch: Option<String>,
    /// Device-driven multi-pass: most workgroups of a procedure a round
    /// (`RunStats::max_workgroups`, `--max-workgroups` resolved for the adapter); absent for
    /// the others and where there is no cap.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_workgroups: Option<u32>,
    /// How long each wait for the GPU polled before it blocked, in microseconds
    /// (`Gpu::spin_wait`: 1,000 on a GPU, 0 on a CPU adapter, unless `SCHED_SPIN_WAIT_US`);
    /// it moves wall times, not GPU times.
    #[serde(default)]
    pub spin_wait_us: u64,
    pub idle_polls: u64,
    pub abandoned: u64,
    /// Megakernel: slot flags (words) cleared on the device before its launches, only those
    /// an earlier launch on the same queues wrote (`RunStats::flags_cleared`); absent for the
    /// others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flags_cleared: Option<u64>,
    pub queue_growths: u64,
    /// Multi-pass rounds run in part under a queue limit (`RunStats::partial_rounds`).
    #[serde(default)]
    pub partial_rounds: u64,
    /// Megakernel items parked on the host under a queue limit (`RunStats::parked_items`).
    #[serde(default)]
    pub parked_items: u64,
    pub peak_occupancy: Vec<u64>,
    pub queue_bytes: u64,
    pub workgroups: u32,
    /// Megakernel: the co-resident workgroups its probe found, where it launched a share of
    /// them (`RunStats::probed_workgroups`, `--workgroup-share`); absent where it launched all
    /// or a fixed count.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probed_workgroups: Option<u32>,
    /// Megakernel with `--turn-anatomy`: per phase (claim, wait, ...), its count over the run
    /// (`scheduler::megakernel::anatomy::TurnAnatomy::phases`), then `turns`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub turn_anatomy: Vec<(String, u64)>,
}

/// Which run of what: the fields every record of one (workload, size, strategy) shares.
pub struct RunKey<'a> {
    pub workload: &'a str,
    pub strategy: &'a Strategy,
    pub prepared: &'a Prepared,
    /// The device it ran on (its name and `Gpu::spin_wait` go into the record).
    pub gpu: &'a Gpu,
    pub run: u32,
}

impl RunRecord {
    pub fn new(k: &RunKey, m: &Measurement) -> RunRecord {
        let s = m.stats.clone().unwrap_or_default();
        let per_s = |ms: f64| (ms > 0.0).then(|| m.items as f64 / ms * 1e3);
        let time = m.gpu_ms.unwrap_or(m.wall_ms);
        RunRecord {
            error: m.mismatch.clone(),
            verified: m.verified,
            items: m.items,
            gpu_ms: m.gpu_ms,
            wall_ms: Some(m.wall_ms),
            items_per_s: m.gpu_ms.and_then(per_s),
            items_per_s_wall: per_s(m.wall_ms),
            gteps: m
                .edges
                .and_then(|e| (time > 0.0).then(|| e as f64 / time / 1e6)),
            executed: s.executed,
            rounds: s.rounds,
            launches: s.launches,
            batches: s.batches,
            local_items: s.local_items,
            idle_polls: s.idle_polls,
            abandoned: s.abandoned,
            flags_cleared: (s.workgroup_size > 0).then_some(s.flags_cleared),
            queue_growths: s.queue_growths,
            partial_rounds: s.partial_rounds,
            parked_items: s.parked_items,
            peak_occupancy: s.peak_occupancy,
            queue_bytes: s.queue_bytes,
            workgroups: s.workgroups,
            probed_workgroups: (s.probed_workgroups > 0 && s.probed_workgroups != s.workgroups)
                .then_some(s.probed_workgroups),
            turn_anatomy: s.turn_anatomy.as_ref().map_or(Vec::new(), |a| {
                let mut v: Vec<(String, u64)> =
                    a.phases().iter().map(|p| (p.0.to_string(), p.2)).collect();
                v.push(("turns".into(), a.turns));
                v
            }),
            item_layout: (!s.item_layout.is_empty()).then(|| s.item_layout.clone()),
            enqueue: (!s.enqueue.is_empty()).then(|| s.enqueue.clone()),
            workgroup_size: (s.workgroup_size > 0).then_some(s.workgroup_size),
            local_queues: (s.workgroup_size > 0).then_some(s.local_queues),
            local_workgroup_bytes: (s.local_workgroup_bytes > 0).then_some(s.local_workgroup_bytes),
            guided_claims: (s.workgroup_size > 0).then_some(s.guided_claims),
            queue_order: (!s.queue_order.is_empty()).then(|| s.queue_order.clone()),
            indirect_validation: matches!(k.strategy.name().as_str(), "multipass" | "frontier")
                .then(scheduler::gpu::indirect_validation),
            round_dispatch: (!s.round_dispatch.is_empty()).then(|| s.round_dispatch.clone()),
            max_workgroups: s.max_workgroups,
            ..Self::failed(k, String::new())
        }
    }

    /// A run that stopped with `error` before it could be measured.
    pub fn failed(k: &RunKey, error: String) -> RunRecord {
        RunRecord {
            workload: k.workload.to_string(),
            strategy: k.strategy.name(),
            policy: k.strategy.policy().map(|p| p.name().to_string()),
            size: k.prepared.size.clone(),
            params: k.prepared.params.clone(),
            item_layout: None,
            enqueue: None,
            workgroup_size: None,
            adapter: k.gpu.adapter_name(),
            run: k.run,
            items: 0,
            problem_items: k.prepared.problem_items,
            verified: false,
            error: Some(error),
            gpu_ms: None,
            wall_ms: None,
            items_per_s: None,
            items_per_s_wall: None,
            gteps: None,
            executed: Vec::new(),
            rounds: 0,
            launches: 0,
            batches: 0,
            local_items: 0,
            local_queues: None,
            local_workgroup_bytes: None,
            guided_claims: None,
            queue_order: None,
            indirect_validation: None,
            round_dispatch: None,
            max_workgroups: None,
            spin_wait_us: k.gpu.spin_wait.as_micros() as u64,
            idle_polls: 0,
            abandoned: 0,
            flags_cleared: None,
            queue_growths: 0,
            partial_rounds: 0,
            parked_items: 0,
            peak_occupancy: Vec::new(),
            queue_bytes: 0,
            workgroups: 0,
            probed_workgroups: None,
            turn_anatomy: Vec::new(),
        }
    }
}
