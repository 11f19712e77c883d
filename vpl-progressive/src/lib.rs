//! # vpl-progressive
//!
//! The progressive point-light renderer of Dammertz, Keller and Lensch,
//! *Progressive Point-Light-Based Global Illumination* (CGF 2010). Each
//! pass partitions path space by the κ-layered materials of
//! [`vpl_core::bsdf`] (§4) and hands every class of light path to exactly
//! one technique (§3):
//!
//! | paths | technique | module |
//! | --- | --- | --- |
//! | ES*L | eye paths that reach a light, added directly | [`eye`] |
//! | EDL, EDD(S\|D)*L | VPLs from 16 light paths a pass, stochastically culled | [`light_paths`], [`gather`] |
//! | EDS(S\|D)*L | caustic histograms: photons from the VPLs, aimed by projection maps, each falling into the one closest eye-vertex bin | [`histogram`], [`projection`] |
//! | ES+D(S\|D)*L | specular gathering: the two above, at eye vertices reached through specular bounces | [`eye`], [`gather`], [`histogram`] |
//!
//! Passes are independent and are averaged in an accumulation buffer of
//! constant size; eye paths start anew every pass, so anti-aliasing,
//! thin-lens depth of field (the camera's lens) and glossy effects refine
//! progressively. Paths that meet a dispersive material carry a wavelength
//! from there on (lazy spectral rendering, §6).
//!
//! ```
//! use vpl_core::SceneSetup;
//! use vpl_progressive::{Progressive, ProgressiveConfig};
//!
//! let setup = SceneSetup::builtin("glass").unwrap();
//! let camera = setup.camera.with_resolution((16, 12)).unwrap();
//! let config = ProgressiveConfig { caustic_paths: 2000, ..Default::default() };
//! let mut r = Progressive::new(&setup.scene, camera, config).unwrap();
//! for _ in 0..2 {
//!     r.pass();
//! }
//! assert_eq!(r.passes(), 2);
//! assert!(r.image().mean()[0] > 0.0);
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

pub mod config;
pub mod error;
pub mod eye;
pub mod gather;
pub mod histogram;
pub mod light_paths;
pub mod lightcut;
pub mod projection;
pub mod renderer;
pub mod vertex;

pub use config::{BinRule, Culling, Gathering, ProgressiveConfig, Techniques};
pub use error::ProgressiveError;
pub use renderer::{PassStats, Progressive, specular_bounds};

/// Bytes a pass holds for each of its VPLs under `gathering`: the VPL as
/// traced and as stored (culling keeps a second list), and with lightcuts
/// its light-tree slot and share of the tree's nodes (one inner node a
/// light, and the parent links). What a memory estimate multiplies by the
/// pass's VPLs (`vpl_render::MemoryEstimate::progressive`).
pub fn bytes_per_vpl(gathering: Gathering) -> u64 {
    let vpl = 2 * std::mem::size_of::<light_paths::PassVpl>() as u64;
    match gathering {
        Gathering::Exhaustive => vpl,
        Gathering::Lightcuts { .. } => {
            vpl + (std::mem::size_of::<Option<vpl_lighttree::Emitter>>() + std::mem::size_of::<vpl_lighttree::Node>() + 8) as u64
        }
    }
}
