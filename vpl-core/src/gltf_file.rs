//! glTF 2.0 scenes (`.gltf` with its buffers and images, or `.glb`), read
//! with the `gltf` crate.
//!
//! What is read, and how it maps onto the toolkit's scene (the table in
//! `docs/scene-files.md` says the same for users):
//!
//! - **Geometry.** The default scene (or the first) with its node
//!   hierarchy: each node's transform (matrix, or translation, rotation and
//!   scale) composes with its parent's. Triangle primitives (lists, strips
//!   and fans) with their `NORMAL`s as shading normals, transformed by the
//!   inverse transpose; a mirroring transform flips the winding. Points and
//!   lines are skipped with a warning. A node that `KHR_node_visibility`
//!   hides is skipped with its subtree.
//! - **Materials.** Albedo is `baseColorFactor` times the average colour of
//!   `baseColorTexture` (sRGB decoded to linear; with `alphaMode` `MASK`
//!   the texels under `alphaCutoff` are left out of the average, with
//!   `BLEND` each texel counts by its alpha). The whole image is averaged,
//!   not the part the texture coordinates reach. Emission is
//!   `emissiveFactor` × `KHR_materials_emissive_strength` × the average of
//!   `emissiveTexture`. Roughness r gives κ through the Blinn–Phong
//!   exponent 2/α² − 2 with α = r² (Walter et al. 2007). A rough (κ < 0.2)
//!   opaque material, metal or not, is Lambertian with the base colour (the
//!   layered model draws a rough reflection as a Lambertian lobe, and so the
//!   VPL methods, which read only the albedo, see what the path tracer
//!   sees). Otherwise it gets the κ-layered model ([`crate::bsdf`]): albedo
//!   (1 − m)·base for metallic m, specular tint (1 − m)·white + m·base,
//!   `KHR_materials_transmission` as `transmission` and `KHR_materials_ior`
//!   as `ior` (1.5 without).
//! - **Lights** (`KHR_lights_punctual`): point, spot and directional, placed
//!   by their nodes (spot and sun along the node's −Z). Their intensities
//!   (cd, lux) are taken as the toolkit's radiometric units (W/sr, W/m²)
//!   with the light's colour; a spot's outer cone is its angle and the
//!   inner cone where its falloff starts. `range` is ignored (light falls
//!   off with the inverse square, as the extension's physical model says).
//! - **Camera.** The first perspective camera a node carries (or the one
//!   with the given name): `yfov` about the vertical axis, looking along the
//!   node's −Z with its +Y up, and 480 pixels high with `aspectRatio`'s
//!   width (4:3 without one). Orthographic cameras are skipped.
//!
//! Everything else (skins, morph targets, animations, texture transforms,
//! other extensions) is ignored; a file that requires an extension this
//! reader does not know is refused by name.

use crate::camera::FovAxis;
use crate::error::{CoreError, Result};
use crate::input::{MAX_MESH_BYTES, read_bytes};
use crate::material::{Layered, Material};
use crate::mesh::{Mesh, TriangleDesc};
use crate::scene_file::{CameraSpec, LightSpec};
use glam::{Mat3, Mat4, Vec3};
pub use gltf;
use gltf::mesh::Mode;
use std::path::{Path, PathBuf};

/// A glTF scene as the toolkit reads it.
#[derive(Clone, Debug, Default)]
pub struct GltfData {
    /// Triangles in world space; their materials index `materials`.
    pub mesh: Mesh,
    /// One material per glTF material the triangles use (and a default
    /// white one for primitives without a material).
    pub materials: Vec<Material>,
    /// The `KHR_lights_punctual` lights, in world space.
    pub lights: Vec<LightSpec>,
    /// The chosen perspective camera, if the file has one.
    pub camera: Option<CameraSpec>,
    /// What loading skipped or noticed.
    pub warnings: Vec<String>,
}

