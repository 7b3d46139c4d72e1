//! Rasterization modes (`RasterMode`, `--raster`): bounding-box rasterization leaves no holes,
//! the nearest-sample mode leaves holes where micropolygons outgrow the sample spacing and
//! few once they are well below it; per mode, every strategy draws the same image and the CPU
//! twin follows. Runs on lavapipe; the adapter comes from the environment and a missing one
//! fails loudly.

use reyes::cpu_render::render_cpu;
use reyes::frame::{FrameData, RasterMode, RenderOptions};
use reyes::image::FrameImage;
use reyes::scene::{self, Scene};
use reyes::stages;
use reyes_accuracy::holes::{Holes, holes};
use scheduler::StrategyKind;

mod common;
use common::{CPU_TWIN_OVER, compare, gpu, renderer, small};

const MODES: [RasterMode; 2] = [RasterMode::BoundingBox, RasterMode::NearestSample];

fn options(raster: RasterMode, mp_size: f32) -> RenderOptions {
    RenderOptions {
        raster,
        mp_size,
        ..small(160, 120)
    }
}

fn render(scene: &Scene, o: &RenderOptions) -> (FrameData, FrameImage) {
    let data = FrameData::new(scene, o).unwrap();
    let g = renderer(StrategyKind::Multipass)
        .render(gpu(), &data)
        .unwrap();
    (data, g.image)
}

/// The teapot at 160x120, 2x2 samples: holes against the exact coverage (4x4 samples a pixel).
#[test]
fn nearest_mode_leaves_holes_at_coarse_micropolygons_and_bbox_mode_none() {
    let s = scene::builtin_teapot();
    let exact = reyes::reference::coverage(&s, 160, 120, 4);
    let holes_of = |raster, mp_size| -> Holes {
        let (data, image) = render(&s, &options(raster, mp_size));
        let h = holes(&image, &exact, data.frame.spp_x * data.frame.spp_y);
        eprintln!("{raster:?} mp_size {mp_size}: {h:?}");
        h
    };
    let coarse = holes_of(RasterMode::NearestSample, 2.0);
    let fine = holes_of(RasterMode::NearestSample, 0.25);
    assert!(
        coarse.interior_px > 1000,
        "teapot interior too small: {coarse:?}"
    );
    // At 2 px micropolygons one sample is written per 4 pixels (16 samples): most of the
    // interior's samples stay empty.
    assert!(coarse.hole_sample_share > 0.5, "{coarse:?}");
    assert!(coarse.hole_px > coarse.interior_px / 2, "{coarse:?}");
    // At 0.25 px, 16 micropolygons a pixel (4 a sample): holes are rare.
    assert!(fine.hole_sample_share < 0.02, "{fine:?}");
    assert!(fine.hole_px * 10 < coarse.hole_px, "{fine:?} vs {coarse:?}");
    for mp_size in [2.0, 0.25] {
        let b = holes_of(RasterMode::BoundingBox, mp_size);
        assert_eq!(
            (b.hole_px, b.hole_samples),
            (0, 0),
            "bbox at {mp_size}: {b:?}"
        );
        assert_eq!(b.interior_px, coarse.interior_px);
    }
}

/// Per mode, at a micropolygon size where the modes differ: the three strategies give the same
/// bits and counters (sample keys combine by atomicMax, whatever the order of work), so does a
/// bucketed render (the nearest sample does not depend on the bucket), and the CPU twin
/// follows within the tolerance of `reyes_gpu`'s comparison (GPU rounding of pow/sqrt moves a
/// packed colour by a step; a sample exactly on an edge or equidistant may go either way).
#[test]
fn each_mode_draws_one_image_on_every_strategy_and_the_cpu_twin_follows() {
    let s = scene::builtin_teapot();
    let mut images = Vec::new();
    for raster in MODES {
        let data = FrameData::new(
            &s,
            &RenderOptions {
                raster,
                mp_size: 1.5,
                ..small(120, 90)
            },
        )
        .unwrap();
        let mp = renderer(StrategyKind::Multipass)
            .render(gpu(), &data)
            .unwrap();
        for kind in [StrategyKind::Megakernel, StrategyKind::MultipassHost] {
            let g = renderer(kind).render(gpu(), &data).unwrap();
            assert!(
                g.image == mp.image,
                "{raster:?}: {kind:?} and multipass differ"
            );
            assert_eq!(g.counters, mp.counters, "{raster:?}: {kind:?}");
        }
        let bucketed = FrameData {
            memory_budget: Some(48 << 10),
            ..data.clone()
        };
        let b = renderer(StrategyKind::Multipass)
            .render(gpu(), &bucketed)
            .unwrap();
        assert!(b.buckets >= 2, "{raster:?}: {} buckets", b.buckets);
        assert!(b.image == mp.image, "{raster:?}: bucketed image differs");
        let cpu = render_cpu(&data);
        assert_eq!(
            mp.counters[stages::C_MICROPOLYGONS],
            cpu.counters[stages::C_MICROPOLYGONS]
        );
        let (max, over) = compare(&mp.image, &cpu.image);
        assert!(
            over < CPU_TWIN_OVER,
            "{raster:?}: {:.3}% of pixels differ from the CPU twin by more than 2/255 (max {max})",
            over * 100.0
        );
        images.push(mp.image);
    }
    // The option reaches the GPU: at 1.5 px micropolygons (2.25 px², 9 samples each) the
    // nearest mode covers under half the samples bbox mode covers (measured: about a third).
    let area: Vec<f32> = (images.iter())
        .map(|i| i.rgba.iter().map(|p| p[3]).sum())
        .collect();
    assert!(
        area[1] < 0.5 * area[0],
        "covered area (sum of alpha) {area:?}"
    );
}
