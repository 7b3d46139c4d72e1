//! `schedbench`: runs a workload under one or every scheduling strategy on the same input,
//! checks every run against the CPU reference, and prints one JSON object per run (`--json`) or a
//! table of medians with their spread.
//!
//! cargo run --release --bin schedbench -- --workload tree --strategy all --runs 10

use std::process::ExitCode;

use scheduler::workloads::tree::{Fanout, TreeParams, TreeRun};
use scheduler::*;
use serde_json::json;

const USAGE: &str = "usage: schedbench [--workload tree] [--strategy megakernel|multipass|all]
  [--json] [--runs N] [--roots N] [--depth N] [--fanout fixed:K|uniform:K] [--work N]
  [--payload WORDS] [--seed N] [--workgroups N] [--policy priority|fifo] [--batch-steps N]
  [--capacity SLOTS]";

struct Options {
    strategies: Vec<StrategyKind>,
    json: bool,
    runs: usize,
    tree: TreeParams,
    workgroups: Option<u32>,
    policy: QueuePolicy,
    batch_steps: u32,
    capacity: u32,
}

fn parse() -> Result<Options, String> {
    let mut o = Options {
        strategies: StrategyKind::ALL.to_vec(),
        json: false,
        runs: 5,
        tree: TreeParams::binary_benchmark(),
        workgroups: None,
        policy: QueuePolicy::Priority(Vec::new()),
        batch_steps: 1,
        capacity: 1 << 22,
    };
    let mut args = std::env::args().skip(1);
    let num = |v: Option<String>, name: &str| -> Result<u32, String> {
        v.ok_or(format!("{name} needs a value"))?
            .parse()
            .map_err(|e| format!("{name}: {e}"))
    };
    while let Some(a) = args.next() {
        match a.as_str() {
            "--workload" => {
                let w = args.next().unwrap_or_default();
                if w != "tree" {
                    return Err(format!("unknown workload `{w}` (known: tree)"));
                }
            }
            "--strategy" => {
                let s = args.next().unwrap_or_default();
                o.strategies = if s == "all" {
                    StrategyKind::ALL.to_vec()
                } else {
                    vec![StrategyKind::parse(&s).ok_or(format!("unknown strategy `{s}`"))?]
                };
            }
            "--json" => o.json = true,
            "--runs" => o.runs = num(args.next(), "--runs")?.max(1) as usize,
            "--roots" => o.tree.roots = num(args.next(), "--roots")?,
            "--depth" => o.tree.max_depth = num(args.next(), "--depth")?,
            "--work" => o.tree.work = num(args.next(), "--work")?,
            "--payload" => o.tree.payload_words = num(args.next(), "--payload")?,
            "--seed" => o.tree.seed = num(args.next(), "--seed")?,
            "--workgroups" => o.workgroups = Some(num(args.next(), "--workgroups")?),
            "--batch-steps" => o.batch_steps = num(args.next(), "--batch-steps")?,
            "--capacity" => o.capacity = num(args.next(), "--capacity")?,
            "--policy" => {
                o.policy = match args.next().as_deref() {
                    Some("priority") => QueuePolicy::Priority(Vec::new()),
                    Some("fifo") => QueuePolicy::Fifo,
                    other => return Err(format!("unknown policy {other:?}")),
                }
            }
            "--fanout" => {
                let f = args.next().unwrap_or_default();
                let (kind, k) = f.split_once(':').ok_or(format!("bad fanout `{f}`"))?;
                let k: u32 = k
                    .trim_start_matches("0..")
                    .parse()
                    .map_err(|e| format!("fanout: {e}"))?;
                o.tree.fanout = match kind {
                    "fixed" => Fanout::Fixed(k),
                    "uniform" => Fanout::Uniform(k),
                    _ => return Err(format!("bad fanout `{f}`")),
                };
            }
            "--help" | "-h" => return Err(USAGE.into()),
            other => return Err(format!("unknown argument `{other}`\n{USAGE}")),
        }
    }
    Ok(o)
}

