//! Radiosity estimates on the device: twin of
//! [`vpl_pathtrace::PathRadiosity`] (the SMC sampler's 16 NEE paths per VPL).

use crate::context::GpuError;
use crate::device::Gpu;
use crate::kernel::{Binding, SAMPLING_WGSL, bind, dispatch, finish_read, groups_1d, layout, pipeline, storage, storage_init, uniform};
use crate::scene::{BVH_WGSL, scene_layout};
use std::sync::{Arc, OnceLock};
use vpl_core::glam::{Vec3, Vec4};
use vpl_core::rng::stream_key;
use vpl_core::{Light, Purpose, RadiosityEstimator, Scene, SurfacePoint};
use vpl_pathtrace::PathRadiosity;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Params {
    pub(crate) jobs: u32,
    pub(crate) paths: u32,
    pub(crate) max_k: u32,
    pub(crate) rr_depth: u32,
    pub(crate) lights: u32,
    pub(crate) two_sided: u32,
    pub(crate) eps: f32,
    pub(crate) row: u32,
    /// Index of the environment light, `u32::MAX` without one.
    pub(crate) env: u32,
    /// `row` of the `sum` dispatch.
    pub(crate) sum_row: u32,
    /// Fewest scattering vertices a counted path has (1 for radiosity).
    pub(crate) min_k: u32,
    /// The clamp's G_max of the segment leaving the first vertex, negative
    /// for none.
    pub(crate) g_max: f32,
    /// `track`: the first chunk of a dispatch, and chunks per pixel.
    pub(crate) first: u32,
    pub(crate) chunks: u32,
    /// `track_sum`: chunks a block adds (a power of two, at most 64).
    pub(crate) block: u32,
    pub(crate) pad: u32,
}

/// The WGSL of the radiosity kernels and of what reads lights as they do
/// (the direct light, `direct.wgsl`).
pub(crate) fn radiosity_source() -> String {
    format!("{BVH_WGSL}\n{SAMPLING_WGSL}\n{}\n{}", include_str!("radiosity.wgsl"), include_str!("direct.wgsl"))
}

/// Vertices from which the CPU path tracer plays Russian roulette.
const RR_DEPTH: u32 = 5;

/// [`PathRadiosity`] as a WGSL kernel: one invocation a (point, path), the
/// same walk (next-event estimation with MIS, cosine-sampled bounces), and
/// the same PCG32 stream per path as the CPU (`stream(seed, 0, RADIOSITY,
/// path)`, derived on the device from one key a point and run on 32-bit
/// words), so an estimate differs from the CPU's only by float rounding and
/// by rays that graze an edge. Batches come through
/// [`RadiosityEstimator::radiosity_many`].
///
/// A batch crosses as 56 B a point up (its surface point and stream key) and
/// 16 B a point down (the sum of its paths, added on the device in path
/// order as the CPU adds them), in one submission; the lights stay on the
/// device until the scene's lights change.
pub struct GpuRadiosity {
    gpu: Gpu,
    /// Paths and bounces, shared with the CPU twin.
    pub config: PathRadiosity,
    kernel: OnceLock<Kernels>,
}

/// The path kernel (one invocation a point and path) and the sum (one a
/// point), over the radiosity layout: the parameters, the jobs, their
/// stream keys, the lights (three buffers), the light of each triangle,
/// each path's light and each point's sum.
pub(crate) struct Kernels {
    pub(crate) layout: wgpu::BindGroupLayout,
    pub(crate) paths: wgpu::ComputePipeline,
    pub(crate) sum: wgpu::ComputePipeline,
}

impl Kernels {
    pub(crate) fn new(ctx: &crate::GpuContext) -> Kernels {
        let layout = radiosity_layout(ctx);
        let source = radiosity_source();
        let paths = pipeline(ctx, "radiosity", &source, "main", &[&scene_layout(ctx), &layout]);
        let sum = pipeline(ctx, "radiosity sum", &source, "sum", &[&scene_layout(ctx), &layout]);
        Kernels { layout, paths, sum }
    }
}

