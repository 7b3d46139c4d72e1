//! Twin of `shaders/reyes/bound.wgsl`: screen bound, culling, and the split-or-dice decision.
//! Rational patches are bounded by their Euclidean control points (convex hull; the weights
//! blossomed from the patch's table, [`super::rational_weights`]), culled as back-facing by
//! the test on their homogeneous net, and get a rational crack bound; the arguments are
//! beside the WGSL. Not twinned: bound.wgsl's phases for root items tagged with an occlusion
//! history (`ROOT_HISTORY`), which only the GPU's pipelined frames make
//! ([`crate::realtime::occlusion`]); the twin renders single frames, whose roots carry none.

use super::{
    ControlNet, Weights, coc, cp_h, cp_point, item_weights, moved_point, project, to_euclidean,
};
use crate::frame::{FrameUniforms, PATCH_MOVING, PatchInfo, PatchItem};
use glam::{Vec2, Vec3, Vec4};

/// See `MAX_DILATE_PX` and `CULL_MARGIN_PX` in common.wgsl: bucketed renders stay exact.
pub const MAX_DILATE_PX: f32 = 2.0;
/// Pixels beyond the bucket within which an item is kept rather than culled as off screen
/// (larger than `MAX_DILATE_PX`, so no dilated micropolygon that reaches the bucket is lost).
pub const CULL_MARGIN_PX: f32 = 3.0;

/// Why Bound drops an item (the `C_CULL_*` counters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cull {
    /// Wholly in front of the near plane or behind the far plane.
    Clip,
    /// Nothing of it (in front of the near plane) reaches the bucket.
    Offscreen,
    /// Back-facing at every point (one-sided surfaces only).
    Backface,
    /// Behind what the bucket's samples already hold everywhere under its bound
    /// ([`super::hiz::occluded`]).
    Occluded,
    /// Wholly cut away by its patch's trim loops ([`super::trim`]).
    Trimmed,
}

/// What Bound does with an item ([`bound`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Decision {
    /// Drop it, for this reason.
    Cull(Cull),
    /// Split along u (else v); `eye` marks a near-plane split (the item's count is already raised).
    Split {
        /// Split along u, else along v.
        along_u: bool,
        /// The item to split.
        item: PatchItem,
        /// A near-plane split.
        eye: bool,
    },
    /// Dice with the rates and dilation filled in; `depth_limited` when it wanted another split.
    /// A grid still crossing the near plane has [`super::NEAR_CLIP_GRID`] set in its rates.
    Dice {
        /// The item with its rates and dilation set.
        item: PatchItem,
        /// It wanted another split but had reached [`crate::frame::FrameUniforms::max_depth`].
        depth_limited: bool,
    },
}

/// Bound's decision for `item` (the work of all 16 threads and of thread 0's reduction);
/// `primvars` is the table of [`crate::frame::FrameData::primvars`], where a rational patch
/// has its weights.
pub fn bound(
    item: &PatchItem,
    f: &FrameUniforms,
    info: &PatchInfo,
    primvars: &[[f32; 4]],
) -> Decision {
    bound_against(item, f, info, primvars, None)
}

