//! How a megakernel is configured: its workgroups, queue policy, local queues and bounds
//! ([`MegakernelConfig`]), chosen when it is compiled.

use super::local::LOCAL_MAX_BYTES;
use crate::item_layout::ItemLayout;
use crate::program::WORKGROUP_SIZE;

/// How many workgroups a launch has.
#[derive(Debug, Clone, PartialEq)]
pub enum Workgroups {
    /// As many as the probe launch finds running at the same time, at most `max`. The default:
    /// a persistent workgroup must never wait on one that has not started.
    Probe {
        /// Most workgroups the probe launches (and so the most it can report).
        max: u32,
    },
    /// A share of what the probe finds: `numerator / denominator` of the co-resident
    /// workgroups (rounded down, at least one), the probe launching at most `max`. For work
    /// that stays narrow, a few thousand items at a time in long chains: fewer workgroups per
    /// SM spread its batches over more SMs' issue slots instead of sharing a few
    /// (docs/scheduler.md 2.3). H100, the deep tree: 1/5 of the 660 probed, 1.117 -> 0.954 ms;
    /// the binary tree, which fills every workgroup, 0.127 -> 0.155 at 2/5 (docs/results.md,
    /// 2026-12-06 (eleventh and twelfth sessions)). Errors: a share of 0 or above 1 is a [`crate::RunError::Program`].
    ProbeShare {
        /// Most workgroups the probe launches.
        max: u32,
        /// The share's numerator, 1..=`denominator`.
        numerator: u32,
        /// The share's denominator, at least 1.
        denominator: u32,
    },
    /// Exactly this many (tests use it to oversubscribe on purpose; waits stay bounded).
    Fixed(u32),
}

impl Workgroups {
    /// The workgroups a launch has when the probe found `probed` co-resident (`Fixed` ignores
    /// it): `Probe`'s all, `ProbeShare`'s share of them rounded down, at least one.
    pub fn of_probed(&self, probed: u32) -> u32 {
        match *self {
            Workgroups::Probe { .. } => probed.max(1),
            Workgroups::ProbeShare {
                numerator,
                denominator,
                ..
            } => (probed as u64 * numerator as u64 / denominator.max(1) as u64).max(1) as u32,
            Workgroups::Fixed(n) => n.max(1),
        }
    }
}

/// Which queue a workgroup takes its next batch from.
#[derive(Debug, Clone, PartialEq)]
pub enum QueuePolicy {
    /// The first queue with work in this order of procedure names (unnamed ones follow in
    /// reverse registration order). "Later stages first" keeps queues short. Items a workgroup
    /// holds in its local queues run before any claim, in this order too, except that a
    /// procedure that emits nothing waits behind other held work until it fills a step
    /// (docs/scheduler.md 2.7).
    Priority(Vec<String>),
    /// The queue whose oldest waiting batch was published first.
    Fifo,
}

/// Turns of the persistent loop per launch on lavapipe: with bodies' own loops (a Reyes grid
/// samples its micropolygons in nested loops) this keeps an invocation's total loop
/// iterations far below lavapipe's cumulative 65,535 cut.
pub const LAVAPIPE_MAX_ITERATIONS: u32 = 96;
/// Polls of a flag per wait on lavapipe (the polls count against the same cut).
pub const LAVAPIPE_SPIN_LIMIT: u32 = 64;

/// Growth factor of the queues after a launch that stopped for want of room: each such launch
/// costs a relaunch (a host wait and new buffers), so growing fourfold instead of twofold halves
/// their number, `log4(need / start)`, for at most 4x the needed memory (within the limit).
pub const ROOM_GROWTH: u64 = 4;

