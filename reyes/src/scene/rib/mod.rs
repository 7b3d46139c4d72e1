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
//! [`primvars`] (`Declare` and the `"Cs"` / `"Os"` primitive variables of patches),
//! [`polygons`] (the polygon requests), [`instance`] (`ObjectBegin` ... `ObjectInstance`) and
//! [`camera`] (the window requests, orthographic projection, named coordinate systems).

mod camera;
mod curves;
mod displacement;
mod frames;
mod input;
mod instance;
mod lexer;
mod motion;
mod patches;
mod polygons;
mod primvars;
mod quadrics;
mod requests;
mod shading;
mod state;
mod subdiv;
mod syntax;
#[cfg(test)]
mod tests;
mod trim;

pub use input::open_rib;

use super::{FrameError, FrameSequence, Scene, SceneError, SceneFrame};
use input::Reader;
use state::Interp;
use std::path::Path;

/// Parses RIB text into its frames. `file` names the input in errors and warnings; archives
/// (`ReadArchive`) are looked up beside it, then in the current directory.
pub fn parse_rib_frames(text: &str, file: &str) -> Result<FrameSequence, SceneError> {
    RibFrames::new(Reader::new(Box::new(text.as_bytes()), file, None)).collect_sequence()
}

/// Parses RIB text of one image: the first frame that can be rendered, with a warning when
/// the file has several ([`FrameSequence::into_scene`]).
pub fn parse_rib(text: &str, file: &str) -> Result<Scene, SceneError> {
    parse_rib_frames(text, file).map(FrameSequence::into_scene)
}

/// Reads a RIB file (gzip-compressed or not) into its frames, as a stream: the memory it
/// needs is the scene's, not the file's. Errors name the file as `path` displays.
pub fn load_rib(path: &Path) -> Result<FrameSequence, SceneError> {
    stream_rib(path)?.collect_sequence()
}

/// The frames of a RIB file (gzip-compressed or not) one at a time ([`RibFrames`]). Errors:
/// the file cannot be opened.
pub fn stream_rib(path: &Path) -> Result<RibFrames<'static>, SceneError> {
    let file = path.display().to_string();
    let src =
        open_rib(path).map_err(|e| SceneError::new(&file, 0, format!("cannot read file: {e}")))?;
    Ok(RibFrames::new(Reader::new(src, &file, Some(path))))
}

/// A RIB stream read frame by frame, as RenderMan reads it: each item is the next frame (a
/// world block, with the options and attributes in effect as RIB carries them over), built
/// when its `WorldEnd` / `FrameEnd` is read and handed over, so the stream holds one frame's
/// scene at a time whatever the file's length. An error inside a `FrameBegin` ... `FrameEnd`
/// block is that frame's ([`FrameError::number`]): the rest of the block is skipped, the
/// state the block saved is restored, and the frames after it are still delivered. An error
/// outside a frame block (or one the lexer cannot read past) ends the stream.
pub struct RibFrames<'a> {
    reader: Reader<'a>,
    it: Interp,
    /// True once the stream has ended (the input's end, or an error that ends it).
    done: bool,
    /// True once a frame or an error has been handed over.
    delivered: bool,
}

