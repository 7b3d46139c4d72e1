//! The turntable of `reyes bench`: the scene turns about the camera-space up axis (y) through the
//! centre of its bounding box, while the camera and the lights stay (so the lighting moves over
//! the surface as on a real turntable). Equivalently the camera orbits the scene's centre with
//! the lights fixed to it.
//!
//! An angle `a` (radians; positive turns +z towards +x) maps a camera-space point p to
//! `R(a) (p - c) + c`, c the centre of the control points' bounding box (which bounds the
//! surfaces: a Bezier patch lies in its control hull). [`orbit_matrix`] gives it as an f32
//! affine matrix for the GPU ([`crate::realtime`] applies it to homogeneous control points);
//! [`orbit_scene`] applies it to a scene on the host in f64 (the reference a GPU frame is
//! tested against).

use crate::scene::Scene;
use glam::{DMat4, DVec3};

/// The scene's centre, which the orbits turn about (defined with the scene, which spins
/// about it too).
pub use crate::scene::scene_centre;

/// The turn by `angle` radians about the y axis through `centre`, in f64.
pub fn orbit_transform(centre: DVec3, angle: f64) -> DMat4 {
    DMat4::from_translation(centre)
        * DMat4::from_rotation_y(angle)
        * DMat4::from_translation(-centre)
}

/// [`orbit_transform`] as the f32 column-major matrix the GPU multiplies homogeneous control
/// points `(x w, y w, z w, w)` by. Its translation column is `c - R c` computed in f64, so at
/// angle 0 the matrix is exactly the identity and a frame equals the unturned scene's bit for
/// bit.
pub fn orbit_matrix(centre: DVec3, angle: f64) -> [[f32; 4]; 4] {
    orbit_transform(centre, angle)
        .to_cols_array_2d()
        .map(|col| col.map(|v| v as f32))
}

/// `scene` turned by `angle` radians about its centre ([`scene_centre`]), control points
/// transformed in f64 (a moving patch's motion D becomes M D M^-1): the host reference of a
/// GPU turntable frame. Lights do not move.
pub fn orbit_scene(scene: &Scene, angle: f64) -> Scene {
    let m = orbit_transform(scene_centre(scene), angle);
    let inv = m.inverse();
    let mut out = scene.clone();
    for p in &mut out.patches {
        for c in p.net.points_mut() {
            *c = m.transform_point3(*c);
        }
        if let Some(d) = &mut p.motion {
            **d = m * **d * inv;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_turn_keeps_the_centre_and_is_the_identity_at_zero() {
        let scene = crate::scene::builtin_teapot();
        let c = scene_centre(&scene);
        let m = orbit_matrix(c, 0.0);
        for (i, col) in m.iter().enumerate() {
            for (j, v) in col.iter().enumerate() {
                assert_eq!(*v, (i == j) as u32 as f32, "column {i} row {j}");
            }
        }
        let t = orbit_transform(c, 1.0);
        assert!((t.transform_point3(c) - c).length() < 1e-12);
        // A quarter turn takes +z (from the centre) to +x, and keeps y.
        let q = orbit_transform(c, std::f64::consts::FRAC_PI_2);
        let p = q.transform_point3(c + DVec3::new(0.0, 2.0, 1.0)) - c;
        assert!((p - DVec3::new(1.0, 2.0, 0.0)).length() < 1e-12, "{p}");
        assert_eq!(orbit_scene(&scene, 0.0).patches, scene.patches);
    }
}
