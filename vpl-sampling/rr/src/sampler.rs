//! The Russian-roulette sampler: a light-path generator's VPLs, each kept
//! with the probability of eq. (3) and scaled by its inverse.

use crate::acceptance::acceptance;
use crate::config::{RrConfig, RrError};
use crate::source::{CandidateSource, LightPaths};
use rayon::prelude::*;
use std::time::Instant;
use vpl_core::image::luminance;
use vpl_core::importons::Importons;
use vpl_core::{Frame, Purpose, Stats, Vpl, VplSampler, VplSet, stream};
use vpl_ir::{InstantRadiosity, IrConfig};

/// Where the frame's Φ̃_total came from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PhiSource {
    /// Nothing known yet: Φ̃_total = 0, every candidate accepted (plain IR).
    #[default]
    None,
    /// The previous frame's indirect image (the paper's progressive setting).
    PreviousImage,
    /// The sampler's own estimate from its previous frame's VPLs against its
    /// camera samples (used when the caller passes no image).
    Carried,
    /// A pilot set of light-path VPLs on the first frame ([`RrConfig::pilot`]).
    Pilot,
}

/// Counts of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RrStats {
    /// Candidate slots asked of the light-path generator (C).
    pub budget: usize,
    /// Candidates it returned (paths that leave the scene store none).
    pub candidates: usize,
    /// Candidates accepted by the roulette.
    pub accepted: usize,
    /// VPLs stored (the accepted ones, thinned at random to I when more).
    pub stored: usize,
    /// Mean acceptance probability p̄ over the candidates (the paper's figure).
    pub mean_acceptance: f32,
    /// Φ̃_v of eq. (3): the desired average pixel contribution of a VPL.
    pub phi_v: f32,
    /// Where Φ̃_total came from.
    pub source: PhiSource,
    /// Milliseconds for the frame.
    pub ms: f64,
}

/// Russian-roulette acceptance of light-path VPLs (Georgiev & Slusallek
/// 2010) as a [`VplSampler`], around any [`CandidateSource`]: light paths
/// ([`RrSampler::over_ir`]) or another sampler ([`crate::SamplerCandidates`]).
pub struct RrSampler {
    config: RrConfig,
    inner: Box<dyn CandidateSource>,
    set: VplSet,
    /// Mean pixel luminance Φ̃_total / P the sampler estimated from its own
    /// VPLs in the last frame.
    carried: Option<f32>,
    /// Accepted candidates per candidate slot asked for, in the last frame.
    rate: Option<f64>,
    stats: RrStats,
}

impl std::fmt::Debug for RrSampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RrSampler").field("config", &self.config).field("inner", &self.inner.name()).field("stats", &self.stats).finish()
    }
}

/// One candidate after the roulette.
struct Judged {
    /// The VPL, flux scaled by 1/p, when accepted.
    kept: Option<Vpl>,
    /// p_i.
    p: f32,
    /// Φ̃_i/p_i of a kept VPL, uncapped: its share of the image mean.
    share: f64,
}

impl RrSampler {
    /// Acceptance around Instant Radiosity with `bounces` light-path bounces
    /// (fresh paths every frame when `fresh_paths`).
    pub fn over_ir(config: RrConfig, bounces: u32, fresh_paths: bool) -> Result<RrSampler, RrError> {
        let ir = InstantRadiosity::new(IrConfig { vpls: config.vpls, bounces, fresh_paths, ..IrConfig::default() })
            .map_err(|_| RrError::Invalid("the light-path generator rejected the budget or bounce count"))?;
        RrSampler::new(config, Box::new(LightPaths(ir)))
    }

    /// Acceptance around `inner`.
    pub fn new(config: RrConfig, inner: Box<dyn CandidateSource>) -> Result<RrSampler, RrError> {
        config.validate()?;
        Ok(RrSampler { config, inner, set: VplSet::new(config.vpls), carried: None, rate: None, stats: RrStats::default() })
    }

    /// The configuration.
    pub fn config(&self) -> &RrConfig {
        &self.config
    }

    /// Counts of the last frame.
    pub fn stats(&self) -> RrStats {
        self.stats
    }

    /// Judges `cands` against Φ̃_v: the roulette of eq. (2)–(3), each
    /// candidate j drawing from stream (seed, frame, ACCEPT, j).
    fn judge(&self, frame: &Frame, imp: &Importons, cands: &[Vpl], phi_v: f32, salt: u64) -> Vec<Judged> {
        let eps = self.config.epsilon;
        // p reaches 1 once Φ̃_i ≥ (1 − ε)·Φ̃_v: no need to sum further.
        let cap = (phi_v > 0.0).then_some((1.0 - eps) * phi_v);
        cands
            .par_iter()
            .enumerate()
            .map(|(j, v)| {
                let phi = imp.mean_contribution(frame.scene, v, true, cap);
                let p = acceptance(phi, phi_v, eps);
                let u = stream(frame.seed ^ salt, frame.index, Purpose::ACCEPT, j as u64).next_f32();
                if u >= p {
                    return Judged { kept: None, p, share: 0.0 };
                }
                let full = if cap.is_some_and(|c| phi >= c) { imp.mean_contribution(frame.scene, v, true, None) } else { phi };
                Judged { kept: Some(Vpl { flux: v.flux / p, ..*v }), p, share: full as f64 / p as f64 }
            })
            .collect()
    }
}

