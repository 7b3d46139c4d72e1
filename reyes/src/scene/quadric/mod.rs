//! RenderMan's quadrics (`Sphere`, `Cylinder`, `Cone`, `Disk`, `Torus`, `Paraboloid`,
//! `Hyperboloid`) as exact rational bicubic Bezier patches in object space.
//!
//! Every quadric is a surface of revolution about z (RI Specification 3.2, sec. 5.4):
//! P(u, v) = Rz(theta) Q(v) with theta = u * thetamax and a profile curve Q(v) that is a
//! circle arc (sphere, torus), a parabola (paraboloid) or a line segment (the others). The
//! sweep is cut into equal pieces of at most 90 degrees, each a rational quadratic arc; the
//! profile likewise (arcs) or in one piece (lines, the parabola, which is a polynomial
//! quadratic). Each (sweep piece, profile piece) pair is the tensor product of the two
//! curves in homogeneous coordinates (Piegl & Tiller, *The NURBS Book*, sec. 8.5, surfaces of
//! revolution), degree-elevated to bicubic. The result is the analytic surface exactly (up to
//! rounding), and u and v run in RenderMan's directions, so dPdu x dPdv points where
//! RenderMan's does: "outward" from the z axis for positive parameters, and turned round by a
//! negative `thetamax`, `zmin > zmax`, `phimin > phimax` and the like (the spec: "the sense of
//! a quadric can be reversed by giving negative parameters").
//!
//! The parametrisation within a patch is NOT RenderMan's: angles advance like the rational
//! arc's parameter (exact at the ends and the middle of each piece, up to about 4 degrees off
//! in between for a 90 degree piece), and the paraboloid's patch parameter is linear in the
//! radius where RenderMan's v is linear in z. Each patch's [`QuadricPatch::u`] and
//! [`QuadricPatch::v`] give the RenderMan parameter range it covers.

use super::rational::{arc, elevate_to_cubic, quarter_turns};
use crate::Error;
use glam::{DVec3, DVec4};

/// A quadric with its RIB arguments; angles in degrees, as RIB gives them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Quadric {
    /// phi runs from asin(zmin/radius) (-90 degrees when zmin <= -radius) to asin(zmax/radius)
    /// (90 when zmax >= radius); P = radius (cos theta cos phi, sin theta cos phi, sin phi).
    Sphere {
        radius: f64,
        zmin: f64,
        zmax: f64,
        thetamax: f64,
    },
    /// P = (radius cos theta, radius sin theta, zmin + v (zmax - zmin)).
    Cylinder {
        radius: f64,
        zmin: f64,
        zmax: f64,
        thetamax: f64,
    },
    /// P = (radius (1 - v) cos theta, radius (1 - v) sin theta, v height).
    Cone {
        height: f64,
        radius: f64,
        thetamax: f64,
    },
    /// P = (radius (1 - v) cos theta, radius (1 - v) sin theta, height).
    Disk {
        height: f64,
        radius: f64,
        thetamax: f64,
    },
    /// phi = phimin + v (phimax - phimin); P = ((major + minor cos phi) cos theta,
    /// (major + minor cos phi) sin theta, minor sin phi).
    Torus {
        major: f64,
        minor: f64,
        phimin: f64,
        phimax: f64,
        thetamax: f64,
    },
    /// z = zmin + v (zmax - zmin), r = rmax sqrt(z / zmax); P = (r cos theta, r sin theta, z).
    /// (The spec's text prints z = v (zmax - zmin), a known misprint: its own examples and
    /// every implementation start at zmin.)
    Paraboloid {
        rmax: f64,
        zmin: f64,
        zmax: f64,
        thetamax: f64,
    },
    /// The segment point1 -> point2 (at v = 0 and 1) swept about z: P = Rz(theta) ((1 - v)
    /// point1 + v point2).
    Hyperboloid {
        point1: DVec3,
        point2: DVec3,
        thetamax: f64,
    },
}

/// One bicubic patch of a quadric.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadricPatch {
    /// Homogeneous control points `(w x, w y, w z, w)`, cp[4*v + u], all weights positive.
    pub hw: [DVec4; 16],
    /// The RenderMan parameter range (u0, u1) the patch's u = 0..1 covers (monotonically,
    /// not proportionally), within [0, 1].
    pub u: (f64, f64),
    /// Likewise for v.
    pub v: (f64, f64),
}

/// A profile piece: a homogeneous cubic `(w x, w y, w z, w)` in v and its RenderMan v range.
type ProfilePiece = ([DVec4; 4], (f64, f64));

/// Sweeps larger than a full turn are cut to one (they would only cover it again).
fn full_turn_at_most(deg: f64) -> f64 {
    deg.clamp(-360.0, 360.0).to_radians()
}

/// A circle arc of the profile, centre `centre` and radius `radius` in the xz half-plane,
/// angles from the x axis towards z (radians), cut into quarter turns.
fn profile_arc(centre: f64, radius: f64, a0: f64, a1: f64) -> Vec<ProfilePiece> {
    let cuts = quarter_turns(a0, a1);
    let n = (cuts.len() - 1) as f64;
    cuts.windows(2)
        .enumerate()
        .map(|(k, c)| {
            let h = arc(c[0], c[1])
                .map(|a| DVec4::new(centre * a.z + radius * a.x, 0.0, radius * a.y, a.z));
            (elevate_to_cubic(&h), (k as f64 / n, (k + 1) as f64 / n))
        })
        .collect()
}

