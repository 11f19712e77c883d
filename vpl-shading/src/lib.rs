//! # vpl-shading
//!
//! The stages that turn VPLs into pixels, shared by every sampler:
//!
//! - [`render_gbuffer`]: position, normals, albedo, material, depth and
//!   directly seen emission per pixel, one camera ray through each centre;
//! - [`direct_light`]: single scattering by next-event estimation with shadow
//!   rays, deterministic (fixed streams per pixel);
//! - [`InterleavedShader`]: 4×4 interleaved shading (each pixel class uses
//!   its own I/16 of the VPLs, weighted to be unbiased), VPL-major, followed by
//!   the [`CrossBilateral`] filter of the SMC paper (§4);
//! - [`ExhaustiveShader`]: all VPLs at every pixel;
//! - [`render_frame`]: the whole frame (sampler, visibility, shading, direct
//!   light) with per-stage timings.
//!
//! The geometry term is clamped by the one rule the clamped path tracer also
//! uses ([`GeometryClamp`]; default [`GeometryClamp::for_budget`]).
//!
//! ```
//! use vpl_core::{GeometryClamp, IndirectShader, SceneSetup, VplVisibility};
//! use vpl_ir::{InstantRadiosity, IrConfig};
//! use vpl_shading::{render_gbuffer, ExhaustiveShader};
//! use vpl_visibility::RayTraced;
//!
//! let setup = SceneSetup::load("cornell").unwrap();
//! let camera = setup.camera.with_resolution((16, 16)).unwrap();
//! let gbuf = render_gbuffer(&setup.scene, &camera);
//! let mut ir = InstantRadiosity::new(IrConfig { vpls: 256, ..IrConfig::default() }).unwrap();
//! let vpls = ir.sample(&setup.scene, 0);
//! let mut vis = RayTraced::default();
//! vis.update(&setup.scene, vpls);
//! let clamp = GeometryClamp::for_budget(vpls.len(), setup.scene.surface_area());
//! let img = ExhaustiveShader { clamp: Some(clamp) }.shade(&gbuf, vpls, &vis);
//! assert!(img.mean()[0] > 0.0);
//! ```
//!
//! [`GeometryClamp`]: vpl_core::GeometryClamp
//! [`GeometryClamp::for_budget`]: vpl_core::GeometryClamp::for_budget

#![warn(missing_docs)]

mod direct;
mod exhaustive;
mod filter;
mod gather;
mod gbuffer;
mod interleaved;
mod pipeline;

pub use direct::direct_light;
pub use exhaustive::ExhaustiveShader;
pub use filter::CrossBilateral;
pub use gbuffer::render_gbuffer;
pub use interleaved::{InterleavedShader, ShadeTimings, CLASSES, TILE};
pub use pipeline::{render_frame, render_frame_on, FrameOutput, FrameSettings, StageTimings};
