//! Limit-surface stencils at the vertices of a quad mesh and the bicubic patches built from
//! them.
//!
//! - Positions: Halstead, Kass & DeRose 1993 ("Efficient, fair interpolation using
//!   Catmull-Clark surfaces", appendix A): a smooth interior vertex of valence n goes to
//!   (n² v + 4 Σ e_i + Σ d_i) / (n (n + 5)) (e_i its edge neighbours, d_i the face
//!   diagonals); a crease vertex to the cubic B-spline limit (a + 4 v + b) / 6 of its crease;
//!   a corner stays.
//! - Tangents: Halstead et al.'s tangent masks, t_k = Σ A_n cos(2π(i-k)/n) e_i +
//!   (cos(2π(i-k)/n) + cos(2π(i-k+1)/n)) d_i with A_n = 1 + cos(2π/n) + cos(π/n)
//!   sqrt(2 (9 + cos(2π/n))), the derivative along edge k. Their length is scaled so that a
//!   planar, evenly spaced vertex of any valence gets Bezier edge points at a third of its
//!   edges; for valence 4 that scale is 1/36, and the point is exactly the bicubic B-spline
//!   patch's. Along a crease the B-spline curve's derivative (b - a)/2; across it, the
//!   derivative of the B-spline patch with the boundary's ghost row (2 P0 - P1): exact for a
//!   regular boundary.
//! - [`approximate_patch`]: the bicubic Bezier patch of a quad from those corner positions,
//!   edge points and interior points (n v + 2 e_k + 2 e_k+1 + d_k) / (n + 5) (the interior
//!   points of Loop & Schaefer 2008, "Approximating Catmull-Clark subdivision surfaces with
//!   bicubic patches"): it interpolates the limit position and tangent plane at its corners,
//!   and neighbours share their edge curves bit for bit (each edge point is a function of
//!   the vertex and the edge only, computed in the vertex's canonical ring order), so the
//!   patches are watertight. Where all four corners are regular it is the exact B-spline
//!   patch; elsewhere it approximates the limit surface (error measured in the tests).

use super::refine::{Stencil, VertexRule, vertex_rule};
use super::topology::{Mesh, Ring, Topology};
use glam::DVec3;
use std::f64::consts::PI;

/// The limit stencils of one vertex: its limit position, and the Bezier edge-point offset
/// (a third of the limit derivative along the edge, in the parameter of one face) toward
/// each edge neighbour, looked up by [`VertexLimit::offset`].
pub struct VertexLimit {
    /// Limit position stencil.
    pub position: Stencil,
    /// (edge neighbour, offset stencil).
    pub offsets: Vec<(u32, Stencil)>,
    /// The canonical ring, when the vertex is smooth, interior and all its faces are quads.
    ring: Option<Ring>,
}

impl VertexLimit {
    /// The offset stencil toward neighbour `w`.
    pub fn offset(&self, w: u32) -> Option<&Stencil> {
        self.offsets.iter().find(|o| o.0 == w).map(|o| &o.1)
    }
}

/// Halstead's A_n.
fn a_n(n: f64) -> f64 {
    let c = (2.0 * PI / n).cos();
    1.0 + c + (PI / n).cos() * (2.0 * (9.0 + c)).sqrt()
}

/// The smooth limit position stencil of the ring's centre `v`.
fn smooth_position(v: u32, r: &Ring) -> Stencil {
    let n = r.edge.len() as f64;
    let d = n * (n + 5.0);
    let mut s = vec![(v, n * n / d)];
    s.extend(r.edge.iter().map(|&e| (e, 4.0 / d)));
    s.extend(r.diag.iter().map(|&e| (e, 1.0 / d)));
    s
}

/// The smooth offset stencil toward ring edge `k` (see the module doc for the scale).
fn smooth_offset(r: &Ring, k: usize) -> Stencil {
    let n = r.edge.len();
    let nf = n as f64;
    let a = a_n(nf);
    let scale = 1.0 / (3.0 * (nf * a / 2.0 + nf * (1.0 + (2.0 * PI / nf).cos())));
    let mut s = Vec::with_capacity(2 * n);
    for i in 0..n {
        let ang = |j: usize| (2.0 * PI * ((j + n - k) % n) as f64 / nf).cos();
        s.push((r.edge[i], scale * a * ang(i)));
        s.push((r.diag[i], scale * (ang(i) + ang(i + 1))));
    }
    s
}

fn axpy(out: &mut Stencil, s: &Stencil, w: f64) {
    out.extend(s.iter().map(|&(i, x)| (i, x * w)));
}

