//! Settings of the two Metropolis IR samplers.

use vpl_core::{Budget, ParamError, ParamKey, Params};

/// Settings of [`crate::MirSampler`] (Metropolis-Hastings over light paths).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirConfig {
    /// The budget I: VPLs per frame, all of equal power toward the camera.
    pub vpls: usize,
    /// Light-path bounces that may carry the VPL (`max_depth − 2`).
    pub bounces: u32,
    /// Camera samples the importance of a path is estimated against.
    pub camera_samples: usize,
    /// Independent paths of the bootstrap phase that estimates the
    /// normalisation b and seeds the chains; `None`: I (at least 256).
    pub bootstrap: Option<usize>,
    /// Markov chains run side by side; each yields I / chains VPLs.
    pub chains: usize,
    /// Metropolis-Hastings steps between two recorded VPLs of a chain.
    pub mutations: u32,
    /// Probability of a large step (an independent new path) per step.
    pub large_step: f32,
    /// Defensive share of the target: f = Φ̃_cam + δ·κ·lum(Φ), κ making the
    /// second term's integral δ times the first's, so that every path that
    /// carries light has f > 0 even when no camera sample sees its VPL.
    pub defensive: f32,
}

impl Default for MirConfig {
    fn default() -> Self {
        MirConfig {
            vpls: 2048,
            bounces: 3,
            camera_samples: 100,
            bootstrap: None,
            chains: 64,
            mutations: 4,
            large_step: 0.3,
            defensive: 0.05,
        }
    }
}

impl MirConfig {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), MirError> {
        if self.vpls == 0 {
            return Err(MirError::Invalid("the VPL budget must be at least 1"));
        }
        if self.bounces == 0 || self.bounces > 32 {
            return Err(MirError::Invalid("VPLs need 1 to 32 light-path bounces (max depth 3 to 34)"));
        }
        if self.camera_samples == 0 || self.chains == 0 || self.mutations == 0 || self.bootstrap == Some(0) {
            return Err(MirError::Invalid("camera samples, chains, mutations and bootstrap paths must be at least 1"));
        }
        if self.camera_samples as u64 > vpl_core::params::MAX_COUNT {
            return Err(MirError::Invalid("camera samples must be at most 2^24"));
        }
        if !((0.0..=1.0).contains(&self.large_step) && self.defensive.is_finite() && self.defensive >= 0.0) {
            return Err(MirError::Invalid("the large-step probability must be in [0, 1] and the defensive share at least 0"));
        }
        Ok(())
    }
}

/// Settings of [`crate::MirResampleSampler`] (the SMC paper's stand-in for MIR).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirResampleConfig {
    /// The budget I.
    pub vpls: usize,
    /// Camera paths per VPL: ratio·I paths are resampled down to I (256 in the SMC paper).
    pub ratio: usize,
    /// Bounces after the secondary vertex y of a camera path (`max_depth − 3`).
    pub radiosity_bounces: u32,
    /// Paths of the radiosity estimate of each chosen VPL.
    pub radiosity_paths: u32,
    /// k of the VPLs' kNN densities; `None`: max(1, ⌊√(I/32)⌋).
    pub knn_k: Option<usize>,
}

impl Default for MirResampleConfig {
    fn default() -> Self {
        MirResampleConfig { vpls: 2048, ratio: 256, radiosity_bounces: 2, radiosity_paths: 16, knn_k: None }
    }
}

impl MirResampleConfig {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), MirError> {
        if self.vpls == 0 || self.ratio == 0 || self.radiosity_paths == 0 || self.knn_k == Some(0) {
            return Err(MirError::Invalid("budget, ratio, radiosity paths and k must be at least 1"));
        }
        if self.vpls.checked_mul(self.ratio).is_none_or(|n| n > 1 << 28) {
            return Err(MirError::Invalid("I times the resample ratio must be at most 2^28"));
        }
        Ok(())
    }
}

/// Errors of the MIR samplers' constructors.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum MirError {
    /// A setting is out of range.
    #[error("invalid MIR settings: {0}")]
    Invalid(&'static str),
}

impl MirConfig {
    /// The keys [`MirConfig::from_params`] reads.
    pub const KEYS: &'static [ParamKey] = &[
        ParamKey { key: "camera-samples", default: "100", about: "camera samples a path's importance is estimated against" },
        ParamKey { key: "mir-chains", default: "64", about: "Markov chains run side by side" },
        ParamKey { key: "mh-iterations", default: "4", about: "Metropolis-Hastings steps between two recorded VPLs of a chain" },
        ParamKey { key: "mir-large-step", default: "0.3", about: "probability of a large (independent) step" },
        ParamKey { key: "mir-defensive", default: "0.05", about: "defensive share of the target for paths no camera sample sees" },
        ParamKey { key: "mir-bootstrap", default: "max(I, 256)", about: "independent paths of the bootstrap phase" },
    ];

    /// The settings of `budget` (I and `max_depth − 2` bounces) with the
    /// defaults, changed by `p`'s keys ([`MirConfig::KEYS`]).
    pub fn from_params(budget: &Budget, p: &Params) -> Result<MirConfig, ParamError> {
        let d = MirConfig::default();
        let large_step = p.get_or("mir-large-step", d.large_step)?;
        if !(0.0..=1.0).contains(&large_step) {
            return Err(p.out_of_range("mir-large-step", large_step, "in [0, 1]"));
        }
        let defensive = p.get_or("mir-defensive", d.defensive)?;
        if defensive < 0.0 {
            return Err(p.out_of_range("mir-defensive", defensive, "at least 0"));
        }
        let bootstrap = p.get::<usize>("mir-bootstrap")?;
        if bootstrap == Some(0) {
            return Err(p.out_of_range("mir-bootstrap", 0, "at least 1"));
        }
        Ok(MirConfig {
            vpls: budget.vpls,
            bounces: budget.bounces(),
            camera_samples: p.count_or("camera-samples", d.camera_samples, 1)?,
            bootstrap,
            chains: p.count_or("mir-chains", d.chains, 1)?,
            mutations: p.count_or("mh-iterations", d.mutations, 1)?,
            large_step,
            defensive,
        })
    }
}

impl MirResampleConfig {
    /// The keys [`MirResampleConfig::from_params`] reads.
    pub const KEYS: &'static [ParamKey] = &[
        ParamKey { key: "resample-ratio", default: "256", about: "camera paths per VPL (ratio·I paths resampled to I)" },
        ParamKey { key: "radiosity-paths", default: "16", about: "paths of each chosen VPL's radiosity estimate" },
        ParamKey { key: "knn-k", default: "max(1, ⌊√(I/32)⌋)", about: "k of the VPLs' kNN densities" },
    ];

    /// The settings of `budget` (I and `max_depth − 3` radiosity bounces)
    /// with the defaults, changed by `p`'s keys ([`MirResampleConfig::KEYS`]).
    pub fn from_params(budget: &Budget, p: &Params) -> Result<MirResampleConfig, ParamError> {
        let d = MirResampleConfig::default();
        let knn_k = p.get::<usize>("knn-k")?;
        if knn_k == Some(0) {
            return Err(p.out_of_range("knn-k", 0, "at least 1"));
        }
        Ok(MirResampleConfig {
            vpls: budget.vpls,
            ratio: p.count_or("resample-ratio", d.ratio, 1)?,
            radiosity_bounces: budget.radiosity_bounces(),
            radiosity_paths: p.count_or("radiosity-paths", d.radiosity_paths, 1)?,
            knn_k,
        })
    }
}
