//! The Reyes stages as CPU code: each file is the Rust twin of the WGSL file of the same name in
//! `shaders/reyes/`, in f32 and in the same order of operations, so that the CPU pipeline
//! (`crate::cpu_render`) is a reference the GPU image is checked against.

pub mod bound;
pub mod dice_shade;
pub mod hiz;
pub mod resolve;
pub mod sample;
pub mod sample_uvt;
pub mod shade;
pub mod split;
pub mod trim;

use glam::{Vec3, Vec4};

/// Counters the stages keep, indexed like `C_*` in `shaders/reyes/common.wgsl`.
pub const C_CULL_CLIP: usize = 0;
/// Items culled because their screen bound misses the bucket.
pub const C_CULL_OFFSCREEN: usize = 1;
/// Grids diced with near-plane clipping: pieces still crossing the plane after the allowed
/// eye splits.
pub const C_NEAR_CLIPPED: usize = 2;
/// Grids diced at `max_depth` although they wanted another split.
pub const C_DEPTH_LIMIT: usize = 3;
/// Micropolygons shaded and sampled.
pub const C_MICROPOLYGONS: usize = 4;
/// Deepest split count of a diced item (a maximum, not a sum).
pub const C_MAX_DEPTH: usize = 5;
/// Splits made because an item crossed the near plane.
pub const C_EYE_SPLITS: usize = 6;
/// Micropolygons culled as back-facing (`Sides 1`).
pub const C_BACKFACE: usize = 7;
/// Items culled in Bound as back-facing at every point.
pub const C_CULL_BACKFACE: usize = 8;
/// Items culled in Bound as hidden behind what is already drawn (occlusion culling,
/// [`hiz`]).
pub const C_CULL_OCCLUDED: usize = 9;
/// Items culled in Bound as wholly cut away by their patch's trim loops ([`trim`]).
pub const C_CULL_TRIMMED: usize = 10;
/// Words of the counter buffer (the `C_*` indices and room to spare).
pub const COUNTERS: usize = 16;

/// `NEAR_CLIP_GRID` in common.wgsl: a bit of `PatchItem::rates` marking a grid that crosses the
/// near plane; DiceShade keeps its points in camera space and sampling clips.
pub const NEAR_CLIP_GRID: u32 = 0x10000;

/// `SMALL_GRID_POINTS` in common.wgsl: grids of at most this many points go to DiceSmall.
pub const SMALL_GRID_POINTS: u32 = 64;

/// `PATCH_RATIONAL` in common.wgsl: see [`crate::frame::PATCH_RATIONAL`].
pub use crate::frame::PATCH_RATIONAL;

/// Whether Bound sends this diced item to DiceSmall (64 threads) rather than DiceShade (256).
pub fn is_small_grid(item: &crate::frame::PatchItem) -> bool {
    let (nu, nv) = (item.rates & 255, (item.rates >> 8) & 255);
    (nu + 1) * (nv + 1) <= SMALL_GRID_POINTS
}

/// An item's 16 control points, xyz each (`PatchItem::cp`): the points of a polynomial patch,
/// the homogeneous `x w, y w, z w` of a rational one; or a net made Euclidean by
/// [`to_euclidean`].
pub type ControlNet = [f32; 48];

/// The 16 weights of a rational item's control points, `w[4*v + u]` ([`rational_weights`]).
pub type Weights = [f32; 16];

/// Control point `i` of a net (`cp_point` in common.wgsl).
pub fn cp_point(cp: &ControlNet, i: usize) -> Vec3 {
    Vec3::new(cp[3 * i], cp[3 * i + 1], cp[3 * i + 2])
}

/// Sets control point `i` of a net (`set_cp_point` in common.wgsl).
pub fn set_cp_point(cp: &mut ControlNet, i: usize, p: Vec3) {
    cp[3 * i..3 * i + 3].copy_from_slice(&p.to_array());
}

/// Homogeneous control point `i` of a rational item, `(x w, y w, z w, w)` (`cp_h` in
/// surface.wgsl).
pub fn cp_h(cp: &ControlNet, w: &Weights, i: usize) -> Vec4 {
    cp_point(cp, i).extend(w[i])
}

/// `net_point` in bound.wgsl: each homogeneous point divided by its weight.
#[allow(
    clippy::needless_range_loop,
    reason = "the index form of the WGSL twin"
)]
pub fn to_euclidean(cp: &ControlNet, w: &Weights) -> ControlNet {
    let mut e = *cp;
    for k in 0..16 {
        set_cp_point(&mut e, k, cp_point(cp, k) / w[k]);
    }
    e
}

