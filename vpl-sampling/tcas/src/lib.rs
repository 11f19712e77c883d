//! # vpl-tcas
//!
//! Temporally coherent adaptive sampling (TCAS; Barák, Bittner, Havran,
//! *Temporally Coherent Adaptive Sampling for Imperfect Shadow Maps*, CGF
//! 2013), the SMC paper's third baseline. VPLs are drawn from reflective
//! shadow maps (one per light, rendered here by ray casting: position,
//! normal and flux per texel) by Metropolis-Hastings with a view-dependent
//! importance: the light a texel's VPL brings to a fixed set of camera
//! samples, visibility ignored, as the method does. Each VPL slot is one
//! Markov chain; the chains and their quasi-random (Halton) proposal
//! sequence continue from frame to frame, so a VPL moves only when a
//! proposal beats it, which keeps the image stable. Single indirect bounce
//! only. 16 iterations per frame by default (the SMC paper's setting;
//! Barák et al. propose 5).
//!
//! ```
//! use vpl_core::{Frame, GBuffer, SceneSetup, VplSampler};
//! use vpl_tcas::{TcasConfig, TcasSampler};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let camera = setup.camera.with_resolution((32, 32)).unwrap();
//! let gbuffer = GBuffer::empty();
//! let frame = |index| Frame { scene: &setup.scene, camera: &camera, time: 0.0, index, seed: 1, gbuffer: &gbuffer, previous: None };
//! let mut tcas = TcasSampler::new(TcasConfig { vpls: 64, rsm_res: 32, ..TcasConfig::default() }).unwrap();
//! assert_eq!(tcas.next_frame(&frame(0)).stored(), 64);
//! // The chains continue from their texels; every VPL is a first bounce.
//! let set = tcas.next_frame(&frame(1));
//! assert!(set.iter().all(|(_, v)| v.bounce == 1));
//! assert!(tcas.stats().accepted < tcas.stats().proposals);
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
mod rsm;
mod sampler;

pub use config::{TcasConfig, TcasError};
pub use rsm::{Rsm, Texel};
pub use sampler::{TcasSampler, TcasStats};
