//! Wavefront OBJ loading through `tobj`, with the material libraries parsed by
//! [`crate::mtl`].
//!
//! Mapping: `Kd` → diffuse albedo, `Ke` → emitted radiance (one-sided, along
//! the face normal); textures are ignored (noted in a warning), as the VPL
//! papers do for sampling; polygons are triangulated; negative (relative)
//! indices are resolved; vertex normals become shading normals. An
//! MTL that does not exist gives its faces the default material and a
//! warning, as does a `usemtl` naming no material; a malformed MTL is an error.
//!
//! A material with a specular colour (`Ks` ≠ 0) or transparency (`d` < 1,
//! `Tr` > 0, or `illum` 6 / 7) gets the κ-layered model of
//! [`vpl_core::bsdf`] (see [`layered_from_mtl`]); the VPL pipeline still reads
//! `Kd` only, the path tracer and the progressive renderer the layers.

use crate::error::{Result, SceneIoError};
use crate::input::{self, MAX_MESH_BYTES, MAX_TEXT_BYTES};
use crate::mtl::{MtlMaterial, parse_mtl};
use crate::sandbox::Sandbox;
use glam::Vec3;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use vpl_core::material::{Layered, Material};
use vpl_core::mesh::{Mesh, TriangleDesc};

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

/// Loads an OBJ file and its material libraries.
///
/// The OBJ is read through [`crate::input`] (a regular file of at most
/// [`MAX_MESH_BYTES`]), each MTL likewise (at most [`MAX_TEXT_BYTES`]) and
/// parsed by [`crate::mtl`]. A library that does not exist gives a warning and
/// the default material; one that is malformed, no regular file or too long is
/// an error. Libraries must lie in the OBJ's folder (see [`load_obj_in`]).
pub fn load_obj(path: &Path) -> Result<ObjData> {
    load_obj_in(path, &Sandbox::for_scene(path, &Default::default())?)
}