/// Extensions whose content this reader uses (any other that a file
/// requires is refused).
pub const SUPPORTED_EXTENSIONS: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_ior", "KHR_materials_transmission", "KHR_node_visibility"];

/// How deep nodes may nest.
const MAX_DEPTH: usize = 256;

/// Image height of a glTF camera (its width follows `aspectRatio`).
const CAMERA_HEIGHT: u32 = 480;

/// Loads a `.gltf` or `.glb` file; `camera` picks a camera by name (the
/// first perspective camera without it).
pub fn load_gltf(path: &Path, camera: Option<&str>) -> Result<GltfData> {
    let err = |reason: String| CoreError::Gltf { path: path.into(), reason };
    let bytes = read_bytes(path, MAX_MESH_BYTES)?;
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice(&bytes).map_err(|e| err(e.to_string()))?;
    drop(bytes);
    for required in document.extensions_required() {
        if !SUPPORTED_EXTENSIONS.contains(&required) {
            return Err(err(format!("requires the extension {required}, which this reader does not support")));
        }
    }
    let base = path.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."));
    let buffers = gltf::import_buffers(&document, Some(&base), blob).map_err(|e| err(format!("buffers: {e}")))?;
    let mut reader = Reader { buffers: &buffers, images: None, base, path: path.into(), data: GltfData::default() };
    let mut state = Walk { default_material: None, cameras: Vec::new() };
    for m in document.materials() {
        reader.material(&document, &m)?;
    }
    // The default scene, or the first; without scenes, the nodes no node
    // has as a child.
    let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let children: std::collections::HashSet<usize> = document.nodes().flat_map(|n| n.children().map(|c| c.index())).collect();
            document.nodes().filter(|n| !children.contains(&n.index())).collect()
        }
    };
    check_forest(&document, &roots).map_err(err)?;
    for node in roots {
        reader.node(&node, Mat4::IDENTITY, &mut state, 0)?;
    }
    reader.data.camera = match camera {
        Some(name) => Some(
            state
                .cameras
                .iter()
                .find(|(n, _)| n.as_deref() == Some(name))
                .map(|(_, c)| c.clone())
                .ok_or_else(|| err(format!("no perspective camera named '{name}'")))?,
        ),
        None => state.cameras.first().map(|(_, c)| c.clone()),
    };
    Ok(reader.data)
}

/// Refuses a node hierarchy that is no set of disjoint trees (glTF 2.0,
/// §3.5.3: no cycles, and each node has at most one parent): a node that is
/// a child twice, of one parent or of two; a scene that lists a node twice;
/// a scene root that is also a child. On a forest the walk from the roots
/// visits each node at most once; without this check, a node that lists
/// its one child twice, at each of 60 levels, would be visited 2⁶⁰ times.
fn check_forest(document: &gltf::Document, roots: &[gltf::Node]) -> std::result::Result<(), String> {
    let mut parent: Vec<Option<usize>> = vec![None; document.nodes().len()];
    for node in document.nodes() {
        for child in node.children() {
            if let Some(first) = parent[child.index()].replace(node.index()) {
                return Err(format!(
                    "node {} is a child twice (of node {first} and of node {}); glTF's nodes form disjoint trees",
                    child.index(),
                    node.index()
                ));
            }
        }
    }
    let mut listed = vec![false; parent.len()];
    for root in roots {
        if std::mem::replace(&mut listed[root.index()], true) {
            return Err(format!("the scene lists node {} twice", root.index()));
        }
        if let Some(p) = parent[root.index()] {
            return Err(format!("node {} is a root of the scene and a child of node {p}; glTF's nodes form disjoint trees", root.index()));
        }
    }
    Ok(())
}

struct Reader<'a> {
    buffers: &'a [gltf::buffer::Data],
    /// Decoded on first use (only files whose materials have textures pay).
    images: Option<Vec<gltf::image::Data>>,
    base: PathBuf,
    path: PathBuf,
    data: GltfData,
}

