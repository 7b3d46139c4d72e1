//! `schedbench --suite`: every workload x strategy x problem size, each strategy warmed up
//! once and then timed `runs` times, every run verified; writes `runs.jsonl`, `summary.md` and
//! a plot per workload into the output folder (each file whole or not at all).

use crate::catalog::WorkloadName;
use crate::error::Error;
use crate::files::{PendingFile, write_file};
use crate::record::{RunKey, RunRecord};
use crate::scale::Scale;
use crate::strategy::{GpuConfig, Strategy};
use crate::workload::{Prepared, Workload};
use crate::{plot, summary};
use scheduler::Gpu;
use scheduler::clocks::ClockKeeper;
use std::path::PathBuf;
use std::time::{Duration, Instant};

pub struct SuiteOptions {
    pub out: PathBuf,
    pub scale: Scale,
    pub runs: u32,
    /// Only these workloads (all built ones when empty).
    pub only: Vec<WorkloadName>,
    pub config: GpuConfig,
    /// The command line, for the summary.
    pub command: String,
}

/// Full GPU load before each GPU strategy's timed runs (`scheduler::clocks::ClockKeeper`;
/// nothing on CPU adapters).
pub const WARM_UP: Duration = Duration::from_millis(500);

/// Runs a strategy once untimed (compilation, buffer sizing and the megakernel's probe are not
/// the strategy's cost), raises the GPU's clocks for [`WARM_UP`], then `runs` timed, verified
/// runs, each after raising the clocks again where the checks since the last raise have left
/// the GPU idle long enough for them to fall (`scheduler::clocks::ClockKeeper`: on the H100,
/// Killeroo 1080p's 0.8 ms frames, each followed by about 300 ms of checking and 20 ms of load,
/// fell from 1980 to 345 MHz 1.7 s after the warm-up; docs/results.md, 2026-12-05 (sixth
/// session)). A run that fails ends the strategy's runs at this size with a failed record; an
/// unverified warm-up run is recorded as a failure too.
pub fn measure(
    gpu: &Gpu,
    w: &mut dyn Workload,
    strategy: &Strategy,
    prepared: &Prepared,
    runs: u32,
) -> Vec<RunRecord> {
    let name = w.name();
    let key = |run| RunKey {
        workload: &name,
        strategy,
        prepared,
        gpu,
        run,
    };
    let warm = w.run(gpu, strategy).and_then(|m| match m.mismatch {
        Some(e) if !m.verified => Err(Error::WarmUpMismatch(e)),
        _ => Ok(()),
    });
    let keeper = warm.and_then(|()| {
        if strategy.is_gpu() {
            ClockKeeper::new(gpu, WARM_UP)
                .map(Some)
                .map_err(Error::from)
        } else {
            Ok(None)
        }
    });
    let mut keeper = match keeper {
        Ok(k) => k,
        Err(e) => return vec![RunRecord::failed(&key(0), e.to_string())],
    };
    let mut out = Vec::new();
    for run in 0..runs {
        if let Some(k) = keeper.as_mut()
            && let Err(e) = k.keep_up()
        {
            out.push(RunRecord::failed(&key(run), e.to_string()));
            break;
        }
        match w.run(gpu, strategy) {
            Ok(m) => out.push(RunRecord::new(&key(run), &m)),
            Err(e) => {
                out.push(RunRecord::failed(&key(run), e.to_string()));
                break;
            }
        }
    }
    out
}

