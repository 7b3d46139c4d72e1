//! What the Reyes GPU test files share: one adapter and one renderer per strategy for the
//! whole test binary (pipelines compile once), small render options, and the image comparison
//! against the CPU twin. The adapter comes from the environment like wgpu's own tests; none is
//! a failure, never a skip.

#![allow(dead_code)] // each test binary uses its own subset

use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::{GpuFrame, GpuRenderer, required_features};
use reyes::image::FrameImage;
use scheduler::{Gpu, StrategyKind};
use std::sync::OnceLock;

pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| {
        Gpu::from_env_requiring(required_features())
            .unwrap_or_else(|e| panic!("GPU tests need an adapter with 64-bit atomics: {e}"))
    })
}

pub fn renderer(kind: StrategyKind) -> &'static GpuRenderer {
    static MK: OnceLock<GpuRenderer> = OnceLock::new();
    static MP: OnceLock<GpuRenderer> = OnceLock::new();
    static MPH: OnceLock<GpuRenderer> = OnceLock::new();
    let cell = match kind {
        StrategyKind::Megakernel => &MK,
        StrategyKind::Multipass => &MP,
        StrategyKind::MultipassHost => &MPH,
    };
    cell.get_or_init(|| GpuRenderer::new(gpu(), kind).unwrap())
}

/// The megakernel's and the multi-pass strategy's frames of `data`, asserting that their
/// images are the same, bit for bit.
pub fn render_both_strategies(data: &FrameData) -> (GpuFrame, GpuFrame) {
    let a = renderer(StrategyKind::Megakernel)
        .render(gpu(), data)
        .unwrap();
    let b = renderer(StrategyKind::Multipass)
        .render(gpu(), data)
        .unwrap();
    assert!(
        a.image == b.image,
        "multipass image differs from megakernel"
    );
    (a, b)
}

pub fn small(w: u32, h: u32) -> RenderOptions {
    RenderOptions {
        width: Some(w),
        height: Some(h),
        ..Default::default()
    }
}

/// Largest per-channel difference (colour in sRGB 8-bit steps, alpha in 1/255) and the share
/// of pixels differing by more than 2 steps ([`FrameImage::compare`]).
pub fn compare(a: &FrameImage, b: &FrameImage) -> (u8, f64) {
    a.compare(b)
}

/// Share of pixels where coverage (alpha) and the exact f64 coverage disagree by more than half
/// a pixel.
pub fn coverage_disagreement(img: &FrameImage, exact: &reyes::reference::Coverage) -> f64 {
    let bad = img
        .rgba
        .iter()
        .zip(&exact.frac)
        .filter(|(p, e)| (p[3] - **e).abs() > 0.5)
        .count();
    bad as f64 / img.rgba.len() as f64
}
