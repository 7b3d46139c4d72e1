//! The viewer's camera (`reyes view`): orbit, pan and dolly about the scene's centre, as the
//! camera-space transform of the scene's control points that [`crate::realtime`] applies on the
//! GPU. As in [`crate::orbit`] the camera and the lights stay, and the scene moves: a point p
//! (camera space: +x right, +y up, +z into the screen) goes to
//!
//! `R (p - c) + s (c + t)`
//!
//! with c the scene's centre ([`crate::orbit::scene_centre`]), `R = Rx(pitch) Ry(yaw)` the
//! orbit (yaw about the camera's up axis first, then pitch about its right axis, both through
//! c), `t = (pan_x, pan_y, 0)` the pan in camera-space units and `s` the dolly: the centre's
//! distance from the eye as a multiple of the scene's own (`s < 1` is closer). The dolly
//! scales the moved centre's position, so it stays on the same ray through the eye: zooming
//! keeps what is under the scene's centre where it is on screen. At the default view
//! ([`ViewCamera::default`]) the transform is exactly the identity: the frame is `reyes
//! render`'s.

use glam::{DMat4, DVec2, DVec3};

/// Radians of orbit per pixel of mouse drag (a drag across 360 px turns half a turn).
pub const ORBIT_RADIANS_PER_PIXEL: f64 = std::f64::consts::PI / 360.0;

/// The dolly factor per wheel step: one step forward brings the scene 10% closer.
pub const DOLLY_PER_STEP: f64 = 0.9;

/// The dolly's range: 1/20 to 20 times the scene's own distance (nearer, the scene crosses the
/// near plane; farther, it is a few pixels).
pub const DOLLY_RANGE: (f64, f64) = (0.05, 20.0);

/// Pitch stays within ±89 degrees, so the orbit never turns the scene upside down.
pub const MAX_PITCH: f64 = 89.0 * std::f64::consts::PI / 180.0;

/// The orbit, pan and dolly of the viewer; see the module documentation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewCamera {
    /// Turn about the camera's up axis (y) through the centre, radians; positive turns +z
    /// towards +x ([`crate::orbit`]'s turntable angle).
    pub yaw: f64,
    /// Turn about the camera's right axis (x) through the centre, radians; positive turns +y
    /// towards +z (tips the top of the scene away). Within ±[`MAX_PITCH`].
    pub pitch: f64,
    /// Pan of the centre in camera space (x right, y up), in camera-space units at the scene's
    /// own distance.
    pub pan: DVec2,
    /// Distance of the centre from the eye as a multiple of its own (1: unmoved).
    pub dolly: f64,
}

impl Default for ViewCamera {
    fn default() -> Self {
        ViewCamera {
            yaw: 0.0,
            pitch: 0.0,
            pan: DVec2::ZERO,
            dolly: 1.0,
        }
    }
}

impl ViewCamera {
    /// The camera at turntable angle `yaw` (radians), otherwise unmoved: its transform is
    /// [`crate::orbit::orbit_transform`]'s, bit for bit.
    pub fn turntable(yaw: f64) -> ViewCamera {
        ViewCamera {
            yaw,
            ..ViewCamera::default()
        }
    }

    /// The f64 transform of camera-space points for a scene centred at `centre`.
    pub fn transform(&self, centre: DVec3) -> DMat4 {
        let r = DMat4::from_rotation_x(self.pitch) * DMat4::from_rotation_y(self.yaw);
        let moved = self.dolly * (centre + self.pan.extend(0.0));
        DMat4::from_translation(moved) * r * DMat4::from_translation(-centre)
    }

