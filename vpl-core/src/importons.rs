//! Camera samples ("importons", Georgiev & Slusallek 2010, §3.3): a few
//! surface points seen through the image, against which view-adaptive VPL
//! samplers (Russian-roulette acceptance, Metropolis IR, TCAS) estimate the
//! light a VPL brings to the camera.
//!
//! The points are the camera hits of rays through a Cranley–Patterson-rotated
//! Halton sequence over the image; `first` picks where in the sequence a set
//! starts, so a sampler can keep its points from frame to frame (the same
//! `first`) or change them (a new `first` each frame).

use crate::camera::Camera;
use crate::halton::Halton;
use crate::scene::Scene;
use crate::vpl::Vpl;
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;

/// A camera-visible point that reflects light toward the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Importon {
    /// Position.
    pub p: Vec3,
    /// Shading normal, toward the camera.
    pub n: Vec3,
    /// Geometric normal, toward the camera.
    pub ng: Vec3,
    /// Diffuse albedo ρ.
    pub albedo: Vec3,
}

/// The importons of one set of camera rays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Importons {
    /// The rays' hits that reflect toward the camera (misses and black or
    /// back-facing surfaces are left out).
    pub points: Vec<Importon>,
    /// Rays cast: the denominator of every mean, since a ray that found no
    /// reflecting point still stands for its share of the image.
    pub cast: usize,
    /// Least squared distance in the geometry term of [`Importons::mean_contribution`]
    /// (0: exact). Samplers that use the mean as a Metropolis target bound
    /// it so that a VPL right beside one camera sample does not hold a chain.
    pub min_distance_sq: f32,
}

impl Importons {
    /// Casts `count` camera rays through points `first .. first + count` of a
    /// Halton sequence over the image, rotated by `seed`.
    pub fn cast(scene: &Scene, camera: &Camera, count: usize, first: u64, seed: u64) -> Importons {
        let halton = Halton::new(4, seed);
        let (w, h) = (camera.resolution.0 as f32, camera.resolution.1 as f32);
        let found: Vec<Option<Importon>> = (0..count as u64)
            .into_par_iter()
            .map(|j| {
                let i = first.wrapping_add(j);
                let ray = camera.ray(halton.sample(i, 0) * w, halton.sample(i, 1) * h, (halton.sample(i, 2), halton.sample(i, 3)));
                let (sp, albedo) = scene.reflecting_hit(&ray)?;
                Some(Importon { p: sp.p, n: sp.n, ng: sp.ng, albedo })
            })
            .collect();
        Importons { points: found.into_iter().flatten().collect(), cast: count, min_distance_sq: 0.0 }
    }

    /// Luminance of the radiance `vpl` reflects toward the camera at
    /// importon `x`: ρ(x)/π · Φ · G(x, y), times V(x, y) when `visibility`.
    #[inline]
    pub fn contribution(scene: &Scene, x: &Importon, vpl: &Vpl, visibility: bool) -> f32 {
        Self::bounded_contribution(scene, x, vpl, visibility, 0.0)
    }

    /// [`Importons::contribution`] with the squared distance in G at least `min_d2`.
    #[inline]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
    pub fn bounded_contribution(scene: &Scene, x: &Importon, vpl: &Vpl, visibility: bool, min_d2: f32) -> f32 {
        let mut g = vpl.geometry(x.p, x.n);
        if min_d2 > 0.0 {
            let d2 = (vpl.y - x.p).length_squared();
            g *= d2 / d2.max(min_d2);
        }
        if g <= 0.0 || (vpl.y - x.p).dot(x.ng) <= 0.0 {
            return 0.0;
        }
        let c = crate::image::luminance(x.albedo * vpl.flux) * (FRAC_1_PI * g);
        if !(c > 0.0) {
            return 0.0;
        }
        if visibility {
            let eps = scene.epsilon();
            if !scene.visible(x.p + x.ng * eps, vpl.y + vpl.n * eps) {
                return 0.0;
            }
        }
        c
    }

    /// Φ̃: the mean over the cast rays of the luminance `vpl` brings, an
    /// estimate of its average pixel contribution (G bounded by
    /// [`Importons::min_distance_sq`]). With `cap`, the sum stops
    /// as soon as the mean is known to reach `cap` (the rest of the rays
    /// could only add to it), and the value returned is then at least `cap`.
    pub fn mean_contribution(&self, scene: &Scene, vpl: &Vpl, visibility: bool, cap: Option<f32>) -> f32 {
        if self.cast == 0 {
            return 0.0;
        }
        let limit = cap.map_or(f64::INFINITY, |c| c as f64 * self.cast as f64);
        let mut sum = 0.0f64;
        for x in &self.points {
            sum += Self::bounded_contribution(scene, x, vpl, visibility, self.min_distance_sq) as f64;
            if sum >= limit {
                break;
            }
        }
        (sum / self.cast as f64) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setup::SceneSetup;

    #[test]
    fn importons_lie_in_view_and_contributions_follow_the_vpl_convention() {
        let s = SceneSetup::builtin("cornell").unwrap();
        let cam = s.camera.with_resolution((32, 32)).unwrap();
        let imp = Importons::cast(&s.scene, &cam, 64, 0, 1);
        assert_eq!(imp.cast, 64);
        // The box fills most of the view; rays that meet the black light (or
        // miss past the box's front edge) find nothing that reflects.
        assert!(imp.points.len() > 48 && imp.points.len() < 64, "{}", imp.points.len());
        assert!(imp.points.iter().all(|x| x.albedo.max_element() > 0.0));
        assert!(imp.points.iter().all(|x| cam.project(x.p).is_some()));
        let x = imp.points[0];
        let vpl = Vpl { y: x.p + x.n * 0.5, n: -x.n, flux: Vec3::ONE, id: 0, bounce: 1 };
        // Facing each other at 0.5 m: G = 1/0.25, contribution ρ/π·4 in luminance.
        let c = Importons::contribution(&s.scene, &x, &vpl, true);
        assert!((c - crate::image::luminance(x.albedo) * 4.0 * FRAC_1_PI).abs() < 1e-4, "{c}");
        let back = Vpl { n: x.n, ..vpl };
        assert_eq!(Importons::contribution(&s.scene, &x, &back, false), 0.0);
        // The cap stops early but never below the cap.
        let full = imp.mean_contribution(&s.scene, &vpl, true, None);
        let capped = imp.mean_contribution(&s.scene, &vpl, true, Some(full * 0.01));
        assert!(capped >= full * 0.01 && capped <= full);
    }
}
