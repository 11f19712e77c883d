//! Wavefront OBJ + MTL loading through `tobj`.
//!
//! Mapping: `Kd` → diffuse albedo, `Ke` → emitted radiance (one-sided, along
//! the face normal); textures are ignored (noted in a warning), as the VPL
//! papers do for sampling; polygons are triangulated; negative (relative)
//! indices are resolved; vertex normals become shading normals. A missing or
//! unreadable MTL gives every face the default material and a warning.
//!
//! A material with a specular colour (`Ks` ≠ 0) or transparency (`d` < 1,
//! `Tr` > 0, or `illum` 6 / 7) gets the κ-layered model of
//! [`crate::bsdf`] (see [`layered_from_mtl`]); the VPL pipeline still reads
//! `Kd` only, the path tracer and the progressive renderer the layers.

use crate::error::{CoreError, Result};
use crate::material::{Layered, Material};
use crate::mesh::{Mesh, TriangleDesc};
use glam::Vec3;
use std::path::Path;

/// What an OBJ file holds: the mesh, its materials and what the loader noticed.
#[derive(Clone, Debug)]
pub struct ObjData {
    /// Geometry; triangle materials index `materials`.
    pub mesh: Mesh,
    /// Materials from the MTL file, plus the default material where needed.
    pub materials: Vec<Material>,
    /// Warnings (missing MTL, ignored textures, faces without material).
    pub warnings: Vec<String>,
}

