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
//!   sees). Otherwise it gets the κ-layered model ([`vpl_core::bsdf`]): albedo
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

use crate::bitmap::{AlphaUse, Depth, Texels};
use crate::error::{Result, SceneIoError};
use crate::input::{MAX_IMAGE_BYTES, MAX_MESH_BYTES, read_bytes};
use crate::sandbox::Sandbox;
use glam::{Mat3, Mat4, Vec3};
pub use gltf;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use vpl_core::CoreError;
use vpl_core::camera::FovAxis;
use vpl_core::material::{Layered, Material};
use vpl_core::mesh::{Mesh, TriangleDesc};
use vpl_core::scene_file::{CameraSpec, LightSpec};

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

/// The most bytes the mesh read from one file may take when no memory limit
/// is given (16 GiB: about 200 M triangles with normals).
pub const MAX_MESH_MEMORY: u64 = 16 << 30;

/// Bytes the loaded mesh takes per vertex read: the position read and its
/// world-space copy.
const BYTES_PER_VERTEX: u64 = 24;
/// Bytes per index read: the index and a third of a triangle record.
const BYTES_PER_INDEX: u64 = 16;

/// Image height of a glTF camera (its width follows `aspectRatio`).
const CAMERA_HEIGHT: u32 = 480;

/// Loads a `.gltf` or `.glb` file; `camera` picks a camera by name (the
/// first perspective camera without it). Its buffers and images must lie
/// in its folder (see [`load_gltf_in`] to allow more).
pub fn load_gltf(path: &Path, camera: Option<&str>) -> Result<GltfData> {
    load_gltf_in(path, camera, &Sandbox::for_scene(path, &Default::default())?)
}

/// [`load_gltf`] reading buffers and images only where `sandbox` allows,
/// and within its memory limit.
pub fn load_gltf_in(path: &Path, camera: Option<&str>, sandbox: &Sandbox) -> Result<GltfData> {
    let err = |reason: String| SceneIoError::Gltf { path: path.into(), reason };
    let bytes = read_bytes(path, MAX_MESH_BYTES)?;
    check_glb_header(&bytes).map_err(err)?;
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| err(e.to_string()))?;
    // The `gltf` validation indexes a primitive's POSITION accessor without
    // a bounds check: looked at first, then the whole document validated.
    check_position_indices(document.as_json()).map_err(err)?;
    let document = gltf::Document::from_json(document.into_json()).map_err(|e| err(e.to_string()))?;
    drop(bytes);
    for required in document.extensions_required() {
        if !SUPPORTED_EXTENSIONS.contains(&required) {
            return Err(err(format!("requires the extension {required}, which this reader does not support")));
        }
    }
    let base = crate::input::folder_of(path);
    let budget = sandbox.memory_limit().unwrap_or(MAX_MESH_MEMORY).min(MAX_MESH_MEMORY);
    let mut reader =
        Reader { buffers: Vec::new(), textures: HashMap::new(), base, sandbox, path: path.into(), budget, data: GltfData::default() };
    reader.buffers = reader.load_buffers(&document, blob)?;
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

/// Refuses a GLB whose header gives a total length under the header's own
/// 12 bytes: the `gltf` reader subtracts 12 from it unchecked (an overflow
/// panic where overflow checks are on).
fn check_glb_header(bytes: &[u8]) -> std::result::Result<(), String> {
    if let Some(len) = bytes.strip_prefix(b"glTF").and_then(|rest| rest.get(4..8)) {
        let length = u32::from_le_bytes([len[0], len[1], len[2], len[3]]);
        if length < 12 {
            return Err(format!("its GLB header gives a length of {length} bytes, less than the header itself"));
        }
    }
    Ok(())
}

