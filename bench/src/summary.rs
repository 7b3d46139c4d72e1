//! `summary.md`: per workload a table of median ± MAD per strategy and size, each strategy's
//! wall time against the best baseline's (the fastest verified strategy that is not the
//! megakernel, measured in the same invocation), and, where the megakernel is not at least
//! [`AIM`] times faster than that baseline on a size whose multi-pass needs at least
//! [`MANY_ROUNDS`] rounds, a line saying why from its statistics.

use crate::record::RunRecord;
use crate::scale::Scale;
use scheduler::stats::median_and_mad;
use std::fmt::Write as _;

/// The speed-up over the best baseline the megakernel is expected to reach on deep work.
pub const AIM: f64 = 1.5;
/// Multi-pass rounds from which a workload counts as deep enough for [`AIM`] to apply.
pub const MANY_ROUNDS: f64 = 10.0;
/// Threads of a scheduler workgroup (every kernel has 256).
const THREADS: f64 = 256.0;

/// What a summary says about the invocation.
pub struct Header {
    pub adapter: String,
    pub scale: Scale,
    pub runs: u32,
    pub command: String,
    pub seconds: f64,
    /// The adapter is a CPU (lavapipe): "GPU" strategies share the baseline's cores.
    pub cpu_adapter: bool,
    /// Workloads this branch does not have.
    pub not_built: Vec<&'static str>,
}

/// The runs of one (workload, size, strategy): medians over its verified runs.
#[derive(Debug, Clone)]
pub struct Cell {
    pub strategy: String,
    pub megakernel: bool,
    pub size: String,
    pub params: String,
    pub problem_items: u64,
    pub items: u64,
    pub runs: usize,
    pub verified: usize,
    pub error: Option<String>,
    /// Median and MAD, ms.
    pub wall: Option<(f64, f64)>,
    pub gpu: Option<(f64, f64)>,
    /// Medians of the scheduler's counters.
    pub rounds: f64,
    pub launches: f64,
    pub batches: f64,
    pub idle_polls: f64,
    pub abandoned: f64,
    pub queue_growths: f64,
    /// Most items waiting at once, all queues together.
    pub peak_occupancy: f64,
    pub workgroups: u32,
}

impl Cell {
    /// Every run verified (and there was one).
    pub fn ok(&self) -> bool {
        self.runs > 0 && self.verified == self.runs
    }
}

fn median(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.collect();
    if v.is_empty() {
        0.0
    } else {
        median_and_mad(&v).0
    }
}

/// Groups records into cells, per workload, in the order they were run.
pub fn cells(records: &[RunRecord]) -> Vec<(String, Vec<Cell>)> {
    let mut out: Vec<(String, Vec<Cell>)> = Vec::new();
    let mut keys: Vec<(String, String, String)> = Vec::new();
    for r in records {
        let k = (r.workload.clone(), r.size.clone(), r.strategy.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    for (workload, size, strategy) in keys {
        let rs: Vec<&RunRecord> = records
            .iter()
            .filter(|r| r.workload == workload && r.size == size && r.strategy == strategy)
            .collect();
        let good: Vec<&&RunRecord> = rs.iter().filter(|r| r.verified).collect();
        let times = |f: fn(&RunRecord) -> Option<f64>| {
            let v: Vec<f64> = good.iter().filter_map(|r| f(r)).collect();
            (!v.is_empty()).then(|| median_and_mad(&v))
        };
        let counter = |f: fn(&RunRecord) -> f64| median(good.iter().map(|r| f(r)));
        let cell = Cell {
            strategy,
            megakernel: rs[0].policy.is_some(),
            size,
            params: rs[0].params.clone(),
            problem_items: rs[0].problem_items,
            items: good.first().map_or(0, |r| r.items),
            runs: rs.len(),
            verified: good.len(),
            error: rs
                .iter()
                .find_map(|r| r.error.clone().filter(|_| !r.verified)),
            wall: times(|r| r.wall_ms),
            gpu: times(|r| r.gpu_ms),
            rounds: counter(|r| r.rounds as f64),
            launches: counter(|r| r.launches as f64),
            batches: counter(|r| r.batches as f64),
            idle_polls: counter(|r| r.idle_polls as f64),
            abandoned: counter(|r| r.abandoned as f64),
            queue_growths: counter(|r| r.queue_growths as f64),
            peak_occupancy: counter(|r| r.peak_occupancy.iter().sum::<u64>() as f64),
            workgroups: good.iter().map(|r| r.workgroups).max().unwrap_or(0),
        };
        match out.iter_mut().find(|(w, _)| *w == workload) {
            Some((_, v)) => v.push(cell),
            None => out.push((workload, vec![cell])),
        }
    }
    out
}

/// The best baseline of one size: the verified non-megakernel cell with the least median
/// wall time (never the multi-pass floor, a reference no user would run).
pub fn best_baseline<'a>(size_cells: &[&'a Cell]) -> Option<&'a Cell> {
    size_cells
        .iter()
        .filter(|c| !c.megakernel && c.ok() && c.wall.is_some())
        .filter(|c| c.strategy != scheduler::StrategyKind::MultipassFloor.name())
        .min_by(|a, b| a.wall.unwrap().0.total_cmp(&b.wall.unwrap().0))
        .copied()
}

