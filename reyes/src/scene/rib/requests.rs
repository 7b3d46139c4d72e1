//! The one dispatch over request names, grouped as the RenderMan Interface Specification
//! groups them: options, transformations, blocks, attributes, shading, geometry.

use super::patches::basis_arg;
use super::state::{Block, Interp};
use super::syntax::{Args, Request};
use crate::scene::SceneError;
use glam::{DMat4, DVec3};

/// Requests the interpreter understands; any other name is skipped with one warning.
pub(super) const KNOWN: &[&str] = &[
    "Format",
    "PixelSamples",
    "Projection",
    "Clipping",
    "Identity",
    "Transform",
    "ConcatTransform",
    "Translate",
    "Rotate",
    "Scale",
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
    "Color",
    "Opacity",
    "Surface",
    "LightSource",
    "Sides",
    "Orientation",
    "ReverseOrientation",
    "ObjectBegin",
    "ObjectEnd",
    "MotionBegin",
    "MotionEnd",
];

impl Interp<'_> {
    pub(super) fn request(&mut self, req: &Request) -> Result<(), SceneError> {
        let mut a = Args {
            req,
            file: self.file,
            pos: 0,
        };
        match req.name.as_str() {
            "Format" => {
                let w = a.int("the x resolution", 1, 1 << 16)?;
                let h = a.int("the y resolution", 1, 1 << 16)?;
                a.num("the pixel aspect ratio")?;
                a.done()?;
                self.scene.width = w as u32;
                self.scene.height = h as u32;
            }
            "PixelSamples" => {
                let mut s = [0u32; 2];
                for (k, slot) in s.iter_mut().enumerate() {
                    let v = a.num(if k == 0 { "xsamples" } else { "ysamples" })?;
                    if !(v > 0.0 && v <= 1024.0) {
                        return Err(a.err(format!("sample count {v} is not in (0, 1024]")));
                    }
                    *slot = v.ceil() as u32;
                }
                a.done()?;
                self.scene.pixel_samples = (s[0], s[1]);
            }
            "Projection" => {
                if self.world_to_camera.is_some() {
                    return Err(a.err("not allowed inside `WorldBegin` ... `WorldEnd`"));
                }
                let name = a.string("the projection type")?;
                if name != "perspective" {
                    return Err(a.err(format!(
                        "projection \"{name}\" is not supported (only \"perspective\")"
                    )));
                }
                for p in a.params()? {
                    match p.name {
                        "fov" => {
                            let fov = p.num(&a)?;
                            if !(fov > 0.0 && fov < 180.0) {
                                return Err(a.err(format!("fov {fov} is not in (0, 180)")));
                            }
                            self.scene.camera.fov_deg = fov;
                        }
                        other => self.ignored_param(req, other),
                    }
                }
                // The spec: the current transformation is reset after the projection.
                self.set_ctm(DMat4::IDENTITY);
            }
            "Clipping" => {
                let near = a.num("near")?;
                let far = a.num("far")?;
                a.done()?;
                if !(near > 0.0 && far > near) {
                    return Err(a.err(format!("need 0 < near < far, found near {near} far {far}")));
                }
                self.scene.camera.near = near;
                self.scene.camera.far = far;
            }
            "Identity" => {
                a.done()?;
                self.set_ctm(self.world_to_camera.unwrap_or(DMat4::IDENTITY));
            }
            "Transform" | "ConcatTransform" => {
                let v = a.fixed(16, "the matrix")?;
                a.done()?;
                // Row-major row-vector matrix == column-major column-vector matrix.
                let m = DMat4::from_cols_slice(&v);
                if req.name == "Transform" {
                    self.set_ctm(self.world_to_camera.unwrap_or(DMat4::IDENTITY) * m);
                } else {
                    self.concat(m);
                }
            }
            "Translate" => {
                let v = a.fixed(3, "the offset")?;
                a.done()?;
                self.concat(DMat4::from_translation(DVec3::from_slice(&v)));
            }
            "Rotate" => {
                let v = a.fixed(4, "angle and axis")?;
                a.done()?;
                let r = crate::scene::rotation(v[0], DVec3::new(v[1], v[2], v[3]))
                    .ok_or_else(|| a.err("the rotation axis is zero"))?;
                self.concat(r);
            }
            "Scale" => {
                let v = a.fixed(3, "the scale factors")?;
                a.done()?;
                self.concat(DMat4::from_scale(DVec3::from_slice(&v)));
            }
            "WorldBegin" => {
                a.done()?;
                if self.world_seen {
                    return Err(a.err("only one `WorldBegin` block per file is supported"));
                }
                self.world_seen = true;
                self.push(Block::World, req.line);
                self.world_to_camera = Some(self.attrs.ctm);
            }
            "WorldEnd" => {
                a.done()?;
                self.pop(Block::World, req)?;
                self.world_to_camera = None;
            }
            "FrameBegin" => {
                if a.peek().is_some() {
                    a.num("the frame number")?;
                }
                a.done()?;
                self.push(Block::Frame, req.line);
            }
            "FrameEnd" => {
                a.done()?;
                self.pop(Block::Frame, req)?;
            }
            "AttributeBegin" => {
                a.done()?;
                self.push(Block::Attribute, req.line);
            }
            "AttributeEnd" => {
                a.done()?;
                self.pop(Block::Attribute, req)?;
            }
            "TransformBegin" => {
                a.done()?;
                self.push(Block::Transform, req.line);
            }
            "TransformEnd" => {
                a.done()?;
                self.pop(Block::Transform, req)?;
            }
            "Basis" => {
                let ub = basis_arg(&mut a, "u")?;
                let vb = basis_arg(&mut a, "v")?;
                a.done()?;
                self.attrs.ubasis = ub;
                self.attrs.vbasis = vb;
            }
            "Color" | "Opacity" => {
                let v = a.fixed(3, "the color")?;
                a.done()?;
                let c = DVec3::from_slice(&v);
                if req.name == "Color" {
                    self.attrs.color = c;
                } else {
                    self.attrs.opacity = c;
                }
                self.current_material = None;
            }
            "Surface" => self.surface(req, &mut a)?,
            "LightSource" => self.light(req, &mut a)?,
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
                            "orientation \"{o}\" is not one of \"lh\", \"rh\", \"inside\", \"outside\""
                        )));
                    }
                };
            }
            "ReverseOrientation" => {
                a.done()?;
                self.attrs.orientation_rh = !self.attrs.orientation_rh;
            }
            "Patch" => self.patch(req, &mut a)?,
            "PatchMesh" => self.patch_mesh(req, &mut a)?,
            "NuPatch" => self.nu_patch(req, &mut a)?,
            "ObjectEnd" => return Err(a.err("without a matching `ObjectBegin`")),
            "MotionBegin" => {
                if self.motion.is_some() {
                    return Err(a.err("nested `MotionBegin`"));
                }
                self.warn_once(
                    req,
                    "MotionBegin",
                    "motion blocks are not supported: using the first time sample of each",
                );
                self.motion = Some(false);
            }
            "MotionEnd" => return Err(a.err("without a matching `MotionBegin`")),
            _ => {
                let msg = format!("skipped unsupported request `{}`", req.name);
                self.warn_once(req, &req.name, &msg);
            }
        }
        Ok(())
    }

    pub(super) fn ignored_param(&mut self, req: &Request, name: &str) {
        let key = format!("{} \"{name}\"", req.name);
        let msg = format!("ignored parameter \"{name}\" of `{}`", req.name);
        self.warn_once(req, &key, &msg);
    }
}
