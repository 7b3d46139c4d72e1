//! What the GPU stages read about a frame: the host twins of the WGSL structs in
//! `shaders/reyes/common.wgsl` (`#[repr(C)]` bytemuck types, layouts checked against naga's
//! reflection in the tests), and their construction from a [`Scene`] and [`RenderOptions`].

use crate::Error;
use crate::scene::{Light, Patch, Scene, SurfaceKind};
use bytemuck::{Pod, Zeroable};

mod options;
mod patch_info;
pub use options::*;
pub use patch_info::*;

/// A queue item of every Reyes stage: a (sub)patch. 224 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PatchItem {
    /// 16 control points, `x, y, z` each, camera space, point `4*v + u` at `cp[3*(4*v + u)..]`:
    /// the points themselves for a polynomial patch; for a rational one ([`PATCH_RATIONAL`] in
    /// its [`PatchInfo::flags`]) the homogeneous `x w, y w, z w`, whose weights are not in the
    /// item but blossomed from its patch's weight table at [`PatchItem::uv`]
    /// (`crate::stages::rational_weights`; docs/reyes.md, "Rational patches").
    pub cp: [f32; 48],
    /// Parameter range in the original patch: u0, u1, v0, v1.
    pub uv: [f32; 4],
    /// Index of the original patch: into [`FrameData::patch_info`] and the scene's patches.
    pub patch_id: u32,
    /// Bits 0..7: splits so far; bits 8..15: splits made because of the near plane.
    pub depth: u32,
    /// Dice rates set by Bound: u in bits 0..7, v in bits 8..15.
    pub rates: u32,
    /// Crack dilation of each boundary edge (v = 0, v = 1, u = 0, u = 1), set by Bound: 8 bits
    /// each from bit 0, in steps of `MAX_DILATE_PX / 255` pixels (`stages::bound::crack_dilation`).
    pub dilate: u32,
}

impl PatchItem {
    /// Splits from the original patch so far (bits 0..7 of `depth`).
    pub fn splits(&self) -> u32 {
        self.depth & 255
    }
    /// Of those, the splits made because the item crossed the near plane (bits 8..15 of `depth`).
    pub fn eye_splits(&self) -> u32 {
        (self.depth >> 8) & 255
    }
}

/// The frame's uniform block, `Frame` in common.wgsl (the layout test below checks it against
/// naga's reflection): image size, sub-samples, camera, dicing limits, the tile a bucket renders,
/// and the sampling modes. One per frame or bucket, bound read-only by every stage.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FrameUniforms {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Sub-samples per pixel along x (`PixelSamples`).
    pub spp_x: u32,
    /// Sub-samples per pixel along y.
    pub spp_y: u32,
    /// Focal length in pixels: half the shorter image side over tan(fov / 2), so that
    /// [`crate::stages::project`] maps camera space to pixels.
    pub focal: f32,
    /// Near clipping distance along camera-space z (`Clipping`).
    pub near: f32,
    /// Far clipping distance along camera-space z (`Clipping`; capped at `f32::MAX`).
    pub far: f32,
    /// Target micropolygon edge in pixels (adaptive dicing; [`RenderOptions::mp_size`]).
    pub mp_size: f32,
    /// Fixed-bound dicing's screen bound in pixels ([`RenderOptions::bound_px`]); 0 for adaptive
    /// dicing.
    pub bound_px: f32,
    /// Most segments per grid side, 1..=15 (15 under fixed-bound dicing).
    pub grid_max: u32,
    /// Most splits of one item (at most 255, the width of its split count); an item there is diced
    /// however large it is (`C_DEPTH_LIMIT`).
    pub max_depth: u32,
    /// Most near-plane splits of one item (at most 255); see [`RenderOptions::max_eye_splits`].
    pub max_eye_splits: u32,
    /// Entries of the light table ([`FrameData::lights`]).
    pub n_lights: u32,
    /// Seed of the per-sample hashes: sub-sample jitter and stochastic transparency.
    pub seed: u32,
    /// The screen bucket a run renders (the whole image without a memory budget); the sample
    /// buffer holds only its pixels. This is its left column, pixels.
    pub tile_x0: u32,
    /// Top row of the bucket, pixels.
    pub tile_y0: u32,
    /// Bucket width in pixels.
    pub tile_w: u32,
    /// Bucket height in pixels.
    pub tile_h: u32,
    /// 1: micropolygons grow by their crack bound; 0 only to show what that buys.
    pub crack_dilation: u32,
    /// The direction displaced patches move along ([`DisplacementNormals`] as its `u32`).
    pub displacement_normals: u32,
    /// How micropolygons are rasterized: [`RasterMode::gpu_code`] (`RASTER_*` in common.wgsl).
    pub raster: u32,
    /// Time and lens sampling (motion blur, depth of field): [`UVT_OFF`] when the frame has
    /// neither, else the algorithm ([`Sampling::gpu_code`], `UVT_*` in common.wgsl).
    pub uvt: u32,
    /// Interleave UVT: the tile side K in pixels (2..=4).
    pub il_tile: u32,
    /// Interleave UVT: the number P of sample permutations the tiles choose from.
    pub il_perms: u32,
    /// Depth of field: the signed circle of confusion of camera-space depth z is
    /// `coc_scale * (inv_focus - 1 / z)` pixels (focal length in pixels times the lens radius;
    /// 0 without depth of field).
    pub coc_scale: f32,
    /// 1 / the focal distance (camera space).
    pub inv_focus: f32,
    /// Occlusion culling in Bound: `OCCLUSION_OFF`, `OCCLUSION_ON` (allowed; no depth
    /// pyramid yet) or `OCCLUSION_TEST` (test against the bucket's pyramid), the constants of
    /// [`crate::stages::hiz`].
    pub occlusion: u32,
}

