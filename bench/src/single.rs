//! `schedbench --workload W`: one workload at one size under the chosen strategies; one JSON
//! object per run (`--json`) or a table of median ± MAD with the ratios between strategies.

use crate::catalog::WorkloadName;
use crate::cli::Cli;
use crate::error::Error;
use crate::record::RunRecord;
use crate::reyes_frames::{ReyesWorkload, load_scene, load_shared_scene};
use crate::strategy::Strategy;
use crate::suite::measure;
use crate::summary::{best_baseline, cells};
use crate::workload::Workload;
use clap::error::ErrorKind;
use reyes::scene;
use scheduler::{Gpu, StrategyKind};
use std::path::Path;

/// Timed runs when `--runs` is not given.
pub const DEFAULT_RUNS: u32 = 5;
/// Mandelbrot's image side when `--size-px` is not given (an exact view).
pub const DEFAULT_SIZE_PX: u32 = 1024;
/// BFS's R-MAT scale when `--scale` is not given.
pub const DEFAULT_SCALE: u32 = 20;

/// The workload the command line describes; usage errors exit with status 2, a scene file
/// that cannot be read or parsed is an error (status 1, naming the file and line).
fn workload(cli: &Cli) -> Result<Box<dyn Workload>, Error> {
    let config = cli.gpu_config();
    match cli.workload.unwrap_or(WorkloadName::Tree) {
        WorkloadName::Tree => Ok(Box::new(crate::tree::single_workload(cli.tree(), config))),
        WorkloadName::Reyes => {
            let scene = match cli.scene.as_str() {
                "teapot" => scene::builtin_teapot(),
                "killeroo" => load_shared_scene("rib/killeroo.rib")?,
                path => load_scene(Path::new(path))?,
            };
            let size = match (cli.width, cli.height) {
                (None, None) => None,
                (w, h) => Some((w.unwrap_or(scene.width), h.unwrap_or(scene.height))),
            };
            let name = format!("reyes-{}", cli.scene);
            Ok(Box::new(ReyesWorkload::new(
                name,
                scene,
                vec![size],
                config,
            )))
        }
        WorkloadName::Mandelbrot => Ok(Box::new(crate::mandelbrot::single_workload(
            cli.size_px.unwrap_or(DEFAULT_SIZE_PX),
            config,
        ))),
        WorkloadName::Bfs => Ok(Box::new(
            crate::bfs::single_workload(cli.scale.unwrap_or(DEFAULT_SCALE), config).unwrap_or_else(
                |e| Cli::usage_error(ErrorKind::InvalidValue, format!("--scale: {e}")),
            ),
        )),
    }
}

/// The strategies `--strategy` names among the workload's: one name, `all`, or a
/// comma-separated list of them (each strategy once, in the order named).
fn strategies(cli: &Cli, w: &dyn Workload) -> Vec<Strategy> {
    let all = w.strategies();
    let wanted = |s: &Strategy| s.policy().is_none_or(|p| p == cli.policy);
    let mut out: Vec<Strategy> = Vec::new();
    for s in cli.strategy.split(',').map(str::trim) {
        let found = match s {
            "all" => all.iter().filter(|x| wanted(x)).cloned().collect(),
            s if s == StrategyKind::Megakernel.name() => all
                .iter()
                .find(|x| x.is_megakernel() && wanted(x))
                .cloned()
                .into_iter()
                .collect(),
            s => Strategy::find(&all, s).into_iter().collect::<Vec<_>>(),
        };
        if found.is_empty() {
            let mut names: Vec<String> = all.iter().map(|s| s.name()).collect();
            let floor = StrategyKind::MultipassFloor.name();
            if Strategy::find(&all, floor).is_some() {
                names.push(floor.into());
            }
            Cli::usage_error(
                ErrorKind::InvalidValue,
                format!(
                    "--strategy: unknown strategy `{s}` for {} (known: all, {})",
                    w.name(),
                    names.join(", ")
                ),
            )
        }
        for x in found {
            if !out.contains(&x) {
                out.push(x);
            }
        }
    }
    out
}

/// Runs and prints; Ok(true) when every run was verified.
pub fn run(cli: &Cli) -> Result<bool, Error> {
    let mut w = workload(cli)?;
    let strategies = strategies(cli, w.as_ref());
    let gpu = crate::open_gpu(cli.workload == Some(WorkloadName::Reyes))?;
    let prepared = w.prepare(&gpu, 0)?;
    let runs = cli.runs.unwrap_or(DEFAULT_RUNS);
    let mut records: Vec<RunRecord> = Vec::new();
    for s in &strategies {
        for r in measure(&gpu, w.as_mut(), s, &prepared, runs) {
            if cli.json {
                reyes_cli::outln!("{}", serde_json::to_string(&r).expect("records serialise"));
            }
            if let Some(e) = r.error.as_ref().filter(|_| !r.verified) {
                log::error!("{} run {}: {e}", r.strategy, r.run);
            }
            records.push(r);
        }
    }
    if !cli.json {
        print_table(&gpu, &prepared.params, prepared.problem_items, &records);
    }
    Ok(records.iter().all(|r| r.verified))
}

/// `x` with `digits` significant digits and no exponent (a CPU adapter's 0.000514 G items/s
/// stays readable beside a GPU's 4.91).
fn significant(x: f64, digits: i32) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let decimals = (digits - 1 - x.abs().log10().floor() as i32).max(0);
    format!("{x:.*}", decimals as usize)
}

