//! GPU Reyes against its CPU twin, across strategies, and against the exact surfaces. Runs on
//! lavapipe in CI; the adapter comes from the environment and a missing one fails loudly.

use reyes::cpu_render::render_cpu;
use reyes::frame::{FrameData, RenderOptions};
use reyes::gpu_render::RendererConfig;
use reyes::image::FrameImage;
use reyes::scene::{self, Scene};
use reyes::stages;
use scheduler::StrategyKind;
use std::path::Path;

mod common;
use common::{CPU_TWIN_OVER, compare, coverage_disagreement, gpu, renderer, small};

fn data_dir() -> std::path::PathBuf {
    reyes::shared_data_dir()
}

fn load(rel: &str) -> Scene {
    let p = data_dir().join(rel);
    scene::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn gpu_image_matches_the_cpu_pipeline_and_strategies_agree_exactly() {
    let data = FrameData::new(&scene::builtin_teapot(), &small(120, 90)).unwrap();
    let cpu = render_cpu(&data);
    let mk = renderer(StrategyKind::Megakernel)
        .render(gpu(), &data)
        .unwrap();
    let mp = renderer(StrategyKind::Multipass)
        .render(gpu(), &data)
        .unwrap();
    // Sample keys are combined with atomicMax, which does not depend on the order of work:
    // both strategies must give the same bits.
    assert_eq!(
        mk.image, mp.image,
        "megakernel and multi-pass images differ"
    );
    assert_eq!(mk.counters, mp.counters);
    assert_eq!(mk.run.executed, mp.run.executed);
    // The CPU twin does the same f32 operations in the same order, so decisions and counts
    // agree exactly; pixels may differ by GPU rounding of pow/sqrt/normalize (a few ulps) that
    // moves a packed 10-bit colour by one step, or a sample lying exactly on an edge.
    assert_eq!(
        mk.run.executed.as_slice(),
        cpu.executed.as_slice(),
        "items per stage"
    );
    assert_eq!(
        mk.counters[stages::C_MICROPOLYGONS],
        cpu.counters[stages::C_MICROPOLYGONS]
    );
    let (max, over) = compare(&mk.image, &cpu.image);
    assert!(
        over < CPU_TWIN_OVER,
        "{:.3}% of pixels differ by more than 2/255 (max {max})",
        over * 100.0
    );
    assert!(
        mk.image.covered_pixels() > 1500,
        "teapot covers too little: {}",
        mk.image.covered_pixels()
    );
}

#[test]
fn paper_mode_fixed_bound_and_pixel_samples_match_the_cpu_pipeline() {
    let o = RenderOptions {
        bound_px: Some(8.0),
        pixel_samples: Some((3, 2)),
        ..small(64, 48)
    };
    let data = FrameData::new(&scene::builtin_teapot(), &o).unwrap();
    let cpu = render_cpu(&data);
    let mk = renderer(StrategyKind::Megakernel)
        .render(gpu(), &data)
        .unwrap();
    assert_eq!(mk.run.executed.as_slice(), cpu.executed.as_slice());
    let (max, over) = compare(&mk.image, &cpu.image);
    assert!(
        over < CPU_TWIN_OVER,
        "{:.3}% of pixels differ by more than 2/255 (max {max})",
        over * 100.0
    );
}

#[test]
fn uteapot_rib_renders_like_the_cpu_pipeline() {
    let s = load("rib/uteapot.rib");
    let (mk, _) = megakernel_like_cpu(&s);
    assert!(mk.image.covered_pixels() > 500);
}

/// The megakernel's 100x75 frame of `s` and the CPU twin's, asserting that at most 0.2% of
/// pixels differ by more than 2/255 (the same f32 shading, a packed colour rounding the other
/// way at a step).
fn megakernel_like_cpu(s: &Scene) -> (reyes::gpu_render::GpuFrame, reyes::cpu_render::CpuRender) {
    let data = FrameData::new(s, &small(100, 75)).unwrap();
    let cpu = render_cpu(&data);
    let mk = renderer(StrategyKind::Megakernel)
        .render(gpu(), &data)
        .unwrap();
    let (max, over) = compare(&mk.image, &cpu.image);
    assert!(
        over < CPU_TWIN_OVER,
        "{:.3}% of pixels differ by more than 2/255 (max {max})",
        over * 100.0
    );
    (mk, cpu)
}

/// Every GPU buffer sized from scene data that can be empty stays valid: no patch at all (a
/// world whose primitives were all skipped), every patch culled, buckets no patch reaches, and
/// a scene without lights or materials. Each gives an image of the requested size with alpha 0
/// and the "nothing drawn" warning, on both strategies (field input `empty-world.rib`).
#[test]
fn empty_worlds_render_an_empty_image_on_every_path() {
    let empty = scene::parse_rib(
        "Format 32 24 1\nProjection \"perspective\" \"fov\" 45\nWorldBegin\nWorldEnd\n",
        "empty.rib",
    )
    .unwrap();
    assert!(empty.patches.is_empty() && empty.materials.is_empty() && empty.lights.is_empty());
    // The teapot behind the eye: every patch is culled in Bound.
    let mut behind = scene::builtin_teapot();
    for p in &mut behind.patches {
        for c in p.cp_mut() {
            c.z = -c.z - 100.0;
        }
    }
    let cases = [
        ("no patch", FrameData::new(&empty, &small(32, 24)).unwrap()),
        (
            "all culled",
            FrameData::new(&behind, &small(32, 24)).unwrap(),
        ),
        (
            "no patch, in buckets",
            FrameData {
                memory_budget: Some(16 << 10),
                ..FrameData::new(&empty, &small(96, 64)).unwrap()
            },
        ),
    ];
    for (what, data) in &cases {
        let warnings = |c: &[u64; stages::COUNTERS]| reyes::warnings::frame_warnings(data, c);
        let cpu = render_cpu(data);
        for kind in StrategyKind::ALL {
            let out = renderer(kind)
                .render(gpu(), data)
                .unwrap_or_else(|e| panic!("{what}, {kind:?}: {e}"));
            let (w, h) = (data.frame.width, data.frame.height);
            assert_eq!((out.image.width, out.image.height), (w, h), "{what}");
            assert!(
                out.image.rgba.iter().all(|p| p[3] == 0.0),
                "{what}, {kind:?}: something was drawn"
            );
            assert!(
                out.image == cpu.image,
                "{what}, {kind:?}: differs from the CPU"
            );
            let ws = warnings(&out.counters);
            assert!(
                ws.iter().any(|m| m.starts_with("nothing was drawn")),
                "{what}, {kind:?}: {ws:?}"
            );
            assert_eq!(ws, warnings(&cpu.counters), "{what}, {kind:?}");
        }
    }
}

#[test]
fn patches_behind_the_eye_are_split_then_clipped_like_the_cpu_pipeline() {
    // Move the camera into the teapot's spout region: patches cross the near plane.
    let mut s = scene::builtin_teapot();
    let shift = s.patches[0].cp()[0];
    for p in &mut s.patches {
        for c in p.cp_mut() {
            c.z -= shift.z;
        }
    }
    s.camera.near = 0.01;
    let data = FrameData::new(&s, &small(64, 48)).unwrap();
    let mk = renderer(StrategyKind::Megakernel)
        .render(gpu(), &data)
        .unwrap();
    assert!(mk.counters[stages::C_EYE_SPLITS] > 0);
    assert!(
        mk.image
            .rgba
            .iter()
            .all(|p| p.iter().all(|v| v.is_finite()))
    );
    let cpu = render_cpu(&data);
    for c in [
        stages::C_NEAR_CLIPPED,
        stages::C_EYE_SPLITS,
        stages::C_MICROPOLYGONS,
    ] {
        assert_eq!(mk.counters[c], cpu.counters[c], "counter {c}");
    }
}

#[test]
fn closed_surface_shows_no_background_inside_its_silhouette() {
    let s = scene::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/closed_blob.rib"
    )))
    .unwrap();
    // Coarse dicing makes neighbouring grids meet at different rates (T-junctions).
    for mp_size in [1.0, 6.0] {
        let o = RenderOptions {
            mp_size,
            pixel_samples: Some((4, 4)),
            ..small(128, 96)
        };
        let data = FrameData::new(&s, &o).unwrap();
        let g = renderer(StrategyKind::Megakernel)
            .render(gpu(), &data)
            .unwrap();
        let exact = reyes::reference::coverage(&s, 128, 96, 8);
        let alpha: Vec<f32> = g.image.rgba.iter().map(|p| p[3]).collect();
        assert_eq!(
            reyes::reference::pinholes(&alpha, &exact),
            0,
            "pinholes at mp_size {mp_size}"
        );
        assert!(coverage_disagreement(&g.image, &exact) < 0.01);
    }
}

