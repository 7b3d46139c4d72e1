//! `reyes`: the Reyes renderer's command line (flags in `cli`). `reyes render [SCENE]
//! [options]` renders a RIB / Newell / BPT scene (default: the built-in Utah teapot) through
//! the scheduler and writes a PNG; `--stats` writes what it did as JSON.

mod bench;
mod bench_devices;
mod cli;
mod drift;
mod error;
mod frames;
mod holes;
mod inputs;
mod measure;
mod multi;
mod setup;
mod sweep;
mod view;

use clap::Parser;
use cli::{Cli, Command, RenderCmd};
use error::CliError;
use reyes::frame::{FrameData, SceneFeatures};
use reyes::gpu_render::{GpuRenderer, RendererConfig};
use reyes::image::FrameImage;
use reyes::scene::Scene;
use reyes::stats::{RunSummary, StageTimes, frame_stats};
use scheduler::{Gpu, StrategyKind};
use std::process::ExitCode;

/// Renders every selected frame of the scene, reading the file a frame at a time: read a
/// frame, render it (if selected), drop it, go on. A frame that fails (its input, its
/// options, its render, its outputs) is reported naming it and the others still render;
/// then the run fails ([`CliError::FramesFailed`], exit 1). A selection that names none of
/// the file's frames is a usage error, found when the file has been read
/// ([`CliError::NoFrameSelected`], exit 2). With a selection (`--frames`,
/// `--frame`), a frame whose outputs all exist is skipped unless `--overwrite`.
fn run(a: RenderCmd) -> Result<(), CliError> {
    let (mut stream, stem) = setup::stream_sequence(a.scene.as_deref())?;
    // The reference of --compare-to, read before anything renders.
    let reference = match &a.compare_to {
        Some(p) => Some((
            p.clone(),
            FrameImage::read_exr(p).map_err(CliError::CompareToUnreadable)?,
        )),
        None => None,
    };
    let requested = frames::Requested {
        out: a.out.as_deref(),
        stats: a.stats.as_deref(),
        float: a.float.as_deref(),
        depth: a.depth.as_deref(),
        exr: a.exr.as_deref(),
        stem: &stem,
    };
    let selection = a.selection();
    let selected = |n: u32| selection.as_ref().is_none_or(|s| s.contains(n));
    let skip_existing = selection.is_some() && !a.overwrite;
    let options = a.render.options();
    // One frame read ahead: whether the file has several frames decides the names.
    let mut file_warnings = Vec::new();
    let mut ahead = stream.next();
    let mut next = stream.next();
    let sequence = next.is_some();
    let several = sequence && selection.as_ref().is_none_or(|s| s.single().is_none());
    let mut namer = frames::Namer::new(&requested, sequence, several)?;
    let mut device = Device::Unopened;
    let mut inputs = inputs::SceneInputs::new(a.scene.as_deref());
    // A bar over the frames rendered (with --runs N > 1: every timed frame) when several
    // may be; it grows as frames come.
    let bar = if several || a.runs > 1 {
        reyes_cli::progress::bar(0, "")
    } else {
        indicatif::ProgressBar::hidden()
    };
    let (mut numbers, mut failed, mut any) = (Vec::new(), Vec::new(), false);
    // --devices: frames go to the devices' threads (a sequence) or are split over them (one
    // frame); they report failed frames here.
    let device_failures = std::sync::Mutex::new(Vec::new());
    let shared = multi::Shared {
        a: &a,
        bar: &bar,
        reference: reference.as_ref(),
        failed: &device_failures,
    };
    std::thread::scope(|scope| -> Result<(), CliError> {
        let mut pool = (a.devices.clone()).map(|d| multi::Pool::new(d, several, scope, &shared));
        while let Some(item) = ahead {
            for w in stream.take_warnings() {
                log::warn!("{w}");
                file_warnings.push(w);
            }
            match item {
                Err(e) => match e.number {
                    Some(n) if !selected(n) => {
                        numbers.push(n);
                        log::warn!("{e} (not selected: not rendered)");
                    }
                    None if numbers.is_empty() => return Err(e.error.into()),
                    n => {
                        numbers.extend(n);
                        any |= n.is_some();
                        eprintln!("reyes render: {e}");
                        failed.push(n.map_or("the file".into(), |n| format!("frame {n}")));
                    }
                },
                Ok(frame) if !selected(frame.number) => numbers.push(frame.number),
                Ok(frame) => {
                    numbers.push(frame.number);
                    any = true;
                    match &frame.unsupported {
                        Some(why) => log::warn!("skipped frame {}: {why}", frame.number),
                        None => {
                            let job = Job {
                                frame,
                                sequence,
                                skip_existing,
                                options: &options,
                                file_warnings: &file_warnings,
                                reference: reference.as_ref(),
                            };
                            let run = (&mut namer, &mut inputs, &mut device);
                            match render_job(&a, job, run, &bar, pool.as_mut()) {
                                Ok(()) => {}
                                Err((None, e)) => return Err(e),
                                Err((Some(n), e)) => {
                                    eprintln!("reyes render: frame {n}: {e}");
                                    failed.push(format!("frame {n}"));
                                }
                            }
                        }
                    }
                }
            }
            // The frame is dropped before the next one is read.
            ahead = next.take().or_else(|| stream.next());
        }
        if let Some(pool) = pool {
            pool.finish();
        }
        Ok(())
    })?;
    failed.extend(
        device_failures
            .into_inner()
            .unwrap_or_else(|p| p.into_inner()),
    );
    bar.finish_and_clear();
    for w in stream.take_warnings() {
        log::warn!("{w}");
    }
    if !any && failed.is_empty() {
        let numbers: Vec<String> = numbers.iter().map(u32::to_string).collect();
        return Err(CliError::NoFrameSelected {
            numbers: numbers.join(", "),
        });
    }
    if !failed.is_empty() {
        return Err(CliError::FramesFailed {
            failed: failed.join(", "),
        });
    }
    Ok(())
}

