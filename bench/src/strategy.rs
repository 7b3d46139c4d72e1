//! What a benchmark run is timed under: one of the scheduler's strategies (the megakernel once
//! per queue policy), the workload's CPU implementation (rayon), or a workload's own baseline.

use scheduler::{
    Gpu, HostMultipassConfig, ItemLayout, MegakernelConfig, MultipassConfig, Program, QueuePolicy,
    RunError, Scheduler, StrategyKind, Workgroups,
};

/// The megakernel's queue policies, as the command line names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Policy {
    /// Later procedures first (`QueuePolicy::Priority` with the default order).
    Priority,
    /// The queue whose oldest waiting batch was published first (`QueuePolicy::Fifo`).
    Fifo,
}

impl Policy {
    pub const ALL: [Policy; 2] = [Policy::Priority, Policy::Fifo];

    pub fn name(self) -> &'static str {
        match self {
            Policy::Priority => "priority",
            Policy::Fifo => "fifo",
        }
    }

    /// The scheduler's policy; `order`: the procedures named first under `Priority`
    /// (`schedbench --priority`), ignored under `Fifo`.
    pub fn queue_policy(self, order: &[String]) -> QueuePolicy {
        match self {
            Policy::Priority => QueuePolicy::Priority(order.to_vec()),
            Policy::Fifo => QueuePolicy::Fifo,
        }
    }
}

/// One strategy of a benchmark. Names (records, tables, plots, `--strategy`): `megakernel`
/// (priority policy, the default), `megakernel-fifo`, every other [`StrategyKind::name`],
/// `cpu`, and each workload's baselines (e.g. BFS's `frontier`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Strategy {
    /// The scheduler; `policy` matters only to the megakernel.
    Scheduler { kind: StrategyKind, policy: Policy },
    /// The workload's multi-threaded CPU implementation (rayon), timed on the host.
    Cpu,
    /// A workload's own implementation outside the scheduler, by name.
    Baseline(&'static str),
}

impl Strategy {
    /// Every scheduler strategy: each [`StrategyKind`] in `StrategyKind::ALL`, the megakernel
    /// once per [`Policy`]. A new `StrategyKind` joins the suite here with no change.
    pub fn scheduler_all() -> Vec<Strategy> {
        let mut v = Vec::new();
        for kind in StrategyKind::ALL {
            if kind == StrategyKind::Megakernel {
                v.extend(Policy::ALL.map(|policy| Strategy::Scheduler { kind, policy }));
            } else {
                v.push(Strategy::Scheduler {
                    kind,
                    policy: Policy::Priority,
                });
            }
        }
        v
    }

