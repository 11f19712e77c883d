//! # vpl-visibility
//!
//! Visibility V(x, y) between camera-visible points x and VPLs y, behind the
//! [`VplVisibility`] trait of `vpl-core`:
//!
//! - [`RayTraced`]: one BVH shadow ray per query, exact.
//! - [`ShadowMaps`]: one hemispherical paraboloid depth map per VPL
//!   (Brabec et al. 2002; Hedman et al. 2017, §4), 128×128 texels by default,
//!   rendered here by casting one ray per texel in the paraboloid
//!   parametrisation; a depth bias that scales with the texel footprint, so
//!   it shrinks as the resolution grows; maps rebuilt lazily, only for slots
//!   whose VPL moved; memory use reported.
//!
//! ```
//! use vpl_core::{SceneSetup, Vpl, VplSet, VplVisibility};
//! use vpl_core::glam::Vec3;
//! use vpl_visibility::{RayTraced, ShadowMaps};
//!
//! let scene = SceneSetup::builtin("cornell").unwrap().scene;
//! let mut set = VplSet::new(1);
//! set.set(0, Some(Vpl { y: Vec3::new(0.0, 0.99, 0.0), n: -Vec3::Y, flux: Vec3::ONE, id: 0, bounce: 1 }));
//! let mut maps = ShadowMaps::new(64).unwrap();
//! let mut rays = RayTraced::default();
//! assert_eq!(maps.update(&scene, &set).rebuilt, 1);
//! rays.update(&scene, &set);
//! let floor = Vec3::new(0.5, -1.0, 0.5);
//! assert_eq!(maps.visible(0, floor, Vec3::Y), rays.visible(0, floor, Vec3::Y));
//! assert_eq!(maps.update(&scene, &set).rebuilt, 0);
//! ```
//!
//! [`VplVisibility`]: vpl_core::VplVisibility
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

mod paraboloid;
mod raytraced;
mod shadow_maps;

pub use paraboloid::{direction_to_paraboloid, paraboloid_to_direction};
pub use raytraced::RayTraced;
pub use shadow_maps::{DEFAULT_RESOLUTION, MAX_RESOLUTION, ShadowMapError, ShadowMaps};
/// A map as shaders read it (defined in vpl-core, beside the trait that hands it out).
pub use vpl_core::MapView;
