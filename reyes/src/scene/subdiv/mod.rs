//! Catmull-Clark subdivision surfaces (RenderMan `SubdivisionMesh "catmull-clark"`) as
//! bicubic Bezier patches of their limit surface, so that the Reyes pipeline bounds, splits
//! and dices them like any other patch.
//!
//! - [`topology`]: the control mesh, its tags and adjacency;
//! - [`refine`]: one Catmull-Clark step with (semi-)sharp creases and corners;
//! - [`limit`]: limit positions and tangents at vertices, the approximating patch;
//! - [`adaptive`]: feature-adaptive subdivision down to regular B-spline patches.
//!
//! Regular quads are exact bicubic B-spline patches; faces that are not quads get one step
//! first; near extraordinary vertices, creases, corners and boundaries the faces are
//! subdivided adaptively [`DEFAULT_MAX_LEVEL`] times and the last ring of faces becomes
//! patches that interpolate the limit position and tangent plane at their corners
//! (`limit::approximate_patch`); the tests bound their distance to the limit surface. The
//! renderer's shading normals are the patches' own (exact on the B-spline patches, the
//! limit normal at the approximating patches' corners).

pub mod adaptive;
pub mod limit;
pub mod refine;
pub mod topology;

#[cfg(test)]
mod tests;

pub use adaptive::{FaceVarying, LimitPatch, limit_patches, limit_patches_with, uniform};
use glam::DVec3;
use topology::{INFINITELY_SHARP, Mesh, SHARPNESS_CAP, Topology, edge_key};

/// Adaptive levels around irregularities: the approximated faces are 1/8 of a control face
/// across (the tests' measured error there is under 0.2% of the object's size).
pub const DEFAULT_MAX_LEVEL: u32 = 3;

/// Control meshes of more faces than this get one adaptive level less per factor of 8 (at
/// least 1): a mesh irregular everywhere (triangles from an exporter) makes up to 4^level
/// patches per face, and the finer levels matter less on a mesh whose faces are already small.
pub const FACES_FOR_FULL_DEPTH: usize = 20_000;

/// The adaptive depth for a control mesh of `faces` faces: [`DEFAULT_MAX_LEVEL`], one less for
/// each factor of 8 beyond [`FACES_FOR_FULL_DEPTH`], at least 1.
pub fn max_level_for(faces: usize) -> u32 {
    let mut level = DEFAULT_MAX_LEVEL;
    let mut limit = FACES_FOR_FULL_DEPTH;
    while faces > limit && level > 1 {
        level -= 1;
        limit = limit.saturating_mul(8);
    }
    level
}

/// `interpolateboundary` as RenderMan defines it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BoundaryMode {
    /// No tag: faces at the boundary are not drawn (the limit surface of the interior).
    #[default]
    None,
    /// `interpolateboundary [1]` (or no value): boundary edges infinitely sharp, and vertices
    /// with one face corners.
    EdgesAndCorners,
    /// `interpolateboundary [2]`: boundary edges infinitely sharp only.
    EdgesOnly,
}

/// The tags of a `SubdivisionMesh` that change its surface.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tags {
    /// Boundary rule.
    pub boundary: BoundaryMode,
    /// Crease chains (vertices joined by edges) with their sharpness.
    pub creases: Vec<(Vec<u32>, f64)>,
    /// Corner vertices with their sharpness.
    pub corners: Vec<(u32, f64)>,
    /// Faces not drawn.
    pub holes: Vec<u32>,
}

/// RenderMan's sharpness: 10 and above (and infinity) mean infinitely sharp.
fn sharpness(s: f64) -> f64 {
    if s >= SHARPNESS_CAP {
        INFINITELY_SHARP
    } else {
        s.max(0.0)
    }
}

/// The control mesh of faces with `sizes[f]` vertices each, `indices` concatenated, over
/// `nverts` vertices, with `tags` applied. Errors name the face, tag or vertex at fault.
pub fn control_mesh(
    sizes: &[usize],
    indices: &[u32],
    nverts: usize,
    tags: &Tags,
) -> Result<Mesh, String> {
    let total: usize = sizes.iter().sum();
    if total != indices.len() {
        return Err(format!(
            "the face sizes add up to {total} vertex indices, but {} are given",
            indices.len()
        ));
    }
    let mut mesh = Mesh {
        nverts,
        vertex_sharpness: vec![0.0; nverts],
        ..Mesh::default()
    };
    let mut at = 0;
    for &n in sizes {
        mesh.faces.push(indices[at..at + n].to_vec());
        at += n;
    }
    mesh.hole = vec![false; sizes.len()];
    mesh.origin = (0..sizes.len() as u32).collect();
    let topo = Topology::new(&mesh)?;
    for &h in &tags.holes {
        *mesh
            .hole
            .get_mut(h as usize)
            .ok_or_else(|| format!("hole tag: face {h} out of range ({} faces)", sizes.len()))? =
            true;
    }
    for (chain, s) in &tags.creases {
        for pair in chain.windows(2) {
            let key = edge_key(pair[0], pair[1]);
            if topo.edge_index.contains_key(&key) {
                mesh.edge_sharpness.insert(key, sharpness(*s));
            }
        }
    }
    for &(v, s) in &tags.corners {
        *mesh
            .vertex_sharpness
            .get_mut(v as usize)
            .ok_or_else(|| format!("corner tag: vertex {v} out of range ({nverts} vertices)"))? =
            sharpness(s);
    }
    // Boundary edges are always sharp (no face beyond them); without interpolateboundary
    // the faces touching the boundary are left undrawn.
    for (e, &key) in topo.edges.iter().enumerate() {
        if topo.edge_faces[e].len() == 1 {
            mesh.edge_sharpness.insert(key, INFINITELY_SHARP);
        }
    }
    for v in 0..nverts as u32 {
        if topo.vertex_faces[v as usize].is_empty() || !topo.is_boundary(v) {
            continue;
        }
        match tags.boundary {
            BoundaryMode::None => {
                for &f in &topo.vertex_faces[v as usize] {
                    mesh.hole[f as usize] = true;
                }
            }
            BoundaryMode::EdgesAndCorners if topo.vertex_faces[v as usize].len() == 1 => {
                mesh.vertex_sharpness[v as usize] = INFINITELY_SHARP;
            }
            _ => {}
        }
    }
    Ok(mesh)
}

/// The limit surface of a `SubdivisionMesh` as patches ([`control_mesh`], then
/// [`limit_patches_with`] to [`max_level_for`] its size); `data[0]` the positions, `fv` the
/// facevarying channels (`fv[channel][corner]`, one value per entry of `indices`).
pub fn catmull_clark(
    sizes: &[usize],
    indices: &[u32],
    tags: &Tags,
    data: Vec<Vec<DVec3>>,
    fv: &[&[DVec3]],
) -> Result<Vec<LimitPatch>, String> {
    let mesh = control_mesh(sizes, indices, data[0].len(), tags)?;
    let fv = (!fv.is_empty()).then(|| {
        let mut at = 0;
        (sizes.iter())
            .map(|&n| {
                let face = (at..at + n)
                    .map(|k| fv.iter().map(|ch| ch[k]).collect())
                    .collect();
                at += n;
                face
            })
            .collect()
    });
    limit_patches_with(mesh, data, fv, max_level_for(sizes.len()))
}
