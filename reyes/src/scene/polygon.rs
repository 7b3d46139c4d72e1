//! Polygons as Reyes dices them: each planar polygon (with holes or not) becomes bilinear
//! patches that the ordinary Bound/Split/Dice path renders, elevated to bicubic Bezier form.
//!
//! - A convex polygon without holes: quads (v0, v_i, v_i+1, v_i+2) of a fan from its first
//!   vertex, one bilinear patch each, and a last triangle when the count is odd. A convex quad
//!   is one patch; a triangle is one degenerate bilinear patch whose (0,1)-(1,1) edge is
//!   collapsed onto its third vertex (the surface is then exactly the flat triangle, and a
//!   primitive variable given per vertex is interpolated barycentrically on it).
//! - Any other polygon (concave, or with holes): its loops are projected onto the plane of
//!   the outer loop's Newell normal, every hole is bridged to the outer loop (Eberly,
//!   "Triangulation by Ear Clipping", 2002, section 3) and the result is cut into triangles by
//!   ear clipping (same paper, section 2).
//!
//! Every piece keeps the polygon's edges whole (no new vertex is made), and the patch's
//! boundary control points of an edge are computed from its two end points in one canonical
//! order ([`bilinear_patch`]): two faces sharing an edge give its control points bit for bit
//! alike, whichever way round each face runs, so the same edge is evaluated identically from
//! both sides.
//!
//! Orientation: a piece's corners run in the polygon's own order, so the patch's dPdu x dPdv
//! is the polygon's winding normal (v1 - v0) x (v2 - v1); the reader applies RenderMan's
//! orientation rules to it exactly as to a patch.

use glam::{DVec2, DVec3};

/// One bilinear piece of a polygon: the polygon's corner numbers (counted through its loops
/// in order, outer loop first) at the patch's corners (0,0), (1,0), (0,1), (1,1). A triangle
/// repeats its third corner in the last two places.
pub(crate) type Piece = [usize; 4];

/// The pieces of a polygon whose loops (outer first, then holes) are `loops`, each at least 3
/// points. A polygon without area (every point on one line) gives no piece: it covers
/// nothing.
pub(crate) fn pieces(loops: &[&[DVec3]]) -> Vec<Piece> {
    let outer = loops[0];
    let normal = newell(outer);
    if !(normal.length_squared() > 0.0) {
        return Vec::new();
    }
    if loops.len() == 1 && convex(outer, normal) {
        return fan(outer.len());
    }
    // Project onto the plane: drop the normal's largest component, keep the outer loop
    // counter-clockwise in 2D.
    let axis = normal.abs().max_position();
    let (i, j) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let sign = if normal[axis] > 0.0 { 1.0 } else { -1.0 };
    let flat = |p: DVec3| DVec2::new(p[i] * sign, p[j]);
    let mut pts: Vec<DVec2> = Vec::new();
    let mut starts = Vec::new();
    for l in loops {
        starts.push(pts.len());
        pts.extend(l.iter().map(|p| flat(*p)));
    }
    let mut ring: Vec<usize> = (0..outer.len()).collect();
    if signed_area(&pts, &ring) < 0.0 {
        ring.reverse();
    }
    // Holes clockwise, bridged in order of their rightmost point (largest x first).
    let mut holes: Vec<Vec<usize>> = (1..loops.len())
        .map(|h| {
            let mut r: Vec<usize> = (starts[h]..starts[h] + loops[h].len()).collect();
            if signed_area(&pts, &r) > 0.0 {
                r.reverse();
            }
            r
        })
        .collect();
    holes.sort_by(|a, b| rightmost_x(&pts, b).total_cmp(&rightmost_x(&pts, a)));
    for (k, hole) in holes.iter().enumerate() {
        bridge(&pts, &mut ring, hole, &holes[k + 1..]);
    }
    let tris = ear_clip(&pts, ring);
    // Triangles in the polygon's own winding: ear clipping ran counter-clockwise in 2D,
    // which is the outer loop's order or its reverse.
    let reversed = {
        let fwd: Vec<usize> = (0..outer.len()).collect();
        signed_area(&pts, &fwd) < 0.0
    };
    tris.into_iter()
        .map(
            |[a, b, c]| {
                if reversed { [a, c, b, b] } else { [a, b, c, c] }
            },
        )
        .collect()
}

