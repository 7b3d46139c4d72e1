//! GPU tests of the scheduler on whatever adapter the environment names (lavapipe in CI).
//! No adapter is a failure, never a skip.

use scheduler::*;
use workloads::tree::{ChildEnqueue, Fanout, TreeParams, TreeRun};

#[path = "common/adapter.rs"]
mod adapter;

fn gpu() -> Gpu {
    adapter::open_gpu(wgpu::Features::empty())
}

fn small_tree(seed: u32) -> TreeParams {
    TreeParams {
        roots: 5,
        max_depth: 8,
        fanout: Fanout::Uniform(3),
        work: 3,
        payload_words: 5,
        seed,
        children: Default::default(),
    }
}

/// A chain of 151 rounds (fan-out 1, depth 150): more than the host-driven timer's query set
/// holds (64 rounds of passes).
fn chain_tree() -> TreeParams {
    TreeParams {
        roots: 3,
        max_depth: 150,
        fanout: Fanout::Fixed(1),
        work: 1,
        payload_words: 1,
        seed: 5,
        children: Default::default(),
    }
}

#[test]
fn tree_matches_cpu_reference_on_every_strategy() {
    let gpu = gpu();
    eprintln!("adapter: {}", gpu.adapter_name());
    let reference = small_tree(7).reference();
    for children in [
        ChildEnqueue::Whole,
        ChildEnqueue::Words,
        ChildEnqueue::ByStrategy,
    ] {
        let params = TreeParams {
            children,
            ..small_tree(7)
        };
        let run = TreeRun::new(&gpu, params).unwrap();
        for kind in StrategyKind::ALL {
            let s = Scheduler::new(&gpu, &run.program, kind, 1 << 12).unwrap();
            let (stats, result) = run.run(&gpu, &s).unwrap();
            eprintln!("{children:?} {kind:?}: {stats:?}");
            assert_eq!(result, reference, "{children:?} {kind:?}");
        }
        // Both item layouts of both multi-passes (the megakernel's are in the stress test).
        for item_layout in [ItemLayout::Interleaved, ItemLayout::Planar] {
            let device = MultipassConfig {
                initial_capacity: 1 << 12,
                item_layout: Some(item_layout),
                ..Default::default()
            };
            let host = HostMultipassConfig {
                initial_capacity: 1 << 12,
                item_layout: Some(item_layout),
                ..Default::default()
            };
            let device = Scheduler::multipass(&gpu, &run.program, device).unwrap();
            let host = Scheduler::multipass_host(&gpu, &run.program, host).unwrap();
            for s in [device, host] {
                let (_, result) = run.run(&gpu, &s).unwrap();
                assert_eq!(result, reference, "{children:?} {item_layout:?}");
            }
        }
    }
}

/// A host-driven run of more rounds than its timer's query set holds (64 passes) reads the
/// full sets' timestamps with the rounds' counts: its submissions are its rounds plus the one
/// after the last round, and it still reports its GPU time.
#[test]
fn host_driven_timestamps_come_back_with_the_rounds() {
    let gpu = gpu();
    let params = chain_tree();
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    let s = Scheduler::new(&gpu, &run.program, StrategyKind::MultipassHost, 1 << 10).unwrap();
    let before = gpu.submissions();
    let (stats, result) = run.run(&gpu, &s).unwrap();
    assert_eq!(result, reference);
    assert!(stats.rounds > 128, "{stats:?}");
    assert_eq!(gpu.submissions() - before, stats.submits + 1, "{stats:?}");
    assert_eq!(stats.submits, stats.rounds, "{stats:?}");
    if gpu.timestamps {
        assert!(stats.gpu_ms.is_some_and(|ms| ms > 0.0), "{stats:?}");
    }
}

/// Waits that poll before they block (`Gpu::spin_wait`) see the same runs finish: exact
/// results on every strategy, whether the spin outlasts the work (a long spin) or runs out
/// first and the wait blocks (a spin of one microsecond). Unless `SCHED_SPIN_WAIT_US` says
/// otherwise a GPU polls for `DEFAULT_SPIN_WAIT` and a CPU adapter (lavapipe), whose work
/// needs the cores, not at all.
#[test]
fn waits_that_poll_first_keep_every_result() {
    let mut gpu = gpu();
    if std::env::var_os(scheduler::gpu::SPIN_WAIT_ENV).is_none() {
        let expected = match gpu.is_cpu_adapter() {
            true => std::time::Duration::ZERO,
            false => scheduler::gpu::DEFAULT_SPIN_WAIT,
        };
        assert_eq!(gpu.spin_wait, expected, "{}", gpu.adapter_name());
    }
    let params = small_tree(11);
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    for spin in [
        std::time::Duration::from_micros(1),
        std::time::Duration::from_secs(5),
    ] {
        gpu.spin_wait = spin;
        for kind in StrategyKind::ALL {
            let s = Scheduler::new(&gpu, &run.program, kind, 1 << 12).unwrap();
            for _ in 0..2 {
                let (stats, result) = run.run(&gpu, &s).unwrap();
                assert_eq!(result, reference, "{kind:?}, spin {spin:?}: {stats:?}");
            }
        }
    }
}

/// Deterministic pseudo-random numbers for the stress test (no extra dependency).
struct Lcg(u64);
impl Lcg {
    fn below(&mut self, n: u32) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) % n as u64) as u32
    }
}

fn stress_configs() -> Vec<(&'static str, MegakernelConfig)> {
    // Every run starts at its initial capacity, so the tiny queues grow run after run (except
    // "oversubscribed" and "probed", which keep the room of the runs before).
    let base = MegakernelConfig {
        size_from_last_run: false,
        ..Default::default()
    };
    vec![
        (
            "one workgroup",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(1),
                initial_capacity: 1 << 12,
                ..base.clone()
            },
        ),
        (
            // Tiny queues grow; short launches end with work left; one-poll waits abandon slots.
            "tiny queues, short launches, impatient waits",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                policy: QueuePolicy::Fifo,
                batch_steps: 2,
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                ..base.clone()
            },
        ),
        (
            // Batches of a different size per procedure (the outbox parts and the queues'
            // slack follow each source's own batch), tiny queues that grow, short launches.
            "steps per procedure, tiny queues, short launches",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                procedure_batch_steps: vec![("leaf".into(), 3), ("branch".into(), 1)],
                batch_steps: 2,
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                ..base.clone()
            },
        ),
        (
            // Launches end at their loop bound with room to spare: the live items go through the
            // host compaction, not the growth one.
            "roomy queues, very short launches",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 6,
                spin_limit: 2,
                initial_capacity: 1 << 15,
                ..base.clone()
            },
        ),
        (
            // Direct enqueue (the default wherever a batch's tickets fit), on
            // one-step batches (the two-step ones above are too large for it: outbox), tiny
            // queues and impatient waits.
            "direct enqueue, tiny queues, short launches, impatient waits",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                direct_enqueue: Some(true),
                ..base.clone()
            },
        ),
        (
            // The same in planar items: live items move plane by plane on the device (growth)
            // and through the host.
            "planar items, tiny queues, short launches, impatient waits",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                batch_steps: 2,
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                item_layout: Some(ItemLayout::Planar),
                ..base.clone()
            },
        ),
        (
            "planar items, roomy queues, very short launches",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 6,
                spin_limit: 2,
                initial_capacity: 1 << 15,
                item_layout: Some(ItemLayout::Planar),
                ..base.clone()
            },
        ),
        (
            // Tickets once per subgroup where the adapter has them (the default takes one
            // per item), both ways of enqueueing.
            "subgroups, direct enqueue, tiny queues, impatient waits",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                direct_enqueue: Some(true),
                subgroups: None,
                ..base.clone()
            },
        ),
        (
            "subgroups, outbox, tiny queues, impatient waits",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                direct_enqueue: Some(false),
                subgroups: None,
                ..base.clone()
            },
        ),
        (
            // Local queues (the trees keep their children local) in regions of a few items:
            // emits overflow to the global queues, held items spill at short launches' ends and
            // when a local batch finds no room in tiny queues.
            "small local regions, tiny queues, short launches",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                local_queues: true,
                local_bytes: 512,
                ..base.clone()
            },
        ),
        (
            "planar items, small local regions, direct enqueue",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 40,
                initial_capacity: 16,
                local_queues: true,
                local_bytes: 512,
                direct_enqueue: Some(true),
                item_layout: Some(ItemLayout::Planar),
                ..base.clone()
            },
        ),
        (
            "local queues in full regions",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                local_queues: true,
                ..base.clone()
            },
        ),
        (
            // The local area in workgroup memory: local batches that emitted only held items
            // skip the release fence and the publish barrier; tiny queues, impatient waits and
            // short launches spill held items from workgroup memory.
            "local area in workgroup memory, tiny queues, short launches, impatient waits",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                local_queues: true,
                local_workgroup_bytes: 1024,
                ..base.clone()
            },
        ),
        (
            "planar items, local area in workgroup memory, outbox enqueue",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                max_iterations: 40,
                local_queues: true,
                local_workgroup_bytes: 3072,
                direct_enqueue: Some(false),
                item_layout: Some(ItemLayout::Planar),
                ..base.clone()
            },
        ),
        (
            // Held sinks run in their priority turn, not after other held work.
            "local queues, sinks not deferred, short launches",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(2),
                max_iterations: 64,
                local_queues: true,
                defer_local_sinks: false,
                ..base.clone()
            },
        ),
        (
            // A local batch of 1,024-thread workgroups holds four times the items, in buffers
            // of the slots buffer sized from the batch; emits go through the outbox.
            "local queues, 1,024-thread workgroups, outbox enqueue, short launches",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(2),
                workgroup_size: 1024,
                max_iterations: 40,
                initial_capacity: 16,
                local_queues: true,
                direct_enqueue: Some(false),
                ..base.clone()
            },
        ),
        (
            // Workgroups of 768 threads: three times the items per step and per batch (the
            // lanes of the turn's probe, 253-255, are inside the first 256).
            "768-thread workgroups, tiny queues, short launches, impatient waits",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(2),
                workgroup_size: 768,
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                ..base.clone()
            },
        ),
        (
            "1024-thread workgroups, planar items, FIFO, tiny queues",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(2),
                workgroup_size: 1024,
                policy: QueuePolicy::Fifo,
                max_iterations: 40,
                initial_capacity: 16,
                item_layout: Some(ItemLayout::Planar),
                ..base.clone()
            },
        ),
        (
            // Claims cut to each workgroup's share of the pending items: more, smaller
            // batches, the same results.
            "guided claims, steps per procedure, tiny queues, short launches",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(3),
                guided_claims: true,
                procedure_batch_steps: vec![("leaf".into(), 4)],
                batch_steps: 2,
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                ..base.clone()
            },
        ),
        (
            "oversubscribed",
            MegakernelConfig {
                workgroups: Workgroups::Fixed(24),
                batch_steps: 4,
                max_iterations: 200,
                initial_capacity: 64,
                size_from_last_run: true,
                ..base.clone()
            },
        ),
        (
            "probed",
            MegakernelConfig {
                policy: QueuePolicy::Fifo,
                initial_capacity: 256,
                size_from_last_run: true,
                ..base
            },
        ),
    ]
}

