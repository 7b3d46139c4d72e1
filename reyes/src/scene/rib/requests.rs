//! The one dispatch over request names, grouped as the RenderMan Interface Specification
//! groups them: options, transformations, blocks (frame, world, attribute, transform),
//! attributes, shading, geometry.
//!
//! Range checks of values the renderer limits (image size, pixel samples, clipping) happen
//! here, where the error can name the file and line, not later in the renderer.

use super::lexer::shown;
use super::patches::basis_arg;
use super::quadrics::QUADRICS;
use super::state::{Block, Interp};
use super::syntax::{Args, Request};
use crate::scene::{MAX_IMAGE_SIDE, MAX_PIXEL_SAMPLES};
use crate::scene::{RI_EPSILON, SceneError};
use glam::{DMat4, DVec3};

/// Requests the interpreter understands; any other name is skipped with one warning.
/// (`ReadArchive`, `ObjectBegin`, `ObjectInstance` and motion blocks are handled by the
/// reading loop.)
pub(super) const KNOWN: &[&str] = &[
    "Format",
    "PixelSamples",
    "ScreenWindow",
    "FrameAspectRatio",
    "CropWindow",
    "Imager",
    "CoordinateSystem",
    "CoordSysTransform",
    "Projection",
    "Clipping",
    "Display",
    "Identity",
    "Transform",
    "ConcatTransform",
    "Translate",
    "Rotate",
    "Scale",
    "Skew",
    "WorldBegin",
    "WorldEnd",
    "FrameBegin",
    "FrameEnd",
    "AttributeBegin",
    "AttributeEnd",
    "TransformBegin",
    "TransformEnd",
    "Basis",
    "Patch",
    "PatchMesh",
    "NuPatch",
    "Polygon",
    "GeneralPolygon",
    "PointsPolygons",
    "PointsGeneralPolygons",
    "SubdivisionMesh",
    "Curves",
    "Points",
    "Sphere",
    "Cylinder",
    "Cone",
    "Disk",
    "Torus",
    "Paraboloid",
    "Hyperboloid",
    "Color",
    "Opacity",
    "Surface",
    "Displacement",
    "Attribute",
    "LightSource",
    "Sides",
    "Orientation",
    "ReverseOrientation",
    "ObjectBegin",
    "ObjectEnd",
    "ObjectInstance",
    "MotionBegin",
    "MotionEnd",
    "Shutter",
    "DepthOfField",
    "ReadArchive",
    "MakeShadow",
    "TrimCurve",
    "Declare",
];

/// A matrix's perspective terms (its last column in RIB's row-vector form) at most this
/// fraction of its homogeneous scale are round-off (a Maya export writes 1e-12 there): the
/// matrix is taken as affine. A point p then gets w = 1 + e.p with |e| <= 1e-9, which moves
/// a point 1e3 units from the origin by at most 1e-6 of its distance.
pub(super) const PROJECTIVE_ROUNDOFF: f64 = 1e-9;

/// `m` with perspective terms within [`PROJECTIVE_ROUNDOFF`] set to exactly 0.
pub(super) fn affine_within_roundoff(mut m: DMat4) -> DMat4 {
    let s = m.w_axis.w.abs();
    let tiny = |x: f64| x != 0.0 && x.abs() <= PROJECTIVE_ROUNDOFF * s;
    if [m.x_axis.w, m.y_axis.w, m.z_axis.w]
        .iter()
        .all(|&x| x == 0.0 || tiny(x))
    {
        m.x_axis.w = 0.0;
        m.y_axis.w = 0.0;
        m.z_axis.w = 0.0;
    }
    m
}

