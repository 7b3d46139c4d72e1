//! Retained objects: `ObjectBegin` / `ObjectEnd` record the requests between them under a
//! handle (a number, as RIB 3.03 writes it, or a name), and `ObjectInstance` replays them as
//! if they stood there inside an `AttributeBegin` / `AttributeEnd`: the object's geometry,
//! attributes and transforms apply on top of the transform and attributes current at the
//! instance (RenderMan Interface Specification 3.2, section 5.6), so every instance stands
//! under its own transform. Archives read inside the definition are recorded with it.
//!
//! Build once, place many: each primitive of a definition is built (parsed, converted to
//! Bezier patches, subdivided) once, at its first replay, and kept as its object-space nets
//! with what does not depend on the placement: colour fields, rational weights, trims
//! ([`Instancing`]). Later replays run the definition's other requests as before (attributes
//! and transforms: cheap), and place the kept nets under the current transform through the
//! same [`Interp::emit_net`] a build uses, with the current attributes (material,
//! orientation, sides, displacement, motion). So an instance is drawn bit for bit as a
//! replay draws it, and its patches share (`Arc`) the fields, weights and trims, which the
//! GPU's tables hold once (`frame::patch_info`). docs/reyes.md, *Instances*.

use super::lexer::shown;
use super::state::{Block, Interp};
use super::syntax::{Arg, Args, Request};
use crate::scene::basis::Basis;
use crate::scene::trim::{PatchTrim, TrimLoops};
use crate::scene::{BilinearForm, ColorField, Patch, Primvars, SceneError};
use glam::{DMat3, DMat4, DVec3};
use std::collections::HashMap;
use std::rc::Rc;
use std::sync::Arc;

/// Most nested instance replays (an object whose definition instances another): bounds the
/// recursion of a definition that instances itself through a redefinition.
const MAX_INSTANCE_DEPTH: usize = 64;

/// Most builds kept of one primitive of a definition (one per state it was built under:
/// bases, trim curves, declarations); past it the primitive is built at each replay.
const MAX_BUILDS: usize = 8;

/// Requests whose patches depend on the transform only through [`Interp::emit_net`]'s
/// `ctm` (checked again for each build): kept and placed, with the quadrics
/// ([`placeable_request`]). The others (curves and points, which face the camera; everything
/// that is not geometry) run at every replay.
const PLACEABLE: &[&str] = &[
    "Patch",
    "PatchMesh",
    "NuPatch",
    "Polygon",
    "GeneralPolygon",
    "PointsPolygons",
    "PointsGeneralPolygons",
    "SubdivisionMesh",
];

/// Whether request `name` is built once and placed ([`PLACEABLE`] and the quadrics).
fn placeable_request(name: &str) -> bool {
    PLACEABLE.contains(&name) || super::quadrics::QUADRICS.contains(&name)
}

/// The kept builds of the primitives of object definitions, and the build under way.
#[derive(Default)]
pub(super) struct Instancing {
    /// By (the definition's address, the request's index in it). A definition's builds go
    /// when it is replaced (its address may be reused) and all at the end of each world.
    builds: HashMap<(usize, usize), Vec<Build>>,
    /// The loops of the definitions' `TrimCurve`s, by the same key: read once, so that the
    /// primitives after one find their builds (whose key holds the loops) and share them.
    trims: HashMap<(usize, usize), Option<Arc<TrimLoops>>>,
    /// What [`Interp::emit_net`] and the polygons are given while a primitive is built.
    capture: Option<Capture>,
    /// Counts `Declare`s: a declaration changes how a primitive's parameters read.
    declarations: u64,
}

impl Instancing {
    /// Drops every build (at the end of a world: the builds hold at most what its patches
    /// hold, so a file of many frames keeps one frame's worth).
    pub(super) fn end_of_world(&mut self) {
        self.builds.clear();
        self.trims.clear();
    }

    /// Called by [`Interp::emit_net`] with the object-space net it transforms: kept while a
    /// primitive is built for its instances.
    /// True while a primitive is built for instances (its object-space parts are kept).
    pub(super) fn capturing(&self) -> bool {
        self.capture.is_some()
    }

    /// The object-space `"N"` field of the patch just emitted (polygon meshes).
    pub(super) fn captured_normals(&mut self, field: ColorField) {
        if let Some(e) = self.capture.as_mut().and_then(|c| c.emitted.last_mut()) {
            e.normals = Some(field);
        }
    }