#[test]
fn stress_randomized_trees_match_the_cpu_reference_exactly() {
    let gpu = gpu();
    let mut rng = Lcg(0x5eed);
    let (mut runs, mut multi_launch, mut grown, mut abandoned) = (0, 0, 0, 0);
    // Megakernel runs whose live items moved on the device (a growth) or through the host.
    let (mut device_moved, mut host_moved) = (0, 0);
    // The same, of megakernels with planar items (moved plane by plane).
    let (mut planar_device_moved, mut planar_host_moved) = (0, 0);
    // Runs that ran items from local queues, and of those, runs of several launches (held items
    // spilled at a launch's end or when a local batch found no room).
    let (mut local_runs, mut local_relaunched) = (0, 0);
    // Both ways a body hands a child over (`enqueue_<t>` whole, `reserve_<t>` and
    // `store_word`), on small and large items: the default for 3-word items (words), each form
    // everywhere for the 62-word items.
    for (payload, children, trees) in [
        (1u32, ChildEnqueue::ByStrategy, 25),
        (62, ChildEnqueue::Whole, 25),
        (62, ChildEnqueue::Words, 12),
    ] {
        let shape = TreeParams {
            roots: 1,
            max_depth: 1,
            fanout: Fanout::Uniform(4),
            work: 0,
            payload_words: payload,
            seed: 0,
            children,
        };
        let mut tree = TreeRun::new(&gpu, shape).unwrap();
        let mut schedulers: Vec<(String, Scheduler)> = stress_configs()
            .into_iter()
            .map(|(name, c)| {
                (
                    name.to_string(),
                    Scheduler::megakernel(&gpu, &tree.program, c).unwrap(),
                )
            })
            .collect();
        // Both ways of enqueueing are exercised: straight into the slots, and (batches too
        // large for a ticket list in workgroup memory) through the outbox.
        let direct: Vec<bool> = (schedulers.iter())
            .filter_map(|(_, s)| match s {
                Scheduler::Megakernel(m) => Some(m.direct_enqueue()),
                _ => None,
            })
            .collect();
        assert!(
            direct.contains(&true) && direct.contains(&false),
            "{direct:?}"
        );
        // And both ways of taking tickets: per subgroup (lavapipe has subgroups of 8) and per
        // item.
        let subgroups: Vec<bool> = (schedulers.iter())
            .filter_map(|(_, s)| match s {
                Scheduler::Megakernel(m) => Some(m.subgroups()),
                _ => None,
            })
            .collect();
        assert!(
            gpu.subgroups || !gpu.is_lavapipe(),
            "lavapipe without subgroups"
        );
        assert!(subgroups.contains(&false), "{subgroups:?}");
        assert_eq!(subgroups.contains(&true), gpu.subgroups, "{subgroups:?}");
        // Device-driven multi-passes that start every run at 16 slots: growth and partial
        // rounds in most runs.
        let tiny_multipass = |fused_rounds, item_layout, max_workgroups| {
            Scheduler::multipass(
                &gpu,
                &tree.program,
                MultipassConfig {
                    rounds_per_submit: 3,
                    initial_capacity: 16,
                    size_from_last_run: false,
                    fused_rounds,
                    item_layout,
                    max_workgroups,
                    ..Default::default()
                },
            )
            .unwrap()
        };
        schedulers.push((
            "multipass, tiny queues".into(),
            tiny_multipass(Some(true), None, None),
        ));
        schedulers.push((
            // At most two workgroups a procedure: a round's items go grid-stride, many steps
            // a workgroup, with growth and partial rounds as above.
            "multipass, two workgroups a procedure, tiny queues".into(),
            tiny_multipass(None, None, Some(2)),
        ));
        schedulers.push((
            "multipass".into(),
            Scheduler::new(&gpu, &tree.program, StrategyKind::Multipass, 1 << 12).unwrap(),
        ));
        schedulers.push((
            // One dispatch per procedure (the tiny ones above and the planar one fuse each
            // round's procedures into one dispatch), growth and partial rounds as above.
            "multipass, a dispatch per procedure, tiny queues".into(),
            tiny_multipass(Some(false), None, None),
        ));
        schedulers.push((
            "multipass-host, tiny queues".into(),
            Scheduler::multipass_host(
                &gpu,
                &tree.program,
                HostMultipassConfig {
                    initial_capacity: 16,
                    size_from_last_run: false,
                    ..Default::default()
                },
            )
            .unwrap(),
        ));
        schedulers.push((
            "multipass-host".into(),
            Scheduler::new(&gpu, &tree.program, StrategyKind::MultipassHost, 1 << 12).unwrap(),
        ));
        schedulers.push((
            // Planar items: carried inputs copied word by word, growth moves them plane by
            // plane on the device.
            "multipass, planar items, tiny queues".into(),
            tiny_multipass(Some(true), Some(ItemLayout::Planar), None),
        ));
        schedulers.push((
            "multipass-host, planar items, tiny queues".into(),
            Scheduler::multipass_host(
                &gpu,
                &tree.program,
                HostMultipassConfig {
                    initial_capacity: 16,
                    item_layout: Some(ItemLayout::Planar),
                    size_from_last_run: false,
                    ..Default::default()
                },
            )
            .unwrap(),
        ));
        for _ in 0..trees {
            let fanout = if rng.below(3) == 0 {
                Fanout::Fixed(1 + rng.below(2))
            } else {
                Fanout::Uniform(2 + rng.below(3))
            };
            let params = TreeParams {
                roots: 1 + rng.below(8),
                max_depth: 2 + rng.below(9),
                fanout,
                work: rng.below(4),
                payload_words: payload,
                seed: rng.below(1 << 30),
                children,
            };
            let reference = params.reference();
            if reference.branches + reference.leaves > 20_000 {
                continue;
            }
            tree.set_params(params.clone()).unwrap();
            for (name, s) in &schedulers {
                let (stats, result) = tree
                    .run(&gpu, s)
                    .unwrap_or_else(|e| panic!("{name}, {}: {e}", params.describe()));
                assert_eq!(
                    result,
                    reference,
                    "{name}, {}: {stats:?}",
                    params.describe()
                );
                runs += 1;
                // Multi-pass counts dispatches as launches; a relaunch is a megakernel matter.
                let mk = s.kind() == StrategyKind::Megakernel;
                multi_launch += (mk && stats.launches > 1) as u32;
                device_moved += (mk && stats.queue_growths > 0) as u32;
                host_moved += (mk && stats.host_compactions > 0) as u32;
                if name.starts_with("planar") {
                    planar_device_moved += (stats.queue_growths > 0) as u32;
                    planar_host_moved += (stats.host_compactions > 0) as u32;
                }
                grown += (stats.queue_growths > 0) as u32;
                abandoned += (stats.abandoned > 0) as u32;
                local_runs += (stats.local_items > 0) as u32;
                local_relaunched += (stats.local_items > 0 && stats.launches > 1) as u32;
                if stats.local_items > 0 {
                    assert!(
                        name.contains("local"),
                        "{name}: local items without local queues"
                    );
                }
            }
        }
    }
    eprintln!(
        "{runs} runs: {multi_launch} needed several launches, {grown} grew a queue, {abandoned} \
         abandoned a wait; megakernel compactions: {device_moved} runs on the device, \
         {host_moved} on the host ({planar_device_moved} and {planar_host_moved} of them with \
         planar items); {local_runs} ran local queues, {local_relaunched} of them relaunched"
    );
    assert!(runs >= 250, "only {runs} runs");
    assert!(
        local_runs > 20 && local_relaunched > 5,
        "{local_runs} runs with local queues, {local_relaunched} of them relaunched"
    );
    // The hard paths must have been exercised, or this test proves little.
    assert!(
        multi_launch > 20 && grown > 20,
        "{multi_launch} multi-launch, {grown} grown"
    );
    assert!(
        device_moved > 10 && host_moved > 10 && planar_device_moved > 5 && planar_host_moved > 5,
        "compactions: {device_moved} on the device, {host_moved} on the host (planar: \
         {planar_device_moved}, {planar_host_moved})"
    );
}

