//! The TCAS sampler: one Metropolis-Hastings chain per VPL over the texels
//! of all lights' reflective shadow maps, continued from frame to frame.

use crate::config::{TcasConfig, TcasError};
use crate::rsm::{Rsm, Texel};
use rayon::prelude::*;
use std::time::Instant;
use vpl_core::importons::Importons;
use vpl_core::scene::LightingKey;
use vpl_core::{Frame, Halton, Purpose, Scene, Stats, Vpl, VplSampler, VplSet, stream};

/// Counts of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TcasStats {
    /// VPLs stored (chains whose texel has importance).
    pub stored: usize,
    /// Proposals made this frame.
    pub proposals: u64,
    /// Proposals accepted.
    pub accepted: u64,
    /// F̂ = Σ_t f(t), the normalisation, estimated from the proposals.
    pub normalisation: f64,
    /// Whether the reflective shadow maps were rendered anew.
    pub rendered_rsms: bool,
    /// Milliseconds for the frame.
    pub ms: f64,
}

/// Temporally coherent adaptive sampling (Barák, Bittner, Havran 2013) as a
/// [`VplSampler`].
#[derive(Debug)]
pub struct TcasSampler {
    config: TcasConfig,
    rsms: Vec<Rsm>,
    lighting: Option<LightingKey>,
    /// The texel each chain stands on (global index light·R² + texel).
    states: Vec<Option<u32>>,
    /// Proposals drawn so far: the quasi-random sequence continues from here.
    drawn: u64,
    frames: u64,
    set: VplSet,
    stats: TcasStats,
}

/// The importance of texels and how proposals are drawn.
struct Domain<'a> {
    scene: &'a Scene,
    rsms: &'a [Rsm],
    importons: &'a Importons,
    texels_per_map: u32,
    halton: Halton,
}

impl Domain<'_> {
    fn texel(&self, g: u32) -> Option<&Texel> {
        let m = &self.rsms[(g / self.texels_per_map) as usize];
        m.texels[(g % self.texels_per_map) as usize].as_ref()
    }

    /// f(t): the luminance the texel's VPL would bring to the camera samples,
    /// visibility ignored (as the method does).
    fn importance(&self, g: u32) -> f64 {
        self.texel(g).map_or(0.0, |t| {
            let v = Vpl { y: t.y, n: t.n, flux: t.power, id: 0, bounce: 1 };
            self.importons.mean_contribution(self.scene, &v, false, None) as f64
        })
    }

    /// q(t): a light chosen in proportion to power, then a uniform texel.
    fn proposal_pdf(&self, g: u32) -> f64 {
        let l = (g / self.texels_per_map) as usize;
        self.scene.light_distribution.pmf(self.rsms[l].light) as f64 / self.texels_per_map as f64
    }

    /// Proposal number h, from point h of a Halton sequence: (light, s, t).
    fn propose(&self, h: u64) -> Option<u32> {
        let (l, p) = self.scene.light_distribution.sample(self.halton.sample(h, 0));
        if p <= 0.0 {
            return None;
        }
        let res = self.rsms.first()?.res;
        let s = ((self.halton.sample(h, 1) * res as f32) as u32).min(res - 1);
        let t = ((self.halton.sample(h, 2) * res as f32) as u32).min(res - 1);
        Some(l as u32 * self.texels_per_map + s + res * t)
    }
}

/// One chain's frame: its state, f there, and Σ f/q over its proposals.
struct ChainFrame {
    state: Option<u32>,
    f: f64,
    sum_f_over_q: f64,
    accepted: u64,
}

impl TcasSampler {
    /// A sampler with `config`.
    pub fn new(config: TcasConfig) -> Result<TcasSampler, TcasError> {
        config.validate()?;
        Ok(TcasSampler {
            config,
            rsms: Vec::new(),
            lighting: None,
            states: vec![None; config.vpls],
            drawn: 0,
            frames: 0,
            set: VplSet::new(config.vpls),
            stats: TcasStats::default(),
        })
    }

    /// Counts of the last frame.
    pub fn stats(&self) -> TcasStats {
        self.stats
    }

    /// The reflective shadow maps of the last frame, one per light.
    pub fn rsms(&self) -> &[Rsm] {
        &self.rsms
    }
}