    /// Every object-space `"N"` value of the request (each placement checks them as a build
    /// does).
    pub(super) fn captured_normal_values(&mut self, values: &[DVec3]) {
        if let Some(c) = &mut self.capture {
            c.normal_values = Some(values.to_vec());
        }
    }

    pub(super) fn captured(
        &mut self,
        ctm: &DMat4,
        index: usize,
        cp: &[DVec3; 16],
        bilinear: Option<([DVec3; 4], BilinearForm)>,
    ) {
        if let Some(c) = &mut self.capture {
            c.emitted.push(Emitted {
                ctm: *ctm,
                index,
                net: match bilinear {
                    Some((corners, form)) => PlacedNet::Bilinear(corners, form),
                    None => PlacedNet::Bicubic(Box::new(*cp)),
                },
                normals: None,
            });
        }
    }

    /// A `Declare` was read.
    pub(super) fn declared(&mut self) {
        self.declarations += 1;
    }
}

/// The state a primitive's build depends on besides its request (the rest is applied when
/// it is placed): its bases, trim curves and the declarations.
struct BuildKey {
    ubasis: Basis,
    vbasis: Basis,
    trim: Option<Arc<TrimLoops>>,
    trim_outside: bool,
    declarations: u64,
}

impl BuildKey {
    fn same(&self, o: &BuildKey) -> bool {
        let trim = match (&self.trim, &o.trim) {
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            (a, b) => a.is_none() && b.is_none(),
        };
        trim && self.ubasis == o.ubasis
            && self.vbasis == o.vbasis
            && self.trim_outside == o.trim_outside
            && self.declarations == o.declarations
    }
}

/// One build of a primitive: its patches, or `None` when they cannot be placed (some net
/// was not under the current transform, or a patch has normals not kept in object space).
struct Build {
    key: BuildKey,
    patches: Option<Rc<Built>>,
}

/// The placeable patches of one build.
struct Built {
    patches: Vec<Placed>,
    /// The request's `"N"` values in object space (polygon meshes with normals).
    normal_values: Option<Vec<DVec3>>,
}

/// What a build is given.
#[derive(Default)]
struct Capture {
    emitted: Vec<Emitted>,
    normal_values: Option<Vec<DVec3>>,
}

/// A net given to [`Interp::emit_net`] during a build.
struct Emitted {
    ctm: DMat4,
    index: usize,
    net: PlacedNet,
    /// The patch's `"N"` field in object space.
    normals: Option<ColorField>,
}

/// An object-space net as [`Interp::emit_net`] takes it.
enum PlacedNet {
    /// Corners of a bilinear patch and how they are elevated.
    Bilinear([DVec3; 4], BilinearForm),
    /// 16 Euclidean control points.
    Bicubic(Box<[DVec3; 16]>),
}

/// A built patch: its object-space net and what every placement shares.
struct Placed {
    index: usize,
    net: PlacedNet,
    weights: Option<Arc<[f64; 16]>>,
    /// The fields; without `"N"` when the patch has normals (`normals`).
    primvars: Option<Arc<Primvars>>,
    /// The `"N"` field in object space: each placement takes it to camera space, and its
    /// fields are then its own.
    normals: Option<ColorField>,
    trim: Option<Arc<PatchTrim>>,
}

/// The placeable form of the patches `built` of one request from what `capture` kept
/// while building it under `ctm`; `None` when they cannot be placed.
fn placeable(capture: Capture, built: &[Patch], ctm: &DMat4) -> Option<Rc<Built>> {
    if capture.emitted.len() != built.len() {
        return None;
    }
    let patches = (capture.emitted.into_iter().zip(built))
        .map(|(e, p)| {
            let normals = p.primvars.as_ref().is_some_and(|v| v.n.is_some());
            if e.ctm != *ctm || normals != e.normals.is_some() {
                return None;
            }
            let primvars = match (&p.primvars, normals) {
                (Some(v), true) => Primvars {
                    n: None,
                    ..Primvars::clone(v)
                }
                .shared(),
                (v, _) => v.clone(),
            };
            Some(Placed {
                index: e.index,
                net: e.net,
                weights: p.net.shared_weights().cloned(),
                primvars,
                normals: e.normals,
                trim: p.trim.clone(),
            })
        })
        .collect::<Option<Vec<Placed>>>()?;
    let normal_values = capture.normal_values;
    if patches.iter().any(|p| p.normals.is_some()) && normal_values.is_none() {
        return None;
    }
    Some(Rc::new(Built {
        patches,
        normal_values,
    }))
}

