//! # vpl-pathtrace
//!
//! The toolkit's reference: a path tracer with next-event estimation and
//! multiple importance sampling (power heuristic) for area lights, delta
//! lights by next-event estimation only, depth in Mitsuba 3's convention, and
//! the modes the VPL experiments need: `full`, `direct`, `indirect` (paths
//! with ≥ 2 scattering vertices), clamped indirect (Hedman et al. 2017, §5.4),
//! tracked pixels with standard errors, and a [`RadiosityEstimator`] for
//! samplers that need L(y) at their VPLs.
//!
//! ```
//! use vpl_core::SceneSetup;
//! use vpl_pathtrace::{render, Mode, PathTracer, RenderSettings};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let camera = setup.camera.with_resolution((16, 16)).unwrap();
//! let pt = PathTracer::new(5, Mode::Full);
//! let out = render(&setup.scene, &camera, &pt, RenderSettings { spp: 4, seed: 1, frame: 0 }, &|_, _| {}).unwrap();
//! assert!(out.image.mean()[0] > 0.0);
//! ```
//!
//! [`RadiosityEstimator`]: vpl_core::RadiosityEstimator
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

pub mod integrator;
pub mod radiosity;
pub mod render;

pub use integrator::PathTracer;
pub use radiosity::PathRadiosity;
pub use render::{
    Accumulator, Footprint, RenderError, RenderOutput, RenderSettings, TRACK_BATCH, TRACK_CHUNK, Tile, TrackRequest, TrackedPixel, pixel,
    render, render_cancellable, render_streamed, track, track_cancellable, track_chunk, track_with,
};
pub use vpl_core::Mode;
