//! How the cells' radiances follow lights that move.
//!
//! A cell's mean radiance L̄(V_i) comes from the candidates of the last T
//! iterations ([`crate::FluxEstimator::Voronoi`]), each estimated under
//! the lights of its own iteration. Under lights that move, the mean
//! lags by about T/2 iterations, and on `building` (a lamp carried from
//! room to room) the lag is most of the error. Measured at frame 360, 40
//! frames into a carry (one seed, 32×24, the sampler stepped every 8th
//! frame and then at each of the 32 before; `SmcSampler::cell_pieces`
//! cuts each cell into its probes, each with its share of the cell's flux):
//!
//! | the cells' light, spread over their probes | image / path tracer |
//! | --- | ---: |
//! | each probe's own radiance now (64 paths), the cells' areas | 0.993 |
//! | each cell's mean of those radiances | 1.016 |
//! | the candidates as estimated in their iterations ([`Relight::None`]) | 1.286 |
//! | scaled by the VPL's own change ([`Relight::Ratio`]) | 1.350 |
//! | [`Relight::Candidates`], 1 path of the direct light alone | 1.252 |
//! | [`Relight::Candidates`], 1 path of 2 bounces | 1.094 |
//! | [`Relight::Candidates`], 4 paths of 2 bounces | 1.054 |
//!
//! and held at frame 360 for 40 iterations, the VPLs at their sites gave
//! 0.995: the areas follow the view, the radiances lag.
//!
//! [`Relight::Candidates`] (the default) moves every cell's mean by the
//! change of a short estimate of its candidates' radiance under common
//! random numbers:
//!
//! ```text
//! L̄_now(V_i) = L̄(V_i) + Σ_h w_h (D_h(now) − D_h(t_h)) / Σ_h w_h,           (1)
//! ```
//!
//! w_h the candidates' weights in the mean, t_h each candidate's
//! iteration, D_h a radiance estimate with `relight-paths` paths (1 by
//! default) of `relight-bounces` bounces after the candidate (by default
//! the radiosity paths': the light that reaches a room through a door
//! comes by more than one bounce, and the direct light alone left most of
//! the lag), drawn from the same random numbers every time (a stream keyed
//! by the candidate's id): the paths keep their vertices, and only their
//! connections to the lights change. The expectation of (1) is the mean
//! of now. It is held at zero or above, which biases it up where the
//! difference is noisy against the cell's light (a cell the lamp left):
//! with 1 path, the cells held at zero hid 7 % of the light in the
//! measurement above; 4 paths halve that at three times the cost. D_h is
//! estimated for each candidate when it is made (I estimates of one path
//! an iteration) and for every candidate held (T · I) at the iterations
//! whose lights changed.
//!
//! Along the sequences (`vpl energy`, 48×36, 3 seeds, the sampler stepped
//! every 8th frame and at each of the 32 before 3 checkpoints; image mean
//! over the path tracer's at the checkpoints, then their mean):
//!
//! | scene | [`Relight::Ratio`] | [`Relight::Candidates`] |
//! | --- | --- | --- |
//! | `building` | 1.005, 1.111, 1.073: **1.063** | 1.028, 1.034, 1.005: **1.022** |
//! | `colonnade` | 0.981, 0.993, 1.077: **1.017** | 0.977, 0.991, 1.060: **1.010** |
//!
//! (measured while the candidates that joined the set took their VPL's
//! second estimate in their cells; with every candidate's first estimate,
//! as now, `building`'s sequence is 1.030 ± 0.007 and `colonnade`'s 1.010),
//! and the same to the last digit where the lights stand still (`office`,
//! `maze`, `courtyard`, `atrium`'s checkpoints within 0.005). The cost is
//! in the frames whose lights moved: SMC's step on `building` took 111 ms
//! against 96 ms (2 cores, I = 2048; the radiosity step 48 against 37 ms).
//!
//! [`Relight::Ratio`] scales each cell's mean by how its own VPL's radiance
//! changed over the same iterations ([`crate::Cell::current_radiance`]):
//! one estimate a cell, and no cost, but one point stands for the whole
//! cell, and where the light comes near (a lamp carried past a wall) the
//! VPL's change is not the cell's. [`Relight::None`] keeps the candidates
//! as estimated.

use vpl_core::params::FromParam;

/// How the cells' mean radiances follow moving lights (see the module text).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Relight {
    /// The candidates as estimated in their iterations: the mean lags.
    None,
    /// Each cell's mean scaled by its VPL's change of radiance.
    Ratio,
    /// Each cell's mean moved by the change of short estimates of its
    /// candidates' radiances under common random numbers (eq. 1).
    #[default]
    Candidates,
}

impl Relight {
    /// Every way, the default last.
    pub const ALL: [Relight; 3] = [Relight::None, Relight::Ratio, Relight::Candidates];

    /// The parameter value naming it.
    pub fn name(self) -> &'static str {
        match self {
            Relight::None => "none",
            Relight::Ratio => "ratio",
            Relight::Candidates => "candidates",
        }
    }
}

impl FromParam for Relight {
    const EXPECTED: &'static str = "none, ratio or candidates";
    fn from_param(text: &str) -> Option<Self> {
        Relight::ALL.into_iter().find(|r| r.name() == text.trim())
    }
}

impl std::fmt::Display for Relight {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for r in Relight::ALL {
            assert_eq!(Relight::from_param(r.name()), Some(r));
            assert_eq!(r.to_string(), r.name());
        }
        assert_eq!(Relight::from_param("later"), None);
        assert_eq!(Relight::default(), Relight::Candidates);
    }
}
