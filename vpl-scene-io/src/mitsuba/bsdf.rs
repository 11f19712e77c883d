//! Mitsuba BSDFs onto the toolkit's materials: Lambertian albedo, or the
//! κ-layered model ([`vpl_core::bsdf`]).
//!
//! | Mitsuba | toolkit |
//! | --- | --- |
//! | `diffuse` | Lambertian, albedo = `reflectance` (0.5) |
//! | `conductor` | mirror (κ = 1), tint = `specular_reflectance` × F₀ of `eta`/`k` or of the named `material` (`none`: 1) |
//! | `roughconductor` | the same with κ from `alpha` (0.1); κ < 0.2: Lambertian with the tint as albedo |
//! | `dielectric`, `roughdielectric` | transmission 1, ior = `int_ior`/`ext_ior` (bk7/air), tint = `specular_transmittance`, κ = 1 or from `alpha` |
//! | `thindielectric` | transmission 1 with ior 1 (no bending; its ≈ 8 % reflection is dropped) |
//! | `plastic`, `roughplastic` | albedo `diffuse_reflectance` (0.5) under a coat of tint `specular_reflectance`, ior `int_ior`/`ext_ior` (polypropylene/air), κ = 1 or from `alpha`; κ < 0.2: Lambertian with the diffuse reflectance |
//! | `twosided` | its nested BSDF, reflecting on both sides |
//!
//! κ follows from a microfacet roughness α through the Blinn–Phong exponent
//! n = 2/α² − 2 (Walter et al. 2007): κ = (n − 1)/1024. A layered rough
//! reflection is drawn as a Lambertian lobe by the toolkit, so a rough
//! (κ < 0.2) opaque BSDF becomes Lambertian, as glTF's rough materials do.

use super::xml::{Object, Value};
use super::{Ctx, TexParam};
use crate::error::Result;
use glam::Vec3;
use vpl_core::material::{Layered, Material};
use vpl_core::spectral::SpectrumKind;

/// A BSDF as the toolkit reads it.
pub(crate) struct Bsdf {
    pub material: Material,
    /// Reflects on both sides (`twosided`, or a dielectric).
    pub two_sided: bool,
}

/// κ of a microfacet roughness α (Beckmann or GGX alike).
pub fn kappa_from_alpha(alpha: f32) -> f32 {
    let a = alpha.max(1e-3);
    let n = 2.0 / (a * a) - 2.0;
    ((n - 1.0) / 1024.0).clamp(0.0, 1.0)
}

/// Named indices of refraction Mitsuba knows (its `int_ior`/`ext_ior`
/// names, at 589 nm).
pub const IOR_NAMES: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.47),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

/// Normal-incidence reflectance F₀ (linear sRGB) of the conductors a
/// `material` parameter may name; `none` is a perfect mirror.
pub const CONDUCTORS: &[(&str, [f32; 3])] = &[
    ("none", [1.0, 1.0, 1.0]),
    ("Ag", [0.972, 0.960, 0.915]),
    ("Al", [0.913, 0.922, 0.924]),
    ("Au", [1.000, 0.766, 0.336]),
    ("Cu", [0.955, 0.638, 0.538]),
    ("Cr", [0.549, 0.556, 0.554]),
];

/// F₀ of a conductor with complex index η + ik: ((η−1)² + k²)/((η+1)² + k²).
pub fn conductor_f0(eta: Vec3, k: Vec3) -> Vec3 {
    let num = (eta - Vec3::ONE) * (eta - Vec3::ONE) + k * k;
    let den = (eta + Vec3::ONE) * (eta + Vec3::ONE) + k * k;
    num / den.max(Vec3::splat(1e-6))
}