#[test]
fn rib_scenes_cover_what_the_exact_surfaces_cover() {
    // Silhouette pixels may differ (micropolygons are chords of the surface, samples are
    // jittered): at most 3% of pixels may differ by more than half their area.
    for (rel, w, h) in [("rib/uteapot.rib", 80, 60), ("rib/killeroo.rib", 120, 78)] {
        // Coverage is alpha before the imager: Killeroo's `Imager "background"` would make
        // every pixel opaque.
        let s = Scene {
            background: None,
            ..load(rel)
        };
        let data = FrameData::new(&s, &small(w, h)).unwrap();
        let g = renderer(StrategyKind::Megakernel)
            .render(gpu(), &data)
            .unwrap();
        let exact = reyes::reference::coverage(&s, w, h, 4);
        let d = coverage_disagreement(&g.image, &exact);
        assert!(
            d < 0.03,
            "{rel}: {:.2}% of pixels disagree with the exact coverage",
            d * 100.0
        );
        assert!(exact.area() > 100.0, "{rel}: scene covers almost nothing");
    }
}

#[test]
fn a_memory_budget_renders_in_buckets_to_the_same_image() {
    let scene = scene::builtin_teapot();
    let whole = FrameData::new(&scene, &small(160, 120)).unwrap();
    for kind in StrategyKind::ALL {
        let r = renderer(kind);
        let reference = r.render(gpu(), &whole).unwrap();
        assert_eq!(reference.buckets, 1);
        // 160x120 pixels of 4 samples need 600 KiB of samples alone.
        let budget = 256 << 10;
        let bucketed = FrameData {
            memory_budget: Some(budget),
            ..whole.clone()
        };
        let b = r.render(gpu(), &bucketed).unwrap();
        eprintln!(
            "{kind:?}: {} buckets ({} recut), {} working bytes (whole frame {} + queues {})",
            b.buckets,
            b.buckets_recut,
            b.peak_working_bytes,
            reference.sample_bytes,
            reference.run.queue_bytes
        );
        assert!(b.buckets >= 4, "{} buckets", b.buckets);
        assert!(b.peak_working_bytes <= budget);
        // The sample test and the jitter do not depend on the bucket, and Bound's cull keeps a
        // margin wider than any crack dilation: the image is the same bit for bit.
        assert!(
            b.image == reference.image,
            "{kind:?}: bucketed image differs"
        );
        assert!(
            b.counters[stages::C_MICROPOLYGONS] >= reference.counters[stages::C_MICROPOLYGONS],
            "buckets re-dice patches that straddle them, never fewer"
        );
    }
}

