//! Twin of `shaders/reyes/dice_shade.wgsl`: the grid of points with normals from the patch's
//! derivatives, shaded; then every micropolygon sampled.

use super::sample::{micropolygon_dilation, sample_micropolygon, sample_near_clipped};
use super::{NEAR_CLIP_GRID, cp_point, project, shade};
use crate::frame::{FrameData, PatchItem};
use glam::Vec3;

fn bern3(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

fn bern2(t: f32) -> [f32; 3] {
    let s = 1.0 - t;
    [s * s, 2.0 * t * s, t * t]
}

/// Position, d/du, d/dv of the patch at (u, v). The tangents come from the hodograph
/// (differences of neighbouring control points), so they are exactly zero where control
/// points coincide (see `eval_patch` in dice_shade.wgsl).
pub fn eval_patch(cp: &[f32; 48], u: f32, v: f32) -> [Vec3; 3] {
    let (bu, bv, hu, hv) = (bern3(u), bern3(v), bern2(u), bern2(v));
    let (mut p, mut pu, mut pv) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
    for j in 0..4 {
        for i in 0..4 {
            let c = cp_point(cp, 4 * j + i);
            p += c * (bu[i] * bv[j]);
            if i < 3 {
                pu += (cp_point(cp, 4 * j + i + 1) - c) * (hu[i] * bv[j]);
            }
            if j < 3 {
                pv += (cp_point(cp, 4 * j + i + 4) - c) * (bu[i] * hv[j]);
            }
        }
    }
    [p, 3.0 * pu, 3.0 * pv]
}

/// Squares of the largest control-net steps along u and v (3 times the steps bound |Pu|
/// and |Pv|).
pub fn net_steps2(cp: &[f32; 48]) -> [f32; 2] {
    let mut m = [0f32; 2];
    for j in 0..4 {
        for i in 0..3 {
            let du = cp_point(cp, 4 * j + i + 1) - cp_point(cp, 4 * j + i);
            let dv = cp_point(cp, 4 * i + j + 4) - cp_point(cp, 4 * i + j);
            m = [m[0].max(du.dot(du)), m[1].max(dv.dot(dv))];
        }
    }
    m
}

/// The outside normal. Where it is degenerate (a vanishing tangent at a collapsed edge, or
/// parallel tangents) it is taken 1e-3, 1e-2, then 1e-1 of the way to the centre until
/// |Pu x Pv| reaches 1e-3 of its largest possible value on the patch; with no tangent plane
/// anywhere (all control points equal) it is the direction to the eye. See dice_shade.wgsl.
pub fn patch_normal(cp: &[f32; 48], u: f32, v: f32, flip: bool) -> Vec3 {
    patch_normal_at(cp, eval_patch(cp, u, v), u, v, flip)
}

/// [`patch_normal`] given `e = eval_patch(cp, u, v)`, as DiceShade calls it.
pub fn patch_normal_at(cp: &[f32; 48], e: [Vec3; 3], u: f32, v: f32, flip: bool) -> Vec3 {
    let mut n = e[1].cross(e[2]);
    let steps2 = net_steps2(cp);
    let least2 = 8.1e-5 * steps2[0] * steps2[1];
    let mut inward = 1.0e-3f32;
    let mut k = 0;
    while k < 3 && !(n.dot(n) > least2) {
        let (qu, qv) = (u + (0.5 - u) * inward, v + (0.5 - v) * inward);
        let f = eval_patch(cp, qu, qv);
        n = f[1].cross(f[2]);
        inward *= 10.0;
        k += 1;
    }
    if !(n.dot(n) > 0.0) {
        return if e[0].dot(e[0]) > 0.0 {
            -e[0]
        } else {
            Vec3::new(0.0, 0.0, -1.0)
        };
    }
    if flip { -n } else { n }
}

/// Grid points (x, y in pixels, z, packed colour bits as f32), row-major, (nu+1) x (nv+1);
/// for a grid marked [`NEAR_CLIP_GRID`], x, y, z in camera space (projected after clipping).
pub fn dice(item: &PatchItem, data: &FrameData) -> (u32, u32, Vec<[f32; 4]>) {
    let f = &data.frame;
    let (nu, nv) = (item.rates & 255, (item.rates >> 8) & 255);
    let info = data.patch_info[item.patch_id as usize];
    let m = &data.materials[info.material as usize];
    let mut grid = Vec::with_capacity(((nu + 1) * (nv + 1)) as usize);
    for t in 0..(nu + 1) * (nv + 1) {
        let u = (t % (nu + 1)) as f32 / nu as f32;
        let v = (t / (nu + 1)) as f32 / nv as f32;
        let e = eval_patch(&item.cp, u, v);
        let n = patch_normal_at(&item.cp, e, u, v, info.flags & 1 != 0);
        let c = shade::shade(e[0], n, m, &data.lights);
        let back = n.dot(e[0]) > 0.0;
        let color = f32::from_bits(shade::pack_color(c, back));
        if item.rates & NEAR_CLIP_GRID != 0 {
            grid.push([e[0].x, e[0].y, e[0].z, color]);
        } else {
            let z = e[0].z.max(f.near);
            let s = project(f, Vec3::new(e[0].x, e[0].y, z));
            grid.push([s[0], s[1], z, color]);
        }
    }
    (nu, nv, grid)
}

/// Dices, shades and samples one grid into `samples`; returns (micropolygons, back-face culled).
pub fn dice_shade(item: &PatchItem, data: &FrameData, samples: &mut [u64]) -> (u32, u32) {
    let (nu, nv, g) = dice(item, data);
    let two_sided = data.patch_info[item.patch_id as usize].flags & 2 != 0;
    let cols = (nu + 1) as usize;
    let mut culled = 0;
    for t in 0..(nu * nv) as usize {
        let (i, j) = (t % nu as usize, t / nu as usize);
        let q = [
            g[j * cols + i],
            g[j * cols + i + 1],
            g[(j + 1) * cols + i + 1],
            g[(j + 1) * cols + i],
        ];
        let sample = if item.rates & NEAR_CLIP_GRID != 0 {
            sample_near_clipped
        } else {
            sample_micropolygon
        };
        let grow = micropolygon_dilation(item.dilate, i as u32, j as u32, nu, nv);
        if !sample(q, grow, two_sided, &data.frame, samples) {
            culled += 1;
        }
    }
    (nu * nv, culled)
}
