//! `Curves` and `Points` (RenderMan Interface Specification 3.2, section 5.5 and the
//! `RiPoints` appendix): their arguments, primitive variables and counts, turned into
//! camera-facing ribbons and discs ([`crate::scene::curves`]) emitted as camera-space patches.
//!
//! `Curves "linear"|"cubic" [nvertices] "nonperiodic"|"periodic"`: a cubic curve's segments
//! follow the current v basis and its step (`Basis`, as `PatchMesh` uses it): a nonperiodic
//! curve of n vertices has (n - 4) / vstep + 1 segments, a periodic one n / vstep; a linear
//! curve n - 1, or n when periodic. Counts per curve: uniform 1, varying the segments + 1
//! (periodic: the segments), vertex its vertices; constant 1 in all. `"width"` (predeclared
//! varying float; default 1) or `"constantwidth"` (constant float) is the ribbon's width in
//! object space, `"N"` (varying normal) turns the ribbon to lie perpendicular to it, `"Cs"` and
//! `"Os"` colour it. Varying values are linear along each segment, vertex values follow the
//! basis like the positions.
//!
//! `Points`: one disc per point of `"P"`, of diameter `"width"` (varying float, one per point)
//! or `"constantwidth"`, facing the eye and shaded as if its normal pointed at the eye.

use super::lexer::shown;
use super::primvars::{Class, ClassCounts, ColorVar, Decl, parse_decl};
use super::state::Interp;
use super::syntax::{Args, Param, Request};
use crate::scene::basis::Mat4x4;
use crate::scene::curves::{self, Along, Segment, View, WidthScale};
use crate::scene::{ColorField, Patch, SceneError};
use glam::{DMat3, DMat4, DVec3};

/// Most curves or vertices of one request (indices stay well inside u32 patch numbering).
const MAX_COUNT: usize = 1 << 28;

/// Where one curve's values sit among the request's.
struct Curve {
    /// Its vertices: `"P"` and vertex values from `vertex0`.
    vertices: usize,
    vertex0: usize,
    /// Its varying values: `varying` of them from `varying0`.
    varying: usize,
    varying0: usize,
    segments: usize,
}

/// The curves of a request, checked against the type, wrap mode and basis step.
fn layout(
    a: &Args,
    nvertices: &[f64],
    cubic: bool,
    periodic: bool,
    step: usize,
) -> Result<Vec<Curve>, SceneError> {
    if nvertices.is_empty() || nvertices.len() > MAX_COUNT {
        return Err(a.err(format!(
            "nvertices: {} curves (need 1..={MAX_COUNT})",
            nvertices.len()
        )));
    }
    let (mut vertex0, mut varying0) = (0usize, 0usize);
    let mut out = Vec::with_capacity(nvertices.len());
    for (i, &n) in nvertices.iter().enumerate() {
        if !(n.fract() == 0.0 && n >= 1.0 && n <= MAX_COUNT as f64) {
            return Err(a.err(format!(
                "nvertices: curve {i} has {n} vertices, not an integer in 1..={MAX_COUNT}"
            )));
        }
        let nv = n as usize;
        let segments = match (cubic, periodic) {
            (false, false) if nv >= 2 => Some(nv - 1),
            (false, true) if nv >= 2 => Some(nv),
            (true, false) if nv >= 4 && (nv - 4).is_multiple_of(step) => Some((nv - 4) / step + 1),
            (true, true) if nv >= 4 && nv.is_multiple_of(step) => Some(nv / step),
            _ => None,
        };
        let Some(segments) = segments else {
            let need = match (cubic, periodic) {
                (false, _) => "at least 2".to_string(),
                (true, false) => format!("4 + k * vstep (vstep {step} of the current `Basis`)"),
                (true, true) => format!("at least 4 and a multiple of vstep {step}"),
            };
            return Err(a.err(format!(
                "nvertices: curve {i} has {nv} vertices; a {} {} curve needs {need}",
                if periodic { "periodic" } else { "nonperiodic" },
                if cubic { "cubic" } else { "linear" },
            )));
        };
        let varying = if periodic { segments } else { segments + 1 };
        out.push(Curve {
            vertices: nv,
            vertex0,
            varying,
            varying0,
            segments,
        });
        vertex0 += nv;
        varying0 += varying;
        if vertex0 > MAX_COUNT {
            return Err(a.err(format!(
                "nvertices add up to more than the reader's limit {MAX_COUNT}"
            )));
        }
    }
    Ok(out)
}

/// A primitive variable as given: its class and values.
struct Var<T> {
    class: Class,
    values: Vec<T>,
}

