//! Motion blur and depth of field through the whole pipeline (docs/reyes.md, "Motion blur and
//! depth of field"), on lavapipe in CI: each effect changes the image where it should and
//! nowhere else, both GPU strategies give the same bits for each sampling algorithm, the CPU
//! twin agrees, and the three algorithms converge to the same many-sample reference.

use reyes::cpu_render::render_cpu;
use reyes::frame::{FrameData, RenderOptions, Sampling};
use reyes::image::FrameImage;
use reyes::orbit::orbit_scene;
use reyes::progress::NoProgress;
use reyes::realtime::{Pixels, RealtimeRenderer};
use reyes::scene::{self, Scene};
use scheduler::StrategyKind;

mod common;
use common::{CPU_TWIN_OVER_MOTION, compare, gpu, renderer};

const ALL: [Sampling; 3] = [
    Sampling::Simple,
    Sampling::Interleave,
    Sampling::BoundingBox,
];

/// Two quads side by side (left at depth 4, right at depth 10) under `motion` (RIB lines
/// around the right quad, e.g. a `MotionBegin` block), 48x32 pixels.
fn quads(options: &str, motion: &str) -> Scene {
    let text = format!(
        "Format 48 32 1\nPixelSamples 2 2\nProjection \"perspective\" \"fov\" 40\n{options}\n\
         WorldBegin\nSurface \"matte\"\n\
         AttributeBegin\nColor 1 0.2 0.2\nTranslate -1.2 0 4\n\
         Patch \"bilinear\" \"P\" [-1 -1 0  0.9 -1 0  -1 1 0  0.9 1 0]\nAttributeEnd\n\
         AttributeBegin\nColor 0.2 0.4 1\n{motion}\nTranslate 2.5 0 10\n\
         Patch \"bilinear\" \"P\" [-1.5 -2 0  1.5 -2 0  -1.5 2 0  1.5 2 0]\nAttributeEnd\n\
         WorldEnd\n"
    );
    scene::parse_rib(&text, "quads.rib").unwrap_or_else(|e| panic!("{e}"))
}

fn options(sampling: Sampling, spp: u32) -> RenderOptions {
    RenderOptions {
        sampling,
        pixel_samples: Some((spp, spp)),
        ..Default::default()
    }
}

/// The megakernel's image, asserting that multipass gives the same bits and counters.
fn render_gpu(data: &FrameData) -> FrameImage {
    let (a, b) = common::render_both_strategies(data);
    assert_eq!(a.counters, b.counters, "counters");
    a.image
}

/// What RIB gives the right quad: a translation of 1 unit along x over the shutter (4.4 px).
const MOVE: &str = "MotionBegin [0 1]\nTranslate 0 0 0\nTranslate 1 0 0\nMotionEnd";
const SHUTTER: &str = "Shutter 0 1";
/// Focused on the left quad's plane (z = 4); lens radius 0.5: the right quad (z = 10) has a
/// circle of confusion of 44 * 0.5 * (1/4 - 1/10) = 3.3 px.
const DOF: &str = "DepthOfField 1 1 4";

/// Pixels (x, y) of the 48x32 image whose colour or alpha differ.
fn differing(a: &FrameImage, b: &FrameImage) -> Vec<(u32, u32)> {
    (0..a.rgba.len())
        .filter(|&i| a.rgba[i] != b.rgba[i])
        .map(|i| (i as u32 % a.width, i as u32 / a.width))
        .collect()
}

/// Pixels partly covered (alpha strictly between 0.05 and 0.95) in columns `x0..x1`.
fn partial(img: &FrameImage, x0: u32, x1: u32) -> usize {
    (0..img.rgba.len())
        .filter(|&i| (x0..x1).contains(&(i as u32 % img.width)))
        .filter(|&i| img.rgba[i][3] > 0.05 && img.rgba[i][3] < 0.95)
        .count()
}

/// A `MotionBegin` block whose two transforms are equal is no motion: the same patches, the
/// same frame, the same bits as the file without it. And motion that is there but zero (an
/// identity map) goes through each time-sampling algorithm and gives the still image bit for
/// bit: each sub-sample is tested once against the unmoved micropolygon, as the still sampler
/// tests it.
#[test]
fn zero_motion_is_no_motion() {
    let still = quads(SHUTTER, "");
    let zero = quads(
        SHUTTER,
        "MotionBegin [0 1]\nTranslate 0 0 0\nTranslate 0 0 0\nMotionEnd",
    );
    assert!(zero.patches.iter().all(|p| p.motion.is_none()));
    let o = options(Sampling::Simple, 2);
    let reference = render_gpu(&FrameData::new(&still, &o).unwrap());
    assert!(reference == render_gpu(&FrameData::new(&zero, &o).unwrap()));
    let mut identity = still.clone();
    identity.patches[1].motion = Some(Box::new(glam::DMat4::IDENTITY));
    for sampling in ALL {
        let d = FrameData::new(&identity, &options(sampling, 2)).unwrap();
        assert!(d.features().uvt, "the time-sampling code runs");
        let img = render_gpu(&d);
        assert!(
            differing(&img, &reference).is_empty(),
            "{sampling:?}: {:?}",
            differing(&img, &reference)
        );
    }
}