/// The megakernel's slots through atomic loads and stores (`Gpu::coherent` false: a device
/// without `MEMORY_DECORATION_COHERENT`), which wgpu's Vulkan backend never takes on its own
/// since it always reports the feature: every stress configuration (tiny queues, growth on
/// the device and through the host, planar items, direct and outbox enqueue, local queues)
/// runs random trees of small and large items exactly.
#[test]
fn megakernels_with_atomic_slots_match_the_cpu_reference_exactly() {
    let mut gpu = gpu();
    gpu.coherent = false;
    let mut rng = Lcg(0xa70c);
    let (mut runs, mut grown, mut local_runs) = (0, 0, 0);
    // Children enqueued whole, and word by word.
    for (payload, children) in [(1u32, ChildEnqueue::Whole), (62, ChildEnqueue::Words)] {
        let shape = TreeParams {
            roots: 1,
            max_depth: 1,
            fanout: Fanout::Uniform(4),
            work: 0,
            payload_words: payload,
            seed: 0,
            children,
        };
        let mut tree = TreeRun::new(&gpu, shape).unwrap();
        let schedulers: Vec<(&str, Scheduler)> = stress_configs()
            .into_iter()
            .map(|(name, c)| (name, Scheduler::megakernel(&gpu, &tree.program, c).unwrap()))
            .collect();
        for _ in 0..4 {
            let params = TreeParams {
                roots: 1 + rng.below(8),
                max_depth: 4 + rng.below(5),
                fanout: Fanout::Uniform(2 + rng.below(3)),
                work: rng.below(4),
                payload_words: payload,
                seed: rng.below(1 << 30),
                children,
            };
            let reference = params.reference();
            tree.set_params(params.clone()).unwrap();
            for (name, s) in &schedulers {
                let (stats, result) = tree
                    .run(&gpu, s)
                    .unwrap_or_else(|e| panic!("{name}, {}: {e}", params.describe()));
                assert_eq!(
                    result,
                    reference,
                    "{name}, {}: {stats:?}",
                    params.describe()
                );
                runs += 1;
                grown += (stats.queue_growths > 0) as u32;
                local_runs += (stats.local_items > 0) as u32;
            }
        }
    }
    eprintln!("{runs} runs with atomic slots: {grown} grew a queue, {local_runs} ran local queues");
    // The paths that move items (growth) and hold them (local queues) must have run.
    assert!(
        grown > 10 && local_runs > 10,
        "{grown} grown, {local_runs} local"
    );
}

/// A megakernel whose workgroup memory would pass the device's limit (`.shared` arrays grow
/// with the workgroup size) is refused when it is built, naming the bytes; the same program
/// at 256 threads builds.
#[test]
fn a_megakernel_past_the_workgroup_memory_limit_is_refused() {
    let gpu = gpu();
    let limit = gpu.device.limits().max_compute_workgroup_storage_size;
    let item = ItemType::new("Word", "struct Word { v: u32 }");
    // Half the limit at 256 threads (one thread per item, 16-byte elements), twice it at
    // 1,024.
    let per_item = (limit / (16 * 256 * 2)).max(1);
    let wide = Procedure::new("wide", item, 1)
        .shared("vec4<f32>", per_item)
        .body("fn wide_execute(item: Word, inv: Invocation) { wide_shared[inv.slot] = vec4<f32>(1.0); }");
    let program = Program::new(vec![wide], UserBindings::default()).unwrap();
    let at = |size| {
        Scheduler::megakernel(
            &gpu,
            &program,
            MegakernelConfig {
                workgroup_size: size,
                ..Default::default()
            },
        )
    };
    let err = at(1024).err().expect("a kernel past the limit was built");
    let msg = err.to_string();
    assert!(
        msg.contains("workgroup memory") && msg.contains(&limit.to_string()),
        "{msg}"
    );
    at(256).unwrap();
}

#[test]
fn emitting_more_than_declared_is_an_error_not_a_silent_drop() {
    let gpu = gpu();
    let item = ItemType::new("Word", "struct Word { v: u32 }");
    // Declares one child but emits two.
    let liar = Procedure::new("liar", item.clone(), 1)
        .emits("sink", 1)
        .body("fn liar_execute(item: Word, inv: Invocation) { enqueue_sink(item); enqueue_sink(item); }");
    let sink =
        Procedure::new("sink", item, 1).body("fn sink_execute(item: Word, inv: Invocation) {}");
    let program = Program::new(vec![liar, sink], UserBindings::default()).unwrap();
    let seeds = [Seed::new("liar", &[7u32; 10])];
    for kind in StrategyKind::ALL {
        let s = Scheduler::new(&gpu, &program, kind, 64).unwrap();
        match s.run(&gpu, &seeds, None) {
            Err(RunError::EmitLimit {
                procedure,
                target,
                declared,
            }) => {
                assert_eq!(
                    (procedure.as_str(), target.as_str(), declared),
                    ("liar", "sink", 1),
                    "{kind:?}"
                );
            }
            other => panic!("{kind:?}: expected an emit-limit error, got {other:?}"),
        }
    }
}

#[test]
fn a_queue_that_cannot_hold_live_work_reports_overflow() {
    let gpu = gpu();
    let item = ItemType::new("Word", "struct Word { v: u32 }");
    // One fan item alone may emit 16 into a sink queue of 8: no plan can run it.
    let fan = Procedure::new("fan", item.clone(), 1)
        .emits("sink", 16)
        .body("fn fan_execute(item: Word, inv: Invocation) { for (var i = 0u; i < 16u; i++) { enqueue_sink(item); } }");
    let sink =
        Procedure::new("sink", item, 1).body("fn sink_execute(item: Word, inv: Invocation) {}");
    let program = Program::new(vec![fan, sink], UserBindings::default()).unwrap();
    let seeds = [Seed::new("fan", &[1u32; 4])];
    let mk = Scheduler::megakernel(
        &gpu,
        &program,
        MegakernelConfig {
            initial_capacity: 8,
            max_capacity: 8,
            workgroups: Workgroups::Fixed(2),
            ..Default::default()
        },
    )
    .unwrap();
    let mp = Scheduler::multipass(
        &gpu,
        &program,
        MultipassConfig {
            initial_capacity: 8,
            max_capacity: 8,
            ..Default::default()
        },
    )
    .unwrap();
    let mph = Scheduler::multipass_host(
        &gpu,
        &program,
        HostMultipassConfig {
            initial_capacity: 8,
            max_capacity: 8,
            ..Default::default()
        },
    )
    .unwrap();
    for s in [mk, mp, mph] {
        match s.run(&gpu, &seeds, None) {
            Err(RunError::QueueOverflow { queue, .. }) => assert_eq!(queue, "sink"),
            other => panic!("expected an overflow of `sink`, got {other:?}"),
        }
    }
}

/// A multi-pass round whose worst case does not fit a queue at its limit runs in part and
/// carries the rest (`scheduler::multipass::partial`): a tree that needs far more room breadth
/// first than its queues may have completes exactly, on both multi-pass strategies (the
/// device-driven one with and without fused rounds).
#[test]
fn multi_pass_rounds_that_cannot_fit_a_queue_at_its_limit_run_in_part_and_stay_exact() {
    let gpu = gpu();
    let params = breadth_tree();
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    let roomy = Scheduler::new(&gpu, &run.program, StrategyKind::MultipassHost, 1 << 16).unwrap();
    let (wide, _) = run.run(&gpu, &roomy).unwrap();
    assert!(wide.peak_occupancy[0] > 4 * 32, "{wide:?}");
    let mp = |fused_rounds| {
        Scheduler::multipass(
            &gpu,
            &run.program,
            MultipassConfig {
                initial_capacity: 16,
                max_capacity: 32,
                fused_rounds: Some(fused_rounds),
                ..Default::default()
            },
        )
        .unwrap()
    };
    let mph = |item_layout| {
        Scheduler::multipass_host(
            &gpu,
            &run.program,
            HostMultipassConfig {
                initial_capacity: 16,
                max_capacity: 32,
                item_layout: Some(item_layout),
                ..Default::default()
            },
        )
        .unwrap()
    };
    for s in [
        mp(false),
        mp(true),
        mph(ItemLayout::Interleaved),
        mph(ItemLayout::Planar),
    ] {
        let (stats, result) = run.run(&gpu, &s).unwrap();
        assert_eq!(result, reference, "{stats:?}");
        assert!(stats.partial_rounds > 0, "{stats:?}");
        assert!(stats.peak_occupancy.iter().all(|&p| p <= 32), "{stats:?}");
    }
}

