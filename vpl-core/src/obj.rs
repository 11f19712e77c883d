//! Wavefront OBJ + MTL loading through `tobj`.
//!
//! Mapping: `Kd` → diffuse albedo, `Ke` → emitted radiance (one-sided, along
//! the face normal); textures are ignored (noted in a warning), as the VPL
//! papers do for sampling; polygons are triangulated; negative (relative)
//! indices are resolved; vertex normals become shading normals. A missing or
//! unreadable MTL gives every face the default material and a warning.

use crate::error::{CoreError, Result};
use crate::material::Material;
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
    let opts = tobj::LoadOptions { triangulate: true, single_index: false, ignore_points: true, ignore_lines: true, ..Default::default() };
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
                Material::emissive(m.name.clone(), kd.clamp(Vec3::ZERO, Vec3::ONE), ke.max(Vec3::ZERO))
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

/// The file names of the `mtllib` statements of an OBJ file (for messages).
fn mtllib_names(path: &Path) -> Vec<String> {
    let Ok(text) = std::fs::read_to_string(path) else { return Vec::new() };
    text.lines()
        .filter_map(|l| l.trim_start().strip_prefix("mtllib "))
        .flat_map(|rest| rest.split('#').next().unwrap_or("").split_whitespace().map(str::to_string).collect::<Vec<_>>())
        .collect()
}
