//! Polygon mesh topology for Catmull-Clark subdivision: faces as vertex lists, the tags that
//! change the subdivision rules (edge and vertex sharpness, holes), and the adjacency the
//! rules and the limit masks need (incident faces and edges of a vertex, the faces of an
//! edge, the ordered one-ring of a manifold vertex).

use std::collections::HashMap;

/// Sharpness that never decays: boundary edges under `interpolateboundary`, and RenderMan's
/// "infinitely sharp" values (10 and above).
pub const INFINITELY_SHARP: f64 = f64::INFINITY;

/// RenderMan treats sharpness 10 and above as infinitely sharp.
pub const SHARPNESS_CAP: f64 = 10.0;

/// A polygon mesh with its subdivision tags. Vertex data lives outside (see `refine`).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Number of vertices.
    pub nverts: usize,
    /// Each face's vertex indices in order (at least 3).
    pub faces: Vec<Vec<u32>>,
    /// Per face: a hole (subdivided with the rest, never drawn).
    pub hole: Vec<bool>,
    /// Per face: the face of the control mesh it comes from (for uniform primitive variables).
    pub origin: Vec<u32>,
    /// Sharpness of tagged edges, keyed by the sorted vertex pair; untagged edges are smooth.
    pub edge_sharpness: HashMap<(u32, u32), f64>,
    /// Per vertex sharpness (`corner` tag); 0 for untagged vertices.
    pub vertex_sharpness: Vec<f64>,
}

/// The sorted key of the edge between `a` and `b`.
pub fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Adjacency of a [`Mesh`], built once per level.
pub struct Topology {
    /// Every edge once, as a sorted vertex pair.
    pub edges: Vec<(u32, u32)>,
    /// Edge index of a sorted vertex pair.
    pub edge_index: HashMap<(u32, u32), u32>,
    /// The faces on each edge (one on a boundary, two inside).
    pub edge_faces: Vec<Vec<u32>>,
    /// The faces around each vertex.
    pub vertex_faces: Vec<Vec<u32>>,
    /// The edges at each vertex.
    pub vertex_edges: Vec<Vec<u32>>,
    /// Directed edge (from, to) to (face, position of `from` in it).
    directed: HashMap<(u32, u32), (u32, u32)>,
}

/// The one-ring of an interior manifold vertex `v` whose faces are all quads, in order:
/// `edge[k]` is the k-th edge neighbour and `diag[k]` the vertex of the k-th face opposite
/// `v`, the face between `edge[k]` and `edge[k + 1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Ring {
    /// Edge neighbours in order.
    pub edge: Vec<u32>,
    /// Face-diagonal neighbours in order.
    pub diag: Vec<u32>,
}

impl Topology {
    /// Builds the adjacency. Errors (with the face index) where the mesh is not an oriented
    /// manifold: an edge used twice in the same direction (three or more faces on an edge,
    /// or neighbours of opposite orientation), a face with a repeated vertex or an index out
    /// of range.
    pub fn new(mesh: &Mesh) -> Result<Topology, String> {
        let mut t = Topology {
            edges: Vec::new(),
            edge_index: HashMap::new(),
            edge_faces: Vec::new(),
            vertex_faces: vec![Vec::new(); mesh.nverts],
            vertex_edges: vec![Vec::new(); mesh.nverts],
            directed: HashMap::new(),
        };
        for (f, face) in mesh.faces.iter().enumerate() {
            let n = face.len();
            if n < 3 {
                return Err(format!("face {f} has {n} vertices (at least 3 needed)"));
            }
            for (k, &v) in face.iter().enumerate() {
                if v as usize >= mesh.nverts {
                    return Err(format!(
                        "face {f}: vertex {v} out of range ({} vertices)",
                        mesh.nverts
                    ));
                }
                if face[..k].contains(&v) {
                    return Err(format!("face {f} uses vertex {v} twice"));
                }
            }
            for k in 0..n {
                let (a, b) = (face[k], face[(k + 1) % n]);
                if t.directed.insert((a, b), (f as u32, k as u32)).is_some() {
                    return Err(format!(
                        "face {f}: edge {a}-{b} is shared by more than two faces or by faces \
                         of opposite orientation (the mesh must be an oriented manifold)"
                    ));
                }
                let key = edge_key(a, b);
                let next = t.edges.len() as u32;
                let e = *t.edge_index.entry(key).or_insert(next);
                if e == next {
                    t.edges.push(key);
                    t.edge_faces.push(Vec::new());
                    t.vertex_edges[a as usize].push(e);
                    t.vertex_edges[b as usize].push(e);
                }
                t.edge_faces[e as usize].push(f as u32);
                t.vertex_faces[a as usize].push(f as u32);
            }
        }
        Ok(t)
    }

