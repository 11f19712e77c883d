//! The harness's description of a VPL renderer (sampler by name, its
//! parameters, budget, stages, backend), which experiments store and
//! compare, built into a [`vpl_render::Renderer`].

use vpl_core::{Budget, Mode, Params, Scene};
use vpl_render::{Clamp, RenderError, Renderer};
use vpl_sampling::Registry;

pub use vpl_render::{ShadingSpec, VisibilitySpec};

/// Where the G-buffer, visibility and shading run, by name (what
/// experiment specs record).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BackendKind {
    /// The CPU stages (rayon).
    #[default]
    Cpu,
    /// The wgpu kernels of `vpl-gpu` (feature `gpu`): G-buffer, shadow maps
    /// or shadow rays, interleaved or exhaustive shading, filter, and the
    /// rays and radiosity estimates of samplers that take them (SMC). The
    /// rest of sampling and the direct light stay on the CPU.
    Gpu,
}

impl BackendKind {
    /// The backend itself (on the GPU: the first adapter found).
    pub fn instantiate(self) -> Result<Box<dyn vpl_render::Backend>, RenderError> {
        match self {
            BackendKind::Cpu => Ok(Box::new(vpl_render::CpuBackend)),
            BackendKind::Gpu => gpu(),
        }
    }
}

#[cfg(feature = "gpu")]
fn gpu() -> Result<Box<dyn vpl_render::Backend>, RenderError> {
    Ok(Box::new(vpl_gpu::backend().map_err(|e| RenderError::backend("gpu", e))?))
}

#[cfg(not(feature = "gpu"))]
fn gpu() -> Result<Box<dyn vpl_render::Backend>, RenderError> {
    Err(RenderError::backend("gpu", "this build has no GPU backend (build vpl-bench with its default feature `gpu`)"))
}

/// Everything that names a VPL renderer.
#[derive(Clone, Debug)]
pub struct PipelineSpec {
    /// Sampler name in the registry.
    pub sampler: String,
    /// Its parameters (keys given must be read; offered ones may not be).
    pub params: Params,
    /// VPL slots and path depth.
    pub budget: Budget,
    /// Visibility.
    pub visibility: VisibilitySpec,
    /// Shading.
    pub shading: ShadingSpec,
    /// Geometry-term clamp: a value, or a rule the renderer resolves (the
    /// view rule follows the camera).
    pub clamp: Clamp,
    /// Gather rays per pixel of the clamp's bias compensation (0: none).
    pub compensation: u32,
    /// Which paths the frames include.
    pub mode: Mode,
    /// Light samples per pixel of direct light.
    pub direct_samples: u32,
    /// Seed of all streams.
    pub seed: u64,
    /// Where the stages run.
    pub backend: BackendKind,
}

impl PipelineSpec {
    /// The renderer of this spec for frames of `scene`, its sampler from `registry`.
    pub fn build(&self, registry: &Registry, scene: &Scene) -> Result<Renderer, RenderError> {
        Renderer::builder(scene)
            .registry(registry)
            .budget(self.budget)
            .sampler(self.sampler.as_str())
            .params(self.params.clone())
            .visibility(self.visibility)
            .shader(self.shading)
            .clamp(self.clamp)
            .compensation(self.compensation)
            .mode(self.mode)
            .direct_samples(self.direct_samples)
            .seed(self.seed)
            .boxed_backend(self.backend.instantiate()?)
            .build()
    }
}

/// A renderer error in one line, a backend's as `--backend NAME: …` (the
/// flag that chose it).
pub fn backend_line(e: RenderError) -> String {
    backend_message(&e)
}

/// [`backend_line`] of a borrowed error.
pub fn backend_message(e: &RenderError) -> String {
    match e {
        RenderError::Backend { backend, message } => format!("--backend {backend}: {message}"),
        e => e.to_string(),
    }
}
