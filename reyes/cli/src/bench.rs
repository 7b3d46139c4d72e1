//! `reyes bench [SCENE] [--width W --height H] [--frames N] [--turntable] [--json]
//! [--strategy NAME] [render options]`: frames of a (turning) scene by the persistent pipelined
//! renderer (`reyes::realtime`): per-frame wall and GPU ms (median, p95) and frames per second,
//! as a table or one JSON object ([`BenchReport`], keys in docs/reyes.md). On a terminal a
//! progress bar counts the frames (`reyes_cli::progress`). With `--peer raster`, the raster peer
//! (`reyes::raster_peer`) timed the same way on the same frames, and its image against the
//! Reyes image of the first and last timed frame ([`PeerReport`]).

use crate::cli::{BenchCmd, Peer};
use crate::error::CliError;
use reyes::gpu_render::WARM_UP;
use reyes::progress::NoProgress;
use reyes::raster_peer::{PeerFrame, RasterPeer};
use reyes::realtime::{Pixels, RealtimeFrame, RealtimeRenderer};
use reyes::stages::{C_CULL_OCCLUDED, C_MICROPOLYGONS};
use scheduler::Gpu;
use scheduler::StrategyKind;
use serde::Serialize;

/// Median and 95th percentile (nearest rank) of per-frame values, with the extremes.
#[derive(Debug, Serialize)]
pub struct Summary {
    pub median: f64,
    pub p95: f64,
    pub min: f64,
    pub max: f64,
}

impl Summary {
    /// `None` for no values.
    pub fn of(values: &[f64]) -> Option<Summary> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
        let n = v.len();
        Some(Summary {
            median: if n % 2 == 1 {
                v[n / 2]
            } else {
                (v[n / 2 - 1] + v[n / 2]) / 2.0
            },
            p95: rank(0.95),
            min: v[0],
            max: v[n - 1],
        })
    }
}

/// One timed frame.
#[derive(Debug, Serialize)]
pub struct FrameRow {
    pub angle_deg: f64,
    pub wall_ms: f64,
    pub gpu_ms: Option<f64>,
    pub micropolygons: u64,
    /// Pieces culled by occlusion (`culls.occluded` of `render --stats`).
    pub occluded: u64,
    /// Why the pipelined attempt did not finish, when the frame was rendered again.
    pub rerendered: Option<String>,
}

/// What `reyes bench --json` prints.
#[derive(Debug, Serialize)]
pub struct BenchReport {
    pub scene: String,
    pub adapter: String,
    pub strategy: String,
    pub width: u32,
    pub height: u32,
    /// Pixel samples per axis.
    pub samples: [u32; 2],
    /// Timed frames.
    pub frames: u32,
    pub turntable: bool,
    pub degrees_per_frame: f64,
    /// Frames pipelined on the GPU; `false` with the reason in `not_pipelined`.
    pub pipelined: bool,
    pub not_pipelined: Option<String>,
    /// Pipelined frames cull from the previous frame (`--occlusion on`, or `auto` on a deep
    /// scene; docs/reyes.md, *Occlusion culling*). Frames not pipelined cull as `render` does.
    pub occlusion: bool,
    /// Per-frame host time between frame completions.
    pub wall_ms: Summary,
    /// Per-frame GPU time (first pass start to last pass end); null without timestamps.
    pub gpu_ms: Option<Summary>,
    /// Per-frame wall minus GPU time: what the host adds. As measured, never clamped: it can be
    /// below 0 ([`WALL_BELOW_GPU`]).
    pub wall_minus_gpu_ms: Option<Summary>,
    /// Timed frames over the sum of their wall times.
    pub fps: f64,
    pub micropolygons: Summary,
    /// Pieces culled by occlusion per frame.
    pub occluded: Summary,
    /// Frames rendered again because their fixed sizes did not suffice.
    pub rerendered: u32,
    pub per_frame: Vec<FrameRow>,
    /// `--peer`: the peer's timing and image difference; absent without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peer: Option<PeerReport>,
    /// `--devices`: each device's frames and rate (`fps` above is then over all devices:
    /// timed frames over the wall time from the first to the last); absent without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub devices: Option<Vec<crate::bench_devices::DeviceBench>>,
}

