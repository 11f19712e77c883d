//! Metropolis Instant Radiosity (Segovia, Iehl, Péroche 2007): light paths
//! drawn by Metropolis-Hastings in proportion to the power their VPL brings
//! to the camera, so that every VPL brings the same power.

use crate::config::{MirConfig, MirError};
use crate::path::{dims, path_vpl, perturb, uniform};
use rayon::prelude::*;
use std::time::Instant;
use vpl_core::image::luminance;
use vpl_core::importons::Importons;
use vpl_core::{Frame, Purpose, Scene, Stats, Vpl, VplSampler, VplSet, stream};

/// Counts of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MirStats {
    /// VPLs stored.
    pub stored: usize,
    /// The normalisation b̂ = E\[f\] from the bootstrap phase.
    pub b: f64,
    /// Bootstrap paths that carried a VPL with f > 0.
    pub bootstrap_useful: usize,
    /// Metropolis-Hastings steps taken.
    pub steps: u64,
    /// Steps accepted.
    pub accepted: u64,
    /// Milliseconds for the frame.
    pub ms: f64,
}

/// Metropolis Instant Radiosity as a [`VplSampler`]; it starts afresh every frame.
#[derive(Debug)]
pub struct MirSampler {
    config: MirConfig,
    set: VplSet,
    stats: MirStats,
}

/// A state of a chain: the path, its VPL, and the target f.
#[derive(Clone)]
struct State {
    u: Vec<f32>,
    vpl: Option<Vpl>,
    f: f64,
}

/// The target of the chains: the camera importance of a path's VPL,
/// Φ̃_cam(u) = mean over the camera samples of the luminance it brings
/// (visibility included), plus the defensive term δ·κ·lum(Φ(u)).
struct Target<'a> {
    scene: &'a Scene,
    importons: Importons,
    bounces: u32,
    /// δ·κ.
    defensive: f64,
}

impl Target<'_> {
    fn eval(&self, u: Vec<f32>, id: u64) -> State {
        let vpl = path_vpl(self.scene, &u, self.bounces, id);
        let f = vpl.map_or(0.0, |v| {
            self.importons.mean_contribution(self.scene, &v, true, None) as f64 + self.defensive * luminance(v.flux) as f64
        });
        State { u, vpl, f: if f.is_finite() { f } else { 0.0 } }
    }
}

impl MirSampler {
    /// A sampler with `config`.
    pub fn new(config: MirConfig) -> Result<MirSampler, MirError> {
        config.validate()?;
        Ok(MirSampler { config, set: VplSet::new(config.vpls), stats: MirStats::default() })
    }

    /// Counts of the last frame.
    pub fn stats(&self) -> MirStats {
        self.stats
    }
}

