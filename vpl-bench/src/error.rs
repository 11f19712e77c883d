//! What the experiments (Georgiev's figures, Table 2, the GPU benchmark) can fail with.

use vpl_core::CoreError;
use vpl_render::RenderError;

/// An experiment's error.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A scene, camera or image error.
    #[error(transparent)]
    Core(#[from] CoreError),
    /// A scene or image file could not be read.
    #[error(transparent)]
    SceneIo(#[from] vpl_scene_io::SceneIoError),
    /// The renderer (a sampler, a backend, a frame) refused or failed; a
    /// backend's error names the flag that chose it (`--backend gpu: …`).
    #[error("{}", crate::pipeline::backend_message(.0))]
    Render(#[from] RenderError),
    /// The SMC sampler refused its settings.
    #[error(transparent)]
    Smc(#[from] vpl_sampling::SmcError),
    /// Shadow maps refused their resolution.
    #[error(transparent)]
    ShadowMaps(#[from] vpl_visibility::ShadowMapError),
    /// A GPU stage failed.
    #[cfg(feature = "gpu")]
    #[error(transparent)]
    Gpu(#[from] vpl_gpu::GpuError),
}
