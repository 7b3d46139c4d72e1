//! Scene input: RIB (a RenderMan subset), Newell's indexed teapot format, plain BPT, and a
//! built-in Utah teapot.
//!
//! Every loader produces the same [`Scene`]: bicubic Bezier patches whose control points are
//! already in camera space, so the renderer never needs to know about bases, NURBS or the
//! RenderMan transformation stack.
//!
//! Camera space is RenderMan's: left-handed, x right, y up, z forward (into the screen).

mod basis;
mod bpt;
pub(crate) mod curves;
mod displacement;
mod newell;
mod nurbs;
mod patch;
pub(crate) mod polygon;
mod primvars;
mod quadric;
pub(crate) mod rational;
mod rib;
mod sequence;
mod spin;
pub mod stacked;
pub mod subdiv;
mod teapot;
pub mod trim;

use glam::{DMat4, DVec3};

use std::path::Path;

pub use crate::error::SceneError;
pub use basis::Basis;
pub use bpt::parse_bpt;
pub use displacement::{
    DISPLACEMENT_NAMES, Displacement, DisplacementMap, DisplacementPattern, MAX_BUMPS_FREQUENCY,
    MAX_MAP_SIDE, MAX_MAP_TEXELS,
};
pub use newell::parse_newell;
pub(crate) use patch::{BilinearForm, bilinear_to_bezier};
pub use patch::{Patch, PatchNet, PatchSource};
pub use primvars::{ColorField, Primvars};
pub use rational::eval_rational_bezier;
pub use rib::{RibFrames, load_rib, open_rib, parse_rib, parse_rib_frames, stream_rib};
pub use sequence::{Display, FrameError, FrameRanges, FrameSequence, SceneFrame};
pub use spin::spin;
pub use teapot::{builtin_teapot, teapot_object_patches};

/// Largest image side accepted (the sample buffer must also fit the adapter; checked there).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Most samples per pixel in x and in y (RenderMan's `PixelSamples`).
pub const MAX_PIXEL_SAMPLES: u32 = 16;

/// RenderMan's `RI_EPSILON`, the default near clipping distance.
pub const RI_EPSILON: f64 = 1.0e-10;
/// RenderMan's `RI_INFINITY` (as in `ri.h`), the default far clipping distance. Finite on
/// purpose, so that projection maths built from it stays finite.
pub const RI_INFINITY: f64 = 1.0e38;

/// A perspective camera looking down +z of camera space.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Full field of view in degrees, spanning the SHORTER side of the image (RenderMan rule).
    pub fov_deg: f64,
    /// Near clipping distance along z, as given by `Clipping` (default [`RI_EPSILON`]).
    pub near: f64,
    /// Far clipping distance along z, as given by `Clipping` (default [`RI_INFINITY`]).
    pub far: f64,
    /// `Shutter open close`: the times the shutter opens and closes (default 0, 0). Motion
    /// blocks' times are on the same axis ([`Patch::motion`]).
    pub shutter: (f64, f64),
    /// `DepthOfField`: a thin lens; `None` (the default) for a pinhole camera.
    pub depth_of_field: Option<DepthOfField>,
    /// World to camera (the transform current at `WorldBegin`; identity for scenes without a
    /// world block): gives world axes in camera space, e.g. for [`spin`].
    pub world_to_camera: glam::DMat4,
}

/// RenderMan's `DepthOfField fstop focallength focaldistance`: a thin lens of focal length
/// `focal_length` and aperture diameter `focal_length / fstop`, focused at camera-space depth
/// `focal_distance` (both in camera-space units). A point at depth z is seen through the lens
/// as a disc (circle of confusion) of radius `focal_px * (focal_length / (2 fstop)) *
/// |1/focal_distance - 1/z|` pixels, `focal_px` the image's focal length in pixels
/// (docs/reyes.md, "Motion blur and depth of field").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthOfField {
    /// The f-number: aperture diameter = focal length / fstop; positive.
    pub fstop: f64,
    /// Positive, camera-space units.
    pub focal_length: f64,
    /// Depth of the plane in focus, camera-space units; positive.
    pub focal_distance: f64,
}