/// [`bound`] with the occlusion test against `hiz`, the bucket's depth pyramid, when the
/// frame asks for it ([`super::hiz::OCCLUSION_TEST`]; `hiz_occluded` in bound.wgsl).
pub fn bound_against(
    item: &PatchItem,
    f: &FrameUniforms,
    info: &PatchInfo,
    primvars: &[[f32; 4]],
    hiz: Option<&super::hiz::Hiz>,
) -> Decision {
    // Each thread's weight is the same bits as thread 0's rational_weights (common.wgsl).
    let weights = item_weights(item, info, primvars);
    let rational = weights.is_some();
    let w = weights.unwrap_or([1.0; 16]);
    // Thread 0's net after to_euclidean: the Euclidean points.
    let euclidean = if rational {
        to_euclidean(&item.cp, &w)
    } else {
        item.cp
    };
    let cp = &euclidean;
    let pts: Vec<(Vec2, f32)> = (0..16)
        .map(|k| {
            let p = cp_point(cp, k);
            let s = if p.z >= f.near {
                project(f, p)
            } else {
                [0.0, 0.0]
            };
            (Vec2::from(s), p.z)
        })
        .collect();
    let mut zmin = pts.iter().map(|p| p.1).fold(pts[0].1, f32::min);
    let mut zmax = pts.iter().map(|p| p.1).fold(pts[0].1, f32::max);
    // A displaced patch's bound grows by its radius r (see bound.wgsl).
    let r = displacement_radius(info, primvars);
    zmin -= r;
    zmax += r;
    // Motion blur or depth of field: culling uses the bound over the shutter and the lens
    // (`uvt_bound` in bound.wgsl); splitting and dicing the patch at shutter open.
    let uvt =
        (f.uvt != crate::frame::UVT_OFF).then(|| uvt_bound(f, cp, info, primvars, r, (zmin, zmax)));
    let moving = uvt.is_some() && info.flags & crate::frame::PATCH_MOVING != 0;
    let (uzmin, uzmax) = uvt.map_or((zmin, zmax), |u| u.2);
    if uzmax < f.near || uzmin > f.far {
        return Decision::Cull(Cull::Clip);
    }
    if info.flags & 2 == 0 && r == 0.0 && !moving && backfacing(&item.cp, info.flags & 1 != 0) {
        return Decision::Cull(Cull::Backface);
    }
    // Trimmed (`bound_execute` in bound.wgsl): culled when wholly cut away, marked when
    // wholly kept.
    let mut marked = *item;
    if super::trim::needs_trim(item, info) {
        match super::trim::classify(primvars, super::trim::header(info), item.uv) {
            super::trim::TRIM_OUT => return Decision::Cull(Cull::Trimmed),
            super::trim::TRIM_IN => marked.depth |= super::trim::TRIM_INSIDE,
            _ => {}
        }
    }
    let item = &marked;
    let depth = item.splits();
    let t0 = Vec2::new(f.tile_x0 as f32, f.tile_y0 as f32) - CULL_MARGIN_PX;
    let t1 =
        Vec2::new((f.tile_x0 + f.tile_w) as f32, (f.tile_y0 + f.tile_h) as f32) + CULL_MARGIN_PX;
    let misses = |lo: Vec2, hi: Vec2| hi.x < t0.x || hi.y < t0.y || lo.x > t1.x || lo.y > t1.y;
    if zmin < f.near {
        let undisplaced = near_visible_bound(f, cp);
        let (lo, hi) = if r > 0.0 || uvt.is_some() {
            (Vec2::splat(-3.0e38), Vec2::splat(3.0e38))
        } else {
            undisplaced
        };
        if misses(lo, hi) {
            return Decision::Cull(Cull::Offscreen);
        }
        // A displaced piece splits by what its undisplaced surface shows (its grown bound
        // never shrinks: see bound.wgsl).
        let (slo, shi) = if r > 0.0 { undisplaced } else { (lo, hi) };
        // The image, not the bucket: see bound.wgsl.
        let image = Vec2::new(f.width as f32, f.height as f32) + CULL_MARGIN_PX;
        let seen = shi.min(image) - slo.max(Vec2::splat(-CULL_MARGIN_PX));
        let grid_px = if f.bound_px > 0.0 {
            f.bound_px
        } else {
            f.grid_max as f32 * f.mp_size
        };
        if seen.x.max(seen.y) > grid_px
            && item.eye_splits() < f.max_eye_splits
            && depth < f.max_depth
        {
            let mut e = *item;
            e.depth += 256;
            let along_u = polygon_length(cp, 1, 4) >= polygon_length(cp, 4, 1);
            return Decision::Split {
                along_u,
                item: e,
                eye: true,
            };
        }
        let mut g = *item;
        g.rates = f.grid_max | f.grid_max << 8 | super::NEAR_CLIP_GRID;
        g.dilate = if f.crack_dilation != 0 {
            // At the nearest front control point: see bound.wgsl.
            let zfront = pts.iter().map(|p| p.1).filter(|&z| z >= f.near);
            let zfront = zfront.fold(zmax, f32::min);
            crack_dilation(f, cp, &w, rational, f.grid_max, f.grid_max, zfront)
        } else {
            0
        };
        return Decision::Dice {
            item: g,
            depth_limited: false,
        };
    }
    let mut lo = pts.iter().fold(pts[0].0, |a, p| a.min(p.0));
    let mut hi = pts.iter().fold(pts[0].0, |a, p| a.max(p.0));
    // bound_px splits by the undisplaced extent (see bound.wgsl).
    let extent = hi - lo;
    if r > 0.0 {
        let mut g = 0f32;
        for k in 0..16 {
            let q = cp_point(cp, k);
            g = g.max(q.length() / (q.z * (q.z - r)));
        }
        lo -= Vec2::splat(f.focal * r * g);
        hi += Vec2::splat(f.focal * r * g);
    }
    let (clo, chi) = match uvt {
        Some((ulo, uhi, _, c)) => (
            (lo - Vec2::splat(c)).min(ulo),
            (hi + Vec2::splat(c)).max(uhi),
        ),
        None => (lo, hi),
    };
    if misses(clo, chi) {
        return Decision::Cull(Cull::Offscreen);
    }
    // Occlusion, by the bound over the shutter and the lens (see bound.wgsl).
    if let Some(h) = hiz
        && f.occlusion == super::hiz::OCCLUSION_TEST
        && super::hiz::occluded(f, h, clo, chi, super::hiz::test_depth(uzmin, uzmax))
    {
        return Decision::Cull(Cull::Occluded);
    }
    let (mut lu, mut lv) = (0f32, 0f32);
    for r in 0..4 {
        let (mut su, mut sv) = (0f32, 0f32);
        for i in 0..3 {
            su += pts[4 * r + i].0.distance(pts[4 * r + i + 1].0);
            sv += pts[4 * i + r].0.distance(pts[4 * (i + 1) + r].0);
        }
        lu = lu.max(su);
        lv = lv.max(sv);
    }
    let (split, nu, nv) = dice_decision(f, lu, lv, extent);
    if split != 0 && depth < f.max_depth {
        return Decision::Split {
            along_u: split == 1,
            item: *item,
            eye: false,
        };
    }
    let mut g = *item;
    g.rates = nu | nv << 8;
    g.dilate = if f.crack_dilation != 0 {
        let camera = crack_dilation(f, cp, &w, rational, nu, nv, zmin);
        if r == 0.0 && uvt.is_none() {
            packed_min(camera, screen_crack_dilation(&pts, &w, nu, nv))
        } else {
            camera
        }
    } else {
        0
    };
    Decision::Dice {
        item: g,
        depth_limited: split != 0,
    }
}