/// The radiosity layout: the parameters, the jobs, their stream keys, the
/// lights (three buffers), the light of each triangle, and two outputs.
pub(crate) fn radiosity_layout(ctx: &crate::GpuContext) -> wgpu::BindGroupLayout {
    let (r, w) = (Binding::Read, Binding::ReadWrite);
    layout(ctx, "radiosity", &[Binding::Uniform, r, r, r, r, r, r, w, w])
}

/// The parameters of a batch of `jobs` points, `config`'s paths each, and
/// the dispatch shapes of its path and sum kernels.
pub(crate) fn path_params(
    ctx: &crate::GpuContext,
    scene: &Scene,
    config: PathRadiosity,
    jobs: usize,
) -> (Params, (u32, u32, u32), (u32, u32, u32)) {
    let groups = groups_1d(ctx, jobs as u64 * config.paths as u64, 64);
    let sum_groups = groups_1d(ctx, jobs as u64, 64);
    let params = Params {
        jobs: jobs as u32,
        paths: config.paths,
        max_k: 1 + config.max_bounces,
        rr_depth: RR_DEPTH,
        row: groups.0 * 64,
        sum_row: sum_groups.0 * 64,
        ..light_params(scene)
    };
    (params, groups, sum_groups)
}

/// A scene's lights as the kernels read them (`radiosity.wgsl`), with the
/// host rows they were made from: uploaded once a device and kept until
/// the lights change ([`Gpu::lights`]).
pub(crate) struct LightBuffers {
    rows: (Vec<Vec4>, Vec<f32>, Vec<f32>, Vec<u32>),
    pub(crate) lights: wgpu::Buffer,
    pub(crate) cdf: wgpu::Buffer,
    pub(crate) pmf: wgpu::Buffer,
    pub(crate) tri_light: wgpu::Buffer,
}

impl LightBuffers {
    /// Whether these are `scene`'s lights (compared in place: only an
    /// upload copies the rows).
    fn hold(&self, scene: &Scene, rows: &[Vec4]) -> bool {
        let d = &scene.light_distribution;
        self.rows.0 == rows && self.rows.1 == d.cdf() && self.rows.2 == d.pmfs() && self.rows.3 == scene.tri_light
    }
}

impl Gpu {
    /// The lights of `scene` on the device: the upload kept from an earlier
    /// call while the lights are the same, else a new one.
    pub(crate) fn lights(&self, scene: &Scene) -> Arc<LightBuffers> {
        let ctx = self.ctx();
        let rows = light_rows(scene);
        let mut cached = self.light_cache().lock().expect("light buffers lock");
        if let Some(c) = cached.as_ref().filter(|c| c.hold(scene, &rows)) {
            return c.clone();
        }
        let (cdf, pmf) = (scene.light_distribution.cdf(), scene.light_distribution.pmfs());
        let made = Arc::new(LightBuffers {
            lights: storage_init(ctx, "lights", &rows),
            cdf: storage_init(ctx, "light cdf", cdf),
            pmf: storage_init(ctx, "light pmf", pmf),
            tri_light: storage_init(ctx, "tri light", &scene.tri_light),
            rows: (rows, cdf.to_vec(), pmf.to_vec(), scene.tri_light.clone()),
        });
        *cached = Some(made.clone());
        made
    }
}

/// The `Params` of `radiosity.wgsl` that its light functions read, for a
/// scene (the path fields zero).
pub(crate) fn light_params(scene: &Scene) -> Params {
    Params {
        jobs: 0,
        paths: 0,
        max_k: 0,
        rr_depth: 0,
        lights: scene.lights.len() as u32,
        two_sided: scene.two_sided as u32,
        eps: scene.epsilon(),
        row: 0,
        env: scene.environment.map_or(u32::MAX, |i| i as u32),
        sum_row: 0,
        min_k: 1,
        g_max: -1.0,
        first: 0,
        chunks: 0,
        block: 0,
        pad: 0,
    }
}