/// The built-in teapot at 96x72, and the same frame under a 64 KiB memory budget, which
/// renders in buckets whose patches do not fit the queues at once (the field report:
/// `--memory-budget 64K --strategy multipass` failed with "capacity 16, needs 19").
fn small_teapot_whole_and_tight() -> (FrameData, FrameData) {
    let whole = FrameData::new(&scene::builtin_teapot(), &small(96, 72)).unwrap();
    let tight = FrameData {
        memory_budget: Some(64 << 10),
        ..whole.clone()
    };
    (whole, tight)
}

/// Under a budget so small that a bucket's patches do not fit the queues at once (the field
/// report: `--memory-budget 64K --strategy multipass` failed with "capacity 16, needs 19"),
/// every strategy splits the bucket's patches into batches and renders the image it renders
/// without a budget, bit for bit.
#[test]
fn patches_that_do_not_fit_the_queues_render_in_batches_to_the_same_image() {
    let (whole, tight) = small_teapot_whole_and_tight();
    let (mut split, mut partial) = (0, 0);
    for kind in StrategyKind::ALL {
        let r = renderer(kind);
        let reference = r.render(gpu(), &whole).unwrap();
        let b = r
            .render(gpu(), &tight)
            .unwrap_or_else(|e| panic!("{kind:?} under 64 KiB: {e}"));
        eprintln!(
            "{kind:?}: {} buckets, {} runs, {} batches split, {} partial rounds, {} working bytes",
            b.buckets, b.runs, b.batches_split, b.run.partial_rounds, b.peak_working_bytes
        );
        partial += b.run.partial_rounds;
        assert!(
            b.image == reference.image,
            "{kind:?}: batched image differs"
        );
        assert!(
            b.peak_working_bytes <= 64 << 10,
            "{kind:?}: over the budget"
        );
        split += b.batches_split;
    }
    assert!(
        split > 0,
        "no strategy needed batches: the test no longer tests them"
    );
    // One patch's splits need more room breadth first than 64 KiB gives: the multi-passes
    // run those rounds in part (scheduler::multipass::partial), as the megakernel's priorities
    // keep its own queues short.
    assert!(
        partial > 0,
        "no multi-pass round ran in part: the test no longer tests them"
    );
}