/// `field` (of normals) taken to camera space by `m`, the inverse transpose of the
/// transform's linear part (as [`super::primvars::normals_to_camera`] takes the values).
fn normals_by(field: &ColorField, m: &DMat3) -> ColorField {
    match field {
        ColorField::Flat(c) => ColorField::Flat(*m * *c),
        ColorField::Bilinear(c) => ColorField::Bilinear(c.map(|c| *m * c)),
        ColorField::Bezier(c) => ColorField::Bezier(c.map(|c| *m * c)),
    }
}

/// The definition being recorded.
pub(super) struct Recording {
    pub(super) handle: String,
    pub(super) line: u64,
    pub(super) requests: Vec<Request>,
}

/// The handle of `ObjectBegin` / `ObjectInstance`: a number or a string.
fn handle(a: &mut Args) -> Result<String, SceneError> {
    let h = match a.take("the object handle")? {
        Arg::Num(v) => format!("{v}"),
        Arg::Nums(v) if v.len() == 1 => format!("{}", v[0]),
        Arg::Str(s) => s.clone(),
        Arg::Strs(v) if v.len() == 1 => v[0].clone(),
        other => {
            return Err(a.err(format!(
                "expected a number or a name for the object handle, found {}",
                other.describe()
            )));
        }
    };
    a.done()?;
    Ok(h)
}

/// Requests that may not stand inside an object definition (they end or start blocks the
/// definition cannot hold).
const NOT_IN_OBJECT: &[&str] = &["FrameBegin", "FrameEnd", "WorldBegin", "WorldEnd"];

impl Interp {
    /// `ObjectBegin handle`: starts recording.
    pub(super) fn object_begin(&mut self, req: &Request) -> Result<(), SceneError> {
        let mut a = Args::new(req);
        let handle = handle(&mut a)?;
        if let Some(r) = &self.recording {
            return Err(a.err(format!(
                "object definitions do not nest (`ObjectBegin` at line {} is open)",
                r.line
            )));
        }
        self.recording = Some(Recording {
            handle,
            line: req.line,
            requests: Vec::new(),
        });
        Ok(())
    }

    /// While recording: keeps `req` for the definition, or ends it at `ObjectEnd`.
    pub(super) fn record(&mut self, req: Request) -> Result<(), SceneError> {
        if req.name == "ObjectBegin" {
            return self.object_begin(&req);
        }
        if NOT_IN_OBJECT.contains(&req.name.as_str()) {
            let line = self.recording.as_ref().map_or(0, |r| r.line);
            return Err(Args::new(&req).err(format!(
                "not allowed inside `ObjectBegin` ... `ObjectEnd` (begun at line {line})"
            )));
        }
        if req.name == "ObjectEnd" {
            Args::new(&req).done()?;
            if let Some(r) = self.recording.take()
                && let Some(old) = self.objects.insert(r.handle, Rc::from(r.requests))
            {
                // The old definition's address may be reused: its builds go with it.
                let at = Rc::as_ptr(&old) as *const Request as usize;
                self.instancing.builds.retain(|k, _| k.0 != at);
                self.instancing.trims.retain(|k, _| k.0 != at);
            }
            return Ok(());
        }
        if let Some(r) = &mut self.recording {
            r.requests.push(req);
        }
        Ok(())
    }

    /// `ObjectInstance handle`: the object's requests, inside an attribute block.
    pub(super) fn object_instance(&mut self, req: &Request) -> Result<(), SceneError> {
        let mut a = Args::new(req);
        let h = handle(&mut a)?;
        let Some(def) = self.objects.get(&h).cloned() else {
            return Err(a.err(format!("no object \"{}\" is defined", shown(&h))));
        };
        if self.instance_depth >= MAX_INSTANCE_DEPTH {
            return Err(a.err(format!(
                "instances nested deeper than {MAX_INSTANCE_DEPTH} (does an object instance \
                 itself?)"
            )));
        }
        self.instance_depth += 1;
        let at = Rc::as_ptr(&def) as *const Request as usize;
        let r = (|| {
            self.push(Block::Attribute, req)?;
            for (i, r) in def.iter().enumerate() {
                if self.motion.is_some() && r.name != "MotionEnd" && self.motion_request(r)? {
                    continue;
                }
                if r.name == "ObjectInstance" {
                    self.object_instance(r)?;
                } else if r.name == "TrimCurve" {
                    self.instanced_trim_curve((at, i), r)?;
                } else if self.motion.is_none() && placeable_request(&r.name) {
                    self.instanced_primitive((at, i), r)?;
                } else {
                    self.request(r)?;
                }
            }
            self.pop(Block::Attribute, req)
        })();
        self.instance_depth -= 1;
        r
    }

