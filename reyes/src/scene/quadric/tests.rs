//! The quadric patches against RenderMan's analytic definitions (RI Specification 3.2 sec.
//! 5.4, written out again here independently of the construction): every sampled point on
//! the analytic surface, every patch corner where the spec's (u, v) puts it, the patches
//! together reaching the whole parameter square and nothing outside it, and the geometric
//! normal dPdu x dPdv pointing the way the spec's does.

use super::*;
use crate::scene::rational::{eval_rational_bezier, from_homogeneous};
use glam::DVec3;

/// The spec's equations: the point at (u, v) in [0, 1]^2.
fn analytic(q: &Quadric, u: f64, v: f64) -> DVec3 {
    let deg = f64::to_radians;
    let around = |thetamax: f64, x: f64, y: f64, z: f64| {
        let (s, c) = (u * deg(thetamax)).sin_cos();
        DVec3::new(x * c - y * s, x * s + y * c, z)
    };
    match *q {
        Quadric::Sphere {
            radius,
            zmin,
            zmax,
            thetamax,
        } => {
            let asin = |z: f64| (z / radius).clamp(-1.0, 1.0).asin();
            let phimin = if zmin > -radius {
                asin(zmin)
            } else {
                deg(-90.0)
            };
            let phimax = if zmax < radius { asin(zmax) } else { deg(90.0) };
            let phi = phimin + v * (phimax - phimin);
            around(thetamax, radius * phi.cos(), 0.0, radius * phi.sin())
        }
        Quadric::Cylinder {
            radius,
            zmin,
            zmax,
            thetamax,
        } => around(thetamax, radius, 0.0, zmin + v * (zmax - zmin)),
        Quadric::Cone {
            height,
            radius,
            thetamax,
        } => around(thetamax, radius * (1.0 - v), 0.0, v * height),
        Quadric::Disk {
            height,
            radius,
            thetamax,
        } => around(thetamax, radius * (1.0 - v), 0.0, height),
        Quadric::Torus {
            major,
            minor,
            phimin,
            phimax,
            thetamax,
        } => {
            let phi = deg(phimin + v * (phimax - phimin));
            around(thetamax, major + minor * phi.cos(), 0.0, minor * phi.sin())
        }
        Quadric::Paraboloid {
            rmax,
            zmin,
            zmax,
            thetamax,
        } => {
            let z = zmin + v * (zmax - zmin);
            around(thetamax, rmax * (z / zmax).sqrt(), 0.0, z)
        }
        Quadric::Hyperboloid {
            point1,
            point2,
            thetamax,
        } => {
            let p = point1.lerp(point2, v);
            around(thetamax, p.x, p.y, p.z)
        }
    }
}

/// The point and its u and v derivatives (one-sided differences stepping into the square,
/// since some definitions are undefined just outside it).
fn derivs(q: &Quadric, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let h = 1e-7;
    let p = analytic(q, u, v);
    let (su, sv) = (if u < 0.5 { h } else { -h }, if v < 0.5 { h } else { -h });
    (
        p,
        (analytic(q, u + su, v) - p) / su,
        (analytic(q, u, v + sv) - p) / sv,
    )
}

/// The (u, v) in [0, 1]^2 whose analytic point is `p`, by damped Gauss-Newton from `guess`,
/// and the distance left.
fn invert(q: &Quadric, p: DVec3, guess: (f64, f64), scale: f64) -> (f64, f64, f64) {
    let (mut u, mut v) = guess;
    for _ in 0..60 {
        let (f, fu, fv) = derivs(q, u, v);
        let r = f - p;
        if r.length() <= 1e-15 * scale {
            break;
        }
        let (a, b, c) = (fu.dot(fu), fu.dot(fv), fv.dot(fv));
        let lam = 1e-12 * (a + c) + 1e-300;
        let (g1, g2) = (fu.dot(r), fv.dot(r));
        let det = (a + lam) * (c + lam) - b * b;
        // Kept in the square: some definitions are undefined outside it, and a point that
        // needs (u, v) outside it then fails the distance check, as it should.
        u = (u - ((c + lam) * g1 - b * g2) / det).clamp(0.0, 1.0);
        v = (v - ((a + lam) * g2 - b * g1) / det).clamp(0.0, 1.0);
    }
    (u, v, (analytic(q, u, v) - p).length())
}