#[test]
fn one_sided_patches_facing_away_are_culled_in_bound_like_the_cpu_pipeline() {
    let mut scene = scene::builtin_teapot();
    for p in &mut scene.patches {
        p.two_sided = false;
    }
    let data = FrameData::new(&scene, &small(120, 90)).unwrap();
    let cpu = render_cpu(&data);
    let g = renderer(StrategyKind::Megakernel)
        .render(gpu(), &data)
        .unwrap();
    eprintln!(
        "patches culled as back-facing: {}, micropolygons: {}",
        g.counters[stages::C_CULL_BACKFACE],
        g.counters[stages::C_BACKFACE]
    );
    // The teapot's far side faces away: whole patches go in Bound, before any split or dice.
    assert!(g.counters[stages::C_CULL_BACKFACE] > 0);
    assert_eq!(g.counters, cpu.counters);
    assert_eq!(g.run.executed.as_slice(), cpu.executed.as_slice());
    let (max, over) = compare(&g.image, &cpu.image);
    assert!(
        over < CPU_TWIN_OVER,
        "{:.3}% differ (max {max})",
        over * 100.0
    );
}

#[test]
fn a_t_junction_cracks_without_dilation_and_not_with_it() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/t_junction.rib");
    let s = scene::load(&path).unwrap();
    let exact = reyes::reference::exact::coverage(&s, 256, 192, 8);
    let render = |crack_dilation: bool| {
        let o = RenderOptions {
            mp_size: 20.0,
            pixel_samples: Some((4, 4)),
            crack_dilation,
            ..Default::default()
        };
        let data = FrameData::new(&s, &o).unwrap();
        let g = renderer(StrategyKind::Megakernel)
            .render(gpu(), &data)
            .unwrap();
        let cpu = render_cpu(&data);
        let alpha = |img: &FrameImage| img.rgba.iter().map(|p| p[3]).collect::<Vec<_>>();
        let holes = reyes::reference::exact::pinholes(&alpha(&g.image), &exact);
        assert_eq!(
            holes,
            reyes::reference::exact::pinholes(&alpha(&cpu.image), &exact),
            "the CPU twin sees the same cracks"
        );
        holes
    };
    let without = render(false);
    let with = render(true);
    eprintln!("pinholes: {without} without crack dilation, {with} with it");
    // Without dilation the coarse lower grid's chords leave slivers between the two grids;
    // this proves the scene exercises the cracks the dilation is there for.
    assert!(
        without > 0,
        "no cracks without dilation: the test scene proves nothing"
    );
    assert_eq!(with, 0, "cracks remain with crack dilation");
}

