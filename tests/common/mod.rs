//! What the Reyes GPU test files share: one adapter and one renderer per strategy for the
//! whole test binary (pipelines compile once), small render options, and the image comparison
//! against the CPU twin. The adapter comes from the environment like wgpu's own tests; none is
//! a failure, never a skip.

#![allow(dead_code)] // each test binary uses its own subset

mod adapter;

use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::{GpuFrame, GpuRenderer, required_features};
use reyes::image::FrameImage;
use scheduler::{Gpu, StrategyKind};
use std::sync::OnceLock;

/// Share of pixels that may differ by more than 2/255 ([`FrameImage::compare`]'s `over`)
/// between a GPU frame and its CPU twin. The twin does the GPU's f32 operations in the same
/// order, so decisions and counts agree exactly (tests assert those with `==`); a pixel may
/// still differ where the GPU rounds `pow`, `sqrt`, `normalize` or `sin` by a few ulps or fuses
/// a multiply-add, which moves a packed 10-bit colour by one step or a sample lying exactly on
/// an edge to its other side.
pub const CPU_TWIN_OVER: f64 = 0.002;

/// [`CPU_TWIN_OVER`] for scenes made to stress f32 (the hard cases: coordinates far from the
/// origin, patches through the near plane, grids of sliver micropolygons) and for rational
/// patches (a homogeneous division per point): many more samples lie within an ulp of an edge.
pub const CPU_TWIN_OVER_HARD: f64 = 0.005;

/// [`CPU_TWIN_OVER`] with motion blur and depth of field: every sample's point is moved over
/// the shutter and its lens position mapped to the disc (`sin`, `cos`), so the ulps that can
/// move a sample across an edge come at every sample rather than once per grid point.
pub const CPU_TWIN_OVER_MOTION: f64 = 0.01;

/// The one device of the test binary, shared by every test (pipelines compile once), from the
/// adapter the environment names (`WGPU_ADAPTER_NAME`, `WGPU_BACKEND`) with the features the
/// renderer needs; none is a panic, never a skip.
pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| adapter::open_gpu(required_features()))
}

pub fn renderer(kind: StrategyKind) -> &'static GpuRenderer {
    static MK: OnceLock<GpuRenderer> = OnceLock::new();
    static MP: OnceLock<GpuRenderer> = OnceLock::new();
    static MPH: OnceLock<GpuRenderer> = OnceLock::new();
    static FLOOR: OnceLock<GpuRenderer> = OnceLock::new();
    let cell = match kind {
        StrategyKind::Megakernel => &MK,
        StrategyKind::Multipass => &MP,
        StrategyKind::MultipassHost => &MPH,
        StrategyKind::MultipassFloor => &FLOOR,
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

/// `data`'s frames by every strategy, asserting identical images and counters, and the CPU
/// twin's, within [`CPU_TWIN_OVER`] of them; the first strategy's frame.
pub fn render_everywhere(data: &FrameData) -> GpuFrame {
    let mut first: Option<GpuFrame> = None;
    for kind in StrategyKind::ALL {
        let f = renderer(kind).render(gpu(), data).unwrap();
        if let Some(a) = &first {
            assert!(
                a.image == f.image,
                "{kind:?}: image differs from megakernel"
            );
            assert_eq!(a.counters, f.counters, "{kind:?}: counters");
        }
        first.get_or_insert(f);
    }
    let first = first.unwrap();
    let cpu = reyes::cpu_render::render_cpu(data);
    let (max, over) = compare(&first.image, &cpu.image);
    assert!(
        over < CPU_TWIN_OVER,
        "CPU twin: {:.3}% of pixels differ by more than 2/255 (max {max})",
        over * 100.0
    );
    first
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
