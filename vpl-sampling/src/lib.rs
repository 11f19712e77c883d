//! # vpl-sampling
//!
//! The facade over the toolkit's VPL samplers: one crate per method lives
//! beside this one (`vpl-ir`, `vpl-rr`, `vpl-mir`, `vpl-tcas`, `vpl-smc`), and this crate re-exports them and keeps a
//! registry that builds any of them by name from one [`SamplerConfig`], so an
//! experiment can swap samplers with a string.
//!
//! ```
//! use vpl_core::{Frame, GBuffer, SceneSetup};
//! use vpl_sampling::{build, SamplerConfig};
//!
//! let setup = SceneSetup::load("cornell").unwrap();
//! let mut sampler = build("ir", &SamplerConfig { vpls: 128, ..SamplerConfig::default() }).unwrap();
//! let gbuffer = GBuffer::empty();
//! let frame = Frame { scene: &setup.scene, camera: &setup.camera, time: 0.0, index: 0, seed: 0, gbuffer: &gbuffer, previous: None };
//! assert_eq!(sampler.next_frame(&frame).len(), 128);
//! assert!(build("nope", &SamplerConfig::default()).is_err());
//! ```

#![warn(missing_docs)]

mod registry;

pub use registry::{build, SamplerConfig, SamplerEntry, SamplingError, PLANNED, SAMPLERS};
pub use vpl_core::{VplSampler, VplSet};
pub use vpl_ir::{InstantRadiosity, IrConfig, IrStats, PathSampling};
pub use vpl_mir::{MirConfig, MirResampleConfig, MirResampleSampler, MirSampler};
pub use vpl_rr::{RrConfig, RrSampler, RrStats};
pub use vpl_smc::{SmcConfig, SmcSampler, SmcStats, SmcTimings};
pub use vpl_tcas::{TcasConfig, TcasSampler};
