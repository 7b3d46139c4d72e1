//! Primitive variables `"Cs"` and `"Os"` through the whole pipeline: every GPU strategy gives
//! the same bits, the CPU twin agrees within the usual tolerance, and the pixels show what the
//! RIB says (field input `varying-color.rib`, vertex colours through a B-spline basis, uniform
//! colours per sub-patch of a mesh, opacity as stochastic coverage). Runs on lavapipe in CI.
//!
//! The scenes are flat patches facing the camera whose points are equally spaced, so a pixel's
//! centre maps to the patch parameters (u, v) linearly and the expected colour is computed
//! here, independently of the renderer.

use reyes::frame::{FrameData, RenderOptions};
use reyes::image::FrameImage;
use reyes::scene::{self, Scene};
use reyes::stages;
use scheduler::StrategyKind;

mod common;
use common::{gpu, renderer};

/// Renders `data` with every strategy (asserting identical images and counters) and the CPU
/// twin (asserting the usual agreement); returns the GPU image.
fn render_everywhere(data: &FrameData) -> FrameImage {
    render_counted(data).0
}

/// [`render_everywhere`], also returning the GPU's counters.
fn render_counted(data: &FrameData) -> (FrameImage, [u64; stages::COUNTERS]) {
    let f = common::render_everywhere(data);
    (f.image, f.counters)
}

fn parse(text: &str) -> Scene {
    scene::parse_rib(text, "test.rib").unwrap_or_else(|e| panic!("{e}"))
}

/// The raster-to-patch mapping of a flat patch spanning x, y in [-1, 1] at depth 4 (as in
/// varying-color.rib): (u, v) of the centre of pixel (px, py), and whether the whole pixel
/// lies `margin` pixels or more inside the patch.
struct Flat {
    width: u32,
    height: u32,
    focal: f64,
}

impl Flat {
    fn new(width: u32, height: u32, fov_deg: f64) -> Flat {
        let short = width.min(height) as f64;
        Flat {
            width,
            height,
            focal: short / 2.0 / (fov_deg.to_radians() / 2.0).tan(),
        }
    }

    fn uv(&self, px: u32, py: u32) -> (f64, f64) {
        let x = (px as f64 + 0.5 - self.width as f64 / 2.0) / self.focal * 4.0;
        let y = (self.height as f64 / 2.0 - py as f64 - 0.5) / self.focal * 4.0;
        ((x + 1.0) / 2.0, (y + 1.0) / 2.0)
    }

    /// Pixels whose square lies at least `margin` pixels inside the patch, with their (u, v).
    fn inside(&self, margin: f64) -> Vec<(usize, (f64, f64))> {
        let px_uv = 2.0 / self.focal; // one pixel in u or v
        let m = (0.5 + margin) * px_uv;
        let mut out = Vec::new();
        for py in 0..self.height {
            for px in 0..self.width {
                let (u, v) = self.uv(px, py);
                if u > m && u < 1.0 - m && v > m && v < 1.0 - m {
                    out.push(((py * self.width + px) as usize, (u, v)));
                }
            }
        }
        out
    }
}

fn rgb(p: [f32; 4]) -> [f64; 3] {
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

fn max_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max)
}

/// Linear colour tolerance for a colour field seen through the pipeline: each micropolygon has
/// one flat colour (the mean of its corners, up to ~2 px apart at `--mp-size 1`: here under
/// 0.015 of the full range) stored as 10-bit sRGB (under 0.003 linear per step).
const COLOR_TOL: f64 = 0.03;