/// [`FrameUniforms::uvt`]: no time or lens sampling; the sampler of a still pinhole frame runs.
pub const UVT_OFF: u32 = 0;
/// [`FrameUniforms::uvt`] of [`Sampling::Simple`].
pub const UVT_SIMPLE: u32 = 1;
/// [`FrameUniforms::uvt`] of [`Sampling::Interleave`].
pub const UVT_INTERLEAVE: u32 = 2;
/// [`FrameUniforms::uvt`] of [`Sampling::BoundingBox`].
pub const UVT_BBOX: u32 = 3;

/// How a frame with motion blur or depth of field samples time and the lens (Sattler &
/// Steinberger, "Reyes Rendering on the GPU", section 3.3; docs/reyes.md, "Motion blur and
/// depth of field"). Each pixel keeps its `PixelSamples` sub-samples; each sub-sample gets one
/// (lens u, lens v, time) triple, which the algorithms assign differently.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Sampling {
    /// Simple UVT: the same S triples in every pixel (S = samples per pixel); each
    /// micropolygon is moved to each triple and rasterized into that triple's sub-sample.
    /// Ghost images when S is small.
    Simple,
    /// Interleave UVT: K x K pixel tiles share K^2 S triples, each sub-sample of the tile one of
    /// them, assigned by one of P permutations chosen per tile (the paper's eq. 2-3). Noise
    /// instead of ghosts.
    Interleave,
    /// Bounding box (the default): each pixel's S triples come from a 64 x 64 pixel table
    /// repeated over the image, one per time stratum in an order shifted per pixel; for each
    /// stratum, the micropolygon's bound over that stratum's times (grown by its circle of
    /// confusion) tests the sub-sample of each pixel under it whose time lies there, at its own
    /// time and lens position. Noise instead of ghosts (stochastic sampling: Cook, Porter and
    /// Carpenter 1984), at a cost that grows with the blur's length rather than its area.
    #[default]
    BoundingBox,
}

impl Sampling {
    /// The value of [`FrameUniforms::uvt`] for a frame that has motion or depth of field.
    pub fn gpu_code(self) -> u32 {
        match self {
            Sampling::Simple => UVT_SIMPLE,
            Sampling::Interleave => UVT_INTERLEAVE,
            Sampling::BoundingBox => UVT_BBOX,
        }
    }

    /// The command line's and the statistics' name.
    pub fn name(self) -> &'static str {
        match self {
            Sampling::Simple => "simple",
            Sampling::Interleave => "interleave",
            Sampling::BoundingBox => "bbox",
        }
    }
}

impl FrameUniforms {
    /// This frame restricted to one bucket.
    pub fn with_tile(&self, t: Tile) -> FrameUniforms {
        FrameUniforms {
            tile_x0: t.x0,
            tile_y0: t.y0,
            tile_w: t.w,
            tile_h: t.h,
            ..*self
        }
    }

    /// The tile covering the whole image (the frame without buckets).
    pub fn whole_image(&self) -> Tile {
        Tile {
            x0: 0,
            y0: 0,
            w: self.width,
            h: self.height,
        }
    }
}

/// A screen-space bucket: pixels `x0..x0 + w`, `y0..y0 + h`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// Left column, pixels.
    pub x0: u32,
    /// Top row, pixels.
    pub y0: u32,
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
}

/// A material as the GPU stages read it (`Material` in common.wgsl): the f32 form of a
/// [`crate::scene::Material`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// `Color` (Cs), linear RGB.
    pub color: [f32; 3],
    /// 0 constant, 1 matte, 2 plastic
    pub kind: u32,
    /// `specularcolor`, linear RGB (plastic's highlight).
    pub specular: [f32; 3],
    /// `Ka`: weight of the ambient light.
    pub ka: f32,
    /// `Kd`: weight of the diffuse term.
    pub kd: f32,
    /// `Ks`: weight of the specular term.
    pub ks: f32,
    /// `roughness`: the highlight's exponent is `1 / roughness`.
    pub roughness: f32,
    /// `Opacity` (Os) as one fraction: the mean of its channels (docs/reyes.md, Opacity).
    pub opacity: f32,
}