struct Walk {
    /// The white material of primitives without one, once needed.
    default_material: Option<u32>,
    /// Perspective cameras in the order met, with their names.
    cameras: Vec<(Option<String>, CameraSpec)>,
}

impl Reader<'_> {
    fn err(&self, reason: String) -> CoreError {
        CoreError::Gltf { path: self.path.clone(), reason }
    }

    fn node(&mut self, node: &gltf::Node, parent: Mat4, state: &mut Walk, depth: usize) -> Result<()> {
        // Validation refuses cycles; the depth bounds the recursion anyway.
        if depth > MAX_DEPTH {
            return Err(self.err(format!("nodes nest deeper than {MAX_DEPTH}")));
        }
        let hidden = node
            .extensions()
            .and_then(|e| e.get("KHR_node_visibility"))
            .and_then(|v| v.get("visible"))
            .and_then(|v| v.as_bool())
            .is_some_and(|v| !v);
        if hidden {
            return Ok(());
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(self.err(format!("node {} has a non-finite transform", node.index())));
        }
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                self.primitive(&mesh, &prim, world, state)?;
            }
        }
        if let Some(light) = node.light() {
            self.light(&light, world)?;
        }
        if let Some(cam) = node.camera() {
            match cam.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    let spec = camera_spec(&p, world);
                    state.cameras.push((cam.name().map(str::to_string), spec));
                }
                gltf::camera::Projection::Orthographic(_) => {
                    self.data.warnings.push(format!("camera {} is orthographic: skipped", cam.name().unwrap_or("(unnamed)")))
                }
            }
        }
        for child in node.children() {
            self.node(&child, world, state, depth + 1)?;
        }
        Ok(())
    }

    fn primitive(&mut self, mesh: &gltf::Mesh, prim: &gltf::Primitive, world: Mat4, state: &mut Walk) -> Result<()> {
        let what = format!("mesh {} primitive {}", mesh.name().unwrap_or(&mesh.index().to_string()), prim.index());
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            self.data.warnings.push(format!("{what}: {mode:?} skipped (only triangles are rendered)"));
            return Ok(());
        }
        let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
            self.data.warnings.push(format!("{what}: no POSITION, skipped"));
            return Ok(());
        };
        self.check_accessor(&pos_acc, &what)?;
        let normal_acc = prim.get(&gltf::Semantic::Normals);
        if let Some(a) = &normal_acc {
            self.check_accessor(a, &what)?;
        }
        if let Some(a) = prim.indices() {
            self.check_accessor(&a, &what)?;
        }
        let buffers = self.buffers;
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<Vec3> =
            reader.read_positions().ok_or_else(|| self.err(format!("{what}: POSITION cannot be read")))?.map(Vec3::from).collect();
        check_bounds(&pos_acc, &positions).map_err(|r| self.err(format!("{what}: {r}")))?;
        let normals: Option<Vec<Vec3>> = match normal_acc {
            Some(_) => {
                Some(reader.read_normals().ok_or_else(|| self.err(format!("{what}: NORMAL cannot be read")))?.map(Vec3::from).collect())
            }
            None => None,
        };
        if normals.as_ref().is_some_and(|n| n.len() != positions.len()) {
            return Err(self.err(format!("{what}: NORMAL and POSITION differ in count")));
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(self.err(format!("{what}: index {bad} is past its {} vertices", positions.len())));
        }
        let tris: Vec<[u32; 3]> =
            match mode {
                Mode::Triangles => indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
                Mode::TriangleStrip => (2..indices.len())
                    .map(|i| {
                        if i % 2 == 0 { [indices[i - 2], indices[i - 1], indices[i]] } else { [indices[i - 1], indices[i - 2], indices[i]] }
                    })
                    .collect(),
                _ => (2..indices.len()).map(|i| [indices[0], indices[i - 1], indices[i]]).collect(),
            };
        let material = match prim.material().index() {
            Some(i) => i as u32,
            None => *state.default_material.get_or_insert_with(|| {
                self.data.materials.push(Material::diffuse("gltf-default", Vec3::ONE));
                self.data.materials.len() as u32 - 1
            }),
        };
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let mirror = Mat3::from_mat4(world).determinant() < 0.0;
        let vbase = self.data.mesh.positions.len() as u32;
        self.data.mesh.positions.extend(positions.iter().map(|&p| world.transform_point3(p)));
        let nbase = self.data.mesh.normals.len() as u32;
        if let Some(ns) = &normals {
            self.data.mesh.normals.extend(ns.iter().map(|&n| (normal_matrix * n).normalize_or_zero()));
        }
        for t in tris {
            let t = if mirror { [t[0], t[2], t[1]] } else { t };
            self.data.mesh.triangles.push(TriangleDesc {
                v: t.map(|i| vbase + i),
                n: normals.as_ref().map(|_| t.map(|i| nbase + i)),
                material,
            });
        }
        Ok(())
    }

    /// Refuses an accessor the `gltf` reader would index past its data.
    fn check_accessor(&self, a: &gltf::Accessor, what: &str) -> Result<()> {
        if a.count() == 0 {
            return Err(self.err(format!("{what}: accessor {} is empty", a.index())));
        }
        if a.sparse().is_some() {
            // The reader bounds-checks sparse data itself (and returns nothing on a bad range).
            return Ok(());
        }
        let Some(view) = a.view() else {
            return Err(self.err(format!("{what}: accessor {} has no buffer view", a.index())));
        };
        let size = a.size();
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(self.err(format!("{what}: buffer view {} has a stride of {stride} for elements of {size} bytes", view.index())));
        }
        let end = a.offset() + stride * (a.count() - 1) + size;
        let buffer_len = self.buffers.get(view.buffer().index()).map_or(0, |d| d.0.len());
        if end > view.length() || view.offset() + view.length() > buffer_len {
            return Err(self.err(format!("{what}: accessor {} reaches past its buffer", a.index())));
        }
        Ok(())
    }

    /// Appends the toolkit's material for `m` (materials keep glTF's order).
    fn material(&mut self, doc: &gltf::Document, m: &gltf::Material) -> Result<()> {
        let index = m.index().unwrap_or(self.data.materials.len());
        let name = m.name().map(str::to_string).unwrap_or_else(|| format!("material{index}"));
        let pbr = m.pbr_metallic_roughness();
        let (cutoff, blend) = match m.alpha_mode() {
            gltf::material::AlphaMode::Mask => (Some(m.alpha_cutoff().unwrap_or(0.5)), false),
            gltf::material::AlphaMode::Blend => (None, true),
            gltf::material::AlphaMode::Opaque => (None, false),
        };
        let tex_avg = match pbr.base_color_texture() {
            Some(info) => self.texture_average(doc, &info.texture(), cutoff, blend, &name)?,
            None => Vec3::ONE,
        };
        let [r, g, b, _] = pbr.base_color_factor();
        let base = Vec3::new(r, g, b).max(Vec3::ZERO) * tex_avg;
        let emissive_avg = match m.emissive_texture() {
            Some(info) => self.texture_average(doc, &info.texture(), None, false, &name)?,
            None => Vec3::ONE,
        };
        let strength = m.emissive_strength().unwrap_or(1.0);
        if !(strength >= 0.0 && strength.is_finite()) {
            return Err(self.err(format!("material {name}: emissiveStrength {strength} must be finite and not negative")));
        }
        let emission = Vec3::from(m.emissive_factor()) * strength * emissive_avg;
        let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
        let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor()).clamp(0.0, 1.0);
        let ior = m.ior().filter(|i| i.is_finite() && *i > 1.0).unwrap_or(1.5);
        let kappa = kappa_from_roughness(roughness);
        // A rough opaque surface is Lambertian with its base colour: the
        // layered model draws a rough (κ < 0.2) reflection layer as a
        // Lambertian lobe anyway, and this way the VPL methods, which read
        // the albedo only, see the same surface as the path tracer.
        let rough_opaque = kappa < 0.2 && transmission == 0.0;
        let mut out = Material::diffuse(name, if rough_opaque { base } else { base * (1.0 - metallic) });
        out.emission = emission;
        if !rough_opaque {
            out.layered = Some(Layered { kappa, specular: Vec3::ONE * (1.0 - metallic) + base * metallic, transmission, ior, abbe: 0.0 });
        }
        self.data.materials.push(out);
        Ok(())
    }

    /// The average linear colour of a texture's image (sRGB decoded).
    fn texture_average(
        &mut self,
        doc: &gltf::Document,
        tex: &gltf::Texture,
        cutoff: Option<f32>,
        blend: bool,
        material: &str,
    ) -> Result<Vec3> {
        if self.images.is_none() {
            let images = gltf::import_images(doc, Some(&self.base), self.buffers).map_err(|e| self.err(format!("images: {e}")))?;
            self.images = Some(images);
        }
        let images = self.images.as_ref().expect("decoded above");
        let Some(img) = images.get(tex.source().index()) else {
            return Err(self.err(format!("material {material}: texture image {} is missing", tex.source().index())));
        };
        match average_colour(img, cutoff, blend) {
            Some(c) => Ok(c),
            None => {
                self.data
                    .warnings
                    .push(format!("material {material}: texture {} has no visible texel; its colour is taken as black", tex.index()));
                Ok(Vec3::ZERO)
            }
        }
    }

    fn light(&mut self, light: &gltf::khr_lights_punctual::Light, world: Mat4) -> Result<()> {
        let colour = Vec3::from(light.color()) * light.intensity();
        let colour = colour.max(Vec3::ZERO);
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        let name = light.name().unwrap_or("(unnamed)");
        let spec = match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => LightSpec::Point { position: position.into(), intensity: colour.into() },
            gltf::khr_lights_punctual::Kind::Directional => {
                LightSpec::Directional { direction: direction.into(), irradiance: colour.into() }
            }
            gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                if !(inner_cone_angle >= 0.0 && inner_cone_angle < outer_cone_angle && outer_cone_angle <= std::f32::consts::FRAC_PI_2) {
                    return Err(self.err(format!(
                        "spot light {name}: innerConeAngle {inner_cone_angle} and outerConeAngle {outer_cone_angle} need 0 ≤ inner < outer ≤ π/2"
                    )));
                }
                LightSpec::Spot {
                    position: position.into(),
                    direction: direction.into(),
                    intensity: colour.into(),
                    angle: outer_cone_angle.to_degrees(),
                    falloff_start: Some(inner_cone_angle.to_degrees()),
                }
            }
        };
        if direction == Vec3::ZERO && !matches!(spec, LightSpec::Point { .. }) {
            return Err(self.err(format!("light {name}: its node's transform gives it no direction")));
        }
        if light.range().is_some() {
            self.data.warnings.push(format!("light {name}: range ignored (inverse-square falloff)"));
        }
        self.data.lights.push(spec);
        Ok(())
    }
}