/// varying-color.rib: red, green, blue and white corners (bottom left, bottom right, top left,
/// top right on screen), every fully covered pixel the bilinear blend at its centre.
#[test]
fn varying_cs_blends_bilinearly_between_the_corners() {
    let path = reyes::shared_data_dir().join("field/varying-color.rib");
    let s = scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
    let img = render_everywhere(&data);
    let flat = Flat::new(320, 240, 45.0);
    let blend = |u: f64, v: f64| {
        let c = [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let w = [(1.0 - u) * (1.0 - v), u * (1.0 - v), (1.0 - u) * v, u * v];
        std::array::from_fn(|k| (0..4).map(|i| w[i] * c[i][k]).sum::<f64>())
    };
    let inside = flat.inside(1.0);
    assert!(inside.len() > 15_000, "{} pixels inside", inside.len());
    let mut worst: f64 = 0.0;
    for &(i, (u, v)) in &inside {
        assert_eq!(img.rgba[i][3], 1.0, "pixel {i} not fully covered");
        worst = worst.max(max_diff(rgb(img.rgba[i]), blend(u, v)));
    }
    assert!(
        worst < COLOR_TOL,
        "largest difference from the blend {worst}"
    );
    // The corners' pixels are the pure colours, the centre the mean of the four.
    let corner = |u: f64, v: f64| {
        let &(i, _) = inside
            .iter()
            .min_by(|a, b| {
                let d = |p: (f64, f64)| (p.0 - u).hypot(p.1 - v);
                d(a.1).total_cmp(&d(b.1))
            })
            .unwrap();
        rgb(img.rgba[i])
    };
    for ((u, v), want) in [
        ((0.0, 0.0), [1.0, 0.0, 0.0]),
        ((1.0, 0.0), [0.0, 1.0, 0.0]),
        ((0.0, 1.0), [0.0, 0.0, 1.0]),
        ((1.0, 1.0), [1.0, 1.0, 1.0]),
        ((0.5, 0.5), [0.5, 0.5, 0.5]),
    ] {
        let got = corner(u, v);
        assert!(max_diff(got, want) < 0.05, "at ({u}, {v}): {got:?}");
    }
}

/// Uniform cubic B-spline weights at t.
fn bspline(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        s * s * s / 6.0,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
        (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
        t * t * t / 6.0,
    ]
}

/// Vertex Cs on a B-spline patch: every pixel shows the B-spline of the 16 colours at its
/// (u, v), evaluated here from the basis functions.
#[test]
fn vertex_cs_follows_the_patch_basis() {
    // Points 2 apart from -3 to 3: the B-spline patch is x, y in [-1, 1], linear in (u, v).
    let points: Vec<String> = (0..16)
        .map(|k| format!("{} {} 0", -3 + 2 * (k % 4), -3 + 2 * (k / 4)))
        .collect();
    let colors: Vec<[f64; 3]> = (0..16)
        .map(|k| {
            let (i, j) = ((k % 4) as f64, (k / 4) as f64);
            [i / 3.0, j / 3.0, ((i * 1.3 + j * 0.7).sin() + 1.0) / 2.0]
        })
        .collect();
    let nums: Vec<String> = colors
        .iter()
        .map(|c| format!("{} {} {}", c[0], c[1], c[2]))
        .collect();
    let s = parse(&format!(
        "Format 160 120 1\nProjection \"perspective\" \"fov\" 45\nTranslate 0 0 4\nWorldBegin\n\
         Surface \"constant\"\nBasis \"b-spline\" 1 \"b-spline\" 1\n\
         Patch \"bicubic\" \"P\" [{}] \"vertex color Cs\" [{}]\nWorldEnd\n",
        points.join(" "),
        nums.join(" ")
    ));
    let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
    let img = render_everywhere(&data);
    let flat = Flat::new(160, 120, 45.0);
    let want = |u: f64, v: f64| -> [f64; 3] {
        let (wu, wv) = (bspline(u), bspline(v));
        std::array::from_fn(|c| (0..16).map(|k| colors[k][c] * wu[k % 4] * wv[k / 4]).sum())
    };
    let inside = flat.inside(1.0);
    assert!(inside.len() > 3_500, "{} pixels inside", inside.len());
    let worst = (inside.iter())
        .map(|&(i, (u, v))| max_diff(rgb(img.rgba[i]), want(u, v)))
        .fold(0.0, f64::max);
    assert!(
        worst < COLOR_TOL,
        "largest difference from the B-spline {worst}"
    );
}

/// Uniform Cs on a bilinear PatchMesh of 3 x 2 sub-patches: each shows its own colour, over a
/// matte surface lit by an ambient light of 1 (so Ka Cs = Cs).
#[test]
fn uniform_cs_colours_each_sub_patch_of_a_mesh() {
    // Corners 2/3 apart in x from -1 to 1, 1 apart in y: sub-patch (pu, pv) is centred at
    // u = (pu + 0.5) / 3, v = (pv + 0.5) / 2.
    let pts: Vec<String> = (0..12)
        .map(|k| format!("{} {} 0", -1.0 + 2.0 * (k % 4) as f64 / 3.0, -1 + (k / 4)))
        .collect();
    let colors = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 1.0],
        [0.5, 0.25, 1.0],
    ];
    let nums: Vec<String> = colors
        .iter()
        .map(|c| format!("{} {} {}", c[0], c[1], c[2]))
        .collect();
    let s = parse(&format!(
        "Format 96 72 1\nProjection \"perspective\" \"fov\" 45\nTranslate 0 0 4\n\
         Declare \"Cs\" \"uniform color\"\nWorldBegin\nLightSource \"ambientlight\" 1\n\
         Surface \"matte\" \"Kd\" 0\nPatchMesh \"bilinear\" 4 \"nonperiodic\" 3 \"nonperiodic\" \
         \"P\" [{}] \"Cs\" [{}]\nWorldEnd\n",
        pts.join(" "),
        nums.join(" ")
    ));
    assert_eq!(s.patches.len(), 6);
    let data = FrameData::new(&s, &RenderOptions::default()).unwrap();
    let img = render_everywhere(&data);
    let flat = Flat::new(96, 72, 45.0);
    let px_uv = 2.0 / flat.focal;
    for (i, (u, v)) in flat.inside(1.0) {
        let (pu, pv) = ((u * 3.0) as usize, (v * 2.0) as usize);
        // Pixels a pixel or more away from the sub-patches' shared edges.
        let edge_u = (u * 3.0 - (u * 3.0).round()).abs() / 3.0;
        let edge_v = (v * 2.0 - (v * 2.0).round()).abs() / 2.0;
        if edge_u < 1.5 * px_uv || edge_v < 1.5 * px_uv {
            continue;
        }
        let got = rgb(img.rgba[i]);
        let want = colors[pv * 3 + pu];
        assert!(
            max_diff(got, want) < 0.005,
            "pixel {i} in sub-patch ({pu}, {pv}): {got:?} instead of {want:?}"
        );
    }
}