/// The multi-pass floor (`HostMultipassConfig::replay_floor`): a tree's first run is a
/// host-driven run that keeps every item it executed (in rounds run in part too, its queues
/// capped at 32 slots), and each later run of the same seeds replays them in one round, one
/// dispatch per procedure: the CPU reference's leaves every time, in both item layouts, with
/// exactly the items the first run executed. A tree of other seeds is kept anew, and both
/// stay kept.
#[test]
fn the_multipass_floor_replays_every_item_once_in_one_round() {
    let gpu = gpu();
    for (params, max_capacity) in [(small_tree(7), 1 << 16), (breadth_tree(), 32)] {
        let reference = params.reference();
        let run = TreeRun::new(&gpu, params.clone()).unwrap();
        let other = TreeParams {
            roots: params.roots + 1,
            ..params.clone()
        };
        let other_reference = other.reference();
        let other = TreeRun::new(&gpu, other).unwrap();
        for item_layout in [ItemLayout::Interleaved, ItemLayout::Planar] {
            let config = HostMultipassConfig {
                initial_capacity: 16,
                max_capacity,
                item_layout: Some(item_layout),
                replay_floor: true,
                ..Default::default()
            };
            let s = Scheduler::multipass_host(&gpu, &run.program, config).unwrap();
            assert_eq!(s.kind(), StrategyKind::MultipassFloor);
            let (kept, result) = run.run(&gpu, &s).unwrap();
            assert_eq!(result, reference, "{kept:?}");
            assert_eq!(kept.strategy, "multipass-floor capture");
            assert!(kept.rounds > 2, "{kept:?}");
            assert_eq!(kept.partial_rounds > 0, max_capacity == 32, "{kept:?}");
            for (r, want, new) in [(&run, &reference, false), (&other, &other_reference, true)] {
                let mut executed = (!new).then(|| kept.executed.clone());
                for _ in 0..2 {
                    let (stats, result) = r.run(&gpu, &s).unwrap();
                    assert_eq!(&result, want, "{item_layout:?} {stats:?}");
                    let Some(executed) = &executed else {
                        assert_eq!(stats.strategy, "multipass-floor capture");
                        executed = Some(stats.executed);
                        continue;
                    };
                    assert_eq!(stats.strategy, "multipass-floor");
                    assert_eq!(stats.rounds, 1, "{stats:?}");
                    assert_eq!(&stats.executed, executed, "{stats:?}");
                    let procedures = executed.iter().filter(|&&k| k > 0).count();
                    assert_eq!(stats.launches, procedures as u64, "{stats:?}");
                }
            }
            // The first tree is still kept beside the other.
            let (stats, result) = run.run(&gpu, &s).unwrap();
            assert_eq!(result, reference);
            assert_eq!(stats.rounds, 1, "{stats:?}");
        }
    }
    // No seeds: kept and replayed as nothing, no round, no launch.
    let word = ItemType::new("Word", "struct Word { v: u32 }");
    let count = Procedure::new("count", word, 1)
        .emits("count", 1)
        .body("fn count_execute(item: Word, inv: Invocation) { if item.v > 0u { enqueue_count(Word(item.v - 1u)); } }");
    let program = Program::new(vec![count], UserBindings::none()).unwrap();
    let s = Scheduler::new(&gpu, &program, StrategyKind::MultipassFloor, 16).unwrap();
    for strategy in ["multipass-floor capture", "multipass-floor"] {
        let stats = s.run(&gpu, &[], None).unwrap();
        assert_eq!(stats.strategy, strategy);
        assert_eq!((stats.executed[0], stats.rounds, stats.launches), (0, 0, 0));
    }
}

/// A megakernel whose queues, at their limit, cannot hold a tree's breadth (it claims each
/// queue oldest first, so a tree fills it level by level) sets the oldest half of the live
/// items aside on the host and runs the newest, depth first (`megakernel/park.rs`): the tree
/// the multi-passes run in part above completes exactly, with local queues and without, and
/// with planar items; one that cannot run a single item still overflows, nothing lost.
#[test]
fn a_megakernel_whose_queues_cannot_hold_a_tree_s_breadth_parks_work_and_stays_exact() {
    let gpu = gpu();
    let params = breadth_tree();
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    let config = |max_capacity, local_queues, item_layout| MegakernelConfig {
        initial_capacity: 16,
        max_capacity,
        local_queues,
        item_layout: Some(item_layout),
        size_from_last_run: false,
        ..Default::default()
    };
    let mk = |c| Scheduler::megakernel(&gpu, &run.program, c).unwrap();
    for (local, layout) in [
        (false, ItemLayout::Interleaved),
        (true, ItemLayout::Interleaved),
        (false, ItemLayout::Planar),
    ] {
        let (stats, result) = run.run(&gpu, &mk(config(32, local, layout))).unwrap();
        assert_eq!(result, reference, "local {local}, {layout:?}: {stats:?}");
        eprintln!(
            "local {local}, {layout:?}: {} launches, {} items parked",
            stats.launches, stats.parked_items
        );
        assert!(stats.parked_items > 0, "{stats:?}");
        assert!(stats.peak_occupancy.iter().all(|&p| p <= 32), "{stats:?}");
    }
    // A branch emits up to two branches: two slots hold the roots, but one root alone
    // leaves no room for its children, so the split that parks the other cannot help.
    match run.run(&gpu, &mk(config(2, false, ItemLayout::Interleaved))) {
        Err(RunError::QueueOverflow { queue, .. }) => assert_eq!(queue, "branch"),
        other => panic!("expected an overflow of `branch`, got {other:?}"),
    }
    // Parked work takes launches of its own: a run that uses up `max_launches` says so.
    let few = mk(MegakernelConfig {
        max_launches: 20,
        ..config(32, false, ItemLayout::Interleaved)
    });
    match run.run(&gpu, &few) {
        Err(RunError::NoProgress(m)) => assert!(m.contains("parked"), "{m}"),
        other => panic!("expected launches used up, got {other:?}"),
    }
}

/// A tree whose widest level, breadth first, holds several hundred nodes (2 roots, depth 9,
/// 1,024 leaves): more than a queue of 32 slots, by far.
fn breadth_tree() -> TreeParams {
    TreeParams {
        roots: 2,
        max_depth: 9,
        fanout: Fanout::Fixed(2),
        work: 1,
        payload_words: 2,
        seed: 7,
        children: Default::default(),
    }
}

/// Growths a queue needs from 16 slots to hold `items` (what it must hold at most: every item
/// the run ever put in it), plus two for a jump to a refused batch's worst case and rounding.
fn growth_bound(stats: &RunStats) -> u64 {
    stats
        .executed
        .iter()
        .map(|&n| (n.max(16) as f64 / 16.0).log2().ceil() as u64 + 2)
        .sum()
}

#[test]
fn a_run_started_at_capacity_16_grows_geometrically_and_stays_exact() {
    let gpu = gpu();
    let params = TreeParams {
        roots: 6,
        max_depth: 10,
        fanout: Fanout::Uniform(4),
        work: 1,
        payload_words: 2,
        seed: 32,
        children: Default::default(),
    };
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params.clone()).unwrap();
    for kind in StrategyKind::ALL {
        let roomy = Scheduler::new(&gpu, &run.program, kind, 1 << 20).unwrap();
        let (base, result) = run.run(&gpu, &roomy).unwrap();
        assert_eq!(result, reference, "{kind:?} roomy");
        assert_eq!(base.queue_growths, 0, "{kind:?}: {base:?}");
        let tiny = Scheduler::new(&gpu, &run.program, kind, 16).unwrap();
        for again in [false, true] {
            let before = gpu.submissions();
            let (stats, result) = run.run(&gpu, &tiny).unwrap();
            // Every submission is one the host waits on (stats.submits), growth included: the
            // workload's clear, the megakernel's upload and the device-driven multi-pass's
            // moved inputs ride with the next launch or chunk. The host-driven multi-pass adds
            // one after its last round, for the caller's ranges and its timestamps together.
            let after_rounds = (kind == StrategyKind::MultipassHost) as u64;
            assert_eq!(
                gpu.submissions() - before,
                stats.submits + after_rounds,
                "{kind:?}: {stats:?}"
            );
            eprintln!(
                "{kind:?}: {} launches, {} submits, {} growths, {} rounds (roomy: {} launches, \
                 {} submits, {} rounds)",
                stats.launches,
                stats.submits,
                stats.queue_growths,
                stats.rounds,
                base.launches,
                base.submits,
                base.rounds
            );
            assert_eq!(result, reference, "{kind:?}");
            let growths = stats.queue_growths;
            if again {
                // Every strategy starts a run with the room its last run needed (the
                // megakernel) or ended with (the multi-passes): no growth, and a multi-pass
                // runs its rounds as the roomy one does.
                assert_eq!(growths, 0, "{kind:?}: {stats:?}");
                if kind == StrategyKind::MultipassHost {
                    assert_eq!(stats.submits, stats.rounds, "{stats:?}");
                    assert_eq!(stats.rounds, base.rounds, "{stats:?}");
                }
                continue;
            }
            assert!(growths >= 1, "{kind:?} never grew from 16: {stats:?}");
            assert!(growths <= growth_bound(&stats), "{kind:?}: {stats:?}");
            match kind {
                // Every launch ends for a reason: done, a queue out of room (then it grew),
                // its loop bound, or slots abandoned after a bounded wait. The last two are
                // scheduling events (more of them on a loaded CPU adapter, where waiting
                // workgroups spend their loop turns), so the count of launches is not bounded
                // by the growths; what holds under any load is that every launch but the last
                // ran a batch or made room, so launches stay within batches plus growths.
                StrategyKind::Megakernel => {
                    assert!(stats.launches <= stats.batches + growths + 1, "{stats:?}")
                }
                // A refused round costs one submission, and the growth after it anticipates
                // the work's growth over a horizon doubling with each refusal: O(log rounds)
                // submissions. The rounds encoded after a refused one run empty; the next
                // submissions encode only the rounds the growth is expected to hold, so all
                // rounds encoded stay within 3x the roomy run's (which encodes 16).
                StrategyKind::Multipass => {
                    let refusals_bound = (stats.rounds.max(2) as f64).log2().ceil() as u64 + 2;
                    assert!(stats.submits <= refusals_bound, "{stats:?}");
                    assert!(stats.launches <= 3 * base.launches, "{stats:?}");
                }
                // Growth happens before a round, in its own submission: nothing extra.
                StrategyKind::MultipassHost => {
                    assert_eq!(stats.submits, stats.rounds, "{stats:?}");
                    assert_eq!(stats.rounds, base.rounds, "{stats:?}");
                }
                StrategyKind::MultipassFloor => unreachable!("not in StrategyKind::ALL"),
            }
        }
    }
}

