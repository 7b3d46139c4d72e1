//! The polygon requests `Polygon`, `GeneralPolygon`, `PointsPolygons` and
//! `PointsGeneralPolygons` (RenderMan Interface Specification 3.2, section 5.2): their
//! arguments, their primitive variables, and their faces as bilinear patches
//! ([`crate::scene::polygon`]) through the same path as every other patch.
//!
//! Primitive variable counts: constant 1; uniform one per face; varying and vertex one per
//! point (the largest index of `vertices` plus one, or the points of a `Polygon` /
//! `GeneralPolygon`); facevarying one per face corner (the sum of the loops' vertex counts).
//! Each emitted piece gets the values at its corners: one value for constant and uniform,
//! else its four corners interpolated bilinearly (on a triangle piece: barycentrically).

use super::lexer::shown;
use super::primvars::{Class, ClassCounts, ColorVar, Decl, parse_decl};
use super::state::Interp;
use super::syntax::{Args, Param, Request};
use crate::scene::polygon::pieces;
use crate::scene::{BilinearForm, ColorField, SceneError};
use glam::{DMat3, DMat4, DVec3};

/// Most loops, corners or points of one polygon request (each index must fit the renderer's
/// u32 patch numbering with room to spare).
const MAX_COUNT: usize = 1 << 28;

/// A polygon request's topology: faces made of loops made of corners, each corner a point.
struct Mesh {
    /// Per face, its loops: a range of `loops` (outer loop first, then holes).
    faces: Vec<std::ops::Range<usize>>,
    /// Per loop, its corners: a range of `corners`.
    loops: Vec<std::ops::Range<usize>>,
    /// Per corner (face-varying index), its point (vertex index).
    corners: Vec<usize>,
    /// The number of points.
    points: usize,
}

/// Non-negative integers of a count or index array, each at most `max`.
fn indices(a: &Args, v: &[f64], what: &str, max: usize) -> Result<Vec<usize>, SceneError> {
    if v.len() > MAX_COUNT {
        return Err(a.err(format!(
            "{what}: {} entries, more than the reader's limit {MAX_COUNT}",
            v.len()
        )));
    }
    v.iter()
        .enumerate()
        .map(|(k, &x)| {
            if x.fract() == 0.0 && x >= 0.0 && x <= max as f64 {
                Ok(x as usize)
            } else {
                Err(a.err(format!(
                    "{what}: entry {k} is {x}, not an integer in 0..={max}"
                )))
            }
        })
        .collect()
}

/// Sum of `counts`, checked against the limit.
fn total(a: &Args, counts: &[usize], what: &str) -> Result<usize, SceneError> {
    let n: usize = counts.iter().sum();
    if n > MAX_COUNT {
        return Err(a.err(format!(
            "{what} add up to {n}, more than the reader's limit {MAX_COUNT}"
        )));
    }
    Ok(n)
}

impl Mesh {
    /// Faces of `nloops[f]` loops of `nverts[l]` corners each, the corners' points
    /// `vertices` (or the corners themselves, in order, when `None`).
    fn new(
        a: &Args,
        nloops: &[usize],
        nverts: &[usize],
        vertices: Option<Vec<usize>>,
    ) -> Result<Mesh, SceneError> {
        let nl = total(a, nloops, "the loop counts")?;
        if nl != nverts.len() {
            return Err(a.err(format!(
                "the loop counts add up to {nl}, but {} vertex counts are given",
                nverts.len()
            )));
        }
        let nc = total(a, nverts, "the vertex counts")?;
        let corners = match vertices {
            Some(v) => {
                if v.len() != nc {
                    return Err(a.err(format!(
                        "the vertex counts add up to {nc}, but {} vertex indices are given",
                        v.len()
                    )));
                }
                v
            }
            None => (0..nc).collect(),
        };
        let points = corners.iter().max().map_or(0, |m| m + 1);
        let mut loops = Vec::with_capacity(nverts.len());
        let mut at = 0;
        for &n in nverts {
            loops.push(at..at + n);
            at += n;
        }
        let mut faces = Vec::with_capacity(nloops.len());
        let mut at = 0;
        for &n in nloops {
            faces.push(at..at + n);
            at += n;
        }
        Ok(Mesh {
            faces,
            loops,
            corners,
            points,
        })
    }