impl DepthOfField {
    /// The lens radius in camera-space units.
    pub fn lens_radius(&self) -> f64 {
        0.5 * self.focal_length / self.fstop
    }
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            fov_deg: 90.0,
            near: RI_EPSILON,
            far: RI_INFINITY,
            shutter: (0.0, 0.0),
            depth_of_field: None,
            world_to_camera: glam::DMat4::IDENTITY,
        }
    }
}

/// Everything the renderer needs for one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Image width in pixels (`Format`, default 640).
    pub width: u32,
    /// Image height in pixels (`Format`, default 480).
    pub height: u32,
    /// Samples per pixel in x and y (`PixelSamples`, default (2, 2)).
    pub pixel_samples: (u32, u32),
    /// Projection, clipping, shutter and lens.
    pub camera: Camera,
    /// Bicubic Bezier patches, control points in camera space.
    pub patches: Vec<Patch>,
    /// Shading parameters; `Patch::material` indexes this.
    pub materials: Vec<Material>,
    /// Lights in camera space. Empty when the input declares none: the renderer decides.
    pub lights: Vec<Light>,
    /// One message per kind of input that was skipped (request, shader or parameter),
    /// naming where it first appeared, e.g. "file:line: skipped unsupported request `Display`".
    pub warnings: Vec<String>,
    /// `Imager "background"`: the linear RGB colour the image is composited over (RenderMan's
    /// standard background imager: `Ci += (1 - alpha) * background; alpha = 1`), so every
    /// pixel comes out opaque; `None` (the default) leaves uncovered pixels transparent black.
    pub background: Option<DVec3>,
}

impl Default for Scene {
    fn default() -> Self {
        Scene {
            width: 640,
            height: 480,
            pixel_samples: (2, 2),
            camera: Camera::default(),
            patches: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            warnings: Vec::new(),
            background: None,
        }
    }
}

/// The three standard RenderMan surface shaders this renderer implements.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SurfaceKind {
    /// `constant`: the surface colour, unlit.
    Constant,
    /// `matte`: `Cs * (Ka ambient + Kd diffuse)`.
    Matte,
    /// `plastic`: matte plus a highlight in `specularcolor`, `Ks specular`.
    Plastic,
    /// RenderMan's `metal`: `Cs * (Ka ambient + Ks specular)`, no diffuse term, the highlight
    /// tinted by the surface colour.
    Metal,
}

/// A surface shader instance with its parameters plus the `Color`/`Opacity` attributes.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Which shader.
    pub kind: SurfaceKind,
    /// `Color` (Cs), default (1, 1, 1).
    pub color: DVec3,
    /// `Opacity` (Os), default (1, 1, 1).
    pub opacity: DVec3,
    /// `"Ka"`: weight of the ambient light.
    pub ka: f64,
    /// `"Kd"`: weight of the diffuse term.
    pub kd: f64,
    /// `"Ks"`: weight of the specular term.
    pub ks: f64,
    /// `"roughness"`: the highlight's exponent is `1 / roughness`.
    pub roughness: f64,
    /// `"specularcolor"` of plastic, default (1, 1, 1).
    pub specular_color: DVec3,
}

impl Material {
    /// Parameter defaults of RenderMan's standard shaders (constant, matte, plastic, metal);
    /// white and opaque.
    pub fn standard(kind: SurfaceKind) -> Material {
        let (ka, kd, ks) = match kind {
            SurfaceKind::Constant => (1.0, 0.0, 0.0),
            SurfaceKind::Matte => (1.0, 1.0, 0.0),
            SurfaceKind::Plastic => (1.0, 0.5, 0.5),
            SurfaceKind::Metal => (1.0, 0.0, 1.0),
        };
        Material {
            kind,
            color: DVec3::ONE,
            opacity: DVec3::ONE,
            ka,
            kd,
            ks,
            roughness: 0.1,
            specular_color: DVec3::ONE,
        }
    }
}

