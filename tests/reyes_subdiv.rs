//! Subdivision surfaces (`SubdivisionMesh "catmull-clark"`) through the whole pipeline: the
//! field's tetrahedron and a cube as closed limit surfaces, rendered by both strategies
//! (identical images) and the CPU twin (same decisions, image within the GPU tests'
//! tolerance), their coverage against the exact f64 coverage of the same patches, and no
//! pinholes: every pixel the exact coverage fills is filled. Runs on lavapipe in CI; the
//! adapter comes from the environment and a missing one fails loudly.

use reyes::cpu_render::render_cpu;
use reyes::frame::{FrameData, RenderOptions};
use reyes::scene::Scene;
use reyes::stages;
use scheduler::StrategyKind;

mod common;
use common::{CPU_TWIN_OVER, compare, coverage_disagreement, gpu, renderer};

const W: u32 = 96;
const H: u32 = 72;

/// Renders `s` at W x H with both strategies and the CPU twin and checks them against each
/// other and against the exact coverage of the patches.
fn renders_closed(name: &str, mut s: Scene) {
    s.width = W;
    s.height = H;
    s.pixel_samples = (4, 4);
    let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
    let cpu = render_cpu(&data);
    let mk = renderer(StrategyKind::Megakernel)
        .render(gpu(), &data)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let mp = renderer(StrategyKind::Multipass)
        .render(gpu(), &data)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(
        mk.image == mp.image,
        "{name}: the strategies' images differ"
    );
    assert_eq!(
        mk.run.executed.as_slice(),
        cpu.executed.as_slice(),
        "{name}: items per stage, GPU and CPU twin"
    );
    for c in [stages::C_MICROPOLYGONS, stages::C_CULL_OFFSCREEN] {
        assert_eq!(mk.counters[c], cpu.counters[c], "{name}: counter {c}");
    }
    let (max, over) = compare(&mk.image, &cpu.image);
    assert!(
        over < CPU_TWIN_OVER,
        "{name}: {:.2}% of pixels differ from the CPU twin (max {max})",
        over * 100.0
    );
    let exact = reyes::reference::coverage(&s, W, H, 4);
    let dis = coverage_disagreement(&mk.image, &exact);
    let full = exact.frac.iter().filter(|&&f| f == 1.0).count();
    // Pinholes: pixels inside the exact silhouette (the pixel and its 8 neighbours fully
    // covered) that the render leaves part empty.
    let alpha: Vec<f32> = mk.image.rgba.iter().map(|p| p[3]).collect();
    let holes = reyes::reference::pinholes(&alpha, &exact);
    eprintln!(
        "{name}: {} patches, {full} full pixels, {holes} holes, {:.2}% pixels off",
        s.patches.len(),
        dis * 100.0
    );
    assert!(
        full > 500,
        "{name}: the surface should fill the frame's middle"
    );
    assert_eq!(holes, 0, "{name}: pinholes");
    assert!(dis < 0.005, "{name}: {:.2}% of pixels off", dis * 100.0);
}

/// The field's tetrahedron (a K-3D export; every vertex extraordinary): a smooth blob.
#[test]
fn the_field_subdivision_tetrahedron_renders_closed() {
    let p = reyes::shared_data_dir().join("field/exporters/subdiv-tetrahedron.rib");
    let s = reyes::scene::load_rib(&p)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        .into_scene();
    assert!(
        !s.warnings.iter().any(|w| w.contains("SubdivisionMesh")),
        "{:?}",
        s.warnings
    );
    renders_closed("subdiv-tetrahedron.rib", s);
}

/// A cube with one creased edge and a corner: the rounded cube, closed.
#[test]
fn a_creased_cube_renders_closed() {
    let rib = "Projection \"perspective\" \"fov\" 40\nTranslate 0 0 6\nRotate 30 1 1 0\n\
               WorldBegin\nSurface \"plastic\"\n\
               SubdivisionMesh \"catmull-clark\" [4 4 4 4 4 4] \
               [0 2 3 1 4 5 7 6 0 1 5 4 2 6 7 3 0 4 6 2 1 3 7 5] \
               [\"crease\" \"corner\"] [2 1 1 1] [0 1 6] [2.5 10] \
               \"P\" [-1 -1 -1 1 -1 -1 -1 1 -1 1 1 -1 -1 -1 1 1 -1 1 -1 1 1 1 1 1]\n\
               WorldEnd\n";
    let s = reyes::scene::parse_rib(rib, "cube.rib").unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    renders_closed("creased cube", s);
}
