//! Settings of the Russian-roulette sampler, with the paper's defaults.

use vpl_core::{Budget, ParamError, ParamKey, Params};

/// Settings of [`crate::RrSampler`]. The defaults are the paper's (§4):
/// ε = 0.05 and N_C = 100 camera samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RrConfig {
    /// The budget I: VPL slots per frame (N of §3.2, the number of VPLs to keep).
    pub vpls: usize,
    /// ε of eq. (3): the least acceptance probability.
    pub epsilon: f32,
    /// N_C: camera samples ("importons") per frame, a Halton sequence over
    /// the image that moves on every frame.
    pub camera_samples: usize,
    /// On the first frame, when no image exists yet, estimate Φ̃_total from a
    /// pilot set of plain light-path VPLs against the camera samples (the
    /// paper's single-image variant, §3.3) instead of starting from Φ̃_total = 0.
    pub pilot: bool,
    /// Most candidates traced per frame, as a multiple of I (bounds the work
    /// when almost nothing is accepted).
    pub max_candidates_factor: usize,
}

impl Default for RrConfig {
    fn default() -> Self {
        RrConfig { vpls: 2048, epsilon: 0.05, camera_samples: 100, pilot: false, max_candidates_factor: 64 }
    }
}

impl RrConfig {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), RrError> {
        if self.vpls == 0 {
            return Err(RrError::Invalid("the VPL budget must be at least 1"));
        }
        if !(self.epsilon > 0.0 && self.epsilon <= 1.0) {
            return Err(RrError::Invalid("epsilon must be in (0, 1]"));
        }
        if self.camera_samples == 0 || self.camera_samples as u64 > vpl_core::params::MAX_COUNT {
            return Err(RrError::Invalid("camera samples must be from 1 to 2^24"));
        }
        if self.max_candidates_factor == 0 || self.vpls.checked_mul(self.max_candidates_factor).is_none_or(|n| n > 1 << 26) {
            return Err(RrError::Invalid("I times the candidate factor must be in 1..=2^26"));
        }
        Ok(())
    }
}

/// Errors of [`crate::RrSampler::new`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum RrError {
    /// A setting is out of range.
    #[error("invalid RR settings: {0}")]
    Invalid(&'static str),
}

impl RrConfig {
    /// The keys [`RrConfig::from_params`] reads.
    pub const KEYS: &'static [ParamKey] = &[
        ParamKey { key: "rr-epsilon", default: "0.05", about: "ε of eq. (3): the least acceptance probability" },
        ParamKey { key: "camera-samples", default: "100", about: "N_C: camera samples per frame" },
        ParamKey { key: "rr-pilot", default: "false", about: "estimate Φ̃_total from a pilot set on the first frame" },
        ParamKey { key: "rr-max-candidates", default: "64", about: "most candidates per frame, as a multiple of I" },
    ];

    /// The settings of `budget` (I) with the paper's defaults, changed by
    /// `p`'s keys ([`RrConfig::KEYS`]).
    pub fn from_params(budget: &Budget, p: &Params) -> Result<RrConfig, ParamError> {
        let d = RrConfig::default();
        let epsilon = p.get_or("rr-epsilon", d.epsilon)?;
        if !(epsilon > 0.0 && epsilon <= 1.0) {
            return Err(p.out_of_range("rr-epsilon", epsilon, "in (0, 1]"));
        }
        Ok(RrConfig {
            vpls: budget.vpls,
            epsilon,
            camera_samples: p.count_or("camera-samples", d.camera_samples, 1)?,
            pilot: p.get_or("rr-pilot", d.pilot)?,
            max_candidates_factor: p.count_or("rr-max-candidates", d.max_candidates_factor, 1)?,
        })
    }
}
