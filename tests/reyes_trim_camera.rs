//! Camera and image requests of real RIB files that change the picture (issue 23, item 5):
//! `TrimCurve` on `NuPatch` (the field file that cuts a disc out of a square), through Bound
//! and DiceShade on the GPU (both strategies, bit-identical) and the CPU twin, against an
//! independent f64 reference of the disc. Runs on lavapipe in CI; the adapter comes from the
//! environment and a missing one fails loudly.

use glam::{DVec2, DVec3};
use reyes::cpu_render::render_cpu;
use reyes::frame::{FrameData, RenderOptions};
use reyes::scene::Scene;
use reyes::stages;

mod common;
use common::{CPU_TWIN_OVER, CPU_TWIN_OVER_HARD, compare, render_both_strategies};

/// The exporter file whose `TrimCurve` (a rational quadratic circle of radius 0.5 about the
/// centre of the parameter square) cuts a disc out of a square `NuPatch`.
fn trim_scene() -> Scene {
    let path = reyes::shared_data_dir().join("field/exporters/trimcurve-format-minus-one.rib");
    reyes::scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Exact coverage of each pixel by the trimmed patch, from `n` x `n` regular sub-samples: the
/// ray through each sub-sample meets the patch's plane (its four corners are coplanar and
/// form a parallelogram, the bilinear NuPatch), the hit's (u, v) on that parallelogram is
/// inside the circle of radius 1/2 about (1/2, 1/2) or not. Independent of the renderer's
/// flattening, splitting and dicing.
fn exact_disc(scene: &Scene, n: u32) -> Vec<f64> {
    let p = &scene.patches[0];
    let (o, a, b) = (p.cp()[0], p.cp()[3] - p.cp()[0], p.cp()[12] - p.cp()[0]);
    let normal = a.cross(b);
    let (w, h) = (scene.width, scene.height);
    let f = w.min(h) as f64 / 2.0 / (scene.camera.fov_deg.to_radians() / 2.0).tan();
    (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f64, (k / w) as f64);
            let hits = (0..n * n)
                .filter(|s| {
                    let sx = x + ((s % n) as f64 + 0.5) / n as f64;
                    let sy = y + ((s / n) as f64 + 0.5) / n as f64;
                    let d = DVec3::new((sx - w as f64 / 2.0) / f, (h as f64 / 2.0 - sy) / f, 1.0);
                    let t = o.dot(normal) / d.dot(normal);
                    let q = d * t - o;
                    // q = u a + v b: solve in the plane (a, b orthogonal here: a square).
                    let uv = DVec2::new(q.dot(a) / a.dot(a), q.dot(b) / b.dot(b));
                    (0.0..=1.0).contains(&uv.x)
                        && (0.0..=1.0).contains(&uv.y)
                        && uv.distance(DVec2::splat(0.5)) <= 0.5
                })
                .count();
            hits as f64 / (n * n) as f64
        })
        .collect()
}

