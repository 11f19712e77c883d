//! Settings of TCAS.

use vpl_core::{Budget, ParamError, ParamKey, Params};

/// Settings of [`crate::TcasSampler`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TcasConfig {
    /// The budget I: one Markov chain per VPL slot.
    pub vpls: usize,
    /// R: texels per side of each light's reflective shadow map.
    pub rsm_res: u32,
    /// Metropolis-Hastings iterations per chain and frame (Barák et al.
    /// propose 5; the SMC paper ran 16, its default here).
    pub iterations: u32,
    /// Further iterations on the first frame, from no state.
    pub warmup: u32,
    /// Camera samples the view-dependent importance is estimated against.
    pub camera_samples: usize,
}

impl Default for TcasConfig {
    fn default() -> Self {
        TcasConfig { vpls: 2048, rsm_res: 64, iterations: 16, warmup: 48, camera_samples: 256 }
    }
}

impl TcasConfig {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), TcasError> {
        if self.vpls == 0 || self.iterations == 0 || self.camera_samples == 0 {
            return Err(TcasError::Invalid("budget, iterations and camera samples must be at least 1"));
        }
        if self.camera_samples as u64 > vpl_core::params::MAX_COUNT {
            return Err(TcasError::Invalid("camera samples must be at most 2^24"));
        }
        if !(1..=4096).contains(&self.rsm_res) {
            return Err(TcasError::Invalid("the RSM resolution must be in 1..=4096"));
        }
        Ok(())
    }
}

/// Errors of [`crate::TcasSampler::new`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TcasError {
    /// A setting is out of range.
    #[error("invalid TCAS settings: {0}")]
    Invalid(&'static str),
}

impl TcasConfig {
    /// The keys [`TcasConfig::from_params`] reads.
    pub const KEYS: &'static [ParamKey] = &[
        ParamKey { key: "mh-iterations", default: "16", about: "Metropolis-Hastings iterations per chain and frame" },
        ParamKey { key: "rsm-res", default: "64", about: "texels per side of each light's reflective shadow map" },
        ParamKey { key: "tcas-warmup", default: "48", about: "further iterations on the first frame" },
        ParamKey { key: "camera-samples", default: "256", about: "camera samples of the view importance" },
    ];

    /// The settings of `budget` (I; one bounce whatever the depth) with the
    /// defaults, changed by `p`'s keys ([`TcasConfig::KEYS`]).
    pub fn from_params(budget: &Budget, p: &Params) -> Result<TcasConfig, ParamError> {
        let d = TcasConfig::default();
        let rsm_res = p.get_or("rsm-res", d.rsm_res)?;
        if !(1..=4096).contains(&rsm_res) {
            return Err(p.out_of_range("rsm-res", rsm_res, "in 1..=4096"));
        }
        Ok(TcasConfig {
            vpls: budget.vpls,
            rsm_res,
            iterations: p.count_or("mh-iterations", d.iterations, 1)?,
            warmup: p.get_or("tcas-warmup", d.warmup)?,
            camera_samples: p.count_or("camera-samples", d.camera_samples, 1)?,
        })
    }
}
