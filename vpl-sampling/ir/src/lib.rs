//! # vpl-ir
//!
//! Keller's Instant Radiosity (SIGGRAPH 1997): light paths leave the lights,
//! chosen in proportion to power, and a VPL is stored at every diffuse vertex
//! up to the bounce limit (three indirect bounces by default, what
//! `--max-depth 5` renders).
//!
//! Russian roulette by albedo, as in the original's quasi-random walk: with
//! ρ̄ the scene's mean albedo, of the `n_j` paths that reach bounce j the
//! first `n_{j+1} = round(ρ̄^j · N)` continue, and each stored VPL of bounce j
//! carries `α · ρ(y) / (π · n_j)`, α the power its path brought to y. Bounce
//! j's light is then the mean over its `n_j` independent paths: unbiased, and
//! the number of VPLs is fixed in advance. `N` is the largest path count whose
//! VPLs fit the budget I; a path that leaves the scene (or reaches a surface
//! from its unlit side, or one that reflects nothing) stores nothing more, so
//! IR may store fewer than I VPLs. [`InstantRadiosity::stats`] counts them.
//!
//! Light path i draws its numbers from stream (seed, LIGHT_PATH, i), or from
//! point i of a Cranley–Patterson-rotated Halton sequence: the frame index is
//! not in the key, so a static scene gives the same VPLs in every frame.
//!
//! ```
//! use vpl_core::{Frame, GBuffer, SceneSetup, VplSampler};
//! use vpl_ir::{InstantRadiosity, IrConfig};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let gbuffer = GBuffer::empty();
//! let frame = Frame { scene: &setup.scene, camera: &setup.camera, time: 0.0, index: 0, seed: 1, gbuffer: &gbuffer, previous: None };
//! let mut ir = InstantRadiosity::new(IrConfig { vpls: 256, ..IrConfig::default() }).unwrap();
//! let set = ir.next_frame(&frame);
//! assert_eq!(set.len(), 256);
//! // The open front of the box lets about a quarter of the light paths escape.
//! assert!(set.stored() > 150 && set.stored() <= 256);
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

mod ir;

pub use ir::{InstantRadiosity, IrConfig, IrError, IrStats, PathSampling};
pub use vpl_core::Halton;