/// A megakernel run whose queues had to grow (each growth a relaunch after a host round trip)
/// teaches its scheduler the room the work needs: the next run, memory allowing, is one launch
/// with no growth. One workgroup, so no slot waits on another workgroup (an abandoned wait would
/// also end a launch) and the work fits lavapipe's bounded launch.
#[test]
fn a_megakernel_run_after_one_that_grew_needs_exactly_one_launch() {
    let gpu = gpu();
    let params = TreeParams {
        roots: 4,
        max_depth: 9,
        fanout: Fanout::Uniform(2),
        work: 1,
        payload_words: 2,
        seed: 5,
        children: Default::default(),
    };
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    let mk = Scheduler::megakernel(
        &gpu,
        &run.program,
        MegakernelConfig {
            workgroups: Workgroups::Fixed(1),
            initial_capacity: 16,
            ..Default::default()
        },
    )
    .unwrap();
    let (first, result) = run.run(&gpu, &mk).unwrap();
    assert_eq!(result, reference);
    assert!(first.queue_growths >= 1 && first.launches >= 2, "{first:?}");
    for _ in 0..2 {
        let (next, result) = run.run(&gpu, &mk).unwrap();
        assert_eq!(result, reference);
        assert_eq!((next.launches, next.queue_growths), (1, 0), "{next:?}");
        assert_eq!(next.submits, 1, "{next:?}");
    }
    // A memory budget below that room still bounds the queues (the remembered room is only a
    // start): the first run's final queues, smaller than the room with every batch's promise.
    let budget = first.queue_bytes;
    let (tight, result) = run.run_within(&gpu, &mk, Some(budget)).unwrap();
    assert_eq!(result, reference);
    assert!(tight.queue_bytes <= budget, "{tight:?} within {budget}");
}

/// A megakernel reused for another tree on the same queues clears only the flags the last run
/// wrote (its tickets, below its reserve), not the whole capacity, and every run stays exact.
/// Without local queues every item of a one-launch run holds a ticket of its queue, so the last
/// run's reserve in queue q is its `executed[q]`; the next run stamps its seeds over the first
/// of them and clears the rest. Full binary trees seed every root in `branch` (queue 0).
#[test]
fn a_reused_megakernel_clears_only_the_flags_its_last_run_wrote() {
    let gpu = gpu();
    let tree = |roots, max_depth| TreeParams {
        roots,
        max_depth,
        fanout: Fanout::Fixed(2),
        work: 1,
        payload_words: 1,
        seed: 3,
        children: Default::default(),
    };
    let shapes = [tree(8, 6), tree(2, 3), tree(8, 6), tree(8, 6)];
    let mut run = TreeRun::new(&gpu, shapes[0].clone()).unwrap();
    let mk = Scheduler::megakernel(
        &gpu,
        &run.program,
        MegakernelConfig {
            workgroups: Workgroups::Fixed(1),
            initial_capacity: 1 << 12,
            local_queues: false,
            ..Default::default()
        },
    )
    .unwrap();
    let mut last: Option<RunStats> = None;
    for shape in shapes {
        run.set_params(shape.clone()).unwrap();
        let (stats, result) = run.run(&gpu, &mk).unwrap();
        assert_eq!(result, shape.reference(), "{shape:?}");
        assert_eq!((stats.launches, stats.abandoned), (1, 0), "{stats:?}");
        let expected = match &last {
            // New queues: wgpu zero-initializes them, nothing to clear.
            None => 0,
            Some(prev) => {
                assert_eq!(
                    stats.queue_bytes, prev.queue_bytes,
                    "the same queues, reused"
                );
                let seeds = [shape.roots as u64, 0];
                (0..2)
                    .map(|q| prev.executed[q].saturating_sub(seeds[q]))
                    .sum()
            }
        };
        assert_eq!(stats.flags_cleared, expected, "{shape:?}: {stats:?}");
        last = Some(stats);
    }
}

#[test]
fn a_queue_memory_budget_is_kept_or_reported_as_overflow() {
    let gpu = gpu();
    let params = small_tree(11);
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    for kind in StrategyKind::ALL {
        let s = Scheduler::new(&gpu, &run.program, kind, 1 << 12).unwrap();
        // Far too small for the live work: an overflow, never a silently shorter run.
        match run.run_within(&gpu, &s, Some(64)) {
            Err(RunError::QueueOverflow { .. }) => {}
            other => panic!("{kind:?}: expected an overflow under 64 bytes, got {other:?}"),
        }
        // A budget that fits: the result is complete and the storage stayed inside it.
        let budget = 1 << 20;
        let (stats, result) = run.run_within(&gpu, &s, Some(budget)).unwrap();
        assert!(stats.queue_bytes <= budget, "{kind:?}: {stats:?}");
        assert!(!stats.local_queues, "{kind:?}: {stats:?}");
        assert_eq!(result, reference, "{kind:?}");
    }
    // The workgroups' local areas, in the slots buffer past the queues, count in the budget:
    // where those of every workgroup would take more than half of it, fewer workgroups run
    // (4,096 asked for here, so that this holds on every adapter, as it does for the probed
    // count of a large GPU).
    let config = MegakernelConfig {
        local_queues: true,
        initial_capacity: 1 << 12,
        workgroups: Workgroups::Fixed(4096),
        ..Default::default()
    };
    let local = Scheduler::megakernel(&gpu, &run.program, config).unwrap();
    let budget = 1 << 20;
    let (stats, result) = run.run_within(&gpu, &local, Some(budget)).unwrap();
    assert!(stats.local_items > 0 && stats.local_queues, "{stats:?}");
    assert!(stats.queue_bytes <= budget, "{stats:?}");
    assert!((1..4096).contains(&stats.workgroups), "{stats:?}");
    assert_eq!(result, reference);
    // The same scheduler without a budget launches them all again, in buffers for all of them.
    let (all, result) = run.run(&gpu, &local).unwrap();
    assert_eq!(all.workgroups, 4096, "{all:?}");
    assert!(all.queue_bytes > stats.queue_bytes, "{all:?}");
    assert_eq!(result, reference);
}

/// The device-driven multi-pass records one indirect dispatch per procedure a round and one plan
/// per submission (the last workgroup of a round plans the next; no scan or compaction passes),
/// runs exactly the rounds the
/// host-driven one needs, and a repeated run encodes as many rounds as the last one needed: one
/// submission, no empty round. Results equal the CPU reference every time, also when the chunks
/// are short enough that the first run needs several submissions.
#[test]
fn device_driven_multipass_counts_its_rounds_and_dispatches() {
    let gpu = gpu();
    let params = TreeParams {
        max_depth: 7,
        fanout: Fanout::Uniform(2),
        ..small_tree(21)
    };
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    let nq = run.program.queue_count() as u64;
    let host = Scheduler::new(&gpu, &run.program, StrategyKind::MultipassHost, 1 << 12).unwrap();
    let (base, result) = run.run(&gpu, &host).unwrap();
    assert_eq!(result, reference);
    let rounds = base.rounds;
    assert!(rounds > 3, "{base:?}");
    // Fused rounds: one indirect dispatch a round for all procedures, the same rounds.
    for (chunk, fused) in [(16, false), (2, false), (16, true), (2, true)] {
        let s = Scheduler::multipass(
            &gpu,
            &run.program,
            MultipassConfig {
                rounds_per_submit: chunk,
                fused_rounds: Some(fused),
                ..Default::default()
            },
        )
        .unwrap();
        let nq = if fused { 1 } else { nq };
        let (first, result) = run.run(&gpu, &s).unwrap();
        assert_eq!(result, reference, "chunk {chunk}, first run");
        assert_eq!(first.rounds, rounds, "{first:?}");
        assert_eq!(first.queue_growths, 0, "{first:?}");
        // Chunks of `chunk` rounds until one ends with no work left (no growth here): the
        // last round with work leaves none, so the chunk that holds it is the last.
        let chunks = rounds.div_ceil(chunk as u64);
        assert_eq!(first.submits, chunks, "chunk {chunk}: {first:?}");
        assert_eq!(
            first.launches,
            chunks * (1 + chunk as u64 * nq),
            "{first:?}"
        );
        for k in 0..2 {
            let (again, result) = run.run(&gpu, &s).unwrap();
            assert_eq!(result, reference, "chunk {chunk}, run {k}");
            assert_eq!(again.rounds, rounds, "{again:?}");
            assert_eq!(again.submits, 1, "chunk {chunk}: {again:?}");
            assert_eq!(again.launches, 1 + rounds * nq, "chunk {chunk}: {again:?}");
            assert_eq!(again.executed, first.executed);
        }
    }
}

