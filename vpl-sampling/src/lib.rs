//! # vpl-sampling
//!
//! The facade over the toolkit's VPL samplers: one crate per method lives
//! beside this one (`vpl-ir`, `vpl-rr`, `vpl-mir`, `vpl-tcas`, `vpl-smc`),
//! and this crate re-exports them and keeps a [`Registry`] that builds any
//! of them by name, so an experiment can swap samplers with a string.
//!
//! The registry is a value: [`Registry::builtin`] holds the toolkit's
//! samplers and [`Registry::register`] adds a user's own. A sampler is built
//! for a [`Budget`] (VPL slots and path depth, set once for a renderer),
//! with the [`Services`] of a backend (a ray caster, radiosity estimators),
//! its settings read by its own crate from key–value [`Params`]; a key it
//! does not read is an error that names the key.
//!
//! ```
//! use vpl_core::{Budget, Frame, GBuffer, Params, SceneSetup, Services};
//! use vpl_sampling::{Registry, SamplerEntry};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let mut registry = Registry::builtin();
//! // A user's sampler: here IR with Halton paths under a name of its own.
//! registry
//!     .register(SamplerEntry::new("halton-ir", "IR on Halton paths", |cx, p| {
//!         let mut q = Params::new();
//!         q.insert("path-sampling", "halton").unwrap();
//!         q.offer("fresh-paths", p.get_or("fresh-paths", false).unwrap());
//!         cx.build("ir", &q)
//!     }))
//!     .unwrap();
//! let params = Params::parse(["fresh-paths=true"]).unwrap();
//! let mut sampler = registry.build("halton-ir", Budget::new(128, 5), &Services::cpu(), &params).unwrap();
//! let gbuffer = GBuffer::empty();
//! let frame = Frame { scene: &setup.scene, camera: &setup.camera, time: 0.0, index: 0, seed: 0, gbuffer: &gbuffer, previous: None };
//! assert_eq!(sampler.next_frame(&frame).len(), 128);
//! assert!(registry.build("smc", Budget::new(128, 5), &Services::cpu(), &Params::parse(["fresh-paths=1"]).unwrap()).is_err());
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

mod builtin;
mod registry;

pub use registry::{BuildFn, MemoryFn, MemoryPart, Registry, SamplerContext, SamplerEntry, SamplingError};
/// The core types a sampler works with, for crates that depend on this one only.
pub use vpl_core;
pub use vpl_core::{Budget, ParamError, ParamKey, Params, Services, Stats, VplSampler, VplSet};
pub use vpl_ir::{InstantRadiosity, IrConfig, IrStats, PathSampling};
pub use vpl_mir::{MirConfig, MirResampleConfig, MirResampleSampler, MirSampler};
pub use vpl_rr::{CandidateSource, LightPaths, RrConfig, RrSampler, RrStats, SamplerCandidates};
pub use vpl_smc::{FluxEstimator, Placement, SmcConfig, SmcError, SmcSampler, SmcStats, SmcTimings};
pub use vpl_tcas::{TcasConfig, TcasSampler};
