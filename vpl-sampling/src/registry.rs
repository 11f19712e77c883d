//! The registry of samplers, by name.

use vpl_core::VplSampler;
use vpl_ir::{InstantRadiosity, IrConfig, PathSampling};
use vpl_mir::{MirConfig, MirResampleConfig, MirResampleSampler, MirSampler};
use vpl_rr::{RrConfig, RrSampler};
use vpl_smc::{SmcConfig, SmcSampler};
use vpl_tcas::{TcasConfig, TcasSampler};

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
    /// Russian-roulette acceptance (its `vpls` is taken from `vpls`); it
    /// wraps IR with `sampling` and `fresh_paths` above.
    pub rr: RrConfig,
    /// Metropolis IR (`vpls` and `bounces` taken from above).
    pub mir: MirConfig,
    /// The resampling stand-in for MIR (`vpls` and `radiosity_bounces` taken from above).
    pub mir_resample: MirResampleConfig,
    /// TCAS (`vpls` taken from above; one bounce whatever the depth).
    pub tcas: TcasConfig,
}

impl Default for SamplerConfig {
    fn default() -> Self {
        SamplerConfig {
            vpls: 2048,
            max_depth: 5,
            sampling: PathSampling::Random,
            fresh_paths: false,
            smc: SmcConfig::default(),
            rr: RrConfig::default(),
            mir: MirConfig::default(),
            mir_resample: MirResampleConfig::default(),
            tcas: TcasConfig::default(),
        }
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

    /// An error when the depth leaves no indirect light for VPLs (max depth < 3).
    fn needs_indirect(&self, name: &'static str) -> Result<(), SamplingError> {
        if self.max_depth < 3 {
            return Err(SamplingError::Config(name, format!("max depth {} has no indirect light for VPLs to carry (at least 3)", self.max_depth)));
        }
        Ok(())
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
        name: "rr",
        about: "Russian-roulette acceptance (Georgiev & Slusallek 2010): IR's VPLs kept in proportion to the light they bring the camera",
        build: |c| {
            c.needs_indirect("rr")?;
            RrSampler::over_ir(RrConfig { vpls: c.vpls, ..c.rr }, c.bounces(), c.fresh_paths)
                .map(|s| Box::new(s) as Box<dyn VplSampler>)
                .map_err(|e| SamplingError::Config("rr", e.to_string()))
        },
    },
    SamplerEntry {
        name: "mir",
        about: "Metropolis Instant Radiosity (Segovia et al. 2007): light paths by Metropolis-Hastings, VPLs of equal power to the camera",
        build: |c| {
            c.needs_indirect("mir")?;
            MirSampler::new(MirConfig { vpls: c.vpls, bounces: c.bounces(), ..c.mir })
                .map(|s| Box::new(s) as Box<dyn VplSampler>)
                .map_err(|e| SamplingError::Config("mir", e.to_string()))
        },
    },
    SamplerEntry {
        name: "mir-resample",
        about: "MIR as the SMC paper ran it: 256·I path-tracer camera paths resampled to I VPLs by the light they bring the camera",
        build: |c| {
            c.needs_indirect("mir-resample")?;
            MirResampleSampler::new(MirResampleConfig { vpls: c.vpls, radiosity_bounces: c.max_depth.saturating_sub(3), ..c.mir_resample })
                .map(|s| Box::new(s) as Box<dyn VplSampler>)
                .map_err(|e| SamplingError::Config("mir-resample", e.to_string()))
        },
    },
    SamplerEntry {
        name: "tcas",
        about: "Temporally coherent adaptive sampling (Barák et al. 2013): Metropolis chains over reflective shadow maps, one bounce",
        build: |c| {
            c.needs_indirect("tcas")?;
            TcasSampler::new(TcasConfig { vpls: c.vpls, ..c.tcas })
                .map(|s| Box::new(s) as Box<dyn VplSampler>)
                .map_err(|e| SamplingError::Config("tcas", e.to_string()))
        },
    },
    SamplerEntry {
        name: "smc",
        about: "Sequential Monte Carlo Instant Radiosity (Hedman et al. 2017): temporally coherent VPLs on indirectly visible surfaces",
        build: |c| {
            c.needs_indirect("smc")?;
            SmcSampler::new(c.smc_config()).map(|s| Box::new(s) as Box<dyn VplSampler>).map_err(|e| SamplingError::Config("smc", e.to_string()))
        },
    },
];

/// Names of the samplers the toolkit plans but this build does not have.
pub const PLANNED: &[&str] = &[];

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
        for name in ["rr", "mir", "mir-resample", "tcas"] {
            assert_eq!(build(name, &SamplerConfig::default()).unwrap().name(), name);
            assert!(matches!(build(name, &SamplerConfig { max_depth: 2, ..SamplerConfig::default() }), Err(SamplingError::Config(..))));
            assert!(matches!(build(name, &SamplerConfig { vpls: 0, ..SamplerConfig::default() }), Err(SamplingError::Config(..))));
        }
        assert!(matches!(build("smc", &SamplerConfig { max_depth: 2, ..SamplerConfig::default() }), Err(SamplingError::Config(..))));
        let bad = SamplerConfig { smc: SmcConfig { resample_ratio: 0, ..SmcConfig::default() }, ..SamplerConfig::default() };
        assert!(matches!(build("smc", &bad), Err(SamplingError::Config(..))));
        assert!(matches!(build("xyz", &SamplerConfig::default()), Err(SamplingError::Unknown(..))));
        assert!(matches!(build("ir", &SamplerConfig { vpls: 0, ..SamplerConfig::default() }), Err(SamplingError::Config(..))));
    }
}
