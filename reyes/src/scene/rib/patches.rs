//! The patch primitives (`Patch`, `PatchMesh`, `NuPatch`): their arguments, the conversion
//! of each piece to a bicubic Bezier patch (through the current `Basis` or the NURBS spans,
//! rational for `NuPatch` "Pw") and its transformation to camera space ([`Interp::emit`],
//! which the quadrics share).

use super::lexer::shown;
use super::primvars::{ClassCounts, ColorVar, MeshCell};
use super::state::Interp;
use super::syntax::{Arg, Args, Param, Request};
use crate::scene::basis::{Basis, block_to_bezier};
use crate::scene::nurbs::{self, NuSurface};
use crate::scene::rational::from_homogeneous;
use crate::scene::{
    BilinearForm, ColorField, Patch, PatchNet, PatchSource, Primvars, SceneError,
    bilinear_to_bezier,
};
use glam::{DMat4, DVec3, DVec4};

/// The largest camera-space coordinate a control point may have: its cube, 1e36, is still
/// finite in f32 (at most 3.4e38), as the renderer's bound arithmetic needs.
pub(crate) const MAX_COORD: f64 = 1.0e12;

/// Most patches one frame may hold, 2^22 (4,194,304): a bilinear `Patch` is 176 bytes on the
/// host (its 4 corners and a shared transform, [`crate::scene::PatchNet`]), a bicubic one 568
/// (16 f64 points on the heap), a rational one 696 (and 16 weights), so a frame of bilinear
/// patches at the limit holds 738 MB before the GPU tables (a bicubic one 2.4 GB). The patch
/// past it is refused at its request's line (10 million identical bilinear patches in a 1.6 MB
/// gzip once took 4 GB and never finished). Frames stream: the limit is per frame, not per
/// file.
pub(crate) const MAX_FRAME_PATCHES: usize = 1 << 22;

#[cfg(test)]
thread_local! {
    /// The limit [`max_frame_patches`] gives in this thread's tests (a test lowers it rather
    /// than parse 4 million patches).
    pub(super) static TEST_MAX_FRAME_PATCHES: std::cell::Cell<usize> =
        const { std::cell::Cell::new(MAX_FRAME_PATCHES) };
}

/// [`MAX_FRAME_PATCHES`].
#[cfg(not(test))]
fn max_frame_patches() -> usize {
    MAX_FRAME_PATCHES
}

/// [`MAX_FRAME_PATCHES`], or what a test of this thread lowered it to.
#[cfg(test)]
fn max_frame_patches() -> usize {
    TEST_MAX_FRAME_PATCHES.with(|m| m.get())
}

/// What the patches of a frame share rather than each hold: the file name of their requests
/// and the transform of bilinear nets ([`PatchNet`]), each kept while it repeats.
#[derive(Default)]
pub(super) struct SharedParts {
    file: Option<(std::rc::Rc<str>, std::sync::Arc<str>)>,
    ctm: Option<std::sync::Arc<DMat4>>,
    displacement: Option<std::sync::Arc<crate::scene::Displacement>>,
}

impl SharedParts {
    /// `file` as the patches' shared name (one allocation per file read in a row).
    fn file(&mut self, file: &std::rc::Rc<str>) -> std::sync::Arc<str> {
        match &self.file {
            Some((rc, arc)) if std::rc::Rc::ptr_eq(rc, file) => arc.clone(),
            _ => {
                let arc: std::sync::Arc<str> = std::sync::Arc::from(&**file);
                self.file = Some((file.clone(), arc.clone()));
                arc
            }
        }
    }

    /// `d` shared (one allocation per displacement used in a row: the patches of a request,
    /// the instances of an object under transforms of one scale), so that the GPU's table
    /// holds it once (`frame::patch_info` writes one entry per allocation).
    fn displacement(
        &mut self,
        d: Option<std::sync::Arc<crate::scene::Displacement>>,
    ) -> Option<std::sync::Arc<crate::scene::Displacement>> {
        use crate::scene::DisplacementPattern as P;
        let d = d?;
        if let Some(old) = &self.displacement {
            let same_pattern = match (&old.pattern, &d.pattern) {
                (P::Bumps { frequency: a }, P::Bumps { frequency: b }) => a == b,
                (P::Map(a), P::Map(b)) => std::sync::Arc::ptr_eq(a, b),
                _ => false,
            };
            if same_pattern
                && old.amount.to_bits() == d.amount.to_bits()
                && old.bound.to_bits() == d.bound.to_bits()
            {
                return Some(old.clone());
            }
        }
        self.displacement = Some(d.clone());
        Some(d)
    }