fn main() -> ExitCode {
    let o = match parse() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    match run(&o) {
        Ok(all_verified) if all_verified => ExitCode::SUCCESS,
        Ok(_) => {
            eprintln!("schedbench: some run did not match the CPU reference");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("schedbench: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(o: &Options) -> Result<bool, RunError> {
    let gpu = Gpu::from_env()?;
    let adapter = gpu.adapter_name();
    let reference = o.tree.reference();
    let tree = TreeRun::new(&gpu, o.tree.clone())?;
    let mut all_verified = true;
    let mut table = Vec::new();
    for &kind in &o.strategies {
        let scheduler = match kind {
            StrategyKind::Megakernel => Scheduler::megakernel(
                &gpu,
                &tree.program,
                MegakernelConfig {
                    workgroups: o
                        .workgroups
                        .map_or(Workgroups::Probe { max: 4096 }, Workgroups::Fixed),
                    policy: o.policy.clone(),
                    batch_steps: o.batch_steps,
                    initial_capacity: o.capacity,
                    ..Default::default()
                },
            )?,
            StrategyKind::Multipass => Scheduler::multipass(
                &gpu,
                &tree.program,
                MultipassConfig {
                    initial_capacity: o.capacity,
                    ..Default::default()
                },
            )?,
            StrategyKind::MultipassHost => Scheduler::multipass_host(
                &gpu,
                &tree.program,
                HostMultipassConfig {
                    initial_capacity: o.capacity,
                    ..Default::default()
                },
            )?,
        };
        tree.run(&gpu, &scheduler)?; // warm-up: first-use costs are not the strategy's
        scheduler::clocks::raise_clocks(&gpu, std::time::Duration::from_millis(500))?;
        let (mut gpu_ms, mut wall_ms) = (Vec::new(), Vec::new());
        let mut last = None;
        for run in 0..o.runs {
            let (stats, result) = tree.run(&gpu, &scheduler)?;
            let verified = result == reference;
            all_verified &= verified;
            if o.json {
                println!(
                    "{}",
                    json!({
                        "workload": "tree",
                        "strategy": kind.name(),
                        "adapter": adapter,
                        "params": o.tree.describe(),
                        "run": run,
                        "items": stats.items(),
                        "verified": verified,
                        "gpu_ms": stats.gpu_ms,
                        "wall_ms": stats.wall_ms,
                        "items_per_s": stats.gpu_ms.map(|g| stats.items() as f64 / g * 1e3),
                        "executed": stats.executed,
                        "launches": stats.launches,
                        "rounds": stats.rounds,
                        "batches": stats.batches,
                        "idle_polls": stats.idle_polls,
                        "abandoned": stats.abandoned,
                        "queue_growths": stats.queue_growths,
                        "peak_occupancy": stats.peak_occupancy,
                        "queue_bytes": stats.queue_bytes,
                        "workgroups": stats.workgroups,
                    })
                );
            }
            if let Some(g) = stats.gpu_ms {
                gpu_ms.push(g);
            }
            wall_ms.push(stats.wall_ms);
            last = Some((stats, verified));
        }
        let (stats, verified) = last.expect("at least one run");
        table.push((kind, stats, verified, gpu_ms, wall_ms));
    }
    if !o.json {
        println!(
            "adapter: {adapter}\nworkload: tree {}\nreference: {reference:?}",
            o.tree.describe()
        );
        println!(
            "{:<11} {:>10} {:>8} {:>20} {:>20} {:>11} {:>8} {:>7}",
            "strategy",
            "items",
            "ok",
            "gpu ms (med ± MAD)",
            "wall ms (med ± MAD)",
            "G items/s",
            "launch",
            "rounds"
        );
        let mut gpu_medians = Vec::new();
        for (kind, s, verified, g, w) in &table {
            let (wm, wd) = scheduler::stats::median_and_mad(&w);
            let (gcol, rate) = if g.is_empty() {
                ("n/a".to_string(), "n/a".to_string())
            } else {
                let (gm, gd) = scheduler::stats::median_and_mad(&g);
                gpu_medians.push((kind.name(), gm));
                (
                    format!("{gm:.3} ± {gd:.3}"),
                    format!("{:.2}", s.items() as f64 / gm / 1e6),
                )
            };
            println!(
                "{:<11} {:>10} {:>8} {:>20} {:>20} {:>11} {:>8} {:>7}",
                kind.name(),
                s.items(),
                verified,
                gcol,
                format!("{wm:.3} ± {wd:.3}"),
                rate,
                s.launches,
                s.rounds
            );
        }
        if let [(a, ga), (b, gb)] = gpu_medians[..] {
            println!("ratio {b}/{a} GPU time: {:.2}x (same run)", gb / ga);
        }
    }
    Ok(all_verified)
}
