//! Retained objects: `ObjectBegin` / `ObjectEnd` record the requests between them under a
//! handle (a number, as RIB 3.03 writes it, or a name), and `ObjectInstance` replays them as
//! if they stood there inside an `AttributeBegin` / `AttributeEnd`: the object's geometry,
//! attributes and transforms apply on top of the transform and attributes current at the
//! instance (RenderMan Interface Specification 3.2, section 5.6), so every instance stands
//! under its own transform. Archives read inside the definition are recorded with it.
//!
//! An instance is expanded into its own patches (no data is shared between instances on the
//! device): a scene of N instances costs what N copies cost.

use super::lexer::shown;
use super::state::{Block, Interp};
use super::syntax::{Arg, Args, Request};
use crate::scene::SceneError;
use std::rc::Rc;

/// Most nested instance replays (an object whose definition instances another): bounds the
/// recursion of a definition that instances itself through a redefinition.
const MAX_INSTANCE_DEPTH: usize = 64;

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
            if let Some(r) = self.recording.take() {
                self.objects.insert(r.handle, Rc::from(r.requests));
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
        let r = (|| {
            self.push(Block::Attribute, req)?;
            for r in def.iter() {
                if self.motion.is_some() && r.name != "MotionEnd" && self.motion_request(r)? {
                    continue;
                }
                if r.name == "ObjectInstance" {
                    self.object_instance(r)?;
                } else {
                    self.request(r)?;
                }
            }
            self.pop(Block::Attribute, req)
        })();
        self.instance_depth -= 1;
        r
    }
}
