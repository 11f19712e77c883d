//! The scene flattened into storage buffers: a binary BVH, the prepared
//! triangles in its primitive order, per-triangle data and materials.

use crate::context::{GpuContext, GpuError};
use crate::kernel::{Binding, bind, layout, storage_init};
use obvhs::BvhBuildParams;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::triangle::Triangle;
use std::sync::Arc;
use std::time::Duration;
use vpl_core::glam::{Vec3, Vec4};
use vpl_core::{Geometry, Scene};

/// WGSL of the scene bindings and the traversal (`closest_hit`, `occluded`),
/// prepended to the kernels that trace rays.
pub(crate) const BVH_WGSL: &str = include_str!("bvh.wgsl");

/// Deepest BVH the traversal stack of `bvh.wgsl` holds.
const MAX_DEPTH: usize = 64;

/// A scene on the device (group 0 of every kernel that traces rays).
///
/// The GPU traverses a binary BVH (obvhs's PLOC builder with reinsertion,
/// up to 4 triangles a leaf) rather than the CPU's 8-wide one: a stack walk
/// of a binary tree is short, portable WGSL. Both test triangles with the
/// same watertight test on the same vertex coordinates
/// ([`Bvh::vertices`](vpl_core::bvh::Bvh::vertices)), so hits agree up to
/// rounding.
pub struct GpuScene {
    /// The geometry uploaded (compared by identity to reuse the upload).
    geometry: Arc<Geometry>,
    /// Materials as uploaded: (albedo, emission) per material.
    materials: Vec<[Vec4; 2]>,
    /// BVH nodes.
    pub nodes: usize,
    /// Depth of the BVH.
    pub depth: usize,
    buffers: Vec<wgpu::Buffer>,
    pub(crate) group: wgpu::BindGroup,
}

fn material_rows(scene: &Scene) -> Vec<[Vec4; 2]> {
    scene.materials.iter().map(|m| [m.albedo.extend(0.0), m.emission.extend(0.0)]).collect()
}

/// Bind-group layout of the scene: six read-only storage buffers.
pub(crate) fn scene_layout(ctx: &GpuContext) -> wgpu::BindGroupLayout {
    layout(ctx, "scene", &[Binding::Read; 6])
}

impl GpuScene {
    /// Builds the BVH and uploads `scene`.
    pub fn new(ctx: &GpuContext, scene: &Scene) -> Result<GpuScene, GpuError> {
        let g = &scene.geometry;
        if g.triangles.is_empty() {
            return Err(GpuError::Invalid(format!("scene `{}` has no triangles", scene.name)));
        }
        // The vertices the CPU's BVH tests (the mesh's own coordinates).
        let vertices: Vec<[Vec3; 3]> =
            (0..g.triangles.len() as u32).map(|i| g.bvh.vertices(i).unwrap_or_else(|| g.triangles[i as usize].corners())).collect();
        let tris: Vec<Triangle> = vertices.iter().map(|v| Triangle { v0: v[0].into(), v1: v[1].into(), v2: v[2].into() }).collect();
        let mut params = BvhBuildParams::medium_build();
        params.max_prims_per_leaf = 4;
        let bvh = build_bvh2_from_tris(&tris, params, &mut Duration::default());
        // Depth by a walk from the root.
        let mut depth = 0;
        let mut todo = vec![(0usize, 1usize)];
        while let Some((i, d)) = todo.pop() {
            depth = depth.max(d);
            let n = &bvh.nodes[i];
            if n.prim_count == 0 {
                todo.push((n.first_index as usize, d + 1));
                todo.push((n.first_index as usize + 1, d + 1));
            }
        }
        if depth > MAX_DEPTH {
            return Err(GpuError::Invalid(format!("BVH of `{}` is {depth} levels deep; the GPU traversal holds {MAX_DEPTH}", scene.name)));
        }
        let nodes: Vec<Vec4> = bvh
            .nodes
            .iter()
            .flat_map(|n| {
                let (a, b) = (n.aabb.min, n.aabb.max);
                [Vec4::new(a.x, a.y, a.z, f32::from_bits(n.first_index)), Vec4::new(b.x, b.y, b.z, f32::from_bits(n.prim_count))]
            })
            .collect();
        let prepared: Vec<Vec4> = bvh.primitive_indices.iter().flat_map(|&i| vertices[i as usize].map(|v| v.extend(0.0))).collect();
        let info: Vec<Vec4> = g
            .triangles
            .iter()
            .flat_map(|t| {
                [t.p0.extend(f32::from_bits(t.material)), t.e1.extend(f32::from_bits(t.normals)), t.e2.extend(t.area), t.ng.extend(0.0)]
            })
            .collect();
        let normals: Vec<Vec4> = g.shading_normals.iter().flat_map(|ns| ns.map(|n| n.extend(0.0))).collect();
        let materials = material_rows(scene);
        let flat_materials: Vec<Vec4> = materials.iter().flatten().copied().collect();
        let buffers = vec![
            storage_init(ctx, "bvh_nodes", &nodes),
            storage_init(ctx, "bvh_tris", &prepared),
            storage_init(ctx, "bvh_order", &bvh.primitive_indices),
            storage_init(ctx, "tri_info", &info),
            storage_init(ctx, "tri_normals", &normals),
            storage_init(ctx, "materials", &flat_materials),
        ];
        let layout = scene_layout(ctx);
        let refs: Vec<&wgpu::Buffer> = buffers.iter().collect();
        let group = bind(ctx, "scene", &layout, &refs);
        Ok(GpuScene { geometry: g.clone(), materials, nodes: bvh.nodes.len(), depth, buffers, group })
    }

    /// Whether this upload is of `scene`'s geometry (by identity) and materials.
    pub fn holds(&self, scene: &Scene) -> bool {
        Arc::ptr_eq(&self.geometry, &scene.geometry) && self.materials == material_rows(scene)
    }

    /// Bytes on the device.
    pub fn memory_bytes(&self) -> u64 {
        self.buffers.iter().map(|b| b.size()).sum()
    }
}

/// A [`GpuScene`] kept across frames and rebuilt when the scene changes.
#[derive(Default)]
pub(crate) struct SceneCache(Option<Arc<GpuScene>>);

impl SceneCache {
    /// The upload of `scene`, reusing the last one when it still holds.
    pub fn get(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<Arc<GpuScene>, GpuError> {
        match &self.0 {
            Some(s) if s.holds(scene) => Ok(s.clone()),
            _ => {
                let s = Arc::new(GpuScene::new(ctx, scene)?);
                self.0 = Some(s.clone());
                Ok(s)
            }
        }
    }
}
