//! Renders a RIB file to a PNG through the `reyes` library, without the command line:
//! `cargo run -p reyes --example render_rib -- scene.rib out.png` (no arguments: the built-in
//! teapot to `teapot.png`). The scene's own camera and `Format` decide the image; the frame
//! runs on the first adapter with 64-bit atomics (`WGPU_ADAPTER_NAME` picks one) under the
//! megakernel, and the CPU twin of the same pipeline renders it again for comparison.

use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::{GpuRenderer, RendererConfig, required_features};
use reyes::{cpu_render, scene};
use scheduler::{Gpu, StrategyKind};
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Mesa's Vulkan drivers want a runtime folder; without a login session they complain.
    reyes::driver_env::ensure_xdg_runtime_dir();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = match args.first() {
        Some(path) => scene::load(Path::new(path))?,
        None => scene::builtin_teapot(),
    };
    let out = args.get(1).map_or("teapot.png", String::as_str);
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    // The frame: root patches, camera and tables, at the scene's resolution.
    let data = FrameData::new(&scene, &RenderOptions::default())?;
    let gpu = Gpu::from_env_requiring(required_features())?;
    let config = RendererConfig::new(StrategyKind::Megakernel).features(data.features());
    let frame = GpuRenderer::new(&gpu, config)?.render(&gpu, &data)?;
    frame.image.write_png(Path::new(out))?;
    // The CPU twin renders the same frame; f32 rounding differs between the two in a few
    // pixels only (the tests bound the share).
    let cpu = cpu_render::render_cpu(&data);
    let (_, share) = frame.image.compare(&cpu.image);
    println!(
        "{out}: {}x{}, {} micropolygons, {:.3}% of pixels off the CPU twin by more than 2 steps",
        frame.image.width,
        frame.image.height,
        frame.counters[reyes::stages::C_MICROPOLYGONS],
        share * 100.0,
    );
    Ok(())
}
