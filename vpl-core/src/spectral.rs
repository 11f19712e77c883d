//! Lazy spectral rendering (Dammertz et al. 2010, §6): RGB transport until a
//! path meets a dispersive surface, where it draws one wavelength λ and
//! carries it, with the RGB colour of λ, until it ends.
//!
//! The colour of λ is the CIE 1931 colour-matching functions (Wyman, Sloan
//! and Shirley's 2013 multi-lobe Gaussian fit) taken to linear sRGB, negative
//! parts cut to zero, each channel divided by its integral over
//! [[`LAMBDA_MIN`], [`LAMBDA_MAX`]] so that white light stays white on
//! average: with λ uniform, E[[`Wavelength::weight`]] = (1, 1, 1), and an RGB
//! throughput β becomes β ⊙ weight without bias. The index of refraction
//! follows Cauchy's law n(λ) = A + B/λ², fitted to the material's n_d
//! (587.6 nm) and Abbe number V_d = (n_d − 1)/(n_F − n_C).
//!
//! ```
//! use vpl_core::spectral::{sample_wavelength, cauchy_ior};
//!
//! let w = sample_wavelength(0.1);
//! assert!(w.lambda > 380.0 && w.lambda < 450.0);
//! // Blue bends more than the reference yellow.
//! assert!(cauchy_ior(1.5, 40.0, w.lambda) > 1.5);
//! ```

use glam::Vec3;
use std::sync::OnceLock;

/// Shortest wavelength sampled (nm).
pub const LAMBDA_MIN: f32 = 380.0;
/// Longest wavelength sampled (nm).
pub const LAMBDA_MAX: f32 = 720.0;
/// Fraunhofer d line, where `ior` is given (nm).
pub const LAMBDA_D: f32 = 587.6;
/// Fraunhofer F line (nm).
pub const LAMBDA_F: f32 = 486.1;
/// Fraunhofer C line (nm).
pub const LAMBDA_C: f32 = 656.3;

/// A drawn wavelength and the RGB weight that replaces the path's colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wavelength {
    /// λ in nm.
    pub lambda: f32,
    /// RGB colour of λ over its density (mean (1, 1, 1) over λ).
    pub weight: Vec3,
}

/// Piecewise Gaussian of the Wyman–Sloan–Shirley fit.
fn g(x: f32, mu: f32, s1: f32, s2: f32) -> f32 {
    let t = (x - mu) / if x < mu { s1 } else { s2 };
    (-0.5 * t * t).exp()
}

/// CIE 1931 x̄, ȳ, z̄ at λ (nm), multi-lobe fit of Wyman et al. 2013.
pub fn cie_xyz(lambda: f32) -> Vec3 {
    let l = lambda;
    let x = 1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7) - 0.065 * g(l, 501.1, 20.4, 26.2);
    let y = 0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1);
    let z = 1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8);
    Vec3::new(x, y, z)
}

/// CIE XYZ to linear sRGB (D65).
pub fn xyz_to_rgb(c: Vec3) -> Vec3 {
    Vec3::new(
        3.2406 * c.x - 1.5372 * c.y - 0.4986 * c.z,
        -0.9689 * c.x + 1.8758 * c.y + 0.0415 * c.z,
        0.0557 * c.x - 0.2040 * c.y + 1.0570 * c.z,
    )
}

/// The clipped sRGB colour of λ before normalisation.
fn raw_rgb(lambda: f32) -> Vec3 {
    xyz_to_rgb(cie_xyz(lambda)).max(Vec3::ZERO)
}

/// ∫ raw_rgb dλ per channel (midpoint rule, 0.25 nm steps).
fn integrals() -> Vec3 {
    static K: OnceLock<Vec3> = OnceLock::new();
    *K.get_or_init(|| {
        let steps = ((LAMBDA_MAX - LAMBDA_MIN) * 4.0) as usize;
        let dl = (LAMBDA_MAX - LAMBDA_MIN) / steps as f32;
        (0..steps).map(|i| raw_rgb(LAMBDA_MIN + (i as f32 + 0.5) * dl) * dl).sum()
    })
}

