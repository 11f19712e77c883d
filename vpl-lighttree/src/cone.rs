//! Bounding cones of directions: the normals of a node's lights, so that a
//! bound on how much light a node sends toward a point can use the angle
//! between the point and the cone (Yuksel 2019, §4; pbrt-v4's
//! `DirectionCone`).

use glam::Vec3;

/// A cone of directions around a unit `axis`: every direction whose angle
/// to the axis is at most acos(`cos_theta`). `cos_theta` > 1 is the empty
/// cone; −1 the whole sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit axis (any unit vector for the empty cone and the sphere).
    pub axis: Vec3,
    /// Cosine of the half-angle.
    pub cos_theta: f32,
}

/// Relative widening of a union's half-angle, so that rounding never leaves
/// a direction of either cone outside it.
const WIDEN: f32 = 1e-5;

impl Cone {
    /// The cone that holds no direction.
    pub const EMPTY: Cone = Cone { axis: Vec3::Z, cos_theta: 2.0 };

    /// The cone that holds every direction.
    pub const SPHERE: Cone = Cone { axis: Vec3::Z, cos_theta: -1.0 };

    /// The cone of the single direction `d` (a unit vector); a direction that
    /// is not finite or not unit-length within 10⁻³ gives the sphere, which
    /// bounds it whatever it is.
    pub fn of(d: Vec3) -> Cone {
        if d.is_finite() && (d.length_squared() - 1.0).abs() < 2e-3 { Cone { axis: d.normalize(), cos_theta: 1.0 } } else { Cone::SPHERE }
    }

    /// Whether it holds no direction.
    pub fn is_empty(&self) -> bool {
        self.cos_theta > 1.0
    }

    /// Whether it holds the unit direction `d` (within the widening).
    pub fn contains(&self, d: Vec3) -> bool {
        !self.is_empty() && self.axis.dot(d) >= self.cos_theta - 1e-5
    }

    /// The smallest cone, as pbrt-v4 bounds it, that holds both (the
    /// half-angle widened by a relative 10⁻⁵ so that rounding never drops a
    /// direction).
    pub fn union(self, other: Cone) -> Cone {
        if self.is_empty() {
            return other;
        }
        if other.is_empty() {
            return self;
        }
        if self.cos_theta <= -1.0 || other.cos_theta <= -1.0 {
            return Cone::SPHERE;
        }
        let theta_a = self.cos_theta.clamp(-1.0, 1.0).acos();
        let theta_b = other.cos_theta.clamp(-1.0, 1.0).acos();
        let theta_d = angle_between(self.axis, other.axis);
        let pi = std::f32::consts::PI;
        if (theta_d + theta_b).min(pi) <= theta_a {
            return self;
        }
        if (theta_d + theta_a).min(pi) <= theta_b {
            return other;
        }
        let theta_o = (theta_a + theta_d + theta_b) * 0.5 * (1.0 + WIDEN) + WIDEN;
        if theta_o >= pi {
            return Cone::SPHERE;
        }
        // Turn the first axis toward the second by θ_o − θ_a, in their plane.
        let w_r = self.axis.cross(other.axis);
        if w_r.length_squared() < 1e-20 {
            return Cone::SPHERE;
        }
        let w_r = w_r.normalize();
        let theta_r = theta_o - theta_a;
        let axis = (self.axis * theta_r.cos() + w_r.cross(self.axis) * theta_r.sin()).normalize();
        Cone { axis, cos_theta: theta_o.cos() }
    }
}

/// The angle between two unit vectors, accurate near 0 and π.
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        std::f32::consts::PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() * 0.5).min(1.0).asin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A union holds both cones' directions, and is no wider than both
    /// half-angles and the angle between the axes.
    #[test]
    fn a_union_holds_both_and_no_more_than_it_must() {
        let a = Cone { axis: Vec3::Z, cos_theta: 30f32.to_radians().cos() };
        let b = Cone { axis: Vec3::X, cos_theta: 10f32.to_radians().cos() };
        let u = a.union(b);
        let half = u.cos_theta.acos().to_degrees();
        assert!((half - 65.0).abs() < 0.01, "(30 + 90 + 10) / 2 = 65°, got {half}");
        for d in [Vec3::Z, Vec3::X, Vec3::new(1.0, 0.0, 0.2).normalize(), Vec3::new(-0.5, 0.0, 1.0).normalize()] {
            assert!(u.contains(d), "{d:?}");
        }
        assert!(!u.contains(Vec3::NEG_Z));
        assert_eq!(Cone::EMPTY.union(a), a);
        assert_eq!(a.union(Cone::of(Vec3::Z)), a, "a cone that holds the other is the union");
        assert_eq!(Cone::of(Vec3::Z).union(Cone::of(Vec3::NEG_Z)).cos_theta, -1.0, "opposite directions: the sphere");
    }
}