/// Opacity 0.5 (constant Os) covers half the samples: alpha over the patch averages 0.5
/// within 5 standard deviations of the binomial mean; over an opaque patch behind it the
/// colours mix half and half with alpha 1; a varying Os from 0 (left) to 1 (right) gives
/// alpha rising across; screen buckets give the same image bit for bit; grids clipped at the
/// near plane cover the same fraction.
#[test]
fn opacity_covers_that_fraction_of_the_samples() {
    let flat = Flat::new(96, 72, 45.0);
    let header = "Format 96 72 1\nPixelSamples 4 4\nProjection \"perspective\" \"fov\" 45\n\
                  Translate 0 0 4\nWorldBegin\nSurface \"constant\"\n";
    // A square of side 2 r at depth 4 + z.
    let quad = |r: f64, z: f64| {
        format!("Patch \"bilinear\" \"P\" [-{r} -{r} {z}  {r} -{r} {z}  -{r} {r} {z}  {r} {r} {z}]")
    };
    let spp = 16.0;
    let mean_alpha = |img: &FrameImage, pixels: &[(usize, (f64, f64))]| {
        pixels
            .iter()
            .map(|&(i, _)| img.rgba[i][3] as f64)
            .sum::<f64>()
            / pixels.len() as f64
    };
    // 5 standard deviations of the mean of n Bernoulli(p) samples, plus the rounding of the
    // threshold to 2^-24.
    let tol = |n: f64, p: f64| 5.0 * (p * (1.0 - p) / n).sqrt() + 1e-6;

    let half = parse(&format!(
        "{header}Color [0 0 1]\n{} \"constant color Os\" [0.5 0.5 0.5]\nWorldEnd\n",
        quad(1.0, 0.0)
    ));
    let data = FrameData::new(&half, &RenderOptions::default()).unwrap();
    let img = render_everywhere(&data);
    let inside = flat.inside(1.0);
    let n = inside.len() as f64 * spp;
    let a = mean_alpha(&img, &inside);
    assert!(
        (a - 0.5).abs() < tol(n, 0.5),
        "mean alpha {a} over {n} samples"
    );
    // Stochastic, per sample: pixels differ, in steps of 1/16.
    assert!(inside.iter().any(|&(i, _)| img.rgba[i][3] < 0.5));
    assert!(inside.iter().any(|&(i, _)| img.rgba[i][3] > 0.5));
    assert!(img.rgba.iter().all(|p| (p[3] * 16.0).fract() == 0.0));
    // Screen buckets decide each sample alike.
    let bucketed = FrameData {
        memory_budget: Some(256 << 10),
        ..data.clone()
    };
    let b = renderer(StrategyKind::Megakernel)
        .render(gpu(), &bucketed)
        .unwrap();
    assert!(b.buckets > 1 && b.image == img, "bucketed image differs");

    // In front of a larger opaque red patch: alpha 1, colour half blue, half red.
    let over = parse(&format!(
        "{header}Color [1 0 0]\n{}\nColor [0 0 1]\nOpacity [0.5 0.5 0.5]\n{}\nWorldEnd\n",
        quad(2.0, 0.5),
        quad(1.0, 0.0)
    ));
    let img = render_everywhere(&FrameData::new(&over, &RenderOptions::default()).unwrap());
    assert!(inside.iter().all(|&(i, _)| img.rgba[i][3] == 1.0));
    let mean = |c: usize| {
        inside
            .iter()
            .map(|&(i, _)| img.rgba[i][c] as f64)
            .sum::<f64>()
            / inside.len() as f64
    };
    for c in [0, 2] {
        assert!(
            (mean(c) - 0.5).abs() < tol(n, 0.5),
            "channel {c}: {}",
            mean(c)
        );
    }

    // A floor just below the eye reaching behind it, with the near plane at 1 so that it
    // crosses the plane in view (grids clipped there): where the opaque floor covers a pixel
    // fully, the transparent one covers half its samples.
    let floor = |opacity: &str| {
        let s = parse(&format!(
            "{}{opacity}Patch \"bilinear\" \"P\" [-8 -0.2 -8  8 -0.2 -8  -8 -0.2 8  8 -0.2 8]\n\
             WorldEnd\n",
            header.replace("WorldBegin", "Clipping 1 100\nWorldBegin")
        ));
        // Coarse micropolygons (8 px), so that those crossing the plane show a band of
        // samples that only their clipped triangles cover.
        let o = RenderOptions {
            mp_size: 8.0,
            ..Default::default()
        };
        render_counted(&FrameData::new(&s, &o).unwrap())
    };
    let (opaque, counters) = floor("");
    assert!(counters[stages::C_NEAR_CLIPPED] > 0, "no grid was clipped");
    let (glass, _) = floor("Opacity [0.5 0.5 0.5]\n");
    let full: Vec<_> = (0..opaque.rgba.len())
        .filter(|&i| opaque.rgba[i][3] == 1.0)
        .map(|i| (i, (0.0, 0.0)))
        .collect();
    assert!(full.len() > 1000, "{} pixels of floor", full.len());
    // All of it, and its nearest rows (the near plane meets it at row 36 + 0.2 f = 53.4).
    let near: Vec<_> = (full.iter().filter(|(i, _)| *i / 96 >= 47).copied()).collect();
    assert!(near.len() > 400, "{} pixels near the plane", near.len());
    for pixels in [&full, &near] {
        let a = mean_alpha(&glass, pixels);
        let n = pixels.len() as f64 * spp;
        assert!(
            (a - 0.5).abs() < tol(n, 0.5),
            "clipped floor: mean alpha {a} over {n}"
        );
    }
    // The pixels along the near plane (covered by micropolygons clipped triangle by triangle):
    // the transparent floor covers half of what the opaque one covers.
    let cut: Vec<usize> = (0..opaque.rgba.len())
        .filter(|&i| i / 96 >= 50 && opaque.rgba[i][3] > 0.0)
        .collect();
    let covered = |img: &FrameImage| cut.iter().map(|&i| img.rgba[i][3] as f64).sum::<f64>();
    let n = covered(&opaque) * spp;
    let ratio = covered(&glass) / covered(&opaque);
    eprintln!(
        "near-plane cut: {} pixels, {n} samples, ratio {ratio}",
        cut.len()
    );
    assert!(n > 300.0, "{n} samples along the near plane");
    assert!(
        (ratio - 0.5).abs() < tol(n, 0.5),
        "along the near plane: {ratio} of {n} samples"
    );

    // Varying Os 0 at u = 0 to 1 at u = 1: each band of columns averages its mean u.
    let ramp = parse(&format!(
        "{header}{} \"Os\" [0 0 0  1 1 1  0 0 0  1 1 1]\nWorldEnd\n",
        quad(1.0, 0.0)
    ));
    let img = render_everywhere(&FrameData::new(&ramp, &RenderOptions::default()).unwrap());
    for band in 0..4 {
        let (lo, hi) = (band as f64 / 4.0, (band + 1) as f64 / 4.0);
        let pixels: Vec<_> = (inside.iter())
            .filter(|(_, (u, _))| (lo..hi).contains(u))
            .copied()
            .collect();
        let expect = pixels.iter().map(|(_, (u, _))| u).sum::<f64>() / pixels.len() as f64;
        let a = mean_alpha(&img, &pixels);
        let n = pixels.len() as f64 * spp;
        // Plus the opacity's evaluation at micropolygon centres, not at samples (< 0.01).
        assert!(
            (a - expect).abs() < tol(n, 0.5) + 0.01,
            "band {band}: mean alpha {a}, expected {expect}"
        );
    }
}