    /// `ctm` shared (one allocation per transform used in a row).
    fn ctm(&mut self, ctm: &DMat4) -> std::sync::Arc<DMat4> {
        match &self.ctm {
            Some(m) if **m == *ctm => m.clone(),
            _ => {
                let m = std::sync::Arc::new(*ctm);
                self.ctm = Some(m.clone());
                m
            }
        }
    }
}

impl Interp {
    pub(super) fn geometry_ctm(&self, a: &Args) -> Result<DMat4, SceneError> {
        if self.world_to_camera.is_none() {
            return Err(a.err("geometry outside `WorldBegin` ... `WorldEnd`"));
        }
        let m = self.attrs.ctm;
        let affine =
            m.x_axis.w == 0.0 && m.y_axis.w == 0.0 && m.z_axis.w == 0.0 && m.w_axis.w != 0.0;
        if !affine {
            return Err(
                a.err("the current transformation is projective; patches need an affine one")
            );
        }
        Ok(m)
    }

    /// Transforms an object-space Bezier patch (Euclidean control points `cp`, weights `w`,
    /// as [`Patch`] holds them) to camera space and adds it. The transform is affine
    /// ([`Self::geometry_ctm`]), so transforming the Euclidean points with the weights kept
    /// is transforming the homogeneous points.
    pub(super) fn emit(
        &mut self,
        a: &Args,
        ctm: &DMat4,
        index: usize,
        cp: [DVec3; 16],
        w: [f64; 16],
    ) -> Result<(), SceneError> {
        self.emit_net(a, ctm, index, cp, w, None, None)
    }

    /// [`Self::emit`] of the bilinear patch of object-space `corners`, elevated to bicubic
    /// as `form` says: kept as its corners and the shared transform ([`PatchNet`]), which
    /// give the same camera-space points when asked for.
    pub(super) fn emit_bilinear(
        &mut self,
        a: &Args,
        ctm: &DMat4,
        index: usize,
        corners: [DVec3; 4],
        form: BilinearForm,
    ) -> Result<(), SceneError> {
        let cp = match form {
            BilinearForm::Patch => bilinear_to_bezier(corners),
            BilinearForm::Polygon => crate::scene::polygon::bilinear_patch(corners),
        };
        let bilinear = Some((corners, form));
        self.emit_net(a, ctm, index, cp, Patch::POLYNOMIAL, bilinear, None)
    }