/// Motion blurs the moving quad and nothing else, and the way it moves: the still quad's
/// pixels keep their bits, and so does everything left of the moving quad's left edge at
/// shutter open (column 28.4); its edges spread over the 4.4 px it moves to the right.
#[test]
fn motion_blurs_only_what_moves() {
    let still =
        render_gpu(&FrameData::new(&quads(SHUTTER, ""), &options(Sampling::Simple, 2)).unwrap());
    for sampling in ALL {
        let d = FrameData::new(&quads(SHUTTER, MOVE), &options(sampling, 2)).unwrap();
        let img = render_gpu(&d);
        let diff = differing(&img, &still);
        assert!(diff.iter().all(|&(x, _)| x >= 28), "{sampling:?}: {diff:?}");
        // The quad's left and right edges (18 rows each) sweep 4.4 px: about 150 pixels
        // change; at least 100 must.
        assert!(
            diff.len() >= 100,
            "{sampling:?}: {} pixels changed",
            diff.len()
        );
        assert!(
            partial(&img, 24, 48) > 2 * partial(&still, 24, 48).max(10),
            "{sampling:?}"
        );
    }
}

/// Depth of field focused on the left quad's plane leaves it sharp (circle of confusion 0:
/// the same bits wherever it covers the pixel fully, away from the other quad's blur) and
/// blurs the far quad.
#[test]
fn depth_of_field_keeps_the_focal_plane_sharp() {
    let still = render_gpu(&FrameData::new(&quads("", ""), &options(Sampling::Simple, 2)).unwrap());
    for sampling in ALL {
        let d = FrameData::new(&quads(DOF, ""), &options(sampling, 2)).unwrap();
        assert!(d.frame.coc_scale > 0.0);
        let img = render_gpu(&d);
        // The focal plane: depth 4 maps to a circle of confusion of exactly 0 (1/4 is exact in
        // f32), so the tolerance is none: every pixel of the left quad keeps its bits, up to
        // column 22 (the far quad's blur reaches 3.3 px left of column 28).
        let diff = differing(&img, &still);
        assert!(diff.iter().all(|&(x, _)| x >= 22), "{sampling:?}: {diff:?}");
        assert!(
            partial(&img, 24, 48) > 2 * partial(&still, 24, 48).max(10),
            "{sampling:?}"
        );
    }
}

/// Megakernel and multipass give the same bits (render_gpu), and the CPU twin the same image
/// within the twin tolerance for motion and depth of field together
/// ([`common::CPU_TWIN_OVER_MOTION`]).
#[test]
fn the_cpu_twin_agrees() {
    let s = quads(&format!("{SHUTTER}\n{DOF}"), MOVE);
    for sampling in ALL {
        let d = FrameData::new(&s, &options(sampling, 2)).unwrap();
        let (max, over) = compare(&render_gpu(&d), &render_cpu(&d).image);
        assert!(
            over <= CPU_TWIN_OVER_MOTION,
            "{sampling:?}: {:.2}% over 2/255 (max {max})",
            over * 100.0
        );
    }
}

/// Root mean square difference of two images' premultiplied linear RGBA.
fn rmse(a: &FrameImage, b: &FrameImage) -> f64 {
    let se: f64 = (a.rgba.iter().zip(&b.rgba))
        .map(|(p, q)| {
            (0..4)
                .map(|c| ((p[c] * p[3]) as f64 - (q[c] * q[3]) as f64).powi(2))
                .sum::<f64>()
        })
        .sum();
    (se / (4 * a.rgba.len()) as f64).sqrt()
}

