//! Displacement: what RIB's `Displacement` request and the `"displacementbound"` attribute
//! give a patch. DiceShade moves every grid point along the surface normal by
//! `amount * pattern(u, v)`, (u, v) the parameters of the original patch (docs/reyes.md,
//! "Displacement").

use crate::Error;
use std::path::Path;
use std::sync::Arc;

/// Built-in displacement shaders, by the names RIB's `Displacement` request uses.
pub const DISPLACEMENT_NAMES: &[&str] = &["bumps", "mapped"];

/// Most texels on a side of a displacement map (its size is packed in 16 bits per side).
pub const MAX_MAP_SIDE: u32 = 16384;

/// Most texels of a displacement map, 2^24 (4096 x 4096; 64 MiB in the frame's table, where
/// they go 4 to a 16-byte entry): checked from the image's header before it is decoded, so a
/// 16384 x 16384 map is refused at its `Displacement` line instead of taking 2.3 GB and then
/// failing as a GPU buffer. Sample a larger map down to fit.
pub const MAX_MAP_TEXELS: u64 = 1 << 24;

/// The scalar field a displacement scales: values in [0, 1] over the original patch's (u, v).
#[derive(Clone, Debug, PartialEq)]
pub enum DisplacementPattern {
    /// `"bumps"`: (sin(pi f u) sin(pi f v))^2 with f = `frequency` (RIB `"frequency"`, a
    /// whole number 1..=[`MAX_BUMPS_FREQUENCY`], default 1): f x f bumps per patch, 0 on every
    /// patch edge, so neighbouring patches agree wherever they meet.
    Bumps {
        /// Bumps per patch side, 1..=[`MAX_BUMPS_FREQUENCY`].
        frequency: u32,
    },
    /// `"mapped"` with `"mapname"`: an image's luminance, sampled bilinearly at (u, v) (texel
    /// centres at (x + 0.5) / width, clamped at the edges; v = 0 is the image's top row).
    Map(Arc<DisplacementMap>),
}

/// Most bumps per patch side of [`DisplacementPattern::Bumps`].
pub const MAX_BUMPS_FREQUENCY: u32 = 64;

/// A displacement map: luminance per texel, row-major from the top row, in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct DisplacementMap {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` luminances in [0, 1], row-major from the top row.
    pub texels: Vec<f32>,
}

impl DisplacementMap {
    /// Reads a PNG (8 or 16 bit, any channels) or OpenEXR image through the `image` crate and
    /// keeps its luminance (for EXR, clamped to [0, 1]). Errors name the file:
    /// [`Error::DisplacementMapUnreadable`], [`Error::DisplacementMapSize`],
    /// [`Error::DisplacementMapNotAFile`] (only regular files are read: a FIFO would block),
    /// [`Error::DisplacementMapNaN`] (a NaN texel is refused, not taken as 0).
    pub fn load(path: &Path) -> Result<DisplacementMap, Error> {
        // Only regular files: a FIFO or a device would block or never end (links are
        // followed). A path that does not exist is left to `image::open`'s error.
        if let Ok(m) = std::fs::metadata(path)
            && !m.is_file()
        {
            return Err(Error::DisplacementMapNotAFile {
                path: path.to_path_buf(),
            });
        }
        let unreadable = |source| Error::DisplacementMapUnreadable {
            path: path.to_path_buf(),
            source,
        };
        let size_error = |(width, height)| Error::DisplacementMapSize {
            path: path.to_path_buf(),
            width,
            height,
            max_side: MAX_MAP_SIDE,
            max_texels: MAX_MAP_TEXELS,
        };
        let fits = |(w, h): (u32, u32)| {
            (1..=MAX_MAP_SIDE).contains(&w)
                && (1..=MAX_MAP_SIDE).contains(&h)
                && w as u64 * h as u64 <= MAX_MAP_TEXELS
        };
        // The size from the header first: nothing is decoded for a map that will not fit.
        let reader = image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| unreadable(image::ImageError::IoError(e)))?;
        let size = reader.into_dimensions().map_err(unreadable)?;
        if !fits(size) {
            return Err(size_error(size));
        }
        let img = image::open(path).map_err(unreadable)?;
        let (width, height) = (img.width(), img.height());
        if !fits((width, height)) {
            return Err(size_error((width, height)));
        }
        let luma = img.to_luma32f();
        if let Some(i) = luma.as_raw().iter().position(|x| x.is_nan()) {
            let i = i as u32;
            return Err(Error::DisplacementMapNaN {
                path: path.to_path_buf(),
                x: i % width,
                y: i / width,
            });
        }
        let texels = luma
            .into_raw()
            .into_iter()
            .map(|x| x.clamp(0.0, 1.0))
            .collect();
        Ok(DisplacementMap {
            width,
            height,
            texels,
        })
    }
}

/// A patch's displacement, in camera space.
#[derive(Clone, Debug, PartialEq)]
pub struct Displacement {
    /// The scalar field, in [0, 1] over the original patch's (u, v).
    pub pattern: DisplacementPattern,
    /// Camera-space distance per unit of the pattern: `"Km"` times the object-to-camera
    /// transform's mean scale (the cube root of its determinant's magnitude; exact for
    /// rotations, translations and uniform scales). Negative moves inward.
    pub amount: f64,
    /// Camera-space radius every point may move: the larger of `"displacementbound"`'s
    /// sphere (object space, times the transform's largest stretch) and |amount| (the
    /// pattern's values lie in [0, 1]), so a bound given too small never culls what shows.
    pub bound: f64,
}