/// The field file renders a disc: its coverage (the sum of alpha) within 0.5% of the exact
/// disc's (micropolygons are kept or dropped whole by their centre, about 1 px across at the
/// default size: the error along the ~440 px rim averages out, and 0.5% is 76 px), no pixel
/// more than half covered where the exact disc covers nothing (the square's corners stay
/// empty), Bound culls the pieces wholly cut away, the strategies agree bit for bit and the
/// CPU twin within the tolerance of the other GPU tests.
#[test]
fn trimcurve_cuts_a_disc_out_of_the_square() {
    let scene = trim_scene();
    assert!(
        !scene.warnings.iter().any(|w| w.contains("TrimCurve")),
        "{:?}",
        scene.warnings
    );
    assert_eq!(scene.patches.len(), 1);
    assert!(scene.patches[0].trim.is_some());
    let options = RenderOptions {
        pixel_samples: Some((4, 4)),
        ..RenderOptions::default()
    };
    let data = FrameData::new(&scene, &options).unwrap();
    assert!(data.features().trim);
    let (mk, _) = render_both_strategies(&data);
    let cpu = render_cpu(&data);
    let (max, over) = compare(&mk.image, &cpu.image);
    assert!(
        over < CPU_TWIN_OVER_HARD,
        "{:.2}% of pixels differ from the CPU twin by more than 2/255 (max {max})",
        over * 100.0
    );
    assert_eq!(
        mk.counters[stages::C_CULL_TRIMMED],
        cpu.counters[stages::C_CULL_TRIMMED]
    );
    assert!(mk.counters[stages::C_CULL_TRIMMED] > 0, "no piece culled");
    let exact = exact_disc(&scene, 8);
    let want: f64 = exact.iter().sum();
    // The disc is large: more than 10,000 px of a 200 x 150 image.
    assert!(want > 10_000.0, "exact disc {want} px");
    for (name, img) in [("GPU", &mk.image), ("CPU twin", &cpu.image)] {
        let got: f64 = img.rgba.iter().map(|p| p[3] as f64).sum();
        eprintln!("{name}: coverage {got:.1} px, exact disc {want:.1} px");
        assert!(
            (got - want).abs() <= 0.005 * want,
            "{name}: coverage {got:.1} px, exact disc {want:.1} px"
        );
        let stray = (img.rgba.iter().zip(&exact))
            .filter(|(p, e)| **e == 0.0 && p[3] > 0.5)
            .count();
        assert_eq!(stray, 0, "{name}: pixels drawn outside the disc");
        // The square's corners (outside the disc, inside the untrimmed square) are empty.
        let (w, h) = (img.width as usize, img.height as usize);
        let c = DVec2::new(w as f64, h as f64) / 2.0;
        let r = (want / std::f64::consts::PI).sqrt();
        for (dx, dy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            let q = c + DVec2::new(dx, dy) * r * 0.85;
            let at = q.y as usize * w + q.x as usize;
            assert_eq!(img.rgba[at][3], 0.0, "{name}: corner ({}, {})", q.x, q.y);
        }
        assert!(
            img.rgba[(h / 2) * w + w / 2][3] == 1.0,
            "{name}: the centre"
        );
    }
}

/// A small scene: a bilinear square left of centre, partly covering the image, `imager` given
/// before the world.
fn imager_scene(imager: &str) -> Scene {
    let rib = format!(
        "Format 48 32 1\nPixelSamples 2 2\nProjection \"perspective\" \"fov\" [40]\n{imager}\n\
         Translate 0 0 5\nWorldBegin\nSurface \"constant\"\nColor [0.9 0.3 0.1]\n\
         Patch \"bilinear\" \"P\" [-1.5 -1 0  0.3 -1 0  -1.5 1 0  0.3 1 0]\nWorldEnd\n"
    );
    let s = reyes::scene::parse_rib(&rib, "imager.rib").unwrap();
    assert!(
        !s.warnings.iter().any(|w| w.contains("Imager")),
        "{:?}",
        s.warnings
    );
    s
}

/// `Imager "background"`: every pixel is composited over the colour and opaque (RenderMan's
/// background imager: Ci += (1 - alpha) background, alpha = 1): uncovered pixels take the
/// colour exactly, covered ones keep theirs, edge pixels are the mix by their coverage, the
/// same arithmetic on the GPU (both strategies, bit for bit) and in the CPU twin (each against
/// its own render without the imager; the two within the other GPU tests' tolerance).
#[test]
fn imager_background_fills_uncovered_pixels() {
    let bg = [0.2f32, 0.4, 0.6];
    let plain = imager_scene("");
    let with = imager_scene("Imager \"background\" \"color background\" [0.2 0.4 0.6]");
    assert_eq!(with.background, Some(DVec3::new(0.2, 0.4, 0.6)));
    // The standard shader's default is white; "bgcolor" is read too; "null" turns it off.
    assert_eq!(
        imager_scene("Imager \"background\"").background,
        Some(DVec3::ONE)
    );
    let other = imager_scene("Imager \"background\" \"bgcolor\" [1 0 0]");
    assert_eq!(other.background, Some(DVec3::X));
    assert_eq!(
        imager_scene("Imager \"background\" \"background\" [1 0 0]\nImager \"null\"").background,
        None
    );
    let o = RenderOptions::default();
    let a = FrameData::new(&plain, &o).unwrap();
    let b = FrameData::new(&with, &o).unwrap();
    let (ga, _) = render_both_strategies(&a);
    let (gb, _) = render_both_strategies(&b);
    let (ca, cb) = (render_cpu(&a), render_cpu(&b));
    let (max, over) = compare(&gb.image, &cb.image);
    assert!(over < CPU_TWIN_OVER, "CPU twin: {over} over, max {max}");
    let (mut empty, mut full, mut edge) = (0, 0, 0);
    let gpu_pairs = ga.image.rgba.iter().zip(&gb.image.rgba);
    for (p, q) in gpu_pairs.chain(ca.image.rgba.iter().zip(&cb.image.rgba)) {
        assert_eq!(q[3], 1.0, "every pixel opaque");
        let k = 1.0 - p[3];
        for c in 0..3 {
            let want = p[c] * p[3] + bg[c] * k;
            assert!((q[c] - want).abs() <= 1e-6, "{p:?} over {bg:?} gave {q:?}");
        }
        match p[3] {
            0.0 => empty += 1,
            1.0 => full += 1,
            _ => edge += 1,
        }
    }
    // Both images counted: each has uncovered, covered and edge pixels.
    assert!(
        empty > 200 && full > 200 && edge > 20,
        "{empty} {full} {edge}"
    );
}

