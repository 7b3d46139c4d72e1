//! A rendered frame and its files: PNG (8-bit sRGB, alpha = coverage), PFM (linear float RGB),
//! depth (PFM, one channel) and OpenEXR (linear f32 R, G, B, A and Z in one file). Files are written to a temporary name and renamed, so a failed
//! write never leaves a half-written image under the requested name.

use crate::Error;
use crate::stages::shade::srgb_encode;
use std::path::Path;

/// How far one image is from another ([`FrameImage::difference`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageDifference {
    /// Peak signal-to-noise ratio of the 8-bit RGBA encodings, dB (infinite when equal).
    pub psnr_db: f64,
    /// Share of pixels differing by more than `threshold` steps in some channel.
    pub over: f64,
    /// Steps (of 255) a pixel may differ by without counting in `over`.
    pub threshold: u8,
    /// Largest difference of a channel, in steps.
    pub max: u8,
}

/// The depth of a pixel where the background shows ("nothing here"): what resolve writes when
/// no sample was hit, and what the depth files turn into +inf.
pub const BACKGROUND_DEPTH: f32 = 3.0e38;

/// Straight (not premultiplied) linear RGBA with coverage as alpha, and the nearest depth per
/// pixel ([`BACKGROUND_DEPTH`] where the background shows).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameImage {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Row-major pixels from the top row, `width * height`: linear RGB and coverage.
    pub rgba: Vec<[f32; 4]>,
    /// Row-major like `rgba`: the nearest camera-space z of each pixel.
    pub depth: Vec<f32>,
}

impl FrameImage {
    /// 8-bit RGBA, row-major: colour clamped to [0, 1] and sRGB-encoded, alpha linear. Not
    /// composited: the colour is straight.
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

    /// How far this image is from `reference` (the same size) in their 8-bit encodings
    /// ([`FrameImage::rgba8`]: colour in sRGB steps, alpha in 1/255): the PSNR over every
    /// channel of every pixel, and the share of pixels differing by more than `threshold`
    /// steps in some channel.
    pub fn difference(&self, reference: &FrameImage, threshold: u8) -> ImageDifference {
        let (x, y) = (self.rgba8(), reference.rgba8());
        let mut sq = 0f64;
        let (mut over, mut max) = (0usize, 0u8);
        for (p, q) in x.chunks(4).zip(y.chunks(4)) {
            let d = (0..4).map(|c| p[c].abs_diff(q[c])).max().unwrap();
            sq += (0..4)
                .map(|c| (p[c] as f64 - q[c] as f64).powi(2))
                .sum::<f64>();
            over += (d > threshold) as usize;
            max = max.max(d);
        }
        let mse = sq / x.len().max(1) as f64;
        ImageDifference {
            psnr_db: if mse > 0.0 {
                10.0 * (255.0f64 * 255.0 / mse).log10()
            } else {
                f64::INFINITY
            },
            over: over as f64 / (x.len() / 4).max(1) as f64,
            threshold,
            max,
        }
    }

    /// Pixels with any coverage: a surface's depth, not [`BACKGROUND_DEPTH`]. Not alpha,
    /// which an `Imager "background"` makes 1 everywhere; alpha only for an image without
    /// depth.
    pub fn covered_pixels(&self) -> usize {
        if self.depth.len() == self.rgba.len() {
            self.depth.iter().filter(|&&z| z < BACKGROUND_DEPTH).count()
        } else {
            self.rgba.iter().filter(|p| p[3] > 0.0).count()
        }
    }

    /// Writes [`FrameImage::rgba8`] to `path` as a PNG, atomically (a temporary file renamed).
    /// Errors: encoding or writing the file ([`Error`]).
    pub fn write_png(&self, path: &Path) -> Result<(), Error> {
        let img = image::RgbaImage::from_raw(self.width, self.height, self.rgba8())
            .ok_or(Error::BufferSizeMismatch)?;
        crate::output::write_atomic(path, &crate::output::png(&img)?)
    }

