//! A VPL renderer assembled from names and settings: sampler, visibility,
//! shader. What `vpl render --method vpl` and `vpl sequence` run.

use vpl_core::{Camera, GBuffer, GeometryClamp, Image, IndirectShader, Mode, Scene, VplSampler, VplVisibility};
use vpl_sampling::SamplerConfig;
use vpl_shading::{ExhaustiveShader, FrameOutput, FrameSettings, InterleavedShader};
use vpl_visibility::{RayTraced, ShadowMaps};

/// VPL-to-pixel visibility.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VisibilitySpec {
    /// Exact BVH shadow rays.
    RayTraced,
    /// Paraboloid shadow maps of this side in texels.
    ShadowMaps(u32),
}

/// Indirect shading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingSpec {
    /// 4×4 interleaved subsets, with or without the cross-bilateral filter.
    Interleaved {
        /// Whether to filter.
        filter: bool,
    },
    /// Every VPL at every pixel.
    Exhaustive,
}

/// Where the G-buffer, visibility and shading run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// The CPU stages (rayon).
    #[default]
    Cpu,
    /// The wgpu kernels of `vpl-gpu` (feature `gpu`): G-buffer, shadow maps
    /// or shadow rays, interleaved or exhaustive shading, filter, and the
    /// rays and radiosity estimates of samplers that take them (SMC). The
    /// rest of sampling and the direct light stay on the CPU.
    Gpu,
}

/// Everything that names a VPL renderer.
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineSpec {
    /// Sampler name in the `vpl-sampling` registry.
    pub sampler: String,
    /// Its settings (budget, depth, …).
    pub config: SamplerConfig,
    /// Visibility.
    pub visibility: VisibilitySpec,
    /// Shading.
    pub shading: ShadingSpec,
    /// Geometry-term clamp.
    pub clamp: Option<GeometryClamp>,
    /// Which paths the frames include.
    pub mode: Mode,
    /// Light samples per pixel of direct light.
    pub direct_samples: u32,
    /// Seed of all streams.
    pub seed: u64,
    /// Where the stages run.
    pub backend: Backend,
}

/// The G-buffer stage of a backend.
pub struct GBufferStage {
    #[cfg(feature = "gpu")]
    gpu: Option<vpl_gpu::Gpu>,
}

impl GBufferStage {
    /// The CPU stage.
    pub fn cpu() -> GBufferStage {
        GBufferStage {
            #[cfg(feature = "gpu")]
            gpu: None,
        }
    }

    /// The stage on `gpu`.
    #[cfg(feature = "gpu")]
    pub fn on(gpu: vpl_gpu::Gpu) -> GBufferStage {
        GBufferStage { gpu: Some(gpu) }
    }

    /// The G-buffer of `scene` seen by `camera`.
    ///
    /// # Panics
    /// On the GPU backend, when the device fails.
    pub fn render(&self, scene: &Scene, camera: &Camera) -> GBuffer {
        #[cfg(feature = "gpu")]
        if let Some(gpu) = &self.gpu {
            return gpu.render_gbuffer(scene, camera).unwrap_or_else(|e| panic!("GPU G-buffer: {e}"));
        }
        vpl_shading::render_gbuffer(scene, camera)
    }

    /// The adapter of the GPU backend, in words (`None` on the CPU).
    pub fn adapter(&self) -> Option<String> {
        #[cfg(feature = "gpu")]
        if let Some(g) = &self.gpu {
            return Some(g.ctx().describe());
        }
        None
    }

    /// Whether images of `size` fit the backend: on the GPU, each per-pixel
    /// buffer (16 bytes a pixel) must fit the adapter's storage-buffer limit.
    /// Says in one line what does not.
    pub fn fits(&self, size: (u32, u32)) -> Result<(), String> {
        #[cfg(feature = "gpu")]
        if let Some(g) = &self.gpu {
            let bytes = size.0 as u64 * size.1 as u64 * 16;
            let limit = g.ctx().device.limits().max_storage_buffer_binding_size as u64;
            if bytes > limit {
                return Err(format!("--backend gpu: {}x{} needs {} MiB per image buffer, over the adapter's {} MiB", size.0, size.1, bytes >> 20, limit >> 20));
            }
        }
        let _ = size;
        Ok(())
    }

    /// Gives `sampler` this backend's ray caster and radiosity estimator
    /// (on the GPU backend: `GpuRays` and `GpuRadiosity`; on the CPU,
    /// nothing changes).
    pub fn equip(&self, sampler: &mut dyn VplSampler) {
        #[cfg(feature = "gpu")]
        if let Some(g) = &self.gpu {
            sampler.set_ray_caster(std::sync::Arc::new(vpl_gpu::GpuRays::new(g.clone())));
            let g = g.clone();
            sampler.set_radiosity_estimator(&move |paths, max_bounces| {
                Box::new(vpl_gpu::GpuRadiosity::new(g.clone(), vpl_pathtrace::PathRadiosity { paths, max_bounces }))
            });
        }
        let _ = sampler;
    }
}

/// The stages after sampling, built for a backend: G-buffer, visibility
/// and shading.
pub struct Stages {
    /// The G-buffer.
    pub gbuffer: GBufferStage,
    /// Visibility.
    pub visibility: Box<dyn VplVisibility>,
    /// Indirect shading.
    pub shader: Box<dyn IndirectShader>,
}

