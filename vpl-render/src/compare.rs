//! Comparing two images that each come with per-pixel standard errors
//! (Mitsuba 3's statistical image tests): per-pixel z-tests and a test of the
//! image means.

use vpl_core::glam::Vec3;
use vpl_core::{CoreError, Image};

/// Result of comparing an estimate with a reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// Pixels compared.
    pub pixels: usize,
    /// Fraction of pixels that pass the per-pixel test at level `alpha`.
    pub pass_rate: f64,
    /// Significance level of the per-pixel test.
    pub alpha: f64,
    /// Mean RGB of the estimate.
    pub mean_a: [f64; 3],
    /// Mean RGB of the reference.
    pub mean_b: [f64; 3],
    /// (mean_a − mean_b) / combined standard error of the two image means, per channel.
    pub mean_z: [f64; 3],
    /// Combined standard error of the difference of the means, per channel.
    pub mean_se: [f64; 3],
    /// Relative mean squared error of a against b (mean of (a−b)²/(b²+0.01)).
    pub rel_mse: f64,
    /// |z| per pixel (largest channel), for the z image.
    pub z_image: Image,
}

/// Relative numeric precision granted to reference values (float32
/// accumulation over 32768 samples: deviations of up to 6.5e-6 are seen in
/// Mitsuba's zero-variance pixels).
pub const REFERENCE_PRECISION: f64 = 1e-5;

/// Two-sided critical value of the standard normal for `alpha`
/// (Acklam's rational approximation of the inverse normal CDF, |error| < 1.2e-9).
pub fn z_critical(alpha: f64) -> f64 {
    inverse_normal_cdf(1.0 - 0.5 * alpha)
}

#[allow(clippy::excessive_precision)] // Acklam's coefficients as published
fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] =
        [-3.969683028665376e1, 2.209460984245205e2, -2.759285104469687e2, 1.383577518672690e2, -3.066479806614716e1, 2.506628277459239];
    const B: [f64; 5] = [-5.447609879822406e1, 1.615858368580409e2, -1.556989798598866e2, 6.680131188771972e1, -1.328068155288572e1];
    const C: [f64; 6] =
        [-7.784894002430293e-3, -3.223964580411365e-1, -2.400758277161838, -2.549732539343734, 4.374664141464968, 2.938163982698783];
    const D: [f64; 4] = [7.784695709041462e-3, 3.224671290700398e-1, 2.445134137142996, 3.754408661907416];
    let pl = 0.02425;
    if p < pl {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5]) / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - pl {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        -inverse_normal_cdf(1.0 - p)
    }
}

/// Compares estimate `a` (with standard errors `a_se`) against reference `b`
/// (with `b_se`).
///
/// Each pixel is one test at level `alpha`: its three channels are tested
/// with two-sided z-tests at α/3 each (Bonferroni), so a correct renderer
/// fails a pixel with probability at most α whatever the correlation between
/// channels. A channel passes when |a − b| ≤ z_{α/6} · sqrt(se_a² + se_b²);
/// The combined error also holds the reference's numeric precision,
/// [`REFERENCE_PRECISION`] × |b|: Mitsuba's float32 film stores the light's
/// radiance 18.387 as 18.38688 in pixels whose standard error is zero.
///
/// The means are compared with the standard error of each image mean taken
/// as sqrt(Σ se²) / N (pixels are independent estimates).
///
/// Errors when the four images do not all have the same size.
pub fn compare(a: &Image, a_se: &Image, b: &Image, b_se: &Image, alpha: f64) -> Result<Comparison, CoreError> {
    let size = |i: &Image| (i.width, i.height);
    if size(a) != size(b) || size(a) != size(a_se) || size(b) != size(b_se) || a.data.is_empty() {
        return Err(CoreError::Image(format!(
            "cannot compare images of sizes {:?}, {:?} (standard errors {:?}, {:?})",
            size(a),
            size(b),
            size(a_se),
            size(b_se)
        )));
    }
    let zc = z_critical(alpha / 3.0);
    let n = a.data.len();
    let mut pass = 0usize;
    let mut var_sum = [0.0f64; 3];
    let mut rel = 0.0f64;
    let mut z_image = Image::new(a.width, a.height);
    for i in 0..n {
        let (x, y, sx, sy) = (a.data[i], b.data[i], a_se.data[i], b_se.data[i]);
        let mut ok = true;
        let mut zmax = 0.0f32;
        for c in 0..3 {
            let d = (x[c] - y[c]) as f64;
            let se2 = (sx[c] as f64).powi(2) + (sy[c] as f64).powi(2);
            var_sum[c] += se2;
            let se2 = se2 + (REFERENCE_PRECISION * y[c] as f64).powi(2);
            let z = if se2 > 0.0 {
                d.abs() / se2.sqrt()
            } else if d == 0.0 {
                0.0
            } else {
                f64::INFINITY
            };
            ok &= z <= zc;
            zmax = zmax.max(z as f32);
            rel += d * d / ((y[c] as f64).powi(2) + 1e-2);
        }
        if ok {
            pass += 1;
        }
        z_image.data[i] = Vec3::splat(zmax);
    }
    let (mean_a, mean_b) = (a.mean(), b.mean());
    let mut mean_z = [0.0; 3];
    let mut mean_se = [0.0; 3];
    for c in 0..3 {
        mean_se[c] = var_sum[c].sqrt() / n as f64;
        mean_z[c] = (mean_a[c] - mean_b[c]) / mean_se[c].max(f64::MIN_POSITIVE);
    }
    Ok(Comparison {
        pixels: n,
        pass_rate: pass as f64 / n as f64,
        alpha,
        mean_a,
        mean_b,
        mean_z,
        mean_se,
        rel_mse: rel / (3 * n) as f64,
        z_image,
    })
}

/// A signed difference image a − b, for writing next to a failed comparison.
pub fn difference(a: &Image, b: &Image) -> Image {
    Image { width: a.width, height: a.height, data: a.data.iter().zip(&b.data).map(|(x, y)| *x - *y).collect() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn critical_values() {
        assert!((z_critical(0.01) - 2.5758293).abs() < 1e-6);
        assert!((z_critical(0.05) - 1.9599640).abs() < 1e-6);
    }

    #[test]
    fn detects_a_shift_and_accepts_identity() {
        let mut a = Image::new(10, 10);
        for (i, p) in a.data.iter_mut().enumerate() {
            *p = Vec3::splat(1.0 + i as f32 * 0.01);
        }
        let se = Image { width: 10, height: 10, data: vec![Vec3::splat(0.01); 100] };
        let same = compare(&a, &se, &a, &se, 0.01).unwrap();
        assert_eq!(same.pass_rate, 1.0);
        let mut b = a.clone();
        for p in b.data.iter_mut() {
            *p += Vec3::splat(0.1);
        }
        let c = compare(&a, &se, &b, &se, 0.01).unwrap();
        assert!(compare(&a, &se, &Image::new(3, 3), &se, 0.01).is_err());
        assert_eq!(c.pass_rate, 0.0);
        assert!(c.mean_z[0] < -4.0);
    }
}
