//! The viewer's camera: fly (look around, move along the view), orbit
//! around the point looked at, dolly toward it; turned into a
//! [`vpl_core::Camera`] of the scene's field of view each frame.

use glam::{Quat, Vec3};
use vpl_core::Camera;

/// A camera that flies or orbits. `up` is the scene camera's up hint: yaw
/// turns about it, and pitch stops short of it so the frame never degenerates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Eye position.
    pub origin: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Distance to the point looked at (the orbit's pivot).
    pub distance: f32,
    /// Unit up axis.
    pub up: Vec3,
}

/// Closest the view direction may come to the up axis (cosine).
const MAX_COS_UP: f32 = 0.995;

impl FlyCamera {
    /// The camera of a scene: its eye, its view direction and the distance to
    /// its target.
    pub fn from_camera(c: &Camera) -> FlyCamera {
        let d = c.target - c.origin;
        let up = c.up.normalize_or(Vec3::Y);
        FlyCamera { origin: c.origin, forward: d.normalize_or(-Vec3::Z), distance: d.length().max(1e-3), up }
    }

    /// The point looked at.
    pub fn target(&self) -> Vec3 {
        self.origin + self.forward * self.distance
    }

    /// Unit vector to the right of the view.
    pub fn right(&self) -> Vec3 {
        self.forward.cross(self.up).normalize_or(Vec3::X)
    }

    /// The view direction turned by `yaw` radians about the up axis and
    /// `pitch` radians about the right axis (positive: left, up), pitch
    /// clamped short of the poles.
    fn turned(&self, yaw: f32, pitch: f32) -> Vec3 {
        let f = Quat::from_axis_angle(self.up, yaw) * self.forward;
        let right = f.cross(self.up).normalize_or(Vec3::X);
        let g = (Quat::from_axis_angle(right, pitch) * f).normalize();
        if g.dot(self.up).abs() > MAX_COS_UP { f } else { g }
    }

    /// Looks around from where the camera stands.
    pub fn look(&mut self, yaw: f32, pitch: f32) {
        self.forward = self.turned(yaw, pitch);
    }

    /// Orbits around the point looked at, keeping the distance to it.
    pub fn orbit(&mut self, yaw: f32, pitch: f32) {
        let pivot = self.target();
        self.forward = self.turned(yaw, pitch);
        self.origin = pivot - self.forward * self.distance;
    }

    /// Moves by `forward`, `right` and `up` scene units along the view axes
    /// (up is the scene's up axis).
    pub fn fly(&mut self, forward: f32, right: f32, up: f32) {
        self.origin += self.forward * forward + self.right() * right + self.up * up;
    }

    /// Moves toward the point looked at by the fraction `f` of the distance
    /// to it (negative: away), never through it.
    pub fn dolly(&mut self, f: f32) {
        // Short of the pivot by more than f32 resolves at the eye's coordinates.
        let nearest = 1e-3 * self.origin.abs().max_element().max(1.0);
        let step = (self.distance * f.clamp(-4.0, 0.9)).min(self.distance - nearest);
        if step > 0.0 || f < 0.0 {
            self.origin += self.forward * step;
            self.distance -= step;
        }
    }

    /// The scene camera `base` (field of view, lens) moved to this eye and
    /// view, at `resolution`.
    pub fn camera(&self, base: &Camera, resolution: (u32, u32)) -> vpl_core::Result<Camera> {
        Camera::new(self.origin, self.target(), self.up, base.fov_deg, base.fov_axis, resolution)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::FovAxis;

    fn cam() -> FlyCamera {
        let c = Camera::new(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0, FovAxis::X, (64, 48)).unwrap();
        FlyCamera::from_camera(&c)
    }

    #[test]
    fn orbit_keeps_the_pivot_and_the_distance() {
        let mut c = cam();
        let pivot = c.target();
        c.orbit(0.7, 0.3);
        assert!((c.target() - pivot).length() < 1e-4);
        assert!(((c.origin - pivot).length() - 5.0).abs() < 1e-4);
        assert!(c.origin.x.abs() > 1.0, "the eye moved round: {:?}", c.origin);
    }

    #[test]
    fn look_keeps_the_eye_and_stops_short_of_the_pole() {
        let mut c = cam();
        let eye = c.origin;
        for _ in 0..100 {
            c.look(0.0, 0.2);
        }
        assert_eq!(c.origin, eye);
        assert!(c.forward.dot(Vec3::Y) <= MAX_COS_UP + 1e-4);
        assert!(c.camera(&Camera::new(eye, c.target(), Vec3::Y, 40.0, FovAxis::X, (8, 8)).unwrap(), (8, 8)).is_ok());
    }

    #[test]
    fn fly_moves_along_the_view_and_dolly_never_passes_the_pivot() {
        let mut c = cam();
        c.fly(1.0, 0.0, 0.0);
        assert!((c.origin - Vec3::new(0.0, 1.0, 4.0)).length() < 1e-5);
        c.fly(0.0, 1.0, 0.5);
        assert!((c.origin - Vec3::new(1.0, 1.5, 4.0)).length() < 1e-5);
        let pivot = c.target();
        for _ in 0..50 {
            c.dolly(0.9);
        }
        assert!(c.distance >= 1e-3, "{}", c.distance);
        assert!((c.target() - pivot).length() < 1e-3);
        assert!(c.camera(&Camera::new(c.origin, pivot, Vec3::Y, 40.0, FovAxis::X, (8, 8)).unwrap(), (8, 8)).is_ok());
        c.dolly(-1.0);
        assert!((c.target() - pivot).length() < 1e-3 && c.distance > 1.9e-3);
    }
}
