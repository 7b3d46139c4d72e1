//! Frames and worlds: `FrameBegin n` / `FrameEnd`, `WorldBegin` / `WorldEnd`, `Display` and
//! `MakeShadow`, and the sequence of frames they make.
//!
//! RenderMan semantics (RenderMan Interface Specification 3.2, §4.1): each world block
//! renders one image with the options in effect at its end. `FrameBegin` saves the options
//! and attributes and `FrameEnd` restores them, so what is set before the first frame applies
//! to every frame and what a frame sets stays in it. A frame holds at most one world. A world
//! outside any frame is a frame of its own, numbered on from the frame before it. Frames that
//! make depth maps (`Display` type "shadow" or "zfile", or a `MakeShadow` in the frame) are
//! kept in the sequence but marked [`SceneFrame::unsupported`].

use super::lexer::shown;
use super::state::{Block, Interp, OpenFrame};
use super::syntax::{Args, Request};
use crate::scene::{Display, Scene, SceneError, SceneFrame};

/// Largest frame number accepted: eight digits keep `####` patterns and file names sane.
pub(super) const MAX_FRAME_NUMBER: usize = 99_999_999;

impl Interp {
    pub(super) fn frame_begin(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let number = match a.peek() {
            Some(_) => a.int("the frame number", 0, MAX_FRAME_NUMBER)? as u32,
            None => self.next_number,
        };
        a.done()?;
        if self.world_to_camera.is_some() {
            return Err(a.err("not allowed inside `WorldBegin` ... `WorldEnd`"));
        }
        if let Some(f) = &self.frame {
            return Err(a.err(format!(
                "frame {} (line {}) has not ended: frames do not nest",
                f.number, f.line
            )));
        }
        self.push(Block::FrameUniforms, req)?;
        self.frame = Some(OpenFrame {
            number,
            line: req.line,
            unsupported: None,
            world: None,
        });
        Ok(())
    }

    pub(super) fn frame_end(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        a.done()?;
        self.pop(Block::FrameUniforms, req)?;
        let frame = self.frame.take().expect("a frame block is open");
        self.next_number = frame.number.saturating_add(1);
        match frame.world {
            Some(mut f) => {
                if f.unsupported.is_none() {
                    f.unsupported = frame.unsupported;
                }
                self.frames.push(f);
            }
            None => {
                let msg = format!(
                    "frame {} has no world block: nothing to render",
                    frame.number
                );
                self.warn_once(req, &msg, &msg);
            }
        }
        Ok(())
    }

    pub(super) fn world_begin(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        a.done()?;
        if self.world_to_camera.is_some() {
            return Err(a.err("world blocks do not nest"));
        }
        if let Some(f) = &self.frame
            && f.world.is_some()
        {
            return Err(a.err(format!(
                "frame {} already has a world block: one `WorldBegin` per frame",
                f.number
            )));
        }
        self.push(Block::World, req)?;
        self.world_to_camera = Some(self.attrs.ctm);
        self.world_to_camera_close = self.attrs.ctm_close;
        Ok(())
    }

    /// Ends the world: its frame is complete (inside a frame block, it waits for `FrameEnd`,
    /// where a `MakeShadow` may still mark it).
    pub(super) fn world_end(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        a.done()?;
        self.pop(Block::World, req)?;
        let world_to_camera = self.world_to_camera.take().unwrap_or_default();
        self.world_to_camera_close = None;
        let o = &self.options;
        let mut scene = Scene {
            width: o.width,
            height: o.height,
            pixel_samples: o.pixel_samples,
            background: o.background,
            camera: crate::scene::Camera {
                world_to_camera,
                ..o.camera.clone()
            },
            ..std::mem::take(&mut self.scene)
        };
        self.frame_camera(req, &mut scene)?;
        self.materials.clear();
        self.current_material = None;
        self.instancing.end_of_world();
        let display = self.options.display.clone();
        let unsupported = display.as_ref().filter(|d| d.is_depth_pass()).map(|d| {
            format!(
                "a depth-map pass (`Display` type \"{}\"), not an image",
                shown(&d.kind)
            )
        });
        let number = self.frame.as_ref().map_or(self.next_number, |f| f.number);
        let frame = SceneFrame {
            number,
            display,
            unsupported,
            scene,
        };
        match &mut self.frame {
            Some(f) => f.world = Some(frame),
            None => {
                self.next_number = number.saturating_add(1);
                self.frames.push(frame);
            }
        }
        Ok(())
    }

    /// `Display name type mode ...`: the frame's output. A name starting with `+` adds a
    /// second output, which this renderer does not make.
    pub(super) fn display(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let name = a.string("the display name")?;
        let kind = a.string("the display type")?;
        let mode = a.string("the display mode")?;
        for p in a.params()? {
            self.ignored_param(req, p.name);
        }
        if name.starts_with('+') {
            self.warn_once(
                req,
                "Display +",
                "skipped an additional `Display` (\"+name\"): one image per frame",
            );
            return Ok(());
        }
        self.options.display = Some(Display {
            name: name.to_string(),
            kind: kind.to_string(),
            mode: mode.to_string(),
        });
        Ok(())
    }

    /// `MakeShadow`: inside a frame block, marks the frame a shadow-map pass.
    pub(super) fn make_shadow(&mut self, req: &Request) {
        match &mut self.frame {
            Some(f) => {
                f.unsupported.get_or_insert_with(|| {
                    format!("a shadow-map pass (`MakeShadow` at line {})", req.line)
                });
            }
            None => self.warn_once(
                req,
                "MakeShadow",
                "skipped unsupported request `MakeShadow`",
            ),
        }
    }
}
