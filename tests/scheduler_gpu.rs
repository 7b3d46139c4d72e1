//! GPU tests of the scheduler on whatever adapter the environment names (lavapipe in CI).
//! No adapter is a failure, never a skip.

use scheduler::workloads::tree::{Fanout, TreeParams, TreeRun};
use scheduler::*;

fn gpu() -> Gpu {
    Gpu::from_env().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

fn small_tree(seed: u32) -> TreeParams {
    TreeParams {
        roots: 5,
        max_depth: 8,
        fanout: Fanout::Uniform(3),
        work: 3,
        payload_words: 5,
        seed,
    }
}

#[test]
fn tree_matches_cpu_reference_on_both_strategies() {
    let gpu = gpu();
    eprintln!("adapter: {}", gpu.adapter_name());
    let params = small_tree(7);
    let reference = params.reference();
    let run = TreeRun::new(&gpu, params).unwrap();
    for kind in StrategyKind::ALL {
        let s = Scheduler::new(&gpu, &run.program, kind, 1 << 12).unwrap();
        let (stats, result) = run.run(&gpu, &s).unwrap();
        eprintln!("{kind:?}: {stats:?}");
        assert_eq!(result, reference, "{kind:?}");
    }
}
