//! The graphics state: the options (image size, samples, camera, display: what a frame
//! block saves), the current attributes (transform, orientation, shading, bases), the stack
//! that `AttributeBegin`/`TransformBegin`/`WorldBegin`/`FrameBegin` save them on, and the
//! interpreter that owns them together with the frames being built.

use super::primvars::Decl;
use super::syntax::Request;
use crate::scene::basis::Basis;
use crate::scene::{
    Camera, DisplacementPattern, Display, Material, Scene, SceneError, SceneFrame, SurfaceKind,
};
use glam::{DMat4, DVec3};
use std::collections::{HashMap, HashSet};
use std::rc::Rc;

/// Most blocks open at once (`AttributeBegin`, `TransformBegin`, ... inside each other).
/// Real scenes nest tens deep; the bound keeps a hostile file's memory small (each level
/// saves the attributes, about 700 bytes) and fails it at once.
pub(super) const MAX_NESTING: usize = 1024;

/// Attributes saved by `AttributeBegin` (and the other attribute-saving blocks).
#[derive(Clone, Debug)]
pub(super) struct Attributes {
    /// Object to camera, column-vector convention.
    pub(super) ctm: DMat4,
    /// Object to camera at shutter close when it differs from `ctm` (a `MotionBegin` block
    /// moved a transform: see `motion.rs`), `None` when the transform does not move.
    pub(super) ctm_close: Option<DMat4>,
    /// RenderMan's current orientation: true = right-handed.
    pub(super) orientation_rh: bool,
    pub(super) two_sided: bool,
    pub(super) color: DVec3,
    pub(super) opacity: DVec3,
    /// Shader and its parameters; its color/opacity fields are unused (see above).
    pub(super) surface: Material,
    pub(super) ubasis: Basis,
    pub(super) vbasis: Basis,
    /// `Displacement`: the pattern and its `"Km"` (object space); `None` for none.
    pub(super) displacement: Option<(DisplacementPattern, f64)>,
    /// `Attribute "displacementbound" "sphere"`: the radius in object space (of each
    /// primitive) or, given in world or camera space, in camera space; the other 0.
    pub(super) displacement_bound: (f64, f64),
    /// `TrimCurve`: the flattened loops that trim the `NuPatch` surfaces after it; `None`
    /// when untrimmed.
    pub(super) trim: Option<std::sync::Arc<crate::scene::trim::TrimLoops>>,
    /// `Attribute "trimcurve" "sense" "outside"`: trimming keeps the outside of the loops.
    pub(super) trim_outside: bool,
}

impl Default for Attributes {
    /// RenderMan's initial attributes.
    fn default() -> Self {
        Attributes {
            ctm: DMat4::IDENTITY,
            ctm_close: None,
            orientation_rh: false,
            two_sided: true,
            color: DVec3::ONE,
            opacity: DVec3::ONE,
            surface: Material::standard(SurfaceKind::Matte),
            ubasis: Basis::BEZIER,
            vbasis: Basis::BEZIER,
            displacement: None,
            displacement_bound: (0.0, 0.0),
            trim: None,
            trim_outside: false,
        }
    }
}

/// The options a frame's image is made with; `FrameBegin` saves them and `FrameEnd`
/// restores them, so options set before the first frame apply to every frame.
#[derive(Clone, Debug)]
pub(super) struct Options {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) pixel_samples: (u32, u32),
    pub(super) camera: Camera,
    pub(super) display: Option<Display>,
    /// `ScreenWindow`, `FrameAspectRatio`, `CropWindow`, orthographic projection.
    pub(super) framing: super::camera::Framing,
    /// `Imager "background"`: the colour the image is composited over (`Scene::background`).
    pub(super) background: Option<DVec3>,
}