impl VplSampler for MirSampler {
    fn name(&self) -> &'static str {
        "mir"
    }

    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        let start = Instant::now();
        let c = self.config;
        let (seed, index, scene) = (frame.seed, frame.index, frame.scene);
        let d = dims(c.bounces);
        let importons = Importons::cast(scene, frame.camera, c.camera_samples, index.wrapping_mul(c.camera_samples as u64), seed);
        let mut target = Target { scene, importons, bounces: c.bounces, defensive: 0.0 };

        // Bootstrap: independent uniform paths estimate b = ∫ f and seed the chains.
        let n_boot = c.bootstrap.unwrap_or(c.vpls.max(256));
        let boot: Vec<State> = (0..n_boot)
            .into_par_iter()
            .map(|b| {
                let mut u = vec![0.0; d];
                uniform(&mut u, &mut stream(seed, index, Purpose::BOOTSTRAP, b as u64));
                target.eval(u, b as u64)
            })
            .collect();
        let mean = |g: &dyn Fn(&State) -> f64| boot.iter().map(g).sum::<f64>() / n_boot as f64;
        let cam = mean(&|s| s.f);
        let flux = mean(&|s| s.vpl.map_or(0.0, |v| luminance(v.flux) as f64));
        // κ = E[Φ̃_cam] / E[lum Φ]: the defensive term integrates to δ·E[Φ̃_cam].
        let kappa = if flux > 0.0 { cam / flux } else { 0.0 };
        target.defensive = c.defensive as f64 * kappa;
        let boot: Vec<State> = boot
            .into_iter()
            .map(|s| {
                let extra = s.vpl.map_or(0.0, |v| target.defensive * luminance(v.flux) as f64);
                State { f: s.f + extra, ..s }
            })
            .collect();
        let b = boot.iter().map(|s| s.f).sum::<f64>() / n_boot as f64;
        let useful = boot.iter().filter(|s| s.f > 0.0).count();

        self.set.begin_frame();
        if !(b > 0.0) {
            (0..c.vpls).for_each(|s| self.set.set(s, None));
            self.stats =
                MirStats { stored: 0, b, bootstrap_useful: useful, steps: 0, accepted: 0, ms: start.elapsed().as_secs_f64() * 1e3 };
            return &self.set;
        }
        let cdf: Vec<f64> = boot
            .iter()
            .scan(0.0, |acc, s| {
                *acc += s.f;
                Some(*acc)
            })
            .collect();
        let total = *cdf.last().unwrap_or(&0.0);

        // Chains: chain k starts from a bootstrap path drawn in proportion to
        // f (no start-up bias) and records a VPL after every `mutations` steps.
        let chains = c.chains.min(c.vpls);
        let per_chain: Vec<(Vec<Option<Vpl>>, u64)> = (0..chains)
            .into_par_iter()
            .map(|k| {
                let (lo, hi) = (k * c.vpls / chains, (k + 1) * c.vpls / chains);
                let mut rng = stream(seed, index, Purpose::CHAIN, k as u64);
                let pick = rng.next_f32() as f64 * total;
                let mut x = boot[cdf.partition_point(|&v| v <= pick).min(n_boot - 1)].clone();
                let mut out = Vec::with_capacity(hi - lo);
                let mut accepted = 0u64;
                for slot in lo..hi {
                    for _ in 0..c.mutations {
                        let mut u = x.u.clone();
                        if rng.next_f32() < c.large_step {
                            uniform(&mut u, &mut rng);
                        } else {
                            perturb(&mut u, &mut rng);
                        }
                        let y = target.eval(u, slot as u64);
                        // Symmetric proposals: a = min(1, f(y) / f(x)).
                        if y.f > 0.0 && rng.next_f32() as f64 * x.f < y.f {
                            x = y;
                            accepted += 1;
                        }
                    }
                    // Equal power: Φ(u)·b / (I·f(u)) brings b/I to the camera.
                    out.push(x.vpl.map(|v| Vpl { flux: v.flux * (b / (c.vpls as f64 * x.f)) as f32, id: slot as u64, ..v }));
                }
                (out, accepted)
            })
            .collect();
        let mut accepted = 0;
        let mut slot = 0;
        for (vpls, a) in per_chain {
            accepted += a;
            for v in vpls {
                self.set.set(slot, v);
                slot += 1;
            }
        }
        self.set.light_paths = (n_boot as u64) + c.vpls as u64 * c.mutations as u64;
        self.stats = MirStats {
            stored: self.set.stored(),
            b,
            bootstrap_useful: useful,
            steps: c.vpls as u64 * c.mutations as u64,
            accepted,
            ms: start.elapsed().as_secs_f64() * 1e3,
        };
        &self.set
    }

    fn stats(&self) -> Stats {
        let s = self.stats;
        Stats::new()
            .count("stored", s.stored)
            .value("b", s.b)
            .count("bootstrap_paths", self.config.bootstrap.unwrap_or(self.config.vpls.max(256)))
            .count("bootstrap_useful", s.bootstrap_useful)
            .count("steps", s.steps as usize)
            .count("accepted", s.accepted as usize)
            .ms("ms", s.ms)
    }
}