/// The radius a displaced patch's points move at most (camera space), 0 when undisplaced:
/// the `bound` of its displacement entry ([`crate::frame::displacement_ref`]).
pub fn displacement_radius(info: &PatchInfo, primvars: &[[f32; 4]]) -> f32 {
    if info.flags & crate::frame::PATCH_DISPLACED != 0 {
        primvars[info.displacement as usize][1]
    } else {
        0.0
    }
}

/// Screen bound (lo, hi) of the part of the patch in front of the near plane: the projections
/// of the front control points and of the crossings of the near plane by segments from a front
/// to a behind control point (`near_visible_bound` in bound.wgsl gives the argument).
pub fn near_visible_bound(f: &FrameUniforms, cp: &ControlNet) -> (Vec2, Vec2) {
    let (mut lo, mut hi) = (Vec2::splat(3.0e38), Vec2::splat(-3.0e38));
    for a in 0..16 {
        let p = cp_point(cp, a);
        if p.z < f.near {
            continue;
        }
        let s = Vec2::from(project(f, p));
        lo = lo.min(s);
        hi = hi.max(s);
        for b in 0..16 {
            let q = cp_point(cp, b);
            if q.z >= f.near {
                continue;
            }
            let x = p + (q - p) * ((p.z - f.near) / (p.z - q.z));
            let c = Vec2::from(project(f, glam::Vec3::new(x.x, x.y, f.near)));
            lo = lo.min(c);
            hi = hi.max(c);
        }
    }
    (lo, hi)
}

/// Whether every point of the patch is back-facing: `backfacing_terms` in bound.wgsl (the
/// proof is there, also why the homogeneous net `cp` serves rational patches), all 144 pairs
/// at once.
pub fn backfacing(cp: &ControlNet, flip: bool) -> bool {
    let sgn = if flip { -1.0 } else { 1.0 };
    (0..144).all(|k| {
        let (b, c) = (k / 12, k % 12);
        let ru = 4 * (b / 3) + b % 3;
        let du = cp_point(cp, ru + 1) - cp_point(cp, ru);
        let dv = cp_point(cp, c + 4) - cp_point(cp, c);
        let n = du.cross(dv);
        let nl = 1.0e-3 * n.length();
        (0..16).all(|a| {
            let p = cp_point(cp, a);
            sgn * p.dot(n) > nl * p.length()
        })
    })
}

