//! Errors of building and running a renderer.

use vpl_core::CoreError;
use vpl_sampling::SamplingError;

/// Errors of [`crate::Renderer`], its builder, backends and sequences.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// A scene, camera, image or file problem.
    #[error(transparent)]
    Core(#[from] CoreError),
    /// The sampler could not be built.
    #[error(transparent)]
    Sampling(#[from] SamplingError),
    /// A setting of the renderer is invalid (names the setting).
    #[error("{0}")]
    Invalid(String),
    /// The backend failed or cannot hold what is asked of it.
    #[error("{backend} backend: {message}")]
    Backend {
        /// The backend's name (`gpu`).
        backend: String,
        /// What went wrong.
        message: String,
    },
    /// A frame range that does not fit the scene's sequence.
    #[error("frames {start}..{end} does not fit the sequence of {count} frames")]
    Frames {
        /// First frame asked for.
        start: u32,
        /// One past the last.
        end: u32,
        /// Frames in the sequence.
        count: u32,
    },
    /// A stage produced NaN or infinite values (a scene value the load-time
    /// checks let through, or a defect): the frame is refused, not shown.
    #[error("frame {frame}: {stage} produced {count} non-finite value(s)")]
    NonFinite {
        /// The first stage that did.
        stage: &'static str,
        /// How many VPLs or pixels.
        count: usize,
        /// The frame index.
        frame: u64,
    },
    /// The frame was cancelled at a stage boundary
    /// ([`crate::Renderer::render_cancellable`]).
    #[error("frame {frame} was cancelled")]
    Cancelled {
        /// The frame index.
        frame: u64,
    },
    /// A tracked pixel lies outside the image.
    #[error("tracked pixel {0},{1} is outside the {2}x{3} image")]
    Pixel(u32, u32, u32, u32),
}

impl RenderError {
    /// A failure of backend `backend`.
    pub fn backend(backend: &str, message: impl std::fmt::Display) -> RenderError {
        RenderError::Backend { backend: backend.into(), message: message.to_string() }
    }
}
