//! Twin of `shaders/reyes/trim.wgsl`: trimming (`TrimCurve`) in the stages. Bound classifies
//! an item's parameter rectangle against its patch's trim loops ([`classify`]): wholly
//! outside, it is culled; wholly inside, it is marked [`TRIM_INSIDE`] and nothing below it
//! tests again; crossing a loop, DiceShade drops each micropolygon whose centre is not kept
//! ([`keeps`]). The table layout is [`crate::frame::trim_ref`]'s.

use crate::frame::{PATCH_TRIMMED, PatchInfo, PatchItem, TRIM_SHIFT};
use glam::Vec2;

/// Bit of `PatchItem::depth` (`TRIM_INSIDE` in trim.wgsl): Bound found the item's parameter
/// rectangle wholly inside the kept region, so it and its pieces are drawn untrimmed.
pub const TRIM_INSIDE: u32 = 0x10000;

/// [`classify`]: the rectangle lies wholly where the surface is cut away.
pub const TRIM_OUT: u32 = 0;
/// [`classify`]: the rectangle lies wholly where the surface is kept.
pub const TRIM_IN: u32 = 1;
/// [`classify`]: a loop's edge touches the rectangle.
pub const TRIM_CROSSING: u32 = 2;

/// True when `item` still needs trimming tests: its patch is trimmed and Bound has not found
/// it wholly inside.
pub fn needs_trim(item: &PatchItem, info: &PatchInfo) -> bool {
    info.flags & PATCH_TRIMMED != 0 && item.depth & TRIM_INSIDE == 0
}

/// `trim_header` in trim.wgsl: the entry of the patch's trim header.
pub fn header(info: &PatchInfo) -> usize {
    (info.flags >> TRIM_SHIFT) as usize
}

/// `trim_param` in trim.wgsl: (u, v) of the original patch in the surface's parameter space.
pub fn param(table: &[[f32; 4]], h: usize, u: f32, v: f32) -> Vec2 {
    let m = table[h];
    Vec2::new(m[0] + m[1] * u, m[2] + m[3] * v)
}

/// `trim_odd` in trim.wgsl: the even-odd rule in f32 (`TrimLoops::contains` in f64).
fn odd(table: &[[f32; 4]], h: usize, p: Vec2) -> bool {
    let e = table[h + 1];
    let (at, n) = (e[0].to_bits() as usize, e[1].to_bits() as usize);
    let mut odd = false;
    for g in &table[at..at + n] {
        if (g[1] > p.y) != (g[3] > p.y) {
            let x = g[0] + (p.y - g[1]) / (g[3] - g[1]) * (g[2] - g[0]);
            if p.x < x {
                odd = !odd;
            }
        }
    }
    odd
}

/// `trim_keeps` in trim.wgsl: whether the surface is kept at (u, v) of the original patch.
pub fn keeps(table: &[[f32; 4]], h: usize, u: f32, v: f32) -> bool {
    let outside = table[h + 1][2].to_bits() != 0;
    odd(table, h, param(table, h, u, v)) != outside
}

/// `trim_classify` in trim.wgsl: the item's parameter rectangle `uv` (u0, u1, v0, v1 of the
/// original patch) against the loops: [`TRIM_CROSSING`] when some edge meets the rectangle
/// grown by 1e-5 of its size (a separating-axis test: the edge's box against the rectangle,
/// then the rectangle's corners against the edge's line), else [`TRIM_IN`] or [`TRIM_OUT`]
/// by its centre.
pub fn classify(table: &[[f32; 4]], h: usize, uv: [f32; 4]) -> u32 {
    let a = param(table, h, uv[0], uv[2]);
    let b = param(table, h, uv[1], uv[3]);
    let g = (b - a) * 1.0e-5;
    let lo = a - g;
    let hi = b + g;
    let e = table[h + 1];
    let (at, n) = (e[0].to_bits() as usize, e[1].to_bits() as usize);
    for s in &table[at..at + n] {
        let (p, q) = (Vec2::new(s[0], s[1]), Vec2::new(s[2], s[3]));
        if p.x.max(q.x) < lo.x || p.x.min(q.x) > hi.x || p.y.max(q.y) < lo.y || p.y.min(q.y) > hi.y
        {
            continue;
        }
        let d = q - p;
        let side = |c: Vec2| d.x * (c.y - p.y) - d.y * (c.x - p.x);
        let s0 = side(lo);
        let s1 = side(Vec2::new(hi.x, lo.y));
        let s2 = side(hi);
        let s3 = side(Vec2::new(lo.x, hi.y));
        let all_pos = s0 > 0.0 && s1 > 0.0 && s2 > 0.0 && s3 > 0.0;
        let all_neg = s0 < 0.0 && s1 < 0.0 && s2 < 0.0 && s3 < 0.0;
        if !all_pos && !all_neg {
            return TRIM_CROSSING;
        }
    }
    let c = (a + b) * 0.5;
    let outside = e[2].to_bits() != 0;
    if odd(table, h, c) != outside {
        TRIM_IN
    } else {
        TRIM_OUT
    }
}