/// Where frames render: not decided before the first frame to render (the GPU is opened
/// then), the CPU twin, or the GPU with its renderer, compiled for what the frames so far
/// need (and again, for the union, when a later frame needs more).
enum Device {
    Unopened,
    Cpu,
    Gpu(Box<Gpu>, Option<Box<(GpuRenderer, SceneFeatures)>>),
}

/// One frame to render and what it needs from the run.
struct Job<'a> {
    frame: reyes::scene::SceneFrame,
    sequence: bool,
    skip_existing: bool,
    options: &'a reyes::frame::RenderOptions,
    file_warnings: &'a [String],
    reference: Option<&'a Reference>,
}

/// Names, checks (names the file system holds, no output one of the scene's inputs) and
/// renders one frame (or skips it when its outputs exist and `skip_existing`); `bar` grows
/// by the frame's steps. Errors: the frame's number (`None`:
/// an error of the whole run, such as a missing output folder or no GPU) and the error.
fn render_job(
    a: &RenderCmd,
    mut job: Job,
    (namer, inputs, device): (&mut frames::Namer, &mut inputs::SceneInputs, &mut Device),
    bar: &indicatif::ProgressBar,
    pool: Option<&mut multi::Pool>,
) -> Result<(), (Option<u32>, CliError)> {
    let number = job.frame.number;
    let at = |e: CliError| (Some(number), e);
    let outputs = namer.outputs(&job.frame).map_err(|e| match e {
        CliError::MissingFolder { .. } => (None, e),
        e => at(e),
    })?;
    let cpu = a.cpu || matches!(device, Device::Cpu);
    // Before anything renders (or is skipped as done): no output is the scene file, an
    // archive or a map.
    inputs.check(outputs.files(cpu)).map_err(at)?;
    if job.skip_existing && outputs.files(cpu).iter().all(|p| p.exists()) {
        reyes_cli::progress::note(format!(
            "frame {number}: skipped, {} exists (--overwrite renders it again)",
            outputs.image.display()
        ));
        return Ok(());
    }
    a.render.change_scene(&mut job.frame.scene).map_err(at)?;
    let data = FrameData::new(&job.frame.scene, job.options).map_err(|e| at(e.into()))?;
    if let Some(pool) = pool {
        let frame = multi::Prepared {
            number,
            sequence: job.sequence,
            scene: job.frame.scene,
            data,
            outputs,
            file_warnings: job.file_warnings.to_vec(),
        };
        return pool.dispatch(frame);
    }
    if let Device::Unopened = device {
        *device = match a.cpu {
            true => Device::Cpu,
            false => {
                let gpu = setup::open_gpu().map_err(|e| (None, e))?;
                match a.cpu_by_default(&gpu) {
                    true => Device::Cpu,
                    false => Device::Gpu(Box::new(gpu), None),
                }
            }
        };
    }
    let gpu = match device {
        Device::Gpu(gpu, renderer) => {
            let need = data.features();
            let have = renderer.as_ref().map(|r| r.1);
            if have.is_none_or(|h| h.union(need) != h) {
                let all = have.map_or(need, |h| h.union(need));
                *renderer = Some(Box::new((gpu_renderer(a, gpu, all).map_err(at)?, all)));
            }
            Some((&**gpu, &renderer.as_ref().expect("made above").0))
        }
        _ => None,
    };
    if job.sequence {
        reyes_cli::progress::note(format!("frame {number}:"));
        bar.set_message(format!("frame {number}"));
    } else {
        bar.set_message("timed frames");
    }
    let steps = if gpu.is_some() { a.runs.max(1) } else { 1 };
    bar.set_length(bar.position() + steps as u64);
    render_frame(
        a,
        &job.frame.scene,
        job.file_warnings,
        &data,
        &outputs,
        (gpu, job.reference),
        bar,
    )
    .map_err(at)
}

