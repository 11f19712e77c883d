//! The typed error of every fallible operation in `vpl-core`.

use std::path::PathBuf;

/// Errors from loading, building and writing scenes and images.
///
/// Each variant's message is one readable line that names the problem, so a
/// binary can print it as is.
#[derive(Debug, thiserror::Error)]
pub enum CoreError {
    /// A file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A file could not be written (directory missing, permission denied, …).
    #[error("cannot write {path}: {reason}")]
    Write {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// A path names something other than a regular file (a device, a pipe, a directory).
    #[error("{path} is {kind}, not a regular file")]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What it is instead.
        kind: &'static str,
    },
    /// A scene file names a file outside the scene's folder (see
    /// `vpl-scene-io`'s `sandbox`).
    #[error(
        "the reference '{reference}' leaves the scene's folder {root}; allow a folder that holds it to read it (--allow-outside PATH, or allow_outside)"
    )]
    OutsideScene {
        /// The reference as the scene file writes it.
        reference: String,
        /// The scene's folder.
        root: PathBuf,
    },
    /// An input file is longer than the limit for its kind
    /// (see `vpl-scene-io`'s `input`).
    #[error("{path} has {size} bytes, more than the {limit} this kind of input may have")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size in bytes (or the bytes read before stopping).
        size: u64,
        /// The limit.
        limit: u64,
    },
    /// A text input is not UTF-8.
    #[error("{path} is not UTF-8 text (invalid byte at offset {offset})")]
    Encoding {
        /// The file.
        path: PathBuf,
        /// Byte offset of the first invalid byte.
        offset: usize,
    },
    /// A material library (MTL) line is malformed or holds an impossible value.
    #[error("{path}:{line}: {reason}")]
    Mtl {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong, naming the statement and the value.
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
    /// An OBJ file could not be parsed.
    #[error("malformed OBJ {path}: {reason}")]
    Obj {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        reason: String,
    },
    /// A glTF 2.0 file could not be read or holds what the renderers cannot use.
    #[error("bad glTF {path}: {reason}")]
    Gltf {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the node, mesh, accessor or material.
        reason: String,
    },
    /// A Mitsuba XML scene could not be read or holds what the toolkit does
    /// not support.
    #[error("{path}:{line}: {reason}")]
    Mitsuba {
        /// The file (the scene or one it includes).
        path: PathBuf,
        /// 1-based line of the element (0 where the whole file is meant).
        line: usize,
        /// What is wrong, naming the element.
        reason: String,
    },
    /// A PLY mesh could not be parsed.
    #[error("bad PLY {path}: {reason}")]
    Ply {
        /// The file.
        path: PathBuf,
        /// What is wrong.
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