/// Newell's normal of a loop: its direction is the winding's, its length twice the area of
/// the loop projected onto the plane it spans.
pub(crate) fn newell(l: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for (k, p) in l.iter().enumerate() {
        let q = l[(k + 1) % l.len()];
        n += DVec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        );
    }
    n
}

/// True when every turn of the loop goes the way of `normal` (collinear points allowed).
fn convex(l: &[DVec3], normal: DVec3) -> bool {
    let n = l.len();
    let scale = normal.length();
    (0..n).all(|k| {
        let (a, b, c) = (l[k], l[(k + 1) % n], l[(k + 2) % n]);
        (b - a).cross(c - b).dot(normal) >= -1e-12 * scale * (b - a).length().max(1e-300)
    })
}

/// The fan of a convex loop of `n` points as quads, and a last triangle for odd `n`.
fn fan(n: usize) -> Vec<Piece> {
    let mut out = Vec::with_capacity(n / 2);
    let mut k = 1;
    while k + 2 < n {
        out.push([0, k, k + 2, k + 1]);
        k += 2;
    }
    if k + 1 < n {
        out.push([0, k, k + 1, k + 1]);
    }
    out
}

fn signed_area(pts: &[DVec2], ring: &[usize]) -> f64 {
    let mut a = 0.0;
    for (k, &i) in ring.iter().enumerate() {
        let (p, q) = (pts[i], pts[ring[(k + 1) % ring.len()]]);
        a += p.x * q.y - q.x * p.y;
    }
    0.5 * a
}

fn rightmost_x(pts: &[DVec2], ring: &[usize]) -> f64 {
    ring.iter().map(|&i| pts[i].x).fold(f64::MIN, f64::max)
}

fn cross2(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// True when segments ab and cd cross at a point inside both (touching ends do not count).
fn crosses(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let d1 = cross2(b - a, c - a);
    let d2 = cross2(b - a, d - a);
    let d3 = cross2(d - c, a - c);
    let d4 = cross2(d - c, b - c);
    ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
}

/// Joins `hole` into `ring` by two coincident edges from the hole's rightmost point to the
/// nearest ring point the bridge sees (crossing no edge of the ring, of the hole or of the
/// holes still to come).
fn bridge(pts: &[DVec2], ring: &mut Vec<usize>, hole: &[usize], later: &[Vec<usize>]) {
    let h = (0..hole.len())
        .max_by(|&a, &b| pts[hole[a]].x.total_cmp(&pts[hole[b]].x))
        .unwrap_or(0);
    let m = pts[hole[h]];
    let edges = |r: &[usize]| {
        (0..r.len())
            .map(|k| (r[k], r[(k + 1) % r.len()]))
            .collect::<Vec<_>>()
    };
    let mut all = edges(ring);
    all.extend(edges(hole));
    for l in later {
        all.extend(edges(l));
    }
    let visible = |k: usize| {
        let p = pts[ring[k]];
        !all.iter().any(|&(a, b)| crosses(m, p, pts[a], pts[b]))
    };
    let mut order: Vec<usize> = (0..ring.len()).collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (pts[ring[a]], pts[ring[b]]);
        // Prefer points to the right of m (Eberly's choice), then the nearest.
        (pa.x < m.x)
            .cmp(&(pb.x < m.x))
            .then(pa.distance_squared(m).total_cmp(&pb.distance_squared(m)))
    });
    let k = order
        .iter()
        .copied()
        .find(|&k| visible(k))
        .unwrap_or(order[0]);
    let mut joined = Vec::with_capacity(ring.len() + hole.len() + 2);
    joined.extend_from_slice(&ring[..=k]);
    joined.extend((0..=hole.len()).map(|s| hole[(h + s) % hole.len()]));
    joined.extend_from_slice(&ring[k..]);
    *ring = joined;
}

