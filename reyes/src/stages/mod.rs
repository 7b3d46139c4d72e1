//! The Reyes stages as CPU code: each file is the Rust twin of the WGSL file of the same name in
//! `shaders/reyes/`, in f32 and in the same order of operations, so that the CPU pipeline
//! (`crate::cpu_render`) is a reference the GPU image is checked against.

pub mod bound;
pub mod dice_shade;
pub mod resolve;
pub mod sample;
pub mod shade;
pub mod split;

use glam::Vec3;

/// Counters the stages keep, indexed like `C_*` in `shaders/reyes/common.wgsl`.
pub const C_CULL_CLIP: usize = 0;
pub const C_CULL_OFFSCREEN: usize = 1;
/// Grids diced with near-plane clipping: pieces still crossing the plane after the allowed
/// eye splits.
pub const C_NEAR_CLIPPED: usize = 2;
pub const C_DEPTH_LIMIT: usize = 3;
pub const C_MICROPOLYGONS: usize = 4;
pub const C_MAX_DEPTH: usize = 5;
pub const C_EYE_SPLITS: usize = 6;
pub const C_BACKFACE: usize = 7;
pub const C_CULL_BACKFACE: usize = 8;
pub const COUNTERS: usize = 16;

/// `NEAR_CLIP_GRID` in common.wgsl: a bit of `PatchItem::rates` marking a grid that crosses the
/// near plane; DiceShade keeps its points in camera space and sampling clips.
pub const NEAR_CLIP_GRID: u32 = 0x10000;

/// `SMALL_GRID_POINTS` in common.wgsl: grids of at most this many points go to DiceSmall.
pub const SMALL_GRID_POINTS: u32 = 64;

/// Whether Bound sends this diced item to DiceSmall (64 threads) rather than DiceShade (256).
pub fn is_small_grid(item: &crate::frame::PatchItem) -> bool {
    let (nu, nv) = (item.rates & 255, (item.rates >> 8) & 255);
    (nu + 1) * (nv + 1) <= SMALL_GRID_POINTS
}

pub(crate) fn cp_point(cp: &[f32; 48], i: usize) -> Vec3 {
    Vec3::new(cp[3 * i], cp[3 * i + 1], cp[3 * i + 2])
}

pub(crate) fn set_cp_point(cp: &mut [f32; 48], i: usize, p: Vec3) {
    cp[3 * i..3 * i + 3].copy_from_slice(&p.to_array());
}

pub(crate) fn project(f: &crate::frame::Frame, p: Vec3) -> [f32; 2] {
    [
        0.5 * f.width as f32 + f.focal * p.x / p.z,
        0.5 * f.height as f32 - f.focal * p.y / p.z,
    ]
}

/// The sample-jitter hash: Wellons's `lowbias32` (its WGSL twin is `reyes_hash` in
/// `shaders/reyes/common.wgsl`).
pub use scheduler::hash::lowbias32 as reyes_hash;
