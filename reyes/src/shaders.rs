//! The Reyes WGSL sources, one stage per file in `shaders/reyes/` (each with a Rust twin in
//! `stages/`).

pub const PATCH_ITEM: &str = include_str!("../../shaders/reyes/patch_item.wgsl");
pub const COMMON: &str = include_str!("../../shaders/reyes/common.wgsl");
pub const BOUND: &str = include_str!("../../shaders/reyes/bound.wgsl");
pub const SPLIT: &str = include_str!("../../shaders/reyes/split.wgsl");
pub const SHADE: &str = include_str!("../../shaders/reyes/shade.wgsl");
pub const SAMPLE: &str = include_str!("../../shaders/reyes/sample.wgsl");
/// Sampling in time and on the lens (motion blur, depth of field): `sample_uvt.wgsl`.
pub const SAMPLE_UVT: &str = include_str!("../../shaders/reyes/sample_uvt.wgsl");
/// Trimming (`TrimCurve`) in Bound and DiceShade: `trim.wgsl` (twin: `stages::trim`).
pub const TRIM: &str = include_str!("../../shaders/reyes/trim.wgsl");
pub const SURFACE: &str = include_str!("../../shaders/reyes/surface.wgsl");
pub const DICE_SHADE: &str = include_str!("../../shaders/reyes/dice_shade.wgsl");
pub const RESOLVE: &str = include_str!("../../shaders/reyes/resolve.wgsl");
pub const ROOTS: &str = include_str!("../../shaders/reyes/roots.wgsl");
pub const RGBA8: &str = include_str!("../../shaders/reyes/rgba8.wgsl");
/// The viewer's draw of a frame to a window (`reyes view`; twin: [`crate::present`]).
pub const PRESENT: &str = include_str!("../../shaders/reyes/present.wgsl");
pub const TESSELLATE: &str = include_str!("../../shaders/reyes/tessellate.wgsl");
pub const RASTER_DRAW: &str = include_str!("../../shaders/reyes/raster_draw.wgsl");
pub const RASTER_RESOLVE: &str = include_str!("../../shaders/reyes/raster_resolve.wgsl");
/// The depth pyramid of a bucket's samples (occlusion culling; twin: `stages::hiz`).
pub const HIZ: &str = include_str!("../../shaders/reyes/hiz.wgsl");
