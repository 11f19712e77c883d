//! SMC's step as the timing experiments run it: on the host (the default
//! SMC, with a backend's rays and radiosity estimates) or, with the GPU
//! backend, wholly on the device (the paper's kNN flux,
//! `vpl_gpu::GpuSmcSampler`, its stages timed there), with the step's
//! milliseconds in the columns of the paper's Table 2.

use crate::error::BenchError;
use serde::{Deserialize, Serialize};
use vpl_core::{Frame, VplSampler, VplSet};
use vpl_sampling::{SmcConfig, SmcSampler, SmcTimings};

/// Where SMC's iteration runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SmcPlace {
    /// The toolkit's default SMC (the Voronoi flux) on the host, its rays
    /// and radiosity estimates on the backend's device.
    #[default]
    Host,
    /// SMC with the paper's kNN flux wholly on the device (GPU backend).
    Device,
}

impl SmcPlace {
    /// The name `--smc` takes.
    pub fn name(self) -> &'static str {
        match self {
            SmcPlace::Host => "host",
            SmcPlace::Device => "device",
        }
    }
}

impl std::str::FromStr for SmcPlace {
    type Err = String;
    fn from_str(s: &str) -> Result<SmcPlace, String> {
        match s {
            "host" => Ok(SmcPlace::Host),
            "device" => Ok(SmcPlace::Device),
            _ => Err(format!("'{s}': host or device")),
        }
    }
}

/// An SMC sampler whose step's stages are timed.
pub enum SmcStep {
    /// On the host.
    Host(Box<SmcSampler>),
    /// On the device, its stages timed with timestamps where it has them.
    #[cfg(feature = "gpu")]
    Device(Box<vpl_gpu::GpuSmcSampler>),
}

impl SmcStep {
    /// The host sampler with `services` (a backend's rays and radiosities).
    pub fn host(config: SmcConfig, services: &vpl_core::Services) -> Result<SmcStep, BenchError> {
        Ok(SmcStep::Host(Box::new(SmcSampler::with_services(config, services)?)))
    }

    /// The device's sampler on `gpu` with `config`'s budget and the
    /// paper's kNN flux at the VPLs' sites, its stages timed.
    #[cfg(feature = "gpu")]
    pub fn device(gpu: &vpl_gpu::Gpu, config: SmcConfig) -> Result<SmcStep, BenchError> {
        use vpl_sampling::{FluxEstimator, Placement};
        let config = SmcConfig { flux: FluxEstimator::Knn, placement: Placement::Site, ..config };
        let mut s = vpl_gpu::GpuSmcSampler::new(gpu.clone(), config)?;
        s.profile(true);
        Ok(SmcStep::Device(Box::new(s)))
    }

    /// Where it runs.
    pub fn place(&self) -> SmcPlace {
        match self {
            SmcStep::Host(_) => SmcPlace::Host,
            #[cfg(feature = "gpu")]
            SmcStep::Device(_) => SmcPlace::Device,
        }
    }

    /// One frame's VPLs.
    pub fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        match self {
            SmcStep::Host(s) => s.next_frame(frame),
            #[cfg(feature = "gpu")]
            SmcStep::Device(s) => s.next_frame(frame),
        }
    }

    /// The last step's milliseconds by stage (the device's as its
    /// timestamps measured them; only the total where it has none).
    pub fn timings(&self) -> SmcTimings {
        match self {
            SmcStep::Host(s) => s.timings(),
            #[cfg(feature = "gpu")]
            SmcStep::Device(s) => s.timings(),
        }
    }
}
