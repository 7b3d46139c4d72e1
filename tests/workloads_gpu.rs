//! GPU tests of the Mandelbrot and BFS workloads on whatever adapter the environment names
//! (lavapipe in CI), every strategy, exact equality with the CPU references. No adapter is a
//! failure, never a skip. Sizes are small: the whole file runs in well under a minute on lavapipe.

use scheduler::*;
use workloads::bfs::{BfsParams, BfsRun, UNREACHED};
use workloads::frontier_bfs::FrontierBfs;
use workloads::mandelbrot::{self, MandelParams, MandelRun};

#[path = "common/adapter.rs"]
mod adapter;

fn gpu() -> Gpu {
    adapter::open_gpu(wgpu::Features::empty())
}

/// Small views, in the arithmetic of `gpu`'s `fma`.
fn small_mandelbrot(gpu: &Gpu) -> Vec<MandelParams> {
    [
        // Clipped edge tiles (100 = 3 × 32 + 4), thin rectangles, every procedure used.
        MandelParams {
            width: 100,
            height: 70,
            max_iterations: 256,
            tile: 32,
            min_side: 6,
            ..MandelParams::whole_set(100)
        },
        // On lavapipe the megakernel's persistent loop and every loop in the bodies share one
        // 65,535-iteration cut per invocation (docs/scheduler.md, section 4), so the dwell loops
        // stay short here: seahorse(128) at 2,048 iterations tripped it (six ms_pixels items ran
        // twice, which the work-count check below caught).
        MandelParams {
            max_iterations: 512,
            ..MandelParams::seahorse(64)
        },
    ]
    .into_iter()
    .map(|p| p.for_gpu(gpu).unwrap())
    .collect()
}

#[test]
fn mandelbrot_equals_the_brute_force_image_on_every_strategy() {
    let gpu = gpu();
    eprintln!("adapter: {}", gpu.adapter_name());
    eprintln!("fma fused: {}", mandelbrot::fma_is_fused(&gpu).unwrap());
    for params in small_mandelbrot(&gpu) {
        let reference = params.reference();
        let cpu = params.mariani_silver();
        assert_eq!(
            cpu.image,
            reference,
            "CPU Mariani-Silver, {}",
            params.describe()
        );
        let run = MandelRun::new(&gpu, params.clone()).unwrap();
        for kind in StrategyKind::ALL {
            let s = Scheduler::new(&gpu, &run.program, kind, 1 << 10).unwrap();
            let (stats, result) = run.run(&gpu, &s).unwrap();
            eprintln!(
                "{kind:?} {}: {:?} {stats:?}",
                params.describe(),
                result.work
            );
            assert_eq!(
                result.image.differing_pixels(&reference),
                0,
                "{kind:?} {}",
                params.describe()
            );
            assert!(result == reference);
            // The same subdivision as the CPU's: same items per procedure, same pixel counts.
            assert_eq!(result.work, cpu.work, "{kind:?} {}", params.describe());
            assert_eq!(
                stats.executed,
                vec![cpu.work.rects, cpu.work.fills, cpu.work.pixel_rects]
            );
        }
    }
}

#[test]
fn mandelbrot_survives_tiny_queues_and_short_launches() {
    let gpu = gpu();
    let params = small_mandelbrot(&gpu).remove(0);
    let reference = params.reference();
    let run = MandelRun::new(&gpu, params).unwrap();
    let s = Scheduler::megakernel(
        &gpu,
        &run.program,
        MegakernelConfig {
            workgroups: Workgroups::Fixed(3),
            max_iterations: 16,
            initial_capacity: 8,
            ..Default::default()
        },
    )
    .unwrap();
    let (stats, result) = run.run(&gpu, &s).unwrap();
    assert!(stats.launches > 1, "{stats:?}");
    assert!(result == reference);
}

#[test]
fn mandelbrot_refuses_parameters_in_the_wrong_arithmetic() {
    let gpu = gpu();
    let mut params = small_mandelbrot(&gpu).remove(0);
    params.fused_fma = !params.fused_fma;
    let e = MandelRun::new(&gpu, params).err().expect("refused");
    assert!(e.to_string().contains("for_gpu"), "{e}");
}

fn check_bfs(gpu: &Gpu, params: BfsParams, scheduler_runs: &[Scheduler], run: &BfsRun) {
    let reference = params.reference();
    for s in scheduler_runs {
        let (stats, levels) = run.run(gpu, s).unwrap();
        let wrong = levels
            .iter()
            .zip(&reference)
            .filter(|(a, b)| a != b)
            .count();
        eprintln!("{} {}: {stats:?}", stats.strategy, params.describe());
        assert_eq!(wrong, 0, "{} {}", stats.strategy, params.describe());
        assert_eq!(levels, reference);
        let reached = reference.iter().filter(|&&l| l != UNREACHED).count() as u64;
        assert!(
            stats.executed[0] >= reached,
            "every reached vertex ran at least once"
        );
    }
}

#[test]
fn bfs_levels_equal_the_cpu_bfs_on_every_strategy() {
    let gpu = gpu();
    // Default shape, then tiny chunks so that even modest degrees go through bfs_edges items.
    for (chunk, split, threads) in [(32, 8, 8), (4, 2, 4)] {
        let mut params = BfsParams::graph500(10, 1).unwrap();
        (params.chunk_edges, params.split, params.threads) = (chunk, split, threads);
        let run = BfsRun::new(&gpu, params.clone()).unwrap();
        let schedulers: Vec<Scheduler> = StrategyKind::ALL
            .into_iter()
            .map(|k| Scheduler::new(&gpu, &run.program, k, 1 << 12).unwrap())
            .collect();
        check_bfs(&gpu, params.clone(), &schedulers, &run);
        let (stats, _) = run.run(&gpu, &schedulers[1]).unwrap();
        assert!(stats.executed[1] > 0, "hub lists were cut into chunks");
    }
}

#[test]
fn bfs_survives_tiny_queues_and_short_launches() {
    let gpu = gpu();
    let mut params = BfsParams::graph500(9, 7).unwrap();
    params.chunk_edges = 8;
    let run = BfsRun::new(&gpu, params.clone()).unwrap();
    let s = [
        Scheduler::megakernel(
            &gpu,
            &run.program,
            MegakernelConfig {
                workgroups: Workgroups::Fixed(4),
                max_iterations: 24,
                spin_limit: 1,
                initial_capacity: 16,
                ..Default::default()
            },
        )
        .unwrap(),
        Scheduler::multipass(
            &gpu,
            &run.program,
            MultipassConfig {
                initial_capacity: 16,
                rounds_per_submit: 3,
                ..Default::default()
            },
        )
        .unwrap(),
    ];
    check_bfs(&gpu, params, &s, &run);
}

#[test]
fn frontier_bfs_equals_the_cpu_bfs() {
    let gpu = gpu();
    for (scale, seed) in [(10, 1), (11, 2)] {
        let params = BfsParams::graph500(scale, seed).unwrap();
        let reference = params.reference();
        let f = FrontierBfs::new(&gpu, params.clone()).unwrap();
        for _ in 0..2 {
            let (stats, levels) = f.run(&gpu).unwrap();
            eprintln!("frontier {}: {stats:?}", params.describe());
            assert_eq!(levels, reference);
            let max = reference.iter().filter(|&&l| l != UNREACHED).max().unwrap();
            assert_eq!(stats.levels, max + 1);
            assert_eq!(
                stats.reached,
                reference.iter().filter(|&&l| l != UNREACHED).count() as u64
            );
        }
    }
}