/// Camera-space control polygon length along rows (`step` 1, `across` 4) or columns.
fn polygon_length(cp: &ControlNet, step: usize, across: usize) -> f32 {
    let mut best = 0f32;
    for r in 0..4 {
        let mut s = 0f32;
        for i in 0..3 {
            s += cp_point(cp, r * across + i * step)
                .distance(cp_point(cp, r * across + (i + 1) * step));
        }
        best = best.max(s);
    }
    best
}

/// (0 dice | 1 split u | 2 split v, rate u, rate v).
fn dice_decision(f: &FrameUniforms, lu: f32, lv: f32, extent: Vec2) -> (u32, u32, u32) {
    let gmax = f.grid_max as f32;
    if f.bound_px > 0.0 {
        let split = extent.x.max(extent.y) > f.bound_px;
        let dir = if lu >= lv { 1 } else { 2 };
        return (if split { dir } else { 0 }, f.grid_max, f.grid_max);
    }
    let nu = (lu / f.mp_size).ceil();
    let nv = (lv / f.mp_size).ceil();
    if nu > gmax || nv > gmax {
        let dir = if nu / gmax >= nv / gmax { 1 } else { 2 };
        return (dir, f.grid_max, f.grid_max);
    }
    (0, nu.max(1.0) as u32, nv.max(1.0) as u32)
}

/// Crack dilation of each boundary edge, packed (v = 0, v = 1, u = 0, u = 1; 8 bits each in
/// steps of `MAX_DILATE_PX / 255`, rounded up): see `crack_dilation` in bound.wgsl and
/// docs/reyes.md. `cp` holds Euclidean points ([`to_euclidean`]) and `w` their weights (read
/// only if `rational`).
pub fn crack_dilation(
    f: &FrameUniforms,
    cp: &ControlNet,
    w: &Weights,
    rational: bool,
    nu: u32,
    nv: u32,
    zmin: f32,
) -> u32 {
    let slack = 2.0 * (1.0 + (f.width.max(f.height) as f32) / f.focal);
    pack_edges(nu, nv, |points, n| {
        let c2 = if rational {
            curve_c2_rational(points.map(|i| cp_h(cp, w, i)))
        } else {
            let b = points.map(|i| cp_point(cp, i));
            6.0 * (b[0] - 2.0 * b[1] + b[2])
                .length()
                .max((b[1] - 2.0 * b[2] + b[3]).length())
        };
        c2 / (8.0 * n * n) * f.focal / zmin * slack
    })
}

/// Packs a crack dilation: for each boundary edge `e` of a 4x4 control net (0: v = 0, 1: v = 1,
/// both along u; 2: u = 0, 3: u = 1, along v; `edge_start`, `edge_step` and `edge_segments` in
/// bound.wgsl), `px(points, n)` gets the edge's four control point indices and the grid's
/// segments along it and gives its dilation in pixels, packed in 8 bits rounded up to
/// [`MAX_DILATE_PX`] / 255 steps, at least one step, at most `MAX_DILATE_PX`
/// (`pack_edge_dilation`).
fn pack_edges(nu: u32, nv: u32, mut px: impl FnMut([usize; 4], f32) -> f32) -> u32 {
    (0..4).fold(0, |packed, e| {
        let along_u = e < 2;
        let start = match e {
            1 => 12,
            3 => 3,
            _ => 0,
        };
        let step = if along_u { 1 } else { 4 };
        let n = if along_u { nu } else { nv } as f32;
        let points = [0, 1, 2, 3].map(|k| start + k * step);
        let q = (px(points, n) * (255.0 / MAX_DILATE_PX))
            .ceil()
            .clamp(1.0, 255.0);
        packed | (q as u32) << (8 * e)
    })
}

/// `screen_crack_dilation` in bound.wgsl: the crack dilation of each boundary edge, packed as
/// [`crack_dilation`] packs it, from the boundary curves as they are on screen. `pts` holds the
/// control points projected (pixels) with their camera depths, all in front of the eye; `w`
/// their weights (1 for a polynomial patch). A perspective view of a rational curve with
/// points b_i and weights w_i is the rational curve with points project(b_i) and weights
/// w_i b_i.z, so [`curve_c2_rational`] bounds |C''| in pixels directly, and a chord over a
/// parameter step 1/n deviates at most |C''| / (8 n^2) pixels from it.
pub fn screen_crack_dilation(pts: &[(Vec2, f32)], w: &Weights, nu: u32, nv: u32) -> u32 {
    pack_edges(nu, nv, |points, n| {
        let c2 = curve_c2_rational(points.map(|i| {
            let (s, z) = pts[i];
            Vec4::new(s.x, s.y, 0.0, w[i] * z)
        }));
        c2 / (8.0 * n * n)
    })
}

