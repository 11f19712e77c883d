//! What a sampler may use that a backend provides: a [`RayCaster`] and a
//! maker of [`RadiosityEstimator`]s. They are handed to a sampler when it is
//! built (the registry passes them), so the sampler trait carries no setter
//! that only one sampler needs.

use crate::budget::Budget;
use crate::params::Params;
use crate::traits::{CpuRays, RadiosityEstimator, RayCaster, VplSampler};
use std::sync::Arc;

/// A radiosity estimator shared between threads.
pub type SharedEstimator = Box<dyn RadiosityEstimator + Send + Sync>;

/// Makes radiosity estimators for a sampler's own settings.
pub trait RadiosityFactory: Send + Sync {
    /// An estimator of `paths` paths per estimate with at most
    /// `max_bounces` scattering vertices after the point.
    fn estimator(&self, paths: u32, max_bounces: u32) -> SharedEstimator;
}

impl<F> RadiosityFactory for F
where
    F: Fn(u32, u32) -> SharedEstimator + Send + Sync,
{
    fn estimator(&self, paths: u32, max_bounces: u32) -> SharedEstimator {
        self(paths, max_bounces)
    }
}

/// Samplers a backend runs wholly on its device: twins of host samplers,
/// offered by the host sampler's registry name, budget and parameters
/// (which the twin reads as that entry does), so a registry entry asks
/// before it builds the host one.
pub trait DeviceSamplers: Send + Sync {
    /// The device's twin of the sampler registered as `name`, for `budget`
    /// with the parameters `params`; `None` when the backend has none for
    /// them (the host sampler runs, and reports any parameter error), an
    /// error when it has one that failed to start.
    fn twin(&self, name: &str, budget: &Budget, params: &Params) -> Option<Result<Box<dyn VplSampler>, DeviceError>>;
}

/// Why a device's sampler failed to start.
pub type DeviceError = Box<dyn std::error::Error + Send + Sync>;

/// The services of a backend.
#[derive(Clone)]
pub struct Services {
    /// Batched ray queries ([`CpuRays`] on the CPU).
    pub rays: Arc<dyn RayCaster>,
    /// Radiosity estimators; `None`: each sampler uses its own CPU path tracer.
    pub radiosity: Option<Arc<dyn RadiosityFactory>>,
    /// Samplers run wholly on the device; `None`: every sampler runs on the host.
    pub samplers: Option<Arc<dyn DeviceSamplers>>,
}

impl Default for Services {
    fn default() -> Self {
        Services::cpu()
    }
}

impl std::fmt::Debug for Services {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Services")
            .field("rays", &self.rays.name())
            .field("radiosity", &self.radiosity.is_some())
            .field("samplers", &self.samplers.is_some())
            .finish()
    }
}

impl Services {
    /// The CPU's: the scene's BVH, and each sampler's own radiosity estimator.
    pub fn cpu() -> Services {
        Services { rays: Arc::new(CpuRays), radiosity: None, samplers: None }
    }
}
