//! Batch ray casting on the device: twin of `Scene::intersect` (closest hit)
//! and `Scene::occluded`.

use crate::context::{GpuContext, GpuError};
use crate::kernel::{Binding, SAMPLING_WGSL, bind, dispatch, finish_read, groups_1d, layout, pipeline, storage, storage_init, uniform};
use crate::scene::{BVH_WGSL, GpuScene, scene_layout};
use vpl_core::{Camera, CameraRays, Ray};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    count: u32,
    row: u32,
    stride: u32,
    tri_only: u32,
}

/// What the batches made on the device begin with: the rays, the `row` of
/// their 2D dispatch, and the stream key they draw from.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BatchHead {
    count: u32,
    row: u32,
    key: [u32; 2],
}

impl BatchHead {
    fn new(count: usize, groups: (u32, u32, u32), key: u64) -> BatchHead {
        BatchHead { count: count as u32, row: groups.0 * WORKGROUP, key: [key as u32, (key >> 32) as u32] }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CameraParams {
    head: BatchHead,
    tri_only: u32,
    pad: [u32; 3],
    origin: [f32; 4],
    forward: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    raster: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BounceParams {
    head: BatchHead,
    eps: f32,
    pad: [u32; 3],
}

/// The hits of a camera batch left on the device, for rays that leave them.
pub(crate) struct KeptCamera {
    key: u64,
    count: usize,
    camera: Camera,
    params: wgpu::Buffer,
    hits: wgpu::Buffer,
}

impl KeptCamera {
    /// Whether these are the hits of `batch`.
    fn holds(&self, batch: &CameraRays) -> bool {
        self.key == batch.key && self.count == batch.rays.len() && self.camera == *batch.camera
    }
}

const WORKGROUP: u32 = 64;

/// How the closest-hit kernels write their answers.
const HITS_WGSL: &str = include_str!("hits.wgsl");

/// What a batch brings back.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Answer {
    /// (t bits, triangle) a ray.
    Hits,
    /// The triangle a ray.
    Triangles,
    /// One bit a ray, in words of 32.
    Occlusion,
}

/// Closest hits as the kernels write them (`u32::MAX`: a miss).
fn hits_of(words: Vec<u32>) -> Vec<Option<(u32, f32)>> {
    words.chunks_exact(2).map(|w| (w[1] != u32::MAX).then(|| (w[1], f32::from_bits(w[0])))).collect()
}

/// Triangles as the kernels write them.
fn triangles_of(words: Vec<u32>) -> Vec<Option<u32>> {
    words.into_iter().map(|t| (t != u32::MAX).then_some(t)).collect()
}

/// Casts batches of rays against a [`GpuScene`]: closest hits as
/// (scene triangle, t) or the triangle alone, occlusion as booleans, with
/// the CPU BVH's conventions (hits in [0, t_max]).
///
/// A ray goes up as 24 B (origin, direction) in a batch of unbounded rays,
/// else 28 B (and t_max); a hit comes back as 8 B, a triangle as 4 B, an
/// occlusion answer as one bit.
pub struct GpuRayCaster {
    layout: wgpu::BindGroupLayout,
    closest: wgpu::ComputePipeline,
    any_hit: wgpu::ComputePipeline,
    camera_layout: wgpu::BindGroupLayout,
    camera: wgpu::ComputePipeline,
    bounce_layout: wgpu::BindGroupLayout,
    bounce: wgpu::ComputePipeline,
}

impl GpuRayCaster {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext) -> GpuRayCaster {
        let scene = scene_layout(ctx);
        let layout = layout(ctx, "raycast", &[Binding::Uniform, Binding::Read, Binding::ReadWrite, Binding::ReadWrite]);
        let source = format!("{BVH_WGSL}\n{HITS_WGSL}\n{}", include_str!("raycast.wgsl"));
        let closest = pipeline(ctx, "closest", &source, "closest", &[&scene, &layout]);
        let any_hit = pipeline(ctx, "any_hit", &source, "any_hit", &[&scene, &layout]);
        let camera_layout = crate::kernel::layout(ctx, "camera rays", &[Binding::Uniform, Binding::ReadWrite]);
        let source = format!("{BVH_WGSL}\n{SAMPLING_WGSL}\n{HITS_WGSL}\n{}", include_str!("camera_rays.wgsl"));
        let camera = pipeline(ctx, "camera rays", &source, "main", &[&scene, &camera_layout]);
        let (u, r, w) = (Binding::Uniform, Binding::Read, Binding::ReadWrite);
        let bounce_layout = crate::kernel::layout(ctx, "bounce rays", &[u, w, u, r, w]);
        let bounce = pipeline(ctx, "bounce rays", &source, "bounce", &[&scene, &bounce_layout]);
        GpuRayCaster { layout, closest, any_hit, camera_layout, camera, bounce_layout, bounce }
    }

    /// Casts `rays` and reads back the words of `answer`.
    fn run(&self, ctx: &GpuContext, scene: &GpuScene, rays: &[Ray], answer: Answer) -> Result<Vec<u32>, GpuError> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        // t_max travels only in a batch that has one.
        let unbounded = rays.iter().all(|r| r.t_max >= 3.0e38);
        let stride = if unbounded { 6 } else { 7 };
        let data: Vec<f32> = rays
            .iter()
            .flat_map(|r| {
                let v = [r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z, r.t_max.min(3.0e38)];
                v.into_iter().take(stride)
            })
            .collect();
        let groups = groups_1d(ctx, rays.len() as u64, WORKGROUP);
        let n = rays.len();
        let params =
            Params { count: n as u32, row: groups.0 * WORKGROUP, stride: stride as u32, tri_only: (answer == Answer::Triangles) as u32 };
        let b_params = uniform(ctx, "raycast params", &params);
        let b_rays = storage_init(ctx, "rays", &data);
        let words = match answer {
            Answer::Hits => 2 * n,
            Answer::Triangles => n,
            Answer::Occlusion => n.div_ceil(32),
        };
        // New buffers start zeroed: the occlusion bits are set, never cleared.
        // Hits take 2n words either way (hits.wgsl); triangles read back the first n.
        let (hits_size, blocked_size) = if answer == Answer::Occlusion { (16, words as u64 * 4) } else { (2 * n as u64 * 4, 16) };
        let b_hits = storage(ctx, "hits", hits_size)?;
        let b_blocked = storage(ctx, "blocked", blocked_size)?;
        let group = bind(ctx, "raycast", &self.layout, &[&b_params, &b_rays, &b_hits, &b_blocked]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let kernel = if answer == Answer::Occlusion { &self.any_hit } else { &self.closest };
        dispatch(&mut enc, kernel, &[&scene.group, &group], groups);
        finish_read(ctx, enc, if answer == Answer::Occlusion { &b_blocked } else { &b_hits }, words)
    }

    /// Makes the `count` camera rays of `camera` under `key` on the device,
    /// casts them and reads back the words of `answer`; with
    /// [`Answer::Triangles`] the hits stay on the device for
    /// [`GpuRayCaster::bounce_triangles`].
    fn run_camera(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: &Camera,
        key: u64,
        count: usize,
        answer: Answer,
    ) -> Result<(Vec<u32>, Option<KeptCamera>), GpuError> {
        if count == 0 {
            return Ok((Vec::new(), None));
        }
        let groups = groups_1d(ctx, count as u64, WORKGROUP);
        let tri_only = answer == Answer::Triangles;
        let [origin, forward, right, up, raster] = camera_rows(camera).map(Into::into);
        let params = CameraParams {
            head: BatchHead::new(count, groups, key),
            tri_only: tri_only as u32,
            pad: [0; 3],
            origin,
            forward,
            right,
            up,
            raster,
        };
        // Triangles, then their t (kept on the device); or (t, triangle) pairs.
        let words = if tri_only { count } else { 2 * count };
        let b_params = uniform(ctx, "camera rays params", &params);
        let b_hits = storage(ctx, "camera hits", 2 * count as u64 * 4)?;
        let group = bind(ctx, "camera rays", &self.camera_layout, &[&b_params, &b_hits]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, &self.camera, &[&scene.group, &group], groups);
        let out = finish_read(ctx, enc, &b_hits, words)?;
        let kept = tri_only.then(|| KeptCamera { key, count, camera: camera.clone(), params: b_params, hits: b_hits });
        Ok((out, kept))
    }

    /// The triangles the rays of `bounce` hit, made on the device from the
    /// hits of the camera batch `kept` holds ([`vpl_core::BounceRays`]):
    /// 8 B a ray up, 4 B back.
    pub(crate) fn bounce_triangles(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        kept: &KeptCamera,
        key: u64,
        eps: f32,
        origins: &[(u32, u32)],
    ) -> Result<Vec<Option<u32>>, GpuError> {
        if origins.is_empty() {
            return Ok(Vec::new());
        }
        let groups = groups_1d(ctx, origins.len() as u64, WORKGROUP);
        let params = BounceParams { head: BatchHead::new(origins.len(), groups, key), eps, pad: [0; 3] };
        let b_params = uniform(ctx, "bounce params", &params);
        let flat: Vec<[u32; 2]> = origins.iter().map(|&(i, j)| [i, j]).collect();
        let b_origins = storage_init(ctx, "bounce origins", &flat);
        let b_out = storage(ctx, "bounce hits", origins.len() as u64 * 4)?;
        let group = bind(ctx, "bounce", &self.bounce_layout, &[&kept.params, &kept.hits, &b_params, &b_origins, &b_out]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, &self.bounce, &[&scene.group, &group], groups);
        Ok(triangles_of(finish_read(ctx, enc, &b_out, origins.len())?))
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
        Ok(hits_of(self.run_camera(ctx, scene, camera, key, count, Answer::Hits)?.0))
    }

    /// The triangles [`GpuRayCaster::closest_camera`] finds, alone (4 B a ray).
    pub fn camera_triangles(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: &Camera,
        key: u64,
        count: usize,
    ) -> Result<Vec<Option<u32>>, GpuError> {
        Ok(triangles_of(self.run_camera(ctx, scene, camera, key, count, Answer::Triangles)?.0))
    }

    /// Closest hit of each ray: (scene triangle, t), as `Scene::intersect`'s
    /// triangle and `Hit::t`.
    pub fn closest(&self, ctx: &GpuContext, scene: &GpuScene, rays: &[Ray]) -> Result<Vec<Option<(u32, f32)>>, GpuError> {
        Ok(hits_of(self.run(ctx, scene, rays, Answer::Hits)?))
    }

    /// The triangle of each ray's closest hit, alone (4 B a ray).
    pub fn closest_triangles(&self, ctx: &GpuContext, scene: &GpuScene, rays: &[Ray]) -> Result<Vec<Option<u32>>, GpuError> {
        Ok(triangles_of(self.run(ctx, scene, rays, Answer::Triangles)?))
    }

    /// Whether each ray meets a surface within its `t_max`, as `Scene::occluded`.
    pub fn occluded(&self, ctx: &GpuContext, scene: &GpuScene, rays: &[Ray]) -> Result<Vec<bool>, GpuError> {
        let bits = self.run(ctx, scene, rays, Answer::Occlusion)?;
        Ok((0..rays.len()).map(|i| bits[i / 32] >> (i % 32) & 1 != 0).collect())
    }
}

/// [`vpl_core::RayCaster`] on the device: batches go through a
/// [`GpuRayCaster`] over the shared scene upload, and the hits are completed
/// on the host ([`vpl_core::Scene::hit_on`]): the triangle the GPU found,
/// at the t the CPU's test of that triangle gives, so a ray that finds the
/// same triangle gives the CPU's hit bit for bit (and only the triangle
/// crosses back).
pub struct GpuRays {
    gpu: crate::Gpu,
    caster: std::sync::OnceLock<GpuRayCaster>,
    /// The hits of the last camera batch and the scene upload they are
    /// of, for rays that leave them.
    kept: std::sync::Mutex<Option<(KeptCamera, std::sync::Arc<GpuScene>)>>,
}

impl GpuRays {
    /// Ray casting on `gpu`.
    pub fn new(gpu: crate::Gpu) -> GpuRays {
        GpuRays { gpu, caster: std::sync::OnceLock::new(), kept: std::sync::Mutex::new(None) }
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
        let tris = self.caster().closest_triangles(self.gpu.ctx(), &gs, rays).unwrap_or_else(|e| panic!("GPU ray casting: {e}"));
        rays.iter().zip(tris).map(|(r, tri)| tri.map(|tri| scene.hit_on(r, tri))).collect()
    }

