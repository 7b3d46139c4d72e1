//! Motion blur and depth of field in RIB: the `Shutter` and `DepthOfField` options, and
//! `MotionBegin [t0 ... tn] ... MotionEnd` blocks around transforms.
//!
//! A motion block holds one request per time; around transforms, the first request gives the
//! object-to-camera transform at the first time and the last request the one at the last time
//! (requests between are checked, then unused: the renderer moves points linearly). At
//! `MotionEnd` the two are interpolated to the shutter's open and close times (clamped to the
//! block's times: outside them the object holds still), and become the current transform
//! ([`Attributes::ctm`]) and its value at shutter close ([`Attributes::ctm_close`]); later
//! transforms apply to both. A patch emitted under a moving transform keeps its shutter-open
//! points and the camera-space map to its shutter-close points ([`crate::scene::Patch::motion`]).
//!
//! Camera motion is the same block before `WorldBegin`, around the camera's transforms: the
//! world-to-camera transform then has a shutter-close value too, which every transform in the
//! world builds on, so each object's map from shutter open to close includes the camera's
//! (inverse) motion: a still object seen by a moving camera moves in camera space exactly as
//! if it had moved the opposite way before a still camera. Lights stay where they are at
//! shutter open. Motion blocks around anything but transforms keep the first time's request,
//! with a warning.

use super::lexer::shown;
use super::state::{Attributes, Interp};
use super::syntax::{Args, Request};
use crate::scene::{DepthOfField, SceneError};
use glam::DMat4;

/// Requests that change the current transform; only these may move.
const TRANSFORMS: &[&str] = &[
    "Translate",
    "Rotate",
    "Scale",
    "Skew",
    "ConcatTransform",
    "Transform",
    "Identity",
];

/// An open `MotionBegin` block.
pub(super) struct MotionBlock {
    /// The block's times, increasing.
    times: Vec<f64>,
    pub(super) line: u64,
    /// Requests read so far inside the block.
    seen: usize,
    /// The name of the block's first request (all must be the same request).
    name: String,
    /// The transform at shutter open and close before the block.
    before: (DMat4, DMat4),
    /// The transform after the first and after the last request.
    first: Option<DMat4>,
    last: Option<DMat4>,
    /// The block moves transforms (of an object in the world block, or the camera's before it).
    moving: bool,
}

/// The largest lens radius `DepthOfField` takes, in focal distances: the renderer's f32
/// circle of confusion at the focal plane (a rounding error times focal length in pixels times
/// this ratio) stays about 0.01 pixel per 1,000 pixels of focal length (real lenses are
/// below 0.1).
pub(crate) const MAX_LENS_RATIO: f64 = 100.0;

