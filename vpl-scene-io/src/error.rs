//! The typed error of reading scene and image files: what the formats and
//! the guards on their input say, beside the core's own errors
//! ([`CoreError`]: bad values, empty scenes, unknown built-ins).

use std::path::PathBuf;
use vpl_core::CoreError;

/// Errors from reading scenes and images.
///
/// Each variant's message is one readable line that names the problem, so a
/// binary can print it as is.
#[derive(Debug, thiserror::Error)]
pub enum SceneIoError {
    /// A file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A path names something other than a regular file (a device, a pipe, a directory).
    #[error("{path} is {kind}, not a regular file")]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What it is instead.
        kind: &'static str,
    },
    /// A scene file names a file outside the scene's folder (see [`crate::sandbox`]).
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
    /// (see [`crate::input`]).
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
    /// What the core said of the scene or image the file describes.
    #[error(transparent)]
    Core(#[from] CoreError),
}

/// Shorthand for `Result<T, SceneIoError>`.
pub type Result<T> = std::result::Result<T, SceneIoError>;