    /// The face holding the directed edge `from` -> `to`, and the position of `from` in it.
    pub fn directed(&self, from: u32, to: u32) -> Option<(u32, u32)> {
        self.directed.get(&(from, to)).copied()
    }

    /// True when `v` is on the mesh boundary (some edge at it has one face) or unused.
    pub fn is_boundary(&self, v: u32) -> bool {
        let es = &self.vertex_edges[v as usize];
        es.is_empty() || es.iter().any(|&e| self.edge_faces[e as usize].len() != 2)
    }

    /// The ordered one-ring of `v` (see [`Ring`]), starting at face `start` (which must hold
    /// `v`). `None` unless `v` is interior, manifold (one fan of faces) and all its faces are
    /// quads.
    pub fn ring(&self, mesh: &Mesh, v: u32, start: u32) -> Option<Ring> {
        let nfaces = self.vertex_faces[v as usize].len();
        let mut ring = Ring {
            edge: Vec::with_capacity(nfaces),
            diag: Vec::with_capacity(nfaces),
        };
        let mut f = start;
        loop {
            let face = &mesh.faces[f as usize];
            if face.len() != 4 {
                return None;
            }
            let k = face.iter().position(|&x| x == v)?;
            ring.edge.push(face[(k + 1) % 4]);
            ring.diag.push(face[(k + 2) % 4]);
            let prev = face[(k + 3) % 4];
            f = self.directed(v, prev)?.0;
            if f == start {
                break;
            }
            if ring.edge.len() > nfaces {
                return None;
            }
        }
        (ring.edge.len() == nfaces).then_some(ring)
    }

    /// [`Self::ring`] from the first face at `v` (the canonical start, so that every use of a
    /// vertex's ring sums in the same order and gives bit-identical results).
    pub fn canonical_ring(&self, mesh: &Mesh, v: u32) -> Option<Ring> {
        let start = *self.vertex_faces[v as usize].first()?;
        self.ring(mesh, v, start)
    }

    /// Sharpness of the edge between `a` and `b` in `mesh` (0 when untagged).
    pub fn sharpness(mesh: &Mesh, a: u32, b: u32) -> f64 {
        mesh.edge_sharpness
            .get(&edge_key(a, b))
            .copied()
            .unwrap_or(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3x3 grid of quads (16 vertices, 9 faces), row-major vertex numbering.
    pub(crate) fn grid3() -> Mesh {
        let mut faces = Vec::new();
        for r in 0..3u32 {
            for c in 0..3u32 {
                let v = r * 4 + c;
                faces.push(vec![v, v + 1, v + 5, v + 4]);
            }
        }
        Mesh {
            nverts: 16,
            hole: vec![false; 9],
            origin: (0..9).collect(),
            faces,
            ..Mesh::default()
        }
    }

    #[test]
    fn the_centre_vertex_of_a_grid_has_an_ordered_ring_and_corners_do_not() {
        let m = grid3();
        let t = Topology::new(&m).unwrap();
        let ring = t.ring(&m, 5, 4).unwrap();
        assert_eq!(ring.edge.len(), 4);
        // Face 4 is [5, 6, 10, 9]: edge 6 first, diagonal 10; then the face across 5-9.
        assert_eq!(ring.edge, vec![6, 9, 4, 1]);
        assert_eq!(ring.diag, vec![10, 8, 0, 2]);
        assert!(t.ring(&m, 0, 0).is_none());
        assert!(t.is_boundary(0) && !t.is_boundary(5));
    }

    #[test]
    fn non_manifold_edges_are_refused() {
        let m = Mesh {
            nverts: 5,
            faces: vec![vec![0, 1, 2], vec![0, 1, 3], vec![1, 0, 4]],
            hole: vec![false; 3],
            origin: vec![0, 1, 2],
            ..Mesh::default()
        };
        let e = Topology::new(&m).err().unwrap();
        assert!(e.contains("face 1: edge 0-1"), "{e}");
    }
}
