//! The quadric primitives (`Sphere`, `Cylinder`, `Cone`, `Disk`, `Torus`, `Paraboloid`,
//! `Hyperboloid`): their arguments, given bare or as one array as the RIB binding allows,
//! made into exact rational bicubic patches ([`crate::scene::quadric`]) and emitted like the
//! other patches. Their parameter lists ("Cs", "st", ...) are ignored with a warning.

use super::state::Interp;
use super::syntax::{Args, Request};
use crate::scene::SceneError;
use crate::scene::quadric::Quadric;
use crate::scene::rational::from_homogeneous;
use glam::DVec3;

/// The quadric request names.
pub(super) const QUADRICS: &[&str] = &[
    "Sphere",
    "Cylinder",
    "Cone",
    "Disk",
    "Torus",
    "Paraboloid",
    "Hyperboloid",
];

/// Reads a quadric request's fixed arguments.
fn quadric_args(req: &Request, a: &mut Args) -> Result<Quadric, SceneError> {
    Ok(match req.name.as_str() {
        "Sphere" => {
            let v = a.fixed(4, "radius zmin zmax thetamax")?;
            Quadric::Sphere {
                radius: v[0],
                zmin: v[1],
                zmax: v[2],
                thetamax: v[3],
            }
        }
        "Cylinder" => {
            let v = a.fixed(4, "radius zmin zmax thetamax")?;
            Quadric::Cylinder {
                radius: v[0],
                zmin: v[1],
                zmax: v[2],
                thetamax: v[3],
            }
        }
        "Cone" => {
            let v = a.fixed(3, "height radius thetamax")?;
            Quadric::Cone {
                height: v[0],
                radius: v[1],
                thetamax: v[2],
            }
        }
        "Disk" => {
            let v = a.fixed(3, "height radius thetamax")?;
            Quadric::Disk {
                height: v[0],
                radius: v[1],
                thetamax: v[2],
            }
        }
        "Torus" => {
            let v = a.fixed(5, "majorradius minorradius phimin phimax thetamax")?;
            Quadric::Torus {
                major: v[0],
                minor: v[1],
                phimin: v[2],
                phimax: v[3],
                thetamax: v[4],
            }
        }
        "Paraboloid" => {
            let v = a.fixed(4, "rmax zmin zmax thetamax")?;
            Quadric::Paraboloid {
                rmax: v[0],
                zmin: v[1],
                zmax: v[2],
                thetamax: v[3],
            }
        }
        _ => {
            let v = a.fixed(7, "point1 point2 thetamax")?;
            Quadric::Hyperboloid {
                point1: DVec3::from_slice(&v[0..3]),
                point2: DVec3::from_slice(&v[3..6]),
                thetamax: v[6],
            }
        }
    })
}

impl Interp {
    /// One quadric request: its patches (none for a quadric of no area), in the object's
    /// transform, with the current orientation (see `rib/mod.rs`).
    pub(super) fn quadric(&mut self, req: &Request, a: &mut Args) -> Result<(), SceneError> {
        let q = quadric_args(req, a)?;
        for p in a.params()? {
            self.ignored_param(req, p.name);
        }
        let ctm = self.geometry_ctm(a)?;
        let patches = q.to_bezier().map_err(|m| a.err(m))?;
        for (i, p) in patches.iter().enumerate() {
            let (cp, w) = from_homogeneous(&p.hw);
            self.emit(a, &ctm, i, cp, w)?;
        }
        Ok(())
    }
}