/// A light in camera space. `color` is already intensity * lightcolor.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// `ambientlight`: the same light on every point, from no direction.
    Ambient {
        /// Intensity times light colour, linear RGB.
        color: DVec3,
    },
    /// `dir` is a unit vector in the direction the light TRAVELS (from -> to).
    Distant {
        /// Intensity times light colour, linear RGB.
        color: DVec3,
        /// Unit direction of travel, camera space.
        dir: DVec3,
    },
    /// `pointlight`: from a position, falling off as 1 / distance².
    Point {
        /// Intensity times light colour, linear RGB.
        color: DVec3,
        /// Position, camera space.
        pos: DVec3,
    },
}

/// The input formats `load` understands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputFormat {
    /// RenderMan Interface Bytestream (`.rib`).
    Rib,
    /// Newell's indexed teapot format: patches as 16 vertex indices each, then the vertices.
    Newell,
    /// Plain BPT (Bezier patch text): per patch its degrees `3 3` and 16 control points.
    Bpt,
}

/// Centre of the axis-aligned bounding box of every control point, camera space; the origin
/// for a scene without patches.
pub fn scene_centre(scene: &Scene) -> DVec3 {
    let mut pts = scene.patches.iter().flat_map(|p| p.cp());
    let Some(first) = pts.next() else {
        return DVec3::ZERO;
    };
    let (lo, hi) = pts.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
    (lo + hi) / 2.0
}

/// Loads a scene of one image from a file: the first frame that can be rendered of
/// [`load_frames`], with a warning when the file has several.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_frames(path).map(FrameSequence::into_scene)
}

/// Loads every frame of a scene file. `.rib` is RIB and `.bpt` is BPT (also with `.gz`
/// added); any other name is recognised by content (a count line followed by 16 indices:
/// Newell; followed by "3 3": BPT; otherwise RIB). Gzip-compressed files are read
/// decompressed, whatever their name. Newell and BPT files make one frame. The first error
/// of any frame fails the load ([`stream_frames`] reads on past a broken frame).
pub fn load_frames(path: &Path) -> Result<FrameSequence, SceneError> {
    match stream_frames(path)? {
        FrameStream(Stream::Rib(r)) => r.collect_sequence(),
        FrameStream(Stream::One(frame, warnings)) => Ok(FrameSequence {
            frames: frame.into_iter().map(|f| *f).collect(),
            warnings,
        }),
    }
}

/// The frames of a scene file one at a time, as [`load_frames`] recognises it: a RIB file's
/// frames as [`RibFrames`] reads them (one frame's scene held at a time; an error in a frame
/// block is that frame's and the frames after it still come), a Newell or BPT file's one
/// frame. Errors: the file cannot be read; a Newell or BPT file's errors.
pub fn stream_frames(path: &Path) -> Result<FrameStream, SceneError> {
    let file = path.display().to_string();
    let cannot = |e: std::io::Error| SceneError::new(&file, 0, format!("cannot read file: {e}"));
    // The name without a `.gz`, and the first lines, decide the format.
    let named = match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("gz") => Path::new(path.file_stem().unwrap_or_default()),
        _ => path,
    };
    let mut head = Vec::new();
    std::io::Read::read_to_end(
        &mut std::io::Read::take(open_rib(path).map_err(cannot)?, 4096),
        &mut head,
    )
    .map_err(cannot)?;
    match detect_format(named, &String::from_utf8_lossy(&head)) {
        InputFormat::Rib => Ok(FrameStream(Stream::Rib(Box::new(stream_rib(path)?)))),
        format => {
            let mut bytes = Vec::new();
            std::io::Read::read_to_end(&mut open_rib(path).map_err(cannot)?, &mut bytes)
                .map_err(cannot)?;
            let text = String::from_utf8_lossy(&bytes);
            let scene = if format == InputFormat::Newell {
                framed_scene(parse_newell(&text, &file)?, teapot::NEWELL_FLIP)
            } else {
                framed_scene(parse_bpt(&text, &file)?, false)
            };
            Ok(FrameStream::single(scene))
        }
    }
}