/// How the values of one curve's segment are found (the curve, the segment, the basis).
struct At<'c> {
    curve: &'c Curve,
    segment: usize,
    cubic: bool,
    step: usize,
    /// Basis to Bezier (`Basis::to_bezier`) of the v basis.
    to_bezier: &'c Mat4x4,
}

impl<T> Var<T>
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    /// The values along one segment as cubic Bezier coefficients.
    fn along(&self, curve_index: usize, at: &At) -> Along<T> {
        let (c, s) = (at.curve, at.segment);
        let v = &self.values;
        match self.class {
            Class::Constant => [v[0]; 4],
            Class::Uniform => [v[curve_index]; 4],
            Class::Varying | Class::FaceVarying => curves::linear(
                v[c.varying0 + s % c.varying],
                v[c.varying0 + (s + 1) % c.varying],
            ),
            Class::Vertex if !at.cubic => curves::linear(
                v[c.vertex0 + s % c.vertices],
                v[c.vertex0 + (s + 1) % c.vertices],
            ),
            Class::Vertex => {
                let g: [T; 4] =
                    std::array::from_fn(|k| v[c.vertex0 + (s * at.step + k) % c.vertices]);
                std::array::from_fn(|i| {
                    (1..4).fold(g[0] * at.to_bezier[i][0], |acc, j| {
                        acc + g[j] * at.to_bezier[i][j]
                    })
                })
            }
        }
    }
}

impl Var<DVec3> {
    /// The field over a ribbon piece covering [t0, t1] of a segment whose values are `along`
    /// (constant across the width, u).
    fn piece_field(&self, along: &Along<DVec3>, t: (f64, f64), cubic: bool) -> ColorField {
        let r = curves::restrict(along, t.0, t.1);
        match self.class {
            Class::Constant | Class::Uniform => ColorField::Flat(r[0]),
            Class::Vertex if cubic => ColorField::Bezier(std::array::from_fn(|k| r[k / 4])),
            _ => ColorField::Bilinear([r[0], r[0], r[3], r[3]]),
        }
    }
}

impl From<ColorVar> for Var<DVec3> {
    fn from(c: ColorVar) -> Self {
        Var {
            class: c.class,
            values: c.values,
        }
    }
}

