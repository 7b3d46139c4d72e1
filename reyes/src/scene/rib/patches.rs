//! The patch primitives (`Patch`, `PatchMesh`, `NuPatch`): their arguments, the conversion
//! of each piece to a bicubic Bezier patch (through the current `Basis` or the NURBS spans)
//! and its transformation to camera space.

use super::lexer::shown;
use super::state::Interp;
use super::syntax::{Arg, Args, Param, Request};
use crate::scene::basis::{Basis, block_to_bezier};
use crate::scene::nurbs::{self, NuSurface};
use crate::scene::{Patch, PatchSource, SceneError};
use glam::{DMat4, DVec3};

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

    /// Transforms an object-space Bezier patch to camera space and adds it.
    pub(super) fn emit(
        &mut self,
        a: &Args,
        ctm: &DMat4,
        index: usize,
        cp: [DVec3; 16],
    ) -> Result<(), SceneError> {
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
        let cp = cp.map(|p| ctm.project_point3(p));
        if let Some((k, p)) = cp.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(a.err(format!(
                "patch {index}: control point {k} is {} in camera space ({})",
                bad(p),
                show_point(*p)
            )));
        }
        // The renderer computes in f32: a point finite in f64 may not be there.
        let beyond_f32 = |p: &DVec3| p.to_array().iter().any(|&x| !(x as f32).is_finite());
        if let Some((k, p)) = cp.iter().enumerate().find(|(_, p)| beyond_f32(p)) {
            return Err(a.err(format!(
                "patch {index}: control point {k} is {} in camera space, beyond the f32 range \
                 (±{:e}) the renderer computes in",
                show_point(*p),
                f32::MAX
            )));
        }
        let material = self.material();
        self.scene.patches.push(Patch {
            cp,
            material,
            flip_normal: self.attrs.orientation_rh,
            two_sided: self.attrs.two_sided,
            source: PatchSource {
                file: a.req.file.to_string(),
                line: a.req.line,
                index: index as u32,
            },
        });
        Ok(())
    }

    pub(super) fn patch(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let kind = a.string("the patch type")?;
        let n = patch_points(a, kind)?;
        let params = a.params()?;
        let pts = self.positions(req, a, &params, n)?;
        let ctm = self.geometry_ctm(a)?;
        check_points(a, 0, &pts, 0..n)?;
        let cp = if n == 4 {
            bilinear_to_bezier([pts[0], pts[1], pts[2], pts[3]])
        } else {
            let g: [DVec3; 16] = std::array::from_fn(|k| pts[k]);
            block_to_bezier(&g, &self.attrs.ubasis, &self.attrs.vbasis)
        };
        self.emit(a, &ctm, 0, cp)
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
        let ctm = self.geometry_ctm(a)?;
        let at = |r: usize, c: usize| pts[(r % nv) * nu + (c % nu)];
        let size = if cubic { 4 } else { 2 };
        for pv in 0..nvp {
            for pu in 0..nup {
                let (r0, c0) = (pv * vstep, pu * ustep);
                let used =
                    (0..size * size).map(|k| ((r0 + k / size) % nv) * nu + (c0 + k % size) % nu);
                check_points(a, pv * nup + pu, &pts, used)?;
                let cp = if cubic {
                    let g = std::array::from_fn(|k| at(r0 + k / 4, c0 + k % 4));
                    block_to_bezier(&g, &self.attrs.ubasis, &self.attrs.vbasis)
                } else {
                    bilinear_to_bezier([
                        at(r0, c0),
                        at(r0, c0 + 1),
                        at(r0 + 1, c0),
                        at(r0 + 1, c0 + 1),
                    ])
                };
                self.emit(a, &ctm, pv * nup + pu, cp)?;
            }
        }
        Ok(())
    }

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
        for o in [uorder, vorder] {
            if o != nurbs::ORDER {
                return Err(a.err(format!(
                    "order {o} is not supported (only order 4, bicubic)"
                )));
            }
        }
        let params = a.params()?;
        let mut surf = NuSurface {
            nu,
            nv,
            uknot,
            vknot,
            urange: (umin, umax),
            vrange: (vmin, vmax),
            points: &[],
        };
        // Knots and ranges first: their errors explain count mismatches best.
        nurbs::span_count(&surf).map_err(|m| a.err(m))?;
        let pts = self.positions(req, a, &params, nu * nv)?;
        let ctm = self.geometry_ctm(a)?;
        surf.points = &pts;
        let patches = nurbs::to_bezier(&surf).map_err(|m| a.err(m))?;
        if let Some(k) = pts.iter().position(|p| !p.is_finite()) {
            // Name the first patch the bad point reaches (conversion spreads it to those).
            return Err(
                match patches
                    .iter()
                    .position(|cp| cp.iter().any(|p| !p.is_finite()))
                {
                    Some(i) => bad_point(a, i, k, pts[k]),
                    None => a.err(format!(
                        "point {k} of \"P\" is {} ({})",
                        nonfinite(pts[k]),
                        show_point(pts[k])
                    )),
                },
            );
        }
        for (i, cp) in patches.into_iter().enumerate() {
            self.emit(a, &ctm, i, cp)?;
        }
        Ok(())
    }

    /// The "P" (or non-rational "Pw") control points of a primitive; other parameters are
    /// ignored with a warning.
    pub(super) fn positions(
        &mut self,
        req: &Request,
        a: &Args,
        params: &[Param],
        n: usize,
    ) -> Result<Vec<DVec3>, SceneError> {
        let mut pos = None;
        for p in params {
            match p.name {
                "P" | "Pw" if pos.is_some() => {
                    return Err(a.err("more than one position parameter"));
                }
                "P" | "Pw" => pos = Some(p),
                "Pz" => return Err(a.err("\"Pz\" height fields are not supported")),
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
        let mut out = Vec::with_capacity(n);
        for (k, c) in v.chunks_exact(dim).enumerate() {
            if dim == 4 && c[3] != 1.0 {
                return Err(a.err(format!(
                    "point {k} of \"Pw\" has w = {}: rational patches are not supported (w must be 1)",
                    c[3]
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

/// Elevates a bilinear patch (corners (0,0), (1,0), (0,1), (1,1)) to bicubic Bezier.
pub(super) fn bilinear_to_bezier(c: [DVec3; 4]) -> [DVec3; 16] {
    std::array::from_fn(|k| {
        let (u, v) = ((k % 4) as f64 / 3.0, (k / 4) as f64 / 3.0);
        c[0].lerp(c[1], u).lerp(c[2].lerp(c[3], u), v)
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
