//! The harness's backends by name, and the description of a renderer
//! ([`PipelineSpec`], vpl-render's) it builds with them.

use vpl_render::RenderError;

pub use vpl_render::{PipelineSpec, ShadingSpec, VisibilitySpec};

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
    /// Its name in [`backends`] (and in experiment specs).
    pub fn name(self) -> &'static str {
        match self {
            BackendKind::Cpu => "cpu",
            BackendKind::Gpu => "gpu",
        }
    }

    /// The backend itself, by name from [`backends`] (on the GPU: the
    /// first adapter found).
    pub fn instantiate(self) -> Result<Box<dyn vpl_render::Backend>, RenderError> {
        backends().instantiate(self.name())
    }
}

/// The backends of this build: the CPU, and the GPU (`vpl_gpu::register`)
/// with the default feature `gpu`.
pub fn backends() -> vpl_render::Backends {
    let mut b = vpl_render::Backends::builtin();
    #[cfg(feature = "gpu")]
    vpl_gpu::register(&mut b);
    #[cfg(not(feature = "gpu"))]
    b.absent("gpu", "build vpl-bench with its default feature `gpu`");
    b
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
