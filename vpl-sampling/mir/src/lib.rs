//! # vpl-mir
//!
//! Metropolis Instant Radiosity and its resampling stand-in, the view-adaptive
//! baselines of the SMC paper (Hedman et al. 2017, §2.2 and §5.1). Both start
//! afresh every frame, as the originals do: no temporal coherence.
//!
//! - [`MirSampler`] (`mir`), after Segovia, Iehl and Péroche (EG 2007):
//!   Metropolis-Hastings over light paths in primary sample space (a point
//!   u ∈ [0,1)^d is a light path and the VPL at one of its bounces, see
//!   [`path_vpl`]), whose target f(u) is the power that VPL brings to the
//!   camera, estimated against camera samples with visibility. Small
//!   perturbations (Kelemen's) and large, independent steps; a bootstrap
//!   phase of independent paths estimates the normalisation b = ∫ f and
//!   seeds the chains in proportion to f. Every VPL then has flux
//!   Φ(u)·b / (I·f(u)): all I bring the camera the same power b / I. A small
//!   defensive term in f keeps paths that no camera sample sees reachable.
//! - [`MirResampleSampler`] (`mir-resample`), what the SMC paper ran in its
//!   experiments: 256·I camera paths of the path tracer, resampled down to I
//!   in proportion to the light they bring the camera; their secondary
//!   vertices are the VPLs, weighted by kNN densities as SMC's are.
//!
//! ```
//! use vpl_core::{Frame, GBuffer, SceneSetup, VplSampler};
//! use vpl_mir::{MirConfig, MirSampler};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let camera = setup.camera.with_resolution((32, 32)).unwrap();
//! let gbuffer = GBuffer::empty();
//! let frame = Frame { scene: &setup.scene, camera: &camera, time: 0.0, index: 0, seed: 1, gbuffer: &gbuffer, previous: None };
//! let mut mir = MirSampler::new(MirConfig { vpls: 64, ..MirConfig::default() }).unwrap();
//! let set = mir.next_frame(&frame);
//! assert_eq!(set.stored(), 64);
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

mod config;
mod metropolis;
mod path;
mod resample;

pub use config::{MirConfig, MirError, MirResampleConfig};
pub use metropolis::{MirSampler, MirStats};
pub use path::{dims, path_vpl, perturb, uniform};
pub use resample::{MirResampleSampler, MirResampleStats};