    fn counts(&self) -> ClassCounts {
        ClassCounts {
            uniform: self.faces.len(),
            varying: self.points,
            vertex: self.points,
            facevarying: self.corners.len(),
        }
    }
}

impl ColorVar {
    /// The field over one piece of face `face` whose corners (face-varying indices) are
    /// `fv`, their points `pt`.
    fn polygon_field(&self, face: usize, fv: [usize; 4], pt: [usize; 4]) -> ColorField {
        let v = &self.values;
        match self.class {
            Class::Constant => ColorField::Flat(v[0]),
            Class::Uniform => ColorField::Flat(v[face]),
            Class::Varying | Class::Vertex => ColorField::Bilinear(pt.map(|k| v[k])),
            Class::FaceVarying => ColorField::Bilinear(fv.map(|k| v[k])),
        }
    }
}

impl Interp {
    /// `Polygon`, `GeneralPolygon`, `PointsPolygons`, `PointsGeneralPolygons`.
    pub(super) fn polygon_request(
        &mut self,
        req: &Request,
        a: &mut Args,
    ) -> Result<(), SceneError> {
        let mesh = match req.name.as_str() {
            "Polygon" => {
                // The point count comes from "P" itself.
                let params = a.params()?;
                let (n, _, _) = super::primvars::counted_by_p(a, &params)?;
                a.pos = 0;
                Mesh::new(a, &[1], &[n], None)?
            }
            "GeneralPolygon" => {
                let nverts = a.array("nverts")?;
                let nverts = indices(a, nverts, "nverts", MAX_COUNT)?;
                Mesh::new(a, &[nverts.len()], &nverts, None)?
            }
            "PointsPolygons" => {
                let nverts = a.array("nverts")?;
                let nverts = indices(a, nverts, "nverts", MAX_COUNT)?;
                let verts = a.array("vertices")?;
                let verts = indices(a, verts, "vertices", MAX_COUNT)?;
                Mesh::new(a, &vec![1; nverts.len()], &nverts, Some(verts))?
            }
            _ => {
                let nloops = a.array("nloops")?;
                let nloops = indices(a, nloops, "nloops", MAX_COUNT)?;
                let nverts = a.array("nverts")?;
                let nverts = indices(a, nverts, "nverts", MAX_COUNT)?;
                let verts = a.array("vertices")?;
                let verts = indices(a, verts, "vertices", MAX_COUNT)?;
                Mesh::new(a, &nloops, &nverts, Some(verts))?
            }
        };
        let all = a.params()?;
        // "N" is read here; `positions` warns about the parameters nobody reads.
        let (normals, params): (Vec<Param>, Vec<Param>) =
            all.into_iter().partition(|p| p.name == "N");
        let pts = self.positions(req, a, &params, mesh.points)?;
        let vars = self.color_vars(a, &params, &mesh.counts())?;
        let ctm = self.geometry_ctm(a)?;
        let nvar = match normals.as_slice() {
            [] => None,
            [p] => Some(self.normal_var(a, p, &mesh.counts(), &ctm)?),
            _ => return Err(a.err("\"N\" given twice")),
        };
        // Building an object's primitive for its instances: the normals as given (object
        // space), which each instance takes to its own camera space.
        let object_normals = match (&nvar, normals.as_slice()) {
            (Some(v), [p]) if self.instancing.capturing() => Some(ColorVar {
                class: v.class,
                values: p.nums(a)?.chunks_exact(3).map(DVec3::from_slice).collect(),
            }),
            _ => None,
        };
        if let Some(v) = &object_normals {
            self.instancing.captured_normal_values(&v.values);
        }
        let mut skipped = 0usize;
        for (f, face) in mesh.faces.iter().enumerate() {
            let loops: Vec<&std::ops::Range<usize>> = mesh.loops[face.clone()]
                .iter()
                .filter(|l| l.len() >= 3)
                .collect();
            if loops.len() < mesh.loops[face.clone()].len() {
                skipped += 1;
            }
            // A face without its outer loop draws nothing.
            if mesh.loops[face.clone()].first().is_none_or(|l| l.len() < 3) {
                continue;
            }
            for l in &loops {
                for c in l.start..l.end {
                    let p = pts[mesh.corners[c]];
                    if !p.is_finite() {
                        return Err(super::patches::bad_point(a, f, mesh.corners[c], p));
                    }
                }
            }
            let positions: Vec<Vec<DVec3>> = loops
                .iter()
                .map(|l| mesh.corners[(*l).clone()].iter().map(|&k| pts[k]).collect())
                .collect();
            let slices: Vec<&[DVec3]> = positions.iter().map(Vec::as_slice).collect();
            // Face-local corner numbers (through the kept loops) to face-varying indices.
            let fv_of: Vec<usize> = loops.iter().flat_map(|l| (*l).clone()).collect();
            for piece in pieces(&slices) {
                let fv = piece.map(|k| fv_of[k]);
                let pt = fv.map(|k| mesh.corners[k]);
                let corners = pt.map(|k| pts[k]);
                let fields = vars.map(|v| v.polygon_field(f, fv, pt));
                let form = BilinearForm::Polygon;
                self.emit_bilinear_with(a, &ctm, f, corners, form, fields)?;
                if let (Some(v), Some(p)) = (&nvar, self.scene.patches.last_mut()) {
                    let mut vars = p
                        .primvars
                        .take()
                        .map(std::sync::Arc::unwrap_or_clone)
                        .unwrap_or_default();
                    vars.n = Some(v.polygon_field(f, fv, pt));
                    p.primvars = vars.shared();
                }
                if let Some(v) = &object_normals {
                    self.instancing.captured_normals(v.polygon_field(f, fv, pt));
                }
            }
        }
        if skipped > 0 {
            let msg = format!(
                "skipped loops of fewer than 3 vertices in `{}` (a face whose outer loop is one \
                 is not drawn)",
                shown(&req.name)
            );
            self.warn_once(req, &format!("{} short loop", req.name), &msg);
        }
        Ok(())
    }
}