/// The lights of `scene` as the kernel reads them: four rows a light.
fn light_rows(scene: &Scene) -> Vec<Vec4> {
    scene
        .lights
        .iter()
        .flat_map(|l| {
            let head = |kind: u32, tri: u32, cos_total: f32| Vec4::new(f32::from_bits(kind), f32::from_bits(tri), cos_total, 0.0);
            match *l {
                Light::Area { triangle, radiance } => [head(0, triangle, 0.0), Vec4::ZERO, radiance.extend(0.0), Vec4::ZERO],
                Light::Point { position, intensity } => [head(1, 0, 0.0), position.extend(0.0), intensity.extend(0.0), Vec4::ZERO],
                Light::Spot { position, direction, intensity, cos_falloff_start, cos_total } => {
                    [head(2, 0, cos_total), position.extend(0.0), intensity.extend(0.0), direction.extend(cos_falloff_start)]
                }
                Light::Directional { direction, irradiance } => {
                    [head(3, 0, 0.0), direction.extend(0.0), irradiance.extend(0.0), Vec4::ZERO]
                }
                Light::Environment { sky } => [head(4, 0, 0.0), sky.zenith.extend(0.0), sky.horizon.extend(0.0), sky.nadir.extend(0.0)],
            }
        })
        .collect()
}

impl GpuRadiosity {
    /// An estimator on `gpu` with `config`'s paths and bounces.
    pub fn new(gpu: Gpu, config: PathRadiosity) -> GpuRadiosity {
        GpuRadiosity { gpu, config, kernel: OnceLock::new() }
    }

    /// L(y) of every (point, seed) pair.
    pub fn estimate(&self, scene: &Scene, points: &[(SurfacePoint, u64)]) -> Result<Vec<Vec3>, GpuError> {
        let paths = self.config.paths;
        if points.is_empty() || paths == 0 {
            return Ok(vec![Vec3::ZERO; points.len()]);
        }
        let ctx = self.gpu.ctx();
        let gs = self.gpu.scene(scene)?;
        let k = self.kernel.get_or_init(|| Kernels::new(ctx));
        let jobs: Vec<Vec4> =
            points.iter().flat_map(|(y, _)| [y.p.extend(f32::from_bits(y.material)), y.n.extend(0.0), y.ng.extend(0.0)]).collect();
        let keys: Vec<[u32; 2]> = points
            .iter()
            .map(|(_, seed)| {
                let key = stream_key(*seed, 0, Purpose::RADIOSITY);
                [key as u32, (key >> 32) as u32]
            })
            .collect();
        let lb = self.gpu.lights(scene);
        let n = points.len() as u64 * paths as u64;
        let (params, groups, sum_groups) = path_params(ctx, scene, self.config, points.len());
        let b_params = uniform(ctx, "radiosity params", &params);
        let b_jobs = storage_init(ctx, "radiosity jobs", &jobs);
        let b_keys = storage_init(ctx, "radiosity keys", &keys);
        let b_out = storage(ctx, "radiosity paths", n * 16)?;
        let b_sum = storage(ctx, "radiosity sums", points.len() as u64 * 16)?;
        let group =
            bind(ctx, "radiosity", &k.layout, &[&b_params, &b_jobs, &b_keys, &lb.lights, &lb.cdf, &lb.pmf, &lb.tri_light, &b_out, &b_sum]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, &k.paths, &[&gs.group, &group], groups);
        dispatch(&mut enc, &k.sum, &[&gs.group, &group], sum_groups);
        let sums: Vec<Vec4> = finish_read(ctx, enc, &b_sum, points.len())?;
        Ok(sums.into_iter().map(|s| s.truncate() / paths as f32).collect())
    }
}

impl RadiosityEstimator for GpuRadiosity {
    /// # Panics
    /// When the device fails.
    fn radiosity(&self, scene: &Scene, y: &SurfacePoint, seed: u64) -> Vec3 {
        self.radiosity_many(scene, &[(*y, seed)])[0]
    }

    /// # Panics
    /// When the device fails.
    fn radiosity_many(&self, scene: &Scene, points: &[(SurfacePoint, u64)]) -> Vec<Vec3> {
        self.estimate(scene, points).unwrap_or_else(|e| panic!("GPU radiosity: {e}"))
    }
}
