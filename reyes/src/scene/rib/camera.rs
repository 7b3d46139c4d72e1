//! The camera and image requests that frame the picture beyond `Projection` and `Format`:
//! `ScreenWindow`, `FrameAspectRatio`, `CropWindow`, `Projection "orthographic"`, and
//! `Imager` (RenderMan Interface Specification 3.2, section 4.1.1).
//!
//! The renderer projects camera space one way only: raster = (W/2 + F x/z, H/2 - F y/z) with
//! F = min(W, H) / 2 / tan(fov / 2). What these requests ask for is reached without a new
//! projection, at `WorldEnd`, from the finished world ([`Interp::frame_camera`]):
//!
//! - A screen window centred on the view whose shape is the image's (K-3D writes the field of
//!   view this way) is exactly a field of view: fov' = 2 atan(tan(fov / 2) / k), k the window's
//!   zoom against the default one. Nothing else changes.
//! - Any other window, and a crop window (a sub-rectangle of the image, rendered as an image of
//!   its own size), is the map raster = (a_x x/z + b_x, c_y - a_y y/z): an affine map of camera
//!   space that keeps z, x' = A x + B z, y' = C y + D z, applied to every patch, motion and
//!   light. The projection is then exact; shading (normals and light directions) is computed
//!   in the stretched or sheared space, which the warning says.
//! - `Projection "orthographic"` (screen x = camera x) moves the world far out along z, by
//!   Z = 1000 times the extent of its control points, and narrows the view to match: the
//!   projection divides by z' = Z + (z - the world's middle depth), so a point's raster offset
//!   from the image centre is off by its relative depth, at most 1/2000 of that offset (0.1 px
//!   on a 320x240 image). Depth (`--depth`) is then z' and the clipping planes are moved with
//!   the world.
//! - `Imager "background"` (RenderMan's standard imager, parameter "background", also read as
//!   "bgcolor" or "color"; white when not given) becomes [`Scene::background`]: the resolve
//!   composites every pixel over it and makes it opaque. `Imager "null"` turns it off. Any
//!   other imager shader given a "bgcolor" or "background" colour is read as that background
//!   imager under an exporter's own name (with a warning); one without is skipped with a warning
//!   naming what the image lacks.

use super::lexer::shown;
use super::patches::MAX_COORD;
use super::state::Interp;
use super::syntax::{Args, Request};
use crate::scene::{Light, RI_INFINITY, Scene, SceneError};
use glam::{DMat4, DVec3, DVec4};

/// How far out an orthographic world is moved, in multiples of its extent.
const ORTHO_DISTANCE: f64 = 1000.0;

/// The window options as given (`None`: RenderMan's default).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Framing {
    /// `ScreenWindow left right bottom top`.
    pub(super) screen_window: Option<[f64; 4]>,
    /// `FrameAspectRatio`.
    pub(super) frame_aspect: Option<f64>,
    /// `CropWindow xmin xmax ymin ymax` (NDC, 0..1; y down).
    pub(super) crop: Option<[f64; 4]>,
    /// `Projection "orthographic"`.
    pub(super) orthographic: bool,
}

