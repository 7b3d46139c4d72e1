//! Occlusion culling in Bound (`reyes::stages::hiz`, docs/reyes.md *Occlusion culling*): the
//! image is the same bits with and without it, on the GPU (lavapipe) and in the CPU twin, on
//! the test scenes; on a stacked scene of screen-filling layers every hidden layer is culled
//! at its root patches, so the frame does exactly the front layer's work; and the counter
//! counts what was culled. Counts, never times.

use reyes::cpu_render::render_cpu;
use reyes::frame::{FrameData, RenderOptions};
use reyes::scene::{self, Scene, stacked::stacked_rib};
use reyes::stages::{C_CULL_OCCLUDED, C_MICROPOLYGONS};
use scheduler::StrategyKind;

mod common;
use common::{CPU_TWIN_OVER, compare, gpu, renderer, small};

fn load(rel: &str) -> Scene {
    let p = reyes::shared_data_dir().join(rel);
    scene::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn with(o: &RenderOptions, occlusion: bool) -> RenderOptions {
    let occlusion = match occlusion {
        true => reyes::frame::Occlusion::On,
        false => reyes::frame::Occlusion::Off,
    };
    RenderOptions {
        occlusion,
        ..o.clone()
    }
}

/// Renders `scene` with and without occlusion culling on the CPU twin and on the GPU
/// (multi-pass; a bucketed render too when `budget`) and asserts the same image bits each
/// way; the GPU follows the twin within the tolerance of `reyes_gpu`. Returns the twin's
/// (micropolygons, occluded) with culling on and off.
fn same_image(name: &str, scene: &Scene, o: &RenderOptions) -> [(u64, u64); 2] {
    let on = FrameData::new(scene, &with(o, true)).unwrap();
    let off = FrameData::new(scene, &with(o, false)).unwrap();
    let (c_on, c_off) = (render_cpu(&on), render_cpu(&off));
    assert!(c_on.image.rgba.iter().any(|p| p[3] > 0.0), "{name}: empty");
    assert!(
        c_on.image == c_off.image,
        "{name}: CPU twin image changed by culling"
    );
    assert_eq!(
        c_off.counters[C_CULL_OCCLUDED], 0,
        "{name}: culled while off"
    );
    let r = renderer(StrategyKind::Multipass);
    let (g_on, g_off) = (
        r.render(gpu(), &on).unwrap(),
        r.render(gpu(), &off).unwrap(),
    );
    assert!(
        g_on.image == g_off.image,
        "{name}: GPU image changed by culling"
    );
    assert_eq!(
        g_off.counters[C_CULL_OCCLUDED], 0,
        "{name}: GPU culled while off"
    );
    let (_, over) = compare(&g_on.image, &c_on.image);
    assert!(over <= CPU_TWIN_OVER, "{name}: GPU vs CPU twin: {over}");
    let counts = |c: &[u64]| (c[C_MICROPOLYGONS], c[C_CULL_OCCLUDED]);
    eprintln!(
        "{name}: CPU on {:?} off {:?}; GPU on {:?}",
        counts(&c_on.counters),
        counts(&c_off.counters),
        counts(&g_on.counters)
    );
    [counts(&c_on.counters), counts(&c_off.counters)]
}

/// The teapot (two-sided: its front hides its back), Killeroo and two field scenes: the same
/// bits with and without culling, on the GPU and the CPU twin; a bucketed render of the teapot
/// too (a pyramid per bucket). Killeroo and the bucketed teapot cull some of their pieces.
#[test]
fn test_scenes_render_the_same_bits_with_and_without_culling() {
    let teapot = scene::builtin_teapot();
    let [on, off] = same_image("teapot", &teapot, &small(64, 48));
    assert!(on.0 <= off.0);
    let bucketed = RenderOptions {
        memory_budget: Some(16 << 10),
        ..small(64, 48)
    };
    let [on, _] = same_image("teapot in buckets", &teapot, &bucketed);
    assert!(on.1 > 0, "the bucketed teapot culls some pieces");
    let [on, _] = same_image("killeroo", &load("rib/killeroo.rib"), &small(96, 62));
    assert!(on.1 > 0, "Killeroo culls some of its back");
    same_image("chair", &load("field/chair.rib"), &small(48, 60));
    same_image("airplane", &load("field/airplane.rib"), &small(64, 48));
}

/// 16 stacked screen-filling layers of 2x2 patches: the first pass draws the front layer
/// alone, every root patch of the 15 behind it is culled (the counter says exactly 60), and
/// the frame dices exactly the micropolygons of the front layer rendered on its own; without
/// culling it dices all 24 layers. The same on the GPU and in the CPU twin, images equal.
#[test]
fn a_stacked_scene_does_only_its_front_layers_work() {
    let (layers, side) = (16, 2);
    let o = small(48, 36);
    let stack = scene::parse_rib(&stacked_rib(layers, side, 48, 36), "stacked.rib").unwrap();
    let front = scene::parse_rib(&stacked_rib(1, side, 48, 36), "front.rib").unwrap();
    let [on, off] = same_image("stacked", &stack, &o);
    let alone = render_cpu(&FrameData::new(&front, &o).unwrap());
    let hidden = ((layers - 1) * side * side) as u64;
    assert_eq!(on.1, hidden, "every hidden root patch culled");
    assert_eq!(
        on.0, alone.counters[C_MICROPOLYGONS],
        "the front layer's work"
    );
    assert!(off.0 >= on.0 * layers as u64 * 9 / 10, "{off:?} vs {on:?}");
    let g = renderer(StrategyKind::Multipass)
        .render(gpu(), &FrameData::new(&stack, &o).unwrap())
        .unwrap();
    assert_eq!(g.counters[C_CULL_OCCLUDED], hidden);
    assert_eq!(g.counters[C_MICROPOLYGONS], on.0);
}

/// One layer of 3x3 patches side by side overlaps nothing: the counter is 0 on the GPU and
/// in the twin.
#[test]
fn nothing_is_culled_where_nothing_overlaps() {
    let one = scene::parse_rib(&stacked_rib(1, 3, 48, 36), "one.rib").unwrap();
    let o = small(48, 36);
    let [on, _] = same_image("one layer", &one, &o);
    assert_eq!(on.1, 0);
    let g = renderer(StrategyKind::Multipass)
        .render(gpu(), &FrameData::new(&one, &o).unwrap())
        .unwrap();
    assert_eq!(g.counters[C_CULL_OCCLUDED], 0);
}

/// `--occlusion auto` (the default) renders in passes only where patches lie deep over each
/// other: the teapot and Killeroo (depth complexity about 1-2) in one pass, nothing culled,
/// the same micropolygons as with culling off; the 16-layer stack in passes, every hidden root
/// culled. CPU twin (the GPU follows the same `hiz::passes`, checked above).
#[test]
fn auto_culls_only_where_layers_are_deep() {
    use reyes::frame::Occlusion;
    let mode = |o: &RenderOptions, occlusion| RenderOptions {
        occlusion,
        ..o.clone()
    };
    let o = small(96, 62);
    assert_eq!(o.occlusion, Occlusion::Auto, "auto is the default");
    for (name, s) in [
        ("teapot", scene::builtin_teapot()),
        ("killeroo", load("rib/killeroo.rib")),
    ] {
        let auto = render_cpu(&FrameData::new(&s, &mode(&o, Occlusion::Auto)).unwrap());
        let off = render_cpu(&FrameData::new(&s, &mode(&o, Occlusion::Off)).unwrap());
        assert_eq!(auto.counters[C_CULL_OCCLUDED], 0, "{name}: one pass");
        assert_eq!(
            auto.counters[C_MICROPOLYGONS], off.counters[C_MICROPOLYGONS],
            "{name}"
        );
    }
    let o = small(48, 36);
    let stack = scene::parse_rib(&stacked_rib(16, 2, 48, 36), "stacked.rib").unwrap();
    let auto = render_cpu(&FrameData::new(&stack, &mode(&o, Occlusion::Auto)).unwrap());
    assert_eq!(
        auto.counters[C_CULL_OCCLUDED],
        15 * 2 * 2,
        "every hidden root culled"
    );
}