impl Interp {
    pub(super) fn request(&mut self, req: &Request) -> Result<(), SceneError> {
        let mut a = Args::new(req);
        let a = &mut a;
        match req.name.as_str() {
            "Format" | "PixelSamples" | "Projection" | "Clipping" => self.option(req, a),
            "Display" => self.display(req, a),
            "ScreenWindow" | "FrameAspectRatio" | "CropWindow" | "Imager" => {
                self.camera_request(req, a)
            }
            "CoordinateSystem" | "CoordSysTransform" => self.coordinate_system(req, a),
            "Identity" | "Transform" | "ConcatTransform" | "Translate" | "Rotate" | "Scale"
            | "Skew" => self.transform(req, a),
            "FrameBegin" => self.frame_begin(req, a),
            "FrameEnd" => self.frame_end(req, a),
            "WorldBegin" => self.world_begin(req, a),
            "WorldEnd" => self.world_end(req, a),
            "AttributeBegin" | "TransformBegin" => {
                a.done()?;
                let block = if req.name == "AttributeBegin" {
                    Block::Attribute
                } else {
                    Block::Transform
                };
                self.push(block, req)
            }
            "AttributeEnd" => {
                a.done()?;
                self.pop(Block::Attribute, req)
            }
            "TransformEnd" => {
                a.done()?;
                self.pop(Block::Transform, req)
            }
            "Basis" | "Color" | "Opacity" | "Sides" | "Orientation" | "ReverseOrientation" => {
                self.attribute(req, a)
            }
            "Declare" => self.declare(req, a),
            "Surface" => self.surface(req, a),
            "Displacement" => self.displacement_request(req, a),
            "Attribute" => self.attribute_request(req, a),
            "LightSource" => self.light(req, a),
            "Patch" => self.patch(req, a),
            "PatchMesh" => self.patch_mesh(req, a),
            "NuPatch" => self.nu_patch(req, a),
            "Polygon" | "GeneralPolygon" | "PointsPolygons" | "PointsGeneralPolygons" => {
                self.polygon_request(req, a)
            }
            "SubdivisionMesh" => self.subdivision_mesh(req, a),
            "Curves" => self.curves(req, a),
            "Points" => self.points(req, a),
            name if QUADRICS.contains(&name) => self.quadric(req, a),
            "ObjectEnd" => Err(a.err("without a matching `ObjectBegin`")),
            "MotionBegin" => self.motion_begin(req, a),
            "MotionEnd" => self.motion_end(req),
            "Shutter" | "DepthOfField" => self.lens_option(req, a),
            "TrimCurve" => self.trim_curve(a),
            "MakeShadow" => {
                self.make_shadow(req);
                Ok(())
            }
            // The RIB version every exporter writes first: nothing to do, nothing to warn.
            "version" => Ok(()),
            _ => {
                let mut msg = format!("skipped unsupported request `{}`", shown(&req.name));
                if let Some(lacks) = skipped_effect(&req.name) {
                    msg = format!("{msg}: {lacks}");
                } else if let Some(known) = misspelt(&req.name) {
                    msg = format!("{msg} (did you mean `{known}`?)");
                }
                self.warn_once(req, &req.name, &msg);
                Ok(())
            }
        }
    }