/// Both multi-passes with stage timing: the same result, rounds and counts as without, one time
/// per procedure plus queue work (none for the host-driven one, whose host plans the rounds),
/// adding up to the run's GPU time. On a small tree, and on a chain of 151 rounds, more than
/// the host-driven timer's query set holds (64 rounds of passes): its full sets come back with
/// the rounds' counts.
#[test]
fn multipass_stage_timing_keeps_results_and_splits_the_time_by_procedure() {
    let gpu = gpu();
    for params in [small_tree(5), chain_tree()] {
        let reference = params.reference();
        let run = TreeRun::new(&gpu, params).unwrap();
        let nq = run.program.queue_count();
        let device = MultipassConfig {
            stage_timing: true,
            ..Default::default()
        };
        let host = HostMultipassConfig {
            stage_timing: true,
            ..Default::default()
        };
        let timed = [
            Scheduler::multipass(&gpu, &run.program, device).unwrap(),
            Scheduler::multipass_host(&gpu, &run.program, host).unwrap(),
        ];
        for s in &timed {
            let (stats, result) = run.run(&gpu, s).unwrap();
            let kind = s.kind();
            assert_eq!(result, reference, "{kind:?}");
            let plain = Scheduler::new(&gpu, &run.program, kind, 1 << 16).unwrap();
            let (untimed, _) = run.run(&gpu, &plain).unwrap();
            assert_eq!(stats.rounds, untimed.rounds, "{kind:?}");
            assert_eq!(stats.executed, untimed.executed, "{kind:?}");
            if !gpu.timestamps {
                eprintln!("adapter has no timestamp queries: only the results are checked");
                assert!(stats.stage_gpu_ms.is_empty(), "{kind:?}");
                continue;
            }
            assert_eq!(stats.stage_gpu_ms.len(), nq + 1, "{kind:?}: {stats:?}");
            assert!(stats.stage_gpu_ms.iter().all(|&t| t >= 0.0), "{stats:?}");
            // Every procedure ran, so each has time.
            assert!(
                stats.stage_gpu_ms[..nq].iter().all(|&t| t > 0.0),
                "{stats:?}"
            );
            if kind == StrategyKind::MultipassHost {
                assert_eq!(stats.stage_gpu_ms[nq], 0.0, "{stats:?}");
                assert!(untimed.stage_gpu_ms.is_empty(), "{untimed:?}");
            }
            let sum: f64 = stats.stage_gpu_ms.iter().sum();
            assert!(
                (sum - stats.gpu_ms.unwrap()).abs() < 1e-9,
                "{kind:?}: {stats:?}"
            );
        }
    }
}

/// A round with more workgroups than its dispatch may have: a 256-thread procedure (one item a
/// step) with 40,000 inputs in a fused round of two procedures, whose share of the dispatch is
/// 65,535 / 2 = 32,767 workgroups. Round 0 is sized by `mp_plan`, round 1 by its inputs'
/// appends (which stop adding workgroups at the share); both stride over every input, so
/// each runs exactly once.
#[test]
fn device_driven_rounds_past_the_dispatch_limit_run_every_input_once() {
    let gpu = gpu();
    let item = ItemType::new("Word", "struct Word { v: u32 }");
    let wide = Procedure::new("wide", item.clone(), 256)
        .emits("mark", 1)
        .body("fn wide_execute(item: Word, inv: Invocation) { if inv.thread == 0u { enqueue_mark(item); } }");
    let mark = Procedure::new("mark", item.clone(), 256).body(
        "fn mark_execute(item: Word, inv: Invocation) { if inv.live && inv.thread == 0u { atomicAdd(&seen[item.v], 1u); } }",
    );
    let user = UserBindings::storage(
        "@group(1) @binding(0) var<storage, read_write> seen: array<atomic<u32>>;",
        &[(0, false)],
    );
    let program = Program::new(vec![wide, mark], user).unwrap();
    let n = 40_000u32;
    let seeds = [Seed::new("wide", &(0..n).collect::<Vec<u32>>())];
    let seen = gpu.storage_buffer("seen", n as u64).unwrap();
    let bind = program.user.bind_group(&gpu, &[&seen]).unwrap();
    let config = MultipassConfig {
        fused_rounds: Some(true),
        ..Default::default()
    };
    let s = Scheduler::multipass(&gpu, &program, config).unwrap();
    let stats = s.run(&gpu, &seeds, Some(&bind)).unwrap();
    assert_eq!(stats.executed, [n as u64, n as u64], "{stats:?}");
    assert_eq!(stats.rounds, 2, "{stats:?}");
    let counts = gpu.read_words(&seen, 0, n as u64).unwrap();
    let wrong: Vec<(usize, u32)> = counts
        .iter()
        .enumerate()
        .filter(|&(_, &c)| c != 1)
        .map(|(i, &c)| (i, c))
        .take(8)
        .collect();
    assert!(wrong.is_empty(), "inputs not run exactly once: {wrong:?}");
}

/// `enqueue_*` adds one item per call by every thread, on every strategy: a 4-thread item whose
/// threads each enqueue one child emits 4, one guarded by `inv.thread == 0u` emits 1, and the
/// declared maximum counts the calls of all the item's threads together.
#[test]
fn every_thread_that_calls_enqueue_adds_an_item_on_every_strategy() {
    let gpu = gpu();
    let item = ItemType::new("Word", "struct Word { v: u32 }");
    // The sinks' items enqueued whole, or (`words`) reserved and stored a word at a time.
    let fan_body = |words: bool| {
        let to_sink = if words {
            "let slot = reserve_sink();\n\
             if slot_reserved(slot) { store_word(slot, Word_v_word, item.v * 4u + inv.thread); }"
        } else {
            "enqueue_sink(Word(item.v * 4u + inv.thread));"
        };
        format!(
            "fn fan_execute(item: Word, inv: Invocation) {{\n{to_sink}\n\
             if inv.thread == 0u {{ enqueue_once(item); }}\n}}"
        )
    };
    let program_of = |declared: u32, words: bool| {
        let fan = Procedure::new("fan", item.clone(), 4)
            .emits("sink", declared)
            .emits("once", 1)
            .body(&fan_body(words));
        let sink = Procedure::new("sink", item.clone(), 1).body(
            "fn sink_execute(item: Word, inv: Invocation) { if inv.live { atomicAdd(&seen[item.v], 1u); } }",
        );
        // `once` marks its own words past the sinks' (item v < 100), so a run that sends
        // `once`'s workgroups to another procedure's items shows.
        let once = Procedure::new("once", item.clone(), 1).body(
            "fn once_execute(item: Word, inv: Invocation) { if inv.live { atomicAdd(&seen[400u + item.v], 1u); } }",
        );
        let user = UserBindings::storage(
            "@group(1) @binding(0) var<storage, read_write> seen: array<atomic<u32>>;",
            &[(0, false)],
        );
        Program::new(vec![fan, sink, once], user).unwrap()
    };
    let n = 100u32;
    let seeds = [Seed::new("fan", &(0..n).collect::<Vec<u32>>())];
    for words in [false, true] {
        let exact = program_of(4, words);
        for kind in StrategyKind::ALL {
            let seen = gpu.storage_buffer("seen", 5 * n as u64).unwrap();
            let bind = exact.user.bind_group(&gpu, &[&seen]).unwrap();
            let s = Scheduler::new(&gpu, &exact, kind, 64).unwrap();
            let stats = s.run(&gpu, &seeds, Some(&bind)).unwrap();
            assert_eq!(
                stats.executed,
                [n as u64, 4 * n as u64, n as u64],
                "{kind:?}, words {words}"
            );
            let counts = gpu.read_words(&seen, 0, 5 * n as u64).unwrap();
            assert!(
                counts.iter().all(|&c| c == 1),
                "{kind:?}, words {words}: {counts:?}"
            );
        }
    }
    let exact = program_of(4, false);
    // The device-driven multi-pass's dispatch groups: a round is one dispatch fused, one per
    // procedure apart, and with the sinks apart one for `fan` and one for `sink` and `once`
    // together (`mp_group_1`, which picks between their loops); with the sinks first, one
    // dispatch whose first workgroups go to `sink` and `once`.
    for (fused, sinks_apart, sinks_first, dispatches, name) in [
        (true, false, false, 1, "fused"),
        (false, false, false, 3, "per-procedure"),
        (true, true, false, 2, "sinks-apart"),
        (true, false, true, 1, "sinks-first"),
    ] {
        let seen = gpu.storage_buffer("seen", 5 * n as u64).unwrap();
        let bind = exact.user.bind_group(&gpu, &[&seen]).unwrap();
        let config = MultipassConfig {
            initial_capacity: 64,
            fused_rounds: Some(fused),
            fused_sinks_apart: sinks_apart,
            fused_sinks_first: sinks_first,
            ..Default::default()
        };
        let s = Scheduler::multipass(&gpu, &exact, config).unwrap();
        for run in 0..2 {
            let stats = s.run(&gpu, &seeds, Some(&bind)).unwrap();
            let what = format!(
                "fused {fused}, sinks apart {sinks_apart}, sinks first {sinks_first}, run {run}: \
                 {stats:?}"
            );
            assert_eq!(stats.executed, [n as u64, 4 * n as u64, n as u64], "{what}");
            assert_eq!(stats.rounds, 2, "{what}");
            assert_eq!(stats.round_dispatch, name, "{what}");
            if run == 1 {
                // The second run encodes exactly the rounds the first needed, in one chunk.
                assert_eq!(stats.launches, 1 + 2 * dispatches, "{what}");
            }
        }
        let counts = gpu.read_words(&seen, 0, 5 * n as u64).unwrap();
        assert!(counts.iter().all(|&c| c == 2), "fused {fused}: {counts:?}");
    }
    // Declaring 3 for 4 threads' calls is an emit-limit error everywhere, either way.
    for (kind, words) in StrategyKind::ALL
        .into_iter()
        .flat_map(|k| [(k, false), (k, true)])
    {
        let short = program_of(3, words);
        let seen = gpu.storage_buffer("seen", 5 * n as u64).unwrap();
        let bind = short.user.bind_group(&gpu, &[&seen]).unwrap();
        let s = Scheduler::new(&gpu, &short, kind, 64).unwrap();
        match s.run(&gpu, &seeds, Some(&bind)) {
            Err(RunError::EmitLimit {
                procedure,
                target,
                declared,
            }) => assert_eq!(
                (procedure.as_str(), target.as_str(), declared),
                ("fan", "sink", 3),
                "{kind:?}, words {words}"
            ),
            other => panic!("{kind:?}, words {words}: expected an emit-limit error, got {other:?}"),
        }
    }
}