    /// Every strategy of a workload with these baselines, scheduler strategies first.
    pub fn all_for(baselines: &[&'static str]) -> Vec<Strategy> {
        let mut v = Self::scheduler_all();
        v.push(Strategy::Cpu);
        v.extend(baselines.iter().map(|b| Strategy::Baseline(b)));
        v
    }

    pub fn name(&self) -> String {
        match self {
            Strategy::Scheduler {
                kind: StrategyKind::Megakernel,
                policy: Policy::Priority,
            } => "megakernel".into(),
            Strategy::Scheduler {
                kind: StrategyKind::Megakernel,
                policy,
            } => format!("megakernel-{}", policy.name()),
            Strategy::Scheduler { kind, .. } => kind.name().into(),
            Strategy::Cpu => "cpu".into(),
            Strategy::Baseline(b) => b.to_string(),
        }
    }

    /// The queue policy, for megakernel runs.
    pub fn policy(&self) -> Option<Policy> {
        match self {
            Strategy::Scheduler {
                kind: StrategyKind::Megakernel,
                policy,
            } => Some(*policy),
            _ => None,
        }
    }

    pub fn is_megakernel(&self) -> bool {
        self.policy().is_some()
    }

    /// Runs on the GPU (the scheduler or a GPU baseline) rather than on the host's cores.
    pub fn is_gpu(&self) -> bool {
        !matches!(self, Strategy::Cpu)
    }

    /// The strategy named `s` among `all` (`megakernel-priority` is accepted for `megakernel`;
    /// `multipass-floor`, never in a workload's list, wherever `multipass-host` is).
    pub fn find(all: &[Strategy], s: &str) -> Option<Strategy> {
        let s = if s == "megakernel-priority" {
            "megakernel"
        } else {
            s
        };
        let floor = StrategyKind::MultipassFloor;
        if s == floor.name() {
            let host = StrategyKind::MultipassHost.name();
            return all
                .iter()
                .any(|x| x.name() == host)
                .then_some(Strategy::Scheduler {
                    kind: floor,
                    policy: Policy::Priority,
                });
        }
        all.iter().find(|x| x.name() == s).cloned()
    }
}

/// Scheduler settings the command line can change (defaults: [`GpuConfig::default`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GpuConfig {
    /// Megakernel workgroups; `None` probes the co-resident count.
    pub workgroups: Option<u32>,
    /// With `workgroups` `None`: launch this share (numerator, denominator) of the probed
    /// count (`Workgroups::ProbeShare`); `None`: the workload's choice
    /// ([`GpuConfig::or_workgroup_share`]; all where a workload makes none).
    pub workgroup_share: Option<(u32, u32)>,
    /// Threads per megakernel workgroup (`MegakernelConfig::workgroup_size`); `None`: its
    /// default (256).
    pub workgroup_size: Option<u32>,
    /// Megakernel workgroup steps per claimed batch (at least 1); `None`: the workload's choice
    /// (1 but for Reyes frames: `reyes::gpu_render::megakernel_batch_steps`).
    pub batch_steps: Option<u32>,
    /// Steps per batch of named procedures (`MegakernelConfig::procedure_batch_steps`);
    /// `None`: the workload's choice ([`GpuConfig::or_procedure_steps`]; each workload's
    /// `megakernel_procedure_steps`).
    pub procedure_steps: Option<Vec<(String, u32)>>,
    /// Longest pause of an idle megakernel workgroup (`MegakernelConfig::idle_backoff`).
    pub idle_backoff: u32,
    /// Procedures named first in the priority policy's order (`QueuePolicy::Priority`); empty:
    /// the default order.
    pub priority: Vec<String>,
    /// `MegakernelConfig::guided_claims`; `None`: the workload's choice
    /// ([`GpuConfig::or_guided_claims`]; on for Reyes frames and BFS on GPUs, off elsewhere).
    pub guided_claims: Option<bool>,
    /// How the queues hold items (`MegakernelConfig::item_layout`); `None`: `ItemLayout::for_program`.
    pub item_layout: Option<ItemLayout>,
    /// `MegakernelConfig::direct_enqueue`; `None`: direct wherever a batch's tickets fit.
    pub direct_enqueue: Option<bool>,
    /// Queue slots at the start of a run; `None` lets the workload choose from its size.
    pub capacity: Option<u32>,
    /// Most slots a queue may grow to (every strategy's `max_capacity`); `None`: the library's
    /// default.
    pub max_capacity: Option<u32>,
    /// `MegakernelConfig::turn_anatomy`.
    pub turn_anatomy: bool,
    /// `MegakernelConfig::subgroups`; `None`: where the adapter has them; default `Some(false)`.
    pub subgroups: Option<bool>,
    /// `MegakernelConfig::local_queues`; `None`: the workload's choice
    /// ([`GpuConfig::or_local_queues`]; off where a workload makes none).
    pub local_queues: Option<bool>,
    /// `MegakernelConfig::local_bytes`; `None`: its default.
    pub local_bytes: Option<u32>,
    /// `MegakernelConfig::local_workgroup_bytes`; `None`: the workload's choice
    /// ([`GpuConfig::or_local_workgroup_bytes`]; narrow trees on GPUs, 0 (the slots buffer)
    /// elsewhere).
    pub local_workgroup_bytes: Option<u32>,
    /// `MegakernelConfig::defer_local_sinks` (default `true`).
    pub defer_local_sinks: bool,
    /// `MultipassConfig::fused_rounds` (the device-driven multi-pass); `None`: by adapter.
    pub fused_rounds: Option<bool>,
    /// `MultipassConfig::fused_sinks_apart` (default `false`).
    pub fused_sinks_apart: bool,
    /// `MultipassConfig::fused_sinks_first` (default `false`).
    pub fused_sinks_first: bool,
    /// `MultipassConfig::max_workgroups`; `None`: by adapter.
    pub max_workgroups: Option<u32>,
}