/// Settings of [`Megakernel::new`](crate::Megakernel::new); [`Default`] gives the documented defaults.
#[derive(Debug, Clone)]
pub struct MegakernelConfig {
    /// Workgroups per launch (default: probed, at most 4,096).
    pub workgroups: Workgroups,
    /// Which queue a workgroup takes its next batch from (default: later procedures first).
    pub policy: QueuePolicy,
    /// Threads per workgroup: a multiple of 256 up to 1,024 and the device's
    /// `max_compute_invocations_per_workgroup` (default 256). Every procedure's items per step
    /// and `.shared` array scale with it. Larger workgroups bound the registers each thread may
    /// take (the 65,536 of an NVIDIA SM shared by at least one workgroup: 768 threads get at
    /// most 80): a way to run more warps per SM where the driver's compiler would otherwise
    /// give a large kernel 128 registers and two workgroups of 256. Measured on the H200 it
    /// made no workload's default faster at every size: Reyes frames as fast or slower at 768,
    /// most trees slower; the large-payload tree faster at 512 at one size of four
    /// (docs/scheduler.md 4; docs/results.md, 2026-12-03 (fifth session)).
    pub workgroup_size: u32,
    /// Workgroup steps per claimed batch (a step runs `workgroup_size / threads_per_item`
    /// items), for every procedure not named in `procedure_batch_steps`.
    pub batch_steps: u32,
    /// Workgroup steps per batch of the procedures named here (`(name, steps)`), overriding
    /// `batch_steps` for them: a batch's turn costs the same scheduling atomics however many
    /// items it holds, so a procedure of few items a step (one grid of 256 threads) amortizes
    /// them over more steps, while one of many small items keeps batches short and its
    /// children published early. Default empty. A name that is not a procedure of the program
    /// is an error of [`Megakernel::new`](crate::Megakernel::new).
    pub procedure_batch_steps: Vec<(String, u32)>,
    /// Guided self-scheduling (Polychronopoulos and Kuck, IEEE Trans. Computers 1987): a claim
    /// takes at most the workgroup's share of every item still pending in the launch,
    /// ceil(`G_PENDING` / workgroups), one step's worth at least, so that the last items of a
    /// workload that is running short are spread over the workgroups instead of held by a few
    /// full batches, while batches stay full as long as the pending work would fill every
    /// workgroup (docs/scheduler.md 2.2). Default `false`. Measured on the H200 at 1920x1080,
    /// with Bound first (`reyes::gpu_render::megakernel_priority`, which turns it on), against
    /// neither: teapot 0.568 -> 0.529 ms, Killeroo 0.807 -> 0.792 (docs/results.md, 2026-12-04
    /// (third session)); on the trees, whose queues run short only at the end, up to 2.4%
    /// slower (2026-12-04 (second session)).
    pub guided_claims: bool,
    /// Loop turns per workgroup per launch; far below lavapipe's 65,535-iteration cut. On
    /// lavapipe that cut counts every loop iteration nested in the persistent loop, bodies'
    /// loops included, so there it is lowered to [`LAVAPIPE_MAX_ITERATIONS`].
    pub max_iterations: u32,
    /// Polls of one slot's flag before it is abandoned to the next launch.
    pub spin_limit: u32,
    /// Longest pause of an idle workgroup between two polls for work, in trips of a chain of
    /// dependent loads (each an L1 hit's latency, during which the warp issues almost nothing)
    /// run by one warp, lanes 0-31, while the others wait at a barrier (docs/scheduler.md 2.2);
    /// the pause doubles per idle turn up to this (each pause jittered between half and one and
    /// a half times its length, so that workgroups idle since the same turn do not poll in
    /// step) and ends at the first claimed batch. On the H200 32 is the best bound measured or
    /// within about 2% of it on every tree, better than no pause (deep tree 1.364 against 1.588
    /// ms), and the load chain beat the earlier multiply-add pause by up to 11% (deep tree;
    /// docs/results.md, 2026-12-03 (second session), "an idle pause that waits on memory"). 0
    /// polls without a pause (and is what lavapipe gets: its loop limiter counts the pause's
    /// trips).
    pub idle_backoff: u32,
    /// Slots per queue at the start of a run (at least twice the seeds).
    pub initial_capacity: u32,
    /// A queue grows (at least doubling) up to this many slots, and never past its share of
    /// the largest storage binding. At that limit a launch that can run nothing parks half of
    /// the live work on the host and runs the rest first (`RunStats::parked_items`); only a
    /// single live item that cannot run is a [`RunError::QueueOverflow`](crate::RunError::QueueOverflow).
    pub max_capacity: u32,
    /// Launches per run before it stops with [`RunError::NoProgress`](crate::RunError::NoProgress) (default 10,000).
    pub max_launches: u32,
    /// How queues and outboxes hold items; `None` (the default) picks
    /// [`ItemLayout::for_program`].
    pub item_layout: Option<ItemLayout>,
    /// Enqueue straight into the target queue's slots (a ticket per item, the batch's tickets
    /// listed in workgroup memory for publishing) instead of into a per-workgroup outbox copied
    /// out after the batch: saves a write and a read of every item, costs an atomic per item
    /// instead of one per batch. Only where a batch's worst-case emits fit
    /// [`MAX_DIRECT_EMITS`] (`Some(true)` where they do not: the outbox, with a warning).
    /// `None` (the default): wherever a batch's tickets fit. Measured on
    /// the H200: 64-word items 1.17 -> 0.80 ms, Reyes frames 1-4% faster (docs/results.md,
    /// "Direct enqueue in the megakernel"); 3-word items were 6-25% slower until the turn lost
    /// its fence after the run, and are now 2-7% faster on four trees of five (irregular 2%
    /// slower; docs/results.md, 2026-12-02, "A cheaper megakernel turn").
    pub direct_enqueue: Option<bool>,
    /// Count what each loop turn spends per phase (claim, wait for flags, execute, enqueue,
    /// reserve, copy, publish) and report it in [`RunStats::turn_anatomy`](crate::RunStats::turn_anatomy): a few registers and one
    /// atomic per counter per workgroup at exit. Off by default; when off the counters are
    /// compiled out.
    pub turn_anatomy: bool,
    /// Take enqueue tickets once per subgroup (one atomic for all lanes of a subgroup that emit
    /// to a queue at once) with wgpu's `SUBGROUP` operations, instead of one atomic per item.
    /// `Some(false)` (the default): one atomic per item; measured on the H200 the subgroup path
    /// was slower on the trees (binary 0.254 against 0.233 ms, large-payload 0.748 against
    /// 0.730; docs/results.md, 2026-12-02), where a batch's lanes rarely emit to one queue at
    /// once. `None`: where the device has them ([`Gpu::subgroups`](crate::Gpu::subgroups)); `Some(true)` on a device
    /// without them is an error.
    pub subgroups: Option<bool>,
    /// Start a run with the room the largest earlier run of this megakernel needed to finish in
    /// one launch (default `true`): queues that had to grow (each growth a relaunch after a host
    /// round trip) are not shrunk back to `initial_capacity`. `false` starts every run at
    /// `initial_capacity` (tests use it to exercise growth run after run).
    pub size_from_last_run: bool,
    /// Keep the emits that procedures declare local ([`crate::Procedure::local`]) in the
    /// workgroup's own area of the slots buffer and run them there next, before claiming from
    /// the global queues (no ticket, flag or claim for them; docs/scheduler.md 2.7). No effect on
    /// a program that declares nothing local. Default `false`: it pays where a batch's children
    /// fill the workgroup's next steps (H200: binary tree 0.160 -> 0.122 ms, irregular 0.183 ->
    /// 0.167, the one-item chain 4.2 -> 2.4 us a turn; docs/results.md, 2026-12-04, "A local
    /// batch without barriers of its own"), on the deep tree too since held leaves wait for held
    /// branches (1.34 -> 1.15 ms; 2026-12-04 (fourth session)), and costs where work splits into
    /// few pieces before other work (Reyes frames 3-5%).
    pub local_queues: bool,
    /// Most bytes of one workgroup's local area, both buffers of every local target (default
    /// [`LOCAL_MAX_BYTES`]: a full batch per buffer where it fits; split evenly between the
    /// targets otherwise). A target whose share holds no item is not kept local, and where no
    /// target is left the megakernel runs without local queues and warns. Global memory: the
    /// slots buffer grows by the area in use (at most this) times the workgroups.
    pub local_bytes: u32,
    /// With local queues, keep the local area in workgroup memory instead of the slots
    /// buffer, at most this many bytes of it (0, the default: the slots buffer, sized by
    /// `local_bytes`). A local batch then reads its items from workgroup memory, and one that
    /// emitted only held items skips the device-scope release fence and the publish barrier
    /// (docs/scheduler.md 2.7). Workgroup memory is what limits co-resident workgroups where
    /// registers do not (H100: 2 KiB cut the trees' 660 workgroups to 528, 4 KiB to 396, 12
    /// KiB to 264; docs/results.md, 2026-12-05 (tenth session) and 2026-12-06 (eleventh)).
    /// The kernel's whole workgroup memory
    /// must fit the device's `max_compute_workgroup_storage_size`, or building it is an error
    /// that says what would fit (the kernel takes about 8 KiB besides, at 256 threads). Like
    /// `local_bytes` it is a most: an area holds at most a full batch per buffer. An area
    /// whose buffers hold less than a step makes part-empty local batches, and warns: at 1-4
    /// KiB the H100's trees ran 1.5-4x slower, the deep trees and the one-item chain at most
    /// 4% faster. Leave it at 0 unless the work is narrow (few items a level, so that
    /// fewer co-resident workgroups cost nothing: the tree's choice,
    /// `TreeParams::megakernel_local_workgroup_bytes` in the `workloads` crate) or for A/B runs.
    pub local_workgroup_bytes: u32,
    /// With local queues, held items of a procedure that emits nothing (a sink) wait while they
    /// are fewer than a step and other held work exists (`LOCAL_DEFER`, docs/scheduler.md 2.7).
    /// Default `true`: H200, deep tree 1.34 -> 1.15 ms, irregular 0.164 -> 0.148, binary 0.122
    /// -> 0.124 (docs/results.md, 2026-12-04 (fourth session)); `false` (`schedbench
    /// --no-defer-local-sinks`) runs held sinks in their priority turn, as before, for that A/B.
    pub defer_local_sinks: bool,
}