/// Steps (of 255, in the 8-bit sRGB image) a pixel of the peer may differ from Reyes's without
/// counting as different (`PeerDifference::over`).
pub const DIFFERENCE_STEPS: u8 = 8;

/// The peer of `--peer`, timed as the Reyes frames are (same angles, warm-up, pipelining).
#[derive(Debug, Serialize)]
pub struct PeerReport {
    /// `raster`.
    pub peer: String,
    /// MSAA samples the peer draws with, and the frame's pixel samples N*M it stands for
    /// (the nearest count the adapter supports when it cannot do N*M).
    pub msaa_samples: u32,
    pub msaa_wanted: u32,
    pub wall_ms: Summary,
    pub gpu_ms: Option<Summary>,
    pub fps: f64,
    /// Triangles drawn per frame (culled back faces not counted).
    pub triangles: Summary,
    /// Frames drawn again because their triangles did not fit the buffers.
    pub redrawn: u32,
    /// What the peer draws differently from what the scene asks (transparency drawn opaque).
    pub warnings: Vec<String>,
    /// The peer's image against Reyes's, on the first and last timed frame.
    pub difference: Vec<PeerDifference>,
    pub per_frame: Vec<PeerRow>,
}

/// The peer's image against the Reyes image of one frame (`FrameImage::difference`).
#[derive(Debug, Serialize)]
pub struct PeerDifference {
    pub angle_deg: f64,
    /// PSNR of the 8-bit RGBA images, dB; null when they are equal.
    pub psnr_db: Option<f64>,
    /// Share of pixels differing by more than `threshold_steps` in some channel.
    pub over: f64,
    pub threshold_steps: u8,
    /// Largest difference of a channel, in steps.
    pub max_steps: u8,
    /// Pixels with any coverage, in each image.
    pub covered_reyes: usize,
    pub covered_peer: usize,
}

/// One timed frame of the peer.
#[derive(Debug, Serialize)]
pub struct PeerRow {
    pub angle_deg: f64,
    pub wall_ms: f64,
    pub gpu_ms: Option<f64>,
    pub triangles: u64,
    /// Tessellation tiles (64 grid points of one patch): the workgroups of the point and of
    /// the quad dispatch.
    pub tiles: u32,
    pub redrawn: Option<String>,
}

pub fn main(a: BenchCmd) -> Result<(), CliError> {
    if a.devices.is_some() {
        return crate::bench_devices::main(a);
    }
    let crate::setup::Setup {
        scene,
        name,
        options,
    } = crate::setup::Setup::load(a.scene.as_deref(), &a.render)?;
    let gpu = crate::setup::open_gpu()?;
    let strategy = a.render.strategy_for(&gpu);
    let mut r = RealtimeRenderer::new(&gpu, &scene, &options, strategy, Pixels::None)?;
    let step = if a.turntable {
        360.0 / a.frames as f64
    } else {
        0.0
    };
    let angle = |i: u32| (a.angle + step * i as f64).to_radians();
    scheduler::clocks::raise_clocks(&gpu, WARM_UP)?;
    // Warm-up and timed frames in one pipelined stream, so that the first timed frame finds the
    // pipeline full as every later one does.
    let timed: Vec<f64> = (0..a.frames).map(angle).collect();
    let warm = (0..a.warmup).map(|i| angle(i % a.frames));
    let all: Vec<f64> = warm.chain(timed.iter().copied()).collect();
    let bar = reyes_cli::progress::bar(all.len() as u64, "frames (warm-up and timed)");
    let mut frames = r.render(&gpu, &all, &|n| bar.inc(n))?;
    bar.finish_and_clear();
    frames.drain(..a.warmup as usize);
    if let Some(out) = &a.out {
        r.set_pixels(&gpu, Pixels::Rgba8)?;
        let last = r.render(&gpu, &timed[timed.len() - 1..], &NoProgress)?;
        let (w, h, _) = r.frame_size();
        let img = image::RgbaImage::from_raw(w, h, last[0].rgba8.clone().unwrap_or_default())
            .ok_or(reyes::Error::BufferSizeMismatch)?;
        reyes::output::write_atomic(out, &reyes::output::png(&img)?)?;
        eprintln!("wrote {}", out.display());
    }
    let peer = match a.peer {
        Some(Peer::Raster) => {
            let o = (&scene, &options);
            Some(raster_peer(&gpu, o, &all, a.warmup, &timed, &mut r)?)
        }
        None => None,
    };
    let mut report = report(&a, &name, &gpu, strategy, &r, step, &frames, &timed);
    report.peer = peer;
    if a.json {
        reyes_cli::outln!("{}", serde_json::to_string_pretty(&report).unwrap());
    } else {
        print_table(&report);
    }
    Ok(())
}

