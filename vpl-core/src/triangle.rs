//! One triangle as the BVH and the shading read it.

use crate::sampling::uniform_triangle;
use glam::Vec3;

/// Per-triangle data kept for shading and light sampling.
#[derive(Clone, Copy, Debug)]
pub struct TriangleData {
    /// First vertex.
    pub p0: Vec3,
    /// Edge p1 − p0.
    pub e1: Vec3,
    /// Edge p2 − p0.
    pub e2: Vec3,
    /// Unit geometric normal, `normalize(e1 × e2)`.
    pub ng: Vec3,
    /// Area.
    pub area: f32,
    /// Material index.
    pub material: u32,
    /// Index into the scene's shading-normal table (`u32::MAX` = flat).
    pub normals: u32,
}

impl TriangleData {
    /// The three corners p0, p0 + e1, p0 + e2 (the mesh's own p1 and p2 up
    /// to the rounding of the edges).
    #[inline]
    pub fn corners(&self) -> [Vec3; 3] {
        [self.p0, self.p0 + self.e1, self.p0 + self.e2]
    }

    /// The point a uniform sample `u` ∈ [0, 1)² maps to ([`uniform_triangle`]):
    /// how light sampling, light emission and the progressive renderer's
    /// primary VPLs place a point on an emitting triangle.
    #[inline]
    pub fn sample_point(&self, u: (f32, f32)) -> Vec3 {
        let (b1, b2) = uniform_triangle(u.0, u.1);
        self.p0 + self.e1 * b1 + self.e2 * b2
    }
}
