//! A complete small workload on the scheduler's public API: each `split` item fans out to
//! `FANOUT` children (one per thread of the item) until depth `DEPTH`, where the children go to
//! `leaf`, which adds one to a counter and a hash of its id to a checksum in a user buffer.
//! The result is checked against the same tree walked on the CPU, for every strategy.
//!
//! ```sh
//! cargo run -p scheduler --example fanout
//! ```
//!
//! It needs no dependency but `scheduler`: wgpu and bytemuck come re-exported.

use std::fmt;
use std::process::ExitCode;

use scheduler::bytemuck::{Pod, Zeroable};
use scheduler::hash::{lowbias32, lowbias32_wgsl};
use scheduler::{
    Gpu, ItemType, Procedure, Program, RunError, Scheduler, Seed, StrategyKind, UserBindings,
};

/// Children per `split` item: one per thread of the item.
const FANOUT: u32 = 4;
/// Roots start at depth 0; children at depth `DEPTH` are leaves.
const DEPTH: u32 = 5;
/// Root items (the seeds).
const ROOTS: u32 = 8;

/// The host twin of the WGSL item `Node` (checked against naga's layout in `main`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
#[bytemuck(crate = "scheduler::bytemuck")]
struct Node {
    id: u32,
    depth: u32,
}

const NODE_WGSL: &str = "struct Node { id: u32, depth: u32 }";

/// Bind group 1: the leaves' counter and checksum (read-write), the tree depth (read-only),
/// and the hash both sides use.
fn user_wgsl() -> String {
    "@group(1) @binding(0) var<storage, read_write> fan_out: array<atomic<u32>, 2>;\n\
     @group(1) @binding(1) var<storage, read> fan_cfg: array<u32, 1>;\n"
        .to_string()
        + &lowbias32_wgsl("fan_hash")
}

/// Every thread of a `split` item enqueues one child: `FANOUT` threads, `FANOUT` children.
const SPLIT_WGSL: &str = "
fn split_execute(item: Node, inv: Invocation) {
    let child = Node(item.id * 4u + inv.thread + 1u, item.depth + 1u);
    if child.depth < fan_cfg[0] { enqueue_split(child); } else { enqueue_leaf(child); }
}";

/// Padding slots (`inv.live == false`) must not touch user memory.
const LEAF_WGSL: &str = "
fn leaf_execute(item: Node, inv: Invocation) {
    if !inv.live { return; }
    atomicAdd(&fan_out[0], 1u);
    atomicAdd(&fan_out[1], fan_hash(item.id));
}";

fn program() -> Result<Program, RunError> {
    let node = ItemType::new("Node", NODE_WGSL);
    let split = Procedure::new("split", node.clone(), FANOUT)
        .emits("split", FANOUT)
        .emits("leaf", FANOUT)
        .body(SPLIT_WGSL);
    let leaf = Procedure::new("leaf", node, 1).body(LEAF_WGSL);
    let user = UserBindings::storage(&user_wgsl(), &[(0, false), (1, true)]);
    Program::new(vec![split, leaf], user)
}

/// What the GPU must produce: items per procedure, leaves counted, wrapping sum of hashes.
#[derive(Debug, PartialEq)]
struct Expected {
    executed: Vec<u64>,
    leaves: u32,
    checksum: u32,
}

/// The same tree walked on the CPU.
fn reference() -> Expected {
    let mut e = Expected {
        executed: vec![0, 0],
        leaves: 0,
        checksum: 0,
    };
    let mut stack: Vec<Node> = (0..ROOTS).map(|id| Node { id, depth: 0 }).collect();
    while let Some(n) = stack.pop() {
        if n.depth < DEPTH {
            e.executed[0] += 1;
            for t in 0..FANOUT {
                let id = n.id.wrapping_mul(4).wrapping_add(t + 1);
                stack.push(Node {
                    id,
                    depth: n.depth + 1,
                });
            }
        } else {
            e.executed[1] += 1;
            e.leaves += 1;
            e.checksum = e.checksum.wrapping_add(lowbias32(n.id));
        }
    }
    e
}