/// A light as the GPU stages read it (`Light` in common.wgsl), camera space: the f32 form of a
/// [`crate::scene::Light`]. 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// Intensity times light colour, linear RGB; a point light's falls off as 1 / distance².
    pub color: [f32; 3],
    /// 0 ambient, 1 distant (`vec` = direction of travel), 2 point (`vec` = position)
    pub kind: u32,
    /// Direction of travel (distant) or position (point), camera space; unused for ambient.
    pub vec: [f32; 3],
    /// Padding to the WGSL struct's 32 bytes.
    pub pad: f32,
}

/// Everything uploaded for one frame.
#[derive(Clone, Debug)]
pub struct FrameData {
    /// The uniform block (`Frame` in common.wgsl).
    pub frame: FrameUniforms,
    /// The material table, indexed by [`PatchInfo::material`].
    pub materials: Vec<GpuMaterial>,
    /// The light table, [`FrameUniforms::n_lights`] entries.
    pub lights: Vec<GpuLight>,
    /// Per original patch, indexed by [`PatchItem::patch_id`].
    pub patch_info: Vec<PatchInfo>,
    /// The colour fields of the patches that have primitive variables, referenced by
    /// `PatchInfo::cs` / `os` ([`field_ref`]), and the weights of the rational patches
    /// (`PatchInfo::weights`); empty when no patch has either.
    pub primvars: Vec<[f32; 4]>,
    /// The root items: one per scene patch, in scene order, the input of Bound.
    pub items: Vec<PatchItem>,
    /// See [`RenderOptions::memory_budget`].
    pub memory_budget: Option<u64>,
    /// `Imager "background"` ([`Scene::background`]) in linear f32: the resolve composites
    /// every pixel over it and makes it opaque; `None` leaves uncovered pixels transparent.
    pub background: Option<[f32; 3]>,
}

impl FrameData {
    /// Bytes of the scene's tables on the device that grow with its patches: the root
    /// items (224 bytes each), the patch infos (32 each) and the primitive-variable table
    /// (16 per entry: fields, weights, displacements, trims, motion). N instances of an
    /// object add N items and infos (and motion entries) but share the rest
    /// (docs/reyes.md, *Instances*).
    pub fn table_bytes(&self) -> u64 {
        (std::mem::size_of_val(self.items.as_slice())
            + std::mem::size_of_val(self.patch_info.as_slice())
            + std::mem::size_of_val(self.primvars.as_slice())) as u64
    }

    /// What this frame needs compiled into the GPU program ([`SceneFeatures`]).
    pub fn features(&self) -> SceneFeatures {
        let os = self.patch_info.iter().any(|i| i.os != 0);
        SceneFeatures {
            rational: (self.patch_info.iter()).any(|i| i.flags & PATCH_RATIONAL != 0),
            primvars: os || self.patch_info.iter().any(|i| i.cs != 0 || i.normal != 0),
            transparent: os || self.materials.iter().any(|m| m.opacity < 1.0),
            displacement: (self.patch_info.iter()).any(|i| i.flags & PATCH_DISPLACED != 0),
            trim: (self.patch_info.iter()).any(|i| i.flags & PATCH_TRIMMED != 0),
            nearest_raster: self.frame.raster == RASTER_NEAREST,
            uvt: self.frame.uvt != UVT_OFF,
        }
    }
}

/// What a frame's scene needs of the stages beyond plain polynomial, opaque patches with their
/// material's colour. The GPU program is compiled with each as a WGSL constant
/// (`SCENE_RATIONAL`, `SCENE_PRIMVARS`, `SCENE_TRANSPARENT` in common.wgsl), so that a scene
/// without them pays nothing for their code paths: not even the registers a GPU compiler keeps
/// for a branch it cannot rule out (measured on the H200: ~5% of a Killeroo frame).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SceneFeatures {
    /// Some patch is rational (`PATCH_RATIONAL`).
    pub rational: bool,
    /// Some patch has "Cs" or "Os" primitive variables.
    pub primvars: bool,
    /// Some surface is not opaque (a material's `Opacity` or an "Os" below 1).
    pub transparent: bool,
    /// Some patch is displaced (`PATCH_DISPLACED`).
    pub displacement: bool,
    /// Some patch is trimmed (`PATCH_TRIMMED`, `SCENE_TRIM`): without it Bound and DiceShade
    /// hold no trimming code.
    pub trim: bool,
    /// The frame is rasterized with [`RasterMode::NearestSample`] (`SCENE_NEAREST_RASTER`):
    /// without it the program holds bounding-box rasterization alone, and the default mode
    /// pays nothing for the other.
    pub nearest_raster: bool,
    /// The frame samples time or the lens (`SCENE_UVT`: motion blur or depth of field):
    /// without it none of that code is compiled, and a still pinhole frame runs the plain
    /// sampler alone.
    pub uvt: bool,
}