/// The RGB weight of λ (colour over uniform density, white-balanced).
pub fn wavelength_weight(lambda: f32) -> Vec3 {
    raw_rgb(lambda) * (LAMBDA_MAX - LAMBDA_MIN) / integrals()
}

/// Draws λ uniformly over [`LAMBDA_MIN`, `LAMBDA_MAX`) with `u` ∈ [0, 1).
pub fn sample_wavelength(u: f32) -> Wavelength {
    let lambda = LAMBDA_MIN + u * (LAMBDA_MAX - LAMBDA_MIN);
    Wavelength { lambda, weight: wavelength_weight(lambda) }
}

/// Cauchy's n(λ) = A + B/λ² through n(λ_d) = `ior` with Abbe number `abbe`
/// (no dispersion when `abbe` ≤ 0).
pub fn cauchy_ior(ior: f32, abbe: f32, lambda: f32) -> f32 {
    if abbe <= 0.0 {
        return ior;
    }
    let inv2 = |l: f32| 1.0 / (l * l);
    let b = (ior - 1.0) / (abbe * (inv2(LAMBDA_F) - inv2(LAMBDA_C)));
    let a = ior - b * inv2(LAMBDA_D);
    a + b * inv2(lambda)
}

/// CIE standard illuminant D65, relative spectral power at 10 nm steps
/// from 360 nm to 830 nm (CIE 15:2004, Table T.1; 100 at 560 nm).
const D65_10NM: [f32; 48] = [
    46.6383, 52.0891, 49.9755, 54.6482, 82.7549, 91.486, 93.4318, 86.6823, 104.865, 117.008, 117.812, 114.861, 115.923, 108.811, 109.354,
    107.802, 104.790, 107.689, 104.405, 104.046, 100.0, 96.3342, 95.788, 88.6856, 90.0062, 89.5991, 87.6987, 83.2886, 83.6992, 80.0268,
    80.2146, 82.2778, 78.2842, 69.7213, 71.6091, 74.349, 61.604, 69.8856, 75.087, 63.5927, 46.4182, 66.8054, 63.3828, 64.304, 59.4519,
    51.959, 57.4406, 60.3125,
];

/// D65 at wavelength `lambda` (nm), linearly interpolated; 0 outside 360–830 nm.
pub fn d65(lambda: f32) -> f32 {
    let x = (lambda - 360.0) / 10.0;
    if !(0.0..=47.0).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(46);
    let t = x - i as f32;
    D65_10NM[i] * (1.0 - t) + D65_10NM[i + 1] * t
}

/// What a sampled spectrum describes, which decides how it becomes RGB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpectrumKind {
    /// A reflectance in [0, 1], seen under D65 (the white of sRGB): a flat
    /// spectrum keeps its value in all three channels.
    Reflectance,
    /// A coefficient that may exceed 1 (a conductor's η or k): read as a
    /// reflectance, but not clamped to 1.
    Unbounded,
    /// Emitted radiance: its CIE XYZ over ∫ȳ dλ, so that a flat spectrum of
    /// value v has luminance Y = v (the equal-energy white, slightly pink in
    /// sRGB).
    Emission,
}