/// `packed_min` in bound.wgsl: the smaller of two packed crack dilations, edge by edge.
pub fn packed_min(a: u32, b: u32) -> u32 {
    (0..4).fold(0, |m, e| {
        let s = 8 * e;
        m | ((a >> s) & 255).min((b >> s) & 255) << s
    })
}

/// An upper bound of |C''| on [0, 1] for the rational cubic with Euclidean control points and
/// weights `p[i] = (b_i, w_i)`, w_i > 0: `curve_c2_rational` in bound.wgsl, where the bound is
/// derived. Equal weights give 6 max|b_{i+2} - 2 b_{i+1} + b_i|, the polynomial bound.
pub fn curve_c2_rational(p: [Vec4; 4]) -> f32 {
    let [b0, b1, b2, b3] = p.map(|q| q.truncate());
    let w = Vec4::new(p[0].w, p[1].w, p[2].w, p[3].w);
    let wmin = w.x.min(w.y).min(w.z.min(w.w));
    let wmax = w.x.max(w.y).max(w.z.max(w.w));
    let d1 = (b1 - b0)
        .length()
        .max((b2 - b1).length())
        .max((b3 - b2).length());
    let d2 = (b0 - 2.0 * b1 + b2)
        .length()
        .max((b1 - 2.0 * b2 + b3).length());
    let r = d1.max(
        (b2 - b0)
            .length()
            .max((b3 - b1).length())
            .max((b3 - b0).length()),
    );
    let dw1 = (w.y - w.x)
        .abs()
        .max((w.z - w.y).abs())
        .max((w.w - w.z).abs());
    let dw2 = (w.z - w.x).abs().max((w.w - w.y).abs());
    let ddw = (w.x - 2.0 * w.y + w.z)
        .abs()
        .max((w.y - 2.0 * w.z + w.w).abs());
    (6.0 * (wmax * d2 + dw2 * d1 + ddw * r) + 18.0 * dw1 / wmin * (wmax * d1 + dw1 * r)) / wmin
}

/// `uvt_bound` in bound.wgsl: the screen bound (lo, hi) of the patch at shutter close (huge
/// when a point there reaches the near plane; empty when it does not move), its depth range
/// over the shutter, and the largest circle of confusion `c` over that range; the caller
/// grows the shutter-open bound by `c` and takes the union. `cp`: Euclidean points; `r`: the
/// displacement radius; (zmin, zmax): depths at shutter open.
pub fn uvt_bound(
    f: &FrameUniforms,
    cp: &ControlNet,
    info: &PatchInfo,
    table: &[[f32; 4]],
    r: f32,
    (zmin, zmax): (f32, f32),
) -> (Vec2, Vec2, (f32, f32), f32) {
    let (mut lo, mut hi) = (Vec2::splat(3.0e38), Vec2::splat(-3.0e38));
    let (mut z0, mut z1) = (zmin, zmax);
    if info.flags & PATCH_MOVING != 0 {
        let m = |k: usize| {
            let e = table[(info.motion as usize) + k];
            Vec3::new(e[0], e[1], e[2])
        };
        let r1 = r * (m(0).dot(m(0)) + m(1).dot(m(1)) + m(2).dot(m(2))).sqrt();
        let (mut g, mut near) = (0f32, false);
        for k in 0..16 {
            let q = moved_point(table, info.motion, cp_point(cp, k));
            z0 = z0.min(q.z - r1);
            z1 = z1.max(q.z + r1);
            if q.z - r1 < f.near {
                near = true;
                continue;
            }
            let s = Vec2::from(project(f, q));
            lo = lo.min(s);
            hi = hi.max(s);
            if r1 > 0.0 {
                g = g.max(q.length() / (q.z * (q.z - r1)));
            }
        }
        lo -= Vec2::splat(f.focal * r1 * g);
        hi += Vec2::splat(f.focal * r1 * g);
        if near {
            (lo, hi) = (Vec2::splat(-3.0e38), Vec2::splat(3.0e38));
        }
    }
    let zn = z0.max(f.near);
    let c = coc(f, zn).abs().max(coc(f, z1.max(zn)).abs());
    (lo - Vec2::splat(c), hi + Vec2::splat(c), (z0, z1), c)
}

