//! Interfaces shared by the stages of the toolkit.

use crate::scene::Scene;
use crate::surface::SurfacePoint;
use glam::Vec3;

/// Estimates the exitant radiance L(y) of a diffuse surface point (its radiosity
/// divided by π), as the SMC sampler and Metropolis IR need for their VPLs.
///
/// `seed` selects the random paths, so a VPL that passes the same seed in
/// every frame gets the same estimate while the scene does not change.
pub trait RadiosityEstimator {
    /// Exitant radiance of `y` toward its front side (normal `y.n`), emission excluded.
    fn radiosity(&self, scene: &Scene, y: &SurfacePoint, seed: u64) -> Vec3;
}
