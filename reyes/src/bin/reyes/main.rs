//! `reyes render [SCENE] [options]`: renders a RIB / Newell / BPT scene (default: the built-in
//! Utah teapot) through the scheduler and writes a PNG; `--stats` writes what it did as JSON.

mod drift;
mod measure;
mod sweep;

use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::{GpuRenderer, required_features};
use reyes::scene;
use reyes::stats::frame_stats;
use scheduler::{Gpu, StrategyKind};
use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str =
    "usage: reyes render [SCENE.rib|teapot|.bpt] [-o OUT.png] [--strategy megakernel|multipass]
  [--stats OUT.json] [--float OUT.pfm] [--depth OUT.pfm] [--width N] [--height N]
  [--samples N|NxM] [--mp-size PX] [--bound-px PX] [--max-depth N] [--runs N] [--cpu]";

struct Args {
    scene: Option<PathBuf>,
    out: Option<PathBuf>,
    strategy: StrategyKind,
    stats: Option<PathBuf>,
    float: Option<PathBuf>,
    depth: Option<PathBuf>,
    runs: u32,
    cpu: bool,
    options: RenderOptions,
}

fn parse(mut it: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut a = Args {
        scene: None,
        out: None,
        strategy: StrategyKind::Megakernel,
        stats: None,
        float: None,
        depth: None,
        runs: 1,
        cpu: false,
        options: RenderOptions::default(),
    };
    fn num<T: std::str::FromStr>(v: Option<String>, flag: &str) -> Result<T, String> {
        let v = v.ok_or_else(|| format!("{flag} needs a value"))?;
        v.parse()
            .map_err(|_| format!("{flag}: `{v}` is not a valid number"))
    }
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "-o" | "--output" => a.out = it.next().map(PathBuf::from),
            "--strategy" => {
                let v = it.next().unwrap_or_default();
                a.strategy = StrategyKind::parse(&v).ok_or(format!("unknown strategy `{v}`"))?;
            }
            "--stats" => a.stats = it.next().map(PathBuf::from),
            "--float" => a.float = it.next().map(PathBuf::from),
            "--depth" => a.depth = it.next().map(PathBuf::from),
            "--width" => a.options.width = Some(num(it.next(), "--width")?),
            "--height" => a.options.height = Some(num(it.next(), "--height")?),
            "--samples" => {
                let v = it.next().unwrap_or_default();
                let (x, y) = v.split_once('x').unwrap_or((&v, &v));
                let p = |s: &str| {
                    s.parse::<u32>()
                        .map_err(|_| format!("--samples: `{v}` is not N or NxM"))
                };
                a.options.pixel_samples = Some((p(x)?, p(y)?));
            }
            "--mp-size" => a.options.mp_size = num(it.next(), "--mp-size")?,
            "--bound-px" => a.options.bound_px = Some(num(it.next(), "--bound-px")?),
            "--max-depth" => a.options.max_depth = num(it.next(), "--max-depth")?,
            "--runs" => a.runs = num(it.next(), "--runs")?,
            "--cpu" => a.cpu = true,
            "-h" | "--help" => return Err(USAGE.into()),
            s if s.starts_with('-') => return Err(format!("unknown option `{s}`\n{USAGE}")),
            s => a.scene = Some(PathBuf::from(s)),
        }
    }
    Ok(a)
}

