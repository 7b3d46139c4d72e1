//! `reyes bench --devices`: the timed frames spread over several devices of one process.
//! Each device (its own thread, its own pipelined renderer, `reyes::realtime`) renders the
//! warm-up frames on its own and raises its clocks; then the timed frames go to the devices
//! from one shared counter, [`CHUNK`] frames at a time (a device pipelines the frames of its
//! chunk), until none is left. Frames per second over all devices: timed frames over the wall
//! time from the start of the timed phase to the last frame; per device: its frames over the
//! time it spent rendering them.

use crate::bench::{BenchReport, Summary};
use crate::cli::BenchCmd;
use crate::error::CliError;
use reyes::devices::{self, OpenedDevice};
use reyes::frame::RenderOptions;
use reyes::gpu_render::{WARM_UP, required_features};
use reyes::progress::NoProgress;
use reyes::realtime::{IN_FLIGHT, Pixels, RealtimeFrame, RealtimeRenderer};
use reyes::scene::Scene;
use scheduler::RunError;
use serde::Serialize;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Barrier, Mutex, OnceLock};
use std::time::Instant;

/// Timed frames a device takes at a time: enough to keep its pipeline full between takes.
pub const CHUNK: usize = 2 * IN_FLIGHT;

/// One device's share of `reyes bench --devices`.
#[derive(Debug, Serialize)]
pub struct DeviceBench {
    /// Its position in the `--devices` list.
    pub slot: usize,
    /// `#N name (backend)`, N its adapter's index.
    pub device: String,
    /// Timed frames it rendered.
    pub frames: u32,
    /// Its frames over `busy_ms`.
    pub fps: f64,
    /// Host time it spent rendering its chunks, ms.
    pub busy_ms: f64,
    /// Its frames' wall ms (between completions within a chunk).
    pub wall_ms: Option<Summary>,
    /// Its frames' GPU ms; null without timestamps.
    pub gpu_ms: Option<Summary>,
}

/// What a device's thread timed: its frames (with their index among the timed ones) and busy
/// ms.
type Timed = (Vec<(usize, RealtimeFrame)>, f64);

pub fn main(a: BenchCmd) -> Result<(), CliError> {
    let selection = a.devices.clone().expect("called with --devices");
    let crate::setup::Setup {
        scene,
        name,
        options,
    } = crate::setup::Setup::load(a.scene.as_deref(), &a.render)?;
    let mut opened = devices::open(&selection, required_features())?;
    for d in &mut opened {
        crate::setup::trust_loops(&mut d.gpu);
    }
    let step = if a.turntable {
        360.0 / a.frames as f64
    } else {
        0.0
    };
    let angle = |i: u32| (a.angle + step * i as f64).to_radians();
    let timed: Vec<f64> = (0..a.frames).map(angle).collect();
    let warm: Vec<f64> = (0..a.warmup).map(|i| angle(i % a.frames)).collect();
    let names: Vec<String> = opened.iter().map(OpenedDevice::name).collect();
    eprintln!("{} devices: {}", names.len(), names.join(", "));
    let n = opened.len();
    let chunk = CHUNK.min(timed.len().div_ceil(n)).max(1);
    let chunks: Vec<&[f64]> = timed.chunks(chunk).collect();
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    // Every thread reaches both gates, also after an error (then the others stop).
    let (gate, end) = (Barrier::new(n), Barrier::new(n));
    let start = OnceLock::new();
    let bar = reyes_cli::progress::bar(timed.len() as u64, "timed frames over the devices");
    let results: Mutex<Vec<Option<Result<Timed, CliError>>>> =
        Mutex::new((0..n).map(|_| None).collect());
    let shared = Run {
        a: &a,
        scene: (&scene, &options, &name),
        angles: (&warm, &timed, step),
        chunks: (&chunks, chunk),
        next: &next,
        failed: &failed,
        gates: (&gate, &end),
        start: &start,
        bar: &bar,
        results: &results,
        names: &names,
    };
    let report = std::thread::scope(|s| {
        let handles: Vec<_> = (opened.into_iter().enumerate())
            .map(|(d, device)| {
                let shared = &shared;
                s.spawn(move || device_thread(shared, d, device))
            })
            .collect();
        let mut report = None;
        for h in handles {
            if let Some(r) = h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)) {
                report = Some(r);
            }
        }
        report.expect("the first device's thread reports")
    });
    bar.finish_and_clear();
    let report = report?;
    if a.json {
        reyes_cli::outln!("{}", serde_json::to_string_pretty(&report).unwrap());
    } else {
        crate::bench::print_table(&report);
    }
    Ok(())
}

/// What the devices' threads share.
struct Run<'a> {
    a: &'a BenchCmd,
    scene: (&'a Scene, &'a RenderOptions, &'a str),
    /// Warm-up and timed angles (radians), degrees per frame.
    angles: (&'a [f64], &'a [f64], f64),
    /// The timed angles in chunks, and the chunk length.
    chunks: (&'a [&'a [f64]], usize),
    next: &'a AtomicUsize,
    failed: &'a AtomicBool,
    /// All ready (timing starts), all done.
    gates: (&'a Barrier, &'a Barrier),
    start: &'a OnceLock<Instant>,
    bar: &'a indicatif::ProgressBar,
    results: &'a Mutex<Vec<Option<Result<Timed, CliError>>>>,
    names: &'a [String],
}

