//! Primitive variables: `Declare`, inline declarations (`"varying color Cs"`), and the
//! `"Cs"` / `"Os"` values of a patch primitive, checked against the counts of their storage
//! class and turned into one [`ColorField`] per emitted Bezier patch.
//!
//! Counts (RenderMan Interface Specification 3.2, section 5.2): constant 1 value; uniform one
//! per patch (`Patch` 1, `PatchMesh` nupatches x nvpatches, `NuPatch` one per segment,
//! (1 + nu - uorder)(1 + nv - vorder)); varying one per patch corner (`Patch` 4, `PatchMesh`
//! (nupatches + 1) or nupatches when u is periodic, times the same in v, `NuPatch`
//! (2 + nu - uorder)(2 + nv - vorder)), interpolated bilinearly over each patch or segment;
//! vertex one per control point, interpolated with the patch's own basis. `"Cs"` and `"Os"`
//! are predeclared `varying color`.

use super::lexer::shown;
use super::state::Interp;
use super::syntax::{Args, Param, Request};
use crate::Error;
use crate::scene::basis::{Basis, block_to_bezier};
use crate::scene::nurbs::{self, NuSurface};
use crate::scene::rational::from_homogeneous;
use crate::scene::{ColorField, SceneError};
use glam::{DVec3, DVec4};

/// Storage class of a primitive variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Class {
    Constant,
    Uniform,
    Varying,
    Vertex,
    /// Counted and interpolated like varying on patches.
    FaceVarying,
}

impl Class {
    pub(super) fn name(self) -> &'static str {
        match self {
            Class::Constant => "constant",
            Class::Uniform => "uniform",
            Class::Varying => "varying",
            Class::Vertex => "vertex",
            Class::FaceVarying => "facevarying",
        }
    }
}

/// A declaration: class, type name and array length (`"uniform float[2]"`: uniform, float, 2).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Decl {
    pub(super) class: Class,
    pub(super) ty: String,
    pub(super) len: usize,
}

/// The RenderMan types a declaration may name.
const TYPES: &[&str] = &[
    "float", "integer", "int", "string", "color", "point", "vector", "normal", "hpoint", "matrix",
    "mpoint",
];

/// Parses a declaration (`[class] type[n]`; the class defaults to uniform, as the spec says).
/// The positions of a primitive whose point count comes from its `"P"` (3 numbers a point) or
/// `"Pw"` (4) itself (`Polygon`, `Points`): `(points, numbers per point, numbers given)`.
/// Errors: neither is given.
pub(super) fn counted_by_p(
    a: &Args,
    params: &[Param],
) -> Result<(usize, usize, usize), SceneError> {
    let p = params
        .iter()
        .find(|p| p.name == "P" || p.name == "Pw")
        .ok_or_else(|| a.err("missing the \"P\" parameter"))?;
    let dim = if p.name == "P" { 3 } else { 4 };
    let len = p.nums(a)?.len();
    Ok((len / dim, dim, len))
}

/// Normals `values` (3 numbers each) taken to camera space by the inverse transpose of the
/// transform's linear part `linear`. Errors: one that leaves the f32 range the renderer shades
/// in, naming its index.
pub(super) fn normals_to_camera<'v>(
    a: &Args,
    linear: glam::DMat3,
    values: impl IntoIterator<Item = &'v [f64]>,
) -> Result<Vec<DVec3>, SceneError> {
    let m = linear.inverse().transpose();
    let values: Vec<DVec3> = values
        .into_iter()
        .map(|c| m * DVec3::from_slice(c))
        .collect();
    if let Some(k) = values.iter().position(|x| !x.as_vec3().is_finite()) {
        return Err(a.err(format!(
            "value {k} of \"N\" is not finite in camera space in the f32 range the renderer \
             shades in"
        )));
    }
    Ok(values)
}

pub(super) fn parse_decl(text: &str) -> Result<Decl, Error> {
    let mut words = text.split_whitespace().peekable();
    let class = match words.peek().copied() {
        Some("constant") => Some(Class::Constant),
        Some("uniform") => Some(Class::Uniform),
        Some("varying") => Some(Class::Varying),
        Some("vertex") => Some(Class::Vertex),
        Some("facevarying") => Some(Class::FaceVarying),
        _ => None,
    };
    if class.is_some() {
        words.next();
    }
    let rest: String = words.collect::<Vec<_>>().join("");
    let (ty, len) = match rest.split_once('[') {
        None => (rest.as_str(), 1),
        Some((ty, n)) => {
            let n = n
                .strip_suffix(']')
                .and_then(|n| n.parse::<usize>().ok())
                .filter(|n| (1..=1 << 16).contains(n))
                .ok_or_else(|| {
                    Error::InvalidDeclaration(format!("bad array length in \"{}\"", shown(text)))
                })?;
            (ty, n)
        }
    };
    if !TYPES.contains(&ty) {
        return Err(Error::InvalidDeclaration(format!(
            "no type in declaration \"{}\"",
            shown(text)
        )));
    }
    Ok(Decl {
        class: class.unwrap_or(Class::Uniform),
        ty: ty.to_string(),
        len,
    })
}

