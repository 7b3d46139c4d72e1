//! The graphics state: the current attributes (transform, orientation, shading, bases), the
//! stack that `AttributeBegin`/`TransformBegin`/`WorldBegin`/`FrameBegin` save it on, and the
//! interpreter that owns it together with the scene being built.

use super::syntax::Request;
use crate::scene::basis::Basis;
use crate::scene::{Material, Scene, SceneError, SurfaceKind};
use glam::{DMat4, DVec3};
use std::collections::{HashMap, HashSet};

/// Attributes saved by `AttributeBegin` (and the other attribute-saving blocks).
#[derive(Clone, Debug)]
pub(super) struct Attributes {
    /// Object to camera, column-vector convention.
    pub(super) ctm: DMat4,
    /// RenderMan's current orientation: true = right-handed.
    pub(super) orientation_rh: bool,
    pub(super) two_sided: bool,
    pub(super) color: DVec3,
    pub(super) opacity: DVec3,
    /// Shader and its parameters; its color/opacity fields are unused (see above).
    pub(super) surface: Material,
    pub(super) ubasis: Basis,
    pub(super) vbasis: Basis,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Block {
    Frame,
    World,
    Attribute,
    Transform,
}

impl Block {
    pub(super) fn begin(self) -> &'static str {
        match self {
            Block::Frame => "FrameBegin",
            Block::World => "WorldBegin",
            Block::Attribute => "AttributeBegin",
            Block::Transform => "TransformBegin",
        }
    }
}

pub(super) struct Interp<'a> {
    pub(super) file: &'a str,
    pub(super) scene: Scene,
    pub(super) attrs: Attributes,
    pub(super) stack: Vec<(Block, u32, Attributes)>,
    /// World-to-camera, saved at `WorldBegin`; `Some` only inside the world block.
    pub(super) world_to_camera: Option<DMat4>,
    pub(super) world_seen: bool,
    pub(super) warned: HashSet<String>,
    pub(super) materials: HashMap<(SurfaceKind, [u64; 13]), u32>,
    /// Material of the current attributes, once looked up.
    pub(super) current_material: Option<u32>,
    /// Inside `MotionBegin`: whether the first (used) time sample has been seen.
    pub(super) motion: Option<bool>,
}

impl Interp<'_> {
    pub(super) fn warn_once(&mut self, req: &Request, key: &str, msg: &str) {
        if self.warned.insert(key.to_string()) {
            self.scene
                .warnings
                .push(format!("{}:{}: {msg}", self.file, req.line));
        }
    }

    /// Sets the CTM, flipping the current orientation when the handedness flips (spec).
    pub(super) fn set_ctm(&mut self, m: DMat4) {
        if (self.attrs.ctm.determinant() < 0.0) != (m.determinant() < 0.0) {
            self.attrs.orientation_rh = !self.attrs.orientation_rh;
        }
        self.attrs.ctm = m;
    }

    pub(super) fn concat(&mut self, m: DMat4) {
        self.set_ctm(self.attrs.ctm * m);
    }

    pub(super) fn push(&mut self, block: Block, line: u32) {
        self.stack.push((block, line, self.attrs.clone()));
    }

    pub(super) fn pop(&mut self, block: Block, req: &Request) -> Result<(), SceneError> {
        let Some((top, line, saved)) = self.stack.pop() else {
            return Err(SceneError::new(
                self.file,
                req.line,
                format!("`{}` without a matching `{}`", req.name, block.begin()),
            ));
        };
        if top != block {
            return Err(SceneError::new(
                self.file,
                req.line,
                format!(
                    "`{}` does not match `{}` at line {line}",
                    req.name,
                    top.begin()
                ),
            ));
        }
        if block == Block::Transform {
            self.set_ctm(saved.ctm);
        } else {
            self.attrs = saved;
            self.current_material = None;
        }
        Ok(())
    }
}