fn ms(t: Option<(f64, f64)>) -> String {
    match t {
        Some((m, d)) => format!("{m:.3} ± {d:.3}"),
        None => "n/a".into(),
    }
}

/// Three significant digits (at least two decimals).
fn significant(x: f64) -> String {
    let decimals = if x > 0.0 {
        (2 - x.log10().floor() as i32).max(2) as usize
    } else {
        2
    };
    format!("{x:.decimals$}")
}

fn count(x: f64) -> String {
    if x.fract() == 0.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.1}")
    }
}

/// Why a megakernel cell is not [`AIM`] times faster than the best baseline, from its counters.
pub fn why(mk: &Cell, best: &Cell, multipass: Option<&Cell>, cpu_adapter: bool) -> String {
    let (mk_ms, best_ms) = (mk.wall.unwrap().0, best.wall.unwrap().0);
    let threads = mk.workgroups as f64 * THREADS;
    let mut s = format!(
        "**{} at {}**: {:.2}x the speed of {} ({mk_ms:.3} against {best_ms:.3} ms wall), \
         short of {AIM}x",
        mk.strategy,
        mk.size,
        best_ms / mk_ms,
        best.strategy
    );
    if let Some(mp) = multipass {
        let _ = write!(
            s,
            "; the device-driven multi-pass needed {} rounds",
            count(mp.rounds)
        );
        if let (Some(a), Some(b)) = (mk.gpu, mp.gpu) {
            let _ = write!(
                s,
                ", its GPU time {:.3} ms against the megakernel's {:.3} ms",
                b.0, a.0
            );
            // The best baseline's GPU time too, when it is another GPU strategy.
            if let Some(g) = best.gpu.filter(|_| best.strategy != mp.strategy) {
                let _ = write!(s, " ({}'s {:.3} ms)", best.strategy, g.0);
            }
        }
    }
    let _ = write!(
        s,
        ". Megakernel: {} launches of {} workgroups, {} batches, {} idle polls ({:.2} per batch), \
         peak queue occupancy {} items ({:.2} per thread of a launch), {} abandoned slots, \
         {} queue growths.",
        count(mk.launches),
        mk.workgroups,
        count(mk.batches),
        count(mk.idle_polls),
        mk.idle_polls / mk.batches.max(1.0),
        count(mk.peak_occupancy),
        mk.peak_occupancy / threads.max(1.0),
        count(mk.abandoned),
        count(mk.queue_growths)
    );
    let mut reasons = Vec::new();
    if mk.idle_polls > mk.batches {
        reasons.push(
            "workgroups spent more loop turns finding nothing to claim than running batches: \
             the work arrives too slowly (or too narrowly) to keep the launch busy"
                .to_string(),
        );
    }
    if threads > 0.0 && mk.peak_occupancy < threads {
        reasons.push(format!(
            "the queues never held more items than the launch has threads ({} < {}): \
             the GPU was underfilled",
            count(mk.peak_occupancy),
            threads
        ));
    }
    if mk.launches > 1.0 {
        reasons.push(format!(
            "{} launches, each ending at its loop bound or when a queue had to grow, and each \
             a host round trip with compaction",
            count(mk.launches)
        ));
    }
    if mk.abandoned > 0.0 {
        reasons.push(
            "slots were abandoned after bounded waits (producers not running: more workgroups \
             than run at once)"
                .to_string(),
        );
    }
    if !best.megakernel && best.gpu.is_none() && best_ms < 5.0 {
        reasons.push(format!(
            "the {} finishes in {best_ms:.3} ms: too little work to pay for a GPU submission \
             and read-back",
            best.strategy
        ));
    }
    if cpu_adapter {
        reasons.push(
            "the adapter is a CPU (lavapipe): the GPU strategies run emulated on the same cores \
             as the CPU implementation"
                .to_string(),
        );
    }
    if reasons.is_empty() {
        reasons.push(
            "no scheduling overhead stands out in the counters: the megakernel's cost per item \
             (queue atomics per batch, outbox copies) is above the baseline's"
                .to_string(),
        );
    }
    let _ = write!(s, " Why: {}.", reasons.join("; "));
    s
}

