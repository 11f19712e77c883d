//! Batch ray casting on the device: twin of `Scene::intersect` (closest hit)
//! and `Scene::occluded`.

use crate::context::{GpuContext, GpuError};
use crate::kernel::{Binding, SAMPLING_WGSL, bind, dispatch, finish_read, groups_1d, layout, pipeline, storage, storage_init, uniform};
use crate::scene::{BVH_WGSL, GpuScene, scene_layout};
use vpl_core::glam::Vec4;
use vpl_core::{Camera, Ray};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    count: u32,
    row: u32,
    pad: [u32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CameraParams {
    count: u32,
    row: u32,
    key: [u32; 2],
    origin: [f32; 4],
    forward: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    raster: [f32; 4],
}

const WORKGROUP: u32 = 64;

/// Casts batches of rays against a [`GpuScene`]: closest hits as
/// (scene triangle, t), occlusion as booleans, with the CPU BVH's
/// conventions (hits in [0, t_max]).
pub struct GpuRayCaster {
    layout: wgpu::BindGroupLayout,
    closest: wgpu::ComputePipeline,
    any_hit: wgpu::ComputePipeline,
    camera_layout: wgpu::BindGroupLayout,
    camera: wgpu::ComputePipeline,
}

impl GpuRayCaster {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext) -> GpuRayCaster {
        let scene = scene_layout(ctx);
        let layout = layout(ctx, "raycast", &[Binding::Uniform, Binding::Read, Binding::ReadWrite, Binding::ReadWrite]);
        let source = format!("{BVH_WGSL}\n{}", include_str!("raycast.wgsl"));
        let closest = pipeline(ctx, "closest", &source, "closest", &[&scene, &layout]);
        let any_hit = pipeline(ctx, "any_hit", &source, "any_hit", &[&scene, &layout]);
        let camera_layout = crate::kernel::layout(ctx, "camera rays", &[Binding::Uniform, Binding::ReadWrite]);
        let source = format!("{BVH_WGSL}\n{SAMPLING_WGSL}\n{}", include_str!("camera_rays.wgsl"));
        let camera = pipeline(ctx, "camera rays", &source, "main", &[&scene, &camera_layout]);
        GpuRayCaster { layout, closest, any_hit, camera_layout, camera }
    }

    /// Casts `rays`: closest hits as (t bits, triangle) pairs, or (`any`)
    /// occlusion as one bit a ray in words of 32.
    fn run(&self, ctx: &GpuContext, scene: &GpuScene, rays: &[Ray], any: bool) -> Result<Vec<[u32; 2]>, GpuError> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let data: Vec<Vec4> = rays.iter().flat_map(|r| [r.o.extend(r.t_max.min(3.0e38)), r.d.extend(0.0)]).collect();
        let groups = groups_1d(ctx, rays.len() as u64, WORKGROUP);
        let params = Params { count: rays.len() as u32, row: groups.0 * WORKGROUP, pad: [0; 2] };
        let b_params = uniform(ctx, "raycast params", &params);
        let b_rays = storage_init(ctx, "rays", &data);
        let words = rays.len().div_ceil(32);
        // New buffers start zeroed: the occlusion bits are set, never cleared.
        let b_hits = storage(ctx, "hits", if any { 16 } else { rays.len() as u64 * 8 })?;
        let b_blocked = storage(ctx, "blocked", if any { words as u64 * 4 } else { 16 })?;
        let group = bind(ctx, "raycast", &self.layout, &[&b_params, &b_rays, &b_hits, &b_blocked]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, if any { &self.any_hit } else { &self.closest }, &[&scene.group, &group], groups);
        if any {
            let bits: Vec<u32> = finish_read(ctx, enc, &b_blocked, words)?;
            Ok((0..rays.len()).map(|i| [bits[i / 32] >> (i % 32) & 1, 0]).collect())
        } else {
            finish_read(ctx, enc, &b_hits, rays.len())
        }
    }

    /// Closest hits of the `count` camera rays of `camera` under `key`
    /// ([`vpl_core::CameraRays`]), made on the device: only the camera and
    /// the key go up. The device's rays differ from the host's by rounding.
    pub fn closest_camera(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: &Camera,
        key: u64,
        count: usize,
    ) -> Result<Vec<Option<(u32, f32)>>, GpuError> {
        if count == 0 {
            return Ok(Vec::new());
        }
        let groups = groups_1d(ctx, count as u64, WORKGROUP);
        let (f, right, up, sx, sy) = camera.raster_basis();
        let (w, h) = camera.resolution;
        let params = CameraParams {
            count: count as u32,
            row: groups.0 * WORKGROUP,
            key: [key as u32, (key >> 32) as u32],
            origin: camera.origin.extend(0.0).into(),
            forward: f.extend(sx).into(),
            right: right.extend(sy).into(),
            up: up.extend(camera.focus_distance).into(),
            raster: [w as f32, h as f32, camera.lens_radius.max(0.0), 0.0],
        };
        let b_params = uniform(ctx, "camera rays params", &params);
        let b_hits = storage(ctx, "camera hits", count as u64 * 8)?;
        let group = bind(ctx, "camera rays", &self.camera_layout, &[&b_params, &b_hits]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, &self.camera, &[&scene.group, &group], groups);
        let hits: Vec<[u32; 2]> = finish_read(ctx, enc, &b_hits, count)?;
        Ok(hits.into_iter().map(|[t, tri]| (tri != u32::MAX).then(|| (tri, f32::from_bits(t)))).collect())
    }

    /// Closest hit of each ray: (scene triangle, t), as `Scene::intersect`'s
    /// triangle and `Hit::t`.
    pub fn closest(&self, ctx: &GpuContext, scene: &GpuScene, rays: &[Ray]) -> Result<Vec<Option<(u32, f32)>>, GpuError> {
        Ok(self.run(ctx, scene, rays, false)?.into_iter().map(|[t, tri]| (tri != u32::MAX).then(|| (tri, f32::from_bits(t)))).collect())
    }

    /// Whether each ray meets a surface within its `t_max`, as `Scene::occluded`.
    pub fn occluded(&self, ctx: &GpuContext, scene: &GpuScene, rays: &[Ray]) -> Result<Vec<bool>, GpuError> {
        Ok(self.run(ctx, scene, rays, true)?.into_iter().map(|[o, _]| o != 0).collect())
    }
}