/// `blossom_lerp` in common.wgsl: exact at t = 0 and t = 1.
fn blossom_lerp(a: f32, b: f32, t: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// `blossom_at` in common.wgsl: the blossom of the cubic with Bernstein coefficients `c` at
/// the `i`-th argument triple of [t0, t1], (t0, t0, t0), (t0, t0, t1), (t0, t1, t1),
/// (t1, t1, t1): the Bezier coefficients of the cubic on [t0, t1] (Ramshaw, "Blossoms are
/// polar forms", 1989).
pub fn blossom_at(c: [f32; 4], t0: f32, t1: f32, i: usize) -> f32 {
    let pick = |k: usize| if i >= k { t1 } else { t0 };
    let (a, b, d) = (pick(3), pick(2), pick(1));
    let p0 = blossom_lerp(c[0], c[1], a);
    let p1 = blossom_lerp(c[1], c[2], a);
    let p2 = blossom_lerp(c[2], c[3], a);
    blossom_lerp(blossom_lerp(p0, p1, b), blossom_lerp(p1, p2, b), d)
}

/// `weight_column` in common.wgsl: the 4 table rows of the weights at entry `at`, each
/// blossomed at the u-arguments of `i`.
fn weight_column(table: &[[f32; 4]], at: u32, uv: [f32; 4], i: usize) -> [f32; 4] {
    std::array::from_fn(|l| blossom_at(table[at as usize + l], uv[0], uv[1], i))
}

/// `rational_weight` in common.wgsl: the weight of control point (i, j) of the rational item
/// with parameter range `uv` whose patch has its 16 weights at entry `at` of `table`
/// (`PatchInfo::weights`, `FrameData::primvars`).
pub fn rational_weight(table: &[[f32; 4]], at: u32, uv: [f32; 4], i: usize, j: usize) -> f32 {
    blossom_at(weight_column(table, at, uv, i), uv[2], uv[3], j)
}

/// `rational_weights` in common.wgsl: all 16 weights of the item, the same bits as
/// [`rational_weight`] (the derivation is beside the WGSL).
pub fn rational_weights(table: &[[f32; 4]], at: u32, uv: [f32; 4]) -> Weights {
    let mut w = [0f32; 16];
    for i in 0..4 {
        let c = weight_column(table, at, uv, i);
        for j in 0..4 {
            w[4 * j + i] = blossom_at(c, uv[2], uv[3], j);
        }
    }
    w
}

/// The weights of `item` (whose patch is `info`) from the table `primvars`, `None` for a
/// polynomial patch (no [`PATCH_RATIONAL`]), which reads none.
pub fn item_weights(
    item: &crate::frame::PatchItem,
    info: &crate::frame::PatchInfo,
    primvars: &[[f32; 4]],
) -> Option<Weights> {
    (info.flags & PATCH_RATIONAL != 0).then(|| rational_weights(primvars, info.weights, item.uv))
}

/// Pixel position (x right, y down, origin at the image's top left) of the camera-space point
/// `p`, `z > 0`: the pinhole projection with [`crate::frame::FrameUniforms::focal`]
/// (`project` in common.wgsl).
pub fn project(f: &crate::frame::FrameUniforms, p: Vec3) -> [f32; 2] {
    [
        0.5 * f.width as f32 + f.focal * p.x / p.z,
        0.5 * f.height as f32 - f.focal * p.y / p.z,
    ]
}

/// The sample-jitter hash: Wellons's `lowbias32` (its WGSL twin is `reyes_hash` in
/// `shaders/reyes/common.wgsl`).
pub use scheduler::hash::lowbias32 as reyes_hash;

/// `moved_point` in common.wgsl: `p` at shutter close under the motion at `at` in the table.
pub fn moved_point(table: &[[f32; 4]], at: u32, p: Vec3) -> Vec3 {
    let r = |k: usize| table[at as usize + k];
    let row = |k: usize| {
        let m = r(k);
        m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]
    };
    Vec3::new(row(0), row(1), row(2))
}

/// `coc` in common.wgsl: the signed circle of confusion in pixels of depth z.
pub fn coc(f: &crate::frame::FrameUniforms, z: f32) -> f32 {
    f.coc_scale * (f.inv_focus - 1.0 / z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::homogeneous::{split_u, split_v};
    use glam::DVec4;

    /// Blossoming a patch's weights at an item's range gives the sub-patch's weights: those
    /// f64 de Casteljau halving gives, to f32 rounding, down random paths of 20 splits. A root
    /// item gets the table's weights exactly, and the two halves of a split get the same bits
    /// on the edge they share.
    #[test]
    fn blossomed_weights_are_the_sub_patch_weights() {
        let mut seed = 0x9e37_79b9u32;
        let mut rnd = || {
            seed = reyes_hash(seed);
            seed as f32 / u32::MAX as f32
        };
        let mut worst = 0f64;
        for _ in 0..100 {
            let w: Weights = std::array::from_fn(|_| 0.01 + 0.99 * rnd());
            let table: Vec<[f32; 4]> = (0..4)
                .map(|l| std::array::from_fn(|u| w[4 * l + u]))
                .collect();
            let mut uv = [0f32, 1.0, 0.0, 1.0];
            assert_eq!(rational_weights(&table, 0, uv), w);
            let mut net: [DVec4; 16] =
                std::array::from_fn(|k| DVec4::new(0.0, 0.0, 0.0, w[k] as f64));
            for _ in 0..20 {
                let along_u = rnd() < 0.5;
                let (lo, hi) = if along_u { (0, 1) } else { (2, 3) };
                let m = (uv[lo] + uv[hi]) * 0.5;
                let (mut first, mut second) = (uv, uv);
                first[hi] = m;
                second[lo] = m;
                let (a, b) = (
                    rational_weights(&table, 0, first),
                    rational_weights(&table, 0, second),
                );
                for r in 0..4 {
                    let (ka, kb) = if along_u {
                        (4 * r + 3, 4 * r)
                    } else {
                        (12 + r, r)
                    };
                    assert_eq!(a[ka].to_bits(), b[kb].to_bits(), "shared edge");
                }
                let take_second = rnd() < 0.5;
                uv = if take_second { second } else { first };
                let halves = if along_u {
                    split_u(&net)
                } else {
                    split_v(&net)
                };
                net = if take_second { halves.1 } else { halves.0 };
                let got = rational_weights(&table, 0, uv);
                for k in 0..16 {
                    let i = k % 4;
                    let j = k / 4;
                    assert_eq!(got[k], rational_weight(&table, 0, uv, i, j));
                    let rel = (got[k] as f64 - net[k].w).abs() / net[k].w;
                    worst = worst.max(rel);
                    assert!(rel < 2e-6, "weight {k}: {} vs {}", got[k], net[k].w);
                }
            }
        }
        eprintln!("largest relative error of a blossomed weight: {worst:.2e}");
    }
}