/// Checks POSITION data against the accessor's `min` and `max` (which
/// glTF requires for positions): a buffer that does not match its
/// accessors, read on regardless, gives a different shape.
fn check_bounds(a: &gltf::Accessor, positions: &[Vec3]) -> std::result::Result<(), String> {
    let bound = |v: Option<gltf::json::Value>| -> Option<Vec3> {
        let v = v?;
        let a = v.as_array()?;
        if a.len() != 3 {
            return None;
        }
        Some(Vec3::new(a[0].as_f64()? as f32, a[1].as_f64()? as f32, a[2].as_f64()? as f32))
    };
    let (Some(lo), Some(hi)) = (bound(a.min()), bound(a.max())) else { return Ok(()) };
    let tol = 1e-4 * (hi - lo).abs().max_element().max(1.0);
    if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !(p.cmpge(lo - tol).all() && p.cmple(hi + tol).all())) {
        return Err(format!(
            "POSITION {i} of accessor {} is {p}, outside the accessor's min {lo} and max {hi}: the buffer does not match its accessors",
            a.index()
        ));
    }
    Ok(())
}

/// κ for glTF's roughness r: α = r² (GGX), the Blinn–Phong exponent with
/// the same lobe width n = 2/α² − 2 (Walter et al. 2007, §5.2), and the
/// layered model's n = 1024κ + 1 solved for κ, clamped to [0, 1].
pub fn kappa_from_roughness(r: f32) -> f32 {
    let alpha = (r * r).max(1e-4);
    let n = 2.0 / (alpha * alpha) - 2.0;
    ((n - 1.0) / 1024.0).clamp(0.0, 1.0)
}