/// Mean luminance of an image.
fn mean_luminance(img: &vpl_core::Image) -> f32 {
    if img.data.is_empty() {
        return 0.0;
    }
    (img.data.iter().map(|c| luminance(*c) as f64).sum::<f64>() / img.data.len() as f64) as f32
}

impl VplSampler for RrSampler {
    fn name(&self) -> &'static str {
        "rr"
    }

    /// Φ̃_total comes from the previous frame's image.
    fn reads_previous_image(&self) -> bool {
        true
    }

    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        let start = Instant::now();
        let c = self.config;
        let budget_i = c.vpls;
        let scene = frame.scene;
        // Importons: N_C Halton camera samples, new ones every frame.
        let n_c = c.camera_samples;
        let imp = Importons::cast(scene, frame.camera, n_c, frame.index.wrapping_mul(n_c as u64), frame.seed);

        // Φ̃_total / P, the mean pixel luminance of the VPLs' light.
        let (mean_lum, source) = match (frame.previous, self.carried) {
            (Some(img), _) => (mean_luminance(img), PhiSource::PreviousImage),
            (None, Some(m)) => (m, PhiSource::Carried),
            (None, None) if c.pilot => {
                // Plain light-path VPLs (p = 1) against the camera samples:
                // Σ_i Φ̃_i estimates the image mean (§3.3, single image).
                let pilot = self.inner.candidates(frame, budget_i, frame.seed ^ 0x9170_7000);
                let judged = self.judge(frame, &imp, &pilot, 0.0, 0x9170_7000);
                let mean = judged.iter().map(|j| j.share).sum::<f64>() as f32;
                // The pilot's Φ̃_i (p = 1: uncapped) also give the acceptance
                // rate to expect, hence the candidate budget.
                let phi_v = mean / budget_i as f32;
                let expected: f64 = judged.iter().map(|j| acceptance(j.share as f32, phi_v, c.epsilon) as f64).sum();
                self.rate = Some(expected / budget_i as f64);
                (mean, PhiSource::Pilot)
            }
            (None, None) => (0.0, PhiSource::None),
        };
        // Φ̃_v = Φ̃_total / (P·N), N = I the VPLs wanted.
        let phi_v = if mean_lum.is_finite() && mean_lum > 0.0 { mean_lum / budget_i as f32 } else { 0.0 };

        // Candidates: as many as the last frame's acceptance rate says are
        // needed for I accepted on average (I when nothing is known).
        let rate = if phi_v > 0.0 { self.rate.unwrap_or(1.0) } else { 1.0 };
        let most = budget_i * c.max_candidates_factor;
        let budget_c = ((budget_i as f64 / rate.max(1e-9)).ceil() as usize).clamp(budget_i, most);
        let cands = self.inner.candidates(frame, budget_c, frame.seed);
        let judged = self.judge(frame, &imp, &cands, phi_v, 0);

        let mean_acceptance =
            if judged.is_empty() { 1.0 } else { (judged.iter().map(|j| j.p as f64).sum::<f64>() / judged.len() as f64) as f32 };
        let mut kept: Vec<Vpl> = judged.iter().filter_map(|j| j.kept).collect();
        let accepted = kept.len();
        self.carried = Some(judged.iter().map(|j| j.share).sum::<f64>() as f32).filter(|m| m.is_finite() && *m > 0.0);
        self.rate = (phi_v > 0.0 || accepted > 0).then(|| (accepted as f64 / budget_c as f64).max(1.0 / most as f64));
        if accepted > budget_i {
            // More accepted than slots: keep a uniform random I of the A, each
            // scaled by A / I, which keeps every expectation (a second roulette
            // of probability I / A).
            let mut rng = stream(frame.seed, frame.index, Purpose::THIN, 0);
            for k in 0..budget_i {
                let j = k + rng.below((accepted - k) as u32) as usize;
                kept.swap(k, j);
            }
            kept.truncate(budget_i);
            let scale = accepted as f32 / budget_i as f32;
            kept.iter_mut().for_each(|v| v.flux *= scale);
        }
        self.set.begin_frame();
        let stored = kept.len();
        let mut it = kept.into_iter();
        for s in 0..budget_i {
            self.set.set(s, it.next());
        }
        self.set.light_paths = 0;
        self.stats = RrStats {
            budget: budget_c,
            candidates: cands.len(),
            accepted,
            stored,
            mean_acceptance,
            phi_v,
            source,
            ms: start.elapsed().as_secs_f64() * 1e3,
        };
        &self.set
    }

    fn stats(&self) -> Stats {
        let s = self.stats;
        Stats::new()
            .count("stored", s.stored)
            .count("budget", s.budget)
            .count("candidates", s.candidates)
            .count("accepted", s.accepted)
            .value("acceptance", s.mean_acceptance as f64)
            .value("phi_v", s.phi_v as f64)
            .ms("ms", s.ms)
    }
}