/// The values of `"Cs"` or `"Os"` on one primitive, as given.
pub(super) struct ColorVar {
    pub(super) class: Class,
    pub(super) values: Vec<DVec3>,
}

/// `"Cs"` and `"Os"` of one primitive.
#[derive(Default)]
pub(super) struct ColorVars {
    pub(super) cs: Option<ColorVar>,
    pub(super) os: Option<ColorVar>,
}

impl ColorVars {
    /// `f` of each variable given: the (`"Cs"`, `"Os"`) fields of one emitted patch.
    pub(super) fn map(
        &self,
        f: impl Fn(&ColorVar) -> ColorField,
    ) -> (Option<ColorField>, Option<ColorField>) {
        (self.cs.as_ref().map(&f), self.os.as_ref().map(&f))
    }
}

/// The number of values each class needs on one primitive.
pub(super) struct ClassCounts {
    pub(super) uniform: usize,
    pub(super) varying: usize,
    pub(super) vertex: usize,
    /// One per face corner: on patches the same as varying, on polygon meshes the sum of
    /// the faces' vertex counts.
    pub(super) facevarying: usize,
}

impl ClassCounts {
    pub(super) fn of(&self, class: Class) -> usize {
        match class {
            Class::Constant => 1,
            Class::Uniform => self.uniform,
            Class::Varying => self.varying,
            Class::FaceVarying => self.facevarying,
            Class::Vertex => self.vertex,
        }
    }
}

impl Interp {
    /// `Declare "name" "declaration"`: later parameters of that name have its class and type.
    /// A declaration the reader cannot parse is skipped with a warning (the name stays as it
    /// was); names other than `"Cs"` and `"Os"` are only remembered.
    pub(super) fn declare(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let name = a.string("the variable name")?;
        let text = a.string("the declaration")?;
        a.done()?;
        match parse_decl(text) {
            Ok(d) => {
                self.declared.insert(name.to_string(), d);
                self.instancing.declared();
            }
            Err(e) => {
                let msg = format!("skipped `Declare` of \"{}\": {e}", shown(name));
                self.warn_once(req, &format!("Declare \"{name}\""), &msg);
            }
        }
        Ok(())
    }

    /// The `"Cs"` and `"Os"` parameters of a primitive with `counts`, their class from the
    /// inline declaration, else `Declare`, else the predeclared `varying color`. Errors name
    /// the variable, its class and the expected count.
    pub(super) fn color_vars(
        &self,
        a: &Args,
        params: &[Param],
        counts: &ClassCounts,
    ) -> Result<ColorVars, SceneError> {
        let mut out = ColorVars::default();
        for p in params {
            let slot = match p.name {
                "Cs" => &mut out.cs,
                "Os" => &mut out.os,
                _ => continue,
            };
            if slot.is_some() {
                return Err(a.err(format!("\"{}\" given twice", p.name)));
            }
            let decl = match p.decl {
                Some(text) => parse_decl(text).map_err(|e| a.err(e))?,
                None => self.declared.get(p.name).cloned().unwrap_or(Decl {
                    class: Class::Varying,
                    ty: "color".into(),
                    len: 1,
                }),
            };
            if decl.ty != "color" || decl.len != 1 {
                return Err(a.err(format!(
                    "\"{}\" must be a color, found {}{}",
                    p.name,
                    decl.ty,
                    if decl.len > 1 {
                        format!("[{}]", decl.len)
                    } else {
                        String::new()
                    }
                )));
            }
            let n = counts.of(decl.class);
            let v = p.nums(a)?;
            if v.len() != 3 * n {
                return Err(a.err(format!(
                    "\"{}\" ({} color) needs {n} value{} ({} numbers), found {} numbers",
                    p.name,
                    decl.class.name(),
                    if n == 1 { "" } else { "s" },
                    3 * n,
                    v.len()
                )));
            }
            if let Some(k) = v.iter().position(|x| !(*x as f32).is_finite()) {
                return Err(a.err(format!(
                    "value {} of \"{}\" ({:e}) is not finite in the f32 range the renderer \
                     shades in",
                    k / 3,
                    p.name,
                    v[k]
                )));
            }
            let values = v.chunks_exact(3).map(DVec3::from_slice).collect();
            *slot = Some(ColorVar {
                class: decl.class,
                values,
            });
        }
        Ok(out)
    }
}

/// Where one sub-patch of a `PatchMesh` sits: its index (pu, pv) among nup x nvp patches,
/// its first control point (row r0, column c0) in the nu x nv mesh, and the wrap modes.
pub(super) struct MeshCell {
    pub(super) pu: usize,
    pub(super) pv: usize,
    pub(super) nup: usize,
    pub(super) nvp: usize,
    pub(super) r0: usize,
    pub(super) c0: usize,
    pub(super) nu: usize,
    pub(super) nv: usize,
    pub(super) uwrap: bool,
    pub(super) vwrap: bool,
}