impl Interp {
    /// `Shutter open close` and `DepthOfField fstop focallength focaldistance` (options).
    pub(super) fn lens_option(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        if self.world_to_camera.is_some() {
            return Err(a.err("an option: not allowed inside `WorldBegin` ... `WorldEnd`"));
        }
        if req.name == "Shutter" {
            let open = a.num("the open time")?;
            let close = a.num("the close time")?;
            a.done()?;
            if !(open.is_finite() && close.is_finite() && open <= close) {
                return Err(a.err(format!(
                    "need finite times with open <= close, found open {open} close {close}"
                )));
            }
            self.options.camera.shutter = (open, close);
            return Ok(());
        }
        // RenderMan: `DepthOfField` with no arguments (or an infinite f-stop) is a pinhole.
        if a.peek().is_none() {
            self.options.camera.depth_of_field = None;
            return Ok(());
        }
        let fstop = a.num("the f-stop")?;
        let focal_length = a.num("the focal length")?;
        let focal_distance = a.num("the focal distance")?;
        a.done()?;
        if fstop == f64::INFINITY {
            self.options.camera.depth_of_field = None;
            return Ok(());
        }
        for (name, v) in [
            ("f-stop", fstop),
            ("focal length", focal_length),
            ("focal distance", focal_distance),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(a.err(format!("the {name} must be positive and finite, found {v}")));
            }
        }
        let dof = DepthOfField {
            fstop,
            focal_length,
            focal_distance,
        };
        // The renderer's circle of confusion at depth z is focal_px x lens radius x (1 /
        // focus - 1 / z) in f32: at the focal plane the difference is a rounding error, which
        // the lens radius over the focal distance magnifies (1e14 made every pixel white).
        // Computed in f64 here, before any f32 sees it.
        let ratio = dof.lens_radius() / focal_distance;
        if !(ratio <= MAX_LENS_RATIO && (dof.lens_radius() * 1e6) as f32 <= f32::MAX) {
            return Err(a.err(format!(
                "the lens radius (focal length / (2 f-stop) = {:e}) is {ratio:e} times the focal \
                 distance: at most {MAX_LENS_RATIO} (beyond it f32 rounding blurs the focal \
                 plane itself)",
                dof.lens_radius()
            )));
        }
        self.options.camera.depth_of_field = Some(dof);
        Ok(())
    }

    /// `MotionBegin [times]`: opens a motion block.
    pub(super) fn motion_begin(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        if self.motion.is_some() {
            return Err(a.err("nested `MotionBegin`"));
        }
        let times = a.array("the times")?.to_vec();
        a.done()?;
        if times.is_empty() || times.iter().any(|t| !t.is_finite()) {
            return Err(a.err("need one or more finite times"));
        }
        // The pair at fault, not the list: a list of 200,000 times once made one 1.9 MB line.
        if let Some(k) = times.windows(2).position(|w| w[0] >= w[1]) {
            return Err(a.err(format!(
                "the times must increase: time {} of {} ({}) is not after time {} ({})",
                k + 2,
                times.len(),
                times[k + 1],
                k + 1,
                times[k]
            )));
        }
        let c = &self.attrs;
        self.motion = Some(MotionBlock {
            times,
            line: req.line,
            seen: 0,
            name: String::new(),
            before: (c.ctm, c.ctm_close.unwrap_or(c.ctm)),
            first: None,
            last: None,
            moving: false,
        });
        Ok(())
    }

    /// A request inside a motion block (not `MotionEnd`): true when it was used or skipped
    /// here, false when the caller runs it as usual.
    pub(super) fn motion_request(&mut self, req: &Request) -> Result<bool, SceneError> {
        let Some(m) = self.motion.as_mut() else {
            return Ok(false);
        };
        let k = m.seen;
        m.seen += 1;
        if k == 0 {
            m.name = req.name.clone();
        } else if req.name != m.name {
            let msg = format!(
                "a motion block holds one kind of request: `{}` after `{}` (`MotionBegin` at \
                 line {})",
                shown(&req.name),
                shown(&m.name),
                m.line
            );
            return Err(SceneError::new(&req.file, req.line, msg));
        }
        let n = m.times.len();
        if k >= n {
            let msg = format!(
                "the motion block (`MotionBegin` at line {}) has {n} time(s) and more requests",
                m.line
            );
            return Err(SceneError::new(&req.file, req.line, msg));
        }
        if !TRANSFORMS.contains(&req.name.as_str()) {
            if k == 0 {
                let what = format!(
                    "motion of `{}` is not supported (the image has no blur from it)",
                    shown(&req.name)
                );
                let key = format!("motion {what}");
                self.warn_once(req, &key, &format!("{what}: using the first time sample"));
                return Ok(false);
            }
            return Ok(true);
        }
        // A transform: run it from the transform before the block at the first time (which
        // also updates the orientation, as the unmoving request would), and from the
        // shutter-close transform before the block at the last; the others are only checked.
        let (before_open, before_close) = m.before;
        let saved = self.attrs.clone();
        let base = if k == 0 { before_open } else { before_close };
        self.attrs.ctm = base;
        self.attrs.ctm_close = None;
        self.request(req)?;
        let after = self.attrs.ctm;
        let m = self.motion.as_mut().expect("open motion block");
        m.moving = true;
        if k == 0 {
            m.first = Some(after);
            self.attrs.ctm_close = saved.ctm_close;
        } else {
            self.attrs = saved;
        }
        if k + 1 == n {
            self.motion.as_mut().expect("open motion block").last = Some(after);
        }
        Ok(true)
    }

    /// `MotionEnd`: closes the block; a moving transform becomes the current transform at
    /// shutter open and close.
    pub(super) fn motion_end(&mut self, req: &Request) -> Result<(), SceneError> {
        let a = Args::new(req);
        a.done()?;
        let Some(m) = self.motion.take() else {
            return Err(a.err("without a matching `MotionBegin`"));
        };
        if m.seen != m.times.len() {
            return Err(a.err(format!(
                "the motion block (`MotionBegin` at line {}) has {} time(s) but {} request(s)",
                m.line,
                m.times.len(),
                m.seen
            )));
        }
        if !m.moving {
            return Ok(());
        }
        let (Some(first), Some(last)) = (m.first, m.last) else {
            return Ok(());
        };
        let (t0, t1) = (m.times[0], m.times[m.times.len() - 1]);
        let at = |s: f64| {
            let f = if t1 > t0 {
                ((s - t0) / (t1 - t0)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            first * (1.0 - f) + last * f
        };
        let (open, close) = self.options.camera.shutter;
        let (c_open, c_close) = (at(open), at(close));
        self.set_ctm(c_open);
        self.attrs.ctm_close = (c_close != c_open).then_some(c_close);
        Ok(())
    }
}

impl Attributes {
    /// The camera-space map from a patch at shutter open to the same patch at shutter close
    /// (`ctm_close * ctm^-1`), `None` when the transform does not move (or cannot be inverted,
    /// a degenerate transform whose patches are flat anyway).
    pub(super) fn motion(&self) -> Option<Box<DMat4>> {
        let close = self.ctm_close?;
        let inv = self.ctm.inverse();
        let d = close * inv;
        (d.is_finite() && d != DMat4::IDENTITY).then(|| Box::new(d))
    }
}
