//! Displacement through the whole pipeline (docs/reyes.md, "Displacement"): every GPU strategy
//! gives the same bits, the CPU twin agrees within the usual tolerance, `"Km" 0` is the
//! undisplaced image bit for bit, the effect changes the image only where the surface is, and
//! exact normals leave no holes where approximate ones do. Runs on lavapipe in CI.
//!
//! Hole count: the scene is a sphere displaced outward ("bumps" >= 0), so the displaced
//! surface encloses the undisplaced sphere and every ray that hits the sphere hits it too. A
//! hole is a pixel the undisplaced sphere covers fully (alpha 1) that the displaced render
//! leaves not fully covered (alpha < 1): background seen through a crack.

use reyes::cpu_render::render_cpu;
use reyes::frame::{DisplacementNormals, FrameData, RenderOptions};
use reyes::image::FrameImage;
use reyes::scene::{self, Scene};

mod common;

/// Renders `data` with every strategy (asserting identical images and counters) and the CPU
/// twin (asserting the usual agreement); returns the GPU image.
fn render_everywhere(data: &FrameData) -> FrameImage {
    common::render_everywhere(data).image
}

/// The megakernel's image of `data`, asserting that the multipass strategy gives the same
/// bits (the CPU twin is checked by the other tests; this saves its time on lavapipe).
fn render_gpu(data: &FrameData) -> FrameImage {
    common::render_both_strategies(data).0.image
}

/// A unit sphere 4 units in front of the eye, `displacement` RIB lines before it.
fn sphere(displacement: &str) -> Scene {
    let text = format!(
        "Format 64 64 1\nPixelSamples 2 2\nProjection \"perspective\" \"fov\" 35\n\
         Translate 0 0 4\nWorldBegin\nSurface \"plastic\"\n{displacement}\n\
         Sphere 1 -1 1 360\nWorldEnd\n"
    );
    scene::parse_rib(&text, "sphere.rib").unwrap_or_else(|e| panic!("{e}"))
}

fn data(scene: &Scene, o: &RenderOptions) -> FrameData {
    FrameData::new(scene, o).unwrap()
}

/// `"Km" 0` goes through every displaced code path (features compiled in, the grid moved by
/// 0, normals with zero slopes) and must give the undisplaced image bit for bit.
#[test]
fn km_zero_is_the_undisplaced_image_bit_for_bit() {
    let o = RenderOptions::default();
    let plain = data(&sphere(""), &o);
    let zero = data(&sphere("Displacement \"bumps\" \"Km\" 0"), &o);
    assert!(zero.features().displacement && !plain.features().displacement);
    let a = render_everywhere(&plain);
    let b = render_everywhere(&zero);
    assert!(a == b, "Km 0 differs from no displacement");
    assert!(a.rgba.iter().any(|p| p[3] > 0.0), "the sphere is drawn");
}

/// Displacing changes the image inside the displaced silhouette (most of the sphere's pixels)
/// and nowhere else: every changed pixel lies within the projected radius of the bound sphere
/// (1 + Km, plus a pixel), and pixels outside it stay background.
#[test]
fn displacement_changes_the_image_only_where_the_surface_is() {
    let o = RenderOptions::default();
    let plain = render_everywhere(&data(&sphere(""), &o));
    let d = data(&sphere("Displacement \"bumps\" \"Km\" 0.15"), &o);
    let bumpy = render_everywhere(&d);
    let f = d.frame;
    let (cx, cy) = (f.width as f32 / 2.0, f.height as f32 / 2.0);
    // Silhouette radius of a sphere of radius r at distance 4: focal r / sqrt(16 - r^2).
    let radius = |r: f32| f.focal * r / (16.0 - r * r).sqrt();
    let (inner, outer) = (radius(1.0), radius(1.15) + 1.5);
    let (mut changed, mut inside) = (0, 0);
    for (k, (a, b)) in plain.rgba.iter().zip(&bumpy.rgba).enumerate() {
        let (x, y) = (
            (k as u32 % f.width) as f32 + 0.5,
            (k as u32 / f.width) as f32 + 0.5,
        );
        let dist = (x - cx).hypot(y - cy);
        let differs = a != b;
        assert!(
            !differs || dist <= outer,
            "pixel ({x}, {y}) at {dist:.1} px changed, outside the bound's {outer:.1} px"
        );
        if dist < inner - 1.0 {
            inside += 1;
            changed += differs as u32;
        }
    }
    eprintln!("{changed} of {inside} pixels inside the sphere changed");
    assert!(
        changed as f64 > 0.5 * inside as f64,
        "{changed} of {inside} pixels inside the sphere changed"
    );
}