impl Interp {
    /// `ScreenWindow`, `FrameAspectRatio`, `CropWindow`, `Imager`.
    pub(super) fn camera_request(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        match req.name.as_str() {
            "ScreenWindow" => {
                let v = a.fixed(4, "left, right, bottom, top")?;
                a.done()?;
                if v[0] == v[1] || v[2] == v[3] {
                    return Err(a.err(format!(
                        "the screen window [{} {} {} {}] has no area",
                        v[0], v[1], v[2], v[3]
                    )));
                }
                self.options.framing.screen_window = Some([v[0], v[1], v[2], v[3]]);
            }
            "FrameAspectRatio" => {
                let f = a.num("the frame aspect ratio")?;
                a.done()?;
                if !(f > 0.0 && f.is_finite()) {
                    return Err(a.err(format!(
                        "the frame aspect ratio must be positive, found {f}"
                    )));
                }
                self.options.framing.frame_aspect = Some(f);
            }
            "CropWindow" => {
                let v = a.fixed(4, "xmin, xmax, ymin, ymax")?;
                a.done()?;
                let ok = |lo: f64, hi: f64| (0.0..=1.0).contains(&lo) && lo < hi && hi <= 1.0;
                if !(ok(v[0], v[1]) && ok(v[2], v[3])) {
                    return Err(a.err(format!(
                        "the crop window [{} {} {} {}] must satisfy 0 <= min < max <= 1",
                        v[0], v[1], v[2], v[3]
                    )));
                }
                self.options.framing.crop =
                    (v != [0.0, 1.0, 0.0, 1.0]).then(|| [v[0], v[1], v[2], v[3]]);
            }
            _ => {
                let name = a.string("the imager name")?;
                let params = a.params()?;
                let param = (params.iter())
                    .find(|p| p.name == "bgcolor" || p.name == "background" || p.name == "color");
                let color = param.and_then(|p| p.vec3(a).ok());
                match name {
                    // RenderMan's standard imager (RI Spec 3.2, appendix A: its parameter
                    // "background" defaults to 1, white); other renderers name it "bgcolor".
                    "background" => {
                        let c = match param {
                            Some(p) => p.vec3(a)?,
                            None => DVec3::ONE,
                        };
                        if !c.is_finite() {
                            return Err(a.err(format!(
                                "the background colour [{} {} {}] is not finite",
                                c.x, c.y, c.z
                            )));
                        }
                        self.options.background = Some(c);
                        return Ok(());
                    }
                    "null" | "" => {
                        self.options.background = None;
                        return Ok(());
                    }
                    _ => {}
                }
                // Another imager shader: none runs. One given a background colour under the
                // standard shader's parameter names is the background imager exporters write
                // under their own names (K-3D's "sample_buster", MeshLab's "MOSAICbackground":
                // `Ci += (1 - alpha) * bgcolor`): composite over that colour, and say so.
                let bg = (params.iter())
                    .find(|p| p.name == "bgcolor" || p.name == "background")
                    .and_then(|p| p.vec3(a).ok())
                    .filter(|c| c.is_finite());
                let msg = match (bg, color) {
                    (Some(c), _) => {
                        self.options.background = Some(c);
                        format!(
                            "`Imager` \"{}\" is not built in: read as the standard background \
                             imager, compositing the image over its colour [{} {} {}]",
                            shown(name),
                            c.x,
                            c.y,
                            c.z
                        )
                    }
                    (None, Some(c)) => format!(
                        "skipped unsupported request `Imager` \"{}\": the background stays transparent black (alpha \
                         0) instead of [{} {} {}]; composite the image over that colour",
                        shown(name),
                        c.x,
                        c.y,
                        c.z
                    ),
                    (None, None) => format!(
                        "skipped unsupported request `Imager` \"{}\": no imager shader is applied to the image",
                        shown(name)
                    ),
                };
                self.warn_once(req, "Imager", &msg);
            }
        }
        Ok(())
    }

    /// Applies the frame's window options to the finished world `scene` (module doc): a field
    /// of view where that is exact, else a camera-space map; the image size of a crop window.
    /// Errors: the map takes a control point beyond the renderer's range.
    pub(super) fn frame_camera(
        &mut self,
        req: &Request,
        scene: &mut Scene,
    ) -> Result<(), SceneError> {
        let f = self.options.framing.clone();
        if f == Framing::default() {
            return Ok(());
        }
        let (w, h) = (scene.width as f64, scene.height as f64);
        let fa = f.frame_aspect.unwrap_or(w / h);
        let [l, r, b, t] = f.screen_window.unwrap_or(if fa >= 1.0 {
            [-fa, fa, -1.0, 1.0]
        } else {
            [-1.0, 1.0, -1.0 / fa, 1.0 / fa]
        });
        // The crop: rendered pixels ceil(W xmin) .. ceil(W xmax) - 1 (spec), likewise in y.
        let [x0, x1, y0, y1] = f.crop.map_or([0.0, w, 0.0, h], |c| {
            [
                (w * c[0]).ceil(),
                (w * c[1]).ceil(),
                (h * c[2]).ceil(),
                (h * c[3]).ceil(),
            ]
        });
        let (w2, h2) = ((x1 - x0).max(1.0), (y1 - y0).max(1.0));
        scene.width = w2 as u32;
        scene.height = h2 as u32;
        // Orthographic: the world's depth range and extent.
        let mut zshift = 0.0;
        let tan_half = if f.orthographic {
            let (lo, hi) = bounds(scene);
            let extent = (hi - lo).max_element();
            let extent = if extent > 0.0 { extent } else { 1.0 };
            let depth = ORTHO_DISTANCE * extent;
            zshift = depth - 0.5 * (lo.z + hi.z);
            1.0 / depth
        } else {
            (scene.camera.fov_deg.to_radians() / 2.0).tan()
        };
        // Wanted: raster x = a_x x/z + b_x, raster y = c_y - a_y y/z.
        let a_x = w / ((r - l) * tan_half);
        let b_x = -l * w / (r - l) - x0;
        let a_y = h / ((t - b) * tan_half);
        let c_y = t * h / (t - b) - y0;
        let focal = w2.min(h2) / 2.0 / (scene.camera.fov_deg.to_radians() / 2.0).tan();
        let (ma, mb) = (a_x / focal, (b_x - w2 / 2.0) / focal);
        let (mc, md) = (a_y / focal, (h2 / 2.0 - c_y) / focal);
        // Exporters write windows to 6 digits (K-3D: 0.666667 for 2/3): a window within 1e-5
        // of centred and of the image's shape is taken as one (1e-5 of the image's half
        // width: under 0.01 px at 16384 px).
        let tol = 1e-5;
        if !f.orthographic && (ma - mc).abs() <= tol * ma && mb.abs() <= tol && md.abs() <= tol {
            // A centred window of the image's shape: a field of view, exactly.
            let t2 = (scene.camera.fov_deg.to_radians() / 2.0).tan() / (0.5 * (ma + mc));
            scene.camera.fov_deg = 2.0 * t2.atan().to_degrees();
            return Ok(());
        }
        let shear = DMat4::from_cols(
            DVec4::new(ma, 0.0, 0.0, 0.0),
            DVec4::new(0.0, mc, 0.0, 0.0),
            DVec4::new(mb, md, 1.0, 0.0),
            DVec4::W,
        );
        let m = shear * DMat4::from_translation(DVec3::new(0.0, 0.0, zshift));
        if f.orthographic {
            let c = &mut scene.camera;
            c.near += zshift;
            c.far = (c.far + zshift).min(RI_INFINITY);
            if c.depth_of_field.is_some() {
                c.depth_of_field = None;
                self.warn_once(
                    req,
                    "orthographic dof",
                    "`DepthOfField` is not applied with `Projection \"orthographic\"`: the \
                     image is sharp everywhere",
                );
            }
        } else {
            let msg = format!(
                "the screen or crop window is not a centred view of the image's shape: it is \
                 rendered exactly, but shading (normals, light directions, highlights) is \
                 computed in camera space stretched by [{ma:.4}, {mc:.4}] and sheared by \
                 [{mb:.4}, {md:.4}]"
            );
            self.warn_once(req, "screen window map", &msg);
        }
        transform_scene(scene, &m).map_err(|e| SceneError::new(&req.file, req.line, e))
    }
}

