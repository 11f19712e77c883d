//! The registry of samplers, by name.

use vpl_core::VplSampler;
use vpl_ir::{InstantRadiosity, IrConfig, PathSampling};
use vpl_smc::{SmcConfig, SmcSampler};

/// What every sampler is built from. Fields a sampler does not use are ignored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplerConfig {
    /// The VPL budget I.
    pub vpls: usize,
    /// Longest path in segments (Mitsuba's convention): VPLs reach
    /// `max_depth − 2` light-path bounces.
    pub max_depth: u32,
    /// Random or Halton light paths (samplers that trace them from the lights).
    pub sampling: PathSampling,
    /// New light paths every frame (IR; see [`IrConfig::fresh_paths`]).
    pub fresh_paths: bool,
    /// The SMC sampler's settings; its `vpls` and `radiosity_bounces` are
    /// taken from `vpls` and `max_depth` above.
    pub smc: SmcConfig,
}

impl Default for SamplerConfig {
    fn default() -> Self {
        SamplerConfig { vpls: 2048, max_depth: 5, sampling: PathSampling::Random, fresh_paths: false, smc: SmcConfig::default() }
    }
}

impl SamplerConfig {
    /// Light-path bounces that carry VPLs: `max_depth − 2`.
    pub fn bounces(&self) -> u32 {
        self.max_depth.saturating_sub(2)
    }

    /// The SMC settings with this config's budget and depth: radiosity paths
    /// of `max_depth − 3` bounces after the VPL.
    pub fn smc_config(&self) -> SmcConfig {
        SmcConfig { vpls: self.vpls, radiosity_bounces: self.max_depth.saturating_sub(3), ..self.smc }
    }
}

/// Errors of [`build`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SamplingError {
    /// No sampler has this name.
    #[error("unknown sampler '{0}' (available: {1})")]
    Unknown(String, String),
    /// A sampler the toolkit plans that this build does not have yet.
    #[error("sampler '{0}' is not available in this build (available: {1})")]
    NotAvailable(String, String),
    /// The configuration does not suit the sampler.
    #[error("sampler '{0}': {1}")]
    Config(&'static str, String),
}

/// A registered sampler.
pub struct SamplerEntry {
    /// Name used on the command line.
    pub name: &'static str,
    /// One line about it.
    pub about: &'static str,
    /// Constructor.
    pub build: fn(&SamplerConfig) -> Result<Box<dyn VplSampler>, SamplingError>,
}

/// Every sampler this build has.
pub const SAMPLERS: &[SamplerEntry] = &[
    SamplerEntry {
        name: "ir",
        about: "Instant Radiosity (Keller 1997): VPLs at the diffuse vertices of light paths",
        build: |c| {
            InstantRadiosity::new(IrConfig { vpls: c.vpls, bounces: c.bounces(), sampling: c.sampling, fresh_paths: c.fresh_paths })
                .map(|s| Box::new(s) as Box<dyn VplSampler>)
                .map_err(|e| SamplingError::Config("ir", e.to_string()))
        },
    },
    SamplerEntry {
        name: "smc",
        about: "Sequential Monte Carlo Instant Radiosity (Hedman et al. 2017): temporally coherent VPLs on indirectly visible surfaces",
        build: |c| {
            if c.max_depth < 3 {
                return Err(SamplingError::Config("smc", format!("max depth {} has no indirect light for VPLs to carry (at least 3)", c.max_depth)));
            }
            SmcSampler::new(c.smc_config()).map(|s| Box::new(s) as Box<dyn VplSampler>).map_err(|e| SamplingError::Config("smc", e.to_string()))
        },
    },
];

/// Names of the samplers the toolkit plans but this build does not have.
pub const PLANNED: &[&str] = &["rr", "mir", "mir-resample", "tcas"];

/// Builds the sampler called `name`.
pub fn build(name: &str, config: &SamplerConfig) -> Result<Box<dyn VplSampler>, SamplingError> {
    let available = SAMPLERS.iter().map(|e| e.name).collect::<Vec<_>>().join(", ");
    match SAMPLERS.iter().find(|e| e.name == name) {
        Some(e) => (e.build)(config),
        None if PLANNED.contains(&name) => Err(SamplingError::NotAvailable(name.into(), available)),
        None => Err(SamplingError::Unknown(name.into(), available)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_resolve_or_explain() {
        assert_eq!(build("ir", &SamplerConfig::default()).unwrap().name(), "ir");
        assert_eq!(build("smc", &SamplerConfig::default()).unwrap().name(), "smc");
        assert!(matches!(build("tcas", &SamplerConfig::default()), Err(SamplingError::NotAvailable(..))));
        assert!(matches!(build("smc", &SamplerConfig { max_depth: 2, ..SamplerConfig::default() }), Err(SamplingError::Config(..))));
        let bad = SamplerConfig { smc: SmcConfig { resample_ratio: 0, ..SmcConfig::default() }, ..SamplerConfig::default() };
        assert!(matches!(build("smc", &bad), Err(SamplingError::Config(..))));
        assert!(matches!(build("xyz", &SamplerConfig::default()), Err(SamplingError::Unknown(..))));
        assert!(matches!(build("ir", &SamplerConfig { vpls: 0, ..SamplerConfig::default() }), Err(SamplingError::Config(..))));
    }
}