impl SceneFeatures {
    /// Every feature: a program that renders any frame.
    pub const ALL: SceneFeatures = SceneFeatures {
        rational: true,
        primvars: true,
        transparent: true,
        displacement: true,
        trim: true,
        nearest_raster: true,
        uvt: true,
    };

    /// True when a program compiled for `self` renders every frame that needs `need`.
    pub fn covers(self, need: SceneFeatures) -> bool {
        (self.rational || !need.rational)
            && (self.primvars || !need.primvars)
            && (self.transparent || !need.transparent)
            && (self.displacement || !need.displacement)
            && (self.trim || !need.trim)
            && (self.nearest_raster || !need.nearest_raster)
            && (self.uvt || !need.uvt)
    }

    /// The features either needs.
    pub fn union(self, o: SceneFeatures) -> SceneFeatures {
        SceneFeatures {
            rational: self.rational || o.rational,
            primvars: self.primvars || o.primvars,
            transparent: self.transparent || o.transparent,
            displacement: self.displacement || o.displacement,
            trim: self.trim || o.trim,
            nearest_raster: self.nearest_raster || o.nearest_raster,
            uvt: self.uvt || o.uvt,
        }
    }

    /// The WGSL constants that select the stages' code paths (prepended to common.wgsl).
    pub fn wgsl(self) -> String {
        format!(
            "const SCENE_RATIONAL: bool = {};\nconst SCENE_PRIMVARS: bool = {};\n\
             const SCENE_TRANSPARENT: bool = {};\nconst SCENE_DISPLACEMENT: bool = {};\nconst SCENE_NEAREST_RASTER: bool = {};\n\
             const SCENE_UVT: bool = {};\nconst SCENE_TRIM: bool = {};\n",
            self.rational,
            self.primvars,
            self.transparent,
            self.displacement,
            self.nearest_raster,
            self.uvt,
            self.trim
        )
    }
}

// The limits a scene's `Format` and `PixelSamples` are read within; the frame holds the
// options to them too.
pub use crate::scene::{MAX_IMAGE_SIDE, MAX_PIXEL_SAMPLES};

/// Smallest micropolygon edge accepted, in pixels: 256 micropolygons per pixel. Below it the
/// work per patch grows without bound (each halving of the size quadruples the grids) while
/// the image no longer changes; both paths would split every patch to `max_depth`.
pub const MIN_MP_SIZE: f32 = 1.0 / 16.0;

/// Most bytes of one frame buffer (the whole image's RGBA, and the sample buffer when the
/// frame is not cut into buckets): 4 GiB - 1, the most a wgpu storage binding can hold on any
/// backend (Vulkan's `maxStorageBufferRange` is 32-bit). The CPU twin is held to the same
/// bound, so a frame the GPU must refuse is refused up front on both paths instead of
/// allocating tens of GiB on the host.
pub const MAX_FRAME_BUFFER_BYTES: u64 = u32::MAX as u64;

/// Bytes of the RGBA image (f32 x 4 per pixel) of a `width` x `height` frame.
pub fn image_bytes(width: u32, height: u32) -> u64 {
    width as u64 * height as u64 * 16
}

/// Checks the options both render paths share that do not depend on the scene: the
/// micropolygon size and the screen bound. Errors ([`Error::InvalidOptions`]) say which option
/// and why.
pub fn check_quality(o: &RenderOptions) -> Result<(), Error> {
    let invalid = |message: String| Err(Error::InvalidOptions(message));
    if !(1..=15).contains(&o.grid_max) {
        return invalid(format!("grid_max {} must be 1..=15", o.grid_max));
    }
    if !(o.mp_size.is_finite() && o.mp_size >= MIN_MP_SIZE) {
        return invalid(format!(
            "micropolygon size {:?} px is not supported: it must be at least {MIN_MP_SIZE} px \
             (256 micropolygons per pixel) and finite",
            o.mp_size
        ));
    }
    let min_bound = 15.0 * MIN_MP_SIZE;
    if let Some(b) = o.bound_px
        && !(b.is_finite() && b >= min_bound)
    {
        return invalid(format!(
            "screen bound {b:?} px is not supported: it must be at least {min_bound} px (grids \
             of 15x15 micropolygons of at least {MIN_MP_SIZE} px) and finite"
        ));
    }
    if !(2..=4).contains(&o.il_tile) {
        return invalid(format!("interleave tile {} must be 2, 3 or 4", o.il_tile));
    }
    if !(1..=1024).contains(&o.il_perms) {
        return invalid(format!(
            "interleave permutations {} must be 1..=1024",
            o.il_perms
        ));
    }
    Ok(())
}

