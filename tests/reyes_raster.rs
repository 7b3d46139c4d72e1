//! The raster peer (`reyes::raster_peer`, `reyes bench --peer raster`): its compute
//! tessellation against the CPU evaluation of the same patches at the same (u, v), polynomial
//! and rational, and its teapot image against the Reyes image of the same frame. Runs on
//! lavapipe; a missing adapter fails loudly.

use glam::Vec3;
use reyes::frame::{FrameData, RenderOptions, homogeneous_points};
use reyes::raster_peer::{GridRate, MAX_RATE, RasterPeer, grid_rate, tessellate_cpu};
use reyes::realtime::Pixels;
use reyes::reference::closed::rational_sphere;
use reyes::scene::{self, Camera, Material, Scene, SurfaceKind};
use scheduler::StrategyKind;

mod common;
use common::{gpu, renderer, small};

const W: u32 = 96;
const H: u32 = 72;

fn sphere() -> Scene {
    Scene {
        width: W,
        height: H,
        pixel_samples: (2, 2),
        camera: Camera {
            fov_deg: 40.0,
            near: 0.1,
            far: 100.0,
            ..Camera::default()
        },
        // One-sided: the far half's quads are culled as facing away.
        patches: rational_sphere(glam::DVec3::new(0.3, -0.2, 4.0), 1.0)
            .into_iter()
            .map(|mut p| {
                p.two_sided = false;
                p
            })
            .collect(),
        materials: vec![Material::standard(SurfaceKind::Plastic)],
        ..Scene::default()
    }
}

/// Every drawn patch's grid points equal the CPU twin's (DiceShade's twin's evaluation and
/// shading of the root item) at the same (u, v): (i/nu, j/nv) inside, snapped to the
/// boundary's own segments on it (`edge_param`). Positions:
/// the same f32 formulas, but the GPU may contract multiply-adds (FMA) and its division and
/// square root differ by an ulp, over ~50 operations per point: within 1e-5 of
/// 1 + |value| (measured: about 1e-6). Colours: 10-bit sRGB channels within 2 steps (the GPU's
/// pow, normalize and sRGB encoding are approximate; measured: 1); the back-facing bit equal
/// except where the normal is within rounding of perpendicular to the view (at most 1% of the
/// points; measured: 0). Rates: the CPU twin's within one segment per side (the GPU's
/// `distance` may round a length across an integer), culled patches culled on both. Indices:
/// two triangles (a, b, c), (a, c, d) per quad, or a degenerate pair where the four corners
/// face away on a one-sided patch.
#[test]
fn tessellation_equals_the_cpu_evaluation_of_each_patch() {
    let teapot = scene::builtin_teapot();
    for (name, s) in [("teapot", teapot), ("rational sphere", sphere())] {
        let o = RenderOptions {
            mp_size: 2.0,
            ..small(W, H)
        };
        let mut peer = RasterPeer::new(gpu(), &s, &o, Pixels::None).unwrap();
        let frames = peer.render(gpu(), &[0.0]).unwrap();
        assert_eq!(frames[0].redrawn, None, "{name}");
        let t = peer.geometry(gpu()).unwrap();
        let data = FrameData::new(&s, &o).unwrap();
        assert!(
            t.counts.drawn > 0 && t.counts.over == 0,
            "{name}: {:?}",
            t.counts
        );
        let (mut worst, mut colour_worst, mut back_differs, mut points) = (0f32, 0u32, 0, 0);
        let mut backface = 0;
        for (id, p) in s.patches.iter().enumerate() {
            let [nu, nv, vb, qb] = t.grids[id];
            let h = homogeneous_points(p);
            let e: [Vec3; 16] =
                std::array::from_fn(|k| Vec3::new(h[k][0], h[k][1], h[k][2]) / h[k][3]);
            let r = grid_rate(&data.frame, &e, MAX_RATE);
            if nu == 0 {
                assert_eq!(r.n, [0, 0], "{name} patch {id}: culled on the GPU only");
                continue;
            }
            let gpu_rate = GridRate {
                n: [nu, nv],
                edges: t.edges[id],
            };
            let near = |a: &[u32], b: &[u32]| a.iter().zip(b).all(|(x, y)| x.abs_diff(*y) <= 1);
            assert!(
                near(&r.n, &gpu_rate.n) && near(&r.edges, &gpu_rate.edges),
                "{name} patch {id}: {gpu_rate:?} on the GPU, {r:?} on the CPU"
            );
            let cpu = tessellate_cpu(&data, id as u32, p, &gpu_rate);
            let gpu_points = &t.vertices[vb as usize..vb as usize + cpu.len()];
            for (g, c) in gpu_points.iter().zip(&cpu) {
                for (a, b) in [(g.x, c.x), (g.y, c.y), (g.w, c.w)] {
                    worst = worst.max((a - b).abs() / (1.0 + b.abs()));
                }
                for k in [0, 10, 20] {
                    let (a, b) = ((g.color >> k) & 1023, (c.color >> k) & 1023);
                    colour_worst = colour_worst.max(a.abs_diff(b));
                }
                back_differs += ((g.color ^ c.color) >> 30 & 1) as usize;
                points += 1;
            }
            let back = |k: u32| !p.two_sided && cpu[k as usize].color >> 30 & 1 == 1;
            let cols = nu + 1;
            for q in 0..nu * nv {
                let a = (q / nu) * cols + q % nu;
                let (b, c, d) = (a + 1, a + cols + 1, a + cols);
                let got = &t.indices[6 * (qb + q) as usize..][..6];
                if got.iter().all(|&i| i == vb + a) {
                    backface += 1;
                    assert!(
                        back(a) && back(b) && back(c) && back(d) || back_differs > 0,
                        "{name} patch {id} quad {q}: culled, but not all corners face away"
                    );
                } else {
                    assert_eq!(
                        got,
                        [a, b, c, a, c, d].map(|i| vb + i),
                        "{name} patch {id} quad {q}"
                    );
                }
            }
        }
        eprintln!(
            "{name}: {} patches drawn, {} culled, {points} points, position error {worst:e}, \
             colour {colour_worst} steps, {back_differs} back bits differ, {backface} quads culled",
            t.counts.drawn, t.counts.culled
        );
        assert!(worst <= 1e-5, "{name}: position error {worst:e}");
        assert!(
            colour_worst <= 2,
            "{name}: colour off by {colour_worst} steps"
        );
        assert!(
            back_differs * 100 <= points,
            "{name}: {back_differs} of {points} back bits"
        );
        assert_eq!(backface, t.counts.backface, "{name}");
    }
}