impl VplSampler for TcasSampler {
    fn name(&self) -> &'static str {
        "tcas"
    }

    /// 1. The RSMs, rendered anew when the lights changed (the chains stay
    ///    on their texels: coherence lives in RSM space).
    /// 2. The importance f(t) of a texel: its VPL's luminance at fixed camera
    ///    samples, unshadowed, G bounded at 5 % of the scene's radius.
    /// 3. Per chain, `iterations` independence-sampler steps: proposal t'
    ///    from the next point of a Halton sequence (light by power, then
    ///    texel), accepted with min(1, f(t')q(t) / (f(t)q(t'))).
    /// 4. F̂ = mean of f/q over this frame's proposals estimates Σ_t f(t), and
    ///    the VPL of a chain on t has flux Φ_t·F̂ / (I·f(t)) (p(t) = f(t)/F̂).
    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        let start = Instant::now();
        let c = self.config;
        let scene = frame.scene;
        let key = LightingKey::of(scene);
        let rendered = self.lighting.as_ref() != Some(&key);
        if rendered {
            self.rsms = (0..scene.lights.len()).map(|l| Rsm::render(scene, l, c.rsm_res)).collect();
            self.lighting = Some(key);
        }
        let mut importons = Importons::cast(scene, frame.camera, c.camera_samples, 0, frame.seed);
        // The importance bounds G at 5 % of the scene's radius: a texel beside
        // one camera sample would otherwise hold its chain for many frames.
        importons.min_distance_sq = (0.05 * scene.radius()).powi(2);
        let domain = Domain {
            scene,
            rsms: &self.rsms,
            importons: &importons,
            texels_per_map: c.rsm_res * c.rsm_res,
            halton: Halton::new(3, frame.seed),
        };
        let iters = c.iterations + if self.frames == 0 { c.warmup } else { 0 };
        let (seed, index, drawn, budget) = (frame.seed, frame.index, self.drawn, c.vpls as u64);
        let empty = self.rsms.is_empty();
        let chains: Vec<ChainFrame> = self
            .states
            .par_iter()
            .enumerate()
            .map(|(k, &state)| {
                if empty {
                    return ChainFrame { state: None, f: 0.0, sum_f_over_q: 0.0, accepted: 0 };
                }
                let mut rng = stream(seed, index, Purpose::CHAIN, k as u64);
                let mut x = state;
                let mut fx = x.map_or(0.0, |g| domain.importance(g));
                let mut sum = 0.0;
                let mut accepted = 0;
                for m in 0..iters as u64 {
                    let Some(y) = domain.propose(drawn + m * budget + k as u64) else { continue };
                    let fy = domain.importance(y);
                    let qy = domain.proposal_pdf(y);
                    sum += fy / qy;
                    let ok = if fx <= 0.0 {
                        fy > 0.0
                    } else {
                        let qx = x.map_or(1.0, |g| domain.proposal_pdf(g));
                        (rng.next_f32() as f64) * fx * qy < fy * qx
                    };
                    if ok {
                        x = Some(y);
                        fx = fy;
                        accepted += 1;
                    }
                }
                ChainFrame { state: x, f: fx, sum_f_over_q: sum, accepted }
            })
            .collect();
        self.drawn += iters as u64 * budget;
        self.frames += 1;
        let proposals = iters as u64 * budget;
        let f_hat = chains.iter().map(|ch| ch.sum_f_over_q).sum::<f64>() / proposals.max(1) as f64;
        self.set.begin_frame();
        for (k, ch) in chains.iter().enumerate() {
            self.states[k] = ch.state;
            let v = ch.state.filter(|_| ch.f > 0.0 && f_hat > 0.0).and_then(|g| {
                let t = domain.texel(g)?;
                let flux = t.power * (f_hat / (c.vpls as f64 * ch.f)) as f32;
                Some(Vpl { y: t.y, n: t.n, flux, id: g as u64, bounce: 1 })
            });
            self.set.set(k, v);
        }
        self.set.light_paths = 0;
        self.stats = TcasStats {
            stored: self.set.stored(),
            proposals,
            accepted: chains.iter().map(|ch| ch.accepted).sum(),
            normalisation: f_hat,
            rendered_rsms: rendered,
            ms: start.elapsed().as_secs_f64() * 1e3,
        };
        &self.set
    }

    fn stats(&self) -> Stats {
        let s = self.stats;
        Stats::new()
            .count("stored", s.stored)
            .count("proposals", s.proposals as usize)
            .count("accepted", s.accepted as usize)
            .value("normalisation", s.normalisation)
            .count("rsms_rendered", s.rendered_rsms as usize)
            .ms("ms", s.ms)
    }
}