/// [`vpl_core::RayCaster`] on the device: batches go through a
/// [`GpuRayCaster`] over the shared scene upload, and the hits are completed
/// on the host ([`vpl_core::Scene::hit_near`]): the triangle the GPU found,
/// at the t the CPU's test of that triangle gives, so a ray that finds the
/// same triangle gives the CPU's hit bit for bit.
pub struct GpuRays {
    gpu: crate::Gpu,
    caster: std::sync::OnceLock<GpuRayCaster>,
}

impl GpuRays {
    /// Ray casting on `gpu`.
    pub fn new(gpu: crate::Gpu) -> GpuRays {
        GpuRays { gpu, caster: std::sync::OnceLock::new() }
    }

    fn caster(&self) -> &GpuRayCaster {
        self.caster.get_or_init(|| GpuRayCaster::new(self.gpu.ctx()))
    }
}

impl vpl_core::RayCaster for GpuRays {
    fn name(&self) -> &'static str {
        "gpu"
    }

    /// # Panics
    /// When the device fails.
    fn intersect(&self, scene: &vpl_core::Scene, rays: &[Ray]) -> Vec<Option<vpl_core::Hit>> {
        let gs = self.gpu.scene(scene).unwrap_or_else(|e| panic!("GPU scene upload: {e}"));
        let hits = self.caster().closest(self.gpu.ctx(), &gs, rays).unwrap_or_else(|e| panic!("GPU ray casting: {e}"));
        rays.iter().zip(hits).map(|(r, h)| h.map(|(tri, t)| scene.hit_near(r, tri, t))).collect()
    }

    /// # Panics
    /// When the device fails.
    fn occluded(&self, scene: &vpl_core::Scene, rays: &[Ray]) -> Vec<bool> {
        let gs = self.gpu.scene(scene).unwrap_or_else(|e| panic!("GPU scene upload: {e}"));
        self.caster().occluded(self.gpu.ctx(), &gs, rays).unwrap_or_else(|e| panic!("GPU ray casting: {e}"))
    }

    /// The rays made on the device from the camera and the key; each hit
    /// completed with the host's ray ([`vpl_core::Scene::hit_near`]).
    ///
    /// # Panics
    /// When the device fails.
    fn intersect_camera(&self, scene: &vpl_core::Scene, batch: &vpl_core::CameraRays) -> Vec<Option<vpl_core::Hit>> {
        let gs = self.gpu.scene(scene).unwrap_or_else(|e| panic!("GPU scene upload: {e}"));
        let hits = self
            .caster()
            .closest_camera(self.gpu.ctx(), &gs, batch.camera, batch.key, batch.rays.len())
            .unwrap_or_else(|e| panic!("GPU ray casting: {e}"));
        batch.rays.iter().zip(hits).map(|(r, h)| h.map(|(tri, t)| scene.hit_near(r, tri, t))).collect()
    }

    /// A batch is a submission and a wait: rounds are better cast together.
    fn speculates(&self) -> bool {
        true
    }
}