/// Linear sRGB of a spectrum given as (wavelength nm, value) pairs in
/// increasing wavelength, linearly interpolated between them and zero
/// outside them, as Mitsuba 3's RGB modes read a `<spectrum>` list:
/// integrated against the CIE 1931 matching functions over 360–830 nm
/// (D65-weighted and normalised for a reflectance), negative channels cut
/// to zero and a reflectance's channels to at most 1. `None` when the
/// wavelengths do not increase or a value is not finite.
pub fn spectrum_to_rgb(samples: &[(f32, f32)], kind: SpectrumKind) -> Option<Vec3> {
    if samples.is_empty() || samples.iter().any(|(l, v)| !l.is_finite() || !v.is_finite()) {
        return None;
    }
    if samples.windows(2).any(|w| w[1].0 <= w[0].0) {
        return None;
    }
    if samples.len() == 1 {
        // One sample: a flat spectrum.
        let v = samples[0].1;
        return Some(match kind {
            SpectrumKind::Reflectance => Vec3::splat(v.clamp(0.0, 1.0)),
            SpectrumKind::Unbounded => Vec3::splat(v.max(0.0)),
            SpectrumKind::Emission => (xyz_to_rgb(Vec3::ONE) * v).max(Vec3::ZERO),
        });
    }
    let value = |l: f32| -> f32 {
        if l < samples[0].0 || l > samples[samples.len() - 1].0 {
            return 0.0;
        }
        let i = samples.partition_point(|s| s.0 <= l).clamp(1, samples.len() - 1);
        let (l0, v0) = samples[i - 1];
        let (l1, v1) = samples[i];
        v0 + (v1 - v0) * (l - l0) / (l1 - l0)
    };
    let illuminant = |l: f32| if kind == SpectrumKind::Emission { 1.0 } else { d65(l) };
    let (steps, lo, hi) = (940usize, 360.0f32, 830.0f32);
    let dl = (hi - lo) / steps as f32;
    let (mut xyz, mut white) = (Vec3::ZERO, Vec3::ZERO);
    for k in 0..steps {
        let l = lo + (k as f32 + 0.5) * dl;
        let cmf = cie_xyz(l) * illuminant(l);
        xyz += cmf * value(l);
        white += cmf;
    }
    Some(match kind {
        // Divided by the illuminant's own colour, channel by channel: a flat
        // reflectance stays grey despite the fit's small errors.
        SpectrumKind::Reflectance => (xyz_to_rgb(xyz) / xyz_to_rgb(white)).clamp(Vec3::ZERO, Vec3::ONE),
        SpectrumKind::Unbounded => (xyz_to_rgb(xyz) / xyz_to_rgb(white)).max(Vec3::ZERO),
        SpectrumKind::Emission => (xyz_to_rgb(xyz) / white.y).max(Vec3::ZERO),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_stays_white_on_average() {
        let n = 4000;
        let mean: Vec3 = (0..n).map(|i| sample_wavelength((i as f32 + 0.5) / n as f32).weight).sum::<Vec3>() / n as f32;
        assert!((mean - Vec3::ONE).abs().max_element() < 2e-3, "{mean}");
    }

    #[test]
    fn flat_spectra_keep_their_value() {
        let r = spectrum_to_rgb(&[(400.0, 0.5), (700.0, 0.5)], SpectrumKind::Reflectance).unwrap();
        // 400–700 nm leaves out a little of the visible range: a few per mille.
        assert!((r - Vec3::splat(0.5)).abs().max_element() < 0.01, "{r}");
        let e = spectrum_to_rgb(&[(360.0, 2.0), (830.0, 2.0)], SpectrumKind::Emission).unwrap();
        // The equal-energy white in linear sRGB (XYZ = (1, 1, 1) taken to sRGB), times 2.
        assert!((e - xyz_to_rgb(Vec3::ONE) * 2.0).abs().max_element() < 0.02, "{e}");
        assert!(spectrum_to_rgb(&[(500.0, 1.0), (400.0, 1.0)], SpectrumKind::Emission).is_none());
    }

    #[test]
    fn red_reflectance_is_red() {
        let r = spectrum_to_rgb(&[(400.0, 0.05), (580.0, 0.05), (620.0, 0.6), (700.0, 0.6)], SpectrumKind::Reflectance).unwrap();
        assert!(r.x > 0.3 && r.y < 0.15 && r.z < 0.1, "{r}");
    }

    #[test]
    fn cauchy_matches_the_abbe_number() {
        let (nd, vd) = (1.5168, 64.17); // BK7
        let nf = cauchy_ior(nd, vd, LAMBDA_F);
        let nc = cauchy_ior(nd, vd, LAMBDA_C);
        assert!((cauchy_ior(nd, vd, LAMBDA_D) - nd).abs() < 1e-5);
        assert!(((nd - 1.0) / (nf - nc) - vd).abs() < 0.05);
        assert_eq!(cauchy_ior(1.5, 0.0, 400.0), 1.5);
    }

    #[test]
    fn hues_run_from_blue_to_red() {
        let b = wavelength_weight(450.0);
        let gr = wavelength_weight(530.0);
        let r = wavelength_weight(640.0);
        assert!(b.z > b.x && b.z > b.y);
        assert!(gr.y > gr.x && gr.y > gr.z);
        assert!(r.x > r.y && r.x > r.z);
    }
}