/// Why the example failed.
#[derive(Debug)]
enum FanoutError {
    /// Setting up: the device, the program, a user buffer or a read-back.
    Run(RunError),
    /// Compiling or running the program for one strategy.
    Strategy(StrategyKind, RunError),
    /// The host twin [`Node`] has another size than the WGSL struct (its WGSL size, bytes).
    NodeSize(u32),
    /// A strategy's result differs from the CPU reference.
    Mismatch {
        strategy: StrategyKind,
        got: Expected,
        expected: Expected,
    },
}

impl fmt::Display for FanoutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FanoutError::Run(e) => write!(f, "{e}"),
            FanoutError::Strategy(kind, e) => write!(f, "{kind:?}: {e}"),
            FanoutError::NodeSize(size) => write!(f, "Node: WGSL size {size} != host size"),
            FanoutError::Mismatch {
                strategy,
                got,
                expected,
            } => write!(
                f,
                "{}: GPU {got:?} differs from the CPU reference {expected:?}",
                strategy.name()
            ),
        }
    }
}

impl std::error::Error for FanoutError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            FanoutError::Run(e) | FanoutError::Strategy(_, e) => Some(e),
            _ => None,
        }
    }
}

impl From<RunError> for FanoutError {
    fn from(e: RunError) -> Self {
        FanoutError::Run(e)
    }
}

/// Runs the tree on every strategy and checks each against the CPU reference; prints the
/// results and statistics when `print`.
fn run(print: bool) -> Result<(), FanoutError> {
    let mut gpu = Gpu::from_env()?;
    // SAFETY: the example's bodies have no loops, and the scheduler's own loops all end
    // (`Gpu::trust_loops`): naga's loop counter can go.
    #[allow(
        unsafe_code,
        reason = "Gpu::trust_loops: every loop of this device's shaders ends"
    )]
    unsafe {
        gpu.trust_loops()
    };
    let program = program()?;
    let layout = scheduler::wgsl::struct_layout(NODE_WGSL, "Node")?;
    if layout.size as usize != size_of::<Node>() {
        return Err(FanoutError::NodeSize(layout.size));
    }
    let expected = reference();
    let roots: Vec<Node> = (0..ROOTS).map(|id| Node { id, depth: 0 }).collect();
    let seeds = [Seed::new("split", &roots)];
    if print {
        println!(
            "adapter: {}; {ROOTS} roots, fan-out {FANOUT}, depth {DEPTH}: expecting {} split and {} leaf items",
            gpu.adapter_name(),
            expected.executed[0],
            expected.executed[1]
        );
    }
    for kind in StrategyKind::ALL {
        // Fresh user buffers per run: the counters start at zero.
        let out = gpu.storage_buffer("fanout out", 2)?;
        let cfg = gpu.upload("fanout cfg", &[DEPTH])?;
        let bind = program.user.bind_group(&gpu, &[&out, &cfg])?;
        let strategy = |e| FanoutError::Strategy(kind, e);
        let scheduler = Scheduler::new(&gpu, &program, kind, 1024).map_err(strategy)?;
        // The counters come back with the run: in the megakernel's and the device-driven
        // multi-pass's own last read-back, after the host-driven one's last round.
        let (stats, mut words) = scheduler
            .run_reading(&gpu, &seeds, Some(&bind), None, &[(&out, 0, 2)])
            .map_err(strategy)?;
        let words = words.pop().expect("one range read");
        let got = Expected {
            executed: stats.executed.clone(),
            leaves: words[0],
            checksum: words[1],
        };
        if print {
            println!(
                "{:<15} leaves {} checksum {:#010x} | executed {:?}, launches {}, submits {}, \
                 rounds {}, growths {}, queue bytes {}, wall {:.1} ms, gpu {}",
                kind.name(),
                got.leaves,
                got.checksum,
                stats.executed,
                stats.launches,
                stats.submits,
                stats.rounds,
                stats.queue_growths,
                stats.queue_bytes,
                stats.wall_ms,
                stats
                    .gpu_ms
                    .map_or("n/a".to_string(), |ms| format!("{ms:.2} ms"))
            );
        }
        if got != expected {
            return Err(FanoutError::Mismatch {
                strategy: kind,
                got,
                expected,
            });
        }
    }
    if print {
        println!("every strategy matches the CPU reference");
    }
    Ok(())
}

fn main() -> ExitCode {
    match run(true) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fanout: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `cargo test` runs the example (its `[[example]]` entry has `test = true`), so CI checks it.
#[test]
fn fanout_matches_the_cpu_reference_on_every_strategy() {
    run(false).unwrap();
}