/// A square 5 units ahead, seen through a camera block (`camera`, before `WorldBegin`) and
/// placed by `object` (inside it, before the square).
fn motion_scene(camera: &str, object: &str) -> Scene {
    let rib = format!(
        "Format 64 48 1\nPixelSamples 4 4\nShutter 0 1\nProjection \"perspective\" \"fov\" [40]\n\
         {camera}\nWorldBegin\nSurface \"constant\"\n{object}\n\
         Patch \"bilinear\" \"P\" [-0.8 -0.8 0  0.8 -0.8 0  -0.8 0.8 0  0.8 0.8 0]\nWorldEnd\n"
    );
    let s = reyes::scene::parse_rib(&rib, "motion.rib").unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    s
}

/// Camera motion (`MotionBegin` around the camera's transforms before `WorldBegin`): a still
/// square under a camera that turns and slides over the shutter blurs exactly as the same
/// square moved the opposite way (the same motion block inside the world) under a still
/// camera: the same patch motion, the same image on the GPU (both strategies) and the CPU
/// twin; and it is blurred (far more partly covered pixels than the still square).
#[test]
fn camera_motion_blurs_like_the_opposite_object_motion() {
    let motion = "MotionBegin [0 1]\nRotate 0 0 1 0\nRotate 8 0 1 0\nMotionEnd\n\
                  MotionBegin [0 1]\nTranslate 0 0 5\nTranslate 0.6 0.2 5\nMotionEnd";
    let moving_camera = motion_scene(motion, "");
    let moving_square = motion_scene("", motion);
    let still = motion_scene("Translate 0 0 5", "");
    let (pa, pb) = (&moving_camera.patches[0], &moving_square.patches[0]);
    let (ma, mb) = (pa.motion.as_deref().unwrap(), pb.motion.as_deref().unwrap());
    assert!(ma.abs_diff_eq(*mb, 1e-12), "{ma} vs {mb}");
    for (a, b) in pa.cp().iter().zip(&pb.cp()) {
        assert!(a.abs_diff_eq(*b, 1e-12));
    }
    let o = RenderOptions::default();
    let a = FrameData::new(&moving_camera, &o).unwrap();
    let b = FrameData::new(&moving_square, &o).unwrap();
    let (ga, _) = render_both_strategies(&a);
    let (gb, _) = render_both_strategies(&b);
    let (max, over) = compare(&ga.image, &gb.image);
    assert!(
        over == 0.0 && max <= 1,
        "camera vs object motion: {over} over, max {max}"
    );
    let ca = render_cpu(&a);
    let (max, over) = compare(&ga.image, &ca.image);
    assert!(
        over < common::CPU_TWIN_OVER_MOTION,
        "CPU twin: {over} over, max {max}"
    );
    let partial = |img: &reyes::image::FrameImage| {
        img.rgba.iter().filter(|p| p[3] > 0.0 && p[3] < 1.0).count()
    };
    let g = render_both_strategies(&FrameData::new(&still, &o).unwrap()).0;
    assert!(
        partial(&ga.image) > 3 * partial(&g.image),
        "blurred {} vs still {}",
        partial(&ga.image),
        partial(&g.image)
    );
}