    /// Format, PixelSamples, Projection, Clipping: options of the frame.
    fn option(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let side = MAX_IMAGE_SIDE as usize;
        match req.name.as_str() {
            "Format" => {
                let w = a.int("the x resolution", 1, side)?;
                let h = a.int("the y resolution", 1, side)?;
                let aspect = a.num("the pixel aspect ratio")?;
                a.done()?;
                // -1 means the default, 1, as other renderers read it.
                if aspect <= 0.0 && aspect != -1.0 {
                    return Err(a.err(format!(
                        "the pixel aspect ratio must be positive (or -1: the default), found \
                         {aspect}"
                    )));
                }
                if aspect > 0.0 && aspect != 1.0 {
                    let msg = format!(
                        "pixel aspect ratio {aspect} is rendered as 1 (square pixels): the \
                         image is stretched by {aspect} horizontally against what was meant"
                    );
                    self.warn_once(req, "pixel aspect", &msg);
                }
                self.options.width = w as u32;
                self.options.height = h as u32;
            }
            "PixelSamples" => {
                let mut s = [0u32; 2];
                let max = MAX_PIXEL_SAMPLES as f64;
                for (k, slot) in s.iter_mut().enumerate() {
                    let v = a.num(if k == 0 { "xsamples" } else { "ysamples" })?;
                    if !(v > 0.0 && v <= max) {
                        return Err(a.err(format!(
                            "sample count {v} is not in (0, {max}] (the renderer's limit)"
                        )));
                    }
                    *slot = v.ceil() as u32;
                }
                a.done()?;
                self.options.pixel_samples = (s[0], s[1]);
            }
            "Projection" => {
                if self.world_to_camera.is_some() {
                    return Err(a.err("not allowed inside `WorldBegin` ... `WorldEnd`"));
                }
                let name = a.string("the projection type")?;
                if name != "perspective" && name != "orthographic" {
                    return Err(a.err(format!(
                        "projection \"{}\" is not supported (only \"perspective\" and \
                         \"orthographic\")",
                        shown(name)
                    )));
                }
                self.options.framing.orthographic = name == "orthographic";
                for p in a.params()? {
                    match p.name {
                        "fov" => {
                            let fov = p.num(a)?;
                            if !(fov > 0.0 && fov < 180.0) {
                                return Err(a.err(format!("fov {fov} is not in (0, 180)")));
                            }
                            self.options.camera.fov_deg = fov;
                        }
                        other => self.ignored_param(req, other),
                    }
                }
                // The spec: the current transformation is reset after the projection.
                self.set_ctm(DMat4::IDENTITY);
            }
            _ => {
                let near = a.num("near")?;
                let far = a.num("far")?;
                a.done()?;
                // The spec: near >= RI_EPSILON, far > near.
                if !(near >= RI_EPSILON && far > near) {
                    return Err(a.err(format!(
                        "need {RI_EPSILON:e} <= near < far, found near {near} far {far}"
                    )));
                }
                self.options.camera.near = near;
                self.options.camera.far = far;
            }
        }
        Ok(())
    }

    /// Identity, Transform, ConcatTransform, Translate, Rotate, Scale, Skew.
    fn transform(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let m = match req.name.as_str() {
            "Identity" => {
                a.done()?;
                self.attrs.ctm_close = None;
                self.set_ctm(self.world_to_camera.unwrap_or(DMat4::IDENTITY));
                return Ok(());
            }
            "Transform" | "ConcatTransform" => {
                let v = a.fixed(16, "the matrix")?;
                a.done()?;
                // Row-major row-vector matrix == column-major column-vector matrix.
                let m = affine_within_roundoff(DMat4::from_cols_slice(&v));
                if req.name == "Transform" {
                    self.attrs.ctm_close = None;
                    self.set_ctm(self.world_to_camera.unwrap_or(DMat4::IDENTITY) * m);
                    return Ok(());
                }
                m
            }
            "Translate" => {
                let v = a.fixed(3, "the offset")?;
                a.done()?;
                DMat4::from_translation(DVec3::from_slice(&v))
            }
            "Rotate" => {
                let v = a.fixed(4, "angle and axis")?;
                a.done()?;
                crate::scene::rotation(v[0], DVec3::new(v[1], v[2], v[3]))
                    .ok_or_else(|| a.err("the rotation axis is zero"))?
            }
            "Skew" => {
                let v = a.fixed(7, "angle and two vectors")?;
                a.done()?;
                let (d1, d2) = (DVec3::new(v[1], v[2], v[3]), DVec3::new(v[4], v[5], v[6]));
                crate::scene::skew(v[0], d1, d2).ok_or_else(|| {
                    a.err(format!(
                        "no shear turns ({d1}) by {} degrees towards ({d2}): the second vector \
                         is zero, the first lies along it, or the turn reaches it",
                        v[0]
                    ))
                })?
            }
            _ => {
                let v = a.fixed(3, "the scale factors")?;
                a.done()?;
                DMat4::from_scale(DVec3::from_slice(&v))
            }
        };
        self.concat(m);
        Ok(())
    }

