//! Twin of `shaders/reyes/bound.wgsl`: screen bound, culling, and the split-or-dice decision.

use super::{cp_point, project};
use crate::frame::{Frame, PatchInfo, PatchItem};
use glam::Vec2;

/// See `MAX_DILATE_PX` and `CULL_MARGIN_PX` in common.wgsl: bucketed renders stay exact.
pub const MAX_DILATE_PX: f32 = 2.0;
pub const CULL_MARGIN_PX: f32 = 3.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cull {
    /// Wholly in front of the near plane or behind the far plane.
    Clip,
    /// Nothing of it (in front of the near plane) reaches the bucket.
    Offscreen,
    /// Back-facing at every point (one-sided surfaces only).
    Backface,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Decision {
    Cull(Cull),
    /// Split along u (else v); `eye` marks a near-plane split (the item's count is already raised).
    Split {
        along_u: bool,
        item: PatchItem,
        eye: bool,
    },
    /// Dice with the rates and dilation filled in; `depth_limited` when it wanted another split.
    /// A grid still crossing the near plane has [`super::NEAR_CLIP_GRID`] set in its rates.
    Dice {
        item: PatchItem,
        depth_limited: bool,
    },
}

pub fn bound(item: &PatchItem, f: &Frame, info: &PatchInfo) -> Decision {
    let cp = &item.cp;
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
    let zmin = pts.iter().map(|p| p.1).fold(pts[0].1, f32::min);
    let zmax = pts.iter().map(|p| p.1).fold(pts[0].1, f32::max);
    if zmax < f.near || zmin > f.far {
        return Decision::Cull(Cull::Clip);
    }
    if info.flags & 2 == 0 && backfacing(cp, info.flags & 1 != 0) {
        return Decision::Cull(Cull::Backface);
    }
    let depth = item.splits();
    let t0 = Vec2::new(f.tile_x0 as f32, f.tile_y0 as f32) - CULL_MARGIN_PX;
    let t1 =
        Vec2::new((f.tile_x0 + f.tile_w) as f32, (f.tile_y0 + f.tile_h) as f32) + CULL_MARGIN_PX;
    let misses = |lo: Vec2, hi: Vec2| hi.x < t0.x || hi.y < t0.y || lo.x > t1.x || lo.y > t1.y;
    if zmin < f.near {
        let (lo, hi) = near_visible_bound(f, cp);
        if misses(lo, hi) {
            return Decision::Cull(Cull::Offscreen);
        }
        // The image, not the bucket: see bound.wgsl.
        let image = Vec2::new(f.width as f32, f.height as f32) + CULL_MARGIN_PX;
        let seen = hi.min(image) - lo.max(Vec2::splat(-CULL_MARGIN_PX));
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
            crack_dilation(f, cp, f.grid_max, f.grid_max, zfront.fold(zmax, f32::min))
        } else {
            0
        };
        return Decision::Dice {
            item: g,
            depth_limited: false,
        };
    }
    let lo = pts.iter().fold(pts[0].0, |a, p| a.min(p.0));
    let hi = pts.iter().fold(pts[0].0, |a, p| a.max(p.0));
    if misses(lo, hi) {
        return Decision::Cull(Cull::Offscreen);
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
    let (split, nu, nv) = dice_decision(f, lu, lv, hi - lo);
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
        crack_dilation(f, cp, nu, nv, zmin)
    } else {
        0
    };
    Decision::Dice {
        item: g,
        depth_limited: split != 0,
    }
}