    /// [`Self::emit`]; `bilinear` the corners the points `cp` were elevated from; `shared`
    /// the weights `w` as another patch holds them (an instance of an object shares them).
    /// While an object's primitive is built for its instances, its object-space nets are
    /// kept ([`super::instance`]).
    #[allow(clippy::too_many_arguments, reason = "one private path for every emit")]
    pub(super) fn emit_net(
        &mut self,
        a: &Args,
        ctm: &DMat4,
        index: usize,
        cp: [DVec3; 16],
        w: [f64; 16],
        bilinear: Option<([DVec3; 4], BilinearForm)>,
        shared: Option<&std::sync::Arc<[f64; 16]>>,
    ) -> Result<(), SceneError> {
        let max = max_frame_patches();
        if self.scene.patches.len() >= max {
            return Err(a.err(format!(
                "patch {index}: more than {max} patches in one frame (the limit \
                 on scene size: each holds 176 to 696 bytes on the host; split the scene into \
                 frames or coarser patches)"
            )));
        }
        let bad = |p: &DVec3| {
            if p.is_nan() { "NaN" } else { "infinite" }
        };
        if let Some((k, p)) = cp.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(a.err(format!(
                "patch {index}: control point {k} is {} ({})",
                bad(p),
                show_point(*p)
            )));
        }
        // Weights come positive from the conversions, the largest 1; the renderer's f32
        // must still see them positive.
        if let Some((k, x)) = w.iter().enumerate().find(|(_, x)| {
            let f = **x as f32;
            f.is_nan() || f <= 0.0
        }) {
            return Err(a.err(format!(
                "patch {index}: weight {k} is {x:e} relative to the largest, below the f32 \
                 range the renderer computes in (the weights span too wide a range)"
            )));
        }
        self.instancing.captured(ctm, index, &cp, bilinear);
        let cp = cp.map(|p| ctm.project_point3(p));
        if let Some((k, p)) = cp.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(a.err(format!(
                "patch {index}: control point {k} is {} in camera space ({})",
                bad(p),
                show_point(*p)
            )));
        }
        // The renderer computes in f32, and its bound arithmetic squares coordinates (and
        // cubes them: an edge cross product dotted with a point): a point finite in f32 may
        // still make those infinite, and a patch whose bound is infinite splits forever
        // (`Sphere 1e25` around the camera never finished).
        let beyond = |p: &DVec3| p.to_array().iter().any(|&x| !(x.abs() <= MAX_COORD));
        if let Some((k, p)) = cp.iter().enumerate().find(|(_, p)| beyond(p)) {
            return Err(a.err(format!(
                "patch {index}: control point {k} is {} in camera space, beyond the f32 range \
                 the renderer computes in (coordinates at most ±{MAX_COORD:e}, so that their \
                 squares and cubes stay finite)",
                show_point(*p),
            )));
        }
        let material = self.material();
        let displacement = self.displacement(ctm);
        let displacement = self.shared.displacement(displacement);
        let net = match (bilinear, shared) {
            (Some((corners, form)), _) => {
                let net = PatchNet::bilinear(corners, self.shared.ctm(ctm), form);
                debug_assert!(net.points() == cp);
                net
            }
            (None, Some(w)) => PatchNet::with_shared_weights(cp, Some(w.clone())),
            (None, None) => PatchNet::new(cp, w),
        };
        let file = self.shared.file(&a.req.file);
        self.scene.patches.push(Patch {
            net,
            material,
            flip_normal: self.attrs.orientation_rh,
            two_sided: self.attrs.two_sided,
            primvars: None,
            displacement,
            motion: self.attrs.motion(),
            trim: None,
            source: PatchSource {
                file,
                line: a.req.line,
                index: index as u32,
            },
        });
        Ok(())
    }

    /// [`Self::emit_bilinear`], then gives the new patch its primitive variables.
    pub(super) fn emit_bilinear_with(
        &mut self,
        a: &Args,
        ctm: &DMat4,
        index: usize,
        corners: [DVec3; 4],
        form: BilinearForm,
        (cs, os): (Option<ColorField>, Option<ColorField>),
    ) -> Result<(), SceneError> {
        self.emit_bilinear(a, ctm, index, corners, form)?;
        self.colour_last_patch(cs, os);
        Ok(())
    }

    /// [`Self::emit`], then gives the new patch its primitive variables.
    pub(super) fn emit_with(
        &mut self,
        a: &Args,
        ctm: &DMat4,
        index: usize,
        cp: [DVec3; 16],
        w: [f64; 16],
        (cs, os): (Option<ColorField>, Option<ColorField>),
    ) -> Result<(), SceneError> {
        self.emit(a, ctm, index, cp, w)?;
        self.colour_last_patch(cs, os);
        Ok(())
    }

    /// Gives the patch just emitted (`emit_net` pushes one whenever it succeeds) its colour
    /// fields.
    fn colour_last_patch(&mut self, cs: Option<ColorField>, os: Option<ColorField>) {
        if let Some(p) = self.scene.patches.last_mut() {
            p.primvars = Primvars { cs, os, n: None }.shared();
        }
    }

    pub(super) fn patch(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let kind = a.string("the patch type")?;
        let n = patch_points(a, kind)?;
        let params = a.params()?;
        let pts = self.positions(req, a, &params, n)?;
        let counts = ClassCounts {
            uniform: 1,
            varying: 4,
            vertex: n,
            facevarying: 4,
        };
        let vars = self.color_vars(a, &params, &counts)?;
        let ctm = self.geometry_ctm(a)?;
        check_points(a, 0, &pts, 0..n)?;
        let (ub, vb) = (&self.attrs.ubasis, &self.attrs.vbasis);
        let fields = vars.map(|v| v.patch_field(n == 16, ub, vb));
        if n == 4 {
            let corners = [pts[0], pts[1], pts[2], pts[3]];
            return self.emit_bilinear_with(a, &ctm, 0, corners, BilinearForm::Patch, fields);
        }
        let g: [DVec3; 16] = std::array::from_fn(|k| pts[k]);
        let cp = block_to_bezier(&g, ub, vb);
        self.emit_with(a, &ctm, 0, cp, Patch::POLYNOMIAL, fields)
    }

    pub(super) fn patch_mesh(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let kind = a.string("the patch type")?;
        let cubic = patch_points(a, kind)? == 16;
        const MAX: usize = 1 << 24;
        let nu = a.int("nu", 1, MAX)?;
        let uwrap = wrap_arg(a, "uwrap")?;
        let nv = a.int("nv", 1, MAX)?;
        let vwrap = wrap_arg(a, "vwrap")?;
        let params = a.params()?;
        let (ustep, vstep) = if cubic {
            (
                self.attrs.ubasis.step as usize,
                self.attrs.vbasis.step as usize,
            )
        } else {
            (1, 1)
        };
        let order = if cubic { 4 } else { 2 };
        let nup = mesh_patches(a, "u", nu, uwrap, ustep, order)?;
        let nvp = mesh_patches(a, "v", nv, vwrap, vstep, order)?;
        let pts = self.positions(req, a, &params, nu * nv)?;
        let varying = (nup + !uwrap as usize) * (nvp + !vwrap as usize);
        let counts = ClassCounts {
            uniform: nup * nvp,
            varying,
            vertex: nu * nv,
            facevarying: varying,
        };
        let vars = self.color_vars(a, &params, &counts)?;
        let ctm = self.geometry_ctm(a)?;
        let at = |r: usize, c: usize| pts[(r % nv) * nu + (c % nu)];
        let size = if cubic { 4 } else { 2 };
        for pv in 0..nvp {
            for pu in 0..nup {
                let (r0, c0) = (pv * vstep, pu * ustep);
                let used =
                    (0..size * size).map(|k| ((r0 + k / size) % nv) * nu + (c0 + k % size) % nu);
                check_points(a, pv * nup + pu, &pts, used)?;
                let corners = [
                    at(r0, c0),
                    at(r0, c0 + 1),
                    at(r0 + 1, c0),
                    at(r0 + 1, c0 + 1),
                ];
                let cell = MeshCell {
                    pu,
                    pv,
                    nup,
                    nvp,
                    r0,
                    c0,
                    nu,
                    nv,
                    uwrap,
                    vwrap,
                };
                let (ub, vb) = (&self.attrs.ubasis, &self.attrs.vbasis);
                let fields = vars.map(|v| v.mesh_field(&cell, cubic, ub, vb));
                let k = pv * nup + pu;
                if cubic {
                    let g = std::array::from_fn(|k| at(r0 + k / 4, c0 + k % 4));
                    let cp = block_to_bezier(&g, ub, vb);
                    self.emit_with(a, &ctm, k, cp, Patch::POLYNOMIAL, fields)?;
                } else {
                    let form = BilinearForm::Patch;
                    self.emit_bilinear_with(a, &ctm, k, corners, form, fields)?;
                }
            }
        }
        Ok(())
    }

    /// `NuPatch`: orders 2 to 4 in each direction, "P" or rational "Pw", the u and v
    /// subranges; one rational bicubic patch per non-empty knot span pair.
    pub(super) fn nu_patch(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        const MAX: usize = 1 << 24;
        let nu = a.int("nu", 1, MAX)?;
        let uorder = a.int("uorder", 1, MAX)?;
        let uknot = a.array("uknot")?;
        let umin = a.num("umin")?;
        let umax = a.num("umax")?;
        let nv = a.int("nv", 1, MAX)?;
        let vorder = a.int("vorder", 1, MAX)?;
        let vknot = a.array("vknot")?;
        let vmin = a.num("vmin")?;
        let vmax = a.num("vmax")?;
        let params = a.params()?;
        let mut surf = NuSurface {
            nu,
            nv,
            uorder,
            vorder,
            uknot,
            vknot,
            urange: (umin, umax),
            vrange: (vmin, vmax),
            points: &[],
        };
        // Orders, knots and ranges first: their errors explain count mismatches best.
        nurbs::span_count(&surf).map_err(|m| a.err(m))?;
        let (values, dim) = self.position_values(req, a, &params, nu * nv)?;
        let varying = (2 + nu - uorder) * (2 + nv - vorder);
        let counts = ClassCounts {
            uniform: (1 + nu - uorder) * (1 + nv - vorder),
            varying,
            vertex: nu * nv,
            facevarying: varying,
        };
        let vars = self.color_vars(a, &params, &counts)?;
        let ctm = self.geometry_ctm(a)?;
        let pts: Vec<DVec4> = if dim == 4 {
            let pts: Vec<DVec4> = values.chunks_exact(4).map(DVec4::from_slice).collect();
            // RenderMan's "Pw" is homogeneous: the point is (x/w, y/w, z/w).
            if let Some(k) = pts.iter().position(|p| !(p.w > 0.0 && p.w.is_finite())) {
                let p = pts[k];
                return Err(a.err(format!(
                    "point {k} of \"Pw\" [{} {} {} {}] has weight w = {}: weights must be \
                     positive and finite",
                    p.x, p.y, p.z, p.w, p.w
                )));
            }
            pts
        } else {
            values
                .chunks_exact(3)
                .map(|c| DVec3::from_slice(c).extend(1.0))
                .collect()
        };
        surf.points = &pts;
        let patches = nurbs::to_bezier(&surf).map_err(|m| a.err(m))?;
        if let Some(k) = pts.iter().position(|p| !p.is_finite()) {
            // Name the first patch the bad point reaches (conversion spreads it to those).
            let name = if dim == 4 { "Pw" } else { "P" };
            let p = pts[k].truncate();
            return Err(
                match patches
                    .iter()
                    .position(|cp| cp.iter().any(|p| !p.is_finite()))
                {
                    Some(i) => a.err(format!(
                        "patch {i}: point {k} of \"{name}\" is {} ({})",
                        nonfinite(p),
                        show_point(p)
                    )),
                    None => a.err(format!(
                        "point {k} of \"{name}\" is {} ({})",
                        nonfinite(p),
                        show_point(p)
                    )),
                },
            );
        }
        // The colour fields need the points' weights (vertex values are weighted like them).
        let fields = |v: &Option<ColorVar>| match v {
            Some(v) => v
                .nurbs_fields(&surf, (uorder, vorder))
                .map(|f| f.into_iter().map(Some).collect()),
            None => Ok(Vec::new()),
        };
        let mut cs: Vec<Option<ColorField>> = fields(&vars.cs).map_err(|m| a.err(m))?;
        let mut os: Vec<Option<ColorField>> = fields(&vars.os).map_err(|m| a.err(m))?;
        let n = patches.len();
        cs.resize(n, None);
        os.resize(n, None);
        // `TrimCurve`: each patch's span of the surface's parameter space, where the loops are.
        let trims = match self.attrs.trim {
            Some(_) => self.patch_trims(&nurbs::patch_spans(&surf).map_err(|m| a.err(m))?),
            None => Vec::new(),
        };
        for (i, ((h, cs), os)) in patches.iter().zip(cs).zip(os).enumerate() {
            let (cp, w) = from_homogeneous(h);
            self.emit_with(a, &ctm, i, cp, w, (cs, os))?;
            if let (Some(t), Some(p)) = (trims.get(i), self.scene.patches.last_mut()) {
                p.trim = Some(t.clone());
            }
        }
        Ok(())
    }

    /// The numbers of the position parameter ("P": 3 per point, "Pw": 4) of a primitive of
    /// `n` points, and that count per point; "Cs" and "Os" are left to `color_vars`, other
    /// parameters are ignored with a warning.
    fn position_values<'p>(
        &mut self,
        req: &Request,
        a: &Args,
        params: &'p [Param],
        n: usize,
    ) -> Result<(&'p [f64], usize), SceneError> {
        let mut pos = None;
        for p in params {
            match p.name {
                "P" | "Pw" if pos.is_some() => {
                    return Err(a.err("more than one position parameter"));
                }
                "P" | "Pw" => pos = Some(p),
                "Pz" => return Err(a.err("\"Pz\" height fields are not supported")),
                // Read by `color_vars`.
                "Cs" | "Os" => {}
                other => self.ignored_param(req, other),
            }
        }
        let p = pos.ok_or_else(|| a.err("missing the \"P\" parameter"))?;
        let dim = if p.name == "P" { 3 } else { 4 };
        let v = p.nums(a)?;
        if v.len() != n * dim {
            return Err(a.err(format!(
                "\"{}\" needs {} numbers ({n} points), found {}",
                p.name,
                n * dim,
                v.len()
            )));
        }
        Ok((v, dim))
    }

    /// The "P" (or non-rational "Pw") control points of a `Patch` or `PatchMesh`; other
    /// parameters are ignored with a warning.
    pub(super) fn positions(
        &mut self,
        req: &Request,
        a: &Args,
        params: &[Param],
        n: usize,
    ) -> Result<Vec<DVec3>, SceneError> {
        let (v, dim) = self.position_values(req, a, params, n)?;
        let mut out = Vec::with_capacity(n);
        for (k, c) in v.chunks_exact(dim).enumerate() {
            if dim == 4 && c[3] != 1.0 {
                return Err(a.err(format!(
                    "point {k} of \"Pw\" has w = {}: rational `{}` is not supported (w must be \
                     1; rational `NuPatch` is)",
                    c[3], req.name
                )));
            }
            out.push(DVec3::new(c[0], c[1], c[2]));
        }
        Ok(out)
    }
}

