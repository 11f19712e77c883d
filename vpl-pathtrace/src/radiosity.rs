//! The path tracer as a [`RadiosityEstimator`]: exitant radiance of a diffuse
//! point from N next-event-estimation paths, seeded by the caller.

use crate::integrator::PathTracer;
use vpl_core::Mode;
use vpl_core::glam::Vec3;
use vpl_core::{Purpose, RadiosityEstimator, Scene, SurfacePoint, stream};

/// Estimates L(y) with `paths` paths of at most `max_bounces` bounces after y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathRadiosity {
    /// Paths per estimate (the SMC paper uses 16).
    pub paths: u32,
    /// Scattering vertices allowed after y (0: direct light at y only).
    pub max_bounces: u32,
}

impl Default for PathRadiosity {
    /// 16 paths, 2 bounces after y: with the camera point and y itself,
    /// that is max-depth 5 (three indirect bounces).
    fn default() -> Self {
        Self { paths: 16, max_bounces: 2 }
    }
}

impl RadiosityEstimator for PathRadiosity {
    fn radiosity(&self, scene: &Scene, y: &SurfacePoint, seed: u64) -> Vec3 {
        let pt = PathTracer::new(u32::MAX, Mode::Full);
        let mut sum = Vec3::ZERO;
        for i in 0..self.paths {
            let mut rng = stream(seed, 0, Purpose::RADIOSITY, i as u64);
            sum += pt.reflected(scene, y, y.n, self.max_bounces, &mut rng);
        }
        sum / self.paths.max(1) as f32
    }
}
