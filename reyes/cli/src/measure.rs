//! `reyes measure [SCENE] [render options] [--ref-samples N] [--reference-png OUT.png] [--json]`:
//! renders on the GPU (a warm-up frame, 0.5 s of full GPU load (clocks), one more frame, then
//! `--runs N` timed ones, median reported) and measures the frame
//! against the exact surfaces (`reyes::accuracy`): geometric error and size of the
//! micropolygons, PSNR and FLIP against an f64 reference render, pinholes. The reference
//! render shows a progress bar on a terminal (`reyes_cli::progress`).

use crate::cli::MeasureCmd;
use crate::error::CliError;
use crate::setup::{self, Setup};
use reyes::frame::FrameData;
use reyes::gpu_render::{GpuFrame, GpuRenderer, RendererConfig};
use reyes::progress::NoProgress;
use reyes::stats::frame_stats;
use reyes_accuracy::exact_image::{ReferenceImage, render_reference};
use reyes_accuracy::geometry::geometry;
use reyes_accuracy::image_error::image_error;
use reyes_accuracy::measure::{Measurement, MetricsCpuMs, pinhole_count};
use scheduler::Gpu;

/// The last of several timed frames, and each timed frame's GPU ms (`None` without
/// timestamps) and wall ms.
pub type TimedFrames = (GpuFrame, Vec<Option<f64>>, Vec<f64>);

/// [`GpuRenderer::timed_frames`]: the last frame and each timed frame's GPU and wall ms.
pub fn timed_frames(
    gpu: &Gpu,
    renderer: &GpuRenderer,
    data: &FrameData,
    runs: u32,
) -> Result<TimedFrames, CliError> {
    let t = renderer.timed_frames(gpu, data, runs, &NoProgress)?;
    Ok((t.last, t.gpu_ms, t.wall_ms))
}

/// Runs the subcommand.
pub fn main(a: MeasureCmd) -> Result<(), CliError> {
    let (json, ref_samples, reference_png) = (a.json, a.ref_samples, &a.reference_png);
    let setup = Setup::load(a.scene.as_deref(), &a.render)?;
    let data = setup.frame_data()?;
    let gpu = setup::open_gpu()?;
    let config = RendererConfig::new(a.render.strategy_for(&gpu)).features(data.features());
    let renderer = setup::renderer(&gpu, config)?;
    let Setup { scene, name, .. } = setup;
    let (frame, gpu_ms, wall_ms) = timed_frames(&gpu, &renderer, &data, a.runs)?;
    let mut stats = frame_stats(&data, &frame, &gpu.adapter_name(), &scene.warnings);
    let gpu_ms: Vec<f64> = gpu_ms.into_iter().flatten().collect();
    if !gpu_ms.is_empty() {
        stats.gpu_ms = Some(scheduler::stats::median_and_mad(&gpu_ms).0);
    }
    stats.wall_ms = scheduler::stats::median_and_mad(&wall_ms).0;
    if let Some(p) = &a.out {
        frame.image.write_png(p)?;
    }
    let (w, h) = (data.frame.width, data.frame.height);
    let rows = reyes_cli::progress::bar(h as u64, "reference render: pixel rows");
    let reference: ReferenceImage = render_reference(&scene, w, h, ref_samples, &|n| rows.inc(n));
    rows.finish_and_clear();
    if let Some(p) = &reference_png {
        reference.image.write_png(p)?;
    }
    let t = std::time::Instant::now();
    let geom = geometry(&scene, &data);
    let geometry_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = std::time::Instant::now();
    let img = image_error(&reference.image, &frame.image);
    let image_ms = t.elapsed().as_secs_f64() * 1e3;
    let m = Measurement {
        scene: &name,
        stats: &stats,
        geometry: &geom,
        image: &img,
        pinholes: pinhole_count(&frame.image, &reference),
        coverage_px: frame.image.rgba.iter().map(|p| p[3] as f64).sum(),
        reference: &reference,
        runs: a.runs.max(1),
        metrics_cpu_ms: MetricsCpuMs {
            reference: reference.cpu_ms,
            geometry: geometry_ms,
            image_error: image_ms,
        },
    };
    let out = serde_json::to_value(m.report())?;
    if json {
        reyes_cli::outln!("{out}");
    } else {
        for (k, v) in out.as_object().into_iter().flatten() {
            reyes_cli::outln!("{k:>32}: {v}");
        }
    }
    Ok(())
}