/// Refuses a primitive whose POSITION names an accessor that does not exist
/// (before `gltf`'s validation, which would index past the accessors).
fn check_position_indices(root: &gltf::json::Root) -> std::result::Result<(), String> {
    use gltf::json::validation::Checked;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(i) = prim.attributes.get(&Checked::Valid(gltf::json::mesh::Semantic::Positions)) {
                if i.value() >= root.accessors.len() {
                    return Err(format!(
                        "mesh {m} primitive {p}: POSITION names accessor {}, but there are {}",
                        i.value(),
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    Ok(())
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
    /// The bytes of each buffer, at least its `byteLength` of them.
    buffers: Vec<Vec<u8>>,
    /// The mean colour of each (image, alpha cutoff, blend) read so far;
    /// images are decoded one at a time, when a material first needs them.
    textures: HashMap<(usize, Option<u32>, bool), Option<Vec3>>,
    /// The folder of the file: relative URIs start here.
    base: PathBuf,
    sandbox: &'a Sandbox,
    path: PathBuf,
    /// Bytes the mesh may still grow by.
    budget: u64,
    data: GltfData,
}

struct Walk {
    /// The white material of primitives without one, once needed.
    default_material: Option<u32>,
    /// Perspective cameras in the order met, with their names.
    cameras: Vec<(Option<String>, CameraSpec)>,
}

impl Reader<'_> {
    fn err(&self, reason: String) -> SceneIoError {
        SceneIoError::Gltf { path: self.path.clone(), reason }
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
        self.check_accessor(&pos_acc, &what, "POSITION", Kind::Vec3)?;
        let normal_acc = prim.get(&gltf::Semantic::Normals);
        if let Some(a) = &normal_acc {
            self.check_accessor(a, &what, "NORMAL", Kind::Vec3)?;
        }
        if let Some(a) = prim.indices() {
            self.check_accessor(&a, &what, "indices", Kind::Index)?;
        }
        // What the primitive adds to the mesh, refused before it is read.
        let vertices = pos_acc.count() as u64;
        let indices = prim.indices().map_or(vertices, |a| a.count() as u64);
        let cost = vertices * BYTES_PER_VERTEX * if normal_acc.is_some() { 2 } else { 1 } + indices * BYTES_PER_INDEX;
        if cost > self.budget {
            return Err(self.err(format!(
                "{what}: its {vertices} vertices and {indices} indices take about {cost} bytes, more than the {} left of the memory limit",
                self.budget
            )));
        }
        self.budget -= cost;
        let buffers = &self.buffers;
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
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

    /// Refuses an accessor the `gltf` reader would misread or index past its
    /// data: one whose type is not what its use requires (glTF 2.0 §3.7.2.1:
    /// POSITION and NORMAL are float VEC3; §3.7.2.2 indices are unsigned
    /// integer scalars), whose elements overlap (a stride under their size),
    /// or whose elements, sparse indices or sparse values reach past their
    /// buffer view or a view past its buffer.
    fn check_accessor(&self, a: &gltf::Accessor, what: &str, role: &str, kind: Kind) -> Result<()> {
        let fail = |reason: String| self.err(format!("{what}: {role} accessor {}: {reason}", a.index()));
        let (ty, dims) = (a.data_type(), a.dimensions());
        let fits = match kind {
            Kind::Vec3 => ty == DataType::F32 && dims == Dimensions::Vec3,
            Kind::Index => matches!(ty, DataType::U8 | DataType::U16 | DataType::U32) && dims == Dimensions::Scalar,
        };
        if !fits {
            let want = match kind {
                Kind::Vec3 => "FLOAT VEC3",
                Kind::Index => "an UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT SCALAR",
            };
            return Err(fail(format!("it holds {ty:?} {dims:?}; {role} must be {want}")));
        }
        if a.count() == 0 {
            return Err(fail("it is empty".into()));
        }
        let size = a.size();
        if let Some(view) = a.view() {
            self.check_elements(&view, a.offset(), a.count(), size).map_err(fail)?;
        }
        if let Some(sparse) = a.sparse() {
            let n = sparse.count();
            if n == 0 || n > a.count() {
                return Err(fail(format!("{n} sparse elements for {} elements (1 to {} allowed)", a.count(), a.count())));
            }
            let indices = sparse.indices();
            let (view, index_size) = (indices.view(), indices.index_type().size());
            self.check_elements(&view, indices.offset(), n, index_size).map_err(|r| fail(format!("sparse indices: {r}")))?;
            let values = sparse.values();
            self.check_elements(&values.view(), values.offset(), n, size).map_err(|r| fail(format!("sparse values: {r}")))?;
        } else if a.view().is_none() {
            return Err(fail("it has neither a buffer view nor sparse data".into()));
        }
        Ok(())
    }

    /// Checks that `count` elements of `size` bytes from `offset` in `view`
    /// (at its stride) lie inside the view, and the view inside its buffer.
    fn check_elements(&self, view: &gltf::buffer::View, offset: usize, count: usize, size: usize) -> std::result::Result<(), String> {
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(format!("buffer view {} has a stride of {stride} bytes for elements of {size}", view.index()));
        }
        let end = (count as u64 - 1)
            .checked_mul(stride as u64)
            .and_then(|x| x.checked_add(offset as u64 + size as u64))
            .filter(|&end| end <= view.length() as u64);
        if end.is_none() {
            return Err(format!("{count} elements of {size} bytes at offset {offset} reach past buffer view {}", view.index()));
        }
        self.view_bytes(view).map(|_| ())
    }

    /// The bytes of a buffer view; an error naming it when it reaches past
    /// its buffer.
    fn view_bytes(&self, view: &gltf::buffer::View) -> std::result::Result<&[u8], String> {
        let buffer = view.buffer().index();
        let data = self.buffers.get(buffer).map_or(&[][..], |d| &d[..]);
        let range = view.offset().checked_add(view.length()).map(|end| view.offset()..end);
        range.and_then(|r| data.get(r)).ok_or_else(|| {
            format!(
                "buffer view {} ({} bytes at offset {}) reaches past buffer {buffer} of {} bytes",
                view.index(),
                view.length(),
                view.offset(),
                data.len()
            )
        })
    }

    /// Every buffer's bytes: the GLB's binary chunk, a base64 `data:` URI,
    /// or a file inside the sandbox (at most [`MAX_MESH_BYTES`]); each must
    /// hold at least the `byteLength` it declares.
    fn load_buffers(&self, document: &gltf::Document, mut blob: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>> {
        let mut out = Vec::with_capacity(document.buffers().len());
        for buffer in document.buffers() {
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob
                    .take()
                    .ok_or_else(|| self.err(format!("buffer {} is the binary chunk, which the file does not have", buffer.index())))?,
                gltf::buffer::Source::Uri(uri) => self.uri_bytes(uri, MAX_MESH_BYTES, &format!("buffer {}", buffer.index()))?,
            };
            if data.len() < buffer.length() {
                return Err(self.err(format!("buffer {} declares {} bytes but holds {}", buffer.index(), buffer.length(), data.len())));
            }
            out.push(data);
        }
        Ok(out)
    }

    /// The bytes a URI names: a base64 `data:` URI, or a relative path
    /// (%-escapes decoded; `file:` URIs taken as paths) read through the
    /// sandbox with at most `limit` bytes. Other schemes are refused.
    fn uri_bytes(&self, uri: &str, limit: u64, what: &str) -> Result<Vec<u8>> {
        let fail = |reason: String| self.err(format!("{what}: {reason}"));
        if let Some(rest) = uri.strip_prefix("data:") {
            let Some((_, data)) = rest.split_once(";base64,") else {
                return Err(fail("its data URI is not base64".into()));
            };
            if data.len() as u64 / 4 * 3 > limit {
                return Err(fail(format!("its data URI holds more than the {limit} bytes this input may have")));
            }
            return base64::decode(data).map_err(|e| fail(format!("its data URI is not valid base64 ({e})")));
        }
        let path = match uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:")) {
            Some(p) => p,
            None if has_scheme(uri) => return Err(fail("only relative paths, file: and data: URIs are read".into())),
            None => uri,
        };
        let decoded = percent_encoding::percent_decode_str(path)
            .decode_utf8()
            .map_err(|_| fail("its URI's %-escapes do not decode to UTF-8".into()))?;
        // A reference that leaves the sandbox keeps its own error; others
        // say which buffer or image they are.
        let wrap = |e: SceneIoError| match e {
            e @ SceneIoError::OutsideScene { .. } => e,
            SceneIoError::Core(CoreError::Invalid(r)) => fail(r),
            e => fail(e.to_string()),
        };
        let file = self.sandbox.resolve(&self.base, &decoded).map_err(wrap)?;
        read_bytes(&file, limit).map_err(wrap)
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

    /// The average linear colour of a texture's image (sRGB decoded),
    /// decoded within the memory limit when first used.
    fn texture_average(
        &mut self,
        doc: &gltf::Document,
        tex: &gltf::Texture,
        cutoff: Option<f32>,
        blend: bool,
        material: &str,
    ) -> Result<Vec3> {
        let image = tex.source();
        let key = (image.index(), cutoff.map(f32::to_bits), blend);
        let mean = match self.textures.get(&key) {
            Some(m) => *m,
            None => {
                let what = format!("material {material}: image {}", image.index());
                // `Image::source` unwraps what glTF 2.0 §5.17 requires
                // (a mimeType beside a bufferView; a uri or a bufferView)
                // and validation does not check: checked here first.
                match doc.as_json().images.get(image.index()) {
                    Some(j) if j.buffer_view.is_some() && j.mime_type.is_none() => {
                        return Err(self.err(format!("{what}: a bufferView image needs a mimeType")));
                    }
                    Some(j) if j.buffer_view.is_none() && j.uri.is_none() => {
                        return Err(self.err(format!("{what}: it has neither a uri nor a bufferView")));
                    }
                    Some(_) => {}
                    None => return Err(self.err(format!("{what}: no such image"))),
                }
                let (bytes, mime) = match image.source() {
                    gltf::image::Source::View { view, mime_type } => {
                        (self.view_bytes(&view).map_err(|r| self.err(format!("{what}: {r}")))?.to_vec(), Some(mime_type))
                    }
                    gltf::image::Source::Uri { uri, mime_type } => (self.uri_bytes(uri, MAX_IMAGE_BYTES, &what)?, mime_type),
                };
                let format = match mime {
                    Some("image/png") => Some(::image::ImageFormat::Png),
                    Some("image/jpeg") => Some(::image::ImageFormat::Jpeg),
                    _ => None,
                };
                let img =
                    crate::bitmap::decode(&bytes, format, self.sandbox.memory_limit()).map_err(|r| self.err(format!("{what}: {r}")))?;
                drop(bytes);
                let mean = crate::bitmap::mean_colour(crate::bitmap::texels(&img), true, AlphaUse { cutoff, blend });
                self.textures.insert(key, mean);
                mean
            }
        };
        match mean {
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
    // The message names the position, never the bytes read (a buffer may
    // be any file the sandbox allows).
    if let Some(i) = positions.iter().position(|p| !(p.cmpge(lo - tol).all() && p.cmple(hi + tol).all())) {
        return Err(format!(
            "POSITION {i} of accessor {} lies outside the accessor's min and max: the buffer does not match its accessors",
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
/// `None` when no texel counts. See [`crate::bitmap::mean_colour`].
pub fn average_colour(img: &gltf::image::Data, cutoff: Option<f32>, blend: bool) -> Option<Vec3> {
    use gltf::image::Format;
    let (channels, depth) = match img.format {
        Format::R8 => (1, Depth::U8),
        Format::R8G8 => (2, Depth::U8),
        Format::R8G8B8 => (3, Depth::U8),
        Format::R8G8B8A8 => (4, Depth::U8),
        Format::R16 => (1, Depth::U16),
        Format::R16G16 => (2, Depth::U16),
        Format::R16G16B16 => (3, Depth::U16),
        Format::R16G16B16A16 => (4, Depth::U16),
        Format::R32G32B32FLOAT => (3, Depth::F32),
        Format::R32G32B32A32FLOAT => (4, Depth::F32),
    };
    crate::bitmap::mean_colour(Texels { bytes: &img.pixels, channels, depth }, true, AlphaUse { cutoff, blend })
}

/// What an accessor must hold for its use.
#[derive(Clone, Copy)]
enum Kind {
    /// POSITION and NORMAL: FLOAT VEC3.
    Vec3,
    /// Indices: unsigned integer scalars.
    Index,
}

/// Whether a URI starts with a scheme (`name:` with a letter first, then
/// letters, digits, `+`, `-` or `.`; RFC 3986 §3.1).
fn has_scheme(uri: &str) -> bool {
    let Some((scheme, _)) = uri.split_once(':') else { return false };
    let mut chars = scheme.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic()) && chars.all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
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