/// The peer's teapot against the Reyes image of the same frame (2x2 pixel samples; the peer
/// at 4x MSAA, supported everywhere). They are different renderers of the same surfaces: the
/// peer's triangles are flat between grid points where Reyes's micropolygons are diced per
/// sub-patch, its colour is interpolated per vertex where Reyes's is flat per micropolygon, and
/// its samples sit at the hardware's fixed positions where Reyes's are jittered. So edges
/// (silhouettes, where coverage differs by a sample or two) differ and interiors mostly match:
/// the covered areas agree within 2% (measured: 0.2%), and the whole image's PSNR is at least
/// 25 dB (measured: 27.5 dB). Pixels well inside the surface (covered, with all 8 neighbours
/// covered, in both) differ by more than 8 sRGB steps in at most 10% of them (measured: 70 of
/// 901, 7.8%): nearly all along the lid's rim, where the lid and the body's opening lie within
/// a pixel of each other and the two tessellations order them differently in depth in spots.
/// Depth where both cover agrees within 1% at 95% of those pixels (measured: 1253 of 1268).
#[test]
fn teapot_image_is_the_reyes_image_but_at_edges() {
    let s = scene::builtin_teapot();
    let o = RenderOptions {
        pixel_samples: Some((2, 2)),
        ..small(W, H)
    };
    let reyes = (renderer(StrategyKind::Multipass).render(gpu(), &FrameData::new(&s, &o).unwrap()))
        .unwrap()
        .image;
    let mut peer = RasterPeer::new(gpu(), &s, &o, Pixels::Float).unwrap();
    assert_eq!(peer.msaa_samples(), 4);
    let f = peer.render(gpu(), &[0.0]).unwrap().remove(0);
    let img = f.image.expect("Pixels::Float gives the image");
    let d = img.difference(&reyes, 8);
    let (a, b) = (img.covered_pixels() as f64, reyes.covered_pixels() as f64);
    let inside = |im: &reyes::image::FrameImage, x: i64, y: i64| {
        (-1..=1).all(|dy| {
            (-1..=1).all(|dx| {
                let (u, v) = (x + dx, y + dy);
                u >= 0
                    && v >= 0
                    && u < W as i64
                    && v < H as i64
                    && im.rgba[(v * W as i64 + u) as usize][3] >= 1.0
            })
        })
    };
    let (x8, y8) = (img.rgba8(), reyes.rgba8());
    let (mut interior, mut off) = (0, 0);
    for y in 0..H as i64 {
        for x in 0..W as i64 {
            if inside(&img, x, y) && inside(&reyes, x, y) {
                interior += 1;
                let p = 4 * (y * W as i64 + x) as usize;
                off += (0..3).any(|c| x8[p + c].abs_diff(y8[p + c]) > 8) as usize;
            }
        }
    }
    eprintln!(
        "teapot: PSNR {:.1} dB, {:.2}% of pixels off by more than 8 steps (max {}), covered {a} \
         vs {b}, {off} of {interior} interior pixels off by more than 8 steps; {} triangles",
        d.psnr_db,
        d.over * 100.0,
        d.max,
        f.counts.triangles()
    );
    assert!(
        b > 1000.0 && (a - b).abs() <= 0.02 * b,
        "covered {a} vs {b}"
    );
    assert!(
        interior > 800 && off * 10 <= interior,
        "{off} of {interior} interior pixels"
    );
    assert!(d.psnr_db >= 25.0, "PSNR {:.1} dB", d.psnr_db);
    // Depth where both cover: the same surface within 1% (a chord of a curved patch against
    // a finer one) but where the two order close surfaces differently or a pixel's nearest
    // sample is of another surface at an edge.
    let both: Vec<(f32, f32)> = (img.depth.iter().zip(&reyes.depth))
        .filter(|(a, b)| **a < 1e30 && **b < 1e30)
        .map(|(a, b)| (*a, *b))
        .collect();
    let close = both
        .iter()
        .filter(|(a, b)| (a - b).abs() <= 0.01 * b)
        .count();
    eprintln!(
        "teapot: depth within 1% at {close} of {} pixels",
        both.len()
    );
    assert!(
        close * 100 >= 95 * both.len(),
        "depth within 1% at {close} of {}",
        both.len()
    );
}