impl FrameData {
    /// The frame of `scene` under the options `o`: the uniforms, materials, lights and the
    /// per-patch tables. Errors: options out of range ([`Error::InvalidOptions`]), a frame
    /// whose buffers exceed a device binding ([`Error::FrameTooLarge`]), per-patch tables over
    /// a binding ([`Error::TablesTooLarge`]).
    pub fn new(scene: &Scene, o: &RenderOptions) -> Result<FrameData, Error> {
        let width = o.width.unwrap_or(scene.width);
        let height = o.height.unwrap_or(scene.height);
        if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(Error::InvalidOptions(format!(
                "image size {width}x{height} is not supported: each side must be 1..={MAX_IMAGE_SIDE}"
            )));
        }
        let (sx, sy) = o.pixel_samples.unwrap_or(scene.pixel_samples);
        let spp = 1..=MAX_PIXEL_SAMPLES;
        if !spp.contains(&sx) || !spp.contains(&sy) {
            return Err(Error::InvalidOptions(format!(
                "pixel samples {sx}x{sy}: each must be 1..={MAX_PIXEL_SAMPLES}"
            )));
        }
        // Sample indices are 32-bit in the shaders and in the CPU pipeline.
        let subsamples = width as u64 * height as u64 * (sx * sy) as u64;
        if subsamples > u32::MAX as u64 {
            return Err(Error::FrameTooLarge(format!(
                "image size {width}x{height} with {sx}x{sy} pixel samples needs {subsamples} \
                 sub-samples, more than a 32-bit sample index reaches ({})",
                u32::MAX
            )));
        }
        let limit = MAX_FRAME_BUFFER_BYTES;
        let image = image_bytes(width, height);
        if image > limit {
            return Err(Error::FrameTooLarge(format!(
                "image size {width}x{height} needs {image} bytes of RGBA, more than the {limit} \
                 bytes (4 GiB) a frame buffer may hold"
            )));
        }
        let samples = subsamples * 8;
        if samples > limit && o.memory_budget.is_none() {
            return Err(Error::FrameTooLarge(format!(
                "image size {width}x{height} with {sx}x{sy} pixel samples needs {samples} bytes \
                 of samples, more than the {limit} bytes (4 GiB) a frame buffer may hold: give \
                 --memory-budget to render it in buckets"
            )));
        }
        check_quality(o)?;
        let fov = scene.camera.fov_deg.to_radians();
        let focal = width.min(height) as f64 / 2.0 / (fov / 2.0).tan();
        let lights = gpu_lights(scene);
        let mut primvars = Vec::new();
        let mut shared = SharedEntries::default();
        let patch_info: Vec<PatchInfo> = (scene.patches.iter())
            .map(|p| patch_info(p, &mut primvars, &mut shared))
            .collect::<Result<_, Error>>()?;
        let frame = FrameUniforms {
            width,
            height,
            spp_x: sx,
            spp_y: sy,
            focal: focal as f32,
            near: scene.camera.near as f32,
            far: scene.camera.far.min(f32::MAX as f64) as f32,
            mp_size: o.mp_size,
            bound_px: o.bound_px.unwrap_or(0.0),
            grid_max: if o.bound_px.is_some() { 15 } else { o.grid_max },
            max_depth: o.max_depth.min(255),
            max_eye_splits: o.max_eye_splits.min(255),
            n_lights: lights.len() as u32,
            seed: o.seed,
            tile_x0: 0,
            tile_y0: 0,
            tile_w: width,
            tile_h: height,
            crack_dilation: o.crack_dilation as u32,
            displacement_normals: o.displacement_normals as u32,
            raster: o.raster.gpu_code(),
            uvt: UVT_OFF,
            il_tile: o.il_tile,
            il_perms: o.il_perms,
            coc_scale: 0.0,
            inv_focus: 0.0,
            occlusion: match o.occlusion {
                Occlusion::Off => crate::stages::hiz::OCCLUSION_OFF,
                Occlusion::Auto => crate::stages::hiz::OCCLUSION_AUTO,
                Occlusion::On => crate::stages::hiz::OCCLUSION_ON,
            },
        };
        let mut frame = frame;
        let moving = patch_info
            .iter()
            .any(|i: &PatchInfo| i.flags & PATCH_MOVING != 0);
        if let Some(d) = &scene.camera.depth_of_field {
            frame.coc_scale = (focal * d.lens_radius()) as f32;
            frame.inv_focus = (1.0 / d.focal_distance) as f32;
        }
        if moving || frame.coc_scale > 0.0 {
            if o.raster == RasterMode::NearestSample {
                return Err(Error::InvalidOptions(
                    "motion blur and depth of field need bounding-box rasterization (--raster bbox)"
                        .to_string(),
                ));
            }
            frame.uvt = o.sampling.gpu_code();
        }
        Ok(FrameData {
            frame,
            materials: scene.materials.iter().map(gpu_material).collect(),
            lights,
            patch_info,
            primvars,
            items: scene
                .patches
                .iter()
                .enumerate()
                .map(|(i, p)| root_item(i as u32, p))
                .collect(),
            memory_budget: o.memory_budget,
            background: scene.background.map(f3),
        })
    }
}

