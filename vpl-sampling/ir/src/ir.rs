//! The Instant Radiosity sampler.

use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use vpl_core::light::channel_mean;
use vpl_core::params::FromParam;
use vpl_core::sampling::cosine_hemisphere;
use vpl_core::{
    Budget, Frame, Halton, LightPathGenerator, LocalFrame, ParamError, ParamKey, Params, Purpose, Ray, Scene, Stats, Vpl, VplSampler,
    VplSet, stream,
};

/// How light paths draw their numbers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathSampling {
    /// Independent pseudo-random streams, one per light path.
    #[default]
    Random,
    /// One point of a rotated Halton sequence per light path (Keller's choice).
    Halton,
}

impl FromParam for PathSampling {
    const EXPECTED: &'static str = "random or halton";
    fn from_param(text: &str) -> Option<Self> {
        match text.trim() {
            "random" => Some(PathSampling::Random),
            "halton" => Some(PathSampling::Halton),
            _ => None,
        }
    }
}

/// Settings of [`InstantRadiosity`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IrConfig {
    /// The budget I: VPL slots per frame.
    pub vpls: usize,
    /// Indirect bounces: VPLs are stored at light-path vertices 1..=bounces
    /// (`max_depth − 2` in Mitsuba's depth convention; 3 for depth 5).
    pub bounces: u32,
    /// Random or Halton light paths.
    pub sampling: PathSampling,
    /// New light paths every frame (the frame index enters the streams and
    /// the Halton rotation): IR as the papers compare it, flickering even in
    /// a static scene. Off: a static scene keeps its VPLs.
    pub fresh_paths: bool,
}

impl Default for IrConfig {
    fn default() -> Self {
        IrConfig { vpls: 2048, bounces: 3, sampling: PathSampling::Random, fresh_paths: false }
    }
}

impl IrConfig {
    /// The keys [`IrConfig::from_params`] reads.
    pub const KEYS: &'static [ParamKey] = &[
        ParamKey { key: "path-sampling", default: "random", about: "how light paths draw their numbers: random or halton" },
        ParamKey { key: "fresh-paths", default: "false", about: "new light paths every frame (without it a static scene keeps its VPLs)" },
    ];

    /// The settings of `budget` (I and `max_depth − 2` bounces), changed by
    /// `p`'s keys ([`IrConfig::KEYS`]).
    pub fn from_params(budget: &Budget, p: &Params) -> Result<IrConfig, ParamError> {
        let d = IrConfig::default();
        Ok(IrConfig {
            vpls: budget.vpls,
            bounces: budget.bounces(),
            sampling: p.get_or("path-sampling", d.sampling)?,
            fresh_paths: p.get_or("fresh-paths", d.fresh_paths)?,
        })
    }
}

/// Errors of [`InstantRadiosity::new`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum IrError {
    /// The budget must hold at least one VPL.
    #[error("the VPL budget must be at least 1")]
    ZeroBudget,
    /// More bounces than the Halton table supports.
    #[error("{0} bounces is more than the supported 64")]
    TooManyBounces(u32),
}

/// Counts of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IrStats {
    /// The budget I.
    pub budget: usize,
    /// Slots the plan fills when no path leaves the scene.
    pub planned: usize,
    /// VPLs stored.
    pub stored: usize,
    /// Light paths N.
    pub light_paths: usize,
    /// Planned VPLs lost because their path left the scene, met a surface from
    /// its unlit side, or reached a black surface.
    pub lost: usize,
}

/// Keller's Instant Radiosity as a [`VplSampler`].
#[derive(Clone, Debug)]
pub struct InstantRadiosity {
    config: IrConfig,
    set: VplSet,
    stats: IrStats,
}

/// Dimensions a light path uses: light choice, position, direction, then a
/// direction per further bounce.
fn dims(bounces: u32) -> usize {
    5 + 2 * bounces.saturating_sub(1) as usize
}

impl InstantRadiosity {
    /// A sampler with `config`.
    pub fn new(config: IrConfig) -> Result<Self, IrError> {
        if config.vpls == 0 {
            return Err(IrError::ZeroBudget);
        }
        if config.bounces > 64 {
            return Err(IrError::TooManyBounces(config.bounces));
        }
        Ok(InstantRadiosity { config, set: VplSet::new(config.vpls), stats: IrStats::default() })
    }

    /// The configuration.
    pub fn config(&self) -> &IrConfig {
        &self.config
    }

    /// Counts of the last frame.
    pub fn stats(&self) -> IrStats {
        self.stats
    }

    /// Samples the VPLs of `scene` with `seed`, as frame 0.
    pub fn sample(&mut self, scene: &Scene, seed: u64) -> &VplSet {
        self.sample_frame(scene, seed, 0)
    }