impl Interp {
    /// A float or vector primitive variable of `Curves` / `Points`: its class from the inline
    /// declaration, else `Declare`, else `default`; its type one of `types`; `dim` numbers per
    /// value, finite in f32; the count its class needs.
    fn var_values<'q>(
        &self,
        a: &Args,
        p: &'q Param,
        default: Decl,
        types: &[&str],
        dim: usize,
        counts: &ClassCounts,
    ) -> Result<Var<&'q [f64]>, SceneError> {
        let decl = match p.decl {
            Some(text) => parse_decl(text).map_err(|e| a.err(e))?,
            None => self.declared.get(p.name).cloned().unwrap_or(default),
        };
        if !types.contains(&decl.ty.as_str()) || decl.len != 1 {
            return Err(a.err(format!(
                "\"{}\" must be a {}, found {}",
                p.name,
                types.join(" or "),
                decl.ty
            )));
        }
        let n = counts.of(decl.class);
        let v = p.nums(a)?;
        if v.len() != dim * n {
            return Err(a.err(format!(
                "\"{}\" ({} {}) needs {n} value{} ({} numbers), found {} numbers",
                p.name,
                decl.class.name(),
                decl.ty,
                if n == 1 { "" } else { "s" },
                dim * n,
                v.len()
            )));
        }
        if let Some(k) = v.iter().position(|x| !(*x as f32).is_finite()) {
            return Err(a.err(format!(
                "value {} of \"{}\" ({:e}) is not finite in the f32 range the renderer uses",
                k / dim,
                p.name,
                v[k]
            )));
        }
        Ok(Var {
            class: decl.class,
            values: v.chunks_exact(dim).collect(),
        })
    }

    /// The width of `Curves` / `Points` (`"width"`, else `"constantwidth"`, else 1) as half
    /// widths in object space.
    fn half_widths(
        &mut self,
        req: &Request,
        a: &Args,
        widths: &[Param],
        counts: &ClassCounts,
    ) -> Result<Var<f64>, SceneError> {
        let width = widths.iter().find(|p| p.name == "width");
        let constant = widths.iter().find(|p| p.name == "constantwidth");
        let (p, class) = match (width, constant) {
            (Some(w), Some(_)) => {
                self.ignored_param(req, "constantwidth");
                (w, Class::Varying)
            }
            (Some(w), None) => (w, Class::Varying),
            (None, Some(c)) => (c, Class::Constant),
            (None, None) => {
                return Ok(Var {
                    class: Class::Constant,
                    values: vec![0.5],
                });
            }
        };
        let decl = Decl {
            class,
            ty: "float".into(),
            len: 1,
        };
        let var = self.var_values(a, p, decl, &["float"], 1, counts)?;
        if let Some(k) = var.values.iter().position(|v| v[0] < 0.0) {
            return Err(a.err(format!(
                "value {k} of \"{}\" is negative ({})",
                p.name, var.values[k][0]
            )));
        }
        Ok(Var {
            class: var.class,
            values: var.values.iter().map(|v| 0.5 * v[0]).collect(),
        })
    }

    /// The view the ribbons and discs face.
    fn facing_view(&self) -> View {
        if self.options.framing.orthographic {
            View::Orthographic
        } else {
            View::Perspective
        }
    }

    /// Emits a camera-space patch of a curve or point: the current material and attributes,
    /// dPdu x dPdv as its outside (the geometry is built facing the eye, or along `"N"`),
    /// displacement scaled by the object's transform `ctm`, and the shading normal `n`.
    fn emit_facing(
        &mut self,
        a: &Args,
        ctm: &DMat4,
        index: usize,
        cp: [DVec3; 16],
        fields: (Option<ColorField>, Option<ColorField>),
        n: Option<ColorField>,
    ) -> Result<(), SceneError> {
        self.emit_with(a, &DMat4::IDENTITY, index, cp, Patch::POLYNOMIAL, fields)?;
        let displacement = self.displacement(ctm);
        if let Some(p) = self.scene.patches.last_mut() {
            p.flip_normal = false;
            p.displacement = displacement;
            if n.is_some() {
                let mut vars = p
                    .primvars
                    .take()
                    .map(std::sync::Arc::unwrap_or_clone)
                    .unwrap_or_default();
                vars.n = n;
                p.primvars = vars.shared();
            }
        }
        Ok(())
    }

    /// `Curves type [nvertices] wrap ...parameters`.
    pub(super) fn curves(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let kind = a.string("the curve type")?;
        let cubic = match kind {
            "linear" => false,
            "cubic" => true,
            _ => {
                return Err(a.err(format!(
                    "curve type \"{}\" is not \"linear\" or \"cubic\"",
                    shown(kind)
                )));
            }
        };
        let nvertices = a.array("nvertices")?;
        let periodic = super::patches::wrap_arg(a, "wrap")?;
        let basis = self.attrs.vbasis;
        let step = if cubic { basis.step as usize } else { 1 };
        let list = layout(a, nvertices, cubic, periodic, step)?;
        let all = a.params()?;
        let (normals, rest): (Vec<Param>, Vec<Param>) =
            all.into_iter().partition(|p| p.name == "N");
        let (widths, params): (Vec<Param>, Vec<Param>) = rest
            .into_iter()
            .partition(|p| matches!(p.name, "width" | "constantwidth"));
        let last = list.last().expect("at least one curve");
        let counts = ClassCounts {
            uniform: list.len(),
            varying: last.varying0 + last.varying,
            vertex: last.vertex0 + last.vertices,
            facevarying: last.varying0 + last.varying,
        };
        let pts = self.positions(req, a, &params, counts.vertex)?;
        if let Some(k) = pts.iter().position(|p| !p.is_finite()) {
            let p = pts[k];
            return Err(a.err(format!(
                "point {k} of \"P\" is {} ({})",
                super::patches::nonfinite(p),
                super::patches::show_point(p)
            )));
        }
        let vars = self.color_vars(a, &params, &counts)?;
        let (cs, os) = (vars.cs.map(Var::from), vars.os.map(Var::from));
        let half = self.half_widths(req, a, &widths, &counts)?;
        let ctm = self.geometry_ctm(a)?;
        let linear_part = DMat3::from_mat4(ctm);
        let normal = match normals.as_slice() {
            [] => None,
            [p] => {
                let decl = Decl {
                    class: Class::Varying,
                    ty: "normal".into(),
                    len: 1,
                };
                let v = self.var_values(a, p, decl, &["normal", "vector"], 3, &counts)?;
                let values = super::primvars::normals_to_camera(
                    a,
                    linear_part,
                    v.values.iter().map(|c| &c[..]),
                )?;
                Some(Var {
                    class: v.class,
                    values,
                })
            }
            _ => return Err(a.err("\"N\" given twice")),
        };
        let cam: Vec<DVec3> = pts.iter().map(|p| ctm.transform_point3(*p)).collect();
        let scale = WidthScale::new(linear_part);
        let view = self.facing_view();
        let to_bezier = basis.to_bezier();
        let mut index = 0usize;
        for (i, c) in list.iter().enumerate() {
            let vertex = |k: usize| cam[c.vertex0 + k % c.vertices];
            for s in 0..c.segments {
                let at = At {
                    curve: c,
                    segment: s,
                    cubic,
                    step,
                    to_bezier: &to_bezier,
                };
                let centre = if cubic {
                    // To Bezier in object space, then transformed: the hermite and power
                    // bases' control values include vectors, which the translation must
                    // not move.
                    let g: [DVec3; 4] =
                        std::array::from_fn(|k| pts[c.vertex0 + (s * step + k) % c.vertices]);
                    std::array::from_fn(|r| {
                        let b = (0..4).fold(DVec3::ZERO, |acc, j| acc + g[j] * to_bezier[r][j]);
                        ctm.transform_point3(b)
                    })
                } else {
                    curves::linear(vertex(s), vertex(s + 1))
                };
                let has_next = periodic || s + 1 < c.segments;
                let has_prev = periodic || s > 0;
                let chord = |k: usize| vertex(k + 1) - vertex(k);
                let joins = if cubic {
                    [None, None]
                } else {
                    [
                        has_prev.then(|| chord(s + c.vertices - 1)),
                        has_next.then(|| chord(s + 1)),
                    ]
                };
                let seg = Segment {
                    centre,
                    linear: !cubic,
                    half_width: half.along(i, &at),
                    normal: normal.as_ref().map(|n| n.along(i, &at)),
                    joins,
                };
                let seg_index = index;
                index += 1;
                if centre.iter().all(|p| *p == centre[0]) {
                    continue; // A segment of no length covers nothing.
                }
                let cs_along = cs.as_ref().map(|v| v.along(i, &at));
                let os_along = os.as_ref().map(|v| v.along(i, &at));
                for piece in seg.ribbon(view, &scale) {
                    let field = |v: &Option<Var<DVec3>>, al: &Option<Along<DVec3>>| {
                        v.as_ref()
                            .zip(al.as_ref())
                            .map(|(v, al)| v.piece_field(al, piece.t, cubic))
                    };
                    let fields = (field(&cs, &cs_along), field(&os, &os_along));
                    let n = normal
                        .as_ref()
                        .map(|v| v.piece_field(&seg.normal.unwrap(), piece.t, cubic));
                    self.emit_facing(a, &ctm, seg_index, piece.cp, fields, n)?;
                }
            }
        }
        Ok(())
    }

    /// `Points ...parameters`: one disc per point.
    pub(super) fn points(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let all = a.params()?;
        let (widths, params): (Vec<Param>, Vec<Param>) = all
            .into_iter()
            .partition(|p| matches!(p.name, "width" | "constantwidth"));
        // The points are counted from "P" itself: its length must be a whole number of them.
        let (n, dim, len) = super::primvars::counted_by_p(a, &params)?;
        if len % dim != 0 {
            let name = if dim == 3 { "P" } else { "Pw" };
            return Err(a.err(format!(
                "\"{name}\" needs a multiple of {dim} numbers ({dim} per point), found {len}"
            )));
        }
        if n > MAX_COUNT {
            return Err(a.err(format!(
                "{n} points, more than the reader's limit {MAX_COUNT}"
            )));
        }
        let counts = ClassCounts {
            uniform: 1,
            varying: n,
            vertex: n,
            facevarying: n,
        };
        let pts = self.positions(req, a, &params, n)?;
        let vars = self.color_vars(a, &params, &counts)?;
        let (cs, os) = (vars.cs.map(Var::from), vars.os.map(Var::from));
        let half = self.half_widths(req, a, &widths, &counts)?;
        let ctm = self.geometry_ctm(a)?;
        let scale = WidthScale::new(DMat3::from_mat4(ctm)).mean();
        let view = self.facing_view();
        let value = |v: &Var<DVec3>, k: usize| match v.class {
            Class::Constant | Class::Uniform => v.values[0],
            _ => v.values[k],
        };
        for (k, p) in pts.iter().enumerate() {
            if !p.is_finite() {
                return Err(a.err(format!(
                    "point {k} of \"P\" is {} ({})",
                    super::patches::nonfinite(*p),
                    super::patches::show_point(*p)
                )));
            }
            let h = match half.class {
                Class::Constant | Class::Uniform => half.values[0],
                _ => half.values[k],
            };
            let (patches, towards_eye) = curves::disc(ctm.transform_point3(*p), h * scale, view);
            for cp in patches {
                let fields = (
                    cs.as_ref().map(|v| ColorField::Flat(value(v, k))),
                    os.as_ref().map(|v| ColorField::Flat(value(v, k))),
                );
                let n = Some(ColorField::Flat(towards_eye));
                self.emit_facing(a, &ctm, k, cp, fields, n)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
#[path = "tests/curves.rs"]
mod tests;
