//! `Displacement` (the built-in displacement shaders, [`DISPLACEMENT_NAMES`]) and
//! `Attribute "displacementbound"`: what they set in the attributes, and the camera-space
//! [`Displacement`] a patch gets from them ([`Interp::displacement`]).

use super::lexer::shown;
use super::state::Interp;
use super::syntax::{Arg, Args, Request};
use crate::scene::{
    DISPLACEMENT_NAMES, Displacement, DisplacementMap, DisplacementPattern, MAX_BUMPS_FREQUENCY,
    SceneError,
};
use glam::{DMat3, DMat4, DVec3};
use std::path::Path;
use std::sync::Arc;

impl Interp {
    /// `Displacement "bumps" "Km" k` or `Displacement "mapped" "mapname" "file" "Km" k`
    /// (`"Km"` defaults to 1). An unknown name is skipped with a warning, as `Surface` skips
    /// one; bad values are errors naming the line.
    pub(super) fn displacement_request(
        &mut self,
        req: &Request,
        a: &mut Args,
    ) -> Result<(), SceneError> {
        let name = a.string("the shader name")?;
        if !DISPLACEMENT_NAMES.contains(&name) {
            let msg = super::requests::with_suggestion(
                format!(
                    "skipped unsupported displacement shader \"{}\" (keeping the previous \
                     displacement; built in: {})",
                    shown(name),
                    DISPLACEMENT_NAMES.join(", ")
                ),
                name,
                DISPLACEMENT_NAMES,
            );
            self.warn_once(req, &format!("Displacement \"{name}\""), &msg);
            return Ok(());
        }
        let mut km = 1.0;
        let mut frequency = 1.0;
        let mut mapname = None;
        for p in a.params()? {
            match (name, p.name) {
                (_, "Km") => km = p.num(a)?,
                ("bumps", "frequency") => frequency = p.num(a)?,
                ("mapped", "mapname") => match p.value {
                    Arg::Str(s) => mapname = Some(s.as_str()),
                    Arg::Strs(v) if v.len() == 1 => mapname = Some(v[0].as_str()),
                    other => {
                        return Err(a.err(format!(
                            "parameter \"mapname\" needs one file name, found {}",
                            other.describe()
                        )));
                    }
                },
                (_, other) => self.ignored_param(req, other),
            }
        }
        if !(km as f32).is_finite() {
            return Err(a.err(format!(
                "\"Km\" {km:e} is beyond the f32 range the renderer displaces in"
            )));
        }
        let pattern = match name {
            "bumps" => {
                let max = MAX_BUMPS_FREQUENCY as f64;
                if !(frequency.fract() == 0.0 && (1.0..=max).contains(&frequency)) {
                    return Err(a.err(format!(
                        "bumps \"frequency\" {frequency} must be a whole number 1..={max}"
                    )));
                }
                DisplacementPattern::Bumps {
                    frequency: frequency as u32,
                }
            }
            _ => {
                let Some(file) = mapname else {
                    return Err(a.err("displacement \"mapped\" needs \"mapname\" (a PNG or EXR)"));
                };
                DisplacementPattern::Map(self.displacement_map(a, file)?)
            }
        };
        self.attrs.displacement = Some((pattern, km));
        Ok(())
    }

    /// The map `file`, looked up beside the RIB file, then in the current directory; read
    /// once per file.
    fn displacement_map(
        &mut self,
        a: &Args,
        file: &str,
    ) -> Result<Arc<DisplacementMap>, SceneError> {
        let beside = Path::new(&*a.req.file)
            .parent()
            .map(|d| d.join(file))
            .unwrap_or_else(|| file.into());
        let path = if beside.exists() { beside } else { file.into() };
        let key = path.to_string_lossy().into_owned();
        if let Some(m) = self.displacement_maps.get(&key) {
            return Ok(m.clone());
        }
        let map = Arc::new(DisplacementMap::load(&path).map_err(|e| a.err(e))?);
        self.displacement_maps.insert(key, map.clone());
        Ok(map)
    }

