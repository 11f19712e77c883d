//! # vpl-rr
//!
//! Russian-roulette VPL acceptance (Georgiev & Slusallek, *Simple and Robust
//! Iterative Importance Sampling of Virtual Point Lights*, EG 2010 short
//! paper): the light paths of Instant Radiosity, or of any other
//! [`LightPathGenerator`](vpl_core::LightPathGenerator), deposit VPL
//! *candidates*; each is kept with probability (eq. 3)
//!
//! ```text
//! p_i = min(Φ̃_i / Φ̃_v + ε, 1),   Φ̃_v = Φ̃_total / (P·N)
//! ```
//!
//! and a kept VPL's flux is divided by p_i (eq. 2), so the estimate stays
//! unbiased while the VPLs gather where they light what the camera sees.
//!
//! - Φ̃_i, the candidate's average pixel contribution, comes from connecting
//!   it, with visibility, to N_C = 100 camera samples ("importons") placed by
//!   a Halton sequence over the image that moves on every frame.
//! - Φ̃_total is the previous frame's indirect luminance summed over its P
//!   pixels ([`Frame::previous`](vpl_core::Frame::previous)); on the first
//!   frame it is 0, so p = 1 and the first frame is plain IR. Callers that
//!   pass no image get the sampler's own estimate from its last frame, and
//!   [`RrConfig::pilot`] estimates it on the first frame from a pilot set.
//! - N is the budget I. The candidate budget C is I divided by the last
//!   frame's acceptance rate, so about I are accepted; fewer leave slots
//!   empty, more are thinned to I at random with their flux scaled by A/I,
//!   which keeps the estimator unbiased.
//!
//! [`RrStats::mean_acceptance`] is the paper's average acceptance probability.
//!
//! ```
//! use vpl_core::{Frame, GBuffer, SceneSetup, VplSampler};
//! use vpl_rr::{RrConfig, RrSampler};
//!
//! let setup = SceneSetup::builtin("corner").unwrap();
//! let camera = setup.camera.with_resolution((32, 24)).unwrap();
//! let gbuffer = GBuffer::empty();
//! let frame = |index| Frame { scene: &setup.scene, camera: &camera, time: 0.0, index, seed: 3, gbuffer: &gbuffer, previous: None };
//! let mut rr = RrSampler::over_ir(RrConfig { vpls: 128, ..RrConfig::default() }, 3, true).unwrap();
//! rr.next_frame(&frame(0));
//! assert_eq!(rr.stats().mean_acceptance, 1.0); // Φ̃_total = 0: plain IR
//! rr.next_frame(&frame(1));
//! assert!(rr.stats().mean_acceptance < 0.5); // around the corner, most candidates are dropped
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

mod acceptance;
mod config;
mod sampler;
mod source;

pub use acceptance::acceptance;
pub use config::{RrConfig, RrError};
pub use sampler::{PhiSource, RrSampler, RrStats};
pub use source::{CandidateSource, LightPaths, SamplerCandidates};
