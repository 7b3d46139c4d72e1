//! `reyes render [SCENE] [options]`: renders a RIB / Newell / BPT scene (default: the built-in
//! Utah teapot) through the scheduler and writes a PNG; `--stats` writes what it did as JSON.

mod drift;
mod frames;
mod measure;
mod sweep;

use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::{GpuRenderer, required_features};
use reyes::scene::{self, FrameRanges, FrameSequence, Scene};
use reyes::stats::frame_stats;
use scheduler::{Gpu, StrategyKind};
use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str =
    "usage: reyes render [SCENE.rib|teapot|.bpt] [-o OUT.png] [--strategy megakernel|multipass]
  [--stats OUT.json] [--float OUT.pfm] [--depth OUT.pfm] [--width N] [--height N]
  [--samples N|NxM] [--mp-size PX] [--bound-px PX] [--max-depth N] [--memory-budget BYTES[K|M|G]]
  [--no-crack-dilation] [--stage-times] [--runs N] [--cpu] [--frames N|A-B|A,B,...]
  A RIB file of several frames writes each frame's Display name into -o's folder, or
  -o NAME.####.png (#### = the frame number; also for --stats, --float, --depth).";

struct Args {
    scene: Option<PathBuf>,
    out: Option<PathBuf>,
    strategy: StrategyKind,
    stats: Option<PathBuf>,
    float: Option<PathBuf>,
    depth: Option<PathBuf>,
    runs: u32,
    cpu: bool,
    /// Multi-pass: time each procedure's passes on their own.
    stage_times: bool,
    /// `--frames`: which frames of a sequence to render (all when `None`).
    frames: Option<FrameRanges>,
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
        stage_times: false,
        frames: None,
        options: RenderOptions::default(),
    };
    fn num<T: std::str::FromStr>(v: Option<String>, flag: &str) -> Result<T, String> {
        let v = v.ok_or_else(|| format!("{flag} needs a value"))?;
        v.parse()
            .map_err(|_| format!("{flag}: `{v}` is not a valid number"))
    }
    /// A byte count with an optional binary suffix: 512K, 64M, 2G.
    fn bytes(v: Option<String>, flag: &str) -> Result<u64, String> {
        let v = v.ok_or_else(|| format!("{flag} needs a value"))?;
        let (digits, shift) = match v.to_ascii_uppercase().chars().last() {
            Some('K') => (&v[..v.len() - 1], 10),
            Some('M') => (&v[..v.len() - 1], 20),
            Some('G') => (&v[..v.len() - 1], 30),
            _ => (&v[..], 0),
        };
        match digits.parse::<u64>() {
            Ok(n) if n > 0 && n.leading_zeros() >= shift => Ok(n << shift),
            _ => Err(format!(
                "{flag}: `{v}` is not a positive byte count like 64M"
            )),
        }
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
            "--memory-budget" => {
                a.options.memory_budget = Some(bytes(it.next(), "--memory-budget")?)
            }
            "--cpu" => a.cpu = true,
            "--frames" => {
                let v = it.next().ok_or("--frames needs a value")?;
                a.frames = Some(FrameRanges::parse(&v)?);
            }
            "--no-crack-dilation" => a.options.crack_dilation = false,
            "--stage-times" => a.stage_times = true,
            "-h" | "--help" => return Err(USAGE.into()),
            s if s.starts_with('-') => return Err(format!("unknown option `{s}`\n{USAGE}")),
            s => a.scene = Some(PathBuf::from(s)),
        }
    }
    Ok(a)
}

/// The scene file's frames (the built-in teapot: one) and its stem for default names.
fn load_sequence(a: &Args) -> Result<(FrameSequence, String), String> {
    Ok(match &a.scene {
        None => (
            FrameSequence::single(scene::builtin_teapot()),
            "teapot".into(),
        ),
        Some(p) if p.as_os_str() == "teapot" => (
            FrameSequence::single(scene::builtin_teapot()),
            "teapot".into(),
        ),
        Some(p) => (
            scene::load_frames(p).map_err(|e| e.to_string())?,
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or("out".into()),
        ),
    })
}

/// Renders every selected frame of the scene; the whole file is read (and every output name
/// decided) before the first frame renders, so a bad file writes nothing.
fn run(a: Args) -> Result<(), String> {
    let (seq, stem) = load_sequence(&a)?;
    for w in &seq.warnings {
        eprintln!("warning: {w}");
    }
    let requested = frames::Requested {
        out: a.out.as_deref(),
        stats: a.stats.as_deref(),
        float: a.float.as_deref(),
        depth: a.depth.as_deref(),
        stem: &stem,
    };
    let (jobs, skipped) = frames::plan(&seq, a.frames.as_ref(), &requested)?;
    for w in &skipped {
        eprintln!("warning: {w}");
    }
    // Each frame's options are checked before any renders.
    let data = jobs
        .iter()
        .map(|(i, _)| FrameData::new(&seq.frames[*i].scene, &a.options))
        .collect::<Result<Vec<_>, _>>()?;
    let gpu = match (a.cpu, jobs.is_empty()) {
        (false, false) => Some(gpu_renderer(&a)?),
        _ => None,
    };
    for ((i, outputs), data) in jobs.iter().zip(&data) {
        if seq.frames.len() > 1 {
            eprintln!("frame {}:", seq.frames[*i].number);
        }
        render_frame(
            &a,
            &seq.frames[*i].scene,
            &seq.warnings,
            data,
            outputs,
            gpu.as_ref(),
        )?;
    }
    Ok(())
}