fn f3(v: glam::DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

fn gpu_material(m: &crate::scene::Material) -> GpuMaterial {
    GpuMaterial {
        color: f3(m.color),
        kind: match m.kind {
            SurfaceKind::Constant => 0,
            SurfaceKind::Matte => 1,
            SurfaceKind::Plastic => 2,
            SurfaceKind::Metal => 3,
        },
        specular: f3(m.specular_color),
        ka: m.ka as f32,
        kd: m.kd as f32,
        ks: m.ks as f32,
        roughness: m.roughness as f32,
        opacity: ((m.opacity.x + m.opacity.y + m.opacity.z) / 3.0) as f32,
    }
}

/// The scene's lights; a scene without any gets one distant light from the eye.
fn gpu_lights(scene: &Scene) -> Vec<GpuLight> {
    let light = |kind, color, vec| GpuLight {
        color: f3(color),
        kind,
        vec: f3(vec),
        pad: 0.0,
    };
    if scene.lights.is_empty() {
        return vec![light(1, glam::DVec3::ONE, glam::DVec3::Z)];
    }
    scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Ambient { color } => light(0, *color, glam::DVec3::ZERO),
            Light::Distant { color, dir } => light(1, *color, *dir),
            Light::Point { color, pos } => light(2, *color, *pos),
        })
        .collect()
}

/// `p`'s [`PatchInfo`], appending to `table` what `shared` does not hold yet: one copy per
/// allocation of fields, weights, displacement and trim, so that N instances of an object
/// cost their N infos (and motion entries) and one copy of the rest.
fn patch_info(
    p: &Patch,
    table: &mut Vec<[f32; 4]>,
    shared: &mut SharedEntries,
) -> Result<PatchInfo, Error> {
    let (cs, os, normal) = match &p.primvars {
        None => (0, 0, 0),
        Some(v) => once(&mut shared.primvars, v, || {
            let mut field =
                |f: Option<&crate::scene::ColorField>| f.map_or(Ok(0), |f| field_ref(table, f));
            Ok((
                field(v.cs.as_ref())?,
                field(v.os.as_ref())?,
                field(v.n.as_ref())?,
            ))
        })?,
    };
    let weights = match p.net.shared_weights().filter(|_| p.is_rational()) {
        None => 0,
        Some(w) => once(&mut shared.weights, w, || {
            weights_ref(table, &homogeneous_points(p))
        })?,
    };
    let displacement = match &p.displacement {
        None => 0,
        Some(d) => once(&mut shared.displacements, d, || {
            displacement_ref(table, &mut shared.maps, d)
        })?,
    };
    let motion = match &p.motion {
        Some(m) => motion_ref(table, m)?,
        None => 0,
    };
    let trim = match &p.trim {
        None => 0,
        Some(t) => once(&mut shared.trims, t, || {
            trim_ref(table, &mut shared.loops, t)
        })?,
    };
    Ok(PatchInfo {
        material: p.material,
        flags: p.flip_normal as u32
            | (p.two_sided as u32) << 1
            | if p.is_rational() { PATCH_RATIONAL } else { 0 }
            | if p.displacement.is_some() {
                PATCH_DISPLACED
            } else {
                0
            }
            | if p.motion.is_some() { PATCH_MOVING } else { 0 }
            | trim,
        cs,
        os,
        weights,
        displacement,
        motion,
        normal,
    })
}

/// Appends the 16 weights of homogeneous points `h` to the table as 4 entries (row v = l in
/// entry l) and returns the first entry's index ([`PatchInfo::weights`]). Errors
/// ([`Error::TablesTooLarge`]) when the table would outgrow what a GPU binding holds.
fn weights_ref(table: &mut Vec<[f32; 4]>, h: &[[f32; 4]; 16]) -> Result<u32, Error> {
    let at = table.len() as u64;
    if (at + 4) * 16 > MAX_FRAME_BUFFER_BYTES {
        return Err(Error::TablesTooLarge {
            what: "weights and primitive variables",
            limit: MAX_FRAME_BUFFER_BYTES,
        });
    }
    table.extend((0..4).map(|l| std::array::from_fn(|u| h[4 * l + u][3])));
    Ok(at as u32)
}

/// The homogeneous control points `(x w, y w, z w, w)` of `p`, `[4*v + u]`, formed in f64 and
/// rounded once to f32, with the weights scaled so that the largest is 1 (a common factor does
/// not change a rational surface; this keeps `x w` within f32 wherever `x` is). For a
/// polynomial patch (all w = 1) these are exactly the f32 coordinates and 1. The object table
/// of the real-time renderer (roots.wgsl) holds these.
pub fn homogeneous_points(p: &Patch) -> [[f32; 4]; 16] {
    let (cp, w) = (p.cp(), p.w());
    let top = w.iter().copied().fold(0.0, f64::max);
    std::array::from_fn(|i| {
        let w = w[i] / top;
        let c = cp[i] * w;
        [c.x as f32, c.y as f32, c.z as f32, w as f32]
    })
}

