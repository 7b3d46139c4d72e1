//! Twin of `shaders/reyes/dice_shade.wgsl` and `surface.wgsl`: the grid of points with normals from the patch's
//! derivatives, displaced along them for a displaced patch, shaded; then every micropolygon
//! sampled.

use super::sample::{Cover, micropolygon_dilation, sample_micropolygon, sample_near_clipped};
use super::{ControlNet, NEAR_CLIP_GRID, Weights, cp_h, cp_point, item_weights, project, shade};
use crate::frame::{
    DISPLACE_BUMPS, DisplacementNormals, FIELD_BILINEAR, FIELD_FLAT, FrameData, PATCH_DISPLACED,
    PatchInfo, PatchItem,
};
use glam::{Vec2, Vec3, Vec4};

fn bern3(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

fn bern2(t: f32) -> [f32; 3] {
    let s = 1.0 - t;
    [s * s, 2.0 * t * s, t * t]
}

/// Position, d/du, d/dv of a polynomial patch (`cp` the points) at (u, v). The tangents come from the
/// hodograph (differences of neighbouring control points), so they are exactly zero where
/// control points coincide (see `eval_patch` in surface.wgsl).
pub fn eval_patch(cp: &ControlNet, u: f32, v: f32) -> [Vec3; 3] {
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

/// Position, d/du, d/dv of a rational item (homogeneous xyz `cp`, weights `w`) at (u, v): the
/// 4D sum and its hodograph as in [`eval_patch`], then the quotient rule P = X/w,
/// Pu = (Xu - wu P)/w (`eval_rational` in surface.wgsl).
pub fn eval_rational(cp: &ControlNet, w: &Weights, u: f32, v: f32) -> [Vec3; 3] {
    let (bu, bv, hu, hv) = (bern3(u), bern3(v), bern2(u), bern2(v));
    let (mut x, mut xu, mut xv) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
    for j in 0..4 {
        for i in 0..4 {
            let c = cp_h(cp, w, 4 * j + i);
            x += c * (bu[i] * bv[j]);
            if i < 3 {
                xu += (cp_h(cp, w, 4 * j + i + 1) - c) * (hu[i] * bv[j]);
            }
            if j < 3 {
                xv += (cp_h(cp, w, 4 * j + i + 4) - c) * (bu[i] * hv[j]);
            }
        }
    }
    let p = x.truncate() / x.w;
    let s = 3.0 / x.w;
    [
        p,
        (xu.truncate() - xu.w * p) * s,
        (xv.truncate() - xv.w * p) * s,
    ]
}

/// [`eval_rational`] for a rational item (`w` its weights, [`item_weights`]), else
/// [`eval_patch`] (`eval_surface`).
pub fn eval_surface(cp: &ControlNet, w: Option<&Weights>, u: f32, v: f32) -> [Vec3; 3] {
    match w {
        Some(w) => eval_rational(cp, w, u, v),
        None => eval_patch(cp, u, v),
    }
}

/// Squares of the largest control-net steps along u and v (3 times the steps bound |Pu|
/// and |Pv|) of a polynomial patch.
pub fn net_steps2(cp: &ControlNet) -> [f32; 2] {
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

/// [`net_steps2`] of a rational item (homogeneous xyz, weights): squares of s_u, s_v with
/// |Pu| <= 3 s_u, s_u = (wmax du + dwu r) / wmin (`net_steps2_rational` in surface.wgsl
/// derives it).
pub fn net_steps2_rational(cp: &ControlNet, w: &Weights) -> [f32; 2] {
    let (mut lo, mut hi) = (Vec3::splat(3.0e38), Vec3::splat(-3.0e38));
    let (mut wmin, mut wmax) = (3.0e38f32, 0f32);
    let mut m = Vec4::ZERO;
    let e = |h: Vec4| h.truncate() / h.w;
    for j in 0..4 {
        for i in 0..4 {
            let h = cp_h(cp, w, 4 * j + i);
            lo = lo.min(e(h));
            hi = hi.max(e(h));
            wmin = wmin.min(h.w);
            wmax = wmax.max(h.w);
        }
        for i in 0..3 {
            let (a, b) = (cp_h(cp, w, 4 * j + i), cp_h(cp, w, 4 * j + i + 1));
            let (c, d) = (cp_h(cp, w, 4 * i + j), cp_h(cp, w, 4 * i + j + 4));
            let du = e(b) - e(a);
            let dv = e(d) - e(c);
            m = m.max(Vec4::new(
                du.dot(du),
                dv.dot(dv),
                (b.w - a.w).abs(),
                (d.w - c.w).abs(),
            ));
        }
    }
    let r = (hi - lo).length();
    let s = (wmax * Vec2::new(m.x.sqrt(), m.y.sqrt()) + Vec2::new(m.z, m.w) * r) / wmin;
    [s.x * s.x, s.y * s.y]
}

/// The outside normal. Where it is degenerate (a vanishing tangent at a collapsed edge, or
/// parallel tangents) it is taken 1e-3, 1e-2, then 1e-1 of the way to the centre until
/// |Pu x Pv| reaches 1e-3 of its largest possible value on the patch; with no tangent plane
/// anywhere (all control points equal) it is the direction to the eye. See surface.wgsl.
/// `cp` is an item's net; `w` its weights if its patch is rational ([`item_weights`]).
pub fn patch_normal(cp: &ControlNet, w: Option<&Weights>, u: f32, v: f32, flip: bool) -> Vec3 {
    patch_normal_at(cp, w, eval_surface(cp, w, u, v), u, v, flip)
}

/// [`patch_normal`] given `e = eval_surface(cp, w, u, v)`, as DiceShade calls it.
pub fn patch_normal_at(
    cp: &ControlNet,
    w: Option<&Weights>,
    e: [Vec3; 3],
    u: f32,
    v: f32,
    flip: bool,
) -> Vec3 {
    let mut n = e[1].cross(e[2]);
    let steps2 = match w {
        Some(w) => net_steps2_rational(cp, w),
        None => net_steps2(cp),
    };
    let least2 = 8.1e-5 * steps2[0] * steps2[1];
    let mut inward = 1.0e-3f32;
    let mut k = 0;
    while k < 3 && !(n.dot(n) > least2) {
        let (qu, qv) = (u + (0.5 - u) * inward, v + (0.5 - v) * inward);
        let f = eval_surface(cp, w, qu, qv);
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

/// `color_field` in surface.wgsl: the value at (u, v) of the original patch of the colour
/// field `field` (`PatchInfo::cs` or `os`, not 0) in the primitive-variable table.
pub fn color_field(table: &[[f32; 4]], field: u32, u: f32, v: f32) -> Vec3 {
    let at = (field >> 2) as usize;
    let c = |k: usize| Vec3::from_slice(&table[at + k][..3]);
    match field & 3 {
        FIELD_FLAT => c(0),
        FIELD_BILINEAR => {
            let lo = c(0) + (c(1) - c(0)) * u;
            let hi = c(2) + (c(3) - c(2)) * u;
            lo + (hi - lo) * v
        }
        _ => {
            let (bu, bv) = (bern3(u), bern3(v));
            let mut out = Vec3::ZERO;
            #[allow(
                clippy::needless_range_loop,
                reason = "the index form of the WGSL twin, summed in the same order"
            )]
            for j in 0..4 {
                for i in 0..4 {
                    out += c(4 * j + i) * (bu[i] * bv[j]);
                }
            }
            out
        }
    }
}

/// `original_uv` in surface.wgsl: (u, v) of the item's own square in its original patch.
pub fn original_uv(item: &PatchItem, u: f32, v: f32) -> (f32, f32) {
    (
        item.uv[0] + (item.uv[1] - item.uv[0]) * u,
        item.uv[2] + (item.uv[3] - item.uv[2]) * v,
    )
}

/// `micropolygon_cover` in dice_shade.wgsl: the opacity of micropolygon (i, j) of an nu x nv
/// grid, the mean of "Os" at its centre (else the material's), as a [`Cover`].
pub fn micropolygon_cover(item: &PatchItem, data: &FrameData, [i, j, nu, nv]: [u32; 4]) -> Cover {
    let info: PatchInfo = data.patch_info[item.patch_id as usize];
    let mut alpha = data.materials[info.material as usize].opacity;
    if info.os != 0 {
        let (u, v) = original_uv(
            item,
            (i as f32 + 0.5) / nu as f32,
            (j as f32 + 0.5) / nv as f32,
        );
        let o = color_field(&data.primvars, info.os, u, v);
        alpha = (o.x + o.y + o.z) / 3.0;
    }
    // Trimmed (`micropolygon_cover` in dice_shade.wgsl): a micropolygon whose centre is cut
    // away covers nothing.
    if super::trim::needs_trim(item, &info) {
        let (u, v) = original_uv(
            item,
            (i as f32 + 0.5) / nu as f32,
            (j as f32 + 0.5) / nv as f32,
        );
        if !super::trim::keeps(&data.primvars, super::trim::header(&info), u, v) {
            alpha = 0.0;
        }
    }
    Cover::new(alpha, item.patch_id)
}

/// Grid points (x, y in pixels, z, packed colour bits as f32), row-major, (nu+1) x (nv+1);
/// for a grid marked [`NEAR_CLIP_GRID`], x, y, z in camera space (projected after clipping).
/// A displaced patch's points move along their normal first, and shade with the normal of
/// the displaced grid (`dice_grid` in dice_shade.wgsl).
pub fn dice(item: &PatchItem, data: &FrameData) -> (u32, u32, Vec<[f32; 4]>) {
    let (nu, nv, grid, _) = dice_points(item, data);
    (nu, nv, grid)
}

/// [`dice`], and each grid point's camera-space position (after displacement).
pub fn dice_points(item: &PatchItem, data: &FrameData) -> (u32, u32, Vec<[f32; 4]>, Vec<Vec3>) {
    let (nu, nv) = (item.rates & 255, (item.rates >> 8) & 255);
    let info = data.patch_info[item.patch_id as usize];
    let points = ((nu + 1) * (nv + 1)) as usize;
    // Each GPU thread blossoms the same weights (rational patches only).
    let weights = item_weights(item, &info, &data.primvars);
    let w = weights.as_ref();
    let flip = info.flags & 1 != 0;
    let uv = |t: usize| {
        (
            (t % (nu as usize + 1)) as f32 / nu as f32,
            (t / (nu as usize + 1)) as f32 / nv as f32,
        )
    };
    let surface: Vec<([Vec3; 3], Vec3)> = (0..points)
        .map(|t| {
            let (u, v) = uv(t);
            let e = eval_surface(&item.cp, w, u, v);
            (e, patch_normal_at(&item.cp, w, e, u, v, flip))
        })
        .collect();
    if info.flags & PATCH_DISPLACED == 0 {
        let grid = (0..points)
            .map(|t| {
                let (u, v) = uv(t);
                shade_point(item, data, surface[t].0[0], surface[t].1, u, v)
            })
            .collect();
        return (nu, nv, grid, surface.iter().map(|s| s.0[0]).collect());
    }
    let at = info.displacement as usize;
    let undisplaced: Vec<Vec3> = surface.iter().map(|s| s.0[0]).collect();
    let approx = data.frame.displacement_normals == DisplacementNormals::Approximate as u32;
    let amount = data.primvars[at][0];
    let mut dirs = Vec::with_capacity(points);
    let mut moved = Vec::with_capacity(points);
    let mut normals = Vec::with_capacity(points);
    for (t, (e, n)) in surface.iter().enumerate() {
        let (u, v) = uv(t);
        let (qu, qv) = original_uv(item, u, v);
        let mut dir = n.normalize();
        let mut ns = *n;
        if approx {
            dir = grid_normal(&undisplaced, t, nu, nv, dir, flip);
        } else {
            let span = Vec2::new(item.uv[1] - item.uv[0], item.uv[3] - item.uv[2]);
            let dq = displacement_slope(&data.primvars, at, qu, qv) * amount * span;
            let s = if flip { -1.0 } else { 1.0 };
            ns = *n + s * (dq.y * e[1].cross(dir) + dq.x * dir.cross(e[2]));
        }
        let d = amount * displacement_pattern(&data.primvars, at, qu, qv);
        dirs.push(dir);
        normals.push(ns);
        moved.push(e[0] + dir * d);
    }
    let grid = (0..points)
        .map(|t| {
            let (u, v) = uv(t);
            let ns = if approx {
                grid_normal(&moved, t, nu, nv, dirs[t], flip)
            } else {
                normals[t]
            };
            shade_point(item, data, moved[t], ns, u, v)
        })
        .collect();
    (nu, nv, grid, moved)
}

/// `shade_point` in dice_shade.wgsl: grid point (u, v) of `item` at camera-space `p` with
/// normal `n`, shaded, as (x, y in pixels, z, colour bits), or camera space for a grid
/// crossing the near plane.
fn shade_point(item: &PatchItem, data: &FrameData, p: Vec3, n: Vec3, u: f32, v: f32) -> [f32; 4] {
    let f = &data.frame;
    let info = data.patch_info[item.patch_id as usize];
    let m = &data.materials[info.material as usize];
    let cs = if info.cs != 0 {
        let (uo, vo) = original_uv(item, u, v);
        color_field(&data.primvars, info.cs, uo, vo)
    } else {
        Vec3::from(m.color)
    };
    let ns = if info.normal != 0 && info.flags & PATCH_DISPLACED == 0 {
        let (uo, vo) = original_uv(item, u, v);
        color_field(&data.primvars, info.normal, uo, vo)
    } else {
        n
    };
    let c = shade::shade(p, ns, m, cs, &data.lights);
    let back = n.dot(p) > 0.0;
    let color = f32::from_bits(shade::pack_color(c, back));
    if item.rates & NEAR_CLIP_GRID != 0 {
        [p.x, p.y, p.z, color]
    } else {
        let z = p.z.max(f.near);
        let s = project(f, Vec3::new(p.x, p.y, z));
        [s[0], s[1], z, color]
    }
}

/// `grid_normal` in dice_shade.wgsl: the outside normal of point `t` of the nu x nv grid
/// `g` (camera space) from its central differences (one-sided on the border), or `fallback`
/// where they are degenerate.
pub fn grid_normal(g: &[Vec3], t: usize, nu: u32, nv: u32, fallback: Vec3, flip: bool) -> Vec3 {
    let (nu, nv) = (nu as usize, nv as usize);
    let cols = nu + 1;
    let (i, j) = (t % cols, t / cols);
    let du = g[j * cols + (i + 1).min(nu)] - g[j * cols + i.saturating_sub(1)];
    let dv = g[(j + 1).min(nv) * cols + i] - g[j.saturating_sub(1) * cols + i];
    let n = du.cross(dv);
    let scale = du.dot(du) + dv.dot(dv);
    // Written so that a NaN falls back too.
    let regular = n.dot(n) > 1.0e-6 * scale * scale;
    if !regular {
        return fallback;
    }
    (if flip { -n } else { n }).normalize()
}

/// `DISPLACE_FD_STEP` in surface.wgsl: the step of [`displacement_slope`]'s differences.
pub const DISPLACE_FD_STEP: f32 = 1.0 / 1024.0;

/// `displacement_slope` in surface.wgsl: central differences (d/du, d/dv) of the pattern at
/// (u, v) of the original patch.
pub fn displacement_slope(table: &[[f32; 4]], at: usize, u: f32, v: f32) -> Vec2 {
    let h = DISPLACE_FD_STEP;
    let p = |u, v| displacement_pattern(table, at, u, v);
    let du = p(u + h, v) - p(u - h, v);
    let dv = p(u, v + h) - p(u, v - h);
    Vec2::new(du, dv) * (0.5 / h)
}

/// `displacement_pattern` in surface.wgsl: the pattern of the displacement entry `at` of
/// `table` at (u, v) of the original patch, in [0, 1].
pub fn displacement_pattern(table: &[[f32; 4]], at: usize, u: f32, v: f32) -> f32 {
    use std::f32::consts::PI;
    let e = table[at];
    if e[2].to_bits() == DISPLACE_BUMPS {
        let f = e[3].to_bits() as f32;
        let s = (PI * f * u).sin() * (PI * f * v).sin();
        return s * s;
    }
    let m = e[3].to_bits() as usize;
    let (w, h) = (table[m][0].to_bits(), table[m][1].to_bits());
    let x = (u * w as f32 - 0.5).clamp(0.0, (w - 1) as f32);
    let y = (v * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
    let (x0, y0) = (x as u32, y as u32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let texel = |x: u32, y: u32| {
        let k = (y * w + x) as usize;
        table[m + 1 + k / 4][k % 4]
    };
    let top = texel(x0, y0) * (1.0 - fx) + texel(x1, y0) * fx;
    let bottom = texel(x0, y1) * (1.0 - fx) + texel(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// Dices, shades and samples one grid into `samples`; returns (micropolygons, back-face culled).
pub fn dice_shade(item: &PatchItem, data: &FrameData, samples: &mut [u64]) -> (u32, u32) {
    let (nu, nv, g, points) = dice_points(item, data);
    let info = data.patch_info[item.patch_id as usize];
    let two_sided = info.flags & 2 != 0;
    let f = &data.frame;
    // Motion blur or depth of field: each point at shutter close too (`shade_point` in
    // dice_shade.wgsl).
    let uvt = f.uvt != crate::frame::UVT_OFF && item.rates & NEAR_CLIP_GRID == 0;
    let close: Vec<[f32; 4]> = if uvt {
        (points.iter())
            .map(|&p| {
                let p1 = if info.flags & crate::frame::PATCH_MOVING != 0 {
                    super::moved_point(&data.primvars, info.motion, p)
                } else {
                    p
                };
                let z1 = p1.z.max(f.near);
                let s = project(f, Vec3::new(p1.x, p1.y, z1));
                [s[0], s[1], z1, 0.0]
            })
            .collect()
    } else {
        Vec::new()
    };
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
        let cover = micropolygon_cover(item, data, [i as u32, j as u32, nu, nv]);
        if uvt {
            let q1 = [
                close[j * cols + i],
                close[j * cols + i + 1],
                close[(j + 1) * cols + i + 1],
                close[(j + 1) * cols + i],
            ];
            let sample = super::sample_uvt::sample_micropolygon_uvt;
            if !sample(q, q1, grow, two_sided, cover, f, samples) {
                culled += 1;
            }
            continue;
        }
        if !sample(q, grow, two_sided, cover, &data.frame, samples) {
            culled += 1;
        }
    }
    (nu * nv, culled)
}
