//! What a user chooses about a render ([`RenderOptions`]) and how micropolygons become samples
//! ([`RasterMode`]).

#[allow(unused_imports)]
use super::*;

/// Quality and size settings of a render; `None` fields come from the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels; `None`: the scene's `Format`.
    pub width: Option<u32>,
    /// Image height in pixels; `None`: the scene's `Format`.
    pub height: Option<u32>,
    /// Sub-samples per pixel (x, y); `None`: the scene's `PixelSamples`.
    pub pixel_samples: Option<(u32, u32)>,
    /// Target micropolygon edge in pixels (RenderMan's shading rate is its square).
    pub mp_size: f32,
    /// `Some(px)`: Patney & Owens' fixed rule (split to a `px` screen bound, dice 16x16).
    pub bound_px: Option<f32>,
    /// Most segments per grid side (grid points = segments + 1 <= 16).
    pub grid_max: u32,
    /// Most splits of one item (clamped to 255); an item that reaches it is diced as it is.
    pub max_depth: u32,
    /// Most of an item's splits made because it crosses the near plane (each is also one of
    /// `max_depth`); a piece that reaches it is diced and clipped, never dropped.
    pub max_eye_splits: u32,
    /// Seed of the sub-sample jitter and stochastic transparency; the same seed gives the same
    /// image.
    pub seed: u32,
    /// Bytes of working memory (sample buffer plus queues) a frame may use; beyond it the
    /// frame renders in screen buckets.
    pub memory_budget: Option<u64>,
    /// Grow micropolygons to close cracks (docs/reyes.md); off only for comparisons.
    pub crack_dilation: bool,
    /// The normal displaced points move along; [`DisplacementNormals::Approximate`] only to
    /// show the holes it leaves.
    pub displacement_normals: DisplacementNormals,
    /// How micropolygons are rasterized ([`RasterMode`]).
    pub raster: RasterMode,
    /// How time and the lens are sampled when the scene has motion or depth of field.
    pub sampling: Sampling,
    /// Interleave UVT's tile side K (2..=4).
    pub il_tile: u32,
    /// Interleave UVT's number of permutations P (1..=1024).
    pub il_perms: u32,
    /// Occlusion culling in Bound against a depth pyramid of what is already drawn
    /// (docs/reyes.md, *Occlusion culling*); the image is the same either way.
    pub occlusion: Occlusion,
}

/// How a micropolygon becomes samples (Sattler & Steinberger, "Reyes Rendering on the GPU",
/// section 4.2; docs/reyes.md, *Rasterization modes*).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RasterMode {
    /// Bounding-box rasterization, the paper's "proper rasterization": every jittered
    /// sub-sample under the micropolygon's screen bound is tested against its two triangles.
    /// Leaves no holes between micropolygons that meet.
    #[default]
    BoundingBox,
    /// The paper's naive mode: one sample per micropolygon, the jittered sub-sample nearest its
    /// centre (the mean of its 4 projected corners), at the mean depth of its corners. Fast, but
    /// leaves holes wherever micropolygons are larger than the sample spacing.
    NearestSample,
}

impl RasterMode {
    /// The value of [`FrameUniforms::raster`] (`RASTER_BBOX`, `RASTER_NEAREST` in common.wgsl).
    pub fn gpu_code(self) -> u32 {
        match self {
            RasterMode::BoundingBox => RASTER_BBOX,
            RasterMode::NearestSample => RASTER_NEAREST,
        }
    }

    /// The mode of a [`FrameUniforms::raster`] value (anything but `RASTER_NEAREST` is bounding-box).
    pub fn from_gpu_code(code: u32) -> RasterMode {
        if code == RASTER_NEAREST {
            RasterMode::NearestSample
        } else {
            RasterMode::BoundingBox
        }
    }

    /// The command line's and the statistics' name: `bbox` or `nearest`.
    pub fn name(self) -> &'static str {
        match self {
            RasterMode::BoundingBox => "bbox",
            RasterMode::NearestSample => "nearest",
        }
    }
}

/// [`FrameUniforms::raster`] of [`RasterMode::BoundingBox`].
pub const RASTER_BBOX: u32 = 0;
/// [`FrameUniforms::raster`] of [`RasterMode::NearestSample`].
pub const RASTER_NEAREST: u32 = 1;

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: None,
            height: None,
            pixel_samples: None,
            mp_size: 1.0,
            bound_px: None,
            grid_max: 15,
            max_depth: 24,
            max_eye_splits: 24,
            seed: 0x5eed,
            memory_budget: None,
            crack_dilation: true,
            displacement_normals: DisplacementNormals::Exact,
            raster: RasterMode::BoundingBox,
            sampling: Sampling::BoundingBox,
            il_tile: 2,
            il_perms: 64,
            occlusion: Occlusion::Auto,
        }
    }
}

/// When a frame is rendered in occlusion-culling passes (`RenderOptions::occlusion`,
/// `--occlusion`). Each pass after the first is one more scheduler run and one depth-pyramid
/// build per bucket: about 0.5 ms on Killeroo at 1920x1080 on an H200, where culling saves 20%
/// of the micropolygons (docs/results.md, 2026-12-02), so the passes pay only where patches
/// lie deep over each other.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Occlusion {
    /// One pass, nothing culled.
    Off,
    /// Passes only where a bucket's root patches cover the screen cells they reach
    /// [`crate::stages::hiz::AUTO_MIN_DEPTH_COMPLEXITY`] times over or more
    /// ([`crate::stages::hiz::depth_complexity`]).
    #[default]
    Auto,
    /// Passes in every bucket.
    On,
}
