//! Error metrics: relative MSE, RMSE and box downsampling of images; the
//! SMC paper's |E| and |E′| of tracked pixels over time.

use vpl_core::glam::Vec3;
use vpl_core::{CoreError, Image};

/// Offset ε in the denominator of [`rel_mse`]: keeps near-black pixels from
/// dominating (the convention of Rousselle et al. and most denoising papers).
pub const REL_MSE_EPSILON: f64 = 1e-2;

fn same_size(a: &Image, b: &Image) -> Result<(), CoreError> {
    if a.width != b.width || a.height != b.height {
        return Err(CoreError::Invalid(format!("images differ in size: {}x{} and {}x{}", a.width, a.height, b.width, b.height)));
    }
    Ok(())
}

/// Relative mean squared error of `a` against the reference `b`:
/// the mean over pixels and channels of (a − b)² / (b² + ε), ε = [`REL_MSE_EPSILON`].
pub fn rel_mse(a: &Image, b: &Image) -> Result<f64, CoreError> {
    same_size(a, b)?;
    let mut s = 0.0f64;
    for (p, q) in a.data.iter().zip(&b.data) {
        for c in 0..3 {
            let (x, y) = (p[c] as f64, q[c] as f64);
            s += (x - y).powi(2) / (y * y + REL_MSE_EPSILON);
        }
    }
    Ok(s / (3 * a.data.len().max(1)) as f64)
}

/// Mean squared error over pixels and channels.
pub fn mse(a: &Image, b: &Image) -> Result<f64, CoreError> {
    same_size(a, b)?;
    let s: f64 = a.data.iter().zip(&b.data).map(|(p, q)| (*p - *q).length_squared() as f64).sum();
    Ok(s / (3 * a.data.len().max(1)) as f64)
}

/// The part of [`mse`] against a Monte Carlo reference that is the
/// reference's own noise: the mean over pixels and channels of σ², σ the
/// reference's per-pixel standard error. For an image `a` independent of the
/// reference, E[(a − b)²] = E[(a − μ)²] + σ², so `mse(a, b) −
/// reference_variance(σ)` estimates `a`'s error against the noise-free image.
pub fn reference_variance(stderr: &Image) -> f64 {
    let s: f64 = stderr.data.iter().map(|e| e.length_squared() as f64).sum();
    s / (3 * stderr.data.len().max(1)) as f64
}

/// Root mean squared error over pixels and channels.
pub fn rmse(a: &Image, b: &Image) -> Result<f64, CoreError> {
    mse(a, b).map(f64::sqrt)
}

/// Box-filters `img` down by an integer `factor` on both axes.
pub fn downsample(img: &Image, factor: u32) -> Result<Image, CoreError> {
    if factor == 0 || img.width % factor != 0 || img.height % factor != 0 {
        return Err(CoreError::Invalid(format!("{}x{} cannot be downsampled by {factor}", img.width, img.height)));
    }
    let mut out = Image::new(img.width / factor, img.height / factor);
    let norm = 1.0 / (factor * factor) as f32;
    for y in 0..out.height {
        for x in 0..out.width {
            let mut s = Vec3::ZERO;
            for dy in 0..factor {
                for dx in 0..factor {
                    s += img.get(x * factor + dx, y * factor + dy);
                }
            }
            out.set(x, y, s * norm);
        }
    }
    Ok(out)
}

/// Reinhard's global operator on the luminance of `c`: L/(1+L) (Reinhard et
/// al. 2002, eq. 3 with L_white = ∞; the SMC paper measures after it).
pub fn tone_mapped_luminance(c: Vec3) -> f64 {
    let l = vpl_core::image::luminance(c).max(0.0) as f64;
    l / (1.0 + l)
}

/// Standard error of [`tone_mapped_luminance`] of a mean with per-channel
/// standard errors `se`: the luminance's error bounded by Σ w_c·se_c
/// (channels fully correlated, the worst case) and carried through the
/// operator's slope 1/(1+L)².
pub fn tone_mapped_stderr(mean: Vec3, se: Vec3) -> f64 {
    let l = vpl_core::image::luminance(mean).max(0.0) as f64;
    let se_l = 0.2126 * se.x as f64 + 0.7152 * se.y as f64 + 0.0722 * se.z as f64;
    se_l / ((1.0 + l) * (1.0 + l))
}

/// The SMC paper's error measures (§5.2, Table 1) of tracked pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TemporalError {
    /// Average |E|: the mean over frames and pixels of |estimate − truth|.
    pub e: f64,
    /// Average |E′|: the mean over pixels and consecutive frame pairs of
    /// |E(t+Δt) − E(t)| / Δt, with Δt = one frame (eq. 10).
    pub e_prime: f64,
    /// The mean signed error: above 0 when the estimate is brighter than the
    /// truth on average (a bias shows here; noise averages out).
    pub bias: f64,
    /// Errors averaged into `e` (frames × pixels).
    pub count: usize,
    /// Differences averaged into `e_prime` ((frames − 1) × pixels).
    pub count_prime: usize,
}

