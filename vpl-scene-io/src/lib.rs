//! # vpl-scene-io
//!
//! Scene and image files for the VPL toolkit. [`load`] takes what a user
//! names on a command line: a built-in scene, a TOML scene file, or a bare
//! model (OBJ, glTF 2.0 `.gltf`/`.glb`, Mitsuba 3 XML), and gives the
//! [`SceneSetup`] every renderer of the toolkit starts from. [`ImageFile`]
//! reads and writes EXR images and writes PNG previews.
//!
//! Every file goes through the same guards: a scene's files must lie in its
//! folder or a root the user allowed ([`sandbox`], [`LoadOptions`]); only
//! regular files are read, never more bytes than a limit decided before the
//! work ([`input`]); textures and images are refused on their headers before
//! the decoder allocates. A hostile file ends in an error, never a panic.
//!
//! One cargo feature per format (all on by default): `toml`, `obj`, `ply`,
//! `gltf`, `mitsuba` (which needs `obj` and `ply`), `exr` and `png`. A format
//! left out answers an error that names its feature.
//!
//! Reading fails with a [`SceneIoError`]: what a format or an input guard
//! says, or the core's [`vpl_core::CoreError`] for what the file describes
//! (a bad value, an empty scene, an unknown built-in). Writing images fails
//! with the core's error alone.
//!
//! ```
//! use vpl_scene_io::{ImageFile, load};
//!
//! // A built-in by name; a path loads a scene file or a model the same way.
//! let setup = load("cornell").unwrap();
//! let (scene, camera) = setup.frame(0).unwrap();
//! assert!(!scene.lights.is_empty() && camera.resolution.0 > 0);
//! // EXR images round-trip exactly.
//! let mut img = vpl_core::Image::new(4, 2);
//! img.data[5] = vpl_core::glam::Vec3::new(0.25, 1e-7, 1000.5);
//! let bytes = img.encode_exr().unwrap();
//! assert_eq!(vpl_core::Image::decode_exr(&bytes, "a.exr".as_ref()).unwrap(), img);
//! ```

#![warn(missing_docs)]

#[cfg(any(feature = "gltf", feature = "mitsuba"))]
pub mod bitmap;
pub mod error;
#[cfg(feature = "gltf")]
pub mod gltf;
pub mod image_file;
pub mod input;
pub mod loader;
#[cfg(feature = "mitsuba")]
pub mod mitsuba;
#[cfg(feature = "obj")]
pub mod mtl;
#[cfg(feature = "obj")]
pub mod obj;
#[cfg(feature = "ply")]
pub mod ply;
pub mod sandbox;
pub mod scene_toml;

pub use error::SceneIoError;
pub use image_file::{ImageFile, encode_png_rgb8, write_png_rgb8};
pub use loader::{Files, from_file, from_file_with, load, load_with};
pub use sandbox::LoadOptions;
pub use scene_toml::{parse_scene_file, read_scene_file};
#[cfg(feature = "toml")]
pub use scene_toml::{scene_toml, setup_toml};
pub use vpl_core::SceneSetup;