impl Stages {
    /// Builds the stages of `backend` for sets of up to `vpls` slots, or
    /// says in one line what is wrong.
    pub fn new(backend: Backend, visibility: VisibilitySpec, shading: ShadingSpec, clamp: Option<GeometryClamp>, seed: u64, vpls: usize) -> Result<Stages, String> {
        if backend == Backend::Gpu {
            return Self::gpu(visibility, shading, clamp, seed, vpls);
        }
        let visibility: Box<dyn VplVisibility> = match visibility {
            VisibilitySpec::RayTraced => Box::new(RayTraced::default()),
            VisibilitySpec::ShadowMaps(res) => Box::new(ShadowMaps::new(res).map_err(|e| format!("shadow maps: {e}"))?),
        };
        let shader: Box<dyn IndirectShader> = match shading {
            ShadingSpec::Exhaustive => Box::new(ExhaustiveShader { clamp }),
            ShadingSpec::Interleaved { filter } => {
                let mut s = InterleavedShader::new(clamp, seed);
                if !filter {
                    s.filter = None;
                }
                Box::new(s)
            }
        };
        Ok(Stages { gbuffer: GBufferStage::cpu(), visibility, shader })
    }

    #[cfg(not(feature = "gpu"))]
    fn gpu(_: VisibilitySpec, _: ShadingSpec, _: Option<GeometryClamp>, _: u64, _: usize) -> Result<Stages, String> {
        Err("--backend gpu: this build has no GPU backend (build vpl-bench with its default feature `gpu`)".into())
    }

    #[cfg(feature = "gpu")]
    fn gpu(visibility: VisibilitySpec, shading: ShadingSpec, clamp: Option<GeometryClamp>, seed: u64, vpls: usize) -> Result<Stages, String> {
        let gpu = vpl_gpu::Gpu::new().map_err(|e| format!("--backend gpu: {e}"))?;
        let visibility: Box<dyn VplVisibility> = match visibility {
            VisibilitySpec::RayTraced => Box::new(vpl_gpu::GpuRayTraced::new(gpu.clone())),
            VisibilitySpec::ShadowMaps(res) => {
                let bytes = vpl_gpu::GpuShadowMaps::atlas_bytes(res, vpls);
                let limit = gpu.ctx().device.limits().max_storage_buffer_binding_size as u64;
                if bytes > limit {
                    return Err(format!("--backend gpu: {vpls} shadow maps of {res}² texels need {} MiB, over the adapter's {} MiB per buffer", bytes >> 20, limit >> 20));
                }
                Box::new(vpl_gpu::GpuShadowMaps::new(gpu.clone(), res).map_err(|e| format!("shadow maps: {e}"))?)
            }
        };
        let shader: Box<dyn IndirectShader> = match shading {
            ShadingSpec::Exhaustive => Box::new(vpl_gpu::GpuInterleavedShader::exhaustive(gpu.clone(), clamp)),
            ShadingSpec::Interleaved { filter } => {
                let mut s = vpl_gpu::GpuInterleavedShader::new(gpu.clone(), clamp, seed);
                if !filter {
                    s.cpu.filter = None;
                }
                Box::new(s)
            }
        };
        Ok(Stages { gbuffer: GBufferStage::on(gpu), visibility, shader })
    }
}

/// A built VPL renderer; samplers and shadow maps keep their state from
/// frame to frame.
pub struct Pipeline {
    /// What it was built from.
    pub spec: PipelineSpec,
    /// The sampler.
    pub sampler: Box<dyn VplSampler>,
    /// The G-buffer stage.
    pub gbuffer: GBufferStage,
    /// The visibility structure.
    pub visibility: Box<dyn VplVisibility>,
    /// The shader.
    pub shader: Box<dyn IndirectShader>,
    /// The indirect image of the last frame, which the next frame's sampler reads.
    pub previous: Option<Image>,
}

impl Pipeline {
    /// Builds the pipeline, or says in one line what is wrong with the spec.
    pub fn new(spec: PipelineSpec) -> Result<Pipeline, String> {
        if spec.direct_samples == 0 {
            return Err("direct light needs at least 1 sample per pixel".into());
        }
        let mut sampler = vpl_sampling::build(&spec.sampler, &spec.config).map_err(|e| e.to_string())?;
        let Stages { gbuffer, visibility, shader } = Stages::new(spec.backend, spec.visibility, spec.shading, spec.clamp, spec.seed, spec.config.vpls)?;
        gbuffer.equip(sampler.as_mut());
        Ok(Pipeline { spec, sampler, gbuffer, visibility, shader, previous: None })
    }

    /// The adapter of the GPU backend, in words (`None` on the CPU backend).
    pub fn adapter(&self) -> Option<String> {
        self.gbuffer.adapter()
    }

    /// Renders frame `index` (at `time` seconds) of `scene` seen by `camera`.
    pub fn render(&mut self, scene: &Scene, camera: &Camera, index: u64, time: f32) -> FrameOutput {
        let settings = FrameSettings {
            mode: self.spec.mode,
            max_depth: self.spec.config.max_depth,
            direct_samples: self.spec.direct_samples,
            seed: self.spec.seed,
            index,
            time,
        };
        let t0 = std::time::Instant::now();
        let gbuffer = self.gbuffer.render(scene, camera);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let out = vpl_shading::render_frame_on(gbuffer, ms, scene, camera, settings, self.previous.as_ref(), self.sampler.as_mut(), self.visibility.as_mut(), self.shader.as_mut());
        self.previous = out.indirect.clone();
        out
    }
}