/// Screen bound (lo, hi) of the part of the patch in front of the near plane: the projections
/// of the front control points and of the crossings of the near plane by segments from a front
/// to a behind control point (`near_visible_bound` in bound.wgsl gives the argument).
pub fn near_visible_bound(f: &Frame, cp: &[f32; 48]) -> (Vec2, Vec2) {
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
/// proof is there), all 144 pairs at once.
pub fn backfacing(cp: &[f32; 48], flip: bool) -> bool {
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
fn polygon_length(cp: &[f32; 48], step: usize, across: usize) -> f32 {
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
fn dice_decision(f: &Frame, lu: f32, lv: f32, extent: Vec2) -> (u32, u32, u32) {
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
/// docs/reyes.md.
pub fn crack_dilation(f: &Frame, cp: &[f32; 48], nu: u32, nv: u32, zmin: f32) -> u32 {
    let slack = 2.0 * (1.0 + (f.width.max(f.height) as f32) / f.focal);
    let mut packed = 0;
    for e in 0..4 {
        let along_u = e < 2;
        let start = if along_u {
            if e == 1 { 12 } else { 0 }
        } else if e == 3 {
            3
        } else {
            0
        };
        let step = if along_u { 1 } else { 4 };
        let n = if along_u { nu } else { nv } as f32;
        let b: Vec<_> = (0..4).map(|k| cp_point(cp, start + k * step)).collect();
        let c2 = 6.0
            * (b[0] - 2.0 * b[1] + b[2])
                .length()
                .max((b[1] - 2.0 * b[2] + b[3]).length());
        let px = c2 / (8.0 * n * n) * f.focal / zmin * slack;
        let q = (px * (255.0 / MAX_DILATE_PX)).ceil().clamp(1.0, 255.0);
        packed |= (q as u32) << (8 * e);
    }
    packed
}

#[cfg(test)]
mod backface_tests {
    use super::*;
    use glam::DVec3;

    /// A patch from a function of the parameters, control points on a 4x4 grid of it.
    fn patch(mut f: impl FnMut(f32, f32) -> [f32; 3]) -> [f32; 48] {
        let mut cp = [0f32; 48];
        for j in 0..4 {
            for i in 0..4 {
                let p = f(i as f32 / 3.0, j as f32 / 3.0);
                cp[3 * (4 * j + i)..3 * (4 * j + i) + 3].copy_from_slice(&p);
            }
        }
        cp
    }

    /// det[P, Pu, Pv] at (u, v) in f64, from the Bernstein form.
    fn det_at(cp: &[f32; 48], u: f64, v: f64) -> f64 {
        let b = |t: f64| {
            [
                (1. - t).powi(3),
                3. * t * (1. - t).powi(2),
                3. * t * t * (1. - t),
                t.powi(3),
            ]
        };
        let db = |t: f64| {
            [
                -3. * (1. - t).powi(2),
                3. * (1. - t).powi(2) - 6. * t * (1. - t),
                6. * t * (1. - t) - 3. * t * t,
                3. * t * t,
            ]
        };
        let (bu, bv, du, dv) = (b(u), b(v), db(u), db(v));
        let (mut p, mut pu, mut pv) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for j in 0..4 {
            for i in 0..4 {
                let c = cp_point(cp, 4 * j + i).as_dvec3();
                p += c * bu[i] * bv[j];
                pu += c * du[i] * bv[j];
                pv += c * bu[i] * dv[j];
            }
        }
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
        // Random bumpy patches near a plane at random attitudes: whenever the test culls, the
        // exact det has the back sign on a dense parameter grid; and it does cull some.
        let mut seed = 0x1234_5678u32;
        let mut rnd = || {
            seed = crate::stages::reyes_hash(seed);
            seed as f32 / u32::MAX as f32 - 0.5
        };
        let mut culled = 0;
        for _ in 0..400 {
            let (tilt, bump) = (rnd() * 3.0, rnd() * 0.8);
            let noise: Vec<f32> = (0..16).map(|_| rnd() * bump).collect();
            let cp = patch(|u, v| {
                let z = 4.0 + tilt * (u - 0.5);
                let k = (4.0 * (v * 3.0).round() + (u * 3.0).round()) as usize;
                [u - 0.5 + rnd() * 0.1, v - 0.5, z + noise[k]]
            });
            for flip in [false, true] {
                if backfacing(&cp, flip) {
                    culled += 1;
                    let sgn = if flip { -1.0 } else { 1.0 };
                    for j in 0..=32 {
                        for i in 0..=32 {
                            let d = det_at(&cp, i as f64 / 32.0, j as f64 / 32.0);
                            assert!(sgn * d > 0.0, "culled but front-facing at ({i}, {j})");
                        }
                    }
                }
            }
        }
        assert!(
            culled > 100,
            "only {culled} of 800 culled: the test proves little"
        );
    }
}