    /// Samples the VPLs of frame `index` of `scene` with `seed` (what
    /// [`VplSampler::next_frame`] does); the index matters only with
    /// [`IrConfig::fresh_paths`].
    pub fn sample_frame(&mut self, scene: &Scene, seed: u64, index: u64) -> &VplSet {
        let vpls = self.config.vpls;
        let batch = self.trace(scene, vpls, seed, index);
        self.set.begin_frame();
        let mut filled = vec![None; vpls];
        for (slot, v) in batch.vpls {
            filled[slot] = Some(v);
        }
        for (slot, v) in filled.into_iter().enumerate() {
            self.set.set(slot, v);
        }
        self.set.light_paths = batch.light_paths as u64;
        let stored = self.set.stored();
        self.stats = IrStats { budget: vpls, planned: batch.planned, stored, light_paths: batch.light_paths, lost: batch.planned - stored };
        &self.set
    }

    /// The light paths of a budget of `budget` slots for frame `index`
    /// (which matters only with [`IrConfig::fresh_paths`]).
    fn trace(&self, scene: &Scene, budget: usize, seed: u64, index: u64) -> Batch {
        let IrConfig { bounces, sampling, fresh_paths, .. } = self.config;
        let frame = if fresh_paths { index } else { 0 };
        let plan = path_plan(budget, bounces, mean_albedo(scene));
        let offsets: Vec<usize> = plan
            .iter()
            .scan(0, |acc, &n| {
                let o = *acc;
                *acc += n;
                Some(o)
            })
            .collect();
        let n_paths = plan.first().copied().unwrap_or(0);
        let halton = (sampling == PathSampling::Halton)
            .then(|| Halton::new(dims(bounces), seed.wrapping_add(frame.wrapping_mul(0x9E37_79B9_7F4A_7C15))));
        let vpls: Vec<(usize, Vpl)> =
            (0..n_paths).into_par_iter().flat_map_iter(|i| trace_path(scene, i, &plan, &offsets, (seed, frame), halton.as_ref())).collect();
        Batch { vpls, planned: plan.iter().sum(), light_paths: n_paths }
    }
}

/// What one budget's light paths stored.
struct Batch {
    /// VPLs with their slots.
    vpls: Vec<(usize, Vpl)>,
    /// Slots the plan fills when no path is lost.
    planned: usize,
    /// Light paths traced.
    light_paths: usize,
}

/// IR as a source of light-path VPLs for samplers that wrap one (RR): a
/// budget of `budget` slots, paths fresh per `frame` only with
/// [`IrConfig::fresh_paths`]; the configured budget is not used.
impl LightPathGenerator for InstantRadiosity {
    fn name(&self) -> &'static str {
        "ir"
    }

    fn generate(&self, scene: &Scene, budget: usize, seed: u64, frame: u64) -> Vec<Vpl> {
        if budget == 0 {
            return Vec::new();
        }
        self.trace(scene, budget, seed, frame).vpls.into_iter().map(|(_, v)| v).collect()
    }
}

impl VplSampler for InstantRadiosity {
    fn name(&self) -> &'static str {
        "ir"
    }

    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        self.sample_frame(frame.scene, frame.seed, frame.index)
    }

    fn stats(&self) -> Stats {
        let s = self.stats;
        Stats::new()
            .count("stored", s.stored)
            .count("budget", s.budget)
            .count("light_paths", s.light_paths)
            .count("planned", s.planned)
            .count("lost", s.lost)
    }
}

/// Area-weighted mean over the scene's triangles of the channel-mean albedo:
/// Keller's average reflectivity ρ̄.
pub fn mean_albedo(scene: &Scene) -> f32 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for t in &scene.geometry.triangles {
        let a = t.area as f64;
        num += a * channel_mean(scene.materials[t.material as usize].albedo).clamp(0.0, 1.0) as f64;
        den += a;
    }
    if den > 0.0 { (num / den) as f32 } else { 0.0 }
}

/// Paths per bounce, `n_j = round(ρ̄^(j−1) · N)` for j = 1..=bounces, with the
/// largest N whose VPLs fit into `budget` slots.
pub fn path_plan(budget: usize, bounces: u32, rho: f32) -> Vec<usize> {
    let rho = rho.clamp(0.0, 1.0) as f64;
    let plan = |n: usize| -> Vec<usize> {
        let mut v = Vec::with_capacity(bounces as usize);
        let mut f = 1.0f64;
        for _ in 0..bounces {
            v.push(((n as f64) * f).round() as usize);
            f *= rho;
        }
        v
    };
    if bounces == 0 {
        return Vec::new();
    }
    let series: f64 = (0..bounces).map(|j| rho.powi(j as i32)).sum();
    let mut n = ((budget as f64 / series).floor() as usize).max(1);
    while n > 1 && plan(n).iter().sum::<usize>() > budget {
        n -= 1;
    }
    while plan(n + 1).iter().sum::<usize>() <= budget {
        n += 1;
    }
    plan(n)
}