/// Pixels the undisplaced sphere covers fully that the displaced render leaves not fully
/// covered (the module's hole count).
fn holes(plain: &FrameImage, displaced: &FrameImage) -> usize {
    (plain.rgba.iter().zip(&displaced.rgba))
        .filter(|(a, b)| a[3] == 1.0 && b[3] < 1.0)
        .count()
}

/// Sattler et al.'s figure 6: displacing along the grids' own finite-difference normals opens
/// holes between neighbouring grids of different rates; along the patch's exact normals there
/// are none. The sphere is one-sided (`Sides 1`), so that a hole shows the background rather
/// than the inside of its far half. Small grids (at most 4 x 4 micropolygons of 2 px) make
/// many grids of different rates meet inside each patch, where the bump is high. Crack
/// dilation stays on: it closes T-junction cracks (the chord error of a coarse grid's edge
/// against its finer neighbour's points), which displacement leaves with either normal
/// (measured without it: exact 26 holes, approximate 567), but not the wider gaps that
/// approximate normals open (measured: exact 0, approximate 255 of 2218 covered pixels).
#[test]
fn exact_normals_leave_no_holes_approximate_normals_do() {
    let o = RenderOptions {
        mp_size: 2.0,
        grid_max: 4,
        ..Default::default()
    };
    let far_sphere = |d: &str| {
        let text = format!(
            "Format 100 100 1\nPixelSamples 2 2\nProjection \"perspective\" \"fov\" 35\n\
             Translate 0 0 6\nWorldBegin\nSides 1\nSurface \"plastic\"\n{d}\nSphere 1 -1 1 360\nWorldEnd\n"
        );
        scene::parse_rib(&text, "far-sphere.rib").unwrap_or_else(|e| panic!("{e}"))
    };
    let plain = render_gpu(&data(&far_sphere(""), &o));
    let bumps = far_sphere("Displacement \"bumps\" \"Km\" 0.8");
    let exact = render_gpu(&data(&bumps, &o));
    let approx = render_gpu(&data(
        &bumps,
        &RenderOptions {
            displacement_normals: DisplacementNormals::Approximate,
            ..o.clone()
        },
    ));
    let covered = plain.rgba.iter().filter(|p| p[3] == 1.0).count();
    let (he, ha) = (holes(&plain, &exact), holes(&plain, &approx));
    eprintln!("holes in {covered} covered pixels: exact normals {he}, approximate {ha}");
    assert!(covered > 1000, "the sphere covers {covered} pixels");
    assert_eq!(he, 0, "exact normals leave holes");
    assert!(
        ha >= 10,
        "approximate normals left {ha} holes: too few to show"
    );
}

/// A map through the pipeline: a uniformly white PNG with `"Km" 0.25` moves every point of the
/// unit sphere 0.25 along its normal, so the image is that of a sphere of radius 1.25 (its
/// coverage up to a few edge samples, its colour on average); every strategy and the CPU
/// twin agree on it.
#[test]
fn a_uniform_map_displaces_the_sphere_to_a_larger_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("white.png");
    image::GrayImage::from_pixel(8, 4, image::Luma([255u8]))
        .save(&png)
        .unwrap();
    let rib = |d: &str, r: f64| {
        format!(
            "Format 64 64 1\nPixelSamples 2 2\nProjection \"perspective\" \"fov\" 35\n\
             Translate 0 0 4\nWorldBegin\nSurface \"plastic\"\n{d}\nSphere {r} -{r} {r} 360\n\
             WorldEnd\n"
        )
    };
    let file = dir.path().join("scene.rib");
    let text = rib(
        "Displacement \"mapped\" \"mapname\" \"white.png\" \"Km\" 0.25",
        1.0,
    );
    let mapped = scene::parse_rib(&text, file.to_str().unwrap()).unwrap();
    let larger = scene::parse_rib(&rib("", 1.25), "larger.rib").unwrap();
    let o = RenderOptions::default();
    let a = render_everywhere(&data(&mapped, &o));
    let b = render_gpu(&data(&larger, &o));
    // Coverage: the same disc up to a few edge samples.
    let n = a.rgba.len() as f64;
    let alpha_off = (a.rgba.iter().zip(&b.rgba))
        .filter(|(p, q)| (p[3] - q[3]).abs() > 0.25)
        .count() as f64
        / n;
    // Colour: the displaced grids keep the rates of the unit sphere, so their micropolygons
    // are 1.25 times larger than the larger sphere's and flat shading steps differ by up to
    // one micropolygon's shading gradient: compared on average, not per pixel.
    let colour_off = (a.rgba.iter().zip(&b.rgba))
        .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs()).sum::<f32>() as f64 / 3.0)
        .sum::<f64>()
        / n;
    eprintln!(
        "mapped vs radius 1.25: coverage off in {:.2}% of pixels, mean colour difference {colour_off:.4}",
        alpha_off * 100.0
    );
    assert!(
        alpha_off < 0.005,
        "coverage differs in {:.2}% of pixels",
        alpha_off * 100.0
    );
    assert!(colour_off < 0.01, "mean colour difference {colour_off}");
}