/// Loads an OBJ file and its MTL.
pub fn load_obj(path: &Path) -> Result<ObjData> {
    if let Err(e) = std::fs::metadata(path) {
        return Err(CoreError::Read { path: path.into(), source: e });
    }
    let opts = tobj::LoadOptions { triangulate: true, single_index: false, ignore_points: true, ignore_lines: true };
    let (models, mtl) = tobj::load_obj(path, &opts).map_err(|e| CoreError::Obj { path: path.into(), reason: e.to_string() })?;
    let mut warnings = Vec::new();
    let mut materials: Vec<Material> = match mtl {
        Ok(ms) => ms
            .iter()
            .map(|m| {
                if m.diffuse_texture.is_some() {
                    warnings.push(format!("{}: texture of material '{}' ignored (Kd used)", path.display(), m.name));
                }
                let kd = m.diffuse.map(Vec3::from).unwrap_or(Vec3::splat(0.5));
                let ke = m.emissive.map(Vec3::from).unwrap_or(Vec3::ZERO);
                let mut mat = Material::emissive(m.name.clone(), kd.clamp(Vec3::ZERO, Vec3::ONE), ke.max(Vec3::ZERO));
                let tr = m.unknown_param.get("Tr").and_then(|v| v.trim().parse::<f32>().ok());
                mat.layered = layered_from_mtl(
                    m.specular.map(Vec3::from),
                    m.shininess,
                    m.dissolve.or(tr.map(|t| 1.0 - t)),
                    m.optical_density,
                    m.illumination_model,
                );
                mat
            })
            .collect(),
        Err(e) => {
            let libs = mtllib_names(path);
            let named = if libs.is_empty() { "named by no mtllib line".to_string() } else { libs.join(", ") };
            warnings.push(format!("{}: material library {named} not loaded ({e}); using the default material", path.display()));
            Vec::new()
        }
    };
    let mut default_index: Option<u32> = None;
    let mut mesh = Mesh::default();
    for model in &models {
        let m = &model.mesh;
        let material = match m.material_id {
            Some(id) if id < materials.len() => id as u32,
            _ => *default_index.get_or_insert_with(|| {
                materials.push(Material::default_material());
                (materials.len() - 1) as u32
            }),
        };
        let pbase = mesh.positions.len() as u32;
        let nbase = mesh.normals.len() as u32;
        mesh.positions.extend(m.positions.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        mesh.normals.extend(m.normals.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        let has_normals = !m.normal_indices.is_empty() && m.normal_indices.len() == m.indices.len();
        for (k, tri) in m.indices.chunks_exact(3).enumerate() {
            let n = has_normals.then(|| {
                let ni = &m.normal_indices[3 * k..3 * k + 3];
                [nbase + ni[0], nbase + ni[1], nbase + ni[2]]
            });
            mesh.triangles.push(TriangleDesc { v: [pbase + tri[0], pbase + tri[1], pbase + tri[2]], n, material });
        }
    }
    Ok(ObjData { mesh, materials, warnings })
}

/// The κ-layered parameters an MTL material describes, if any:
///
/// | MTL | layered model |
/// | --- | --- |
/// | `Ks` | `specular` (the layer tint); white for a transparent material without `Ks` |
/// | `Ns` | κ = (Ns − 1) / 1024, the inverse of the exponent 1024κ + 1, clamped to [0, 1] |
/// | `illum` 3, 5, 7 without `Ns` | κ = 1 (ray-traced mirror reflection) |
/// | `d` (or 1 − `Tr`) | `transmission` = 1 − d |
/// | `illum` 6, 7 with `d` = 1 | `transmission` = 1 (refraction) |
/// | `Ni` | `ior` (1.5 when absent or ≤ 1) |
///
/// `None` (plain Lambertian) when `Ks` is black or absent and nothing transmits.
pub fn layered_from_mtl(ks: Option<Vec3>, ns: Option<f32>, dissolve: Option<f32>, ni: Option<f32>, illum: Option<u8>) -> Option<Layered> {
    let ks = ks.unwrap_or(Vec3::ZERO).clamp(Vec3::ZERO, Vec3::ONE);
    let d = dissolve.unwrap_or(1.0).clamp(0.0, 1.0);
    let refracts = matches!(illum, Some(6 | 7));
    let transmission = if d < 1.0 {
        1.0 - d
    } else if refracts {
        1.0
    } else {
        0.0
    };
    if ks.max_element() <= 0.0 && transmission <= 0.0 {
        return None;
    }
    let kappa = match ns {
        Some(n) if n.is_finite() => ((n - 1.0) / 1024.0).clamp(0.0, 1.0),
        _ if matches!(illum, Some(3 | 5 | 7)) => 1.0,
        _ => 0.0,
    };
    let specular = if ks.max_element() <= 0.0 { Vec3::ONE } else { ks };
    let ior = ni.filter(|n| n.is_finite() && *n > 1.0).unwrap_or(1.5);
    Some(Layered { kappa, specular, transmission, ior, abbe: 0.0 })
}

/// The file names of the `mtllib` statements of an OBJ file (for messages).
fn mtllib_names(path: &Path) -> Vec<String> {
    let Ok(text) = std::fs::read_to_string(path) else { return Vec::new() };
    text.lines()
        .filter_map(|l| l.trim_start().strip_prefix("mtllib "))
        .flat_map(|rest| rest.split('#').next().unwrap_or("").split_whitespace().map(str::to_string).collect::<Vec<_>>())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mtl_maps_to_layers() {
        // Lambertian materials stay plain.
        assert_eq!(layered_from_mtl(Some(Vec3::ZERO), Some(10.0), Some(1.0), Some(1.5), Some(2)), None);
        assert_eq!(layered_from_mtl(None, None, None, None, None), None);
        // A glossy coat: κ from Ns.
        let l = layered_from_mtl(Some(Vec3::splat(0.5)), Some(205.8), None, None, Some(2)).unwrap();
        assert!((l.kappa - 0.2).abs() < 1e-3 && l.transmission == 0.0 && l.specular == Vec3::splat(0.5));
        // A mirror without Ns.
        assert_eq!(layered_from_mtl(Some(Vec3::ONE), None, None, None, Some(3)).unwrap().kappa, 1.0);
        // Glass: illum 7, Ni 1.5, no Ks.
        let g = layered_from_mtl(None, Some(1025.0), None, Some(1.45), Some(7)).unwrap();
        assert!(g.transmission == 1.0 && g.kappa == 1.0 && (g.ior - 1.45).abs() < 1e-6 && g.specular == Vec3::ONE);
        // Dissolve: partly transparent.
        assert!((layered_from_mtl(None, None, Some(0.25), None, None).unwrap().transmission - 0.75).abs() < 1e-6);
    }
}