/// Ear clipping of a counter-clockwise ring (which may pass a bridge twice): triangles of
/// corner numbers, counter-clockwise. Where no ear is found (a self-intersecting or
/// degenerate ring) the flattest corner is cut anyway, so the loop always ends.
fn ear_clip(pts: &[DVec2], mut ring: Vec<usize>) -> Vec<[usize; 3]> {
    let mut out = Vec::with_capacity(ring.len().saturating_sub(2));
    let mut start = 0;
    while ring.len() > 3 {
        let n = ring.len();
        let mut cut = None;
        for s in 0..n {
            let k = (start + s) % n;
            let (a, b, c) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
            if is_ear(pts, &ring, a, b, c) {
                cut = Some(k);
                break;
            }
        }
        let k = cut.unwrap_or_else(|| {
            (0..n)
                .max_by(|&x, &y| turn(pts, &ring, x).total_cmp(&turn(pts, &ring, y)))
                .unwrap_or(0)
        });
        let (a, b, c) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
        if cross2(pts[b] - pts[a], pts[c] - pts[b]) != 0.0 {
            out.push([a, b, c]);
        }
        ring.remove(k);
        start = k % ring.len();
    }
    if ring.len() == 3 && cross2(pts[ring[1]] - pts[ring[0]], pts[ring[2]] - pts[ring[1]]) != 0.0 {
        out.push([ring[0], ring[1], ring[2]]);
    }
    out
}

/// The left turn at ring position k (positive: convex).
fn turn(pts: &[DVec2], ring: &[usize], k: usize) -> f64 {
    let n = ring.len();
    let (a, b, c) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
    cross2(pts[b] - pts[a], pts[c] - pts[b])
}

/// abc is convex and no other ring point lies inside it or on its boundary (points equal to
/// a, b or c, as bridges make, excepted).
fn is_ear(pts: &[DVec2], ring: &[usize], a: usize, b: usize, c: usize) -> bool {
    let (pa, pb, pc) = (pts[a], pts[b], pts[c]);
    if cross2(pb - pa, pc - pb) <= 0.0 {
        return false;
    }
    ring.iter().all(|&i| {
        let p = pts[i];
        if p == pa || p == pb || p == pc {
            return true;
        }
        let inside = cross2(pb - pa, p - pa) >= 0.0
            && cross2(pc - pb, p - pb) >= 0.0
            && cross2(pa - pc, p - pc) >= 0.0;
        !inside
    })
}

/// The bicubic Bezier form of the bilinear patch with corners `c` at (0,0), (1,0), (0,1),
/// (1,1). Each boundary edge's two inner control points come from its end points taken in
/// one canonical order (the lexicographically smaller first), so a neighbour running the
/// edge the other way computes the same numbers; the four inner points are the bilinear
/// map at (1/3, 2/3)². Exact: a bilinear patch is a bicubic one.
pub(crate) fn bilinear_patch(c: [DVec3; 4]) -> [DVec3; 16] {
    let mut cp: [DVec3; 16] = std::array::from_fn(|k| {
        let (u, v) = ((k % 4) as f64 / 3.0, (k / 4) as f64 / 3.0);
        c[0].lerp(c[1], u).lerp(c[2].lerp(c[3], u), v)
    });
    let edges = [
        (c[0], c[1], [0, 1, 2, 3]),
        (c[2], c[3], [12, 13, 14, 15]),
        (c[0], c[2], [0, 4, 8, 12]),
        (c[1], c[3], [3, 7, 11, 15]),
    ];
    for (p, q, at) in edges {
        let e = edge_points(p, q);
        for (k, i) in at.into_iter().enumerate() {
            cp[i] = e[k];
        }
    }
    cp
}