/// How far `p` is from the implicit surface, relative to `scale` (None: the test relies on
/// the parametric inversion alone).
fn implicit_residual(q: &Quadric, p: DVec3, scale: f64) -> Option<f64> {
    let rho = p.truncate().length();
    let r = match *q {
        Quadric::Sphere { radius, .. } => p.length() - radius.abs(),
        Quadric::Cylinder { radius, .. } => rho - radius.abs(),
        Quadric::Cone { height, radius, .. } => rho - radius.abs() * (1.0 - p.z / height),
        Quadric::Disk { height, .. } => p.z - height,
        Quadric::Torus { major, minor, .. } => {
            ((rho - major).powi(2) + p.z * p.z).sqrt() - minor.abs()
        }
        Quadric::Paraboloid { rmax, zmax, .. } => p.z - zmax * rho * rho / (rmax * rmax),
        Quadric::Hyperboloid { .. } => return None,
    };
    Some(r.abs() / scale)
}

/// Samples every patch of `q` on a (N+1)^2 grid and checks it against the definition.
fn check(q: Quadric, patches_expected: usize) {
    let patches = q.to_bezier().unwrap();
    assert_eq!(patches.len(), patches_expected, "{q:?}");
    // The size of the surface, for relative tolerances.
    let scale = (0..=20)
        .flat_map(|i| (0..=20).map(move |j| (i as f64 / 20.0, j as f64 / 20.0)))
        .map(|(u, v)| analytic(&q, u, v).length())
        .fold(0.0f64, f64::max);
    // Samples per patch side, and cells per side of the parameter square: a patch spans at
    // most the whole range in each direction and its samples are about 1/24 of that apart
    // (a rational arc's speed varies by under 20%), so each of the 16 cells gets some.
    const N: usize = 24;
    const G: usize = 16;
    let mut reached = vec![false; G * G];
    for (k, p) in patches.iter().enumerate() {
        assert!(
            p.hw.iter().all(|h| h.w > 0.0 && h.is_finite()),
            "{q:?} patch {k}"
        );
        let (cp, w) = from_homogeneous(&p.hw);
        // Corners: where the spec's (u, v) puts them.
        for (s, t) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            let want = analytic(&q, p.u.0 + s * (p.u.1 - p.u.0), p.v.0 + t * (p.v.1 - p.v.0));
            let got = eval_rational_bezier(&cp, &w, s, t).0;
            assert!(
                want.distance(got) < 1e-12 * scale,
                "{q:?} patch {k} corner ({s},{t})"
            );
        }
        for i in 0..=N {
            for j in 0..=N {
                let (s, t) = (i as f64 / N as f64, j as f64 / N as f64);
                let (pos, ds, dt) = eval_rational_bezier(&cp, &w, s, t);
                let at = format!("{q:?} patch {k} at ({s}, {t}): {pos}");
                if let Some(r) = implicit_residual(&q, pos, scale) {
                    assert!(r < 1e-9, "{at}: off the surface by {r:e} (relative)");
                }
                let guess = (p.u.0 + s * (p.u.1 - p.u.0), p.v.0 + t * (p.v.1 - p.v.0));
                let (u, v, dist) = invert(&q, pos, guess, scale);
                assert!(dist < 1e-9 * scale, "{at}: no (u, v) within {dist:e}");
                // Inside the patch's parameter range, hence inside [0, 1]^2.
                let tol = 1e-9;
                let within =
                    |x: f64, (a, b): (f64, f64)| x >= a.min(b) - tol && x <= a.max(b) + tol;
                assert!(
                    within(u, p.u) && within(v, p.v),
                    "{at}: (u, v) = ({u}, {v})"
                );
                let cell = |x: f64| ((x * G as f64) as usize).min(G - 1);
                reached[cell(v.clamp(0.0, 1.0)) * G + cell(u.clamp(0.0, 1.0))] = true;
                // The geometric normal points the spec's way.
                let np = ds.cross(dt);
                let (_, fu, fv) = derivs(&q, u, v);
                let na = fu.cross(fv);
                let tiny = 1e-6 * scale * scale;
                if np.length() > tiny && na.length() > tiny {
                    let cos = np.dot(na) / (np.length() * na.length());
                    assert!(cos > 1.0 - 1e-5, "{at}: normal {np} vs the spec's {na}");
                }
            }
        }
    }
    let missing: Vec<usize> = (0..G * G).filter(|&c| !reached[c]).collect();
    assert!(
        missing.is_empty(),
        "{q:?}: parameter cells never reached: {missing:?}"
    );
}

