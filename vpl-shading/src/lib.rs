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
//! - [`ExhaustiveShader`]: all VPLs at every pixel.
//!
//! The stateful frame pipeline that strings these together with a sampler
//! and visibility is the crate `vpl-render`.
//!
//! The geometry term is clamped by the one rule the clamped path tracer also
//! uses ([`GeometryClamp`]; default [`GeometryClamp::for_view`]).
//!
//! ```
//! use vpl_core::{GeometryClamp, IndirectShader, SceneSetup, Vpl, VplSet, VplVisibility};
//! use vpl_shading::{render_gbuffer, ExhaustiveShader};
//! use vpl_visibility::RayTraced;
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let camera = setup.camera.with_resolution((16, 16)).unwrap();
//! let gbuf = render_gbuffer(&setup.scene, &camera);
//! // One VPL where the centre pixel's ray meets the scene, facing the camera
//! // (any sampler's VplSet shades the same way).
//! let ray = camera.ray(8.0, 8.0, (0.5, 0.5));
//! let y = setup.scene.intersect(&ray).unwrap().point.facing(-ray.d);
//! let mut vpls = VplSet::new(1);
//! vpls.set(0, Some(Vpl { y: y.p + y.n * 1e-3, n: y.n, flux: vpl_core::glam::Vec3::ONE, id: 0, bounce: 1 }));
//! let mut vis = RayTraced::default();
//! vis.update(&setup.scene, &vpls);
//! let clamp = GeometryClamp::for_view(vpls.len(), &setup.scene, &camera);
//! let img = ExhaustiveShader { clamp: Some(clamp) }.shade(&gbuf, &vpls, &vis);
//! assert!(img.mean()[0] > 0.0);
//! ```
//!
//! [`GeometryClamp`]: vpl_core::GeometryClamp
//! [`GeometryClamp::for_view`]: vpl_core::GeometryClamp::for_view
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

mod culling;
mod direct;
mod exhaustive;
mod filter;
mod gather;
mod gather_maps;
mod gbuffer;
mod interleaved;
mod lightcuts;

pub use culling::CulledShader;
pub use direct::direct_light;
pub use exhaustive::ExhaustiveShader;
pub use filter::CrossBilateral;
pub use gbuffer::{environment_at_misses, render_gbuffer};
pub use interleaved::{CLASSES, InterleavedShader, ShadeTimings, TILE};
pub use lightcuts::LightcutShader;
