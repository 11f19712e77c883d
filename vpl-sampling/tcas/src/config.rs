//! Settings of TCAS.

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