/// Runs the suite; true when every run was verified. Errors: the output folder or a file
/// cannot be written, or a workload's input cannot be read.
pub fn run_suite(gpu: &Gpu, o: &SuiteOptions) -> Result<bool, Error> {
    let start = Instant::now();
    std::fs::create_dir_all(&o.out).map_err(|source| Error::File {
        path: o.out.clone(),
        source,
    })?;
    let names: Vec<WorkloadName> = if o.only.is_empty() {
        WorkloadName::ALL
            .into_iter()
            .filter(|w| w.built())
            .collect()
    } else {
        o.only.clone()
    };
    let mut workloads = Vec::new();
    for n in &names {
        workloads.extend(n.suite(o.scale, &o.config)?);
    }
    let not_built: Vec<&str> = WorkloadName::ALL
        .iter()
        .filter(|w| !w.built())
        .map(|w| w.name())
        .collect();
    let total = workloads
        .iter()
        .map(|w| w.sizes().len() * w.strategies().len())
        .sum::<usize>();
    // On a terminal: a bar over (workload, size, strategy) steps (`reyes_cli::progress`).
    let bar = reyes_cli::progress::bar(total as u64, "");
    let mut jsonl = PendingFile::new(&o.out, "runs.jsonl")?;
    let mut records = Vec::new();
    for w in &mut workloads {
        let name = w.name();
        for (i, label) in w.sizes().into_iter().enumerate() {
            bar.set_message(format!("{name} {label}: input and CPU reference"));
            let strategies = w.strategies();
            let prepared = w.prepare(gpu, i);
            for s in &strategies {
                bar.set_message(format!("{name} {label}: {}", s.name()));
                let recs = match &prepared {
                    Ok(p) => measure(gpu, w.as_mut(), s, p, o.runs),
                    Err(e) => {
                        let p = Prepared {
                            size: label.clone(),
                            params: String::new(),
                            problem_items: 0,
                        };
                        let key = RunKey {
                            workload: &name,
                            strategy: s,
                            prepared: &p,
                            gpu,
                            run: 0,
                        };
                        vec![RunRecord::failed(&key, format!("preparing the size: {e}"))]
                    }
                };
                for r in recs {
                    let mut line = serde_json::to_string(&r).expect("records serialise");
                    line.push('\n');
                    jsonl.write(line.as_bytes())?;
                    // The logger writes above the bar (`reyes_cli::logging`).
                    if let Some(e) = r.error.as_ref().filter(|_| !r.verified) {
                        log::error!(
                            "{} {} {} run {}: {e}",
                            r.workload,
                            r.size,
                            r.strategy,
                            r.run
                        );
                    }
                    records.push(r);
                }
                bar.inc(1);
            }
        }
    }
    bar.finish_and_clear();
    let runs_path = jsonl.finish()?;
    let header = summary::Header {
        adapter: gpu.adapter_name(),
        scale: o.scale,
        runs: o.runs,
        command: o.command.clone(),
        seconds: start.elapsed().as_secs_f64(),
        cpu_adapter: gpu.is_cpu_adapter(),
        not_built,
    };
    let md = summary::markdown(&header, &records);
    let summary_path = write_file(&o.out, "summary.md", md.as_bytes())?;
    let plots = plot::write_plots(&o.out, &records)?;
    let verified = records.iter().filter(|r| r.verified).count();
    reyes_cli::outln!(
        "{} runs ({verified} verified) in {:.0} s: {}, {}, {} plots in {}",
        records.len(),
        start.elapsed().as_secs_f64(),
        runs_path.display(),
        summary_path.display(),
        plots.len(),
        o.out.display()
    );
    Ok(verified == records.len())
}

/// Draws the plots of the suite whose records are `dir/runs.jsonl` into `dir` (as
/// [`run_suite`] does after its runs); returns their paths. Errors: the file cannot be read
/// ([`Error::File`]), a line is not a record ([`Error::Record`]) or none is
/// ([`Error::NoRecords`]), a plot
/// cannot be written.
pub fn replot(dir: &std::path::Path) -> Result<Vec<std::path::PathBuf>, Error> {
    let path = dir.join("runs.jsonl");
    let text = std::fs::read_to_string(&path).map_err(|source| Error::File {
        path: path.clone(),
        source,
    })?;
    let mut records = Vec::new();
    for (i, l) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        records.push(
            serde_json::from_str::<RunRecord>(l).map_err(|e| Error::Record {
                path: path.clone(),
                line: i + 1,
                message: e.to_string(),
            })?,
        );
    }
    if records.is_empty() {
        return Err(Error::NoRecords(path));
    }
    plot::write_plots(dir, &records)
}
