//! Settings of the two Metropolis IR samplers.

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
        MirConfig { vpls: 2048, bounces: 3, camera_samples: 100, bootstrap: None, chains: 64, mutations: 4, large_step: 0.3, defensive: 0.05 }
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
        if !(0.0..=1.0).contains(&self.large_step) || !(self.defensive >= 0.0 && self.defensive.is_finite()) {
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
