//! Twin of `shaders/reyes/split.wgsl`: de Casteljau halves at the parameter midpoint, on the
//! item's xyz (the points, or a rational patch's homogeneous x w, y w, z w, which split
//! linearly too; its weights follow from the child's uv).

use super::{cp_point, set_cp_point};
use crate::frame::PatchItem;
use glam::Vec3;

/// Half `second` of the cubic p0..p3 at t = 1/2 (symmetric: a shared curve splits to the same
/// bits).
pub fn half_curve(p: [Vec3; 4], second: bool) -> [Vec3; 4] {
    let a = (p[0] + p[1]) * 0.5;
    let b = (p[1] + p[2]) * 0.5;
    let c = (p[2] + p[3]) * 0.5;
    let d = (a + b) * 0.5;
    let e = (b + c) * 0.5;
    let m = (d + e) * 0.5;
    if second {
        [m, e, c, p[3]]
    } else {
        [p[0], a, d, m]
    }
}

/// Half `second` of `item` along u (else v), with its parameter range and one more split.
pub fn split_half(item: &PatchItem, along_u: bool, second: bool) -> PatchItem {
    let mut child = *item;
    let (step, across) = if along_u { (1, 4) } else { (4, 1) };
    for r in 0..4 {
        let o = r * across;
        let row = [0, 1, 2, 3].map(|i| cp_point(&item.cp, o + i * step));
        for (i, p) in half_curve(row, second).into_iter().enumerate() {
            set_cp_point(&mut child.cp, o + i * step, p);
        }
    }
    let (lo, hi) = if along_u { (0, 1) } else { (2, 3) };
    let m = (item.uv[lo] + item.uv[hi]) * 0.5;
    if second {
        child.uv[lo] = m
    } else {
        child.uv[hi] = m
    }
    child.depth = item.depth + 1;
    child
}
