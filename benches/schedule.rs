//! Criterion benches of the scheduling strategies on the tree workload (the same runs as
//! `schedbench`). Every measured run is also checked against the CPU reference.
//! SCHED_BENCH_FULL=1 selects the 2,097,088-item benchmark tree (for real GPUs).

use criterion::{Criterion, criterion_group, criterion_main};
use scheduler::*;
use workloads::tree::{Fanout, TreeParams, TreeRun};

fn trees() -> Vec<(&'static str, TreeParams)> {
    if std::env::var_os("SCHED_BENCH_FULL").is_some() {
        vec![
            ("binary-depth14", TreeParams::binary_benchmark()),
            (
                "irregular-deep",
                TreeParams {
                    roots: 64,
                    max_depth: 40,
                    fanout: Fanout::Uniform(3),
                    work: 0,
                    payload_words: 1,
                    seed: 3,
                    children: Default::default(),
                },
            ),
        ]
    } else {
        vec![(
            "binary-depth8",
            TreeParams {
                roots: 8,
                max_depth: 8,
                ..TreeParams::binary_benchmark()
            },
        )]
    }
}

fn bench(c: &mut Criterion) {
    let mut gpu = Gpu::from_env().expect("benches need a GPU adapter");
    // SAFETY: the trees' procedures and the scheduler's modules end every loop
    // (`Gpu::trust_loops`), as in schedbench.
    #[allow(
        unsafe_code,
        reason = "Gpu::trust_loops: every loop of this device's shaders ends"
    )]
    unsafe {
        gpu.trust_loops()
    };
    for (name, params) in trees() {
        let reference = params.reference();
        let tree = TreeRun::new(&gpu, params).unwrap();
        let mut group = c.benchmark_group(format!("tree/{name}"));
        group.sample_size(10);
        for kind in StrategyKind::ALL {
            let s = Scheduler::new(&gpu, &tree.program, kind, 1 << 22).unwrap();
            group.bench_function(kind.name(), |b| {
                b.iter(|| {
                    let (_, r) = tree.run(&gpu, &s).unwrap();
                    assert_eq!(r, reference);
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
