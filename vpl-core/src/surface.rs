//! Points on surfaces.

use glam::Vec3;

/// A point on the scene's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position.
    pub p: Vec3,
    /// Unit geometric normal, from the triangle's winding (counter-clockwise seen from its tip).
    pub ng: Vec3,
    /// Unit shading normal (interpolated vertex normals, or `ng`), on the same side as `ng`.
    pub n: Vec3,
    /// Triangle index in the scene.
    pub triangle: u32,
    /// Material index in the scene.
    pub material: u32,
}

impl SurfacePoint {
    /// `p` moved off the surface toward direction `w` by `eps`, to start a ray
    /// that must not hit this surface again.
    #[inline]
    pub fn offset_toward(&self, w: Vec3, eps: f32) -> Vec3 {
        if w.dot(self.ng) >= 0.0 { self.p + self.ng * eps } else { self.p - self.ng * eps }
    }

    /// A copy whose normals face the half-space that contains `w` (two-sided shading).
    #[inline]
    pub fn facing(&self, w: Vec3) -> SurfacePoint {
        if w.dot(self.ng) >= 0.0 { *self } else { SurfacePoint { ng: -self.ng, n: -self.n, ..*self } }
    }
}

/// A ray–scene intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// The point hit.
    pub point: SurfacePoint,
}
