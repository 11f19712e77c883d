//! # vpl-bench
//!
//! The toolkit's experiments as a library: Table 1 and Table 2 of the SMC
//! paper, figures, Georgiev's experiments, plots, image comparisons with
//! standard errors, the validation of the path tracer against Mitsuba 3,
//! stage timings and throughput figures. Each reports progress through a
//! callback and returns its results; the `vpl` command (`vpl-cli`) parses
//! arguments, draws progress bars and writes the files.
//!
//! ```
//! use vpl_bench::compare::{compare, z_critical};
//! use vpl_core::{glam::Vec3, Image};
//!
//! let a = Image { width: 1, height: 1, data: vec![Vec3::splat(1.0)] };
//! let se = Image { width: 1, height: 1, data: vec![Vec3::splat(0.1)] };
//! let c = compare(&a, &se, &a, &se, 0.01).unwrap();
//! assert_eq!(c.pass_rate, 1.0);
//! assert!((z_critical(0.01) - 2.576).abs() < 1e-3);
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

pub mod cpu_time;
pub mod energy;
pub mod error;
pub mod figures;
pub mod georgiev;
#[cfg(feature = "gpu")]
pub mod gpu_bench;
pub mod manylights;
pub mod pipeline;
pub mod plot;
pub mod progressive;
pub mod rays;
pub mod scenes;
pub mod smc_step;
pub mod stages;
pub mod table1;
pub mod table2;
pub mod validation;

pub use vpl_render::{compare, metrics, sequence};
