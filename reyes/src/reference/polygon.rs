//! Exact planar and clipping helpers of the coverage reference (`exact`): boxes, a curve's
//! deviation from its chord, clipping a loop against a z plane, and the non-zero winding test.
//! Each is written so that a segment and its reverse give the same (or negated) numbers, which
//! keeps the coverage of cells sharing an edge watertight.

use glam::{DVec2, DVec3};

/// Axis-aligned box of a point set.
pub(super) fn bounds(q: &[DVec2]) -> (DVec2, DVec2) {
    q.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

/// Lexicographic order on points, used to make computations independent of direction.
fn before(a: DVec2, b: DVec2) -> bool {
    (a.x, a.y) <= (b.x, b.y)
}

/// Distance from `p` to segment `ab`, computed identically for `ab` and `ba`.
fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let (a, b) = if before(a, b) { (a, b) } else { (b, a) };
    let d = b - a;
    let l2 = d.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + d * t)
}

/// How far a projected cubic's inner control points stray from its chord: the curve lies
/// within this distance of the chord (hull property). Symmetric under reversal.
pub(super) fn curve_deviation(q: &[DVec2; 4]) -> f64 {
    segment_distance(q[1], q[0], q[3]).max(segment_distance(q[2], q[0], q[3]))
}

/// Point where segment ab meets the plane z = `plane`, computed from the endpoint with the
/// smaller z so that ab and ba give the same point.
pub(super) fn cut_at_z(a: DVec3, b: DVec3, plane: f64) -> DVec3 {
    let (a, b) = if (a.z, a.x, a.y) <= (b.z, b.x, b.y) {
        (a, b)
    } else {
        (b, a)
    };
    let t = (plane - a.z) / (b.z - a.z);
    let p = a + (b - a) * t;
    DVec3::new(p.x, p.y, plane)
}

/// Sutherland-Hodgman: the part of a closed 3D loop with z >= plane (`keep_above`) or
/// z <= plane.
pub(super) fn clip_z(poly: &[DVec3], plane: f64, keep_above: bool) -> Vec<DVec3> {
    let inside = |p: &DVec3| {
        if keep_above {
            p.z >= plane
        } else {
            p.z <= plane
        }
    };
    let mut out = Vec::with_capacity(poly.len() + 2);
    for (k, &a) in poly.iter().enumerate() {
        let b = poly[(k + 1) % poly.len()];
        if inside(&a) {
            out.push(a);
        }
        if inside(&a) != inside(&b) {
            out.push(cut_at_z(a, b, plane));
        }
    }
    out
}

/// Sign of (b - a) x (s - a), computed identically (negated) for the reversed segment.
fn side(a: DVec2, b: DVec2, s: DVec2) -> f64 {
    if before(a, b) {
        (b - a).perp_dot(s - a)
    } else {
        -(a - b).perp_dot(s - b)
    }
}

/// Non-zero winding test of `s` against a closed polygon, points on the boundary included.
/// Segment contributions are exact negatives for a segment and its reverse, so polygons that
/// share edges tile the plane without gaps.
pub(super) fn covers(poly: &[DVec2], s: DVec2) -> bool {
    let mut winding = 0i32;
    for (k, &a) in poly.iter().enumerate() {
        let b = poly[(k + 1) % poly.len()];
        let d = side(a, b, s);
        if d == 0.0 && s.cmpge(a.min(b)).all() && s.cmple(a.max(b)).all() {
            return true;
        }
        if a.y <= s.y {
            if b.y > s.y && d > 0.0 {
                winding += 1;
            }
        } else if b.y <= s.y && d < 0.0 {
            winding -= 1;
        }
    }
    winding != 0
}