#[test]
fn spheres() {
    let s = |radius, zmin, zmax, thetamax| Quadric::Sphere {
        radius,
        zmin,
        zmax,
        thetamax,
    };
    check(s(1.0, -1.0, 1.0, 360.0), 8);
    check(s(2.0, -0.5, 1.5, 200.0), 3);
    check(s(1.0, 0.3, -0.7, -120.0), 2);
    check(s(1.5, -2.0, 2.0, 90.0), 2);
    check(s(0.35, -0.35, 0.35, 37.7), 2);
    // Negative radius: the spec's phi limits taken literally (zmin <= -radius: -90).
    check(s(-1.0, -1.0, 1.0, 360.0), 8);
}

#[test]
fn cylinders_cones_disks() {
    let cyl = |radius, zmin, zmax, thetamax| Quadric::Cylinder {
        radius,
        zmin,
        zmax,
        thetamax,
    };
    check(cyl(1.0, -1.0, 1.0, 360.0), 4);
    check(cyl(0.1, 1.45, -1.45, 270.0), 3);
    check(cyl(2.0, 0.0, 3.0, -45.0), 1);
    let cone = |height, radius, thetamax| Quadric::Cone {
        height,
        radius,
        thetamax,
    };
    check(cone(1.0, 1.0, 360.0), 4);
    check(cone(2.0, 0.5, -300.0), 4);
    check(cone(-1.0, 1.0, 100.0), 2);
    let disk = |height, radius, thetamax| Quadric::Disk {
        height,
        radius,
        thetamax,
    };
    check(disk(0.0, 1.0, 360.0), 4);
    check(disk(0.5, 2.0, -90.0), 1);
    check(disk(1.0, 1.0, 37.7), 1);
}

#[test]
fn tori() {
    let t = |major, minor, phimin, phimax, thetamax| Quadric::Torus {
        major,
        minor,
        phimin,
        phimax,
        thetamax,
    };
    check(t(1.0, 0.3, 0.0, 360.0, 360.0), 16);
    check(t(0.925925, 0.844443, -27.5333, 95.2222, 360.0), 8);
    check(t(0.7, 0.35, 360.0, 0.0, 360.0), 16);
    check(t(2.0, 0.5, -90.0, 45.0, -200.0), 6);
}

#[test]
fn paraboloids() {
    let p = |rmax, zmin, zmax, thetamax| Quadric::Paraboloid {
        rmax,
        zmin,
        zmax,
        thetamax,
    };
    check(p(1.0, 0.0, 1.0, 360.0), 4);
    check(p(0.5, 0.2, 0.7, 270.0), 3);
    check(p(1.0, -2.0, -0.5, 360.0), 4);
    check(p(2.0, 1.0, 0.25, -90.0), 1);
    let e = p(1.0, 0.0, 0.0, 360.0).to_bezier().unwrap_err().to_string();
    assert!(e.contains("zmax is 0"), "{e}");
    let e = p(1.0, -1.0, 1.0, 360.0)
        .to_bezier()
        .unwrap_err()
        .to_string();
    assert!(e.contains("opposite sides of 0"), "{e}");
}

#[test]
fn hyperboloids() {
    let h = |a: [f64; 3], b: [f64; 3], thetamax| Quadric::Hyperboloid {
        point1: DVec3::from(a),
        point2: DVec3::from(b),
        thetamax,
    };
    check(h([1.0, -1.0, -1.0], [1.0, 1.0, 1.0], 360.0), 4);
    check(h([0.0, 0.0, 0.0], [1.3, 0.0, 0.0], 360.0), 4);
    check(h([0.5, 0.0, -1.0], [0.0, 0.5, 1.0], -270.0), 3);
    check(h([1.0, 0.0, 0.0], [1.0, 0.0, 1.0], 180.0), 2);
}