/// A scene file's frames one at a time ([`stream_frames`]): an iterator of each frame or the
/// error that frame (or the file) has, in file order.
pub struct FrameStream(Stream);

enum Stream {
    Rib(Box<RibFrames<'static>>),
    One(Option<Box<SceneFrame>>, Vec<String>),
}

impl FrameStream {
    /// The stream of the one frame of `scene` (frame 1, no `Display`); its warnings become
    /// the stream's.
    pub fn single(scene: Scene) -> FrameStream {
        let mut seq = FrameSequence::single(scene);
        let frame = seq.frames.pop().map(Box::new);
        FrameStream(Stream::One(frame, seq.warnings))
    }

    /// The file's warnings given since the last call (one per kind of skipped input).
    pub fn take_warnings(&mut self) -> Vec<String> {
        match &mut self.0 {
            Stream::Rib(r) => r.take_warnings(),
            Stream::One(_, w) => std::mem::take(w),
        }
    }
}

impl Iterator for FrameStream {
    type Item = Result<SceneFrame, FrameError>;

    fn next(&mut self) -> Option<Self::Item> {
        match &mut self.0 {
            Stream::Rib(r) => r.next(),
            Stream::One(f, _) => f.take().map(|f| Ok(*f)),
        }
    }
}

/// Decides the format of a file from its extension, else from its first two lines.
pub fn detect_format(path: &Path, text: &str) -> InputFormat {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("rib") => return InputFormat::Rib,
        Some("bpt") => return InputFormat::Bpt,
        _ => {}
    }
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("");
    let second = lines.next().unwrap_or("");
    if first.parse::<u64>().is_err() {
        return InputFormat::Rib;
    }
    let fields: Vec<&str> = second
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|f| !f.is_empty())
        .collect();
    let all_ints = fields.iter().all(|f| f.parse::<u64>().is_ok());
    match fields.len() {
        16 if all_ints => InputFormat::Newell,
        2 if all_ints => InputFormat::Bpt,
        _ => InputFormat::Rib,
    }
}

/// An object-space bicubic Bezier patch with its origin, as read from a geometry-only file.
pub type ObjectPatch = ([DVec3; 16], PatchSource);

/// Places geometry-only input (Newell, BPT: z up, no camera) in front of the built-in
/// teapot's camera: the view direction of uteapot.rib, the bounding sphere filling the
/// shorter image side, uteapot.rib's lights and a plastic material. `flip_normal` is applied
/// to every patch (the file format, not the geometry, decides which side is outside).
pub fn framed_scene(patches: Vec<ObjectPatch>, flip_normal: bool) -> Scene {
    teapot::frame(patches, flip_normal)
}

/// RenderMan's `Rotate` (shared by the RIB interpreter and the built-in framing): angle in
/// degrees about `axis`, numerically the usual axis-angle matrix (+90 about z takes x to y),
/// which in a left-handed space turns clockwise when seen from +z looking at the origin.
/// `None` for a zero or non-finite axis or angle.
pub(crate) fn rotation(angle_deg: f64, axis: DVec3) -> Option<DMat4> {
    let len = axis.length();
    if len == 0.0 || !len.is_finite() || !angle_deg.is_finite() {
        return None;
    }
    Some(DMat4::from_axis_angle(axis / len, angle_deg.to_radians()))
}

