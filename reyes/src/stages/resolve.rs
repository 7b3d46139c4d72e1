//! Twin of `shaders/reyes/resolve.wgsl`: sub-samples to pixels (linear colour, coverage alpha).

use super::shade::srgb_decode;
use crate::image::BACKGROUND_DEPTH;

/// Straight (not premultiplied) linear RGBA and nearest depth ([`BACKGROUND_DEPTH`] where
/// nothing was hit).
/// With a `background` (`Imager "background"`) every pixel is composited over it and opaque:
/// `c alpha + background (1 - alpha)`, alpha 1.
pub fn resolve(
    keys: &[u64],
    width: u32,
    height: u32,
    spp: u32,
    background: Option<[f32; 3]>,
) -> (Vec<[f32; 4]>, Vec<f32>) {
    let n = (width * height) as usize;
    let (mut rgba, mut depth) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for p in 0..n {
        let (mut sum, mut covered, mut zmin) = ([0f32; 3], 0u32, BACKGROUND_DEPTH);
        for &k in &keys[p * spp as usize..(p + 1) * spp as usize] {
            let (lo, hi) = (k as u32, (k >> 32) as u32);
            if hi == 0 {
                continue;
            }
            covered += 1;
            for (c, s) in sum.iter_mut().enumerate() {
                *s += srgb_decode(((lo >> (10 * c)) & 1023) as f32 / 1023.0);
            }
            zmin = zmin.min(f32::from_bits(!hi));
        }
        let c = if covered > 0 {
            sum.map(|s| s / covered as f32)
        } else {
            [0.0; 3]
        };
        let alpha = covered as f32 / spp as f32;
        rgba.push(match background {
            Some(b) => {
                let k = 1.0 - alpha;
                [
                    c[0] * alpha + b[0] * k,
                    c[1] * alpha + b[1] * k,
                    c[2] * alpha + b[2] * k,
                    1.0,
                ]
            }
            None => [c[0], c[1], c[2], alpha],
        });
        depth.push(zmin);
    }
    (rgba, depth)
}
