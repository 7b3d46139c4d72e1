//! Holes: background showing through a surface where a reference says the surface covers the
//! image, counted per pixel and per sub-sample (docs/reyes.md, *Rasterization modes*). The
//! reference is a per-pixel [`Coverage`]: the exact f64 surfaces (`reference::coverage`) or,
//! where those are not the surface drawn (a displaced scene), a bounding-box render of the same
//! frame ([`coverage_of`]).

use reyes::image::FrameImage;
use reyes::reference::Coverage;
use serde::{Deserialize, Serialize};

/// A render's holes against a reference coverage.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Holes {
    /// Pixels that must be solid: the reference covers them and their 8 neighbours fully
    /// ([`Coverage::interior`]), so any correct renderer covers every one of their sub-samples,
    /// whatever its sample pattern.
    pub interior_px: usize,
    /// Interior pixels the render leaves partly empty (alpha below 1 by more than 8-bit
    /// quantisation, 1/512, allows): `reference::pinholes`.
    pub hole_px: usize,
    /// Empty sub-samples of the interior pixels: the sum of round((1 - alpha) * samples per
    /// pixel) over them.
    pub hole_samples: u64,
    /// `hole_samples` over the interior pixels' sub-samples, in [0, 1].
    pub hole_sample_share: f64,
}

/// The holes of `image` (rendered with `samples_per_pixel` sub-samples per pixel) inside
/// `reference`'s interior. Panics when the two differ in size.
pub fn holes(image: &FrameImage, reference: &Coverage, samples_per_pixel: u32) -> Holes {
    let alpha: Vec<f32> = image.rgba.iter().map(|p| p[3]).collect();
    let hole_px = reyes::reference::pinholes(&alpha, reference);
    let interior = reference.interior();
    let spp = samples_per_pixel as f64;
    let (mut interior_px, mut hole_samples) = (0usize, 0u64);
    for (inside, a) in interior.iter().zip(&alpha) {
        if *inside {
            interior_px += 1;
            hole_samples += ((1.0 - (*a as f64).clamp(0.0, 1.0)) * spp).round() as u64;
        }
    }
    let all = interior_px as f64 * spp;
    Holes {
        interior_px,
        hole_px,
        hole_samples,
        hole_sample_share: if all > 0.0 {
            hole_samples as f64 / all
        } else {
            0.0
        },
    }
}

/// A render's own coverage (its alpha per pixel) as a reference: that of a bounding-box render
/// (`RasterMode::BoundingBox`) of the frame measures another mode's holes on a surface the
/// exact reference does not know (displacement).
pub fn coverage_of(image: &FrameImage) -> Coverage {
    Coverage {
        width: image.width,
        height: image.height,
        frac: image.rgba.iter().map(|p| p[3].clamp(0.0, 1.0)).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(alpha: &[f32], w: u32) -> FrameImage {
        FrameImage {
            width: w,
            height: alpha.len() as u32 / w,
            rgba: alpha.iter().map(|&a| [0.0, 0.0, 0.0, a]).collect(),
            depth: vec![0.0; alpha.len()],
        }
    }

    /// A 5x5 fully covered reference has a 3x3 interior; a render missing one of 4 sub-samples
    /// of the centre pixel and everything of a border pixel has one interior hole pixel
    /// (the border pixel is not interior) and one hole sample.
    #[test]
    fn counts_empty_samples_of_interior_pixels_only() {
        let reference = coverage_of(&image(&[1.0; 25], 5));
        assert_eq!(reference.interior().iter().filter(|b| **b).count(), 9);
        let mut a = [1.0; 25];
        a[12] = 0.75;
        a[0] = 0.0;
        let h = holes(&image(&a, 5), &reference, 4);
        assert_eq!(h.interior_px, 9);
        assert_eq!(h.hole_px, 1);
        assert_eq!(h.hole_samples, 1);
        assert!((h.hole_sample_share - 1.0 / 36.0).abs() < 1e-12);
        let solid = holes(&image(&[1.0; 25], 5), &reference, 4);
        assert_eq!((solid.hole_px, solid.hole_samples), (0, 0));
    }
}