/// The whole summary.
pub fn markdown(h: &Header, records: &[RunRecord]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# schedbench suite\n");
    let _ = writeln!(
        s,
        "Adapter: {}. Scale: {}, {} timed runs per strategy and size after one untimed \
         warm-up run; {} runs in {:.0} s. Command: `{}`.\n",
        h.adapter,
        h.scale.name(),
        h.runs,
        records.len(),
        h.seconds,
        h.command
    );
    if !h.not_built.is_empty() {
        let _ = writeln!(
            s,
            "Not in this build: {} (their code is not in this branch).\n",
            h.not_built.join(", ")
        );
    }
    let _ = writeln!(
        s,
        "Times are median ± MAD over the verified runs. *wall* is host time of a whole run \
         (uploads, submissions, waits and the result's read-back), the one clock every \
         strategy has, so the ratios use it; *GPU* is timestamp time of the scheduler's passes \
         (Reyes: plus resolve). *× best* is a strategy's median wall time over the best \
         baseline's: the fastest verified strategy other than the megakernel (multi-pass, \
         `cpu` = the workload's multi-threaded CPU implementation, or the workload's own \
         baseline) at the same size in this invocation; below 1 is faster. `megakernel` uses \
         the priority queue policy (the default; each record's `queue_order` gives its order), \
         `megakernel-fifo` the FIFO one. Reyes' `cpu` \
         is its CPU twin `reyes::cpu_render`, one thread.\n"
    );
    let all = cells(records);
    let failed: usize = all.iter().flat_map(|(_, c)| c).filter(|c| !c.ok()).count();
    if failed > 0 {
        let _ = writeln!(
            s,
            "**{failed} strategy and size combinations had runs that failed or were not \
             verified; their times are left out.**\n"
        );
    }
    for (workload, cs) in &all {
        let _ = writeln!(s, "## {workload}\n");
        let mut sizes: Vec<&str> = Vec::new();
        for c in cs {
            if !sizes.contains(&c.size.as_str()) {
                sizes.push(&c.size);
            }
        }
        for size in &sizes {
            let c = cs.iter().find(|c| c.size == *size).unwrap();
            let _ = writeln!(s, "- {size}: {} ({} items)", c.params, c.problem_items);
        }
        let _ = writeln!(
            s,
            "\n| size | strategy | verified | wall ms | GPU ms | M items/s (wall) | × best | \
             rounds | launches | idle polls | peak queue |"
        );
        let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
        let mut whys = Vec::new();
        for size in &sizes {
            let here: Vec<&Cell> = cs.iter().filter(|c| c.size == *size).collect();
            let best = best_baseline(&here);
            for c in &here {
                let ratio = match (best, c.wall) {
                    (Some(b), Some(_)) if std::ptr::eq(*c, b) => "1 (best)".to_string(),
                    (Some(b), Some(w)) => format!("{:.2}", w.0 / b.wall.unwrap().0),
                    _ => "n/a".into(),
                };
                let rate = c
                    .wall
                    .map_or("n/a".into(), |w| significant(c.items as f64 / w.0 / 1e3));
                let _ = writeln!(
                    s,
                    "| {} | {} | {}{}/{} | {} | {} | {} | {} | {} | {} | {} | {} |",
                    c.size,
                    c.strategy,
                    if c.ok() { "" } else { "**no** " },
                    c.verified,
                    c.runs,
                    ms(c.wall),
                    ms(c.gpu),
                    rate,
                    ratio,
                    count(c.rounds),
                    count(c.launches),
                    count(c.idle_polls),
                    count(c.peak_occupancy)
                );
            }
            let multipass = here.iter().find(|c| c.strategy == "multipass").copied();
            let deep = multipass.is_some_and(|m| m.ok() && m.rounds >= MANY_ROUNDS);
            if let (Some(b), true) = (best, deep) {
                for mk in here.iter().filter(|c| c.megakernel && c.ok()) {
                    if let Some(w) = mk.wall
                        && b.wall.unwrap().0 / w.0 < AIM
                    {
                        whys.push(why(mk, b, multipass, h.cpu_adapter));
                    }
                }
            }
        }
        for c in cs.iter().filter(|c| !c.ok()) {
            let _ = writeln!(
                s,
                "\n**{} at {}**: {}",
                c.strategy,
                c.size,
                c.error.as_deref().unwrap_or("no runs")
            );
        }
        if !whys.is_empty() {
            let _ = writeln!(
                s,
                "\nWhere the megakernel is not {AIM}x faster than the best baseline (multi-pass \
                 needs ≥ {MANY_ROUNDS} rounds):\n"
            );
            for w in whys {
                let _ = writeln!(s, "- {w}");
            }
        }
        let _ = writeln!(s, "\n![{workload}]({})\n", plot_file_name(workload));
    }
    s
}