/// A renderer compiled for a scene's features only (`SceneFeatures`: no rational patches,
/// primitive variables or transparency for the teapot) draws the same image as the one compiled
/// for every feature (bit for bit on lavapipe; within one 8-bit step on a GPU), with the same
/// counters, and refuses a frame that needs more than it was built for.
#[test]
fn a_renderer_compiled_for_the_scenes_features_draws_the_same_image() {
    use reyes::frame::SceneFeatures;
    let scene = scene::builtin_teapot();
    let data = FrameData::new(&scene, &small(96, 72)).unwrap();
    assert_eq!(data.features(), SceneFeatures::default());
    for kind in [StrategyKind::Megakernel, StrategyKind::Multipass] {
        let config = RendererConfig::new(kind).features(data.features());
        let plain = reyes::gpu_render::GpuRenderer::new(gpu(), config).unwrap();
        let a = plain.render(gpu(), &data).unwrap();
        let b = renderer(kind).render(gpu(), &data).unwrap();
        assert_eq!(a.counters, b.counters);
        if gpu().is_cpu_adapter() {
            assert!(a.image == b.image, "{kind:?}: images differ");
        } else {
            // A GPU's compiler may contract multiply-adds differently in two different
            // programs (seen on NVIDIA: one pixel of thousands off by 4e-4), which moves a
            // colour by less than one 8-bit step and never a sample across an edge.
            let (max, over) = a.image.compare(&b.image);
            assert!(
                max <= 1 && over == 0.0,
                "{kind:?}: images differ by {max} steps"
            );
        }
        let mut rational = scene.clone();
        rational.patches[0].w_mut()[5] = 2.0;
        let needs = FrameData::new(&rational, &small(96, 72)).unwrap();
        assert!(needs.features().rational);
        match plain.render(gpu(), &needs) {
            Err(scheduler::RunError::Program(m)) => assert!(m.contains("rational"), "{m}"),
            other => panic!(
                "{kind:?}: a rational frame on a plain renderer: {:?}",
                other.err()
            ),
        }
    }
}

/// Planar queues (word k of every item together; the default on GPUs) render the same image,
/// bit for bit, and the same counters as interleaved ones (lavapipe's default): the item layout
/// changes where a patch's words live, never what they hold. Small queues make the run grow
/// them, which moves live patches plane by plane. (The megakernel only, compiled for the
/// teapot's features as the test above does, so lavapipe's shader cache serves the interleaved
/// one: each new program costs lavapipe a long first compile. The host-driven multi-pass's
/// planar queues are checked on trees in scheduler_gpu.rs.)
#[test]
fn planar_and_interleaved_queues_draw_the_same_image() {
    use scheduler::{ItemLayout, MegakernelConfig, Scheduler};
    let scene = scene::builtin_teapot();
    let data = FrameData::new(&scene, &small(96, 72)).unwrap();
    let features = data.features();
    let config = RendererConfig::new(StrategyKind::Megakernel).features(features);
    let interleaved = reyes::gpu_render::GpuRenderer::new(gpu(), config).unwrap();
    assert_eq!(interleaved.scheduler.item_layout(), ItemLayout::Interleaved);
    let program = reyes::gpu_render::program_for(features).unwrap();
    let s = Scheduler::megakernel(
        gpu(),
        &program,
        MegakernelConfig {
            item_layout: Some(ItemLayout::Planar),
            initial_capacity: 16,
            ..Default::default()
        },
    )
    .unwrap();
    let config = RendererConfig::new(StrategyKind::Megakernel)
        .features(features)
        .scheduler(s);
    let planar = reyes::gpu_render::GpuRenderer::new(gpu(), config).unwrap();
    let (a, b) = (
        interleaved.render(gpu(), &data).unwrap(),
        planar.render(gpu(), &data).unwrap(),
    );
    assert!(a.image == b.image, "images differ");
    assert_eq!(a.counters, b.counters);
    assert!(b.run.queue_growths > 0, "{:?}", b.run);
}