/// A point for an error message: `[x, y, z]` as `DVec3` prints it, except that huge
/// coordinates (next to an overflow) are shown in exponent form instead of 300 digits.
pub(super) fn show_point(p: DVec3) -> String {
    let c = |v: f64| {
        if v.abs() < 1.0e15 || !v.is_finite() {
            format!("{v}")
        } else {
            format!("{v:e}")
        }
    };
    format!("[{}, {}, {}]", c(p.x), c(p.y), c(p.z))
}

pub(super) fn nonfinite(p: DVec3) -> &'static str {
    if p.is_nan() { "NaN" } else { "infinite" }
}

pub(super) fn bad_point(a: &Args, patch: usize, k: usize, p: DVec3) -> SceneError {
    a.err(format!(
        "patch {patch}: point {k} of \"P\" is {} ({})",
        nonfinite(p),
        show_point(p)
    ))
}

/// Fails on the first non-finite point among `used`, naming patch `patch`.
pub(super) fn check_points(
    a: &Args,
    patch: usize,
    pts: &[DVec3],
    used: impl Iterator<Item = usize>,
) -> Result<(), SceneError> {
    for k in used {
        if !pts[k].is_finite() {
            return Err(bad_point(a, patch, k, pts[k]));
        }
    }
    Ok(())
}

