//! A scene set spinning over the shutter without editing its file (`reyes render --spin`):
//! what a `MotionBegin` rotation around the whole world block would do.

use super::Scene;
use crate::Error;
use glam::{DMat4, DVec3};

/// Spins every patch of `scene` by `degrees` over the shutter about the world's z axis
/// through the centre of the scene's bound ([`super::scene_centre`]): the patches stay where
/// they are at shutter open and are turned by `degrees` at shutter close (composed with any
/// motion they already have). Points move linearly between the two (as the renderer moves
/// every point: docs/reyes.md). Errors: [`Error::NonFiniteSpin`], and
/// [`Error::DegenerateSpinAxis`] when the world's z axis is degenerate in camera space.
pub fn spin(scene: &mut Scene, degrees: f64) -> Result<(), Error> {
    if !degrees.is_finite() {
        return Err(Error::NonFiniteSpin { degrees });
    }
    if degrees == 0.0 {
        return Ok(());
    }
    let axis = scene
        .camera
        .world_to_camera
        .transform_vector3(DVec3::Z)
        .try_normalize()
        .ok_or(Error::DegenerateSpinAxis)?;
    let c = super::scene_centre(scene);
    let turn = DMat4::from_translation(c)
        * DMat4::from_axis_angle(axis, degrees.to_radians())
        * DMat4::from_translation(-c);
    for p in &mut scene.patches {
        let m = match &p.motion {
            Some(m) => turn * **m,
            None => turn,
        };
        p.motion = Some(Box::new(m));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The turn keeps the centre and moves other points about the world z axis: for the
    /// built-in teapot, the teapot's own up axis (its object space is its world), not the
    /// camera's view axis.
    #[test]
    fn spin_turns_about_world_z_through_the_centre() {
        let mut s = crate::scene::builtin_teapot();
        let c = super::super::scene_centre(&s);
        spin(&mut s, 90.0).unwrap();
        let m = s.patches[0].motion.as_deref().unwrap();
        assert!((m.transform_point3(c) - c).length() < 1e-9);
        // The teapot's axis in camera space is the turn's axis: its direction stays put.
        let (_, up) = crate::scene::teapot::axis_in_camera();
        assert!((m.transform_vector3(up) - up).length() < 1e-9, "{up}");
        assert!(up.dot(DVec3::Z).abs() < 0.99, "the view axis: {up}");
        // A direction across the axis turns by 90 degrees.
        let across = up.any_orthonormal_vector();
        let turned = m.transform_vector3(across);
        assert!(turned.dot(across).abs() < 1e-9 && turned.dot(up).abs() < 1e-9);
        assert!(spin(&mut s, f64::NAN).is_err());
    }
}