/// One device's thread: builds its renderer and warms up, waits for the others, takes
/// chunks of timed frames until none is left, waits for the others; the first device's
/// thread then makes the report (and `-o`'s image) and returns it.
fn device_thread(
    run: &Run,
    d: usize,
    device: OpenedDevice,
) -> Option<Result<BenchReport, CliError>> {
    let a = run.a;
    let gpu = &device.gpu;
    let (scene, options, name) = run.scene;
    let (warm, timed, step) = run.angles;
    let (chunks, chunk) = run.chunks;
    let setup = (|| {
        let strategy = a.render.strategy_for(gpu);
        let mut r = RealtimeRenderer::new(gpu, scene, options, strategy, Pixels::None)?;
        scheduler::clocks::raise_clocks(gpu, WARM_UP)?;
        r.render(gpu, warm, &NoProgress)?;
        Ok::<_, RunError>(r)
    })()
    .map_err(|e| at(&device, e));
    if setup.is_err() {
        run.failed.store(true, Ordering::Relaxed);
    }
    run.gates.0.wait();
    let start = *run.start.get_or_init(Instant::now);
    let mut r = match setup {
        Ok(r) => Some(r),
        Err(e) => {
            run.results.lock().unwrap_or_else(|p| p.into_inner())[d] = Some(Err(e));
            None
        }
    };
    if let Some(r) = r.as_mut() {
        let (mut mine, mut busy) = (Vec::new(), 0.0);
        let result = loop {
            if run.failed.load(Ordering::Relaxed) {
                break Ok(());
            }
            let k = run.next.fetch_add(1, Ordering::Relaxed);
            let Some(angles) = chunks.get(k) else {
                break Ok(());
            };
            let t0 = Instant::now();
            match r.render(gpu, angles, &|n| run.bar.inc(n)) {
                Ok(frames) => {
                    busy += t0.elapsed().as_secs_f64() * 1e3;
                    mine.extend((k * chunk..).zip(frames));
                }
                Err(e) => {
                    run.failed.store(true, Ordering::Relaxed);
                    let first = k * chunk;
                    let last = first + angles.len() - 1;
                    let e = RunError::Device(format!("timed frames {first}-{last}: {e}"));
                    break Err(at(&device, e));
                }
            }
        };
        run.results.lock().unwrap_or_else(|p| p.into_inner())[d] =
            Some(result.map(|()| (mine, busy)));
    }
    run.gates.1.wait();
    let span_ms = start.elapsed().as_secs_f64() * 1e3;
    if d != 0 {
        return None;
    }
    let results = std::mem::take(&mut *run.results.lock().unwrap_or_else(|p| p.into_inner()));
    Some((|| {
        let mut all: Vec<(usize, RealtimeFrame)> = Vec::new();
        let mut per_device = Vec::new();
        for (slot, result) in results.into_iter().enumerate() {
            let (frames, busy_ms) = result.expect("every device's thread stores its result")?;
            let wall: Vec<f64> = frames.iter().map(|f| f.1.wall_ms).collect();
            let gpu_ms: Option<Vec<f64>> = frames.iter().map(|f| f.1.gpu_ms).collect();
            per_device.push(DeviceBench {
                slot,
                device: run.names[slot].clone(),
                frames: frames.len() as u32,
                fps: frames.len() as f64 / (busy_ms / 1e3).max(1e-9),
                busy_ms,
                wall_ms: Summary::of(&wall),
                gpu_ms: gpu_ms.as_deref().and_then(Summary::of),
            });
            all.extend(frames);
        }
        all.sort_by_key(|f| f.0);
        let frames: Vec<RealtimeFrame> = all.into_iter().map(|f| f.1).collect();
        let mut r = r.expect("an error of this device is returned above");
        let strategy = r.strategy();
        let mut report = crate::bench::report(a, name, gpu, strategy, &r, step, &frames, timed);
        report.adapter = run.names.join(" + ");
        report.fps = frames.len() as f64 / (span_ms / 1e3);
        report.devices = Some(per_device);
        if let Some(out) = &a.out {
            r.set_pixels(gpu, Pixels::Rgba8)?;
            let last = r.render(gpu, &timed[timed.len() - 1..], &NoProgress)?;
            let (w, h, _) = r.frame_size();
            let img = image::RgbaImage::from_raw(w, h, last[0].rgba8.clone().unwrap_or_default())
                .ok_or(reyes::Error::BufferSizeMismatch)?;
            reyes::output::write_atomic(out, &reyes::output::png(&img)?)?;
            eprintln!("wrote {}", out.display());
        }
        Ok(report)
    })())
}

/// A device's error, naming the device.
fn at(device: &OpenedDevice, e: RunError) -> CliError {
    RunError::Device(format!("{}: {e}", device.name())).into()
}
