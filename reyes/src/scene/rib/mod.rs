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
//! One file per concern: [`lexer`] (bytes to tokens), [`input`] (tokens to requests, through
//! the scene file and the archives it reads), [`syntax`] (requests and typed access to their
//! arguments), [`state`] (options, attributes and the block stack), [`requests`] (the one
//! dispatch over request names), [`frames`] (frame and world blocks: the sequence of frames),
//! [`shading`] (surfaces, lights, the material table), [`patches`] (the patch primitives
//! and their conversion to Bezier patches), [`displacement`] (`Displacement` and
//! `"displacementbound"`), [`quadrics`] (the quadric primitives), [`motion`] (`Shutter`, `DepthOfField`, motion blocks) and
//! [`primvars`] (`Declare` and the `"Cs"` / `"Os"` primitive variables of patches).

mod displacement;
mod frames;
mod input;
mod lexer;
mod motion;
mod patches;
mod primvars;
mod quadrics;
mod requests;
mod shading;
mod state;
mod syntax;
#[cfg(test)]
mod tests;

pub use input::open_rib;

use super::{FrameSequence, Scene, SceneError};
use input::Reader;
use state::Interp;
use std::path::Path;

/// Parses RIB text into its frames. `file` names the input in errors and warnings; archives
/// (`ReadArchive`) are looked up beside it, then in the current directory.
pub fn parse_rib_frames(text: &str, file: &str) -> Result<FrameSequence, SceneError> {
    read(Reader::new(Box::new(text.as_bytes()), file, None))
}

/// Parses RIB text of one image: the first frame that can be rendered, with a warning when
/// the file has several ([`FrameSequence::into_scene`]).
pub fn parse_rib(text: &str, file: &str) -> Result<Scene, SceneError> {
    parse_rib_frames(text, file).map(FrameSequence::into_scene)
}

/// Reads a RIB file (gzip-compressed or not) into its frames, as a stream: the memory it
/// needs is the scene's, not the file's. Errors name the file as `path` displays.
pub fn load_rib(path: &Path) -> Result<FrameSequence, SceneError> {
    let file = path.display().to_string();
    let src =
        open_rib(path).map_err(|e| SceneError::new(&file, 0, format!("cannot read file: {e}")))?;
    read(Reader::new(src, &file, Some(path)))
}

/// Runs the requests of `reader` to its end.
fn read(mut reader: Reader) -> Result<FrameSequence, SceneError> {
    let mut it = Interp::new();
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
                        return Err(reader.eof_error(format!(
                            "unexpected end of file inside `ObjectBegin` (line {})",
                            req.line
                        )));
                    }
                }
            }
            continue;
        }
        if it.motion.is_some() && req.name != "MotionEnd" && it.motion_request(&req)? {
            continue;
        }
        if req.name == "ReadArchive" {
            reader.read_archive(&req)?;
            continue;
        }
        it.request(&req)?;
    }
    if let Some(m) = &it.motion {
        return Err(reader.eof_error(format!(
            "unexpected end of file inside `MotionBegin` (line {})",
            m.line
        )));
    }
    if let Some(open) = it.stack.last() {
        return Err(reader.eof_error(format!(
            "unexpected end of file inside `{}` ({})",
            open.block.begin(),
            open.place(&reader.file())
        )));
    }
    if it.frames.is_empty() {
        return Err(reader.eof_error("no `WorldBegin` ... `WorldEnd` block in the file"));
    }
    Ok(it.finish())
}