/// The renderer for `features` on `gpu`.
fn gpu_renderer(
    a: &RenderCmd,
    gpu: &Gpu,
    features: SceneFeatures,
) -> Result<GpuRenderer, CliError> {
    let strategy = a.render.strategy_for(gpu);
    if a.stage_times && strategy == StrategyKind::Megakernel {
        log::warn!(
            "--stage-times: the megakernel's stages share one launch; only the multi-passes time them apart"
        );
    }
    let config = RendererConfig::new(strategy)
        .stage_timing(a.stage_times)
        .features(features);
    setup::renderer(gpu, config)
}

/// `--compare-to`'s file and image.
type Reference = (std::path::PathBuf, FrameImage);

/// Renders one frame to its outputs, on the CPU twin when `gpu` is `None`; with a
/// `reference` (`--compare-to`), reports the image error against it.
fn render_frame(
    a: &RenderCmd,
    scene: &Scene,
    file_warnings: &[String],
    data: &FrameData,
    out: &frames::Outputs,
    (gpu, reference): (Option<(&Gpu, &GpuRenderer)>, Option<&Reference>),
    progress: &indicatif::ProgressBar,
) -> Result<(), CliError> {
    let Some((gpu, renderer)) = gpu else {
        let t0 = std::time::Instant::now();
        let r = reyes::cpu_render::render_cpu(data);
        let secs = t0.elapsed().as_secs_f64();
        progress.inc(1);
        if let Some(reference) = reference {
            compare_to(reference, &r.image)?;
        }
        // The CPU twin keeps the GPU's counters: the same frame warnings.
        for w in reyes::warnings::frame_warnings(data, &r.counters) {
            log::warn!("{w}");
        }
        r.image.write_png(&out.image)?;
        reyes_cli::progress::note(format!(
            "wrote {} ({}x{}, CPU reference, {:.2} s)",
            out.image.display(),
            r.image.width,
            r.image.height,
            secs
        ));
        return Ok(());
    };
    let (frame, times) = gpu_frame(a, gpu, renderer, data, progress)?;
    let adapter = gpu.adapter_name();
    write_frame(
        (scene, file_warnings, data),
        out,
        frame,
        times,
        &adapter,
        reference,
        None,
    )
}

/// One GPU frame's times: its GPU ms (when timestamps exist) and wall ms.
type Times = Vec<(Option<f64>, f64)>;

/// Renders `data` on `gpu`: one frame, or with --runs N > 1 N frames timed after a warm-up
/// (GpuRenderer::timed_frames), each printed; the (last) frame and the times. The multi-pass
/// floor is always timed after its warm-up: its first frame is the host-driven run it keeps,
/// not the floor.
fn gpu_frame(
    a: &RenderCmd,
    gpu: &Gpu,
    renderer: &GpuRenderer,
    data: &FrameData,
    progress: &indicatif::ProgressBar,
) -> Result<(reyes::gpu_render::GpuFrame, Times), CliError> {
    let timed = a.runs > 1 || renderer.strategy() == StrategyKind::MultipassFloor;
    Ok(if timed {
        let t = renderer.timed_frames(gpu, data, a.runs, &|n| progress.inc(n))?;
        for (i, (g, w)) in t.gpu_ms.iter().zip(&t.wall_ms).enumerate() {
            let g = g.map_or("n/a".into(), |g| format!("{g:.3}"));
            reyes_cli::progress::note(format!("run {i}: GPU {g} ms, wall {w:.2} ms"));
        }
        let times = t
            .gpu_ms
            .iter()
            .copied()
            .zip(t.wall_ms.iter().copied())
            .collect();
        (t.last, times)
    } else {
        let f = renderer.render(gpu, data)?;
        progress.inc(1);
        let gpu_ms = f.run.gpu_ms.zip(f.resolve_gpu_ms).map(|(x, y)| x + y);
        let wall_ms = f.wall_ms;
        (f, vec![(gpu_ms, wall_ms)])
    })
}