#[test]
fn normals_point_outward_for_positive_parameters() {
    // The spec: "outward from the z-axis" (the disk: +z) under the default orientation;
    // a negative thetamax turns the quadric inside out.
    let cases = [
        (
            Quadric::Sphere {
                radius: 1.0,
                zmin: -1.0,
                zmax: 1.0,
                thetamax: 360.0,
            },
            1.0,
        ),
        (
            Quadric::Sphere {
                radius: 1.0,
                zmin: -1.0,
                zmax: 1.0,
                thetamax: -360.0,
            },
            -1.0,
        ),
        (
            Quadric::Cylinder {
                radius: 1.0,
                zmin: 0.0,
                zmax: 1.0,
                thetamax: 360.0,
            },
            1.0,
        ),
        (
            Quadric::Cone {
                height: 1.0,
                radius: 1.0,
                thetamax: 360.0,
            },
            1.0,
        ),
        (
            Quadric::Torus {
                major: 1.0,
                minor: 0.2,
                phimin: 0.0,
                phimax: 360.0,
                thetamax: 360.0,
            },
            1.0,
        ),
        (
            Quadric::Paraboloid {
                rmax: 1.0,
                zmin: 0.1,
                zmax: 1.0,
                thetamax: 360.0,
            },
            1.0,
        ),
        (
            Quadric::Hyperboloid {
                point1: DVec3::new(1.0, -1.0, -1.0),
                point2: DVec3::new(1.0, 1.0, 1.0),
                thetamax: 360.0,
            },
            1.0,
        ),
    ];
    for (q, sign) in cases {
        for p in q.to_bezier().unwrap() {
            let (cp, w) = from_homogeneous(&p.hw);
            let (pos, du, dv) = eval_rational_bezier(&cp, &w, 0.4, 0.6);
            let n = du.cross(dv);
            // Away from the axis, and for the torus away from its core circle.
            let away = match q {
                Quadric::Torus { major, .. } => pos - pos.with_z(0.0).normalize() * major,
                _ => pos.with_z(0.0),
            };
            assert!(n.dot(away) * sign > 0.0, "{q:?}: normal {n} at {pos}");
        }
    }
    let disk = Quadric::Disk {
        height: 0.5,
        radius: 1.0,
        thetamax: 300.0,
    };
    for p in disk.to_bezier().unwrap() {
        let (cp, w) = from_homogeneous(&p.hw);
        let (_, du, dv) = eval_rational_bezier(&cp, &w, 0.4, 0.6);
        assert!(du.cross(dv).z > 0.0);
    }
}

#[test]
fn degenerate_quadrics_give_no_patches() {
    let none = |q: Quadric| assert!(q.to_bezier().unwrap().is_empty(), "{q:?}");
    none(Quadric::Sphere {
        radius: 1.0,
        zmin: -1.0,
        zmax: 1.0,
        thetamax: 0.0,
    });
    none(Quadric::Sphere {
        radius: 0.0,
        zmin: -1.0,
        zmax: 1.0,
        thetamax: 360.0,
    });
    none(Quadric::Sphere {
        radius: 1.0,
        zmin: 0.5,
        zmax: 0.5,
        thetamax: 360.0,
    });
    none(Quadric::Cylinder {
        radius: 1.0,
        zmin: 1.0,
        zmax: 1.0,
        thetamax: 360.0,
    });
    none(Quadric::Cylinder {
        radius: 0.0,
        zmin: 0.0,
        zmax: 1.0,
        thetamax: 360.0,
    });
    none(Quadric::Disk {
        height: 1.0,
        radius: 0.0,
        thetamax: 360.0,
    });
    none(Quadric::Torus {
        major: 1.0,
        minor: 0.0,
        phimin: 0.0,
        phimax: 360.0,
        thetamax: 360.0,
    });
    none(Quadric::Hyperboloid {
        point1: DVec3::new(0.0, 0.0, -1.0),
        point2: DVec3::new(0.0, 0.0, 1.0),
        thetamax: 360.0,
    });
    // More than a full turn is a full turn.
    let q = Quadric::Cylinder {
        radius: 1.0,
        zmin: 0.0,
        zmax: 1.0,
        thetamax: 720.0,
    };
    assert_eq!(q.to_bezier().unwrap().len(), 4);
}
