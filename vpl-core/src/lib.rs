//! # vpl-core
//!
//! The vocabulary every crate of the VPL toolkit speaks. First the four
//! stages a renderer is made of, as traits:
//!
//! - [`VplSampler`]: places the VPL set ([`Vpl`], [`VplSet`]) each
//!   [`Frame`], with a [`RadiosityEstimator`] for the light a point
//!   reflects;
//! - [`VplVisibility`]: answers whether a VPL sees a point (shadow maps,
//!   rays), updated incrementally as slots move;
//! - [`IndirectShader`]: gathers the set at the receivers of a [`GBuffer`];
//! - [`RayCaster`] and [`LightPathGenerator`]: rays and light paths in
//!   batches, on the CPU ([`CpuRays`]) or a device ([`Services`]).
//!
//! Then what they share: rays and local frames, seeded random streams
//! keyed by purpose and index, spectra and BSDFs, the scene (one triangle
//! mesh, materials, lights, an 8-wide BVH built by `obvhs` with a
//! watertight triangle test), cameras, the G-buffer, images, sampler
//! parameters and statistics, budgets, the built-in scenes and their
//! animations, and scene descriptions ([`SceneFile`], [`SceneSetup`]).
//!
//! No file format is read or written here: the `vpl-scene-io` crate reads
//! scene files (TOML, OBJ/MTL, PLY, glTF, Mitsuba XML) through
//! [`ModelLoader`] and reads and writes EXR and PNG images, with its own
//! error (`SceneIoError`, which holds a [`CoreError`] for what the core
//! refuses). The core's writes are atomic byte writes
//! ([`image::write_atomic`]).
//!
//! ```
//! use vpl_core::{SceneSetup, Purpose, stream};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let ray = setup.camera.ray(128.0, 128.0, (0.5, 0.5));
//! let hit = setup.scene.intersect(&ray).expect("the tall box");
//! assert!(hit.point.p.z < 1.0 && hit.t > 2.8);
//! let mut rng = stream(0, 0, Purpose::PIXEL, 42);
//! assert!(rng.next_f32() < 1.0);
//! ```
//!
//! ## Build profile
//!
//! Debug builds of the toolkit's crates are 20–50× slower than optimised ones
//! (an SMC frame takes 9.7 s instead of 0.18 s). The toolkit's own workspace
//! optimises its dependencies, but a workspace's profile does not reach the
//! projects that depend on it. Add to your project's `Cargo.toml`:
//!
//! ```toml
//! [profile.dev.package."*"]
//! opt-level = 3
//! ```
//!
//! Your own crates stay quick to compile; every dependency, this one included,
//! is optimised.

#![warn(missing_docs)]

pub mod bsdf;
pub mod budget;
pub mod builtin;
pub mod bvh;
pub mod camera;
pub mod clamp;
pub mod cpu;
pub mod distribution;
pub mod emission;
pub mod environment;
pub mod error;
pub mod frame;
pub mod gbuffer;
pub mod halton;
pub mod image;
pub mod importons;
pub mod light;
pub mod material;
pub mod mesh;
pub mod mode;
pub mod params;
pub mod ray;
pub mod resample;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod scene_file;
pub mod sequence;
pub mod services;
pub mod setup;
pub mod shadow_map;
pub mod spectral;
pub mod stats;
pub mod surface;
pub mod traits;
pub mod triangle;
pub mod validate;
pub mod view;
pub mod vpl;

pub use budget::Budget;
pub use camera::{BounceRays, Camera, CameraRays, FovAxis};
pub use clamp::GeometryClamp;
pub use emission::EmittedRay;
pub use error::{CoreError, Result};
pub use frame::Frame;
pub use gbuffer::{GBuffer, GSample, Receivers};
pub use glam;
pub use halton::Halton;
pub use image::Image;
pub use importons::Importon;
pub use light::{Light, LightSample};
pub use material::{Layered, Material, MaterialPolicy};
pub use mesh::{Mesh, TriangleDesc};
pub use mode::Mode;
pub use params::{ParamError, ParamKey, Params};
pub use ray::{LocalFrame, Ray};
pub use rng::{Purpose, RngStream, stream};
pub use scene::{Geometry, Scene, TriangleData};
pub use scene_file::SceneFile;
pub use sequence::Sequence;
pub use services::{DeviceError, DeviceSamplers, RadiosityFactory, Services, SharedEstimator};
pub use setup::{Model, ModelLoader, NoModelFiles, SceneSetup};
pub use shadow_map::{MapView, ShadowMapSource};
pub use stats::{Stat, Stats};
pub use surface::{Hit, SurfacePoint};
pub use traits::{
    CpuRays, DeviceKey, IndirectShader, LightPathGenerator, RadiosityEstimator, RayCaster, VisibilityUpdate, VplSampler, VplVisibility,
};
pub use vpl::{Vpl, VplSet};