/// The axis-aligned box of every control point (the origin for an empty world).
fn bounds(scene: &Scene) -> (DVec3, DVec3) {
    let mut pts = scene.patches.iter().flat_map(|p| p.cp());
    let Some(first) = pts.next() else {
        return (DVec3::ZERO, DVec3::ZERO);
    };
    pts.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)))
}

/// Maps the camera space of `scene` by the affine `m`: control points, motion, lights and the
/// world-to-camera transform.
fn transform_scene(scene: &mut Scene, m: &DMat4) -> Result<(), String> {
    let inv = m.inverse();
    for p in &mut scene.patches {
        for c in p.net.points_mut() {
            *c = m.transform_point3(*c);
            if !c.to_array().iter().all(|x| x.abs() <= MAX_COORD) {
                return Err(format!(
                    "the screen window takes a control point of patch {} (line {}) to [{} {} \
                     {}], beyond the renderer's range ±{MAX_COORD:e}",
                    p.source.index, p.source.line, c.x, c.y, c.z
                ));
            }
        }
        if let Some(mo) = &mut p.motion {
            **mo = *m * **mo * inv;
        }
    }
    for l in &mut scene.lights {
        match l {
            Light::Ambient { .. } => {}
            Light::Distant { dir, .. } => *dir = m.transform_vector3(*dir).normalize(),
            Light::Point { pos, .. } => *pos = m.transform_point3(*pos),
        }
    }
    scene.camera.world_to_camera = *m * scene.camera.world_to_camera;
    Ok(())
}

impl Interp {
    /// `CoordinateSystem "name"`: names the current transform; `CoordSysTransform "name"`
    /// makes a named one current ("camera" and "world" are predefined; "object" and
    /// "shader" are the current one).
    pub(super) fn coordinate_system(
        &mut self,
        req: &Request,
        a: &mut Args,
    ) -> Result<(), SceneError> {
        let name = a.string("the coordinate system name")?;
        a.done()?;
        if req.name == "CoordinateSystem" {
            let saved = (self.attrs.ctm, self.attrs.ctm_close);
            self.coordinate_systems.insert(name.to_string(), saved);
            return Ok(());
        }
        let (ctm, close) = match name {
            "object" | "shader" => return Ok(()),
            "camera" => (DMat4::IDENTITY, None),
            "world" => (
                self.world_to_camera.unwrap_or(DMat4::IDENTITY),
                self.world_to_camera_close,
            ),
            _ => match self.coordinate_systems.get(name) {
                Some(c) => *c,
                None => {
                    return Err(a.err(format!(
                        "no coordinate system \"{}\" is defined (`CoordinateSystem` names \
                         one; \"camera\", \"world\", \"object\" are predefined)",
                        shown(name)
                    )));
                }
            },
        };
        self.set_ctm(ctm);
        self.attrs.ctm_close = close;
        Ok(())
    }
}