    /// Linear RGB as PFM (bottom row first, little-endian).
    pub fn write_pfm(&self, path: &Path) -> Result<(), Error> {
        self.pfm(path, 3, |p, c| self.rgba[p][c])
    }

    /// Camera-space depth as a one-channel PFM; background pixels hold +inf.
    pub fn write_depth(&self, path: &Path) -> Result<(), Error> {
        self.pfm(path, 1, |p, _| self.file_depth(p))
    }

    /// Background depth in the files: +inf (the renderer's [`BACKGROUND_DEPTH`]).
    fn file_depth(&self, p: usize) -> f32 {
        if self.depth[p] >= BACKGROUND_DEPTH {
            f32::INFINITY
        } else {
            self.depth[p]
        }
    }

    /// The image as OpenEXR: one layer, channels R, G, B, A and Z, all 32-bit float, linear,
    /// ZIP-compressed (lossless). Colour is premultiplied by alpha (coverage), as OpenEXR
    /// defines it and compositing tools expect (`R = rgba[0] * rgba[3]`, exactly in f32); Z is
    /// the camera-space depth of the nearest sample, +inf where the background shows. Rows
    /// top to bottom. Written with the `exr` crate.
    pub fn exr(&self) -> Result<Vec<u8>, crate::Error> {
        use exr::prelude::*;
        let n = self.rgba.len();
        let premultiplied =
            |c: usize| FlatSamples::F32(self.rgba.iter().map(|p| p[c] * p[3]).collect());
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![
            AnyChannel::new("R", premultiplied(0)),
            AnyChannel::new("G", premultiplied(1)),
            AnyChannel::new("B", premultiplied(2)),
            AnyChannel::new(
                "A",
                FlatSamples::F32(self.rgba.iter().map(|p| p[3]).collect()),
            ),
            AnyChannel::new(
                "Z",
                FlatSamples::F32((0..n).map(|p| self.file_depth(p)).collect()),
            ),
        ]));
        let layer = Layer::new(
            (self.width as usize, self.height as usize),
            LayerAttributes::default(),
            Encoding::SMALL_LOSSLESS,
            channels,
        );
        let mut out = std::io::Cursor::new(Vec::new());
        Image::from_layer(layer)
            .write()
            .to_buffered(&mut out)
            .map_err(crate::Error::EncodeExr)?;
        Ok(out.into_inner())
    }

    /// Reads an OpenEXR image as [`FrameImage::exr`] writes it: channels R, G, B
    /// (premultiplied), A and optionally Z, in f32 or f16, first layer. Errors name the file.
    pub fn read_exr(path: &Path) -> Result<FrameImage, crate::Error> {
        use exr::prelude::*;
        let missing = |what: String| crate::Error::ImageContent {
            path: path.to_path_buf(),
            what,
        };
        let image =
            read_all_flat_layers_from_file(path).map_err(|source| crate::Error::ReadExr {
                path: path.to_path_buf(),
                source,
            })?;
        let layer = (image.layer_data.first()).ok_or_else(|| missing("no image layer".into()))?;
        let (w, h) = (layer.size.width(), layer.size.height());
        let channel = |name: &str| {
            (layer.channel_data.list.iter())
                .find(|c| c.name.eq(name))
                .map(|c| c.sample_data.values_as_f32().collect::<Vec<f32>>())
        };
        let need = |name: &str| channel(name).ok_or_else(|| missing(format!("no {name} channel")));
        let (r, g, b, a) = (need("R")?, need("G")?, need("B")?, need("A")?);
        let z = channel("Z").unwrap_or_else(|| vec![f32::INFINITY; w * h]);
        let rgba = (0..w * h)
            .map(|i| {
                let s = if a[i] > 0.0 { 1.0 / a[i] } else { 0.0 };
                [r[i] * s, g[i] * s, b[i] * s, a[i]]
            })
            .collect();
        let depth = z
            .iter()
            .map(|&z| if z.is_finite() { z } else { BACKGROUND_DEPTH })
            .collect();
        Ok(FrameImage {
            width: w as u32,
            height: h as u32,
            rgba,
            depth,
        })
    }

    /// [`FrameImage::exr`] written to `path` (atomically).
    pub fn write_exr(&self, path: &Path) -> Result<(), Error> {
        crate::output::write_atomic(path, &self.exr()?)
    }

    fn pfm(
        &self,
        path: &Path,
        channels: usize,
        value: impl Fn(usize, usize) -> f32,
    ) -> Result<(), Error> {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Coverage is counted from depth: the same frame composited over an `Imager
    /// "background"` (every pixel opaque) has as many covered pixels as without it.
    #[test]
    fn covered_pixels_are_the_same_with_a_background_imager() {
        let keys = |covered: bool| {
            let hi = if covered { !1.5f32.to_bits() } else { 0 };
            (u64::from(hi) << 32) | 0x3ff
        };
        // 3 x 2 pixels, 2 samples each: two pixels covered (one at the edge), four not.
        let samples = [
            true, true, false, true, false, false, false, false, false, false, false, false,
        ];
        let k: Vec<u64> = samples.iter().map(|&c| keys(c)).collect();
        let (plain, depth) = crate::stages::resolve::resolve(&k, 3, 2, 2, None);
        let (opaque, depth_bg) = crate::stages::resolve::resolve(&k, 3, 2, 2, Some([1.0; 3]));
        let image = |rgba, depth| FrameImage {
            width: 3,
            height: 2,
            rgba,
            depth,
        };
        assert!(opaque.iter().all(|p| p[3] == 1.0));
        assert_eq!(image(plain, depth).covered_pixels(), 2);
        assert_eq!(image(opaque, depth_bg).covered_pixels(), 2);
    }

    /// The OpenEXR file reads back (with the `exr` crate) as the image's channels, exactly:
    /// premultiplied colour, coverage, depth with the background at +inf.
    #[test]
    fn exr_holds_colour_alpha_and_depth_exactly() {
        let (width, height) = (5u32, 3u32);
        let n = (width * height) as usize;
        let img = FrameImage {
            width,
            height,
            rgba: (0..n)
                .map(|i| {
                    let t = i as f32 / 7.0;
                    [t, 1.0 - t / 3.0, 0.1 + t * t, (i % 4) as f32 / 3.0]
                })
                .collect(),
            depth: (0..n)
                .map(|i| if i % 4 == 0 { 3.0e38 } else { 1.5 + i as f32 })
                .collect(),
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.exr");
        img.write_exr(&path).unwrap();
        let read = exr::prelude::read_first_flat_layer_from_file(&path).unwrap();
        let layer = &read.layer_data;
        assert_eq!(layer.size.0, width as usize);
        assert_eq!(layer.size.1, height as usize);
        let channel = |name: &str| -> Vec<f32> {
            let c = layer
                .channel_data
                .list
                .iter()
                .find(|c| &c.name == name)
                .unwrap_or_else(|| panic!("no channel {name}"));
            match &c.sample_data {
                exr::prelude::FlatSamples::F32(v) => v.clone(),
                other => panic!("{name} is not f32: {other:?}"),
            }
        };
        let names: Vec<String> = (layer.channel_data.list.iter())
            .map(|c| c.name.to_string())
            .collect();
        assert_eq!(names, ["A", "B", "G", "R", "Z"]);
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            let want: Vec<f32> = img.rgba.iter().map(|p| p[c] * p[3]).collect();
            assert_eq!(channel(name), want, "{name}");
        }
        let alpha: Vec<f32> = img.rgba.iter().map(|p| p[3]).collect();
        assert_eq!(channel("A"), alpha);
        let z = channel("Z");
        assert_eq!(z[0], f32::INFINITY);
        assert_eq!(z[1], 2.5);
        assert_eq!(z, (0..n).map(|p| img.file_depth(p)).collect::<Vec<_>>());
    }
}
