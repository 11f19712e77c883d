//! Where Russian-roulette acceptance gets its candidates: any source of
//! VPL sets that are each an unbiased estimate of the light field on their
//! own, be it light paths (Instant Radiosity) or another sampler.

use vpl_core::{Frame, LightPathGenerator, Vpl, VplSampler};

/// A source of candidate VPLs for [`crate::RrSampler`].
pub trait CandidateSource: Send {
    /// Short name (`ir`, `smc`, …).
    fn name(&self) -> &str;
    /// About `budget` candidates for `frame`, their random numbers keyed by
    /// `seed` (the frame's seed, or a salted one for a pilot set), in the
    /// flux convention of [`vpl_core::vpl`]: their sum estimates the light
    /// field without bias.
    fn candidates(&mut self, frame: &Frame, budget: usize, seed: u64) -> Vec<Vpl>;
}

/// Candidates from a [`LightPathGenerator`] (Instant Radiosity): as many
/// slots as asked, fresh for every call.
#[derive(Debug)]
pub struct LightPaths<G>(pub G);

impl<G: LightPathGenerator> CandidateSource for LightPaths<G> {
    fn name(&self) -> &str {
        self.0.name()
    }

    fn candidates(&mut self, frame: &Frame, budget: usize, seed: u64) -> Vec<Vpl> {
        self.0.generate(frame.scene, budget, seed, frame.index)
    }
}

/// Candidates from another sampler: the VPLs of its next frame, whatever
/// budget is asked (its own budget was fixed when it was built). A stateful
/// sampler advances by one frame per call, so a pilot set on the first frame
/// advances it twice.
pub struct SamplerCandidates(pub Box<dyn VplSampler>);

impl std::fmt::Debug for SamplerCandidates {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("SamplerCandidates").field(&self.0.name()).finish()
    }
}

impl CandidateSource for SamplerCandidates {
    fn name(&self) -> &str {
        self.0.name()
    }

    fn candidates(&mut self, frame: &Frame, _budget: usize, seed: u64) -> Vec<Vpl> {
        let frame = Frame { seed, ..*frame };
        self.0.next_frame(&frame).iter().map(|(_, v)| *v).collect()
    }
}
