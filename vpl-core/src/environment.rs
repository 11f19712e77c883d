//! Light from infinitely far away in every direction: a constant
//! environment, or an RGB sky gradient from the zenith (+Y) through the
//! horizon to the nadir (−Y).
//!
//! Radiance arriving from direction ω (pointing away from the receiver,
//! toward the sky) depends on its height y = ω_y only, linearly from the
//! horizon (y = 0) to the zenith (y = 1) and to the nadir (y = −1). As y is
//! uniform over the sphere (Archimedes), directions are drawn with density
//! proportional to the channel mean of the radiance: y from that piecewise
//! linear density, the azimuth uniform, p(ω) = f(y) / (2π ∫f). A constant
//! sky is drawn uniformly, p = 1/4π.
//!
//! ```
//! use vpl_core::environment::Sky;
//! use vpl_core::glam::Vec3;
//!
//! let sky = Sky::constant(Vec3::splat(2.0));
//! let (w, pdf) = sky.sample((0.3, 0.7));
//! assert!((pdf - 0.25 / std::f32::consts::PI).abs() < 1e-6);
//! assert_eq!(sky.radiance(w), Vec3::splat(2.0));
//! ```

use crate::light::channel_mean;
use glam::Vec3;
use std::f32::consts::PI;

/// Sky radiance at the zenith, horizon and nadir, linear in height between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sky {
    /// Radiance arriving from straight above (+Y).
    pub zenith: Vec3,
    /// Radiance arriving along the horizon.
    pub horizon: Vec3,
    /// Radiance arriving from straight below (−Y).
    pub nadir: Vec3,
}

impl Sky {
    /// The same radiance from every direction.
    pub fn constant(radiance: Vec3) -> Sky {
        Sky { zenith: radiance, horizon: radiance, nadir: radiance }
    }

    /// Radiance arriving from direction `w` (unit, pointing to the sky).
    #[inline]
    pub fn radiance(&self, w: Vec3) -> Vec3 {
        let y = w.y.clamp(-1.0, 1.0);
        // Exact for a constant sky (the difference is zero), and within an
        // ulp of the zenith and nadir colours at the poles.
        if y >= 0.0 { self.horizon + (self.zenith - self.horizon) * y } else { self.horizon + (self.nadir - self.horizon) * (-y) }
    }

    /// ∫ of the channel mean of the radiance over the upper and the lower
    /// half of y ∈ [−1, 1] (the solid-angle integral is 2π times their sum).
    fn halves(&self) -> (f32, f32) {
        let h = channel_mean(self.horizon);
        (0.5 * (h + channel_mean(self.zenith)), 0.5 * (h + channel_mean(self.nadir)))
    }

    /// ∫ L dω over the sphere (channel mean).
    pub fn integral(&self) -> f32 {
        let (up, down) = self.halves();
        2.0 * PI * (up + down)
    }

    /// Power entering a sphere of radius `r` around the scene (channel
    /// mean): π r² ∫ L dω, 4π² r² L for a constant sky (pbrt-v4 §12.5).
    pub fn power(&self, r: f32) -> f32 {
        PI * r * r * self.integral()
    }

    /// Draws a direction toward the sky with density ∝ the channel mean of
    /// its radiance; returns it and its solid-angle density (`pdf` 0 for a
    /// black sky).
    pub fn sample(&self, u: (f32, f32)) -> (Vec3, f32) {
        let (up, down) = self.halves();
        let total = up + down;
        if total.is_nan() || total <= 0.0 {
            return (Vec3::Y, 0.0);
        }
        let p_up = up / total;
        let h = channel_mean(self.horizon);
        // t ∈ [0, 1] from the density ∝ a + (b − a)t, by inverting its CDF
        // in the form that stays exact as b → a.
        let linear = |u: f32, a: f32, b: f32| -> f32 {
            let den = a + (a * a + (b * b - a * a) * u).max(0.0).sqrt();
            if den > 0.0 { (u * (a + b) / den).clamp(0.0, 1.0) } else { u }
        };
        let y = if u.0 < p_up {
            linear(u.0 / p_up, h, channel_mean(self.zenith))
        } else {
            -linear(((u.0 - p_up) / (1.0 - p_up)).min(1.0), h, channel_mean(self.nadir))
        };
        let s = (1.0 - y * y).max(0.0).sqrt();
        let phi = 2.0 * PI * u.1;
        let w = Vec3::new(s * phi.cos(), y, s * phi.sin());
        (w, self.pdf(w))
    }

    /// Solid-angle density of [`Sky::sample`] for direction `w`.
    #[inline]
    pub fn pdf(&self, w: Vec3) -> f32 {
        let total = self.integral();
        if total > 0.0 { channel_mean(self.radiance(w)) / total } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::uniform_sphere;

    fn gradient() -> Sky {
        Sky { zenith: Vec3::new(0.2, 0.4, 1.0), horizon: Vec3::new(1.0, 0.9, 0.8), nadir: Vec3::new(0.1, 0.1, 0.05) }
    }

    /// The density integrates to one and the samples follow it: the mean of
    /// L/p over samples is ∫L dω, checked against a uniform-sphere estimate.
    #[test]
    fn samples_follow_the_density() {
        let sky = gradient();
        let n = 200_000;
        let strat = |i: u32| ((i as f32 + 0.5) / n as f32, (i as f32 * 0.618_034).fract());
        let mut is = 0.0f64;
        let mut uni = 0.0f64;
        let mut pdf_sum = 0.0f64;
        for i in 0..n {
            let (w, pdf) = sky.sample(strat(i));
            assert!((w.length() - 1.0).abs() < 1e-4 && pdf > 0.0);
            assert!((sky.pdf(w) - pdf).abs() <= 1e-5 * pdf);
            is += (channel_mean(sky.radiance(w)) / pdf) as f64;
            let (a, b) = strat(i);
            let v = uniform_sphere(a, b);
            uni += (channel_mean(sky.radiance(v)) * 4.0 * PI) as f64;
            pdf_sum += (sky.pdf(v) * 4.0 * PI) as f64;
        }
        let exact = sky.integral() as f64;
        assert!((is / n as f64 / exact - 1.0).abs() < 1e-4, "{} vs {exact}", is / n as f64);
        assert!((uni / n as f64 / exact - 1.0).abs() < 1e-3, "{} vs {exact}", uni / n as f64);
        assert!((pdf_sum / n as f64 - 1.0).abs() < 1e-3);
    }

    #[test]
    fn constant_sky_is_uniform_and_black_sky_has_no_density() {
        let sky = Sky::constant(Vec3::ONE);
        assert!((sky.integral() - 4.0 * PI).abs() < 1e-5);
        assert!((sky.power(2.0) - 16.0 * PI * PI).abs() < 1e-3);
        assert_eq!(Sky::constant(Vec3::ZERO).sample((0.5, 0.5)).1, 0.0);
        assert_eq!(sky.radiance(Vec3::new(0.6, 0.48, 0.64)), Vec3::ONE);
        let g = gradient();
        assert!((g.radiance(Vec3::Y) - g.zenith).abs().max_element() < 1e-6);
        assert!((g.radiance(Vec3::NEG_Y) - g.nadir).abs().max_element() < 1e-6);
        assert_eq!(g.radiance(Vec3::X), g.horizon);
    }
}