/// The file name of a workload's plot (`plot.rs` draws it, the summary links it).
pub fn plot_file_name(workload: &str) -> String {
    format!("{workload}.png")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(strategy: &str, mk: bool, wall: f64, rounds: u64, verified: bool) -> RunRecord {
        RunRecord {
            workload: "tree-binary".into(),
            strategy: strategy.into(),
            policy: mk.then(|| "priority".into()),
            size: "roots=1".into(),
            params: "p".into(),
            item_layout: None,
            enqueue: None,
            workgroup_size: None,
            adapter: "a".into(),
            run: 0,
            items: 1000,
            problem_items: 1000,
            verified,
            error: (!verified).then(|| "wrong".into()),
            gpu_ms: None,
            wall_ms: Some(wall),
            items_per_s: None,
            items_per_s_wall: None,
            gteps: None,
            executed: vec![],
            rounds,
            launches: if mk { 3 } else { 0 },
            batches: 10,
            local_items: 0,
            local_queues: None,
            local_workgroup_bytes: None,
            guided_claims: None,
            queue_order: None,
            indirect_validation: None,
            round_dispatch: None,
            max_workgroups: None,
            spin_wait_us: 0,
            idle_polls: 50,
            abandoned: 0,
            flags_cleared: None,
            queue_growths: 0,
            partial_rounds: 0,
            parked_items: 0,
            peak_occupancy: vec![100],
            queue_bytes: 0,
            workgroups: if mk { 4 } else { 0 },
            probed_workgroups: None,
            turn_anatomy: Vec::new(),
        }
    }

    #[test]
    fn the_best_baseline_is_the_fastest_verified_non_megakernel() {
        let records = vec![
            rec("megakernel", true, 1.0, 0, true),
            rec("multipass", false, 4.0, 15, true),
            rec("cpu", false, 2.0, 0, true),
            rec("frontier", false, 0.5, 0, false),
        ];
        let all = cells(&records);
        let here: Vec<&Cell> = all[0].1.iter().collect();
        assert_eq!(best_baseline(&here).unwrap().strategy, "cpu");
        let md = markdown(
            &Header {
                adapter: "a".into(),
                scale: Scale::Small,
                runs: 1,
                command: "c".into(),
                seconds: 1.0,
                cpu_adapter: false,
                not_built: vec![],
            },
            &records,
        );
        assert!(md.contains("| roots=1 | cpu | 1/1 | 2.000 ± 0.000 | n/a | 0.500 | 1 (best) |"));
        assert!(md.contains("| roots=1 | megakernel | 1/1 | 1.000 ± 0.000 | n/a | 1.00 | 0.50 |"));
        assert!(md.contains("**frontier at roots=1**: wrong"));
        // 2x faster than the best baseline: no explanation owed.
        assert!(!md.contains("short of"));
    }

    #[test]
    fn the_best_baselines_gpu_time_is_named_beside_the_device_driven_ones() {
        let timed = |strategy: &str, mk: bool, wall: f64, rounds: u64, gpu: f64| RunRecord {
            gpu_ms: Some(gpu),
            ..rec(strategy, mk, wall, rounds, true)
        };
        let records = vec![
            timed("megakernel", true, 3.0, 0, 1.0),
            timed("multipass", false, 4.0, 15, 2.0),
            timed("multipass-host", false, 2.5, 15, 0.9),
        ];
        let all = cells(&records);
        let here: Vec<&Cell> = all[0].1.iter().collect();
        let text = why(here[0], here[2], Some(here[1]), false);
        assert!(
            text.contains("its GPU time 2.000 ms against the megakernel's 1.000 ms (multipass-host's 0.900 ms)"),
            "{text}"
        );
        // Where the best baseline is the device-driven one, it is not named twice.
        let text = why(here[0], here[1], Some(here[1]), false);
        assert!(!text.contains("'s 2.000"), "{text}");
    }

    #[test]
    fn a_slow_megakernel_on_deep_work_is_explained_from_its_counters() {
        let records = vec![
            rec("megakernel", true, 3.0, 0, true),
            rec("multipass", false, 4.0, 15, true),
            rec("cpu", false, 2.0, 0, true),
        ];
        let all = cells(&records);
        let here: Vec<&Cell> = all[0].1.iter().collect();
        let text = why(here[0], here[2], Some(here[1]), false);
        assert!(text.contains("0.67x the speed of cpu"), "{text}");
        assert!(
            text.contains("device-driven multi-pass needed 15 rounds"),
            "{text}"
        );
        assert!(text.contains("50 idle polls (5.00 per batch)"), "{text}");
        assert!(text.contains("more loop turns finding nothing"), "{text}");
        assert!(text.contains("underfilled"), "{text}");
        // Shallow work (fewer than 10 rounds) owes no explanation.
        let shallow = vec![
            rec("megakernel", true, 3.0, 0, true),
            rec("multipass", false, 4.0, 9, true),
        ];
        let h = Header {
            adapter: "a".into(),
            scale: Scale::Small,
            runs: 1,
            command: "c".into(),
            seconds: 1.0,
            cpu_adapter: false,
            not_built: vec![],
        };
        assert!(!markdown(&h, &shallow).contains("short of"));
        assert!(markdown(&h, &records).contains("short of"));
    }
}