    /// Basis, Color, Opacity, Sides, Orientation, ReverseOrientation.
    fn attribute(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        match req.name.as_str() {
            "Basis" => {
                let ub = basis_arg(a, "u")?;
                let vb = basis_arg(a, "v")?;
                a.done()?;
                self.attrs.ubasis = ub;
                self.attrs.vbasis = vb;
            }
            "Color" | "Opacity" => {
                let v = a.fixed(3, "the color")?;
                a.done()?;
                if let Some(x) = v.iter().find(|x| x.abs() > f32::MAX as f64) {
                    return Err(a.err(format!(
                        "{x:e} is beyond the f32 range the renderer shades in"
                    )));
                }
                let c = DVec3::from_slice(&v);
                if req.name == "Color" {
                    self.attrs.color = c;
                } else {
                    self.attrs.opacity = c;
                }
                self.current_material = None;
            }
            "Sides" => {
                let s = a.num("the number of sides")?;
                a.done()?;
                self.attrs.two_sided = match s {
                    1.0 => false,
                    2.0 => true,
                    _ => return Err(a.err(format!("sides must be 1 or 2, found {s}"))),
                };
            }
            "Orientation" => {
                let o = a.string("the orientation")?;
                a.done()?;
                let coordsys_rh = self.attrs.ctm.determinant() < 0.0;
                self.attrs.orientation_rh = match o {
                    "lh" => false,
                    "rh" => true,
                    "outside" => coordsys_rh,
                    "inside" => !coordsys_rh,
                    _ => {
                        return Err(a.err(format!(
                            "orientation \"{}\" is not one of \"lh\", \"rh\", \"inside\", \"outside\"",
                            shown(o)
                        )));
                    }
                };
            }
            _ => {
                a.done()?;
                self.attrs.orientation_rh = !self.attrs.orientation_rh;
            }
        }
        Ok(())
    }

    pub(super) fn ignored_param(&mut self, req: &Request, name: &str) {
        let key = format!("{} \"{name}\"", req.name);
        let msg = format!("ignored parameter \"{}\" of `{}`", shown(name), req.name);
        self.warn_once(req, &key, &msg);
    }
}

/// What the image lacks when a commonly written request is skipped (the warning says it).
/// The request `name` probably meant: one it reads whose name is `name` but for case, or one
/// edit away (two for names of 8 letters or more), so that a typo does not pass as an
/// unsupported request. Other standard requests (`Hider`, `Option`) are not that close to
/// one the reader knows.
fn misspelt(name: &str) -> Option<&'static str> {
    closest(name, KNOWN)
}

/// The entry of `known` that `name` most likely misspells (case aside, or one edit from a name
/// of 4+ characters, two from one of 8+; Damerau-Levenshtein distance), for a warning's "did you
/// mean": requests, shader names, subdivision schemes.
pub(super) fn closest(name: &str, known: &[&'static str]) -> Option<&'static str> {
    let close = |k: &str| {
        let d = strsim::damerau_levenshtein(name, k);
        k.eq_ignore_ascii_case(name) || (name.len() >= 4 && d == 1) || (name.len() >= 8 && d == 2)
    };
    known.iter().copied().find(|k| close(k))
}

/// `msg` with " (did you mean `x`?)" where `name` misspells an entry of `known`.
pub(super) fn with_suggestion(msg: String, name: &str, known: &[&'static str]) -> String {
    match closest(name, known) {
        Some(k) => format!("{msg} (did you mean \"{k}\"?)"),
        None => msg,
    }
}

fn skipped_effect(name: &str) -> Option<&'static str> {
    Some(match name {
        "PixelFilter" => {
            "each pixel is the plain mean of its own samples (a box filter of width 1)"
        }
        "Exposure" => "no gain or gamma is applied (linear colour, sRGB-encoded on output)",
        "ShadingInterpolation" => "micropolygons are flat-shaded at their corners' mean colour",
        "Matte" => "the object is drawn as an ordinary surface, not a holdout",
        "Atmosphere" | "Interior" | "Exterior" => "no volume shading (the air is clear)",
        "Illuminate" => "lights stay on for every object",
        "ShadingRate" => {
            "micropolygons are `--mp-size` pixels on a side (default 1, a shading rate of 1) \
             whatever the file asks"
        }
        _ => return None,
    })
}