impl Default for Options {
    fn default() -> Self {
        let s = Scene::default();
        Options {
            width: s.width,
            height: s.height,
            pixel_samples: s.pixel_samples,
            camera: s.camera,
            display: None,
            framing: Default::default(),
            background: None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Block {
    FrameUniforms,
    World,
    Attribute,
    Transform,
}

impl Block {
    pub(super) fn begin(self) -> &'static str {
        match self {
            Block::FrameUniforms => "FrameBegin",
            Block::World => "WorldBegin",
            Block::Attribute => "AttributeBegin",
            Block::Transform => "TransformBegin",
        }
    }
}

/// One open block: where it began and the state it restores.
pub(super) struct Saved {
    pub(super) block: Block,
    pub(super) file: Rc<str>,
    pub(super) line: u64,
    pub(super) attrs: Attributes,
    /// The options, saved by `FrameBegin` only.
    pub(super) options: Option<Box<Options>>,
}

impl Saved {
    /// "line 3", or "a.rib:3" when the block began in another file than `here`.
    pub(super) fn place(&self, here: &str) -> String {
        if *self.file == *here {
            format!("line {}", self.line)
        } else {
            format!("{}:{}", self.file, self.line)
        }
    }
}

/// The frame block being read.
pub(super) struct OpenFrame {
    pub(super) number: u32,
    pub(super) line: u64,
    /// Set by `MakeShadow`: the frame is a shadow-map pass.
    pub(super) unsupported: Option<String>,
    /// The frame's world, once its `WorldEnd` has been read.
    pub(super) world: Option<SceneFrame>,
}

pub(super) struct Interp {
    pub(super) options: Options,
    pub(super) attrs: Attributes,
    pub(super) stack: Vec<Saved>,
    /// World-to-camera, saved at `WorldBegin`; `Some` only inside the world block.
    pub(super) world_to_camera: Option<DMat4>,
    /// World-to-camera at shutter close when the camera moves (a motion block before
    /// `WorldBegin`), saved with [`Self::world_to_camera`].
    pub(super) world_to_camera_close: Option<DMat4>,
    /// The world being read: its patches, materials and lights (options are added at
    /// `WorldEnd`). Lights given before `WorldBegin` go to the next world.
    pub(super) scene: Scene,
    pub(super) frame: Option<OpenFrame>,
    /// Finished frames, in file order.
    pub(super) frames: Vec<SceneFrame>,
    /// The number of the next world outside a frame block.
    pub(super) next_number: u32,
    pub(super) warnings: Vec<String>,
    pub(super) warned: HashSet<String>,
    pub(super) materials: HashMap<(SurfaceKind, [u64; 13]), u32>,
    /// Material of the current attributes, once looked up.
    pub(super) current_material: Option<u32>,
    /// The open `MotionBegin` block.
    pub(super) motion: Option<super::motion::MotionBlock>,
    /// `Declare`d primitive variables by name (global, not saved by blocks).
    pub(super) declared: HashMap<String, Decl>,
    /// Displacement maps read so far, by path (each file read once).
    pub(super) displacement_maps: HashMap<String, std::sync::Arc<crate::scene::DisplacementMap>>,
    /// The object definition being recorded (`ObjectBegin` ... `ObjectEnd`).
    pub(super) recording: Option<super::instance::Recording>,
    /// Object definitions by handle (kept for the rest of the file, as RIB uses them).
    pub(super) objects: HashMap<String, Rc<[Request]>>,
    /// `ObjectInstance` replays under way (an object may instance another).
    pub(super) instance_depth: usize,
    /// The objects' primitives built once for their instances.
    pub(super) instancing: super::instance::Instancing,
    /// `CoordinateSystem`s by name: the transform at shutter open and close.
    pub(super) coordinate_systems: HashMap<String, (DMat4, Option<DMat4>)>,
    /// The file name and transform the patches share.
    pub(super) shared: super::patches::SharedParts,
}

impl Interp {
    pub(super) fn new() -> Interp {
        Interp {
            options: Options::default(),
            attrs: Attributes::default(),
            stack: Vec::new(),
            world_to_camera: None,
            world_to_camera_close: None,
            scene: Scene::default(),
            frame: None,
            frames: Vec::new(),
            next_number: 1,
            warnings: Vec::new(),
            warned: HashSet::new(),
            materials: HashMap::new(),
            current_material: None,
            motion: None,
            declared: HashMap::new(),
            displacement_maps: HashMap::new(),
            recording: None,
            objects: HashMap::new(),
            instance_depth: 0,
            instancing: Default::default(),
            coordinate_systems: HashMap::new(),
            shared: Default::default(),
        }
    }

    pub(super) fn warn_once(&mut self, req: &Request, key: &str, msg: &str) {
        if self.warned.insert(key.to_string()) {
            self.warnings
                .push(format!("{}:{}: {msg}", req.file, req.line));
        }
    }

    /// Sets the CTM, flipping the current orientation when the handedness flips (spec).
    pub(super) fn set_ctm(&mut self, m: DMat4) {
        if (self.attrs.ctm.determinant() < 0.0) != (m.determinant() < 0.0) {
            self.attrs.orientation_rh = !self.attrs.orientation_rh;
        }
        self.attrs.ctm = m;
    }

    /// Applies `m` first to points, at shutter open and (when moving) at shutter close.
    pub(super) fn concat(&mut self, m: DMat4) {
        if let Some(c) = &mut self.attrs.ctm_close {
            *c *= m;
        }
        self.set_ctm(self.attrs.ctm * m);
    }

    /// Opens a block, saving the attributes (and for a frame, the options). At most
    /// [`MAX_NESTING`] blocks are open at once.
    pub(super) fn push(&mut self, block: Block, req: &Request) -> Result<(), SceneError> {
        if self.stack.len() >= MAX_NESTING {
            return Err(SceneError::new(
                &req.file,
                req.line,
                format!(
                    "`{}`: blocks nested deeper than {MAX_NESTING} (the reader's limit; is an \
                     `{}` missing?)",
                    req.name,
                    block.begin().replace("Begin", "End")
                ),
            ));
        }
        self.stack.push(Saved {
            block,
            file: req.file.clone(),
            line: req.line,
            attrs: self.attrs.clone(),
            options: (block == Block::FrameUniforms).then(|| Box::new(self.options.clone())),
        });
        Ok(())
    }

    pub(super) fn pop(&mut self, block: Block, req: &Request) -> Result<(), SceneError> {
        let Some(saved) = self.stack.pop() else {
            return Err(SceneError::new(
                &req.file,
                req.line,
                format!("`{}` without a matching `{}`", req.name, block.begin()),
            ));
        };
        if saved.block != block {
            return Err(SceneError::new(
                &req.file,
                req.line,
                format!(
                    "`{}` does not match `{}` at {}",
                    req.name,
                    saved.block.begin(),
                    saved.place(&req.file)
                ),
            ));
        }
        if block == Block::Transform {
            self.set_ctm(saved.attrs.ctm);
            self.attrs.ctm_close = saved.attrs.ctm_close;
        } else {
            self.attrs = saved.attrs;
            self.current_material = None;
        }
        if let Some(options) = saved.options {
            self.options = *options;
        }
        Ok(())
    }

    /// Leaves the frame block `number` after an error in it: the blocks opened inside it are
    /// dropped, the state `FrameBegin` saved is restored, the world read so far is dropped.
    pub(super) fn abandon_frame(&mut self, number: u32) {
        if let Some(at) = (self.stack.iter()).rposition(|s| s.block == Block::FrameUniforms) {
            self.stack.truncate(at + 1);
            let saved = self.stack.pop().expect("the frame's block");
            self.attrs = saved.attrs;
            if let Some(options) = saved.options {
                self.options = *options;
            }
        }
        self.current_material = None;
        self.world_to_camera = None;
        self.world_to_camera_close = None;
        self.scene = Scene::default();
        self.materials.clear();
        self.instancing.end_of_world();
        self.motion = None;
        self.recording = None;
        self.frame = None;
        self.next_number = number.saturating_add(1);
    }
}
