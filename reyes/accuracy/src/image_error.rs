//! Image error of a render against the reference render: PSNR and FLIP's mean.
//!
//! Both compare what a viewer sees: each image composited over black (linear colour times
//! coverage), encoded to 8-bit sRGB, RGB only. PSNR is over those 8-bit sRGB values (peak
//! 255, all three channels); FLIP is NVIDIA's perceptual difference (Andersson et al. 2020,
//! the LDR variant, through the `nv-flip` crate) at its default 67 pixels per degree, the
//! mean of its per-pixel error map in [0, 1].

use reyes::image::FrameImage;
use reyes::stages::shade::srgb_encode;

/// RGB bytes of `img` composited over black, 8-bit sRGB.
pub fn composite_srgb8(img: &FrameImage) -> Vec<u8> {
    img.rgba
        .iter()
        .flat_map(|p| {
            let a = p[3].clamp(0.0, 1.0);
            [0, 1, 2].map(|c| (srgb_encode(p[c] * a) * 255.0).round() as u8)
        })
        .collect()
}

/// Peak signal-to-noise ratio in dB of two equally long 8-bit images; +infinity when they
/// are identical.
pub fn psnr_db(reference: &[u8], test: &[u8]) -> f64 {
    assert_eq!(reference.len(), test.len(), "images differ in size");
    let se: f64 = reference
        .iter()
        .zip(test)
        .map(|(&a, &b)| (a as f64 - b as f64).powi(2))
        .sum();
    let mse = se / reference.len().max(1) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0 * 255.0 / mse).log10()
    }
}

/// Mean of FLIP's error map of `test` against `reference` (RGB bytes, 8-bit sRGB).
pub fn flip_mean(reference: &[u8], test: &[u8], width: u32, height: u32) -> f64 {
    assert_eq!(reference.len(), (width * height * 3) as usize);
    assert_eq!(test.len(), reference.len());
    let map = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(width, height, reference),
        nv_flip::FlipImageRgb8::with_data(width, height, test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    nv_flip::FlipPool::from_image(&map).mean() as f64
}

/// PSNR and FLIP of a render against a reference of the same size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageError {
    /// PSNR in dB over the 8-bit sRGB values; infinite for identical images.
    pub psnr_db: f64,
    /// Mean of FLIP's per-pixel error map, in [0, 1] (0: identical).
    pub flip_mean: f64,
}

/// PSNR and FLIP of `test` against `reference`, both composited over black (see the module
/// doc). Panics when their sizes differ.
pub fn image_error(reference: &FrameImage, test: &FrameImage) -> ImageError {
    assert_eq!(
        (reference.width, reference.height),
        (test.width, test.height),
        "images differ in size"
    );
    let (a, b) = (composite_srgb8(reference), composite_srgb8(test));
    srgb8_error(&a, &b, reference.width, reference.height)
}

/// [`ImageError`] of composited 8-bit sRGB images (see [`composite_srgb8`]).
pub fn srgb8_error(reference: &[u8], test: &[u8], width: u32, height: u32) -> ImageError {
    ImageError {
        psnr_db: psnr_db(reference, test),
        flip_mean: flip_mean(reference, test, width, height),
    }
}

/// [`srgb8_error`] of many images against one reference, on all cores (FLIP itself runs on
/// one).
pub fn srgb8_errors(
    reference: &[u8],
    tests: &[Vec<u8>],
    width: u32,
    height: u32,
) -> Vec<ImageError> {
    let mut out = super::parallel::in_chunks(tests.len(), 1, |k| {
        srgb8_error(reference, &tests[k.start], width, height)
    });
    out.sort_by_key(|e| e.0);
    out.into_iter().map(|e| e.1).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth gradient with a disc, straight alpha on its edge.
    fn picture(w: u32, h: u32) -> FrameImage {
        let rgba = (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f32, (k / w) as f32);
                let r = ((x - w as f32 / 2.0).powi(2) + (y - h as f32 / 2.0).powi(2)).sqrt();
                let a = (h as f32 / 3.0 - r).clamp(0.0, 1.0);
                [x / w as f32, y / h as f32, 0.4, a]
            })
            .collect();
        FrameImage {
            width: w,
            height: h,
            rgba,
            depth: vec![1.0; (w * h) as usize],
        }
    }

    #[test]
    fn identical_images_have_no_error() {
        let a = picture(64, 48);
        let e = image_error(&a, &a.clone());
        assert_eq!(e.psnr_db, f64::INFINITY);
        assert_eq!(e.flip_mean, 0.0);
    }

    #[test]
    fn perturbed_images_have_finite_growing_error() {
        let a = picture(64, 48);
        let perturb = |amount: f32| {
            let mut b = a.clone();
            for (k, p) in b.rgba.iter_mut().enumerate() {
                if k % 7 == 0 {
                    p[1] = (p[1] + amount).min(1.0);
                }
            }
            image_error(&a, &b)
        };
        let (small, big) = (perturb(0.05), perturb(0.3));
        assert!(small.psnr_db.is_finite() && small.psnr_db > big.psnr_db);
        assert!(
            big.psnr_db > 5.0 && small.psnr_db < 60.0,
            "{small:?} {big:?}"
        );
        assert!(0.0 < small.flip_mean && small.flip_mean < big.flip_mean);
        assert!(big.flip_mean < 1.0);
        // The parallel batch gives the same numbers, in order.
        let r = composite_srgb8(&a);
        let mut b = a.clone();
        b.rgba[5][0] = 0.0;
        let tests = vec![composite_srgb8(&b), r.clone(), composite_srgb8(&b)];
        let batch = srgb8_errors(&r, &tests, 64, 48);
        assert_eq!(batch.len(), 3);
        assert_eq!(batch[0], image_error(&a, &b));
        assert_eq!(batch[1].psnr_db, f64::INFINITY);
        assert_eq!(batch[2], batch[0]);
    }

    /// PSNR of a known error: every byte off by 1 gives 20 log10(255) dB.
    #[test]
    fn psnr_of_a_known_error() {
        let a = vec![100u8; 300];
        let b = vec![101u8; 300];
        assert!((psnr_db(&a, &b) - 20.0 * 255f64.log10()).abs() < 1e-12);
    }

    /// Coverage counts: a half-covered white pixel composites to half-intensity grey.
    #[test]
    fn compositing_uses_coverage() {
        let img = FrameImage {
            width: 2,
            height: 1,
            rgba: vec![[1.0, 1.0, 1.0, 0.5], [1.0, 1.0, 1.0, 0.0]],
            depth: vec![1.0; 2],
        };
        let half = (srgb_encode(0.5) * 255.0).round() as u8;
        assert_eq!(composite_srgb8(&img), vec![half, half, half, 0, 0, 0]);
    }
}