impl<'a> RibFrames<'a> {
    fn new(reader: Reader<'a>) -> RibFrames<'a> {
        RibFrames {
            reader,
            it: Interp::new(),
            done: false,
            delivered: false,
        }
    }

    /// The warnings given since the last call (one per kind of skipped input in the file).
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.it.warnings)
    }

    /// The frames held, read but not yet handed over: at most one (a test of the streaming).
    #[cfg(test)]
    pub(crate) fn held(&self) -> usize {
        self.it.frames.len()
            + usize::from(self.it.frame.as_ref().is_some_and(|f| f.world.is_some()))
    }

    /// Every frame, stopping at the first error (as the whole file read at once).
    pub fn collect_sequence(mut self) -> Result<FrameSequence, SceneError> {
        let mut frames = Vec::new();
        for f in self.by_ref() {
            frames.push(f.map_err(|e| e.error)?);
        }
        Ok(FrameSequence {
            frames,
            warnings: self.take_warnings(),
        })
    }

    /// Runs the next request. `Ok(false)` at the end of the input; an error comes with
    /// whether its request was a `FrameEnd` (the end of the frame it belongs to).
    fn step(&mut self) -> Result<bool, (SceneError, bool)> {
        let req = match self.reader.next_request() {
            Ok(Some(r)) => r,
            Ok(None) => return Ok(false),
            Err(e) => return Err((e, false)),
        };
        let frame_end = req.name == "FrameEnd";
        if self.it.recording.is_some() && req.name != "ReadArchive" {
            // Inside `ObjectBegin` ... `ObjectEnd`: kept for `ObjectInstance`.
            return self
                .it
                .record(req)
                .map(|()| true)
                .map_err(|e| (e, frame_end));
        }
        let r = (|| {
            let (reader, it) = (&mut self.reader, &mut self.it);
            match req.name.as_str() {
                "ObjectBegin" => return it.object_begin(&req),
                "ObjectInstance" => return it.object_instance(&req),
                _ => {}
            }
            if it.motion.is_some() && req.name != "MotionEnd" && it.motion_request(&req)? {
                return Ok(());
            }
            if req.name == "ReadArchive" {
                return reader.read_archive(&req);
            }
            it.request(&req)
        })();
        r.map(|()| true).map_err(|e| (e, frame_end))
    }

    /// The checks at the end of the input: every block closed, some frame read.
    fn end(&mut self) -> Option<FrameError> {
        let number = self.it.frame.as_ref().map(|f| f.number);
        let error = if let Some(r) = &self.it.recording {
            self.reader.eof_error(format!(
                "unexpected end of file inside `ObjectBegin` (line {})",
                r.line
            ))
        } else if let Some(m) = &self.it.motion {
            self.reader.eof_error(format!(
                "unexpected end of file inside `MotionBegin` (line {})",
                m.line
            ))
        } else if let Some(open) = self.it.stack.last() {
            self.reader.eof_error(format!(
                "unexpected end of file inside `{}` ({})",
                open.block.begin(),
                open.place(&self.reader.file())
            ))
        } else if !self.delivered {
            self.reader
                .eof_error("no `WorldBegin` ... `WorldEnd` block in the file")
        } else {
            return None;
        };
        Some(FrameError { number, error })
    }

    /// After `error`: inside a frame block, skips to its `FrameEnd` (unless the error was
    /// at it) and restores the state the block saved; elsewhere, ends the stream.
    fn recover(&mut self, error: SceneError, at_frame_end: bool) -> FrameError {
        let Some(number) = self.it.frame.as_ref().map(|f| f.number) else {
            self.done = true;
            return FrameError {
                number: None,
                error,
            };
        };
        if !at_frame_end {
            loop {
                match self.reader.next_request() {
                    Ok(Some(r)) if r.name == "FrameEnd" => break,
                    Ok(Some(_)) => {}
                    Ok(None) | Err(_) => {
                        self.done = true;
                        break;
                    }
                }
            }
        }
        self.it.abandon_frame(number);
        FrameError {
            number: Some(number),
            error,
        }
    }
}

impl Iterator for RibFrames<'_> {
    type Item = Result<SceneFrame, FrameError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if !self.it.frames.is_empty() {
                self.delivered = true;
                return Some(Ok(self.it.frames.remove(0)));
            }
            if self.done {
                return None;
            }
            match self.step() {
                Ok(true) => {}
                Ok(false) => {
                    self.done = true;
                    let e = self.end()?;
                    self.delivered = true;
                    return Some(Err(e));
                }
                Err((e, at_frame_end)) => {
                    self.delivered = true;
                    return Some(Err(self.recover(e, at_frame_end)));
                }
            }
        }
    }
}
