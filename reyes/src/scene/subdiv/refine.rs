//! One Catmull-Clark step (Catmull & Clark 1978) with the sharp and semi-sharp crease rules
//! of DeRose, Kass & Truong 1998 ("Subdivision surfaces in character animation", section 3):
//! every face of n sides becomes n quads, and each new vertex is a fixed weighted sum of old
//! ones (a stencil), applied to positions and primitive variables alike.
//!
//! New vertices are numbered: the old vertices' new positions first (vertex points), then
//! one per edge in [`Topology::edges`] order (edge points), then one per face (face points).
//! The child quad at corner i of face f = (v0 .. vn-1) is (vertex point of vi, edge point of
//! vi-vi+1, face point of f, edge point of vi-1-vi): its u runs along the parent's edge
//! vi -> vi+1, so children keep the parent's orientation.

use super::topology::{INFINITELY_SHARP, Mesh, Topology, edge_key};
use glam::DVec3;
use std::collections::HashMap;

/// A new vertex as a weighted sum of old ones.
pub type Stencil = Vec<(u32, f64)>;

/// Applies `stencils` to the old values `old`.
pub fn apply(stencils: &[Stencil], old: &[DVec3]) -> Vec<DVec3> {
    stencils
        .iter()
        .map(|s| s.iter().map(|&(i, w)| old[i as usize] * w).sum())
        .collect()
}

/// The sharpness a tag keeps one level finer: one less, never below 0; infinite stays.
fn decay(s: f64) -> f64 {
    if s == INFINITELY_SHARP {
        s
    } else {
        (s - 1.0).max(0.0)
    }
}

/// Adds `w` times stencil `s` to `out`.
fn add(out: &mut Stencil, s: &Stencil, w: f64) {
    out.extend(s.iter().map(|&(i, x)| (i, x * w)));
}

/// How a vertex moves, from its sharp edges and own sharpness (DeRose et al. 1998): smooth
/// (fewer than two sharp edges), crease (two, moving along them), corner (more, or a
/// sharp vertex); with the sharpness (at most 1) that blends the sharp rule with the smooth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VertexRule {
    /// The smooth Catmull-Clark rule.
    Smooth,
    /// Crease along the edges to these two neighbours, blended by the weight.
    Crease(u32, u32, f64),
    /// Fixed, blended by the weight.
    Corner(f64),
}

/// The rule of vertex `v` of `mesh`.
pub fn vertex_rule(mesh: &Mesh, topo: &Topology, v: u32) -> VertexRule {
    let mut sharp = Vec::new();
    for &e in &topo.vertex_edges[v as usize] {
        let (a, b) = topo.edges[e as usize];
        let s = mesh.edge_sharpness.get(&(a, b)).copied().unwrap_or(0.0);
        if s > 0.0 {
            sharp.push((if a == v { b } else { a }, s));
        }
    }
    let vs = mesh.vertex_sharpness[v as usize];
    let mean = |s: &[(u32, f64)]| s.iter().map(|x| x.1.min(1.0)).sum::<f64>() / s.len() as f64;
    if vs > 0.0 {
        VertexRule::Corner(vs.min(1.0))
    } else if sharp.len() > 2 {
        VertexRule::Corner(mean(&sharp))
    } else if sharp.len() == 2 {
        VertexRule::Crease(sharp[0].0, sharp[1].0, mean(&sharp))
    } else {
        VertexRule::Smooth
    }
}