/// A patch 5 units from the eye displaced by `"Km" 6` (or bounded by a huge
/// `"displacementbound"`): every piece's grown bound reaches the eye however small the piece,
/// and splitting by that bound once made 2^24 pieces (no end, CPU twin and GPU). A piece is
/// split by what its undisplaced surface shows and its grids are clipped at the near plane:
/// every strategy and the CPU twin agree, with a handful of eye splits, and the patch is drawn.
#[test]
fn a_displacement_reaching_the_eye_is_clipped_not_split_without_end() {
    let patch = "Patch \"bicubic\" \"P\" [-1.5 -1.5 0 -0.5 -1.5 0 0.5 -1.5 0 1.5 -1.5 0 \
                 -1.5 -0.5 0 -0.5 -0.5 0 0.5 -0.5 0 1.5 -0.5 0 -1.5 0.5 0 -0.5 0.5 0 0.5 0.5 0 \
                 1.5 0.5 0 -1.5 1.5 0 -0.5 1.5 0 0.5 1.5 0 1.5 1.5 0]";
    for displacement in [
        "Displacement \"bumps\" \"Km\" 6",
        "Attribute \"displacementbound\" \"sphere\" [1e30]\nDisplacement \"bumps\" \"Km\" 0.2",
    ] {
        // A small image: the bumps reach past the eye, so their clipped micropolygons cover
        // the whole image and each is tested against every sample (seconds on lavapipe).
        let text = format!(
            "Format 16 12 1\nPixelSamples 1 1\nProjection \"perspective\" \"fov\" [40]\n\
             Translate 0 0 5\nWorldBegin\nSurface \"matte\"\n{displacement}\n{patch}\nWorldEnd\n"
        );
        let s = scene::parse_rib(&text, "reaches-eye.rib").unwrap_or_else(|e| panic!("{e}"));
        let d = data(&s, &RenderOptions::default());
        let cpu = render_cpu(&d);
        let eye = cpu.counters[reyes::stages::C_EYE_SPLITS];
        assert!(eye <= 64, "{displacement}: {eye} eye splits");
        assert!(
            cpu.counters[reyes::stages::C_NEAR_CLIPPED] >= 1,
            "{displacement}: no grid clipped at the near plane"
        );
        let image = render_everywhere(&d);
        assert!(image.covered_pixels() > 0, "{displacement}: nothing drawn");
    }
    // --bound-px splits a displaced piece by its undisplaced extent: a patch clear of the eye
    // whose grown screen box stays wider than bound_px at any split.
    let text = format!(
        "Format 64 48 1\nPixelSamples 2 2\nProjection \"perspective\" \"fov\" [40]\n\
         Translate 0 0 5\nWorldBegin\nSurface \"matte\"\nDisplacement \"bumps\" \"Km\" 2\n\
         {patch}\nWorldEnd\n"
    );
    let s = scene::parse_rib(&text, "bound-px.rib").unwrap();
    let o = RenderOptions {
        bound_px: Some(8.0),
        ..RenderOptions::default()
    };
    let cpu = render_cpu(&data(&s, &o));
    assert!(
        cpu.executed[1] + cpu.executed[2] < 4096,
        "{} splits",
        cpu.executed[1] + cpu.executed[2]
    );
}