/// The root item of `p`: the xyz of its [`homogeneous_points`] (for a polynomial patch the f32
/// points), whose weights [`FrameData::new`] puts in the weight table of a rational patch.
pub fn root_item(id: u32, p: &Patch) -> PatchItem {
    let h = homogeneous_points(p);
    PatchItem {
        cp: std::array::from_fn(|k| h[k / 3][k % 3]),
        uv: [0.0, 1.0, 0.0, 1.0],
        patch_id: id,
        depth: 0,
        rates: 0,
        dilate: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scheduler::wgsl::struct_layout;

    /// Each host struct has the size and field offsets naga computes for its WGSL twin.
    #[test]
    fn host_structs_match_wgsl_layouts() {
        let src = &[crate::shaders::PATCH_ITEM, crate::shaders::COMMON].concat();
        let check = |name: &str, size: usize, offsets: &[(&str, usize)]| {
            let l = struct_layout(src, name).unwrap();
            assert_eq!(l.size as usize, size, "{name} size");
            for (field, off) in offsets {
                let got = l
                    .members
                    .iter()
                    .find(|(n, _)| n == field)
                    .map(|m| m.1 as usize);
                assert_eq!(got, Some(*off), "{name}.{field}");
            }
        };
        use std::mem::{offset_of, size_of};
        assert_eq!(
            size_of::<PatchItem>(),
            224,
            "48 floats of control points, uv, 4 words"
        );
        check(
            "PatchItem",
            size_of::<PatchItem>(),
            &[
                ("cp", offset_of!(PatchItem, cp)),
                ("uv", offset_of!(PatchItem, uv)),
                ("patch_id", offset_of!(PatchItem, patch_id)),
                ("depth", offset_of!(PatchItem, depth)),
                ("rates", offset_of!(PatchItem, rates)),
                ("dilate", offset_of!(PatchItem, dilate)),
            ],
        );
        check(
            "Frame",
            size_of::<FrameUniforms>(),
            &[
                ("focal", offset_of!(FrameUniforms, focal)),
                ("bound_px", offset_of!(FrameUniforms, bound_px)),
                ("n_lights", offset_of!(FrameUniforms, n_lights)),
                ("seed", offset_of!(FrameUniforms, seed)),
                ("tile_x0", offset_of!(FrameUniforms, tile_x0)),
                ("tile_h", offset_of!(FrameUniforms, tile_h)),
                ("crack_dilation", offset_of!(FrameUniforms, crack_dilation)),
                (
                    "displacement_normals",
                    offset_of!(FrameUniforms, displacement_normals),
                ),
                ("raster", offset_of!(FrameUniforms, raster)),
                ("uvt", offset_of!(FrameUniforms, uvt)),
                ("il_tile", offset_of!(FrameUniforms, il_tile)),
                ("il_perms", offset_of!(FrameUniforms, il_perms)),
                ("coc_scale", offset_of!(FrameUniforms, coc_scale)),
                ("inv_focus", offset_of!(FrameUniforms, inv_focus)),
                ("occlusion", offset_of!(FrameUniforms, occlusion)),
            ],
        );
        check(
            "Material",
            size_of::<GpuMaterial>(),
            &[
                ("kind", offset_of!(GpuMaterial, kind)),
                ("specular", offset_of!(GpuMaterial, specular)),
                ("ka", offset_of!(GpuMaterial, ka)),
                ("roughness", offset_of!(GpuMaterial, roughness)),
                ("opacity", offset_of!(GpuMaterial, opacity)),
            ],
        );
        check(
            "Light",
            size_of::<GpuLight>(),
            &[
                ("kind", offset_of!(GpuLight, kind)),
                ("vec", offset_of!(GpuLight, vec)),
            ],
        );
        check(
            "PatchInfo",
            size_of::<PatchInfo>(),
            &[
                ("flags", offset_of!(PatchInfo, flags)),
                ("cs", offset_of!(PatchInfo, cs)),
                ("os", offset_of!(PatchInfo, os)),
                ("weights", offset_of!(PatchInfo, weights)),
                ("displacement", offset_of!(PatchInfo, displacement)),
                ("motion", offset_of!(PatchInfo, motion)),
                ("normal", offset_of!(PatchInfo, normal)),
            ],
        );
    }

    /// Only patches with primitive variables use table space; each field is referenced by its
    /// entry index and shape, in f32.
    #[test]
    fn primvars_fill_the_table_only_for_patches_that_have_them() {
        use crate::scene::{ColorField, Primvars};
        use glam::DVec3;
        let mut scene = crate::scene::builtin_teapot();
        let plain = FrameData::new(&scene, &RenderOptions::default()).unwrap();
        assert!(plain.primvars.is_empty());
        assert!(plain.patch_info.iter().all(|i| i.cs == 0 && i.os == 0));
        let corners = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE];
        scene.patches[3].primvars = Primvars {
            cs: Some(ColorField::Bilinear(corners)),
            os: Some(ColorField::Flat(DVec3::splat(0.5))),
            n: None,
        }
        .shared();
        scene.patches[7].primvars = Primvars {
            cs: None,
            os: Some(ColorField::Bezier([DVec3::splat(0.25); 16])),
            n: None,
        }
        .shared();
        let d = FrameData::new(&scene, &RenderOptions::default()).unwrap();
        assert_eq!(d.primvars.len(), 4 + 1 + 16);
        assert_eq!(
            (d.patch_info[3].cs, d.patch_info[3].os),
            (FIELD_BILINEAR, 4 << 2 | FIELD_FLAT)
        );
        assert_eq!(
            (d.patch_info[7].cs, d.patch_info[7].os),
            (0, 5 << 2 | FIELD_BEZIER)
        );
        assert_eq!(d.patch_info[0], plain.patch_info[0]);
        assert_eq!(d.primvars[2], [0.0, 0.0, 1.0, 0.0]);
        assert_eq!(d.primvars[4], [0.5, 0.5, 0.5, 0.0]);
        assert_eq!(d.primvars[20], [0.25, 0.25, 0.25, 0.0]);
    }

    /// A rational patch's item keeps the xyz of its homogeneous points and its weights go to
    /// the table, 4 entries at `PatchInfo::weights`, as `homogeneous_points` scales them; a
    /// polynomial patch's item holds its f32 points and it uses no table space.
    #[test]
    fn rational_weights_go_to_the_table() {
        let mut scene = crate::scene::builtin_teapot();
        scene.patches[5].w_mut()[6] = 4.0;
        scene.patches[5].w_mut()[9] = 0.5;
        let d = FrameData::new(&scene, &RenderOptions::default()).unwrap();
        assert_eq!(d.primvars.len(), 4);
        for (i, (p, info)) in scene.patches.iter().zip(&d.patch_info).enumerate() {
            let h = homogeneous_points(p);
            let xyz: Vec<f32> = h.iter().flat_map(|q| [q[0], q[1], q[2]]).collect();
            assert_eq!(d.items[i].cp.to_vec(), xyz);
            if i == 5 {
                assert_eq!(info.flags & PATCH_RATIONAL, PATCH_RATIONAL);
                assert_eq!(info.weights, 0);
                for (k, q) in h.iter().enumerate() {
                    assert_eq!(d.primvars[k / 4][k % 4], q[3]);
                }
                assert_eq!(h[6][3], 1.0, "scaled to a largest of 1");
                assert_eq!(h[9][3], 0.125);
            } else {
                assert_eq!((info.flags & PATCH_RATIONAL, info.weights), (0, 0));
                let pts = p
                    .cp()
                    .into_iter()
                    .flat_map(|c| [c.x as f32, c.y as f32, c.z as f32]);
                assert_eq!(d.items[i].cp.to_vec(), pts.collect::<Vec<_>>());
            }
        }
    }

    #[test]
    fn bad_image_sizes_are_errors() {
        let scene = crate::scene::builtin_teapot();
        for (w, h) in [(0, 10), (10, 0), (MAX_IMAGE_SIDE + 1, 10)] {
            let o = RenderOptions {
                width: Some(w),
                height: Some(h),
                ..Default::default()
            };
            assert!(
                FrameData::new(&scene, &o)
                    .unwrap_err()
                    .to_string()
                    .contains("image size")
            );
        }
    }

    /// The checks both render paths share: sizes that need a frame buffer no GPU binds,
    /// micropolygons and screen bounds too small to bound the work.
    #[test]
    fn frame_buffers_and_quality_are_bounded() {
        let scene = crate::scene::builtin_teapot();
        let with = |f: &dyn Fn(&mut RenderOptions)| {
            let mut o = RenderOptions::default();
            f(&mut o);
            FrameData::new(&scene, &o)
                .map(|_| ())
                .map_err(|e| e.to_string())
        };
        let e = with(&|o| (o.width, o.height) = (Some(16384), Some(16384))).unwrap_err();
        assert!(e.contains("needs 4294967296 bytes of RGBA"), "{e}");
        let big = |o: &mut RenderOptions| (o.width, o.height) = (Some(16000), Some(16000));
        let e = with(&big).unwrap_err();
        assert!(
            e.contains("bytes of samples") && e.contains("--memory-budget"),
            "{e}"
        );
        assert!(
            with(&|o| {
                big(o);
                o.memory_budget = Some(1 << 26);
            })
            .is_ok(),
            "in buckets the sample buffer is one bucket's"
        );
        for mp in [1e-30, 0.06, f32::NAN, f32::INFINITY, 0.0, -1.0] {
            let e = with(&|o| o.mp_size = mp).unwrap_err();
            assert!(e.contains("micropolygon size"), "{mp}: {e}");
        }
        assert!(with(&|o| o.mp_size = MIN_MP_SIZE).is_ok());
        let e = with(&|o| o.bound_px = Some(0.5)).unwrap_err();
        assert!(e.contains("screen bound 0.5 px"), "{e}");
        assert!(with(&|o| o.bound_px = Some(8.0)).is_ok());
        let e = with(&|o| o.pixel_samples = Some((17, 1))).unwrap_err();
        assert_eq!(e, "pixel samples 17x1: each must be 1..=16");
    }
}