    /// A mouse drag of `(dx, dy)` window pixels (x right, y down) with the orbit button: the
    /// scene turns as if grabbed at its front, right drag turning its front to the right, down
    /// drag tipping its front down.
    pub fn orbit_by_pixels(&mut self, dx: f64, dy: f64) {
        // The front (the side facing the eye, -z from the centre) moves right when +z turns
        // towards -x: a negative yaw.
        self.yaw -= dx * ORBIT_RADIANS_PER_PIXEL;
        // Rx(a) takes the front (-z) to +y for a > 0: a down drag (dy > 0) is a negative pitch.
        self.pitch = (self.pitch - dy * ORBIT_RADIANS_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// A drag of `(dx, dy)` window pixels with the pan button: the centre follows the mouse
    /// exactly on screen. `centre_depth`: the scene centre's camera-space z (> 0) before the
    /// dolly; `focal`: the projection's focal length in pixels
    /// ([`crate::frame::FrameUniforms::focal`]: raster x = w/2 + focal x / z).
    pub fn pan_by_pixels(&mut self, dx: f64, dy: f64, centre_depth: f64, focal: f64) {
        // At depth d = dolly * centre_depth a pixel is d / focal camera units; the pan is
        // scaled by the dolly in the transform, so the dolly cancels.
        let units = centre_depth.abs().max(1e-9) / focal.max(1e-9);
        self.pan += DVec2::new(dx, -dy) * units;
    }

    /// `steps` wheel steps (positive: towards the scene), each [`DOLLY_PER_STEP`], within
    /// [`DOLLY_RANGE`].
    pub fn zoom_by_steps(&mut self, steps: f64) {
        self.dolly = (self.dolly * DOLLY_PER_STEP.powf(steps)).clamp(DOLLY_RANGE.0, DOLLY_RANGE.1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::orbit::{orbit_transform, scene_centre};

    /// Raster position of a camera-space point (common.wgsl's `project`).
    fn project(p: DVec3, w: f64, h: f64, focal: f64) -> DVec2 {
        DVec2::new(0.5 * w + focal * p.x / p.z, 0.5 * h - focal * p.y / p.z)
    }

    #[test]
    fn the_default_view_is_the_identity_and_yaw_alone_is_the_turntable() {
        let c = scene_centre(&crate::scene::builtin_teapot());
        assert_eq!(ViewCamera::default().transform(c), DMat4::IDENTITY);
        for a in [0.3, -2.0, 4.0] {
            assert_eq!(
                ViewCamera::turntable(a).transform(c),
                orbit_transform(c, a),
                "angle {a}"
            );
        }
    }

    #[test]
    fn orbit_keeps_the_centre_and_turns_the_front_with_the_drag() {
        let c = DVec3::new(0.5, -0.25, 6.0);
        let mut v = ViewCamera::default();
        v.orbit_by_pixels(90.0, 0.0);
        let m = v.transform(c);
        assert!((m.transform_point3(c) - c).length() < 1e-12);
        // The front point moves right (+x) under a right drag.
        let front = m.transform_point3(c - DVec3::Z);
        assert!(front.x > c.x + 0.5, "{front}");
        let mut v = ViewCamera::default();
        v.orbit_by_pixels(0.0, 90.0);
        // Down drag: the front moves down (-y).
        let front = v.transform(c).transform_point3(c - DVec3::Z);
        assert!(front.y < c.y - 0.5, "{front}");
        // Pitch is clamped.
        v.orbit_by_pixels(0.0, 1e6);
        assert_eq!(v.pitch, -MAX_PITCH);
    }

    #[test]
    fn a_pan_moves_the_centre_with_the_mouse_at_any_dolly() {
        let c = DVec3::new(0.2, 0.1, 5.0);
        let (w, h, focal) = (320.0, 240.0, 290.0);
        for dolly in [1.0, 0.5, 3.0] {
            let mut v = ViewCamera {
                dolly,
                yaw: 0.7,
                ..ViewCamera::default()
            };
            let before = project(v.transform(c).transform_point3(c), w, h, focal);
            v.pan_by_pixels(12.0, -7.0, c.z, focal);
            let after = project(v.transform(c).transform_point3(c), w, h, focal);
            let moved = after - before;
            assert!(
                (moved - DVec2::new(12.0, -7.0)).length() < 1e-9,
                "dolly {dolly}: {moved}"
            );
        }
    }

    #[test]
    fn zoom_keeps_the_centre_on_screen_and_scales_its_distance() {
        let c = DVec3::new(0.3, -0.4, 4.0);
        let (w, h, focal) = (320.0, 240.0, 290.0);
        let mut v = ViewCamera::default();
        v.pan_by_pixels(20.0, 10.0, c.z, focal);
        let at = |v: &ViewCamera| v.transform(c).transform_point3(c);
        let before = at(&v);
        v.zoom_by_steps(3.0);
        let after = at(&v);
        assert!((project(after, w, h, focal) - project(before, w, h, focal)).length() < 1e-9);
        assert!((after.z - before.z * 0.9f64.powi(3)).abs() < 1e-12);
        v.zoom_by_steps(1e3);
        assert_eq!(v.dolly, DOLLY_RANGE.0);
        v.zoom_by_steps(-1e4);
        assert_eq!(v.dolly, DOLLY_RANGE.1);
    }
}
