//! The RIB interpreter: a graphics-state stack, transforms, attributes and the patch
//! primitives, turning a RIB stream into a [`Scene`] of camera-space Bezier patches.
//!
//! Conventions (RenderMan Interface Specification 3.2):
//! - Points are row vectors in the spec (`P' = P M`); we hold column-vector glam matrices,
//!   so the 16 numbers of `Transform`/`ConcatTransform` (row-major `M`) read as column-major
//!   give `M^T` directly. Each new transform applies FIRST to points: `CTM = CTM * M`.
//! - The CTM current at `WorldBegin` is world-to-camera; inside the world block the CTM is
//!   object-to-camera. `Identity` and `Transform` inside the world block are relative to
//!   world space (they start again from the camera transform saved at `WorldBegin`).
//! - `Rotate a x y z`: the usual axis-angle matrix (x -> y for +90 about z), which is what
//!   the spec's left-handed rule means numerically (checked against uteapot.rib: upright,
//!   seen from above, in front of the camera).
//! - Orientation: the spec keeps a "current orientation" (lh/rh) that starts left-handed,
//!   flips whenever the handedness of the current coordinate system flips (a transform with
//!   negative determinant, or restoring one), and is set by `Orientation`/
//!   `ReverseOrientation`. The surface normal is dPdu x dPdv in OBJECT space, negated when
//!   the current orientation differs from the object system's handedness. Our patches are
//!   in camera space, where the cross product of transformed tangents is
//!   det(CTM) CTM^-T (dPdu x dPdv): it gains the sign of det(CTM). Both sign changes
//!   together leave exactly one rule: the camera-space dPdu x dPdv must be negated iff the
//!   current orientation is right-handed. That is `Patch::flip_normal`. (By this rule
//!   uteapot.rib's teapot, a mirror image of Newell's data, faces inward; killeroo.rib's
//!   mirroring camera `Transform` makes every patch flip, facing it outward.)
//!
//! One file per concern: [`lexer`] (bytes to tokens), [`syntax`] (tokens to requests and
//! typed argument access), [`state`] (the graphics state and its stacks), [`requests`] (the
//! one dispatch over request names), [`shading`] (surfaces, lights, the material table) and
//! [`patches`] (the patch primitives and their conversion to Bezier patches).

mod lexer;
mod patches;
mod requests;
mod shading;
mod state;
mod syntax;
#[cfg(test)]
mod tests;

use super::basis::Basis;
use super::{Material, Scene, SceneError, SurfaceKind};
use glam::{DMat4, DVec3};
use lexer::tokenize;
use state::{Attributes, Interp};
use std::collections::{HashMap, HashSet};
use syntax::Reader;

/// Parses RIB text. `file` names the input in errors and warnings.
pub fn parse_rib(text: &str, file: &str) -> Result<Scene, SceneError> {
    let toks = tokenize(text.as_bytes(), file)?;
    let eof_line = text.lines().count().max(1) as u32;
    let mut reader = Reader {
        file,
        toks: toks.into_iter().peekable(),
        eof_line,
    };
    let mut it = Interp {
        file,
        scene: Scene::default(),
        attrs: Attributes {
            ctm: DMat4::IDENTITY,
            orientation_rh: false,
            two_sided: true,
            color: DVec3::ONE,
            opacity: DVec3::ONE,
            surface: Material::standard(SurfaceKind::Matte),
            ubasis: Basis::BEZIER,
            vbasis: Basis::BEZIER,
        },
        stack: Vec::new(),
        world_to_camera: None,
        world_seen: false,
        warned: HashSet::new(),
        materials: HashMap::new(),
        current_material: None,
        motion: None,
    };
    while let Some(req) = reader.next_request()? {
        if req.name == "ObjectBegin" {
            it.warn_once(
                &req,
                "ObjectBegin",
                "skipped `ObjectBegin` ... `ObjectEnd` (retained geometry is not supported)",
            );
            loop {
                match reader.next_request()? {
                    Some(r) if r.name == "ObjectEnd" => break,
                    Some(_) => {}
                    None => {
                        return Err(SceneError::new(
                            file,
                            eof_line,
                            format!(
                                "unexpected end of file inside `ObjectBegin` (line {})",
                                req.line
                            ),
                        ));
                    }
                }
            }
            continue;
        }
        if let Some(first_done) = it.motion {
            if req.name == "MotionEnd" {
                it.motion = None;
                continue;
            }
            if first_done {
                continue;
            }
            it.motion = Some(true);
        }
        it.request(&req)?;
    }
    if let Some((block, line, _)) = it.stack.last() {
        return Err(SceneError::new(
            file,
            eof_line,
            format!(
                "unexpected end of file inside `{}` (line {line})",
                block.begin()
            ),
        ));
    }
    if !it.world_seen {
        return Err(SceneError::new(
            file,
            eof_line,
            "no `WorldBegin` ... `WorldEnd` block in the file",
        ));
    }
    Ok(it.scene)
}