impl ColorVar {
    /// The field over a single `Patch` (bicubic in bases `ub`, `vb`, or bilinear).
    pub(super) fn patch_field(&self, bicubic: bool, ub: &Basis, vb: &Basis) -> ColorField {
        let v = &self.values;
        match self.class {
            Class::Constant | Class::Uniform => ColorField::Flat(v[0]),
            Class::Varying | Class::FaceVarying => ColorField::Bilinear([v[0], v[1], v[2], v[3]]),
            Class::Vertex if bicubic => {
                ColorField::Bezier(block_to_bezier(&std::array::from_fn(|k| v[k]), ub, vb))
            }
            Class::Vertex => ColorField::Bilinear([v[0], v[1], v[2], v[3]]),
        }
    }

    /// The field over one sub-patch of a `PatchMesh`: uniform values one per sub-patch,
    /// varying values at the sub-patches' corners (the first row / column repeated where the
    /// mesh wraps), vertex values through the basis like the positions.
    pub(super) fn mesh_field(
        &self,
        m: &MeshCell,
        bicubic: bool,
        ub: &Basis,
        vb: &Basis,
    ) -> ColorField {
        let v = &self.values;
        match self.class {
            Class::Constant => ColorField::Flat(v[0]),
            Class::Uniform => ColorField::Flat(v[m.pv * m.nup + m.pu]),
            Class::Varying | Class::FaceVarying => {
                let nuv = m.nup + !m.uwrap as usize;
                let nvv = m.nvp + !m.vwrap as usize;
                let at = |r: usize, c: usize| v[(r % nvv) * nuv + c % nuv];
                let (r, c) = (m.pv, m.pu);
                ColorField::Bilinear([at(r, c), at(r, c + 1), at(r + 1, c), at(r + 1, c + 1)])
            }
            Class::Vertex => {
                let at = |r: usize, c: usize| v[(r % m.nv) * m.nu + c % m.nu];
                let (r0, c0) = (m.r0, m.c0);
                if bicubic {
                    let g = std::array::from_fn(|k| at(r0 + k / 4, c0 + k % 4));
                    ColorField::Bezier(block_to_bezier(&g, ub, vb))
                } else {
                    ColorField::Bilinear([
                        at(r0, c0),
                        at(r0, c0 + 1),
                        at(r0 + 1, c0),
                        at(r0 + 1, c0 + 1),
                    ])
                }
            }
        }
    }

    /// The fields over the Bezier patches of a `NuPatch`, in the order of
    /// `nurbs::to_bezier`: uniform values one per segment, varying values at the segments'
    /// corners, bilinear over each segment and cut to the span inside the parameter range.
    ///
    /// Vertex values are converted by that same function with the weights of `surf`'s
    /// (homogeneous) points, as `(w c, w)`, and each Bezier coefficient is divided by its
    /// Bezier weight: the colour net of the patch in the same homogeneous weighting as its
    /// points, interpolated as a polynomial bicubic field. For a polynomial surface (all
    /// w = 1) that is the exact NURBS interpolation of the values; for a rational one it is
    /// exact at the patch's corners and wherever the values are equal, and elsewhere differs
    /// from the rational interpolation sum(N w c) / sum(N w) by the variation of the weights
    /// (a choice: the colour table holds polynomial fields only).
    pub(super) fn nurbs_fields(
        &self,
        surf: &NuSurface,
        order: (usize, usize),
    ) -> Result<Vec<ColorField>, Error> {
        let v = &self.values;
        if self.class == Class::Vertex {
            let weighted: Vec<DVec4> = (v.iter().zip(surf.points))
                .map(|(c, p)| (*c * p.w).extend(p.w))
                .collect();
            let colors = NuSurface {
                points: &weighted,
                ..*surf
            };
            return Ok(nurbs::to_bezier(&colors)?
                .iter()
                .map(|h| ColorField::Bezier(from_homogeneous(h).0))
                .collect());
        }
        let segs_u = surf.nu + 1 - order.0;
        let segment = |knots: &[f64], order: usize, (i, a, b): (usize, f64, f64)| {
            let (t0, t1) = (knots[i], knots[i + 1]);
            let f = |x: f64| (x - t0) / (t1 - t0);
            (i + 1 - order, (f(a), f(b)))
        };
        Ok(nurbs::patch_spans(surf)?
            .into_iter()
            .map(|[us, vs]| {
                let (su, fu) = segment(surf.uknot, order.0, us);
                let (sv, fv) = segment(surf.vknot, order.1, vs);
                match self.class {
                    Class::Constant => ColorField::Flat(v[0]),
                    Class::Uniform => ColorField::Flat(v[sv * segs_u + su]),
                    _ => {
                        let at = |r: usize, c: usize| v[r * (segs_u + 1) + c];
                        ColorField::Bilinear([
                            at(sv, su),
                            at(sv, su + 1),
                            at(sv + 1, su),
                            at(sv + 1, su + 1),
                        ])
                        .restricted(fu, fv)
                    }
                }
            })
            .collect())
    }
}