/// RenderMan's `metal` surface (field input `airplane.rib` uses it): the GPU matches the CPU
/// twin within the tolerance of the test above (the same f32 shading, rounding at a step), and
/// the highlights take the surface's colour: on a red metal teapot no pixel is whitened, where
/// the same teapot in plastic (white highlights) has such pixels.
#[test]
fn metal_surfaces_render_like_the_cpu_pipeline_with_tinted_highlights() {
    let mut s = scene::builtin_teapot();
    let red = glam::DVec3::new(1.0, 0.15, 0.1);
    for m in &mut s.materials {
        *m = scene::Material {
            color: red,
            roughness: 0.05,
            ..scene::Material::standard(scene::SurfaceKind::Metal)
        };
    }
    let (mk, cpu) = megakernel_like_cpu(&s);
    // Whitened pixels (green at least 0.3 of red; the image is linear): a red metal's pixels
    // are its colour times a scalar, green/red at most 0.15; plastic adds white highlights
    // (measured: green/red up to 0.43 on this teapot).
    let greener = |img: &FrameImage| {
        (img.rgba.iter())
            .filter(|p| p[3] > 0.0 && p[1] >= 0.3 * p[0])
            .count()
    };
    assert!(cpu.image.covered_pixels() > 500);
    assert_eq!(greener(&mk.image), 0);
    for m in &mut s.materials {
        *m = scene::Material {
            color: red,
            roughness: 0.05,
            ..scene::Material::standard(scene::SurfaceKind::Plastic)
        };
    }
    let plastic = render_cpu(&FrameData::new(&s, &small(100, 75)).unwrap());
    assert!(
        greener(&plastic.image) > 0,
        "plastic shows white highlights"
    );
}

