//! # vpl-density
//!
//! k-nearest-neighbour estimates of the area density of a point set, as the
//! SMC sampler uses them for its VPLs (Hedman et al. 2017, §3.2.4, eq. 7):
//!
//! ```text
//! p(y) ≈ k / (N · π · r_k(y)²)
//! ```
//!
//! with `N` the number of points and `r_k(y)` the distance from `y` to its
//! k-th nearest neighbour, found by an unconstrained 3D search that assumes
//! the neighbours lie on y's (planar) surface, as photon mapping does. The
//! k-d tree is kiddo's; its distances are squared, which is what the formula
//! needs. Queries with a predicate, and each point's nearest other point,
//! walk a second tree of this crate's own, built by the first of them, that
//! skips the points the predicate refuses instead of ranking them.
//!
//! - [`KnnDensity::at`]: the density of the set at any point (a candidate
//!   against the current VPLs; k = 1 there, so candidates near a VPL look
//!   well sampled and are rarely chosen).
//! - [`KnnDensity::members`]: the density at each of the set's own points,
//!   the point itself excluded from its neighbours.
//! - Neighbour queries for other estimators: [`KnnDensity::member_nearest`],
//!   [`KnnDensity::within`] and [`KnnDensity::nearest_accepted`] (the
//!   nearest point a predicate takes, e.g. one facing the same way), which
//!   SMC's Voronoi-cell flux uses.
//! - [`rendering_k`]: `k = max(1, ⌊√(I/32)⌋)` for the densities that weight
//!   rendered VPLs (eq. 8): k → ∞ and k/I → 0 as I grows, which makes the
//!   estimate consistent; k = 8 at I = 2048.
//!
//! Every query depends only on the set of points, not on their order, but
//! for ties in distance (the predicate queries give them to the lower index).
//!
//! ```
//! use glam::Vec3;
//! use vpl_density::{rendering_k, KnnDensity};
//!
//! // 64×64 points on a grid over the unit square: density 1 per m².
//! let pts: Vec<Vec3> = (0..4096).map(|i| Vec3::new((i % 64) as f32 + 0.5, (i / 64) as f32 + 0.5, 0.0) / 64.0).collect();
//! let d = KnnDensity::new(&pts).unwrap();
//! // The 64 nearest points fill a disc of area ≈ 64/4096 m².
//! let p = d.at(Vec3::new(0.5, 0.5, 0.0), 64).unwrap();
//! assert!((p - 1.0).abs() < 0.1, "{p}");
//! assert_eq!(rendering_k(2048), 8);
//! assert_eq!(d.members(8).len(), 4096);
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

mod accepted;
mod knn;

pub use knn::{DensityError, KnnDensity, rendering_k, set_densities};