/// Number of control points per patch for a `Patch`/`PatchMesh` type.
pub(super) fn patch_points(a: &Args, kind: &str) -> Result<usize, SceneError> {
    match kind {
        "bicubic" => Ok(16),
        "bilinear" => Ok(4),
        _ => Err(a.err(format!(
            "patch type \"{}\" is not \"bicubic\" or \"bilinear\"",
            shown(kind)
        ))),
    }
}

pub(super) fn wrap_arg(a: &mut Args, what: &str) -> Result<bool, SceneError> {
    match a.string(what)? {
        "periodic" => Ok(true),
        "nonperiodic" => Ok(false),
        w => Err(a.err(format!(
            "{what} \"{}\" is not \"periodic\" or \"nonperiodic\"",
            shown(w)
        ))),
    }
}

/// Patches along one direction of a mesh (RenderMan rules).
pub(super) fn mesh_patches(
    a: &Args,
    dir: &str,
    n: usize,
    periodic: bool,
    step: usize,
    order: usize,
) -> Result<usize, SceneError> {
    let ok = if periodic {
        n.is_multiple_of(step)
    } else {
        n >= order && (n - order).is_multiple_of(step)
    };
    if !ok {
        let rule = if periodic {
            format!("a multiple of the step {step}")
        } else {
            format!("{order} + k * step {step}")
        };
        return Err(a.err(format!("n{dir} = {n} does not fit the basis: need {rule}")));
    }
    Ok(if periodic {
        n / step
    } else {
        (n - order) / step + 1
    })
}

/// One half of a `Basis` request: a name or 16 numbers, then the step.
pub(super) fn basis_arg(a: &mut Args, dir: &str) -> Result<Basis, SceneError> {
    let what = format!("the {dir} basis");
    let matrix = match a.peek() {
        Some(Arg::Str(_)) | Some(Arg::Strs(_)) => {
            let name = a.string(&what)?;
            Basis::by_name(name)
                .ok_or_else(|| a.err(format!("unknown basis \"{}\"", shown(name))))?
                .matrix
        }
        _ => {
            let v = a.fixed(16, &what)?;
            std::array::from_fn(|r| std::array::from_fn(|c| v[4 * r + c]))
        }
    };
    let step = a.int(&format!("the {dir} step"), 1, 1 << 16)? as u32;
    Ok(Basis { matrix, step })
}