impl Interp {
    /// The `"N"` parameter of a polygon request with `counts`: its class from the inline
    /// declaration, else `Declare`, else the predeclared `varying normal`; its values taken
    /// to camera space by the inverse transpose of `ctm` (normals stay perpendicular to the
    /// transformed surface).
    fn normal_var(
        &self,
        a: &Args,
        p: &Param,
        counts: &ClassCounts,
        ctm: &DMat4,
    ) -> Result<ColorVar, SceneError> {
        let decl = match p.decl {
            Some(text) => parse_decl(text).map_err(|e| a.err(e))?,
            None => self.declared.get("N").cloned().unwrap_or(Decl {
                class: Class::Varying,
                ty: "normal".into(),
                len: 1,
            }),
        };
        if !(decl.ty == "normal" || decl.ty == "vector") || decl.len != 1 {
            return Err(a.err(format!("\"N\" must be a normal, found {}", decl.ty)));
        }
        let n = counts.of(decl.class);
        let v = p.nums(a)?;
        if v.len() != 3 * n {
            return Err(a.err(format!(
                "\"N\" ({} normal) needs {n} values ({} numbers), found {} numbers",
                decl.class.name(),
                3 * n,
                v.len()
            )));
        }
        let values =
            super::primvars::normals_to_camera(a, DMat3::from_mat4(*ctm), v.chunks_exact(3))?;
        Ok(ColorVar {
            class: decl.class,
            values,
        })
    }
}