#[cfg(test)]
mod backface_tests {
    use super::*;

    /// A patch from a function of the parameters, control points on a 4x4 grid of it.
    fn patch(mut f: impl FnMut(f32, f32) -> [f32; 3]) -> ControlNet {
        let mut cp = [0f32; 48];
        for j in 0..4 {
            for i in 0..4 {
                let p = f(i as f32 / 3.0, j as f32 / 3.0);
                super::super::set_cp_point(&mut cp, 4 * j + i, p.into());
            }
        }
        cp
    }

    /// det[P, Pu, Pv] at (u, v) in f64 of the (rational) patch with homogeneous net `cp`
    /// and weights `w`, from its exact derivatives.
    fn det_at(cp: &ControlNet, w: &Weights, u: f64, v: f64) -> f64 {
        let h = std::array::from_fn(|k| cp_h(cp, w, k).as_dvec4());
        let (p, pu, pv) = crate::reference::homogeneous::eval_rational(&h, u, v);
        p.dot(pu.cross(pv))
    }

    #[test]
    fn a_plane_is_culled_from_its_back_only() {
        // z = 5 plane; Pu = +x, Pv = +y, so det = P . z > 0: the back-face sign.
        let facing_away = patch(|u, v| [u - 0.5, v - 0.5, 5.0]);
        assert!(backfacing(&facing_away, false));
        assert!(!backfacing(&facing_away, true), "flipped, it faces the eye");
        // Seen edge-on (the plane contains the eye's line of sight): never culled.
        let edge_on = patch(|u, v| [0.0, v - 0.5, 4.0 + u]);
        assert!(!backfacing(&edge_on, false) && !backfacing(&edge_on, true));
    }

    #[test]
    fn a_patch_with_a_silhouette_is_never_culled() {
        // A U-shaped trough opening away from the eye: its sides are seen from the inside
        // near the ends and from the outside near the bottom, with silhouettes between.
        let half = patch(|u, v| {
            let i = (3.0 * u).round() as usize;
            [[-1.0, -1.0, 1.0, 1.0][i], v - 0.5, [6.0, 1.0, 1.0, 6.0][i]]
        });
        assert!(!backfacing(&half, false) && !backfacing(&half, true));
    }

    #[test]
    fn a_culled_patch_is_back_facing_at_every_point() {
        // Random bumpy patches near a plane at random attitudes, every other one rational
        // (weights in [0.7, 1], the test on its homogeneous net): whenever the test culls,
        // the exact det of the rational surface has the back sign on a dense parameter grid;
        // and it does cull some of each kind.
        let mut seed = 0x1234_5678u32;
        let mut rnd = || {
            seed = crate::stages::reyes_hash(seed);
            seed as f32 / u32::MAX as f32 - 0.5
        };
        let mut culled = [0; 2];
        for n in 0..800 {
            let (tilt, bump) = (rnd() * 3.0, rnd() * 0.8);
            let noise: Vec<f32> = (0..16).map(|_| rnd() * bump).collect();
            let mut cp = patch(|u, v| {
                let z = 4.0 + tilt * (u - 0.5);
                let k = (4.0 * (v * 3.0).round() + (u * 3.0).round()) as usize;
                [u - 0.5 + rnd() * 0.1, v - 0.5, z + noise[k]]
            });
            let rational = n % 2 == 1;
            let mut w = [1f32; 16];
            if rational {
                for (k, wk) in w.iter_mut().enumerate() {
                    *wk = 0.85 + rnd() * 0.3;
                    let p = cp_point(&cp, k) * *wk;
                    super::super::set_cp_point(&mut cp, k, p);
                }
            }
            for flip in [false, true] {
                if backfacing(&cp, flip) {
                    culled[rational as usize] += 1;
                    let sgn = if flip { -1.0 } else { 1.0 };
                    for j in 0..=32 {
                        for i in 0..=32 {
                            let d = det_at(&cp, &w, i as f64 / 32.0, j as f64 / 32.0);
                            assert!(sgn * d > 0.0, "culled but front-facing at ({i}, {j})");
                        }
                    }
                }
            }
        }
        assert!(
            culled.iter().all(|&c| c > 100),
            "only {culled:?} of 800 each culled: the test proves little"
        );
    }
}

