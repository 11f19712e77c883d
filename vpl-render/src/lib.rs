//! # vpl-render
//!
//! The VPL renderer as a library: what a researcher's own application
//! depends on to render frames with any sampler of the toolkit (or their
//! own), shadow maps or shadow rays, interleaved or exhaustive shading, on
//! the CPU or on a backend from another crate (`vpl-gpu` implements
//! [`Backend`]: `.backend(vpl_gpu::backend()?)`).
//!
//! - [`Renderer`] and its builder: the budget (VPL slots I) and the path
//!   depth are set once and every stage reads them from there; the sampler,
//!   the visibility structure and the shader keep their state from frame to
//!   frame;
//! - [`Backend`], [`CpuBackend`]: where the G-buffer, visibility and shading
//!   run, and the services (ray caster, radiosity estimators) samplers get;
//!   [`Backends`]: backends by name, other crates' registered beside the CPU
//!   (`vpl_gpu::register`);
//! - [`PipelineSpec`]: one description of a renderer (sampler and
//!   parameters, budget, stages, clamp, backend by name), one line of text
//!   as its written form, what the command line, Python and experiments use;
//! - [`render_frame`]: one frame ([`FrameRequest`]) from given stages
//!   ([`FrameStages`]), timed per stage;
//! - [`sequence`]: frames of a scene's animation with tracked pixels, CSV;
//! - [`metrics`] and [`compare`]: relMSE, RMSE, the SMC paper's |E| and |E′|,
//!   per-pixel z-tests against a reference with standard errors.
//!
//! No command-line, progress-bar or plotting crate is in its tree.
//!
//! ```
//! use vpl_core::{Mode, Params, SceneSetup};
//! use vpl_render::{Renderer, ShadingSpec, VisibilitySpec};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let camera = setup.camera.with_resolution((32, 32)).unwrap();
//! let mut renderer = Renderer::builder(&setup.scene)
//!     .vpls(64)
//!     .sampler("smc")
//!     .params(Params::parse(["warmup=2", "m-max=4"]).unwrap())
//!     .visibility(VisibilitySpec::ShadowMaps(32))
//!     .shader(ShadingSpec::Interleaved { filter: true })
//!     .mode(Mode::Indirect)
//!     .build()
//!     .unwrap();
//! let first = renderer.render(&setup.scene, &camera, 0, 0.0).unwrap();
//! let second = renderer.render(&setup.scene, &camera, 1, 1.0 / 30.0).unwrap();
//! assert_eq!(first.stored, 64);
//! assert!(second.moved <= 4);
//! assert!(first.image.mean()[0] > 0.0);
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

mod backend;
mod backends;
pub mod compare;
pub mod compensation;
mod error;
mod frame;
pub mod memory;
pub mod metrics;
mod pipeline;
mod renderer;
pub mod sequence;
mod spec;

pub use backend::{Backend, CpuBackend};
pub use backends::{AUTO, BackendEntry, BackendFactory, Backends};
pub use compensation::Compensation;
pub use error::RenderError;
pub use frame::{FrameOutput, FrameRequest, FrameSettings, FrameStages, StageTimings, count_non_finite, render_frame};
pub use memory::MemoryEstimate;
pub use pipeline::PipelineSpec;
pub use renderer::{Renderer, RendererBuilder, SamplerChoice};
pub use sequence::{SequenceFrame, default_tracked_pixels, run_sequence};
pub use spec::{Clamp, ReadBack, ShadingSpec, VisibilitySpec};
/// The core types (scenes, cameras, images, VPL sets), for crates that depend on this one.
pub use vpl_core;
pub use vpl_sampling::Registry;
