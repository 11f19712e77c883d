//! The viewer's errors.

use std::path::PathBuf;

/// Why the viewer could not start or stopped.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    /// The scene, or an image the session reads, could not be loaded.
    #[error(transparent)]
    Scene(#[from] vpl_scene_io::SceneIoError),
    /// A scene, camera or image value the core refused, or a file it could
    /// not write.
    #[error(transparent)]
    Core(#[from] vpl_core::CoreError),
    /// The pipeline's sampler refused its parameters (a key it does not
    /// read, a value out of range).
    #[error("{source}")]
    Sampler {
        /// The sampler's name.
        name: String,
        /// What the registry said.
        #[source]
        source: Box<vpl_sampling::SamplingError>,
    },
    /// A sampler name the registry does not hold.
    #[error("unknown sampler `{name}` (the registry holds {known})")]
    UnknownSampler {
        /// The name asked for.
        name: String,
        /// The names it holds, comma-separated.
        known: String,
    },
    /// No display to open a window on (no X server or Wayland compositor).
    #[error("no display to open a window on ({0}); run under X11 or Wayland, or under Xvfb (xvfb-run vpl view …)")]
    NoDisplay(String),
    /// No graphics adapter can present to the window.
    #[error("no graphics adapter can draw the window ({0}); install a Vulkan or GL driver (mesa-vulkan-drivers gives lavapipe)")]
    NoAdapter(String),
    /// The window's surface failed.
    #[error("the window's surface failed: {0}")]
    Surface(String),
    /// The backend asked for is not in this build, or did not open.
    #[error("{0}")]
    Backend(String),
    /// A frame failed in a scripted session (interactively it is shown on screen).
    #[error("rendering failed: {0}")]
    Render(String),
    /// An option out of its range.
    #[error("{0}")]
    Invalid(String),
    /// A script line is wrong.
    #[error(transparent)]
    Script(#[from] crate::script::ScriptError),
    /// A screenshot or other file could not be written.
    #[error("cannot write {path}: {reason}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}
