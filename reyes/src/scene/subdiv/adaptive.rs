//! Feature-adaptive subdivision (Nießner, Loop, Meyer & DeRose 2012, "Feature-adaptive GPU
//! rendering of Catmull-Clark subdivision surfaces", section 3): a quad whose four corners
//! are regular (interior, valence 4, untagged, smooth edges) is exactly a bicubic B-spline
//! patch and is emitted as one; every other face is subdivided, only it and the two rings
//! of faces its children's stencils reach, until `max_level`, where the faces still
//! irregular become [`super::limit::approximate_patch`]es.

use super::limit::{VertexLimit, approximate_patch, vertex_limit};
use super::refine::{Stencil, apply, refine};
use super::topology::{Mesh, Topology};
use crate::scene::basis::{Basis, block_to_bezier};
use glam::DVec3;
use std::collections::HashMap;

/// One bicubic Bezier patch of the limit surface: 16 values, cp[4*v + u], per channel
/// (channel 0 the positions, then the primitive variables subdivided with them).
#[derive(Clone, Debug, PartialEq)]
pub struct LimitPatch {
    /// Per channel the 16 Bezier coefficients.
    pub channels: Vec<[DVec3; 16]>,
    /// The face of the control mesh the patch lies on.
    pub origin: u32,
    /// Subdivision level it was emitted at (0: a face of the control mesh).
    pub level: u32,
    /// True for an exact B-spline patch, false for an approximation near an irregularity.
    pub exact: bool,
    /// Per facevarying channel ([`limit_patches_with`]) its values at the patch's corners
    /// (u, v) = (0, 0), (1, 0), (0, 1), (1, 1), interpolated bilinearly in between; empty
    /// without facevarying channels.
    pub facevarying: Vec<[DVec3; 4]>,
}

/// Facevarying values: per face, per corner, per channel.
pub type FaceVarying = Vec<Vec<Vec<DVec3>>>;

/// The facevarying values of the children [`refine`] makes of `faces` (in its order: per face,
/// the child at each corner i, (vertex i, edge i -> i+1, face centre, edge i-1 -> i)),
/// interpolated linearly over each face: the corner's value, the edges' midpoints, the mean
/// of the corners.
fn refine_facevarying(faces: &[Vec<Vec<DVec3>>]) -> FaceVarying {
    let mid = |a: &[DVec3], b: &[DVec3]| -> Vec<DVec3> {
        a.iter().zip(b).map(|(x, y)| (*x + *y) * 0.5).collect()
    };
    let mut out = Vec::new();
    for face in faces {
        let n = face.len();
        let centre: Vec<DVec3> = (0..face[0].len())
            .map(|c| face.iter().map(|corner| corner[c]).sum::<DVec3>() / n as f64)
            .collect();
        for i in 0..n {
            let (prev, v, next) = (&face[(i + n - 1) % n], &face[i], &face[(i + 1) % n]);
            out.push(vec![v.clone(), mid(v, next), centre.clone(), mid(prev, v)]);
        }
    }
    out
}

/// The bilinear corner values ([`LimitPatch::facevarying`]) of a quad whose corners 0..3 are
/// the patch's (u, v) = (0, 0), (1, 0), (1, 1), (0, 1) (its first edge along u).
fn quad_corners(face: &[Vec<DVec3>]) -> Vec<[DVec3; 4]> {
    (0..face.first().map_or(0, |c| c.len()))
        .map(|c| [face[0][c], face[1][c], face[3][c], face[2][c]])
        .collect()
}

/// Local ring position to 4x4 grid position for corner `i` of a quad (see [`grid16`]).
fn rotate(i: usize, (r, c): (usize, usize)) -> usize {
    let (r, c) = match i {
        0 => (r, c),
        1 => (c, 3 - r),
        2 => (3 - r, 3 - c),
        _ => (3 - c, r),
    };
    4 * r + c
}

