//! Sampling rays leaving the lights: the first segment of every light path
//! (Instant Radiosity, and the light-path samplers built on it).

use crate::light::Light;
use crate::ray::{LocalFrame, Ray};
use crate::sampling::{concentric_disk, cosine_hemisphere, uniform_sphere};
use crate::scene::Scene;
use glam::Vec3;
use std::f32::consts::PI;

/// A ray leaving a light, with its power weight.
#[derive(Clone, Copy, Debug)]
pub struct EmittedRay {
    /// The ray, already offset from the emitting surface.
    pub ray: Ray,
    /// Power weight β = Le·cos θ / (p_select · p_A · p_ω): the power the
    /// ray carries (W), whose mean over rays is the lights' total power.
    pub beta: Vec3,
    /// Index of the light in [`Scene::lights`].
    pub light: usize,
}

impl Scene {
    /// Chooses a light in proportion to power (`u_select`) and samples a ray
    /// leaving it: a point (`u_pos`) and a direction (`u_dir`). Area lights
    /// emit cosine-distributed from a uniform point, point lights uniformly
    /// over the sphere, spots uniformly inside their cone, the sun from a
    /// disk of the scene's bounding radius that faces it, the environment
    /// along a direction drawn as [`crate::environment::Sky::sample`] draws
    /// it, from such a disk facing that direction. `None` when the
    /// sample carries nothing.
    pub fn sample_emission(&self, u_select: f32, u_pos: (f32, f32), u_dir: (f32, f32)) -> Option<EmittedRay> {
        let (i, p_select) = self.light_distribution.sample(u_select);
        if p_select <= 0.0 {
            return None;
        }
        let e = self.emit_from(i, u_pos, u_dir)?;
        Some(EmittedRay { beta: e.beta / p_select, ..e })
    }

    /// A ray leaving light `i` (no selection): a point (`u_pos`) and a
    /// direction (`u_dir`) as in [`Scene::sample_emission`]; the power
    /// weight's mean over uniform `u_pos`, `u_dir` is the power of light `i`
    /// alone. Reflective shadow maps index it by (`u_pos`, `u_dir`).
    /// `None` when the sample carries nothing or `i` is out of range.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
    pub fn emit_from(&self, i: usize, u_pos: (f32, f32), u_dir: (f32, f32)) -> Option<EmittedRay> {
        let (ray, beta) = match self.lights.get(i)? {
            Light::Area { triangle, radiance } => {
                let t = &self.geometry.triangles[*triangle as usize];
                let y = t.sample_point(u_pos);
                let d = LocalFrame::from_normal(t.ng).to_world(cosine_hemisphere(u_dir.0, u_dir.1));
                // Le·cos / (1/A · cos/π) = π·A·Le.
                (Ray::new(y + t.ng * self.epsilon(), d), *radiance * (PI * t.area))
            }
            Light::Point { position, intensity } => {
                // I / (1/4π).
                (Ray::new(*position, uniform_sphere(u_dir.0, u_dir.1)), *intensity * (4.0 * PI))
            }
            Light::Spot { position, direction, intensity, cos_falloff_start, cos_total } => {
                let cos = 1.0 - u_dir.0 * (1.0 - cos_total);
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let phi = 2.0 * PI * u_dir.1;
                let d = LocalFrame::from_normal(*direction).to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos));
                let pdf = 1.0 / (2.0 * PI * (1.0 - cos_total));
                let f = Light::spot_falloff(cos, *cos_falloff_start, *cos_total);
                (Ray::new(*position, d), *intensity * (f / pdf))
            }
            Light::Directional { direction, irradiance } => {
                let r = self.radius();
                // E over a disk of area π r².
                (self.parallel_ray(*direction, u_pos), *irradiance * (PI * r * r))
            }
            Light::Environment { sky } => {
                // ω toward the sky; the light travels along −ω.
                let (w, pdf) = sky.sample(u_dir);
                if !(pdf > 0.0) {
                    return None;
                }
                let r = self.radius();
                // L(ω)·cos over (p(ω) · 1/(π r²)): the radiance through a disk facing ω.
                (self.parallel_ray(-w, u_pos), sky.radiance(w) * (PI * r * r / pdf))
            }
        };
        if !(beta.max_element() > 0.0) {
            return None;
        }
        Some(EmittedRay { ray, beta, light: i })
    }

    /// A ray along `d` from the point `u_pos` of the disk of the scene's
    /// bounding radius that faces `d` from outside the scene: the rays of
    /// the sun and of a sky direction.
    fn parallel_ray(&self, d: Vec3, u_pos: (f32, f32)) -> Ray {
        let (lo, hi) = self.geometry.bounds;
        let r = self.radius();
        let f = LocalFrame::from_normal(d);
        let q = concentric_disk(u_pos.0, u_pos.1) * r;
        Ray::new(0.5 * (lo + hi) - d * (1.01 * r) + f.s * q.x + f.t * q.y, d)
    }
}

#[cfg(test)]
mod tests {
    use crate::light::{Light, channel_mean};
    use crate::material::Material;
    use crate::mesh::Mesh;
    use crate::scene::Scene;
    use glam::Vec3;

    /// The mean power weight of emitted rays is the total power of the lights.
    #[test]
    fn mean_power_weight_is_total_power() {
        let mut mesh = Mesh::default();
        mesh.push_quad(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(-1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, -1.0), 0);
        let lights = vec![
            Light::Point { position: Vec3::Y, intensity: Vec3::new(1.0, 2.0, 3.0) },
            Light::Spot { position: Vec3::Y, direction: -Vec3::Y, intensity: Vec3::splat(5.0), cos_falloff_start: 0.9, cos_total: 0.8 },
            Light::Directional { direction: -Vec3::Y, irradiance: Vec3::splat(2.0) },
            Light::Environment {
                sky: crate::environment::Sky { zenith: Vec3::new(0.2, 0.4, 1.0), horizon: Vec3::splat(0.8), nadir: Vec3::splat(0.1) },
            },
        ];
        let s = Scene::new("q", &mesh, vec![Material::emissive("m", Vec3::splat(0.5), Vec3::splat(0.7))], lights, true).unwrap();
        let total: f64 = (0..s.lights.len())
            .map(|i| {
                let area = match &s.lights[i] {
                    Light::Area { triangle, .. } => s.geometry.triangles[*triangle as usize].area,
                    _ => 0.0,
                };
                s.lights[i].power(area, s.radius()) as f64
            })
            .sum();
        let n = 256u32;
        let mut sum = 0.0f64;
        for a in 0..n {
            for b in 0..16u32 {
                let u = |k: u32, m: u32| (k as f32 + 0.5) / m as f32;
                if let Some(e) = s.sample_emission(u(a, n), (u(b, 16), u((b * 7) % 16, 16)), (u(b, 16), u((a * 5) % 16, 16))) {
                    sum += channel_mean(e.beta) as f64;
                    assert!((e.ray.d.length() - 1.0).abs() < 1e-4);
                }
            }
        }
        let mean = sum / (n * 16) as f64;
        assert!((mean / total - 1.0).abs() < 0.01, "mean {mean} total {total}");
    }
}