    /// `Attribute "displacementbound" "sphere" [r] ["coordinatesystem" "space"]`, r in
    /// `"object"` space (the default; also `"shader"`), `"world"` or `"camera"` (also
    /// `"current"`); `Attribute "identifier"` (the object's name, which exporters write for
    /// every object and nothing in the image depends on) is read without a word; other
    /// attributes are skipped with a warning.
    pub(super) fn attribute_request(
        &mut self,
        req: &Request,
        a: &mut Args,
    ) -> Result<(), SceneError> {
        let name = a.string("the attribute name")?;
        let params = a.params()?;
        if name == "trimcurve" {
            return self.trim_attribute(req, a, &params);
        }
        if name == "identifier" {
            return Ok(());
        }
        if name != "displacementbound" {
            let msg = format!("skipped unsupported attribute \"{}\"", shown(name));
            self.warn_once(req, &format!("Attribute \"{name}\""), &msg);
            return Ok(());
        }
        let mut radius = None;
        let mut space = BoundSpace::Object;
        for p in params {
            match p.name {
                "sphere" => {
                    let r = p.num(a)?;
                    if !(r >= 0.0 && (r as f32).is_finite()) {
                        return Err(a.err(format!(
                            "displacementbound \"sphere\" {r} must be a finite radius >= 0"
                        )));
                    }
                    radius = Some(r);
                }
                "coordinatesystem" => {
                    let name = match p.value {
                        Arg::Str(s) => Some(s.as_str()),
                        Arg::Strs(v) if v.len() == 1 => Some(v[0].as_str()),
                        _ => None,
                    };
                    space = match name {
                        Some("object" | "shader") => BoundSpace::Object,
                        Some("world") => BoundSpace::World,
                        Some("camera" | "current") => BoundSpace::Camera,
                        _ => {
                            return Err(a.err(format!(
                                "displacementbound \"coordinatesystem\" {}: expected \"object\", \
                                 \"shader\", \"world\", \"camera\" or \"current\"",
                                p.value.describe()
                            )));
                        }
                    };
                }
                other => self.ignored_param(req, other),
            }
        }
        if let Some(r) = radius {
            // An object-space radius follows each primitive's transform ([`Self::
            // displacement`]); one in world or camera space is taken to camera space now.
            self.attrs.displacement_bound = match space {
                BoundSpace::Object => (r, 0.0),
                BoundSpace::World => {
                    let m = self.world_to_camera.unwrap_or(DMat4::IDENTITY);
                    (0.0, r * largest_stretch(&DMat3::from_mat4(m)))
                }
                BoundSpace::Camera => (0.0, r),
            };
        }
        Ok(())
    }

    /// The camera-space displacement of a patch emitted with object-to-camera `ctm` under
    /// the current attributes (see [`Displacement`] for the scales).
    pub(super) fn displacement(&self, ctm: &DMat4) -> Option<Arc<Displacement>> {
        let (pattern, km) = self.attrs.displacement.clone()?;
        let m = DMat3::from_mat4(*ctm);
        let mean_scale = m.determinant().abs().cbrt();
        let amount = km * mean_scale;
        let (object, camera) = self.attrs.displacement_bound;
        let bound = (object * largest_stretch(&m)).max(camera).max(amount.abs());
        Some(Arc::new(Displacement {
            pattern,
            amount,
            bound,
        }))
    }
}

/// Spaces `"displacementbound"` may be given in.
#[derive(Clone, Copy)]
enum BoundSpace {
    Object,
    World,
    Camera,
}

/// The largest singular value of `m` (how far it moves a point of a unit sphere at most):
/// the square root of the largest eigenvalue of m^T m by power iteration, started from each
/// axis so that no start is orthogonal to the answer, times 1 + 1e-6 so that the iteration's
/// shortfall (from below) cannot make the bound too small.
fn largest_stretch(m: &DMat3) -> f64 {
    let mtm = m.transpose() * *m;
    let mut best = 0f64;
    for start in [DVec3::X, DVec3::Y, DVec3::Z] {
        let mut x = start;
        for _ in 0..64 {
            let y = mtm * x;
            let l = y.length();
            if l == 0.0 {
                break;
            }
            x = y / l;
        }
        best = best.max((*m * x).length());
    }
    best * (1.0 + 1e-6)
}