/// The 16 B-spline control points (grid[4*row + col], columns along the face's first edge)
/// of quad `f`, if it is regular: each corner interior, valence 4 with quads around, no
/// vertex or edge tags at it.
fn grid16(mesh: &Mesh, topo: &Topology, f: u32) -> Option<[u32; 16]> {
    let face = &mesh.faces[f as usize];
    if face.len() != 4 {
        return None;
    }
    let mut g = [u32::MAX; 16];
    for (i, &v) in face.iter().enumerate() {
        if mesh.vertex_sharpness[v as usize] != 0.0 {
            return None;
        }
        let ring = topo.ring(mesh, v, f)?;
        if ring.edge.len() != 4
            || ring
                .edge
                .iter()
                .any(|&e| Topology::sharpness(mesh, v, e) != 0.0)
        {
            return None;
        }
        g[rotate(i, (1, 1))] = v;
        let places = [
            (1, 2),
            (2, 2),
            (2, 1),
            (2, 0),
            (1, 0),
            (0, 0),
            (0, 1),
            (0, 2),
        ];
        for k in 0..4 {
            g[rotate(i, places[2 * k])] = ring.edge[k];
            g[rotate(i, places[2 * k + 1])] = ring.diag[k];
        }
    }
    Some(g)
}

/// Faces sharing a vertex with a face of `set`, and `set` itself.
fn grow(mesh: &Mesh, topo: &Topology, set: &[bool]) -> Vec<bool> {
    let mut out = set.to_vec();
    for (f, face) in mesh.faces.iter().enumerate() {
        if set[f] {
            for &v in face {
                for &g in &topo.vertex_faces[v as usize] {
                    out[g as usize] = true;
                }
            }
        }
    }
    out
}

/// The sub-mesh of the faces in `keep`, its vertex data, and which of its faces `need`.
fn extract(
    mesh: &Mesh,
    data: &[Vec<DVec3>],
    keep: &[bool],
    need: &[bool],
) -> (Mesh, Vec<Vec<DVec3>>, Vec<bool>) {
    let mut map = vec![u32::MAX; mesh.nverts];
    let mut old = Vec::new();
    let mut sub = Mesh::default();
    let mut sub_need = Vec::new();
    for (f, face) in mesh.faces.iter().enumerate() {
        if !keep[f] {
            continue;
        }
        let mut nf = Vec::with_capacity(face.len());
        for &v in face {
            if map[v as usize] == u32::MAX {
                map[v as usize] = old.len() as u32;
                old.push(v);
            }
            nf.push(map[v as usize]);
        }
        sub.faces.push(nf);
        sub.hole.push(mesh.hole[f]);
        sub.origin.push(mesh.origin[f]);
        sub_need.push(need[f]);
    }
    sub.nverts = old.len();
    sub.vertex_sharpness = old
        .iter()
        .map(|&v| mesh.vertex_sharpness[v as usize])
        .collect();
    for (&(a, b), &s) in &mesh.edge_sharpness {
        let (ma, mb) = (map[a as usize], map[b as usize]);
        if ma != u32::MAX && mb != u32::MAX {
            sub.edge_sharpness
                .insert(super::topology::edge_key(ma, mb), s);
        }
    }
    let sub_data = data
        .iter()
        .map(|ch| old.iter().map(|&v| ch[v as usize]).collect())
        .collect();
    (sub, sub_data, sub_need)
}

/// The limit surface of `mesh` (holes left out) as bicubic patches. `data[c][v]` is channel
/// c at vertex v (channel 0 the positions); `max_level` (at least 1) bounds the adaptive
/// subdivision. Errors: the mesh is not an oriented manifold (see [`Topology::new`]).
pub fn limit_patches(
    mesh: Mesh,
    data: Vec<Vec<DVec3>>,
    max_level: u32,
) -> Result<Vec<LimitPatch>, String> {
    limit_patches_with(mesh, data, None, max_level)
}

