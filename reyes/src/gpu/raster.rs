//! What the raster peer's draw pipeline fixes about its targets and vertices: the colour and
//! depth formats and the vertex (`RasterVertex` in tessellate.wgsl), beside the pipelines that
//! use them (`Pipelines::raster`); the peer (`crate::raster_peer`) re-exports them.

use bytemuck::{Pod, Zeroable};

/// The colour target: linear RGB, alpha 1 where drawn, so the resolve's alpha is coverage.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The depth target (reversed depth near / z: a float's precision where it is needed).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A vertex of the peer's triangles (`RasterVertex` in tessellate.wgsl; 16 bytes): the clip
/// position divided by the near distance, `(x, y, 1, w)` with `x = 2 focal px / (width near)`,
/// `y = 2 focal py / (height near)` and `w = pz / near` for the camera-space point `p` (so
/// depth `1 / w = near / pz`), and the packed colour of [`crate::stages::shade::pack_color`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct RasterVertex {
    /// Clip x over the near distance: `2 focal px / (width near)`.
    pub x: f32,
    /// Clip y over the near distance: `2 focal py / (height near)`.
    pub y: f32,
    /// Clip w: `pz / near`.
    pub w: f32,
    /// Shaded colour, packed by [`crate::stages::shade::pack_color`].
    pub color: u32,
}