/// Most tickets one batch of a 256-thread workgroup may list for direct enqueue
/// (`MegakernelConfig::direct_enqueue`): 8 KiB of workgroup memory, beside the 4 KiB of
/// `wg_ready`, within the 16 KiB every Vulkan device offers. Larger workgroups may list this
/// many per 256 threads, where the whole kernel's workgroup memory fits the device's limit.
pub const MAX_DIRECT_EMITS: u32 = 2048;

impl Default for MegakernelConfig {
    fn default() -> Self {
        MegakernelConfig {
            workgroups: Workgroups::Probe { max: 4096 },
            workgroup_size: WORKGROUP_SIZE,
            policy: QueuePolicy::Priority(Vec::new()),
            batch_steps: 1,
            procedure_batch_steps: Vec::new(),
            guided_claims: false,
            max_iterations: 16_384,
            spin_limit: 4096,
            idle_backoff: 32,
            initial_capacity: 1 << 16,
            max_capacity: 1 << 26,
            max_launches: 10_000,
            item_layout: None,
            direct_enqueue: None,
            turn_anatomy: false,
            subgroups: Some(false),
            size_from_last_run: true,
            local_queues: false,
            local_bytes: LOCAL_MAX_BYTES,
            local_workgroup_bytes: 0,
            defer_local_sinks: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Workgroups;

    /// A share of the probed width rounds down and keeps one workgroup; the others as given.
    #[test]
    fn a_probe_share_takes_its_part_of_the_probed_width() {
        let share = |numerator, denominator| Workgroups::ProbeShare {
            max: 4096,
            numerator,
            denominator,
        };
        assert_eq!(share(2, 5).of_probed(660), 264);
        assert_eq!(share(2, 5).of_probed(528), 211);
        assert_eq!(share(1, 1).of_probed(660), 660);
        assert_eq!(share(2, 5).of_probed(2), 1);
        assert_eq!(Workgroups::Probe { max: 4096 }.of_probed(660), 660);
        assert_eq!(Workgroups::Fixed(3).of_probed(660), 3);
    }
}