/// The three algorithms estimate the same image: their error (RMSE of premultiplied linear
/// RGBA) against a many-sample reference (the CPU twin's mean of the three at 16x16 samples
/// per pixel) shrinks as the samples grow from 1 to 64 per pixel, to under 0.3 of it. (Noise
/// alone would fall 8-fold; the reference's own noise and the anti-aliasing of the edges hold
/// every algorithm near 0.04 at 64 samples: measured 0.23-0.26 of the 1-sample error for
/// the three, the bounding box's per-pixel samples, hashed over the whole image since they
/// became the default, at 0.26.)
#[test]
fn the_algorithms_converge_to_one_reference() {
    let s = quads(&format!("{SHUTTER}\n{DOF}"), MOVE);
    let refs: Vec<FrameImage> = ALL
        .iter()
        .map(|&a| render_cpu(&FrameData::new(&s, &options(a, 16)).unwrap()).image)
        .collect();
    // At 256 samples the three agree to within their noise (measured 0.011-0.014; at one
    // sample each is 0.16-0.18 from the reference).
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let e = rmse(&refs[i], &refs[j]);
        assert!(
            e < 0.02,
            "{:?} against {:?} at 256 spp: RMSE {e}",
            ALL[i],
            ALL[j]
        );
    }
    let mut reference = refs[0].clone();
    for (i, p) in reference.rgba.iter_mut().enumerate() {
        for (c, v) in p.iter_mut().enumerate() {
            *v = refs
                .iter()
                .map(|r| r.rgba[i][c] * r.rgba[i][3])
                .sum::<f32>()
                / 3.0;
        }
        // Premultiplied above; straight again (rmse premultiplies).
        if p[3] > 0.0 {
            for c in 0..3 {
                p[c] /= p[3];
            }
        }
    }
    for sampling in ALL {
        let errors: Vec<f64> = [1, 2, 4, 8]
            .iter()
            .map(|&n| {
                rmse(
                    &reference,
                    &render_gpu(&FrameData::new(&s, &options(sampling, n)).unwrap()),
                )
            })
            .collect();
        eprintln!("{sampling:?}: RMSE at 1, 4, 16, 64 spp: {errors:?}");
        assert!(
            errors.windows(2).all(|w| w[1] < w[0]) && errors[3] < 0.3 * errors[0],
            "{sampling:?}: RMSE at 1, 4, 16, 64 spp: {errors:?}"
        );
    }
}

/// The pipelined renderer of `reyes bench` renders a spinning teapot (`reyes render --spin`)
/// with depth of field as `reyes render` renders it turned on the host: at angle 0 bit for
/// bit, at 40 degrees (the motion seen from the turned camera, T D T^-1, rewritten in the
/// table each frame) within the turntable test's tolerance (reyes_realtime.rs: f32 against
/// f64 turns move a few edge samples): at most 0.5% of pixels off by more than 2/255.
#[test]
fn the_pipelined_renderer_blurs_like_render() {
    let mut s = scene::builtin_teapot();
    scene::spin(&mut s, 10.0).unwrap();
    s.camera.depth_of_field = Some(scene::DepthOfField {
        fstop: 4.0,
        focal_length: 1.0,
        focal_distance: 5.0,
    });
    let o = RenderOptions {
        width: Some(48),
        height: Some(36),
        ..options(Sampling::BoundingBox, 1)
    };
    let mut r =
        RealtimeRenderer::new(gpu(), &s, &o, StrategyKind::Multipass, Pixels::Float).unwrap();
    let frames = r
        .render(gpu(), &[0.0, 40f64.to_radians()], &NoProgress)
        .unwrap();
    for (f, deg) in frames.iter().zip([0.0, 40.0]) {
        let host = FrameData::new(&orbit_scene(&s, f64::to_radians(deg)), &o).unwrap();
        let reference = renderer(StrategyKind::Multipass)
            .render(gpu(), &host)
            .unwrap()
            .image;
        let got = f.image.as_ref().unwrap();
        if deg == 0.0 {
            assert!(got == &reference, "angle 0 differs from reyes render");
        } else {
            let (max, over) = got.compare(&reference);
            assert!(
                over <= 0.005,
                "{deg} deg: {:.2}% over 2/255 (max {max})",
                over * 100.0
            );
        }
    }
    let still = FrameData::new(&scene::builtin_teapot(), &o).unwrap();
    let still = renderer(StrategyKind::Multipass)
        .render(gpu(), &still)
        .unwrap()
        .image;
    assert!(
        frames[0].image.as_ref().unwrap() != &still,
        "the spin and the lens blur"
    );
}

/// A bar 6 px wide and 200 px tall sliding 90 px to the right over the shutter (x from
/// [30, 36] at shutter open to [120, 126] at close), 240x240, the default pixel samples (2x2).
fn sliding_bar() -> Scene {
    // fov 90 on a square frame: focal 120 px; at depth 1.2, x = 120 + 100 X, y = 120 - 100 Y.
    let text = "Format 240 240 1\nProjection \"perspective\" \"fov\" 90\nShutter 0 1\n\
        WorldBegin\nSurface \"constant\"\nAttributeBegin\n\
        MotionBegin [0 1]\nTranslate 0 0 0\nTranslate 0.9 0 0\nMotionEnd\n\
        Patch \"bilinear\" \"P\" [-0.9 -1 1.2  -0.84 -1 1.2  -0.9 1 1.2  -0.84 1 1.2]\n\
        AttributeEnd\nWorldEnd\n";
    scene::parse_rib(text, "sliding_bar.rib").unwrap_or_else(|e| panic!("{e}"))
}