impl Default for GpuConfig {
    fn default() -> Self {
        GpuConfig {
            workgroups: None,
            workgroup_share: None,
            workgroup_size: None,
            batch_steps: None,
            procedure_steps: None,
            idle_backoff: MegakernelConfig::default().idle_backoff,
            priority: Vec::new(),
            guided_claims: None,
            item_layout: None,
            direct_enqueue: None,
            capacity: None,
            max_capacity: None,
            turn_anatomy: false,
            subgroups: Some(false),
            local_queues: None,
            local_bytes: None,
            local_workgroup_bytes: None,
            defer_local_sinks: true,
            fused_rounds: None,
            fused_sinks_apart: false,
            fused_sinks_first: false,
            max_workgroups: None,
        }
    }
}

impl GpuConfig {
    /// This configuration with `workload`'s batch steps per procedure where the command line
    /// named none.
    pub fn or_procedure_steps(mut self, workload: Vec<(String, u32)>) -> GpuConfig {
        self.procedure_steps = self.procedure_steps.or(Some(workload));
        self
    }

    /// This configuration with `workload`'s queue order where the command line named none.
    pub fn or_priority(mut self, workload: Vec<String>) -> GpuConfig {
        if self.priority.is_empty() {
            self.priority = workload;
        }
        self
    }

    /// This configuration with `workload`'s choice of guided claims where the command line
    /// made none.
    pub fn or_guided_claims(mut self, workload: bool) -> GpuConfig {
        self.guided_claims = self.guided_claims.or(Some(workload));
        self
    }

    /// This configuration with `workload`'s share of the probed workgroups where the command
    /// line gave neither a share nor a count.
    pub fn or_workgroup_share(mut self, workload: (u32, u32)) -> GpuConfig {
        self.workgroup_share = self.workgroup_share.or(Some(workload));
        self
    }

    /// This configuration with `workload`'s local area in workgroup memory where the command
    /// line gave none.
    pub fn or_local_workgroup_bytes(mut self, workload: u32) -> GpuConfig {
        self.local_workgroup_bytes = self.local_workgroup_bytes.or(Some(workload));
        self
    }

    /// This configuration with `workload`'s choice of local queues where the command line
    /// made none.
    pub fn or_local_queues(mut self, workload: bool) -> GpuConfig {
        self.local_queues = self.local_queues.or(Some(workload));
        self
    }
}

