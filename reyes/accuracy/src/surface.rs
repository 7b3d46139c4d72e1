//! The ground-truth surface: a scene's bicubic Bezier patches, polynomial or rational, evaluated
//! in f64 straight from their control points and weights (points, exact derivatives, outside
//! normals; `reference::homogeneous::eval_patch`), shaded with the same surface and
//! light models as `stages/shade.rs` but in f64. Nothing here reads a `PatchItem` or
//! `FrameData`, so it shares no arithmetic with the GPU path or its f32 twins: the metrics in
//! this module's siblings compare the renderer against it.

use glam::DVec3;
use reyes::reference::homogeneous::eval_patch;
use reyes::scene::{Light, Material, Patch, Scene, SurfaceKind};

/// An exact surface point of a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position, camera space.
    pub p: DVec3,
    /// Partial derivative dP/du, camera space.
    pub dpdu: DVec3,
    /// Partial derivative dP/dv, camera space.
    pub dpdv: DVec3,
    /// Unit outside normal (after the patch's `flip_normal`).
    pub n: DVec3,
}

/// How far inside the patch the normal is taken where dPdu x dPdv vanishes (a collapsed
/// edge, e.g. the teapot lid's apex): the normal there is the limit of nearby normals, and
/// in f64 a step this small approximates that limit to about this size in angle.
const DEGENERATE_STEP: f64 = 1.0e-7;

/// Evaluates patch `patch` at parameters (u, v) of its own [0, 1]^2.
pub fn eval(patch: &Patch, u: f64, v: f64) -> SurfacePoint {
    let (p, dpdu, dpdv) = eval_patch(patch, u, v);
    let mut n = dpdu.cross(dpdv);
    // A rational patch's tangent along a collapsed edge is not exactly zero but rounding noise
    // of about 1e-16 |P| (quotient rule), at any angle: call it degenerate below 1e-12 of the
    // control points' distance from the eye. (Polynomial: tiny = 0, an exact zero test.)
    let tiny = if patch.is_rational() {
        1.0e-12 * patch.cp().iter().map(|c| c.length()).fold(0.0, f64::max)
    } else {
        0.0
    };
    let degenerate = !(n.length_squared()
        > 1.0e-24 * dpdu.length_squared() * dpdv.length_squared())
        || dpdu.length() <= tiny
        || dpdv.length() <= tiny;
    if degenerate {
        let (iu, iv) = (
            u + (0.5 - u) * DEGENERATE_STEP,
            v + (0.5 - v) * DEGENERATE_STEP,
        );
        let (_, a, b) = eval_patch(patch, iu, iv);
        n = a.cross(b);
    }
    if patch.flip_normal {
        n = -n;
    }
    SurfacePoint {
        p,
        dpdu,
        dpdv,
        n: n.normalize_or_zero(),
    }
}

/// Whether the point is seen from its back (the outside normal faces away from the eye),
/// the test `Sides 1` culls by.
pub fn back_facing(s: &SurfacePoint) -> bool {
    s.n.dot(s.p) > 0.0
}

/// The lights the renderer uses for `scene`: its own, or, when it declares none, one distant
/// light of intensity 1 shining from the eye along +z (the rule in `frame.rs`).
pub fn scene_lights(scene: &Scene) -> Vec<Light> {
    if scene.lights.is_empty() {
        vec![Light::Distant {
            color: DVec3::ONE,
            dir: DVec3::Z,
        }]
    } else {
        scene.lights.clone()
    }
}