/// [`load_obj`] reading material libraries only where `sandbox` allows.
pub fn load_obj_in(path: &Path, sandbox: &Sandbox) -> Result<ObjData> {
    let bytes = input::read_bytes(path, MAX_MESH_BYTES)?;
    let dir = input::folder_of(path);
    parse_obj(&bytes, path, |name| {
        let found = sandbox.resolve(&dir, name).and_then(|p| input::read_text(&p, MAX_TEXT_BYTES).map(|t| (p, t)));
        match found {
            Err(SceneIoError::Read { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e),
            Ok(found) => Ok(Some(found)),
        }
    })
}

/// Parses the bytes of an OBJ file; `path` names it in messages and
/// `library` answers an `mtllib` name (as written in the file) with the
/// library's path and text, `None` when it does not exist.
pub fn parse_obj(bytes: &[u8], path: &Path, library: impl Fn(&str) -> Result<Option<(PathBuf, String)>>) -> Result<ObjData> {
    let bytes = bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(bytes);
    let usemtl = prescan(bytes, path)?;
    let mut warnings = Vec::new();
    // The libraries are parsed here, not by tobj: tobj only learns each
    // material's index (its own material list stays empty).
    let state = RefCell::new(Libraries::default());
    let opts = tobj::LoadOptions { triangulate: true, single_index: false, ignore_points: true, ignore_lines: true };
    let loaded = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &opts, |name: &Path| {
        state.borrow_mut().load(&name.to_string_lossy(), &library);
        Ok((Vec::new(), state.borrow().index.clone().into_iter().collect()))
    });
    let libs = state.into_inner();
    if let Some(e) = libs.error {
        return Err(e);
    }
    let (models, _) = loaded.map_err(|e| SceneIoError::Obj { path: path.into(), reason: e.to_string() })?;
    warnings.extend(libs.warnings);
    let mut materials: Vec<Material> = Vec::with_capacity(libs.materials.len());
    for m in &libs.materials {
        if m.diffuse_texture.is_some() {
            warnings.push(format!("{}: texture of material '{}' ignored (Kd used)", path.display(), m.name));
        }
        let mut mat = Material::emissive(m.name.clone(), m.kd.unwrap_or(Vec3::splat(0.5)), m.ke.unwrap_or(Vec3::ZERO));
        mat.layered = layered_from_mtl(m.ks, m.ns, m.dissolve, m.ni, m.illum);
        materials.push(mat);
    }
    warnings.extend(unknown_usemtl(&usemtl, path, &libs.index));
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

/// The material libraries an OBJ names, merged in `mtllib` order.
#[derive(Default)]
struct Libraries {
    materials: Vec<MtlMaterial>,
    /// Material name → index in `materials` (a later library's name wins).
    index: BTreeMap<String, usize>,
    warnings: Vec<String>,
    /// The first hard error; loading stops reporting it.
    error: Option<SceneIoError>,
}

impl Libraries {
    /// Loads the `mtllib` statement `names` (one file name, or several
    /// separated by spaces when no file has the whole line as its name).
    fn load(&mut self, names: &str, library: &impl Fn(&str) -> Result<Option<(PathBuf, String)>>) {
        if self.error.is_some() {
            return;
        }
        let names = names.trim();
        match library(names) {
            // `mtllib a.mtl b.mtl`: several libraries when no file has the whole line as its name.
            Ok(None) if names.contains(char::is_whitespace) => {
                for name in names.split_whitespace() {
                    let answer = library(name);
                    self.take(name, answer);
                }
            }
            answer => self.take(names, answer),
        }
    }

    fn take(&mut self, name: &str, answer: Result<Option<(PathBuf, String)>>) {
        if self.error.is_some() {
            return;
        }
        match answer.and_then(|a| a.map(|(p, text)| parse_mtl(&text, &p)).transpose()) {
            Err(e) => self.error = Some(e),
            Ok(None) => self.warnings.push(format!("material library {name} not found; its materials get the default material")),
            Ok(Some(lib)) => {
                self.warnings.extend(lib.warnings);
                for m in lib.materials {
                    self.index.insert(m.name.clone(), self.materials.len());
                    self.materials.push(m);
                }
            }
        }
    }
}

/// One pass over the OBJ before tobj sees it. Checks the indices of face,
/// line and point statements: an index 0 or a relative (negative) index that
/// reaches before the first element of its kind is an error naming the line
/// (tobj 4.0.5 turns it into an index near 2⁶⁴ and overflows). Returns the
/// `usemtl` names with the first line that uses each, for
/// [`unknown_usemtl`].
fn prescan(bytes: &[u8], path: &Path) -> Result<BTreeMap<String, usize>> {
    let mut counts = [0i64; 3];
    let mut usemtl = BTreeMap::new();
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let Ok(line) = std::str::from_utf8(line) else { continue };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("usemtl") => {
                let name = line.trim().strip_prefix("usemtl").unwrap_or_default().trim();
                if !name.is_empty() {
                    usemtl.entry(name.to_string()).or_insert(i + 1);
                }
            }
            Some("f" | "l" | "p") => {
                for word in words {
                    for (k, part) in word.split('/').take(3).enumerate() {
                        let Ok(x) = part.parse::<i64>() else { continue };
                        let kind = ["vertex", "texture coordinate", "normal"][k];
                        let reason = if x == 0 {
                            format!("{kind} index 0 in '{word}': OBJ indices start at 1")
                        } else if x < 0 && x.unsigned_abs() > counts[k] as u64 {
                            format!("relative {kind} index {x} in '{word}' reaches before the first {kind} ({} defined so far)", counts[k])
                        } else {
                            continue;
                        };
                        return Err(SceneIoError::Obj { path: path.into(), reason: format!("line {}: {reason}", i + 1) });
                    }
                }
            }
            _ => {}
        }
    }
    Ok(usemtl)
}