/// |E| and |E′| of `estimate` against `truth`, both indexed
/// `[frame][pixel]` over consecutive frames (tone-mapped luminances).
pub fn temporal_error(estimate: &[Vec<f64>], truth: &[Vec<f64>]) -> Result<TemporalError, CoreError> {
    if estimate.len() != truth.len() || estimate.iter().zip(truth).any(|(a, b)| a.len() != b.len()) {
        return Err(CoreError::Invalid("estimate and truth differ in frames or pixels".into()));
    }
    let err: Vec<Vec<f64>> = estimate.iter().zip(truth).map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect()).collect();
    let mut out = TemporalError::default();
    let (mut s, mut sp, mut b) = (0.0, 0.0, 0.0);
    for (f, row) in err.iter().enumerate() {
        for (p, e) in row.iter().enumerate() {
            s += e.abs();
            b += e;
            out.count += 1;
            if f > 0 {
                sp += (e - err[f - 1][p]).abs();
                out.count_prime += 1;
            }
        }
    }
    out.e = if out.count > 0 { s / out.count as f64 } else { 0.0 };
    out.bias = if out.count > 0 { b / out.count as f64 } else { 0.0 };
    out.e_prime = if out.count_prime > 0 { sp / out.count_prime as f64 } else { 0.0 };
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_on_small_images() {
        let a = Image { width: 2, height: 2, data: vec![Vec3::ONE, Vec3::ZERO, Vec3::ONE, Vec3::ZERO] };
        let d = downsample(&a, 2).unwrap();
        assert_eq!(d.data, vec![Vec3::splat(0.5)]);
        assert_eq!(rel_mse(&a, &a).unwrap(), 0.0);
        let b = Image { data: vec![Vec3::splat(2.0); 4], ..a.clone() };
        assert!((rmse(&b, &Image { data: vec![Vec3::ONE; 4], ..a.clone() }).unwrap() - 1.0).abs() < 1e-9);
        assert!(downsample(&a, 3).is_err());
        assert!(rel_mse(&a, &d).is_err());
    }

    /// The noise correction: for a = μ exactly and b = μ + noise of known
    /// σ, mse − reference_variance is 0 within 4 standard errors of the
    /// mean of 40 000 squared draws.
    #[test]
    fn reference_variance_removes_the_references_noise() {
        let n = 40_000;
        let mut rng = vpl_core::stream(1, 0, vpl_core::Purpose::TEST, 0);
        let mu = Vec3::splat(0.3);
        let sigma = 0.05f32;
        // Uniform noise of standard deviation σ: half-width σ·√3.
        let b: Vec<Vec3> = (0..n)
            .map(|_| mu + Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5) * (2.0 * sigma * 3f32.sqrt()))
            .collect();
        let a = Image { width: n as u32, height: 1, data: vec![mu; n] };
        let b = Image { width: n as u32, height: 1, data: b };
        let se = Image { width: n as u32, height: 1, data: vec![Vec3::splat(sigma); n] };
        let raw = mse(&a, &b).unwrap();
        let var = reference_variance(&se) as f64;
        // Var(e²) for uniform e of variance σ²: (9/5 − 1)·σ⁴.
        let se_mean = (0.8f64).sqrt() * var / ((3 * n) as f64).sqrt();
        assert!((raw - var).abs() < 4.0 * se_mean, "raw {raw}, variance {var}, standard error {se_mean}");
        // Without the correction the error of a perfect image would be σ².
        assert!(raw > 0.9 * var);
    }

    /// |E| and |E′| on a 3-frame, 2-pixel series worked by hand:
    /// errors e = [[0.1, −0.2], [0.3, −0.2], [0.0, 0.1]];
    /// |E| = (0.1+0.2+0.3+0.2+0.0+0.1)/6 = 0.15;
    /// differences [[0.2, 0.0], [−0.3, 0.3]], |E′| = 0.8/4 = 0.2.
    #[test]
    fn temporal_error_matches_hand_values() {
        let truth = vec![vec![0.5, 0.4], vec![0.5, 0.4], vec![0.6, 0.2]];
        let est = vec![vec![0.6, 0.2], vec![0.8, 0.2], vec![0.6, 0.3]];
        let t = temporal_error(&est, &truth).unwrap();
        assert!((t.e - 0.15).abs() < 1e-12, "{t:?}");
        assert!((t.e_prime - 0.2).abs() < 1e-12, "{t:?}");
        assert_eq!((t.count, t.count_prime), (6, 4));
        // Signed: (0.1 − 0.2 + 0.3 − 0.2 + 0.0 + 0.1)/6 = 0.1/6.
        assert!((t.bias - 0.1 / 6.0).abs() < 1e-12, "{t:?}");
        // A constant offset has error but no flicker.
        let off: Vec<Vec<f64>> = truth.iter().map(|r| r.iter().map(|x| x + 0.05).collect()).collect();
        let t = temporal_error(&off, &truth).unwrap();
        assert!((t.e - 0.05).abs() < 1e-12 && t.e_prime.abs() < 1e-12);
        assert!(temporal_error(&est[..2], &truth).is_err());
        // Reinhard: L = 1 maps to 1/2, L = 3 to 3/4; grey is its own luminance.
        assert!((tone_mapped_luminance(Vec3::ONE) - 0.5).abs() < 1e-6);
        assert!((tone_mapped_luminance(Vec3::splat(3.0)) - 0.75).abs() < 1e-6);
        // Slope 1/(1+L)² = 1/4 at L = 1: a standard error of 0.1 in every channel becomes 0.025.
        assert!((tone_mapped_stderr(Vec3::ONE, Vec3::splat(0.1)) - 0.025).abs() < 1e-6);
    }
}