/// Fused multi-pass rounds (every procedure of a round in one dispatch; the default on GPUs,
/// off on lavapipe), and fused rounds with the sinks in a dispatch of their own, render the
/// same image, bit for bit, and the same counters as a dispatch per procedure: a round's
/// procedures read their own inputs and append to the next round's, so running them together
/// changes no item. The teapot's features, as the tests above, so
/// lavapipe's shader cache serves the per-procedure program.
#[test]
fn fused_multipass_rounds_draw_the_same_image() {
    use scheduler::{MultipassConfig, Scheduler};
    let (data, tight) = small_teapot_whole_and_tight();
    let features = data.features();
    let program = reyes::gpu_render::program_for(features).unwrap();
    let render_with = |fused, fused_sinks_apart, fused_sinks_first, data: &FrameData| {
        let s = Scheduler::multipass(
            gpu(),
            &program,
            MultipassConfig {
                fused_rounds: Some(fused),
                fused_sinks_apart,
                fused_sinks_first,
                ..Default::default()
            },
        )
        .unwrap();
        let config = RendererConfig::new(StrategyKind::Multipass)
            .features(features)
            .scheduler(s);
        let r = reyes::gpu_render::GpuRenderer::new(gpu(), config).unwrap();
        r.render(gpu(), data).unwrap()
    };
    let render_data =
        |fused, sinks_apart, data: &FrameData| render_with(fused, sinks_apart, false, data);
    let render = |fused, fused_sinks_apart| render_data(fused, fused_sinks_apart, &data);
    let (apart, fused) = (render(false, false), render(true, false));
    assert!(apart.image == fused.image, "images differ");
    assert_eq!(apart.counters, fused.counters);
    assert_eq!(apart.run.rounds, fused.run.rounds, "{:?}", fused.run);
    assert!(
        fused.run.launches < apart.run.launches,
        "fused {:?}, apart {:?}",
        fused.run,
        apart.run
    );
    // The sinks (DiceShade, DiceSmall) in a dispatch of their own, the producers (Bound and the
    // splits) in another: two dispatch groups of several procedures each.
    let sinks = render(true, true);
    assert!(
        apart.image == sinks.image,
        "images differ with the sinks apart"
    );
    assert_eq!(apart.counters, sinks.counters);
    assert_eq!(apart.run.rounds, sinks.run.rounds, "{:?}", sinks.run);
    // Each submission's plan, then per encoded round one dispatch fused, two with the sinks
    // apart, over the same submissions and encoded rounds.
    assert_eq!(sinks.run.submits, fused.run.submits);
    assert_eq!(
        sinks.run.launches - fused.run.launches,
        fused.run.launches - fused.run.submits,
        "two dispatches a round where fused has one: {:?}, fused {:?}",
        sinks.run,
        fused.run
    );
    // Under a 64 KiB budget, as patches_that_do_not_fit_the_queues_render_in_batches...: the
    // groups' dispatches through buckets, growth and rounds run in part.
    let b = render_data(true, true, &tight);
    assert!(
        apart.image == b.image,
        "the sinks apart under 64 KiB: image differs"
    );
    assert!(
        b.run.partial_rounds > 0,
        "no round ran in part: the test no longer tests them ({:?})",
        b.run
    );
    // The sinks' workgroups first in the fused round's dispatch: the same image and counters,
    // one dispatch a round, also through buckets and rounds run in part.
    let first = render_with(true, false, true, &data);
    assert!(
        apart.image == first.image,
        "images differ with the sinks first"
    );
    assert_eq!(apart.counters, first.counters);
    assert_eq!(first.run.launches, fused.run.launches, "{:?}", first.run);
    let c = render_with(true, false, true, &tight);
    assert!(
        apart.image == c.image,
        "the sinks first under 64 KiB: image differs"
    );
}

/// The multi-pass floor (`--strategy multipass-floor`) draws the host-driven multi-pass's
/// image and counters, bit for bit: its first frame is a host-driven frame that keeps every
/// item it executed, the next replays them in one round (each procedure's items in one
/// dispatch), and the depth-tested samples do not depend on the order items run in. Under a
/// memory budget the frame runs once per bucket and batch, and each run keeps its own items.
#[test]
fn the_multipass_floor_draws_the_host_driven_image() {
    let (whole, bucketed) = small_teapot_whole_and_tight();
    let floor = renderer(StrategyKind::MultipassFloor);
    for data in [&whole, &bucketed] {
        let host = renderer(StrategyKind::MultipassHost)
            .render(gpu(), data)
            .unwrap();
        let kept = floor.render(gpu(), data).unwrap();
        let replayed = floor.render(gpu(), data).unwrap();
        eprintln!(
            "host {:?}\nkept {:?}\nreplayed {:?}",
            host.run, kept.run, replayed.run
        );
        for f in [&kept, &replayed] {
            assert!(f.image == host.image, "image differs from multipass-host");
            assert_eq!(f.counters, host.counters);
            assert_eq!(f.runs, host.runs);
        }
        // One submission a run; one round a run of any items (a bucket may hold none).
        assert_eq!(
            replayed.run.submits, replayed.runs as u64,
            "{:?}",
            replayed.run
        );
        assert!(
            replayed.run.rounds <= replayed.runs as u64,
            "{:?}",
            replayed.run
        );
        assert!(
            replayed.run.launches < kept.run.launches,
            "{:?}",
            replayed.run
        );
        assert_eq!(replayed.run.executed, kept.run.executed);
    }
}