/// [`limit_patches`] with facevarying channels: `fv[f][corner][channel]` for every face of
/// `mesh`, interpolated linearly over each control face (refined with the faces: each child
/// corner takes its parent corner's value, an edge's midpoint or the face's mean) and given
/// to each patch at its corners ([`LimitPatch::facevarying`]).
pub fn limit_patches_with(
    mesh: Mesh,
    data: Vec<Vec<DVec3>>,
    mut fv: Option<FaceVarying>,
    max_level: u32,
) -> Result<Vec<LimitPatch>, String> {
    let max_level = max_level.max(1);
    let mut need: Vec<bool> = mesh.hole.iter().map(|h| !h).collect();
    let (mut mesh, mut data) = (mesh, data);
    let mut out = Vec::new();
    for level in 0..=max_level {
        let topo = Topology::new(&mesh)?;
        let last = level == max_level;
        let mut limits: Vec<Option<VertexLimit>> = Vec::new();
        let mut cache: Vec<Vec<DVec3>> = Vec::new();
        let mut offsets: Vec<HashMap<(u32, u32), DVec3>> = Vec::new();
        for f in 0..mesh.faces.len() {
            if !need[f] {
                continue;
            }
            if let Some(g) = grid16(&mesh, &topo, f as u32) {
                let channels = data
                    .iter()
                    .map(|ch| {
                        let pts = g.map(|v| ch[v as usize]);
                        block_to_bezier(&pts, &Basis::B_SPLINE, &Basis::B_SPLINE)
                    })
                    .collect();
                out.push(LimitPatch {
                    channels,
                    origin: mesh.origin[f],
                    level,
                    exact: true,
                    facevarying: fv.as_ref().map_or(Vec::new(), |fv| quad_corners(&fv[f])),
                });
                need[f] = false;
            } else if last && mesh.faces[f].len() == 4 {
                if limits.is_empty() {
                    // Every vertex of a needed face, once, in the canonical ring order.
                    limits = (0..mesh.nverts).map(|_| None).collect();
                    for (g, face) in mesh.faces.iter().enumerate() {
                        if need[g] {
                            for &v in face {
                                if limits[v as usize].is_none() {
                                    limits[v as usize] = Some(vertex_limit(&mesh, &topo, v));
                                }
                            }
                        }
                    }
                    for ch in &data {
                        let eval = |s: &Stencil| -> DVec3 {
                            s.iter().map(|&(i, w)| ch[i as usize] * w).sum()
                        };
                        cache.push(
                            limits
                                .iter()
                                .map(|l| l.as_ref().map_or(DVec3::ZERO, |l| eval(&l.position)))
                                .collect(),
                        );
                        let mut off = HashMap::new();
                        for (v, l) in limits.iter().enumerate() {
                            for (w, s) in l.iter().flat_map(|l| l.offsets.iter()) {
                                off.insert((v as u32, *w), eval(s));
                            }
                        }
                        offsets.push(off);
                    }
                }
                let channels = (0..data.len())
                    .map(|c| {
                        let ch = &data[c];
                        let eval = |s: &Stencil| -> DVec3 {
                            s.iter().map(|&(i, w)| ch[i as usize] * w).sum()
                        };
                        approximate_patch(
                            &mesh,
                            f,
                            &limits,
                            &eval,
                            &|v| cache[c][v as usize],
                            &|v, w| offsets[c][&(v, w)],
                        )
                    })
                    .collect();
                out.push(LimitPatch {
                    channels,
                    origin: mesh.origin[f],
                    level,
                    exact: false,
                    facevarying: fv.as_ref().map_or(Vec::new(), |fv| quad_corners(&fv[f])),
                });
                need[f] = false;
            }
        }
        if !need.iter().any(|&n| n) {
            break;
        }
        let keep = grow(&mesh, &topo, &grow(&mesh, &topo, &need));
        let (sub, sub_data, sub_need) = extract(&mesh, &data, &keep, &need);
        let sub_topo = Topology::new(&sub)?;
        let (child, stencils) = refine(&sub, &sub_topo);
        if let Some(values) = &mut fv {
            let kept: Vec<Vec<Vec<DVec3>>> = (values.drain(..).zip(&keep))
                .filter(|(_, k)| **k)
                .map(|(v, _)| v)
                .collect();
            *values = refine_facevarying(&kept);
        }
        need = sub
            .faces
            .iter()
            .zip(&sub_need)
            .flat_map(|(face, &n)| std::iter::repeat_n(n, face.len()))
            .collect();
        data = sub_data.iter().map(|ch| apply(&stencils, ch)).collect();
        mesh = child;
    }
    Ok(out)
}

/// Uniform subdivision `levels` times (every face, holes included): the reference the tests
/// compare the adaptive patches with.
pub fn uniform(
    mesh: &Mesh,
    data: &[Vec<DVec3>],
    levels: u32,
) -> Result<(Mesh, Vec<Vec<DVec3>>), String> {
    let (mut mesh, mut data) = (mesh.clone(), data.to_vec());
    for _ in 0..levels {
        let topo = Topology::new(&mesh)?;
        let (child, st) = refine(&mesh, &topo);
        data = data.iter().map(|ch| apply(&st, ch)).collect();
        mesh = child;
    }
    Ok((mesh, data))
}