#[cfg(test)]
mod crack_tests {
    use super::*;
    use glam::{DVec3, DVec4, Vec3};

    /// |C''(t)| of the rational cubic with homogeneous control points `h`, exactly (f64):
    /// C = X / w, C' = (X' - w' C) / w, C'' = (X'' - 2 w' C' - w'' C) / w.
    fn c2_at(h: &[DVec4; 4], t: f64) -> f64 {
        let s = 1.0 - t;
        let b = [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t];
        let d1 = [
            -3.0 * s * s,
            3.0 * s * s - 6.0 * t * s,
            6.0 * t * s - 3.0 * t * t,
            3.0 * t * t,
        ];
        let d2 = [6.0 * s, 6.0 * t - 12.0 * s, 6.0 * s - 12.0 * t, 6.0 * t];
        let sum = |w: [f64; 4]| (0..4).map(|i| h[i] * w[i]).sum::<DVec4>();
        let (x, x1, x2) = (sum(b), sum(d1), sum(d2));
        let c = x.truncate() / x.w;
        let c1 = (x1.truncate() - x1.w * c) / x.w;
        let c2: DVec3 = (x2.truncate() - 2.0 * x1.w * c1 - x2.w * c) / x.w;
        c2.length()
    }

    /// The rational crack bound holds: on random rational cubics (weights over two decades)
    /// it is at least the exact max |C''| on a dense grid, so chord errors max|C''| h^2 / 8 are
    /// covered; with equal weights it is the polynomial bound exactly.
    #[test]
    fn the_rational_second_derivative_bound_holds() {
        let mut seed = 0xdead_beefu32;
        let mut rnd = || {
            seed = crate::stages::reyes_hash(seed);
            seed as f32 / u32::MAX as f32
        };
        let mut worst_ratio = f64::INFINITY;
        for n in 0..2000 {
            let spread = [1.0, 4.0, 100.0][n % 3];
            let p: [Vec4; 4] = std::array::from_fn(|_| {
                let b = Vec3::new(rnd(), rnd(), rnd()) * 4.0 - 2.0;
                b.extend(1.0 + rnd() * (spread - 1.0))
            });
            let bound = curve_c2_rational(p) as f64;
            let h = p.map(|q| (q.truncate() * q.w).extend(q.w).as_dvec4());
            let exact = (0..=400)
                .map(|k| c2_at(&h, k as f64 / 400.0))
                .fold(0.0, f64::max);
            assert!(
                bound >= exact * (1.0 - 1e-5),
                "bound {bound} < {exact} for {p:?}"
            );
            worst_ratio = worst_ratio.min(bound / exact);
            // Equal weights: the polynomial bound.
            let eq = p.map(|q| q.truncate().extend(0.7));
            let [b0, b1, b2, b3] = eq.map(|q| q.truncate());
            let poly = 6.0
                * (b0 - 2.0 * b1 + b2)
                    .length()
                    .max((b1 - 2.0 * b2 + b3).length());
            assert!((curve_c2_rational(eq) - poly).abs() <= 1e-6 * poly);
        }
        eprintln!("tightest bound / exact max |C''|: {worst_ratio:.3}");
    }

    /// On the rational quarter circle (unit radius, degree-raised), the bound is within a
    /// small factor of the truth: dilation stays close to what the chord error needs.
    #[test]
    fn the_bound_is_not_loose_on_a_circular_arc() {
        let s = 0.5f64.sqrt();
        let q = [
            DVec4::new(1.0, 0.0, 0.0, 1.0),
            DVec4::new(s, s, 0.0, s),
            DVec4::new(0.0, 1.0, 0.0, 1.0),
        ];
        let h = [
            q[0],
            (q[0] + 2.0 * q[1]) / 3.0,
            (2.0 * q[1] + q[2]) / 3.0,
            q[2],
        ];
        let p = h.map(|x| (x.truncate() / x.w).extend(x.w).as_vec4());
        let bound = curve_c2_rational(p) as f64;
        let exact = (0..=400)
            .map(|k| c2_at(&h, k as f64 / 400.0))
            .fold(0.0, f64::max);
        eprintln!("quarter circle: bound {bound:.3}, exact max |C''| {exact:.3}");
        assert!(bound >= exact && bound < 6.0 * exact, "{bound} vs {exact}");
    }
}