/// Compiles `program` for a scheduler strategy, queues starting at `capacity` slots.
/// Panics if `strategy` is not a scheduler strategy (callers dispatch on that first).
pub fn compile(
    gpu: &Gpu,
    program: &Program,
    strategy: &Strategy,
    config: &GpuConfig,
    capacity: u32,
) -> Result<Scheduler, RunError> {
    let Strategy::Scheduler { kind, policy } = strategy else {
        panic!("compile: `{}` is not a scheduler strategy", strategy.name());
    };
    #[allow(unreachable_patterns)] // the wildcard serves strategies added to StrategyKind later
    match kind {
        StrategyKind::Megakernel => Scheduler::megakernel(
            gpu,
            program,
            MegakernelConfig {
                workgroups: match (config.workgroups, config.workgroup_share) {
                    (Some(n), _) => Workgroups::Fixed(n),
                    (None, Some((numerator, denominator))) if numerator != denominator => {
                        Workgroups::ProbeShare {
                            max: 4096,
                            numerator,
                            denominator,
                        }
                    }
                    (None, _) => Workgroups::Probe { max: 4096 },
                },
                workgroup_size: config
                    .workgroup_size
                    .unwrap_or(MegakernelConfig::default().workgroup_size),
                policy: policy.queue_policy(&config.priority),
                batch_steps: config.batch_steps.unwrap_or(1),
                procedure_batch_steps: config.procedure_steps.clone().unwrap_or_default(),
                guided_claims: config.guided_claims.unwrap_or(false),
                idle_backoff: config.idle_backoff,
                item_layout: config.item_layout,
                direct_enqueue: config.direct_enqueue,
                turn_anatomy: config.turn_anatomy,
                subgroups: config.subgroups,
                local_queues: config.local_queues.unwrap_or(false),
                local_bytes: config
                    .local_bytes
                    .unwrap_or(MegakernelConfig::default().local_bytes),
                local_workgroup_bytes: config.local_workgroup_bytes.unwrap_or(0),
                defer_local_sinks: config.defer_local_sinks,
                initial_capacity: capacity,
                max_capacity: config
                    .max_capacity
                    .unwrap_or(MegakernelConfig::default().max_capacity),
                ..Default::default()
            },
        ),
        StrategyKind::Multipass => Scheduler::multipass(
            gpu,
            program,
            MultipassConfig {
                initial_capacity: capacity,
                fused_rounds: config.fused_rounds,
                fused_sinks_apart: config.fused_sinks_apart,
                fused_sinks_first: config.fused_sinks_first,
                max_workgroups: config.max_workgroups,
                max_capacity: config
                    .max_capacity
                    .unwrap_or(MultipassConfig::default().max_capacity),
                ..Default::default()
            },
        ),
        StrategyKind::MultipassHost | StrategyKind::MultipassFloor => Scheduler::multipass_host(
            gpu,
            program,
            HostMultipassConfig {
                initial_capacity: capacity,
                replay_floor: *kind == StrategyKind::MultipassFloor,
                item_layout: config.item_layout,
                max_capacity: config
                    .max_capacity
                    .unwrap_or(HostMultipassConfig::default().max_capacity),
                ..Default::default()
            },
        ),
        // Strategies added to StrategyKind later run with their default configuration.
        other => Scheduler::new(gpu, program, *other, capacity),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_found_again() {
        let all = Strategy::all_for(&["frontier"]);
        let names: Vec<String> = all.iter().map(|s| s.name()).collect();
        assert!(names.contains(&"megakernel".to_string()));
        assert!(names.contains(&"megakernel-fifo".to_string()));
        assert!(names.contains(&"multipass".to_string()));
        assert_eq!(names.iter().filter(|n| *n == "cpu").count(), 1);
        for (i, n) in names.iter().enumerate() {
            assert_eq!(names.iter().position(|m| m == n), Some(i), "{n} twice");
            assert_eq!(Strategy::find(&all, n).as_ref(), Some(&all[i]));
        }
        assert_eq!(
            Strategy::find(&all, "megakernel-priority"),
            Strategy::find(&all, "megakernel")
        );
        assert_eq!(Strategy::find(&all, "gpu"), None);
        assert_eq!(
            all.iter().filter(|s| s.is_megakernel()).count(),
            Policy::ALL.len()
        );
        // The floor is named, never listed, and found wherever the host-driven multi-pass is.
        let floor = StrategyKind::MultipassFloor;
        assert!(!names.contains(&floor.name().to_string()));
        let found = Strategy::find(&all, floor.name()).unwrap();
        assert_eq!(found.name(), "multipass-floor");
        assert!(found.is_gpu() && !found.is_megakernel());
        let cpu_only = [Strategy::Cpu];
        assert_eq!(Strategy::find(&cpu_only, floor.name()), None);
    }
}
