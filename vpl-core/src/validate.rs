//! The guard against non-finite and absurd scene values: every scene, however
//! it was made (a file, a built-in, a library caller), passes these checks in
//! [`crate::Scene::new`], so no renderer starts on a value that turns its
//! sums into inf or NaN.
//!
//! The bounds leave many orders of magnitude between the largest accepted
//! value and f32's overflow (3.4·10³⁸): a radiance of 10¹² on a surface of
//! 10²⁰ m² (a square 10¹⁰ m on a side) still has a finite power, and squared
//! distances between coordinates of 10¹⁰ are 10²⁰.

use crate::error::{CoreError, Result};
use crate::light::Light;
use crate::material::Material;
use glam::Vec3;

/// The largest emitted radiance (W m⁻² sr⁻¹ per channel) a material may have.
/// The sun's is about 2·10⁷.
pub const MAX_RADIANCE: f32 = 1e12;
/// The largest radiant intensity (W sr⁻¹) of a point or spot light.
pub const MAX_INTENSITY: f32 = 1e15;
/// The largest irradiance (W m⁻²) of a directional light.
pub const MAX_IRRADIANCE: f32 = 1e12;
/// The largest absolute coordinate (scene units) of a vertex or light.
pub const MAX_COORDINATE: f32 = 1e10;

fn bad(what: impl Into<String>, reason: String) -> CoreError {
    CoreError::BadValue { what: what.into(), reason }
}

/// A number as people write it: 3e38 rather than 39 digits.
fn num(v: f32) -> String {
    if v.is_finite() && v != 0.0 && (v.abs() >= 1e7 || v.abs() < 1e-4) { format!("{v:e}") } else { format!("{v}") }
}

fn show(v: Vec3) -> String {
    format!("{} {} {}", num(v.x), num(v.y), num(v.z))
}

/// A colour in [0, `max`] per channel.
pub fn colour(v: Vec3, max: f32, what: &str) -> Result<()> {
    if !v.is_finite() {
        return Err(bad(what, format!("{} is not finite", show(v))));
    }
    if v.min_element() < 0.0 {
        return Err(bad(what, format!("{} is negative", show(v))));
    }
    if v.max_element() > max {
        return Err(bad(what, format!("{} is above {}", show(v), num(max))));
    }
    Ok(())
}

/// A position within [`MAX_COORDINATE`] of the origin on every axis.
pub fn position(p: Vec3, what: &str) -> Result<()> {
    if !p.is_finite() {
        return Err(bad(what, format!("{} is not finite", show(p))));
    }
    if p.abs().max_element() > MAX_COORDINATE {
        return Err(bad(what, format!("{} lies beyond ±{}", show(p), num(MAX_COORDINATE))));
    }
    Ok(())
}

/// A material: albedo and specular colour in [0, 1] (more would create
/// energy), emission in [0, [`MAX_RADIANCE`]], κ and transmission in [0, 1],
/// a finite positive index of refraction, a finite non-negative Abbe number.
pub fn material(m: &Material) -> Result<()> {
    let name = &m.name;
    colour(m.albedo, 1.0, &format!("material '{name}' albedo"))
        .map_err(|e| explain(e, "an albedo above 1 reflects more light than it receives"))?;
    colour(m.emission, MAX_RADIANCE, &format!("material '{name}' emission"))?;
    if let Some(l) = &m.layered {
        colour(l.specular, 1.0, &format!("material '{name}' specular"))?;
        let unit = |v: f32, key: &str| -> Result<()> {
            if (0.0..=1.0).contains(&v) { Ok(()) } else { Err(bad(format!("material '{name}' {key}"), format!("{v} is not in [0, 1]"))) }
        };
        unit(l.kappa, "kappa")?;
        unit(l.transmission, "transmission")?;
        if !(l.ior.is_finite() && l.ior > 0.0 && l.ior <= 10.0) {
            return Err(bad(format!("material '{name}' ior"), format!("{} is not in (0, 10]", l.ior)));
        }
        if !(l.abbe.is_finite() && l.abbe >= 0.0) {
            return Err(bad(format!("material '{name}' abbe"), format!("{} is not a finite non-negative number", l.abbe)));
        }
    }
    Ok(())
}

fn explain(e: CoreError, why: &str) -> CoreError {
    match e {
        CoreError::BadValue { what, reason } if reason.contains("above") => {
            CoreError::BadValue { what, reason: format!("{reason}: {why}") }
        }
        e => e,
    }
}

/// A light that is not an emissive triangle: finite positions and unit
/// directions, intensities and irradiances within their bounds. `index`
/// names it (the `[[lights]]` entry).
pub fn light(l: &Light, index: usize) -> Result<()> {
    let what = |key: &str| format!("light {index} {key}");
    let direction = |d: Vec3| -> Result<()> {
        if d.is_finite() && d.is_normalized() { Ok(()) } else { Err(bad(what("direction"), format!("{} is not a unit vector", show(d)))) }
    };
    match l {
        Light::Area { radiance, .. } => colour(*radiance, MAX_RADIANCE, &what("radiance")),
        Light::Point { position: p, intensity } => {
            position(*p, &what("position"))?;
            colour(*intensity, MAX_INTENSITY, &what("intensity"))
        }
        Light::Spot { position: p, direction: d, intensity, cos_falloff_start, cos_total } => {
            position(*p, &what("position"))?;
            direction(*d)?;
            if !(cos_falloff_start.is_finite() && cos_total.is_finite()) {
                return Err(bad(what("angle"), "is not finite".into()));
            }
            colour(*intensity, MAX_INTENSITY, &what("intensity"))
        }
        Light::Directional { direction: d, irradiance } => {
            direction(*d)?;
            colour(*irradiance, MAX_IRRADIANCE, &what("irradiance"))
        }
        Light::Environment { sky } => {
            colour(sky.zenith, MAX_RADIANCE, &what("radiance"))?;
            colour(sky.horizon, MAX_RADIANCE, &what("horizon"))?;
            colour(sky.nadir, MAX_RADIANCE, &what("ground"))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_what_cannot_be_rendered() {
        assert!(material(&Material::emissive("l", Vec3::splat(0.5), Vec3::splat(17.0))).is_ok());
        let e = material(&Material::emissive("l", Vec3::splat(0.5), Vec3::splat(3e38))).unwrap_err().to_string();
        assert!(e.contains("material 'l' emission") && e.contains("above"), "{e}");
        let e = material(&Material::diffuse("w", Vec3::new(1.2, 0.5, 0.5))).unwrap_err().to_string();
        assert!(e.contains("albedo") && e.contains("reflects more"), "{e}");
        assert!(material(&Material::diffuse("w", Vec3::new(f32::NAN, 0.5, 0.5))).unwrap_err().to_string().contains("not finite"));
        let e = light(&Light::Point { position: Vec3::new(0.0, 1e20, 0.0), intensity: Vec3::ONE }, 2).unwrap_err().to_string();
        assert!(e.contains("light 2 position") && e.contains("beyond"), "{e}");
        assert!(light(&Light::Directional { direction: Vec3::Y, irradiance: Vec3::splat(f32::INFINITY) }, 0).is_err());
        assert!(light(&Light::Directional { direction: Vec3::new(0.0, 2.0, 0.0), irradiance: Vec3::ONE }, 0).is_err());
        assert!(position(Vec3::new(1e9, -1e9, 0.0), "v").is_ok());
    }
}