/// RenderMan's `Skew angle dx1 dy1 dz1 dx2 dy2 dz2`: the shear along `d2` that turns `d1` by
/// `angle_deg` degrees towards `d2` (points move parallel to `d2` in proportion to their
/// component along `d1`'s part perpendicular to `d2`), as BMRT and Pixie build it: with `n` the
/// unit `d2` and `p` the unit part of `d1` across it, `x -> x + s (p . x) n`, `s = cot(theta -
/// angle) - cot(theta)`, `theta` the angle from `d2` to `d1`. `None` when `d2` is zero, `d1`
/// has no part across `d2`, a value is not finite, or the turn would reach (within 1e-9 of
/// `d1`'s length) or pass `d2`.
pub(crate) fn skew(angle_deg: f64, d1: DVec3, d2: DVec3) -> Option<DMat4> {
    let n = d2.try_normalize()?;
    let across = d1 - d1.dot(n) * n;
    let p = across.try_normalize()?;
    let (a_perp, a_par) = (d1.dot(p), d1.dot(n));
    let (sin, cos) = angle_deg.to_radians().sin_cos();
    let (rx, ry) = (a_perp * cos - a_par * sin, a_perp * sin + a_par * cos);
    // Reaching d2 within round-off (cos 90 degrees is 6e-17, not 0) is reaching it.
    if !(rx > 1e-9 * d1.length()) || !ry.is_finite() {
        return None;
    }
    let s = ry / rx - a_par / a_perp;
    // Column-vector form: I + s n p^T.
    let shear = glam::DMat3::from_cols(p.x * s * n, p.y * s * n, p.z * s * n);
    Some(DMat4::from_mat3(glam::DMat3::IDENTITY + shear))
}