/// Warnings for `usemtl` names (with the first line that uses each, from
/// [`prescan`]) that no library defines: their faces get the default material.
fn unknown_usemtl(usemtl: &BTreeMap<String, usize>, path: &Path, index: &BTreeMap<String, usize>) -> Vec<String> {
    usemtl
        .iter()
        .filter(|(name, _)| !index.contains_key(name.as_str()))
        .map(|(name, line)| {
            format!(
                "{}:{line}: usemtl '{name}' names no material of the loaded libraries; its faces get the default material",
                path.display()
            )
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl lamp\nf 1 2 3 4\n";

    fn with_mtl(obj: &str, mtl: &'static str) -> Result<ObjData> {
        parse_obj(obj.as_bytes(), Path::new("s.obj"), |name| Ok((name == "s.mtl").then(|| (PathBuf::from("s.mtl"), mtl.to_string()))))
    }

    #[test]
    fn libraries_are_parsed_by_the_toolkit() {
        // One number for a colour is all three channels.
        let d = with_mtl(&format!("mtllib s.mtl\n{QUAD}"), "newmtl lamp\nKd 0.8\nKe 10\n").unwrap();
        assert_eq!(d.mesh.triangles.len(), 2);
        assert_eq!((d.materials[0].albedo, d.materials[0].emission), (Vec3::splat(0.8), Vec3::splat(10.0)));
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        // A byte-order mark before mtllib.
        let d = with_mtl(&format!("\u{feff}mtllib s.mtl\n{QUAD}"), "newmtl lamp\nKe 1 1 1\n").unwrap();
        assert!(d.materials[0].is_emissive(), "{:?}", d.warnings);
        // Two numbers: an error naming file, line and value (tobj 4.0.5 panics here).
        let e = with_mtl(&format!("mtllib s.mtl\n{QUAD}"), "newmtl lamp\n\nKe 10 10\n").unwrap_err().to_string();
        assert!(e.starts_with("s.mtl:3: Ke needs one or three numbers"), "{e}");
        // An mtllib naming the OBJ itself.
        let obj = format!("mtllib s.obj\n{QUAD}");
        let e = parse_obj(obj.as_bytes(), Path::new("s.obj"), |_| Ok(Some((PathBuf::from("s.obj"), obj.clone())))).unwrap_err();
        assert!(e.to_string().contains("no material library"), "{e}");
    }

    #[test]
    fn indices_before_the_first_vertex_are_errors_naming_the_line() {
        let quad = |f: &str| format!("v 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\n{f}\n");
        for (f, needle) in [
            ("f 1 2 -2147483648", "line 5: relative vertex index -2147483648"),
            ("f 1//-2 2//1 3//1", "relative normal index -2"),
            ("f 0 1 2", "vertex index 0"),
            ("l 1 -4", "relative vertex index -4"),
        ] {
            let e = parse_obj(quad(f).as_bytes(), Path::new("s.obj"), |_| Ok(None)).unwrap_err().to_string();
            assert!(e.contains(needle) && e.contains("s.obj"), "{f}: {e}");
        }
        assert!(parse_obj(quad("f -3 -2 -1").as_bytes(), Path::new("s.obj"), |_| Ok(None)).is_ok());
    }

    #[test]
    fn missing_libraries_and_materials_are_warnings_naming_them() {
        let d = with_mtl(&format!("mtllib other.mtl\n{QUAD}"), "").unwrap();
        assert!(d.warnings.iter().any(|w| w.contains("other.mtl not found")), "{:?}", d.warnings);
        let d = with_mtl(&format!("mtllib s.mtl\n{QUAD}"), "newmtl lump\nKe 1\n").unwrap();
        assert!(d.warnings.iter().any(|w| w.contains("s.obj:6: usemtl 'lamp' names no material")), "{:?}", d.warnings);
        assert_eq!(d.materials.last().unwrap().name, "default");
        // Several libraries on one line.
        let two = |name: &str| -> Result<Option<(PathBuf, String)>> {
            Ok(match name {
                "a.mtl" => Some(("a.mtl".into(), "newmtl wall\nKd 0.5\n".into())),
                "b.mtl" => Some(("b.mtl".into(), "newmtl lamp\nKe 2\n".into())),
                _ => None,
            })
        };
        let d = parse_obj(format!("mtllib a.mtl b.mtl\n{QUAD}").as_bytes(), Path::new("s.obj"), two).unwrap();
        assert_eq!(d.materials.len(), 2);
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    }

    #[test]
    #[cfg(unix)]
    fn devices_are_refused_as_obj_and_as_mtl() {
        let e = load_obj(Path::new("/dev/zero")).unwrap_err();
        assert!(matches!(e, SceneIoError::NotAFile { .. }), "{e}");
        let dir = std::env::temp_dir().join(format!("vpl-core-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("s.obj"), format!("mtllib /dev/zero\n{QUAD}")).unwrap();
        // Outside the OBJ's folder: refused by the sandbox, naming it.
        let e = load_obj(&dir.join("s.obj")).unwrap_err();
        assert!(matches!(e, SceneIoError::OutsideScene { .. }) && e.to_string().contains("/dev/zero"), "{e}");
        // Allowed there, it is still no regular file.
        let sandbox = Sandbox::for_scene(&dir.join("s.obj"), &crate::LoadOptions::allowing("/dev")).unwrap();
        let e = load_obj_in(&dir.join("s.obj"), &sandbox).unwrap_err();
        assert!(e.to_string().contains("/dev/zero is a device"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

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