/// RenderMan's constant / matte / plastic at camera-space point `p` with outside normal `n`
/// (faced toward the eye), in linear RGB, unclamped: the model of `stages/shade.rs` in f64.
pub fn shade(p: DVec3, n: DVec3, m: &Material, lights: &[Light]) -> DVec3 {
    let i = p.normalize();
    let nn = n.normalize();
    let nf = if nn.dot(i) > 0.0 { -nn } else { nn };
    let v = -i;
    let (mut amb, mut diff, mut spec) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for l in lights {
        let (cl, dir) = match *l {
            Light::Ambient { color } => {
                amb += color;
                continue;
            }
            Light::Distant { color, dir } => (color, -dir),
            Light::Point { color, pos } => {
                let d = pos - p;
                (color / d.dot(d).max(1.0e-20), d)
            }
        };
        let ld = dir.normalize();
        diff += cl * nf.dot(ld).max(0.0);
        let h = (ld + v).normalize();
        spec += cl * nf.dot(h).max(0.0).powf(1.0 / m.roughness.max(1.0e-4));
    }
    match m.kind {
        SurfaceKind::Constant => m.color,
        SurfaceKind::Matte => m.color * (m.ka * amb + m.kd * diff),
        SurfaceKind::Plastic => {
            m.color * (m.ka * amb + m.kd * diff) + m.specular_color * m.ks * spec
        }
        SurfaceKind::Metal => m.color * (m.ka * amb + m.ks * spec),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use reyes::scene::{PatchSource, builtin_teapot};

    fn patch(cp: [DVec3; 16]) -> Patch {
        let source = PatchSource {
            file: "test".into(),
            line: 0,
            index: 0,
        };
        Patch::new(cp, Patch::POLYNOMIAL, source)
    }

    /// z = u^2 + v^2 over x = u, y = v: u^2 is the cubic Bernstein polynomial with
    /// coefficients 0, 0, 1/3, 1, and u with 0, 1/3, 2/3, 1.
    fn paraboloid() -> Patch {
        let sq = [0.0, 0.0, 1.0 / 3.0, 1.0];
        patch(std::array::from_fn(|k| {
            let (i, j) = (k % 4, k / 4);
            DVec3::new(i as f64 / 3.0, j as f64 / 3.0, sq[i] + sq[j])
        }))
    }

    #[test]
    fn known_points_derivatives_and_normals() {
        let p = paraboloid();
        for (u, v) in [(0.0, 0.0), (0.3, 0.8), (1.0, 0.5), (0.77, 0.01)] {
            let s = eval(&p, u, v);
            assert!(s.p.distance(DVec3::new(u, v, u * u + v * v)) < 1e-14);
            assert!(s.dpdu.distance(DVec3::new(1.0, 0.0, 2.0 * u)) < 1e-13);
            assert!(s.dpdv.distance(DVec3::new(0.0, 1.0, 2.0 * v)) < 1e-13);
            let n = DVec3::new(-2.0 * u, -2.0 * v, 1.0).normalize();
            assert!(s.n.distance(n) < 1e-13, "{} vs {n}", s.n);
        }
        let mut flipped = paraboloid();
        flipped.flip_normal = true;
        assert!(eval(&flipped, 0.3, 0.4).n.distance(-eval(&p, 0.3, 0.4).n) < 1e-15);
        // Corners interpolate the corner control points.
        let t = &builtin_teapot().patches[5];
        for (u, v, k) in [(0.0, 0.0, 0), (1.0, 0.0, 3), (0.0, 1.0, 12), (1.0, 1.0, 15)] {
            assert_eq!(eval(t, u, v).p, t.cp()[k]);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1.0e-6;
        for p in builtin_teapot().patches.iter().step_by(3) {
            for (u, v) in [(0.2, 0.3), (0.5, 0.5), (0.9, 0.15)] {
                let s = eval(p, u, v);
                let du = (eval(p, u + h, v).p - eval(p, u - h, v).p) / (2.0 * h);
                let dv = (eval(p, u, v + h).p - eval(p, u, v - h).p) / (2.0 * h);
                let scale = s.dpdu.length().max(s.dpdv.length()).max(1.0);
                assert!(s.dpdu.distance(du) < 1e-6 * scale, "{} {du}", s.dpdu);
                assert!(s.dpdv.distance(dv) < 1e-6 * scale, "{} {dv}", s.dpdv);
                // The normal is perpendicular to both tangents.
                assert!(s.n.dot(du).abs() < 1e-6 * du.length().max(1e-12));
                assert!(s.n.dot(dv).abs() < 1e-6 * dv.length().max(1e-12));
            }
        }
    }

    /// Where a whole edge collapses to a point the normal is the limit from inside.
    #[test]
    fn collapsed_edge_has_the_limit_normal() {
        // A cone: the row v = 0 collapses to the apex; the surface near it is z = r.
        let p = patch(std::array::from_fn(|k| {
            let (i, j) = (k % 4, k / 4);
            let r = j as f64 / 3.0;
            let x = i as f64 / 3.0 - 0.5;
            DVec3::new(x * r, r, r)
        }));
        let s = eval(&p, 0.5, 0.0);
        assert!(s.n.is_finite() && (s.n.length() - 1.0).abs() < 1e-12);
        let near = eval(&p, 0.5, 1e-4).n;
        assert!(s.n.distance(near) < 1e-3, "{} vs {near}", s.n);
    }

    #[test]
    fn shading_matches_the_f32_twin() {
        let s = builtin_teapot();
        let data = reyes::frame::FrameData::new(&s, &Default::default()).unwrap();
        let lights = scene_lights(&s);
        assert_eq!(lights.len(), data.lights.len());
        let m32 = &data.materials[0];
        let m = &s.materials[0];
        let mut worst: f64 = 0.0;
        for p in &s.patches {
            for (u, v) in [(0.25, 0.25), (0.5, 0.75), (0.8, 0.4)] {
                let e = eval(p, u, v);
                let c = shade(e.p, e.n, m, &lights);
                let c32 = reyes::stages::shade::shade(
                    e.p.as_vec3(),
                    e.n.as_vec3(),
                    m32,
                    m32.color.into(),
                    &data.lights,
                );
                worst = worst.max((c - c32.as_dvec3()).abs().max_element());
            }
        }
        assert!(worst < 1e-4, "f64 and f32 shading differ by {worst}");
        // A scene without lights gets the frame's default light.
        let dark = Scene {
            lights: Vec::new(),
            ..s.clone()
        };
        let d = reyes::frame::FrameData::new(&dark, &Default::default()).unwrap();
        let Light::Distant { color, dir } = scene_lights(&dark)[0] else {
            panic!("not distant")
        };
        assert_eq!(
            (d.lights[0].kind, d.lights[0].vec),
            (1, dir.as_vec3().into())
        );
        assert_eq!(d.lights[0].color, <[f32; 3]>::from(color.as_vec3()));
    }
}