/// Evaluates a bicubic Bezier patch (cp[4*v + u]) and its derivatives at (u, v).
/// Used by tests and handy for renderer-side checks.
pub fn eval_bezier(cp: &[DVec3; 16], u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let ((bu, du), (bv, dv)) = (rational::bernstein3(u), rational::bernstein3(v));
    let mut p = DVec3::ZERO;
    let mut pu = DVec3::ZERO;
    let mut pv = DVec3::ZERO;
    for j in 0..4 {
        for i in 0..4 {
            let c = cp[4 * j + i];
            p += c * (bu[i] * bv[j]);
            pu += c * (du[i] * bv[j]);
            pv += c * (bu[i] * dv[j]);
        }
    }
    (p, pu, pv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// The shared test data lives outside the repository (licence terms): read it in place.
    fn shared(rel: &str) -> PathBuf {
        let p = crate::shared_data_dir().join(rel);
        assert!(
            p.is_file(),
            "test data {} is missing (set REYES_SHARED_DATA to the shared data directory, or \
             keep it next to the repository as shared/data)",
            p.display()
        );
        p
    }

    /// Projects a camera-space point to raster coordinates (pixels, y down).
    fn raster(s: &Scene, p: DVec3) -> (f64, f64) {
        let short = s.width.min(s.height) as f64;
        let f = (short / 2.0) / (s.camera.fov_deg.to_radians() / 2.0).tan();
        (
            s.width as f64 / 2.0 + f * p.x / p.z,
            s.height as f64 / 2.0 - f * p.y / p.z,
        )
    }

    /// Fraction of sample points (u, v on a 5x5 grid per patch) whose outside normal (after
    /// `flip_normal`) points away from the line `axis_point` + t * `axis_dir`.
    fn outward_fraction(s: &Scene, axis_point: DVec3, axis_dir: DVec3) -> f64 {
        let (mut out, mut total) = (0usize, 0usize);
        for p in &s.patches {
            for a in 0..5 {
                for b in 0..5 {
                    let (pos, du, dv) =
                        eval_bezier(&p.cp(), 0.1 + 0.2 * a as f64, 0.1 + 0.2 * b as f64);
                    let mut n = du.cross(dv);
                    if p.flip_normal {
                        n = -n;
                    }
                    if n.length() < 1e-9 {
                        continue;
                    }
                    let d = pos - axis_point;
                    let radial = d - axis_dir * d.dot(axis_dir);
                    if radial.length() < 1e-6 {
                        continue;
                    }
                    total += 1;
                    if n.dot(radial) > 0.0 {
                        out += 1;
                    }
                }
            }
        }
        out as f64 / total as f64
    }

    #[test]
    fn uteapot_rib() {
        let s = load(&shared("rib/uteapot.rib")).unwrap();
        assert_eq!(s.patches.len(), 32);
        assert_eq!((s.width, s.height), (640, 400));
        assert_eq!(s.camera.fov_deg, 25.0);
        assert_eq!(s.pixel_samples, (2, 2));
        assert_eq!(s.lights.len(), 4);
        assert!(matches!(s.lights[0], Light::Ambient { .. }));
        assert_eq!(s.materials.len(), 1);
        let m = &s.materials[0];
        assert_eq!(m.kind, SurfaceKind::Plastic);
        assert_eq!(m.color, DVec3::new(1.0, 0.5, 0.3));
        assert_eq!((m.ka, m.kd, m.ks, m.roughness), (0.1, 0.05, 1.0, 0.1));
        assert_eq!(m.specular_color, DVec3::new(1.0, 0.4, 0.1));
        // Set -x and the unknown "wood2" surface (Display is read, not skipped).
        let w = s.warnings.join("\n");
        assert!(
            w.contains("uteapot.rib:1: skipped unsupported request `set`"),
            "{w}"
        );
        assert!(!w.contains("`Display`"), "{w}");
        assert!(w.contains("wood2"), "{w}");

        let (mut inside, mut n) = (0, 0);
        let (mut sx, mut sy) = (0.0, 0.0);
        for p in &s.patches {
            assert!(!p.flip_normal && p.two_sided && p.material == 0);
            for c in &p.cp() {
                assert!(c.z > 0.0, "control point behind the camera: {c}");
                let (x, y) = raster(&s, *c);
                n += 1;
                sx += x;
                sy += y;
                if (0.0..640.0).contains(&x) && (0.0..400.0).contains(&y) {
                    inside += 1;
                }
            }
        }
        assert!(
            inside as f64 > 0.9 * n as f64,
            "{inside} of {n} control points in view"
        );
        // Roughly centred.
        let (cx, cy) = (sx / n as f64, sy / n as f64);
        assert!(
            (cx - 320.0).abs() < 100.0 && (cy - 200.0).abs() < 100.0,
            "centre {cx},{cy}"
        );
        // The teapot is upright: its knob (top) is above its bottom on screen.
        let knob = raster(&s, s.patches[24].cp()[0]);
        let bottom = raster(&s, s.patches[0].cp()[15]);
        assert!(knob.1 < bottom.1, "knob {knob:?} bottom {bottom:?}");

        // Orientation. uteapot.rib leaves Orientation at its default ("outside", left-handed)
        // and has no mirroring transform, so RenderMan's normal is dPdu x dPdv unflipped.
        // Its data (a mirror image of Newell's) winds the other way round from Newell's, so
        // by the RenderMan rules the uteapot.rib body's outside normal points INTO the
        // teapot. That is RenderMan's answer for this file (it says `Sides 2`); the
        // built-in teapot is oriented outward (see teapot.rs).
        // Body patches: 0-3 (back) and 6-9 (front); 4, 5, 10, 11 are the rim's lip.
        let body = Scene {
            patches: [0, 1, 2, 3, 6, 7, 8, 9]
                .map(|i| s.patches[i].clone())
                .to_vec(),
            ..s.clone()
        };
        let (axis_p, axis_d) = world_axis_in_camera_uteapot();
        let f = outward_fraction(&body, axis_p, axis_d);
        assert!(f < 0.05, "uteapot.rib body outward fraction {f}");
    }

    /// uteapot.rib's world z axis in camera space, from its camera transform.
    fn world_axis_in_camera_uteapot() -> (DVec3, DVec3) {
        let m = DMat4::from_translation(DVec3::new(0.0, 0.0, 400.0))
            * rotation(-115.0, DVec3::X).unwrap()
            * rotation(19.0, DVec3::Z).unwrap()
            * DMat4::from_translation(DVec3::new(-25.0, 0.0, -50.0));
        (
            m.transform_point3(DVec3::ZERO),
            m.transform_vector3(DVec3::Z).normalize(),
        )
    }

    #[test]
    fn killeroo_rib() {
        let t = std::time::Instant::now();
        let s = load(&shared("rib/killeroo.rib")).unwrap();
        let elapsed = t.elapsed();
        assert_eq!(s.patches.len(), 11_532);
        assert_eq!((s.width, s.height), (796, 515));
        assert!((s.camera.fov_deg - 29.1143).abs() < 1e-12);
        assert_eq!((s.camera.near, s.camera.far), (30.258, 3025.8));
        assert_eq!(s.lights.len(), 1);
        assert_eq!(s.materials.len(), 1);
        assert_eq!(s.materials[0].kind, SurfaceKind::Matte);
        assert_eq!((s.materials[0].ka, s.materials[0].kd), (0.0, 1.0));
        // Its `Imager "background"` is applied (white: every pixel opaque).
        assert_eq!(s.background, Some(DVec3::ONE));
        let hits = (s.warnings.iter())
            .filter(|w| w.contains("skipped unsupported request `Option`"))
            .count();
        assert_eq!(hits, 1, "warnings for Option: {:?}", s.warnings);
        // Its displacement shader is not a built-in one; its "displacementbound" is read.
        for skipped in [
            "skipped unsupported displacement shader \"disp_textured\"",
            "skipped unsupported attribute \"render\"",
        ] {
            let hits = s.warnings.iter().filter(|w| w.contains(skipped)).count();
            assert_eq!(hits, 1, "warnings for {skipped}: {:?}", s.warnings);
        }
        assert!(s.patches.iter().all(|p| p.displacement.is_none()));
        // Its `Declare`s are read (and its declared shader parameters then ignored).
        assert!(!s.warnings.iter().any(|w| w.contains("Declare")));
        assert!(
            s.warnings
                .iter()
                .any(|w| w.ends_with("killeroo.rib:6: skipped unsupported request `Option`"))
        );
        // The camera transform mirrors (det < 0), so RenderMan's current orientation has
        // flipped to right-handed along with it.
        assert!(s.patches.iter().all(|p| p.flip_normal));
        // Rough check that this makes the model's outside face outward: most patch centres'
        // outside normals point away from the centroid (about 63%; 37% without the flip).
        let centroid = s.patches.iter().map(|p| p.cp()[5]).sum::<DVec3>() / s.patches.len() as f64;
        let outward = s
            .patches
            .iter()
            .filter(|p| {
                let (pos, du, dv) = eval_bezier(&p.cp(), 0.5, 0.5);
                let n = if p.flip_normal {
                    -du.cross(dv)
                } else {
                    du.cross(dv)
                };
                n.dot(pos - centroid) > 0.0
            })
            .count();
        assert!(
            outward as f64 > 0.55 * s.patches.len() as f64,
            "{outward} outward"
        );
        // The model is in front of the camera and mostly in view.
        let mut inside = 0;
        for p in &s.patches {
            assert!(p.cp().iter().all(|c| c.z > 30.0));
            let (x, y) = raster(&s, p.cp()[5]);
            if (0.0..796.0).contains(&x) && (0.0..515.0).contains(&y) {
                inside += 1;
            }
        }
        assert!(inside as f64 > 0.9 * s.patches.len() as f64);
        eprintln!("killeroo.rib parsed in {elapsed:?}");
    }

    #[test]
    fn newell_teapot_matches_builtin() {
        let path = shared("newell/teapot");
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(detect_format(&path, &text), InputFormat::Newell);
        let parsed = parse_newell(&text, "teapot").unwrap();
        let builtin = teapot_object_patches();
        assert_eq!(parsed.len(), 32);
        assert_eq!(builtin.len(), 32);
        for (i, (a, b)) in parsed.iter().zip(&builtin).enumerate() {
            assert_eq!(a.0, *b, "patch {i}");
        }
        // Loading the file frames it exactly like the built-in teapot.
        let s = load(&path).unwrap();
        let t = builtin_teapot();
        assert_eq!(s.patches.len(), 32);
        for (a, b) in s.patches.iter().zip(&t.patches) {
            assert_eq!(a.cp(), b.cp());
            assert_eq!(a.flip_normal, b.flip_normal);
        }
    }

    #[test]
    fn builtin_teapot_framed_and_outward() {
        let s = builtin_teapot();
        assert_eq!(s.patches.len(), 32);
        assert_eq!((s.width, s.height), (800, 600));
        assert_eq!(s.lights.len(), 4);
        let mut n = 0;
        let mut inside = 0;
        for p in &s.patches {
            for c in &p.cp() {
                assert!(c.z > 0.0);
                let (x, y) = raster(&s, *c);
                n += 1;
                if (0.0..800.0).contains(&x) && (0.0..600.0).contains(&y) {
                    inside += 1;
                }
            }
        }
        assert_eq!(inside, n, "every control point in view");
        // Body patches (Newell's 4..12; 0..4 are the rim) face away from the z axis.
        let body = Scene {
            patches: s.patches[4..12].to_vec(),
            ..s.clone()
        };
        let (ap, ad) = teapot::axis_in_camera();
        let f = outward_fraction(&body, ap, ad);
        assert!(f > 0.95, "body outward fraction {f}");
    }

    #[test]
    fn error_display_names_file_and_line() {
        let e = SceneError::new("a.rib", 7, "bad");
        assert_eq!(e.to_string(), "a.rib:7: bad");
        let e: Box<dyn std::error::Error> = Box::new(e);
        assert_eq!(e.to_string(), "a.rib:7: bad");
    }

    #[test]
    fn load_missing_file_is_an_error() {
        let e = load(Path::new("/nonexistent/x.rib")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("/nonexistent/x.rib: cannot read file")
        );
    }

    #[test]
    fn load_bpt_file() {
        let mut text = String::from("1\n3 3\n");
        for k in 0..16 {
            text += &format!(
                "{} {} {}\n",
                k % 4,
                k / 4,
                if k % 5 == 0 { 1.0 } else { 0.0 }
            );
        }
        let path =
            std::env::temp_dir().join(format!("reyes-scene-test-{}.bpt", std::process::id()));
        std::fs::write(&path, &text).unwrap();
        let s = load(&path);
        std::fs::remove_file(&path).unwrap();
        let s = s.unwrap();
        assert_eq!(s.patches.len(), 1);
        assert_eq!((s.width, s.height), (800, 600));
        assert!(s.patches[0].cp().iter().all(|c| c.z > 0.0));
        assert_eq!(s.patches[0].source.line, 2);
    }

    #[test]
    fn format_detection() {
        let p = Path::new("x");
        assert_eq!(detect_format(p, "2\n3 3\n0 0 0\n"), InputFormat::Bpt);
        assert_eq!(
            detect_format(p, "1\n1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16\n"),
            InputFormat::Newell
        );
        assert_eq!(detect_format(p, "WorldBegin\nWorldEnd\n"), InputFormat::Rib);
        assert_eq!(
            detect_format(Path::new("a.RIB"), "1\n3 3\n"),
            InputFormat::Rib
        );
        assert_eq!(detect_format(Path::new("a.bpt"), ""), InputFormat::Bpt);
    }
}