/// The GPU and its renderer, made once for all frames.
fn gpu_renderer(a: &Args) -> Result<(Gpu, GpuRenderer), String> {
    let gpu = Gpu::from_env_requiring(required_features()).map_err(|e| e.to_string())?;
    if a.stage_times && a.strategy == StrategyKind::Megakernel {
        eprintln!(
            "warning: --stage-times: the megakernel's stages share one launch; only multipass times them apart"
        );
    }
    let renderer = GpuRenderer::with_stage_timing(&gpu, a.strategy, a.stage_times)
        .map_err(|e| e.to_string())?;
    Ok((gpu, renderer))
}

/// Renders one frame to its outputs, on the CPU twin when `gpu` is `None`.
fn render_frame(
    a: &Args,
    scene: &Scene,
    file_warnings: &[String],
    data: &FrameData,
    out: &frames::Outputs,
    gpu: Option<&(Gpu, GpuRenderer)>,
) -> Result<(), String> {
    let Some((gpu, renderer)) = gpu else {
        let r = reyes::cpu_render::render_cpu(data);
        // The CPU twin keeps the GPU's counters: the same frame warnings.
        for w in reyes::warnings::frame_warnings(data, &r.counters) {
            eprintln!("warning: {w}");
        }
        r.image.write_png(&out.image)?;
        eprintln!("wrote {} (CPU reference)", out.image.display());
        return Ok(());
    };
    // One frame makes the image; with --runs N > 1, N frames are timed after a warm-up
    // (GpuRenderer::timed_frames).
    let (frame, times) = if a.runs > 1 {
        let t = renderer
            .timed_frames(gpu, data, a.runs)
            .map_err(|e| e.to_string())?;
        for (i, (g, w)) in t.gpu_ms.iter().zip(&t.wall_ms).enumerate() {
            eprintln!("run {i}: GPU {g:?} ms, wall {w:.2} ms");
        }
        let times = t
            .gpu_ms
            .iter()
            .copied()
            .zip(t.wall_ms.iter().copied())
            .collect();
        (t.last, times)
    } else {
        let f = renderer.render(gpu, data).map_err(|e| e.to_string())?;
        let gpu_ms = f.run.gpu_ms.zip(f.resolve_gpu_ms).map(|(x, y)| x + y);
        let wall_ms = f.wall_ms;
        (f, vec![(gpu_ms, wall_ms)])
    };
    // Where the renderer gave up on something (near-plane culls, split limit, nothing drawn).
    let frame_warnings = reyes::warnings::frame_warnings(data, &frame.counters);
    for w in &frame_warnings {
        eprintln!("warning: {w}");
    }
    let all_warnings: Vec<String> = file_warnings
        .iter()
        .chain(&scene.warnings)
        .chain(&frame_warnings)
        .cloned()
        .collect();
    let mut stats = frame_stats(data, &frame, &gpu.adapter_name(), &all_warnings);
    stats["runs"] = run_summary(&times);
    frame.image.write_png(&out.image)?;
    if let Some(p) = &out.float {
        frame.image.write_pfm(p)?;
    }
    if let Some(p) = &out.depth {
        frame.image.write_depth(p)?;
    }
    if let Some(p) = &out.stats {
        let text = serde_json::to_string_pretty(&stats).unwrap();
        reyes::output::write_atomic(p, (text + "\n").as_bytes())?;
    }
    eprintln!(
        "wrote {} ({}x{}, {}{}: {} grids, {} micropolygons, GPU {} ms, wall {:.1} ms)",
        out.image.display(),
        data.frame.width,
        data.frame.height,
        a.strategy.name(),
        match frame.buckets {
            1 => String::new(),
            n => format!(
                " in {n} buckets, {:.1} MiB working memory",
                frame.peak_working_bytes as f64 / (1 << 20) as f64
            ),
        },
        stats["grids_diced"],
        stats["micropolygons"],
        match (&stats["runs"]["gpu_ms"], stats["gpu_ms"].as_f64()) {
            (serde_json::Value::Object(m), _) if a.runs > 1 => format!(
                "{:.3} ± {:.3} (median ± MAD of {})",
                m["median"].as_f64().unwrap_or(f64::NAN),
                m["mad"].as_f64().unwrap_or(f64::NAN),
                a.runs
            ),
            (_, Some(v)) => format!("{v:.3}"),
            _ => "n/a".into(),
        },
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

/// The subcommands, for `reyes` without one.
const COMMANDS: &str = "usage: reyes COMMAND [options]
  render   render a scene to PNG (the built-in teapot without a file)
  measure  a frame's geometric and image error against the exact surfaces, as JSON
  sweep    speed against error over quality settings: CSV, markdown and a plot
  drift    f32 split drift against f64 over 0-24 split levels
`reyes COMMAND --help` for each";

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let cmd = args.next().unwrap_or_default();
    let result = match cmd.as_str() {
        "render" => parse(args).and_then(run),
        "measure" => measure::main(args),
        "sweep" => sweep::main(args),
        "drift" => drift::main(args),
        _ => {
            eprintln!("{COMMANDS}");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("reyes {cmd}: {e}");
            ExitCode::FAILURE
        }
    }
}