/// The mean linear RGB of an image's texels (8- and 16-bit channels are
/// sRGB, float channels linear); with `cutoff`, texels whose alpha is
/// under it are left out; with `blend`, each texel counts by its alpha.
/// `None` when no texel counts.
pub fn average_colour(img: &gltf::image::Data, cutoff: Option<f32>, blend: bool) -> Option<Vec3> {
    use gltf::image::Format;
    let (channels, bytes) = match img.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    let texel = channels * bytes;
    // A lookup table for 8-bit sRGB.
    let lut: Vec<f32> = (0..256).map(|v| crate::image::srgb_to_linear(v as f32 / 255.0)).collect();
    let read = |t: &[u8], c: usize| -> f32 {
        match bytes {
            1 => t[c] as f32 / 255.0,
            2 => u16::from_le_bytes([t[2 * c], t[2 * c + 1]]) as f32 / 65535.0,
            _ => f32::from_le_bytes([t[4 * c], t[4 * c + 1], t[4 * c + 2], t[4 * c + 3]]),
        }
    };
    let linear = |t: &[u8], c: usize| -> f32 {
        match bytes {
            1 => lut[t[c] as usize],
            2 => crate::image::srgb_to_linear(read(t, c)),
            _ => read(t, c),
        }
    };
    let (mut sum, mut weight) = (glam::DVec3::ZERO, 0.0f64);
    for t in img.pixels.chunks_exact(texel) {
        let rgb = match channels {
            1 | 2 => Vec3::splat(linear(t, 0)),
            _ => Vec3::new(linear(t, 0), linear(t, 1), linear(t, 2)),
        };
        let alpha = match channels {
            2 => read(t, 1),
            4 => read(t, 3),
            _ => 1.0,
        };
        let w = match cutoff {
            Some(c) if alpha < c => continue,
            _ if blend => alpha.clamp(0.0, 1.0),
            _ => 1.0,
        };
        if rgb.is_finite() {
            sum += rgb.as_dvec3() * w as f64;
            weight += w as f64;
        }
    }
    (weight > 0.0).then(|| (sum / weight).as_vec3())
}

/// A perspective camera on a node: at the node's origin, looking along its
/// −Z with its +Y up.
fn camera_spec(p: &gltf::camera::Perspective, world: Mat4) -> CameraSpec {
    let origin = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    let aspect = p.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0).unwrap_or(4.0 / 3.0);
    let width = ((CAMERA_HEIGHT as f32 * aspect).round() as u32).clamp(1, 16384);
    CameraSpec {
        origin: origin.into(),
        target: (origin + forward).into(),
        up: up.into(),
        fov: p.yfov().to_degrees(),
        fov_axis: FovAxis::Y,
        resolution: [width, CAMERA_HEIGHT],
        lens_radius: 0.0,
        focus_distance: 1.0,
    }
}