impl Ctx<'_> {
    /// The material of BSDF `b` (named `name` where it has no id).
    pub(crate) fn bsdf(&mut self, b: &Object, depth: usize) -> Result<Bsdf> {
        let name = b.id.clone().unwrap_or_else(|| format!("{}@{}", b.ty, b.at.line));
        let mut out = match b.ty.as_str() {
            "twosided" => {
                let nested = self.nested(b, "bsdf")?;
                let Some(inner) = nested.first() else {
                    return Err(self.doc.err(b.at, format!("{} needs a nested <bsdf>", b.what())));
                };
                if nested.len() > 1 {
                    self.warn(b.at, format!("{}: a different back-side BSDF is not supported; both sides use the first", b.what()));
                }
                if depth > 8 {
                    return Err(self.doc.err(b.at, "twosided BSDFs nest too deeply"));
                }
                let inner = self.bsdf(inner, depth + 1)?;
                let mut m = inner.material;
                if b.id.is_some() {
                    m.name = name.clone();
                }
                Bsdf { material: m, two_sided: true }
            }
            "diffuse" => {
                let albedo = self.colour(b, "reflectance", Vec3::splat(0.5), SpectrumKind::Reflectance, TexParam::Allowed)?;
                Bsdf { material: Material::diffuse(&name, albedo), two_sided: false }
            }
            "conductor" | "roughconductor" => {
                let f0 = self.conductor_f0(b)?;
                let tint = f0 * self.colour(b, "specular_reflectance", Vec3::ONE, SpectrumKind::Reflectance, TexParam::Allowed)?;
                let kappa = if b.ty == "conductor" { 1.0 } else { kappa_from_alpha(self.alpha(b)?) };
                let material = if kappa < 0.2 {
                    Material::diffuse(&name, tint.min(Vec3::ONE))
                } else {
                    let mut m = Material::diffuse(&name, Vec3::ZERO);
                    m.layered = Some(Layered { kappa, specular: tint, transmission: 0.0, ior: 1.5, abbe: 0.0 });
                    m
                };
                Bsdf { material, two_sided: false }
            }
            "dielectric" | "roughdielectric" | "thindielectric" => {
                let ior = if b.ty == "thindielectric" {
                    let _ = (self.ior(b, "int_ior", 1.5046)?, self.ior(b, "ext_ior", 1.000277)?);
                    self.warn(b.at, format!("{}: drawn as a clear sheet (no bending); its reflection (≈ 8 %) is dropped", b.what()));
                    1.0
                } else {
                    self.ior(b, "int_ior", 1.5046)? / self.ior(b, "ext_ior", 1.000277)?
                };
                if !(ior.is_finite() && ior > 0.0) {
                    return Err(self.doc.err(b.at, format!("{}: int_ior/ext_ior = {ior} is not a positive number", b.what())));
                }
                let _ = self.colour(b, "specular_reflectance", Vec3::ONE, SpectrumKind::Reflectance, TexParam::Allowed)?;
                let tint = self.colour(b, "specular_transmittance", Vec3::ONE, SpectrumKind::Reflectance, TexParam::Allowed)?;
                let kappa = if b.ty == "roughdielectric" { kappa_from_alpha(self.alpha(b)?) } else { 1.0 };
                let mut m = Material::diffuse(&name, Vec3::ZERO);
                m.layered = Some(Layered { kappa, specular: tint, transmission: 1.0, ior, abbe: 0.0 });
                Bsdf { material: m, two_sided: true }
            }
            "plastic" | "roughplastic" => {
                let diffuse = self.colour(b, "diffuse_reflectance", Vec3::splat(0.5), SpectrumKind::Reflectance, TexParam::Allowed)?;
                let specular = self.colour(b, "specular_reflectance", Vec3::ONE, SpectrumKind::Reflectance, TexParam::Allowed)?;
                let ior = self.ior(b, "int_ior", 1.49)? / self.ior(b, "ext_ior", 1.000277)?;
                if let Some(p) = b.prop("nonlinear") {
                    if p.value == Value::Boolean(true) {
                        self.warn(p.at, format!("{}: nonlinear = true is drawn as the linear model", b.what()));
                    }
                }
                let kappa = if b.ty == "plastic" { 1.0 } else { kappa_from_alpha(self.alpha(b)?) };
                let mut m = Material::diffuse(&name, diffuse);
                if kappa >= 0.2 {
                    m.layered = Some(Layered { kappa, specular, transmission: 0.0, ior: ior.max(1.0 + 1e-4), abbe: 0.0 });
                }
                Bsdf { material: m, two_sided: false }
            }
            other => {
                return Err(self.doc.err(
                    b.at,
                    format!(
                        "<bsdf type=\"{other}\"> is not supported (diffuse, conductor, roughconductor, dielectric, roughdielectric, thindielectric, plastic, roughplastic, twosided are)"
                    ),
                ));
            }
        };
        if b.ty != "twosided" {
            out.material.name = name;
        }
        self.unused(b, &["distribution", "sample_visible", "alpha_u", "alpha_v", "alpha"]);
        Ok(out)
    }

    /// α of a rough BSDF: `alpha`, or the geometric mean of `alpha_u` and
    /// `alpha_v` (the toolkit's lobes are isotropic).
    fn alpha(&mut self, b: &Object) -> Result<f32> {
        let u = b.prop("alpha_u").map(|p| self.float_value(b, p)).transpose()?;
        let v = b.prop("alpha_v").map(|p| self.float_value(b, p)).transpose()?;
        let a = match (u, v) {
            (Some(u), Some(v)) => {
                if u != v {
                    self.warn(b.at, format!("{}: anisotropic α ({u}, {v}) drawn as isotropic {}", b.what(), (u * v).sqrt()));
                }
                (u * v).sqrt()
            }
            _ => self.float(b, "alpha", 0.1)?,
        };
        if !(a > 0.0 && a.is_finite()) {
            return Err(self.doc.err(b.at, format!("{}: alpha {a} must be positive", b.what())));
        }
        Ok(a)
    }

    /// An index of refraction: a number or one of [`IOR_NAMES`].
    fn ior(&mut self, b: &Object, key: &str, default: f32) -> Result<f32> {
        let Some(p) = b.prop(key) else { return Ok(default) };
        match &p.value {
            Value::Float(f) if *f > 0.0 => Ok(*f),
            Value::Integer(i) if *i > 0 => Ok(*i as f32),
            Value::String(s) => IOR_NAMES.iter().find(|(n, _)| n.eq_ignore_ascii_case(s.trim())).map(|(_, v)| *v).ok_or_else(|| {
                let names: Vec<&str> = IOR_NAMES.iter().map(|(n, _)| *n).collect();
                self.doc.err(p.at, format!("{}: {key} '{s}' is not a known medium ({})", b.what(), names.join(", ")))
            }),
            v => Err(self.doc.err(p.at, format!("{}: {key} must be a positive number or a medium's name, not a {}", b.what(), v.kind()))),
        }
    }

    /// F₀ of a conductor: from `eta` and `k`, or the named `material`.
    fn conductor_f0(&mut self, b: &Object) -> Result<Vec3> {
        let eta = b.prop("eta");
        let k = b.prop("k");
        let material = b.prop("material");
        match (eta, k) {
            (Some(e), Some(k)) => {
                if let Some(m) = material {
                    self.warn(m.at, format!("{}: material is ignored where eta and k are given", b.what()));
                }
                let e = self.colour_of(b, e, SpectrumKind::Unbounded)?;
                let k = self.colour_of(b, k, SpectrumKind::Unbounded)?;
                Ok(conductor_f0(e, k))
            }
            (None, None) => {
                let Some(m) = material else { return Ok(Vec3::ONE) };
                let Value::String(name) = &m.value else {
                    return Err(self.doc.err(m.at, format!("{}: material must be a string", b.what())));
                };
                CONDUCTORS.iter().find(|(n, _)| n == name).map(|(_, f)| Vec3::from(*f)).ok_or_else(|| {
                    let names: Vec<&str> = CONDUCTORS.iter().map(|(n, _)| *n).collect();
                    self.doc.err(
                        m.at,
                        format!("{}: conductor material '{name}' is not known ({}); give eta and k instead", b.what(), names.join(", ")),
                    )
                })
            }
            _ => Err(self.doc.err(b.at, format!("{}: eta and k must be given together", b.what()))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kappa_follows_the_phong_exponent() {
        // α = 0.1: n = 198, just under the diffuse threshold.
        assert!((kappa_from_alpha(0.1) - 197.0 / 1024.0).abs() < 1e-4);
        assert_eq!(kappa_from_alpha(0.001), 1.0);
        assert_eq!(kappa_from_alpha(1.0), 0.0);
    }

    #[test]
    fn gold_f0_from_eta_and_k() {
        // η, k of gold at about 650, 550, 450 nm.
        let f = conductor_f0(Vec3::new(0.143, 0.374, 1.442), Vec3::new(3.983, 2.385, 1.603));
        assert!(f.x > 0.9 && f.y > 0.6 && f.y < 0.9 && f.z < 0.5, "{f}");
    }
}