/// Writes a GPU frame's outputs (image, --float, --depth, --exr, --stats with the times and,
/// with --devices, each device's part) and prints what it did; with a `reference`
/// (`--compare-to`), reports the image error against it.
fn write_frame(
    (scene, file_warnings, data): (&Scene, &[String], &FrameData),
    out: &frames::Outputs,
    frame: reyes::gpu_render::GpuFrame,
    times: Times,
    adapter: &str,
    reference: Option<&Reference>,
    devices: Option<Vec<reyes::stats::DeviceStats>>,
) -> Result<(), CliError> {
    // Where the renderer gave up on something (near-plane culls, split limit, nothing drawn).
    let frame_warnings = reyes::warnings::frame_warnings(data, &frame.counters);
    for w in &frame_warnings {
        log::warn!("{w}");
    }
    let all_warnings: Vec<String> = file_warnings
        .iter()
        .chain(&scene.warnings)
        .chain(&frame_warnings)
        .cloned()
        .collect();
    let mut stats = frame_stats(data, &frame, adapter, &all_warnings);
    stats.runs = Some(RunSummary::of(&times));
    stats.devices = devices;
    if let Some(reference) = reference {
        stats.image_error = Some(compare_to(reference, &frame.image)?);
    }
    frame.image.write_png(&out.image)?;
    if let Some(p) = &out.float {
        frame.image.write_pfm(p)?;
    }
    if let Some(p) = &out.depth {
        frame.image.write_depth(p)?;
    }
    if let Some(p) = &out.exr {
        frame.image.write_exr(p)?;
    }
    if let Some(p) = &out.stats {
        let text = serde_json::to_string_pretty(&stats).unwrap();
        reyes::output::write_atomic(p, (text + "\n").as_bytes())?;
    }
    if let Some(line) = stage_text(&stats.gpu_ms_per_stage) {
        reyes_cli::progress::note(line);
    }
    reyes_cli::progress::note(format!(
        "wrote {} ({}x{}, {}{}: {} grids, {} micropolygons, {})",
        out.image.display(),
        data.frame.width,
        data.frame.height,
        frame.run.strategy,
        match frame.buckets {
            1 => String::new(),
            n => format!(
                " in {n} buckets, {:.1} MiB working memory",
                frame.peak_working_bytes as f64 / (1 << 20) as f64
            ),
        },
        stats.grids_diced,
        stats.micropolygons,
        times_text(stats.runs.as_ref(), stats.gpu_ms, frame.wall_ms)
    ));
    Ok(())
}

/// With `--stage-times` (each procedure timed apart), the last frame's GPU ms per stage as one
/// line, so that they are seen without `--stats`; `None` for a run timed as one.
fn stage_text(stages: &StageTimes) -> Option<String> {
    let StageTimes::PerStage {
        bound,
        splitu,
        splitv,
        diceshade,
        dicesmall,
        queue_work,
        resolve,
    } = stages
    else {
        return None;
    };
    let resolve = resolve.map_or("n/a".into(), |r| format!("{r:.3}"));
    Some(format!(
        "GPU ms per stage (last run): bound {bound:.3}, splitu {splitu:.3}, splitv {splitv:.3}, \
         diceshade {diceshade:.3}, dicesmall {dicesmall:.3}, queue work {queue_work:.3}, \
         resolve {resolve}"
    ))
}

