//! The typed error of every fallible operation in `vpl-core`.

use std::path::PathBuf;

/// Errors from building scenes, cameras and images, and from writing
/// files; reading files has its own (`vpl_scene_io::SceneIoError`).
///
/// Each variant's message is one readable line that names the problem, so a
/// binary can print it as is.
#[derive(Debug, thiserror::Error)]
pub enum CoreError {
    /// A file could not be written (directory missing, permission denied, …).
    #[error("cannot write {path}: {reason}")]
    Write {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// A scene value is non-finite or outside what the renderers can hold
    /// (see [`crate::validate`]).
    #[error("{what}: {reason}")]
    BadValue {
        /// The file, material or light, and the parameter.
        what: String,
        /// What is wrong with the value, quoting it.
        reason: String,
    },
    /// A scene file (TOML) could not be parsed or is inconsistent.
    #[error("bad scene file {path}: {reason}")]
    SceneFile {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the key where there is one.
        reason: String,
    },
    /// Geometry holds a NaN or infinite coordinate.
    #[error("non-finite vertex {index} ({value}) in {what}")]
    NonFinite {
        /// Where the geometry came from.
        what: String,
        /// The offending vertex index (0-based).
        index: usize,
        /// The value as text.
        value: String,
    },
    /// The scene has no (non-degenerate) triangles.
    #[error("the scene {0} is empty: it has no triangles with nonzero area")]
    EmptyScene(String),
    /// The scene has no light source (no emissive triangle, point, spot or sun).
    #[error("the scene {0} has no lights: add an emissive material (Ke) or a [[lights]] entry")]
    NoLights(String),
    /// A camera parameter is out of range.
    #[error("bad camera: {0}")]
    Camera(String),
    /// An image has the wrong size, or a file is no image this crate can read.
    #[error("bad image: {0}")]
    Image(String),
    /// A named built-in scene does not exist.
    #[error("unknown built-in scene '{0}' (known: cornell, maze, office, courtyard, atrium, corner, glass, building, colonnade)")]
    UnknownBuiltin(String),
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    Invalid(String),
}

/// Shorthand for `Result<T, CoreError>`.
pub type Result<T> = std::result::Result<T, CoreError>;
