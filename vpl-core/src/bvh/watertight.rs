//! The watertight ray–triangle test of Woop, Benthin and Wald ("Watertight
//! Ray/Triangle Intersection", JCGT 2(1), 2013).
//!
//! The ray is made the +z axis of a sheared frame: its largest direction
//! component becomes z, the other two follow in a right-handed order, and a
//! shear sends the direction to (0, 0, 1). A triangle's vertices, moved into
//! that frame, are tested in 2D: the scaled barycentrics
//!
//! ```text
//! U = C_x B_y − C_y B_x,  V = A_x C_y − A_y C_x,  W = B_x A_y − B_y A_x     (eq. 4)
//! ```
//!
//! are the edge functions of the three edges at the origin. The ray meets
//! the triangle where all three have one sign; a shared edge gives both
//! triangles the same edge function with opposite signs, so a ray through it
//! meets at least one of them (none slips through) whatever the rounding,
//! as long as the two triangles hold the same vertex coordinates. Where an
//! edge function rounds to exactly zero it is recomputed in double
//! precision (§3.3), which keeps the sign decision exact. The hit distance
//! is T / det with T = U A_z + V B_z + W C_z and det = U + V + W (eq. 6),
//! compared as T against t_max · det to avoid the division on a miss.

use glam::Vec3;

/// A ray prepared for [`ShearedRay::hit`]: its origin, the axis permutation
/// (k_x, k_y, k_z) and the shear (S_x, S_y, S_z) of eq. (3).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShearedRay {
    o: Vec3,
    k: [usize; 3],
    s: [f32; 3],
}

impl ShearedRay {
    /// The frame of a ray from `o` along `d` (any length, not zero).
    #[inline(always)]
    pub(crate) fn new(o: Vec3, d: Vec3) -> ShearedRay {
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Keep the winding: a negative z flips the frame's handedness.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        ShearedRay { o, k: [kx, ky, kz], s: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]] }
    }

    /// The ray parameter at which the ray meets the triangle `v` within
    /// `[0, t_max]`, or `None`. Both sides of the triangle count.
    #[inline(always)]
    pub(crate) fn hit(&self, v: &[Vec3; 3], t_max: f32) -> Option<f32> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.s;
        let a = (v[0] - self.o).to_array();
        let b = (v[1] - self.o).to_array();
        let c = (v[2] - self.o).to_array();
        // Eq. (3): the vertices sheared into the ray's frame.
        let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
        let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
        let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
        // Eq. (4), in double precision where single precision gives exactly 0.
        let mut u = cx * by - cy * bx;
        let mut v_ = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v_ == 0.0 || w == 0.0 {
            let d = |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
            u = d(cx, by, cy, bx);
            v_ = d(ax, cy, ay, cx);
            w = d(bx, ay, by, ax);
        }
        if (u < 0.0 || v_ < 0.0 || w < 0.0) && (u > 0.0 || v_ > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v_ + w;
        if det == 0.0 {
            return None;
        }
        // Eq. (6): the scaled hit distance, tested before the division.
        let t = u * (sz * a[kz]) + v_ * (sz * b[kz]) + w * (sz * c[kz]);
        let outside = if det > 0.0 { t < 0.0 || t > t_max * det } else { t > 0.0 || t < t_max * det };
        if outside {
            return None;
        }
        let t = t / det;
        // A NaN (a degenerate ray) is no hit.
        (t >= 0.0).then_some(t)
    }
}

/// Eight triangles around a vertex with awkward coordinates, each sharing
/// an edge with the next: (centre, rim vertices, triangles), for the tests
/// of watertightness here and in `fan`.
#[cfg(test)]
pub(super) fn shared_edge_fan() -> (Vec3, Vec<Vec3>, Vec<[Vec3; 3]>) {
    let centre = Vec3::new(0.1, 0.7, 0.3);
    let ring: Vec<Vec3> = (0..8)
        .map(|i| {
            let a = i as f32 * std::f32::consts::TAU / 8.0 + 0.1;
            centre + Vec3::new(a.cos() * 1.3, a.sin() * 0.7, 0.05 * (i as f32).sin())
        })
        .collect();
    let fan = (0..8).map(|i| [centre, ring[i], ring[(i + 1) % 8]]).collect();
    (centre, ring, fan)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [Vec3; 3] = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];

    #[test]
    fn hits_inside_misses_outside_from_both_sides() {
        for (o, d) in [(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z), (Vec3::new(0.25, 0.25, -2.0), Vec3::Z)] {
            let t = ShearedRay::new(o, d).hit(&TRI, f32::INFINITY).unwrap();
            assert!((t - o.z.abs()).abs() < 1e-6, "{t}");
            assert_eq!(ShearedRay::new(o, d).hit(&TRI, 0.5), None, "beyond t_max");
            assert_eq!(ShearedRay::new(o, -d).hit(&TRI, f32::INFINITY), None, "behind the origin");
        }
        assert_eq!(ShearedRay::new(Vec3::new(0.75, 0.75, 1.0), Vec3::NEG_Z).hit(&TRI, f32::INFINITY), None);
        // Oblique, with every component of the direction used.
        let d = Vec3::new(0.3, -0.2, -1.0).normalize();
        let o = Vec3::new(0.2, 0.3, 0.0) - d * 2.0;
        let t = ShearedRay::new(o, d).hit(&TRI, f32::INFINITY).unwrap();
        assert!((t - 2.0).abs() < 1e-5, "{t}");
        // A zero or non-finite direction hits nothing.
        assert_eq!(ShearedRay::new(Vec3::new(0.2, 0.2, 1.0), Vec3::ZERO).hit(&TRI, f32::INFINITY), None);
        assert_eq!(ShearedRay::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NAN).hit(&TRI, f32::INFINITY), None);
    }

    /// Rays through the shared edge of two triangles, and through their
    /// shared vertex, meet at least one of them: a fan of eight triangles
    /// around a vertex with awkward coordinates, and 20,000 rays aimed at
    /// points on its edges from random origins.
    #[test]
    fn no_ray_slips_between_triangles_that_share_an_edge() {
        let (centre, ring, fan) = shared_edge_fan();
        let mut rng = crate::rng::stream(5, 0, crate::rng::Purpose::TEST, 0);
        for n in 0..20_000 {
            let i = n % 8;
            let f = if n % 100 == 0 { 0.0 } else { rng.next_f32() };
            let target = centre + (ring[i] - centre) * f;
            let (u, v) = rng.next_2d();
            let o = target + Vec3::new(u - 0.5, v - 0.5, 1.0 + u) * 3.0;
            let r = ShearedRay::new(o, target - o);
            assert!(fan.iter().any(|t| r.hit(t, f32::INFINITY).is_some()), "ray {n} towards {target:?} slipped through");
        }
    }
}
