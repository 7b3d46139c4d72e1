//! A rendered frame and its files: PNG (8-bit sRGB, alpha = coverage), PFM (linear float RGB)
//! and depth (PFM, one channel). Files are written to a temporary name and renamed, so a failed
//! write never leaves a half-written image under the requested name.

use crate::stages::shade::srgb_encode;
use std::path::Path;

/// Straight (not premultiplied) linear RGBA with coverage as alpha, and the nearest depth per
/// pixel (3e38 where the background shows).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameImage {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<[f32; 4]>,
    pub depth: Vec<f32>,
}

impl FrameImage {
    pub fn rgba8(&self) -> Vec<u8> {
        let q = |x: f32| (srgb_encode(x) * 255.0).round() as u8;
        self.rgba
            .iter()
            .flat_map(|p| {
                [
                    q(p[0]),
                    q(p[1]),
                    q(p[2]),
                    (p[3].clamp(0.0, 1.0) * 255.0).round() as u8,
                ]
            })
            .collect()
    }

    /// How far two images of the same size differ: the largest per-channel difference of
    /// their 8-bit encodings ([`FrameImage::rgba8`]: colour in sRGB steps, alpha in 1/255) and
    /// the share of pixels differing by more than 2 steps in some channel.
    pub fn compare(&self, other: &FrameImage) -> (u8, f64) {
        let (x, y) = (self.rgba8(), other.rgba8());
        let d: Vec<u8> = x
            .chunks(4)
            .zip(y.chunks(4))
            .map(|(p, q)| (0..4).map(|c| p[c].abs_diff(q[c])).max().unwrap())
            .collect();
        let max = d.iter().copied().max().unwrap_or(0);
        let over = d.iter().filter(|&&v| v > 2).count() as f64 / d.len().max(1) as f64;
        (max, over)
    }

    /// Pixels with any coverage.
    pub fn covered_pixels(&self) -> usize {
        self.rgba.iter().filter(|p| p[3] > 0.0).count()
    }

    pub fn write_png(&self, path: &Path) -> Result<(), String> {
        let img = image::RgbaImage::from_raw(self.width, self.height, self.rgba8())
            .ok_or("image buffer size mismatch")?;
        crate::output::write_atomic(path, &crate::output::png(&img)?)
    }

    /// Linear RGB as PFM (bottom row first, little-endian).
    pub fn write_pfm(&self, path: &Path) -> Result<(), String> {
        self.pfm(path, 3, |p, c| self.rgba[p][c])
    }

    /// Camera-space depth as a one-channel PFM; background pixels hold +inf.
    pub fn write_depth(&self, path: &Path) -> Result<(), String> {
        self.pfm(path, 1, |p, _| {
            if self.depth[p] >= 3.0e38 {
                f32::INFINITY
            } else {
                self.depth[p]
            }
        })
    }

    fn pfm(
        &self,
        path: &Path,
        channels: usize,
        value: impl Fn(usize, usize) -> f32,
    ) -> Result<(), String> {
        let header = format!(
            "{}\n{} {}\n-1.0\n",
            if channels == 3 { "PF" } else { "Pf" },
            self.width,
            self.height
        );
        let mut bytes = header.into_bytes();
        for y in (0..self.height as usize).rev() {
            for x in 0..self.width as usize {
                for c in 0..channels {
                    bytes.extend_from_slice(&value(y * self.width as usize + x, c).to_le_bytes());
                }
            }
        }
        crate::output::write_atomic(path, &bytes)
    }
}
