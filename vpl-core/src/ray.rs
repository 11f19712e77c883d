//! Rays and local orthonormal frames.

use glam::Vec3;

/// A ray `o + t·d`, `t ∈ (0, t_max)`; `d` is unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: Vec3,
    /// Unit direction.
    pub d: Vec3,
    /// Largest parameter that counts as a hit.
    pub t_max: f32,
}

impl Ray {
    /// A ray of unbounded length.
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Self { o, d, t_max: f32::INFINITY }
    }

    /// A ray that ends at `t_max`.
    #[inline]
    pub fn segment(o: Vec3, d: Vec3, t_max: f32) -> Self {
        Self { o, d, t_max }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// An orthonormal frame (s, t, n): local +Z is `n`.
///
/// Built with the branchless construction of Duff et al. (JCGT 2017),
/// "Building an Orthonormal Basis, Revisited".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalFrame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// Normal (local +Z).
    pub n: Vec3,
}

impl LocalFrame {
    /// The frame whose +Z axis is the unit vector `n`.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// A local vector expressed in world space.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    /// A world vector expressed in this frame.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal() {
        for n in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::Z, Vec3::new(1.0, -2.0, 0.5).normalize()] {
            let f = LocalFrame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5);
            let v = Vec3::new(0.3, -0.4, 0.8);
            assert!((f.to_local(f.to_world(v)) - v).length() < 1e-5);
        }
    }
}