/// The limit stencils of vertex `v` of a quad mesh. Sharp rules apply where the remaining
/// sharpness is at least 1/2, smooth ones below (an approximation of the semi-sharp blend
/// at the last level, where it matters least).
pub fn vertex_limit(mesh: &Mesh, topo: &Topology, v: u32) -> VertexLimit {
    let ring = topo.canonical_ring(mesh, v);
    let neighbours: Vec<u32> = topo.vertex_edges[v as usize]
        .iter()
        .map(|&e| {
            let (a, b) = topo.edges[e as usize];
            if a == v { b } else { a }
        })
        .collect();
    let rule = match vertex_rule(mesh, topo, v) {
        VertexRule::Crease(_, _, w) | VertexRule::Corner(w) if w < 0.5 && ring.is_some() => {
            VertexRule::Smooth
        }
        VertexRule::Smooth if ring.is_none() => VertexRule::Corner(1.0),
        r => r,
    };
    let position: Stencil = match rule {
        VertexRule::Smooth => smooth_position(v, ring.as_ref().expect("smooth has a ring")),
        VertexRule::Crease(a, b, _) => vec![(a, 1.0 / 6.0), (v, 4.0 / 6.0), (b, 1.0 / 6.0)],
        VertexRule::Corner(_) => vec![(v, 1.0)],
    };
    let offsets = neighbours
        .iter()
        .map(|&w| {
            let s = match rule {
                VertexRule::Smooth => {
                    let r = ring.as_ref().expect("smooth has a ring");
                    let k = r.edge.iter().position(|&x| x == w).expect("ring neighbour");
                    smooth_offset(r, k)
                }
                VertexRule::Crease(a, b, _) if w == a || w == b => {
                    let other = if w == a { b } else { a };
                    vec![(w, 1.0 / 6.0), (other, -1.0 / 6.0)]
                }
                VertexRule::Crease(..) => cross_offset(mesh, topo, v, w, &position),
                VertexRule::Corner(_) => vec![(w, 1.0 / 3.0), (v, -1.0 / 3.0)],
            };
            (w, s)
        })
        .collect();
    VertexLimit {
        position,
        offsets,
        ring: match rule {
            VertexRule::Smooth => ring,
            _ => None,
        },
    }
}

/// Offset across a crease, from crease vertex `v` toward `w`: a third of the ghost-row
/// derivative ((x + 4 w + x')/6 - limit(v)), x and x' the neighbours of w in the two faces
/// on the edge v-w.
fn cross_offset(mesh: &Mesh, topo: &Topology, v: u32, w: u32, limit: &Stencil) -> Stencil {
    let (Some((f0, k0)), Some((f1, k1))) = (topo.directed(v, w), topo.directed(w, v)) else {
        return vec![(w, 1.0 / 3.0), (v, -1.0 / 3.0)];
    };
    let (a, b) = (&mesh.faces[f0 as usize], &mesh.faces[f1 as usize]);
    let x = a[(k0 as usize + 2) % a.len()];
    let x1 = b[(k1 as usize + b.len() - 1) % b.len()];
    let mut s = vec![(x, 1.0 / 18.0), (w, 4.0 / 18.0), (x1, 1.0 / 18.0)];
    axpy(&mut s, limit, -1.0 / 3.0);
    s
}

/// Interior Bezier point next to corner `v` of quad `face` (at position `k`).
fn interior(lim: &VertexLimit, face: &[u32], k: usize) -> Stencil {
    let (v, next, diag, prev) = (
        face[k],
        face[(k + 1) % 4],
        face[(k + 2) % 4],
        face[(k + 3) % 4],
    );
    if let Some(r) = &lim.ring {
        let n = r.edge.len() as f64;
        let d = n + 5.0;
        return vec![
            (v, n / d),
            (next, 2.0 / d),
            (prev, 2.0 / d),
            (diag, 1.0 / d),
        ];
    }
    let mut s = lim.position.clone();
    axpy(&mut s, lim.offset(next).expect("face neighbour"), 1.0);
    axpy(&mut s, lim.offset(prev).expect("face neighbour"), 1.0);
    s
}

/// The approximating bicubic patch of quad `f` (see the module doc) as 16 values of each
/// channel, cp[4*v + u], u along the face's first edge. `limits[v]` are the vertex limits,
/// `values[v]` a channel's limit positions and `offset` the channel's edge-point offsets
/// (both evaluated once per vertex, so that neighbouring patches agree bit for bit).
pub fn approximate_patch(
    mesh: &Mesh,
    f: usize,
    limits: &[Option<VertexLimit>],
    eval: &dyn Fn(&Stencil) -> DVec3,
    position: &dyn Fn(u32) -> DVec3,
    offset: &dyn Fn(u32, u32) -> DVec3,
) -> [DVec3; 16] {
    let face = &mesh.faces[f];
    let c = [face[0], face[1], face[2], face[3]];
    let edge = |a: u32, b: u32| position(a) + offset(a, b);
    let inner = |k: usize| {
        let lim = limits[c[k] as usize]
            .as_ref()
            .expect("limit of a used vertex");
        eval(&interior(lim, face, k))
    };
    [
        position(c[0]),
        edge(c[0], c[1]),
        edge(c[1], c[0]),
        position(c[1]),
        edge(c[0], c[3]),
        inner(0),
        inner(1),
        edge(c[1], c[2]),
        edge(c[3], c[0]),
        inner(3),
        inner(2),
        edge(c[2], c[1]),
        position(c[3]),
        edge(c[3], c[2]),
        edge(c[2], c[3]),
        position(c[2]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn valence_four_scale_is_the_b_spline_one() {
        assert!((a_n(4.0) - 4.0).abs() < 1e-14);
        let r = Ring {
            edge: vec![1, 2, 3, 4],
            diag: vec![5, 6, 7, 8],
        };
        // b10 - b00 of a bicubic B-spline patch: (4 (e0 - e2) + d0 + d3 - d1 - d2) / 36.
        let s = smooth_offset(&r, 0);
        let want = [
            (1, 4.0),
            (3, -4.0),
            (5, 1.0),
            (8, 1.0),
            (6, -1.0),
            (7, -1.0),
        ];
        for (i, w) in want {
            let got: f64 = s.iter().filter(|x| x.0 == i).map(|x| x.1).sum();
            assert!((got - w / 36.0).abs() < 1e-15, "{i}: {got}");
        }
    }
}
