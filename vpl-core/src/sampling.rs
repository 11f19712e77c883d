//! Warping functions from the unit square, with their densities.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Cosine-weighted direction on the local hemisphere (+Z), by Malley's method
/// over Shirley–Chiu's concentric disk; density `cos θ / π` (solid angle).
#[inline]
pub fn cosine_hemisphere(u: f32, v: f32) -> Vec3 {
    let d = concentric_disk(u, v);
    let z = (1.0 - d.x * d.x - d.y * d.y).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Density of [`cosine_hemisphere`] for a local direction.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * std::f32::consts::FRAC_1_PI
}

/// Uniform point on the unit disk (Shirley–Chiu concentric mapping).
#[inline]
pub fn concentric_disk(u: f32, v: f32) -> Vec2 {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.abs() > b.abs() { (a, FRAC_PI_4 * (b / a)) } else { (b, FRAC_PI_2 - FRAC_PI_4 * (a / b)) };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Uniform direction on the unit sphere; density `1 / 4π`.
#[inline]
pub fn uniform_sphere(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform barycentrics (b1, b2) on a triangle (Heitz 2019's low-distortion map
/// is not needed here; this is the square-root parametrisation, pbrt-v4 §A.5.5).
#[inline]
pub fn uniform_triangle(u: f32, v: f32) -> (f32, f32) {
    let su = u.sqrt();
    (1.0 - su, v * su)
}

/// Power heuristic with β = 2 (Veach 1997, eq. 9.13) for two strategies.
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    if a + b == 0.0 { 0.0 } else { a / (a + b) }
}

/// Radical inverse of `i` in base `b` (Halton sequence component).
pub fn radical_inverse(mut i: u64, base: u64) -> f64 {
    let inv = 1.0 / base as f64;
    let mut f = inv;
    let mut r = 0.0;
    while i > 0 {
        r += (i % base) as f64 * f;
        i /= base;
        f *= inv;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{Purpose, stream};

    #[test]
    fn cosine_hemisphere_has_cosine_moments() {
        // E[cos θ] under cos θ/π is 2/3; variance of cos θ is 1/2 − 4/9 = 1/18.
        let mut s = stream(0, 0, Purpose::TEST, 1);
        let n = 200_000;
        let mut m = 0.0f64;
        for _ in 0..n {
            let d = cosine_hemisphere(s.next_f32(), s.next_f32());
            assert!((d.length() - 1.0).abs() < 1e-4 && d.z >= 0.0);
            m += d.z as f64;
        }
        m /= n as f64;
        let se = (1.0 / 18.0 / n as f64).sqrt();
        assert!((m - 2.0 / 3.0).abs() < 5.0 * se, "mean cos {m}");
    }

    #[test]
    fn halton_base2_is_van_der_corput() {
        assert_eq!(radical_inverse(1, 2), 0.5);
        assert_eq!(radical_inverse(2, 2), 0.25);
        assert_eq!(radical_inverse(3, 2), 0.75);
        assert!((radical_inverse(1, 3) - 1.0 / 3.0).abs() < 1e-12);
    }
}