/// The segment from `a` to `b` as a profile of one piece.
fn profile_line(a: DVec3, b: DVec3) -> Vec<ProfilePiece> {
    vec![(
        elevate_to_cubic(&[a.extend(1.0), b.extend(1.0)]),
        (0.0, 1.0),
    )]
}

impl Quadric {
    fn thetamax(self) -> f64 {
        match self {
            Quadric::Sphere { thetamax, .. }
            | Quadric::Cylinder { thetamax, .. }
            | Quadric::Cone { thetamax, .. }
            | Quadric::Disk { thetamax, .. }
            | Quadric::Torus { thetamax, .. }
            | Quadric::Paraboloid { thetamax, .. }
            | Quadric::Hyperboloid { thetamax, .. } => thetamax,
        }
    }

    /// The profile Q(v) in pieces, in order of v.
    fn profile(self) -> Result<Vec<ProfilePiece>, Error> {
        Ok(match self {
            Quadric::Sphere {
                radius, zmin, zmax, ..
            } => {
                let half = std::f64::consts::FRAC_PI_2;
                let asin = |z: f64| (z / radius).clamp(-1.0, 1.0).asin();
                let phimin = if zmin > -radius { asin(zmin) } else { -half };
                let phimax = if zmax < radius { asin(zmax) } else { half };
                profile_arc(0.0, radius, phimin, phimax)
            }
            Quadric::Torus {
                major,
                minor,
                phimin,
                phimax,
                ..
            } => {
                let phimax = phimin + (phimax - phimin).clamp(-360.0, 360.0);
                profile_arc(major, minor, phimin.to_radians(), phimax.to_radians())
            }
            Quadric::Cylinder {
                radius, zmin, zmax, ..
            } => profile_line(DVec3::new(radius, 0.0, zmin), DVec3::new(radius, 0.0, zmax)),
            Quadric::Cone { height, radius, .. } => {
                profile_line(DVec3::new(radius, 0.0, 0.0), DVec3::new(0.0, 0.0, height))
            }
            Quadric::Disk { height, radius, .. } => profile_line(
                DVec3::new(radius, 0.0, height),
                DVec3::new(0.0, 0.0, height),
            ),
            Quadric::Hyperboloid { point1, point2, .. } => profile_line(point1, point2),
            Quadric::Paraboloid {
                rmax, zmin, zmax, ..
            } => {
                if zmax == 0.0 {
                    return Err(Error::InvalidSurface(
                        "zmax is 0: the paraboloid r = rmax sqrt(z / zmax) is undefined".into(),
                    ));
                }
                if zmin / zmax < 0.0 {
                    return Err(Error::InvalidSurface(format!(
                        "zmin {zmin} and zmax {zmax} lie on opposite sides of 0: \
                         r = rmax sqrt(z / zmax) is undefined between them"
                    )));
                }
                // z = zmax (r / rmax)^2 is a parabola in r: with r linear in the curve
                // parameter, a polynomial quadratic whose middle point has r halfway and
                // z = zmax r0 r1 / rmax^2 = zmax sqrt(zmin / zmax).
                let (q, r1) = ((zmin / zmax).sqrt(), rmax);
                let r0 = rmax * q;
                let h = [
                    DVec4::new(r0, 0.0, zmin, 1.0),
                    DVec4::new(0.5 * (r0 + r1), 0.0, zmax * q, 1.0),
                    DVec4::new(r1, 0.0, zmax, 1.0),
                ];
                vec![(elevate_to_cubic(&h), (0.0, 1.0))]
            }
        })
    }

    /// The quadric as rational bicubic Bezier patches in object space, ordered profile piece
    /// (v) major, sweep piece (u) minor: at most 4 x 4 (a torus), 4 x 2 for a whole sphere,
    /// 4 x 1 for the others. A quadric of no area (thetamax 0, a zero radius, zmin = zmax, a
    /// profile on the z axis, ...) gives no patches. Errors: a paraboloid with zmax = 0 or z
    /// range crossing 0 (the message has no location; the caller adds it). Arguments are
    /// finite (the RIB reader checks).
    pub fn to_bezier(self) -> Result<Vec<QuadricPatch>, Error> {
        let sweep = full_turn_at_most(self.thetamax());
        let profile = self.profile()?;
        let euclid = |h: &DVec4| h.truncate() / h.w;
        let first = euclid(&profile[0].0[0]);
        let all_points = || profile.iter().flat_map(|(c, _)| c.iter().map(euclid));
        let on_axis = all_points().all(|p| p.x == 0.0 && p.y == 0.0);
        let one_point = all_points().all(|p| p == first);
        if sweep == 0.0 || on_axis || one_point {
            return Ok(Vec::new());
        }
        let cuts = quarter_turns(0.0, sweep);
        let nu = (cuts.len() - 1) as f64;
        let mut out = Vec::with_capacity(profile.len() * cuts.len());
        for (b, v) in &profile {
            for (k, c) in cuts.windows(2).enumerate() {
                let a = elevate_to_cubic(&arc(c[0], c[1]));
                // Rz(theta) applied to the profile, bilinear in the two homogeneous curves:
                // x = cos Qx - sin Qy, y = sin Qx + cos Qy, z = Qz, weights multiplied.
                let hw = std::array::from_fn(|m| {
                    let (a, b) = (a[m % 4], b[m / 4]);
                    DVec4::new(
                        a.x * b.x - a.y * b.y,
                        a.y * b.x + a.x * b.y,
                        a.z * b.z,
                        a.z * b.w,
                    )
                });
                out.push(QuadricPatch {
                    hw,
                    u: (k as f64 / nu, (k + 1) as f64 / nu),
                    v: *v,
                });
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests;