/// Alpha summed over each column of `img`.
fn column_coverage(img: &FrameImage) -> Vec<f64> {
    let mut c = vec![0f64; img.width as usize];
    for (i, p) in img.rgba.iter().enumerate() {
        c[i % img.width as usize] += p[3] as f64;
    }
    c
}

/// The exact time-averaged column coverage of [`sliding_bar`]: 200 rows times the mean over
/// the shutter of the overlap of column [x, x + 1] with the bar [30 + 90 t, 36 + 90 t]
/// (midpoint rule over 90,000 instants: 1,000 per pixel of travel, far below the noise).
fn sliding_bar_exact(width: usize) -> Vec<f64> {
    let steps = 90_000;
    let mut c = vec![0f64; width];
    for s in 0..steps {
        let t = (s as f64 + 0.5) / steps as f64;
        let (a, b) = (30.0 + 90.0 * t, 36.0 + 90.0 * t);
        for (x, v) in c.iter_mut().enumerate() {
            let overlap = (b.min(x as f64 + 1.0) - a.max(x as f64)).max(0.0);
            *v += 200.0 * overlap / steps as f64;
        }
    }
    c
}

/// `profile` box-filtered over 5 columns (a ghost copy's gap is 16 px wide, the noise of one
/// column about 13% of the plateau; the filter takes it to about 6%).
fn smooth(profile: &[f64]) -> Vec<f64> {
    (0..profile.len())
        .map(|x| {
            let (a, b) = (x.saturating_sub(2), (x + 3).min(profile.len()));
            profile[a..b].iter().sum::<f64>() / 5.0
        })
        .collect()
}

/// The ghost criterion: how many distinct copies the smoothed column coverage shows, that is
/// separate runs where it rises above 3/4 of `plateau` (the exact blur's height), a run ending
/// only where it falls below 1/4 of it. A smooth blur is one run; S ghosts (Simple UVT at S
/// samples, copies apart) are S.
fn copies(profile: &[f64], plateau: f64) -> usize {
    let (mut runs, mut inside) = (0, false);
    for &v in profile {
        if !inside && v > 0.75 * plateau {
            runs += 1;
            inside = true;
        } else if inside && v < 0.25 * plateau {
            inside = false;
        }
    }
    runs
}

/// Issue 23, item 7: at the default settings a moving bar blurs smoothly instead of showing S
/// copies. The default sampler (bounding box: each pixel's samples at their own times,
/// stratified per pixel) shows one copy where Simple UVT shows the 4 of its 4 instants, its
/// column coverage follows the exact time average (the most any smoothed column is off is
/// under 0.3 of the plateau; Simple's copies are 3.75 times it), and the covered area is the
/// bar's, 1,200 px, within 5%: each of the 76,800 samples under the swept band (96 x 200 px, 4
/// each) is covered with probability at most p = 1/15, so the area's standard deviation is at
/// most sqrt(76800 p (1 - p)) / 4 = 17 px (1.4%; the tolerance is 3.5 of it) without the time
/// stratification, which only lowers it. Both GPU strategies give
/// the same bits (render_gpu) and the CPU twin the same image within the motion tolerance.
#[test]
fn the_default_blurs_motion_without_ghosts() {
    assert_eq!(RenderOptions::default().sampling, Sampling::BoundingBox);
    let s = sliding_bar();
    let exact = sliding_bar_exact(240);
    let plateau = 200.0 * 6.0 / 90.0;
    let exact_smooth = smooth(&exact);
    let d = FrameData::new(&s, &RenderOptions::default()).unwrap();
    assert_eq!((d.frame.spp_x, d.frame.spp_y), (2, 2));
    let img = render_gpu(&d);
    let (max, over) = compare(&img, &render_cpu(&d).image);
    assert!(
        over <= CPU_TWIN_OVER_MOTION,
        "CPU twin: {:.2}% over 2/255 (max {max})",
        over * 100.0
    );
    let simple = render_gpu(&FrameData::new(&s, &options(Sampling::Simple, 2)).unwrap());
    for (name, img) in [("default", &img), ("simple", &simple)] {
        let profile = smooth(&column_coverage(img));
        let n = copies(&profile, plateau);
        let off = (profile.iter().zip(&exact_smooth))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let area: f64 = column_coverage(img).iter().sum();
        eprintln!(
            "{name}: {n} copies, smoothed column coverage off by up to {:.2} of the plateau, \
             area {area:.1} px (exact 1200)",
            off / plateau
        );
        if name == "default" {
            assert_eq!(n, 1, "the default shows {n} copies");
            assert!(off < 0.3 * plateau, "profile off by {off:.2} px");
            assert!((area - 1200.0).abs() < 60.0, "area {area:.1}, exact 1200");
        } else {
            assert!(
                n >= 3,
                "Simple UVT shows {n} copies: the criterion misses ghosts"
            );
        }
    }
}
