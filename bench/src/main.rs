//! `schedbench`: runs workloads under every scheduling strategy on the same input, checks every
//! run against the CPU reference, and prints one JSON object per run (`--json`) or a table of
//! medians with their spread; `--suite` runs every workload x strategy x size and writes a
//! report (runs.jsonl, summary.md, plots). Exit status: 0 when every run was verified, 1 when
//! one was not or a run failed, 2 for usage errors.
//!
//! cargo run --release --bin schedbench -- --workload tree --strategy all --runs 10
//! cargo run --release --bin schedbench -- --suite --size small --out report/

mod bfs;
mod catalog;
mod cli;
mod error;
mod files;
mod mandelbrot;
mod plot;
mod record;
mod reyes_frames;
mod scale;
mod single;
mod strategy;
mod suite;
mod summary;
mod tree;
mod workload;

use catalog::WorkloadName;
use clap::Parser;
use cli::Cli;
use error::Error;
use scheduler::Gpu;
use std::process::ExitCode;

/// The environment's GPU, with the features reyes needs when `needs_reyes`, its loops trusted
/// (`Gpu::trust_loops`). Errors: no adapter, or one without the features.
fn open_gpu(needs_reyes: bool) -> Result<Gpu, Error> {
    let mut gpu = if needs_reyes {
        Gpu::from_env_requiring(reyes::gpu_render::required_features())
    } else {
        Gpu::from_env()
    }?;
    // SAFETY: schedbench compiles the scheduler's, its workloads' and reyes's shaders only,
    // whose loops all end (docs/scheduler.md 4, "Naga's loop bounding").
    #[allow(
        unsafe_code,
        reason = "Gpu::trust_loops: every loop of this device's shaders ends"
    )]
    unsafe {
        gpu.trust_loops()
    };
    Ok(gpu)
}

fn run_suite(cli: &Cli) -> Result<bool, Error> {
    let only: Vec<WorkloadName> = cli.workload.into_iter().collect();
    let needs_reyes = only.is_empty() || only.contains(&WorkloadName::Reyes);
    let gpu = open_gpu(needs_reyes)?;
    let options = suite::SuiteOptions {
        out: cli.out.clone().expect("clap requires --out with --suite"),
        scale: cli.size,
        runs: cli.runs.unwrap_or(cli.size.default_runs()),
        only,
        config: cli.gpu_config(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
    };
    suite::run_suite(&gpu, &options)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    cli.check();
    reyes::driver_env::ensure_xdg_runtime_dir();
    reyes_cli::logging::init();
    let result = if let Some(dir) = &cli.replot {
        suite::replot(dir).map(|plots| {
            reyes_cli::outln!("{} plots in {}", plots.len(), dir.display());
            true
        })
    } else if cli.suite {
        run_suite(&cli)
    } else {
        single::run(&cli)
    };
    match result {
        // A table or record that could not be written (reported when it failed).
        Ok(true) if reyes_cli::stdout::failed() => ExitCode::FAILURE,
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => {
            log::error!("some run failed or did not match the CPU reference");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("schedbench: {e}");
            ExitCode::FAILURE
        }
    }
}