/// Guided claims (`MegakernelConfig::guided_claims`) take at most a workgroup's share of the
/// pending items, ceil(pending / workgroups), one step at least: 64 items of a 64-thread
/// procedure (4 a step, batches of up to 32 at 8 steps) need at least 64 / ceil(64 / 8) = 8
/// batches on 8 workgroups, where whole batches could take them in 2; on one workgroup the share
/// is everything, so guided or not, exactly 2 batches. Every item runs once either way.
#[test]
fn guided_claims_take_a_workgroups_share_of_the_pending_items() {
    let gpu = gpu();
    let n = 64u32;
    let item = ItemType::new("Word", "struct Word { v: u32 }");
    let wide = Procedure::new("wide", item, 64).body(
        "fn wide_execute(item: Word, inv: Invocation) {\n\
         if inv.live && inv.thread == 0u { atomicAdd(&seen[item.v], 1u); }\n}",
    );
    let user = UserBindings::storage(
        "@group(1) @binding(0) var<storage, read_write> seen: array<atomic<u32>>;",
        &[(0, false)],
    );
    let program = Program::new(vec![wide], user).unwrap();
    let seeds = [Seed::new("wide", &(0..n).collect::<Vec<u32>>())];
    let batches = |workgroups: u32, guided_claims: bool| {
        let s = Scheduler::megakernel(
            &gpu,
            &program,
            MegakernelConfig {
                workgroups: Workgroups::Fixed(workgroups),
                batch_steps: 8,
                guided_claims,
                ..Default::default()
            },
        )
        .unwrap();
        let seen = gpu.storage_buffer("seen", n as u64).unwrap();
        let bind = program.user.bind_group(&gpu, &[&seen]).unwrap();
        let stats = s.run(&gpu, &seeds, Some(&bind)).unwrap();
        eprintln!("{workgroups} workgroups, guided {guided_claims}: {stats:?}");
        assert_eq!(stats.executed, [n as u64]);
        let words = gpu.read_words(&seen, 0, n as u64).unwrap();
        assert!(words.iter().all(|&c| c == 1), "{words:?}");
        stats.batches
    };
    assert_eq!(batches(1, false), 2);
    assert_eq!(batches(1, true), 2);
    let guided = batches(8, true);
    assert!((8..=n as u64 / 4).contains(&guided), "{guided} batches");
}

/// A share of the probed workgroups launches that share of them, rounded down and at least one,
/// says what the probe found, and keeps the result exact; an empty share or one above 1 is
/// refused.
#[test]
fn a_probe_share_launches_its_part_of_the_probed_workgroups_exactly() {
    let gpu = gpu();
    let params = small_tree(11);
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    let with = |workgroups| {
        Scheduler::megakernel(
            &gpu,
            &run.program,
            MegakernelConfig {
                workgroups,
                ..Default::default()
            },
        )
    };
    let all = with(Workgroups::Probe { max: 64 }).unwrap();
    let (stats, result) = run.run(&gpu, &all).unwrap();
    assert_eq!(result, reference);
    assert_eq!(stats.probed_workgroups, stats.workgroups);
    // Each megakernel probes on its own: on a busy CPU adapter two probes may count
    // differently, so the share is checked against its own probe.
    let share = Workgroups::ProbeShare {
        max: 64,
        numerator: 1,
        denominator: 2,
    };
    let half = with(share).unwrap();
    let (stats, result) = run.run(&gpu, &half).unwrap();
    assert_eq!(result, reference);
    assert!((1..=64).contains(&stats.probed_workgroups), "{stats:?}");
    assert_eq!(stats.workgroups, (stats.probed_workgroups / 2).max(1));
    for (numerator, denominator) in [(0, 2), (3, 2)] {
        let bad = Workgroups::ProbeShare {
            max: 64,
            numerator,
            denominator,
        };
        let e = with(bad)
            .err()
            .expect("an empty or too large share is refused");
        assert!(e.to_string().contains("workgroup share"), "{e}");
    }
}

/// Held work that emits nothing waits for held work that does: a chain of `link`s, each emitting
/// the next link and one `tip` (a sink), both kept local, on one workgroup. Run in priority order
/// (tips first) every level would take two local batches; with the tips deferred until they fill
/// a step or nothing else is held, the 100 links take one batch each and the 100 tips one
/// between them; without the deferral they take about 200. Every item runs once.
#[test]
fn held_items_that_emit_nothing_wait_for_held_work_that_does() {
    let gpu = gpu();
    let depth = 100u32;
    let item = ItemType::new("Link", "struct Link { v: u32 }");
    let link = Procedure::new("link", item.clone(), 1)
        .emits("link", 1)
        .emits("tip", 1)
        .local("link")
        .local("tip")
        .body(&format!(
            "fn link_execute(item: Link, inv: Invocation) {{\n\
             if !inv.live {{ return; }}\n\
             atomicAdd(&seen[item.v], 1u);\n\
             enqueue_tip(Link(item.v));\n\
             if item.v + 1u < {depth}u {{ enqueue_link(Link(item.v + 1u)); }}\n}}"
        ));
    let tip = Procedure::new("tip", item, 1).body(
        "fn tip_execute(item: Link, inv: Invocation) {\n\
         if inv.live { atomicAdd(&seen[item.v], 0x10000u); }\n}",
    );
    let user = UserBindings::storage(
        "@group(1) @binding(0) var<storage, read_write> seen: array<atomic<u32>>;",
        &[(0, false)],
    );
    let program = Program::new(vec![link, tip], user).unwrap();
    for defer in [true, false] {
        let s = Scheduler::megakernel(
            &gpu,
            &program,
            MegakernelConfig {
                workgroups: Workgroups::Fixed(1),
                local_queues: true,
                defer_local_sinks: defer,
                ..Default::default()
            },
        )
        .unwrap();
        let seen = gpu.storage_buffer("seen", depth as u64).unwrap();
        let bind = program.user.bind_group(&gpu, &[&seen]).unwrap();
        let stats = s
            .run(&gpu, &[Seed::new("link", &[0])], Some(&bind))
            .unwrap();
        eprintln!("defer {defer}: {stats:?}");
        assert_eq!(stats.executed, [depth as u64, depth as u64]);
        let words = gpu.read_words(&seen, 0, depth as u64).unwrap();
        assert!(words.iter().all(|&c| c == 0x10001), "{words:?}");
        if defer {
            // The seed's claimed batch, 99 local link batches, the tips' one; a launch cut
            // short by a loop bound (lavapipe) spills what is held and may add a batch per
            // relaunch.
            let bound = depth as u64 + 1 + 2 * (stats.launches as u64 - 1);
            assert!(
                stats.batches <= bound,
                "{} batches, at most {bound}",
                stats.batches
            );
        } else {
            // Without the deferral (`MegakernelConfig::defer_local_sinks` off) each link's
            // tip takes a turn of its own.
            assert!(
                stats.batches >= 3 * depth as u64 / 2,
                "{} batches without the deferral",
                stats.batches
            );
        }
    }
}