/// `--compare-to`: the image error of `image` against the reference, printed (stderr) and
/// returned for the statistics. Errors when the sizes differ.
fn compare_to(
    (path, reference): &Reference,
    image: &FrameImage,
) -> Result<reyes::stats::ImageErrorStats, CliError> {
    if (reference.width, reference.height) != (image.width, image.height) {
        return Err(CliError::CompareToSize {
            path: path.clone(),
            reference: (reference.width, reference.height),
            frame: (image.width, image.height),
        });
    }
    let e = reyes_accuracy::image_error::image_error(reference, image);
    reyes_cli::progress::note(format!(
        "image error against {}: PSNR {:.2} dB, FLIP mean {:.4}",
        path.display(),
        e.psnr_db,
        e.flip_mean
    ));
    Ok(reyes::stats::ImageErrorStats {
        reference: path.display().to_string(),
        psnr_db: e.psnr_db,
        flip_mean: e.flip_mean,
    })
}

/// The frame's times as `reyes render` prints them: one run's GPU and wall ms; of several
/// (`--runs N`), the median GPU ms (± MAD) of the N timed frames beside the last one's wall ms.
/// `gpu_ms` is the last frame's; "n/a" without timestamps.
fn times_text(runs: Option<&RunSummary>, gpu_ms: Option<f64>, last_wall_ms: f64) -> String {
    match runs.filter(|r| r.count > 1) {
        Some(r) => {
            let gpu = r.gpu_ms.as_ref().map_or("GPU n/a".into(), |m| {
                format!("GPU {:.3} ± {:.3} ms (median ± MAD)", m.median, m.mad)
            });
            format!(
                "{} runs: {gpu}, last run wall {last_wall_ms:.1} ms",
                r.count
            )
        }
        None => {
            let gpu = gpu_ms.map_or("GPU n/a".into(), |v| format!("GPU {v:.3} ms"));
            format!("{gpu}, wall {last_wall_ms:.1} ms")
        }
    }
}

fn main() -> ExitCode {
    // Usage errors exit 2 naming the flag; --help and --version print to stdout and exit 0.
    let cli = Cli::parse();
    if let Err(e) = cli.command.check_conflicts() {
        use clap::CommandFactory;
        Cli::command()
            .error(clap::error::ErrorKind::ArgumentConflict, e)
            .exit();
    }
    reyes::driver_env::ensure_xdg_runtime_dir();
    reyes_cli::logging::init();
    let name = cli.command.name();
    let result = match cli.command {
        Command::Render(a) => run(a),
        Command::Measure(a) => measure::main(a),
        Command::Holes(a) => holes::main(a),
        Command::Sweep(a) => sweep::main(a),
        Command::Drift(a) => drift::main(a),
        Command::Bench(a) => bench::main(a),
        Command::View(a) => view::main(a),
        Command::Devices => multi::list_devices(),
    };
    match result {
        // A table or report that could not be written (reported when it failed).
        Ok(()) if reyes_cli::stdout::failed() => ExitCode::FAILURE,
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("reyes {name}: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_runs_print_the_median_gpu_time_beside_the_last_wall_time() {
        let times = [(Some(2.0), 10.0), (Some(1.0), 30.0), (Some(4.0), 20.0)];
        let s = RunSummary::of(&times);
        assert_eq!(
            times_text(Some(&s), Some(4.0), 20.0),
            "3 runs: GPU 2.000 ± 1.000 ms (median ± MAD), last run wall 20.0 ms"
        );
        let no_timestamps = RunSummary::of(&[(None, 10.0), (None, 12.0)]);
        assert_eq!(
            times_text(Some(&no_timestamps), None, 12.0),
            "2 runs: GPU n/a, last run wall 12.0 ms"
        );
        let one = RunSummary::of(&[(Some(1.5), 9.0)]);
        assert_eq!(
            times_text(Some(&one), Some(1.5), 9.0),
            "GPU 1.500 ms, wall 9.0 ms"
        );
        assert_eq!(times_text(None, None, 9.0), "GPU n/a, wall 9.0 ms");
    }

    #[test]
    fn stage_times_print_one_line_only_when_timed_apart() {
        let apart = StageTimes::PerStage {
            bound: 0.25,
            splitu: 0.1,
            splitv: 0.0926,
            diceshade: 0.9,
            dicesmall: 0.2,
            queue_work: 0.0,
            resolve: None,
        };
        assert_eq!(
            stage_text(&apart).unwrap(),
            "GPU ms per stage (last run): bound 0.250, splitu 0.100, splitv 0.093, diceshade \
             0.900, dicesmall 0.200, queue work 0.000, resolve n/a"
        );
        let whole = StageTimes::Whole {
            schedule: Some(1.0),
            note: None,
            resolve: Some(0.03),
        };
        assert_eq!(stage_text(&whole), None);
    }
}