fn print_table(gpu: &Gpu, params: &str, problem_items: u64, records: &[RunRecord]) {
    let Some((workload, cs)) = cells(records).into_iter().next() else {
        return;
    };
    reyes_cli::outln!(
        "adapter: {} (wgpu's indirect-call validation {})\nworkload: {workload} {params}\n\
         reference: {problem_items} items",
        gpu.adapter_name(),
        if scheduler::gpu::indirect_validation() {
            "on"
        } else {
            "off"
        }
    );
    reyes_cli::outln!(
        "{:<16} {:>10} {:>8} {:>20} {:>20} {:>11} {:>8} {:>7}",
        "strategy",
        "items",
        "verified",
        "gpu ms (med ± MAD)",
        "wall ms (med ± MAD)",
        "G items/s",
        "launch",
        "rounds"
    );
    let fmt = |t: Option<(f64, f64)>| t.map_or("n/a".into(), |(m, d)| format!("{m:.3} ± {d:.3}"));
    for c in &cs {
        reyes_cli::outln!(
            "{:<16} {:>10} {:>8} {:>20} {:>20} {:>11} {:>8} {:>7}",
            c.strategy,
            c.items,
            c.ok(),
            fmt(c.gpu),
            fmt(c.wall),
            // Per GPU ms; runs without GPU time (the CPU's) per wall ms.
            c.gpu
                .or(c.wall)
                .map_or("n/a".into(), |g| significant(c.items as f64 / g.0 / 1e6, 3)),
            c.launches,
            c.rounds
        );
    }
    // What each scheduler strategy ran with (item layout, the megakernel's enqueue and
    // workgroup size).
    let mut queues: Vec<String> = Vec::new();
    for r in records {
        if let Some(l) = &r.item_layout {
            let e = r
                .enqueue
                .as_ref()
                .map_or(String::new(), |e| format!(", {e} enqueue"));
            let w = r
                .workgroup_size
                .map_or(String::new(), |w| format!(", {w} threads per workgroup"));
            let local = match (r.local_queues, r.local_workgroup_bytes) {
                (Some(true), Some(b)) => format!(", local queues ({b} bytes of workgroup memory)"),
                (Some(true), None) => ", local queues".into(),
                _ => String::new(),
            };
            let guided = match r.guided_claims {
                Some(true) => ", guided claims",
                _ => "",
            };
            let order = r
                .queue_order
                .as_ref()
                .map_or(String::new(), |o| format!(", queue order {}", o.join(",")));
            let rounds = r
                .round_dispatch
                .as_ref()
                .map_or(String::new(), |d| format!(", {d} rounds"));
            let cap = r.max_workgroups.map_or(String::new(), |n| {
                format!(", at most {n} workgroups a procedure")
            });
            let share = r.probed_workgroups.map_or(String::new(), |p| {
                format!(", {} of {p} co-resident workgroups", r.workgroups)
            });
            let line = format!(
                "{}: {l} items{e}{w}{share}{local}{guided}{order}{rounds}{cap}",
                r.strategy
            );
            if !queues.contains(&line) {
                queues.push(line);
            }
        }
    }
    if !queues.is_empty() {
        reyes_cli::outln!("queues: {}", queues.join("; "));
    }
    reyes_cli::outln!(
        "G items/s: items per GPU time; for runs without GPU time (cpu), per wall time"
    );
    // GPU time against the first strategy's (the megakernel's when it ran), as before.
    let gpu_timed: Vec<_> = cs.iter().filter_map(|c| c.gpu.map(|g| (c, g.0))).collect();
    if let Some(((first, a), rest)) = gpu_timed.split_first() {
        for (c, b) in rest {
            reyes_cli::outln!(
                "ratio {}/{} GPU time: {:.2}x (medians of this invocation)",
                c.strategy,
                first.strategy,
                b / a
            );
        }
    }
    print_turn_anatomy(records);
    let refs: Vec<_> = cs.iter().collect();
    if let Some(best) = best_baseline(&refs) {
        for c in cs.iter().filter(|c| c.megakernel) {
            if let Some(w) = c.wall {
                reyes_cli::outln!(
                    "{} wall time / best baseline ({}): {:.2}x",
                    c.strategy,
                    best.strategy,
                    w.0 / best.wall.unwrap().0
                );
            }
        }
    }
}

/// `--turn-anatomy`: per megakernel strategy, the table of its run with the median GPU time
/// (wall time without one).
fn print_turn_anatomy(records: &[RunRecord]) {
    let mut names: Vec<&str> = Vec::new();
    for r in records.iter().filter(|r| !r.turn_anatomy.is_empty()) {
        if !names.contains(&r.strategy.as_str()) {
            names.push(&r.strategy);
        }
    }
    for name in names {
        let mut runs: Vec<&RunRecord> = records
            .iter()
            .filter(|r| r.strategy == name && !r.turn_anatomy.is_empty())
            .collect();
        runs.sort_by(|a, b| {
            let t = |r: &RunRecord| r.gpu_ms.or(r.wall_ms).unwrap_or(0.0);
            t(a).total_cmp(&t(b))
        });
        let r = runs[runs.len() / 2];
        let pairs = r.turn_anatomy.iter().map(|(n, c)| (n.as_str(), *c));
        if let Some(a) = scheduler::megakernel::anatomy::TurnAnatomy::from_named(pairs) {
            reyes_cli::outln!("{name}, run {} (median time):", r.run);
            reyes_cli::out!("{}", a.table(r.batches, r.workgroups, r.gpu_ms));
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn rates_keep_three_significant_digits() {
        assert_eq!(super::significant(4.9112, 3), "4.91");
        assert_eq!(super::significant(0.000514, 3), "0.000514");
        assert_eq!(super::significant(123.4, 3), "123");
        assert_eq!(super::significant(0.0, 3), "0");
    }
}