fn run(a: Args) -> Result<(), String> {
    let (scene, name) = match &a.scene {
        None => (scene::builtin_teapot(), "teapot".to_string()),
        Some(p) if p.as_os_str() == "teapot" => (scene::builtin_teapot(), "teapot".to_string()),
        Some(p) => (
            scene::load(p).map_err(|e| e.to_string())?,
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or("out".into()),
        ),
    };
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{name}.png")));
    let data = FrameData::new(&scene, &a.options)?;
    if a.cpu {
        let r = reyes::cpu_render::render_cpu(&data);
        r.image.write_png(&out)?;
        eprintln!("wrote {} (CPU reference)", out.display());
        return Ok(());
    }
    let gpu = Gpu::from_env_requiring(required_features()).map_err(|e| e.to_string())?;
    let renderer = GpuRenderer::new(&gpu, a.strategy).map_err(|e| e.to_string())?;
    // The first frame compiles pipelines and sizes the queues; with --runs N > 1 it is a
    // warm-up and the N frames after it are timed.
    let mut frame = renderer.render(&gpu, &data).map_err(|e| e.to_string())?;
    let mut times = Vec::new();
    for i in 0..a.runs {
        if a.runs > 1 {
            frame = renderer.render(&gpu, &data).map_err(|e| e.to_string())?;
        }
        let gpu_ms = frame
            .run
            .gpu_ms
            .zip(frame.resolve_gpu_ms)
            .map(|(x, y)| x + y);
        if a.runs > 1 {
            eprintln!("run {i}: GPU {gpu_ms:?} ms, wall {:.2} ms", frame.wall_ms);
        }
        times.push((gpu_ms, frame.wall_ms));
    }
    let mut stats = frame_stats(&data, &frame, &gpu.adapter_name(), &scene.warnings);
    stats["runs"] = run_summary(&times);
    if frame.counters[reyes::stages::C_CULL_NEAR] > 0 {
        eprintln!(
            "warning: {} patch pieces still crossed the near plane after {} eye splits and were culled",
            frame.counters[reyes::stages::C_CULL_NEAR],
            data.frame.max_eye_splits
        );
    }
    frame.image.write_png(&out)?;
    if let Some(p) = &a.float {
        frame.image.write_pfm(p)?;
    }
    if let Some(p) = &a.depth {
        frame.image.write_depth(p)?;
    }
    if let Some(p) = &a.stats {
        let text = serde_json::to_string_pretty(&stats).unwrap();
        std::fs::write(p, text + "\n").map_err(|e| format!("{}: {e}", p.display()))?;
    }
    eprintln!(
        "wrote {} ({}x{}, {}: {} grids, {} micropolygons, GPU {} ms, wall {:.1} ms)",
        out.display(),
        data.frame.width,
        data.frame.height,
        a.strategy.name(),
        stats["grids_diced"],
        stats["micropolygons"],
        stats["gpu_ms"]
            .as_f64()
            .map_or("n/a".into(), |v| format!("{v:.3}")),
        frame.wall_ms
    );
    Ok(())
}

/// Median and median absolute deviation of each run's GPU and wall time.
fn run_summary(times: &[(Option<f64>, f64)]) -> serde_json::Value {
    fn med_mad(v: Vec<f64>) -> serde_json::Value {
        if v.is_empty() {
            return serde_json::Value::Null;
        }
        let (median, mad) = scheduler::stats::median_and_mad(&v);
        serde_json::json!({ "median": median, "mad": mad, "all": v })
    }
    serde_json::json!({
        "count": times.len(),
        "gpu_ms": med_mad(times.iter().filter_map(|t| t.0).collect()),
        "wall_ms": med_mad(times.iter().map(|t| t.1).collect()),
    })
}

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    match args.next().as_deref() {
        Some("render") => {}
        Some("drift") => {
            return drift::main(args).map_or_else(
                |e| {
                    eprintln!("reyes drift: {e}");
                    ExitCode::FAILURE
                },
                |()| ExitCode::SUCCESS,
            );
        }
        Some(cmd @ ("measure" | "sweep")) => {
            let r = if cmd == "measure" {
                measure::main(args)
            } else {
                sweep::main(args)
            };
            return r.map_or_else(
                |e| {
                    eprintln!("reyes {cmd}: {e}");
                    ExitCode::FAILURE
                },
                |()| ExitCode::SUCCESS,
            );
        }
        _ => {
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    }
    match parse(args).and_then(run) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("reyes: {e}");
            ExitCode::FAILURE
        }
    }
}