/// The cubic Bezier points of the straight edge from `p` to `q`, computed from the
/// lexicographically smaller end point so that `edge_points(q, p)` is the exact reverse.
pub(crate) fn edge_points(p: DVec3, q: DVec3) -> [DVec3; 4] {
    let swap = q.to_array() < p.to_array();
    let (a, b) = if swap { (q, p) } else { (p, q) };
    let third = |t: f64| a + (b - a) * t;
    let e = [a, third(1.0 / 3.0), third(2.0 / 3.0), b];
    if swap { [e[3], e[2], e[1], e[0]] } else { e }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area3(a: DVec3, b: DVec3, c: DVec3) -> f64 {
        0.5 * (b - a).cross(c - a).length()
    }

    /// The exact area of a piece: a bilinear patch's area by fine quadrature (these are
    /// planar, so the cross product's length is the Jacobian), a degenerate one's as a
    /// triangle.
    fn piece_area(l: &[DVec3], p: Piece) -> f64 {
        let c = p.map(|k| l[k]);
        if p[2] == p[3] {
            return area3(c[0], c[1], c[2]);
        }
        area3(c[0], c[1], c[3]) + area3(c[0], c[3], c[2])
    }

    fn flat(v: &[(f64, f64)]) -> Vec<DVec3> {
        v.iter().map(|&(x, y)| DVec3::new(x, y, 0.0)).collect()
    }

    #[test]
    fn convex_polygons_become_fan_quads_with_the_polygon_area() {
        for n in 3..9 {
            let l: Vec<DVec3> = (0..n)
                .map(|k| {
                    let t = std::f64::consts::TAU * k as f64 / n as f64;
                    DVec3::new(t.cos(), t.sin(), 0.5)
                })
                .collect();
            let ps = pieces(&[&l]);
            assert_eq!(ps.len(), (n - 1) / 2, "n = {n}");
            let area: f64 = ps.iter().map(|p| piece_area(&l, *p)).sum();
            let exact = 0.5 * n as f64 * (std::f64::consts::TAU / n as f64).sin();
            assert!((area - exact).abs() < 1e-12, "n = {n}: {area} vs {exact}");
            // Same winding as the polygon (+z).
            for p in ps {
                let cp = bilinear_patch(p.map(|k| l[k]));
                let (_, du, dv) = crate::scene::eval_bezier(&cp, 0.3, 0.3);
                assert!(du.cross(dv).z > 0.0);
            }
        }
    }

    #[test]
    fn concave_polygon_is_ear_clipped_to_its_area() {
        // An L shape (area 3), both windings.
        let mut v = vec![
            (0.0, 0.0),
            (2.0, 0.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (0.0, 2.0),
        ];
        for _ in 0..2 {
            let l = flat(&v);
            let ps = pieces(&[&l]);
            assert_eq!(ps.len(), 4);
            let area: f64 = ps.iter().map(|p| piece_area(&l, *p)).sum();
            assert!((area - 3.0).abs() < 1e-12, "{area}");
            let wind = newell(&l).z.signum();
            for p in ps {
                let c = p.map(|k| l[k]);
                assert_eq!((c[1] - c[0]).cross(c[2] - c[1]).z.signum(), wind);
            }
            v.reverse();
        }
    }

    #[test]
    fn holes_are_cut_out() {
        // A 4x4 square with two 1x1 holes: area 14.
        let outer = flat(&[(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0)]);
        let h1 = flat(&[(1.0, 1.0), (2.0, 1.0), (2.0, 2.0), (1.0, 2.0)]);
        let h2 = flat(&[(2.5, 2.5), (2.5, 3.5), (3.5, 3.5), (3.5, 2.5)]);
        let loops: Vec<&[DVec3]> = vec![&outer, &h1, &h2];
        let all: Vec<DVec3> = [outer.clone(), h1.clone(), h2.clone()].concat();
        let ps = pieces(&loops);
        let area: f64 = ps.iter().map(|p| piece_area(&all, *p)).sum();
        assert!((area - 14.0).abs() < 1e-12, "{area}");
        // No triangle covers a hole's centre.
        for c in [DVec2::new(1.5, 1.5), DVec2::new(3.0, 3.0)] {
            for p in &ps {
                let t = [all[p[0]], all[p[1]], all[p[2]]].map(|q| q.truncate());
                let inside = (0..3).all(|k| cross2(t[(k + 1) % 3] - t[k], c - t[k]) > 0.0);
                assert!(!inside, "{p:?} covers the hole at {c}");
            }
        }
    }

    #[test]
    fn degenerate_polygon_covers_nothing() {
        let l = flat(&[(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)]);
        assert!(pieces(&[&l]).is_empty());
    }

    #[test]
    fn shared_edges_get_identical_control_points_both_ways() {
        let (a, b) = (DVec3::new(0.1, 0.7, 3.3), DVec3::new(-1.9, 0.35, 2.1));
        let e = edge_points(a, b);
        let mut r = edge_points(b, a);
        r.reverse();
        assert_eq!(e, r);
        // Two quads on either side of edge ab, running it opposite ways.
        let p = bilinear_patch([a, b, DVec3::new(0.0, 2.0, 3.0), DVec3::new(-2.0, 2.0, 2.0)]);
        let q = bilinear_patch([
            b,
            a,
            DVec3::new(-2.0, -1.0, 2.0),
            DVec3::new(0.0, -1.0, 3.0),
        ]);
        assert_eq!([p[0], p[1], p[2], p[3]], [q[3], q[2], q[1], q[0]]);
    }
}