/// Times the raster peer on `all` angles (the first `warmup` untimed) and compares its image
/// with the Reyes renderer's on the first and last of `timed`.
fn raster_peer(
    gpu: &Gpu,
    (scene, options): (&reyes::scene::Scene, &reyes::frame::RenderOptions),
    all: &[f64],
    warmup: u32,
    timed: &[f64],
    r: &mut RealtimeRenderer,
) -> Result<PeerReport, scheduler::RunError> {
    let pipelines = r.renderer().pipelines();
    let mut p = RasterPeer::with_pipelines(gpu, pipelines, scene, options, Pixels::None)?;
    let warnings = p.warnings();
    for w in &warnings {
        log::warn!("{w}");
    }
    let mut frames: Vec<PeerFrame> = p.render(gpu, all)?;
    frames.drain(..warmup as usize);
    let mut check = vec![timed[0]];
    if timed.len() > 1 && timed[timed.len() - 1] != timed[0] {
        check.push(timed[timed.len() - 1]);
    }
    r.set_pixels(gpu, Pixels::Float)?;
    p.set_pixels(gpu, Pixels::Float)?;
    let reyes = r.render(gpu, &check, &NoProgress)?;
    let peer = p.render(gpu, &check)?;
    let difference = (reyes.iter().zip(&peer).zip(&check))
        .map(|((a, b), angle)| {
            let (ra, pb) = (a.image.as_ref().unwrap(), b.image.as_ref().unwrap());
            let d = pb.difference(ra, DIFFERENCE_STEPS);
            PeerDifference {
                angle_deg: angle.to_degrees(),
                psnr_db: d.psnr_db.is_finite().then_some(d.psnr_db),
                over: d.over,
                threshold_steps: d.threshold,
                max_steps: d.max,
                covered_reyes: ra.covered_pixels(),
                covered_peer: pb.covered_pixels(),
            }
        })
        .collect();
    let (_, _, spp) = p.frame_size();
    let wall: Vec<f64> = frames.iter().map(|f| f.wall_ms).collect();
    let gpu_ms: Option<Vec<f64>> = frames.iter().map(|f| f.gpu_ms).collect();
    let tri: Vec<f64> = (frames.iter())
        .map(|f| f.counts.triangles() as f64)
        .collect();
    Ok(PeerReport {
        peer: "raster".into(),
        msaa_samples: p.msaa_samples(),
        msaa_wanted: spp[0] * spp[1],
        wall_ms: Summary::of(&wall).expect("at least one frame"),
        gpu_ms: gpu_ms.as_deref().and_then(Summary::of),
        fps: frames.len() as f64 / (wall.iter().sum::<f64>() / 1e3),
        triangles: Summary::of(&tri).expect("at least one frame"),
        redrawn: frames.iter().filter(|f| f.redrawn.is_some()).count() as u32,
        warnings,
        difference,
        per_frame: frames
            .iter()
            .map(|f| PeerRow {
                angle_deg: f.angle.to_degrees(),
                wall_ms: f.wall_ms,
                gpu_ms: f.gpu_ms,
                triangles: f.counts.triangles(),
                tiles: f.counts.tiles,
                redrawn: f.redrawn.clone(),
            })
            .collect(),
    })
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn report(
    a: &BenchCmd,
    name: &str,
    gpu: &Gpu,
    strategy: StrategyKind,
    r: &RealtimeRenderer,
    step: f64,
    frames: &[RealtimeFrame],
    angles: &[f64],
) -> BenchReport {
    let (width, height, samples) = r.frame_size();
    let wall: Vec<f64> = frames.iter().map(|f| f.wall_ms).collect();
    let gpu_ms: Option<Vec<f64>> = frames.iter().map(|f| f.gpu_ms).collect();
    let diff = gpu_ms
        .as_ref()
        .map(|g| wall.iter().zip(g).map(|(w, g)| w - g).collect::<Vec<_>>());
    let count = |c: usize| -> Vec<f64> { frames.iter().map(|f| f.counters[c] as f64).collect() };
    BenchReport {
        scene: name.into(),
        adapter: gpu.adapter_name(),
        strategy: strategy.name().into(),
        width,
        height,
        samples,
        frames: frames.len() as u32,
        turntable: a.turntable,
        degrees_per_frame: step,
        pipelined: r.not_pipelined().is_none(),
        not_pipelined: r.not_pipelined().map(String::from),
        occlusion: r.occlusion(),
        wall_ms: Summary::of(&wall).expect("at least one frame"),
        gpu_ms: gpu_ms.as_deref().and_then(Summary::of),
        wall_minus_gpu_ms: diff.as_deref().and_then(Summary::of),
        fps: frames.len() as f64 / (wall.iter().sum::<f64>() / 1e3),
        micropolygons: Summary::of(&count(C_MICROPOLYGONS)).expect("at least one frame"),
        occluded: Summary::of(&count(C_CULL_OCCLUDED)).expect("at least one frame"),
        rerendered: frames.iter().filter(|f| f.rerendered.is_some()).count() as u32,
        per_frame: (frames.iter().zip(angles))
            .map(|(f, angle)| FrameRow {
                angle_deg: angle.to_degrees(),
                wall_ms: f.wall_ms,
                gpu_ms: f.gpu_ms,
                micropolygons: f.counters[C_MICROPOLYGONS],
                occluded: f.counters[C_CULL_OCCLUDED],
                rerendered: f.rerendered.clone(),
            })
            .collect(),
        peer: None,
        devices: None,
    }
}

pub(crate) fn print_table(r: &BenchReport) {
    reyes_cli::outln!(
        "reyes bench: {} {}x{} ({}x{} samples), {}, {} frames{}, {}",
        r.scene,
        r.width,
        r.height,
        r.samples[0],
        r.samples[1],
        r.strategy,
        r.frames,
        if r.turntable {
            format!(" (turntable, {:.2} deg/frame)", r.degrees_per_frame)
        } else {
            String::new()
        },
        r.adapter
    );
    if let Some(why) = &r.not_pipelined {
        reyes_cli::outln!("not pipelined: {why}");
    }
    if r.occlusion {
        reyes_cli::outln!("occlusion culling from the previous frame (two phases)");
    }
    reyes_cli::outln!("{:<14} {:>10} {:>10}", "", "median", "p95");
    let row = |label: &str, s: Option<&Summary>| match s {
        Some(s) => reyes_cli::outln!("{label:<14} {:>10.3} {:>10.3}", s.median, s.p95),
        None => reyes_cli::outln!("{label:<14} {:>10} {:>10}", "n/a", "n/a"),
    };
    row("wall ms", Some(&r.wall_ms));
    row("GPU ms", r.gpu_ms.as_ref());
    row("wall - GPU ms", r.wall_minus_gpu_ms.as_ref());
    if let Some(note) = wall_minus_gpu_note(r.wall_minus_gpu_ms.as_ref()) {
        reyes_cli::outln!("{note}");
    }
    reyes_cli::outln!("{:<14} {:>10.0}", "micropolygons", r.micropolygons.median);
    reyes_cli::outln!("{:<14} {:>10.0}", "occluded", r.occluded.median);
    reyes_cli::outln!("{:<14} {:>10.1}", "fps", r.fps);
    reyes_cli::outln!(
        "{:<14} {:>10}",
        "re-rendered",
        format!("{} of {}", r.rerendered, r.frames)
    );
    let mut reasons: Vec<&str> = (r.per_frame.iter())
        .filter_map(|f| f.rerendered.as_deref())
        .collect();
    reasons.dedup();
    for why in reasons.iter().take(3) {
        reyes_cli::outln!("  re-rendered: {why}");
    }
    if let Some(p) = &r.peer {
        print_peer(p);
    }
    for d in r.devices.iter().flatten() {
        let gpu = d
            .gpu_ms
            .as_ref()
            .map_or("n/a".into(), |g| format!("{:.3}", g.median));
        reyes_cli::outln!(
            "device {} ({}): {} frames, {:.1} fps, busy {:.1} ms, median GPU {gpu} ms",
            d.slot,
            d.device,
            d.frames,
            d.fps,
            d.busy_ms
        );
    }
}

/// Why "wall - GPU" can be below 0. It is printed as measured rather than clamped at 0: a clamp
/// would bias its median and p95 upwards and hide the frames where the two clocks disagree.
pub const WALL_BELOW_GPU: &str = "a frame's GPU time spans its first \
pass's start to its last pass's end on the GPU's timestamp clock, its wall time the host's \
interval between two frame completions; with frames in flight together (pipelined) or clocks \
that drift (a CPU adapter's timestamps), the first can exceed the second. Shown as measured, \
not clamped.";

/// The note printed under the table when any frame's wall - GPU time was below 0: it names the
/// smallest, which the table (median, p95) may not show, then says why.
fn wall_minus_gpu_note(s: Option<&Summary>) -> Option<String> {
    s.filter(|s| s.min < 0.0).map(|s| {
        format!(
            "note: wall - GPU below 0 in some frames (smallest {:.3} ms): {WALL_BELOW_GPU}",
            s.min
        )
    })
}

fn print_peer(p: &PeerReport) {
    reyes_cli::outln!(
        "peer {}: {}x MSAA{}",
        p.peer,
        p.msaa_samples,
        if p.msaa_samples == p.msaa_wanted {
            String::new()
        } else {
            format!(
                " (the adapter cannot do {}, the frame's pixel samples)",
                p.msaa_wanted
            )
        }
    );
    reyes_cli::outln!("{:<14} {:>10} {:>10}", "", "median", "p95");
    let row = |label: &str, s: Option<&Summary>| match s {
        Some(s) => reyes_cli::outln!("{label:<14} {:>10.3} {:>10.3}", s.median, s.p95),
        None => reyes_cli::outln!("{label:<14} {:>10} {:>10}", "n/a", "n/a"),
    };
    row("wall ms", Some(&p.wall_ms));
    row("GPU ms", p.gpu_ms.as_ref());
    reyes_cli::outln!("{:<14} {:>10.0}", "triangles", p.triangles.median);
    reyes_cli::outln!("{:<14} {:>10.1}", "fps", p.fps);
    reyes_cli::outln!(
        "{:<14} {:>10}",
        "redrawn",
        format!("{} of {}", p.redrawn, p.per_frame.len())
    );
    for d in &p.difference {
        reyes_cli::outln!(
            "image vs Reyes at {:.1} deg: PSNR {}, {:.2}% of pixels off by more than {}/255 \
             (max {}), covered {} vs {}",
            d.angle_deg,
            d.psnr_db
                .map_or("inf".to_string(), |v| format!("{v:.1} dB")),
            d.over * 100.0,
            d.threshold_steps,
            d.max_steps,
            d.covered_peer,
            d.covered_reyes
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_p95_by_nearest_rank() {
        let v: Vec<f64> = (1..=20).map(|i| i as f64).collect();
        let s = Summary::of(&v).unwrap();
        assert_eq!((s.median, s.p95, s.min, s.max), (10.5, 19.0, 1.0, 20.0));
        let s = Summary::of(&[3.0]).unwrap();
        assert_eq!((s.median, s.p95), (3.0, 3.0));
        assert!(Summary::of(&[]).is_none());
    }

    /// A negative wall - GPU is kept as measured (not clamped) and explained by a note; none
    /// when every frame's host time covered its GPU time, or without timestamps.
    #[test]
    fn negative_wall_minus_gpu_is_kept_and_explained() {
        let wall = [10.0, 12.0, 11.0];
        let gpu = [10.5, 9.0, 9.5];
        let diff: Vec<f64> = wall.iter().zip(gpu).map(|(w, g)| w - g).collect();
        let s = Summary::of(&diff).unwrap();
        assert_eq!(s.min, -0.5);
        let note = wall_minus_gpu_note(Some(&s)).unwrap();
        assert!(
            note.contains("smallest -0.500 ms") && note.ends_with(WALL_BELOW_GPU),
            "{note}"
        );
        let s = Summary::of(&[0.0, 3.0]).unwrap();
        assert_eq!(wall_minus_gpu_note(Some(&s)), None);
        assert_eq!(wall_minus_gpu_note(None), None);
    }
}