    /// The state a primitive's build depends on now ([`BuildKey`]).
    fn build_key(&self) -> BuildKey {
        BuildKey {
            ubasis: self.attrs.ubasis,
            vbasis: self.attrs.vbasis,
            trim: self.attrs.trim.clone(),
            trim_outside: self.attrs.trim_outside,
            declarations: self.instancing.declarations,
        }
    }

    /// `TrimCurve` `req` of a definition (`at` as for [`Self::instanced_primitive`]): its
    /// loops as the first replay read them (they depend on the request alone).
    fn instanced_trim_curve(
        &mut self,
        at: (usize, usize),
        req: &Request,
    ) -> Result<(), SceneError> {
        if let Some(loops) = self.instancing.trims.get(&at) {
            self.attrs.trim = loops.clone();
            return Ok(());
        }
        self.request(req)?;
        self.instancing.trims.insert(at, self.attrs.trim.clone());
        Ok(())
    }

    /// Primitive `req` of a definition (`at`: the definition's address and the request's
    /// index): placed from its build under the current state, or built (and kept).
    fn instanced_primitive(&mut self, at: (usize, usize), req: &Request) -> Result<(), SceneError> {
        let key = self.build_key();
        let kept = (self.instancing.builds.get(&at))
            .and_then(|v| v.iter().find(|b| b.key.same(&key)))
            .map(|b| b.patches.clone());
        match kept {
            Some(Some(patches)) => return self.place(req, &patches),
            Some(None) => return self.request(req),
            None => {}
        }
        let (start, ctm) = (self.scene.patches.len(), self.attrs.ctm);
        self.instancing.capture = Some(Capture::default());
        let r = self.request(req);
        let capture = self.instancing.capture.take().unwrap_or_default();
        r?;
        let patches = placeable(capture, &self.scene.patches[start..], &ctm);
        let builds = self.instancing.builds.entry(at).or_default();
        if builds.len() < MAX_BUILDS {
            builds.push(Build { key, patches });
        }
        Ok(())
    }

    /// The built `patches` of `req` under the current transform and attributes, as
    /// [`Interp::emit_net`] made them in the build (so with the same checks and bits).
    fn place(&mut self, req: &Request, built: &Built) -> Result<(), SceneError> {
        let a = Args::new(req);
        let ctm = self.geometry_ctm(&a)?;
        // The normals: checked as a build checks them (all, in camera space), and the
        // inverse transpose of the same linear part to take each patch's field there.
        let normals = match &built.normal_values {
            None => None,
            Some(values) => {
                let linear = DMat3::from_mat4(ctm);
                let values = values.iter().map(|v| v.as_ref().as_slice());
                super::primvars::normals_to_camera(&a, linear, values)?;
                Some(linear.inverse().transpose())
            }
        };
        for p in &built.patches {
            let w = p.weights.as_deref().copied().unwrap_or(Patch::POLYNOMIAL);
            let (cp, bilinear) = match &p.net {
                PlacedNet::Bilinear(corners, form) => {
                    let cp = match form {
                        BilinearForm::Patch => crate::scene::bilinear_to_bezier(*corners),
                        BilinearForm::Polygon => crate::scene::polygon::bilinear_patch(*corners),
                    };
                    (cp, Some((*corners, *form)))
                }
                PlacedNet::Bicubic(cp) => (**cp, None),
            };
            self.emit_net(&a, &ctm, p.index, cp, w, bilinear, p.weights.as_ref())?;
            if let Some(last) = self.scene.patches.last_mut() {
                last.primvars = match (&p.normals, &normals) {
                    (Some(n), Some(m)) => Primvars {
                        n: Some(normals_by(n, m)),
                        ..p.primvars.as_deref().cloned().unwrap_or_default()
                    }
                    .shared(),
                    _ => p.primvars.clone(),
                };
                last.trim = p.trim.clone();
            }
        }
        Ok(())
    }
}