/// Light path `i`: the VPLs it stores, with their slots.
fn trace_path(
    scene: &Scene,
    i: usize,
    plan: &[usize],
    offsets: &[usize],
    (seed, frame): (u64, u64),
    halton: Option<&Halton>,
) -> Vec<(usize, Vpl)> {
    let mut rng = stream(seed, frame, Purpose::LIGHT_PATH, i as u64);
    let mut dim = 0usize;
    let mut next = || -> f32 {
        let u = match halton {
            Some(h) => h.sample(i as u64, dim),
            None => rng.next_f32(),
        };
        dim += 1;
        u
    };
    let mut out = Vec::with_capacity(plan.len());
    let (u_sel, u_pos, u_dir) = (next(), (next(), next()), (next(), next()));
    let Some(e) = scene.sample_emission(u_sel, u_pos, u_dir) else { return out };
    let mut alpha = e.beta;
    let mut ray = e.ray;
    let eps = scene.epsilon();
    for (j, &n_j) in plan.iter().enumerate() {
        if i >= n_j {
            break;
        }
        let Some((sp, rho)) = scene.reflecting_hit(&ray) else { break };
        let slot = offsets[j] + i;
        // Flux α·ρ/π per path, averaged over the n_j paths of bounce j.
        let flux = alpha * rho * (FRAC_1_PI / n_j as f32);
        out.push((slot, Vpl { y: sp.p, n: sp.n, flux, id: slot as u64, bounce: j as u32 + 1 }));
        if plan.get(j + 1).is_none_or(|&n| i >= n) {
            break;
        }
        // Cosine sampling about the shading normal: f·cos/pdf = ρ.
        let wi = LocalFrame::from_normal(sp.n).to_world(cosine_hemisphere(next(), next()));
        if wi.dot(sp.ng) <= 0.0 {
            break;
        }
        alpha *= rho;
        ray = Ray::new(sp.p + sp.ng * eps, wi);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::SceneSetup;

    #[test]
    fn plan_fills_the_budget_with_geometric_counts() {
        let p = path_plan(2048, 3, 0.5);
        assert!(p.iter().sum::<usize>() <= 2048 && p.iter().sum::<usize>() > 2040, "{p:?}");
        assert!((p[1] as f32 / p[0] as f32 - 0.5).abs() < 1e-2 && (p[2] as f32 / p[0] as f32 - 0.25).abs() < 1e-2);
        assert_eq!(path_plan(10, 1, 0.7), vec![10]);
        assert_eq!(path_plan(10, 3, 0.0), vec![10, 0, 0]);
        assert!(path_plan(10, 0, 0.5).is_empty());
    }

    #[test]
    fn static_scene_gives_the_same_vpls_and_no_changes() {
        let scene = SceneSetup::builtin("cornell").unwrap().scene;
        for sampling in [PathSampling::Random, PathSampling::Halton] {
            let mut ir = InstantRadiosity::new(IrConfig { vpls: 512, bounces: 3, sampling, fresh_paths: false }).unwrap();
            let a = ir.sample(&scene, 5).clone();
            assert_eq!(a.changed_count(), a.stored());
            let b = ir.sample(&scene, 5);
            assert!(a.slots() == b.slots(), "the VPLs differ between frames");
            assert_eq!(b.changed_count(), 0);
            let s = ir.stats();
            assert_eq!(s.stored + s.lost, s.planned);
            // The closed box loses paths only through the light's back and the box's open front.
            assert!(s.stored as f32 > 0.7 * s.planned as f32, "{s:?}");
            // With fresh paths, the next frame's VPLs are new ones.
            let mut fresh = InstantRadiosity::new(IrConfig { vpls: 512, bounces: 3, sampling, fresh_paths: true }).unwrap();
            let f0 = fresh.sample_frame(&scene, 5, 0).clone();
            assert!(f0.slots() == a.slots(), "frame 0 of fresh paths differs from fixed paths");
            let f1 = fresh.sample_frame(&scene, 5, 1);
            assert!(f1.moved_count() > 400, "only {} slots moved", f1.moved_count());
        }
    }

    #[test]
    fn bounce_counts_follow_the_plan() {
        let scene = SceneSetup::builtin("cornell").unwrap().scene;
        let mut ir =
            InstantRadiosity::new(IrConfig { vpls: 1000, bounces: 2, sampling: PathSampling::Halton, fresh_paths: false }).unwrap();
        let set = ir.sample(&scene, 1);
        let plan = path_plan(1000, 2, mean_albedo(&scene));
        let b1 = set.iter().filter(|(_, v)| v.bounce == 1).count();
        let b2 = set.iter().filter(|(_, v)| v.bounce == 2).count();
        assert!(b1 <= plan[0] && b2 <= plan[1] && b1 > 0 && b2 > 0);
        assert!(set.iter().all(|(_, v)| v.bounce <= 2 && v.flux.min_element() >= 0.0));
        assert_eq!(InstantRadiosity::new(IrConfig { vpls: 0, ..IrConfig::default() }).unwrap_err(), IrError::ZeroBudget);
    }
}