    /// # Panics
    /// When the device fails.
    fn occluded(&self, scene: &vpl_core::Scene, rays: &[Ray]) -> Vec<bool> {
        let gs = self.gpu.scene(scene).unwrap_or_else(|e| panic!("GPU scene upload: {e}"));
        self.caster().occluded(self.gpu.ctx(), &gs, rays).unwrap_or_else(|e| panic!("GPU ray casting: {e}"))
    }

    /// The rays made on the device from the camera and the key; each hit
    /// completed with the host's ray ([`vpl_core::Scene::hit_on`]).
    ///
    /// # Panics
    /// When the device fails.
    fn intersect_camera(&self, scene: &vpl_core::Scene, batch: &vpl_core::CameraRays) -> Vec<Option<vpl_core::Hit>> {
        let gs = self.gpu.scene(scene).unwrap_or_else(|e| panic!("GPU scene upload: {e}"));
        let (words, kept) = self
            .caster()
            .run_camera(self.gpu.ctx(), &gs, batch.camera, batch.key, batch.rays.len(), Answer::Triangles)
            .unwrap_or_else(|e| panic!("GPU ray casting: {e}"));
        *self.kept.lock().expect("kept camera hits lock") = kept.map(|k| (k, gs));
        batch.rays.iter().zip(triangles_of(words)).map(|(r, tri)| tri.map(|tri| scene.hit_on(r, tri))).collect()
    }