/// `Scheduler::run_reading` returns the ranges as the run left them, on every strategy: a
/// small range and a large one (copied with each launch's or submission's read-back, or read
/// once after the host-driven multi-pass's last round), and both for a run of no seeds (no
/// round at all). A range that cannot be read is an error naming it, before the run.
#[test]
fn a_run_reads_ranges_back_as_it_left_them_on_every_strategy() {
    let gpu = gpu();
    let n = 300u32;
    let item = ItemType::new("Word", "struct Word { v: u32 }");
    // Each seed v marks seen[v] and sends v + n on once; those mark seen[v + n].
    let mark = Procedure::new("mark", item, 1)
        .emits("mark", 1)
        .body(&format!(
            "fn mark_execute(item: Word, inv: Invocation) {{\n\
         if inv.live {{ atomicAdd(&seen[item.v], 1u); }}\n\
         if inv.live && item.v < {n}u {{ enqueue_mark(Word(item.v + {n}u)); }}\n}}"
        ));
    let user = UserBindings::storage(
        "@group(1) @binding(0) var<storage, read_write> seen: array<atomic<u32>>;",
        &[(0, false)],
    );
    let program = Program::new(vec![mark], user).unwrap();
    let big_words = (1 << 16) + 5;
    let pattern: Vec<u32> = (0..big_words as u32)
        .map(|i| i.wrapping_mul(2_654_435_761))
        .collect();
    for kind in StrategyKind::ALL {
        let s = Scheduler::new(&gpu, &program, kind, 64).unwrap();
        for seeded in [n, 0] {
            let seen = gpu.storage_buffer("seen", 2 * n as u64).unwrap();
            let big = gpu.storage_buffer("big", big_words).unwrap();
            gpu.queue
                .write_buffer(&big, 0, bytemuck::cast_slice(&pattern));
            let bind = program.user.bind_group(&gpu, &[&seen]).unwrap();
            let seeds = [Seed::new("mark", &(0..seeded).collect::<Vec<u32>>())];
            let reads = [(&seen, 0, 2 * n as u64), (&big, 3, big_words - 3)];
            let (stats, words) = s
                .run_reading(&gpu, &seeds, Some(&bind), None, &reads)
                .unwrap();
            assert_eq!(stats.executed, [2 * seeded as u64], "{kind:?}");
            let marked = if seeded > 0 { 1 } else { 0 };
            assert_eq!(words.len(), 2, "{kind:?}");
            assert!(
                words[0].iter().all(|&w| w == marked),
                "{kind:?}, {seeded} seeds"
            );
            assert_eq!(words[1], pattern[3..], "{kind:?}, {seeded} seeds");
        }
        // A range past its buffer, or a buffer that cannot be copied from, is refused by name
        // before the run.
        let seen = gpu.storage_buffer("seen", 2 * n as u64).unwrap();
        let bind = program.user.bind_group(&gpu, &[&seen]).unwrap();
        let no_copy = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("no copy"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let seeds = [Seed::new("mark", &[0u32])];
        for (reads, expected) in [
            (
                vec![(&seen, 0, 2 * n as u64 + 1)],
                "read range 0 (words 0..601): past the end",
            ),
            (
                vec![(&seen, 0, 1), (&no_copy, 0, 4)],
                "read range 1 (words 0..4): its buffer lacks COPY_SRC",
            ),
        ] {
            match s.run_reading(&gpu, &seeds, Some(&bind), None, &reads) {
                Err(RunError::Program(m)) => assert!(m.contains(expected), "{kind:?}: {m}"),
                other => panic!("{kind:?}: expected a program error, got {other:?}"),
            }
        }
        let (stats, _) = s.run_reading(&gpu, &seeds, Some(&bind), None, &[]).unwrap();
        assert_eq!(stats.executed, [2], "{kind:?}: runs after a refused range");
    }
}

/// Two procedures of 4 and 2 threads running one execute function (`Procedure::execute_of`):
/// each runs its own items with its own threads (`inv.threads`), enqueues as the function says
/// under its own declared emits, on every strategy; the megakernel has one call site for both.
#[test]
fn procedures_sharing_an_execute_function_each_run_their_own_items_on_every_strategy() {
    let gpu = gpu();
    let n = 50u32;
    let item = ItemType::new("Word", "struct Word { v: u32 }");
    // Thread t of item v marks seen[4 v + t]; a seeded item (v < n) also sends v + n to narrow.
    let wide = Procedure::new("wide", item.clone(), 4)
        .emits("narrow", 1)
        .body(&format!(
            "fn wide_execute(item: Word, inv: Invocation) {{\n\
             if inv.live {{ atomicAdd(&seen[item.v * 4u + inv.thread], inv.threads); }}\n\
             if inv.thread == 0u && item.v < {n}u {{ enqueue_narrow(Word(item.v + {n}u)); }}\n}}"
        ));
    let narrow = Procedure::new("narrow", item, 2)
        .emits("narrow", 1)
        .execute_of("wide");
    let user = UserBindings::storage(
        "@group(1) @binding(0) var<storage, read_write> seen: array<atomic<u32>>;",
        &[(0, false)],
    );
    let program = Program::new(vec![wide, narrow], user).unwrap();
    let seeds = [Seed::new("wide", &(0..n).collect::<Vec<u32>>())];
    // CPU reference: wide's 4 threads add 4 each to their items' words, narrow's 2 threads 2.
    let mut expected = vec![0u32; 8 * n as usize];
    for v in 0..n as usize {
        expected[4 * v..4 * v + 4].fill(4);
        expected[4 * (v + n as usize)..4 * (v + n as usize) + 2].fill(2);
    }
    for kind in StrategyKind::ALL {
        let seen = gpu.storage_buffer("seen", 8 * n as u64).unwrap();
        let bind = program.user.bind_group(&gpu, &[&seen]).unwrap();
        let s = Scheduler::new(&gpu, &program, kind, 64).unwrap();
        let stats = s.run(&gpu, &seeds, Some(&bind)).unwrap();
        assert_eq!(stats.executed, [n as u64, n as u64], "{kind:?}");
        let words = gpu.read_words(&seen, 0, 8 * n as u64).unwrap();
        assert_eq!(words, expected, "{kind:?}");
    }
}

/// A run recorded without host waits ([`RecordedRun`]): sized from a full run of the same work,
/// recorded twice into one encoder from seeds in a device buffer, each status says it finished
/// with the CPU's count; sized to its seeds, its status says it did not (never a silent partial
/// run); seeds other than those it was made for are refused. Items are three words that must
/// agree (a node splits only if they do), so a word misplaced on the way into a queue, in
/// either item layout, changes the count.
#[test]
fn recorded_runs_finish_like_a_run_or_say_they_did_not() {
    let gpu = gpu();
    let node = ItemType::new("Node", "struct Node { v: u32, a: u32, b: u32 }");
    let split = Procedure::new("split", node, 1).emits("split", 2).body(
        "fn node(v: u32) -> Node { return Node(v, v * 3u + 1u, v ^ 0x55u); }\n\
         fn split_execute(item: Node, inv: Invocation) {\n\
             if item.v > 0u && item.a == item.v * 3u + 1u && item.b == (item.v ^ 0x55u) {\n\
                 enqueue_split(node(item.v - 1u)); enqueue_split(node(item.v - 1u)); } }",
    );
    let program = Program::new(vec![split], UserBindings::none()).unwrap();
    let vs = [3u32, 5, 6, 0, 11];
    let roots: Vec<[u32; 3]> = vs.iter().map(|&v| [v, v * 3 + 1, v ^ 0x55]).collect();
    // A root v is a full binary tree of depth v: 2^(v+1) - 1 items.
    let expected: u64 = vs.iter().map(|&v| (1u64 << (v + 1)) - 1).sum();
    let n = roots.len() as u32;
    let seeds_buf = gpu.upload("seeds", &roots).unwrap();
    let seeds = [DeviceSeeds {
        procedure: "split",
        buffer: &seeds_buf,
        count: n,
    }];
    // One workgroup: a recorded megakernel's queues get one batch's worst case per workgroup
    // on top of their size, which on a large GPU (the H200: ~4,000 workgroups) would make even
    // the tiny run below big enough for the whole tree. (Two were not co-resident on a loaded
    // lavapipe: slots abandoned after their bounded wait.)
    let megakernel = |item_layout| {
        Scheduler::megakernel(
            &gpu,
            &program,
            MegakernelConfig {
                initial_capacity: 64,
                workgroups: Workgroups::Fixed(1),
                item_layout: Some(item_layout),
                ..Default::default()
            },
        )
        .unwrap()
    };
    for s in [
        megakernel(ItemLayout::Interleaved),
        megakernel(ItemLayout::Planar),
        Scheduler::new(&gpu, &program, StrategyKind::Multipass, 64).unwrap(),
        // Planar: the seeds reach the round buffers' planes through the device scatter.
        Scheduler::multipass(
            &gpu,
            &program,
            MultipassConfig {
                initial_capacity: 64,
                item_layout: Some(ItemLayout::Planar),
                ..Default::default()
            },
        )
        .unwrap(),
    ] {
        let kind = s.kind();
        let full = s.run(&gpu, &[Seed::new("split", &roots)], None).unwrap();
        assert_eq!(full.executed, [expected]);
        let size = RecordedSize::from_stats(&program, kind, &full, &[n], 1.0);
        let run = RecordedRun::new(&gpu, &s, &[("split", n)], &size, None, None).unwrap();
        let words = run.status_words();
        let status = gpu.storage_buffer("status", 2 * words).unwrap();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for k in 0..2 {
            run.record(&s, &mut enc, &seeds, None, &status, k * words)
                .unwrap();
        }
        gpu.submit(enc);
        let all = gpu.read_words(&status, 0, 2 * words).unwrap();
        for (k, st) in all.chunks(words as usize).enumerate() {
            match run.outcome(&program, st).unwrap() {
                Outcome::Done(stats) => {
                    assert_eq!(stats.executed, [expected], "{kind:?} record {k}");
                    assert_eq!(stats.submits, 0);
                }
                o => panic!("{kind:?} record {k}: {o:?}"),
            }
        }
        let tiny = RecordedSize {
            capacity: vec![1],
            rounds: 1,
        };
        let run = RecordedRun::new(&gpu, &s, &[("split", n)], &tiny, None, None).unwrap();
        assert!(run.size.capacity[0] < expected as u32, "{:?}", run.size);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        run.record(&s, &mut enc, &seeds, None, &status, 0).unwrap();
        gpu.submit(enc);
        let st = gpu.read_words(&status, 0, words).unwrap();
        match run.outcome(&program, &st).unwrap() {
            Outcome::Incomplete(why) => assert!(!why.is_empty()),
            o => panic!("{kind:?}: a run too small for its work finished: {o:?}"),
        }
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        let e = run.record(&s, &mut enc, &[], None, &status, 0).unwrap_err();
        assert!(matches!(e, RunError::Program(_)), "{e:?}");
    }
    let host = Scheduler::new(&gpu, &program, StrategyKind::MultipassHost, 64).unwrap();
    let e = RecordedRun::new(&gpu, &host, &[("split", n)], &tiny_size(), None, None)
        .err()
        .unwrap();
    assert!(matches!(e, RunError::Program(_)), "{e:?}");
}

fn tiny_size() -> RecordedSize {
    RecordedSize {
        capacity: vec![1],
        rounds: 1,
    }
}

/// Naga's loop bounding (`Gpu::bounds_loops`): a device keeps wgpu's default until its owner
/// trusts its loops, except where the driver bounds loops itself (lavapipe); once trusted, it
/// is left out unless `SCHED_LOOP_BOUNDING=on` asks for it back. (Every other test here runs on
/// a trusted device: `adapter::open_gpu`.)
#[test]
fn loop_bounding_follows_trust_and_the_driver() {
    let mut gpu = Gpu::from_env().expect("GPU tests need an adapter");
    assert_eq!(gpu.bounds_loops(), !gpu.driver_bounds_loops());
    // SAFETY: the device compiles nothing here.
    #[allow(unsafe_code, reason = "the test of Gpu::trust_loops")]
    unsafe {
        gpu.trust_loops()
    };
    let forced = std::env::var(scheduler::gpu::LOOP_BOUNDING_ENV).is_ok_and(|v| v == "on");
    assert_eq!(gpu.bounds_loops(), forced && !gpu.driver_bounds_loops());
}