/// One Catmull-Clark step: the finer mesh (tags decayed, holes and origins inherited) and the
/// stencil of each of its vertices over the coarser mesh's.
pub fn refine(mesh: &Mesh, topo: &Topology) -> (Mesh, Vec<Stencil>) {
    let nv = mesh.nverts;
    let ne = topo.edges.len();
    let face_stencil = |f: usize| -> Stencil {
        let face = &mesh.faces[f];
        let w = 1.0 / face.len() as f64;
        face.iter().map(|&v| (v, w)).collect()
    };
    let faces: Vec<Stencil> = (0..mesh.faces.len()).map(face_stencil).collect();

    let mut stencils: Vec<Stencil> = Vec::with_capacity(nv + ne + faces.len());
    // Vertex points.
    for v in 0..nv as u32 {
        let vf = &topo.vertex_faces[v as usize];
        let ve = &topo.vertex_edges[v as usize];
        let smooth = || -> Stencil {
            let n = ve.len() as f64;
            if vf.is_empty() {
                return vec![(v, 1.0)];
            }
            // (Q + 2R + (n - 3) S) / n: Q the mean face point, R the mean edge midpoint.
            let mut s = vec![(v, (n - 3.0) / n)];
            for &f in vf {
                add(&mut s, &faces[f as usize], 1.0 / (vf.len() as f64 * n));
            }
            for &e in ve {
                let (a, b) = topo.edges[e as usize];
                s.push((a, 1.0 / (n * n)));
                s.push((b, 1.0 / (n * n)));
            }
            s
        };
        let st = match vertex_rule(mesh, topo, v) {
            VertexRule::Smooth if topo.is_boundary(v) && !vf.is_empty() => {
                // A boundary edge is always tagged sharp by the reader; this only guards a
                // mesh built otherwise: keep the vertex where it is.
                vec![(v, 1.0)]
            }
            VertexRule::Smooth => smooth(),
            VertexRule::Crease(a, b, w) => {
                let mut s = vec![(a, 0.125 * w), (b, 0.125 * w), (v, 0.75 * w)];
                if w < 1.0 {
                    add(&mut s, &smooth(), 1.0 - w);
                }
                s
            }
            VertexRule::Corner(w) => {
                let mut s = vec![(v, w)];
                if w < 1.0 {
                    add(&mut s, &smooth(), 1.0 - w);
                }
                s
            }
        };
        stencils.push(st);
    }
    // Edge points.
    for (e, &(a, b)) in topo.edges.iter().enumerate() {
        let s = mesh.edge_sharpness.get(&(a, b)).copied().unwrap_or(0.0);
        let ef = &topo.edge_faces[e];
        let sharp: Stencil = vec![(a, 0.5), (b, 0.5)];
        let st = if ef.len() != 2 || s >= 1.0 {
            sharp
        } else {
            let mut smooth: Stencil = vec![(a, 0.25), (b, 0.25)];
            for &f in ef {
                add(&mut smooth, &faces[f as usize], 0.25);
            }
            if s > 0.0 {
                let mut out = Vec::new();
                add(&mut out, &sharp, s);
                add(&mut out, &smooth, 1.0 - s);
                out
            } else {
                smooth
            }
        };
        stencils.push(st);
    }
    stencils.extend(faces);

    // Children.
    let ep = |a: u32, b: u32| (nv + topo.edge_index[&edge_key(a, b)] as usize) as u32;
    let mut child = Mesh {
        nverts: stencils.len(),
        vertex_sharpness: mesh.vertex_sharpness.iter().map(|&s| decay(s)).collect(),
        ..Mesh::default()
    };
    child.vertex_sharpness.resize(child.nverts, 0.0);
    for (f, face) in mesh.faces.iter().enumerate() {
        let fp = (nv + ne + f) as u32;
        let n = face.len();
        for i in 0..n {
            let (prev, v, next) = (face[(i + n - 1) % n], face[i], face[(i + 1) % n]);
            child.faces.push(vec![v, ep(v, next), fp, ep(prev, v)]);
            child.hole.push(mesh.hole[f]);
            child.origin.push(mesh.origin[f]);
        }
    }
    let mut sharp = HashMap::new();
    for (&(a, b), &s) in &mesh.edge_sharpness {
        let s = decay(s);
        let Some(&e) = topo.edge_index.get(&(a, b)) else {
            continue;
        };
        if s > 0.0 {
            let m = (nv + e as usize) as u32;
            sharp.insert(edge_key(a, m), s);
            sharp.insert(edge_key(b, m), s);
        }
    }
    child.edge_sharpness = sharp;
    (child, stencils)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_and_points() -> (Mesh, Vec<DVec3>) {
        let m = Mesh {
            nverts: 4,
            faces: vec![vec![0, 1, 2, 3]],
            hole: vec![false],
            origin: vec![0],
            edge_sharpness: [(0, 1), (1, 2), (2, 3), (0, 3)]
                .into_iter()
                .map(|k| (k, INFINITELY_SHARP))
                .collect(),
            vertex_sharpness: vec![INFINITELY_SHARP; 4],
        };
        let p = vec![
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        (m, p)
    }

    #[test]
    fn a_quad_with_sharp_boundary_and_corners_splits_into_four_bilinear_quads() {
        let (m, p) = quad_and_points();
        let t = Topology::new(&m).unwrap();
        let (c, st) = refine(&m, &t);
        let q = apply(&st, &p);
        assert_eq!(c.faces.len(), 4);
        assert_eq!(q.len(), 9);
        assert_eq!(&q[..4], &p[..]);
        assert_eq!(q[8], DVec3::new(0.5, 0.5, 0.0));
        for e in &q[4..8] {
            assert!(e.x == 0.5 || e.y == 0.5);
        }
        // The boundary edges stay infinitely sharp, the inner edges are smooth.
        assert_eq!(c.edge_sharpness.len(), 8);
        assert!(c.faces.iter().all(|f| f.len() == 4));
    }

    #[test]
    fn every_stencil_is_an_affine_combination() {
        let (mut m, _) = quad_and_points();
        m.edge_sharpness.insert((0, 1), 0.4);
        m.vertex_sharpness = vec![0.0, 0.3, 0.0, 2.0];
        let t = Topology::new(&m).unwrap();
        let (_, st) = refine(&m, &t);
        for s in &st {
            let w: f64 = s.iter().map(|x| x.1).sum();
            assert!((w - 1.0).abs() < 1e-12, "{s:?}");
        }
    }
}