    /// Made on the device from the camera batch's hits when they are the
    /// last batch's (else cast as given); each hit completed with the
    /// host's ray ([`vpl_core::Scene::hit_on`]).
    ///
    /// # Panics
    /// When the device fails.
    fn intersect_bounce(&self, scene: &vpl_core::Scene, batch: &vpl_core::BounceRays) -> Vec<Option<vpl_core::Hit>> {
        let gs = self.gpu.scene(scene).unwrap_or_else(|e| panic!("GPU scene upload: {e}"));
        let kept = self.kept.lock().expect("kept camera hits lock");
        let Some((k, _)) = kept.as_ref().filter(|(k, s)| k.holds(batch.camera) && std::sync::Arc::ptr_eq(s, &gs)) else {
            drop(kept);
            return self.intersect(scene, &batch.rays);
        };
        let tris = self
            .caster()
            .bounce_triangles(self.gpu.ctx(), &gs, k, batch.key, scene.epsilon(), &batch.origins)
            .unwrap_or_else(|e| panic!("GPU ray casting: {e}"));
        batch.rays.iter().zip(tris).map(|(r, tri)| tri.map(|tri| scene.hit_on(r, tri))).collect()
    }

    /// A batch is a submission and a wait: rounds are better cast together.
    fn speculates(&self) -> bool {
        true
    }
}

/// The camera as `camera_ray_of` and `camera_ray_at` (`sampling.wgsl`) read
/// it: the origin; the forward axis with s_x; the right axis with s_y; the
/// true up with the focus distance; the raster (width, height, lens radius,
/// 0).
pub(crate) fn camera_rows(camera: &Camera) -> [vpl_core::glam::Vec4; 5] {
    let (f, right, up, sx, sy) = camera.raster_basis();
    let (w, h) = camera.resolution;
    [
        camera.origin.extend(0.0),
        f.extend(sx),
        right.extend(sy),
        up.extend(camera.focus_distance),
        vpl_core::glam::Vec4::new(w as f32, h as f32, camera.lens_radius.max(0.0), 0.0),
    ]
}
