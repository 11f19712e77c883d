//! Radiosity estimates on the device: twin of
//! [`vpl_pathtrace::PathRadiosity`] (the SMC sampler's 16 NEE paths per VPL).

use crate::context::GpuError;
use crate::device::Gpu;
use crate::kernel::{Binding, bind, dispatch, finish, groups_1d, layout, pipeline, read_back, storage, storage_init, uniform};
use crate::scene::{BVH_WGSL, scene_layout};
use std::sync::OnceLock;
use vpl_core::glam::{Vec3, Vec4};
use vpl_core::rng::stream_state;
use vpl_core::{Light, Purpose, RadiosityEstimator, Scene, SurfacePoint};
use vpl_pathtrace::PathRadiosity;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    jobs: u32,
    paths: u32,
    max_k: u32,
    rr_depth: u32,
    lights: u32,
    two_sided: u32,
    eps: f32,
    row: u32,
    /// Index of the environment light, `u32::MAX` without one.
    env: u32,
    pad: [u32; 3],
}

/// Vertices from which the CPU path tracer plays Russian roulette.
const RR_DEPTH: u32 = 5;

/// [`PathRadiosity`] as a WGSL kernel: one invocation a (point, path), the
/// same walk (next-event estimation with MIS, cosine-sampled bounces), and
/// the same PCG32 stream per path as the CPU (`stream(seed, 0, RADIOSITY,
/// path)`, run on 32-bit words), so an estimate differs from the CPU's only
/// by float rounding and by rays that graze an edge. Batches come through
/// [`RadiosityEstimator::radiosity_many`].
pub struct GpuRadiosity {
    gpu: Gpu,
    /// Paths and bounces, shared with the CPU twin.
    pub config: PathRadiosity,
    kernel: OnceLock<(wgpu::BindGroupLayout, wgpu::ComputePipeline)>,
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
        let (layout, pipeline) = self.kernel.get_or_init(|| {
            let r = Binding::Read;
            let l = layout(ctx, "radiosity", &[Binding::Uniform, r, r, r, r, r, r, Binding::ReadWrite]);
            let source = format!("{BVH_WGSL}\n{}", include_str!("radiosity.wgsl"));
            let p = pipeline(ctx, "radiosity", &source, "main", &[&scene_layout(ctx), &l]);
            (l, p)
        });
        let jobs: Vec<Vec4> =
            points.iter().flat_map(|(y, _)| [y.p.extend(f32::from_bits(y.material)), y.n.extend(0.0), y.ng.extend(0.0)]).collect();
        let rng: Vec<[u32; 4]> = points
            .iter()
            .flat_map(|(_, seed)| {
                (0..paths).map(move |i| {
                    let (s, inc) = stream_state(*seed, 0, Purpose::RADIOSITY, i as u64);
                    [s as u32, (s >> 32) as u32, inc as u32, (inc >> 32) as u32]
                })
            })
            .collect();
        let lights: Vec<Vec4> = scene
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
            .collect();
        let n = points.len() as u64 * paths as u64;
        let groups = groups_1d(ctx, n, 64);
        let params = Params {
            jobs: points.len() as u32,
            paths,
            max_k: 1 + self.config.max_bounces,
            rr_depth: RR_DEPTH,
            lights: scene.lights.len() as u32,
            two_sided: scene.two_sided as u32,
            eps: scene.epsilon(),
            row: groups.0 * 64,
            env: scene.environment.map_or(u32::MAX, |i| i as u32),
            pad: [0; 3],
        };
        let b_params = uniform(ctx, "radiosity params", &params);
        let b_jobs = storage_init(ctx, "radiosity jobs", &jobs);
        let b_rng = storage_init(ctx, "radiosity rng", &rng);
        let b_lights = storage_init(ctx, "lights", &lights);
        let b_cdf = storage_init(ctx, "light cdf", scene.light_distribution.cdf());
        let b_pmf = storage_init(ctx, "light pmf", scene.light_distribution.pmfs());
        let b_tri_light = storage_init(ctx, "tri light", &scene.tri_light);
        let b_out = storage(ctx, "radiosity out", n * 16)?;
        let group = bind(ctx, "radiosity", layout, &[&b_params, &b_jobs, &b_rng, &b_lights, &b_cdf, &b_pmf, &b_tri_light, &b_out]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, pipeline, &[&gs.group, &group], groups);
        finish(ctx, enc)?;
        let out: Vec<Vec4> = read_back(ctx, &b_out, n as usize)?;
        // Summed in path order, as the CPU twin sums.
        Ok(out
            .chunks(paths as usize)
            .map(|c| {
                let mut sum = Vec3::ZERO;
                for v in c {
                    sum += v.truncate();
                }
                sum / paths as f32
            })
            .collect())
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
